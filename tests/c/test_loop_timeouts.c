/* Timeouts and the safe state of the CAN frame loop (include/wetclutch_can/wc_loop.h):
 * ClutchSensors or TorqueRequest stop (three configurations), the safe state
 * and its minimum current, recovery through the E2E SyncCounter, and the
 * safe state before the first frame of each input. The default
 * configuration's debounce and the fault matrix: test_loop_faults.c.
 * The mock port, the frames, the reference chain and the fixture:
 * wc_test_loop_harness.h. */
#include "wc_test_loop_harness.h"

/* ======================================================================== */
/* Timeouts and the safe state                                              */
/* ======================================================================== */

/* ClutchSensors stop (the request goes on; timer deadlines step the loop):
 * fresh for timeout-1 periods, then SensorTimeout + SafeStateActive and the
 * minimum current; one timeout counted. Recovery needs the reference frame
 * and SyncCounter - 1 more in sequence, then the next frame is used. */
static void sensor_timeout_case(fixture_t *fx, const wc_loop_config_t *config)
{
    fixture_init_with(fx, config);
    const uint32_t timeout = config->sensor_timeout_periods;
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }
    const uint32_t stale_periods = 5u;
    for (uint32_t j = 1u; j < timeout + stale_periods; ++j) {  /* j periods without a sensor frame */
        good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
        port_tick();
        run_steps(&fx->loop, 1u);
        const bool stale = (j >= timeout);
        const expected_t e = ref_step(&fx->ref, stale);
        check_step(fx, &e, stale ? SAFE_SENSORS : 0u);
        if (stale) { check_min_current(); }
        WC_CHECK(fx->loop.counters.sensor_timeouts == (stale ? 1u : 0u), "period %u: %u sensor timeouts",
                 (unsigned)j, (unsigned)fx->loop.counters.sensor_timeouts);
    }
    assert_int_equal(fx->loop.counters.safe_steps, stale_periods);
    assert_int_equal(fx->loop.counters.request_timeouts, 0u);

    /* Recovery: the sender restarts with a counter 7 ahead of the old
     * sequence. Its first frame is the new reference and the next
     * SyncCounter - 1 are in sequence but not yet used (wc_e2e.h SYNC, no
     * counter error): the input stays stale; the SyncCounter-th +1 frame is
     * used and, with this fixture's one-period debounce, control resumes. */
    fx->sensors_alive = (uint8_t)((fx->sensors_alive + 7u) % WC_E2E_COUNTER_MODULO);
    const period_t back = { 900.0f, 70.0f, 60.0f, 150.0f, MODE_TORQUE };
    for (uint32_t k = 0u; k < config->e2e.sync_counter; ++k) {
        good_request(fx, back.torque_Nm, back.mode);
        sync_sensors(fx, back.slip_rpm, back.oil_degC, back.housing_degC);
        run_steps(&fx->loop, 1u);
        const expected_t e = ref_step(&fx->ref, true);
        check_step(fx, &e, SAFE_SENSORS);
        check_min_current();
    }
    (void)good_period(fx, &back, 0u);
    (void)good_period(fx, &back, 0u);
    check_rejected_only(&fx->loop, WC_REJECT_SYNC, config->e2e.sync_counter);
    assert_int_equal(fx->loop.counters.sensor_timeouts, 1u);
    assert_int_equal(fx->loop.counters.safe_steps, stale_periods + config->e2e.sync_counter);
}

/* Timeouts of the default configuration and two others (sensor, request). */
static const wc_loop_config_t timeout_configs[] = {
    { 10u, 10u, { 2u, 3u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u }, { 3u, 25u, { 2u, 1u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u }, { 1u, 1u, { 2u, 2u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u }
};

static void test_sensor_timeout_and_recovery(void **state)
{
    for (size_t i = 0u; i < WC_TEST_COUNT(timeout_configs); ++i) { sensor_timeout_case(*state, &timeout_configs[i]); }
}

/* TorqueRequest stops (frame clock: sensor frames step the loop). */
static void request_timeout_case(fixture_t *fx, const wc_loop_config_t *config)
{
    fixture_init_with(fx, config);
    const uint32_t timeout = config->request_timeout_periods;
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }
    const uint32_t stale_periods = 4u;
    for (uint32_t j = 1u; j < timeout + stale_periods; ++j) {
        good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
        run_steps(&fx->loop, 1u);
        const bool stale = (j >= timeout);
        const expected_t e = ref_step(&fx->ref, stale);
        check_step(fx, &e, stale ? SAFE_REQUEST : 0u);
        if (stale) { check_min_current(); }
        WC_CHECK(fx->loop.counters.request_timeouts == (stale ? 1u : 0u), "period %u: %u request timeouts",
                 (unsigned)j, (unsigned)fx->loop.counters.request_timeouts);
    }
    assert_int_equal(fx->loop.counters.sensor_timeouts, 0u);

    fx->request_alive = (uint8_t)((fx->request_alive + 11u) % WC_E2E_COUNTER_MODULO);
    const period_t back = { 500.0f, 60.0f, 55.0f, 220.0f, MODE_TORQUE };
    for (uint32_t k = 0u; k < config->e2e.sync_counter; ++k) {  /* reference + SYNC frames: not used */
        sync_request(fx, back.torque_Nm, back.mode);
        good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
        run_steps(&fx->loop, 1u);
        const expected_t e = ref_step(&fx->ref, true);
        check_step(fx, &e, SAFE_REQUEST);
        check_min_current();
    }
    (void)good_period(fx, &back, 0u);
    (void)good_period(fx, &back, 0u);
    check_rejected_only(&fx->loop, WC_REJECT_SYNC, config->e2e.sync_counter);
    assert_int_equal(fx->loop.counters.request_timeouts, 1u);
    assert_int_equal(fx->loop.counters.safe_steps, stale_periods + config->e2e.sync_counter);
}

static void test_request_timeout_and_recovery(void **state)
{
    for (size_t i = 0u; i < WC_TEST_COUNT(timeout_configs); ++i) { request_timeout_case(*state, &timeout_configs[i]); }
}

/* Before the first valid frame of an input the loop is in the safe state;
 * that is not a timeout (nothing went from fresh to stale). */
static void test_safe_state_before_first_frames(void **state)
{
    fixture_t *fx = *state;
    /* no frame at all */
    for (int k = 0; k < 3; ++k) {
        port_tick();
        run_steps(&fx->loop, 1u);
        const expected_t e = ref_step(&fx->ref, true);
        check_step(fx, &e, SAFE_SENSORS | SAFE_REQUEST);
        check_min_current();
    }
    /* sensors only */
    for (int k = 0; k < 3; ++k) {
        good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
        run_steps(&fx->loop, 1u);
        const expected_t e = ref_step(&fx->ref, true);
        check_step(fx, &e, SAFE_REQUEST);
        check_min_current();
    }
    /* both */
    (void)good_period(fx, &NOMINAL, 0u);
    assert_int_equal(fx->loop.counters.sensor_timeouts, 0u);
    assert_int_equal(fx->loop.counters.request_timeouts, 0u);
    assert_int_equal(fx->loop.counters.safe_steps, 6u);

    /* and the other way round: a request but no sensors yet */
    fixture_init(fx);
    good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
    port_tick();
    run_steps(&fx->loop, 1u);
    const expected_t e = ref_step(&fx->ref, true);
    check_step(fx, &e, SAFE_SENSORS);
    check_min_current();
    (void)good_period(fx, &NOMINAL, 0u);
}

/* ======================================================================== */

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_sensor_timeout_and_recovery, setup),
        cmocka_unit_test_setup(test_request_timeout_and_recovery, setup),
        cmocka_unit_test_setup(test_safe_state_before_first_frames, setup),
    };
    return cmocka_run_group_tests_name("wc_loop_timeouts", tests, NULL, NULL);
}
