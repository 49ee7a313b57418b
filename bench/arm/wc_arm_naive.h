/* The naive baseline of the inverse, for the Cortex-M4F benchmark only: what
 * wc_inverse would cost without the h_bar(p_c) table. */
#ifndef WC_ARM_NAIVE_H
#define WC_ARM_NAIVE_H

#include <wetclutch/wetclutch.h>

/* Same contract as wc_inverse, and the outer bisection on F_c that
 * wc_inverse used before its segment search + Newton (src/model/wc_inverse.c
 * up to commit 823133d: the below-drag and saturated checks first, then
 * bracket [0, force_max], stop at 0.01 N or 24 halvings), but each torque
 * evaluation solves
 * eq. 15 for the separation h by a bounded bisection (expf, erfcf) and then
 * evaluates eq. 9 (erff, expf). Float only. Inputs are not range-checked:
 * the benchmark passes valid ones. */
wc_status_t wc_arm_naive_inverse(const wc_model_t *model, float slip_rad_s, float theta_degC,
                                 float torque_request_Nm, wc_inverse_t *out);

#endif /* WC_ARM_NAIVE_H */
