/* Oil dynamic viscosity, eq. 2. */
#ifndef WC_VISCOSITY_H
#define WC_VISCOSITY_H

#include "wc_calibration.h"

/* mu_v(theta) = mv1 e^(mv2 theta) + mv3 e^(mv4 theta), Pa s. The caller
 * passes a finite, plausible temperature (wc_torque checks it). */
float wc_viscosity_Pa_s(const wc_calibration_t *cal, float theta_degC);

#endif /* WC_VISCOSITY_H */
