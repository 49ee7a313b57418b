/* Frame-clock determinism of the CAN frame loop (include/wetclutch_can/wc_loop.h):
 * the same frame sequence gives the same output frames, a changed request
 * changes them from its own period on, and the counters add up to what the
 * script holds (a synthetic engagement with one bad frame of each kind).
 * The mock port, the frames, the reference chain and the fixture:
 * wc_test_loop_harness.h. */
#include "wc_test_loop_harness.h"

/* ======================================================================== */
/* Frame-clock determinism and counters                                     */
/* ======================================================================== */

#define ENGAGEMENT_PERIODS 300
#define CHANGED_PERIOD 150

typedef struct {
    wc_can_frame_t frames[1024];
    size_t count;
    uint32_t good;                        /* frames that pass every check */
    uint32_t bad[WC_REJECT_REASONS];      /* frames each check drops */
    uint32_t steps;                       /* ClutchSensors frames without flags */
} script_t;

static void script_add(script_t *s, const wc_can_frame_t *f, int reject)  /* reject < 0: a good frame */
{
    assert_true(s->count < WC_TEST_COUNT(s->frames));
    s->frames[s->count++] = *f;
    if (reject < 0) { s->good++; } else { s->bad[reject]++; }
    if (f->id == WC_CAN_CLUTCH_SENSORS_FRAME_ID && f->flags == 0u) { s->steps++; }
}

/* A synthetic engagement, one TorqueRequest and one ClutchSensors frame per
 * period: slip 1500 rpm -> 0, request ramping to 250 Nm, oil warming; with
 * a corrupted copy (CRC), a repeated request (counter), a bench frame
 * (unknown id), an implausible sensor frame, a remote frame (format) and a
 * short copy in between. torque_change_Nm is added to one period's request. */
static void build_engagement(script_t *s, float torque_change_Nm)
{
    memset(s, 0, sizeof *s);
    uint8_t s_alive = 3u;
    uint8_t r_alive = 9u;
    for (int k = 0; k < ENGAGEMENT_PERIODS; ++k) {
        const float x = (float)k / (float)ENGAGEMENT_PERIODS;
        float torque_Nm = (k < CHANGED_PERIOD) ? 250.0f * (float)k / (float)CHANGED_PERIOD : 250.0f;
        if (k == CHANGED_PERIOD) { torque_Nm += torque_change_Nm; }
        const wc_can_frame_t q = request_frame(torque_Nm, MODE_TORQUE, r_alive);
        script_add(s, &q, -1);
        if (k == 120) {
            const wc_can_frame_t again = request_frame(torque_Nm + 100.0f, MODE_TORQUE, r_alive);
            script_add(s, &again, WC_REJECT_COUNTER);
        }
        r_alive = wc_e2e_counter_next(r_alive);
        if (k == 180) {
            wc_can_frame_t bench = empty_frame(WC_CAN_BENCH_MEASUREMENT_FRAME_ID + 1u);  /* not in the DBC */
            const wc_can_bench_measurement_phys_t m = { 5000.0f, 250.0f, 95.0f };
            assert_int_equal(wc_can_encode_bench_measurement(bench.data, &m, sizeof bench.data), WC_CAN_OK);
            script_add(s, &bench, WC_REJECT_UNKNOWN_ID);
        }
        const wc_can_frame_t f = sensors_frame(1500.0f * (1.0f - x), 80.0f + 10.0f * x, 75.0f, s_alive);
        if (k == 240) {
            wc_can_frame_t remote = f;
            remote.flags = WC_CAN_FLAG_REMOTE;
            script_add(s, &remote, WC_REJECT_FORMAT);
        }
        if (k == 200) {
            const implausible_t sna = { "OilTemp SNA", SIG_OIL, (int32_t)WC_CAN_CLUTCH_SENSORS_OIL_TEMP_SNA_CHOICE };
            const wc_can_frame_t bad = implausible_frame(&sna, s_alive);
            script_add(s, &bad, WC_REJECT_IMPLAUSIBLE);
        } else {
            script_add(s, &f, -1);
        }
        s_alive = wc_e2e_counter_next(s_alive);
        if (k == 60) {
            wc_can_frame_t corrupt = f;
            corrupt.data[5] ^= 0x20u;
            script_add(s, &corrupt, WC_REJECT_CRC);
        }
        if (k == 250) {
            wc_can_frame_t shorter = f;
            shorter.dlc = 7u;
            script_add(s, &shorter, WC_REJECT_SHORT);
        }
    }
}

typedef struct {
    wc_can_frame_t frames[TX_LOG_MAX];
    uint32_t count;
} capture_t;

static capture_t capture_a;
static capture_t capture_b;

/* A fresh loop, the whole script through the mock port; the output frames
 * into cap. */
static void replay(fixture_t *fx, const script_t *s, capture_t *cap)
{
    fixture_init(fx);
    for (size_t i = 0u; i < s->count; ++i) { port_deliver(&s->frames[i]); }
    run_steps(&fx->loop, s->steps);
    cap->count = tx_log.count;
    memcpy(cap->frames, tx_log.frames, tx_log.count * sizeof tx_log.frames[0]);
}

/* Index of the first frame that differs (id, DLC, flags, data bytes), or
 * the shorter count if one is a prefix of the other. */
static uint32_t first_difference(const capture_t *a, const capture_t *b)
{
    const uint32_t n = (a->count < b->count) ? a->count : b->count;
    for (uint32_t i = 0u; i < n; ++i) {
        const wc_can_frame_t *x = &a->frames[i];
        const wc_can_frame_t *y = &b->frames[i];
        if (x->id != y->id || x->dlc != y->dlc || x->flags != y->flags || x->dlc > 8u ||
            memcmp(x->data, y->data, x->dlc) != 0) {
            return i;
        }
    }
    return n;
}

static script_t engagement;
static script_t engagement_changed;

static void test_frame_clock_determinism(void **state)
{
    fixture_t *fx = *state;
    build_engagement(&engagement, 0.0f);
    replay(fx, &engagement, &capture_a);
    replay(fx, &engagement, &capture_b);
    assert_int_equal(capture_a.count, 2u * engagement.steps);
    assert_int_equal(capture_b.count, capture_a.count);
    const uint32_t same = first_difference(&capture_a, &capture_b);
    WC_CHECK(same == capture_a.count, "replays differ at output frame %u of %u", (unsigned)same,
             (unsigned)capture_a.count);

    /* One request 20 Nm higher: the outputs must differ, and not before that
     * period's step (its sensor frame is the (CHANGED_PERIOD+2)-th step: the
     * corrupted copy at period 60 stepped once more). */
    build_engagement(&engagement_changed, 20.0f);
    replay(fx, &engagement_changed, &capture_b);
    assert_int_equal(capture_b.count, capture_a.count);
    const uint32_t diff = first_difference(&capture_a, &capture_b);
    const uint32_t changed_step = (uint32_t)CHANGED_PERIOD + 1u;  /* 0-based step index */
    WC_CHECK(diff < capture_a.count, "a different frame sequence gave identical output");
    WC_CHECK(diff == 2u * changed_step, "first difference at output frame %u, expected %u (VfsCommand of step %u)",
             (unsigned)diff, (unsigned)(2u * changed_step), (unsigned)changed_step);
}

/* frames_in = frames offered; frames_used + all rejections = frames_in;
 * frames_out = frames sent; each count equal to what the script holds. */
static void test_counters_add_up(void **state)
{
    fixture_t *fx = *state;
    build_engagement(&engagement, 0.0f);
    replay(fx, &engagement, &capture_a);
    const wc_loop_counters_t *c = &fx->loop.counters;
    assert_int_equal(c->frames_in, engagement.count);
    assert_int_equal(c->frames_in, tx_log.offered);
    assert_int_equal(c->frames_used, engagement.good);
    for (int r = 0; r < (int)WC_REJECT_REASONS; ++r) {
        WC_CHECK(c->rejected[r] == engagement.bad[r], "rejected[%d] = %u, script has %u", r,
                 (unsigned)c->rejected[r], (unsigned)engagement.bad[r]);
    }
    assert_int_equal(c->frames_used + rejected_total(c), c->frames_in);
    assert_int_equal(c->steps, engagement.steps);
    assert_int_equal(c->steps, tx_log.steps);
    assert_int_equal(c->frames_out, tx_log.count);
    assert_int_equal(c->frames_out, WC_LOOP_TX_CYCLIC * c->steps);
    assert_int_equal(tx_log.refused, 0u);
    assert_int_equal(c->sensor_timeouts + c->request_timeouts + c->safe_steps, 0u);
    /* every reason the script exercises was seen once */
    for (int r = 0; r < (int)WC_REJECT_OVERFLOW; ++r) { assert_int_equal(engagement.bad[r], 1u); }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_frame_clock_determinism, setup),
        cmocka_unit_test_setup(test_counters_add_up, setup),
    };
    return cmocka_run_group_tests_name("wc_loop_determinism", tests, NULL, NULL);
}
