/* Physical <-> raw conversion of one signal (wc_can_scaling.h). The signal
 * descriptors and the frames that use this are generated from
 * hil/wetclutch.dbc (src/can/generated/wc_can_signals.c). */
#include "wetclutch_can/wc_can_scaling.h"

#include <stddef.h>

#include "wc_can_scaling_inline.h"

/* ---- results ------------------------------------------------------------- */

bool wc_can_is_error(wc_can_result_t result)
{
    return result >= WC_CAN_ERR_NAN;
}

wc_can_result_t wc_can_worst(wc_can_result_t a, wc_can_result_t b)
{
    return wc_can_worst_of(a, b);
}

/* ---- one signal ---------------------------------------------------------- */

wc_can_result_t wc_can_phys_to_raw(const wc_can_signal_t *sig, float value,
                                   int32_t *raw)
{
    if ((sig == NULL) || (raw == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
    return wc_can_scale_to_raw(sig, value, raw);
}

wc_can_result_t wc_can_raw_to_phys(const wc_can_signal_t *sig, int32_t raw,
                                   float *value)
{
    if ((sig == NULL) || (value == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
    return wc_can_scale_to_phys(sig, raw, value);
}
