/* The calibrations compiled into wc_tcu, selected with --calibration NAME.
 * To add one: `wetclutch lut tools/calibrations/NAME.toml --out lut`, then a
 * line in wc_tcu_calibrations.c. */
#ifndef WC_TCU_CALIBRATIONS_H
#define WC_TCU_CALIBRATIONS_H

#include <stddef.h>

#include "wetclutch/wc_calibration.h"
#include "wetclutch/wc_gearbox.h"
#include "wetclutch/wc_shift.h"

typedef struct {
    const char *name;
    const wc_calibration_t *calibration;
} wc_tcu_calibration_t;

extern const wc_tcu_calibration_t wc_tcu_calibrations[];
extern const size_t wc_tcu_calibration_count;

/* Shift calibrations (DESIGN 10), selected with --shift NAME: the variants of
 * tools/calibrations/shift_1_2.toml (`wetclutch lut ... --out lut`). */
typedef struct {
    const char *name;
    const wc_shift_calibration_t *calibration;
} wc_tcu_shift_calibration_t;

extern const wc_tcu_shift_calibration_t wc_tcu_shift_calibrations[];
extern const size_t wc_tcu_shift_calibration_count;

/* The named shift calibration, or NULL. */
const wc_shift_calibration_t *wc_tcu_find_shift_calibration(const char *name);

/* Gearbox descriptions (DESIGN 15), selected with --gearbox NAME: the tables
 * `wetclutch gearbox` generates (lut/wc_<name>_gearbox.h). The named one, or NULL. */
const wc_gearbox_t *wc_tcu_find_gearbox(const char *name);

#endif /* WC_TCU_CALIBRATIONS_H */
