#include "wetclutch/wc_adapt.h"

#include <math.h>
#include <stddef.h>

#include "wetclutch/wc_shift.h"
#include "wc_internal.h"

static float clip(float value, float lo, float hi)
{
    return (value > lo) ? ((value < hi) ? value : hi) : lo;  /* NaN -> lo */
}

/* What a shift that changed nothing reports (also: adaptation off, a reset): the defaults of node 0. */
static const wc_adapt_change_t unchanged = { (uint32_t)WC_ADAPT_RESULT_OFF, 0u, 1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f };

void wc_adapt_reset(wc_adapt_t *adapt)
{
    WC_ASSERT(adapt != NULL);
    if (adapt == NULL) { return; }
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        adapt->values.friction_scale[i] = 1.0f;
        adapt->values.confidence[i] = 0.0f;
    }
    adapt->values.film_factor = 1.0f;
    adapt->values.kiss_offset_Pa = 0.0f;
    adapt->values.shifts_learned = 0u;
    wc_adapt_begin(adapt);
}

wc_adapt_change_t wc_adapt_command_reset(wc_adapt_t *adapt)
{
    WC_ASSERT(adapt != NULL);
    if (adapt != NULL) {
        wc_adapt_reset(adapt);
        adapt->status |= WC_ADAPT_STATUS_RESET;
    }
    return unchanged;
}

static bool within(float value, float lo, float hi) { return (value >= lo) && (value <= hi); }

bool wc_adapt_values_valid(const wc_adapt_values_t *values, const wc_shift_calibration_t *cal)
{
    if ((values == NULL) || (cal == NULL)) { return false; }
    bool valid = within(values->film_factor, cal->adapt_film_factor_min, cal->adapt_film_factor_max) &&
                 within(values->kiss_offset_Pa, -cal->adapt_kiss_band_Pa, cal->adapt_kiss_band_Pa);
    for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
        valid = valid && within(values->friction_scale[i], 1.0f - cal->adapt_scale_band, 1.0f + cal->adapt_scale_band) &&
                within(values->confidence[i], 0.0f, 1.0f);
    }
    return valid;
}

/* DESIGN 12: the interpolation weights of the nodes at theta (linear between
 * neighbours, the end node's beyond the ends): weight[lower] = 1 - x at node
 * lower, 1 - weight at lower + 1. The nodes are strictly increasing
 * (wc_shift_calibration_check). Returns lower. */
static uint32_t node_weights(const wc_shift_calibration_t *cal, float theta_degC, float *upper_weight)
{
    const float *node = cal->adapt_theta_node_degC;
    if (!(theta_degC > node[0])) {
        *upper_weight = 0.0f;
        return 0u;  /* also NaN: the first node */
    }
    for (uint32_t i = 0u; i + 1u < WC_ADAPT_NODES; ++i) {
        if (theta_degC < node[i + 1u]) {
            *upper_weight = (theta_degC - node[i]) / (node[i + 1u] - node[i]);
            return i;
        }
    }
    *upper_weight = 0.0f;
    return WC_ADAPT_NODES - 1u;
}

static bool adaptation_on(const wc_adapt_t *adapt, const wc_shift_calibration_t *cal)
{
    return (adapt != NULL) && (cal != NULL) && (cal->adaptation == 1u);
}

wc_model_correction_t wc_adapt_correction(const wc_adapt_t *adapt, const wc_shift_calibration_t *cal,
                                          const wc_clutch_t *clutch, float theta_degC)
{
    wc_model_correction_t c = { 0.0f, 0.0f, 0.0f };
    if (!adaptation_on(adapt, cal) || (clutch == NULL) || (clutch->model.cal == NULL)) { return c; }
    const wc_adapt_values_t *v = &adapt->values;
    float upper;
    const uint32_t lower = node_weights(cal, theta_degC, &upper);
    const float scale = (upper > 0.0f) ? (v->friction_scale[lower] +
                                          (v->friction_scale[lower + 1u] - v->friction_scale[lower]) * upper)
                                       : v->friction_scale[lower];
    c.friction_scale_delta = scale - 1.0f;
    c.film_factor_delta = v->film_factor - 1.0f;
    /* DESIGN 12: the kiss point as a force (a large piston times a wide band: clipped to the correction's range) */
    c.kiss_offset_N = clip(v->kiss_offset_Pa * clutch->model.cal->piston_area_m2, -WC_CORRECTION_KISS_MAX_N,
                           WC_CORRECTION_KISS_MAX_N);
    return c;
}

void wc_adapt_begin(wc_adapt_t *adapt)
{
    if (adapt == NULL) { return; }
    static const wc_adapt_window_t empty = { false, false, false, 0u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                                             0.0f, 0.0f, 0.0f, 0.0f, { 0.0f, 0.0f, 0.0f, 0.0f, 0.0f },
                                             0.0f, 0.0f, 0.0f, 0.0f, 0.0f };
    adapt->window = empty;
}

void wc_adapt_sample(wc_adapt_t *adapt, const wc_shift_calibration_t *cal, float elapsed_s, float slip_rad_s,
                     float drive_rad_s2, float inverse_inertia, const wc_clutch_t *clutch,
                     const wc_step_output_t *out)
{
    if (!adaptation_on(adapt, cal) || (clutch == NULL) || (out == NULL) || (clutch->model.cal == NULL)) { return; }
    wc_adapt_window_t *w = &adapt->window;
    if (elapsed_s < cal->adapt_window_skip_s) { return; }
    const wc_status_t invalid = WC_STATUS_SLIP_INVALID | WC_STATUS_THETA_INVALID | WC_STATUS_TORQUE_INVALID;
    if ((out->status & invalid) != 0u) { w->fault = true; }  /* a glitch: this shift teaches nothing */
    const bool finite = isfinite(slip_rad_s) && isfinite(drive_rad_s2) && isfinite(inverse_inertia) &&
                        isfinite(out->model.torque_Nm) && isfinite(out->model.coulomb_Nm) &&
                        isfinite(out->contact_force_N) && isfinite(out->theta_degC);
    if (!finite) {
        w->fault = true;
        return;
    }
    if (w->closed) { return; }
    if (!(slip_rad_s > cal->min_start_slip_rad_s)) {  /* near the lock the plant may stick: the window ends */
        w->closed = w->started;
        return;
    }
    const float dt_s = clutch->model.cal->control_period_s;
    if (w->started) {
        /* DESIGN 12 (wc_adapt.h): the torque the driveline implies over the
         * last period, against the model's torque of that period */
        const float implied_Nm = (w->drive_prev_rad_s2 - (slip_rad_s - w->slip_prev_rad_s) / dt_s) / inverse_inertia;
        const float model_Nm = w->model_prev_Nm;
        w->samples++;
        w->sum_model_Nm += model_Nm;
        w->sum_implied_Nm += implied_Nm;
        if ((float)(w->samples - 1u) * dt_s < cal->adapt_film_window_s) {  /* the first samples: exact */
            w->sum_model_early_Nm += model_Nm;
            w->sum_implied_early_Nm += implied_Nm;
        }
        float upper;
        const uint32_t lower = node_weights(cal, w->theta_prev_degC, &upper);
        w->weight_Nm[lower] += (1.0f - upper) * model_Nm;
        if (upper > 0.0f) { w->weight_Nm[lower + 1u] += upper * model_Nm; }
        const float r = implied_Nm - model_Nm;
        const float x1 = w->coulomb_prev_Nm;
        const float x2 = w->coulomb_per_N_prev;
        w->s11_Nm2 += x1 * x1;
        w->s12_Nm2_per_N += x1 * x2;
        w->s22_Nm2_per_N2 += x2 * x2;
        w->s1r_Nm2 += x1 * r;
        w->s2r_Nm2_per_N += x2 * r;
    } else {
        w->started = true;
        w->slip_start_rad_s = slip_rad_s;
    }
    w->slip_prev_rad_s = slip_rad_s;
    w->drive_prev_rad_s2 = drive_rad_s2;
    w->model_prev_Nm = out->model.torque_Nm;
    w->coulomb_prev_Nm = out->model.coulomb_Nm;
    w->coulomb_per_N_prev = (out->contact_force_N > 0.0f) ? (out->model.coulomb_Nm / out->contact_force_N) : 0.0f;
    w->theta_prev_degC = out->theta_degC;
}

/* The kiss point's update from the least squares (wc_adapt.h), in Pa; 0 when
 * the force did not vary enough to tell an offset from a scale. */
static float kiss_innovation_Pa(const wc_adapt_window_t *w, const wc_shift_calibration_t *cal, float piston_area_m2)
{
    const float product = w->s11_Nm2 * w->s22_Nm2_per_N2;
    const float determinant = product - w->s12_Nm2_per_N * w->s12_Nm2_per_N;
    if (!(product > 0.0f) || !(determinant >= cal->adapt_min_conditioning * product) || !(determinant > 0.0f)) {
        return 0.0f;  /* also NaN */
    }
    const float b1 = (w->s22_Nm2_per_N2 * w->s1r_Nm2 - w->s12_Nm2_per_N * w->s2r_Nm2_per_N) / determinant;
    const float b2 = (w->s11_Nm2 * w->s2r_Nm2_per_N - w->s12_Nm2_per_N * w->s1r_Nm2) / determinant;
    if (!(1.0f + b1 >= 0.5f)) { return 0.0f; }
    const float innovation_Pa = -b2 / (1.0f + b1) / piston_area_m2;
    return isfinite(innovation_Pa) ? innovation_Pa : 0.0f;
}

wc_adapt_change_t wc_adapt_finish(wc_adapt_t *adapt, const wc_shift_calibration_t *cal, uint32_t abort_reason,
                                  const wc_clutch_t *clutch)
{
    wc_adapt_change_t change = unchanged;
    if (!adaptation_on(adapt, cal) || (clutch == NULL) || (clutch->model.cal == NULL)) { return change; }
    wc_adapt_values_t *v = &adapt->values;
    const wc_adapt_window_t *w = &adapt->window;
    /* the node with the largest share: the one the report shows */
    uint32_t node = 0u;
    for (uint32_t i = 1u; i < WC_ADAPT_NODES; ++i) {
        if (w->weight_Nm[i] > w->weight_Nm[node]) { node = i; }
    }
    const float scale_before = v->friction_scale[node];
    const float film_before = v->film_factor;
    const float kiss_before_Pa = v->kiss_offset_Pa;

    const float rho = w->sum_implied_Nm / w->sum_model_Nm;
    const float drop_rad_s = w->slip_start_rad_s - w->slip_prev_rad_s;
    wc_adapt_result_t result = WC_ADAPT_RESULT_UPDATED;
    if (abort_reason != 0u) { result = WC_ADAPT_RESULT_ABORTED; }
    else if (w->fault) { result = WC_ADAPT_RESULT_INPUT_FAULT; }
    else if ((w->samples == 0u) || !(w->sum_model_Nm > 0.0f) ||
             !(drop_rad_s >= cal->adapt_min_slip_drop * w->slip_start_rad_s)) {
        result = WC_ADAPT_RESULT_EXCITATION;
    } else if (!within(rho, WC_ADAPT_RHO_MIN, WC_ADAPT_RHO_MAX)) {
        result = WC_ADAPT_RESULT_IMPLAUSIBLE;  /* also NaN */
    }
    if (result == WC_ADAPT_RESULT_UPDATED) {
        /* friction scale per node, by its share of the window (DESIGN 12) */
        float total_Nm = 0.0f;
        for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) { total_Nm += w->weight_Nm[i]; }
        float share[WC_ADAPT_NODES];
        float share_sq = 0.0f;  /* sum of the squared shares, in [1/WC_ADAPT_NODES, 1] */
        for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
            share[i] = (total_Nm > 0.0f) ? clip(w->weight_Nm[i] / total_Nm, 0.0f, 1.0f) : 0.0f;
            share_sq += share[i] * share[i];
        }
        const float band = cal->adapt_scale_band;
        /* each node's own step, normalised: the interpolated scale at the window's temperatures moves by
         * gain * its error; a confident node's own step is at most half a step (one faulty shift costs it less) */
        float own_step[WC_ADAPT_NODES];
        float window_scale = 0.0f;  /* the window's interpolated scale after the own steps */
        for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
            const float own = (share_sq > 0.0f) ? (share[i] / share_sq) : 0.0f;
            const float limit = cal->adapt_scale_step * (1.0f - 0.5f * v->confidence[i]);
            own_step[i] = clip(cal->adapt_scale_gain * own * v->friction_scale[i] * (rho - 1.0f), -limit, limit);
            window_scale += share[i] * (v->friction_scale[i] + own_step[i]);
        }
        for (uint32_t i = 0u; i < WC_ADAPT_NODES; ++i) {
            /* a node not yet learned (confidence 0) takes the window's scale, a smooth prior (neighbouring
             * temperatures have similar scales until shifts there say otherwise): the level the learned nodes
             * hold, not a sum of every shift's error (which a node outside the windows, with no feedback of
             * its own, would drift on); at most a step per shift */
            const float c = v->confidence[i];
            const float s = v->friction_scale[i];
            const float step = clip((c * own_step[i]) + ((1.0f - c) * (window_scale - s)), -cal->adapt_scale_step,
                                    cal->adapt_scale_step);
            v->friction_scale[i] = clip(s + step, 1.0f - band, 1.0f + band);
            v->confidence[i] = clip(c + cal->adapt_confidence_gain * share[i] * (1.0f - c), 0.0f, 1.0f);
        }
        /* kiss point: the force offset the residual shows */
        const float kiss_step_Pa = clip(cal->adapt_kiss_gain *
                                            kiss_innovation_Pa(w, cal, clutch->model.cal->piston_area_m2),
                                        -cal->adapt_kiss_step_Pa, cal->adapt_kiss_step_Pa);
        v->kiss_offset_Pa = clip(v->kiss_offset_Pa + kiss_step_Pa, -cal->adapt_kiss_band_Pa, cal->adapt_kiss_band_Pa);
        /* film factor: less torque early than late is a slower film */
        const float rho_early = w->sum_implied_early_Nm / w->sum_model_early_Nm;
        if ((clutch->model.film_damping_m4 > 0.0f) && (w->sum_model_early_Nm > 0.0f) && (rho_early > 0.0f) &&
            isfinite(rho_early)) {
            const float step = clip(cal->adapt_film_gain * (rho / rho_early - 1.0f), -cal->adapt_film_step,
                                    cal->adapt_film_step);
            v->film_factor = clip(v->film_factor * (1.0f + step), cal->adapt_film_factor_min,
                                  cal->adapt_film_factor_max);
        }
        v->shifts_learned = (v->shifts_learned < UINT32_MAX) ? (v->shifts_learned + 1u) : UINT32_MAX;
    }
    change.result = (uint32_t)result;
    change.node = node;
    change.friction_scale = v->friction_scale[node];
    change.friction_scale_change = v->friction_scale[node] - scale_before;
    change.confidence = v->confidence[node];
    change.film_factor = v->film_factor;
    change.film_factor_change = v->film_factor - film_before;
    change.kiss_offset_Pa = v->kiss_offset_Pa;
    change.kiss_offset_change_Pa = v->kiss_offset_Pa - kiss_before_Pa;
    return change;
}
