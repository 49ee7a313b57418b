/* The gearbox image (wc_gearbox_image.h; issue 29 item 1) under libFuzzer, as
 * an extra input interpretation of fuzz_calibration (byte 0 with bits 7 and
 * 6 set).
 *
 * Input after byte 0:
 *   byte 1  bits 0-1: the image
 *             0  the remaining bytes as they are (any length, read in place:
 *                AddressSanitizer sees a read past them);
 *             1  the 8HP's image (lut/wc_8hp_gearbox.h written by
 *                wc_gearbox_image_write) with edits until the bytes run out:
 *                a payload word (u16 index modulo the words) and a new value
 *                (a byte choosing: raw u32, a small integer 0..300, a float
 *                from fz_float, the word + or - 1, 0), sealed again (header
 *                and CRC right);
 *             2  as 1 (the last 5 bytes left), then one byte of the sealed
 *                image changed (u16 position, u8 xor) and the image cut to
 *                a length (u16 modulo the image's length + 1);
 *             3  the 8HP's image with one payload word set to 0x01 (an
 *                unused word, if it is one, must be refused).
 * Oracle (abort with a message): the result is one of the documented codes,
 * BAD_FIELD's error a payload offset with a field name, BAD_GEARBOX's a
 * wc_gearbox_error_t; not OK: the gearbox zeroed; OK: wc_gearbox_check
 * accepts it, wc_gearbox_image_write gives the input's image bytes back, and
 * so does the table with what it does not use zeroed by this harness (one
 * gearbox, one image), every shift the table finds has finite element slips
 * at any speeds, and every holding request is finite and at least the floor
 * for a closed element. */
#include "fuzz_gearbox_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wc_gearbox.h>
#include <wetclutch_can/wc_gearbox_image.h>

#include "wc_8hp_gearbox.h"
#include "wc_fuzz_common.h"

#define IMAGE_MAX WC_IMAGE_BYTES(WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES)

static unsigned long inputs;
static unsigned long loaded_count;

void fz_gearbox_image_counts(unsigned long *n, unsigned long *loaded)
{
    *n = inputs;
    *loaded = loaded_count;
}

static void fail(const char *what, uint32_t result, uint32_t error)
{
    fprintf(stderr, "fuzz_gearbox_image: %s (result %u, error %u)\n", what, (unsigned)result, (unsigned)error);
    abort();
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_le32(uint8_t *p, uint32_t v)
{
    for (uint32_t i = 0u; i < 4u; ++i) { p[i] = (uint8_t)(v >> (8u * i)); }
}

static uint32_t new_word(fz_reader_t *r, uint32_t old)
{
    const uint8_t how = fz_u8(r);
    float f = 0.0f;
    switch (how % 5u) {
    case 0: return fz_u32(r);
    case 1: return fz_u16(r) % 301u;
    case 2:
        f = fz_float(r, -25.0f, 25.0f);
        { uint32_t w; memcpy(&w, &f, sizeof w); return w; }
    case 3: return ((how & 0x80u) != 0u) ? old + 1u : old - 1u;
    default: return 0u;
    }
}

/* g with everything it does not use set to 0, by this harness's own reading of wc_gearbox_image.h: the gears
 * it lacks, the shifts past shift_count, the elements past element_count. */
static void zero_unused(wc_gearbox_t *g)
{
    for (uint32_t gear = 0u; gear < WC_GEARBOX_GEARS_MAX; ++gear) {
        const bool used = (gear == WC_GEARBOX_REVERSE) ? g->has_reverse : (gear <= g->forward_gears);
        if (!used) {
            g->ratio[gear] = 0.0f;
            g->closed_mask[gear] = 0u;
        }
        for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
            if (!used || (e >= g->element_count)) { g->holding_torque_per_Nm[gear][e] = 0.0f; }
        }
    }
    for (uint32_t i = 0u; i < WC_GEARBOX_SHIFTS_MAX; ++i) {
        if (i >= g->shift_count) {
            memset(&g->shift[i], 0, sizeof g->shift[i]);
            continue;
        }
        for (uint32_t e = g->element_count; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
            g->shift[i].slip[e].a = 0.0f;
            g->shift[i].slip[e].b = 0.0f;
        }
    }
}

static void check_loaded(const uint8_t *image, size_t length, const wc_gearbox_t *g)
{
    if (wc_gearbox_check(g) != WC_GEARBOX_OK) { fail("OK but wc_gearbox_check refuses it", 0u, 0u); }
    static uint8_t again[IMAGE_MAX];
    const size_t n = wc_gearbox_image_write(g, again, sizeof again);
    if ((n == 0u) || (n > length) || (memcmp(again, image, n) != 0)) { fail("OK but not its image's bytes", 0u, 0u); }
    /* one gearbox, one image: what it does not use was 0 in the image (+0: a -0 is a nonzero word) */
    static wc_gearbox_t used;
    used = *g;
    zero_unused(&used);
    if ((wc_gearbox_image_write(&used, again, sizeof again) != n) || (memcmp(again, image, n) != 0)) {
        fail("OK with a nonzero word the gearbox does not use", 0u, 0u);
    }
    static const float speeds_rad_s[] = { -1000.0f, 0.0f, 1.0f, 600.0f };
    for (uint32_t from = 0u; from < WC_GEARBOX_GEARS_MAX; ++from) {
        for (uint32_t to = 0u; to < WC_GEARBOX_GEARS_MAX; ++to) {
            const wc_gearbox_shift_t *s = NULL;
            if (wc_gearbox_find_shift(g, from, to, &s) != WC_GEARBOX_SHIFT_OK) { continue; }
            for (uint32_t e = 0u; e < g->element_count; ++e) {
                for (size_t i = 0u; i < sizeof speeds_rad_s / sizeof speeds_rad_s[0]; ++i) {
                    const float slip = wc_gearbox_element_slip_rad_s(s, e, speeds_rad_s[i], speeds_rad_s[3u - i]);
                    if (!isfinite(slip)) { fail("an element's slip not finite", from, to); }
                }
            }
        }
        for (uint32_t e = 0u; e < WC_GEARBOX_ELEMENTS_MAX; ++e) {
            const float request_Nm = wc_gearbox_holding_request_Nm(g, from, e, 400.0f, 1.3f, 30.0f);
            const bool closed = (from <= g->forward_gears) && (((g->closed_mask[from] >> e) & 1u) != 0u) &&
                                ((from != WC_GEARBOX_REVERSE) || g->has_reverse);
            if (!isfinite(request_Nm) || (closed && !(request_Nm >= 30.0f)) || (!closed && (request_Nm != 0.0f))) {
                fail("a holding request out of its contract", from, e);
            }
        }
    }
}

void fz_gearbox_image_input(const uint8_t *data, size_t size, bool verbose)
{
    ++inputs;
    fz_reader_t r;
    fz_reader_init(&r, data + 1, size - 1u);
    const uint8_t mode = fz_u8(&r) & 3u;
    static uint8_t image[IMAGE_MAX];
    const uint8_t *in = NULL;
    size_t length = 0u;
    uint8_t *copy = NULL;
    if (mode == 0u) {
        in = (size >= 2u) ? data + 2 : data;
        length = (size >= 2u) ? size - 2u : 0u;
    } else {
        length = wc_gearbox_image_write(&wc_gearbox_8hp, image, sizeof image);
        const uint32_t words = wc_gearbox_image_payload_bytes / 4u;
        if (mode == 3u) {
            put_le32(&image[WC_IMAGE_HEADER_BYTES + 4u * (fz_u16(&r) % words)], 1u);
        } else {
            while (fz_more(&r) && ((mode == 1u) || (r.size - r.pos > 5u))) {  /* mode 2: 5 bytes left for the cut */
                uint8_t *w = &image[WC_IMAGE_HEADER_BYTES + 4u * (fz_u16(&r) % words)];
                put_le32(w, new_word(&r, le32(w)));
            }
        }
        (void)wc_image_seal(image, sizeof image, WC_GEARBOX_IMAGE_MAGIC, WC_GEARBOX_IMAGE_VERSION,
                            wc_gearbox_image_payload_bytes);
        if (mode == 2u) {  /* position, xor, length: read in that order */
            const uint16_t position = fz_u16(&r);
            const uint8_t xor_mask = fz_u8(&r);
            const uint16_t cut = fz_u16(&r);
            image[position % length] ^= xor_mask;
            length = cut % (length + 1u);
        }
        copy = malloc(length > 0u ? length : 1u);  /* exactly its length: ASan sees a read past it */
        if (copy == NULL) { abort(); }
        memcpy(copy, image, length);
        in = copy;
    }
    static wc_gearbox_t g;
    memset(&g, 0xA5, sizeof g);
    const wc_gearbox_image_status_t s = wc_gearbox_image_load(length > 0u ? in : NULL, length, &g);
    if (verbose) {
        fprintf(stderr, "gearbox image: mode %u, %zu bytes: %s (%s)\n", (unsigned)mode, length,
                wc_gearbox_image_result_name(s.result), wc_gearbox_image_error_name(s));
    }
    if (s.result >= (uint32_t)WC_GEARBOX_IMAGE_RESULTS) { fail("an undocumented result", s.result, s.error); }
    if ((s.result == (uint32_t)WC_GEARBOX_IMAGE_BAD_FIELD) &&
        ((s.error >= wc_gearbox_image_payload_bytes) || (strcmp(wc_gearbox_image_error_name(s), "unknown") == 0))) {
        fail("BAD_FIELD without a field", s.result, s.error);
    }
    if ((s.result == (uint32_t)WC_GEARBOX_IMAGE_BAD_GEARBOX) && (s.error > (uint32_t)WC_GEARBOX_SHIFT_MODEL)) {
        fail("BAD_GEARBOX without a wc_gearbox_error_t", s.result, s.error);
    }
    if (s.result == (uint32_t)WC_GEARBOX_IMAGE_OK) {
        ++loaded_count;
        check_loaded(in, length, &g);
    } else {
        static const wc_gearbox_t zero;  /* the load memsets the whole struct, padding included */
        if (memcmp(&g, &zero, sizeof g) != 0) { fail("refused but not zeroed", s.result, s.error); }
    }
    free(copy);
}
