/* The calibration image (include/wetclutch_can/wc_cal_image.h; DESIGN 13):
 * the checks around the generated codec (generated/wc_cal_image_layout.c). */
#include "wetclutch_can/wc_cal_image.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "generated/wc_cal_image_layout.h"
#include "wetclutch/wc_image.h"


/* The whole shift (DESIGN 14): an image holds one clutch calibration, which
 * the off-going clutch shares (the same lining in these transmissions). */
static void wc_cal_set_offgoing(wc_cal_set_t *set)
{
    set->loop.offgoing = ((set->loop.shift != NULL) && (set->shift.coordinator == 1u)) ? &set->clutch : NULL;
}

WC_STATIC_ASSERT(WC_CAL_IMAGE_LOOP_FIELDS == (uint32_t)WC_CAL_LOOP_ERRORS - 1u, one_limit_per_loop_code);
WC_STATIC_ASSERT(WC_CAL_IMAGE_OFFSET_LOOP_SHIFT_ENABLED == WC_CAL_IMAGE_LOOP_BEGIN, shift_enabled_first_loop_field);
/* the three film arrays follow each other, node i of each 4 * NODES bytes apart */
WC_STATIC_ASSERT(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M ==
                 WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_PRESSURE_PA + 4u * WC_CAL_IMAGE_FILM_NODES, film_arrays_adjacent);
WC_STATIC_ASSERT(WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_SLOPE_M_PER_PA ==
                 WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M + 4u * WC_CAL_IMAGE_FILM_NODES, film_arrays_adjacent_too);
/* a shift field's code is its word in the struct (wc_shift.c), which is its word in the layout */
WC_STATIC_ASSERT(WC_CAL_IMAGE_SHIFT_END - WC_CAL_IMAGE_SHIFT_BEGIN ==
                 4u * (uint32_t)(WC_SHIFT_CAL_ERRORS - WC_SHIFT_CAL_TURBINE_INERTIA), shift_word_per_code);
WC_STATIC_ASSERT(WC_CAL_IMAGE_PAYLOAD_BYTES <= WC_IMAGE_PAYLOAD_MAX_BYTES, payload_fits_the_format);

static wc_cal_image_status_t status_of(uint32_t result, uint32_t error)
{
    const wc_cal_image_status_t status = { result, error };
    return status;
}

/* Loop fields [first, last) of the payload inside their limits: 0, or the first failing field's code. */
static uint32_t loop_problem(const uint8_t *payload, uint32_t first, uint32_t last)
{
    for (uint32_t i = first; (i < last) && (i < WC_CAL_IMAGE_LOOP_FIELDS); ++i) {
        const wc_cal_image_limit_t *limit = &wc_cal_image_loop_limits[i];
        const uint32_t value = wc_image_get_u32(&payload[limit->offset]);
        if ((value < limit->lower) || (value > limit->upper)) { return i + 1u; }
    }
    return (uint32_t)WC_CAL_LOOP_OK;
}

/* The first nonzero word of payload[begin, end) (4-byte steps): its offset, or end. */
static uint32_t first_nonzero_word(const uint8_t *payload, uint32_t begin, uint32_t end)
{
    for (uint32_t offset = begin; (offset < end) && (offset < WC_CAL_IMAGE_PAYLOAD_BYTES); offset += 4u) {
        if (wc_image_get_u32(&payload[offset]) != 0u) { return offset; }
    }
    return end;
}

/* The film table's length and unused nodes (0 in each of the three arrays). */
static bool film_layout_valid(const uint8_t *payload, uint32_t length)
{
    if (length > WC_CAL_IMAGE_FILM_NODES) { return false; }
    for (uint32_t a = 0u; a < 3u; ++a) {
        const uint32_t array = WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_PRESSURE_PA + a * 4u * WC_CAL_IMAGE_FILM_NODES;
        const uint32_t end = array + 4u * WC_CAL_IMAGE_FILM_NODES;
        if (first_nonzero_word(payload, array + 4u * length, end) != end) { return false; }
    }
    return true;
}

/* The decoded set and its payload, checked whole in the header's order. */
static wc_cal_image_status_t check(const uint8_t *payload, const wc_cal_set_t *set)
{
    if (!film_layout_valid(payload, set->clutch.film.length)) {
        return status_of((uint32_t)WC_CAL_IMAGE_BAD_CLUTCH, (uint32_t)WC_CAL_FILM_TABLE);
    }
    const wc_cal_error_t clutch = wc_calibration_check(&set->clutch);
    if (clutch != WC_CAL_OK) { return status_of((uint32_t)WC_CAL_IMAGE_BAD_CLUTCH, (uint32_t)clutch); }
    const uint32_t enabled = loop_problem(payload, 0u, 1u);
    if (enabled != (uint32_t)WC_CAL_LOOP_OK) { return status_of((uint32_t)WC_CAL_IMAGE_BAD_LOOP, enabled); }
    if (set->shift_enabled) {
        const wc_shift_cal_error_t shift = wc_shift_calibration_check(&set->shift);
        if (shift != WC_SHIFT_CAL_OK) { return status_of((uint32_t)WC_CAL_IMAGE_BAD_SHIFT, (uint32_t)shift); }
    } else {
        const uint32_t nonzero = first_nonzero_word(payload, WC_CAL_IMAGE_SHIFT_BEGIN, WC_CAL_IMAGE_SHIFT_END);
        if (nonzero != WC_CAL_IMAGE_SHIFT_END) {
            return status_of((uint32_t)WC_CAL_IMAGE_BAD_SHIFT,
                             (uint32_t)WC_SHIFT_CAL_TURBINE_INERTIA + (nonzero - WC_CAL_IMAGE_SHIFT_BEGIN) / 4u);
        }
    }
    const uint32_t loop = loop_problem(payload, 1u, WC_CAL_IMAGE_LOOP_FIELDS);
    if (loop != (uint32_t)WC_CAL_LOOP_OK) { return status_of((uint32_t)WC_CAL_IMAGE_BAD_LOOP, loop); }
    return status_of((uint32_t)WC_CAL_IMAGE_OK, 0u);
}

wc_cal_image_status_t wc_cal_image_decode(const uint8_t *payload, wc_cal_set_t *set)
{
    WC_ASSERT((payload != NULL) && (set != NULL));
    if (set == NULL) { return status_of((uint32_t)WC_IMAGE_MISSING, 0u); }
    memset(set, 0, sizeof *set);  /* no pointer, hook or bench flag from anywhere but here */
    if (payload == NULL) { return status_of((uint32_t)WC_IMAGE_MISSING, 0u); }
    wc_cal_image_layout_decode(payload, set);
    set->clutch.film.pressure_Pa = set->film_pressure_Pa;
    set->clutch.film.hbar_m = set->film_hbar_m;
    set->clutch.film.slope_m_per_Pa = set->film_slope_m_per_Pa;
    const wc_cal_image_status_t status = check(payload, set);
    if (status.result == (uint32_t)WC_CAL_IMAGE_OK) {
        set->loop.shift = set->shift_enabled ? &set->shift : NULL;
        wc_cal_set_offgoing(set);
    } else {
        memset(set, 0, sizeof *set);  /* never a half-used calibration: wc_loop_init refuses a zero one */
    }
    return status;
}

void wc_cal_image_encode(const wc_cal_set_t *set, uint8_t *payload)
{
    WC_ASSERT((set != NULL) && (payload != NULL));
    if ((set == NULL) || (payload == NULL)) { return; }
    wc_cal_image_layout_encode(set, payload);
}

wc_cal_image_status_t wc_cal_image_load(const uint8_t *image, size_t length, wc_cal_set_t *set)
{
    WC_ASSERT(set != NULL);
    if (set == NULL) { return status_of((uint32_t)WC_IMAGE_MISSING, 0u); }
    const uint8_t *payload = NULL;
    const wc_image_status_t read = wc_image_read(image, length, WC_CAL_IMAGE_MAGIC, WC_CAL_IMAGE_VERSION,
                                                 WC_CAL_IMAGE_PAYLOAD_BYTES, &payload);
    if ((read != WC_IMAGE_OK) || (payload == NULL)) {
        memset(set, 0, sizeof *set);
        return status_of((uint32_t)read, 0u);
    }
    return wc_cal_image_decode(payload, set);
}

size_t wc_cal_image_write(const wc_cal_set_t *set, uint8_t *image, size_t capacity)
{
    WC_ASSERT(set != NULL);
    if ((set == NULL) || (image == NULL) || (capacity < (size_t)WC_IMAGE_BYTES(WC_CAL_IMAGE_PAYLOAD_BYTES))) {
        return 0u;
    }
    wc_cal_image_layout_encode(set, &image[WC_IMAGE_HEADER_BYTES]);
    return wc_image_seal(image, capacity, WC_CAL_IMAGE_MAGIC, WC_CAL_IMAGE_VERSION, WC_CAL_IMAGE_PAYLOAD_BYTES);
}

/* A calibration struct copied byte by byte: no C library call (the ARM
 * footprint check links only what its firmware uses; a struct assignment of
 * this size is a memcpy call). */
static void copy_bytes(void *destination, const void *source, size_t bytes)
{
    unsigned char *d = (unsigned char *)destination;
    const unsigned char *s = (const unsigned char *)source;
    for (size_t i = 0u; (i < bytes) && (i < sizeof(wc_shift_calibration_t) + sizeof(wc_calibration_t)); ++i) {
        d[i] = s[i];
    }
}

bool wc_cal_set_from(wc_cal_set_t *set, const wc_calibration_t *clutch, const wc_shift_calibration_t *shift,
                     const wc_loop_config_t *loop)
{
    WC_ASSERT((set != NULL) && (clutch != NULL));
    if (set == NULL) { return false; }
    memset(set, 0, sizeof *set);
    if ((clutch == NULL) || (clutch->film.length > WC_CAL_IMAGE_FILM_NODES) || (clutch->film.pressure_Pa == NULL) ||
        (clutch->film.hbar_m == NULL) || (clutch->film.slope_m_per_Pa == NULL)) {
        return false;
    }
    copy_bytes(&set->clutch, clutch, sizeof set->clutch);
    for (uint32_t i = 0u; (i < clutch->film.length) && (i < WC_CAL_IMAGE_FILM_NODES); ++i) {
        set->film_pressure_Pa[i] = clutch->film.pressure_Pa[i];
        set->film_hbar_m[i] = clutch->film.hbar_m[i];
        set->film_slope_m_per_Pa[i] = clutch->film.slope_m_per_Pa[i];
    }
    set->clutch.film.pressure_Pa = set->film_pressure_Pa;
    set->clutch.film.hbar_m = set->film_hbar_m;
    set->clutch.film.slope_m_per_Pa = set->film_slope_m_per_Pa;
    if (shift != NULL) {
        copy_bytes(&set->shift, shift, sizeof set->shift);
        set->shift_enabled = true;
    }
    const wc_loop_config_t defaults = WC_LOOP_CONFIG_DEFAULT;
    const wc_loop_config_t *from = (loop != NULL) ? loop : &defaults;
    set->loop.sensor_timeout_periods = from->sensor_timeout_periods;
    set->loop.request_timeout_periods = from->request_timeout_periods;
    set->loop.e2e = from->e2e;
    set->loop.recovery_periods = from->recovery_periods;
    set->loop.shift = set->shift_enabled ? &set->shift : NULL;
    wc_cal_set_offgoing(set);
    return true;
}

/* Indexed by the result code: wc_image_status_t's, then wc_cal_image_result_t's. */
static const char *const result_names[] = {
    "OK", "MISSING", "TRUNCATED", "BAD_MAGIC", "BAD_VERSION", "BAD_LENGTH", "BAD_CRC",
    "BAD_CLUTCH", "BAD_SHIFT", "BAD_LOOP",
};
WC_STATIC_ASSERT(sizeof result_names / sizeof result_names[0] == (size_t)WC_CAL_IMAGE_RESULTS, result_name_per_code);
WC_STATIC_ASSERT((uint32_t)WC_CAL_IMAGE_BAD_CLUTCH == (uint32_t)WC_IMAGE_STATUSES, results_follow_image_codes);

const char *wc_cal_image_result_name(uint32_t result)
{
    return (result < (uint32_t)WC_CAL_IMAGE_RESULTS) ? result_names[result] : "unknown";
}

const char *wc_cal_image_error_name(wc_cal_image_status_t status)
{
    const char *name = NULL;
    if (status.result == (uint32_t)WC_CAL_IMAGE_BAD_CLUTCH) {
        name = wc_cal_error_name((wc_cal_error_t)status.error);
    } else if ((status.result == (uint32_t)WC_CAL_IMAGE_BAD_SHIFT) &&
               (status.error >= (uint32_t)WC_SHIFT_CAL_TURBINE_INERTIA) &&
               (status.error < (uint32_t)WC_SHIFT_CAL_ERRORS)) {
        name = wc_cal_image_field_name(WC_CAL_IMAGE_SHIFT_BEGIN +
                                       4u * (status.error - (uint32_t)WC_SHIFT_CAL_TURBINE_INERTIA));
    } else if ((status.result == (uint32_t)WC_CAL_IMAGE_BAD_LOOP) && (status.error >= 1u) &&
               (status.error <= WC_CAL_IMAGE_LOOP_FIELDS)) {
        name = wc_cal_image_field_name(wc_cal_image_loop_limits[status.error - 1u].offset);
    } else if ((status.result == (uint32_t)WC_CAL_IMAGE_BAD_SHIFT) || (status.result == (uint32_t)WC_CAL_IMAGE_BAD_LOOP)) {
        name = "unknown";
    } else {
        name = "";
    }
    return (name != NULL) ? name : "unknown";
}
