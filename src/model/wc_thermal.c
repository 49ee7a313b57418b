#include "wetclutch/wc_thermal.h"

#include <math.h>

#include "wc_internal.h"

wc_status_t wc_thermal_step(const wc_model_t *model, float *theta_degC, float power_W,
                            float theta_oil_degC, float theta_housing_degC)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    WC_ASSERT(theta_degC != NULL);
    wc_status_t status = WC_STATUS_OK;
    if (!(isfinite(power_W) && (power_W >= 0.0f))) { status |= WC_STATUS_POWER_INVALID; }
    if (!wc_theta_valid(theta_oil_degC) || !wc_theta_valid(theta_housing_degC)) {
        status |= WC_STATUS_THETA_INVALID;
    }
    if (status != WC_STATUS_OK) { return status; }  /* state untouched */

    const wc_calibration_t *cal = model->cal;
    const float k1 = cal->oil_conductance_W_per_K;
    const float k2 = cal->housing_conductance_W_per_K;
    /* eq. 1 at rest: C dtheta/dt = 0 */
    const float steady_degC = (power_W + k1 * theta_oil_degC + k2 * theta_housing_degC) / (k1 + k2);
    /* eq. 1 exact ZOH step; the decay factor was computed at init */
    *theta_degC = steady_degC + (*theta_degC - steady_degC) * model->thermal_decay;
    return WC_STATUS_OK;
}
