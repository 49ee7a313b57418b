/* wc_tcu --uds: the diagnostic server over the frame loop (wc_tcu_diag.h). */
#define _GNU_SOURCE
#include "wc_tcu_diag.h"
#include "wc_device_secret.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/random.h>

#include <openssl/evp.h>
#include <openssl/hmac.h>

#include "wetclutch/wc_image.h"
#include "wetclutch_can/wc_can_signals.h"
#include "wc_atomic_file.h"

/* The fault matrix's rows as DTCs (ISO 14229-1 D.1 3-byte numbers: the SAE J2012 code in the first two
 * bytes, its failure type byte last: 0x81 invalid serial data, 0x82 alive counter incorrect, 0x83 signal
 * protection (CRC) incorrect, 0x86 signal invalid, 0x87 missing message, 0x88 bus off, 0x98 over
 * temperature). Level faults (a timeout, over-temperature) are debounced over 5 steps each way; event
 * faults (a status bit in one VfsCommand) fail at once and pass after 100 clean steps. Confirmed in the
 * first cycle with a failure; aged out after 40 fault-free cycles. */
enum {
    DTC_SENSOR_TIMEOUT = 0, DTC_REQUEST_TIMEOUT, DTC_CRC_ERROR, DTC_COUNTER_ERROR, DTC_IMPLAUSIBLE_INPUT,
    DTC_FRAME_LOST, DTC_BUS_ERROR, DTC_OVER_TEMPERATURE, DTC_DEADLINE_MISS, DTC_CAL_PAGE_REJECTED,
    DTC_MEMORY_LOST, DTC_COUNT
};
#define LEVEL(number, priority) { (number), 5, -5, 1u, 1u, 1u, (priority), true }
#define EVENT(number, priority) { (number), 5, -100, 5u, 1u, 1u, (priority), false }
static const wc_dtc_definition_t dtc_table[DTC_COUNT] = {
    [DTC_SENSOR_TIMEOUT] = LEVEL(0xD10087u, 1u),     /* U1100-87 ClutchSensors (or OffgoingSensors) missing */
    [DTC_REQUEST_TIMEOUT] = LEVEL(0xD10187u, 1u),    /* U1101-87 TorqueRequest (or ShiftCommand) missing */
    [DTC_CRC_ERROR] = EVENT(0xD10283u, 2u),          /* U1102-83 an input's E2E CRC wrong */
    [DTC_COUNTER_ERROR] = EVENT(0xD10282u, 2u),      /* U1102-82 an input's alive counter wrong */
    [DTC_IMPLAUSIBLE_INPUT] = EVENT(0xD10286u, 2u),  /* U1102-86 a signal SNA, out of range, reserved */
    [DTC_FRAME_LOST] = EVENT(0xD10381u, 3u),         /* U1103-81 frames lost before the loop */
    [DTC_BUS_ERROR] = EVENT(0xD10388u, 2u),          /* U1103-88 error passive, bus-off, failed send */
    [DTC_OVER_TEMPERATURE] = LEVEL(0x170098u, 0u),   /* P1700-98 clutch over temperature */
    [DTC_DEADLINE_MISS] = EVENT(0x060647u, 3u),      /* P0606-47 control step deadline missed */
    [DTC_CAL_PAGE_REJECTED] = EVENT(0x060200u, 3u),  /* P0602-00 an XCP calibration page refused */
    [DTC_MEMORY_LOST] = EVENT(0x062F00u, 1u),        /* P062F-00 the fault memory's image was corrupt */
};
/* The status bit that is each row's test (0: tested elsewhere). */
static const uint16_t dtc_status_bit[DTC_COUNT] = {
    [DTC_SENSOR_TIMEOUT] = WC_CAN_STATUS_SENSOR_TIMEOUT,
    [DTC_REQUEST_TIMEOUT] = WC_CAN_STATUS_REQUEST_TIMEOUT,
    [DTC_CRC_ERROR] = WC_CAN_STATUS_CRC_ERROR,
    [DTC_COUNTER_ERROR] = WC_CAN_STATUS_COUNTER_ERROR,
    [DTC_IMPLAUSIBLE_INPUT] = WC_CAN_STATUS_IMPLAUSIBLE_INPUT,
    [DTC_FRAME_LOST] = WC_CAN_STATUS_FRAME_LOST,
    [DTC_BUS_ERROR] = WC_CAN_STATUS_BUS_ERROR,
    [DTC_OVER_TEMPERATURE] = WC_CAN_STATUS_OVER_TEMPERATURE,
    [DTC_DEADLINE_MISS] = WC_CAN_STATUS_DEADLINE_MISS,
};

#define DID_SERIAL 0xF18Cu
#define DID_SOFTWARE_VERSION 0xF195u
#define DID_SYSTEM_NAME 0xF197u
#define DID_CALIBRATION 0xFD00u
#define DID_TEMPERATURES 0xFD01u
#define DID_LEARNED 0xFD02u
#define DID_FAULT_COUNTERS 0xFD03u
#define ROUTINE_ADAPTATION_RESET 0x0201u
#define SYSTEM_NAME "wetclutch TCU"
#define SEED_BYTES 16u
#define KEY_BYTES 16u
#define LOOP_COUNTER_WORDS (WC_REJECT_REASONS + 6u)
#define LEARNED_BYTES (4u * (2u * WC_ADAPT_NODES + 3u))

static void put_u32_be(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static void put_f32_be(uint8_t *p, float v)
{
    uint32_t bits = 0u;
    memcpy(&bits, &v, sizeof bits);
    put_u32_be(p, bits);
}

/* ---- the DIDs' read hooks (context: the diag) ---------------------------------------------------------- */

static bool read_serial(void *context, uint8_t *data, uint32_t length)
{
    const wc_tcu_diag_t *d = context;
    memcpy(data, d->serial, length);
    return true;
}

static bool read_software_version(void *context, uint8_t *data, uint32_t length)
{
    (void)context;
    memcpy(data, WC_TCU_SOFTWARE_VERSION, length);
    return true;
}

static bool read_system_name(void *context, uint8_t *data, uint32_t length)
{
    (void)context;
    memcpy(data, SYSTEM_NAME, length);
    return true;
}

static bool read_calibration(void *context, uint8_t *data, uint32_t length)
{
    const wc_tcu_diag_t *d = context;
    (void)length;
    put_u32_be(data, d->cal_image_crc32);
    data[4] = (uint8_t)(d->cal_layout_version >> 8);
    data[5] = (uint8_t)d->cal_layout_version;
    return true;
}

static bool read_temperatures(void *context, uint8_t *data, uint32_t length)
{
    const wc_tcu_diag_t *d = context;
    (void)length;
    put_f32_be(data, d->loop->clutch.theta_degC);
    put_f32_be(data + 4, d->loop->input.theta_oil_degC);
    put_f32_be(data + 8, d->loop->input.theta_housing_degC);
    return true;
}

static bool adaptation_on(const wc_loop_t *loop)
{
    return (loop->config.shift != NULL) && (loop->config.shift->adaptation == 1u);
}

static bool read_learned(void *context, uint8_t *data, uint32_t length)
{
    const wc_tcu_diag_t *d = context;
    (void)length;
    if (!adaptation_on(d->loop)) { return false; }  /* conditionsNotCorrect: nothing is learned */
    const wc_adapt_values_t *v = &d->loop->adapt.values;
    uint8_t *p = data;
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i, p += 4) { put_f32_be(p, v->friction_scale[i]); }
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i, p += 4) { put_f32_be(p, v->confidence[i]); }
    put_f32_be(p, v->film_factor);
    put_f32_be(p + 4, v->kiss_offset_Pa);
    put_u32_be(p + 8, v->shifts_learned);
    return true;
}

static bool read_fault_counters(void *context, uint8_t *data, uint32_t length)
{
    const wc_tcu_diag_t *d = context;
    const wc_loop_counters_t *k = &d->loop->counters;
    (void)length;
    uint8_t *p = data;
    for (uint32_t r = 0u; r < WC_REJECT_REASONS; ++r, p += 4) { put_u32_be(p, k->rejected[r]); }
    const uint32_t more[6] = { k->sensor_timeouts, k->request_timeouts, k->frames_lost_by_port, k->bus_errors,
                               k->deadline_misses, k->safe_steps };
    for (uint32_t i = 0u; i < 6u; ++i, p += 4) { put_u32_be(p, more[i]); }
    for (uint32_t i = 0u; i < DTC_COUNT; ++i, p += 4) { put_u32_be(p, wc_dtc_fault_count(&d->dtc, i)); }
    return true;
}

/* ---- routine 0x0201: the adaptation reset --------------------------------------------------------------- */

static uint8_t reset_start(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status,
                           uint32_t capacity, uint32_t *status_length)
{
    wc_tcu_diag_t *d = context;
    (void)option;
    (void)status;
    (void)capacity;
    *status_length = 0u;
    if (option_length != 0u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    if (!wc_loop_request_adaptation_reset(d->loop)) { return WC_UDS_NRC_CONDITIONS; }
    d->reset_requested = true;
    return 0u;
}

static uint8_t reset_results(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status,
                             uint32_t capacity, uint32_t *status_length)
{
    const wc_tcu_diag_t *d = context;
    (void)option;
    (void)option_length;
    if (capacity < 1u) { return WC_UDS_NRC_RESPONSE_TOO_LONG; }
    status[0] = d->loop->adaptation_reset_requested ? 1u : 0u;  /* 1 pending, 0 done */
    *status_length = 1u;
    return 0u;
}

/* ---- ECUReset 0x11 softReset (ISO 14229-1:2013 9.3; wc_tcu_diag.h) ------------------------------------ */

/* conditionsNotCorrect while a shift runs: a reset would release the clutch in the middle of a gear change */
static uint8_t ecu_reset_check(void *context, uint8_t reset_type)
{
    const wc_tcu_diag_t *d = context;
    (void)reset_type;
    return wc_shift_phase_running(d->loop->shift.phase) ? (uint8_t)WC_UDS_NRC_CONDITIONS : 0u;
}

/* Called by wc_uds_step once the positive response is on the bus; the reset waits for the end of the step. */
static void ecu_reset(void *context, uint8_t reset_type)
{
    wc_tcu_diag_t *d = context;
    (void)reset_type;
    d->ecu_reset_pending = true;
}

/* ---- security hooks: getrandom(2) and HMAC-SHA256 (OpenSSL) -------------------------------------------- */

static bool key_of_seed(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    const wc_tcu_diag_t *d = context;
    return wc_device_secret_key((void *)&d->secret, seed, seed_length, key, key_length);
}

/* ---- files ---------------------------------------------------------------------------------------------- */

static int read_secret(wc_tcu_diag_t *d)
{
    if (d->options.secret_file == NULL) {
        fprintf(stderr, "%s: --uds needs --secret-file PATH (the device secret of the security access key)\n",
                d->options.program);
        return -1;
    }
    return wc_device_secret_read(&d->secret, d->options.secret_file, d->options.program);
}

static void store_dtc(wc_tcu_diag_t *d)
{
    if (d->options.dtc_file == NULL) {
        static uint8_t sink[WC_DTC_IMAGE_BYTES];  /* the flag must clear: nothing to write to */
        (void)wc_dtc_image_write(&d->dtc, sink, sizeof sink);
        return;
    }
    uint8_t image[WC_DTC_IMAGE_BYTES];
    const char *step = "encode";
    if ((wc_dtc_image_write(&d->dtc, image, sizeof image) != sizeof image) ||
        (wc_atomic_file_write(d->options.dtc_file, image, sizeof image, &step) != 0)) {
        const int error = errno;
        if (d->dtc_write_failures++ == 0u) {
            fprintf(stderr, "%s: fault memory %s not written (%s: %s); the previous image is kept (further"
                            " failures counted)\n", d->options.program, d->options.dtc_file, step, strerror(error));
        }
        return;
    }
    d->dtc_writes++;
}

static void load_dtc(wc_tcu_diag_t *d)
{
    static const char *const reason[] = { "ok", "missing", "truncated", "bad magic", "bad layout version",
                                          "bad length", "bad CRC-32" };
    static uint8_t image[WC_DTC_IMAGE_BYTES + 1u];  /* one byte more: a longer file is not this image */
    size_t length = 0u;
    const char *path = d->options.dtc_file;
    FILE *f = (path != NULL) ? fopen(path, "rb") : NULL;
    if (f != NULL) {
        length = fread(image, 1u, sizeof image, f);
        if (ferror(f)) {
            fprintf(stderr, "%s: fault memory %s: %s\n", d->options.program, path, strerror(errno));
        }
        fclose(f);
    } else if ((path != NULL) && (errno != ENOENT)) {
        fprintf(stderr, "%s: fault memory %s: %s\n", d->options.program, path, strerror(errno));
    }
    const uint32_t code = wc_dtc_image_load(&d->dtc, (f != NULL) ? image : NULL, length);
    if ((code != (uint32_t)WC_IMAGE_OK) && (f != NULL)) {
        const char *why = (code < (uint32_t)(sizeof reason / sizeof reason[0])) ? reason[code] : "invalid";
        fprintf(stderr, "%s: fault memory %s not used (%s): an empty memory and DTC 0x%06X\n", d->options.program,
                path, why, dtc_table[DTC_MEMORY_LOST].number);
    }
}

/* ---- the server ----------------------------------------------------------------------------------------- */

int wc_tcu_diag_open(wc_tcu_diag_t *d, const wc_tcu_diag_options_t *options, wc_loop_t *loop, const wc_xcp_t *xcp,
                     const uint8_t *cal_image, size_t cal_image_length)
{
    memset(d, 0, sizeof *d);
    d->options = *options;
    d->loop = loop;
    d->xcp = xcp;
    d->xcp_pages_rejected_seen = (xcp != NULL) ? xcp->status.pages_rejected : 0u;
    const char *serial = (options->serial != NULL) ? options->serial : "WC0000000001";
    const size_t serial_length = strlen(serial);
    if ((serial_length == 0u) || (serial_length > WC_TCU_DIAG_SERIAL_MAX_BYTES)) {
        fprintf(stderr, "%s: --serial '%s': 1..%u characters\n", options->program, serial,
                WC_TCU_DIAG_SERIAL_MAX_BYTES);
        return -1;
    }
    memcpy(d->serial, serial, serial_length);
    if (read_secret(d) != 0) { return -1; }
    if (cal_image_length < WC_IMAGE_HEADER_BYTES + WC_IMAGE_CRC_BYTES) {
        fprintf(stderr, "%s: --uds: no calibration image (a bug)\n", options->program);
        return -1;
    }
    d->cal_image_crc32 = wc_image_get_u32(cal_image + cal_image_length - WC_IMAGE_CRC_BYTES);
    d->cal_layout_version = wc_image_get_u32(cal_image + 4u);

    const wc_dtc_config_t dtc_config = { dtc_table, DTC_COUNT, options->dtc_aging_cycles, DTC_MEMORY_LOST, &d->environment };
    if (!wc_dtc_init(&d->dtc, &dtc_config)) {
        fprintf(stderr, "%s: --uds: the DTC table is refused (a bug)\n", options->program);
        return -1;
    }
    load_dtc(d);
    wc_dtc_cycle_start(&d->dtc);  /* one wc_tcu run is one operation cycle */

    const wc_uds_did_t dids[WC_TCU_DIAG_DIDS] = {  /* every entry filled: did_count below */
        { DID_SERIAL, (uint16_t)serial_length, read_serial, d },
        { DID_SOFTWARE_VERSION, (uint16_t)(sizeof WC_TCU_SOFTWARE_VERSION - 1u), read_software_version, d },
        { DID_SYSTEM_NAME, (uint16_t)(sizeof SYSTEM_NAME - 1u), read_system_name, d },
        { DID_CALIBRATION, 6u, read_calibration, d },
        { DID_TEMPERATURES, 12u, read_temperatures, d },
        { DID_LEARNED, (uint16_t)LEARNED_BYTES, read_learned, d },
        { DID_FAULT_COUNTERS, (uint16_t)(4u * (LOOP_COUNTER_WORDS + DTC_COUNT)), read_fault_counters, d },
    };
    memcpy(d->dids, dids, sizeof dids);
    d->routines[0] = (wc_uds_routine_t){ ROUTINE_ADAPTATION_RESET, reset_start, reset_results, d };

    wc_uds_config_t *u = &d->uds_config;
    *u = (wc_uds_config_t)WC_UDS_CONFIG_DEFAULT;
    u->period_us = options->period_us;
    u->seed_bytes = SEED_BYTES;
    u->key_bytes = KEY_BYTES;
    u->delay_ms = options->security_delay_ms;
    u->dids = d->dids;
    u->did_count = (uint32_t)(sizeof dids / sizeof dids[0]);
    u->routines = d->routines;
    u->routine_count = 1u;
    u->dtc = &d->dtc;
    u->random = wc_device_secret_random;
    u->key = key_of_seed;
    u->reset_check = ecu_reset_check;
    u->reset = ecu_reset;
    u->context = d;
    if (!wc_uds_init(&d->uds, u)) {
        fprintf(stderr, "%s: --uds: the UDS configuration is refused (period %u us)\n", options->program,
                options->period_us);
        return -1;
    }
    wc_isotp_config_t tp = WC_ISOTP_CONFIG_DEFAULT;
    tp.rx_physical_id = WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID;
    tp.rx_functional_id = WC_CAN_UDS_FUNCTIONAL_REQUEST_FRAME_ID;
    tp.tx_id = WC_CAN_UDS_RESPONSE_FRAME_ID;
    tp.frames_per_step = options->frames_per_step;
    tp.period_us = options->period_us;
    if (!wc_isotp_init(&d->tp, &tp)) {
        fprintf(stderr, "%s: --uds: the ISO-TP configuration is refused (frames per step %u, period %u us)\n",
                options->program, options->frames_per_step, options->period_us);
        return -1;
    }
    if (wc_dtc_changed(&d->dtc)) { store_dtc(d); }
    return 0;
}

bool wc_tcu_diag_is_request(uint32_t id)
{
    return (id == WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID) || (id == WC_CAN_UDS_FUNCTIONAL_REQUEST_FRAME_ID);
}

void wc_tcu_diag_receive(wc_tcu_diag_t *d, const wc_can_frame_t *frame)
{
    (void)wc_isotp_receive(&d->tp, frame);  /* a full ring is counted */
}

/* The operating point for a snapshot: what this TCU measures or estimates (the output and turbine speeds
 * are not on its bus: NaN, stored as 0), the gear where the shift control knows it (0: not known). */
static void refresh_environment(wc_tcu_diag_t *d)
{
    const wc_loop_t *loop = d->loop;
    wc_dtc_snapshot_t *e = &d->environment;
    e->slip_speed_rad_s = loop->input.slip_rad_s;
    e->output_speed_rad_s = NAN;
    e->turbine_speed_rad_s = NAN;
    e->theta_clutch_degC = loop->clutch.theta_degC;
    e->theta_oil_degC = loop->input.theta_oil_degC;
    e->theta_housing_degC = loop->input.theta_housing_degC;
    e->current_oncoming_mA = loop->last.current_mA;
    e->current_offgoing_mA = wc_loop_whole_shift(&loop->config) ? loop->offgoing_last.current_mA : 0.0f;
    const uint32_t phase = loop->shift.phase;
    e->shift_phase = (uint8_t)phase;
    e->gear = 0u;
    if (loop->config.shift != NULL) {
        if (phase == (uint32_t)WC_SHIFT_LOCKED) { e->gear = 2u; }                         /* the 1->2 upshift done */
        else if (wc_shift_phase_running(phase)) { e->gear = 1u; }                        /* still in 1st */
    }
}

uint32_t wc_tcu_diag_step(wc_tcu_diag_t *d, const wc_can_frame_t *loop_out, uint32_t n, wc_can_frame_t *out,
                          uint32_t capacity)
{
    wc_can_vfs_command_phys_t vfs;
    if ((n > 0u) && (loop_out[0].id == WC_CAN_VFS_COMMAND_FRAME_ID) &&
        (wc_can_decode_vfs_command(&vfs, loop_out[0].data, sizeof loop_out[0].data) == WC_CAN_OK)) {
        refresh_environment(d);
        const uint16_t status = vfs.status;
        const uint16_t timeouts = WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_REQUEST_TIMEOUT;
        if ((status & timeouts) == 0u) { d->inputs_started = true; }
        for (uint32_t i = 0u; i < DTC_COUNT; ++i) {
            const uint16_t bit = dtc_status_bit[i];
            /* an input is tested for its timeout once it has been there: not at start-up */
            if ((bit == 0u) || (((bit & timeouts) != 0u) && !d->inputs_started)) { continue; }
            wc_dtc_report(&d->dtc, i, (status & bit) != 0u);
        }
        if (d->xcp != NULL) {
            const uint32_t rejected = d->xcp->status.pages_rejected;
            wc_dtc_report(&d->dtc, DTC_CAL_PAGE_REJECTED, rejected != d->xcp_pages_rejected_seen);
            d->xcp_pages_rejected_seen = rejected;
        }
    }
    const uint32_t frames = wc_uds_step(&d->uds, &d->tp, out, capacity);
    if (wc_dtc_changed(&d->dtc)) { store_dtc(d); }
    return frames;
}

bool wc_tcu_diag_reset_pending(const wc_tcu_diag_t *d) { return d->ecu_reset_pending; }

void wc_tcu_diag_reset(wc_tcu_diag_t *d)
{
    d->ecu_reset_pending = false;
    d->ecu_resets++;
    wc_dtc_cycle_end(&d->dtc);  /* the operation cycle's end (wc_dtc.h: pending, healing, ageing) */
    store_dtc(d);
    if (d->options.dtc_file != NULL) {  /* the memory a restarted ECU finds: its image (without a file: as it is) */
        const wc_dtc_config_t config = d->dtc.config;
        (void)wc_dtc_init(&d->dtc, &config);  /* accepted at open */
        load_dtc(d);
    }
    wc_dtc_cycle_start(&d->dtc);
    d->inputs_started = false;  /* the restarted loop's inputs are stale until they come: no timeout test */
    const wc_uds_counters_t uds_counters = d->uds.counters;
    const wc_isotp_counters_t tp_counters = d->tp.counters;
    const wc_isotp_config_t tp_config = d->tp.config;
    (void)wc_uds_init(&d->uds, &d->uds_config);  /* default session, locked, the delay of a start; accepted at open */
    (void)wc_isotp_init(&d->tp, &tp_config);
    d->uds.counters = uds_counters;
    d->tp.counters = tp_counters;
    if (wc_dtc_changed(&d->dtc)) { store_dtc(d); }
}

void wc_tcu_diag_close(wc_tcu_diag_t *d)
{
    wc_dtc_cycle_end(&d->dtc);
    store_dtc(d);
    fprintf(stderr, "%s: uds: requests %u (positive %u, negative %u), invalid keys %u, soft resets %lu; iso-tp"
                    " malformed %u, rx overflows %u; fault memory writes %lu (failed %lu)\n",
            d->options.program, d->uds.counters.requests, d->uds.counters.positive, d->uds.counters.negative,
            d->uds.counters.invalid_keys, d->ecu_resets, d->tp.counters.malformed, d->tp.counters.rx_overflows,
            d->dtc_writes, d->dtc_write_failures);
}
