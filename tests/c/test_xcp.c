/* The XCP on CAN slave (include/wetclutch_can/wc_xcp.h, src/can/wc_xcp.c;
 * DESIGN 13) over a running frame loop with the table1 calibration:
 *  - every command's positive response, byte by byte, against the layouts
 *    of ASAM MCD-1 XCP part 2 (CONNECT, GET_STATUS, SYNCH,
 *    GET_COMM_MODE_INFO, GET_ID + UPLOAD of the text, SET_MTA, UPLOAD,
 *    SHORT_UPLOAD, BUILD_CHECKSUM, the page commands, the DAQ information
 *    commands, the dynamic DAQ sequence and the DAQ frames: PIDs, the 2-byte
 *    step timestamp and the loop's values at that step);
 *  - every error class (ignored frames, CMD_UNKNOWN, CMD_SYNTAX,
 *    OUT_OF_RANGE, ACCESS_DENIED, WRITE_PROTECTED, PAGE_NOT_VALID,
 *    SEQUENCE, MEMORY_OVERFLOW, DAQ_CONFIG, DAQ_ACTIVE, ring overflow);
 *  - calibration: a DOWNLOAD of holding_margin used by the next step (the
 *    locked clutch's force scales as 1 + margin), refused pages (the loop's
 *    calibration and outputs bit-identical to a twin loop without XCP, the
 *    status and one EV_USER event), the reference page back by
 *    SET_CAL_PAGE, a page prepared while the controller runs on the
 *    reference page;
 *  - DAQ overload, and the control frames of a loop with an XCP session
 *    byte-identical to those of a loop without one.
 * Every loop step here has a twin: the same frames into a second wc_loop_t
 * without XCP, so "no effect on control" is a byte comparison. */
#include "wc_test_support.h"

#include "generated/wc_cal_image_layout.h"
#include "wc_shift_1_2_shift.h"
#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_cal_image.h"
#include "wetclutch_can/wc_e2e.h"
#include "wetclutch_can/wc_loop.h"
#include "wetclutch_can/wc_xcp.h"

#define THETA_START_degC 40.0f
#define PAYLOAD WC_CAL_IMAGE_PAYLOAD_BYTES
#define OIL_degC THETA_START_degC  /* oil = housing = start: at zero slip the observer does not move (no drift) */
#define LOCK_TORQUE_Nm 100.0f  /* well inside the capacity at i_max with margin 0.5 (checked below) */

#define MODE_OPEN WC_CAN_TORQUE_REQUEST_MODE_OPEN_CHOICE
#define MODE_TORQUE WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE

/* Recovery after one fresh period (the steady tests see control at once); the image's limits hold it. */
static const wc_loop_config_t rig_config = { 10u, 10u, { 2u, 3u }, 1u, false, NULL, NULL, NULL, NULL };
static const wc_xcp_config_t xcp_config = WC_XCP_CONFIG_DEFAULT;

typedef struct {
    wc_loop_t loop;   /* with the slave */
    wc_loop_t twin;   /* the same frames, no slave */
    wc_xcp_t xcp;
    wc_cal_set_t set;
    uint8_t reference[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];  /* the reference page: table1 + rig_config */
    uint8_t alive;
    uint32_t control_steps;
    wc_can_frame_t out[WC_LOOP_TX_FRAMES];
    wc_can_frame_t twin_out[WC_LOOP_TX_FRAMES];
    wc_can_frame_t xout[WC_XCP_TX_FRAMES];
    uint32_t xn;
} rig_t;

static rig_t rig;  /* two loops and a slave: static, not the stack */

static int setup(void **state)
{
    (void)state;
    memset(&rig, 0, sizeof rig);
    assert_true(wc_cal_set_from(&rig.set, &wc_table1_calibration, NULL, &rig_config));
    wc_cal_image_encode(&rig.set, rig.reference);
    assert_int_equal(wc_loop_init(&rig.loop, &wc_table1_calibration, &rig_config, THETA_START_degC), WC_CAL_OK);
    assert_int_equal(wc_loop_init(&rig.twin, &wc_table1_calibration, &rig_config, THETA_START_degC), WC_CAL_OK);
    assert_true(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &xcp_config));
    return 0;
}

/* ======================================================================== */
/* Frames and commands                                                      */
/* ======================================================================== */

static wc_can_frame_t xcp_frame(const uint8_t *bytes, uint32_t dlc)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = WC_CAN_XCP_COMMAND_FRAME_ID;
    f.dlc = (uint8_t)dlc;
    for (uint32_t i = 0u; (i < dlc) && (i < 8u); ++i) { f.data[i] = bytes[i]; }
    return f;
}

static void queue_frame(const wc_can_frame_t *f) { assert_true(wc_xcp_receive(&rig.xcp, f)); }

/* One wc_xcp_step; every frame it returns is an XcpResponse of DLC 8 without flags. */
static uint32_t xstep(bool control_step)
{
    memset(rig.xout, 0xA5, sizeof rig.xout);  /* a byte the slave forgets to write shows */
    rig.xn = wc_xcp_step(&rig.xcp, control_step, rig.xout);
    assert_true(rig.xn <= WC_XCP_TX_FRAMES);
    for (uint32_t i = 0u; i < rig.xn; ++i) {
        WC_CHECK((rig.xout[i].id == WC_CAN_XCP_RESPONSE_FRAME_ID) && (rig.xout[i].dlc == 8u) &&
                     (rig.xout[i].flags == 0u),
                 "frame %u: id 0x%x dlc %u flags %u", (unsigned)i, (unsigned)rig.xout[i].id,
                 (unsigned)rig.xout[i].dlc, (unsigned)rig.xout[i].flags);
    }
    return rig.xn;
}

/* One command frame and the step that answers it: exactly `frames` frames back (the response first). */
static const wc_can_frame_t *command_n(const uint8_t *bytes, uint32_t dlc, uint32_t frames)
{
    const wc_can_frame_t f = xcp_frame(bytes, dlc);
    queue_frame(&f);
    const uint32_t n = xstep(false);
    WC_CHECK(n == frames, "command 0x%02x: %u frames, expected %u", (unsigned)bytes[0], (unsigned)n, (unsigned)frames);
    return &rig.xout[0];
}

static const wc_can_frame_t *command(const uint8_t *bytes, uint32_t dlc) { return command_n(bytes, dlc, 1u); }

#define BYTES(...) ((const uint8_t[]){ __VA_ARGS__ })
#define CMD(...) command(BYTES(__VA_ARGS__), (uint32_t)sizeof(BYTES(__VA_ARGS__)))

static void expect_bytes(const wc_can_frame_t *f, const uint8_t want[8], int line)
{
    bool same = true;
    for (uint32_t i = 0u; i < 8u; ++i) { same = same && (f->data[i] == want[i]); }
    if (!same) {
        print_error("line %d: got %02x %02x %02x %02x %02x %02x %02x %02x, expected %02x %02x %02x %02x %02x %02x %02x "
                    "%02x\n",
                    line, f->data[0], f->data[1], f->data[2], f->data[3], f->data[4], f->data[5], f->data[6],
                    f->data[7], want[0], want[1], want[2], want[3], want[4], want[5], want[6], want[7]);
        fail();
    }
}
#define EXPECT(frame, ...) expect_bytes((frame), BYTES(__VA_ARGS__), __LINE__)

static void expect_ok(const wc_can_frame_t *f, int line)
{
    if (f->data[0] != WC_XCP_PID_RES) {
        print_error("line %d: PID 0x%02x (error 0x%02x), expected a positive response\n", line, f->data[0], f->data[1]);
        fail();
    }
}
#define EXPECT_OK(frame) expect_ok((frame), __LINE__)

/* An error packet: PID 0xFE, the code, the rest 0 (ERR_OUT_OF_RANGE of BUILD_CHECKSUM aside). */
static void expect_error(const wc_can_frame_t *f, uint8_t code, int line)
{
    expect_bytes(f, BYTES(WC_XCP_PID_ERR, code, 0, 0, 0, 0, 0, 0), line);
}
#define EXPECT_ERR(frame, code) expect_error((frame), (code), __LINE__)

static uint8_t byte_of(uint32_t value, uint32_t i) { return (uint8_t)((value >> (8u * i)) & 0xFFu); }

#define U32(v) byte_of((v), 0u), byte_of((v), 1u), byte_of((v), 2u), byte_of((v), 3u)

static void connect(void)
{
    EXPECT(CMD(WC_XCP_CONNECT, 0), 0xFF, 0x05, 0x80, 8, 8, 0, 1, 1);
}

static void set_mta(uint32_t address)
{
    EXPECT(CMD(WC_XCP_SET_MTA, 0, 0, 0, U32(address)), 0xFF, 0, 0, 0, 0, 0, 0, 0);
}

/* DOWNLOAD of n bytes at the MTA: the response (and, after it, a page event if expected). */
static const wc_can_frame_t *download_n(const uint8_t *data, uint32_t n, uint32_t frames)
{
    assert_true(n <= 6u);
    uint8_t cmd[8] = { WC_XCP_DOWNLOAD, (uint8_t)n, 0, 0, 0, 0, 0, 0 };
    for (uint32_t i = 0u; i < n; ++i) { cmd[2u + i] = data[i]; }
    return command_n(cmd, 2u + n, frames);
}

static uint32_t cal_address(uint32_t offset) { return xcp_config.cal_base + offset; }
static uint32_t loop_address(size_t offset) { return xcp_config.loop_base + (uint32_t)offset; }

static void f32_bytes(float value, uint8_t out[4])
{
    uint32_t w;
    memcpy(&w, &value, sizeof w);
    for (uint32_t i = 0u; i < 4u; ++i) { out[i] = byte_of(w, i); }
}

/* A float of the working page written by SET_MTA + DOWNLOAD; frames: 1, or 2 with a page event. */
static const wc_can_frame_t *download_f32(uint32_t offset, float value, uint32_t frames)
{
    set_mta(cal_address(offset));
    uint8_t b[4];
    f32_bytes(value, b);
    return download_n(b, 4u, frames);
}

/* n bytes from address by SET_MTA and UPLOADs of at most 7 (the slave's MAX_CTO - 1). */
static void upload(uint32_t address, uint8_t *out, uint32_t n)
{
    set_mta(address);
    for (uint32_t done = 0u; done < n;) {
        const uint32_t chunk = (n - done < 7u) ? n - done : 7u;
        const wc_can_frame_t *r = CMD(WC_XCP_UPLOAD, (uint8_t)chunk);
        EXPECT_OK(r);
        for (uint32_t i = 0u; i < chunk; ++i) { out[done + i] = r->data[1u + i]; }
        for (uint32_t i = 1u + chunk; i < 8u; ++i) { assert_int_equal(r->data[i], 0u); }  /* padding 0 */
        done += chunk;
    }
}

/* ======================================================================== */
/* The loop                                                                 */
/* ======================================================================== */

static void queue_period_frames(wc_loop_t *loop, float slip_rpm, float torque_Nm, uint8_t mode, uint8_t alive)
{
    wc_can_frame_t s;
    memset(&s, 0, sizeof s);
    s.id = WC_CAN_CLUTCH_SENSORS_FRAME_ID;
    s.dlc = 8u;
    const wc_can_clutch_sensors_phys_t sp = { slip_rpm, OIL_degC, OIL_degC, alive };
    assert_int_equal(wc_can_encode_clutch_sensors(s.data, &sp, sizeof s.data), WC_CAN_OK);
    wc_can_frame_t q = s;
    q.id = WC_CAN_TORQUE_REQUEST_FRAME_ID;
    memset(q.data, 0, sizeof q.data);
    const wc_can_torque_request_phys_t qp = { torque_Nm, mode, alive };
    assert_int_equal(wc_can_encode_torque_request(q.data, &qp, sizeof q.data), WC_CAN_OK);
    assert_true(wc_loop_receive(loop, &s));
    assert_true(wc_loop_receive(loop, &q));
}

static bool same_frame(const wc_can_frame_t *a, const wc_can_frame_t *b)
{
    return (a->id == b->id) && (a->dlc == b->dlc) && (a->flags == b->flags) && (memcmp(a->data, b->data, 8u) == 0);
}

/* One control period of both loops (the slave's loop first, then its
 * wc_xcp_step as wc_tcu runs it: after the step's frames). Returns whether
 * the two loops' frames are byte-identical. */
static bool period(float slip_rpm, float torque_Nm, uint8_t mode)
{
    queue_period_frames(&rig.loop, slip_rpm, torque_Nm, mode, rig.alive);
    queue_period_frames(&rig.twin, slip_rpm, torque_Nm, mode, rig.alive);
    rig.alive = wc_e2e_counter_next(rig.alive);
    assert_int_equal(wc_loop_step(&rig.loop, rig.out), WC_LOOP_TX_CYCLIC);
    assert_int_equal(wc_loop_step(&rig.twin, rig.twin_out), WC_LOOP_TX_CYCLIC);
    rig.control_steps++;
    (void)xstep(true);
    return same_frame(&rig.out[0], &rig.twin_out[0]) && same_frame(&rig.out[1], &rig.twin_out[1]);
}

static float vfs_current_mA(const wc_can_frame_t *f)
{
    wc_can_vfs_command_phys_t cmd;
    assert_false(wc_can_is_error(wc_can_decode_vfs_command(&cmd, f->data, f->dlc)));
    return cmd.vfs_current_mA;
}

/* The commanded contact force of a current: F = i K A_p - F_s (the inverse's P = (F + F_s) / A_p, i = P / K). */
static double force_of_current_N(double current_mA)
{
    const wc_calibration_t *cal = &wc_table1_calibration;
    return current_mA * (double)cal->vfs_gain_Pa_per_mA * (double)cal->piston_area_m2 - (double)cal->return_spring_force_N;
}

/* Torque control at zero slip until the clutch is locked (DESIGN 9), the outputs equal to the twin's. */
static void lock_clutch(void)
{
    /* the VFS lag (60 ms) brings the force up, then the dwell: a few hundred periods (test_clutch.c) */
    for (uint32_t k = 0u; (k < 2000u) && !rig.loop.clutch.lockup.locked; ++k) {
        assert_true(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE));
    }
    assert_true(rig.loop.clutch.lockup.locked);
    for (uint32_t k = 0u; k < 5u; ++k) { assert_true(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE)); }
    assert_true((rig.loop.last.status & WC_STATUS_LOCKED) != 0u);
    assert_true((rig.loop.last.status & WC_STATUS_SATURATED) == 0u);
}

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
/* DAQ                                                                      */
/* ======================================================================== */

/* Two lists on event 0: list 0 of ODTs 0 (timestamp, last.current_mA, tx_alive) and 1 (clutch.theta_degC), every
 * step; list 1 of ODT 2 (timestamp, counters.steps, the slave's status.daq_frames low byte), every second step. */
static void daq_configure(void)
{
    EXPECT(CMD(WC_XCP_FREE_DAQ), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_ALLOC_DAQ, 0, 2, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 0, 0, 2));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 1, 0, 1));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 0, 0, 0, 2));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 0, 0, 1, 1));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 1, 0, 0, 2));
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 0, 0, 0, 0));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(offsetof(wc_loop_t, last.current_mA)))));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 1, 0, U32(loop_address(offsetof(wc_loop_t, tx_alive)))));
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 0, 0, 1, 0));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(offsetof(wc_loop_t, clutch.theta_degC)))));
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 1, 0, 0, 0));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(offsetof(wc_loop_t, counters.steps)))));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 1, 0,
                  U32(xcp_config.status_base + (uint32_t)offsetof(wc_xcp_status_t, daq_frames))));
    /* SET_DAQ_LIST_MODE: mode TIMESTAMP, list, event 0, prescaler, priority */
    EXPECT(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 0, 0, 0, 0, 1, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 1, 0, 0, 0, 2, 0));
    /* START_STOP_DAQ_LIST select: FIRST_PID (absolute ODT numbers) */
    EXPECT(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 0, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 1, 0), 0xFF, 2, 0, 0, 0, 0, 0, 0);
}

static void expect_ts(const wc_can_frame_t *f, uint8_t pid)
{
    WC_CHECK(f->data[0] == pid, "PID %u, expected %u", (unsigned)f->data[0], (unsigned)pid);
    WC_CHECK((f->data[1] == byte_of(rig.control_steps, 0u)) && (f->data[2] == byte_of(rig.control_steps, 1u)),
             "timestamp %u, expected the step %u", (unsigned)(f->data[1] | (f->data[2] << 8)),
             (unsigned)rig.control_steps);
}

static void test_daq_sequence_and_frames(void **state)
{
    (void)state;
    connect();
    for (uint32_t k = 0u; k < 7u; ++k) { assert_true(period(0.0f, 0.0f, MODE_OPEN)); }
    daq_configure();
    assert_int_equal(rig.xcp.odt_count, 3u);
    EXPECT(CMD(WC_XCP_GET_STATUS), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_START_STOP_SYNCH, 1), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_GET_STATUS), 0xFF, 0x40, 0, 0, 0, 0, 0, 0);  /* DAQ_RUNNING */
    /* no DAQ without a control step */
    assert_int_equal(xstep(false), 0u);

    for (uint32_t k = 1u; k <= 10u; ++k) {
        const uint32_t frames_before = rig.xcp.status.daq_frames;
        assert_true(period(1000.0f - 50.0f * (float)k, 10.0f * (float)k, MODE_TORQUE));
        const bool list1 = (k % 2u) == 0u;  /* prescaler 2 */
        assert_int_equal(rig.xn, list1 ? 3u : 2u);
        assert_int_equal(rig.xcp.status.daq_frames - frames_before, rig.xn);  /* every frame sent is counted */
        const wc_can_frame_t *f = rig.xout;
        expect_ts(&f[0], 0u);
        assert_memory_equal(&f[0].data[3], &rig.loop.last.current_mA, 4u);
        assert_int_equal(f[0].data[7], rig.loop.tx_alive);
        /* the current sampled is the one this step's VfsCommand carries (one LSB, 1/32 mA) */
        assert_true(fabsf(vfs_current_mA(&rig.out[0]) - rig.loop.last.current_mA) <= 0.5f / 32.0f);
        assert_int_equal(f[1].data[0], 1u);
        assert_memory_equal(&f[1].data[1], &rig.loop.clutch.theta_degC, 4u);  /* no timestamp after the first ODT */
        assert_memory_equal(&f[1].data[5], BYTES(0, 0, 0), 3u);
        if (list1) {
            expect_ts(&f[2], 2u);
            assert_memory_equal(&f[2].data[3], &rig.loop.counters.steps, 4u);
            assert_int_equal(f[2].data[7], byte_of(frames_before + 2u, 0u));  /* sampled after list 0's frames */
        }
        assert_int_equal(rig.xcp.status.daq_frames, frames_before + rig.xn);
    }
    assert_int_equal(rig.xcp.status.daq_samples, 15u);
    /* stop all: no more DAQ frames */
    EXPECT_OK(CMD(WC_XCP_START_STOP_SYNCH, 0));
    EXPECT(CMD(WC_XCP_GET_STATUS), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    assert_int_equal(rig.xn, 0u);
    /* START_STOP_DAQ_LIST start of list 1 alone: FIRST_PID 2, sampled at its prescaler */
    EXPECT(CMD(WC_XCP_START_STOP_DAQ_LIST, 1, 1, 0), 0xFF, 2, 0, 0, 0, 0, 0, 0);
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    assert_int_equal(rig.xn, 0u);
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    assert_int_equal(rig.xn, 1u);
    expect_ts(&rig.xout[0], 2u);
    /* DISCONNECT stops DAQ */
    EXPECT_OK(CMD(WC_XCP_DISCONNECT));
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    assert_int_equal(rig.xn, 0u);
}

static void test_daq_errors(void **state)
{
    (void)state;
    connect();
    /* allocation out of sequence: ALLOC_ODT / ALLOC_ODT_ENTRY before their predecessor, ALLOC_DAQ after ALLOC_ODT */
    EXPECT_ERR(CMD(WC_XCP_ALLOC_DAQ, 0, 1, 0), WC_XCP_ERR_SEQUENCE);  /* no FREE_DAQ yet */
    EXPECT_OK(CMD(WC_XCP_FREE_DAQ));
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT, 0, 0, 0, 1), WC_XCP_ERR_SEQUENCE);
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 0, 0, 0, 1), WC_XCP_ERR_SEQUENCE);
    /* too many lists, too many ODTs: ERR_MEMORY_OVERFLOW */
    EXPECT_ERR(CMD(WC_XCP_ALLOC_DAQ, 0, WC_XCP_DAQ_LISTS + 1u, 0), WC_XCP_ERR_MEMORY_OVERFLOW);
    EXPECT_OK(CMD(WC_XCP_ALLOC_DAQ, 0, 2, 0));
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT, 0, 0, 0, WC_XCP_ODTS + 1u), WC_XCP_ERR_MEMORY_OVERFLOW);
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT, 0, 2, 0, 1), WC_XCP_ERR_OUT_OF_RANGE);  /* list 2 of 2 */
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 0, 0, WC_XCP_ODTS - 1u));
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT, 0, 1, 0, 2), WC_XCP_ERR_MEMORY_OVERFLOW);  /* 23 + 2 > 24 */
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 1, 0, 1));
    EXPECT_ERR(CMD(WC_XCP_ALLOC_DAQ, 0, 1, 0), WC_XCP_ERR_SEQUENCE);
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 0, 0, 0, WC_XCP_ODT_ENTRIES + 1u), WC_XCP_ERR_MEMORY_OVERFLOW);
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 0, 0, 0, 2));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT_ENTRY, 0, 1, 0, 0, 1));
    EXPECT_ERR(CMD(WC_XCP_ALLOC_ODT, 0, 1, 0, 1), WC_XCP_ERR_SEQUENCE);  /* after ALLOC_ODT_ENTRY */
    /* WRITE_DAQ without SET_DAQ_PTR; a pointer past the allocation */
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(0u))), WC_XCP_ERR_SEQUENCE);
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_PTR, 0, 0, 0, 0, 2), WC_XCP_ERR_OUT_OF_RANGE);
    /* the first ODT holds 7 - 2 (timestamp) bytes: 4 + 2 is too many (ERR_DAQ_CONFIG), 4 + 1 fits */
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 0, 0, 0, 0));
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(offsetof(wc_loop_t, last.current_mA)))));
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 0xFF, 2, 0, U32(loop_address(offsetof(wc_loop_t, tx_alive)))),
               WC_XCP_ERR_DAQ_CONFIG);
    EXPECT_OK(CMD(WC_XCP_WRITE_DAQ, 0xFF, 1, 0, U32(loop_address(offsetof(wc_loop_t, tx_alive)))));
    /* an entry outside the regions, a bit offset, a size above the ODT's */
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 1, 0, 0, 0));
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(0x00005000u)), WC_XCP_ERR_ACCESS_DENIED);
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 3, 1, 0, U32(loop_address(0u))), WC_XCP_ERR_OUT_OF_RANGE);
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 0xFF, 8, 0, U32(loop_address(0u))), WC_XCP_ERR_OUT_OF_RANGE);
    /* list modes the slave has not: STIM, DTO_CTR, PID_OFF; event 1; prescaler 0 */
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x02, 1, 0, 0, 0, 1, 0), WC_XCP_ERR_MODE_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 1, 0, 1, 0, 1, 0), WC_XCP_ERR_OUT_OF_RANGE);
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 1, 0, 0, 0, 0, 0), WC_XCP_ERR_OUT_OF_RANGE);
    /* a running list cannot change: SET_DAQ_PTR, WRITE_DAQ (pointer set before the start), SET_DAQ_LIST_MODE */
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 1, 0, 0, 0));
    EXPECT_OK(CMD(WC_XCP_START_STOP_DAQ_LIST, 1, 1, 0));
    EXPECT_ERR(CMD(WC_XCP_WRITE_DAQ, 0xFF, 4, 0, U32(loop_address(0u))), WC_XCP_ERR_DAQ_ACTIVE);
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_PTR, 0, 1, 0, 0, 0), WC_XCP_ERR_DAQ_ACTIVE);
    EXPECT_ERR(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 1, 0, 0, 0, 1, 0), WC_XCP_ERR_DAQ_ACTIVE);
    EXPECT_ERR(CMD(WC_XCP_START_STOP_DAQ_LIST, 3, 1, 0), WC_XCP_ERR_MODE_NOT_VALID);
    EXPECT_ERR(CMD(WC_XCP_START_STOP_SYNCH, 3), WC_XCP_ERR_MODE_NOT_VALID);
    /* the list that is not running still can */
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_PTR, 0, 0, 0, 0, 0));
}

/* A list of more ODTs than WC_XCP_DAQ_FRAMES_PER_STEP is never sampled (never a partial list), every skipped
 * sample is counted, and each start sends one EV_DAQ_OVERLOAD; a list that fits is still sampled. */
static void test_daq_overload(void **state)
{
    (void)state;
    connect();
    EXPECT_OK(CMD(WC_XCP_FREE_DAQ));
    EXPECT_OK(CMD(WC_XCP_ALLOC_DAQ, 0, 2, 0));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 0, 0, WC_XCP_DAQ_FRAMES_PER_STEP + 1u));
    EXPECT_OK(CMD(WC_XCP_ALLOC_ODT, 0, 1, 0, 2));
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 0, 0, 0, 0, 1, 0));
    EXPECT_OK(CMD(WC_XCP_SET_DAQ_LIST_MODE, 0x10, 1, 0, 0, 0, 1, 0));
    EXPECT_OK(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 0, 0));
    EXPECT(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 1, 0), 0xFF, WC_XCP_DAQ_FRAMES_PER_STEP + 1u, 0, 0, 0, 0, 0, 0);
    for (uint32_t start = 1u; start <= 2u; ++start) {
        EXPECT_OK(CMD(WC_XCP_START_STOP_SYNCH, 1));
        for (uint32_t k = 0u; k < 5u; ++k) {
            assert_true(period(0.0f, 0.0f, MODE_OPEN));
            const uint32_t events = (k == 0u) ? 1u : 0u;
            assert_int_equal(rig.xn, 2u + events);  /* list 1's two ODTs, then the event */
            expect_ts(&rig.xout[0], WC_XCP_DAQ_FRAMES_PER_STEP + 1u);
            assert_int_equal(rig.xout[1].data[0], WC_XCP_DAQ_FRAMES_PER_STEP + 2u);
            if (events != 0u) { EXPECT(&rig.xout[2], 0xFD, WC_XCP_EV_DAQ_OVERLOAD, 0, 0, 0, 0, 0, 0); }
            assert_int_equal(rig.xcp.status.daq_overloads, 5u * (start - 1u) + k + 1u);
        }
        /* stop, select both again */
        EXPECT_OK(CMD(WC_XCP_START_STOP_SYNCH, 0));
        EXPECT_OK(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 0, 0));
        EXPECT_OK(CMD(WC_XCP_START_STOP_DAQ_LIST, 2, 1, 0));
    }
    assert_int_equal(rig.xcp.status.daq_samples, 10u);
    assert_int_equal(rig.xcp.status.daq_frames, 20u);
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
    for (uint32_t r = 0u; r < WC_XCP_REGIONS; ++r) {
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

/* ======================================================================== */
/* Calibration                                                              */
/* ======================================================================== */

/* A DOWNLOAD of holding_margin is checked with the page and used by the next wc_loop_step: the locked clutch's
 * commanded force F = i K A_p - F_s = T_req (1 + m) / c_s scales by (1 + m_new) / (1 + m_old). */
static void test_download_used_at_next_step(void **state)
{
    (void)state;
    connect();
    lock_clutch();
    const double m_old = (double)wc_table1_calibration.holding_margin;
    const float m_new = 0.5f;
    const double i_old_mA = (double)vfs_current_mA(&rig.out[0]);
    const double model_old_mA = (double)rig.loop.last.current_mA;
    EXPECT(download_f32(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, m_new, 1u), 0xFF, 0, 0, 0, 0, 0, 0, 0);
    assert_int_equal(rig.xcp.status.pages_accepted, 1u);
    assert_int_equal(rig.xcp.status.page_result, WC_CAL_IMAGE_OK);
    assert_true(wc_test_same_float(rig.loop.clutch.model.cal->holding_margin, m_new));
    assert_true(rig.loop.clutch.model.cal != &wc_table1_calibration);
    assert_true(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE) == false);  /* the twin keeps 0.2 */
    assert_true(rig.loop.clutch.lockup.locked);
    assert_true((rig.loop.last.status & WC_STATUS_SATURATED) == 0u);
    const double i_new_mA = (double)vfs_current_mA(&rig.out[0]);
    const double want = (1.0 + (double)m_new) / (1.0 + m_old);
    const double ratio = force_of_current_N(i_new_mA) / force_of_current_N(i_old_mA);
    /* Tolerance: one VfsCurrent LSB (1/32 mA) of rounding on each of the two currents, as force relative to
     * F_old, plus 1e-4 for the float arithmetic (c_s does not drift: slip 0, oil = housing = the estimate). */
    const double lsb_N = (double)wc_table1_calibration.vfs_gain_Pa_per_mA * (double)wc_table1_calibration.piston_area_m2 /
                         32.0;
    const double tol = 2.0 * lsb_N / force_of_current_N(i_old_mA) + 1e-4;
    print_message("locked at %.0f Nm: %.4f -> %.4f mA, force %.1f -> %.1f N, ratio %.6f (want %.6f, tolerance %.2g)\n",
                  (double)LOCK_TORQUE_Nm, i_old_mA, i_new_mA, force_of_current_N(i_old_mA), force_of_current_N(i_new_mA),
                  ratio, want, tol);
    WC_CHECK_CLOSE("force ratio (frame)", 0, ratio, want, tol, 0.0);
    /* the model's own currents, unrounded: the same ratio to float precision (F = i K A_p - F_s in float in the
     * inverse and here in double: a few ulp of i, F_s / F ~ 0.3 amplifies them; 1e-5) */
    const double model_ratio = force_of_current_N((double)rig.loop.last.current_mA) / force_of_current_N(model_old_mA);
    WC_CHECK_CLOSE("force ratio (model)", 0, model_ratio, want, 1e-5, 0.0);
    /* the twin (without XCP) keeps the old force */
    WC_CHECK_CLOSE("twin current", 0, (double)vfs_current_mA(&rig.twin_out[0]), i_old_mA, 1e-4, 0.0);
    /* back to the old value: the twin's frames again after the next step */
    EXPECT_OK(download_f32(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, (float)m_old, 1u));
    assert_int_equal(rig.xcp.status.pages_accepted, 2u);
    (void)period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE);
    /* the holding current is the twin's again, byte for byte (ClutchEstimate's modelled pressure still lags) */
    assert_true(same_frame(&rig.out[0], &rig.twin_out[0]));
}

typedef struct {
    const char *name;
    uint32_t offset;        /* of the float written */
    float value;            /* NaN: a quiet NaN */
    bool from_node;         /* value = factor x the page's float at offset - 4 (a film node relative to its neighbour) */
    uint32_t result;
    uint32_t error;
} bad_page_t;

static float page_f32(const uint8_t *page, uint32_t offset)
{
    float v;
    memcpy(&v, &page[offset], sizeof v);
    return v;
}

/* A page that fails the check is not used: the loop's model (calibration pointer and derived constants) and
 * configuration stay bit-identical, its frames equal the twin's, the status and one EV_USER event say why; the
 * page restored is accepted again. */
static void test_refused_pages(void **state)
{
    static const bad_page_t cases[] = {
        { "holding_margin 5.0", WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, 5.0f, false, WC_CAL_IMAGE_BAD_CLUTCH,
          WC_CAL_HOLDING_MARGIN },
        { "holding_margin NaN", WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, NAN, false, WC_CAL_IMAGE_BAD_CLUTCH,
          WC_CAL_HOLDING_MARGIN },
        { "film h_bar rising (node 3 above node 2)", WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M + 12u, 1.5f, true,
          WC_CAL_IMAGE_BAD_CLUTCH, WC_CAL_FILM_NOT_MONOTONE },
        { "film pressure axis not increasing (node 3 = node 2)", WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_PRESSURE_PA + 12u,
          1.0f, true, WC_CAL_IMAGE_BAD_CLUTCH, WC_CAL_FILM_AXIS_NOT_MONOTONE },
        { "control period 2 ms", WC_CAL_IMAGE_OFFSET_CLUTCH_CONTROL_PERIOD_S, 2e-3f, false, WC_XCP_PAGE_NOT_ONLINE,
          0u },
        { "shift_enabled 2", WC_CAL_IMAGE_OFFSET_LOOP_SHIFT_ENABLED, 0.0f, false, WC_CAL_IMAGE_BAD_LOOP,
          WC_CAL_LOOP_SHIFT_ENABLED },
        { "sync_counter 0", WC_CAL_IMAGE_OFFSET_LOOP_E2E_SYNC_COUNTER, 0.0f, false, WC_CAL_IMAGE_BAD_LOOP,
          WC_CAL_LOOP_SYNC_COUNTER },
    };
    for (size_t c = 0u; c < WC_TEST_COUNT(cases); ++c) {
        const bad_page_t *k = &cases[c];
        print_message("refused page: %s\n", k->name);
        (void)setup(state);
        connect();
        lock_clutch();
        static wc_model_t model_before;
        static wc_loop_config_t config_before;
        memcpy(&model_before, &rig.loop.clutch.model, sizeof model_before);  /* padding too: memcmp below */
        memcpy(&config_before, &rig.loop.config, sizeof config_before);
        uint8_t bytes[4];
        if (k->offset >= WC_CAL_IMAGE_LOOP_BEGIN) {  /* a u32 field: shift_enabled 2, or the value 0 */
            const uint32_t v = (k->offset == WC_CAL_IMAGE_OFFSET_LOOP_SHIFT_ENABLED) ? 2u : 0u;
            for (uint32_t i = 0u; i < 4u; ++i) { bytes[i] = byte_of(v, i); }
        } else {
            const float v = k->from_node ? k->value * page_f32(rig.reference, k->offset - 4u) : k->value;
            f32_bytes(v, bytes);
        }
        set_mta(cal_address(k->offset));
        const wc_can_frame_t *r = download_n(bytes, 4u, 2u);
        EXPECT_OK(&r[0]);
        /* EV_USER: 0xFD 0xFE, the result, the error as a word */
        EXPECT(&r[1], 0xFD, 0xFE, (uint8_t)k->result, byte_of(k->error, 0u), byte_of(k->error, 1u), 0, 0, 0);
        assert_int_equal(rig.xcp.status.page_result, k->result);
        assert_int_equal(rig.xcp.status.page_error, k->error);
        assert_int_equal(rig.xcp.status.pages_rejected, 1u);
        assert_int_equal(rig.xcp.status.pages_accepted, 0u);
        assert_memory_equal(&rig.loop.clutch.model, &model_before, sizeof model_before);
        assert_memory_equal(&rig.loop.config, &config_before, sizeof config_before);
        assert_ptr_equal(rig.loop.clutch.model.cal, &wc_table1_calibration);
        /* the refused page is not checked again (one event), and control is the twin's, byte for byte */
        for (uint32_t p = 0u; p < 5u; ++p) {
            assert_true(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE));
            assert_int_equal(rig.xn, 0u);
        }
        assert_int_equal(rig.xcp.status.pages_rejected, 1u);
        /* the bytes back: a valid page, accepted, no event; control still the twin's (the same calibration) */
        set_mta(cal_address(k->offset));
        EXPECT_OK(download_n(&rig.reference[k->offset], 4u, 1u));
        assert_int_equal(rig.xcp.status.page_result, WC_CAL_IMAGE_OK);
        assert_int_equal(rig.xcp.status.page_error, 0u);
        assert_int_equal(rig.xcp.status.pages_accepted, 1u);
        assert_true(rig.loop.clutch.model.cal != &wc_table1_calibration);
        for (uint32_t p = 0u; p < 5u; ++p) { assert_true(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE)); }
    }
}

/* SET_CAL_PAGE of the ECU access to page 1 gives the loop the reference calibration; back to page 0 the working
 * page's. The page changes at the step's check (one per wc_xcp_step). */
static void test_ecu_page_switch(void **state)
{
    (void)state;
    connect();
    lock_clutch();
    EXPECT_OK(download_f32(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, 0.5f, 1u));
    assert_false(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE));
    EXPECT_OK(CMD(WC_XCP_SET_CAL_PAGE, 0x01, 0, 1));
    assert_int_equal(rig.xcp.status.ecu_page, 1u);
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x01, 0), 0xFF, 0, 0, 1, 0, 0, 0, 0);
    EXPECT(CMD(WC_XCP_GET_CAL_PAGE, 0x02, 0), 0xFF, 0, 0, 0, 0, 0, 0, 0);  /* the XCP access stays on page 0 */
    /* the loop's calibration is table1's, value for value (film nodes included) */
    const wc_calibration_t *now = rig.loop.clutch.model.cal;
    const wc_calibration_t *t1 = &wc_table1_calibration;
    assert_memory_equal(now, t1, offsetof(wc_calibration_t, film));
    assert_int_equal(now->film.length, t1->film.length);
    assert_memory_equal(now->film.pressure_Pa, t1->film.pressure_Pa, t1->film.length * sizeof(float));
    assert_memory_equal(now->film.hbar_m, t1->film.hbar_m, t1->film.length * sizeof(float));
    assert_memory_equal(now->film.slope_m_per_Pa, t1->film.slope_m_per_Pa, t1->film.length * sizeof(float));
    assert_memory_equal((const uint8_t *)now + offsetof(wc_calibration_t, film) + sizeof t1->film,
                        (const uint8_t *)t1 + offsetof(wc_calibration_t, film) + sizeof t1->film,
                        sizeof *t1 - offsetof(wc_calibration_t, film) - sizeof t1->film);
    /* the VfsCommand is the twin's at once, byte for byte (the holding current depends on the margin, the request
     * and the temperature only); ClutchEstimate follows as the modelled pressure's lag forgets the one period */
    for (uint32_t p = 0u; p < 5u; ++p) {
        (void)period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE);
        assert_true(same_frame(&rig.out[0], &rig.twin_out[0]));
    }
    /* back on the working page: 0.5 again */
    EXPECT_OK(CMD(WC_XCP_SET_CAL_PAGE, 0x01, 0, 0));
    assert_true(wc_test_same_float(rig.loop.clutch.model.cal->holding_margin, 0.5f));
    assert_false(period(0.0f, LOCK_TORQUE_Nm, MODE_TORQUE));
    assert_int_equal(rig.xcp.status.pages_accepted, 3u);
}

/* A page prepared while the controller runs on the reference page (the tool's usual order: ECU on page 1,
 * download, ECU back on page 0) is checked once, when the controller changes to it: the downloads in between
 * check nothing. Here the shift control is switched on in the page (a valid shift calibration and
 * shift_enabled 1): refused as WC_XCP_PAGE_NOT_ONLINE with one event. */
static void test_page_prepared_offline(void **state)
{
    (void)state;
    static wc_cal_set_t with_shift;
    static uint8_t target[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
    assert_true(wc_cal_set_from(&with_shift, &wc_table1_calibration, &wc_shift_1_2_full, &rig_config));
    wc_cal_image_encode(&with_shift, target);
    wc_cal_set_t check;
    assert_int_equal(wc_cal_image_decode(target, &check).result, WC_CAL_IMAGE_OK);
    connect();
    EXPECT_OK(CMD(WC_XCP_SET_CAL_PAGE, 0x01, 0, 1));
    assert_true(period(0.0f, 0.0f, MODE_OPEN));
    const uint32_t accepted = rig.xcp.status.pages_accepted;  /* the reference page, once */
    assert_int_equal(accepted, 1u);
    set_mta(cal_address(0u));
    uint32_t downloads = 0u;
    for (uint32_t at = 0u; at < PAYLOAD; at += 6u) {
        const uint32_t n = (PAYLOAD - at < 6u) ? PAYLOAD - at : 6u;
        EXPECT_OK(download_n(&target[at], n, 1u));  /* no page event: the controller is not on this page */
        downloads++;
    }
    assert_int_equal(downloads, (PAYLOAD + 5u) / 6u);
    assert_memory_equal(rig.xcp.working_page, target, PAYLOAD);
    assert_int_equal(rig.xcp.status.pages_accepted, accepted);
    assert_int_equal(rig.xcp.status.pages_rejected, 0u);
    const wc_can_frame_t *r = command_n(BYTES(WC_XCP_SET_CAL_PAGE, 0x01, 0, 0), 4u, 2u);
    EXPECT_OK(&r[0]);
    EXPECT(&r[1], 0xFD, 0xFE, (uint8_t)WC_XCP_PAGE_NOT_ONLINE, 0, 0, 0, 0, 0);
    assert_int_equal(rig.xcp.status.page_result, WC_XCP_PAGE_NOT_ONLINE);
    assert_int_equal(rig.xcp.status.pages_rejected, 1u);
    assert_null(rig.loop.config.shift);
    for (uint32_t p = 0u; p < 3u; ++p) { assert_true(period(0.0f, 0.0f, MODE_OPEN)); }
}

/* The control frames of a loop with an XCP session (DAQ running, uploads, downloads of the values already there,
 * page copies that change nothing) are byte-identical to those of a loop without one, over an engagement. */
static void test_session_has_no_effect_on_control(void **state)
{
    (void)state;
    connect();
    daq_configure();
    EXPECT_OK(CMD(WC_XCP_START_STOP_SYNCH, 1));
    for (uint32_t k = 0u; k < 300u; ++k) {
        const float u = (float)k / 300.0f;
        const float slip_rpm = (k < 250u) ? 1500.0f * (1.0f - u * 1.2f) : 0.0f;
        const uint8_t mode = (uint8_t)((k < 30u) ? MODE_OPEN : MODE_TORQUE);
        WC_CHECK(period(slip_rpm > 0.0f ? slip_rpm : 0.0f, 200.0f * u, mode), "step %u differs", (unsigned)k);
        assert_true(rig.xn >= 2u);  /* the DAQ ran */
        switch (k % 4u) {
        case 0u:
            EXPECT_OK(download_f32(WC_CAL_IMAGE_OFFSET_CLUTCH_HOLDING_MARGIN, wc_table1_calibration.holding_margin, 1u));
            break;
        case 1u:  /* the bytes already there, at the MTA case 0 left (holding_margin + 4) */
            EXPECT_OK(download_n(&rig.reference[rig.xcp.mta - xcp_config.cal_base], 6u, 1u));
            break;
        case 2u: EXPECT_OK(CMD(WC_XCP_COPY_CAL_PAGE, 0, 1, 0, 0)); break;
        default: EXPECT_OK(CMD(WC_XCP_SHORT_UPLOAD, 7, 0, 0, U32(loop_address(offsetof(wc_loop_t, last))))); break;
        }
    }
    assert_int_equal(rig.xcp.status.pages_accepted, 0u);
    assert_int_equal(rig.xcp.status.pages_rejected, 0u);
    assert_true(rig.xcp.status.daq_samples > 300u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_connect_status_and_information, setup),
        cmocka_unit_test_setup(test_get_id_then_upload, setup),
        cmocka_unit_test_setup(test_upload_page_and_checksum, setup),
        cmocka_unit_test_setup(test_upload_measurements, setup),
        cmocka_unit_test_setup(test_calibration_page_commands, setup),
        cmocka_unit_test_setup(test_daq_sequence_and_frames, setup),
        cmocka_unit_test_setup(test_daq_errors, setup),
        cmocka_unit_test_setup(test_daq_overload, setup),
        cmocka_unit_test_setup(test_command_errors, setup),
        cmocka_unit_test_setup(test_frames_without_answer, setup),
        cmocka_unit_test_setup(test_download_used_at_next_step, setup),
        cmocka_unit_test_setup(test_refused_pages, setup),
        cmocka_unit_test_setup(test_ecu_page_switch, setup),
        cmocka_unit_test_setup(test_page_prepared_offline, setup),
        cmocka_unit_test_setup(test_session_has_no_effect_on_control, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
