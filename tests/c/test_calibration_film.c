/* Calibration check of the film table h_bar(p_c) (wc_calibration_check, via
 * wc_model_init and wc_clutch_init; DESIGN section 8 "Calibration validity"):
 * its arrays and length, the longest table, a strictly increasing pressure
 * axis, finite entries, the h_bar range, monotone data with slopes <= 0, the
 * Fritsch-Carlson bound on every interval and a positive interpolant.
 * The other calibration-check tests: test_calibration.c (listed variants,
 * sweep), test_calibration_fields.c (field by field); the shared part:
 * wc_test_calibration_harness.h. */
#include "wc_test_calibration_harness.h"

/* ------------------------------------------------------------------------ */
/* The film table                                                             */

static void test_film_table_missing_arrays_and_length(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    c.cal.film.pressure_Pa = NULL;
    expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.pressure_Pa NULL", 0.0);
    copy_table1(&c);
    c.cal.film.hbar_m = NULL;
    expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.hbar_m NULL", 0.0);
    copy_table1(&c);
    c.cal.film.slope_m_per_Pa = NULL;
    expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.slope_m_per_Pa NULL", 0.0);

    const uint32_t bad_length[] = { 0u, 1u, WC_FILM_MAX_NODES + 1u, UINT32_MAX };
    for (size_t k = 0u; k < WC_TEST_COUNT(bad_length); ++k) {
        copy_table1(&c);
        c.cal.film.length = bad_length[k];
        expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.length", (double)bad_length[k]);
    }
    /* A shorter table must still reach the contact pressure at the maximum current. */
    copy_table1(&c);
    c.cal.film.length = 2u;
    expect_code(&c.cal, WC_CAL_FILM_COVERAGE, "film.length 2 (11 Pa .. 18 Pa)", 2.0);
    c.pressure_Pa[1] = c.pressure_Pa[NODES - 1u];
    c.hbar_m[1] = c.hbar_m[NODES - 1u];
    c.slope_m_per_Pa[0] = 0.0f;
    c.slope_m_per_Pa[1] = 0.0f;
    expect_code(&c.cal, WC_CAL_OK, "film.length 2 (first and last node)", 2.0);
}

/* The longest table the library accepts, WC_FILM_MAX_NODES nodes. */
static void test_film_table_longest(void **state)
{
    (void)state;
    static float p[WC_FILM_MAX_NODES];
    static float h[WC_FILM_MAX_NODES];
    static float s[WC_FILM_MAX_NODES];
    for (uint32_t i = 0u; i < WC_FILM_MAX_NODES; ++i) {
        p[i] = 5000.0f * (float)(i + 1u);       /* up to 5.12 MPa */
        h[i] = 2e-5f - 1e-8f * (float)i;        /* slope -2e-12 m/Pa */
        s[i] = -2e-12f;
    }
    cal_copy_t c;
    copy_table1(&c);
    c.cal.film.pressure_Pa = p;
    c.cal.film.hbar_m = h;
    c.cal.film.slope_m_per_Pa = s;
    c.cal.film.length = WC_FILM_MAX_NODES;
    expect_code(&c.cal, WC_CAL_OK, "film.length", (double)WC_FILM_MAX_NODES);
    p[WC_FILM_MAX_NODES - 1u] = p[WC_FILM_MAX_NODES - 2u];
    expect_code(&c.cal, WC_CAL_FILM_AXIS_NOT_MONOTONE, "film.pressure_Pa last pair equal", 0.0);
}

static void test_film_axis_not_monotone(void **state)
{
    (void)state;
    const uint32_t at[] = { 1u, 10u, NODES - 1u };  /* pair (at-1, at) */
    for (size_t k = 0u; k < WC_TEST_COUNT(at); ++k) {
        const uint32_t i = at[k];
        cal_copy_t c;
        copy_table1(&c);
        c.pressure_Pa[i] = c.pressure_Pa[i - 1u];  /* equal: not strictly increasing */
        expect_code(&c.cal, WC_CAL_FILM_AXIS_NOT_MONOTONE, "film.pressure_Pa equal pair", (double)i);
        copy_table1(&c);
        const float tmp = c.pressure_Pa[i];
        c.pressure_Pa[i] = c.pressure_Pa[i - 1u];
        c.pressure_Pa[i - 1u] = tmp;  /* swapped */
        expect_code(&c.cal, WC_CAL_FILM_AXIS_NOT_MONOTONE, "film.pressure_Pa swapped pair", (double)i);
    }
}

static void test_film_entries_non_finite(void **state)
{
    (void)state;
    const float non_finite[] = { NAN, INFINITY, -INFINITY };
    const uint32_t at[] = { 0u, 31u, NODES - 1u };
    for (size_t k = 0u; k < WC_TEST_COUNT(at); ++k) {
        const uint32_t i = at[k];
        for (size_t v = 0u; v < WC_TEST_COUNT(non_finite); ++v) {
            cal_copy_t c;
            copy_table1(&c);
            c.pressure_Pa[i] = non_finite[v];
            expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.pressure_Pa non-finite", (double)i);
            copy_table1(&c);
            c.hbar_m[i] = non_finite[v];
            expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.hbar_m non-finite", (double)i);
            copy_table1(&c);
            c.slope_m_per_Pa[i] = non_finite[v];
            expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.slope_m_per_Pa non-finite", (double)i);
        }
    }
}

/* h_bar in [1e-9, 1e-3] m at every node, p_0 >= 0. */
static void test_film_range(void **state)
{
    (void)state;
    const float bad_hbar[] = { 0.0f, -0.0f, -1e-6f, -3.7e-9f, 9.9e-10f, 1.01e-3f, 1.0f };
    const uint32_t at[] = { 0u, 31u, NODES - 1u };
    for (size_t k = 0u; k < WC_TEST_COUNT(at); ++k) {
        for (size_t v = 0u; v < WC_TEST_COUNT(bad_hbar); ++v) {
            cal_copy_t c;
            copy_table1(&c);
            c.hbar_m[at[k]] = bad_hbar[v];
            expect_code(&c.cal, WC_CAL_FILM_RANGE, "film.hbar_m", (double)bad_hbar[v]);
        }
    }
    cal_copy_t c;
    copy_table1(&c);
    c.pressure_Pa[0] = -1.0f;  /* a contact pressure is not negative */
    expect_code(&c.cal, WC_CAL_FILM_RANGE, "film.pressure_Pa[0] negative", -1.0);
    copy_table1(&c);
    const float first_Pa = c.pressure_Pa[0];
    for (uint32_t i = 0u; i < NODES; ++i) {
        c.pressure_Pa[i] -= first_Pa;  /* the axis shifted to start at 0: same intervals */
    }
    expect_code(&c.cal, WC_CAL_OK, "film.pressure_Pa[0] zero", 0.0);
    /* the whole table scaled: the thinnest node leaves the range */
    copy_table1(&c);
    for (uint32_t i = 0u; i < NODES; ++i) {
        c.hbar_m[i] *= 0.1f;
        c.slope_m_per_Pa[i] *= 0.1f;
    }
    expect_code(&c.cal, WC_CAL_FILM_RANGE, "film.hbar_m x 0.1 (last node 0.7 nm)", 0.1);
    copy_table1(&c);
    for (uint32_t i = 0u; i < NODES; ++i) {
        c.hbar_m[i] *= 50.0f;
        c.slope_m_per_Pa[i] *= 50.0f;
    }
    expect_code(&c.cal, WC_CAL_FILM_RANGE, "film.hbar_m x 50 (first node 1.2 mm)", 50.0);
    for (uint32_t i = 0u; i < NODES; ++i) {
        c.hbar_m[i] *= 0.8f;
        c.slope_m_per_Pa[i] *= 0.8f;
    }
    expect_code(&c.cal, WC_CAL_OK, "film.hbar_m x 40 (first node 0.96 mm)", 40.0);
}

/* Slopes <= 0, data strictly decreasing, Fritsch-Carlson on every interval. */
static void test_film_not_monotone(void **state)
{
    (void)state;
    const uint32_t at[] = { 0u, 31u, NODES - 1u };
    for (size_t k = 0u; k < WC_TEST_COUNT(at); ++k) {
        const uint32_t i = at[k];
        cal_copy_t c;
        copy_table1(&c);
        c.slope_m_per_Pa[i] = 1e-20f;  /* h_bar falls as p_c rises */
        expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "film.slope_m_per_Pa positive", (double)i);
        copy_table1(&c);
        c.slope_m_per_Pa[i] = 0.0f;    /* flat at a node: monotone, accepted */
        expect_code(&c.cal, WC_CAL_OK, "film.slope_m_per_Pa zero", (double)i);
        copy_table1(&c);
        c.slope_m_per_Pa[i] *= 100.0f;  /* far steeper than the data: the cubic overshoots */
        expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "film.slope_m_per_Pa x 100", (double)i);
    }
    for (uint32_t i = 1u; i < NODES; i += 21u) {
        cal_copy_t c;
        copy_table1(&c);
        c.hbar_m[i] = c.hbar_m[i - 1u];  /* flat data */
        expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "film.hbar_m equal pair", (double)i);
        copy_table1(&c);
        c.hbar_m[i] = 1.01f * c.hbar_m[i - 1u];  /* rising */
        expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "film.hbar_m rising", (double)i);
    }
}

/* alpha^2 + beta^2 <= 9 is the bound: alpha = 3 accepted, a little more rejected. */
static void test_film_fritsch_carlson_bound(void **state)
{
    (void)state;
    float p[2] = { 0.0f, 4.2e6f };
    float h[2] = { 2e-5f, 1e-5f };
    float s[2] = { 0.0f, 0.0f };
    const float delta = (h[1] - h[0]) / (p[1] - p[0]);
    cal_copy_t c;
    copy_table1(&c);
    c.cal.film.pressure_Pa = p;
    c.cal.film.hbar_m = h;
    c.cal.film.slope_m_per_Pa = s;
    c.cal.film.length = 2u;
    /* 2.9999: the bound itself, less the float rounding of s / delta */
    const float alpha_beta[][2] = { { 2.9999f, 0.0f }, { 0.0f, 2.9999f }, { 2.1f, 2.1f }, { 1.0f, 1.0f } };
    for (size_t k = 0u; k < WC_TEST_COUNT(alpha_beta); ++k) {
        s[0] = alpha_beta[k][0] * delta;
        s[1] = alpha_beta[k][1] * delta;
        expect_code(&c.cal, WC_CAL_OK, "alpha^2 + beta^2 <= 9", (double)k);
    }
    const float outside[][2] = { { 3.01f, 0.0f }, { 0.0f, 3.01f }, { 2.2f, 2.1f }, { 10.0f, 10.0f } };
    for (size_t k = 0u; k < WC_TEST_COUNT(outside); ++k) {
        s[0] = outside[k][0] * delta;
        s[1] = outside[k][1] * delta;
        expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "alpha^2 + beta^2 > 9", (double)k);
    }
}

/* The film example: a node slope that the old check accepted (<= 0)
 * makes the interpolant negative (h_bar -3.7e-9 m class); now rejected. And
 * the accepted extreme: nodes 1 mm and 1 nm on one interval with alpha = 3,
 * where float rounding is worst: the interpolant stays above 0.5 nm. */
static void test_film_interpolant_positive(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    const uint32_t k = NODES - 2u;
    c.slope_m_per_Pa[k] *= 40.0f;  /* steep at the thin end */
    float lowest = INFINITY;
    for (int j = 0; j <= 1000; ++j) {
        const float q = c.pressure_Pa[k] + (c.pressure_Pa[k + 1u] - c.pressure_Pa[k]) * (float)j / 1000.0f;
        const float hb = wc_film_hbar_m(&c.cal.film, q);
        lowest = (hb < lowest) ? hb : lowest;
    }
    print_message("    steep slope at node %u: interpolant down to %.3g m\n", (unsigned)k, (double)lowest);
    WC_CHECK(!(lowest > 0.0f), "the example should make h_bar <= 0 (got %g)", (double)lowest);
    expect_code(&c.cal, WC_CAL_FILM_NOT_MONOTONE, "film.slope_m_per_Pa x 40 at the thin end", (double)k);

    const float scenarios[][3] = {
        /* hbar_0, alpha, beta; hbar_1 = 1e-9 */
        { 1e-3f, 0.0f, 0.0f }, { 1e-3f, 3.0f, 0.0f }, { 1e-3f, 0.0f, 3.0f }, { 1e-3f, 2.12f, 2.12f },
        { 1e-4f, 3.0f, 0.0f }, { 1e-5f, 2.9f, 0.7f },
    };
    const float widths[] = { 1e-3f, 1.0f, 3.7e6f };
    for (size_t n = 0u; n < WC_TEST_COUNT(scenarios); ++n) {
        for (size_t w = 0u; w < WC_TEST_COUNT(widths); ++w) {
            float p[2] = { 0.0f, widths[w] };
            float h[2] = { scenarios[n][0], WC_CAL_LIMIT_FILM_HBAR_MIN_m };
            const float delta = (h[1] - h[0]) / (p[1] - p[0]);
            float s[2] = { scenarios[n][1] * delta, scenarios[n][2] * delta };
            const wc_film_table_t film = { p, h, s, 2u };
            float low = INFINITY;
            /* every float t in [0.99, 1) and a coarse sweep of the rest */
            for (float t = 0.99f; t < 1.0f; t = nextafterf(t, 2.0f)) {
                const float hb = wc_film_hbar_m(&film, t * widths[w]);
                low = (hb < low) ? hb : low;
            }
            for (int j = 0; j <= 4096; ++j) {
                const float hb = wc_film_hbar_m(&film, widths[w] * (float)j / 4096.0f);
                low = (hb < low) ? hb : low;
            }
            WC_CHECK(low >= 0.5f * WC_CAL_LIMIT_FILM_HBAR_MIN_m, "scenario %u width %g: h_bar down to %g",
                     (unsigned)n, (double)widths[w], (double)low);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_film_table_missing_arrays_and_length),
        cmocka_unit_test(test_film_table_longest),
        cmocka_unit_test(test_film_axis_not_monotone),
        cmocka_unit_test(test_film_entries_non_finite),
        cmocka_unit_test(test_film_range),
        cmocka_unit_test(test_film_not_monotone),
        cmocka_unit_test(test_film_fritsch_carlson_bound),
        cmocka_unit_test(test_film_interpolant_positive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
