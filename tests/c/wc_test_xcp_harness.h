/* The shared part of the XCP on CAN slave's tests (include/wetclutch_can/wc_xcp.h,
 * src/can/wc_xcp.c; DESIGN 13): test_xcp_commands.c, test_xcp_daq.c,
 * test_xcp_calibration.c. Include it instead of wc_test_support.h; it
 * includes lut/wc_table1_calibration.h (one translation unit per test program).
 *
 * The rig: a frame loop with the table1 calibration and a slave on it, and a
 * twin loop fed the same frames without XCP, so "no effect on control" is a
 * byte comparison (period()). Commands are built byte by byte (CMD, BYTES)
 * and every response is checked byte by byte (EXPECT, EXPECT_OK, EXPECT_ERR)
 * against the layouts of ASAM MCD-1 XCP part 2. */
#ifndef WC_TEST_XCP_HARNESS_H
#define WC_TEST_XCP_HARNESS_H

#include "wc_test_support.h"

#include "generated/wc_cal_image_layout.h"
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
static const wc_loop_config_t rig_config = { 10u, 10u, { 2u, 3u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u };
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

static inline int setup(void **state)
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

static inline wc_can_frame_t xcp_frame(const uint8_t *bytes, uint32_t dlc)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = WC_CAN_XCP_COMMAND_FRAME_ID;
    f.dlc = (uint8_t)dlc;
    for (uint32_t i = 0u; (i < dlc) && (i < 8u); ++i) { f.data[i] = bytes[i]; }
    return f;
}

static inline void queue_frame(const wc_can_frame_t *f) { assert_true(wc_xcp_receive(&rig.xcp, f)); }

/* One wc_xcp_step; every frame it returns is an XcpResponse of DLC 8 without flags. */
static inline uint32_t xstep(bool control_step)
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
static inline const wc_can_frame_t *command_n(const uint8_t *bytes, uint32_t dlc, uint32_t frames)
{
    const wc_can_frame_t f = xcp_frame(bytes, dlc);
    queue_frame(&f);
    const uint32_t n = xstep(false);
    WC_CHECK(n == frames, "command 0x%02x: %u frames, expected %u", (unsigned)bytes[0], (unsigned)n, (unsigned)frames);
    return &rig.xout[0];
}

static inline const wc_can_frame_t *command(const uint8_t *bytes, uint32_t dlc) { return command_n(bytes, dlc, 1u); }

#define BYTES(...) ((const uint8_t[]){ __VA_ARGS__ })
#define CMD(...) command(BYTES(__VA_ARGS__), (uint32_t)sizeof(BYTES(__VA_ARGS__)))

static inline void expect_bytes(const wc_can_frame_t *f, const uint8_t want[8], int line)
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

static inline void expect_ok(const wc_can_frame_t *f, int line)
{
    if (f->data[0] != WC_XCP_PID_RES) {
        print_error("line %d: PID 0x%02x (error 0x%02x), expected a positive response\n", line, f->data[0], f->data[1]);
        fail();
    }
}
#define EXPECT_OK(frame) expect_ok((frame), __LINE__)

/* An error packet: PID 0xFE, the code, the rest 0 (ERR_OUT_OF_RANGE of BUILD_CHECKSUM aside). */
static inline void expect_error(const wc_can_frame_t *f, uint8_t code, int line)
{
    expect_bytes(f, BYTES(WC_XCP_PID_ERR, code, 0, 0, 0, 0, 0, 0), line);
}
#define EXPECT_ERR(frame, code) expect_error((frame), (code), __LINE__)

static inline uint8_t byte_of(uint32_t value, uint32_t i) { return (uint8_t)((value >> (8u * i)) & 0xFFu); }

#define U32(v) byte_of((v), 0u), byte_of((v), 1u), byte_of((v), 2u), byte_of((v), 3u)

static inline void connect(void)
{
    EXPECT(CMD(WC_XCP_CONNECT, 0), 0xFF, 0x05, 0x80, 8, 8, 0, 1, 1);
}

static inline void set_mta(uint32_t address)
{
    EXPECT(CMD(WC_XCP_SET_MTA, 0, 0, 0, U32(address)), 0xFF, 0, 0, 0, 0, 0, 0, 0);
}

/* DOWNLOAD of n bytes at the MTA: the response (and, after it, a page event if expected). */
static inline const wc_can_frame_t *download_n(const uint8_t *data, uint32_t n, uint32_t frames)
{
    assert_true(n <= 6u);
    uint8_t cmd[8] = { WC_XCP_DOWNLOAD, (uint8_t)n, 0, 0, 0, 0, 0, 0 };
    for (uint32_t i = 0u; i < n; ++i) { cmd[2u + i] = data[i]; }
    return command_n(cmd, 2u + n, frames);
}

static inline uint32_t cal_address(uint32_t offset) { return xcp_config.cal_base + offset; }
static inline uint32_t loop_address(size_t offset) { return xcp_config.loop_base + (uint32_t)offset; }

static inline void f32_bytes(float value, uint8_t out[4])
{
    uint32_t w;
    memcpy(&w, &value, sizeof w);
    for (uint32_t i = 0u; i < 4u; ++i) { out[i] = byte_of(w, i); }
}

/* A float of the working page written by SET_MTA + DOWNLOAD; frames: 1, or 2 with a page event. */
static inline const wc_can_frame_t *download_f32(uint32_t offset, float value, uint32_t frames)
{
    set_mta(cal_address(offset));
    uint8_t b[4];
    f32_bytes(value, b);
    return download_n(b, 4u, frames);
}

/* n bytes from address by SET_MTA and UPLOADs of at most 7 (the slave's MAX_CTO - 1). */
static inline void upload(uint32_t address, uint8_t *out, uint32_t n)
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

static inline void queue_period_frames(wc_loop_t *loop, float slip_rpm, float torque_Nm, uint8_t mode, uint8_t alive)
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

static inline bool same_frame(const wc_can_frame_t *a, const wc_can_frame_t *b)
{
    return (a->id == b->id) && (a->dlc == b->dlc) && (a->flags == b->flags) && (memcmp(a->data, b->data, 8u) == 0);
}

/* One control period of both loops (the slave's loop first, then its
 * wc_xcp_step as wc_tcu runs it: after the step's frames). Returns whether
 * the two loops' frames are byte-identical. */
static inline bool period(float slip_rpm, float torque_Nm, uint8_t mode)
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

static inline float vfs_current_mA(const wc_can_frame_t *f)
{
    wc_can_vfs_command_phys_t cmd;
    assert_false(wc_can_is_error(wc_can_decode_vfs_command(&cmd, f->data, f->dlc)));
    return cmd.vfs_current_mA;
}

/* The commanded contact force of a current: F = i K A_p - F_s (the inverse's P = (F + F_s) / A_p, i = P / K). */
static inline double force_of_current_N(double current_mA)
{
    const wc_calibration_t *cal = &wc_table1_calibration;
    return current_mA * (double)cal->vfs_gain_Pa_per_mA * (double)cal->piston_area_m2 - (double)cal->return_spring_force_N;
}

/* Torque control at zero slip until the clutch is locked (DESIGN 9), the outputs equal to the twin's. */
static inline void lock_clutch(void)
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

#endif /* WC_TEST_XCP_HARNESS_H */
