/* The CAN frame loop in control (include/wetclutch_can/wc_loop.h): torque
 * control through the frames against the reference chain and a golden
 * inverse vector of the Python reference, VfsCommand's alive counter, Modes
 * Open and Locked, the deadline-miss flag, and bench mode (a fresh
 * BenchMeasurement replaces the modelled apply force).
 * The mock port, the frames, the reference chain and the fixture:
 * wc_test_loop_harness.h. */
#include "wc_test_loop_harness.h"

#include "wc_golden_vectors.h"

/* ======================================================================== */
/* Normal operation                                                         */
/* ======================================================================== */

static const wc_golden_inverse_t *golden_inverse(double slip_rpm, double theta_degC, double torque_Nm)
{
    for (size_t i = 0u; i < WC_TEST_COUNT(wc_golden_inverse); ++i) {
        const wc_golden_inverse_t *g = &wc_golden_inverse[i];
        if (fabs(g->slip_rpm - slip_rpm) < 1e-9 && fabs(g->theta_degC - theta_degC) < 1e-9 &&
            fabs(g->torque_Nm - torque_Nm) < 1e-9) {
            return g;
        }
    }
    fail_msg("no golden inverse vector at %g rpm, %g degC, %g Nm", slip_rpm, theta_degC, torque_Nm);
    return NULL;
}

/* Torque control through the frames: every step's VfsCommand and
 * ClutchEstimate match the reference chain, the status carries only the
 * model's bits; the first step also matches the Python reference. */
static void test_torque_control_outputs(void **state)
{
    fixture_t *fx = *state;

    /* First step: observer at the start temperature (40 degC), inputs exactly
     * on a golden vector. Tolerance: the float inverse against the double
     * reference (1e-4 relative, as in test_inverse.c) plus one raw step. */
    const wc_golden_inverse_t *g = golden_inverse(-750.0, 40.0, 150.0);
    const period_t first = { -750.0f, 40.0f, 40.0f, 150.0f, MODE_TORQUE };
    (void)good_period(fx, &first, 0u);
    wc_can_vfs_command_phys_t cmd;
    wc_can_clutch_estimate_phys_t est;
    last_outputs(&cmd, &est);
    WC_CHECK_CLOSE("VfsCurrent vs golden", 0, cmd.vfs_current_mA, g->current_mA, 1e-4,
                   (double)wc_can_sig_vfs_command_vfs_current.scale);
    WC_CHECK_CLOSE("PressureCommand vs golden", 0, cmd.pressure_command_kPa, g->pressure_kPa, 1e-4,
                   (double)wc_can_sig_vfs_command_pressure_command.scale);

    /* An engagement: slip falls, the request goes through below-drag (0 Nm),
     * normal, above the capacity (1500 Nm near lock-up) and normal again; oil warms. */
    uint32_t steps_plain = 0u;
    uint32_t steps_below_drag = 0u;
    uint32_t steps_saturated = 0u;
    for (int k = 0; k < 240; ++k) {
        const float torque_Nm = (k < 30) ? 0.0f : ((k < 200) ? 150.0f + (float)k : ((k < 230) ? 1500.0f : 300.0f));
        const period_t p = { 1200.0f - 5.0f * (float)k, 60.0f + 0.05f * (float)k, 55.0f, torque_Nm, MODE_TORQUE };
        const expected_t e = good_period(fx, &p, 0u);
        if (e.model_bits == 0u) { steps_plain++; }
        if ((e.model_bits & WC_CAN_STATUS_BELOW_DRAG) != 0u) { steps_below_drag++; }
        if ((e.model_bits & WC_CAN_STATUS_SATURATED) != 0u) { steps_saturated++; }
    }
    /* The run covered all three cases, so the status assertions meant something. */
    WC_CHECK(steps_plain > 0u && steps_below_drag > 0u && steps_saturated > 0u,
             "plain %u, below drag %u, saturated %u steps", (unsigned)steps_plain, (unsigned)steps_below_drag,
             (unsigned)steps_saturated);
    assert_int_equal(fx->loop.counters.safe_steps, 0u);
    assert_int_equal(rejected_total(&fx->loop.counters), 0u);
}

/* VfsCommand's alive counter: +1 mod 16 per frame, wrapping. */
static void test_vfs_alive_counter(void **state)
{
    fixture_t *fx = *state;
    for (int k = 0; k < 40; ++k) { (void)good_period(fx, &NOMINAL, 0u); }
    uint32_t wraps = 0u;
    for (uint32_t i = 2u; i < tx_log.count; i += 2u) {
        wc_can_vfs_command_phys_t prev;
        wc_can_vfs_command_phys_t next;
        assert_int_equal(tx_log.frames[i - 2u].id, WC_CAN_VFS_COMMAND_FRAME_ID);
        assert_int_equal(tx_log.frames[i].id, WC_CAN_VFS_COMMAND_FRAME_ID);
        assert_int_equal(wc_can_decode_vfs_command(&prev, tx_log.frames[i - 2u].data, 8u), WC_CAN_OK);
        assert_int_equal(wc_can_decode_vfs_command(&next, tx_log.frames[i].data, 8u), WC_CAN_OK);
        WC_CHECK(next.alive_counter == ((prev.alive_counter + 1u) % WC_E2E_COUNTER_MODULO),
                 "frame %u: counter %u after %u", (unsigned)i, (unsigned)next.alive_counter,
                 (unsigned)prev.alive_counter);
        if (next.alive_counter < prev.alive_counter) { wraps++; }
    }
    WC_CHECK(wraps >= 2u, "only %u wraps in 40 frames", (unsigned)wraps);
}

/* Mode Open: the solenoid's minimum current; Locked: its maximum (DBC Mode). */
static void test_mode_open_and_locked(void **state)
{
    fixture_t *fx = *state;
    const wc_calibration_t *cal = &wc_table1_calibration;
    const uint8_t modes[] = { MODE_OPEN, MODE_LOCKED, MODE_TORQUE, MODE_LOCKED, MODE_OPEN };
    for (size_t m = 0u; m < WC_TEST_COUNT(modes); ++m) {
        for (int k = 0; k < 20; ++k) {
            period_t p = NOMINAL;
            p.mode = modes[m];
            (void)good_period(fx, &p, 0u);  /* against the reference, no loop bits */
            wc_can_vfs_command_phys_t cmd;
            wc_can_clutch_estimate_phys_t est;
            last_outputs(&cmd, &est);
            /* tolerance: one raw step, 1/32 mA */
            if (modes[m] == MODE_OPEN) {
                WC_CHECK_CLOSE("Open: minimum current", k, cmd.vfs_current_mA, cal->vfs_current_min_mA, 0.0,
                               (double)wc_can_sig_vfs_command_vfs_current.scale);
            } else if (modes[m] == MODE_LOCKED) {
                WC_CHECK_CLOSE("Locked: maximum current", k, cmd.vfs_current_mA, cal->vfs_current_max_mA, 0.0,
                               (double)wc_can_sig_vfs_command_vfs_current.scale);
                /* tolerance: one raw step, 1/16 kPa */
                WC_CHECK_CLOSE("Locked: pressure K i_max", k, cmd.pressure_command_kPa,
                               1e-3 * (double)cal->vfs_gain_Pa_per_mA * (double)cal->vfs_current_max_mA, 0.0,
                               (double)wc_can_sig_vfs_command_pressure_command.scale);
            }
        }
    }
}

/* A missed deadline is flagged in the next VfsCommand only, and counted. */
static void test_deadline_miss_flag(void **state)
{
    fixture_t *fx = *state;
    (void)good_period(fx, &NOMINAL, 0u);
    wc_loop_deadline_missed(&fx->loop, 3u);
    (void)good_period(fx, &NOMINAL, WC_CAN_STATUS_DEADLINE_MISS);
    (void)good_period(fx, &NOMINAL, 0u);
    assert_int_equal(fx->loop.counters.deadline_misses, 3u);
}

/* ======================================================================== */
/* Bench mode                                                               */
/* ======================================================================== */

/* * A fresh BenchMeasurement replaces the modelled apply force in the torque
 * model (the paper's validation); stale, the modelled VFS pressure is back.
 * Expectations from wc_torque at the force the policy names, with the
 * loop's own temperature estimate of that step. */

static void bench_period(fixture_t *fx, const float *load_N)
{
    good_request(fx, NOMINAL.torque_Nm, NOMINAL.mode);
    if (load_N != NULL) {
        wc_can_frame_t b = empty_frame(WC_CAN_BENCH_MEASUREMENT_FRAME_ID);
        const wc_can_bench_measurement_phys_t m = { *load_N, 100.0f, 60.0f };
        assert_int_equal(wc_can_encode_bench_measurement(b.data, &m, sizeof b.data), WC_CAN_OK);
        port_deliver(&b);
    }
    good_sensors(fx, NOMINAL.slip_rpm, NOMINAL.oil_degC, NOMINAL.housing_degC);
    run_steps(&fx->loop, 1u);
}

static void check_model_torque_at(const fixture_t *fx, long k, float force_N)
{
    wc_torque_t t;
    assert_int_equal(wc_torque(&fx->loop.clutch.model, NOMINAL.slip_rpm * WC_RAD_S_PER_RPM, fx->loop.last.theta_degC,
                               force_N, &t), WC_STATUS_OK);
    wc_can_vfs_command_phys_t cmd;
    wc_can_clutch_estimate_phys_t est;
    last_outputs(&cmd, &est);
    /* tolerance: one raw step of ModelTorque (0.1 Nm); same float arithmetic otherwise */
    WC_CHECK_CLOSE("ModelTorque at the policy's force", k, est.model_torque_Nm, t.torque_Nm, 0.0,
                   (double)wc_can_sig_clutch_estimate_model_torque.scale);
}

static void test_bench_force_replaces_modelled_force(void **state)
{
    fixture_t *fx = *state;
    wc_loop_config_t bench_config = config_no_debounce;
    bench_config.bench_input_enabled = true;  /* wc_tcu --bench */
    fixture_init_with(fx, &bench_config);
    const wc_calibration_t *cal = &wc_table1_calibration;
    for (int k = 0; k < 5; ++k) { bench_period(fx, NULL); }
    const float load_N = 1188.0f;
    for (long k = 0; k < 30; ++k) {
        const float theta_before = fx->loop.clutch.theta_degC;
        bench_period(fx, &load_N);
        check_model_torque_at(fx, k, 1188.0f);  /* 0.1 N/bit: 1188 N is exact */
        /* The observer's heat input is the measured torque (100 Nm in bench_period). */
        float theta_expected = theta_before;
        assert_int_equal(wc_thermal_step(&fx->loop.clutch.model, &theta_expected,
                                         fabsf(100.0f * fx->loop.sensors.slip_speed_rpm * WC_RAD_S_PER_RPM),
                                         fx->loop.sensors.oil_temp_degC, fx->loop.sensors.housing_temp_degC),
                         WC_STATUS_OK);
        /* same float operations in the same order: equal to within float rounding of one step */
        WC_CHECK(fabsf(fx->loop.clutch.theta_degC - theta_expected) < 1e-5f,
                 "step %ld: observer %g, expected with the measured torque %g", k,
                 (double)fx->loop.clutch.theta_degC, (double)theta_expected);
    }
    /* The modelled force differs clearly, so a loop ignoring the bench fails above. */
    const float modelled_N = wc_contact_force_N(cal, fx->loop.clutch.pressure_model_Pa);
    WC_CHECK(fabsf(modelled_N - load_N) > 50.0f, "modelled force %g N too close to the load %g N",
             (double)modelled_N, (double)load_N);
    /* A negative reading (noise at zero load) counts as 0 N. */
    const float negative_N = -3.0f;
    bench_period(fx, &negative_N);
    check_model_torque_at(fx, 100, 0.0f);
    /* Bench frames stop: fresh for sensor_timeout periods, then the modelled pressure. */
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    for (uint32_t k = 0u; k + 1u < config.sensor_timeout_periods; ++k) {
        bench_period(fx, NULL);
        check_model_torque_at(fx, 200 + (long)k, 0.0f);
    }
    for (long k = 0; k < 5; ++k) {
        bench_period(fx, NULL);
        check_model_torque_at(fx, 300 + k, wc_contact_force_N(cal, fx->loop.clutch.pressure_model_Pa));
        wc_can_vfs_command_phys_t cmd;
        wc_can_clutch_estimate_phys_t est;
        last_outputs(&cmd, &est);
        WC_CHECK((cmd.status & (WC_CAN_STATUS_SAFE_STATE_ACTIVE | WC_CAN_STATUS_IMPLAUSIBLE_INPUT |
                                WC_CAN_STATUS_BENCH_INPUT)) == 0u,
                 "bench staleness must not raise a fault, and the bench is no longer used (status 0x%x)",
                 (unsigned)cmd.status);
    }
    assert_int_equal(fx->loop.counters.rejected[WC_REJECT_UNKNOWN_ID], 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_torque_control_outputs, setup),
        cmocka_unit_test_setup(test_vfs_alive_counter, setup),
        cmocka_unit_test_setup(test_mode_open_and_locked, setup),
        cmocka_unit_test_setup(test_deadline_miss_flag, setup),
        cmocka_unit_test_setup(test_bench_force_replaces_modelled_force, setup),
    };
    return cmocka_run_group_tests_name("wc_loop_control", tests, NULL, NULL);
}
