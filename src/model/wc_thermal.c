#include "wetclutch/wc_thermal.h"

#include <math.h>

#include "wc_internal.h"

wc_status_t wc_thermal_step(const wc_model_t *model, float *theta_degC, float power_W,
                            float theta_oil_degC, float theta_housing_degC)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    WC_ASSERT(theta_degC != NULL);
    if ((model == NULL) || (model->cal == NULL) || (theta_degC == NULL)) { return WC_STATUS_NOT_INITIALISED; }
    wc_status_t status = WC_STATUS_OK;
    if (!(isfinite(power_W) && (power_W >= 0.0f))) { status |= WC_STATUS_POWER_INVALID; }
    if (!wc_theta_valid(theta_oil_degC) || !wc_theta_valid(theta_housing_degC)) {
        status |= WC_STATUS_THETA_INVALID;
    }
    if (status != WC_STATUS_OK) { return status; }  /* state untouched */

    *theta_degC = wc_thermal_advance(model, *theta_degC, power_W, theta_oil_degC, theta_housing_degC);
    return WC_STATUS_OK;
}
