/* A validated calibration plus the constants derived from it once, at init
 * (R_eff, the exact discretization factors), so that no step recomputes
 * them. One per clutch; wc_clutch_t holds one. */
#ifndef WC_MODEL_H
#define WC_MODEL_H

#include "wc_calibration.h"

typedef struct {
    const wc_calibration_t *cal;
    float effective_radius_m;   /* R_eff, eq. 3 */
    float force_max_N;          /* contact force at the solenoid's maximum current */
    float hbar_at_force_max_m;  /* h_bar(force_max_N / A_f): the inverse's saturation test */
    float thermal_decay;        /* a = exp(-(k1 + k2) dt / C), eq. 1 exact ZOH */
    float vfs_decay;            /* exp(-dt / tau), VFS first-order lag */
    float film_damping_m4;      /* 3 pi phi K / 2: the squeeze film's damping per unit of mu_v (DESIGN 9); 0: off */
} wc_model_t;

/* Validate cal (wc_calibration_check) and derive the constants. On error the
 * model is left unusable (cal = NULL) and the failing field is returned. */
wc_cal_error_t wc_model_init(wc_model_t *model, const wc_calibration_t *cal);

#endif /* WC_MODEL_H */
