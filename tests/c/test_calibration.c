/* Calibration check (wc_calibration_check, via wc_model_init and wc_clutch_init):
 * every field is rejected with the error code that names it. */
#include "wc_test_support.h"

#include <float.h>

#include "wc_table1_calibration.h"

typedef enum {
    RULE_POSITIVE,     /* finite and > 0 */
    RULE_NONNEGATIVE,  /* finite and >= 0 */
    RULE_FINITE        /* any finite value */
} rule_t;

typedef struct {
    const char *name;  /* field name, also what wc_cal_error_name must say */
    size_t offset;
    rule_t rule;
    wc_cal_error_t code;
} float_field_t;

#define FIELD(member, rule, code) { #member, offsetof(wc_calibration_t, member), rule, code }

/* Every float field of wc_calibration_t, in declaration order. */
static const float_field_t float_fields[] = {
    FIELD(outer_radius_m, RULE_POSITIVE, WC_CAL_OUTER_RADIUS),
    FIELD(inner_radius_m, RULE_POSITIVE, WC_CAL_INNER_RADIUS),
    FIELD(friction_area_m2, RULE_POSITIVE, WC_CAL_FRICTION_AREA),
    FIELD(piston_area_m2, RULE_POSITIVE, WC_CAL_PISTON_AREA),
    FIELD(oil_conductance_W_per_K, RULE_POSITIVE, WC_CAL_OIL_CONDUCTANCE),
    FIELD(housing_conductance_W_per_K, RULE_NONNEGATIVE, WC_CAL_HOUSING_CONDUCTANCE),
    FIELD(heat_capacity_J_per_K, RULE_POSITIVE, WC_CAL_HEAT_CAPACITY),
    FIELD(viscosity_a1_Pa_s, RULE_NONNEGATIVE, WC_CAL_VISCOSITY_A1),
    FIELD(viscosity_b1_per_K, RULE_FINITE, WC_CAL_VISCOSITY_B1),
    FIELD(viscosity_a2_Pa_s, RULE_NONNEGATIVE, WC_CAL_VISCOSITY_A2),
    FIELD(viscosity_b2_per_K, RULE_FINITE, WC_CAL_VISCOSITY_B2),
    FIELD(mu1, RULE_POSITIVE, WC_CAL_MU1),
    FIELD(mu2, RULE_POSITIVE, WC_CAL_MU2),
    FIELD(mu3, RULE_FINITE, WC_CAL_MU3),
    FIELD(stribeck_speed_m_s, RULE_POSITIVE, WC_CAL_STRIBECK_SPEED),
    FIELD(theta1_degC, RULE_FINITE, WC_CAL_THETA1),
    FIELD(theta2_K, RULE_POSITIVE, WC_CAL_THETA2),
    FIELD(vfs_gain_Pa_per_mA, RULE_POSITIVE, WC_CAL_VFS_GAIN),
    FIELD(vfs_time_constant_s, RULE_POSITIVE, WC_CAL_VFS_TIME_CONSTANT),
    FIELD(return_spring_force_N, RULE_NONNEGATIVE, WC_CAL_RETURN_SPRING_FORCE),
    FIELD(vfs_current_min_mA, RULE_NONNEGATIVE, WC_CAL_VFS_CURRENT_MIN),
    FIELD(vfs_current_max_mA, RULE_POSITIVE, WC_CAL_VFS_CURRENT_MAX),
    FIELD(control_period_s, RULE_POSITIVE, WC_CAL_CONTROL_PERIOD),
};

#define NODES WC_TABLE1_FILM_NODES

/* A writable copy of table1, film arrays included. */
typedef struct {
    wc_calibration_t cal;
    float pressure_Pa[NODES];
    float hbar_m[NODES];
    float slope_m_per_Pa[NODES];
} cal_copy_t;

static void copy_table1(cal_copy_t *c)
{
    c->cal = wc_table1_calibration;
    memcpy(c->pressure_Pa, wc_table1_film_pressure_Pa, sizeof c->pressure_Pa);
    memcpy(c->hbar_m, wc_table1_film_hbar_m, sizeof c->hbar_m);
    memcpy(c->slope_m_per_Pa, wc_table1_film_slope_m_per_Pa, sizeof c->slope_m_per_Pa);
    c->cal.film.pressure_Pa = c->pressure_Pa;
    c->cal.film.hbar_m = c->hbar_m;
    c->cal.film.slope_m_per_Pa = c->slope_m_per_Pa;
    c->cal.film.length = NODES;
}

static float *field_ptr(wc_calibration_t *cal, size_t offset)
{
    return (float *)(void *)((unsigned char *)cal + offset);
}

/* The check, wc_model_init and wc_clutch_init must all give `expected`; on an
 * error the model is left unusable (cal == NULL). */
static void expect_code(const wc_calibration_t *cal, wc_cal_error_t expected, const char *what, double value)
{
    const wc_cal_error_t check = wc_calibration_check(cal);
    WC_CHECK(check == expected, "%s = %g: wc_calibration_check gave %d (%s), expected %d (%s)", what, value,
             (int)check, wc_cal_error_name(check), (int)expected, wc_cal_error_name(expected));

    wc_model_t model;
    memset(&model, 0xA5, sizeof model);
    const wc_cal_error_t model_code = wc_model_init(&model, cal);
    WC_CHECK(model_code == expected, "%s = %g: wc_model_init gave %d, expected %d", what, value, (int)model_code,
             (int)expected);

    wc_clutch_t clutch;
    memset(&clutch, 0xA5, sizeof clutch);
    const wc_cal_error_t clutch_code = wc_clutch_init(&clutch, cal, 40.0f);
    WC_CHECK(clutch_code == expected, "%s = %g: wc_clutch_init gave %d, expected %d", what, value,
             (int)clutch_code, (int)expected);
    if (expected == WC_CAL_OK) {
        WC_CHECK(model.cal == cal, "%s: model not bound to its calibration", what);
        WC_CHECK(clutch.model.cal == cal, "%s: clutch not bound to its calibration", what);
    } else {
        WC_CHECK(model.cal == NULL, "%s = %g: model left usable after error", what, value);
        WC_CHECK(clutch.model.cal == NULL, "%s = %g: clutch left usable after error", what, value);
    }
}

static void test_table1_is_valid(void **state)
{
    (void)state;
    expect_code(&wc_table1_calibration, WC_CAL_OK, "table1", 0.0);
    cal_copy_t c;
    copy_table1(&c);
    expect_code(&c.cal, WC_CAL_OK, "table1 copy", 0.0);
}

static void test_null_arguments(void **state)
{
    (void)state;
    assert_int_equal(wc_calibration_check(NULL), WC_CAL_NULL);
    wc_model_t model;
    assert_int_equal(wc_model_init(&model, NULL), WC_CAL_NULL);
    assert_null(model.cal);
    assert_int_equal(wc_model_init(NULL, &wc_table1_calibration), WC_CAL_NULL);
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, NULL, 40.0f), WC_CAL_NULL);
    assert_int_equal(wc_clutch_init(NULL, &wc_table1_calibration, 40.0f), WC_CAL_NULL);
}

/* The table above must cover every float field and every field code once. */
static void test_field_table_is_complete(void **state)
{
    (void)state;
    const size_t n = WC_TEST_COUNT(float_fields);
    /* 24 scalar fields in wc_calibration_t: 23 float + friction_pairs (uint32). */
    assert_int_equal(n, 23);
    for (size_t i = 0u; i < n; ++i) {
        for (size_t j = i + 1u; j < n; ++j) {
            WC_CHECK(float_fields[i].offset != float_fields[j].offset, "%s twice", float_fields[i].name);
            WC_CHECK(float_fields[i].code != float_fields[j].code, "code of %s twice", float_fields[i].name);
        }
        WC_CHECK(float_fields[i].offset + sizeof(float) <= offsetof(wc_calibration_t, film), "%s",
                 float_fields[i].name);
    }
    /* Float fields + friction_pairs + the film table fill the struct up to film. */
    assert_int_equal(n * sizeof(float) + sizeof(uint32_t), offsetof(wc_calibration_t, film));
}

static void test_every_float_field_rejects_invalid_values(void **state)
{
    (void)state;
    const float non_finite[] = { NAN, INFINITY, -INFINITY };
    const float non_positive[] = { 0.0f, -0.0f, -FLT_MIN, -1.0f, -FLT_MAX };
    const float negative[] = { -FLT_MIN, -1e-30f, -1.0f, -FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(float_fields); ++i) {
        const float_field_t *f = &float_fields[i];
        cal_copy_t c;
        for (size_t k = 0u; k < WC_TEST_COUNT(non_finite); ++k) {
            copy_table1(&c);
            *field_ptr(&c.cal, f->offset) = non_finite[k];
            expect_code(&c.cal, f->code, f->name, (double)non_finite[k]);
        }
        if (f->rule == RULE_POSITIVE) {
            for (size_t k = 0u; k < WC_TEST_COUNT(non_positive); ++k) {
                copy_table1(&c);
                *field_ptr(&c.cal, f->offset) = non_positive[k];
                expect_code(&c.cal, f->code, f->name, (double)non_positive[k]);
            }
        }
        if (f->rule == RULE_NONNEGATIVE) {
            for (size_t k = 0u; k < WC_TEST_COUNT(negative); ++k) {
                copy_table1(&c);
                *field_ptr(&c.cal, f->offset) = negative[k];
                expect_code(&c.cal, f->code, f->name, (double)negative[k]);
            }
        }
        /* The error's name is the field's name, for the log. */
        assert_string_equal(wc_cal_error_name(f->code), f->name);
    }
}

/* The check must not over-reject: the boundary of each rule is valid. */
static void test_boundary_values_are_accepted(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(float_fields); ++i) {
        const float_field_t *f = &float_fields[i];
        cal_copy_t c;
        copy_table1(&c);
        float *value = field_ptr(&c.cal, f->offset);
        switch (f->rule) {
        case RULE_NONNEGATIVE:
            if (f->code == WC_CAL_VFS_CURRENT_MIN) {
                *value = 0.5f * c.cal.vfs_current_max_mA;  /* any value below the maximum */
                expect_code(&c.cal, WC_CAL_OK, f->name, (double)*value);
            }
            *value = 0.0f;
            expect_code(&c.cal, WC_CAL_OK, f->name, 0.0);
            break;
        case RULE_FINITE:
            *value = -(*value) - 1.0f;  /* sign flipped, and not zero */
            expect_code(&c.cal, WC_CAL_OK, f->name, (double)*value);
            *value = 0.0f;
            expect_code(&c.cal, WC_CAL_OK, f->name, 0.0);
            break;
        case RULE_POSITIVE:
            if ((f->code == WC_CAL_OUTER_RADIUS) || (f->code == WC_CAL_VFS_CURRENT_MAX)) {
                *value *= 2.0f;  /* must stay above inner radius / minimum current */
            } else if (f->code == WC_CAL_INNER_RADIUS) {
                *value = FLT_MIN;  /* the smallest positive normal, below the outer radius */
            } else {
                *value = 0.5f * (*value);
            }
            expect_code(&c.cal, WC_CAL_OK, f->name, (double)*value);
            break;
        default:
            fail();
        }
    }
}

static void test_inner_radius_not_below_outer(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    c.cal.inner_radius_m = c.cal.outer_radius_m;
    expect_code(&c.cal, WC_CAL_INNER_RADIUS, "inner_radius_m == outer", (double)c.cal.inner_radius_m);
    c.cal.inner_radius_m = nextafterf(c.cal.outer_radius_m, INFINITY);
    expect_code(&c.cal, WC_CAL_INNER_RADIUS, "inner_radius_m just above outer", (double)c.cal.inner_radius_m);
    c.cal.inner_radius_m = 2.0f * c.cal.outer_radius_m;
    expect_code(&c.cal, WC_CAL_INNER_RADIUS, "inner_radius_m > outer", (double)c.cal.inner_radius_m);
    c.cal.inner_radius_m = nextafterf(c.cal.outer_radius_m, 0.0f);
    expect_code(&c.cal, WC_CAL_OK, "inner_radius_m just below outer", (double)c.cal.inner_radius_m);
}

static void test_current_max_not_above_min(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    c.cal.vfs_current_min_mA = 200.0f;
    c.cal.vfs_current_max_mA = 200.0f;
    expect_code(&c.cal, WC_CAL_VFS_CURRENT_MAX, "vfs_current_max_mA == min", 200.0);
    c.cal.vfs_current_max_mA = 100.0f;
    expect_code(&c.cal, WC_CAL_VFS_CURRENT_MAX, "vfs_current_max_mA < min", 100.0);
    c.cal.vfs_current_max_mA = nextafterf(200.0f, INFINITY);
    expect_code(&c.cal, WC_CAL_OK, "vfs_current_max_mA just above min", (double)c.cal.vfs_current_max_mA);
}

/* The inverse's iteration bound covers forces up to WC_FORCE_MAX_N: a piston
 * force at the maximum current beyond it is rejected, naming the current. */
static void test_force_at_max_current_within_bound(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    const float force_limit_mA = WC_FORCE_MAX_N / (c.cal.vfs_gain_Pa_per_mA * c.cal.piston_area_m2);
    c.cal.vfs_current_max_mA = 1.01f * force_limit_mA;
    expect_code(&c.cal, WC_CAL_VFS_CURRENT_MAX, "piston force above WC_FORCE_MAX_N", (double)c.cal.vfs_current_max_mA);
    c.cal.vfs_current_max_mA = 0.99f * force_limit_mA;
    expect_code(&c.cal, WC_CAL_OK, "piston force just below WC_FORCE_MAX_N", (double)c.cal.vfs_current_max_mA);
}

static void test_friction_pairs(void **state)
{
    (void)state;
    const uint32_t bad[] = { 0u, 65u, UINT32_MAX };
    for (size_t k = 0u; k < WC_TEST_COUNT(bad); ++k) {
        cal_copy_t c;
        copy_table1(&c);
        c.cal.friction_pairs = bad[k];
        expect_code(&c.cal, WC_CAL_FRICTION_PAIRS, "friction_pairs", (double)bad[k]);
    }
    const uint32_t good[] = { 1u, 64u };
    for (size_t k = 0u; k < WC_TEST_COUNT(good); ++k) {
        cal_copy_t c;
        copy_table1(&c);
        c.cal.friction_pairs = good[k];
        expect_code(&c.cal, WC_CAL_OK, "friction_pairs", (double)good[k]);
    }
    assert_string_equal(wc_cal_error_name(WC_CAL_FRICTION_PAIRS), "friction_pairs");
}

/* With several bad fields the first one in declaration order is reported. */
static void test_first_failing_field_is_reported(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    c.cal.control_period_s = NAN;
    c.cal.mu2 = -1.0f;
    c.cal.film.length = 1u;
    expect_code(&c.cal, WC_CAL_MU2, "mu2 and control_period_s and film", -1.0);
    c.cal.outer_radius_m = 0.0f;
    expect_code(&c.cal, WC_CAL_OUTER_RADIUS, "outer_radius_m first", 0.0);
}

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
    copy_table1(&c);
    c.cal.film.length = 2u;  /* the shortest table */
    expect_code(&c.cal, WC_CAL_OK, "film.length", 2.0);
}

/* The longest table the library accepts, WC_FILM_MAX_NODES nodes. */
static void test_film_table_longest(void **state)
{
    (void)state;
    static float p[WC_FILM_MAX_NODES];
    static float h[WC_FILM_MAX_NODES];
    static float s[WC_FILM_MAX_NODES];
    for (uint32_t i = 0u; i < WC_FILM_MAX_NODES; ++i) {
        p[i] = 1000.0f * (float)(i + 1u);
        h[i] = 2e-5f - 1e-8f * (float)i;
        s[i] = -1e-11f;
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
        copy_table1(&c);
        c.pressure_Pa[i] = nextafterf(c.pressure_Pa[i - 1u], INFINITY);  /* one ulp above: still valid */
        if (i + 1u < NODES) {
            WC_CHECK(c.pressure_Pa[i] < c.pressure_Pa[i + 1u], "test table setup at %u", (unsigned)i);
        }
        expect_code(&c.cal, WC_CAL_OK, "film.pressure_Pa one ulp apart", (double)i);
    }
}

static void test_film_entries_non_finite_or_unphysical(void **state)
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
        cal_copy_t c;
        copy_table1(&c);
        c.hbar_m[i] = 0.0f;  /* a film has a positive thickness */
        expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.hbar_m zero", (double)i);
        copy_table1(&c);
        c.hbar_m[i] = -1e-6f;
        expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.hbar_m negative", (double)i);
        copy_table1(&c);
        c.slope_m_per_Pa[i] = 1e-12f;  /* h_bar falls as p_c rises */
        expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.slope_m_per_Pa positive", (double)i);
    }
    cal_copy_t c;
    copy_table1(&c);
    c.pressure_Pa[0] = -1.0f;  /* a contact pressure is not negative */
    expect_code(&c.cal, WC_CAL_FILM_TABLE, "film.pressure_Pa negative", -1.0);
}

static void test_error_names(void **state)
{
    (void)state;
    const char *names[WC_CAL_FILM_AXIS_NOT_MONOTONE + 1];
    for (int e = WC_CAL_OK; e <= (int)WC_CAL_FILM_AXIS_NOT_MONOTONE; ++e) {
        names[e] = wc_cal_error_name((wc_cal_error_t)e);
        assert_non_null(names[e]);
        WC_CHECK(strlen(names[e]) > 0u, "empty name for %d", e);
        WC_CHECK(strcmp(names[e], "unknown") != 0, "code %d has no name", e);
        for (int k = WC_CAL_OK; k < e; ++k) {
            WC_CHECK(strcmp(names[k], names[e]) != 0, "codes %d and %d share the name %s", k, e, names[e]);
        }
    }
    assert_string_equal(wc_cal_error_name((wc_cal_error_t)(WC_CAL_FILM_AXIS_NOT_MONOTONE + 1)), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table1_is_valid),
        cmocka_unit_test(test_null_arguments),
        cmocka_unit_test(test_field_table_is_complete),
        cmocka_unit_test(test_every_float_field_rejects_invalid_values),
        cmocka_unit_test(test_boundary_values_are_accepted),
        cmocka_unit_test(test_inner_radius_not_below_outer),
        cmocka_unit_test(test_current_max_not_above_min),
        cmocka_unit_test(test_force_at_max_current_within_bound),
        cmocka_unit_test(test_friction_pairs),
        cmocka_unit_test(test_first_failing_field_is_reported),
        cmocka_unit_test(test_film_table_missing_arrays_and_length),
        cmocka_unit_test(test_film_table_longest),
        cmocka_unit_test(test_film_axis_not_monotone),
        cmocka_unit_test(test_film_entries_non_finite_or_unphysical),
        cmocka_unit_test(test_error_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
