/* The loop fuzzer's shared parts: fuzz_loop.c (the input format, the records, the entry points),
 * fuzz_loop_check.c (the oracle of the loop's frames), fuzz_loop_xcp.c (the XCP slave beside the loop),
 * fuzz_loop_uds.c (ISO-TP, UDS and a fault memory beside the loop), fuzz_loop_starts.c (the starts inside
 * the whole shift). */
#ifndef FUZZ_LOOP_H
#define FUZZ_LOOP_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wetclutch.h>
#include <wetclutch_can/wc_e2e.h>
#include <wetclutch_can/wc_loop.h>
#include <wetclutch_can/wc_xcp.h>

#include "wc_fuzz_common.h"

/* Records per input. The loop's steps are the fuzzer's cost (a sanitized step with its oracle: 2-4 us), and
 * libFuzzer mutates up to the longest input it has: the bound is the longest scenario an input needs, a whole
 * shift from wc_loop_init (660 periods: seeds_loop.py's whole_shift, about 800 records); every timer is a few
 * hundred steps at most from wc_loop_init or a snapshot (timeouts <= 31 and recovery <= 63 periods, each
 * phase of the whole shift <= 150 periods from its snapshot, the inertia timeout 270 from the middle one,
 * UDS_WAIT_STEPS). It was 4096. */
#define MAX_RECORDS 1024u

typedef struct {
    wc_loop_clock_t clock;
    bool make_valid;
    bool plausible;
    wc_loop_config_t config;
    uint8_t alive_sensors;   /* next alive counter of each E2E frame ("make valid") */
    uint8_t alive_request;
    uint8_t alive_shift;
    uint8_t alive_offgoing;
    bool shift;              /* shift control on */
    bool whole;              /* the whole shift (wc_loop_whole_shift) */
    bool have_whole_tx;      /* OffgoingVfsCommand/EngineTorqueRequest seen: their counters must count */
    uint8_t offgoing_alive;
    uint8_t engine_alive;
    float engine_increase_max_Nm;   /* the widest engine limits of the shift calibrations the loop ran on */
    float engine_reduction_max_Nm;
    uint32_t engine_steps;   /* statistics for WC_FUZZ_VERBOSE: InterventionActive, fallback in the safe state */
    uint32_t fallback_steps;
    bool shift_stepped;      /* the step ran the shift controller (Shift mode, or a shift running before it) */
    uint32_t reports;        /* ShiftReports, and the last one's AbortReason (WC_FUZZ_VERBOSE) */
    uint8_t last_abort;
    uint32_t frames_out;     /* frames the steps returned */
    bool have_tx;            /* a VfsCommand was seen: its counter must count */
    uint8_t tx_alive;
    uint32_t fresh_run;      /* consecutive steps without a timeout bit */
    uint32_t steps;
    uint32_t safe_steps;     /* statistics for WC_FUZZ_VERBOSE */
    uint32_t control_steps;
} harness_t;

extern wc_loop_t loop;                     /* the loop under test (~1 KiB: static, not on the fuzzer's stack) */
extern const wc_calibration_t *const cal;  /* table1 */
extern bool verbose;                       /* WC_FUZZ_VERBOSE */

/* What the fuzzing run executed (printed at exit, scripts/fuzz.sh shows it): inputs and loop steps by kind, the
 * whole shift's steps by phase and by fallback. Counted from the first input on (not the snapshots' prefixes). */
enum { KIND_PLAIN, KIND_SHIFT, KIND_WHOLE_INIT, KIND_WHOLE_SNAPSHOT, KIND_XCP, KIND_UDS, KINDS };
typedef struct {
    bool counting;
    unsigned long inputs[KINDS];
    unsigned long steps[KINDS];
    unsigned long steps_max;
    unsigned long whole_phase_steps[7];     /* wc_shift_phase_t: IDLE .. ABORTED */
    unsigned long whole_fallback_steps[4];  /* WC_SHIFT_FALLBACK_NONE .. RELEASED (the controller's, in Shift mode) */
    unsigned long reports;                  /* ShiftReports */
} run_stats_t;
extern run_stats_t stats;

/* fuzz_loop.c: one wc_loop_iterate and its oracle (then the XCP slave's step); the records of an input; its
 * header (byte 0, the loop configuration, the shift options) into h; a fresh loop (wc_loop_init). */
void iterate(harness_t *h, const wc_can_frame_t *frame, bool tick, unsigned record, bool xcp_waits);
void run_records(harness_t *h, fz_reader_t *r, unsigned *record);
void read_harness_options(harness_t *h, uint8_t options);
float read_header(harness_t *h, fz_reader_t *r, uint8_t *options_out, uint8_t *shift_options_out);
void start_fresh(harness_t *h, uint8_t options, uint8_t shift_options, float theta_start_degC);

/* fuzz_loop_check.c: the oracle after a step (its frames out), and of the counters */
void check_step(harness_t *h, const wc_can_frame_t out[WC_LOOP_TX_FRAMES]);
void check_counters(const harness_t *h);

/* fuzz_loop_xcp.c: the slave beside the loop, started at the input's first XCP frame (false: no slave for
 * this configuration); running; a command frame queued; its step with the oracle; an XCP record's frame;
 * forgotten at an input's start; its statistics (WC_FUZZ_VERBOSE). */
bool xcp_start(const harness_t *h);
bool xcp_running(void);
void xcp_receive(const wc_can_frame_t *f);
void xcp_step(const harness_t *h, bool control_step, unsigned record);
void build_xcp_frame(fz_reader_t *r, wc_can_frame_t *f);
void xcp_reset(void);
void xcp_print(void);

/* fuzz_loop_uds.c: ISO-TP, the UDS server and a fault memory beside the loop, started at the input's first
 * UDS record; running; a UDS record (c its command byte) read and its frame queued; a request-id frame of a
 * frame record queued; the diagnostic step after a loop step (its frames out) with the oracle; forgotten at
 * an input's start; its statistics (WC_FUZZ_VERBOSE). */
bool uds_running(void);
void uds_record(fz_reader_t *r, uint8_t c);
bool uds_receive(const wc_can_frame_t *f);
void uds_step(const wc_can_frame_t *out, unsigned record);
void uds_forget(void);
void uds_print(void);

/* fuzz_loop_starts.c: the snapshots of the scripted prefixes (LLVMFuzzerInitialize), and a start from one
 * (start 1..15: the loop and the harness state as the prefix left them) */
void make_snapshots(void);
void start_from_snapshot(harness_t *h, uint32_t start);

#endif /* FUZZ_LOOP_H */
