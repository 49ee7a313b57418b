#include "wetclutch/wc_hydraulics.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"

float wc_piston_pressure_Pa(const wc_calibration_t *cal, float force_N)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    /* F_app = P A_p - F_s  =>  P = (F_app + F_s) / A_p */
    return (force_N + cal->return_spring_force_N) / cal->piston_area_m2;
}

float wc_contact_force_N(const wc_calibration_t *cal, float pressure_Pa)
{
    WC_ASSERT(cal != NULL);
    if (cal == NULL) { return 0.0f; }
    const float force_N = pressure_Pa * cal->piston_area_m2 - cal->return_spring_force_N;
    return (force_N > 0.0f) ? force_N : 0.0f;  /* the spring holds the pack open */
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
    /* tau dP/dt = K i - P, exact for i held over the period */
    const float target_Pa = model->cal->vfs_gain_Pa_per_mA * current_mA;
    return target_Pa + (pressure_reached_Pa - target_Pa) * model->vfs_decay;
}
