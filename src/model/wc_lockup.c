#include "wetclutch/wc_lockup.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"

void wc_lockup_init(wc_lockup_t *lockup)
{
    WC_ASSERT(lockup != NULL);
    if (lockup == NULL) { return; }
    lockup->locked = false;
    lockup->direction = 1;
    lockup->dwell_periods = 0u;
}

bool wc_lockup_update(wc_lockup_t *lockup, const wc_calibration_t *cal, float slip_rad_s, float required_Nm,
                      float capacity_Nm)
{
    WC_ASSERT((lockup != NULL) && (cal != NULL));
    if ((lockup == NULL) || (cal == NULL)) { return false; }
    const float slip_abs = fabsf(slip_rad_s);
    /* Strictly below the capacity (NaN fails): a clutch with no force holds nothing. */
    const bool holds = fabsf(required_Nm) < capacity_Nm;
    if (lockup->locked) {
        /* Breakaway (DESIGN 9); the wider band is the hysteresis against a noisy slip. */
        if (!(slip_abs <= cal->breakaway_slip_rad_s) || !holds) {
            lockup->locked = false;
            lockup->dwell_periods = 0u;
            /* the slip that broke away sets the direction (not the dither inside the band while locked) */
            if (slip_abs >= cal->lock_slip_rad_s) { lockup->direction = (slip_rad_s < 0.0f) ? (int8_t)-1 : (int8_t)1; }
        }
        return lockup->locked;
    }
    if ((slip_abs < cal->lock_slip_rad_s) && holds) {
        if (lockup->dwell_periods < UINT8_MAX) { ++lockup->dwell_periods; }
        /* the dwell debounces the lock: one noisy sample inside the band is not a lock */
        lockup->locked = lockup->dwell_periods >= cal->lock_dwell_periods;
    } else {
        lockup->dwell_periods = 0u;
        if (slip_abs >= cal->lock_slip_rad_s) { lockup->direction = (slip_rad_s < 0.0f) ? (int8_t)-1 : (int8_t)1; }
    }
    return lockup->locked;
}

float wc_lockup_torque_Nm(const wc_lockup_t *lockup, float required_Nm, float capacity_Nm)
{
    WC_ASSERT(lockup != NULL);
    if (lockup == NULL) { return 0.0f; }
    const float direction = (lockup->direction < 0) ? -1.0f : 1.0f;
    const float along = direction * required_Nm;  /* the part in the lock direction */
    const float held = (along > 0.0f) ? ((along < capacity_Nm) ? along : capacity_Nm) : 0.0f;  /* NaN: 0 */
    return direction * held;
}
