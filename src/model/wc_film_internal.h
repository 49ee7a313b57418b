/* Internal: the squeeze-film step of wc_film.h in two halves, so that
 * wc_clutch_step computes the contact pressure of its film state once per
 * period and shares it between the lead, the torque and the film's advance
 * (DESIGN section 9, section 11). For a table that passed
 * wc_calibration_check; the public functions of wc_film.h check theirs. */
#ifndef WC_FILM_INTERNAL_H
#define WC_FILM_INTERNAL_H

#include <stdint.h>

#include "wetclutch/wc_film.h"

typedef struct {
    float pressure_Pa;      /* p_c at the film: wc_film_pressure_Pa */
    float secant_Pa_per_m;  /* dp_c/dh_bar of the table segment that holds it (< 0) */
} wc_film_contact_t;

/* No segment known: wc_film_hbar_near_m searches. */
#define WC_FILM_NO_SEGMENT UINT32_MAX

/* wc_film_hbar_m without its argument checks, trying the table segment
 * `segment` (nodes segment, segment + 1) before the binary search: the same
 * value bit for bit, whatever the segment (a wrong one costs two compares). */
float wc_film_hbar_near_m(const wc_film_table_t *table, float pressure_Pa, uint32_t segment);

/* The contact pressure of the film hbar_m and its segment's secant. */
wc_film_contact_t wc_film_contact(const wc_film_table_t *table, float hbar_m);

/* wc_film_advance_m with the film's contact already computed (wc_film_contact
 * of the same hbar_m), the settled film's lookup starting at `segment`
 * (wc_film_hbar_near_m): bit for bit the same film. */
float wc_film_advance_at_m(const wc_film_table_t *table, float area_m2, float hbar_m,
                           const wc_film_contact_t *contact, float apply_force_N, float damping_N_s_m2, float dt_s,
                           uint32_t segment);

#endif /* WC_FILM_INTERNAL_H */
