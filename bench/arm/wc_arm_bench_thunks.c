/* The probe's thunks (wc_arm_bench.h): each window of wc_arm_bench.c holds one indirect call of one
 * of them, which calls the measured function with its arguments from a bench_ctx_t. */
#include "wc_arm_bench.h"
#include "wc_arm_naive.h"
#include "wc_table1_cal_image.h"  /* lut/: table1 + shift_1_2_full, in the .wc_calibration section (one TU) */

const uint8_t *const bench_cal_image = wc_table1_cal_image;
const uint32_t bench_cal_image_bytes = WC_TABLE1_CAL_IMAGE_BYTES;

/* noipa: never inlined, cloned or specialised, so each window holds exactly
 * one indirect call and the measured code cannot be scheduled across the
 * SysTick reads. */
#define THUNK(name) __attribute__((noipa)) void name(void *ctx)

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
THUNK(thunk_uds_step)
{
    bench_ctx_t *c = ctx;
    c->diag_frames = wc_uds_step(c->uds, c->tp, c->diag_tx, WC_ISOTP_MAX_FRAMES_PER_STEP);
}
THUNK(thunk_diag_report) { diag_report(ctx); }
/* the control step of wc_tcu --uds: the loop, the fault memory's tests, the server */
THUNK(thunk_loop_diag_step)
{
    bench_ctx_t *c = ctx;
    c->tx_frames = wc_loop_step(c->loop, c->tx);
    diag_report(c);
    c->diag_frames = wc_uds_step(c->uds, c->tp, c->diag_tx, WC_ISOTP_MAX_FRAMES_PER_STEP);
}
