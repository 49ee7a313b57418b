/* Internal: the model at one operating point (slip, theta), where only the
 * film depends on the force. mu_f and mu_v (up to three expf) are computed
 * once per control step and shared by the inverse and the forward torque
 * (wc_clutch_step); the public wc_torque and wc_inverse compute their own. */
#ifndef WC_OPERATING_POINT_H
#define WC_OPERATING_POINT_H

#include <stdint.h>

#include "wetclutch/wc_inverse.h"
#include "wetclutch/wc_model.h"
#include "wetclutch/wc_status.h"
#include "wetclutch/wc_torque.h"
#include "wc_film_internal.h"

typedef struct {
    float coulomb_Nm_per_N;  /* R_eff N_c mu_f(v, theta), eq. 6 */
    float viscous_Nm_m;      /* R_eff N_c mu_v(theta) A_f v, eq. 7 times h_bar */
    float mu_f;
    float viscosity_Pa_s;    /* mu_v(theta), eq. 2: the squeeze film's damping (DESIGN 9) */
    float temperature_factor; /* 1 + mu3 (theta - theta1) / theta2 of eq. 18: the static capacity's too */
} wc_torque_point_t;

/* mu_f, mu_v at a valid (slip, theta). */
void wc_torque_point(const wc_model_t *model, float slip_rad_s, float theta_degC, wc_torque_point_t *point);

/* eq. 5-8 at the point for a valid force_N, signed with the slip. */
void wc_torque_at_point(const wc_model_t *model, const wc_torque_point_t *point, float slip_rad_s, float force_N,
                        wc_torque_t *out);

/* The inverse at the point for a valid torque_request_Nm (wc_inverse.h).
 * *film_segment: set to the film table's segment that holds the force found
 * when the force was solved on a segment, for the lookup of that force's film
 * (the lead's); left as it is (the caller's WC_FILM_NO_SEGMENT) when it was
 * not (below drag, saturated, outside the table). */
wc_status_t wc_inverse_at_point(const wc_model_t *model, const wc_torque_point_t *point, float torque_request_Nm,
                                wc_inverse_t *out, uint32_t *film_segment);

/* The inverse for a locked clutch (DESIGN 9): the force whose static capacity
 * (static_Nm_per_N > 0 per newton) holds torque_request_Nm with the
 * calibration's holding margin, clamped to the force at the maximum current
 * (WC_STATUS_SATURATED). */
wc_status_t wc_inverse_holding(const wc_model_t *model, float static_Nm_per_N, float torque_request_Nm,
                               wc_inverse_t *out);

/* Static capacity per newton of contact force at the point (DESIGN 9): the static factor times
 * mu_f(0, theta) R_eff N_c, eq. 18 at v = 0: mu_f(0, theta) = mu2 (1 + mu3 (theta - theta1) / theta2). */
static inline float wc_static_capacity_Nm_per_N(const wc_model_t *model, const wc_torque_point_t *point)
{
    const wc_calibration_t *cal = model->cal;
    return model->effective_radius_m * (float)cal->friction_pairs * cal->static_friction_factor * cal->mu2 *
           point->temperature_factor;
}

/* eq. 5-8 at the point for a contact force and the film it stands on (the
 * steady film of eq. 16, or the squeeze-film state of DESIGN 9), the viscous
 * term sheared over gap_m: the film h_bar itself, or an open element's gap
 * (DESIGN 15, wc_clutch.c); out->hbar_m is the film's. */
static inline void wc_torque_at_gap(const wc_torque_point_t *point, float slip_rad_s, float force_N,
                                    float hbar_m, float gap_m, wc_torque_t *out)
{
    const float sign = (slip_rad_s < 0.0f) ? -1.0f : 1.0f;  /* torque acts against the slip */
    out->coulomb_Nm = sign * point->coulomb_Nm_per_N * force_N;   /* eq. 6 */
    out->viscous_Nm = sign * point->viscous_Nm_m / gap_m;         /* eq. 7 */
    out->torque_Nm = out->coulomb_Nm + out->viscous_Nm;           /* eq. 5 */
    out->hbar_m = hbar_m;
    out->mu_f = point->mu_f;
}

/* eq. 5-8 at the point for a contact force and the film it stands on. */
static inline void wc_torque_at_film(const wc_torque_point_t *point, float slip_rad_s, float force_N,
                                     float hbar_m, wc_torque_t *out)
{
    wc_torque_at_gap(point, slip_rad_s, force_N, hbar_m, hbar_m, out);
}

/* Segment k of the film table (nodes k, k+1) as a cubic in t in [0, 1]
 * (p = p_k + t (p_k+1 - p_k)): h_bar(t) = c[0] + t (c[1] + t (c[2] + t c[3])).
 * The same cubic Hermite as wc_film_hbar_m (wc_film.c), in the power basis
 * (eq. 9, 15, 16); tests/c/test_film.c checks the two agree. Inline: the
 * inverse calls it once per solve on its hot path. */
static inline void wc_film_segment_cubic(const wc_film_table_t *table, uint32_t k, float coefficient[4])
{
    /* The Hermite basis expanded in powers of t, with the slopes scaled to
     * the segment: m = (p_k+1 - p_k) dh_bar/dp_c. */
    const float width_Pa = table->pressure_Pa[k + 1u] - table->pressure_Pa[k];
    const float h0 = table->hbar_m[k];
    const float h1 = table->hbar_m[k + 1u];
    const float m0 = width_Pa * table->slope_m_per_Pa[k];
    const float m1 = width_Pa * table->slope_m_per_Pa[k + 1u];
    coefficient[0] = h0;
    coefficient[1] = m0;
    coefficient[2] = 3.0f * (h1 - h0) - 2.0f * m0 - m1;
    coefficient[3] = 2.0f * (h0 - h1) + m0 + m1;
}

#endif /* WC_OPERATING_POINT_H */
