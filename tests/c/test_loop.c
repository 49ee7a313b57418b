/* cmocka tests of the CAN frame loop (include/wetclutch_can/wc_loop.h,
 * src/can/wc_loop.c) with the port mocked.
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
#include "wc_test_support.h"

#include "wc_golden_vectors.h"
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

static void port_reset(void)
{
    script_len = 0u;
    memset(&tx_log, 0, sizeof tx_log);
}

/* The port will deliver this frame (a copy; the script slot outlives the receive). */
static void port_deliver(const wc_can_frame_t *frame)
{
    assert_true(script_len < SCRIPT_MAX);
    script[script_len] = *frame;
    will_return(mock_port_receive, PORT_FRAME);
    will_return(mock_port_receive, cast_ptr_to_largest_integral_type(&script[script_len]));
    script_len++;
}

static void port_tick(void)
{
    will_return(mock_port_receive, PORT_TICK);
}

static int mock_port_receive(wc_can_frame_t *frame)
{
    const int event = mock_type(int);
    if (event == PORT_FRAME) {
        *frame = *mock_ptr_type(const wc_can_frame_t *);
    }
    return event;
}

static int mock_port_send(const wc_can_frame_t *frame)
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
static void expect_step_frames(void)
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
static uint32_t drive(wc_loop_t *loop)
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
static void run_steps(wc_loop_t *loop, uint32_t expected_steps)
{
    will_return(mock_port_receive, PORT_END);
    const uint32_t steps = drive(loop);
    WC_CHECK(steps == expected_steps, "%u steps, expected %u", (unsigned)steps, (unsigned)expected_steps);
}

/* ======================================================================== */
/* Frames                                                                   */
/* ======================================================================== */

static wc_can_frame_t empty_frame(uint32_t id)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    return f;
}

static wc_can_frame_t sensors_frame(float slip_rpm, float oil_degC, float housing_degC, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    const wc_can_clutch_sensors_phys_t s = { slip_rpm, oil_degC, housing_degC, alive };
    assert_int_equal(wc_can_encode_clutch_sensors(f.data, &s, sizeof f.data), WC_CAN_OK);
    return f;
}

static wc_can_frame_t request_frame(float torque_Nm, uint8_t mode, uint8_t alive)
{
    wc_can_frame_t f = empty_frame(WC_CAN_TORQUE_REQUEST_FRAME_ID);
    const wc_can_torque_request_phys_t q = { torque_Nm, mode, alive };
    assert_int_equal(wc_can_encode_torque_request(f.data, &q, sizeof f.data), WC_CAN_OK);
    return f;
}

/* Raw signal values packed by the generated code, then E2E-protected: the CRC
 * and the counter are right whatever the values. */
static wc_can_frame_t raw_sensors_frame(int32_t slip_raw, int32_t oil_raw, int32_t housing_raw, uint8_t alive)
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

static wc_can_frame_t raw_request_frame(int32_t torque_raw, uint8_t mode, uint8_t alive)
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
static int32_t raw_of(const wc_can_signal_t *sig, float value)
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

static void fixture_init_with(fixture_t *fx, const wc_loop_config_t *config)
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
static const wc_loop_config_t config_no_debounce = { 10u, 10u, { 2u, 3u }, 1u, false, NULL };

static void fixture_init(fixture_t *fx)
{
    fixture_init_with(fx, &config_no_debounce);
}

static int setup(void **state)
{
    fixture_init(&fixture);
    *state = &fixture;
    return 0;
}

/* DBC Mode: 0 Open, 1 TorqueControl, 2 Locked. */
static wc_clutch_mode_t clutch_mode(uint8_t can_mode)
{
    switch (can_mode) {
    case MODE_TORQUE: return WC_MODE_TORQUE;
    case MODE_LOCKED: return WC_MODE_LOCKED;
    default: return WC_MODE_OPEN;
    }
}

static uint16_t model_bits_of(wc_status_t status)
{
    uint16_t bits = 0u;
    if ((status & WC_STATUS_SATURATED) != 0u) { bits |= WC_CAN_STATUS_SATURATED; }
    if ((status & WC_STATUS_CURRENT_CLAMPED) != 0u) { bits |= WC_CAN_STATUS_CURRENT_CLAMPED; }
    if ((status & WC_STATUS_BELOW_DRAG) != 0u) { bits |= WC_CAN_STATUS_BELOW_DRAG; }
    return bits;
}

static float slip_rad_s_of(const wc_can_clutch_sensors_phys_t *s)
{
    return s->slip_speed_rpm * WC_RAD_S_PER_RPM;
}

/* VFS current wc_inverse gives for a request at the given inputs. */
static float inverse_current_mA(const ref_t *ref, float slip_rpm, float theta_degC, float torque_Nm)
{
    wc_inverse_t inv;
    (void)wc_inverse(&ref->model, slip_rpm * WC_RAD_S_PER_RPM, theta_degC, torque_Nm, &inv);
    return inv.current_mA;
}

/* One control period of the reference; safe: the loop must be in its safe
 * state (Open, whatever was requested). */
static expected_t ref_step(ref_t *ref, bool safe)
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
static void last_outputs(wc_can_vfs_command_phys_t *cmd, wc_can_clutch_estimate_phys_t *est)
{
    assert_true(tx_log.count >= WC_LOOP_TX_CYCLIC);
    const wc_can_frame_t *vfs = &tx_log.frames[tx_log.count - 2u];
    const wc_can_frame_t *estimate = &tx_log.frames[tx_log.count - 1u];
    assert_int_equal(wc_can_decode_vfs_command(cmd, vfs->data, vfs->dlc), WC_CAN_OK);
    assert_int_equal(wc_can_decode_clutch_estimate(est, estimate->data, estimate->dlc), WC_CAN_OK);
}

static bool finite_step_output(const wc_step_output_t *o)
{
    return isfinite(o->current_mA) && isfinite(o->pressure_command_Pa) && isfinite(o->pressure_model_Pa) &&
           isfinite(o->force_command_N) && isfinite(o->theta_degC) && isfinite(o->model.torque_Nm) &&
           isfinite(o->model.coulomb_Nm) && isfinite(o->model.viscous_Nm) && isfinite(o->model.hbar_m) &&
           isfinite(o->model.mu_f);
}

/* The last step's frames against the reference: every signal within one raw
 * step of its DBC scaling, the status word exactly the model's bits plus
 * loop_bits. */
static void check_step(const fixture_t *fx, const expected_t *e, uint16_t loop_bits)
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

static void good_sensors(fixture_t *fx, float slip_rpm, float oil_degC, float housing_degC)
{
    const wc_can_frame_t f = sensors_frame(slip_rpm, oil_degC, housing_degC, fx->sensors_alive);
    fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
    assert_int_equal(wc_can_decode_clutch_sensors(&fx->ref.sensors, f.data, f.dlc), WC_CAN_OK);
    port_deliver(&f);
}

static void good_request(fixture_t *fx, float torque_Nm, uint8_t mode)
{
    const wc_can_frame_t f = request_frame(torque_Nm, mode, fx->request_alive);
    fx->request_alive = wc_e2e_counter_next(fx->request_alive);
    assert_int_equal(wc_can_decode_torque_request(&fx->ref.request, f.data, f.dlc), WC_CAN_OK);
    port_deliver(&f);
}

/* A valid frame with the next counter that the loop must NOT use (its E2E
 * receiver is synchronising: wc_e2e.h SYNC); the reference keeps its values. */
static void sync_sensors(fixture_t *fx, float slip_rpm, float oil_degC, float housing_degC)
{
    const wc_can_frame_t f = sensors_frame(slip_rpm, oil_degC, housing_degC, fx->sensors_alive);
    fx->sensors_alive = wc_e2e_counter_next(fx->sensors_alive);
    port_deliver(&f);
}

static void sync_request(fixture_t *fx, float torque_Nm, uint8_t mode)
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
static expected_t good_period(fixture_t *fx, const period_t *p, uint16_t loop_bits)
{
    good_request(fx, p->torque_Nm, p->mode);
    good_sensors(fx, p->slip_rpm, p->oil_degC, p->housing_degC);
    run_steps(&fx->loop, 1u);
    const expected_t e = ref_step(&fx->ref, false);
    check_step(fx, &e, loop_bits);
    return e;
}

static uint32_t rejected_total(const wc_loop_counters_t *c)
{
    uint32_t n = 0u;
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) { n += c->rejected[r]; }
    return n;
}

/* Every reject counter is zero except `reason`, which is `count`. */
static void check_rejected_only(const wc_loop_t *loop, wc_loop_reject_t reason, uint32_t count)
{
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) {
        const uint32_t want = (r == (int)reason) ? count : 0u;
        WC_CHECK(loop->counters.rejected[r] == want, "rejected[%d] = %u, expected %u", r,
                 (unsigned)loop->counters.rejected[r], (unsigned)want);
    }
}

static bool same_sensors(const wc_can_clutch_sensors_phys_t *a, const wc_can_clutch_sensors_phys_t *b)
{
    return wc_test_same_float(a->slip_speed_rpm, b->slip_speed_rpm) &&
           wc_test_same_float(a->oil_temp_degC, b->oil_temp_degC) &&
           wc_test_same_float(a->housing_temp_degC, b->housing_temp_degC);
}

static bool same_request(const wc_can_torque_request_phys_t *a, const wc_can_torque_request_phys_t *b)
{
    return wc_test_same_float(a->torque_request_Nm, b->torque_request_Nm) && (a->mode == b->mode);
}

/* The loop still holds the values the reference holds (the bad frame was not used). */
static void check_held(const fixture_t *fx)
{
    WC_CHECK(same_sensors(&fx->loop.sensors, &fx->ref.sensors), "sensors changed: slip %g rpm, oil %g degC",
             (double)fx->loop.sensors.slip_speed_rpm, (double)fx->loop.sensors.oil_temp_degC);
    WC_CHECK(same_request(&fx->loop.request, &fx->ref.request), "request changed: %g Nm, mode %u",
             (double)fx->loop.request.torque_request_Nm, (unsigned)fx->loop.request.mode);
}

/* The check can fail: the two currents differ by more than two raw steps. */
static void check_distinguishable(float held_mA, float other_mA)
{
    WC_CHECK(fabsf(held_mA - other_mA) > 2.0f * wc_can_sig_vfs_command_vfs_current.scale,
             "test cannot tell the held value (%g mA) from the bad frame's (%g mA)", (double)held_mA,
             (double)other_mA);
}

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
/* Timeouts and the safe state                                              */
/* ======================================================================== */

#define SAFE_SENSORS (WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_SAFE_STATE_ACTIVE)
#define SAFE_REQUEST (WC_CAN_STATUS_REQUEST_TIMEOUT | WC_CAN_STATUS_SAFE_STATE_ACTIVE)

/* Minimum current in the safe state (wc_loop.h policy). */
static void check_min_current(void)
{
    wc_can_vfs_command_phys_t cmd;
    wc_can_clutch_estimate_phys_t est;
    last_outputs(&cmd, &est);
    /* tolerance: one raw step, 1/32 mA */
    WC_CHECK_CLOSE("safe state: minimum current", (long)tx_log.steps, cmd.vfs_current_mA,
                   wc_table1_calibration.vfs_current_min_mA, 0.0, (double)wc_can_sig_vfs_command_vfs_current.scale);
}

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
    { 10u, 10u, { 2u, 3u }, 1u, false, NULL }, { 3u, 25u, { 2u, 1u }, 1u, false, NULL }, { 1u, 1u, { 2u, 2u }, 1u, false, NULL }
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

typedef enum { SIG_SLIP, SIG_OIL, SIG_HOUSING, SIG_TORQUE, SIG_MODE } signal_t;

typedef struct {
    const char *name;
    signal_t which;
    int32_t raw;  /* the implausible raw value */
} implausible_t;

/* The frame of one implausible case: every other signal valid but changed
 * from the held value (slip 1500 rpm, oil 120 degC, housing 110 degC;
 * 300 Nm, Locked), the right counter and CRC. */
static wc_can_frame_t implausible_frame(const implausible_t *c, uint8_t alive)
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

/* ======================================================================== */
/* Frame-clock determinism and counters                                     */
/* ======================================================================== */

#define ENGAGEMENT_PERIODS 300
#define CHANGED_PERIOD 150

typedef struct {
    wc_can_frame_t frames[1024];
    size_t count;
    uint32_t good;                        /* frames that pass every check */
    uint32_t bad[WC_REJECT_REASONS];      /* frames each check drops */
    uint32_t steps;                       /* ClutchSensors frames without flags */
} script_t;

static void script_add(script_t *s, const wc_can_frame_t *f, int reject)  /* reject < 0: a good frame */
{
    assert_true(s->count < WC_TEST_COUNT(s->frames));
    s->frames[s->count++] = *f;
    if (reject < 0) { s->good++; } else { s->bad[reject]++; }
    if (f->id == WC_CAN_CLUTCH_SENSORS_FRAME_ID && f->flags == 0u) { s->steps++; }
}

/* A synthetic engagement, one TorqueRequest and one ClutchSensors frame per
 * period: slip 1500 rpm -> 0, request ramping to 250 Nm, oil warming; with
 * a corrupted copy (CRC), a repeated request (counter), a bench frame
 * (unknown id), an implausible sensor frame, a remote frame (format) and a
 * short copy in between. torque_change_Nm is added to one period's request. */
static void build_engagement(script_t *s, float torque_change_Nm)
{
    memset(s, 0, sizeof *s);
    uint8_t s_alive = 3u;
    uint8_t r_alive = 9u;
    for (int k = 0; k < ENGAGEMENT_PERIODS; ++k) {
        const float x = (float)k / (float)ENGAGEMENT_PERIODS;
        float torque_Nm = (k < CHANGED_PERIOD) ? 250.0f * (float)k / (float)CHANGED_PERIOD : 250.0f;
        if (k == CHANGED_PERIOD) { torque_Nm += torque_change_Nm; }
        const wc_can_frame_t q = request_frame(torque_Nm, MODE_TORQUE, r_alive);
        script_add(s, &q, -1);
        if (k == 120) {
            const wc_can_frame_t again = request_frame(torque_Nm + 100.0f, MODE_TORQUE, r_alive);
            script_add(s, &again, WC_REJECT_COUNTER);
        }
        r_alive = wc_e2e_counter_next(r_alive);
        if (k == 180) {
            wc_can_frame_t bench = empty_frame(WC_CAN_BENCH_MEASUREMENT_FRAME_ID + 1u);  /* not in the DBC */
            const wc_can_bench_measurement_phys_t m = { 5000.0f, 250.0f, 95.0f };
            assert_int_equal(wc_can_encode_bench_measurement(bench.data, &m, sizeof bench.data), WC_CAN_OK);
            script_add(s, &bench, WC_REJECT_UNKNOWN_ID);
        }
        const wc_can_frame_t f = sensors_frame(1500.0f * (1.0f - x), 80.0f + 10.0f * x, 75.0f, s_alive);
        if (k == 240) {
            wc_can_frame_t remote = f;
            remote.flags = WC_CAN_FLAG_REMOTE;
            script_add(s, &remote, WC_REJECT_FORMAT);
        }
        if (k == 200) {
            const implausible_t sna = { "OilTemp SNA", SIG_OIL, (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE };
            const wc_can_frame_t bad = implausible_frame(&sna, s_alive);
            script_add(s, &bad, WC_REJECT_IMPLAUSIBLE);
        } else {
            script_add(s, &f, -1);
        }
        s_alive = wc_e2e_counter_next(s_alive);
        if (k == 60) {
            wc_can_frame_t corrupt = f;
            corrupt.data[5] ^= 0x20u;
            script_add(s, &corrupt, WC_REJECT_CRC);
        }
        if (k == 250) {
            wc_can_frame_t shorter = f;
            shorter.dlc = 7u;
            script_add(s, &shorter, WC_REJECT_SHORT);
        }
    }
}

typedef struct {
    wc_can_frame_t frames[TX_LOG_MAX];
    uint32_t count;
} capture_t;

static capture_t capture_a;
static capture_t capture_b;

/* A fresh loop, the whole script through the mock port; the output frames
 * into cap. */
static void replay(fixture_t *fx, const script_t *s, capture_t *cap)
{
    fixture_init(fx);
    for (size_t i = 0u; i < s->count; ++i) { port_deliver(&s->frames[i]); }
    run_steps(&fx->loop, s->steps);
    cap->count = tx_log.count;
    memcpy(cap->frames, tx_log.frames, tx_log.count * sizeof tx_log.frames[0]);
}

/* Index of the first frame that differs (id, DLC, flags, data bytes), or
 * the shorter count if one is a prefix of the other. */
static uint32_t first_difference(const capture_t *a, const capture_t *b)
{
    const uint32_t n = (a->count < b->count) ? a->count : b->count;
    for (uint32_t i = 0u; i < n; ++i) {
        const wc_can_frame_t *x = &a->frames[i];
        const wc_can_frame_t *y = &b->frames[i];
        if (x->id != y->id || x->dlc != y->dlc || x->flags != y->flags || x->dlc > 8u ||
            memcmp(x->data, y->data, x->dlc) != 0) {
            return i;
        }
    }
    return n;
}

static script_t engagement;
static script_t engagement_changed;

static void test_frame_clock_determinism(void **state)
{
    fixture_t *fx = *state;
    build_engagement(&engagement, 0.0f);
    replay(fx, &engagement, &capture_a);
    replay(fx, &engagement, &capture_b);
    assert_int_equal(capture_a.count, 2u * engagement.steps);
    assert_int_equal(capture_b.count, capture_a.count);
    const uint32_t same = first_difference(&capture_a, &capture_b);
    WC_CHECK(same == capture_a.count, "replays differ at output frame %u of %u", (unsigned)same,
             (unsigned)capture_a.count);

    /* One request 20 Nm higher: the outputs must differ, and not before that
     * period's step (its sensor frame is the (CHANGED_PERIOD+2)-th step: the
     * corrupted copy at period 60 stepped once more). */
    build_engagement(&engagement_changed, 20.0f);
    replay(fx, &engagement_changed, &capture_b);
    assert_int_equal(capture_b.count, capture_a.count);
    const uint32_t diff = first_difference(&capture_a, &capture_b);
    const uint32_t changed_step = (uint32_t)CHANGED_PERIOD + 1u;  /* 0-based step index */
    WC_CHECK(diff < capture_a.count, "a different frame sequence gave identical output");
    WC_CHECK(diff == 2u * changed_step, "first difference at output frame %u, expected %u (VfsCommand of step %u)",
             (unsigned)diff, (unsigned)(2u * changed_step), (unsigned)changed_step);
}

/* frames_in = frames offered; frames_used + all rejections = frames_in;
 * frames_out = frames sent; each count equal to what the script holds. */
static void test_counters_add_up(void **state)
{
    fixture_t *fx = *state;
    build_engagement(&engagement, 0.0f);
    replay(fx, &engagement, &capture_a);
    const wc_loop_counters_t *c = &fx->loop.counters;
    assert_int_equal(c->frames_in, engagement.count);
    assert_int_equal(c->frames_in, tx_log.offered);
    assert_int_equal(c->frames_used, engagement.good);
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) {
        WC_CHECK(c->rejected[r] == engagement.bad[r], "rejected[%d] = %u, script has %u", r,
                 (unsigned)c->rejected[r], (unsigned)engagement.bad[r]);
    }
    assert_int_equal(c->frames_used + rejected_total(c), c->frames_in);
    assert_int_equal(c->steps, engagement.steps);
    assert_int_equal(c->steps, tx_log.steps);
    assert_int_equal(c->frames_out, tx_log.count);
    assert_int_equal(c->frames_out, WC_LOOP_TX_CYCLIC * c->steps);
    assert_int_equal(tx_log.refused, 0u);
    assert_int_equal(c->sensor_timeouts + c->request_timeouts + c->safe_steps, 0u);
    /* every reason the script exercises was seen once */
    for (int r = 0; r < (int)WC_REJECT_OVERFLOW; ++r) { assert_int_equal(engagement.bad[r], 1u); }
}


/* ---- bench mode ------------------------------------------------------------
 * A fresh BenchMeasurement replaces the modelled apply force in the torque
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
        cmocka_unit_test_setup(test_sensor_timeout_and_recovery, setup),
        cmocka_unit_test_setup(test_request_timeout_and_recovery, setup),
        cmocka_unit_test_setup(test_safe_state_before_first_frames, setup),
        cmocka_unit_test_setup(test_counter_repeat_and_jump, setup),
        cmocka_unit_test_setup(test_crc_error, setup),
        cmocka_unit_test_setup(test_short_unknown_and_format, setup),
        cmocka_unit_test_setup(test_ring_overflow, setup),
        cmocka_unit_test_setup(test_implausible_signals, setup),
        cmocka_unit_test_setup(test_persistent_implausible_sensor, setup),
        cmocka_unit_test_setup(test_frame_clock_determinism, setup),
        cmocka_unit_test_setup(test_counters_add_up, setup),
        cmocka_unit_test_setup(test_bench_force_replaces_modelled_force, setup),
    };
    return cmocka_run_group_tests_name("wc_loop", tests, NULL, NULL);
}
