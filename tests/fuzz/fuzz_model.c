/* libFuzzer harness of the model library (include/wetclutch/) with the
 * table1 calibration (lut/wc_table1_calibration.h).
 *
 * Input: a sequence of operations until the bytes run out (at most MAX_OPS).
 * Each starts with an operation byte, then its float arguments, each read by
 * fz_float (wc_fuzz_common.h): raw bit patterns (NaN payloads, +-Inf,
 * denormals, huge values), values inside the argument's range, the library's
 * limits and one ulp beside them. The operations call every public model
 * function: wc_torque, wc_inverse, wc_thermal_step, wc_friction_coefficient,
 * wc_viscosity_Pa_s, wc_film_hbar_m, wc_piston_pressure_Pa,
 * wc_contact_force_N, wc_vfs_current_mA, wc_vfs_lag_step, and wc_clutch_step
 * on one wc_clutch_t (initialised from a fuzzed start temperature) with
 * fuzzed inputs, modes 0..2 and out-of-range values cast into the enum, and
 * bench inputs.
 *
 * Oracle (abort with a message on violation):
 *  - every output finite; every status bit one of include/wetclutch/wc_status.h,
 *    and the input-rejection bits exactly those the inputs call for;
 *  - currents within [vfs_current_min_mA, vfs_current_max_mA]; OPEN (and an
 *    unknown mode) gives the minimum, LOCKED the maximum;
 *  - torque: |T| below the capacity bound (mu_f <= 1 at WC_FORCE_MAX_N times
 *    R_eff N_c plus the largest viscous torque: mu_v at -40 degC, the largest
 *    slip, the thinnest film of the table; about 1.1e8 Nm for table1, see
 *    tests/fuzz/README.md), 0 < mu_f <= 1,
 *    sign of the slip (torque >= 0 for slip >= 0), zero with the open-clutch
 *    film for rejected input;
 *  - h_bar > 0, within the table's range, non-increasing in p_c;
 *  - the inverse: force in [0, F_max], and T(F) brackets the request to
 *    within the force tolerance when no flag is raised;
 *  - the observer estimate stays in [WC_THETA_MIN_degC, WC_THETA_MAX_degC],
 *    is untouched on rejected input, and the over-temperature bit follows
 *    the documented hysteresis.
 * The arithmetic helpers are checked for every input (the literal promise of
 * DESIGN.md section 3; they limit their inputs since the strict findings of
 * tests/fuzz/README.md); WC_FUZZ_LAX=1 checks them only inside the domain the
 * library itself calls them with. */
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wetclutch.h>

#include "wc_fuzz_common.h"
#include "wc_table1_calibration.h"

#define MAX_OPS 256u

#define ALL_STATUS_BITS                                                                                  \
    (WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED | WC_STATUS_CURRENT_CLAMPED | WC_STATUS_SLIP_INVALID |   \
     WC_STATUS_THETA_INVALID | WC_STATUS_FORCE_INVALID | WC_STATUS_TORQUE_INVALID |                      \
     WC_STATUS_POWER_INVALID | WC_STATUS_OVER_TEMPERATURE | WC_STATUS_NOT_INITIALISED | WC_STATUS_LOCKED)

static const wc_calibration_t *const cal = &wc_table1_calibration;
static wc_model_t model;
static bool strict;
static float hbar_min_m;
static float hbar_max_m;
static float torque_bound_Nm;  /* mu_f 1 at WC_FORCE_MAX_N plus the largest viscous torque */
static float torque_arm_m;     /* R_eff N_c */

static bool in_range(float x, float lo, float hi) { return (x >= lo) && (x <= hi); }
static bool slip_ok(float x) { return in_range(x, -WC_SLIP_MAX_rad_s, WC_SLIP_MAX_rad_s); }
static bool theta_ok(float x) { return in_range(x, WC_THETA_MIN_degC, WC_THETA_MAX_degC); }

/* The input bits every model call must raise for its operating point. */
static wc_status_t operating_point_bits(float slip, float theta)
{
    return (slip_ok(slip) ? 0u : WC_STATUS_SLIP_INVALID) | (theta_ok(theta) ? 0u : WC_STATUS_THETA_INVALID);
}
static bool same_bits(float a, float b) { return fz_bits_of(a) == fz_bits_of(b); }
static bool close_rel(float a, float b, float rel, float abs_tol)
{
    return fabsf(a - b) <= rel * fmaxf(fabsf(a), fabsf(b)) + abs_tol;
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const wc_cal_error_t e = wc_model_init(&model, cal);
    if (e != WC_CAL_OK) {
        fprintf(stderr, "fuzz_model: table1 calibration rejected: %s\n", wc_cal_error_name(e));
        abort();
    }
    strict = !fz_env_flag("WC_FUZZ_LAX");  /* every input, since the helpers limit theirs */
    hbar_min_m = cal->film.hbar_m[0];
    hbar_max_m = cal->film.hbar_m[0];
    for (uint32_t i = 0u; i < cal->film.length; ++i) {
        hbar_min_m = fminf(hbar_min_m, cal->film.hbar_m[i]);
        hbar_max_m = fmaxf(hbar_max_m, cal->film.hbar_m[i]);
    }
    /* mu_v falls with theta for table1 (both exponents negative): largest at -40 degC. */
    const float mu_v_max = fmaxf(wc_viscosity_Pa_s(cal, WC_THETA_MIN_degC), wc_viscosity_Pa_s(cal, WC_THETA_MAX_degC));
    const float v_max = model.effective_radius_m * WC_SLIP_MAX_rad_s;
    torque_arm_m = model.effective_radius_m * (float)cal->friction_pairs;
    torque_bound_Nm = 1.01f * (torque_arm_m * WC_FORCE_MAX_N +
                               torque_arm_m * mu_v_max * cal->friction_area_m2 * v_max / hbar_min_m);
    if (!fz_finite(torque_bound_Nm)) {
        fprintf(stderr, "fuzz_model: torque bound %g not finite\n", (double)torque_bound_Nm);
        abort();
    }
    if (fz_env_flag("WC_FUZZ_VERBOSE")) {
        fprintf(stderr, "fuzz_model: |T| bound %g Nm (Coulomb %g at mu_f 1, viscous at mu_v %g Pa s, h_bar %g m)\n",
                (double)torque_bound_Nm, (double)(torque_arm_m * WC_FORCE_MAX_N), (double)mu_v_max,
                (double)hbar_min_m);
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Checks shared by wc_torque and wc_clutch_step                            */
/* ------------------------------------------------------------------------ */

static void check_torque_output(const wc_torque_t *t, float slip_rad_s, bool rejected, float force_N)
{
    FZ_CHECK(fz_finite(t->torque_Nm) && fz_finite(t->coulomb_Nm) && fz_finite(t->viscous_Nm) &&
                 fz_finite(t->hbar_m) && fz_finite(t->mu_f),
             "non-finite torque output: T %g Tc %g Tv %g hbar %g mu_f %g", (double)t->torque_Nm,
             (double)t->coulomb_Nm, (double)t->viscous_Nm, (double)t->hbar_m, (double)t->mu_f);
    FZ_CHECK(t->hbar_m > 0.0f, "h_bar %g not positive", (double)t->hbar_m);
    FZ_CHECK(in_range(t->hbar_m, hbar_min_m * (1.0f - 1e-4f), hbar_max_m * (1.0f + 1e-4f)),
             "h_bar %g outside the table's [%g, %g]", (double)t->hbar_m, (double)hbar_min_m, (double)hbar_max_m);
    FZ_CHECK(fabsf(t->torque_Nm) <= torque_bound_Nm, "|T| %g above the capacity bound %g", (double)t->torque_Nm,
             (double)torque_bound_Nm);
    FZ_CHECK(close_rel(t->torque_Nm, t->coulomb_Nm + t->viscous_Nm, 1e-6f, 1e-6f), "T %g != Tc %g + Tv %g",
             (double)t->torque_Nm, (double)t->coulomb_Nm, (double)t->viscous_Nm);
    if (slip_rad_s < 0.0f) {
        FZ_CHECK((t->torque_Nm <= 0.0f) && (t->coulomb_Nm <= 0.0f) && (t->viscous_Nm <= 0.0f),
                 "torque against the slip: slip %g, T %g (Tc %g, Tv %g)", (double)slip_rad_s, (double)t->torque_Nm,
                 (double)t->coulomb_Nm, (double)t->viscous_Nm);
    } else {
        FZ_CHECK((t->torque_Nm >= 0.0f) && (t->coulomb_Nm >= 0.0f) && (t->viscous_Nm >= 0.0f),
                 "torque against the slip: slip %g, T %g (Tc %g, Tv %g)", (double)slip_rad_s, (double)t->torque_Nm,
                 (double)t->coulomb_Nm, (double)t->viscous_Nm);
    }
    if (rejected) {
        FZ_CHECK((t->torque_Nm == 0.0f) && (t->mu_f == 0.0f) && (t->coulomb_Nm == 0.0f) && (t->viscous_Nm == 0.0f) &&
                     (t->hbar_m == cal->film.hbar_m[0]),
                 "rejected input must give zero torque with the open-clutch film: T %g mu_f %g hbar %g",
                 (double)t->torque_Nm, (double)t->mu_f, (double)t->hbar_m);
    } else {
        FZ_CHECK((t->mu_f > 0.0f) && (t->mu_f <= 1.0f), "mu_f %g outside (0, 1]", (double)t->mu_f);
        /* Coulomb part: mu_f F R_eff N_c exactly (eq. 6), up to rounding. */
        FZ_CHECK(close_rel(fabsf(t->coulomb_Nm), t->mu_f * force_N * torque_arm_m, 1e-5f, 1e-6f),
                 "|Tc| %g != mu_f %g * F %g * R_eff N_c %g", (double)t->coulomb_Nm, (double)t->mu_f, (double)force_N,
                 (double)torque_arm_m);
    }
}

/* ------------------------------------------------------------------------ */
/* Operations                                                                */
/* ------------------------------------------------------------------------ */

static void op_torque(fz_reader_t *r, unsigned step)
{
    const float slip = fz_float(r, -1100.0f, 1100.0f);
    const float theta = fz_float(r, -60.0f, 300.0f);
    const float force = fz_float(r, -10.0f, 1.1e5f);
    fz_context("wc_torque(slip, theta, force)", step);
    fz_arg(slip); fz_arg(theta); fz_arg(force);
    wc_torque_t t;
    const wc_status_t st = wc_torque(&model, slip, theta, force, &t);
    const wc_status_t expected = operating_point_bits(slip, theta) |
                                 (in_range(force, 0.0f, WC_FORCE_MAX_N) ? 0u : WC_STATUS_FORCE_INVALID);
    FZ_CHECK(st == expected, "status 0x%x, expected exactly 0x%x", (unsigned)st, (unsigned)expected);
    check_torque_output(&t, slip, expected != 0u, force);
}

/* |T| at a force, for the inverse's bracket checks. */
static float torque_abs(float slip, float theta, float force)
{
    wc_torque_t t;
    const float f = fminf(fmaxf(force, 0.0f), WC_FORCE_MAX_N);
    (void)wc_torque(&model, slip, theta, f, &t);
    return fabsf(t.torque_Nm);
}

static void op_inverse(fz_reader_t *r, unsigned step)
{
    const float slip = fz_float(r, -1100.0f, 1100.0f);
    const float theta = fz_float(r, -60.0f, 300.0f);
    const float request = fz_float(r, -10.0f, 3000.0f);
    fz_context("wc_inverse(slip, theta, request)", step);
    fz_arg(slip); fz_arg(theta); fz_arg(request);
    wc_inverse_t inv;
    const wc_status_t st = wc_inverse(&model, slip, theta, request, &inv);
    const wc_status_t invalid = operating_point_bits(slip, theta) |
                                (in_range(request, 0.0f, WC_TORQUE_MAX_Nm) ? 0u : WC_STATUS_TORQUE_INVALID);
    FZ_CHECK((st & WC_STATUS_INPUT_INVALID) == invalid, "input bits 0x%x, expected 0x%x", (unsigned)st,
             (unsigned)invalid);
    FZ_CHECK((st & ~(WC_STATUS_INPUT_INVALID | WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED |
                     WC_STATUS_CURRENT_CLAMPED)) == 0u,
             "unexpected status bits 0x%x", (unsigned)st);
    FZ_CHECK(fz_finite(inv.force_N) && fz_finite(inv.pressure_Pa) && fz_finite(inv.current_mA),
             "non-finite inverse: F %g P %g i %g", (double)inv.force_N, (double)inv.pressure_Pa,
             (double)inv.current_mA);
    FZ_CHECK(in_range(inv.current_mA, cal->vfs_current_min_mA, cal->vfs_current_max_mA),
             "current %g mA outside [%g, %g]", (double)inv.current_mA, (double)cal->vfs_current_min_mA,
             (double)cal->vfs_current_max_mA);
    FZ_CHECK(in_range(inv.force_N, 0.0f, model.force_max_N), "force %g outside [0, %g]", (double)inv.force_N,
             (double)model.force_max_N);
    FZ_CHECK(inv.iterations <= WC_INVERSE_MAX_ITERATIONS, "iterations %u", (unsigned)inv.iterations);
    FZ_CHECK(close_rel(inv.pressure_Pa, (inv.force_N + cal->return_spring_force_N) / cal->piston_area_m2, 1e-5f, 1e-3f),
             "pressure %g != (F %g + F_s) / A_p", (double)inv.pressure_Pa, (double)inv.force_N);
    if (invalid != 0u) {
        FZ_CHECK((inv.force_N == 0.0f) && ((st & (WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED)) == 0u),
                 "rejected input must give force 0: F %g, status 0x%x", (double)inv.force_N, (unsigned)st);
        return;
    }
    /* The answer against the forward model (tolerances: the inverse's force
     * tolerance, and float rounding of T). */
    const float eps_Nm = 1e-4f * request + 1e-3f;
    const float tol_N = 2.0f * WC_INVERSE_FORCE_TOLERANCE_N;
    if ((st & WC_STATUS_BELOW_DRAG) != 0u) {
        FZ_CHECK(inv.force_N == 0.0f, "below drag with force %g", (double)inv.force_N);
        FZ_CHECK(torque_abs(slip, theta, 0.0f) >= request - eps_Nm, "below drag, but T(0) = %g < request",
                 (double)torque_abs(slip, theta, 0.0f));
    } else if ((st & WC_STATUS_SATURATED) != 0u) {
        FZ_CHECK((inv.force_N == model.force_max_N) && (inv.current_mA == cal->vfs_current_max_mA),
                 "saturated with F %g, i %g", (double)inv.force_N, (double)inv.current_mA);
        FZ_CHECK(torque_abs(slip, theta, model.force_max_N) <= request + eps_Nm,
                 "saturated, but T(F_max) = %g > request", (double)torque_abs(slip, theta, model.force_max_N));
    } else {
        const float lo = torque_abs(slip, theta, inv.force_N - tol_N);
        const float hi = torque_abs(slip, theta, inv.force_N + tol_N);
        FZ_CHECK((lo <= request + eps_Nm) && (hi >= request - eps_Nm),
                 "T(F -+ %g N) = [%.9g, %.9g] does not bracket the request (F = %.9g)", (double)tol_N, (double)lo,
                 (double)hi, (double)inv.force_N);
    }
}

static float theta_state = 40.0f;  /* the caller's observer state for wc_thermal_step */

static void op_thermal(fz_reader_t *r, unsigned step)
{
    const uint8_t how = fz_u8(r);
    if ((how & 0x0Fu) == 0u) { theta_state = fz_float(r, -100.0f, 400.0f); }  /* any caller state */
    const float power = fz_float(r, -10.0f, 1e7f);
    const float oil = fz_float(r, -60.0f, 300.0f);
    const float housing = ((how & 0x10u) != 0u) ? oil : fz_float(r, -60.0f, 300.0f);
    const float before = theta_state;
    fz_context("wc_thermal_step(theta, power, oil, housing)", step);
    fz_arg(before); fz_arg(power); fz_arg(oil); fz_arg(housing);
    const wc_status_t st = wc_thermal_step(&model, &theta_state, power, oil, housing);
    const wc_status_t expected = ((fz_finite(power) && (power >= 0.0f)) ? 0u : WC_STATUS_POWER_INVALID) |
                                 ((theta_ok(oil) && theta_ok(housing)) ? 0u : WC_STATUS_THETA_INVALID);
    FZ_CHECK(st == expected, "status 0x%x, expected exactly 0x%x", (unsigned)st, (unsigned)expected);
    if (st != 0u) {
        FZ_CHECK(same_bits(theta_state, before), "rejected input changed the state: %g -> %g", (double)before,
                 (double)theta_state);
        if (!theta_ok(theta_state)) { theta_state = 40.0f; }
        return;
    }
    FZ_CHECK(fz_finite(theta_state) && theta_ok(theta_state), "estimate %g outside [%g, %g]", (double)theta_state,
             (double)WC_THETA_MIN_degC, (double)WC_THETA_MAX_degC);
    if (theta_ok(before)) {
        /* Heat input >= 0: the step moves towards theta_ss >= min(oil, housing). */
        const float floor_degC = fminf(before, fminf(oil, housing));
        FZ_CHECK(theta_state >= floor_degC - 1e-3f, "estimate %g fell below min(theta, oil, housing) %g",
                 (double)theta_state, (double)floor_degC);
    }
}

static void op_friction(fz_reader_t *r, unsigned step)
{
    const float speed = fz_float(r, -100.0f, 100.0f);
    const float theta = fz_float(r, -60.0f, 300.0f);
    fz_context("wc_friction_coefficient(speed, theta)", step);
    fz_arg(speed); fz_arg(theta);
    const float mu = wc_friction_coefficient(cal, speed, theta);
    if (fz_finite(speed) && theta_ok(theta)) {
        FZ_CHECK(fz_finite(mu) && (mu > 0.0f) && (mu <= 1.0f), "mu_f %g outside (0, 1] on the domain", (double)mu);
    } else if (strict) {
        FZ_CHECK(fz_finite(mu), "[strict] mu_f %g not finite outside the domain", (double)mu);
    }
}

static void op_viscosity(fz_reader_t *r, unsigned step)
{
    const float theta = fz_float(r, -60.0f, 300.0f);
    fz_context("wc_viscosity_Pa_s(theta)", step);
    fz_arg(theta);
    const float mu_v = wc_viscosity_Pa_s(cal, theta);
    if (theta_ok(theta)) {
        FZ_CHECK(fz_finite(mu_v) && (mu_v > 0.0f), "mu_v %g not finite and positive", (double)mu_v);
    } else if (strict) {
        FZ_CHECK(fz_finite(mu_v), "[strict] mu_v %g not finite outside the plausible temperatures", (double)mu_v);
    }
}

static void op_film(fz_reader_t *r, unsigned step)
{
    const float p1 = fz_float(r, -1e3f, 5e6f);
    const float p2 = fz_float(r, -1e3f, 5e6f);
    fz_context("wc_film_hbar_m(p1), wc_film_hbar_m(p2)", step);
    fz_arg(p1); fz_arg(p2);
    const float h1 = wc_film_hbar_m(&cal->film, p1);
    const float h2 = wc_film_hbar_m(&cal->film, p2);
    const uint32_t last = cal->film.length - 1u;
    FZ_CHECK(fz_finite(h1) && fz_finite(h2) && (h1 > 0.0f) && (h2 > 0.0f), "h_bar %g, %g", (double)h1, (double)h2);
    FZ_CHECK(in_range(h1, hbar_min_m, hbar_max_m) && in_range(h2, hbar_min_m, hbar_max_m),
             "h_bar %g, %g outside the nodes' [%g, %g]", (double)h1, (double)h2, (double)hbar_min_m,
             (double)hbar_max_m);
    if (!(p1 > cal->film.pressure_Pa[0])) {  /* also NaN: the open-clutch end */
        FZ_CHECK(h1 == cal->film.hbar_m[0], "h_bar(%g) = %g, not the first node", (double)p1, (double)h1);
    }
    if (p1 >= cal->film.pressure_Pa[last]) {
        FZ_CHECK(h1 == cal->film.hbar_m[last], "h_bar(%g) = %g, not the last node", (double)p1, (double)h1);
    }
    if (p1 < p2) {  /* h_bar falls as p_c rises (monotone Hermite) */
        FZ_CHECK(h1 >= h2 * (1.0f - 1e-6f), "h_bar not monotone: h(%g) = %.9g < h(%g) = %.9g", (double)p1,
                 (double)h1, (double)p2, (double)h2);
    }
}

static void op_hydraulics(fz_reader_t *r, unsigned step)
{
    const uint8_t which = fz_u8(r) % 4u;
    if (which == 0u) {
        const float force = fz_float(r, -10.0f, 1.1e5f);
        fz_context("wc_piston_pressure_Pa(force)", step);
        fz_arg(force);
        const float p = wc_piston_pressure_Pa(cal, force);
        if (in_range(force, 0.0f, WC_FORCE_MAX_N)) {
            FZ_CHECK(fz_finite(p) && (p > 0.0f), "pressure %g for a valid force", (double)p);
            FZ_CHECK(close_rel(wc_contact_force_N(cal, p), force, 1e-5f, 1e-2f), "contact force of %g Pa: %g != %g",
                     (double)p, (double)wc_contact_force_N(cal, p), (double)force);
        } else if (strict) {
            FZ_CHECK(fz_finite(p), "[strict] pressure %g not finite", (double)p);
        }
    } else if (which == 1u) {
        const float p = fz_float(r, -1e5f, 1e7f);
        fz_context("wc_contact_force_N(pressure)", step);
        fz_arg(p);
        const float f = wc_contact_force_N(cal, p);
        FZ_CHECK(!(f < 0.0f), "negative contact force %g", (double)f);
        if (fz_finite(p)) {
            FZ_CHECK(fz_finite(f), "force %g for a finite pressure", (double)f);
        } else if (strict) {
            FZ_CHECK(fz_finite(f), "[strict] force %g not finite", (double)f);
        }
    } else if (which == 2u) {
        const float p = fz_float(r, -1e5f, 3e6f);
        fz_context("wc_vfs_current_mA(pressure)", step);
        fz_arg(p);
        float i = -1.0f;
        const wc_status_t st = wc_vfs_current_mA(cal, p, &i);
        FZ_CHECK(fz_finite(i) && in_range(i, cal->vfs_current_min_mA, cal->vfs_current_max_mA),
                 "current %g outside [%g, %g]", (double)i, (double)cal->vfs_current_min_mA,
                 (double)cal->vfs_current_max_mA);
        const float raw = p / cal->vfs_gain_Pa_per_mA;
        const bool clamp = !in_range(raw, cal->vfs_current_min_mA, cal->vfs_current_max_mA);
        FZ_CHECK(st == (clamp ? WC_STATUS_CURRENT_CLAMPED : 0u), "status 0x%x for i = %g", (unsigned)st, (double)raw);
        if (!clamp) { FZ_CHECK(i == raw, "current %g != P/K %g", (double)i, (double)raw); }
    } else {
        const float p = fz_float(r, -1e5f, 3e6f);
        const float i = fz_float(r, -100.0f, 1200.0f);
        fz_context("wc_vfs_lag_step(pressure, current)", step);
        fz_arg(p); fz_arg(i);
        const float next = wc_vfs_lag_step(&model, p, i);
        const float k = cal->vfs_gain_Pa_per_mA;
        if (in_range(i, cal->vfs_current_min_mA, cal->vfs_current_max_mA) &&
            in_range(p, k * cal->vfs_current_min_mA, k * cal->vfs_current_max_mA)) {
            /* the library's own use: a convex step inside the solenoid's range */
            FZ_CHECK(fz_finite(next) && in_range(next, fminf(p, k * i) * (1.0f - 1e-6f) - 1e-3f,
                                                 fmaxf(p, k * i) * (1.0f + 1e-6f) + 1e-3f),
                     "lag step %g not between %g and K i = %g", (double)next, (double)p, (double)(k * i));
        } else if (fz_finite(p) && fz_finite(i) && (fabsf(p) < 1e30f) && (fabsf(i) < 1e30f)) {
            FZ_CHECK(fz_finite(next), "lag step %g for finite inputs", (double)next);
        } else if (strict) {
            FZ_CHECK(fz_finite(next), "[strict] lag step %g not finite", (double)next);
        }
    }
}

/* ------------------------------------------------------------------------ */
/* wc_clutch_step                                                            */
/* ------------------------------------------------------------------------ */

static wc_clutch_t clutch;
static bool over_temperature;  /* the documented hysteresis, tracked here */

static wc_clutch_mode_t fuzz_mode(uint8_t b, fz_reader_t *r)
{
    if (b < 240u) { return (wc_clutch_mode_t)(b % 3u); }
    /* out of range values cast into the enum */
    static const long odd[] = { 3, 4, 15, 255, -1, 0x7fffffffL, -0x7fffffffL - 1L, 0x10000L };
    const long v = (b < 248u) ? odd[b - 240u] : (long)(int32_t)fz_u32(r);
    return (wc_clutch_mode_t)v;
}

static void op_clutch_step(fz_reader_t *r, unsigned step)
{
    wc_step_input_t in;
    memset(&in, 0, sizeof in);
    const uint8_t flags = fz_u8(r);
    in.slip_rad_s = fz_float(r, -1100.0f, 1100.0f);
    in.theta_oil_degC = fz_float(r, -60.0f, 300.0f);
    in.theta_housing_degC = ((flags & 0x01u) != 0u) ? in.theta_oil_degC : fz_float(r, -60.0f, 300.0f);
    in.torque_request_Nm = fz_float(r, -10.0f, 3000.0f);
    in.mode = fuzz_mode(fz_u8(r), r);
    if ((flags & 0x02u) != 0u) {
        in.bench.valid = true;
        in.bench.apply_force_N = fz_float(r, -100.0f, 1.2e5f);
        in.bench.torque_Nm = fz_float(r, -1.2e5f, 1.2e5f);
    }
    /* the shift controller's inputs (DESIGN 9/10): lag compensation, thermal-blind model, carried torque */
    if ((flags & 0x04u) != 0u) {  /* as wc_lag_compensation makes it, or hand-filled with anything */
        const float time_s = fz_float(r, -1.0f, 20.0f);
        in.lag_compensation = wc_lag_compensation(&clutch, time_s);
        if ((flags & 0x20u) != 0u) { in.lag_compensation.vfs_gain = fz_float(r, -1.0f, 1e30f); }
        if ((flags & 0x40u) != 0u) { in.lag_compensation.time_s = time_s; }
    }
    in.theta_from_oil = (flags & 0x08u) != 0u;
    if ((flags & 0x10u) != 0u) { in.carried_torque_Nm = fz_float(r, -10.0f, 6000.0f); }
    const float theta_before = clutch.theta_degC;
    fz_context("wc_clutch_step(slip, oil, housing, request, [bench force, bench torque]; mode, bench)", step);
    fz_arg(in.slip_rad_s); fz_arg(in.theta_oil_degC); fz_arg(in.theta_housing_degC); fz_arg(in.torque_request_Nm);
    fz_arg(in.bench.apply_force_N); fz_arg(in.bench.torque_Nm);
    fz_ctx.iargs[0] = (long)in.mode;
    fz_ctx.iargs[1] = in.bench.valid ? 1 : 0;

    wc_step_output_t out;
    memset(&out, 0xA5, sizeof out);  /* every field must be written */
    const wc_status_t st = wc_clutch_step(&clutch, &in, &out);
    FZ_CHECK(st == out.status, "returned 0x%x, out.status 0x%x", (unsigned)st, (unsigned)out.status);
    FZ_CHECK((st & ~ALL_STATUS_BITS) == 0u, "undefined status bits 0x%x", (unsigned)st);
    FZ_CHECK((st & (WC_STATUS_NOT_INITIALISED | WC_STATUS_POWER_INVALID)) == 0u, "status 0x%x on an initialised clutch",
             (unsigned)st);

    const bool mode_known = (in.mode == WC_MODE_OPEN) || (in.mode == WC_MODE_TORQUE) || (in.mode == WC_MODE_LOCKED);
    const bool bench_force_ok = in_range(in.bench.apply_force_N, 0.0f, WC_FORCE_MAX_N);
    const bool bench_torque_ok = in_range(in.bench.torque_Nm, -WC_TORQUE_MAX_Nm, WC_TORQUE_MAX_Nm);
    const wc_status_t expected =
        (slip_ok(in.slip_rad_s) ? 0u : WC_STATUS_SLIP_INVALID) |
        ((theta_ok(in.theta_oil_degC) && theta_ok(in.theta_housing_degC)) ? 0u : WC_STATUS_THETA_INVALID) |
        ((in_range(in.torque_request_Nm, 0.0f, WC_TORQUE_MAX_Nm) && mode_known &&
          (!in.bench.valid || bench_torque_ok)) ? 0u : WC_STATUS_TORQUE_INVALID) |
        ((!in.bench.valid || bench_force_ok) ? 0u : WC_STATUS_FORCE_INVALID);
    FZ_CHECK((st & WC_STATUS_INPUT_INVALID) == expected, "input bits 0x%x, expected exactly 0x%x", (unsigned)st,
             (unsigned)expected);

    /* held inputs: valid values only */
    FZ_CHECK(slip_ok(clutch.held.slip_rad_s) && theta_ok(clutch.held.theta_oil_degC) &&
                 theta_ok(clutch.held.theta_housing_degC) &&
                 in_range(clutch.held.torque_request_Nm, 0.0f, WC_TORQUE_MAX_Nm),
             "a held input is invalid: slip %g oil %g housing %g request %g", (double)clutch.held.slip_rad_s,
             (double)clutch.held.theta_oil_degC, (double)clutch.held.theta_housing_degC,
             (double)clutch.held.torque_request_Nm);

    /* observer */
    /* the model's temperature: the estimate before the step, or the (held, valid) oil temperature */
    FZ_CHECK(same_bits(out.theta_degC, in.theta_from_oil ? clutch.held.theta_oil_degC : theta_before),
             "out.theta %g is not the %s %g", (double)out.theta_degC,
             in.theta_from_oil ? "held oil temperature" : "estimate before the step",
             (double)(in.theta_from_oil ? clutch.held.theta_oil_degC : theta_before));
    FZ_CHECK(fz_finite(clutch.theta_degC) && theta_ok(clutch.theta_degC), "estimate %g outside [%g, %g]",
             (double)clutch.theta_degC, (double)WC_THETA_MIN_degC, (double)WC_THETA_MAX_degC);
    if (clutch.theta_degC > WC_THETA_OVER_degC) {
        over_temperature = true;
    } else if (clutch.theta_degC < WC_THETA_OVER_degC - WC_THETA_OVER_HYSTERESIS_K) {
        over_temperature = false;
    }
    FZ_CHECK(((st & WC_STATUS_OVER_TEMPERATURE) != 0u) == over_temperature,
             "over-temperature bit %d, hysteresis says %d at %g degC", (st & WC_STATUS_OVER_TEMPERATURE) != 0u,
             over_temperature, (double)clutch.theta_degC);

    /* solenoid */
    FZ_CHECK(fz_finite(out.current_mA) && in_range(out.current_mA, cal->vfs_current_min_mA, cal->vfs_current_max_mA),
             "current %g outside [%g, %g]", (double)out.current_mA, (double)cal->vfs_current_min_mA,
             (double)cal->vfs_current_max_mA);
    if (!mode_known || (in.mode == WC_MODE_OPEN)) {
        FZ_CHECK(out.current_mA == cal->vfs_current_min_mA, "open/unknown mode, current %g", (double)out.current_mA);
    } else if (in.mode == WC_MODE_LOCKED) {
        FZ_CHECK(out.current_mA == cal->vfs_current_max_mA, "locked mode, current %g", (double)out.current_mA);
    }
    /* the wanted pressure: K i, except when the current leads the VFS lag (then within the solenoid's range) */
    const bool led = mode_known && (in.mode == WC_MODE_TORQUE) && (in.lag_compensation.time_s > 0.0f) &&
                     (in.lag_compensation.time_s <= WC_CAL_LIMIT_VFS_TIME_CONSTANT_MAX_s) &&
                     (in.lag_compensation.vfs_gain > 0.0f) && (in.lag_compensation.vfs_gain <= FLT_MAX);
    if (led) {
        FZ_CHECK(fz_finite(out.pressure_command_Pa) &&
                     in_range(out.pressure_command_Pa, cal->vfs_gain_Pa_per_mA * cal->vfs_current_min_mA,
                              cal->vfs_gain_Pa_per_mA * cal->vfs_current_max_mA),
                 "led: pressure command %g outside the solenoid's range", (double)out.pressure_command_Pa);
    } else {
        FZ_CHECK(out.pressure_command_Pa == cal->vfs_gain_Pa_per_mA * out.current_mA, "pressure command %g != K i",
                 (double)out.pressure_command_Pa);
    }
    const float k = cal->vfs_gain_Pa_per_mA;
    FZ_CHECK(fz_finite(out.pressure_model_Pa) &&
                 in_range(out.pressure_model_Pa, k * cal->vfs_current_min_mA * (1.0f - 1e-6f) - 1e-3f,
                          k * cal->vfs_current_max_mA * (1.0f + 1e-6f) + 1e-3f) &&
                 same_bits(out.pressure_model_Pa, clutch.pressure_model_Pa),
             "modelled pressure %g (state %g)", (double)out.pressure_model_Pa, (double)clutch.pressure_model_Pa);
    FZ_CHECK(fz_finite(out.force_command_N) && in_range(out.force_command_N, 0.0f, model.force_max_N),
             "force command %g outside [0, %g]", (double)out.force_command_N, (double)model.force_max_N);
    FZ_CHECK(out.inverse_iterations <= WC_INVERSE_MAX_ITERATIONS, "iterations %u", (unsigned)out.inverse_iterations);

    /* torque model: the force is the bench's when valid, else the modelled pressure's */
    const float force_used = (in.bench.valid && bench_force_ok) ? in.bench.apply_force_N
                                                                : wc_contact_force_N(cal, clutch.pressure_model_Pa);
    FZ_CHECK(same_bits(out.contact_force_N, force_used), "contact force %g, the steady film's %g (film state off)",
             (double)out.contact_force_N, (double)force_used);
    FZ_CHECK(fz_finite(out.static_capacity_Nm) && (out.static_capacity_Nm >= 0.0f), "static capacity %g",
             (double)out.static_capacity_Nm);
    if ((out.status & WC_STATUS_LOCKED) != 0u) {   /* DESIGN 9: the held torque, within the capacity */
        FZ_CHECK(fz_finite(out.model.torque_Nm) && (fabsf(out.model.torque_Nm) <= out.static_capacity_Nm) &&
                     (out.model.torque_Nm * (float)clutch.lockup.direction >= 0.0f),
                 "locked torque %g, capacity %g, direction %d", (double)out.model.torque_Nm,
                 (double)out.static_capacity_Nm, (int)clutch.lockup.direction);
        return;
    }
    /* inside the lock band the torque keeps the lock direction (the slip's sign there is noise) */
    const float slip = clutch.held.slip_rad_s;
    const float sign_slip = (fabsf(slip) < cal->lock_slip_rad_s)
                                ? (float)clutch.lockup.direction * fmaxf(fabsf(slip), FLT_MIN) : slip;
    check_torque_output(&out.model, sign_slip, false, force_used);
}

/* ------------------------------------------------------------------------ */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader_t r;
    fz_reader_init(&r, data, size);

    /* A fresh clutch per input, from a fuzzed start temperature (an invalid
     * one starts at theta1). */
    const float theta_start = fz_float(&r, -60.0f, 300.0f);
    fz_context("wc_clutch_init(theta_start)", 0u);
    fz_arg(theta_start);
    memset(&clutch, 0, sizeof clutch);
    FZ_CHECK(wc_clutch_init(&clutch, cal, theta_start) == WC_CAL_OK, "init failed");
    FZ_CHECK(theta_ok(clutch.theta_degC), "start estimate %g", (double)clutch.theta_degC);
    over_temperature = false;
    theta_state = theta_ok(theta_start) ? theta_start : 40.0f;

    for (unsigned step = 1u; (step <= MAX_OPS) && fz_more(&r); ++step) {
        switch (fz_u8(&r) % 12u) {
        case 0: op_torque(&r, step); break;
        case 1: op_inverse(&r, step); break;
        case 2: op_thermal(&r, step); break;
        case 3: op_friction(&r, step); break;
        case 4: op_viscosity(&r, step); break;
        case 5: op_film(&r, step); break;
        case 6: op_hydraulics(&r, step); break;
        default: op_clutch_step(&r, step); break;  /* 7..11: the step gets the most weight */
        }
    }
    return 0;
}
