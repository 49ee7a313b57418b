#include "wetclutch/wc_hydraulics.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wc_internal.h"

float wc_piston_pressure_Pa(const wc_calibration_t *cal, float force_N)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    /* Any input: a force outside [0, WC_FORCE_MAX_N] is limited to it (NaN: 0). */
    const float force = (force_N >= 0.0f) ? ((force_N <= WC_FORCE_MAX_N) ? force_N : WC_FORCE_MAX_N) : 0.0f;
    return wc_piston_pressure_at(cal, force);
}

float wc_contact_force_N(const wc_calibration_t *cal, float pressure_Pa)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    const float force_N = wc_contact_force_at(cal, pressure_Pa);  /* 0 for NaN too */
    return (force_N < WC_FORCE_MAX_N) ? force_N : WC_FORCE_MAX_N;  /* an infinite pressure: the largest force */
}

wc_status_t wc_vfs_current_mA(const wc_calibration_t *cal, float pressure_Pa, float *current_mA)
{
    WC_ASSERT((cal != NULL) && (current_mA != NULL));
    if ((cal == NULL) || (current_mA == NULL)) {
        if (current_mA != NULL) { *current_mA = 0.0f; }
        return WC_STATUS_NOT_INITIALISED;
    }
    const float current = pressure_Pa / cal->vfs_gain_Pa_per_mA;  /* P = K i */
    if (!(current >= cal->vfs_current_min_mA)) {  /* also NaN */
        *current_mA = cal->vfs_current_min_mA;
        return WC_STATUS_CURRENT_CLAMPED;
    }
    if (current > cal->vfs_current_max_mA) {
        *current_mA = cal->vfs_current_max_mA;
        return WC_STATUS_CURRENT_CLAMPED;
    }
    *current_mA = current;
    return WC_STATUS_OK;
}

float wc_vfs_lag_step(const wc_model_t *model, float pressure_reached_Pa, float current_mA)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    if ((model == NULL) || (model->cal == NULL)) { return 0.0f; }
    /* Any input: a current outside the solenoid's range is limited to it (NaN:
     * the minimum); a reached pressure that is not a number restarts at rest. */
    const wc_calibration_t *cal = model->cal;
    const float current = (current_mA >= cal->vfs_current_min_mA)
                              ? ((current_mA <= cal->vfs_current_max_mA) ? current_mA : cal->vfs_current_max_mA)
                              : cal->vfs_current_min_mA;
    const float reached_Pa =
        isfinite(pressure_reached_Pa) ? pressure_reached_Pa : cal->vfs_gain_Pa_per_mA * cal->vfs_current_min_mA;
    return wc_vfs_lag_at(model, reached_Pa, current);
}
