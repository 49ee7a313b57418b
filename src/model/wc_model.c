#include "wetclutch/wc_model.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_config.h"
#include "wetclutch/wc_film.h"
#include "wc_internal.h"

wc_cal_error_t wc_model_init(wc_model_t *model, const wc_calibration_t *cal)
{
    WC_ASSERT(model != NULL);
    if (model == NULL) { return WC_CAL_NULL; }
    model->cal = NULL;
    const wc_cal_error_t error = wc_calibration_check(cal);
    if (error != WC_CAL_OK) { return error; }

    const float force_at_max_N = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA * cal->piston_area_m2 -
                                 cal->return_spring_force_N;
    model->force_max_N = (force_at_max_N > 0.0f) ? force_at_max_N : 0.0f;
    model->hbar_at_force_max_m = wc_film_hbar_m(&cal->film, model->force_max_N / cal->friction_area_m2);
    /* eq. 1, exact for a zero-order-hold input: computed once here, never per step */
    const float k_total_W_per_K = cal->oil_conductance_W_per_K + cal->housing_conductance_W_per_K;
    model->thermal_decay = expf(-k_total_W_per_K * cal->control_period_s / cal->heat_capacity_J_per_K);
    model->vfs_decay = expf(-cal->control_period_s / cal->vfs_time_constant_s);
    wc_model_set_geometry(model, cal);
    return WC_CAL_OK;
}

void wc_model_set_geometry(wc_model_t *model, const wc_calibration_t *cal)
{
    const float ro = cal->outer_radius_m;
    const float ri = cal->inner_radius_m;
    /* eq. 3: R_eff = 2/3 (Ro^3 - Ri^3) / (Ro^2 - Ri^2), written as
     * 2/3 (Ro^2 + Ro Ri + Ri^2) / (Ro + Ri) to avoid cancellation in float. */
    model->effective_radius_m = (2.0f / 3.0f) * (ro * ro + ro * ri + ri * ri) / (ro + ri);
    /* DESIGN section 9: Reynolds' squeeze film between annular plates,
     * K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri). For a narrow annulus the
     * two terms cancel (by 1/140 for Table 1's pack; to nothing in float as
     * Ri -> Ro), so with s = (Ro - Ri)/(Ro + Ri) <= 0.25 the series
     * K = 8 m^4 s^3 (4/3 + 4/45 s^2 + 44/945 s^4), m = (Ro + Ri)/2 (from
     * ln(Ro/Ri) = 2 atanh s; relative error <= 6e-6), else the direct form
     * (cancellation by at most 1/13). tests/c/test_film.c checks Table 1's
     * against double; the calibration fuzzer every accepted pair of radii. */
    const float s = (ro - ri) / (ro + ri);
    float reynolds_m4;
    if (s <= 0.25f) {
        const float m = 0.5f * (ro + ri);
        const float m2 = m * m;
        const float s2 = s * s;
        reynolds_m4 = 8.0f * m2 * m2 * s2 * s * (4.0f / 3.0f + s2 * (4.0f / 45.0f + s2 * (44.0f / 945.0f)));
    } else {
        const float difference_m2 = (ro - ri) * (ro + ri);
        reynolds_m4 = difference_m2 * ((ro * ro + ri * ri) - difference_m2 / logf(ro / ri));
    }
    model->film_damping_m4 = 1.5f * 3.14159265f * cal->film_squeeze_factor * reynolds_m4;
    model->cal = cal;
}
