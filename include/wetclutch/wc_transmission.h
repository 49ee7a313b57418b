/* The shift elements of a clutch-to-clutch gearbox (DESIGN 15; issue 29):
 * one clutch model (observer, inverse, lock-up) per element, the closed
 * elements of a gear held at what they must carry plus a margin (the inverse
 * at the gear's slip, not the maximum current), and every single-element
 * shift of the gearbox's table run by one of the two shift controllers of
 * wc_shift.h on the shift's reduced model (the paper's §2 reduction,
 * wc_gearbox.h):
 *
 *   type (wc_gearbox_shift_type)  controller      frame     options (wc_shift.h)
 *   power-on upshift              wc_shift_step   as is     (today's 1->2 controller)
 *   power-off downshift (coast)   inertia-first   as is     WC_SHIFT_INERTIA_FIRST_ENGINE: the engine
 *                                                           request moves the turbine
 *   power-on downshift (kickdown) inertia-first   as is     none: T_t moves the turbine
 *   power-off upshift (tip-out)   inertia-first   mirrored  WC_SHIFT_INERTIA_FIRST_ASSIST: the on-coming
 *                                                           element's push
 *
 * Mirrored: the controller sees every speed, slip and torque negated (the
 * driveline's equations are odd in them, so a tip-out is a kickdown's
 * dynamics with the turbine torque -T_t >= 0, DESIGN 15); the engine request
 * it returns is negated back. The controller's clutches are
 * the on-coming and off-going elements as equivalent clutches in the
 * controller's coordinates (slip / a): radii x |a|, the squeeze-film
 * factor / a^4 and the open drag's aeration speed / |a|, so that the model's torque is |a| x the element's and its
 * sliding speed, film, friction and heat the element's own
 * (tools/wetclutch/shift/matrix8.py states the derivation); the element's
 * state (temperature, pressure, film, lock-up) carries over both ways.
 *
 * During a shift the two elements it keeps closed are held at their maximum
 * current (they carry the slipping elements' reactions and the inertia
 * torques besides T_t's share: not bounded by T_t).
 * In a gear the closed elements are held at the inverse at zero slip (a
 * gear slip, w_t - ratio w_o, tells that the box slips, not which element:
 * debounced, it holds them at the maximum current, below), an open element's
 * slip is its own (a w_t - b w_o of a shift from the gear: its drag heats it). The safe state (the caller's, or a
 * speed not valid) holds the closed elements at their maximum current (the
 * gear kept without inputs); a shift's own fallback is wc_shift.h's.
 * After a shift the elements hold the target gear when it completed or the
 * on-coming element had taken the gear (wc_shift_t.second_gear), else the
 * source gear (handed back). */
#ifndef WC_TRANSMISSION_H
#define WC_TRANSMISSION_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_clutch.h"
#include "wc_gearbox.h"
#include "wc_shift.h"

typedef struct {
    const wc_gearbox_t *gearbox;
    const wc_calibration_t *element[WC_GEARBOX_ELEMENTS_MAX];  /* each element's own clutch (pack, piston, spring, VFS) */
    const wc_shift_calibration_t *shift;  /* phases, gains, fill, engine, fallback; coordinator 1; its driveline
                                           * model is each shift's (wc_gearbox_shift_calibration) */
    float holding_margin_factor;          /* in a gear: request = |holding_torque_per_Nm x T_t| x this, in [1, 5];
                                           * the element's locked inverse adds its own holding_margin on top
                                           * (the 8HP's tools: 1.3 x 1.2 = 1.56 x the need; at 20 degC the
                                           * open elements' drag leaves A in 7th 1.22 in truth) */
    float holding_floor_Nm;               /* ... and at least this, in [0, 1e4] */
} wc_transmission_config_t;

/* What wc_transmission_init finds first (0 = valid). */
typedef enum {
    WC_TRANSMISSION_OK = 0,
    WC_TRANSMISSION_NULL,
    WC_TRANSMISSION_GEARBOX,        /* wc_gearbox_check failed */
    WC_TRANSMISSION_ELEMENT,        /* an element's calibration missing or invalid (wc_calibration_check) */
    WC_TRANSMISSION_SHIFT,          /* the shift calibration invalid, not coordinator 1, or invalid with a shift's
                                     * reduced model */
    WC_TRANSMISSION_HOLDING,        /* the holding margin or floor out of range */
    WC_TRANSMISSION_GEAR            /* the start gear is not a gear of the box */
} wc_transmission_error_t;

/* The shift request (DBC ShiftCommand with the current gear). */
typedef struct {
    bool request;                  /* 1: shift to target_gear; its rising edge in a gear starts the shift; 0 (or
                                    * another target) during a shift: cancelled */
    uint32_t current_gear;         /* the integrator's view: must be the gear the elements hold */
    uint32_t target_gear;
    float turbine_torque_Nm;       /* signed: > 0 the engine pulls (power-on), <= 0 it drags (power-off) */
    float target_inertia_time_s;
} wc_transmission_command_t;

typedef struct {
    float turbine_rad_s;           /* not finite or |.| > WC_SLIP_MAX_rad_s: invalid (the safe state) */
    float output_rad_s;
    float theta_oil_degC;
    float theta_housing_degC;
    bool safe;                     /* the frame loop's safe state (a lost, frozen or implausible input) */
} wc_transmission_input_t;

typedef struct {
    wc_step_output_t element[WC_GEARBOX_ELEMENTS_MAX];  /* each element's step (current_mA is its VFS command) */
    uint32_t gear;                 /* the gear the elements hold, or the running shift's source gear */
    uint32_t shift_phase;          /* wc_shift_phase_t of the running shift; IDLE in a gear */
    uint32_t shift_type;           /* wc_shift_type_t of the running (or last) shift */
    uint32_t refusal;              /* wc_gearbox_shift_result_t of the last request's edge (0: accepted) */
    bool engine_active;            /* DBC EngineTorqueRequest */
    float engine_delta_Nm;
} wc_transmission_output_t;

typedef struct {
    wc_clutch_t element[WC_GEARBOX_ELEMENTS_MAX];
    wc_step_input_t element_in[WC_GEARBOX_ELEMENTS_MAX];
    wc_calibration_t equivalent[2];      /* the running shift's on-coming [0] and off-going [1] element */
    wc_shift_calibration_t shift_cal;    /* the running shift's */
    wc_shift_t shift;
    const wc_gearbox_shift_t *row;       /* the running shift; NULL in a gear */
    const wc_gearbox_shift_t *gear_row;  /* a shift from the gear (its open elements' slips); NULL: none */
    uint32_t gear;
    uint32_t type;                       /* wc_shift_type_t */
    uint32_t refusal;
    uint64_t runnable;                   /* bit i: shift i's equivalent clutches are within the limits */
    float sign;                          /* 1, or -1: a power-off shift, mirrored */
    bool last_request;
    uint32_t gear_slip_periods;          /* consecutive periods of a gear slip beyond WC_TRANSMISSION_GEAR_SLIP_rad_s */
    bool gear_slipped;                   /* latched until the next shift: the gear held at the maximum current */
    /* DESIGN 12 per element: each element's learned values; a power-on upshift learns into its on-coming
     * element's (the running shift's adapt: its values in at the start, out at the end) when the shift
     * calibration's adaptation is 1. The inertia-first types do not learn yet. */
    wc_adapt_values_t learned[WC_GEARBOX_ELEMENTS_MAX];
    wc_adapt_t adapt;
} wc_transmission_t;

/* In a gear the closed elements are held at the inverse at zero slip; a gear
 * slip (turbine - ratio x output) beyond 5 rpm (issue 29's in-gear limit) for
 * WC_TRANSMISSION_GEAR_SLIP_PERIODS in a row (a slipping element, or a speed
 * sensor stuck at a plausible value) holds them at the maximum current until
 * the next shift: the holding never falls with the slip. */
#define WC_TRANSMISSION_GEAR_SLIP_rad_s 0.52f
#define WC_TRANSMISSION_GEAR_SLIP_PERIODS 20u

/* Check the configuration (the gearbox, every element, the shift calibration
 * with every shift's reduced model, the holding) and start in gear at
 * theta_start_degC. A shift whose equivalent clutch leaves the limits is
 * refused when requested (WC_GEARBOX_SHIFT_NO_MODEL), not here: the others run. */
wc_transmission_error_t wc_transmission_init(wc_transmission_t *tx, const wc_transmission_config_t *config,
                                             uint32_t gear, float theta_start_degC);

/* Element e's learned values (DESIGN 12): false for an element the gearbox
 * does not have. */
bool wc_transmission_learned(const wc_transmission_t *tx, uint32_t element, wc_adapt_values_t *values);

/* Load element e's learned values (from an adaptation image): refused
 * (false, nothing changed) during a shift, for an element the gearbox does
 * not have, or for values outside the shift calibration's bands
 * (wc_adapt_values_valid). */
bool wc_transmission_load_learned(wc_transmission_t *tx, const wc_transmission_config_t *config, uint32_t element,
                                  const wc_adapt_values_t *values);

/* Element e's values back to the calibration's (wc_adapt_reset): refused
 * during a shift or for an element the gearbox does not have. */
bool wc_transmission_reset_learned(wc_transmission_t *tx, const wc_transmission_config_t *config, uint32_t element);

/* One control period: the elements' inputs, their steps, the outputs.
 * Returns true when a shift ended this step (*report its quality vector, in
 * the controller's frame: magnitudes). out->element[e].current_mA is element
 * e's VFS command; out must hold the previous step's output (zero-initialised
 * before the first: the controllers' anti-windup reads its saturation). */
bool wc_transmission_step(wc_transmission_t *tx, const wc_transmission_config_t *config,
                          const wc_transmission_command_t *command, const wc_transmission_input_t *input,
                          wc_transmission_output_t *out, wc_shift_report_t *report);

/* The element's equivalent clutch in a shift's controller coordinates
 * (radii x |slip_scale|, film_squeeze_factor / slip_scale^4, the rest the
 * element's; film table shared). Returns wc_calibration_check of the result. */
wc_cal_error_t wc_transmission_equivalent(const wc_calibration_t *element, float slip_scale, wc_calibration_t *out);

#endif /* WC_TRANSMISSION_H */
