/* The inertia-phase-first shift (DESIGN 15; wc_shift.h): the kickdown in
 * the controller's frame, the tip-out upshift mirrored by wc_transmission.
 * The off-going clutch lets the turbine run to the target gear's speed on
 * the reference slip; the on-coming clutch, filled at its kiss point, takes
 * the torque over at synchronism. The transitions (command, safe state,
 * fallback) and the inertia phase's end are the torque-first shift's
 * (wc_shift_internal.h). */
#include "wetclutch/wc_shift.h"

#include <math.h>
#include <stddef.h>

#include "wc_internal.h"
#include "wc_shift_internal.h"

/* DESIGN 15: the off-going clutch (slip w_t - b1 w_o, a = 1) carries T_1 while
 * the on-coming one (slip w_t - b w_o < 0) carries T_c: I_t dw_t/dt = T_t -
 * T_1 + T_c, I_out dw_o/dt = b1 T_1 - b T_c - T_road, so d(slip)/dt = T_t / I_t
 * - T_1 k_1 + T_c k_c, k_1 = 1 / I_t + b b1 / I_out, k_c = 1 / I_t + b^2 /
 * I_out (+ the road load, small, left to the PI). The feed-forward for the
 * reference's rate is the hold-back T_1 = (T_t / I_t - dref/dt) / k_1; a
 * negative one (T_t cannot move the turbine that fast) is, with the
 * on-coming assist, the on-coming clutch's push T_c = -T_1 k_1 / k_c. */
static float holdback_k1(const wc_shift_calibration_t *cal)
{
    return 1.0f / cal->turbine_inertia_kg_m2 + cal->output_ratio * cal->offgoing_ratio / cal->output_inertia_kg_m2;
}

static float holdback_feedforward_Nm(const wc_shift_calibration_t *cal, float k_1, float turbine_torque_Nm,
                                     float rate_rad_s2)
{
    const float t_1 = (turbine_torque_Nm / cal->turbine_inertia_kg_m2 - rate_rad_s2) / k_1;
    return (t_1 < WC_TORQUE_MAX_Nm) ? ((t_1 > -WC_TORQUE_MAX_Nm) ? t_1 : -WC_TORQUE_MAX_Nm) : WC_TORQUE_MAX_Nm;
}

/* The torque the on-coming clutch carries once synchronous (the torque-first
 * shift's feed-forward at a zero slip rate, DESIGN 10): a T_t / I_t /
 * (a^2 / I_t + b^2 / I_out), a = 1. */
static float oncoming_carried_Nm(const wc_shift_calibration_t *cal, float turbine_torque_Nm)
{
    const float i_t = cal->turbine_inertia_kg_m2;
    const float b = cal->output_ratio;
    /* a magnitude: after a coast downshift it holds the engine's drag (T_t < 0) */
    return wc_shift_clamp_torque_Nm(fabsf(turbine_torque_Nm / i_t) / (1.0f / i_t + b * b / cal->output_inertia_kg_m2));
}

/* Without the on-coming assist only the turbine torque moves the turbine
 * (the off-going clutch can only hold it back): the reference's peak rate
 * 1.5 |slip_0| / T must stay within T_t / I_t, with WC_SHIFT_FEASIBLE_MARGIN
 * to spare for the PI. A target faster than that is stretched (at most to
 * inertia_time_max_s): a kickdown's engine torque sets the pace, the feedback
 * does not saturate at an empty clutch and time out (DESIGN 15). */
#define WC_SHIFT_FEASIBLE_MARGIN 1.25f
static float feasible_time_s(const wc_shift_calibration_t *cal, float target_time_s, float start_slip_rad_s,
                             float turbine_torque_Nm)
{
    const float acceleration_rad_s2 = turbine_torque_Nm / cal->turbine_inertia_kg_m2;
    const float need_s = WC_SHIFT_FEASIBLE_MARGIN * 1.5f * fabsf(start_slip_rad_s);
    /* need / acceleration > max, written without the division (acceleration may be 0) */
    if (!(need_s < cal->inertia_time_max_s * acceleration_rad_s2)) { return cal->inertia_time_max_s; }
    const float feasible_s = need_s / acceleration_rad_s2;
    return (feasible_s > target_time_s) ? feasible_s : target_time_s;
}

/* DESIGN 15, the kickdown: the on-coming clutch's fill is timed to arrive at
 * synchronism. Filled early, it waits at its kiss point with the whole
 * shift's slip across a closed pack: its drag (eq. 5-8's viscous term at
 * |slip| ~ 200 rad/s, some 80 N m on the 8HP's 3->2) ties the gearbox up at
 * the inertia phase's start and the output torque falls (measured: -33 m/s^3).
 * So it stays open until the reference leaves lead_s = prepare_time_s (the
 * fill's duration) to the target; then the fill pulse, then the kiss point.
 * Returns the periods since the fill began (0 before; UINT32_MAX when not in
 * the inertia phase). With the on-coming assist (the tip-out) it may have to
 * push from the start: filled in PREPARE, as the torque-first shift. */
static uint32_t late_fill_periods(const wc_shift_t *shift, const wc_shift_calibration_t *cal, float dt_s)
{
    const uint32_t target = wc_shift_periods_of(shift->target_time_s, dt_s);
    const uint32_t lead = wc_shift_periods_of(cal->prepare_time_s, dt_s);
    const uint32_t start = (target > lead) ? (target - lead) : 0u;
    return (shift->phase_periods >= start) ? (shift->phase_periods - start + 1u) : 0u;
}

/* The smoothstep of the torque phase at its next period (0 .. 1). */
static float handover_share(const wc_shift_t *shift, const wc_shift_calibration_t *cal, float dt_s)
{
    const float t_s = (float)(shift->phase_periods + 1u) * dt_s;
    const float x = (cal->torque_phase_time_s > 0.0f) ? (t_s / cal->torque_phase_time_s) : 1.0f;
    const float xc = (x < 1.0f) ? x : 1.0f;
    return xc * xc * (3.0f - 2.0f * xc);
}

typedef struct {
    float oncoming_Nm;   /* the on-coming clutch's request (WC_MODE_TORQUE) */
    float engine_Nm;     /* WC_SHIFT_INERTIA_FIRST_ENGINE: the engine request (> 0: more torque) */
    float offgoing_Nm;   /* the off-going clutch's request */
    bool offgoing_locked;  /* hand-back: the off-going clutch at its maximum current */
    bool offgoing_open;
} requests_t;

/* The phase's law; may change the phase (PREPARE -> INERTIA). */
static requests_t phase_requests(wc_shift_t *shift, const wc_shift_calibration_t *cal, float slip_rad_s, float dt_s,
                                 bool offgoing_saturated, bool oncoming_saturated, bool assist, bool engine)
{
    requests_t r = { 0.0f, 0.0f, 0.0f, false, true };
    const float t_t_Nm = shift->turbine_torque_Nm;
    const uint32_t phase = shift->phase;
    if ((phase == (uint32_t)WC_SHIFT_IDLE) || (phase == (uint32_t)WC_SHIFT_ABORTED)) {
        r.offgoing_locked = !shift->second_gear;  /* hand-back, or the source gear held until the shift starts */
        r.offgoing_open = shift->second_gear;
        return r;
    }
    if (phase == (uint32_t)WC_SHIFT_PREPARE) {
        const uint32_t n = wc_shift_periods_of(cal->prepare_time_s, dt_s);
        if (shift->phase_periods < n) {
            const float x = (float)(shift->phase_periods + 1u) / (float)n;
            /* magnitudes: before a coast downshift it holds the engine's drag (T_t < 0) */
            const float from_Nm = cal->offgoing_holding_factor * fabsf(t_t_Nm);
            const float to_Nm = (1.0f + cal->offgoing_margin_factor) * fabsf(t_t_Nm);
            r.offgoing_Nm = from_Nm + (to_Nm - from_Nm) * x;
            r.offgoing_open = false;
            return r;
        }
        /* inertia phase: the reference starts at the measured slip (below the target gear's speed); bumpless:
         * the integral takes what the feed-forward does not give of the last request */
        wc_shift_enter(shift, WC_SHIFT_INERTIA);
        shift->start_slip_rad_s = slip_rad_s;
        /* the torque that moves the turbine: T_t, or with the engine what it may add to the driver's T_t0 */
        const float moving_Nm = engine ? (shift->driver_torque_Nm + cal->engine_increase_max_Nm) : t_t_Nm;
        if (!assist) { shift->target_time_s = feasible_time_s(cal, shift->target_time_s, slip_rad_s, moving_Nm); }
        shift->request_Nm = (1.0f + cal->offgoing_margin_factor) * fabsf(t_t_Nm);
        shift->integral_Nm = shift->request_Nm - cal->feedforward_gain * holdback_feedforward_Nm(cal, holdback_k1(cal), t_t_Nm, 0.0f);
        if (!(slip_rad_s < -cal->min_start_slip_rad_s)) {
            wc_shift_abort(shift, WC_SHIFT_ABORT_NO_SLIP);
            r.offgoing_locked = true;  /* handed back */
            r.offgoing_open = false;
            return r;
        }
    }
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) {
        float rate_rad_s2;
        const float elapsed_s = (float)shift->phase_periods * dt_s;
        const float reference = wc_shift_reference_at(shift->start_slip_rad_s, shift->target_time_s, elapsed_s, &rate_rad_s2);
        const float k_1 = holdback_k1(cal);
        const float ff_Nm = cal->feedforward_gain * holdback_feedforward_Nm(cal, k_1, t_t_Nm, rate_rad_s2);
        /* slip above the reference: the turbine runs ahead, the off-going clutch holds more (with the assist:
         * the on-coming one pushes less) */
        const float error = slip_rad_s - reference;
        shift->error_sq_sum += error * error;
        shift->inertia_periods++;
        const float pi_Nm = cal->kp_Nm_per_rad_s * error + shift->integral_Nm;
        const float holdback_Nm = ff_Nm + pi_Nm;
        if (engine) {
            /* the coast downshift: the engine accelerates the turbine on the reference, engine_lead_time_s ahead
             * (its lag): I_t dref/dt - T_t0; the turbine lagging (PI < 0) asks it for -PI k_1 I_t more (the
             * turbine torque that a hold-back of PI would take away, DESIGN 15) */
            float lead_rate_rad_s2;
            (void)wc_shift_reference_at(shift->start_slip_rad_s, shift->target_time_s,
                                        elapsed_s + cal->engine_lead_time_s, &lead_rate_rad_s2);
            const float lagging_Nm = (pi_Nm < 0.0f) ? (-pi_Nm * k_1 * cal->turbine_inertia_kg_m2) : 0.0f;
            const float want_Nm = cal->turbine_inertia_kg_m2 * lead_rate_rad_s2 - shift->driver_torque_Nm + lagging_Nm;
            r.engine_Nm = (want_Nm > 0.0f) ? ((want_Nm < cal->engine_increase_max_Nm) ? want_Nm : cal->engine_increase_max_Nm)
                                           : 0.0f;
            shift->engine_from_Nm = r.engine_Nm;  /* where the torque phase's ramp-out starts */
        }
        /* anti-windup: no integration further into a saturated clutch, nor below 0 without the assist (with the
         * engine: not while the engine is at its limit) */
        const bool engine_full = engine && !(r.engine_Nm < cal->engine_increase_max_Nm);
        const bool blocked = (offgoing_saturated && (error > 0.0f)) ||
                             ((error < 0.0f) && (assist ? oncoming_saturated : (engine ? engine_full : (holdback_Nm <= 0.0f))));
        if (!blocked) {
            const float integral = shift->integral_Nm + cal->ki_Nm_per_rad * error * dt_s;
            const float limit = cal->integral_limit_Nm;
            shift->integral_Nm = (integral > limit) ? limit : ((integral < -limit) ? -limit : integral);
        }
        if (slip_rad_s > cal->flare_slip_rad_s) { shift->report.flare = true; }  /* past synchronism */
        r.offgoing_Nm = holdback_Nm;
        /* the push per newton metre of negative hold-back: k_1 / k_c (above) */
        const float b = cal->output_ratio;
        const float k_c = 1.0f / cal->turbine_inertia_kg_m2 + b * b / cal->output_inertia_kg_m2;
        r.oncoming_Nm = assist ? (-holdback_Nm * k_1 / k_c) : 0.0f;  /* clamped at 0 by set_input */
        /* the tip-out: once the hold-back is spent (the on-coming clutch pushes), the off-going clutch opens for
         * good, while the push still ramps in: at its kiss point its drag at the shift's slip would be a tie-up
         * the push works against, and its release at synchronism a step of the output torque (DESIGN 15) */
        /* (the coast downshift likewise: once the engine carries the turbine, the off-going clutch's drag at
         * the shift's slip would push the coasting vehicle, then vanish at synchronism) */
        if ((assist || engine) && !(holdback_Nm > 0.0f)) { shift->offgoing_released = true; }
        r.offgoing_open = shift->offgoing_released;
        return r;
    }
    /* TORQUE (the hand-over at synchronism), LOCKED */
    const float hold_Nm = cal->holding_torque_factor * oncoming_carried_Nm(cal, t_t_Nm);
    const float x = (phase == (uint32_t)WC_SHIFT_TORQUE) ? handover_share(shift, cal, dt_s) : 1.0f;
    /* the turbine running past synchronism (slip > 0: the off-going clutch lets go while T_t still drives) is
     * taken by the on-coming clutch in closed loop (the torque-first shift's flare correction, DESIGN 14) */
    /* (after a coast downshift T_t < 0 drags the turbine back below synchronism: the slip past it is
     * negative, and the on-coming clutch holds it the same way) */
    const float past_signed_rad_s = engine ? -slip_rad_s : slip_rad_s;
    const float past_rad_s = (past_signed_rad_s > 0.0f) ? past_signed_rad_s : 0.0f;
    if (phase == (uint32_t)WC_SHIFT_TORQUE) {
        const float integral_Nm = shift->flare_integral_Nm + cal->flare_ki_Nm_per_rad * past_rad_s * dt_s;
        shift->flare_integral_Nm = (integral_Nm < fabsf(t_t_Nm)) ? integral_Nm : fabsf(t_t_Nm);  /* anti-windup: |T_t| */
        if (slip_rad_s > cal->flare_slip_rad_s) { shift->report.flare = true; }
    }
    r.oncoming_Nm = hold_Nm * x + cal->flare_kp_Nm_per_rad_s * past_rad_s + shift->flare_integral_Nm;
    r.engine_Nm = (engine && (phase == (uint32_t)WC_SHIFT_TORQUE)) ? (shift->engine_from_Nm * (1.0f - x)) : 0.0f;
    r.offgoing_Nm = shift->phase_start_request_Nm * (1.0f - x);
    /* nothing to hand over (the tip-out's hold-back ended at 0: the on-coming clutch pushed): open at once,
     * not at the kiss point, where its drag at the whole shift's slip ties the gearbox up (DESIGN 15) */
    r.offgoing_open = !(x < 1.0f) || !(shift->phase_start_request_Nm > 0.0f) || shift->offgoing_released;
    return r;
}

static void set_input(wc_step_input_t *in, wc_clutch_mode_t mode, float request_Nm, float carried_Nm,
                      const wc_lag_compensation_t *lag)
{
    const wc_model_correction_t none = { 0.0f, 0.0f, 0.0f };
    in->mode = mode;
    in->torque_request_Nm = (mode == WC_MODE_TORQUE) ? wc_shift_clamp_torque_Nm(request_Nm) : 0.0f;
    in->carried_torque_Nm = (mode == WC_MODE_TORQUE) ? wc_shift_clamp_torque_Nm(carried_Nm) : 0.0f;
    in->lag_compensation = *lag;
    in->theta_from_oil = false;
    in->correction = none;
}

/* After the steps: the inertia phase's end (synchronism: the torque phase),
 * the hand-over's end (LOCKED, or AbortReason 2). */
static void phase_end(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_clutch_t *clutch, bool locked,
                      float slip_rad_s, float dt_s, bool off_driven)
{
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) {
        /* the on-coming clutch waits at its kiss point: its model does not lock; synchronism ends the phase,
         * also when the slip runs through it without a dwell in the lock band (a tip-out's turbine, pulled down
         * by the engine's drag, goes on below the target gear's speed: the torque phase's correction of the
         * slip past synchronism takes it; measured on the 8HP's 1->2: through 0 at 1.3 s, then a 300 rpm sag
         * and an inertia timeout). Only where the off-going clutch no longer drives the slip (off_driven false:
         * the tip-out's push, the coast's engine): in a kickdown its hold-back pulls an overshoot back (on the
         * 4->3 ending at the crossing flared 33 rpm) */
        const bool crossed = !off_driven && !(slip_rad_s < 0.0f) &&
                             (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE);
        if (crossed) { shift->report.inertia_time_s = (float)(shift->phase_periods + 1u) * dt_s; }
        if (crossed || wc_shift_inertia_over(shift, cal, clutch, false, slip_rad_s, dt_s)) {
            shift->phase_start_request_Nm = shift->request_Nm;
            /* the coast downshift's engine request at synchronism: only what cancels the engine's drag (no net
             * turbine torque), then ramped out over the hand-over: what the PI added for a lagging turbine would
             * reach the output through the closing on-coming clutch as a push (measured: +96 N m, 11 m/s^3) */
            const float drag_Nm = -shift->driver_torque_Nm;
            const float hold_Nm = (drag_Nm > 0.0f) ? drag_Nm : 0.0f;
            shift->engine_from_Nm = (shift->engine_from_Nm < hold_Nm) ? shift->engine_from_Nm : hold_Nm;
            shift->second_gear = true;  /* from here the on-coming clutch takes the gear: a lost input finishes */
            wc_shift_enter(shift, WC_SHIFT_TORQUE);
        }
    } else if (shift->phase == (uint32_t)WC_SHIFT_TORQUE) {
        wc_shift_handover_end(shift, locked, wc_shift_periods_of(cal->torque_phase_time_s, dt_s));
    }
}

bool wc_shift_inertia_first_step(wc_shift_t *shift, const wc_shift_calibration_t *cal,
                                 const wc_shift_command_t *command, bool safe, uint32_t options, wc_clutch_t *clutch,
                                 wc_step_input_t *in, wc_step_output_t *out, wc_shift_report_t *report,
                                 wc_shift_offgoing_t *offgoing)
{
    WC_ASSERT((shift != NULL) && (cal != NULL) && (command != NULL) && (clutch != NULL) && (in != NULL) &&
              (out != NULL) && (report != NULL) && (offgoing != NULL));
    if ((shift == NULL) || (cal == NULL) || (command == NULL) || (clutch == NULL) || (in == NULL) || (out == NULL) ||
        (report == NULL) || (offgoing == NULL) || (offgoing->clutch == NULL) || (offgoing->in == NULL) ||
        (offgoing->out == NULL)) {
        return false;
    }
    const uint32_t phase_before = shift->phase;
    const float dt_s = (clutch->model.cal != NULL) ? clutch->model.cal->control_period_s : 1e-3f;  /* init failed: any */
    const float slip_rad_s = wc_slip_valid(in->slip_rad_s) ? in->slip_rad_s : clutch->held.slip_rad_s;
    const float s1 = offgoing->in->slip_rad_s;
    shift->offgoing_slip_rad_s = wc_slip_valid(s1) ? s1 : offgoing->clutch->held.slip_rad_s;
    if (safe) {
        shift->fallback_periods = (shift->fallback_periods < UINT32_MAX) ? (shift->fallback_periods + 1u) : UINT32_MAX;
    } else if (!wc_shift_phase_running(shift->phase)) {
        shift->fallback_periods = 0u;
    }
    /* the coast downshift's engine drags: a negative T_t is its normal command */
    const float torque_min_Nm = ((options & WC_SHIFT_INERTIA_FIRST_ENGINE) != 0u) ? -WC_TORQUE_MAX_Nm : 0.0f;
    wc_shift_transitions(shift, cal, command, safe, true, torque_min_Nm, slip_rad_s, dt_s, clutch, NULL, offgoing);

    /* the clutches' inputs: the phase's law; the safe state holds the source gear until the hand-over */
    const bool offgoing_saturated = (offgoing->out->status & WC_STATUS_SATURATED) != 0u;
    const bool oncoming_saturated = (out->status & WC_STATUS_SATURATED) != 0u;  /* last step's outputs */
    const bool oncoming_assist = (options & WC_SHIFT_INERTIA_FIRST_ASSIST) != 0u;
    const bool engine = (options & WC_SHIFT_INERTIA_FIRST_ENGINE) != 0u;
    const requests_t r = phase_requests(shift, cal, slip_rad_s, dt_s, offgoing_saturated, oncoming_saturated,
                                        oncoming_assist, engine);
    /* the on-coming clutch: filled in PREPARE with the assist, else late in the inertia phase (above) */
    const bool inertia = shift->phase == (uint32_t)WC_SHIFT_INERTIA;
    const uint32_t fill_periods = (inertia && !oncoming_assist) ? late_fill_periods(shift, cal, dt_s) : 0u;
    const bool filling = oncoming_assist ? (shift->phase == (uint32_t)WC_SHIFT_PREPARE) : (fill_periods > 0u);
    const bool on_active = (oncoming_assist && ((shift->phase == (uint32_t)WC_SHIFT_PREPARE) || inertia)) ||
                           (inertia && (fill_periods > 0u)) || (shift->phase == (uint32_t)WC_SHIFT_TORQUE) ||
                           (shift->phase == (uint32_t)WC_SHIFT_LOCKED);
    const float carried_on_Nm = oncoming_carried_Nm(cal, shift->turbine_torque_Nm);
    set_input(in, on_active ? WC_MODE_TORQUE : WC_MODE_OPEN, r.oncoming_Nm, carried_on_Nm, &shift->lag_compensation);
    const bool hand_back = (safe && !shift->second_gear) || r.offgoing_locked;
    const wc_clutch_mode_t off_mode = hand_back ? WC_MODE_LOCKED : (r.offgoing_open ? WC_MODE_OPEN : WC_MODE_TORQUE);
    /* it carries the turbine torque while it holds (the lock-up's decision: below it, it slips) */
    set_input(offgoing->in, off_mode, r.offgoing_Nm, shift->turbine_torque_Nm, &shift->offgoing_lag);
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) { shift->request_Nm = wc_shift_clamp_torque_Nm(r.offgoing_Nm); }

    (void)wc_clutch_step(clutch, in, out);
    wc_shift_fill_pulse(cal, clutch, filling, oncoming_assist ? shift->phase_periods : (fill_periods - 1u), dt_s, out);
    (void)wc_clutch_step(offgoing->clutch, offgoing->in, offgoing->out);
    /* the engine request (the coast downshift); none in the safe state or a fallback */
    offgoing->engine_active = engine && (r.engine_Nm > 0.0f) && !safe &&
                              (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE);
    offgoing->engine_delta_Nm = offgoing->engine_active ? r.engine_Nm : 0.0f;

    const bool locked = (out->status & WC_STATUS_LOCKED) != 0u;
    const uint32_t phase_stepped = shift->phase;
    phase_end(shift, cal, clutch, locked, slip_rad_s, dt_s, options == 0u);

    /* the quality vector: both clutches' heat (eq. 1), the output torque T_c + (b1 / b) T_1's jerk */
    const float heat_W = fabsf(out->model.torque_Nm * slip_rad_s) + fabsf(offgoing->out->model.torque_Nm * shift->offgoing_slip_rad_s);
    const float theta_degC = (clutch->theta_degC > offgoing->clutch->theta_degC) ? clutch->theta_degC
                                                                                : offgoing->clutch->theta_degC;
    const float output_Nm = out->model.torque_Nm + cal->offgoing_ratio / cal->output_ratio * offgoing->out->model.torque_Nm;
    const bool ended = wc_shift_account(shift, cal, phase_before, phase_stepped, heat_W, theta_degC, output_Nm, dt_s);
    if (ended) {
        shift->report.adaptation = wc_adapt_finish(NULL, cal, shift->report.abort_reason, clutch);
        *report = shift->report;
    }
    return ended;
}
