/* The probe's XCP rows (wc_arm_bench.c): the slave (wc_xcp.h) in a calibration session beside the loop,
 * and the page check's parts. */
#include "wc_arm_bench.h"
#include "wc_arm_xcp.h"

/* ------------------------------------------------------------------------ */
/* The XCP slave (wc_xcp.h) in a calibration session                        */

/* The loop runs on the committed image (table1 + shift_1_2_full) in torque
 * control at one operating point; the XCP slave steps right after it, with
 * the image's payload as its reference page. One master command a period at
 * most: a master waits for each response (no block mode). */
#define XCP_SLIP_rpm 750.0f
#define XCP_THETA_degC 80.0f
#define XCP_REQUEST_Nm 100.0f
#define XCP_SETTLE_PERIODS 32u    /* the loop out of its start-up safe state (E2E sync, recovery) */
#define XCP_MEASURED_PERIODS 64u  /* samples of the idle and DAQ rows */
#define XCP_CHECKSUMS 4u
#define XCP_DOWNLOADS 8u          /* the gain changed and changed back, 4 times */
#define XCP_KP_SCALE 1.01f

static wc_xcp_t xcp;
static wc_cal_set_t xcp_loop_set;     /* the loop's calibration: the committed image */
static wc_cal_set_t xcp_scratch_set;  /* the master's view of the page; the decode row's set */
static uint8_t xcp_scratch_page[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
static uint8_t crc_block[WC_XCP_CHECKSUM_MAX_BYTES];
static uint8_t xcp_alive;

/* One control period: the loop's two input frames queued and the loop
 * stepped, then the master's command (NULL: none) received, then
 * wc_xcp_step, measured into row unless row is ROWS. False when a command
 * is not answered by a positive response as the step's first frame. */
static bool xcp_period(const wc_can_frame_t *command, row_t row)
{
    queue_frames(XCP_SLIP_rpm, XCP_THETA_degC, XCP_REQUEST_Nm, xcp_alive);
    xcp_alive = wc_e2e_counter_next(xcp_alive);
    thunk_loop_step(&bench);
    if ((command != NULL) && !wc_xcp_receive(&xcp, command)) { return false; }
    if (row < ROWS) {
        record(row, measure(thunk_xcp_step, &bench));
    } else {
        thunk_xcp_step(&bench);
    }
    return (command == NULL) || ((bench.xcp_frames >= 1u) && (bench.xcp_tx[0].data[0] == WC_XCP_PID_RES));
}

/* The step's frames from first on are the DAQ list's 8 ODTs (PIDs 0..7),
 * each carrying its signal's bytes as the loop holds them after its step,
 * the first after the timestamp. */
static bool xcp_daq_frames_ok(uint32_t first)
{
    if (bench.xcp_frames != first + WC_ARM_XCP_DAQ_SIGNALS) { return false; }
    for (uint32_t i = 0u; i < WC_ARM_XCP_DAQ_SIGNALS; ++i) {
        const wc_can_frame_t *f = &bench.xcp_tx[first + i];
        const uint8_t *signal = (const uint8_t *)&loop + wc_arm_xcp_signal_offset(i);
        const uint32_t pos = (i == 0u) ? 3u : 1u;
        if ((f->id != WC_CAN_XCP_RESPONSE_FRAME_ID) || (f->data[0] != (uint8_t)i) ||
            (memcmp(&f->data[pos], signal, 4u) != 0)) {
            return false;
        }
    }
    return true;
}

/* What a master computes from the A2L to set the shift PI gain to
 * reference kp x scale: the bytes of the page that change (*length, at
 * most 4: one float) and their offset in the page. */
static uint32_t xcp_kp_bytes(const uint8_t *reference, float scale, uint8_t bytes[4], uint32_t *length)
{
    *length = 0u;
    if (wc_cal_image_decode(reference, &xcp_scratch_set).result != (uint32_t)WC_CAL_IMAGE_OK) { return 0u; }
    xcp_scratch_set.shift.kp_Nm_per_rad_s *= scale;
    wc_cal_image_encode(&xcp_scratch_set, xcp_scratch_page);
    uint32_t first = 0u;
    for (uint32_t i = 0u; i < wc_cal_image_payload_bytes; ++i) {
        if (xcp_scratch_page[i] == xcp.working_page[i]) { continue; }
        if (*length == 0u) { first = i; }
        if (i - first >= 4u) {  /* more than one float changed */
            *length = 0u;
            return 0u;
        }
        *length = i - first + 1u;
    }
    for (uint32_t i = 0u; i < *length; ++i) { bytes[i] = xcp_scratch_page[first + i]; }
    return first;
}

void bench_xcp(void)
{
    const uint8_t *reference = &bench_cal_image[WC_IMAGE_HEADER_BYTES];
    const wc_xcp_config_t config = WC_XCP_CONFIG_DEFAULT;
    if ((wc_cal_image_load(bench_cal_image, bench_cal_image_bytes, &xcp_loop_set).result !=
         (uint32_t)WC_CAL_IMAGE_OK) ||
        (wc_loop_init(&loop, &xcp_loop_set.clutch, &xcp_loop_set.loop, XCP_THETA_degC) != WC_CAL_OK) ||
        !wc_xcp_init(&xcp, &loop, reference, &config)) {
        fail("xcp: the image, wc_loop_init or wc_xcp_init");
        return;
    }
    bench.loop = &loop;
    bench.xcp = &xcp;
    xcp_alive = 0u;
    const wc_can_frame_t connect = wc_arm_xcp_connect();
    bool ok = xcp_period(&connect, ROWS);
    for (uint32_t k = 0u; k < XCP_SETTLE_PERIODS; ++k) { ok = xcp_period(NULL, ROWS) && ok; }
    const uint32_t safe_steps = loop.counters.safe_steps;

    /* Connected, no command, no DAQ. */
    for (uint32_t k = 0u; k < XCP_MEASURED_PERIODS; ++k) {
        ok = xcp_period(NULL, ROW_XCP_IDLE) && (bench.xcp_frames == 0u) && ok;
    }
    if (!ok) { fail("xcp: CONNECT refused, or an idle step sent a frame"); }

    /* The DAQ list configured by its commands, one a period, then sampled. */
    wc_can_frame_t setup[WC_ARM_XCP_DAQ_SETUP_FRAMES];
    const uint32_t setup_frames = wc_arm_xcp_daq_setup(config.loop_base, setup);
    for (uint32_t i = 0u; i < setup_frames; ++i) {
        if (!xcp_period(&setup[i], ROWS)) {
            wc_arm_puts("XCP command ");
            wc_arm_put_u32(i);
            wc_arm_puts(" of the DAQ setup: response PID ");
            wc_arm_put_u32(bench.xcp_tx[0].data[0]);
            wc_arm_puts(", error ");
            wc_arm_put_u32(bench.xcp_tx[0].data[1]);
            wc_arm_puts("\n");
            fail("xcp: the DAQ configuration was refused");
            return;
        }
    }
    ok = true;
    for (uint32_t k = 0u; k < XCP_MEASURED_PERIODS; ++k) {
        ok = xcp_period(NULL, ROW_XCP_DAQ) && xcp_daq_frames_ok(0u) && ok;
    }
    if (!ok) { fail("xcp: a DAQ step did not send the list's 8 ODTs with the loop's values"); }

    /* BUILD_CHECKSUM over the whole page, the DAQ list running. */
    const wc_can_frame_t set_mta_page = wc_arm_xcp_set_mta(config.cal_base);
    const wc_can_frame_t checksum = wc_arm_xcp_build_checksum(wc_cal_image_payload_bytes);
    for (uint32_t k = 0u; k < XCP_CHECKSUMS; ++k) {
        ok = xcp_period(&set_mta_page, ROWS) && xcp_period(&checksum, ROW_XCP_CHECKSUM_PAGE) &&
             (wc_image_get_u32(&bench.xcp_tx[0].data[4]) == wc_image_crc32(xcp.working_page, wc_cal_image_payload_bytes)) &&
             xcp_daq_frames_ok(1u) && ok;
    }
    if (!ok) { fail("xcp: BUILD_CHECKSUM of the page"); }

    /* DOWNLOAD of the shift PI gain, scaled and back: each step checks the
     * whole page and gives it to the loop; the DAQ list running. */
    const float kp_reference = xcp_loop_set.shift.kp_Nm_per_rad_s;
    for (uint32_t k = 0u; k < XCP_DOWNLOADS; ++k) {
        const float scale = ((k % 2u) == 0u) ? XCP_KP_SCALE : 1.0f;
        uint8_t bytes[4];
        uint32_t length = 0u;
        const uint32_t offset = xcp_kp_bytes(reference, scale, bytes, &length);
        const wc_can_frame_t set_mta = wc_arm_xcp_set_mta(config.cal_base + offset);
        const wc_can_frame_t download = wc_arm_xcp_download(bytes, length);
        const uint32_t accepted = xcp.status.pages_accepted;
        ok = (length > 0u) && xcp_period(&set_mta, ROWS) && xcp_period(&download, ROW_XCP_DOWNLOAD_CHECK) &&
             (xcp.status.pages_accepted == accepted + 1u) && (xcp.status.page_result == 0u) &&
             (loop.config.shift != NULL) && (loop.config.shift->kp_Nm_per_rad_s >= kp_reference * scale) &&
             (loop.config.shift->kp_Nm_per_rad_s <= kp_reference * scale) && xcp_daq_frames_ok(1u) && ok;
    }
    if (!ok) { fail("xcp: a DOWNLOAD of the gain was not checked, accepted and given to the loop"); }
    if (loop.counters.safe_steps != safe_steps) { fail("xcp: the loop went to its safe state in the session"); }

    /* The largest BUILD_CHECKSUM block's CRC (no region is that large: the
     * CRC-32 a block of WC_XCP_CHECKSUM_MAX_BYTES would cost). */
    for (uint32_t i = 0u; i < WC_XCP_CHECKSUM_MAX_BYTES; ++i) { crc_block[i] = (uint8_t)(i * 131u); }
    bench.crc_data = crc_block;
    bench.crc_length = WC_XCP_CHECKSUM_MAX_BYTES;
    record(ROW_CRC32_MAX_BLOCK, measure(thunk_crc32, &bench));

    /* The page check's two parts: the decode with its checks, and the loop's
     * recalibration (wc_model_init: the clutch check again, the shift check again). */
    bench.payload = xcp.working_page;
    bench.cal_set = &xcp_scratch_set;
    record(ROW_CAL_IMAGE_DECODE, measure(thunk_cal_image_decode, &bench));
    if (bench.cal_image_status.result != (uint32_t)WC_CAL_IMAGE_OK) { fail("xcp: wc_cal_image_decode of the page"); }
    record(ROW_LOOP_RECALIBRATE, measure(thunk_loop_recalibrate, &bench));
    if (bench.cal_error != WC_CAL_OK) { fail("xcp: wc_loop_recalibrate"); }

    wc_arm_puts("XCP session: ");
    wc_arm_put_u32(xcp.status.commands);
    wc_arm_puts(" commands, ");
    wc_arm_put_u32(xcp.status.daq_frames);
    wc_arm_puts(" DAQ frames, ");
    wc_arm_put_u32(xcp.status.pages_accepted);
    wc_arm_puts(" pages accepted, sizeof(wc_xcp_t) ");
    wc_arm_put_u32((uint32_t)sizeof(wc_xcp_t));
    wc_arm_puts(" B\n");
}
