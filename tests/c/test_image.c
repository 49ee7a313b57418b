/* The persistent image format (wc_image.h) and the adaptation image
 * (wc_adapt_image.h): CRC-32 against its check value and a bitwise
 * reference, the layout byte by byte, every single-bit flip and every
 * truncation detected and named, wrong fields with a right CRC, the C writer
 * byte-identical with Python's golden image (tests/vectors/
 * wc_adapt_image_golden.hex, written by tests/python/test_image.py for the
 * values of golden_values() here), and a load that falls back to the
 * calibration's values with a status bit for every bad image. */
#include "wc_test_support.h"

#include <stdio.h>
#include <stdlib.h>

#include "wc_test_fixtures.h"
#include "wetclutch/wc_adapt_image.h"
#include "wetclutch/wc_image.h"

#define MAGIC 0x50414357u
#define PAYLOAD_BYTES 56u
#define IMAGE_BYTES WC_IMAGE_BYTES(PAYLOAD_BYTES)
#define GOLDEN_CLUTCH 2u

/* CRC-32 bit by bit (the definition: reflected 0xEDB88320), to check the table form. */
static uint32_t crc32_bitwise(const uint8_t *data, size_t length)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0u; i < length; ++i) {
        crc ^= data[i];
        for (unsigned k = 0u; k < 8u; ++k) { crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u))); }
    }
    return ~crc;
}

/* A deterministic byte stream (LCG) for payloads and arbitrary images. */
static uint8_t next_byte(uint32_t *seed)
{
    *seed = *seed * 1664525u + 1013904223u;
    return (uint8_t)(*seed >> 24);
}

/* A generic image of PAYLOAD_BYTES payload bytes 0, 1, 2, ... */
static void make_image(uint8_t image[IMAGE_BYTES])
{
    uint8_t payload[PAYLOAD_BYTES];
    for (unsigned i = 0u; i < PAYLOAD_BYTES; ++i) { payload[i] = (uint8_t)i; }
    assert_int_equal(wc_image_write(image, IMAGE_BYTES, MAGIC, 1u, payload, PAYLOAD_BYTES), IMAGE_BYTES);
}

/* The CRC recomputed over [0, 16 + PAYLOAD_BYTES): a field wrong on purpose, the CRC right. */
static void reseal(uint8_t image[IMAGE_BYTES])
{
    wc_image_put_u32(&image[16u + PAYLOAD_BYTES], crc32_bitwise(image, 16u + PAYLOAD_BYTES));
}

/* The status a flip of bit `bit` of a whole image must give. */
static wc_image_status_t status_of_flip(size_t bit)
{
    return (bit < 32u) ? WC_IMAGE_BAD_MAGIC : (bit < 64u) ? WC_IMAGE_BAD_VERSION
                     : (bit < 128u) ? WC_IMAGE_BAD_LENGTH : WC_IMAGE_BAD_CRC;
}

/* ---- the generic format ----------------------------------------------------- */

static void test_crc32(void **state)
{
    (void)state;
    static const uint8_t check[] = "123456789";
    assert_int_equal(wc_image_crc32(check, 9u), 0xCBF43926u);
    assert_int_equal(wc_image_crc32(check, 0u), 0u);
    assert_int_equal(wc_image_crc32(NULL, 0u), 0u);
    uint8_t buffer[300];
    uint32_t seed = 1u;
    for (size_t n = 0u; n <= sizeof buffer; ++n) {
        for (size_t i = 0u; i < n; ++i) { buffer[i] = next_byte(&seed); }
        WC_CHECK(wc_image_crc32(buffer, n) == crc32_bitwise(buffer, n), "length %zu", n);
    }
}

static void test_little_endian_fields(void **state)
{
    (void)state;
    uint8_t b[4];
    wc_image_put_u32(b, 0x11223344u);
    assert_memory_equal(b, "\x44\x33\x22\x11", 4u);
    assert_int_equal(wc_image_get_u32(b), 0x11223344u);
    wc_image_put_f32(b, 1.0f);
    assert_memory_equal(b, "\x00\x00\x80\x3f", 4u);
    assert_true(wc_test_same_float(wc_image_get_f32(b), 1.0f));
    static const float specials[] = { -0.0f, INFINITY, -INFINITY, FLT_MIN / 4.0f, FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(specials); ++i) {
        wc_image_put_f32(b, specials[i]);
        assert_true(wc_test_same_float(wc_image_get_f32(b), specials[i]));
    }
    wc_image_put_u32(b, 0x7FA00001u);  /* a signalling NaN's payload travels as bits */
    wc_image_put_f32(b, wc_image_get_f32(b));
    assert_int_equal(wc_image_get_u32(b), 0x7FA00001u);
}

static void test_round_trip_and_layout(void **state)
{
    (void)state;
    uint8_t image[IMAGE_BYTES + 8u];
    memset(image, 0xFF, sizeof image);
    make_image(image);
    assert_memory_equal(image, "\x57\x43\x41\x50\x01\x00\x00\x00\x38\x00\x00\x00\x00\x00\x00\x00", 16u);
    for (unsigned i = 0u; i < PAYLOAD_BYTES; ++i) { assert_int_equal(image[16u + i], i); }
    assert_int_equal(wc_image_get_u32(&image[16u + PAYLOAD_BYTES]), crc32_bitwise(image, 16u + PAYLOAD_BYTES));
    assert_int_equal(image[IMAGE_BYTES], 0xFFu);  /* nothing written past the image */

    const uint8_t *payload = NULL;
    assert_int_equal(wc_image_read(image, IMAGE_BYTES, MAGIC, 1u, PAYLOAD_BYTES, &payload), WC_IMAGE_OK);
    assert_ptr_equal(payload, &image[16]);
    /* the rest of a flash sector after the CRC is ignored */
    assert_int_equal(wc_image_read(image, sizeof image, MAGIC, 1u, PAYLOAD_BYTES, &payload), WC_IMAGE_OK);
    assert_int_equal(wc_image_read(image, IMAGE_BYTES, MAGIC, 1u, PAYLOAD_BYTES, NULL), WC_IMAGE_OK);

    /* sealed in place, or written with the payload already in place: the same bytes */
    uint8_t sealed[IMAGE_BYTES];
    for (unsigned i = 0u; i < PAYLOAD_BYTES; ++i) { sealed[16u + i] = (uint8_t)i; }
    assert_int_equal(wc_image_seal(sealed, sizeof sealed, MAGIC, 1u, PAYLOAD_BYTES), IMAGE_BYTES);
    assert_memory_equal(sealed, image, IMAGE_BYTES);
    uint8_t in_place[IMAGE_BYTES];
    for (unsigned i = 0u; i < PAYLOAD_BYTES; ++i) { in_place[16u + i] = (uint8_t)i; }
    assert_int_equal(wc_image_write(in_place, sizeof in_place, MAGIC, 1u, &in_place[16], PAYLOAD_BYTES), IMAGE_BYTES);
    assert_memory_equal(in_place, image, IMAGE_BYTES);

    /* an empty payload */
    uint8_t empty[WC_IMAGE_BYTES(0u)];
    assert_int_equal(wc_image_write(empty, sizeof empty, 9u, 3u, NULL, 0u), sizeof empty);
    assert_int_equal(wc_image_read(empty, sizeof empty, 9u, 3u, 0u, &payload), WC_IMAGE_OK);
    assert_ptr_equal(payload, &empty[16]);
}

static void test_write_refuses_what_does_not_fit(void **state)
{
    (void)state;
    uint8_t payload[PAYLOAD_BYTES] = { 0u };
    uint8_t image[IMAGE_BYTES];
    for (size_t capacity = 0u; capacity < IMAGE_BYTES; ++capacity) {
        memset(image, 0xA5, sizeof image);
        assert_int_equal(wc_image_write(image, capacity, MAGIC, 1u, payload, PAYLOAD_BYTES), 0u);
        assert_int_equal(wc_image_seal(image, capacity, MAGIC, 1u, PAYLOAD_BYTES), 0u);
        for (size_t i = 0u; i < sizeof image; ++i) { WC_CHECK(image[i] == 0xA5u, "capacity %zu wrote byte %zu", capacity, i); }
    }
    assert_int_equal(wc_image_write(NULL, IMAGE_BYTES, MAGIC, 1u, payload, PAYLOAD_BYTES), 0u);
    assert_int_equal(wc_image_seal(NULL, IMAGE_BYTES, MAGIC, 1u, PAYLOAD_BYTES), 0u);
    assert_int_equal(wc_image_write(image, IMAGE_BYTES, MAGIC, 1u, NULL, 1u), 0u);
    /* longer than the format allows, whatever the capacity claims (refused before any byte is written) */
    assert_int_equal(wc_image_write(image, SIZE_MAX, MAGIC, 1u, payload, WC_IMAGE_PAYLOAD_MAX_BYTES + 1u), 0u);
    assert_int_equal(wc_image_seal(image, SIZE_MAX, MAGIC, 1u, 0xFFFFFFFFu), 0u);
}

static void test_every_single_bit_flip_is_detected(void **state)
{
    (void)state;
    uint8_t good[IMAGE_BYTES];
    make_image(good);
    for (size_t bit = 0u; bit < 8u * IMAGE_BYTES; ++bit) {
        uint8_t image[IMAGE_BYTES];
        memcpy(image, good, sizeof image);
        image[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        const uint8_t *payload = good;
        const wc_image_status_t status = wc_image_read(image, sizeof image, MAGIC, 1u, PAYLOAD_BYTES, &payload);
        WC_CHECK(status == status_of_flip(bit), "bit %zu: status %d", bit, (int)status);
        assert_null(payload);
    }
}

static void test_every_truncation_is_detected(void **state)
{
    (void)state;
    uint8_t good[IMAGE_BYTES];
    make_image(good);
    for (size_t n = 0u; n < IMAGE_BYTES; ++n) {
        /* exactly n bytes on the heap: the address sanitizer (host-debug) reports any read past them */
        uint8_t *image = malloc(n > 0u ? n : 1u);
        assert_non_null(image);
        memcpy(image, good, n);
        const uint8_t *payload = good;
        const wc_image_status_t status = wc_image_read(image, n, MAGIC, 1u, PAYLOAD_BYTES, &payload);
        WC_CHECK(status == ((n == 0u) ? WC_IMAGE_MISSING : WC_IMAGE_TRUNCATED), "length %zu: status %d", n,
                 (int)status);
        assert_null(payload);
        free(image);
    }
    assert_int_equal(wc_image_read(NULL, IMAGE_BYTES, MAGIC, 1u, PAYLOAD_BYTES, NULL), WC_IMAGE_MISSING);
}

static void test_a_wrong_field_with_a_right_crc_is_named(void **state)
{
    (void)state;
    static const struct {
        size_t offset;
        uint32_t value;
        wc_image_status_t expected;
    } cases[] = {
        { 0u, MAGIC + 1u, WC_IMAGE_BAD_MAGIC },  { 4u, 2u, WC_IMAGE_BAD_VERSION },
        { 4u, 0u, WC_IMAGE_BAD_VERSION },        { 8u, 52u, WC_IMAGE_BAD_LENGTH },
        { 8u, 60u, WC_IMAGE_BAD_LENGTH },        { 8u, 0xFFFFFFFFu, WC_IMAGE_BAD_LENGTH },
        { 12u, 1u, WC_IMAGE_BAD_LENGTH },        { 12u, 0x80000000u, WC_IMAGE_BAD_LENGTH },
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(cases); ++i) {
        uint8_t image[IMAGE_BYTES];
        make_image(image);
        wc_image_put_u32(&image[cases[i].offset], cases[i].value);
        reseal(image);
        const wc_image_status_t status = wc_image_read(image, sizeof image, MAGIC, 1u, PAYLOAD_BYTES, NULL);
        WC_CHECK(status == cases[i].expected, "case %zu: status %d", i, (int)status);
    }
    /* a caller that expects the largest u32 length: BAD_LENGTH (over the format's limit), no overflow */
    uint8_t header[WC_IMAGE_BYTES(0u)];
    assert_int_equal(wc_image_write(header, sizeof header, MAGIC, 1u, NULL, 0u), sizeof header);
    wc_image_put_u32(&header[8], 0xFFFFFFFFu);
    assert_int_equal(wc_image_read(header, sizeof header, MAGIC, 1u, 0xFFFFFFFFu, NULL), WC_IMAGE_BAD_LENGTH);
}

/* ---- the adaptation image ---------------------------------------------------- */

/* The values of tests/python/test_image.py's GOLDEN_VALUES. */
static wc_adapt_values_t golden_values(void)
{
    const wc_adapt_values_t v = { { 1.05f, 0.97f, 1.0f, 1.125f, 0.9f }, { 0.25f, 0.5f, 0.0f, 1.0f, 0.125f },
                                  1.5f, -1234.5f, 42u };
    return v;
}

/* The golden image (wc_test_read_hex). */
static size_t read_golden(uint8_t *out, size_t capacity)
{
    return wc_test_read_hex(WC_TEST_VECTORS_DIR "/wc_adapt_image_golden.hex", out, capacity);
}

static void assert_defaults(const wc_adapt_t *adapt)
{
    wc_adapt_t reference;
    memset(&reference, 0, sizeof reference);
    wc_adapt_reset(&reference);
    assert_memory_equal(&adapt->values, &reference.values, sizeof reference.values);
    for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
        assert_true(wc_test_same_float(adapt->values.friction_scale[i], 1.0f));
        assert_true(wc_test_same_float(adapt->values.confidence[i], 0.0f));
    }
    assert_true(wc_test_same_float(adapt->values.film_factor, 1.0f));
    assert_true(wc_test_same_float(adapt->values.kiss_offset_Pa, 0.0f));
}

/* An instance holding the golden values and both image bits plus RESET. */
static wc_adapt_t learned(void)
{
    wc_adapt_t adapt;
    memset(&adapt, 0, sizeof adapt);
    adapt.values = golden_values();
    adapt.status = WC_ADAPT_STATUS_IMAGE_MISSING | WC_ADAPT_STATUS_IMAGE_INVALID | WC_ADAPT_STATUS_RESET;
    return adapt;
}

static const wc_shift_calibration_t shift_cal = WC_TEST_SHIFT_CALIBRATION;

/* A failed load: the result, the calibration's values, the status bit, RESET kept. */
static void expect_fallback(const uint8_t *image, size_t length, uint32_t clutch_id, uint32_t expected, size_t index)
{
    wc_adapt_t adapt = learned();
    const uint32_t result = wc_adapt_image_load(&adapt, &shift_cal, clutch_id, image, length);
    WC_CHECK(result == expected, "case %zu: load gave %u, expected %u", index, (unsigned)result, (unsigned)expected);
    assert_defaults(&adapt);
    const uint32_t bit = (expected == (uint32_t)WC_IMAGE_MISSING) ? WC_ADAPT_STATUS_IMAGE_MISSING
                                                                  : WC_ADAPT_STATUS_IMAGE_INVALID;
    assert_int_equal(adapt.status, bit | WC_ADAPT_STATUS_RESET);
}

static void test_c_writer_gives_the_golden_bytes(void **state)
{
    (void)state;
    uint8_t golden[IMAGE_BYTES + 1u];
    assert_int_equal(read_golden(golden, sizeof golden), WC_ADAPT_IMAGE_BYTES);
    const wc_adapt_t adapt = learned();
    uint8_t image[WC_ADAPT_IMAGE_BYTES];
    assert_int_equal(wc_adapt_image_write(&adapt, GOLDEN_CLUTCH, image, sizeof image), WC_ADAPT_IMAGE_BYTES);
    assert_memory_equal(image, golden, WC_ADAPT_IMAGE_BYTES);
    for (size_t capacity = 0u; capacity < WC_ADAPT_IMAGE_BYTES; ++capacity) {
        assert_int_equal(wc_adapt_image_write(&adapt, GOLDEN_CLUTCH, image, capacity), 0u);
    }
    assert_int_equal(wc_adapt_image_write(&adapt, GOLDEN_CLUTCH, NULL, sizeof image), 0u);
}

static void test_load_round_trip(void **state)
{
    (void)state;
    uint8_t golden[IMAGE_BYTES];
    assert_int_equal(read_golden(golden, sizeof golden), WC_ADAPT_IMAGE_BYTES);
    wc_adapt_t adapt;
    memset(&adapt, 0, sizeof adapt);
    wc_adapt_reset(&adapt);
    adapt.status = WC_ADAPT_STATUS_IMAGE_MISSING | WC_ADAPT_STATUS_IMAGE_INVALID | WC_ADAPT_STATUS_RESET;
    assert_int_equal(wc_adapt_image_load(&adapt, &shift_cal, GOLDEN_CLUTCH, golden, sizeof golden), WC_IMAGE_OK);
    const wc_adapt_values_t expected = golden_values();
    assert_memory_equal(&adapt.values, &expected, sizeof expected);
    assert_int_equal(adapt.status, WC_ADAPT_STATUS_RESET);  /* the image bits cleared, RESET not */
}

static void test_load_missing_wrong_clutch_and_version(void **state)
{
    (void)state;
    uint8_t golden[IMAGE_BYTES];
    assert_int_equal(read_golden(golden, sizeof golden), WC_ADAPT_IMAGE_BYTES);
    expect_fallback(NULL, 0u, GOLDEN_CLUTCH, WC_IMAGE_MISSING, 0u);
    expect_fallback(golden, 0u, GOLDEN_CLUTCH, WC_IMAGE_MISSING, 1u);
    expect_fallback(golden, sizeof golden, GOLDEN_CLUTCH + 1u, WC_ADAPT_IMAGE_WRONG_CLUTCH, 2u);
    wc_image_put_u32(&golden[4], WC_ADAPT_IMAGE_VERSION + 1u);
    reseal(golden);
    expect_fallback(golden, sizeof golden, GOLDEN_CLUTCH, WC_IMAGE_BAD_VERSION, 3u);
}

static void test_load_every_bit_flip_and_truncation_falls_back(void **state)
{
    (void)state;
    uint8_t golden[IMAGE_BYTES];
    assert_int_equal(read_golden(golden, sizeof golden), WC_ADAPT_IMAGE_BYTES);
    for (size_t bit = 0u; bit < 8u * IMAGE_BYTES; ++bit) {
        uint8_t image[IMAGE_BYTES];
        memcpy(image, golden, sizeof image);
        image[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        expect_fallback(image, sizeof image, GOLDEN_CLUTCH, (uint32_t)status_of_flip(bit), bit);
    }
    for (size_t n = 0u; n < IMAGE_BYTES; ++n) {
        uint8_t *image = malloc(n > 0u ? n : 1u);
        assert_non_null(image);
        memcpy(image, golden, n);
        expect_fallback(image, n, GOLDEN_CLUTCH, (n == 0u) ? (uint32_t)WC_IMAGE_MISSING : (uint32_t)WC_IMAGE_TRUNCATED, n);
        free(image);
    }
}

/* Values outside the bands, in a well-formed image (right CRC): the calibration's values. */
static void test_load_out_of_band_values_fall_back(void **state)
{
    (void)state;
    const float band = shift_cal.adapt_scale_band;
    for (unsigned k = 0u; k < 12u; ++k) {
        wc_adapt_t adapt = learned();
        wc_adapt_values_t *v = &adapt.values;
        switch (k) {
        case 0: v->friction_scale[0] = 5.0f; break;
        case 1: v->friction_scale[4] = NAN; break;
        case 2: v->friction_scale[2] = 1.0f + 2.0f * band; break;
        case 3: v->friction_scale[1] = -INFINITY; break;
        case 4: v->confidence[1] = 2.0f; break;
        case 5: v->confidence[3] = -0.1f; break;
        case 6: v->confidence[0] = NAN; break;
        case 7: v->film_factor = shift_cal.adapt_film_factor_max * 2.0f; break;
        case 8: v->film_factor = shift_cal.adapt_film_factor_min * 0.5f; break;
        case 9: v->film_factor = INFINITY; break;
        case 10: v->kiss_offset_Pa = -2.0f * shift_cal.adapt_kiss_band_Pa - 1.0f; break;
        default: v->kiss_offset_Pa = NAN; break;
        }
        uint8_t image[WC_ADAPT_IMAGE_BYTES];
        assert_int_equal(wc_adapt_image_write(&adapt, 7u, image, sizeof image), WC_ADAPT_IMAGE_BYTES);
        expect_fallback(image, sizeof image, 7u, WC_ADAPT_IMAGE_BAD_VALUES, k);
    }
}

/* A float near the band [center - half, center + half]: a quarter of the
 * draws outside it, some not finite. */
static float draw(uint32_t *seed, float center, float half)
{
    const uint8_t pick = next_byte(seed);
    if (pick < 8u) {
        static const float specials[8] = { NAN, INFINITY, -INFINITY, -0.0f, FLT_MAX, -FLT_MAX, FLT_MIN, 1e30f };
        return specials[pick];
    }
    const float u = (float)next_byte(seed) / 255.0f;  /* 0..1 */
    return center + half * (2.5f * u - 1.25f);
}

/* Arbitrary bytes, and well-formed images (right CRC) of values around the
 * bands: every load leaves values that wc_adapt_values_valid accepts, and
 * the status bit says whether the image was taken (a smaller sibling of the
 * fuzz harness, run in every ctest). */
static void test_load_any_bytes_leaves_valid_values(void **state)
{
    (void)state;
    const float scale_band = shift_cal.adapt_scale_band;
    const float film_center = 0.5f * (shift_cal.adapt_film_factor_min + shift_cal.adapt_film_factor_max);
    const float film_half = 0.5f * (shift_cal.adapt_film_factor_max - shift_cal.adapt_film_factor_min);
    uint32_t seed = 20u;
    unsigned results[WC_ADAPT_IMAGE_RESULTS] = { 0u };
    for (unsigned trial = 0u; trial < 20000u; ++trial) {
        uint8_t image[IMAGE_BYTES];
        if ((trial % 4u) == 0u) {
            for (size_t i = 0u; i < sizeof image; ++i) { image[i] = next_byte(&seed); }
        } else {
            wc_adapt_t source;
            memset(&source, 0, sizeof source);
            for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
                /* most draws in band: the whole image passes now and then */
                source.values.friction_scale[i] = (trial % 4u == 1u) ? draw(&seed, 1.0f, scale_band) : 1.0f;
                source.values.confidence[i] = (trial % 4u == 2u) ? draw(&seed, 0.5f, 0.5f) : 0.5f;
            }
            source.values.film_factor = draw(&seed, film_center, film_half);
            source.values.kiss_offset_Pa = draw(&seed, 0.0f, shift_cal.adapt_kiss_band_Pa);
            source.values.shifts_learned = (uint32_t)next_byte(&seed) << 24;
            assert_int_equal(wc_adapt_image_write(&source, 3u, image, sizeof image), IMAGE_BYTES);
        }
        wc_adapt_t adapt = learned();
        const uint32_t result = wc_adapt_image_load(&adapt, &shift_cal, 3u, image, sizeof image);
        WC_CHECK(result < WC_ADAPT_IMAGE_RESULTS, "trial %u: result %u", trial, (unsigned)result);
        WC_CHECK(wc_adapt_values_valid(&adapt.values, &shift_cal), "trial %u: invalid values kept", trial);
        WC_CHECK((result == (uint32_t)WC_IMAGE_OK) == ((adapt.status & WC_ADAPT_STATUS_IMAGE_INVALID) == 0u),
                 "trial %u: status 0x%x for result %u", trial, (unsigned)adapt.status, (unsigned)result);
        results[result] += 1u;
    }
    print_message("    20000 images: %u loaded, %u bad values, %u bad magic\n", results[WC_IMAGE_OK],
                  results[WC_ADAPT_IMAGE_BAD_VALUES], results[WC_IMAGE_BAD_MAGIC]);
    assert_true(results[WC_IMAGE_OK] > 1000u);                  /* the value check lets good values through */
    assert_true(results[WC_ADAPT_IMAGE_BAD_VALUES] > 1000u);    /* and stops the others */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32),
        cmocka_unit_test(test_little_endian_fields),
        cmocka_unit_test(test_round_trip_and_layout),
        cmocka_unit_test(test_write_refuses_what_does_not_fit),
        cmocka_unit_test(test_every_single_bit_flip_is_detected),
        cmocka_unit_test(test_every_truncation_is_detected),
        cmocka_unit_test(test_a_wrong_field_with_a_right_crc_is_named),
        cmocka_unit_test(test_c_writer_gives_the_golden_bytes),
        cmocka_unit_test(test_load_round_trip),
        cmocka_unit_test(test_load_missing_wrong_clutch_and_version),
        cmocka_unit_test(test_load_every_bit_flip_and_truncation_falls_back),
        cmocka_unit_test(test_load_out_of_band_values_fall_back),
        cmocka_unit_test(test_load_any_bytes_leaves_valid_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
