/* wc_calibration_check: the rules of DESIGN section 8, "Calibration validity".
 *
 * What each rule proves (the limits and their reasons are in
 * include/wetclutch/wc_calibration.h; tools/wetclutch/calibration/rules.py applies
 * the same rules). On the model's domain, theta in [WC_THETA_MIN_degC,
 * WC_THETA_MAX_degC], |slip| <= WC_SLIP_MAX_rad_s, 0 <= F_c <= WC_FORCE_MAX_N:
 *  - R_eff = 2/3 (Ro^2 + Ro Ri + Ri^2) / (Ro + Ri) lies in (Ri, Ro) <= 1 m, so
 *    v = R_eff |dw| <= 1047 m/s and the torque arm R_eff N_c <= 64 m;
 *  - eq. 2: |b theta| <= 75 keeps wc_exp in its domain; each term a e^(b theta)
 *    is monotone, so mu_v lies between the sums of the terms' values at the
 *    two ends, which must be > 0 and <= the limit;
 *  - eq. 18: the Stribeck factor lies between mu1 and mu2 (in [1e-3, 1]); the
 *    temperature factor is linear in theta, so it is positive on the domain
 *    when it is at both ends, and mu_f <= max(mu1, mu2) times its larger end;
 *  - eq. 1: k1 + k2 bounded away from 0 and a thermal time constant between
 *    the control period and the limit give a finite steady state and a decay
 *    factor in [1/e, 1];
 *  - hydraulics: the piston applies (K i_max A_p > F_s) and its force stays
 *    within WC_FORCE_MAX_N, the inverse's range;
 *  - film: nodes in [h_min, h_max] and the Fritsch-Carlson condition on every
 *    interval make the cubic Hermite monotone, hence between its nodes: h_bar
 *    is positive and bounded wherever it is evaluated, and T_v = ... / h_bar
 *    is finite; the table reaches the contact pressure at the maximum current.
 * Every comparison is written so that NaN fails it. The fields are checked
 * first, each against its range (declaration order), then the relations. */
#include "wetclutch/wc_calibration.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "wc_field_ranges.h"
#include "wc_internal.h"

/* x in [lo, hi]. False for NaN (every comparison with NaN is false), and for
 * +-Inf when the bounds are finite. */
static bool within(float x, float lo, float hi) { return (x >= lo) && (x <= hi); }

static float larger(float a, float b) { return (a > b) ? a : b; }
static float smaller(float a, float b) { return (a < b) ? a : b; }

/* The range of each scalar field, in declaration order, which is the order
 * of the codes: member, code, flags (wc_field_ranges.h), low, high. The
 * relations between fields come after (check_relations). */
#define WC_CAL_FIELD_RANGES(X) \
    X(outer_radius_m, WC_CAL_OUTER_RADIUS, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_RADIUS_MAX_m) \
    X(inner_radius_m, WC_CAL_INNER_RADIUS, WC_FIELD_LOW_OPEN, 0.0f, FLT_MAX)       /* and < R_o */ \
    X(friction_area_m2, WC_CAL_FRICTION_AREA, WC_FIELD_LOW_OPEN, 0.0f, FLT_MAX)    /* and <= pi R_o^2 */ \
    X(piston_area_m2, WC_CAL_PISTON_AREA, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_PISTON_AREA_MAX_m2) \
    X(friction_pairs, WC_CAL_FRICTION_PAIRS, WC_FIELD_INTEGER, 1.0f, (float)WC_CAL_LIMIT_FRICTION_PAIRS_MAX) \
    X(oil_conductance_W_per_K, WC_CAL_OIL_CONDUCTANCE, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_CONDUCTANCE_MAX_W_per_K) \
    X(housing_conductance_W_per_K, WC_CAL_HOUSING_CONDUCTANCE, 0u, 0.0f, WC_CAL_LIMIT_CONDUCTANCE_MAX_W_per_K) \
    X(heat_capacity_J_per_K, WC_CAL_HEAT_CAPACITY, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_HEAT_CAPACITY_MAX_J_per_K) \
    /* mu_v(0 degC) = a1 + a2: a coefficient above the mu_v limit fails anyway */ \
    X(viscosity_a1_Pa_s, WC_CAL_VISCOSITY_A1, 0u, 0.0f, WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s) \
    X(viscosity_b1_per_K, WC_CAL_VISCOSITY_B1, 0u, -WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K, \
      WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K) \
    X(viscosity_a2_Pa_s, WC_CAL_VISCOSITY_A2, 0u, 0.0f, WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s) \
    X(viscosity_b2_per_K, WC_CAL_VISCOSITY_B2, 0u, -WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K, \
      WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K) \
    X(mu1, WC_CAL_MU1, 0u, WC_CAL_LIMIT_MU_MIN, WC_CAL_LIMIT_MU_MAX) \
    X(mu2, WC_CAL_MU2, 0u, WC_CAL_LIMIT_MU_MIN, WC_CAL_LIMIT_MU_MAX) \
    X(mu3, WC_CAL_MU3, 0u, -FLT_MAX, FLT_MAX)                                      /* finite */ \
    X(stribeck_speed_m_s, WC_CAL_STRIBECK_SPEED, 0u, WC_CAL_LIMIT_STRIBECK_SPEED_MIN_m_s, \
      WC_CAL_LIMIT_STRIBECK_SPEED_MAX_m_s) \
    X(theta1_degC, WC_CAL_THETA1, 0u, WC_THETA_MIN_degC, WC_THETA_MAX_degC) \
    X(theta2_K, WC_CAL_THETA2, 0u, WC_CAL_LIMIT_THETA2_MIN_K, FLT_MAX) \
    X(vfs_gain_Pa_per_mA, WC_CAL_VFS_GAIN, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_VFS_GAIN_MAX_Pa_per_mA) \
    X(vfs_time_constant_s, WC_CAL_VFS_TIME_CONSTANT, 0u, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MIN_s, \
      WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s) \
    X(return_spring_force_N, WC_CAL_RETURN_SPRING_FORCE, 0u, 0.0f, WC_CAL_LIMIT_SPRING_FORCE_MAX_N) \
    X(vfs_current_min_mA, WC_CAL_VFS_CURRENT_MIN, 0u, 0.0f, WC_CAL_LIMIT_CURRENT_MAX_mA) \
    X(vfs_current_max_mA, WC_CAL_VFS_CURRENT_MAX, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_CURRENT_MAX_mA) /* and > i_min */ \
    X(control_period_s, WC_CAL_CONTROL_PERIOD, 0u, WC_CAL_LIMIT_CONTROL_PERIOD_MIN_s, \
      WC_CAL_LIMIT_CONTROL_PERIOD_MAX_s) \
    X(film_squeeze_factor, WC_CAL_FILM_SQUEEZE_FACTOR, 0u, 0.0f, WC_CAL_LIMIT_FILM_SQUEEZE_FACTOR_MAX) \
    X(static_friction_factor, WC_CAL_STATIC_FRICTION_FACTOR, 0u, WC_CAL_LIMIT_STATIC_FRICTION_FACTOR_MIN, \
      WC_CAL_LIMIT_STATIC_FRICTION_FACTOR_MAX) \
    X(lock_slip_rad_s, WC_CAL_LOCK_SLIP, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_LOCK_SLIP_MAX_rad_s) \
    X(breakaway_slip_rad_s, WC_CAL_BREAKAWAY_SLIP, WC_FIELD_LOW_OPEN, 0.0f, WC_CAL_LIMIT_BREAKAWAY_SLIP_MAX_rad_s) \
    X(holding_margin, WC_CAL_HOLDING_MARGIN, 0u, WC_CAL_LIMIT_HOLDING_MARGIN_MIN, WC_CAL_LIMIT_HOLDING_MARGIN_MAX) \
    X(lock_dwell_periods, WC_CAL_LOCK_DWELL, WC_FIELD_INTEGER, 1.0f, (float)WC_CAL_LIMIT_LOCK_DWELL_MAX_periods) \
    X(open_clearance_m, WC_CAL_OPEN_CLEARANCE, 0u, 0.0f, WC_CAL_LIMIT_OPEN_CLEARANCE_MAX_m) \
    X(open_aeration_speed_rad_s, WC_CAL_OPEN_AERATION_SPEED, WC_FIELD_OR_ZERO, \
      WC_CAL_LIMIT_OPEN_AERATION_SPEED_MIN_rad_s, WC_CAL_LIMIT_OPEN_AERATION_SPEED_MAX_rad_s)

#define WC_CAL_RANGE(member, code, flags, low, high) { (low), (high) },
#define WC_CAL_FLAGS(member, code, flags, low, high) (uint8_t)(flags),
/* Field i fails with code WC_CAL_OUTER_RADIUS + i: each field sits at its code's word. */
#define WC_CAL_AT_ITS_CODE(member, code, flags, low, high) \
    WC_STATIC_ASSERT(offsetof(wc_calibration_t, member) == 4u * (size_t)((code) - WC_CAL_OUTER_RADIUS), \
                     member##_sits_at_its_code);

static const wc_field_range_t field_range[] = { WC_CAL_FIELD_RANGES(WC_CAL_RANGE) };
static const uint8_t field_flags[] = { WC_CAL_FIELD_RANGES(WC_CAL_FLAGS) };
static const wc_field_rules_t field_rules = { field_range, field_flags, sizeof field_flags };
WC_CAL_FIELD_RANGES(WC_CAL_AT_ITS_CODE)
/* Every scalar field has its range: the last one is the last before the film table. */
WC_STATIC_ASSERT(sizeof field_flags == (size_t)(WC_CAL_OPEN_AERATION_SPEED - WC_CAL_OUTER_RADIUS + 1), one_range_per_code);
WC_STATIC_ASSERT(offsetof(wc_calibration_t, film) == sizeof field_flags * 4u, every_scalar_field_has_a_range);
WC_STATIC_ASSERT((sizeof(float) == 4u) && (sizeof(uint32_t) == 4u), fields_are_words);

uint32_t wc_field_first_invalid(const void *fields, const wc_field_rules_t *rules)
{
    const unsigned char *base = (const unsigned char *)fields;
    float previous = 0.0f;
    for (uint32_t i = 0u; (i < WC_FIELD_MAX_COUNT) && (i < rules->count); ++i) {
        const uint32_t flags = rules->flags[i];
        float x;
        if ((flags & WC_FIELD_INTEGER) != 0u) {
            uint32_t n;
            memcpy(&n, base + 4u * i, sizeof n);
            x = (float)n;  /* exact against the integer bounds: floats are exact up to 2^24 */
        } else {
            memcpy(&x, base + 4u * i, sizeof x);
        }
        const float low = ((flags & WC_FIELD_LOW_PREVIOUS) != 0u) ? previous : rules->range[i].low;
        const bool above_low = ((flags & WC_FIELD_LOW_OPEN) != 0u) ? (x > low) : (x >= low);
        const bool off = ((flags & WC_FIELD_OR_ZERO) != 0u) && within(x, 0.0f, 0.0f);
        if (!off && !(above_low && (x <= rules->range[i].high))) { return i; }
        previous = x;
    }
    return rules->count;
}

static wc_cal_error_t check_fields(const wc_calibration_t *cal)
{
    const uint32_t i = wc_field_first_invalid(cal, &field_rules);
    return (i < field_rules.count) ? (wc_cal_error_t)((uint32_t)WC_CAL_OUTER_RADIUS + i) : WC_CAL_OK;
}

/* One term a e^(b theta) of eq. 2 at both ends of the domain, added to the
 * running lower and upper bounds of mu_v (the term is monotone in theta). */
static void add_viscosity_term(float a, float b, float *low, float *high)
{
    const float at_min = a * wc_exp(b * WC_THETA_MIN_degC);
    const float at_max = a * wc_exp(b * WC_THETA_MAX_degC);
    *low += smaller(at_min, at_max);
    *high += larger(at_min, at_max);
}

/* The rules between fields, each after the last field it involves. */
static wc_cal_error_t check_relations(const wc_calibration_t *cal)
{
    const float ro = cal->outer_radius_m;
    if (!(cal->inner_radius_m < ro)) { return WC_CAL_INNER_RADIUS; }
    if (!(cal->friction_area_m2 <= WC_CAL_LIMIT_PI * ro * ro)) { return WC_CAL_FRICTION_AREA; }
    const float k_W_per_K = cal->oil_conductance_W_per_K + cal->housing_conductance_W_per_K;
    if (!(k_W_per_K >= WC_CAL_LIMIT_CONDUCTANCE_SUM_MIN_W_per_K)) { return WC_CAL_CONDUCTANCE_SUM; }

    float low = 0.0f;
    float high = 0.0f;
    add_viscosity_term(cal->viscosity_a1_Pa_s, cal->viscosity_b1_per_K, &low, &high);
    add_viscosity_term(cal->viscosity_a2_Pa_s, cal->viscosity_b2_per_K, &low, &high);
    if (!(low > 0.0f) || !(high <= WC_CAL_LIMIT_VISCOSITY_MAX_Pa_s)) { return WC_CAL_VISCOSITY_RANGE; }

    /* the temperature factor of eq. 18 as the model computes it; linear in
     * theta: positive on the domain iff positive at both ends */
    const float at_min = wc_friction_temperature_factor(cal, WC_THETA_MIN_degC);
    const float at_max = wc_friction_temperature_factor(cal, WC_THETA_MAX_degC);
    if (!(at_min > 0.0f) || !(at_max > 0.0f) ||
        !(larger(cal->mu1, cal->mu2) * larger(at_min, at_max) <= WC_CAL_LIMIT_MU_MAX)) {
        return WC_CAL_FRICTION_DOMAIN;
    }

    /* The inverse's iteration bound assumes the force range stays below
     * WC_FORCE_MAX_N (2^WC_INVERSE_MAX_ITERATIONS halvings reach the tolerance),
     * and a piston that cannot overcome its spring never applies the clutch. */
    const float piston_force_N = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2;
    if (!(cal->vfs_current_max_mA > cal->vfs_current_min_mA) || !(piston_force_N <= WC_FORCE_MAX_N) ||
        !(piston_force_N - cal->return_spring_force_N > 0.0f)) {
        return WC_CAL_VFS_CURRENT_MAX;
    }

    /* eq. 1: C / (k1 + k2) */
    const float time_constant_s = cal->heat_capacity_J_per_K / k_W_per_K;
    if (!within(time_constant_s, cal->control_period_s, WC_CAL_LIMIT_TIME_CONSTANT_MAX_s)) {
        return WC_CAL_THERMAL_TIME_CONSTANT;
    }

    /* DESIGN section 9: the film state off (0: the field's range excludes < 0
     * and NaN), or a squeeze factor the update resolves;
     * breakaway outside the lock band (the hysteresis that keeps the lock from flapping) */
    if (!(!(cal->film_squeeze_factor > 0.0f) || (cal->film_squeeze_factor >= WC_CAL_LIMIT_FILM_SQUEEZE_FACTOR_MIN))) {
        return WC_CAL_FILM_SQUEEZE_FACTOR;
    }
    if (!(cal->breakaway_slip_rad_s > cal->lock_slip_rad_s)) { return WC_CAL_BREAKAWAY_SLIP; }
    return WC_CAL_OK;
}

/* The film table's rules in the order they are reported (as
 * calibration.film_problem applies them: each rule over the whole table
 * before the next). One pass over the nodes collects the rules that fail,
 * the first of them is reported. */
#define FILM_AXIS (1u << 0)          /* WC_CAL_FILM_AXIS_NOT_MONOTONE */
#define FILM_RANGE (1u << 1)         /* WC_CAL_FILM_RANGE */
#define FILM_NOT_MONOTONE (1u << 2)  /* WC_CAL_FILM_NOT_MONOTONE */

static wc_cal_error_t check_film(const wc_calibration_t *cal)
{
    const wc_film_table_t *t = &cal->film;
    if ((t->pressure_Pa == NULL) || (t->hbar_m == NULL) || (t->slope_m_per_Pa == NULL) ||
        (t->length < 2u) || (t->length > WC_FILM_MAX_NODES)) {
        return WC_CAL_FILM_TABLE;
    }
    const float *p = t->pressure_Pa;
    const float *h = t->hbar_m;
    const float *s = t->slope_m_per_Pa;
    const uint32_t n = t->length;
    uint32_t failed = (p[0] >= 0.0f) ? 0u : FILM_RANGE;  /* a contact pressure is not negative */
    /* Bounded by WC_FILM_MAX_NODES (n <= it, checked above). */
    for (uint32_t i = 0u; (i < WC_FILM_MAX_NODES) && (i < n); ++i) {
        /* a non-finite entry is the first rule: reported whatever else fails */
        if (!isfinite(p[i]) || !isfinite(h[i]) || !isfinite(s[i])) { return WC_CAL_FILM_TABLE; }
        if ((i > 0u) && !(p[i] > p[i - 1u])) { failed |= FILM_AXIS; }
        if (!within(h[i], WC_CAL_LIMIT_FILM_HBAR_MIN_m, WC_CAL_LIMIT_FILM_HBAR_MAX_m)) { failed |= FILM_RANGE; }
        if (!(s[i] <= 0.0f)) { failed |= FILM_NOT_MONOTONE; }  /* h_bar falls as p_c rises */
        if (i + 1u < n) {
            const float delta = (h[i + 1u] - h[i]) / (p[i + 1u] - p[i]);
            /* the data strictly decreasing, and Fritsch-Carlson: alpha, beta >= 0
             * (slopes <= 0, delta < 0) and alpha^2 + beta^2 <= 9: the cubic
             * Hermite on the interval is monotone */
            const float alpha = s[i] / delta;
            const float beta = s[i + 1u] / delta;
            if (!(delta < 0.0f) || !(alpha * alpha + beta * beta <= WC_CAL_LIMIT_FRITSCH_CARLSON)) {
                failed |= FILM_NOT_MONOTONE;
            }
        }
    }
    if ((failed & FILM_AXIS) != 0u) { return WC_CAL_FILM_AXIS_NOT_MONOTONE; }
    if ((failed & FILM_RANGE) != 0u) { return WC_CAL_FILM_RANGE; }
    if (failed != 0u) { return WC_CAL_FILM_NOT_MONOTONE; }
    /* The table reaches the contact pressure at the maximum current (the force
     * wc_model_init derives); beyond its last node the film is held constant. */
    const float force_max_N =
        cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 - cal->return_spring_force_N;
    if (!(p[n - 1u] >= force_max_N / cal->friction_area_m2)) { return WC_CAL_FILM_COVERAGE; }
    return WC_CAL_OK;
}

wc_cal_error_t wc_calibration_check(const wc_calibration_t *cal)
{
    if (cal == NULL) { return WC_CAL_NULL; }
    wc_cal_error_t error = check_fields(cal);
    if (error == WC_CAL_OK) { error = check_relations(cal); }
    if (error == WC_CAL_OK) { error = check_film(cal); }
    return error;
}

/* Indexed by wc_cal_error_t, in its order: a code added without a name fails to compile. */
static const char *const cal_error_names[] = {
    "ok",
    "calibration (NULL)",
    "outer_radius_m",
    "inner_radius_m",
    "friction_area_m2",
    "piston_area_m2",
    "friction_pairs",
    "oil_conductance_W_per_K",
    "housing_conductance_W_per_K",
    "heat_capacity_J_per_K",
    "viscosity_a1_Pa_s",
    "viscosity_b1_per_K",
    "viscosity_a2_Pa_s",
    "viscosity_b2_per_K",
    "mu1",
    "mu2",
    "mu3",
    "stribeck_speed_m_s",
    "theta1_degC",
    "theta2_K",
    "vfs_gain_Pa_per_mA",
    "vfs_time_constant_s",
    "return_spring_force_N",
    "vfs_current_min_mA",
    "vfs_current_max_mA",
    "control_period_s",
    "film_squeeze_factor",
    "static_friction_factor",
    "lock_slip_rad_s",
    "breakaway_slip_rad_s",
    "holding_margin",
    "lock_dwell_periods",
    "open_clearance_m",
    "open_aeration_speed_rad_s",
    "film (table arrays, length or entries)",
    "film.pressure_Pa (not strictly increasing)",
    "oil_conductance_W_per_K + housing_conductance_W_per_K",
    "heat_capacity_J_per_K / (oil_conductance_W_per_K + housing_conductance_W_per_K)",
    "viscosity_a1_Pa_s..viscosity_b2_per_K (mu_v on the temperature domain)",
    "mu1, mu2, mu3, theta1_degC, theta2_K (mu_f on the temperature domain)",
    "film.hbar_m, film.pressure_Pa (outside the physical range)",
    "film.hbar_m, film.slope_m_per_Pa (not monotone: Fritsch-Carlson)",
    "film.pressure_Pa (last node below the contact pressure at vfs_current_max_mA)",
};
WC_STATIC_ASSERT(sizeof cal_error_names / sizeof cal_error_names[0] == (size_t)WC_CAL_ERRORS,
                 cal_error_names_cover_every_code);

const char *wc_cal_error_name(wc_cal_error_t error)
{
    return ((unsigned)error < (unsigned)WC_CAL_ERRORS) ? cal_error_names[error] : "unknown";
}
