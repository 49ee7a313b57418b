/* Physical <-> raw conversion for the frames of hil/wetclutch.dbc, and
 * whole-frame encode/decode with E2E protection.
 *
 * Why this exists: the cantools-generated codec (generated/wc_can.[ch], made
 * with --no-floating-point-numbers) only packs and unpacks raw integers. Its
 * own floating-point encode (not generated here) truncates instead of
 * rounding (cantools issue 635), converts out-of-range values with undefined
 * behaviour, and goes through a `double` helper. This wrapper does the
 * scaling in single precision instead:
 *
 *   encode  raw = roundf((value - offset) / scale)   round to nearest, ties
 *                                                     away from zero
 *           raw limited to [raw_min, raw_max], the raw values of the DBC
 *           [minimum|maximum] (-> WC_CAN_SATURATED, frame still sent);
 *           NaN -> raw_nan (-> WC_CAN_ERR_NAN, frame still sent): the SNA
 *           value for signals that have one, 0 mA / 0 kPa for VfsCurrent /
 *           PressureCommand (no solenoid current); +-inf saturate.
 *   decode  value = raw * scale + offset
 *           raw == SNA            -> value NaN,        WC_CAN_ERR_SNA
 *           raw outside [min,max] -> value unclamped,  WC_CAN_ERR_RANGE
 *
 * Note: cantools in Python rounds with round() (ties to even); this code
 * rounds ties away from zero (as cantools' --use-round C code does). They can
 * differ by one raw step only for a value exactly half a step from two raw
 * values, which needs a binary scale (0.25 rpm, 1/32 mA, 1/16 kPa).
 *
 * The descriptor constants below restate the DBC's factor/offset/min/max;
 * tests/c/test_can_codec.c checks raw_min/raw_max against the generated
 * is_in_range functions and tests/python/test_dbc.py checks every signal's
 * conversion against cantools.
 *
 * Portable C99: no heap, no stdio, float only, no global mutable state.
 */
#ifndef WC_CAN_SCALING_H
#define WC_CAN_SCALING_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "generated/wc_can.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Result of a conversion, ordered by severity (a frame reports the worst
 *  of its signals). Values >= WC_CAN_ERR_NAN are errors. */
typedef enum {
    WC_CAN_OK = 0,
    WC_CAN_SATURATED = 1,  /**< encode: value limited to [min, max] */
    WC_CAN_ERR_NAN = 2,    /**< encode: NaN, the signal's raw_nan was sent */
    WC_CAN_ERR_RANGE = 3,  /**< decode: raw outside [min, max] (or reserved Mode) */
    WC_CAN_ERR_SNA = 4,    /**< decode: raw is "signal not available" */
    WC_CAN_ERR_CRC = 5,    /**< decode: E2E CRC mismatch, nothing decoded */
    WC_CAN_ERR_SIZE = 6    /**< NULL pointer or buffer shorter than 8 bytes */
} wc_can_result_t;

/** True for WC_CAN_ERR_*. */
bool wc_can_is_error(wc_can_result_t result);

/** The more severe of two results. */
wc_can_result_t wc_can_worst(wc_can_result_t a, wc_can_result_t b);

/** Scaling of one signal, as in the DBC: value = raw * scale + offset. */
typedef struct {
    float scale;     /**< DBC factor, physical unit per raw step */
    float offset;    /**< DBC offset, physical unit */
    int32_t raw_min; /**< raw value of the DBC minimum */
    int32_t raw_max; /**< raw value of the DBC maximum */
    int32_t raw_nan; /**< raw value the encoder sends for NaN */
    int32_t raw_sna; /**< reserved "signal not available" raw (if has_sna) */
    bool has_sna;
} wc_can_signal_t;

/* One descriptor per scaled signal (message_signal). */
extern const wc_can_signal_t wc_can_sig_clutch_sensors_slip_speed;        /* rpm  */
extern const wc_can_signal_t wc_can_sig_clutch_sensors_oil_temp;          /* degC */
extern const wc_can_signal_t wc_can_sig_clutch_sensors_housing_temp;      /* degC */
extern const wc_can_signal_t wc_can_sig_torque_request_torque_request;    /* Nm   */
extern const wc_can_signal_t wc_can_sig_vfs_command_vfs_current;          /* mA   */
extern const wc_can_signal_t wc_can_sig_vfs_command_pressure_command;     /* kPa  */
extern const wc_can_signal_t wc_can_sig_clutch_estimate_estimated_clutch_temp; /* degC */
extern const wc_can_signal_t wc_can_sig_clutch_estimate_model_torque;     /* Nm   */
extern const wc_can_signal_t wc_can_sig_clutch_estimate_mu_f;             /* 1    */
extern const wc_can_signal_t wc_can_sig_clutch_estimate_film_thickness;   /* um   */
extern const wc_can_signal_t wc_can_sig_bench_measurement_load_cell_force;     /* N    */
extern const wc_can_signal_t wc_can_sig_bench_measurement_measured_torque;     /* Nm   */
extern const wc_can_signal_t wc_can_sig_bench_measurement_clutch_thermistor_temp; /* degC */

/** Physical -> raw, as described at the top. *raw is always written
 *  (unless a pointer is NULL: WC_CAN_ERR_SIZE). */
wc_can_result_t wc_can_phys_to_raw(const wc_can_signal_t *sig, float value,
                                   int32_t *raw);

/** Raw -> physical, as described at the top. *value is always written. */
wc_can_result_t wc_can_raw_to_phys(const wc_can_signal_t *sig, int32_t raw,
                                   float *value);

/* VfsCommand status word: bit n is DBC signal frame bit 48 + n. */
#define WC_CAN_STATUS_SENSOR_TIMEOUT     (1u << 0)
#define WC_CAN_STATUS_REQUEST_TIMEOUT    (1u << 1)
#define WC_CAN_STATUS_CRC_ERROR          (1u << 2)
#define WC_CAN_STATUS_COUNTER_ERROR      (1u << 3)
#define WC_CAN_STATUS_IMPLAUSIBLE_INPUT  (1u << 4)
#define WC_CAN_STATUS_SATURATED          (1u << 5)
#define WC_CAN_STATUS_CURRENT_CLAMPED    (1u << 6)
#define WC_CAN_STATUS_BELOW_DRAG         (1u << 7)
#define WC_CAN_STATUS_SAFE_STATE_ACTIVE  (1u << 8)
#define WC_CAN_STATUS_DEADLINE_MISS      (1u << 9)
/** Bits 10..15 are reserved: ignored by the encoder, sent as 0. */
#define WC_CAN_STATUS_DEFINED_MASK       0x03FFu

/* Frames in physical units. The alive counter is sent as given (low 4 bits)
 * and returned as received; checking it is the caller's job (wc_e2e.h). */
typedef struct {
    float slip_speed_rpm;
    float oil_temp_degC;
    float housing_temp_degC;
    uint8_t alive_counter;
} wc_can_clutch_sensors_phys_t;

typedef struct {
    float torque_request_Nm;
    uint8_t mode; /**< WC_CAN_TORQUE_REQUEST_MODE_*_CHOICE (generated) */
    uint8_t alive_counter;
} wc_can_torque_request_phys_t;

typedef struct {
    float vfs_current_mA;
    float pressure_command_kPa;
    uint16_t status; /**< WC_CAN_STATUS_* bits */
    uint8_t alive_counter;
} wc_can_vfs_command_phys_t;

typedef struct {
    float estimated_clutch_temp_degC;
    float model_torque_Nm;
    float mu_f;
    float film_thickness_um; /**< h_bar in micrometres (hbar_m * 1e6) */
} wc_can_clutch_estimate_phys_t;

typedef struct {
    float load_cell_force_N;
    float measured_torque_Nm;
    float clutch_thermistor_temp_degC;
} wc_can_bench_measurement_phys_t;

/* Encode: converts every signal, packs dst[0..7] (unused bits 0) and, for
 * E2E frames, writes the CRC (wc_e2e.h; data id = low byte of the frame id).
 * Returns the worst signal result; the frame is complete and sendable unless
 * the result is WC_CAN_ERR_SIZE (dst NULL or size < 8: nothing written).
 * A mode above WC_CAN_TORQUE_REQUEST_MODE_LOCKED_CHOICE is sent as given
 * (low 4 bits) and reported as WC_CAN_ERR_RANGE. */
wc_can_result_t wc_can_encode_clutch_sensors(uint8_t *dst,
    const wc_can_clutch_sensors_phys_t *src, size_t size);
wc_can_result_t wc_can_encode_torque_request(uint8_t *dst,
    const wc_can_torque_request_phys_t *src, size_t size);
wc_can_result_t wc_can_encode_vfs_command(uint8_t *dst,
    const wc_can_vfs_command_phys_t *src, size_t size);
wc_can_result_t wc_can_encode_clutch_estimate(uint8_t *dst,
    const wc_can_clutch_estimate_phys_t *src, size_t size);
wc_can_result_t wc_can_encode_bench_measurement(uint8_t *dst,
    const wc_can_bench_measurement_phys_t *src, size_t size);

/* Decode: WC_CAN_ERR_SIZE (src shorter than 8 bytes) and WC_CAN_ERR_CRC
 * (E2E frames) leave *dst untouched; otherwise every field is written and
 * the worst signal result is returned (WC_CAN_ERR_SNA / WC_CAN_ERR_RANGE
 * mean: implausible input, do not use the frame). */
wc_can_result_t wc_can_decode_clutch_sensors(wc_can_clutch_sensors_phys_t *dst,
    const uint8_t *src, size_t size);
wc_can_result_t wc_can_decode_torque_request(wc_can_torque_request_phys_t *dst,
    const uint8_t *src, size_t size);
wc_can_result_t wc_can_decode_vfs_command(wc_can_vfs_command_phys_t *dst,
    const uint8_t *src, size_t size);
wc_can_result_t wc_can_decode_clutch_estimate(wc_can_clutch_estimate_phys_t *dst,
    const uint8_t *src, size_t size);
wc_can_result_t wc_can_decode_bench_measurement(wc_can_bench_measurement_phys_t *dst,
    const uint8_t *src, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* WC_CAN_SCALING_H */
