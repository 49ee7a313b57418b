#ifndef WC_ARM_CALIBRATION_H
#define WC_ARM_CALIBRATION_H

#include <wetclutch/wc_calibration.h>

/* lut/wc_table1_calibration.h, compiled in wc_arm_calibration.c. */
extern const wc_calibration_t *const wc_arm_calibration;
/* lut/wc_bench_identified_calibration.h: the identified calibration that the main job and the
 * shift runner use (squeeze-film state on). */
extern const wc_calibration_t *const wc_arm_identified_calibration;

#endif /* WC_ARM_CALIBRATION_H */
