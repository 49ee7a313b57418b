/* Lumped thermal observer of the friction-surface temperature, eq. 1,
 * discretized exactly for inputs held over one control period:
 * theta[k+1] = theta_ss + (theta[k] - theta_ss) a, a = exp(-(k1+k2) dt / C),
 * theta_ss = (P + k1 theta_oil + k2 theta_housing) / (k1 + k2). */
#ifndef WC_THERMAL_H
#define WC_THERMAL_H

#include "wc_model.h"
#include "wc_status.h"

/* Advance *theta_degC by one period with heat input power_W = |T dw|; the
 * result is kept in [WC_THETA_MIN_degC, WC_THETA_MAX_degC] (thermal envelope).
 * Invalid input: *theta_degC is left unchanged and the status says why. */
wc_status_t wc_thermal_step(const wc_model_t *model, float *theta_degC, float power_W,
                            float theta_oil_degC, float theta_housing_degC);

#endif /* WC_THERMAL_H */
