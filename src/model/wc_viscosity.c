#include "wetclutch/wc_viscosity.h"

#include <math.h>
#include <stddef.h>

#include "wc_internal.h"

float wc_viscosity_Pa_s(const wc_calibration_t *cal, float theta_degC)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    /* eq. 2 */
    return cal->viscosity_a1_Pa_s * wc_exp(cal->viscosity_b1_per_K * theta_degC) +
           cal->viscosity_a2_Pa_s * wc_exp(cal->viscosity_b2_per_K * theta_degC);
}
