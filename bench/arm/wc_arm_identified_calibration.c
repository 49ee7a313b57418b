/* The bench_identified calibration (squeeze-film state on: the one the main
 * job and the shift runner use) and its h_bar(p_c) table, in a library of its
 * own so that the flash reported for the calibration stays table1's. */
#include "wc_arm_calibration.h"

#include "wc_bench_identified_calibration.h"

const wc_calibration_t *const wc_arm_identified_calibration = &wc_bench_identified_calibration;
