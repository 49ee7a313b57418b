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

/* The torque the off-going clutch carries while the source gear holds (the
 * hold-back's feed-forward at a zero slip rate, DESIGN 15): |T_t| / (I_t k_1),
 * less than T_t by the turbine's share of the vehicle's acceleration (on the
 * 8HP's 3->2 at full load 196 of 250 N m). The PREPARE ramp ends just above
 * it (not above T_t: held there, the element's lock-up margin kept it stuck
 * 70 ms into the inertia phase, then it broke away with the integral wound
 * up: 15 m/s^3 at the kickdown's start). */
static float offgoing_carried_Nm(const wc_shift_calibration_t *cal, float turbine_torque_Nm)
{
    return wc_shift_clamp_torque_Nm(fabsf(turbine_torque_Nm) / (cal->turbine_inertia_kg_m2 * holdback_k1(cal)));
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

/* The comfort jerk the reference is designed for, on the controller's model:
 * the kickdown's issue-29 target 15 m/s^3 with a fifth to spare, the
 * tip-out's 5 with two fifths (the model's jerk is optimistic: measured
 * against the 8-speed plant 1.0-1.9 x). Design constants of the controller
 * until the calibration image can carry them (its layout is generated into
 * the CAN image, src/can). */
#define WC_SHIFT_KICKDOWN_JERK_m_s3 12.0f
#define WC_SHIFT_TIPOUT_JERK_m_s3 3.0f

/* DESIGN 15: a coast downshift requested with the pedal pressed (T_t0 > 0, below the power-on type's 50 N m:
 * a downshift on the down line at part pedal) takes the drive away at this rate of the turbine
 * torque, over the engine's lag at least: the off-going element's ramp out and the engine's reduction to its
 * zero torque, so the output's fall stays within the coast's 5 m/s^3 (the 8HP's 2->1 on the open converter at
 * T_t 12 / 31 / 46 N m: 3.2 / 3.6 / 5.6 m/s^3; at 100 N m/s 4.7 / 4.2 / 5.6; over the engine's lag alone, 90 ms,
 * 31 N m jerked 11.4). A design constant as the two above. */
#define WC_SHIFT_PRESSED_RATE_Nm_per_s 60.0f

/* The time the pressed drive's ramp out takes (above); the engine's lag without a pressed pedal. */
static float drive_ramp_s(const wc_shift_t *shift, const wc_shift_calibration_t *cal)
{
    const float ramp_s = shift->driver_torque_Nm / WC_SHIFT_PRESSED_RATE_Nm_per_s;  /* <= 0 without a pressed pedal */
    return (ramp_s > cal->engine_lead_time_s) ? ramp_s : cal->engine_lead_time_s;
}

/* The coast downshift's lowest engine request elapsed_s into its inertia phase: 0, or with T_t0 > 0 down to
 * the engine's zero torque (-T_t0, at most engine_reduction_max_Nm as the power-on upshift's reduction),
 * ramped in over drive_ramp_s. T_t0 > 0 is the engine's drive at the request: a pressed pedal, or an open
 * converter's creep at idle, where the engine has little to give back. */
static float engine_floor_Nm(const wc_shift_t *shift, const wc_shift_calibration_t *cal, float elapsed_s)
{
    if (!(shift->driver_torque_Nm > 0.0f)) { return 0.0f; }
    const float ramp_s = drive_ramp_s(shift, cal);
    const float x = (elapsed_s < ramp_s) ? (elapsed_s / ramp_s) : 1.0f;  /* ramp_s >= T_t0 / rate > 0 */
    const float drive_Nm = (shift->driver_torque_Nm < cal->engine_reduction_max_Nm) ? shift->driver_torque_Nm
                                                                                    : cal->engine_reduction_max_Nm;
    return -drive_Nm * x;
}

/* The slip jerk j (rad/s^3, the rate of d(slip)/dt) that gives the vehicle
 * the jerk J (DESIGN 10, 15, with the relations above): while the off-going
 * clutch holds back, d(slip)/dt = T_t / I_t - k_1 T_1 and the output torque
 * is b1 T_1, so the vehicle's jerk is (jerk_per_torque_rate / b) b1
 * |dT_1/dt| = (jerk_per_torque_rate / b) (b1 / k_1) |d^2 slip/dt^2|
 * (jerk_per_torque_rate / b = r_f / (m r_w)); while the on-coming one pushes
 * (pushes: the tip-out's assist, T_1 = 0) the output torque is b T_c =
 * (b / k_c) (d(slip)/dt - T_t / I_t): b / k_c instead, the larger of the two
 * bounds j. 0: no bound (jerk_per_torque_rate 0). */
static float slip_jerk_rad_s3_of(const wc_shift_calibration_t *cal, float vehicle_jerk_m_s3, bool pushes)
{
    const float b = cal->output_ratio;
    const float k_c = 1.0f / cal->turbine_inertia_kg_m2 + b * b / cal->output_inertia_kg_m2;
    const float off_gain = cal->offgoing_ratio / holdback_k1(cal);
    const float on_gain = b / k_c;
    const float gain = cal->jerk_per_torque_rate / b * ((pushes && (on_gain > off_gain)) ? on_gain : off_gain);
    return (gain > 0.0f) ? (vehicle_jerk_m_s3 / gain) : 0.0f;
}

/* The inertia-first shift's reference slip (DESIGN 10's reference with the
 * comfort bound of DESIGN 15): its rate a trapezoid in time, rising at the
 * slip jerk j for ramp_s, flat at |slip_0| / (T - ramp_s), falling at j to 0
 * at T (zero slope at synchronism, as DESIGN 10 asks). The smoothstep's
 * rate 6 |slip_0| x (1 - x) / T rises at 6 |slip_0| / T^2 from the start,
 * where the hold-back leaves the output: the trapezoid at the same time T
 * rises at |slip_0| / (ramp (T - ramp)). The ramp: the smallest within j,
 * ramp (T - ramp) = |slip_0| / j, ramp = (T - sqrt(T^2 - 4 |slip_0| / j)) /
 * 2 (T^2 < 4 |slip_0| / j, too fast for j: the triangle, ramp = T / 2), but
 * at least ramp_min_share T: at T / 3 the flat rate is the smoothstep's peak
 * 1.5 |slip_0| / T and the ramp's jerk 4.5 |slip_0| / T^2, 3/4 of the
 * smoothstep's (the model's j is optimistic, above; the smallest ramp
 * measured 15.3 m/s^3 on the 8HP's 6->4 against 13.0 at T / 3). */
static float ramp_time_s(float target_time_s, float start_slip_rad_s, float slip_jerk_rad_s3, float ramp_min_share,
                         float flat_max_rad_s2)
{
    if (!(slip_jerk_rad_s3 > 0.0f)) { return 0.5f * target_time_s; }
    const float d_s2 = target_time_s * target_time_s - 4.0f * fabsf(start_slip_rad_s) / slip_jerk_rad_s3;
    const float ramp_s = (d_s2 > 0.0f) ? (0.5f * (target_time_s - sqrtf(d_s2))) : (0.5f * target_time_s);
    float min_s = ramp_min_share * target_time_s;
    if (flat_max_rad_s2 > 0.0f) {
        /* no longer than the flat rate's bound leaves (|slip_0| / (T - ramp) <= flat_max), nor below T / 3 */
        const float room_s = target_time_s - fabsf(start_slip_rad_s) / flat_max_rad_s2;
        const float third_s = target_time_s / 3.0f;
        const float bound_s = (room_s > third_s) ? room_s : third_s;
        min_s = (min_s < bound_s) ? min_s : bound_s;
    }
    return (ramp_s > min_s) ? ramp_s : min_s;
}

static float trapezoid_reference(float start_slip_rad_s, float target_time_s, float ramp_s, float elapsed_s,
                                 float *rate_rad_s2)
{
    *rate_rad_s2 = 0.0f;
    if (!(target_time_s > 0.0f) || !(ramp_s > 1e-6f)) { return 0.0f; }
    const float flat_per_s = 1.0f / (target_time_s - ramp_s);  /* ramp <= T / 2: T - ramp >= T / 2 > 0 */
    const float t_s = (elapsed_s > 0.0f) ? ((elapsed_s < target_time_s) ? elapsed_s : target_time_s) : 0.0f;
    const float left_s = target_time_s - t_s;
    float done;    /* the share of the slip taken, 0 .. 1 */
    float rate_per_s;
    if (t_s < ramp_s) {
        done = 0.5f * flat_per_s * t_s * t_s / ramp_s;
        rate_per_s = flat_per_s * t_s / ramp_s;
    } else if (left_s > ramp_s) {
        done = flat_per_s * (t_s - 0.5f * ramp_s);
        rate_per_s = flat_per_s;
    } else {
        done = 1.0f - 0.5f * flat_per_s * left_s * left_s / ramp_s;
        rate_per_s = flat_per_s * left_s / ramp_s;
    }
    *rate_rad_s2 = -start_slip_rad_s * rate_per_s;
    return start_slip_rad_s * (1.0f - done);
}

/* The reference of the running shift at elapsed_s: the kickdown's and the
 * tip-out's trapezoid (its ramp from the latched target time and start slip:
 * no state besides those; slip_jerk_rad_s3 > 0), else DESIGN 10's smoothstep
 * (the coast downshift: the engine moves the turbine, no clutch torque
 * reaches the output until synchronism). */
typedef struct {
    float slip_jerk_rad_s3;   /* j; 0: DESIGN 10's smoothstep */
    float ramp_min_share;     /* the ramp at least this share of T ... */
    float flat_max_rad_s2;    /* ... unless the flat rate would pass this (> 0), not below T / 3 */
} profile_t;

static float reference_at(const wc_shift_t *shift, const profile_t *profile, float elapsed_s, float *rate_rad_s2)
{
    if (!(profile->slip_jerk_rad_s3 > 0.0f)) {
        return wc_shift_reference_at(shift->start_slip_rad_s, shift->target_time_s, elapsed_s, rate_rad_s2);
    }
    const float ramp_s = ramp_time_s(shift->target_time_s, shift->start_slip_rad_s, profile->slip_jerk_rad_s3,
                                     profile->ramp_min_share, profile->flat_max_rad_s2);
    return trapezoid_reference(shift->start_slip_rad_s, shift->target_time_s, ramp_s, elapsed_s, rate_rad_s2);
}

/* Without the on-coming assist only the turbine torque (with the engine:
 * what the engine may add) moves the turbine, the off-going clutch can only
 * hold it back: the reference's flat rate must stay within T_t / I_t, with
 * WC_SHIFT_FEASIBLE_MARGIN to spare for the PI, and its ramps within j. A
 * target faster than that is stretched to the shortest such trapezoid: ramp
 * a / j at the flat rate a = T_t / (I_t margin), T = |slip_0| / a + a / j
 * (|slip_0| >= a^2 / j; else the triangle T = 2 sqrt(|slip_0| / j)), at most
 * inertia_time_max_s: a kickdown's engine torque and its comfort set the
 * pace, the feedback does not saturate at an empty clutch and time out
 * (DESIGN 15). */
#define WC_SHIFT_FEASIBLE_MARGIN 1.15f
static float feasible_time_s(const wc_shift_calibration_t *cal, float target_time_s, float start_slip_rad_s,
                             float turbine_torque_Nm, float slip_jerk_rad_s3)
{
    const float acceleration_rad_s2 = turbine_torque_Nm / (cal->turbine_inertia_kg_m2 * WC_SHIFT_FEASIBLE_MARGIN);
    const float slip_rad_s = fabsf(start_slip_rad_s);
    if (!(acceleration_rad_s2 * cal->inertia_time_max_s > slip_rad_s)) { return cal->inertia_time_max_s; }
    float need_s = 1.5f * slip_rad_s / acceleration_rad_s2;  /* ramp T / 3: the flat rate 1.5 |slip_0| / T */
    if (slip_jerk_rad_s3 > 0.0f) {
        const float ramp_s = acceleration_rad_s2 / slip_jerk_rad_s3;
        const float jerk_s = (slip_rad_s >= acceleration_rad_s2 * ramp_s) ? (slip_rad_s / acceleration_rad_s2 + ramp_s)
                                                                          : (2.0f * sqrtf(slip_rad_s / slip_jerk_rad_s3));
        need_s = (jerk_s > need_s) ? jerk_s : need_s;
    }
    need_s = (need_s < cal->inertia_time_max_s) ? need_s : cal->inertia_time_max_s;
    return (need_s > target_time_s) ? need_s : target_time_s;
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

/* The coast downshift's PI on the engine (DESIGN 14's engine with its lag):
 * the PI's kp through k_1 I_t is a proportional gain kp k_1 I_t on the
 * turbine's I_t, a crossover at kp k_1 rad/s (25 on the 8HP's 6->4); the
 * engine lags by engine_lead_time_s (90 ms): its kp is scaled by g = 1 / (2
 * lead kp k_1) (<= 1) to cross over at 1 / (2 lead), its ki by g^2 to keep
 * the PI's zero ki / kp below the crossover (measured at the full gain: the
 * request swung 20 <-> 60 N m at 2.5 Hz, 5 m/s^3). */
static float engine_loop_gain(const wc_shift_calibration_t *cal, float k_1)
{
    const float crossover = 2.0f * cal->engine_lead_time_s * cal->kp_Nm_per_rad_s * k_1;
    return (crossover > 1.0f) ? (1.0f / crossover) : 1.0f;
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
                                 bool offgoing_saturated, bool oncoming_saturated, bool assist, bool engine,
                                 float oncoming_model_Nm, float oncoming_viscous_Nm)
{
    requests_t r = { 0.0f, 0.0f, 0.0f, false, true };
    const float t_t_Nm = shift->turbine_torque_Nm;
    /* the reference within the type's comfort bound (0: the coast downshift's smoothstep); its ramps at least
     * T / 3 (above; the tip-out's shortest ramp within its bound, the lowest flat rate, let the turbine run
     * away under the drag once the off-going element had let go: the 4->5 synchronised at 0.74 s of 1.2) */
    const float slip_jerk_rad_s3 = engine ? 0.0f : slip_jerk_rad_s3_of(cal, assist ? WC_SHIFT_TIPOUT_JERK_m_s3
                                                                                 : WC_SHIFT_KICKDOWN_JERK_m_s3, assist);
    /* the kickdown's ramps 0.4 T where its flat rate stays within what T_t0 can do (feasible_time_s; 1/3: the
     * 8HP's 4->3 flared 32 rpm, 6->4 13.0 m/s^3 against 9.5 at 0.4) */
    const float flat_max_rad_s2 = (assist || engine) ? 0.0f
        : (shift->driver_torque_Nm / (cal->turbine_inertia_kg_m2 * WC_SHIFT_FEASIBLE_MARGIN));
    const profile_t profile = { slip_jerk_rad_s3, assist ? (1.0f / 3.0f) : 0.4f, flat_max_rad_s2 };
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
            const float to_Nm = (1.0f + cal->offgoing_margin_factor) * offgoing_carried_Nm(cal, t_t_Nm);
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
        if (!assist) {
            shift->target_time_s = feasible_time_s(cal, shift->target_time_s, slip_rad_s, moving_Nm, slip_jerk_rad_s3);
        }
        shift->request_Nm = (1.0f + cal->offgoing_margin_factor) * offgoing_carried_Nm(cal, t_t_Nm);
        /* (the coast downshift: the PI is the engine's, from 0; the off-going clutch only follows the drag out) */
        shift->integral_Nm = engine ? 0.0f
                                    : (shift->request_Nm - cal->feedforward_gain * holdback_feedforward_Nm(cal, holdback_k1(cal), t_t_Nm, 0.0f));
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
        const float reference = reference_at(shift, &profile, elapsed_s, &rate_rad_s2);
        const float k_1 = holdback_k1(cal);
        const float ff_Nm = cal->feedforward_gain * holdback_feedforward_Nm(cal, k_1, t_t_Nm, rate_rad_s2);
        /* slip above the reference: the turbine runs ahead, the off-going clutch holds more (with the assist:
         * the on-coming one pushes less) */
        const float error = slip_rad_s - reference;
        shift->error_sq_sum += error * error;
        shift->inertia_periods++;
        /* (the coast downshift's PI at the engine's loop gain, engine_loop_gain) */
        const float engine_gain = engine ? engine_loop_gain(cal, k_1) : 1.0f;
        const float pi_Nm = engine_gain * cal->kp_Nm_per_rad_s * error + shift->integral_Nm;
        const float holdback_Nm = ff_Nm + pi_Nm;
        /* the coast downshift's lowest engine request (engine_floor_Nm: 0 but with T_t0 > 0) */
        const float floor_Nm = engine ? engine_floor_Nm(shift, cal, elapsed_s) : 0.0f;
        if (engine) {
            /* the coast downshift: the engine accelerates the turbine on the reference, engine_lead_time_s ahead
             * (its lag): I_t dref/dt - T_t0; the PI's correction -PI k_1 I_t (the turbine torque that a hold-back
             * of PI would take away, DESIGN 15) both ways: more when the turbine lags, less when it runs ahead
             * (the off-going clutch, open, cannot hold it back: with the correction one way only the turbine
             * ran ahead of the reference and synchronised at 1.36-1.62 s of 2.0 s) */
            float lead_rate_rad_s2;
            (void)reference_at(shift, &profile, elapsed_s + cal->engine_lead_time_s, &lead_rate_rad_s2);
            const float correction_Nm = -pi_Nm * k_1 * cal->turbine_inertia_kg_m2;
            const float want_Nm = cal->turbine_inertia_kg_m2 * lead_rate_rad_s2 - shift->driver_torque_Nm + correction_Nm;
            /* DESIGN 15: with the driver's pedal pressed (T_t0 > 0: a downshift on the down line below the
             * power-on type's torque) the turbine runs ahead of the reference on its own: the engine takes back
             * down to its zero torque (-T_t0), as the power-on upshift's reduction (the 8HP's 2->1 on the open
             * converter at T_t 31 N m synchronised at 0.57 s of 2.0 and flared 93 rpm) */
            r.engine_Nm = (want_Nm > floor_Nm) ? ((want_Nm < cal->engine_increase_max_Nm) ? want_Nm : cal->engine_increase_max_Nm)
                                               : floor_Nm;
            shift->engine_from_Nm = r.engine_Nm;  /* where the torque phase's ramp-out starts */
        }
        /* anti-windup: no integration further into a saturated clutch, nor below 0 without the assist (with the
         * engine: not while the engine is at either limit, its clutches are open) */
        const bool engine_full = engine && !(r.engine_Nm < cal->engine_increase_max_Nm);
        const bool engine_none = engine && !(r.engine_Nm > floor_Nm);
        const bool blocked = (offgoing_saturated && (error > 0.0f) && !engine) || ((error > 0.0f) && engine_none) ||
                             ((error < 0.0f) && (assist ? oncoming_saturated : (engine ? engine_full : (holdback_Nm <= 0.0f))));
        if (!blocked) { wc_shift_integrate(shift, cal, engine_gain * engine_gain * cal->ki_Nm_per_rad * error * dt_s); }
        if (slip_rad_s > cal->flare_slip_rad_s) { shift->report.flare = true; }  /* past synchronism */
        r.offgoing_Nm = holdback_Nm;
        if (engine) {
            /* the coast downshift's off-going clutch carries what is left of the drag while the engine's torque
             * rises through 0 (T_t, the engine's estimate, has the intervention in it), with the margin, then
             * opens for good: no step of the output torque, no hold-back against the engine. At the latest
             * after the engine's lag (engine_lead_time_s: an estimate without the intervention would hold it),
             * or with T_t0 > 0 after drive_ramp_s */
            const float lag_s = drive_ramp_s(shift, cal);
            const float lag_left = (lag_s > 0.0f) ? (1.0f - elapsed_s / lag_s) : 0.0f;
            /* (with the pedal pressed at the request, T_t0 > 0, it carries the drive the engine's reduction
             * takes away: the same ramp out, not a step of the output torque) */
            const bool pressed = shift->driver_torque_Nm > 0.0f;
            const float drag_now_Nm = ((t_t_Nm < 0.0f) || pressed) ? offgoing_carried_Nm(cal, t_t_Nm) : 0.0f;
            const float drag_lag_Nm = (lag_left > 0.0f) ? (lag_left * offgoing_carried_Nm(cal, shift->driver_torque_Nm)) : 0.0f;
            const float drag_Nm = (drag_now_Nm < drag_lag_Nm) ? drag_now_Nm : drag_lag_Nm;
            r.offgoing_Nm = (1.0f + cal->offgoing_margin_factor) * drag_Nm;
            if (!(drag_Nm > 0.0f)) { shift->offgoing_released = true; }
        }
        /* the push per newton metre of negative hold-back: k_1 / k_c (above) */
        const float b = cal->output_ratio;
        const float k_c = 1.0f / cal->turbine_inertia_kg_m2 + b * b / cal->output_inertia_kg_m2;
        r.oncoming_Nm = assist ? (-holdback_Nm * k_1 / k_c) : 0.0f;  /* clamped at 0 by set_input */
        /* the tip-out: once the hold-back is spent (the on-coming clutch pushes), the off-going clutch opens for
         * good, while the push still ramps in: at its kiss point its drag at the shift's slip would be a tie-up
         * the push works against, and its release at synchronism a step of the output torque (DESIGN 15) */
        /* (the coast downshift likewise: once the engine carries the turbine, the off-going clutch's drag at
         * the shift's slip would push the coasting vehicle, then vanish at synchronism) */
        if (assist && !(holdback_Nm > 0.0f)) { shift->offgoing_released = true; }
        r.offgoing_open = shift->offgoing_released;
        return r;
    }
    /* TORQUE (the hand-over at synchronism), LOCKED */
    const float hold_Nm = cal->holding_torque_factor * oncoming_carried_Nm(cal, t_t_Nm);
    const float x = (phase == (uint32_t)WC_SHIFT_TORQUE) ? handover_share(shift, cal, dt_s) : 1.0f;
    /* the turbine running past synchronism (slip > 0: the off-going clutch lets go while T_t still drives) is
     * taken by the on-coming clutch in closed loop (the torque-first shift's flare correction, DESIGN 14). The
     * coast downshift's turbine may pass it either way: dragged back below by T_t < 0, or run up past it by an
     * engine that drives (T_t0 > 0: a pressed pedal, the open converter's creep while braking to a stop; the
     * 8-speed's 2->1 at 5 km/h, brake 700 N m, creep 33 N m: corrected one way only, it ran 560 rpm past and
     * the lock-up failed). The clutch's torque works against its slip on either side: |slip| */
    const float past_rad_s = engine ? fabsf(slip_rad_s) : ((slip_rad_s > 0.0f) ? slip_rad_s : 0.0f);
    if (phase == (uint32_t)WC_SHIFT_TORQUE) {
        const float integral_Nm = shift->flare_integral_Nm + cal->flare_ki_Nm_per_rad * past_rad_s * dt_s;
        /* anti-windup: |T_t| beyond what the clutch carries already. |T_t| alone: a cold coast downshift's
         * on-coming element, whose drag at its kiss point was more than the integral could ask, slipped on at
         * 9 rad/s after synchronism, carrying T_t by its drag, and failed to lock (8-speed 6->5 at 20 degC) */
        const float limit_Nm = fabsf(t_t_Nm) + fabsf(oncoming_model_Nm);
        shift->flare_integral_Nm = (integral_Nm < limit_Nm) ? integral_Nm : limit_Nm;
        if (slip_rad_s > cal->flare_slip_rad_s) { shift->report.flare = true; }
    }
    /* the tip-out's hand-over: the on-coming clutch must hold the engine's drag by friction, and the viscous
     * drag at the slip left vanishes as it locks, so the inverse (at the measured slip) is asked for it on top;
     * else a cold pack at its kiss point carries that small T_t by its drag alone at a slip that never closes
     * (the 8HP's 6->7 and 5->7 at 20 degC: 4 rad/s of A's own slip for 0.9 s at its kiss point, lock-up failed).
     * Not in a kickdown: its T_t share dominates the drag, and the cold drag added as friction jerked (3->2 at
     * 25 % load 9.6 -> 15.4 m/s^3, 7->6 at full load 11.9 -> 18.4) */
    const float drag_Nm = (assist && (phase == (uint32_t)WC_SHIFT_TORQUE)) ? fabsf(oncoming_viscous_Nm) : 0.0f;
    r.oncoming_Nm = hold_Nm * x + cal->flare_kp_Nm_per_rad_s * past_rad_s + shift->flare_integral_Nm + drag_Nm;
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
    in->band_release = false;
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
                                        oncoming_assist, engine, out->model.torque_Nm, out->model.viscous_Nm);
    /* the on-coming clutch: with the assist (the tip-out) at its kiss point from PREPARE, without the fill
     * pulse: the pulse's overshoot at the whole slip pushed the turbine down at the phase's start (on the 8HP's
     * 3->4 57 N m of the element's torque against the engine's drag of 22, the off-going element held back 66
     * N m against it: 12 m/s^3; without it 2.5); filled late, before its push, the pulse and the kiss point's
     * drag came as a step into a free turbine (2->3 16 m/s^3). Without the assist late in the inertia phase,
     * the fill pulse, then the kiss point (above). */
    const bool inertia = shift->phase == (uint32_t)WC_SHIFT_INERTIA;
    const uint32_t fill_periods = (inertia && !oncoming_assist) ? late_fill_periods(shift, cal, dt_s) : 0u;
    const bool filling = !oncoming_assist && (fill_periods > 0u);
    const bool on_active = (oncoming_assist && ((shift->phase == (uint32_t)WC_SHIFT_PREPARE) || inertia)) ||
                           (inertia && (fill_periods > 0u)) || (shift->phase == (uint32_t)WC_SHIFT_TORQUE) ||
                           (shift->phase == (uint32_t)WC_SHIFT_LOCKED);
    const float carried_on_Nm = oncoming_carried_Nm(cal, shift->turbine_torque_Nm);
    set_input(in, on_active ? WC_MODE_TORQUE : WC_MODE_OPEN, r.oncoming_Nm, carried_on_Nm, &shift->lag_compensation);
    const bool hand_back = (safe && !shift->second_gear) || r.offgoing_locked;
    const wc_clutch_mode_t off_mode = hand_back ? WC_MODE_LOCKED : (r.offgoing_open ? WC_MODE_OPEN : WC_MODE_TORQUE);
    /* what it carries while it holds (the lock-up's decision: below it, it slips) */
    set_input(offgoing->in, off_mode, r.offgoing_Nm, offgoing_carried_Nm(cal, shift->turbine_torque_Nm),
              &shift->offgoing_lag);
    /* DESIGN 15: in the inertia phase the off-going element may release below its kiss point (at a light
     * load its pack's drag there carries all the turbine torque, and the turbine never reaches the new gear),
     * and in the hand-over, where its request ramps to 0: held at its kiss point a cold pack's drag at the new
     * gear's slip fought the on-coming element (8HP 7->5 at 25 % and 20 degC: 51 m/s^3, 8->6 at full load 20) */
    offgoing->in->band_release = inertia || (shift->phase == (uint32_t)WC_SHIFT_TORQUE);
    if (shift->phase == (uint32_t)WC_SHIFT_INERTIA) { shift->request_Nm = wc_shift_clamp_torque_Nm(r.offgoing_Nm); }

    (void)wc_clutch_step(clutch, in, out);
    wc_shift_fill_pulse(cal, clutch, filling, oncoming_assist ? shift->phase_periods : (fill_periods - 1u), dt_s, out);
    (void)wc_clutch_step(offgoing->clutch, offgoing->in, offgoing->out);
    /* the engine request (the coast downshift); none in the safe state or a fallback */
    offgoing->engine_active = engine && ((r.engine_Nm > 0.0f) || (r.engine_Nm < 0.0f)) && !safe &&
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
