/* libFuzzer harness of the calibration check (wc_calibration_check) and of
 * the promise it carries (DESIGN.md sections 3 and 8): every output of every
 * public function is finite and physical for every input and every
 * calibration the check accepts.
 *
 * Input:
 *   byte 0  film table: bits 0-1 == 0 keeps table1's arrays (64 nodes);
 *           otherwise a copy of table1's film arrays of length byte 1 % 65
 *           (0..64; bit 2: contiguous nodes from offset byte 2, else nodes
 *           spread evenly over the table), each array allocated with exactly
 *           that many floats so that AddressSanitizer sees any read past the
 *           end; bits 3-4 == 3: one of the three pointers NULL (bits 5-6).
 *   then edits until the bytes run out (at most MAX_EDITS): a target byte
 *   (one of the 30 float fields, friction_pairs, or a node of the film's
 *   pressure / h_bar / slope array, index in one more byte) and a mutation
 *   (raw float bits, a special or in-range value, a factor 2^(k/8), a
 *   perturbation by up to 3 %, a negation, some ulps up or down).
 *
 * If wc_calibration_check accepts the result (WC_CAL_OK), the model is
 * evaluated on a fixed grid of operating points: slip {-1047, -100, -0.01,
 * 0, 0.01, 100, 1047} rad/s, theta {-40, 20, 120, 250} degC, force {0, 100,
 * 1000, F_max of the calibration, WC_FORCE_MAX_N} N, request {0, 10, 100,
 * 1000, 1e4} Nm, with wc_friction_coefficient, wc_viscosity_Pa_s,
 * wc_film_hbar_m (4 points per segment), wc_torque, wc_inverse and a
 * sequence of wc_clutch_step (modes TORQUE, LOCKED, OPEN) on one clutch.
 * Oracle (abort with a message): wc_model_init agrees with the check and
 * derives finite constants; mu_f > 0 and mu_v > 0, finite; h_bar finite,
 * > 0 and non-increasing in p_c (the Fritsch-Carlson promise); every torque,
 * force, pressure, current and temperature finite; torque with the sign of
 * the slip and non-decreasing in the force (eq. 8: what makes the inverse
 * unique); no input-rejection bit for these valid inputs; current within the
 * calibration's range (never negative), the minimum for OPEN and the maximum
 * for LOCKED; force within [0, F_max]; the estimate within the envelope.
 * A rejected calibration must make wc_model_init fail with the same code.
 *
 * Byte 0 with bits 7 and 6 set (FZ_GEARBOX_IMAGE_INPUT): a gearbox image
 * instead, fuzz_gearbox_image.c. Byte 0 with bit 7 alone (FZ_ADAPT_IMAGE_INPUT):
 * the input is an adaptation image instead, read and checked by fuzz_adapt_image.c (the persistent image
 * format's loader, DESIGN 12: a fourth harness would add a minute to
 * scripts/test.sh, see README.md). */
#include <float.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wetclutch.h>

#include "fuzz_adapt_image.h"
#include "fuzz_gearbox_image.h"
#include "wc_fuzz_common.h"
#include "wc_table1_calibration.h"

#define MAX_EDITS 32u
#define FILM_COPY_MAX 64u

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static bool verbose;
static unsigned long inputs;
static unsigned long accepted;  /* calibrations the check accepted, evaluated on the grid */

/* At exit: how many inputs were calibrations the check accepted (the ones
 * that reach the model); scripts/fuzz.sh prints the line. */
static void report_acceptance(void)
{
    unsigned long images;
    unsigned long loaded;
    unsigned long gearboxes;
    unsigned long gearboxes_loaded;
    fz_adapt_image_counts(&images, &loaded);
    fz_gearbox_image_counts(&gearboxes, &gearboxes_loaded);
    fprintf(stderr, "fuzz_calibration: %lu inputs, %lu accepted by wc_calibration_check and evaluated; "
            "%lu adaptation images, %lu loaded; %lu gearbox images, %lu loaded\n", inputs, accepted, images, loaded,
            gearboxes, gearboxes_loaded);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    verbose = fz_env_flag("WC_FUZZ_VERBOSE");
    (void)atexit(report_acceptance);
    return 0;
}

typedef struct {
    const char *name;
    size_t offset;
} float_field_t;

#define FIELD(f) { #f, offsetof(wc_calibration_t, f) }
static const float_field_t float_fields[] = {
    FIELD(outer_radius_m), FIELD(inner_radius_m), FIELD(friction_area_m2), FIELD(piston_area_m2),
    FIELD(oil_conductance_W_per_K), FIELD(housing_conductance_W_per_K), FIELD(heat_capacity_J_per_K),
    FIELD(viscosity_a1_Pa_s), FIELD(viscosity_b1_per_K), FIELD(viscosity_a2_Pa_s), FIELD(viscosity_b2_per_K),
    FIELD(mu1), FIELD(mu2), FIELD(mu3), FIELD(stribeck_speed_m_s), FIELD(theta1_degC), FIELD(theta2_K),
    FIELD(vfs_gain_Pa_per_mA), FIELD(vfs_time_constant_s), FIELD(return_spring_force_N),
    FIELD(vfs_current_min_mA), FIELD(vfs_current_max_mA), FIELD(control_period_s),
    FIELD(film_squeeze_factor), FIELD(static_friction_factor), FIELD(lock_slip_rad_s), FIELD(breakaway_slip_rad_s),
    FIELD(holding_margin), FIELD(open_clearance_m), FIELD(open_aeration_speed_rad_s),
};
#undef FIELD
#define N_FLOAT_FIELDS (sizeof float_fields / sizeof float_fields[0])

static float *field_ptr(wc_calibration_t *c, size_t i) { return (float *)(void *)((char *)c + float_fields[i].offset); }

/* One mutation of a float (see the top of the file). */
static float mutate(fz_reader_t *r, float x)
{
    const float scale = fmaxf(fabsf(x), 1.0f);
    switch (fz_u8(r) % 6u) {
    case 0: return fz_float(r, -4.0f * scale, 4.0f * scale);
    case 1: return x * exp2f((float)(int8_t)fz_u8(r) / 8.0f);
    case 2: return x * (1.0f + (float)(int16_t)fz_u16(r) / (32768.0f * 32.0f));
    case 3: return -x;
    case 4: {
        const uint8_t n = fz_u8(r);
        float y = x;
        for (unsigned k = 0u; k < (n & 0x7Fu); ++k) { y = nextafterf(y, ((n & 0x80u) != 0u) ? -INFINITY : INFINITY); }
        return y;
    }
    default: return fz_float(r, 0.0f, 2.0f * scale);
    }
}

/* ------------------------------------------------------------------------ */
/* Evaluation of an accepted calibration                                     */
/* ------------------------------------------------------------------------ */

static const float slips[] = { -1047.0f, -100.0f, -0.01f, 0.0f, 0.01f, 100.0f, 1047.0f };
static const float thetas[] = { -40.0f, 20.0f, 120.0f, 250.0f };
static const float requests[] = { 0.0f, 10.0f, 100.0f, 1000.0f, 1e4f };
#define N_SLIPS (sizeof slips / sizeof slips[0])
#define N_THETAS (sizeof thetas / sizeof thetas[0])
#define N_REQUESTS (sizeof requests / sizeof requests[0])

static bool in_range(float x, float lo, float hi) { return (x >= lo) && (x <= hi); }

static void check_torque(const wc_torque_t *t, float slip, const char *what)
{
    FZ_CHECK(fz_finite(t->torque_Nm) && fz_finite(t->coulomb_Nm) && fz_finite(t->viscous_Nm) &&
                 fz_finite(t->hbar_m) && fz_finite(t->mu_f),
             "%s: non-finite torque output: T %g Tc %g Tv %g hbar %g mu_f %g", what, (double)t->torque_Nm,
             (double)t->coulomb_Nm, (double)t->viscous_Nm, (double)t->hbar_m, (double)t->mu_f);
    FZ_CHECK(t->hbar_m > 0.0f, "%s: h_bar %g not positive", what, (double)t->hbar_m);
    FZ_CHECK(t->mu_f > 0.0f, "%s: mu_f %g not positive", what, (double)t->mu_f);
    const bool against = (slip < 0.0f) ? ((t->torque_Nm > 0.0f) || (t->coulomb_Nm > 0.0f) || (t->viscous_Nm > 0.0f))
                                       : ((t->torque_Nm < 0.0f) || (t->coulomb_Nm < 0.0f) || (t->viscous_Nm < 0.0f));
    FZ_CHECK(!against, "%s: torque against the slip %g: T %g (Tc %g, Tv %g)", what, (double)slip,
             (double)t->torque_Nm, (double)t->coulomb_Nm, (double)t->viscous_Nm);
}

static void evaluate(const wc_calibration_t *c)
{
    wc_model_t model;
    fz_context("wc_model_init(accepted calibration)", 0u);
    FZ_CHECK(wc_model_init(&model, c) == WC_CAL_OK, "wc_model_init rejects what wc_calibration_check accepted");
    FZ_CHECK(fz_finite(model.effective_radius_m) && (model.effective_radius_m > 0.0f) &&
                 fz_finite(model.effective_radius_m * (float)model.cal->friction_pairs),
             "R_eff %g, R_eff N_c %g", (double)model.effective_radius_m,
             (double)(model.effective_radius_m * (float)model.cal->friction_pairs));
    FZ_CHECK(fz_finite(model.film_damping_m4) && (model.film_damping_m4 >= 0.0f) &&
                 ((model.film_damping_m4 > 0.0f) == (c->film_squeeze_factor > 0.0f)),
             "squeeze-film damping %g m^4 for phi %g", (double)model.film_damping_m4, (double)c->film_squeeze_factor);
    FZ_CHECK(fz_finite(model.force_max_N) && in_range(model.force_max_N, 0.0f, WC_FORCE_MAX_N),
             "F_max %g outside [0, %g]", (double)model.force_max_N, (double)WC_FORCE_MAX_N);
    FZ_CHECK(fz_finite(model.hbar_at_force_max_m) && (model.hbar_at_force_max_m > 0.0f), "h_bar(F_max) %g",
             (double)model.hbar_at_force_max_m);
    FZ_CHECK(in_range(model.thermal_decay, 0.0f, 1.0f) && in_range(model.vfs_decay, 0.0f, 1.0f),
             "decay factors %g (thermal), %g (VFS) outside [0, 1]", (double)model.thermal_decay,
             (double)model.vfs_decay);
    const float i_min = c->vfs_current_min_mA;
    const float i_max = c->vfs_current_max_mA;

    /* eq. 18 and eq. 2 on the domain */
    for (size_t s = 0u; s < N_SLIPS; ++s) {
        for (size_t k = 0u; k < N_THETAS; ++k) {
            const float v = model.effective_radius_m * fabsf(slips[s]);
            fz_context("wc_friction_coefficient(speed, theta)", 0u);
            fz_arg(v); fz_arg(thetas[k]);
            const float mu = wc_friction_coefficient(c, v, thetas[k]);
            FZ_CHECK(fz_finite(mu) && (mu > 0.0f), "mu_f %g not finite and positive", (double)mu);
        }
    }
    for (size_t k = 0u; k < N_THETAS; ++k) {
        fz_context("wc_viscosity_Pa_s(theta)", 0u);
        fz_arg(thetas[k]);
        const float mu_v = wc_viscosity_Pa_s(c, thetas[k]);
        FZ_CHECK(fz_finite(mu_v) && (mu_v > 0.0f), "mu_v %g not finite and positive", (double)mu_v);
    }

    /* the film interpolant: positive, non-increasing, clamped at the ends */
    const wc_film_table_t *film = &c->film;
    float previous = wc_film_hbar_m(film, -1.0f);
    float previous_p = -1.0f;
    for (uint32_t n = 0u; n + 1u < film->length; ++n) {
        for (unsigned q = 0u; q < 4u; ++q) {
            const float p = film->pressure_Pa[n] + (film->pressure_Pa[n + 1u] - film->pressure_Pa[n]) * (float)q / 4.0f;
            fz_context("wc_film_hbar_m(p) along the table", n);
            fz_arg(p); fz_arg(previous_p);
            const float h = wc_film_hbar_m(film, p);
            FZ_CHECK(fz_finite(h) && (h > 0.0f), "h_bar(%g) = %g not finite and positive", (double)p, (double)h);
            FZ_CHECK(h <= previous * (1.0f + 1e-6f), "h_bar rises with p_c: h(%g) = %.9g > h(%g) = %.9g", (double)p,
                     (double)h, (double)previous_p, (double)previous);
            previous = h;
            previous_p = p;
        }
    }
    const float h_end = wc_film_hbar_m(film, film->pressure_Pa[film->length - 1u] * 2.0f + 1.0f);
    FZ_CHECK(fz_finite(h_end) && (h_end > 0.0f) && (h_end <= previous * (1.0f + 1e-6f)), "h_bar beyond the table %g",
             (double)h_end);

    /* forward model: finite, signed with the slip, non-decreasing in F */
    float forces[5] = { 0.0f, 100.0f, 1000.0f, model.force_max_N, WC_FORCE_MAX_N };
    for (size_t a = 1u; a < 5u; ++a) {  /* sort (insertion): F_max may be anywhere */
        for (size_t b = a; (b > 0u) && (forces[b] < forces[b - 1u]); --b) {
            const float t = forces[b];
            forces[b] = forces[b - 1u];
            forces[b - 1u] = t;
        }
    }
    for (size_t s = 0u; s < N_SLIPS; ++s) {
        for (size_t k = 0u; k < N_THETAS; ++k) {
            float last_abs = 0.0f;
            for (size_t f = 0u; f < 5u; ++f) {
                fz_context("wc_torque(slip, theta, force)", 0u);
                fz_arg(slips[s]); fz_arg(thetas[k]); fz_arg(forces[f]);
                wc_torque_t t;
                const wc_status_t st = wc_torque(&model, slips[s], thetas[k], forces[f], &t);
                FZ_CHECK(st == WC_STATUS_OK, "status 0x%x for valid input", (unsigned)st);
                check_torque(&t, slips[s], "wc_torque");
                FZ_CHECK(fabsf(t.torque_Nm) >= last_abs * (1.0f - 1e-5f), "|T| falls with the force: %.9g after %.9g",
                         (double)fabsf(t.torque_Nm), (double)last_abs);
                last_abs = fabsf(t.torque_Nm);
            }
        }
    }

    /* inverse */
    for (size_t s = 0u; s < N_SLIPS; ++s) {
        for (size_t k = 0u; k < N_THETAS; ++k) {
            for (size_t q = 0u; q < N_REQUESTS; ++q) {
                fz_context("wc_inverse(slip, theta, request)", 0u);
                fz_arg(slips[s]); fz_arg(thetas[k]); fz_arg(requests[q]);
                wc_inverse_t inv;
                const wc_status_t st = wc_inverse(&model, slips[s], thetas[k], requests[q], &inv);
                FZ_CHECK((st & ~(WC_STATUS_BELOW_DRAG | WC_STATUS_SATURATED | WC_STATUS_CURRENT_CLAMPED)) == 0u,
                         "status 0x%x for valid input", (unsigned)st);
                FZ_CHECK(fz_finite(inv.force_N) && fz_finite(inv.pressure_Pa) && fz_finite(inv.current_mA),
                         "non-finite inverse: F %g P %g i %g", (double)inv.force_N, (double)inv.pressure_Pa,
                         (double)inv.current_mA);
                FZ_CHECK(in_range(inv.current_mA, i_min, i_max), "current %g outside [%g, %g]",
                         (double)inv.current_mA, (double)i_min, (double)i_max);
                FZ_CHECK(in_range(inv.force_N, 0.0f, model.force_max_N), "force %g outside [0, %g]",
                         (double)inv.force_N, (double)model.force_max_N);
                FZ_CHECK(inv.iterations <= WC_INVERSE_MAX_ITERATIONS, "iterations %u", (unsigned)inv.iterations);
            }
        }
    }

    /* the control step */
    wc_clutch_t clutch;
    fz_context("wc_clutch_init(20 degC)", 0u);
    FZ_CHECK(wc_clutch_init(&clutch, c, 20.0f) == WC_CAL_OK, "wc_clutch_init rejects an accepted calibration");
    /* the fourth: torque control released into the spring's band below the kiss point's drag (DESIGN 15) */
    static const wc_clutch_mode_t modes[4] = { WC_MODE_TORQUE, WC_MODE_LOCKED, WC_MODE_OPEN, WC_MODE_TORQUE };
    unsigned n = 0u;
    for (size_t k = 0u; k < N_THETAS; ++k) {
        for (size_t s = 0u; s < N_SLIPS; ++s) {
            for (size_t q = 0u; q < N_REQUESTS; ++q) {
                for (size_t m = 0u; m < 4u; ++m) {
                    const wc_step_input_t in = { slips[s], thetas[k], thetas[k], requests[q], modes[m],
                                                 { false, 0.0f, 0.0f }, { 0.0f, 0.0f }, false, 0.0f, { 0.0f, 0.0f, 0.0f },
                                                 m == 3u };
                    fz_context("wc_clutch_step(slip, oil = housing, request; mode)", ++n);
                    fz_arg(slips[s]); fz_arg(thetas[k]); fz_arg(requests[q]);
                    fz_ctx.iargs[0] = (long)modes[m];
                    fz_ctx.iargs[1] = (m == 3u) ? 1 : 0;  /* band_release */
                    wc_step_output_t out;
                    const wc_status_t st = wc_clutch_step(&clutch, &in, &out);
                    FZ_CHECK((st & (WC_STATUS_INPUT_INVALID | WC_STATUS_NOT_INITIALISED)) == 0u,
                             "status 0x%x for valid input", (unsigned)st);
                    FZ_CHECK(fz_finite(out.current_mA) && in_range(out.current_mA, i_min, i_max),
                             "current %g outside [%g, %g]", (double)out.current_mA, (double)i_min, (double)i_max);
                    if (modes[m] == WC_MODE_OPEN) {
                        FZ_CHECK(out.current_mA == i_min, "open: current %g", (double)out.current_mA);
                    } else if (modes[m] == WC_MODE_LOCKED) {
                        FZ_CHECK(out.current_mA == i_max, "locked: current %g", (double)out.current_mA);
                    }
                    FZ_CHECK(fz_finite(out.pressure_command_Pa) && fz_finite(out.pressure_model_Pa) &&
                                 (out.pressure_model_Pa >= 0.0f) && fz_finite(out.force_command_N) &&
                                 in_range(out.force_command_N, 0.0f, model.force_max_N),
                             "pressure command %g, modelled %g, force %g", (double)out.pressure_command_Pa,
                             (double)out.pressure_model_Pa, (double)out.force_command_N);
                    FZ_CHECK(fz_finite(clutch.theta_degC) &&
                                 in_range(clutch.theta_degC, WC_THETA_MIN_degC, WC_THETA_MAX_degC),
                             "estimate %g outside the envelope", (double)clutch.theta_degC);
                    /* inside the lock band the torque keeps the lock direction (DESIGN 9); locked, it is
                     * the held torque, within the static capacity */
                    const float slip = clutch.held.slip_rad_s;
                    const float direction = (clutch.lockup.direction < 0) ? -1.0f : 1.0f;
                    const bool keeps_direction = (fabsf(slip) < c->lock_slip_rad_s) || ((out.status & WC_STATUS_LOCKED) != 0u);
                    check_torque(&out.model, keeps_direction ? direction * fmaxf(fabsf(slip), FLT_MIN) : slip,
                                 "wc_clutch_step");
                    FZ_CHECK(fz_finite(out.static_capacity_Nm) && (out.static_capacity_Nm >= 0.0f) &&
                                 (((out.status & WC_STATUS_LOCKED) == 0u) ||
                                  (fabsf(out.model.torque_Nm) <= out.static_capacity_Nm)),
                             "wc_clutch_step: static capacity %g, torque %g, status 0x%x",
                             (double)out.static_capacity_Nm, (double)out.model.torque_Nm, (unsigned)out.status);
                }
            }
        }
    }
}

/* WC_FUZZ_VERBOSE=1: the calibration under test, for the diagnosis of a finding. */
static void print_calibration(const wc_calibration_t *c)
{
    for (size_t i = 0u; i < N_FLOAT_FIELDS; ++i) {
        const float x = *(const float *)(const void *)((const char *)c + float_fields[i].offset);
        const float t1 = *(const float *)(const void *)((const char *)&wc_table1_calibration + float_fields[i].offset);
        fprintf(stderr, "  %-28s %.9g [%a]%s\n", float_fields[i].name, (double)x, (double)x,
                (fz_bits_of(x) != fz_bits_of(t1)) ? "   (changed)" : "");
    }
    fprintf(stderr, "  %-28s %u\n", "friction_pairs", (unsigned)c->friction_pairs);
    fprintf(stderr, "  film: %u nodes%s\n", (unsigned)c->film.length,
            (c->film.pressure_Pa == wc_table1_calibration.film.pressure_Pa) ? " (table1's arrays)" : " (a copy)");
    if ((c->film.pressure_Pa != NULL) && (c->film.hbar_m != NULL) && (c->film.slope_m_per_Pa != NULL)) {
        for (uint32_t i = 0u; i < c->film.length; ++i) {
            fprintf(stderr, "    [%2u] p %.9g h %.9g s %.9g\n", (unsigned)i, (double)c->film.pressure_Pa[i],
                    (double)c->film.hbar_m[i], (double)c->film.slope_m_per_Pa[i]);
        }
    }
}

/* ------------------------------------------------------------------------ */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if ((size > 0u) && ((data[0] & FZ_GEARBOX_IMAGE_INPUT) == FZ_GEARBOX_IMAGE_INPUT)) {
        fz_gearbox_image_input(data, size, verbose);
        return 0;
    }
    if ((size > 0u) && ((data[0] & FZ_ADAPT_IMAGE_INPUT) != 0u)) {
        fz_adapt_image_input(data, size, verbose);
        return 0;
    }
    fz_reader_t r;
    fz_reader_init(&r, data, size);
    wc_calibration_t c = wc_table1_calibration;
    const wc_film_table_t *t1 = &wc_table1_calibration.film;

    const uint8_t film_mode = fz_u8(&r);
    float *arrays[3] = { NULL, NULL, NULL };
    uint32_t length = 0u;
    if ((film_mode & 3u) != 0u) {
        length = fz_u8(&r) % (FILM_COPY_MAX + 1u);
        const uint8_t offset_byte = fz_u8(&r);
        const float *src[3] = { t1->pressure_Pa, t1->hbar_m, t1->slope_m_per_Pa };
        for (unsigned a = 0u; a < 3u; ++a) {
            /* exactly `length` floats: ASan reports a read past the end */
            arrays[a] = (float *)malloc((length > 0u ? length : 1u) * sizeof(float));
            if (arrays[a] == NULL) { abort(); }
            for (uint32_t i = 0u; i < length; ++i) {
                uint32_t j;
                if ((film_mode & 4u) != 0u) {
                    j = (offset_byte % (t1->length - length + 1u)) + i;  /* contiguous */
                } else {
                    j = (length > 1u) ? (i * (t1->length - 1u)) / (length - 1u) : 0u;  /* spread evenly */
                }
                arrays[a][i] = src[a][j];
            }
        }
        c.film.pressure_Pa = arrays[0];
        c.film.hbar_m = arrays[1];
        c.film.slope_m_per_Pa = arrays[2];
        c.film.length = length;
        if (((film_mode >> 3) & 3u) == 3u) {
            switch ((film_mode >> 5) % 3u) {
            case 0: c.film.pressure_Pa = NULL; break;
            case 1: c.film.hbar_m = NULL; break;
            default: c.film.slope_m_per_Pa = NULL; break;
            }
        }
    }

    for (unsigned e = 0u; (e < MAX_EDITS) && fz_more(&r); ++e) {
        const unsigned target = fz_u8(&r) % (unsigned)(N_FLOAT_FIELDS + 4u);
        if (target < N_FLOAT_FIELDS) {
            float *f = field_ptr(&c, target);
            *f = mutate(&r, *f);
        } else if (target == N_FLOAT_FIELDS) {
            const uint8_t how = fz_u8(&r) % 3u;
            c.friction_pairs = (how == 0u) ? fz_u8(&r)
                             : (how == 1u) ? fz_u32(&r)
                                           : c.friction_pairs + (uint32_t)(int32_t)(int8_t)fz_u8(&r);  /* mod 2^32 */
        } else {
            const unsigned a = target - (unsigned)N_FLOAT_FIELDS - 1u;
            const uint8_t index = fz_u8(&r);
            if ((length > 0u) && (arrays[a] != NULL)) {
                float *node = &arrays[a][index % length];
                *node = mutate(&r, *node);
            }
        }
    }

    fz_context("wc_calibration_check", 0u);
    const wc_cal_error_t err = wc_calibration_check(&c);
    FZ_CHECK((unsigned)err < (unsigned)WC_CAL_ERRORS, "error code %d", (int)err);
    if (verbose) { print_calibration(&c); }
    inputs++;
    if (err == WC_CAL_OK) {
        accepted++;
        evaluate(&c);
    } else {
        wc_model_t model;
        FZ_CHECK(wc_model_init(&model, &c) == err, "wc_model_init and wc_calibration_check disagree");
        FZ_CHECK(model.cal == NULL, "a failed wc_model_init left a usable model");
    }
    if (verbose) {
        fprintf(stderr, "fuzz_calibration: %s (%lu accepted so far)\n", wc_cal_error_name(err), accepted);
    }
    for (unsigned a = 0u; a < 3u; ++a) { free(arrays[a]); }
    return 0;
}
