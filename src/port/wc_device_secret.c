/* The device secret, its seed and key (wc_device_secret.h). */
#define _GNU_SOURCE
#include "wc_device_secret.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/random.h>
#include <sys/types.h>

#include <openssl/evp.h>
#include <openssl/hmac.h>

int wc_device_secret_read(wc_device_secret_t *secret, const char *path, const char *program)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: --secret-file %s: %s\n", program, path, strerror(errno));
        return -1;
    }
    uint8_t extra = 0u;
    secret->length = fread(secret->bytes, 1u, sizeof secret->bytes, f);
    const int error = ferror(f) ? errno : 0;
    const bool longer = (secret->length == sizeof secret->bytes) && (fread(&extra, 1u, 1u, f) == 1u);
    fclose(f);
    if (error != 0) {
        fprintf(stderr, "%s: --secret-file %s: %s\n", program, path, strerror(error));
        return -1;
    }
    if ((secret->length < WC_DEVICE_SECRET_MIN_BYTES) || longer) {
        fprintf(stderr, "%s: --secret-file %s: %zu bytes; the device secret must be %u..%u bytes\n", program, path,
                longer ? sizeof secret->bytes + 1u : secret->length, WC_DEVICE_SECRET_MIN_BYTES,
                WC_DEVICE_SECRET_MAX_BYTES);
        return -1;
    }
    return 0;
}

bool wc_device_secret_random(void *context, uint8_t *seed, uint32_t length)
{
    (void)context;
    size_t done = 0u;
    for (int tries = 0; (done < length) && (tries < 16); ++tries) {
        const ssize_t n = getrandom(seed + done, length - done, 0);
        if (n > 0) { done += (size_t)n; }
        else if (errno != EINTR) { break; }
    }
    return done == length;  /* false: the server refuses the seed, never a predictable one */
}

bool wc_device_secret_key(void *context, const uint8_t *seed, uint32_t seed_length, uint8_t *key,
                          uint32_t key_length)
{
    const wc_device_secret_t *secret = context;
    uint8_t mac[EVP_MAX_MD_SIZE];
    unsigned int mac_length = 0u;
    if ((HMAC(EVP_sha256(), secret->bytes, (int)secret->length, seed, seed_length, mac, &mac_length) == NULL) ||
        (mac_length < key_length)) {
        return false;
    }
    memcpy(key, mac, key_length);
    return true;
}
