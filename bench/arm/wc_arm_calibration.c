/* The table1 calibration and its h_bar(p_c) table as a firmware translation
 * unit holds them (static const data from lut/). Its own library target, so
 * scripts/bench_arm.sh can report its flash next to the two libraries. */
#include "wc_arm_calibration.h"

#include "wc_table1_calibration.h"

const wc_calibration_t *const wc_arm_calibration = &wc_table1_calibration;
