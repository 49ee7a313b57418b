/* Shift control of the 1->2 upshift's on-coming clutch (include/wetclutch/wc_shift.h,
 * src/model/wc_shift.c; DESIGN section 10), the VFS lag compensation and the
 * thermal-blind option of wc_clutch_step (wc_clutch.h), and Shift mode in the
 * CAN frame loop (wc_loop.h).
 *
 *  - calibration check: the test calibration passes; every field rejects
 *    NaN, +-inf and a value just outside each limit with its own code, and
 *    accepts its limits (inclusive);
 *  - the reference slip (smoothstep) and the feed-forward against their
 *    formulas, in double;
 *  - lag compensation: faster pressure, current bounded and flagged, and off
 *    (0, NaN, negative, inf) bit for bit the uncompensated step;
 *  - theta_from_oil: the model at the oil temperature, the observer running;
 *  - the phase state machine on a small plant (below), its aborts, the
 *    one-report rule, anti-windup bounds and non-finite sensors;
 *  - the frame loop in Shift mode with frames from the generated codec.
 *
 * The plant (DESIGN 10 reduced to the turbine side, the output side fixed):
 *   I_t d(slip)/dt = a (T_t - a T_c),  T_c = out.model.torque_Nm,
 * integrated with explicit Euler at the control period. Until the inertia
 * phase starts the off-going clutch holds the turbine (slip constant); from
 * then on the turbine is free. Slip cannot cross zero (the plates stick:
 * it stays at 0 while the clutch torque exceeds T_t's share), and while the
 * clutch model says locked the slip is 0 (static friction holds it). */
#include "wc_test_support.h"

#include <float.h>
#include <stdio.h>

#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_loop.h"

#define DT_s 0.001f            /* table1's control period */
#define THETA_OIL_degC 80.0f
#define START_SLIP_rad_s 100.0f  /* about 950 rpm: 1->2 at ~2800 rpm engine speed, ratios 4.7 / 3.1 */
#define TURBINE_TORQUE_Nm 100.0f
#define TARGET_TIME_s 0.5f
#define SLIP_CAP_rad_s 1000.0f   /* the plant's free turbine is capped below WC_SLIP_MAX_rad_s */

/* The test's shift calibration (values from the brief of the test, within every limit). */
static const wc_shift_calibration_t test_cal = {
    .turbine_inertia_kg_m2 = 0.25f,
    .turbine_ratio = 1.0f,
    .output_inertia_kg_m2 = 1e5f,  /* the test's plant holds the output speed: an output side that does not move */
    .output_ratio = 1.0f,
    .jerk_per_torque_rate = 0.01f,
    .prepare_time_s = 0.05f,
    .torque_phase_time_s = 0.1f,
    .inertia_time_min_s = 0.1f,
    .inertia_time_max_s = 2.0f,
    .inertia_timeout_factor = 1.5f,
    .lockup_ramp_time_s = 0.05f,
    .holding_torque_factor = 1.3f,
    .min_start_slip_rad_s = 5.0f,
    .feedforward_gain = 1.0f,
    .kp_Nm_per_rad_s = 2.0f,
    .ki_Nm_per_rad = 40.0f,
    .integral_limit_Nm = 300.0f,
    .lag_compensation_time_s = 0.015f,
    .theta_source = (uint32_t)WC_SHIFT_THETA_OBSERVER,
    .flare_slip_rad_s = 10.0f,
    .tie_up_factor = 1.5f,
    .jerk_filter_time_s = 0.02f,
};

static bool finite_output(const wc_step_output_t *out)
{
    return isfinite(out->current_mA) && isfinite(out->pressure_command_Pa) && isfinite(out->pressure_model_Pa) &&
           isfinite(out->force_command_N) && isfinite(out->theta_degC) && isfinite(out->contact_force_N) &&
           isfinite(out->static_capacity_Nm) && isfinite(out->model.torque_Nm) && isfinite(out->model.coulomb_Nm) &&
           isfinite(out->model.viscous_Nm) && isfinite(out->model.hbar_m) && isfinite(out->model.mu_f);
}

static bool finite_report(const wc_shift_report_t *r)
{
    return isfinite(r->inertia_time_s) && isfinite(r->slip_rmse_rad_s) && isfinite(r->peak_jerk_m_s3) &&
           isfinite(r->friction_energy_J) && isfinite(r->peak_theta_degC) && (r->inertia_time_s >= 0.0f) &&
           (r->slip_rmse_rad_s >= 0.0f) && (r->peak_jerk_m_s3 >= 0.0f) && (r->friction_energy_J >= 0.0f);
}

static bool finite_shift_state(const wc_shift_t *s)
{
    return isfinite(s->turbine_torque_Nm) && isfinite(s->target_time_s) && isfinite(s->start_slip_rad_s) &&
           isfinite(s->integral_Nm) && isfinite(s->request_Nm) && isfinite(s->phase_start_request_Nm) &&
           isfinite(s->filtered_torque_Nm) && isfinite(s->error_sq_sum) && finite_report(&s->report);
}

/* ======================================================================== */
/* Calibration check                                                        */
/* ======================================================================== */

typedef struct {
    const char *name;
    size_t offset;
    wc_shift_cal_error_t code;
    float lo;             /* inclusive limits (wc_shift.h) */
    float hi;
    bool off_or_time;     /* 0 (off) or within [lo, hi] */
} shift_field_t;

#define SHIFT_FIELD(member, err, lo, hi, off) \
    { #member, offsetof(wc_shift_calibration_t, member), (err), (lo), (hi), (off) }

/* In declaration order; inertia_time_max_s's lower limit is test_cal's inertia_time_min_s. */
static const shift_field_t shift_fields[] = {
    SHIFT_FIELD(turbine_inertia_kg_m2, WC_SHIFT_CAL_TURBINE_INERTIA, 1e-4f, 100.0f, false),
    SHIFT_FIELD(turbine_ratio, WC_SHIFT_CAL_TURBINE_RATIO, 0.05f, 20.0f, false),
    SHIFT_FIELD(output_inertia_kg_m2, WC_SHIFT_CAL_OUTPUT_INERTIA, 1e-4f, 1e5f, false),
    SHIFT_FIELD(output_ratio, WC_SHIFT_CAL_OUTPUT_RATIO, 0.05f, 20.0f, false),
    SHIFT_FIELD(jerk_per_torque_rate, WC_SHIFT_CAL_JERK_PER_TORQUE_RATE, 0.0f, 1.0f, false),
    SHIFT_FIELD(prepare_time_s, WC_SHIFT_CAL_PREPARE_TIME, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(torque_phase_time_s, WC_SHIFT_CAL_TORQUE_PHASE_TIME, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(inertia_time_min_s, WC_SHIFT_CAL_INERTIA_TIME_MIN, WC_SHIFT_LIMIT_INERTIA_TIME_MIN_s,
                WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s, false),
    SHIFT_FIELD(inertia_time_max_s, WC_SHIFT_CAL_INERTIA_TIME_MAX, 0.1f, WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s, false),
    SHIFT_FIELD(inertia_timeout_factor, WC_SHIFT_CAL_INERTIA_TIMEOUT_FACTOR, 1.05f, 10.0f, false),
    SHIFT_FIELD(lockup_ramp_time_s, WC_SHIFT_CAL_LOCKUP_RAMP_TIME, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(holding_torque_factor, WC_SHIFT_CAL_HOLDING_TORQUE_FACTOR, 1.0f, 5.0f, false),
    SHIFT_FIELD(min_start_slip_rad_s, WC_SHIFT_CAL_MIN_START_SLIP, 0.0f, WC_SLIP_MAX_rad_s, false),
    SHIFT_FIELD(feedforward_gain, WC_SHIFT_CAL_FEEDFORWARD_GAIN, 0.0f, 2.0f, false),
    SHIFT_FIELD(kp_Nm_per_rad_s, WC_SHIFT_CAL_KP, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX, false),
    SHIFT_FIELD(ki_Nm_per_rad, WC_SHIFT_CAL_KI, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX, false),
    SHIFT_FIELD(integral_limit_Nm, WC_SHIFT_CAL_INTEGRAL_LIMIT, 0.0f, WC_TORQUE_MAX_Nm, false),
    SHIFT_FIELD(lag_compensation_time_s, WC_SHIFT_CAL_LAG_COMPENSATION_TIME, 1e-3f, WC_SHIFT_LIMIT_TIME_MAX_s, true),
    SHIFT_FIELD(flare_slip_rad_s, WC_SHIFT_CAL_FLARE_SLIP, 0.0f, WC_SLIP_MAX_rad_s, false),
    SHIFT_FIELD(tie_up_factor, WC_SHIFT_CAL_TIE_UP_FACTOR, 1.0f, 10.0f, false),
    SHIFT_FIELD(jerk_filter_time_s, WC_SHIFT_CAL_JERK_FILTER_TIME, 1e-3f, WC_SHIFT_LIMIT_TIME_MAX_s, true),
};

static float *shift_field_ptr(wc_shift_calibration_t *cal, size_t offset)
{
    return (float *)(void *)((unsigned char *)cal + offset);
}

/* test_cal with one field set; the inertia time minimum above test_cal's
 * maximum also raises the maximum, so that only the tested field decides. */
static wc_shift_cal_error_t check_with(const shift_field_t *f, float value)
{
    wc_shift_calibration_t cal = test_cal;
    *shift_field_ptr(&cal, f->offset) = value;
    if ((f->code == WC_SHIFT_CAL_INERTIA_TIME_MIN) && (value > cal.inertia_time_max_s)) {
        cal.inertia_time_max_s = WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s;
    }
    return wc_shift_calibration_check(&cal);
}

static void test_calibration_valid(void **state)
{
    (void)state;
    assert_int_equal(wc_shift_calibration_check(&test_cal), WC_SHIFT_CAL_OK);
    wc_shift_calibration_t off = test_cal;  /* both "0 = off" fields off */
    off.lag_compensation_time_s = 0.0f;
    off.jerk_filter_time_s = 0.0f;
    off.theta_source = (uint32_t)WC_SHIFT_THETA_OIL;
    assert_int_equal(wc_shift_calibration_check(&off), WC_SHIFT_CAL_OK);
    assert_int_equal(wc_shift_calibration_check(NULL), WC_SHIFT_CAL_NULL);
}

/* Every code from TURBINE_INERTIA to JERK_FILTER_TIME belongs to exactly one
 * tested field (theta_source, the one integer field, is tested on its own). */
static void test_calibration_every_code_tested(void **state)
{
    (void)state;
    for (int code = (int)WC_SHIFT_CAL_TURBINE_INERTIA; code < (int)WC_SHIFT_CAL_ERRORS; ++code) {
        unsigned uses = (code == (int)WC_SHIFT_CAL_THETA_SOURCE) ? 1u : 0u;
        for (size_t i = 0u; i < WC_TEST_COUNT(shift_fields); ++i) {
            if ((int)shift_fields[i].code == code) { uses++; }
        }
        WC_CHECK(uses == 1u, "error code %d is tested by %u fields", code, uses);
    }
    /* the float fields and theta_source cover the whole struct */
    WC_CHECK(sizeof(wc_shift_calibration_t) == (WC_TEST_COUNT(shift_fields) + 1u) * sizeof(float),
             "wc_shift_calibration_t has %zu bytes: a field without a test?", sizeof(wc_shift_calibration_t));
}

static void test_calibration_each_field_rejected(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(shift_fields); ++i) {
        const shift_field_t *f = &shift_fields[i];
        const float below = (f->lo > 0.0f) ? nextafterf(f->lo, 0.0f) : -1e-6f;
        const float bad[] = { NAN, -NAN, INFINITY, -INFINITY, -1.0f, below, nextafterf(f->hi, INFINITY),
                              2.0f * f->hi, -FLT_MAX, FLT_MAX };
        for (size_t k = 0u; k < WC_TEST_COUNT(bad); ++k) {
            if (f->off_or_time && (bad[k] >= 0.0f) && (bad[k] <= 0.0f)) { continue; }  /* never: 0 is off */
            const wc_shift_cal_error_t got = check_with(f, bad[k]);
            WC_CHECK(got == f->code, "%s = %g: code %d, expected %d", f->name, (double)bad[k], (int)got, (int)f->code);
        }
        if (f->off_or_time) {  /* between off and the shortest time */
            const float gap[] = { 1e-6f, 5e-4f, nextafterf(1e-3f, 0.0f) };
            for (size_t k = 0u; k < WC_TEST_COUNT(gap); ++k) {
                const wc_shift_cal_error_t got = check_with(f, gap[k]);
                WC_CHECK(got == f->code, "%s = %g: code %d, expected %d", f->name, (double)gap[k], (int)got,
                         (int)f->code);
            }
        }
    }
    const uint32_t bad_source[] = { 2u, 3u, UINT32_MAX };
    for (size_t k = 0u; k < WC_TEST_COUNT(bad_source); ++k) {
        wc_shift_calibration_t cal = test_cal;
        cal.theta_source = bad_source[k];
        assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_THETA_SOURCE);
    }
}

static void test_calibration_limits_inclusive(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(shift_fields); ++i) {
        const shift_field_t *f = &shift_fields[i];
        const float good[] = { f->lo, f->hi, 0.5f * (f->lo + f->hi) };
        for (size_t k = 0u; k < WC_TEST_COUNT(good); ++k) {
            const wc_shift_cal_error_t got = check_with(f, good[k]);
            WC_CHECK(got == WC_SHIFT_CAL_OK, "%s = %g: code %d, expected OK", f->name, (double)good[k], (int)got);
        }
        if (f->off_or_time || (f->lo <= 0.0f)) {
            WC_CHECK(check_with(f, 0.0f) == WC_SHIFT_CAL_OK, "%s = 0 rejected", f->name);
        }
    }
    /* the inertia time maximum may equal the minimum, not go below it */
    wc_shift_calibration_t cal = test_cal;
    cal.inertia_time_max_s = cal.inertia_time_min_s;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    cal.inertia_time_min_s = 1.0f;
    cal.inertia_time_max_s = 0.5f;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_INERTIA_TIME_MAX);
}

/* ======================================================================== */
/* Reference slip and feed-forward                                          */
/* ======================================================================== */

static void test_reference_ends(void **state)
{
    (void)state;
    float rate = 1.0f;
    /* start: the start slip, zero slope */
    float ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, 0.0f, &rate);
    WC_CHECK(wc_test_same_float(ref, START_SLIP_rad_s), "ref(0) = %.9g", (double)ref);
    WC_CHECK(fabsf(rate) <= 0.0f, "rate(0) = %g", (double)rate);
    /* end: 0, zero slope */
    rate = 1.0f;
    ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, TARGET_TIME_s, &rate);
    WC_CHECK(fabsf(ref) <= 0.0f, "ref(T) = %g", (double)ref);
    WC_CHECK(fabsf(rate) <= 0.0f, "rate(T) = %g", (double)rate);
    /* half time: half the start slip (s(1/2) = 1/2; exact in float) */
    ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, 0.5f * TARGET_TIME_s, &rate);
    WC_CHECK_CLOSE("ref(T/2)", 0, ref, 0.5 * (double)START_SLIP_rad_s, 1e-6, 0.0);
    /* peak rate at T/2: -1.5 start / T */
    WC_CHECK_CLOSE("rate(T/2)", 0, rate, -1.5 * (double)START_SLIP_rad_s / (double)TARGET_TIME_s, 1e-6, 0.0);
    /* elapsed NaN or negative: the start; beyond the target: 0; rate 0 in each case */
    const float before[] = { NAN, -NAN, -1e-3f, -1.0f, -INFINITY };
    for (size_t k = 0u; k < WC_TEST_COUNT(before); ++k) {
        rate = 1.0f;
        ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, before[k], &rate);
        WC_CHECK(wc_test_same_float(ref, START_SLIP_rad_s), "elapsed %g: ref %g", (double)before[k], (double)ref);
        WC_CHECK(fabsf(rate) <= 0.0f, "elapsed %g: rate %g", (double)before[k], (double)rate);
    }
    const float after[] = { nextafterf(TARGET_TIME_s, INFINITY), 1.0f, 100.0f, FLT_MAX, INFINITY };
    for (size_t k = 0u; k < WC_TEST_COUNT(after); ++k) {
        rate = 1.0f;
        ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, after[k], &rate);
        WC_CHECK(fabsf(ref) <= 0.0f, "elapsed %g: ref %g", (double)after[k], (double)ref);
        WC_CHECK(fabsf(rate) <= 0.0f, "elapsed %g: rate %g", (double)after[k], (double)rate);
    }
    /* the rate pointer is optional */
    ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, 0.5f * TARGET_TIME_s, NULL);
    WC_CHECK_CLOSE("ref(T/2), no rate", 0, ref, 0.5 * (double)START_SLIP_rad_s, 1e-6, 0.0);
}

/* Monotone non-increasing over [0, 1.2 T] in 0.1 ms steps, and the rate is
 * the derivative: central difference in double of the float reference with
 * h = 1 ms. Tolerance: float rounding of the reference, ~start * 2^-23 =
 * 1.2e-5 rad/s, divided by 2h gives 6e-3 rad/s^2; the difference's
 * truncation, h^2/6 |s'''| start / T^3 = 1.6e-3 rad/s^2; allowed 0.02 rad/s^2
 * (the rate peaks at 300 rad/s^2). */
static void test_reference_monotone_and_rate(void **state)
{
    (void)state;
    const double h = 1e-3;
    const double tol = 0.02;
    wc_test_worst_t worst = { 0.0, -1 };
    float previous = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, 0.0f, NULL);
    for (int i = 1; i <= 6000; ++i) {
        const float t = 1e-4f * (float)i;
        float rate;
        const float ref = wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, t, &rate);
        WC_CHECK(ref <= previous, "not monotone at t = %.4f s: %.9g after %.9g", (double)t, (double)ref,
                 (double)previous);
        WC_CHECK((ref >= 0.0f) && (ref <= START_SLIP_rad_s), "ref(%g) = %g outside [0, start]", (double)t, (double)ref);
        previous = ref;
        const double up = (double)wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, (float)((double)t + h), NULL);
        const double down = (double)wc_shift_reference_slip(START_SLIP_rad_s, TARGET_TIME_s, (float)((double)t - h), NULL);
        if (((double)t > h) && ((double)t + h < (double)TARGET_TIME_s)) {  /* inside: no kink of the clamp */
            const double numeric = (up - down) / (2.0 * h);
            WC_CHECK_CLOSE("rate vs central difference", i, rate, numeric, 0.0, tol);
            wc_test_worst_update(&worst, fabs((double)rate - numeric), i);
        }
    }
    wc_test_worst_print("reference rate", &worst, tol);
}

static void test_feedforward_formula(void **state)
{
    (void)state;
    const float ratios[] = { 0.5f, 1.0f, 2.0f, 4.7f };
    const float inertias[] = { 0.05f, 0.25f, 1.0f };
    const float torques[] = { 0.0f, 10.0f, 100.0f, 400.0f };
    const float rates[] = { -1000.0f, -300.0f, -1.0f, 0.0f };  /* the inertia phase's rate is <= 0 */
    for (size_t a = 0u; a < WC_TEST_COUNT(ratios); ++a) {
        for (size_t j = 0u; j < WC_TEST_COUNT(inertias); ++j) {
            wc_shift_calibration_t cal = test_cal;
            cal.turbine_ratio = ratios[a];
            cal.turbine_inertia_kg_m2 = inertias[j];
            for (size_t t = 0u; t < WC_TEST_COUNT(torques); ++t) {
                for (size_t r = 0u; r < WC_TEST_COUNT(rates); ++r) {
                    const double ai = (double)ratios[a], it = (double)inertias[j];
                    const double b = (double)cal.output_ratio, io = (double)cal.output_inertia_kg_m2;
                    const double expected = (ai * (double)torques[t] / it - (double)rates[r]) /
                                            (ai * ai / it + b * b / io);  /* DESIGN 10, stiff driveshaft */
                    const float got = wc_shift_feedforward_Nm(&cal, torques[t], rates[r]);
                    /* a few float operations: 1e-6 relative */
                    WC_CHECK_CLOSE("feed-forward", (long)(a * 1000u + j * 100u + t * 10u + r), got, expected, 1e-6,
                                   1e-6);
                }
            }
        }
    }
}

static void test_feedforward_bounds(void **state)
{
    (void)state;
    /* a positive rate (slip rising) or a negative turbine torque: the
     * formula is negative, the feed-forward 0 (a clutch cannot push) */
    WC_CHECK(wc_shift_feedforward_Nm(&test_cal, 0.0f, 100.0f) >= 0.0f, "negative");
    WC_CHECK(fabsf(wc_shift_feedforward_Nm(&test_cal, 0.0f, 100.0f)) <= 0.0f, "not 0");
    WC_CHECK(fabsf(wc_shift_feedforward_Nm(&test_cal, -50.0f, 0.0f)) <= 0.0f, "not 0");
    const float extreme[] = { NAN, INFINITY, -INFINITY, FLT_MAX, -FLT_MAX, 1e30f, -1e30f, 0.0f };
    for (size_t i = 0u; i < WC_TEST_COUNT(extreme); ++i) {
        for (size_t j = 0u; j < WC_TEST_COUNT(extreme); ++j) {
            const float ff = wc_shift_feedforward_Nm(&test_cal, extreme[i], extreme[j]);
            WC_CHECK(isfinite(ff) && (ff >= 0.0f) && (ff <= WC_TORQUE_MAX_Nm), "T_t %g, rate %g: %g",
                     (double)extreme[i], (double)extreme[j], (double)ff);
        }
    }
}

/* ======================================================================== */
/* Lag compensation and theta_from_oil (wc_clutch_step)                      */
/* ======================================================================== */

static wc_step_input_t torque_input(float slip_rad_s, float request_Nm, float lag_s)
{
    wc_step_input_t in;
    memset(&in, 0, sizeof in);
    in.slip_rad_s = slip_rad_s;
    in.theta_oil_degC = THETA_OIL_degC;
    in.theta_housing_degC = THETA_OIL_degC;
    in.torque_request_Nm = request_Nm;
    in.mode = WC_MODE_TORQUE;
    in.lag_compensation_time_s = lag_s;
    in.theta_from_oil = true;  /* the wanted pressure then does not drift with the observer */
    return in;
}

/* Periods until the modelled pressure covers 63.2 % of a request step from
 * the settled request 0 to request_Nm; *wanted_Pa the settled pressure. */
static int rise_periods(float request_Nm, float lag_s, float *wanted_Pa, bool *clamped_seen, bool *current_in_range)
{
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, cal, THETA_OIL_degC), WC_CAL_OK);
    wc_step_output_t out;
    wc_step_input_t in = torque_input(50.0f, 0.0f, lag_s);
    for (int k = 0; k < 1000; ++k) { (void)wc_clutch_step(&clutch, &in, &out); }
    const float p0 = out.pressure_model_Pa;
    in.torque_request_Nm = request_Nm;
    int crossing = -1;
    float p[1500];
    *clamped_seen = false;
    *current_in_range = true;
    for (int k = 0; k < 1500; ++k) {
        (void)wc_clutch_step(&clutch, &in, &out);
        p[k] = out.pressure_model_Pa;
        if ((out.status & WC_STATUS_CURRENT_CLAMPED) != 0u) { *clamped_seen = true; }
        if (!((out.current_mA >= cal->vfs_current_min_mA) && (out.current_mA <= cal->vfs_current_max_mA))) {
            *current_in_range = false;
        }
    }
    *wanted_Pa = p[1499];
    const float level = p0 + 0.632f * (*wanted_Pa - p0);
    for (int k = 0; k < 1500; ++k) {
        if (p[k] >= level) {
            crossing = k + 1;  /* periods after the step */
            break;
        }
    }
    return crossing;
}

static void test_lag_compensation_faster(void **state)
{
    (void)state;
    float wanted_off;
    float wanted_on;
    bool clamped;
    bool in_range;
    /* 150 Nm at 50 rad/s: a moderate pressure; the compensated current stays in range */
    const int off = rise_periods(150.0f, 0.0f, &wanted_off, &clamped, &in_range);
    WC_CHECK(!clamped && in_range, "uncompensated: clamped %d, in range %d", clamped, in_range);
    const int on = rise_periods(150.0f, 0.015f, &wanted_on, &clamped, &in_range);
    WC_CHECK(in_range, "compensated current outside the solenoid range");
    print_message("    63%% of the pressure step: %d periods uncompensated, %d with t = 15 ms (clamped %d)\n", off,
                  on, clamped);
    /* tau = 60 ms: 60 periods (+-2 for the discrete crossing); t = 15 ms: 15 +-2 */
    WC_CHECK((off >= 58) && (off <= 62), "uncompensated 63 %% after %d periods, expected ~60 (tau)", off);
    WC_CHECK((on >= 13) && (on <= 17), "compensated 63 %% after %d periods, expected ~15", on);
    WC_CHECK_CLOSE("settled pressure, compensated vs not", 0, wanted_on, wanted_off, 1e-4, 0.0);
}

static void test_lag_compensation_clamped(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    float wanted;
    bool clamped;
    bool in_range;
    /* a big step: the lead asks for more than the maximum current */
    const int on = rise_periods(450.0f, 0.015f, &wanted, &clamped, &in_range);
    WC_CHECK(clamped, "a large step did not saturate the current (WC_STATUS_CURRENT_CLAMPED never set)");
    WC_CHECK(in_range, "current outside [min, max]");
    WC_CHECK(on > 0, "never reached 63 %%");

    /* and downwards: from a high pressure to request 0 the lead asks for less than the minimum */
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, cal, THETA_OIL_degC), WC_CAL_OK);
    wc_step_output_t out;
    wc_step_input_t in = torque_input(50.0f, 400.0f, 0.015f);
    for (int k = 0; k < 500; ++k) { (void)wc_clutch_step(&clutch, &in, &out); }
    in.torque_request_Nm = 0.0f;
    (void)wc_clutch_step(&clutch, &in, &out);
    WC_CHECK((out.status & WC_STATUS_CURRENT_CLAMPED) != 0u, "downward step: not flagged CURRENT_CLAMPED");
    WC_CHECK(wc_test_same_float(out.current_mA, cal->vfs_current_min_mA), "downward step: current %g mA",
             (double)out.current_mA);
    /* settled: no clamp */
    for (int k = 0; k < 1000; ++k) { (void)wc_clutch_step(&clutch, &in, &out); }
    WC_CHECK((out.status & WC_STATUS_CURRENT_CLAMPED) == 0u, "settled: still CURRENT_CLAMPED");
}

/* 0, -0, NaN, negative, infinite: exactly the uncompensated step. The
 * same sequence runs on two clutches; outputs and states compared bytewise. */
static void test_lag_compensation_off_is_exact(void **state)
{
    (void)state;
    const float off[] = { 0.0f, -0.0f, NAN, -NAN, -1e-3f, -1.0f, -INFINITY, INFINITY };
    for (size_t i = 0u; i < WC_TEST_COUNT(off); ++i) {
        wc_clutch_t a;
        wc_clutch_t b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        assert_int_equal(wc_clutch_init(&a, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
        assert_int_equal(wc_clutch_init(&b, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
        for (int k = 0; k < 600; ++k) {
            const float request = (k < 100) ? 0.0f : ((k < 300) ? 300.0f : ((k < 450) ? 20.0f : 600.0f));
            const float slip = 80.0f - 0.15f * (float)k;  /* through zero: lock-up too */
            wc_step_input_t in_a = torque_input(slip, request, 0.0f);
            in_a.theta_from_oil = false;
            in_a.mode = (k < 550) ? WC_MODE_TORQUE : WC_MODE_OPEN;
            wc_step_input_t in_b = in_a;
            in_b.lag_compensation_time_s = off[i];
            wc_step_output_t out_a;
            wc_step_output_t out_b;
            memset(&out_a, 0, sizeof out_a);
            memset(&out_b, 0, sizeof out_b);
            const wc_status_t sa = wc_clutch_step(&a, &in_a, &out_a);
            const wc_status_t sb = wc_clutch_step(&b, &in_b, &out_b);
            WC_CHECK(sa == sb, "time %g, step %d: status %x vs %x", (double)off[i], k, (unsigned)sa, (unsigned)sb);
            WC_CHECK(memcmp(&out_a, &out_b, sizeof out_a) == 0, "time %g, step %d: outputs differ (current %.9g vs %.9g)",
                     (double)off[i], k, (double)out_a.current_mA, (double)out_b.current_mA);
            WC_CHECK(memcmp(&a, &b, sizeof a) == 0, "time %g, step %d: states differ", (double)off[i], k);
        }
    }
}

/* Every output finite and the current in range for compensation times
 * from tiny to the VFS limit, with hard request changes. */
static void test_lag_compensation_any_time_finite(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const float times[] = { FLT_MIN, 1e-20f, 1e-6f, 1e-3f, 0.015f, 0.06f, 0.5f, 10.0f, 20.0f, FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(times); ++i) {
        wc_clutch_t clutch;
        assert_int_equal(wc_clutch_init(&clutch, cal, THETA_OIL_degC), WC_CAL_OK);
        for (int k = 0; k < 400; ++k) {
            const float request = ((k / 50) % 2 == 0) ? 0.0f : 800.0f;
            wc_step_input_t in = torque_input(30.0f, request, times[i]);
            wc_step_output_t out;
            (void)wc_clutch_step(&clutch, &in, &out);
            WC_CHECK(finite_output(&out), "time %g step %d: non-finite output", (double)times[i], k);
            WC_CHECK((out.current_mA >= cal->vfs_current_min_mA) && (out.current_mA <= cal->vfs_current_max_mA),
                     "time %g step %d: current %g", (double)times[i], k, (double)out.current_mA);
        }
    }
}

static void test_theta_from_oil(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const float hot_degC = 180.0f;
    const float oil_degC = 60.0f;
    wc_clutch_t blind;
    wc_clutch_t aware;
    assert_int_equal(wc_clutch_init(&blind, cal, hot_degC), WC_CAL_OK);  /* observer starts hot */
    assert_int_equal(wc_clutch_init(&aware, cal, hot_degC), WC_CAL_OK);
    wc_model_t model;
    assert_int_equal(wc_model_init(&model, cal), WC_CAL_OK);
    float theta_before = blind.theta_degC;
    for (int k = 0; k < 200; ++k) {
        wc_step_input_t in;
        memset(&in, 0, sizeof in);
        in.slip_rad_s = 60.0f;
        in.theta_oil_degC = oil_degC;
        in.theta_housing_degC = oil_degC;
        in.torque_request_Nm = 150.0f;
        in.mode = WC_MODE_TORQUE;
        in.theta_from_oil = true;
        wc_step_output_t out;
        (void)wc_clutch_step(&blind, &in, &out);
        WC_CHECK(wc_test_same_float(out.theta_degC, oil_degC), "step %d: theta used %g, oil %g", k,
                 (double)out.theta_degC, (double)oil_degC);
        /* the torque model at the oil temperature and the contact force */
        wc_torque_t t;
        (void)wc_torque(&model, in.slip_rad_s, oil_degC, out.contact_force_N, &t);
        WC_CHECK_CLOSE("torque at the oil temperature", k, out.model.torque_Nm, t.torque_Nm, 1e-5, 1e-4);
        /* the observer advances: eq. 1 with P = |T dw| from the hot estimate */
        float expected = theta_before;
        (void)wc_thermal_step(&model, &expected, fabsf(out.model.torque_Nm * in.slip_rad_s), oil_degC, oil_degC);
        WC_CHECK_CLOSE("observer", k, blind.theta_degC, expected, 1e-6, 1e-4);
        WC_CHECK(!wc_test_same_float(blind.theta_degC, theta_before), "step %d: observer did not move", k);
        theta_before = blind.theta_degC;

        in.theta_from_oil = false;
        wc_step_output_t out_aware;
        (void)wc_clutch_step(&aware, &in, &out_aware);
        WC_CHECK(out_aware.theta_degC > oil_degC + 50.0f, "observer-based step used %g", (double)out_aware.theta_degC);
    }
    /* the observer cools towards the oil in both */
    WC_CHECK(blind.theta_degC < hot_degC, "observer did not cool: %g", (double)blind.theta_degC);
}

/* ======================================================================== */
/* Shift state machine on the plant                                          */
/* ======================================================================== */

typedef struct {
    const wc_shift_calibration_t *cal;
    wc_clutch_t clutch;
    wc_shift_t shift;
    wc_step_output_t out;
    wc_shift_report_t report;
    float slip_rad_s;
    float plant_torque_Nm;     /* the true T_t */
    bool offgoing_released;    /* the plant's turbine is free from the inertia phase on */
    bool turbine_held;         /* tie-up plant: the off-going never releases */
    uint32_t ended;            /* wc_shift_step returned true */
    uint32_t phase_log[16];    /* distinct phases in order */
    uint32_t phase_log_len;
    uint32_t phase_steps[8];   /* steps that ended in each phase */
    float max_abs_integral_Nm;
    bool all_finite;
} sim_t;

static void sim_init(sim_t *s, const wc_shift_calibration_t *cal, float slip_rad_s, float plant_torque_Nm)
{
    memset(s, 0, sizeof *s);
    s->cal = cal;
    assert_int_equal(wc_clutch_init(&s->clutch, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
    wc_shift_init(&s->shift);
    s->slip_rad_s = slip_rad_s;
    s->plant_torque_Nm = plant_torque_Nm;
    s->all_finite = true;
    s->phase_log[0] = (uint32_t)WC_SHIFT_IDLE;
    s->phase_log_len = 1u;
}

static wc_shift_command_t command_of(bool request, float turbine_torque_Nm, float target_s)
{
    const wc_shift_command_t c = { request, 2u, turbine_torque_Nm, target_s };
    return c;
}

/* One period: the controller with the measured slip (or sensor_slip when
 * given: a sensor fault), then the plant. Returns wc_shift_step's result. */
static bool sim_step_sensor(sim_t *s, const wc_shift_command_t *command, bool safe, float sensor_slip,
                            float sensor_oil)
{
    wc_step_input_t sensors;
    memset(&sensors, 0, sizeof sensors);
    sensors.slip_rad_s = sensor_slip;
    sensors.theta_oil_degC = sensor_oil;
    sensors.theta_housing_degC = THETA_OIL_degC;
    const bool ended = wc_shift_step(&s->shift, s->cal, command, safe, &s->clutch, &sensors, &s->out, &s->report);
    if (ended) { s->ended++; }
    const uint32_t phase = s->shift.phase;
    if (phase != s->phase_log[s->phase_log_len - 1u]) {
        assert_true(s->phase_log_len < WC_TEST_COUNT(s->phase_log));
        s->phase_log[s->phase_log_len++] = phase;
    }
    assert_true(phase < 8u);
    s->phase_steps[phase]++;
    if (fabsf(s->shift.integral_Nm) > s->max_abs_integral_Nm) { s->max_abs_integral_Nm = fabsf(s->shift.integral_Nm); }
    if (!finite_output(&s->out) || !finite_shift_state(&s->shift)) { s->all_finite = false; }

    /* plant */
    if (phase == (uint32_t)WC_SHIFT_INERTIA) { s->offgoing_released = true; }
    if (s->offgoing_released && !s->turbine_held) {
        const float a = s->cal->turbine_ratio;
        const float accel = a * (s->plant_torque_Nm - a * s->out.model.torque_Nm) / s->cal->turbine_inertia_kg_m2;
        float next = s->slip_rad_s + accel * DT_s;
        if ((s->slip_rad_s >= 0.0f) && (next < 0.0f)) { next = 0.0f; }  /* the plates stick at zero */
        s->slip_rad_s = (next < SLIP_CAP_rad_s) ? next : SLIP_CAP_rad_s;
        if ((s->out.status & WC_STATUS_LOCKED) != 0u) { s->slip_rad_s = 0.0f; }  /* static friction holds */
    }
    return ended;
}

static bool sim_step(sim_t *s, const wc_shift_command_t *command, bool safe)
{
    return sim_step_sensor(s, command, safe, s->slip_rad_s, THETA_OIL_degC);
}

/* Runs with the command until the shift ends or max_steps; returns the steps. */
static uint32_t sim_run_to_end(sim_t *s, const wc_shift_command_t *command, uint32_t max_steps)
{
    for (uint32_t k = 0u; k < max_steps; ++k) {
        if (sim_step(s, command, false)) { return k + 1u; }
    }
    return max_steps;
}

static uint32_t sim_run_until_phase(sim_t *s, const wc_shift_command_t *command, wc_shift_phase_t phase,
                                    uint32_t extra_steps)
{
    uint32_t k = 0u;
    while ((s->shift.phase != (uint32_t)phase) && (k < 5000u)) {
        (void)sim_step(s, command, false);
        k++;
    }
    WC_CHECK(s->shift.phase == (uint32_t)phase, "phase %u not reached (at %u)", (unsigned)phase, (unsigned)s->shift.phase);
    for (uint32_t i = 0u; i < extra_steps; ++i) {
        (void)sim_step(s, command, false);
        k++;
    }
    return k;
}

static void print_report(const char *what, const wc_shift_report_t *r)
{
    print_message("    %s: inertia %.3f s, slip RMSE %.3f rad/s, peak jerk %.3f m/s^3, energy %.1f J, peak theta %.1f degC,"
                  " flare %d, tie-up %d, abort %u\n",
                  what, (double)r->inertia_time_s, (double)r->slip_rmse_rad_s, (double)r->peak_jerk_m_s3,
                  (double)r->friction_energy_J, (double)r->peak_theta_degC, r->flare, r->tie_up,
                  (unsigned)r->abort_reason);
}

static void test_shift_completes(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(false, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    for (int k = 0; k < 20; ++k) { assert_false(sim_step(&s, &command, false)); }  /* idle: released */
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "idle current %g",
             (double)s.out.current_mA);
    command.request = true;
    const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_LOCKED, "ended in phase %u after %u steps", (unsigned)s.shift.phase,
             (unsigned)steps);
    print_report("shift", &s.report);
    const uint32_t expected_log[] = { WC_SHIFT_IDLE, WC_SHIFT_PREPARE, WC_SHIFT_TORQUE, WC_SHIFT_INERTIA,
                                      WC_SHIFT_LOCKUP, WC_SHIFT_LOCKED };
    WC_CHECK(s.phase_log_len == WC_TEST_COUNT(expected_log), "%u phases", (unsigned)s.phase_log_len);
    for (uint32_t i = 0u; i < s.phase_log_len; ++i) {
        WC_CHECK(s.phase_log[i] == expected_log[i], "phase %u: %u, expected %u", (unsigned)i, (unsigned)s.phase_log[i],
                 (unsigned)expected_log[i]);
    }
    /* phase lengths: prepare 50, torque 100 (the step that enters the next
     * phase counts to the next), lock-up ramp 50 periods */
    WC_CHECK((s.phase_steps[WC_SHIFT_PREPARE] >= 49u) && (s.phase_steps[WC_SHIFT_PREPARE] <= 51u), "prepare %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_PREPARE]);
    WC_CHECK((s.phase_steps[WC_SHIFT_TORQUE] >= 99u) && (s.phase_steps[WC_SHIFT_TORQUE] <= 101u), "torque %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_TORQUE]);
    WC_CHECK((s.phase_steps[WC_SHIFT_LOCKUP] >= 49u) && (s.phase_steps[WC_SHIFT_LOCKUP] <= 51u), "lockup %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_LOCKUP]);
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_NONE);
    /* inertia time: the reference reaches 0 at the target; the lock-up dwell
     * (10 periods) and the tracking lag come on top: within [0.9, 1.15] target */
    WC_CHECK((s.report.inertia_time_s >= 0.9f * TARGET_TIME_s) && (s.report.inertia_time_s <= 1.15f * TARGET_TIME_s),
             "inertia time %g s, target %g s", (double)s.report.inertia_time_s, (double)TARGET_TIME_s);
    WC_CHECK_CLOSE("inertia time = inertia phase steps", 0, s.report.inertia_time_s,
                   (double)s.phase_steps[WC_SHIFT_INERTIA] * (double)DT_s, 0.0, 1.5e-3);
    /* tracking: RMSE under 3 % of the start slip */
    WC_CHECK(s.report.slip_rmse_rad_s < 0.03f * START_SLIP_rad_s, "slip RMSE %g rad/s", (double)s.report.slip_rmse_rad_s);
    WC_CHECK(!s.report.flare && !s.report.tie_up, "flare %d tie-up %d", s.report.flare, s.report.tie_up);
    /* energy: about the ideal T_c * slip integral, (T_t/a) * start/2 * target = 2.5 kJ, plus the inertia's share */
    WC_CHECK((s.report.friction_energy_J > 1500.0f) && (s.report.friction_energy_J < 6000.0f), "energy %g J",
             (double)s.report.friction_energy_J);
    WC_CHECK((s.report.peak_theta_degC > THETA_OIL_degC) && (s.report.peak_theta_degC < 200.0f), "peak theta %g",
             (double)s.report.peak_theta_degC);
    WC_CHECK(s.report.peak_jerk_m_s3 > 0.0f, "peak jerk %g", (double)s.report.peak_jerk_m_s3);
    WC_CHECK(finite_report(&s.report) && s.all_finite, "non-finite");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
    WC_CHECK(fabsf(s.slip_rad_s) <= 0.0f, "slip %g after lock", (double)s.slip_rad_s);

    /* locked: the holding request stays, no second report */
    for (int k = 0; k < 300; ++k) { (void)sim_step(&s, &command, false); }
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.shift.phase, WC_SHIFT_LOCKED);
    WC_CHECK_CLOSE("holding request", 0, s.shift.request_Nm,
                   (double)test_cal.holding_torque_factor * (double)TURBINE_TORQUE_Nm / (double)test_cal.turbine_ratio,
                   1e-6, 0.0);
    WC_CHECK((s.out.status & WC_STATUS_LOCKED) != 0u, "not locked while holding");
    /* the command ends: idle, released, still one report */
    command.request = false;
    for (int k = 0; k < 10; ++k) { (void)sim_step(&s, &command, false); }
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    assert_int_equal(s.ended, 1u);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "idle current %g",
             (double)s.out.current_mA);
}

static void test_shift_cancel(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
    assert_int_equal(s.ended, 0u);
    command.request = false;
    WC_CHECK(sim_step(&s, &command, false), "cancel did not end the shift");
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_CANCELLED);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    WC_CHECK(s.report.inertia_time_s <= 0.0f, "inertia time %g of an unfinished inertia phase",
             (double)s.report.inertia_time_s);
    for (int k = 0; k < 200; ++k) {
        (void)sim_step(&s, &command, false);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
    }
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    /* cancelled in PREPARE and in TORQUE too */
    const wc_shift_phase_t phases[] = { WC_SHIFT_PREPARE, WC_SHIFT_TORQUE, WC_SHIFT_LOCKUP };
    for (size_t i = 0u; i < WC_TEST_COUNT(phases); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        command.request = true;
        (void)sim_run_until_phase(&s, &command, phases[i], 5u);
        command.request = false;
        WC_CHECK(sim_step(&s, &command, false), "phase %u: cancel did not end the shift", (unsigned)phases[i]);
        assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_CANCELLED);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
    }
}

/* After an abort the clutch stays released while the request stays 1 (no
 * restart, no flapping); request 0 then a new rising edge starts a new shift. */
static void test_shift_input_lost_and_restart(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 50u);
    WC_CHECK(sim_step(&s, &command, true), "safe state did not end the shift");
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INPUT_LOST);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    /* safe, then not safe, the request still 1: aborted and released */
    for (int k = 0; k < 300; ++k) {
        (void)sim_step(&s, &command, k < 50);
        WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_ABORTED, "step %d: phase %u", k, (unsigned)s.shift.phase);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "step %d: %g mA",
                 k, (double)s.out.current_mA);
    }
    assert_int_equal(s.ended, 1u);
    /* request 0: idle; then a rising edge: a new shift (the slip flared meanwhile: the plant's turbine was free) */
    command.request = false;
    (void)sim_step(&s, &command, false);
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    s.slip_rad_s = START_SLIP_rad_s;
    s.offgoing_released = false;  /* the plant: first gear again */
    command.request = true;
    (void)sim_step(&s, &command, false);
    assert_int_equal(s.shift.phase, WC_SHIFT_PREPARE);
    const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_LOCKED, "second shift ended in %u after %u steps",
             (unsigned)s.shift.phase, (unsigned)steps);
    assert_int_equal(s.ended, 2u);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_NONE);
    /* a fresh report: no flare carried over from the aborted shift */
    WC_CHECK(!s.report.flare, "flare of the first shift carried over");
}

/* The safe state while the shift is LOCKED (completed, request still 1): the
 * frame loop's safe-state policy is the solenoid's minimum current
 * (wc_loop.h), and wc_shift.h says safe = "the loop's safe state is active". */
static void test_shift_safe_while_locked_releases(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    assert_int_equal(s.shift.phase, WC_SHIFT_LOCKED);
    (void)sim_step(&s, &command, true);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA),
             "safe state while LOCKED: current %g mA (phase %u), expected the minimum %g mA", (double)s.out.current_mA,
             (unsigned)s.shift.phase, (double)wc_table1_calibration.vfs_current_min_mA);
}

static void test_shift_invalid_command(void **state)
{
    (void)state;
    static sim_t s;
    const wc_shift_command_t bad[] = {
        { true, 3u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 1u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 0u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 2u, TURBINE_TORQUE_Nm, nextafterf(0.1f, 0.0f) },  /* below inertia_time_min_s */
        { true, 2u, TURBINE_TORQUE_Nm, nextafterf(2.0f, 3.0f) },  /* above inertia_time_max_s */
        { true, 2u, TURBINE_TORQUE_Nm, NAN },
        { true, 2u, TURBINE_TORQUE_Nm, -INFINITY },
        { true, 2u, -1.0f, TARGET_TIME_s },
        { true, 2u, -1e-6f, TARGET_TIME_s },
        { true, 2u, NAN, TARGET_TIME_s },
        { true, 2u, INFINITY, TARGET_TIME_s },
        { true, 2u, nextafterf(WC_TORQUE_MAX_Nm, INFINITY), TARGET_TIME_s },
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        WC_CHECK(sim_step(&s, &bad[i], false), "command %zu: did not end at the start", i);
        assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
        WC_CHECK(s.report.abort_reason == (uint32_t)WC_SHIFT_ABORT_INVALID_COMMAND, "command %zu: reason %u", i,
                 (unsigned)s.report.abort_reason);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "command %zu: %g mA",
                 i, (double)s.out.current_mA);
        for (int k = 0; k < 100; ++k) {
            (void)sim_step(&s, &bad[i], false);
            WC_CHECK(finite_output(&s.out) && finite_report(&s.shift.report), "command %zu: non-finite output", i);
        }
        assert_int_equal(s.ended, 1u);
        WC_CHECK(finite_report(&s.report), "command %zu: non-finite report", i);
    }
    /* the limits themselves are valid */
    const wc_shift_command_t edge[] = { { true, 2u, 0.0f, 0.1f }, { true, 2u, TURBINE_TORQUE_Nm, 2.0f } };
    for (size_t i = 0u; i < WC_TEST_COUNT(edge); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        assert_false(sim_step(&s, &edge[i], false));
        assert_int_equal(s.shift.phase, WC_SHIFT_PREPARE);
    }
}

static void test_shift_inertia_timeout(void **state)
{
    (void)state;
    static sim_t s;
    /* (a) the clutch cannot pull: 2000 Nm against a capacity of a few hundred Nm; the turbine flares */
    sim_init(&s, &test_cal, START_SLIP_rad_s, 2000.0f);
    wc_shift_command_t command = command_of(true, 2000.0f, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    print_report("cannot pull", &s.report);
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INERTIA_TIMEOUT);
    assert_int_equal(s.ended, 1u);
    /* after target * factor = 0.75 s: the first period past it */
    WC_CHECK_CLOSE("timeout", 0, s.report.inertia_time_s, (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor),
                   0.0, 1.5e-3);
    WC_CHECK_CLOSE("inertia phase steps", 0, (double)s.phase_steps[WC_SHIFT_INERTIA] * (double)DT_s,
                   (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor), 0.0, 1.5e-3);
    WC_CHECK(s.report.flare, "the turbine ran away and no flare was reported");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
    /* the timeout is decided on the step's clutch output (after wc_clutch_step):
     * released from the next period on */
    (void)sim_step(&s, &command, false);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    assert_int_equal(s.ended, 1u);
    WC_CHECK(s.all_finite && finite_report(&s.report), "non-finite");

    /* (b) the slip never falls (the off-going clutch holds the turbine): timeout and tie-up */
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    s.turbine_held = true;
    command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    print_report("tie-up", &s.report);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INERTIA_TIMEOUT);
    WC_CHECK_CLOSE("timeout", 0, s.report.inertia_time_s, (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor),
                   0.0, 1.5e-3);
    WC_CHECK(s.report.tie_up, "the slip held while the clutch pulled and no tie-up was reported");
    WC_CHECK(!s.report.flare, "flare reported with the slip held");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
}

static void test_shift_no_slip(void **state)
{
    (void)state;
    static sim_t s;
    const float slips[] = { 0.0f, 3.0f, 5.0f, -50.0f };  /* not above min_start_slip_rad_s (5) */
    for (size_t i = 0u; i < WC_TEST_COUNT(slips); ++i) {
        sim_init(&s, &test_cal, slips[i], TURBINE_TORQUE_Nm);
        const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
        const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
        assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
        WC_CHECK(s.report.abort_reason == (uint32_t)WC_SHIFT_ABORT_NO_SLIP, "slip %g: reason %u", (double)slips[i],
                 (unsigned)s.report.abort_reason);
        /* at the inertia phase's start: after prepare + torque phase */
        WC_CHECK((steps >= 150u) && (steps <= 152u), "slip %g: ended after %u steps", (double)slips[i], (unsigned)steps);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
        assert_int_equal(s.ended, 1u);
    }
}

/* Anti-windup: the integral within +-integral_limit_Nm in every phase,
 * also with a small limit, feedback only (feed-forward 0) and a high ki. */
static void test_shift_integral_bounded(void **state)
{
    (void)state;
    static sim_t s;
    wc_shift_calibration_t cal = test_cal;
    const float limits[] = { 0.0f, 20.0f, 50.0f, 300.0f };
    const float ff_gains[] = { 0.0f, 0.5f, 1.0f, 2.0f };
    const float plant_torque[] = { TURBINE_TORQUE_Nm, 2000.0f };
    for (size_t l = 0u; l < WC_TEST_COUNT(limits); ++l) {
        for (size_t g = 0u; g < WC_TEST_COUNT(ff_gains); ++g) {
            for (size_t p = 0u; p < WC_TEST_COUNT(plant_torque); ++p) {
                cal.integral_limit_Nm = limits[l];
                cal.feedforward_gain = ff_gains[g];
                cal.ki_Nm_per_rad = 400.0f;
                sim_init(&s, &cal, START_SLIP_rad_s, plant_torque[p]);
                const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
                (void)sim_run_to_end(&s, &command, 5000u);
                WC_CHECK(s.max_abs_integral_Nm <= limits[l],
                         "limit %g, feed-forward gain %g, plant %g Nm: |integral| reached %g (abort %u)",
                         (double)limits[l], (double)ff_gains[g], (double)plant_torque[p],
                         (double)s.max_abs_integral_Nm, (unsigned)s.report.abort_reason);
                WC_CHECK(s.all_finite, "non-finite");
                assert_int_equal(s.ended, 1u);
            }
        }
    }
}

/* Non-finite sensor values during the inertia phase: every output finite,
 * the shift state and report finite, one report. */
static void test_shift_non_finite_sensors(void **state)
{
    (void)state;
    static sim_t s;
    const float bad[] = { NAN, INFINITY, -INFINITY, -NAN, FLT_MAX, -FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
        (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
        for (int k = 0; k < 30; ++k) {
            const bool slip_bad = (k % 3) != 2;
            const bool ended = sim_step_sensor(&s, &command, false, slip_bad ? bad[i] : s.slip_rad_s,
                                               ((k % 2) == 0) ? bad[i] : THETA_OIL_degC);
            WC_CHECK(!ended || (s.shift.phase == (uint32_t)WC_SHIFT_LOCKED) || (s.shift.phase == (uint32_t)WC_SHIFT_ABORTED),
                     "ended in %u", (unsigned)s.shift.phase);
            WC_CHECK(finite_output(&s.out), "sensor %g, step %d: non-finite output", (double)bad[i], k);
            WC_CHECK(finite_shift_state(&s.shift), "sensor %g, step %d: non-finite shift state", (double)bad[i], k);
        }
        (void)sim_run_to_end(&s, &command, 5000u);
        WC_CHECK(s.ended == 1u, "sensor %g: %u reports", (double)bad[i], (unsigned)s.ended);
        WC_CHECK(s.all_finite && finite_report(&s.report), "sensor %g: non-finite", (double)bad[i]);
        print_report("non-finite sensor", &s.report);
    }
    /* a non-finite turbine torque in the command during the shift: ignored (the latched one is kept) */
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
    command.turbine_torque_Nm = NAN;
    for (int k = 0; k < 20; ++k) { (void)sim_step(&s, &command, false); }
    WC_CHECK(wc_test_same_float(s.shift.turbine_torque_Nm, TURBINE_TORQUE_Nm), "turbine torque %g",
             (double)s.shift.turbine_torque_Nm);
    WC_CHECK(s.all_finite, "non-finite");
}

/* The quality vector's theta with the thermal-blind model: the clutch model
 * uses the oil temperature, the report the observer's. */
static void test_shift_theta_source_oil(void **state)
{
    (void)state;
    static sim_t s;
    wc_shift_calibration_t cal = test_cal;
    cal.theta_source = (uint32_t)WC_SHIFT_THETA_OIL;
    sim_init(&s, &cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 200u);
    WC_CHECK(wc_test_same_float(s.out.theta_degC, THETA_OIL_degC), "theta used %g", (double)s.out.theta_degC);
    WC_CHECK(s.clutch.theta_degC > THETA_OIL_degC + 1.0f, "observer %g did not heat", (double)s.clutch.theta_degC);
    (void)sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.report.peak_theta_degC > THETA_OIL_degC + 1.0f, "peak theta %g", (double)s.report.peak_theta_degC);
}

/* ======================================================================== */
/* Frame loop in Shift mode                                                  */
/* ======================================================================== */

typedef struct {
    wc_loop_t loop;
    uint8_t alive;
    float slip_rad_s;
    bool offgoing_released;
    uint32_t reports;
    uint32_t steps;
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    uint32_t n;
    wc_can_shift_report_phys_t last_report;
    wc_can_vfs_command_phys_t vfs;
} loop_sim_t;

static wc_can_frame_t frame_of(uint32_t id)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    return f;
}

static void loop_queue_sensors(loop_sim_t *l)
{
    wc_can_frame_t f = frame_of(WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    const wc_can_clutch_sensors_phys_t s = { l->slip_rad_s / WC_RAD_S_PER_RPM, THETA_OIL_degC, THETA_OIL_degC, l->alive };
    assert_true(wc_can_encode_clutch_sensors(f.data, &s, sizeof f.data) <= WC_CAN_SATURATED);
    assert_true(wc_loop_receive(&l->loop, &f));
}

static void loop_queue_request(loop_sim_t *l, uint8_t mode)
{
    wc_can_frame_t f = frame_of(WC_CAN_TORQUE_REQUEST_FRAME_ID);
    const wc_can_torque_request_phys_t q = { 0.0f, mode, l->alive };
    assert_int_equal(wc_can_encode_torque_request(f.data, &q, sizeof f.data), WC_CAN_OK);
    assert_true(wc_loop_receive(&l->loop, &f));
}

static void loop_queue_command(loop_sim_t *l, bool request, float turbine_torque_Nm, float target_ms)
{
    wc_can_frame_t f = frame_of(WC_CAN_SHIFT_COMMAND_FRAME_ID);
    const wc_can_shift_command_phys_t c = { request ? 1.0f : 0.0f, 2.0f, turbine_torque_Nm, target_ms, l->alive };
    assert_int_equal(wc_can_encode_shift_command(f.data, &c, sizeof f.data), WC_CAN_OK);
    assert_true(wc_loop_receive(&l->loop, &f));
}

/* One period: the frames asked for, one step, the plant. */
static void loop_period(loop_sim_t *l, bool sensors, int mode, int shift_request)
{
    if (sensors) { loop_queue_sensors(l); }
    if (mode >= 0) { loop_queue_request(l, (uint8_t)mode); }
    if (shift_request >= 0) { loop_queue_command(l, shift_request != 0, TURBINE_TORQUE_Nm, 1000.0f * TARGET_TIME_s); }
    l->alive = wc_e2e_counter_next(l->alive);
    memset(l->out, 0xA5, sizeof l->out);
    l->n = wc_loop_step(&l->loop, l->out);
    l->steps++;
    WC_CHECK((l->n == WC_LOOP_TX_CYCLIC) || (l->n == WC_LOOP_TX_FRAMES), "%u frames", (unsigned)l->n);
    assert_int_equal(l->out[0].id, WC_CAN_VFS_COMMAND_FRAME_ID);
    assert_int_equal(l->out[1].id, WC_CAN_CLUTCH_ESTIMATE_FRAME_ID);
    wc_can_vfs_command_phys_t vfs;
    assert_true(wc_can_decode_vfs_command(&vfs, l->out[0].data, l->out[0].dlc) <= WC_CAN_SATURATED);
    l->vfs = vfs;
    if (l->n == WC_LOOP_TX_FRAMES) {
        assert_int_equal(l->out[2].id, WC_CAN_SHIFT_REPORT_FRAME_ID);
        assert_int_equal(l->out[2].dlc, WC_CAN_SHIFT_REPORT_LENGTH);
        assert_int_equal(l->out[2].flags, 0u);
        assert_true(wc_can_decode_shift_report(&l->last_report, l->out[2].data, l->out[2].dlc) <= WC_CAN_SATURATED);
        l->reports++;
    }
    /* plant, as in sim_step, on the loop's clutch output */
    if (l->loop.shift.phase == (uint32_t)WC_SHIFT_INERTIA) { l->offgoing_released = true; }
    if (l->offgoing_released) {
        const float accel = (TURBINE_TORQUE_Nm - l->loop.last.model.torque_Nm) / test_cal.turbine_inertia_kg_m2;
        float next = l->slip_rad_s + accel * DT_s;
        if ((l->slip_rad_s >= 0.0f) && (next < 0.0f)) { next = 0.0f; }
        l->slip_rad_s = (next < SLIP_CAP_rad_s) ? next : SLIP_CAP_rad_s;
        if ((l->loop.last.status & WC_STATUS_LOCKED) != 0u) { l->slip_rad_s = 0.0f; }
    }
}

static void loop_start(loop_sim_t *l, const wc_shift_calibration_t *cal)
{
    memset(l, 0, sizeof *l);
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = cal;
    assert_int_equal(wc_loop_init(&l->loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
    l->slip_rad_s = START_SLIP_rad_s;
    /* Shift mode, request 0, until the safe state is over (E2E sync + recovery) */
    for (int k = 0; k < 40; ++k) { loop_period(l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 0); }
    WC_CHECK((l->vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "still in the safe state: status %x",
             (unsigned)l->vfs.status);
    assert_int_equal(l->reports, 0u);
}

/* A value and its decoded frame: one raw step of the DBC scaling, plus the
 * saturation to the signal's range. */
static void check_signal(const char *what, float decoded, double expected, double lo, double hi, double step)
{
    const double clamped = (expected < lo) ? lo : ((expected > hi) ? hi : expected);
    WC_CHECK_CLOSE(what, 0, decoded, clamped, 0.0, step);
}

static void test_loop_shift_report(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    uint32_t report_step = 0u;
    for (int k = 0; k < 2000; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        if (l.n == WC_LOOP_TX_FRAMES) { report_step = l.steps; }
        WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "safe state during the shift");
    }
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    print_message("    loop: report at step %u\n", (unsigned)report_step);
    const wc_shift_report_t *q = &l.loop.report;
    print_report("loop shift", q);
    assert_int_equal(q->abort_reason, WC_SHIFT_ABORT_NONE);
    assert_int_equal(l.last_report.abort_reason, WC_SHIFT_ABORT_NONE);
    check_signal("InertiaPhaseTime", l.last_report.inertia_phase_time_ms, 1000.0 * (double)q->inertia_time_s, 0.0, 4000.0,
                 1.0);
    check_signal("SlipRmse", l.last_report.slip_rmse_rpm, (double)q->slip_rmse_rad_s / (double)WC_RAD_S_PER_RPM, 0.0,
                 500.0, 0.5);
    check_signal("PeakJerk", l.last_report.peak_jerk_m_per_s3, (double)q->peak_jerk_m_s3, 0.0, 100.0, 0.1);
    check_signal("FrictionEnergy", l.last_report.friction_energy_kJ, 1e-3 * (double)q->friction_energy_J, 0.0, 40.0, 0.01);
    check_signal("PeakClutchTemp", l.last_report.peak_clutch_temp_degC, (double)q->peak_theta_degC, -40.0, 350.0, 0.1);
    check_signal("Flare", l.last_report.flare, q->flare ? 1.0 : 0.0, 0.0, 1.0, 0.0);
    check_signal("TieUp", l.last_report.tie_up, q->tie_up ? 1.0 : 0.0, 0.0, 1.0, 0.0);
    WC_CHECK((q->inertia_time_s >= 0.9f * TARGET_TIME_s) && (q->inertia_time_s <= 1.15f * TARGET_TIME_s),
             "inertia time %g s", (double)q->inertia_time_s);
    assert_int_equal(l.loop.counters.frames_out, 2u * l.steps + 1u);
    /* the request withdrawn after LOCKED: idle, no report */
    for (int k = 0; k < 50; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 0); }
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
}

static void test_loop_shift_command_stale(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    while (l.loop.shift.phase != (uint32_t)WC_SHIFT_INERTIA) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        assert_true(l.steps < 1000u);
    }
    for (int k = 0; k < 50; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1); }
    /* ShiftCommand stops: stale after request_timeout_periods (10) */
    uint32_t first_timeout = 0u;
    for (uint32_t k = 1u; k <= 30u; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, -1);
        if ((first_timeout == 0u) && ((l.vfs.status & WC_CAN_STATUS_REQUEST_TIMEOUT) != 0u)) {
            first_timeout = k;
            WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "timeout without the safe state");
            WC_CHECK(fabsf(l.vfs.vfs_current_mA - wc_table1_calibration.vfs_current_min_mA) <= 0.5f,
                     "safe state current %g mA", (double)l.vfs.vfs_current_mA);
            assert_int_equal(l.n, WC_LOOP_TX_FRAMES);  /* the aborted shift's report, in the same step */
            assert_int_equal(l.last_report.abort_reason, WC_SHIFT_ABORT_INPUT_LOST);
        }
    }
    WC_CHECK((first_timeout >= 10u) && (first_timeout <= 12u), "StatusRequestTimeout after %u periods",
             (unsigned)first_timeout);
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_ABORTED);
    WC_CHECK(l.loop.counters.request_timeouts >= 1u, "request timeout not counted");
}

/* The frame loop's safe state after a completed shift (LOCKED, request still 1):
 * the safe-state policy of wc_loop.h is the solenoid's minimum current. */
static void test_loop_safe_state_after_shift_releases(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    for (int k = 0; (k < 2000) && (l.loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED); ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    for (int k = 0; k < 30; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, -1); }
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "no safe state: status %x", (unsigned)l.vfs.status);
    WC_CHECK(fabsf(l.vfs.vfs_current_mA - wc_table1_calibration.vfs_current_min_mA) <= 0.5f,
             "StatusSafeStateActive with %g mA (shift phase %u): the safe state must be the minimum current",
             (double)l.vfs.vfs_current_mA, (unsigned)l.loop.shift.phase);
}

/* After a completed shift the VCU hands the clutch back (Mode 2, Locked):
 * the very first period in the new mode commands it (maximum current), with
 * no period of the shift controller's released output in between (a 1 ms dip
 * to the minimum current on the solenoid). */
static void test_loop_leaving_shift_mode_after_the_shift_has_no_dip(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    for (int k = 0; (k < 2000) && (l.loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED); ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    const float max_mA = wc_table1_calibration.vfs_current_max_mA;
    for (int k = 0; k < 20; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE, 0);
        WC_CHECK(fabsf(l.vfs.vfs_current_mA - max_mA) <= 0.5f, "period %d in Locked mode: %g mA, not the maximum %g",
                 k, (double)l.vfs.vfs_current_mA, (double)max_mA);
        assert_int_equal(l.n, WC_LOOP_TX_CYCLIC);  /* no second report */
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
}

static void test_loop_mode3_without_shift(void **state)
{
    (void)state;
    static loop_sim_t l;
    memset(&l, 0, sizeof l);
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    assert_int_equal(wc_loop_init(&l.loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
    l.slip_rad_s = START_SLIP_rad_s;
    /* torque control first, out of the safe state */
    for (int k = 0; k < 40; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, -1); }
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "safe state: %x", (unsigned)l.vfs.status);
    const uint32_t implausible = l.loop.counters.rejected[WC_REJECT_IMPLAUSIBLE];
    const uint32_t unknown = l.loop.counters.rejected[WC_REJECT_UNKNOWN_ID];
    const uint32_t sync0 = l.loop.counters.rejected[WC_REJECT_SYNC];
    const uint32_t used0 = l.loop.counters.frames_used;
    /* mode 3 (and ShiftCommand frames) without config.shift */
    for (int k = 0; k < 30; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        if (k == 0) {
            WC_CHECK((l.vfs.status & WC_CAN_STATUS_IMPLAUSIBLE_INPUT) != 0u, "mode 3 not flagged implausible");
        }
        assert_int_equal(l.n, WC_LOOP_TX_CYCLIC);
    }
    /* every TorqueRequest rejected: implausible, except the SyncCounter (3)
     * frames after the request's timeout restarted its E2E receiver */
    const uint32_t n_implausible = l.loop.counters.rejected[WC_REJECT_IMPLAUSIBLE] - implausible;
    const uint32_t n_sync = l.loop.counters.rejected[WC_REJECT_SYNC] - sync0;
    WC_CHECK((n_implausible + n_sync == 30u) && (n_sync <= 3u), "%u implausible, %u sync", (unsigned)n_implausible,
             (unsigned)n_sync);
    assert_int_equal(l.loop.counters.frames_used - used0, 30u);  /* the sensor frames only */
    assert_int_equal(l.loop.counters.rejected[WC_REJECT_UNKNOWN_ID] - unknown, 30u);
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_REQUEST_TIMEOUT) != 0u, "the rejected requests did not time out");
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "no safe state");
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
    assert_int_equal(l.reports, 0u);
}

static void test_loop_init_invalid_shift_calibration(void **state)
{
    (void)state;
    static wc_loop_t loop;
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    wc_shift_calibration_t cal;
    for (size_t i = 0u; i < WC_TEST_COUNT(shift_fields); ++i) {
        cal = test_cal;
        *shift_field_ptr(&cal, shift_fields[i].offset) = NAN;
        config.shift = &cal;
        WC_CHECK(wc_loop_init(&loop, &wc_table1_calibration, &config, THETA_OIL_degC) != WC_CAL_OK,
                 "%s = NaN: wc_loop_init succeeded", shift_fields[i].name);
        /* the failed loop is unusable (no calibration bound) */
        WC_CHECK(loop.clutch.model.cal == NULL, "%s: loop left usable", shift_fields[i].name);
    }
    cal = test_cal;
    cal.theta_source = 7u;
    config.shift = &cal;
    assert_int_not_equal(wc_loop_init(&loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
    config.shift = &test_cal;
    assert_int_equal(wc_loop_init(&loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_calibration_valid),
        cmocka_unit_test(test_calibration_every_code_tested),
        cmocka_unit_test(test_calibration_each_field_rejected),
        cmocka_unit_test(test_calibration_limits_inclusive),
        cmocka_unit_test(test_reference_ends),
        cmocka_unit_test(test_reference_monotone_and_rate),
        cmocka_unit_test(test_feedforward_formula),
        cmocka_unit_test(test_feedforward_bounds),
        cmocka_unit_test(test_lag_compensation_faster),
        cmocka_unit_test(test_lag_compensation_clamped),
        cmocka_unit_test(test_lag_compensation_off_is_exact),
        cmocka_unit_test(test_lag_compensation_any_time_finite),
        cmocka_unit_test(test_theta_from_oil),
        cmocka_unit_test(test_shift_completes),
        cmocka_unit_test(test_shift_cancel),
        cmocka_unit_test(test_shift_input_lost_and_restart),
        cmocka_unit_test(test_shift_safe_while_locked_releases),
        cmocka_unit_test(test_shift_invalid_command),
        cmocka_unit_test(test_shift_inertia_timeout),
        cmocka_unit_test(test_shift_no_slip),
        cmocka_unit_test(test_shift_integral_bounded),
        cmocka_unit_test(test_shift_non_finite_sensors),
        cmocka_unit_test(test_shift_theta_source_oil),
        cmocka_unit_test(test_loop_shift_report),
        cmocka_unit_test(test_loop_shift_command_stale),
        cmocka_unit_test(test_loop_safe_state_after_shift_releases),
        cmocka_unit_test(test_loop_leaving_shift_mode_after_the_shift_has_no_dip),
        cmocka_unit_test(test_loop_mode3_without_shift),
        cmocka_unit_test(test_loop_init_invalid_shift_calibration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
