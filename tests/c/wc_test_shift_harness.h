/* The shared part of the shift tests (test_shift.c, test_shift_clutch_step.c,
 * test_shift_phases.c, test_shift_loop.c): the shift scenario of
 * wc_test_fixtures.h (calibration, plant, frames; shared with the ARM probe)
 * under the names the tests use, and the output check and the report print
 * that more than one of them needs. Include it instead of wc_test_support.h. */
#ifndef WC_TEST_SHIFT_HARNESS_H
#define WC_TEST_SHIFT_HARNESS_H

#include "wc_test_support.h"
#include "wc_test_fixtures.h"

#define DT_s 0.001f            /* table1's control period */
#define THETA_OIL_degC WC_TEST_SHIFT_OIL_degC
#define START_SLIP_rad_s WC_TEST_SHIFT_START_SLIP_rad_s
#define TURBINE_TORQUE_Nm WC_TEST_SHIFT_TURBINE_TORQUE_Nm
#define TARGET_TIME_s WC_TEST_SHIFT_TARGET_TIME_s

/* The test's shift calibration (wc_test_fixtures.h). */
static const wc_shift_calibration_t test_cal = WC_TEST_SHIFT_CALIBRATION;

static inline bool finite_output(const wc_step_output_t *out)
{
    return isfinite(out->current_mA) && isfinite(out->pressure_command_Pa) && isfinite(out->pressure_model_Pa) &&
           isfinite(out->force_command_N) && isfinite(out->theta_degC) && isfinite(out->contact_force_N) &&
           isfinite(out->static_capacity_Nm) && isfinite(out->model.torque_Nm) && isfinite(out->model.coulomb_Nm) &&
           isfinite(out->model.viscous_Nm) && isfinite(out->model.hbar_m) && isfinite(out->model.mu_f);
}

static inline void print_report(const char *what, const wc_shift_report_t *r)
{
    print_message("    %s: inertia %.3f s, slip RMSE %.3f rad/s, peak jerk %.3f m/s^3, energy %.1f J, peak theta %.1f degC,"
                  " flare %d, tie-up %d, abort %u\n",
                  what, (double)r->inertia_time_s, (double)r->slip_rmse_rad_s, (double)r->peak_jerk_m_s3,
                  (double)r->friction_energy_J, (double)r->peak_theta_degC, r->flare, r->tie_up,
                  (unsigned)r->abort_reason);
}

#endif /* WC_TEST_SHIFT_HARNESS_H */
