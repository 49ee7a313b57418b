/* Helpers shared by the library's modules; not part of the public API. */
#ifndef WC_INTERNAL_H
#define WC_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"

static inline bool wc_in_range(float x, float lo, float hi)
{
    /* false for NaN: every comparison with NaN is false */
    return (x >= lo) && (x <= hi);
}

static inline bool wc_slip_valid(float slip_rad_s)
{
    return wc_in_range(slip_rad_s, -WC_SLIP_MAX_rad_s, WC_SLIP_MAX_rad_s);
}

static inline bool wc_theta_valid(float theta_degC)
{
    return wc_in_range(theta_degC, WC_THETA_MIN_degC, WC_THETA_MAX_degC);
}

/* e^x within 2 ulp of expf on [-87, 88], in about a third of newlib's
 * instructions (src/model/wc_exp.c; tests/c/test_exp.c). */
float wc_exp(float x);

#endif /* WC_INTERNAL_H */
