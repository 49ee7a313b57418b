/* The probe's transmission rows (wc_arm_bench.c; DESIGN 11, 15): wc_transmission_step with the 8HP
 * table's five elements (lut/wc_8hp_gearbox.h), each Table 1's clutch, the shift calibration
 * wc_shift_1_2_whole_full, driven by the C tests' plant (tests/c/wc_test_transmission_rig.h: the shift's
 * reduced two-speed model), 80 degC:
 *   :in_gear          3rd gear held at T_t 200 Nm (the three closed elements' inverse at their holding
 *                     need x 1.2, the two open ones at the minimum): 256 steps
 *   :power_on_up      2->3 at +150 Nm, every step from the request to the shift's end
 *   :power_off_up     2->3 at -80 Nm (tip-out: the inertia-first controller, mirrored)
 *   :power_on_down    3->2 at +150 Nm (kickdown: the inertia-first controller)
 *   :power_off_down   3->2 at -40 Nm (coast: the torque-first controller, mirrored)
 * Each shift must complete (AbortReason 0) in the target gear, else RESULT FAIL. RAM lines: the
 * transmission's state and one element's part of it (its clutch and its input).
 * The frame loop with the transmission (wc_loop_step, config.transmission; issue 29 item 3), the same
 * plant, ShiftCommand and GearboxSensors queued before each measured step (their encoding not measured):
 *   wc_loop_step:gearbox_in_gear      3rd gear held at 200 Nm: 256 steps
 *   wc_loop_step:gearbox_power_on_up  2->3 at +150 Nm, every step from the request to the ShiftReport
 * (the decode of both frames, the freshness, the transmission's step, five element commands, GearboxStatus,
 * EngineTorqueRequest). */
#include "wc_arm_bench.h"

#include "wc_8hp_gearbox.h"
#include "wc_shift_1_2_shift.h"
#include "wc_test_transmission_rig.h"

#define TX_OUTPUT_rad_s 60.0f
#define TX_OIL_degC 80.0f
#define TX_TARGET_s 0.4f
#define TX_IN_GEAR_STEPS 256u
#define TX_SETTLE_STEPS 300u      /* the VFS lag and the lock dwell in the start gear */
#define TX_SHIFT_STEPS_MAX 4000u  /* the longest (a stretched tip-out) ends well before */

static wc_transmission_t tx;
static wc_transmission_config_t tx_config;
static wc_transmission_output_t tx_output;

void thunk_transmission_step(void *ctx)
{
    bench_ctx_t *c = (bench_ctx_t *)ctx;
    c->tx_ended = wc_transmission_step(c->transmission, c->tx_config, &c->tx_command, &c->tx_input, c->tx_output, &c->shift_report);
}

typedef struct {
    float turbine_rad_s;
    float output_rad_s;
    float turbine_torque_Nm;
    float engine_Nm;             /* what the engine delivers of the transmission's request (the rig's lag) */
} tx_plant_t;

/* One measured (or not) step with the request current -> target, then the plant. */
static void tx_step(tx_plant_t *p, bool request, uint32_t current, uint32_t target, row_t row, bool measured)
{
    bench.tx_command = (wc_transmission_command_t){ request, current, target, p->turbine_torque_Nm, TX_TARGET_s };
    bench.tx_input = (wc_transmission_input_t){ p->turbine_rad_s, p->output_rad_s, TX_OIL_degC, TX_OIL_degC, false };
    if (measured) {
        record(row, measure(thunk_transmission_step, &bench));
    } else {
        thunk_transmission_step(&bench);
    }
    wc_test_tx_plant(&wc_gearbox_8hp, &tx, &tx_output, p->turbine_torque_Nm, wc_arm_calibration->control_period_s,
                     &p->engine_Nm, &p->turbine_rad_s, &p->output_rad_s);
}

/* Start in gear from, settle, then measure every step of the shift from -> to; it must complete. */
static void tx_shift(uint32_t from, uint32_t to, float turbine_torque_Nm, row_t row)
{
    if (wc_transmission_init(&tx, &tx_config, from, TX_OIL_degC) != WC_TRANSMISSION_OK) {
        fail("wc_transmission_init(8hp, table1)");
        return;
    }
    (void)memset(&tx_output, 0, sizeof tx_output);
    tx_plant_t p = { wc_gearbox_8hp.ratio[from] * TX_OUTPUT_rad_s, TX_OUTPUT_rad_s, turbine_torque_Nm, 0.0f };
    for (uint32_t k = 0u; k < TX_SETTLE_STEPS; ++k) { tx_step(&p, false, from, to, row, false); }
    bench.tx_ended = false;
    for (uint32_t k = 0u; (k < TX_SHIFT_STEPS_MAX) && !bench.tx_ended; ++k) { tx_step(&p, true, from, to, row, true); }
    if (!bench.tx_ended || (bench.shift_report.abort_reason != (uint32_t)WC_SHIFT_ABORT_NONE) || (tx.gear != to)) {
        fail("a transmission row's shift did not complete in its target gear");
    }
}

static wc_loop_t gearbox_loop;
static uint8_t gearbox_alive;

/* One step of the frame loop with the transmission: the period's two frames queued, the step measured
 * (or not), then the plant. */
static void loop_step(tx_plant_t *p, bool request, uint32_t current, uint32_t target, row_t row, bool measured)
{
    wc_can_frame_t f = { WC_CAN_SHIFT_COMMAND_FRAME_ID, 8u, 0u, { 0u } };
    const wc_can_shift_command_phys_t c = { request ? 1.0f : 0.0f, 0.0f, (float)target, p->turbine_torque_Nm,
                                            TX_TARGET_s * 1.0e3f, (float)current, gearbox_alive };
    (void)wc_can_encode_shift_command(f.data, &c, sizeof f.data);
    (void)wc_loop_receive(&gearbox_loop, &f);
    wc_can_frame_t s = { WC_CAN_GEARBOX_SENSORS_FRAME_ID, 8u, 0u, { 0u } };
    const wc_can_gearbox_sensors_phys_t g = { TX_OIL_degC, p->turbine_rad_s / WC_RAD_S_PER_RPM,
                                              p->output_rad_s / WC_RAD_S_PER_RPM, TX_OIL_degC, gearbox_alive };
    (void)wc_can_encode_gearbox_sensors(s.data, &g, sizeof s.data);
    (void)wc_loop_receive(&gearbox_loop, &s);
    gearbox_alive = wc_e2e_counter_next(gearbox_alive);
    if (measured) {
        record(row, measure(thunk_loop_step, &bench));
    } else {
        thunk_loop_step(&bench);
    }
    wc_test_tx_plant(&wc_gearbox_8hp, &gearbox_loop.transmission, &gearbox_loop.transmission_out, p->turbine_torque_Nm,
                     wc_arm_calibration->control_period_s, &p->engine_Nm, &p->turbine_rad_s, &p->output_rad_s);
}

static void bench_gearbox_loop(void)
{
    wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    config.transmission = &tx_config;
    config.transmission_start_gear = 3u;
    if (wc_loop_init(&gearbox_loop, NULL, &config, TX_OIL_degC) != WC_CAL_OK) {
        fail("wc_loop_init(8hp transmission)");
        return;
    }
    wc_loop_t *kept = bench.loop;
    bench.loop = &gearbox_loop;
    tx_plant_t p = { wc_gearbox_8hp.ratio[3] * TX_OUTPUT_rad_s, TX_OUTPUT_rad_s, 200.0f, 0.0f };
    for (uint32_t k = 0u; k < TX_SETTLE_STEPS; ++k) { loop_step(&p, false, 3u, 3u, ROW_LOOP_GEARBOX_IN_GEAR, false); }
    for (uint32_t k = 0u; k < TX_IN_GEAR_STEPS; ++k) { loop_step(&p, false, 3u, 3u, ROW_LOOP_GEARBOX_IN_GEAR, true); }
    config.transmission_start_gear = 2u;
    gearbox_alive = 0u;
    if (wc_loop_init(&gearbox_loop, NULL, &config, TX_OIL_degC) != WC_CAL_OK) {
        fail("wc_loop_init(8hp transmission)");
        bench.loop = kept;
        return;
    }
    p = (tx_plant_t){ wc_gearbox_8hp.ratio[2] * TX_OUTPUT_rad_s, TX_OUTPUT_rad_s, 150.0f, 0.0f };
    for (uint32_t k = 0u; k < TX_SETTLE_STEPS; ++k) { loop_step(&p, false, 2u, 2u, ROW_LOOP_GEARBOX_POWER_ON_UP, false); }
    bench.tx_frames = 0u;
    const uint32_t with_report = wc_gearbox_8hp.element_count + 3u;  /* the cyclic frames and the ShiftReport */
    for (uint32_t k = 0u; (k < TX_SHIFT_STEPS_MAX) && (bench.tx_frames < with_report); ++k) {
        loop_step(&p, true, 2u, 3u, ROW_LOOP_GEARBOX_POWER_ON_UP, true);
    }
    /* five element commands, GearboxStatus, EngineTorqueRequest and the ShiftReport; completed in 3rd */
    if ((bench.tx_frames != with_report) || (gearbox_loop.report.abort_reason != (uint32_t)WC_SHIFT_ABORT_NONE) ||
        (gearbox_loop.transmission.gear != 3u)) {
        fail("the gearbox loop's shift did not complete in 3rd");
    }
    bench.loop = kept;
}

void bench_transmission(void)
{
    wc_test_tx_config(&tx_config, &wc_gearbox_8hp, wc_arm_calibration, &wc_shift_1_2_whole_full);
    bench.transmission = &tx;
    bench.tx_config = &tx_config;
    bench.tx_output = &tx_output;

    if (wc_transmission_init(&tx, &tx_config, 3u, TX_OIL_degC) != WC_TRANSMISSION_OK) {
        fail("wc_transmission_init(8hp, table1)");
        return;
    }
    (void)memset(&tx_output, 0, sizeof tx_output);
    tx_plant_t p = { wc_gearbox_8hp.ratio[3] * TX_OUTPUT_rad_s, TX_OUTPUT_rad_s, 200.0f, 0.0f };
    for (uint32_t k = 0u; k < TX_SETTLE_STEPS; ++k) { tx_step(&p, false, 3u, 3u, ROW_TX_IN_GEAR, false); }
    for (uint32_t k = 0u; k < TX_IN_GEAR_STEPS; ++k) { tx_step(&p, false, 3u, 3u, ROW_TX_IN_GEAR, true); }

    tx_shift(2u, 3u, 150.0f, ROW_TX_POWER_ON_UP);
    tx_shift(2u, 3u, -80.0f, ROW_TX_POWER_OFF_UP);
    tx_shift(3u, 2u, 150.0f, ROW_TX_POWER_ON_DOWN);
    tx_shift(3u, 2u, -40.0f, ROW_TX_POWER_OFF_DOWN);

    bench_gearbox_loop();

    put_ram("wc_transmission_t", (uint32_t)sizeof(wc_transmission_t));
    put_ram("wc_transmission_t:per_element", (uint32_t)(sizeof(wc_clutch_t) + sizeof(wc_step_input_t)));
}
