/* Adaptation: learning the clutch in the vehicle from the shift's own data
 * (DESIGN 12). Per clutch, from what a vehicle TCU measures (the slip, the
 * engine's turbine torque estimate, the oil and housing temperatures), never
 * from a load cell:
 *   - a friction scale at WC_ADAPT_NODES friction-surface temperatures (the
 *     observer's theta, eq. 1), interpolated linearly between the nodes and
 *     held beyond them; it multiplies mu_f (eq. 18) in the torque model and the
 *     inverse (wc_model_correction_t);
 *   - the squeeze-film factor (DESIGN 9), as a multiplier of the calibration's;
 *   - the kiss point, as a pressure offset from the calibration's
 *     (return_spring_force / piston_area).
 * The shift controller (wc_shift.c) feeds the inertia phase's samples to
 * wc_adapt_sample and calls wc_adapt_finish when the shift ends; the learned
 * values change only there, only after a valid shift, each at most by its
 * per-shift step and always inside its band (the shift calibration's
 * adapt_* fields, wc_shift.h). State: wc_adapt_t (caller-owned, one per
 * clutch); wc_adapt_values_t is what persists (wc_adapt_image.h).
 *
 * The measurement (DESIGN 10, 12). In the inertia phase the off-going clutch
 * is open and the driveline model gives the clutch torque from the slip:
 *     d(slip)/dt = a T_t / I_t - T_c (a^2 / I_t + b^2 / I_out)
 *  => T_imp = (drive - d(slip)/dt) / m,  drive = a T_t / I_t,  m = a^2/I_t + b^2/I_out,
 * (the turbine-side form a T_c = T_t - I_t dw_t/dt of DESIGN 12 needs the
 * turbine speed, which the DBC does not carry; the slip form uses the same
 * driveline model as the feed-forward, and the output side's share b^2/I_out
 * is 2 % of m). Sample j of the window pairs the model's torque of the
 * previous period (the torque of the pressure the plant saw over the period)
 * with the slip change over it:
 *     T_imp,j = (drive_{j-1} - (slip_j - slip_{j-1}) / dt) / m.
 * The window: from adapt_window_skip_s after the inertia phase's start (the
 * off-going clutch's last torque) while the slip stays above
 * min_start_slip_rad_s (near the lock the plant may stick: no kinetic
 * torque), to the end of the inertia phase; the window closes for good at
 * the first slip at or below it (a slip that comes back is not paired with
 * the sample before the gap). A sample with a non-finite value marks the
 * window invalid (fault) and is not used. The early part (the film factor's)
 * is the samples j with (j - 1) dt < adapt_film_window_s.
 *
 * The update (wc_adapt_finish), of a valid shift only: completed (no abort,
 * so no safe state), no invalid input during the window, at least one sample,
 * the slip fallen by adapt_min_slip_drop of its value at the window's start,
 * sum T_model > 0 and rho within [WC_ADAPT_RHO_MIN, WC_ADAPT_RHO_MAX]:
 *   - friction scale: rho = sum T_imp / sum T_model (the model torque already
 *     carries the learned scale, so rho is the remaining error); node i's
 *     share q_i = W_i / sum W, W_i = sum over the samples of w_i(theta) T_model
 *     (w_i: the interpolation weight of node i at the sample's theta, so a
 *     node learns only from the temperatures near it). Then, normalised so
 *     that the interpolated scale at the window's temperatures moves by the
 *     gain times its error (Q = sum_j q_j^2 > 0):
 *         a_i = clip(adapt_scale_gain (q_i / Q) s_i (rho - 1), +-adapt_scale_step (1 - c_i / 2))
 *     (node i's own step; c_i the confidence before the update: a confident
 *     node's own step is at most half a step, so one faulty shift costs it
 *     less), the window's interpolated scale after the own steps
 *     L = sum_j q_j (s_j + a_j), and
 *         s_i += clip(c_i a_i + (1 - c_i) (L - s_i), +-adapt_scale_step),
 *     clipped to [1 - adapt_scale_band, 1 + adapt_scale_band]: a node not yet
 *     learned takes the window's scale, a smooth prior, at most a step per
 *     shift. It holds the level the learned nodes hold, whatever the shares
 *     of the windows; a node that took each shift's error itself (or each
 *     shift's change of the window's scale), outside every window and so
 *     without feedback through rho, summed the errors and drifted (issue 31,
 *     three low phases of the drive cycle: element C's 120 degC node at 1.25
 *     against a truth of 1.015, its 80 degC node at 1.07);
 *         c_i += adapt_confidence_gain q_i (1 - c_i)   (confidence, 0..1).
 *   - kiss point: least squares of the residual r = T_imp - T_model on
 *     x1 = the model's Coulomb torque and x2 = its Coulomb torque per newton
 *     of contact force (r = (s - 1) x1 - s dF x2 for a contact force dF lower
 *     than modelled): with the normal equations' determinant
 *     D = S11 S22 - S12^2 and D / (S11 S22) >= adapt_min_conditioning
 *     (the force varied enough to tell an offset from a scale),
 *         b1 = (S22 S1r - S12 S2r) / D, b2 = (S11 S2r - S12 S1r) / D,
 *         dP = -b2 / (1 + b1) / A_p   (1 + b1 >= 0.5, else no kiss update),
 *         kiss += clip(adapt_kiss_gain dP, +-adapt_kiss_step_Pa), clipped to +-adapt_kiss_band_Pa.
 *   - film factor (the clutch's film state on): rho_e = the same ratio over
 *     the window's first adapt_film_window_s; a film slower than modelled
 *     gives less torque early than late (rho_e < rho):
 *         f *= 1 + clip(adapt_film_gain (rho / rho_e - 1), +-adapt_film_step),
 *     clipped to [adapt_film_factor_min, adapt_film_factor_max]
 *     (rho_e and the early sums > 0, else no film update).
 * A shift that is not valid changes nothing (the report says why).
 *
 * Every output is finite for every input: the learned values are checked
 * when loaded (wc_adapt_image.h) and clipped when learned, NaN samples mark
 * the window invalid. All loops are bounded by WC_ADAPT_NODES. */
#ifndef WC_ADAPT_H
#define WC_ADAPT_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_clutch.h"

#define WC_ADAPT_NODES 5u
/* The plausible range of one shift's torque ratio rho: outside, the shift is
 * not used (a sensor or estimate fault, not a clutch). */
#define WC_ADAPT_RHO_MIN 0.5f
#define WC_ADAPT_RHO_MAX 2.0f

/* The adaptation's calibration: fields of wc_shift_calibration_t (adapt_*,
 * checked by wc_shift_calibration_check), read through this view. */
struct wc_shift_calibration;

/* What persists per clutch (the adaptation image's payload). The defaults
 * (wc_adapt_reset): scales 1, confidences 0, film factor 1, kiss offset 0. */
typedef struct {
    float friction_scale[WC_ADAPT_NODES];  /* multiplies mu_f at node i's temperature */
    float confidence[WC_ADAPT_NODES];      /* 0 (never learned) .. 1 */
    float film_factor;                     /* multiplies film_squeeze_factor */
    float kiss_offset_Pa;                  /* learned kiss pressure minus the calibration's */
    uint32_t shifts_learned;               /* valid shifts that updated the values (saturates) */
} wc_adapt_values_t;

/* Why a finished shift did (not) update the values (DBC AdaptationReport.Result). */
typedef enum {
    WC_ADAPT_RESULT_OFF = 0,            /* adaptation switched off (adaptation = 0) */
    WC_ADAPT_RESULT_UPDATED = 1,
    WC_ADAPT_RESULT_ABORTED = 2,        /* the shift did not complete (safe state included) */
    WC_ADAPT_RESULT_INPUT_FAULT = 3,    /* an input was invalid during the window */
    WC_ADAPT_RESULT_EXCITATION = 4,     /* no sample, or the slip did not fall enough */
    WC_ADAPT_RESULT_IMPLAUSIBLE = 5     /* rho outside [WC_ADAPT_RHO_MIN, WC_ADAPT_RHO_MAX] */
} wc_adapt_result_t;

/* Status bits of wc_adapt_t.status (sticky until the next load or reset). */
#define WC_ADAPT_STATUS_IMAGE_MISSING 1u    /* no image at init: the calibration's values */
#define WC_ADAPT_STATUS_IMAGE_INVALID 2u    /* bad magic, version, length, CRC or value: the calibration's values */
#define WC_ADAPT_STATUS_RESET 4u            /* reset by command since the last load */

/* What one shift changed (the report's adaptation part). */
typedef struct {
    uint32_t result;                /* wc_adapt_result_t */
    uint32_t node;                  /* the node with the largest share */
    float friction_scale;           /* that node's scale after the shift */
    float friction_scale_change;    /* and its change by the shift */
    float confidence;               /* that node's confidence after the shift */
    float film_factor;              /* after the shift */
    float film_factor_change;
    float kiss_offset_Pa;           /* after the shift */
    float kiss_offset_change_Pa;
} wc_adapt_change_t;

/* The running window of the inertia phase (reset at each shift's start). */
typedef struct {
    bool started;                   /* the window's first sample is in */
    bool fault;                     /* an invalid input (status bit or non-finite value) in the window */
    bool closed;                    /* the slip fell to min_start_slip_rad_s: no more samples this shift */
    uint32_t samples;
    float slip_start_rad_s;         /* at the window's start */
    float slip_prev_rad_s;
    float drive_prev_rad_s2;        /* a T_t / I_t of the previous period */
    float model_prev_Nm;            /* the previous period's model torque, its Coulomb part, per newton */
    float coulomb_prev_Nm;
    float coulomb_per_N_prev;
    float theta_prev_degC;
    float sum_model_Nm;             /* sums over the window's samples */
    float sum_implied_Nm;
    float sum_model_early_Nm;       /* over its first adapt_film_window_s */
    float sum_implied_early_Nm;
    float weight_Nm[WC_ADAPT_NODES];
    /* the kiss point's normal equations: x1 in Nm, x2 in Nm/N, r in Nm */
    float s11_Nm2, s12_Nm2_per_N, s22_Nm2_per_N2, s1r_Nm2, s2r_Nm2_per_N;
} wc_adapt_window_t;

typedef struct {
    wc_adapt_values_t values;
    wc_adapt_window_t window;
    uint32_t status;                /* WC_ADAPT_STATUS_* */
} wc_adapt_t;

/* The calibration's values (defaults); status unchanged. */
void wc_adapt_reset(wc_adapt_t *adapt);

/* A reset by command (DBC ShiftCommand.AdaptationReset): the calibration's
 * values and WC_ADAPT_STATUS_RESET; returns what to report (result OFF, the
 * defaults). NULL: WC_ASSERT, the report only. */
wc_adapt_change_t wc_adapt_command_reset(wc_adapt_t *adapt);

/* Values inside the bands of cal (finite, confidences in [0, 1]): true. */
bool wc_adapt_values_valid(const wc_adapt_values_t *values, const struct wc_shift_calibration *cal);

/* The model correction of the learned values for a clutch at theta_degC
 * (wc_step_input_t.correction): the interpolated scale, the film factor, the
 * kiss offset as a force (times the piston area). Adaptation off (cal's
 * adaptation 0), or adapt NULL: no correction (zeros). */
wc_model_correction_t wc_adapt_correction(const wc_adapt_t *adapt, const struct wc_shift_calibration *cal,
                                          const wc_clutch_t *clutch, float theta_degC);

/* Start a shift's window. */
void wc_adapt_begin(wc_adapt_t *adapt);

/* One inertia-phase period after the clutch step: elapsed_s since the phase
 * start, the slip the controller used, drive_rad_s2 = a T_t / I_t,
 * inverse_inertia = a^2/I_t + b^2/I_out, the clutch step's output. */
void wc_adapt_sample(wc_adapt_t *adapt, const struct wc_shift_calibration *cal, float elapsed_s, float slip_rad_s,
                     float drive_rad_s2, float inverse_inertia, const wc_clutch_t *clutch,
                     const wc_step_output_t *out);

/* The shift ended (completed: abort_reason 0): the update above. Returns what
 * it changed (adaptation off: result OFF, nothing changed). */
wc_adapt_change_t wc_adapt_finish(wc_adapt_t *adapt, const struct wc_shift_calibration *cal, uint32_t abort_reason,
                                  const wc_clutch_t *clutch);

#endif /* WC_ADAPT_H */
