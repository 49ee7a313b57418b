/* Thermal observer, eq. 1, exact zero-order-hold discretization:
 * theta[k+1] = theta_ss + (theta[k] - theta_ss) a, a = exp(-(k1 + k2) dt / C). */
#include "wc_test_support.h"

#include <float.h>

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"

static wc_model_t model;

static int setup(void **state)
{
    (void)state;
    return (wc_model_init(&model, &wc_table1_calibration) == WC_CAL_OK) ? 0 : -1;
}

static double k_total(const wc_calibration_t *cal)
{
    return (double)cal->oil_conductance_W_per_K + (double)cal->housing_conductance_W_per_K;
}

static double steady_degC(const wc_calibration_t *cal, double power_W, double oil, double housing)
{
    return (power_W + (double)cal->oil_conductance_W_per_K * oil + (double)cal->housing_conductance_W_per_K * housing) /
           k_total(cal);
}

/* How far the float observer may be from exact arithmetic on eq. 1.
 * Each step rounds theta to float (half an ulp); the errors are forgotten at
 * the rate 1 - a per step, so they add up to at most ulp/2 / (1 - a); the
 * float theta_ss adds a bias of a few ulps. The bound is reached near
 * equilibrium: once |theta - theta_ss| (1 - a) is below half an ulp of theta,
 * the update rounds back to theta and the observer stops (a dead band of
 * 3.4 mK at 32..64 degC, 6.8 mK at 64..128 degC for table1 at 1 ms). */
static double float_state_bound(const wc_model_t *m, double theta_abs_max)
{
    const float x = fabsf((float)theta_abs_max);
    const double ulp = (double)(nextafterf(x, INFINITY) - x);
    return (0.5 / (1.0 - (double)m->thermal_decay) + 4.0) * ulp;
}

/* How far the float decay factor a_f moves the transient after n steps:
 * |a_f^n - a^n| |theta_0 - theta_ss| (table1: a_f is 2.9e-8 below a, 5.2e-5
 * of 1 - a; at most |a_f - a| / (e (1 - a)) = 1.9e-5 of the step). */
static double decay_share(const wc_model_t *m, double a_exact, double n, double step)
{
    return fabs(pow((double)m->thermal_decay, n) - pow(a_exact, n)) * fabs(step);
}

/* The decay factor is computed once, at init: a = exp(-(k1+k2) dt / C) to float. */
static void test_decay_factor(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const double a = exp(-k_total(cal) * (double)cal->control_period_s / (double)cal->heat_capacity_J_per_K);
    /* float: the argument (3 roundings) and expf (~1 ulp): 4 ulps of a < 1 */
    WC_CHECK_CLOSE("thermal_decay", 0, model.thermal_decay, a, 4.0 * WC_TEST_FLT_EPSILON, 0.0);
    /* C / (k1 + k2) = 1.77 s (DESIGN.md section 2) */
    WC_CHECK_CLOSE("time constant", 0, (double)cal->heat_capacity_J_per_K / k_total(cal), 1.77, 0.0, 0.005);
}

/* Golden series from the double reference (model.thermal_observer): 3 s of
 * slip, torque, oil and housing steps; theta[k] is the estimate before row k.
 * Tolerance: the float decay factor's share, <= 1.9e-5 of the largest
 * |theta - theta_ss| of the series (see decay_share), plus the float state's
 * bound at the hottest theta of the series (float_state_bound). For table1
 * that is about 1.3e-3 + 6.8e-3 K (1.1e-4 of the 75 degC the series reaches;
 * a worst case: the observed error is ten times smaller). */
static void test_matches_golden_series(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const size_t n = WC_TEST_COUNT(wc_golden_thermal);
    WC_CHECK(n >= 1000u, "only %zu golden rows", n);
    double theta_max = 0.0;
    double transient_max = 0.0;
    for (size_t k = 0u; k < n; ++k) {
        const wc_golden_thermal_t *g = &wc_golden_thermal[k];
        const double power_W = fabs(g->torque_Nm * g->slip_rpm * WC_TEST_RAD_S_PER_RPM);
        theta_max = fmax(theta_max, fabs(g->theta_degC));
        transient_max = fmax(transient_max,
                             fabs(g->theta_degC - steady_degC(cal, power_W, g->theta_oil_degC, g->theta_housing_degC)));
    }
    const double a = exp(-k_total(cal) * (double)cal->control_period_s / (double)cal->heat_capacity_J_per_K);
    const double tolerance_K = fabs((double)model.thermal_decay - a) / (exp(1.0) * (1.0 - a)) * transient_max +
                               float_state_bound(&model, theta_max);

    float theta = (float)wc_golden_thermal[0].theta_oil_degC;  /* the reference starts at the first oil temperature */
    wc_test_worst_t worst = { 0.0, -1 };
    for (size_t k = 0u; k < n; ++k) {
        const wc_golden_thermal_t *g = &wc_golden_thermal[k];
        WC_CHECK_CLOSE("theta_degC", k, theta, g->theta_degC, 0.0, tolerance_K);
        wc_test_worst_update(&worst, fabs((double)theta - g->theta_degC), (long)k);
        /* heat input P = |T dw| (eq. 1), in float as the firmware computes it */
        const float power_W = fabsf((float)g->torque_Nm * wc_test_rpm_to_rad_s(g->slip_rpm));
        const wc_status_t status =
            wc_thermal_step(&model, &theta, power_W, (float)g->theta_oil_degC, (float)g->theta_housing_degC);
        WC_CHECK(status == WC_STATUS_OK, "row %zu: 0x%x", k, (unsigned)status);
    }
    wc_test_worst_print("theta vs golden (K)", &worst, tolerance_K);
}

/* Constant inputs: the exact solution of eq. 1,
 * theta(t) = theta_ss + (theta_0 - theta_ss) exp(-(k1 + k2) t / C).
 * Tolerance at step n: decay_share + float_state_bound (above). */
static void test_constant_input_vs_exact_solution(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const struct { float theta0, power_W, oil, housing; } cases[] = {
        { 40.0f, 4712.0f, 40.0f, 38.0f },    /* 150 Nm at 300 rpm: heating */
        { 180.0f, 0.0f, 45.0f, 60.0f },      /* hot pack cooling down */
        { -40.0f, 20000.0f, -40.0f, -40.0f },/* cold start, hard slip */
        { 80.0f, 0.0f, 80.0f, 80.0f },       /* already at rest */
    };
    const double a = exp(-k_total(cal) * (double)cal->control_period_s / (double)cal->heat_capacity_J_per_K);
    const long checkpoints[] = { 1, 2, 10, 100, 1000, 1772, 5000, 20000 };
    for (size_t c = 0u; c < WC_TEST_COUNT(cases); ++c) {
        float theta = cases[c].theta0;
        const double ss = steady_degC(cal, (double)cases[c].power_W, (double)cases[c].oil, (double)cases[c].housing);
        long step = 0;
        for (size_t p = 0u; p < WC_TEST_COUNT(checkpoints); ++p) {
            for (; step < checkpoints[p]; ++step) {
                assert_int_equal(wc_thermal_step(&model, &theta, cases[c].power_W, cases[c].oil, cases[c].housing),
                                 WC_STATUS_OK);
            }
            const double n = (double)step;
            const double t_s = n * (double)cal->control_period_s;
            const double exact = ss + ((double)cases[c].theta0 - ss) *
                                          exp(-k_total(cal) * t_s / (double)cal->heat_capacity_J_per_K);
            const double tolerance_K = decay_share(&model, a, n, (double)cases[c].theta0 - ss) +
                                       float_state_bound(&model, fmax(fabs((double)cases[c].theta0), fabs(ss)));
            WC_CHECK_CLOSE("theta vs exact", (long)(c * 100000u) + step, theta, exact, 0.0, tolerance_K);
        }
    }
}

/* Heat balance at rest: the fixed point is theta_ss, to within the float
 * state's dead band (float_state_bound: 3.4 mK here, at 58.8 degC). */
static void test_steady_state(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    float theta = 20.0f;
    for (int k = 0; k < 60000; ++k) {  /* 34 time constants: e^-34 ~ 2e-15 */
        assert_int_equal(wc_thermal_step(&model, &theta, 1000.0f, 60.0f, 30.0f), WC_STATUS_OK);
    }
    const double ss = steady_degC(cal, 1000.0, 60.0, 30.0);
    WC_CHECK_CLOSE("theta_ss", 0, theta, ss, 0.0, float_state_bound(&model, ss));
}

static void expect_unchanged(float power_W, float oil, float housing, wc_status_t expected)
{
    const float start[] = { 63.25f, -40.0f, 250.0f };
    for (size_t i = 0u; i < WC_TEST_COUNT(start); ++i) {
        float theta = start[i];
        const wc_status_t status = wc_thermal_step(&model, &theta, power_W, oil, housing);
        WC_CHECK(status == expected, "P %g, oil %g, housing %g: 0x%x, expected 0x%x", (double)power_W, (double)oil,
                 (double)housing, (unsigned)status, (unsigned)expected);
        WC_CHECK(wc_test_same_float(theta, start[i]), "P %g, oil %g, housing %g: state %.9g changed to %.9g",
                 (double)power_W, (double)oil, (double)housing, (double)start[i], (double)theta);
    }
}

static void test_bad_inputs_leave_state_unchanged(void **state)
{
    (void)state;
    const float bad_power[] = { NAN, INFINITY, -INFINITY, -FLT_MIN, -1.0f, -FLT_MAX };
    const float bad_theta[] = { NAN, INFINITY, -INFINITY, nextafterf(WC_THETA_MIN_degC, -INFINITY),
                                nextafterf(WC_THETA_MAX_degC, INFINITY), -273.15f, 1e9f };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_power); ++i) {
        expect_unchanged(bad_power[i], 40.0f, 40.0f, WC_STATUS_POWER_INVALID);
    }
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_theta); ++i) {
        expect_unchanged(100.0f, bad_theta[i], 40.0f, WC_STATUS_THETA_INVALID);
        expect_unchanged(100.0f, 40.0f, bad_theta[i], WC_STATUS_THETA_INVALID);
        expect_unchanged(NAN, bad_theta[i], bad_theta[i], WC_STATUS_POWER_INVALID | WC_STATUS_THETA_INVALID);
    }
    /* The edges are valid and move the state. */
    float theta = 63.25f;
    assert_int_equal(wc_thermal_step(&model, &theta, 0.0f, WC_THETA_MIN_degC, WC_THETA_MAX_degC), WC_STATUS_OK);
    WC_CHECK(!wc_test_same_float(theta, 63.25f) && isfinite(theta), "theta %g", (double)theta);
}

/* A second calibration with other k1, k2, C gives its own dynamics. */
static void test_uses_its_calibration(void **state)
{
    (void)state;
    wc_calibration_t cal = wc_table1_calibration;
    cal.oil_conductance_W_per_K = 50.0f;
    cal.housing_conductance_W_per_K = 0.0f;  /* allowed: no path to the housing */
    cal.heat_capacity_J_per_K = 100.0f;
    wc_model_t other;
    assert_int_equal(wc_model_init(&other, &cal), WC_CAL_OK);
    float theta = 20.0f;
    for (int k = 0; k < 2000; ++k) {  /* 1 time constant (C / k1 = 2 s) */
        assert_int_equal(wc_thermal_step(&other, &theta, 500.0f, 20.0f, 200.0f), WC_STATUS_OK);
    }
    /* theta_ss = 20 + 500/50 = 30 degC, housing ignored (k2 = 0); tolerance as
     * in test_constant_input_vs_exact_solution, with this model's float decay. */
    const double a = exp(-50.0 * (double)cal.control_period_s / 100.0);
    WC_CHECK_CLOSE("k2 = 0, one time constant", 0, theta, 30.0 - 10.0 * exp(-1.0), 0.0,
                   decay_share(&other, a, 2000.0, 10.0) + float_state_bound(&other, 30.0));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decay_factor),
        cmocka_unit_test(test_matches_golden_series),
        cmocka_unit_test(test_constant_input_vs_exact_solution),
        cmocka_unit_test(test_steady_state),
        cmocka_unit_test(test_bad_inputs_leave_state_unchanged),
        cmocka_unit_test(test_uses_its_calibration),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
