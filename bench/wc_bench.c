/* Host benchmark of wc_clutch_step and wc_inverse over a grid of operating
 * points: slip 0-3000 rpm, oil 10-120 degC, torque request from 0 to beyond
 * the capacity at the maximum current (table1 calibration).
 *
 * Two modes, chosen by where it runs:
 *  - under valgrind --tool=callgrind --collect-atstart=no (scripts/bench.sh):
 *    every measured call is wrapped in CALLGRIND_TOGGLE_COLLECT and dumped
 *    with CALLGRIND_DUMP_STATS_AT("<call> <operating point>"), so the
 *    callgrind output holds one instruction count per call; an empty toggle
 *    pair ("overhead") is dumped too, for subtraction. The figures come from
 *    the output file (scripts/bench.sh parses it);
 *  - natively: wall-clock ns per call, median over batches. Noisy (frequency
 *    scaling, other load, the host is not the target): a secondary figure.
 *
 *   wc_bench [--quick]     --quick: a coarse grid and few repeats (smoke test)
 */
#define _POSIX_C_SOURCE 199309L

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "wetclutch/wetclutch.h"
#include "wc_table1_calibration.h"

#ifdef WC_HAVE_CALLGRIND_H
#include <valgrind/callgrind.h>
#define WC_ON_VALGRIND() (RUNNING_ON_VALGRIND != 0)
#define WC_COLLECT_TOGGLE() CALLGRIND_TOGGLE_COLLECT
#define WC_DUMP(label) CALLGRIND_DUMP_STATS_AT(label)
#else
#define WC_ON_VALGRIND() 0
#define WC_COLLECT_TOGGLE() ((void)0)
#define WC_DUMP(label) ((void)(label))
#endif

#define WC_ARRAY_LENGTH(a) (sizeof(a) / sizeof((a)[0]))

/* Steps run before the measured one, so the VFS lag has left its rest value
 * (tau = 60 ms) and the film lookup interpolates instead of clamping. */
#define WC_BENCH_WARMUP_STEPS 20u
/* Calls per timed batch (wall clock) and batches per operating point. */
#define WC_BENCH_BATCH 16u
#define WC_BENCH_REPEATS 24u

static const float slip_grid_rpm[] = {0.0f, 10.0f, 50.0f, 200.0f, 500.0f, 1000.0f, 2000.0f, 3000.0f};
static const float theta_grid_degC[] = {10.0f, 25.0f, 40.0f, 60.0f, 80.0f, 100.0f, 120.0f};
/* Torque request as a fraction of the capacity at the maximum current:
 * 0 (below the drag), inside the range, exactly at and above saturation. */
static const float request_grid[] = {0.0f, 0.01f, 0.1f, 0.25f, 0.5f, 0.75f, 0.9f, 0.99f, 1.0f, 1.1f};

static const float quick_slip_rpm[] = {0.0f, 1000.0f, 3000.0f};
static const float quick_theta_degC[] = {10.0f, 120.0f};
static const float quick_request[] = {0.0f, 0.5f, 1.1f};

typedef struct {
    const float *slip_rpm;
    size_t slip_count;
    const float *theta_degC;
    size_t theta_count;
    const float *request;
    size_t request_count;
    uint32_t repeats;
} bench_grid_t;

typedef struct {
    float slip_rpm;
    float theta_degC;
    float request_fraction;
    float request_Nm;
} bench_point_t;

typedef struct {
    uint32_t points;
    uint32_t below_drag;
    uint32_t saturated;
    uint32_t invalid;
    uint32_t max_iterations;
} bench_tally_t;

/* Clutch torque at the maximum current: the capacity the requests scale. */
static float capacity_Nm(const wc_model_t *model, float slip_rad_s, float theta_degC)
{
    wc_torque_t torque;
    (void)wc_torque(model, slip_rad_s, theta_degC, model->force_max_N, &torque);
    return (torque.torque_Nm < 0.0f) ? -torque.torque_Nm : torque.torque_Nm;
}

static wc_step_input_t point_input(const bench_point_t *p)
{
    const wc_step_input_t in = {
        .slip_rad_s = p->slip_rpm * WC_RAD_S_PER_RPM,
        .theta_oil_degC = p->theta_degC,
        .theta_housing_degC = p->theta_degC,
        .torque_request_Nm = p->request_Nm,
        .mode = WC_MODE_TORQUE,
    };
    return in;
}

/* A fresh clutch at the operating point, warmed up. */
static void prepare(wc_clutch_t *clutch, const bench_point_t *p)
{
    if (wc_clutch_init(clutch, &wc_table1_calibration, p->theta_degC) != WC_CAL_OK) {
        fprintf(stderr, "wc_bench: table1 calibration rejected\n");
        exit(2);
    }
    const wc_step_input_t in = point_input(p);
    wc_step_output_t out;
    for (uint32_t i = 0u; i < WC_BENCH_WARMUP_STEPS; ++i) {
        (void)wc_clutch_step(clutch, &in, &out);
    }
}

static void label_of(char *label, size_t size, const char *call, const bench_point_t *p, uint32_t iterations,
                     wc_status_t status)
{
    (void)snprintf(label, size, "%s slip=%.0frpm theta=%.0fC request=%.2fxcap(%.1fNm) iterations=%u status=0x%02x",
                   call, (double)p->slip_rpm, (double)p->theta_degC, (double)p->request_fraction,
                   (double)p->request_Nm, (unsigned)iterations, (unsigned)status);
}

/* Callgrind mode: one dump per measured call. */
static void count_point(const bench_point_t *p, bench_tally_t *tally)
{
    char label[160];
    wc_clutch_t clutch;
    prepare(&clutch, p);
    const wc_step_input_t in = point_input(p);

    WC_COLLECT_TOGGLE();
    WC_COLLECT_TOGGLE();
    WC_DUMP("overhead");

    wc_step_output_t out;
    WC_COLLECT_TOGGLE();
    const wc_status_t step_status = wc_clutch_step(&clutch, &in, &out);
    WC_COLLECT_TOGGLE();
    label_of(label, sizeof label, "wc_clutch_step", p, out.inverse_iterations, step_status);
    WC_DUMP(label);

    wc_inverse_t inv;
    WC_COLLECT_TOGGLE();
    const wc_status_t inv_status = wc_inverse(&clutch.model, in.slip_rad_s, clutch.theta_degC, p->request_Nm, &inv);
    WC_COLLECT_TOGGLE();
    label_of(label, sizeof label, "wc_inverse", p, inv.iterations, inv_status);
    WC_DUMP(label);

    tally->points++;
    if ((inv_status & WC_STATUS_BELOW_DRAG) != 0u) { tally->below_drag++; }
    if ((inv_status & WC_STATUS_SATURATED) != 0u) { tally->saturated++; }
    if (((inv_status | step_status) & WC_STATUS_INPUT_INVALID) != 0u) { tally->invalid++; }
    if (inv.iterations > tally->max_iterations) { tally->max_iterations = inv.iterations; }
    if (out.inverse_iterations > tally->max_iterations) { tally->max_iterations = out.inverse_iterations; }
}

static double now_ns(void)
{
    struct timespec t;
    (void)clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

static volatile float sink;  /* keeps the timed results alive */

/* Wall-clock mode: per-call ns of each batch, appended to the sample arrays. */
static void time_point(const bench_point_t *p, uint32_t repeats, double *step_ns, double *inverse_ns, size_t *count)
{
    const wc_step_input_t in = point_input(p);
    for (uint32_t r = 0u; r < repeats; ++r) {
        wc_clutch_t clutch;
        prepare(&clutch, p);
        wc_step_output_t out;
        float acc = 0.0f;
        const double t0 = now_ns();
        for (uint32_t i = 0u; i < WC_BENCH_BATCH; ++i) {
            (void)wc_clutch_step(&clutch, &in, &out);
            acc += out.current_mA;
        }
        const double t1 = now_ns();
        wc_inverse_t inv;
        for (uint32_t i = 0u; i < WC_BENCH_BATCH; ++i) {
            (void)wc_inverse(&clutch.model, in.slip_rad_s, clutch.theta_degC, p->request_Nm, &inv);
            acc += inv.current_mA;
        }
        const double t2 = now_ns();
        sink = acc;
        step_ns[*count] = (t1 - t0) / (double)WC_BENCH_BATCH;
        inverse_ns[*count] = (t2 - t1) / (double)WC_BENCH_BATCH;
        (*count)++;
    }
}

static int compare_double(const void *a, const void *b)
{
    const double x = *(const double *)a;
    const double y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof v[0], compare_double);
    return (n % 2u) ? v[n / 2u] : 0.5 * (v[n / 2u - 1u] + v[n / 2u]);
}

int main(int argc, char **argv)
{
    bench_grid_t grid = {slip_grid_rpm, WC_ARRAY_LENGTH(slip_grid_rpm), theta_grid_degC,
                         WC_ARRAY_LENGTH(theta_grid_degC), request_grid, WC_ARRAY_LENGTH(request_grid),
                         WC_BENCH_REPEATS};
    if ((argc == 2) && (strcmp(argv[1], "--quick") == 0)) {
        grid = (bench_grid_t){quick_slip_rpm, WC_ARRAY_LENGTH(quick_slip_rpm), quick_theta_degC,
                              WC_ARRAY_LENGTH(quick_theta_degC), quick_request, WC_ARRAY_LENGTH(quick_request), 2u};
    } else if (argc != 1) {
        fprintf(stderr, "usage: %s [--quick]\n", argv[0]);
        return 2;
    }
    const int counting = WC_ON_VALGRIND();
    const size_t points = grid.slip_count * grid.theta_count * grid.request_count;
    double *step_ns = NULL;
    double *inverse_ns = NULL;
    if (!counting) {
        step_ns = malloc(points * grid.repeats * sizeof *step_ns);
        inverse_ns = malloc(points * grid.repeats * sizeof *inverse_ns);
        if ((step_ns == NULL) || (inverse_ns == NULL)) {
            fprintf(stderr, "wc_bench: out of memory\n");
            return 2;
        }
    }

    wc_model_t model;
    if (wc_model_init(&model, &wc_table1_calibration) != WC_CAL_OK) {
        fprintf(stderr, "wc_bench: table1 calibration rejected\n");
        return 2;
    }
    bench_tally_t tally = {0u, 0u, 0u, 0u, 0u};
    size_t samples = 0u;
    for (size_t s = 0u; s < grid.slip_count; ++s) {
        for (size_t t = 0u; t < grid.theta_count; ++t) {
            const float capacity = capacity_Nm(&model, grid.slip_rpm[s] * WC_RAD_S_PER_RPM, grid.theta_degC[t]);
            for (size_t r = 0u; r < grid.request_count; ++r) {
                const bench_point_t p = {grid.slip_rpm[s], grid.theta_degC[t], grid.request[r],
                                         grid.request[r] * capacity};
                if (counting) {
                    count_point(&p, &tally);
                } else {
                    time_point(&p, grid.repeats, step_ns, inverse_ns, &samples);
                }
            }
        }
    }

    printf("wc_bench: %zu operating points (slip %.0f-%.0f rpm, %.0f-%.0f degC, request %.2f-%.2f x capacity)\n",
           points, (double)grid.slip_rpm[0], (double)grid.slip_rpm[grid.slip_count - 1u],
           (double)grid.theta_degC[0], (double)grid.theta_degC[grid.theta_count - 1u], (double)grid.request[0],
           (double)grid.request[grid.request_count - 1u]);
    if (counting) {
        printf("wc_bench: callgrind mode: one dump per call; inverse: %u below drag, %u saturated, "
               "%u with invalid input, at most %u iterations (WC_INVERSE_MAX_ITERATIONS %u)\n",
               (unsigned)tally.below_drag, (unsigned)tally.saturated, (unsigned)tally.invalid,
               (unsigned)tally.max_iterations, (unsigned)WC_INVERSE_MAX_ITERATIONS);
    } else {
        printf("wc_bench: host wall clock (NOISY, secondary figure; %zu batches of %u calls): "
               "median %.1f ns per wc_clutch_step, %.1f ns per wc_inverse\n",
               samples, (unsigned)WC_BENCH_BATCH, median(step_ns, samples), median(inverse_ns, samples));
    }
    free(step_ns);
    free(inverse_ns);
    return (tally.invalid == 0u) ? 0 : 1;
}
