/* The loop fuzzer's oracle of the loop's frames and counters (fuzz_loop.h): after every wc_loop_iterate
 * (abort with a message on violation). The input format: fuzz_loop.c.
 *
 *  - it returns WC_LOOP_TX_CYCLIC exactly when the clock says so (a tick, or
 *    with the frame clock a ClutchSensors frame without flags), else 0;
 *    the step's frames are the cyclic ones (2; 4 with the whole shift), then
 *    ShiftReport, then AdaptationReport;
 *  - the step's frames: VfsCommand (0x120, DLC 8) decodes with a good CRC,
 *    its alive counter counts +1, reserved status bits are 0; VfsCurrent
 *    within the calibration's current range, and the model's own output
 *    (loop->last) finite and in range (a NaN current would be sent as 0 mA);
 *    ClutchEstimate (0x121) decodes without SNA or range error;
 *  - safe state: a timeout bit implies StatusSafeStateActive; the safe state
 *    ends only after both inputs were fresh for recovery_periods steps in a
 *    row; in the safe state the current is the calibration's minimum;
 *    StatusBenchInput only with bench input enabled;
 *  - with shift control a step may add ShiftReport (0x122) and, with
 *    adaptation, AdaptationReport (0x123; alone after a reset), which decode
 *    (SNA-free, saturated at most); with adaptation the learned values stay
 *    inside their bands (wc_adapt_values_valid) after every step;
 *  - counters: frames_used + sum(rejected) + frames still queued ==
 *    frames_in; frames_out == the frames the steps returned;
 *  - the whole shift (wc_loop_whole_shift): frames 2 and 3 are
 *    OffgoingVfsCommand (0x124) and EngineTorqueRequest (0x125), DLC 8, no
 *    flags; both decode without error (E2E CRC right, no SNA, no range
 *    error), their alive counters count +1 per step, every decoded value is
 *    finite and inside its DBC range; OffgoingVfsCommand: VfsCurrent within
 *    the off-going calibration's current range and the off-going model's own
 *    output (loop->offgoing_last, finite) within half a bit of it, ShiftPhase
 *    and Fallback those of the controller; EngineTorqueRequest:
 *    InterventionActive 0/1 as loop->whole.engine_active, TorqueDelta within
 *    [-engine_reduction_max_Nm, engine_increase_max_Nm] of the shift
 *    calibration (the widest the loop ran on: an XCP page may narrow them
 *    during a ramp-out) and 0 when InterventionActive is 0; in the safe
 *    state (README, "Fault in the middle of a shift"; wc_shift.c fall_back,
 *    offgoing_input): InterventionActive 0, the off-going current exactly its
 *    calibrated maximum (held 1st gear: IDLE, hand-back) or minimum
 *    (released); by the controller's state (its Fallback may be the last
 *    shift's): outside Shift mode the minimum (not the loop's clutch: also
 *    outside the safe state, with no engine request); without second gear
 *    (IDLE, PREPARE, TORQUE, a hand-back) the maximum; with it (inertia phase
 *    on: Fallback 1 finished on the model, 3 released) the minimum once the
 *    hand-over into the inertia phase is over, which a lost input ends at
 *    once (README's fault table: released); the on-coming clutch at its minimum as without the whole
 *    shift except while a shift finishes on the model (Fallback 1, INERTIA
 *    .. LOCKED: the on-coming clutch as planned, only its range checked);
 *  - the current range, the safe state's minimum and the recovery debounce
 *    are those of the calibration the loop uses now (an accepted XCP page
 *    may change them);
 *  - XCP, after every wc_xcp_step: at most WC_XCP_TX_FRAMES frames, each of
 *    id 0x7F1, DLC 8, no flags, its PID 0xFF/0xFE/0xFD or a DAQ PID below
 *    the allocated ODT count; after every page check (the only place a
 *    calibration changes; wc_calibration_check is costly) the loop's
 *    calibration passes
 *    wc_calibration_check (and its shift calibration
 *    wc_shift_calibration_check, the off-going clutch's calibration
 *    wc_calibration_check), its control period, shift control's and the
 *    whole shift's presence are the ones it started with; the loop's own frames are in
 *    their own array (VfsCommand first, checked above).
 * At the end one more tick empties the ring and the counters must add up
 * with nothing queued. */
#include "fuzz_loop.h"

static uint32_t rejected_sum(const wc_loop_t *l)
{
    uint32_t n = 0u;
    for (unsigned i = 0u; i < (unsigned)WC_REJECT_REASONS; ++i) { n += l->counters.rejected[i]; }
    return n;
}

void check_counters(const harness_t *h)
{
    const uint32_t queued = loop.rx_tail - loop.rx_head;
    FZ_CHECK(queued <= WC_LOOP_RX_CAPACITY, "ring holds %u frames", (unsigned)queued);
    FZ_CHECK(loop.counters.frames_used + rejected_sum(&loop) + queued == loop.counters.frames_in,
             "counters: used %u + rejected %u + queued %u != in %u", (unsigned)loop.counters.frames_used,
             (unsigned)rejected_sum(&loop), (unsigned)queued, (unsigned)loop.counters.frames_in);
    FZ_CHECK((loop.counters.steps == h->steps) && (loop.counters.frames_out == h->frames_out),
             "steps %u (harness %u), frames out %u", (unsigned)loop.counters.steps, (unsigned)h->steps,
             (unsigned)loop.counters.frames_out);
}

/* The whole shift's two cyclic frames (out[2], out[3]) and the off-going clutch after a step. */
static void check_whole(harness_t *h, const wc_can_frame_t out[WC_LOOP_TX_FRAMES], bool safe)
{
    const wc_calibration_t *og_cal = loop.offgoing.model.cal;  /* an accepted XCP page may have changed it */
    const wc_shift_calibration_t *sc = loop.config.shift;
    const float i_min = og_cal->vfs_current_min_mA;
    const float i_max = og_cal->vfs_current_max_mA;
    const float lsb_mA = 1.0f / 32.0f;  /* VfsCurrent scaling */
    const float lsb_Nm = 0.05f;         /* TorqueDelta scaling */
    if (sc->engine_increase_max_Nm > h->engine_increase_max_Nm) { h->engine_increase_max_Nm = sc->engine_increase_max_Nm; }
    if (sc->engine_reduction_max_Nm > h->engine_reduction_max_Nm) { h->engine_reduction_max_Nm = sc->engine_reduction_max_Nm; }

    /* the off-going clutch's own model output (the frame would hide a NaN as 0 mA) */
    const wc_step_output_t *o = &loop.offgoing_last;
    FZ_CHECK(fz_finite(o->current_mA) && (o->current_mA >= i_min) && (o->current_mA <= i_max),
             "off-going model current %g outside [%g, %g]", (double)o->current_mA, (double)i_min, (double)i_max);
    FZ_CHECK(fz_finite(o->pressure_command_Pa) && fz_finite(o->pressure_model_Pa) && fz_finite(o->force_command_N) &&
                 fz_finite(o->theta_degC) && fz_finite(o->model.torque_Nm) && fz_finite(o->model.hbar_m) &&
                 fz_finite(o->model.mu_f) && (o->model.hbar_m > 0.0f),
             "non-finite off-going output: P %g Pm %g F %g theta %g T %g hbar %g mu_f %g",
             (double)o->pressure_command_Pa, (double)o->pressure_model_Pa, (double)o->force_command_N,
             (double)o->theta_degC, (double)o->model.torque_Nm, (double)o->model.hbar_m, (double)o->model.mu_f);
    FZ_CHECK((loop.offgoing.theta_degC >= WC_THETA_MIN_degC) && (loop.offgoing.theta_degC <= WC_THETA_MAX_degC),
             "off-going estimate %g outside the envelope", (double)loop.offgoing.theta_degC);
    FZ_CHECK((o->status & WC_STATUS_NOT_INITIALISED) == 0u, "off-going model status 0x%x", (unsigned)o->status);

    /* OffgoingVfsCommand */
    FZ_CHECK((out[2].id == WC_CAN_OFFGOING_VFS_COMMAND_FRAME_ID) && (out[2].dlc == 8u) && (out[2].flags == 0u),
             "third frame id 0x%x dlc %u flags %u (OffgoingVfsCommand expected)", (unsigned)out[2].id,
             (unsigned)out[2].dlc, (unsigned)out[2].flags);
    wc_can_offgoing_vfs_command_phys_t og;
    const wc_can_result_t ro = wc_can_decode_offgoing_vfs_command(&og, out[2].data, out[2].dlc);
    FZ_CHECK(!wc_can_is_error(ro), "OffgoingVfsCommand does not decode cleanly (result %d)", (int)ro);
    FZ_CHECK(fz_finite(og.vfs_current_mA) && fz_finite(og.pressure_command_kPa) && fz_finite(og.shift_phase) &&
                 (og.vfs_current_mA >= 0.0f) && (og.vfs_current_mA <= 2000.0f) && (og.pressure_command_kPa >= 0.0f) &&
                 (og.pressure_command_kPa <= 4000.0f) && (og.shift_phase >= 0.0f) && (og.shift_phase <= 6.0f) &&
                 (og.fallback <= WC_CAN_OFFGOING_VFS_COMMAND_FALLBACK_RELEASED_CHOICE),
             "OffgoingVfsCommand outside the DBC: current %g pressure %g phase %g fallback %u",
             (double)og.vfs_current_mA, (double)og.pressure_command_kPa, (double)og.shift_phase, (unsigned)og.fallback);
    FZ_CHECK((og.shift_phase == (float)loop.shift.phase) && (og.fallback == loop.shift.fallback),
             "OffgoingVfsCommand phase %g fallback %u, controller %u %u", (double)og.shift_phase,
             (unsigned)og.fallback, (unsigned)loop.shift.phase, (unsigned)loop.shift.fallback);
    FZ_CHECK((og.vfs_current_mA >= i_min - 0.5f * lsb_mA) && (og.vfs_current_mA <= i_max + 0.5f * lsb_mA) &&
                 (fabsf(og.vfs_current_mA - o->current_mA) <= 0.5f * lsb_mA),
             "off-going VfsCurrent %g, model current %g, range [%g, %g]", (double)og.vfs_current_mA,
             (double)o->current_mA, (double)i_min, (double)i_max);

    /* EngineTorqueRequest */
    FZ_CHECK((out[3].id == WC_CAN_ENGINE_TORQUE_REQUEST_FRAME_ID) && (out[3].dlc == 8u) && (out[3].flags == 0u),
             "fourth frame id 0x%x dlc %u flags %u (EngineTorqueRequest expected)", (unsigned)out[3].id,
             (unsigned)out[3].dlc, (unsigned)out[3].flags);
    wc_can_engine_torque_request_phys_t eng;
    const wc_can_result_t rq = wc_can_decode_engine_torque_request(&eng, out[3].data, out[3].dlc);
    FZ_CHECK(!wc_can_is_error(rq), "EngineTorqueRequest does not decode cleanly (result %d)", (int)rq);
    FZ_CHECK(fz_finite(eng.intervention_active) && fz_finite(eng.torque_delta_Nm) &&
                 ((eng.intervention_active == 0.0f) || (eng.intervention_active == 1.0f)) &&
                 (eng.torque_delta_Nm >= -1000.0f) && (eng.torque_delta_Nm <= 1000.0f),
             "EngineTorqueRequest outside the DBC: active %g delta %g", (double)eng.intervention_active,
             (double)eng.torque_delta_Nm);
    const bool active = eng.intervention_active == 1.0f;
    FZ_CHECK(active == loop.whole.engine_active, "InterventionActive %g, controller %d", (double)eng.intervention_active,
             (int)loop.whole.engine_active);
    /* half an LSB, and a little: the encoder rounds ties away from zero, and 0.05 Nm is not exact in binary, so
     * a tie (-129.325 Nm -> -129.35) is a few float ulps more than half an LSB off */
    const float half_lsb_Nm = 0.5f * lsb_Nm * 1.001f;
    FZ_CHECK((eng.torque_delta_Nm >= -h->engine_reduction_max_Nm - half_lsb_Nm) &&
                 (eng.torque_delta_Nm <= h->engine_increase_max_Nm + half_lsb_Nm),
             "TorqueDelta %g outside [-%g, %g]", (double)eng.torque_delta_Nm, (double)h->engine_reduction_max_Nm,
             (double)h->engine_increase_max_Nm);
    if (active) {
        FZ_CHECK(fz_finite(loop.whole.engine_delta_Nm) && (fabsf(eng.torque_delta_Nm - loop.whole.engine_delta_Nm) <= half_lsb_Nm),
                 "TorqueDelta %g, controller %g", (double)eng.torque_delta_Nm, (double)loop.whole.engine_delta_Nm);
        h->engine_steps++;
    } else {
        FZ_CHECK(eng.torque_delta_Nm == 0.0f, "TorqueDelta %g with InterventionActive 0", (double)eng.torque_delta_Nm);
    }

    if (stats.counting) {
        stats.whole_phase_steps[(loop.shift.phase < 7u) ? loop.shift.phase : 6u]++;
        stats.whole_fallback_steps[h->shift_stepped ? (loop.shift.fallback & 3u) : 0u]++;
    }

    /* alive counters: +1 per step, each frame its own */
    if (h->have_whole_tx) {
        FZ_CHECK(og.alive_counter == (uint8_t)((h->offgoing_alive + 1u) % 16u),
                 "OffgoingVfsCommand alive counter %u after %u", (unsigned)og.alive_counter, (unsigned)h->offgoing_alive);
        FZ_CHECK(eng.alive_counter == (uint8_t)((h->engine_alive + 1u) % 16u),
                 "EngineTorqueRequest alive counter %u after %u", (unsigned)eng.alive_counter, (unsigned)h->engine_alive);
    }
    h->have_whole_tx = true;
    h->offgoing_alive = og.alive_counter;
    h->engine_alive = eng.alive_counter;

    /* outside Shift mode (no shift running) the off-going clutch is not the loop's: open, no engine request
     * (wc_loop.c run) */
    if (!h->shift_stepped) {
        FZ_CHECK((o->current_mA == i_min) && !active, "not in Shift mode: off-going current %g mA (minimum %g), "
                 "InterventionActive %g", (double)o->current_mA, (double)i_min, (double)eng.intervention_active);
    }

    /* the safe state (README, "Fault in the middle of a shift"; wc_shift.c fall_back, offgoing_input); the
     * fallback of the last shift stays in the controller after it (sent in OffgoingVfsCommand.Fallback): its
     * rows only when the controller stepped */
    if (safe) {
        FZ_CHECK(!active, "InterventionActive in the safe state (delta %g)", (double)eng.torque_delta_Nm);
        const bool at_max = (o->current_mA == i_max) && (fabsf(og.vfs_current_mA - i_max) <= 0.5f * lsb_mA);
        const bool at_min = (o->current_mA == i_min) && (fabsf(og.vfs_current_mA - i_min) <= 0.5f * lsb_mA);
        FZ_CHECK(at_max || at_min,
                 "safe state: off-going current %g mA (frame %g) neither its maximum %g nor minimum %g (phase %u, "
                 "fallback %u, second gear %d)",
                 (double)o->current_mA, (double)og.vfs_current_mA, (double)i_max, (double)i_min,
                 (unsigned)loop.shift.phase, (unsigned)loop.shift.fallback, (int)loop.shift.second_gear);
        /* wc_shift.c offgoing_input, by the controller's state (its Fallback may be the last shift's): without
         * second gear (IDLE, PREPARE, TORQUE, a hand-back's ABORTED) it holds 1st gear at its maximum; with it
         * (INERTIA on; FINISH, RELEASED) it is released: a lost input ends the hand-over at once */
        if (h->shift_stepped && !loop.shift.second_gear) {
            FZ_CHECK(at_max, "safe state without second gear: off-going current %g mA, maximum %g (phase %u, "
                     "fallback %u)", (double)o->current_mA, (double)i_max, (unsigned)loop.shift.phase,
                     (unsigned)loop.shift.fallback);
        } else if (h->shift_stepped) {
            FZ_CHECK(at_min, "safe state, second gear: off-going current %g mA, not released (minimum %g; phase %u, "
                     "fallback %u, released %d)", (double)o->current_mA, (double)i_min, (unsigned)loop.shift.phase,
                     (unsigned)loop.shift.fallback, (int)loop.shift.offgoing_released);
        }
        const uint32_t fallback = h->shift_stepped ? loop.shift.fallback : (uint32_t)WC_SHIFT_FALLBACK_NONE;
        if (fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE) { h->fallback_steps++; }
    }
}

/* The frames and state after a step. */
void check_step(harness_t *h, const wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    h->steps++;
    const wc_calibration_t *now = loop.clutch.model.cal;  /* an accepted XCP page may have changed it */
    const float i_min = now->vfs_current_min_mA;
    const float i_max = now->vfs_current_max_mA;
    const float lsb_mA = 1.0f / 32.0f;  /* VfsCurrent scaling */

    /* the model's own output (the frame would hide a NaN as 0 mA) */
    const wc_step_output_t *o = &loop.last;
    FZ_CHECK(fz_finite(o->current_mA) && (o->current_mA >= i_min) && (o->current_mA <= i_max),
             "model current %g outside [%g, %g]", (double)o->current_mA, (double)i_min, (double)i_max);
    FZ_CHECK(fz_finite(o->pressure_command_Pa) && fz_finite(o->pressure_model_Pa) && fz_finite(o->force_command_N) &&
                 fz_finite(o->theta_degC) && fz_finite(o->model.torque_Nm) && fz_finite(o->model.hbar_m) &&
                 fz_finite(o->model.mu_f) && (o->model.hbar_m > 0.0f),
             "non-finite step output: P %g Pm %g F %g theta %g T %g hbar %g mu_f %g", (double)o->pressure_command_Pa,
             (double)o->pressure_model_Pa, (double)o->force_command_N, (double)o->theta_degC,
             (double)o->model.torque_Nm, (double)o->model.hbar_m, (double)o->model.mu_f);
    FZ_CHECK((loop.clutch.theta_degC >= WC_THETA_MIN_degC) && (loop.clutch.theta_degC <= WC_THETA_MAX_degC),
             "estimate %g outside the envelope", (double)loop.clutch.theta_degC);
    FZ_CHECK((o->status & WC_STATUS_NOT_INITIALISED) == 0u, "model status 0x%x", (unsigned)o->status);

    /* VfsCommand */
    FZ_CHECK((out[0].id == WC_CAN_VFS_COMMAND_FRAME_ID) && (out[0].dlc == 8u) && (out[0].flags == 0u),
             "first frame id 0x%x dlc %u flags %u", (unsigned)out[0].id, (unsigned)out[0].dlc, (unsigned)out[0].flags);
    wc_can_vfs_command_phys_t cmd;
    const wc_can_result_t rc = wc_can_decode_vfs_command(&cmd, out[0].data, out[0].dlc);
    FZ_CHECK(!wc_can_is_error(rc), "VfsCommand does not decode: result %d", (int)rc);
    FZ_CHECK((out[0].data[7] & 0x80u) == 0u, "reserved status bit set: byte 7 = 0x%02x", (unsigned)out[0].data[7]);
    if (h->have_tx) {
        FZ_CHECK(cmd.alive_counter == (uint8_t)((h->tx_alive + 1u) % 16u), "tx alive counter %u after %u",
                 (unsigned)cmd.alive_counter, (unsigned)h->tx_alive);
    }
    h->have_tx = true;
    h->tx_alive = cmd.alive_counter;
    FZ_CHECK((cmd.vfs_current_mA >= i_min - 0.5f * lsb_mA) && (cmd.vfs_current_mA <= i_max + 0.5f * lsb_mA),
             "VfsCurrent %g outside [%g, %g]", (double)cmd.vfs_current_mA, (double)i_min, (double)i_max);
    FZ_CHECK(fabsf(cmd.vfs_current_mA - o->current_mA) <= 0.5f * lsb_mA, "VfsCurrent %g, model current %g",
             (double)cmd.vfs_current_mA, (double)o->current_mA);

    /* safe state and its debounce */
    const uint16_t timeouts = WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_REQUEST_TIMEOUT;
    const bool safe = (cmd.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u;
    h->fresh_run = ((cmd.status & timeouts) != 0u) ? 0u : h->fresh_run + 1u;
    if ((cmd.status & timeouts) != 0u) {
        FZ_CHECK(safe, "timeout bits 0x%x without StatusSafeStateActive", (unsigned)cmd.status);
    }
    if (!safe) {
        FZ_CHECK(h->fresh_run >= loop.config.recovery_periods,
                 "safe state left after %u fresh steps (recovery %u)", (unsigned)h->fresh_run,
                 (unsigned)loop.config.recovery_periods);
        h->control_steps++;
    } else {
        /* the whole shift finished on the model (README: "on-coming clutch as planned"): its range only */
        const bool finishing = h->whole && h->shift_stepped && (loop.shift.fallback == (uint32_t)WC_SHIFT_FALLBACK_FINISH) &&
                               (wc_shift_phase_running(loop.shift.phase) || (loop.shift.phase == (uint32_t)WC_SHIFT_LOCKED));
        if (!finishing) {
            FZ_CHECK((o->current_mA == i_min) && (fabsf(cmd.vfs_current_mA - i_min) <= 0.5f * lsb_mA),
                     "safe state with current %g mA (frame %g), minimum %g", (double)o->current_mA,
                     (double)cmd.vfs_current_mA, (double)i_min);
        }
        h->safe_steps++;
    }
    if (!h->config.bench_input_enabled) {
        FZ_CHECK((cmd.status & WC_CAN_STATUS_BENCH_INPUT) == 0u, "StatusBenchInput with bench input off");
    }

    /* ClutchEstimate */
    FZ_CHECK((out[1].id == WC_CAN_CLUTCH_ESTIMATE_FRAME_ID) && (out[1].dlc == 8u) && (out[1].flags == 0u),
             "second frame id 0x%x dlc %u flags %u", (unsigned)out[1].id, (unsigned)out[1].dlc, (unsigned)out[1].flags);
    wc_can_clutch_estimate_phys_t est;
    const wc_can_result_t re = wc_can_decode_clutch_estimate(&est, out[1].data, out[1].dlc);
    FZ_CHECK(!wc_can_is_error(re), "ClutchEstimate does not decode cleanly (result %d: SNA = NaN sent, or range)",
             (int)re);
    if (h->whole) { check_whole(h, out, safe); }
    check_counters(h);
}
