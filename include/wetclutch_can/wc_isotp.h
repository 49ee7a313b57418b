/* ISO-TP (ISO 15765-2, the transport layer of diagnostics on CAN; DESIGN 17):
 * the server side of one diagnostic connection, normal addressing, classical
 * CAN (TX_DL 8). Portable (no OS calls), no heap, every loop bounded by a
 * compile-time constant.
 *
 * Ids (wc_isotp_config_t; the integrator takes them from the DBC): one
 * physical request id (tester -> this ECU, every frame type), one functional
 * request id (tester -> every ECU: single frames only; a functional FF, CF
 * or FC is ignored: segmented messages are physical only, ISO
 * 15765-2:2016 9.3) and one response id (this ECU -> tester: responses and the
 * flow control frames of a request). Every frame sent has DLC 8, padded with
 * the configured byte (0xCC by default; ISO 15765-2:2016 9.5.2).
 *
 * Frame types (ISO 15765-2:2016 9.4, 9.6): N_PCI byte 0, high nibble
 *   0 SingleFrame      SF_DL (low nibble) 1..7, data after it;
 *   1 FirstFrame       FF_DL 12 bits (low nibble, byte 1) 8..4095, or 0 and
 *                      a 32-bit FF_DL in bytes 2..5 (escape, > 4095), data after;
 *   2 ConsecutiveFrame SN (low nibble) 1, 2, .. 15, 0, 1, .., 7 data bytes;
 *   3 FlowControl      FS (low nibble) 0 ContinueToSend, 1 Wait, 2 Overflow,
 *                      byte 1 BlockSize (0: no further FC), byte 2 STmin:
 *                      0x00-0x7F ms, 0xF1-0xF9 100-900 us, any other value
 *                      reserved, read as 0x7F (ISO 15765-2:2016 9.6.5).
 *
 * Reception of a request:
 *  - SF: the whole request. A SF with SF_DL 0, SF_DL > 7 or SF_DL > DLC - 1
 *    is ignored and counted malformed (9.6.2).
 *  - FF (physical only, DLC 8): FF_DL < 8, or an escape FF_DL <= 4095, is
 *    ignored (9.6.3); a message longer than WC_ISOTP_BUFFER_BYTES is
 *    answered by FC Overflow and not received (9.6.5); otherwise the FC
 *    ContinueToSend with the configured BS and STmin follows, again after
 *    every BS consecutive frames.
 *  - CF: the SN must be the next one, otherwise the reception is aborted
 *    (N_WRONG_SN, 9.6.4) and counted; a CF shorter than the bytes it must
 *    carry (7, or the rest in the last one) is ignored (malformed). N_Cr
 *    (the time from our FC or the last CF to the next CF, default 1000 ms,
 *    ISO 15765-2:2016 9.8.1) ends the reception (counted).
 *  - A frame that does not fit the state is handled as 9.8.3 says
 *    for a half-duplex entity: a SF or FF during a reception aborts it
 *    (N_UNEXP_PDU, counted unexpected) and starts a new one; a CF outside a
 *    reception and an FC outside a transmission are ignored (unexpected);
 *    an unknown N_PCI type is ignored (malformed). A new request (SF or FF)
 *    while a response is being sent, or while a received request waits for
 *    its answer, is ignored (counted busy): the server answers one request
 *    at a time, in order (ISO 14229-2 session layer; half duplex).
 *
 * Transmission of a response (wc_isotp_respond): a SF up to 7 bytes, or a
 * FF and CFs; the tester's FC decides the pace: ContinueToSend with BS (0:
 * the rest without further FC) and STmin, rounded up to whole control
 * periods (a CF goes out no earlier than ceil(STmin / period) steps after
 * the previous one); Wait restarts the N_Bs timer; Overflow or an invalid
 * FS ends the transmission (counted, 9.6.5); no FC within N_Bs (default
 * 1000 ms, 9.8.1) ends it too.
 *
 * Who calls what (the contract of wc_loop.h): wc_isotp_receive may run in
 * the CAN receive interrupt (single-producer/single-consumer ring; it
 * writes only rx_tail and counters.rx_overflows); everything else runs in
 * the control task, never concurrently with itself: wc_isotp_step right
 * after wc_loop_step, once the port has handed the step's control frames
 * (VfsCommand first) to its transmit queue, so that diagnostics never delay
 * or displace a control frame; wc_isotp_init before the interrupt is
 * enabled.
 *
 * Cost of one wc_isotp_step, at most: the frames queued since the last step
 * (WC_ISOTP_RX_CAPACITY, each at most one 7-byte copy), two timer updates,
 * and frames_per_step frames built (at most WC_ISOTP_MAX_FRAMES_PER_STEP;
 * default 1: one diagnostic frame beside a control step). */
#ifndef WC_ISOTP_H
#define WC_ISOTP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wc_can_frame.h"

/* The longest request and the longest response, bytes (one buffer each).
 * A build may raise it up to 4095 (the 12-bit FF_DL). */
#ifndef WC_ISOTP_BUFFER_BYTES
#define WC_ISOTP_BUFFER_BYTES 256u
#endif
#if (WC_ISOTP_BUFFER_BYTES < 8u) || (WC_ISOTP_BUFFER_BYTES > 4095u)
#error "WC_ISOTP_BUFFER_BYTES must be in [8, 4095] (ISO 15765-2 FF_DL without the escape)"
#endif
#define WC_ISOTP_RX_CAPACITY 16u          /* frames buffered between two steps (power of two) */
#define WC_ISOTP_MAX_FRAMES_PER_STEP 8u   /* the ceiling of wc_isotp_config_t.frames_per_step */

/* N_PCI types and flow status values (ISO 15765-2:2016 9.6.1, 9.6.5). */
enum {
    WC_ISOTP_PCI_SF = 0x0, WC_ISOTP_PCI_FF = 0x1, WC_ISOTP_PCI_CF = 0x2, WC_ISOTP_PCI_FC = 0x3,
    WC_ISOTP_FS_CTS = 0x0, WC_ISOTP_FS_WAIT = 0x1, WC_ISOTP_FS_OVFLW = 0x2
};

typedef struct {
    uint32_t rx_physical_id;     /* requests to this ECU */
    uint32_t rx_functional_id;   /* requests to every ECU (single frames only) */
    uint32_t tx_id;              /* responses and flow control */
    bool extended_ids;           /* the three ids are 29-bit (frames with WC_CAN_FLAG_EXTENDED) */
    uint8_t block_size;          /* BS of our FC: CFs between two FCs, 0 = no further FC */
    uint8_t st_min;              /* STmin of our FC, the raw byte (0x00-0x7F ms, 0xF1-0xF9 100-900 us) */
    uint8_t padding;             /* the byte after the data in every frame sent */
    uint32_t frames_per_step;    /* frames sent per step at most, 1..WC_ISOTP_MAX_FRAMES_PER_STEP */
    uint32_t period_us;          /* the control period: one step */
    uint32_t n_bs_ms;            /* N_Bs: our FF or last CF of a block -> the tester's FC */
    uint32_t n_cr_ms;            /* N_Cr: our FC or the last CF -> the tester's next CF */
} wc_isotp_config_t;

/* OBD-style default ids (0x7E0 / 0x7DF / 0x7E8); the integrator's come from the DBC.
 * Our FC: BS 0, STmin 1 ms (the tester sends at most one CF a control period). */
#define WC_ISOTP_CONFIG_DEFAULT { 0x7E0u, 0x7DFu, 0x7E8u, false, 0u, 0x01u, 0xCCu, 1u, 1000u, 1000u, 1000u }

typedef struct {
    uint32_t frames_in;          /* frames taken from the ring */
    uint32_t ignored;            /* not ours: other id, remote/error/id-format flags, functional FF/CF/FC */
    uint32_t malformed;          /* unknown N_PCI, bad SF_DL/FF_DL, short FF/CF/FC (ignored) */
    uint32_t unexpected;         /* CF or FC outside its state (ignored); reception interrupted by SF/FF */
    uint32_t busy;               /* SF/FF ignored: a response in flight or a request waiting for its answer */
    uint32_t wrong_sn;           /* receptions aborted: CF out of sequence */
    uint32_t rx_timeouts;        /* receptions aborted: N_Cr */
    uint32_t tx_timeouts;        /* transmissions aborted: N_Bs */
    uint32_t rx_overflows;       /* frames lost before the step: ring full */
    uint32_t overflow_fcs;       /* FC Overflow sent: a request longer than WC_ISOTP_BUFFER_BYTES */
    uint32_t tx_aborted;         /* transmissions ended by the tester: FC Overflow or an invalid FS */
    uint32_t waits;              /* FC Wait received */
    uint32_t requests;           /* complete requests */
    uint32_t responses;          /* responses completely sent */
} wc_isotp_counters_t;

typedef struct {
    wc_isotp_config_t config;
    uint32_t n_bs_steps;         /* the timeouts in steps (rounded up) */
    uint32_t n_cr_steps;
    /* receive ring (wc_isotp_receive -> wc_isotp_step) */
    wc_can_frame_t rx[WC_ISOTP_RX_CAPACITY];
    volatile uint32_t rx_head;   /* written only by wc_isotp_step */
    volatile uint32_t rx_tail;   /* written only by wc_isotp_receive */
    /* reception */
    uint8_t rx_state;            /* wc_isotp.c */
    uint8_t rx_fc;               /* FC to send: 0 none, 1 ContinueToSend, 2 Overflow */
    uint8_t rx_sn;               /* the SN the next CF must carry */
    bool rx_functional;          /* the request came on the functional id */
    uint32_t rx_length;          /* bytes of the request (FF_DL or SF_DL) */
    uint32_t rx_offset;          /* bytes received */
    uint32_t rx_block;           /* CFs received since our last FC */
    uint32_t rx_elapsed_steps;   /* since our FC or the last CF (N_Cr) */
    uint8_t rx_buffer[WC_ISOTP_BUFFER_BYTES];
    /* transmission */
    uint8_t tx_state;            /* wc_isotp.c */
    uint8_t tx_sn;               /* the SN of the next CF */
    uint8_t tx_block_size;       /* the tester's BS */
    uint32_t tx_st_steps;        /* the tester's STmin in steps (rounded up) */
    uint32_t tx_st_wait_steps;   /* steps before the next CF may go */
    uint32_t tx_length;
    uint32_t tx_offset;          /* bytes sent */
    uint32_t tx_block;           /* CFs sent since the tester's last FC */
    uint32_t tx_elapsed_steps;   /* since our FF, the block's last CF or a Wait (N_Bs) */
    uint8_t tx_buffer[WC_ISOTP_BUFFER_BYTES];
    wc_isotp_counters_t counters;
    bool initialised;
} wc_isotp_t;

/* Idle, from config (copied). Returns false (unusable: every later call
 * asserts) on a NULL argument or a configuration out of range: ids beyond
 * 11 (or 29) bits or the request ids equal to tx_id, frames_per_step
 * outside 1..WC_ISOTP_MAX_FRAMES_PER_STEP, period_us outside 100..1000000,
 * a timeout outside 1..60000 ms. */
bool wc_isotp_init(wc_isotp_t *tp, const wc_isotp_config_t *config);

/* Queue one received frame (any id: the step ignores and counts the frames
 * that are not ours). Returns false, counting rx_overflows, when the ring is
 * full. ISR-safe (see above). */
bool wc_isotp_receive(wc_isotp_t *tp, const wc_can_frame_t *frame);

/* One control step: handles the queued frames, the N_Cr / N_Bs timers, and
 * writes at most min(capacity, frames_per_step) frames to send to out (a
 * pending FC first, then the response's next frames); returns their count. */
uint32_t wc_isotp_step(wc_isotp_t *tp, wc_can_frame_t *out, uint32_t capacity);

/* The complete request that waits for its answer: its bytes (valid until
 * wc_isotp_respond), *length_bytes and *functional set; NULL when there is
 * none (then *length_bytes is 0). functional may be NULL. */
const uint8_t *wc_isotp_request(const wc_isotp_t *tp, uint32_t *length_bytes, bool *functional);

/* Where the answer to the waiting request is written (WC_ISOTP_BUFFER_BYTES
 * bytes) before wc_isotp_respond. */
uint8_t *wc_isotp_response_buffer(wc_isotp_t *tp);

/* Answers the waiting request with the first length_bytes of the response
 * buffer (0: no response, e.g. a suppressed one) and releases the request;
 * the frames go out from the next wc_isotp_step. Returns false (nothing
 * changes) when no request waits or length_bytes > WC_ISOTP_BUFFER_BYTES. */
bool wc_isotp_respond(wc_isotp_t *tp, uint32_t length_bytes);

/* True while a response is being sent (its last frame not yet out and not
 * aborted). */
bool wc_isotp_sending(const wc_isotp_t *tp);

#endif /* WC_ISOTP_H */
