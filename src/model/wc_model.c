#include "wetclutch/wc_model.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wetclutch/wc_film.h"

wc_cal_error_t wc_model_init(wc_model_t *model, const wc_calibration_t *cal)
{
    WC_ASSERT(model != NULL);
    if (model == NULL) { return WC_CAL_NULL; }
    model->cal = NULL;
    const wc_cal_error_t error = wc_calibration_check(cal);
    if (error != WC_CAL_OK) { return error; }

    const float ro = cal->outer_radius_m;
    const float ri = cal->inner_radius_m;
    /* eq. 3: R_eff = 2/3 (Ro^3 - Ri^3) / (Ro^2 - Ri^2), written as
     * 2/3 (Ro^2 + Ro Ri + Ri^2) / (Ro + Ri) to avoid cancellation in float. */
    model->effective_radius_m = (2.0f / 3.0f) * (ro * ro + ro * ri + ri * ri) / (ro + ri);
    model->torque_arm_m = model->effective_radius_m * (float)cal->friction_pairs;
    const float force_at_max_N = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 -
                                 cal->return_spring_force_N;
    model->force_max_N = (force_at_max_N > 0.0f) ? force_at_max_N : 0.0f;
    model->hbar_at_force_max_m = wc_film_hbar_m(&cal->film, model->force_max_N / cal->friction_area_m2);
    /* eq. 1, exact for a zero-order-hold input: computed once here, never per step */
    const float k_total_W_per_K = cal->oil_conductance_W_per_K + cal->housing_conductance_W_per_K;
    model->thermal_decay = expf(-k_total_W_per_K * cal->control_period_s / cal->heat_capacity_J_per_K);
    model->vfs_decay = expf(-cal->control_period_s / cal->vfs_time_constant_s);
    model->cal = cal;
    return WC_CAL_OK;
}
