#include "wetclutch/wc_lockup.h"

#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wc_lockup_internal.h"

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
    return wc_lockup_advance(lockup, cal, slip_rad_s, required_Nm, capacity_Nm);
}

float wc_lockup_torque_Nm(const wc_lockup_t *lockup, float required_Nm, float capacity_Nm)
{
    WC_ASSERT(lockup != NULL);
    if (lockup == NULL) { return 0.0f; }
    return wc_lockup_held_Nm(lockup, required_Nm, capacity_Nm);
}
