#include "wc_tcu_calibrations.h"

#include "wc_bench_identified_calibration.h"
#include "wc_table1_calibration.h"

const wc_tcu_calibration_t wc_tcu_calibrations[] = {
    {"table1", &wc_table1_calibration},  /* paper Table 1 + project defaults */
    /* identified from the simulated bench campaign (tools/calibrations/bench_identified.toml) */
    {"bench_identified", &wc_bench_identified_calibration},
};
const size_t wc_tcu_calibration_count = sizeof wc_tcu_calibrations / sizeof wc_tcu_calibrations[0];
