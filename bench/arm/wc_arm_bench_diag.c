/* The probe's diagnostic rows (wc_arm_bench.c; DESIGN 11, 17): ISO-TP (wc_isotp.h), the UDS server
 * (wc_uds.h) and the fault memory (wc_dtc.h) beside the loop, wired as wc_tcu --uds wires them
 * (src/port/wc_tcu_diag.c): after each wc_loop_step the fault memory's tests from the step's VfsCommand
 * status word (here DTC i tests status bit i: 15 tests, level and event debouncing in turn, and a "memory
 * lost" DTC: 16 definitions), the snapshot's operating point refreshed, then wc_uds_step with one frame a
 * step (wc_tcu's default). The loop on the committed image (table1 + shift_1_2_full) in torque control at
 * 750 rpm, 80 degC, 100 Nm, as the XCP rows. A tester sends one frame a step at most: its request, then its
 * flow control (ContinueToSend, no further FC, STmin 0) the step after our FirstFrame.
 *   wc_uds_step:idle / wc_loop_step+diag:idle       no request (64 steps)
 *   :read_did_multiframe   0x22 of F190 (17 characters), FD01 (3 temperatures), FD03 (the loop's rejects by
 *                          reason): a 68-byte answer, FF + 9 CFs; every step of the exchange, from the one
 *                          that serves the request (the DID reads) to the last CF
 *   :read_dtc_list         0x19 0x0A (reportSupportedDTC: every DTC and its status, the longest list; 0x02
 *                          lists only the DTCs with a status bit of the mask) over the 16 DTCs: a 67-byte
 *                          answer, every step of the exchange
 * wc_uds_step rows: the server and ISO-TP alone (the loop step and the tests outside the window);
 * wc_dtc_report:vfs_status_15_tests: the tests alone (the idle steps: the VfsCommand's decode, the
 * snapshot's operating point, 15 wc_dtc_report);
 * wc_loop_step+diag rows: the whole control step of wc_tcu --uds (loop, tests, server). Every answer is
 * checked (positive, its length, its DIDs' values). RAM lines: sizeof wc_isotp_t, wc_uds_t, wc_dtc_t. */
#include "wc_arm_bench.h"
#include "wc_test_diag_hooks.h"  /* tests/c: the hooks' stand-ins */

#define DIAG_TESTS WC_CAN_STATUS_BITS   /* DTC i: VfsCommand status bit i */
#define DIAG_DTCS (DIAG_TESTS + 1u)     /* and "memory lost" */
#define DIAG_SLIP_rpm 750.0f
#define DIAG_THETA_degC 80.0f
#define DIAG_REQUEST_Nm 100.0f
#define DIAG_SETTLE_PERIODS 32u         /* the loop out of its start-up safe state */
#define DIAG_IDLE_PERIODS 64u
#define DIAG_EXCHANGE_PERIODS 24u       /* the longest exchange: request, FF, FC, 9 CFs */
#define DIAG_IDENTITY "WETCLUTCHARM00001"

static wc_isotp_t tp;
static wc_uds_t uds;
static wc_uds_config_t uds_config;
static wc_dtc_t dtc;
static wc_dtc_definition_t definitions[DIAG_DTCS];
static wc_dtc_snapshot_t environment;
static uint8_t diag_alive;
static uint8_t next_seed;

static bool diag_random(void *context, uint8_t *seed, uint32_t length)
{
    (void)context;
    return wc_test_counter_seed(&next_seed, seed, length);
}

static bool diag_key(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    (void)context;
    return wc_test_xor_key(seed, seed_length, key, key_length);
}

static const wc_uds_did_t dids[] = {
    { 0xF190u, (uint16_t)(sizeof DIAG_IDENTITY - 1u), wc_test_read_text, DIAG_IDENTITY },
    { 0xFD01u, 12u, wc_test_read_temperatures, &loop },
    { 0xFD03u, (uint16_t)(4u * WC_REJECT_REASONS), wc_test_read_rejects, &loop },
};

/* The fault memory's tests from the step's VfsCommand and the snapshot's operating point (wc_tcu_diag.c's
 * wiring), outside or inside the window. */
void diag_report(bench_ctx_t *c)
{
    wc_can_vfs_command_phys_t vfs;
    if (wc_can_decode_vfs_command(&vfs, c->tx[0].data, sizeof c->tx[0].data) != WC_CAN_OK) { return; }
    environment.slip_speed_rad_s = loop.input.slip_rad_s;
    environment.theta_clutch_degC = loop.clutch.theta_degC;
    environment.theta_oil_degC = loop.input.theta_oil_degC;
    environment.theta_housing_degC = loop.input.theta_housing_degC;
    environment.current_oncoming_mA = loop.last.current_mA;
    environment.shift_phase = (uint8_t)loop.shift.phase;
    for (uint32_t i = 0u; i < DIAG_TESTS; ++i) { wc_dtc_report(c->dtc, i, ((vfs.status >> i) & 1u) != 0u); }
}

static bool diag_init(void)
{
    for (uint32_t i = 0u; i < DIAG_DTCS; ++i) {
        const bool level = (i % 2u) == 0u;
        definitions[i] = (wc_dtc_definition_t){ 0xD0A000u + i, 5, level ? -5 : -100, level ? 1u : 5u, 1u, 1u,
                                                (uint8_t)(i % 4u), level };
    }
    const wc_dtc_config_t dtc_config = { definitions, DIAG_DTCS, 40u, DIAG_TESTS, &environment };
    uds_config = (wc_uds_config_t)WC_UDS_CONFIG_DEFAULT;
    uds_config.dids = dids;
    uds_config.did_count = (uint32_t)WC_ARRAY_LENGTH(dids);
    uds_config.dtc = &dtc;
    uds_config.random = diag_random;
    uds_config.key = diag_key;
    wc_isotp_config_t tp_config = WC_ISOTP_CONFIG_DEFAULT;
    tp_config.rx_physical_id = WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID;
    tp_config.rx_functional_id = WC_CAN_UDS_FUNCTIONAL_REQUEST_FRAME_ID;
    tp_config.tx_id = WC_CAN_UDS_RESPONSE_FRAME_ID;
    if (!wc_dtc_init(&dtc, &dtc_config) || !wc_uds_init(&uds, &uds_config) || !wc_isotp_init(&tp, &tp_config)) {
        return false;
    }
    wc_dtc_cycle_start(&dtc);
    bench.tp = &tp;
    bench.uds = &uds;
    bench.dtc = &dtc;
    return true;
}

/* One control period: the loop's input frames queued; the loop step, the tests and the server step, the
 * whole measured (whole_step) or the server step alone, into row (ROWS: not measured). */
static void diag_period(row_t row, bool whole_step)
{
    queue_frames(DIAG_SLIP_rpm, DIAG_THETA_degC, DIAG_REQUEST_Nm, diag_alive);
    diag_alive = wc_e2e_counter_next(diag_alive);
    if (whole_step && (row < ROWS)) {
        record(row, measure(thunk_loop_diag_step, &bench));
        return;
    }
    thunk_loop_step(&bench);
    if (row == ROW_DIAG_IDLE) {
        record(ROW_DIAG_TESTS, measure(thunk_diag_report, &bench));
    } else {
        diag_report(&bench);
    }
    if (row < ROWS) {
        record(row, measure(thunk_uds_step, &bench));
    } else {
        thunk_uds_step(&bench);
    }
}

/* A tester's request (a SingleFrame of length bytes) and its flow control after our FirstFrame, one frame a
 * step; every step from the request's to the answer's last frame measured. True when the answer, complete,
 * begins with positive (its length in *answer_length). */
static bool diag_exchange(const uint8_t *request, uint32_t length, row_t row, bool whole_step, uint8_t positive,
                          uint32_t *answer_length)
{
    wc_can_frame_t frame = { WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID, 8u, 0u, { 0u } };
    frame.data[0] = (uint8_t)length;
    for (uint32_t i = 0u; i < length; ++i) { frame.data[1u + i] = request[i]; }
    const uint32_t responses = tp.counters.responses;
    bool sent = wc_isotp_receive(&tp, &frame);
    for (uint32_t k = 0u; sent && (k < DIAG_EXCHANGE_PERIODS) && (tp.counters.responses == responses); ++k) {
        diag_period(row, whole_step);
        if ((bench.diag_frames == 1u) && ((bench.diag_tx[0].data[0] >> 4) == (uint8_t)WC_ISOTP_PCI_FF)) {
            const wc_can_frame_t fc = { WC_CAN_UDS_PHYSICAL_REQUEST_FRAME_ID, 8u, 0u, { 0x30u, 0u, 0u } };
            sent = wc_isotp_receive(&tp, &fc);
        }
    }
    *answer_length = tp.tx_length;
    return sent && (tp.counters.responses == responses + 1u) && (tp.tx_buffer[0] == positive);
}

static bool diag_exchanges(row_t did_row, row_t dtc_row, bool whole_step)
{
    static const uint8_t read_dids[] = { WC_UDS_SID_READ_DID, 0xF1u, 0x90u, 0xFDu, 0x01u, 0xFDu, 0x03u };
    static const uint8_t read_dtcs[] = { WC_UDS_SID_READ_DTC, 0x0Au };  /* reportSupportedDTC: every DTC */
    const uint32_t did_bytes = 1u + 3u * 2u + (sizeof DIAG_IDENTITY - 1u) + 12u + 4u * WC_REJECT_REASONS;
    uint32_t length = 0u;
    bool ok = diag_exchange(read_dids, sizeof read_dids, did_row, whole_step, 0x62u, &length) && (length == did_bytes) &&
              (memcmp(&tp.tx_buffer[3], DIAG_IDENTITY, sizeof DIAG_IDENTITY - 1u) == 0);
    ok = diag_exchange(read_dtcs, sizeof read_dtcs, dtc_row, whole_step, 0x59u, &length) &&
         (length == 3u + 4u * DIAG_DTCS) && ok;
    return ok;
}

void bench_diag(void)
{
    static wc_cal_set_t set;
    if ((wc_cal_image_load(bench_cal_image, bench_cal_image_bytes, &set).result != (uint32_t)WC_CAL_IMAGE_OK) ||
        (wc_loop_init(&loop, &set.clutch, &set.loop, DIAG_THETA_degC) != WC_CAL_OK) || !diag_init()) {
        fail("diag: the image, wc_loop_init or the servers' init");
        return;
    }
    bench.loop = &loop;
    diag_alive = 0u;
    for (uint32_t k = 0u; k < DIAG_SETTLE_PERIODS; ++k) { diag_period(ROWS, false); }
    const uint32_t safe_steps = loop.counters.safe_steps;
    bool ok = true;
    for (uint32_t k = 0u; k < DIAG_IDLE_PERIODS; ++k) {
        diag_period(ROW_DIAG_IDLE, false);
        ok = (bench.diag_frames == 0u) && ok;
    }
    for (uint32_t k = 0u; k < DIAG_IDLE_PERIODS; ++k) {
        diag_period(ROW_LOOP_DIAG_IDLE, true);
        ok = (bench.diag_frames == 0u) && (bench.tx_frames == WC_LOOP_TX_CYCLIC) && ok;
    }
    if (!ok) { fail("diag: an idle step sent a diagnostic frame"); }
    if (!diag_exchanges(ROW_DIAG_READ_DID, ROW_DIAG_READ_DTC, false) ||
        !diag_exchanges(ROW_LOOP_DIAG_READ_DID, ROW_LOOP_DIAG_READ_DTC, true)) {
        fail("diag: a ReadDataByIdentifier or ReadDTCInformation answer wrong or incomplete");
    }
    if (loop.counters.safe_steps != safe_steps) { fail("diag: the loop went to its safe state in the session"); }
    wc_arm_puts("DIAG session: ");
    wc_arm_put_u32(uds.counters.requests);
    wc_arm_puts(" requests, ");
    wc_arm_put_u32(tp.counters.responses);
    wc_arm_puts(" responses, ");
    wc_arm_put_u32(dtc.overflows);
    wc_arm_puts(" DTC overflows\n");
    put_ram("wc_isotp_t", (uint32_t)sizeof(wc_isotp_t));
    put_ram("wc_uds_t", (uint32_t)sizeof(wc_uds_t));
    put_ram("wc_dtc_t", (uint32_t)sizeof(wc_dtc_t));
}
