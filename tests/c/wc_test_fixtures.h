/* Fixtures shared by the C tests (tests/c) and the Cortex-M4F probe
 * (bench/arm/wc_arm_bench.c): one home for the shift test scenario.
 *
 * Self-contained on purpose: only the library's public headers and the C
 * library, no cmocka and no lut/ header (a lut/ header defines its
 * calibration and is included in one translation unit only; the probe keeps
 * table1 in its own unit to size its flash). Header-only: static inline
 * functions and initializer macros.
 *
 * The shift scenario (DESIGN 10): a 1->2 upshift of the on-coming clutch,
 * turbine torque 100 Nm, slip 100 rad/s at the inertia phase's start (about
 * 950 rpm: 1->2 at ~2800 rpm engine speed, ratios 4.7 / 3.1), target 0.5 s,
 * oil and housing at 80 degC, on a reduced plant: the turbine side only, the
 * output side fixed,
 *   I_t d(slip)/dt = a (T_t - a T_c),  T_c = the clutch model's torque,
 * integrated with explicit Euler at the control period. Until the inertia
 * phase starts the off-going clutch holds the turbine (slip constant; the
 * caller decides when it lets go); from then on the turbine is free. Slip
 * cannot cross zero (the plates stick: it stays at 0 while the clutch torque
 * exceeds T_t's share), and while the clutch model says locked the slip is 0
 * (static friction holds it). */
#ifndef WC_TEST_FIXTURES_H
#define WC_TEST_FIXTURES_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_can_frame.h>
#include <wetclutch_can/wc_can_signals.h>

/* ---- the shift scenario ---------------------------------------------------- */

#define WC_TEST_SHIFT_OIL_degC 80.0f               /* oil and housing */
#define WC_TEST_SHIFT_START_SLIP_rad_s 100.0f      /* about 950 rpm */
#define WC_TEST_SHIFT_TURBINE_TORQUE_Nm 100.0f
#define WC_TEST_SHIFT_TARGET_TIME_s 0.5f
#define WC_TEST_SHIFT_SLIP_CAP_rad_s 1000.0f       /* the plant's free turbine is capped below WC_SLIP_MAX_rad_s */

/* The shift test calibration (within every limit of wc_shift.h): lag
 * compensation 15 ms, the observer's temperature. An initializer, like
 * WC_LOOP_CONFIG_DEFAULT:
 *   static const wc_shift_calibration_t cal = WC_TEST_SHIFT_CALIBRATION; */
#define WC_TEST_SHIFT_CALIBRATION                                                                              \
    {                                                                                                          \
        .turbine_inertia_kg_m2 = 0.25f,                                                                        \
        .turbine_ratio = 1.0f,                                                                                 \
        .output_inertia_kg_m2 = 1e5f, /* the plant holds the output speed: an output side that does not move */ \
        .output_ratio = 1.0f,                                                                                  \
        .jerk_per_torque_rate = 0.01f,                                                                         \
        .prepare_time_s = 0.05f,                                                                               \
        .torque_phase_time_s = 0.1f,                                                                           \
        .inertia_time_min_s = 0.1f,                                                                            \
        .inertia_time_max_s = 2.0f,                                                                            \
        .inertia_timeout_factor = 1.5f,                                                                        \
        .lockup_ramp_time_s = 0.05f,                                                                           \
        .holding_torque_factor = 1.3f,                                                                         \
        .min_start_slip_rad_s = 5.0f,                                                                          \
        .feedforward_gain = 1.0f,                                                                              \
        .kp_Nm_per_rad_s = 2.0f,                                                                               \
        .ki_Nm_per_rad = 40.0f,                                                                                \
        .integral_limit_Nm = 300.0f,                                                                           \
        .lag_compensation_time_s = 0.015f,                                                                     \
        .theta_source = (uint32_t)WC_SHIFT_THETA_OBSERVER,                                                     \
        .flare_slip_rad_s = 10.0f,                                                                             \
        .tie_up_factor = 1.5f,                                                                                 \
        .jerk_filter_time_s = 0.02f,                                                                           \
        WC_TEST_ADAPTATION_RULES(0u)                                                                           \
    }

/* The adaptation's rules of the test calibrations (DESIGN 12; the values of
 * tools/calibrations/shift_1_2.toml), adaptation on (1u) or off (0u). */
#define WC_TEST_ADAPTATION_RULES(on)                                                                           \
    .adaptation = (on), .adapt_theta_node_degC = { 40.0f, 80.0f, 120.0f, 160.0f, 200.0f },                    \
    .adapt_scale_band = 0.3f, .adapt_scale_step = 0.05f, .adapt_scale_gain = 0.6f,                            \
    .adapt_confidence_gain = 0.3f, .adapt_film_factor_min = 0.2f, .adapt_film_factor_max = 5.0f,              \
    .adapt_film_step = 0.3f, .adapt_film_gain = 0.0f, .adapt_kiss_band_Pa = 60e3f,                            \
    .adapt_kiss_step_Pa = 10e3f, .adapt_kiss_gain = 0.0f, .adapt_window_skip_s = 0.03f,                       \
    .adapt_film_window_s = 0.1f, .adapt_min_slip_drop = 0.5f, .adapt_min_conditioning = 0.05f,

/* Periods in Shift mode with ShiftRequest 0 after wc_loop_init with
 * WC_LOOP_CONFIG_DEFAULT, enough to leave the safe state (E2E sync and
 * recovery_periods); a rising edge of ShiftRequest then starts the shift. */
#define WC_TEST_SHIFT_LOOP_SETTLE_PERIODS 40u

/* One period of the free turbine: the slip after period_s with the clutch
 * torque of `out` (cal's turbine inertia and ratio, turbine torque
 * turbine_torque_Nm). Call it only once the off-going clutch has let go. */
static inline float wc_test_shift_plant_slip_rad_s(const wc_shift_calibration_t *cal, float slip_rad_s,
                                                   float turbine_torque_Nm, const wc_step_output_t *out,
                                                   float period_s)
{
    const float a = cal->turbine_ratio;
    const float accel = a * (turbine_torque_Nm - a * out->model.torque_Nm) / cal->turbine_inertia_kg_m2;
    float next = slip_rad_s + accel * period_s;
    if ((slip_rad_s >= 0.0f) && (next < 0.0f)) { next = 0.0f; }  /* the plates stick at zero */
    next = (next < WC_TEST_SHIFT_SLIP_CAP_rad_s) ? next : WC_TEST_SHIFT_SLIP_CAP_rad_s;
    if ((out->status & WC_STATUS_LOCKED) != 0u) { next = 0.0f; }  /* static friction holds */
    return next;
}

/* ---- frames ---------------------------------------------------------------- */

/* A classic frame: the id, DLC 8, no flags, every byte (padding too) zero. */
static inline wc_can_frame_t wc_test_can_frame(uint32_t id)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    return f;
}

/* The three frames of one period in Shift mode, from the generated encoders;
 * each returns the encoder's result, the caller decides what is acceptable. */

/* ClutchSensors: the slip, oil and housing at WC_TEST_SHIFT_OIL_degC. */
static inline wc_can_result_t wc_test_shift_sensors_frame(wc_can_frame_t *frame, float slip_rad_s, uint8_t alive)
{
    *frame = wc_test_can_frame(WC_CAN_CLUTCH_SENSORS_FRAME_ID);
    const wc_can_clutch_sensors_phys_t s = { slip_rad_s / WC_RAD_S_PER_RPM, WC_TEST_SHIFT_OIL_degC,
                                             WC_TEST_SHIFT_OIL_degC, alive };
    return wc_can_encode_clutch_sensors(frame->data, &s, sizeof frame->data);
}

/* TorqueRequest: 0 Nm in the given Mode (WC_CAN_TORQUE_REQUEST_MODE_SHIFT_CHOICE for Shift mode). */
static inline wc_can_result_t wc_test_shift_request_frame(wc_can_frame_t *frame, uint8_t mode, uint8_t alive)
{
    *frame = wc_test_can_frame(WC_CAN_TORQUE_REQUEST_FRAME_ID);
    const wc_can_torque_request_phys_t q = { 0.0f, mode, alive };
    return wc_can_encode_torque_request(frame->data, &q, sizeof frame->data);
}

/* ShiftCommand: the 1->2 upshift (target gear 2), requested or not. */
static inline wc_can_result_t wc_test_shift_command_frame(wc_can_frame_t *frame, bool request,
                                                          float turbine_torque_Nm, float target_ms, uint8_t alive)
{
    *frame = wc_test_can_frame(WC_CAN_SHIFT_COMMAND_FRAME_ID);
    const wc_can_shift_command_phys_t c = { request ? 1.0f : 0.0f, 0.0f, 2.0f, turbine_torque_Nm, target_ms, 1.0f, alive };
    return wc_can_encode_shift_command(frame->data, &c, sizeof frame->data);
}

#endif /* WC_TEST_FIXTURES_H */
