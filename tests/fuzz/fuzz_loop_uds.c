/* The loop fuzzer's diagnostic server (fuzz_loop.h; DESIGN 17): ISO-TP (wc_isotp.h), the UDS server
 * (wc_uds.h) and a fault memory (wc_dtc.h) beside the loop, wired as wc_tcu --uds wires them
 * (src/port/wc_tcu_diag.c): every frame of a UDS record goes to wc_isotp_receive (the loop iterates without
 * it), and after every wc_loop_iterate that stepped the fault memory takes its tests from that step's
 * VfsCommand status word (here: DTC i tests status bit i, 15 of them, level and event debouncing in turn;
 * one more, "memory lost", for a corrupt image), then wc_uds_step writes its frames into their own array.
 * Started at the input's first UDS record (an input without one pays nothing for it).
 *
 * A UDS record (fuzz_loop.c: c & 3 == 3, c bit 4 clear, c bit 7 set; c bit 5: a tick with it) is c bits 2-3,
 * the kind, then a selector byte s and the frame's 8 data bytes:
 *   0  physical: the 8 bytes on the physical request id, DLC 8 (SF, FF, CF, FC as fuzzed);
 *   1  functional: the same on the functional id;
 *   2  a request: a SingleFrame, on the functional id if s bit 7, SF_DL = 1 + (s >> 4 & 7) (8: malformed),
 *      the service id uds_sids[s & 0x0F] (past its end: the first data byte) after the PCI, then the data
 *      bytes; a sendKey (0x27 0x02) carries the key of the last seed the server sent (the key hook's,
 *      "aimed") unless the first data byte's bit 0 is set;
 *   3  a format byte first (fuzz_loop.c's: bit 7 set, DLC = low nibble, flags = bits 4-6) on the id s & 3
 *      picks: physical, functional, the response id (ours: never a request), or a fuzzed 16-bit id (two
 *      bytes more).
 * The first record's s also configures ISO-TP: frames_per_step 1 + (s & 7); N_Bs and N_Cr 10 steps (an
 * input reaches them without being long). The server: 4-byte seed and
 * key (test stand-ins: a counter and an XOR, not a MAC), 3 attempts, a 10-step delay also after init; DIDs
 * F190 (17 characters: a segmented answer), FD01 (temperatures), FD02 (learned values; 0x22 without
 * adaptation), FD03 (loop counters); routine 0x0201 the adaptation reset (wc_loop_request_adaptation_reset);
 * ECUReset's hook ends and starts an operation cycle of the fault memory. The fault memory's image is
 * written whenever it changed (as the integrator does) and read back into a second memory, which must agree.
 *
 * Oracle after every wc_uds_step (abort with a message on violation):
 *  - at most frames_per_step frames, each on the response id, DLC 8, no flags, a valid N_PCI: SF with
 *    SF_DL 1..7, FF with FF_DL 8..WC_ISOTP_BUFFER_BYTES, CF, or FC ContinueToSend / Overflow;
 *  - a request served in the step (the counters say which answer): a positive response starts with the
 *    service id + 0x40; a negative one is 0x7F, the service id and an NRC of ISO 14229-1 Annex A.1 that the
 *    server gives, never one a functional request must not get (0x11, 0x12, 0x31, 0x7E, 0x7F); a positive
 *    ClearDiagnosticInformation or RoutineControl only while unlocked; a positive sendKey only in the
 *    extended session and only with the key hook's key of the server's seed;
 *  - the fault memory: every DTC's status byte consistent (ISO 14229-1 D.2: testFailed and
 *    testFailedThisOperationCycle imply testFailedSinceLastClear; testNotCompletedThisOperationCycle excludes
 *    testFailedThisOperationCycle, testNotCompletedSinceLastClear excludes testFailedSinceLastClear;
 *    warningIndicatorRequested implies confirmedDTC), an entry only for a DTC failed since the clear; its
 *    image read back gives the same status bytes and entries.
 * The loop's own frames are checked by fuzz_loop_check.c before the diagnostic step: diagnostics never
 * change them (the routine's adaptation reset acts at the next step, as ShiftCommand's would). */
#include "fuzz_loop.h"

#include <wetclutch_can/wc_dtc.h>
#include <wetclutch_can/wc_isotp.h>
#include <wetclutch_can/wc_uds.h>

#include "wc_test_diag_hooks.h"  /* tests/c: the hooks' stand-ins */

#define UDS_PHYSICAL_ID WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID
#define UDS_FUNCTIONAL_ID WC_CAN_UDS_FUNCTIONAL_REQUEST_FRAME_ID
#define UDS_RESPONSE_ID WC_CAN_UDS_RESPONSE_FRAME_ID
#define UDS_KEY_BYTES 4u
#define UDS_STATUS_TESTS WC_CAN_STATUS_BITS        /* DTC i: VfsCommand status bit i */
#define UDS_DTCS (UDS_STATUS_TESTS + 1u)           /* and "memory lost" */
#define UDS_DTC_BASE 0xD0A000u
#define SECURITY_SEED_SUB 0x01u
/* N_Bs, N_Cr and the security delay (also after init), in steps of 1 ms: not ISO 15765-2's 1000 ms nor a real
 * delay, so that an input reaches each timeout with a few records (the loop's steps are the fuzzer's cost; the
 * timer code is the same for any length). seeds_loop.py UDS_WAIT_STEPS. */
#define UDS_WAIT_STEPS 10u
#define SECURITY_KEY_SUB 0x02u

/* The services a request record picks (s & 0x0F); past the end the first data byte is the service id. */
static const uint8_t uds_sids[] = {
    WC_UDS_SID_SESSION, WC_UDS_SID_RESET, WC_UDS_SID_CLEAR_DTC, WC_UDS_SID_READ_DTC, WC_UDS_SID_READ_DID,
    WC_UDS_SID_READ_DID, WC_UDS_SID_SECURITY, WC_UDS_SID_SECURITY, WC_UDS_SID_ROUTINE, WC_UDS_SID_TESTER_PRESENT,
    WC_UDS_SID_READ_DTC,
};

typedef struct {
    wc_isotp_t tp;
    wc_uds_t uds;
    wc_uds_config_t config;
    wc_dtc_t dtc;
    wc_dtc_t read_back;                 /* the image read back (the oracle's second memory) */
    wc_dtc_definition_t definitions[UDS_DTCS];
    wc_dtc_snapshot_t environment;
    uint8_t image[WC_DTC_IMAGE_BYTES];
    uint8_t next_seed;                  /* the random hook's counter */
    uint8_t last_seed[WC_UDS_SEED_MAX_BYTES];
    bool seed_seen;                     /* a positive requestSeed with a nonzero seed went out */
    uint32_t resets;                    /* ECUReset hook calls: operation cycles */
    uint32_t frames;                    /* statistics for WC_FUZZ_VERBOSE */
} uds_rig_t;

static uds_rig_t rig;     /* ~6 KiB: static, not on the fuzzer's stack */
static bool uds_on;

static bool uds_random(void *context, uint8_t *seed, uint32_t length)
{
    uds_rig_t *r = context;
    return wc_test_counter_seed(&r->next_seed, seed, length);
}

static bool uds_key(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    (void)context;
    return wc_test_xor_key(seed, seed_length, key, key_length);
}

/* ECUReset: one operation cycle of the fault memory (the loop keeps running: its oracle follows it). */
static void uds_reset(void *context, uint8_t reset_type)
{
    uds_rig_t *r = context;
    (void)reset_type;
    r->resets++;
    wc_dtc_cycle_end(&r->dtc);
    wc_dtc_cycle_start(&r->dtc);
}

static bool read_learned(void *context, uint8_t *data, uint32_t length)
{
    (void)context;
    (void)length;
    if ((loop.config.shift == NULL) || (loop.config.shift->adaptation != 1u)) { return false; }
    wc_test_put_floats_be(data, loop.adapt.values.friction_scale, WC_ADAPT_NODES);
    wc_test_put_floats_be(&data[4u * WC_ADAPT_NODES], loop.adapt.values.confidence, WC_ADAPT_NODES);
    return true;
}

static uint8_t routine_start(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status,
                             uint32_t capacity, uint32_t *status_length)
{
    (void)context;
    (void)option;
    (void)status;
    (void)capacity;
    *status_length = 0u;
    if (option_length != 0u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    return wc_loop_request_adaptation_reset(&loop) ? 0u : (uint8_t)WC_UDS_NRC_CONDITIONS;
}

static uint8_t routine_results(void *context, const uint8_t *option, uint32_t option_length, uint8_t *status,
                               uint32_t capacity, uint32_t *status_length)
{
    (void)context;
    (void)option;
    (void)option_length;
    if (capacity < 1u) { return WC_UDS_NRC_RESPONSE_TOO_LONG; }
    status[0] = loop.adaptation_reset_requested ? 1u : 0u;
    *status_length = 1u;
    return 0u;
}

static const wc_uds_did_t dids[] = {
    { 0xF190u, 17u, wc_test_read_text, "WETCLUTCHFUZZ0001" },
    { 0xFD01u, 12u, wc_test_read_temperatures, &loop },
    { 0xFD02u, (uint16_t)(8u * WC_ADAPT_NODES), read_learned, NULL },
    { 0xFD03u, (uint16_t)(4u * WC_REJECT_REASONS), wc_test_read_rejects, &loop },
};
static const wc_uds_routine_t routines[] = { { 0x0201u, routine_start, routine_results, NULL } };

/* The server beside the loop, at the input's first UDS record (s: its selector byte). */
static void uds_start(uint8_t s)
{
    memset(&rig, 0, sizeof rig);
    rig.next_seed = 0x11u;
    for (uint32_t i = 0u; i < UDS_DTCS; ++i) {
        const bool level = (i % 2u) == 0u;
        rig.definitions[i] = (wc_dtc_definition_t){ UDS_DTC_BASE + i, 5, level ? -5 : -100, level ? 1u : 5u, 1u,
                                                   (uint8_t)(1u + i % 3u), (uint8_t)(i % 4u), level };
    }
    const wc_dtc_config_t dtc_config = { rig.definitions, UDS_DTCS, 3u, UDS_STATUS_TESTS, &rig.environment };
    FZ_CHECK(wc_dtc_init(&rig.dtc, &dtc_config) && wc_dtc_init(&rig.read_back, &dtc_config),
             "wc_dtc_init refused the harness's table");
    wc_dtc_cycle_start(&rig.dtc);
    wc_uds_config_t *c = &rig.config;
    *c = (wc_uds_config_t)WC_UDS_CONFIG_DEFAULT;
    c->period_us = (uint32_t)(cal->control_period_s * 1.0e6f + 0.5f);
    c->key_bytes = UDS_KEY_BYTES;
    c->delay_ms = UDS_WAIT_STEPS;  /* an input can wait it out */
    c->dids = dids;
    c->did_count = (uint32_t)(sizeof dids / sizeof dids[0]);
    c->routines = routines;
    c->routine_count = 1u;
    c->dtc = &rig.dtc;
    c->random = uds_random;
    c->key = uds_key;
    c->reset = uds_reset;
    c->context = &rig;
    FZ_CHECK(wc_uds_init(&rig.uds, c), "wc_uds_init refused the harness's configuration");
    wc_isotp_config_t tp = WC_ISOTP_CONFIG_DEFAULT;
    tp.rx_physical_id = UDS_PHYSICAL_ID;
    tp.rx_functional_id = UDS_FUNCTIONAL_ID;
    tp.tx_id = UDS_RESPONSE_ID;
    tp.frames_per_step = 1u + (s & 7u);
    tp.period_us = c->period_us;
    tp.n_bs_ms = UDS_WAIT_STEPS;  /* not 1000: an input reaches the timeouts without being long */
    tp.n_cr_ms = UDS_WAIT_STEPS;
    FZ_CHECK(wc_isotp_init(&rig.tp, &tp), "wc_isotp_init refused the harness's configuration");
    uds_on = true;
}

bool uds_running(void) { return uds_on; }

void uds_forget(void) { uds_on = false; }

/* A UDS record's frame (see the top of the file), queued for the next step. */
void uds_record(fz_reader_t *r, uint8_t c)
{
    const uint8_t s = fz_u8(r);
    if (!uds_on) { uds_start(s); }
    const uint32_t kind = (c >> 2) & 3u;
    wc_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.dlc = 8u;
    f.id = UDS_PHYSICAL_ID;
    if (kind == 3u) {
        const uint8_t format = fz_u8(r);
        f.dlc = (uint8_t)(format & 0x0Fu);
        f.flags = (uint8_t)((format >> 4) & 0x07u);
        static const uint32_t ids[3] = { UDS_PHYSICAL_ID, UDS_FUNCTIONAL_ID, UDS_RESPONSE_ID };
        f.id = ((s & 3u) < 3u) ? ids[s & 3u] : (uint32_t)fz_u16(r);
    } else if (kind == 1u) {
        f.id = UDS_FUNCTIONAL_ID;
    }
    for (uint32_t i = 0u; i < sizeof f.data; ++i) { f.data[i] = fz_u8(r); }
    if (kind == 2u) {  /* a SingleFrame request */
        const uint8_t first = f.data[0];
        if ((s & 0x80u) != 0u) { f.id = UDS_FUNCTIONAL_ID; }
        const uint32_t pick = s & 0x0Fu;
        const uint8_t sid = (pick < sizeof uds_sids) ? uds_sids[pick] : first;
        for (uint32_t i = sizeof f.data - 1u; i >= 2u; --i) { f.data[i] = f.data[i - 1u]; }
        f.data[0] = (uint8_t)(1u + ((s >> 4) & 7u));  /* N_PCI type SF (0), SF_DL */
        f.data[1] = sid;
        const bool send_key = (sid == WC_UDS_SID_SECURITY) && ((f.data[2] & 0x7Fu) == SECURITY_KEY_SUB);
        if (send_key && rig.seed_seen && ((first & 1u) == 0u)) {  /* aimed: the key hook's key */
            f.data[0] = (uint8_t)(2u + UDS_KEY_BYTES);
            (void)uds_key(&rig, rig.last_seed, rig.config.seed_bytes, &f.data[3], UDS_KEY_BYTES);
        }
    }
    (void)wc_isotp_receive(&rig.tp, &f);  /* a full ring is counted */
}

/* A frame record's frame on a request id, once the server runs: to ISO-TP, as wc_tcu routes it (false: the
 * loop's). */
bool uds_receive(const wc_can_frame_t *f)
{
    if (!uds_on || ((f->id != UDS_PHYSICAL_ID) && (f->id != UDS_FUNCTIONAL_ID))) { return false; }
    (void)wc_isotp_receive(&rig.tp, f);
    return true;
}

/* The NRCs the server gives (ISO 14229-1:2013 Annex A.1; wc_uds.h). */
static bool known_nrc(uint8_t nrc)
{
    static const uint8_t known[] = {
        WC_UDS_NRC_SERVICE_NOT_SUPPORTED, WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED, WC_UDS_NRC_INCORRECT_LENGTH,
        WC_UDS_NRC_RESPONSE_TOO_LONG, WC_UDS_NRC_CONDITIONS, WC_UDS_NRC_SEQUENCE, WC_UDS_NRC_OUT_OF_RANGE,
        WC_UDS_NRC_SECURITY_DENIED, WC_UDS_NRC_INVALID_KEY, WC_UDS_NRC_EXCEEDED_ATTEMPTS,
        WC_UDS_NRC_DELAY_NOT_EXPIRED, WC_UDS_NRC_SUBFUNCTION_NOT_IN_SESSION, WC_UDS_NRC_SERVICE_NOT_IN_SESSION,
    };
    for (size_t i = 0u; i < sizeof known; ++i) {
        if (known[i] == nrc) { return true; }
    }
    return false;
}

static bool functional_silent(uint8_t nrc)
{
    return (nrc == WC_UDS_NRC_SERVICE_NOT_SUPPORTED) || (nrc == WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED) ||
           (nrc == WC_UDS_NRC_OUT_OF_RANGE) || (nrc == WC_UDS_NRC_SUBFUNCTION_NOT_IN_SESSION) ||
           (nrc == WC_UDS_NRC_SERVICE_NOT_IN_SESSION);
}

static void check_frames(const wc_can_frame_t *out, uint32_t n)
{
    FZ_CHECK(n <= rig.tp.config.frames_per_step, "wc_uds_step sent %u frames (at most %u)", (unsigned)n,
             (unsigned)rig.tp.config.frames_per_step);
    for (uint32_t i = 0u; i < n; ++i) {
        const wc_can_frame_t *f = &out[i];
        FZ_CHECK((f->id == UDS_RESPONSE_ID) && (f->dlc == 8u) && (f->flags == 0u), "UDS frame %u: id 0x%x dlc %u flags %u",
                 (unsigned)i, (unsigned)f->id, (unsigned)f->dlc, (unsigned)f->flags);
        const uint32_t type = f->data[0] >> 4;
        const uint32_t low = f->data[0] & 0x0Fu;
        const uint32_t ff_dl = (low << 8) | f->data[1];
        const bool ok = ((type == WC_ISOTP_PCI_SF) && (low >= 1u) && (low <= 7u)) ||
                        ((type == WC_ISOTP_PCI_FF) && (ff_dl >= 8u) && (ff_dl <= WC_ISOTP_BUFFER_BYTES)) ||
                        (type == WC_ISOTP_PCI_CF) ||
                        ((type == WC_ISOTP_PCI_FC) && ((low == WC_ISOTP_FS_CTS) || (low == WC_ISOTP_FS_OVFLW)));
        FZ_CHECK(ok, "UDS frame %u: N_PCI %02x %02x", (unsigned)i, f->data[0], f->data[1]);
    }
}

/* The request the step served and its answer (the counters say which one). */
static void check_answer(const wc_uds_counters_t *before, bool unlocked_before, uint8_t session_before)
{
    const wc_uds_counters_t *k = &rig.uds.counters;
    if (k->requests == before->requests) { return; }
    FZ_CHECK(k->requests == before->requests + 1u, "%u requests in one step", (unsigned)(k->requests - before->requests));
    const uint32_t answers = (k->positive - before->positive) + (k->negative - before->negative) +
                             (k->suppressed - before->suppressed);
    FZ_CHECK(answers == 1u, "a request with %u answers", (unsigned)answers);
    const uint8_t *req = rig.tp.rx_buffer;
    const uint8_t *rsp = rig.tp.tx_buffer;
    const uint8_t sid = req[0];
    const bool functional = rig.tp.rx_functional;
    fz_ctx.iargs[0] = sid;
    fz_ctx.iargs[1] = (long)rig.tp.rx_length;
    if (k->negative != before->negative) {
        FZ_CHECK((rig.tp.tx_length == 3u) && (rsp[0] == WC_UDS_NEGATIVE) && (rsp[1] == sid) && known_nrc(rsp[2]),
                 "negative response %02x %02x %02x (length %u) to service %02x", rsp[0], rsp[1], rsp[2],
                 (unsigned)rig.tp.tx_length, sid);
        FZ_CHECK(!functional || !functional_silent(rsp[2]), "NRC %02x to a functional request", rsp[2]);
        return;
    }
    if (k->positive == before->positive) { return; }  /* suppressed */
    FZ_CHECK((rig.tp.tx_length >= 1u) && (rsp[0] == (uint8_t)(sid + WC_UDS_POSITIVE_OFFSET)),
             "positive response %02x to service %02x", rsp[0], sid);
    FZ_CHECK(((sid != WC_UDS_SID_CLEAR_DTC) && (sid != WC_UDS_SID_ROUTINE)) || unlocked_before,
             "service %02x answered positively while locked", sid);
    if ((sid == WC_UDS_SID_SECURITY) && ((req[1] & 0x7Fu) == SECURITY_KEY_SUB)) {
        uint8_t key[UDS_KEY_BYTES];
        (void)uds_key(&rig, rig.uds.seed, rig.config.seed_bytes, key, UDS_KEY_BYTES);
        FZ_CHECK((session_before == WC_UDS_SESSION_EXTENDED) && (rig.tp.rx_length == 2u + UDS_KEY_BYTES) &&
                     (memcmp(&req[2], key, UDS_KEY_BYTES) == 0),
                 "unlocked by a wrong key (session %u)", (unsigned)session_before);
    }
    if ((sid == WC_UDS_SID_SECURITY) && ((req[1] & 0x7Fu) == SECURITY_SEED_SUB) && (rsp[2] != 0u)) {
        memcpy(rig.last_seed, &rsp[2], rig.config.seed_bytes);
        rig.seed_seen = true;
    }
}

/* Every DTC's status byte consistent (ISO 14229-1:2013 D.2), and the image read back the same memory. */
static void check_memory(void)
{
    for (uint32_t i = 0u; i < UDS_DTCS; ++i) {
        const uint8_t st = wc_dtc_status(&rig.dtc, i);
        const bool since_clear = (st & WC_DTC_TFSLC) != 0u;
        FZ_CHECK(((st & (WC_DTC_TF | WC_DTC_TFTOC)) == 0u) || since_clear, "DTC %u status %02x: failed, not since the clear",
                 (unsigned)i, st);
        FZ_CHECK(((st & WC_DTC_TNCTOC) == 0u) || ((st & WC_DTC_TFTOC) == 0u), "DTC %u status %02x", (unsigned)i, st);
        FZ_CHECK(((st & WC_DTC_TNCSLC) == 0u) || !since_clear, "DTC %u status %02x", (unsigned)i, st);
        FZ_CHECK(((st & WC_DTC_WIR) == 0u) || ((st & WC_DTC_CONFIRMED) != 0u), "DTC %u status %02x: warning, not confirmed",
                 (unsigned)i, st);
        FZ_CHECK((wc_dtc_snapshot(&rig.dtc, i) == NULL) || since_clear, "DTC %u status %02x: an entry, no failure",
                 (unsigned)i, st);
    }
    if (!wc_dtc_changed(&rig.dtc)) { return; }
    FZ_CHECK(wc_dtc_image_write(&rig.dtc, rig.image, sizeof rig.image) == sizeof rig.image, "wc_dtc_image_write");
    FZ_CHECK(wc_dtc_image_load(&rig.read_back, rig.image, sizeof rig.image) == (uint32_t)WC_IMAGE_OK,
             "the image just written does not load");
    for (uint32_t i = 0u; i < UDS_DTCS; ++i) {
        FZ_CHECK((wc_dtc_status(&rig.read_back, i) == wc_dtc_status(&rig.dtc, i)) &&
                     ((wc_dtc_snapshot(&rig.read_back, i) == NULL) == (wc_dtc_snapshot(&rig.dtc, i) == NULL)) &&
                     (wc_dtc_fault_count(&rig.read_back, i) == wc_dtc_fault_count(&rig.dtc, i)),
                 "DTC %u read back as %02x, is %02x", (unsigned)i, wc_dtc_status(&rig.read_back, i),
                 wc_dtc_status(&rig.dtc, i));
    }
}

/* After a loop step (its frames out, VfsCommand first): the tests from the status word, one server step. */
void uds_step(const wc_can_frame_t *out, unsigned record)
{
    wc_can_vfs_command_phys_t vfs;
    if (wc_can_decode_vfs_command(&vfs, out[0].data, out[0].dlc) == WC_CAN_OK) {  /* checked before: it decodes */
        rig.environment.slip_speed_rad_s = loop.input.slip_rad_s;
        rig.environment.theta_clutch_degC = loop.clutch.theta_degC;
        rig.environment.theta_oil_degC = loop.input.theta_oil_degC;
        rig.environment.theta_housing_degC = loop.input.theta_housing_degC;
        rig.environment.current_oncoming_mA = loop.last.current_mA;
        rig.environment.shift_phase = (uint8_t)loop.shift.phase;
        for (uint32_t i = 0u; i < UDS_STATUS_TESTS; ++i) { wc_dtc_report(&rig.dtc, i, ((vfs.status >> i) & 1u) != 0u); }
    }
    const wc_uds_counters_t before = rig.uds.counters;
    const bool unlocked_before = wc_uds_unlocked(&rig.uds);
    const uint8_t session_before = wc_uds_session(&rig.uds);
    wc_can_frame_t dout[WC_ISOTP_MAX_FRAMES_PER_STEP];  /* exactly the most a step sends: ASan sees a write past it */
    memset(dout, 0, sizeof dout);
    fz_context("wc_uds_step", record);
    const uint32_t n = wc_uds_step(&rig.uds, &rig.tp, dout, WC_ISOTP_MAX_FRAMES_PER_STEP);
    rig.frames += n;
    check_frames(dout, n);
    check_answer(&before, unlocked_before, session_before);
    check_memory();
}

void uds_print(void)
{
    if (!uds_on) { return; }
    const wc_uds_counters_t *k = &rig.uds.counters;
    const wc_isotp_counters_t *t = &rig.tp.counters;
    fprintf(stderr,
            "fuzz_loop: uds requests %u (positive %u, negative %u, suppressed %u), invalid keys %u, resets %u, "
            "unlocked %d; iso-tp frames in %u out %u, malformed %u, unexpected %u, busy %u, wrong SN %u, "
            "overflows %u; DTC overflows %u\n",
            (unsigned)k->requests, (unsigned)k->positive, (unsigned)k->negative, (unsigned)k->suppressed,
            (unsigned)k->invalid_keys, (unsigned)rig.resets, (int)wc_uds_unlocked(&rig.uds), (unsigned)t->frames_in,
            (unsigned)rig.frames, (unsigned)t->malformed, (unsigned)t->unexpected, (unsigned)t->busy,
            (unsigned)t->wrong_sn, (unsigned)t->rx_overflows, (unsigned)rig.dtc.overflows);
}
