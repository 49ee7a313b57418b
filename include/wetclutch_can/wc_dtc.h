/* Fault memory (DESIGN 17): each fault the integrator tests is a DTC
 * (diagnostic trouble code, ISO 14229-1) with the status byte of ISO
 * 14229-1:2013 D.2, a debounce counter, a snapshot at first failure, ageing
 * over operation cycles, a bounded number of stored entries, fault counters
 * and a persistent image in the format of wc_image.h (DESIGN 12). Portable
 * (no OS calls), no heap, every loop bounded by a compile-time constant.
 *
 * Definitions (wc_dtc_definition_t, the integrator's const table, e.g. one
 * row of the fault matrix each): the 3-byte DTC number, the debounce
 * (a counter that steps up by fail_step on a failed test report and down by
 * pass_step on a passed one, clamped to [pass_threshold, fail_threshold];
 * at fail_threshold the result is "failed", at pass_threshold "passed": a
 * qualified result), the confirmation (confirm_cycles operation cycles with
 * a failure), the priority (displacement) and whether a confirmed DTC
 * requests the warning indicator.
 *
 * The status byte, every bit maintained (ISO 14229-1:2013 D.2):
 *   bit 0 testFailed (TF): the last qualified result was failed.
 *   bit 1 testFailedThisOperationCycle (TFTOC): a failure this cycle; 0 at
 *         cycle start.
 *   bit 2 pendingDTC: a failure this cycle or the last one; 0 at the end of
 *         a cycle in which the test completed without failing.
 *   bit 3 confirmedDTC: failed in confirm_cycles cycles (counted while
 *         pending: a tested fault-free cycle restarts the count); 0 after
 *         ageing, a clear, or the loss of its entry to displacement.
 *   bit 4 testNotCompletedSinceLastClear: 1 after a clear (and on an empty
 *         memory), 0 at the first qualified result.
 *   bit 5 testFailedSinceLastClear: 1 at a failure, 0 only by a clear (kept
 *         through ageing: the history of the fault).
 *   bit 6 testNotCompletedThisOperationCycle: 1 at cycle start, 0 at the
 *         first qualified result in the cycle.
 *   bit 7 warningIndicatorRequested: for a definition with
 *         warning_indicator, 1 while confirmed and not healed: 0 at the end
 *         of a tested fault-free cycle, at ageing and at a clear.
 *   An empty (or cleared) memory reads 0x50 for every DTC.
 *
 * Entries (at most WC_DTC_MAX_ENTRIES): a DTC gets an entry with the
 * snapshot (wc_dtc_snapshot_t, copied from the integrator's struct that
 * config.environment points to) at its first qualified failure while it
 * has none. Displacement when every entry is taken: the new DTC takes the
 * entry of a DTC with a priority number >= its own (0 = most important),
 * choosing one that is not testFailed now, then the largest priority
 * number, then the oldest; the displaced DTC loses confirmedDTC and
 * warningIndicatorRequested. If every stored DTC is more important, the new
 * one is not stored (overflows counted); its status byte is kept.
 * Ageing: at the end of each cycle in which a DTC with an entry or
 * confirmedDTC neither failed (TFTOC 0) nor is failed (TF 0), its ageing
 * counter counts up (a failure restarts it); at config.aging_cycles the
 * entry is removed and confirmedDTC, pendingDTC and warningIndicatorRequested
 * are 0.
 * Fault counters: the number of qualified failures (testFailed 0 -> 1) of
 * each DTC, saturating; cleared with the DTC.
 *
 * Persistence: wc_dtc_image_write / wc_dtc_image_load, the wc_image.h
 * format, magic "WCDT", layout version 1, WC_DTC_IMAGE_PAYLOAD_BYTES
 * bytes, little-endian, byte by byte:
 *     0   u32 the next entry sequence number
 *     4   u32 overflows
 *     8   WC_DTC_MAX_DEFINITIONS slots of 12 bytes: u32 DTC number (0:
 *         unused), u32 fault count, u8 status, u8 failed cycles, u8 ageing
 *         cycles, u8 0
 *     ... WC_DTC_MAX_ENTRIES entries of 44 bytes: u32 DTC number (0: free),
 *         u32 sequence, 8 f32 (the snapshot's floats in struct order), u8
 *         shift phase, u8 gear, u16 0.
 * Slots and entries are matched to the definitions by DTC number (a table
 * reordered by new firmware keeps its history; numbers it no longer has are
 * dropped). A missing image (an erased store) is an empty memory; a corrupt
 * one (truncated, wrong magic, version or length, bad CRC) is an empty
 * memory with config.memory_lost failed at once (confirmed, stored); that
 * DTC passes at the next cycle start (the memory is whole again). The
 * integrator writes the image when wc_dtc_changed says so (a qualified
 * transition, a cycle start or end that changed a bit, a clear, a load
 * that lost the memory); wc_dtc_image_write clears the flag. The debounce
 * counters are not stored (a power cycle restarts them at 0).
 *
 * Who calls what: every function in one task context (the control task),
 * never concurrently. Cost: wc_dtc_report O(1), plus at a first failure one
 * pass over the WC_DTC_MAX_ENTRIES entries; wc_dtc_cycle_start / _end and
 * wc_dtc_clear one pass over the definitions and the entries; the image
 * functions one pass over WC_DTC_IMAGE_BYTES. */
#ifndef WC_DTC_H
#define WC_DTC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <wetclutch/wc_image.h>

#ifndef WC_DTC_MAX_DEFINITIONS
#define WC_DTC_MAX_DEFINITIONS 32u    /* DTCs one memory supports */
#endif
#ifndef WC_DTC_MAX_ENTRIES
#define WC_DTC_MAX_ENTRIES 8u         /* DTCs stored with a snapshot at once */
#endif
#if (WC_DTC_MAX_DEFINITIONS < 1u) || (WC_DTC_MAX_DEFINITIONS > 254u) || (WC_DTC_MAX_ENTRIES < 1u) || \
    (WC_DTC_MAX_ENTRIES > WC_DTC_MAX_DEFINITIONS)
#error "WC_DTC_MAX_DEFINITIONS must be in [1, 254] and WC_DTC_MAX_ENTRIES in [1, WC_DTC_MAX_DEFINITIONS]"
#endif

#define WC_DTC_NONE 0xFFFFFFFFu       /* no definition (config.memory_lost, wc_dtc_find) */
#define WC_DTC_GROUP_ALL 0xFFFFFFu    /* groupOfDTC "all groups" (ISO 14229-1:2013 11.2, Annex D.1) */

/* statusOfDTC bits (ISO 14229-1:2013 D.2). */
#define WC_DTC_TF 0x01u
#define WC_DTC_TFTOC 0x02u
#define WC_DTC_PENDING 0x04u
#define WC_DTC_CONFIRMED 0x08u
#define WC_DTC_TNCSLC 0x10u
#define WC_DTC_TFSLC 0x20u
#define WC_DTC_TNCTOC 0x40u
#define WC_DTC_WIR 0x80u
#define WC_DTC_STATUS_AVAILABILITY 0xFFu   /* every bit is maintained */
#define WC_DTC_STATUS_EMPTY (WC_DTC_TNCSLC | WC_DTC_TNCTOC)

/* The operating point at a DTC's first failure. The integrator fills it
 * each step (config.environment); non-finite values are stored as 0 (NaN)
 * or +-FLT_MAX (infinities). */
typedef struct {
    float slip_speed_rad_s;
    float output_speed_rad_s;
    float turbine_speed_rad_s;
    float theta_clutch_degC;         /* the observer's estimate */
    float theta_oil_degC;
    float theta_housing_degC;
    float current_oncoming_mA;
    float current_offgoing_mA;
    uint8_t shift_phase;             /* wc_shift.h's phase */
    uint8_t gear;
} wc_dtc_snapshot_t;

#define WC_DTC_SNAPSHOT_FLOATS 8u
/* The snapshot as UDS reads it (ReadDTCInformation 0x04): the 8 floats as
 * IEEE-754 single, big-endian (ISO 14229-1 byte order), in struct order,
 * then shift phase and gear. */
#define WC_DTC_SNAPSHOT_BYTES (4u * WC_DTC_SNAPSHOT_FLOATS + 2u)

typedef struct {
    uint32_t number;           /* the DTC, 0x000001..0xFFFFFE */
    int16_t fail_threshold;    /* >= 1: the counter here is a failed result */
    int16_t pass_threshold;    /* <= 0: the counter here is a passed result */
    uint8_t fail_step;         /* >= 1 */
    uint8_t pass_step;         /* >= 1 */
    uint8_t confirm_cycles;    /* >= 1: cycles with a failure until confirmedDTC */
    uint8_t priority;          /* 0 most important (displacement) */
    bool warning_indicator;    /* a confirmed DTC requests the warning indicator (bit 7) */
} wc_dtc_definition_t;

typedef struct {
    const wc_dtc_definition_t *definitions;
    uint32_t count;                         /* 1..WC_DTC_MAX_DEFINITIONS */
    uint32_t aging_cycles;                  /* 1..255 fault-free cycles until a DTC ages out */
    uint32_t memory_lost;                   /* index of the "fault memory lost" DTC, or WC_DTC_NONE */
    const wc_dtc_snapshot_t *environment;   /* the integrator's snapshot, filled each step (NULL: zeros) */
} wc_dtc_config_t;

typedef struct {
    int16_t debounce;          /* the counter */
    uint8_t status;            /* statusOfDTC */
    uint8_t failed_cycles;     /* cycles with a failure while pending (confirmation) */
    uint8_t aging_cycles;      /* fault-free cycles counted toward ageing */
    uint8_t entry;             /* its entry, or WC_DTC_NO_ENTRY */
    uint32_t fault_count;      /* qualified failures, saturating */
} wc_dtc_state_t;

#define WC_DTC_NO_ENTRY 0xFFu

typedef struct {
    uint8_t definition;        /* WC_DTC_NO_ENTRY: free */
    uint32_t sequence;         /* order of storage (displacement takes the oldest) */
    wc_dtc_snapshot_t snapshot;
} wc_dtc_entry_t;

typedef struct {
    wc_dtc_config_t config;
    wc_dtc_state_t state[WC_DTC_MAX_DEFINITIONS];
    wc_dtc_entry_t entries[WC_DTC_MAX_ENTRIES];
    uint32_t next_sequence;
    uint32_t overflows;        /* failures not stored: every entry held a more important DTC */
    bool memory_lost_pending;  /* memory_lost failed at a load: it passes at the next cycle start */
    bool changed;              /* the image differs from the last one written */
    bool initialised;
} wc_dtc_t;

#define WC_DTC_IMAGE_MAGIC 0x54444357u    /* "WCDT" little-endian */
#define WC_DTC_IMAGE_VERSION 1u
#define WC_DTC_SLOT_BYTES 12u
#define WC_DTC_ENTRY_BYTES 44u
#define WC_DTC_IMAGE_PAYLOAD_BYTES \
    (8u + WC_DTC_SLOT_BYTES * WC_DTC_MAX_DEFINITIONS + WC_DTC_ENTRY_BYTES * WC_DTC_MAX_ENTRIES)
#define WC_DTC_IMAGE_BYTES WC_IMAGE_BYTES(WC_DTC_IMAGE_PAYLOAD_BYTES)

/* An empty memory (every status 0x50, no entry) from config (copied; the
 * definitions and the environment are the caller's, and must outlive the
 * memory). Returns false (unusable: later calls assert) on a NULL argument
 * or a configuration out of range: count, a definition's number (0,
 * 0xFFFFFF or above, or twice), threshold, step or confirm_cycles, ageing,
 * memory_lost beyond count. */
bool wc_dtc_init(wc_dtc_t *dtc, const wc_dtc_config_t *config);

/* One result of the test of DTC index (definition order): failed or passed.
 * An index beyond the table is ignored. */
void wc_dtc_report(wc_dtc_t *dtc, uint32_t index, bool failed);

/* Operation cycle (e.g. ignition on .. off, or a power cycle). */
void wc_dtc_cycle_start(wc_dtc_t *dtc);
void wc_dtc_cycle_end(wc_dtc_t *dtc);

/* ClearDiagnosticInformation: group WC_DTC_GROUP_ALL clears every DTC, a
 * DTC number clears that one (status 0x50, no entry, counters 0). Returns
 * false (nothing cleared) for any other group. */
bool wc_dtc_clear(wc_dtc_t *dtc, uint32_t group);

/* The index of DTC number, or WC_DTC_NONE. */
uint32_t wc_dtc_find(const wc_dtc_t *dtc, uint32_t number);

/* Of DTC index: the status byte (0 beyond the table), the stored snapshot
 * (NULL when it has no entry), the fault count (0 beyond the table). */
uint8_t wc_dtc_status(const wc_dtc_t *dtc, uint32_t index);
const wc_dtc_snapshot_t *wc_dtc_snapshot(const wc_dtc_t *dtc, uint32_t index);
uint32_t wc_dtc_fault_count(const wc_dtc_t *dtc, uint32_t index);

/* The memory changed since the last wc_dtc_image_write (or init/load). */
bool wc_dtc_changed(const wc_dtc_t *dtc);

/* Writes the image (WC_DTC_IMAGE_BYTES) and clears the changed flag.
 * Returns the bytes written; 0 (nothing written, flag kept) when image is
 * NULL or capacity too small. */
size_t wc_dtc_image_write(wc_dtc_t *dtc, uint8_t *image, size_t capacity);

/* Replaces the memory by the image's (length bytes at image; NULL/0: no
 * image). Returns the wc_image_status_t of wc_image_read: OK (restored),
 * MISSING (empty memory), anything else (empty memory, memory_lost failed). */
uint32_t wc_dtc_image_load(wc_dtc_t *dtc, const uint8_t *image, size_t length);

/* The UDS form of a snapshot (WC_DTC_SNAPSHOT_BYTES, see above). */
void wc_dtc_snapshot_encode(const wc_dtc_snapshot_t *snapshot, uint8_t out[WC_DTC_SNAPSHOT_BYTES]);

#endif /* WC_DTC_H */
