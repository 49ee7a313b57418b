/* The calibrations compiled into wc_tcu, selected with --calibration NAME.
 * To add one: `wetclutch lut tools/calibrations/NAME.toml --out lut`, then a
 * line in wc_tcu_calibrations.c. */
#ifndef WC_TCU_CALIBRATIONS_H
#define WC_TCU_CALIBRATIONS_H

#include <stddef.h>

#include "wetclutch/wc_calibration.h"

typedef struct {
    const char *name;
    const wc_calibration_t *calibration;
} wc_tcu_calibration_t;

extern const wc_tcu_calibration_t wc_tcu_calibrations[];
extern const size_t wc_tcu_calibration_count;

#endif /* WC_TCU_CALIBRATIONS_H */
