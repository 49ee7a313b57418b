/* libFuzzer harness of the frame loop's transmission mode (wc_loop_config_t.transmission, DESIGN 15;
 * src/can/wc_loop_gearbox.c): the 8HP gearbox (wc_gearbox_8hp), every element the table1 clutch, the whole
 * shift's calibration (as tests/c/test_loop_gearbox.c configures it); GearboxSensors and ShiftCommand in,
 * one ElementXVfsCommand per element, GearboxStatus and EngineTorqueRequest out, through wc_loop_iterate.
 *
 * Input:
 *   byte 0  options: bit 0 clock (0 timer, 1 frame: a step per GearboxSensors data frame); bit 1 "make
 *           valid": the harness writes the E2E CRC and an incrementing alive counter into every
 *           GearboxSensors/ShiftCommand frame; bit 2 "plausible": their signals are mapped into their DBC
 *           ranges (2 bytes a signal; ShiftCommand: request, target gear, current gear bytes); bit 3 a
 *           fuzzed loop configuration follows (timeouts, E2E MaxDeltaCounter/SyncCounter, recovery: 5
 *           bytes, as fuzz_loop.c); bits 4-7 the start gear (value % 9: 0 reverse, 1..8).
 *   then records until the bytes run out (at most MAX_RECORDS), each a command byte c:
 *     c & 3 == 0  a timer tick without a frame
 *     c & 3 == 1  a frame; with the timer clock, a tick too if c bit 2
 *     c & 3 == 2  a frame and a tick
 *     c & 3 == 3  a port event (RX dropped / bus error / TX failed / deadline missed: c bits 2-3) and a
 *                 count byte
 *   c bits 3-4 choose the frame id: GearboxSensors, ShiftCommand, a single-clutch input (ClutchSensors,
 *   TorqueRequest or OffgoingSensors by a byte: unknown to the transmission), other (a 16-bit id); a format
 *   byte (bit 7: DLC = low nibble, flags = bits 4-6) and the data bytes follow; c bits 6-7 are the fault in
 *   "make valid" mode: 0 none, 1 alive counter advanced by a fuzzed nibble, 2 a wrong CRC, 3 as fuzzed.
 *
 * The oracle (abort with ORACLE VIOLATION on a violation), after every wc_loop_iterate:
 *  - it returns 0 frames, or exactly element_count + 2 cyclic frames (+1 ShiftReport) when the clock says
 *    so (a tick, or with the frame clock a GearboxSensors data frame without flags);
 *  - frame e < element_count is ElementXVfsCommand (0x128 + e), DLC 8, no flags; its CRC checks with its
 *    own data id, it decodes (with element A's layout, re-protected) without SNA or range error, its alive
 *    counter counts +1 per step, VfsCurrent within the element calibration's current range (half an LSB);
 *  - then GearboxStatus (decodes, alive +1, Gear and TargetGear within the gearbox's gears) and
 *    EngineTorqueRequest (decodes, alive +1, InterventionActive 0/1, TorqueDelta within the shift
 *    calibration's limits and 0 when inactive); a ShiftReport decodes;
 *  - the transmission's own outputs (loop->transmission_out) finite, each element's current in its range;
 *  - safe state: a timeout bit implies StatusSafeStateActive, the safe state ends only after
 *    recovery_periods fresh steps in a row; in it no engine request, and an element that holds the gear
 *    (Role HELD) never lowers its current from one step to the next; once it has lasted 5 steps with no shift
 *    running (ShiftPhase IDLE), the gear's closed elements at their maximum, the others at their minimum;
 *  - counters: frames_used + sum(rejected) + queued == frames_in, steps and frames out as returned. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_e2e.h>
#include <wetclutch_can/wc_loop.h>

#include "wc_8hp_gearbox.h"
#include "wc_fuzz_common.h"
#include "wc_shift_1_2_shift.h"
#include "wc_table1_calibration.h"

#define MAX_RECORDS 1024u    /* as fuzz_loop.h: a shift from a gear with its timeouts fits (the seeds: <= 530) */
#define SAFE_SETTLE_STEPS 5u /* the VFS lag's first steps at the maximum command */

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const wc_gearbox_t *const box = &wc_gearbox_8hp;
static wc_transmission_config_t tx_config;
static wc_loop_t loop;  /* static: not on the fuzzer's stack */
static bool verbose;

typedef struct {
    wc_loop_clock_t clock;
    bool make_valid;
    bool plausible;
    wc_loop_config_t config;
    uint8_t alive_sensors;   /* next alive counter of each E2E input ("make valid") */
    uint8_t alive_command;
    bool have_tx;            /* the previous step's counters, which must count +1 */
    uint8_t element_alive[WC_GEARBOX_ELEMENTS_MAX];
    uint8_t status_alive;
    uint8_t engine_alive;
    float element_mA[WC_GEARBOX_ELEMENTS_MAX];  /* the previous step's (the safe state never lets a held one go) */
    uint8_t element_role[WC_GEARBOX_ELEMENTS_MAX];
    bool safe_before;
    uint32_t safe_run;       /* consecutive steps in the safe state */
    uint32_t fresh_run;      /* consecutive steps without a timeout bit */
    uint32_t steps;
    uint32_t frames_out;
    uint32_t safe_steps;     /* statistics */
    uint32_t shift_steps;
    uint32_t reports;
} harness_t;

/* What the run executed (printed at exit, scripts/fuzz.sh shows it). */
static struct {
    unsigned long inputs, steps, safe_steps, shift_steps, reports, refusals;
    unsigned long phase_steps[7];
} stats;

static float map_u16(uint16_t u, float lo, float hi) { return lo + (hi - lo) * ((float)u / 65535.0f); }

static void build_frame(harness_t *h, fz_reader_t *r, uint8_t c, wc_can_frame_t *f)
{
    static const uint32_t single[3] = { WC_CAN_CLUTCH_SENSORS_FRAME_ID, WC_CAN_TORQUE_REQUEST_FRAME_ID,
                                        WC_CAN_OFFGOING_SENSORS_FRAME_ID };
    const uint8_t sel = (uint8_t)((c >> 3) & 3u);
    memset(f, 0, sizeof *f);
    f->id = (sel == 0u) ? WC_CAN_GEARBOX_SENSORS_FRAME_ID
            : (sel == 1u) ? WC_CAN_SHIFT_COMMAND_FRAME_ID
            : (sel == 2u) ? single[fz_u8(r) % 3u] : (uint32_t)fz_u16(r);
    const uint8_t format = fz_u8(r);
    f->dlc = 8u;
    if ((format & 0x80u) != 0u) {
        f->dlc = (uint8_t)(format & 0x0Fu);
        f->flags = (uint8_t)((format >> 4) & 0x07u);
        if ((f->flags & WC_CAN_FLAG_EXTENDED) != 0u) { f->id = (f->id << 13) ^ fz_u16(r); }
    }
    const uint8_t fault = h->make_valid ? (uint8_t)(c >> 6) : 3u;
    const bool sensors = f->id == WC_CAN_GEARBOX_SENSORS_FRAME_ID;
    const bool command = f->id == WC_CAN_SHIFT_COMMAND_FRAME_ID;
    if (h->plausible && (fault != 3u) && sensors) {
        const wc_can_gearbox_sensors_phys_t g = {
            map_u16(fz_u16(r), -40.0f, 200.0f), map_u16(fz_u16(r), -8000.0f, 8000.0f),
            map_u16(fz_u16(r), -8000.0f, 8000.0f), map_u16(fz_u16(r), -40.0f, 200.0f), 0u };
        (void)wc_can_encode_gearbox_sensors(f->data, &g, sizeof f->data);
    } else if (h->plausible && (fault != 3u) && command) {
        const float request = (float)(fz_u8(r) & 1u);
        const float target = (float)(fz_u8(r) % 9u);
        const float current = (float)(fz_u8(r) % 9u);
        const float torque = map_u16(fz_u16(r), -1000.0f, 1000.0f);
        const float time_ms = map_u16(fz_u16(r), 50.0f, 2000.0f);
        const wc_can_shift_command_phys_t s = { request, 0.0f /* AdaptationReset */, target, torque, time_ms,
                                                current, 0u };
        (void)wc_can_encode_shift_command(f->data, &s, sizeof f->data);
    } else {
        for (size_t i = 0u; i < sizeof f->data; ++i) { f->data[i] = fz_u8(r); }
    }
    if (!(sensors || command) || (fault == 3u)) { return; }
    uint8_t *alive = sensors ? &h->alive_sensors : &h->alive_command;
    if (fault == 1u) { *alive = (uint8_t)((*alive + (fz_u8(r) & WC_E2E_COUNTER_MASK) + 15u) % 16u); }
    f->data[WC_E2E_COUNTER_BYTE] = (uint8_t)((f->data[WC_E2E_COUNTER_BYTE] & ~WC_E2E_COUNTER_MASK) | *alive);
    *alive = wc_e2e_counter_next(*alive);
    (void)wc_e2e_protect(f->id, f->data, sizeof f->data);
    if (fault == 2u) { f->data[WC_E2E_CRC_BYTE] ^= (uint8_t)(fz_u8(r) | 1u); }
}

static void check_counters(const harness_t *h)
{
    const uint32_t queued = loop.rx_tail - loop.rx_head;
    uint32_t rejected = 0u;
    for (unsigned i = 0u; i < (unsigned)WC_REJECT_REASONS; ++i) { rejected += loop.counters.rejected[i]; }
    FZ_CHECK(queued <= WC_LOOP_RX_CAPACITY, "ring holds %u frames", (unsigned)queued);
    FZ_CHECK(loop.counters.frames_used + rejected + queued == loop.counters.frames_in,
             "counters: used %u + rejected %u + queued %u != in %u", (unsigned)loop.counters.frames_used,
             (unsigned)rejected, (unsigned)queued, (unsigned)loop.counters.frames_in);
    FZ_CHECK((loop.counters.steps == h->steps) && (loop.counters.frames_out == h->frames_out),
             "steps %u (harness %u), frames out %u (harness %u)", (unsigned)loop.counters.steps, (unsigned)h->steps,
             (unsigned)loop.counters.frames_out, (unsigned)h->frames_out);
}

/* The step's frames (n of them) and the transmission's state. */
static void check_step(harness_t *h, const wc_can_frame_t *out, uint32_t n)
{
    const uint32_t elements = box->element_count;
    const float lsb_mA = 1.0f / 32.0f;  /* VfsCurrent scaling */
    const float lsb_Nm = 0.05f;         /* TorqueDelta scaling */
    h->steps++;
    FZ_CHECK((n == elements + 2u) || (n == elements + 3u), "%u frames in a step, expected %u (+1 ShiftReport)",
             (unsigned)n, (unsigned)(elements + 2u));

    /* GearboxStatus first: the safe state decides the element checks */
    const wc_can_frame_t *fs = &out[elements];
    FZ_CHECK((fs->id == WC_CAN_GEARBOX_STATUS_FRAME_ID) && (fs->dlc == 8u) && (fs->flags == 0u),
             "frame %u id 0x%x dlc %u flags %u (GearboxStatus expected)", (unsigned)elements, (unsigned)fs->id,
             (unsigned)fs->dlc, (unsigned)fs->flags);
    wc_can_gearbox_status_phys_t st;
    const wc_can_result_t rs = wc_can_decode_gearbox_status(&st, fs->data, fs->dlc);
    FZ_CHECK(!wc_can_is_error(rs), "GearboxStatus does not decode cleanly (result %d)", (int)rs);
    FZ_CHECK(fz_finite(st.gear) && fz_finite(st.target_gear) && fz_finite(st.shift_phase) &&
                 (st.gear <= (float)box->forward_gears) && (st.target_gear <= (float)box->forward_gears) &&
                 (st.shift_phase >= 0.0f) && (st.shift_phase <= 6.0f),
             "GearboxStatus gear %g target %g phase %g", (double)st.gear, (double)st.target_gear,
             (double)st.shift_phase);
    const uint16_t timeouts = WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_REQUEST_TIMEOUT;
    const bool safe = (st.status & WC_CAN_STATUS_SAFE_STATE_ACTIVE) != 0u;
    if ((st.status & timeouts) != 0u) {
        FZ_CHECK(safe, "timeout bits 0x%x without StatusSafeStateActive", (unsigned)st.status);
    }
    h->fresh_run = ((st.status & timeouts) != 0u) ? 0u : h->fresh_run + 1u;
    if (!safe) {
        FZ_CHECK(h->fresh_run >= loop.config.recovery_periods, "safe state left after %u fresh steps (recovery %u)",
                 (unsigned)h->fresh_run, (unsigned)loop.config.recovery_periods);
    }
    h->safe_run = safe ? h->safe_run + 1u : 0u;
    const bool idle = st.shift_phase == (float)WC_SHIFT_IDLE;
    const uint32_t gear = (uint32_t)st.gear;

    /* the elements' frames */
    for (uint32_t e = 0u; e < elements; ++e) {
        const wc_can_frame_t *f = &out[e];
        const wc_calibration_t *ec = tx_config.element[e];
        FZ_CHECK((f->id == WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID + e) && (f->dlc == 8u) && (f->flags == 0u),
                 "frame %u id 0x%x dlc %u flags %u (element %u's command expected)", (unsigned)e, (unsigned)f->id,
                 (unsigned)f->dlc, (unsigned)f->flags, (unsigned)e);
        FZ_CHECK(wc_e2e_check_crc(f->id, f->data, f->dlc) == WC_E2E_OK, "element %u: CRC with its own data id",
                 (unsigned)e);
        wc_can_frame_t copy = *f;  /* element A's layout and decoder: its CRC re-written with A's data id */
        (void)wc_e2e_protect(WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID, copy.data, copy.dlc);
        wc_can_element_a_vfs_command_phys_t c;
        const wc_can_result_t rc = wc_can_decode_element_a_vfs_command(&c, copy.data, copy.dlc);
        FZ_CHECK(!wc_can_is_error(rc), "element %u's command does not decode cleanly (result %d)", (unsigned)e, (int)rc);
        FZ_CHECK(fz_finite(c.vfs_current_mA) && fz_finite(c.pressure_command_kPa) && fz_finite(c.estimated_temp_degC) &&
                     (c.vfs_current_mA >= ec->vfs_current_min_mA - 0.5f * lsb_mA) &&
                     (c.vfs_current_mA <= ec->vfs_current_max_mA + 0.5f * lsb_mA) && (c.role <= 3u) && (c.locked <= 1u),
                 "element %u: current %g mA (range [%g, %g]), pressure %g, temperature %g, role %u, locked %u",
                 (unsigned)e, (double)c.vfs_current_mA, (double)ec->vfs_current_min_mA, (double)ec->vfs_current_max_mA,
                 (double)c.pressure_command_kPa, (double)c.estimated_temp_degC, (unsigned)c.role, (unsigned)c.locked);
        if (h->have_tx) {
            FZ_CHECK(c.alive_counter == (uint8_t)((h->element_alive[e] + 1u) % 16u), "element %u alive counter %u after %u",
                     (unsigned)e, (unsigned)c.alive_counter, (unsigned)h->element_alive[e]);
        }
        h->element_alive[e] = c.alive_counter;
        /* the transmission's own output: the frame would hide a NaN */
        const wc_step_output_t *o = &loop.transmission_out.element[e];
        FZ_CHECK(fz_finite(o->current_mA) && (o->current_mA >= ec->vfs_current_min_mA) &&
                     (o->current_mA <= ec->vfs_current_max_mA) && (fabsf(o->current_mA - c.vfs_current_mA) <= 0.5f * lsb_mA) &&
                     fz_finite(o->pressure_command_Pa) && fz_finite(o->theta_degC) && fz_finite(o->model.torque_Nm),
                 "element %u: model current %g mA (frame %g), pressure %g, theta %g, torque %g", (unsigned)e,
                 (double)o->current_mA, (double)c.vfs_current_mA, (double)o->pressure_command_Pa, (double)o->theta_degC,
                 (double)o->model.torque_Nm);
        /* the safe state holds the gear: a held element never let go, not even for a period */
        if (safe && h->safe_before && (h->element_role[e] == WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_HELD_CHOICE)) {
            FZ_CHECK(c.vfs_current_mA >= h->element_mA[e] - 0.5f * lsb_mA,
                     "safe state: held element %u lowered from %g to %g mA (gear %u, phase %g)", (unsigned)e,
                     (double)h->element_mA[e], (double)c.vfs_current_mA, (unsigned)gear, (double)st.shift_phase);
        }
        if (safe && idle && (h->safe_run > SAFE_SETTLE_STEPS) && (gear < WC_GEARBOX_GEARS_MAX)) {
            const bool closed = ((box->closed_mask[gear] >> e) & 1u) != 0u;
            const float want = closed ? ec->vfs_current_max_mA : ec->vfs_current_min_mA;
            FZ_CHECK(fabsf(c.vfs_current_mA - want) <= 0.5f * lsb_mA,
                     "safe state in gear %u: element %u (%s) at %g mA, expected %g", (unsigned)gear, (unsigned)e,
                     closed ? "closed" : "open", (double)c.vfs_current_mA, (double)want);
        }
        h->element_mA[e] = c.vfs_current_mA;
        h->element_role[e] = c.role;
    }

    /* EngineTorqueRequest */
    const wc_can_frame_t *fe = &out[elements + 1u];
    FZ_CHECK((fe->id == WC_CAN_ENGINE_TORQUE_REQUEST_FRAME_ID) && (fe->dlc == 8u) && (fe->flags == 0u),
             "frame %u id 0x%x (EngineTorqueRequest expected)", (unsigned)(elements + 1u), (unsigned)fe->id);
    wc_can_engine_torque_request_phys_t eng;
    const wc_can_result_t re = wc_can_decode_engine_torque_request(&eng, fe->data, fe->dlc);
    FZ_CHECK(!wc_can_is_error(re), "EngineTorqueRequest does not decode cleanly (result %d)", (int)re);
    const wc_shift_calibration_t *sc = tx_config.shift;
    const float half_lsb_Nm = 0.5f * lsb_Nm * 1.001f;  /* a tie rounds away from zero (fuzz_loop_check.c) */
    FZ_CHECK(((eng.intervention_active == 0.0f) || (eng.intervention_active == 1.0f)) && fz_finite(eng.torque_delta_Nm) &&
                 (eng.torque_delta_Nm >= -sc->engine_reduction_max_Nm - half_lsb_Nm) &&
                 (eng.torque_delta_Nm <= sc->engine_increase_max_Nm + half_lsb_Nm),
             "EngineTorqueRequest active %g delta %g (limits -%g, %g)", (double)eng.intervention_active,
             (double)eng.torque_delta_Nm, (double)sc->engine_reduction_max_Nm, (double)sc->engine_increase_max_Nm);
    if (eng.intervention_active == 0.0f) {
        FZ_CHECK(eng.torque_delta_Nm == 0.0f, "TorqueDelta %g with InterventionActive 0", (double)eng.torque_delta_Nm);
    }
    if (safe) {
        FZ_CHECK(eng.intervention_active == 0.0f, "InterventionActive in the safe state (delta %g)",
                 (double)eng.torque_delta_Nm);
    }
    if (h->have_tx) {
        FZ_CHECK(st.alive_counter == (uint8_t)((h->status_alive + 1u) % 16u), "GearboxStatus alive counter %u after %u",
                 (unsigned)st.alive_counter, (unsigned)h->status_alive);
        FZ_CHECK(eng.alive_counter == (uint8_t)((h->engine_alive + 1u) % 16u),
                 "EngineTorqueRequest alive counter %u after %u", (unsigned)eng.alive_counter, (unsigned)h->engine_alive);
    }
    h->status_alive = st.alive_counter;
    h->engine_alive = eng.alive_counter;
    h->have_tx = true;
    h->safe_before = safe;

    if (n == elements + 3u) {
        const wc_can_frame_t *fr = &out[elements + 2u];
        FZ_CHECK((fr->id == WC_CAN_SHIFT_REPORT_FRAME_ID) && (fr->dlc == 8u) && (fr->flags == 0u),
                 "frame %u id 0x%x (ShiftReport expected)", (unsigned)(elements + 2u), (unsigned)fr->id);
        wc_can_shift_report_phys_t q;
        const wc_can_result_t rq = wc_can_decode_shift_report(&q, fr->data, fr->dlc);
        FZ_CHECK(!wc_can_is_error(rq), "ShiftReport does not decode cleanly (result %d)", (int)rq);
        h->reports++;
        stats.reports++;
    }
    h->safe_steps += safe ? 1u : 0u;
    h->shift_steps += idle ? 0u : 1u;
    stats.phase_steps[(st.shift_phase <= 6.0f) ? (unsigned)st.shift_phase : 6u]++;
    stats.refusals += (st.refusal != 0u) ? 1u : 0u;
    check_counters(h);
}

static void iterate(harness_t *h, const wc_can_frame_t *frame, bool tick, unsigned record)
{
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    memset(out, 0, sizeof out);
    fz_context(frame ? "wc_loop_iterate(frame)" : "wc_loop_iterate(NULL, tick)", record);
    if (frame != NULL) {
        fz_ctx.iargs[0] = (long)frame->id;
        fz_ctx.iargs[1] = (long)frame->dlc * 16 + frame->flags;
    }
    const uint32_t n = wc_loop_iterate(&loop, h->clock, frame, tick, out);
    const bool expected = tick || ((h->clock == WC_LOOP_CLOCK_FRAME) && (frame != NULL) &&
                                   (frame->id == WC_CAN_GEARBOX_SENSORS_FRAME_ID) && (frame->flags == 0u));
    FZ_CHECK(expected || (n == 0u), "wc_loop_iterate returned %u frames without a step", (unsigned)n);
    FZ_CHECK(n <= WC_LOOP_TX_FRAMES, "wc_loop_iterate returned %u frames", (unsigned)n);
    h->frames_out += n;
    if (expected) {
        check_step(h, out, n);
    } else {
        check_counters(h);
    }
}

static void report_stats(void)
{
    const unsigned long *p = stats.phase_steps;
    fprintf(stderr, "fuzz_gearbox: %lu inputs, %lu loop steps (%.0f per input), safe %lu, steps by ShiftPhase: idle %lu "
                    "prepare %lu torque %lu inertia %lu lockup %lu locked %lu aborted %lu; shift reports %lu, steps "
                    "with a refusal %lu\n",
            stats.inputs, stats.steps, (stats.inputs > 0u) ? (double)stats.steps / (double)stats.inputs : 0.0,
            stats.safe_steps, p[0], p[1], p[2], p[3], p[4], p[5], p[6], stats.reports, stats.refusals);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    verbose = fz_env_flag("WC_FUZZ_VERBOSE");
    tx_config.gearbox = box;
    for (uint32_t e = 0u; e < box->element_count; ++e) { tx_config.element[e] = &wc_table1_calibration; }
    tx_config.shift = &wc_shift_1_2_whole_full;
    tx_config.holding_margin_factor = 1.2f;
    tx_config.holding_floor_Nm = 5.0f;
    (void)atexit(report_stats);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader_t r;
    fz_reader_init(&r, data, size);
    harness_t h;
    memset(&h, 0, sizeof h);
    const uint8_t options = fz_u8(&r);
    h.clock = ((options & 0x01u) != 0u) ? WC_LOOP_CLOCK_FRAME : WC_LOOP_CLOCK_TIMER;
    h.make_valid = (options & 0x02u) != 0u;
    h.plausible = (options & 0x04u) != 0u;
    const wc_loop_config_t defaults = WC_LOOP_CONFIG_DEFAULT;
    h.config = defaults;
    if ((options & 0x08u) != 0u) {
        h.config.sensor_timeout_periods = fz_u8(&r) % 32u;
        h.config.request_timeout_periods = fz_u8(&r) % 32u;
        h.config.e2e.max_delta_counter = fz_u8(&r) % 20u;
        h.config.e2e.sync_counter = fz_u8(&r) % 8u;
        h.config.recovery_periods = fz_u8(&r) % 64u;
    }
    h.config.transmission = &tx_config;
    h.config.transmission_start_gear = (uint32_t)(options >> 4) % 9u;
    fz_context("wc_loop_init(transmission; start gear, recovery)", 0u);
    fz_ctx.iargs[0] = (long)h.config.transmission_start_gear;
    fz_ctx.iargs[1] = (long)h.config.recovery_periods;
    FZ_CHECK(wc_loop_init(&loop, NULL, &h.config, 80.0f) == WC_CAL_OK, "wc_loop_init refused the transmission");

    unsigned record = 1u;
    for (; (record <= MAX_RECORDS) && fz_more(&r); ++record) {
        const uint8_t c = fz_u8(&r);
        if ((c & 3u) == 0u) {
            iterate(&h, NULL, true, record);
        } else if ((c & 3u) == 3u) {
            const uint8_t count = fz_u8(&r);
            fz_context("port event", record);
            switch ((c >> 2) & 3u) {
            case 0: wc_loop_port_event(&loop, WC_LOOP_PORT_RX_DROPPED, count); break;
            case 1: wc_loop_port_event(&loop, WC_LOOP_PORT_BUS_ERROR, count); break;
            case 2: wc_loop_port_event(&loop, WC_LOOP_PORT_TX_FAILED, count); break;
            default: wc_loop_deadline_missed(&loop, count); break;
            }
            check_counters(&h);
        } else {
            wc_can_frame_t f;
            build_frame(&h, &r, c, &f);
            const bool tick = ((c & 3u) == 2u) || ((h.clock == WC_LOOP_CLOCK_TIMER) && ((c & 0x04u) != 0u));
            iterate(&h, &f, tick, record);
        }
    }
    iterate(&h, NULL, true, MAX_RECORDS + 1u);  /* empties the ring */
    FZ_CHECK(loop.rx_tail == loop.rx_head, "frames left in the ring after a step");
    stats.inputs++;
    stats.steps += h.steps;
    stats.safe_steps += h.safe_steps;
    stats.shift_steps += h.shift_steps;
    if (verbose) {
        fprintf(stderr, "fuzz_gearbox: %zu bytes, clock %d, valid %d, plausible %d, start gear %u: steps %u (safe %u, "
                        "shifting %u), reports %u, gear %u, phase %u, frames in %u used %u\n",
                size, (int)h.clock, (int)h.make_valid, (int)h.plausible, (unsigned)h.config.transmission_start_gear,
                (unsigned)h.steps, (unsigned)h.safe_steps, (unsigned)h.shift_steps, (unsigned)h.reports,
                (unsigned)loop.transmission_out.gear, (unsigned)loop.transmission_out.shift_phase,
                (unsigned)loop.counters.frames_in, (unsigned)loop.counters.frames_used);
    }
    return 0;
}
