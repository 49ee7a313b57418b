/* The transmission (include/wetclutch/wc_transmission.h) for Python's ctypes:
 * tools/wetclutch/shift/transmission8.py drives wc_transmission_step in
 * process, in lockstep with the 8-speed plant, on the 8HP table
 * (lut/wc_8hp_gearbox.h). The calibrations come as calibration images (the
 * firmware's own decoder, wc_cal_image_load): one per element (its clutch),
 * one more whose shift part is the shift calibration. A host tool: no
 * arithmetic of its own, only the flat interface ctypes needs. */
#include <stddef.h>
#include <string.h>

#include <wetclutch/wc_transmission.h>
#include <wetclutch_can/wc_cal_image.h>

#include "wc_8hp_gearbox.h"

#define HOST_ELEMENTS 5u
#define HOST_REPORT_FIELDS 9u

typedef struct {
    wc_cal_set_t element[HOST_ELEMENTS];
    wc_cal_set_t shift;
    wc_transmission_config_t config;
    wc_transmission_t tx;
    wc_transmission_output_t out;
    wc_shift_report_t report;
} wc_host_tx_t;

/* One step's results, flat. */
typedef struct {
    float current_mA[HOST_ELEMENTS];
    float theta_degC[HOST_ELEMENTS];     /* each element's observer */
    float model_torque_Nm[HOST_ELEMENTS];
    float engine_delta_Nm;
    uint32_t engine_active;
    uint32_t gear;
    uint32_t phase;
    uint32_t type;
    uint32_t refusal;
    uint32_t ended;
    float report[HOST_REPORT_FIELDS];    /* inertia time s, slip RMSE rad/s, peak jerk, energy J, peak theta, flare,
                                          * tie-up, abort reason, fallback (on the step the shift ended) */
} wc_host_tx_step_t;

size_t wc_host_tx_size(void);
size_t wc_host_tx_step_size(void);
int wc_host_tx_init(wc_host_tx_t *h, const uint8_t *images, const uint32_t *lengths, uint32_t gear, float theta_degC,
                    float margin_factor, float floor_Nm);
int wc_host_tx_step(wc_host_tx_t *h, uint32_t request, uint32_t current_gear, uint32_t target_gear,
                    float turbine_torque_Nm, float target_time_s, float turbine_rad_s, float output_rad_s,
                    float oil_degC, float housing_degC, uint32_t safe, wc_host_tx_step_t *o);

size_t wc_host_tx_size(void) { return sizeof(wc_host_tx_t); }
size_t wc_host_tx_step_size(void) { return sizeof(wc_host_tx_step_t); }

/* images: HOST_ELEMENTS + 1 images back to back, lengths[i] bytes each. Returns 0, 100 + i for image i
 * refused (its status result in the low bits: 100 + 10 i + result is not needed: i is enough), or 200 + the
 * transmission's error. */
int wc_host_tx_init(wc_host_tx_t *h, const uint8_t *images, const uint32_t *lengths, uint32_t gear, float theta_degC,
                    float margin_factor, float floor_Nm)
{
    if ((h == NULL) || (images == NULL) || (lengths == NULL)) { return 1; }
    (void)memset(h, 0, sizeof *h);
    size_t offset = 0u;
    for (uint32_t i = 0u; i <= HOST_ELEMENTS; ++i) {
        wc_cal_set_t *set = (i < HOST_ELEMENTS) ? &h->element[i] : &h->shift;
        const wc_cal_image_status_t status = wc_cal_image_load(images + offset, lengths[i], set);
        if (status.result != (uint32_t)WC_CAL_IMAGE_OK) { return 100 + (int)i; }
        offset += lengths[i];
    }
    if (!h->shift.shift_enabled) { return 100 + (int)HOST_ELEMENTS; }
    h->config.gearbox = &wc_gearbox_8hp;
    for (uint32_t e = 0u; e < HOST_ELEMENTS; ++e) { h->config.element[e] = &h->element[e].clutch; }
    h->config.shift = &h->shift.shift;
    h->config.holding_margin_factor = margin_factor;
    h->config.holding_floor_Nm = floor_Nm;
    const wc_transmission_error_t error = wc_transmission_init(&h->tx, &h->config, gear, theta_degC);
    return (error == WC_TRANSMISSION_OK) ? 0 : 200 + (int)error;
}

int wc_host_tx_step(wc_host_tx_t *h, uint32_t request, uint32_t current_gear, uint32_t target_gear,
                    float turbine_torque_Nm, float target_time_s, float turbine_rad_s, float output_rad_s,
                    float oil_degC, float housing_degC, uint32_t safe, wc_host_tx_step_t *o)
{
    if ((h == NULL) || (o == NULL)) { return 1; }
    const wc_transmission_command_t command = { request != 0u, current_gear, target_gear, turbine_torque_Nm,
                                                target_time_s };
    const wc_transmission_input_t input = { turbine_rad_s, output_rad_s, oil_degC, housing_degC, safe != 0u };
    const bool ended = wc_transmission_step(&h->tx, &h->config, &command, &input, &h->out, &h->report);
    for (uint32_t e = 0u; e < HOST_ELEMENTS; ++e) {
        o->current_mA[e] = h->out.element[e].current_mA;
        o->theta_degC[e] = h->tx.element[e].theta_degC;
        o->model_torque_Nm[e] = h->out.element[e].model.torque_Nm;
    }
    o->engine_delta_Nm = h->out.engine_delta_Nm;
    o->engine_active = h->out.engine_active ? 1u : 0u;
    o->gear = h->out.gear;
    o->phase = h->out.shift_phase;
    o->type = h->out.shift_type;
    o->refusal = h->out.refusal;
    o->ended = ended ? 1u : 0u;
    const wc_shift_report_t *r = &h->report;
    const float report[HOST_REPORT_FIELDS] = { r->inertia_time_s, r->slip_rmse_rad_s, r->peak_jerk_m_s3,
                                               r->friction_energy_J, r->peak_theta_degC, r->flare ? 1.0f : 0.0f,
                                               r->tie_up ? 1.0f : 0.0f, (float)r->abort_reason, (float)r->fallback };
    (void)memcpy(o->report, report, sizeof report);
    return 0;
}
