#include "wetclutch/wc_film.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "wc_film_internal.h"
#include "wetclutch/wc_config.h"

float wc_film_hbar_m(const wc_film_table_t *table, float pressure_Pa)
{
    WC_ASSERT(table != NULL);
    if ((table == NULL) || (table->pressure_Pa == NULL) || (table->hbar_m == NULL) || (table->length < 2u)) {
        return 0.0f;  /* contract violation with asserts off */
    }
    return wc_film_hbar_near_m(table, pressure_Pa, WC_FILM_NO_SEGMENT);
}

float wc_film_hbar_near_m(const wc_film_table_t *table, float pressure_Pa, uint32_t segment)
{
    const float *p = table->pressure_Pa;
    const uint32_t last = table->length - 1u;
    /* Clamp; the negated compare also sends NaN to the open-clutch end. */
    if (!(pressure_Pa > p[0])) { return table->hbar_m[0]; }
    if (pressure_Pa >= p[last]) { return table->hbar_m[last]; }

    uint32_t lo = segment;
    uint32_t hi = segment + 1u;
    if (!((segment < last) && (p[lo] <= pressure_Pa) && (pressure_Pa < p[hi]))) {
        /* Binary search for p[lo] <= pressure < p[hi]; at most log2(length) halvings. */
        lo = 0u;
        hi = last;
        for (uint32_t guard = 0u; (guard < 32u) && (hi - lo > 1u); ++guard) {
            const uint32_t mid = lo + (hi - lo) / 2u;
            if (p[mid] <= pressure_Pa) { lo = mid; } else { hi = mid; }
        }
    }

    /* Cubic Hermite with the exact slopes d h_bar / d p_c at both nodes. */
    const float width_Pa = p[hi] - p[lo];
    const float t = (pressure_Pa - p[lo]) / width_Pa;
    const float t2 = t * t;
    const float t3 = t2 * t;
    const float h00 = 2.0f * t3 - 3.0f * t2 + 1.0f;
    const float h10 = t3 - 2.0f * t2 + t;
    const float h01 = -2.0f * t3 + 3.0f * t2;
    const float h11 = t3 - t2;
    return h00 * table->hbar_m[lo] + h10 * width_Pa * table->slope_m_per_Pa[lo] +
           h01 * table->hbar_m[hi] + h11 * width_Pa * table->slope_m_per_Pa[hi];
}


/* The contact pressure at which the table's film is hbar_m (the inverse of
 * wc_film_hbar_m), and the secant dp_c/dh_bar of the segment that holds it
 * (finite and < 0: the nodes strictly decrease), for a valid table. */
static float film_pressure_Pa(const wc_film_table_t *table, float hbar_m, float *secant_Pa_per_m)
{
    const float *h = table->hbar_m;  /* strictly decreasing (wc_calibration_check) */
    const float *p = table->pressure_Pa;
    const uint32_t last = table->length - 1u;
    /* At or above the open-clutch film no asperity touches (NaN counts as
     * open); below the last node, the last node's pressure. */
    if (!(hbar_m < h[0])) {
        *secant_Pa_per_m = (p[1] - p[0]) / (h[1] - h[0]);
        return 0.0f;
    }
    if (hbar_m <= h[last]) {
        *secant_Pa_per_m = (p[last] - p[last - 1u]) / (h[last] - h[last - 1u]);
        return p[last];
    }
    /* Binary search for h[lo] > hbar >= h[hi]; at most log2(length) halvings. */
    uint32_t lo = 0u;
    uint32_t hi = last;
    for (uint32_t guard = 0u; (guard < 32u) && (hi - lo > 1u); ++guard) {
        const uint32_t mid = lo + (hi - lo) / 2u;
        if (h[mid] > hbar_m) { lo = mid; } else { hi = mid; }
    }
    const float width_Pa = p[hi] - p[lo];
    *secant_Pa_per_m = width_Pa / (h[hi] - h[lo]);
    /* Solve the segment's cubic (the Hermite of wc_film_hbar_m, monotone by
     * Fritsch-Carlson) for t: safeguarded Newton from the linear guess, the
     * bracket [t_lo, t_hi] shrinking each step, so t stays in the segment
     * whatever the slopes. */
    const float m0 = width_Pa * table->slope_m_per_Pa[lo];
    const float m1 = width_Pa * table->slope_m_per_Pa[hi];
    const float c2 = 3.0f * (h[hi] - h[lo]) - 2.0f * m0 - m1;
    const float c3 = 2.0f * (h[lo] - h[hi]) + m0 + m1;
    float t_lo = 0.0f;
    float t_hi = 1.0f;
    float t = (hbar_m - h[lo]) / (h[hi] - h[lo]);
    for (uint32_t i = 0u; i < WC_FILM_INVERSE_ITERATIONS; ++i) {
        const float residual_m = (h[lo] - hbar_m) + t * (m0 + t * (c2 + t * c3));
        if (residual_m > 0.0f) { t_lo = t; } else { t_hi = t; }  /* h_bar(t) falls with t */
        const float derivative_m = m0 + t * (2.0f * c2 + 3.0f * t * c3);
        const float newton = (derivative_m < 0.0f) ? t - residual_m / derivative_m : -1.0f;
        /* inclusive: a converged step lands on t, which is now a bracket end */
        t = ((newton >= t_lo) && (newton <= t_hi)) ? newton : 0.5f * (t_lo + t_hi);
    }
    return p[lo] + t * width_Pa;
}

float wc_film_pressure_Pa(const wc_film_table_t *table, float hbar_m)
{
    WC_ASSERT(table != NULL);
    if ((table == NULL) || (table->pressure_Pa == NULL) || (table->hbar_m == NULL) || (table->length < 2u)) {
        return 0.0f;  /* contract violation with asserts off */
    }
    float secant_Pa_per_m;
    return film_pressure_Pa(table, hbar_m, &secant_Pa_per_m);
}

wc_film_contact_t wc_film_contact(const wc_film_table_t *table, float hbar_m)
{
    wc_film_contact_t contact;
    contact.pressure_Pa = film_pressure_Pa(table, hbar_m, &contact.secant_Pa_per_m);
    return contact;
}

float wc_film_advance_m(const wc_film_table_t *table, float area_m2, float hbar_m, float apply_force_N,
                        float damping_N_s_m2, float dt_s)
{
    const wc_film_contact_t contact = wc_film_contact(table, hbar_m);
    return wc_film_advance_at_m(table, area_m2, hbar_m, &contact, apply_force_N, damping_N_s_m2, dt_s,
                                WC_FILM_NO_SEGMENT);
}

float wc_film_advance_at_m(const wc_film_table_t *table, float area_m2, float hbar_m,
                           const wc_film_contact_t *contact, float apply_force_N, float damping_N_s_m2, float dt_s,
                           uint32_t segment)
{
    /* Where the film settles under this force: eq. 16 (F_h = 0). */
    const float settled_m = wc_film_hbar_near_m(table, apply_force_N / area_m2, segment);
    /* DESIGN section 9, eq. 10 with Reynolds' squeeze force between annular
     * plates: F_app = F_c(h_bar) + D (-dh_bar/dt) / h_bar^3, D = 3 pi phi mu_v K / 2.
     * In u = 1 / h_bar^2 it reads D du/dt = 2 (F_app - F_c): the h_bar^3 of the
     * wide gap drops out (exact there), and the asperities' stiffness
     * dF_c/du = -A_f (dp_c/dh_bar) h_bar^3 / 2 >= 0 is taken implicitly. */
    const float secant_Pa_per_m = contact->secant_Pa_per_m;
    const float squeeze_N = apply_force_N - area_m2 * contact->pressure_Pa;
    const float hbar3_m3 = hbar_m * hbar_m * hbar_m;
    const float u_per_m2 = 1.0f / (hbar_m * hbar_m);
    const float du_per_m2 = 2.0f * dt_s * squeeze_N / (damping_N_s_m2 - dt_s * area_m2 * secant_Pa_per_m * hbar3_m3);
    const float u_next_per_m2 = u_per_m2 + du_per_m2;
    const float u_settled_per_m2 = 1.0f / (settled_m * settled_m);
    /* Never past the settled film: each step moves h_bar towards it and stops
     * there, so under a held force the film converges without overshoot, for
     * any damping (a NaN step also lands on the settled film). */
    const bool closing = u_settled_per_m2 > u_per_m2;
    const bool short_of_settled = closing ? (u_next_per_m2 < u_settled_per_m2) : (u_next_per_m2 > u_settled_per_m2);
    if (!short_of_settled) { return settled_m; }
    const bool forward = closing ? (u_next_per_m2 > u_per_m2) : (u_next_per_m2 < u_per_m2);
    return forward ? 1.0f / sqrtf(u_next_per_m2) : hbar_m;
}
