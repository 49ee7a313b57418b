/* The adaptation (include/wetclutch/wc_adapt.h, src/model/wc_adapt.c; DESIGN 12) against the golden
 * vectors of the double-precision reference (tools/wetclutch/reference/adaptation.py, written from the
 * header's specification; the synthetic windows: tools/wetclutch/generate/adapt_vectors.py):
 *
 *  - wc_adapt_correction of a set of learned values at temperatures below, on, between and above the
 *    nodes; off (adaptation 0) and no state (NULL): no correction;
 *  - wc_adapt_sample over a window and wc_adapt_finish, per case: the model matches the plant, the
 *    plant's friction +10 %, a later kiss point, a slower film (with the film state on and off), learned
 *    values (the normalised update, an unlearned node's prior, the band, the kiss step's clip), an
 *    implausible torque ratio, too little excitation, an invalid input, an aborted shift, adaptation
 *    off: the result, the report's node, the window's sample count, every learned value after the
 *    update, and what the report says it changed.
 *
 * The window's inputs are float32 values (9 significant digits in the header): the firmware and the
 * reference see the same numbers, and the differences are the firmware's float arithmetic against
 * double. Each tolerance is next to its check with the reason. */
#include "wc_test_support.h"

#include "wc_golden_vectors.h"
#include "wc_table1_calibration.h"
#include "wc_test_fixtures.h"

/* table1 with the vectors' film factor (the film state on) or without (off) */
static wc_calibration_t clutch_cal(bool film_on)
{
    wc_calibration_t cal = wc_table1_calibration;
    cal.film_squeeze_factor = film_on ? WC_GOLDEN_ADAPT_FILM_SQUEEZE_FACTOR : 0.0f;
    return cal;
}

/* The adaptation switch of a calibration (the vectors' rules set it on). */
static void switch_adaptation(wc_shift_calibration_t *cal, uint32_t adaptation) { cal->adaptation = adaptation; }

static wc_shift_calibration_t adapt_cal(uint32_t adaptation)
{
    wc_shift_calibration_t cal = WC_TEST_SHIFT_CALIBRATION;
    WC_GOLDEN_ADAPT_CALIBRATION(&cal);  /* the vectors' rules */
    switch_adaptation(&cal, adaptation);
    return cal;
}

static void set_values(wc_adapt_t *adapt, const wc_golden_adapt_values_t *v)
{
    wc_adapt_reset(adapt);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        adapt->values.friction_scale[i] = (float)v->friction_scale[i];
        adapt->values.confidence[i] = (float)v->confidence[i];
    }
    adapt->values.film_factor = (float)v->film_factor;
    adapt->values.kiss_offset_Pa = (float)v->kiss_offset_Pa;
    adapt->values.shifts_learned = v->shifts_learned;
}

/* ======================================================================== */
/* wc_adapt_correction                                                      */
/* ======================================================================== */

/* The interpolated scale s_lo + (s_hi - s_lo) x in float: a few roundings of values near 1 (6e-8 each),
 * the weight x = (theta - node) / (node spacing) with its own two; the delta s - 1 loses nothing more
 * (Sterbenz). 3e-7 absolute = about 5 roundings. The film delta f - 1 is exact in float, its golden
 * value is the exact one printed with 9 significant digits (5e-10 of 0.3: 1e-9 absolute); the kiss
 * force offset_Pa x A_p is one rounding of a product (relative 6e-8, 1.2e-7 allowed). */
#define CORRECTION_SCALE_ABS_TOL 3e-7
#define CORRECTION_FILM_ABS_TOL 1e-9
#define CORRECTION_KISS_REL_TOL 1.2e-7

static void test_correction_matches_golden(void **state)
{
    (void)state;
    const wc_calibration_t cal = clutch_cal(true);
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &cal, 80.0f), WC_CAL_OK);
    const wc_shift_calibration_t scal = adapt_cal(1u);
    assert_int_equal(wc_shift_calibration_check(&scal), WC_SHIFT_CAL_OK);
    wc_adapt_t adapt;
    const wc_golden_adapt_case_t *learned = NULL;
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_adapt_cases); ++i) {
        if (strcmp(wc_golden_adapt_cases[i].name, "learned") == 0) { learned = &wc_golden_adapt_cases[i]; }
    }
    assert_non_null(learned);
    set_values(&adapt, &learned->before);
    wc_test_worst_t worst = { 0.0, -1 };
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_adapt_correction); ++i) {
        const wc_golden_adapt_correction_t *g = &wc_golden_adapt_correction[i];
        const wc_model_correction_t c = wc_adapt_correction(&adapt, &scal, &clutch, (float)g->theta_degC);
        WC_CHECK_CLOSE("friction_scale_delta", i, c.friction_scale_delta, g->friction_scale_delta, 0.0,
                       CORRECTION_SCALE_ABS_TOL);
        WC_CHECK_CLOSE("film_factor_delta", i, c.film_factor_delta, g->film_factor_delta, 0.0, CORRECTION_FILM_ABS_TOL);
        WC_CHECK_CLOSE("kiss_offset_N", i, c.kiss_offset_N, g->kiss_offset_N, CORRECTION_KISS_REL_TOL, 0.0);
        wc_test_worst_update(&worst, fabs((double)c.friction_scale_delta - g->friction_scale_delta), (long)i);
    }
    wc_test_worst_print("scale delta vs golden", &worst, CORRECTION_SCALE_ABS_TOL);
}

static void test_correction_off_is_zero(void **state)
{
    (void)state;
    const wc_calibration_t cal = clutch_cal(true);
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &cal, 80.0f), WC_CAL_OK);
    const wc_shift_calibration_t off = adapt_cal(0u);
    const wc_shift_calibration_t on = adapt_cal(1u);
    wc_adapt_t adapt;
    set_values(&adapt, &wc_golden_adapt_cases[0].before);
    adapt.values.friction_scale[2] = 1.1f;
    adapt.values.kiss_offset_Pa = 5000.0f;
    const float thetas[] = { -40.0f, 100.0f, 250.0f };
    for (size_t i = 0u; i < WC_TEST_COUNT(thetas); ++i) {
        const wc_model_correction_t a = wc_adapt_correction(&adapt, &off, &clutch, thetas[i]);
        const wc_model_correction_t b = wc_adapt_correction(NULL, &on, &clutch, thetas[i]);
        assert_true(wc_test_same_float(a.friction_scale_delta, 0.0f) && wc_test_same_float(a.film_factor_delta, 0.0f) &&
                    wc_test_same_float(a.kiss_offset_N, 0.0f));
        assert_true(wc_test_same_float(b.friction_scale_delta, 0.0f) && wc_test_same_float(b.film_factor_delta, 0.0f) &&
                    wc_test_same_float(b.kiss_offset_N, 0.0f));
    }
}

/* ======================================================================== */
/* wc_adapt_sample + wc_adapt_finish on the synthetic windows               */
/* ======================================================================== */

/* Tolerances of the learned values after one update (float against double on the same float inputs).
 * The window's sums run over N <= 200 samples: a float sum of N terms of one sign is within
 * (N - 1) eps / 2 = 1.2e-5 of its value (eps = 1.19e-7), and each implied torque carries a few
 * roundings of its own (the slip difference is exact, the division by dt, the drive's subtraction
 * and the division by m are not).
 *  - scale: rho = sum T_imp / sum T_model is within 2.4e-5 relative; the step gain g s (rho - 1) with
 *    g s <= 1.3 (the normalised share of these windows times the scale), and g's own shares are the
 *    same kind of sums: 4e-5 absolute;
 *  - confidence: c + gain q (1 - c), q a ratio of two such sums (2.4e-5), times gain (1 - c) <= 0.3:
 *    1e-5 absolute;
 *  - film factor: f (1 + gain (rho / rho_e - 1)), rho_e over the window's first 40 ms (20 samples),
 *    the ratio of the ratios within 5e-5, times gain f <= 0.65: 5e-5 relative;
 *  - kiss offset: the least squares' determinant D = S11 S22 - S12^2 cancels to D / (S11 S22) = 0.03
 *    here, and so does b2's numerator: the sums' 1.2e-5 become 1e-3 of the estimate, plus the
 *    residual r = T_imp - T_model (a few Nm) carrying the implied torque's roundings (about 1e-4 Nm a
 *    sample) divided by the same conditioning: 2e-3 of the step plus 20 Pa (the matched window's
 *    estimate is that noise alone: 0.3 Pa in double). */
#define SCALE_ABS_TOL 4e-5
#define CONFIDENCE_ABS_TOL 1e-5
#define FILM_REL_TOL 5e-5
#define KISS_REL_TOL 2e-3
#define KISS_ABS_TOL_Pa 20.0

typedef struct {
    wc_test_worst_t scale, confidence, film, kiss;
} adapt_worst_t;

static wc_adapt_change_t run_case(const wc_golden_adapt_case_t *gc, wc_adapt_t *adapt)
{
    const wc_calibration_t cal = clutch_cal(gc->film_on != 0u);
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &cal, 80.0f), WC_CAL_OK);
    const wc_shift_calibration_t scal = adapt_cal(gc->adaptation);
    assert_int_equal(wc_shift_calibration_check(&scal), WC_SHIFT_CAL_OK);
    set_values(adapt, &gc->before);
    wc_adapt_begin(adapt);
    for (unsigned j = 0u; j < gc->count; ++j) {
        const wc_golden_adapt_sample_t *g = &wc_golden_adapt_samples[gc->first + j];
        wc_step_output_t out;
        memset(&out, 0, sizeof out);
        out.model.torque_Nm = (float)g->torque_Nm;
        out.model.coulomb_Nm = (float)g->coulomb_Nm;
        out.model.mu_f = (float)g->mu_f;
        out.contact_force_N = (float)g->contact_force_N;
        out.theta_degC = (float)g->theta_degC;
        out.status = (wc_status_t)g->status;
        wc_adapt_sample(adapt, &scal, (float)g->elapsed_s, (float)g->slip_rad_s, (float)g->drive_rad_s2,
                        (float)gc->inverse_inertia, &clutch, &out);
    }
    return wc_adapt_finish(adapt, &scal, gc->abort_reason, &clutch);
}

static void check_case(const wc_golden_adapt_case_t *gc, adapt_worst_t *worst)
{
    wc_adapt_t adapt;
    const wc_adapt_change_t change = run_case(gc, &adapt);
    const wc_adapt_values_t *v = &adapt.values;
    WC_CHECK(change.result == gc->result, "%s: result %u, expected %u", gc->name, (unsigned)change.result, gc->result);
    WC_CHECK(change.node == gc->node, "%s: node %u, expected %u", gc->name, (unsigned)change.node, gc->node);
    WC_CHECK(adapt.window.samples == gc->samples, "%s: %u window samples, expected %u", gc->name,
             (unsigned)adapt.window.samples, gc->samples);
    WC_CHECK(v->shifts_learned == gc->after.shifts_learned, "%s: shifts_learned %u, expected %u", gc->name,
             (unsigned)v->shifts_learned, gc->after.shifts_learned);
    const long k = (long)(gc - wc_golden_adapt_cases);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        WC_CHECK_CLOSE(gc->name, k * 10 + (long)i, v->friction_scale[i], gc->after.friction_scale[i], 0.0, SCALE_ABS_TOL);
        WC_CHECK_CLOSE(gc->name, k * 10 + 5 + (long)i, v->confidence[i], gc->after.confidence[i], 0.0,
                       CONFIDENCE_ABS_TOL);
        wc_test_worst_update(&worst->scale, fabs((double)v->friction_scale[i] - gc->after.friction_scale[i]), k);
        wc_test_worst_update(&worst->confidence, fabs((double)v->confidence[i] - gc->after.confidence[i]), k);
    }
    WC_CHECK_CLOSE(gc->name, k, v->film_factor, gc->after.film_factor, FILM_REL_TOL, 0.0);
    wc_test_worst_update(&worst->film, wc_test_rel_error((double)v->film_factor, gc->after.film_factor), k);
    /* the kiss step: tolerance relative to the change (the offset before is exact) */
    const double kiss_change = gc->after.kiss_offset_Pa - gc->before.kiss_offset_Pa;
    const double kiss_tol = KISS_ABS_TOL_Pa + KISS_REL_TOL * fabs(kiss_change);
    WC_CHECK_CLOSE(gc->name, k, v->kiss_offset_Pa, gc->after.kiss_offset_Pa, 0.0, kiss_tol);
    wc_test_worst_update(&worst->kiss, fabs((double)v->kiss_offset_Pa - gc->after.kiss_offset_Pa), k);
    if (gc->result != (unsigned)WC_ADAPT_RESULT_UPDATED) {
        /* nothing learned: every value bit for bit what it was (before holds float values) */
        for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
            assert_true(wc_test_same_float(v->friction_scale[i], (float)gc->before.friction_scale[i]));
            assert_true(wc_test_same_float(v->confidence[i], (float)gc->before.confidence[i]));
        }
        assert_true(wc_test_same_float(v->film_factor, (float)gc->before.film_factor));
        assert_true(wc_test_same_float(v->kiss_offset_Pa, (float)gc->before.kiss_offset_Pa));
    }
    if (gc->result != (unsigned)WC_ADAPT_RESULT_OFF) {
        /* the report: the node's values after the shift and what the shift changed, exactly */
        const uint32_t n = change.node;
        assert_true(wc_test_same_float(change.friction_scale, v->friction_scale[n]));
        assert_true(wc_test_same_float(change.friction_scale_change, v->friction_scale[n] - (float)gc->before.friction_scale[n]));
        assert_true(wc_test_same_float(change.confidence, v->confidence[n]));
        assert_true(wc_test_same_float(change.film_factor, v->film_factor));
        assert_true(wc_test_same_float(change.film_factor_change, v->film_factor - (float)gc->before.film_factor));
        assert_true(wc_test_same_float(change.kiss_offset_Pa, v->kiss_offset_Pa));
        assert_true(wc_test_same_float(change.kiss_offset_change_Pa, v->kiss_offset_Pa - (float)gc->before.kiss_offset_Pa));
    }
}

static void test_finish_matches_golden(void **state)
{
    (void)state;
    adapt_worst_t worst = { { 0.0, -1 }, { 0.0, -1 }, { 0.0, -1 }, { 0.0, -1 } };
    assert_true(WC_TEST_COUNT(wc_golden_adapt_cases) >= 13u);
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_adapt_cases); ++i) {
        check_case(&wc_golden_adapt_cases[i], &worst);  /* the NaN sample and the slip that re-enters included */
    }
    wc_test_worst_print("friction scale (abs)", &worst.scale, SCALE_ABS_TOL);
    wc_test_worst_print("confidence (abs)", &worst.confidence, CONFIDENCE_ABS_TOL);
    wc_test_worst_print("film factor (rel)", &worst.film, FILM_REL_TOL);
    wc_test_worst_print("kiss offset (Pa)", &worst.kiss, KISS_ABS_TOL_Pa);
}

/* The truth of the synthetic windows, in the direction the header promises (the exact values are the
 * golden check's): a +10 % plant moves every scale up by at most the step, a later kiss point moves the
 * offset up, a slower film the film factor up, and the matched plant changes no value by more than the
 * float noise the tolerances above allow. */
static const wc_golden_adapt_case_t *find_case(const char *name)
{
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_adapt_cases); ++i) {
        if (strcmp(wc_golden_adapt_cases[i].name, name) == 0) { return &wc_golden_adapt_cases[i]; }
    }
    fail_msg("no golden case %s", name);
    return NULL;
}

static void test_direction_of_each_update(void **state)
{
    (void)state;
    const wc_shift_calibration_t scal = adapt_cal(1u);
    wc_adapt_t adapt;
    (void)run_case(find_case("friction_plus10"), &adapt);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        assert_true(adapt.values.friction_scale[i] > 1.04f);
        assert_true(adapt.values.friction_scale[i] <= 1.0f + scal.adapt_scale_step);
    }
    (void)run_case(find_case("kiss_later"), &adapt);
    assert_true(adapt.values.kiss_offset_Pa > 5000.0f && adapt.values.kiss_offset_Pa <= scal.adapt_kiss_step_Pa);
    (void)run_case(find_case("film_slow"), &adapt);
    assert_true(adapt.values.film_factor > 1.03f);
    (void)run_case(find_case("matched"), &adapt);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        assert_true(fabsf(adapt.values.friction_scale[i] - 1.0f) <= (float)SCALE_ABS_TOL);
    }
    assert_true(fabsf(adapt.values.kiss_offset_Pa) <= (float)KISS_ABS_TOL_Pa);
    assert_true(fabsf(adapt.values.film_factor - 1.0f) <= (float)FILM_REL_TOL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_correction_matches_golden),
        cmocka_unit_test(test_correction_off_is_zero),
        cmocka_unit_test(test_finish_matches_golden),
        cmocka_unit_test(test_direction_of_each_update),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
