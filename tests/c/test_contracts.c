/* API contracts (wc_config.h WC_ASSERT): a NULL pointer or an instance that
 * was never initialised, or whose init failed, reaches the integrator's
 * assert hook before anything is dereferenced. This executable compiles the
 * library's sources itself with WC_ASSERT routed to cmocka's mock_assert
 * (wc_test_assert_config.h); expect_assert_failure fails the test if the hook
 * is not called. */
#include "wc_test_support.h"

#include <math.h>
#include <string.h>

#include "wc_table1_calibration.h"
#include "wc_test_fixtures.h"
#include "wetclutch_can/wc_loop.h"

static wc_step_input_t torque_input(void)
{
    wc_step_input_t in;
    memset(&in, 0, sizeof in);
    in.slip_rad_s = 50.0f;
    in.theta_oil_degC = 40.0f;
    in.theta_housing_degC = 40.0f;
    in.torque_request_Nm = 100.0f;
    in.mode = WC_MODE_TORQUE;
    return in;
}

static void test_valid_calls_do_not_assert(void **state)
{
    (void)state;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &wc_table1_calibration, 40.0f), WC_CAL_OK);
    const wc_step_input_t in = torque_input();
    wc_step_output_t out;
    (void)wc_clutch_step(&clutch, &in, &out);  /* mock_assert(1, ...) is a no-op */
    assert_true(out.current_mA > 0.0f);
}

static void test_clutch_step_null_pointers_assert(void **state)
{
    (void)state;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &wc_table1_calibration, 40.0f), WC_CAL_OK);
    const wc_step_input_t in = torque_input();
    wc_step_output_t out;
    expect_assert_failure(wc_clutch_step(NULL, &in, &out));
    expect_assert_failure(wc_clutch_step(&clutch, NULL, &out));
    expect_assert_failure(wc_clutch_step(&clutch, &in, NULL));
    expect_assert_failure(wc_clutch_init(NULL, &wc_table1_calibration, 40.0f));
}

static void test_clutch_step_uninitialised_asserts(void **state)
{
    (void)state;
    wc_clutch_t never;  /* static-storage-like: all zero, never initialised */
    memset(&never, 0, sizeof never);
    const wc_step_input_t in = torque_input();
    wc_step_output_t out;
    expect_assert_failure(wc_clutch_step(&never, &in, &out));
}

static void test_clutch_step_after_failed_init_asserts(void **state)
{
    (void)state;
    wc_calibration_t bad = wc_table1_calibration;
    bad.outer_radius_m = NAN;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &bad, 40.0f), WC_CAL_OUTER_RADIUS);
    const wc_step_input_t in = torque_input();
    wc_step_output_t out;
    expect_assert_failure(wc_clutch_step(&clutch, &in, &out));
}

static void test_model_functions_assert_on_unusable_model(void **state)
{
    (void)state;
    wc_model_t model;
    memset(&model, 0, sizeof model);  /* cal == NULL: not initialised */
    wc_torque_t torque;
    wc_inverse_t inverse;
    float theta_degC = 40.0f;
    expect_assert_failure(wc_torque(&model, 10.0f, 40.0f, 1000.0f, &torque));
    expect_assert_failure(wc_inverse(&model, 10.0f, 40.0f, 100.0f, &inverse));
    expect_assert_failure(wc_thermal_step(&model, &theta_degC, 0.0f, 40.0f, 40.0f));
    expect_assert_failure(wc_vfs_lag_step(&model, 0.0f, 100.0f));
    expect_assert_failure(wc_film_hbar_m(NULL, 1.0e5f));
    expect_assert_failure(wc_friction_coefficient(NULL, 0.1f, 40.0f));
    expect_assert_failure(wc_viscosity_Pa_s(NULL, 40.0f));
}

static void test_loop_contracts(void **state)
{
    (void)state;
    static wc_loop_t loop;  /* large: not on the stack */
    memset(&loop, 0, sizeof loop);
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    expect_assert_failure(wc_loop_step(&loop, out));  /* never initialised */
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    expect_assert_failure(wc_loop_init(&loop, &wc_table1_calibration, NULL, 40.0f));
    assert_int_equal(wc_loop_init(&loop, &wc_table1_calibration, &config, 40.0f), WC_CAL_OK);
    expect_assert_failure(wc_loop_receive(&loop, NULL));
    expect_assert_failure(wc_loop_step(&loop, NULL));
    assert_int_equal(wc_loop_step(&loop, out), WC_LOOP_TX_CYCLIC);
}

/* DESIGN 12: the adaptation's entry points. NULL instance: reset and the image
 * functions assert; the shift controller's calls take NULL as "no adaptation"
 * (documented in wc_adapt.h / wc_shift.h) and change nothing. */
static void test_adaptation_contracts(void **state)
{
    (void)state;
    static const wc_shift_calibration_t cal = WC_TEST_SHIFT_CALIBRATION;
    wc_adapt_t adapt;
    uint8_t image[WC_ADAPT_IMAGE_BYTES];
    expect_assert_failure(wc_adapt_reset(NULL));
    expect_assert_failure(wc_adapt_command_reset(NULL));
    expect_assert_failure(wc_adapt_image_load(NULL, &cal, 0u, image, sizeof image));
    expect_assert_failure(wc_adapt_image_load(&adapt, NULL, 0u, image, sizeof image));
    expect_assert_failure(wc_adapt_image_write(NULL, 0u, image, sizeof image));
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &wc_table1_calibration, 40.0f), WC_CAL_OK);
    const wc_model_correction_t none = wc_adapt_correction(NULL, &cal, &clutch, 80.0f);
    assert_float_equal(none.friction_scale_delta, 0.0f, 0.0f);
    assert_float_equal(none.film_factor_delta, 0.0f, 0.0f);
    assert_float_equal(none.kiss_offset_N, 0.0f, 0.0f);
    wc_adapt_begin(NULL);
    const wc_adapt_change_t off = wc_adapt_finish(NULL, &cal, 0u, &clutch);
    assert_int_equal(off.result, WC_ADAPT_RESULT_OFF);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_calls_do_not_assert),
        cmocka_unit_test(test_clutch_step_null_pointers_assert),
        cmocka_unit_test(test_clutch_step_uninitialised_asserts),
        cmocka_unit_test(test_clutch_step_after_failed_init_asserts),
        cmocka_unit_test(test_model_functions_assert_on_unusable_model),
        cmocka_unit_test(test_adaptation_contracts),
        cmocka_unit_test(test_loop_contracts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
