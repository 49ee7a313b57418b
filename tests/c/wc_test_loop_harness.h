/* The shared part of the frame-loop tests (include/wetclutch_can/wc_loop.h,
 * src/can/wc_loop.c) with the port mocked: test_loop_control.c,
 * test_loop_timeouts.c, test_loop_rejections.c, test_loop_determinism.c.
 * Include it instead of wc_test_support.h; it includes
 * lut/wc_table1_calibration.h (one translation unit per test program).
 *
 * The mock port stands in for SocketCAN (src/port/wc_socketcan.c):
 *   mock_port_receive  hands out what a test queued with will_return: a frame
 *                      (PORT_FRAME, then a pointer into the test's script),
 *                      PORT_TICK (a timer deadline passed without a frame) or
 *                      PORT_END (the log is over);
 *   mock_port_send     checks id, DLC and flags of every frame it is asked to
 *                      send against expect_value (VfsCommand, then
 *                      ClutchEstimate, DLC 8, no flags) and records it.
 * drive() runs the main loop of src/port/wc_tcu.c with --clock frame through
 * the same wc_loop_iterate: every received frame is queued, a ClutchSensors
 * frame without flags ends the period (one wc_loop_step) and the step's
 * frames are sent through the port. PORT_TICK steps like a deadline of
 * --clock timer; the tests use it only where a period without any
 * ClutchSensors frame is the point.
 *
 * Frames are built with the generated encoders (wc_can_signals.h); implausible
 * raw values are packed with the generated pack functions and protected with
 * wc_e2e_protect, so that only plausibility fails.
 *
 * Expectations never restate outputs of the C code: every step is replayed
 * on a reference chain built from the lower layers (wc_inverse,
 * wc_vfs_lag_step, wc_contact_force_N, wc_torque, wc_thermal_step) fed with
 * the inputs the documented policy says the loop must use (the last valid
 * frame of each input; Open mode in the safe state), plus one golden inverse
 * vector from the Python reference (tests/vectors/wc_golden_vectors.h). The
 * output frames are decoded with wc_can_decode_*; the tolerance of each signal
 * is one raw step of its DBC scaling. */
#ifndef WC_TEST_LOOP_HARNESS_H
#define WC_TEST_LOOP_HARNESS_H

#include "wc_test_support.h"
#include "wc_test_fixtures.h"

#include "wetclutch_can/wc_loop.h"
#include "wc_table1_calibration.h"

#define THETA_START_degC 40.0f
#define SCRIPT_MAX 4096u  /* frames queued in the mock port at once */
#define TX_LOG_MAX 4096u  /* frames the mock port records */

#define MODE_OPEN WC_CAN_TORQUE_REQUEST_MODE_OPEN_CHOICE
#define MODE_TORQUE WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE
#define MODE_LOCKED WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE

/* The loop's own status bits (everything but the model's Saturated,
 * CurrentClamped and BelowDrag). */
#define LOOP_BITS                                                                                       \
    (WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_REQUEST_TIMEOUT | WC_CAN_STATUS_CRC_ERROR |           \
     WC_CAN_STATUS_COUNTER_ERROR | WC_CAN_STATUS_IMPLAUSIBLE_INPUT | WC_CAN_STATUS_SAFE_STATE_ACTIVE | \
     WC_CAN_STATUS_DEADLINE_MISS)

/* ======================================================================== */
/* Mock port                                                                */
/* ======================================================================== */

enum { PORT_END = -1, PORT_TICK = 0, PORT_FRAME = 1 };

static wc_can_frame_t script[SCRIPT_MAX];  /* frames queued, owned here until received */
static size_t script_len;

typedef struct {
    wc_can_frame_t frames[TX_LOG_MAX];  /* what the loop asked the port to send */
    uint32_t count;
    uint32_t steps;    /* wc_loop_step calls by drive() */
    uint32_t offered;  /* frames given to wc_loop_receive */
    uint32_t refused;  /* ... of which wc_loop_receive returned false */
} tx_log_t;

static tx_log_t tx_log;

static inline void port_reset(void)
{
    script_len = 0u;
    memset(&tx_log, 0, sizeof tx_log);
}

/* The port will deliver this frame (a copy; the script slot outlives the receive). */
static inline void port_deliver(const wc_can_frame_t *frame)
{
    assert_true(script_len < SCRIPT_MAX);
    script[script_len] = *frame;
    will_return(mock_port_receive, PORT_FRAME);
    will_return(mock_port_receive, cast_ptr_to_largest_integral_type(&script[script_len]));
    script_len++;
}

static inline void port_tick(void)
{
    will_return(mock_port_receive, PORT_TICK);
}

static inline int mock_port_receive(wc_can_frame_t *frame)
{
    const int event = mock_type(int);
    if (event == PORT_FRAME) {
        *frame = *mock_ptr_type(const wc_can_frame_t *);
    }
    return event;
}

static inline int mock_port_send(const wc_can_frame_t *frame)
{
    const uint32_t frame_id = frame->id;
    const uint32_t frame_dlc = frame->dlc;
    const uint32_t frame_flags = frame->flags;
    check_expected(frame_id);
    check_expected(frame_dlc);
    check_expected(frame_flags);
    assert_true(tx_log.count < TX_LOG_MAX);
    tx_log.frames[tx_log.count++] = *frame;
    return 0;
}

/* What every step must send (wc_loop.h): VfsCommand, then ClutchEstimate. */
static inline void expect_step_frames(void)
{
    expect_value(mock_port_send, frame_id, WC_CAN_VFS_COMMAND_FRAME_ID);
    expect_value(mock_port_send, frame_dlc, WC_CAN_VFS_COMMAND_LENGTH);
    expect_value(mock_port_send, frame_flags, 0u);
    expect_value(mock_port_send, frame_id, WC_CAN_CLUTCH_ESTIMATE_FRAME_ID);
    expect_value(mock_port_send, frame_dlc, WC_CAN_CLUTCH_ESTIMATE_LENGTH);
    expect_value(mock_port_send, frame_flags, 0u);
}

/* wc_tcu's main loop, --clock frame, until PORT_END: the same
 * wc_loop_iterate that wc_tcu calls, fed by the mocked port. PORT_TICK steps
 * without a frame (the timer clock's deadline). Returns the number of steps. */
static inline uint32_t drive(wc_loop_t *loop)
{
    uint32_t steps = 0u;
    for (;;) {
        wc_can_frame_t frame;
        memset(&frame, 0, sizeof frame);
        const int event = mock_port_receive(&frame);
        if (event == PORT_END) { break; }
        const uint32_t overflows = loop->counters.rejected[WC_REJECT_OVERFLOW];
        wc_can_frame_t out[WC_LOOP_TX_FRAMES];
        memset(out, 0xA5, sizeof out);  /* a field the loop forgets to write shows */
        const bool tick = (event == PORT_TICK);
        if (tick || ((frame.id == WC_CAN_CLUTCH_SENSORS_FRAME_ID) && (frame.flags == 0u))) { expect_step_frames(); }
        const uint32_t n = wc_loop_iterate(loop, WC_LOOP_CLOCK_FRAME, (event == PORT_FRAME) ? &frame : NULL, tick, out);
        if (event == PORT_FRAME) {
            tx_log.offered++;
            if (loop->counters.rejected[WC_REJECT_OVERFLOW] != overflows) { tx_log.refused++; }
        }
        if (n == 0u) { continue; }
        assert_int_equal(n, WC_LOOP_TX_CYCLIC);
        for (uint32_t i = 0u; i < n; ++i) {
            assert_int_equal(mock_port_send(&out[i]), 0);
        }
        steps++;
    }
    tx_log.steps += steps;
    script_len = 0u;  /* everything queued has been received */
    return steps;
}

/* Ends the queued log and drives it; the number of steps must be as given. */
static inline void run_steps(wc_loop_t *loop, uint32_t expected_steps)
{
    will_return(mock_port_receive, PORT_END);
    const uint32_t steps = drive(loop);
    WC_CHECK(steps == expected_steps, "%u steps, expected %u", (unsigned)steps, (unsigned)expected_steps);
}

/* ======================================================================== */
/* Frames                                                                   */
/* ======================================================================== */

/* A frame with the id, DLC 8, no flags, zero data: wc_test_can_frame
 * (wc_test_fixtures.h) under the loop tests' name. */
static inline wc_can_frame_t empty_frame(uint32_t id)
{
    return wc_test_can_frame(id);
}

static inline wc_can_frame_t sensors_frame(float slip_rpm, float oil_degC, float housing_degC, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    const wc_can_clutch_sensors_phys_t s = { slip_rpm, oil_degC, housing_degC, alive };
    assert_int_equal(wc_can_encode_clutch_sensors(f.data, &s, sizeof f.data), WC_CAN_OK);
    return f;
}

static inline wc_can_frame_t request_frame(float torque_Nm, uint8_t mode, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_TORQUE_REQUEST_FRAME_ID);
    const wc_can_torque_request_phys_t q = { torque_Nm, mode, alive };
    assert_int_equal(wc_can_encode_torque_request(f.data, &q, sizeof f.data), WC_CAN_OK);
    return f;
}

/* Raw signal values packed by the generated code, then E2E-protected: the CRC
 * and the counter are right whatever the values. */
static inline wc_can_frame_t raw_sensors_frame(int32_t slip_raw, int32_t oil_raw, int32_t housing_raw, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    struct wc_can_clutch_sensors_t msg;
    assert_int_equal(wc_can_clutch_sensors_init(&msg), 0);
    msg.slip_speed = (int16_t)slip_raw;
    msg.oil_temp = (uint16_t)oil_raw;
    msg.housing_temp = (uint16_t)housing_raw;
    msg.alive_counter = alive;
    assert_int_equal(wc_can_clutch_sensors_pack(f.data, &msg, sizeof f.data), WC_CAN_CLUTCH_SENSORS_LENGTH);
    assert_int_equal(wc_e2e_protect(f.id, f.data, sizeof f.data), WC_E2E_OK);
    return f;
}

static inline wc_can_frame_t raw_request_frame(int32_t torque_raw, uint8_t mode, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_TORQUE_REQUEST_FRAME_ID);
    struct wc_can_torque_request_t msg;
    assert_int_equal(wc_can_torque_request_init(&msg), 0);
    msg.torque_request = (uint16_t)torque_raw;
    msg.mode = mode;
    msg.alive_counter = alive;
    assert_int_equal(wc_can_torque_request_pack(f.data, &msg, sizeof f.data), WC_CAN_TORQUE_REQUEST_LENGTH);
    assert_int_equal(wc_e2e_protect(f.id, f.data, sizeof f.data), WC_E2E_OK);
    return f;
}

/* Raw value of a valid physical value (the encoder's rounding). */
static inline int32_t raw_of(const wc_can_signal_t *sig, float value)
{
    int32_t raw = 0;
    assert_int_equal(wc_can_phys_to_raw(sig, value, &raw), WC_CAN_OK);
    return raw;
}

/* ======================================================================== */
/* Reference chain and fixture                                              */
/* ======================================================================== */

/* The clutch replayed from the lower layers, fed with the inputs the loop
 * must be using (the last valid frame of each). */
typedef struct {
    wc_model_t model;
    float theta_degC;   /* observer */
    float pressure_Pa;  /* VFS lag */
    wc_can_clutch_sensors_phys_t sensors;
    wc_can_torque_request_phys_t request;
} ref_t;

/* One step's outputs, in the units of the frames. */
typedef struct {
    float current_mA;
    float pressure_kPa;
    float theta_degC;
    float torque_Nm;
    float mu_f;
    float film_um;
    uint16_t model_bits;  /* Saturated / CurrentClamped / BelowDrag from the model */
} expected_t;

typedef struct {
    wc_loop_t loop;
    ref_t ref;
    uint8_t sensors_alive;  /* counter of the next ClutchSensors frame */
    uint8_t request_alive;  /* counter of the next TorqueRequest frame */
} fixture_t;

static fixture_t fixture;  /* wc_loop_t holds the receive ring: static, not the stack */

static inline void fixture_init_with(fixture_t *fx, const wc_loop_config_t *config)
{
    memset(fx, 0, sizeof *fx);
    assert_int_equal(wc_loop_init(&fx->loop, &wc_table1_calibration, config, THETA_START_degC), WC_CAL_OK);
    assert_int_equal(wc_model_init(&fx->ref.model, &wc_table1_calibration), WC_CAL_OK);
    const wc_calibration_t *cal = &wc_table1_calibration;
    fx->ref.theta_degC = THETA_START_degC;                                  /* observer starts there */
    fx->ref.pressure_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_min_mA;  /* VFS at rest */
    /* Before the first valid frame (wc_loop_init): no slip, both temperatures
     * at the start temperature, Open requested. */
    fx->ref.sensors.slip_speed_rpm = 0.0f;
    fx->ref.sensors.oil_temp_degC = THETA_START_degC;
    fx->ref.sensors.housing_temp_degC = THETA_START_degC;
    fx->ref.request.torque_request_Nm = 0.0f;
    fx->ref.request.mode = MODE_OPEN;
    port_reset();
}

/* The default configuration with a recovery debounce of one period: the
 * tests of steady behaviour see control from the first pair of frames. The
 * debounce, SyncCounter and the fault matrix use WC_LOOP_CONFIG_DEFAULT
 * itself (tests/c/test_loop_faults.c). */
static const wc_loop_config_t config_no_debounce = { 10u, 10u, { 2u, 3u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u };

static inline void fixture_init(fixture_t *fx)
{
    fixture_init_with(fx, &config_no_debounce);
}

static inline int setup(void **state)
{
    fixture_init(&fixture);
    *state = &fixture;
    return 0;
}

/* DBC Mode: 0 Open, 1 TorqueControl, 2 Locked. */
static inline wc_clutch_mode_t clutch_mode(uint8_t can_mode)
{
    switch (can_mode) {
    case MODE_TORQUE: return WC_MODE_TORQUE;
    case MODE_LOCKED: return WC_MODE_LOCKED;
    default: return WC_MODE_OPEN;
    }
}

static inline uint16_t model_bits_of(wc_status_t status)
{
    uint16_t bits = 0u;
    if ((status & WC_STATUS_SATURATED) != 0u) { bits |= WC_CAN_STATUS_SATURATED; }
    if ((status & WC_STATUS_CURRENT_CLAMPED) != 0u) { bits |= WC_CAN_STATUS_CURRENT_CLAMPED; }
    if ((status & WC_STATUS_BELOW_DRAG) != 0u) { bits |= WC_CAN_STATUS_BELOW_DRAG; }
    return bits;
}

static inline float slip_rad_s_of(const wc_can_clutch_sensors_phys_t *s)
{
    return s->slip_speed_rpm * WC_RAD_S_PER_RPM;
}

/* VFS current wc_inverse gives for a request at the given inputs. */
static inline float inverse_current_mA(const ref_t *ref, float slip_rpm, float theta_degC, float torque_Nm)
{
    wc_inverse_t inv;
    (void)wc_inverse(&ref->model, slip_rpm * WC_RAD_S_PER_RPM, theta_degC, torque_Nm, &inv);
    return inv.current_mA;
}

/* One control period of the reference; safe: the loop must be in its safe
 * state (Open, whatever was requested). */
static inline expected_t ref_step(ref_t *ref, bool safe)
{
    const wc_calibration_t *cal = ref->model.cal;
    const float slip_rad_s = slip_rad_s_of(&ref->sensors);
    const wc_clutch_mode_t mode = safe ? WC_MODE_OPEN : clutch_mode(ref->request.mode);
    wc_status_t status = WC_STATUS_OK;
    expected_t e;
    memset(&e, 0, sizeof e);
    if (mode == WC_MODE_TORQUE) {
        wc_inverse_t inv;
        status |= wc_inverse(&ref->model, slip_rad_s, ref->theta_degC, ref->request.torque_request_Nm, &inv);
        e.current_mA = inv.current_mA;
    } else {
        e.current_mA = (mode == WC_MODE_LOCKED) ? cal->vfs_current_max_mA : cal->vfs_current_min_mA;
    }
    e.pressure_kPa = cal->vfs_gain_Pa_per_mA * e.current_mA * 1.0e-3f;
    e.theta_degC = ref->theta_degC;  /* the estimate before this step's update */
    ref->pressure_Pa = wc_vfs_lag_step(&ref->model, ref->pressure_Pa, e.current_mA);
    wc_torque_t t;
    status |= wc_torque(&ref->model, slip_rad_s, ref->theta_degC, wc_contact_force_N(cal, ref->pressure_Pa), &t);
    status |= wc_thermal_step(&ref->model, &ref->theta_degC, fabsf(t.torque_Nm * slip_rad_s),
                              ref->sensors.oil_temp_degC, ref->sensors.housing_temp_degC);
    WC_CHECK((status & WC_STATUS_INPUT_INVALID) == 0u, "reference rejected its inputs: 0x%x", (unsigned)status);
    e.torque_Nm = t.torque_Nm;
    e.mu_f = t.mu_f;
    e.film_um = t.hbar_m * 1.0e6f;
    e.model_bits = model_bits_of(status);
    return e;
}

/* The last step's frames, decoded (the VfsCommand CRC must verify). */
static inline void last_outputs(wc_can_vfs_command_phys_t *cmd, wc_can_clutch_estimate_phys_t *est)
{
    assert_true(tx_log.count >= WC_LOOP_TX_CYCLIC);
    const wc_can_frame_t *vfs = &tx_log.frames[tx_log.count - 2u];
    const wc_can_frame_t *estimate = &tx_log.frames[tx_log.count - 1u];
    assert_int_equal(wc_can_decode_vfs_command(cmd, vfs->data, vfs->dlc), WC_CAN_OK);
    assert_int_equal(wc_can_decode_clutch_estimate(est, estimate->data, estimate->dlc), WC_CAN_OK);
}

static inline bool finite_step_output(const wc_step_output_t *o)
{
    return isfinite(o->current_mA) && isfinite(o->pressure_command_Pa) && isfinite(o->pressure_model_Pa) &&
           isfinite(o->force_command_N) && isfinite(o->theta_degC) && isfinite(o->model.torque_Nm) &&
           isfinite(o->model.coulomb_Nm) && isfinite(o->model.viscous_Nm) && isfinite(o->model.hbar_m) &&
           isfinite(o->model.mu_f);
}

/* The last step's frames against the reference: every signal within one raw
 * step of its DBC scaling, the status word exactly the model's bits plus
 * loop_bits. */
static inline void check_step(const fixture_t *fx, const expected_t *e, uint16_t loop_bits)
{
    wc_can_vfs_command_phys_t cmd;
    wc_can_clutch_estimate_phys_t est;
    last_outputs(&cmd, &est);
    const long k = (long)tx_log.steps;
    /* tolerance: one raw step, 1/32 mA */
    WC_CHECK_CLOSE("VfsCurrent mA", k, cmd.vfs_current_mA, e->current_mA, 0.0,
                   (double)wc_can_sig_vfs_command_vfs_current.scale);
    /* tolerance: one raw step, 1/16 kPa */
    WC_CHECK_CLOSE("PressureCommand kPa", k, cmd.pressure_command_kPa, e->pressure_kPa, 0.0,
                   (double)wc_can_sig_vfs_command_pressure_command.scale);
    /* tolerance: one raw step, 0.1 degC */
    WC_CHECK_CLOSE("EstimatedClutchTemp degC", k, est.estimated_clutch_temp_degC, e->theta_degC, 0.0,
                   (double)wc_can_sig_clutch_estimate_estimated_clutch_temp.scale);
    /* tolerance: one raw step, 0.1 Nm */
    WC_CHECK_CLOSE("ModelTorque Nm", k, est.model_torque_Nm, e->torque_Nm, 0.0,
                   (double)wc_can_sig_clutch_estimate_model_torque.scale);
    /* tolerance: one raw step, 1e-5 */
    WC_CHECK_CLOSE("MuF", k, est.mu_f, e->mu_f, 0.0, (double)wc_can_sig_clutch_estimate_mu_f.scale);
    /* tolerance: one raw step, 0.001 um */
    WC_CHECK_CLOSE("FilmThickness um", k, est.film_thickness_um, e->film_um, 0.0,
                   (double)wc_can_sig_clutch_estimate_film_thickness.scale);
    const uint16_t expected = (uint16_t)(e->model_bits | loop_bits);
    WC_CHECK(cmd.status == expected, "step %ld: status 0x%03x, expected 0x%03x", k, (unsigned)cmd.status,
             (unsigned)expected);
    WC_CHECK(finite_step_output(&fx->loop.last), "step %ld: non-finite model output", k);
}

/* ---- sending frames -------------------------------------------------------
 * good_*: a valid frame with the next counter; the reference takes its
 * decoded (quantized) values, as the loop must. */

static inline void good_sensors(fixture_t *fx, float slip_rpm, float oil_degC, float housing_degC)
{
    const wc_can_frame_t f = sensors_frame(slip_rpm, oil_degC, housing_degC, fx->sensors_alive);
    fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
    assert_int_equal(wc_can_decode_clutch_sensors(&fx->ref.sensors, f.data, f.dlc), WC_CAN_OK);
    port_deliver(&f);
}

static inline void good_request(fixture_t *fx, float torque_Nm, uint8_t mode)
{
    const wc_can_frame_t f = request_frame(torque_Nm, mode, fx->request_alive);
    fx->request_alive = wc_e2e_counter_next(fx->request_alive);
    assert_int_equal(wc_can_decode_torque_request(&fx->ref.request, f.data, f.dlc), WC_CAN_OK);
    port_deliver(&f);
}

/* A valid frame with the next counter that the loop must NOT use (its E2E
 * receiver is synchronising: wc_e2e.h SYNC); the reference keeps its values. */
static inline void sync_sensors(fixture_t *fx, float slip_rpm, float oil_degC, float housing_degC)
{
    const wc_can_frame_t f = sensors_frame(slip_rpm, oil_degC, housing_degC, fx->sensors_alive);
    fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
    port_deliver(&f);
}

static inline void sync_request(fixture_t *fx, float torque_Nm, uint8_t mode)
{
    const wc_can_frame_t f = request_frame(torque_Nm, mode, fx->request_alive);
    fx->request_alive = wc_e2e_counter_next(fx->request_alive);
    port_deliver(&f);
}

typedef struct {
    float slip_rpm;
    float oil_degC;
    float housing_degC;
    float torque_Nm;
    uint8_t mode;
} period_t;

static const period_t NOMINAL = { 500.0f, 60.0f, 55.0f, 150.0f, MODE_TORQUE };

/* One frame-clock period with both inputs valid: TorqueRequest, then
 * ClutchSensors (one step); checked against the reference with loop_bits. */
static inline expected_t good_period(fixture_t *fx, const period_t *p, uint16_t loop_bits)
{
    good_request(fx, p->torque_Nm, p->mode);
    good_sensors(fx, p->slip_rpm, p->oil_degC, p->housing_degC);
    run_steps(&fx->loop, 1u);
    const expected_t e = ref_step(&fx->ref, false);
    check_step(fx, &e, loop_bits);
    return e;
}

static inline uint32_t rejected_total(const wc_loop_counters_t *c)
{
    uint32_t n = 0u;
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) { n += c->rejected[r]; }
    return n;
}

/* Every reject counter is zero except `reason`, which is `count`. */
static inline void check_rejected_only(const wc_loop_t *loop, wc_loop_reject_t reason, uint32_t count)
{
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) {
        const uint32_t want = (r == (int)reason) ? count : 0u;
        WC_CHECK(loop->counters.rejected[r] == want, "rejected[%d] = %u, expected %u", r,
                 (unsigned)loop->counters.rejected[r], (unsigned)want);
    }
}

static inline bool same_sensors(const wc_can_clutch_sensors_phys_t *a, const wc_can_clutch_sensors_phys_t *b)
{
    return wc_test_same_float(a->slip_speed_rpm, b->slip_speed_rpm) &&
           wc_test_same_float(a->oil_temp_degC, b->oil_temp_degC) &&
           wc_test_same_float(a->housing_temp_degC, b->housing_temp_degC);
}

static inline bool same_request(const wc_can_torque_request_phys_t *a, const wc_can_torque_request_phys_t *b)
{
    return wc_test_same_float(a->torque_request_Nm, b->torque_request_Nm) && (a->mode == b->mode);
}

/* The loop still holds the values the reference holds (the bad frame was not used). */
static inline void check_held(const fixture_t *fx)
{
    WC_CHECK(same_sensors(&fx->loop.sensors, &fx->ref.sensors), "sensors changed: slip %g rpm, oil %g degC",
             (double)fx->loop.sensors.slip_speed_rpm, (double)fx->loop.sensors.oil_temp_degC);
    WC_CHECK(same_request(&fx->loop.request, &fx->ref.request), "request changed: %g Nm, mode %u",
             (double)fx->loop.request.torque_request_Nm, (unsigned)fx->loop.request.mode);
}

/* The check can fail: the two currents differ by more than two raw steps. */
static inline void check_distinguishable(float held_mA, float other_mA)
{
    WC_CHECK(fabsf(held_mA - other_mA) > 2.0f * wc_can_sig_vfs_command_vfs_current.scale,
             "test cannot tell the held value (%g mA) from the bad frame's (%g mA)", (double)held_mA,
             (double)other_mA);
}

/* ---- the safe state ------------------------------------------------------ */

#define SAFE_SENSORS (WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_SAFE_STATE_ACTIVE)
#define SAFE_REQUEST (WC_CAN_STATUS_REQUEST_TIMEOUT | WC_CAN_STATUS_SAFE_STATE_ACTIVE)

/* Minimum current in the safe state (wc_loop.h policy). */
static inline void check_min_current(void)
{
    wc_can_vfs_command_phys_t cmd;
    wc_can_clutch_estimate_phys_t est;
    last_outputs(&cmd, &est);
    /* tolerance: one raw step, 1/32 mA */
    WC_CHECK_CLOSE("safe state: minimum current", (long)tx_log.steps, cmd.vfs_current_mA,
                   wc_table1_calibration.vfs_current_min_mA, 0.0, (double)wc_can_sig_vfs_command_vfs_current.scale);
}

/* ---- implausible signals --------------------------------------------------- */

typedef enum { SIG_SLIP, SIG_OIL, SIG_HOUSING, SIG_TORQUE, SIG_MODE } signal_t;

typedef struct {
    const char *name;
    signal_t which;
    int32_t raw;  /* the implausible raw value */
} implausible_t;

/* The frame of one implausible case: every other signal valid but changed
 * from the held value (slip 1500 rpm, oil 120 degC, housing 110 degC;
 * 300 Nm, Locked), the right counter and CRC. */
static inline wc_can_frame_t implausible_frame(const implausible_t *c, uint8_t alive)
{
    int32_t slip = raw_of(&wc_can_sig_clutch_sensors_slip_speed, 1500.0f);
    int32_t oil = raw_of(&wc_can_sig_clutch_sensors_oil_temp, 120.0f);
    int32_t housing = raw_of(&wc_can_sig_clutch_sensors_housing_temp, 110.0f);
    int32_t torque = raw_of(&wc_can_sig_torque_request_torque_request, 300.0f);
    uint8_t mode = MODE_LOCKED;
    switch (c->which) {
    case SIG_SLIP: slip = c->raw; break;
    case SIG_OIL: oil = c->raw; break;
    case SIG_HOUSING: housing = c->raw; break;
    case SIG_TORQUE: torque = c->raw; mode = MODE_TORQUE; break;
    case SIG_MODE: mode = (uint8_t)c->raw; break;
    default: fail();
    }
    if (c->which <= SIG_HOUSING) { return raw_sensors_frame(slip, oil, housing, alive); }
    return raw_request_frame(torque, mode, alive);
}

#endif /* WC_TEST_LOOP_HARNESS_H */
