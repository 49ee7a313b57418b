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
 * sends (wc_e2e_counter_next). The receiver (wc_e2e_receive) follows the
 * semantics of AUTOSAR E2E Profile 1 (DESIGN.md section 8), with
 * delta = (counter - previous) mod 16 and two parameters, MaxDeltaCounter
 * and SyncCounter (wc_e2e_config_t):
 *
 *   state    frame                               status          use   next state
 *   INIT     any (first frame after init)        INITIAL         yes   VALID
 *   NOSYNC   any (first frame after a timeout)   SYNC            no    SYNCING (reference = counter, 0 in sequence)
 *   SYNCING  delta 1, SyncCounter-th in a row    OK              yes   VALID
 *   SYNCING  delta 1, fewer so far               SYNC            no    SYNCING
 *   SYNCING  delta 0                             REPEATED        no    SYNCING
 *   SYNCING  other                               WRONGSEQUENCE   no    SYNCING (reference = counter, 0 in sequence)
 *   VALID    delta 1                             OK              yes   VALID
 *   VALID    2 <= delta <= MaxDeltaCounter,      OKSOMELOST      yes   VALID
 *            the previous used frame was OK
 *   VALID    delta 0                             REPEATED        no    VALID (reference unchanged)
 *   VALID    delta > MaxDeltaCounter, or a       WRONGSEQUENCE   no    SYNCING (reference = counter, 0 in sequence)
 *            second loss in a row
 *   (wc_e2e_receiver_init)                                             INIT
 *   (the input timed out: wc_e2e_receiver_restart)                     NOSYNC
 *
 * So a repeated counter is never new data; one lost frame costs one frame,
 * not two; and a sender whose counter is frozen, or follows any fixed
 * pattern other than +1 (+2 every frame: loss after loss), never gets its
 * data used again until it counts +1 for SyncCounter frames. Only the very
 * first frame after init is used without that proof: nothing unexpected has
 * happened yet (a sender frozen from the start is caught by its timeout).
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

/** What the receiver made of a frame's alive counter (AUTOSAR E2E Profile 1
 *  check status; WRONGCRC and NONEWDATA are the caller's: a frame that
 *  failed its CRC never reaches the receiver, a period without a frame is
 *  the input's timeout). */
typedef enum {
    WC_E2E_STATUS_OK = 0,             /**< delta 1: use the frame */
    WC_E2E_STATUS_OKSOMELOST = 1,     /**< 1 < delta <= MaxDeltaCounter: use the frame, frames were lost */
    WC_E2E_STATUS_INITIAL = 2,        /**< first frame after init: the reference, used */
    WC_E2E_STATUS_SYNC = 3,           /**< after a timeout or wrong sequence: the reference or an
                                           in-sequence frame, fewer than SyncCounter so far: not used */
    WC_E2E_STATUS_REPEATED = 4,       /**< delta 0: no new data */
    WC_E2E_STATUS_WRONGSEQUENCE = 5   /**< any other counter: not used, resynchronise */
} wc_e2e_status_t;

/** Receiver parameters (AUTOSAR E2E Profile 1 names). Any value is safe:
 *  max_delta_counter below 2 tolerates no lost frame, 15 or more every jump
 *  that is not a repeat; sync_counter 0 or 1 resumes on the first +1 frame. */
typedef struct {
    uint8_t max_delta_counter; /**< largest accepted delta (2: one lost frame) */
    uint8_t sync_counter;      /**< consecutive +1 frames needed after a timeout or WRONGSEQUENCE */
} wc_e2e_config_t;

/** Receiver state of one alive counter (one per received E2E frame). */
typedef struct {
    uint8_t previous;     /**< last counter used or resynchronised to, 0..15 */
    uint8_t state;        /**< INIT, NOSYNC, SYNCING or VALID (wc_e2e.c) */
    uint8_t in_sequence;  /**< consecutive +1 frames while SYNCING */
    bool lost_last;       /**< the last used frame was OKSOMELOST */
} wc_e2e_receiver_t;

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

/** Starts a receiver (INIT): its first frame is used. */
void wc_e2e_receiver_init(wc_e2e_receiver_t *rx);

/** Restarts a receiver after its input timed out (NOSYNC): its frames are
 *  used again after the reference frame and SyncCounter +1 frames. */
void wc_e2e_receiver_restart(wc_e2e_receiver_t *rx);

/** Checks a received alive counter (only its low 4 bits are used) and
 *  updates the state as in the table at the top of this file. A NULL
 *  pointer gives WRONGSEQUENCE. */
wc_e2e_status_t wc_e2e_receive(wc_e2e_receiver_t *rx, const wc_e2e_config_t *config, uint8_t counter);

/** True for the statuses whose frame carries data to use (OK, OKSOMELOST, INITIAL). */
bool wc_e2e_status_usable(wc_e2e_status_t status);

/** Sender side: the counter to send after `counter` ((counter + 1) mod 16). */
uint8_t wc_e2e_counter_next(uint8_t counter);

#ifdef __cplusplus
}
#endif

#endif /* WC_E2E_H */
