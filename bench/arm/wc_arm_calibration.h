#ifndef WC_ARM_CALIBRATION_H
#define WC_ARM_CALIBRATION_H

#include <wetclutch/wc_calibration.h>

/* lut/wc_table1_calibration.h, compiled in wc_arm_calibration.c. */
extern const wc_calibration_t *const wc_arm_calibration;

#endif /* WC_ARM_CALIBRATION_H */
