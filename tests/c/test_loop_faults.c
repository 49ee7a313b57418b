/* Fault-injection matrix of the CAN frame loop with its default configuration
 * (timeout 10 periods, MaxDeltaCounter 2, SyncCounter 3, recovery 20
 * periods): for each fault, the period the loop reacts in, its output while
 * the fault lasts, and the period it recovers in, against the safe-state
 * table of docs/integrating.md (DESIGN.md section 8). The loop runs on a
 * timer clock (one step per period whatever arrives), the sender is a
 * well-behaved VCU and sensor front end except for the injected fault.
 *
 * Periods are counted from 0; "reaction" is the number of periods from the
 * first faulty period to the first period with StatusSafeStateActive, and
 * "recovery" from the first good period to the first period without it. */
#include "wc_test_support.h"

#include <stdio.h>

#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_loop.h"

#define T_TIMEOUT 10u   /* WC_LOOP_CONFIG_DEFAULT sensor/request timeout */
#define T_SYNC 3u       /* SyncCounter */
#define T_RECOVERY 20u  /* recovery_periods */
#define MAX_PERIODS 2400

/* What the sender does in one period. */
typedef enum {
    SEND_GOOD = 0,      /* valid frame, counter +1 */
    SEND_NONE,          /* no frame */
    SEND_CRC,           /* a bit flipped after the CRC: counter +1 consumed */
    SEND_REPEAT,        /* the previous counter again */
    SEND_JUMP,          /* counter +5 (more than MaxDeltaCounter) */
    SEND_PLUS2,         /* counter +2 every frame */
    SEND_SNA,           /* the first scaled signal SNA (NaN encoded), counter +1 */
    SEND_RESERVED_MODE  /* TorqueRequest Mode 7 (reserved), counter +1 */
} send_t;

typedef struct {
    wc_loop_t loop;
    uint8_t sensors_alive;
    uint8_t request_alive;
    uint16_t status[MAX_PERIODS];
    float current_mA[MAX_PERIODS];
    int periods;
} run_t;

static run_t run;  /* the loop holds its ring: static storage */

static void start(const wc_loop_config_t *config)
{
    memset(&run, 0, sizeof run);
    assert_int_equal(wc_loop_init(&run.loop, &wc_table1_calibration, config, 60.0f), WC_CAL_OK);
}

static uint8_t next_counter(uint8_t *alive, send_t how)
{
    const uint8_t previous = (uint8_t)((*alive + 15u) % 16u);
    switch (how) {
    case SEND_REPEAT: return previous;
    case SEND_JUMP: *alive = (uint8_t)((*alive + 5u) % 16u); break;
    case SEND_PLUS2: *alive = (uint8_t)((*alive + 1u) % 16u); break;
    default: break;
    }
    const uint8_t c = *alive;
    *alive = wc_e2e_counter_next(*alive);
    return c;
}

static void deliver(const wc_can_frame_t *f)
{
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    assert_int_equal(wc_loop_iterate(&run.loop, WC_LOOP_CLOCK_TIMER, f, false, out), 0u);
}

static void send_sensors(send_t how, float slip_rpm)
{
    if (how == SEND_NONE) { return; }
    wc_can_frame_t f = { WC_CAN_CLUTCH_SENSORS_FRAME_ID, 8u, 0u, { 0u } };
    const wc_can_clutch_sensors_phys_t s = { (how == SEND_SNA) ? NAN : slip_rpm, 60.0f, 55.0f,
                                             next_counter(&run.sensors_alive, how) };
    (void)wc_can_encode_clutch_sensors(f.data, &s, sizeof f.data);
    if (how == SEND_CRC) { f.data[3] ^= 0x10u; }
    deliver(&f);
}

static void send_request(send_t how, float torque_Nm)
{
    if (how == SEND_NONE) { return; }
    wc_can_frame_t f = { WC_CAN_TORQUE_REQUEST_FRAME_ID, 8u, 0u, { 0u } };
    const wc_can_torque_request_phys_t q = { (how == SEND_SNA) ? NAN : torque_Nm,
                                             (how == SEND_RESERVED_MODE) ? 7u : (uint8_t)WC_MODE_TORQUE,
                                             next_counter(&run.request_alive, how) };
    (void)wc_can_encode_torque_request(f.data, &q, sizeof f.data);
    if (how == SEND_CRC) { f.data[3] ^= 0x01u; }
    deliver(&f);
}

/* One period: the frames, then the timer tick; records the VfsCommand. */
static void period(send_t sensors, send_t request)
{
    assert_true(run.periods < MAX_PERIODS);
    send_request(request, 150.0f);
    send_sensors(sensors, 500.0f);
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    assert_int_equal(wc_loop_iterate(&run.loop, WC_LOOP_CLOCK_TIMER, NULL, true, out), WC_LOOP_TX_CYCLIC);
    wc_can_vfs_command_phys_t cmd;
    assert_int_equal(wc_can_decode_vfs_command(&cmd, out[0].data, out[0].dlc), WC_CAN_OK);
    run.status[run.periods] = cmd.status;
    run.current_mA[run.periods] = cmd.vfs_current_mA;
    run.periods++;
}

static bool safe_at(int k) { return (run.status[k] & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u; }

/* Periods from `from` to the first one whose safe state is `safe`, or -1. */
static int periods_until(int from, bool safe)
{
    for (int k = from; k < run.periods; ++k) {
        if (safe_at(k) == safe) { return k - from; }
    }
    return -1;
}

static int safe_transitions(int from, int to)
{
    int n = 0;
    for (int k = from + 1; k < to; ++k) { n += (safe_at(k) != safe_at(k - 1)) ? 1 : 0; }
    return n;
}

/* While safe: the solenoid's minimum current (one raw step, 1/32 mA). */
static void check_safe_output(int from, int to)
{
    for (int k = from; k < to; ++k) {
        WC_CHECK(safe_at(k), "period %d: not in the safe state (status 0x%04x)", k, (unsigned)run.status[k]);
        WC_CHECK_CLOSE("safe current", k, run.current_mA[k], wc_table1_calibration.vfs_current_min_mA, 0.0,
                       (double)wc_can_sig_vfs_command_vfs_current.scale);
    }
}

/* Start-up with both inputs good: control after T_RECOVERY fresh periods. */
static int start_up(void)
{
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    start(&config);
    for (int k = 0; k < 40; ++k) { period(SEND_GOOD, SEND_GOOD); }
    const int control = periods_until(0, false);
    assert_int_equal(control, (int)T_RECOVERY - 1);  /* fresh in periods 0..19: controlling in period 19 */
    return run.periods;
}

typedef struct {
    const char *name;
    send_t sensors;          /* what the faulty input sends while the fault lasts */
    send_t request;
    int fault_periods;
    int reaction;            /* expected periods to the safe state; -1: never */
    int recovery;            /* expected periods from the first good frame to control; -1: no safe state */
    uint16_t bit;            /* a status bit expected in the first faulty period (0: none checked) */
} fault_case_t;

/* Persistent faults on one input: reaction in T_TIMEOUT - 1 periods (the
 * T_TIMEOUT-th period without a used frame), safe state held for as long as
 * the fault lasts, recovery when the sender is good again: its reference frame
 * and SyncCounter - 1 more are not used, then T_RECOVERY fresh periods. */
static const fault_case_t persistent[] = {
    { "sensors stop", SEND_NONE, SEND_GOOD, 200, T_TIMEOUT - 1, T_SYNC + T_RECOVERY - 1, 0u },
    { "request stop", SEND_GOOD, SEND_NONE, 200, T_TIMEOUT - 1, T_SYNC + T_RECOVERY - 1, 0u },
    { "sensors CRC persistent", SEND_CRC, SEND_GOOD, 200, T_TIMEOUT - 1, T_SYNC + T_RECOVERY - 1,
      WC_CAN_STATUS_CRC_ERROR },
    /* frozen: the frozen frames after the timeout already gave the reference, so the
     * sender counting on is in sequence from its first good frame: one period less */
    { "sensors counter frozen", SEND_REPEAT, SEND_GOOD, 500, T_TIMEOUT - 1, T_SYNC + T_RECOVERY - 2,
      WC_CAN_STATUS_COUNTER_ERROR },
    { "request counter frozen", SEND_GOOD, SEND_REPEAT, 500, T_TIMEOUT - 1, T_SYNC + T_RECOVERY - 2,
      WC_CAN_STATUS_COUNTER_ERROR },
    /* +2: the first +2 frame is one lost frame and is used; the timeout runs from it; the
     * +2 frames after the timeout give the reference, as for the frozen sender */
    { "sensors counter +2 every frame", SEND_PLUS2, SEND_GOOD, 500, T_TIMEOUT, T_SYNC + T_RECOVERY - 2, 0u },
    /* implausible frames in sequence keep the receiver synchronised: recovery is the debounce alone
     * (the SyncCounter frames after the timeout restart are implausible ones) */
    { "sensors SNA persistent", SEND_SNA, SEND_GOOD, 200, T_TIMEOUT - 1, T_RECOVERY - 1,
      WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
    { "request SNA persistent", SEND_GOOD, SEND_SNA, 200, T_TIMEOUT - 1, T_RECOVERY - 1,
      WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
    { "request reserved Mode persistent", SEND_GOOD, SEND_RESERVED_MODE, 200, T_TIMEOUT - 1, T_RECOVERY - 1,
      WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
};

/* Single faulty frames: flagged in their period, no safe state at all. */
static const fault_case_t once[] = {
    { "sensors CRC once", SEND_CRC, SEND_GOOD, 1, -1, -1, WC_CAN_STATUS_CRC_ERROR },
    { "request CRC once", SEND_GOOD, SEND_CRC, 1, -1, -1, WC_CAN_STATUS_CRC_ERROR },
    { "sensors counter repeat once", SEND_REPEAT, SEND_GOOD, 1, -1, -1, WC_CAN_STATUS_COUNTER_ERROR },
    { "sensors counter jump once", SEND_JUMP, SEND_GOOD, 1, -1, -1, WC_CAN_STATUS_COUNTER_ERROR },
    { "request counter jump once", SEND_GOOD, SEND_JUMP, 1, -1, -1, WC_CAN_STATUS_COUNTER_ERROR },
    { "sensors SNA once", SEND_SNA, SEND_GOOD, 1, -1, -1, WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
    { "request reserved Mode once", SEND_GOOD, SEND_RESERVED_MODE, 1, -1, -1, WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
};

static void run_case(const fault_case_t *c)
{
    const int f0 = start_up();
    for (int k = 0; k < c->fault_periods; ++k) { period(c->sensors, c->request); }
    const int f1 = run.periods;
    for (int k = 0; k < 80; ++k) { period(SEND_GOOD, SEND_GOOD); }
    if (c->bit != 0u) {
        WC_CHECK((run.status[f0] & c->bit) != 0u, "%s: status 0x%04x lacks 0x%04x in the first faulty period",
                 c->name, (unsigned)run.status[f0], (unsigned)c->bit);
    }
    if (c->reaction < 0) {
        WC_CHECK(periods_until(f0, true) < 0, "%s: safe state entered", c->name);
        printf("    %-34s reaction: none (flagged)          recovery: -\n", c->name);
        return;
    }
    const int reaction = periods_until(f0, true);
    WC_CHECK(reaction == c->reaction, "%s: safe state after %d periods, expected %d", c->name, reaction, c->reaction);
    check_safe_output(f0 + reaction, f1);  /* held for as long as the fault lasts */
    const int recovery = periods_until(f1, false);
    WC_CHECK(recovery == c->recovery, "%s: control back after %d good periods, expected %d", c->name, recovery,
             c->recovery);
    WC_CHECK(safe_transitions(f0, run.periods) == 2, "%s: %d safe-state transitions, expected 2 (in, out)", c->name,
             safe_transitions(f0, run.periods));
    printf("    %-34s reaction: %2d periods (%2d ms)     recovery: %2d periods\n", c->name, reaction, reaction + 1,
           recovery);
}

static void test_persistent_faults(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(persistent); ++i) { run_case(&persistent[i]); }
}

static void test_single_faults(void **state)
{
    (void)state;
    for (size_t i = 0u; i < WC_TEST_COUNT(once); ++i) { run_case(&once[i]); }
}

/* NaN in every signal: the encoder sends SNA for it (the DBC), the loop
 * rejects the frame as implausible; persistent, that is a timeout. */
static void test_nan_in_every_signal(void **state)
{
    (void)state;
    for (int which = 0; which < 4; ++which) {
        const int f0 = start_up();
        for (int k = 0; k < 30; ++k) {
            wc_can_frame_t s = { WC_CAN_CLUTCH_SENSORS_FRAME_ID, 8u, 0u, { 0u } };
            const wc_can_clutch_sensors_phys_t sp = { (which == 0) ? NAN : 500.0f, (which == 1) ? NAN : 60.0f,
                                                      (which == 2) ? NAN : 55.0f,
                                                      next_counter(&run.sensors_alive, SEND_GOOD) };
            (void)wc_can_encode_clutch_sensors(s.data, &sp, sizeof s.data);
            wc_can_frame_t q = { WC_CAN_TORQUE_REQUEST_FRAME_ID, 8u, 0u, { 0u } };
            const wc_can_torque_request_phys_t qp = { (which == 3) ? NAN : 150.0f, (uint8_t)WC_MODE_TORQUE,
                                                      next_counter(&run.request_alive, SEND_GOOD) };
            (void)wc_can_encode_torque_request(q.data, &qp, sizeof q.data);
            deliver(&q);
            deliver(&s);
            wc_can_frame_t out[WC_LOOP_TX_FRAMES];
            (void)wc_loop_iterate(&run.loop, WC_LOOP_CLOCK_TIMER, NULL, true, out);
            wc_can_vfs_command_phys_t cmd;
            assert_int_equal(wc_can_decode_vfs_command(&cmd, out[0].data, out[0].dlc), WC_CAN_OK);
            run.status[run.periods] = cmd.status;
            run.current_mA[run.periods] = cmd.vfs_current_mA;
            run.periods++;
        }
        WC_CHECK(periods_until(f0, true) == (int)T_TIMEOUT - 1, "NaN in signal %d: safe after %d periods", which,
                 periods_until(f0, true));
        check_safe_output(f0 + (int)T_TIMEOUT - 1, run.periods);
    }
}

/* Intermittent sensors (1 frame in 11): the safe state is entered once and
 * held; the solenoid never toggles (DESIGN section 8: no square wave). */
static void test_intermittent_holds_safe_state(void **state)
{
    (void)state;
    const int f0 = start_up();
    for (int k = 0; k < 2000; ++k) { period(((k % 11) == 0) ? SEND_GOOD : SEND_NONE, SEND_GOOD); }
    const int entered = periods_until(f0, true);
    WC_CHECK(entered >= 0, "intermittent sensors: never safe");
    check_safe_output(f0 + entered, run.periods);
    const int transitions = safe_transitions(f0, run.periods);
    assert_int_equal(transitions, 1);
    printf("    intermittent 1 in 11 for 2 s: safe after %d periods, %d transition(s), held\n", entered, transitions);
}

/* A burst of 100 frames in one period (ring 32): the excess is lost and
 * flagged StatusFrameLost in the next VfsCommand; no safe state. An
 * unknown-id flood (20 per period) with good frames: flagged, controlled. */
static void test_burst_and_flood(void **state)
{
    (void)state;
    const int f0 = start_up();
    for (int i = 0; i < 100; ++i) {
        const wc_can_frame_t junk = { 0x7FFu, 8u, 0u, { 0u } };
        deliver(&junk);
    }
    period(SEND_GOOD, SEND_GOOD);  /* its own frames were lost in the full ring */
    WC_CHECK((run.status[f0] & WC_CAN_STATUS_FRAME_LOST) != 0u, "burst: no StatusFrameLost (0x%04x)",
             (unsigned)run.status[f0]);
    WC_CHECK(run.loop.counters.rejected[WC_REJECT_OVERFLOW] == 100u - WC_LOOP_RX_CAPACITY + 2u,
             "burst: %u overflows", (unsigned)run.loop.counters.rejected[WC_REJECT_OVERFLOW]);
    /* the lost frames were a lost counter step each: the next good ones are OKSOMELOST, used */
    for (int k = 0; k < 20; ++k) {
        for (int i = 0; i < 20; ++i) {
            const wc_can_frame_t junk = { 0x555u, 8u, 0u, { 0u } };
            deliver(&junk);
        }
        period(SEND_GOOD, SEND_GOOD);
        WC_CHECK((run.status[run.periods - 1] & WC_CAN_STATUS_FRAME_LOST) != 0u, "flood: no StatusFrameLost");
    }
    WC_CHECK(periods_until(f0, true) < 0, "burst or flood: safe state entered");
}

/* BenchMeasurement frames while bench input is disabled (the default): not
 * used (counted as unknown id, StatusFrameLost), StatusBenchInput never set,
 * and a 5000 Nm "measured torque" does not heat the observer. */
static void test_bench_frames_ignored_when_disabled(void **state)
{
    (void)state;
    const int f0 = start_up();
    const float theta_before = run.loop.clutch.theta_degC;
    for (int k = 0; k < 200; ++k) {
        wc_can_frame_t b = { WC_CAN_BENCH_MEASUREMENT_FRAME_ID, 8u, 0u, { 0u } };
        const wc_can_bench_measurement_phys_t m = { 5000.0f, 5000.0f, 60.0f };
        (void)wc_can_encode_bench_measurement(b.data, &m, sizeof b.data);
        deliver(&b);
        period(SEND_GOOD, SEND_GOOD);
    }
    for (int k = f0; k < run.periods; ++k) {
        WC_CHECK((run.status[k] & WC_CAN_STATUS_BENCH_INPUT) == 0u, "period %d: StatusBenchInput", k);
    }
    assert_int_equal(run.loop.counters.rejected[WC_REJECT_UNKNOWN_ID], 200u);
    /* the model's own heat input at 150 Nm, 500 rpm warms it by a few kelvin, not 250 K */
    WC_CHECK(run.loop.clutch.theta_degC < theta_before + 30.0f, "observer %g degC from %g: bench torque used",
             (double)run.loop.clutch.theta_degC, (double)theta_before);
}

/* A hot clutch: oil 120 degC, slip 300 rad/s, 400 Nm requested for 6 s. The
 * estimate stays in the envelope, StatusOverTemperature comes on once and
 * stays (hysteresis), and the command does not oscillate (issue: 4,626
 * jumps of more than 50 mA before the envelope). */
static void test_over_temperature_no_oscillation(void **state)
{
    (void)state;
    wc_clutch_t clutch;
    assert_int_equal(wc_clutch_init(&clutch, &wc_table1_calibration, 120.0f), WC_CAL_OK);
    const wc_step_input_t in = { 300.0f, 120.0f, 120.0f, 400.0f, WC_MODE_TORQUE, { false, 0.0f, 0.0f }, { 0.0f, 0.0f }, false, 0.0f, { 0.0f, 0.0f, 0.0f }, false };
    wc_step_output_t out;
    float previous_mA = 0.0f;
    int jumps = 0;
    int over_on = -1;
    int over_changes = 0;
    bool over_previous = false;
    for (int k = 0; k < 6000; ++k) {
        const wc_status_t status = wc_clutch_step(&clutch, &in, &out);
        WC_CHECK((status & WC_STATUS_INPUT_INVALID) == 0u, "step %d: input invalid 0x%x", k, (unsigned)status);
        WC_CHECK(clutch.theta_degC <= WC_THETA_MAX_degC, "step %d: %g degC", k, (double)clutch.theta_degC);
        const bool over = (status & WC_STATUS_OVER_TEMPERATURE) != 0u;
        if (over && (over_on < 0)) { over_on = k; }
        if ((k > 0) && (over != over_previous)) { over_changes++; }
        over_previous = over;
        if ((k > 0) && (fabsf(out.current_mA - previous_mA) > 50.0f)) { jumps++; }
        previous_mA = out.current_mA;
    }
    WC_CHECK(over_on >= 0, "never over-temperature (theta %g degC)", (double)clutch.theta_degC);
    assert_int_equal(over_changes, 1);
    assert_int_equal(jumps, 0);
    printf("    hot clutch: over-temperature from step %d, theta %.1f degC at 6 s, %d current jumps > 50 mA\n",
           over_on, (double)clutch.theta_degC, jumps);
    /* cooling: the bit clears only below the threshold minus the hysteresis */
    const wc_step_input_t cool = { 0.0f, 40.0f, 40.0f, 0.0f, WC_MODE_OPEN, { false, 0.0f, 0.0f }, { 0.0f, 0.0f }, false, 0.0f, { 0.0f, 0.0f, 0.0f }, false };
    int cleared = -1;
    for (int k = 0; k < 20000 && cleared < 0; ++k) {
        const wc_status_t status = wc_clutch_step(&clutch, &cool, &out);
        if ((status & WC_STATUS_OVER_TEMPERATURE) == 0u) { cleared = k; }
    }
    WC_CHECK(cleared >= 0, "over-temperature never cleared");
    WC_CHECK(clutch.theta_degC < WC_THETA_OVER_degC - WC_THETA_OVER_HYSTERESIS_K + 0.5f,
             "cleared at %g degC", (double)clutch.theta_degC);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_persistent_faults),
        cmocka_unit_test(test_single_faults),
        cmocka_unit_test(test_nan_in_every_signal),
        cmocka_unit_test(test_intermittent_holds_safe_state),
        cmocka_unit_test(test_burst_and_flood),
        cmocka_unit_test(test_bench_frames_ignored_when_disabled),
        cmocka_unit_test(test_over_temperature_no_oscillation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
