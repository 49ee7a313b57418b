/* E2E protection: CRC-8 SAE J1850 and alive counter. See wc_e2e.h. */
#include "wetclutch_can/wc_e2e.h"

#include <wetclutch/wc_config.h>
#include <stddef.h>

/* CRC-8 by table, two sizes of the same definition (tests/c/test_can_codec.c
 * checks each against the bitwise one, for every pair of bytes):
 *  - byte table: the register after shifting byte n through eight steps of
 *    polynomial 0x1D; one lookup a byte, 256 bytes of flash (the default
 *    when optimising for speed: about 100 instructions saved per frame);
 *  - nibble table: after four steps; two lookups a byte, 16 bytes (the
 *    default at -Os, where the CAN layer's flash budget is 6 KiB).
 * WC_E2E_CRC_NIBBLE_TABLE set to 0 or 1 chooses explicitly. */
#ifndef WC_E2E_CRC_NIBBLE_TABLE
#if defined(__OPTIMIZE_SIZE__)
#define WC_E2E_CRC_NIBBLE_TABLE 1
#else
#define WC_E2E_CRC_NIBBLE_TABLE 0
#endif
#endif

#if WC_E2E_CRC_NIBBLE_TABLE
static const uint8_t crc8_nibble[16] = {
    0x00u, 0x1Du, 0x3Au, 0x27u, 0x74u, 0x69u, 0x4Eu, 0x53u,
    0xE8u, 0xF5u, 0xD2u, 0xCFu, 0x9Cu, 0x81u, 0xA6u, 0xBBu,
};

/* One byte into the CRC-8 register. */
static uint8_t crc8_j1850_update(uint8_t crc, uint8_t byte)
{
    uint8_t reg = (uint8_t)(crc ^ byte);
    reg = (uint8_t)((uint8_t)(reg << 4) ^ crc8_nibble[reg >> 4]);
    reg = (uint8_t)((uint8_t)(reg << 4) ^ crc8_nibble[reg >> 4]);
    return reg;
}
#else
static const uint8_t crc8_table[256] = {
    0x00u, 0x1Du, 0x3Au, 0x27u, 0x74u, 0x69u, 0x4Eu, 0x53u, 0xE8u, 0xF5u, 0xD2u, 0xCFu,
    0x9Cu, 0x81u, 0xA6u, 0xBBu, 0xCDu, 0xD0u, 0xF7u, 0xEAu, 0xB9u, 0xA4u, 0x83u, 0x9Eu,
    0x25u, 0x38u, 0x1Fu, 0x02u, 0x51u, 0x4Cu, 0x6Bu, 0x76u, 0x87u, 0x9Au, 0xBDu, 0xA0u,
    0xF3u, 0xEEu, 0xC9u, 0xD4u, 0x6Fu, 0x72u, 0x55u, 0x48u, 0x1Bu, 0x06u, 0x21u, 0x3Cu,
    0x4Au, 0x57u, 0x70u, 0x6Du, 0x3Eu, 0x23u, 0x04u, 0x19u, 0xA2u, 0xBFu, 0x98u, 0x85u,
    0xD6u, 0xCBu, 0xECu, 0xF1u, 0x13u, 0x0Eu, 0x29u, 0x34u, 0x67u, 0x7Au, 0x5Du, 0x40u,
    0xFBu, 0xE6u, 0xC1u, 0xDCu, 0x8Fu, 0x92u, 0xB5u, 0xA8u, 0xDEu, 0xC3u, 0xE4u, 0xF9u,
    0xAAu, 0xB7u, 0x90u, 0x8Du, 0x36u, 0x2Bu, 0x0Cu, 0x11u, 0x42u, 0x5Fu, 0x78u, 0x65u,
    0x94u, 0x89u, 0xAEu, 0xB3u, 0xE0u, 0xFDu, 0xDAu, 0xC7u, 0x7Cu, 0x61u, 0x46u, 0x5Bu,
    0x08u, 0x15u, 0x32u, 0x2Fu, 0x59u, 0x44u, 0x63u, 0x7Eu, 0x2Du, 0x30u, 0x17u, 0x0Au,
    0xB1u, 0xACu, 0x8Bu, 0x96u, 0xC5u, 0xD8u, 0xFFu, 0xE2u, 0x26u, 0x3Bu, 0x1Cu, 0x01u,
    0x52u, 0x4Fu, 0x68u, 0x75u, 0xCEu, 0xD3u, 0xF4u, 0xE9u, 0xBAu, 0xA7u, 0x80u, 0x9Du,
    0xEBu, 0xF6u, 0xD1u, 0xCCu, 0x9Fu, 0x82u, 0xA5u, 0xB8u, 0x03u, 0x1Eu, 0x39u, 0x24u,
    0x77u, 0x6Au, 0x4Du, 0x50u, 0xA1u, 0xBCu, 0x9Bu, 0x86u, 0xD5u, 0xC8u, 0xEFu, 0xF2u,
    0x49u, 0x54u, 0x73u, 0x6Eu, 0x3Du, 0x20u, 0x07u, 0x1Au, 0x6Cu, 0x71u, 0x56u, 0x4Bu,
    0x18u, 0x05u, 0x22u, 0x3Fu, 0x84u, 0x99u, 0xBEu, 0xA3u, 0xF0u, 0xEDu, 0xCAu, 0xD7u,
    0x35u, 0x28u, 0x0Fu, 0x12u, 0x41u, 0x5Cu, 0x7Bu, 0x66u, 0xDDu, 0xC0u, 0xE7u, 0xFAu,
    0xA9u, 0xB4u, 0x93u, 0x8Eu, 0xF8u, 0xE5u, 0xC2u, 0xDFu, 0x8Cu, 0x91u, 0xB6u, 0xABu,
    0x10u, 0x0Du, 0x2Au, 0x37u, 0x64u, 0x79u, 0x5Eu, 0x43u, 0xB2u, 0xAFu, 0x88u, 0x95u,
    0xC6u, 0xDBu, 0xFCu, 0xE1u, 0x5Au, 0x47u, 0x60u, 0x7Du, 0x2Eu, 0x33u, 0x14u, 0x09u,
    0x7Fu, 0x62u, 0x45u, 0x58u, 0x0Bu, 0x16u, 0x31u, 0x2Cu, 0x97u, 0x8Au, 0xADu, 0xB0u,
    0xE3u, 0xFEu, 0xD9u, 0xC4u,
};

/* One byte into the CRC-8 register. */
static uint8_t crc8_j1850_update(uint8_t crc, uint8_t byte)
{
    return crc8_table[(uint8_t)(crc ^ byte)];
}
#endif

/* The frame CRC covers the bytes after the CRC byte, which comes first. */
WC_STATIC_ASSERT(WC_E2E_CRC_BYTE == 0u, e2e_crc_is_byte_0);

uint8_t wc_e2e_crc8_j1850(const uint8_t *data, size_t len)
{
    uint8_t crc = WC_E2E_CRC8_INIT;
    size_t i;

    if (data == NULL) {
        len = 0u;
    }
    for (i = 0u; (i < WC_E2E_CRC_MAX_BYTES) && (i < len); ++i) {
        crc = crc8_j1850_update(crc, data[i]);
    }
    return (uint8_t)(crc ^ WC_E2E_CRC8_XOR_OUT);
}

wc_e2e_result_t wc_e2e_frame_crc(uint32_t frame_id, const uint8_t *frame,
                                 size_t size, uint8_t *crc)
{
    uint8_t reg = WC_E2E_CRC8_INIT;
    size_t i;

    if ((frame == NULL) || (crc == NULL) || (size < WC_E2E_FRAME_BYTES)) {
        return WC_E2E_ERR_SIZE;
    }
    reg = crc8_j1850_update(reg, (uint8_t)(frame_id & 0xFFu)); /* data id */
#if defined(__GNUC__) && !defined(__clang__) && !defined(__OPTIMIZE_SIZE__)
#pragma GCC unroll 8  /* 7 fixed iterations, 3 of them every control period (bench/arm) */
#endif
    for (i = WC_E2E_CRC_BYTE + 1u; i < WC_E2E_FRAME_BYTES; ++i) {  /* every byte after the CRC */
        reg = crc8_j1850_update(reg, frame[i]);
    }
    *crc = (uint8_t)(reg ^ WC_E2E_CRC8_XOR_OUT);
    return WC_E2E_OK;
}

wc_e2e_result_t wc_e2e_protect(uint32_t frame_id, uint8_t *frame, size_t size)
{
    uint8_t crc = 0u;
    const wc_e2e_result_t result = wc_e2e_frame_crc(frame_id, frame, size, &crc);

    if (result == WC_E2E_OK) {
        frame[WC_E2E_CRC_BYTE] = crc;
    }
    return result;
}

wc_e2e_result_t wc_e2e_check_crc(uint32_t frame_id, const uint8_t *frame,
                                 size_t size)
{
    uint8_t crc = 0u;
    const wc_e2e_result_t result = wc_e2e_frame_crc(frame_id, frame, size, &crc);

    if (result != WC_E2E_OK) {
        return result;
    }
    return (frame[WC_E2E_CRC_BYTE] == crc) ? WC_E2E_OK : WC_E2E_ERR_CRC;
}

/* Receiver states (wc_e2e.h). */
enum { RX_INIT = 0u, RX_NOSYNC = 1u, RX_SYNCING = 2u, RX_VALID = 3u };

static void start(wc_e2e_receiver_t *rx, uint8_t state)
{
    if (rx != NULL) {
        rx->previous = 0u;
        rx->state = state;
        rx->in_sequence = 0u;
        rx->lost_last = false;
    }
}

void wc_e2e_receiver_init(wc_e2e_receiver_t *rx) { start(rx, RX_INIT); }

void wc_e2e_receiver_restart(wc_e2e_receiver_t *rx) { start(rx, RX_NOSYNC); }

/* Start over from this counter: SyncCounter +1 frames needed. */
static wc_e2e_status_t resynchronise(wc_e2e_receiver_t *rx, uint8_t received, wc_e2e_status_t status)
{
    rx->previous = received;
    rx->state = RX_SYNCING;
    rx->in_sequence = 0u;
    rx->lost_last = false;
    return status;
}

wc_e2e_status_t wc_e2e_receive(wc_e2e_receiver_t *rx, const wc_e2e_config_t *config, uint8_t counter)
{
    if ((rx == NULL) || (config == NULL)) {
        return WC_E2E_STATUS_WRONGSEQUENCE;
    }
    const uint8_t received = (uint8_t)(counter & WC_E2E_COUNTER_MASK);
    const uint8_t delta = (uint8_t)((uint8_t)(received - rx->previous) & WC_E2E_COUNTER_MASK);
    if ((rx->state == RX_VALID) && (delta == 1u)) {  /* the usual frame first */
        rx->previous = received;
        rx->lost_last = false;
        return WC_E2E_STATUS_OK;
    }
    if (rx->state == RX_INIT) {
        rx->previous = received;
        rx->state = RX_VALID;
        return WC_E2E_STATUS_INITIAL;
    }
    if (rx->state == RX_NOSYNC) {
        return resynchronise(rx, received, WC_E2E_STATUS_SYNC);
    }
    if (delta == 0u) {
        return WC_E2E_STATUS_REPEATED;  /* no new data; the reference stays */
    }
    if (rx->state == RX_SYNCING) {
        if (delta != 1u) {
            return resynchronise(rx, received, WC_E2E_STATUS_WRONGSEQUENCE);
        }
        rx->previous = received;
        rx->in_sequence++;
        if (rx->in_sequence < config->sync_counter) {
            return WC_E2E_STATUS_SYNC;
        }
        rx->state = RX_VALID;
        rx->lost_last = false;
        return WC_E2E_STATUS_OK;
    }
    /* VALID */
    if (delta == 1u) {
        rx->previous = received;
        rx->lost_last = false;
        return WC_E2E_STATUS_OK;
    }
    if ((delta <= config->max_delta_counter) && !rx->lost_last) {
        rx->previous = received;
        rx->lost_last = true;
        return WC_E2E_STATUS_OKSOMELOST;
    }
    return resynchronise(rx, received, WC_E2E_STATUS_WRONGSEQUENCE);
}

bool wc_e2e_status_usable(wc_e2e_status_t status)
{
    return (status == WC_E2E_STATUS_OK) || (status == WC_E2E_STATUS_OKSOMELOST) ||
           (status == WC_E2E_STATUS_INITIAL);
}

uint8_t wc_e2e_counter_next(uint8_t counter)
{
    return (uint8_t)((uint8_t)(counter + 1u) & WC_E2E_COUNTER_MASK);
}
