/* Average oil-film thickness from contact pressure, h_bar(p_c) (eq. 9, 15,
 * 16), by cubic Hermite interpolation of the generated table. */
#ifndef WC_FILM_H
#define WC_FILM_H

#include "wc_calibration.h"

/* h_bar in m. Clamps at both ends of the table: below its first node (an open
 * clutch) the thickest film, above its last the thinnest. NaN maps to the
 * first node (open clutch). The table must have passed wc_calibration_check. */
float wc_film_hbar_m(const wc_film_table_t *table, float pressure_Pa);

/* Safeguarded Newton steps of wc_film_pressure_Pa on one segment: three from
 * the linear guess reach float precision on the tables `wetclutch lut` writes
 * (tests/c/test_film.c); the bracket keeps any table's answer in its segment. */
#ifndef WC_FILM_INVERSE_ITERATIONS
#define WC_FILM_INVERSE_ITERATIONS 3u
#endif

/* The inverse of wc_film_hbar_m: the contact pressure p_c in Pa at which the
 * film is hbar_m. 0 at or above the table's first (open-clutch) film, NaN
 * included; the last node's pressure at or below the last film. */
float wc_film_pressure_Pa(const wc_film_table_t *table, float hbar_m);

/* One control period dt_s of the squeeze film (DESIGN section 9): the film
 * h_bar in m after dt_s under apply_force_N, from hbar_m, with the film's
 * damping D = 3 pi phi mu_v(theta) K / 2 in N s m^2 (wc_model_t's
 * film_damping_m4 times mu_v). Moves towards the settled film
 * wc_film_hbar_m(F_app / A_f) and never past it: stable for every state, force
 * and damping > 0. hbar_m must be a film of the table's range. */
float wc_film_advance_m(const wc_film_table_t *table, float area_m2, float hbar_m, float apply_force_N,
                        float damping_N_s_m2, float dt_s);

#endif /* WC_FILM_H */
