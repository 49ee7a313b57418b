/* On-coming clutch control of a 1->2 upshift (DESIGN section 10): a phase
 * state machine, the inertia phase's reference slip, the driveline model's
 * feed-forward torque and a PI on the slip (2-DOF), passed through the clutch
 * model's inverse and the VFS lag compensation (wc_clutch_step), plus the
 * shift's quality vector. All state in wc_shift_t (caller-owned), the shift
 * calibration read-only; the clutch is the caller's wc_clutch_t, which the
 * shift controller steps while a shift runs.
 *
 * Phases (wc_shift_phase_t):
 *   IDLE      no shift: the clutch is released (minimum current).
 *   PREPARE   prepare_time_s after the command: torque request 0, i.e. the
 *             piston filled to its spring preload (kiss point).
 *   TORQUE    torque phase, torque_phase_time_s: the request ramps linearly
 *             from 0 to the turbine torque's share T_t / a while the
 *             off-going clutch releases (the off-going is not ours).
 *   INERTIA   the reference slip goes from the slip at phase start to 0 in
 *             the commanded target time with zero slope at both ends
 *             (smoothstep); request = feed-forward + PI(slip - reference).
 *             Ends when the slip has stayed inside the clutch's lock band
 *             (lock_slip_rad_s) for lock_dwell_periods, the model locks, or
 *             the reference has ended (target time elapsed) with the slip
 *             within min_start_slip_rad_s.
 *   LOCKUP    hand-over: the request ramps to holding_torque_factor * T_t / a
 *             in lockup_ramp_time_s, so that the static capacity exceeds the
 *             torque the clutch carries (the feed-forward at a zero slip rate,
 *             passed to the lock-up as carried_torque_Nm) and the model locks (wc_lockup, DESIGN 9);
 *             LOCKED once locked and the ramp done; not locked after
 *             WC_SHIFT_LOCKUP_WAIT ramp times: abort.
 *   LOCKED    shift complete; the holding request stays until the command ends
 *             or the safe state begins (then IDLE: released).
 *   ABORTED   released to the safe state (minimum current) until the command
 *             ends; the report says why.
 * The report (wc_shift_report_t) is produced once, on entering LOCKED or
 * ABORTED. */
#ifndef WC_SHIFT_H
#define WC_SHIFT_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_adapt.h"
#include "wc_clutch.h"

typedef enum {
    WC_SHIFT_IDLE = 0,
    WC_SHIFT_PREPARE,
    WC_SHIFT_TORQUE,
    WC_SHIFT_INERTIA,
    WC_SHIFT_LOCKUP,
    WC_SHIFT_LOCKED,
    WC_SHIFT_ABORTED
} wc_shift_phase_t;

/* Why a shift ended without completing. The values are those of the DBC
 * signal ShiftReport.AbortReason. */
typedef enum {
    WC_SHIFT_ABORT_NONE = 0,
    WC_SHIFT_ABORT_INERTIA_TIMEOUT = 1,  /* inertia phase longer than target * inertia_timeout_factor */
    WC_SHIFT_ABORT_LOCKUP_FAILED = 2,    /* the clutch was not locked at the end of the hand-over */
    WC_SHIFT_ABORT_INPUT_LOST = 3,       /* the frame loop went to its safe state during the shift */
    WC_SHIFT_ABORT_CANCELLED = 4,        /* the command was withdrawn before the shift completed */
    WC_SHIFT_ABORT_INVALID_COMMAND = 5,  /* target gear not WC_SHIFT_TARGET_GEAR, target time or turbine torque
                                          * out of range */
    WC_SHIFT_ABORT_NO_SLIP = 6           /* slip at inertia start not above min_start_slip_rad_s */
} wc_shift_abort_t;

/* Which temperature the clutch model uses during a shift. */
typedef enum {
    WC_SHIFT_THETA_OBSERVER = 0,  /* the thermal observer's friction-surface estimate (eq. 1) */
    WC_SHIFT_THETA_OIL = 1        /* the oil temperature: a thermal-blind model (comparison only) */
} wc_shift_theta_source_t;

typedef struct wc_shift_calibration {
    /* The TCU's driveline model (DESIGN 10): the turbine side and the clutch's kinematics. */
    float turbine_inertia_kg_m2;       /* I_t: turbine + engine (converter locked) */
    float turbine_ratio;               /* a in slip = a w_t - b w_o: clutch slip per turbine speed */
    float output_inertia_kg_m2;        /* I_o plus the vehicle referred to the output shaft, m r_w^2 / r_f^2 */
    float output_ratio;                /* b: clutch slip per output speed (the target gear's ratio) */
    float jerk_per_torque_rate;        /* vehicle jerk per on-coming clutch torque rate, (m/s^3) / (Nm/s): b r_f / (m r_w) */
    /* Phases */
    float prepare_time_s;
    float torque_phase_time_s;
    float inertia_time_min_s;          /* accepted commanded target inertia times */
    float inertia_time_max_s;
    float inertia_timeout_factor;      /* abort when the inertia phase exceeds target * this (> 1) */
    float lockup_ramp_time_s;          /* hand-over to the holding torque */
    float holding_torque_factor;       /* holding request / (T_t / a), >= 1 */
    float min_start_slip_rad_s;        /* slip at inertia start must exceed it; at the reference's end
                                        * a slip within it is pulled in by the hand-over */
    /* 2-DOF control */
    float feedforward_gain;            /* 1: the driveline feed-forward; 0: feedback only (comparison) */
    float kp_Nm_per_rad_s;             /* PI on the slip error (slip - reference) */
    float ki_Nm_per_rad;
    float integral_limit_Nm;           /* |integral term| bound (anti-windup) */
    float lag_compensation_time_s;     /* t of wc_lag_compensation() for wc_step_input_t; 0: off */
    uint32_t theta_source;             /* wc_shift_theta_source_t */
    /* Quality */
    float flare_slip_rad_s;            /* slip above the slip at inertia start + this: flare */
    float tie_up_factor;               /* torque-phase request estimate above factor * T_t / a while the slip holds: tie-up */
    float jerk_filter_time_s;          /* first-order filter on the torque before its rate is taken */
    /* Adaptation (DESIGN 12, wc_adapt.h): the learning rules; 0 = off, the
     * controller bit for bit the unadapted one. */
    uint32_t adaptation;               /* 1: learn (wc_adapt_t of wc_shift_step) and use the learned values */
    float adapt_theta_node_degC[WC_ADAPT_NODES];  /* the friction scale's temperatures, strictly increasing */
    float adapt_scale_band;            /* |friction scale - 1| <= band */
    float adapt_scale_step;            /* |change of a node's scale| per shift <= step */
    float adapt_scale_gain;            /* fraction of the measured error taken per shift */
    float adapt_confidence_gain;       /* confidence += gain * share * (1 - confidence) per update */
    float adapt_film_factor_min;       /* the film factor's band (a multiplier, 1 = the calibration's) */
    float adapt_film_factor_max;
    float adapt_film_step;             /* |relative change of the film factor| per shift <= step */
    float adapt_film_gain;
    float adapt_kiss_band_Pa;          /* |kiss offset| <= band */
    float adapt_kiss_step_Pa;          /* |change of the kiss offset| per shift <= step */
    float adapt_kiss_gain;
    float adapt_window_skip_s;         /* the window starts this long after the inertia phase's start */
    float adapt_film_window_s;         /* the film factor's early part of the window */
    float adapt_min_slip_drop;         /* excitation: the slip falls by this fraction of its window start */
    float adapt_min_conditioning;      /* the kiss point's least squares: D / (S11 S22) at least this */
    /* The whole shift (DESIGN 14): 0 = the on-coming clutch alone, bit for bit
     * the controller above (the off-going clutch and the engine are not ours);
     * 1 = the coordinator: fill, the off-going clutch's capacity, the engine
     * torque intervention and the per-phase fallback of a lost input. */
    uint32_t coordinator;
    float offgoing_ratio;              /* b1 = i1: the off-going clutch's slip a w_t - b1 w_o (1st gear); > output_ratio */
    float fill_pulse_current_mA;       /* fill: this VFS current for fill_pulse_time_s, then the kiss point */
    float fill_pulse_time_s;           /* <= prepare_time_s */
    float offgoing_holding_factor;     /* off-going capacity request before the torque phase / T_t */
    float offgoing_margin_factor;      /* torque phase: request = carried torque + factor * T_t0 (+ its lock-up margin) */
    float offgoing_lag_compensation_time_s;  /* the off-going clutch's lag compensation (DESIGN 9); 0: off */
    float flare_kp_Nm_per_rad_s;       /* torque phase: off-going request + kp * (off-going slip > 0) ... */
    float flare_ki_Nm_per_rad;         /* ... + ki * its integral (flare corrected in closed loop) */
    float handover_slip_rad_s;         /* off-going slip below -this: the on-coming holds the turbine (tie-up): release */
    uint32_t engine_intervention;      /* 1: request engine torque (DBC EngineTorqueRequest) */
    float engine_increase_max_Nm;      /* torque phase: increase <= this */
    float engine_reduction_max_Nm;     /* inertia phase: reduction <= this, and the engine not below its zero torque (T_t0) */
    float engine_fill_fraction;        /* torque phase: increase = fraction * (b1 - b) / b * T_t0 (the torque hole) */
    float engine_reduction_fraction;   /* inertia phase: reduction = fraction * I_t |dref/dt| / a (the inertia torque), <= 2 */
    float engine_recovery_time_s;      /* after the inertia phase what is left of the request ramps out in this time */
    float engine_lead_time_s;          /* the request runs this far ahead of the reference (the engine's lag and delay) */
    float fallback_time_s;             /* a lost input in the inertia phase or later: finish on the model this long at most */
} wc_shift_calibration_t;

/* Which field an invalid shift calibration fails on (0 = valid): the fields
 * in declaration order. */
typedef enum {
    WC_SHIFT_CAL_OK = 0,
    WC_SHIFT_CAL_NULL,
    WC_SHIFT_CAL_TURBINE_INERTIA,
    WC_SHIFT_CAL_TURBINE_RATIO,
    WC_SHIFT_CAL_OUTPUT_INERTIA,
    WC_SHIFT_CAL_OUTPUT_RATIO,
    WC_SHIFT_CAL_JERK_PER_TORQUE_RATE,
    WC_SHIFT_CAL_PREPARE_TIME,
    WC_SHIFT_CAL_TORQUE_PHASE_TIME,
    WC_SHIFT_CAL_INERTIA_TIME_MIN,
    WC_SHIFT_CAL_INERTIA_TIME_MAX,     /* also: below the minimum */
    WC_SHIFT_CAL_INERTIA_TIMEOUT_FACTOR,
    WC_SHIFT_CAL_LOCKUP_RAMP_TIME,
    WC_SHIFT_CAL_HOLDING_TORQUE_FACTOR,
    WC_SHIFT_CAL_MIN_START_SLIP,
    WC_SHIFT_CAL_FEEDFORWARD_GAIN,
    WC_SHIFT_CAL_KP,
    WC_SHIFT_CAL_KI,
    WC_SHIFT_CAL_INTEGRAL_LIMIT,
    WC_SHIFT_CAL_LAG_COMPENSATION_TIME,
    WC_SHIFT_CAL_THETA_SOURCE,
    WC_SHIFT_CAL_FLARE_SLIP,
    WC_SHIFT_CAL_TIE_UP_FACTOR,
    WC_SHIFT_CAL_JERK_FILTER_TIME,
    WC_SHIFT_CAL_ADAPTATION,
    WC_SHIFT_CAL_ADAPT_THETA_NODE0,    /* one code per node (WC_ADAPT_NODES): strictly increasing */
    WC_SHIFT_CAL_ADAPT_THETA_NODE1,
    WC_SHIFT_CAL_ADAPT_THETA_NODE2,
    WC_SHIFT_CAL_ADAPT_THETA_NODE3,
    WC_SHIFT_CAL_ADAPT_THETA_NODE4,
    WC_SHIFT_CAL_ADAPT_SCALE_BAND,
    WC_SHIFT_CAL_ADAPT_SCALE_STEP,
    WC_SHIFT_CAL_ADAPT_SCALE_GAIN,
    WC_SHIFT_CAL_ADAPT_CONFIDENCE_GAIN,
    WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MIN,
    WC_SHIFT_CAL_ADAPT_FILM_FACTOR_MAX,
    WC_SHIFT_CAL_ADAPT_FILM_STEP,
    WC_SHIFT_CAL_ADAPT_FILM_GAIN,
    WC_SHIFT_CAL_ADAPT_KISS_BAND,
    WC_SHIFT_CAL_ADAPT_KISS_STEP,
    WC_SHIFT_CAL_ADAPT_KISS_GAIN,
    WC_SHIFT_CAL_ADAPT_WINDOW_SKIP,
    WC_SHIFT_CAL_ADAPT_FILM_WINDOW,
    WC_SHIFT_CAL_ADAPT_MIN_SLIP_DROP,
    WC_SHIFT_CAL_ADAPT_MIN_CONDITIONING,
    WC_SHIFT_CAL_COORDINATOR,
    WC_SHIFT_CAL_OFFGOING_RATIO,       /* also: coordinator 1 and not WC_SHIFT_GEAR_STEP_MIN x output_ratio
                                        * away from it */
    WC_SHIFT_CAL_FILL_PULSE_CURRENT,
    WC_SHIFT_CAL_FILL_PULSE_TIME,      /* also: above prepare_time_s */
    WC_SHIFT_CAL_OFFGOING_HOLDING_FACTOR,
    WC_SHIFT_CAL_OFFGOING_MARGIN_FACTOR,
    WC_SHIFT_CAL_OFFGOING_LAG_COMPENSATION_TIME,
    WC_SHIFT_CAL_FLARE_KP,
    WC_SHIFT_CAL_FLARE_KI,
    WC_SHIFT_CAL_HANDOVER_SLIP,
    WC_SHIFT_CAL_ENGINE_INTERVENTION,
    WC_SHIFT_CAL_ENGINE_INCREASE_MAX,
    WC_SHIFT_CAL_ENGINE_REDUCTION_MAX,
    WC_SHIFT_CAL_ENGINE_FILL_FRACTION,
    WC_SHIFT_CAL_ENGINE_REDUCTION_FRACTION,
    WC_SHIFT_CAL_ENGINE_RECOVERY_TIME,
    WC_SHIFT_CAL_ENGINE_LEAD_TIME,
    WC_SHIFT_CAL_FALLBACK_TIME,
    WC_SHIFT_CAL_ERRORS
} wc_shift_cal_error_t;

/* Limits of wc_shift_calibration_check: every time within [0, 10] s (the
 * inertia times within [0.05, 5] s, the jerk filter and the lag compensation
 * time 0 or >= 1e-3 s), the inertia within (0, 100] kg m^2, the ratio within
 * [0.05, 20], the output inertia within [1e-4, 1e5] kg m^2, gains within
 * [0, 1e5], factors as commented. */
#define WC_SHIFT_LIMIT_TIME_MAX_s 10.0f
#define WC_SHIFT_LIMIT_INERTIA_TIME_MIN_s 0.05f
#define WC_SHIFT_LIMIT_INERTIA_TIME_MAX_s 5.0f
#define WC_SHIFT_LIMIT_GAIN_MAX 1e5f
/* The fill pulse's current: within the DBC's VfsCurrent range. */
#define WC_SHIFT_LIMIT_CURRENT_MAX_mA 2000.0f
/* The engine request's limits: within the DBC's EngineTorqueRequest.TorqueDelta range. */
#define WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm 1000.0f
/* The kiss offset's band: at most 1 MPa (a kiss pressure is about 0.1 MPa). */
#define WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa 1e6f
/* The shift controller knows one shift, its calibration's reduced model
 * (DESIGN 10, 15): the command's target gear is this one (the 1->2 bench's
 * 2nd gear; wc_transmission maps every shift of a gearbox onto it). */
#define WC_SHIFT_TARGET_GEAR 2u
/* The off-going and the target ratio differ by at least this fraction of the
 * target's (the gear step 1 - b / b1 divides; real steps are 10 % and more). */
#define WC_SHIFT_GEAR_STEP_MIN 0.01f
/* The hand-over waits this many lockup_ramp_time_s for the lock-up (its dwell, a slow cold film). */
#define WC_SHIFT_LOCKUP_WAIT 4u
/* The whole shift (DESIGN 14): into the inertia phase the off-going clutch
 * goes on tracking what it still carries until its slip shows that the
 * on-coming clutch holds the turbine (below -handover_slip_rad_s), at most
 * this long; then it is released. */
#define WC_SHIFT_HANDOVER_MAX_s 0.1f

wc_shift_cal_error_t wc_shift_calibration_check(const wc_shift_calibration_t *cal);

/* The fallback of a shift whose input was lost (DESIGN 14; the values of DBC
 * OffgoingVfsCommand.Fallback). Only with the coordinator; without it a lost
 * input releases the clutch (AbortReason 3). */
typedef enum {
    WC_SHIFT_FALLBACK_NONE = 0,
    WC_SHIFT_FALLBACK_FINISH = 1,    /* inertia phase or later: finished on the model (feed-forward on the
                                      * reference, no feedback), for at most fallback_time_s */
    WC_SHIFT_FALLBACK_HANDBACK = 2,  /* prepare or torque phase: handed back to the off-going gear (off-going at
                                      * its maximum current, on-coming released); AbortReason 3 */
    WC_SHIFT_FALLBACK_RELEASED = 3   /* neither possible (the finish took longer than fallback_time_s): released */
} wc_shift_fallback_t;

/* The second clutch and the engine of the whole shift (coordinator 1). The
 * off-going clutch is the caller's wc_clutch_t with its own calibration; in
 * holds its sensors (slip: the off-going slip a w_t - b1 w_o, temperatures),
 * the controller writes the rest and steps it. */
typedef struct {
    wc_clutch_t *clutch;
    wc_step_input_t *in;
    wc_step_output_t *out;
    bool engine_active;            /* out: DBC EngineTorqueRequest.InterventionActive */
    float engine_delta_Nm;         /* out: its TorqueDelta (0 when not active) */
} wc_shift_offgoing_t;

/* The shift command (DBC ShiftCommand), as the frame loop received it. */
typedef struct {
    bool request;                  /* 1: shift on; a rising edge while IDLE starts it; 0: end/cancel */
    uint32_t target_gear;          /* WC_SHIFT_TARGET_GEAR: the one shift of the calibration's reduced model */
    float turbine_torque_Nm;       /* the engine controller's turbine torque estimate T_t */
    float target_inertia_time_s;   /* in [inertia_time_min_s, inertia_time_max_s] */
} wc_shift_command_t;

/* The quality vector of one shift (DESIGN 10; DBC ShiftReport). */
typedef struct {
    float inertia_time_s;          /* inertia phase start to lock (0 if it never started) */
    float slip_rmse_rad_s;         /* RMS(slip - reference) over the inertia phase */
    float peak_jerk_m_s3;          /* |jerk_per_torque_rate * d(filtered request torque)/dt|, max over the shift */
    float friction_energy_J;       /* integral of |T dw| (model torque) over the shift */
    float peak_theta_degC;         /* highest friction-surface estimate during the shift */
    bool flare;
    bool tie_up;
    uint32_t abort_reason;         /* wc_shift_abort_t */
    wc_adapt_change_t adaptation;  /* what the shift changed of the learned values (DESIGN 12) */
    uint32_t fallback;             /* wc_shift_fallback_t (coordinator) */
} wc_shift_report_t;

typedef struct {
    uint32_t phase;                /* wc_shift_phase_t */
    uint32_t phase_periods;        /* periods spent in the phase */
    bool last_request;             /* the command's request bit at the previous step (edge detection) */
    float turbine_torque_Nm;       /* T_t latched, then followed from the command */
    float target_time_s;           /* latched at start */
    float start_slip_rad_s;        /* slip at inertia start */
    float integral_Nm;             /* PI integral term */
    float request_Nm;              /* last torque request */
    float phase_start_request_Nm;  /* request when the lock-up hand-over began */
    float filtered_torque_Nm;      /* jerk estimate filter state */
    float error_sq_sum;            /* sum of squared slip errors over the inertia phase, (rad/s)^2 */
    uint32_t inertia_periods;
    uint32_t band_periods;         /* consecutive periods with the slip inside the lock band */
    wc_lag_compensation_t lag_compensation;  /* of the calibration's time, made at the shift's start */
    wc_shift_report_t report;      /* running, final at the end */
    /* The whole shift (coordinator, DESIGN 14) */
    float driver_torque_Nm;        /* T_t0: the turbine torque at the command, before any intervention */
    float oncoming_torque_Nm;      /* the on-coming model's torque of the last step */
    float flare_integral_Nm;       /* off-going flare correction's integral */
    float engine_from_Nm;          /* the request when the reduction's recovery began */
    uint32_t fallback;             /* wc_shift_fallback_t of the running shift */
    uint32_t fallback_periods;     /* periods since the input was lost */
    uint32_t recovery_periods;     /* periods since the engine's recovery began */
    float offgoing_slip_rad_s;     /* this step's off-going slip (measured, else the clutch's last valid) */
    float last_slip_rad_s;         /* the on-coming slip of the last step */
    float slip_rate_rad_s2;        /* its rate, filtered (jerk_filter_time_s): in 1st gear the turbine's acceleration */
    bool offgoing_released;        /* the hand-over is over: the off-going clutch is open (DESIGN 14) */
    bool second_gear;              /* the on-coming clutch has the gear (from the inertia phase until the
                                    * command's withdrawal): the off-going clutch stays open */
    wc_lag_compensation_t offgoing_lag;  /* the off-going clutch's lag compensation */
} wc_shift_t;

void wc_shift_init(wc_shift_t *shift);

/* A shift in progress (PREPARE .. LOCKUP): it owns the clutch until it ends. */
static inline bool wc_shift_phase_running(uint32_t phase)
{
    return (phase >= (uint32_t)WC_SHIFT_PREPARE) && (phase <= (uint32_t)WC_SHIFT_LOCKUP);
}

/* The reference slip of the inertia phase (DESIGN 10) at elapsed_s after its
 * start: start_slip * (1 - s(x)), s(x) = 3x^2 - 2x^3, x = elapsed / target
 * clamped to [0, 1]; *rate_rad_s2 its time derivative (0 at both ends). */
float wc_shift_reference_slip(float start_slip_rad_s, float target_time_s, float elapsed_s, float *rate_rad_s2);

/* Feed-forward torque of the inertia phase, DESIGN 10 with a stiff
 * driveshaft: the vehicle moves with the output shaft, I_o -> I_out = I_o +
 * m r_w^2 / r_f^2, and T_s -> the road load, taken as 0 (it is small against
 * the clutch torque and the PI takes it):
 * T_ff = (a T_t / I_t - dref/dt) / (a^2 / I_t + b^2 / I_out), >= 0. */
float wc_shift_feedforward_Nm(const wc_shift_calibration_t *cal, float turbine_torque_Nm, float reference_rate_rad_s2);

/* One control period while the frame loop is in shift mode and not in its
 * safe state (safe = true: the loop's safe state is active; a running shift
 * aborts with WC_SHIFT_ABORT_INPUT_LOST). in holds the sensors (slip,
 * temperatures, bench); the controller writes the rest of the clutch input in
 * place (mode, torque request, carried torque, lag compensation, temperature
 * source, the adaptation's correction, band_release in the whole shift's torque
 * and inertia phases: on return in is the input the clutch stepped with), steps the
 * clutch (wc_clutch_step) and updates the quality vector. Returns true when
 * the shift ended this step; *report then holds its quality vector.
 * out must hold the previous step's output (zero-initialised before the
 * first): its WC_STATUS_SATURATED stops the integral (anti-windup). A request
 * bit already 1 when the safe state ends starts no shift: a new 0 -> 1 edge
 * is needed (no restart without the VCU's consent). adapt: the clutch's
 * learned values (DESIGN 12), used and updated when cal->adaptation is 1;
 * NULL (or adaptation 0): none, and the report's adaptation part says OFF.
 * offgoing: the off-going clutch and the engine request (coordinator 1,
 * DESIGN 14; NULL otherwise; with the coordinator and NULL the shift runs
 * without the off-going clutch and the engine, as coordinator 0). The
 * coordinator also runs in IDLE (the off-going clutch holds 1st gear at
 * offgoing_holding_factor * T_t; at its maximum current in the safe state). */
bool wc_shift_step(wc_shift_t *shift, const wc_shift_calibration_t *cal, const wc_shift_command_t *command,
                   bool safe, wc_clutch_t *clutch, wc_adapt_t *adapt, wc_step_input_t *in, wc_step_output_t *out,
                   wc_shift_report_t *report, wc_shift_offgoing_t *offgoing);

/* The inertia-phase-first shift (DESIGN 15: the power-on downshift, the
 * kickdown; mirrored by wc_transmission, the power-off upshift, the tip-out;
 * with WC_SHIFT_INERTIA_FIRST_ENGINE, not mirrored, the power-off downshift,
 * the coast): the off-going clutch (offgoing, required) lets the turbine run
 * to the target gear's speed on the reference slip (the coast: the engine
 * moves it, below) while the on-coming clutch (clutch) waits, open or at its
 * kiss point; at synchronism the torque phase hands the torque over. In the
 * controller's frame the turbine torque is >= 0 (with
 * WC_SHIFT_INERTIA_FIRST_ENGINE <= 0), the on-coming slip starts negative (the
 * turbine below the target gear's speed) and the off-going slip turns
 * positive. k_1 = 1 / I_t + b b1 / I_out, k_c = 1 / I_t + b^2 / I_out.
 * Phases:
 *   PREPARE   prepare_time_s: the off-going request ramps from
 *             offgoing_holding_factor x |T_t| to (1 + offgoing_margin_factor)
 *             x what it carries, |T_t| / (I_t k_1) (less than T_t by the
 *             turbine's share of the vehicle's acceleration): just above it.
 *             With WC_SHIFT_INERTIA_FIRST_ASSIST (the tip-out) the on-coming
 *             clutch waits at its kiss point from the start, without the fill
 *             pulse (its overshoot at the whole slip pushed the turbine
 *             down); without it (the kickdown, the coast) it stays open.
 *   INERTIA   the reference slip from the on-coming slip at the phase start
 *             (below -min_start_slip_rad_s, else AbortReason 6) to 0: for the
 *             kickdown and the tip-out its rate a trapezoid (ramps no steeper
 *             than the slip jerk that gives the vehicle a design jerk through
 *             jerk_per_torque_rate, 12 m/s^3 for the kickdown, 3 for the
 *             tip-out; at least 0.4 T for the kickdown where the flat rate
 *             stays within what T_t can do, else down to T / 3, and T / 3 for
 *             the tip-out; a zero slope at synchronism), for the coast DESIGN
 *             10's smoothstep. The hold-back = feed-forward (T_t / I_t -
 *             dref/dt) / k_1 + PI(slip - reference) is the off-going request.
 *             Without the assist (the kickdown, the coast: the engine sets the
 *             pace) the on-coming clutch's fill is timed to arrive at
 *             synchronism: open until the reference leaves prepare_time_s to
 *             its end, then the fill pulse and the kiss point (filled early it
 *             drags across the whole slip: a tie-up); and a target faster than
 *             the turbine can be moved (by T_t; the coast: T_t0 +
 *             engine_increase_max_Nm) is stretched to the shortest reference
 *             it can follow (the flat rate within that torque / (1.15 I_t),
 *             the kickdown's ramps within its jerk; at most
 *             inertia_time_max_s). With it (the tip-out: a small
 *             drag would take seconds) a negative hold-back is the on-coming
 *             clutch's push, x k_1 / k_c, in the commanded time; once the
 *             hold-back is spent the off-going clutch opens for good. Ends as
 *             the torque-first inertia phase (the lock band's dwell, or the
 *             reference ended within min_start_slip_rad_s) or, where the
 *             off-going clutch no longer drives the slip (the tip-out's push,
 *             the coast's engine), when the slip reaches 0; flare: the slip
 *             above +flare_slip_rad_s (past synchronism).
 *   TORQUE    torque_phase_time_s at synchronism: the on-coming request
 *             rises on a smoothstep to holding_torque_factor x its carried
 *             torque (+ flare_kp x the slip past synchronism + flare_ki x its
 *             integral: the turbine running past is taken in closed loop;
 *             after a coast, below it: T_t < 0 drags the turbine back) while
 *             the off-going request falls from its last value to 0 on the
 *             same smoothstep (open at once when it held nothing or had
 *             opened for good); LOCKED once the on-coming clutch is locked
 *             and the ramp done; not locked after WC_SHIFT_LOCKUP_WAIT ramp
 *             times: AbortReason 2.
 *   LOCKED / ABORTED as the torque-first shift. A lost input (safe): before
 *             the torque phase handed back (the off-going clutch at its
 *             maximum current, AbortReason 3, fallback HANDBACK); from the
 *             torque phase on finished on the model (the ramps on time, never
 *             reported locked without the slip), released after
 *             fallback_time_s.
 * With WC_SHIFT_INERTIA_FIRST_ENGINE (the coast downshift, not mirrored: T_t
 * below the power-on type's, the engine cannot raise the turbine) the engine does the
 * inertia phase (DESIGN 15: "engine torque increase requested"): the request
 * I_t dref/dt - T_t0 at the reference engine_lead_time_s ahead, corrected by
 * the PI both ways (-PI k_1 I_t: more when the turbine lags, less when it
 * runs ahead) with its gains scaled to the engine's lag (kp to a crossover at
 * 1 / (2 engine_lead_time_s), ki by the square of that factor), within 0 ..
 * engine_increase_max_Nm (with T_t0 > 0, a pressed pedal or a converter's
 * creep, from -min(T_t0, engine_reduction_max_Nm), ramped in at 60 N m/s);
 * at synchronism cut to what cancels the drag and ramped out over the torque
 * phase. The off-going clutch carries what is left of the drag (with T_t0 > 0
 * the drive, |T_t|) with the margin while the engine's torque goes through 0,
 * at the latest for engine_lead_time_s (with T_t0 > 0 the ramp's time), then
 * opens for good; the target is
 * stretched to what T_t0 + engine_increase_max_Nm can do. The on-coming
 * clutch then never drags the vehicle into the turbine's acceleration.
 * Without it no engine request (engine_active false). No adaptation in this
 * type yet; the report's friction energy is both clutches' (the off-going one
 * does the inertia phase's work), its jerk that of the output torque T_c +
 * (b1 / b) T_1, tie_up never set (the plant measures it). */
#define WC_SHIFT_INERTIA_FIRST_ASSIST 1u  /* the tip-out: a negative hold-back is the on-coming clutch's push */
#define WC_SHIFT_INERTIA_FIRST_ENGINE 2u  /* the coast downshift: the engine request moves the turbine */
bool wc_shift_inertia_first_step(wc_shift_t *shift, const wc_shift_calibration_t *cal,
                                 const wc_shift_command_t *command, bool safe, uint32_t options, wc_clutch_t *clutch,
                                 wc_step_input_t *in, wc_step_output_t *out, wc_shift_report_t *report,
                                 wc_shift_offgoing_t *offgoing);

#endif /* WC_SHIFT_H */
