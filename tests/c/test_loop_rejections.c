/* Frames the CAN frame loop must not use (include/wetclutch_can/wc_loop.h):
 * a repeated or jumping alive counter, a CRC error, a short frame, an
 * unknown id, a wrong format, a full receive ring, implausible signals (SNA,
 * out of range, reserved Mode) and a sensor that keeps sending them; each
 * counted by reason, flagged in that step's status, the held values used.
 * The mock port, the frames, the reference chain and the fixture:
 * wc_test_loop_harness.h. */
#include "wc_test_loop_harness.h"

/* E2E and format rejections                                                */
/* ======================================================================== */

/* A repeated and a jumping alive counter (3 or 5 ahead: more than one lost
 * frame), on each input: the frame (which carries a different value) is not
 * used, it is counted, and StatusCounterError is in the VfsCommand of that
 * step only. After a jump the sender's next SyncCounter - 1 frames are in
 * sequence but not yet used (SYNC, no error bit, the input is still fresh:
 * no safe state); the one after is used. */
static void test_counter_repeat_and_jump(void **state)
{
    fixture_t *fx = *state;
    const float other_slip_rpm = 1500.0f;
    const float other_torque_Nm = 300.0f;
    uint32_t bad = 0u;
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }

    for (int jump = 0; jump <= 1; ++jump) {
        /* ClutchSensors: repeat = the last accepted counter again; jump = 3 ahead */
        const uint8_t last = (uint8_t)((fx->sensors_alive + 15u) % 16u);
        const uint8_t bad_counter = jump ? (uint8_t)((last + 3u) % 16u) : last;
        good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
        const wc_can_frame_t f = sensors_frame(other_slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC, bad_counter);
        port_deliver(&f);
        run_steps(&fx->loop, 1u);
        bad++;
        check_distinguishable(inverse_current_mA(&fx->ref, fx->ref.sensors.slip_speed_rpm, fx->ref.theta_degC,
                                                 NOMINAL.torque_Nm),
                              inverse_current_mA(&fx->ref, other_slip_rpm, fx->ref.theta_degC, NOMINAL.torque_Nm));
        const expected_t e = ref_step(&fx->ref, false);  /* held sensors */
        check_step(fx, &e, WC_CAN_STATUS_COUNTER_ERROR);
        check_held(fx);
        assert_int_equal(fx->loop.counters.rejected[WC_REJECT_COUNTER], bad);
        /* A repeat leaves the reference; a jump resynchronises to it. */
        if (jump) {
            fx->sensors_alive = wc_e2e_counter_next(bad_counter);
            for (int k = 1; k < 3; ++k) {  /* SyncCounter 3: two more frames not used */
                good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
                sync_sensors(fx, other_slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
                run_steps(&fx->loop, 1u);
                const expected_t s_e = ref_step(&fx->ref, false);  /* held sensors */
                check_step(fx, &s_e, 0u);
                check_held(fx);
            }
        }
        (void)good_period(fx, &NOMINAL, 0u);  /* next VfsCommand: bit gone */
        (void)good_period(fx, &NOMINAL, 0u);
    }
    for (int jump = 0; jump <= 1; ++jump) {
        /* TorqueRequest, the same way */
        const uint8_t last = (uint8_t)((fx->request_alive + 15u) % 16u);
        const uint8_t bad_counter = jump ? (uint8_t)((last + 5u) % 16u) : last;
        const wc_can_frame_t f = request_frame(other_torque_Nm, MODE_TORQUE, bad_counter);
        port_deliver(&f);
        good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
        run_steps(&fx->loop, 1u);
        bad++;
        check_distinguishable(inverse_current_mA(&fx->ref, NOMINAL.slip_rpm, fx->ref.theta_degC,
                                                 fx->ref.request.torque_request_Nm),
                              inverse_current_mA(&fx->ref, NOMINAL.slip_rpm, fx->ref.theta_degC, other_torque_Nm));
        const expected_t e = ref_step(&fx->ref, false);  /* held request */
        check_step(fx, &e, WC_CAN_STATUS_COUNTER_ERROR);
        check_held(fx);
        assert_int_equal(fx->loop.counters.rejected[WC_REJECT_COUNTER], bad);
        if (jump) {
            fx->request_alive = wc_e2e_counter_next(bad_counter);
            for (int k = 1; k < 3; ++k) {
                sync_request(fx, other_torque_Nm, MODE_TORQUE);
                good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
                run_steps(&fx->loop, 1u);
                const expected_t s_e = ref_step(&fx->ref, false);  /* held request */
                check_step(fx, &s_e, 0u);
                check_held(fx);
            }
        }
        (void)good_period(fx, &NOMINAL, 0u);
        (void)good_period(fx, &NOMINAL, 0u);
    }
    assert_int_equal(fx->loop.counters.safe_steps, 0u);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_SYNC], 4u);  /* 2 per jump */
}

/* One flipped bit: the CRC fails, the frame is not used, StatusCrcError in
 * that step's VfsCommand only. The sender's counter went on with the lost
 * frame, so its next frame is one ahead of the expected one: OKSOMELOST,
 * used (wc_e2e.h: one lost frame costs one frame), no counter error. */
static void test_crc_error(void **state)
{
    fixture_t *fx = *state;
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }

    /* ClutchSensors: bit 3 of byte 2 (SlipSpeed) */
    good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
    wc_can_frame_t f = sensors_frame(1500.0f, NOMINAL.oil_degC, NOMINAL.housing_degC, fx->sensors_alive);
    fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
    f.data[2] ^= (uint8_t)(1u << 3);
    port_deliver(&f);
    run_steps(&fx->loop, 1u);
    expected_t e = ref_step(&fx->ref, false);
    check_step(fx, &e, WC_CAN_STATUS_CRC_ERROR);
    check_held(fx);
    check_rejected_only(&fx->loop, WC_REJECT_CRC, 1u);

    const period_t after = { 1500.0f, NOMINAL.oil_degC, NOMINAL.housing_degC, NOMINAL.torque_Nm, NOMINAL.mode };
    (void)good_period(fx, &after, 0u);   /* used at once */
    (void)good_period(fx, &NOMINAL, 0u);

    /* TorqueRequest: bit 0 of byte 3 (TorqueRequest high byte), then the
     * sender's next frame, used at once. */
    const period_t more = { NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC, 300.0f, MODE_TORQUE };
    f = request_frame(more.torque_Nm, more.mode, fx->request_alive);
    fx->request_alive = wc_e2e_counter_next(fx->request_alive);
    f.data[3] ^= 1u;
    port_deliver(&f);
    good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
    run_steps(&fx->loop, 1u);
    e = ref_step(&fx->ref, false);
    check_step(fx, &e, WC_CAN_STATUS_CRC_ERROR);
    check_held(fx);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_CRC], 2u);

    (void)good_period(fx, &more, 0u);   /* the sender's next frame: used at once */
    (void)good_period(fx, &more, 0u);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_CRC], 2u);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_COUNTER], 0u);
    assert_int_equal(rejected_total(&fx->loop.counters), 2u);
}

/* Short frame, unknown id and wrong format (extended, remote, error), each
 * raising StatusFrameLost in the step that processed it: not
 * used, counted by reason. These frames are built with the counter the next
 * good frame carries as well: a frame that never reaches the counter check
 * must not consume it. */
static void test_short_unknown_and_format(void **state)
{
    fixture_t *fx = *state;
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }

    /* DLC 7: a ClutchSensors frame, so the frame clock steps on it */
    good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
    wc_can_frame_t f = sensors_frame(1500.0f, 90.0f, 80.0f, fx->sensors_alive);
    f.dlc = 7u;
    port_deliver(&f);
    run_steps(&fx->loop, 1u);
    expected_t e = ref_step(&fx->ref, false);
    check_step(fx, &e, WC_CAN_STATUS_FRAME_LOST);  /* lost before its check: StatusFrameLost, that step only */
    check_held(fx);
    check_rejected_only(&fx->loop, WC_REJECT_SHORT, 1u);
    (void)good_period(fx, &NOMINAL, 0u);
    check_rejected_only(&fx->loop, WC_REJECT_SHORT, 1u);

    /* Unknown ids: a bench frame under an id the DBC does not define, our own
     * VfsCommand echoed back, an id nobody uses. None steps the frame clock. */
    wc_can_frame_t bench = empty_frame(WC_CAN_BENCH_MEASUREMENT_FRAME_ID + 1u);
    const wc_can_bench_measurement_phys_t m = { 1000.0f, 100.0f, 60.0f };
    assert_int_equal(wc_can_encode_bench_measurement(bench.data, &m, sizeof bench.data), WC_CAN_OK);
    port_deliver(&bench);
    const wc_can_frame_t echo = tx_log.frames[tx_log.count - 2u];
    port_deliver(&echo);
    wc_can_frame_t stranger = sensors_frame(1500.0f, 90.0f, 80.0f, fx->sensors_alive);
    stranger.id = 0x7FFu;
    port_deliver(&stranger);
    (void)good_period(fx, &NOMINAL, WC_CAN_STATUS_FRAME_LOST);
    (void)good_period(fx, &NOMINAL, 0u);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_UNKNOWN_ID], 3u);
    assert_int_equal(rejected_total(&fx->loop.counters), 1u + 3u);

    /* Extended, remote and error flags on otherwise valid frames of both
     * inputs (changed values, the counters the next good frames use). */
    const uint8_t flags[] = { WC_CAN_FLAG_EXTENDED, WC_CAN_FLAG_REMOTE, WC_CAN_FLAG_ERROR };
    for (size_t i = 0u; i < WC_TEST_COUNT(flags); ++i) {
        wc_can_frame_t s = sensors_frame(1500.0f, 90.0f, 80.0f, fx->sensors_alive);
        s.flags = flags[i];
        wc_can_frame_t q = request_frame(600.0f, MODE_LOCKED, fx->request_alive);
        q.flags = flags[i];
        port_deliver(&q);
        port_deliver(&s);  /* flagged: no step */
        (void)good_period(fx, &NOMINAL, WC_CAN_STATUS_FRAME_LOST);
        check_held(fx);
    }
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_FORMAT], 2u * WC_TEST_COUNT(flags));
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_COUNTER], 0u);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_CRC], 0u);
    assert_int_equal(rejected_total(&fx->loop.counters), 1u + 3u + 2u * WC_TEST_COUNT(flags));
}

/* More than WC_LOOP_RX_CAPACITY frames before a step: the extra ones are
 * refused (wc_loop_receive returns false) and counted; the ring works again
 * after the step. */
static void test_ring_overflow(void **state)
{
    fixture_t *fx = *state;
    (void)good_period(fx, &NOMINAL, 0u);

    /* Straight into wc_loop_receive: the return value. */
    for (uint32_t i = 0u; i < WC_LOOP_RX_CAPACITY; ++i) {
        const wc_can_frame_t q = request_frame(NOMINAL.torque_Nm, MODE_TORQUE, fx->request_alive);
        fx->request_alive = wc_e2e_counter_next(fx->request_alive);
        WC_CHECK(wc_loop_receive(&fx->loop, &q), "frame %u of %u refused", (unsigned)i,
                 (unsigned)WC_LOOP_RX_CAPACITY);
    }
    const wc_can_frame_t extra = request_frame(NOMINAL.torque_Nm, MODE_TORQUE, fx->request_alive);
    assert_false(wc_loop_receive(&fx->loop, &extra));
    check_rejected_only(&fx->loop, WC_REJECT_OVERFLOW, 1u);

    /* Through the port: the ring is still full, so this sensor frame is lost
     * too, but the frame clock still steps on it. */
    const wc_can_frame_t s = sensors_frame(NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC,
                                           fx->sensors_alive);
    port_deliver(&s);
    run_steps(&fx->loop, 1u);
    assert_int_equal(tx_log.refused, 1u);
    check_rejected_only(&fx->loop, WC_REJECT_OVERFLOW, 2u);
    /* the 32 queued requests were in sequence: all used */
    assert_int_equal(fx->loop.counters.frames_used, 2u + WC_LOOP_RX_CAPACITY);
    assert_int_equal(fx->loop.counters.frames_in, 2u + WC_LOOP_RX_CAPACITY + 2u);

    /* After the step the ring takes frames again (the lost sensor frame is
     * sent once more, with its counter). */
    port_deliver(&s);
    run_steps(&fx->loop, 1u);
    assert_int_equal(tx_log.refused, 1u);
    assert_int_equal(fx->loop.counters.frames_used, 3u + WC_LOOP_RX_CAPACITY);
    assert_int_equal(fx->loop.counters.frames_in,
                     fx->loop.counters.frames_used + rejected_total(&fx->loop.counters));
}

/* ======================================================================== */
/* Implausible signals                                                      */
/* ======================================================================== */

/* SNA, out of the DBC range and reserved Mode, each in one frame with a
 * correct counter and CRC: WC_REJECT_IMPLAUSIBLE, StatusImplausibleInput in
 * that step only, the held values are used, outputs finite; the counter was
 * in sequence, so the next frame is used without a counter error. */
static void test_implausible_signals(void **state)
{
    fixture_t *fx = *state;
    const wc_can_signal_t *slip = &wc_can_sig_clutch_sensors_slip_speed;
    const wc_can_signal_t *oil = &wc_can_sig_clutch_sensors_oil_temp;
    const wc_can_signal_t *housing = &wc_can_sig_clutch_sensors_housing_temp;
    const wc_can_signal_t *torque = &wc_can_sig_torque_request_torque_request;
    const implausible_t cases[] = {
        { "SlipSpeed SNA", SIG_SLIP, WC_CAN_CLUTCH_SENSORS_SLIP_SPEED_SNA_CHOICE },
        { "SlipSpeed above 8000 rpm", SIG_SLIP, slip->raw_max + 1 },
        { "SlipSpeed below -8000 rpm", SIG_SLIP, slip->raw_min - 1 },
        { "OilTemp SNA", SIG_OIL, (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE },
        { "OilTemp above 200 degC", SIG_OIL, oil->raw_max + 1 },
        { "OilTemp below -40 degC", SIG_OIL, oil->raw_min - 1 },
        { "HousingTemp SNA", SIG_HOUSING, (int32_t)WC_CAN_CLUTCH_SENSORS_HOUSING_TEMP_SNA_CHOICE },
        { "HousingTemp above 200 degC", SIG_HOUSING, housing->raw_max + 1 },
        { "TorqueRequest SNA", SIG_TORQUE, (int32_t)WC_CAN_TORQUE_REQUEST_TORQUE_REQUEST_SNA_CHOICE },
        { "TorqueRequest above 2000 Nm", SIG_TORQUE, torque->raw_max + 1 },
        { "Mode 4 (reserved)", SIG_MODE, 4 },
        { "Mode 15 (reserved)", SIG_MODE, 15 },
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(cases); ++i) {
        const implausible_t *c = &cases[i];
        print_message("    %s\n", c->name);
        fixture_init(fx);
        for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }
        if (c->which <= SIG_HOUSING) {
            good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
            const wc_can_frame_t f = implausible_frame(c, fx->sensors_alive);
            fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
            wc_can_clutch_sensors_phys_t decoded;
            WC_CHECK(wc_can_is_error(wc_can_decode_clutch_sensors(&decoded, f.data, f.dlc)), "%s: decodes as valid",
                     c->name);
            port_deliver(&f);
        } else {
            const wc_can_frame_t f = implausible_frame(c, fx->request_alive);
            fx->request_alive = wc_e2e_counter_next(fx->request_alive);
            wc_can_torque_request_phys_t decoded;
            WC_CHECK(wc_can_is_error(wc_can_decode_torque_request(&decoded, f.data, f.dlc)), "%s: decodes as valid",
                     c->name);
            port_deliver(&f);
            good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
        }
        run_steps(&fx->loop, 1u);
        const expected_t e = ref_step(&fx->ref, false);  /* held values, still fresh */
        check_step(fx, &e, WC_CAN_STATUS_IMPLAUSIBLE_INPUT);
        check_held(fx);
        check_rejected_only(&fx->loop, WC_REJECT_IMPLAUSIBLE, 1u);
        (void)good_period(fx, &NOMINAL, 0u);
        check_rejected_only(&fx->loop, WC_REJECT_IMPLAUSIBLE, 1u);
    }
}

/* A sensor that keeps sending an implausible OilTemp (in sequence, right CRC)
 * is as good as silent: StatusImplausibleInput every step, and after the
 * sensor timeout the safe state. A plausible frame ends it. */
static void test_persistent_implausible_sensor(void **state)
{
    fixture_t *fx = *state;
    const uint32_t timeout = fx->loop.config.sensor_timeout_periods;
    const implausible_t sna = { "OilTemp SNA", SIG_OIL, (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE };
    for (int k = 0; k < 5; ++k) { (void)good_period(fx, &NOMINAL, 0u); }
    const uint32_t stale_periods = 6u;
    for (uint32_t j = 1u; j < timeout + stale_periods; ++j) {
        good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
        const wc_can_frame_t f = implausible_frame(&sna, fx->sensors_alive);
        fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
        port_deliver(&f);
        run_steps(&fx->loop, 1u);
        const bool stale = (j >= timeout);
        /* The timeout (period `timeout`) restarts the E2E receiver: the next
         * SyncCounter frames are the reference and in-sequence SYNC frames,
         * whose plausibility is not looked at; after them, implausible again. */
        const bool syncing = (j > timeout) && (j <= timeout + fx->loop.config.e2e.sync_counter);
        const expected_t e = ref_step(&fx->ref, stale);
        check_step(fx, &e, (uint16_t)((syncing ? 0u : WC_CAN_STATUS_IMPLAUSIBLE_INPUT) | (stale ? SAFE_SENSORS : 0u)));
        if (stale) { check_min_current(); }
        check_held(fx);
        WC_CHECK(fx->loop.counters.sensor_timeouts == (stale ? 1u : 0u), "period %u: %u sensor timeouts",
                 (unsigned)j, (unsigned)fx->loop.counters.sensor_timeouts);
    }
    const uint32_t sync = fx->loop.config.e2e.sync_counter;
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_IMPLAUSIBLE], timeout + stale_periods - 1u - sync);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_SYNC], sync);
    /* the implausible frames were in sequence: the receiver is synchronised, the next good frame is used */
    (void)good_period(fx, &NOMINAL, 0u);
    (void)good_period(fx, &NOMINAL, 0u);
    assert_int_equal(fx->loop.counters.safe_steps, stale_periods);
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_COUNTER], 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_counter_repeat_and_jump, setup),
        cmocka_unit_test_setup(test_crc_error, setup),
        cmocka_unit_test_setup(test_short_unknown_and_format, setup),
        cmocka_unit_test_setup(test_ring_overflow, setup),
        cmocka_unit_test_setup(test_implausible_signals, setup),
        cmocka_unit_test_setup(test_persistent_implausible_sensor, setup),
    };
    return cmocka_run_group_tests_name("wc_loop_rejections", tests, NULL, NULL);
}
