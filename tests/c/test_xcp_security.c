/* XCP seed & key (include/wetclutch_can/wc_xcp.h, src/can/wc_xcp.c; DESIGN
 * 17) against the layouts of ASAM MCD-1 XCP part 2:
 *  - no hooks: nothing protected (GET_STATUS protection 0, GET_SEED length
 *    0, UNLOCK ERR_SEQUENCE), a DOWNLOAD works as before;
 *  - with hooks: CAL/PAG locked (DOWNLOAD, SET_CAL_PAGE, GET_CAL_PAGE,
 *    COPY_CAL_PAGE, GET_PAG_PROCESSOR_INFO: ERR_ACCESS_LOCKED) until GET_SEED
 *    + UNLOCK with the key hook's key; uploads and DAQ stay open; DAQ
 *    locked too with protect_daq, unlocked on its own;
 *  - a wrong key (or length): ERR_ACCESS_LOCKED and the session
 *    disconnected; the seed used once; DISCONNECT locks again;
 *  - wrong keys counted across sessions, then a lock-out of
 *    unlock_delay_steps control steps: GET_SEED of a protected resource
 *    ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE (no seed, no key to try), the
 *    writes ERR_ACCESS_LOCKED; a right key, and the lock-out's end, start the
 *    count from 0;
 *  - GET_SEED's and UNLOCK's error classes, a failing random hook, the
 *    configurations init refuses.
 * Built twice: as test_xcp_security against the library, and as
 * test_xcp_read_only with src/can/wc_xcp.c compiled under
 * WC_XCP_READ_ONLY (tests/CMakeLists.txt): there DOWNLOAD, SET_CAL_PAGE
 * and COPY_CAL_PAGE answer ERR_CMD_UNKNOWN even when unlocked.
 * The hooks here are test stand-ins (a counter and an XOR), not a MAC. */
#include "wc_test_support.h"

#include "wc_table1_calibration.h"
#include "wetclutch_can/wc_cal_image.h"
#include "wetclutch_can/wc_loop.h"
#include "wetclutch_can/wc_xcp.h"

#define THETA_START_degC 40.0f
#define CAL_BASE 0x00010000u

static const wc_loop_config_t rig_config = { 10u, 10u, { 2u, 3u }, 1u, false, NULL, NULL, NULL, NULL, NULL, 1u };

typedef struct {
    wc_loop_t loop;
    wc_xcp_t xcp;
    wc_cal_set_t set;
    uint8_t reference[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
    wc_can_frame_t xout[WC_XCP_TX_FRAMES];
    uint8_t next_seed;      /* the random hook's counter */
    bool random_fails;
    uint32_t random_calls;
    uint32_t key_calls;
} rig_t;

static rig_t rig;

static bool test_random(void *context, uint8_t *seed, uint32_t length)
{
    rig_t *r = context;
    r->random_calls++;
    if (r->random_fails) { return false; }
    for (uint32_t i = 0u; i < length; ++i) { seed[i] = r->next_seed++; }
    return true;
}

static bool test_key(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    rig_t *r = context;
    r->key_calls++;
    for (uint32_t i = 0u; i < key_length; ++i) { key[i] = (uint8_t)(seed[i % seed_length] ^ (0x5Au + i)); }
    return true;
}

static wc_xcp_config_t protected_config(bool protect_daq)
{
    wc_xcp_config_t c = WC_XCP_CONFIG_DEFAULT;
    c.protect_daq = protect_daq;
    c.seed_bytes = 4u;
    c.key_bytes = 6u;
    c.random = test_random;
    c.key = test_key;
    c.context = &rig;
    return c;
}

static void rig_init(const wc_xcp_config_t *config)
{
    memset(&rig, 0, sizeof rig);
    rig.next_seed = 0x10u;
    assert_true(wc_cal_set_from(&rig.set, &wc_table1_calibration, NULL, &rig_config));
    wc_cal_image_encode(&rig.set, rig.reference);
    assert_int_equal(wc_loop_init(&rig.loop, &wc_table1_calibration, &rig_config, THETA_START_degC), WC_CAL_OK);
    assert_true(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, config));
}

/* One command and the step that answers it: the frames back (0: no answer). */
static uint32_t send(const uint8_t *bytes, uint32_t dlc)
{
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = WC_CAN_XCP_COMMAND_FRAME_ID;
    f.dlc = (uint8_t)dlc;
    for (uint32_t i = 0u; i < dlc; ++i) { f.data[i] = bytes[i]; }
    assert_true(wc_xcp_receive(&rig.xcp, &f));
    memset(rig.xout, 0xA5, sizeof rig.xout);
    return wc_xcp_step(&rig.xcp, false, rig.xout);
}

#define BYTES(...) ((const uint8_t[]){ __VA_ARGS__ })
#define SEND(...) send(BYTES(__VA_ARGS__), (uint32_t)sizeof(BYTES(__VA_ARGS__)))

/* The one answer's PID and its second byte (the error code, or the first parameter). */
static void expect_answer(uint32_t frames, uint8_t pid, uint8_t second, int line)
{
    if ((frames != 1u) || (rig.xout[0].data[0] != pid) || (rig.xout[0].data[1] != second)) {
        print_error("line %d: %u frames, %02x %02x; expected 1 frame, %02x %02x\n", line, (unsigned)frames,
                    rig.xout[0].data[0], rig.xout[0].data[1], pid, second);
        fail();
    }
}
#define EXPECT_OK(frames, second) expect_answer((frames), 0xFFu, (second), __LINE__)
#define EXPECT_ERR(frames, code) expect_answer((frames), 0xFEu, (code), __LINE__)

static uint8_t protection(void)
{
    assert_int_equal(SEND(WC_XCP_GET_STATUS), 1u);
    assert_int_equal(rig.xout[0].data[0], 0xFFu);
    return rig.xout[0].data[2];
}

/* A DOWNLOAD of the byte the page holds at CAL_BASE (no page change): its answer. */
static uint32_t download_same_byte(void)
{
    assert_int_equal(SEND(WC_XCP_SET_MTA, 0u, 0u, 0u, 0x00u, 0x00u, 0x01u, 0x00u), 1u);
    return SEND(WC_XCP_DOWNLOAD, 1u, rig.reference[0]);
}

/* Writes once unlocked: positive, or ERR_CMD_UNKNOWN in the read-only build. */
/* A write while locked: ERR_ACCESS_LOCKED, or ERR_CMD_UNKNOWN in the read-only build. */
#ifdef WC_XCP_READ_ONLY
#define EXPECT_WRITE_OK(frames) EXPECT_ERR((frames), WC_XCP_ERR_CMD_UNKNOWN)
#define EXPECT_WRITE_LOCKED(frames) EXPECT_ERR((frames), WC_XCP_ERR_CMD_UNKNOWN)
#else
#define EXPECT_WRITE_OK(frames) EXPECT_OK((frames), 0u)
#define EXPECT_WRITE_LOCKED(frames) EXPECT_ERR((frames), WC_XCP_ERR_ACCESS_LOCKED)
#endif

/* GET_SEED for resource and UNLOCK with the hook's key (+ flip in its first byte). */
static void seed_and_key(uint8_t resource, uint8_t flip)
{
    assert_int_equal(SEND(WC_XCP_GET_SEED, 0u, resource), 1u);
    assert_int_equal(rig.xout[0].data[0], 0xFFu);
    assert_int_equal(rig.xout[0].data[1], 4u);  /* the seed's length, the whole seed in this frame */
    uint8_t seed[4], key[6];
    for (uint32_t i = 0u; i < 4u; ++i) { seed[i] = rig.xout[0].data[2u + i]; }
    assert_true(test_key(&rig, seed, 4u, key, 6u));
    key[0] ^= flip;
    (void)SEND(WC_XCP_UNLOCK, 6u, key[0], key[1], key[2], key[3], key[4], key[5]);
}

/* ======================================================================== */

static void test_no_hooks_nothing_protected(void **state)
{
    (void)state;
    const wc_xcp_config_t config = WC_XCP_CONFIG_DEFAULT;
    rig_init(&config);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);  /* RESOURCE: CAL/PAG and DAQ available */
    assert_int_equal(protection(), 0u);
    EXPECT_OK(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 0u);  /* length 0: not protected */
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 1u, 0u), WC_XCP_ERR_SEQUENCE);
    EXPECT_WRITE_OK(download_same_byte());
}

static void test_cal_pag_locked_until_unlock(void **state)
{
    (void)state;
    const wc_xcp_config_t config = protected_config(false);
    rig_init(&config);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(protection(), WC_XCP_RESOURCE_CAL_PAG);
    EXPECT_WRITE_LOCKED(download_same_byte());
    EXPECT_WRITE_LOCKED(SEND(WC_XCP_SET_CAL_PAGE, 0x03u, 0u, 1u));
    EXPECT_ERR(SEND(WC_XCP_GET_CAL_PAGE, 0x01u, 0u), WC_XCP_ERR_ACCESS_LOCKED);
    EXPECT_WRITE_LOCKED(SEND(WC_XCP_COPY_CAL_PAGE, 0u, 1u, 0u, 0u));
    EXPECT_ERR(SEND(WC_XCP_GET_PAG_PROCESSOR_INFO), WC_XCP_ERR_ACCESS_LOCKED);
    assert_int_equal(rig.xcp.working_page[0], rig.reference[0]);
    /* reads and DAQ stay open */
    EXPECT_OK(SEND(WC_XCP_SHORT_UPLOAD, 1u, 0u, 0u, 0x00u, 0x00u, 0x01u, 0x00u), rig.reference[0]);
    EXPECT_OK(SEND(WC_XCP_FREE_DAQ), 0u);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);
    EXPECT_OK(1u, 0u);  /* UNLOCK's answer: nothing locked any more */
    assert_int_equal(rig.key_calls, 2u);  /* the test's own call and the slave's */
    assert_int_equal(protection(), 0u);
    EXPECT_WRITE_OK(download_same_byte());
    EXPECT_OK(SEND(WC_XCP_GET_CAL_PAGE, 0x01u, 0u), 0u);
    EXPECT_OK(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 0u);  /* unlocked: seed length 0 */
    /* DISCONNECT restores the protection */
    EXPECT_OK(SEND(WC_XCP_DISCONNECT), 0u);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(protection(), WC_XCP_RESOURCE_CAL_PAG);
    EXPECT_WRITE_LOCKED(download_same_byte());
#ifdef WC_XCP_READ_ONLY
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);
    EXPECT_OK(1u, 0u);
    EXPECT_WRITE_OK(SEND(WC_XCP_SET_CAL_PAGE, 0x03u, 0u, 1u));  /* unlocked, and still no page switch */
    EXPECT_WRITE_OK(SEND(WC_XCP_COPY_CAL_PAGE, 0u, 1u, 0u, 0u));
#endif
}

static void test_wrong_key_disconnects(void **state)
{
    (void)state;
    const wc_xcp_config_t config = protected_config(false);
    rig_init(&config);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0x01u);
    EXPECT_ERR(1u, WC_XCP_ERR_ACCESS_LOCKED);
    assert_false(rig.xcp.connected);
    assert_int_equal(SEND(WC_XCP_GET_STATUS), 0u);  /* disconnected: no answer */
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(protection(), WC_XCP_RESOURCE_CAL_PAG);
    /* the seed is gone with the session: UNLOCK needs a new one */
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 6u, 0u, 0u, 0u, 0u, 0u, 0u), WC_XCP_ERR_SEQUENCE);
    /* a key of another length: wrong, disconnected */
    assert_int_equal(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 1u);
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 4u, 0u, 0u, 0u, 0u), WC_XCP_ERR_ACCESS_LOCKED);
    assert_false(rig.xcp.connected);
    /* the right key after a wrong one: a fresh seed each time */
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);
    EXPECT_OK(1u, 0u);
    /* an UNLOCK consumes its seed: a second one is out of sequence */
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 6u, 0u, 0u, 0u, 0u, 0u, 0u), WC_XCP_ERR_SEQUENCE);
    assert_true(rig.xcp.connected);
}

#define LOCKOUT_ATTEMPTS 3u
#define LOCKOUT_STEPS 5u

/* n control steps of time (wc_xcp_step with control_step, no command) */
static void control_steps(uint32_t n)
{
    for (uint32_t i = 0u; i < n; ++i) { assert_int_equal(wc_xcp_step(&rig.xcp, true, rig.xout), 0u); }
}

/* CONNECT (if not connected) and one wrong key: ERR_ACCESS_LOCKED, disconnected */
static void wrong_key(void)
{
    if (!rig.xcp.connected) { EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u); }
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0x01u);
    EXPECT_ERR(1u, WC_XCP_ERR_ACCESS_LOCKED);
    assert_false(rig.xcp.connected);
}

static wc_xcp_config_t lockout_config(void)
{
    wc_xcp_config_t c = protected_config(false);
    c.unlock_attempts = LOCKOUT_ATTEMPTS;
    c.unlock_delay_steps = LOCKOUT_STEPS;
    return c;
}

static void test_wrong_keys_counted_then_locked_out(void **state)
{
    (void)state;
    const wc_xcp_config_t config = lockout_config();
    rig_init(&config);
    wrong_key();  /* the count survives the disconnect a wrong key makes ... */
    wrong_key();
    assert_int_equal(rig.xcp.unlock_failures, 2u);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);  /* ... and a DISCONNECT and a new CONNECT */
    EXPECT_OK(SEND(WC_XCP_DISCONNECT), 0u);
    wrong_key();  /* the third: the lock-out */
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    const uint32_t random_calls = rig.random_calls;
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 6u, 0u, 0u, 0u, 0u, 0u, 0u), WC_XCP_ERR_SEQUENCE);  /* no seed: no key to try */
    EXPECT_WRITE_LOCKED(download_same_byte());
    EXPECT_OK(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_DAQ), 0u);  /* not protected here: length 0 */
    assert_true(rig.xcp.connected);
    /* time is control steps: commands without one do not shorten it */
    for (uint32_t i = 0u; i < 2u * LOCKOUT_STEPS; ++i) {
        EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    }
    control_steps(LOCKOUT_STEPS - 1u);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    assert_int_equal(rig.random_calls, random_calls);  /* not one seed in the lock-out */
    control_steps(1u);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);  /* over: a seed, and the right key unlocks */
    EXPECT_OK(1u, 0u);
    EXPECT_WRITE_OK(download_same_byte());
    assert_int_equal(rig.xcp.unlock_failures, 0u);
}

static void test_count_starts_again(void **state)
{
    (void)state;
    const wc_xcp_config_t config = lockout_config();
    rig_init(&config);
    /* a right key resets the count: two wrong, the right one, two wrong again: no lock-out */
    wrong_key();
    wrong_key();
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);
    EXPECT_OK(1u, 0u);
    EXPECT_OK(SEND(WC_XCP_DISCONNECT), 0u);
    wrong_key();
    wrong_key();
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 1u);
    assert_int_equal(rig.xout[0].data[0], 0xFFu);  /* a seed */
    /* the lock-out's end does too: three wrong, waited out, then three wrong again lock out again */
    EXPECT_OK(SEND(WC_XCP_DISCONNECT), 0u);
    wrong_key();
    control_steps(LOCKOUT_STEPS);
    wrong_key();
    wrong_key();
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 1u);
    assert_int_equal(rig.xout[0].data[0], 0xFFu);  /* two since the end: no lock-out */
    EXPECT_OK(SEND(WC_XCP_DISCONNECT), 0u);
    wrong_key();
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    /* the step counter wraps (2^32 control steps): the lock-out still ends after its steps */
    const wc_xcp_config_t again = lockout_config();
    rig_init(&again);
    rig.xcp.status.timestamp = 0xFFFFFFFEu;
    wrong_key();
    wrong_key();
    wrong_key();
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    control_steps(LOCKOUT_STEPS - 1u);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    control_steps(1u);
    assert_int_equal(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), 1u);
    assert_int_equal(rig.xout[0].data[0], 0xFFu);
}

static void test_daq_protected_by_config(void **state)
{
    (void)state;
    const wc_xcp_config_t config = protected_config(true);
    rig_init(&config);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    assert_int_equal(protection(), WC_XCP_RESOURCE_CAL_PAG | WC_XCP_RESOURCE_DAQ);
    EXPECT_ERR(SEND(WC_XCP_FREE_DAQ), WC_XCP_ERR_ACCESS_LOCKED);
    EXPECT_ERR(SEND(WC_XCP_GET_DAQ_PROCESSOR_INFO), WC_XCP_ERR_ACCESS_LOCKED);
    EXPECT_ERR(SEND(WC_XCP_START_STOP_SYNCH, 0u), WC_XCP_ERR_ACCESS_LOCKED);
    seed_and_key(WC_XCP_RESOURCE_CAL_PAG, 0u);
    EXPECT_OK(1u, WC_XCP_RESOURCE_DAQ);  /* one resource a seed: DAQ still locked */
    EXPECT_ERR(SEND(WC_XCP_FREE_DAQ), WC_XCP_ERR_ACCESS_LOCKED);
    seed_and_key(WC_XCP_RESOURCE_DAQ, 0u);
    EXPECT_OK(1u, 0u);
    EXPECT_OK(SEND(WC_XCP_FREE_DAQ), 0u);
}

static void test_seed_errors(void **state)
{
    (void)state;
    const wc_xcp_config_t config = protected_config(false);
    rig_init(&config);
    EXPECT_OK(SEND(WC_XCP_CONNECT, 0u), 0x05u);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 1u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_SEQUENCE);  /* no remaining part */
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 2u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_OUT_OF_RANGE);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, 0x05u), WC_XCP_ERR_OUT_OF_RANGE);  /* two resources */
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, 0u), WC_XCP_ERR_OUT_OF_RANGE);
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u), WC_XCP_ERR_CMD_SYNTAX);
    EXPECT_ERR(SEND(WC_XCP_UNLOCK), WC_XCP_ERR_CMD_SYNTAX);
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 6u, 1u, 2u), WC_XCP_ERR_CMD_SYNTAX);  /* fewer key bytes than it says */
    EXPECT_OK(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_DAQ), 0u);        /* not protected here */
    rig.random_fails = true;  /* never a predictable seed */
    EXPECT_ERR(SEND(WC_XCP_GET_SEED, 0u, WC_XCP_RESOURCE_CAL_PAG), WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE);
    EXPECT_ERR(SEND(WC_XCP_UNLOCK, 6u, 0u, 0u, 0u, 0u, 0u, 0u), WC_XCP_ERR_SEQUENCE);
    assert_true(rig.xcp.connected);
    assert_int_equal(protection(), WC_XCP_RESOURCE_CAL_PAG);
}

static void test_init_refuses_half_protection(void **state)
{
    (void)state;
    wc_xcp_config_t c = protected_config(false);
    c.key = NULL;
    memset(&rig.xcp, 0, sizeof rig.xcp);
    assert_true(wc_loop_init(&rig.loop, &wc_table1_calibration, &rig_config, THETA_START_degC) == WC_CAL_OK);
    assert_true(wc_cal_set_from(&rig.set, &wc_table1_calibration, NULL, &rig_config));
    wc_cal_image_encode(&rig.set, rig.reference);
    assert_false(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
    c = protected_config(false);
    c.random = NULL;
    assert_false(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
    static const uint32_t bad[][2] = { { 0u, 6u }, { 7u, 6u }, { 4u, 0u }, { 4u, 7u } };
    for (uint32_t i = 0u; i < sizeof bad / sizeof bad[0]; ++i) {
        c = protected_config(false);
        c.seed_bytes = bad[i][0];
        c.key_bytes = bad[i][1];
        assert_false(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
    }
    static const uint32_t bad_lockout[][2] = { { 0u, 10u }, { 256u, 10u }, { 3u, 0u },
                                               { 3u, WC_XCP_UNLOCK_DELAY_MAX_STEPS + 1u } };
    for (uint32_t i = 0u; i < sizeof bad_lockout / sizeof bad_lockout[0]; ++i) {
        c = protected_config(false);
        c.unlock_attempts = bad_lockout[i][0];
        c.unlock_delay_steps = bad_lockout[i][1];
        assert_false(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
    }
    c = protected_config(false);
    c.seed_bytes = WC_XCP_SEED_MAX_BYTES;
    c.key_bytes = 1u;
    c.unlock_attempts = 255u;
    c.unlock_delay_steps = WC_XCP_UNLOCK_DELAY_MAX_STEPS;
    assert_true(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
    c = (wc_xcp_config_t)WC_XCP_CONFIG_DEFAULT;  /* without the hooks the attempts are not looked at */
    c.unlock_attempts = 0u;
    c.unlock_delay_steps = 0u;
    assert_true(wc_xcp_init(&rig.xcp, &rig.loop, rig.reference, &c));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_hooks_nothing_protected),
        cmocka_unit_test(test_cal_pag_locked_until_unlock),
        cmocka_unit_test(test_wrong_key_disconnects),
        cmocka_unit_test(test_wrong_keys_counted_then_locked_out),
        cmocka_unit_test(test_count_starts_again),
        cmocka_unit_test(test_daq_protected_by_config),
        cmocka_unit_test(test_seed_errors),
        cmocka_unit_test(test_init_refuses_half_protection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
