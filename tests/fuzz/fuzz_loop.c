/* libFuzzer harness of the CAN frame loop (include/wetclutch_can/wc_loop.h)
 * with the table1 calibration: a stream of CAN frames, timer ticks and port
 * events into one wc_loop_t through wc_loop_iterate.
 *
 * Input:
 *   byte 0  options: bit 0 clock (0 timer, 1 frame); bit 1 bench input
 *           enabled; bit 2 "make valid": the harness writes the E2E CRC
 *           (wc_e2e_protect) and an incrementing alive counter into every
 *           ClutchSensors/TorqueRequest frame, so that the fuzzer gets past
 *           E2E into the model; bit 3 "plausible": the signals of those
 *           frames (and BenchMeasurement) are mapped into their DBC ranges
 *           (the physical encoders write them); bits 4-5 start temperature
 *           (40, -40, 250 degC or NaN); bit 6 a fuzzed loop configuration
 *           (timeouts, E2E MaxDeltaCounter/SyncCounter, recovery) follows in
 *           bytes 1-5, else WC_LOOP_CONFIG_DEFAULT; bit 7 shift control on
 *           (config.shift = shift_1_2 full, or with bit 1 shift_1_2 adaptive:
 *           adaptation on, DESIGN 12; bench input off, and the
 *           BenchMeasurement choice of the frame id below is ShiftCommand,
 *           E2E-valid and plausible like the other control frames, Mode 0..3).
 *   with bit 7, one more byte (after the configuration bytes): bit 0 the
 *           whole shift (DESIGN 14): config.shift = shift_1_2 whole_full
 *           (coordinator 1, engine intervention; bit 1 of byte 0 no longer
 *           picks adaptive) and config.offgoing = the table1 calibration (the
 *           on-coming clutch's); the third ClutchSensors choice of the frame
 *           id below is then OffgoingSensors (E2E-valid and plausible like the
 *           other control frames, its own alive counter; raw bytes give SNA
 *           and out-of-range values); bits 1-4 (with bit 0) the start: 0 at
 *           wc_loop_init as above, k = 1..15 inside the whole shift, from the
 *           snapshot start_points[(k - 1) % 10] ("Starts inside the whole
 *           shift" below: idle in Shift mode, torque phase, inertia phase,
 *           lock-up, locked, fallbacks) that a fixed scripted prefix left; the
 *           loop's configuration and start temperature are then the
 *           snapshot's (byte 0 bits 4-5 unused), a fuzzed loop configuration
 *           (bit 6) is applied with wc_loop_recalibrate, and the clock,
 *           "make valid" and "plausible" are the input's; bits 5-7 unused.
 *   then records until the bytes run out (at most MAX_RECORDS), each a
 *   command byte c:
 *     c & 3 == 0  a timer tick without a frame
 *     c & 3 == 1  a frame; with the timer clock, a tick too if c bit 2
 *     c & 3 == 2  a frame and a tick
 *     c & 3 == 3  a port event (RX dropped / bus error / TX failed /
 *                 deadline missed) with a count byte; with c bit 4 an XCP
 *                 command frame instead (below)
 *   c bits 3-5 choose the frame id (ClutchSensors x3, TorqueRequest x3,
 *   BenchMeasurement, other); "other" reads a 16-bit id, and a byte of
 *   format (bit 7 set: DLC = low nibble 0..15, flags = bits 4-6) follows
 *   for every frame; then 8 data bytes (in plausible mode: 2 bytes per
 *   signal). c bits 6-7 are the fault in "make valid" mode: 0 none, 1 alive
 *   counter advanced by a fuzzed nibble (one more byte: 0 repeats, 2 loses a
 *   frame, ...), 2 a wrong CRC (one more byte), 3 the frame as fuzzed.
 *
 * XCP (wc_xcp.h, DESIGN 13): a wc_xcp_t beside the loop, started at the
 * input's first XCP frame, its reference page the loop's calibration
 * (wc_cal_set_from + wc_cal_image_encode; a fuzzed loop configuration
 * outside the image's limits: no slave, an XCP record is a port event). As in
 * wc_tcu, every frame of the XcpCommand id goes to wc_xcp_receive (the loop
 * iterates without it) and wc_xcp_step runs after every wc_loop_iterate
 * (control_step = the loop stepped) into its own output array, except after
 * an XCP record with c bit 6 that did not step the loop (its frame waits in
 * the ring: several in a row overflow it). An XCP
 * record (c & 3 == 3, c bit 4; c bit 5: a tick with it) is a selector byte
 * s, then [a format byte as above if s bit 6], then 7 data bytes after the
 * command code: s & 0x1F picks the code from xcp_codes (past its end: the
 * first data byte is the code); s bit 5 "aimed": an address (SET_MTA,
 * SHORT_UPLOAD, WRITE_DAQ) is put inside or just past a region (data byte 4
 * picks it, bytes 5-6 the offset), extension 0; a DOWNLOAD writes 4 bytes,
 * the working page's float at the MTA times 1 + (int8)byte 2 / 128 (so that
 * pages the check accepts, with other values, reach the loop); SET_CAL_PAGE
 * a valid mode and page 0/1; BUILD_CHECKSUM a block of at most 1 KiB.
 *
 * Oracle after every wc_loop_iterate (abort with a message on violation):
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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_e2e.h>
#include <wetclutch_can/wc_loop.h>
#include <wetclutch_can/wc_xcp.h>

#include "wc_fuzz_common.h"
#include "wc_shift_1_2_shift.h"
#include "wc_table1_calibration.h"

#define MAX_RECORDS 4096u

static const wc_calibration_t *const cal = &wc_table1_calibration;
static bool verbose;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
    wc_loop_clock_t clock;
    bool make_valid;
    bool plausible;
    wc_loop_config_t config;
    uint8_t alive_sensors;   /* next alive counter of each E2E frame ("make valid") */
    uint8_t alive_request;
    uint8_t alive_shift;
    uint8_t alive_offgoing;
    bool shift;              /* shift control on */
    bool whole;              /* the whole shift (wc_loop_whole_shift) */
    bool have_whole_tx;      /* OffgoingVfsCommand/EngineTorqueRequest seen: their counters must count */
    uint8_t offgoing_alive;
    uint8_t engine_alive;
    float engine_increase_max_Nm;   /* the widest engine limits of the shift calibrations the loop ran on */
    float engine_reduction_max_Nm;
    uint32_t engine_steps;   /* statistics for WC_FUZZ_VERBOSE: InterventionActive, fallback in the safe state */
    uint32_t fallback_steps;
    bool shift_stepped;      /* the step ran the shift controller (Shift mode, or a shift running before it) */
    uint32_t reports;        /* ShiftReports, and the last one's AbortReason (WC_FUZZ_VERBOSE) */
    uint8_t last_abort;
    uint32_t frames_out;     /* frames the steps returned */
    bool have_tx;            /* a VfsCommand was seen: its counter must count */
    uint8_t tx_alive;
    uint32_t fresh_run;      /* consecutive steps without a timeout bit */
    uint32_t steps;
    uint32_t safe_steps;     /* statistics for WC_FUZZ_VERBOSE */
    uint32_t control_steps;
} harness_t;

static wc_loop_t loop;  /* ~1 KiB: static, not on the fuzzer's stack */
static wc_xcp_t xcp;    /* the XCP slave beside the loop (~10 KiB) */
static bool xcp_on;     /* wc_xcp_init accepted the loop's calibration as a page */
static bool xcp_tried;  /* wc_xcp_init was tried (at the input's first XCP frame) */
static uint32_t xcp_checks;  /* page checks seen (accepted + rejected): the calibration can change only there */
static wc_cal_set_t xcp_set;
static uint8_t xcp_reference[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
static const wc_xcp_config_t xcp_config = WC_XCP_CONFIG_DEFAULT;
static uint32_t xcp_frames;  /* statistics for WC_FUZZ_VERBOSE */

/* The commands an XCP record picks (s & 0x1F); past the end the frame's first data byte is the code. */
static const uint8_t xcp_codes[] = {
    WC_XCP_CONNECT, WC_XCP_DISCONNECT, WC_XCP_GET_STATUS, WC_XCP_SYNCH, WC_XCP_GET_COMM_MODE_INFO, WC_XCP_GET_ID,
    WC_XCP_SET_MTA, WC_XCP_UPLOAD, WC_XCP_SHORT_UPLOAD, WC_XCP_BUILD_CHECKSUM, WC_XCP_DOWNLOAD, WC_XCP_DOWNLOAD,
    WC_XCP_SET_CAL_PAGE, WC_XCP_GET_CAL_PAGE, WC_XCP_GET_PAG_PROCESSOR_INFO, WC_XCP_COPY_CAL_PAGE,
    WC_XCP_SET_DAQ_PTR, WC_XCP_WRITE_DAQ, WC_XCP_SET_DAQ_LIST_MODE, WC_XCP_START_STOP_DAQ_LIST,
    WC_XCP_START_STOP_SYNCH, WC_XCP_GET_DAQ_CLOCK, WC_XCP_GET_DAQ_PROCESSOR_INFO, WC_XCP_GET_DAQ_RESOLUTION_INFO,
    WC_XCP_GET_DAQ_EVENT_INFO, WC_XCP_FREE_DAQ, WC_XCP_ALLOC_DAQ, WC_XCP_ALLOC_ODT, WC_XCP_ALLOC_ODT_ENTRY,
};

static float map_u16(uint16_t u, float lo, float hi) { return lo + (hi - lo) * ((float)u / 65535.0f); }

/* A frame as the fuzzer describes it (see the top of the file). */
static void build_frame(harness_t *h, fz_reader_t *r, uint8_t c, wc_can_frame_t *f)
{
    static const uint32_t ids[7] = {
        WC_CAN_CLUTCH_SENSORS_FRAME_ID, WC_CAN_CLUTCH_SENSORS_FRAME_ID, WC_CAN_CLUTCH_SENSORS_FRAME_ID,
        WC_CAN_TORQUE_REQUEST_FRAME_ID, WC_CAN_TORQUE_REQUEST_FRAME_ID, WC_CAN_TORQUE_REQUEST_FRAME_ID,
        WC_CAN_BENCH_MEASUREMENT_FRAME_ID,
    };
    const uint8_t sel = (uint8_t)((c >> 3) & 7u);
    memset(f, 0, sizeof *f);
    f->id = (sel < 7u) ? ids[sel] : (uint32_t)fz_u16(r);
    if ((sel == 6u) && h->shift) { f->id = WC_CAN_SHIFT_COMMAND_FRAME_ID; }
    if ((sel == 2u) && h->whole) { f->id = WC_CAN_OFFGOING_SENSORS_FRAME_ID; }
    const uint8_t format = fz_u8(r);
    if ((format & 0x80u) != 0u) {
        f->dlc = (uint8_t)(format & 0x0Fu);
        f->flags = (uint8_t)((format >> 4) & 0x07u);
        if ((f->flags & WC_CAN_FLAG_EXTENDED) != 0u) { f->id = (f->id << 13) ^ fz_u16(r); }  /* 29-bit ids */
    } else {
        f->dlc = 8u;
        f->flags = 0u;
    }
    const uint8_t fault = h->make_valid ? (uint8_t)(c >> 6) : 3u;
    const bool sensors = (f->id == WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    const bool request = (f->id == WC_CAN_TORQUE_REQUEST_FRAME_ID);
    const bool bench = (f->id == WC_CAN_BENCH_MEASUREMENT_FRAME_ID);
    const bool shift = h->shift && (f->id == WC_CAN_SHIFT_COMMAND_FRAME_ID);
    const bool offgoing = h->whole && (f->id == WC_CAN_OFFGOING_SENSORS_FRAME_ID);
    if (h->plausible && (fault != 3u) && offgoing) {
        const wc_can_offgoing_sensors_phys_t o = { map_u16(fz_u16(r), -8000.0f, 8000.0f), 0u };
        (void)wc_can_encode_offgoing_sensors(f->data, &o, sizeof f->data);
    } else if (h->plausible && (fault != 3u) && shift) {
        const wc_can_shift_command_phys_t s = {
            (float)(fz_u8(r) & 1u), (float)(fz_u8(r) & 1u) /* AdaptationReset */, (float)(fz_u8(r) % 8u + 1u),
            map_u16(fz_u16(r), -1000.0f, 1000.0f),
            map_u16(fz_u16(r), 50.0f, 2000.0f), 0u };
        (void)wc_can_encode_shift_command(f->data, &s, sizeof f->data);
    } else if (h->plausible && (fault != 3u) && (sensors || request || bench)) {
        if (sensors) {
            const wc_can_clutch_sensors_phys_t s = {
                map_u16(fz_u16(r), -8000.0f, 8000.0f), map_u16(fz_u16(r), -40.0f, 200.0f),
                map_u16(fz_u16(r), -40.0f, 200.0f), 0u };
            (void)wc_can_encode_clutch_sensors(f->data, &s, sizeof f->data);
        } else if (request) {
            const wc_can_torque_request_phys_t q = { map_u16(fz_u16(r), 0.0f, 2000.0f),
                                                     (uint8_t)(fz_u8(r) % (h->shift ? 4u : 3u)), 0u };
            (void)wc_can_encode_torque_request(f->data, &q, sizeof f->data);
        } else {
            const wc_can_bench_measurement_phys_t b = {
                map_u16(fz_u16(r), -20000.0f, 20000.0f), map_u16(fz_u16(r), -5000.0f, 5000.0f),
                map_u16(fz_u16(r), -40.0f, 350.0f) };
            (void)wc_can_encode_bench_measurement(f->data, &b, sizeof f->data);
        }
    } else {
        for (size_t i = 0u; i < sizeof f->data; ++i) { f->data[i] = fz_u8(r); }
    }
    if (!h->make_valid || !(sensors || request || shift || offgoing) || (fault == 3u)) { return; }
    uint8_t *alive = sensors ? &h->alive_sensors
                             : (request ? &h->alive_request : (shift ? &h->alive_shift : &h->alive_offgoing));
    if (fault == 1u) {  /* counter = previous + delta: 0 repeats, 2 loses one frame, ... */
        const uint8_t delta = (uint8_t)(fz_u8(r) & WC_E2E_COUNTER_MASK);
        *alive = (uint8_t)((*alive + delta + 15u) % 16u);
    }
    f->data[WC_E2E_COUNTER_BYTE] = (uint8_t)((f->data[WC_E2E_COUNTER_BYTE] & ~WC_E2E_COUNTER_MASK) | *alive);
    *alive = wc_e2e_counter_next(*alive);
    (void)wc_e2e_protect(f->id, f->data, sizeof f->data);
    if (fault == 2u) { f->data[WC_E2E_CRC_BYTE] ^= (uint8_t)(fz_u8(r) | 1u); }  /* a wrong CRC */
}

static uint32_t rejected_sum(const wc_loop_t *l)
{
    uint32_t n = 0u;
    for (unsigned i = 0u; i < (unsigned)WC_REJECT_REASONS; ++i) { n += l->counters.rejected[i]; }
    return n;
}

static void check_counters(const harness_t *h)
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
static void check_step(harness_t *h, const wc_can_frame_t out[WC_LOOP_TX_FRAMES])
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

static bool same_bits(float a, float b)
{
    uint32_t x;
    uint32_t y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

/* wc_xcp_step after the loop's iteration, into its own array, and its oracle. */
static void xcp_step(const harness_t *h, bool control_step, unsigned record)
{
    wc_can_frame_t xout[WC_XCP_TX_FRAMES];  /* exactly the contract's size: ASan sees a write past it */
    memset(xout, 0, sizeof xout);
    fz_context("wc_xcp_step(control_step)", record);
    fz_ctx.iargs[0] = control_step;
    const uint32_t n = wc_xcp_step(&xcp, control_step, xout);
    FZ_CHECK(n <= WC_XCP_TX_FRAMES, "wc_xcp_step returned %u frames", (unsigned)n);
    xcp_frames += n;
    for (uint32_t i = 0u; i < n; ++i) {
        const wc_can_frame_t *f = &xout[i];
        FZ_CHECK((f->id == WC_CAN_XCP_RESPONSE_FRAME_ID) && (f->dlc == 8u) && (f->flags == 0u),
                 "XCP frame %u: id 0x%x dlc %u flags %u", (unsigned)i, (unsigned)f->id, (unsigned)f->dlc,
                 (unsigned)f->flags);
        const uint8_t pid = f->data[0];
        FZ_CHECK((pid == WC_XCP_PID_RES) || (pid == WC_XCP_PID_ERR) || (pid == WC_XCP_PID_EV) || (pid < xcp.odt_count),
                 "XCP frame %u: PID 0x%02x (ODTs %u)", (unsigned)i, (unsigned)pid, (unsigned)xcp.odt_count);
    }
    const uint32_t checks = xcp.status.pages_accepted + xcp.status.pages_rejected;
    if (checks == xcp_checks) { return; }  /* no page check in this step: the loop's calibration is as it was */
    xcp_checks = checks;
    const wc_calibration_t *now = loop.clutch.model.cal;
    const wc_cal_error_t e = wc_calibration_check(now);
    FZ_CHECK(e == WC_CAL_OK, "the loop runs on a calibration the check refuses: %s", wc_cal_error_name(e));
    FZ_CHECK(same_bits(now->control_period_s, cal->control_period_s), "control period changed online: %g s",
             (double)now->control_period_s);
    FZ_CHECK((loop.config.shift != NULL) == h->shift, "shift control %s online",
             (loop.config.shift != NULL) ? "switched on" : "switched off");
    FZ_CHECK(wc_loop_whole_shift(&loop.config) == h->whole, "the whole shift %s online",
             h->whole ? "switched off" : "switched on");
    if (h->whole) {
        const wc_cal_error_t eo = wc_calibration_check(loop.offgoing.model.cal);
        FZ_CHECK(eo == WC_CAL_OK, "the off-going clutch runs on a calibration the check refuses: %s",
                 wc_cal_error_name(eo));
    }
    if (loop.config.shift != NULL) {
        FZ_CHECK(wc_shift_calibration_check(loop.config.shift) == WC_SHIFT_CAL_OK,
                 "the loop runs on a shift calibration the check refuses");
    }
}

/* The slave, started at the input's first XCP frame (inputs without one pay nothing for it): the loop still
 * runs on the calibration it was initialised with, the reference page's. A fuzzed loop configuration outside
 * the image's limits (a timeout or SyncCounter 0, ...) does not decode: no slave then. */
static bool xcp_start(const harness_t *h)
{
    if (!xcp_tried) {
        xcp_tried = true;
        xcp_on = wc_cal_set_from(&xcp_set, cal, h->config.shift, &h->config);
        if (xcp_on) {
            wc_cal_image_encode(&xcp_set, xcp_reference);
            xcp_on = wc_xcp_init(&xcp, &loop, xcp_reference, &xcp_config);
        }
    }
    return xcp_on;
}

/* An XCP command frame as the fuzzer describes it (see the top of the file). */
static void build_xcp_frame(fz_reader_t *r, wc_can_frame_t *f)
{
    const uint8_t s = fz_u8(r);
    memset(f, 0, sizeof *f);
    f->id = WC_CAN_XCP_COMMAND_FRAME_ID;
    f->dlc = 8u;
    if ((s & 0x40u) != 0u) {
        const uint8_t format = fz_u8(r);
        f->dlc = (uint8_t)(format & 0x0Fu);
        f->flags = (uint8_t)((format >> 4) & 0x07u);
    }
    const uint32_t pick = s & 0x1Fu;
    uint8_t *d = f->data;
    for (size_t i = 1u; i < sizeof f->data; ++i) { d[i] = fz_u8(r); }
    d[0] = (pick < sizeof xcp_codes) ? xcp_codes[pick] : d[1];
    if ((s & 0x20u) == 0u) { return; }  /* as fuzzed */
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&xcp, regions);
    switch (d[0]) {
    case WC_XCP_SET_MTA:
    case WC_XCP_SHORT_UPLOAD:
    case WC_XCP_WRITE_DAQ: {
        const wc_xcp_region_t *g = &regions[d[4] & 3u];
        const uint32_t address = g->base + (uint32_t)(d[5] | (d[6] << 8)) % (g->size + 8u);
        d[3] = 0u;
        for (uint32_t i = 0u; i < 4u; ++i) { d[4u + i] = (uint8_t)(address >> (8u * i)); }
        if (d[0] == WC_XCP_WRITE_DAQ) { d[1] = 0xFFu; d[2] = (uint8_t)(d[2] % 8u); }
        break;
    }
    case WC_XCP_DOWNLOAD: {
        const uint32_t offset = xcp.mta - regions[0].base;
        const float factor = 1.0f + (float)(int8_t)d[2] / 128.0f;
        float v = factor;
        if ((xcp.mta >= regions[0].base) && (offset + 4u <= regions[0].size)) {
            memcpy(&v, &xcp.working_page[offset], sizeof v);
            v *= factor;
        }
        d[1] = 4u;
        memcpy(&d[2], &v, sizeof v);
        break;
    }
    case WC_XCP_SET_CAL_PAGE:
        d[1] = (uint8_t)(1u + d[1] % 3u);
        d[2] = 0u;
        d[3] &= 1u;
        break;
    case WC_XCP_BUILD_CHECKSUM:
        d[6] = 0u;
        d[7] = 0u;
        d[5] &= 3u;
        break;
    default:
        break;
    }
}

static void iterate(harness_t *h, const wc_can_frame_t *frame, bool tick, unsigned record, bool xcp_waits)
{
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    memset(out, 0, sizeof out);
    fz_context(frame ? "wc_loop_iterate(frame)" : "wc_loop_iterate(NULL, tick)", record);
    if (frame != NULL) {
        fz_ctx.iargs[0] = (long)frame->id;
        fz_ctx.iargs[1] = (long)frame->dlc * 16 + frame->flags;
    }
    const bool running_before = wc_shift_phase_running(loop.shift.phase);
    const uint32_t n = wc_loop_iterate(&loop, h->clock, frame, tick, out);
    /* as wc_loop.c prepare: Mode is the last used TorqueRequest's (frames are processed only in the step) */
    h->shift_stepped = h->shift && ((loop.request.mode == WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE) || running_before);
    const bool expected = tick || ((h->clock == WC_LOOP_CLOCK_FRAME) && (frame != NULL) &&
                                   (frame->id == WC_CAN_CLUTCH_SENSORS_FRAME_ID) && (frame->flags == 0u));
    const bool adaptive = h->shift && (loop.config.shift->adaptation == 1u);
    /* the cyclic frames: VfsCommand, ClutchEstimate (and OffgoingVfsCommand, EngineTorqueRequest: the whole shift) */
    const uint32_t cyclic = WC_LOOP_TX_CYCLIC + (h->whole ? WC_LOOP_TX_WHOLE_SHIFT : 0u);
    const uint32_t most = !h->shift ? cyclic : (adaptive ? cyclic + 2u : cyclic + 1u);
    FZ_CHECK(expected ? ((n >= cyclic) && (n <= most) && (n <= WC_LOOP_TX_FRAMES)) : (n == 0u),
             "wc_loop_iterate returned %u, expected %u..%u", (unsigned)n, expected ? (unsigned)cyclic : 0u,
             expected ? (unsigned)most : 0u);
    for (uint32_t i = cyclic; expected && (i < n); ++i) {
        FZ_CHECK((out[i].dlc == 8u) && (out[i].flags == 0u), "frame %u dlc %u flags %u", (unsigned)i,
                 (unsigned)out[i].dlc, (unsigned)out[i].flags);
        if (out[i].id == WC_CAN_SHIFT_REPORT_FRAME_ID) {
            FZ_CHECK(i == cyclic, "ShiftReport at position %u", (unsigned)i);
            wc_can_shift_report_phys_t q;
            const wc_can_result_t rq = wc_can_decode_shift_report(&q, out[i].data, out[i].dlc);
            FZ_CHECK(!wc_can_is_error(rq), "ShiftReport does not decode cleanly (result %d)", (int)rq);
            h->reports++;
            h->last_abort = q.abort_reason;
        } else {
            FZ_CHECK(adaptive && (out[i].id == WC_CAN_ADAPTATION_REPORT_FRAME_ID), "frame %u id 0x%x", (unsigned)i,
                     (unsigned)out[i].id);
            wc_can_adaptation_report_phys_t a;
            const wc_can_result_t ra = wc_can_decode_adaptation_report(&a, out[i].data, out[i].dlc);
            FZ_CHECK(!wc_can_is_error(ra), "AdaptationReport does not decode cleanly (result %d)", (int)ra);
        }
    }
    if (adaptive) {
        FZ_CHECK(wc_adapt_values_valid(&loop.adapt.values, loop.config.shift), "learned values outside their bands");
    }
    h->frames_out += n;
    if (n >= cyclic) {
        check_step(h, out);
    } else {
        check_counters(h);
    }
    if (xcp_on && ((n > 0u) || !xcp_waits)) { xcp_step(h, n > 0u, record); }
}

/* The records of an input (see the top of the file) until the bytes run out or *record passes MAX_RECORDS. */
static void run_records(harness_t *h, fz_reader_t *r, unsigned *record)
{
    for (; (*record <= MAX_RECORDS) && fz_more(r); ++*record) {
        const uint8_t c = fz_u8(r);
        switch (c & 3u) {
        case 0:
            iterate(h, NULL, true, *record, false);
            break;
        case 1:
        case 2: {
            wc_can_frame_t f;
            build_frame(h, r, c, &f);
            const bool tick = ((c & 3u) == 2u) || ((h->clock == WC_LOOP_CLOCK_TIMER) && ((c & 0x04u) != 0u));
            if ((f.id == WC_CAN_XCP_COMMAND_FRAME_ID) && xcp_start(h)) {  /* as wc_tcu: the slave's, not the loop's */
                (void)wc_xcp_receive(&xcp, &f);
                iterate(h, NULL, tick, *record, false);
            } else {
                iterate(h, &f, tick, *record, false);
            }
            break;
        }
        default: {
            if (((c & 0x10u) != 0u) && xcp_start(h)) {  /* an XCP command frame */
                wc_can_frame_t f;
                build_xcp_frame(r, &f);
                (void)wc_xcp_receive(&xcp, &f);  /* a full ring is counted */
                iterate(h, NULL, (c & 0x20u) != 0u, *record, (c & 0x40u) != 0u);
                break;
            }
            const uint8_t count = fz_u8(r);
            fz_context("port event", *record);
            switch ((c >> 2) & 3u) {
            case 0: wc_loop_port_event(&loop, WC_LOOP_PORT_RX_DROPPED, count); break;
            case 1: wc_loop_port_event(&loop, WC_LOOP_PORT_BUS_ERROR, count); break;
            case 2: wc_loop_port_event(&loop, WC_LOOP_PORT_TX_FAILED, count); break;
            default: wc_loop_deadline_missed(&loop, count); break;
            }
            check_counters(h);
            break;
        }
        }
    }
}

/* The loop configuration bytes (options bit 6; see the top of the file) into h->config. */
static void read_loop_config(harness_t *h, fz_reader_t *r)
{
    h->config.sensor_timeout_periods = fz_u8(r) % 32u;
    h->config.request_timeout_periods = fz_u8(r) % 32u;
    h->config.e2e.max_delta_counter = fz_u8(r) % 20u;
    h->config.e2e.sync_counter = fz_u8(r) % 8u;
    h->config.recovery_periods = fz_u8(r) % 64u;
}

/* The harness options of byte 0 that are not the loop's state (a start from a snapshot takes them too). */
static void read_harness_options(harness_t *h, uint8_t options)
{
    h->clock = ((options & 0x01u) != 0u) ? WC_LOOP_CLOCK_FRAME : WC_LOOP_CLOCK_TIMER;
    h->make_valid = (options & 0x04u) != 0u;
    h->plausible = (options & 0x08u) != 0u;
}

/* The header of an input: byte 0 (*options), the loop configuration (bit 6), the shift-options byte (bit 7;
 * else 0: *shift_options); into h (zeroed first). Returns the start temperature (bits 4-5). */
static float read_header(harness_t *h, fz_reader_t *r, uint8_t *options_out, uint8_t *shift_options_out)
{
    memset(h, 0, sizeof *h);
    const uint8_t options = fz_u8(r);
    read_harness_options(h, options);
    static const float starts[4] = { 40.0f, -40.0f, 250.0f, NAN };
    const float theta_start_degC = starts[(options >> 4) & 3u];
    const wc_loop_config_t defaults = WC_LOOP_CONFIG_DEFAULT;
    h->config = defaults;
    if ((options & 0x40u) != 0u) { read_loop_config(h, r); }
    h->shift = (options & 0x80u) != 0u;
    h->config.bench_input_enabled = ((options & 0x02u) != 0u) && !h->shift;
    h->config.shift = !h->shift ? NULL : (((options & 0x02u) != 0u) ? &wc_shift_1_2_adaptive : &wc_shift_1_2_full);
    const uint8_t shift_options = h->shift ? fz_u8(r) : 0u;
    if ((shift_options & 0x01u) != 0u) {  /* the whole shift: the off-going clutch as the on-coming one */
        h->config.shift = &wc_shift_1_2_whole_full;
        h->config.offgoing = cal;
    }
    h->whole = wc_loop_whole_shift(&h->config);
    if (h->whole) {
        h->engine_increase_max_Nm = h->config.shift->engine_increase_max_Nm;
        h->engine_reduction_max_Nm = h->config.shift->engine_reduction_max_Nm;
    }
    *options_out = options;
    *shift_options_out = shift_options;
    return theta_start_degC;
}

/* A fresh loop for the header read: wc_loop_init. */
static void start_fresh(harness_t *h, uint8_t options, uint8_t shift_options, float theta_start_degC)
{
    fz_context("wc_loop_init(theta_start; options, recovery)", 0u);
    fz_arg(theta_start_degC);
    fz_ctx.iargs[0] = options | (shift_options << 8);
    fz_ctx.iargs[1] = (long)h->config.recovery_periods;
    FZ_CHECK(wc_loop_init(&loop, cal, &h->config, theta_start_degC) == WC_CAL_OK, "wc_loop_init failed");
    FZ_CHECK(wc_loop_whole_shift(&loop.config) == h->whole, "the loop's whole shift %d, configured %d",
             (int)wc_loop_whole_shift(&loop.config), (int)h->whole);
}

/* ------------------------------------------------------------------------ */
/* Starts inside the whole shift (shift-options bits 1-4)                   */
/* ------------------------------------------------------------------------ */

/* A whole shift needs hundreds of loop steps to reach its later phases (PREPARE 50 periods, TORQUE 220, INERTIA
 * at least 200, LOCKUP 50, a fallback's finish 1000): an input that starts there at wc_loop_init is long and every
 * execution of it pays for the phases before. Instead an input can start from a snapshot: the loop (and the
 * harness's own state: its E2E senders' counters, the oracle's history) as a fixed scripted prefix left it. The
 * prefixes are frame streams through the same records, iterate() and oracle as any input; they do not depend on
 * fuzz bytes. They run once, in LLVMFuzzerInitialize; an input that starts from one costs a copy of the loop.
 * wc_loop_t is caller-owned plain storage (no allocation, no state outside it): restored at the same address
 * its pointers (the off-going view into the loop, the calibrations) are those of the run that made it.
 *
 * The scripts are those of make_seeds.py (SCRIPT_NOMINAL, the whole_shift seed's scenario, in the frames of its
 * whole_periods: a 1->2 upshift at a constant output speed, ClutchSensors with the tick every 2nd 1 ms period and
 * a bare tick between, OffgoingSensors every 4th, ShiftCommand and TorqueRequest in Shift mode every 10th), with
 * byte 0 = 0xCC (shift control, loop configuration, plausible, make valid; timer clock, 40 degC), its
 * WHOLE_CONFIG (timeouts 25, MaxDeltaCounter 2, SyncCounter 2, recovery 5) and the whole shift. A seed that
 * starts from a snapshot continues the same script from its period; started at wc_loop_init with the script's
 * periods before it, the same input gives the same loop state bit for bit. */
#define W_O_RPM (3000.0 / 4.7)
#define SLIP_12_RPM ((4.7 - 3.1) * W_O_RPM)
#define INERTIA_MS 250.0
static const uint8_t prefix_header[] = { 0x80u | 0x40u | 0x08u | 0x04u, 25u, 25u, 2u, 2u, 5u, 0x01u };

enum { LOST_NONE = 0u, LOST_ALL = 1u };
typedef struct {
    uint32_t first;          /* periods first..last-1 */
    uint32_t last;
    uint8_t request;         /* ShiftCommand.ShiftRequest */
    int32_t inertia_start;   /* the period the slip starts to fall (smoothstep over INERTIA_MS); < 0: not yet */
    uint8_t lost;            /* LOST_ALL: no frame at all, a bare tick per period */
} segment_t;

typedef struct {
    const char *name;
    const segment_t *script;  /* ends with last == 0 */
    uint32_t period;          /* the snapshot is taken before this period of the script */
} start_point_t;

/* make_seeds.py SCRIPT_NOMINAL: in Shift mode, the request edge at 30, the slip falls from 300, withdrawn at 640. */
static const segment_t script_nominal[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 300u, 1u, -1, LOST_NONE }, { 300u, 640u, 1u, 300, LOST_NONE },
    { 640u, 660u, 0u, 300, LOST_NONE }, { 0u, 0u, 0u, 0, 0u } };
/* Every input lost in the inertia phase (the sensors time out after 25 periods): finished on the model, released
 * after fallback_time_s (1 s). */
static const segment_t script_lost_inertia[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 300u, 1u, -1, LOST_NONE }, { 300u, 400u, 1u, 300, LOST_NONE },
    { 400u, 1420u, 1u, 300, LOST_ALL }, { 0u, 0u, 0u, 0, 0u } };
/* Every input lost in the torque phase: handed back. */
static const segment_t script_lost_torque[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 200u, 1u, -1, LOST_NONE }, { 200u, 300u, 1u, -1, LOST_ALL },
    { 0u, 0u, 0u, 0, 0u } };

/* shift-options bits 1-4: 0 wc_loop_init, k = 1..15 start_points[(k - 1) % N]. The phases are those the table1
 * calibration and wc_shift_1_2_whole_full give (WC_FUZZ_VERBOSE=1 prints them); make_seeds.py START has the same table. */
static const start_point_t start_points[] = {
    { "idle in Shift mode, inputs fresh (the request edge next)", script_nominal, 30u },
    { "torque phase, its start", script_nominal, 90u },
    { "torque phase, 20 ms before its end", script_nominal, 280u },
    { "inertia phase, the off-going clutch's hand-over", script_nominal, 305u },
    { "inertia phase, its middle", script_nominal, 430u },
    { "lock-up hand-over", script_nominal, 560u },
    { "locked (the request withdrawn at 640)", script_nominal, 620u },
    { "inputs lost 30 periods ago in the inertia phase (fallback finish)", script_lost_inertia, 430u },
    { "fallback finish, 25 periods before its end (released)", script_lost_inertia, 1390u },
    { "inputs lost 30 periods ago in the torque phase (handed back)", script_lost_torque, 230u },
};
#define START_POINTS (sizeof start_points / sizeof start_points[0])

typedef struct {
    wc_loop_t loop;
    harness_t h;
} snapshot_t;
static snapshot_t snapshots[START_POINTS];  /* 1.7 KiB each */

static size_t put_u16_of(uint8_t *b, double x, double lo, double hi)
{
    /* make_seeds.py u16_of: round half to even (nearbyint in the default rounding mode), saturated */
    double u = nearbyint((x - lo) / (hi - lo) * 65535.0);
    u = (u < 0.0) ? 0.0 : ((u > 65535.0) ? 65535.0 : u);
    const uint16_t v = (uint16_t)u;
    b[0] = (uint8_t)(v & 0xFFu);
    b[1] = (uint8_t)(v >> 8);
    return 2u;
}

static double smoothstep(double x)
{
    x = (x < 0.0) ? 0.0 : ((x > 1.0) ? 1.0 : x);
    return x * x * (3.0 - 2.0 * x);
}

/* The records of period k of a segment (make_seeds.py whole_periods, offgoing_every 4); returns their length. */
static size_t script_period(const segment_t *s, uint32_t k, uint8_t *b)
{
    size_t n = 0u;
    const double x = (s->inertia_start < 0) ? 0.0 : ((double)k - (double)s->inertia_start) / INERTIA_MS;
    const double slip = SLIP_12_RPM * (1.0 - smoothstep(x));
    const bool sent = s->lost == LOST_NONE;
    if (sent && (k % 10u == 0u)) {
        b[n++] = 1u | (6u << 3);  /* ShiftCommand: request, AdaptationReset 0, gear 2, 150 Nm, 250 ms */
        b[n++] = 0u;
        b[n++] = s->request;
        b[n++] = 0u;
        b[n++] = 1u;
        n += put_u16_of(&b[n], 150.0, -1000.0, 1000.0);
        n += put_u16_of(&b[n], INERTIA_MS, 50.0, 2000.0);
        b[n++] = 1u | (3u << 3);  /* TorqueRequest: 0 Nm, Mode 3 (Shift) */
        b[n++] = 0u;
        n += put_u16_of(&b[n], 0.0, 0.0, 2000.0);
        b[n++] = 3u;
    }
    if (sent && (k % 4u == 0u)) {
        b[n++] = 1u | (2u << 3);  /* OffgoingSensors */
        b[n++] = 0u;
        n += put_u16_of(&b[n], slip - SLIP_12_RPM, -8000.0, 8000.0);
    }
    if (sent && (k % 2u == 0u)) {
        b[n++] = 1u | 0x04u;  /* ClutchSensors with the tick: oil 80, housing 75 degC */
        b[n++] = 0u;
        n += put_u16_of(&b[n], slip, -8000.0, 8000.0);
        n += put_u16_of(&b[n], 80.0, -40.0, 200.0);
        n += put_u16_of(&b[n], 75.0, -40.0, 200.0);
    } else {
        b[n++] = 0u;  /* a bare tick */
    }
    return n;
}

/* Runs every script once and keeps the snapshots (LLVMFuzzerInitialize: before the first input). */
static void make_snapshots(void)
{
    for (size_t i = 0u; i < START_POINTS; ++i) {
        const start_point_t *p = &start_points[i];
        if ((i > 0u) && (p->script == start_points[i - 1u].script) && (p->period >= start_points[i - 1u].period)) {
            continue;  /* taken on the previous one's run */
        }
        harness_t h;
        fz_reader_t r;
        uint8_t options;
        uint8_t shift_options;
        fz_reader_init(&r, prefix_header, sizeof prefix_header);
        const float theta_start_degC = read_header(&h, &r, &options, &shift_options);
        start_fresh(&h, options, shift_options, theta_start_degC);
        xcp_on = false;
        xcp_tried = false;
        size_t next = i;  /* the snapshots of this script, in period order */
        for (const segment_t *s = p->script; s->last != 0u; ++s) {
            for (uint32_t k = s->first; k < s->last; ++k) {
                while ((next < START_POINTS) && (start_points[next].script == p->script) &&
                       (start_points[next].period == k)) {
                    FZ_CHECK(loop.rx_tail == loop.rx_head, "snapshot with frames in the ring");
                    memcpy(&snapshots[next].loop, &loop, sizeof loop);
                    snapshots[next].h = h;
                    ++next;
                }
                uint8_t b[64];  /* a period's records: at most 31 bytes */
                fz_reader_init(&r, b, script_period(s, k, b));
                unsigned record = 1u;
                run_records(&h, &r, &record);
            }
        }
        FZ_CHECK((next == START_POINTS) || (start_points[next].script != p->script),
                 "start point %u after its script's end", (unsigned)next);
    }
    if (verbose) {
        for (size_t i = 0u; i < START_POINTS; ++i) {
            const wc_loop_t *l = &snapshots[i].loop;
            fprintf(stderr, "fuzz_loop: start %u: %s: period %u, phase %u (%u periods), fallback %u, safe %d, "
                            "second gear %d, off-going released %d\n",
                    (unsigned)(i + 1u), start_points[i].name, (unsigned)start_points[i].period, (unsigned)l->shift.phase,
                    (unsigned)l->shift.phase_periods, (unsigned)l->shift.fallback,
                    (int)(l->fresh_periods < l->config.recovery_periods), (int)l->shift.second_gear,
                    (int)l->shift.offgoing_released);
        }
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    verbose = fz_env_flag("WC_FUZZ_VERBOSE");
    make_snapshots();
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader_t r;
    fz_reader_init(&r, data, size);
    harness_t h;
    uint8_t options;
    uint8_t shift_options;
    const float theta_start_degC = read_header(&h, &r, &options, &shift_options);
    const uint32_t start = ((shift_options & 0x01u) != 0u) ? ((shift_options >> 1) & 0x0Fu) : 0u;
    if (start == 0u) {
        start_fresh(&h, options, shift_options, theta_start_degC);
    } else {
        /* a start inside the whole shift: the snapshot's loop and harness state (its configuration and start
         * temperature); byte 0's clock, "make valid" and "plausible" apply from here on, and a fuzzed loop
         * configuration (bit 6: timeouts, E2E, recovery) through wc_loop_recalibrate, as an XCP page would */
        const snapshot_t *s = &snapshots[(start - 1u) % START_POINTS];
        const wc_loop_config_t fuzzed = h.config;
        memcpy(&loop, &s->loop, sizeof loop);
        h = s->h;
        read_harness_options(&h, options);
        if ((options & 0x40u) != 0u) {
            h.config.sensor_timeout_periods = fuzzed.sensor_timeout_periods;
            h.config.request_timeout_periods = fuzzed.request_timeout_periods;
            h.config.e2e = fuzzed.e2e;
            h.config.recovery_periods = fuzzed.recovery_periods;
            fz_context("wc_loop_recalibrate(the fuzzed loop configuration; start, recovery)", 0u);
            fz_ctx.iargs[0] = (long)start;
            fz_ctx.iargs[1] = (long)h.config.recovery_periods;
            FZ_CHECK(wc_loop_recalibrate(&loop, cal, &h.config) == WC_CAL_OK, "wc_loop_recalibrate failed");
        }
    }
    xcp_on = false;
    xcp_tried = false;
    xcp_frames = 0u;
    xcp_checks = 0u;

    unsigned record = 1u;
    run_records(&h, &r, &record);
    iterate(&h, NULL, true, MAX_RECORDS + 1u, false);  /* empties the ring */
    FZ_CHECK(loop.rx_tail == loop.rx_head, "frames left in the ring after a step");
    if (verbose) {
        fprintf(stderr,
                "fuzz_loop: %zu bytes, clock %d, valid %d, plausible %d: steps %u (control %u, safe %u), frames in %u, "
                "used %u, rejected crc %u counter %u short %u unknown %u format %u implausible %u overflow %u sync %u\n",
                size, (int)h.clock, (int)h.make_valid, (int)h.plausible, (unsigned)h.steps, (unsigned)h.control_steps,
                (unsigned)h.safe_steps, (unsigned)loop.counters.frames_in, (unsigned)loop.counters.frames_used,
                (unsigned)loop.counters.rejected[WC_REJECT_CRC], (unsigned)loop.counters.rejected[WC_REJECT_COUNTER],
                (unsigned)loop.counters.rejected[WC_REJECT_SHORT], (unsigned)loop.counters.rejected[WC_REJECT_UNKNOWN_ID],
                (unsigned)loop.counters.rejected[WC_REJECT_FORMAT],
                (unsigned)loop.counters.rejected[WC_REJECT_IMPLAUSIBLE],
                (unsigned)loop.counters.rejected[WC_REJECT_OVERFLOW], (unsigned)loop.counters.rejected[WC_REJECT_SYNC]);
        if (h.whole) {
            fprintf(stderr, "fuzz_loop: whole shift (start %u): phase %u, fallback %u, engine intervention steps %u, "
                            "safe steps with a fallback %u, sensor timeouts %u\n",
                    (unsigned)start, (unsigned)loop.shift.phase, (unsigned)loop.shift.fallback, (unsigned)h.engine_steps,
                    (unsigned)h.fallback_steps, (unsigned)loop.counters.sensor_timeouts);
        }
        if (h.shift) {
            fprintf(stderr, "fuzz_loop: shift reports %u, the last AbortReason %u\n", (unsigned)h.reports,
                    (unsigned)h.last_abort);
        }
        if (xcp_on) {
            fprintf(stderr,
                    "fuzz_loop: xcp commands %u (errors %u, ignored %u, lost %u), frames out %u, pages accepted %u "
                    "rejected %u (last %u/%u), daq samples %u overloads %u\n",
                    (unsigned)xcp.status.commands, (unsigned)xcp.status.errors, (unsigned)xcp.status.ignored,
                    (unsigned)xcp.status.rx_overflows, (unsigned)xcp_frames, (unsigned)xcp.status.pages_accepted,
                    (unsigned)xcp.status.pages_rejected, (unsigned)xcp.status.page_result,
                    (unsigned)xcp.status.page_error, (unsigned)xcp.status.daq_samples,
                    (unsigned)xcp.status.daq_overloads);
        }
    }
    return 0;
}
