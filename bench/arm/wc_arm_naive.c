#include "wc_arm_naive.h"

#include <math.h>

/* Contact parameters of the table1 calibration, tools/calibrations/table1.toml,
 * section [contact]. They are not in the C calibration struct (lut/ carries
 * only the h_bar(p_c) table generated from them), so they are repeated here;
 * keep them in step with the TOML. */
#define NAIVE_YOUNGS_MODULUS_Pa 10.0e6f     /* E, paper Table 1 */
#define NAIVE_ASPERITY_DENSITY_m2 1.667e7f  /* N, project default: N beta sigma = 0.05 */
#define NAIVE_TIP_RADIUS_m 5.0e-4f          /* beta, paper Table 1 */
#define NAIVE_ROUGHNESS_m 6.0e-6f           /* sigma, paper Table 1 */

#define NAIVE_SQRT_PI 1.7724539f
#define NAIVE_SQRT_HALF_PI 1.2533141f
#define NAIVE_SQRT_HALF 0.70710678f
#define NAIVE_INV_SQRT_2PI 0.39894228f

/* eq. 15 prefactor sqrt(pi/2) E N beta sigma (626.8 kPa). */
#define NAIVE_PRESSURE_SCALE_Pa \
    (NAIVE_SQRT_HALF_PI * NAIVE_YOUNGS_MODULUS_Pa * NAIVE_ASPERITY_DENSITY_m2 * NAIVE_TIP_RADIUS_m * NAIVE_ROUGHNESS_m)

/* The film domain of the table (table1.toml [film_lut]), in x = h / (sqrt2 sigma):
 * open-clutch end h = 4 sigma (separation_max_sigma), where p_c = 11.226 Pa
 * (eq. 15 in double); below that pressure the film is clamped there, as the
 * table lookup does. The closed end x = -2 (h = -17 um, p_c = 4.5 MPa) lies
 * beyond the table's 4.2 MPa (contact_pressure_max) and far beyond the
 * 2.68 MPa of the maximum current. */
#define NAIVE_X_OPEN 2.8284271f
#define NAIVE_X_CLOSED (-2.0f)
#define NAIVE_PRESSURE_OPEN_Pa 11.225990f

/* Outer bisection on F_c: the bisection wc_inverse used up to commit 823133d
 * (src/model/wc_inverse.c then): bracket [0, force_max], stop once it is
 * 0.01 N wide or after 24 halvings (table1 needs 21 = ceil(log2(10863 N / 0.01 N))).
 * Own constants: the library's WC_INVERSE_MAX_ITERATIONS now bounds its
 * Newton steps, not a bisection. */
#define NAIVE_FORCE_MAX_HALVINGS 24u
#define NAIVE_FORCE_TOLERANCE_N 0.01f

/* Inner bisection on x: at most this many halvings, stopping once the bracket
 * is this narrow (4.83 / 2^23 = 5.8e-7: about one float ulp of x near 2). */
#define NAIVE_FILM_MAX_HALVINGS 24u
#define NAIVE_X_TOLERANCE 1.0e-6f

/* eq. 15 with x = h / (sqrt2 sigma), h / sigma = sqrt2 x:
 * p_c = sqrt(pi/2) E N beta sigma [e^(-x^2) - sqrt(pi) x erfc(x)]. */
static float contact_pressure_Pa(float x)
{
    return NAIVE_PRESSURE_SCALE_Pa * (expf(-x * x) - NAIVE_SQRT_PI * x * erfcf(x));
}

/* eq. 9: h_bar = h/2 (1 + erf x) + sigma/sqrt(2 pi) e^(-x^2). */
static float film_hbar_m(float x)
{
    const float h_m = x * (NAIVE_ROUGHNESS_m / NAIVE_SQRT_HALF);
    return 0.5f * h_m * (1.0f + erff(x)) + NAIVE_ROUGHNESS_m * NAIVE_INV_SQRT_2PI * expf(-x * x);
}

/* h_bar(p_c): eq. 15 solved for x by bisection (p_c strictly decreasing in x), then eq. 9. */
static float naive_hbar_m(float pressure_Pa)
{
    float x = NAIVE_X_OPEN;
    if (pressure_Pa > NAIVE_PRESSURE_OPEN_Pa) {
        float lo = NAIVE_X_CLOSED;  /* p_c(lo) >= pressure */
        float hi = NAIVE_X_OPEN;    /* p_c(hi) < pressure */
        for (uint32_t i = 0u; (i < NAIVE_FILM_MAX_HALVINGS) && (hi - lo > NAIVE_X_TOLERANCE); ++i) {
            const float mid = 0.5f * (lo + hi);
            if (contact_pressure_Pa(mid) > pressure_Pa) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        x = 0.5f * (lo + hi);
    }
    return film_hbar_m(x);
}

typedef struct {
    float coulomb_Nm_per_N;  /* R_eff N_c mu_f */
    float viscous_Nm_m;      /* R_eff N_c mu_v A_f v: viscous torque times h_bar */
    float area_m2;
} naive_point_t;

/* eq. 8 at contact force force_N, magnitude. */
static float naive_torque_Nm(const naive_point_t *point, float force_N)
{
    return point->coulomb_Nm_per_N * force_N + point->viscous_Nm_m / naive_hbar_m(force_N / point->area_m2);
}

static void finish(const wc_model_t *model, float force_N, wc_status_t *status, wc_inverse_t *out)
{
    out->force_N = force_N;
    out->pressure_Pa = wc_piston_pressure_Pa(model->cal, force_N);
    *status |= wc_vfs_current_mA(model->cal, out->pressure_Pa, &out->current_mA);
}

wc_status_t wc_arm_naive_inverse(const wc_model_t *model, float slip_rad_s, float theta_degC,
                                 float torque_request_Nm, wc_inverse_t *out)
{
    const wc_calibration_t *cal = model->cal;
    wc_status_t status = WC_STATUS_OK;
    out->iterations = 0u;

    /* The same per-point terms as the library (eq. 2, 4, 6, 7, 18). */
    const float speed_m_s = model->effective_radius_m * fabsf(slip_rad_s);
    naive_point_t point;
    point.coulomb_Nm_per_N = (model->effective_radius_m * (float)model->cal->friction_pairs) * wc_friction_coefficient(cal, speed_m_s, theta_degC);
    point.viscous_Nm_m = (model->effective_radius_m * (float)model->cal->friction_pairs) * wc_viscosity_Pa_s(cal, theta_degC) * cal->friction_area_m2 * speed_m_s;
    point.area_m2 = cal->friction_area_m2;

    if (torque_request_Nm <= naive_torque_Nm(&point, 0.0f)) {
        status |= WC_STATUS_BELOW_DRAG;
        finish(model, 0.0f, &status, out);
        return status;
    }
    if (torque_request_Nm > naive_torque_Nm(&point, model->force_max_N)) {
        out->force_N = model->force_max_N;
        out->current_mA = cal->vfs_current_max_mA;
        out->pressure_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA;
        return status | WC_STATUS_SATURATED;
    }
    float lo_N = 0.0f;
    float hi_N = model->force_max_N;
    uint32_t i = 0u;
    for (; (i < NAIVE_FORCE_MAX_HALVINGS) && (hi_N - lo_N > NAIVE_FORCE_TOLERANCE_N); ++i) {
        const float mid_N = 0.5f * (lo_N + hi_N);
        if (naive_torque_Nm(&point, mid_N) < torque_request_Nm) {
            lo_N = mid_N;
        } else {
            hi_N = mid_N;
        }
    }
    out->iterations = i;
    finish(model, 0.5f * (lo_N + hi_N), &status, out);
    return status;
}
