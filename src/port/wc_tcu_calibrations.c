#include "wc_tcu_calibrations.h"

#include <string.h>

#include "wc_8hp_gearbox.h"
#include "wc_bench_identified_calibration.h"
#include "wc_shift_1_2_shift.h"
#include "wc_table1_calibration.h"

const wc_tcu_calibration_t wc_tcu_calibrations[] = {
    {"table1", &wc_table1_calibration},  /* paper Table 1 + project defaults */
    /* identified from the simulated bench campaign (tools/calibrations/bench_identified.toml) */
    {"bench_identified", &wc_bench_identified_calibration},
};
const size_t wc_tcu_calibration_count = sizeof wc_tcu_calibrations / sizeof wc_tcu_calibrations[0];

const wc_tcu_shift_calibration_t wc_tcu_shift_calibrations[] = {
    {"shift_1_2_full", &wc_shift_1_2_full},          /* (c) 2-DOF, full model */
    {"shift_1_2_blind", &wc_shift_1_2_blind},        /* (b) 2-DOF, thermal-blind */
    {"shift_1_2_feedback", &wc_shift_1_2_feedback},  /* (a) PI only */
    {"shift_1_2_nolag", &wc_shift_1_2_nolag},        /* (c) without lag compensation */
    {"shift_1_2_adaptive", &wc_shift_1_2_adaptive},  /* (c) with adaptation (DESIGN 12) */
    /* the whole shift (DESIGN 14): fill, off-going clutch, engine intervention */
    {"shift_1_2_whole_full", &wc_shift_1_2_whole_full},          /* (c) */
    {"shift_1_2_whole_blind", &wc_shift_1_2_whole_blind},        /* (b) */
    {"shift_1_2_whole_feedback", &wc_shift_1_2_whole_feedback},  /* (a) */
};
const size_t wc_tcu_shift_calibration_count = sizeof wc_tcu_shift_calibrations / sizeof wc_tcu_shift_calibrations[0];

const wc_shift_calibration_t *wc_tcu_find_shift_calibration(const char *name)
{
    for (size_t i = 0; i < wc_tcu_shift_calibration_count; ++i) {
        if (strcmp(name, wc_tcu_shift_calibrations[i].name) == 0) { return wc_tcu_shift_calibrations[i].calibration; }
    }
    return NULL;
}

const wc_gearbox_t *wc_tcu_find_gearbox(const char *name)
{
    static const struct {
        const char *name;
        const wc_gearbox_t *gearbox;
    } gearboxes[] = {
        {"8hp", &wc_gearbox_8hp},  /* tools/gearboxes/8hp.toml: five elements, eight forward gears and reverse */
    };
    for (size_t i = 0; i < sizeof gearboxes / sizeof gearboxes[0]; ++i) {
        if (strcmp(name, gearboxes[i].name) == 0) { return gearboxes[i].gearbox; }
    }
    return NULL;
}
