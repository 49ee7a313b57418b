/* What the frame loop's two files share (not public): wc_loop.c (the ring,
 * the frames' checks, one clutch and its whole shift) and wc_loop_gearbox.c
 * (the transmission's inputs, step and frames, DESIGN 15). */
#ifndef WC_LOOP_INTERNAL_H
#define WC_LOOP_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wetclutch_can/wc_loop.h"

/* What a step's preparation found, with this period's status bits (bits
 * 0..15, WC_CAN_STATUS_*) in one word. */
#define STEP_SHIFT (1uL << 16)   /* the shift controller steps the clutch */
#define STEP_SAFE (1uL << 17)    /* the safe state is active */
#define STEP_REPORT (1uL << 18)  /* a shift ended: ShiftReport */
#define STEP_ADAPT (1uL << 19)   /* the learned values changed or were reset: AdaptationReport, the hook */

/* Freshness after this period's frames; returns true when stale. */
static inline bool wc_loop_update_freshness(wc_loop_input_t *in, uint32_t timeout_periods, uint32_t *timeouts)
{
    const bool stale = !in->seen || (in->age_periods >= timeout_periods);
    if (stale && !in->stale && in->seen) {
        (*timeouts)++;
        in->seen = false;
        wc_e2e_receiver_restart(&in->e2e);  /* the input must prove itself: reference + SyncCounter frames */
    }
    in->stale = stale;
    if (in->age_periods < UINT32_MAX) { in->age_periods++; }
    return stale;
}

/* The safe state's debounce (DESIGN 8): the control inputs fresh (no timeout
 * bit in step) for recovery_periods in a row. Returns true while safe. */
static inline bool wc_loop_safe_after(wc_loop_t *loop, uint32_t step)
{
    const bool fresh = (step & (WC_CAN_STATUS_SENSOR_TIMEOUT | WC_CAN_STATUS_REQUEST_TIMEOUT)) == 0u;
    loop->fresh_periods = fresh ? ((loop->fresh_periods < UINT32_MAX) ? loop->fresh_periods + 1u : UINT32_MAX) : 0u;
    return !fresh || (loop->fresh_periods < loop->config.recovery_periods);
}

/* Model status bit -> the status word's bit. */
static inline uint16_t wc_loop_status_bits(wc_status_t status)
{
    static const struct {
        wc_status_t model;
        uint16_t can;
    } map[] = {
        { WC_STATUS_SATURATED, WC_CAN_STATUS_SATURATED },
        { WC_STATUS_CURRENT_CLAMPED, WC_CAN_STATUS_CURRENT_CLAMPED },
        { WC_STATUS_BELOW_DRAG, WC_CAN_STATUS_BELOW_DRAG },
        { WC_STATUS_INPUT_INVALID, WC_CAN_STATUS_IMPLAUSIBLE_INPUT },
        { WC_STATUS_OVER_TEMPERATURE, WC_CAN_STATUS_OVER_TEMPERATURE },
        { WC_STATUS_NOT_INITIALISED, WC_CAN_STATUS_SAFE_STATE_ACTIVE },
        { WC_STATUS_LOCKED, WC_CAN_STATUS_LOCKED },
    };
    uint16_t bits = 0u;
#if defined(__GNUC__) && !defined(__clang__) && !defined(__OPTIMIZE_SIZE__)
#pragma GCC unroll 8  /* seven fixed entries, every period (bench/arm) */
#endif
    for (size_t i = 0u; i < (sizeof map / sizeof map[0]); ++i) {
        if ((status & map[i].model) != 0u) { bits = (uint16_t)(bits | map[i].can); }
    }
    return bits;
}

#define STEP_GEARBOX (1uL << 20) /* the loop runs the transmission: wc_loop_gearbox_run takes the step */

/* An input that has seen nothing: stale, its E2E receiver waiting for a reference. */
static inline void wc_loop_input_reset(wc_loop_input_t *in)
{
    in->age_periods = 0u;
    in->seen = false;
    in->stale = true;
    wc_e2e_receiver_init(&in->e2e);
}

/* An output frame's header: the id, its DBC length, no flags. */
static inline void wc_loop_frame_header(wc_can_frame_t *f, uint32_t id, uint8_t dlc)
{
    f->id = id;
    f->dlc = dlc;
    f->flags = 0u;
}

/* EngineTorqueRequest (DESIGN 14, 15) at *out: the delta when active, else
 * inactive with 0 N m; its own alive counter. Inline: every period of the
 * whole shift (a call cost bench/arm's wc_loop_step:whole_shift 9 instructions). */
static inline void wc_loop_engine_frame(wc_loop_t *loop, bool active, float delta_Nm, wc_can_frame_t *out)
{
    const wc_can_engine_torque_request_phys_t engine = {
        .intervention_active = active ? 1.0f : 0.0f,
        .torque_delta_Nm = active ? delta_Nm : 0.0f,
        .alive_counter = loop->tx_alive_engine,
    };
    loop->tx_alive_engine = wc_e2e_counter_next(loop->tx_alive_engine);
    wc_loop_frame_header(out, WC_CAN_ENGINE_TORQUE_REQUEST_FRAME_ID, WC_CAN_ENGINE_TORQUE_REQUEST_LENGTH);
    (void)wc_can_encode_engine_torque_request(out->data, &engine, sizeof out->data);
}

/* The transmission (wc_loop_gearbox.c). Its init after wc_loop_init's memset: WC_CAL_NULL when refused. */
wc_cal_error_t wc_loop_gearbox_init(wc_loop_t *loop, const wc_loop_config_t *config, float theta_start_degC);
/* One period after the ring was drained (step: the pending status bits): the
 * inputs' freshness, the safe state, the transmission's step, the frames. */
uint32_t wc_loop_gearbox_run(wc_loop_t *loop, uint32_t step, wc_can_frame_t out[WC_LOOP_TX_FRAMES]);

#endif /* WC_LOOP_INTERNAL_H */
