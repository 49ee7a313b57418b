#include "wetclutch/wc_clutch.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "wc_film_internal.h"
#include "wetclutch/wc_film.h"
#include "wetclutch/wc_hydraulics.h"
#include "wc_internal.h"
#include "wetclutch/wc_thermal.h"
#include "wc_lockup_internal.h"
#include "wc_operating_point.h"

/* DESIGN section 3 / issue "state <= 64 B per clutch" (60 B on Cortex-M4F, 64 B on a 64-bit host). */
WC_STATIC_ASSERT(sizeof(wc_clutch_t) <= 64u, clutch_state_fits_in_64_bytes);

wc_cal_error_t wc_clutch_init(wc_clutch_t *clutch, const wc_calibration_t *cal, float theta_start_degC)
{
    WC_ASSERT(clutch != NULL);
    if (clutch == NULL) { return WC_CAL_NULL; }
    const wc_cal_error_t error = wc_model_init(&clutch->model, cal);
    if (error != WC_CAL_OK) { return error; }
    const float theta = wc_theta_valid(theta_start_degC) ? theta_start_degC : cal->theta1_degC;
    clutch->theta_degC = theta;
    clutch->pressure_model_Pa = cal->vfs_gain_Pa_per_mA * cal->vfs_current_min_mA;  /* VFS at rest */
    clutch->held.slip_rad_s = 0.0f;
    clutch->held.theta_oil_degC = theta;
    clutch->held.theta_housing_degC = theta;
    clutch->held.torque_request_Nm = 0.0f;
    clutch->over_temperature = false;
    /* the film settled under the force of the VFS at rest */
    clutch->film_hbar_m = wc_film_hbar_m(&cal->film, wc_contact_force_at(cal, clutch->pressure_model_Pa) /
                                                         cal->friction_area_m2);
    wc_lockup_init(&clutch->lockup);
    return WC_CAL_OK;
}

/* Replace each invalid input by its last valid value; remember the valid ones. */
static wc_status_t accept_inputs(wc_held_inputs_t *held, const wc_step_input_t *in)
{
    wc_status_t status = WC_STATUS_OK;
    if (wc_slip_valid(in->slip_rad_s)) { held->slip_rad_s = in->slip_rad_s; }
    else { status |= WC_STATUS_SLIP_INVALID; }
    if (wc_theta_valid(in->theta_oil_degC)) { held->theta_oil_degC = in->theta_oil_degC; }
    else { status |= WC_STATUS_THETA_INVALID; }
    if (wc_theta_valid(in->theta_housing_degC)) { held->theta_housing_degC = in->theta_housing_degC; }
    else { status |= WC_STATUS_THETA_INVALID; }
    if (wc_in_range(in->torque_request_Nm, 0.0f, WC_TORQUE_MAX_Nm)) { held->torque_request_Nm = in->torque_request_Nm; }
    else { status |= WC_STATUS_TORQUE_INVALID; }
    return status;
}

/* A lag compensation time in (0, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s]; NaN is not. */
static bool lag_time_valid(float time_s)
{
    return (time_s > 0.0f) && (time_s <= WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s);
}

/* DESIGN 9, hydraulic lag: the VFS lag is P' = P + (K i - P)(1 - d), d = e^(-dt/tau)
 * (exact for i held over the period). To move the modelled pressure towards
 * the wanted P* as a lag of time constant t would, P' = P + (P* - P)(1 - e^(-dt/t)),
 * the current must be K i = P + (P* - P)(1 - e^(-dt/t)) / (1 - d): a bounded
 * inverse of the lag, the current clamped to the solenoid's range. t >= tau
 * asks for no lead (the factor <= 1 is kept: a slower, smoother approach).
 * The factor is wc_lag_compensation_t.vfs_gain (wc_lag_compensation). */
static wc_status_t lead_lag(const wc_model_t *model, float pressure_Pa, float gain, wc_inverse_t *inv)
{
    const wc_calibration_t *cal = model->cal;
    const float wanted_Pa = cal->vfs_gain_Pa_per_mA * inv->current_mA;
    const float current_mA = (pressure_Pa + (wanted_Pa - pressure_Pa) * gain) / cal->vfs_gain_Pa_per_mA;
    if (current_mA > cal->vfs_current_max_mA) {
        inv->current_mA = cal->vfs_current_max_mA;
        return WC_STATUS_CURRENT_CLAMPED;
    }
    if (current_mA < cal->vfs_current_min_mA) {
        inv->current_mA = cal->vfs_current_min_mA;
        return WC_STATUS_CURRENT_CLAMPED;
    }
    inv->current_mA = current_mA;
    return WC_STATUS_OK;
}

/* DESIGN 12: the learned kiss point moves the return spring's preload by the
 * offset, both ways: P = (F + F_s + offset) / A_p, at least 0 (F, offset finite
 * and bounded: the inverse's force, the accepted correction). */
static float kiss_pressure_Pa(const wc_calibration_t *cal, float force_N, float kiss_offset_N)
{
    const float pressure_Pa = (force_N + cal->return_spring_force_N + kiss_offset_N) / cal->piston_area_m2;
    return (pressure_Pa > 0.0f) ? pressure_Pa : 0.0f;
}

/* DESIGN 9, squeeze film, the lead's first half: the apply force that moves
 * the film state h_bar towards the film h_bar* of the wanted contact force
 * as a first-order approach of time t would, from F_app = F_c(h_bar) +
 * D mu_v (-dh_bar/dt) / h_bar^3 with dh_bar/dt = (h_bar* - h_bar) / t; never
 * below the wanted force (the steady command), at most F_max. The piston
 * pressure of that force, as a current, goes to lead_lag. contact_Pa is the
 * asperity pressure p_c(h_bar) of the film state (film on; t in range: the caller's checks). */
static void lead_film(const wc_model_t *model, float hbar_m, float contact_Pa, float damping_N_s_m2, float time_s,
                      uint32_t film_segment, float kiss_offset_N, wc_inverse_t *inv)
{
    const wc_calibration_t *cal = model->cal;
    const float contact_N = cal->friction_area_m2 * contact_Pa;
    /* the inverse found the force on film_segment: the lookup starts there */
    const float target_hbar_m = wc_film_hbar_near_m(&cal->film, inv->force_N / cal->friction_area_m2, film_segment);
    if (!(hbar_m > target_hbar_m)) { return; }  /* at or past the wanted film: the steady force */
    const float squeeze_N = damping_N_s_m2 * (hbar_m - target_hbar_m) /
                            (time_s * hbar_m * hbar_m * hbar_m);  /* h_bar >= the table's minimum: finite */
    float force_N = contact_N + squeeze_N;
    if (!(force_N > inv->force_N)) { return; }
    force_N = (force_N < model->force_max_N) ? force_N : model->force_max_N;
    /* the pressure of F plus the learned kiss offset (DESIGN 12); the current clamped to the solenoid's range */
    (void)wc_vfs_current_mA(cal, kiss_pressure_Pa(cal, force_N, kiss_offset_N), &inv->current_mA);
}

/* DESIGN 15, the open element's drag: with the piston off the pack the viscous term shears the film h_bar
 * plus the retracted stroke's clearance per gap, and the open pack's aeration divides it by 1 + (slip / w_a)^2.
 * The piston strokes against its return spring, whose force rises from its preload at the retracted end
 * (WC_SPRING_PRELOAD_FRACTION x F_s) to F_s at the pack (the kiss point): with P A_p between the two it stands
 * in between, retracted by the fraction r = (F_s - P A_p) / ((1 - preload) F_s) in [0, 1] (the spring's rate),
 * and the gap is (h_bar + r clearance) (1 + r (slip / w_a)^2): at the kiss point the film alone, as the plates
 * shear it there, fully retracted the clearance and the whole aeration. h_bar <= 1 mm, clearance <= 5 mm, the
 * factor in [1, 1.1e6] (the calibration's limits, |slip| <= WC_SLIP_MAX_rad_s): finite, >= h_bar, so the torque
 * stays finite and only falls. Off (both 0) or applied (r = 0): h_bar, bit for bit. */
#define WC_SPRING_PRELOAD_FRACTION 0.8f

static inline float retracted_fraction(const wc_calibration_t *cal, float pressure_Pa)
{
    const float spring_N = cal->return_spring_force_N;
    const float piston_N = pressure_Pa * cal->piston_area_m2;
    const float band_N = (1.0f - WC_SPRING_PRELOAD_FRACTION) * spring_N;
    if (!(band_N > 0.0f)) { return (piston_N > 0.0f) ? 0.0f : 1.0f; }  /* no spring (F_s 0): no band */
    const float r = (spring_N - piston_N) / band_N;
    return (r > 0.0f) ? ((r < 1.0f) ? r : 1.0f) : ((r <= 0.0f) ? 0.0f : 1.0f);  /* NaN: retracted */
}

/* retracted_fraction's inverse: the pressure that stands the piston off the pack by the fraction r */
static inline float band_pressure_Pa(const wc_calibration_t *cal, float retracted)
{
    return cal->return_spring_force_N * (1.0f - retracted * (1.0f - WC_SPRING_PRELOAD_FRACTION)) / cal->piston_area_m2;
}

static inline float open_gap_m(const wc_calibration_t *cal, float hbar_m, float retracted, float slip_rad_s)
{
    float gap_m = hbar_m;
    if (retracted > 0.0f) {
        gap_m += retracted * cal->open_clearance_m;
        if (cal->open_aeration_speed_rad_s > 0.0f) {
            const float aeration = slip_rad_s / cal->open_aeration_speed_rad_s;
            gap_m *= 1.0f + retracted * aeration * aeration;
        }
    }
    return gap_m;
}

/* DESIGN 15, the release into the band (wc_step_input_t.band_release): the retracted fraction r whose viscous
 * drag at the point is viscous_Nm (the request less the film's contact torque), the inverse of open_gap_m:
 * gap(r) = (h_bar + r c)(1 + r a^2) = G = T_v0 / viscous_Nm, a = slip / w_a, T_v0 the point's viscous
 * torque times its gap. The quadratic c a^2 r^2 + (c + h_bar a^2) r - (G - h_bar) = 0 in the form without a
 * cancellation, r = 2 (G - h_bar) / (B + sqrt(B^2 + 4 c a^2 (G - h_bar))), B = c + h_bar a^2; 0 where the
 * film alone drags less than wanted (G <= h_bar), 1 where even the whole gap drags more (and for a request
 * at or below 0), so G - h_bar <= gap(1) - h_bar stays bounded (h_bar <= 1 mm, c <= 5 mm, a^2 <= 1.1e6). */
static float band_fraction(const wc_calibration_t *cal, const wc_torque_point_t *point, float viscous_Nm,
                           float hbar_m, float slip_rad_s)
{
    const float whole_gap_m = open_gap_m(cal, hbar_m, 1.0f, slip_rad_s);
    if (!(viscous_Nm > 0.0f) || !(point->viscous_Nm_m < viscous_Nm * whole_gap_m)) { return 1.0f; }  /* NaN: 1 */
    const float excess_m = point->viscous_Nm_m / viscous_Nm - hbar_m;  /* G - h_bar, < gap(1) - h_bar */
    if (!(excess_m > 0.0f)) { return 0.0f; }
    const float a = (cal->open_aeration_speed_rad_s > 0.0f) ? (slip_rad_s / cal->open_aeration_speed_rad_s) : 0.0f;
    const float c_m = cal->open_clearance_m;
    const float b_m = c_m + hbar_m * a * a;  /* 0 only with no clearance at zero slip, where T_v0 = 0 returned above */
    const float r = 2.0f * excess_m / (b_m + sqrtf(b_m * b_m + 4.0f * c_m * a * a * excess_m));
    return (r > 0.0f) ? ((r < 1.0f) ? r : 1.0f) : 0.0f;
}

/* DESIGN 15: a request below the kiss point's drag, into the spring's band: the fraction (before the learned
 * kiss offset, as the forward model's retracted fraction) whose drag is the request less the film's contact
 * torque; film: the film state hbar_m (else the steady film at zero force). Never above the learned
 * kiss point (an earlier one, offset < 0, would apply the pack in the band). */
static wc_status_t release_into_band(const wc_calibration_t *c, const wc_torque_point_t *point, bool film,
                                     float film_hbar_m, float contact_Pa, const wc_held_inputs_t *u,
                                     float kiss_offset_N, wc_inverse_t *inv)
{
    const float hbar_m = film ? film_hbar_m : wc_film_hbar_near_m(&c->film, 0.0f, WC_FILM_NO_SEGMENT);
    const float contact_Nm = film ? (point->coulomb_Nm_per_N * c->friction_area_m2 * contact_Pa) : 0.0f;
    const float band_Pa = band_pressure_Pa(c, band_fraction(c, point, u->torque_request_Nm - contact_Nm, hbar_m,
                                                            u->slip_rad_s));
    const float kiss_Pa = kiss_pressure_Pa(c, 0.0f, kiss_offset_N);
    inv->pressure_Pa = (band_Pa < kiss_Pa) ? band_Pa : kiss_Pa;
    return wc_vfs_current_mA(c, inv->pressure_Pa, &inv->current_mA);
}

/* x != 0 without a float equality (-Wfloat-equal); false for NaN. */
static bool nonzero(float x) { return (x < 0.0f) || (x > 0.0f); }

/* Any field of the correction set (a bit pattern other than +0): one test on
 * the plain step's path instead of the range checks. */
static bool correction_present(const wc_model_correction_t *c)
{
    uint32_t scale, film, kiss;
    memcpy(&scale, &c->friction_scale_delta, sizeof scale);
    memcpy(&film, &c->film_factor_delta, sizeof film);
    memcpy(&kiss, &c->kiss_offset_N, sizeof kiss);
    return (scale | film | kiss) != 0u;
}

/* The adaptation's correction (DESIGN 12) if every field is in its range, else none. */
static wc_model_correction_t accept_correction(const wc_model_correction_t *c)
{
    const wc_model_correction_t none = { 0.0f, 0.0f, 0.0f };
    const bool valid = (c->friction_scale_delta >= -WC_CORRECTION_SCALE_MAX) &&
                       (c->friction_scale_delta <= WC_CORRECTION_SCALE_MAX) &&
                       (c->film_factor_delta >= WC_CORRECTION_FILM_DELTA_MIN) &&
                       (c->film_factor_delta <= WC_CORRECTION_FILM_DELTA_MAX) &&
                       (c->kiss_offset_N >= -WC_CORRECTION_KISS_MAX_N) && (c->kiss_offset_N <= WC_CORRECTION_KISS_MAX_N);
    return valid ? *c : none;
}

/* The inverse's contact force commanded with the learned kiss point: the
 * current of that pressure, in the solenoid's range. */
static wc_status_t shift_kiss(const wc_calibration_t *cal, float kiss_offset_N, wc_inverse_t *inv)
{
    inv->pressure_Pa = kiss_pressure_Pa(cal, inv->force_N, kiss_offset_N);
    return wc_vfs_current_mA(cal, inv->pressure_Pa, &inv->current_mA);
}

wc_status_t wc_clutch_step(wc_clutch_t *clutch, const wc_step_input_t *in, wc_step_output_t *out)
{
    WC_ASSERT((clutch != NULL) && (in != NULL) && (out != NULL));
    WC_ASSERT((clutch == NULL) || (clutch->model.cal != NULL));  /* initialised, and its init succeeded */
    if ((clutch == NULL) || (in == NULL) || (out == NULL)) { return WC_STATUS_NOT_INITIALISED; }
    if (clutch->model.cal == NULL) {
        static const wc_step_output_t released = { 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                                                   { 0.0f, 0.0f, 0.0f, 0.0f, 0.0f }, 0u, WC_STATUS_NOT_INITIALISED };
        *out = released;  /* no calibration: no current at all */
        return WC_STATUS_NOT_INITIALISED;
    }
    const wc_model_t *model = &clutch->model;
    wc_status_t status = accept_inputs(&clutch->held, in);
    const wc_held_inputs_t *u = &clutch->held;

    /* The inverse and the forward torque see the same (slip, theta): mu_f and
     * mu_v once per step. Every input of the point is valid: the held slip and
     * request by accept_inputs, the estimate by init and the thermal envelope,
     * the held oil temperature by accept_inputs. */
    out->theta_degC = in->theta_from_oil ? u->theta_oil_degC : clutch->theta_degC;
    WC_ASSERT(wc_theta_valid(out->theta_degC));
    wc_torque_point_t point;
    wc_torque_point(model, u->slip_rad_s, out->theta_degC, &point);
    float static_Nm_per_N = wc_static_capacity_Nm_per_N(model, &point);
    const bool corrected = correction_present(&in->correction);  /* DESIGN 12; absent: the calibration's model */
    wc_model_correction_t correction = { 0.0f, 0.0f, 0.0f };
    if (corrected) { correction = accept_correction(&in->correction); }
    if (corrected && nonzero(correction.friction_scale_delta)) {
        /* DESIGN 12: the learned friction scale corrects mu_f (eq. 18), kinetic and static */
        const float scale = 1.0f + correction.friction_scale_delta;
        point.mu_f *= scale;
        point.coulomb_Nm_per_N *= scale;
        static_Nm_per_N *= scale;
    }
    wc_inverse_t inv;
    uint32_t film_segment = WC_FILM_NO_SEGMENT;  /* of the commanded force: where the lookups below start */
    if ((in->mode == WC_MODE_TORQUE) && clutch->lockup.locked) {
        status |= wc_inverse_holding(model, static_Nm_per_N, u->torque_request_Nm, &inv);  /* DESIGN 9 */
    } else if (in->mode == WC_MODE_TORQUE) {
        status |= wc_inverse_at_point(model, &point, u->torque_request_Nm, &inv, &film_segment);
    } else {
        if (in->mode != WC_MODE_LOCKED && in->mode != WC_MODE_OPEN) { status |= WC_STATUS_TORQUE_INVALID; }
        const wc_calibration_t *cal = model->cal;
        inv.current_mA = (in->mode == WC_MODE_LOCKED) ? cal->vfs_current_max_mA : cal->vfs_current_min_mA;
        inv.force_N = wc_contact_force_at(cal, cal->vfs_gain_Pa_per_mA * inv.current_mA);
        inv.pressure_Pa = cal->vfs_gain_Pa_per_mA * inv.current_mA;
        inv.iterations = 0u;
    }
    if (corrected && (in->mode == WC_MODE_TORQUE) && nonzero(correction.kiss_offset_N)) {
        status |= shift_kiss(model->cal, correction.kiss_offset_N, &inv);
    }
    /* DESIGN 9: the asperity contact of the film state, once per period: the
     * lead, the torque and the film's advance share it. */
    const bool film = model->film_damping_m4 > 0.0f;
    /* the squeeze film's damping at this viscosity, times the learned film factor (DESIGN 9, 12) */
    float damping_N_s_m2 = model->film_damping_m4 * point.viscosity_Pa_s;
    if (corrected) { damping_N_s_m2 *= 1.0f + correction.film_factor_delta; }
    const float hbar_m = clutch->film_hbar_m;
    wc_film_contact_t contact = { 0.0f, 0.0f };
    if (film) { contact = wc_film_contact(&model->cal->film, hbar_m); }
    /* (from the calibration each step: a flag in wc_model_t would take the clutch past its 64 B) */
    const bool open_drag = (model->cal->open_clearance_m > 0.0f) || (model->cal->open_aeration_speed_rad_s > 0.0f);
    if (in->band_release && open_drag && (in->mode == WC_MODE_TORQUE) && !clutch->lockup.locked &&
        !(inv.force_N > 0.0f)) {
        status |= release_into_band(model->cal, &point, film, hbar_m, contact.pressure_Pa, u, correction.kiss_offset_N,
                                    &inv);
    }
    const wc_lag_compensation_t *lag = &in->lag_compensation;
    const bool lead = (in->mode == WC_MODE_TORQUE) && lag_time_valid(lag->time_s) && (lag->vfs_gain > 0.0f) &&
                      (lag->vfs_gain <= FLT_MAX);  /* also NaN: off */
    if (lead && film) {
        lead_film(model, hbar_m, contact.pressure_Pa, damping_N_s_m2, lag->time_s, film_segment,
                  correction.kiss_offset_N, &inv);
    }
    out->pressure_command_Pa = model->cal->vfs_gain_Pa_per_mA * inv.current_mA;  /* the pressure wanted */
    if (lead) { status |= lead_lag(model, clutch->pressure_model_Pa, lag->vfs_gain, &inv); }
    out->current_mA = inv.current_mA;
    out->force_command_N = inv.force_N;
    out->inverse_iterations = inv.iterations;

    clutch->pressure_model_Pa = wc_vfs_lag_at(model, clutch->pressure_model_Pa, inv.current_mA);
    out->pressure_model_Pa = clutch->pressure_model_Pa;
    float force_N = wc_contact_force_at(model->cal, clutch->pressure_model_Pa);
    /* DESIGN 15: how far the piston stands off the pack (before the learned kiss offset); without an open
     * drag calibrated (both fields 0) it changes nothing, and is not computed */
    const wc_calibration_t *drag_cal = model->cal;
    float retracted = open_drag ? retracted_fraction(drag_cal, clutch->pressure_model_Pa) : 0.0f;
    if (corrected && nonzero(correction.kiss_offset_N)) {
        /* DESIGN 12: the learned kiss point moves the spring's preload: F = P A_p - F_s - offset, within
         * [0, WC_FORCE_MAX_N] (|offset| <= WC_CORRECTION_KISS_MAX_N) */
        const wc_calibration_t *c = model->cal;
        const float moved_N = clutch->pressure_model_Pa * c->piston_area_m2 - c->return_spring_force_N -
                              correction.kiss_offset_N;
        force_N = (moved_N > 0.0f) ? ((moved_N < WC_FORCE_MAX_N) ? moved_N : WC_FORCE_MAX_N) : 0.0f;
    }
    const bool bench_force = in->bench.valid && wc_in_range(in->bench.apply_force_N, 0.0f, WC_FORCE_MAX_N);
    const bool bench_torque = in->bench.valid &&
                              wc_in_range(in->bench.torque_Nm, -WC_TORQUE_MAX_Nm, WC_TORQUE_MAX_Nm);
    if (in->bench.valid && !bench_force) { status |= WC_STATUS_FORCE_INVALID; }
    if (in->bench.valid && !bench_torque) { status |= WC_STATUS_TORQUE_INVALID; }
    if (bench_force) {
        force_N = in->bench.apply_force_N;
        retracted = (force_N > 0.0f) ? 0.0f : 1.0f;  /* a bench's load cell measures the apply force itself */
    }
    /* valid: the modelled force is in [0, F_max] (F_max <= WC_FORCE_MAX_N by the
     * calibration check), the bench force was range-checked above */
    const wc_calibration_t *cal = model->cal;
    /* Inside the lock band the slip's sign is sensor noise: the torque keeps
     * the direction of the slip before it (DESIGN 9), so the estimate does not
     * flip sign with every noisy sample before the lock. */
    const float direction = (clutch->lockup.direction < 0) ? -1.0f : 1.0f;
    const float signed_slip_rad_s = (fabsf(u->slip_rad_s) < cal->lock_slip_rad_s) ? direction : u->slip_rad_s;
    /* (the torque takes only its sign from it: the speed is the point's) */
    if (film) {
        /* DESIGN 9: the asperities carry F_c(h_bar) of the film state; the
         * squeeze film carries the rest, and the film advances under the force. */
        const float contact_N = cal->friction_area_m2 * contact.pressure_Pa;
        wc_torque_at_gap(&point, signed_slip_rad_s, contact_N, hbar_m, open_gap_m(cal, hbar_m, retracted, u->slip_rad_s),
                         &out->model);
        out->contact_force_N = contact_N;
        clutch->film_hbar_m = wc_film_advance_at_m(&cal->film, cal->friction_area_m2, hbar_m, &contact, force_N,
                                                   damping_N_s_m2,
                                                   cal->control_period_s, film_segment);
    } else {
        /* eq. 16: the paper's steady film (the modelled force lags the commanded one: no segment to start
         * from that would hold in the worst case) */
        const float steady_hbar_m =
            wc_film_hbar_near_m(&cal->film, force_N / cal->friction_area_m2, WC_FILM_NO_SEGMENT);
        wc_torque_at_gap(&point, signed_slip_rad_s, force_N, steady_hbar_m,
                         open_gap_m(cal, steady_hbar_m, retracted, u->slip_rad_s), &out->model);
        out->contact_force_N = force_N;
    }

    /* DESIGN 9: lock-up against the static capacity at the contact force. */
    out->static_capacity_Nm = static_Nm_per_N * out->contact_force_N;
    const bool carried = (in->carried_torque_Nm > 0.0f) && (in->carried_torque_Nm <= WC_TORQUE_MAX_Nm);
    const float required_Nm = bench_torque ? in->bench.torque_Nm
                                           : direction * (carried ? in->carried_torque_Nm : u->torque_request_Nm);
    const bool locked = wc_lockup_advance(&clutch->lockup, cal, u->slip_rad_s, required_Nm, out->static_capacity_Nm);
    if (locked) {
        out->model.torque_Nm = wc_lockup_held_Nm(&clutch->lockup, required_Nm, out->static_capacity_Nm);
        out->model.coulomb_Nm = out->model.torque_Nm;  /* static friction only: no slip, no viscous shear */
        out->model.viscous_Nm = 0.0f;
        status |= WC_STATUS_LOCKED;
    }

    /* eq. 1 heat input: friction power |T dw|; none while locked */
    const float heat_torque_Nm = bench_torque ? in->bench.torque_Nm : out->model.torque_Nm;
    const float power_W = locked ? 0.0f : fabsf(heat_torque_Nm * u->slip_rad_s);  /* finite: model or range-checked */
    clutch->theta_degC = wc_thermal_advance(model, clutch->theta_degC, power_W, u->theta_oil_degC,
                                            u->theta_housing_degC);  /* the held temperatures are valid */
    /* Over-temperature with hysteresis on the updated estimate (DESIGN section 8). */
    if (clutch->theta_degC > WC_THETA_OVER_degC) {
        clutch->over_temperature = true;
    } else if (clutch->theta_degC < WC_THETA_OVER_degC - WC_THETA_OVER_HYSTERESIS_K) {
        clutch->over_temperature = false;
    }
    if (clutch->over_temperature) { status |= WC_STATUS_OVER_TEMPERATURE; }
    out->status = status;
    return status;
}

wc_lag_compensation_t wc_lag_compensation(const wc_clutch_t *clutch, float time_s)
{
    WC_ASSERT(clutch != NULL);
    wc_lag_compensation_t lag = { 0.0f, 0.0f };  /* off; also for a clutch whose init failed (no calibration) */
    if ((clutch == NULL) || (clutch->model.cal == NULL) || !lag_time_valid(time_s)) {
        return lag;
    }
    /* DESIGN 9, lead_lag: the factor (1 - e^(-dt/t)) / (1 - d), d = e^(-dt/tau); finite and > 0 for
     * t in (0, WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s] (dt and tau checked by the calibration check) */
    const wc_model_t *model = &clutch->model;
    lag.time_s = time_s;
    lag.vfs_gain = (1.0f - wc_exp(-model->cal->control_period_s / time_s)) / (1.0f - model->vfs_decay);
    return lag;
}
