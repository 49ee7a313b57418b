/* Torque request -> contact force -> piston pressure -> VFS current.
 * T(F_c) is strictly increasing in F_c (eq. 8), so the force is unique: a
 * binary search over the film table's nodes finds the segment that holds it,
 * then at most WC_INVERSE_MAX_ITERATIONS safeguarded Newton steps on that
 * segment's cubic, to within WC_INVERSE_FORCE_TOLERANCE_N (src/model/wc_inverse.c). */
#ifndef WC_INVERSE_H
#define WC_INVERSE_H

#include <stdint.h>

#include "wc_model.h"
#include "wc_status.h"

typedef struct {
    float force_N;        /* contact force F_c */
    float pressure_Pa;    /* piston pressure (F_c + F_s) / A_p */
    float current_mA;     /* VFS current, within the solenoid range */
    uint32_t iterations;  /* Newton steps used (0: below drag, saturated, or outside the table) */
} wc_inverse_t;

/* torque_request_Nm is a magnitude (>= 0): the clutch torque wanted against
 * the slip. Below the drag at F_c = 0: force 0, WC_STATUS_BELOW_DRAG. Above
 * the capacity at the maximum current: force at the maximum current,
 * WC_STATUS_SATURATED. Invalid input: force 0 and the current that holds the
 * piston at the spring preload (clamped), with the input's status bit. */
wc_status_t wc_inverse(const wc_model_t *model, float slip_rad_s, float theta_degC,
                       float torque_request_Nm, wc_inverse_t *out);

#endif /* WC_INVERSE_H */
