/* The probe's shift rows (wc_arm_bench.c): wc_shift_step and wc_loop_step in Shift mode over one 1->2
 * upshift's inertia phase (DESIGN 10, 12), and the whole shift with both clutches and the engine request
 * (DESIGN 14), with the whole shift's RAM lines. */
#include "wc_arm_bench.h"
#include "wc_shift_1_2_shift.h"   /* lut/: wc_shift_1_2_whole_full, the whole shift's calibration */
#include "wc_test_fixtures.h"     /* tests/c: the shift scenario of the C tests */

/* ------------------------------------------------------------------------ */
/* Shift control over one upshift (DESIGN 10)                               */

#define SHIFT_TURBINE_TORQUE_Nm WC_TEST_SHIFT_TURBINE_TORQUE_Nm
#define SHIFT_START_SLIP_rad_s WC_TEST_SHIFT_START_SLIP_rad_s
#define SHIFT_TARGET_TIME_s WC_TEST_SHIFT_TARGET_TIME_s
#define SHIFT_OIL_degC WC_TEST_SHIFT_OIL_degC
#define SHIFT_MAX_PERIODS 3000u

/* The C tests' shift calibration (tests/c/wc_test_fixtures.h). */
static const wc_shift_calibration_t shift_calibration = WC_TEST_SHIFT_CALIBRATION;

/* The plant of tests/c/wc_test_fixtures.h (the shift tests' too): the turbine held by the off-going clutch
 * until the inertia phase, then I_t d(slip)/dt = a (T_t - a T_c); the plates
 * stick at zero slip and while the model is locked. */
typedef struct {
    float slip_rad_s;
    bool released;
} shift_plant_t;

static void plant_advance(shift_plant_t *p, uint32_t phase, const wc_step_output_t *out)
{
    if (phase == (uint32_t)WC_SHIFT_INERTIA) { p->released = true; }
    if (!p->released) { return; }
    p->slip_rad_s = wc_test_shift_plant_slip_rad_s(&shift_calibration, p->slip_rad_s, SHIFT_TURBINE_TORQUE_Nm, out,
                                                   wc_arm_calibration->control_period_s);
}

static wc_shift_t shift;
static wc_adapt_t adapt;
static wc_shift_calibration_t shift_adaptive;  /* shift_calibration with adaptation on (DESIGN 12) */

/* wc_shift_step on its own: every step that starts in the inertia phase;
 * adaptive: with adaptation on (its samples), and end_row the step in which
 * the shift ends (the adaptation's update, wc_adapt_finish). */
void bench_shift_step(const wc_calibration_t *cal, row_t row, bool adaptive, row_t end_row)
{
    shift_adaptive = shift_calibration;
    shift_adaptive.adaptation = 1u;
    wc_adapt_reset(&adapt);
    if ((wc_shift_calibration_check(&shift_adaptive) != WC_SHIFT_CAL_OK) ||
        (wc_clutch_init(&clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("shift: calibration");
        return;
    }
    wc_shift_init(&shift);
    shift_plant_t plant = {SHIFT_START_SLIP_rad_s, false};
    bench.clutch = &clutch;
    bench.shift = &shift;
    bench.shift_cal = adaptive ? &shift_adaptive : &shift_calibration;
    bench.adapt = adaptive ? &adapt : NULL;
    bench.shift_command = (wc_shift_command_t){true, 2u, SHIFT_TURBINE_TORQUE_Nm, SHIFT_TARGET_TIME_s};
    static const wc_step_output_t no_output;
    bench.step_out = no_output;  /* wc_shift_step reads the previous step's status (anti-windup) */
    uint32_t reports = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        bench.step_in = (wc_step_input_t){.slip_rad_s = plant.slip_rad_s, .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        if (shift.phase == (uint32_t)WC_SHIFT_INERTIA) {
            record(row, measure(thunk_shift_step, &bench));
        } else if (adaptive && (shift.phase == (uint32_t)WC_SHIFT_LOCKUP)) {
            const uint32_t n = measure(thunk_shift_step, &bench);
            if (bench.shift_ended) { record(end_row, n); }
        } else {
            thunk_shift_step(&bench);
        }
        if (bench.shift_ended) { reports++; }
        plant_advance(&plant, shift.phase, &bench.step_out);
    }
    if ((reports != 1u) || (shift.phase != (uint32_t)WC_SHIFT_LOCKED) || (bench.shift_report.abort_reason != 0u) ||
        (adaptive && (bench.shift_report.adaptation.result != (uint32_t)WC_ADAPT_RESULT_UPDATED))) {
        wc_arm_puts("SHIFT phase ");
        wc_arm_put_u32(shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(bench.shift_report.abort_reason);
        wc_arm_puts("\n");
        fail("wc_shift_step: the shift did not complete");
    }
    wc_arm_puts("SHIFT wc_shift_step: inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(bench.shift_report.inertia_time_s * 1000.0f));
    wc_arm_puts(" ms (target ");
    wc_arm_put_u32((uint32_t)lroundf(SHIFT_TARGET_TIME_s * 1000.0f));
    wc_arm_puts(" ms), slip RMSE ");
    wc_arm_put_fixed((uint32_t)lroundf(bench.shift_report.slip_rmse_rad_s * 1000.0f), 3u);
    wc_arm_puts(" rad/s\n");
}

/* ClutchSensors, TorqueRequest (Mode 3 Shift) and ShiftCommand of one period. */
static void queue_shift_frames(float slip_rad_s, bool shift_request, uint8_t alive)
{
    wc_can_frame_t frame;
    if (wc_test_shift_sensors_frame(&frame, slip_rad_s, alive) != WC_CAN_OK) { fail("shift: sensors frame"); }
    (void)wc_loop_receive(&loop, &frame);
    if (wc_test_shift_request_frame(&frame, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, alive) != WC_CAN_OK) {
        fail("shift: request frame");
    }
    (void)wc_loop_receive(&loop, &frame);
    if (wc_test_shift_command_frame(&frame, shift_request, SHIFT_TURBINE_TORQUE_Nm, SHIFT_TARGET_TIME_s * 1000.0f,
                                    alive) != WC_CAN_OK) {
        fail("shift: command frame");
    }
    (void)wc_loop_receive(&loop, &frame);
}

/* wc_loop_step in Shift mode: the default configuration with the shift
 * calibration. ShiftRequest is 0 until the loop has left its safe state (E2E
 * sync, recovery_periods), then 1: a rising edge outside the safe state
 * starts the shift. Every step that starts in the inertia phase is a sample. */
#define SHIFT_LOOP_SETTLE_PERIODS WC_TEST_SHIFT_LOOP_SETTLE_PERIODS
void bench_loop_shift(const wc_calibration_t *cal, row_t row)
{
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = &shift_calibration;
    if (wc_loop_init(&loop, cal, &config, SHIFT_OIL_degC) != WC_CAL_OK) {
        fail("shift: wc_loop_init");
        return;
    }
    bench.loop = &loop;
    shift_plant_t plant = {SHIFT_START_SLIP_rad_s, false};
    uint32_t reports = 0u;
    uint32_t safe_in_shift = 0u;
    uint8_t alive = 0u;
    uint32_t frames_in = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        queue_shift_frames(plant.slip_rad_s, k >= SHIFT_LOOP_SETTLE_PERIODS, alive);
        frames_in += 3u;
        alive = wc_e2e_counter_next(alive);
        const uint32_t safe_before = loop.counters.safe_steps;
        if (loop.shift.phase == (uint32_t)WC_SHIFT_INERTIA) {
            record(row, measure(thunk_loop_step, &bench));
            if (loop.counters.safe_steps != safe_before) { safe_in_shift++; }
        } else {
            thunk_loop_step(&bench);
        }
        if (bench.tx_frames > WC_LOOP_TX_CYCLIC) { reports++; }  /* ShiftReport (no AdaptationReport: adaptation off) */
        plant_advance(&plant, loop.shift.phase, &loop.last);
    }
    /* E2E: SyncCounter frames of each of the three inputs are not used */
    const uint32_t sync = loop.counters.rejected[WC_REJECT_SYNC];
    if ((reports != 1u) || (loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED) || (loop.report.abort_reason != 0u) ||
        (safe_in_shift != 0u) || (loop.counters.frames_used + sync != frames_in)) {
        wc_arm_puts("SHIFT loop phase ");
        wc_arm_put_u32(loop.shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(loop.report.abort_reason);
        wc_arm_puts(", reports ");
        wc_arm_put_u32(reports);
        wc_arm_puts(", frames used ");
        wc_arm_put_u32(loop.counters.frames_used);
        wc_arm_puts(" + sync ");
        wc_arm_put_u32(sync);
        wc_arm_puts(" of ");
        wc_arm_put_u32(frames_in);
        wc_arm_puts("\n");
        fail("wc_loop_step (Shift mode): the shift did not complete, or a frame was rejected");
    }
    wc_arm_puts("SHIFT wc_loop_step: inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(loop.report.inertia_time_s * 1000.0f));
    wc_arm_puts(" ms\n");
}

/* ------------------------------------------------------------------------ */
/* The whole shift (DESIGN 14): two clutches and the engine request         */

/* wc_shift_1_2_whole_full (lut/wc_shift_1_2_shift.h): coordinator 1, fill pulse, off-going capacity
 * control, engine intervention. The off-going clutch is a second wc_clutch_t with the same clutch
 * calibration as the on-coming one. */
#define WHOLE_SHIFT_CAL wc_shift_1_2_whole_full
/* Periods with ShiftRequest 0 before the edge: the coordinator holds 1st gear in IDLE (the off-going
 * clutch's lock-up dwell is 10 periods). The loop's settle (E2E sync, recovery) is longer. */
#define WHOLE_IDLE_PERIODS 40u
#define WHOLE_SLIP_MAX_rad_s 1000.0f
#define WHOLE_PLANT_TURBINE_INERTIA_kg_m2 0.25f  /* the plant's I_t: the nominal of tools/plants/upshift_1_2.toml */

/* The bench's plant of the whole shift (not the tools' vehicle plant: it only has to drive the phases),
 * the C tests' reduced plant with the off-going clutch added: the output speed w_o held (a vehicle much
 * heavier than the turbine, and no road load), so both slips move with the turbine speed w_t (a = 1):
 *   off-going  s1 = w_t - b1 w_o,   on-coming  s2 = w_t - b w_o = s1 + (b1 - b) w_o,
 *   I_t dw_t/dt = T_t - T_2 - T_1   (T_2, T_1: the clutch models' signed torques of this step),
 * explicit Euler at the control period, with (b1 - b) w_o = SHIFT_START_SLIP_rad_s (1st gear: s1 = 0,
 * s2 = 100 rad/s). A clutch at zero slip sticks while the torque it has to hold (T_t minus the other
 * clutch's torque) stays within its static capacity (the model's, wc_step_output_t.static_capacity_Nm),
 * else it slips; a slip that crosses 0 sticks there. The engine follows its request at once:
 * T_t = T_t0 + delta while InterventionActive, which ShiftCommand.TurbineTorque reports in the next period.
 * Starts in 1st gear: the off-going clutch stuck, s2 = 100 rad/s, T_t = T_t0 = 100 Nm. */
typedef struct {
    float offgoing_slip_rad_s;  /* s1 */
    bool offgoing_stuck;
    bool oncoming_stuck;
    float turbine_torque_Nm;    /* T_t with the engine's intervention */
    float min_offgoing_slip_rad_s;
    float max_offgoing_slip_rad_s;
} whole_plant_t;

static float whole_oncoming_slip(const whole_plant_t *p)
{
    return p->oncoming_stuck ? 0.0f : (p->offgoing_slip_rad_s + SHIFT_START_SLIP_rad_s);
}

static void whole_plant_init(whole_plant_t *p)
{
    *p = (whole_plant_t){0.0f, true, false, SHIFT_TURBINE_TORQUE_Nm, 0.0f, 0.0f};
}

static void whole_plant_advance(whole_plant_t *p, const wc_step_output_t *on, const wc_step_output_t *off,
                                bool engine_active, float engine_delta_Nm)
{
    const float t_t = SHIFT_TURBINE_TORQUE_Nm + (engine_active ? engine_delta_Nm : 0.0f);
    p->turbine_torque_Nm = (t_t > 0.0f) ? t_t : 0.0f;
    const float turbine_Nm = p->turbine_torque_Nm;
    if (p->oncoming_stuck && (fabsf(turbine_Nm - off->model.torque_Nm) <= on->static_capacity_Nm)) { return; }
    p->oncoming_stuck = false;
    if (p->offgoing_stuck && (fabsf(turbine_Nm - on->model.torque_Nm) <= off->static_capacity_Nm)) { return; }
    p->offgoing_stuck = false;
    const float s1 = p->offgoing_slip_rad_s;
    const float accel = (turbine_Nm - on->model.torque_Nm - off->model.torque_Nm) / WHOLE_PLANT_TURBINE_INERTIA_kg_m2;
    float next = s1 + accel * wc_arm_calibration->control_period_s;
    if ((s1 + SHIFT_START_SLIP_rad_s > 0.0f) && (next + SHIFT_START_SLIP_rad_s <= 0.0f)) {
        next = -SHIFT_START_SLIP_rad_s;  /* the on-coming plates stick: 2nd gear */
        p->oncoming_stuck = true;
    } else if (((s1 > 0.0f) && (next <= 0.0f)) || ((s1 < 0.0f) && (next >= 0.0f))) {
        next = 0.0f;  /* the off-going plates stick: 1st gear */
        p->offgoing_stuck = true;
    }
    next = fminf(fmaxf(next, -WHOLE_SLIP_MAX_rad_s), WHOLE_SLIP_MAX_rad_s);
    p->offgoing_slip_rad_s = next;
    p->min_offgoing_slip_rad_s = fminf(p->min_offgoing_slip_rad_s, next);
    p->max_offgoing_slip_rad_s = fmaxf(p->max_offgoing_slip_rad_s, next);
}

/* The worst step of each part of the whole shift: the step of the command's edge (the shift's start: two
 * lag compensations), then by the phase the step starts in. */
enum { WHOLE_PART_START = 0, WHOLE_PARTS = 1 + (int)WC_SHIFT_LOCKUP };
static const char *const whole_part_name[WHOLE_PARTS] = {"start", "prepare", "torque", "inertia", "lockup"};
typedef struct {
    uint32_t worst[WHOLE_PARTS];
    uint32_t engine_steps;      /* steps with the engine intervention active */
    float engine_min_Nm;
    float engine_max_Nm;
} whole_parts_t;

/* Record n into row when the step belongs to the shift: it started in a running phase, or it started the
 * shift (IDLE before, a running phase after). */
static void whole_record(row_t row, whole_parts_t *parts, uint32_t phase_before, uint32_t phase_after, uint32_t n)
{
    uint32_t part;
    if (wc_shift_phase_running(phase_before)) {
        part = phase_before;
    } else if ((phase_before == (uint32_t)WC_SHIFT_IDLE) && wc_shift_phase_running(phase_after)) {
        part = WHOLE_PART_START;
    } else {
        return;
    }
    record(row, n);
    if (n > parts->worst[part]) { parts->worst[part] = n; }
}

static void whole_engine(whole_parts_t *parts, bool active, float delta_Nm)
{
    if (!active) { return; }
    parts->engine_steps++;
    parts->engine_min_Nm = fminf(parts->engine_min_Nm, delta_Nm);
    parts->engine_max_Nm = fmaxf(parts->engine_max_Nm, delta_Nm);
}

static void whole_print(const char *what, row_t row, const whole_parts_t *parts, const whole_plant_t *plant,
                        const wc_shift_report_t *report)
{
    wc_arm_puts("WHOLE ");
    wc_arm_puts(row_name[row]);
    wc_arm_puts(" (");
    wc_arm_puts(what);
    wc_arm_puts(") worst by part:");
    for (uint32_t i = 0u; i < (uint32_t)WHOLE_PARTS; ++i) {
        wc_arm_puts(" ");
        wc_arm_puts(whole_part_name[i]);
        wc_arm_puts(" ");
        wc_arm_put_u32(parts->worst[i]);
    }
    wc_arm_puts("; inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(report->inertia_time_s * 1000.0f));
    wc_arm_puts(" ms, off-going slip ");
    wc_arm_put_i32((int32_t)lroundf(plant->min_offgoing_slip_rad_s));
    wc_arm_puts(" .. ");
    wc_arm_put_i32((int32_t)lroundf(plant->max_offgoing_slip_rad_s));
    wc_arm_puts(" rad/s, engine active ");
    wc_arm_put_u32(parts->engine_steps);
    wc_arm_puts(" steps, delta ");
    wc_arm_put_i32((int32_t)lroundf(parts->engine_min_Nm));
    wc_arm_puts(" .. ");
    wc_arm_put_i32((int32_t)lroundf(parts->engine_max_Nm));
    wc_arm_puts(" Nm, flare ");
    wc_arm_put_u32(report->flare ? 1u : 0u);
    wc_arm_puts(", tie-up ");
    wc_arm_put_u32(report->tie_up ? 1u : 0u);
    wc_arm_puts("\n");
}

/* What a whole shift must have done: completed (one report, LOCKED, no abort, no fallback), the off-going
 * clutch handed over (its slip turned negative past the hand-over threshold), the engine asked. */
static bool whole_ok(uint32_t reports, uint32_t phase, const wc_shift_report_t *report, const whole_plant_t *plant,
                     const whole_parts_t *parts)
{
    return (reports == 1u) && (phase == (uint32_t)WC_SHIFT_LOCKED) && (report->abort_reason == 0u) &&
           (report->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE) &&
           (plant->min_offgoing_slip_rad_s < -WHOLE_SHIFT_CAL.handover_slip_rad_s) && plant->oncoming_stuck &&
           (parts->engine_steps > 0u) && (parts->engine_min_Nm < 0.0f) && (parts->engine_max_Nm > 0.0f);
}

static wc_clutch_t offgoing_clutch;

/* wc_shift_step with the coordinator: both clutches of cal, every step of one 1->2 upshift from the
 * command's edge to the step in which it ends (prepare/fill, torque phase, inertia phase, hand-over). */
void bench_whole_shift_step(const wc_calibration_t *cal, row_t row)
{
    if ((wc_shift_calibration_check(&WHOLE_SHIFT_CAL) != WC_SHIFT_CAL_OK) || (WHOLE_SHIFT_CAL.coordinator != 1u) ||
        (wc_clutch_init(&clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK) ||
        (wc_clutch_init(&offgoing_clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("whole shift: calibration");
        return;
    }
    wc_shift_init(&shift);
    static wc_step_input_t offgoing_in;
    static wc_step_output_t offgoing_out;
    static const wc_step_output_t no_output;
    offgoing_out = no_output;
    wc_shift_offgoing_t offgoing = {&offgoing_clutch, &offgoing_in, &offgoing_out, false, 0.0f};
    whole_plant_t plant;
    whole_plant_init(&plant);
    whole_parts_t parts = {{0u}, 0u, 0.0f, 0.0f};
    bench.clutch = &clutch;
    bench.shift = &shift;
    bench.shift_cal = &WHOLE_SHIFT_CAL;
    bench.adapt = NULL;
    bench.offgoing = &offgoing;
    bench.step_out = no_output;  /* wc_shift_step reads the previous step's status (anti-windup) */
    uint32_t reports = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        bench.shift_command = (wc_shift_command_t){k >= WHOLE_IDLE_PERIODS, 2u, plant.turbine_torque_Nm, SHIFT_TARGET_TIME_s};
        bench.step_in = (wc_step_input_t){.slip_rad_s = whole_oncoming_slip(&plant), .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        offgoing_in = (wc_step_input_t){.slip_rad_s = plant.offgoing_slip_rad_s, .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        const uint32_t phase_before = shift.phase;
        const uint32_t n = measure(thunk_whole_shift_step, &bench);
        whole_record(row, &parts, phase_before, shift.phase, n);
        if (bench.shift_ended) { reports++; }
        whole_engine(&parts, offgoing.engine_active, offgoing.engine_delta_Nm);
        whole_plant_advance(&plant, &bench.step_out, &offgoing_out, offgoing.engine_active, offgoing.engine_delta_Nm);
    }
    bench.offgoing = NULL;
    whole_print("wc_shift_step", row, &parts, &plant, &bench.shift_report);
    if (!whole_ok(reports, shift.phase, &bench.shift_report, &plant, &parts)) {
        wc_arm_puts("WHOLE phase ");
        wc_arm_put_u32(shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(bench.shift_report.abort_reason);
        wc_arm_puts(", fallback ");
        wc_arm_put_u32(bench.shift_report.fallback);
        wc_arm_puts("\n");
        fail("wc_shift_step (whole shift): the shift did not complete with a hand-over and the engine's request");
    }
}

/* wc_loop_step in Shift mode with the whole shift (config.offgoing: cal again): ClutchSensors,
 * OffgoingSensors, TorqueRequest (Mode 3) and ShiftCommand queued each period; every step of the shift
 * as in bench_whole_shift_step; each step sends OffgoingVfsCommand and EngineTorqueRequest too. */
void bench_loop_whole_shift(const wc_calibration_t *cal, row_t row)
{
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = &WHOLE_SHIFT_CAL;
    config.offgoing = cal;
    if (!wc_loop_whole_shift(&config) || (wc_loop_init(&loop, cal, &config, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("whole shift: wc_loop_init");
        return;
    }
    bench.loop = &loop;
    whole_plant_t plant;
    whole_plant_init(&plant);
    whole_parts_t parts = {{0u}, 0u, 0.0f, 0.0f};
    uint32_t reports = 0u;
    uint32_t safe_in_shift = 0u;
    uint32_t short_steps = 0u;
    uint8_t alive = 0u;
    uint32_t frames_in = 0u;
    const uint32_t per_step = WC_LOOP_TX_CYCLIC + WC_LOOP_TX_WHOLE_SHIFT;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        const bool request = k >= SHIFT_LOOP_SETTLE_PERIODS;
        wc_can_frame_t frame;
        const wc_can_offgoing_sensors_phys_t og = {plant.offgoing_slip_rad_s / WC_RAD_S_PER_RPM, alive};
        if ((wc_test_shift_sensors_frame(&frame, whole_oncoming_slip(&plant), alive) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: sensors frame");
        }
        frame = wc_test_can_frame(WC_CAN_OFFGOING_SENSORS_FRAME_ID);
        if ((wc_can_encode_offgoing_sensors(frame.data, &og, sizeof frame.data) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: off-going sensors frame");
        }
        if ((wc_test_shift_request_frame(&frame, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, alive) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: request frame");
        }
        if ((wc_test_shift_command_frame(&frame, request, plant.turbine_torque_Nm, SHIFT_TARGET_TIME_s * 1000.0f, alive) !=
             WC_CAN_OK) || !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: command frame");
        }
        frames_in += 4u;
        alive = wc_e2e_counter_next(alive);
        const uint32_t safe_before = loop.counters.safe_steps;
        const uint32_t phase_before = loop.shift.phase;
        const uint32_t n = measure(thunk_loop_step, &bench);
        whole_record(row, &parts, phase_before, loop.shift.phase, n);
        if (wc_shift_phase_running(phase_before) && (loop.counters.safe_steps != safe_before)) { safe_in_shift++; }
        if (bench.tx_frames < per_step) { short_steps++; }
        if (bench.tx_frames > per_step) { reports++; }  /* ShiftReport (no AdaptationReport: adaptation off) */
        whole_engine(&parts, loop.whole.engine_active, loop.whole.engine_delta_Nm);
        whole_plant_advance(&plant, &loop.last, &loop.offgoing_last, loop.whole.engine_active, loop.whole.engine_delta_Nm);
    }
    /* E2E: SyncCounter frames of each of the four inputs are not used */
    const uint32_t sync = loop.counters.rejected[WC_REJECT_SYNC];
    whole_print("wc_loop_step", row, &parts, &plant, &loop.report);
    if (!whole_ok(reports, loop.shift.phase, &loop.report, &plant, &parts) || (safe_in_shift != 0u) ||
        (short_steps != 0u) || (loop.counters.frames_used + sync != frames_in)) {
        wc_arm_puts("WHOLE loop phase ");
        wc_arm_put_u32(loop.shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(loop.report.abort_reason);
        wc_arm_puts(", reports ");
        wc_arm_put_u32(reports);
        wc_arm_puts(", steps without the whole shift's frames ");
        wc_arm_put_u32(short_steps);
        wc_arm_puts(", frames used ");
        wc_arm_put_u32(loop.counters.frames_used);
        wc_arm_puts(" + sync ");
        wc_arm_put_u32(sync);
        wc_arm_puts(" of ");
        wc_arm_put_u32(frames_in);
        wc_arm_puts("\n");
        fail("wc_loop_step (whole shift): the shift did not complete, or a frame was rejected");
    }
}

/* RAM of the whole shift (DESIGN 14): the loop's state holds the second clutch whether or not it is used. */
void whole_ram(void)
{
    const uint32_t offgoing_bytes = (uint32_t)(sizeof loop.offgoing + sizeof loop.offgoing_input +
                                               sizeof loop.offgoing_last + sizeof loop.offgoing_in +
                                               sizeof loop.offgoing_sensors);
    put_ram("wc_loop_t", (uint32_t)sizeof(wc_loop_t));
    put_ram("wc_clutch_t", (uint32_t)sizeof(wc_clutch_t));
    put_ram("wc_shift_t", (uint32_t)sizeof(wc_shift_t));
    put_ram("wc_loop_t.offgoing_parts", offgoing_bytes);
    /* a caller of wc_shift_step: shift, two clutches, in/out each */
    put_ram("whole_shift_step_state", (uint32_t)(sizeof(wc_shift_t) + 2u * (sizeof(wc_clutch_t) +
                                                                           sizeof(wc_step_input_t) +
                                                                           sizeof(wc_step_output_t))));
}
