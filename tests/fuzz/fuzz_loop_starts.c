/* The loop fuzzer's starts inside the whole shift (fuzz_loop.h; shift-options bits 1-4 of the input). */
#include "fuzz_loop.h"

#include "wc_shift_1_2_shift.h"

/* ------------------------------------------------------------------------ */
/* Starts inside the whole shift (shift-options bits 1-4)                   */
/* ------------------------------------------------------------------------ */

/* A whole shift needs hundreds of loop steps to reach its later phases (PREPARE 50 periods, TORQUE 220, INERTIA
 * at least 200, LOCKUP 50, a fallback's finish 1000): an input that starts there at wc_loop_init is long and every
 * execution of it pays for the phases before. Instead an input can start from a snapshot: the loop (and the
 * harness's own state: its E2E senders' counters, the oracle's history) as a fixed scripted prefix left it. The
 * prefixes are frame streams through the same records, iterate() and oracle as any input; they do not depend on
 * fuzz bytes. They run once, in LLVMFuzzerInitialize; an input that starts from one costs a copy of the loop.
 * wc_loop_t is caller-owned plain storage (no allocation, no state outside it): restored at the same address
 * its pointers (the off-going view into the loop, the calibrations) are those of the run that made it.
 *
 * The scripts are those of make_seeds.py (SCRIPT_NOMINAL, the whole_shift seed's scenario, in the frames of its
 * whole_periods: a 1->2 upshift at a constant output speed, ClutchSensors with the tick every 2nd 1 ms period and
 * a bare tick between, OffgoingSensors every 4th, ShiftCommand and TorqueRequest in Shift mode every 10th), with
 * byte 0 = 0xCC (shift control, loop configuration, plausible, make valid; timer clock, 40 degC), its
 * WHOLE_CONFIG (timeouts 25, MaxDeltaCounter 2, SyncCounter 2, recovery 5) and the whole shift. A seed that
 * starts from a snapshot continues the same script from its period; started at wc_loop_init with the script's
 * periods before it, the same input gives the same loop state bit for bit. */
#define W_O_RPM (3000.0 / 4.7)
#define SLIP_12_RPM ((4.7 - 3.1) * W_O_RPM)
#define INERTIA_MS 250.0
static const uint8_t prefix_header[] = { 0x80u | 0x40u | 0x08u | 0x04u, 25u, 25u, 2u, 2u, 5u, 0x01u };

enum { LOST_NONE = 0u, LOST_ALL = 1u };
typedef struct {
    uint32_t first;          /* periods first..last-1 */
    uint32_t last;
    uint8_t request;         /* ShiftCommand.ShiftRequest */
    int32_t inertia_start;   /* the period the slip starts to fall (smoothstep over INERTIA_MS); < 0: not yet */
    uint8_t lost;            /* LOST_ALL: no frame at all, a bare tick per period */
} segment_t;

typedef struct {
    const char *name;
    const segment_t *script;  /* ends with last == 0 */
    uint32_t period;          /* the snapshot is taken before this period of the script */
} start_point_t;

/* make_seeds.py SCRIPT_NOMINAL: in Shift mode, the request edge at 30, the slip falls from 300, withdrawn at 640. */
static const segment_t script_nominal[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 300u, 1u, -1, LOST_NONE }, { 300u, 640u, 1u, 300, LOST_NONE },
    { 640u, 660u, 0u, 300, LOST_NONE }, { 0u, 0u, 0u, 0, 0u } };
/* Every input lost in the inertia phase (the sensors time out after 25 periods): finished on the model, released
 * after fallback_time_s (1 s). */
static const segment_t script_lost_inertia[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 300u, 1u, -1, LOST_NONE }, { 300u, 400u, 1u, 300, LOST_NONE },
    { 400u, 1420u, 1u, 300, LOST_ALL }, { 0u, 0u, 0u, 0, 0u } };
/* Every input lost in the torque phase: handed back. */
static const segment_t script_lost_torque[] = {
    { 0u, 30u, 0u, -1, LOST_NONE }, { 30u, 200u, 1u, -1, LOST_NONE }, { 200u, 300u, 1u, -1, LOST_ALL },
    { 0u, 0u, 0u, 0, 0u } };

/* shift-options bits 1-4: 0 wc_loop_init, k = 1..15 start_points[(k - 1) % N]. The phases are those the table1
 * calibration and wc_shift_1_2_whole_full give (WC_FUZZ_VERBOSE=1 prints them); make_seeds.py START has the same table. */
static const start_point_t start_points[] = {
    { "idle in Shift mode, inputs fresh (the request edge next)", script_nominal, 30u },
    { "torque phase, its start", script_nominal, 90u },
    { "torque phase, 20 ms before its end", script_nominal, 280u },
    { "inertia phase, the off-going clutch's hand-over", script_nominal, 305u },
    { "inertia phase, its middle", script_nominal, 430u },
    { "lock-up hand-over", script_nominal, 560u },
    { "locked (the request withdrawn at 640)", script_nominal, 620u },
    { "inputs lost 30 periods ago in the inertia phase (fallback finish)", script_lost_inertia, 430u },
    { "fallback finish, 25 periods before its end (released)", script_lost_inertia, 1390u },
    { "inputs lost 30 periods ago in the torque phase (handed back)", script_lost_torque, 230u },
};
#define START_POINTS (sizeof start_points / sizeof start_points[0])

typedef struct {
    wc_loop_t loop;
    harness_t h;
} snapshot_t;
static snapshot_t snapshots[START_POINTS];  /* 1.7 KiB each */

static size_t put_u16_of(uint8_t *b, double x, double lo, double hi)
{
    /* make_seeds.py u16_of: round half to even (nearbyint in the default rounding mode), saturated */
    double u = nearbyint((x - lo) / (hi - lo) * 65535.0);
    u = (u < 0.0) ? 0.0 : ((u > 65535.0) ? 65535.0 : u);
    const uint16_t v = (uint16_t)u;
    b[0] = (uint8_t)(v & 0xFFu);
    b[1] = (uint8_t)(v >> 8);
    return 2u;
}

static double smoothstep(double x)
{
    x = (x < 0.0) ? 0.0 : ((x > 1.0) ? 1.0 : x);
    return x * x * (3.0 - 2.0 * x);
}

/* The records of period k of a segment (make_seeds.py whole_periods, offgoing_every 4); returns their length. */
static size_t script_period(const segment_t *s, uint32_t k, uint8_t *b)
{
    size_t n = 0u;
    const double x = (s->inertia_start < 0) ? 0.0 : ((double)k - (double)s->inertia_start) / INERTIA_MS;
    const double slip = SLIP_12_RPM * (1.0 - smoothstep(x));
    const bool sent = s->lost == LOST_NONE;
    if (sent && (k % 10u == 0u)) {
        b[n++] = 1u | (6u << 3);  /* ShiftCommand: request, AdaptationReset 0, gear 2, 150 Nm, 250 ms */
        b[n++] = 0u;
        b[n++] = s->request;
        b[n++] = 0u;
        b[n++] = 1u;
        n += put_u16_of(&b[n], 150.0, -1000.0, 1000.0);
        n += put_u16_of(&b[n], INERTIA_MS, 50.0, 2000.0);
        b[n++] = 1u | (3u << 3);  /* TorqueRequest: 0 Nm, Mode 3 (Shift) */
        b[n++] = 0u;
        n += put_u16_of(&b[n], 0.0, 0.0, 2000.0);
        b[n++] = 3u;
    }
    if (sent && (k % 4u == 0u)) {
        b[n++] = 1u | (2u << 3);  /* OffgoingSensors */
        b[n++] = 0u;
        n += put_u16_of(&b[n], slip - SLIP_12_RPM, -8000.0, 8000.0);
    }
    if (sent && (k % 2u == 0u)) {
        b[n++] = 1u | 0x04u;  /* ClutchSensors with the tick: oil 80, housing 75 degC */
        b[n++] = 0u;
        n += put_u16_of(&b[n], slip, -8000.0, 8000.0);
        n += put_u16_of(&b[n], 80.0, -40.0, 200.0);
        n += put_u16_of(&b[n], 75.0, -40.0, 200.0);
    } else {
        b[n++] = 0u;  /* a bare tick */
    }
    return n;
}

/* Runs every script once and keeps the snapshots (LLVMFuzzerInitialize: before the first input). */
void make_snapshots(void)
{
    for (size_t i = 0u; i < START_POINTS; ++i) {
        const start_point_t *p = &start_points[i];
        if ((i > 0u) && (p->script == start_points[i - 1u].script) && (p->period >= start_points[i - 1u].period)) {
            continue;  /* taken on the previous one's run */
        }
        harness_t h;
        fz_reader_t r;
        uint8_t options;
        uint8_t shift_options;
        fz_reader_init(&r, prefix_header, sizeof prefix_header);
        const float theta_start_degC = read_header(&h, &r, &options, &shift_options);
        start_fresh(&h, options, shift_options, theta_start_degC);
        xcp_reset();
        size_t next = i;  /* the snapshots of this script, in period order */
        for (const segment_t *s = p->script; s->last != 0u; ++s) {
            for (uint32_t k = s->first; k < s->last; ++k) {
                while ((next < START_POINTS) && (start_points[next].script == p->script) &&
                       (start_points[next].period == k)) {
                    FZ_CHECK(loop.rx_tail == loop.rx_head, "snapshot with frames in the ring");
                    memcpy(&snapshots[next].loop, &loop, sizeof loop);
                    snapshots[next].h = h;
                    ++next;
                }
                uint8_t b[64];  /* a period's records: at most 31 bytes */
                fz_reader_init(&r, b, script_period(s, k, b));
                unsigned record = 1u;
                run_records(&h, &r, &record);
            }
        }
        FZ_CHECK((next == START_POINTS) || (start_points[next].script != p->script),
                 "start point %u after its script's end", (unsigned)next);
    }
    if (verbose) {
        for (size_t i = 0u; i < START_POINTS; ++i) {
            const wc_loop_t *l = &snapshots[i].loop;
            fprintf(stderr, "fuzz_loop: start %u: %s: period %u, phase %u (%u periods), fallback %u, safe %d, "
                            "second gear %d, off-going released %d\n",
                    (unsigned)(i + 1u), start_points[i].name, (unsigned)start_points[i].period, (unsigned)l->shift.phase,
                    (unsigned)l->shift.phase_periods, (unsigned)l->shift.fallback,
                    (int)(l->fresh_periods < l->config.recovery_periods), (int)l->shift.second_gear,
                    (int)l->shift.offgoing_released);
        }
    }
}

void start_from_snapshot(harness_t *h, uint32_t start)
{
    const snapshot_t *s = &snapshots[(start - 1u) % START_POINTS];
    memcpy(&loop, &s->loop, sizeof loop);
    *h = s->h;
}
