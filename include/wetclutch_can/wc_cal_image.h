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
 * Unused bytes are 0: the film nodes past the table's length, and the whole
 * shift calibration when shift control is off (shift_enabled 0). A nonzero
 * one is refused (BAD_CLUTCH with WC_CAL_FILM_TABLE, BAD_SHIFT with the
 * field's code), so one calibration has one image (its CRC identifies it)
 * and nothing in a page looks like a calibration without being used.
 * wc_cal_set_from builds such a set from compiled-in calibrations.
 *
 * Checks, in this order (the first failing one is the status): the image
 * (wc_image_read: MISSING .. BAD_CRC); the film length (at most
 * WC_CAL_IMAGE_FILM_NODES) and the unused nodes; wc_calibration_check
 * (BAD_CLUTCH, error = wc_cal_error_t); shift_enabled 0 or 1 (BAD_LOOP);
 * wc_shift_calibration_check when on, the shift bytes 0 when off (BAD_SHIFT,
 * error = wc_shift_cal_error_t); the loop's limits (BAD_LOOP, error =
 * wc_cal_loop_error_t). The loop's limits are the layout's
 * (image_layout.py LOOP_LIMITS, with their reasons): timeouts 1..1000
 * periods, MaxDeltaCounter 1..7, SyncCounter 1..15, recovery 1..10000
 * periods.
 *
 * An image that is refused: the safe state. The library cannot run a
 * clutch without a calibration, so a refused image leaves the set zeroed
 * (wc_loop_init refuses it: never a half-used calibration), and the
 * integrator's documented reaction is the loop's safe state without the
 * loop: the solenoid at its minimum current (clutch released), no control,
 * and the integrator's status/diagnostic bit set with the result and error
 * below, until a valid image is loaded. The host programs (wc_tcu,
 * wc_replay --calibration-image FILE) refuse to start instead: one line
 * naming the result and the field (wc_cal_image_result_name,
 * wc_cal_image_error_name), exit code 2.
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

/* Which loop field is outside its limits (the error of BAD_LOOP), in the
 * layout's order. */
typedef enum {
    WC_CAL_LOOP_OK = 0,
    WC_CAL_LOOP_SHIFT_ENABLED,       /* shift_enabled neither 0 nor 1 */
    WC_CAL_LOOP_SENSOR_TIMEOUT,      /* sensor_timeout_periods outside 1..1000 */
    WC_CAL_LOOP_REQUEST_TIMEOUT,     /* request_timeout_periods outside 1..1000 */
    WC_CAL_LOOP_MAX_DELTA_COUNTER,   /* e2e.max_delta_counter outside 1..7 */
    WC_CAL_LOOP_SYNC_COUNTER,        /* e2e.sync_counter outside 1..15 */
    WC_CAL_LOOP_RECOVERY,            /* recovery_periods outside 1..10000 */
    WC_CAL_LOOP_ERRORS
} wc_cal_loop_error_t;

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

/* Writes set's image to image[0..capacity): returns its length, 0 when it does not fit.
 * The set as it is, unchecked (wc_cal_image_load checks). */
size_t wc_cal_image_write(const wc_cal_set_t *set, uint8_t *image, size_t capacity);

/* A set from compiled-in calibrations (lut/ headers): clutch copied with its
 * film nodes into the set's arrays (the rest 0) and clutch.film pointing at
 * them; shift copied and on when not NULL (else off and 0); loop's
 * timeouts, E2E and recovery copied (loop NULL: WC_LOOP_CONFIG_DEFAULT),
 * loop.shift = &set->shift or NULL, no bench input, no hooks. Unchecked.
 * False (set zeroed) when set or clutch is NULL, or the film table is longer
 * than WC_CAL_IMAGE_FILM_NODES or has a NULL array. */
bool wc_cal_set_from(wc_cal_set_t *set, const wc_calibration_t *clutch, const wc_shift_calibration_t *shift,
                     const wc_loop_config_t *loop);

/* The name of a result ("OK", "BAD_CRC", "BAD_SHIFT", ...; "unknown"), and
 * of the field a status's error names: wc_cal_error_name's for BAD_CLUTCH,
 * the layout's name ("shift.kp_Nm_per_rad_s", "loop.e2e.sync_counter") for
 * BAD_SHIFT and BAD_LOOP; "" for the image results. For messages. */
const char *wc_cal_image_result_name(uint32_t result);
const char *wc_cal_image_error_name(wc_cal_image_status_t status);

#endif /* WC_CAL_IMAGE_H */
