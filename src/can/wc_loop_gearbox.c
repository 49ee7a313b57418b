/* The frame loop with the transmission (DESIGN 15; wc_loop.h,
 * config.transmission): GearboxSensors and ShiftCommand in, the elements'
 * VFS commands, GearboxStatus and EngineTorqueRequest out every period,
 * ShiftReport when a shift ends. The ring, the frames' checks and the
 * counters are wc_loop.c's; this file is the transmission's part of a step. */
#include <stddef.h>
#include <string.h>

#include "wetclutch/wetclutch.h"
#include "wc_loop_internal.h"

/* The six element frames share one layout (tests/python/test_dbc.py): each
 * is encoded with element A's encoder, then E2E-protected with its own id. */
WC_STATIC_ASSERT((WC_CAN_ELEMENT_F_VFS_COMMAND_FRAME_ID == WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID + 5u) &&
                 (WC_GEARBOX_ELEMENTS_MAX == 6u), one_element_frame_per_element);
WC_STATIC_ASSERT((WC_CAN_ELEMENT_A_VFS_COMMAND_LENGTH == WC_E2E_FRAME_BYTES) &&
                 (WC_CAN_GEARBOX_STATUS_LENGTH == WC_E2E_FRAME_BYTES) &&
                 (WC_CAN_GEARBOX_SENSORS_LENGTH == WC_E2E_FRAME_BYTES), transmission_frames_are_e2e_frames);
/* GearboxStatus says the type and refusal with the C enums' values. */
WC_STATIC_ASSERT((WC_CAN_GEARBOX_STATUS_SHIFT_TYPE_POWER_OFF_DOWNSHIFT_CHOICE == WC_SHIFT_TYPE_POWER_OFF_DOWN) &&
                 (WC_CAN_GEARBOX_STATUS_SHIFT_TYPE_POWER_ON_DOWNSHIFT_CHOICE == WC_SHIFT_TYPE_POWER_ON_DOWN) &&
                 (WC_CAN_GEARBOX_STATUS_SHIFT_TYPE_POWER_OFF_UPSHIFT_CHOICE == WC_SHIFT_TYPE_POWER_OFF_UP),
                 shift_type_is_the_dbc_choice);
WC_STATIC_ASSERT((WC_CAN_GEARBOX_STATUS_REFUSAL_NO_MODEL_CHOICE == WC_GEARBOX_SHIFT_NO_MODEL) &&
                 (WC_CAN_GEARBOX_STATUS_REFUSAL_NOT_CURRENT_CHOICE == WC_GEARBOX_SHIFT_NOT_CURRENT) &&
                 (WC_CAN_GEARBOX_STATUS_REFUSAL_SWAP_CHOICE == WC_GEARBOX_SHIFT_SWAP), refusal_is_the_dbc_choice);

wc_cal_error_t wc_loop_gearbox_init(wc_loop_t *loop, const wc_loop_config_t *config, float theta_start_degC)
{
    /* one clutch's options do not apply: the transmission has its own shift calibration and no bench input */
    if ((config->shift != NULL) || (config->offgoing != NULL) || config->bench_input_enabled) { return WC_CAL_NULL; }
    if (wc_transmission_init(&loop->transmission, config->transmission, config->transmission_start_gear,
                             theta_start_degC) != WC_TRANSMISSION_OK) {
        return WC_CAL_NULL;
    }
    loop->config = *config;
    wc_loop_input_reset(&loop->gearbox_in);
    wc_loop_input_reset(&loop->shift_in);
    wc_loop_input_reset(&loop->sensors_in);   /* not inputs here: never seen */
    wc_loop_input_reset(&loop->request_in);
    wc_loop_input_reset(&loop->bench_in);
    wc_loop_input_reset(&loop->offgoing_in);
    loop->gearbox_sensors.oil_temp_degC = theta_start_degC;
    loop->gearbox_sensors.housing_temp_degC = theta_start_degC;
    return WC_CAL_OK;
}

/* The inputs' freshness and the safe state, then the transmission's command and input. */
static WC_NOINLINE uint32_t prepare(wc_loop_t *loop, uint32_t step)
{
    if (wc_loop_update_freshness(&loop->gearbox_in, loop->config.sensor_timeout_periods,
                                 &loop->counters.sensor_timeouts)) {
        step |= WC_CAN_STATUS_SENSOR_TIMEOUT;
    }
    if (wc_loop_update_freshness(&loop->shift_in, loop->config.request_timeout_periods,
                                 &loop->counters.request_timeouts)) {
        step |= WC_CAN_STATUS_REQUEST_TIMEOUT;
    }
    const bool safe = wc_loop_safe_after(loop, step);
    if (safe) {
        step |= WC_CAN_STATUS_SAFE_STATE_ACTIVE | STEP_SAFE;
        loop->counters.safe_steps++;
    }
    const wc_can_shift_command_phys_t *c = &loop->shift_command;  /* decoded: every value within its DBC range */
    wc_transmission_command_t *command = &loop->transmission_command;
    command->request = c->shift_request > 0.5f;
    command->current_gear = (uint32_t)c->current_gear;
    command->target_gear = (uint32_t)c->target_gear;
    command->turbine_torque_Nm = c->turbine_torque_Nm;
    command->target_inertia_time_s = c->target_inertia_time_ms * 1.0e-3f;
    const wc_can_gearbox_sensors_phys_t *s = &loop->gearbox_sensors;
    wc_transmission_input_t *in = &loop->transmission_input;
    in->turbine_rad_s = s->turbine_speed_rpm * WC_RAD_S_PER_RPM;
    in->output_rad_s = s->output_speed_rpm * WC_RAD_S_PER_RPM;
    in->theta_oil_degC = s->oil_temp_degC;
    in->theta_housing_degC = s->housing_temp_degC;
    in->safe = safe;
    return step;
}

/* Element e's role (DBC ElementXVfsCommand.Role). */
static uint8_t role_of(const wc_gearbox_t *gearbox, const wc_transmission_t *tx, uint32_t e)
{
    const wc_gearbox_shift_t *row = tx->row;
    if (row != NULL) {
        if (e == row->oncoming) { return (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_ONCOMING_CHOICE; }
        if (e == row->offgoing) { return (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_OFFGOING_CHOICE; }
    }
    const uint32_t gear = (row != NULL) ? row->source_gear : tx->gear;
    return (((gearbox->closed_mask[gear] >> e) & 1u) != 0u)
               ? (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_HELD_CHOICE
               : (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_OPEN_CHOICE;
}

/* The cyclic frames: one VFS command per element, GearboxStatus, EngineTorqueRequest. Returns their count. */
static WC_NOINLINE uint32_t encode(wc_loop_t *loop, uint32_t step, wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    const wc_transmission_t *tx = &loop->transmission;
    const wc_transmission_output_t *o = &loop->transmission_out;
    const wc_gearbox_t *gearbox = loop->config.transmission->gearbox;
    const uint32_t elements = gearbox->element_count;  /* checked: <= WC_GEARBOX_ELEMENTS_MAX */
    uint32_t status = step & 0xFFFFu;
    bool held_locked = tx->row == NULL;   /* in a gear, every closed element locked: StatusLocked */
    uint32_t n = 0u;
    for (uint32_t e = 0u; (e < elements) && (e < WC_GEARBOX_ELEMENTS_MAX); ++e) {
        const wc_step_output_t *element = &o->element[e];
        const uint8_t role = role_of(gearbox, tx, e);
        const bool locked = (element->status & WC_STATUS_LOCKED) != 0u;
        if (role == (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_ROLE_HELD_CHOICE) { held_locked = held_locked && locked; }
        status |= wc_loop_status_bits(element->status & ~(wc_status_t)WC_STATUS_LOCKED);
        const wc_can_element_a_vfs_command_phys_t command = {
            .vfs_current_mA = element->current_mA,
            .pressure_command_kPa = element->pressure_command_Pa * 1.0e-3f,
            .estimated_temp_degC = element->theta_degC,
            .role = role,
            .locked = locked ? (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_LOCKED_LOCKED_CHOICE
                             : (uint8_t)WC_CAN_ELEMENT_A_VFS_COMMAND_LOCKED_SLIPPING_CHOICE,
            .alive_counter = loop->tx_alive_element[e],
        };
        loop->tx_alive_element[e] = wc_e2e_counter_next(loop->tx_alive_element[e]);
        wc_can_frame_t *f = &out[n++];
        wc_loop_frame_header(f, WC_CAN_ELEMENT_A_VFS_COMMAND_FRAME_ID + e, WC_CAN_ELEMENT_A_VFS_COMMAND_LENGTH);
        if (wc_can_encode_element_a_vfs_command(f->data, &command, sizeof f->data) == WC_CAN_SATURATED) {
            status |= WC_CAN_STATUS_SATURATED;
        }
        (void)wc_e2e_protect(f->id, f->data, sizeof f->data);  /* the CRC over this element's data id */
    }
    if (held_locked) { status |= WC_CAN_STATUS_LOCKED; }
    const wc_can_gearbox_status_phys_t frame_status = {
        .gear = (float)o->gear,
        .target_gear = (float)((tx->row != NULL) ? tx->row->target_gear : o->gear),
        .shift_phase = (float)o->shift_phase,
        .shift_type = (uint8_t)o->shift_type,
        .refusal = (uint8_t)o->refusal,
        .status = (uint16_t)status,
        .alive_counter = loop->tx_alive_status,
    };
    loop->tx_alive_status = wc_e2e_counter_next(loop->tx_alive_status);
    wc_loop_frame_header(&out[n], WC_CAN_GEARBOX_STATUS_FRAME_ID, WC_CAN_GEARBOX_STATUS_LENGTH);
    (void)wc_can_encode_gearbox_status(out[n].data, &frame_status, sizeof out[n].data);
    n++;
    /* no engine request in the safe state */
    wc_loop_engine_frame(loop, o->engine_active && ((step & STEP_SAFE) == 0u), o->engine_delta_Nm, &out[n]);
    return n + 1u;
}

uint32_t wc_loop_gearbox_run(wc_loop_t *loop, uint32_t step, wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    step = prepare(loop, step);
    if (wc_transmission_step(&loop->transmission, loop->config.transmission, &loop->transmission_command,
                             &loop->transmission_input, &loop->transmission_out, &loop->report)) {
        step |= STEP_REPORT;
    }
    uint32_t n = encode(loop, step, out);
    if ((step & STEP_REPORT) != 0u) { wc_loop_shift_report_frame(&loop->report, &out[n++]); }
    loop->counters.steps++;
    loop->counters.frames_out += n;
    return n;
}
