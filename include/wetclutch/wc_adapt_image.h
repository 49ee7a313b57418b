/* The adaptation image: one clutch's learned values (wc_adapt_values_t,
 * wc_adapt.h) in the persistent image format of wc_image.h (DESIGN 12).
 * Read at init (wc_adapt_image_load), written at shift end through the
 * integrator's hook (wc_adapt_image_write into the integrator's buffer,
 * which the hook stores; the host programs write it to a file atomically).
 *
 *     magic 0x50414357 (the bytes "WCAP"), layout version 1,
 *     payload (WC_ADAPT_IMAGE_PAYLOAD_BYTES, little-endian):
 *       offset  0  clutch id                       u32
 *       offset  4  friction_scale[WC_ADAPT_NODES]  f32 each
 *       offset 24  confidence[WC_ADAPT_NODES]      f32 each
 *       offset 44  film_factor                     f32
 *       offset 48  kiss_offset_Pa                  f32
 *       offset 52  shifts_learned                  u32
 * A change of this layout (another field, another WC_ADAPT_NODES) is a new
 * version. tools/wetclutch/calibration/adaptation_image.py writes and reads
 * the same bytes.
 *
 * Calls: from the task that owns the clutch's wc_adapt_t (not beside a
 * wc_shift_step on the same instance). Any bytes give the calibration's
 * values or the image's checked values, never a crash or a read past
 * `length`. */
#ifndef WC_ADAPT_IMAGE_H
#define WC_ADAPT_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "wc_adapt.h"
#include "wc_image.h"

#define WC_ADAPT_IMAGE_MAGIC 0x50414357u    /* "WCAP" little-endian */
#define WC_ADAPT_IMAGE_VERSION 1u
/* clutch id, 2 x WC_ADAPT_NODES node values, film factor, kiss offset,
 * shifts learned: 4 bytes each (checked against the fields in wc_adapt_image.c) */
#define WC_ADAPT_IMAGE_PAYLOAD_BYTES 56u
#define WC_ADAPT_IMAGE_BYTES WC_IMAGE_BYTES(WC_ADAPT_IMAGE_PAYLOAD_BYTES)   /* 76 */

/* What wc_adapt_image_load found: the wc_image_status_t codes (OK, MISSING,
 * TRUNCATED, BAD_MAGIC, BAD_VERSION, BAD_LENGTH, BAD_CRC), then these. */
#define WC_ADAPT_IMAGE_WRONG_CLUTCH ((uint32_t)WC_IMAGE_STATUSES)          /* 7: another clutch's image */
#define WC_ADAPT_IMAGE_BAD_VALUES ((uint32_t)WC_IMAGE_STATUSES + 1u)       /* 8: outside the bands (wc_adapt_values_valid) */
#define WC_ADAPT_IMAGE_RESULTS ((uint32_t)WC_IMAGE_STATUSES + 2u)

/* Writes adapt's values as clutch clutch_id's image to image[0 ..):
 * returns WC_ADAPT_IMAGE_BYTES, or 0 (nothing written) when adapt or image
 * is NULL or capacity < WC_ADAPT_IMAGE_BYTES. */
size_t wc_adapt_image_write(const wc_adapt_t *adapt, uint32_t clutch_id, uint8_t *image, size_t capacity);

/* Loads clutch clutch_id's values from image (length bytes; NULL or 0: no
 * image). OK (0): adapt->values are the image's and the
 * WC_ADAPT_STATUS_IMAGE_* bits are cleared. Any other result:
 * wc_adapt_reset(adapt) (the calibration's values), then the status bit
 * WC_ADAPT_STATUS_IMAGE_MISSING for MISSING, WC_ADAPT_STATUS_IMAGE_INVALID
 * for every other reason (the other IMAGE bit cleared). The result: a
 * wc_image_status_t code, WC_ADAPT_IMAGE_WRONG_CLUTCH or
 * WC_ADAPT_IMAGE_BAD_VALUES (wc_adapt_values_valid(values, cal) false: a
 * value not finite or outside cal's bands). adapt and cal must not be NULL
 * (WC_ASSERT; with asserts off: BAD_VALUES, and adapt untouched when NULL). */
uint32_t wc_adapt_image_load(wc_adapt_t *adapt, const struct wc_shift_calibration *cal, uint32_t clutch_id,
                             const uint8_t *image, size_t length);

#endif /* WC_ADAPT_IMAGE_H */
