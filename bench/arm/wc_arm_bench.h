/* The Cortex-M4F probe's shared parts (DESIGN 11): the rows, the thunks' context and the measurement
 * (wc_arm_bench.c), the thunks (wc_arm_bench_thunks.c), and one file a concern: the model and frame
 * grid (wc_arm_bench_grid.c), shift control and the whole shift (wc_arm_bench_shift.c), the XCP
 * session (wc_arm_bench_xcp.c), the diagnostic server (wc_arm_bench_diag.c). What each row measures: the
 * top of wc_arm_bench.c (and of the concern's file). */
#ifndef WC_ARM_BENCH_H
#define WC_ARM_BENCH_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch/wc_transmission.h>
#include <wetclutch_can/wc_cal_image.h>
#include <wetclutch_can/wc_can_signals.h>
#include <wetclutch_can/wc_loop.h>
#include <wetclutch_can/wc_dtc.h>
#include <wetclutch_can/wc_isotp.h>
#include <wetclutch_can/wc_uds.h>
#include <wetclutch_can/wc_xcp.h>

#include "wc_arm_calibration.h"
#include "wc_arm_io.h"

#define WC_ARRAY_LENGTH(a) (sizeof(a) / sizeof((a)[0]))
#define WARMUP_STEPS 3u
/* The grid (wc_arm_bench_grid.c): slip 8 x theta 4 x request 6 points; wc_clutch_step:film_lag measures
 * this many steps at each. */
#define GRID_POINTS 192u
#define FILM_LAG_SAMPLES_PER_POINT 6u

/* The TorqueRequest signal's DBC range is 0..2000 Nm (hil/wetclutch.dbc):
 * the loop's request is capped there so that every frame is plausible. */
#define LOOP_REQUEST_MAX_Nm 2000.0f

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
    ROW_DIAG_TESTS,
    ROW_DIAG_IDLE,
    ROW_DIAG_READ_DID,
    ROW_DIAG_READ_DTC,
    ROW_LOOP_DIAG_IDLE,
    ROW_LOOP_DIAG_READ_DID,
    ROW_LOOP_DIAG_READ_DTC,
    ROW_TX_IN_GEAR,
    ROW_TX_POWER_ON_UP,
    ROW_TX_POWER_OFF_UP,
    ROW_TX_POWER_ON_DOWN,
    ROW_TX_POWER_OFF_DOWN,
    ROW_LOOP_GEARBOX_IN_GEAR,
    ROW_LOOP_GEARBOX_POWER_ON_UP,
    ROWS
} row_t;

/* Names as in bench/arm_ceilings.txt (wc_arm_bench.c). */
extern const char *const row_name[ROWS];

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
    wc_isotp_t *tp;                          /* the diagnostic rows: ISO-TP, the UDS server, the fault memory */
    wc_uds_t *uds;
    wc_dtc_t *dtc;
    wc_can_frame_t diag_tx[WC_ISOTP_MAX_FRAMES_PER_STEP];
    uint32_t diag_frames;
    wc_transmission_t *transmission;         /* the transmission rows (wc_arm_bench_transmission.c) */
    const wc_transmission_config_t *tx_config;
    wc_transmission_command_t tx_command;
    wc_transmission_input_t tx_input;
    wc_transmission_output_t *tx_output;
    bool tx_ended;
} bench_ctx_t;

typedef void (*thunk_t)(void *ctx);

/* The thunks (wc_arm_bench_thunks.c): one call of the measured function with arguments from a bench_ctx_t. */
void thunk_empty(void *ctx);
void thunk_nops(void *ctx);
void thunk_clutch_step(void *ctx);
void thunk_inverse(void *ctx);
void thunk_naive_inverse(void *ctx);
void thunk_torque(void *ctx);
void thunk_thermal_step(void *ctx);
void thunk_friction_viscosity(void *ctx);
void thunk_expf(void *ctx);
void thunk_loop_step(void *ctx);
void thunk_shift_step(void *ctx);
void thunk_whole_shift_step(void *ctx);
void thunk_decode_clutch_sensors(void *ctx);
void thunk_decode_torque_request(void *ctx);
void thunk_encode_vfs_command(void *ctx);
void thunk_encode_clutch_estimate(void *ctx);
void thunk_cal_image_load(void *ctx);
void thunk_xcp_step(void *ctx);
void thunk_crc32(void *ctx);
void thunk_cal_image_decode(void *ctx);
void thunk_loop_recalibrate(void *ctx);
void thunk_crc8(void *ctx);
void thunk_uds_step(void *ctx);
void thunk_diag_report(void *ctx);
void thunk_loop_diag_step(void *ctx);
void thunk_transmission_step(void *ctx);

/* The measurement (wc_arm_bench.c): instructions of one call of thunk(ctx), the empty window subtracted;
 * a sample of a row; a failure (RESULT FAIL, the first reason kept). */
uint32_t measure(thunk_t thunk, bench_ctx_t *ctx);
void record(row_t row, uint32_t instructions);
void fail(const char *reason);
void put_point(float slip_rpm, float theta_degC, float fraction);
/* A RAM line: "RAM <name> <bytes>" (a state's sizeof on the target). */
void put_ram(const char *name, uint32_t bytes);

/* The state the concerns share (wc_arm_bench.c). */
extern bench_ctx_t bench;
extern wc_model_t model;
extern wc_clutch_t clutch;
extern wc_calibration_t film_calibration;  /* table1 with the squeeze-film state on (DESIGN 9) */
extern wc_loop_t loop;
/* The committed calibration image lut/wc_table1_cal_image.h (table1 + shift_1_2_full, in its .wc_calibration
 * section; included in wc_arm_bench_thunks.c only). */
extern const uint8_t *const bench_cal_image;
extern const uint32_t bench_cal_image_bytes;

/* One ClutchSensors and one TorqueRequest frame with alive counter alive, queued in the loop (wc_arm_bench_grid.c). */
void queue_frames(float slip_rpm, float theta_degC, float request_Nm, uint8_t alive);

/* Where the naive inverse differs most from wc_inverse. */
typedef struct {
    float diff_N;
    float force_N;  /* wc_inverse's */
    float slip_rpm;
    float theta_degC;
    float fraction;
} worst_diff_t;

/* The concerns: the grid's rows (the naive inverse's worst difference in *worst), the shift rows, the
 * whole shift's RAM lines, the XCP session. */
void bench_grid(worst_diff_t *worst);
void bench_shift_step(const wc_calibration_t *cal, row_t row, bool adaptive, row_t end_row);
void bench_loop_shift(const wc_calibration_t *cal, row_t row);
void bench_whole_shift_step(const wc_calibration_t *cal, row_t row);
void bench_loop_whole_shift(const wc_calibration_t *cal, row_t row);
void whole_ram(void);
void bench_xcp(void);
void bench_transmission(void);
/* The diagnostic rows (wc_arm_bench_diag.c), and their integrator's wiring: the fault memory's tests from the
 * loop step's VfsCommand (c->tx) and the snapshot's operating point. */
void bench_diag(void);
void diag_report(bench_ctx_t *c);

#endif /* WC_ARM_BENCH_H */
