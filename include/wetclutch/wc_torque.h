/* Clutch torque model, eq. 3-8: Coulomb plus viscous friction. */
#ifndef WC_TORQUE_H
#define WC_TORQUE_H

#include "wc_model.h"
#include "wc_status.h"

typedef struct {
    float torque_Nm;   /* T = T_c + T_v, eq. 5/8; sign of the slip (slip >= 0: positive) */
    float coulomb_Nm;  /* T_c, eq. 6 */
    float viscous_Nm;  /* T_v, eq. 7 */
    float hbar_m;      /* h_bar(F_c / A_f), eq. 9, 15, 16 */
    float mu_f;        /* eq. 18 */
} wc_torque_t;

/* Torque transmitted by the slipping clutch: positive for slip >= 0, negative
 * for slip < 0, i.e. the friction acts against the slip on the faster member.
 * At zero slip the value is the static capacity mu_f(0) F_c R_eff N_c.
 * Invalid input (NaN, Inf, out of range, negative force): *out is zero torque
 * with the open-clutch film, and the status says which input was wrong. */
wc_status_t wc_torque(const wc_model_t *model, float slip_rad_s, float theta_degC, float force_N,
                      wc_torque_t *out);

#endif /* WC_TORQUE_H */
