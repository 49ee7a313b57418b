/* The shift controller's calibration and formulas (include/wetclutch/wc_shift.h,
 * src/model/wc_shift.c; DESIGN section 10).
 *
 *  - calibration check: the test calibration passes; every field rejects
 *    NaN, +-inf and a value just outside each limit with its own code, and
 *    accepts its limits (inclusive); wc_loop_init refuses what it refuses;
 *  - the reference slip (smoothstep) and the feed-forward against their
 *    formulas, in double.
 *
 * The other shift tests, by concern: test_shift_clutch_step.c (the lag
 * compensation and theta_from_oil of wc_clutch_step), test_shift_phases.c
 * (the phase state machine on the plant), test_shift_loop.c (Shift mode in
 * the frame loop); their shared part is wc_test_shift_harness.h, the
 * scenario (calibration, plant, frames) wc_test_fixtures.h. */
#include "wc_test_shift_harness.h"

#include <float.h>

#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_loop.h"

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
    /* adaptation (DESIGN 12); adaptation, the nodes and the scale band are tested on their own */
    SHIFT_FIELD(adapt_scale_step, WC_SHIFT_CAL_ADAPT_SCALE_STEP, 0.0f, WC_CORRECTION_SCALE_MAX, false),
    SHIFT_FIELD(adapt_scale_gain, WC_SHIFT_CAL_ADAPT_SCALE_GAIN, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_confidence_gain, WC_SHIFT_CAL_ADAPT_CONFIDENCE_GAIN, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_film_factor_min, WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MIN, 0.01f, 1.0f, false),
    SHIFT_FIELD(adapt_film_factor_max, WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MAX, 1.0f, 1.0f + WC_CORRECTION_FILM_DELTA_MAX, false),
    SHIFT_FIELD(adapt_film_step, WC_SHIFT_CAL_ADAPT_FILM_STEP, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_film_gain, WC_SHIFT_CAL_ADAPT_FILM_GAIN, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_kiss_band_Pa, WC_SHIFT_CAL_ADAPT_KISS_BAND, 0.0f, WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa, false),
    SHIFT_FIELD(adapt_kiss_step_Pa, WC_SHIFT_CAL_ADAPT_KISS_STEP, 0.0f, WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa, false),
    SHIFT_FIELD(adapt_kiss_gain, WC_SHIFT_CAL_ADAPT_KISS_GAIN, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_window_skip_s, WC_SHIFT_CAL_ADAPT_WINDOW_SKIP, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(adapt_film_window_s, WC_SHIFT_CAL_ADAPT_FILM_WINDOW, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(adapt_min_slip_drop, WC_SHIFT_CAL_ADAPT_MIN_SLIP_DROP, 0.0f, 1.0f, false),
    SHIFT_FIELD(adapt_min_conditioning, WC_SHIFT_CAL_ADAPT_MIN_CONDITIONING, 0.0f, 1.0f, false),
    /* the whole shift (DESIGN 14); coordinator and engine_intervention are tested on their own */
    SHIFT_FIELD(offgoing_ratio, WC_SHIFT_CAL_OFFGOING_RATIO, 0.05f, 20.0f, true),
    SHIFT_FIELD(fill_pulse_current_mA, WC_SHIFT_CAL_FILL_PULSE_CURRENT, 0.0f, WC_SHIFT_LIMIT_CURRENT_MAX_mA, false),
    SHIFT_FIELD(fill_pulse_time_s, WC_SHIFT_CAL_FILL_PULSE_TIME, 0.0f, 0.05f, false),  /* <= test_cal's prepare time */
    SHIFT_FIELD(offgoing_holding_factor, WC_SHIFT_CAL_OFFGOING_HOLDING_FACTOR, 0.0f, 5.0f, false),
    SHIFT_FIELD(offgoing_margin_factor, WC_SHIFT_CAL_OFFGOING_MARGIN_FACTOR, 0.0f, 1.0f, false),
    SHIFT_FIELD(offgoing_lag_compensation_time_s, WC_SHIFT_CAL_OFFGOING_LAG_COMPENSATION_TIME, 1e-3f,
                WC_SHIFT_LIMIT_TIME_MAX_s, true),
    SHIFT_FIELD(flare_kp_Nm_per_rad_s, WC_SHIFT_CAL_FLARE_KP, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX, false),
    SHIFT_FIELD(flare_ki_Nm_per_rad, WC_SHIFT_CAL_FLARE_KI, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX, false),
    SHIFT_FIELD(handover_slip_rad_s, WC_SHIFT_CAL_HANDOVER_SLIP, 0.0f, WC_SLIP_MAX_rad_s, false),
    SHIFT_FIELD(engine_increase_max_Nm, WC_SHIFT_CAL_ENGINE_INCREASE_MAX, 0.0f, WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm, false),
    SHIFT_FIELD(engine_reduction_max_Nm, WC_SHIFT_CAL_ENGINE_REDUCTION_MAX, 0.0f, WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm, false),
    SHIFT_FIELD(engine_fill_fraction, WC_SHIFT_CAL_ENGINE_FILL_FRACTION, 0.0f, 1.0f, false),
    SHIFT_FIELD(engine_reduction_fraction, WC_SHIFT_CAL_ENGINE_REDUCTION_FRACTION, 0.0f, 2.0f, false),
    SHIFT_FIELD(engine_recovery_time_s, WC_SHIFT_CAL_ENGINE_RECOVERY_TIME, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
    SHIFT_FIELD(engine_lead_time_s, WC_SHIFT_CAL_ENGINE_LEAD_TIME, 0.0f, 1.0f, false),
    SHIFT_FIELD(fallback_time_s, WC_SHIFT_CAL_FALLBACK_TIME, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s, false),
};

/* The fields with a rule of their own (test_calibration_adaptation_rules): the
 * integer theta_source and adaptation, the strictly increasing nodes, the
 * scale band (open at 0). */
static bool tested_on_its_own(int code)
{
    return (code == (int)WC_SHIFT_CAL_THETA_SOURCE) || (code == (int)WC_SHIFT_CAL_ADAPTATION) ||
           ((code >= (int)WC_SHIFT_CAL_ADAPT_THETA_NODE0) && (code <= (int)WC_SHIFT_CAL_ADAPT_THETA_NODE4)) ||
           (code == (int)WC_SHIFT_CAL_ADAPT_SCALE_BAND) || (code == (int)WC_SHIFT_CAL_COORDINATOR) ||
           (code == (int)WC_SHIFT_CAL_ENGINE_INTERVENTION);
}
#define ON_ITS_OWN_WORDS (2u + WC_ADAPT_NODES + 1u + 2u)

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
        unsigned uses = tested_on_its_own(code) ? 1u : 0u;
        for (size_t i = 0u; i < WC_TEST_COUNT(shift_fields); ++i) {
            if ((int)shift_fields[i].code == code) { uses++; }
        }
        WC_CHECK(uses == 1u, "error code %d is tested by %u fields", code, uses);
    }
    /* the float fields and theta_source cover the whole struct */
    WC_CHECK(sizeof(wc_shift_calibration_t) == (WC_TEST_COUNT(shift_fields) + ON_ITS_OWN_WORDS) * sizeof(float),
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

/* DESIGN 12: adaptation 0 or 1; the nodes within the thermal envelope and
 * strictly increasing (a node equal to the one before it is rejected with its
 * own code); the scale band in (0, WC_CORRECTION_SCALE_MAX]. */
/* The whole shift's own rules (DESIGN 14): the integer switches, and with the
 * coordinator an off-going ratio above the on-coming one. */
static void test_calibration_whole_shift_rules(void **state)
{
    (void)state;
    wc_shift_calibration_t cal = test_cal;
    cal.engine_intervention = 1u;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    cal.engine_intervention = 2u;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_ENGINE_INTERVENTION);
    cal = test_cal;
    cal.coordinator = 2u;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_COORDINATOR);
    cal.coordinator = 1u;
    cal.offgoing_ratio = 0.0f;  /* off (0) is not a ratio for the coordinator */
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OFFGOING_RATIO);
    cal.offgoing_ratio = cal.output_ratio;  /* the two gears must differ (the gear step divides) */
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OFFGOING_RATIO);
    cal.offgoing_ratio = cal.output_ratio * 1.009f;  /* a step below WC_SHIFT_GEAR_STEP_MIN (1 %) */
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OFFGOING_RATIO);
    cal.offgoing_ratio = cal.output_ratio * 0.991f;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OFFGOING_RATIO);
    cal.offgoing_ratio = cal.output_ratio * 1.5f;  /* an upshift's reduced model */
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    cal.offgoing_ratio = cal.output_ratio / 1.5f;  /* a downshift's (DESIGN 15) */
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    cal.offgoing_ratio = NAN;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OFFGOING_RATIO);
}

static void test_calibration_adaptation_rules(void **state)
{
    (void)state;
    wc_shift_calibration_t cal = test_cal;
    cal.adaptation = 1u;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    cal.adaptation = 2u;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_ADAPTATION);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        const wc_shift_cal_error_t code = (wc_shift_cal_error_t)((uint32_t)WC_SHIFT_CAL_ADAPT_THETA_NODE0 + i);
        const float bad[] = { NAN, INFINITY, -INFINITY, WC_THETA_MAX_degC + 1.0f, WC_THETA_MIN_degC - 1.0f };
        for (size_t k = 0u; k < WC_TEST_COUNT(bad); ++k) {
            cal = test_cal;
            cal.adapt_theta_node_degC[i] = bad[k];
            WC_CHECK(wc_shift_calibration_check(&cal) == code, "node %u = %g", (unsigned)i, (double)bad[k]);
        }
        if (i > 0u) {  /* equal to the node before: not strictly increasing */
            cal = test_cal;
            cal.adapt_theta_node_degC[i] = cal.adapt_theta_node_degC[i - 1u];
            WC_CHECK(wc_shift_calibration_check(&cal) == code, "node %u equal to its predecessor", (unsigned)i);
        }
    }
    const float nodes_ok[WC_ADAPT_NODES] = { WC_THETA_MIN_degC, 0.0f, 100.0f, 200.0f, WC_THETA_MAX_degC };
    cal = test_cal;
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) { cal.adapt_theta_node_degC[i] = nodes_ok[i]; }
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
    const float band_bad[] = { 0.0f, -0.1f, nextafterf(WC_CORRECTION_SCALE_MAX, 1.0f), NAN };
    for (size_t k = 0u; k < WC_TEST_COUNT(band_bad); ++k) {
        cal = test_cal;
        cal.adapt_scale_band = band_bad[k];
        WC_CHECK(wc_shift_calibration_check(&cal) == WC_SHIFT_CAL_ADAPT_SCALE_BAND, "band %g", (double)band_bad[k]);
    }
    cal = test_cal;
    cal.adapt_scale_band = WC_CORRECTION_SCALE_MAX;
    assert_int_equal(wc_shift_calibration_check(&cal), WC_SHIFT_CAL_OK);
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
/* The calibration check through wc_loop_init                               */
/* ======================================================================== */

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
        cmocka_unit_test(test_calibration_adaptation_rules),
        cmocka_unit_test(test_calibration_whole_shift_rules),
        cmocka_unit_test(test_reference_ends),
        cmocka_unit_test(test_reference_monotone_and_rate),
        cmocka_unit_test(test_feedforward_formula),
        cmocka_unit_test(test_feedforward_bounds),
        cmocka_unit_test(test_loop_init_invalid_shift_calibration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
