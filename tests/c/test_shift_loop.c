/* Shift mode in the CAN frame loop (include/wetclutch_can/wc_loop.h,
 * src/can/wc_loop.c; DESIGN section 10): TorqueRequest Mode 3 and
 * ShiftCommand frames from the generated codec, the shift on the plant of
 * wc_test_fixtures.h, the ShiftReport frame, a stale command, the safe state
 * after a shift, leaving Shift mode, Mode 3 without a shift calibration. */
#include "wc_test_shift_harness.h"

/* A step in which a shift ends: the cyclic frames and ShiftReport (adaptation off: no AdaptationReport). */
#define REPORT_FRAMES (WC_LOOP_TX_CYCLIC + 1u)

#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_loop.h"

/* ======================================================================== */
/* Frame loop in Shift mode                                                  */
/* ======================================================================== */

typedef struct {
    wc_loop_t loop;
    uint8_t alive;
    float slip_rad_s;
    bool offgoing_released;
    uint32_t reports;
    uint32_t steps;
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    uint32_t n;
    wc_can_shift_report_phys_t last_report;
    wc_can_vfs_command_phys_t vfs;
} loop_sim_t;

static void loop_queue_sensors(loop_sim_t *l)
{
    wc_can_frame_t f;
    assert_true(wc_test_shift_sensors_frame(&f, l->slip_rad_s, l->alive) <= WC_CAN_SATURATED);
    assert_true(wc_loop_receive(&l->loop, &f));
}

static void loop_queue_request(loop_sim_t *l, uint8_t mode)
{
    wc_can_frame_t f;
    assert_int_equal(wc_test_shift_request_frame(&f, mode, l->alive), WC_CAN_OK);
    assert_true(wc_loop_receive(&l->loop, &f));
}

static void loop_queue_command(loop_sim_t *l, bool request, float turbine_torque_Nm, float target_ms)
{
    wc_can_frame_t f;
    assert_int_equal(wc_test_shift_command_frame(&f, request, turbine_torque_Nm, target_ms, l->alive), WC_CAN_OK);
    assert_true(wc_loop_receive(&l->loop, &f));
}

/* One period: the frames asked for, one step, the plant. */
static void loop_period(loop_sim_t *l, bool sensors, int mode, int shift_request)
{
    if (sensors) { loop_queue_sensors(l); }
    if (mode >= 0) { loop_queue_request(l, (uint8_t)mode); }
    if (shift_request >= 0) { loop_queue_command(l, shift_request != 0, TURBINE_TORQUE_Nm, 1000.0f * TARGET_TIME_s); }
    l->alive = wc_e2e_counter_next(l->alive);
    memset(l->out, 0xA5, sizeof l->out);
    l->n = wc_loop_step(&l->loop, l->out);
    l->steps++;
    WC_CHECK((l->n == WC_LOOP_TX_CYCLIC) || (l->n == REPORT_FRAMES), "%u frames", (unsigned)l->n);
    assert_int_equal(l->out[0].id, WC_CAN_VFS_COMMAND_FRAME_ID);
    assert_int_equal(l->out[1].id, WC_CAN_CLUTCH_ESTIMATE_FRAME_ID);
    wc_can_vfs_command_phys_t vfs;
    assert_true(wc_can_decode_vfs_command(&vfs, l->out[0].data, l->out[0].dlc) <= WC_CAN_SATURATED);
    l->vfs = vfs;
    if (l->n == REPORT_FRAMES) {
        assert_int_equal(l->out[2].id, WC_CAN_SHIFT_REPORT_FRAME_ID);
        assert_int_equal(l->out[2].dlc, WC_CAN_SHIFT_REPORT_LENGTH);
        assert_int_equal(l->out[2].flags, 0u);
        assert_true(wc_can_decode_shift_report(&l->last_report, l->out[2].data, l->out[2].dlc) <= WC_CAN_SATURATED);
        l->reports++;
    }
    /* plant, as in sim_step, on the loop's clutch output */
    if (l->loop.shift.phase == (uint32_t)WC_SHIFT_INERTIA) { l->offgoing_released = true; }
    if (l->offgoing_released) {
        l->slip_rad_s =
            wc_test_shift_plant_slip_rad_s(&test_cal, l->slip_rad_s, TURBINE_TORQUE_Nm, &l->loop.last, DT_s);
    }
}

static void loop_start(loop_sim_t *l, const wc_shift_calibration_t *cal)
{
    memset(l, 0, sizeof *l);
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = cal;
    assert_int_equal(wc_loop_init(&l->loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
    l->slip_rad_s = START_SLIP_rad_s;
    /* Shift mode, request 0, until the safe state is over (E2E sync + recovery) */
    for (uint32_t k = 0u; k < WC_TEST_SHIFT_LOOP_SETTLE_PERIODS; ++k) {
        loop_period(l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 0);
    }
    WC_CHECK((l->vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "still in the safe state: status %x",
             (unsigned)l->vfs.status);
    assert_int_equal(l->reports, 0u);
}

/* A value and its decoded frame: one raw step of the DBC scaling, plus the
 * saturation to the signal's range. */
static void check_signal(const char *what, float decoded, double expected, double lo, double hi, double step)
{
    const double clamped = (expected < lo) ? lo : ((expected > hi) ? hi : expected);
    WC_CHECK_CLOSE(what, 0, decoded, clamped, 0.0, step);
}

static void test_loop_shift_report(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    uint32_t report_step = 0u;
    for (int k = 0; k < 2000; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        if (l.n == REPORT_FRAMES) { report_step = l.steps; }
        WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "safe state during the shift");
    }
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    print_message("    loop: report at step %u\n", (unsigned)report_step);
    const wc_shift_report_t *q = &l.loop.report;
    print_report("loop shift", q);
    assert_int_equal(q->abort_reason, WC_SHIFT_ABORT_NONE);
    assert_int_equal(l.last_report.abort_reason, WC_SHIFT_ABORT_NONE);
    check_signal("InertiaPhaseTime", l.last_report.inertia_phase_time_ms, 1000.0 * (double)q->inertia_time_s, 0.0, 4000.0,
                 1.0);
    check_signal("SlipRmse", l.last_report.slip_rmse_rpm, (double)q->slip_rmse_rad_s / (double)WC_RAD_S_PER_RPM, 0.0,
                 500.0, 0.5);
    check_signal("PeakJerk", l.last_report.peak_jerk_m_per_s3, (double)q->peak_jerk_m_s3, 0.0, 100.0, 0.1);
    check_signal("FrictionEnergy", l.last_report.friction_energy_kJ, 1e-3 * (double)q->friction_energy_J, 0.0, 40.0, 0.01);
    check_signal("PeakClutchTemp", l.last_report.peak_clutch_temp_degC, (double)q->peak_theta_degC, -40.0, 350.0, 0.1);
    check_signal("Flare", l.last_report.flare, q->flare ? 1.0 : 0.0, 0.0, 1.0, 0.0);
    check_signal("TieUp", l.last_report.tie_up, q->tie_up ? 1.0 : 0.0, 0.0, 1.0, 0.0);
    WC_CHECK((q->inertia_time_s >= 0.9f * TARGET_TIME_s) && (q->inertia_time_s <= 1.15f * TARGET_TIME_s),
             "inertia time %g s", (double)q->inertia_time_s);
    assert_int_equal(l.loop.counters.frames_out, 2u * l.steps + 1u);
    /* the request withdrawn after LOCKED: idle, no report */
    for (int k = 0; k < 50; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 0); }
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
}

/* A figure beyond its DBC range goes out at the limit with Saturated 1
 * (issue 29 item 7: a peak jerk of 117-131 m/s^3 was sent as 100, unflagged);
 * within every range Saturated is 0. */
static void test_shift_report_saturation_is_flagged(void **state)
{
    (void)state;
    wc_shift_report_t q;
    memset(&q, 0, sizeof q);
    q.inertia_time_s = 0.4f;
    q.slip_rmse_rad_s = 2.0f;
    q.peak_jerk_m_s3 = 60.0f;
    q.friction_energy_J = 3000.0f;
    q.peak_theta_degC = 120.0f;
    wc_can_frame_t frame;
    wc_can_shift_report_phys_t r;
    wc_loop_shift_report_frame(&q, &frame);
    assert_int_equal(frame.id, WC_CAN_SHIFT_REPORT_FRAME_ID);
    assert_false(wc_can_is_error(wc_can_decode_shift_report(&r, frame.data, frame.dlc)));
    assert_float_equal(r.peak_jerk_m_per_s3, 60.0f, 0.05f);  /* tolerance: half the signal's 0.1 m/s^3 step */
    assert_float_equal(r.saturated, 0.0f, 0.0f);
    q.peak_jerk_m_s3 = 125.0f;                                /* the probe's figure, above the 100 m/s^3 range */
    wc_loop_shift_report_frame(&q, &frame);
    assert_false(wc_can_is_error(wc_can_decode_shift_report(&r, frame.data, frame.dlc)));
    assert_float_equal(r.peak_jerk_m_per_s3, 100.0f, 0.05f);
    assert_float_equal(r.saturated, 1.0f, 0.0f);
    q.peak_jerk_m_s3 = 60.0f;
    q.friction_energy_J = 45.0e3f;                            /* above the 40 kJ range */
    wc_loop_shift_report_frame(&q, &frame);
    assert_false(wc_can_is_error(wc_can_decode_shift_report(&r, frame.data, frame.dlc)));
    assert_float_equal(r.saturated, 1.0f, 0.0f);
}

static void test_loop_shift_command_stale(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    while (l.loop.shift.phase != (uint32_t)WC_SHIFT_INERTIA) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        assert_true(l.steps < 1000u);
    }
    for (int k = 0; k < 50; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1); }
    /* ShiftCommand stops: stale after request_timeout_periods (10) */
    uint32_t first_timeout = 0u;
    for (uint32_t k = 1u; k <= 30u; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, -1);
        if ((first_timeout == 0u) && ((l.vfs.status & WC_CAN_STATUS_REQUEST_TIMEOUT) != 0u)) {
            first_timeout = k;
            WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "timeout without the safe state");
            WC_CHECK(fabsf(l.vfs.vfs_current_mA - wc_table1_calibration.vfs_current_min_mA) <= 0.5f,
                     "safe state current %g mA", (double)l.vfs.vfs_current_mA);
            assert_int_equal(l.n, REPORT_FRAMES);  /* the aborted shift's report, in the same step */
            assert_int_equal(l.last_report.abort_reason, WC_SHIFT_ABORT_INPUT_LOST);
        }
    }
    WC_CHECK((first_timeout >= 10u) && (first_timeout <= 12u), "StatusRequestTimeout after %u periods",
             (unsigned)first_timeout);
    assert_int_equal(l.reports, 1u);
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_ABORTED);
    WC_CHECK(l.loop.counters.request_timeouts >= 1u, "request timeout not counted");
}

/* The frame loop's safe state after a completed shift (LOCKED, request still 1):
 * the safe-state policy of wc_loop.h is the solenoid's minimum current. */
static void test_loop_safe_state_after_shift_releases(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    for (int k = 0; (k < 2000) && (l.loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED); ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    for (int k = 0; k < 30; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, -1); }
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "no safe state: status %x", (unsigned)l.vfs.status);
    WC_CHECK(fabsf(l.vfs.vfs_current_mA - wc_table1_calibration.vfs_current_min_mA) <= 0.5f,
             "StatusSafeStateActive with %g mA (shift phase %u): the safe state must be the minimum current",
             (double)l.vfs.vfs_current_mA, (unsigned)l.loop.shift.phase);
}

/* After a completed shift the VCU hands the clutch back (Mode 2, Locked):
 * the very first period in the new mode commands it (maximum current), with
 * no period of the shift controller's released output in between (a 1 ms dip
 * to the minimum current on the solenoid). */
static void test_loop_leaving_shift_mode_after_the_shift_has_no_dip(void **state)
{
    (void)state;
    static loop_sim_t l;
    loop_start(&l, &test_cal);
    for (int k = 0; (k < 2000) && (l.loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED); ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_LOCKED);
    const float max_mA = wc_table1_calibration.vfs_current_max_mA;
    for (int k = 0; k < 20; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE, 0);
        WC_CHECK(fabsf(l.vfs.vfs_current_mA - max_mA) <= 0.5f, "period %d in Locked mode: %g mA, not the maximum %g",
                 k, (double)l.vfs.vfs_current_mA, (double)max_mA);
        assert_int_equal(l.n, WC_LOOP_TX_CYCLIC);  /* no second report */
    }
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
}

static void test_loop_mode3_without_shift(void **state)
{
    (void)state;
    static loop_sim_t l;
    memset(&l, 0, sizeof l);
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    assert_int_equal(wc_loop_init(&l.loop, &wc_table1_calibration, &config, THETA_OIL_degC), WC_CAL_OK);
    l.slip_rad_s = START_SLIP_rad_s;
    /* torque control first, out of the safe state */
    for (int k = 0; k < 40; ++k) { loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, -1); }
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) == 0u, "safe state: %x", (unsigned)l.vfs.status);
    const uint32_t implausible = l.loop.counters.rejected[WC_REJECT_IMPLAUSIBLE];
    const uint32_t unknown = l.loop.counters.rejected[WC_REJECT_UNKNOWN_ID];
    const uint32_t sync0 = l.loop.counters.rejected[WC_REJECT_SYNC];
    const uint32_t used0 = l.loop.counters.frames_used;
    /* mode 3 (and ShiftCommand frames) without config.shift */
    for (int k = 0; k < 30; ++k) {
        loop_period(&l, true, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, 1);
        if (k == 0) {
            WC_CHECK((l.vfs.status & WC_CAN_STATUS_IMPLAUSIBLE_INPUT) != 0u, "mode 3 not flagged implausible");
        }
        assert_int_equal(l.n, WC_LOOP_TX_CYCLIC);
    }
    /* every TorqueRequest rejected: implausible, except the SyncCounter (3)
     * frames after the request's timeout restarted its E2E receiver */
    const uint32_t n_implausible = l.loop.counters.rejected[WC_REJECT_IMPLAUSIBLE] - implausible;
    const uint32_t n_sync = l.loop.counters.rejected[WC_REJECT_SYNC] - sync0;
    WC_CHECK((n_implausible + n_sync == 30u) && (n_sync <= 3u), "%u implausible, %u sync", (unsigned)n_implausible,
             (unsigned)n_sync);
    assert_int_equal(l.loop.counters.frames_used - used0, 30u);  /* the sensor frames only */
    assert_int_equal(l.loop.counters.rejected[WC_REJECT_UNKNOWN_ID] - unknown, 30u);
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_REQUEST_TIMEOUT) != 0u, "the rejected requests did not time out");
    WC_CHECK((l.vfs.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u, "no safe state");
    assert_int_equal(l.loop.shift.phase, WC_SHIFT_IDLE);
    assert_int_equal(l.reports, 0u);
}

/* ======================================================================== */
/* Adaptation in the loop (DESIGN 12): AdaptationReport, the hook, the reset */
/* ======================================================================== */

typedef struct {
    uint32_t calls;
    wc_adapt_values_t values;  /* as the hook saw them */
} hook_log_t;

static void adaptation_hook(const wc_adapt_t *adapt, void *context)
{
    hook_log_t *log = context;
    log->calls++;
    log->values = adapt->values;
}

/* One period of the adaptive loop on a plant whose clutch gives friction_factor
 * times the model's torque; reset: ShiftCommand.AdaptationReset. Returns the
 * frames sent; *adaptation the decoded AdaptationReport when there was one. */
static uint32_t adaptive_period(loop_sim_t *l, int shift_request, bool reset, float friction_factor,
                                wc_can_adaptation_report_phys_t *adaptation, bool *had_adaptation)
{
    loop_queue_sensors(l);
    loop_queue_request(l, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE);
    wc_can_frame_t f = wc_test_can_frame(WC_CAN_SHIFT_COMMAND_FRAME_ID);
    const wc_can_shift_command_phys_t c = { shift_request ? 1.0f : 0.0f, reset ? 1.0f : 0.0f, 2.0f, TURBINE_TORQUE_Nm,
                                            1000.0f * TARGET_TIME_s, 1.0f, l->alive };
    assert_int_equal(wc_can_encode_shift_command(f.data, &c, sizeof f.data), WC_CAN_OK);
    assert_true(wc_loop_receive(&l->loop, &f));
    l->alive = wc_e2e_counter_next(l->alive);
    l->n = wc_loop_step(&l->loop, l->out);
    *had_adaptation = false;
    for (uint32_t i = WC_LOOP_TX_CYCLIC; i < l->n; ++i) {
        if (l->out[i].id == WC_CAN_ADAPTATION_REPORT_FRAME_ID) {
            assert_true(wc_can_decode_adaptation_report(adaptation, l->out[i].data, l->out[i].dlc) <= WC_CAN_SATURATED);
            *had_adaptation = true;
        }
    }
    if (l->loop.shift.phase == (uint32_t)WC_SHIFT_INERTIA) { l->offgoing_released = true; }
    if (l->offgoing_released) {
        wc_step_output_t plant = l->loop.last;
        plant.model.torque_Nm *= friction_factor;  /* the real clutch: more friction than the model */
        l->slip_rad_s = wc_test_shift_plant_slip_rad_s(&test_cal, l->slip_rad_s, TURBINE_TORQUE_Nm, &plant, DT_s);
    }
    return l->n;
}

static void test_loop_adaptation_report_hook_and_reset(void **state)
{
    (void)state;
    static loop_sim_t l;
    static wc_shift_calibration_t adaptive;
    adaptive = test_cal;
    adaptive.adaptation = 1u;
    loop_start(&l, &adaptive);
    static hook_log_t log;
    memset(&log, 0, sizeof log);
    l.loop.config.adaptation_changed = adaptation_hook;
    l.loop.config.adaptation_context = &log;
    assert_int_equal(wc_loop_load_adaptation(&l.loop, NULL, 0u), WC_IMAGE_MISSING);
    wc_can_adaptation_report_phys_t a;
    bool had = false;
    uint32_t reports = 0u;
    for (int k = 0; (k < 2000) && (reports == 0u); ++k) {
        /* AdaptationReset rises during the shift (k 200: running): ignored, no reset */
        const uint32_t n = adaptive_period(&l, 1, k >= 200, 1.2f, &a, &had);
        if (had) {
            reports++;
            assert_int_equal(n, WC_LOOP_TX_CYCLIC + 2u);  /* VfsCommand, ClutchEstimate, ShiftReport, AdaptationReport */
            assert_int_equal(l.out[2].id, WC_CAN_SHIFT_REPORT_FRAME_ID);
        }
    }
    assert_int_equal(reports, 1u);
    assert_int_equal(l.loop.report.abort_reason, WC_SHIFT_ABORT_NONE);
    /* a clutch 20 % stronger than the model: the scale rises, by at most the per-shift step */
    const wc_adapt_change_t *change = &l.loop.report.adaptation;
    assert_int_equal(change->result, WC_ADAPT_RESULT_UPDATED);
    WC_CHECK((change->friction_scale_change > 0.0f) && (change->friction_scale_change <= adaptive.adapt_scale_step),
             "scale change %g (step %g)", (double)change->friction_scale_change, (double)adaptive.adapt_scale_step);
    assert_float_equal(a.result, 1.0f, 0.0f);
    assert_float_equal(a.image_missing, 1.0f, 0.0f);
    assert_float_equal(a.friction_scale, change->friction_scale, 0.0005f);        /* one raw step (DBC) */
    assert_float_equal(a.friction_scale_change, change->friction_scale_change, 0.00025f);
    assert_int_equal(log.calls, 1u);
    assert_memory_equal(&log.values, &l.loop.adapt.values, sizeof log.values);
    print_message("    adaptation: node %u scale %.4f (+%.4f), confidence %.2f\n", (unsigned)change->node,
                  (double)change->friction_scale, (double)change->friction_scale_change, (double)change->confidence);
    /* the reset's edge came during the shift: nothing reset */
    assert_true(l.loop.adapt.values.friction_scale[change->node] > 1.0f);
    /* the request withdrawn, the reset bit dropped, then raised: a reset, reported and stored */
    for (int k = 0; k < 5; ++k) { (void)adaptive_period(&l, 0, false, 1.2f, &a, &had); assert_false(had); }
    (void)adaptive_period(&l, 0, true, 1.2f, &a, &had);
    assert_true(had);
    assert_float_equal(a.result, 0.0f, 0.0f);
    assert_float_equal(a.friction_scale, 1.0f, 0.0f);
    assert_int_equal(log.calls, 2u);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) { assert_float_equal(log.values.friction_scale[i], 1.0f, 0.0f); }
    assert_true((l.loop.adapt.status & WC_ADAPT_STATUS_RESET) != 0u);
    (void)adaptive_period(&l, 0, true, 1.2f, &a, &had);  /* held: no second reset */
    assert_false(had);
    assert_int_equal(log.calls, 2u);
    /* a diagnostic tester's request (UDS routine 0x0201): taken at the next step, reported and stored once */
    assert_true(wc_loop_request_adaptation_reset(&l.loop));
    (void)adaptive_period(&l, 0, false, 1.2f, &a, &had);
    assert_true(had);
    assert_float_equal(a.result, 0.0f, 0.0f);
    assert_int_equal(log.calls, 3u);
    assert_false(l.loop.adaptation_reset_requested);
    (void)adaptive_period(&l, 0, false, 1.2f, &a, &had);
    assert_false(had);
    /* refused while a shift runs, and without adaptation */
    for (int k = 0; (k < 50) && !wc_shift_phase_running(l.loop.shift.phase); ++k) {
        (void)adaptive_period(&l, 1, false, 1.2f, &a, &had);
    }
    assert_true(wc_shift_phase_running(l.loop.shift.phase));
    assert_false(wc_loop_request_adaptation_reset(&l.loop));
    static loop_sim_t plain;
    loop_start(&plain, &test_cal);  /* adaptation 0 */
    assert_false(wc_loop_request_adaptation_reset(&plain.loop));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_loop_shift_report),
        cmocka_unit_test(test_shift_report_saturation_is_flagged),
        cmocka_unit_test(test_loop_shift_command_stale),
        cmocka_unit_test(test_loop_safe_state_after_shift_releases),
        cmocka_unit_test(test_loop_leaving_shift_mode_after_the_shift_has_no_dip),
        cmocka_unit_test(test_loop_mode3_without_shift),
        cmocka_unit_test(test_loop_adaptation_report_hook_and_reset),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
