/* UDS server (ISO 14229-1:2013; DESIGN 17): the contract is in wc_uds.h.
 * Request and response layouts: the service's clause (wc_uds.h), every
 * multi-byte value big-endian. */
#include "wetclutch_can/wc_uds.h"

#include <string.h>

#include "wetclutch/wc_config.h"

#define MIN_RESPONSE 3u                    /* a negative response: 0x7F, SID, NRC */
#define DTC_FORMAT_ISO14229 0x01u          /* DTCFormatIdentifier (11.3, D.3) */
#define SNAPSHOT_RECORD 0x01u              /* our one DTCSnapshotRecordNumber */
#define SNAPSHOT_ALL_RECORDS 0xFFu
#define ROUTINE_START 0x01u
#define ROUTINE_RESULTS 0x03u
#define SECURITY_SEED 0x01u
#define SECURITY_KEY 0x02u
#define OK 0u                              /* a service's positive result (NRCs are nonzero) */

WC_STATIC_ASSERT(WC_ISOTP_BUFFER_BYTES >= 8u, uds_responses_fit);
WC_STATIC_ASSERT(WC_UDS_MAX_ROUTINES <= 255u, uds_routines_fit);

/* One request being served. */
typedef struct {
    const uint8_t *req;
    uint32_t length;
    uint8_t *rsp;
    uint32_t capacity;
    uint32_t n;          /* response bytes written */
    bool suppress;       /* suppressPosRspMsgIndicationBit */
    bool full;           /* a byte did not fit: responseTooLong */
} call_t;

/* ceil(time / period); time_ms <= 3600000 (wc_uds_init), so the microseconds fit 32 bits. */
static uint32_t steps_of(uint32_t time_ms, uint32_t period_us)
{
    const uint32_t us = time_ms * 1000u;
    return (us / period_us) + (((us % period_us) != 0u) ? 1u : 0u);
}

static bool put(call_t *c, uint32_t byte)
{
    if (c->n >= c->capacity) {
        c->full = true;
        return false;
    }
    c->rsp[c->n] = (uint8_t)(byte & 0xFFu);
    c->n++;
    return true;
}

static bool put16(call_t *c, uint32_t value) { return put(c, value >> 8) && put(c, value); }

static bool put24(call_t *c, uint32_t value) { return put(c, value >> 16) && put(c, value >> 8) && put(c, value); }

static uint32_t get16(const uint8_t *p) { return ((uint32_t)p[0] << 8) | (uint32_t)p[1]; }

static uint32_t get24(const uint8_t *p) { return ((uint32_t)p[0] << 16) | ((uint32_t)p[1] << 8) | (uint32_t)p[2]; }

/* The first response bytes: SID + 0x40 and (for a sub-function service) the sub-function echo. */
static void begin(call_t *c, uint32_t sid) { c->n = 0u; (void)put(c, sid + WC_UDS_POSITIVE_OFFSET); }

/* Figure 6's first check: a sub-function byte is there (>= 2 bytes, else 0x13); its bit 7 suppresses. */
static uint8_t sub_function(call_t *c, uint8_t *sub)
{
    if (c->length < 2u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    *sub = (uint8_t)(c->req[1] & 0x7Fu);
    c->suppress = (c->req[1] & WC_UDS_SUPPRESS_POSITIVE) != 0u;
    return OK;
}

static void lock(wc_uds_t *uds)
{
    uds->unlocked = false;
    uds->seed_sent = false;
}

static void enter_session(wc_uds_t *uds, uint8_t session)
{
    uds->session = session;
    lock(uds);  /* every session change re-locks (9.2.1) */
    for (uint32_t i = 0u; i < WC_UDS_MAX_ROUTINES; ++i) { uds->routine_started[i] = false; }
    uds->s3_left_steps = uds->s3_steps;
}

/* ---------------------------------------------------------------- services */

static uint8_t session_control(wc_uds_t *uds, call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    if ((sub != WC_UDS_SESSION_DEFAULT) && (sub != WC_UDS_SESSION_EXTENDED)) {
        return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED;
    }
    if (c->length != 2u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    enter_session(uds, sub);
    begin(c, WC_UDS_SID_SESSION);
    (void)put(c, sub);
    (void)put16(c, uds->config->p2_ms);             /* P2server_max, 1 ms units (9.2.3) */
    (void)put16(c, uds->config->p2_star_ms / 10u);  /* P2*server_max, 10 ms units */
    return OK;
}

static uint8_t tester_present(call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    if (sub != 0x00u) { return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED; }
    if (c->length != 2u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    begin(c, WC_UDS_SID_TESTER_PRESENT);
    (void)put(c, sub);
    return OK;
}

static uint8_t ecu_reset(wc_uds_t *uds, call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    if ((sub != WC_UDS_RESET_SOFT) || (uds->config->reset == NULL)) { return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED; }
    if (c->length != 2u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    if (uds->config->reset_check != NULL) {
        const uint8_t refused = uds->config->reset_check(uds->config->context, sub);
        if (refused != OK) { return refused; }
    }
    uds->reset_type = sub;  /* runs once the response is out (wc_uds_step) */
    begin(c, WC_UDS_SID_RESET);
    (void)put(c, sub);
    return OK;
}

static const wc_uds_did_t *find_did(const wc_uds_t *uds, uint32_t id)
{
    for (uint32_t i = 0u; (i < WC_UDS_MAX_DIDS) && (i < uds->config->did_count); ++i) {
        if (uds->config->dids[i].id == id) { return &uds->config->dids[i]; }
    }
    return NULL;
}

static uint8_t read_data(const wc_uds_t *uds, call_t *c)
{
    if ((c->length < 3u) || (((c->length - 1u) % 2u) != 0u) || ((c->length - 1u) / 2u > WC_UDS_MAX_DIDS_PER_REQUEST)) {
        return WC_UDS_NRC_INCORRECT_LENGTH;
    }
    begin(c, WC_UDS_SID_READ_DID);
    bool any = false;
    for (uint32_t k = 0u; (k < WC_UDS_MAX_DIDS_PER_REQUEST) && (1u + 2u * k < c->length); ++k) {
        const uint32_t id = get16(&c->req[1u + 2u * k]);
        const wc_uds_did_t *did = find_did(uds, id);
        if (did == NULL) { continue; }  /* left out; none at all is 0x31 below */
        any = true;
        if (c->n + 2u + did->length_bytes > c->capacity) { return WC_UDS_NRC_RESPONSE_TOO_LONG; }
        (void)put16(c, id);
        if (!did->read(did->context, &c->rsp[c->n], did->length_bytes)) { return WC_UDS_NRC_CONDITIONS; }
        c->n += did->length_bytes;
    }
    return any ? OK : WC_UDS_NRC_OUT_OF_RANGE;
}

/* The DTCs whose status matches mask (0x01: their count; 0x02, 0x0A: DTC and status each). */
static uint8_t report_by_mask(const wc_dtc_t *dtc, call_t *c, uint8_t sub, uint8_t mask)
{
    (void)put(c, WC_DTC_STATUS_AVAILABILITY);
    uint32_t count = 0u;
    for (uint32_t i = 0u; (i < WC_DTC_MAX_DEFINITIONS) && (i < dtc->config.count); ++i) {
        const uint8_t status = wc_dtc_status(dtc, i);
        if ((sub != 0x0Au) && ((status & mask & WC_DTC_STATUS_AVAILABILITY) == 0u)) { continue; }
        count++;
        if ((sub != 0x01u) && !(put24(c, dtc->config.definitions[i].number) && put(c, status))) {
            return WC_UDS_NRC_RESPONSE_TOO_LONG;
        }
    }
    if (sub == 0x01u) {
        (void)put(c, DTC_FORMAT_ISO14229);
        (void)put16(c, count);
    }
    return OK;
}

static uint8_t report_snapshot(const wc_uds_t *uds, call_t *c)
{
    const wc_dtc_t *dtc = uds->config->dtc;
    const uint32_t number = get24(&c->req[2]);
    const uint32_t record = c->req[5];
    const uint32_t index = wc_dtc_find(dtc, number);
    if ((index == WC_DTC_NONE) || ((record != SNAPSHOT_RECORD) && (record != SNAPSHOT_ALL_RECORDS))) {
        return WC_UDS_NRC_OUT_OF_RANGE;
    }
    (void)put24(c, number);
    (void)put(c, wc_dtc_status(dtc, index));
    const wc_dtc_snapshot_t *snapshot = wc_dtc_snapshot(dtc, index);
    if (snapshot == NULL) { return OK; }  /* supported, nothing stored: DTC and status only */
    if (c->n + 4u + WC_DTC_SNAPSHOT_BYTES > c->capacity) { return WC_UDS_NRC_RESPONSE_TOO_LONG; }
    (void)put(c, SNAPSHOT_RECORD);
    (void)put(c, 1u);  /* DTCSnapshotRecordNumberOfIdentifiers */
    (void)put16(c, uds->config->snapshot_did);
    wc_dtc_snapshot_encode(snapshot, &c->rsp[c->n]);
    c->n += WC_DTC_SNAPSHOT_BYTES;
    return OK;
}

static uint8_t read_dtc_information(const wc_uds_t *uds, call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    uint32_t expected_length = 0u;
    switch (sub) {
    case 0x01u:
    case 0x02u: expected_length = 3u; break;
    case 0x04u: expected_length = 6u; break;
    case 0x0Au: expected_length = 2u; break;
    default: return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED;
    }
    if (c->length != expected_length) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    begin(c, WC_UDS_SID_READ_DTC);
    (void)put(c, sub);
    if (sub == 0x04u) { return report_snapshot(uds, c); }
    return report_by_mask(uds->config->dtc, c, sub, (sub == 0x0Au) ? 0u : c->req[2]);
}

static uint8_t clear_dtc(const wc_uds_t *uds, call_t *c)
{
    if (c->length != 4u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    if (!wc_dtc_clear(uds->config->dtc, get24(&c->req[1]))) { return WC_UDS_NRC_OUT_OF_RANGE; }
    begin(c, WC_UDS_SID_CLEAR_DTC);
    return OK;
}

/* Equal without an early exit (the time does not tell how many bytes matched). */
static bool same_bytes(const uint8_t *a, const uint8_t *b, uint32_t length)
{
    uint32_t diff = 0u;
    for (uint32_t i = 0u; (i < WC_UDS_KEY_MAX_BYTES) && (i < length); ++i) { diff |= (uint32_t)(a[i] ^ b[i]); }
    return diff == 0u;
}

static uint8_t security_access(wc_uds_t *uds, call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    const wc_uds_config_t *cfg = uds->config;
    if (sub == SECURITY_SEED) {
        if (c->length != 2u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
        if (uds->delay_left_steps > 0u) { return WC_UDS_NRC_DELAY_NOT_EXPIRED; }
        if (uds->unlocked) {
            memset(uds->seed, 0, sizeof uds->seed);  /* already unlocked: a zero seed (9.4.1) */
            uds->seed_sent = false;
        } else {
            if (!cfg->random(cfg->context, uds->seed, cfg->seed_bytes)) { return WC_UDS_NRC_CONDITIONS; }
            uds->seed_sent = true;
        }
        begin(c, WC_UDS_SID_SECURITY);
        (void)put(c, sub);
        for (uint32_t i = 0u; (i < WC_UDS_SEED_MAX_BYTES) && (i < cfg->seed_bytes); ++i) { (void)put(c, uds->seed[i]); }
        return OK;
    }
    if (sub != SECURITY_KEY) { return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED; }
    if (!uds->seed_sent) { return WC_UDS_NRC_SEQUENCE; }  /* no seed to answer (9.4.4) */
    uds->seed_sent = false;                              /* every key consumes the seed */
    if (c->length != 2u + cfg->key_bytes) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    uint8_t expected[WC_UDS_KEY_MAX_BYTES];
    if (!cfg->key(cfg->context, uds->seed, cfg->seed_bytes, expected, cfg->key_bytes)) { return WC_UDS_NRC_CONDITIONS; }
    const bool match = same_bytes(&c->req[2], expected, cfg->key_bytes);
    memset(expected, 0, sizeof expected);
    if (!match) {
        uds->counters.invalid_keys++;
        uds->failed_attempts++;
        if (uds->failed_attempts >= cfg->max_attempts) {
            uds->delay_left_steps = uds->delay_steps;
            return WC_UDS_NRC_EXCEEDED_ATTEMPTS;
        }
        return WC_UDS_NRC_INVALID_KEY;
    }
    uds->unlocked = true;
    uds->failed_attempts = 0u;
    begin(c, WC_UDS_SID_SECURITY);
    (void)put(c, sub);
    return OK;
}

static uint8_t routine_control(wc_uds_t *uds, call_t *c)
{
    uint8_t sub = 0u;
    const uint8_t nrc = sub_function(c, &sub);
    if (nrc != OK) { return nrc; }
    if ((sub != ROUTINE_START) && (sub != ROUTINE_RESULTS)) { return WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED; }
    if (c->length < 4u) { return WC_UDS_NRC_INCORRECT_LENGTH; }
    const uint32_t id = get16(&c->req[2]);
    uint32_t index = WC_UDS_MAX_ROUTINES;
    for (uint32_t i = 0u; (i < WC_UDS_MAX_ROUTINES) && (i < uds->config->routine_count); ++i) {
        if (uds->config->routines[i].id == id) { index = i; }
    }
    if (index == WC_UDS_MAX_ROUTINES) { return WC_UDS_NRC_OUT_OF_RANGE; }
    const wc_uds_routine_t *r = &uds->config->routines[index];
    const wc_uds_routine_fn fn = (sub == ROUTINE_START) ? r->start : r->results;
    if (fn == NULL) { return WC_UDS_NRC_OUT_OF_RANGE; }
    if ((sub == ROUTINE_RESULTS) && !uds->routine_started[index]) { return WC_UDS_NRC_SEQUENCE; }
    begin(c, WC_UDS_SID_ROUTINE);
    (void)put(c, sub);
    (void)put16(c, id);
    uint32_t status_length = 0u;
    const uint8_t result =
        fn(r->context, &c->req[4], c->length - 4u, &c->rsp[c->n], c->capacity - c->n, &status_length);
    if (result != OK) { return result; }
    if (status_length > c->capacity - c->n) { return WC_UDS_NRC_RESPONSE_TOO_LONG; }  /* a hook that overstates */
    c->n += status_length;
    if (sub == ROUTINE_START) { uds->routine_started[index] = true; }
    return OK;
}

/* ---------------------------------------------------------------- server */

/* The negative responses a functional request does not get (7.5). */
static bool suppressed_when_functional(uint8_t nrc)
{
    return (nrc == WC_UDS_NRC_SERVICE_NOT_SUPPORTED) || (nrc == WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED) ||
           (nrc == WC_UDS_NRC_OUT_OF_RANGE) || (nrc == WC_UDS_NRC_SUBFUNCTION_NOT_IN_SESSION) ||
           (nrc == WC_UDS_NRC_SERVICE_NOT_IN_SESSION);
}

static uint8_t serve(wc_uds_t *uds, call_t *c)
{
    const uint8_t sid = c->req[0];
    const wc_uds_config_t *cfg = uds->config;
    const bool security_hooks = (cfg->random != NULL) && (cfg->key != NULL);
    /* Figure 5: supported (0x11), in this session (0x7F), security (0x33) */
    switch (sid) {
    case WC_UDS_SID_SESSION: return session_control(uds, c);
    case WC_UDS_SID_RESET: return ecu_reset(uds, c);
    case WC_UDS_SID_TESTER_PRESENT: return tester_present(c);
    case WC_UDS_SID_READ_DID: return read_data(uds, c);
    case WC_UDS_SID_READ_DTC:
        return (cfg->dtc == NULL) ? WC_UDS_NRC_SERVICE_NOT_SUPPORTED : read_dtc_information(uds, c);
    case WC_UDS_SID_CLEAR_DTC:
        if (cfg->dtc == NULL) { return WC_UDS_NRC_SERVICE_NOT_SUPPORTED; }
        return uds->unlocked ? clear_dtc(uds, c) : WC_UDS_NRC_SECURITY_DENIED;
    case WC_UDS_SID_SECURITY:
        if (!security_hooks) { return WC_UDS_NRC_SERVICE_NOT_SUPPORTED; }
        if (uds->session == WC_UDS_SESSION_DEFAULT) { return WC_UDS_NRC_SERVICE_NOT_IN_SESSION; }
        return security_access(uds, c);
    case WC_UDS_SID_ROUTINE:
        if (cfg->routine_count == 0u) { return WC_UDS_NRC_SERVICE_NOT_SUPPORTED; }
        return uds->unlocked ? routine_control(uds, c) : WC_UDS_NRC_SECURITY_DENIED;
    default: return WC_UDS_NRC_SERVICE_NOT_SUPPORTED;
    }
}

uint32_t wc_uds_handle(wc_uds_t *uds, const uint8_t *request, uint32_t length, bool functional, uint8_t *response,
                       uint32_t capacity)
{
    WC_ASSERT((uds != NULL) && uds->initialised && (request != NULL) && (response != NULL));
    if ((uds == NULL) || !uds->initialised || (request == NULL) || (response == NULL) || (length == 0u) ||
        (capacity < MIN_RESPONSE)) {
        return 0u;
    }
    uds->counters.requests++;
    uds->s3_left_steps = uds->s3_steps;  /* any request keeps the session (S3) */
    call_t c = { request, length, response, capacity, 0u, false, false };
    uint8_t nrc = serve(uds, &c);
    if ((nrc == OK) && c.full) { nrc = WC_UDS_NRC_RESPONSE_TOO_LONG; }
    if (nrc == OK) {
        if (c.suppress) {
            uds->counters.suppressed++;
            return 0u;
        }
        uds->counters.positive++;
        return c.n;
    }
    if (functional && suppressed_when_functional(nrc)) {
        uds->counters.suppressed++;
        return 0u;
    }
    response[0] = WC_UDS_NEGATIVE;
    response[1] = request[0];
    response[2] = nrc;
    uds->counters.negative++;
    return MIN_RESPONSE;
}

void wc_uds_tick(wc_uds_t *uds)
{
    WC_ASSERT((uds != NULL) && uds->initialised);
    if ((uds == NULL) || !uds->initialised) { return; }
    if (uds->delay_left_steps > 0u) {
        uds->delay_left_steps--;
        if (uds->delay_left_steps == 0u) { uds->failed_attempts = 0u; }
    }
    if (uds->session != WC_UDS_SESSION_DEFAULT) {
        if (uds->s3_left_steps > 0u) { uds->s3_left_steps--; }
        if (uds->s3_left_steps == 0u) {  /* S3 expired: the default session, locked */
            uds->counters.s3_timeouts++;
            enter_session(uds, WC_UDS_SESSION_DEFAULT);
        }
    }
}

uint32_t wc_uds_step(wc_uds_t *uds, wc_isotp_t *tp, wc_can_frame_t *out, uint32_t capacity)
{
    WC_ASSERT((uds != NULL) && uds->initialised && (tp != NULL) && (out != NULL));
    if ((uds == NULL) || !uds->initialised || (tp == NULL) || (out == NULL)) { return 0u; }
    wc_uds_tick(uds);
    const uint32_t n = wc_isotp_step(tp, out, capacity);
    if (wc_isotp_sending(tp)) { uds->s3_left_steps = uds->s3_steps; }  /* a response in flight keeps the session */
    if ((uds->reset_type != 0u) && !wc_isotp_sending(tp)) {
        /* the reset's response is in out (its last frame) or was suppressed: the hook runs now, so that the
         * port sends the response and then resets within this step, and no request can reach the server
         * between the two (a tester's next request, sent on the response, would be lost in the reset) */
        const uint8_t type = uds->reset_type;
        uds->reset_type = 0u;
        uds->counters.resets++;
        uds->config->reset(uds->config->context, type);
        return n;  /* a request completed meanwhile is the reset's to drop, not to serve */
    }
    uint32_t length = 0u;
    bool functional = false;
    const uint8_t *request = wc_isotp_request(tp, &length, &functional);
    if (request != NULL) {
        const uint32_t answer = wc_uds_handle(uds, request, length, functional, wc_isotp_response_buffer(tp),
                                              WC_ISOTP_BUFFER_BYTES);
        (void)wc_isotp_respond(tp, answer);
    }
    return n;
}

uint8_t wc_uds_session(const wc_uds_t *uds)
{
    WC_ASSERT(uds != NULL);
    return (uds == NULL) ? (uint8_t)WC_UDS_SESSION_DEFAULT : uds->session;
}

bool wc_uds_unlocked(const wc_uds_t *uds)
{
    WC_ASSERT(uds != NULL);
    return (uds != NULL) && uds->unlocked;
}

static bool tables_valid(const wc_uds_config_t *c)
{
    if (((c->dids == NULL) && (c->did_count > 0u)) || (c->did_count > WC_UDS_MAX_DIDS) ||
        ((c->routines == NULL) && (c->routine_count > 0u)) || (c->routine_count > WC_UDS_MAX_ROUTINES)) {
        return false;
    }
    for (uint32_t i = 0u; (i < WC_UDS_MAX_DIDS) && (i < c->did_count); ++i) {
        const wc_uds_did_t *d = &c->dids[i];
        if ((d->read == NULL) || (d->length_bytes < 1u) || (d->length_bytes > WC_ISOTP_BUFFER_BYTES - 3u)) {
            return false;
        }
        for (uint32_t j = 0u; j < i; ++j) {
            if (c->dids[j].id == d->id) { return false; }
        }
    }
    for (uint32_t i = 0u; (i < WC_UDS_MAX_ROUTINES) && (i < c->routine_count); ++i) {
        for (uint32_t j = 0u; j < i; ++j) {
            if (c->routines[j].id == c->routines[i].id) { return false; }
        }
    }
    return true;
}

bool wc_uds_init(wc_uds_t *uds, const wc_uds_config_t *config)
{
    WC_ASSERT((uds != NULL) && (config != NULL));
    if ((uds == NULL) || (config == NULL)) { return false; }
    memset(uds, 0, sizeof *uds);
    const wc_uds_config_t *c = config;
    const bool valid = (c->period_us >= 100u) && (c->period_us <= 1000000u) && (c->p2_ms <= 0xFFFFu) &&
                       (c->p2_star_ms / 10u <= 0xFFFFu) && (c->s3_ms >= 1u) && (c->s3_ms <= 600000u) &&
                       (c->seed_bytes >= 1u) && (c->seed_bytes <= WC_UDS_SEED_MAX_BYTES) && (c->key_bytes >= 1u) &&
                       (c->key_bytes <= WC_UDS_KEY_MAX_BYTES) && (c->max_attempts >= 1u) &&
                       (c->delay_ms <= 3600000u) && (2u + c->seed_bytes <= WC_ISOTP_BUFFER_BYTES) && tables_valid(c);
    if (!valid) { return false; }
    uds->config = c;
    uds->s3_steps = steps_of(c->s3_ms, c->period_us);
    uds->delay_steps = steps_of(c->delay_ms, c->period_us);
    uds->delay_left_steps = c->delay_at_init ? uds->delay_steps : 0u;
    uds->initialised = true;
    enter_session(uds, WC_UDS_SESSION_DEFAULT);
    return true;
}
