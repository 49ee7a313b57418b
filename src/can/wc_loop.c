#include "wetclutch_can/wc_loop.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "wetclutch/wetclutch.h"
#include "wc_loop_internal.h"

/* Sizes the loop relies on. */
WC_STATIC_ASSERT((WC_LOOP_RX_CAPACITY & (WC_LOOP_RX_CAPACITY - 1u)) == 0u, rx_ring_is_a_power_of_two);
WC_STATIC_ASSERT(WC_LOOP_RX_CAPACITY >= 2u * WC_LOOP_RX_ID_COUNT, rx_ring_holds_two_periods_of_input);
WC_STATIC_ASSERT((WC_LOOP_TX_CYCLIC == 2u) && (WC_LOOP_TX_FRAMES >= WC_LOOP_TX_CYCLIC + WC_LOOP_TX_WHOLE_SHIFT + 2u) &&
                 (WC_LOOP_TX_FRAMES >= WC_LOOP_TX_GEARBOX_CYCLIC + 1u), tx_holds_the_cyclic_frames_and_the_reports);
WC_STATIC_ASSERT(WC_CAN_ADAPTATION_REPORT_LENGTH <= sizeof(((wc_can_frame_t *)0)->data), adaptation_report_fits_a_frame);
WC_STATIC_ASSERT(WC_CAN_SHIFT_COMMAND_LENGTH == WC_E2E_FRAME_BYTES, shift_command_is_an_e2e_frame);
WC_STATIC_ASSERT(WC_CAN_SHIFT_REPORT_LENGTH <= sizeof(((wc_can_frame_t *)0)->data), shift_report_fits_a_frame);
WC_STATIC_ASSERT(WC_CAN_CLUTCH_SENSORS_LENGTH == WC_E2E_FRAME_BYTES, clutch_sensors_is_an_e2e_frame);
WC_STATIC_ASSERT(WC_CAN_TORQUE_REQUEST_LENGTH == WC_E2E_FRAME_BYTES, torque_request_is_an_e2e_frame);
WC_STATIC_ASSERT(WC_CAN_VFS_COMMAND_LENGTH == WC_E2E_FRAME_BYTES, vfs_command_is_an_e2e_frame);
WC_STATIC_ASSERT(WC_CAN_CLUTCH_ESTIMATE_LENGTH <= sizeof(((wc_can_frame_t *)0)->data), clutch_estimate_fits_a_frame);
WC_STATIC_ASSERT(WC_CAN_BENCH_MEASUREMENT_LENGTH <= sizeof(((wc_can_frame_t *)0)->data), bench_fits_a_frame);
WC_STATIC_ASSERT(WC_CAN_STATUS_BITS <= 16u, status_word_is_16_bits);

/* The shift part of a configuration: a shift calibration that passes its
 * check (which says which field fails), and with the whole shift (DESIGN 14)
 * the off-going clutch's calibration. */
static bool shift_config_usable(const wc_loop_config_t *config)
{
    if (config->shift == NULL) { return true; }
    return (wc_shift_calibration_check(config->shift) == WC_SHIFT_CAL_OK) &&
           ((config->shift->coordinator != 1u) || (config->offgoing != NULL));
}

wc_cal_error_t wc_loop_init(wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config,
                            float theta_start_degC)
{
    WC_ASSERT((loop != NULL) && (config != NULL));
    if ((loop == NULL) || (config == NULL)) { return WC_CAL_NULL; }
    memset(loop, 0, sizeof *loop);
    if (wc_loop_gearbox(config)) { return wc_loop_gearbox_init(loop, config, theta_start_degC); }
    if (!shift_config_usable(config)) { return WC_CAL_NULL; }
    const wc_cal_error_t error = wc_clutch_init(&loop->clutch, cal, theta_start_degC);
    if (error != WC_CAL_OK) { return error; }
    if (wc_loop_whole_shift(config)) {
        const wc_cal_error_t offgoing_error = wc_clutch_init(&loop->offgoing, config->offgoing, theta_start_degC);
        if (offgoing_error != WC_CAL_OK) { return offgoing_error; }
    }
    loop->whole.clutch = &loop->offgoing;  /* the shift controller's view of the off-going clutch */
    loop->whole.in = &loop->offgoing_input;
    loop->whole.out = &loop->offgoing_last;
    wc_shift_init(&loop->shift);
    wc_adapt_reset(&loop->adapt);
    loop->adapt.status = WC_ADAPT_STATUS_IMAGE_MISSING;  /* until wc_loop_load_adaptation */
    loop->config = *config;
    wc_loop_input_reset(&loop->sensors_in);
    wc_loop_input_reset(&loop->request_in);
    wc_loop_input_reset(&loop->bench_in);
    wc_loop_input_reset(&loop->shift_in);
    wc_loop_input_reset(&loop->offgoing_in);
    loop->sensors.oil_temp_degC = theta_start_degC;
    loop->sensors.housing_temp_degC = theta_start_degC;
    loop->request.mode = WC_CAN_TORQUE_REQUEST_MODE_OPEN_CHOICE;
    return WC_CAL_OK;
}

wc_cal_error_t wc_loop_recalibrate(wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config)
{
    WC_ASSERT((loop != NULL) && (cal != NULL) && (config != NULL));
    if ((loop == NULL) || (cal == NULL) || (config == NULL)) { return WC_CAL_NULL; }
    if (wc_loop_gearbox(config) || wc_loop_gearbox(&loop->config)) { return WC_CAL_NULL; }  /* not online yet */
    if (!shift_config_usable(config)) { return WC_CAL_NULL; }
    /* the whole shift cannot be switched on or off online */
    if (wc_loop_whole_shift(config) != wc_loop_whole_shift(&loop->config)) { return WC_CAL_NULL; }
    wc_model_t model;
    const wc_cal_error_t error = wc_model_init(&model, cal);  /* the check and the constants derived once */
    if (error != WC_CAL_OK) { return error; }
    if (wc_loop_whole_shift(config)) {
        wc_model_t offgoing_model;
        const wc_cal_error_t offgoing_error = wc_model_init(&offgoing_model, config->offgoing);
        if (offgoing_error != WC_CAL_OK) { return offgoing_error; }
        loop->offgoing.model = offgoing_model;
    }
    loop->clutch.model = model;
    const wc_loop_config_t kept = loop->config;
    loop->config = *config;
    loop->config.bench_input_enabled = kept.bench_input_enabled;
    loop->config.adaptation_changed = kept.adaptation_changed;
    loop->config.adaptation_context = kept.adaptation_context;
    return WC_CAL_OK;
}

uint32_t wc_loop_load_adaptation(wc_loop_t *loop, const uint8_t *image, size_t length)
{
    WC_ASSERT(loop != NULL);
    if (loop == NULL) { return (uint32_t)WC_IMAGE_MISSING; }
    return wc_adapt_image_load(&loop->adapt, loop->config.shift, 0u, image, length);
}

bool wc_loop_request_adaptation_reset(wc_loop_t *loop)
{
    WC_ASSERT(loop != NULL);
    if ((loop == NULL) || (loop->config.shift == NULL) || (loop->config.shift->adaptation != 1u) ||
        wc_shift_phase_running(loop->shift.phase)) {
        return false;
    }
    loop->adaptation_reset_requested = true;
    return true;
}

/* Status bit of each reject reason, indexed by wc_loop_reject_t in its
 * order. SYNC frames are in sequence: no error, the input's timeout bit
 * says it is not yet used. */
static const uint16_t reject_flag[] = {
    WC_CAN_STATUS_CRC_ERROR,          /* WC_REJECT_CRC */
    WC_CAN_STATUS_COUNTER_ERROR,      /* WC_REJECT_COUNTER */
    WC_CAN_STATUS_FRAME_LOST,         /* WC_REJECT_SHORT */
    WC_CAN_STATUS_FRAME_LOST,         /* WC_REJECT_UNKNOWN_ID */
    WC_CAN_STATUS_FRAME_LOST,         /* WC_REJECT_FORMAT */
    WC_CAN_STATUS_IMPLAUSIBLE_INPUT,  /* WC_REJECT_IMPLAUSIBLE */
    WC_CAN_STATUS_FRAME_LOST,         /* WC_REJECT_OVERFLOW (raised by the step, not the ISR) */
    0u,                               /* WC_REJECT_SYNC */
};
WC_STATIC_ASSERT(sizeof reject_flag / sizeof reject_flag[0] == (size_t)WC_REJECT_REASONS, reject_flag_for_every_reason);

static void reject(wc_loop_t *loop, wc_loop_reject_t reason)
{
    loop->counters.rejected[reason]++;
    loop->pending_status = (uint16_t)(loop->pending_status | reject_flag[reason]);
}

/* Producer side of the single-producer/single-consumer ring: writes only
 * rx[], rx_tail, counters.frames_in and counters.rejected[WC_REJECT_OVERFLOW]. */
bool wc_loop_receive(wc_loop_t *loop, const wc_can_frame_t *frame)
{
    WC_ASSERT((loop != NULL) && (frame != NULL));
    if ((loop == NULL) || (frame == NULL)) { return false; }
    loop->counters.frames_in++;
    const uint32_t tail = loop->rx_tail;
    if ((tail - loop->rx_head) >= WC_LOOP_RX_CAPACITY) {
        loop->counters.rejected[WC_REJECT_OVERFLOW]++;  /* no status bit: pending_status is the consumer's */
        return false;
    }
    loop->rx[tail % WC_LOOP_RX_CAPACITY] = *frame;
    WC_MEMORY_BARRIER();        /* the frame is written before it is published */
    loop->rx_tail = tail + 1u;
    return true;
}

void wc_loop_deadline_missed(wc_loop_t *loop, uint32_t missed)
{
    WC_ASSERT(loop != NULL);
    if (loop == NULL) { return; }
    loop->counters.deadline_misses += missed;
    if (missed > 0u) { loop->pending_status = (uint16_t)(loop->pending_status | WC_CAN_STATUS_DEADLINE_MISS); }
}

void wc_loop_port_event(wc_loop_t *loop, wc_loop_port_event_t event, uint32_t count)
{
    WC_ASSERT(loop != NULL);
    if ((loop == NULL) || (count == 0u)) { return; }
    if (event == WC_LOOP_PORT_RX_DROPPED) {
        loop->counters.frames_lost_by_port += count;
        loop->pending_status = (uint16_t)(loop->pending_status | WC_CAN_STATUS_FRAME_LOST);
    } else {
        loop->counters.bus_errors += count;
        loop->pending_status = (uint16_t)(loop->pending_status | WC_CAN_STATUS_BUS_ERROR);
    }
}

/* accept() tests the usable E2E statuses and the decode errors by their order. */
WC_STATIC_ASSERT((WC_E2E_STATUS_OK < WC_E2E_STATUS_SYNC) && (WC_E2E_STATUS_OKSOMELOST < WC_E2E_STATUS_SYNC) &&
                 (WC_E2E_STATUS_INITIAL < WC_E2E_STATUS_SYNC) && (WC_E2E_STATUS_SYNC < WC_E2E_STATUS_REPEATED) &&
                 (WC_E2E_STATUS_REPEATED < WC_E2E_STATUS_WRONGSEQUENCE) && (WC_E2E_STATUS_INITIAL == 2),
                 e2e_usable_statuses_come_first);
WC_STATIC_ASSERT((WC_CAN_SATURATED < WC_CAN_ERR_NAN) && (WC_CAN_ERR_NAN < WC_CAN_ERR_RANGE), can_errors_come_last);

/* Map a decode result and (for E2E frames) the alive counter to use / reject. */
WC_INLINE_HOT bool accept(wc_loop_t *loop, wc_loop_input_t *in, wc_can_result_t decoded, bool e2e, uint8_t alive)
{
    if (decoded == WC_CAN_ERR_SIZE) { reject(loop, WC_REJECT_SHORT); return false; }
    if (decoded == WC_CAN_ERR_CRC) { reject(loop, WC_REJECT_CRC); return false; }
    /* The counter is checked before plausibility: an implausible frame still
     * proves the sender is alive and in sequence. */
    if (e2e) {
        const wc_e2e_status_t status = wc_e2e_receive(&in->e2e, &loop->config.e2e, alive);
        if (status > WC_E2E_STATUS_INITIAL) {  /* wc_e2e_status_usable, inline: see the asserts below */
            reject(loop, (status == WC_E2E_STATUS_SYNC) ? WC_REJECT_SYNC : WC_REJECT_COUNTER);
            return false;
        }
    }
    if (decoded >= WC_CAN_ERR_NAN) { reject(loop, WC_REJECT_IMPLAUSIBLE); return false; }  /* wc_can_is_error */
    in->age_periods = 0u;
    in->seen = true;
    loop->counters.frames_used++;
    return true;
}

static WC_NOINLINE void process(wc_loop_t *loop, const wc_can_frame_t *f)
{
    if ((f->flags & (WC_CAN_FLAG_EXTENDED | WC_CAN_FLAG_REMOTE | WC_CAN_FLAG_ERROR)) != 0u) {
        reject(loop, WC_REJECT_FORMAT);
        return;
    }
    const bool gearbox = wc_loop_gearbox(&loop->config);
    if ((f->id == WC_CAN_CLUTCH_SENSORS_FRAME_ID) && !gearbox) {
        wc_can_clutch_sensors_phys_t s = {0.0f, 0.0f, 0.0f, 0u};
        const wc_can_result_t r = wc_can_decode_clutch_sensors(&s, f->data, f->dlc);
        if (accept(loop, &loop->sensors_in, r, true, s.alive_counter)) { loop->sensors = s; }
    } else if ((f->id == WC_CAN_TORQUE_REQUEST_FRAME_ID) && !gearbox) {
        wc_can_torque_request_phys_t q = {0.0f, 0u, 0u};
        wc_can_result_t r = wc_can_decode_torque_request(&q, f->data, f->dlc);
        if ((q.mode == WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE) && (loop->config.shift == NULL) && (r < WC_CAN_ERR_NAN)) {
            r = WC_CAN_ERR_RANGE;  /* no shift controller configured: Mode 3 is not a mode here */
        }
        if (accept(loop, &loop->request_in, r, true, q.alive_counter)) { loop->request = q; }
    } else if ((f->id == WC_CAN_SHIFT_COMMAND_FRAME_ID) && ((loop->config.shift != NULL) || gearbox)) {
        wc_can_shift_command_phys_t c = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0u};
        const wc_can_result_t r = wc_can_decode_shift_command(&c, f->data, f->dlc);
        if (accept(loop, &loop->shift_in, r, true, c.alive_counter)) { loop->shift_command = c; }
    } else if ((f->id == WC_CAN_OFFGOING_SENSORS_FRAME_ID) && wc_loop_whole_shift(&loop->config)) {
        wc_can_offgoing_sensors_phys_t o = {0.0f, 0u};
        const wc_can_result_t r = wc_can_decode_offgoing_sensors(&o, f->data, f->dlc);
        if (accept(loop, &loop->offgoing_in, r, true, o.alive_counter)) { loop->offgoing_sensors = o; }
    } else if ((f->id == WC_CAN_GEARBOX_SENSORS_FRAME_ID) && gearbox) {
        wc_can_gearbox_sensors_phys_t g = {0.0f, 0.0f, 0.0f, 0.0f, 0u};
        const wc_can_result_t r = wc_can_decode_gearbox_sensors(&g, f->data, f->dlc);
        if (accept(loop, &loop->gearbox_in, r, true, g.alive_counter)) { loop->gearbox_sensors = g; }
    } else if ((f->id == WC_CAN_BENCH_MEASUREMENT_FRAME_ID) && loop->config.bench_input_enabled) {
        wc_can_bench_measurement_phys_t b = {0.0f, 0.0f, 0.0f};
        const wc_can_result_t r = wc_can_decode_bench_measurement(&b, f->data, f->dlc);
        if (accept(loop, &loop->bench_in, r, false, 0u)) { loop->bench = b; }
    } else {
        reject(loop, WC_REJECT_UNKNOWN_ID);
    }
}

/* One numbering for the mode: the C enum has the DBC's values. */
WC_STATIC_ASSERT(WC_MODE_OPEN == WC_CAN_TORQUE_REQUEST_MODE_OPEN_CHOICE, mode_open_is_dbc_open);
WC_STATIC_ASSERT(WC_MODE_TORQUE == WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, mode_torque_is_dbc_torque);
WC_STATIC_ASSERT(WC_MODE_LOCKED == WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE, mode_locked_is_dbc_locked);

/* A decoded Mode passed the DBC range check; anything else releases. */
static wc_clutch_mode_t mode_of(uint8_t can_mode)
{
    return (can_mode <= (uint8_t)WC_MODE_LOCKED) ? (wc_clutch_mode_t)can_mode : WC_MODE_OPEN;
}

void wc_loop_shift_report_frame(const wc_shift_report_t *q, wc_can_frame_t *out)
{
    WC_ASSERT((q != NULL) && (out != NULL));
    if ((q == NULL) || (out == NULL)) { return; }
    wc_can_shift_report_phys_t report = {
        .inertia_phase_time_ms = q->inertia_time_s * 1.0e3f,
        .slip_rmse_rpm = q->slip_rmse_rad_s / WC_RAD_S_PER_RPM,
        .peak_jerk_m_per_s3 = q->peak_jerk_m_s3,
        .friction_energy_kJ = q->friction_energy_J * 1.0e-3f,
        .peak_clutch_temp_degC = q->peak_theta_degC,
        .flare = q->flare ? 1.0f : 0.0f,
        .tie_up = q->tie_up ? 1.0f : 0.0f,
        .saturated = 0.0f,
        .abort_reason = (uint8_t)q->abort_reason,
    };
    out->id = WC_CAN_SHIFT_REPORT_FRAME_ID;
    out->dlc = WC_CAN_SHIFT_REPORT_LENGTH;
    out->flags = 0u;
    /* the encoder limits each figure to its DBC range (a NaN: its raw_nan) and says so: the frame then says so too */
    if (wc_can_encode_shift_report(out->data, &report, sizeof out->data) != WC_CAN_OK) {
        report.saturated = 1.0f;
        (void)wc_can_encode_shift_report(out->data, &report, sizeof out->data);
    }
}

/* The adaptation report frame (DBC AdaptationReport): what the last shift
 * changed, or a reset (result OFF), with the image's status. */
static WC_NOINLINE void encode_adaptation(const wc_adapt_change_t *a, uint32_t adapt_status, wc_can_frame_t *out)
{
    const wc_can_adaptation_report_phys_t report = {
        .result = (float)a->result,
        .node = (float)a->node,
        .image_missing = ((adapt_status & WC_ADAPT_STATUS_IMAGE_MISSING) != 0u) ? 1.0f : 0.0f,
        .image_invalid = ((adapt_status & WC_ADAPT_STATUS_IMAGE_INVALID) != 0u) ? 1.0f : 0.0f,
        .friction_scale = a->friction_scale,
        .friction_scale_change = a->friction_scale_change,
        .confidence = a->confidence,
        .film_factor = a->film_factor,
        .kiss_offset_kPa = a->kiss_offset_Pa * 1.0e-3f,
    };
    out->id = WC_CAN_ADAPTATION_REPORT_FRAME_ID;
    out->dlc = WC_CAN_ADAPTATION_REPORT_LENGTH;
    out->flags = 0u;
    (void)wc_can_encode_adaptation_report(out->data, &report, sizeof out->data);  /* saturates to the DBC ranges */
}

/* The two cyclic output frames of a step. Apart from wc_loop_step so that its
 * locals are not on the stack while the model runs. */
static WC_NOINLINE void encode_outputs(wc_loop_t *loop, uint16_t bits, wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    const wc_step_output_t *o = &loop->last;
    const wc_can_clutch_estimate_phys_t estimate = {
        .estimated_clutch_temp_degC = o->theta_degC,
        .model_torque_Nm = o->model.torque_Nm,
        .mu_f = o->model.mu_f,
        .film_thickness_um = o->model.hbar_m * 1.0e6f,
        .lock_state = ((o->status & WC_STATUS_LOCKED) != 0u) ? (uint8_t)WC_CAN_CLUTCH_ESTIMATE_LOCK_STATE_LOCKED_CHOICE
                                                             : (uint8_t)WC_CAN_CLUTCH_ESTIMATE_LOCK_STATE_SLIPPING_CHOICE,
    };
    out[1].id = WC_CAN_CLUTCH_ESTIMATE_FRAME_ID;
    out[1].dlc = WC_CAN_CLUTCH_ESTIMATE_LENGTH;
    out[1].flags = 0u;
    if (wc_can_encode_clutch_estimate(out[1].data, &estimate, sizeof out[1].data) == WC_CAN_SATURATED) {
        bits |= WC_CAN_STATUS_SATURATED;
    }
    const wc_can_vfs_command_phys_t command = {
        .vfs_current_mA = o->current_mA,
        .pressure_command_kPa = o->pressure_command_Pa * 1.0e-3f,
        .status = bits,
        .alive_counter = loop->tx_alive,
    };
    loop->tx_alive = wc_e2e_counter_next(loop->tx_alive);
    out[0].id = WC_CAN_VFS_COMMAND_FRAME_ID;
    out[0].dlc = WC_CAN_VFS_COMMAND_LENGTH;
    out[0].flags = 0u;
    (void)wc_can_encode_vfs_command(out[0].data, &command, sizeof out[0].data);

}

/* The whole shift's cyclic frames (DESIGN 14) after ClutchEstimate at out[n]:
 * OffgoingVfsCommand, EngineTorqueRequest. Returns the new count. */
static WC_NOINLINE uint32_t encode_whole_shift(wc_loop_t *loop, wc_can_frame_t out[WC_LOOP_TX_FRAMES], uint32_t n)
{
    const wc_step_output_t *o = &loop->offgoing_last;
    const wc_can_offgoing_vfs_command_phys_t command = {
        .vfs_current_mA = o->current_mA,
        .pressure_command_kPa = o->pressure_command_Pa * 1.0e-3f,
        .shift_phase = (float)loop->shift.phase,
        .fallback = (uint8_t)loop->shift.fallback,
        .alive_counter = loop->tx_alive_offgoing,
    };
    loop->tx_alive_offgoing = wc_e2e_counter_next(loop->tx_alive_offgoing);
    out[n].id = WC_CAN_OFFGOING_VFS_COMMAND_FRAME_ID;
    out[n].dlc = WC_CAN_OFFGOING_VFS_COMMAND_LENGTH;
    out[n].flags = 0u;
    (void)wc_can_encode_offgoing_vfs_command(out[n].data, &command, sizeof out[n].data);
    wc_loop_engine_frame(loop, loop->whole.engine_active, loop->whole.engine_delta_Nm, &out[n + 1u]);
    return n + WC_LOOP_TX_WHOLE_SHIFT;
}

/* prepare() sets the clutch input field by field: all of them (a new field fails here). */
WC_STATIC_ASSERT(sizeof(wc_step_input_t) == 16u * 4u, the_loop_sets_every_field_of_the_clutch_input);
WC_STATIC_ASSERT(WC_CAN_STATUS_BITS <= 16u, status_bits_below_the_step_flags);

/* The frames of this period, the inputs' freshness and the safe state, then
 * the clutch input (loop->input) and in Shift mode the shift command
 * (loop->command). Apart from the step so that its locals are not on the
 * stack while the model runs. */
static WC_NOINLINE uint32_t prepare(wc_loop_t *loop)
{
    /* Consumer side of the ring: writes only rx_head. The frames queued when
     * the step starts are this period's; one arriving meanwhile waits for the
     * next step (its slot is not released before then). */
    const uint32_t head = loop->rx_head;
    const uint32_t tail = loop->rx_tail;
    WC_MEMORY_BARRIER();  /* the frames are read after their publication was seen */
    const uint32_t queued = tail - head;  /* free-running indices: <= WC_LOOP_RX_CAPACITY */
    for (uint32_t i = 0u; (i < WC_LOOP_RX_CAPACITY) && (i < queued); ++i) {
        process(loop, &loop->rx[(head + i) % WC_LOOP_RX_CAPACITY]);
    }
    WC_MEMORY_BARRIER();  /* ...and fully read before their slots are released */
    loop->rx_head = tail; /* wraps at 2^32, a multiple of the capacity */
    /* Frames the ISR could not queue since the last step (its counter is the producer's). */
    const uint32_t overflows = loop->counters.rejected[WC_REJECT_OVERFLOW];
    if (overflows != loop->overflows_seen) {
        loop->overflows_seen = overflows;
        loop->pending_status = (uint16_t)(loop->pending_status | WC_CAN_STATUS_FRAME_LOST);
    }
    uint32_t step = loop->pending_status;
    loop->pending_status = 0u;
    if (wc_loop_gearbox(&loop->config)) { return step | STEP_GEARBOX; }  /* wc_loop_gearbox_run does the rest */
    if (wc_loop_update_freshness(&loop->sensors_in, loop->config.sensor_timeout_periods, &loop->counters.sensor_timeouts)) {
        step |= WC_CAN_STATUS_SENSOR_TIMEOUT;
    }
    if (wc_loop_update_freshness(&loop->request_in, loop->config.request_timeout_periods, &loop->counters.request_timeouts)) {
        step |= WC_CAN_STATUS_REQUEST_TIMEOUT;
    }
    /* Shift mode: ShiftCommand is a control input too (its staleness counts as the request's). */
    const bool shift_mode = (loop->config.shift != NULL) && (loop->request.mode == WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE);
    if ((loop->config.shift != NULL) &&
        wc_loop_update_freshness(&loop->shift_in, loop->config.request_timeout_periods, &loop->counters.request_timeouts) &&
        shift_mode) {
        step |= WC_CAN_STATUS_REQUEST_TIMEOUT;
    }
    /* The whole shift (DESIGN 14): in Shift mode OffgoingSensors is a sensor input too. */
    if (wc_loop_whole_shift(&loop->config) &&
        wc_loop_update_freshness(&loop->offgoing_in, loop->config.sensor_timeout_periods, &loop->counters.sensor_timeouts) &&
        shift_mode) {
        step |= WC_CAN_STATUS_SENSOR_TIMEOUT;
    }
    /* Debounce: both control inputs fresh for recovery_periods in a row. */
    const bool safe = wc_loop_safe_after(loop, step);
    uint32_t bench_timeouts = 0u;  /* bench frames are optional: staleness is not a fault */
    const bool bench_fresh = loop->config.bench_input_enabled &&
                             !wc_loop_update_freshness(&loop->bench_in, loop->config.sensor_timeout_periods, &bench_timeouts);
    const float load_cell_N = loop->bench.load_cell_force_N;

    /* the clutch input, field by field into the loop (no copy of a whole struct) */
    wc_step_input_t *in = &loop->input;
    in->slip_rad_s = loop->sensors.slip_speed_rpm * WC_RAD_S_PER_RPM;
    in->theta_oil_degC = loop->sensors.oil_temp_degC;
    in->theta_housing_degC = loop->sensors.housing_temp_degC;
    in->torque_request_Nm = loop->request.torque_request_Nm;
    in->mode = safe ? WC_MODE_OPEN : mode_of(loop->request.mode);
    in->bench.valid = bench_fresh;
    in->bench.apply_force_N = (load_cell_N > 0.0f) ? load_cell_N : 0.0f;
    in->bench.torque_Nm = loop->bench.measured_torque_Nm;
    in->lag_compensation.time_s = 0.0f;
    in->lag_compensation.vfs_gain = 0.0f;
    in->theta_from_oil = false;
    in->band_release = false;
    in->carried_torque_Nm = 0.0f;
    in->correction.friction_scale_delta = 0.0f;  /* the shift controller sets it (DESIGN 12) */
    in->correction.film_factor_delta = 0.0f;
    in->correction.kiss_offset_N = 0.0f;
    if (wc_loop_whole_shift(&loop->config)) {  /* the off-going clutch's sensors; the controller sets the rest */
        wc_step_input_t *og = &loop->offgoing_input;
        og->slip_rad_s = loop->offgoing_sensors.offgoing_slip_speed_rpm * WC_RAD_S_PER_RPM;
        og->theta_oil_degC = in->theta_oil_degC;
        og->theta_housing_degC = in->theta_housing_degC;
        og->mode = WC_MODE_OPEN;
        og->torque_request_Nm = 0.0f;
    }
    if (bench_fresh) { step |= WC_CAN_STATUS_BENCH_INPUT; }
    if (safe) {
        step |= WC_CAN_STATUS_SAFE_STATE_ACTIVE | STEP_SAFE;
        loop->counters.safe_steps++;
    }
    const bool shift_running = wc_shift_phase_running(loop->shift.phase);
    if (!shift_mode && !shift_running && (loop->shift.phase != (uint32_t)WC_SHIFT_IDLE)) {
        wc_shift_init(&loop->shift);  /* a finished shift ends with its mode: the new mode acts now */
    }
    /* DESIGN 12: a reset of the learned values on a 0 -> 1 edge of the (valid) AdaptationReset, not during a shift */
    const bool reset = (loop->config.shift != NULL) && (loop->config.shift->adaptation == 1u) && shift_mode &&
                       (loop->shift_command.adaptation_reset > 0.5f);
    /* ...or requested by a diagnostic routine (wc_loop_request_adaptation_reset; an authenticated tester,
     * so also in the safe state), dropped if a shift started since */
    const bool requested = loop->adaptation_reset_requested && !shift_running;
    loop->adaptation_reset_requested = false;
    if ((reset && !loop->last_adaptation_reset && !shift_running && !safe) || requested) {
        loop->report.adaptation = wc_adapt_command_reset(&loop->adapt);
        step |= STEP_ADAPT;
    }
    loop->last_adaptation_reset = reset;
    if ((loop->config.shift != NULL) && (shift_mode || shift_running)) {
        /* the shift controller owns the clutch; leaving Shift mode mid-shift withdraws the command (abort) */
        const wc_can_shift_command_phys_t *c = &loop->shift_command;
        const wc_shift_command_t command = {
            .request = shift_mode && (c->shift_request > 0.5f),
            .target_gear = (uint32_t)c->target_gear,          /* decoded: within [1, 8] */
            .turbine_torque_Nm = c->turbine_torque_Nm,
            .target_inertia_time_s = c->target_inertia_time_ms * 1.0e-3f,
        };
        loop->command = command;
        step |= STEP_SHIFT;
    }
    return step;
}

/* After the model: the model's status bits, the output frames, the counters. */
static WC_NOINLINE uint32_t finish(wc_loop_t *loop, uint32_t step, wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    encode_outputs(loop, (uint16_t)(step | wc_loop_status_bits(loop->last.status)), out);
    uint32_t n = WC_LOOP_TX_CYCLIC;
    if (wc_loop_whole_shift(&loop->config)) { n = encode_whole_shift(loop, out, n); }
    if ((step & STEP_REPORT) != 0u) { wc_loop_shift_report_frame(&loop->report, &out[n++]); }
    if ((step & STEP_ADAPT) != 0u) {
        encode_adaptation(&loop->report.adaptation, loop->adapt.status, &out[n++]);
        if (loop->config.adaptation_changed != NULL) {
            loop->config.adaptation_changed(&loop->adapt, loop->config.adaptation_context);
        }
    }
    loop->counters.steps++;
    loop->counters.frames_out += n;
    return n;
}

/* Queue frame (NULL: none), then when step_now one control period. The one
 * routine behind wc_loop_step and wc_loop_iterate, which tail-call it: on the
 * deepest stack chain (Shift mode) only this frame lies above the model's. */
static WC_NOINLINE uint32_t run(wc_loop_t *loop, const wc_can_frame_t *frame, bool step_now,
                                wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    if (frame != NULL) { (void)wc_loop_receive(loop, frame); }  /* a refusal is counted (WC_REJECT_OVERFLOW) */
    if (!step_now) { return 0u; }
    /* initialised, and its init succeeded */
    WC_ASSERT((loop->clutch.model.cal != NULL) || (loop->transmission.element[0].model.cal != NULL));
    uint32_t step = prepare(loop);
    if ((step & STEP_GEARBOX) != 0u) { return wc_loop_gearbox_run(loop, step & (uint32_t)~STEP_GEARBOX, out); }
    if ((step & STEP_SHIFT) != 0u) {
        /* the whole shift: loop->whole points at the off-going clutch (wc_loop_init); no copy on the stack */
        const bool ended = wc_shift_step(&loop->shift, loop->config.shift, &loop->command, (step & STEP_SAFE) != 0u,
                                         &loop->clutch, &loop->adapt, &loop->input, &loop->last, &loop->report,
                                         wc_loop_whole_shift(&loop->config) ? &loop->whole : NULL);
        if (ended) {
            step |= STEP_REPORT;
            /* adaptation on: what the shift changed goes out with the report (the hook persists it) */
            if (loop->config.shift->adaptation == 1u) { step |= STEP_ADAPT; }
        }
    } else {
        (void)wc_clutch_step(&loop->clutch, &loop->input, &loop->last);  /* its status is loop->last.status */
        if (wc_loop_whole_shift(&loop->config)) {  /* not in Shift mode: the off-going clutch is not ours: open */
            (void)wc_clutch_step(&loop->offgoing, &loop->offgoing_input, &loop->offgoing_last);
            loop->whole.engine_active = false;
            loop->whole.engine_delta_Nm = 0.0f;
        }
    }
    return finish(loop, step, out);
}

uint32_t wc_loop_step(wc_loop_t *loop, wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    WC_ASSERT((loop != NULL) && (out != NULL));
    if ((loop == NULL) || (out == NULL)) { return 0u; }
    /* With asserts off an uninitialised loop still answers: the clutch step
     * gives 0 mA and WC_STATUS_NOT_INITIALISED, sent as the safe state. */
    return run(loop, NULL, true, out);
}

uint32_t wc_loop_iterate(wc_loop_t *loop, wc_loop_clock_t clock, const wc_can_frame_t *frame, bool tick,
                         wc_can_frame_t out[WC_LOOP_TX_FRAMES])
{
    WC_ASSERT((loop != NULL) && (out != NULL));
    if ((loop == NULL) || (out == NULL)) { return 0u; }
    const bool step_now = tick || ((frame != NULL) && (clock == WC_LOOP_CLOCK_FRAME) &&
                                   (frame->id == (wc_loop_gearbox(&loop->config) ? WC_CAN_GEARBOX_SENSORS_FRAME_ID
                                                                                 : WC_CAN_CLUTCH_SENSORS_FRAME_ID)) &&
                                   (frame->flags == 0u));
    return run(loop, frame, step_now, out);
}

uint32_t wc_loop_rx_ids(const wc_loop_config_t *config, uint32_t ids[WC_LOOP_RX_ID_COUNT])
{
    WC_ASSERT((config != NULL) && (ids != NULL));
    if ((config == NULL) || (ids == NULL)) { return 0u; }
    uint32_t n = 0u;
    if (wc_loop_gearbox(config)) {
        ids[n++] = WC_CAN_GEARBOX_SENSORS_FRAME_ID;
        ids[n++] = WC_CAN_SHIFT_COMMAND_FRAME_ID;
        return n;
    }
    ids[n++] = WC_CAN_CLUTCH_SENSORS_FRAME_ID;
    ids[n++] = WC_CAN_TORQUE_REQUEST_FRAME_ID;
    if (config->shift != NULL) { ids[n++] = WC_CAN_SHIFT_COMMAND_FRAME_ID; }
    if (wc_loop_whole_shift(config)) { ids[n++] = WC_CAN_OFFGOING_SENSORS_FRAME_ID; }
    if (config->bench_input_enabled) { ids[n++] = WC_CAN_BENCH_MEASUREMENT_FRAME_ID; }
    return n;
}
