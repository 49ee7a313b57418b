/* Consumer of the installed or add_subdirectory()'d libraries: init one
 * clutch from the generated table1 calibration, step it once, check the
 * answer; then one period of the CAN frame loop (wetclutch_can). */
#include <stdio.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_loop.h>
#include "wc_table1_calibration.h"

static wc_loop_t loop;  /* large (receive ring): static storage */

int main(void)
{
    wc_clutch_t clutch;
    const wc_cal_error_t error = wc_clutch_init(&clutch, &wc_table1_calibration, 80.0f);
    if (error != WC_CAL_OK) {
        fprintf(stderr, "wc_consumer: calibration rejected: %s\n", wc_cal_error_name(error));
        return 1;
    }
    const wc_step_input_t in = {
        .slip_rad_s = 500.0f * WC_RAD_S_PER_RPM,
        .theta_oil_degC = 80.0f,
        .theta_housing_degC = 70.0f,
        .torque_request_Nm = 100.0f,
        .mode = WC_MODE_TORQUE,
    };
    wc_step_output_t out;
    const wc_status_t status = wc_clutch_step(&clutch, &in, &out);
    printf("wc_consumer: status 0x%02x, current %.1f mA, force %.1f N, %u iterations\n",
           (unsigned)status, (double)out.current_mA, (double)out.force_command_N,
           (unsigned)out.inverse_iterations);
    const int ok = (status == WC_STATUS_OK) && (out.current_mA > 0.0f) && (out.force_command_N > 0.0f);

    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    wc_can_frame_t tx[WC_LOOP_TX_FRAMES];
    const int loop_ok = (wc_loop_init(&loop, &wc_table1_calibration, &config, 80.0f) == WC_CAL_OK) &&
                        (wc_loop_step(&loop, tx) == WC_LOOP_TX_CYCLIC) && (tx[0].id == WC_CAN_VFS_COMMAND_FRAME_ID);
    printf("wc_consumer: loop step sent 0x%03x (no input yet: safe state)\n", (unsigned)tx[0].id);
    return (ok && loop_ok) ? 0 : 1;
}
