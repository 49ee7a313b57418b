/* Coulomb friction coefficient map, eq. 18. */
#ifndef WC_FRICTION_H
#define WC_FRICTION_H

#include "wc_calibration.h"

/* mu_f(v, theta) = (mu1 + (mu2 - mu1) e^(-|v|/v_s)) (1 + mu3 (theta - theta1)/theta2).
 * speed_m_s is the sliding speed R_eff |dw| (eq. 4); its sign is ignored (NaN
 * counts as fast). A theta outside [WC_THETA_MIN_degC, WC_THETA_MAX_degC] is
 * taken at the nearest end, NaN at the cold end: the result is always in the
 * (0, 1] the calibration check guarantees on the domain. */
float wc_friction_coefficient(const wc_calibration_t *cal, float speed_m_s, float theta_degC);

#endif /* WC_FRICTION_H */
