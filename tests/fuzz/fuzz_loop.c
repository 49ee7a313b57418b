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
 *                 deadline missed: c bits 2-3) with a count byte; with c
 *                 bit 4 an XCP command frame instead (fuzz_loop_xcp.c);
 *                 else with c bit 7 a UDS frame (fuzz_loop_uds.c)
 *   c bits 3-5 choose the frame id (ClutchSensors x3, TorqueRequest x3,
 *   BenchMeasurement, other); "other" reads a 16-bit id, and a byte of
 *   format (bit 7 set: DLC = low nibble 0..15, flags = bits 4-6) follows
 *   for every frame; then 8 data bytes (in plausible mode: 2 bytes per
 *   signal). c bits 6-7 are the fault in "make valid" mode: 0 none, 1 alive
 *   counter advanced by a fuzzed nibble (one more byte: 0 repeats, 2 loses a
 *   frame, ...), 2 a wrong CRC (one more byte), 3 the frame as fuzzed.
 *   A frame of a UDS request id goes to the diagnostic server once it runs
 *   (fuzz_loop_uds.c), as an XcpCommand frame goes to the XCP slave.
 *
 * The oracle: fuzz_loop_check.c; the XCP slave beside the loop: fuzz_loop_xcp.c; ISO-TP, the UDS server
 * and a fault memory beside it: fuzz_loop_uds.c; the starts inside the whole shift: fuzz_loop_starts.c. */
#include "fuzz_loop.h"

#include "wc_shift_1_2_shift.h"
#include "wc_table1_calibration.h"

const wc_calibration_t *const cal = &wc_table1_calibration;
bool verbose;
run_stats_t stats;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

wc_loop_t loop;

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
        /* CurrentGear 0: the single-clutch paths ignore it (their logs send 0) */
        const wc_can_shift_command_phys_t s = {
            (float)(fz_u8(r) & 1u), (float)(fz_u8(r) & 1u) /* AdaptationReset */, (float)(fz_u8(r) % 8u + 1u),
            map_u16(fz_u16(r), -1000.0f, 1000.0f),
            map_u16(fz_u16(r), 50.0f, 2000.0f), 0.0f /* CurrentGear */, 0u };
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


void iterate(harness_t *h, const wc_can_frame_t *frame, bool tick, unsigned record, bool xcp_waits)
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
            stats.reports += stats.counting ? 1u : 0u;
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
    if (xcp_running() && ((n > 0u) || !xcp_waits)) { xcp_step(h, n > 0u, record); }
    if (uds_running() && (n > 0u)) { uds_step(out, record); }  /* as wc_tcu: after the step's frames and XCP */
}

/* The records of an input (see the top of the file) until the bytes run out or *record passes MAX_RECORDS. */
void run_records(harness_t *h, fz_reader_t *r, unsigned *record)
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
                xcp_receive(&f);
                iterate(h, NULL, tick, *record, false);
            } else if (uds_receive(&f)) {  /* a request id once the diagnostic server runs: its, not the loop's */
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
                xcp_receive(&f);  /* a full ring is counted */
                iterate(h, NULL, (c & 0x20u) != 0u, *record, (c & 0x40u) != 0u);
                break;
            }
            if ((c & 0x90u) == 0x80u) {  /* a UDS record (fuzz_loop_uds.c) */
                uds_record(r, c);
                iterate(h, NULL, (c & 0x20u) != 0u, *record, false);
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
void read_harness_options(harness_t *h, uint8_t options)
{
    h->clock = ((options & 0x01u) != 0u) ? WC_LOOP_CLOCK_FRAME : WC_LOOP_CLOCK_TIMER;
    h->make_valid = (options & 0x04u) != 0u;
    h->plausible = (options & 0x08u) != 0u;
}

/* The header of an input: byte 0 (*options), the loop configuration (bit 6), the shift-options byte (bit 7;
 * else 0: *shift_options); into h (zeroed first). Returns the start temperature (bits 4-5). */
float read_header(harness_t *h, fz_reader_t *r, uint8_t *options_out, uint8_t *shift_options_out)
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
void start_fresh(harness_t *h, uint8_t options, uint8_t shift_options, float theta_start_degC)
{
    fz_context("wc_loop_init(theta_start; options, recovery)", 0u);
    fz_arg(theta_start_degC);
    fz_ctx.iargs[0] = options | (shift_options << 8);
    fz_ctx.iargs[1] = (long)h->config.recovery_periods;
    FZ_CHECK(wc_loop_init(&loop, cal, &h->config, theta_start_degC) == WC_CAL_OK, "wc_loop_init failed");
    FZ_CHECK(wc_loop_whole_shift(&loop.config) == h->whole, "the loop's whole shift %d, configured %d",
             (int)wc_loop_whole_shift(&loop.config), (int)h->whole);
}


/* At exit: what the run executed (run_stats_t), one line that scripts/fuzz.sh prints. */
static void report_stats(void)
{
    static const char *const kinds[KINDS] = { "plain", "shift", "whole from init", "whole from a snapshot", "XCP",
                                              "UDS" };
    unsigned long inputs = 0u;
    unsigned long steps = 0u;
    for (unsigned k = 0u; k < (unsigned)KINDS; ++k) {
        inputs += stats.inputs[k];
        steps += stats.steps[k];
    }
    fprintf(stderr, "fuzz_loop: %lu inputs, %lu loop steps (%.0f per input, at most %lu); inputs/steps by kind:", inputs,
            steps, (inputs > 0u) ? (double)steps / (double)inputs : 0.0, stats.steps_max);
    for (unsigned k = 0u; k < (unsigned)KINDS; ++k) { fprintf(stderr, " %s %lu/%lu", kinds[k], stats.inputs[k], stats.steps[k]); }
    const unsigned long *p = stats.whole_phase_steps;
    const unsigned long *f = stats.whole_fallback_steps;
    fprintf(stderr, "; whole-shift steps by phase: idle %lu prepare %lu torque %lu inertia %lu lockup %lu locked %lu "
                    "aborted %lu, by fallback: none %lu finish %lu handback %lu released %lu; shift reports %lu\n",
            p[0], p[1], p[2], p[3], p[4], p[5], p[6], f[0], f[1], f[2], f[3], stats.reports);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    verbose = fz_env_flag("WC_FUZZ_VERBOSE");
    make_snapshots();
    stats.counting = true;
    (void)atexit(report_stats);
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
        const wc_loop_config_t fuzzed = h.config;
        start_from_snapshot(&h, start);
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
    xcp_reset();
    uds_forget();

    const uint32_t steps_before = h.steps;  /* a snapshot's prefix */
    unsigned record = 1u;
    run_records(&h, &r, &record);
    iterate(&h, NULL, true, MAX_RECORDS + 1u, false);  /* empties the ring */
    FZ_CHECK(loop.rx_tail == loop.rx_head, "frames left in the ring after a step");
    const unsigned kind = uds_running() ? KIND_UDS
                          : xcp_running() ? KIND_XCP
                          : (h.whole && (start != 0u)) ? KIND_WHOLE_SNAPSHOT
                          : h.whole ? KIND_WHOLE_INIT
                          : h.shift ? KIND_SHIFT : KIND_PLAIN;
    const unsigned long input_steps = h.steps - steps_before;
    stats.inputs[kind]++;
    stats.steps[kind] += input_steps;
    stats.steps_max = (input_steps > stats.steps_max) ? input_steps : stats.steps_max;
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
        xcp_print();
        uds_print();
    }
    return 0;
}
