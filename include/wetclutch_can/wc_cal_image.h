/* The calibration image: the clutch, shift and loop calibration of one
 * clutch as one versioned, CRC-protected byte block in the persistent image
 * format of wc_image.h (DESIGN 13). The firmware checks it at init (and the
 * XCP calibration page, wc_xcp.h, every time a master changes it) with the
 * same rules as the compiled-in calibration: wc_calibration_check,
 * wc_shift_calibration_check and the loop's limits below. An image that
 * fails any of them is not used at all (never a half-used calibration).
 *
 *     magic 0x49434357 (the bytes "WCCI"), layout version 1,
 *     payload WC_CAL_IMAGE_PAYLOAD_BYTES, little-endian, byte by byte: the
 *     fields of tools/wetclutch/calibration/image_layout.py in its order
 *     (the single source of the layout: the generated codec
 *     src/can/generated/wc_cal_image_layout.c and the A2L's characteristics
 *     come from it). The film table travels with a capacity of
 *     WC_CAL_IMAGE_FILM_NODES nodes and its length.
 * A change of the layout is a new version.
 *
 * The payload is also the XCP calibration page (wc_xcp.h): a master writes
 * it byte by byte at the A2L's addresses, and wc_cal_image_decode checks the
 * whole page before the loop uses any of it.
 *
 * Calls: pure functions of their arguments (no state); a wc_cal_set_t is
 * the caller's. Every loop bounded by a compile-time constant. */
#ifndef WC_CAL_IMAGE_H
#define WC_CAL_IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wc_loop.h"
#include <wetclutch/wc_calibration.h>
#include <wetclutch/wc_image.h>
#include <wetclutch/wc_shift.h>

#define WC_CAL_IMAGE_MAGIC 0x49434357u   /* "WCCI" little-endian */
#define WC_CAL_IMAGE_VERSION 1u
#define WC_CAL_IMAGE_FILM_NODES 64u      /* the film table's capacity in the image */

/* The on-target linker section of a compiled-in calibration image (its own
 * flash sector, replaceable without relinking). Empty on hosts. */
#ifndef WC_CAL_IMAGE_SECTION
#if defined(__arm__) && defined(__GNUC__)
#define WC_CAL_IMAGE_SECTION __attribute__((section(".wc_calibration"), used))
#else
#define WC_CAL_IMAGE_SECTION
#endif
#endif

/* A decoded calibration: it owns the film table's nodes (clutch.film points
 * into film_*), and loop.shift points at shift when shift_enabled. The loop
 * and the clutch keep pointers into it: it must outlive their use. */
typedef struct {
    wc_calibration_t clutch;
    float film_pressure_Pa[WC_CAL_IMAGE_FILM_NODES];
    float film_hbar_m[WC_CAL_IMAGE_FILM_NODES];
    float film_slope_m_per_Pa[WC_CAL_IMAGE_FILM_NODES];
    wc_shift_calibration_t shift;
    bool shift_enabled;              /* shift control on (the loop's config.shift = &shift) */
    wc_loop_config_t loop;           /* timeouts, E2E, recovery; shift as above; no hooks, no bench input */
} wc_cal_set_t;

/* Why an image or a page is not used: the image codes of wc_image.h, then these. */
typedef enum {
    WC_CAL_IMAGE_OK = 0,
    WC_CAL_IMAGE_BAD_CLUTCH = WC_IMAGE_STATUSES,  /* wc_calibration_check failed: error says which field */
    WC_CAL_IMAGE_BAD_SHIFT,                       /* wc_shift_calibration_check failed: error says which */
    WC_CAL_IMAGE_BAD_LOOP,                        /* a loop field outside its limit: error = its index */
    WC_CAL_IMAGE_RESULTS
} wc_cal_image_result_t;

typedef struct {
    uint32_t result;   /* wc_image_status_t or wc_cal_image_result_t */
    uint32_t error;    /* the failing field's code (wc_cal_error_t, wc_shift_cal_error_t, loop index); 0 */
} wc_cal_image_status_t;

/* The payload's length in bytes (generated with the layout). */
extern const uint32_t wc_cal_image_payload_bytes;
#define WC_CAL_IMAGE_PAYLOAD_MAX_BYTES 2048u   /* static buffers; the generated length is checked against it */

/* Decodes a payload (wc_cal_image_payload_bytes bytes) into set and checks
 * it whole. On anything but OK, set is left with no usable calibration
 * (do not use it) and the status says why. */
wc_cal_image_status_t wc_cal_image_decode(const uint8_t *payload, wc_cal_set_t *set);

/* Encodes set into payload (wc_cal_image_payload_bytes bytes). */
void wc_cal_image_encode(const wc_cal_set_t *set, uint8_t *payload);

/* Reads and checks a whole image (wc_image_read, then decode). */
wc_cal_image_status_t wc_cal_image_load(const uint8_t *image, size_t length, wc_cal_set_t *set);

/* Writes set's image to image[0..capacity): returns its length, 0 when it does not fit. */
size_t wc_cal_image_write(const wc_cal_set_t *set, uint8_t *image, size_t capacity);

#endif /* WC_CAL_IMAGE_H */
