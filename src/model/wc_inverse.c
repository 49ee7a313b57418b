#include "wetclutch/wc_inverse.h"

#include <math.h>

#include "wetclutch/wc_hydraulics.h"
#include "wc_internal.h"
#include "wc_torque_point.h"

static void finish(const wc_model_t *model, float force_N, wc_status_t *status, wc_inverse_t *out)
{
    out->force_N = force_N;
    out->pressure_Pa = wc_piston_pressure_Pa(model->cal, force_N);
    *status |= wc_vfs_current_mA(model->cal, out->pressure_Pa, &out->current_mA);
}

wc_status_t wc_inverse(const wc_model_t *model, float slip_rad_s, float theta_degC,
                       float torque_request_Nm, wc_inverse_t *out)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    WC_ASSERT(out != NULL);
    wc_status_t status = WC_STATUS_OK;
    out->iterations = 0u;
    if (!wc_slip_valid(slip_rad_s)) { status |= WC_STATUS_SLIP_INVALID; }
    if (!wc_theta_valid(theta_degC)) { status |= WC_STATUS_THETA_INVALID; }
    if (!wc_in_range(torque_request_Nm, 0.0f, WC_TORQUE_MAX_Nm)) { status |= WC_STATUS_TORQUE_INVALID; }
    if (status != WC_STATUS_OK) {
        finish(model, 0.0f, &status, out);  /* documented safe answer: no contact force */
        return status;
    }

    wc_torque_point_t point;
    wc_torque_point(model, slip_rad_s, theta_degC, &point);
    float hbar_m = 0.0f;
    if (torque_request_Nm <= wc_torque_point_magnitude(model, &point, 0.0f, &hbar_m)) {
        status |= WC_STATUS_BELOW_DRAG;  /* the drag alone exceeds the request */
        finish(model, 0.0f, &status, out);
        return status;
    }
    if (torque_request_Nm > wc_torque_point_magnitude(model, &point, model->force_max_N, &hbar_m)) {
        /* Beyond the capacity at the maximum current: command exactly that
         * current (recomputing it from F_max could land a float step above
         * the range and raise a spurious clamp flag). */
        const wc_calibration_t *cal = model->cal;
        out->force_N = model->force_max_N;
        out->current_mA = cal->vfs_current_max_mA;
        out->pressure_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA;
        return status | WC_STATUS_SATURATED;
    }

    /* T(F) is strictly increasing (eq. 8): keep T(lo) < request <= T(hi). */
    float lo_N = 0.0f;
    float hi_N = model->force_max_N;
    uint32_t i = 0u;
    for (; (i < WC_INVERSE_MAX_ITERATIONS) && (hi_N - lo_N > WC_INVERSE_FORCE_TOLERANCE_N); ++i) {
        const float mid_N = 0.5f * (lo_N + hi_N);
        if (wc_torque_point_magnitude(model, &point, mid_N, &hbar_m) < torque_request_Nm) {
            lo_N = mid_N;
        } else {
            hi_N = mid_N;
        }
    }
    out->iterations = i;
    finish(model, 0.5f * (lo_N + hi_N), &status, out);
    return status;
}
