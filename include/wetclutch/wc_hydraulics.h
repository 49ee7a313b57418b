/* Piston, return spring and variable-force solenoid (VFS).
 * Piston: F_app = P A_p - F_s (zero below the spring force).
 * VFS: steady pressure P = K i; the reached pressure lags with time constant tau. */
#ifndef WC_HYDRAULICS_H
#define WC_HYDRAULICS_H

#include "wc_model.h"
#include "wc_status.h"

/* Piston pressure that holds contact force force_N against the spring, Pa
 * (a force outside [0, WC_FORCE_MAX_N] is limited to it, NaN to 0). */
float wc_piston_pressure_Pa(const wc_calibration_t *cal, float force_N);

/* Contact force from piston pressure, N: 0 below the spring preload (and for
 * NaN), at most WC_FORCE_MAX_N. */
float wc_contact_force_N(const wc_calibration_t *cal, float pressure_Pa);

/* VFS current for a pressure, clamped to [vfs_current_min, vfs_current_max];
 * WC_STATUS_CURRENT_CLAMPED when clamped (NaN gives the minimum, clamped). */
wc_status_t wc_vfs_current_mA(const wc_calibration_t *cal, float pressure_Pa, float *current_mA);

/* One control period of the VFS first-order lag towards K * current_mA,
 * exact for a current held over the period. Returns the reached pressure, Pa.
 * A current outside the solenoid's range is limited to it (NaN: the minimum);
 * a reached pressure that is not finite restarts from rest. */
float wc_vfs_lag_step(const wc_model_t *model, float pressure_reached_Pa, float current_mA);

#endif /* WC_HYDRAULICS_H */
