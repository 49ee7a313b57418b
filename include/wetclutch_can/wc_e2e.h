/* End-to-end protection of the wet-clutch control frames (DESIGN.md section 4),
 * in the style of AUTOSAR E2E: a CRC-8 SAE J1850 and a 4-bit alive counter.
 *
 * Frame layout (fixed for every E2E frame of hil/wetclutch.dbc; the pytest
 * tests/python/test_dbc.py checks the DBC against these constants):
 *   byte 0        Crc
 *   byte 1 [3:0]  AliveCounter
 *   bytes 1..7    everything else
 *
 * CRC: CRC-8 SAE J1850 (polynomial 0x1D, initial value 0xFF, final XOR 0xFF,
 * not reflected; check value over "123456789" is 0x4B). The protected input
 * is the data id followed by the frame's bytes 1..7 (every byte except the
 * CRC byte), in that order:
 *     Crc = CRC8_J1850(data_id, byte1, byte2, ..., byte7)
 * The data id is the low byte of the 11-bit frame id (0x110 -> 0x10), so a
 * frame received under the wrong id fails the check. The low bytes of the
 * E2E frame ids are distinct (checked in the pytest).
 *
 * Alive counter: the sender increments it by 1 modulo 16 for every frame it
 * sends (wc_e2e_counter_next). The receiver (wc_e2e_counter_check), with
 * previous = the last counter it accepted or resynchronised to:
 *   - first frame (after wc_e2e_counter_init, e.g. at start or after an input
 *     timeout): accepted, becomes the reference        -> WC_E2E_COUNTER_INITIAL
 *   - counter == previous + 1 (mod 16): accepted        -> WC_E2E_COUNTER_OK
 *   - counter == previous: repeated frame (a stuck or re-sent frame): dropped,
 *     reference unchanged                               -> WC_E2E_COUNTER_REPEATED
 *   - anything else (frames lost or out of order): dropped, and the reference
 *     is resynchronised to the received counter, so the next consecutive
 *     frame is accepted again                           -> WC_E2E_COUNTER_WRONG_SEQUENCE
 * REPEATED and WRONG_SEQUENCE are both counter errors (the frame is dropped
 * and counted); the two codes only let the caller count them apart. A stuck
 * sender therefore never delivers fresh data and the input timeout fires.
 * One lost frame costs one more (the next frame is a jump and is dropped).
 *
 * Portable C99: no heap, no global mutable state, loops bounded by constants.
 */
#ifndef WC_E2E_H
#define WC_E2E_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Classic CAN frame length the E2E frames use (DLC 8). */
#define WC_E2E_FRAME_BYTES 8u
/** Index of the CRC byte in an E2E frame. */
#define WC_E2E_CRC_BYTE 0u
/** Index of the byte that holds the alive counter (low nibble). */
#define WC_E2E_COUNTER_BYTE 1u
/** Mask of the alive counter within WC_E2E_COUNTER_BYTE. */
#define WC_E2E_COUNTER_MASK 0x0Fu
/** The alive counter counts modulo this. */
#define WC_E2E_COUNTER_MODULO 16u
/** wc_e2e_crc8_j1850 processes at most this many bytes (CAN FD maximum). */
#define WC_E2E_CRC_MAX_BYTES 64u

/** CRC-8 SAE J1850 parameters. */
#define WC_E2E_CRC8_POLY 0x1Du
#define WC_E2E_CRC8_INIT 0xFFu
#define WC_E2E_CRC8_XOR_OUT 0xFFu

typedef enum {
    WC_E2E_OK = 0,
    WC_E2E_ERR_CRC = -1,  /**< CRC mismatch: drop the frame */
    WC_E2E_ERR_SIZE = -2  /**< NULL or shorter than WC_E2E_FRAME_BYTES */
} wc_e2e_result_t;

typedef enum {
    WC_E2E_COUNTER_OK = 0,             /**< previous + 1: use the frame */
    WC_E2E_COUNTER_INITIAL = 1,        /**< first frame since init: use the frame */
    WC_E2E_COUNTER_REPEATED = 2,       /**< same as previous: drop, count */
    WC_E2E_COUNTER_WRONG_SEQUENCE = 3  /**< jump: drop, count, resynchronise */
} wc_e2e_counter_result_t;

/** Receiver state of one alive counter (one per received E2E frame). */
typedef struct {
    uint8_t previous; /**< last accepted or resynchronised counter, 0..15 */
    bool synced;      /**< false until the first frame after init */
} wc_e2e_counter_state_t;

/** CRC-8 SAE J1850 of len bytes (init 0xFF, xor-out 0xFF). At most
 *  WC_E2E_CRC_MAX_BYTES bytes are processed; data may be NULL if len is 0. */
uint8_t wc_e2e_crc8_j1850(const uint8_t *data, size_t len);

/** The E2E CRC of a frame: over (frame_id & 0xFF) then every byte of the
 *  first WC_E2E_FRAME_BYTES except WC_E2E_CRC_BYTE. The CRC byte's current
 *  content does not matter. Returns WC_E2E_ERR_SIZE for NULL pointers or
 *  size < WC_E2E_FRAME_BYTES, else WC_E2E_OK and *crc. */
wc_e2e_result_t wc_e2e_frame_crc(uint32_t frame_id, const uint8_t *frame,
                                 size_t size, uint8_t *crc);

/** Writes the E2E CRC into frame[WC_E2E_CRC_BYTE]. */
wc_e2e_result_t wc_e2e_protect(uint32_t frame_id, uint8_t *frame, size_t size);

/** Checks frame[WC_E2E_CRC_BYTE]: WC_E2E_OK, WC_E2E_ERR_CRC or WC_E2E_ERR_SIZE. */
wc_e2e_result_t wc_e2e_check_crc(uint32_t frame_id, const uint8_t *frame,
                                 size_t size);

/** Resets a receiver: the next frame is accepted as the reference. */
void wc_e2e_counter_init(wc_e2e_counter_state_t *state);

/** Checks a received alive counter (only its low 4 bits are used) and
 *  updates the state as described at the top of this file. */
wc_e2e_counter_result_t wc_e2e_counter_check(wc_e2e_counter_state_t *state,
                                             uint8_t counter);

/** True if the result means "use the frame" (OK or INITIAL). */
bool wc_e2e_counter_accepted(wc_e2e_counter_result_t result);

/** Sender side: the counter to send after `counter` ((counter + 1) mod 16). */
uint8_t wc_e2e_counter_next(uint8_t counter);

#ifdef __cplusplus
}
#endif

#endif /* WC_E2E_H */
