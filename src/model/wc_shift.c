#include "wetclutch/wc_shift.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "wc_field_ranges.h"
#include "wc_internal.h"
#include "wc_shift_internal.h"

/* The range of each field, in declaration order, which is the order of the
 * codes: member, code, flags (wc_field_ranges.h), low, high. A time "0 or
 * within": 0 switches it off. */
#define WC_SHIFT_FIELD_RANGES(X) \
    X(turbine_inertia_kg_m2, WC_SHIFT_CAL_TURBINE_INERTIA, 0u, 1e-4f, 100.0f) \
    X(turbine_ratio, WC_SHIFT_CAL_TURBINE_RATIO, 0u, 0.05f, 20.0f) \
    X(output_inertia_kg_m2, WC_SHIFT_CAL_OUTPUT_INERTIA, 0u, 1e-4f, 1e5f) \
    X(output_ratio, WC_SHIFT_CAL_OUTPUT_RATIO, 0u, 0.05f, 20.0f) \
    X(jerk_per_torque_rate, WC_SHIFT_CAL_JERK_PER_TORQUE_RATE, 0u, 0.0f, 1.0f) \
    X(prepare_time_s, WC_SHIFT_CAL_PREPARE_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(torque_phase_time_s, WC_SHIFT_CAL_TORQUE_PHASE_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(inertia_time_min_s, WC_SHIFT_CAL_INERTIA_TIME_MIN, 0u, WC_SHIFT_LIMIT_INERTIA_TIME_MIN_s, \
      WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s) \
    X(inertia_time_max_s, WC_SHIFT_CAL_INERTIA_TIME_MAX, WC_FIELD_LOW_PREVIOUS, 0.0f, \
      WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s)                                     /* >= inertia_time_min_s */ \
    X(inertia_timeout_factor, WC_SHIFT_CAL_INERTIA_TIMEOUT_FACTOR, 0u, 1.05f, 10.0f) \
    X(lockup_ramp_time_s, WC_SHIFT_CAL_LOCKUP_RAMP_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(holding_torque_factor, WC_SHIFT_CAL_HOLDING_TORQUE_FACTOR, 0u, 1.0f, 5.0f) \
    X(min_start_slip_rad_s, WC_SHIFT_CAL_MIN_START_SLIP, 0u, 0.0f, WC_SLIP_MAX_rad_s) \
    X(feedforward_gain, WC_SHIFT_CAL_FEEDFORWARD_GAIN, 0u, 0.0f, 2.0f) \
    X(kp_Nm_per_rad_s, WC_SHIFT_CAL_KP, 0u, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX) \
    X(ki_Nm_per_rad, WC_SHIFT_CAL_KI, 0u, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX) \
    X(integral_limit_Nm, WC_SHIFT_CAL_INTEGRAL_LIMIT, 0u, 0.0f, WC_TORQUE_MAX_Nm) \
    X(lag_compensation_time_s, WC_SHIFT_CAL_LAG_COMPENSATION_TIME, WC_FIELD_OR_ZERO, 1e-3f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(theta_source, WC_SHIFT_CAL_THETA_SOURCE, WC_FIELD_INTEGER, 0.0f, (float)WC_SHIFT_THETA_OIL) \
    X(flare_slip_rad_s, WC_SHIFT_CAL_FLARE_SLIP, 0u, 0.0f, WC_SLIP_MAX_rad_s) \
    X(tie_up_factor, WC_SHIFT_CAL_TIE_UP_FACTOR, 0u, 1.0f, 10.0f) \
    X(jerk_filter_time_s, WC_SHIFT_CAL_JERK_FILTER_TIME, WC_FIELD_OR_ZERO, 1e-3f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(adaptation, WC_SHIFT_CAL_ADAPTATION, WC_FIELD_INTEGER, 0.0f, 1.0f) \
    X(adapt_theta_node_degC[0], WC_SHIFT_CAL_ADAPT_THETA_NODE0, 0u, WC_THETA_MIN_degC, WC_THETA_MAX_degC) \
    X(adapt_theta_node_degC[1], WC_SHIFT_CAL_ADAPT_THETA_NODE1, WC_FIELD_LOW_PREVIOUS | WC_FIELD_LOW_OPEN, 0.0f, WC_THETA_MAX_degC) \
    X(adapt_theta_node_degC[2], WC_SHIFT_CAL_ADAPT_THETA_NODE2, WC_FIELD_LOW_PREVIOUS | WC_FIELD_LOW_OPEN, 0.0f, WC_THETA_MAX_degC) \
    X(adapt_theta_node_degC[3], WC_SHIFT_CAL_ADAPT_THETA_NODE3, WC_FIELD_LOW_PREVIOUS | WC_FIELD_LOW_OPEN, 0.0f, WC_THETA_MAX_degC) \
    X(adapt_theta_node_degC[4], WC_SHIFT_CAL_ADAPT_THETA_NODE4, WC_FIELD_LOW_PREVIOUS | WC_FIELD_LOW_OPEN, 0.0f, WC_THETA_MAX_degC) \
    X(adapt_scale_band, WC_SHIFT_CAL_ADAPT_SCALE_BAND, WC_FIELD_LOW_OPEN, 0.0f, WC_CORRECTION_SCALE_MAX) \
    X(adapt_scale_step, WC_SHIFT_CAL_ADAPT_SCALE_STEP, 0u, 0.0f, WC_CORRECTION_SCALE_MAX) \
    X(adapt_scale_gain, WC_SHIFT_CAL_ADAPT_SCALE_GAIN, 0u, 0.0f, 1.0f) \
    X(adapt_confidence_gain, WC_SHIFT_CAL_ADAPT_CONFIDENCE_GAIN, 0u, 0.0f, 1.0f) \
    X(adapt_film_factor_min, WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MIN, 0u, 0.01f, 1.0f) \
    X(adapt_film_factor_max, WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MAX, 0u, 1.0f, 1.0f + WC_CORRECTION_FILM_DELTA_MAX) \
    X(adapt_film_step, WC_SHIFT_CAL_ADAPT_FILM_STEP, 0u, 0.0f, 1.0f) \
    X(adapt_film_gain, WC_SHIFT_CAL_ADAPT_FILM_GAIN, 0u, 0.0f, 1.0f) \
    X(adapt_kiss_band_Pa, WC_SHIFT_CAL_ADAPT_KISS_BAND, 0u, 0.0f, WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa) \
    X(adapt_kiss_step_Pa, WC_SHIFT_CAL_ADAPT_KISS_STEP, 0u, 0.0f, WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa) \
    X(adapt_kiss_gain, WC_SHIFT_CAL_ADAPT_KISS_GAIN, 0u, 0.0f, 1.0f) \
    X(adapt_window_skip_s, WC_SHIFT_CAL_ADAPT_WINDOW_SKIP, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(adapt_film_window_s, WC_SHIFT_CAL_ADAPT_FILM_WINDOW, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(adapt_min_slip_drop, WC_SHIFT_CAL_ADAPT_MIN_SLIP_DROP, 0u, 0.0f, 1.0f) \
    X(adapt_min_conditioning, WC_SHIFT_CAL_ADAPT_MIN_CONDITIONING, 0u, 0.0f, 1.0f) \
    X(coordinator, WC_SHIFT_CAL_COORDINATOR, WC_FIELD_INTEGER, 0.0f, 1.0f) \
    X(offgoing_ratio, WC_SHIFT_CAL_OFFGOING_RATIO, WC_FIELD_OR_ZERO, 0.05f, 20.0f) \
    X(fill_pulse_current_mA, WC_SHIFT_CAL_FILL_PULSE_CURRENT, 0u, 0.0f, WC_SHIFT_LIMIT_CURRENT_MAX_mA) \
    X(fill_pulse_time_s, WC_SHIFT_CAL_FILL_PULSE_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(offgoing_holding_factor, WC_SHIFT_CAL_OFFGOING_HOLDING_FACTOR, 0u, 0.0f, 5.0f) \
    X(offgoing_margin_factor, WC_SHIFT_CAL_OFFGOING_MARGIN_FACTOR, 0u, 0.0f, 1.0f) \
    X(offgoing_lag_compensation_time_s, WC_SHIFT_CAL_OFFGOING_LAG_COMPENSATION_TIME, WC_FIELD_OR_ZERO, 1e-3f, \
      WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(flare_kp_Nm_per_rad_s, WC_SHIFT_CAL_FLARE_KP, 0u, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX) \
    X(flare_ki_Nm_per_rad, WC_SHIFT_CAL_FLARE_KI, 0u, 0.0f, WC_SHIFT_LIMIT_GAIN_MAX) \
    X(handover_slip_rad_s, WC_SHIFT_CAL_HANDOVER_SLIP, 0u, 0.0f, WC_SLIP_MAX_rad_s) \
    X(engine_intervention, WC_SHIFT_CAL_ENGINE_INTERVENTION, WC_FIELD_INTEGER, 0.0f, 1.0f) \
    X(engine_increase_max_Nm, WC_SHIFT_CAL_ENGINE_INCREASE_MAX, 0u, 0.0f, WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm) \
    X(engine_reduction_max_Nm, WC_SHIFT_CAL_ENGINE_REDUCTION_MAX, 0u, 0.0f, WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm) \
    X(engine_fill_fraction, WC_SHIFT_CAL_ENGINE_FILL_FRACTION, 0u, 0.0f, 1.0f) \
    X(engine_reduction_fraction, WC_SHIFT_CAL_ENGINE_REDUCTION_FRACTION, 0u, 0.0f, 2.0f) \
    X(engine_recovery_time_s, WC_SHIFT_CAL_ENGINE_RECOVERY_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s) \
    X(engine_lead_time_s, WC_SHIFT_CAL_ENGINE_LEAD_TIME, 0u, 0.0f, 1.0f) \
    X(fallback_time_s, WC_SHIFT_CAL_FALLBACK_TIME, 0u, 0.0f, WC_SHIFT_LIMIT_TIME_MAX_s)

#define WC_SHIFT_RANGE(member, code, flags, low, high) { (low), (high) },
#define WC_SHIFT_FLAGS(member, code, flags, low, high) (uint8_t)(flags),
/* Field i fails with code WC_SHIFT_CAL_TURBINE_INERTIA + i: each field sits at its code's word. */
#define WC_SHIFT_AT_ITS_CODE(member, code, flags, low, high) \
    WC_STATIC_ASSERT(offsetof(wc_shift_calibration_t, member) == 4u * (size_t)((code) - WC_SHIFT_CAL_TURBINE_INERTIA), \
                     shift_##code##_sits_at_its_code);

static const wc_field_range_t field_range[] = { WC_SHIFT_FIELD_RANGES(WC_SHIFT_RANGE) };
static const uint8_t field_flags[] = { WC_SHIFT_FIELD_RANGES(WC_SHIFT_FLAGS) };
static const wc_field_rules_t field_rules = { field_range, field_flags, sizeof field_flags };
WC_SHIFT_FIELD_RANGES(WC_SHIFT_AT_ITS_CODE)
WC_STATIC_ASSERT(WC_ADAPT_NODES == 5u, one_range_per_adaptation_node);
WC_STATIC_ASSERT(sizeof field_flags == (size_t)(WC_SHIFT_CAL_ERRORS - WC_SHIFT_CAL_TURBINE_INERTIA), one_range_per_code);
WC_STATIC_ASSERT(sizeof(wc_shift_calibration_t) == sizeof field_flags * 4u, every_field_has_a_range);

wc_shift_cal_error_t wc_shift_calibration_check(const wc_shift_calibration_t *cal)
{
    if (cal == NULL) { return WC_SHIFT_CAL_NULL; }
    const uint32_t i = wc_field_first_invalid(cal, &field_rules);
    if (i < field_rules.count) { return (wc_shift_cal_error_t)((uint32_t)WC_SHIFT_CAL_TURBINE_INERTIA + i); }
    /* DESIGN 14, 15: the two gears differ (the gear step 1 - b / b1 divides; a downshift's b1 is below b) */
    if ((cal->coordinator == 1u) && (!(cal->offgoing_ratio > 0.0f) || /* off (0) is no ratio for the coordinator */
                                     !(fabsf(cal->offgoing_ratio - cal->output_ratio) >= WC_SHIFT_GEAR_STEP_MIN * cal->output_ratio))) {
        return WC_SHIFT_CAL_OFFGOING_RATIO;
    }
    if (cal->fill_pulse_time_s > cal->prepare_time_s) { return WC_SHIFT_CAL_FILL_PULSE_TIME; }
    return WC_SHIFT_CAL_OK;
}

void wc_shift_init(wc_shift_t *shift)
{
    WC_ASSERT(shift != NULL);
    if (shift == NULL) { return; }
    (void)memset(shift, 0, sizeof *shift);  /* all zero: IDLE, no report, no fallback (IEEE 754 zeros) */
}

float wc_shift_reference_slip(float start_slip_rad_s, float target_time_s, float elapsed_s, float *rate_rad_s2)
{
    return wc_shift_reference_at(start_slip_rad_s, target_time_s, elapsed_s, rate_rad_s2);
}

/* The driveline model's terms of the feed-forward (DESIGN 10), once per
 * step for both of its uses (the inertia phase's feed-forward and the torque
 * the clutch carries once synchronous). */
typedef struct {
    float drive_rad_s2;          /* a T_t / I_t */
    float inverse_inertia;       /* a^2 / I_t + b^2 / I_out, 1 / (kg m^2) */
} wc_driveline_t;

static wc_driveline_t driveline(const wc_shift_calibration_t *cal, float turbine_torque_Nm)
{
    /* DESIGN 10: T_ff = (a T_t / I_t + b T_s / I_o - dref/dt) / (a^2 / I_t + b^2 / I_o),
     * stiff driveshaft: I_o -> I_out (output shaft + vehicle), T_s -> road load ~ 0 */
    const float a = cal->turbine_ratio;
    const float b = cal->output_ratio;
    const float i_t = cal->turbine_inertia_kg_m2;
    const wc_driveline_t d = { a * turbine_torque_Nm / i_t, a * a / i_t + b * b / cal->output_inertia_kg_m2 };
    return d;
}

static float feedforward_Nm(const wc_driveline_t *d, float reference_rate_rad_s2)
{
    return wc_shift_clamp_torque_Nm((d->drive_rad_s2 - reference_rate_rad_s2) / d->inverse_inertia);
}

float wc_shift_feedforward_Nm(const wc_shift_calibration_t *cal, float turbine_torque_Nm, float reference_rate_rad_s2)
{
    const wc_driveline_t d = driveline(cal, turbine_torque_Nm);
    return feedforward_Nm(&d, reference_rate_rad_s2);
}

/* The whole shift (DESIGN 14) runs when the calibration asks for it and the
 * caller gave the off-going clutch. */
static bool coordinated(const wc_shift_calibration_t *cal, const wc_shift_offgoing_t *offgoing)
{
    return (cal->coordinator == 1u) && (offgoing != NULL) && (offgoing->clutch != NULL) && (offgoing->in != NULL) &&
           (offgoing->out != NULL);
}

static void start(wc_shift_t *shift, const wc_shift_command_t *command, float slip_rad_s,
                  const wc_lag_compensation_t *lag, const wc_lag_compensation_t *offgoing_lag, wc_adapt_t *adapt)
{
    const float last_slip_rad_s = shift->last_slip_rad_s;  /* the slip's rate goes on across the start */
    const float slip_rate_rad_s2 = shift->slip_rate_rad_s2;
    wc_shift_init(shift);
    shift->last_slip_rad_s = last_slip_rad_s;
    shift->slip_rate_rad_s2 = slip_rate_rad_s2;
    wc_adapt_begin(adapt);  /* a new window (NULL: none) */
    shift->lag_compensation = *lag;  /* its exponential once per shift, not per step */
    shift->offgoing_lag = *offgoing_lag;
    shift->last_request = true;
    shift->turbine_torque_Nm = command->turbine_torque_Nm;
    shift->driver_torque_Nm = command->turbine_torque_Nm;  /* T_t0: before any intervention (DESIGN 14) */
    shift->target_time_s = command->target_inertia_time_s;
    shift->start_slip_rad_s = slip_rad_s;
    shift->report.peak_theta_degC = WC_THETA_MIN_degC;
    wc_shift_enter(shift, WC_SHIFT_PREPARE);
}

/* The turbine torque that goes through the clutches in 1st gear (DESIGN 14):
 * the turbine accelerates with the vehicle, dslip/dt = (1 - b / b1) dw_t/dt
 * (a = 1), and I_t dw_t/dt of T_t goes into that, not through the clutches.
 * The on-coming clutch takes over this much (more pulls against the
 * off-going one: tie-up), and the off-going one carries what is left of it. */
static float through_Nm(const wc_shift_t *shift, const wc_shift_calibration_t *cal)
{
    /* |.| >= 1 % (checked with the coordinator); < 0 in a coast downshift's mirror (wc_transmission.h) */
    const float gear_step = 1.0f - cal->output_ratio / cal->offgoing_ratio;
    return wc_shift_clamp_torque_Nm(shift->turbine_torque_Nm - cal->turbine_inertia_kg_m2 * shift->slip_rate_rad_s2 / gear_step);
}

/* DESIGN 14, 15: the model's error the slip PI found: its integral beyond the share the feed-forward
 * leaves to it ((1 - gain) T_t / a: all of it on feedback alone), never below 0. The lock-up ramps to the
 * holding margin plus this: the margin does not cover a model error (a cold pack whose friction the model
 * overrates held the 8-speed's 6->7 at 20 degC short of lock-up: AbortReason 2). */
static float model_error_Nm(const wc_shift_t *shift, const wc_shift_calibration_t *cal, float share_Nm)
{
    const float excess_Nm = shift->integral_Nm - (1.0f - cal->feedforward_gain) * share_Nm;
    return (excess_Nm > 0.0f) ? excess_Nm : 0.0f;
}

/* The flare (DESIGN 14): the off-going clutch slipping forward, the turbine above the 1st-gear speed. */
static float flare_slip_rad_s(const wc_shift_t *shift)
{
    return (shift->offgoing_slip_rad_s > 0.0f) ? shift->offgoing_slip_rad_s : 0.0f;
}

/* The whole shift's torque phase (DESIGN 14): the on-coming clutch's share
 * of the turbine torque, a smoothstep over torque_phase_time_s (zero slope at
 * both ends: the off-going clutch's lagging release is not left behind at the
 * hand-over, and the output torque does not kink), lead_s ahead. */
static float torque_phase_share(const wc_shift_t *shift, const wc_shift_calibration_t *cal, float dt_s, float lead_s)
{
    const float t_s = (float)(shift->phase_periods + 1u) * dt_s + lead_s;
    const float x = (cal->torque_phase_time_s > 0.0f) ? (t_s / cal->torque_phase_time_s) : 1.0f;
    const float xc = (x < 1.0f) ? x : 1.0f;
    return xc * xc * (3.0f - 2.0f * xc);
}

/* The torque request of this period (the phase's law); may change the phase.
 * d: the driveline terms of this step, carried_Nm the feed-forward at a zero
 * slip rate. coord: the whole shift (DESIGN 14). */
static float phase_request_Nm(wc_shift_t *shift, const wc_shift_calibration_t *cal, float slip_rad_s,
                              float dt_s, bool saturated, const wc_driveline_t *d, float carried_Nm, bool coord)
{
    const float share_Nm = shift->turbine_torque_Nm / cal->turbine_ratio;  /* T_t / a */
    if (shift->phase == (uint32_t)WC_SHIFT_PREPARE) {
        if (shift->phase_periods < wc_shift_periods_of(cal->prepare_time_s, dt_s)) { return 0.0f; }
        wc_shift_enter(shift, WC_SHIFT_TORQUE);
    }
    if (shift->phase == (uint32_t)WC_SHIFT_TORQUE) {
        const uint32_t n = wc_shift_periods_of(cal->torque_phase_time_s, dt_s);
        /* DESIGN 14: the off-going clutch slips backwards, so the on-coming clutch holds the turbine (the
         * speeds show the tie-up): the torque phase is over, the off-going clutch is released */
        const bool handed_over = coord && (shift->offgoing_slip_rad_s < -cal->handover_slip_rad_s);
        if ((shift->phase_periods < n) && !handed_over) {
            if (!coord) { return share_Nm * (float)(shift->phase_periods + 1u) / (float)n; }
            /* a flare (the off-going clutch slips forward) is also taken by the on-coming clutch, which takes
             * the torque over anyway and follows faster than the off-going one's falling pressure */
            const float flare_rad_s = flare_slip_rad_s(shift);
            return share_Nm * torque_phase_share(shift, cal, dt_s, 0.0f) +
                   cal->flare_kp_Nm_per_rad_s * flare_rad_s + shift->flare_integral_Nm;
        }
        /* inertia phase: the reference starts at the measured slip; bumpless:
         * the integral takes what the feed-forward does not give of the last request */
        wc_shift_enter(shift, WC_SHIFT_INERTIA);
        shift->second_gear = coord;
        shift->start_slip_rad_s = slip_rad_s;
        shift->integral_Nm = shift->request_Nm - cal->feedforward_gain * carried_Nm;
        if (!(slip_rad_s > cal->min_start_slip_rad_s)) {
            wc_shift_abort(shift, WC_SHIFT_ABORT_NO_SLIP);
            return 0.0f;
        }
    }
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) {
        float rate_rad_s2;
        const float elapsed_s = (float)shift->phase_periods * dt_s;
        const float reference = wc_shift_reference_at(shift->start_slip_rad_s, shift->target_time_s, elapsed_s, &rate_rad_s2);
        const float ff_Nm = cal->feedforward_gain * feedforward_Nm(d, rate_rad_s2);
        if (shift->fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE) {
            /* DESIGN 14: the slip is not known: the feed-forward on the reference, the integral frozen */
            return ff_Nm + shift->integral_Nm;
        }
        const float error = slip_rad_s - reference;  /* slip above the reference: more torque */
        shift->error_sq_sum += error * error;
        shift->inertia_periods++;
        /* anti-windup: no integration further into a saturated request */
        const bool blocked = (saturated && (error > 0.0f)) || ((shift->request_Nm <= 0.0f) && (error < 0.0f));
        if (!blocked) { wc_shift_integrate(shift, cal, cal->ki_Nm_per_rad * error * dt_s); }
        if (slip_rad_s > shift->start_slip_rad_s + cal->flare_slip_rad_s) { shift->report.flare = true; }
        if ((slip_rad_s >= shift->start_slip_rad_s) && (shift->request_Nm > cal->tie_up_factor * share_Nm)) {
            shift->report.tie_up = true;  /* the turbine does not move although the clutch pulls hard: something holds it */
        }
        return ff_Nm + cal->kp_Nm_per_rad_s * error + shift->integral_Nm;
    }
    /* DESIGN 14: the hold covers the driver's torque while the engine's reduction ramps out */
    const float hold_share_Nm = (coord && (shift->driver_torque_Nm > shift->turbine_torque_Nm))
                                    ? (shift->driver_torque_Nm / cal->turbine_ratio) : share_Nm;
    if (shift->phase == (uint32_t)WC_SHIFT_LOCKUP) {
        const uint32_t n = wc_shift_periods_of(cal->lockup_ramp_time_s, dt_s);
        /* DESIGN 15: on the whole shift the lock-up is not open loop: the PI goes on, and the ramp carries
         * the model's error it found (the anti-windup as in the inertia phase) */
        if (coord && (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE) && !(saturated && (slip_rad_s > 0.0f))) {
            wc_shift_integrate(shift, cal, cal->ki_Nm_per_rad * slip_rad_s * dt_s);  /* the slip left: the error on a zero reference */
        }
        const float hold_Nm = cal->holding_torque_factor * hold_share_Nm + (coord ? model_error_Nm(shift, cal, share_Nm) : 0.0f);
        const float x = (n > 0u) ? ((float)(shift->phase_periods + 1u) / (float)n) : 1.0f;
        return shift->phase_start_request_Nm + (hold_Nm - shift->phase_start_request_Nm) * ((x < 1.0f) ? x : 1.0f);
    }
    /* LOCKED: hold */
    return cal->holding_torque_factor * hold_share_Nm;
}

/* A lost input (the loop's safe state) with the coordinator (DESIGN 14): the
 * fallback of the phase, the engine request withdrawn (engine_request). */
static void fall_back(wc_shift_t *shift, const wc_shift_calibration_t *cal, float dt_s)
{
    if (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE) {
        if (!shift->second_gear) {
            /* the off-going clutch still has the gear (the torque-first shift's prepare and torque phases, the
             * inertia-first one's prepare and inertia phases): hand it back */
            wc_shift_set_fallback(shift, WC_SHIFT_FALLBACK_HANDBACK);
            wc_shift_abort(shift, WC_SHIFT_ABORT_INPUT_LOST);
            return;
        }
        wc_shift_set_fallback(shift, WC_SHIFT_FALLBACK_FINISH);  /* inertia phase or later: finish on the model */
    }
    if ((float)shift->fallback_periods * dt_s > cal->fallback_time_s) {
        wc_shift_set_fallback(shift, WC_SHIFT_FALLBACK_RELEASED);  /* neither possible: released */
        if (wc_shift_phase_running(shift->phase)) {
            wc_shift_abort(shift, WC_SHIFT_ABORT_INPUT_LOST);
        } else {
            wc_shift_enter(shift, WC_SHIFT_IDLE);  /* LOCKED: released; the off-going clutch stays open (second gear) */
        }
    }
}

/* The input back after a finish on the model (DESIGN 14; issue 29 item 7:
 * the finish looked at the model only and reported a slipping clutch
 * locked): the shift looks at the slip again. In the inertia phase the
 * feedback resumes on a reference restarted at the measured slip (bumpless,
 * as at the phase's start; the report's inertia time counts from the
 * restart); in the hand-over the ramp restarts from the present request and
 * the lock-up decides as without a fault (locked, or AbortReason 2). The
 * report keeps the fallback; the adaptation's window restarts (the fault's
 * gap is no sample). A LOCKED shift (locked before the fault) holds. */
static void resume(wc_shift_t *shift, const wc_shift_calibration_t *cal, float slip_rad_s, wc_adapt_t *adapt)
{
    shift->fallback = (uint32_t)WC_SHIFT_FALLBACK_NONE;
    shift->fallback_periods = 0u;
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) {
        const wc_driveline_t d = driveline(cal, shift->turbine_torque_Nm);
        wc_shift_enter(shift, WC_SHIFT_INERTIA);
        shift->start_slip_rad_s = slip_rad_s;
        shift->band_periods = 0u;
        shift->integral_Nm = shift->request_Nm - cal->feedforward_gain * feedforward_Nm(&d, 0.0f);
        wc_adapt_begin(adapt);
    } else if (shift->phase == (uint32_t)WC_SHIFT_LOCKUP) {
        wc_shift_enter(shift, WC_SHIFT_LOCKUP);
        shift->phase_start_request_Nm = shift->request_Nm;
        wc_adapt_begin(adapt);
    } else {
        /* LOCKED: holds */
    }
}

void wc_shift_transitions(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                                      bool safe, bool coord, float torque_min_Nm, float slip_rad_s, float dt_s,
                                      const wc_clutch_t *clutch, wc_adapt_t *adapt, const wc_shift_offgoing_t *offgoing)
{
    const bool edge = command->request && !shift->last_request;
    shift->last_request = command->request;

    /* Transitions on the command and the loop's state. */
    if (coord && safe && (wc_shift_phase_running(shift->phase) || (shift->phase == (uint32_t)WC_SHIFT_LOCKED))) {
        fall_back(shift, cal, dt_s);  /* DESIGN 14: not released at once */
    } else if (safe || !command->request) {
        if (wc_shift_phase_running(shift->phase)) {
            wc_shift_abort(shift, safe ? WC_SHIFT_ABORT_INPUT_LOST : WC_SHIFT_ABORT_CANCELLED);
        } else if (!command->request || (shift->phase == (uint32_t)WC_SHIFT_LOCKED)) {
            wc_shift_enter(shift, WC_SHIFT_IDLE);  /* the safe state releases a completed shift's clutch too */
            if (!safe) { shift->second_gear = false; }  /* withdrawn: the VCU takes 1st gear back (DESIGN 14) */
        }
    } else if (edge && (shift->phase == (uint32_t)WC_SHIFT_IDLE)) {
        if (wc_shift_command_valid(cal, command, torque_min_Nm)) {
            const wc_lag_compensation_t lag = wc_lag_compensation(clutch, cal->lag_compensation_time_s);
            const wc_lag_compensation_t off = coord ? wc_lag_compensation(offgoing->clutch,
                                                                          cal->offgoing_lag_compensation_time_s)
                                                    : shift->offgoing_lag;
            start(shift, command, slip_rad_s, &lag, &off, adapt);
        } else {  /* nothing of the command is kept (it may hold NaN) */
            wc_shift_init(shift);
            shift->last_request = true;
            wc_shift_abort(shift, WC_SHIFT_ABORT_INVALID_COMMAND);
        }
    }
    if (!safe && (shift->phase == (uint32_t)WC_SHIFT_IDLE)) {
        shift->fallback = (uint32_t)WC_SHIFT_FALLBACK_NONE;  /* over with the fault (the report keeps it) */
    }
    const bool resumed = coord && !safe && (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_FINISH);
    const bool follow = wc_shift_phase_running(shift->phase) || (coord && (shift->phase == (uint32_t)WC_SHIFT_IDLE));
    if (coord && (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_FINISH) && !resumed) {
        /* DESIGN 14: the fallback withdrew the engine request: the driver's torque T_t0, not the last
         * estimate, which may still hold the reduction (issue 29 item 7) */
        shift->turbine_torque_Nm = shift->driver_torque_Nm;
    } else if (follow && wc_shift_in_closed(command->turbine_torque_Nm, torque_min_Nm, WC_TORQUE_MAX_Nm)) {
        shift->turbine_torque_Nm = command->turbine_torque_Nm;  /* follow the engine's estimate */
    }
    if (resumed) { resume(shift, cal, slip_rad_s, adapt); }
}

/* Before the clutch step: the transitions on the command and the loop's
 * state, then the clutch input (in place: mode, request, carried torque, lag
 * compensation, temperature source). saturated: the last step's output was. */
static WC_NOINLINE void shift_before(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                         bool safe, bool saturated, float viscous_Nm, float slip_rad_s, float dt_s, const wc_clutch_t *clutch,
                         wc_adapt_t *adapt, wc_step_input_t *in, const wc_shift_offgoing_t *offgoing)
{
    const bool coord = coordinated(cal, offgoing);
    wc_shift_transitions(shift, cal, command, safe, coord, 0.0f, slip_rad_s, dt_s, clutch, adapt, offgoing);

    in->mode = WC_MODE_OPEN;
    in->torque_request_Nm = 0.0f;
    in->carried_torque_Nm = 0.0f;
    in->lag_compensation = shift->lag_compensation;
    in->theta_from_oil = (cal->theta_source == (uint32_t)WC_SHIFT_THETA_OIL);
    in->band_release = false;
    const wc_model_correction_t none = { 0.0f, 0.0f, 0.0f };
    in->correction = none;
    if (wc_shift_phase_running(shift->phase) || (shift->phase == (uint32_t)WC_SHIFT_LOCKED)) {
        if (cal->adaptation == 1u) {
            /* DESIGN 12: the learned values at the temperature the model uses this step */
            const float theta_degC = in->theta_from_oil ? (wc_theta_valid(in->theta_oil_degC) ? in->theta_oil_degC
                                                                                               : clutch->held.theta_oil_degC)
                                                        : clutch->theta_degC;
            in->correction = wc_adapt_correction(adapt, cal, clutch, theta_degC);
        }
        const wc_driveline_t d = driveline(cal, shift->turbine_torque_Nm);
        /* once synchronous the clutch carries what the driveline model says
         * (the feed-forward at a zero slip rate), not the request */
        const float carried_Nm = feedforward_Nm(&d, 0.0f);
        /* DESIGN 15: the lock-up closes the slip to hold by static friction, and the modelled viscous drag at
         * the slip left vanishes as it closes: the inverse (at the measured slip) is asked for it on top (the
         * last step's model), or a cold pack whose drag the model overrates stays at its kiss point (8-speed
         * 6->7 at 20 degC: the model's drag at the kiss point met the ramp's request, the slip never closed:
         * AbortReason 2). A drag beyond the torque range (NaN included) adds nothing. */
        const bool drag_valid = fabsf(viscous_Nm) <= WC_TORQUE_MAX_Nm;
        const float drag_Nm = (coord && (shift->phase == (uint32_t)WC_SHIFT_LOCKUP) && drag_valid) ? fabsf(viscous_Nm) : 0.0f;
        const float request_Nm = wc_shift_clamp_torque_Nm(phase_request_Nm(shift, cal, slip_rad_s, dt_s, saturated, &d, carried_Nm,
                                                                  coord) + drag_Nm);
        if (shift->phase != (uint32_t)WC_SHIFT_ABORTED) {
            in->mode = WC_MODE_TORQUE;
            in->torque_request_Nm = request_Nm;
            shift->request_Nm = request_Nm;
            in->carried_torque_Nm = carried_Nm;
            /* DESIGN 15: in the torque and inertia phases of the whole shift the on-coming element may release
             * below its kiss point too: at a light load or a skip shift's slip its drag there exceeds the
             * request, and held there it stalled the inertia phase (8-speed 6->7 at 25 % load: lock-up failed) */
            in->band_release = coord && (shift->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE) &&
                               ((shift->phase == (uint32_t)WC_SHIFT_TORQUE) || (shift->phase == (uint32_t)WC_SHIFT_INERTIA));
        }
    }
}

/* The engine's torque request of this step (DESIGN 14): torque phase, an
 * increase with the on-coming clutch's ramp that fills part of the torque
 * hole (b1 - b) / b * T_t0; inertia phase, the increase fades with the
 * reference while a reduction of engine_reduction_fraction times the
 * turbine's inertia torque I_t |dref/dt| / a takes the inertia torque out of
 * the clutch (1: the output torque does not hump and does not step at
 * lock-up; more: less friction energy); after the inertia phase what is left
 * ramps out in engine_recovery_time_s. 0 and inactive otherwise, and from a
 * fallback to the shift's end. */
static WC_NOINLINE void engine_request(wc_shift_t *shift, const wc_shift_calibration_t *cal, float dt_s, wc_shift_offgoing_t *og)
{
    float delta_Nm = 0.0f;
    /* a fallback withdraws the request for the rest of the shift (no step back in when the input returns) */
    bool active = (cal->engine_intervention == 1u) && (shift->report.fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE);
    const float t0_Nm = shift->driver_torque_Nm;
    const float hole_Nm = cal->engine_fill_fraction * (cal->offgoing_ratio - cal->output_ratio) / cal->output_ratio * t0_Nm;
    /* a downshift's b1 < b: the torque phase raises the output torque; a negative "increase" lowers it */
    const float max_Nm = cal->engine_increase_max_Nm;
    const float increase_Nm = (hole_Nm < max_Nm) ? ((hole_Nm > -max_Nm) ? hole_Nm : -max_Nm) : max_Nm;
    const uint32_t phase = shift->phase;
    if (phase == (uint32_t)WC_SHIFT_TORQUE) {
        delta_Nm = increase_Nm * torque_phase_share(shift, cal, dt_s, cal->engine_lead_time_s);
        shift->recovery_periods = 0u;
    } else if (phase == (uint32_t)WC_SHIFT_INERTIA) {
        float rate_rad_s2;
        const float elapsed_s = (float)shift->phase_periods * dt_s + cal->engine_lead_time_s;
        const float reference = wc_shift_reference_at(shift->start_slip_rad_s, shift->target_time_s, elapsed_s, &rate_rad_s2);
        const float s = (shift->start_slip_rad_s > 0.0f) ? (1.0f - reference / shift->start_slip_rad_s) : 1.0f;
        const float inertia_Nm = cal->engine_reduction_fraction * cal->turbine_inertia_kg_m2 * fabsf(rate_rad_s2) /
                                 cal->turbine_ratio;
        const float reduction_Nm = (inertia_Nm < cal->engine_reduction_max_Nm) ? inertia_Nm : cal->engine_reduction_max_Nm;
        delta_Nm = increase_Nm * (1.0f - s) - reduction_Nm;
        /* DESIGN 14: at most down to the engine's zero torque: at a light load the inertia torque exceeds T_t0
         * (8-speed 6->7 at 25 %: 149 of 62 N m), the engine was driven into its drag and the on-coming element's
         * request fell below its drag at the kiss point: the inertia phase stalled (lock-up failed) */
        if (delta_Nm < -t0_Nm) { delta_Nm = -t0_Nm; }  /* T_t0 >= 0: the command's check */
        shift->engine_from_Nm = delta_Nm;
        shift->recovery_periods = 0u;
    } else if ((phase == (uint32_t)WC_SHIFT_LOCKUP) || (phase == (uint32_t)WC_SHIFT_LOCKED)) {
        const float t_s = (float)shift->recovery_periods * dt_s;
        const float y = (cal->engine_recovery_time_s > 0.0f) ? (t_s / cal->engine_recovery_time_s) : 1.0f;
        active = active && (y < 1.0f);
        delta_Nm = shift->engine_from_Nm * (1.0f - ((y < 1.0f) ? y : 1.0f));
        shift->recovery_periods = (shift->recovery_periods < UINT32_MAX) ? (shift->recovery_periods + 1u) : UINT32_MAX;
    } else {
        active = false;
    }
    og->engine_active = active;
    og->engine_delta_Nm = active ? delta_Nm : 0.0f;
}

/* The off-going clutch's input (DESIGN 14; wc_shift_step steps it): it holds 1st gear at
 * offgoing_holding_factor * T_t until the torque phase; there its request is
 * the torque it still carries, T_t - a T_c (T_c the on-coming model's torque
 * of this step), plus offgoing_margin_factor * T_t0 and the flare correction
 * (PI on the off-going slip above 0: the turbine runs up); released from the
 * inertia phase on (second gear). A hand-back (an abort before the inertia
 * phase) and IDLE in the safe state hold it at the maximum current. */
static WC_NOINLINE void offgoing_input(wc_shift_t *shift, const wc_shift_calibration_t *cal, bool safe, float oncoming_torque_Nm,
                          float dt_s, wc_shift_offgoing_t *og)
{
    wc_step_input_t *in = og->in;
    const uint32_t phase = shift->phase;
    const float t_t_Nm = shift->turbine_torque_Nm;
    in->mode = WC_MODE_OPEN;
    in->torque_request_Nm = 0.0f;
    in->carried_torque_Nm = 0.0f;
    in->lag_compensation = shift->offgoing_lag;
    in->theta_from_oil = false;
    in->band_release = false;
    const wc_model_correction_t none = { 0.0f, 0.0f, 0.0f };
    in->correction = none;
    bool handing_over = false;
    if (!shift->second_gear) {
        if (safe || (phase == (uint32_t)WC_SHIFT_ABORTED)) {
            in->mode = WC_MODE_LOCKED;  /* hold the gear without inputs (hand-back) */
        } else if ((phase == (uint32_t)WC_SHIFT_IDLE) || (phase == (uint32_t)WC_SHIFT_PREPARE)) {
            in->mode = WC_MODE_TORQUE;
            in->torque_request_Nm = wc_shift_clamp_torque_Nm(cal->offgoing_holding_factor * t_t_Nm);
            in->carried_torque_Nm = wc_shift_clamp_torque_Nm(t_t_Nm);
        } else if (phase == (uint32_t)WC_SHIFT_TORQUE) {
            handing_over = true;
        } else {
            /* INERTIA .. LOCKED without second gear: cannot happen (set on entering INERTIA); open */
        }
    } else if ((phase == (uint32_t)WC_SHIFT_INERTIA) && !shift->offgoing_released) {
        /* the hand-over's end: the off-going clutch slips backwards (the on-coming one holds the turbine);
         * a lost input ends it at once (the fallback releases it: its slip is not known) */
        shift->offgoing_released = safe || (shift->fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE) ||
                                   (shift->offgoing_slip_rad_s < -cal->handover_slip_rad_s) ||
                                   ((float)shift->phase_periods * dt_s >= WC_SHIFT_HANDOVER_MAX_s);
        handing_over = !shift->offgoing_released;
    } else {
        /* second gear: open */
    }
    if (handing_over) {
        const float carried_Nm = wc_shift_clamp_torque_Nm(through_Nm(shift, cal) - cal->turbine_ratio * oncoming_torque_Nm);
        const float flare_rad_s = flare_slip_rad_s(shift);
        const float integral_Nm = shift->flare_integral_Nm + cal->flare_ki_Nm_per_rad * flare_rad_s * dt_s;
        shift->flare_integral_Nm = (integral_Nm < t_t_Nm) ? integral_Nm : t_t_Nm;  /* anti-windup: T_t */
        if (flare_rad_s > cal->flare_slip_rad_s) { shift->report.flare = true; }
        in->mode = WC_MODE_TORQUE;
        /* the margin tapers with the on-coming clutch's ramp: at the hand-over the off-going clutch
         * holds nothing the on-coming one could fight (tie-up) */
        const float taper = (phase == (uint32_t)WC_SHIFT_TORQUE) ? (1.0f - torque_phase_share(shift, cal, dt_s, 0.0f)) : 0.0f;
        in->torque_request_Nm = wc_shift_clamp_torque_Nm(carried_Nm + cal->offgoing_margin_factor * shift->driver_torque_Nm * taper +
                                                cal->flare_kp_Nm_per_rad_s * flare_rad_s + shift->flare_integral_Nm);
        in->carried_torque_Nm = carried_Nm;
    }
}

/* The inertia phase's end, after the step (both controllers, DESIGN 10):
 * true when it is over (the slip in the lock band for the dwell, the model
 * locked, or the reference ended near synchronism), report.inertia_time_s
 * set; an overrun aborts (AbortReason 1). locked: the controlled clutch's
 * model locked this step. */
bool wc_shift_inertia_over(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_clutch_t *clutch, bool locked,
                           float slip_rad_s, float dt_s)
{
    const bool fallback = shift->fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE;
    const float elapsed_s = (float)(shift->phase_periods + 1u) * dt_s;
    const wc_calibration_t *clutch_cal = clutch->model.cal;
    const bool in_band = (clutch_cal != NULL) && (fabsf(slip_rad_s) < clutch_cal->lock_slip_rad_s);
    shift->band_periods = in_band ? (shift->band_periods + 1u) : 0u;  /* bounded: the phase times out */
    const bool synchronous = (clutch_cal != NULL) && (shift->band_periods >= clutch_cal->lock_dwell_periods);
    /* the reference has ended near synchronism: the last slip (the clutch's
     * torque falls with it, and its static capacity is below the kinetic
     * torque there) is pulled in by the hand-over's force, not left to the
     * integral; far from it the inertia phase goes on (and may time out) */
    const bool reference_ended = (elapsed_s >= shift->target_time_s) &&
                                 (fallback || (fabsf(slip_rad_s) <= cal->min_start_slip_rad_s));
    if ((!fallback && (locked || synchronous)) || reference_ended) {
        shift->report.inertia_time_s = elapsed_s;
        return true;
    }
    if (elapsed_s > shift->target_time_s * cal->inertia_timeout_factor) {
        shift->report.inertia_time_s = elapsed_s;
        wc_shift_abort(shift, WC_SHIFT_ABORT_INERTIA_TIMEOUT);
    }
    return false;
}

/* The quality vector's period (both controllers, DESIGN 10): from the
 * command to the shift's end the friction heat heat_W (eq. 1's input), the
 * peak temperature, the jerk of output_torque_Nm (not on the first sample);
 * the phase's period count (a phase entered after the step counts from the
 * next); true when the shift ended this step (LOCKED or ABORTED entered),
 * then the slip RMSE is final. */
bool wc_shift_account(wc_shift_t *shift, const wc_shift_calibration_t *cal, uint32_t phase_before, uint32_t phase_stepped,
                      float heat_W, float theta_degC, float output_torque_Nm, float dt_s)
{
    if (wc_shift_phase_running(phase_before) || wc_shift_phase_running(shift->phase)) {
        wc_shift_report_t *q = &shift->report;
        q->friction_energy_J += heat_W * dt_s;
        if (theta_degC > q->peak_theta_degC) { q->peak_theta_degC = theta_degC; }
        const float jerk = wc_shift_jerk(cal, &shift->filtered_torque_Nm, output_torque_Nm, dt_s);
        if (wc_shift_phase_running(phase_before) && (jerk > q->peak_jerk_m_s3)) { q->peak_jerk_m_s3 = jerk; }
    }
    if (shift->phase == phase_stepped) {
        shift->phase_periods = (shift->phase_periods < UINT32_MAX) ? (shift->phase_periods + 1u) : UINT32_MAX;
    }
    const bool ended = (phase_before != shift->phase) &&
                       ((shift->phase == (uint32_t)WC_SHIFT_LOCKED) || (shift->phase == (uint32_t)WC_SHIFT_ABORTED));
    if (ended) {
        shift->report.slip_rmse_rad_s = (shift->inertia_periods > 0u)
                                            ? sqrtf(shift->error_sq_sum / (float)shift->inertia_periods) : 0.0f;
    }
    return ended;
}

/* After the clutch step: the lock-up decides the inertia phase's end, the
 * quality vector, the report. Returns true when the shift ended. */
static WC_NOINLINE bool shift_after(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_clutch_t *clutch,
                        wc_adapt_t *adapt, const wc_step_output_t *out, wc_shift_report_t *report,
                        uint32_t phase_before, float slip_rad_s, float dt_s)
{
    const uint32_t phase_stepped = shift->phase;
    const bool locked = (out->status & WC_STATUS_LOCKED) != 0u;
    const bool fallback = shift->fallback != (uint32_t)WC_SHIFT_FALLBACK_NONE;
    if ((shift->phase == (uint32_t)WC_SHIFT_INERTIA) && (cal->adaptation == 1u) && !fallback) {
        /* DESIGN 12: the window's sample of this period (its torque against the slip's change) */
        const wc_driveline_t d = driveline(cal, shift->turbine_torque_Nm);
        wc_adapt_sample(adapt, cal, (float)shift->phase_periods * dt_s, slip_rad_s, d.drive_rad_s2,
                        d.inverse_inertia, clutch, out);
    }
    if ((shift->phase == (uint32_t)WC_SHIFT_INERTIA) && wc_shift_inertia_over(shift, cal, clutch, locked, slip_rad_s, dt_s)) {
        shift->phase_start_request_Nm = shift->request_Nm;
        wc_shift_enter(shift, WC_SHIFT_LOCKUP);
    } else if (shift->phase == (uint32_t)WC_SHIFT_LOCKUP) {
        wc_shift_handover_end(shift, locked, wc_shift_periods_of(cal->lockup_ramp_time_s, dt_s));
    }

    const bool ended = wc_shift_account(shift, cal, phase_before, phase_stepped, fabsf(out->model.torque_Nm * slip_rad_s),
                                        clutch->theta_degC, out->model.torque_Nm, dt_s);
    if (ended) {
        /* DESIGN 12: learn from the shift (only a valid one changes anything) */
        shift->report.adaptation = wc_adapt_finish(adapt, cal, shift->report.abort_reason, clutch);
        *report = shift->report;
    }
    return ended;
}

/* The fill pulse (DESIGN 14): in the prepare phase's first fill_pulse_time_s
 * the VFS gets fill_pulse_current_mA to stroke the piston fast; the model
 * steps at the kiss point meanwhile (request 0), which is what the chamber
 * holds while the piston strokes against its spring. */
WC_NOINLINE void wc_shift_fill_pulse(const wc_shift_calibration_t *cal, const wc_clutch_t *clutch, bool filling,
                                     uint32_t fill_periods, float dt_s, wc_step_output_t *out)
{
    const wc_calibration_t *c = clutch->model.cal;
    if ((c == NULL) || !filling || (fill_periods >= wc_shift_periods_of(cal->fill_pulse_time_s, dt_s)) ||
        (cal->fill_pulse_time_s <= 0.0f)) {
        return;
    }
    const float i = cal->fill_pulse_current_mA;
    const float i_mA = (i < c->vfs_current_min_mA) ? c->vfs_current_min_mA : ((i > c->vfs_current_max_mA) ? c->vfs_current_max_mA : i);
    if (i_mA > out->current_mA) {
        out->current_mA = i_mA;
        out->pressure_command_Pa = c->vfs_gain_Pa_per_mA * i_mA;
    }
}

bool wc_shift_step(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                   bool safe, wc_clutch_t *clutch, wc_adapt_t *adapt, wc_step_input_t *in, wc_step_output_t *out,
                   wc_shift_report_t *report, wc_shift_offgoing_t *offgoing)
{
    WC_ASSERT((shift != NULL) && (cal != NULL) && (command != NULL) && (clutch != NULL) && (in != NULL) &&
              (out != NULL) && (report != NULL));
    if ((shift == NULL) || (cal == NULL) || (command == NULL) || (clutch == NULL) || (in == NULL) ||
        (out == NULL) || (report == NULL)) {
        return false;
    }
    const bool coord = coordinated(cal, offgoing);
    const uint32_t phase_before = shift->phase;
    const float dt_s = (clutch->model.cal != NULL) ? clutch->model.cal->control_period_s : 1e-3f;  /* init failed: any */
    /* the measured slip, or while it is invalid the clutch's last valid one */
    const float slip_rad_s = wc_slip_valid(in->slip_rad_s) ? in->slip_rad_s : clutch->held.slip_rad_s;
    const bool saturated = (out->status & WC_STATUS_SATURATED) != 0u;  /* last step's output */
    if (coord) {
        const float s = offgoing->in->slip_rad_s;
        shift->offgoing_slip_rad_s = wc_slip_valid(s) ? s : offgoing->clutch->held.slip_rad_s;
        /* the slip's rate, first-order filtered (DESIGN 14: the turbine's acceleration in 1st gear) */
        const float alpha = dt_s / (cal->jerk_filter_time_s + dt_s);
        const float rate = (slip_rad_s - shift->last_slip_rad_s) / dt_s;
        shift->slip_rate_rad_s2 += (rate - shift->slip_rate_rad_s2) * alpha;
        shift->last_slip_rad_s = slip_rad_s;
        if (safe) {
            shift->fallback_periods = (shift->fallback_periods < UINT32_MAX) ? (shift->fallback_periods + 1u) : UINT32_MAX;
        } else if (!wc_shift_phase_running(shift->phase)) {
            shift->fallback_periods = 0u;
        }
    }
    shift_before(shift, cal, command, safe, saturated, out->model.viscous_Nm, slip_rad_s, dt_s, clutch, adapt, in, offgoing);
    (void)wc_clutch_step(clutch, in, out);
    if (coord) {  /* DESIGN 14: the fill pulse, the off-going clutch (one clutch step deep), the engine */
        wc_shift_fill_pulse(cal, clutch, shift->phase == (uint32_t)WC_SHIFT_PREPARE, shift->phase_periods, dt_s, out);
        offgoing_input(shift, cal, safe, out->model.torque_Nm, dt_s, offgoing);
        (void)wc_clutch_step(offgoing->clutch, offgoing->in, offgoing->out);
        engine_request(shift, cal, dt_s, offgoing);
    }
    return shift_after(shift, cal, clutch, adapt, out, report, phase_before, slip_rad_s, dt_s);
}
