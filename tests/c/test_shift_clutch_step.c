/* What the shift controller asks of wc_clutch_step (include/wetclutch/wc_clutch.h;
 * DESIGN section 10): the VFS lag compensation and the thermal-blind option.
 *
 *  - lag compensation: faster pressure, current bounded and flagged, off
 *    (0, NaN, negative, inf; a hand-filled time or gain out of range) bit for
 *    bit the uncompensated step, made once by wc_lag_compensation;
 *  - theta_from_oil: the model at the oil temperature, the observer running. */
#include "wc_test_shift_harness.h"

#include <float.h>

#include "wc_table1_calibration.h"

/* ======================================================================== */
/* Lag compensation and theta_from_oil (wc_clutch_step)                      */
/* ======================================================================== */

static wc_step_input_t torque_input(const wc_clutch_t *clutch, float slip_rad_s, float request_Nm, float lag_s)
{
    wc_step_input_t in;
    memset(&in, 0, sizeof in);
    in.slip_rad_s = slip_rad_s;
    in.theta_oil_degC = THETA_OIL_degC;
    in.theta_housing_degC = THETA_OIL_degC;
    in.torque_request_Nm = request_Nm;
    in.mode = WC_MODE_TORQUE;
    in.lag_compensation = wc_lag_compensation(clutch, lag_s);
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
    wc_step_input_t in = torque_input(&clutch, 50.0f, 0.0f, lag_s);
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
    wc_step_input_t in = torque_input(&clutch, 50.0f, 400.0f, 0.015f);
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

/* 400 steps of a fresh clutch with the request jumping between 0 and 800 Nm
 * every 50 periods under lag compensation `lag`: every output finite, the
 * current in the solenoid's range (`what` names the case in a failure). */
static void hard_requests_stay_finite(const wc_lag_compensation_t *lag, double what)
{
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, cal, THETA_OIL_degC), WC_CAL_OK);
    for (int k = 0; k < 400; ++k) {
        const float request = ((k / 50) % 2 == 0) ? 0.0f : 800.0f;
        wc_step_input_t in = torque_input(&clutch, 30.0f, request, 0.0f);
        in.lag_compensation = *lag;
        wc_step_output_t out;
        (void)wc_clutch_step(&clutch, &in, &out);
        WC_CHECK(finite_output(&out), "case %g step %d: non-finite output", what, k);
        WC_CHECK((out.current_mA >= cal->vfs_current_min_mA) && (out.current_mA <= cal->vfs_current_max_mA),
                 "case %g step %d: current %g", what, k, (double)out.current_mA);
    }
}

/* Off is exactly the uncompensated step: wc_lag_compensation of a time 0,
 * -0, NaN, negative or infinite, and a hand-filled lag compensation with a
 * time out of range or a gain that is not finite and positive. The same
 * sequence runs on two clutches; outputs and states compared bytewise. */
static void test_lag_compensation_off_is_exact(void **state)
{
    (void)state;
    const float off[] = { 0.0f, -0.0f, NAN, -NAN, -1e-3f, -1.0f, -INFINITY, INFINITY };
    const wc_lag_compensation_t raw_off[] = {
        { 0.0f, 1.0f }, { -0.015f, 1.0f }, { NAN, 1.0f }, { 21.0f, 1.0f }, { INFINITY, 1.0f },  /* time */
        { 0.015f, 0.0f }, { 0.015f, -1.0f }, { 0.015f, NAN }, { 0.015f, INFINITY }, { 0.015f, -INFINITY },  /* gain */
    };
    const size_t cases = WC_TEST_COUNT(off) + WC_TEST_COUNT(raw_off);
    for (size_t i = 0u; i < cases; ++i) {
        wc_clutch_t a;
        wc_clutch_t b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        assert_int_equal(wc_clutch_init(&a, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
        assert_int_equal(wc_clutch_init(&b, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
        const wc_lag_compensation_t lag = (i < WC_TEST_COUNT(off)) ? wc_lag_compensation(&b, off[i])
                                                                   : raw_off[i - WC_TEST_COUNT(off)];
        if (i < WC_TEST_COUNT(off)) {  /* the constructor says off with zeros */
            WC_CHECK(wc_test_same_float(lag.time_s, 0.0f) && wc_test_same_float(lag.vfs_gain, 0.0f),
                     "time %g: wc_lag_compensation not off (%g, %g)", (double)off[i], (double)lag.time_s,
                     (double)lag.vfs_gain);
        }
        for (int k = 0; k < 600; ++k) {
            const float request = (k < 100) ? 0.0f : ((k < 300) ? 300.0f : ((k < 450) ? 20.0f : 600.0f));
            const float slip = 80.0f - 0.15f * (float)k;  /* through zero: lock-up too */
            wc_step_input_t in_a = torque_input(&a, slip, request, 0.0f);
            in_a.theta_from_oil = false;
            in_a.mode = (k < 550) ? WC_MODE_TORQUE : WC_MODE_OPEN;
            wc_step_input_t in_b = in_a;
            in_b.lag_compensation = lag;
            wc_step_output_t out_a;
            wc_step_output_t out_b;
            memset(&out_a, 0, sizeof out_a);
            memset(&out_b, 0, sizeof out_b);
            const wc_status_t sa = wc_clutch_step(&a, &in_a, &out_a);
            const wc_status_t sb = wc_clutch_step(&b, &in_b, &out_b);
            WC_CHECK(sa == sb, "case %zu (time %g, gain %g), step %d: status %x vs %x", i, (double)lag.time_s,
                     (double)lag.vfs_gain, k, (unsigned)sa, (unsigned)sb);
            WC_CHECK(memcmp(&out_a, &out_b, sizeof out_a) == 0,
                     "case %zu (time %g, gain %g), step %d: outputs differ (current %.9g vs %.9g)", i,
                     (double)lag.time_s, (double)lag.vfs_gain, k, (double)out_a.current_mA, (double)out_b.current_mA);
            WC_CHECK(memcmp(&a, &b, sizeof a) == 0, "case %zu, step %d: states differ", i, k);
        }
    }
}

/* A lag compensation is made once and used every step: the same as the one
 * made for the step itself, for any time in range (the gain is the exact
 * expression of DESIGN 9, computed once). And a hand-filled gain that is
 * finite and positive, however large or small, keeps every output finite and
 * the current in the solenoid's range. */
static void test_lag_compensation_made_once(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, cal, THETA_OIL_degC), WC_CAL_OK);
    const wc_lag_compensation_t lag = wc_lag_compensation(&clutch, 0.015f);
    WC_CHECK(wc_test_same_float(lag.time_s, 0.015f), "time %g", (double)lag.time_s);
    /* (1 - e^(-dt/t)) / (1 - e^(-dt/tau)) in double: 1 ms, 15 ms, tau of table1 */
    const double expected = (1.0 - exp(-(double)cal->control_period_s / 0.015)) /
                            (1.0 - exp(-(double)cal->control_period_s / (double)cal->vfs_time_constant_s));
    WC_CHECK(fabs((double)lag.vfs_gain / expected - 1.0) < 1e-5, "gain %.9g, expected %.9g (float rounding: < 1e-5)",
             (double)lag.vfs_gain, expected);
    const float gains[] = { FLT_MIN, 1e-20f, 1e-3f, 1e3f, 1e20f, FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(gains); ++i) {
        const wc_lag_compensation_t hand_filled = { 0.015f, gains[i] };
        hard_requests_stay_finite(&hand_filled, (double)gains[i]);
    }
}

/* Every output finite and the current in range for compensation times
 * from tiny to the VFS limit, with hard request changes. */
static void test_lag_compensation_any_time_finite(void **state)
{
    (void)state;
    const float times[] = { FLT_MIN, 1e-20f, 1e-6f, 1e-3f, 0.015f, 0.06f, 0.5f, 10.0f, 20.0f, FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(times); ++i) {
        wc_clutch_t clutch;
        assert_int_equal(wc_clutch_init(&clutch, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
        const wc_lag_compensation_t lag = wc_lag_compensation(&clutch, times[i]);
        hard_requests_stay_finite(&lag, (double)times[i]);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lag_compensation_faster),
        cmocka_unit_test(test_lag_compensation_clamped),
        cmocka_unit_test(test_lag_compensation_off_is_exact),
        cmocka_unit_test(test_lag_compensation_made_once),
        cmocka_unit_test(test_lag_compensation_any_time_finite),
        cmocka_unit_test(test_theta_from_oil),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
