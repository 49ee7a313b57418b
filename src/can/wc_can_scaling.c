/* Physical <-> raw conversion and whole-frame encode/decode. See
 * wc_can_scaling.h. The constants restate hil/wetclutch.dbc (factor, offset,
 * [min|max] converted to raw, SNA from the generated VAL_ macros). */
#include "wc_can_scaling.h"

#include <math.h>

#include "wc_e2e.h"

/* ---- signal descriptors (DBC: raw = (value - offset) / factor) ---------- */

/* 0.25 rpm/bit, signed 16 bit, [-8000|8000] rpm -> raw +-32000. */
const wc_can_signal_t wc_can_sig_clutch_sensors_slip_speed = {
    .scale = 0.25f, .offset = 0.0f, .raw_min = -32000, .raw_max = 32000,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_SENSORS_SLIP_SPEED_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_SENSORS_SLIP_SPEED_SNA_CHOICE, .has_sna = true,
};
/* 0.1 degC/bit, offset -50, 12 bit, [-40|200] degC -> raw 100..2500. */
const wc_can_signal_t wc_can_sig_clutch_sensors_oil_temp = {
    .scale = 0.1f, .offset = -50.0f, .raw_min = 100, .raw_max = 2500,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE, .has_sna = true,
};
const wc_can_signal_t wc_can_sig_clutch_sensors_housing_temp = {
    .scale = 0.1f, .offset = -50.0f, .raw_min = 100, .raw_max = 2500,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_SENSORS_HOUSING_TEMP_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_SENSORS_HOUSING_TEMP_SNA_CHOICE, .has_sna = true,
};
/* 0.05 Nm/bit, unsigned 16 bit, [0|2000] Nm -> raw 0..40000. */
const wc_can_signal_t wc_can_sig_torque_request_torque_request = {
    .scale = 0.05f, .offset = 0.0f, .raw_min = 0, .raw_max = 40000,
    .raw_nan = (int32_t)WC_CAN_TORQUE_REQUEST_TORQUE_REQUEST_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_TORQUE_REQUEST_TORQUE_REQUEST_SNA_CHOICE, .has_sna = true,
};
/* 1/32 mA/bit, unsigned 16 bit, [0|2000] mA -> raw 0..64000; no SNA:
 * NaN -> 0 mA (no solenoid current). */
const wc_can_signal_t wc_can_sig_vfs_command_vfs_current = {
    .scale = 0.03125f, .offset = 0.0f, .raw_min = 0, .raw_max = 64000,
    .raw_nan = 0, .raw_sna = 0, .has_sna = false,
};
/* 1/16 kPa/bit, unsigned 16 bit, [0|4000] kPa -> raw 0..64000; no SNA:
 * NaN -> 0 kPa. */
const wc_can_signal_t wc_can_sig_vfs_command_pressure_command = {
    .scale = 0.0625f, .offset = 0.0f, .raw_min = 0, .raw_max = 64000,
    .raw_nan = 0, .raw_sna = 0, .has_sna = false,
};
/* 0.1 degC/bit, offset -50, 12 bit, [-40|350] degC -> raw 100..4000. */
const wc_can_signal_t wc_can_sig_clutch_estimate_estimated_clutch_temp = {
    .scale = 0.1f, .offset = -50.0f, .raw_min = 100, .raw_max = 4000,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_ESTIMATE_ESTIMATED_CLUTCH_TEMP_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_ESTIMATE_ESTIMATED_CLUTCH_TEMP_SNA_CHOICE, .has_sna = true,
};
/* 0.1 Nm/bit, signed 16 bit, [-3000|3000] Nm -> raw +-30000. */
const wc_can_signal_t wc_can_sig_clutch_estimate_model_torque = {
    .scale = 0.1f, .offset = 0.0f, .raw_min = -30000, .raw_max = 30000,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_ESTIMATE_MODEL_TORQUE_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_ESTIMATE_MODEL_TORQUE_SNA_CHOICE, .has_sna = true,
};
/* 1e-5/bit, unsigned 16 bit, [0|0.6] -> raw 0..60000. */
const wc_can_signal_t wc_can_sig_clutch_estimate_mu_f = {
    .scale = 1e-5f, .offset = 0.0f, .raw_min = 0, .raw_max = 60000,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_ESTIMATE_MU_F_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_ESTIMATE_MU_F_SNA_CHOICE, .has_sna = true,
};
/* 0.001 um/bit, unsigned 16 bit, [0|65] um -> raw 0..65000. */
const wc_can_signal_t wc_can_sig_clutch_estimate_film_thickness = {
    .scale = 0.001f, .offset = 0.0f, .raw_min = 0, .raw_max = 65000,
    .raw_nan = (int32_t)WC_CAN_CLUTCH_ESTIMATE_FILM_THICKNESS_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_CLUTCH_ESTIMATE_FILM_THICKNESS_SNA_CHOICE, .has_sna = true,
};
/* 0.1 N/bit, signed 20 bit, [-20000|20000] N -> raw +-200000. */
const wc_can_signal_t wc_can_sig_bench_measurement_load_cell_force = {
    .scale = 0.1f, .offset = 0.0f, .raw_min = -200000, .raw_max = 200000,
    .raw_nan = (int32_t)WC_CAN_BENCH_MEASUREMENT_LOAD_CELL_FORCE_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_BENCH_MEASUREMENT_LOAD_CELL_FORCE_SNA_CHOICE, .has_sna = true,
};
/* 0.01 Nm/bit, signed 20 bit, [-5000|5000] Nm -> raw +-500000. */
const wc_can_signal_t wc_can_sig_bench_measurement_measured_torque = {
    .scale = 0.01f, .offset = 0.0f, .raw_min = -500000, .raw_max = 500000,
    .raw_nan = (int32_t)WC_CAN_BENCH_MEASUREMENT_MEASURED_TORQUE_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_BENCH_MEASUREMENT_MEASURED_TORQUE_SNA_CHOICE, .has_sna = true,
};
/* 0.1 degC/bit, offset -50, 12 bit, [-40|350] degC -> raw 100..4000. */
const wc_can_signal_t wc_can_sig_bench_measurement_clutch_thermistor_temp = {
    .scale = 0.1f, .offset = -50.0f, .raw_min = 100, .raw_max = 4000,
    .raw_nan = (int32_t)WC_CAN_BENCH_MEASUREMENT_CLUTCH_THERMISTOR_TEMP_SNA_CHOICE,
    .raw_sna = (int32_t)WC_CAN_BENCH_MEASUREMENT_CLUTCH_THERMISTOR_TEMP_SNA_CHOICE, .has_sna = true,
};

/* ---- results ------------------------------------------------------------- */

bool wc_can_is_error(wc_can_result_t result)
{
    return result >= WC_CAN_ERR_NAN;
}

wc_can_result_t wc_can_worst(wc_can_result_t a, wc_can_result_t b)
{
    return (b > a) ? b : a;
}

/* ---- one signal ---------------------------------------------------------- */

wc_can_result_t wc_can_phys_to_raw(const wc_can_signal_t *sig, float value,
                                   int32_t *raw)
{
    float steps;

    if ((sig == NULL) || (raw == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
    if (isnan(value)) {
        *raw = sig->raw_nan;
        return WC_CAN_ERR_NAN;
    }
    /* Every raw limit is below 2^24 in magnitude, so it is exact in float and
     * the comparisons below decide saturation exactly; +-inf saturates. */
    steps = roundf((value - sig->offset) / sig->scale);
    if (steps < (float)sig->raw_min) {
        *raw = sig->raw_min;
        return WC_CAN_SATURATED;
    }
    if (steps > (float)sig->raw_max) {
        *raw = sig->raw_max;
        return WC_CAN_SATURATED;
    }
    *raw = (int32_t)steps;
    return WC_CAN_OK;
}

wc_can_result_t wc_can_raw_to_phys(const wc_can_signal_t *sig, int32_t raw,
                                   float *value)
{
    if ((sig == NULL) || (value == NULL)) {
        return WC_CAN_ERR_SIZE;
    }
    if (sig->has_sna && (raw == sig->raw_sna)) {
        *value = NAN;
        return WC_CAN_ERR_SNA;
    }
    *value = ((float)raw * sig->scale) + sig->offset;
    if ((raw < sig->raw_min) || (raw > sig->raw_max)) {
        return WC_CAN_ERR_RANGE;
    }
    return WC_CAN_OK;
}

/* Converts one value and folds its result into *acc; returns the raw value. */
static int32_t to_raw(const wc_can_signal_t *sig, float value,
                      wc_can_result_t *acc)
{
    int32_t raw = 0;

    *acc = wc_can_worst(*acc, wc_can_phys_to_raw(sig, value, &raw));
    return raw;
}

static float to_phys(const wc_can_signal_t *sig, int32_t raw,
                     wc_can_result_t *acc)
{
    float value = 0.0f;

    *acc = wc_can_worst(*acc, wc_can_raw_to_phys(sig, raw, &value));
    return value;
}

static uint8_t counter_bits(uint8_t counter)
{
    return (uint8_t)(counter & WC_E2E_COUNTER_MASK);
}

static uint8_t status_bit(uint16_t status, unsigned bit)
{
    return (uint8_t)(((uint32_t)status >> bit) & 1u);
}

/* ---- ClutchSensors ------------------------------------------------------- */

wc_can_result_t wc_can_encode_clutch_sensors(uint8_t *dst,
    const wc_can_clutch_sensors_phys_t *src, size_t size)
{
    struct wc_can_clutch_sensors_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_CLUTCH_SENSORS_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_can_clutch_sensors_init(&msg);
    msg.slip_speed = (int16_t)to_raw(&wc_can_sig_clutch_sensors_slip_speed,
                                     src->slip_speed_rpm, &result);
    msg.oil_temp = (uint16_t)to_raw(&wc_can_sig_clutch_sensors_oil_temp,
                                    src->oil_temp_degC, &result);
    msg.housing_temp = (uint16_t)to_raw(&wc_can_sig_clutch_sensors_housing_temp,
                                        src->housing_temp_degC, &result);
    msg.alive_counter = counter_bits(src->alive_counter);
    msg.crc = 0u;
    if (wc_can_clutch_sensors_pack(dst, &msg, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_e2e_protect(WC_CAN_CLUTCH_SENSORS_FRAME_ID, dst, size);
    return result;
}

wc_can_result_t wc_can_decode_clutch_sensors(wc_can_clutch_sensors_phys_t *dst,
    const uint8_t *src, size_t size)
{
    struct wc_can_clutch_sensors_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_CLUTCH_SENSORS_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    if (wc_e2e_check_crc(WC_CAN_CLUTCH_SENSORS_FRAME_ID, src, size) != WC_E2E_OK) {
        return WC_CAN_ERR_CRC;
    }
    if (wc_can_clutch_sensors_unpack(&msg, src, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    dst->slip_speed_rpm = to_phys(&wc_can_sig_clutch_sensors_slip_speed,
                                  msg.slip_speed, &result);
    dst->oil_temp_degC = to_phys(&wc_can_sig_clutch_sensors_oil_temp,
                                 msg.oil_temp, &result);
    dst->housing_temp_degC = to_phys(&wc_can_sig_clutch_sensors_housing_temp,
                                     msg.housing_temp, &result);
    dst->alive_counter = msg.alive_counter;
    return result;
}

/* ---- TorqueRequest ------------------------------------------------------- */

wc_can_result_t wc_can_encode_torque_request(uint8_t *dst,
    const wc_can_torque_request_phys_t *src, size_t size)
{
    struct wc_can_torque_request_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_TORQUE_REQUEST_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_can_torque_request_init(&msg);
    msg.torque_request = (uint16_t)to_raw(&wc_can_sig_torque_request_torque_request,
                                          src->torque_request_Nm, &result);
    msg.mode = (uint8_t)(src->mode & 0x0Fu);
    if (src->mode > WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE) {
        result = wc_can_worst(result, WC_CAN_ERR_RANGE);
    }
    msg.alive_counter = counter_bits(src->alive_counter);
    msg.crc = 0u;
    if (wc_can_torque_request_pack(dst, &msg, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_e2e_protect(WC_CAN_TORQUE_REQUEST_FRAME_ID, dst, size);
    return result;
}

wc_can_result_t wc_can_decode_torque_request(wc_can_torque_request_phys_t *dst,
    const uint8_t *src, size_t size)
{
    struct wc_can_torque_request_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_TORQUE_REQUEST_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    if (wc_e2e_check_crc(WC_CAN_TORQUE_REQUEST_FRAME_ID, src, size) != WC_E2E_OK) {
        return WC_CAN_ERR_CRC;
    }
    if (wc_can_torque_request_unpack(&msg, src, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    dst->torque_request_Nm = to_phys(&wc_can_sig_torque_request_torque_request,
                                     msg.torque_request, &result);
    dst->mode = msg.mode;
    if (!wc_can_torque_request_mode_is_in_range(msg.mode)) {
        result = wc_can_worst(result, WC_CAN_ERR_RANGE);
    }
    dst->alive_counter = msg.alive_counter;
    return result;
}

/* ---- VfsCommand ---------------------------------------------------------- */

wc_can_result_t wc_can_encode_vfs_command(uint8_t *dst,
    const wc_can_vfs_command_phys_t *src, size_t size)
{
    struct wc_can_vfs_command_t msg;
    wc_can_result_t result = WC_CAN_OK;
    uint16_t status;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_VFS_COMMAND_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    status = src->status;
    (void)wc_can_vfs_command_init(&msg);
    msg.vfs_current = (uint16_t)to_raw(&wc_can_sig_vfs_command_vfs_current,
                                       src->vfs_current_mA, &result);
    msg.pressure_command = (uint16_t)to_raw(&wc_can_sig_vfs_command_pressure_command,
                                            src->pressure_command_kPa, &result);
    msg.status_sensor_timeout = status_bit(status, 0u);
    msg.status_request_timeout = status_bit(status, 1u);
    msg.status_crc_error = status_bit(status, 2u);
    msg.status_counter_error = status_bit(status, 3u);
    msg.status_implausible_input = status_bit(status, 4u);
    msg.status_saturated = status_bit(status, 5u);
    msg.status_current_clamped = status_bit(status, 6u);
    msg.status_below_drag = status_bit(status, 7u);
    msg.status_safe_state_active = status_bit(status, 8u);
    msg.status_deadline_miss = status_bit(status, 9u);
    msg.alive_counter = counter_bits(src->alive_counter);
    msg.crc = 0u;
    if (wc_can_vfs_command_pack(dst, &msg, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_e2e_protect(WC_CAN_VFS_COMMAND_FRAME_ID, dst, size);
    return result;
}

wc_can_result_t wc_can_decode_vfs_command(wc_can_vfs_command_phys_t *dst,
    const uint8_t *src, size_t size)
{
    struct wc_can_vfs_command_t msg;
    wc_can_result_t result = WC_CAN_OK;
    uint32_t status = 0u;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_VFS_COMMAND_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    if (wc_e2e_check_crc(WC_CAN_VFS_COMMAND_FRAME_ID, src, size) != WC_E2E_OK) {
        return WC_CAN_ERR_CRC;
    }
    if (wc_can_vfs_command_unpack(&msg, src, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    dst->vfs_current_mA = to_phys(&wc_can_sig_vfs_command_vfs_current,
                                  msg.vfs_current, &result);
    dst->pressure_command_kPa = to_phys(&wc_can_sig_vfs_command_pressure_command,
                                        msg.pressure_command, &result);
    status |= (uint32_t)(msg.status_sensor_timeout & 1u) << 0;
    status |= (uint32_t)(msg.status_request_timeout & 1u) << 1;
    status |= (uint32_t)(msg.status_crc_error & 1u) << 2;
    status |= (uint32_t)(msg.status_counter_error & 1u) << 3;
    status |= (uint32_t)(msg.status_implausible_input & 1u) << 4;
    status |= (uint32_t)(msg.status_saturated & 1u) << 5;
    status |= (uint32_t)(msg.status_current_clamped & 1u) << 6;
    status |= (uint32_t)(msg.status_below_drag & 1u) << 7;
    status |= (uint32_t)(msg.status_safe_state_active & 1u) << 8;
    status |= (uint32_t)(msg.status_deadline_miss & 1u) << 9;
    dst->status = (uint16_t)status;
    dst->alive_counter = msg.alive_counter;
    return result;
}

/* ---- ClutchEstimate (no E2E) --------------------------------------------- */

wc_can_result_t wc_can_encode_clutch_estimate(uint8_t *dst,
    const wc_can_clutch_estimate_phys_t *src, size_t size)
{
    struct wc_can_clutch_estimate_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_CLUTCH_ESTIMATE_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_can_clutch_estimate_init(&msg);
    msg.estimated_clutch_temp = (uint16_t)to_raw(
        &wc_can_sig_clutch_estimate_estimated_clutch_temp,
        src->estimated_clutch_temp_degC, &result);
    msg.model_torque = (int16_t)to_raw(&wc_can_sig_clutch_estimate_model_torque,
                                       src->model_torque_Nm, &result);
    msg.mu_f = (uint16_t)to_raw(&wc_can_sig_clutch_estimate_mu_f, src->mu_f, &result);
    msg.film_thickness = (uint16_t)to_raw(&wc_can_sig_clutch_estimate_film_thickness,
                                          src->film_thickness_um, &result);
    if (wc_can_clutch_estimate_pack(dst, &msg, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    return result;
}

wc_can_result_t wc_can_decode_clutch_estimate(wc_can_clutch_estimate_phys_t *dst,
    const uint8_t *src, size_t size)
{
    struct wc_can_clutch_estimate_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_CLUTCH_ESTIMATE_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    if (wc_can_clutch_estimate_unpack(&msg, src, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    dst->estimated_clutch_temp_degC = to_phys(
        &wc_can_sig_clutch_estimate_estimated_clutch_temp,
        msg.estimated_clutch_temp, &result);
    dst->model_torque_Nm = to_phys(&wc_can_sig_clutch_estimate_model_torque,
                                   msg.model_torque, &result);
    dst->mu_f = to_phys(&wc_can_sig_clutch_estimate_mu_f, msg.mu_f, &result);
    dst->film_thickness_um = to_phys(&wc_can_sig_clutch_estimate_film_thickness,
                                     msg.film_thickness, &result);
    return result;
}

/* ---- BenchMeasurement (no E2E) ------------------------------------------- */

wc_can_result_t wc_can_encode_bench_measurement(uint8_t *dst,
    const wc_can_bench_measurement_phys_t *src, size_t size)
{
    struct wc_can_bench_measurement_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_BENCH_MEASUREMENT_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    (void)wc_can_bench_measurement_init(&msg);
    msg.load_cell_force = to_raw(&wc_can_sig_bench_measurement_load_cell_force,
                                 src->load_cell_force_N, &result);
    msg.measured_torque = to_raw(&wc_can_sig_bench_measurement_measured_torque,
                                 src->measured_torque_Nm, &result);
    msg.clutch_thermistor_temp = (uint16_t)to_raw(
        &wc_can_sig_bench_measurement_clutch_thermistor_temp,
        src->clutch_thermistor_temp_degC, &result);
    if (wc_can_bench_measurement_pack(dst, &msg, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    return result;
}

wc_can_result_t wc_can_decode_bench_measurement(wc_can_bench_measurement_phys_t *dst,
    const uint8_t *src, size_t size)
{
    struct wc_can_bench_measurement_t msg;
    wc_can_result_t result = WC_CAN_OK;

    if ((dst == NULL) || (src == NULL) || (size < WC_CAN_BENCH_MEASUREMENT_LENGTH)) {
        return WC_CAN_ERR_SIZE;
    }
    if (wc_can_bench_measurement_unpack(&msg, src, size) < 0) {
        return WC_CAN_ERR_SIZE;
    }
    dst->load_cell_force_N = to_phys(&wc_can_sig_bench_measurement_load_cell_force,
                                     msg.load_cell_force, &result);
    dst->measured_torque_Nm = to_phys(&wc_can_sig_bench_measurement_measured_torque,
                                      msg.measured_torque, &result);
    dst->clutch_thermistor_temp_degC = to_phys(
        &wc_can_sig_bench_measurement_clutch_thermistor_temp,
        msg.clutch_thermistor_temp, &result);
    return result;
}
