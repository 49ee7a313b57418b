/* Internal: eq. 8 at a fixed operating point (slip, theta), where only the
 * film depends on the force. The inverse evaluates T(F_c) many times at one
 * point, so mu_f and mu_v (two expf each) are computed once. */
#ifndef WC_TORQUE_POINT_H
#define WC_TORQUE_POINT_H

#include "wetclutch/wc_model.h"

typedef struct {
    float coulomb_Nm_per_N;  /* R_eff N_c mu_f(v, theta), eq. 6 */
    float viscous_Nm_m;      /* R_eff N_c mu_v(theta) A_f v, eq. 7 times h_bar */
    float mu_f;
} wc_torque_point_t;

void wc_torque_point(const wc_model_t *model, float slip_rad_s, float theta_degC, wc_torque_point_t *point);

/* |T| at force_N (>= 0); *hbar_m receives the film used. */
float wc_torque_point_magnitude(const wc_model_t *model, const wc_torque_point_t *point, float force_N,
                                float *hbar_m);

#endif /* WC_TORQUE_POINT_H */
