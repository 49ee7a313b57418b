/* The XCP on CAN slave's commands (include/wetclutch_can/wc_xcp.h,
 * src/can/wc_xcp.c; DESIGN 13) over a running frame loop with the table1
 * calibration:
 *  - every command's positive response, byte by byte, against the layouts
 *    of ASAM MCD-1 XCP part 2 (CONNECT, GET_STATUS, SYNCH,
 *    GET_COMM_MODE_INFO, GET_ID + UPLOAD of the text, SET_MTA, UPLOAD,
 *    SHORT_UPLOAD, BUILD_CHECKSUM, the page commands, the DAQ information
 *    commands);
 *  - every error class of the commands (ignored frames, CMD_UNKNOWN,
 *    CMD_SYNTAX, OUT_OF_RANGE, ACCESS_DENIED, WRITE_PROTECTED,
 *    PAGE_NOT_VALID, ring overflow).
 * DAQ: test_xcp_daq.c; calibration changes: test_xcp_calibration.c; the rig:
 * wc_test_xcp_harness.h. */
#include "wc_test_xcp_harness.h"

#include <string.h>

#include <wetclutch_can/wc_gearbox_image.h>

#include "generated/wc_gearbox_image_layout.h"
#include "wc_8hp_gearbox.h"

/* ======================================================================== */
/* Positive responses                                                       */
/* ======================================================================== */

static void test_connect_status_and_information(void **state)
{
    (void)state;
    /* before CONNECT: no answer at all, counted as ignored */
    const wc_can_frame_t status = xcp_frame(BYTES(WC_XCP_GET_STATUS), 1u);
    queue_frame(&status);
    assert_int_equal(xstep(false), 0u);
    assert_int_equal(rig.xcp.status.ignored, 1u);
    assert_int_equal(rig.xcp.status.commands, 0u);

    /* CONNECT: RESOURCE CAL/PAG + DAQ, COMM_MODE_BASIC Intel/byte/optional, MAX_CTO 8, MAX_DTO 8 (word), versions 1 */
    connect();
    /* GET_STATUS: session status 0, no protection, reserved, session configuration id 0 */
    EXPECT(CMD(WC_XCP_GET_STATUS), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    /* SYNCH: the error packet ERR_CMD_SYNCH */
    EXPECT(CMD(WC_XCP_SYNCH), 0xFE, 0x00, 0, 0, 0, 0, 0, 0);
    /* GET_COMM_MODE_INFO: reserved, COMM_MODE_OPTIONAL 0, reserved, MAX_BS 0, MIN_ST 0, QUEUE_SIZE 0, driver 1.0 */
    EXPECT(CMD(WC_XCP_GET_COMM_MODE_INFO), 0xFF, 0, 0, 0, 0, 0, 0, 0x10);
    /* GET_PAG_PROCESSOR_INFO: MAX_SEGMENT 1, PAG_PROPERTIES 0 (no freeze) */
    EXPECT(CMD(WC_XCP_GET_PAG_PROCESSOR_INFO), 0xFF, 1, 0, 0, 0, 0, 0, 0);
    /* GET_DAQ_PROCESSOR_INFO: dynamic | prescaler | timestamps | overload by event (0x93), MAX_DAQ 4,
     * MAX_EVENT_CHANNEL 1, MIN_DAQ 0, DAQ_KEY_BYTE 0 */
    EXPECT(CMD(WC_XCP_GET_DAQ_PROCESSOR_INFO), 0xFF, 0x93, WC_XCP_DAQ_LISTS, 0, 1, 0, 0, 0);
    /* GET_DAQ_RESOLUTION_INFO: granularity 1, max ODT entry 7, STIM 1 / 0, TIMESTAMP_MODE 10 us | FIXED | 2 bytes,
     * TIMESTAMP_TICKS = the control period in 10 us (table1: 1 ms = 100) */
    assert_true(fabsf(wc_table1_calibration.control_period_s - 1e-3f) < 1e-9f);
    EXPECT(CMD(WC_XCP_GET_DAQ_RESOLUTION_INFO), 0xFF, 1, 7, 1, 0, 0x4A, 100, 0);
    /* GET_DAQ_EVENT_INFO 0: DAQ + event consistency (0x84), MAX_DAQ_LIST 4, name length 12, cycle 100 x 10 us
     * (unit 4), priority 0xFF; the name by UPLOAD from the MTA it sets */
    EXPECT(CMD(WC_XCP_GET_DAQ_EVENT_INFO, 0, 0, 0), 0xFF, 0x84, WC_XCP_DAQ_LISTS, 12, 100, 4, 0xFF, 0);
    const wc_can_frame_t *r = CMD(WC_XCP_UPLOAD, 7);
    EXPECT(r, 0xFF, 'c', 'o', 'n', 't', 'r', 'o', 'l');
    EXPECT(CMD(WC_XCP_UPLOAD, 5), 0xFF, '_', 's', 't', 'e', 'p', 0, 0);
    EXPECT_ERR(CMD(WC_XCP_GET_DAQ_EVENT_INFO, 0, 1, 0), WC_XCP_ERR_OUT_OF_RANGE);  /* one event channel */
    /* GET_DAQ_CLOCK: reserved, trigger 0, payload format 0, the 32-bit timestamp (the step counter) */
    for (uint32_t k = 0u; k < 3u; ++k) { assert_true(period(0.0f, 0.0f, MODE_OPEN)); }
    EXPECT(CMD(WC_XCP_GET_DAQ_CLOCK), 0xFF, 0, 0, 0, 3, 0, 0, 0);
    assert_int_equal(rig.xcp.status.timestamp, 3u);
    assert_int_equal(rig.xcp.status.commands, 12u);
    assert_int_equal(rig.xcp.status.errors, 2u);  /* SYNCH and the event channel */

    /* DISCONNECT: positive, then commands are ignored again */
    EXPECT(CMD(WC_XCP_DISCONNECT), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    queue_frame(&status);
    assert_int_equal(xstep(false), 0u);
    assert_int_equal(rig.xcp.status.ignored, 2u);
}

static void test_get_id_then_upload(void **state)
{
    (void)state;
    connect();
    /* GET_ID type 0 (ASCII): mode 0 (upload from the MTA), reserved, length 13 ("wetclutch TCU") as a DWORD */
    EXPECT(CMD(WC_XCP_GET_ID, 0), 0xFF, 0, 0, 0, 13, 0, 0, 0);
    EXPECT(CMD(WC_XCP_UPLOAD, 7), 0xFF, 'w', 'e', 't', 'c', 'l', 'u', 't');
    EXPECT(CMD(WC_XCP_UPLOAD, 6), 0xFF, 'c', 'h', ' ', 'T', 'C', 'U', 0);
    /* GET_ID type 1 (A2L name without path and extension): "wetclutch" */
    EXPECT(CMD(WC_XCP_GET_ID, 1), 0xFF, 0, 0, 0, 9, 0, 0, 0);
    EXPECT(CMD(WC_XCP_UPLOAD, 7), 0xFF, 'w', 'e', 't', 'c', 'l', 'u', 't');
    EXPECT(CMD(WC_XCP_UPLOAD, 2), 0xFF, 'c', 'h', 0, 0, 0, 0, 0);
    /* another type: no text */
    EXPECT(CMD(WC_XCP_GET_ID, 4), 0xFF, 0, 0, 0, 0, 0, 0, 0);
}

/* The calibration page read by UPLOAD and by SHORT_UPLOAD is the reference payload (table1 + the loop's settings,
 * wc_cal_set_from + wc_cal_image_encode here), on both pages; BUILD_CHECKSUM is its wc_image_crc32. */
static void test_upload_page_and_checksum(void **state)
{
    (void)state;
    static uint8_t expected[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
    static wc_cal_set_t set;
    assert_true(wc_cal_set_from(&set, &wc_table1_calibration, NULL, &rig_config));
    wc_cal_image_encode(&set, expected);
    connect();
    for (uint8_t page = 0u; page < 2u; ++page) {
        EXPECT_OK(CMD(WC_XCP_SET_CAL_PAGE, 0x02, 0, page));  /* the XCP's page: UPLOAD reads it */
        static uint8_t read[PAYLOAD];
        memset(read, 0x5A, sizeof read);
        upload(cal_address(0u), read, PAYLOAD);
        assert_memory_equal(read, expected, PAYLOAD);
        /* the MTA is past the page: one more byte is outside every region */
        EXPECT_ERR(CMD(WC_XCP_UPLOAD, 1), WC_XCP_ERR_ACCESS_DENIED);
        /* SHORT_UPLOAD at offsets through the page, the last 7 bytes on its end */
        static const uint32_t offsets[] = { 0u, WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, 333u, PAYLOAD - 7u };
        for (size_t i = 0u; i < WC_TEST_COUNT(offsets); ++i) {
            const wc_can_frame_t *r = CMD(WC_XCP_SHORT_UPLOAD, 7, 0, 0, U32(cal_address(offsets[i])));
            EXPECT_OK(r);
            assert_memory_equal(&r->data[1], &expected[offsets[i]], 7u);
        }
        /* BUILD_CHECKSUM over the page: XCP_CRC_32 (0x09), reserved, the CRC as a DWORD; the MTA moves past it */
        set_mta(cal_address(0u));
        const uint32_t crc = wc_image_crc32(expected, PAYLOAD);
        EXPECT(CMD(WC_XCP_BUILD_CHECKSUM, 0, 0, 0, U32(PAYLOAD)), 0xFF, 0x09, 0, 0, U32(crc));
        assert_int_equal(rig.xcp.mta, cal_address(PAYLOAD));
    }
    /* a block above MAX_BLOCKSIZE: ERR_OUT_OF_RANGE with MAX_BLOCKSIZE (4096) in bytes 4..7 */
    set_mta(cal_address(0u));
    EXPECT(CMD(WC_XCP_BUILD_CHECKSUM, 0, 0, 0, U32(WC_XCP_CHECKSUM_MAX_BYTES + 1u)), 0xFE, WC_XCP_ERR_OUT_OF_RANGE, 0,
           0, U32(WC_XCP_CHECKSUM_MAX_BYTES));
    /* a block that runs past the page's end */
    set_mta(cal_address(1u));
    EXPECT_ERR(CMD(WC_XCP_BUILD_CHECKSUM, 0, 0, 0, U32(PAYLOAD)), WC_XCP_ERR_ACCESS_DENIED);
}

/* The loop region reads the wc_loop_t, the status region the slave's counters. */
static void test_upload_measurements(void **state)
{
    (void)state;
    for (uint32_t k = 0u; k < 4u; ++k) { assert_true(period(0.0f, 0.0f, MODE_OPEN)); }
    connect();
    uint8_t b[4];
    upload(loop_address(offsetof(wc_loop_t, counters.steps)), b, 4u);
    uint32_t steps;
    memcpy(&steps, b, sizeof steps);
    assert_int_equal(steps, 4u);
    upload(loop_address(offsetof(wc_loop_t, last.current_mA)), b, 4u);
    assert_memory_equal(b, &rig.loop.last.current_mA, 4u);
    upload(xcp_config.status_base + (uint32_t)offsetof(wc_xcp_status_t, timestamp), b, 4u);
    uint32_t timestamp;
    memcpy(&timestamp, b, sizeof timestamp);
    assert_int_equal(timestamp, 4u);
}

static void test_calibration_page_commands(void **state)
{
    (void)state;
    connect();
    /* GET_CAL_PAGE (ECU / XCP access, segment 0): reserved, reserved, the page */
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x01, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x02, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    /* SET_CAL_PAGE of the XCP access only */
    EXPECT(CMD(WC_XCP_SET_CAL_PAGE, 0x02, 0, 1), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x02, 0), 0xFF, 0, 0, 1, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x01, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    assert_int_equal(rig.xcp.status.ecu_page, 0u);
    /* page 2 does not exist; nor does segment 1; a mode without ECU or XCP is not valid */
    EXPECT_ERR(CMD(WC_XCP_SET_CAL_PAGE, 0x03, 0, 2), WC_XCP_ERR_PAGE_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_SET_CAL_PAGE, 0x03, 1, 0), WC_XCP_ERR_SEGMENT_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_SET_CAL_PAGE, 0x00, 0, 0), WC_XCP_ERR_MODE_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_GET_CAL_PAGE, 0x01, 1), WC_XCP_ERR_SEGMENT_NOT_VALID);
    /* the reference page is read-only: DOWNLOAD through the XCP page 1, COPY_CAL_PAGE to page 1 */
    set_mta(cal_address(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN));
    EXPECT_ERR(download_n(BYTES(0, 0, 0, 0), 4u, 1u), WC_XCP_ERR_WRITE_PROTECTED);
    EXPECT_ERR(CMD(WC_XCP_COPY_CAL_PAGE, 0, 0, 0, 1), WC_XCP_ERR_WRITE_PROTECTED);
    EXPECT_ERR(CMD(WC_XCP_COPY_CAL_PAGE, 0, 2, 0, 0), WC_XCP_ERR_PAGE_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_COPY_CAL_PAGE, 1, 1, 0, 0), WC_XCP_ERR_SEGMENT_NOT_VALID);
    /* COPY_CAL_PAGE reference -> working restores a changed working page (then checked and accepted) */
    EXPECT_OK(CMD(WC_XCP_SET_CAL_PAGE, 0x02, 0, 0));
    EXPECT_OK(download_f32(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, 0.3f, 1u));
    assert_int_equal(rig.xcp.status.pages_accepted, 1u);
    assert_true(fabsf(rig.loop.clutch.model.cal->holding_margin - 0.3f) < 1e-9f);
    EXPECT(CMD(WC_XCP_COPY_CAL_PAGE, 0, 1, 0, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    assert_memory_equal(rig.xcp.working_page, rig.reference, PAYLOAD);
    assert_int_equal(rig.xcp.status.pages_accepted, 2u);
    assert_true(wc_test_same_float(rig.loop.clutch.model.cal->holding_margin, wc_table1_calibration.holding_margin));
    /* copying an identical page changes nothing: no check */
    EXPECT_OK(CMD(WC_XCP_COPY_CAL_PAGE, 0, 1, 0, 0));
    assert_int_equal(rig.xcp.status.pages_accepted, 2u);
}

/* ======================================================================== */
/* Errors and frames that get no answer                                     */
/* ======================================================================== */

static void test_command_errors(void **state)
{
    (void)state;
    connect();
    EXPECT_ERR(CMD(0xC0), WC_XCP_ERR_CMD_UNKNOWN);               /* not an XCP command */
    EXPECT_ERR(CMD(0xF1, 0, 0, 0, 0, 0, 0, 0), WC_XCP_ERR_CMD_UNKNOWN);  /* USER_CMD: not supported */
    EXPECT_ERR(CMD(0xF8, 0, 0), WC_XCP_ERR_OUT_OF_RANGE);  /* GET_SEED of no resource (test_xcp_security.c) */
    EXPECT_ERR(command(BYTES(WC_XCP_SET_MTA, 0, 0, 0), 4u), WC_XCP_ERR_CMD_SYNTAX);  /* too short */
    EXPECT_ERR(command(BYTES(WC_XCP_GET_ID), 1u), WC_XCP_ERR_CMD_SYNTAX);
    EXPECT_ERR(command(BYTES(WC_XCP_DOWNLOAD, 4, 1, 2), 4u), WC_XCP_ERR_CMD_SYNTAX);  /* 4 bytes announced, 2 sent */
    EXPECT_ERR(command(BYTES(WC_XCP_ALLOC_ODT, 0, 0, 0), 4u), WC_XCP_ERR_CMD_SYNTAX);
    set_mta(cal_address(0u));
    EXPECT(CMD(WC_XCP_UPLOAD, 8), 0xFE, WC_XCP_ERR_OUT_OF_RANGE, 0, 0, 0, 0, 0, 0);  /* 7 bytes at most */
    EXPECT_ERR(CMD(WC_XCP_UPLOAD, 0), WC_XCP_ERR_OUT_OF_RANGE);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 8, 0, 0, U32(cal_address(0u))), WC_XCP_ERR_OUT_OF_RANGE);
    set_mta(cal_address(0u));
    EXPECT_ERR(CMD(WC_XCP_DOWNLOAD, 7, 1, 2, 3, 4, 5, 6), WC_XCP_ERR_OUT_OF_RANGE);  /* 6 at most in a frame */
    /* outside every region: below, between, above; with address extension 1 */
    static const uint32_t outside[] = { 0u, 0x00005000u, 0x00010000u - 1u, 0x00010000u + PAYLOAD, 0x00400000u,
                                        0xFFFFFFF0u };
    for (size_t i = 0u; i < WC_TEST_COUNT(outside); ++i) {
        EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 0, U32(outside[i])), WC_XCP_ERR_ACCESS_DENIED);
    }
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 1, U32(cal_address(0u))), WC_XCP_ERR_ACCESS_DENIED);
    EXPECT_ERR(CMD(WC_XCP_SET_MTA, 0, 0, 1, U32(cal_address(0u))), WC_XCP_ERR_ACCESS_DENIED);
    /* straddling each region's end: one byte too many is denied, the last bytes themselves are not */
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&rig.xcp, regions);
    assert_int_equal(regions[0].size, PAYLOAD);
    assert_int_equal(regions[1].size, sizeof(wc_loop_t));
    for (uint32_t r = 0u; r < 4u; ++r) {  /* the gearbox's and the elements' regions (none given here): below */
        const uint32_t end = regions[r].base + regions[r].size;
        EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(end - 3u)), WC_XCP_ERR_ACCESS_DENIED);
        EXPECT_OK(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(end - 4u)));
        EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 0, U32(end)), WC_XCP_ERR_ACCESS_DENIED);
    }
    /* DOWNLOAD into the loop, the status, the id: read-only */
    static const uint32_t read_only[] = { 0x00100000u, 0x00200000u, 0x00300000u };
    for (size_t i = 0u; i < WC_TEST_COUNT(read_only); ++i) {
        set_mta(read_only[i]);
        EXPECT_ERR(download_n(BYTES(0, 0), 2u, 1u), WC_XCP_ERR_WRITE_PROTECTED);
    }
    /* ... and outside every region: denied; straddling the working page's end: denied, nothing written */
    set_mta(0x00005000u);
    EXPECT_ERR(download_n(BYTES(0, 0), 2u, 1u), WC_XCP_ERR_ACCESS_DENIED);
    set_mta(cal_address(PAYLOAD - 1u));
    EXPECT_ERR(download_n(BYTES(1, 1), 2u, 1u), WC_XCP_ERR_ACCESS_DENIED);
    assert_memory_equal(rig.xcp.working_page, rig.reference, PAYLOAD);
    assert_int_equal(rig.xcp.status.pages_accepted + rig.xcp.status.pages_rejected, 0u);
    /* every command but CONNECT, the 7 SET_MTAs and the 4 uploads of a region's last bytes was an error */
    assert_int_equal(rig.xcp.status.errors, rig.xcp.status.commands - 1u - 7u - 4u);
}

/* The gearbox region (issue 29 item 1): the payload of the gearbox image the transmission runs, read only;
 * without one, denied. */
static void test_gearbox_region(void **state)
{
    (void)state;
    static uint8_t image[WC_IMAGE_BYTES(WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES)];
    static uint8_t uploaded[WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES];
    const uint32_t base = xcp_config.gearbox_base;
    const uint32_t n = wc_gearbox_image_payload_bytes;
    connect();
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(base)), WC_XCP_ERR_ACCESS_DENIED);
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, image, sizeof image), WC_IMAGE_BYTES(n));
    const uint8_t *payload = &image[WC_IMAGE_HEADER_BYTES];
    wc_xcp_set_gearbox(&rig.xcp, payload);
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&rig.xcp, regions);
    assert_int_equal(regions[4].base, base);
    assert_int_equal(regions[4].size, n);
    upload(base, uploaded, n);
    assert_memory_equal(uploaded, payload, n);
    /* the A2L's gearbox.ratio[3] at its layout offset: the compiled-in table's 3rd gear */
    assert_memory_equal(&uploaded[WC_GEARBOX_IMAGE_OFFSET_RATIO + 4u * 3u], &wc_gearbox_8hp.ratio[3], 4u);
    EXPECT_OK(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(base + n - 4u)));
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(base + n - 3u)), WC_XCP_ERR_ACCESS_DENIED);
    set_mta(base + 4u * 3u);
    EXPECT_ERR(download_n(BYTES(0, 0, 0, 0), 4u, 1u), WC_XCP_ERR_WRITE_PROTECTED);
    assert_memory_equal(uploaded, payload, n);
    wc_xcp_set_gearbox(&rig.xcp, NULL);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(base)), WC_XCP_ERR_ACCESS_DENIED);
}

/* Each element's region: its calibration payload, read only; without one, or past the elements, denied. */
static void test_element_regions(void **state)
{
    (void)state;
    static uint8_t uploaded[PAYLOAD];
    const uint32_t element2 = xcp_config.element_base + 2u * WC_XCP_ELEMENT_STRIDE;
    connect();
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(element2)), WC_XCP_ERR_ACCESS_DENIED);
    wc_xcp_set_element(&rig.xcp, 2u, rig.reference);           /* a calibration payload stands for the element's */
    wc_xcp_set_element(&rig.xcp, WC_GEARBOX_ELEMENTS_MAX, rig.reference);   /* no such element: nothing */
    wc_xcp_region_t regions[WC_XCP_REGIONS];
    wc_xcp_regions(&rig.xcp, regions);
    assert_int_equal(regions[WC_XCP_FIRST_ELEMENT_REGION + 2u].base, element2);
    assert_int_equal(regions[WC_XCP_FIRST_ELEMENT_REGION + 2u].size, PAYLOAD);
    upload(element2, uploaded, PAYLOAD);
    assert_memory_equal(uploaded, rig.reference, PAYLOAD);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 0, U32(element2 + PAYLOAD)), WC_XCP_ERR_ACCESS_DENIED);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 0, U32(element2 - WC_XCP_ELEMENT_STRIDE)), WC_XCP_ERR_ACCESS_DENIED);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 1, 0, 0,
                   U32(xcp_config.element_base + WC_GEARBOX_ELEMENTS_MAX * WC_XCP_ELEMENT_STRIDE)),
               WC_XCP_ERR_ACCESS_DENIED);
    set_mta(element2);
    EXPECT_ERR(download_n(BYTES(0, 0, 0, 0), 4u, 1u), WC_XCP_ERR_WRITE_PROTECTED);
    assert_memory_equal(uploaded, rig.reference, PAYLOAD);
    wc_xcp_set_element(&rig.xcp, 2u, NULL);
    EXPECT_ERR(CMD(WC_XCP_SHORT_UPLOAD, 4, 0, 0, U32(element2)), WC_XCP_ERR_ACCESS_DENIED);
}

static void test_frames_without_answer(void **state)
{
    (void)state;
    connect();
    wc_can_frame_t f[6];
    for (size_t i = 0u; i < WC_TEST_COUNT(f); ++i) { f[i] = xcp_frame(BYTES(WC_XCP_GET_STATUS), 1u); }
    f[0].flags = WC_CAN_FLAG_EXTENDED;
    f[1].flags = WC_CAN_FLAG_REMOTE;
    f[2].flags = WC_CAN_FLAG_ERROR;
    f[3].dlc = 0u;
    f[4].id = WC_CAN_XCP_RESPONSE_FRAME_ID;  /* the port filters by id; the slave checks it too */
    f[5].dlc = 9u;
    for (size_t i = 0u; i < WC_TEST_COUNT(f); ++i) {
        queue_frame(&f[i]);
        assert_int_equal(xstep(false), 0u);
    }
    assert_int_equal(rig.xcp.status.ignored, WC_TEST_COUNT(f));
    assert_int_equal(rig.xcp.status.commands, 1u);
    /* ring overflow: WC_XCP_RX_CAPACITY frames between two steps fit, one more is lost and counted; a step
     * answers one command (wc_xcp.h), the others wait in the ring for the next steps, in order */
    for (uint32_t i = 0u; i < WC_XCP_RX_CAPACITY; ++i) {
        const wc_can_frame_t g = xcp_frame(BYTES(WC_XCP_GET_ID, (uint8_t)i), 2u);
        queue_frame(&g);
    }
    const wc_can_frame_t lost = xcp_frame(BYTES(WC_XCP_GET_STATUS), 1u);
    assert_false(wc_xcp_receive(&rig.xcp, &lost));
    assert_int_equal(rig.xcp.status.rx_overflows, 1u);
    static const uint8_t lengths[WC_XCP_RX_CAPACITY] = { 13u, 9u, 0u, 0u };  /* GET_ID 0, 1, 2, 3 */
    for (uint32_t i = 0u; i < WC_XCP_RX_CAPACITY; ++i) {
        assert_int_equal(xstep(i == 0u), 1u);
        EXPECT(&rig.xout[0], 0xFF, 0, 0, 0, lengths[i], 0, 0, 0);
    }
    assert_int_equal(xstep(false), 0u);
    assert_int_equal(rig.xcp.status.commands, 1u + WC_XCP_RX_CAPACITY);
    const wc_can_frame_t g = xcp_frame(BYTES(WC_XCP_GET_STATUS), 1u);
    queue_frame(&g);
    assert_int_equal(xstep(false), 1u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_connect_status_and_information, setup),
        cmocka_unit_test_setup(test_get_id_then_upload, setup),
        cmocka_unit_test_setup(test_upload_page_and_checksum, setup),
        cmocka_unit_test_setup(test_upload_measurements, setup),
        cmocka_unit_test_setup(test_calibration_page_commands, setup),
        cmocka_unit_test_setup(test_command_errors, setup),
        cmocka_unit_test_setup(test_gearbox_region, setup),
        cmocka_unit_test_setup(test_element_regions, setup),
        cmocka_unit_test_setup(test_frames_without_answer, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
