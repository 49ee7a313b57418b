/* The CAN frame loop of one clutch (its whole shift: two clutches), or of a
 * gearbox's shift elements (the transmission, DESIGN 15): portable (no OS
 * calls), fixed-size receive ring, E2E checks, input freshness, one model
 * step per period and the cyclic output frames. The frames and their scaling are those of
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
 * Safe-state policy (also in docs/integrating.md, with the reaction and
 * recovery periods):
 *  - A received frame is used only if its length, CRC and alive counter are
 *    right and every signal is plausible (inside its DBC range, not SNA, Mode
 *    not reserved). The alive counter follows AUTOSAR E2E Profile 1
 *    (wc_e2e.h): a repeated counter is no new data; one lost frame is
 *    tolerated; any other jump, and the first frame after init or a timeout,
 *    restart the input, whose frames are used again only after SyncCounter
 *    consecutive +1 frames. A rejected frame is counted by reason; CRC,
 *    counter and implausible rejections set StatusCrcError /
 *    StatusCounterError / StatusImplausibleInput in the next VfsCommand;
 *    frames lost before the check (ring full, short, unknown id, format,
 *    port drops) set StatusFrameLost.
 *  - Between used frames the last used value of each input is held.
 *  - An input with no used frame for its timeout (default 10 periods) is
 *    stale: StatusSensorTimeout or StatusRequestTimeout, and its E2E receiver
 *    restarts. While either control input is stale, and until both have been
 *    fresh for recovery_periods (default 20) in a row, the loop outputs the
 *    safe state, StatusSafeStateActive. Outside the whole shift it is the
 *    solenoid's minimum current (clutch released: an element that cannot be
 *    controlled is opened; the transmission's limp-home strategy is the
 *    integrator's). With the whole shift (DESIGN 14, config.offgoing) the
 *    safe state is the fallback of the shift's phase, not a release: in IDLE
 *    and in a hand-back (prepare or torque phase) the off-going clutch holds
 *    1st gear at its maximum current and the on-coming one is released; from
 *    the inertia phase on the on-coming clutch finishes on the model and
 *    holds 2nd gear for at most fallback_time_s, then both are released
 *    (OffgoingVfsCommand.Fallback says which; wc_shift.h). The observer keeps
 *    running on the held temperatures. An input that comes and goes
 *    therefore holds the safe state instead of switching the solenoid.
 *  - With the transmission (config.transmission, DESIGN 15) the control
 *    inputs are GearboxSensors (turbine and output speed, oil and housing
 *    temperature; the sensor timeout, StatusSensorTimeout) and ShiftCommand
 *    (with CurrentGear; the request timeout, StatusRequestTimeout);
 *    ClutchSensors, TorqueRequest and OffgoingSensors are unknown ids. Its
 *    safe state holds the gear: every closed element at its maximum current
 *    (wc_transmission.h), a running shift takes its phase's fallback, no
 *    engine request, no new shift (GearboxStatus.Refusal 7).
 *  - Before the inputs have been fresh for recovery_periods after init, the
 *    loop is in the safe state.
 *  - BenchMeasurement (bench only, no E2E) is used only when
 *    bench_input_enabled (wc_tcu --bench; otherwise it is an unknown id and
 *    the port filters it out). While fresh (same timeout as the sensors),
 *    its load-cell force replaces the modelled apply force in the torque
 *    model and its measured torque gives the observer's heat input (the
 *    paper's validation, Fig. 14/15; wc_bench_input_t), and StatusBenchInput
 *    is set; a negative force reading (load-cell noise at zero load) counts
 *    as 0 N.
 */
#ifndef WC_LOOP_H
#define WC_LOOP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wc_can_frame.h"
#include "wc_can_signals.h"
#include <wetclutch/wc_clutch.h>
#include <wetclutch/wc_shift.h>
#include <wetclutch/wc_transmission.h>
#include "wc_e2e.h"

#define WC_LOOP_RX_CAPACITY 32u   /* frames buffered between two steps */
#define WC_LOOP_TX_CYCLIC 2u      /* every step: VfsCommand, ClutchEstimate */
#define WC_LOOP_TX_WHOLE_SHIFT 2u /* every step too with the whole shift (DESIGN 14): OffgoingVfsCommand, EngineTorqueRequest */
#define WC_LOOP_TX_GEARBOX_CYCLIC (WC_GEARBOX_ELEMENTS_MAX + 2u) /* with the transmission, every step: one
                                  * ElementXVfsCommand per element, GearboxStatus, EngineTorqueRequest */
#define WC_LOOP_TX_FRAMES 9u      /* at most: ... then ShiftReport (and AdaptationReport) in the step a shift ends */

typedef struct {
    uint32_t sensor_timeout_periods;   /* ClutchSensors freshness limit (default 10) */
    uint32_t request_timeout_periods;  /* TorqueRequest freshness limit (default 10) */
    wc_e2e_config_t e2e;               /* MaxDeltaCounter 2 (one lost frame), SyncCounter 3 */
    uint32_t recovery_periods;         /* both inputs fresh this long before the safe state ends (20) */
    bool bench_input_enabled;          /* use BenchMeasurement (bench only; default off) */
    const wc_shift_calibration_t *shift;  /* shift control (DESIGN 10; checked at init); NULL: off */
    /* Adaptation (DESIGN 12, shift calibration adaptation = 1): called from
     * wc_loop_step after the output frames of a step in which the learned
     * values changed (a shift updated them, or a reset by
     * ShiftCommand.AdaptationReset), with the clutch's adaptation state, for
     * the integrator to persist (wc_adapt_image_write). It runs in the control
     * task: it must only copy or schedule (an NVM job), not block. NULL: none. */
    void (*adaptation_changed)(const wc_adapt_t *adapt, void *context);
    void *adaptation_context;
    /* The whole shift (DESIGN 14, shift calibration coordinator = 1): the
     * off-going clutch's own calibration (checked at init; required then).
     * The loop then also receives OffgoingSensors (a control input in Shift
     * mode, with the sensor timeout) and sends OffgoingVfsCommand and
     * EngineTorqueRequest every step after ClutchEstimate. */
    const wc_calibration_t *offgoing;
    /* The transmission (DESIGN 15): a gearbox's shift elements instead of one
     * clutch (checked at init by wc_transmission_init; shift, offgoing and
     * the bench input must then be off: the transmission has its own shift
     * calibration). NULL: one clutch. It starts holding transmission_start_gear. */
    const wc_transmission_config_t *transmission;
    uint32_t transmission_start_gear;
} wc_loop_config_t;

#define WC_LOOP_CONFIG_DEFAULT { 10u, 10u, { 2u, 3u }, 20u, false, NULL, NULL, NULL, NULL, NULL, 1u }

/* The whole shift runs (DESIGN 14): a shift calibration with the coordinator and the off-going clutch's calibration. */
static inline bool wc_loop_whole_shift(const wc_loop_config_t *config)
{
    return (config->shift != NULL) && (config->shift->coordinator == 1u) && (config->offgoing != NULL);
}

/* The loop runs a gearbox's shift elements (DESIGN 15). */
static inline bool wc_loop_gearbox(const wc_loop_config_t *config)
{
    return config->transmission != NULL;
}

typedef enum {
    WC_REJECT_CRC = 0,      /* E2E CRC mismatch */
    WC_REJECT_COUNTER,      /* E2E REPEATED or WRONGSEQUENCE */
    WC_REJECT_SHORT,        /* DLC below 8 */
    WC_REJECT_UNKNOWN_ID,   /* not a frame the TCU receives (BenchMeasurement when bench input is off) */
    WC_REJECT_FORMAT,       /* extended id, remote or error frame */
    WC_REJECT_IMPLAUSIBLE,  /* signal SNA, out of DBC range, or reserved Mode */
    WC_REJECT_OVERFLOW,     /* receive ring full: frame lost before the step */
    WC_REJECT_SYNC,         /* E2E SYNC: after a timeout or wrong sequence, waiting for SyncCounter frames */
    WC_REJECT_REASONS
} wc_loop_reject_t;

typedef struct {
    uint32_t frames_in;                     /* frames offered to wc_loop_receive */
    uint32_t frames_used;                   /* frames that passed every check */
    uint32_t frames_out;                    /* frames produced by wc_loop_step */
    uint32_t rejected[WC_REJECT_REASONS];
    uint32_t sensor_timeouts;               /* fresh -> stale transitions */
    uint32_t frames_lost_by_port;           /* reported by the port (kernel drops) */
    uint32_t bus_errors;                    /* reported by the port (error passive, bus-off, tx failure) */
    uint32_t request_timeouts;
    uint32_t safe_steps;                    /* steps spent in the safe state */
    uint32_t steps;
    uint32_t deadline_misses;               /* reported by the port */
} wc_loop_counters_t;

typedef struct {
    uint32_t age_periods;           /* periods since the last frame used */
    bool seen;                      /* a frame used since init or timeout */
    bool stale;
    wc_e2e_receiver_t e2e;
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
    wc_loop_input_t shift_in;
    wc_loop_input_t offgoing_in;            /* OffgoingSensors (the whole shift) */
    wc_can_clutch_sensors_phys_t sensors;   /* last valid */
    wc_can_offgoing_sensors_phys_t offgoing_sensors;  /* last valid */
    wc_can_shift_command_phys_t shift_command;  /* last valid */
    wc_shift_t shift;                       /* the shift controller (config.shift) */
    wc_shift_report_t report;               /* the last shift's quality vector */
    wc_adapt_t adapt;                       /* the clutch's learned values (DESIGN 12) */
    bool last_adaptation_reset;             /* ShiftCommand.AdaptationReset at the last step (edge) */
    wc_can_torque_request_phys_t request;   /* last valid */
    wc_can_bench_measurement_phys_t bench;  /* last valid */
    uint32_t fresh_periods;                 /* consecutive periods with both control inputs fresh */
    uint32_t overflows_seen;                /* rejected[WC_REJECT_OVERFLOW] at the last step */
    uint16_t pending_status;                /* event bits for the next VfsCommand */
    uint8_t tx_alive;
    wc_loop_counters_t counters;
    wc_step_output_t last;                  /* last step's model output */
    wc_step_input_t input;                  /* last step's clutch input (in Shift mode as the controller set it) */
    wc_shift_command_t command;             /* last Shift-mode step's command to the shift controller */
    /* The whole shift (DESIGN 14; config.offgoing) */
    wc_clutch_t offgoing;                   /* the off-going clutch */
    wc_step_input_t offgoing_input;
    wc_step_output_t offgoing_last;
    wc_shift_offgoing_t whole;              /* the shift controller's view of them (pointers into this loop) and
                                             * the engine request of the last step */
    uint8_t tx_alive_offgoing;
    uint8_t tx_alive_engine;
    bool adaptation_reset_requested;        /* wc_loop_request_adaptation_reset: taken at the next step */
    /* The transmission (DESIGN 15; config.transmission) */
    wc_loop_input_t gearbox_in;             /* GearboxSensors */
    wc_can_gearbox_sensors_phys_t gearbox_sensors;  /* last valid */
    wc_transmission_t transmission;
    wc_transmission_command_t transmission_command;  /* this step's, from ShiftCommand */
    wc_transmission_input_t transmission_input;      /* this step's, from GearboxSensors */
    wc_transmission_output_t transmission_out;       /* the last step's (the controllers read it back) */
    uint8_t tx_alive_element[WC_GEARBOX_ELEMENTS_MAX];
    uint8_t tx_alive_status;
} wc_loop_t;

/* Validate the calibration (and the shift calibration: a failing one returns
 * WC_CAL_NULL) and start in the safe state (no input seen). With the
 * transmission cal is not used (may be NULL: each element has its own in
 * config.transmission); a transmission that wc_transmission_init refuses
 * (it says why), or one beside a shift, off-going or bench configuration,
 * returns WC_CAL_NULL. */
wc_cal_error_t wc_loop_init(wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config,
                            float theta_start_degC);

/* Give a running loop another calibration without resetting its state
 * (observer, VFS lag, film, lock-up, E2E receivers, a running shift): the
 * XCP calibration page (wc_xcp.h, DESIGN 13). cal is checked
 * (wc_calibration_check) and config->shift when not NULL; on any failure
 * nothing changes and the failing code is returned (WC_CAL_NULL for the
 * shift calibration, as wc_loop_init). From config the loop takes the
 * timeouts, E2E, recovery and shift calibration; the bench input and the
 * adaptation hook stay as wc_loop_init set them. The control period and
 * the shift control's presence are the port's (its timer, its receive
 * filter): the caller keeps them (wc_xcp refuses a page that changes
 * them). Both objects must outlive their use, as at init. Same context as
 * wc_loop_step, never beside it. A loop with the transmission (either
 * side) refuses with WC_CAL_NULL: its online calibration is not there yet. */
wc_cal_error_t wc_loop_recalibrate(wc_loop_t *loop, const wc_calibration_t *cal, const wc_loop_config_t *config);

/* Load the clutch's learned values from an adaptation image (wc_adapt_image.h)
 * after wc_loop_init, before the first step: an image that is NULL, empty,
 * truncated, of another version or clutch, with a bad CRC-32 or a value
 * outside its band gives the calibration's values and sets
 * WC_ADAPT_STATUS_IMAGE_MISSING / _INVALID (sent in AdaptationReport). Without
 * a call the loop starts from the calibration's values with IMAGE_MISSING.
 * Returns the image load's code (wc_adapt_image.h). */
uint32_t wc_loop_load_adaptation(wc_loop_t *loop, const uint8_t *image, size_t length);

/* Reset the clutch's learned values as ShiftCommand.AdaptationReset does (DESIGN 12), on a diagnostic
 * tester's request (UDS RoutineControl, wc_uds.h): taken at the next wc_loop_step, which then sends the
 * AdaptationReport and calls the adaptation hook; unlike the CAN bit, also in the safe state and in any
 * mode. Returns false (nothing requested) when adaptation is off (no shift calibration, or its adaptation
 * 0) or a shift runs. Same context as wc_loop_step, never beside it. */
bool wc_loop_request_adaptation_reset(wc_loop_t *loop);

/* Queue one received frame for the next step. Returns false (and counts
 * WC_REJECT_OVERFLOW) when the ring is full. */
bool wc_loop_receive(wc_loop_t *loop, const wc_can_frame_t *frame);

/* The port missed `missed` step deadlines: counted, flagged in the next VfsCommand. */
void wc_loop_deadline_missed(wc_loop_t *loop, uint32_t missed);

/* What a port reports about the bus. Each is counted and flagged in the next
 * VfsCommand: frames lost before the loop saw them -> StatusFrameLost; a
 * controller error or a failed transmit -> StatusBusError. */
typedef enum {
    WC_LOOP_PORT_RX_DROPPED = 0,  /* frames dropped by the port or its kernel (count) */
    WC_LOOP_PORT_BUS_ERROR,       /* error passive, bus-off, controller problem (count = events) */
    WC_LOOP_PORT_TX_FAILED        /* a frame could not be sent (count) */
} wc_loop_port_event_t;
void wc_loop_port_event(wc_loop_t *loop, wc_loop_port_event_t event, uint32_t count);

/* One control period: process the queued frames, update freshness, step the
 * model (in Shift mode through the shift controller, wc_shift.h), and write
 * the output frames to out: VfsCommand, ClutchEstimate, and in the step a
 * shift ends its ShiftReport. Returns the number of frames written
 * (WC_LOOP_TX_CYCLIC, or WC_LOOP_TX_FRAMES with a report).
 *
 * Shift mode (TorqueRequest.Mode 3, only with config.shift): ShiftCommand is
 * a third control input (E2E, timeout request_timeout_periods, counted as a
 * request timeout: StatusRequestTimeout) and the safe state applies to it
 * like to the others; a shift running when the safe state begins aborts
 * (released, ShiftReport AbortReason 3), or with the whole shift takes the
 * fallback of its phase (above; wc_shift.h). Leaving Shift mode ends a finished
 * shift at once (the new mode acts in that very period) and aborts a running
 * one (AbortReason 4, released). Without config.shift, Mode 3 is implausible
 * and ShiftCommand an unknown id. */
uint32_t wc_loop_step(wc_loop_t *loop, wc_can_frame_t out[WC_LOOP_TX_FRAMES]);

/* The ShiftReport frame of a shift's quality vector, as wc_loop_step sends
 * it when a shift ends: each figure limited to its DBC range, and Saturated 1
 * when one was (issue 29 item 7: a peak jerk of 117-131 m/s^3 went out as
 * 100 with nothing to say so). */
void wc_loop_shift_report_frame(const wc_shift_report_t *q, wc_can_frame_t *out);

/* When a port's main loop steps the model. */
typedef enum {
    WC_LOOP_CLOCK_TIMER = 0,  /* a fixed period: the port passes tick = true at each deadline */
    WC_LOOP_CLOCK_FRAME = 1   /* one step per received ClutchSensors data frame (with the transmission:
                               * GearboxSensors; deterministic replay) */
} wc_loop_clock_t;

/* The work of one iteration of a port's main loop, the same for every port
 * (wc_tcu on SocketCAN, the loop tests with a mocked port): queue frame (NULL
 * when the port's wait ended without one), then step when the clock says so:
 * tick, or with WC_LOOP_CLOCK_FRAME a ClutchSensors (transmission: GearboxSensors) data frame. Returns the
 * number of frames written to out for the port to transmit (0 when no step). */
uint32_t wc_loop_iterate(wc_loop_t *loop, wc_loop_clock_t clock, const wc_can_frame_t *frame, bool tick,
                         wc_can_frame_t out[WC_LOOP_TX_FRAMES]);

/* All ids the loop can receive: the control frames, ShiftCommand (used only
 * with config.shift or the transmission), OffgoingSensors (only with the
 * whole shift), BenchMeasurement (only with bench_input_enabled),
 * GearboxSensors (only with the transmission, which takes only it and
 * ShiftCommand). */
#define WC_LOOP_RX_IDS { WC_CAN_CLUTCH_SENSORS_FRAME_ID, WC_CAN_TORQUE_REQUEST_FRAME_ID, \
                         WC_CAN_SHIFT_COMMAND_FRAME_ID, WC_CAN_OFFGOING_SENSORS_FRAME_ID, \
                         WC_CAN_BENCH_MEASUREMENT_FRAME_ID, WC_CAN_GEARBOX_SENSORS_FRAME_ID }
#define WC_LOOP_RX_ID_COUNT 6u

/* The receive filter of a port for this configuration: writes the ids the
 * loop uses (of WC_LOOP_RX_IDS) to ids and returns their count; a port
 * filters out the rest (they would count as unknown ids). */
uint32_t wc_loop_rx_ids(const wc_loop_config_t *config, uint32_t ids[WC_LOOP_RX_ID_COUNT]);

#endif /* WC_LOOP_H */
