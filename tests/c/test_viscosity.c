/* Oil viscosity, eq. 2: mu_v(theta) = mv1 e^(mv2 theta) + mv3 e^(mv4 theta). */
#include "wc_test_support.h"

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"

/* Eq. 2 in double, from the same (float) calibration constants. */
static double viscosity_reference(const wc_calibration_t *cal, double theta_degC)
{
    return (double)cal->viscosity_a1_Pa_s * exp((double)cal->viscosity_b1_per_K * theta_degC) +
           (double)cal->viscosity_a2_Pa_s * exp((double)cal->viscosity_b2_per_K * theta_degC);
}

/* Tolerance of the float evaluation against eq. 2 in double: the product
 * b theta rounds to 2^-24 relative; over -40..250 degC |b theta| <= 0.07838 * 250
 * = 19.6, so e^(b theta) is off by up to 19.6 * 6e-8 = 1.2e-6 relative; expf
 * adds ~1 ulp (1.2e-7) and the sum one more rounding. 3e-6 covers that. */
#define VISCOSITY_REL_TOL 3e-6

static void test_matches_eq2_over_the_plausible_range(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_test_worst_t worst = { 0.0, -1 };
    long k = 0;
    for (double theta = (double)WC_THETA_MIN_degC; theta <= (double)WC_THETA_MAX_degC; theta += 0.25, ++k) {
        const float mu_v = wc_viscosity_Pa_s(cal, (float)theta);
        const double expected = viscosity_reference(cal, theta);
        WC_CHECK(isfinite(mu_v) && (mu_v > 0.0f), "mu_v(%g) = %g", theta, (double)mu_v);
        WC_CHECK_CLOSE("mu_v vs eq. 2", k, mu_v, expected, VISCOSITY_REL_TOL, 0.0);
        wc_test_worst_update(&worst, wc_test_rel_error((double)mu_v, expected), k);
    }
    wc_test_worst_print("mu_v vs eq. 2 (double)", &worst, VISCOSITY_REL_TOL);
}

/* The paper's oil: 40 degC gives 150.2 e^-3.1352 + 58.15 e^-0.8736 mPa s. */
static void test_paper_value_at_40_degC(void **state)
{
    (void)state;
    const double expected = 0.1502 * exp(-0.07838 * 40.0) + 0.05815 * exp(-0.02184 * 40.0);
    /* Table 1 values as written, against the float calibration: the constants
     * round to float (6e-8 relative) plus the float evaluation (3e-6, above). */
    WC_CHECK_CLOSE("mu_v(40 degC)", 0, wc_viscosity_Pa_s(&wc_table1_calibration, 40.0f), expected,
                   VISCOSITY_REL_TOL, 0.0);
}

/* mu_v recovered from the golden viscous torque of the double reference
 * (tools/wetclutch/reference/model): T_v = R_eff N_c mu_v A_f v / h_bar (eq. 7), so
 * mu_v = T_v h_bar / (R_eff N_c A_f v). The golden values carry 9 digits
 * (5e-9 relative); the reference's constants are the decimal Table 1 values,
 * the C's their float roundings (6e-8 relative each, 4 of them here). */
static void test_matches_golden_viscous_torque(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const double ro = 0.08315;  /* Table 1, as the reference uses them */
    const double ri = 0.07174;
    const double r_eff = 2.0 / 3.0 * (ro * ro * ro - ri * ri * ri) / (ro * ro - ri * ri);
    const double area = 4.053e-3;
    wc_test_worst_t worst = { 0.0, -1 };
    size_t used = 0u;
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_torque); ++i) {
        const wc_golden_torque_t *g = &wc_golden_torque[i];
        if (fabs(g->slip_rpm) < 100.0) {
            continue;  /* small torques: 9 printed digits are fewer significant ones */
        }
        const double speed_m_s = r_eff * fabs(g->slip_rpm) * WC_TEST_RAD_S_PER_RPM;
        const double mu_v = fabs(g->viscous_Nm) * (g->hbar_um * 1e-6) /
                            (r_eff * (double)cal->friction_pairs * area * speed_m_s);
        const float got = wc_viscosity_Pa_s(cal, (float)g->theta_degC);
        WC_CHECK_CLOSE("mu_v vs golden", i, got, mu_v, VISCOSITY_REL_TOL, 0.0);
        wc_test_worst_update(&worst, wc_test_rel_error((double)got, mu_v), (long)i);
        ++used;
    }
    WC_CHECK(used > 100u, "only %zu golden rows used", used);
    wc_test_worst_print("mu_v vs golden T_v", &worst, VISCOSITY_REL_TOL);
}

/* Both exponents are negative: thinner oil when hotter, strictly. */
static void test_strictly_decreasing_in_temperature(void **state)
{
    (void)state;
    float previous = wc_viscosity_Pa_s(&wc_table1_calibration, WC_THETA_MIN_degC);
    for (float theta = WC_THETA_MIN_degC + 0.5f; theta <= WC_THETA_MAX_degC; theta += 0.5f) {
        const float mu_v = wc_viscosity_Pa_s(&wc_table1_calibration, theta);
        WC_CHECK(mu_v < previous, "mu_v(%g) = %.9g not below %.9g", (double)theta, (double)mu_v, (double)previous);
        previous = mu_v;
    }
}

/* The calibration is really used: a second oil gives its own value. */
static void test_uses_its_calibration(void **state)
{
    (void)state;
    wc_calibration_t cal = wc_table1_calibration;
    cal.viscosity_a1_Pa_s = 0.0f;
    cal.viscosity_a2_Pa_s = 0.01f;
    cal.viscosity_b2_per_K = 0.0f;
    WC_CHECK_CLOSE("constant viscosity", 0, wc_viscosity_Pa_s(&cal, 77.0f), 0.01, 1e-7, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_eq2_over_the_plausible_range),
        cmocka_unit_test(test_paper_value_at_40_degC),
        cmocka_unit_test(test_matches_golden_viscous_torque),
        cmocka_unit_test(test_strictly_decreasing_in_temperature),
        cmocka_unit_test(test_uses_its_calibration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
