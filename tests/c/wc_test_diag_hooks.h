/* Stand-ins for the integrator's diagnostic hooks (wc_uds.h, wc_xcp.h) where a test drives the servers:
 * for the loop fuzzer (tests/fuzz/fuzz_loop_uds.c) and the Cortex-M4F probe (bench/arm/wc_arm_bench_diag.c).
 *  - security: the seed from a counter (never all zero), the key an XOR of the seed; no cryptography (the
 *    programs use a keyed MAC: src/port/wc_device_secret.c, DESIGN 17);
 *  - data identifiers' read hooks (wc_uds_did_t): a text (context: the text), the loop's temperatures and
 *    its rejects by reason (context: the wc_loop_t), every number big-endian (ISO 14229-1), floats as
 *    IEEE-754 single. */
#ifndef WC_TEST_DIAG_HOOKS_H
#define WC_TEST_DIAG_HOOKS_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include <wetclutch_can/wc_loop.h>

/* length seed bytes from *counter (odd: never all zero), the counter advanced */
static inline bool wc_test_counter_seed(uint8_t *counter, uint8_t *seed, uint32_t length)
{
    for (uint32_t i = 0u; i < length; ++i) { seed[i] = (uint8_t)((*counter)++ | 1u); }
    return true;
}

/* the key of seed: each byte the seed's (repeated) XOR 0xA5 + its index */
static inline bool wc_test_xor_key(const uint8_t *seed, uint32_t seed_length, uint8_t *key, uint32_t key_length)
{
    for (uint32_t i = 0u; i < key_length; ++i) { key[i] = (uint8_t)(seed[i % seed_length] ^ (0xA5u + i)); }
    return true;
}

static inline void wc_test_put_u32_be(uint8_t *p, uint32_t v)
{
    for (uint32_t i = 0u; i < 4u; ++i) { p[i] = (uint8_t)(v >> (24u - 8u * i)); }
}

static inline void wc_test_put_floats_be(uint8_t *p, const float *v, uint32_t n)
{
    for (uint32_t i = 0u; i < n; ++i) {
        uint32_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        wc_test_put_u32_be(&p[4u * i], bits);
    }
}

/* DID: the text at context, length characters */
static inline bool wc_test_read_text(void *context, uint8_t *data, uint32_t length)
{
    memcpy(data, context, length);
    return true;
}

/* DID, 12 bytes: the loop's clutch estimate, oil and housing temperatures (degC) */
static inline bool wc_test_read_temperatures(void *context, uint8_t *data, uint32_t length)
{
    const wc_loop_t *lp = context;
    (void)length;
    const float v[3] = { lp->clutch.theta_degC, lp->input.theta_oil_degC, lp->input.theta_housing_degC };
    wc_test_put_floats_be(data, v, 3u);
    return true;
}

/* DID, 4 * WC_REJECT_REASONS bytes: the loop's rejected frames by reason */
static inline bool wc_test_read_rejects(void *context, uint8_t *data, uint32_t length)
{
    const wc_loop_t *lp = context;
    (void)length;
    for (uint32_t r = 0u; r < WC_REJECT_REASONS; ++r) { wc_test_put_u32_be(&data[4u * r], lp->counters.rejected[r]); }
    return true;
}

#endif /* WC_TEST_DIAG_HOOKS_H */
