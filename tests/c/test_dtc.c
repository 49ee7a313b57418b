/* Fault memory (include/wetclutch_can/wc_dtc.h, src/can/wc_dtc.c; ISO
 * 14229-1:2013 Annex D.2 status bits):
 *  - debounce: counts up and down by the steps, clamps, qualifies at the
 *    thresholds (a prefailed counter changes no bit);
 *  - the status byte bit by bit over operation cycles: first failure,
 *    pass, cycle start and end, confirmation after confirm_cycles, a
 *    tested fault-free cycle clears pending and heals the warning
 *    indicator, an untested cycle does not;
 *  - ageing after aging_cycles fault-free cycles (a failure restarts it),
 *    testFailedSinceLastClear kept;
 *  - the snapshot at first failure (not overwritten later, non-finite
 *    values stored finite), its UDS encoding (big-endian IEEE-754);
 *  - displacement by priority, testFailed and age, and overflow;
 *  - fault counters, clear (all, one, unknown), the changed flag;
 *  - image: round trip, a reordered table, corrupt and wrong-version
 *    images (empty memory, the memory-lost DTC confirmed, passed at the
 *    next cycle start), a missing image, configurations refused. */
#include "wc_test_support.h"

#include "wetclutch_can/wc_dtc.h"

enum { SENSOR, REQUEST, HOT, SLOW, LOST, LOW_A, LOW_B, LOW_C, LOW_D, LOW_E, LOW_F, LOW_G, DEFS };

/* number, fail threshold, pass threshold, fail step, pass step, confirm cycles, priority, warning */
static const wc_dtc_definition_t table[DEFS] = {
    [SENSOR] = { 0xC10000u, 3, -2, 1u, 1u, 1u, 1u, true },
    [REQUEST] = { 0xC11100u, 6, -3, 2u, 1u, 1u, 1u, false },
    [HOT] = { 0x0A1600u, 1, 0, 1u, 1u, 2u, 2u, true },
    [SLOW] = { 0x0A1700u, 1, 0, 1u, 1u, 1u, 5u, false },
    [LOST] = { 0x062F00u, 1, 0, 1u, 1u, 1u, 0u, false },
    [LOW_A] = { 0x0B0001u, 1, 0, 1u, 1u, 1u, 9u, false },
    [LOW_B] = { 0x0B0002u, 1, 0, 1u, 1u, 1u, 9u, false },
    [LOW_C] = { 0x0B0003u, 1, 0, 1u, 1u, 1u, 9u, false },
    [LOW_D] = { 0x0B0004u, 1, 0, 1u, 1u, 1u, 9u, false },
    [LOW_E] = { 0x0B0005u, 1, 0, 1u, 1u, 1u, 8u, false },
    [LOW_F] = { 0x0B0006u, 1, 0, 1u, 1u, 1u, 9u, false },
    [LOW_G] = { 0x0B0007u, 1, 0, 1u, 1u, 1u, 9u, false },
};

static wc_dtc_snapshot_t environment;
static const wc_dtc_config_t config = { table, DEFS, 3u, LOST, &environment };
static wc_dtc_t dtc;
static uint8_t image[WC_DTC_IMAGE_BYTES + 16u];

static int setup(void **state)
{
    (void)state;
    memset(&environment, 0, sizeof environment);
    assert_true(wc_dtc_init(&dtc, &config));
    wc_dtc_cycle_start(&dtc);
    return 0;
}

static void report_n(uint32_t index, bool failed, uint32_t times)
{
    for (uint32_t k = 0u; k < times; ++k) { wc_dtc_report(&dtc, index, failed); }
}

static uint8_t status(uint32_t index) { return wc_dtc_status(&dtc, index); }

/* One operation cycle: end, start. */
static void next_cycle(void)
{
    wc_dtc_cycle_end(&dtc);
    wc_dtc_cycle_start(&dtc);
}

/* ======================================================================== */

static void test_empty_memory(void **state)
{
    (void)state;
    for (uint32_t i = 0u; i < DEFS; ++i) {
        assert_int_equal(status(i), WC_DTC_TNCSLC | WC_DTC_TNCTOC);  /* 0x50 */
        assert_null(wc_dtc_snapshot(&dtc, i));
        assert_int_equal(wc_dtc_fault_count(&dtc, i), 0u);
    }
    assert_int_equal(status(DEFS), 0u);  /* beyond the table */
    assert_int_equal(wc_dtc_find(&dtc, 0x0A1600u), HOT);
    assert_int_equal(wc_dtc_find(&dtc, 0x0A1601u), WC_DTC_NONE);
    wc_dtc_report(&dtc, DEFS, true);  /* ignored */
    assert_false(wc_dtc_changed(&dtc));
}

static void test_debounce(void **state)
{
    (void)state;
    /* REQUEST: +2 a failure, -1 a pass, failed at 6, passed at -3 */
    report_n(REQUEST, true, 2u);  /* 4: prefailed, no bit */
    assert_int_equal(status(REQUEST), 0x50u);
    report_n(REQUEST, false, 1u);  /* 3 */
    report_n(REQUEST, true, 1u);   /* 5 */
    assert_int_equal(status(REQUEST), 0x50u);
    assert_false(wc_dtc_changed(&dtc));
    report_n(REQUEST, true, 1u);   /* 6: failed */
    assert_int_equal(status(REQUEST), WC_DTC_TF | WC_DTC_TFTOC | WC_DTC_PENDING | WC_DTC_CONFIRMED | WC_DTC_TFSLC);
    assert_true(wc_dtc_changed(&dtc));
    report_n(REQUEST, true, 50u);  /* clamps at 6 */
    assert_int_equal(dtc.state[REQUEST].debounce, 6);
    report_n(REQUEST, false, 8u);  /* 6 -> -2: still failed */
    assert_true((status(REQUEST) & WC_DTC_TF) != 0u);
    report_n(REQUEST, false, 1u);  /* -3: passed */
    assert_int_equal(status(REQUEST), WC_DTC_TFTOC | WC_DTC_PENDING | WC_DTC_CONFIRMED | WC_DTC_TFSLC);
    report_n(REQUEST, false, 20u);  /* clamps at -3 */
    assert_int_equal(dtc.state[REQUEST].debounce, -3);
    /* a passed test of a fresh DTC: only the not-completed bits go */
    report_n(SLOW, false, 1u);
    assert_int_equal(status(SLOW), 0x00u);
}

static void test_status_over_operation_cycles(void **state)
{
    (void)state;
    /* SENSOR: confirm at the first failing cycle, warning indicator */
    report_n(SENSOR, true, 3u);
    assert_int_equal(status(SENSOR), 0xAFu);  /* WIR TFSLC CDTC PDTC TFTOC TF */
    assert_int_equal(wc_dtc_fault_count(&dtc, SENSOR), 1u);
    report_n(SENSOR, false, 4u);  /* 3 -> -1: still failed */
    assert_int_equal(status(SENSOR), 0xAFu);
    report_n(SENSOR, false, 1u);  /* -2: passed */
    assert_int_equal(status(SENSOR), 0xAEu);
    next_cycle();  /* failed in the cycle: pending stays, TFTOC goes, TNCTOC comes */
    assert_int_equal(status(SENSOR), WC_DTC_WIR | WC_DTC_TNCTOC | WC_DTC_TFSLC | WC_DTC_CONFIRMED | WC_DTC_PENDING);
    next_cycle();  /* not tested: nothing heals */
    assert_int_equal(status(SENSOR), 0xECu);
    report_n(SENSOR, false, 2u);  /* tested, passed */
    assert_int_equal(status(SENSOR), 0xACu);
    next_cycle();  /* a tested fault-free cycle: not pending, warning healed; confirmed until ageing */
    assert_int_equal(status(SENSOR), WC_DTC_TNCTOC | WC_DTC_TFSLC | WC_DTC_CONFIRMED);
    report_n(SENSOR, true, 3u);  /* again: a second fault, the lamp again */
    assert_int_equal(status(SENSOR), 0xAFu);
    assert_int_equal(wc_dtc_fault_count(&dtc, SENSOR), 2u);
    report_n(SENSOR, false, 5u);
    report_n(SENSOR, true, 5u);
    assert_int_equal(wc_dtc_fault_count(&dtc, SENSOR), 3u);  /* every testFailed 0 -> 1 */

    /* HOT: two cycles with a failure until confirmed */
    report_n(HOT, true, 1u);
    assert_int_equal(status(HOT), WC_DTC_TF | WC_DTC_TFTOC | WC_DTC_PENDING | WC_DTC_TFSLC);
    report_n(HOT, false, 1u);
    next_cycle();
    report_n(HOT, false, 1u);
    next_cycle();  /* a tested fault-free cycle restarts the confirmation count */
    assert_int_equal(status(HOT), WC_DTC_TNCTOC | WC_DTC_TFSLC);
    report_n(HOT, true, 1u);
    assert_true((status(HOT) & WC_DTC_CONFIRMED) == 0u);
    next_cycle();  /* untested cycle in between: the count holds */
    next_cycle();
    report_n(HOT, true, 1u);
    assert_int_equal(status(HOT), WC_DTC_WIR | WC_DTC_TFSLC | WC_DTC_CONFIRMED | WC_DTC_PENDING | WC_DTC_TFTOC |
                                      WC_DTC_TF);
}

static void test_ageing(void **state)
{
    (void)state;
    report_n(SLOW, true, 1u);
    report_n(SLOW, false, 1u);
    assert_non_null(wc_dtc_snapshot(&dtc, SLOW));
    next_cycle();  /* failed this cycle: no ageing */
    assert_int_equal(dtc.state[SLOW].aging_cycles, 0u);
    next_cycle();
    next_cycle();  /* two fault-free cycles */
    assert_int_equal(dtc.state[SLOW].aging_cycles, 2u);
    report_n(SLOW, true, 1u);  /* a failure restarts the count */
    report_n(SLOW, false, 1u);
    assert_int_equal(dtc.state[SLOW].aging_cycles, 0u);
    next_cycle();
    next_cycle();
    next_cycle();
    assert_true((status(SLOW) & WC_DTC_CONFIRMED) != 0u);  /* 2 fault-free cycles of 3 */
    assert_non_null(wc_dtc_snapshot(&dtc, SLOW));
    next_cycle();  /* the third: aged out */
    assert_int_equal(status(SLOW), WC_DTC_TNCTOC | WC_DTC_TFSLC);  /* the history of the fault stays */
    assert_null(wc_dtc_snapshot(&dtc, SLOW));
    assert_int_equal(dtc.state[SLOW].aging_cycles, 0u);
    assert_int_equal(wc_dtc_fault_count(&dtc, SLOW), 2u);
    /* a DTC that is still testFailed (never passed again) does not age */
    report_n(SENSOR, true, 3u);
    for (uint32_t k = 0u; k < 10u; ++k) { next_cycle(); }
    assert_true((status(SENSOR) & WC_DTC_CONFIRMED) != 0u);
    assert_non_null(wc_dtc_snapshot(&dtc, SENSOR));
}

static void test_snapshot_at_first_failure(void **state)
{
    (void)state;
    environment = (wc_dtc_snapshot_t){ 150.0f, 200.0f, 250.0f, 120.5f, 80.0f, 60.0f, 900.0f, 100.0f, 3u, 2u };
    report_n(HOT, true, 1u);
    environment.slip_speed_rad_s = 999.0f;  /* a later failure keeps the first snapshot */
    report_n(HOT, false, 1u);
    report_n(HOT, true, 1u);
    const wc_dtc_snapshot_t *s = wc_dtc_snapshot(&dtc, HOT);
    assert_non_null(s);
    assert_true(wc_test_same_float(s->slip_speed_rad_s, 150.0f));
    assert_true(wc_test_same_float(s->theta_clutch_degC, 120.5f));
    assert_true(wc_test_same_float(s->current_offgoing_mA, 100.0f));
    assert_int_equal(s->shift_phase, 3u);
    assert_int_equal(s->gear, 2u);
    /* UDS form: big-endian IEEE-754 (150.0f = 0x43160000), then phase and gear */
    uint8_t bytes[WC_DTC_SNAPSHOT_BYTES];
    wc_dtc_snapshot_encode(s, bytes);
    assert_memory_equal(bytes, ((const uint8_t[]){ 0x43, 0x16, 0x00, 0x00, 0x43, 0x48, 0x00, 0x00 }), 8u);
    assert_memory_equal(&bytes[12], ((const uint8_t[]){ 0x42, 0xF1, 0x00, 0x00 }), 4u);  /* 120.5 */
    assert_int_equal(bytes[32], 3u);
    assert_int_equal(bytes[33], 2u);
    /* non-finite inputs are stored finite */
    environment.slip_speed_rad_s = NAN;
    environment.output_speed_rad_s = INFINITY;
    environment.turbine_speed_rad_s = -INFINITY;
    report_n(SLOW, true, 1u);
    s = wc_dtc_snapshot(&dtc, SLOW);
    assert_non_null(s);
    assert_true(wc_test_same_float(s->slip_speed_rad_s, 0.0f));
    assert_true(wc_test_same_float(s->output_speed_rad_s, FLT_MAX));
    assert_true(wc_test_same_float(s->turbine_speed_rad_s, -FLT_MAX));
    /* without an environment: zeros */
    wc_dtc_config_t bare = config;
    bare.environment = NULL;
    assert_true(wc_dtc_init(&dtc, &bare));
    report_n(SLOW, true, 1u);
    s = wc_dtc_snapshot(&dtc, SLOW);
    assert_non_null(s);
    assert_true(wc_test_same_float(s->theta_oil_degC, 0.0f));
}

/* Every entry taken: the rule of wc_dtc.h decides which one goes. */
static void test_displacement(void **state)
{
    (void)state;
    assert_int_equal(WC_DTC_MAX_ENTRIES, 8u);
    const uint32_t order[8] = { LOW_A, LOW_B, LOW_C, LOW_D, LOW_E, LOW_F, SENSOR, REQUEST };
    for (uint32_t k = 0u; k < 8u; ++k) {
        environment.gear = (uint8_t)k;
        report_n(order[k], true, 6u);
    }
    report_n(LOW_B, false, 1u);  /* LOW_B passes again: no longer testFailed */
    report_n(LOW_C, false, 1u);
    /* SLOW (priority 5): the entries of priority >= 5 not failing now (LOW_B, LOW_C), the oldest: LOW_B */
    report_n(SLOW, true, 1u);
    assert_non_null(wc_dtc_snapshot(&dtc, SLOW));
    assert_null(wc_dtc_snapshot(&dtc, LOW_B));
    assert_int_equal(status(LOW_B) & (WC_DTC_CONFIRMED | WC_DTC_TF), 0u);  /* it loses confirmedDTC */
    assert_true((status(LOW_B) & WC_DTC_TFSLC) != 0u);
    /* HOT (2): LOW_C (not failing) */
    report_n(HOT, true, 1u);
    assert_null(wc_dtc_snapshot(&dtc, LOW_C));
    /* LOW_G (9): all failing now; among priority >= 9 (LOW_A, LOW_D, LOW_F) the oldest: LOW_A */
    report_n(LOW_G, true, 1u);
    assert_null(wc_dtc_snapshot(&dtc, LOW_A));
    assert_non_null(wc_dtc_snapshot(&dtc, LOW_E));  /* priority 8: more important than LOW_G */
    /* LOST (0): the largest priority number first: 9 (LOW_D, LOW_F, LOW_G) before LOW_E's 8; the oldest LOW_D */
    report_n(LOST, true, 1u);
    assert_null(wc_dtc_snapshot(&dtc, LOW_D));
    assert_non_null(wc_dtc_snapshot(&dtc, LOW_F));
    assert_int_equal(dtc.overflows, 0u);
    /* entries now: LOW_E 8, LOW_F 9, SENSOR 1, REQUEST 1, SLOW 5, HOT 2, LOW_G 9, LOST 0; LOW_A (9) fails again:
     * LOW_F and LOW_G (9, failing, LOW_F older) */
    report_n(LOW_A, true, 1u);
    assert_null(wc_dtc_snapshot(&dtc, LOW_F));
    assert_non_null(wc_dtc_snapshot(&dtc, LOW_A));
    uint32_t stored = 0u;
    for (uint32_t i = 0u; i < DEFS; ++i) { stored += (wc_dtc_snapshot(&dtc, i) != NULL) ? 1u : 0u; }
    assert_int_equal(stored, WC_DTC_MAX_ENTRIES);
}

/* Every entry held by a more important DTC: the new one is not stored, its status kept. */
static void test_overflow(void **state)
{
    (void)state;
    static wc_dtc_definition_t important[WC_DTC_MAX_ENTRIES + 1u];
    for (uint32_t i = 0u; i <= WC_DTC_MAX_ENTRIES; ++i) {
        const uint8_t priority = (uint8_t)((i < WC_DTC_MAX_ENTRIES) ? 0u : 1u);
        important[i] = (wc_dtc_definition_t){ 0x100000u + i, 1, 0, 1u, 1u, 1u, priority, false };
    }
    const wc_dtc_config_t c = { important, WC_DTC_MAX_ENTRIES + 1u, 3u, WC_DTC_NONE, NULL };
    assert_true(wc_dtc_init(&dtc, &c));
    wc_dtc_cycle_start(&dtc);
    for (uint32_t i = 0u; i <= WC_DTC_MAX_ENTRIES; ++i) { wc_dtc_report(&dtc, i, true); }
    assert_null(wc_dtc_snapshot(&dtc, WC_DTC_MAX_ENTRIES));
    assert_int_equal(dtc.overflows, 1u);
    assert_int_equal(wc_dtc_status(&dtc, WC_DTC_MAX_ENTRIES), 0x2Fu);
    for (uint32_t i = 0u; i < WC_DTC_MAX_ENTRIES; ++i) { assert_non_null(wc_dtc_snapshot(&dtc, i)); }
}

static void test_clear(void **state)
{
    (void)state;
    report_n(SENSOR, true, 3u);
    report_n(SLOW, true, 1u);
    uint8_t buffer[WC_DTC_IMAGE_BYTES];
    assert_int_equal(wc_dtc_image_write(&dtc, buffer, sizeof buffer), WC_DTC_IMAGE_BYTES);
    assert_false(wc_dtc_changed(&dtc));
    assert_false(wc_dtc_clear(&dtc, 0x123456u));  /* no such DTC or group */
    assert_false(wc_dtc_changed(&dtc));
    assert_true(wc_dtc_clear(&dtc, table[SLOW].number));
    assert_true(wc_dtc_changed(&dtc));
    assert_int_equal(status(SLOW), 0x50u);
    assert_null(wc_dtc_snapshot(&dtc, SLOW));
    assert_int_equal(wc_dtc_fault_count(&dtc, SLOW), 0u);
    assert_int_equal(status(SENSOR), 0xAFu);
    assert_true(wc_dtc_clear(&dtc, WC_DTC_GROUP_ALL));
    for (uint32_t i = 0u; i < DEFS; ++i) {
        assert_int_equal(status(i), 0x50u);
        assert_null(wc_dtc_snapshot(&dtc, i));
        assert_int_equal(wc_dtc_fault_count(&dtc, i), 0u);
    }
    report_n(SENSOR, true, 1u);  /* the debounce restarted at 0: 1 of 3 */
    assert_int_equal(status(SENSOR), 0x50u);
}

static void fill_some(void)
{
    environment = (wc_dtc_snapshot_t){ -12.5f, 300.0f, 310.0f, 95.0f, 70.0f, 65.0f, 450.0f, 20.0f, 4u, 1u };
    report_n(SENSOR, true, 3u);
    report_n(HOT, true, 1u);
    report_n(HOT, false, 1u);
    next_cycle();
    report_n(SLOW, true, 1u);
    report_n(SLOW, false, 1u);
    report_n(REQUEST, false, 3u);
    next_cycle();  /* HOT passed and did not fail again: one cycle toward ageing */
    assert_int_equal(dtc.state[HOT].aging_cycles, 1u);
}

static void expect_same_memory(const wc_dtc_t *a, const wc_dtc_t *b, uint32_t count)
{
    for (uint32_t i = 0u; i < count; ++i) {
        const uint32_t j = wc_dtc_find(b, a->config.definitions[i].number);
        assert_int_not_equal(j, WC_DTC_NONE);
        assert_int_equal(wc_dtc_status(a, i), wc_dtc_status(b, j));
        assert_int_equal(wc_dtc_fault_count(a, i), wc_dtc_fault_count(b, j));
        assert_int_equal(a->state[i].failed_cycles, b->state[j].failed_cycles);
        assert_int_equal(a->state[i].aging_cycles, b->state[j].aging_cycles);
        const wc_dtc_snapshot_t *sa = wc_dtc_snapshot(a, i);
        const wc_dtc_snapshot_t *sb = wc_dtc_snapshot(b, j);
        assert_int_equal(sa == NULL, sb == NULL);
        if (sa != NULL) {
            uint8_t ea[WC_DTC_SNAPSHOT_BYTES];
            uint8_t eb[WC_DTC_SNAPSHOT_BYTES];
            wc_dtc_snapshot_encode(sa, ea);
            wc_dtc_snapshot_encode(sb, eb);
            assert_memory_equal(ea, eb, sizeof ea);
        }
    }
}

static void test_image_round_trip(void **state)
{
    (void)state;
    fill_some();
    assert_true(wc_dtc_changed(&dtc));
    assert_int_equal(wc_dtc_image_write(&dtc, image, WC_DTC_IMAGE_BYTES - 1u), 0u);  /* too small */
    assert_true(wc_dtc_changed(&dtc));
    assert_int_equal(wc_dtc_image_write(&dtc, image, sizeof image), WC_DTC_IMAGE_BYTES);
    assert_false(wc_dtc_changed(&dtc));
    /* the same bytes as the image format writes them (wc_image.h) */
    const uint8_t *payload = NULL;
    assert_int_equal(wc_image_read(image, WC_DTC_IMAGE_BYTES, WC_DTC_IMAGE_MAGIC, WC_DTC_IMAGE_VERSION,
                                   WC_DTC_IMAGE_PAYLOAD_BYTES, &payload),
                     WC_IMAGE_OK);
    assert_int_equal(wc_image_get_u32(&payload[8]), table[0].number);
    static wc_dtc_t restored;
    assert_true(wc_dtc_init(&restored, &config));
    assert_int_equal(wc_dtc_image_load(&restored, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_OK);
    assert_false(wc_dtc_changed(&restored));
    expect_same_memory(&dtc, &restored, DEFS);
    /* a later firmware with the table reordered and a DTC dropped keeps the history by number */
    static wc_dtc_definition_t reordered[DEFS - 1u];
    for (uint32_t i = 0u; i + 1u < DEFS; ++i) { reordered[i] = table[DEFS - 1u - i]; }  /* SENSOR dropped */
    const wc_dtc_config_t c = { reordered, DEFS - 1u, 3u, WC_DTC_NONE, NULL };
    assert_true(wc_dtc_init(&restored, &c));
    assert_int_equal(wc_dtc_image_load(&restored, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_OK);
    expect_same_memory(&restored, &dtc, DEFS - 1u);
    assert_int_equal(wc_dtc_find(&restored, table[SENSOR].number), WC_DTC_NONE);
    /* and goes on counting from there */
    wc_dtc_cycle_end(&restored);
    assert_true(wc_dtc_changed(&restored));
}

static void test_corrupt_image_loses_the_memory(void **state)
{
    (void)state;
    fill_some();
    assert_int_equal(wc_dtc_image_write(&dtc, image, sizeof image), WC_DTC_IMAGE_BYTES);
    image[40] ^= 0x01u;  /* one bit in the payload */
    environment.gear = 7u;
    assert_int_equal(wc_dtc_image_load(&dtc, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_BAD_CRC);
    for (uint32_t i = 0u; i < DEFS; ++i) {
        if (i != LOST) { assert_int_equal(status(i), 0x50u); }
    }
    assert_int_equal(status(LOST), 0x2Fu);  /* failed, confirmed, stored */
    assert_non_null(wc_dtc_snapshot(&dtc, LOST));
    assert_int_equal(wc_dtc_snapshot(&dtc, LOST)->gear, 7u);
    assert_true(wc_dtc_changed(&dtc));  /* the empty memory is to be written */
    wc_dtc_cycle_start(&dtc);  /* the next cycle: the memory is whole again */
    assert_int_equal(status(LOST), WC_DTC_TFSLC | WC_DTC_CONFIRMED | WC_DTC_PENDING);
    next_cycle();
    next_cycle();
    next_cycle();
    next_cycle();  /* ... and ages out like any other */
    assert_int_equal(status(LOST) & WC_DTC_CONFIRMED, 0u);

    /* another layout version */
    image[40] ^= 0x01u;
    wc_image_put_u32(&image[4], WC_DTC_IMAGE_VERSION + 1u);
    assert_int_equal(wc_dtc_image_load(&dtc, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_BAD_VERSION);
    assert_int_equal(status(LOST), 0x2Fu);
    assert_int_equal(status(SENSOR), 0x50u);
    /* truncated */
    wc_image_put_u32(&image[4], WC_DTC_IMAGE_VERSION);
    assert_int_equal(wc_dtc_image_load(&dtc, image, WC_DTC_IMAGE_BYTES - 1u), WC_IMAGE_TRUNCATED);
    assert_int_equal(status(LOST), 0x2Fu);
    /* the repaired image is whole */
    assert_int_equal(wc_dtc_image_load(&dtc, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_OK);
    assert_int_equal(status(LOST), 0x50u);
    assert_true((status(SENSOR) & WC_DTC_CONFIRMED) != 0u);
    /* no image at all (an erased store, the first start): empty, no DTC */
    assert_int_equal(wc_dtc_image_load(&dtc, NULL, 0u), WC_IMAGE_MISSING);
    for (uint32_t i = 0u; i < DEFS; ++i) { assert_int_equal(status(i), 0x50u); }
    assert_false(wc_dtc_changed(&dtc));
    /* without a memory-lost DTC: just empty */
    wc_dtc_config_t c = config;
    c.memory_lost = WC_DTC_NONE;
    assert_true(wc_dtc_init(&dtc, &c));
    image[40] ^= 0x01u;
    assert_int_equal(wc_dtc_image_load(&dtc, image, WC_DTC_IMAGE_BYTES), WC_IMAGE_BAD_CRC);
    for (uint32_t i = 0u; i < DEFS; ++i) { assert_int_equal(status(i), 0x50u); }
}

static void test_init_refuses_bad_configurations(void **state)
{
    (void)state;
    static wc_dtc_definition_t d[2];
    d[0] = table[SENSOR];
    d[1] = table[HOT];
    wc_dtc_config_t c = { d, 2u, 3u, WC_DTC_NONE, NULL };
    assert_true(wc_dtc_init(&dtc, &c));
    c.count = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.count = WC_DTC_MAX_DEFINITIONS + 1u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.count = 2u;
    c.aging_cycles = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.aging_cycles = 256u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.aging_cycles = 3u;
    c.memory_lost = 2u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.memory_lost = WC_DTC_NONE;
    const wc_dtc_definition_t good = d[1];
    d[1].number = d[0].number;  /* twice */
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].number = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].number = WC_DTC_GROUP_ALL;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].fail_threshold = 0;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].pass_threshold = 1;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].fail_step = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].pass_step = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    d[1] = good; d[1].confirm_cycles = 0u;
    assert_false(wc_dtc_init(&dtc, &c));
    c.definitions = NULL;
    assert_false(wc_dtc_init(&dtc, &c));
    assert_false(dtc.initialised);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_empty_memory, setup),
        cmocka_unit_test_setup(test_debounce, setup),
        cmocka_unit_test_setup(test_status_over_operation_cycles, setup),
        cmocka_unit_test_setup(test_ageing, setup),
        cmocka_unit_test_setup(test_snapshot_at_first_failure, setup),
        cmocka_unit_test_setup(test_displacement, setup),
        cmocka_unit_test_setup(test_overflow, setup),
        cmocka_unit_test_setup(test_clear, setup),
        cmocka_unit_test_setup(test_image_round_trip, setup),
        cmocka_unit_test_setup(test_corrupt_image_loses_the_memory, setup),
        cmocka_unit_test_setup(test_init_refuses_bad_configurations, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
