/* Cortex-M4F instruction counts of the library's public functions, under
 * QEMU (DESIGN.md section 11):
 *
 *   qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -semihosting \
 *                   -icount shift=8,sleep=off -kernel wc_arm_bench.elf
 *
 * With -icount shift=8 one instruction takes 2^8 ns of virtual time and the
 * SysTick, clocked from the 25 MHz CPU clock (CLKSOURCE = 1), ticks every
 * 40 ns, so instructions = ticks * 40 / 256, rounded to nearest. SysTick is
 * reloaded before every window; the window is one indirect call of a small
 * thunk that calls the measured function with arguments from a context
 * struct, and the empty thunk's window is subtracted. So a figure is the
 * call as a caller pays it: argument loads, the call, the result store,
 * about 5 instructions over the function's own (thunk_expf: push, vldr, mov,
 * bl, vstr, pop against the empty thunk's bx lr).
 * A block of 1000 nops must read 1000 (else FAIL). QEMU counts
 * instructions, not cycles; repeated runs are byte-identical.
 *
 * Grid (192 points): slip {-3000, -750, -0.25, 0, 0.25, 50, 750, 3000} rpm x
 * clutch temperature {10, 40, 80, 120} degC (oil = housing = theta) x torque
 * request {0, 0.05, 0.3, 0.6, 0.9, 1.1} x the capacity at that point
 * (|wc_torque| at force_max). Per function: samples, median (the lower
 * middle sample) and worst. The inverse is split by the status it returns:
 * below_drag, saturated, and solve (neither: the library's segment search
 * and Newton steps, the naive baseline's bisection). The naive baseline
 * (wc_arm_naive.c: no h_bar table, eq. 15 solved by bisection with
 * erfcf/expf at every torque evaluation) runs on the same points and must
 * agree with wc_inverse within NAIVE_AGREEMENT_mN; the ratio naive /
 * wc_inverse of the solve rows' median and worst is printed.
 *
 * Shift control (DESIGN 10) is measured over a realistic trajectory instead
 * of the grid: one 1->2 upshift (turbine torque 100 Nm, slip 100 rad/s at the
 * inertia phase's start, target 0.5 s, oil 80 degC) on the reduced plant of
 * tests/c/wc_test_fixtures.h (I_t d(slip)/dt = a (T_t - a T_c), the turbine held
 * until the inertia phase, the output side fixed), with the shift
 * calibration of the shift tests (lag compensation 15 ms, observer temperature).
 * Every step that starts in the inertia phase is a sample:
 *   wc_shift_step:inertia       wc_shift_step (clutch step with the lag
 *                               compensation included);
 *   wc_loop_step:shift_inertia  wc_loop_step in Shift mode (TorqueRequest
 *                               Mode 3), three frames (ClutchSensors,
 *                               TorqueRequest, ShiftCommand) queued per period.
 * The shift must complete (LOCKED, one report, no safe step) or RESULT FAIL.
 *
 * The whole shift (DESIGN 14): wc_shift_1_2_whole_full (coordinator 1: fill
 * pulse, off-going capacity control, engine torque request), the off-going
 * clutch a second wc_clutch_t with the same clutch calibration as the
 * on-coming one, one 1->2 upshift (T_t0 100 Nm, on-coming slip 100 rad/s in
 * 1st gear, target 0.5 s, oil 80 degC) on the bench's two-clutch plant
 * (whole_plant_t: output speed held, I_t dw_t/dt = T_t - T_2 - T_1 with both
 * models' torques, stick-slip on the models' static capacities, the engine
 * following its request at once). Every step from the command's edge to the
 * step in which the shift ends is a sample (prepare/fill, torque phase with
 * the off-going capacity control, inertia phase with the off-going clutch's
 * hand-over, lock-up), after 40 idle periods with the coordinator holding
 * 1st gear:
 *   wc_shift_step:whole         wc_shift_step with the off-going clutch
 *                               (wc_shift_offgoing_t): both clutch steps and
 *                               the engine request;
 *   wc_loop_step:whole_shift    wc_loop_step in Shift mode with
 *                               config.offgoing (wc_loop_whole_shift): four
 *                               frames queued per period (ClutchSensors,
 *                               OffgoingSensors, TorqueRequest Mode 3,
 *                               ShiftCommand with the engine's turbine torque),
 *                               four sent (+ OffgoingVfsCommand,
 *                               EngineTorqueRequest), ShiftReport at the end;
 *   :whole_film, :whole_shift_film  the same with bench_identified (film on).
 * Each prints its worst step per part of the shift (WHOLE lines: start,
 * prepare, torque, inertia, lockup). The shift must complete (LOCKED, one
 * report, no abort, no fallback, the off-going slip below -handover_slip,
 * the engine asked for more and for less torque, every frame used, no safe
 * step) or RESULT FAIL. RAM lines: sizeof(wc_loop_t) (it holds the second
 * clutch, its input, output, E2E input and sensors whether or not the whole
 * shift runs), wc_clutch_t, wc_shift_t, the loop's off-going parts, and the
 * state a caller of wc_shift_step keeps for the whole shift.
 *
 * The calibration image (DESIGN 13): one wc_cal_image_load of the committed
 * lut/wc_table1_cal_image.h (linked into its own .wc_calibration section,
 * mps2_an386.ld), which must be accepted (image, film layout,
 * wc_calibration_check, wc_shift_calibration_check, loop limits) and give
 * table1 (row wc_cal_image_load:table1_full; one sample: the same bytes
 * every time).
 *
 * The XCP on CAN slave (wc_xcp.h) in a calibration session: the loop on the
 * committed image in torque control, wc_xcp_step right after each
 * wc_loop_step, a master's command frames (wc_arm_xcp.c) received one a
 * period; rows wc_xcp_step:idle (connected, nothing to do),
 * :daq_8_signals (one DAQ list, 8 floats of wc_loop_t.last in 8 ODTs,
 * configured by FREE_DAQ .. START_STOP_SYNCH), :checksum_page
 * (BUILD_CHECKSUM over the page) and :download_page_check (a DOWNLOAD of the
 * shift PI gain: the whole-page check and wc_loop_recalibrate), the last two
 * with the DAQ list running; every response, DAQ frame's bytes, checksum and
 * accepted page is checked. Then the page check's parts
 * (wc_cal_image_decode:page, wc_loop_recalibrate:table1_full) and the CRC-32
 * of the largest checksum block (wc_image_crc32:4096B).
 *
 * Output lines (parsed by scripts/bench_arm.sh):
 *   EMPTY <instructions>        window overhead, subtracted from every figure
 *   NOP <instructions>          1000 nops (must read 1000)
 *   ROW <name> <samples> <median> <worst>
 *   RAM <name> <bytes>          sizes of the whole shift's state (sizeof on the target)
 *   WHOLE ...                   the whole shift's rows: worst per part, what the shift did
 *   NAIVE ...                   naive-vs-library force check and ratio
 *   RESULT OK | RESULT FAIL <why>
 * main returns 0 only with RESULT OK (startup.S turns it into QEMU's exit code).
 */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_cal_image.h>
#include <wetclutch_can/wc_can_signals.h>
#include <wetclutch_can/wc_loop.h>
#include <wetclutch_can/wc_xcp.h>

#include "wc_arm_calibration.h"
#include "wc_arm_io.h"
#include "wc_arm_naive.h"
#include "wc_arm_xcp.h"
#include "wc_shift_1_2_shift.h"    /* lut/: wc_shift_1_2_whole_full, the whole shift's calibration */
#include "wc_table1_cal_image.h"  /* lut/: table1 + shift_1_2_full, in the .wc_calibration section */
#include "wc_test_fixtures.h"  /* tests/c: the shift scenario of the C tests */

#ifndef WC_ARM_BENCH_LEVEL
#define WC_ARM_BENCH_LEVEL unknown
#endif
#define WC_STR_(x) #x
#define WC_STR(x) WC_STR_(x)

#define WC_ARRAY_LENGTH(a) (sizeof(a) / sizeof((a)[0]))

/* SysTick (ARMv7-M architecture reference, B3.3). */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_CSR_ENABLE 0x1u
#define SYST_CSR_CLKSOURCE_CPU 0x4u  /* the processor clock: 25 MHz on mps2-an386 */
#define SYST_MAX 0x00FFFFFFu         /* 24-bit down-counter */

#define NS_PER_TICK 40u              /* 25 MHz */
#define ICOUNT_SHIFT 8u              /* -icount shift=8: 256 ns per instruction */
/* A window must stay well inside one SysTick period (2^24 ticks = 2.6 M instructions). */
#define WINDOW_MAX_INSTRUCTIONS 2000000u

#define NOP_BLOCK 1000u
#define WARMUP_STEPS 3u

/* The TorqueRequest signal's DBC range is 0..2000 Nm (hil/wetclutch.dbc):
 * the loop's request is capped there so that every frame is plausible. */
#define LOOP_REQUEST_MAX_Nm 2000.0f
/* The naive inverse must agree with wc_inverse within this: the table's
 * 3.9e-5 relative error and both solvers' 0.01 N tolerances stay far below. */
#define NAIVE_AGREEMENT_mN 5000u

static const float slip_grid_rpm[] = {-3000.0f, -750.0f, -0.25f, 0.0f, 0.25f, 50.0f, 750.0f, 3000.0f};
static const float theta_grid_degC[] = {10.0f, 40.0f, 80.0f, 120.0f};
static const float request_grid[] = {0.0f, 0.05f, 0.3f, 0.6f, 0.9f, 1.1f};

#define GRID_POINTS (WC_ARRAY_LENGTH(slip_grid_rpm) * WC_ARRAY_LENGTH(theta_grid_degC) * WC_ARRAY_LENGTH(request_grid))

typedef enum {
    ROW_CLUTCH_STEP = 0,
    ROW_CLUTCH_STEP_FILM,
    ROW_CLUTCH_STEP_FILM_LAG,
    ROW_INVERSE_SOLVE,
    ROW_INVERSE_BELOW_DRAG,
    ROW_INVERSE_SATURATED,
    ROW_NAIVE_SOLVE,
    ROW_NAIVE_BELOW_DRAG,
    ROW_NAIVE_SATURATED,
    ROW_TORQUE,
    ROW_THERMAL_STEP,
    ROW_FRICTION_VISCOSITY,
    ROW_EXPF,
    ROW_LOOP_STEP,
    ROW_DECODE_CLUTCH_SENSORS,
    ROW_DECODE_TORQUE_REQUEST,
    ROW_ENCODE_VFS_COMMAND,
    ROW_ENCODE_CLUTCH_ESTIMATE,
    ROW_CRC8,
    ROW_SHIFT_STEP,
    ROW_LOOP_STEP_SHIFT,
    ROW_SHIFT_STEP_FILM,
    ROW_LOOP_STEP_SHIFT_FILM,
    ROW_SHIFT_STEP_ADAPT,
    ROW_SHIFT_END_ADAPT,
    ROW_CAL_IMAGE_LOAD,
    ROW_XCP_IDLE,
    ROW_XCP_DAQ,
    ROW_XCP_CHECKSUM_PAGE,
    ROW_XCP_DOWNLOAD_CHECK,
    ROW_CRC32_MAX_BLOCK,
    ROW_CAL_IMAGE_DECODE,
    ROW_LOOP_RECALIBRATE,
    ROW_SHIFT_STEP_WHOLE,
    ROW_LOOP_STEP_WHOLE,
    ROW_SHIFT_STEP_WHOLE_FILM,
    ROW_LOOP_STEP_WHOLE_FILM,
    ROWS
} row_t;

/* Names as in bench/arm_ceilings.txt (no spaces). */
static const char *const row_name[ROWS] = {
    [ROW_CLUTCH_STEP] = "wc_clutch_step",
    [ROW_SHIFT_STEP_ADAPT] = "wc_shift_step:inertia_adaptive",
    [ROW_SHIFT_END_ADAPT] = "wc_shift_step:end_adaptive",
    [ROW_CAL_IMAGE_LOAD] = "wc_cal_image_load:table1_full",
    [ROW_XCP_IDLE] = "wc_xcp_step:idle",
    [ROW_XCP_DAQ] = "wc_xcp_step:daq_8_signals",
    [ROW_XCP_CHECKSUM_PAGE] = "wc_xcp_step:checksum_page",
    [ROW_XCP_DOWNLOAD_CHECK] = "wc_xcp_step:download_page_check",
    [ROW_CRC32_MAX_BLOCK] = "wc_image_crc32:4096B",
    [ROW_CAL_IMAGE_DECODE] = "wc_cal_image_decode:page",
    [ROW_LOOP_RECALIBRATE] = "wc_loop_recalibrate:table1_full",
    [ROW_CLUTCH_STEP_FILM] = "wc_clutch_step:film",
    [ROW_CLUTCH_STEP_FILM_LAG] = "wc_clutch_step:film_lag",
    [ROW_INVERSE_SOLVE] = "wc_inverse:solve",
    [ROW_INVERSE_BELOW_DRAG] = "wc_inverse:below_drag",
    [ROW_INVERSE_SATURATED] = "wc_inverse:saturated",
    [ROW_NAIVE_SOLVE] = "naive_inverse:solve",
    [ROW_NAIVE_BELOW_DRAG] = "naive_inverse:below_drag",
    [ROW_NAIVE_SATURATED] = "naive_inverse:saturated",
    [ROW_TORQUE] = "wc_torque",
    [ROW_THERMAL_STEP] = "wc_thermal_step",
    [ROW_FRICTION_VISCOSITY] = "wc_friction_coefficient+wc_viscosity_Pa_s",
    [ROW_EXPF] = "expf",
    [ROW_LOOP_STEP] = "wc_loop_step",
    [ROW_DECODE_CLUTCH_SENSORS] = "wc_can_decode_clutch_sensors",
    [ROW_DECODE_TORQUE_REQUEST] = "wc_can_decode_torque_request",
    [ROW_ENCODE_VFS_COMMAND] = "wc_can_encode_vfs_command",
    [ROW_ENCODE_CLUTCH_ESTIMATE] = "wc_can_encode_clutch_estimate",
    [ROW_CRC8] = "wc_e2e_crc8_j1850:8B",
    [ROW_SHIFT_STEP] = "wc_shift_step:inertia",
    [ROW_LOOP_STEP_SHIFT] = "wc_loop_step:shift_inertia",
    [ROW_SHIFT_STEP_FILM] = "wc_shift_step:inertia_film",
    [ROW_LOOP_STEP_SHIFT_FILM] = "wc_loop_step:shift_inertia_film",
    [ROW_SHIFT_STEP_WHOLE] = "wc_shift_step:whole",
    [ROW_LOOP_STEP_WHOLE] = "wc_loop_step:whole_shift",
    [ROW_SHIFT_STEP_WHOLE_FILM] = "wc_shift_step:whole_film",
    [ROW_LOOP_STEP_WHOLE_FILM] = "wc_loop_step:whole_shift_film",
};

/* Shift trajectory: the inertia phase lasts at most target * timeout factor = 750 periods; the whole
 * shift's rows sample every step of the shift: prepare 50 + torque phase 220 + inertia at most 800 +
 * hand-over at most 200 periods (wc_shift_1_2_whole_full, target 0.5 s). */
#define SHIFT_SAMPLES_MAX 1536u
/* expf: two arguments per grid point; the shift rows: one per inertia-phase period */
/* wc_clutch_step:film_lag: the steps of FILM_LAG_STEPS per grid point */
#define FILM_LAG_SAMPLES_PER_POINT 6u
#define SAMPLES_PER_ROW ((FILM_LAG_SAMPLES_PER_POINT * GRID_POINTS > SHIFT_SAMPLES_MAX) ? \
                         FILM_LAG_SAMPLES_PER_POINT * GRID_POINTS : SHIFT_SAMPLES_MAX)
static uint32_t samples[ROWS][SAMPLES_PER_ROW];
static uint32_t sample_count[ROWS];

/* Everything a thunk reads or writes: arguments in, results out. */
typedef struct {
    const wc_model_t *model;
    const wc_calibration_t *cal;
    float slip_rad_s;
    float theta_degC;
    float request_Nm;
    float force_N;
    float power_W;
    float speed_m_s;
    float exp_argument;
    float theta_state_degC;
    float mu_f;
    float mu_v_Pa_s;
    float exp_value;
    wc_status_t status;
    wc_inverse_t inverse;
    wc_torque_t torque;
    wc_clutch_t *clutch;
    wc_step_input_t step_in;
    wc_step_output_t step_out;
    wc_loop_t *loop;
    wc_can_frame_t tx[WC_LOOP_TX_FRAMES];
    uint32_t tx_frames;
    uint8_t sensors_frame[8];
    uint8_t request_frame[8];
    uint8_t out_frame[8];
    wc_can_clutch_sensors_phys_t sensors;
    wc_can_torque_request_phys_t request;
    wc_can_vfs_command_phys_t vfs;
    wc_can_clutch_estimate_phys_t estimate;
    wc_can_result_t can_result;
    uint8_t crc;
    wc_shift_t *shift;
    const wc_shift_calibration_t *shift_cal;
    wc_adapt_t *adapt;                       /* the shift rows: NULL (adaptation off) or the adaptive run's */
    wc_shift_offgoing_t *offgoing;           /* the whole shift's rows: the off-going clutch and the engine */
    wc_shift_command_t shift_command;
    wc_shift_report_t shift_report;
    wc_cal_set_t *cal_set;
    wc_cal_image_status_t cal_image_status;
    bool shift_ended;
    wc_xcp_t *xcp;
    wc_can_frame_t xcp_tx[WC_XCP_TX_FRAMES];
    uint32_t xcp_frames;
    const uint8_t *payload;                  /* wc_cal_image_decode's */
    const uint8_t *crc_data;                 /* wc_image_crc32's, crc_length bytes */
    uint32_t crc_length;
    uint32_t crc32;
    wc_cal_error_t cal_error;
} bench_ctx_t;

typedef void (*thunk_t)(void *ctx);

/* noipa: never inlined, cloned or specialised, so each window holds exactly
 * one indirect call and the measured code cannot be scheduled across the
 * SysTick reads. */
#define THUNK(name) __attribute__((noipa)) static void name(void *ctx)

THUNK(thunk_empty) { (void)ctx; }
THUNK(thunk_nops)
{
    (void)ctx;
    __asm__ volatile(".rept 1000\n\tnop\n\t.endr" ::: "memory");
}
THUNK(thunk_clutch_step)
{
    bench_ctx_t *c = ctx;
    c->status = wc_clutch_step(c->clutch, &c->step_in, &c->step_out);
}
THUNK(thunk_inverse)
{
    bench_ctx_t *c = ctx;
    c->status = wc_inverse(c->model, c->slip_rad_s, c->theta_degC, c->request_Nm, &c->inverse);
}
THUNK(thunk_naive_inverse)
{
    bench_ctx_t *c = ctx;
    c->status = wc_arm_naive_inverse(c->model, c->slip_rad_s, c->theta_degC, c->request_Nm, &c->inverse);
}
THUNK(thunk_torque)
{
    bench_ctx_t *c = ctx;
    c->status = wc_torque(c->model, c->slip_rad_s, c->theta_degC, c->force_N, &c->torque);
}
THUNK(thunk_thermal_step)
{
    bench_ctx_t *c = ctx;
    c->status = wc_thermal_step(c->model, &c->theta_state_degC, c->power_W, c->theta_degC, c->theta_degC);
}
THUNK(thunk_friction_viscosity)
{
    bench_ctx_t *c = ctx;
    c->mu_f = wc_friction_coefficient(c->cal, c->speed_m_s, c->theta_degC);
    c->mu_v_Pa_s = wc_viscosity_Pa_s(c->cal, c->theta_degC);
}
THUNK(thunk_expf)
{
    bench_ctx_t *c = ctx;
    c->exp_value = expf(c->exp_argument);
}
THUNK(thunk_loop_step)
{
    bench_ctx_t *c = ctx;
    c->tx_frames = wc_loop_step(c->loop, c->tx);
}
THUNK(thunk_shift_step)
{
    bench_ctx_t *c = ctx;
    c->shift_ended = wc_shift_step(c->shift, c->shift_cal, &c->shift_command, false, c->clutch, c->adapt, &c->step_in,
                                   &c->step_out, &c->shift_report, NULL);
}
THUNK(thunk_whole_shift_step)
{
    bench_ctx_t *c = ctx;
    c->shift_ended = wc_shift_step(c->shift, c->shift_cal, &c->shift_command, false, c->clutch, c->adapt, &c->step_in,
                                   &c->step_out, &c->shift_report, c->offgoing);
}
THUNK(thunk_decode_clutch_sensors)
{
    bench_ctx_t *c = ctx;
    c->can_result = wc_can_decode_clutch_sensors(&c->sensors, c->sensors_frame, sizeof c->sensors_frame);
}
THUNK(thunk_decode_torque_request)
{
    bench_ctx_t *c = ctx;
    c->can_result = wc_can_decode_torque_request(&c->request, c->request_frame, sizeof c->request_frame);
}
THUNK(thunk_encode_vfs_command)
{
    bench_ctx_t *c = ctx;
    c->can_result = wc_can_encode_vfs_command(c->out_frame, &c->vfs, sizeof c->out_frame);
}
THUNK(thunk_encode_clutch_estimate)
{
    bench_ctx_t *c = ctx;
    c->can_result = wc_can_encode_clutch_estimate(c->out_frame, &c->estimate, sizeof c->out_frame);
}
THUNK(thunk_cal_image_load)
{
    bench_ctx_t *c = ctx;
    c->cal_image_status = wc_cal_image_load(wc_table1_cal_image, sizeof wc_table1_cal_image, c->cal_set);
}
THUNK(thunk_xcp_step)
{
    bench_ctx_t *c = ctx;
    c->xcp_frames = wc_xcp_step(c->xcp, true, c->xcp_tx);
}
THUNK(thunk_crc32)
{
    bench_ctx_t *c = ctx;
    c->crc32 = wc_image_crc32(c->crc_data, c->crc_length);
}
THUNK(thunk_cal_image_decode)
{
    bench_ctx_t *c = ctx;
    c->cal_image_status = wc_cal_image_decode(c->payload, c->cal_set);
}
THUNK(thunk_loop_recalibrate)
{
    bench_ctx_t *c = ctx;
    c->cal_error = wc_loop_recalibrate(c->loop, &c->cal_set->clutch, &c->cal_set->loop);
}
THUNK(thunk_crc8)
{
    bench_ctx_t *c = ctx;
    c->crc = wc_e2e_crc8_j1850(c->sensors_frame, sizeof c->sensors_frame);
}

/* SysTick ticks over one call of thunk(ctx). */
__attribute__((noipa)) static uint32_t window_ticks(thunk_t thunk, void *ctx)
{
    SYST_CSR = 0u;
    SYST_RVR = SYST_MAX;
    SYST_CVR = 0u;  /* any write clears the counter */
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_CLKSOURCE_CPU;
    const uint32_t start = SYST_CVR;
    thunk(ctx);
    const uint32_t end = SYST_CVR;
    return (start - end) & SYST_MAX;
}

static uint32_t window_instructions(thunk_t thunk, void *ctx)
{
    const uint32_t ticks = window_ticks(thunk, ctx);
    return (ticks * NS_PER_TICK + (1u << (ICOUNT_SHIFT - 1u))) >> ICOUNT_SHIFT;
}

static uint32_t empty_window;
static bool failed;
static const char *fail_reason = "";

static void fail(const char *reason)
{
    if (!failed) {
        failed = true;
        fail_reason = reason;
    }
    wc_arm_puts("FAIL ");
    wc_arm_puts(reason);
    wc_arm_puts("\n");
}

static uint32_t measure(thunk_t thunk, bench_ctx_t *ctx)
{
    const uint32_t raw = window_instructions(thunk, ctx);
    if ((raw < empty_window) || (raw > WINDOW_MAX_INSTRUCTIONS)) {
        fail("window outside [empty window, WINDOW_MAX_INSTRUCTIONS]");
        return 0u;
    }
    return raw - empty_window;
}

static void record(row_t row, uint32_t instructions)
{
    if (sample_count[row] < SAMPLES_PER_ROW) {
        samples[row][sample_count[row]] = instructions;
        sample_count[row]++;
    }
}

static void sort(uint32_t *v, uint32_t n)
{
    for (uint32_t i = 1u; i < n; ++i) {
        const uint32_t x = v[i];
        uint32_t j = i;
        while ((j > 0u) && (v[j - 1u] > x)) {
            v[j] = v[j - 1u];
            j--;
        }
        v[j] = x;
    }
}

/* Inverse rows by the status the call returned. */
static row_t inverse_row(wc_status_t status, row_t solve)
{
    if ((status & WC_STATUS_BELOW_DRAG) != 0u) { return (row_t)(solve + 1); }
    if ((status & WC_STATUS_SATURATED) != 0u) { return (row_t)(solve + 2); }
    return solve;
}

static void put_point(float slip_rpm, float theta_degC, float fraction)
{
    wc_arm_puts(" at slip ");
    wc_arm_put_i32((int32_t)lroundf(slip_rpm * 100.0f));
    wc_arm_puts("e-2 rpm, theta ");
    wc_arm_put_i32((int32_t)lroundf(theta_degC));
    wc_arm_puts(" degC, request ");
    wc_arm_put_u32((uint32_t)lroundf(fraction * 100.0f));
    wc_arm_puts("% of capacity");
}

static wc_model_t model;
static wc_clutch_t clutch;
static wc_calibration_t film_calibration;  /* table1 with the squeeze-film state on (DESIGN 9) */
static wc_loop_t loop;
static bench_ctx_t ctx;

/* One ClutchSensors and one TorqueRequest frame with alive counter `alive`,
 * queued in the loop. */
static void queue_frames(float slip_rpm, float theta_degC, float request_Nm, uint8_t alive)
{
    const wc_can_clutch_sensors_phys_t sensors = {slip_rpm, theta_degC, theta_degC, alive};
    const wc_can_torque_request_phys_t request = {fminf(request_Nm, LOOP_REQUEST_MAX_Nm),
                                                  WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, alive};
    if ((wc_can_encode_clutch_sensors(ctx.sensors_frame, &sensors, sizeof ctx.sensors_frame) != WC_CAN_OK) ||
        (wc_can_encode_torque_request(ctx.request_frame, &request, sizeof ctx.request_frame) != WC_CAN_OK)) {
        fail("encoding the loop's input frames");
    }
    wc_can_frame_t frame = {WC_CAN_CLUTCH_SENSORS_FRAME_ID, 8u, 0u, {0u}};
    for (uint32_t i = 0u; i < 8u; ++i) { frame.data[i] = ctx.sensors_frame[i]; }
    (void)wc_loop_receive(&loop, &frame);
    frame.id = WC_CAN_TORQUE_REQUEST_FRAME_ID;
    for (uint32_t i = 0u; i < 8u; ++i) { frame.data[i] = ctx.request_frame[i]; }
    (void)wc_loop_receive(&loop, &frame);
}

/* Where the naive inverse differs most from wc_inverse. */
typedef struct {
    float diff_N;
    float force_N;  /* wc_inverse's */
    float slip_rpm;
    float theta_degC;
    float fraction;
} worst_diff_t;

/* The film_lag row's measured steps of a fresh clutch: the first, the lead at
 * work while the film closes (the film settles in about 0.1 s), and settled. */
#define FILM_LAG_TIME_s 0.015f
static const uint32_t film_lag_steps[FILM_LAG_SAMPLES_PER_POINT] = {1u, 4u, 10u, 25u, 60u, 150u};

static void bench_point(float slip_rpm, float theta_degC, float fraction, worst_diff_t *worst)
{
    const float slip_rad_s = slip_rpm * WC_RAD_S_PER_RPM;
    ctx.model = &model;
    ctx.cal = model.cal;
    ctx.slip_rad_s = slip_rad_s;
    ctx.theta_degC = theta_degC;

    wc_torque_t capacity;
    if (wc_torque(&model, slip_rad_s, theta_degC, model.force_max_N, &capacity) != WC_STATUS_OK) {
        fail("capacity: wc_torque rejected a grid point");
    }
    const float request_Nm = fraction * fabsf(capacity.torque_Nm);
    ctx.request_Nm = request_Nm;

    /* wc_inverse, then the naive baseline at the same point. */
    const uint32_t inverse_count = measure(thunk_inverse, &ctx);
    const wc_status_t inverse_status = ctx.status;
    const wc_inverse_t inverse = ctx.inverse;
    if ((inverse_status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_inverse rejected a grid point"); }
    record(inverse_row(inverse_status, ROW_INVERSE_SOLVE), inverse_count);

    const uint32_t naive_count = measure(thunk_naive_inverse, &ctx);
    const row_t naive_row = inverse_row(ctx.status, ROW_NAIVE_SOLVE);
    record(naive_row, naive_count);
    if ((naive_row - ROW_NAIVE_SOLVE) != (inverse_row(inverse_status, ROW_INVERSE_SOLVE) - ROW_INVERSE_SOLVE)) {
        wc_arm_puts("NAIVE case differs from wc_inverse");
        put_point(slip_rpm, theta_degC, fraction);
        wc_arm_puts("\n");
        fail("naive inverse: below-drag/saturated case differs from wc_inverse");
    }
    const float diff_N = fabsf(ctx.inverse.force_N - inverse.force_N);
    if (diff_N > worst->diff_N) {
        *worst = (worst_diff_t){diff_N, inverse.force_N, slip_rpm, theta_degC, fraction};
    }

    /* wc_torque at the force the inverse found. */
    ctx.force_N = inverse.force_N;
    record(ROW_TORQUE, measure(thunk_torque, &ctx));
    const float torque_Nm = ctx.torque.torque_Nm;

    /* Observer step with the heat input of that torque. */
    ctx.theta_state_degC = theta_degC;
    ctx.power_W = fabsf(torque_Nm * slip_rad_s);
    record(ROW_THERMAL_STEP, measure(thunk_thermal_step, &ctx));

    ctx.speed_m_s = model.effective_radius_m * fabsf(slip_rad_s);
    record(ROW_FRICTION_VISCOSITY, measure(thunk_friction_viscosity, &ctx));

    /* expf at the model's typical arguments: the two viscosity exponents of eq. 2. */
    ctx.exp_argument = model.cal->viscosity_b1_per_K * theta_degC;
    record(ROW_EXPF, measure(thunk_expf, &ctx));
    ctx.exp_argument = model.cal->viscosity_b2_per_K * theta_degC;
    record(ROW_EXPF, measure(thunk_expf, &ctx));

    /* wc_clutch_step: a fresh clutch at theta, the 4th step measured. */
    if (wc_clutch_init(&clutch, model.cal, theta_degC) != WC_CAL_OK) { fail("wc_clutch_init"); }
    ctx.clutch = &clutch;
    ctx.step_in = (wc_step_input_t){.slip_rad_s = slip_rad_s, .theta_oil_degC = theta_degC,
                                    .theta_housing_degC = theta_degC, .torque_request_Nm = request_Nm,
                                    .mode = WC_MODE_TORQUE, .bench = {false, 0.0f, 0.0f}};
    for (uint32_t k = 0u; k < WARMUP_STEPS; ++k) { thunk_clutch_step(&ctx); }
    record(ROW_CLUTCH_STEP, measure(thunk_clutch_step, &ctx));
    if ((ctx.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step rejected a grid point"); }
    const wc_step_output_t step = ctx.step_out;

    /* The same with the squeeze-film state on: a fresh clutch (open film), the 4th step measured. */
    if (wc_clutch_init(&clutch, &film_calibration, theta_degC) != WC_CAL_OK) { fail("wc_clutch_init (film)"); }
    for (uint32_t k = 0u; k < WARMUP_STEPS; ++k) { thunk_clutch_step(&ctx); }
    record(ROW_CLUTCH_STEP_FILM, measure(thunk_clutch_step, &ctx));
    if ((ctx.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step (film) rejected a grid point"); }

    /* The configuration the shift controller runs the clutch in: the identified
     * calibration (film on) with the lag compensation of 15 ms (shift_1_2.toml),
     * a fresh clutch at the open film; the steps of FILM_LAG_STEPS measured, so
     * that the film's approach (lead active, then settled) is on the grid. */
    if (wc_clutch_init(&clutch, wc_arm_identified_calibration, theta_degC) != WC_CAL_OK) {
        fail("wc_clutch_init (identified)");
    }
    ctx.step_in.lag_compensation = wc_lag_compensation(&clutch, FILM_LAG_TIME_s);
    for (uint32_t k = 1u, next = 0u; next < FILM_LAG_SAMPLES_PER_POINT; ++k) {
        if (k == film_lag_steps[next]) {
            record(ROW_CLUTCH_STEP_FILM_LAG, measure(thunk_clutch_step, &ctx));
            if ((ctx.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step (film, lag) rejected a grid point"); }
            next++;
        } else {
            thunk_clutch_step(&ctx);
        }
    }
    ctx.step_in.lag_compensation = wc_lag_compensation(&clutch, 0.0f);  /* off */

    /* wc_loop_step: both input frames queued every period, the 4th step measured. */
    /* The default configuration with a one-period recovery debounce, so that the
     * 4th step is a controlling one (the debounce counts periods, it costs nothing). */
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.recovery_periods = 1u;
    if (wc_loop_init(&loop, model.cal, &config, theta_degC) != WC_CAL_OK) { fail("wc_loop_init"); }
    ctx.loop = &loop;
    for (uint8_t k = 0u; k <= WARMUP_STEPS; ++k) {
        queue_frames(slip_rpm, theta_degC, request_Nm, k);
        if (k < WARMUP_STEPS) {
            thunk_loop_step(&ctx);
        } else {
            record(ROW_LOOP_STEP, measure(thunk_loop_step, &ctx));
        }
    }
    const uint32_t frames_in = 2u * (WARMUP_STEPS + 1u);
    if ((ctx.tx_frames != WC_LOOP_TX_CYCLIC) || (loop.counters.frames_used != frames_in) ||
        (loop.counters.safe_steps != 0u)) {
        wc_arm_puts("LOOP frames used ");
        wc_arm_put_u32(loop.counters.frames_used);
        wc_arm_puts(", safe steps ");
        wc_arm_put_u32(loop.counters.safe_steps);
        put_point(slip_rpm, theta_degC, fraction);
        wc_arm_puts("\n");
        fail("wc_loop_step: an input frame was rejected or the loop was in the safe state");
    }

    /* The frame codec and the CRC, on the last period's frames. */
    record(ROW_DECODE_CLUTCH_SENSORS, measure(thunk_decode_clutch_sensors, &ctx));
    if (ctx.can_result != WC_CAN_OK) { fail("wc_can_decode_clutch_sensors"); }
    record(ROW_DECODE_TORQUE_REQUEST, measure(thunk_decode_torque_request, &ctx));
    if (ctx.can_result != WC_CAN_OK) { fail("wc_can_decode_torque_request"); }
    ctx.vfs = (wc_can_vfs_command_phys_t){step.current_mA, 0.001f * step.pressure_command_Pa, 0u, WARMUP_STEPS};
    record(ROW_ENCODE_VFS_COMMAND, measure(thunk_encode_vfs_command, &ctx));
    ctx.estimate = (wc_can_clutch_estimate_phys_t){step.theta_degC, step.model.torque_Nm, step.model.mu_f,
                                                   1.0e6f * step.model.hbar_m, 0u};
    record(ROW_ENCODE_CLUTCH_ESTIMATE, measure(thunk_encode_clutch_estimate, &ctx));
    record(ROW_CRC8, measure(thunk_crc8, &ctx));
}

/* ------------------------------------------------------------------------ */
/* Shift control over one upshift (DESIGN 10)                               */

#define SHIFT_TURBINE_TORQUE_Nm WC_TEST_SHIFT_TURBINE_TORQUE_Nm
#define SHIFT_START_SLIP_rad_s WC_TEST_SHIFT_START_SLIP_rad_s
#define SHIFT_TARGET_TIME_s WC_TEST_SHIFT_TARGET_TIME_s
#define SHIFT_OIL_degC WC_TEST_SHIFT_OIL_degC
#define SHIFT_MAX_PERIODS 3000u

/* The C tests' shift calibration (tests/c/wc_test_fixtures.h). */
static const wc_shift_calibration_t shift_calibration = WC_TEST_SHIFT_CALIBRATION;

/* The plant of tests/c/wc_test_fixtures.h (the shift tests' too): the turbine held by the off-going clutch
 * until the inertia phase, then I_t d(slip)/dt = a (T_t - a T_c); the plates
 * stick at zero slip and while the model is locked. */
typedef struct {
    float slip_rad_s;
    bool released;
} shift_plant_t;

static void plant_advance(shift_plant_t *p, uint32_t phase, const wc_step_output_t *out)
{
    if (phase == (uint32_t)WC_SHIFT_INERTIA) { p->released = true; }
    if (!p->released) { return; }
    p->slip_rad_s = wc_test_shift_plant_slip_rad_s(&shift_calibration, p->slip_rad_s, SHIFT_TURBINE_TORQUE_Nm, out,
                                                   wc_arm_calibration->control_period_s);
}

static wc_shift_t shift;
static wc_adapt_t adapt;
static wc_shift_calibration_t shift_adaptive;  /* shift_calibration with adaptation on (DESIGN 12) */

/* wc_shift_step on its own: every step that starts in the inertia phase;
 * adaptive: with adaptation on (its samples), and end_row the step in which
 * the shift ends (the adaptation's update, wc_adapt_finish). */
static void bench_shift_step(const wc_calibration_t *cal, row_t row, bool adaptive, row_t end_row)
{
    shift_adaptive = shift_calibration;
    shift_adaptive.adaptation = 1u;
    wc_adapt_reset(&adapt);
    if ((wc_shift_calibration_check(&shift_adaptive) != WC_SHIFT_CAL_OK) ||
        (wc_clutch_init(&clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("shift: calibration");
        return;
    }
    wc_shift_init(&shift);
    shift_plant_t plant = {SHIFT_START_SLIP_rad_s, false};
    ctx.clutch = &clutch;
    ctx.shift = &shift;
    ctx.shift_cal = adaptive ? &shift_adaptive : &shift_calibration;
    ctx.adapt = adaptive ? &adapt : NULL;
    ctx.shift_command = (wc_shift_command_t){true, 2u, SHIFT_TURBINE_TORQUE_Nm, SHIFT_TARGET_TIME_s};
    static const wc_step_output_t no_output;
    ctx.step_out = no_output;  /* wc_shift_step reads the previous step's status (anti-windup) */
    uint32_t reports = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        ctx.step_in = (wc_step_input_t){.slip_rad_s = plant.slip_rad_s, .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        if (shift.phase == (uint32_t)WC_SHIFT_INERTIA) {
            record(row, measure(thunk_shift_step, &ctx));
        } else if (adaptive && (shift.phase == (uint32_t)WC_SHIFT_LOCKUP)) {
            const uint32_t n = measure(thunk_shift_step, &ctx);
            if (ctx.shift_ended) { record(end_row, n); }
        } else {
            thunk_shift_step(&ctx);
        }
        if (ctx.shift_ended) { reports++; }
        plant_advance(&plant, shift.phase, &ctx.step_out);
    }
    if ((reports != 1u) || (shift.phase != (uint32_t)WC_SHIFT_LOCKED) || (ctx.shift_report.abort_reason != 0u) ||
        (adaptive && (ctx.shift_report.adaptation.result != (uint32_t)WC_ADAPT_RESULT_UPDATED))) {
        wc_arm_puts("SHIFT phase ");
        wc_arm_put_u32(shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(ctx.shift_report.abort_reason);
        wc_arm_puts("\n");
        fail("wc_shift_step: the shift did not complete");
    }
    wc_arm_puts("SHIFT wc_shift_step: inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(ctx.shift_report.inertia_time_s * 1000.0f));
    wc_arm_puts(" ms (target ");
    wc_arm_put_u32((uint32_t)lroundf(SHIFT_TARGET_TIME_s * 1000.0f));
    wc_arm_puts(" ms), slip RMSE ");
    wc_arm_put_fixed((uint32_t)lroundf(ctx.shift_report.slip_rmse_rad_s * 1000.0f), 3u);
    wc_arm_puts(" rad/s\n");
}

/* ClutchSensors, TorqueRequest (Mode 3 Shift) and ShiftCommand of one period. */
static void queue_shift_frames(float slip_rad_s, bool shift_request, uint8_t alive)
{
    wc_can_frame_t frame;
    if (wc_test_shift_sensors_frame(&frame, slip_rad_s, alive) != WC_CAN_OK) { fail("shift: sensors frame"); }
    (void)wc_loop_receive(&loop, &frame);
    if (wc_test_shift_request_frame(&frame, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, alive) != WC_CAN_OK) {
        fail("shift: request frame");
    }
    (void)wc_loop_receive(&loop, &frame);
    if (wc_test_shift_command_frame(&frame, shift_request, SHIFT_TURBINE_TORQUE_Nm, SHIFT_TARGET_TIME_s * 1000.0f,
                                    alive) != WC_CAN_OK) {
        fail("shift: command frame");
    }
    (void)wc_loop_receive(&loop, &frame);
}

/* wc_loop_step in Shift mode: the default configuration with the shift
 * calibration. ShiftRequest is 0 until the loop has left its safe state (E2E
 * sync, recovery_periods), then 1: a rising edge outside the safe state
 * starts the shift. Every step that starts in the inertia phase is a sample. */
#define SHIFT_LOOP_SETTLE_PERIODS WC_TEST_SHIFT_LOOP_SETTLE_PERIODS
static void bench_loop_shift(const wc_calibration_t *cal, row_t row)
{
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = &shift_calibration;
    if (wc_loop_init(&loop, cal, &config, SHIFT_OIL_degC) != WC_CAL_OK) {
        fail("shift: wc_loop_init");
        return;
    }
    ctx.loop = &loop;
    shift_plant_t plant = {SHIFT_START_SLIP_rad_s, false};
    uint32_t reports = 0u;
    uint32_t safe_in_shift = 0u;
    uint8_t alive = 0u;
    uint32_t frames_in = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        queue_shift_frames(plant.slip_rad_s, k >= SHIFT_LOOP_SETTLE_PERIODS, alive);
        frames_in += 3u;
        alive = wc_e2e_counter_next(alive);
        const uint32_t safe_before = loop.counters.safe_steps;
        if (loop.shift.phase == (uint32_t)WC_SHIFT_INERTIA) {
            record(row, measure(thunk_loop_step, &ctx));
            if (loop.counters.safe_steps != safe_before) { safe_in_shift++; }
        } else {
            thunk_loop_step(&ctx);
        }
        if (ctx.tx_frames > WC_LOOP_TX_CYCLIC) { reports++; }  /* ShiftReport (no AdaptationReport: adaptation off) */
        plant_advance(&plant, loop.shift.phase, &loop.last);
    }
    /* E2E: SyncCounter frames of each of the three inputs are not used */
    const uint32_t sync = loop.counters.rejected[WC_REJECT_SYNC];
    if ((reports != 1u) || (loop.shift.phase != (uint32_t)WC_SHIFT_LOCKED) || (loop.report.abort_reason != 0u) ||
        (safe_in_shift != 0u) || (loop.counters.frames_used + sync != frames_in)) {
        wc_arm_puts("SHIFT loop phase ");
        wc_arm_put_u32(loop.shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(loop.report.abort_reason);
        wc_arm_puts(", reports ");
        wc_arm_put_u32(reports);
        wc_arm_puts(", frames used ");
        wc_arm_put_u32(loop.counters.frames_used);
        wc_arm_puts(" + sync ");
        wc_arm_put_u32(sync);
        wc_arm_puts(" of ");
        wc_arm_put_u32(frames_in);
        wc_arm_puts("\n");
        fail("wc_loop_step (Shift mode): the shift did not complete, or a frame was rejected");
    }
    wc_arm_puts("SHIFT wc_loop_step: inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(loop.report.inertia_time_s * 1000.0f));
    wc_arm_puts(" ms\n");
}

/* ------------------------------------------------------------------------ */
/* The whole shift (DESIGN 14): two clutches and the engine request         */

/* wc_shift_1_2_whole_full (lut/wc_shift_1_2_shift.h): coordinator 1, fill pulse, off-going capacity
 * control, engine intervention. The off-going clutch is a second wc_clutch_t with the same clutch
 * calibration as the on-coming one. */
#define WHOLE_SHIFT_CAL wc_shift_1_2_whole_full
/* Periods with ShiftRequest 0 before the edge: the coordinator holds 1st gear in IDLE (the off-going
 * clutch's lock-up dwell is 10 periods). The loop's settle (E2E sync, recovery) is longer. */
#define WHOLE_IDLE_PERIODS 40u
#define WHOLE_SLIP_MAX_rad_s 1000.0f
#define WHOLE_PLANT_TURBINE_INERTIA_kg_m2 0.25f  /* the plant's I_t: the nominal of tools/plants/upshift_1_2.toml */

/* The bench's plant of the whole shift (not the tools' vehicle plant: it only has to drive the phases),
 * the C tests' reduced plant with the off-going clutch added: the output speed w_o held (a vehicle much
 * heavier than the turbine, and no road load), so both slips move with the turbine speed w_t (a = 1):
 *   off-going  s1 = w_t - b1 w_o,   on-coming  s2 = w_t - b w_o = s1 + (b1 - b) w_o,
 *   I_t dw_t/dt = T_t - T_2 - T_1   (T_2, T_1: the clutch models' signed torques of this step),
 * explicit Euler at the control period, with (b1 - b) w_o = SHIFT_START_SLIP_rad_s (1st gear: s1 = 0,
 * s2 = 100 rad/s). A clutch at zero slip sticks while the torque it has to hold (T_t minus the other
 * clutch's torque) stays within its static capacity (the model's, wc_step_output_t.static_capacity_Nm),
 * else it slips; a slip that crosses 0 sticks there. The engine follows its request at once:
 * T_t = T_t0 + delta while InterventionActive, which ShiftCommand.TurbineTorque reports in the next period.
 * Starts in 1st gear: the off-going clutch stuck, s2 = 100 rad/s, T_t = T_t0 = 100 Nm. */
typedef struct {
    float offgoing_slip_rad_s;  /* s1 */
    bool offgoing_stuck;
    bool oncoming_stuck;
    float turbine_torque_Nm;    /* T_t with the engine's intervention */
    float min_offgoing_slip_rad_s;
    float max_offgoing_slip_rad_s;
} whole_plant_t;

static float whole_oncoming_slip(const whole_plant_t *p)
{
    return p->oncoming_stuck ? 0.0f : (p->offgoing_slip_rad_s + SHIFT_START_SLIP_rad_s);
}

static void whole_plant_init(whole_plant_t *p)
{
    *p = (whole_plant_t){0.0f, true, false, SHIFT_TURBINE_TORQUE_Nm, 0.0f, 0.0f};
}

static void whole_plant_advance(whole_plant_t *p, const wc_step_output_t *on, const wc_step_output_t *off,
                                bool engine_active, float engine_delta_Nm)
{
    const float t_t = SHIFT_TURBINE_TORQUE_Nm + (engine_active ? engine_delta_Nm : 0.0f);
    p->turbine_torque_Nm = (t_t > 0.0f) ? t_t : 0.0f;
    const float turbine_Nm = p->turbine_torque_Nm;
    if (p->oncoming_stuck && (fabsf(turbine_Nm - off->model.torque_Nm) <= on->static_capacity_Nm)) { return; }
    p->oncoming_stuck = false;
    if (p->offgoing_stuck && (fabsf(turbine_Nm - on->model.torque_Nm) <= off->static_capacity_Nm)) { return; }
    p->offgoing_stuck = false;
    const float s1 = p->offgoing_slip_rad_s;
    const float accel = (turbine_Nm - on->model.torque_Nm - off->model.torque_Nm) / WHOLE_PLANT_TURBINE_INERTIA_kg_m2;
    float next = s1 + accel * wc_arm_calibration->control_period_s;
    if ((s1 + SHIFT_START_SLIP_rad_s > 0.0f) && (next + SHIFT_START_SLIP_rad_s <= 0.0f)) {
        next = -SHIFT_START_SLIP_rad_s;  /* the on-coming plates stick: 2nd gear */
        p->oncoming_stuck = true;
    } else if (((s1 > 0.0f) && (next <= 0.0f)) || ((s1 < 0.0f) && (next >= 0.0f))) {
        next = 0.0f;  /* the off-going plates stick: 1st gear */
        p->offgoing_stuck = true;
    }
    next = fminf(fmaxf(next, -WHOLE_SLIP_MAX_rad_s), WHOLE_SLIP_MAX_rad_s);
    p->offgoing_slip_rad_s = next;
    p->min_offgoing_slip_rad_s = fminf(p->min_offgoing_slip_rad_s, next);
    p->max_offgoing_slip_rad_s = fmaxf(p->max_offgoing_slip_rad_s, next);
}

/* The worst step of each part of the whole shift: the step of the command's edge (the shift's start: two
 * lag compensations), then by the phase the step starts in. */
enum { WHOLE_PART_START = 0, WHOLE_PARTS = 1 + (int)WC_SHIFT_LOCKUP };
static const char *const whole_part_name[WHOLE_PARTS] = {"start", "prepare", "torque", "inertia", "lockup"};
typedef struct {
    uint32_t worst[WHOLE_PARTS];
    uint32_t engine_steps;      /* steps with the engine intervention active */
    float engine_min_Nm;
    float engine_max_Nm;
} whole_parts_t;

/* Record n into row when the step belongs to the shift: it started in a running phase, or it started the
 * shift (IDLE before, a running phase after). */
static void whole_record(row_t row, whole_parts_t *parts, uint32_t phase_before, uint32_t phase_after, uint32_t n)
{
    uint32_t part;
    if (wc_shift_phase_running(phase_before)) {
        part = phase_before;
    } else if ((phase_before == (uint32_t)WC_SHIFT_IDLE) && wc_shift_phase_running(phase_after)) {
        part = WHOLE_PART_START;
    } else {
        return;
    }
    record(row, n);
    if (n > parts->worst[part]) { parts->worst[part] = n; }
}

static void whole_engine(whole_parts_t *parts, bool active, float delta_Nm)
{
    if (!active) { return; }
    parts->engine_steps++;
    parts->engine_min_Nm = fminf(parts->engine_min_Nm, delta_Nm);
    parts->engine_max_Nm = fmaxf(parts->engine_max_Nm, delta_Nm);
}

static void whole_print(const char *what, row_t row, const whole_parts_t *parts, const whole_plant_t *plant,
                        const wc_shift_report_t *report)
{
    wc_arm_puts("WHOLE ");
    wc_arm_puts(row_name[row]);
    wc_arm_puts(" (");
    wc_arm_puts(what);
    wc_arm_puts(") worst by part:");
    for (uint32_t i = 0u; i < (uint32_t)WHOLE_PARTS; ++i) {
        wc_arm_puts(" ");
        wc_arm_puts(whole_part_name[i]);
        wc_arm_puts(" ");
        wc_arm_put_u32(parts->worst[i]);
    }
    wc_arm_puts("; inertia phase ");
    wc_arm_put_u32((uint32_t)lroundf(report->inertia_time_s * 1000.0f));
    wc_arm_puts(" ms, off-going slip ");
    wc_arm_put_i32((int32_t)lroundf(plant->min_offgoing_slip_rad_s));
    wc_arm_puts(" .. ");
    wc_arm_put_i32((int32_t)lroundf(plant->max_offgoing_slip_rad_s));
    wc_arm_puts(" rad/s, engine active ");
    wc_arm_put_u32(parts->engine_steps);
    wc_arm_puts(" steps, delta ");
    wc_arm_put_i32((int32_t)lroundf(parts->engine_min_Nm));
    wc_arm_puts(" .. ");
    wc_arm_put_i32((int32_t)lroundf(parts->engine_max_Nm));
    wc_arm_puts(" Nm, flare ");
    wc_arm_put_u32(report->flare ? 1u : 0u);
    wc_arm_puts(", tie-up ");
    wc_arm_put_u32(report->tie_up ? 1u : 0u);
    wc_arm_puts("\n");
}

/* What a whole shift must have done: completed (one report, LOCKED, no abort, no fallback), the off-going
 * clutch handed over (its slip turned negative past the hand-over threshold), the engine asked. */
static bool whole_ok(uint32_t reports, uint32_t phase, const wc_shift_report_t *report, const whole_plant_t *plant,
                     const whole_parts_t *parts)
{
    return (reports == 1u) && (phase == (uint32_t)WC_SHIFT_LOCKED) && (report->abort_reason == 0u) &&
           (report->fallback == (uint32_t)WC_SHIFT_FALLBACK_NONE) &&
           (plant->min_offgoing_slip_rad_s < -WHOLE_SHIFT_CAL.handover_slip_rad_s) && plant->oncoming_stuck &&
           (parts->engine_steps > 0u) && (parts->engine_min_Nm < 0.0f) && (parts->engine_max_Nm > 0.0f);
}

static wc_clutch_t offgoing_clutch;

/* wc_shift_step with the coordinator: both clutches of cal, every step of one 1->2 upshift from the
 * command's edge to the step in which it ends (prepare/fill, torque phase, inertia phase, hand-over). */
static void bench_whole_shift_step(const wc_calibration_t *cal, row_t row)
{
    if ((wc_shift_calibration_check(&WHOLE_SHIFT_CAL) != WC_SHIFT_CAL_OK) || (WHOLE_SHIFT_CAL.coordinator != 1u) ||
        (wc_clutch_init(&clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK) ||
        (wc_clutch_init(&offgoing_clutch, cal, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("whole shift: calibration");
        return;
    }
    wc_shift_init(&shift);
    static wc_step_input_t offgoing_in;
    static wc_step_output_t offgoing_out;
    static const wc_step_output_t no_output;
    offgoing_out = no_output;
    wc_shift_offgoing_t offgoing = {&offgoing_clutch, &offgoing_in, &offgoing_out, false, 0.0f};
    whole_plant_t plant;
    whole_plant_init(&plant);
    whole_parts_t parts = {{0u}, 0u, 0.0f, 0.0f};
    ctx.clutch = &clutch;
    ctx.shift = &shift;
    ctx.shift_cal = &WHOLE_SHIFT_CAL;
    ctx.adapt = NULL;
    ctx.offgoing = &offgoing;
    ctx.step_out = no_output;  /* wc_shift_step reads the previous step's status (anti-windup) */
    uint32_t reports = 0u;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        ctx.shift_command = (wc_shift_command_t){k >= WHOLE_IDLE_PERIODS, 2u, plant.turbine_torque_Nm, SHIFT_TARGET_TIME_s};
        ctx.step_in = (wc_step_input_t){.slip_rad_s = whole_oncoming_slip(&plant), .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        offgoing_in = (wc_step_input_t){.slip_rad_s = plant.offgoing_slip_rad_s, .theta_oil_degC = SHIFT_OIL_degC,
                                        .theta_housing_degC = SHIFT_OIL_degC};
        const uint32_t phase_before = shift.phase;
        const uint32_t n = measure(thunk_whole_shift_step, &ctx);
        whole_record(row, &parts, phase_before, shift.phase, n);
        if (ctx.shift_ended) { reports++; }
        whole_engine(&parts, offgoing.engine_active, offgoing.engine_delta_Nm);
        whole_plant_advance(&plant, &ctx.step_out, &offgoing_out, offgoing.engine_active, offgoing.engine_delta_Nm);
    }
    ctx.offgoing = NULL;
    whole_print("wc_shift_step", row, &parts, &plant, &ctx.shift_report);
    if (!whole_ok(reports, shift.phase, &ctx.shift_report, &plant, &parts)) {
        wc_arm_puts("WHOLE phase ");
        wc_arm_put_u32(shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(ctx.shift_report.abort_reason);
        wc_arm_puts(", fallback ");
        wc_arm_put_u32(ctx.shift_report.fallback);
        wc_arm_puts("\n");
        fail("wc_shift_step (whole shift): the shift did not complete with a hand-over and the engine's request");
    }
}

/* wc_loop_step in Shift mode with the whole shift (config.offgoing: cal again): ClutchSensors,
 * OffgoingSensors, TorqueRequest (Mode 3) and ShiftCommand queued each period; every step of the shift
 * as in bench_whole_shift_step; each step sends OffgoingVfsCommand and EngineTorqueRequest too. */
static void bench_loop_whole_shift(const wc_calibration_t *cal, row_t row)
{
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.shift = &WHOLE_SHIFT_CAL;
    config.offgoing = cal;
    if (!wc_loop_whole_shift(&config) || (wc_loop_init(&loop, cal, &config, SHIFT_OIL_degC) != WC_CAL_OK)) {
        fail("whole shift: wc_loop_init");
        return;
    }
    ctx.loop = &loop;
    whole_plant_t plant;
    whole_plant_init(&plant);
    whole_parts_t parts = {{0u}, 0u, 0.0f, 0.0f};
    uint32_t reports = 0u;
    uint32_t safe_in_shift = 0u;
    uint32_t short_steps = 0u;
    uint8_t alive = 0u;
    uint32_t frames_in = 0u;
    const uint32_t per_step = WC_LOOP_TX_CYCLIC + WC_LOOP_TX_WHOLE_SHIFT;
    for (uint32_t k = 0u; (k < SHIFT_MAX_PERIODS) && (reports == 0u); ++k) {
        const bool request = k >= SHIFT_LOOP_SETTLE_PERIODS;
        wc_can_frame_t frame;
        const wc_can_offgoing_sensors_phys_t og = {plant.offgoing_slip_rad_s / WC_RAD_S_PER_RPM, alive};
        if ((wc_test_shift_sensors_frame(&frame, whole_oncoming_slip(&plant), alive) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: sensors frame");
        }
        frame = wc_test_can_frame(WC_CAN_OFFGOING_SENSORS_FRAME_ID);
        if ((wc_can_encode_offgoing_sensors(frame.data, &og, sizeof frame.data) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: off-going sensors frame");
        }
        if ((wc_test_shift_request_frame(&frame, WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE, alive) != WC_CAN_OK) ||
            !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: request frame");
        }
        if ((wc_test_shift_command_frame(&frame, request, plant.turbine_torque_Nm, SHIFT_TARGET_TIME_s * 1000.0f, alive) !=
             WC_CAN_OK) || !wc_loop_receive(&loop, &frame)) {
            fail("whole shift: command frame");
        }
        frames_in += 4u;
        alive = wc_e2e_counter_next(alive);
        const uint32_t safe_before = loop.counters.safe_steps;
        const uint32_t phase_before = loop.shift.phase;
        const uint32_t n = measure(thunk_loop_step, &ctx);
        whole_record(row, &parts, phase_before, loop.shift.phase, n);
        if (wc_shift_phase_running(phase_before) && (loop.counters.safe_steps != safe_before)) { safe_in_shift++; }
        if (ctx.tx_frames < per_step) { short_steps++; }
        if (ctx.tx_frames > per_step) { reports++; }  /* ShiftReport (no AdaptationReport: adaptation off) */
        whole_engine(&parts, loop.whole.engine_active, loop.whole.engine_delta_Nm);
        whole_plant_advance(&plant, &loop.last, &loop.offgoing_last, loop.whole.engine_active, loop.whole.engine_delta_Nm);
    }
    /* E2E: SyncCounter frames of each of the four inputs are not used */
    const uint32_t sync = loop.counters.rejected[WC_REJECT_SYNC];
    whole_print("wc_loop_step", row, &parts, &plant, &loop.report);
    if (!whole_ok(reports, loop.shift.phase, &loop.report, &plant, &parts) || (safe_in_shift != 0u) ||
        (short_steps != 0u) || (loop.counters.frames_used + sync != frames_in)) {
        wc_arm_puts("WHOLE loop phase ");
        wc_arm_put_u32(loop.shift.phase);
        wc_arm_puts(", abort reason ");
        wc_arm_put_u32(loop.report.abort_reason);
        wc_arm_puts(", reports ");
        wc_arm_put_u32(reports);
        wc_arm_puts(", steps without the whole shift's frames ");
        wc_arm_put_u32(short_steps);
        wc_arm_puts(", frames used ");
        wc_arm_put_u32(loop.counters.frames_used);
        wc_arm_puts(" + sync ");
        wc_arm_put_u32(sync);
        wc_arm_puts(" of ");
        wc_arm_put_u32(frames_in);
        wc_arm_puts("\n");
        fail("wc_loop_step (whole shift): the shift did not complete, or a frame was rejected");
    }
}

/* RAM of the whole shift (DESIGN 14): the loop's state holds the second clutch whether or not it is used. */
static void whole_ram(void)
{
    const uint32_t offgoing_bytes = (uint32_t)(sizeof loop.offgoing + sizeof loop.offgoing_input +
                                               sizeof loop.offgoing_last + sizeof loop.offgoing_in +
                                               sizeof loop.offgoing_sensors);
    wc_arm_puts("RAM wc_loop_t ");
    wc_arm_put_u32((uint32_t)sizeof(wc_loop_t));
    wc_arm_puts("\nRAM wc_clutch_t ");
    wc_arm_put_u32((uint32_t)sizeof(wc_clutch_t));
    wc_arm_puts("\nRAM wc_shift_t ");
    wc_arm_put_u32((uint32_t)sizeof(wc_shift_t));
    wc_arm_puts("\nRAM wc_loop_t.offgoing_parts ");
    wc_arm_put_u32(offgoing_bytes);
    wc_arm_puts("\nRAM whole_shift_step_state ");  /* a caller of wc_shift_step: shift, two clutches, in/out each */
    wc_arm_put_u32((uint32_t)(sizeof(wc_shift_t) + 2u * (sizeof(wc_clutch_t) + sizeof(wc_step_input_t) +
                                                         sizeof(wc_step_output_t))));
    wc_arm_puts("\n");
}

/* ------------------------------------------------------------------------ */
/* The XCP slave (wc_xcp.h) in a calibration session                        */

/* The loop runs on the committed image (table1 + shift_1_2_full) in torque
 * control at one operating point; the XCP slave steps right after it, with
 * the image's payload as its reference page. One master command a period at
 * most: a master waits for each response (no block mode). */
#define XCP_SLIP_rpm 750.0f
#define XCP_THETA_degC 80.0f
#define XCP_REQUEST_Nm 100.0f
#define XCP_SETTLE_PERIODS 32u    /* the loop out of its start-up safe state (E2E sync, recovery) */
#define XCP_MEASURED_PERIODS 64u  /* samples of the idle and DAQ rows */
#define XCP_CHECKSUMS 4u
#define XCP_DOWNLOADS 8u          /* the gain changed and changed back, 4 times */
#define XCP_KP_SCALE 1.01f

static wc_xcp_t xcp;
static wc_cal_set_t xcp_loop_set;     /* the loop's calibration: the committed image */
static wc_cal_set_t xcp_scratch_set;  /* the master's view of the page; the decode row's set */
static uint8_t xcp_scratch_page[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
static uint8_t crc_block[WC_XCP_CHECKSUM_MAX_BYTES];
static uint8_t xcp_alive;

/* One control period: the loop's two input frames queued and the loop
 * stepped, then the master's command (NULL: none) received, then
 * wc_xcp_step, measured into row unless row is ROWS. False when a command
 * is not answered by a positive response as the step's first frame. */
static bool xcp_period(const wc_can_frame_t *command, row_t row)
{
    queue_frames(XCP_SLIP_rpm, XCP_THETA_degC, XCP_REQUEST_Nm, xcp_alive);
    xcp_alive = wc_e2e_counter_next(xcp_alive);
    thunk_loop_step(&ctx);
    if ((command != NULL) && !wc_xcp_receive(&xcp, command)) { return false; }
    if (row < ROWS) {
        record(row, measure(thunk_xcp_step, &ctx));
    } else {
        thunk_xcp_step(&ctx);
    }
    return (command == NULL) || ((ctx.xcp_frames >= 1u) && (ctx.xcp_tx[0].data[0] == WC_XCP_PID_RES));
}

/* The step's frames from first on are the DAQ list's 8 ODTs (PIDs 0..7),
 * each carrying its signal's bytes as the loop holds them after its step,
 * the first after the timestamp. */
static bool xcp_daq_frames_ok(uint32_t first)
{
    if (ctx.xcp_frames != first + WC_ARM_XCP_DAQ_SIGNALS) { return false; }
    for (uint32_t i = 0u; i < WC_ARM_XCP_DAQ_SIGNALS; ++i) {
        const wc_can_frame_t *f = &ctx.xcp_tx[first + i];
        const uint8_t *signal = (const uint8_t *)&loop + wc_arm_xcp_signal_offset(i);
        const uint32_t pos = (i == 0u) ? 3u : 1u;
        if ((f->id != WC_CAN_XCP_RESPONSE_FRAME_ID) || (f->data[0] != (uint8_t)i) ||
            (memcmp(&f->data[pos], signal, 4u) != 0)) {
            return false;
        }
    }
    return true;
}

/* What a master computes from the A2L to set the shift PI gain to
 * reference kp x scale: the bytes of the page that change (*length, at
 * most 4: one float) and their offset in the page. */
static uint32_t xcp_kp_bytes(const uint8_t *reference, float scale, uint8_t bytes[4], uint32_t *length)
{
    *length = 0u;
    if (wc_cal_image_decode(reference, &xcp_scratch_set).result != (uint32_t)WC_CAL_IMAGE_OK) { return 0u; }
    xcp_scratch_set.shift.kp_Nm_per_rad_s *= scale;
    wc_cal_image_encode(&xcp_scratch_set, xcp_scratch_page);
    uint32_t first = 0u;
    for (uint32_t i = 0u; i < wc_cal_image_payload_bytes; ++i) {
        if (xcp_scratch_page[i] == xcp.working_page[i]) { continue; }
        if (*length == 0u) { first = i; }
        if (i - first >= 4u) {  /* more than one float changed */
            *length = 0u;
            return 0u;
        }
        *length = i - first + 1u;
    }
    for (uint32_t i = 0u; i < *length; ++i) { bytes[i] = xcp_scratch_page[first + i]; }
    return first;
}

static void bench_xcp(void)
{
    const uint8_t *reference = &wc_table1_cal_image[WC_IMAGE_HEADER_BYTES];
    const wc_xcp_config_t config = WC_XCP_CONFIG_DEFAULT;
    if ((wc_cal_image_load(wc_table1_cal_image, sizeof wc_table1_cal_image, &xcp_loop_set).result !=
         (uint32_t)WC_CAL_IMAGE_OK) ||
        (wc_loop_init(&loop, &xcp_loop_set.clutch, &xcp_loop_set.loop, XCP_THETA_degC) != WC_CAL_OK) ||
        !wc_xcp_init(&xcp, &loop, reference, &config)) {
        fail("xcp: the image, wc_loop_init or wc_xcp_init");
        return;
    }
    ctx.loop = &loop;
    ctx.xcp = &xcp;
    xcp_alive = 0u;
    const wc_can_frame_t connect = wc_arm_xcp_connect();
    bool ok = xcp_period(&connect, ROWS);
    for (uint32_t k = 0u; k < XCP_SETTLE_PERIODS; ++k) { ok = xcp_period(NULL, ROWS) && ok; }
    const uint32_t safe_steps = loop.counters.safe_steps;

    /* Connected, no command, no DAQ. */
    for (uint32_t k = 0u; k < XCP_MEASURED_PERIODS; ++k) {
        ok = xcp_period(NULL, ROW_XCP_IDLE) && (ctx.xcp_frames == 0u) && ok;
    }
    if (!ok) { fail("xcp: CONNECT refused, or an idle step sent a frame"); }

    /* The DAQ list configured by its commands, one a period, then sampled. */
    wc_can_frame_t setup[WC_ARM_XCP_DAQ_SETUP_FRAMES];
    const uint32_t setup_frames = wc_arm_xcp_daq_setup(config.loop_base, setup);
    for (uint32_t i = 0u; i < setup_frames; ++i) {
        if (!xcp_period(&setup[i], ROWS)) {
            wc_arm_puts("XCP command ");
            wc_arm_put_u32(i);
            wc_arm_puts(" of the DAQ setup: response PID ");
            wc_arm_put_u32(ctx.xcp_tx[0].data[0]);
            wc_arm_puts(", error ");
            wc_arm_put_u32(ctx.xcp_tx[0].data[1]);
            wc_arm_puts("\n");
            fail("xcp: the DAQ configuration was refused");
            return;
        }
    }
    ok = true;
    for (uint32_t k = 0u; k < XCP_MEASURED_PERIODS; ++k) {
        ok = xcp_period(NULL, ROW_XCP_DAQ) && xcp_daq_frames_ok(0u) && ok;
    }
    if (!ok) { fail("xcp: a DAQ step did not send the list's 8 ODTs with the loop's values"); }

    /* BUILD_CHECKSUM over the whole page, the DAQ list running. */
    const wc_can_frame_t set_mta_page = wc_arm_xcp_set_mta(config.cal_base);
    const wc_can_frame_t checksum = wc_arm_xcp_build_checksum(wc_cal_image_payload_bytes);
    for (uint32_t k = 0u; k < XCP_CHECKSUMS; ++k) {
        ok = xcp_period(&set_mta_page, ROWS) && xcp_period(&checksum, ROW_XCP_CHECKSUM_PAGE) &&
             (wc_image_get_u32(&ctx.xcp_tx[0].data[4]) == wc_image_crc32(xcp.working_page, wc_cal_image_payload_bytes)) &&
             xcp_daq_frames_ok(1u) && ok;
    }
    if (!ok) { fail("xcp: BUILD_CHECKSUM of the page"); }

    /* DOWNLOAD of the shift PI gain, scaled and back: each step checks the
     * whole page and gives it to the loop; the DAQ list running. */
    const float kp_reference = xcp_loop_set.shift.kp_Nm_per_rad_s;
    for (uint32_t k = 0u; k < XCP_DOWNLOADS; ++k) {
        const float scale = ((k % 2u) == 0u) ? XCP_KP_SCALE : 1.0f;
        uint8_t bytes[4];
        uint32_t length = 0u;
        const uint32_t offset = xcp_kp_bytes(reference, scale, bytes, &length);
        const wc_can_frame_t set_mta = wc_arm_xcp_set_mta(config.cal_base + offset);
        const wc_can_frame_t download = wc_arm_xcp_download(bytes, length);
        const uint32_t accepted = xcp.status.pages_accepted;
        ok = (length > 0u) && xcp_period(&set_mta, ROWS) && xcp_period(&download, ROW_XCP_DOWNLOAD_CHECK) &&
             (xcp.status.pages_accepted == accepted + 1u) && (xcp.status.page_result == 0u) &&
             (loop.config.shift != NULL) && (loop.config.shift->kp_Nm_per_rad_s >= kp_reference * scale) &&
             (loop.config.shift->kp_Nm_per_rad_s <= kp_reference * scale) && xcp_daq_frames_ok(1u) && ok;
    }
    if (!ok) { fail("xcp: a DOWNLOAD of the gain was not checked, accepted and given to the loop"); }
    if (loop.counters.safe_steps != safe_steps) { fail("xcp: the loop went to its safe state in the session"); }

    /* The largest BUILD_CHECKSUM block's CRC (no region is that large: the
     * CRC-32 a block of WC_XCP_CHECKSUM_MAX_BYTES would cost). */
    for (uint32_t i = 0u; i < WC_XCP_CHECKSUM_MAX_BYTES; ++i) { crc_block[i] = (uint8_t)(i * 131u); }
    ctx.crc_data = crc_block;
    ctx.crc_length = WC_XCP_CHECKSUM_MAX_BYTES;
    record(ROW_CRC32_MAX_BLOCK, measure(thunk_crc32, &ctx));

    /* The page check's two parts: the decode with its checks, and the loop's
     * recalibration (wc_model_init: the clutch check again, the shift check again). */
    ctx.payload = xcp.working_page;
    ctx.cal_set = &xcp_scratch_set;
    record(ROW_CAL_IMAGE_DECODE, measure(thunk_cal_image_decode, &ctx));
    if (ctx.cal_image_status.result != (uint32_t)WC_CAL_IMAGE_OK) { fail("xcp: wc_cal_image_decode of the page"); }
    record(ROW_LOOP_RECALIBRATE, measure(thunk_loop_recalibrate, &ctx));
    if (ctx.cal_error != WC_CAL_OK) { fail("xcp: wc_loop_recalibrate"); }

    wc_arm_puts("XCP session: ");
    wc_arm_put_u32(xcp.status.commands);
    wc_arm_puts(" commands, ");
    wc_arm_put_u32(xcp.status.daq_frames);
    wc_arm_puts(" DAQ frames, ");
    wc_arm_put_u32(xcp.status.pages_accepted);
    wc_arm_puts(" pages accepted, sizeof(wc_xcp_t) ");
    wc_arm_put_u32((uint32_t)sizeof(wc_xcp_t));
    wc_arm_puts(" B\n");
}

static uint32_t median_of(row_t row)
{
    return (sample_count[row] == 0u) ? 0u : samples[row][(sample_count[row] - 1u) / 2u];
}

static uint32_t worst_of(row_t row)
{
    return (sample_count[row] == 0u) ? 0u : samples[row][sample_count[row] - 1u];
}

/* naive / library, in hundredths, rounded. */
static void put_ratio(uint32_t naive, uint32_t library)
{
    if (library == 0u) {
        wc_arm_puts("n/a");
        return;
    }
    const uint64_t hundredths = ((uint64_t)naive * 100u + library / 2u) / library;
    wc_arm_put_fixed((uint32_t)hundredths, 2u);
}

int main(void)
{
    wc_arm_puts("wc_arm_bench: Cortex-M4F instruction counts (QEMU mps2-an386, -icount shift=8), level -"
                WC_STR(WC_ARM_BENCH_LEVEL) "\n");

    /* Calibration: the empty window (subtracted from every figure; it must be
     * the same every time), then 1000 nops. */
    empty_window = window_instructions(thunk_empty, &ctx);
    for (uint32_t i = 0u; i < 8u; ++i) {
        if (window_instructions(thunk_empty, &ctx) != empty_window) { fail("the empty window is not constant"); }
    }
    wc_arm_puts("EMPTY ");
    wc_arm_put_u32(empty_window);
    wc_arm_puts("\n");
    const uint32_t nops = measure(thunk_nops, &ctx);
    wc_arm_puts("NOP ");
    wc_arm_put_u32(nops);
    wc_arm_puts(" (a block of 1000 nops; must read 1000 +- 1)\n");
    if ((nops + 1u < NOP_BLOCK) || (nops > NOP_BLOCK + 1u)) { fail("1000 nops do not read 1000"); }

    film_calibration = *wc_arm_calibration;
    film_calibration.film_squeeze_factor = 0.1f;  /* the bench's (tools/calibrations/bench_true.toml) */
    if (wc_model_init(&model, wc_arm_calibration) != WC_CAL_OK) {
        fail("wc_model_init(table1)");
    } else {
        worst_diff_t worst = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
        for (uint32_t s = 0u; s < WC_ARRAY_LENGTH(slip_grid_rpm); ++s) {
            for (uint32_t t = 0u; t < WC_ARRAY_LENGTH(theta_grid_degC); ++t) {
                for (uint32_t r = 0u; r < WC_ARRAY_LENGTH(request_grid); ++r) {
                    bench_point(slip_grid_rpm[s], theta_grid_degC[t], request_grid[r], &worst);
                }
            }
        }

        static wc_cal_set_t cal_set;
        ctx.cal_set = &cal_set;
        record(ROW_CAL_IMAGE_LOAD, measure(thunk_cal_image_load, &ctx));
        if ((ctx.cal_image_status.result != (uint32_t)WC_CAL_IMAGE_OK) ||
            (memcmp(&cal_set.clutch, wc_arm_calibration, offsetof(wc_calibration_t, film)) != 0) || !cal_set.shift_enabled) {
            fail("wc_cal_image_load: the committed table1 image refused or not table1");
        }

        bench_shift_step(wc_arm_calibration, ROW_SHIFT_STEP, false, ROW_SHIFT_STEP);
        bench_loop_shift(wc_arm_calibration, ROW_LOOP_STEP_SHIFT);
        bench_shift_step(wc_arm_identified_calibration, ROW_SHIFT_STEP_FILM, false, ROW_SHIFT_STEP_FILM);
        bench_shift_step(wc_arm_identified_calibration, ROW_SHIFT_STEP_ADAPT, true, ROW_SHIFT_END_ADAPT);
        bench_loop_shift(wc_arm_identified_calibration, ROW_LOOP_STEP_SHIFT_FILM);
        bench_whole_shift_step(wc_arm_calibration, ROW_SHIFT_STEP_WHOLE);
        bench_loop_whole_shift(wc_arm_calibration, ROW_LOOP_STEP_WHOLE);
        bench_whole_shift_step(wc_arm_identified_calibration, ROW_SHIFT_STEP_WHOLE_FILM);
        bench_loop_whole_shift(wc_arm_identified_calibration, ROW_LOOP_STEP_WHOLE_FILM);
        whole_ram();
        bench_xcp();

        wc_arm_puts("GRID ");
        wc_arm_put_u32((uint32_t)GRID_POINTS);
        wc_arm_puts(" points: slip 8 x theta 4 x request 6\n");
        for (uint32_t row = 0u; row < (uint32_t)ROWS; ++row) {
            sort(samples[row], sample_count[row]);
            wc_arm_puts("ROW ");
            wc_arm_puts(row_name[row]);
            wc_arm_puts(" ");
            wc_arm_put_u32(sample_count[row]);
            wc_arm_puts(" ");
            wc_arm_put_u32(median_of((row_t)row));
            wc_arm_puts(" ");
            wc_arm_put_u32(worst_of((row_t)row));
            wc_arm_puts("\n");
            if (sample_count[row] == 0u) { fail("a row has no samples"); }
        }

        const uint32_t worst_diff_mN = (uint32_t)lroundf(worst.diff_N * 1000.0f);
        wc_arm_puts("NAIVE force_diff_worst_N ");
        wc_arm_put_fixed(worst_diff_mN, 3u);
        wc_arm_puts(" (|F_naive - F_wc_inverse| over the grid, limit ");
        wc_arm_put_fixed(NAIVE_AGREEMENT_mN, 3u);
        wc_arm_puts(" N; worst at F = ");
        wc_arm_put_u32((uint32_t)lroundf(worst.force_N));
        wc_arm_puts(" N");
        put_point(worst.slip_rpm, worst.theta_degC, worst.fraction);
        wc_arm_puts(")\n");
        if (worst_diff_mN > NAIVE_AGREEMENT_mN) { fail("the naive inverse disagrees with wc_inverse"); }
        wc_arm_puts("NAIVE ratio_solve_median ");
        put_ratio(median_of(ROW_NAIVE_SOLVE), median_of(ROW_INVERSE_SOLVE));
        wc_arm_puts(" ratio_solve_worst ");
        put_ratio(worst_of(ROW_NAIVE_SOLVE), worst_of(ROW_INVERSE_SOLVE));
        wc_arm_puts("\n");
    }

    if (failed) {
        wc_arm_puts("RESULT FAIL ");
        wc_arm_puts(fail_reason);
        wc_arm_puts("\n");
        return 1;
    }
    wc_arm_puts("RESULT OK\n");
    return 0;
}
