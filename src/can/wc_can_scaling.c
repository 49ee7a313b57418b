/* Physical <-> raw conversion of one signal (wc_can_scaling.h). The signal
 * descriptors and the frames that use this are generated from
 * hil/wetclutch.dbc (src/can/generated/wc_can_signals.c). */
#include "wetclutch_can/wc_can_scaling.h"

#include <math.h>

/* ---- results ------------------------------------------------------------- */

bool wc_can_is_error(wc_can_result_t result)
{
    return result >= WC_CAN_ERR_NAN;
}

wc_can_result_t wc_can_worst(wc_can_result_t a, wc_can_result_t b)
{
    return (b > a) ? b : a;
}

/* ---- one signal ---------------------------------------------------------- */

wc_can_result_t wc_can_phys_to_raw(const wc_can_signal_t *sig, float value,
                                   int32_t *raw)
{
    float steps;

    if ((sig == NULL) || (raw == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
    if (isnan(value)) {
        *raw = sig->raw_nan;
        return WC_CAN_ERR_NAN;
    }
    /* Every raw limit is below 2^24 in magnitude, so it is exact in float and
     * the comparisons below decide saturation exactly; +-inf saturates. */
    steps = roundf((value - sig->offset) / sig->scale);
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

wc_can_result_t wc_can_raw_to_phys(const wc_can_signal_t *sig, int32_t raw,
                                   float *value)
{
    if ((sig == NULL) || (value == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
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
