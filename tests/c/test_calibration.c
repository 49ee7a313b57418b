/* Calibration check (wc_calibration_check, via wc_model_init and wc_clutch_init),
 * DESIGN section 8 "Calibration validity": the check proves the library's
 * promise (every output of every public function finite and physical for
 * every input and every calibration it accepts) from the equations.
 *  - single- and multi-field variants of table1, each rejected with the error
 *    code that names the field or relation, or accepted (the single-field
 *    ones are mirrored, same values and same names, in
 *    tests/python/test_calibration_rules.py, which parses the lists here);
 *  - a sweep: for every variant the check accepts (the listed ones and
 *    thousands of random single- and multi-field variants), wc_torque,
 *    wc_inverse, wc_thermal_step and wc_clutch_step give finite, physical
 *    outputs over a grid of operating points; none may fail.
 * The other calibration-check tests, by concern: test_calibration_fields.c
 * (each field, its limits, the relations between fields, the error names),
 * test_calibration_film.c (the film table); their shared part is
 * wc_test_calibration_harness.h. */
#include "wc_test_calibration_harness.h"

#include <float.h>
#include <stdio.h>

/* ------------------------------------------------------------------------ */
/* Variants of table1: up to three fields set, and the code expected.        */

typedef struct {
    size_t offset;
    float value;
} setting_t;

typedef struct {
    const char *label;
    wc_cal_error_t code;
    uint32_t count;
    setting_t set[3];
} variant_t;

#define SET(member, value) { offsetof(wc_calibration_t, member), (value) }
#define V1(code, m, v) { #m " = " #v, code, 1u, { SET(m, v), { 0u, 0.0f }, { 0u, 0.0f } } }
#define V2(code, m1, v1, m2, v2) \
    { #m1 " = " #v1 ", " #m2 " = " #v2, code, 2u, { SET(m1, v1), SET(m2, v2), { 0u, 0.0f } } }
#define V3(code, m1, v1, m2, v2, m3, v3) \
    { #m1 " = " #v1 ", " #m2 " = " #v2 ", " #m3 " = " #v3, code, 3u, { SET(m1, v1), SET(m2, v2), SET(m3, v3) } }

static void apply_variant(cal_copy_t *c, const variant_t *v)
{
    copy_table1(c);
    for (uint32_t k = 0u; k < v->count; ++k) {
        *field_ptr(&c->cal, v->set[k].offset) = v->set[k].value;
    }
}

/* Rejected. Single-field ones: mirrored in tests/python/test_calibration_rules.py (REJECTED). */
static const variant_t rejected_variants[] = {
    /* geometry: 0 < R_i < R_o <= 1 m, 0 < A_f <= pi R_o^2, 0 < A_p <= 1 m^2 */
    V1(WC_CAL_OUTER_RADIUS, outer_radius_m, 0.0f),
    V1(WC_CAL_OUTER_RADIUS, outer_radius_m, -0.08f),
    V1(WC_CAL_OUTER_RADIUS, outer_radius_m, 1.5f),
    V1(WC_CAL_OUTER_RADIUS, outer_radius_m, 1e30f),           /* issue 10: R_eff inf */
    V1(WC_CAL_INNER_RADIUS, inner_radius_m, 0.0f),
    V1(WC_CAL_INNER_RADIUS, inner_radius_m, 0.08315f),        /* == R_o */
    V1(WC_CAL_INNER_RADIUS, inner_radius_m, 0.09f),
    V1(WC_CAL_FRICTION_AREA, friction_area_m2, 0.0f),
    V1(WC_CAL_FRICTION_AREA, friction_area_m2, 0.022f),       /* > pi R_o^2 = 0.02172 m^2 */
    V1(WC_CAL_FRICTION_AREA, friction_area_m2, 1e30f),
    V1(WC_CAL_PISTON_AREA, piston_area_m2, 0.0f),
    V1(WC_CAL_PISTON_AREA, piston_area_m2, 1.5f),
    /* thermal: 0 < k1 <= 1e5, 0 <= k2 <= 1e5, k1 + k2 >= 1e-3 W/K, 0 < C <= 1e7 J/K,
     * dt <= C / (k1 + k2) <= 1e5 s */
    V1(WC_CAL_OIL_CONDUCTANCE, oil_conductance_W_per_K, 0.0f),
    V1(WC_CAL_OIL_CONDUCTANCE, oil_conductance_W_per_K, -1.0f),
    V1(WC_CAL_OIL_CONDUCTANCE, oil_conductance_W_per_K, 2e5f),
    V1(WC_CAL_HOUSING_CONDUCTANCE, housing_conductance_W_per_K, -1.0f),
    V1(WC_CAL_HOUSING_CONDUCTANCE, housing_conductance_W_per_K, 2e5f),
    V1(WC_CAL_HEAT_CAPACITY, heat_capacity_J_per_K, 0.0f),
    V1(WC_CAL_HEAT_CAPACITY, heat_capacity_J_per_K, 2e7f),
    V1(WC_CAL_THERMAL_TIME_CONSTANT, heat_capacity_J_per_K, 0.1f),   /* 0.6 ms < dt = 1 ms */
    /* viscosity (eq. 2): 0 <= a <= 100 Pa s, |b| <= 0.3 /K, 0 < mu_v <= 100 Pa s on the domain */
    V1(WC_CAL_VISCOSITY_A1, viscosity_a1_Pa_s, -0.1f),
    V1(WC_CAL_VISCOSITY_A1, viscosity_a1_Pa_s, 200.0f),
    V1(WC_CAL_VISCOSITY_B1, viscosity_b1_per_K, 0.36f),      /* issue 10: e^(0.36 * 250) overflows */
    V1(WC_CAL_VISCOSITY_B1, viscosity_b1_per_K, -0.31f),
    V1(WC_CAL_VISCOSITY_RANGE, viscosity_b1_per_K, 0.3f),    /* mu_v(250 degC) = 0.15 e^75 Pa s */
    V1(WC_CAL_VISCOSITY_RANGE, viscosity_a1_Pa_s, 50.0f),    /* mu_v(-40 degC) = 50 e^3.1 = 1150 Pa s */
    V1(WC_CAL_VISCOSITY_A2, viscosity_a2_Pa_s, -0.1f),
    V1(WC_CAL_VISCOSITY_B2, viscosity_b2_per_K, 0.5f),
    V1(WC_CAL_VISCOSITY_B2, viscosity_b2_per_K, -0.5f),
    V1(WC_CAL_VISCOSITY_RANGE, viscosity_b2_per_K, -0.2f),   /* mu_v(-40 degC) = 0.058 e^8 = 173 Pa s */
    /* friction (eq. 18): 1e-3 <= mu1, mu2 <= 1, 1e-6 <= v_s <= 100 m/s, theta1 in the domain,
     * theta2 >= 1 K, 0 < mu_f <= 1 on the domain */
    V1(WC_CAL_MU1, mu1, 0.0f),
    V1(WC_CAL_MU1, mu1, -0.1f),
    V1(WC_CAL_MU1, mu1, 5e-4f),                               /* below 1e-3: mu_f may round to 0 */
    V1(WC_CAL_MU1, mu1, 1.5f),
    V1(WC_CAL_FRICTION_DOMAIN, mu1, 0.5f),                   /* mu_f(250 degC) = 0.5 * 2.56 */
    V1(WC_CAL_MU2, mu2, 0.0f),
    V1(WC_CAL_MU2, mu2, 1.5f),
    V1(WC_CAL_MU2, mu2, 1e-30f),                              /* mu1 + (mu2 - mu1) = 0 in float */
    V1(WC_CAL_FRICTION_DOMAIN, mu3, -0.52f),                 /* issue 10: mu_f(250 degC) < 0 */
    V1(WC_CAL_FRICTION_DOMAIN, mu3, 1.0f),                   /* mu_f(-40 degC) < 0 */
    V1(WC_CAL_FRICTION_DOMAIN, mu3, 1e30f),
    V1(WC_CAL_STRIBECK_SPEED, stribeck_speed_m_s, 0.0f),
    V1(WC_CAL_STRIBECK_SPEED, stribeck_speed_m_s, 1e-7f),
    V1(WC_CAL_STRIBECK_SPEED, stribeck_speed_m_s, 200.0f),
    V1(WC_CAL_THETA1, theta1_degC, -41.0f),
    V1(WC_CAL_THETA1, theta1_degC, 251.0f),
    V1(WC_CAL_FRICTION_DOMAIN, theta1_degC, 250.0f),         /* mu_f(-40 degC) < 0 */
    V1(WC_CAL_THETA2, theta2_K, 1e-38f),                     /* issue 10: mu_f inf/NaN */
    V1(WC_CAL_THETA2, theta2_K, 0.5f),
    V1(WC_CAL_THETA2, theta2_K, 0.0f),
    V1(WC_CAL_THETA2, theta2_K, -70.0f),
    V1(WC_CAL_FRICTION_DOMAIN, theta2_K, 10.0f),             /* mu_f(-40 degC) < 0 */
    /* hydraulics: 0 < K <= 1e6 Pa/mA, 1e-4 <= tau <= 10 s, 0 <= F_s <= 1e5 N,
     * 0 <= i_min < i_max <= 1e4 mA, 0 < K i_max A_p - F_s, K i_max A_p <= WC_FORCE_MAX_N */
    V1(WC_CAL_VFS_GAIN, vfs_gain_Pa_per_mA, 0.0f),
    V1(WC_CAL_VFS_GAIN, vfs_gain_Pa_per_mA, 2e6f),
    V1(WC_CAL_VFS_CURRENT_MAX, vfs_gain_Pa_per_mA, 1e5f),    /* piston force 4.98e5 N */
    V1(WC_CAL_VFS_CURRENT_MAX, vfs_gain_Pa_per_mA, 100.0f),  /* 498 N < F_s: cannot apply */
    V1(WC_CAL_VFS_TIME_CONSTANT, vfs_time_constant_s, 0.0f),
    V1(WC_CAL_VFS_TIME_CONSTANT, vfs_time_constant_s, 5e-5f),
    V1(WC_CAL_VFS_TIME_CONSTANT, vfs_time_constant_s, 20.0f),
    V1(WC_CAL_RETURN_SPRING_FORCE, return_spring_force_N, -1.0f),
    V1(WC_CAL_RETURN_SPRING_FORCE, return_spring_force_N, 2e5f),
    V1(WC_CAL_VFS_CURRENT_MAX, return_spring_force_N, 20000.0f),  /* above the piston's 11456 N */
    V1(WC_CAL_VFS_CURRENT_MIN, vfs_current_min_mA, -1.0f),
    V1(WC_CAL_VFS_CURRENT_MIN, vfs_current_min_mA, 2e4f),
    V1(WC_CAL_VFS_CURRENT_MAX, vfs_current_min_mA, 1000.0f),      /* == the maximum */
    V1(WC_CAL_VFS_CURRENT_MAX, vfs_current_max_mA, 0.0f),
    V1(WC_CAL_VFS_CURRENT_MAX, vfs_current_max_mA, 2e4f),
    V1(WC_CAL_FILM_COVERAGE, vfs_current_max_mA, 1700.0f),        /* p_c 4.66 MPa > the table's 4.2 MPa */
    /* control period: 1e-4..0.1 s */
    V1(WC_CAL_CONTROL_PERIOD, control_period_s, 0.0f),
    V1(WC_CAL_CONTROL_PERIOD, control_period_s, 5e-5f),
    V1(WC_CAL_CONTROL_PERIOD, control_period_s, 0.2f),
    /* engagement edges (DESIGN 9) */
    V1(WC_CAL_FILM_SQUEEZE_FACTOR, film_squeeze_factor, -0.1f),
    V1(WC_CAL_FILM_SQUEEZE_FACTOR, film_squeeze_factor, 1.5f),
    V1(WC_CAL_FILM_SQUEEZE_FACTOR, film_squeeze_factor, 1e-5f),    /* neither off nor resolvable */
    V1(WC_CAL_STATIC_FRICTION_FACTOR, static_friction_factor, 0.4f),
    V1(WC_CAL_STATIC_FRICTION_FACTOR, static_friction_factor, 2.5f),
    V1(WC_CAL_LOCK_SLIP, lock_slip_rad_s, 0.0f),
    V1(WC_CAL_LOCK_SLIP, lock_slip_rad_s, 11.0f),
    V1(WC_CAL_BREAKAWAY_SLIP, breakaway_slip_rad_s, 0.0f),
    V1(WC_CAL_BREAKAWAY_SLIP, breakaway_slip_rad_s, 25.0f),
    V1(WC_CAL_BREAKAWAY_SLIP, breakaway_slip_rad_s, 0.3f),          /* == the lock band: no hysteresis */
    V1(WC_CAL_HOLDING_MARGIN, holding_margin, 0.0f),                /* no torque hysteresis */
    V1(WC_CAL_HOLDING_MARGIN, holding_margin, 1.5f),
    /* the open element's drag (DESIGN 15): clearance 0..5 mm, aeration speed 0 (off) or 1..1e4 rad/s */
    V1(WC_CAL_OPEN_CLEARANCE, open_clearance_m, -1e-6f),
    V1(WC_CAL_OPEN_CLEARANCE, open_clearance_m, 6e-3f),
    V1(WC_CAL_OPEN_AERATION_SPEED, open_aeration_speed_rad_s, -1.0f),
    V1(WC_CAL_OPEN_AERATION_SPEED, open_aeration_speed_rad_s, 0.5f),   /* neither off nor a speed */
    V1(WC_CAL_OPEN_AERATION_SPEED, open_aeration_speed_rad_s, 2e4f),
    /* relations of several fields */
    V2(WC_CAL_CONDUCTANCE_SUM, oil_conductance_W_per_K, 1e-40f, housing_conductance_W_per_K, 0.0f),  /* issue 10 */
    V2(WC_CAL_CONDUCTANCE_SUM, oil_conductance_W_per_K, 5e-4f, housing_conductance_W_per_K, 4e-4f),
    V3(WC_CAL_THERMAL_TIME_CONSTANT, oil_conductance_W_per_K, 1.0f, housing_conductance_W_per_K, 0.0f,
       heat_capacity_J_per_K, 1e6f),                                                          /* 1e6 s */
    V2(WC_CAL_THERMAL_TIME_CONSTANT, heat_capacity_J_per_K, 5.0f, control_period_s, 0.05f),    /* 31 ms < dt */
    V2(WC_CAL_VISCOSITY_RANGE, viscosity_a1_Pa_s, 0.0f, viscosity_a2_Pa_s, 0.0f),              /* mu_v = 0 */
    V2(WC_CAL_VISCOSITY_RANGE, viscosity_a1_Pa_s, 1e-45f, viscosity_a2_Pa_s, 0.0f),            /* underflows */
    V2(WC_CAL_FRICTION_DOMAIN, mu2, 1.0f, mu3, 0.01f),                                         /* mu_f 1.03 */
    V2(WC_CAL_THERMAL_TIME_CONSTANT, oil_conductance_W_per_K, 1e-3f, housing_conductance_W_per_K, 0.0f), /* 2.9e5 s */
};

/* Accepted: the limits are not over-tight. Single-field ones: mirrored in the Python test (ACCEPTED). */
static const variant_t accepted_variants[] = {
    V1(WC_CAL_OK, outer_radius_m, 1.0f),
    V1(WC_CAL_OK, inner_radius_m, 1e-6f),
    V1(WC_CAL_OK, friction_area_m2, 0.0217f),              /* just below pi R_o^2 */
    V1(WC_CAL_OK, piston_area_m2, 0.006f),
    V1(WC_CAL_OK, oil_conductance_W_per_K, 1e5f),          /* C / (k1 + k2) = 2.9 ms */
    V1(WC_CAL_OK, oil_conductance_W_per_K, 1e-40f),        /* k2 carries the heat */
    V1(WC_CAL_OK, housing_conductance_W_per_K, 0.0f),
    V1(WC_CAL_OK, heat_capacity_J_per_K, 1e4f),
    V1(WC_CAL_OK, viscosity_a1_Pa_s, 0.0f),
    V1(WC_CAL_OK, viscosity_a2_Pa_s, 0.0f),
    V1(WC_CAL_OK, viscosity_b1_per_K, 0.0f),
    V1(WC_CAL_OK, viscosity_b2_per_K, 0.0f),
    V1(WC_CAL_OK, viscosity_b1_per_K, -0.1f),
    V1(WC_CAL_OK, mu1, 0.3f),
    V1(WC_CAL_OK, mu2, 0.39f),                              /* mu_f(250 degC) = 0.999 */
    V1(WC_CAL_OK, mu3, 0.0f),
    V1(WC_CAL_OK, mu3, 0.87f),                              /* mu_f(-40 degC) = 0.0006 */
    V1(WC_CAL_OK, mu3, -0.3f),
    V1(WC_CAL_OK, stribeck_speed_m_s, 1e-6f),
    V1(WC_CAL_OK, stribeck_speed_m_s, 100.0f),
    V1(WC_CAL_OK, theta1_degC, -40.0f),
    V1(WC_CAL_OK, theta1_degC, 90.0f),
    V1(WC_CAL_OK, theta2_K, 1e30f),
    V1(WC_CAL_OK, vfs_gain_Pa_per_mA, 3000.0f),
    V1(WC_CAL_OK, vfs_time_constant_s, 1e-4f),
    V1(WC_CAL_OK, vfs_time_constant_s, 10.0f),
    V1(WC_CAL_OK, return_spring_force_N, 0.0f),
    V1(WC_CAL_OK, return_spring_force_N, 11000.0f),        /* 456 N left to apply */
    V1(WC_CAL_OK, vfs_current_min_mA, 500.0f),
    V1(WC_CAL_OK, vfs_current_max_mA, 1400.0f),
    V1(WC_CAL_OK, control_period_s, 1e-4f),
    V1(WC_CAL_OK, control_period_s, 0.1f),
    V1(WC_CAL_OK, open_clearance_m, 1.875e-4f),             /* 1.5 mm over 8 gaps */
    V1(WC_CAL_OK, open_clearance_m, 5e-3f),
    V1(WC_CAL_OK, open_aeration_speed_rad_s, 1.0f),         /* the strongest aeration: slip / w_a up to 1047 */
    V1(WC_CAL_OK, open_aeration_speed_rad_s, 157.08f),      /* 1500 rpm */
    V1(WC_CAL_OK, open_aeration_speed_rad_s, 1e4f),
    V2(WC_CAL_OK, open_clearance_m, 5e-3f, open_aeration_speed_rad_s, 1.0f),
    V2(WC_CAL_OK, viscosity_a1_Pa_s, 0.0f, viscosity_b1_per_K, 0.3f),
    V2(WC_CAL_OK, viscosity_a1_Pa_s, 0.0f, viscosity_b1_per_K, -0.3f),
    V2(WC_CAL_OK, theta2_K, 1.0f, mu3, 0.0f),
    V2(WC_CAL_OK, mu2, 1.0f, mu3, 0.0f),
    V3(WC_CAL_OK, oil_conductance_W_per_K, 1e-3f, housing_conductance_W_per_K, 0.0f,
       heat_capacity_J_per_K, 100.0f),                     /* k1 + k2 at its limit, C / (k1 + k2) at its */
};

static void test_rejected_variants(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(rejected_variants); ++i) {
        cal_copy_t c;
        apply_variant(&c, &rejected_variants[i]);
        expect_code(&c.cal, rejected_variants[i].code, rejected_variants[i].label, (double)i);
    }
}

static void test_accepted_variants(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(accepted_variants); ++i) {
        cal_copy_t c;
        apply_variant(&c, &accepted_variants[i]);
        expect_code(&c.cal, WC_CAL_OK, accepted_variants[i].label, (double)i);
    }
}

/* ------------------------------------------------------------------------ */
/* The sweep: accepted calibrations give finite, physical outputs.           */

typedef struct {
    long checks;
    long violations;
    const char *label;  /* the variant, for the first violations' messages */
    bool quiet;         /* count only (rejected variants run unchecked) */
} sweep_t;

static void violation(sweep_t *s, const char *format, ...)
{
    ++s->violations;
    if (s->quiet || (s->violations > 3)) { return; }
    va_list args;
    va_start(args, format);
    char text[256];
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    print_error("    unphysical [%s]: %s\n", s->label, text);
}

#define PHYSICAL(s, cond, ...) do { ++(s)->checks; if (!(cond)) { violation((s), __VA_ARGS__); } } while (0)

static const float sweep_slips[] = { -WC_SLIP_MAX_rad_s, -500.0f, -10.0f, -1e-3f, 0.0f, 1e-3f, 10.0f, 500.0f,
                                     WC_SLIP_MAX_rad_s };
static const float sweep_thetas[] = { WC_THETA_MIN_degC, -10.0f, 40.0f, 100.0f, 200.0f, WC_THETA_MAX_degC };
#define MU_F_ROUNDING 1.000001f   /* mu_f <= 1 up to a few float roundings of eq. 18 */

/* The torque result at a valid input: finite, acting against the slip. */
static void check_torque_out(sweep_t *s, const wc_torque_t *t, float slip, const char *where)
{
    PHYSICAL(s, isfinite(t->torque_Nm) && isfinite(t->coulomb_Nm) && isfinite(t->viscous_Nm),
             "%s: torque not finite (%g = %g + %g) at slip %g", where, (double)t->torque_Nm, (double)t->coulomb_Nm,
             (double)t->viscous_Nm, (double)slip);
    PHYSICAL(s, isfinite(t->hbar_m) && (t->hbar_m > 0.0f), "%s: h_bar %g at slip %g", where, (double)t->hbar_m,
             (double)slip);
    PHYSICAL(s, (t->mu_f > 0.0f) && (t->mu_f <= MU_F_ROUNDING), "%s: mu_f %g", where, (double)t->mu_f);
    if (slip < 0.0f) {
        PHYSICAL(s, (t->torque_Nm <= 0.0f) && (t->coulomb_Nm <= 0.0f) && (t->viscous_Nm <= 0.0f),
                 "%s: torque %g (%g + %g) at negative slip %g", where, (double)t->torque_Nm, (double)t->coulomb_Nm,
                 (double)t->viscous_Nm, (double)slip);
    } else {
        PHYSICAL(s, (t->torque_Nm >= 0.0f) && (t->coulomb_Nm >= 0.0f) && (t->viscous_Nm >= 0.0f),
                 "%s: torque %g (%g + %g) at slip %g >= 0", where, (double)t->torque_Nm, (double)t->coulomb_Nm,
                 (double)t->viscous_Nm, (double)slip);
    }
}

static void check_current(sweep_t *s, const wc_calibration_t *cal, float current_mA, const char *where)
{
    PHYSICAL(s, (current_mA >= cal->vfs_current_min_mA) && (current_mA <= cal->vfs_current_max_mA),
             "%s: current %g mA outside [%g, %g]", where, (double)current_mA, (double)cal->vfs_current_min_mA,
             (double)cal->vfs_current_max_mA);
}

/* wc_model_init's derived constants, without the check: to measure what a
 * rejected calibration would have done (diagnostic only). */
static void bind_unchecked(wc_model_t *model, const wc_calibration_t *cal)
{
    const float ro = cal->outer_radius_m;
    const float ri = cal->inner_radius_m;
    model->effective_radius_m = (2.0f / 3.0f) * (ro * ro + ro * ri + ri * ri) / (ro + ri);
    const float force_N = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 -
                          cal->return_spring_force_N;
    model->force_max_N = (force_N > 0.0f) ? force_N : 0.0f;
    model->hbar_at_force_max_m = wc_film_hbar_m(&cal->film, model->force_max_N / cal->friction_area_m2);
    const float k = cal->oil_conductance_W_per_K + cal->housing_conductance_W_per_K;
    model->thermal_decay = expf(-k * cal->control_period_s / cal->heat_capacity_J_per_K);
    model->vfs_decay = expf(-cal->control_period_s / cal->vfs_time_constant_s);
    model->film_damping_m4 = 0.0f;  /* the steady film: the diagnostics measure the paper's model */
    model->cal = cal;
}

/* Every public function over the grid; counts the checks and the violations. */
static void sweep_model(sweep_t *s, const wc_model_t *model)
{
    const wc_calibration_t *cal = model->cal;
    const float f_max = model->force_max_N;
    PHYSICAL(s, isfinite(f_max) && (f_max > 0.0f) && (f_max <= WC_FORCE_MAX_N), "force at i_max %g", (double)f_max);
    PHYSICAL(s, (model->thermal_decay >= 0.0f) && (model->thermal_decay <= 1.0f), "thermal decay %g",
             (double)model->thermal_decay);
    PHYSICAL(s, (model->vfs_decay >= 0.0f) && (model->vfs_decay <= 1.0f), "vfs decay %g", (double)model->vfs_decay);
    const float forces[] = { 0.0f, 1e-3f, 0.25f * f_max, 0.5f * f_max, f_max, WC_FORCE_MAX_N };
    const float request_fractions[] = { 0.0f, 1e-3f, 0.1f, 0.5f, 0.999f, 1.0f, 2.0f };

    for (size_t a = 0u; a < WC_TEST_COUNT(sweep_slips); ++a) {
        const float slip = sweep_slips[a];
        for (size_t b = 0u; b < WC_TEST_COUNT(sweep_thetas); ++b) {
            const float theta = sweep_thetas[b];
            wc_torque_t t;
            for (size_t f = 0u; f < WC_TEST_COUNT(forces); ++f) {
                const wc_status_t st = wc_torque(model, slip, theta, forces[f], &t);
                PHYSICAL(s, st == WC_STATUS_OK, "wc_torque status 0x%x at valid input", (unsigned)st);
                check_torque_out(s, &t, slip, "wc_torque");
            }
            (void)wc_torque(model, slip, theta, f_max, &t);
            const float capacity = fabsf(t.torque_Nm);
            for (size_t r = 0u; r <= WC_TEST_COUNT(request_fractions); ++r) {
                float request = (r < WC_TEST_COUNT(request_fractions)) ? request_fractions[r] * capacity
                                                                         : WC_TORQUE_MAX_Nm;
                request = (request <= WC_TORQUE_MAX_Nm) ? request : WC_TORQUE_MAX_Nm;  /* valid input */
                wc_inverse_t inv;
                const wc_status_t st = wc_inverse(model, slip, theta, request, &inv);
                PHYSICAL(s, (st & WC_STATUS_INPUT_INVALID) == 0u, "wc_inverse status 0x%x at valid input",
                         (unsigned)st);
                PHYSICAL(s, isfinite(inv.force_N) && (inv.force_N >= 0.0f) && (inv.force_N <= f_max),
                         "wc_inverse force %g outside [0, %g] (request %g)", (double)inv.force_N, (double)f_max,
                         (double)request);
                PHYSICAL(s, isfinite(inv.pressure_Pa) && (inv.pressure_Pa >= 0.0f), "wc_inverse pressure %g",
                         (double)inv.pressure_Pa);
                PHYSICAL(s, inv.iterations <= WC_INVERSE_MAX_ITERATIONS, "wc_inverse %u iterations",
                         (unsigned)inv.iterations);
                check_current(s, cal, inv.current_mA, "wc_inverse");
            }
        }
    }

    const float powers[] = { 0.0f, 1e3f, 1e9f, FLT_MAX };
    for (size_t a = 0u; a < WC_TEST_COUNT(sweep_thetas); ++a) {
        for (size_t b = 0u; b < WC_TEST_COUNT(sweep_thetas); b += 2u) {
            for (size_t c = 1u; c < WC_TEST_COUNT(sweep_thetas); c += 2u) {
                for (size_t p = 0u; p < WC_TEST_COUNT(powers); ++p) {
                    float theta = sweep_thetas[a];
                    const wc_status_t st = wc_thermal_step(model, &theta, powers[p], sweep_thetas[b], sweep_thetas[c]);
                    PHYSICAL(s, st == WC_STATUS_OK, "wc_thermal_step status 0x%x", (unsigned)st);
                    PHYSICAL(s, (theta >= WC_THETA_MIN_degC) && (theta <= WC_THETA_MAX_degC),
                             "wc_thermal_step theta %g (power %g)", (double)theta, (double)powers[p]);
                }
            }
        }
    }
}

/* wc_clutch_step through a scripted run: every mode, every slip and
 * temperature of the grid, requests 0..1e5 Nm, bench input, a long locked
 * slip that heats the pack to the envelope. */
static void sweep_clutch(sweep_t *s, wc_clutch_t *clutch)
{
    const wc_calibration_t *cal = clutch->model.cal;
    const float f_max = clutch->model.force_max_N;
    const float requests[] = { 0.0f, 1.0f, 50.0f, 500.0f, 5000.0f, WC_TORQUE_MAX_Nm };
    for (uint32_t k = 0u; k < 160u; ++k) {
        wc_step_input_t in;
        memset(&in, 0, sizeof in);
        const bool heat = (k >= 100u) && (k < 140u);
        in.slip_rad_s = heat ? WC_SLIP_MAX_rad_s : sweep_slips[k % WC_TEST_COUNT(sweep_slips)];
        in.theta_oil_degC = sweep_thetas[(k / 3u) % WC_TEST_COUNT(sweep_thetas)];
        in.theta_housing_degC = sweep_thetas[(k / 5u) % WC_TEST_COUNT(sweep_thetas)];
        in.torque_request_Nm = requests[k % WC_TEST_COUNT(requests)];
        in.mode = heat ? WC_MODE_LOCKED
                : ((k % 7u) == 3u) ? WC_MODE_LOCKED : (((k % 11u) == 5u) ? WC_MODE_OPEN : WC_MODE_TORQUE);
        if ((k % 13u) == 6u) {
            in.bench.valid = true;
            in.bench.apply_force_N = 0.5f * f_max;
            in.bench.torque_Nm = ((k & 1u) != 0u) ? WC_TORQUE_MAX_Nm : -WC_TORQUE_MAX_Nm;
        }
        wc_step_output_t out;
        (void)wc_clutch_step(clutch, &in, &out);
        check_current(s, cal, out.current_mA, "wc_clutch_step");
        PHYSICAL(s, isfinite(out.pressure_command_Pa) && (out.pressure_command_Pa >= 0.0f),
                 "wc_clutch_step pressure command %g", (double)out.pressure_command_Pa);
        PHYSICAL(s, isfinite(out.pressure_model_Pa) && (out.pressure_model_Pa >= 0.0f),
                 "wc_clutch_step pressure model %g", (double)out.pressure_model_Pa);
        PHYSICAL(s, isfinite(out.force_command_N) && (out.force_command_N >= 0.0f) &&
                        (out.force_command_N <= WC_FORCE_MAX_N),
                 "wc_clutch_step force command %g", (double)out.force_command_N);
        PHYSICAL(s, (out.theta_degC >= WC_THETA_MIN_degC) && (out.theta_degC <= WC_THETA_MAX_degC),
                 "wc_clutch_step theta %g", (double)out.theta_degC);
        PHYSICAL(s, (clutch->theta_degC >= WC_THETA_MIN_degC) && (clutch->theta_degC <= WC_THETA_MAX_degC),
                 "wc_clutch_step state theta %g", (double)clutch->theta_degC);
        /* Inside the lock band the torque keeps the lock direction (DESIGN 9); locked, it is the held
         * torque, within the static capacity. */
        const float slip = clutch->held.slip_rad_s;
        const float direction = (clutch->lockup.direction < 0) ? -1.0f : 1.0f;
        const bool keeps_direction = (fabsf(slip) < cal->lock_slip_rad_s) || ((out.status & WC_STATUS_LOCKED) != 0u);
        const float sign_slip = keeps_direction ? direction * fmaxf(fabsf(slip), FLT_MIN) : slip;
        check_torque_out(s, &out.model, sign_slip, "wc_clutch_step");
        PHYSICAL(s, isfinite(out.static_capacity_Nm) && (out.static_capacity_Nm >= 0.0f),
                 "wc_clutch_step static capacity %g", (double)out.static_capacity_Nm);
        if ((out.status & WC_STATUS_LOCKED) != 0u) {
            PHYSICAL(s, fabsf(out.model.torque_Nm) <= out.static_capacity_Nm,
                     "wc_clutch_step locked torque %g above the capacity %g", (double)out.model.torque_Nm,
                     (double)out.static_capacity_Nm);
        }
    }
}

/* The whole sweep for an accepted calibration (wc_model_init / wc_clutch_init)
 * or, with unchecked = true, for a rejected one bound without the check. */
static long sweep(const wc_calibration_t *cal, const char *label, bool unchecked)
{
    sweep_t s = { 0, 0, label, unchecked };
    wc_clutch_t clutch;
    if (unchecked) {
        memset(&clutch, 0, sizeof clutch);
        bind_unchecked(&clutch.model, cal);
        clutch.theta_degC = 40.0f;
        clutch.pressure_model_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_min_mA;
        clutch.held.theta_oil_degC = 40.0f;
        clutch.held.theta_housing_degC = 40.0f;
    } else if (wc_clutch_init(&clutch, cal, 40.0f) != WC_CAL_OK) {
        violation(&s, "wc_clutch_init refused an accepted calibration");
        return s.violations;
    }
    sweep_model(&s, &clutch.model);
    sweep_clutch(&s, &clutch);
    return s.violations;
}

static void test_sweep_listed_variants(void **state)
{
    (void)state;
    long bad = sweep(&wc_table1_calibration, "table1", false);
    for (size_t i = 0u; i < WC_TEST_COUNT(accepted_variants); ++i) {
        cal_copy_t c;
        apply_variant(&c, &accepted_variants[i]);
        bad += sweep(&c.cal, accepted_variants[i].label, false);
    }
    /* the listed rejected variants, bound without the check: how many break
     * the promise on the grid (printed), and the examples must */
    static const char *const examples[] = { "viscosity_b1_per_K = 0.36f", "theta2_K = 1e-38f", "mu3 = -0.52f",
                                            "outer_radius_m = 1e30f" };
    long shown = 0;
    long broken_total = 0;
    for (size_t i = 0u; i < WC_TEST_COUNT(rejected_variants); ++i) {
        cal_copy_t c;
        apply_variant(&c, &rejected_variants[i]);
        const long broken = sweep(&c.cal, rejected_variants[i].label, true);
        broken_total += (broken > 0) ? 1 : 0;
        for (size_t e = 0u; e < WC_TEST_COUNT(examples); ++e) {
            if (strcmp(rejected_variants[i].label, examples[e]) == 0) {
                WC_CHECK(broken > 0, "the issue's example %s should break the promise unchecked", examples[e]);
                ++shown;
            }
        }
    }
    print_message("    listed rejected variants that break the promise when used unchecked: %ld of %lu\n",
                  broken_total, (unsigned long)WC_TEST_COUNT(rejected_variants));
    assert_int_equal(shown, WC_TEST_COUNT(examples));
    WC_CHECK(bad == 0, "%ld unphysical outputs from accepted calibrations", bad);
}

/* xorshift64*: deterministic, so a failure reproduces. */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint32_t rng_next(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 0x2545F4914F6CDD1Dull) >> 32);
}
static float rng_unit(void) { return (float)(rng_next() >> 8) * (1.0f / 16777216.0f); }  /* [0, 1) */
static uint32_t rng_below(uint32_t n) { return rng_next() % n; }

static void mutate_float(float *v)
{
    static const float specials[] = { 0.0f, -0.0f, FLT_MIN, 1e-40f, 1e-30f, 1e-6f, 1.0f, 1e6f, 1e30f, FLT_MAX,
                                      -1.0f, NAN, INFINITY, -INFINITY };
    switch (rng_below(6u)) {
    case 0: *v *= powf(10.0f, 8.0f * rng_unit() - 4.0f); break;                  /* 1e-4 .. 1e4 times */
    case 1: *v *= 0.25f + 3.75f * rng_unit(); break;                               /* 0.25 .. 4 times */
    case 2: *v *= 0.9f + 0.2f * rng_unit(); break;                                 /* +-10 % */
    case 3: *v = -(*v) * powf(10.0f, 4.0f * rng_unit() - 2.0f); break;            /* sign flipped */
    case 4: *v += (rng_unit() - 0.5f) * 4.0f * (fabsf(*v) + 1.0f); break;          /* through zero */
    default: *v = specials[rng_below((uint32_t)WC_TEST_COUNT(specials))]; break;
    }
}

static void mutate_film(cal_copy_t *c)
{
    const uint32_t n = c->cal.film.length;
    const uint32_t i = rng_below(n);
    const float factor = powf(10.0f, 4.0f * rng_unit() - 2.0f);
    switch (rng_below(9u)) {
    case 0:  /* the pressure axis scaled, slopes with it: same shape */
        for (uint32_t k = 0u; k < n; ++k) { c->pressure_Pa[k] *= factor; c->slope_m_per_Pa[k] /= factor; }
        break;
    case 1:  /* h_bar scaled, slopes with it */
        for (uint32_t k = 0u; k < n; ++k) { c->hbar_m[k] *= factor; c->slope_m_per_Pa[k] *= factor; }
        break;
    case 2:  /* all slopes scaled: Fritsch-Carlson in or out */
        for (uint32_t k = 0u; k < n; ++k) { c->slope_m_per_Pa[k] *= 0.5f + 3.0f * rng_unit(); }
        break;
    case 3: c->hbar_m[i] *= 0.5f + rng_unit(); break;
    case 4: c->slope_m_per_Pa[i] *= 1.0f + 60.0f * rng_unit(); break;
    case 5: c->pressure_Pa[i] *= 0.8f + 0.4f * rng_unit(); break;
    case 6: c->cal.film.length = 2u + rng_below(NODES - 1u); break;
    case 7:  /* h_bar shifted: same differences, the range moves */
        for (uint32_t k = 0u; k < n; ++k) { c->hbar_m[k] += (rng_unit() - 0.7f) * 2e-8f; }
        break;
    default: mutate_float(&c->slope_m_per_Pa[i]); break;
    }
}

/* 1 - 10^-k, k in 1..7: just inside a limit. */
static double inside(void) { return 1.0 - pow(10.0, -(double)(1u + rng_below(7u))); }

/* Largest alpha^2 + beta^2 of the table (Fritsch-Carlson), in double. */
static double fritsch_carlson_max(const cal_copy_t *c)
{
    double worst = 0.0;
    for (uint32_t k = 0u; k + 1u < c->cal.film.length; ++k) {
        const double delta = ((double)c->hbar_m[k + 1u] - (double)c->hbar_m[k]) /
                             ((double)c->pressure_Pa[k + 1u] - (double)c->pressure_Pa[k]);
        const double a = (double)c->slope_m_per_Pa[k] / delta;
        const double b = (double)c->slope_m_per_Pa[k + 1u] / delta;
        worst = (a * a + b * b > worst) ? a * a + b * b : worst;
    }
    return worst;
}

/* A calibration at the edge of one rule: where an unphysical output would
 * hide if a rule were too loose. */
static void mutate_edge(cal_copy_t *c)
{
    wc_calibration_t *cal = &c->cal;
    const uint32_t n = cal->film.length;
    const double end = (rng_below(2u) == 0u) ? (double)WC_THETA_MIN_degC : (double)WC_THETA_MAX_degC;
    switch (rng_below(11u)) {
    case 0:  /* mu_f's temperature factor just above 0 at one end */
        if (fabs(end - (double)cal->theta1_degC) > 1.0) {
            cal->mu3 = (float)(-(double)cal->theta2_K / (end - (double)cal->theta1_degC) * inside());
        }
        break;
    case 1: {  /* mu_f just below 1 */
        const double lo = 1.0 + (double)cal->mu3 * ((double)WC_THETA_MIN_degC - (double)cal->theta1_degC) /
                                (double)cal->theta2_K;
        const double hi = 1.0 + (double)cal->mu3 * ((double)WC_THETA_MAX_degC - (double)cal->theta1_degC) /
                                (double)cal->theta2_K;
        const double mu = inside() / ((lo > hi) ? lo : hi);
        if (rng_below(2u) == 0u) { cal->mu1 = (float)mu; } else { cal->mu2 = (float)mu; }
        break;
    }
    case 2: {  /* an exponent at its limit, mu_v just below its limit at that end */
        const float b = (rng_below(2u) == 0u) ? WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K
                                              : -WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K;
        const double at = (b > 0.0f) ? (double)WC_THETA_MAX_degC : (double)WC_THETA_MIN_degC;
        cal->viscosity_b1_per_K = b;
        cal->viscosity_a1_Pa_s = (float)(0.5 * (double)WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s * inside() / exp((double)b * at));
        break;
    }
    case 3: {  /* the thinnest node just above 1 nm (slopes scaled with h_bar) */
        const double f = (double)WC_CAL_LIMIT_FILM_HBAR_MIN_m / (double)c->hbar_m[n - 1u] / inside();
        for (uint32_t k = 0u; k < n; ++k) {
            c->hbar_m[k] = (float)((double)c->hbar_m[k] * f);
            c->slope_m_per_Pa[k] = (float)((double)c->slope_m_per_Pa[k] * f);
        }
        break;
    }
    case 4: {  /* h_bar from 1 mm down to 1 nm: h -> A h^g, the widest ratio the range allows */
        const double h0 = (double)c->hbar_m[0];
        const double h1 = (double)c->hbar_m[n - 1u];
        const double g = log(1e-3 / 1e-9) / log(h0 / h1);
        const double a = 1e-3 * inside() / pow(h0, g);
        for (uint32_t k = 0u; k < n; ++k) {
            const double h = (double)c->hbar_m[k];
            c->hbar_m[k] = (float)(a * pow(h, g));
            c->slope_m_per_Pa[k] = (float)(a * g * pow(h, g - 1.0) * (double)c->slope_m_per_Pa[k]);
        }
        c->hbar_m[n - 1u] = (c->hbar_m[n - 1u] < WC_CAL_LIMIT_FILM_HBAR_MIN_m) ? WC_CAL_LIMIT_FILM_HBAR_MIN_m
                                                                               : c->hbar_m[n - 1u];
        break;
    }
    case 5: {  /* slopes scaled to just inside the Fritsch-Carlson bound */
        const double f = sqrt(9.0 / fritsch_carlson_max(c)) * inside();
        for (uint32_t k = 0u; k < n; ++k) { c->slope_m_per_Pa[k] = (float)((double)c->slope_m_per_Pa[k] * f); }
        break;
    }
    case 6: {  /* thermal time constant at the control period or at its limit */
        const double k = (double)cal->oil_conductance_W_per_K + (double)cal->housing_conductance_W_per_K;
        const double tc = (rng_below(2u) == 0u) ? (double)cal->control_period_s / inside()
                                                : (double)WC_CAL_LIMIT_TIME_CONSTANT_MAX_s * inside();
        cal->heat_capacity_J_per_K = (float)(tc * k);
        break;
    }
    case 7:  /* k1 + k2 at its limit */
        cal->oil_conductance_W_per_K = WC_CAL_LIMIT_CONDUCTANCE_SUM_MIN_W_per_K;
        cal->housing_conductance_W_per_K = 0.0f;
        cal->heat_capacity_J_per_K = (float)((double)WC_CAL_LIMIT_CONDUCTANCE_SUM_MIN_W_per_K * 1e3 * inside());
        break;
    case 8: {  /* piston force at WC_FORCE_MAX_N, the table made to reach it */
        cal->vfs_current_max_mA = (float)((double)WC_FORCE_MAX_N * inside() /
                                          ((double)cal->vfs_gain_Pa_per_mA * (double)cal->piston_area_m2));
        cal->outer_radius_m = 0.3f;
        cal->friction_area_m2 = 0.25f;
        break;
    }
    case 9:  /* the spring just below the piston force: the clutch barely applies */
        cal->return_spring_force_N = (float)((double)cal->vfs_gain_Pa_per_mA * (double)cal->vfs_current_max_mA *
                                             (double)cal->piston_area_m2 * inside());
        break;
    default:  /* the table ends just at the contact pressure at the maximum current */
        cal->vfs_current_max_mA = (float)(((double)c->pressure_Pa[n - 1u] * (double)cal->friction_area_m2 +
                                           (double)cal->return_spring_force_N) * inside() /
                                          ((double)cal->vfs_gain_Pa_per_mA * (double)cal->piston_area_m2));
        break;
    }
}

static void mutate_one(cal_copy_t *c)
{
    if (rng_below(4u) == 0u) {
        mutate_edge(c);
        return;
    }
    const uint32_t pick = rng_below((uint32_t)WC_TEST_COUNT(float_fields) + 3u);
    if (pick < WC_TEST_COUNT(float_fields)) {
        mutate_float(field_ptr(&c->cal, float_fields[pick].offset));
    } else if (pick == WC_TEST_COUNT(float_fields)) {
        static const uint32_t pairs[] = { 0u, 1u, 2u, 63u, 64u, 65u, 1000u, UINT32_MAX };
        c->cal.friction_pairs = pairs[rng_below((uint32_t)WC_TEST_COUNT(pairs))];
    } else {
        mutate_film(c);
    }
}

static void test_sweep_random_variants(void **state)
{
    (void)state;
    enum { SINGLE = 3000, MULTI = 3000 };
    long accepted[2] = { 0, 0 };
    long rejected[2] = { 0, 0 };
    long unphysical_accepted = 0;
    long unphysical_rejected = 0;
    long codes[WC_CAL_ERRORS];
    memset(codes, 0, sizeof codes);
    char label[64];
    for (int v = 0; v < SINGLE + MULTI; ++v) {
        const int multi = (v >= SINGLE) ? 1 : 0;
        cal_copy_t c;
        copy_table1(&c);
        const uint32_t changes = multi ? 2u + rng_below(4u) : 1u;
        for (uint32_t k = 0u; k < changes; ++k) { mutate_one(&c); }
        snprintf(label, sizeof label, "random variant %d", v);
        const wc_cal_error_t code = wc_calibration_check(&c.cal);
        codes[code] += 1;
        if (code == WC_CAL_OK) {
            ++accepted[multi];
            unphysical_accepted += (sweep(&c.cal, label, false) > 0) ? 1 : 0;
        } else {
            ++rejected[multi];
            const bool bindable = (c.cal.friction_pairs >= 1u) && (c.cal.friction_pairs <= 1000u);
            if (bindable) { unphysical_rejected += (sweep(&c.cal, label, true) > 0) ? 1 : 0; }
        }
    }
    print_message("    random single-field variants: %ld accepted, %ld rejected\n", accepted[0], rejected[0]);
    print_message("    random multi-field variants (2-5 changes): %ld accepted, %ld rejected\n", accepted[1],
                  rejected[1]);
    print_message("    accepted but unphysical: %ld; rejected that would have been unphysical: %ld\n",
                  unphysical_accepted, unphysical_rejected);
    for (int e = 1; e < (int)WC_CAL_ERRORS; ++e) {
        if (codes[e] > 0) { print_message("      %5ld x %s\n", codes[e], wc_cal_error_name((wc_cal_error_t)e)); }
    }
    WC_CHECK(accepted[0] > 500 && accepted[1] > 100, "too few accepted variants to say anything (%ld, %ld)",
             accepted[0], accepted[1]);
    WC_CHECK(unphysical_accepted == 0, "%ld accepted calibrations gave unphysical outputs", unphysical_accepted);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rejected_variants),
        cmocka_unit_test(test_accepted_variants),
        cmocka_unit_test(test_sweep_listed_variants),
        cmocka_unit_test(test_sweep_random_variants),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
