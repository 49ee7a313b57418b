/* E2E protection: CRC-8 SAE J1850 and alive counter. See wc_e2e.h. */
#include "wetclutch_can/wc_e2e.h"

/* The CRC-8 register after shifting nibble n (in its top four bits) through
 * four steps of polynomial 0x1D: process a byte as two nibbles, two lookups
 * instead of eight conditional shifts (16 bytes of flash; a 256-entry table
 * would save two shifts a byte for 240 more). tests/c/test_can_codec.c checks
 * it against the bitwise definition for every byte value. */
static const uint8_t crc8_nibble[16] = {
    0x00u, 0x1Du, 0x3Au, 0x27u, 0x74u, 0x69u, 0x4Eu, 0x53u,
    0xE8u, 0xF5u, 0xD2u, 0xCFu, 0x9Cu, 0x81u, 0xA6u, 0xBBu,
};

/* One byte into the (non-reflected) CRC-8 register. */
static uint8_t crc8_j1850_update(uint8_t crc, uint8_t byte)
{
    uint8_t reg = (uint8_t)(crc ^ byte);
    reg = (uint8_t)((uint8_t)(reg << 4) ^ crc8_nibble[reg >> 4]);
    reg = (uint8_t)((uint8_t)(reg << 4) ^ crc8_nibble[reg >> 4]);
    return reg;
}

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
    for (i = 0u; i < WC_E2E_FRAME_BYTES; ++i) {
        if (i != WC_E2E_CRC_BYTE) {
            reg = crc8_j1850_update(reg, frame[i]);
        }
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

void wc_e2e_counter_init(wc_e2e_counter_state_t *state)
{
    if (state != NULL) {
        state->previous = 0u;
        state->synced = false;
    }
}

wc_e2e_counter_result_t wc_e2e_counter_check(wc_e2e_counter_state_t *state,
                                             uint8_t counter)
{
    const uint8_t received = (uint8_t)(counter & WC_E2E_COUNTER_MASK);
    uint8_t delta;

    if (state == NULL) {
        return WC_E2E_COUNTER_WRONG_SEQUENCE;
    }
    if (!state->synced) {
        state->previous = received;
        state->synced = true;
        return WC_E2E_COUNTER_INITIAL;
    }
    delta = (uint8_t)((uint8_t)(received - state->previous) & WC_E2E_COUNTER_MASK);
    if (delta == 1u) {
        state->previous = received;
        return WC_E2E_COUNTER_OK;
    }
    if (delta == 0u) {
        return WC_E2E_COUNTER_REPEATED;
    }
    state->previous = received; /* resynchronise */
    return WC_E2E_COUNTER_WRONG_SEQUENCE;
}

bool wc_e2e_counter_accepted(wc_e2e_counter_result_t result)
{
    return (result == WC_E2E_COUNTER_OK) || (result == WC_E2E_COUNTER_INITIAL);
}

uint8_t wc_e2e_counter_next(uint8_t counter)
{
    return (uint8_t)((uint8_t)(counter + 1u) & WC_E2E_COUNTER_MASK);
}
