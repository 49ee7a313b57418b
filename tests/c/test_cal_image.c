/* The calibration image (include/wetclutch_can/wc_cal_image.h; DESIGN 13):
 *  - the C codec against Python's golden image (tests/vectors/
 *    wc_cal_image_golden.hex, written by tests/python/test_cal_image.py: every
 *    payload word a distinct value, pattern() here and there): decoded into
 *    the right member, word by word, and written back to the same bytes;
 *  - the committed image lut/wc_table1_cal_image.h (Python's writer) loads
 *    and equals the compiled-in table1 + shift_1_2_full, and the C writer
 *    gives its bytes; every compiled-in shift variant round-trips;
 *  - each rule, failing, gives its result and code, and the set is zeroed
 *    (wc_loop_init refuses it); the loop's limits at and past both ends;
 *  - every single-bit flip and every truncation of a real image is refused. */
#include "wc_test_support.h"

#include <stdio.h>
#include <stdlib.h>

#include "generated/wc_cal_image_layout.h"
#include "wc_shift_1_2_shift.h"
#include "wc_table1_cal_image.h"
#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_cal_image.h"

#define PAYLOAD WC_CAL_IMAGE_PAYLOAD_BYTES
#define IMAGE_BYTES WC_IMAGE_BYTES(PAYLOAD)

/* tests/python/test_cal_image.py's pattern: payload word w (loop fields aside). */
static uint32_t pattern(uint32_t word) { return 0x3F800000u + word * 0x1001u; }

static uint32_t word_at(const void *base, size_t offset)
{
    uint32_t w;
    memcpy(&w, (const unsigned char *)base + offset, sizeof w);
    return w;
}

static size_t read_golden(uint8_t *out, size_t capacity)
{
    return wc_test_read_hex(WC_TEST_VECTORS_DIR "/wc_cal_image_golden.hex", out, capacity);
}

static void test_payload_size(void **state)
{
    (void)state;
    assert_int_equal(wc_cal_image_payload_bytes, PAYLOAD);
    assert_int_equal(PAYLOAD, 1168u);  /* 1088 + the whole shift's 18 words (DESIGN 14) + the open drag's 2 (DESIGN 15) */
    assert_true(PAYLOAD <= WC_CAL_IMAGE_PAYLOAD_MAX_BYTES);
    assert_int_equal(WC_TABLE1_CAL_IMAGE_BYTES, IMAGE_BYTES);
    assert_string_equal(wc_cal_image_field_name(0u), "clutch.outer_radius_m");
    assert_string_equal(wc_cal_image_field_name(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M + 4u * 63u), "clutch.film.hbar_m");
    assert_string_equal(wc_cal_image_field_name(PAYLOAD - 1u), "loop.recovery_periods");
    assert_null(wc_cal_image_field_name(PAYLOAD));
}

/* Python's bytes decode into the right members: the clutch's and the shift's words in their structs' order,
 * the film arrays node by node, the loop's fields by name; written back by the C writer to the same bytes. */
static void test_golden_image_round_trip(void **state)
{
    (void)state;
    uint8_t golden[IMAGE_BYTES + 1u];
    assert_int_equal(read_golden(golden, sizeof golden), IMAGE_BYTES);
    const uint8_t *payload = NULL;
    assert_int_equal(wc_image_read(golden, IMAGE_BYTES, WC_CAL_IMAGE_MAGIC, WC_CAL_IMAGE_VERSION, PAYLOAD, &payload),
                     WC_IMAGE_OK);
    static wc_cal_set_t set;
    memset(&set, 0, sizeof set);
    wc_cal_image_layout_decode(payload, &set);
    for (uint32_t i = 0u; 4u * i < (uint32_t)offsetof(wc_calibration_t, film); ++i) {
        WC_CHECK(word_at(&set.clutch, 4u * i) == pattern(i), "clutch word %u", (unsigned)i);
    }
    assert_int_equal(set.clutch.film.length, pattern(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_LENGTH / 4u));
    for (uint32_t i = 0u; i < WC_CAL_IMAGE_FILM_NODES; ++i) {
        assert_int_equal(word_at(set.film_pressure_Pa, 4u * i), pattern(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_PRESSURE_PA / 4u + i));
        assert_int_equal(word_at(set.film_hbar_m, 4u * i), pattern(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M / 4u + i));
        assert_int_equal(word_at(set.film_slope_m_per_Pa, 4u * i),
                         pattern(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_SLOPE_M_PER_PA / 4u + i));
    }
    for (uint32_t i = 0u; 4u * i < (uint32_t)sizeof(wc_shift_calibration_t); ++i) {
        WC_CHECK(word_at(&set.shift, 4u * i) == pattern(WC_CAL_IMAGE_SHIFT_BEGIN / 4u + i), "shift word %u", (unsigned)i);
    }
    assert_true(set.shift_enabled);
    assert_int_equal(set.loop.sensor_timeout_periods, 11u);
    assert_int_equal(set.loop.request_timeout_periods, 12u);
    assert_int_equal(set.loop.e2e.max_delta_counter, 5u);
    assert_int_equal(set.loop.e2e.sync_counter, 6u);
    assert_int_equal(set.loop.recovery_periods, 37u);

    uint8_t image[IMAGE_BYTES];
    for (size_t capacity = 0u; capacity < IMAGE_BYTES; capacity += 97u) {
        assert_int_equal(wc_cal_image_write(&set, image, capacity), 0u);
    }
    assert_int_equal(wc_cal_image_write(&set, image, sizeof image), IMAGE_BYTES);
    assert_memory_equal(image, golden, IMAGE_BYTES);
    uint8_t again[PAYLOAD];
    wc_cal_image_encode(&set, again);
    assert_memory_equal(again, payload, PAYLOAD);
}

static void assert_loop_defaults(const wc_cal_set_t *set)
{
    const wc_loop_config_t defaults = WC_LOOP_CONFIG_DEFAULT;
    assert_int_equal(set->loop.sensor_timeout_periods, defaults.sensor_timeout_periods);
    assert_int_equal(set->loop.request_timeout_periods, defaults.request_timeout_periods);
    assert_int_equal(set->loop.e2e.max_delta_counter, defaults.e2e.max_delta_counter);
    assert_int_equal(set->loop.e2e.sync_counter, defaults.e2e.sync_counter);
    assert_int_equal(set->loop.recovery_periods, defaults.recovery_periods);
    assert_false(set->loop.bench_input_enabled);
    assert_null(set->loop.adaptation_changed);
    assert_null(set->loop.adaptation_context);
}

/* The committed image (Python's writer) is table1 + shift_1_2_full, field for field, and the C writer gives its
 * bytes from the compiled-in calibrations. */
static void test_committed_image_is_the_compiled_in_calibration(void **state)
{
    (void)state;
    static wc_cal_set_t set;
    const wc_cal_image_status_t status = wc_cal_image_load(wc_table1_cal_image, sizeof wc_table1_cal_image, &set);
    assert_int_equal(status.result, WC_CAL_IMAGE_OK);
    assert_int_equal(status.error, 0u);
    assert_memory_equal(&set.clutch, &wc_table1_calibration, offsetof(wc_calibration_t, film));
    assert_int_equal(set.clutch.film.length, WC_TABLE1_FILM_NODES);
    assert_ptr_equal(set.clutch.film.hbar_m, set.film_hbar_m);
    assert_memory_equal(set.film_pressure_Pa, wc_table1_film_pressure_Pa, sizeof wc_table1_film_pressure_Pa);
    assert_memory_equal(set.film_hbar_m, wc_table1_film_hbar_m, sizeof wc_table1_film_hbar_m);
    assert_memory_equal(set.film_slope_m_per_Pa, wc_table1_film_slope_m_per_Pa, sizeof wc_table1_film_slope_m_per_Pa);
    assert_memory_equal(&set.shift, &wc_shift_1_2_full, sizeof wc_shift_1_2_full);
    assert_true(set.shift_enabled);
    assert_ptr_equal(set.loop.shift, &set.shift);
    assert_loop_defaults(&set);
    static wc_loop_t loop;
    assert_int_equal(wc_loop_init(&loop, &set.clutch, &set.loop, 40.0f), WC_CAL_OK);

    static wc_cal_set_t built;
    assert_true(wc_cal_set_from(&built, &wc_table1_calibration, &wc_shift_1_2_full, NULL));
    uint8_t image[IMAGE_BYTES];
    assert_int_equal(wc_cal_image_write(&built, image, sizeof image), IMAGE_BYTES);
    assert_memory_equal(image, wc_table1_cal_image, IMAGE_BYTES);
}

/* Every compiled-in shift variant, and shift control off, round-trips through an image. */
static void test_every_compiled_in_variant_round_trips(void **state)
{
    (void)state;
    const wc_shift_calibration_t *variants[] = { &wc_shift_1_2_full, &wc_shift_1_2_blind, &wc_shift_1_2_feedback,
                                                 &wc_shift_1_2_nolag, &wc_shift_1_2_adaptive, NULL };
    for (size_t v = 0u; v < WC_TEST_COUNT(variants); ++v) {
        static wc_cal_set_t built;
        static wc_cal_set_t loaded;
        assert_true(wc_cal_set_from(&built, &wc_table1_calibration, variants[v], NULL));
        uint8_t image[IMAGE_BYTES];
        assert_int_equal(wc_cal_image_write(&built, image, sizeof image), IMAGE_BYTES);
        const wc_cal_image_status_t status = wc_cal_image_load(image, sizeof image, &loaded);
        WC_CHECK(status.result == WC_CAL_IMAGE_OK, "variant %zu: result %u error %u", v, (unsigned)status.result,
                 (unsigned)status.error);
        assert_int_equal(loaded.shift_enabled, variants[v] != NULL);
        if (variants[v] != NULL) {
            assert_memory_equal(&loaded.shift, variants[v], sizeof loaded.shift);
            assert_ptr_equal(loaded.loop.shift, &loaded.shift);
        } else {
            assert_null(loaded.loop.shift);
        }
    }
}

/* A set of table1 with shift control, changed by change(), written and loaded: the status. */
typedef void (*change_t)(wc_cal_set_t *set, uint32_t value);

static wc_cal_image_status_t load_changed(change_t change, uint32_t value, bool shift)
{
    static wc_cal_set_t set;
    static wc_cal_set_t loaded;
    assert_true(wc_cal_set_from(&set, &wc_table1_calibration, shift ? &wc_shift_1_2_full : NULL, NULL));
    change(&set, value);
    uint8_t image[IMAGE_BYTES];
    assert_int_equal(wc_cal_image_write(&set, image, sizeof image), IMAGE_BYTES);
    memset(&loaded, 0xA5, sizeof loaded);
    const wc_cal_image_status_t status = wc_cal_image_load(image, sizeof image, &loaded);
    if (status.result != (uint32_t)WC_CAL_IMAGE_OK) {  /* nothing usable left: a zero set, which init refuses */
        static const wc_cal_set_t zero;
        assert_memory_equal(&loaded, &zero, sizeof zero);
        static wc_loop_t loop;
        assert_int_not_equal(wc_loop_init(&loop, &loaded.clutch, &loaded.loop, 40.0f), WC_CAL_OK);
    }
    return status;
}

static void set_outer_radius(wc_cal_set_t *s, uint32_t v) { (void)v; s->clutch.outer_radius_m = 0.0f; }
static void set_inner_radius(wc_cal_set_t *s, uint32_t v) { (void)v; s->clutch.inner_radius_m = s->clutch.outer_radius_m; }
static void set_mu1_nan(wc_cal_set_t *s, uint32_t v) { (void)v; s->clutch.mu1 = NAN; }
static void set_film_length(wc_cal_set_t *s, uint32_t v) { s->clutch.film.length = v; }
static void set_film_node(wc_cal_set_t *s, uint32_t v) { s->film_hbar_m[v] = s->film_hbar_m[v + 1u]; }
static void set_kp(wc_cal_set_t *s, uint32_t v) { (void)v; s->shift.kp_Nm_per_rad_s = -1.0f; }
static void set_theta_source(wc_cal_set_t *s, uint32_t v) { s->shift.theta_source = v; }
static void set_shift_word(wc_cal_set_t *s, uint32_t v) { memset((unsigned char *)&s->shift + 4u * v, 0x11, 4u); }
static void set_sensor_timeout(wc_cal_set_t *s, uint32_t v) { s->loop.sensor_timeout_periods = v; }
static void set_request_timeout(wc_cal_set_t *s, uint32_t v) { s->loop.request_timeout_periods = v; }
static void set_max_delta(wc_cal_set_t *s, uint32_t v) { s->loop.e2e.max_delta_counter = (uint8_t)v; }
static void set_sync(wc_cal_set_t *s, uint32_t v) { s->loop.e2e.sync_counter = (uint8_t)v; }
static void set_recovery(wc_cal_set_t *s, uint32_t v) { s->loop.recovery_periods = v; }
static void set_nothing(wc_cal_set_t *s, uint32_t v) { (void)s; (void)v; }

static void expect(change_t change, uint32_t value, bool shift, uint32_t result, uint32_t error, const char *what)
{
    const wc_cal_image_status_t status = load_changed(change, value, shift);
    WC_CHECK((status.result == result) && (status.error == error), "%s %u: result %s error %u (%s), expected %s %u",
             what, (unsigned)value, wc_cal_image_result_name(status.result), (unsigned)status.error,
             wc_cal_image_error_name(status), wc_cal_image_result_name(result), (unsigned)error);
}

static void test_clutch_and_shift_rules_give_their_codes(void **state)
{
    (void)state;
    const uint32_t clutch = WC_CAL_IMAGE_BAD_CLUTCH;
    const uint32_t shift = WC_CAL_IMAGE_BAD_SHIFT;
    expect(set_nothing, 0u, true, WC_CAL_IMAGE_OK, 0u, "valid");
    expect(set_nothing, 0u, false, WC_CAL_IMAGE_OK, 0u, "valid, shift off");
    expect(set_outer_radius, 0u, true, clutch, WC_CAL_OUTER_RADIUS, "outer radius 0");
    expect(set_inner_radius, 0u, true, clutch, WC_CAL_INNER_RADIUS, "inner radius = outer");
    expect(set_mu1_nan, 0u, true, clutch, WC_CAL_MU1, "mu1 NaN");
    expect(set_film_length, WC_CAL_IMAGE_FILM_NODES + 1u, true, clutch, WC_CAL_FILM_TABLE, "film length");
    expect(set_film_length, 0xFFFFFFFFu, true, clutch, WC_CAL_FILM_TABLE, "film length");
    expect(set_film_length, 1u, true, clutch, WC_CAL_FILM_TABLE, "film length (nodes past it not 0)");
    expect(set_film_node, 10u, true, clutch, WC_CAL_FILM_NOT_MONOTONE, "film node");
    /* table1 has 64 nodes: a shorter table (length 32) with its unused nodes not 0 */
    static wc_cal_set_t set;
    static wc_cal_set_t loaded;
    assert_true(wc_cal_set_from(&set, &wc_table1_calibration, NULL, NULL));
    set.clutch.film.length = 32u;
    uint8_t image[IMAGE_BYTES];
    assert_int_equal(wc_cal_image_write(&set, image, sizeof image), IMAGE_BYTES);
    wc_cal_image_status_t status = wc_cal_image_load(image, sizeof image, &loaded);
    assert_int_equal(status.result, WC_CAL_IMAGE_BAD_CLUTCH);
    assert_int_equal(status.error, WC_CAL_FILM_TABLE);
    for (uint32_t i = 32u; i < WC_CAL_IMAGE_FILM_NODES; ++i) {
        set.film_pressure_Pa[i] = 0.0f;
        set.film_hbar_m[i] = 0.0f;
        set.film_slope_m_per_Pa[i] = 0.0f;
    }
    assert_int_equal(wc_cal_image_write(&set, image, sizeof image), IMAGE_BYTES);
    status = wc_cal_image_load(image, sizeof image, &loaded);
    assert_int_equal(status.result, WC_CAL_IMAGE_BAD_CLUTCH);  /* 32 nodes no longer reach the maximum pressure */
    assert_int_equal(status.error, WC_CAL_FILM_COVERAGE);

    expect(set_kp, 0u, true, shift, WC_SHIFT_CAL_KP, "kp -1");
    expect(set_theta_source, 2u, true, shift, WC_SHIFT_CAL_THETA_SOURCE, "theta_source");
    /* shift control off: every shift word must be 0, and a nonzero one is named by its code */
    for (uint32_t w = 0u; 4u * w < (uint32_t)sizeof(wc_shift_calibration_t); ++w) {
        expect(set_shift_word, w, false, shift, (uint32_t)WC_SHIFT_CAL_TURBINE_INERTIA + w, "shift word, off");
    }
    expect(set_kp, 0u, false, shift, WC_SHIFT_CAL_KP, "kp -1, off");
    const wc_cal_image_status_t named = { WC_CAL_IMAGE_BAD_SHIFT, WC_SHIFT_CAL_KP };
    assert_string_equal(wc_cal_image_error_name(named), "shift.kp_Nm_per_rad_s");
    const wc_cal_image_status_t clutch_named = { WC_CAL_IMAGE_BAD_CLUTCH, WC_CAL_INNER_RADIUS };
    assert_string_equal(wc_cal_image_error_name(clutch_named), "inner_radius_m");
    assert_string_equal(wc_cal_image_result_name(WC_CAL_IMAGE_BAD_LOOP), "BAD_LOOP");
    assert_string_equal(wc_cal_image_result_name(WC_IMAGE_BAD_CRC), "BAD_CRC");
    assert_string_equal(wc_cal_image_result_name(99u), "unknown");
}

/* Each loop field at both ends of its limits (accepted) and one past them (refused with its code). */
static void test_loop_limits_give_their_codes(void **state)
{
    (void)state;
    static const struct {
        change_t change;
        uint32_t code;
        uint32_t lower;
        uint32_t upper;
        uint32_t past_upper;   /* the member's type may not hold more */
    } cases[] = {
        { set_sensor_timeout, WC_CAL_LOOP_SENSOR_TIMEOUT, 1u, 1000u, 1001u },
        { set_request_timeout, WC_CAL_LOOP_REQUEST_TIMEOUT, 1u, 1000u, 0xFFFFFFFFu },
        { set_max_delta, WC_CAL_LOOP_MAX_DELTA_COUNTER, 1u, 7u, 8u },
        { set_sync, WC_CAL_LOOP_SYNC_COUNTER, 1u, 15u, 255u },
        { set_recovery, WC_CAL_LOOP_RECOVERY, 1u, 10000u, 10001u },
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(cases); ++i) {
        expect(cases[i].change, cases[i].lower, true, WC_CAL_IMAGE_OK, 0u, "loop lower");
        expect(cases[i].change, cases[i].upper, true, WC_CAL_IMAGE_OK, 0u, "loop upper");
        expect(cases[i].change, cases[i].lower - 1u, true, WC_CAL_IMAGE_BAD_LOOP, cases[i].code, "loop below");
        expect(cases[i].change, cases[i].past_upper, true, WC_CAL_IMAGE_BAD_LOOP, cases[i].code, "loop above");
        assert_int_equal(wc_cal_image_loop_limits[cases[i].code - 1u].lower, cases[i].lower);
        assert_int_equal(wc_cal_image_loop_limits[cases[i].code - 1u].upper, cases[i].upper);
    }
    const wc_cal_image_status_t named = { WC_CAL_IMAGE_BAD_LOOP, WC_CAL_LOOP_SYNC_COUNTER };
    assert_string_equal(wc_cal_image_error_name(named), "loop.e2e.sync_counter");

    /* shift_enabled neither 0 nor 1 (the bool cannot say it: written into the payload, CRC right) */
    static wc_cal_set_t set;
    static wc_cal_set_t loaded;
    assert_true(wc_cal_set_from(&set, &wc_table1_calibration, &wc_shift_1_2_full, NULL));
    uint8_t image[IMAGE_BYTES];
    assert_int_equal(wc_cal_image_write(&set, image, sizeof image), IMAGE_BYTES);
    wc_image_put_u32(&image[WC_IMAGE_HEADER_BYTES + WC_CAL_IMAGE_OFFSET_LOOP_SHIFT_ENABLED], 2u);
    assert_int_equal(wc_image_seal(image, sizeof image, WC_CAL_IMAGE_MAGIC, WC_CAL_IMAGE_VERSION, PAYLOAD), IMAGE_BYTES);
    const wc_cal_image_status_t status = wc_cal_image_load(image, sizeof image, &loaded);
    assert_int_equal(status.result, WC_CAL_IMAGE_BAD_LOOP);
    assert_int_equal(status.error, WC_CAL_LOOP_SHIFT_ENABLED);
    assert_false(loaded.shift_enabled);
}

/* The status a flip of bit `bit` of a whole image must give. */
static uint32_t status_of_flip(size_t bit)
{
    return (bit < 32u) ? WC_IMAGE_BAD_MAGIC : (bit < 64u) ? WC_IMAGE_BAD_VERSION
                     : (bit < 128u) ? WC_IMAGE_BAD_LENGTH : WC_IMAGE_BAD_CRC;
}

static void test_every_bit_flip_and_truncation_is_refused(void **state)
{
    (void)state;
    static wc_cal_set_t set;
    static const wc_cal_set_t zero;
    for (size_t bit = 0u; bit < 8u * IMAGE_BYTES; ++bit) {
        uint8_t image[IMAGE_BYTES];
        memcpy(image, wc_table1_cal_image, sizeof image);
        image[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        memset(&set, 0x5A, sizeof set);
        const wc_cal_image_status_t status = wc_cal_image_load(image, sizeof image, &set);
        WC_CHECK(status.result == status_of_flip(bit), "bit %zu: result %u", bit, (unsigned)status.result);
        if ((bit % 61u) == 0u) { assert_memory_equal(&set, &zero, sizeof zero); }
    }
    for (size_t n = 0u; n < IMAGE_BYTES; ++n) {
        uint8_t *image = malloc(n > 0u ? n : 1u);  /* exactly n bytes: the sanitizer sees any read past them */
        assert_non_null(image);
        memcpy(image, wc_table1_cal_image, n);
        const wc_cal_image_status_t status = wc_cal_image_load(image, n, &set);
        WC_CHECK(status.result == ((n == 0u) ? (uint32_t)WC_IMAGE_MISSING : (uint32_t)WC_IMAGE_TRUNCATED),
                 "length %zu: result %u", n, (unsigned)status.result);
        free(image);
    }
    assert_int_equal(wc_cal_image_load(NULL, 0u, &set).result, WC_IMAGE_MISSING);
    /* the rest of a flash sector after the CRC is ignored */
    static uint8_t sector[4096];
    memset(sector, 0xFF, sizeof sector);
    memcpy(sector, wc_table1_cal_image, IMAGE_BYTES);
    assert_int_equal(wc_cal_image_load(sector, sizeof sector, &set).result, WC_CAL_IMAGE_OK);
}

static void test_set_from_refuses_what_the_image_cannot_hold(void **state)
{
    (void)state;
    static wc_cal_set_t set;
    wc_calibration_t cal = wc_table1_calibration;
    cal.film.length = WC_CAL_IMAGE_FILM_NODES + 1u;
    assert_false(wc_cal_set_from(&set, &cal, NULL, NULL));
    cal = wc_table1_calibration;
    cal.film.hbar_m = NULL;
    assert_false(wc_cal_set_from(&set, &cal, NULL, NULL));
    wc_loop_config_t loop = WC_LOOP_CONFIG_DEFAULT;
    loop.recovery_periods = 33u;
    loop.bench_input_enabled = true;
    assert_true(wc_cal_set_from(&set, &wc_table1_calibration, NULL, &loop));
    assert_int_equal(set.loop.recovery_periods, 33u);
    assert_false(set.loop.bench_input_enabled);  /* never from a calibration */
    assert_null(set.loop.shift);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_payload_size),
        cmocka_unit_test(test_golden_image_round_trip),
        cmocka_unit_test(test_committed_image_is_the_compiled_in_calibration),
        cmocka_unit_test(test_every_compiled_in_variant_round_trips),
        cmocka_unit_test(test_clutch_and_shift_rules_give_their_codes),
        cmocka_unit_test(test_loop_limits_give_their_codes),
        cmocka_unit_test(test_every_bit_flip_and_truncation_is_refused),
        cmocka_unit_test(test_set_from_refuses_what_the_image_cannot_hold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
