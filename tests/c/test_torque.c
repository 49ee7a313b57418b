/* Torque model, eq. 3-8: T = R_eff N_c (mu_f F_c + mu_v A_f v / h_bar(F_c / A_f)). */
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

/* Tolerances against the double reference (tools/wetclutch/reference/model, exact film):
 *  - h_bar: the LUT's max relative error 3.875e-5 (`wetclutch lut`, grid 100x
 *    denser than the table) + float Hermite evaluation and p_c rounding ~1e-6;
 *  - viscous = c / h_bar: the same 3.9e-5 through 1/h_bar, + mu_v in float
 *    (<= 3e-6, see test_viscosity.c) + the float roundings of the constants;
 *  - total = coulomb + viscous, both positive: at most the larger of the two;
 *  - coulomb = R_eff N_c mu_f F: no LUT; mu_f in float (<= 2e-6, test_friction.c)
 *    and three more float roundings;
 *  - mu_f: see test_friction.c.
 * The required bar is 1e-4 relative for all; these are tighter and still justified. */
#define HBAR_REL_TOL 5e-5
#define VISCOUS_REL_TOL 5e-5
#define TORQUE_REL_TOL 5e-5
#define COULOMB_REL_TOL 3e-6
#define MU_F_REL_TOL 2e-6

static void test_matches_golden(void **state)
{
    (void)state;
    wc_test_worst_t worst_t = { 0.0, -1 }, worst_c = { 0.0, -1 }, worst_v = { 0.0, -1 }, worst_h = { 0.0, -1 },
                    worst_mu = { 0.0, -1 };
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_torque); ++i) {
        const wc_golden_torque_t *g = &wc_golden_torque[i];
        wc_torque_t out;
        const wc_status_t status = wc_torque(&model, wc_test_rpm_to_rad_s(g->slip_rpm), (float)g->theta_degC,
                                             (float)g->force_N, &out);
        WC_CHECK(status == WC_STATUS_OK, "row %zu: status 0x%x", i, (unsigned)status);
        const long k = (long)i;
        WC_CHECK_CLOSE("torque_Nm", k, out.torque_Nm, g->torque_Nm, TORQUE_REL_TOL, 0.0);
        WC_CHECK_CLOSE("coulomb_Nm", k, out.coulomb_Nm, g->coulomb_Nm, COULOMB_REL_TOL, 0.0);
        WC_CHECK_CLOSE("viscous_Nm", k, out.viscous_Nm, g->viscous_Nm, VISCOUS_REL_TOL, 0.0);
        WC_CHECK_CLOSE("hbar_um", k, 1e6 * (double)out.hbar_m, g->hbar_um, HBAR_REL_TOL, 0.0);
        WC_CHECK_CLOSE("mu_f", k, out.mu_f, g->mu_f, MU_F_REL_TOL, 0.0);
        wc_test_worst_update(&worst_t, wc_test_rel_error((double)out.torque_Nm, g->torque_Nm), k);
        wc_test_worst_update(&worst_c, wc_test_rel_error((double)out.coulomb_Nm, g->coulomb_Nm), k);
        wc_test_worst_update(&worst_v, wc_test_rel_error((double)out.viscous_Nm, g->viscous_Nm), k);
        wc_test_worst_update(&worst_h, wc_test_rel_error(1e6 * (double)out.hbar_m, g->hbar_um), k);
        wc_test_worst_update(&worst_mu, wc_test_rel_error((double)out.mu_f, g->mu_f), k);
    }
    wc_test_worst_print("torque_Nm", &worst_t, TORQUE_REL_TOL);
    wc_test_worst_print("coulomb_Nm", &worst_c, COULOMB_REL_TOL);
    wc_test_worst_print("viscous_Nm", &worst_v, VISCOUS_REL_TOL);
    wc_test_worst_print("hbar_um", &worst_h, HBAR_REL_TOL);
    wc_test_worst_print("mu_f", &worst_mu, MU_F_REL_TOL);
}

/* DESIGN.md section 2: T at 750 rpm, 1188 N = 194.6 / 154.7 / 146.9 Nm at
 * 40 / 65 / 90 degC, and R_eff from the radii 0.077585 m. The document
 * truncates (the reference gives 146.950 Nm at 90 degC, golden vectors), so
 * the tolerance is one unit of the last printed digit plus the model
 * tolerance above. */
static void test_design_reference_numbers(void **state)
{
    (void)state;
    WC_CHECK_CLOSE("R_eff", 0, model.effective_radius_m, 0.077585, 0.0, 0.000001 + 1e-7);
    const float theta_degC[] = { 40.0f, 65.0f, 90.0f };
    const double torque_Nm[] = { 194.6, 154.7, 146.9 };
    for (size_t i = 0u; i < WC_TEST_COUNT(theta_degC); ++i) {
        wc_torque_t out;
        assert_int_equal(wc_torque(&model, wc_test_rpm_to_rad_s(750.0), theta_degC[i], 1188.0f, &out), WC_STATUS_OK);
        WC_CHECK_CLOSE("DESIGN torque", i, out.torque_Nm, torque_Nm[i], TORQUE_REL_TOL, 0.1);
    }
}

/* eq. 8: T strictly increasing in F_c for every (v, theta), which the inverse
 * relies on. Two sweeps: 0..2 N (below 0.045 N the film is clamped and only
 * the Coulomb part rises) and 0..F_max. Each step is 0.01 N / 0.5 N, or
 * longer where needed for the Coulomb part alone, R_eff N_c mu_f dF, to rise
 * by 16 ulps of |T|: at -40 degC and 9999 rpm the drag is 30 kNm (ulp
 * 0.002 Nm) and with the thin film at F_max the viscous part reaches 3 MNm
 * (ulp 0.25 Nm), beyond the resolution of a 0.01 N step. The first sweep
 * then covers 100 such steps instead of 2 N. */
static long sweep(float slip, float theta, float base_step_N, float end_N, double slip_rpm)
{
    wc_torque_t out;
    assert_int_equal(wc_torque(&model, slip, theta, 0.0f, &out), WC_STATUS_OK);
    const float coulomb_per_N = (model.effective_radius_m * (float)model.cal->friction_pairs) * out.mu_f;
    float previous = fabsf(out.torque_Nm);
    float force = 0.0f;
    long steps = 0;
    for (; (force < end_N) && (steps < 10000000L); ++steps) {
        const float ulp = nextafterf(previous, INFINITY) - previous;
        force += fmaxf(base_step_N, 16.0f * ulp / coulomb_per_N);
        assert_int_equal(wc_torque(&model, slip, theta, force, &out), WC_STATUS_OK);
        const float magnitude = fabsf(out.torque_Nm);
        WC_CHECK(magnitude > previous, "slip %g rpm, %g degC: |T(%.9g N)| = %.9g not above %.9g", slip_rpm,
                 (double)theta, (double)force, (double)magnitude, (double)previous);
        previous = magnitude;
    }
    WC_CHECK(steps >= 40, "slip %g rpm, %g degC: only %ld steps", slip_rpm, (double)theta, steps);
    return steps;
}

static void test_strictly_increasing_in_force(void **state)
{
    (void)state;
    const double slips_rpm[] = { -9999.0, -750.0, -3.0, 0.0, 0.5, 3.0, 12.0, 100.0, 750.0, 1500.0, 3000.0, 9999.0 };
    const float thetas_degC[] = { -40.0f, 10.0f, 40.0f, 65.0f, 90.0f, 120.0f, 250.0f };
    long checked = 0;
    for (size_t s = 0u; s < WC_TEST_COUNT(slips_rpm); ++s) {
        const float slip = wc_test_rpm_to_rad_s(slips_rpm[s]);
        for (size_t t = 0u; t < WC_TEST_COUNT(thetas_degC); ++t) {
            wc_torque_t out;
            assert_int_equal(wc_torque(&model, slip, thetas_degC[t], 0.0f, &out), WC_STATUS_OK);
            const float drag = fabsf(out.torque_Nm);
            const float first_step_N =
                fmaxf(0.01f, 16.0f * (nextafterf(drag, INFINITY) - drag) / ((model.effective_radius_m * (float)model.cal->friction_pairs) * out.mu_f));
            checked += sweep(slip, thetas_degC[t], 0.01f, fmaxf(2.0f, 100.0f * first_step_N), slips_rpm[s]);
            checked += sweep(slip, thetas_degC[t], 0.5f, model.force_max_N, slips_rpm[s]);
        }
    }
    WC_CHECK(checked > 1000000L, "only %ld steps", checked);
    print_message("    %ld force steps checked\n", checked);
}

/* The torque acts against the slip: T(-dw) = -T(dw) bit for bit, the same
 * film and mu_f; dw >= 0 gives T >= 0; at dw = 0 only the static capacity. */
static void test_sign_follows_slip(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_torque); ++i) {
        const wc_golden_torque_t *g = &wc_golden_torque[i];
        const float slip = wc_test_rpm_to_rad_s(fabs(g->slip_rpm));
        const float theta = (float)g->theta_degC;
        const float force = (float)g->force_N;
        wc_torque_t pos;
        wc_torque_t neg;
        assert_int_equal(wc_torque(&model, slip, theta, force, &pos), WC_STATUS_OK);
        assert_int_equal(wc_torque(&model, -slip, theta, force, &neg), WC_STATUS_OK);
        if (slip > 0.0f) {
            WC_CHECK(wc_test_same_float(neg.torque_Nm, -pos.torque_Nm), "row %zu", i);
            WC_CHECK(wc_test_same_float(neg.coulomb_Nm, -pos.coulomb_Nm), "row %zu", i);
            WC_CHECK(wc_test_same_float(neg.viscous_Nm, -pos.viscous_Nm), "row %zu", i);
        } else {  /* -0 is "slip >= 0": the same, positive answer */
            WC_CHECK(wc_test_same_float(neg.torque_Nm, pos.torque_Nm), "row %zu", i);
            WC_CHECK(wc_test_same_float(neg.coulomb_Nm, pos.coulomb_Nm), "row %zu", i);
            WC_CHECK(wc_test_same_float(neg.viscous_Nm, pos.viscous_Nm), "row %zu", i);
        }
        WC_CHECK(wc_test_same_float(neg.hbar_m, pos.hbar_m), "row %zu", i);
        WC_CHECK(wc_test_same_float(neg.mu_f, pos.mu_f), "row %zu", i);
        WC_CHECK((pos.torque_Nm >= 0.0f) && (pos.coulomb_Nm >= 0.0f) && (pos.viscous_Nm >= 0.0f), "row %zu", i);
        if (slip > 0.0f) {
            WC_CHECK((pos.torque_Nm > 0.0f) && (neg.torque_Nm < 0.0f), "row %zu: slip without torque", i);
            WC_CHECK((pos.viscous_Nm > 0.0f) && (neg.viscous_Nm < 0.0f), "row %zu: slip without drag", i);
        } else {
            WC_CHECK(wc_test_same_float(fabsf(pos.viscous_Nm), 0.0f), "row %zu: drag at zero slip", i);
            WC_CHECK(wc_test_same_float(pos.torque_Nm, pos.coulomb_Nm), "row %zu", i);
        }
        /* eq. 5: the parts add up (one float addition) */
        WC_CHECK_CLOSE("T = T_c + T_v", i, pos.torque_Nm, (double)pos.coulomb_Nm + (double)pos.viscous_Nm,
                       WC_TEST_FLT_EPSILON, 0.0);
    }
}

static void expect_rejected(float slip, float theta, float force, wc_status_t expected_bits)
{
    wc_torque_t out = { NAN, NAN, NAN, NAN, NAN };
    const wc_status_t status = wc_torque(&model, slip, theta, force, &out);
    WC_CHECK(status == expected_bits, "wc_torque(%g, %g, %g): status 0x%x, expected 0x%x", (double)slip,
             (double)theta, (double)force, (unsigned)status, (unsigned)expected_bits);
    /* Documented safe answer: zero torque with the open-clutch film. */
    WC_CHECK(wc_test_same_float(fabsf(out.torque_Nm), 0.0f) && wc_test_same_float(fabsf(out.coulomb_Nm), 0.0f) &&
                 wc_test_same_float(fabsf(out.viscous_Nm), 0.0f) && wc_test_same_float(fabsf(out.mu_f), 0.0f),
             "wc_torque(%g, %g, %g): T %g Tc %g Tv %g mu %g", (double)slip, (double)theta, (double)force,
             (double)out.torque_Nm, (double)out.coulomb_Nm, (double)out.viscous_Nm, (double)out.mu_f);
    WC_CHECK(wc_test_same_float(out.hbar_m, wc_table1_calibration.film.hbar_m[0]), "h_bar %g", (double)out.hbar_m);
}

static void test_bad_inputs(void **state)
{
    (void)state;
    const float slip_ok = wc_test_rpm_to_rad_s(750.0);
    const float bad_slip[] = { NAN, INFINITY, -INFINITY, nextafterf(WC_SLIP_MAX_rad_s, INFINITY),
                               -nextafterf(WC_SLIP_MAX_rad_s, INFINITY), 1e6f, -FLT_MAX };
    const float bad_theta[] = { NAN, INFINITY, -INFINITY, nextafterf(WC_THETA_MIN_degC, -INFINITY),
                                nextafterf(WC_THETA_MAX_degC, INFINITY), -273.15f, 1e6f };
    const float bad_force[] = { NAN, INFINITY, -INFINITY, -FLT_MIN, -1.0f, -1188.0f,
                                nextafterf(WC_FORCE_MAX_N, INFINITY), FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_slip); ++i) {
        expect_rejected(bad_slip[i], 65.0f, 1188.0f, WC_STATUS_SLIP_INVALID);
    }
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_theta); ++i) {
        expect_rejected(slip_ok, bad_theta[i], 1188.0f, WC_STATUS_THETA_INVALID);
    }
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_force); ++i) {
        expect_rejected(slip_ok, 65.0f, bad_force[i], WC_STATUS_FORCE_INVALID);
    }
    expect_rejected(NAN, NAN, NAN, WC_STATUS_SLIP_INVALID | WC_STATUS_THETA_INVALID | WC_STATUS_FORCE_INVALID);
    expect_rejected(INFINITY, 65.0f, -1.0f, WC_STATUS_SLIP_INVALID | WC_STATUS_FORCE_INVALID);
}

/* The edges of the plausible ranges are accepted, with finite outputs. */
static void test_range_edges_accepted(void **state)
{
    (void)state;
    const float slips[] = { -WC_SLIP_MAX_rad_s, WC_SLIP_MAX_rad_s, 0.0f, -0.0f };
    const float thetas[] = { WC_THETA_MIN_degC, WC_THETA_MAX_degC };
    const float forces[] = { 0.0f, -0.0f, WC_FORCE_MAX_N };
    for (size_t s = 0u; s < WC_TEST_COUNT(slips); ++s) {
        for (size_t t = 0u; t < WC_TEST_COUNT(thetas); ++t) {
            for (size_t f = 0u; f < WC_TEST_COUNT(forces); ++f) {
                wc_torque_t out = { NAN, NAN, NAN, NAN, NAN };
                const wc_status_t status = wc_torque(&model, slips[s], thetas[t], forces[f], &out);
                WC_CHECK(status == WC_STATUS_OK, "(%g, %g, %g): 0x%x", (double)slips[s], (double)thetas[t],
                         (double)forces[f], (unsigned)status);
                WC_CHECK(isfinite(out.torque_Nm) && isfinite(out.coulomb_Nm) && isfinite(out.viscous_Nm) &&
                             isfinite(out.hbar_m) && isfinite(out.mu_f) && (out.hbar_m > 0.0f) && (out.mu_f > 0.0f),
                         "(%g, %g, %g)", (double)slips[s], (double)thetas[t], (double)forces[f]);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_golden),
        cmocka_unit_test(test_design_reference_numbers),
        cmocka_unit_test(test_strictly_increasing_in_force),
        cmocka_unit_test(test_sign_follows_slip),
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_range_edges_accepted),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
