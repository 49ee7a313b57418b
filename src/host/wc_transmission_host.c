/* The transmission (include/wetclutch/wc_transmission.h) for Python's ctypes:
 * tools/wetclutch/shift/transmission8.py drives wc_transmission_step in
 * process, in lockstep with the 8-speed plant. Everything comes as images,
 * through the firmware's own decoders: the gearbox table as a gearbox image
 * (wc_gearbox_image_load: the table of the plant's own gearbox description,
 * `wetclutch gearbox --image`; a gearbox of HOST_ELEMENTS elements), then one
 * calibration image per element (its clutch, wc_cal_image_load), one more
 * whose shift part is the shift calibration. A host tool: no arithmetic of
 * its own, only the flat interface ctypes needs.
 *
 * Two ways in (wc_host_tx_init, wc_host_tx_init_frames): wc_transmission_step
 * called directly, or the frame loop with config.transmission (wc_loop.h; the
 * same wc_loop_iterate as wc_tcu and wc_replay --gearbox): each step's values
 * encoded as ShiftCommand and GearboxSensors (the generated codec, E2E), the
 * loop stepped on GearboxSensors, the step record decoded from the frames it
 * sent (what is not on the bus, the model torque, is NaN); the step's frames
 * in and out are kept for wc_host_tx_frames. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include <wetclutch/wc_transmission.h>
#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_cal_image.h>
#include <wetclutch_can/wc_gearbox_image.h>
#include <wetclutch_can/wc_loop.h>

#define HOST_ELEMENTS 5u
#define HOST_REPORT_FIELDS 9u

typedef struct {
    wc_gearbox_t gearbox;
    wc_cal_set_t element[HOST_ELEMENTS];
    wc_cal_set_t shift;
    wc_transmission_config_t config;
    wc_transmission_t tx;
    wc_transmission_output_t out;
    wc_shift_report_t report;
    bool frames;                          /* wc_host_tx_init_frames: through the frame loop */
    wc_loop_t loop;
    uint8_t alive;                        /* the two input frames' alive counter */
    wc_can_frame_t in[2];                 /* the last step's frames: ShiftCommand, GearboxSensors */
    wc_can_frame_t sent[WC_LOOP_TX_FRAMES];
    uint32_t sent_count;
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

/* Element e's learned values (wc_transmission_learned; direct mode only): 0, or 1 (frames mode, no such
 * element, NULL). */
int wc_host_tx_learned(const wc_host_tx_t *h, uint32_t e, wc_adapt_values_t *values);
int wc_host_tx_learned(const wc_host_tx_t *h, uint32_t e, wc_adapt_values_t *values)
{
    if ((h == NULL) || h->frames || (values == NULL) || (e >= HOST_ELEMENTS)) { return 1; }
    return wc_transmission_learned(&h->tx, e, values) ? 0 : 1;
}

/* Load element e's learned values (wc_transmission_load_learned: in a gear, within the bands): 0, or 1. */
int wc_host_tx_load_learned(wc_host_tx_t *h, uint32_t e, const wc_adapt_values_t *values);
int wc_host_tx_load_learned(wc_host_tx_t *h, uint32_t e, const wc_adapt_values_t *values)
{
    if ((h == NULL) || h->frames || (values == NULL)) { return 1; }
    return wc_transmission_load_learned(&h->tx, &h->config, e, values) ? 0 : 1;
}

size_t wc_host_tx_learned_size(void);
size_t wc_host_tx_learned_size(void) { return sizeof(wc_adapt_values_t); }

size_t wc_host_tx_size(void) { return sizeof(wc_host_tx_t); }
size_t wc_host_tx_step_size(void) { return sizeof(wc_host_tx_step_t); }

/* images: the gearbox image, then HOST_ELEMENTS + 1 calibration images, back to back, lengths[i] bytes each.
 * Returns 0, 100 for a gearbox image refused or not of HOST_ELEMENTS elements, 101 + e for element e's image
 * refused, 101 + HOST_ELEMENTS for the shift image refused or without shift control, or 200 + the
 * transmission's error. */
int wc_host_tx_init(wc_host_tx_t *h, const uint8_t *images, const uint32_t *lengths, uint32_t gear, float theta_degC,
                    float margin_factor, float floor_Nm)
{
    if ((h == NULL) || (images == NULL) || (lengths == NULL)) { return 1; }
    (void)memset(h, 0, sizeof *h);
    if ((wc_gearbox_image_load(images, lengths[0], &h->gearbox).result != (uint32_t)WC_GEARBOX_IMAGE_OK) ||
        (h->gearbox.element_count != HOST_ELEMENTS)) {
        return 100;
    }
    size_t offset = lengths[0];
    for (uint32_t i = 0u; i <= HOST_ELEMENTS; ++i) {
        wc_cal_set_t *set = (i < HOST_ELEMENTS) ? &h->element[i] : &h->shift;
        const wc_cal_image_status_t status = wc_cal_image_load(images + offset, lengths[1u + i], set);
        if (status.result != (uint32_t)WC_CAL_IMAGE_OK) { return 101 + (int)i; }
        offset += lengths[1u + i];
    }
    if (!h->shift.shift_enabled) { return 101 + (int)HOST_ELEMENTS; }
    h->config.gearbox = &h->gearbox;
    for (uint32_t e = 0u; e < HOST_ELEMENTS; ++e) { h->config.element[e] = &h->element[e].clutch; }
    h->config.shift = &h->shift.shift;
    h->config.holding_margin_factor = margin_factor;
    h->config.holding_floor_Nm = floor_Nm;
    const wc_transmission_error_t error = wc_transmission_init(&h->tx, &h->config, gear, theta_degC);
    return (error == WC_TRANSMISSION_OK) ? 0 : 200 + (int)error;
}

/* As wc_host_tx_init, then the frame loop on that configuration (the shift image's loop timeouts and E2E).
 * Returns wc_host_tx_init's codes, or 300 when wc_loop_init refuses. */
int wc_host_tx_init_frames(wc_host_tx_t *h, const uint8_t *images, const uint32_t *lengths, uint32_t gear,
                           float theta_degC, float margin_factor, float floor_Nm);
int wc_host_tx_init_frames(wc_host_tx_t *h, const uint8_t *images, const uint32_t *lengths, uint32_t gear,
                           float theta_degC, float margin_factor, float floor_Nm)
{
    const int rc = wc_host_tx_init(h, images, lengths, gear, theta_degC, margin_factor, floor_Nm);
    if (rc != 0) { return rc; }
    wc_loop_config_t config = h->shift.loop;
    config.shift = NULL;
    config.offgoing = NULL;
    config.transmission = &h->config;
    config.transmission_start_gear = gear;
    if (wc_loop_init(&h->loop, NULL, &config, theta_degC) != WC_CAL_OK) { return 300; }
    h->frames = true;
    return 0;
}

/* The last step's frames (frames mode): up to max, inputs first (ShiftCommand, GearboxSensors), then what
 * the loop sent, each as id and 8 data bytes (DLC 8 throughout); returns how many were written. */
uint32_t wc_host_tx_frames(const wc_host_tx_t *h, uint32_t *ids, uint8_t *data, uint32_t max);
uint32_t wc_host_tx_frames(const wc_host_tx_t *h, uint32_t *ids, uint8_t *data, uint32_t max)
{
    if ((h == NULL) || (ids == NULL) || (data == NULL) || !h->frames) { return 0u; }
    uint32_t n = 0u;
    for (uint32_t i = 0u; (i < 2u + h->sent_count) && (n < max); ++i, ++n) {
        const wc_can_frame_t *f = (i < 2u) ? &h->in[i] : &h->sent[i - 2u];
        ids[n] = f->id;
        (void)memcpy(data + 8u * n, f->data, 8u);
    }
    return n;
}

static float clamp(float x, float lo, float hi) { return (x < lo) ? lo : ((x > hi) ? hi : x); }

/* One step through the frame loop: the frames in, the record decoded from the frames out. */
static int step_frames(wc_host_tx_t *h, uint32_t request, uint32_t current_gear, uint32_t target_gear,
                       float turbine_torque_Nm, float target_time_s, float turbine_rad_s, float output_rad_s,
                       float oil_degC, float housing_degC, wc_host_tx_step_t *o)
{
    const wc_can_shift_command_phys_t c = { request ? 1.0f : 0.0f, 0.0f, (float)target_gear,
                                            clamp(turbine_torque_Nm, -1000.0f, 1000.0f),
                                            roundf(clamp(target_time_s * 1e3f, 50.0f, 2000.0f)), (float)current_gear,
                                            h->alive };
    const wc_can_gearbox_sensors_phys_t s = { oil_degC, clamp(turbine_rad_s / WC_RAD_S_PER_RPM, -8000.0f, 8000.0f),
                                              clamp(output_rad_s / WC_RAD_S_PER_RPM, -8000.0f, 8000.0f),
                                              roundf(housing_degC), h->alive };
    h->alive = wc_e2e_counter_next(h->alive);
    h->in[0] = (wc_can_frame_t){ WC_CAN_SHIFT_COMMAND_FRAME_ID, 8u, 0u, { 0u } };
    h->in[1] = (wc_can_frame_t){ WC_CAN_GEARBOX_SENSORS_FRAME_ID, 8u, 0u, { 0u } };
    (void)wc_can_encode_shift_command(h->in[0].data, &c, sizeof h->in[0].data);
    (void)wc_can_encode_gearbox_sensors(h->in[1].data, &s, sizeof h->in[1].data);
    (void)wc_loop_iterate(&h->loop, WC_LOOP_CLOCK_FRAME, &h->in[0], false, h->sent);
    h->sent_count = wc_loop_iterate(&h->loop, WC_LOOP_CLOCK_FRAME, &h->in[1], false, h->sent);
    (void)memset(o, 0, sizeof *o);
    for (uint32_t e = 0u; e < HOST_ELEMENTS; ++e) { o->model_torque_Nm[e] = NAN; }
    for (uint32_t i = 0u; i < HOST_REPORT_FIELDS; ++i) { o->report[i] = NAN; }
    for (uint32_t i = 0u; i < h->sent_count; ++i) {
        wc_can_frame_t f = h->sent[i];
        if ((f.id >= WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID) && (f.id < WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID + HOST_ELEMENTS)) {
            const uint32_t e = f.id - WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID;
            if (wc_e2e_check_crc(f.id, f.data, f.dlc) != WC_E2E_OK) { return 2; }
            (void)wc_e2e_protect(WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID, f.data, f.dlc);  /* one layout: A's decoder */
            wc_can_element_a_vfs_command_phys_t v;
            if (wc_can_decode_element_a_vfs_command(&v, f.data, f.dlc) > WC_CAN_SATURATED) { return 2; }
            o->current_mA[e] = v.vfs_current_mA;
            o->theta_degC[e] = v.estimated_temp_degC;
        } else if (f.id == WC_CAN_GEARBOX_STATUS_FRAME_ID) {
            wc_can_gearbox_status_phys_t v;
            if (wc_can_decode_gearbox_status(&v, f.data, f.dlc) > WC_CAN_SATURATED) { return 2; }
            o->gear = (uint32_t)v.gear;
            o->phase = (uint32_t)v.shift_phase;
            o->type = v.shift_type;
            o->refusal = v.refusal;
        } else if (f.id == WC_CAN_ENGINE_TORQUE_REQUEST_FRAME_ID) {
            wc_can_engine_torque_request_phys_t v;
            if (wc_can_decode_engine_torque_request(&v, f.data, f.dlc) > WC_CAN_SATURATED) { return 2; }
            o->engine_active = (v.intervention_active > 0.5f) ? 1u : 0u;
            o->engine_delta_Nm = v.torque_delta_Nm;
        } else if (f.id == WC_CAN_SHIFT_REPORT_FRAME_ID) {
            wc_can_shift_report_phys_t v;
            if (wc_can_decode_shift_report(&v, f.data, f.dlc) > WC_CAN_SATURATED) { return 2; }
            o->ended = 1u;
            const float report[HOST_REPORT_FIELDS] = { v.inertia_phase_time_ms * 1e-3f, v.slip_rmse_rpm * WC_RAD_S_PER_RPM,
                                                       v.peak_jerk_m_per_s3, v.friction_energy_kJ * 1e3f,
                                                       v.peak_clutch_temp_degC, v.flare, v.tie_up,
                                                       (float)v.abort_reason, NAN /* the fallback: not on the bus */ };
            (void)memcpy(o->report, report, sizeof report);
        }
    }
    return (h->sent_count >= HOST_ELEMENTS + 2u) ? 0 : 2;
}

int wc_host_tx_step(wc_host_tx_t *h, uint32_t request, uint32_t current_gear, uint32_t target_gear,
                    float turbine_torque_Nm, float target_time_s, float turbine_rad_s, float output_rad_s,
                    float oil_degC, float housing_degC, uint32_t safe, wc_host_tx_step_t *o)
{
    if ((h == NULL) || (o == NULL)) { return 1; }
    if (h->frames) {  /* safe: the loop's own (the inputs' freshness) */
        return step_frames(h, request, current_gear, target_gear, turbine_torque_Nm, target_time_s, turbine_rad_s,
                           output_rad_s, oil_degC, housing_degC, o);
    }
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
