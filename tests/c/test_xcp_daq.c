/* The XCP on CAN slave's DAQ (include/wetclutch_can/wc_xcp.h,
 * src/can/wc_xcp.c; DESIGN 13) over a running frame loop with the table1
 * calibration:
 *  - the dynamic DAQ sequence and the DAQ frames: PIDs, the 2-byte step
 *    timestamp and the loop's values at that step;
 *  - DAQ's error classes (SEQUENCE, MEMORY_OVERFLOW, DAQ_CONFIG, DAQ_ACTIVE,
 *    MODE_NOT_VALID) and the overload of a list that does not fit a step;
 *  - the control frames of a loop with an XCP session (DAQ running, uploads,
 *    downloads that change nothing) byte-identical to those of a loop
 *    without one.
 * The rig and its twin loop: wc_test_xcp_harness.h. */
#include "wc_test_xcp_harness.h"

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
        cmocka_unit_test_setup(test_daq_sequence_and_frames, setup),
        cmocka_unit_test_setup(test_daq_errors, setup),
        cmocka_unit_test_setup(test_daq_overload, setup),
        cmocka_unit_test_setup(test_session_has_no_effect_on_control, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
