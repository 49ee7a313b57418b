/* The shift phase state machine (wc_shift_step, include/wetclutch/wc_shift.h,
 * src/model/wc_shift.c; DESIGN section 10) on the plant of
 * wc_test_fixtures.h: the phases in order, their aborts, the one-report rule,
 * anti-windup bounds and non-finite sensors. */
#include "wc_test_shift_harness.h"

#include <float.h>

#include "wc_table1_calibration.h"

static bool finite_report(const wc_shift_report_t *r)
{
    return isfinite(r->inertia_time_s) && isfinite(r->slip_rmse_rad_s) && isfinite(r->peak_jerk_m_s3) &&
           isfinite(r->friction_energy_J) && isfinite(r->peak_theta_degC) && (r->inertia_time_s >= 0.0f) &&
           (r->slip_rmse_rad_s >= 0.0f) && (r->peak_jerk_m_s3 >= 0.0f) && (r->friction_energy_J >= 0.0f);
}

static bool finite_shift_state(const wc_shift_t *s)
{
    return isfinite(s->turbine_torque_Nm) && isfinite(s->target_time_s) && isfinite(s->start_slip_rad_s) &&
           isfinite(s->integral_Nm) && isfinite(s->request_Nm) && isfinite(s->phase_start_request_Nm) &&
           isfinite(s->filtered_torque_Nm) && isfinite(s->error_sq_sum) && finite_report(&s->report);
}

/* ======================================================================== */
/* Shift state machine on the plant                                          */
/* ======================================================================== */

typedef struct {
    const wc_shift_calibration_t *cal;
    wc_clutch_t clutch;
    wc_shift_t shift;
    wc_step_output_t out;
    wc_shift_report_t report;
    float slip_rad_s;
    float plant_torque_Nm;     /* the true T_t */
    bool offgoing_released;    /* the plant's turbine is free from the inertia phase on */
    bool turbine_held;         /* tie-up plant: the off-going never releases */
    uint32_t ended;            /* wc_shift_step returned true */
    uint32_t phase_log[16];    /* distinct phases in order */
    uint32_t phase_log_len;
    uint32_t phase_steps[8];   /* steps that ended in each phase */
    float max_abs_integral_Nm;
    bool all_finite;
} sim_t;

static void sim_init(sim_t *s, const wc_shift_calibration_t *cal, float slip_rad_s, float plant_torque_Nm)
{
    memset(s, 0, sizeof *s);
    s->cal = cal;
    assert_int_equal(wc_clutch_init(&s->clutch, &wc_table1_calibration, THETA_OIL_degC), WC_CAL_OK);
    wc_shift_init(&s->shift);
    s->slip_rad_s = slip_rad_s;
    s->plant_torque_Nm = plant_torque_Nm;
    s->all_finite = true;
    s->phase_log[0] = (uint32_t)WC_SHIFT_IDLE;
    s->phase_log_len = 1u;
}

static wc_shift_command_t command_of(bool request, float turbine_torque_Nm, float target_s)
{
    const wc_shift_command_t c = { request, 2u, turbine_torque_Nm, target_s };
    return c;
}

/* One period: the controller with the measured slip (or sensor_slip when
 * given: a sensor fault), then the plant. Returns wc_shift_step's result. */
static bool sim_step_sensor(sim_t *s, const wc_shift_command_t *command, bool safe, float sensor_slip,
                            float sensor_oil)
{
    wc_step_input_t sensors;
    memset(&sensors, 0, sizeof sensors);
    sensors.slip_rad_s = sensor_slip;
    sensors.theta_oil_degC = sensor_oil;
    sensors.theta_housing_degC = THETA_OIL_degC;
    const bool ended = wc_shift_step(&s->shift, s->cal, command, safe, &s->clutch, NULL, &sensors, &s->out, &s->report, NULL);
    if (ended) { s->ended++; }
    const uint32_t phase = s->shift.phase;
    if (phase != s->phase_log[s->phase_log_len - 1u]) {
        assert_true(s->phase_log_len < WC_TEST_COUNT(s->phase_log));
        s->phase_log[s->phase_log_len++] = phase;
    }
    assert_true(phase < 8u);
    s->phase_steps[phase]++;
    if (fabsf(s->shift.integral_Nm) > s->max_abs_integral_Nm) { s->max_abs_integral_Nm = fabsf(s->shift.integral_Nm); }
    if (!finite_output(&s->out) || !finite_shift_state(&s->shift)) { s->all_finite = false; }

    /* plant */
    if (phase == (uint32_t)WC_SHIFT_INERTIA) { s->offgoing_released = true; }
    if (s->offgoing_released && !s->turbine_held) {
        s->slip_rad_s = wc_test_shift_plant_slip_rad_s(s->cal, s->slip_rad_s, s->plant_torque_Nm, &s->out, DT_s);
    }
    return ended;
}

static bool sim_step(sim_t *s, const wc_shift_command_t *command, bool safe)
{
    return sim_step_sensor(s, command, safe, s->slip_rad_s, THETA_OIL_degC);
}

/* Runs with the command until the shift ends or max_steps; returns the steps. */
static uint32_t sim_run_to_end(sim_t *s, const wc_shift_command_t *command, uint32_t max_steps)
{
    for (uint32_t k = 0u; k < max_steps; ++k) {
        if (sim_step(s, command, false)) { return k + 1u; }
    }
    return max_steps;
}

static uint32_t sim_run_until_phase(sim_t *s, const wc_shift_command_t *command, wc_shift_phase_t phase,
                                    uint32_t extra_steps)
{
    uint32_t k = 0u;
    while ((s->shift.phase != (uint32_t)phase) && (k < 5000u)) {
        (void)sim_step(s, command, false);
        k++;
    }
    WC_CHECK(s->shift.phase == (uint32_t)phase, "phase %u not reached (at %u)", (unsigned)phase, (unsigned)s->shift.phase);
    for (uint32_t i = 0u; i < extra_steps; ++i) {
        (void)sim_step(s, command, false);
        k++;
    }
    return k;
}

static void test_shift_completes(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(false, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    for (int k = 0; k < 20; ++k) { assert_false(sim_step(&s, &command, false)); }  /* idle: released */
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "idle current %g",
             (double)s.out.current_mA);
    command.request = true;
    const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_LOCKED, "ended in phase %u after %u steps", (unsigned)s.shift.phase,
             (unsigned)steps);
    print_report("shift", &s.report);
    const uint32_t expected_log[] = { WC_SHIFT_IDLE, WC_SHIFT_PREPARE, WC_SHIFT_TORQUE, WC_SHIFT_INERTIA,
                                      WC_SHIFT_LOCKUP, WC_SHIFT_LOCKED };
    WC_CHECK(s.phase_log_len == WC_TEST_COUNT(expected_log), "%u phases", (unsigned)s.phase_log_len);
    for (uint32_t i = 0u; i < s.phase_log_len; ++i) {
        WC_CHECK(s.phase_log[i] == expected_log[i], "phase %u: %u, expected %u", (unsigned)i, (unsigned)s.phase_log[i],
                 (unsigned)expected_log[i]);
    }
    /* phase lengths: prepare 50, torque 100 (the step that enters the next
     * phase counts to the next), lock-up ramp 50 periods */
    WC_CHECK((s.phase_steps[WC_SHIFT_PREPARE] >= 49u) && (s.phase_steps[WC_SHIFT_PREPARE] <= 51u), "prepare %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_PREPARE]);
    WC_CHECK((s.phase_steps[WC_SHIFT_TORQUE] >= 99u) && (s.phase_steps[WC_SHIFT_TORQUE] <= 101u), "torque %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_TORQUE]);
    WC_CHECK((s.phase_steps[WC_SHIFT_LOCKUP] >= 49u) && (s.phase_steps[WC_SHIFT_LOCKUP] <= 51u), "lockup %u steps",
             (unsigned)s.phase_steps[WC_SHIFT_LOCKUP]);
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_NONE);
    /* inertia time: the reference reaches 0 at the target; the lock-up dwell
     * (10 periods) and the tracking lag come on top: within [0.9, 1.15] target */
    WC_CHECK((s.report.inertia_time_s >= 0.9f * TARGET_TIME_s) && (s.report.inertia_time_s <= 1.15f * TARGET_TIME_s),
             "inertia time %g s, target %g s", (double)s.report.inertia_time_s, (double)TARGET_TIME_s);
    WC_CHECK_CLOSE("inertia time = inertia phase steps", 0, s.report.inertia_time_s,
                   (double)s.phase_steps[WC_SHIFT_INERTIA] * (double)DT_s, 0.0, 1.5e-3);
    /* tracking: RMSE under 3 % of the start slip */
    WC_CHECK(s.report.slip_rmse_rad_s < 0.03f * START_SLIP_rad_s, "slip RMSE %g rad/s", (double)s.report.slip_rmse_rad_s);
    WC_CHECK(!s.report.flare && !s.report.tie_up, "flare %d tie-up %d", s.report.flare, s.report.tie_up);
    /* energy: about the ideal T_c * slip integral, (T_t/a) * start/2 * target = 2.5 kJ, plus the inertia's share */
    WC_CHECK((s.report.friction_energy_J > 1500.0f) && (s.report.friction_energy_J < 6000.0f), "energy %g J",
             (double)s.report.friction_energy_J);
    WC_CHECK((s.report.peak_theta_degC > THETA_OIL_degC) && (s.report.peak_theta_degC < 200.0f), "peak theta %g",
             (double)s.report.peak_theta_degC);
    WC_CHECK(s.report.peak_jerk_m_s3 > 0.0f, "peak jerk %g", (double)s.report.peak_jerk_m_s3);
    WC_CHECK(finite_report(&s.report) && s.all_finite, "non-finite");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
    WC_CHECK(fabsf(s.slip_rad_s) <= 0.0f, "slip %g after lock", (double)s.slip_rad_s);

    /* locked: the holding request stays, no second report */
    for (int k = 0; k < 300; ++k) { (void)sim_step(&s, &command, false); }
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.shift.phase, WC_SHIFT_LOCKED);
    WC_CHECK_CLOSE("holding request", 0, s.shift.request_Nm,
                   (double)test_cal.holding_torque_factor * (double)TURBINE_TORQUE_Nm / (double)test_cal.turbine_ratio,
                   1e-6, 0.0);
    WC_CHECK((s.out.status & WC_STATUS_LOCKED) != 0u, "not locked while holding");
    /* the command ends: idle, released, still one report */
    command.request = false;
    for (int k = 0; k < 10; ++k) { (void)sim_step(&s, &command, false); }
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    assert_int_equal(s.ended, 1u);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "idle current %g",
             (double)s.out.current_mA);
}

static void test_shift_cancel(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
    assert_int_equal(s.ended, 0u);
    command.request = false;
    WC_CHECK(sim_step(&s, &command, false), "cancel did not end the shift");
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_CANCELLED);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    WC_CHECK(s.report.inertia_time_s <= 0.0f, "inertia time %g of an unfinished inertia phase",
             (double)s.report.inertia_time_s);
    for (int k = 0; k < 200; ++k) {
        (void)sim_step(&s, &command, false);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
    }
    assert_int_equal(s.ended, 1u);
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    /* cancelled in PREPARE and in TORQUE too */
    const wc_shift_phase_t phases[] = { WC_SHIFT_PREPARE, WC_SHIFT_TORQUE, WC_SHIFT_LOCKUP };
    for (size_t i = 0u; i < WC_TEST_COUNT(phases); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        command.request = true;
        (void)sim_run_until_phase(&s, &command, phases[i], 5u);
        command.request = false;
        WC_CHECK(sim_step(&s, &command, false), "phase %u: cancel did not end the shift", (unsigned)phases[i]);
        assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_CANCELLED);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
    }
}

/* After an abort the clutch stays released while the request stays 1 (no
 * restart, no flapping); request 0 then a new rising edge starts a new shift. */
static void test_shift_input_lost_and_restart(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 50u);
    WC_CHECK(sim_step(&s, &command, true), "safe state did not end the shift");
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INPUT_LOST);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    /* safe, then not safe, the request still 1: aborted and released */
    for (int k = 0; k < 300; ++k) {
        (void)sim_step(&s, &command, k < 50);
        WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_ABORTED, "step %d: phase %u", k, (unsigned)s.shift.phase);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "step %d: %g mA",
                 k, (double)s.out.current_mA);
    }
    assert_int_equal(s.ended, 1u);
    /* request 0: idle; then a rising edge: a new shift (the slip flared meanwhile: the plant's turbine was free) */
    command.request = false;
    (void)sim_step(&s, &command, false);
    assert_int_equal(s.shift.phase, WC_SHIFT_IDLE);
    s.slip_rad_s = START_SLIP_rad_s;
    s.offgoing_released = false;  /* the plant: first gear again */
    command.request = true;
    (void)sim_step(&s, &command, false);
    assert_int_equal(s.shift.phase, WC_SHIFT_PREPARE);
    const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.shift.phase == (uint32_t)WC_SHIFT_LOCKED, "second shift ended in %u after %u steps",
             (unsigned)s.shift.phase, (unsigned)steps);
    assert_int_equal(s.ended, 2u);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_NONE);
    /* a fresh report: no flare carried over from the aborted shift */
    WC_CHECK(!s.report.flare, "flare of the first shift carried over");
}

/* The safe state while the shift is LOCKED (completed, request still 1): the
 * frame loop's safe-state policy is the solenoid's minimum current
 * (wc_loop.h), and wc_shift.h says safe = "the loop's safe state is active". */
static void test_shift_safe_while_locked_releases(void **state)
{
    (void)state;
    static sim_t s;
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    assert_int_equal(s.shift.phase, WC_SHIFT_LOCKED);
    (void)sim_step(&s, &command, true);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA),
             "safe state while LOCKED: current %g mA (phase %u), expected the minimum %g mA", (double)s.out.current_mA,
             (unsigned)s.shift.phase, (double)wc_table1_calibration.vfs_current_min_mA);
}

static void test_shift_invalid_command(void **state)
{
    (void)state;
    static sim_t s;
    const wc_shift_command_t bad[] = {
        { true, 3u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 1u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 0u, TURBINE_TORQUE_Nm, TARGET_TIME_s },
        { true, 2u, TURBINE_TORQUE_Nm, nextafterf(0.1f, 0.0f) },  /* below inertia_time_min_s */
        { true, 2u, TURBINE_TORQUE_Nm, nextafterf(2.0f, 3.0f) },  /* above inertia_time_max_s */
        { true, 2u, TURBINE_TORQUE_Nm, NAN },
        { true, 2u, TURBINE_TORQUE_Nm, -INFINITY },
        { true, 2u, -1.0f, TARGET_TIME_s },
        { true, 2u, -1e-6f, TARGET_TIME_s },
        { true, 2u, NAN, TARGET_TIME_s },
        { true, 2u, INFINITY, TARGET_TIME_s },
        { true, 2u, nextafterf(WC_TORQUE_MAX_Nm, INFINITY), TARGET_TIME_s },
    };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        WC_CHECK(sim_step(&s, &bad[i], false), "command %zu: did not end at the start", i);
        assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
        WC_CHECK(s.report.abort_reason == (uint32_t)WC_SHIFT_ABORT_INVALID_COMMAND, "command %zu: reason %u", i,
                 (unsigned)s.report.abort_reason);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "command %zu: %g mA",
                 i, (double)s.out.current_mA);
        for (int k = 0; k < 100; ++k) {
            (void)sim_step(&s, &bad[i], false);
            WC_CHECK(finite_output(&s.out) && finite_report(&s.shift.report), "command %zu: non-finite output", i);
        }
        assert_int_equal(s.ended, 1u);
        WC_CHECK(finite_report(&s.report), "command %zu: non-finite report", i);
    }
    /* the limits themselves are valid */
    const wc_shift_command_t edge[] = { { true, 2u, 0.0f, 0.1f }, { true, 2u, TURBINE_TORQUE_Nm, 2.0f } };
    for (size_t i = 0u; i < WC_TEST_COUNT(edge); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        assert_false(sim_step(&s, &edge[i], false));
        assert_int_equal(s.shift.phase, WC_SHIFT_PREPARE);
    }
}

static void test_shift_inertia_timeout(void **state)
{
    (void)state;
    static sim_t s;
    /* (a) the clutch cannot pull: 2000 Nm against a capacity of a few hundred Nm; the turbine flares */
    sim_init(&s, &test_cal, START_SLIP_rad_s, 2000.0f);
    wc_shift_command_t command = command_of(true, 2000.0f, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    print_report("cannot pull", &s.report);
    assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INERTIA_TIMEOUT);
    assert_int_equal(s.ended, 1u);
    /* after target * factor = 0.75 s: the first period past it */
    WC_CHECK_CLOSE("timeout", 0, s.report.inertia_time_s, (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor),
                   0.0, 1.5e-3);
    WC_CHECK_CLOSE("inertia phase steps", 0, (double)s.phase_steps[WC_SHIFT_INERTIA] * (double)DT_s,
                   (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor), 0.0, 1.5e-3);
    WC_CHECK(s.report.flare, "the turbine ran away and no flare was reported");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
    /* the timeout is decided on the step's clutch output (after wc_clutch_step):
     * released from the next period on */
    (void)sim_step(&s, &command, false);
    WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
             (double)s.out.current_mA);
    assert_int_equal(s.ended, 1u);
    WC_CHECK(s.all_finite && finite_report(&s.report), "non-finite");

    /* (b) the slip never falls (the off-going clutch holds the turbine): timeout and tie-up */
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    s.turbine_held = true;
    command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_to_end(&s, &command, 5000u);
    print_report("tie-up", &s.report);
    assert_int_equal(s.report.abort_reason, WC_SHIFT_ABORT_INERTIA_TIMEOUT);
    WC_CHECK_CLOSE("timeout", 0, s.report.inertia_time_s, (double)(TARGET_TIME_s * test_cal.inertia_timeout_factor),
                   0.0, 1.5e-3);
    WC_CHECK(s.report.tie_up, "the slip held while the clutch pulled and no tie-up was reported");
    WC_CHECK(!s.report.flare, "flare reported with the slip held");
    WC_CHECK(s.max_abs_integral_Nm <= test_cal.integral_limit_Nm, "integral %g", (double)s.max_abs_integral_Nm);
}

static void test_shift_no_slip(void **state)
{
    (void)state;
    static sim_t s;
    const float slips[] = { 0.0f, 3.0f, 5.0f, -50.0f };  /* not above min_start_slip_rad_s (5) */
    for (size_t i = 0u; i < WC_TEST_COUNT(slips); ++i) {
        sim_init(&s, &test_cal, slips[i], TURBINE_TORQUE_Nm);
        const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
        const uint32_t steps = sim_run_to_end(&s, &command, 5000u);
        assert_int_equal(s.shift.phase, WC_SHIFT_ABORTED);
        WC_CHECK(s.report.abort_reason == (uint32_t)WC_SHIFT_ABORT_NO_SLIP, "slip %g: reason %u", (double)slips[i],
                 (unsigned)s.report.abort_reason);
        /* at the inertia phase's start: after prepare + torque phase */
        WC_CHECK((steps >= 150u) && (steps <= 152u), "slip %g: ended after %u steps", (double)slips[i], (unsigned)steps);
        WC_CHECK(wc_test_same_float(s.out.current_mA, wc_table1_calibration.vfs_current_min_mA), "current %g mA",
                 (double)s.out.current_mA);
        assert_int_equal(s.ended, 1u);
    }
}

/* Anti-windup: the integral within +-integral_limit_Nm in every phase,
 * also with a small limit, feedback only (feed-forward 0) and a high ki. */
static void test_shift_integral_bounded(void **state)
{
    (void)state;
    static sim_t s;
    wc_shift_calibration_t cal = test_cal;
    const float limits[] = { 0.0f, 20.0f, 50.0f, 300.0f };
    const float ff_gains[] = { 0.0f, 0.5f, 1.0f, 2.0f };
    const float plant_torque[] = { TURBINE_TORQUE_Nm, 2000.0f };
    for (size_t l = 0u; l < WC_TEST_COUNT(limits); ++l) {
        for (size_t g = 0u; g < WC_TEST_COUNT(ff_gains); ++g) {
            for (size_t p = 0u; p < WC_TEST_COUNT(plant_torque); ++p) {
                cal.integral_limit_Nm = limits[l];
                cal.feedforward_gain = ff_gains[g];
                cal.ki_Nm_per_rad = 400.0f;
                sim_init(&s, &cal, START_SLIP_rad_s, plant_torque[p]);
                const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
                (void)sim_run_to_end(&s, &command, 5000u);
                WC_CHECK(s.max_abs_integral_Nm <= limits[l],
                         "limit %g, feed-forward gain %g, plant %g Nm: |integral| reached %g (abort %u)",
                         (double)limits[l], (double)ff_gains[g], (double)plant_torque[p],
                         (double)s.max_abs_integral_Nm, (unsigned)s.report.abort_reason);
                WC_CHECK(s.all_finite, "non-finite");
                assert_int_equal(s.ended, 1u);
            }
        }
    }
}

/* Non-finite sensor values during the inertia phase: every output finite,
 * the shift state and report finite, one report. */
static void test_shift_non_finite_sensors(void **state)
{
    (void)state;
    static sim_t s;
    const float bad[] = { NAN, INFINITY, -INFINITY, -NAN, FLT_MAX, -FLT_MAX };
    for (size_t i = 0u; i < WC_TEST_COUNT(bad); ++i) {
        sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
        const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
        (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
        for (int k = 0; k < 30; ++k) {
            const bool slip_bad = (k % 3) != 2;
            const bool ended = sim_step_sensor(&s, &command, false, slip_bad ? bad[i] : s.slip_rad_s,
                                               ((k % 2) == 0) ? bad[i] : THETA_OIL_degC);
            WC_CHECK(!ended || (s.shift.phase == (uint32_t)WC_SHIFT_LOCKED) || (s.shift.phase == (uint32_t)WC_SHIFT_ABORTED),
                     "ended in %u", (unsigned)s.shift.phase);
            WC_CHECK(finite_output(&s.out), "sensor %g, step %d: non-finite output", (double)bad[i], k);
            WC_CHECK(finite_shift_state(&s.shift), "sensor %g, step %d: non-finite shift state", (double)bad[i], k);
        }
        (void)sim_run_to_end(&s, &command, 5000u);
        WC_CHECK(s.ended == 1u, "sensor %g: %u reports", (double)bad[i], (unsigned)s.ended);
        WC_CHECK(s.all_finite && finite_report(&s.report), "sensor %g: non-finite", (double)bad[i]);
        print_report("non-finite sensor", &s.report);
    }
    /* a non-finite turbine torque in the command during the shift: ignored (the latched one is kept) */
    sim_init(&s, &test_cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 100u);
    command.turbine_torque_Nm = NAN;
    for (int k = 0; k < 20; ++k) { (void)sim_step(&s, &command, false); }
    WC_CHECK(wc_test_same_float(s.shift.turbine_torque_Nm, TURBINE_TORQUE_Nm), "turbine torque %g",
             (double)s.shift.turbine_torque_Nm);
    WC_CHECK(s.all_finite, "non-finite");
}

/* The quality vector's theta with the thermal-blind model: the clutch model
 * uses the oil temperature, the report the observer's. */
static void test_shift_theta_source_oil(void **state)
{
    (void)state;
    static sim_t s;
    wc_shift_calibration_t cal = test_cal;
    cal.theta_source = (uint32_t)WC_SHIFT_THETA_OIL;
    sim_init(&s, &cal, START_SLIP_rad_s, TURBINE_TORQUE_Nm);
    const wc_shift_command_t command = command_of(true, TURBINE_TORQUE_Nm, TARGET_TIME_s);
    (void)sim_run_until_phase(&s, &command, WC_SHIFT_INERTIA, 200u);
    WC_CHECK(wc_test_same_float(s.out.theta_degC, THETA_OIL_degC), "theta used %g", (double)s.out.theta_degC);
    WC_CHECK(s.clutch.theta_degC > THETA_OIL_degC + 1.0f, "observer %g did not heat", (double)s.clutch.theta_degC);
    (void)sim_run_to_end(&s, &command, 5000u);
    WC_CHECK(s.report.peak_theta_degC > THETA_OIL_degC + 1.0f, "peak theta %g", (double)s.report.peak_theta_degC);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shift_completes),
        cmocka_unit_test(test_shift_cancel),
        cmocka_unit_test(test_shift_input_lost_and_restart),
        cmocka_unit_test(test_shift_safe_while_locked_releases),
        cmocka_unit_test(test_shift_invalid_command),
        cmocka_unit_test(test_shift_inertia_timeout),
        cmocka_unit_test(test_shift_no_slip),
        cmocka_unit_test(test_shift_integral_bounded),
        cmocka_unit_test(test_shift_non_finite_sensors),
        cmocka_unit_test(test_shift_theta_source_oil),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
