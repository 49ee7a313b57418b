/* Lock-up of the on-coming clutch (DESIGN section 9): slipping <-> locked.
 * The paper's friction model is kinetic only (section 3.5: it "cannot express
 * the friction force at zero velocity"); this two-state logic is where it
 * stops. Locked when the slip stays inside the lock band for the dwell and the
 * torque the clutch must carry, times 1 + holding_margin / 2, is below its
 * static capacity; breakaway when the slip leaves the wider breakaway band or
 * the torque reaches the capacity (hysteresis on both). */
#ifndef WC_LOCKUP_H
#define WC_LOCKUP_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_calibration.h"

typedef struct {
    bool locked;
    int8_t direction;       /* +1 / -1: the sign of the slip before it entered the lock band */
    uint8_t dwell_periods;  /* consecutive periods inside the lock band, saturating */
} wc_lockup_t;

/* Slipping, positive direction. */
void wc_lockup_init(wc_lockup_t *lockup);

/* One control period. required_Nm: the torque the clutch must carry, signed
 * like the slip (a torque sensor, or the request in the lock direction);
 * capacity_Nm: the static capacity at this period's contact force (>= 0).
 * NaN inputs count as outside the band / above the capacity (slipping).
 * Returns the new state's locked flag. */
bool wc_lockup_update(wc_lockup_t *lockup, const wc_calibration_t *cal, float slip_rad_s, float required_Nm,
                      float capacity_Nm);

/* What a locked clutch transmits: the required torque in the lock direction,
 * at most the capacity, never of the other sign (0 instead); finite for any
 * input (a NaN or negative capacity holds 0). */
float wc_lockup_torque_Nm(const wc_lockup_t *lockup, float required_Nm, float capacity_Nm);

#endif /* WC_LOCKUP_H */
