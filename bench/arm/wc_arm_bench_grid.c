/* The probe's grid rows (wc_arm_bench.c, "Grid"): the model's functions, wc_clutch_step (plain, film, the
 * shift's film + lag configuration), wc_loop_step in torque control, the frame codec and the CRC, at each
 * of the 192 points, and the naive inverse against wc_inverse. */
#include "wc_arm_bench.h"
#include "wc_arm_naive.h"

static const float slip_grid_rpm[] = {-3000.0f, -750.0f, -0.25f, 0.0f, 0.25f, 50.0f, 750.0f, 3000.0f};
static const float theta_grid_degC[] = {10.0f, 40.0f, 80.0f, 120.0f};
static const float request_grid[] = {0.0f, 0.05f, 0.3f, 0.6f, 0.9f, 1.1f};
WC_STATIC_ASSERT(WC_ARRAY_LENGTH(slip_grid_rpm) * WC_ARRAY_LENGTH(theta_grid_degC) * WC_ARRAY_LENGTH(request_grid) ==
                     GRID_POINTS, grid_points);


/* Inverse rows by the status the call returned. */
static row_t inverse_row(wc_status_t status, row_t solve)
{
    if ((status & WC_STATUS_BELOW_DRAG) != 0u) { return (row_t)(solve + 1); }
    if ((status & WC_STATUS_SATURATED) != 0u) { return (row_t)(solve + 2); }
    return solve;
}

/* One ClutchSensors and one TorqueRequest frame with alive counter `alive`,
 * queued in the loop. */
void queue_frames(float slip_rpm, float theta_degC, float request_Nm, uint8_t alive)
{
    const wc_can_clutch_sensors_phys_t sensors = {slip_rpm, theta_degC, theta_degC, alive};
    const wc_can_torque_request_phys_t request = {fminf(request_Nm, LOOP_REQUEST_MAX_Nm),
                                                  WC_CAN_TORQUE_REQUEST_MODE_TORQUE_CONTROL_CHOICE, alive};
    if ((wc_can_encode_clutch_sensors(bench.sensors_frame, &sensors, sizeof bench.sensors_frame) != WC_CAN_OK) ||
        (wc_can_encode_torque_request(bench.request_frame, &request, sizeof bench.request_frame) != WC_CAN_OK)) {
        fail("encoding the loop's input frames");
    }
    wc_can_frame_t frame = {WC_CAN_CLUTCH_SENSORS_FRAME_ID, 8u, 0u, {0u}};
    for (uint32_t i = 0u; i < 8u; ++i) { frame.data[i] = bench.sensors_frame[i]; }
    (void)wc_loop_receive(&loop, &frame);
    frame.id = WC_CAN_TORQUE_REQUEST_FRAME_ID;
    for (uint32_t i = 0u; i < 8u; ++i) { frame.data[i] = bench.request_frame[i]; }
    (void)wc_loop_receive(&loop, &frame);
}

/* The film_lag row's measured steps of a fresh clutch: the first, the lead at
 * work while the film closes (the film settles in about 0.1 s), and settled. */
#define FILM_LAG_TIME_s 0.015f
static const uint32_t film_lag_steps[FILM_LAG_SAMPLES_PER_POINT] = {1u, 4u, 10u, 25u, 60u, 150u};

static void bench_point(float slip_rpm, float theta_degC, float fraction, worst_diff_t *worst)
{
    const float slip_rad_s = slip_rpm * WC_RAD_S_PER_RPM;
    bench.model = &model;
    bench.cal = model.cal;
    bench.slip_rad_s = slip_rad_s;
    bench.theta_degC = theta_degC;

    wc_torque_t capacity;
    if (wc_torque(&model, slip_rad_s, theta_degC, model.force_max_N, &capacity) != WC_STATUS_OK) {
        fail("capacity: wc_torque rejected a grid point");
    }
    const float request_Nm = fraction * fabsf(capacity.torque_Nm);
    bench.request_Nm = request_Nm;

    /* wc_inverse, then the naive baseline at the same point. */
    const uint32_t inverse_count = measure(thunk_inverse, &bench);
    const wc_status_t inverse_status = bench.status;
    const wc_inverse_t inverse = bench.inverse;
    if ((inverse_status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_inverse rejected a grid point"); }
    record(inverse_row(inverse_status, ROW_INVERSE_SOLVE), inverse_count);

    const uint32_t naive_count = measure(thunk_naive_inverse, &bench);
    const row_t naive_row = inverse_row(bench.status, ROW_NAIVE_SOLVE);
    record(naive_row, naive_count);
    if ((naive_row - ROW_NAIVE_SOLVE) != (inverse_row(inverse_status, ROW_INVERSE_SOLVE) - ROW_INVERSE_SOLVE)) {
        wc_arm_puts("NAIVE case differs from wc_inverse");
        put_point(slip_rpm, theta_degC, fraction);
        wc_arm_puts("\n");
        fail("naive inverse: below-drag/saturated case differs from wc_inverse");
    }
    const float diff_N = fabsf(bench.inverse.force_N - inverse.force_N);
    if (diff_N > worst->diff_N) {
        *worst = (worst_diff_t){diff_N, inverse.force_N, slip_rpm, theta_degC, fraction};
    }

    /* wc_torque at the force the inverse found. */
    bench.force_N = inverse.force_N;
    record(ROW_TORQUE, measure(thunk_torque, &bench));
    const float torque_Nm = bench.torque.torque_Nm;

    /* Observer step with the heat input of that torque. */
    bench.theta_state_degC = theta_degC;
    bench.power_W = fabsf(torque_Nm * slip_rad_s);
    record(ROW_THERMAL_STEP, measure(thunk_thermal_step, &bench));

    bench.speed_m_s = model.effective_radius_m * fabsf(slip_rad_s);
    record(ROW_FRICTION_VISCOSITY, measure(thunk_friction_viscosity, &bench));

    /* expf at the model's typical arguments: the two viscosity exponents of eq. 2. */
    bench.exp_argument = model.cal->viscosity_b1_per_K * theta_degC;
    record(ROW_EXPF, measure(thunk_expf, &bench));
    bench.exp_argument = model.cal->viscosity_b2_per_K * theta_degC;
    record(ROW_EXPF, measure(thunk_expf, &bench));

    /* wc_clutch_step: a fresh clutch at theta, the 4th step measured. */
    if (wc_clutch_init(&clutch, model.cal, theta_degC) != WC_CAL_OK) { fail("wc_clutch_init"); }
    bench.clutch = &clutch;
    bench.step_in = (wc_step_input_t){.slip_rad_s = slip_rad_s, .theta_oil_degC = theta_degC,
                                    .theta_housing_degC = theta_degC, .torque_request_Nm = request_Nm,
                                    .mode = WC_MODE_TORQUE, .bench = {false, 0.0f, 0.0f}};
    for (uint32_t k = 0u; k < WARMUP_STEPS; ++k) { thunk_clutch_step(&bench); }
    record(ROW_CLUTCH_STEP, measure(thunk_clutch_step, &bench));
    if ((bench.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step rejected a grid point"); }
    const wc_step_output_t step = bench.step_out;

    /* The same with the squeeze-film state on: a fresh clutch (open film), the 4th step measured. */
    if (wc_clutch_init(&clutch, &film_calibration, theta_degC) != WC_CAL_OK) { fail("wc_clutch_init (film)"); }
    for (uint32_t k = 0u; k < WARMUP_STEPS; ++k) { thunk_clutch_step(&bench); }
    record(ROW_CLUTCH_STEP_FILM, measure(thunk_clutch_step, &bench));
    if ((bench.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step (film) rejected a grid point"); }

    /* The configuration the shift controller runs the clutch in: the identified
     * calibration (film on) with the lag compensation of 15 ms (shift_1_2.toml),
     * a fresh clutch at the open film; the steps of FILM_LAG_STEPS measured, so
     * that the film's approach (lead active, then settled) is on the grid. */
    if (wc_clutch_init(&clutch, wc_arm_identified_calibration, theta_degC) != WC_CAL_OK) {
        fail("wc_clutch_init (identified)");
    }
    bench.step_in.lag_compensation = wc_lag_compensation(&clutch, FILM_LAG_TIME_s);
    for (uint32_t k = 1u, next = 0u; next < FILM_LAG_SAMPLES_PER_POINT; ++k) {
        if (k == film_lag_steps[next]) {
            record(ROW_CLUTCH_STEP_FILM_LAG, measure(thunk_clutch_step, &bench));
            if ((bench.status & WC_STATUS_INPUT_INVALID) != 0u) { fail("wc_clutch_step (film, lag) rejected a grid point"); }
            next++;
        } else {
            thunk_clutch_step(&bench);
        }
    }
    bench.step_in.lag_compensation = wc_lag_compensation(&clutch, 0.0f);  /* off */

    /* wc_loop_step: both input frames queued every period, the 4th step measured. */
    /* The default configuration with a one-period recovery debounce, so that the
     * 4th step is a controlling one (the debounce counts periods, it costs nothing). */
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.recovery_periods = 1u;
    if (wc_loop_init(&loop, model.cal, &config, theta_degC) != WC_CAL_OK) { fail("wc_loop_init"); }
    bench.loop = &loop;
    for (uint8_t k = 0u; k <= WARMUP_STEPS; ++k) {
        queue_frames(slip_rpm, theta_degC, request_Nm, k);
        if (k < WARMUP_STEPS) {
            thunk_loop_step(&bench);
        } else {
            record(ROW_LOOP_STEP, measure(thunk_loop_step, &bench));
        }
    }
    const uint32_t frames_in = 2u * (WARMUP_STEPS + 1u);
    if ((bench.tx_frames != WC_LOOP_TX_CYCLIC) || (loop.counters.frames_used != frames_in) ||
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
    record(ROW_DECODE_CLUTCH_SENSORS, measure(thunk_decode_clutch_sensors, &bench));
    if (bench.can_result != WC_CAN_OK) { fail("wc_can_decode_clutch_sensors"); }
    record(ROW_DECODE_TORQUE_REQUEST, measure(thunk_decode_torque_request, &bench));
    if (bench.can_result != WC_CAN_OK) { fail("wc_can_decode_torque_request"); }
    bench.vfs = (wc_can_vfs_command_phys_t){step.current_mA, 0.001f * step.pressure_command_Pa, 0u, WARMUP_STEPS};
    record(ROW_ENCODE_VFS_COMMAND, measure(thunk_encode_vfs_command, &bench));
    bench.estimate = (wc_can_clutch_estimate_phys_t){step.theta_degC, step.model.torque_Nm, step.model.mu_f,
                                                   1.0e6f * step.model.hbar_m, 0u};
    record(ROW_ENCODE_CLUTCH_ESTIMATE, measure(thunk_encode_clutch_estimate, &bench));
    record(ROW_CRC8, measure(thunk_crc8, &bench));
}

void bench_grid(worst_diff_t *worst)
{
    for (uint32_t s = 0u; s < WC_ARRAY_LENGTH(slip_grid_rpm); ++s) {
        for (uint32_t t = 0u; t < WC_ARRAY_LENGTH(theta_grid_degC); ++t) {
            for (uint32_t r = 0u; r < WC_ARRAY_LENGTH(request_grid); ++r) {
                bench_point(slip_grid_rpm[s], theta_grid_degC[t], request_grid[r], worst);
            }
        }
    }
}
