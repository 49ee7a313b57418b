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
    const float force_at_max_N = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 -
                                 cal->return_spring_force_N;
    model->force_max_N = (force_at_max_N > 0.0f) ? force_at_max_N : 0.0f;
    model->hbar_at_force_max_m = wc_film_hbar_m(&cal->film, model->force_max_N / cal->friction_area_m2);
    /* eq. 1, exact for a zero-order-hold input: computed once here, never per step */
    const float k_total_W_per_K = cal->oil_conductance_W_per_K + cal->housing_conductance_W_per_K;
    model->thermal_decay = expf(-k_total_W_per_K * cal->control_period_s / cal->heat_capacity_J_per_K);
    model->vfs_decay = expf(-cal->control_period_s / cal->vfs_time_constant_s);
    /* DESIGN section 9: Reynolds' squeeze film between annular plates,
     * K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri), written as
     * (Ro^2 - Ri^2) ((Ro^2 + Ri^2) - (Ro^2 - Ri^2) / ln(Ro/Ri)) with
     * ln(Ro/Ri) = log1p((Ro - Ri)/Ri): the bracket still cancels (by 1/140 for
     * Table 1's pack), a relative error of about 2e-5 in float
     * (tests/c/test_film.c against the double reference). */
    const float difference_m2 = (ro - ri) * (ro + ri);
    const float reynolds_m4 = difference_m2 * ((ro * ro + ri * ri) - difference_m2 / log1pf((ro - ri) / ri));
    model->film_damping_m4 = 1.5f * 3.14159265f * cal->film_squeeze_factor * reynolds_m4;
    model->cal = cal;
    return WC_CAL_OK;
}
