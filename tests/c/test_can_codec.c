/* cmocka tests of the CAN codec: the generated pack/unpack
 * (src/can/generated/wc_can.c), the scaling wrapper (src/can/wc_can_scaling.c)
 * and the E2E protection (src/can/wc_e2e.c). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <string.h>

#include "wetclutch_can/wc_can_signals.h"
#include "wetclutch_can/wc_e2e.h"

#define FRAME_BYTES 8u

/* Half of one raw step, in physical units. */
static float half_step(const wc_can_signal_t *sig)
{
    return 0.5f * sig->scale;
}

static int32_t raw_of(const wc_can_signal_t *sig, float value,
                      wc_can_result_t expected_result)
{
    int32_t raw = 0x7EADBEEF;

    assert_int_equal(wc_can_phys_to_raw(sig, value, &raw), expected_result);
    return raw;
}

/* ---- CRC-8 SAE J1850 ----------------------------------------------------- */

/* CRC-8 SAE J1850 by its definition: eight conditional shifts a byte
 * (polynomial 0x1D, init 0xFF, xor-out 0xFF, not reflected). The library
 * uses a nibble table; every single byte after every register value, and
 * a pseudo-random message, must agree. */
static uint8_t crc8_bitwise(const uint8_t *data, size_t len)
{
    uint8_t reg = 0xFFu;
    for (size_t i = 0u; i < len; ++i) {
        reg = (uint8_t)(reg ^ data[i]);
        for (unsigned bit = 0u; bit < 8u; ++bit) {
            reg = (uint8_t)(((reg & 0x80u) != 0u) ? (((unsigned)reg << 1) ^ 0x1Du) : ((unsigned)reg << 1));
        }
    }
    return (uint8_t)(reg ^ 0xFFu);
}

static void test_crc8_table_matches_bitwise(void **state)
{
    (void)state;
    uint8_t two[2];
    for (unsigned a = 0u; a < 256u; ++a) {
        for (unsigned b = 0u; b < 256u; ++b) {
            two[0] = (uint8_t)a;
            two[1] = (uint8_t)b;
            assert_int_equal(wc_e2e_crc8_j1850(two, 2u), crc8_bitwise(two, 2u));
        }
    }
    uint8_t message[64];
    uint32_t x = 12345u;
    for (size_t i = 0u; i < sizeof message; ++i) {
        x = x * 1103515245u + 12345u;
        message[i] = (uint8_t)(x >> 24);
    }
    for (size_t len = 0u; len <= sizeof message; ++len) {
        assert_int_equal(wc_e2e_crc8_j1850(message, len), crc8_bitwise(message, len));
    }
}

static void test_crc8_autosar_vectors(void **state)
{
    /* AUTOSAR SWS CRC Library, Crc_CalculateCRC8 (SAE J1850) check values. */
    static const struct {
        uint8_t data[9];
        size_t len;
        uint8_t crc;
    } vectors[] = {
        {{0x00, 0x00, 0x00, 0x00}, 4u, 0x59u},
        {{0xF2, 0x01, 0x83}, 3u, 0x37u},
        {{0x0F, 0xAA, 0x00, 0x55}, 4u, 0x79u},
        {{0x00, 0xFF, 0x55, 0x11}, 4u, 0xB8u},
        {{0x33, 0x22, 0x55, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE, 0xFF}, 9u, 0xCBu},
        {{0x92, 0x6B, 0x55}, 3u, 0x8Cu},
        {{0xFF, 0xFF, 0xFF, 0xFF}, 4u, 0x74u},
    };
    static const uint8_t check[] = "123456789";
    size_t i;

    (void)state;
    for (i = 0u; i < sizeof vectors / sizeof vectors[0]; ++i) {
        assert_int_equal(wc_e2e_crc8_j1850(vectors[i].data, vectors[i].len),
                         vectors[i].crc);
    }
    /* catalogue check value of CRC-8/SAE-J1850 */
    assert_int_equal(wc_e2e_crc8_j1850(check, 9u), 0x4Bu);
    /* no data: init 0xFF xor-out 0xFF */
    assert_int_equal(wc_e2e_crc8_j1850(NULL, 0u), 0x00u);
}

static void test_frame_crc_covers_data_id_and_bytes_1_to_7(void **state)
{
    uint8_t frame[FRAME_BYTES] = {0xAAu, 0x05u, 0x80u, 0x0Cu, 0x60u, 0x0Eu, 0x01u, 0x02u};
    const uint8_t manual[FRAME_BYTES] = {0x20u, 0x05u, 0x80u, 0x0Cu, 0x60u, 0x0Eu, 0x01u, 0x02u};
    uint8_t crc = 0u;
    uint8_t crc_other = 0u;
    unsigned bit;

    (void)state;
    assert_int_equal(wc_e2e_frame_crc(0x120u, frame, sizeof frame, &crc), WC_E2E_OK);
    assert_int_equal(crc, wc_e2e_crc8_j1850(manual, sizeof manual));
    /* the CRC byte itself is not covered */
    frame[0] = 0x55u;
    assert_int_equal(wc_e2e_frame_crc(0x120u, frame, sizeof frame, &crc_other), WC_E2E_OK);
    assert_int_equal(crc_other, crc);
    /* only the low byte of the id is the data id */
    assert_int_equal(wc_e2e_frame_crc(0x720u, frame, sizeof frame, &crc_other), WC_E2E_OK);
    assert_int_equal(crc_other, crc);
    assert_int_equal(wc_e2e_frame_crc(0x121u, frame, sizeof frame, &crc_other), WC_E2E_OK);
    assert_int_not_equal(crc_other, crc);

    assert_int_equal(wc_e2e_protect(0x120u, frame, sizeof frame), WC_E2E_OK);
    assert_int_equal(frame[0], crc);
    assert_int_equal(wc_e2e_check_crc(0x120u, frame, sizeof frame), WC_E2E_OK);
    assert_int_equal(wc_e2e_check_crc(0x121u, frame, sizeof frame), WC_E2E_ERR_CRC);
    /* every single-bit error is detected */
    for (bit = 0u; bit < 8u * FRAME_BYTES; ++bit) {
        frame[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        assert_int_equal(wc_e2e_check_crc(0x120u, frame, sizeof frame), WC_E2E_ERR_CRC);
        frame[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    }
    /* short or missing buffers */
    assert_int_equal(wc_e2e_frame_crc(0x120u, frame, 7u, &crc), WC_E2E_ERR_SIZE);
    assert_int_equal(wc_e2e_frame_crc(0x120u, NULL, 8u, &crc), WC_E2E_ERR_SIZE);
    assert_int_equal(wc_e2e_frame_crc(0x120u, frame, 8u, NULL), WC_E2E_ERR_SIZE);
    assert_int_equal(wc_e2e_protect(0x120u, frame, 7u), WC_E2E_ERR_SIZE);
    assert_int_equal(wc_e2e_check_crc(0x120u, frame, 0u), WC_E2E_ERR_SIZE);
}

/* ---- alive counter ------------------------------------------------------- */

/* The receiver of wc_e2e.h (AUTOSAR E2E Profile 1 semantics), default
 * parameters MaxDeltaCounter 2, SyncCounter 3. */
static const wc_e2e_config_t e2e_default = { 2u, 3u };

/* After a timeout: the reference and SyncCounter - 1 frames are SYNC, the
 * SyncCounter-th in-sequence frame is the first OK. */
static void receive_synced(wc_e2e_receiver_t *rx, uint8_t *counter)
{
    wc_e2e_receiver_restart(rx);
    assert_int_equal(wc_e2e_receive(rx, &e2e_default, *counter), WC_E2E_STATUS_SYNC);
    for (unsigned k = 1u; k < e2e_default.sync_counter; ++k) {
        *counter = wc_e2e_counter_next(*counter);
        assert_int_equal(wc_e2e_receive(rx, &e2e_default, *counter), WC_E2E_STATUS_SYNC);
    }
    *counter = wc_e2e_counter_next(*counter);
    assert_int_equal(wc_e2e_receive(rx, &e2e_default, *counter), WC_E2E_STATUS_OK);
}

static void test_counter_sequence_and_wrap(void **state)
{
    wc_e2e_receiver_t rx;
    uint8_t counter = 13u;

    (void)state;
    /* after init the first frame is used at once */
    wc_e2e_receiver_init(&rx);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_INITIAL);
    assert_true(wc_e2e_status_usable(WC_E2E_STATUS_INITIAL));
    counter = wc_e2e_counter_next(counter);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_OK);
    receive_synced(&rx, &counter);
    assert_false(wc_e2e_status_usable(WC_E2E_STATUS_SYNC));
    assert_true(wc_e2e_status_usable(WC_E2E_STATUS_OK));
    /* ..., 15, 0, 1, ... : wrap 15 -> 0 is a normal step */
    for (unsigned i = 0u; i < 40u; ++i) {
        counter = wc_e2e_counter_next(counter);
        assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_OK);
    }
    assert_int_equal(wc_e2e_counter_next(15u), 0u);
    assert_int_equal(wc_e2e_counter_next(0u), 1u);
    /* the high nibble is ignored */
    counter = wc_e2e_counter_next(counter);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, (uint8_t)(counter | 0xF0u)), WC_E2E_STATUS_OK);
}

static void test_counter_repeat_and_jump(void **state)
{
    wc_e2e_receiver_t rx;
    uint8_t counter = 4u;

    (void)state;
    receive_synced(&rx, &counter);   /* 4, 5, 6 SYNC, 7 OK */
    /* repeated: no new data, reference kept */
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 7u), WC_E2E_STATUS_REPEATED);
    assert_false(wc_e2e_status_usable(WC_E2E_STATUS_REPEATED));
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 8u), WC_E2E_STATUS_OK);
    /* one frame lost (9 missing): used, OKSOMELOST; one lost frame costs one frame */
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 10u), WC_E2E_STATUS_OKSOMELOST);
    assert_true(wc_e2e_status_usable(WC_E2E_STATUS_OKSOMELOST));
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 11u), WC_E2E_STATUS_OK);
    /* two lost (delta 3 > MaxDeltaCounter): wrong sequence, then SyncCounter frames */
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 14u), WC_E2E_STATUS_WRONGSEQUENCE);
    assert_false(wc_e2e_status_usable(WC_E2E_STATUS_WRONGSEQUENCE));
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 15u), WC_E2E_STATUS_SYNC);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 0u), WC_E2E_STATUS_SYNC);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 1u), WC_E2E_STATUS_OK);
    /* going backwards is a wrong sequence too */
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, 0u), WC_E2E_STATUS_WRONGSEQUENCE);
    /* NULL: never usable */
    assert_int_equal(wc_e2e_receive(NULL, &e2e_default, 3u), WC_E2E_STATUS_WRONGSEQUENCE);
    assert_int_equal(wc_e2e_receive(&rx, NULL, 3u), WC_E2E_STATUS_WRONGSEQUENCE);
    /* MaxDeltaCounter 0: no lost frame tolerated (a +2 is a wrong sequence) */
    const wc_e2e_config_t strict = { 0u, 3u };
    uint8_t c = 0u;
    receive_synced(&rx, &c);
    assert_int_equal(wc_e2e_receive(&rx, &strict, (uint8_t)(c + 2u)), WC_E2E_STATUS_WRONGSEQUENCE);
}

/* A frozen sender (same counter forever) and a sender counting +2 every
 * frame: after their first frame neither delivers usable data again. */
static void test_counter_frozen_and_fixed_pattern(void **state)
{
    (void)state;
    wc_e2e_receiver_t rx;
    uint8_t counter = 9u;
    receive_synced(&rx, &counter);
    for (unsigned i = 0u; i < 100u; ++i) {
        assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_REPEATED);
    }
    /* the same after the timeout restarts the receiver */
    wc_e2e_receiver_restart(&rx);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_SYNC);
    for (unsigned i = 0u; i < 100u; ++i) {
        assert_false(wc_e2e_status_usable(wc_e2e_receive(&rx, &e2e_default, counter)));
    }
    /* +2 every frame: the first jump is one lost frame (used), then never again */
    receive_synced(&rx, &counter);
    counter = (uint8_t)((counter + 2u) & 0x0Fu);
    assert_int_equal(wc_e2e_receive(&rx, &e2e_default, counter), WC_E2E_STATUS_OKSOMELOST);
    for (unsigned i = 0u; i < 100u; ++i) {
        counter = (uint8_t)((counter + 2u) & 0x0Fu);
        assert_false(wc_e2e_status_usable(wc_e2e_receive(&rx, &e2e_default, counter)));
    }
}

/* ---- rounding ------------------------------------------------------------ */

static void test_rounding_at_step_boundaries_binary_scale(void **state)
{
    const wc_can_signal_t *cur = &wc_can_sig_vfs_command_vfs_current; /* 1/32 mA */
    const wc_can_signal_t *slip = &wc_can_sig_clutch_sensors_slip_speed; /* 0.25 rpm */
    const float tie = 10.0f + half_step(cur);  /* exactly raw 320.5 */

    (void)state;
    assert_int_equal(raw_of(cur, 10.0f, WC_CAN_OK), 320);
    /* exactly half a step above raw 320: rounds to nearest, tie away from 0 */
    assert_int_equal(raw_of(cur, tie, WC_CAN_OK), 321);
    assert_int_equal(raw_of(cur, nextafterf(tie, 0.0f), WC_CAN_OK), 320);
    assert_int_equal(raw_of(cur, nextafterf(tie, 100.0f), WC_CAN_OK), 321);
    /* truncation (cantools issue 635) would give 320 for 321 - 1 ulp */
    assert_int_equal(raw_of(cur, nextafterf(321.0f * cur->scale, 0.0f), WC_CAN_OK), 321);

    /* signed: ties go away from zero on both sides */
    assert_int_equal(raw_of(slip, 0.125f, WC_CAN_OK), 1);
    assert_int_equal(raw_of(slip, -0.125f, WC_CAN_OK), -1);
    assert_int_equal(raw_of(slip, nextafterf(-0.125f, 0.0f), WC_CAN_OK), 0);
    assert_int_equal(raw_of(slip, -750.375f, WC_CAN_OK), -3002);
    assert_int_equal(raw_of(slip, -750.374f, WC_CAN_OK), -3001);
    assert_int_equal(raw_of(&wc_can_sig_vfs_command_pressure_command,
                            100.03125f, WC_CAN_OK), 1601);
}

static void test_rounding_decimal_scale_and_offset(void **state)
{
    const wc_can_signal_t *oil = &wc_can_sig_clutch_sensors_oil_temp; /* 0.1, -50 */
    const wc_can_signal_t *mu = &wc_can_sig_clutch_estimate_mu_f;     /* 1e-5 */
    const wc_can_signal_t *h = &wc_can_sig_clutch_estimate_film_thickness;

    (void)state;
    /* (25.04 + 50) / 0.1 = 750.4 -> 750; 750.6 -> 751 */
    assert_int_equal(raw_of(oil, 25.04f, WC_CAN_OK), 750);
    assert_int_equal(raw_of(oil, 25.06f, WC_CAN_OK), 751);
    assert_int_equal(raw_of(oil, 25.0f, WC_CAN_OK), 750);
    assert_int_equal(raw_of(oil, -40.0f, WC_CAN_OK), 100);
    assert_int_equal(raw_of(oil, 200.0f, WC_CAN_OK), 2500);
    /* 0.1 degC is not exact in float: 0.1 of a step either side of a tie
     * must still round to the nearer raw value */
    assert_int_equal(raw_of(oil, 25.04f + 0.01f, WC_CAN_OK), 751);
    assert_int_equal(raw_of(oil, 25.06f - 0.02f, WC_CAN_OK), 750);
    assert_int_equal(raw_of(mu, 0.1164f, WC_CAN_OK), 11640);
    assert_int_equal(raw_of(mu, 0.116404f, WC_CAN_OK), 11640);
    assert_int_equal(raw_of(mu, 0.116406f, WC_CAN_OK), 11641);
    assert_int_equal(raw_of(h, 4.3425f + 0.0001f, WC_CAN_OK), 4343);
    assert_int_equal(raw_of(h, 4.3424f, WC_CAN_OK), 4342);
}

/* ---- saturation ---------------------------------------------------------- */

/* wc_can_phys_to_raw rounds without newlib's roundf (round_half_away in
 * wc_can_scaling.c). Against the definition (roundf, then saturate) for every
 * descriptor: every raw step and the two half-steps around it near both
 * limits and zero, ties, one float ulp either side of each tie, and
 * pseudo-random values over 10x the range; results and raw values equal. */
static wc_can_result_t phys_to_raw_by_definition(const wc_can_signal_t *sig, float value, int32_t *raw)
{
    const float steps = roundf((value - sig->offset) / sig->scale);
    if (steps < (float)sig->raw_min) { *raw = sig->raw_min; return WC_CAN_SATURATED; }
    if (steps > (float)sig->raw_max) { *raw = sig->raw_max; return WC_CAN_SATURATED; }
    *raw = (int32_t)steps;
    return WC_CAN_OK;
}

static void check_rounding(const wc_can_signal_t *sig, float value)
{
    int32_t got = 0;
    int32_t want = 0;
    const wc_can_result_t r_got = wc_can_phys_to_raw(sig, value, &got);
    const wc_can_result_t r_want = phys_to_raw_by_definition(sig, value, &want);
    if ((r_got != r_want) || (got != want)) {
        fail_msg("value %.9g (scale %g, offset %g): raw %ld result %d, by definition raw %ld result %d",
                 (double)value, (double)sig->scale, (double)sig->offset, (long)got, (int)r_got, (long)want,
                 (int)r_want);
    }
}

static void test_rounding_equals_roundf(void **state)
{
    (void)state;
    const wc_can_signal_t *const sigs[] = {
        &wc_can_sig_clutch_sensors_slip_speed, &wc_can_sig_clutch_sensors_oil_temp,
        &wc_can_sig_torque_request_torque_request, &wc_can_sig_vfs_command_vfs_current,
        &wc_can_sig_vfs_command_pressure_command, &wc_can_sig_clutch_estimate_estimated_clutch_temp,
        &wc_can_sig_clutch_estimate_model_torque, &wc_can_sig_clutch_estimate_mu_f,
        &wc_can_sig_clutch_estimate_film_thickness, &wc_can_sig_bench_measurement_load_cell_force,
        &wc_can_sig_bench_measurement_measured_torque,
    };
    uint32_t x = 2463534242u;
    for (size_t k = 0u; k < sizeof sigs / sizeof sigs[0]; ++k) {
        const wc_can_signal_t *sig = sigs[k];
        const int32_t anchors[] = { sig->raw_min, 0, sig->raw_max };
        for (size_t a = 0u; a < 3u; ++a) {
            for (int32_t d = -300; d <= 300; ++d) {
                const float raw = (float)(anchors[a] + d);
                for (int h = -1; h <= 1; ++h) {
                    const float tie = (raw + 0.5f * (float)h) * sig->scale + sig->offset;
                    check_rounding(sig, tie);
                    check_rounding(sig, nextafterf(tie, INFINITY));
                    check_rounding(sig, nextafterf(tie, -INFINITY));
                }
            }
        }
        const float span = (float)(sig->raw_max - sig->raw_min) * sig->scale;
        for (int n = 0; n < 20000; ++n) {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            const float u = (float)(x >> 8) / 16777216.0f;  /* [0, 1) */
            check_rounding(sig, sig->offset + (float)sig->raw_min * sig->scale + (10.0f * u - 4.5f) * span);
        }
        check_rounding(sig, INFINITY);
        check_rounding(sig, -INFINITY);
        check_rounding(sig, 3.0e38f);
        check_rounding(sig, -3.0e38f);
    }
}

static void test_saturation_at_both_ends(void **state)
{
    const wc_can_signal_t *cur = &wc_can_sig_vfs_command_vfs_current;
    const wc_can_signal_t *slip = &wc_can_sig_clutch_sensors_slip_speed;
    const wc_can_signal_t *force = &wc_can_sig_bench_measurement_load_cell_force;
    const wc_can_signal_t *temp = &wc_can_sig_clutch_estimate_estimated_clutch_temp;
    const float top_tie = 2000.0f + half_step(cur); /* raw 64000.5 */

    (void)state;
    /* top: max itself is fine, half a step above rounds out of range */
    assert_int_equal(raw_of(cur, 2000.0f, WC_CAN_OK), 64000);
    assert_int_equal(raw_of(cur, nextafterf(top_tie, 0.0f), WC_CAN_OK), 64000);
    assert_int_equal(raw_of(cur, top_tie, WC_CAN_SATURATED), 64000);
    assert_int_equal(raw_of(cur, 5000.0f, WC_CAN_SATURATED), 64000);
    assert_int_equal(raw_of(cur, FLT_MAX, WC_CAN_SATURATED), 64000);
    assert_int_equal(raw_of(cur, INFINITY, WC_CAN_SATURATED), 64000);
    /* bottom */
    assert_int_equal(raw_of(cur, 0.0f, WC_CAN_OK), 0);
    assert_int_equal(raw_of(cur, -half_step(cur) * 0.999f, WC_CAN_OK), 0);
    assert_int_equal(raw_of(cur, -half_step(cur), WC_CAN_SATURATED), 0);
    assert_int_equal(raw_of(cur, -1.0f, WC_CAN_SATURATED), 0);
    assert_int_equal(raw_of(cur, -INFINITY, WC_CAN_SATURATED), 0);
    /* signed */
    assert_int_equal(raw_of(slip, -8000.0f, WC_CAN_OK), -32000);
    assert_int_equal(raw_of(slip, -8000.125f, WC_CAN_SATURATED), -32000);
    assert_int_equal(raw_of(slip, 8000.125f, WC_CAN_SATURATED), 32000);
    assert_int_equal(raw_of(slip, -FLT_MAX, WC_CAN_SATURATED), -32000);
    assert_int_equal(raw_of(force, -1.0e9f, WC_CAN_SATURATED), -200000);
    assert_int_equal(raw_of(force, 1.0e9f, WC_CAN_SATURATED), 200000);
    /* offset signal: limits are the DBC [min|max], not the 12-bit raw range */
    assert_int_equal(raw_of(temp, -60.0f, WC_CAN_SATURATED), 100);
    assert_int_equal(raw_of(temp, 400.0f, WC_CAN_SATURATED), 4000);
}

/* ---- NaN ----------------------------------------------------------------- */

static void test_nan_maps_to_documented_raw(void **state)
{
    (void)state;
    /* actuator commands: NaN -> 0 (no solenoid current) */
    assert_int_equal(raw_of(&wc_can_sig_vfs_command_vfs_current, NAN, WC_CAN_ERR_NAN), 0);
    assert_int_equal(raw_of(&wc_can_sig_vfs_command_pressure_command, NAN, WC_CAN_ERR_NAN), 0);
    /* measured/estimated values: NaN -> SNA */
    assert_int_equal(raw_of(&wc_can_sig_clutch_estimate_estimated_clutch_temp, NAN, WC_CAN_ERR_NAN),
                     (int32_t)WC_CAN_CLUTCH_ESTIMATE_ESTIMATED_CLUTCH_TEMP_SNA_CHOICE);
    assert_int_equal(raw_of(&wc_can_sig_clutch_estimate_model_torque, -NAN, WC_CAN_ERR_NAN), -32768);
    assert_int_equal(raw_of(&wc_can_sig_clutch_estimate_mu_f, NAN, WC_CAN_ERR_NAN), 65535);
    assert_int_equal(raw_of(&wc_can_sig_clutch_estimate_film_thickness, NAN, WC_CAN_ERR_NAN), 65535);
    assert_int_equal(raw_of(&wc_can_sig_clutch_sensors_slip_speed, NAN, WC_CAN_ERR_NAN), -32768);
    assert_true(wc_can_is_error(WC_CAN_ERR_NAN));
    assert_false(wc_can_is_error(WC_CAN_SATURATED));
}

static void test_nan_in_vfs_command_frame(void **state)
{
    uint8_t frame[FRAME_BYTES];
    wc_can_vfs_command_phys_t in = {NAN, 230.0f, 0u, 3u};
    wc_can_vfs_command_phys_t out;

    (void)state;
    assert_int_equal(wc_can_encode_vfs_command(frame, &in, sizeof frame), WC_CAN_ERR_NAN);
    /* the frame is still complete and valid: 0 mA, CRC fine */
    assert_int_equal(wc_can_decode_vfs_command(&out, frame, sizeof frame), WC_CAN_OK);
    assert_float_equal(out.vfs_current_mA, 0.0f, 0.0f);
    assert_float_equal(out.pressure_command_kPa, 230.0f, 0.0f);
}

/* ---- decode -------------------------------------------------------------- */

static void test_decode_sna_and_range(void **state)
{
    float value = 0.0f;
    const wc_can_signal_t *oil = &wc_can_sig_clutch_sensors_oil_temp;

    (void)state;
    assert_int_equal(wc_can_raw_to_phys(oil, 750, &value), WC_CAN_OK);
    assert_float_equal(value, 25.0f, 1e-4f);
    assert_int_equal(wc_can_raw_to_phys(oil, 4095, &value), WC_CAN_ERR_SNA);
    assert_true(isnan(value));
    /* outside [min|max]: value unclamped, flagged */
    assert_int_equal(wc_can_raw_to_phys(oil, 99, &value), WC_CAN_ERR_RANGE);
    assert_float_equal(value, -40.1f, 1e-4f);
    assert_int_equal(wc_can_raw_to_phys(oil, 2501, &value), WC_CAN_ERR_RANGE);
    assert_float_equal(value, 200.1f, 1e-4f);
    assert_int_equal(wc_can_raw_to_phys(&wc_can_sig_clutch_sensors_slip_speed, -32768, &value),
                     WC_CAN_ERR_SNA);
    assert_int_equal(wc_can_raw_to_phys(&wc_can_sig_clutch_sensors_slip_speed, -32767, &value),
                     WC_CAN_ERR_RANGE);
    /* signals without SNA: raw 0 is a value */
    assert_int_equal(wc_can_raw_to_phys(&wc_can_sig_vfs_command_vfs_current, 0, &value), WC_CAN_OK);
    assert_int_equal(wc_can_raw_to_phys(&wc_can_sig_vfs_command_vfs_current, 65535, &value),
                     WC_CAN_ERR_RANGE);
    assert_int_equal(wc_can_raw_to_phys(NULL, 0, &value), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_raw_to_phys(oil, 0, NULL), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_phys_to_raw(oil, 0.0f, NULL), WC_CAN_ERR_SIZE);
}

/* The descriptors' raw limits equal the DBC [min|max] as generated into
 * wc_can_<msg>_<sig>_is_in_range() and SNA lies outside them. */
#define CHECK_LIMITS(sig, fn, type) do {                                    \
        assert_true(fn((type)(sig).raw_min));                              \
        assert_true(fn((type)(sig).raw_max));                              \
        assert_false(fn((type)((sig).raw_min - 1)));                       \
        assert_false(fn((type)((sig).raw_max + 1)));                       \
        if ((sig).has_sna) {                                               \
            assert_false(fn((type)(sig).raw_sna));                         \
        }                                                                  \
    } while (0)

static void test_descriptors_match_generated_ranges(void **state)
{
    (void)state;
    CHECK_LIMITS(wc_can_sig_clutch_sensors_slip_speed,
                 wc_can_clutch_sensors_slip_speed_is_in_range, int16_t);
    CHECK_LIMITS(wc_can_sig_clutch_sensors_oil_temp,
                 wc_can_clutch_sensors_oil_temp_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_clutch_sensors_housing_temp,
                 wc_can_clutch_sensors_housing_temp_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_torque_request_torque_request,
                 wc_can_torque_request_torque_request_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_clutch_estimate_estimated_clutch_temp,
                 wc_can_clutch_estimate_estimated_clutch_temp_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_clutch_estimate_model_torque,
                 wc_can_clutch_estimate_model_torque_is_in_range, int16_t);
    CHECK_LIMITS(wc_can_sig_clutch_estimate_mu_f,
                 wc_can_clutch_estimate_mu_f_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_clutch_estimate_film_thickness,
                 wc_can_clutch_estimate_film_thickness_is_in_range, uint16_t);
    CHECK_LIMITS(wc_can_sig_bench_measurement_load_cell_force,
                 wc_can_bench_measurement_load_cell_force_is_in_range, int32_t);
    CHECK_LIMITS(wc_can_sig_bench_measurement_measured_torque,
                 wc_can_bench_measurement_measured_torque_is_in_range, int32_t);
    CHECK_LIMITS(wc_can_sig_bench_measurement_clutch_thermistor_temp,
                 wc_can_bench_measurement_clutch_thermistor_temp_is_in_range, uint16_t);
    /* VfsCurrent/PressureCommand: min is 0, raw_min - 1 is not representable */
    assert_true(wc_can_vfs_command_vfs_current_is_in_range(64000u));
    assert_false(wc_can_vfs_command_vfs_current_is_in_range(64001u));
    assert_true(wc_can_vfs_command_pressure_command_is_in_range(64000u));
    assert_false(wc_can_vfs_command_pressure_command_is_in_range(64001u));
    assert_int_equal(wc_can_sig_vfs_command_vfs_current.raw_min, 0);
    assert_int_equal(wc_can_sig_vfs_command_pressure_command.raw_min, 0);
    /* the physical range checks agree at the limits */
    assert_true(wc_can_clutch_sensors_oil_temp_is_in_phys_range(-40.0f));
    assert_true(wc_can_clutch_sensors_oil_temp_is_in_phys_range(200.0f));
    assert_false(wc_can_clutch_sensors_oil_temp_is_in_phys_range(200.1f));
}

/* ---- frames -------------------------------------------------------------- */

static void test_vfs_command_golden_layout(void **state)
{
    /* 100 mA = raw 3200 = 0x0C80, 230 kPa = raw 3680 = 0x0E60,
     * status bits 0 and 9 (frame bits 48, 57), counter 5 */
    const wc_can_vfs_command_phys_t in = {100.0f, 230.0f,
        (uint16_t)(WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_DEADLINE_MISS), 5u};
    const uint8_t crc_input[FRAME_BYTES] = {0x20u, 0x05u, 0x80u, 0x0Cu, 0x60u, 0x0Eu, 0x01u, 0x02u};
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_vfs_command(frame, &in, sizeof frame), WC_CAN_OK);
    assert_memory_equal(&frame[1], &crc_input[1], 7u);
    assert_int_equal(frame[0], wc_e2e_crc8_j1850(crc_input, sizeof crc_input));
}

static void test_round_trip_clutch_sensors(void **state)
{
    const wc_can_clutch_sensors_phys_t in = {-750.3f, 65.04f, 41.27f, 9u};
    wc_can_clutch_sensors_phys_t out;
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_clutch_sensors(frame, &in, sizeof frame), WC_CAN_OK);
    assert_int_equal(wc_e2e_check_crc(WC_CAN_CLUTCH_SENSORS_FRAME_ID, frame, sizeof frame),
                     WC_E2E_OK);
    assert_int_equal(wc_can_decode_clutch_sensors(&out, frame, sizeof frame), WC_CAN_OK);
    assert_float_equal(out.slip_speed_rpm, -750.25f, 0.0f);
    assert_float_equal(out.oil_temp_degC, 65.0f, 1e-4f);
    assert_float_equal(out.housing_temp_degC, 41.3f, 1e-4f);
    assert_int_equal(out.alive_counter, 9u);
}

static void test_round_trip_torque_request(void **state)
{
    const wc_can_torque_request_phys_t in = {150.02f,
        (uint8_t)WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, 15u};
    wc_can_torque_request_phys_t out;
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_torque_request(frame, &in, sizeof frame), WC_CAN_OK);
    assert_int_equal(wc_can_decode_torque_request(&out, frame, sizeof frame), WC_CAN_OK);
    assert_float_equal(out.torque_request_Nm, 150.0f, 1e-3f);
    assert_int_equal(out.mode, WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE);
    assert_int_equal(out.alive_counter, 15u);
}

static void test_torque_request_reserved_mode(void **state)
{
    wc_can_torque_request_phys_t in = {10.0f, 4u, 0u};  /* 3 is Shift (DESIGN 10); 4..15 reserved */
    wc_can_torque_request_phys_t out;
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_torque_request(frame, &in, sizeof frame), WC_CAN_ERR_RANGE);
    assert_int_equal(wc_can_decode_torque_request(&out, frame, sizeof frame), WC_CAN_ERR_RANGE);
    assert_int_equal(out.mode, 4u);
    /* SNA torque request */
    in.mode = (uint8_t)WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE;
    in.torque_request_Nm = NAN;
    assert_int_equal(wc_can_encode_torque_request(frame, &in, sizeof frame), WC_CAN_ERR_NAN);
    assert_int_equal(wc_can_decode_torque_request(&out, frame, sizeof frame), WC_CAN_ERR_SNA);
    assert_true(isnan(out.torque_request_Nm));
}

static void test_round_trip_vfs_command(void **state)
{
    const wc_can_vfs_command_phys_t in = {157.8f, 363.0f, 0xFFFFu, 0u};
    wc_can_vfs_command_phys_t out;
    uint8_t frame[FRAME_BYTES];
    unsigned bit;

    (void)state;
    assert_int_equal(wc_can_encode_vfs_command(frame, &in, sizeof frame), WC_CAN_OK);
    assert_int_equal(wc_can_decode_vfs_command(&out, frame, sizeof frame), WC_CAN_OK);
    assert_float_equal(out.vfs_current_mA, 157.8125f, 0.0f); /* nearest 1/32 */
    assert_float_equal(out.pressure_command_kPa, 363.0f, 0.0f);
    /* the reserved status bit (above WC_CAN_STATUS_BITS: 15) is not sent */
    assert_int_equal(out.status, WC_CAN_STATUS_DEFINED_MASK);
    assert_int_equal(WC_CAN_STATUS_DEFINED_MASK, 0x7FFFu);
    assert_int_equal(frame[7] & 0x80u, 0u);
    assert_int_equal(frame[1] & 0xF0u, 0u);
    /* each status bit on its own */
    for (bit = 0u; bit < 16u; ++bit) {
        wc_can_vfs_command_phys_t one = in;

        one.status = (uint16_t)(1u << bit);
        assert_int_equal(wc_can_encode_vfs_command(frame, &one, sizeof frame), WC_CAN_OK);
        assert_int_equal(wc_can_decode_vfs_command(&out, frame, sizeof frame), WC_CAN_OK);
        assert_int_equal(out.status, one.status & WC_CAN_STATUS_DEFINED_MASK);
    }
}

static void test_round_trip_clutch_estimate(void **state)
{
    const wc_can_clutch_estimate_phys_t in = {146.93f, -154.66f, 0.0904345f, 4.34249f,
                                               WC_CAN_CLUTCH_ESTIMATE_LOCK_STATE_LOCKED_CHOICE};
    wc_can_clutch_estimate_phys_t out;
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_clutch_estimate(frame, &in, sizeof frame), WC_CAN_OK);
    assert_int_equal(wc_can_decode_clutch_estimate(&out, frame, sizeof frame), WC_CAN_OK);
    /* within half a raw step (plus float rounding of the decode) */
    assert_float_equal(out.estimated_clutch_temp_degC, in.estimated_clutch_temp_degC, 0.05f + 1e-4f);
    assert_float_equal(out.model_torque_Nm, in.model_torque_Nm, 0.05f + 1e-4f);
    assert_float_equal(out.mu_f, in.mu_f, 0.5e-5f + 1e-7f);
    assert_float_equal(out.film_thickness_um, in.film_thickness_um, 0.5e-3f + 1e-6f);
    assert_float_equal(out.model_torque_Nm, -154.7f, 1e-4f);
    assert_int_equal(out.lock_state, WC_CAN_CLUTCH_ESTIMATE_LOCK_STATE_LOCKED_CHOICE);
    assert_int_equal(frame[1] & 0x10u, 0x10u);  /* LockState: frame bit 12 */
}

static void test_round_trip_bench_measurement(void **state)
{
    const wc_can_bench_measurement_phys_t in = {-1188.04f, 4999.996f, 349.96f};
    wc_can_bench_measurement_phys_t out;
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_bench_measurement(frame, &in, sizeof frame), WC_CAN_OK);
    assert_int_equal(wc_can_decode_bench_measurement(&out, frame, sizeof frame), WC_CAN_OK);
    assert_float_equal(out.load_cell_force_N, -1188.0f, 1e-3f);
    assert_float_equal(out.measured_torque_Nm, 5000.0f, 1e-3f);
    assert_float_equal(out.clutch_thermistor_temp_degC, 350.0f, 1e-3f);
    /* negative 20-bit values sign-extend on unpack */
    assert_int_equal(frame[7], 0u);
}

static void test_round_trip_raw_sweep(void **state)
{
    /* every raw value of a 16-bit signal survives decode -> encode */
    const wc_can_signal_t *sigs[] = {
        &wc_can_sig_clutch_sensors_slip_speed,
        &wc_can_sig_clutch_sensors_oil_temp,
        &wc_can_sig_torque_request_torque_request,
        &wc_can_sig_vfs_command_vfs_current,
        &wc_can_sig_vfs_command_pressure_command,
        &wc_can_sig_clutch_estimate_estimated_clutch_temp,
        &wc_can_sig_clutch_estimate_model_torque,
        &wc_can_sig_clutch_estimate_mu_f,
        &wc_can_sig_clutch_estimate_film_thickness,
        &wc_can_sig_bench_measurement_clutch_thermistor_temp,
    };
    size_t i;
    int32_t raw;

    (void)state;
    for (i = 0u; i < sizeof sigs / sizeof sigs[0]; ++i) {
        for (raw = sigs[i]->raw_min; raw <= sigs[i]->raw_max; ++raw) {
            float value = 0.0f;
            int32_t back = 0;

            assert_int_equal(wc_can_raw_to_phys(sigs[i], raw, &value), WC_CAN_OK);
            assert_int_equal(wc_can_phys_to_raw(sigs[i], value, &back), WC_CAN_OK);
            assert_int_equal(back, raw);
        }
    }
}

static void test_crc_error_drops_frame(void **state)
{
    const wc_can_clutch_sensors_phys_t in = {100.0f, 60.0f, 50.0f, 1u};
    wc_can_clutch_sensors_phys_t out = {1.0f, 2.0f, 3.0f, 4u};
    wc_can_torque_request_phys_t req = {5.0f, 1u, 6u};
    uint8_t frame[FRAME_BYTES];

    (void)state;
    assert_int_equal(wc_can_encode_clutch_sensors(frame, &in, sizeof frame), WC_CAN_OK);
    frame[4] ^= 0x10u;
    assert_int_equal(wc_can_decode_clutch_sensors(&out, frame, sizeof frame), WC_CAN_ERR_CRC);
    assert_float_equal(out.slip_speed_rpm, 1.0f, 0.0f); /* untouched */
    assert_int_equal(out.alive_counter, 4u);
    frame[4] ^= 0x10u;
    /* a ClutchSensors frame read as TorqueRequest fails (data id differs) */
    assert_int_equal(wc_can_decode_torque_request(&req, frame, sizeof frame), WC_CAN_ERR_CRC);
    assert_int_equal(wc_can_decode_clutch_sensors(&out, frame, sizeof frame), WC_CAN_OK);
}

static void test_short_buffer_is_an_error(void **state)
{
    uint8_t frame[FRAME_BYTES];
    uint8_t untouched[FRAME_BYTES];
    const wc_can_vfs_command_phys_t cmd = {1.0f, 2.0f, 0u, 0u};
    const wc_can_clutch_estimate_phys_t est = {1.0f, 2.0f, 0.1f, 3.0f, 0u};
    const wc_can_clutch_sensors_phys_t sen = {1.0f, 2.0f, 3.0f, 0u};
    const wc_can_torque_request_phys_t req = {1.0f, 0u, 0u};
    const wc_can_bench_measurement_phys_t bench = {1.0f, 2.0f, 3.0f};
    wc_can_vfs_command_phys_t cmd_out;
    wc_can_clutch_estimate_phys_t est_out;
    wc_can_clutch_sensors_phys_t sen_out;
    wc_can_torque_request_phys_t req_out;
    wc_can_bench_measurement_phys_t bench_out;
    struct wc_can_vfs_command_t raw_msg;

    (void)state;
    memset(frame, 0xA5, sizeof frame);
    memcpy(untouched, frame, sizeof frame);
    assert_int_equal(wc_can_encode_vfs_command(frame, &cmd, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_encode_clutch_estimate(frame, &est, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_encode_clutch_sensors(frame, &sen, 0u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_encode_torque_request(frame, &req, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_encode_bench_measurement(frame, &bench, 7u), WC_CAN_ERR_SIZE);
    assert_memory_equal(frame, untouched, sizeof frame);
    assert_int_equal(wc_can_encode_vfs_command(NULL, &cmd, 8u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_encode_vfs_command(frame, NULL, 8u), WC_CAN_ERR_SIZE);

    assert_int_equal(wc_can_decode_vfs_command(&cmd_out, frame, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_clutch_estimate(&est_out, frame, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_clutch_sensors(&sen_out, frame, 1u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_torque_request(&req_out, frame, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_bench_measurement(&bench_out, frame, 7u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_bench_measurement(&bench_out, NULL, 8u), WC_CAN_ERR_SIZE);
    assert_int_equal(wc_can_decode_bench_measurement(NULL, frame, 8u), WC_CAN_ERR_SIZE);

    /* the generated layer itself */
    (void)wc_can_vfs_command_init(&raw_msg);
    assert_int_equal(wc_can_vfs_command_pack(frame, &raw_msg, 7u), -EINVAL);
    assert_int_equal(wc_can_vfs_command_unpack(&raw_msg, frame, 7u), -EINVAL);
    assert_int_equal(wc_can_vfs_command_pack(frame, &raw_msg, 8u), 8);
}

static void test_worst_result(void **state)
{
    (void)state;
    assert_int_equal(wc_can_worst(WC_CAN_OK, WC_CAN_SATURATED), WC_CAN_SATURATED);
    assert_int_equal(wc_can_worst(WC_CAN_ERR_SNA, WC_CAN_ERR_RANGE), WC_CAN_ERR_SNA);
    assert_int_equal(wc_can_worst(WC_CAN_ERR_NAN, WC_CAN_SATURATED), WC_CAN_ERR_NAN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc8_autosar_vectors),
        cmocka_unit_test(test_crc8_table_matches_bitwise),
        cmocka_unit_test(test_rounding_equals_roundf),
        cmocka_unit_test(test_frame_crc_covers_data_id_and_bytes_1_to_7),
        cmocka_unit_test(test_counter_sequence_and_wrap),
        cmocka_unit_test(test_counter_repeat_and_jump),
        cmocka_unit_test(test_counter_frozen_and_fixed_pattern),
        cmocka_unit_test(test_rounding_at_step_boundaries_binary_scale),
        cmocka_unit_test(test_rounding_decimal_scale_and_offset),
        cmocka_unit_test(test_saturation_at_both_ends),
        cmocka_unit_test(test_nan_maps_to_documented_raw),
        cmocka_unit_test(test_nan_in_vfs_command_frame),
        cmocka_unit_test(test_decode_sna_and_range),
        cmocka_unit_test(test_descriptors_match_generated_ranges),
        cmocka_unit_test(test_vfs_command_golden_layout),
        cmocka_unit_test(test_round_trip_clutch_sensors),
        cmocka_unit_test(test_round_trip_torque_request),
        cmocka_unit_test(test_torque_request_reserved_mode),
        cmocka_unit_test(test_round_trip_vfs_command),
        cmocka_unit_test(test_round_trip_clutch_estimate),
        cmocka_unit_test(test_round_trip_bench_measurement),
        cmocka_unit_test(test_round_trip_raw_sweep),
        cmocka_unit_test(test_crc_error_drops_frame),
        cmocka_unit_test(test_short_buffer_is_an_error),
        cmocka_unit_test(test_worst_result),
    };

    return cmocka_run_group_tests_name("can_codec", tests, NULL, NULL);
}
