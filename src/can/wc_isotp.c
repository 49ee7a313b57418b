/* ISO-TP server side (ISO 15765-2:2016; DESIGN 17): the contract is in
 * wc_isotp.h; the clauses cited below are those of the 2016 edition. */
#include "wetclutch_can/wc_isotp.h"

#include <string.h>

#include "wetclutch/wc_config.h"

#define CAN_DL 8u                      /* classical CAN, TX_DL = 8 (9.5.1) */
#define SF_DATA_MAX 7u                 /* SF_DL 1..7 with TX_DL 8 (9.6.2) */
#define FF_DATA 6u                     /* data bytes in a FF with a 12-bit FF_DL */
#define FF_ESCAPE_DATA 2u              /* ... with the 32-bit FF_DL escape (9.6.3) */
#define CF_DATA 7u
#define FF_DL_12BIT_MAX 4095u
#define STMIN_MAX_MS 0x7Fu             /* reserved STmin values read as this (9.6.5) */
#define ID_11BIT_MAX 0x7FFu
#define ID_29BIT_MAX 0x1FFFFFFFu

enum { RX_IDLE = 0, RX_WAIT_CF, RX_DONE };             /* reception */
enum { FC_NONE = 0, FC_CTS, FC_OVERFLOW };             /* our flow control to send */
enum { TX_IDLE = 0, TX_FIRST, TX_WAIT_FC, TX_CF };     /* transmission */

WC_STATIC_ASSERT((WC_ISOTP_RX_CAPACITY & (WC_ISOTP_RX_CAPACITY - 1u)) == 0u, isotp_rx_ring_is_a_power_of_two);
WC_STATIC_ASSERT(WC_ISOTP_MAX_FRAMES_PER_STEP >= 1u, isotp_at_least_one_frame_a_step);

static void copy_bytes(uint8_t *dst, const uint8_t *src, uint32_t length)
{
    for (uint32_t i = 0u; (i < length) && (i < CAN_DL); ++i) { dst[i] = src[i]; }
}

/* ceil(time_us / period_us), at least 1 for a nonzero time. */
static uint32_t steps_of(uint32_t time_us, uint32_t period_us)
{
    return (time_us / period_us) + (((time_us % period_us) != 0u) ? 1u : 0u);
}

/* STmin (9.6.5): 0x00-0x7F ms, 0xF1-0xF9 100-900 us, reserved values as 0x7F ms. */
static uint32_t st_min_us(uint8_t raw)
{
    if (raw <= STMIN_MAX_MS) { return (uint32_t)raw * 1000u; }
    if ((raw >= 0xF1u) && (raw <= 0xF9u)) { return ((uint32_t)raw - 0xF0u) * 100u; }
    return STMIN_MAX_MS * 1000u;
}

static bool id_valid(uint32_t id, bool extended) { return id <= (extended ? ID_29BIT_MAX : ID_11BIT_MAX); }

bool wc_isotp_init(wc_isotp_t *tp, const wc_isotp_config_t *config)
{
    WC_ASSERT((tp != NULL) && (config != NULL));
    if ((tp == NULL) || (config == NULL)) { return false; }
    memset(tp, 0, sizeof *tp);
    const wc_isotp_config_t *c = config;
    const bool valid = id_valid(c->rx_physical_id, c->extended_ids) && id_valid(c->rx_functional_id, c->extended_ids) &&
                       id_valid(c->tx_id, c->extended_ids) && (c->rx_physical_id != c->tx_id) &&
                       (c->rx_functional_id != c->tx_id) && (c->frames_per_step >= 1u) &&
                       (c->frames_per_step <= WC_ISOTP_MAX_FRAMES_PER_STEP) && (c->period_us >= 100u) &&
                       (c->period_us <= 1000000u) && (c->n_bs_ms >= 1u) && (c->n_bs_ms <= 60000u) &&
                       (c->n_cr_ms >= 1u) && (c->n_cr_ms <= 60000u);
    if (!valid) { return false; }
    tp->config = *c;
    tp->n_bs_steps = steps_of(c->n_bs_ms * 1000u, c->period_us);
    tp->n_cr_steps = steps_of(c->n_cr_ms * 1000u, c->period_us);
    tp->initialised = true;
    return true;
}

bool wc_isotp_receive(wc_isotp_t *tp, const wc_can_frame_t *frame)
{
    WC_ASSERT((tp != NULL) && (frame != NULL));
    if ((tp == NULL) || (frame == NULL)) { return false; }
    const uint32_t tail = tp->rx_tail;
    if ((tail - tp->rx_head) >= WC_ISOTP_RX_CAPACITY) {
        tp->counters.rx_overflows++;
        return false;
    }
    tp->rx[tail & (WC_ISOTP_RX_CAPACITY - 1u)] = *frame;
    WC_MEMORY_BARRIER();
    tp->rx_tail = tail + 1u;
    return true;
}

/* ------------------------------------------------------------ reception */

/* A new request (SF or FF) may start: not while a response is in flight or
 * a received request waits for its answer (half duplex, one request at a
 * time; wc_isotp.h). A reception in progress is aborted (9.8.3). */
static bool may_start_request(wc_isotp_t *tp)
{
    if ((tp->tx_state != TX_IDLE) || (tp->rx_state == RX_DONE)) {
        tp->counters.busy++;
        return false;
    }
    if (tp->rx_state == RX_WAIT_CF) {
        tp->counters.unexpected++;  /* N_UNEXP_PDU: the old reception ends, the new one starts */
        tp->rx_state = RX_IDLE;
        tp->rx_fc = FC_NONE;
    }
    return true;
}

static void on_single_frame(wc_isotp_t *tp, const wc_can_frame_t *f, bool functional)
{
    const uint32_t sf_dl = (uint32_t)f->data[0] & 0x0Fu;
    if ((sf_dl == 0u) || (sf_dl > SF_DATA_MAX) || (sf_dl + 1u > f->dlc)) {  /* 9.6.2: ignore */
        tp->counters.malformed++;
        return;
    }
    if (functional && (tp->rx_state == RX_WAIT_CF)) {  /* one request buffer: the physical reception goes on */
        tp->counters.busy++;
        return;
    }
    if (!may_start_request(tp)) { return; }
    copy_bytes(tp->rx_buffer, &f->data[1], sf_dl);
    tp->rx_length = sf_dl;
    tp->rx_offset = sf_dl;
    tp->rx_functional = functional;
    tp->rx_state = RX_DONE;
    tp->counters.requests++;
}

static void on_first_frame(wc_isotp_t *tp, const wc_can_frame_t *f)
{
    if (f->dlc < CAN_DL) {  /* a FF always fills the frame (9.6.3) */
        tp->counters.malformed++;
        return;
    }
    uint32_t ff_dl = (((uint32_t)f->data[0] & 0x0Fu) << 8) | (uint32_t)f->data[1];
    uint32_t data_at = 2u;
    if (ff_dl == 0u) {  /* the 32-bit escape: only for FF_DL > 4095 */
        ff_dl = ((uint32_t)f->data[2] << 24) | ((uint32_t)f->data[3] << 16) | ((uint32_t)f->data[4] << 8) |
                (uint32_t)f->data[5];
        data_at = 6u;
        if (ff_dl <= FF_DL_12BIT_MAX) {
            tp->counters.malformed++;
            return;
        }
    } else if (ff_dl <= SF_DATA_MAX) {  /* would have fitted a SF: ignore (9.6.3) */
        tp->counters.malformed++;
        return;
    }
    if (!may_start_request(tp)) { return; }
    if (ff_dl > WC_ISOTP_BUFFER_BYTES) {  /* FC Overflow, no reception (9.6.5) */
        tp->rx_fc = FC_OVERFLOW;
        return;
    }
    const uint32_t n = CAN_DL - data_at;
    copy_bytes(tp->rx_buffer, &f->data[data_at], n);
    tp->rx_length = ff_dl;
    tp->rx_offset = n;
    tp->rx_functional = false;
    tp->rx_sn = 1u;
    tp->rx_block = 0u;
    tp->rx_elapsed_steps = 0u;
    tp->rx_state = RX_WAIT_CF;
    tp->rx_fc = FC_CTS;
}

static void on_consecutive_frame(wc_isotp_t *tp, const wc_can_frame_t *f)
{
    if ((tp->rx_state != RX_WAIT_CF) || (tp->rx_fc != FC_NONE)) {  /* nobody waits for it (9.8.3) */
        tp->counters.unexpected++;
        return;
    }
    const uint32_t remaining = tp->rx_length - tp->rx_offset;
    const uint32_t n = (remaining < CF_DATA) ? remaining : CF_DATA;
    if ((uint32_t)f->dlc < n + 1u) {  /* shorter than the bytes it must carry: ignore */
        tp->counters.malformed++;
        return;
    }
    if (((uint32_t)f->data[0] & 0x0Fu) != tp->rx_sn) {  /* N_WRONG_SN: the reception ends (9.6.4) */
        tp->counters.wrong_sn++;
        tp->rx_state = RX_IDLE;
        return;
    }
    copy_bytes(&tp->rx_buffer[tp->rx_offset], &f->data[1], n);
    tp->rx_offset += n;
    tp->rx_sn = (uint8_t)((tp->rx_sn + 1u) & 0x0Fu);
    tp->rx_elapsed_steps = 0u;
    if (tp->rx_offset >= tp->rx_length) {
        tp->rx_state = RX_DONE;
        tp->counters.requests++;
        return;
    }
    tp->rx_block++;
    if ((tp->config.block_size != 0u) && (tp->rx_block >= tp->config.block_size)) {
        tp->rx_block = 0u;
        tp->rx_fc = FC_CTS;  /* the next block's FC; N_Cr starts again once it is sent */
    }
}

static void on_flow_control(wc_isotp_t *tp, const wc_can_frame_t *f)
{
    if (tp->tx_state != TX_WAIT_FC) {  /* 9.8.3: ignore */
        tp->counters.unexpected++;
        return;
    }
    if (f->dlc < 3u) {
        tp->counters.malformed++;
        return;
    }
    switch ((uint32_t)f->data[0] & 0x0Fu) {
    case WC_ISOTP_FS_CTS:
        tp->tx_block_size = f->data[1];
        tp->tx_st_steps = steps_of(st_min_us(f->data[2]), tp->config.period_us);
        tp->tx_st_wait_steps = 0u;  /* the first CF of a block may follow the FC at once */
        tp->tx_block = 0u;
        tp->tx_state = TX_CF;
        break;
    case WC_ISOTP_FS_WAIT:
        tp->counters.waits++;
        tp->tx_elapsed_steps = 0u;  /* N_Bs again (9.8.1) */
        break;
    default:  /* Overflow, or an invalid FS: the transmission ends (9.6.5) */
        tp->counters.tx_aborted++;
        tp->tx_state = TX_IDLE;
        break;
    }
}

static bool is_ours(const wc_isotp_t *tp, const wc_can_frame_t *f, uint32_t id)
{
    const uint32_t format = (uint32_t)f->flags & (WC_CAN_FLAG_EXTENDED | WC_CAN_FLAG_REMOTE | WC_CAN_FLAG_ERROR);
    const uint32_t expected = tp->config.extended_ids ? WC_CAN_FLAG_EXTENDED : 0u;
    return (f->id == id) && (format == expected);
}

static void on_frame(wc_isotp_t *tp, const wc_can_frame_t *f)
{
    tp->counters.frames_in++;
    const bool physical = is_ours(tp, f, tp->config.rx_physical_id);
    const bool functional = !physical && is_ours(tp, f, tp->config.rx_functional_id);
    if ((!physical && !functional) || (f->dlc == 0u) || (f->dlc > CAN_DL)) {
        tp->counters.ignored++;
        return;
    }
    const uint32_t type = (uint32_t)f->data[0] >> 4;
    if (functional && (type != WC_ISOTP_PCI_SF)) {  /* functional: single frames only (9.3) */
        tp->counters.ignored++;
        return;
    }
    switch (type) {
    case WC_ISOTP_PCI_SF: on_single_frame(tp, f, functional); break;
    case WC_ISOTP_PCI_FF: on_first_frame(tp, f); break;
    case WC_ISOTP_PCI_CF: on_consecutive_frame(tp, f); break;
    case WC_ISOTP_PCI_FC: on_flow_control(tp, f); break;
    default: tp->counters.malformed++; break;  /* unknown N_PCI type: ignore (9.8.3) */
    }
}

/* -------------------------------------------------------------- sending */

static wc_can_frame_t *new_frame(const wc_isotp_t *tp, wc_can_frame_t *f)
{
    f->id = tp->config.tx_id;
    f->dlc = (uint8_t)CAN_DL;
    f->flags = (uint8_t)(tp->config.extended_ids ? WC_CAN_FLAG_EXTENDED : 0u);
    memset(f->data, tp->config.padding, sizeof f->data);
    return f;
}

static void send_flow_control(wc_isotp_t *tp, wc_can_frame_t *f)
{
    (void)new_frame(tp, f);
    if (tp->rx_fc == FC_OVERFLOW) {
        f->data[0] = (uint8_t)((WC_ISOTP_PCI_FC << 4) | WC_ISOTP_FS_OVFLW);
        f->data[1] = 0u;
        f->data[2] = 0u;
        tp->counters.overflow_fcs++;
    } else {
        f->data[0] = (uint8_t)(WC_ISOTP_PCI_FC << 4);  /* FS 0: ContinueToSend */
        f->data[1] = tp->config.block_size;
        f->data[2] = tp->config.st_min;
        tp->rx_elapsed_steps = 0u;  /* N_Cr from here */
    }
    tp->rx_fc = FC_NONE;
}

static void response_sent(wc_isotp_t *tp)
{
    tp->tx_state = TX_IDLE;
    tp->counters.responses++;
}

/* The response's next frame into f, if one may go now; returns whether it did. */
static bool send_response_frame(wc_isotp_t *tp, wc_can_frame_t *f)
{
    if (tp->tx_state == TX_FIRST) {
        (void)new_frame(tp, f);
        if (tp->tx_length <= SF_DATA_MAX) {
            f->data[0] = (uint8_t)tp->tx_length;
            copy_bytes(&f->data[1], tp->tx_buffer, tp->tx_length);
            response_sent(tp);
        } else {
            f->data[0] = (uint8_t)((WC_ISOTP_PCI_FF << 4) | ((tp->tx_length >> 8) & 0x0Fu));
            f->data[1] = (uint8_t)(tp->tx_length & 0xFFu);
            copy_bytes(&f->data[2], tp->tx_buffer, FF_DATA);
            tp->tx_offset = FF_DATA;
            tp->tx_sn = 1u;
            tp->tx_elapsed_steps = 0u;
            tp->tx_state = TX_WAIT_FC;
        }
        return true;
    }
    if ((tp->tx_state != TX_CF) || (tp->tx_st_wait_steps > 0u)) { return false; }
    (void)new_frame(tp, f);
    const uint32_t remaining = tp->tx_length - tp->tx_offset;
    const uint32_t n = (remaining < CF_DATA) ? remaining : CF_DATA;
    f->data[0] = (uint8_t)((WC_ISOTP_PCI_CF << 4) | tp->tx_sn);
    copy_bytes(&f->data[1], &tp->tx_buffer[tp->tx_offset], n);
    tp->tx_offset += n;
    tp->tx_sn = (uint8_t)((tp->tx_sn + 1u) & 0x0Fu);
    tp->tx_st_wait_steps = tp->tx_st_steps;
    tp->tx_block++;
    if (tp->tx_offset >= tp->tx_length) {
        response_sent(tp);
    } else if ((tp->tx_block_size != 0u) && (tp->tx_block >= tp->tx_block_size)) {
        tp->tx_elapsed_steps = 0u;  /* N_Bs from the block's last CF */
        tp->tx_state = TX_WAIT_FC;
    }
    return true;
}

uint32_t wc_isotp_step(wc_isotp_t *tp, wc_can_frame_t *out, uint32_t capacity)
{
    WC_ASSERT((tp != NULL) && (out != NULL) && (tp->initialised));
    if ((tp == NULL) || (out == NULL) || !tp->initialised) { return 0u; }
    /* the frames queued since the last step, at most the ring's capacity */
    const uint32_t tail = tp->rx_tail;
    WC_MEMORY_BARRIER();
    for (uint32_t k = 0u; (k < WC_ISOTP_RX_CAPACITY) && (tp->rx_head != tail); ++k) {
        on_frame(tp, &tp->rx[tp->rx_head & (WC_ISOTP_RX_CAPACITY - 1u)]);
        WC_MEMORY_BARRIER();
        tp->rx_head = tp->rx_head + 1u;
    }
    /* timers: N_Cr while waiting for a CF after our FC, N_Bs while waiting for the tester's FC (9.8.1) */
    if ((tp->rx_state == RX_WAIT_CF) && (tp->rx_fc == FC_NONE)) {
        tp->rx_elapsed_steps++;
        if (tp->rx_elapsed_steps >= tp->n_cr_steps) {
            tp->counters.rx_timeouts++;
            tp->rx_state = RX_IDLE;
        }
    }
    if (tp->tx_state == TX_WAIT_FC) {
        tp->tx_elapsed_steps++;
        if (tp->tx_elapsed_steps >= tp->n_bs_steps) {
            tp->counters.tx_timeouts++;
            tp->tx_state = TX_IDLE;
        }
    }
    if (tp->tx_st_wait_steps > 0u) { tp->tx_st_wait_steps--; }
    /* the frames: our FC first, then the response */
    const uint32_t budget = (capacity < tp->config.frames_per_step) ? capacity : tp->config.frames_per_step;
    uint32_t n = 0u;
    if ((n < budget) && (tp->rx_fc != FC_NONE)) {
        send_flow_control(tp, &out[n]);
        n++;
    }
    for (uint32_t k = 0u; (k < WC_ISOTP_MAX_FRAMES_PER_STEP) && (n < budget); ++k) {
        if (!send_response_frame(tp, &out[n])) { break; }
        n++;
    }
    return n;
}

const uint8_t *wc_isotp_request(const wc_isotp_t *tp, uint32_t *length_bytes, bool *functional)
{
    WC_ASSERT((tp != NULL) && (length_bytes != NULL));
    if ((tp == NULL) || (length_bytes == NULL)) { return NULL; }
    *length_bytes = 0u;
    if (tp->rx_state != RX_DONE) { return NULL; }
    *length_bytes = tp->rx_length;
    if (functional != NULL) { *functional = tp->rx_functional; }
    return tp->rx_buffer;
}

uint8_t *wc_isotp_response_buffer(wc_isotp_t *tp)
{
    WC_ASSERT(tp != NULL);
    return (tp == NULL) ? NULL : tp->tx_buffer;
}

bool wc_isotp_respond(wc_isotp_t *tp, uint32_t length_bytes)
{
    WC_ASSERT(tp != NULL);
    if ((tp == NULL) || (tp->rx_state != RX_DONE) || (length_bytes > WC_ISOTP_BUFFER_BYTES)) { return false; }
    tp->rx_state = RX_IDLE;
    if (length_bytes > 0u) {
        tp->tx_length = length_bytes;
        tp->tx_offset = 0u;
        tp->tx_state = TX_FIRST;
    }
    return true;
}

bool wc_isotp_sending(const wc_isotp_t *tp)
{
    WC_ASSERT(tp != NULL);
    return (tp != NULL) && (tp->tx_state != TX_IDLE);
}
