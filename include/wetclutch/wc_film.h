/* Average oil-film thickness from contact pressure, h_bar(p_c) (eq. 9, 15,
 * 16), by cubic Hermite interpolation of the generated table. */
#ifndef WC_FILM_H
#define WC_FILM_H

#include "wc_calibration.h"

/* h_bar in m. Clamps at both ends of the table: below its first node (an open
 * clutch) the thickest film, above its last the thinnest. NaN maps to the
 * first node (open clutch). The table must have passed wc_calibration_check. */
float wc_film_hbar_m(const wc_film_table_t *table, float pressure_Pa);

#endif /* WC_FILM_H */
