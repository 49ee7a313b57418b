#include "wetclutch/wc_film.h"

#include <stddef.h>

#include "wetclutch/wc_config.h"

float wc_film_hbar_m(const wc_film_table_t *table, float pressure_Pa)
{
    WC_ASSERT(table != NULL);
    if ((table == NULL) || (table->pressure_Pa == NULL) || (table->hbar_m == NULL) || (table->length < 2u)) {
        return 0.0f;  /* contract violation with asserts off */
    }
    const float *p = table->pressure_Pa;
    const uint32_t last = table->length - 1u;
    /* Clamp; the negated compare also sends NaN to the open-clutch end. */
    if (!(pressure_Pa > p[0])) { return table->hbar_m[0]; }
    if (pressure_Pa >= p[last]) { return table->hbar_m[last]; }

    /* Binary search for p[lo] <= pressure < p[hi]; at most log2(length) halvings. */
    uint32_t lo = 0u;
    uint32_t hi = last;
    for (uint32_t guard = 0u; (guard < 32u) && (hi - lo > 1u); ++guard) {
        const uint32_t mid = lo + (hi - lo) / 2u;
        if (p[mid] <= pressure_Pa) { lo = mid; } else { hi = mid; }
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

