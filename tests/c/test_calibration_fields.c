/* Calibration check (wc_calibration_check, via wc_model_init and wc_clutch_init),
 * DESIGN section 8 "Calibration validity", field by field:
 *  - table1 passes, NULL is refused, the field table covers every float
 *    field and every field code once, NaN and +-inf in any field give that
 *    field's code;
 *  - the limits are inclusive where the header says so;
 *  - the count fields and the relations between fields, each with its code,
 *    and with several bad fields the first one in declaration order;
 *  - every error code has its own name.
 * The listed variants and the sweep: test_calibration.c; the film table:
 * test_calibration_film.c; the shared part: wc_test_calibration_harness.h. */
#include "wc_test_calibration_harness.h"

#include <float.h>

/* ------------------------------------------------------------------------ */
/* The float fields                                                          */

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
    /* 32 scalar fields in wc_calibration_t: 30 float + friction_pairs and lock_dwell_periods (uint32). */
    assert_int_equal(n, 30);
    for (size_t i = 0u; i < n; ++i) {
        for (size_t j = i + 1u; j < n; ++j) {
            WC_CHECK(float_fields[i].offset != float_fields[j].offset, "%s twice", float_fields[i].name);
            WC_CHECK(float_fields[i].code != float_fields[j].code, "code of %s twice", float_fields[i].name);
        }
        WC_CHECK(float_fields[i].offset + sizeof(float) <= offsetof(wc_calibration_t, film), "%s",
                 float_fields[i].name);
    }
    /* Float fields, friction_pairs and lock_dwell_periods fill the struct up to film (after padding to
     * the pointers' alignment); the open drag's two floats come after lock_dwell_periods. */
    assert_int_equal((n - 2u) * sizeof(float) + sizeof(uint32_t), offsetof(wc_calibration_t, lock_dwell_periods));
    assert_int_equal(offsetof(wc_calibration_t, open_aeration_speed_rad_s) + sizeof(float),
                     (n + 2u) * sizeof(float));
    assert_true(offsetof(wc_calibration_t, film) - (n + 2u) * sizeof(float) < sizeof(void *));
}

/* NaN and +-Inf in any field: that field's code (every rule rejects them). */
static void test_every_float_field_rejects_non_finite(void **state)
{
    (void)state;
    const float non_finite[] = { NAN, -NAN, INFINITY, -INFINITY };
    for (size_t i = 0u; i < WC_TEST_COUNT(float_fields); ++i) {
        const float_field_t *f = &float_fields[i];
        for (size_t k = 0u; k < WC_TEST_COUNT(non_finite); ++k) {
            cal_copy_t c;
            copy_table1(&c);
            *field_ptr(&c.cal, f->offset) = non_finite[k];
            expect_code(&c.cal, f->code, f->name, (double)non_finite[k]);
        }
        /* The error's name is the field's name, for the log. */
        assert_string_equal(wc_cal_error_name(f->code), f->name);
    }
}

/* The limits are inclusive where the header says so: at the limit accepted,
 * one float beyond it rejected. */
typedef struct {
    const char *name;
    size_t offset;
    float limit;
    float beyond;     /* direction: +INFINITY or -INFINITY */
    wc_cal_error_t code;
} limit_t;

#define LIMIT(member, limit, beyond, code) { #member, offsetof(wc_calibration_t, member), limit, beyond, code }

static void test_limits_are_inclusive(void **state)
{
    (void)state;
    /* each on a table1 copy with the other fields chosen so that only this limit binds */
    const limit_t limits[] = {
        LIMIT(outer_radius_m, WC_CAL_LIMIT_RADIUS_MAX_m, INFINITY, WC_CAL_OUTER_RADIUS),
        LIMIT(piston_area_m2, WC_CAL_LIMIT_PISTON_AREA_MAX_m2, INFINITY, WC_CAL_PISTON_AREA),
        LIMIT(oil_conductance_W_per_K, WC_CAL_LIMIT_CONDUCTANCE_MAX_W_per_K, INFINITY, WC_CAL_OIL_CONDUCTANCE),
        LIMIT(housing_conductance_W_per_K, WC_CAL_LIMIT_CONDUCTANCE_MAX_W_per_K, INFINITY,
              WC_CAL_HOUSING_CONDUCTANCE),
        LIMIT(housing_conductance_W_per_K, 0.0f, -INFINITY, WC_CAL_HOUSING_CONDUCTANCE),
        LIMIT(heat_capacity_J_per_K, WC_CAL_LIMIT_HEAT_CAPACITY_MAX_J_per_K, INFINITY, WC_CAL_HEAT_CAPACITY),
        LIMIT(viscosity_b1_per_K, WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K, INFINITY, WC_CAL_VISCOSITY_B1),
        LIMIT(viscosity_b1_per_K, -WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K, -INFINITY, WC_CAL_VISCOSITY_B1),
        LIMIT(viscosity_b2_per_K, WC_CAL_LIMIT_VISCOSITY_EXPONENT_MAX_per_K, INFINITY, WC_CAL_VISCOSITY_B2),
        LIMIT(viscosity_a1_Pa_s, 0.0f, -INFINITY, WC_CAL_VISCOSITY_A1),
        LIMIT(mu1, WC_CAL_LIMIT_MU_MAX, INFINITY, WC_CAL_MU1),
        LIMIT(mu1, WC_CAL_LIMIT_MU_MIN, -INFINITY, WC_CAL_MU1),
        LIMIT(mu2, WC_CAL_LIMIT_MU_MAX, INFINITY, WC_CAL_MU2),
        LIMIT(mu2, WC_CAL_LIMIT_MU_MIN, -INFINITY, WC_CAL_MU2),
        LIMIT(stribeck_speed_m_s, WC_CAL_LIMIT_STRIBECK_SPEED_MIN_m_s, -INFINITY, WC_CAL_STRIBECK_SPEED),
        LIMIT(stribeck_speed_m_s, WC_CAL_LIMIT_STRIBECK_SPEED_MAX_m_s, INFINITY, WC_CAL_STRIBECK_SPEED),
        LIMIT(theta1_degC, WC_THETA_MIN_degC, -INFINITY, WC_CAL_THETA1),
        LIMIT(theta1_degC, WC_THETA_MAX_degC, INFINITY, WC_CAL_THETA1),
        LIMIT(theta2_K, WC_CAL_LIMIT_THETA2_MIN_K, -INFINITY, WC_CAL_THETA2),
        LIMIT(vfs_gain_Pa_per_mA, WC_CAL_LIMIT_VFS_GAIN_MAX_Pa_per_mA, INFINITY, WC_CAL_VFS_GAIN),
        LIMIT(vfs_time_constant_s, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MIN_s, -INFINITY, WC_CAL_VFS_TIME_CONSTANT),
        LIMIT(vfs_time_constant_s, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s, INFINITY, WC_CAL_VFS_TIME_CONSTANT),
        LIMIT(return_spring_force_N, 0.0f, -INFINITY, WC_CAL_RETURN_SPRING_FORCE),
        LIMIT(return_spring_force_N, WC_CAL_LIMIT_SPRING_FORCE_MAX_N, INFINITY, WC_CAL_RETURN_SPRING_FORCE),
        LIMIT(vfs_current_min_mA, 0.0f, -INFINITY, WC_CAL_VFS_CURRENT_MIN),
        LIMIT(vfs_current_max_mA, WC_CAL_LIMIT_CURRENT_MAX_mA, INFINITY, WC_CAL_VFS_CURRENT_MAX),
        LIMIT(control_period_s, WC_CAL_LIMIT_CONTROL_PERIOD_MIN_s, -INFINITY, WC_CAL_CONTROL_PERIOD),
        LIMIT(control_period_s, WC_CAL_LIMIT_CONTROL_PERIOD_MAX_s, INFINITY, WC_CAL_CONTROL_PERIOD),
        LIMIT(open_clearance_m, 0.0f, -INFINITY, WC_CAL_OPEN_CLEARANCE),
        LIMIT(open_clearance_m, WC_CAL_LIMIT_OPEN_CLEARANCE_MAX_m, INFINITY, WC_CAL_OPEN_CLEARANCE),
        /* 0 is off; between 0 and the minimum neither off nor on */
        LIMIT(open_aeration_speed_rad_s, WC_CAL_LIMIT_OPEN_AERATION_SPEED_MIN_rad_s, -INFINITY,
              WC_CAL_OPEN_AERATION_SPEED),
        LIMIT(open_aeration_speed_rad_s, WC_CAL_LIMIT_OPEN_AERATION_SPEED_MAX_rad_s, INFINITY,
              WC_CAL_OPEN_AERATION_SPEED),
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(limits); ++i) {
        const limit_t *l = &limits[i];
        cal_copy_t c;
        copy_table1(&c);
        wc_calibration_t *cal = &c.cal;
        /* make room so that no relation binds before the limit under test */
        cal->viscosity_a1_Pa_s = 0.05f;               /* mu_v = a1 + a2 = 0.1 Pa s */
        cal->viscosity_b1_per_K = 0.0f;
        cal->viscosity_a2_Pa_s = 0.05f;
        cal->viscosity_b2_per_K = 0.0f;
        cal->mu3 = 0.0f;                              /* mu_f = mu1 .. mu2 */
        cal->outer_radius_m = 0.5f;                   /* room for A_f: pi R_o^2 = 0.785 m^2 */
        cal->friction_area_m2 = 0.5f;                 /* the table covers 1e5 N / 0.5 m^2 */
        cal->heat_capacity_J_per_K = 1e3f;            /* tc 6.2 s */
        cal->vfs_gain_Pa_per_mA = 1000.0f;            /* piston force 4981 N at 1000 mA */
        if (l->offset == offsetof(wc_calibration_t, viscosity_b1_per_K)) { cal->viscosity_a1_Pa_s = 0.0f; }
        if (l->offset == offsetof(wc_calibration_t, viscosity_b2_per_K)) { cal->viscosity_a2_Pa_s = 0.0f; }
        if (l->code == WC_CAL_PISTON_AREA) {
            cal->vfs_gain_Pa_per_mA = 50.0f;          /* 50 kN at 1 m^2: within WC_FORCE_MAX_N */
        }
        if (l->code == WC_CAL_VFS_GAIN) {
            cal->piston_area_m2 = 1e-5f;              /* 1e6 * 1000 * 1e-5 = 1e4 N */
        }
        if (l->code == WC_CAL_VFS_CURRENT_MAX) {
            cal->piston_area_m2 = 1e-3f;              /* 1e4 mA: 1e4 N */
        }
        if (l->code == WC_CAL_HEAT_CAPACITY) {
            cal->oil_conductance_W_per_K = 1e3f;      /* 1e7 / 1e3 = 1e4 s */
        }
        if ((l->code == WC_CAL_OIL_CONDUCTANCE) || (l->code == WC_CAL_HOUSING_CONDUCTANCE)) {
            cal->heat_capacity_J_per_K = 1e4f;        /* C / 1e5 W/K = 0.1 s */
        }
        float *value = field_ptr(cal, l->offset);
        *value = l->limit;
        if ((l->code == WC_CAL_RETURN_SPRING_FORCE) && (l->limit > 0.0f)) {
            /* F_s = WC_FORCE_MAX_N: no piston within WC_FORCE_MAX_N overcomes it */
            expect_code(cal, WC_CAL_VFS_CURRENT_MAX, l->name, (double)l->limit);
            *value = nextafterf(l->limit, l->beyond);
            expect_code(cal, l->code, l->name, (double)*value);
            continue;
        }
        expect_code(cal, WC_CAL_OK, l->name, (double)l->limit);
        *value = nextafterf(l->limit, l->beyond);
        expect_code(cal, l->code, l->name, (double)*value);
    }
}

/* A count field (uint32_t at offset): 0, max + 1 and UINT32_MAX rejected with code, 1 and max accepted. */
static void check_count_field(size_t offset, uint32_t max, wc_cal_error_t code, const char *name)
{
    const uint32_t values[] = { 0u, max + 1u, UINT32_MAX, 1u, max };
    for (size_t k = 0u; k < WC_TEST_COUNT(values); ++k) {
        cal_copy_t c;
        copy_table1(&c);
        memcpy((unsigned char *)&c.cal + offset, &values[k], sizeof values[k]);
        expect_code(&c.cal, (k < 3u) ? code : WC_CAL_OK, name, (double)values[k]);
    }
    assert_string_equal(wc_cal_error_name(code), name);
}

static void test_friction_pairs(void **state)
{
    (void)state;
    check_count_field(offsetof(wc_calibration_t, friction_pairs), WC_CAL_LIMIT_FRICTION_PAIRS_MAX,
                      WC_CAL_FRICTION_PAIRS, "friction_pairs");
}

static void test_lock_dwell(void **state)
{
    (void)state;
    check_count_field(offsetof(wc_calibration_t, lock_dwell_periods), WC_CAL_LIMIT_LOCK_DWELL_MAX_periods,
                      WC_CAL_LOCK_DWELL, "lock_dwell_periods");
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
    c.cal.inner_radius_m = nextafterf(c.cal.outer_radius_m, 0.0f);
    expect_code(&c.cal, WC_CAL_OK, "inner_radius_m just below outer", (double)c.cal.inner_radius_m);
    c.cal.inner_radius_m = FLT_MIN;
    expect_code(&c.cal, WC_CAL_OK, "inner_radius_m = FLT_MIN", (double)c.cal.inner_radius_m);
}

/* A_f <= pi R_o^2, computed in float as the check does. */
static void test_friction_area_within_the_disc(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    const float disc = WC_CAL_LIMIT_PI * c.cal.outer_radius_m * c.cal.outer_radius_m;
    c.cal.friction_area_m2 = disc;
    expect_code(&c.cal, WC_CAL_OK, "friction_area_m2 = pi R_o^2", (double)disc);
    c.cal.friction_area_m2 = nextafterf(disc, INFINITY);
    expect_code(&c.cal, WC_CAL_FRICTION_AREA, "friction_area_m2 above pi R_o^2", (double)disc);
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
 * force at the maximum current beyond it is rejected, naming the current; a
 * piston that cannot overcome its spring too. */
static void test_piston_force_at_max_current(void **state)
{
    (void)state;
    cal_copy_t c;
    copy_table1(&c);
    c.cal.outer_radius_m = 0.2f;
    c.cal.friction_area_m2 = 0.1f;  /* the table (4.2 MPa) covers 1e5 N */
    const float force_limit_mA = WC_FORCE_MAX_N / (c.cal.vfs_gain_Pa_per_mA * c.cal.piston_area_m2);
    c.cal.vfs_current_max_mA = 1.01f * force_limit_mA;
    c.cal.vfs_current_max_mA = (c.cal.vfs_current_max_mA < WC_CAL_LIMIT_CURRENT_MAX_mA) ? c.cal.vfs_current_max_mA
                                                                                        : WC_CAL_LIMIT_CURRENT_MAX_mA;
    expect_code(&c.cal, WC_CAL_VFS_CURRENT_MAX, "piston force above WC_FORCE_MAX_N", (double)c.cal.vfs_current_max_mA);
    c.cal.vfs_current_max_mA = 0.99f * force_limit_mA;
    expect_code(&c.cal, WC_CAL_OK, "piston force just below WC_FORCE_MAX_N", (double)c.cal.vfs_current_max_mA);

    copy_table1(&c);
    const float spring_mA = c.cal.return_spring_force_N / (c.cal.vfs_gain_Pa_per_mA * c.cal.piston_area_m2);
    c.cal.vfs_current_max_mA = 0.999f * spring_mA;
    expect_code(&c.cal, WC_CAL_VFS_CURRENT_MAX, "piston force below F_s", (double)c.cal.vfs_current_max_mA);
    c.cal.vfs_current_max_mA = 1.001f * spring_mA;
    expect_code(&c.cal, WC_CAL_OK, "piston force just above F_s", (double)c.cal.vfs_current_max_mA);
}

/* With several bad fields the first one in declaration order is reported;
 * the relations between fields after every field's own range. */
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

    copy_table1(&c);
    c.cal.mu3 = -0.52f;                      /* FRICTION_DOMAIN: a relation */
    c.cal.vfs_gain_Pa_per_mA = 0.0f;         /* a later field, but a field */
    expect_code(&c.cal, WC_CAL_VFS_GAIN, "mu3 and vfs_gain", 0.0);
    c.cal.vfs_gain_Pa_per_mA = wc_table1_calibration.vfs_gain_Pa_per_mA;
    expect_code(&c.cal, WC_CAL_FRICTION_DOMAIN, "mu3", -0.52);
    c.cal.viscosity_b2_per_K = -0.2f;        /* VISCOSITY_RANGE, before FRICTION_DOMAIN */
    expect_code(&c.cal, WC_CAL_VISCOSITY_RANGE, "b2 and mu3", -0.2);
    c.cal.friction_pairs = 0u;               /* a field: before every relation */
    expect_code(&c.cal, WC_CAL_FRICTION_PAIRS, "friction_pairs and b2 and mu3", 0.0);
    c.cal.film.length = 0u;                  /* the film last */
    expect_code(&c.cal, WC_CAL_FRICTION_PAIRS, "friction_pairs and film", 0.0);
}

static void test_error_names(void **state)
{
    (void)state;
    const char *names[WC_CAL_ERRORS];
    for (int e = WC_CAL_OK; e < (int)WC_CAL_ERRORS; ++e) {
        names[e] = wc_cal_error_name((wc_cal_error_t)e);
        assert_non_null(names[e]);
        WC_CHECK(strlen(names[e]) > 0u, "empty name for %d", e);
        WC_CHECK(strcmp(names[e], "unknown") != 0, "code %d has no name", e);
        for (int k = WC_CAL_OK; k < e; ++k) {
            WC_CHECK(strcmp(names[k], names[e]) != 0, "codes %d and %d share the name %s", k, e, names[e]);
        }
    }
    assert_string_equal(wc_cal_error_name(WC_CAL_ERRORS), "unknown");
    assert_string_equal(wc_cal_error_name((wc_cal_error_t)(WC_CAL_ERRORS + 1)), "unknown");
    /* The names the Python loader quotes (tests/python/test_calibration_rules.py, C_NAMES). */
    assert_string_equal(wc_cal_error_name(WC_CAL_CONDUCTANCE_SUM),
                        "oil_conductance_W_per_K + housing_conductance_W_per_K");
    assert_string_equal(wc_cal_error_name(WC_CAL_THERMAL_TIME_CONSTANT),
                        "heat_capacity_J_per_K / (oil_conductance_W_per_K + housing_conductance_W_per_K)");
    assert_string_equal(wc_cal_error_name(WC_CAL_VISCOSITY_RANGE),
                        "viscosity_a1_Pa_s..viscosity_b2_per_K (mu_v on the temperature domain)");
    assert_string_equal(wc_cal_error_name(WC_CAL_FRICTION_DOMAIN),
                        "mu1, mu2, mu3, theta1_degC, theta2_K (mu_f on the temperature domain)");
    assert_string_equal(wc_cal_error_name(WC_CAL_FILM_COVERAGE),
                        "film.pressure_Pa (last node below the contact pressure at vfs_current_max_mA)");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table1_is_valid),
        cmocka_unit_test(test_null_arguments),
        cmocka_unit_test(test_field_table_is_complete),
        cmocka_unit_test(test_every_float_field_rejects_non_finite),
        cmocka_unit_test(test_limits_are_inclusive),
        cmocka_unit_test(test_friction_pairs),
        cmocka_unit_test(test_lock_dwell),
        cmocka_unit_test(test_inner_radius_not_below_outer),
        cmocka_unit_test(test_friction_area_within_the_disc),
        cmocka_unit_test(test_current_max_not_above_min),
        cmocka_unit_test(test_piston_force_at_max_current),
        cmocka_unit_test(test_first_failing_field_is_reported),
        cmocka_unit_test(test_error_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
