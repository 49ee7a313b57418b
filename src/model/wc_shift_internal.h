/* What the two shift controllers share (not part of the public API): the
 * torque-phase-first one (wc_shift.c: the power-on upshift and, mirrored,
 * the coast downshift) and the inertia-phase-first one
 * (wc_shift_inertia_first.c: the kickdown and, mirrored, the tip-out
 * upshift), DESIGN 10, 14, 15. */
#ifndef WC_SHIFT_INTERNAL_H
#define WC_SHIFT_INTERNAL_H

#include "wetclutch/wc_shift.h"
#include "wc_internal.h"

/* A value in [lo, hi] (false for NaN). */
static inline bool wc_shift_in_closed(float value, float lo, float hi) { return (value >= lo) && (value <= hi); }

/* The reference slip of the inertia phase (DESIGN 10): smoothstep from the
 * start slip to 0; zero slope at both ends, so the feed-forward (and the
 * clutch torque) neither steps at the phase start nor at lock-up. Inline in
 * the steps at -O2 (no call, no rate through memory). */
WC_INLINE_HOT float wc_shift_reference_at(float start_slip_rad_s, float target_time_s, float elapsed_s,
                                          float *rate_rad_s2)
{
    float x = (target_time_s > 0.0f) ? (elapsed_s / target_time_s) : 1.0f;
    x = (x > 0.0f) ? ((x < 1.0f) ? x : 1.0f) : 0.0f;  /* also NaN -> 0 */
    if (rate_rad_s2 != NULL) {
        *rate_rad_s2 = (target_time_s > 0.0f) ? (-6.0f * start_slip_rad_s * x * (1.0f - x) / target_time_s) : 0.0f;
    }
    return start_slip_rad_s * (1.0f - x * x * (3.0f - 2.0f * x));
}

/* A torque request within [0, WC_TORQUE_MAX_Nm] (NaN -> 0). */
static inline float wc_shift_clamp_torque_Nm(float torque_Nm)
{
    return (torque_Nm > 0.0f) ? ((torque_Nm < WC_TORQUE_MAX_Nm) ? torque_Nm : WC_TORQUE_MAX_Nm) : 0.0f;
}

/* The slip PI's integral (DESIGN 10) advanced by increment_Nm (ki x error x dt, times the controller's loop
 * gain squared), within the calibration's anti-windup bound: the one home of both controllers' integral. */
static inline void wc_shift_integrate(wc_shift_t *shift, const wc_shift_calibration_t *cal, float increment_Nm)
{
    const float integral = shift->integral_Nm + increment_Nm;
    const float limit = cal->integral_limit_Nm;
    shift->integral_Nm = (integral > limit) ? limit : ((integral < -limit) ? -limit : integral);
}

static inline uint32_t wc_shift_periods_of(float time_s, float dt_s)
{
    const float n = time_s / dt_s + 0.5f;  /* both checked: time <= 10 s, dt >= 1e-4 s */
    return (uint32_t)n;
}

static inline void wc_shift_enter(wc_shift_t *shift, wc_shift_phase_t phase)
{
    shift->phase = (uint32_t)phase;
    shift->phase_periods = 0u;
}

static inline void wc_shift_abort(wc_shift_t *shift, wc_shift_abort_t reason)
{
    wc_shift_enter(shift, WC_SHIFT_ABORTED);
    shift->report.abort_reason = (uint32_t)reason;
}

/* The fallback in the state and in the running report. */
static inline void wc_shift_set_fallback(wc_shift_t *shift, wc_shift_fallback_t fallback)
{
    shift->fallback = (uint32_t)fallback;
    shift->report.fallback = (uint32_t)fallback;
}

/* A command the controller can start: its target gear, a target time in the
 * calibration's range, a turbine torque in [0, WC_TORQUE_MAX_Nm] (a power-off
 * shift's comes mirrored, wc_transmission.h). */
static inline bool wc_shift_command_valid(const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                                          float torque_min_Nm)
{
    return (command->target_gear == WC_SHIFT_TARGET_GEAR) &&
           wc_shift_in_closed(command->target_inertia_time_s, cal->inertia_time_min_s, cal->inertia_time_max_s) &&
           wc_shift_in_closed(command->turbine_torque_Nm, torque_min_Nm, WC_TORQUE_MAX_Nm);
}

/* The transitions on the command and the loop's state, before the steps
 * (wc_shift.c; both controllers): a start on the request's edge in IDLE
 * (an invalid command aborts, AbortReason 5), a cancel, the safe state
 * (with the coordinator the fallback of DESIGN 14: handed back while the
 * off-going clutch has the gear, !second_gear; else finished on the model,
 * released after fallback_time_s), the input's return (resume), the turbine
 * torque followed from the command. coord: the off-going clutch is ours.
 * torque_min_Nm: the lowest turbine torque a command may carry (0; the coast
 * downshift's -WC_TORQUE_MAX_Nm: the engine drags). */
void wc_shift_transitions(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                          bool safe, bool coord, float torque_min_Nm, float slip_rad_s, float dt_s,
                          const wc_clutch_t *clutch, wc_adapt_t *adapt, const wc_shift_offgoing_t *offgoing);

/* The hand-over's end, after the step (both controllers: the torque-first
 * shift's LOCKUP, the inertia-first one's TORQUE): LOCKED once the clutch
 * that takes the gear is locked and its ramp of ramp_periods done (the
 * lock-up's dwell and the film may end after it), AbortReason 2 when not
 * locked after WC_SHIFT_LOCKUP_WAIT ramps; during a fallback the slip is not
 * known: the hand-over goes on, never reported locked (issue 29 item 7). */
static inline void wc_shift_handover_end(wc_shift_t *shift, bool locked, uint32_t ramp_periods)
{
    if (shift->fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE) {
        /* the input back restarts it (resume), else the fallback releases it after fallback_time_s */
    } else if (locked && (shift->phase_periods + 1u >= ramp_periods)) {
        wc_shift_enter(shift, WC_SHIFT_LOCKED);
    } else if (shift->phase_periods + 1u >= WC_SHIFT_LOCKUP_WAIT * ramp_periods + 1u) {
        wc_shift_abort(shift, WC_SHIFT_ABORT_LOCKUP_FAILED);
    } else {
        /* ramping, or waiting for the lock */
    }
}

/* The inertia phase's end, after the step (wc_shift.c; both controllers):
 * true when over (report.inertia_time_s set); an overrun aborts. */
bool wc_shift_inertia_over(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_clutch_t *clutch, bool locked,
                           float slip_rad_s, float dt_s);

/* The quality vector's period and the shift's end (wc_shift.c; both controllers). */
bool wc_shift_account(wc_shift_t *shift, const wc_shift_calibration_t *cal, uint32_t phase_before, uint32_t phase_stepped,
                      float heat_W, float theta_degC, float output_torque_Nm, float dt_s);

/* The fill pulse (DESIGN 14), after the on-coming clutch's step: while
 * filling, for fill_pulse_time_s from the fill's start (fill_periods since
 * then), the current at least fill_pulse_current_mA. The torque-first shift
 * fills in PREPARE; the inertia-first one late in the inertia phase
 * (wc_shift_inertia_first.c). */
void wc_shift_fill_pulse(const wc_shift_calibration_t *cal, const wc_clutch_t *clutch, bool filling,
                         uint32_t fill_periods, float dt_s, wc_step_output_t *out);

/* The first-order filtered jerk of a torque (DESIGN 10's quality vector):
 * updates *filtered_Nm and returns |jerk_per_torque_rate x its rate|. */
static inline float wc_shift_jerk(const wc_shift_calibration_t *cal, float *filtered_Nm, float torque_Nm, float dt_s)
{
    const float alpha = dt_s / (cal->jerk_filter_time_s + dt_s);  /* first-order filter, exact for tau = 0 */
    const float filtered = *filtered_Nm + (torque_Nm - *filtered_Nm) * alpha;
    const float jerk = fabsf(cal->jerk_per_torque_rate * (filtered - *filtered_Nm) / dt_s);
    *filtered_Nm = filtered;
    return jerk;
}

#endif /* WC_SHIFT_INTERNAL_H */
