#include "wetclutch/wc_friction.h"

#include <math.h>
#include <stddef.h>

#include "wc_internal.h"

/* Speed / v_s beyond which the Stribeck term cannot change mu_f (see below). */
#define WC_STRIBECK_NEGLIGIBLE 30.0f

/* eq. 18 for a temperature in the model's domain (the inverse and the torque
 * model call it with a checked one), given as its temperature factor. */
float wc_friction_at(const wc_calibration_t *cal, float speed_m_s, float temperature_factor)
{
    /* eq. 18: Stribeck exponential in speed times a linear temperature term.
     * Above 30 Stribeck speeds e^-x < 1e-13: (mu2 - mu1) e^-x is below half an
     * ulp of mu1 unless |mu2 - mu1| > 6e5 mu1, so the sum is mu1 exactly and
     * the exponential is skipped. */
    const float x = fabsf(speed_m_s) / cal->stribeck_speed_m_s;
    const float decay = (x < WC_STRIBECK_NEGLIGIBLE) ? wc_exp(-x) : 0.0f;
    const float stribeck = cal->mu1 + (cal->mu2 - cal->mu1) * decay;
    return stribeck * temperature_factor;
}

float wc_friction_coefficient(const wc_calibration_t *cal, float speed_m_s, float theta_degC)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    /* Any input gives a finite, physical coefficient: a temperature outside the
     * domain is taken at its nearest end (NaN at the cold end); a speed that is
     * not a number counts as fast (the Stribeck term vanishes). */
    const float theta = (theta_degC >= WC_THETA_MIN_degC)
                            ? ((theta_degC <= WC_THETA_MAX_degC) ? theta_degC : WC_THETA_MAX_degC)
                            : WC_THETA_MIN_degC;
    return wc_friction_at(cal, speed_m_s, wc_friction_temperature_factor(cal, theta));
}
