/* The shared part of the calibration-check tests (test_calibration.c,
 * test_calibration_fields.c, test_calibration_film.c): a writable copy of
 * table1, the float fields of wc_calibration_t with their error codes, and
 * the check every test applies to a variant (wc_calibration_check,
 * wc_model_init and wc_clutch_init agree). Include it instead of
 * wc_test_support.h; it includes lut/wc_table1_calibration.h (one
 * translation unit per test program). */
#ifndef WC_TEST_CALIBRATION_HARNESS_H
#define WC_TEST_CALIBRATION_HARNESS_H

#include "wc_test_support.h"

#include "wc_table1_calibration.h"

#define NODES WC_TABLE1_FILM_NODES

/* A writable copy of table1, film arrays included. */
typedef struct {
    wc_calibration_t cal;
    float pressure_Pa[NODES];
    float hbar_m[NODES];
    float slope_m_per_Pa[NODES];
} cal_copy_t;

static inline void copy_table1(cal_copy_t *c)
{
    c->cal = wc_table1_calibration;
    memcpy(c->pressure_Pa, wc_table1_film_pressure_Pa, sizeof c->pressure_Pa);
    memcpy(c->hbar_m, wc_table1_film_hbar_m, sizeof c->hbar_m);
    memcpy(c->slope_m_per_Pa, wc_table1_film_slope_m_per_Pa, sizeof c->slope_m_per_Pa);
    c->cal.film.pressure_Pa = c->pressure_Pa;
    c->cal.film.hbar_m = c->hbar_m;
    c->cal.film.slope_m_per_Pa = c->slope_m_per_Pa;
    c->cal.film.length = NODES;
}

static inline float *field_ptr(wc_calibration_t *cal, size_t offset)
{
    return (float *)(void *)((unsigned char *)cal + offset);
}

/* The check, wc_model_init and wc_clutch_init must all give `expected`; on an
 * error the model is left unusable (cal == NULL). */
static inline void expect_code(const wc_calibration_t *cal, wc_cal_error_t expected, const char *what, double value)
{
    const wc_cal_error_t check = wc_calibration_check(cal);
    WC_CHECK(check == expected, "%s = %g: wc_calibration_check gave %d (%s), expected %d (%s)", what, value,
             (int)check, wc_cal_error_name(check), (int)expected, wc_cal_error_name(expected));

    wc_model_t model;
    memset(&model, 0xA5, sizeof model);
    const wc_cal_error_t model_code = wc_model_init(&model, cal);
    WC_CHECK(model_code == expected, "%s = %g: wc_model_init gave %d, expected %d", what, value, (int)model_code,
             (int)expected);

    wc_clutch_t clutch;
    memset(&clutch, 0xA5, sizeof clutch);
    const wc_cal_error_t clutch_code = wc_clutch_init(&clutch, cal, 40.0f);
    WC_CHECK(clutch_code == expected, "%s = %g: wc_clutch_init gave %d, expected %d", what, value,
             (int)clutch_code, (int)expected);
    if (expected == WC_CAL_OK) {
        WC_CHECK(model.cal == cal, "%s: model not bound to its calibration", what);
        WC_CHECK(clutch.model.cal == cal, "%s: clutch not bound to its calibration", what);
    } else {
        WC_CHECK(model.cal == NULL, "%s = %g: model left usable after error", what, value);
        WC_CHECK(clutch.model.cal == NULL, "%s = %g: clutch left usable after error", what, value);
    }
}

/* ------------------------------------------------------------------------ */
/* The float fields                                                          */

typedef struct {
    const char *name;  /* field name, also what wc_cal_error_name must say */
    size_t offset;
    wc_cal_error_t code;
} float_field_t;

#define FIELD(member, code) { #member, offsetof(wc_calibration_t, member), code }

/* Every float field of wc_calibration_t, in declaration order. */
static const float_field_t float_fields[] = {
    FIELD(outer_radius_m, WC_CAL_OUTER_RADIUS),
    FIELD(inner_radius_m, WC_CAL_INNER_RADIUS),
    FIELD(friction_area_m2, WC_CAL_FRICTION_AREA),
    FIELD(piston_area_m2, WC_CAL_PISTON_AREA),
    FIELD(oil_conductance_W_per_K, WC_CAL_OIL_CONDUCTANCE),
    FIELD(housing_conductance_W_per_K, WC_CAL_HOUSING_CONDUCTANCE),
    FIELD(heat_capacity_J_per_K, WC_CAL_HEAT_CAPACITY),
    FIELD(viscosity_a1_Pa_s, WC_CAL_VISCOSITY_A1),
    FIELD(viscosity_b1_per_K, WC_CAL_VISCOSITY_B1),
    FIELD(viscosity_a2_Pa_s, WC_CAL_VISCOSITY_A2),
    FIELD(viscosity_b2_per_K, WC_CAL_VISCOSITY_B2),
    FIELD(mu1, WC_CAL_MU1),
    FIELD(mu2, WC_CAL_MU2),
    FIELD(mu3, WC_CAL_MU3),
    FIELD(stribeck_speed_m_s, WC_CAL_STRIBECK_SPEED),
    FIELD(theta1_degC, WC_CAL_THETA1),
    FIELD(theta2_K, WC_CAL_THETA2),
    FIELD(vfs_gain_Pa_per_mA, WC_CAL_VFS_GAIN),
    FIELD(vfs_time_constant_s, WC_CAL_VFS_TIME_CONSTANT),
    FIELD(return_spring_force_N, WC_CAL_RETURN_SPRING_FORCE),
    FIELD(vfs_current_min_mA, WC_CAL_VFS_CURRENT_MIN),
    FIELD(vfs_current_max_mA, WC_CAL_VFS_CURRENT_MAX),
    FIELD(control_period_s, WC_CAL_CONTROL_PERIOD),
    FIELD(film_squeeze_factor, WC_CAL_FILM_SQUEEZE_FACTOR),
    FIELD(static_friction_factor, WC_CAL_STATIC_FRICTION_FACTOR),
    FIELD(lock_slip_rad_s, WC_CAL_LOCK_SLIP),
    FIELD(breakaway_slip_rad_s, WC_CAL_BREAKAWAY_SLIP),
    FIELD(holding_margin, WC_CAL_HOLDING_MARGIN),
    FIELD(open_clearance_m, WC_CAL_OPEN_CLEARANCE),
    FIELD(open_aeration_speed_rad_s, WC_CAL_OPEN_AERATION_SPEED),
};

#endif /* WC_TEST_CALIBRATION_HARNESS_H */
