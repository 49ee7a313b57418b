/* The transmission's test plant (tests/c/test_transmission.c and the
 * Cortex-M4F probe's transmission rows, bench/arm): it only drives the
 * phases (no validation of the model: tools/wetclutch/simulate/gearbox_plant
 * does that in closed loop). The shift's own reduced two-speed model
 * (turbine inertia I_t and the output's I_out of the row, the elements'
 * model torques in its coordinates, no road load), rigid in a gear; in a
 * shift held at the source (target) gear's ratio while the off-going
 * (on-coming) element's modelled static capacity carries what it must, else
 * both speeds move with T_t and both elements' torques. The engine follows
 * the transmission's request with a first-order lag of the shift
 * calibration's engine_lead_time_s (what the TCU expects; *engine_Nm its
 * state): T_t = the driver's + what it delivers (the coast downshift's
 * inertia phase is the engine's work, DESIGN 15); the caller's torque
 * estimate stays the driver's. */
#ifndef WC_TEST_TRANSMISSION_RIG_H
#define WC_TEST_TRANSMISSION_RIG_H

#include <math.h>

#include <wetclutch/wc_transmission.h>

/* The tests' and the probe's transmission: every element of the gearbox the
 * same clutch (element_cal), the shift calibration shift, holding need x 1.2
 * and at least 5 N m in a gear. */
static inline void wc_test_tx_config(wc_transmission_config_t *config, const wc_gearbox_t *g,
                                     const wc_calibration_t *element_cal, const wc_shift_calibration_t *shift)
{
    config->gearbox = g;
    for (uint32_t e = 0u; e < g->element_count; ++e) { config->element[e] = element_cal; }
    config->shift = shift;
    config->holding_margin_factor = 1.2f;
    config->holding_floor_Nm = 5.0f;
}

/* One period of the plant after the transmission's step (its outputs in out). */
static inline void wc_test_tx_plant(const wc_gearbox_t *g, const wc_transmission_t *tx,
                                    const wc_transmission_output_t *out, float turbine_torque_Nm, float dt_s,
                                    float *engine_Nm, float *turbine_rad_s, float *output_rad_s)
{
    const float asked_Nm = out->engine_active ? out->engine_delta_Nm : 0.0f;
    *engine_Nm += (asked_Nm - *engine_Nm) * dt_s / (tx->shift_cal.engine_lead_time_s + dt_s);
    const wc_gearbox_shift_t *row = (tx->row != NULL) ? tx->row : tx->gear_row;
    const float i_t = row->turbine_inertia_kg_m2;
    const float i_out = row->output_inertia_kg_m2;
    const float t_t = turbine_torque_Nm + *engine_Nm;
    if (tx->row == NULL) {  /* in a gear: rigid at its ratio */
        const float ratio = g->ratio[tx->gear];
        *output_rad_s += ratio * t_t / (i_out + i_t * ratio * ratio) * dt_s;
        *turbine_rad_s = ratio * *output_rad_s;
        return;
    }
    const wc_step_output_t *on = &out->element[row->oncoming];
    const wc_step_output_t *off = &out->element[row->offgoing];
    /* the model torques in the controller's frame, x tx->sign back to the real one */
    const float t_on = tx->sign * on->model.torque_Nm;
    const float t_off = tx->sign * off->model.torque_Nm;
    const float b = row->output_ratio;
    const float b1 = row->offgoing_ratio;
    const float s_on = *turbine_rad_s - b * *output_rad_s;
    const float s_off = *turbine_rad_s - b1 * *output_rad_s;
    /* held in the source gear: (I_out + I_t b1^2) dw_o/dt = b1 T_t + (b - b1) T_on; the off-going carries the rest */
    const float a_source = (b1 * t_t + (b - b1) * t_on) / (i_out + i_t * b1 * b1);
    const float a_target = (b * t_t + (b1 - b) * t_off) / (i_out + i_t * b * b);
    if ((fabsf(s_off) < 0.5f) && (off->static_capacity_Nm >= fabsf(t_t - t_on - i_t * b1 * a_source))) {
        *output_rad_s += a_source * dt_s;
        *turbine_rad_s = b1 * *output_rad_s;
    } else if ((fabsf(s_on) < 0.5f) && (on->static_capacity_Nm >= fabsf(t_t - t_off - i_t * b * a_target))) {
        *output_rad_s += a_target * dt_s;
        *turbine_rad_s = b * *output_rad_s;
    } else {
        *turbine_rad_s += (t_t - t_on - t_off) / i_t * dt_s;
        *output_rad_s += (b * t_on + b1 * t_off) / i_out * dt_s;
    }
}

#endif /* WC_TEST_TRANSMISSION_RIG_H */
