#include "wetclutch/wc_inverse.h"

#include <math.h>

#include "wetclutch/wc_hydraulics.h"
#include "wc_internal.h"
#include "wc_operating_point.h"

/* The inverse of eq. 8 at one operating point (mu_f, mu_v fixed):
 *     T(F) = c F + v / h_bar(F / A_f),   c = R_eff N_c mu_f,  v = R_eff N_c mu_v A_f |v_slip|,
 * strictly increasing in F (eq. 8; h_bar decreases with p_c). The film table
 * gives T at its nodes for the price of a multiply-add each, so the inverse
 *  1. finds the table segment that holds the root by a binary search over the
 *     nodes, comparing h (T_req - c F) with v: the sign of T_req - T(F)
 *     without a division (h > 0);
 *  2. solves T(F) = T_req on that segment's cubic Hermite (the same cubic
 *     the forward model interpolates, wc_film_hbar_m) by Newton's method
 *     from the linear interpolation of T between the nodes, safeguarded by
 *     the segment bracket (a step that leaves the bracket is a bisection),
 *     at most WC_INVERSE_MAX_ITERATIONS steps, stopping once a Newton step
 *     moves F by less than WC_INVERSE_FORCE_TOLERANCE_N / 2.
 * Outside the table's pressure range h_bar is clamped (constant), so T is
 * linear in F there and the root has a closed form. */

static void finish(const wc_model_t *model, float force_N, wc_status_t *status, wc_inverse_t *out)
{
    out->force_N = force_N;
    out->pressure_Pa = wc_piston_pressure_at(model->cal, force_N);
    *status |= wc_vfs_current_mA(model->cal, out->pressure_Pa, &out->current_mA);
}

/* h (T_req - c F) - v = h (T_req - T(F)) for film h > 0: positive while T(F) < T_req. */
static float excess(const wc_torque_point_t *point, float request_Nm, float force_N, float hbar_m)
{
    return hbar_m * (request_Nm - point->coulomb_Nm_per_N * force_N) - point->viscous_Nm_m;
}

/* Root where the film is the constant hbar_m: c F + v / h = T_req. */
static float linear_root(const wc_torque_point_t *point, float request_Nm, float hbar_m)
{
    const float denominator = point->coulomb_Nm_per_N * hbar_m;
    return (denominator > 0.0f) ? (request_Nm * hbar_m - point->viscous_Nm_m) / denominator : 0.0f;
}

typedef struct {
    uint32_t node;     /* segment [node, node + 1] */
    float excess_lo;   /* excess at the segment's nodes: >= 0 at node, < 0 at node + 1 */
    float excess_hi;
} wc_segment_t;

/* Binary search for the segment with excess(node) >= 0 > excess(node + 1),
 * given excess(0) >= 0 > excess(last); at most log2(length) probes. */
static wc_segment_t find_segment(const wc_film_table_t *film, float area_m2, const wc_torque_point_t *point,
                                 float request_Nm, float excess_first, float excess_last)
{
    /* Locals, not the struct, in the loop: the compiler keeps them in registers. */
    const float *pressure_Pa = film->pressure_Pa;
    const float *hbar_m = film->hbar_m;
    const float c_per_Pa = point->coulomb_Nm_per_N * area_m2;  /* T per unit of p_c */
    const float v = point->viscous_Nm_m;
    uint32_t lo = 0u;
    uint32_t hi = film->length - 1u;
    float excess_lo = excess_first;
    float excess_hi = excess_last;
    for (uint32_t guard = 0u; (guard < 32u) && (hi - lo > 1u); ++guard) {
        const uint32_t mid = (lo + hi) / 2u;  /* lengths are at most WC_FILM_MAX_NODES: no overflow */
        const float e = hbar_m[mid] * (request_Nm - c_per_Pa * pressure_Pa[mid]) - v;  /* excess() */
        if (e >= 0.0f) {
            lo = mid;
            excess_lo = e;
        } else {
            hi = mid;
            excess_hi = e;
        }
    }
    const wc_segment_t s = { lo, excess_lo, excess_hi };
    return s;
}

/* Newton on the segment's cubic, in t in [0, 1] (F = F_k + t W). */
static float solve_segment(const wc_film_table_t *film, float area_m2, const wc_torque_point_t *point,
                           float request_Nm, const wc_segment_t *s, uint32_t *iterations)
{
    float cubic[4];
    wc_film_segment_cubic(film, s->node, cubic);
    const float force_k_N = film->pressure_Pa[s->node] * area_m2;
    const float width_N = (film->pressure_Pa[s->node + 1u] - film->pressure_Pa[s->node]) * area_m2;
    const float c = point->coulomb_Nm_per_N;
    const float v = point->viscous_Nm_m;
    /* Start: the cubic Hermite of t(T) through both nodes, with the slopes
     * dt/dT = 1 / (dT/dt) there (dT/dt = c W - v h' / h^2, positive). With
     * T_req - T_k = e_lo / h_k and T_k+1 - T_req = -e_hi / h_k+1: */
    const float h0 = film->hbar_m[s->node];
    const float h1 = film->hbar_m[s->node + 1u];
    const float below_Nm = s->excess_lo / h0;
    const float span_Nm = below_Nm - s->excess_hi / h1;                 /* T_k+1 - T_k > 0 */
    const float u = below_Nm / span_Nm;
    const float slope0 = c * width_N - v * cubic[1] / (h0 * h0);
    const float m1 = (film->pressure_Pa[s->node + 1u] - film->pressure_Pa[s->node]) * film->slope_m_per_Pa[s->node + 1u];
    const float slope1 = c * width_N - v * m1 / (h1 * h1);                 /* dh/dt at t = 1 */
    const float u2 = u * u;
    const float u3 = u2 * u;
    float t = (3.0f * u2 - 2.0f * u3) + (u3 - 2.0f * u2 + u) * (span_Nm / slope0) + (u3 - u2) * (span_Nm / slope1);
    t = (t > 0.0f) ? ((t < 1.0f) ? t : 1.0f) : 0.0f;
    float t_lo = 0.0f;
    float t_hi = 1.0f;
    uint32_t i = 0u;
    while (i < WC_INVERSE_MAX_ITERATIONS) {
        ++i;
        const float h = cubic[0] + t * (cubic[1] + t * (cubic[2] + t * cubic[3]));  /* eq. 9 via the LUT */
        const float dh_dt = cubic[1] + t * (2.0f * cubic[2] + t * 3.0f * cubic[3]);
        const float e = excess(point, request_Nm, force_k_N + t * width_N, h);
        if (e > 0.0f) { t_lo = t; } else { t_hi = t; }
        /* f(t) = T(F(t)) - T_req = -e / h, f'(t) = c W - v h' / h^2: step -f/f' = e h / (c W h^2 - v h') */
        const float slope = c * width_N * h * h - v * dh_dt;
        float next = (slope > 0.0f) ? t + e * h / slope : -1.0f;
        const bool newton = (next >= t_lo) && (next <= t_hi);
        if (!newton) { next = 0.5f * (t_lo + t_hi); }  /* safeguard: bisect the bracket */
        const float moved_N = fabsf(next - t) * width_N;
        t = next;
        if ((newton && (moved_N <= 0.5f * WC_INVERSE_FORCE_TOLERANCE_N)) ||
            ((t_hi - t_lo) * width_N <= WC_INVERSE_FORCE_TOLERANCE_N)) {
            break;
        }
    }
    *iterations = i;
    return force_k_N + t * width_N;
}

wc_status_t wc_inverse_at_point(const wc_model_t *model, const wc_torque_point_t *point, float torque_request_Nm,
                                wc_inverse_t *out, uint32_t *film_segment)
{
    const wc_calibration_t *cal = model->cal;
    const wc_film_table_t *film = &cal->film;
    wc_status_t status = WC_STATUS_OK;
    out->iterations = 0u;

    /* At F_c = 0 the film is the table's first (thickest, clamped) node. */
    if (torque_request_Nm * film->hbar_m[0] <= point->viscous_Nm_m) {
        status |= WC_STATUS_BELOW_DRAG;  /* the drag alone meets the request */
        finish(model, 0.0f, &status, out);
        return status;
    }
    if (excess(point, torque_request_Nm, model->force_max_N, model->hbar_at_force_max_m) > 0.0f) {
        /* Beyond the capacity at the maximum current: command exactly that
         * current (recomputing it from F_max could land a float step above
         * the range and raise a spurious clamp flag). */
        out->force_N = model->force_max_N;
        out->current_mA = cal->vfs_current_max_mA;
        out->pressure_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA;
        return WC_STATUS_SATURATED;
    }

    const float area_m2 = cal->friction_area_m2;
    const uint32_t last = film->length - 1u;
    const float excess_first = excess(point, torque_request_Nm, film->pressure_Pa[0] * area_m2, film->hbar_m[0]);
    const float excess_last = excess(point, torque_request_Nm, film->pressure_Pa[last] * area_m2, film->hbar_m[last]);
    float force_N;
    if (excess_first < 0.0f) {
        force_N = linear_root(point, torque_request_Nm, film->hbar_m[0]);     /* below the first node */
    } else if (excess_last >= 0.0f) {
        force_N = linear_root(point, torque_request_Nm, film->hbar_m[last]);  /* above the last node */
    } else {
        const wc_segment_t s = find_segment(film, area_m2, point, torque_request_Nm, excess_first, excess_last);
        force_N = solve_segment(film, area_m2, point, torque_request_Nm, &s, &out->iterations);
        *film_segment = s.node;
    }
    /* The root lies in (0, F_max]: keep float rounding from stepping outside. */
    force_N = (force_N > 0.0f) ? force_N : 0.0f;
    force_N = (force_N < model->force_max_N) ? force_N : model->force_max_N;
    finish(model, force_N, &status, out);
    return status;
}

wc_status_t wc_inverse_holding(const wc_model_t *model, float static_Nm_per_N, float torque_request_Nm,
                               wc_inverse_t *out)
{
    /* DESIGN 9: a locked clutch carries the request if its static capacity
     * does, c_s F_c > T_req; the margin keeps it locked against the
     * capacity's error. c_s > 0 on the domain (mu2 >= 1e-3, a positive
     * temperature factor and static factor: wc_calibration_check). */
    wc_status_t status = WC_STATUS_OK;
    const wc_calibration_t *cal = model->cal;
    const float force_N = torque_request_Nm * (1.0f + cal->holding_margin) / static_Nm_per_N;
    out->iterations = 0u;
    if (!(force_N <= model->force_max_N)) {  /* also NaN (an underflowing capacity): hold with all there is */
        /* the maximum current itself, as wc_inverse_at_point's saturated branch */
        out->force_N = model->force_max_N;
        out->current_mA = cal->vfs_current_max_mA;
        out->pressure_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA;
        return WC_STATUS_SATURATED;
    }
    finish(model, force_N, &status, out);
    return status;
}

/* The documented answer to rejected input (wc_inverse.h): no contact force. */
static wc_status_t wc_inverse_rejected(const wc_model_t *model, wc_status_t status, wc_inverse_t *out)
{
    out->iterations = 0u;
    finish(model, 0.0f, &status, out);  /* documented safe answer: no contact force */
    return status;
}

wc_status_t wc_inverse(const wc_model_t *model, float slip_rad_s, float theta_degC,
                       float torque_request_Nm, wc_inverse_t *out)
{
    WC_ASSERT((model != NULL) && (model->cal != NULL));
    WC_ASSERT(out != NULL);
    if (out == NULL) { return WC_STATUS_NOT_INITIALISED; }
    if ((model == NULL) || (model->cal == NULL)) {
        const wc_inverse_t none = { 0.0f, 0.0f, 0.0f, 0u };
        *out = none;  /* no calibration: no current */
        return WC_STATUS_NOT_INITIALISED;
    }
    wc_status_t status = WC_STATUS_OK;
    out->iterations = 0u;
    if (!wc_slip_valid(slip_rad_s)) { status |= WC_STATUS_SLIP_INVALID; }
    if (!wc_theta_valid(theta_degC)) { status |= WC_STATUS_THETA_INVALID; }
    if (!wc_in_range(torque_request_Nm, 0.0f, WC_TORQUE_MAX_Nm)) { status |= WC_STATUS_TORQUE_INVALID; }
    if (status != WC_STATUS_OK) {
        return wc_inverse_rejected(model, status, out);
    }
    wc_torque_point_t point;
    wc_torque_point(model, slip_rad_s, theta_degC, &point);
    uint32_t film_segment = WC_FILM_NO_SEGMENT;
    return wc_inverse_at_point(model, &point, torque_request_Nm, out, &film_segment);
}
