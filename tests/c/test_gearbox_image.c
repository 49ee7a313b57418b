/* The gearbox image (include/wetclutch_can/wc_gearbox_image.h; issue 29):
 * Python's image of tools/gearboxes/8hp_shifts.toml (tests/vectors/
 * wc_8hp_gearbox_image.hex, written by tests/python/test_gearbox_image.py)
 * loads into exactly the compiled-in table (lut/wc_8hp_gearbox.h, generated
 * from the same shift table), and the C writer gives Python's bytes; every
 * rule of wc_gearbox_image.h refuses its corruption, naming the field, and
 * leaves the gearbox zeroed. */
#include "wc_test_support.h"

#include <string.h>

#include <wetclutch/wc_gearbox.h>
#include <wetclutch_can/wc_gearbox_image.h>

#include "generated/wc_gearbox_image_layout.h"
#include "wc_8hp_gearbox.h"

#define IMAGE_BYTES WC_IMAGE_BYTES(WC_GEARBOX_IMAGE_PAYLOAD_BYTES)

static uint8_t image[IMAGE_BYTES + 64u];
static wc_gearbox_t loaded;

/* Every field equal (floats bit for bit: the image and the header carry the same float). */
static void assert_same_gearbox(const wc_gearbox_t *a, const wc_gearbox_t *b)
{
    assert_int_equal(a->element_count, b->element_count);
    assert_int_equal(a->closed_per_gear, b->closed_per_gear);
    assert_int_equal(a->forward_gears, b->forward_gears);
    assert_int_equal(a->has_reverse, b->has_reverse);
    assert_memory_equal(a->ratio, b->ratio, sizeof a->ratio);
    assert_memory_equal(a->closed_mask, b->closed_mask, sizeof a->closed_mask);
    assert_memory_equal(a->holding_torque_per_Nm, b->holding_torque_per_Nm, sizeof a->holding_torque_per_Nm);
    assert_int_equal(a->shift_count, b->shift_count);
    for (uint32_t i = 0u; i < WC_GEARBOX_SHIFTS_MAX; ++i) {
        const wc_gearbox_shift_t *s = &a->shift[i];
        const wc_gearbox_shift_t *t = &b->shift[i];
        assert_int_equal(s->source_gear, t->source_gear);
        assert_int_equal(s->target_gear, t->target_gear);
        assert_int_equal(s->oncoming, t->oncoming);
        assert_int_equal(s->offgoing, t->offgoing);
        assert_memory_equal(s->slip, t->slip, sizeof s->slip);
        const float x[7] = { s->output_ratio, s->offgoing_ratio, s->oncoming_slip_scale, s->offgoing_slip_scale,
                             s->turbine_inertia_kg_m2, s->output_inertia_kg_m2, s->jerk_per_torque_rate };
        const float y[7] = { t->output_ratio, t->offgoing_ratio, t->oncoming_slip_scale, t->offgoing_slip_scale,
                             t->turbine_inertia_kg_m2, t->output_inertia_kg_m2, t->jerk_per_torque_rate };
        assert_memory_equal(x, y, sizeof x);
    }
}

static void assert_zeroed(const wc_gearbox_t *g)
{
    static const wc_gearbox_t zero;
    assert_same_gearbox(g, &zero);
}

static size_t golden(uint8_t *out, size_t capacity)
{
    return wc_test_read_hex(WC_TEST_VECTORS_DIR "/wc_8hp_gearbox_image.hex", out, capacity);
}

static void test_python_image_is_the_compiled_in_table(void **state)
{
    (void)state;
    const size_t n = golden(image, sizeof image);
    assert_int_equal(n, IMAGE_BYTES);
    const wc_gearbox_image_status_t s = wc_gearbox_image_load(image, n, &loaded);
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_OK);
    assert_int_equal(s.error, 0u);
    assert_same_gearbox(&loaded, &wc_gearbox_8hp);
}

static void test_c_writer_gives_pythons_bytes(void **state)
{
    (void)state;
    static uint8_t python[IMAGE_BYTES + 64u];
    const size_t n = golden(python, sizeof python);
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, image, sizeof image), IMAGE_BYTES);
    assert_memory_equal(image, python, n);
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, image, IMAGE_BYTES - 1u), 0u);
    assert_int_equal(wc_gearbox_image_write(NULL, image, sizeof image), 0u);
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, NULL, sizeof image), 0u);
}

/* The 8HP's image with one payload word replaced, sealed again (a valid CRC): the rules, not the CRC, refuse it. */
static wc_gearbox_image_status_t load_with_word(uint32_t offset, uint32_t word)
{
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, image, sizeof image), IMAGE_BYTES);
    wc_image_put_u32(&image[WC_IMAGE_HEADER_BYTES + offset], word);
    assert_int_equal(wc_image_seal(image, sizeof image, WC_GEARBOX_IMAGE_MAGIC, WC_GEARBOX_IMAGE_VERSION,
                                   WC_GEARBOX_IMAGE_PAYLOAD_BYTES), IMAGE_BYTES);
    (void)memset(&loaded, 0x5A, sizeof loaded);
    return wc_gearbox_image_load(image, IMAGE_BYTES, &loaded);
}

static void assert_bad_field(uint32_t offset, uint32_t word, const char *name)
{
    const wc_gearbox_image_status_t s = load_with_word(offset, word);
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_BAD_FIELD);
    assert_int_equal(s.error, offset);
    assert_string_equal(wc_gearbox_image_error_name(s), name);
    assert_zeroed(&loaded);
}

static void test_narrow_members_must_fit_their_type(void **state)
{
    (void)state;
    /* 256 + 3: as a uint8_t it would be element 3, a valid table with another element */
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_SHIFT_ONCOMING + 4u * 5u, 259u, "gearbox.shift.oncoming");
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_SHIFT_SOURCE_GEAR, 0x101u, "gearbox.shift.source_gear");
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_HAS_REVERSE, 2u, "gearbox.has_reverse");
}

static void test_unused_words_must_be_zero(void **state)
{
    (void)state;
    /* a shift past shift_count (36), a gear past forward_gears (8), an element past element_count (5) */
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_SHIFT_OUTPUT_RATIO + 4u * 40u, 0x3F800000u, "gearbox.shift.output_ratio");
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_RATIO + 4u * 9u, 0x3F000000u, "gearbox.ratio");
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_SHIFT_SLIP_A + 4u * (2u * WC_GEARBOX_ELEMENTS_MAX + 5u), 0x3F800000u,
                     "gearbox.shift.slip_a");
    assert_bad_field(WC_GEARBOX_IMAGE_OFFSET_HOLDING_TORQUE_PER_NM + 4u * (3u * WC_GEARBOX_ELEMENTS_MAX + 5u),
                     0x80000000u, "gearbox.holding_torque_per_Nm");   /* -0: not the zero word */
}

static void test_the_gearbox_check_applies(void **state)
{
    (void)state;
    const uint32_t nan_word = 0x7FC00000u;
    wc_gearbox_image_status_t s = load_with_word(WC_GEARBOX_IMAGE_OFFSET_RATIO + 4u * 3u, nan_word);
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_BAD_GEARBOX);
    assert_int_equal(s.error, WC_GEARBOX_GEAR_RATIO);
    assert_string_equal(wc_gearbox_image_error_name(s), "GEAR_RATIO");
    assert_string_equal(wc_gearbox_image_result_name(s.result), "BAD_GEARBOX");
    assert_zeroed(&loaded);
    s = load_with_word(WC_GEARBOX_IMAGE_OFFSET_SHIFT_ONCOMING, 1u);   /* 1-2 closes E (4), not B */
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_BAD_GEARBOX);
    assert_int_equal(s.error, WC_GEARBOX_SHIFT_ELEMENTS);
    s = load_with_word(WC_GEARBOX_IMAGE_OFFSET_SHIFT_COUNT, 65u);
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_BAD_GEARBOX);
    assert_int_equal(s.error, WC_GEARBOX_COUNTS);
    s = load_with_word(WC_GEARBOX_IMAGE_OFFSET_SHIFT_TURBINE_INERTIA_KG_M2, 0u);
    assert_int_equal(s.result, WC_GEARBOX_IMAGE_BAD_GEARBOX);
    assert_int_equal(s.error, WC_GEARBOX_SHIFT_MODEL);
    assert_string_equal(wc_gearbox_error_name(WC_GEARBOX_SHIFT_MODEL), "SHIFT_MODEL");
    assert_string_equal(wc_gearbox_error_name(WC_GEARBOX_ERRORS), "unknown");
}

static void test_the_image_format_applies(void **state)
{
    (void)state;
    assert_int_equal(wc_gearbox_image_write(&wc_gearbox_8hp, image, sizeof image), IMAGE_BYTES);
    wc_gearbox_image_status_t s = wc_gearbox_image_load(image, IMAGE_BYTES - 1u, &loaded);
    assert_int_equal(s.result, WC_IMAGE_TRUNCATED);
    assert_string_equal(wc_gearbox_image_error_name(s), "");
    assert_zeroed(&loaded);
    image[WC_IMAGE_HEADER_BYTES + 100u] ^= 0x01u;
    s = wc_gearbox_image_load(image, IMAGE_BYTES, &loaded);
    assert_int_equal(s.result, WC_IMAGE_BAD_CRC);
    assert_string_equal(wc_gearbox_image_result_name(s.result), "BAD_CRC");
    assert_int_equal(wc_gearbox_image_load(NULL, 0u, &loaded).result, WC_IMAGE_MISSING);
    /* a calibration image is not a gearbox image */
    assert_int_equal(wc_image_seal(image, sizeof image, 0x49434357u, 1u, WC_GEARBOX_IMAGE_PAYLOAD_BYTES), IMAGE_BYTES);
    assert_int_equal(wc_gearbox_image_load(image, IMAGE_BYTES, &loaded).result, WC_IMAGE_BAD_MAGIC);
    assert_string_equal(wc_gearbox_image_result_name(99u), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_python_image_is_the_compiled_in_table),
        cmocka_unit_test(test_c_writer_gives_pythons_bytes),
        cmocka_unit_test(test_narrow_members_must_fit_their_type),
        cmocka_unit_test(test_unused_words_must_be_zero),
        cmocka_unit_test(test_the_gearbox_check_applies),
        cmocka_unit_test(test_the_image_format_applies),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
