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
 * The diagnostic server (wc_isotp.h, wc_uds.h, wc_dtc.h; DESIGN 17) beside the
 * loop on the committed image, as wc_tcu --uds wires it, a tester's frame a
 * step at most (wc_arm_bench_diag.c): rows wc_uds_step:idle,
 * :read_did_multiframe (a 68-byte ReadDataByIdentifier answer, every step of
 * its exchange), :read_dtc_list (ReadDTCInformation 0x0A over 16 DTCs), the
 * server and ISO-TP alone; wc_dtc_report:vfs_status_15_tests, the fault
 * memory's tests from a step's VfsCommand (its decode, 15 wc_dtc_report, the
 * snapshot's operating point); wc_loop_step+diag:... the same exchanges in the
 * whole control step (the loop, the fault memory's 15 tests from its
 * VfsCommand, the server). RAM lines of the three states.
 *
 * Output lines (parsed by scripts/bench_arm.sh):
 *   EMPTY <instructions>        window overhead, subtracted from every figure
 *   NOP <instructions>          1000 nops (must read 1000)
 *   ROW <name> <samples> <median> <worst>
 *   RAM <name> <bytes>          sizes of the whole shift's and the diagnostic states (sizeof on the target)
 *   WHOLE ...                   the whole shift's rows: worst per part, what the shift did
 *   NAIVE ...                   naive-vs-library force check and ratio
 *   RESULT OK | RESULT FAIL <why>
 * main returns 0 only with RESULT OK (startup.S turns it into QEMU's exit code).
 */
#include "wc_arm_bench.h"

#ifndef WC_ARM_BENCH_LEVEL
#define WC_ARM_BENCH_LEVEL unknown
#endif
#define WC_STR_(x) #x
#define WC_STR(x) WC_STR_(x)

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

/* The naive inverse must agree with wc_inverse within this: the table's
 * 3.9e-5 relative error and both solvers' 0.01 N tolerances stay far below. */
#define NAIVE_AGREEMENT_mN 5000u


/* Names as in bench/arm_ceilings.txt (no spaces). */
const char *const row_name[ROWS] = {
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
    [ROW_DIAG_TESTS] = "wc_dtc_report:vfs_status_15_tests",
    [ROW_DIAG_IDLE] = "wc_uds_step:idle",
    [ROW_DIAG_READ_DID] = "wc_uds_step:read_did_multiframe",
    [ROW_DIAG_READ_DTC] = "wc_uds_step:read_dtc_list",
    [ROW_LOOP_DIAG_IDLE] = "wc_loop_step+diag:idle",
    [ROW_LOOP_DIAG_READ_DID] = "wc_loop_step+diag:read_did_multiframe",
    [ROW_LOOP_DIAG_READ_DTC] = "wc_loop_step+diag:read_dtc_list",
    [ROW_TX_IN_GEAR] = "wc_transmission_step:in_gear",
    [ROW_TX_POWER_ON_UP] = "wc_transmission_step:power_on_up",
    [ROW_TX_POWER_OFF_UP] = "wc_transmission_step:power_off_up",
    [ROW_TX_POWER_ON_DOWN] = "wc_transmission_step:power_on_down",
    [ROW_TX_POWER_OFF_DOWN] = "wc_transmission_step:power_off_down",
    [ROW_LOOP_GEARBOX_IN_GEAR] = "wc_loop_step:gearbox_in_gear",
    [ROW_LOOP_GEARBOX_POWER_ON_UP] = "wc_loop_step:gearbox_power_on_up",
};

/* Shift trajectory: the inertia phase lasts at most target * timeout factor = 750 periods; the whole
 * shift's rows sample every step of the shift: prepare 50 + torque phase 220 + inertia at most 800 +
 * hand-over at most 200 periods (wc_shift_1_2_whole_full, target 0.5 s). */
#define SHIFT_SAMPLES_MAX 1536u
/* expf: two arguments per grid point; the shift rows: one per inertia-phase period;
 * wc_clutch_step:film_lag: FILM_LAG_SAMPLES_PER_POINT steps per grid point */
#define SAMPLES_PER_ROW ((FILM_LAG_SAMPLES_PER_POINT * GRID_POINTS > SHIFT_SAMPLES_MAX) ? \
                         FILM_LAG_SAMPLES_PER_POINT * GRID_POINTS : SHIFT_SAMPLES_MAX)
static uint32_t samples[ROWS][SAMPLES_PER_ROW];
static uint32_t sample_count[ROWS];

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

void fail(const char *reason)
{
    if (!failed) {
        failed = true;
        fail_reason = reason;
    }
    wc_arm_puts("FAIL ");
    wc_arm_puts(reason);
    wc_arm_puts("\n");
}

uint32_t measure(thunk_t thunk, bench_ctx_t *ctx)
{
    const uint32_t raw = window_instructions(thunk, ctx);
    if ((raw < empty_window) || (raw > WINDOW_MAX_INSTRUCTIONS)) {
        fail("window outside [empty window, WINDOW_MAX_INSTRUCTIONS]");
        return 0u;
    }
    return raw - empty_window;
}

void record(row_t row, uint32_t instructions)
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

void put_point(float slip_rpm, float theta_degC, float fraction)
{
    wc_arm_puts(" at slip ");
    wc_arm_put_i32((int32_t)lroundf(slip_rpm * 100.0f));
    wc_arm_puts("e-2 rpm, theta ");
    wc_arm_put_i32((int32_t)lroundf(theta_degC));
    wc_arm_puts(" degC, request ");
    wc_arm_put_u32((uint32_t)lroundf(fraction * 100.0f));
    wc_arm_puts("% of capacity");
}

void put_ram(const char *name, uint32_t bytes)
{
    wc_arm_puts("RAM ");
    wc_arm_puts(name);
    wc_arm_puts(" ");
    wc_arm_put_u32(bytes);
    wc_arm_puts("\n");
}

wc_model_t model;
wc_clutch_t clutch;
wc_calibration_t film_calibration;
wc_loop_t loop;
bench_ctx_t bench;

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
    empty_window = window_instructions(thunk_empty, &bench);
    for (uint32_t i = 0u; i < 8u; ++i) {
        if (window_instructions(thunk_empty, &bench) != empty_window) { fail("the empty window is not constant"); }
    }
    wc_arm_puts("EMPTY ");
    wc_arm_put_u32(empty_window);
    wc_arm_puts("\n");
    const uint32_t nops = measure(thunk_nops, &bench);
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
        bench_grid(&worst);

        static wc_cal_set_t cal_set;
        bench.cal_set = &cal_set;
        record(ROW_CAL_IMAGE_LOAD, measure(thunk_cal_image_load, &bench));
        if ((bench.cal_image_status.result != (uint32_t)WC_CAL_IMAGE_OK) ||
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
        bench_diag();
        bench_transmission();

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
