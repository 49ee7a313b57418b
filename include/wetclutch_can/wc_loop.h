/* The CAN frame loop of one clutch: portable (no OS calls), fixed-size
 * receive ring, E2E checks, input freshness, one model step per period and
 * the two output frames. The frames and their scaling are those of
 * hil/wetclutch.dbc (generated codec: wc_can.h, wc_can_signals.h).
 *
 * Who may call what, from where (one wc_loop_t per clutch, no shared state
 * between instances, no locks inside):
 *  - wc_loop_receive may run in the CAN receive interrupt while the task runs
 *    wc_loop_step: the receive ring is single-producer/single-consumer, each
 *    index has one writer (rx_tail: wc_loop_receive, rx_head: wc_loop_step),
 *    and the producer touches nothing else but counters.frames_in and
 *    counters.rejected[WC_REJECT_OVERFLOW]. At most one producer context per
 *    instance (two receive ISRs of different priority need a critical
 *    section around the call). WC_MEMORY_BARRIER orders the index updates
 *    (wc_config.h: a compiler barrier, enough on a single core).
 *  - wc_loop_step, wc_loop_iterate, wc_loop_deadline_missed and reading
 *    counters/last run in one task context (the periodic task); never
 *    concurrently with each other.
 *  - wc_loop_init runs before the interrupt that calls wc_loop_receive is
 *    enabled.
 *
 * Safe-state policy (also in README.md):
 *  - A received frame is used only if its length, CRC and alive counter are
 *    right and every signal is plausible (inside its DBC range, not SNA, Mode
 *    not reserved). Otherwise it is dropped and counted by reason; CRC,
 *    counter and implausible rejections set StatusCrcError /
 *    StatusCounterError / StatusImplausibleInput in the next VfsCommand.
 *  - Between valid frames the last valid value of each input is held.
 *  - An input with no valid frame for its timeout (default 10 periods = 10 ms)
 *    is stale: StatusSensorTimeout or StatusRequestTimeout, plus
 *    StatusSafeStateActive, and the safe output: the solenoid's minimum
 *    current (clutch released: an element that cannot be controlled is opened;
 *    the transmission's limp-home strategy is the integrator's). The observer
 *    keeps running on the held temperatures with the released clutch.
 *  - The first valid frame after a timeout (its counter is taken as the new
 *    reference) ends the safe state for that input.
 *  - Before the first valid frame of each input the loop is in the safe state.
 *  - BenchMeasurement (bench only, no E2E): while fresh (same timeout as the
 *    sensors), its load-cell force replaces the modelled apply force in the
 *    torque model and its measured torque gives the observer's heat input
 *    (the paper's validation, Fig. 14/15; wc_bench_input_t); a negative force
 *    reading (load-cell noise at zero load) counts as 0 N. Stale or absent,
 *    the modelled VFS pressure and model torque are used: no safe state, no
 *    status bit.
 */
#ifndef WC_LOOP_H
#define WC_LOOP_H

#include <stdbool.h>
#include <stdint.h>

#include "wc_can_frame.h"
#include "wc_can_signals.h"
#include <wetclutch/wc_clutch.h>
#include "wc_e2e.h"

#define WC_LOOP_RX_CAPACITY 32u   /* frames buffered between two steps */
#define WC_LOOP_TX_FRAMES 2u      /* VfsCommand, ClutchEstimate */

typedef struct {
    uint32_t sensor_timeout_periods;   /* ClutchSensors freshness limit */
    uint32_t request_timeout_periods;  /* TorqueRequest freshness limit */
} wc_loop_config_t;

#define WC_LOOP_CONFIG_DEFAULT { 10u, 10u }

typedef enum {
    WC_REJECT_CRC = 0,      /* E2E CRC mismatch */
    WC_REJECT_COUNTER,      /* alive counter repeated or jumped */
    WC_REJECT_SHORT,        /* DLC below 8 */
    WC_REJECT_UNKNOWN_ID,   /* not a frame the TCU receives */
    WC_REJECT_FORMAT,       /* extended id, remote or error frame */
    WC_REJECT_IMPLAUSIBLE,  /* signal SNA, out of DBC range, or reserved Mode */
    WC_REJECT_OVERFLOW,     /* receive ring full: frame lost before the step */
    WC_REJECT_REASONS
} wc_loop_reject_t;

typedef struct {
    uint32_t frames_in;                     /* frames offered to wc_loop_receive */
    uint32_t frames_used;                   /* frames that passed every check */
    uint32_t frames_out;                    /* frames produced by wc_loop_step */
    uint32_t rejected[WC_REJECT_REASONS];
    uint32_t sensor_timeouts;               /* fresh -> stale transitions */
    uint32_t request_timeouts;
    uint32_t safe_steps;                    /* steps spent in the safe state */
    uint32_t steps;
    uint32_t deadline_misses;               /* reported by the port */
} wc_loop_counters_t;

typedef struct {
    uint32_t age_periods;           /* periods since the last valid frame */
    bool seen;                      /* a valid frame since init or timeout */
    bool stale;
    wc_e2e_counter_state_t alive;
} wc_loop_input_t;

typedef struct {
    wc_clutch_t clutch;
    wc_loop_config_t config;
    wc_can_frame_t rx[WC_LOOP_RX_CAPACITY];
    volatile uint32_t rx_head;      /* frames taken by wc_loop_step (written only there) */
    volatile uint32_t rx_tail;      /* frames queued by wc_loop_receive (written only there) */
    wc_loop_input_t sensors_in;
    wc_loop_input_t request_in;
    wc_loop_input_t bench_in;
    wc_can_clutch_sensors_phys_t sensors;   /* last valid */
    wc_can_torque_request_phys_t request;   /* last valid */
    wc_can_bench_measurement_phys_t bench;  /* last valid */
    uint16_t pending_status;                /* event bits for the next VfsCommand */
    uint8_t tx_alive;
    wc_loop_counters_t counters;
    wc_step_output_t last;                  /* last step's model output */
} wc_loop_t;

/* Validate the calibration and start in the safe state (no input seen). */
wc_cal_error_t wc_loop_init(wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config,
                            float theta_start_degC);

/* Queue one received frame for the next step. Returns false (and counts
 * WC_REJECT_OVERFLOW) when the ring is full. */
bool wc_loop_receive(wc_loop_t *loop, const wc_can_frame_t *frame);

/* The port missed `missed` step deadlines: counted, flagged in the next VfsCommand. */
void wc_loop_deadline_missed(wc_loop_t *loop, uint32_t missed);

/* One control period: process the queued frames, update freshness, step the
 * model, and write the output frames (VfsCommand, ClutchEstimate) to out.
 * Returns the number of frames written (WC_LOOP_TX_FRAMES). */
uint32_t wc_loop_step(wc_loop_t *loop, wc_can_frame_t out[WC_LOOP_TX_FRAMES]);

/* When a port's main loop steps the model. */
typedef enum {
    WC_LOOP_CLOCK_TIMER = 0,  /* a fixed period: the port passes tick = true at each deadline */
    WC_LOOP_CLOCK_FRAME = 1   /* one step per received ClutchSensors data frame (deterministic replay) */
} wc_loop_clock_t;

/* The work of one iteration of a port's main loop, the same for every port
 * (wc_tcu on SocketCAN, the loop tests with a mocked port): queue frame (NULL
 * when the port's wait ended without one), then step when the clock says so:
 * tick, or with WC_LOOP_CLOCK_FRAME a ClutchSensors data frame. Returns the
 * number of frames written to out for the port to transmit (0 when no step). */
uint32_t wc_loop_iterate(wc_loop_t *loop, wc_loop_clock_t clock, const wc_can_frame_t *frame, bool tick,
                         wc_can_frame_t out[WC_LOOP_TX_FRAMES]);

/* Receive filter ids for the port (the frames wc_loop_receive uses). */
#define WC_LOOP_RX_IDS { WC_CAN_CLUTCH_SENSORS_FRAME_ID, WC_CAN_TORQUE_REQUEST_FRAME_ID, \
                         WC_CAN_BENCH_MEASUREMENT_FRAME_ID }
#define WC_LOOP_RX_ID_COUNT 3u

#endif /* WC_LOOP_H */
