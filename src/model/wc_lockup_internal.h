/* Internal: the lock-up state machine of wc_lockup.h (DESIGN section 9),
 * inline for wc_clutch_step's hot path; the public functions in wc_lockup.c
 * add the argument checks. */
#ifndef WC_LOCKUP_INTERNAL_H
#define WC_LOCKUP_INTERNAL_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "wetclutch/wc_lockup.h"

static inline int8_t wc_lockup_sign(float slip_rad_s) { return (slip_rad_s < 0.0f) ? (int8_t)-1 : (int8_t)1; }

static inline bool wc_lockup_advance(wc_lockup_t *lockup, const wc_calibration_t *cal, float slip_rad_s,
                                     float required_Nm, float capacity_Nm)
{
    const float slip_abs = fabsf(slip_rad_s);
    const float required_abs = fabsf(required_Nm);
    /* Torque hysteresis: a locked clutch holds while the torque stays below its
     * capacity; it locks only with half the holding margin to spare, so a
     * capacity that settles at (1 + margin) times the request (the holding
     * inverse) never decides on rounding. Strict (NaN fails): no force, no hold. */
    const bool holds = required_abs < capacity_Nm;
    const bool locks = required_abs * (1.0f + 0.5f * cal->holding_margin) < capacity_Nm;
    if (lockup->locked) {
        /* Breakaway; the wider band is the hysteresis against a noisy slip. */
        if (!(slip_abs <= cal->breakaway_slip_rad_s) || !holds) {
            lockup->locked = false;
            lockup->dwell_periods = 0u;
            /* the slip that broke away sets the direction (not the dither inside the band while locked) */
            if (slip_abs >= cal->lock_slip_rad_s) { lockup->direction = wc_lockup_sign(slip_rad_s); }
        }
        return lockup->locked;
    }
    if ((slip_abs < cal->lock_slip_rad_s) && locks) {
        if (lockup->dwell_periods < UINT8_MAX) { ++lockup->dwell_periods; }
        /* the dwell debounces the lock: one noisy sample inside the band is not a lock */
        lockup->locked = lockup->dwell_periods >= cal->lock_dwell_periods;
    } else {
        lockup->dwell_periods = 0u;
        if (slip_abs >= cal->lock_slip_rad_s) { lockup->direction = wc_lockup_sign(slip_rad_s); }
    }
    return lockup->locked;
}

static inline float wc_lockup_held_Nm(const wc_lockup_t *lockup, float required_Nm, float capacity_Nm)
{
    const float direction = (lockup->direction < 0) ? -1.0f : 1.0f;
    const float along = direction * required_Nm;  /* the part in the lock direction */
    const float limit = (capacity_Nm > 0.0f) ? capacity_Nm : 0.0f;                 /* NaN or negative: 0 */
    const float held = (along > 0.0f) ? ((along < limit) ? along : limit) : 0.0f;  /* NaN: 0 */
    return direction * held;
}

#endif /* WC_LOCKUP_INTERNAL_H */
