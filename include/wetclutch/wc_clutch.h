/* One on-coming clutch: the model, the observer and the VFS lag, advanced
 * one control period per wc_clutch_step. All state lives in wc_clutch_t,
 * owned by the caller; the calibration is shared read-only. */
#ifndef WC_CLUTCH_H
#define WC_CLUTCH_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_inverse.h"
#include "wc_lockup.h"
#include "wc_model.h"
#include "wc_status.h"
#include "wc_torque.h"

/* What the solenoid is asked to do. The values are those of the DBC signal
 * TorqueRequest.Mode (hil/wetclutch.dbc; the CAN layer static_asserts it), so
 * a zero-initialized input asks for the released clutch. */
typedef enum {
    WC_MODE_OPEN = 0,    /* minimum current: clutch released (also the safe state) */
    WC_MODE_TORQUE = 1,  /* invert the model to deliver torque_request_Nm */
    WC_MODE_LOCKED = 2   /* maximum current: clutch locked */
} wc_clutch_mode_t;

/* On a test bench, measurements the vehicle does not have. When valid, the
 * torque model uses the measured apply force (load cell) instead of the force
 * of the modelled VFS pressure, and the observer takes its heat input from the
 * measured torque: the paper validates the torque model (Fig. 15) and the
 * temperature estimate (Fig. 14) this way. */
typedef struct {
    bool valid;
    float apply_force_N;       /* load cell, >= 0 */
    float torque_Nm;           /* torque sensor, signed like the slip */
} wc_bench_input_t;

/* Lag compensation (DESIGN 9), made by wc_lag_compensation() once per setting
 * (its exponential is a per-shift constant, not a per-step one). Zero
 * (zero-initialized): off. */
typedef struct {
    float time_s;    /* t of the lead, in (0, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s] when on */
    float vfs_gain;  /* (1 - e^(-dt/t)) / (1 - e^(-dt/tau)): the VFS lag's inverse for t, > 0 when on */
} wc_lag_compensation_t;

/* The adaptation's correction of the model (DESIGN 12, wc_adapt.h), made by
 * wc_adapt_correction. Zero (zero-initialized): none, bit for bit the
 * calibration's model. A field outside its range (NaN included) voids the
 * whole correction (none; no status bit): the ranges are the widest bands a
 * shift calibration accepts. */
typedef struct {
    float friction_scale_delta;  /* mu_f (eq. 18) x (1 + this), within [-WC_CORRECTION_SCALE_MAX, WC_CORRECTION_SCALE_MAX] */
    float film_factor_delta;     /* the squeeze film's damping (DESIGN 9) x (1 + this), within [WC_CORRECTION_FILM_DELTA_MIN, WC_CORRECTION_FILM_DELTA_MAX] */
    float kiss_offset_N;         /* contact force = apply force - this (a later kiss point: > 0), |.| <= WC_CORRECTION_KISS_MAX_N */
} wc_model_correction_t;
#define WC_CORRECTION_SCALE_MAX 0.5f
#define WC_CORRECTION_FILM_DELTA_MIN (-0.995f)
#define WC_CORRECTION_FILM_DELTA_MAX 19.0f
#define WC_CORRECTION_KISS_MAX_N 5000.0f

typedef struct {
    float slip_rad_s;          /* clutch slip speed dw, signed */
    float theta_oil_degC;      /* oil (sump) temperature */
    float theta_housing_degC;  /* housing temperature */
    float torque_request_Nm;   /* wanted clutch torque, magnitude >= 0 (WC_MODE_TORQUE) */
    wc_clutch_mode_t mode;
    wc_bench_input_t bench;    /* zero-initialized: not on a bench */
    /* Lag compensation (DESIGN 9): off (zero-initialized) commands the steady
     * current of the wanted force and leaves the squeeze film and the VFS lag
     * (tau) to act; on (wc_lag_compensation() of a t > 0, WC_MODE_TORQUE) leads
     * both: with the film state on, the wanted apply force is raised so that
     * the film approaches the wanted contact force's film with time constant t
     * (never below the steady force), and the current leads the VFS lag so
     * that the modelled pressure approaches that force's pressure with time
     * constant t instead of tau; bounded to F_max and the solenoid's range.
     * A time outside (0, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s] or a gain that
     * is not finite and positive: off, WC_STATUS_INPUT_INVALID not set. */
    wc_lag_compensation_t lag_compensation;
    /* true: the model (inverse and torque) takes the oil temperature instead of
     * the observer's estimate (a thermal-blind model, for comparisons); the
     * observer keeps running. */
    bool theta_from_oil;
    /* The torque the clutch must carry once locked, for the lock-up decision
     * and the locked estimate (DESIGN 9), when the caller knows it better than
     * the request (a shift controller: the turbine torque's share while it
     * commands more to lock). 0 (zero-initialized), not finite or out of
     * range: the request. A bench's torque sensor takes precedence. */
    float carried_torque_Nm;
    /* The adaptation's correction (wc_adapt_correction); zero: none. */
    wc_model_correction_t correction;
    /* true (WC_MODE_TORQUE, slipping): a request below the drag the element
     * has at its kiss point retracts the piston into its return spring's band
     * (DESIGN 15: the pressure between the spring's preload and the kiss
     * point) by the fraction whose open drag is the request; 0 or less: all
     * the way, the spring's preload. An off-going element released under
     * control needs it: at its kiss point a dragging pack may carry all of a
     * light load; so does the on-coming element of a power-on upshift in its
     * torque and inertia phases, whose drag at a high slip or a light load
     * exceeds the request. Never above the learned kiss point (an earlier one would
     * apply the pack). false (zero-initialized): the inverse's floor is the
     * kiss point (the lead may still command below it for a period). Without
     * an open drag calibrated it changes nothing. */
    bool band_release;
} wc_step_input_t;

typedef struct {
    float current_mA;           /* VFS current command */
    float pressure_command_Pa;  /* the pressure wanted: K * current, or with the lag compensation the
                                 * pressure the led current drives the VFS towards */
    float pressure_model_Pa;    /* pressure the lagged VFS is modelled to reach */
    float force_command_N;      /* contact force the inverse asked for */
    float theta_degC;           /* friction-surface temperature used this step */
    float contact_force_N;      /* F_c the torque model used: the apply force, or the squeeze film's asperity force */
    float static_capacity_Nm;   /* static capacity at that force (DESIGN 9) */
    wc_torque_t model;          /* torque model at the modelled pressure; while locked the held torque */
    uint32_t inverse_iterations;
    wc_status_t status;
} wc_step_output_t;

/* The last valid value of each checked input. */
typedef struct {
    float slip_rad_s;
    float theta_oil_degC;
    float theta_housing_degC;
    float torque_request_Nm;
} wc_held_inputs_t;

typedef struct {
    wc_model_t model;
    float theta_degC;           /* observer state, in [WC_THETA_MIN_degC, WC_THETA_MAX_degC] */
    float pressure_model_Pa;    /* VFS lag state */
    wc_held_inputs_t held;
    float film_hbar_m;          /* squeeze-film state h_bar (DESIGN 9); the steady film when it is off */
    wc_lockup_t lockup;         /* slipping / locked (DESIGN 9) */
    bool over_temperature;      /* WC_STATUS_OVER_TEMPERATURE with hysteresis */
} wc_clutch_t;

/* Validate cal and start the observer at theta_start_degC (the oil
 * temperature is the usual choice). Returns the failing field, or WC_CAL_OK. */
wc_cal_error_t wc_clutch_init(wc_clutch_t *clutch, const wc_calibration_t *cal, float theta_start_degC);

/* One control period:
 *  1. each input is checked; an invalid one is replaced by its last valid
 *     value (held) and flagged, so one bad sample changes no state with a
 *     bad number;
 *  2. WC_MODE_TORQUE: inverse at the current temperature estimate (or the oil
 *     temperature, theta_from_oil) -> current command (a locked clutch: the
 *     force that holds the request with the holding margin), then led ahead
 *     of the VFS lag when the lag compensation is on; WC_MODE_OPEN / WC_MODE_LOCKED: the solenoid's minimum /
 *     maximum current (an unknown mode counts as WC_MODE_OPEN and is flagged
 *     WC_STATUS_TORQUE_INVALID);
 *  3. VFS lag -> modelled pressure -> apply force (on a bench: the measured
 *     apply force) -> contact force (the apply force, eq. 16; with the film
 *     state on, the asperity force at the squeeze film, which then advances
 *     under the apply force) -> torque model;
 *  4. lock-up (wc_lockup.h) with the torque the clutch must carry (on a
 *     bench: the measured torque; else carried_torque_Nm or the request, in
 *     the lock direction)
 *     against the static capacity; while locked the estimate is the held
 *     torque (wc_lockup_torque_Nm) and WC_STATUS_LOCKED is set;
 *  5. observer advanced with P = |T dw| (0 while locked), T the model torque
 *     (on a bench: the measured torque), kept in the thermal envelope; above
 *     WC_THETA_OVER_degC WC_STATUS_OVER_TEMPERATURE is set until the estimate
 *     falls WC_THETA_OVER_HYSTERESIS_K below it. Implausible bench values are
 *     flagged and not used.
 * out->theta_degC is the estimate before this step's update. A NULL pointer
 * or an instance whose init failed (or never ran: zero-filled) is a contract
 * violation: WC_ASSERT, and with asserts off zero outputs (0 mA) and
 * WC_STATUS_NOT_INITIALISED. */
wc_status_t wc_clutch_step(wc_clutch_t *clutch, const wc_step_input_t *in, wc_step_output_t *out);

/* The lag compensation of time constant time_s for this clutch's calibration
 * (DESIGN 9), for wc_step_input_t.lag_compensation: computed once, used every
 * step. time_s outside (0, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s] (NaN
 * included), or a clutch whose init failed: off (zeros). NULL: WC_ASSERT, off. */
wc_lag_compensation_t wc_lag_compensation(const wc_clutch_t *clutch, float time_s);

#endif /* WC_CLUTCH_H */
