#include "wetclutch/wc_transmission.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "wc_internal.h"

/* The holding's limits (wc_transmission_config_t). */
#define HOLDING_MARGIN_MAX 5.0f
#define HOLDING_FLOOR_MAX_Nm 1e4f

static bool gear_of(const wc_gearbox_t *g, uint32_t gear)
{
    return (gear < WC_GEARBOX_GEARS_MAX) && (g->closed_mask[gear] != 0u) &&
           ((gear != WC_GEARBOX_REVERSE) ? (gear <= g->forward_gears) : g->has_reverse);
}

/* A shift of the table from this gear: its slip maps give the open elements' slips in the gear. */
static const wc_gearbox_shift_t *row_from(const wc_gearbox_t *g, uint32_t gear)
{
    for (uint32_t i = 0u; (i < g->shift_count) && (i < WC_GEARBOX_SHIFTS_MAX); ++i) {
        if (g->shift[i].source_gear == gear) { return &g->shift[i]; }
    }
    return NULL;
}

/* The equivalent clutch without its check (checked at init, per shift). */
static void make_equivalent(const wc_calibration_t *element, float slip_scale, wc_calibration_t *out)
{
    /* DESIGN 15 (matrix8.py): the radii x |a| make R_eff (eq. 3) and with it the torque arm and the static
     * capacity x |a| while the sliding speed R_eff |slip / a| (eq. 4), and so mu_f (eq. 18), the viscous term
     * (eq. 5-8) and eq. 1's power, stay the element's; the squeeze film's Reynolds factor is of degree 4 in
     * the radii (wc_model.c); the open drag's aeration speed is a slip, / |a| in these coordinates (0 stays
     * off). Forces, pressures, areas, the open clearance and the heat capacity are the element's. */
    const float s = fabsf(slip_scale);
    *out = *element;
    out->outer_radius_m = element->outer_radius_m * s;
    out->inner_radius_m = element->inner_radius_m * s;
    out->film_squeeze_factor = element->film_squeeze_factor / (s * s * s * s);
    out->open_aeration_speed_rad_s = element->open_aeration_speed_rad_s / s;
}

wc_cal_error_t wc_transmission_equivalent(const wc_calibration_t *element, float slip_scale, wc_calibration_t *out)
{
    WC_ASSERT((element != NULL) && (out != NULL));
    if ((element == NULL) || (out == NULL)) { return WC_CAL_NULL; }
    make_equivalent(element, slip_scale, out);
    return wc_calibration_check(out);
}

/* Every shift's reduced model with the shift calibration (in the state's
 * copy, not on the stack: 244 B), and which shifts have both equivalent
 * clutches within the limits (tx->runnable; the others are refused with
 * WC_GEARBOX_SHIFT_NO_MODEL): the checks once here, not in a control step. */
static wc_transmission_error_t check_shifts(wc_transmission_t *tx, const wc_transmission_config_t *config)
{
    const wc_gearbox_t *g = config->gearbox;
    for (uint32_t i = 0u; (i < g->shift_count) && (i < WC_GEARBOX_SHIFTS_MAX); ++i) {
        const wc_gearbox_shift_t *row = &g->shift[i];
        if (wc_gearbox_shift_calibration(config->shift, row, &tx->shift_cal) != WC_SHIFT_CAL_OK) {
            return WC_TRANSMISSION_SHIFT;
        }
        if ((wc_transmission_equivalent(config->element[row->oncoming], row->oncoming_slip_scale, &tx->equivalent[0]) == WC_CAL_OK) &&
            (wc_transmission_equivalent(config->element[row->offgoing], row->offgoing_slip_scale, &tx->equivalent[1]) == WC_CAL_OK)) {
            tx->runnable |= (uint64_t)1u << i;
        }
    }
    return WC_TRANSMISSION_OK;
}

wc_transmission_error_t wc_transmission_init(wc_transmission_t *tx, const wc_transmission_config_t *config,
                                             uint32_t gear, float theta_start_degC)
{
    WC_ASSERT((tx != NULL) && (config != NULL));
    if ((tx == NULL) || (config == NULL) || (config->gearbox == NULL) || (config->shift == NULL)) {
        return WC_TRANSMISSION_NULL;
    }
    (void)memset(tx, 0, sizeof *tx);
    const wc_gearbox_t *g = config->gearbox;
    if (wc_gearbox_check(g) != WC_GEARBOX_OK) { return WC_TRANSMISSION_GEARBOX; }
    for (uint32_t e = 0u; e < g->element_count; ++e) {
        if ((config->element[e] == NULL) ||
            (wc_clutch_init(&tx->element[e], config->element[e], theta_start_degC) != WC_CAL_OK)) {
            return WC_TRANSMISSION_ELEMENT;
        }
    }
    if ((wc_shift_calibration_check(config->shift) != WC_SHIFT_CAL_OK) || (config->shift->coordinator != 1u)) {
        return WC_TRANSMISSION_SHIFT;
    }
    const wc_transmission_error_t shifts = check_shifts(tx, config);
    if (shifts != WC_TRANSMISSION_OK) { return shifts; }
    if (!wc_in_range(config->holding_margin_factor, 1.0f, HOLDING_MARGIN_MAX) ||
        !wc_in_range(config->holding_floor_Nm, 0.0f, HOLDING_FLOOR_MAX_Nm)) {
        return WC_TRANSMISSION_HOLDING;
    }
    if (!gear_of(g, gear)) { return WC_TRANSMISSION_GEAR; }
    wc_adapt_reset(&tx->adapt);
    for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) { tx->learned[e] = tx->adapt.values; }
    tx->gear = gear;
    tx->gear_row = row_from(g, gear);
    tx->sign = 1.0f;
    return WC_TRANSMISSION_OK;
}

/* A shift's start on the request's edge (DESIGN 15): refused with its
 * reason, or the row, its type and frame, its reduced model (checked at
 * init) and the two elements as equivalent clutches. */
static void start_shift(wc_transmission_t *tx, const wc_transmission_config_t *config,
                        const wc_transmission_command_t *command, bool safe)
{
    const wc_gearbox_t *g = config->gearbox;
    const wc_gearbox_shift_t *row = NULL;
    wc_gearbox_shift_result_t result = WC_GEARBOX_SHIFT_BUSY;
    if (!safe) {
        result = (command->current_gear != tx->gear) ? WC_GEARBOX_SHIFT_NOT_CURRENT
                                                     : wc_gearbox_find_shift(g, tx->gear, command->target_gear, &row);
    }
    if ((result == WC_GEARBOX_SHIFT_OK) && (row != NULL) &&
        (((tx->runnable >> (uint32_t)(row - g->shift)) & 1u) == 0u)) {
        result = WC_GEARBOX_SHIFT_NO_MODEL;
    }
    tx->refusal = (uint32_t)result;
    if ((result != WC_GEARBOX_SHIFT_OK) || (row == NULL)) { return; }
    tx->type = (uint32_t)wc_gearbox_shift_type(g, row, command->turbine_torque_Nm);
    /* mirrored: the tip-out (the kickdown's controller with the speeds and torques negated, DESIGN 15) */
    tx->sign = (tx->type == (uint32_t)WC_SHIFT_TYPE_POWER_OFF_UP) ? -1.0f : 1.0f;
    (void)wc_gearbox_shift_calibration(config->shift, row, &tx->shift_cal);
    make_equivalent(config->element[row->oncoming], row->oncoming_slip_scale, &tx->equivalent[0]);
    make_equivalent(config->element[row->offgoing], row->offgoing_slip_scale, &tx->equivalent[1]);
    wc_model_set_geometry(&tx->element[row->oncoming].model, &tx->equivalent[0]);
    wc_model_set_geometry(&tx->element[row->offgoing].model, &tx->equivalent[1]);
    wc_shift_init(&tx->shift);
    tx->adapt.values = tx->learned[row->oncoming];  /* DESIGN 12: the on-coming element's (a power-on upshift's) */
    tx->row = row;
    tx->gear_slip_periods = 0u;  /* a new gear: its slip watched afresh */
    tx->gear_slipped = false;
}

/* A closed element's input in a gear: the inverse of what it must carry plus
 * the margin (DESIGN 15), at its maximum current in the safe state. */
static void hold(wc_step_input_t *in, const wc_transmission_config_t *config, uint32_t gear, uint32_t element,
                 float turbine_torque_Nm, bool safe)
{
    const wc_gearbox_t *g = config->gearbox;
    in->mode = safe ? WC_MODE_LOCKED : WC_MODE_TORQUE;
    in->torque_request_Nm = wc_gearbox_holding_request_Nm(g, gear, element, turbine_torque_Nm,
                                                          config->holding_margin_factor, config->holding_floor_Nm);
    /* what it carries: the request without the margin (not finite: the request) */
    const float carried_Nm = fabsf(g->holding_torque_per_Nm[gear][element] * turbine_torque_Nm);
    in->carried_torque_Nm = (carried_Nm < in->torque_request_Nm) ? carried_Nm : in->torque_request_Nm;
}

static float element_slip(const wc_gearbox_shift_t *row, uint32_t e, float w_t, float w_o, bool valid)
{
    return (valid && (row != NULL)) ? wc_gearbox_element_slip_rad_s(row, e, w_t, w_o) : NAN;
}

/* In a gear: the closed elements held at the inverse at zero slip (DESIGN 15; at their maximum in the safe
 * state or once the gear slipped, WC_TRANSMISSION_GEAR_SLIP_rad_s), the open ones open at their own slip. */
static void hold_gear(wc_transmission_t *tx, const wc_transmission_config_t *config,
                      const wc_transmission_command_t *command, float w_t, float w_o, bool valid, bool safe)
{
    const wc_gearbox_t *g = config->gearbox;
    const float gear_slip_rad_s = valid ? (w_t - g->ratio[tx->gear] * w_o) : 0.0f;
    /* the review's finding: held at the measured slip, the inverse's current fell as the gear slipped (-35 %
     * with the output speed stuck at 0); now at zero slip, and a slip that lasts holds at the maximum */
    const bool slipping = fabsf(gear_slip_rad_s) > WC_TRANSMISSION_GEAR_SLIP_rad_s;
    tx->gear_slip_periods = slipping ? ((tx->gear_slip_periods < UINT32_MAX) ? (tx->gear_slip_periods + 1u) : UINT32_MAX)
                                     : 0u;
    if (tx->gear_slip_periods >= WC_TRANSMISSION_GEAR_SLIP_PERIODS) { tx->gear_slipped = true; }
    for (uint32_t e = 0u; e < g->element_count; ++e) {
        wc_step_input_t *in = &tx->element_in[e];
        if (((g->closed_mask[tx->gear] >> e) & 1u) != 0u) {
            hold(in, config, tx->gear, e, command->turbine_torque_Nm, safe || tx->gear_slipped);
            in->slip_rad_s = valid ? 0.0f : NAN;
        } else {
            in->mode = WC_MODE_OPEN;
            in->slip_rad_s = element_slip(tx->gear_row, e, w_t, w_o, valid);
        }
    }
}

/* A shift's period: the controller of its type on the on-coming and
 * off-going elements (in its frame), the held elements at their maximum
 * current, the fourth open. Returns true when it ended. */
static bool shift_step(wc_transmission_t *tx, const wc_transmission_config_t *config,
                       const wc_transmission_command_t *command, float w_t, float w_o, bool valid, bool safe,
                       wc_transmission_output_t *out, wc_shift_report_t *report)
{
    const wc_gearbox_t *g = config->gearbox;
    const wc_gearbox_shift_t *row = tx->row;
    const uint32_t on = row->oncoming;
    const uint32_t off = row->offgoing;
    const float sign = tx->sign;
    tx->element_in[on].slip_rad_s = sign * element_slip(row, on, w_t, w_o, valid) / row->oncoming_slip_scale;
    tx->element_in[off].slip_rad_s = sign * element_slip(row, off, w_t, w_o, valid) / row->offgoing_slip_scale;
    for (uint32_t e = 0u; e < g->element_count; ++e) {
        if ((e == on) || (e == off)) { continue; }
        wc_step_input_t *in = &tx->element_in[e];
        if (((g->closed_mask[row->source_gear] >> e) & 1u) != 0u) {
            /* held through the shift at the maximum current: besides T_t's share it carries the reactions of
             * the two slipping elements' torques and of the inertias, which T_t does not bound (a tip-out's
             * on-coming push is several times the engine's drag); measured on the 8-speed plant, a held
             * element at its in-gear holding broke away (transmission8) */
            in->mode = WC_MODE_LOCKED;
            in->slip_rad_s = 0.0f;  /* held: not observable in the shift's two speeds (its slip map is 0, 0) */
        } else {
            in->mode = WC_MODE_OPEN;
            in->slip_rad_s = element_slip(row, e, w_t, w_o, valid);
        }
    }
    /* the controller's command: this shift's (another target, or the request withdrawn: cancelled) */
    const wc_shift_command_t c = { command->request && (command->target_gear == row->target_gear), WC_SHIFT_TARGET_GEAR,
                                   sign * command->turbine_torque_Nm, command->target_inertia_time_s };
    wc_shift_offgoing_t og = { &tx->element[off], &tx->element_in[off], &out->element[off], false, 0.0f };
    const bool torque_first = tx->type == (uint32_t)WC_SHIFT_TYPE_POWER_ON_UP;
    /* the tip-out (mirrored) with the on-coming assist, the kickdown without, the coast downshift with the
     * engine as the inertia phase's actuator (wc_shift.h) */
    const uint32_t options = (tx->type == (uint32_t)WC_SHIFT_TYPE_POWER_OFF_UP) ? WC_SHIFT_INERTIA_FIRST_ASSIST
                             : ((tx->type == (uint32_t)WC_SHIFT_TYPE_POWER_OFF_DOWN) ? WC_SHIFT_INERTIA_FIRST_ENGINE : 0u);
    const bool ended = torque_first
        ? wc_shift_step(&tx->shift, &tx->shift_cal, &c, safe, &tx->element[on], &tx->adapt, &tx->element_in[on],
                        &out->element[on], report, &og)
        : wc_shift_inertia_first_step(&tx->shift, &tx->shift_cal, &c, safe, options, &tx->element[on],
                                      &tx->element_in[on], &out->element[on], report, &og);
    out->engine_active = og.engine_active;
    out->engine_delta_Nm = sign * og.engine_delta_Nm;  /* back to the real frame */
    return ended;
}

/* The shift's end: the gear the elements hold, the two elements back to their own clutches. */
static void end_shift(wc_transmission_t *tx, const wc_transmission_config_t *config)
{
    const wc_gearbox_shift_t *row = tx->row;
    const bool target = (tx->shift.phase == (uint32_t)WC_SHIFT_LOCKED) || tx->shift.second_gear;
    tx->gear = target ? row->target_gear : row->source_gear;
    tx->gear_row = row_from(config->gearbox, tx->gear);
    wc_model_set_geometry(&tx->element[row->oncoming].model, config->element[row->oncoming]);
    wc_model_set_geometry(&tx->element[row->offgoing].model, config->element[row->offgoing]);
    tx->learned[row->oncoming] = tx->adapt.values;  /* what the shift learned (unchanged where it did not) */
    tx->row = NULL;
}

bool wc_transmission_learned(const wc_transmission_t *tx, uint32_t element, wc_adapt_values_t *values)
{
    WC_ASSERT((tx != NULL) && (values != NULL));
    if ((tx == NULL) || (values == NULL) || (element >= WC_GEARBOX_ELEMENTS_MAX)) { return false; }
    *values = tx->learned[element];
    return true;
}

/* An element the running configuration has, and no shift running. */
static bool learned_writable(const wc_transmission_t *tx, const wc_gearbox_t *g, uint32_t element)
{
    return (tx->row == NULL) && (g != NULL) && (element < g->element_count);
}

bool wc_transmission_load_learned(wc_transmission_t *tx, const wc_transmission_config_t *config, uint32_t element,
                                  const wc_adapt_values_t *values)
{
    WC_ASSERT((tx != NULL) && (config != NULL) && (values != NULL));
    if ((tx == NULL) || (config == NULL) || (values == NULL) || !learned_writable(tx, config->gearbox, element) ||
        !wc_adapt_values_valid(values, config->shift)) {
        return false;
    }
    tx->learned[element] = *values;
    return true;
}

bool wc_transmission_reset_learned(wc_transmission_t *tx, const wc_transmission_config_t *config, uint32_t element)
{
    WC_ASSERT((tx != NULL) && (config != NULL));
    if ((tx == NULL) || (config == NULL) || !learned_writable(tx, config->gearbox, element)) { return false; }
    wc_adapt_t defaults;
    (void)memset(&defaults, 0, sizeof defaults);
    wc_adapt_reset(&defaults);
    tx->learned[element] = defaults.values;
    return true;
}

bool wc_transmission_step(wc_transmission_t *tx, const wc_transmission_config_t *config,
                          const wc_transmission_command_t *command, const wc_transmission_input_t *input,
                          wc_transmission_output_t *out, wc_shift_report_t *report)
{
    WC_ASSERT((tx != NULL) && (config != NULL) && (command != NULL) && (input != NULL) && (out != NULL) &&
              (report != NULL));
    if ((tx == NULL) || (config == NULL) || (config->gearbox == NULL) || (command == NULL) || (input == NULL) ||
        (out == NULL) || (report == NULL)) {
        return false;
    }
    const wc_gearbox_t *g = config->gearbox;
    const float w_t = input->turbine_rad_s;
    const float w_o = input->output_rad_s;
    const bool valid = wc_slip_valid(w_t) && wc_slip_valid(w_o);
    const bool safe = input->safe || !valid;
    const bool edge = command->request && !tx->last_request;
    tx->last_request = command->request;
    if ((tx->row == NULL) && edge) { start_shift(tx, config, command, safe); }

    const wc_model_correction_t none = { 0.0f, 0.0f, 0.0f };
    for (uint32_t e = 0u; e < g->element_count; ++e) {
        wc_step_input_t *in = &tx->element_in[e];
        in->theta_oil_degC = input->theta_oil_degC;
        in->theta_housing_degC = input->theta_housing_degC;
        in->mode = WC_MODE_OPEN;
        in->torque_request_Nm = 0.0f;
        in->carried_torque_Nm = 0.0f;
        in->lag_compensation.time_s = 0.0f;
        in->lag_compensation.vfs_gain = 0.0f;
        in->theta_from_oil = false;
        in->band_release = false;
        in->correction = none;
        in->bench.valid = false;
    }
    bool ended = false;
    uint32_t phase = (uint32_t)WC_SHIFT_IDLE;
    out->engine_active = false;
    out->engine_delta_Nm = 0.0f;
    if (tx->row != NULL) {
        const uint32_t on = tx->row->oncoming;
        const float on_before_mA = out->element[on].current_mA;   /* out holds the last step's (the contract) */
        const float on_before_Pa = out->element[on].pressure_command_Pa;
        ended = shift_step(tx, config, command, w_t, w_o, valid, safe, out, report);
        phase = tx->shift.phase;
        for (uint32_t e = 0u; e < g->element_count; ++e) {  /* the shift stepped its two */
            if ((e != tx->row->oncoming) && (e != tx->row->offgoing)) {
                (void)wc_clutch_step(&tx->element[e], &tx->element_in[e], &out->element[e]);
            }
        }
        if (ended) {
            const bool aborted = tx->shift.phase == (uint32_t)WC_SHIFT_ABORTED;
            end_shift(tx, config);
            /* an aborted shift whose on-coming element had taken the gear ends with the controller's release
             * of it; the gear is kept, so it keeps its last command for this period (the review's finding:
             * 135 -> 0 -> 1000 mA), and the gear's hold takes it from the next */
            if (aborted && (((g->closed_mask[tx->gear] >> on) & 1u) != 0u) &&
                (out->element[on].current_mA < on_before_mA)) {
                out->element[on].current_mA = on_before_mA;
                out->element[on].pressure_command_Pa = on_before_Pa;
            }
        }
    } else {
        hold_gear(tx, config, command, w_t, w_o, valid, safe);
        for (uint32_t e = 0u; e < g->element_count; ++e) {
            (void)wc_clutch_step(&tx->element[e], &tx->element_in[e], &out->element[e]);
        }
    }
    out->gear = (tx->row != NULL) ? tx->row->source_gear : tx->gear;  /* after a shift's end: its result */
    out->shift_phase = phase;
    out->shift_type = tx->type;
    out->refusal = tx->refusal;
    return ended;
}
