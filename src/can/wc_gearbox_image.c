/* The gearbox image (wc_gearbox_image.h): the image format of wc_image.h
 * around the generated codec of wc_gearbox_image_layout.c, and the rules of
 * one gearbox, one image. */
#include "wetclutch_can/wc_gearbox_image.h"

#include <string.h>

#include "generated/wc_gearbox_image_layout.h"
#include "wetclutch/wc_config.h"

static wc_gearbox_image_status_t status_of(uint32_t result, uint32_t error)
{
    const wc_gearbox_image_status_t s = { result, error };
    return s;
}

static bool word_is_zero(const uint8_t *payload, uint32_t offset)
{
    return wc_image_get_u32(&payload[offset]) == 0u;
}

/* The first narrow member's word that does not fit its C type (its offset), or 0 (offset 0 is not narrow). */
static uint32_t narrow_out_of_type(const uint8_t *payload)
{
    for (size_t f = 0u; f < WC_GEARBOX_IMAGE_NARROW_FIELDS; ++f) {
        const wc_gearbox_image_narrow_t *n = &wc_gearbox_image_narrow[f];
        for (uint32_t i = 0u; i < n->count; ++i) {
            const uint32_t offset = (uint32_t)n->offset + 4u * i;
            if (wc_image_get_u32(&payload[offset]) > (uint32_t)n->max) { return offset; }
        }
    }
    return 0u;
}

/* The first nonzero word of row `row` of rows[] (all of it when unused, else its elements past
 * element_count), or 0. */
static uint32_t unused_nonzero(const uint8_t *payload, const wc_gearbox_image_rows_t *rows, size_t fields, uint32_t row,
                               bool used, uint32_t element_count)
{
    for (size_t f = 0u; f < fields; ++f) {
        const uint32_t start = (uint32_t)rows[f].offset + 4u * (uint32_t)rows[f].row_words * row;
        for (uint32_t w = 0u; w < rows[f].row_words; ++w) {
            const bool in_use = used && ((rows[f].per_element == 0u) || (w < element_count));
            if (!in_use && !word_is_zero(payload, start + 4u * w)) { return start + 4u * w; }
        }
    }
    return 0u;
}

static uint32_t first_unused_nonzero(const uint8_t *payload, const wc_gearbox_t *g)
{
    for (uint32_t gear = 0u; gear < WC_GEARBOX_GEARS_MAX; ++gear) {
        const bool used = (gear == WC_GEARBOX_REVERSE) ? g->has_reverse : (gear <= g->forward_gears);
        const uint32_t at = unused_nonzero(payload, wc_gearbox_image_gear_rows, WC_GEARBOX_IMAGE_GEAR_FIELDS, gear, used,
                                           g->element_count);
        if (at != 0u) { return at; }
    }
    for (uint32_t shift = 0u; shift < WC_GEARBOX_SHIFTS_MAX; ++shift) {
        const uint32_t at = unused_nonzero(payload, wc_gearbox_image_shift_rows, WC_GEARBOX_IMAGE_SHIFT_FIELDS, shift,
                                           shift < g->shift_count, g->element_count);
        if (at != 0u) { return at; }
    }
    return 0u;
}

wc_gearbox_image_status_t wc_gearbox_image_load(const uint8_t *image, size_t length, wc_gearbox_t *gearbox)
{
    WC_ASSERT(gearbox != NULL);
    if (gearbox == NULL) { return status_of((uint32_t)WC_IMAGE_MISSING, 0u); }
    (void)memset(gearbox, 0, sizeof *gearbox);
    const uint8_t *payload = NULL;
    const wc_image_status_t read = wc_image_read(image, length, WC_GEARBOX_IMAGE_MAGIC, WC_GEARBOX_IMAGE_VERSION,
                                                 WC_GEARBOX_IMAGE_PAYLOAD_BYTES, &payload);
    if (read != WC_IMAGE_OK) { return status_of((uint32_t)read, 0u); }
    wc_gearbox_image_status_t status = status_of((uint32_t)WC_GEARBOX_IMAGE_OK, 0u);
    const uint32_t narrow = narrow_out_of_type(payload);
    if (narrow != 0u) {
        status = status_of((uint32_t)WC_GEARBOX_IMAGE_BAD_FIELD, narrow);
    } else {
        wc_gearbox_image_layout_decode(payload, gearbox);
        const wc_gearbox_error_t error = wc_gearbox_check(gearbox);
        const uint32_t unused = (error == WC_GEARBOX_OK) ? first_unused_nonzero(payload, gearbox) : 0u;
        if (error != WC_GEARBOX_OK) {
            status = status_of((uint32_t)WC_GEARBOX_IMAGE_BAD_GEARBOX, (uint32_t)error);
        } else if (unused != 0u) {
            status = status_of((uint32_t)WC_GEARBOX_IMAGE_BAD_FIELD, unused);
        } else {
            /* used as it is */
        }
    }
    if (status.result != (uint32_t)WC_GEARBOX_IMAGE_OK) { (void)memset(gearbox, 0, sizeof *gearbox); }
    return status;
}

size_t wc_gearbox_image_write(const wc_gearbox_t *gearbox, uint8_t *image, size_t capacity)
{
    const size_t bytes = WC_IMAGE_BYTES((size_t)WC_GEARBOX_IMAGE_PAYLOAD_BYTES);
    if ((gearbox == NULL) || (image == NULL) || (capacity < bytes)) { return 0u; }
    wc_gearbox_image_layout_encode(gearbox, &image[WC_IMAGE_HEADER_BYTES]);
    return wc_image_seal(image, capacity, WC_GEARBOX_IMAGE_MAGIC, WC_GEARBOX_IMAGE_VERSION,
                         WC_GEARBOX_IMAGE_PAYLOAD_BYTES);
}

static const char *const result_names[] = {
    "OK", "MISSING", "TRUNCATED", "BAD_MAGIC", "BAD_VERSION", "BAD_LENGTH", "BAD_CRC", "BAD_FIELD", "BAD_GEARBOX",
};
WC_STATIC_ASSERT(sizeof result_names / sizeof result_names[0] == (size_t)WC_GEARBOX_IMAGE_RESULTS, result_name_per_code);

const char *wc_gearbox_image_result_name(uint32_t result)
{
    return (result < (uint32_t)WC_GEARBOX_IMAGE_RESULTS) ? result_names[result] : "unknown";
}

const char *wc_gearbox_image_error_name(wc_gearbox_image_status_t status)
{
    const char *name = "";
    if (status.result == (uint32_t)WC_GEARBOX_IMAGE_BAD_FIELD) {
        name = wc_gearbox_image_field_name(status.error);
    } else if (status.result == (uint32_t)WC_GEARBOX_IMAGE_BAD_GEARBOX) {
        name = wc_gearbox_error_name(status.error);
    } else {
        /* the image's own results name no field */
    }
    return (name != NULL) ? name : "unknown";
}
