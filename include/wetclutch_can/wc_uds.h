/* UDS server (ISO 14229-1:2013, unified diagnostic services; DESIGN 17):
 * takes a complete request (from ISO-TP, wc_isotp.h), physically or
 * functionally addressed, and produces the response bytes, or none.
 * Portable (no OS calls), no heap, every loop bounded by a compile-time
 * constant; the library hand-rolls no cryptography (the seed and the
 * expected key come from the integrator's hooks).
 *
 * Services (clause of ISO 14229-1:2013), sessions, security:
 *   0x10 DiagnosticSessionControl (9.2): 0x01 default, 0x03 extended; the
 *        response carries P2 (ms) and P2* (10 ms units). Every accepted
 *        change re-locks security and forgets started routines.
 *   0x11 ECUReset (9.3): 0x03 softReset only (0x01 hardReset and the others
 *        are not supported: 0x12; the library cannot emulate a power cycle).
 *        The integrator's reset_check may refuse (its NRC, e.g. 0x22 while
 *        the vehicle moves); the reset hook runs in the wc_uds_step that
 *        hands the response's last frame to the port (or, suppressed, in the
 *        next one): the port sends the step's frames, then resets, so no
 *        request reaches the server between the response and the reset.
 *   0x14 ClearDiagnosticInformation (11.2): group 0xFFFFFF or one DTC
 *        number; security.
 *   0x19 ReadDTCInformation (11.3): 0x01 reportNumberOfDTCByStatusMask,
 *        0x02 reportDTCByStatusMask, 0x04 reportDTCSnapshotRecordByDTCNumber
 *        (record 0x01, or 0xFF for all: one record, one identifier,
 *        config.snapshot_did, WC_DTC_SNAPSHOT_BYTES of wc_dtc.h), 0x0A
 *        reportSupportedDTC. DTCFormatIdentifier 0x01 (ISO 14229-1).
 *   0x22 ReadDataByIdentifier (10.2): up to WC_UDS_MAX_DIDS_PER_REQUEST DIDs
 *        of the integrator's table; unsupported ones are left out, none
 *        supported is 0x31.
 *   0x27 SecurityAccess (9.4): one level, 0x01 requestSeed / 0x02 sendKey,
 *        extended session only. The seed from config.random (all zero when
 *        already unlocked), the expected key from config.key; sendKey
 *        without a fresh seed: 0x24; a wrong key: 0x35, and at the
 *        max_attempts-th consecutive one 0x36 and a delay of delay_ms during
 *        which requestSeed is answered 0x37 (also after init when
 *        delay_at_init: a reset does not buy new attempts). The delay's end
 *        resets the count. Every sendKey consumes the seed.
 *   0x31 RoutineControl (13.2): 0x01 startRoutine and 0x03
 *        requestRoutineResults of the integrator's routine table (results
 *        before a start: 0x24); security.
 *   0x3E TesterPresent (9.6): 0x00.
 *   "security": while locked the request gets 0x33 (the security check of
 *   7.5 Figure 5, after the session check). Writes, when they come, take the
 *   same guard (wc_uds_unlocked).
 * Sessions: 0x27 only in the extended session (0x7F in the default one,
 * the services allowed per session, ISO 14229-1:2013 9.2.1); every other
 * service in both. S3 (default 5000 ms): the extended session without a
 * request (or a response in flight) for S3 falls back to the default session
 * and re-locks.
 *
 * Checks in the order of ISO 14229-1:2013 7.5 Figures 5 and 6: service
 * supported (0x11), in the active session (0x7F), security (0x33); then
 * for a service with a sub-function: length >= 2 (0x13), sub-function
 * supported (0x12), sequence (0x24); then the service's own checks (0x13
 * length, 0x31 out of range, 0x22 conditions, 0x14 response too long,
 * 0x35-0x37 security access). Bit 7 of a sub-function byte
 * (suppressPosRspMsgIndicationBit) suppresses the positive response only.
 * Functional requests: the negative responses 0x11, 0x12, 0x31, 0x7E and
 * 0x7F are not sent (ISO 14229-1:2013 7.5); the others are.
 *
 * Who calls what: every function in the control task (never concurrently);
 * wc_uds_step after the control frames were handed to the port (wc_isotp.h).
 * Cost of one wc_uds_step: one wc_isotp_step (wc_isotp.h), at most one
 * request served: at most WC_UDS_MAX_DIDS_PER_REQUEST lookups in a table of
 * WC_UDS_MAX_DIDS and their read hooks, or one pass over the DTCs
 * (WC_DTC_MAX_DEFINITIONS), or one routine or key hook (the integrator's
 * cost: a MAC in the key hook is the largest item), plus one reset hook. */
#ifndef WC_UDS_H
#define WC_UDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wc_can_frame.h"
#include "wc_dtc.h"
#include "wc_isotp.h"

#define WC_UDS_SEED_MAX_BYTES 32u
#define WC_UDS_KEY_MAX_BYTES 32u
#define WC_UDS_MAX_DIDS 64u               /* DID table size */
#define WC_UDS_MAX_DIDS_PER_REQUEST 16u   /* DIDs one 0x22 request may ask for */
#define WC_UDS_MAX_ROUTINES 8u            /* routine table size */

/* Service ids (ISO 14229-1:2013); a positive response is SID + 0x40. */
enum {
    WC_UDS_SID_SESSION = 0x10, WC_UDS_SID_RESET = 0x11, WC_UDS_SID_CLEAR_DTC = 0x14, WC_UDS_SID_READ_DTC = 0x19,
    WC_UDS_SID_READ_DID = 0x22, WC_UDS_SID_SECURITY = 0x27, WC_UDS_SID_ROUTINE = 0x31,
    WC_UDS_SID_TESTER_PRESENT = 0x3E, WC_UDS_NEGATIVE = 0x7F, WC_UDS_POSITIVE_OFFSET = 0x40
};

/* Negative response codes (ISO 14229-1:2013 Annex A.1). */
enum {
    WC_UDS_NRC_SERVICE_NOT_SUPPORTED = 0x11, WC_UDS_NRC_SUBFUNCTION_NOT_SUPPORTED = 0x12,
    WC_UDS_NRC_INCORRECT_LENGTH = 0x13, WC_UDS_NRC_RESPONSE_TOO_LONG = 0x14, WC_UDS_NRC_CONDITIONS = 0x22,
    WC_UDS_NRC_SEQUENCE = 0x24, WC_UDS_NRC_OUT_OF_RANGE = 0x31, WC_UDS_NRC_SECURITY_DENIED = 0x33,
    WC_UDS_NRC_INVALID_KEY = 0x35, WC_UDS_NRC_EXCEEDED_ATTEMPTS = 0x36, WC_UDS_NRC_DELAY_NOT_EXPIRED = 0x37,
    WC_UDS_NRC_SUBFUNCTION_NOT_IN_SESSION = 0x7E, WC_UDS_NRC_SERVICE_NOT_IN_SESSION = 0x7F
};

enum { WC_UDS_SESSION_DEFAULT = 0x01, WC_UDS_SESSION_EXTENDED = 0x03 };
enum { WC_UDS_RESET_HARD = 0x01, WC_UDS_RESET_SOFT = 0x03 };
#define WC_UDS_SUPPRESS_POSITIVE 0x80u     /* suppressPosRspMsgIndicationBit of a sub-function byte */

/* One data identifier: read writes exactly length_bytes bytes to data;
 * false: conditionsNotCorrect (0x22). */
typedef struct {
    uint16_t id;
    uint16_t length_bytes;     /* 1..WC_ISOTP_BUFFER_BYTES - 3 */
    bool (*read)(void *context, uint8_t *data, uint32_t length_bytes);
    void *context;
} wc_uds_did_t;

/* A routine's start or results: the option record (request bytes after the
 * routine id) in, the status record out (at most capacity bytes,
 * *status_length set). Returns 0 (positive) or an NRC (e.g. 0x22, 0x31). */
typedef uint8_t (*wc_uds_routine_fn)(void *context, const uint8_t *option, uint32_t option_length,
                                     uint8_t *status_record, uint32_t capacity, uint32_t *status_length);

typedef struct {
    uint16_t id;
    wc_uds_routine_fn start;     /* 0x01; NULL: 0x31 */
    wc_uds_routine_fn results;   /* 0x03; NULL: 0x31 */
    void *context;
} wc_uds_routine_t;

typedef struct {
    uint32_t period_us;          /* the control period: one wc_uds_step */
    uint32_t p2_ms;              /* P2server_max reported by 0x10 (0..65535) */
    uint32_t p2_star_ms;         /* P2*server_max (0..655350, sent in 10 ms units) */
    uint32_t s3_ms;              /* S3server: non-default session timeout */
    uint32_t seed_bytes;         /* 1..WC_UDS_SEED_MAX_BYTES */
    uint32_t key_bytes;          /* 1..WC_UDS_KEY_MAX_BYTES */
    uint32_t max_attempts;       /* >= 1 consecutive wrong keys until 0x36 and the delay */
    uint32_t delay_ms;           /* the delay (0x37) */
    bool delay_at_init;          /* the delay also runs after init */
    uint16_t snapshot_did;       /* the identifier of the snapshot in 0x19 0x04 */
    const wc_uds_did_t *dids;
    uint32_t did_count;          /* 0..WC_UDS_MAX_DIDS */
    const wc_uds_routine_t *routines;
    uint32_t routine_count;      /* 0..WC_UDS_MAX_ROUTINES */
    wc_dtc_t *dtc;               /* the fault memory (0x14, 0x19); NULL: those services unsupported */
    /* the integrator's hooks, called with context; NULL random or key: no 0x27 (0x11) */
    bool (*random)(void *context, uint8_t *seed, uint32_t seed_length);  /* false: 0x22 */
    bool (*key)(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length);
    uint8_t (*reset_check)(void *context, uint8_t reset_type);  /* 0 or the NRC; NULL: always 0 */
    void (*reset)(void *context, uint8_t reset_type);           /* NULL: no 0x11 (0x12) */
    void *context;
} wc_uds_config_t;

/* P2 50 ms, P2* 5000 ms, S3 5000 ms (ISO 14229-2 defaults), 4-byte seed and key,
 * 3 attempts, 10 s delay, also after init; the tables, the memory and the hooks empty. */
#define WC_UDS_CONFIG_DEFAULT                                                                                 \
    { 1000u, 50u, 5000u, 5000u, 4u, 4u, 3u, 10000u, true, 0xDD00u, NULL, 0u, NULL, 0u, NULL, NULL, NULL, NULL, \
      NULL, NULL }

typedef struct {
    uint32_t requests;           /* requests handled */
    uint32_t positive;           /* positive responses sent */
    uint32_t negative;           /* negative responses sent */
    uint32_t suppressed;         /* no response: suppressPosRsp, or a functional NRC */
    uint32_t invalid_keys;       /* wrong keys (0x35 and 0x36) */
    uint32_t s3_timeouts;        /* falls back to the default session */
    uint32_t resets;             /* reset hook calls */
} wc_uds_counters_t;

typedef struct {
    const wc_uds_config_t *config;  /* the caller's (not copied): it must outlive the server */
    uint32_t s3_steps;           /* the times in steps (rounded up) */
    uint32_t delay_steps;
    uint8_t session;
    bool unlocked;
    bool seed_sent;              /* a seed waits for its key */
    uint8_t seed[WC_UDS_SEED_MAX_BYTES];
    uint32_t failed_attempts;
    uint32_t delay_left_steps;
    uint32_t s3_left_steps;
    bool routine_started[WC_UDS_MAX_ROUTINES];
    uint8_t reset_type;          /* the reset to run after the response; 0: none */
    wc_uds_counters_t counters;
    bool initialised;
} wc_uds_t;

/* Default session, locked, on config (kept by pointer, like its tables and
 * hooks: static const in a firmware). Returns false (unusable: later calls
 * assert) on a NULL argument or a configuration out of range (see the
 * fields; a table pointer NULL with a nonzero count, a DID without read,
 * two entries with one id). */
bool wc_uds_init(wc_uds_t *uds, const wc_uds_config_t *config);

/* Serves one request (length bytes; functional: it came on the functional
 * id). Writes the response to response (capacity bytes, at least 3) and
 * returns its length; 0: no response. */
uint32_t wc_uds_handle(wc_uds_t *uds, const uint8_t *request, uint32_t length, bool functional, uint8_t *response,
                       uint32_t capacity);

/* One control period of time: S3 and the security delay. */
void wc_uds_tick(wc_uds_t *uds);

/* One control step of the whole server: wc_uds_tick, wc_isotp_step (frames
 * to out, returns their count), then a pending reset hook once its response
 * is in out (no request served in that step), else the request that
 * completed, answered through tp. */
uint32_t wc_uds_step(wc_uds_t *uds, wc_isotp_t *tp, wc_can_frame_t *out, uint32_t capacity);

uint8_t wc_uds_session(const wc_uds_t *uds);
bool wc_uds_unlocked(const wc_uds_t *uds);

#endif /* WC_UDS_H */
