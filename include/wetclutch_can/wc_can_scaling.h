/* Physical <-> raw conversion for the frames of hil/wetclutch.dbc, and
 * whole-frame encode/decode with E2E protection.
 *
 * Why this exists: the cantools-generated codec (generated/wc_can.[ch], made
 * with --no-floating-point-numbers) only packs and unpacks raw integers. Its
 * own floating-point encode (not generated here) truncates instead of
 * rounding (cantools issue 635), converts out-of-range values with undefined
 * behaviour, and goes through a `double` helper. This wrapper does the
 * scaling in single precision instead:
 *
 *   encode  raw = roundf((value - offset) / scale)   round to nearest, ties
 *                                                     away from zero
 *           raw limited to [raw_min, raw_max], the raw values of the DBC
 *           [minimum|maximum] (-> WC_CAN_SATURATED, frame still sent);
 *           NaN -> raw_nan (-> WC_CAN_ERR_NAN, frame still sent): the SNA
 *           value for signals that have one, 0 mA / 0 kPa for VfsCurrent /
 *           PressureCommand (no solenoid current); +-inf saturate.
 *   decode  value = raw * scale + offset
 *           raw == SNA            -> value NaN,        WC_CAN_ERR_SNA
 *           raw outside [min,max] -> value unclamped,  WC_CAN_ERR_RANGE
 *
 * Note: cantools in Python rounds with round() (ties to even); this code
 * rounds ties away from zero (as cantools' --use-round C code does). They can
 * differ by one raw step only for a value exactly half a step from two raw
 * values, which needs a binary scale (0.25 rpm, 1/32 mA, 1/16 kPa).
 *
 * The descriptors (one wc_can_signal_t per signal), the frame structs in
 * physical units and the whole-frame encode/decode are generated from the
 * DBC into wc_can_signals.h / src/can/generated/wc_can_signals.c by
 * tools/gen_can_codec.sh; tests/c/test_can_codec.c checks raw_min/raw_max
 * against cantools' is_in_range functions and tests/python/test_dbc.py
 * checks every signal's conversion against cantools in Python.
 *
 * Portable C99: no heap, no stdio, float only, no global mutable state.
 */
#ifndef WC_CAN_SCALING_H
#define WC_CAN_SCALING_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Result of a conversion, ordered by severity (a frame reports the worst
 *  of its signals). Values >= WC_CAN_ERR_NAN are errors. */
typedef enum {
    WC_CAN_OK = 0,
    WC_CAN_SATURATED = 1,  /**< encode: value limited to [min, max] */
    WC_CAN_ERR_NAN = 2,    /**< encode: NaN, the signal's raw_nan was sent */
    WC_CAN_ERR_RANGE = 3,  /**< decode: raw outside [min, max] (or reserved Mode) */
    WC_CAN_ERR_SNA = 4,    /**< decode: raw is "signal not available" */
    WC_CAN_ERR_CRC = 5,    /**< decode: E2E CRC mismatch, nothing decoded */
    WC_CAN_ERR_SIZE = 6    /**< NULL pointer or buffer shorter than 8 bytes */
} wc_can_result_t;

/** True for WC_CAN_ERR_*. */
bool wc_can_is_error(wc_can_result_t result);

/** The more severe of two results. */
wc_can_result_t wc_can_worst(wc_can_result_t a, wc_can_result_t b);

/** Scaling of one signal, as in the DBC: value = raw * scale + offset. */
typedef struct {
    float scale;     /**< DBC factor, physical unit per raw step */
    float offset;    /**< DBC offset, physical unit */
    int32_t raw_min; /**< raw value of the DBC minimum */
    int32_t raw_max; /**< raw value of the DBC maximum */
    int32_t raw_nan; /**< raw value the encoder sends for NaN */
    int32_t raw_sna; /**< reserved "signal not available" raw (if has_sna) */
    bool has_sna;
} wc_can_signal_t;

/** Physical -> raw, as described at the top. *raw is always written
 *  (unless a pointer is NULL: WC_CAN_ERR_SIZE). */
wc_can_result_t wc_can_phys_to_raw(const wc_can_signal_t *sig, float value,
                                   int32_t *raw);

/** Raw -> physical, as described at the top. *value is always written. */
wc_can_result_t wc_can_raw_to_phys(const wc_can_signal_t *sig, int32_t raw,
                                   float *value);

#ifdef __cplusplus
}
#endif

#endif /* WC_CAN_SCALING_H */
