#include "wetclutch/wc_torque.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_film.h"
#include "wetclutch/wc_friction.h"
#include "wc_internal.h"
#include "wc_operating_point.h"
#include "wetclutch/wc_viscosity.h"

void wc_torque_point(const wc_model_t *model, float slip_rad_s, float theta_degC, wc_torque_point_t *point)
{
    const wc_calibration_t *cal = model->cal;
    const float speed_m_s = model->effective_radius_m * fabsf(slip_rad_s);                  /* eq. 4 */
    const float torque_arm_m = model->effective_radius_m * (float)cal->friction_pairs;      /* R_eff N_c */
    point->temperature_factor = wc_friction_temperature_factor(cal, theta_degC);             /* eq. 18 */
    point->mu_f = wc_friction_at(cal, speed_m_s, point->temperature_factor);                /* eq. 18 */
    point->coulomb_Nm_per_N = torque_arm_m * point->mu_f;                            /* eq. 6 */
    point->viscosity_Pa_s = wc_viscosity_Pa_s(cal, theta_degC);                           /* eq. 2 */
    point->viscous_Nm_m = torque_arm_m * point->viscosity_Pa_s * cal->friction_area_m2 * speed_m_s;  /* eq. 7 */
}

/* The documented answer to rejected input (wc_torque.h): zero torque with the open-clutch film. */
static void wc_torque_rejected(const wc_model_t *model, wc_torque_t *out)
{
    out->torque_Nm = 0.0f;
    out->coulomb_Nm = 0.0f;
    out->viscous_Nm = 0.0f;
    out->hbar_m = model->cal->film.hbar_m[0];
    out->mu_f = 0.0f;
}

void wc_torque_at_point(const wc_model_t *model, const wc_torque_point_t *point, float slip_rad_s, float force_N,
                        wc_torque_t *out)
{
    /* eq. 16: steady film, p_c = F_c / A_f (the table passed the calibration check at init; the
     * modelled force lags the commanded one: no segment to start from that would hold in the worst case) */
    const float hbar_m = wc_film_hbar_near_m(&model->cal->film, force_N / model->cal->friction_area_m2,
                                             WC_FILM_NO_SEGMENT);
    wc_torque_at_film(point, slip_rad_s, force_N, hbar_m, out);
}


wc_status_t wc_torque(const wc_model_t *model, float slip_rad_s, float theta_degC, float force_N,
                      wc_torque_t *out)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    WC_ASSERT(out != NULL);
    if (out == NULL) { return WC_STATUS_NOT_INITIALISED; }
    if ((model == NULL) || (model->cal == NULL)) {
        const wc_torque_t none = { 0.0f, 0.0f, 0.0f, 0.0f, 0.0f };
        *out = none;
        return WC_STATUS_NOT_INITIALISED;
    }
    wc_status_t status = WC_STATUS_OK;
    if (!wc_slip_valid(slip_rad_s)) { status |= WC_STATUS_SLIP_INVALID; }
    if (!wc_theta_valid(theta_degC)) { status |= WC_STATUS_THETA_INVALID; }
    if (!wc_in_range(force_N, 0.0f, WC_FORCE_MAX_N)) { status |= WC_STATUS_FORCE_INVALID; }
    if (status != WC_STATUS_OK) {
        wc_torque_rejected(model, out);
        return status;
    }
    wc_torque_point_t point;
    wc_torque_point(model, slip_rad_s, theta_degC, &point);
    wc_torque_at_point(model, &point, slip_rad_s, force_N, out);
    return WC_STATUS_OK;
}
