/* UDS server (include/wetclutch_can/wc_uds.h, src/can/wc_uds.c; ISO
 * 14229-1:2013), request by request, every response byte compared:
 *  - 0x10 sessions (P2/P2*), 0x3E, 0x11 soft reset (hook after the response
 *    left through ISO-TP, reset_check, suppressed), 0x22 one and several
 *    DIDs, 0x19 0x01 / 0x02 / 0x04 (snapshot record) / 0x0A, 0x14 all and
 *    one DTC, 0x31 start and results;
 *  - every NRC each service can give (0x11, 0x12, 0x13, 0x14, 0x22, 0x24,
 *    0x31, 0x33, 0x7F; 0x7E cannot occur: no sub-function here is
 *    session-bound), the check order of 7.5, suppressPosRsp, and the
 *    functional rules (0x11/0x12/0x31/0x7E/0x7F suppressed, 0x13/0x33 not);
 *  - SecurityAccess: the sequence (seed, key, 0x24 without a seed, a key
 *    consumes the seed, zero seed when unlocked), wrong keys (0x35, then
 *    0x36 and the delay with 0x37, the count reset by the delay's end),
 *    the delay after init, re-lock on every session change and at S3
 *    (TesterPresent and a response in flight keep the session);
 *  - the whole server over ISO-TP (wc_uds_step): a segmented response. */
#include "wc_test_support.h"

#include "wetclutch_can/wc_uds.h"

#define DELAY_STEPS 100u

/* ------------------------------------------------------------ the integrator's side */

typedef struct {
    uint32_t seeds;          /* seeds handed out */
    bool random_fails;
    bool key_fails;
    uint8_t reset_refusal;   /* reset_check's answer */
    uint32_t resets;
    uint8_t reset_type;
    uint32_t routine_starts;
} fake_t;

static fake_t fake;

static bool random_hook(void *context, uint8_t *seed, uint32_t length)
{
    fake_t *f = context;
    if (f->random_fails) { return false; }
    f->seeds++;
    for (uint32_t i = 0u; i < length; ++i) { seed[i] = (uint8_t)(0x10u * f->seeds + i); }
    return true;
}

/* A stand-in for the integrator's MAC: the tests only need a key that depends on the seed. */
static bool key_hook(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    const fake_t *f = context;
    for (uint32_t i = 0u; i < key_length; ++i) { key[i] = (uint8_t)(seed[i % seed_length] ^ 0x5Au); }
    return !f->key_fails;
}

static uint8_t reset_check(void *context, uint8_t type)
{
    (void)type;
    return ((const fake_t *)context)->reset_refusal;
}

static void reset_hook(void *context, uint8_t type)
{
    fake_t *f = context;
    f->resets++;
    f->reset_type = type;
}

static bool read_text(void *context, uint8_t *data, uint32_t length)
{
    const char *text = context;
    for (uint32_t i = 0u; i < length; ++i) { data[i] = (uint8_t)text[i]; }
    return true;
}

static bool read_fails(void *context, uint8_t *data, uint32_t length)
{
    (void)context;
    (void)data;
    (void)length;
    return false;
}

static bool read_zeros(void *context, uint8_t *data, uint32_t length)
{
    (void)context;
    memset(data, 0, length);
    return true;
}

static uint8_t adaptation_reset(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status_record,
                                uint32_t capacity, uint32_t *status_length)
{
    (void)option;
    fake_t *f = context;
    if (option_length != 0u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    f->routine_starts++;
    assert_true(capacity >= 1u);
    status_record[0] = 0x00u;
    *status_length = 1u;
    return 0u;
}

static uint8_t adaptation_results(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status_record,
                                  uint32_t capacity, uint32_t *status_length)
{
    (void)option;
    (void)option_length;
    const fake_t *f = context;
    assert_true(capacity >= 2u);
    status_record[0] = 0x02u;  /* completed */
    status_record[1] = (uint8_t)f->routine_starts;
    *status_length = 2u;
    return 0u;
}

static uint8_t refuses(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status_record,
                       uint32_t capacity, uint32_t *status_length)
{
    (void)context; (void)option; (void)option_length; (void)status_record; (void)capacity; (void)status_length;
    return WC_UDS_NRC_CONDITIONS;
}

static const wc_uds_did_t dids[] = {
    { 0xF18Cu, 8u, read_text, (void *)"WC000042" },
    { 0xF195u, 4u, read_text, (void *)"1.30" },
    { 0x0101u, 2u, read_fails, NULL },
    { 0x0200u, 200u, read_zeros, NULL },
};

static const wc_uds_routine_t routines[] = {
    { 0x0201u, adaptation_reset, adaptation_results, &fake },
    { 0x0202u, refuses, NULL, &fake },
};

static const wc_dtc_definition_t dtc_table[] = {
    { 0xC10000u, 1, 0, 1u, 1u, 1u, 1u, true },
    { 0x0A1600u, 1, 0, 1u, 1u, 1u, 2u, false },
    { 0x0A1700u, 1, 0, 1u, 1u, 1u, 3u, false },
};

static wc_dtc_snapshot_t environment;
static const wc_dtc_config_t dtc_config = { dtc_table, 3u, 3u, WC_DTC_NONE, &environment };
static wc_dtc_t dtc;
static wc_uds_config_t config;
static wc_uds_t uds;
static uint8_t rsp[WC_ISOTP_BUFFER_BYTES];
static uint32_t rsp_length;

static int setup(void **state)
{
    (void)state;
    memset(&fake, 0, sizeof fake);
    assert_true(wc_dtc_init(&dtc, &dtc_config));
    wc_dtc_cycle_start(&dtc);
    config = (wc_uds_config_t)WC_UDS_CONFIG_DEFAULT;
    config.delay_ms = DELAY_STEPS;  /* 1 ms period: steps */
    config.delay_at_init = false;
    config.dids = dids;
    config.did_count = (uint32_t)WC_TEST_COUNT(dids);
    config.routines = routines;
    config.routine_count = (uint32_t)WC_TEST_COUNT(routines);
    config.dtc = &dtc;
    config.random = random_hook;
    config.key = key_hook;
    config.reset_check = reset_check;
    config.reset = reset_hook;
    config.context = &fake;
    assert_true(wc_uds_init(&uds, &config));
    return 0;
}

/* ------------------------------------------------------------ requests */

#define BYTES(...) ((const uint8_t[]){ __VA_ARGS__ })
#define SIZE(...) ((uint32_t)sizeof(BYTES(__VA_ARGS__)))

static void request(bool functional, const uint8_t *bytes, uint32_t length)
{
    memset(rsp, 0xA5, sizeof rsp);
    rsp_length = wc_uds_handle(&uds, bytes, length, functional, rsp, (uint32_t)sizeof rsp);
}

static void expect_response(const uint8_t *want, uint32_t length, int line)
{
    if ((rsp_length != length) || (memcmp(rsp, want, length) != 0)) {
        print_error("line %d: %u bytes, expected %u:", line, (unsigned)rsp_length, (unsigned)length);
        for (uint32_t i = 0u; (i < rsp_length) && (i < 16u); ++i) { print_error(" %02x", rsp[i]); }
        print_error("\n");
        fail();
    }
}

/* REQ(...) then EXPECT(...) / EXPECT_NRC(sid, nrc) / EXPECT_NONE() */
#define REQ(...) request(false, BYTES(__VA_ARGS__), SIZE(__VA_ARGS__))
#define FREQ(...) request(true, BYTES(__VA_ARGS__), SIZE(__VA_ARGS__))
#define EXPECT(...) expect_response(BYTES(__VA_ARGS__), SIZE(__VA_ARGS__), __LINE__)
#define EXPECT_NRC(sid, nrc) expect_response(BYTES(0x7F, (sid), (nrc)), 3u, __LINE__)
#define EXPECT_NONE() assert_int_equal(rsp_length, 0u)

static void ticks(uint32_t n)
{
    for (uint32_t k = 0u; k < n; ++k) { wc_uds_tick(&uds); }
}

static void extended_session(void)
{
    REQ(0x10, 0x03);
    EXPECT(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4);
}

static void unlock(void)
{
    REQ(0x27, 0x01);
    assert_int_equal(rsp_length, 6u);
    uint8_t key[6] = { 0x27, 0x02 };
    for (uint32_t i = 0u; i < 4u; ++i) { key[2u + i] = (uint8_t)(rsp[2u + i] ^ 0x5Au); }
    request(false, key, 6u);
    EXPECT(0x67, 0x02);
    assert_true(wc_uds_unlocked(&uds));
}

/* ======================================================================== */

static void test_session_control(void **state)
{
    (void)state;
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_DEFAULT);
    extended_session();  /* P2 50 ms = 0x0032, P2* 5000 ms = 500 x 10 ms = 0x01F4 */
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_EXTENDED);
    REQ(0x10, 0x01);
    EXPECT(0x50, 0x01, 0x00, 0x32, 0x01, 0xF4);
    REQ(0x10, 0x02);        /* programming: not here */
    EXPECT_NRC(0x10, 0x12);
    REQ(0x10);
    EXPECT_NRC(0x10, 0x13);
    REQ(0x10, 0x03, 0x00);  /* the sub-function is known, the length wrong */
    EXPECT_NRC(0x10, 0x13);
    REQ(0x10, 0x05, 0x00);  /* unknown sub-function first (Figure 6) */
    EXPECT_NRC(0x10, 0x12);
    REQ(0x10, 0x83);        /* suppressPosRsp: no answer, but the session changes */
    EXPECT_NONE();
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_EXTENDED);
    REQ(0x10, 0x82);        /* the bit does not hide a negative response */
    EXPECT_NRC(0x10, 0x12);
    assert_int_equal(uds.counters.suppressed, 1u);
    assert_int_equal(uds.counters.negative, 5u);
}

static void test_tester_present(void **state)
{
    (void)state;
    REQ(0x3E, 0x00);
    EXPECT(0x7E, 0x00);
    REQ(0x3E, 0x80);
    EXPECT_NONE();
    FREQ(0x3E, 0x80);
    EXPECT_NONE();
    REQ(0x3E, 0x01);
    EXPECT_NRC(0x3E, 0x12);
    REQ(0x3E, 0x00, 0x00);
    EXPECT_NRC(0x3E, 0x13);
    REQ(0x3E);
    EXPECT_NRC(0x3E, 0x13);
}

static void test_unsupported_and_functional_rules(void **state)
{
    (void)state;
    REQ(0x2E, 0xF1, 0x90, 0x00);  /* WriteDataByIdentifier: not (yet) a service */
    EXPECT_NRC(0x2E, 0x11);
    REQ(0x50, 0x03);              /* a response id */
    EXPECT_NRC(0x50, 0x11);
    REQ(0x27, 0x01);              /* security access in the default session */
    EXPECT_NRC(0x27, 0x7F);
    /* functional: 0x11, 0x12, 0x31, 0x7F are not sent ... */
    FREQ(0x2E, 0xF1, 0x90, 0x00);
    EXPECT_NONE();
    FREQ(0x10, 0x02);
    EXPECT_NONE();
    FREQ(0x22, 0x12, 0x34);
    EXPECT_NONE();
    FREQ(0x27, 0x01);
    EXPECT_NONE();
    /* ... 0x13 and 0x33 are; a positive answer too */
    FREQ(0x3E, 0x00, 0x00);
    EXPECT_NRC(0x3E, 0x13);
    FREQ(0x14, 0xFF, 0xFF, 0xFF);
    EXPECT_NRC(0x14, 0x33);
    FREQ(0x22, 0xF1, 0x95);
    EXPECT(0x62, 0xF1, 0x95, '1', '.', '3', '0');
    request(false, BYTES(0x3E), 0u);  /* an empty request: nothing */
    EXPECT_NONE();
    assert_int_equal(uds.counters.suppressed, 4u);
    /* no fault memory: its services are unsupported; no security hooks: no 0x27; no routines: no 0x31 */
    config.dtc = NULL;
    config.random = NULL;
    config.routine_count = 0u;
    assert_true(wc_uds_init(&uds, &config));
    extended_session();
    REQ(0x19, 0x0A);
    EXPECT_NRC(0x19, 0x11);
    REQ(0x14, 0xFF, 0xFF, 0xFF);
    EXPECT_NRC(0x14, 0x11);
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x11);
    REQ(0x31, 0x01, 0x02, 0x01);
    EXPECT_NRC(0x31, 0x11);
}

static void test_read_data_by_identifier(void **state)
{
    (void)state;
    REQ(0x22, 0xF1, 0x8C);
    EXPECT(0x62, 0xF1, 0x8C, 'W', 'C', '0', '0', '0', '0', '4', '2');
    REQ(0x22, 0xF1, 0x95, 0x12, 0x34, 0xF1, 0x8C);  /* the unknown one is left out */
    EXPECT(0x62, 0xF1, 0x95, '1', '.', '3', '0', 0xF1, 0x8C, 'W', 'C', '0', '0', '0', '0', '4', '2');
    REQ(0x22, 0x12, 0x34);
    EXPECT_NRC(0x22, 0x31);
    REQ(0x22, 0xF1);
    EXPECT_NRC(0x22, 0x13);
    REQ(0x22);
    EXPECT_NRC(0x22, 0x13);
    REQ(0x22, 0xF1, 0x8C, 0xF1);
    EXPECT_NRC(0x22, 0x13);
    uint8_t many[1u + 2u * (WC_UDS_MAX_DIDS_PER_REQUEST + 1u)];
    many[0] = 0x22u;
    for (uint32_t i = 0u; i <= WC_UDS_MAX_DIDS_PER_REQUEST; ++i) {
        many[1u + 2u * i] = 0xF1u;
        many[2u + 2u * i] = 0x95u;
    }
    request(false, many, (uint32_t)sizeof many);  /* one DID too many */
    EXPECT_NRC(0x22, 0x13);
    request(false, many, (uint32_t)sizeof many - 2u);  /* the most: 16 x 6 bytes */
    assert_int_equal(rsp_length, 1u + 6u * WC_UDS_MAX_DIDS_PER_REQUEST);
    REQ(0x22, 0x01, 0x01);  /* the read hook refuses */
    EXPECT_NRC(0x22, 0x22);
    REQ(0x22, 0x02, 0x00);  /* 203 bytes fit */
    assert_int_equal(rsp_length, 203u);
    REQ(0x22, 0x02, 0x00, 0x02, 0x00);  /* 405 do not */
    EXPECT_NRC(0x22, 0x14);
    /* a response buffer too small for a positive answer: responseTooLong, never a cut answer */
    uint8_t small[5];
    assert_int_equal(wc_uds_handle(&uds, BYTES(0x10, 0x01), 2u, false, small, 5u), 3u);
    assert_memory_equal(small, BYTES(0x7F, 0x10, 0x14), 3u);
    assert_int_equal(wc_uds_handle(&uds, BYTES(0x10, 0x01), 2u, false, small, 2u), 0u);
}

static void test_read_dtc_information(void **state)
{
    (void)state;
    environment = (wc_dtc_snapshot_t){ 150.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 3u, 2u };
    wc_dtc_report(&dtc, 0u, true);   /* C10000: 0xAF */
    wc_dtc_report(&dtc, 2u, false);  /* 0A1700: 0x00 */
    REQ(0x19, 0x01, 0x09);          /* testFailed or confirmed */
    EXPECT(0x59, 0x01, 0xFF, 0x01, 0x00, 0x01);
    REQ(0x19, 0x01, 0x50);          /* not completed: the untested one */
    EXPECT(0x59, 0x01, 0xFF, 0x01, 0x00, 0x01);
    REQ(0x19, 0x02, 0xFF);
    EXPECT(0x59, 0x02, 0xFF, 0xC1, 0x00, 0x00, 0xAF, 0x0A, 0x16, 0x00, 0x50);
    REQ(0x19, 0x0A);                /* every supported DTC, whatever its status */
    EXPECT(0x59, 0x0A, 0xFF, 0xC1, 0x00, 0x00, 0xAF, 0x0A, 0x16, 0x00, 0x50, 0x0A, 0x17, 0x00, 0x00);
    REQ(0x19, 0x04, 0xC1, 0x00, 0x00, 0x01);
    assert_int_equal(rsp_length, 6u + 4u + WC_DTC_SNAPSHOT_BYTES);
    assert_memory_equal(rsp, BYTES(0x59, 0x04, 0xC1, 0x00, 0x00, 0xAF, 0x01, 0x01, 0xDD, 0x00, 0x43, 0x16, 0x00, 0x00),
                        14u);
    assert_int_equal(rsp[6u + 4u + 32u], 3u);
    assert_int_equal(rsp[6u + 4u + 33u], 2u);
    REQ(0x19, 0x04, 0xC1, 0x00, 0x00, 0xFF);  /* all records: the same one */
    assert_int_equal(rsp_length, 6u + 4u + WC_DTC_SNAPSHOT_BYTES);
    REQ(0x19, 0x04, 0x0A, 0x16, 0x00, 0x01);  /* nothing stored: DTC and status */
    EXPECT(0x59, 0x04, 0x0A, 0x16, 0x00, 0x50);
    REQ(0x19, 0x04, 0x0A, 0x16, 0x01, 0x01);  /* no such DTC */
    EXPECT_NRC(0x19, 0x31);
    REQ(0x19, 0x04, 0xC1, 0x00, 0x00, 0x02);  /* no such record */
    EXPECT_NRC(0x19, 0x31);
    REQ(0x19, 0x06, 0xC1, 0x00, 0x00, 0xFF);  /* extended data: not supported */
    EXPECT_NRC(0x19, 0x12);
    REQ(0x19, 0x01);
    EXPECT_NRC(0x19, 0x13);
    REQ(0x19, 0x02, 0xFF, 0x00);
    EXPECT_NRC(0x19, 0x13);
    REQ(0x19, 0x04, 0xC1, 0x00, 0x00);
    EXPECT_NRC(0x19, 0x13);
    REQ(0x19, 0x0A, 0x00);
    EXPECT_NRC(0x19, 0x13);
    REQ(0x19);
    EXPECT_NRC(0x19, 0x13);
    REQ(0x19, 0x82, 0xFF);  /* suppressed positive */
    EXPECT_NONE();
}

/* The whole server over ISO-TP: requests as frames, responses as frames. */
static wc_isotp_t tp;
static wc_can_frame_t frames[WC_ISOTP_MAX_FRAMES_PER_STEP];

static void frame_in(const uint8_t *bytes, uint32_t length)
{
    wc_can_frame_t f;
    memset(&f, 0xCC, sizeof f);
    f.id = 0x7E0u;
    f.dlc = 8u;
    f.flags = 0u;
    for (uint32_t i = 0u; i < length; ++i) { f.data[i] = bytes[i]; }
    assert_true(wc_isotp_receive(&tp, &f));
}
#define FRAME_IN(...) frame_in(BYTES(__VA_ARGS__), SIZE(__VA_ARGS__))

static uint32_t server_step(void) { return wc_uds_step(&uds, &tp, frames, WC_ISOTP_MAX_FRAMES_PER_STEP); }

static void test_ecu_reset_after_the_response(void **state)
{
    (void)state;
    const wc_isotp_config_t tp_config = WC_ISOTP_CONFIG_DEFAULT;
    assert_true(wc_isotp_init(&tp, &tp_config));
    FRAME_IN(0x02, 0x11, 0x03);
    assert_int_equal(server_step(), 0u);  /* served: the response goes out next step */
    assert_int_equal(fake.resets, 0u);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x02, 0x51, 0x03, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC), 8u);
    assert_int_equal(fake.resets, 1u);    /* in the step that hands the response out: the port sends, then resets */
    assert_int_equal(fake.reset_type, WC_UDS_RESET_SOFT);
    FRAME_IN(0x02, 0x3E, 0x00);           /* the tester's next request, sent on the response: after the reset */
    assert_int_equal(server_step(), 0u);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x02, 0x7E, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC), 8u);
    assert_int_equal(server_step(), 0u);
    assert_int_equal(fake.resets, 1u);    /* once */
    FRAME_IN(0x02, 0x11, 0x83);           /* suppressed: at the next step */
    assert_int_equal(server_step(), 0u);
    assert_int_equal(server_step(), 0u);
    assert_int_equal(fake.resets, 2u);
    REQ(0x11, 0x01);                      /* hard reset: not supported */
    EXPECT_NRC(0x11, 0x12);
    REQ(0x11, 0x03, 0x00);
    EXPECT_NRC(0x11, 0x13);
    fake.reset_refusal = WC_UDS_NRC_CONDITIONS;  /* e.g. the vehicle moves */
    REQ(0x11, 0x03);
    EXPECT_NRC(0x11, 0x22);
    assert_int_equal(uds.reset_type, 0u);
    config.reset = NULL;
    assert_true(wc_uds_init(&uds, &config));
    REQ(0x11, 0x03);
    EXPECT_NRC(0x11, 0x12);
}

static void test_server_over_isotp(void **state)
{
    (void)state;
    const wc_isotp_config_t tp_config = WC_ISOTP_CONFIG_DEFAULT;
    assert_true(wc_isotp_init(&tp, &tp_config));
    FRAME_IN(0x05, 0x22, 0xF1, 0x8C, 0xF1, 0x95);  /* 1 + 10 + 6 = 17 bytes back: FF + 2 CF */
    assert_int_equal(server_step(), 0u);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x10, 17, 0x62, 0xF1, 0x8C, 'W', 'C', '0'), 8u);
    FRAME_IN(0x30, 0x00, 0x00);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x21, '0', '0', '0', '4', '2', 0xF1, 0x95), 8u);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x22, '1', '.', '3', '0', 0xCC, 0xCC, 0xCC), 8u);
    assert_int_equal(tp.counters.responses, 1u);
    /* a request split over frames */
    FRAME_IN(0x10, 0x09, 0x22, 0xF1, 0x95, 0xF1, 0x95, 0xF1);
    assert_int_equal(server_step(), 1u);  /* our FC */
    FRAME_IN(0x21, 0x95, 0xF1, 0x95);
    assert_int_equal(server_step(), 0u);
    assert_int_equal(server_step(), 1u);
    assert_memory_equal(frames[0].data, BYTES(0x10, 25, 0x62, 0xF1, 0x95, '1', '.', '3'), 8u);
    /* the response in flight keeps the extended session past S3 */
    uds.session = WC_UDS_SESSION_EXTENDED;
    for (uint32_t k = 0u; k < 5500u; ++k) { (void)server_step(); }  /* the tester never sends the FC: N_Bs ends it */
    assert_int_equal(tp.counters.tx_timeouts, 1u);
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_EXTENDED);  /* S3 from the end of the response */
    for (uint32_t k = 0u; k < 600u; ++k) { (void)server_step(); }
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_DEFAULT);  /* 1000 steps of N_Bs + 5000 of S3 */
    assert_int_equal(uds.counters.s3_timeouts, 1u);
}

static void test_init_refuses_bad_configurations(void **state)
{
    (void)state;
    const wc_uds_config_t good = config;
    wc_uds_config_t c = good;
    c.seed_bytes = 0u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.seed_bytes = WC_UDS_SEED_MAX_BYTES + 1u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.key_bytes = 0u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.max_attempts = 0u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.period_us = 0u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.p2_ms = 0x10000u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.s3_ms = 0u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.did_count = WC_UDS_MAX_DIDS + 1u;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.dids = NULL;
    assert_false(wc_uds_init(&uds, &c));
    c = good; c.routine_count = WC_UDS_MAX_ROUTINES + 1u;
    assert_false(wc_uds_init(&uds, &c));
    static const wc_uds_did_t twice[] = { { 1u, 1u, read_zeros, NULL }, { 1u, 2u, read_zeros, NULL } };
    c = good; c.dids = twice; c.did_count = 2u;
    assert_false(wc_uds_init(&uds, &c));
    static const wc_uds_did_t no_read[] = { { 1u, 1u, NULL, NULL } };
    c = good; c.dids = no_read; c.did_count = 1u;
    assert_false(wc_uds_init(&uds, &c));
    static const wc_uds_did_t too_long[] = { { 1u, WC_ISOTP_BUFFER_BYTES - 2u, read_zeros, NULL } };
    c = good; c.dids = too_long; c.did_count = 1u;
    assert_false(wc_uds_init(&uds, &c));
    static const wc_uds_routine_t same[] = { { 5u, refuses, NULL, NULL }, { 5u, refuses, NULL, NULL } };
    c = good; c.routines = same; c.routine_count = 2u;
    assert_false(wc_uds_init(&uds, &c));
    assert_false(uds.initialised);
    c = good;
    assert_true(wc_uds_init(&uds, &c));
}

/* ------------------------------------------------------------ security */

static void test_security_access_sequence(void **state)
{
    (void)state;
    extended_session();
    REQ(0x27, 0x02, 0x4A, 0x4B, 0x48, 0x49);  /* a key without a seed */
    EXPECT_NRC(0x27, 0x24);
    REQ(0x27, 0x01);
    EXPECT(0x67, 0x01, 0x10, 0x11, 0x12, 0x13);
    REQ(0x27, 0x01, 0x00);
    EXPECT_NRC(0x27, 0x13);
    REQ(0x27, 0x03);  /* one level only */
    EXPECT_NRC(0x27, 0x12);
    REQ(0x27);
    EXPECT_NRC(0x27, 0x13);
    REQ(0x27, 0x01);  /* a new seed replaces the old one */
    EXPECT(0x67, 0x01, 0x20, 0x21, 0x22, 0x23);
    REQ(0x27, 0x02, 0x4A, 0x4B, 0x48, 0x49);  /* the old seed's key */
    EXPECT_NRC(0x27, 0x35);
    REQ(0x27, 0x02, 0x7A, 0x7B, 0x78, 0x79);  /* the right key, but the seed was consumed */
    EXPECT_NRC(0x27, 0x24);
    REQ(0x27, 0x01);
    EXPECT(0x67, 0x01, 0x30, 0x31, 0x32, 0x33);
    REQ(0x27, 0x02, 0x6A, 0x6B, 0x68);  /* a short key: a format error, the seed consumed, no attempt counted */
    EXPECT_NRC(0x27, 0x13);
    REQ(0x27, 0x02, 0x6A, 0x6B, 0x68, 0x69);
    EXPECT_NRC(0x27, 0x24);
    assert_int_equal(uds.failed_attempts, 1u);
    fake.key_fails = true;  /* the integrator's key hook cannot answer */
    REQ(0x27, 0x01);
    REQ(0x27, 0x02, 0x0A, 0x0B, 0x08, 0x09);
    EXPECT_NRC(0x27, 0x22);
    fake.key_fails = false;
    fake.random_fails = true;
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x22);
    fake.random_fails = false;
    assert_false(wc_uds_unlocked(&uds));
    unlock();
    assert_int_equal(uds.failed_attempts, 0u);
    REQ(0x27, 0x01);  /* unlocked: a zero seed, and nothing to answer */
    EXPECT(0x67, 0x01, 0x00, 0x00, 0x00, 0x00);
    REQ(0x27, 0x02, 0x5A, 0x5A, 0x5A, 0x5A);
    EXPECT_NRC(0x27, 0x24);
    assert_true(wc_uds_unlocked(&uds));
}

static void wrong_key(uint8_t nrc)
{
    REQ(0x27, 0x01);
    assert_int_equal(rsp_length, 6u);
    REQ(0x27, 0x02, 0x00, 0x00, 0x00, 0x00);
    EXPECT_NRC(0x27, nrc);
}

static void test_wrong_keys_and_the_delay(void **state)
{
    (void)state;
    extended_session();
    wrong_key(0x35);
    wrong_key(0x35);
    wrong_key(0x36);  /* the third: exceededNumberOfAttempts, the delay starts */
    assert_int_equal(uds.counters.invalid_keys, 3u);
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x37);
    REQ(0x27, 0x02, 0x00, 0x00, 0x00, 0x00);  /* no seed in the delay */
    EXPECT_NRC(0x27, 0x24);
    ticks(DELAY_STEPS - 1u);
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x37);
    ticks(1u);
    wrong_key(0x35);  /* the delay's end reset the count */
    wrong_key(0x35);
    wrong_key(0x36);
    extended_session();  /* a session change does not end the delay */
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x37);
    ticks(DELAY_STEPS);
    unlock();
}

static void test_delay_after_init(void **state)
{
    (void)state;
    config.delay_at_init = true;  /* a reset buys no new attempts */
    assert_true(wc_uds_init(&uds, &config));
    extended_session();
    REQ(0x27, 0x01);
    EXPECT_NRC(0x27, 0x37);
    ticks(DELAY_STEPS);
    unlock();
}

static void test_relock_on_session_change_and_s3(void **state)
{
    (void)state;
    extended_session();
    unlock();
    extended_session();  /* extended -> extended re-locks too */
    assert_false(wc_uds_unlocked(&uds));
    REQ(0x14, 0xFF, 0xFF, 0xFF);
    EXPECT_NRC(0x14, 0x33);
    unlock();
    REQ(0x10, 0x01);
    assert_false(wc_uds_unlocked(&uds));
    extended_session();
    unlock();
    ticks(4999u);  /* S3 5000 ms */
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_EXTENDED);
    assert_true(wc_uds_unlocked(&uds));
    ticks(1u);
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_DEFAULT);
    assert_false(wc_uds_unlocked(&uds));
    assert_int_equal(uds.counters.s3_timeouts, 1u);
    extended_session();
    for (uint32_t k = 0u; k < 3u; ++k) {  /* TesterPresent (functional, suppressed) keeps the session */
        ticks(4000u);
        FREQ(0x3E, 0x80);
        EXPECT_NONE();
    }
    assert_int_equal(wc_uds_session(&uds), WC_UDS_SESSION_EXTENDED);
    ticks(10000u);  /* the default session has no S3 */
    assert_int_equal(uds.counters.s3_timeouts, 2u);
}

static void test_guarded_services(void **state)
{
    (void)state;
    wc_dtc_report(&dtc, 0u, true);
    REQ(0x14, 0xFF, 0xFF, 0xFF);  /* locked: in any session */
    EXPECT_NRC(0x14, 0x33);
    REQ(0x14, 0xFF);              /* security before the length (Figure 5) */
    EXPECT_NRC(0x14, 0x33);
    REQ(0x31, 0x01, 0x02, 0x01);
    EXPECT_NRC(0x31, 0x33);
    assert_int_equal(wc_dtc_status(&dtc, 0u), 0xAFu);
    assert_int_equal(fake.routine_starts, 0u);
    extended_session();
    unlock();
    REQ(0x14, 0xFF, 0xFF);
    EXPECT_NRC(0x14, 0x13);
    REQ(0x14, 0x12, 0x34, 0x56);
    EXPECT_NRC(0x14, 0x31);
    REQ(0x14, 0xC1, 0x00, 0x00);  /* one DTC */
    EXPECT(0x54);
    assert_int_equal(wc_dtc_status(&dtc, 0u), 0x50u);
    wc_dtc_report(&dtc, 1u, true);
    REQ(0x14, 0xFF, 0xFF, 0xFF);  /* all */
    EXPECT(0x54);
    assert_int_equal(wc_dtc_status(&dtc, 1u), 0x50u);
    /* routines */
    REQ(0x31, 0x03, 0x02, 0x01);  /* results before a start */
    EXPECT_NRC(0x31, 0x24);
    REQ(0x31, 0x01, 0x02, 0x01);
    EXPECT(0x71, 0x01, 0x02, 0x01, 0x00);
    REQ(0x31, 0x03, 0x02, 0x01);
    EXPECT(0x71, 0x03, 0x02, 0x01, 0x02, 0x01);
    REQ(0x31, 0x01, 0x02, 0x01, 0xAA);  /* the routine's own check of its option record */
    EXPECT_NRC(0x31, 0x13);
    REQ(0x31, 0x81, 0x02, 0x01);
    EXPECT_NONE();
    assert_int_equal(fake.routine_starts, 2u);
    REQ(0x31, 0x01, 0x12, 0x34);
    EXPECT_NRC(0x31, 0x31);
    REQ(0x31, 0x02, 0x02, 0x01);  /* stopRoutine: not supported */
    EXPECT_NRC(0x31, 0x12);
    REQ(0x31, 0x01, 0x02);
    EXPECT_NRC(0x31, 0x13);
    REQ(0x31);
    EXPECT_NRC(0x31, 0x13);
    REQ(0x31, 0x01, 0x02, 0x02);
    EXPECT_NRC(0x31, 0x22);
    REQ(0x31, 0x03, 0x02, 0x02);  /* no results function */
    EXPECT_NRC(0x31, 0x31);
    extended_session();  /* a session change forgets the started routines */
    unlock();
    REQ(0x31, 0x03, 0x02, 0x01);
    EXPECT_NRC(0x31, 0x24);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_session_control, setup),
        cmocka_unit_test_setup(test_tester_present, setup),
        cmocka_unit_test_setup(test_unsupported_and_functional_rules, setup),
        cmocka_unit_test_setup(test_read_data_by_identifier, setup),
        cmocka_unit_test_setup(test_read_dtc_information, setup),
        cmocka_unit_test_setup(test_ecu_reset_after_the_response, setup),
        cmocka_unit_test_setup(test_server_over_isotp, setup),
        cmocka_unit_test_setup(test_init_refuses_bad_configurations, setup),
        cmocka_unit_test_setup(test_security_access_sequence, setup),
        cmocka_unit_test_setup(test_wrong_keys_and_the_delay, setup),
        cmocka_unit_test_setup(test_delay_after_init, setup),
        cmocka_unit_test_setup(test_relock_on_session_change_and_s3, setup),
        cmocka_unit_test_setup(test_guarded_services, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
