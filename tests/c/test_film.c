/* Film thickness h_bar(p_c) from the generated table (eq. 9, 15, 16),
 * cubic Hermite with the exact slopes, clamped at both ends. */
#include "wc_test_support.h"

#include <float.h>
#include <stdio.h>

#include "wc_golden_vectors.h"
#include "wc_operating_point.h"  /* internal: the inverse's power-basis form of a segment */
#include "wc_table1_calibration.h"

static const wc_film_table_t *table1(void) { return &wc_table1_calibration.film; }

/* ---- Independent double reference of eq. 9 and 15 ----------------------
 * Paper Table 1 (E, beta, sigma) and the project default N (DESIGN.md 2):
 * the contact constants are not part of the C calibration, only the table
 * made from them, so the test restates them. */
#define REF_E_Pa 10.0e6
#define REF_BETA_m 5.0e-4
#define REF_SIGMA_m 6.0e-6
#define REF_N_per_m2 1.667e7
#define REF_SEPARATION_MAX_m (4.0 * REF_SIGMA_m)  /* film_lut.separation_max_sigma */
#define REF_PRESSURE_MAX_Pa 4.2e6                   /* film_lut.contact_pressure_max */
#define REF_PI 3.14159265358979323846

/* p_c(h), eq. 15 (Greenwood-Williamson, eq. 11-14). */
static double ref_contact_pressure_Pa(double h_m)
{
    const double x = h_m / (sqrt(2.0) * REF_SIGMA_m);
    const double k = sqrt(REF_PI / 2.0) * REF_E_Pa * REF_N_per_m2 * REF_BETA_m * REF_SIGMA_m;
    return k * (exp(-x * x) - (h_m / REF_SIGMA_m) * sqrt(REF_PI / 2.0) * erfc(x));
}

/* h_bar(h), eq. 9 (Patir-Cheng). */
static double ref_film_m(double h_m)
{
    const double x = h_m / (sqrt(2.0) * REF_SIGMA_m);
    return h_m / 2.0 * (1.0 + erf(x)) + REF_SIGMA_m / sqrt(2.0 * REF_PI) * exp(-x * x);
}

/* Inverse of eq. 15 by bisection: p_c is strictly decreasing in h. */
static double ref_separation_m(double pressure_Pa)
{
    double lo = -60.0 * REF_SIGMA_m;
    double hi = 60.0 * REF_SIGMA_m;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (ref_contact_pressure_Pa(mid) > pressure_Pa) { lo = mid; } else { hi = mid; }
    }
    return 0.5 * (lo + hi);
}

/* The LUT against h_bar: `wetclutch lut` reports a max relative error of
 * 3.875e-5 for table1 (measured on a grid 100x denser than the table, with
 * the entries rounded to float). On top: the float Hermite evaluation
 * (~1e-6 relative) and the rounding of p_c to float (6e-8 times
 * |d ln h_bar / d ln p_c| <= 9 at the table's top: 5e-7). 5e-5 covers it. */
#define LUT_REL_TOL 5e-5

static void test_matches_golden_hbar(void **state)
{
    (void)state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    wc_test_worst_t worst = { 0.0, -1 };
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_torque); ++i) {
        const wc_golden_torque_t *g = &wc_golden_torque[i];
        const float pressure_Pa = (float)g->force_N / cal->friction_area_m2;  /* eq. 16, as the firmware does */
        const float hbar_m = wc_film_hbar_m(table1(), pressure_Pa);
        WC_CHECK_CLOSE("h_bar vs golden", i, hbar_m, g->hbar_um * 1e-6, LUT_REL_TOL, 0.0);
        wc_test_worst_update(&worst, wc_test_rel_error((double)hbar_m, g->hbar_um * 1e-6), (long)i);
    }
    wc_test_worst_print("h_bar vs golden", &worst, LUT_REL_TOL);
}

/* Dense sweep over the whole table against the double reference above:
 * 200 points per table interval, uniform in the separation h like the nodes. */
static void test_matches_eq9_eq15_everywhere(void **state)
{
    (void)state;
    const double h_min = ref_separation_m(REF_PRESSURE_MAX_Pa);
    const double h_max = REF_SEPARATION_MAX_m;
    const long n = 200L * (long)(WC_TABLE1_FILM_NODES - 1u);
    wc_test_worst_t worst = { 0.0, -1 };
    for (long k = 0; k <= n; ++k) {
        const double h = h_max + (h_min - h_max) * (double)k / (double)n;
        const float pressure_Pa = (float)ref_contact_pressure_Pa(h);
        const double expected = ref_film_m(h);
        const float hbar_m = wc_film_hbar_m(table1(), pressure_Pa);
        WC_CHECK_CLOSE("h_bar vs eq. 9/15", k, hbar_m, expected, LUT_REL_TOL, 0.0);
        wc_test_worst_update(&worst, wc_test_rel_error((double)hbar_m, expected), k);
    }
    wc_test_worst_print("h_bar vs eq. 9/15 (dense)", &worst, LUT_REL_TOL);
}

/* The reference numbers of DESIGN.md section 2, given to 4 digits:
 * h_bar at 903 / 1188 / 1613 N = 5.077 / 4.342 / 3.534 um. The document
 * truncates (the reference gives 3.53493 um at 1613 N, golden vectors), so
 * the tolerance is one unit of the last digit (0.001 um) plus the LUT error
 * (3.9e-5 x 5.1 um). */
static void test_design_reference_numbers(void **state)
{
    (void)state;
    const double force_N[] = { 903.0, 1188.0, 1613.0 };
    const double hbar_um[] = { 5.077, 4.342, 3.534 };
    for (size_t i = 0u; i < WC_TEST_COUNT(force_N); ++i) {
        const float pressure_Pa = (float)force_N[i] / wc_table1_calibration.friction_area_m2;
        WC_CHECK_CLOSE("DESIGN h_bar", i, 1e6 * (double)wc_film_hbar_m(table1(), pressure_Pa), hbar_um[i], 0.0,
                       0.001 + 3.9e-5 * 5.1);
    }
}

/* Nodes are hit exactly: t = 0 gives h00 = 1 and every other basis 0. */
static void test_nodes_exact(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    for (uint32_t i = 0u; i < t->length; ++i) {
        const float h = wc_film_hbar_m(t, t->pressure_Pa[i]);
        WC_CHECK(wc_test_same_float(h, t->hbar_m[i]), "node %u: %.9g != %.9g", (unsigned)i, (double)h,
                 (double)t->hbar_m[i]);
    }
}

/* Below the first node (an open clutch) the thickest film, above the last
 * the thinnest, NaN the open-clutch end: exactly the end entries. */
static void test_clamps_both_ends_and_nan(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    const float first = t->hbar_m[0];
    const float last = t->hbar_m[t->length - 1u];
    const float below[] = { nextafterf(t->pressure_Pa[0], 0.0f), 1.0f, 0.0f, -0.0f, -1.0f, -FLT_MAX, -INFINITY, NAN,
                            -NAN };
    for (size_t i = 0u; i < WC_TEST_COUNT(below); ++i) {
        const float h = wc_film_hbar_m(t, below[i]);
        WC_CHECK(wc_test_same_float(h, first), "p = %g: %.9g, expected the first node %.9g", (double)below[i],
                 (double)h, (double)first);
    }
    const float above[] = { t->pressure_Pa[t->length - 1u], nextafterf(t->pressure_Pa[t->length - 1u], INFINITY),
                            1e7f, 1e12f, FLT_MAX, INFINITY };
    for (size_t i = 0u; i < WC_TEST_COUNT(above); ++i) {
        const float h = wc_film_hbar_m(t, above[i]);
        WC_CHECK(wc_test_same_float(h, last), "p = %g: %.9g, expected the last node %.9g", (double)above[i],
                 (double)h, (double)last);
    }
    /* ...and the ends are the reference's clamps (model.film_domain):
     * h_bar(separation_max) and h_bar at p_c_max. */
    WC_CHECK_CLOSE("open-clutch film", 0, first, ref_film_m(REF_SEPARATION_MAX_m), 1e-6, 0.0);
    WC_CHECK_CLOSE("thinnest film", 0, last, ref_film_m(ref_separation_m(REF_PRESSURE_MAX_Pa)), 1e-6, 0.0);
}

/* h_bar falls as p_c rises: strictly, at 256 points per interval (the
 * smallest step changes h_bar by >= 1e-4 relative, far above float rounding). */
static void test_strictly_decreasing_in_pressure(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    float previous = wc_film_hbar_m(t, t->pressure_Pa[0]);
    long count = 0;
    for (uint32_t i = 0u; i + 1u < t->length; ++i) {
        const double p0 = (double)t->pressure_Pa[i];
        const double p1 = (double)t->pressure_Pa[i + 1u];
        for (int j = 1; j <= 256; ++j, ++count) {
            const float p = (float)(p0 + (p1 - p0) * (double)j / 256.0);
            const float h = wc_film_hbar_m(t, p);
            WC_CHECK(h < previous, "h_bar(%.9g Pa) = %.9g not below %.9g (interval %u)", (double)p, (double)h,
                     (double)previous, (unsigned)i);
            previous = h;
        }
    }
    WC_CHECK(count == 256L * (long)(t->length - 1u), "%ld points", count);
}

/* The interpolation itself, apart from the generated data: a cubic Hermite
 * with exact slopes reproduces a cubic exactly (here to float rounding),
 * on unequal intervals and with a 2-node table. */
static double cubic_hbar(double p) { const double u = 1.0 - p / 2000.0; return 1e-5 * u * u * u + 1e-6; }
static double cubic_slope(double p) { const double u = 1.0 - p / 2000.0; return -3e-5 / 2000.0 * u * u; }

static void test_hermite_reproduces_a_cubic(void **state)
{
    (void)state;
    static const double nodes[] = { 0.0, 150.0, 400.0, 1000.0, 1900.0 };
    float p[5];
    float h[5];
    float s[5];
    for (size_t i = 0u; i < 5u; ++i) {
        p[i] = (float)nodes[i];
        h[i] = (float)cubic_hbar(nodes[i]);
        s[i] = (float)cubic_slope(nodes[i]);
    }
    const uint32_t lengths[] = { 5u, 2u };
    for (size_t l = 0u; l < WC_TEST_COUNT(lengths); ++l) {
        wc_calibration_t cal = wc_table1_calibration;
        cal.film.pressure_Pa = p;
        cal.film.hbar_m = h;
        cal.film.slope_m_per_Pa = s;
        cal.film.length = lengths[l];
        /* the table must reach the contact pressure at the maximum current: a spring that leaves
         * half the last node's pressure to apply at 1000 mA */
        cal.return_spring_force_N = cal.vfs_gain_Pa_per_mA * cal.vfs_current_max_mA * cal.piston_area_m2 -
                                    0.5f * p[lengths[l] - 1u] * cal.friction_area_m2;
        assert_int_equal(wc_calibration_check(&cal), WC_CAL_OK);
        const double top = (double)p[lengths[l] - 1u];
        for (double q = 0.5; q < top; q += 3.7) {
            /* float data (6e-8 relative each) and ~20 float operations */
            WC_CHECK_CLOSE("cubic", (long)q, wc_film_hbar_m(&cal.film, (float)q), cubic_hbar((double)(float)q),
                           2e-6, 0.0);
        }
    }
}

/* The inverse solves on each segment's cubic in the power basis
 * (wc_film_segment_cubic); it must be the interpolant wc_film_hbar_m
 * evaluates, to float rounding: 32 points per segment, relative 1e-5
 * (a few float roundings of terms that partly cancel near the nodes). */
static void test_segment_cubic_is_the_interpolant(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    double worst = 0.0;
    for (uint32_t k = 0u; k + 1u < t->length; ++k) {
        float c[4];
        wc_film_segment_cubic(t, k, c);
        for (int j = 0; j <= 32; ++j) {
            const float u = (float)j / 32.0f;
            const float p = t->pressure_Pa[k] + u * (t->pressure_Pa[k + 1u] - t->pressure_Pa[k]);
            if (!(p < t->pressure_Pa[k + 1u])) { continue; }  /* the last point rounds onto the next node */
            const double power = (double)(c[0] + u * (c[1] + u * (c[2] + u * c[3])));
            const double hermite = (double)wc_film_hbar_m(t, p);
            const double rel = fabs(power - hermite) / hermite;
            if (rel > worst) { worst = rel; }
            WC_CHECK(rel <= 1e-5, "segment %u, t %g: power basis %.9g, Hermite %.9g", (unsigned)k, (double)u,
                     power, hermite);
        }
    }
    printf("    segment cubic vs wc_film_hbar_m: max relative difference %.3g (allowed 1e-5)\n", worst);
}

/* ---- Squeeze film (DESIGN 9) -------------------------------------------- */

/* wc_film_pressure_Pa inverts wc_film_hbar_m: on a dense grid of pressures over the table,
 * p(h_bar(p)) = p within 2e-5 relative (float rounding of h_bar, 6e-8, times |d ln p / d ln h_bar| <= ~10
 * at the open end, plus Newton's 3 steps), and 0 at and above the open film, the last node at the thinnest. */
static void test_pressure_inverts_hbar(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    double worst = 0.0;
    for (int i = 1; i < 4000; ++i) {
        const float p = t->pressure_Pa[0] + (t->pressure_Pa[t->length - 1u] - t->pressure_Pa[0]) * (float)i / 4000.0f;
        if (p < 1000.0f) { continue; }  /* the open end: p_c of a few Pa, 1e-6 N of force */
        const float back = wc_film_pressure_Pa(t, wc_film_hbar_m(t, p));
        const double rel = fabs((double)back / (double)p - 1.0);
        worst = (rel > worst) ? rel : worst;
    }
    printf("    wc_film_pressure_Pa(wc_film_hbar_m(p)): max relative error %.3g (allowed 2e-5)\n", worst);
    WC_CHECK(worst <= 2e-5, "inverse error %g", worst);
    assert_true(wc_test_same_float(wc_film_pressure_Pa(t, t->hbar_m[0]), 0.0f));
    assert_true(wc_test_same_float(wc_film_pressure_Pa(t, 1.0f), 0.0f));
    assert_true(wc_test_same_float(wc_film_pressure_Pa(t, NAN), 0.0f));
    assert_true(wc_test_same_float(wc_film_pressure_Pa(t, 0.0f), t->pressure_Pa[t->length - 1u]));
}

/* The model's squeeze-film damping per unit viscosity, 3 pi phi K / 2 in float, against K in double:
 * K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri) cancels by 1/140 for Table 1's pack, 1e-4 covers the float
 * form (wc_model.c). */
static void test_reynolds_factor(void **state)
{
    (void)state;
    wc_calibration_t cal = wc_table1_calibration;
    cal.film_squeeze_factor = 0.1f;
    wc_model_t model;
    assert_int_equal(wc_model_init(&model, &cal), WC_CAL_OK);
    const double ro = (double)cal.outer_radius_m;
    const double ri = (double)cal.inner_radius_m;
    const double k = ro * ro * ro * ro - ri * ri * ri * ri - (ro * ro - ri * ri) * (ro * ro - ri * ri) / log(ro / ri);
    WC_CHECK_CLOSE("film_damping_m4", 0, model.film_damping_m4, 1.5 * REF_PI * (double)cal.film_squeeze_factor * k,
                   1e-4, 0.0);
    printf("    K = %.6g m^4 (double), damping 3 pi phi K / 2 = %.6g m^4 at phi 0.1\n", k, (double)model.film_damping_m4);
}

/* The update is stable for every state and input (wc_film.h): from the open film and from the thinnest,
 * under no force, the nominal, and the largest a pack takes, for the stiffest and the slowest dampings of
 * the domain (phi 1e-4 .. 1, mu_v of Table 1's oil at 250 and -40 degC), h_bar moves monotonically towards
 * the settled film and never past it; where the film is fast it arrives. The stiffness of the stiffest case
 * (dt A_f |dp_c/dh_bar| h_bar^3 / D at the thinnest film, 250 degC, phi 1e-4) is printed: far above 1,
 * where an explicit step would diverge. */
static void test_advance_is_monotone_and_bounded(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    const float area = wc_table1_calibration.friction_area_m2;
    const float dt = wc_table1_calibration.control_period_s;
    const double k_m4 = 1.54e-7;   /* test_reynolds_factor's K, rounded */
    const float viscosities[] = { 6.0e-4f, 3.6f };           /* Table 1's mu_v at 250 and -40 degC, Pa s */
    const float factors[] = { 1e-4f, 0.1f, 1.0f };
    const float forces[] = { 0.0f, 100.0f, 1188.0f, 10000.0f };
    const float starts[] = { t->hbar_m[0], t->hbar_m[t->length - 1u], 5e-6f };
    double stiffest = 0.0;
    for (size_t v = 0u; v < WC_TEST_COUNT(viscosities); ++v) {
        for (size_t f = 0u; f < WC_TEST_COUNT(factors); ++f) {
            const float damping = (float)(1.5 * REF_PI * k_m4) * factors[f] * viscosities[v];
            for (size_t i = 0u; i < WC_TEST_COUNT(forces); ++i) {
                const float settled = wc_film_hbar_m(t, forces[i] / area);
                for (size_t s0 = 0u; s0 < WC_TEST_COUNT(starts); ++s0) {
                    float h = starts[s0];
                    const float toward = (settled < h) ? -1.0f : 1.0f;
                    for (int k = 0; k < 3000; ++k) {
                        const float next = wc_film_advance_m(t, area, h, forces[i], damping, dt);
                        WC_CHECK(isfinite(next) && (next >= t->hbar_m[t->length - 1u]) && (next <= t->hbar_m[0]),
                                 "h_bar %g outside the table", (double)next);
                        WC_CHECK(toward * (next - h) >= 0.0f, "moved away from the settled film: %g -> %g (settled %g)",
                                 (double)h, (double)next, (double)settled);
                        WC_CHECK(toward * (settled - next) >= 0.0f, "past the settled film: %g (settled %g)",
                                 (double)next, (double)settled);
                        h = next;
                    }
                    if ((viscosities[v] < 1e-3f) && (factors[f] < 1e-3f)) {  /* fast: settled within 3 s */
                        WC_CHECK_CLOSE("settled", (long)i, h, settled, 1e-4, 0.0);
                    }
                }
            }
            /* stiffness dt / tau = A_f |dp_c/dh_bar| h_bar^3 dt / D, largest over the table's segments */
            double stiff = 0.0;
            for (uint32_t n = 0u; n + 1u < t->length; ++n) {
                const double slope = (double)(t->pressure_Pa[n + 1u] - t->pressure_Pa[n]) /
                                     (double)(t->hbar_m[n] - t->hbar_m[n + 1u]);
                const double h3 = pow(0.5 * (double)(t->hbar_m[n] + t->hbar_m[n + 1u]), 3.0);
                const double here = (double)area * slope * h3 * (double)dt / (double)damping;
                stiff = (here > stiff) ? here : stiff;
            }
            stiffest = (stiff > stiffest) ? stiff : stiffest;
        }
    }
    printf("    stiffest film step in the domain: dt / tau = %.3g (explicit Euler diverges above 2)\n", stiffest);
    WC_CHECK(stiffest > 2.0, "the sweep does not reach a stiff case (%g)", stiffest);
}

/* Settling under a held force follows the Reynolds law: from the open film at 1188 N, Table 1's oil at
 * 40 degC and phi 0.1, the film closes within 0.5 s (the bench's 0.05..0.1 s equivalent time constant near
 * contact, paper 2.5), and never in one step (it is not the steady film). */
static void test_advance_settles_like_a_squeeze_film(void **state)
{
    (void)state;
    const wc_film_table_t *t = table1();
    const float area = wc_table1_calibration.friction_area_m2;
    const float damping = (float)(1.5 * REF_PI * 1.54e-7 * 0.1 * 0.0308);  /* mu_v(40 degC) = 30.8 mPa s */
    const float settled = wc_film_hbar_m(t, 1188.0f / area);
    float h = t->hbar_m[0];
    int steps_to_90 = -1;
    const float gap = t->hbar_m[0] - settled;
    for (int k = 0; k < 500; ++k) {
        h = wc_film_advance_m(t, area, h, 1188.0f, damping, 1e-3f);
        if ((steps_to_90 < 0) && (h - settled <= 0.1f * gap)) { steps_to_90 = k + 1; }
    }
    printf("    open film to 90 %% of the way to the settled film at 1188 N, 40 degC, phi 0.1: %d ms\n", steps_to_90);
    WC_CHECK((steps_to_90 > 5) && (steps_to_90 < 300), "%d steps", steps_to_90);
    WC_CHECK_CLOSE("settled after 0.5 s", 0, h, settled, 1e-3, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_golden_hbar),
        cmocka_unit_test(test_matches_eq9_eq15_everywhere),
        cmocka_unit_test(test_design_reference_numbers),
        cmocka_unit_test(test_nodes_exact),
        cmocka_unit_test(test_clamps_both_ends_and_nan),
        cmocka_unit_test(test_strictly_decreasing_in_pressure),
        cmocka_unit_test(test_hermite_reproduces_a_cubic),
        cmocka_unit_test(test_segment_cubic_is_the_interpolant),
        cmocka_unit_test(test_pressure_inverts_hbar),
        cmocka_unit_test(test_reynolds_factor),
        cmocka_unit_test(test_advance_is_monotone_and_bounded),
        cmocka_unit_test(test_advance_settles_like_a_squeeze_film),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
