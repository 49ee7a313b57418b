/* Piston, return spring and VFS: F_app = P A_p - F_s (0 below the spring),
 * P = K i clamped to the solenoid range, first-order lag with time constant tau. */
#include "wc_test_support.h"

#include <float.h>

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"

static const wc_calibration_t *cal1(void) { return &wc_table1_calibration; }

/* (F + F_s) / A_p and P A_p - F_s in float: one addition and one
 * multiplication or division, each rounding to 2^-24 relative: 3 ulps. */
#define HYDRAULICS_REL_TOL (3.0 * WC_TEST_FLT_EPSILON)

static void test_piston_pressure(void **state)
{
    (void)state;
    const wc_calibration_t *cal = cal1();
    for (float force = 0.0f; force <= 12000.0f; force += 7.25f) {
        const double expected = ((double)force + (double)cal->return_spring_force_N) / (double)cal->piston_area_m2;
        WC_CHECK_CLOSE("piston pressure", (long)force, wc_piston_pressure_Pa(cal, force), expected, HYDRAULICS_REL_TOL,
                       0.0);
    }
    /* Table 1: the spring alone needs F_s / A_p = 593.3 N / 4981 mm^2 = 119.11 kPa. */
    WC_CHECK_CLOSE("preload pressure", 0, wc_piston_pressure_Pa(cal, 0.0f), 593.3 / 4.981e-3, 2e-7, 0.0);
}

static void test_contact_force(void **state)
{
    (void)state;
    const wc_calibration_t *cal = cal1();
    const double preload_Pa = (double)cal->return_spring_force_N / (double)cal->piston_area_m2;
    for (float pressure = 0.0f; pressure <= 3.0e6f; pressure += 997.0f) {
        const float force = wc_contact_force_N(cal, pressure);
        const double product = (double)pressure * (double)cal->piston_area_m2;
        const double expected = fmax(product - (double)cal->return_spring_force_N, 0.0);
        /* P A_p - F_s cancels near the preload: the error is relative to P A_p */
        WC_CHECK_CLOSE("contact force", (long)pressure, force, expected, 0.0, HYDRAULICS_REL_TOL * product);
        WC_CHECK(force >= 0.0f, "negative force %g at %g Pa", (double)force, (double)pressure);
        if ((double)pressure <= preload_Pa) {
            WC_CHECK(wc_test_same_float(force, 0.0f), "force %g below the preload (%g Pa)", (double)force,
                     (double)pressure);
        }
    }
    /* Below the spring, never negative; an invalid pressure is no force. */
    const float no_force[] = { -1.0f, -1e9f, -INFINITY, NAN, 0.0f, 100000.0f };
    for (size_t i = 0u; i < WC_TEST_COUNT(no_force); ++i) {
        WC_CHECK(wc_test_same_float(wc_contact_force_N(cal, no_force[i]), 0.0f), "P = %g", (double)no_force[i]);
    }
    /* Round trip over the solenoid's force range. */
    for (float force = 0.0f; force <= 10863.0f; force += 3.5f) {
        const float back = wc_contact_force_N(cal, wc_piston_pressure_Pa(cal, force));
        WC_CHECK_CLOSE("force round trip", (long)force, back, force, 0.0,
                       2.0 * HYDRAULICS_REL_TOL * ((double)force + (double)cal->return_spring_force_N));
    }
}

/* The pressure and current columns of the golden inverse vectors obey
 * P = (F + F_s) / A_p and i = P / K, clamped, in the double reference too. */
static void test_matches_golden_pressure_and_current(void **state)
{
    (void)state;
    const wc_calibration_t *cal = cal1();
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_inverse); ++i) {
        const wc_golden_inverse_t *g = &wc_golden_inverse[i];
        const float pressure_Pa = wc_piston_pressure_Pa(cal, (float)g->force_N);
        /* float: 3 ulps (above) + the golden's 9 digits + Table 1 constants to float */
        WC_CHECK_CLOSE("pressure_kPa", i, 1e-3 * (double)pressure_Pa, g->pressure_kPa, 5e-7, 0.0);
        float current_mA = NAN;
        const wc_status_t status = wc_vfs_current_mA(cal, pressure_Pa, &current_mA);
        WC_CHECK_CLOSE("current_mA", i, current_mA, g->current_mA, 5e-7, 0.0);
        WC_CHECK((status != 0u) == ((g->status & (int)WC_STATUS_CURRENT_CLAMPED) != 0),
                 "row %zu: clamped flag 0x%x, golden status %d", i, (unsigned)status, g->status);
    }
}

static void test_current_clamping_and_flag(void **state)
{
    (void)state;
    wc_calibration_t cal = wc_table1_calibration;
    cal.vfs_current_min_mA = 100.0f;  /* a solenoid with a non-zero minimum */
    const double k = (double)cal.vfs_gain_Pa_per_mA;
    float current = NAN;
    /* In range: P / K, not flagged. */
    for (float pressure = 230000.0f; pressure <= 2300000.0f; pressure += 1234.5f) {
        assert_int_equal(wc_vfs_current_mA(&cal, pressure, &current), WC_STATUS_OK);
        WC_CHECK_CLOSE("P / K", (long)pressure, current, (double)pressure / k, WC_TEST_FLT_EPSILON, 0.0);
    }
    /* Exactly at the ends: not clamped. */
    assert_int_equal(wc_vfs_current_mA(&cal, 2300.0f * 100.0f, &current), WC_STATUS_OK);
    WC_CHECK(wc_test_same_float(current, 100.0f), "%g", (double)current);
    assert_int_equal(wc_vfs_current_mA(&cal, 2300.0f * 1000.0f, &current), WC_STATUS_OK);
    WC_CHECK(wc_test_same_float(current, 1000.0f), "%g", (double)current);
    /* Below the range, negative, -Inf and NaN: the minimum, flagged. */
    const float low[] = { nextafterf(230000.0f, 0.0f), 1000.0f, 0.0f, -5.0f, -INFINITY, NAN };
    for (size_t i = 0u; i < WC_TEST_COUNT(low); ++i) {
        current = NAN;
        WC_CHECK(wc_vfs_current_mA(&cal, low[i], &current) == WC_STATUS_CURRENT_CLAMPED, "P = %g", (double)low[i]);
        WC_CHECK(wc_test_same_float(current, 100.0f), "P = %g: i = %g", (double)low[i], (double)current);
    }
    /* Above: the maximum, flagged. */
    const float high[] = { nextafterf(2300000.0f, INFINITY), 3.0e6f, FLT_MAX, INFINITY };
    for (size_t i = 0u; i < WC_TEST_COUNT(high); ++i) {
        current = NAN;
        WC_CHECK(wc_vfs_current_mA(&cal, high[i], &current) == WC_STATUS_CURRENT_CLAMPED, "P = %g", (double)high[i]);
        WC_CHECK(wc_test_same_float(current, 1000.0f), "P = %g: i = %g", (double)high[i], (double)current);
    }
}

/* VFS lag: tau dP/dt = K i - P, exact for i held over a period:
 * P(n dt) = K i + (P_0 - K i) exp(-n dt / tau).
 * Tolerance: the float decay exp(-dt/tau) differs from the exact one by up
 * to half an ulp (3e-8, 1.8e-6 of 1 - a); its share |a_f^n - a^n| |P_0 - K i|
 * is computed below; the float state rounds by half an ulp per step
 * (<= 0.125 Pa at 2.3 MPa), forgotten with tau/dt = 60 steps: <= 8 Pa. */
static void test_vfs_lag_vs_exact_exponential(void **state)
{
    (void)state;
    wc_model_t model;
    assert_int_equal(wc_model_init(&model, cal1()), WC_CAL_OK);
    const wc_calibration_t *cal = cal1();
    const double dt = (double)cal->control_period_s;
    const double tau = (double)cal->vfs_time_constant_s;
    const double a = exp(-dt / tau);
    WC_CHECK_CLOSE("vfs_decay", 0, model.vfs_decay, a, 2.0 * WC_TEST_FLT_EPSILON, 0.0);
    const struct { float p0_Pa, current_mA; } cases[] = {
        { 0.0f, 500.0f }, { 2.3e6f, 0.0f }, { 119113.0f, 1000.0f }, { 1.0e6f, 434.782608f },
    };
    for (size_t c = 0u; c < WC_TEST_COUNT(cases); ++c) {
        float pressure = cases[c].p0_Pa;
        const double target = (double)cal->vfs_gain_Pa_per_mA * (double)cases[c].current_mA;
        for (long n = 1; n <= 1000; ++n) {  /* 16.7 tau */
            pressure = wc_vfs_lag_step(&model, pressure, cases[c].current_mA);
            const double exact = target + ((double)cases[c].p0_Pa - target) * exp(-(double)n * dt / tau);
            const double decay_share = fabs(pow((double)model.vfs_decay, (double)n) - pow(a, (double)n)) *
                                       fabs((double)cases[c].p0_Pa - target);
            WC_CHECK_CLOSE("VFS lag", (long)c * 10000L + n, pressure, exact, 0.0, decay_share + 8.0);
        }
    }
    /* After 60 steps (one tau): 1 - 1/e of the way (the tolerance above, 8 Pa + the decay's share < 1 Pa). */
    float pressure = 0.0f;
    for (int n = 0; n < 60; ++n) { pressure = wc_vfs_lag_step(&model, pressure, 1000.0f); }
    WC_CHECK_CLOSE("one tau", 0, pressure, 2.3e6 * (1.0 - exp(-1.0)), 0.0, 10.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_piston_pressure),
        cmocka_unit_test(test_contact_force),
        cmocka_unit_test(test_matches_golden_pressure_and_current),
        cmocka_unit_test(test_current_clamping_and_flag),
        cmocka_unit_test(test_vfs_lag_vs_exact_exponential),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
