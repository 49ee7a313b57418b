/* Internal: the scaling of one signal as inline functions, so that the
 * generated frame codec (generated/wc_can_signals.c), where every descriptor
 * is a constant of the same translation unit, gets them inlined and folded
 * (DESIGN section 11: about half the instructions of a frame). The public
 * wc_can_phys_to_raw / wc_can_raw_to_phys (wc_can_scaling.c) check their
 * pointers and call these; the semantics are described in wc_can_scaling.h. */
#ifndef WC_CAN_SCALING_INLINE_H
#define WC_CAN_SCALING_INLINE_H

#include <math.h>
#include <stdint.h>

#include "wetclutch/wc_config.h"
#include "wetclutch_can/wc_can_scaling.h"

WC_INLINE_HOT wc_can_result_t wc_can_worst_of(wc_can_result_t a, wc_can_result_t b)
{
    return (b > a) ? b : a;
}

/* roundf for |x| <= 2^24: to nearest, ties away from zero. The conversion to
 * int truncates toward zero and x - t is exact, so this equals roundf
 * bit for bit, in a handful of instructions instead of a newlib call. */
WC_INLINE_HOT float wc_can_round_half_away(float x)
{
    const float t = (float)(int32_t)x;
    const float r = x - t;
    if (r >= 0.5f) { return t + 1.0f; }
    if (r <= -0.5f) { return t - 1.0f; }
    return t;
}

/* Physical -> raw; sig and raw are valid pointers. */
WC_INLINE_HOT wc_can_result_t wc_can_scale_to_raw(const wc_can_signal_t *sig, float value, int32_t *raw)
{
    if (isnan(value)) {
        *raw = sig->raw_nan;
        return WC_CAN_ERR_NAN;
    }
    /* Every raw limit is below 2^24 in magnitude, so it is exact in float and
     * the comparisons below decide saturation exactly; +-inf saturates. A
     * value beyond [raw_min - 1, raw_max + 1] saturates before rounding (it
     * would after rounding too), which keeps the rounding in its range. */
    const float unrounded = (value - sig->offset) / sig->scale;
    const float lowest = (float)sig->raw_min - 1.0f;
    const float highest = (float)sig->raw_max + 1.0f;
    const float steps =
        wc_can_round_half_away((unrounded < lowest) ? lowest : ((unrounded > highest) ? highest : unrounded));
    if (steps < (float)sig->raw_min) {
        *raw = sig->raw_min;
        return WC_CAN_SATURATED;
    }
    if (steps > (float)sig->raw_max) {
        *raw = sig->raw_max;
        return WC_CAN_SATURATED;
    }
    *raw = (int32_t)steps;
    return WC_CAN_OK;
}

/* Raw -> physical; sig and value are valid pointers. */
WC_INLINE_HOT wc_can_result_t wc_can_scale_to_phys(const wc_can_signal_t *sig, int32_t raw, float *value)
{
    if (sig->has_sna && (raw == sig->raw_sna)) {
        *value = NAN;
        return WC_CAN_ERR_SNA;
    }
    *value = ((float)raw * sig->scale) + sig->offset;
    if ((raw < sig->raw_min) || (raw > sig->raw_max)) {
        return WC_CAN_ERR_RANGE;
    }
    return WC_CAN_OK;
}

#endif /* WC_CAN_SCALING_INLINE_H */
