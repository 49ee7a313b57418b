/* The adaptation image (include/wetclutch/wc_adapt_image.h; DESIGN 12). */
#include "wetclutch/wc_adapt_image.h"

#include <stddef.h>
#include <stdint.h>

#include "wetclutch/wc_adapt.h"
#include "wetclutch/wc_image.h"

/* The payload's offsets (the layout in wc_adapt_image.h). */
#define ADAPT_OFFSET_CLUTCH_ID 0u
#define ADAPT_OFFSET_SCALE 4u
#define ADAPT_OFFSET_CONFIDENCE (ADAPT_OFFSET_SCALE + (4u * WC_ADAPT_NODES))
#define ADAPT_OFFSET_FILM_FACTOR (ADAPT_OFFSET_CONFIDENCE + (4u * WC_ADAPT_NODES))
#define ADAPT_OFFSET_KISS_OFFSET (ADAPT_OFFSET_FILM_FACTOR + 4u)
#define ADAPT_OFFSET_SHIFTS_LEARNED (ADAPT_OFFSET_KISS_OFFSET + 4u)

/* The payload holds the clutch id and every field of wc_adapt_values_t, 4
 * bytes each: a field added to the values (or another WC_ADAPT_NODES) fails
 * here until the layout and its version follow. */
WC_STATIC_ASSERT(WC_ADAPT_IMAGE_PAYLOAD_BYTES == ADAPT_OFFSET_SHIFTS_LEARNED + 4u, adapt_image_payload_layout);
WC_STATIC_ASSERT(sizeof(wc_adapt_values_t) == 4u * (2u * WC_ADAPT_NODES + 3u), adapt_image_values_fields);
WC_STATIC_ASSERT(WC_ADAPT_IMAGE_BYTES == 76u, adapt_image_bytes);

size_t wc_adapt_image_write(const wc_adapt_t *adapt, uint32_t clutch_id, uint8_t *image, size_t capacity)
{
    WC_ASSERT(adapt != NULL);
    if ((adapt == NULL) || (image == NULL) || (capacity < (size_t)WC_ADAPT_IMAGE_BYTES)) { return 0u; }
    /* the payload encoded in place, then the header and the CRC around it */
    uint8_t *payload = &image[WC_IMAGE_HEADER_BYTES];
    const wc_adapt_values_t *v = &adapt->values;
    wc_image_put_u32(&payload[ADAPT_OFFSET_CLUTCH_ID], clutch_id);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        wc_image_put_f32(&payload[ADAPT_OFFSET_SCALE + (4u * i)], v->friction_scale[i]);
        wc_image_put_f32(&payload[ADAPT_OFFSET_CONFIDENCE + (4u * i)], v->confidence[i]);
    }
    wc_image_put_f32(&payload[ADAPT_OFFSET_FILM_FACTOR], v->film_factor);
    wc_image_put_f32(&payload[ADAPT_OFFSET_KISS_OFFSET], v->kiss_offset_Pa);
    wc_image_put_u32(&payload[ADAPT_OFFSET_SHIFTS_LEARNED], v->shifts_learned);
    return wc_image_seal(image, capacity, WC_ADAPT_IMAGE_MAGIC, WC_ADAPT_IMAGE_VERSION, WC_ADAPT_IMAGE_PAYLOAD_BYTES);
}

uint32_t wc_adapt_image_load(wc_adapt_t *adapt, const struct wc_shift_calibration *cal, uint32_t clutch_id,
                             const uint8_t *image, size_t length)
{
    WC_ASSERT(adapt != NULL);
    WC_ASSERT(cal != NULL);
    if (adapt == NULL) { return WC_ADAPT_IMAGE_BAD_VALUES; }
    const uint8_t *payload = NULL;
    uint32_t result = (uint32_t)wc_image_read(image, length, WC_ADAPT_IMAGE_MAGIC, WC_ADAPT_IMAGE_VERSION,
                                              WC_ADAPT_IMAGE_PAYLOAD_BYTES, &payload);
    if ((result == (uint32_t)WC_IMAGE_OK) && (payload != NULL)) {
        if (wc_image_get_u32(&payload[ADAPT_OFFSET_CLUTCH_ID]) != clutch_id) {
            result = WC_ADAPT_IMAGE_WRONG_CLUTCH;
        } else {
            /* decoded in place: a refused image's values are replaced by the defaults below, before
             * anyone sees them (the caller owns adapt, wc_adapt_image.h), and no 56-byte copy on the stack */
            wc_adapt_values_t *v = &adapt->values;
            for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
                v->friction_scale[i] = wc_image_get_f32(&payload[ADAPT_OFFSET_SCALE + (4u * i)]);
                v->confidence[i] = wc_image_get_f32(&payload[ADAPT_OFFSET_CONFIDENCE + (4u * i)]);
            }
            v->film_factor = wc_image_get_f32(&payload[ADAPT_OFFSET_FILM_FACTOR]);
            v->kiss_offset_Pa = wc_image_get_f32(&payload[ADAPT_OFFSET_KISS_OFFSET]);
            v->shifts_learned = wc_image_get_u32(&payload[ADAPT_OFFSET_SHIFTS_LEARNED]);
            if ((cal == NULL) || !wc_adapt_values_valid(v, cal)) { result = WC_ADAPT_IMAGE_BAD_VALUES; }
        }
    }
    adapt->status &= ~(WC_ADAPT_STATUS_IMAGE_MISSING | WC_ADAPT_STATUS_IMAGE_INVALID);
    if (result != (uint32_t)WC_IMAGE_OK) {
        wc_adapt_reset(adapt);
        adapt->status |= (result == (uint32_t)WC_IMAGE_MISSING) ? WC_ADAPT_STATUS_IMAGE_MISSING
                                                                : WC_ADAPT_STATUS_IMAGE_INVALID;
    }
    return result;
}
