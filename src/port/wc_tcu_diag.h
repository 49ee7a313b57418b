/* wc_tcu --uds: the TCU's diagnostic server on the host (DESIGN 17). The
 * portable ISO-TP transport (wc_isotp.h), UDS server (wc_uds.h) and fault
 * memory (wc_dtc.h) wired to one frame loop, with what only a host program
 * provides: the seed from getrandom(2), the key as HMAC-SHA256(device
 * secret, seed) truncated to the key length by OpenSSL's libcrypto (the
 * secret read from a file), and the fault memory in a file written
 * atomically (wc_atomic_file.h). Not portable core: POSIX, stdio, OpenSSL.
 *
 * Ids from the DBC (generated wc_can.h): requests on UdsPhysicalRequest and
 * UdsFunctionalRequest, answers on UdsResponse.
 *
 * Data identifiers (ReadDataByIdentifier 0x22; numbers big-endian, floats
 * IEEE-754 single big-endian):
 *   0xF18C ECUSerialNumber              --serial TEXT (ASCII)
 *   0xF195 SystemSupplierECUSoftwareVersionNumber  WC_TCU_SOFTWARE_VERSION (ASCII)
 *   0xF197 SystemNameOrEngineType       "wetclutch TCU" (ASCII, the XCP identity)
 *   0xFD00 calibration                  u32 CRC-32 of the calibration image the loop started with (the
 *                                       image's own CRC field, wc_image.h), u16 its layout version
 *   0xFD01 clutch temperatures          f32 clutch estimate, oil, housing (degC)
 *   0xFD02 learned values               WC_ADAPT_NODES f32 friction scales, WC_ADAPT_NODES f32
 *                                       confidences, f32 film factor, f32 kiss offset (Pa), u32 shifts
 *                                       learned; 0x22 when the loop has no adaptation
 *   0xFD03 fault counters               u32 each: the loop's rejects by reason (wc_loop_reject_t order),
 *                                       sensor and request timeouts, frames lost by the port, bus errors,
 *                                       deadline misses, steps in the safe state; then each DTC's fault
 *                                       count in the table's order
 *   0xDD00 the DTC snapshot record's identifier (ReadDTCInformation 0x04, wc_dtc.h)
 * Routine (RoutineControl 0x31, security): 0x0201 adaptation reset (start:
 * wc_loop_request_adaptation_reset, 0x22 when adaptation is off or a shift
 * runs; results: 1 byte, 0 done, 1 pending).
 *
 * ECUReset (0x11) softReset 0x03, as an ECU does it (ISO 14229-1:2013 9.3):
 * refused with 0x22 while a shift runs; else the positive response goes out
 * first, and at the end of the step after it (wc_tcu_diag_reset_pending) the
 * program restarts what a reset restarts: the learned values and the fault
 * memory persisted, the operation cycle ended and a new one started
 * (wc_dtc_cycle_end / _start: one reset is one operation cycle, like one
 * wc_tcu run), the fault memory read back from its image, the UDS server
 * and ISO-TP restarted (default session, locked, the security delay of a
 * start: wc_uds.h delay_at_init), and the loop re-initialised on the
 * calibration it runs (wc_tcu.c: the safe state, then the normal debounced
 * recovery, DESIGN 8).
 *
 * DTCs: the rows of the fault matrix (wc_tcu_diag.c, dtc_table). Each step
 * the VfsCommand status word the loop just produced reports every row's
 * test; an operation cycle is one wc_tcu run, or the time between two
 * soft resets. */
#ifndef WC_TCU_DIAG_H
#define WC_TCU_DIAG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_dtc.h"
#include "wetclutch_can/wc_isotp.h"
#include "wetclutch_can/wc_loop.h"
#include "wetclutch_can/wc_uds.h"
#include "wetclutch_can/wc_xcp.h"
#include "wc_device_secret.h"

#define WC_TCU_SOFTWARE_VERSION "wetclutch 0.1.0"
#define WC_TCU_DIAG_SERIAL_MAX_BYTES 32u
#define WC_TCU_DIAG_TX_FRAMES WC_ISOTP_MAX_FRAMES_PER_STEP
#define WC_TCU_DIAG_DIDS 7u

typedef struct {
    const char *program;          /* for messages */
    const char *secret_file;      /* the device secret (required) */
    const char *dtc_file;         /* the fault memory's image; NULL: in memory only */
    const char *serial;           /* DID 0xF18C */
    uint32_t period_us;           /* the control period */
    uint32_t security_delay_ms;   /* after max attempts, and after start */
    uint32_t frames_per_step;     /* diagnostic frames sent per step at most */
    uint32_t dtc_aging_cycles;    /* fault-free operation cycles until a confirmed DTC ages out (1..255) */
} wc_tcu_diag_options_t;

typedef struct {
    wc_tcu_diag_options_t options;
    wc_loop_t *loop;
    const wc_xcp_t *xcp;          /* NULL: no XCP (its rejected pages are a DTC) */
    wc_isotp_t tp;
    wc_uds_t uds;
    wc_uds_config_t uds_config;
    wc_uds_did_t dids[WC_TCU_DIAG_DIDS];
    wc_uds_routine_t routines[1];
    wc_dtc_t dtc;
    wc_dtc_snapshot_t environment;    /* the operating point, refreshed each step */
    wc_device_secret_t secret;        /* the key of SecurityAccess (wc_device_secret.h) */
    char serial[WC_TCU_DIAG_SERIAL_MAX_BYTES + 1u];
    uint32_t cal_image_crc32;
    uint32_t cal_layout_version;
    uint32_t xcp_pages_rejected_seen;
    bool inputs_started;          /* both control inputs fresh once: the timeout tests run from then on */
    bool reset_requested;         /* routine 0x0201 started, not yet taken by the loop */
    bool ecu_reset_pending;       /* ECUReset answered: the program resets at the end of this step */
    unsigned long ecu_resets;     /* soft resets done */
    unsigned long dtc_writes;
    unsigned long dtc_write_failures;
} wc_tcu_diag_t;

/* Reads the secret, builds the servers over loop (after wc_loop_init and the
 * adaptation image), loads the fault memory from options->dtc_file and
 * starts an operation cycle. cal_image (cal_image_length bytes) is the
 * calibration image the loop runs. Returns 0, or -1 after one line on
 * stderr. */
int wc_tcu_diag_open(wc_tcu_diag_t *diag, const wc_tcu_diag_options_t *options, wc_loop_t *loop,
                     const wc_xcp_t *xcp, const uint8_t *cal_image, size_t cal_image_length);

/* A frame on one of the request ids (the port passes them; the loop must not see them). */
bool wc_tcu_diag_is_request(uint32_t id);

/* Queue a request frame for the next step. */
void wc_tcu_diag_receive(wc_tcu_diag_t *diag, const wc_can_frame_t *frame);

/* After a loop step that produced loop_out (n frames, VfsCommand first):
 * the fault tests from its status word, the snapshot, one server step;
 * writes the diagnostic frames to out (capacity) and returns their count;
 * persists the fault memory when it changed. */
uint32_t wc_tcu_diag_step(wc_tcu_diag_t *diag, const wc_can_frame_t *loop_out, uint32_t n, wc_can_frame_t *out,
                          uint32_t capacity);

/* An ECUReset was answered (its response is on the bus): the caller resets
 * at the end of this step, wc_tcu_diag_reset and the loop's restart. */
bool wc_tcu_diag_reset_pending(const wc_tcu_diag_t *diag);

/* The diagnostic half of a soft reset: the operation cycle ended and the
 * fault memory persisted, read back from its image (kept as it is without
 * --dtc-file), a new cycle started, the servers restarted (their counters
 * kept), the timeout tests waiting for the inputs again. */
void wc_tcu_diag_reset(wc_tcu_diag_t *diag);

/* End of the operation cycle: the memory's cycle end, persisted. */
void wc_tcu_diag_close(wc_tcu_diag_t *diag);

#endif /* WC_TCU_DIAG_H */
