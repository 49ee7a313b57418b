/* The device secret of the security access (DESIGN 17): one home for what
 * both wc_tcu's UDS SecurityAccess (wc_tcu_diag.c) and its XCP GET_SEED /
 * UNLOCK (wc_tcu.c) need. The seed from getrandom(2); the key the first
 * key_length bytes of HMAC-SHA256(secret, seed) by OpenSSL's libcrypto (the
 * portable library calls these as the integrator's hooks and hand-rolls no
 * cryptography). Host only: POSIX, stdio, OpenSSL. */
#ifndef WC_DEVICE_SECRET_H
#define WC_DEVICE_SECRET_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define WC_DEVICE_SECRET_MIN_BYTES 16u
#define WC_DEVICE_SECRET_MAX_BYTES 1024u

typedef struct {
    uint8_t bytes[WC_DEVICE_SECRET_MAX_BYTES];
    size_t length;
} wc_device_secret_t;

/* Reads path (16..1024 bytes); 0, or -1 after one line on stderr naming program and path. */
int wc_device_secret_read(wc_device_secret_t *secret, const char *path, const char *program);

/* The hooks (wc_uds_config_t, wc_xcp_config_t): random ignores context; key takes a wc_device_secret_t.
 * Both return false rather than a predictable or short value. */
bool wc_device_secret_random(void *context, uint8_t *seed, uint32_t length);
bool wc_device_secret_key(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key,
                          uint32_t key_length);

#endif
