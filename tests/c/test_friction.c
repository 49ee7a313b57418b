/* Coulomb friction coefficient, eq. 18:
 * mu_f(v, theta) = (mu1 + (mu2 - mu1) e^(-|v|/v_s)) (1 + mu3 (theta - theta1)/theta2). */
#include "wc_test_support.h"

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"

static double friction_reference(const wc_calibration_t *cal, double speed_m_s, double theta_degC)
{
    const double mu1 = (double)cal->mu1;
    const double mu2 = (double)cal->mu2;
    const double stribeck = mu1 + (mu2 - mu1) * exp(-fabs(speed_m_s) / (double)cal->stribeck_speed_m_s);
    return stribeck * (1.0 + (double)cal->mu3 * (theta_degC - (double)cal->theta1_degC) / (double)cal->theta2_K);
}

/* Float against eq. 18 in double with the same constants: about ten float
 * roundings of 6e-8 each; the exponential's argument error |v/v_s| 6e-8 is
 * weighted by (mu2 - mu1) e^(-v/v_s) / mu_f, at most 0.07 here. The
 * temperature factor stays >= 0.4 over -40..250 degC (no cancellation).
 * 1e-6 relative is about 8 float ulps. */
#define FRICTION_REL_TOL 1e-6

static void test_matches_eq18_on_a_grid(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const double speeds_m_s[] = { 0.0, 1e-4, 0.003, 0.01, 0.02424, 0.05, 0.1, 0.3, 1.0, 5.0, 24.0, 81.2 };
    wc_test_worst_t worst = { 0.0, -1 };
    long k = 0;
    for (size_t i = 0u; i < WC_TEST_COUNT(speeds_m_s); ++i) {
        for (double theta = -40.0; theta <= 250.0; theta += 2.5, ++k) {
            const float speed = (float)speeds_m_s[i];
            const float mu = wc_friction_coefficient(cal, speed, (float)theta);
            const double expected = friction_reference(cal, (double)speed, theta);
            WC_CHECK_CLOSE("mu_f vs eq. 18", k, mu, expected, FRICTION_REL_TOL, 0.0);
            wc_test_worst_update(&worst, wc_test_rel_error((double)mu, expected), k);
        }
    }
    wc_test_worst_print("mu_f vs eq. 18 (double)", &worst, FRICTION_REL_TOL);
}

/* mu_f of the golden torque vectors (double reference, tools/wetclutch/reference/model).
 * The C gets the sliding speed as the firmware does, R_eff |dw| in float; the
 * reference uses the decimal Table 1 constants where the C has their float
 * roundings (6e-8 each). 2e-6 = the 1e-6 above plus that and the speed's
 * rounding through the exponential. */
#define FRICTION_GOLDEN_REL_TOL 2e-6

static void test_matches_golden(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_model_t model;
    assert_int_equal(wc_model_init(&model, cal), WC_CAL_OK);
    wc_test_worst_t worst = { 0.0, -1 };
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_torque); ++i) {
        const wc_golden_torque_t *g = &wc_golden_torque[i];
        const float speed_m_s = model.effective_radius_m * fabsf(wc_test_rpm_to_rad_s(g->slip_rpm));
        const float mu = wc_friction_coefficient(cal, speed_m_s, (float)g->theta_degC);
        WC_CHECK_CLOSE("mu_f vs golden", i, mu, g->mu_f, FRICTION_GOLDEN_REL_TOL, 0.0);
        wc_test_worst_update(&worst, wc_test_rel_error((double)mu, g->mu_f), (long)i);
    }
    wc_test_worst_print("mu_f vs golden", &worst, FRICTION_GOLDEN_REL_TOL);
}

static void test_limits_and_symmetry(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const double mu1 = (double)cal->mu1;
    const double mu2 = (double)cal->mu2;
    const double mu3 = (double)cal->mu3;
    /* At theta_1 the temperature factor is 1: mu2 at rest, mu1 fast. */
    WC_CHECK_CLOSE("mu_f(0, theta1)", 0, wc_friction_coefficient(cal, 0.0f, cal->theta1_degC), mu2,
                   FRICTION_REL_TOL, 0.0);
    WC_CHECK_CLOSE("mu_f(100 m/s, theta1)", 0, wc_friction_coefficient(cal, 100.0f, cal->theta1_degC), mu1,
                   FRICTION_REL_TOL, 0.0);
    /* theta1 + theta2: factor 1 + mu3. */
    WC_CHECK_CLOSE("mu_f(0, theta1 + theta2)", 0,
                   wc_friction_coefficient(cal, 0.0f, cal->theta1_degC + cal->theta2_K), mu2 * (1.0 + mu3),
                   FRICTION_REL_TOL, 0.0);
    /* The sign of the speed is ignored, bit for bit. */
    for (float v = 0.0f; v < 30.0f; v += 0.37f) {
        for (float theta = -40.0f; theta <= 250.0f; theta += 29.0f) {
            const float plus = wc_friction_coefficient(cal, v, theta);
            const float minus = wc_friction_coefficient(cal, -v, theta);
            WC_CHECK(wc_test_same_float(plus, minus), "mu_f(%g) %.9g != mu_f(-%g) %.9g", (double)v, (double)plus,
                     (double)v, (double)minus);
        }
    }
}

/* mu2 < mu1 in Table 1: mu_f rises with speed; mu3 > 0: it rises with temperature. */
static void test_monotone(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    for (float theta = -40.0f; theta <= 250.0f; theta += 10.0f) {
        float previous = wc_friction_coefficient(cal, 0.0f, theta);
        for (float v = 0.001f; v <= 0.2f; v += 0.001f) {  /* the Stribeck region, v_s = 0.024 m/s */
            const float mu = wc_friction_coefficient(cal, v, theta);
            WC_CHECK(mu >= previous, "mu_f(%g, %g) = %.9g below %.9g", (double)v, (double)theta, (double)mu,
                     (double)previous);
            previous = mu;
        }
    }
    for (float v = 0.0f; v <= 1.0f; v += 0.125f) {
        float previous = wc_friction_coefficient(cal, v, -40.0f);
        for (float theta = -39.0f; theta <= 250.0f; theta += 1.0f) {
            const float mu = wc_friction_coefficient(cal, v, theta);
            WC_CHECK(mu > previous, "mu_f(%g, %g) = %.9g not above %.9g", (double)v, (double)theta, (double)mu,
                     (double)previous);
            previous = mu;
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_eq18_on_a_grid),
        cmocka_unit_test(test_matches_golden),
        cmocka_unit_test(test_limits_and_symmetry),
        cmocka_unit_test(test_monotone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
