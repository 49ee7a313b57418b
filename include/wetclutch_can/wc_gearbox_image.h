/* The gearbox image: a gearbox's table (wc_gearbox_t, include/wetclutch/
 * wc_gearbox.h; DESIGN 15, issue 29) as a versioned, CRC-protected byte
 * block in the persistent image format of wc_image.h (DESIGN 13), so that a
 * TCU runs a gearbox it did not compile in: the table `wetclutch gearbox ...
 * --image FILE` writes from a gearbox description and a vehicle, the same
 * numbers as the header it generates (lut/wc_<name>_gearbox.h).
 *
 *     magic 0x42474357 (the bytes "WCGB"), layout version 1, payload
 *     wc_gearbox_image_payload_bytes, little-endian, byte by byte: the
 *     fields of tools/wetclutch/calibration/gearbox_image.py in its order
 *     (the single source: the generated codec src/can/generated/
 *     wc_gearbox_image_layout.c and the A2L's gearbox.* characteristics come
 *     from it); arrays whole at their bounds (WC_GEARBOX_GEARS_MAX,
 *     WC_GEARBOX_ELEMENTS_MAX, WC_GEARBOX_SHIFTS_MAX).
 * A change of the layout is a new version.
 *
 * One gearbox, one image: what the gearbox does not use is 0 (the gears it
 * does not have, the shifts past shift_count, the elements past
 * element_count), the narrow members (gear and element numbers, has_reverse)
 * hold values that fit them (0..255; 0 or 1). Checks, in this order (the
 * first failing one is the status): the image (wc_image_read: MISSING ..
 * BAD_CRC); the narrow members (BAD_FIELD, error = the word's byte offset);
 * wc_gearbox_check (BAD_GEARBOX, error = wc_gearbox_error_t); the unused
 * words 0 (BAD_FIELD). A refused image leaves the gearbox zeroed (never a
 * half-used table); the host programs refuse to start (wc_tcu, wc_replay
 * --gearbox-image FILE: one line naming the result and the field, exit 2).
 *
 * Calls: pure functions of their arguments (no state); every loop bounded by
 * a compile-time constant. */
#ifndef WC_GEARBOX_IMAGE_H
#define WC_GEARBOX_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include <wetclutch/wc_gearbox.h>
#include <wetclutch/wc_image.h>

#define WC_GEARBOX_IMAGE_MAGIC 0x42474357u   /* "WCGB" little-endian */
#define WC_GEARBOX_IMAGE_VERSION 1u

/* Why an image is not used: the image codes of wc_image.h, then these. */
typedef enum {
    WC_GEARBOX_IMAGE_OK = 0,
    WC_GEARBOX_IMAGE_BAD_FIELD = WC_IMAGE_STATUSES,  /* a narrow member out of its type, or an unused word not 0:
                                                      * error = its byte offset in the payload */
    WC_GEARBOX_IMAGE_BAD_GEARBOX,                    /* wc_gearbox_check failed: error = wc_gearbox_error_t */
    WC_GEARBOX_IMAGE_RESULTS
} wc_gearbox_image_result_t;

typedef struct {
    uint32_t result;   /* wc_image_status_t or wc_gearbox_image_result_t */
    uint32_t error;    /* BAD_FIELD: the payload offset; BAD_GEARBOX: wc_gearbox_error_t (wc_gearbox_error_name); else 0 */
} wc_gearbox_image_status_t;

/* The payload's length in bytes (generated with the layout), at most
 * WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES (static buffers; checked where generated). */
extern const uint32_t wc_gearbox_image_payload_bytes;
#define WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES 8192u

/* Reads and checks a whole image (image: length bytes) into gearbox. On
 * anything but OK gearbox is zeroed and the status says why. */
wc_gearbox_image_status_t wc_gearbox_image_load(const uint8_t *image, size_t length, wc_gearbox_t *gearbox);

/* Writes gearbox's image to image[0..capacity): returns its length,
 * WC_IMAGE_BYTES(wc_gearbox_image_payload_bytes); 0 when it does not fit or
 * an argument is NULL. The gearbox as it is, unchecked (the load checks): a
 * table that passes wc_gearbox_check but holds nonzero values where it does
 * not use them (a slip of an element past element_count) writes an image the
 * load refuses (BAD_FIELD). */
size_t wc_gearbox_image_write(const wc_gearbox_t *gearbox, uint8_t *image, size_t capacity);

/* The name of a result ("OK", "BAD_CRC", "BAD_FIELD", "BAD_GEARBOX";
 * "unknown"), and of what a status's error names: the layout's field
 * ("gearbox.shift.oncoming") for BAD_FIELD, wc_gearbox_error_t's for
 * BAD_GEARBOX ("SHIFT_SLIPS"), "" otherwise. For messages. */
const char *wc_gearbox_image_result_name(uint32_t result);
const char *wc_gearbox_image_error_name(wc_gearbox_image_status_t status);

#endif /* WC_GEARBOX_IMAGE_H */
