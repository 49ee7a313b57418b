/* ISO-TP server side (include/wetclutch_can/wc_isotp.h, src/can/wc_isotp.c;
 * ISO 15765-2:2016), frame by frame:
 *  - every frame type: SF requests (physical and functional), FF + CF
 *    requests with our FC (BS, STmin), SF and FF + CF responses paced by
 *    the tester's FC (BS, STmin rounded up to control periods, reserved
 *    STmin as 127 ms, WAIT, OVFLW, invalid FS), SN wrap-around, padding;
 *  - every error path: FC OVFLW for a request longer than the buffer, a
 *    wrong SN, N_Cr and N_Bs timeouts (exactly at 1000 steps), malformed
 *    frames (SF_DL 0 / > 7 / beyond the DLC, short FF, FF_DL < 8, escape
 *    FF_DL <= 4095, unknown N_PCI, short CF and FC), unexpected CF/FC, a
 *    SF that interrupts a reception, functional FF/CF/FC ignored, requests
 *    while a response is in flight (busy), foreign ids and frame formats,
 *    ring overflow, the frame budget per step, configurations refused. */
#include "wc_test_support.h"

#include "wetclutch_can/wc_isotp.h"

#define PHYS 0x7E0u
#define FUNC 0x7DFu
#define RESP 0x7E8u
#define PAD 0xCCu

static wc_isotp_t tp;
static wc_can_frame_t out[WC_ISOTP_MAX_FRAMES_PER_STEP];
static uint32_t n_out;

static void init_with(uint8_t block_size, uint8_t st_min, uint32_t frames_per_step)
{
    wc_isotp_config_t config = WC_ISOTP_CONFIG_DEFAULT;
    config.block_size = block_size;
    config.st_min = st_min;
    config.frames_per_step = frames_per_step;
    assert_true(wc_isotp_init(&tp, &config));
}

static int setup(void **state)
{
    (void)state;
    init_with(0u, 0x01u, 1u);
    return 0;
}

#define BYTES(...) ((const uint8_t[]){ __VA_ARGS__ })
#define RX(id, ...) rx_frame((id), BYTES(__VA_ARGS__), (uint32_t)sizeof(BYTES(__VA_ARGS__)))

static void rx_frame(uint32_t id, const uint8_t *bytes, uint32_t dlc)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = (uint8_t)dlc;
    for (uint32_t i = 0u; (i < dlc) && (i < 8u); ++i) { f.data[i] = bytes[i]; }
    assert_true(wc_isotp_receive(&tp, &f));
}

/* One step; every frame sent goes on the response id with DLC 8 and no flags. */
static uint32_t step(void)
{
    memset(out, 0xA5, sizeof out);
    n_out = wc_isotp_step(&tp, out, WC_ISOTP_MAX_FRAMES_PER_STEP);
    for (uint32_t i = 0u; i < n_out; ++i) {
        assert_int_equal(out[i].id, RESP);
        assert_int_equal(out[i].dlc, 8u);
        assert_int_equal(out[i].flags, 0u);
    }
    return n_out;
}

static void steps_without_frames(uint32_t count)
{
    for (uint32_t k = 0u; k < count; ++k) { assert_int_equal(step(), 0u); }
}

static void expect_frame(const wc_can_frame_t *f, const uint8_t want[8], int line)
{
    if (memcmp(f->data, want, 8u) != 0) {
        print_error("line %d: got %02x %02x %02x %02x %02x %02x %02x %02x\n", line, f->data[0], f->data[1], f->data[2],
                    f->data[3], f->data[4], f->data[5], f->data[6], f->data[7]);
        fail();
    }
}
#define EXPECT(f, ...) expect_frame((f), BYTES(__VA_ARGS__), __LINE__)

/* The waiting request: exactly these bytes. */
static void expect_request(const uint8_t *want, uint32_t length, bool functional)
{
    uint32_t got_length = 99u;
    bool got_functional = !functional;
    const uint8_t *req = wc_isotp_request(&tp, &got_length, &got_functional);
    assert_non_null(req);
    assert_int_equal(got_length, length);
    assert_int_equal(got_functional, functional);
    assert_memory_equal(req, want, length);
}

static void expect_no_request(void)
{
    uint32_t length = 99u;
    assert_null(wc_isotp_request(&tp, &length, NULL));
    assert_int_equal(length, 0u);
}

static void respond(const uint8_t *bytes, uint32_t length)
{
    uint8_t *buffer = wc_isotp_response_buffer(&tp);
    for (uint32_t i = 0u; i < length; ++i) { buffer[i] = bytes[i]; }
    assert_true(wc_isotp_respond(&tp, length));
}

static uint8_t pattern(uint32_t i) { return (uint8_t)(i * 7u + 3u); }

/* ======================================================================== */

static void test_single_frames(void **state)
{
    (void)state;
    RX(PHYS, 0x02, 0x10, 0x03);  /* DLC 3: a SF needs no padding from the tester */
    steps_without_frames(1u);
    expect_request(BYTES(0x10, 0x03), 2u, false);
    /* one request at a time: a second SF waits for nothing, it is ignored */
    RX(PHYS, 0x02, 0x3E, 0x00, PAD, PAD, PAD, PAD, PAD);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.busy, 1u);
    expect_request(BYTES(0x10, 0x03), 2u, false);
    respond(BYTES(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4), 6u);
    expect_no_request();
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x06, 0x50, 0x03, 0x00, 0x32, 0x01, 0xF4, PAD);
    assert_false(wc_isotp_sending(&tp));
    /* functional SF (7 bytes, the most a SF holds) */
    RX(FUNC, 0x07, 1, 2, 3, 4, 5, 6, 7);
    steps_without_frames(1u);
    expect_request(BYTES(1, 2, 3, 4, 5, 6, 7), 7u, true);
    assert_true(wc_isotp_respond(&tp, 0u));  /* no response */
    steps_without_frames(3u);
    assert_int_equal(tp.counters.requests, 2u);
    assert_int_equal(tp.counters.responses, 1u);
    assert_false(wc_isotp_respond(&tp, 1u));  /* nothing waits */
}

static void test_segmented_request(void **state)
{
    (void)state;
    init_with(2u, 0x05u, 1u);  /* our FC: BS 2, STmin 5 ms */
    uint8_t msg[20];
    for (uint32_t i = 0u; i < 20u; ++i) { msg[i] = pattern(i); }
    RX(PHYS, 0x10, 20, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]);
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x30, 2, 5, PAD, PAD, PAD, PAD, PAD);
    RX(PHYS, 0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]);
    RX(PHYS, 0x22, msg[13], msg[14], msg[15], msg[16], msg[17], msg[18], msg[19]);
    assert_int_equal(step(), 0u);  /* the last CF ends the message: no FC after it */
    expect_request(msg, 20u, false);

    /* 30 bytes: FF + 4 CFs, an FC after every 2 */
    assert_true(wc_isotp_respond(&tp, 0u));
    uint8_t big[30];
    for (uint32_t i = 0u; i < 30u; ++i) { big[i] = pattern(i + 40u); }
    RX(PHYS, 0x10, 30, big[0], big[1], big[2], big[3], big[4], big[5]);
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x30, 2, 5, PAD, PAD, PAD, PAD, PAD);
    RX(PHYS, 0x21, big[6], big[7], big[8], big[9], big[10], big[11], big[12]);
    RX(PHYS, 0x22, big[13], big[14], big[15], big[16], big[17], big[18], big[19]);
    RX(PHYS, 0x23, big[20], big[21], big[22], big[23], big[24], big[25], big[26]);  /* before our FC: ignored */
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x30, 2, 5, PAD, PAD, PAD, PAD, PAD);
    assert_int_equal(tp.counters.unexpected, 1u);
    expect_no_request();
    RX(PHYS, 0x23, big[20], big[21], big[22], big[23], big[24], big[25], big[26]);
    RX(PHYS, 0x24, big[27], big[28], big[29]);  /* the last CF may be short: DLC 4 carries its 3 bytes */
    assert_int_equal(step(), 0u);
    expect_request(big, 30u, false);
}

static void test_request_longer_than_the_buffer(void **state)
{
    (void)state;
    const uint32_t length = WC_ISOTP_BUFFER_BYTES + 1u;
    RX(PHYS, (uint8_t)(0x10u | (length >> 8)), (uint8_t)(length & 0xFFu), 1, 2, 3, 4, 5, 6);
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x32, 0, 0, PAD, PAD, PAD, PAD, PAD);  /* FC Overflow */
    assert_int_equal(tp.counters.overflow_fcs, 1u);
    RX(PHYS, 0x21, 1, 2, 3, 4, 5, 6, 7);  /* the tester ignores it: no reception to continue */
    steps_without_frames(1u);
    expect_no_request();
    assert_int_equal(tp.counters.unexpected, 1u);
    /* the escape FF (FF_DL 0, 32-bit length 5000) too */
    RX(PHYS, 0x10, 0x00, 0x00, 0x00, 0x13, 0x88, 9, 9);
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x32, 0, 0, PAD, PAD, PAD, PAD, PAD);
    /* exactly the buffer fits */
    const uint32_t fits = WC_ISOTP_BUFFER_BYTES;
    RX(PHYS, (uint8_t)(0x10u | (fits >> 8)), (uint8_t)(fits & 0xFFu), 1, 2, 3, 4, 5, 6);
    assert_int_equal(step(), 1u);
    assert_int_equal(out[0].data[0], 0x30u);
}

static void test_wrong_sequence_number(void **state)
{
    (void)state;
    RX(PHYS, 0x10, 20, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x22, 6, 7, 8, 9, 10, 11, 12);  /* SN 2 where 1 is due */
    RX(PHYS, 0x21, 6, 7, 8, 9, 10, 11, 12);  /* the reception has ended: nobody waits */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.wrong_sn, 1u);
    assert_int_equal(tp.counters.unexpected, 1u);
    expect_no_request();
}

static void test_n_cr_timeout(void **state)
{
    (void)state;
    RX(PHYS, 0x10, 20, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);  /* our FC: N_Cr starts */
    steps_without_frames(999u);
    assert_int_equal(tp.counters.rx_timeouts, 0u);
    RX(PHYS, 0x21, 6, 7, 8, 9, 10, 11, 12);  /* in time (999 ms): restarts N_Cr */
    steps_without_frames(999u);
    assert_int_equal(tp.counters.rx_timeouts, 0u);
    steps_without_frames(1u);  /* 1000 ms without the next CF */
    assert_int_equal(tp.counters.rx_timeouts, 1u);
    RX(PHYS, 0x22, 13, 14, 15, 16, 17, 18, 19);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.unexpected, 1u);
    expect_no_request();
}

static void test_malformed_frames_ignored(void **state)
{
    (void)state;
    RX(PHYS, 0x00, 1, 2, 3, 4, 5, 6, 7);        /* SF_DL 0 */
    RX(PHYS, 0x08, 1, 2, 3, 4, 5, 6, 7);        /* SF_DL 8 */
    RX(PHYS, 0x05, 1, 2, 3);                    /* SF_DL 5 in DLC 4 */
    RX(PHYS, 0x10, 20, 1, 2, 3, 4, 5);          /* FF of DLC 7 */
    RX(PHYS, 0x10, 5, 1, 2, 3, 4, 5, 6);        /* FF_DL 5 < 8 */
    RX(PHYS, 0x10, 0x00, 0, 0, 0x0F, 0xFF, 1, 2);  /* escape with FF_DL 4095 */
    RX(PHYS, 0x40, 1, 2, 3, 4, 5, 6, 7);        /* N_PCI 4 */
    RX(PHYS, 0xF1, 1, 2, 3, 4, 5, 6, 7);        /* N_PCI 15 */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.malformed, 8u);
    expect_no_request();
    /* a short CF in a reception, a short FC in a transmission */
    RX(PHYS, 0x10, 20, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x21, 6, 7, 8, 9, 10, 11);         /* 6 bytes where 7 are due */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.malformed, 9u);
    RX(PHYS, 0x21, 6, 7, 8, 9, 10, 11, 12);     /* the reception goes on */
    RX(PHYS, 0x22, 13, 14, 15, 16, 17, 18, 19);
    steps_without_frames(1u);
    uint32_t length = 0u;
    assert_non_null(wc_isotp_request(&tp, &length, NULL));
    uint8_t answer[10] = { 0 };
    respond(answer, 10u);
    assert_int_equal(step(), 1u);  /* FF */
    RX(PHYS, 0x30, 0);                          /* FC of DLC 2 */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.malformed, 10u);
    assert_true(wc_isotp_sending(&tp));
    /* an empty frame */
    wc_can_frame_t empty;
    memset(&empty, 0, sizeof empty);
    empty.id = PHYS;
    assert_true(wc_isotp_receive(&tp, &empty));
    steps_without_frames(1u);
    assert_int_equal(tp.counters.ignored, 1u);
}

static void test_functional_segmented_frames_ignored(void **state)
{
    (void)state;
    RX(FUNC, 0x10, 20, 0, 1, 2, 3, 4, 5);  /* no FC for a functional FF */
    RX(FUNC, 0x21, 6, 7, 8, 9, 10, 11, 12);
    RX(FUNC, 0x30, 0, 0);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.ignored, 3u);
    expect_no_request();
    /* a functional SF during a physical reception: one buffer, the reception goes on */
    RX(PHYS, 0x10, 8, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);
    RX(FUNC, 0x02, 0x3E, 0x80);
    RX(PHYS, 0x21, 6, 7);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.busy, 1u);
    expect_request(BYTES(0, 1, 2, 3, 4, 5, 6, 7), 8u, false);
}

static void test_unexpected_frames(void **state)
{
    (void)state;
    RX(PHYS, 0x21, 1, 2, 3, 4, 5, 6, 7);  /* CF, nothing received */
    RX(PHYS, 0x30, 0, 0);                 /* FC, nothing sent */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.unexpected, 2u);
    /* a SF during a reception ends it and is the new request (9.8.3) */
    RX(PHYS, 0x10, 20, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x02, 0x22, 0xF1);
    RX(PHYS, 0x21, 6, 7, 8, 9, 10, 11, 12);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.unexpected, 4u);  /* the interrupted reception and the orphan CF */
    expect_request(BYTES(0x22, 0xF1), 2u, false);
    /* a FF during a reception restarts it */
    assert_true(wc_isotp_respond(&tp, 0u));
    RX(PHYS, 0x10, 20, 0, 1, 2, 3, 4, 5);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x10, 9, 9, 8, 7, 6, 5, 4);
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x30, 0, 1, PAD, PAD, PAD, PAD, PAD);
    RX(PHYS, 0x21, 3, 2, 3, 4, 5, 6, 7);
    steps_without_frames(1u);
    expect_request(BYTES(9, 8, 7, 6, 5, 4, 3, 2, 3), 9u, false);
}

/* A response of `length` pattern bytes is queued for the next step. */
static void queue_response(uint32_t length)
{
    RX(PHYS, 0x01, 0x3E);
    steps_without_frames(1u);
    uint8_t *buffer = wc_isotp_response_buffer(&tp);
    for (uint32_t i = 0u; i < length; ++i) { buffer[i] = pattern(i); }
    assert_true(wc_isotp_respond(&tp, length));
}

static void expect_cf(const wc_can_frame_t *f, uint32_t sn, uint32_t offset, uint32_t length)
{
    assert_int_equal(f->data[0], 0x20u | sn);
    for (uint32_t i = 0u; i < 7u; ++i) {
        assert_int_equal(f->data[1u + i], (offset + i < length) ? pattern(offset + i) : PAD);
    }
}

static void test_segmented_response_paced_by_the_tester(void **state)
{
    (void)state;
    queue_response(27u);  /* FF 6 + CFs 7, 7, 7 */
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x10, 27, pattern(0), pattern(1), pattern(2), pattern(3), pattern(4), pattern(5));
    steps_without_frames(5u);  /* waits for the FC */
    RX(PHYS, 0x30, 2, 3);       /* CTS, BS 2, STmin 3 ms */
    assert_int_equal(step(), 1u);  /* the block's first CF follows the FC at once */
    expect_cf(&out[0], 1u, 6u, 27u);
    steps_without_frames(2u);      /* STmin 3 ms: two steps without */
    assert_int_equal(step(), 1u);
    expect_cf(&out[0], 2u, 13u, 27u);
    steps_without_frames(10u);     /* the block is done: an FC is due */
    RX(PHYS, 0x31, 0, 0);          /* WAIT: N_Bs starts again */
    steps_without_frames(999u);
    assert_int_equal(tp.counters.waits, 1u);
    assert_int_equal(tp.counters.tx_timeouts, 0u);
    RX(PHYS, 0x30, 0, 0xF5);       /* CTS, BS 0, STmin 500 us -> one step */
    assert_int_equal(step(), 1u);
    expect_cf(&out[0], 3u, 20u, 27u);
    assert_false(wc_isotp_sending(&tp));
    assert_int_equal(tp.counters.responses, 1u);
    steps_without_frames(2u);
}

static void test_reserved_st_min_is_127_ms(void **state)
{
    (void)state;
    queue_response(20u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x30, 0, 0x80);  /* reserved */
    assert_int_equal(step(), 1u);
    expect_cf(&out[0], 1u, 6u, 20u);
    steps_without_frames(126u);
    assert_int_equal(step(), 1u);
    expect_cf(&out[0], 2u, 13u, 20u);
}

static void test_response_ended_by_the_tester_or_n_bs(void **state)
{
    (void)state;
    queue_response(20u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x32, 0, 0);  /* Overflow */
    steps_without_frames(3u);
    assert_int_equal(tp.counters.tx_aborted, 1u);
    assert_false(wc_isotp_sending(&tp));
    queue_response(20u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x33, 0, 0);  /* FS 3: invalid */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.tx_aborted, 2u);
    queue_response(20u);
    assert_int_equal(step(), 1u);  /* FF: N_Bs starts */
    steps_without_frames(999u);
    assert_true(wc_isotp_sending(&tp));
    steps_without_frames(1u);
    assert_int_equal(tp.counters.tx_timeouts, 1u);
    assert_false(wc_isotp_sending(&tp));
    RX(PHYS, 0x30, 0, 0);  /* too late */
    steps_without_frames(1u);
    assert_int_equal(tp.counters.unexpected, 1u);
    assert_int_equal(tp.counters.responses, 0u);
}

static void test_requests_while_sending_are_ignored(void **state)
{
    (void)state;
    queue_response(20u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x02, 0x10, 0x01);             /* half duplex: ignored */
    RX(PHYS, 0x10, 8, 1, 2, 3, 4, 5, 6);    /* no FC for it either */
    RX(FUNC, 0x02, 0x3E, 0x80);
    steps_without_frames(1u);
    assert_int_equal(tp.counters.busy, 3u);
    expect_no_request();
    RX(PHYS, 0x30, 0, 0);
    assert_int_equal(step(), 1u);
    assert_int_equal(step(), 1u);
    assert_false(wc_isotp_sending(&tp));
    RX(PHYS, 0x02, 0x10, 0x01);
    steps_without_frames(1u);
    expect_request(BYTES(0x10, 0x01), 2u, false);
}

/* A 200-byte request and response: SN 1..15, 0, 1, ... */
static void test_sequence_numbers_wrap(void **state)
{
    (void)state;
    uint8_t msg[200];
    for (uint32_t i = 0u; i < 200u; ++i) { msg[i] = pattern(i); }
    RX(PHYS, 0x10, 200, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]);
    assert_int_equal(step(), 1u);
    uint32_t offset = 6u;
    for (uint32_t sn = 1u; offset < 200u; ++sn) {
        wc_can_frame_t f;
        memset(&f, PAD, sizeof f);
        f.id = PHYS;
        f.dlc = 8u;
        f.flags = 0u;
        f.data[0] = (uint8_t)(0x20u | (sn & 0x0Fu));
        for (uint32_t i = 0u; (i < 7u) && (offset + i < 200u); ++i) { f.data[1u + i] = msg[offset + i]; }
        assert_true(wc_isotp_receive(&tp, &f));
        steps_without_frames(1u);
        offset += 7u;
    }
    expect_request(msg, 200u, false);
    uint8_t *buffer = wc_isotp_response_buffer(&tp);
    for (uint32_t i = 0u; i < 200u; ++i) { buffer[i] = pattern(i); }
    assert_true(wc_isotp_respond(&tp, 200u));
    assert_int_equal(step(), 1u);
    EXPECT(&out[0], 0x10, 200, pattern(0), pattern(1), pattern(2), pattern(3), pattern(4), pattern(5));
    RX(PHYS, 0x30, 0, 0);
    for (uint32_t k = 0u; k < 28u; ++k) {  /* 194 bytes: 28 CFs, one a step */
        assert_int_equal(step(), 1u);
        expect_cf(&out[0], (k + 1u) & 0x0Fu, 6u + 7u * k, 200u);
    }
    assert_false(wc_isotp_sending(&tp));
}

static void test_frames_per_step(void **state)
{
    (void)state;
    init_with(0u, 0u, 4u);
    queue_response(40u);  /* FF + 5 CFs */
    assert_int_equal(step(), 1u);  /* FF, then the FC is due */
    RX(PHYS, 0x30, 0, 0);
    assert_int_equal(step(), 4u);
    for (uint32_t k = 0u; k < 4u; ++k) { expect_cf(&out[k], k + 1u, 6u + 7u * k, 40u); }
    assert_int_equal(step(), 1u);
    expect_cf(&out[0], 5u, 34u, 40u);
    /* the caller's capacity bounds it too */
    queue_response(40u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x30, 0, 0);
    memset(out, 0, sizeof out);
    assert_int_equal(wc_isotp_step(&tp, out, 2u), 2u);
    assert_int_equal(step(), 3u);  /* the rest, budget 4 */
    for (uint32_t k = 0u; k < 3u; ++k) { expect_cf(&out[k], k + 3u, 20u + 7u * k, 40u); }
    /* with the tester's STmin 1 ms: one CF a step whatever the budget */
    init_with(0u, 0u, 4u);
    queue_response(40u);
    assert_int_equal(step(), 1u);
    RX(PHYS, 0x30, 0, 1);
    for (uint32_t k = 0u; k < 5u; ++k) {
        assert_int_equal(step(), 1u);
        expect_cf(&out[0], k + 1u, 6u + 7u * k, 40u);
    }
}

static void test_foreign_frames_and_ring_overflow(void **state)
{
    (void)state;
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.dlc = 8u;
    f.data[0] = 0x02u;
    f.data[1] = 0x3Eu;
    f.id = 0x123u;
    assert_true(wc_isotp_receive(&tp, &f));
    f.id = PHYS;
    f.flags = WC_CAN_FLAG_EXTENDED;
    assert_true(wc_isotp_receive(&tp, &f));
    f.flags = WC_CAN_FLAG_REMOTE;
    assert_true(wc_isotp_receive(&tp, &f));
    f.flags = WC_CAN_FLAG_ERROR;
    assert_true(wc_isotp_receive(&tp, &f));
    f.id = RESP;
    f.flags = 0u;
    assert_true(wc_isotp_receive(&tp, &f));
    steps_without_frames(1u);
    assert_int_equal(tp.counters.ignored, 5u);
    assert_int_equal(tp.counters.frames_in, 5u);
    expect_no_request();
    f.id = PHYS;
    for (uint32_t i = 0u; i < WC_ISOTP_RX_CAPACITY; ++i) { assert_true(wc_isotp_receive(&tp, &f)); }
    assert_false(wc_isotp_receive(&tp, &f));
    assert_int_equal(tp.counters.rx_overflows, 1u);
    steps_without_frames(1u);  /* the whole ring in one step: one request, the rest busy */
    assert_int_equal(tp.counters.requests, 1u);
    assert_int_equal(tp.counters.busy, WC_ISOTP_RX_CAPACITY - 1u);
}

static void test_extended_ids(void **state)
{
    (void)state;
    wc_isotp_config_t config = WC_ISOTP_CONFIG_DEFAULT;
    config.extended_ids = true;
    config.rx_physical_id = 0x18DA10F1u;
    config.rx_functional_id = 0x18DB33F1u;
    config.tx_id = 0x18DAF110u;
    config.padding = 0x55u;
    assert_true(wc_isotp_init(&tp, &config));
    wc_can_frame_t f = { 0x18DA10F1u, 3u, WC_CAN_FLAG_EXTENDED, { 0x02, 0x3E, 0x00, 0, 0, 0, 0, 0 } };
    assert_true(wc_isotp_receive(&tp, &f));
    f.flags = 0u;  /* the same id as an 11-bit frame cannot be: ignored */
    assert_true(wc_isotp_receive(&tp, &f));
    wc_can_frame_t tx[1];
    assert_int_equal(wc_isotp_step(&tp, tx, 1u), 0u);
    assert_int_equal(tp.counters.ignored, 1u);
    *wc_isotp_response_buffer(&tp) = 0x7Eu;
    assert_true(wc_isotp_respond(&tp, 1u));
    assert_int_equal(wc_isotp_step(&tp, tx, 1u), 1u);
    assert_int_equal(tx[0].id, 0x18DAF110u);
    assert_int_equal(tx[0].flags, WC_CAN_FLAG_EXTENDED);
    assert_memory_equal(tx[0].data, BYTES(0x01, 0x7E, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55), 8u);
}

static void test_init_refuses_bad_configurations(void **state)
{
    (void)state;
    const wc_isotp_config_t good = WC_ISOTP_CONFIG_DEFAULT;
    wc_isotp_config_t c = good;
    assert_true(wc_isotp_init(&tp, &c));
    assert_int_equal(tp.n_bs_steps, 1000u);
    assert_int_equal(tp.n_cr_steps, 1000u);
    c.period_us = 3000u;  /* 1000 ms / 3 ms rounds up */
    assert_true(wc_isotp_init(&tp, &c));
    assert_int_equal(tp.n_cr_steps, 334u);
    c = good; c.rx_physical_id = 0x800u;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.tx_id = c.rx_physical_id;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.tx_id = c.rx_functional_id;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.frames_per_step = 0u;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.frames_per_step = WC_ISOTP_MAX_FRAMES_PER_STEP + 1u;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.period_us = 99u;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.n_bs_ms = 0u;
    assert_false(wc_isotp_init(&tp, &c));
    c = good; c.n_cr_ms = 60001u;
    assert_false(wc_isotp_init(&tp, &c));
    assert_false(tp.initialised);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_single_frames, setup),
        cmocka_unit_test_setup(test_segmented_request, setup),
        cmocka_unit_test_setup(test_request_longer_than_the_buffer, setup),
        cmocka_unit_test_setup(test_wrong_sequence_number, setup),
        cmocka_unit_test_setup(test_n_cr_timeout, setup),
        cmocka_unit_test_setup(test_malformed_frames_ignored, setup),
        cmocka_unit_test_setup(test_functional_segmented_frames_ignored, setup),
        cmocka_unit_test_setup(test_unexpected_frames, setup),
        cmocka_unit_test_setup(test_segmented_response_paced_by_the_tester, setup),
        cmocka_unit_test_setup(test_reserved_st_min_is_127_ms, setup),
        cmocka_unit_test_setup(test_response_ended_by_the_tester_or_n_bs, setup),
        cmocka_unit_test_setup(test_requests_while_sending_are_ignored, setup),
        cmocka_unit_test_setup(test_sequence_numbers_wrap, setup),
        cmocka_unit_test_setup(test_frames_per_step, setup),
        cmocka_unit_test_setup(test_foreign_frames_and_ring_overflow, setup),
        cmocka_unit_test_setup(test_extended_ids, setup),
        cmocka_unit_test_setup(test_init_refuses_bad_configurations, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
