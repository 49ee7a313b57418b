/* XCP on CAN slave (ASAM MCD-1 XCP 1.x, CAN transport layer; DESIGN 13):
 * what a calibration tool (CANape, INCA, pyxcp) needs to read and change a
 * running clutch controller. Portable (no OS calls), no heap, every loop
 * bounded by a compile-time constant.
 *
 * Frames: XcpCommand (master -> slave) and XcpResponse (slave -> master) of
 * hil/wetclutch.dbc, the lowest-priority ids of the database; not E2E frames.
 * Responses and DAQ frames are padded to DLC 8.
 *
 * Commands: CONNECT, DISCONNECT, GET_STATUS, SYNCH, GET_COMM_MODE_INFO,
 * GET_ID, SET_MTA, UPLOAD, SHORT_UPLOAD, DOWNLOAD, BUILD_CHECKSUM (XCP_CRC_32),
 * calibration pages SET_CAL_PAGE, GET_CAL_PAGE, COPY_CAL_PAGE,
 * GET_PAG_PROCESSOR_INFO; dynamic DAQ: GET_DAQ_PROCESSOR_INFO,
 * GET_DAQ_RESOLUTION_INFO, GET_DAQ_EVENT_INFO, GET_DAQ_CLOCK, FREE_DAQ,
 * ALLOC_DAQ, ALLOC_ODT, ALLOC_ODT_ENTRY, SET_DAQ_PTR, WRITE_DAQ,
 * SET_DAQ_LIST_MODE, START_STOP_DAQ_LIST, START_STOP_SYNCH. Any other
 * command: ERR_CMD_UNKNOWN. A command before CONNECT is ignored (no
 * response), as the standard says; a command frame shorter than its
 * parameters: ERR_CMD_SYNTAX. Upload and download at most 7 / 6 bytes a
 * command (no block mode), address granularity BYTE, Intel byte order.
 *
 * Seed & key (GET_SEED, UNLOCK; DESIGN 17): with the integrator's random
 * and key hooks in the config, CAL/PAG is protected (DOWNLOAD, SET_CAL_PAGE,
 * GET_CAL_PAGE, COPY_CAL_PAGE, GET_PAG_PROCESSOR_INFO answer
 * ERR_ACCESS_LOCKED while locked), and DAQ (every DAQ command) too when
 * config.protect_daq; UPLOAD, SHORT_UPLOAD, BUILD_CHECKSUM and GET_ID stay
 * open (measurement reads). Both hooks NULL: nothing protected (a trusted
 * bus, as before). CONNECT's RESOURCE byte gives the resources available,
 * GET_STATUS's second byte the ones still locked (the standard's layouts).
 * GET_SEED mode 0 (first part) with one resource bit: a new seed of
 * config.seed_bytes from the random hook (false: ERR_RESOURCE_TEMPORARY_
 * NOT_ACCESSIBLE), length 0 when that resource is not locked; seed and key
 * fit one frame each (at most WC_XCP_SEED_MAX_BYTES / WC_XCP_KEY_MAX_BYTES),
 * so mode 1 (remaining part) is ERR_SEQUENCE. UNLOCK without a seed:
 * ERR_SEQUENCE; every UNLOCK consumes the seed; a key other than the key
 * hook's (or of another length): ERR_ACCESS_LOCKED and the session
 * disconnected, as the standard says. DISCONNECT (and a wrong key) restores
 * the protection. The library hand-rolls no cryptography.
 * Failed attempts (DESIGN 17): the wrong keys in a row are counted across
 * sessions (a DISCONNECT or a new CONNECT does not reset the count; a right
 * key does); at config.unlock_attempts of them a lock-out of
 * config.unlock_delay_steps control steps (wc_xcp_step with control_step)
 * begins, during which GET_SEED of a protected resource answers
 * ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE (the GET_SEED row of the XCP 1.x
 * error matrix: "access to the requested resource is temporary not
 * possible"; ERR_ACCESS_LOCKED is not in that row), so no key can be tried;
 * the protected commands keep answering ERR_ACCESS_LOCKED. The lock-out's
 * end starts the count from 0. A start (wc_xcp_init) has no lock-out.
 *
 * Build option WC_XCP_READ_ONLY (a production build): DOWNLOAD,
 * SET_CAL_PAGE and COPY_CAL_PAGE are removed (ERR_CMD_UNKNOWN); the
 * controller stays on the page it started on.
 *
 * Memory the master may touch (anything else: ERR_ACCESS_DENIED; a write
 * to a read-only region: ERR_WRITE_PROTECTED), addresses with extension 0:
 *   calibration segment 0 at cal_base: the calibration image's payload
 *       (wc_cal_image.h), page 0 = the RAM working page (read/write), page
 *       1 = the reference page (read only: the image the TCU started from);
 *   measurement at loop_base: the wc_loop_t (read only);
 *   slave status at status_base: wc_xcp_status_t (read only);
 *   identification at id_base: the GET_ID texts (read only);
 *   gearbox at gearbox_base: the gearbox image's payload (wc_gearbox_image.h)
 *       of the transmission the TCU runs (read only: a gearbox is flashed,
 *       not tuned while it drives); wc_xcp_set_gearbox gives it, and
 *       without one the region answers ERR_ACCESS_DENIED;
 *   element e (0 .. WC_GEARBOX_ELEMENTS_MAX - 1) at element_base +
 *       e WC_XCP_ELEMENT_STRIDE: that element's calibration image payload
 *       (wc_cal_image.h: its clutch; shift control off), read only, given
 *       by wc_xcp_set_element (else ERR_ACCESS_DENIED). Online calibration
 *       of a running transmission's elements is not there
 *       (wc_loop_recalibrate refuses a transmission).
 * On a 64-bit host the bases are offsets the slave reports (wc_xcp_init's
 * config, printed by wc_tcu --xcp-layout); on a 32-bit target they may be
 * the objects' addresses. The A2L (tools/wetclutch/generate/a2l.py) takes
 * them from the linked program.
 *
 * Calibration: the ECU uses page 0 or 1 (SET_CAL_PAGE). A DOWNLOAD changes
 * only the working page; once per wc_xcp_step, if the working page changed
 * and the ECU uses it, the whole page is decoded and checked
 * (wc_cal_image_decode: the same rules as at init) and only then given to
 * the loop (wc_loop_recalibrate: the next control period uses it); a page
 * that fails is not used at all: the last good calibration stays, the
 * status says why (wc_xcp_status_t.page_result / page_error, readable by
 * UPLOAD and DAQ) and an EV_USER event packet carries the same two codes.
 * The shift control's presence and the control period cannot change online
 * (rejected as WC_XCP_PAGE_NOT_ONLINE).
 *
 * DAQ: dynamic lists, one event channel (0, "control_step": the control
 * step, cycle = the calibration's control period), sampled once per step
 * after the step's outputs, every list with a 2-byte timestamp in its first
 * ODT (TIMESTAMP_FIXED: the step counter, one tick a control period;
 * GET_DAQ_RESOLUTION_INFO says so) and absolute ODT numbers as PIDs. At
 * most WC_XCP_DAQ_FRAMES_PER_STEP DAQ frames a step: a list that does not
 * fit in the step is not sampled in it (never a partial list), counted in
 * daq_overloads, and the first overload after a start sends EV_DAQ_OVERLOAD.
 *
 * Who calls what (the contract of wc_loop.h): wc_xcp_receive may run in the
 * CAN receive interrupt (single-producer/single-consumer ring; it writes
 * only rx_tail and the rx counters); wc_xcp_step runs in the control task
 * right after wc_loop_step and after the port has handed the step's frames
 * (VfsCommand first) to its transmit queue, so that XCP never delays or
 * displaces a control frame; wc_xcp_init before the interrupt is enabled.
 * The cost of one wc_xcp_step is bounded: one command (a master waits for
 * each response; more queued frames wait for the next steps), one page
 * check, WC_XCP_DAQ_FRAMES_PER_STEP frames (docs/results.md and
 * bench/arm_ceilings.txt give the instruction counts). */
#ifndef WC_XCP_H
#define WC_XCP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wc_cal_image.h"
#include "wc_can_frame.h"
#include "wc_loop.h"
#include <wetclutch/wc_gearbox.h>

#define WC_XCP_RX_CAPACITY 4u            /* command frames buffered between two steps (power of two) */
#define WC_XCP_DAQ_LISTS 4u              /* dynamic DAQ lists */
#define WC_XCP_ODTS 24u                  /* ODTs over all lists (PIDs 0..23) */
#define WC_XCP_ODT_ENTRIES 96u           /* ODT entries over all lists */
#define WC_XCP_DAQ_FRAMES_PER_STEP 12u   /* DAQ frames sent per control step at most */
/* the command's response or error, a page event, the DAQ frames and an overload event */
#define WC_XCP_TX_FRAMES (3u + WC_XCP_DAQ_FRAMES_PER_STEP)
#define WC_XCP_CHECKSUM_MAX_BYTES 4096u  /* BUILD_CHECKSUM block size limit (a step's bounded cost) */
#define WC_XCP_ID_BYTES 96u
#define WC_XCP_SEED_MAX_BYTES 6u         /* one GET_SEED response (MAX_CTO - 2) */
#define WC_XCP_KEY_MAX_BYTES 6u          /* one UNLOCK command (MAX_CTO - 2) */

/* Command codes (ASAM XCP part 2). */
enum {
    WC_XCP_CONNECT = 0xFF, WC_XCP_DISCONNECT = 0xFE, WC_XCP_GET_STATUS = 0xFD, WC_XCP_SYNCH = 0xFC,
    WC_XCP_GET_COMM_MODE_INFO = 0xFB, WC_XCP_GET_ID = 0xFA, WC_XCP_SET_MTA = 0xF6, WC_XCP_UPLOAD = 0xF5,
    WC_XCP_SHORT_UPLOAD = 0xF4, WC_XCP_BUILD_CHECKSUM = 0xF3, WC_XCP_DOWNLOAD = 0xF0,
    WC_XCP_SET_CAL_PAGE = 0xEB, WC_XCP_GET_CAL_PAGE = 0xEA, WC_XCP_GET_PAG_PROCESSOR_INFO = 0xE9,
    WC_XCP_COPY_CAL_PAGE = 0xE4, WC_XCP_SET_DAQ_PTR = 0xE2, WC_XCP_WRITE_DAQ = 0xE1,
    WC_XCP_SET_DAQ_LIST_MODE = 0xE0, WC_XCP_START_STOP_DAQ_LIST = 0xDE, WC_XCP_START_STOP_SYNCH = 0xDD,
    WC_XCP_GET_DAQ_CLOCK = 0xDC, WC_XCP_GET_DAQ_PROCESSOR_INFO = 0xDA, WC_XCP_GET_DAQ_RESOLUTION_INFO = 0xD9,
    WC_XCP_GET_DAQ_EVENT_INFO = 0xD7, WC_XCP_FREE_DAQ = 0xD6, WC_XCP_ALLOC_DAQ = 0xD5, WC_XCP_ALLOC_ODT = 0xD4,
    WC_XCP_ALLOC_ODT_ENTRY = 0xD3, WC_XCP_GET_SEED = 0xF8, WC_XCP_UNLOCK = 0xF7
};

/* Resource bits (CONNECT's RESOURCE, GET_STATUS's protection status, GET_SEED's resource). */
enum { WC_XCP_RESOURCE_CAL_PAG = 0x01, WC_XCP_RESOURCE_DAQ = 0x04, WC_XCP_RESOURCE_STIM = 0x08,
       WC_XCP_RESOURCE_PGM = 0x10 };

/* Packet identifiers and error codes (ASAM XCP part 2). */
enum {
    WC_XCP_PID_RES = 0xFF, WC_XCP_PID_ERR = 0xFE, WC_XCP_PID_EV = 0xFD,
    WC_XCP_ERR_CMD_SYNCH = 0x00, WC_XCP_ERR_CMD_BUSY = 0x10, WC_XCP_ERR_DAQ_ACTIVE = 0x11,
    WC_XCP_ERR_CMD_UNKNOWN = 0x20, WC_XCP_ERR_CMD_SYNTAX = 0x21, WC_XCP_ERR_OUT_OF_RANGE = 0x22,
    WC_XCP_ERR_WRITE_PROTECTED = 0x23, WC_XCP_ERR_ACCESS_DENIED = 0x24, WC_XCP_ERR_ACCESS_LOCKED = 0x25,
    WC_XCP_ERR_PAGE_NOT_VALID = 0x26,
    WC_XCP_ERR_MODE_NOT_VALID = 0x27, WC_XCP_ERR_SEGMENT_NOT_VALID = 0x28, WC_XCP_ERR_SEQUENCE = 0x29,
    WC_XCP_ERR_DAQ_CONFIG = 0x2A, WC_XCP_ERR_MEMORY_OVERFLOW = 0x30,
    WC_XCP_ERR_RESOURCE_TEMPORARY_NOT_ACCESSIBLE = 0x33,
    WC_XCP_EV_DAQ_OVERLOAD = 0x06, WC_XCP_EV_USER = 0xFE
};

/* Result of the last page check (wc_xcp_status_t.page_result): a
 * wc_cal_image_result_t code (0 = accepted), or this. */
#define WC_XCP_PAGE_NOT_ONLINE ((uint32_t)WC_CAL_IMAGE_RESULTS)   /* shift on/off or control period changed */

typedef struct {
    uint32_t base;       /* XCP address of the region's byte 0 (extension 0) */
    uint32_t size;       /* bytes */
} wc_xcp_region_t;

/* The slave's configuration: the region bases (on a host: offsets of a
 * virtual address space; WC_XCP_CONFIG_DEFAULT), the identification, the
 * seed & key hooks (as wc_uds.h's). */
typedef struct {
    uint32_t cal_base;
    uint32_t loop_base;
    uint32_t status_base;
    uint32_t id_base;
    const char *ident;        /* GET_ID type 0 (ASCII), at most WC_XCP_ID_BYTES / 2 */
    const char *a2l_name;     /* GET_ID type 1 (A2L file name without path and extension) */
    bool protect_daq;         /* with the hooks: DAQ locked too (CAL/PAG always) */
    uint32_t seed_bytes;      /* 1..WC_XCP_SEED_MAX_BYTES (with the hooks) */
    uint32_t key_bytes;       /* 1..WC_XCP_KEY_MAX_BYTES (with the hooks) */
    /* the integrator's hooks, called with context; both NULL: nothing protected, one NULL: init fails */
    bool (*random)(void *context, uint8_t *seed, uint32_t seed_length);
    bool (*key)(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length);
    void *context;
    uint32_t unlock_attempts;     /* 1..255 wrong keys in a row until the lock-out (with the hooks) */
    uint32_t unlock_delay_steps;  /* the lock-out, 1..WC_XCP_UNLOCK_DELAY_MAX_STEPS control steps (with the hooks) */
    uint32_t gearbox_base;        /* the gearbox region's base (wc_xcp_set_gearbox; last: added with issue 29) */
    uint32_t element_base;        /* element 0's region (wc_xcp_set_element), element e WC_XCP_ELEMENT_STRIDE on */
} wc_xcp_config_t;

#define WC_XCP_ELEMENT_STRIDE 0x00010000u

#define WC_XCP_UNLOCK_DELAY_MAX_STEPS 0x7FFFFFFFu

/* Unprotected (no hooks); 6-byte seed and key once hooks are set; with them 3 wrong keys in a row lock
 * GET_SEED out for 10000 control steps (10 s at the 1 ms period), as UDS SecurityAccess's default (wc_uds.h). */
#define WC_XCP_CONFIG_DEFAULT                                                                          \
    { 0x00010000u, 0x00100000u, 0x00200000u, 0x00300000u, "wetclutch TCU", "wetclutch", false, 6u, 6u, \
      NULL, NULL, NULL, 3u, 10000u, 0x00400000u, 0x00500000u }

/* What the master can read of the slave (UPLOAD, DAQ): the counters and the
 * last page check. */
typedef struct {
    uint32_t commands;            /* commands answered (positive or error) */
    uint32_t errors;              /* error packets sent */
    uint32_t ignored;             /* frames ignored: not connected, empty, extended/remote/error, wrong id */
    uint32_t rx_overflows;        /* command frames lost: ring full */
    uint32_t daq_samples;         /* DAQ list samples sent */
    uint32_t daq_frames;          /* DAQ frames sent */
    uint32_t daq_overloads;       /* list samples skipped: the step's DAQ frame budget was spent */
    uint32_t pages_accepted;      /* calibration pages checked and given to the loop */
    uint32_t pages_rejected;      /* pages refused (the last good one kept) */
    uint32_t page_result;         /* last check: wc_cal_image_result_t (0 OK) or WC_XCP_PAGE_NOT_ONLINE */
    uint32_t page_error;          /* its failing field's code (wc_cal_image_status_t.error) */
    uint32_t ecu_page;            /* the page the controller uses: 0 working, 1 reference */
    uint32_t timestamp;           /* control steps since init: the DAQ timestamp (16 low bits sent) */
} wc_xcp_status_t;

typedef struct {
    const uint8_t *src;   /* resolved at WRITE_DAQ */
    uint8_t size;         /* bytes, 0: not written */
} wc_xcp_odt_entry_t;

typedef struct {
    uint8_t first_entry;
    uint8_t entries;
} wc_xcp_odt_t;

typedef struct {
    uint8_t first_odt;    /* absolute ODT number of the first ODT: its PID */
    uint8_t odts;
    uint8_t mode;         /* SET_DAQ_LIST_MODE bits (TIMESTAMP) + SELECTED + RUNNING */
    uint8_t prescaler;    /* >= 1 */
    uint8_t prescaler_count;
} wc_xcp_daq_list_t;

typedef struct {
    wc_xcp_config_t config;
    wc_loop_t *loop;
    const uint8_t *reference_page;  /* the image's payload the TCU started from (flash) */
    const uint8_t *gearbox_page;    /* the gearbox image's payload (flash); NULL: no gearbox region */
    const uint8_t *element_page[WC_GEARBOX_ELEMENTS_MAX];  /* each element's calibration payload; NULL: none */
    uint8_t working_page[WC_CAL_IMAGE_PAYLOAD_MAX_BYTES];
    wc_cal_set_t sets[2];           /* the decoded working page: the one the loop uses, the next */
    int32_t loop_set;               /* index of sets the loop uses; -1: the integrator's own */
    bool page_dirty;                /* the working page changed since its last check */
    uint32_t xcp_page;              /* the page UPLOAD/DOWNLOAD address: 0 working, 1 reference */
    char id[WC_XCP_ID_BYTES];       /* GET_ID texts, NUL-separated */
    wc_can_frame_t rx[WC_XCP_RX_CAPACITY];
    volatile uint32_t rx_head;      /* written only by wc_xcp_step */
    volatile uint32_t rx_tail;      /* written only by wc_xcp_receive */
    bool connected;
    uint8_t locked;                 /* resource bits still protected (GET_STATUS) */
    uint8_t seed_resource;          /* the resource of the seed sent; 0: no seed waits for its key */
    uint8_t seed[WC_XCP_SEED_MAX_BYTES];
    uint32_t unlock_failures;       /* wrong keys in a row, across sessions (0 again at a right key, a lock-out's end) */
    bool lockout;                   /* a lock-out was started ... */
    uint32_t lockout_end;           /* ... and ends at this status.timestamp (no cost per step) */
    uint32_t mta;                   /* memory transfer address */
    /* DAQ */
    wc_xcp_daq_list_t lists[WC_XCP_DAQ_LISTS];
    wc_xcp_odt_t odts[WC_XCP_ODTS];
    wc_xcp_odt_entry_t entries[WC_XCP_ODT_ENTRIES];
    uint8_t daq_count;              /* allocated lists */
    uint8_t odt_count;              /* allocated ODTs */
    uint8_t entry_count;            /* allocated entries */
    uint8_t alloc_stage;            /* dynamic allocation sequence (wc_xcp.c) */
    uint8_t ptr_list, ptr_odt, ptr_entry;  /* SET_DAQ_PTR */
    bool ptr_valid;
    bool daq_running;
    bool overload_reported;         /* EV_DAQ_OVERLOAD sent since the last start */
    wc_xcp_status_t status;
} wc_xcp_t;

/* Start disconnected, with the working page a copy of reference_payload
 * (wc_cal_image_payload_bytes bytes: the image the loop was initialised
 * from, wc_cal_image.h) and the controller on it, protected resources
 * locked. loop must be initialised (wc_loop_init) from that same
 * calibration. Returns false (slave unusable) on a NULL argument, a
 * reference that does not decode, one hook without the other, or (with the
 * hooks) a seed or key length, unlock_attempts or unlock_delay_steps out of
 * range. */
bool wc_xcp_init(wc_xcp_t *xcp, wc_loop_t *loop, const uint8_t *reference_payload, const wc_xcp_config_t *config);

/* Queue one frame of the XcpCommand id (the port filters by id). Returns
 * false, counting rx_overflows, when the ring is full. */
bool wc_xcp_receive(wc_xcp_t *xcp, const wc_can_frame_t *frame);

/* Process the oldest queued command, check a changed working page once (and give
 * it to the loop), and, when control_step is true (the loop stepped in this
 * iteration), sample the running DAQ lists. Writes the frames to send to
 * out (responses first, then DAQ) and returns their count. */
uint32_t wc_xcp_step(wc_xcp_t *xcp, bool control_step, wc_can_frame_t out[WC_XCP_TX_FRAMES]);

/* The gearbox region's bytes: gearbox_payload (wc_gearbox_image_payload_bytes
 * bytes, wc_gearbox_image.h: the payload of the gearbox image the
 * transmission runs, or the compiled-in table's encoded once at start) must
 * outlive the slave; NULL: the region answers ERR_ACCESS_DENIED again (a DAQ
 * list already pointing into it keeps sampling those bytes, which is why
 * they must outlive the slave). */
void wc_xcp_set_gearbox(wc_xcp_t *xcp, const uint8_t *gearbox_payload);

/* Element e's region: its calibration image payload (wc_cal_image_payload_bytes bytes, the element's clutch
 * as wc_cal_image_encode writes it), which must outlive the slave; NULL: denied again; e out of range: nothing. */
void wc_xcp_set_element(wc_xcp_t *xcp, uint32_t element, const uint8_t *element_payload);

/* The memory regions (for the A2L and wc_tcu --xcp-layout): index 0 cal,
 * 1 loop, 2 status, 3 id, 4 gearbox, then WC_XCP_FIRST_ELEMENT_REGION + e element e. */
#define WC_XCP_FIRST_ELEMENT_REGION 5u
#define WC_XCP_REGIONS (WC_XCP_FIRST_ELEMENT_REGION + WC_GEARBOX_ELEMENTS_MAX)
void wc_xcp_regions(const wc_xcp_t *xcp, wc_xcp_region_t regions[WC_XCP_REGIONS]);

#endif /* WC_XCP_H */
