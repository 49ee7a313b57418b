#include "wetclutch/wc_friction.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"

float wc_friction_coefficient(const wc_calibration_t *cal, float speed_m_s, float theta_degC)
{
    WC_ASSERT(cal != NULL);
    /* eq. 18: Stribeck exponential in speed times a linear temperature term */
    const float stribeck = cal->mu1 + (cal->mu2 - cal->mu1) * expf(-fabsf(speed_m_s) / cal->stribeck_speed_m_s);
    return stribeck * (1.0f + cal->mu3 * (theta_degC - cal->theta1_degC) / cal->theta2_K);
}
