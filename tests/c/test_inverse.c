/* Inverse: torque request -> contact force (bounded bisection on T(F_c),
 * eq. 8) -> piston pressure -> VFS current. */
#include "wc_test_support.h"

#include <stdio.h>

#include <float.h>

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"

static wc_model_t model;

static int setup(void **state)
{
    (void)state;
    return (wc_model_init(&model, &wc_table1_calibration) == WC_CAL_OK) ? 0 : -1;
}

static float torque_magnitude(float slip_rad_s, float theta_degC, float force_N)
{
    wc_torque_t out;
    const wc_status_t status = wc_torque(&model, slip_rad_s, theta_degC, force_N, &out);
    WC_CHECK(status == WC_STATUS_OK, "wc_torque(%g, %g, %g): 0x%x", (double)slip_rad_s, (double)theta_degC,
             (double)force_N, (unsigned)status);
    return fabsf(out.torque_Nm);
}

/* Tolerances against the double reference, whose bisection is exact:
 *  - force: the C stops once the bracket is narrower than
 *    WC_INVERSE_FORCE_TOLERANCE_N (0.01 N) and answers its middle, so it is
 *    within 0.005 N of the root of the float model; the float model's torque
 *    differs from the reference by <= 5e-5 relative (film LUT 3.9e-5, see
 *    test_torque.c), which moves the root by about as much relative to F when
 *    the Coulomb part dominates. Hence 0.01 N absolute + 1e-4 relative;
 *  - pressure = (F + F_s)/A_p and current = pressure / K inherit the force's
 *    error divided by F + F_s >= 593 N: 0.01/593 = 1.7e-5 + the relative part,
 *    and 3 float roundings. 1e-4 relative. */
#define FORCE_ABS_TOL_N 0.01
#define FORCE_REL_TOL 1e-4
#define PRESSURE_REL_TOL 1e-4
#define CURRENT_REL_TOL 1e-4

static void test_matches_golden(void **state)
{
    (void)state;
    wc_test_worst_t worst_f = { 0.0, -1 }, worst_p = { 0.0, -1 }, worst_i = { 0.0, -1 };
    size_t counts[3] = { 0u, 0u, 0u };  /* bisected, below drag, saturated */
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_inverse); ++i) {
        const wc_golden_inverse_t *g = &wc_golden_inverse[i];
        wc_inverse_t out;
        const wc_status_t status =
            wc_inverse(&model, wc_test_rpm_to_rad_s(g->slip_rpm), (float)g->theta_degC, (float)g->torque_Nm, &out);
        const long k = (long)i;
        /* The status bits of the reference (BELOW_DRAG, SATURATED, CURRENT_CLAMPED). */
        WC_CHECK(status == (wc_status_t)g->status, "row %zu (%g rpm, %g degC, %g Nm): status 0x%x, golden 0x%x", i,
                 g->slip_rpm, g->theta_degC, g->torque_Nm, (unsigned)status, (unsigned)g->status);
        WC_CHECK_CLOSE("force_N", k, out.force_N, g->force_N, FORCE_REL_TOL, FORCE_ABS_TOL_N);
        WC_CHECK_CLOSE("pressure_kPa", k, 1e-3 * (double)out.pressure_Pa, g->pressure_kPa, PRESSURE_REL_TOL, 0.0);
        WC_CHECK_CLOSE("current_mA", k, out.current_mA, g->current_mA, CURRENT_REL_TOL, 0.0);
        WC_CHECK(out.iterations <= WC_INVERSE_MAX_ITERATIONS, "row %zu: %u iterations", i, (unsigned)out.iterations);
        wc_test_worst_update(&worst_f, fabs((double)out.force_N - g->force_N), k);
        wc_test_worst_update(&worst_p, wc_test_rel_error(1e-3 * (double)out.pressure_Pa, g->pressure_kPa), k);
        wc_test_worst_update(&worst_i, wc_test_rel_error((double)out.current_mA, g->current_mA), k);
        if ((status & WC_STATUS_BELOW_DRAG) != 0u) {
            ++counts[1];
        } else if ((status & WC_STATUS_SATURATED) != 0u) {
            ++counts[2];
        } else {
            ++counts[0];
        }
    }
    /* The golden set exercises all three branches. */
    WC_CHECK((counts[0] > 100u) && (counts[1] > 10u) && (counts[2] > 10u), "bisected %zu, drag %zu, saturated %zu",
             counts[0], counts[1], counts[2]);
    wc_test_worst_print("force_N (absolute, N)", &worst_f, FORCE_ABS_TOL_N);
    wc_test_worst_print("pressure_kPa", &worst_p, PRESSURE_REL_TOL);
    wc_test_worst_print("current_mA", &worst_i, CURRENT_REL_TOL);
}

/* Round trip: the torque model at the answer brackets the request within the
 * force tolerance, T(F - 0.01 N) <= T_req <= T(F + 0.01 N) (the root of the
 * float model is within WC_INVERSE_FORCE_TOLERANCE_N of F), and the Newton
 * steps stopped on the tolerance, not on the iteration cap. */
static void test_round_trip(void **state)
{
    (void)state;
    const double slips_rpm[] = { -750.0, 0.0, 0.5, 3.0, 12.0, 50.0, 100.0, 300.0, 750.0, 1500.0, 3000.0, 9000.0 };
    const float thetas[] = { -40.0f, 10.0f, 25.0f, 40.0f, 65.0f, 90.0f, 120.0f, 200.0f };
    long bisected = 0;
    long steps_histogram[WC_INVERSE_MAX_ITERATIONS] = {0};
    for (size_t s = 0u; s < WC_TEST_COUNT(slips_rpm); ++s) {
        const float slip = wc_test_rpm_to_rad_s(slips_rpm[s]);
        for (size_t t = 0u; t < WC_TEST_COUNT(thetas); ++t) {
            for (float request = 0.0f; request <= 1500.0f; request += 3.7f) {
                wc_inverse_t out;
                const wc_status_t status = wc_inverse(&model, slip, thetas[t], request, &out);
                WC_CHECK(out.iterations <= WC_INVERSE_MAX_ITERATIONS, "%u iterations", (unsigned)out.iterations);
                if ((status & (WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED)) != 0u) {
                    continue;
                }
                ++bisected;
                const float lo = fmaxf(out.force_N - 0.01f, 0.0f);
                const float hi = out.force_N + 0.01f;
                const float t_lo = torque_magnitude(slip, thetas[t], lo);
                const float t_hi = torque_magnitude(slip, thetas[t], hi);
                WC_CHECK((t_lo <= request) && (request <= t_hi),
                         "%g rpm, %g degC: T_req %g not in [T(%g) = %.9g, T(%g) = %.9g]", slips_rpm[s],
                         (double)thetas[t], (double)request, (double)lo, (double)t_lo, (double)hi, (double)t_hi);
                const float achieved = torque_magnitude(slip, thetas[t], out.force_N);
                WC_CHECK(fabsf(achieved - request) <= t_hi - t_lo, "|T(F) - T_req| = %g", (double)(achieved - request));
                /* Stopped on the tolerance, not on the cap: every root here lies
                 * inside the film table, so at least one Newton step was taken. */
                WC_CHECK((out.iterations >= 1u) && (out.iterations < WC_INVERSE_MAX_ITERATIONS),
                         "stopped after %u Newton steps", (unsigned)out.iterations);
                steps_histogram[out.iterations]++;
                WC_CHECK(status == WC_STATUS_OK, "status 0x%x", (unsigned)status);
            }
        }
    }
    WC_CHECK(bisected > 10000, "only %ld solved cases", bisected);
    printf("    Newton steps per solve:");
    for (uint32_t k = 0u; k < WC_INVERSE_MAX_ITERATIONS; ++k) {
        if (steps_histogram[k] != 0) { printf(" %u: %ld", (unsigned)k, steps_histogram[k]); }
    }
    printf(" (of %ld)\n", bisected);
}

/* Below the drag at F_c = 0 the answer is F_c = 0 and the spring-preload pressure. */
static void test_below_drag(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const double preload_Pa = (double)cal->return_spring_force_N / (double)cal->piston_area_m2;
    const double slips_rpm[] = { 0.0, 50.0, 750.0, 3000.0 };
    for (size_t s = 0u; s < WC_TEST_COUNT(slips_rpm); ++s) {
        const float slip = wc_test_rpm_to_rad_s(slips_rpm[s]);
        const float drag = torque_magnitude(slip, 10.0f, 0.0f);
        const float requests[] = { 0.0f, 0.5f * drag, drag };
        for (size_t r = 0u; r < WC_TEST_COUNT(requests); ++r) {
            wc_inverse_t out;
            const wc_status_t status = wc_inverse(&model, slip, 10.0f, requests[r], &out);
            WC_CHECK(status == WC_STATUS_BELOW_DRAG, "%g rpm, %g Nm (drag %g): 0x%x", slips_rpm[s],
                     (double)requests[r], (double)drag, (unsigned)status);
            WC_CHECK(wc_test_same_float(out.force_N, 0.0f), "force %g", (double)out.force_N);
            WC_CHECK_CLOSE("preload pressure", (long)s, out.pressure_Pa, preload_Pa, 3.0 * WC_TEST_FLT_EPSILON, 0.0);
            WC_CHECK_CLOSE("preload current", (long)s, out.current_mA, preload_Pa / (double)cal->vfs_gain_Pa_per_mA,
                           4.0 * WC_TEST_FLT_EPSILON, 0.0);
            assert_int_equal(out.iterations, 0);
        }
        if (drag > 0.0f) {  /* just above the drag: a (small) force */
            wc_inverse_t out;
            const float request = nextafterf(drag, INFINITY) * (1.0f + 1e-4f);
            assert_int_equal(wc_inverse(&model, slip, 10.0f, request, &out), WC_STATUS_OK);
            WC_CHECK(out.force_N > 0.0f, "force %g", (double)out.force_N);
        }
    }
}

/* Above the capacity at the maximum current: F_max, the maximum current, SATURATED. */
static void test_saturation(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    /* F_max = K i_max A_p - F_s = 2300 * 1000 * 4.981e-3 - 593.3 = 10863 N */
    WC_CHECK_CLOSE("force_max_N", 0, model.force_max_N, 10863.0, 2.0 * WC_TEST_FLT_EPSILON, 0.0);
    const double slips_rpm[] = { 0.0, 100.0, 3000.0 };
    for (size_t s = 0u; s < WC_TEST_COUNT(slips_rpm); ++s) {
        const float slip = wc_test_rpm_to_rad_s(slips_rpm[s]);
        const float capacity = torque_magnitude(slip, 65.0f, model.force_max_N);
        const float requests[] = { nextafterf(capacity, INFINITY) * (1.0f + 1e-6f), 2.0f * capacity,
                                   WC_TORQUE_MAX_Nm };
        for (size_t r = 0u; r < WC_TEST_COUNT(requests); ++r) {
            wc_inverse_t out;
            const wc_status_t status = wc_inverse(&model, slip, 65.0f, requests[r], &out);
            WC_CHECK((status & ~WC_STATUS_CURRENT_CLAMPED) == WC_STATUS_SATURATED, "%g Nm: 0x%x",
                     (double)requests[r], (unsigned)status);
            WC_CHECK(wc_test_same_float(out.force_N, model.force_max_N), "force %g", (double)out.force_N);
            WC_CHECK_CLOSE("max current", (long)r, out.current_mA, (double)cal->vfs_current_max_mA, 4.0 * WC_TEST_FLT_EPSILON,
                           0.0);
            WC_CHECK(out.current_mA <= cal->vfs_current_max_mA, "current %.9g above the maximum",
                     (double)out.current_mA);
            assert_int_equal(out.iterations, 0);
        }
        /* Exactly the capacity is reachable (T(F) < T_req is the saturation test). */
        wc_inverse_t out;
        assert_int_equal(wc_inverse(&model, slip, 65.0f, capacity, &out), WC_STATUS_OK);
        WC_CHECK(out.force_N >= model.force_max_N - 0.01f, "force %g", (double)out.force_N);
    }
}

/* DESIGN.md section 2: 150 Nm at 750 rpm, 90 degC -> F_c = 1214.8 N,
 * P = 363.0 kPa, i = 157.8 mA. One unit of the last digit + the tolerances
 * above; but the document's F_c is itself 0.11 N above the reference's
 * (golden row: 1214.69377 N, 362.97807 kPa, 157.816552 mA), so F_c gets 0.2 N. */
static void test_design_reference_numbers(void **state)
{
    (void)state;
    wc_inverse_t out;
    assert_int_equal(wc_inverse(&model, wc_test_rpm_to_rad_s(750.0), 90.0f, 150.0f, &out), WC_STATUS_OK);
    WC_CHECK_CLOSE("force", 0, out.force_N, 1214.8, 0.0, 0.2);
    WC_CHECK_CLOSE("pressure kPa", 0, 1e-3 * (double)out.pressure_Pa, 363.0, PRESSURE_REL_TOL, 0.1);
    WC_CHECK_CLOSE("current", 0, out.current_mA, 157.8, CURRENT_REL_TOL, 0.1);
}

static void expect_rejected(float slip, float theta, float request, wc_status_t expected_bits)
{
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_inverse_t out = { NAN, NAN, NAN, 99u };
    const wc_status_t status = wc_inverse(&model, slip, theta, request, &out);
    WC_CHECK((status & WC_STATUS_INPUT_INVALID) == expected_bits, "(%g, %g, %g): 0x%x, expected bits 0x%x",
             (double)slip, (double)theta, (double)request, (unsigned)status, (unsigned)expected_bits);
    WC_CHECK((status & (WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED)) == 0u, "0x%x", (unsigned)status);
    /* Documented safe answer: no contact force, the current holding the spring preload. */
    WC_CHECK(wc_test_same_float(out.force_N, 0.0f), "force %g", (double)out.force_N);
    const double preload_Pa = (double)cal->return_spring_force_N / (double)cal->piston_area_m2;
    WC_CHECK_CLOSE("safe pressure", 0, out.pressure_Pa, preload_Pa, 3.0 * WC_TEST_FLT_EPSILON, 0.0);
    WC_CHECK_CLOSE("safe current", 0, out.current_mA, preload_Pa / (double)cal->vfs_gain_Pa_per_mA, 4.0 * WC_TEST_FLT_EPSILON,
                   0.0);
    assert_int_equal(out.iterations, 0);
}

static void test_bad_inputs(void **state)
{
    (void)state;
    const float slip_ok = wc_test_rpm_to_rad_s(750.0);
    const float bad_slip[] = { NAN, INFINITY, -INFINITY, nextafterf(WC_SLIP_MAX_rad_s, INFINITY), -2000.0f };
    const float bad_theta[] = { NAN, INFINITY, -INFINITY, nextafterf(WC_THETA_MIN_degC, -INFINITY),
                                nextafterf(WC_THETA_MAX_degC, INFINITY) };
    const float bad_torque[] = { NAN, INFINITY, -INFINITY, -FLT_MIN, -150.0f, nextafterf(WC_TORQUE_MAX_Nm, INFINITY) };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_slip); ++i) {
        expect_rejected(bad_slip[i], 65.0f, 150.0f, WC_STATUS_SLIP_INVALID);
    }
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_theta); ++i) {
        expect_rejected(slip_ok, bad_theta[i], 150.0f, WC_STATUS_THETA_INVALID);
    }
    for (size_t i = 0u; i < WC_TEST_COUNT(bad_torque); ++i) {
        expect_rejected(slip_ok, 65.0f, bad_torque[i], WC_STATUS_TORQUE_INVALID);
    }
    expect_rejected(NAN, NAN, NAN, WC_STATUS_SLIP_INVALID | WC_STATUS_THETA_INVALID | WC_STATUS_TORQUE_INVALID);
    /* The edges of the ranges are valid inputs. */
    wc_inverse_t out;
    const wc_status_t status = wc_inverse(&model, -WC_SLIP_MAX_rad_s, WC_THETA_MAX_degC, WC_TORQUE_MAX_Nm, &out);
    WC_CHECK((status & WC_STATUS_INPUT_INVALID) == 0u, "0x%x", (unsigned)status);
    WC_CHECK(isfinite(out.force_N) && isfinite(out.pressure_Pa) && isfinite(out.current_mA), "non-finite output");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_golden),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_below_drag),
        cmocka_unit_test(test_saturation),
        cmocka_unit_test(test_design_reference_numbers),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
