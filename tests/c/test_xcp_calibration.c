/* Calibration through the XCP on CAN slave (include/wetclutch_can/wc_xcp.h,
 * src/can/wc_xcp.c; DESIGN 13) over a running frame loop with the table1
 * calibration: a DOWNLOAD of holding_margin used by the next step (the
 * locked clutch's force scales as 1 + margin), refused pages (the loop's
 * calibration and outputs bit-identical to a twin loop without XCP, the
 * status and one EV_USER event), the reference page back by SET_CAL_PAGE,
 * a page prepared while the controller runs on the reference page.
 * The rig and its twin loop: wc_test_xcp_harness.h. */
#include "wc_test_xcp_harness.h"

#include "wc_shift_1_2_shift.h"

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_download_used_at_next_step, setup),
        cmocka_unit_test_setup(test_refused_pages, setup),
        cmocka_unit_test_setup(test_ecu_page_switch, setup),
        cmocka_unit_test_setup(test_page_prepared_offline, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
