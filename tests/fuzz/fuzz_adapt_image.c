/* The adaptation image (wc_adapt_image.h, wc_image.h) under libFuzzer, as an
 * extra input interpretation of fuzz_calibration (byte 0 bit 7 set; README.md
 * says why it has no harness of its own).
 *
 * Input after byte 0:
 *   byte 1  bits 0-1: the image
 *             0  the remaining bytes as they are (any length, read in place:
 *                AddressSanitizer sees a read past them);
 *             1  the remaining bytes as the payload (zero-padded to 56) of a
 *                well-formed image: header and CRC right;
 *             2  as 1, then one byte changed (position, xor) and the image cut
 *                to a length (2 more bytes each);
 *             3  a well-formed image of fz_float values around the bands
 *                (inside, on the edges, one ulp outside, NaN, Inf, raw bits);
 *           bit 2: the expected clutch id is read (u32), otherwise the image's;
 *           bit 3: the calibration's bands read too (scale band, film factor
 *                min and max, kiss band), kept when wc_shift_calibration_check
 *                accepts them;
 *           bit 4: the test's shift_1_2 calibration with adaptation off
 *                instead of the adaptive one.
 *   Modes 1-3 copy the image to a buffer of exactly its length.
 * Oracle (abort with a message): the result is one of the documented codes
 * and the one an independent reading of the bytes gives (the format's checks
 * in order, a bitwise CRC-32, the clutch id, the values against the bands);
 * after the load every value is finite and inside the bands; OK: the values
 * are the image's bit for bit and wc_adapt_image_write gives the image's
 * bytes back; any other result: the calibration's values (1, 0, 1, 0, 0);
 * the status bits: none of the image bits for OK, MISSING for MISSING,
 * INVALID otherwise, the other bits kept. */
#include "fuzz_adapt_image.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <wetclutch/wc_adapt_image.h>
#include <wetclutch/wetclutch.h>

#include "wc_fuzz_common.h"
#include "wc_shift_1_2_shift.h"

#define PAYLOAD WC_ADAPT_IMAGE_PAYLOAD_BYTES
#define IMAGE WC_ADAPT_IMAGE_BYTES

static unsigned long images;
static unsigned long images_loaded;

void fz_adapt_image_counts(unsigned long *inputs, unsigned long *loaded)
{
    *inputs = images;
    *loaded = images_loaded;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_le32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0u; i < 4u; ++i) { p[i] = (uint8_t)(v >> (8u * i)); }
}

static float f32_at(const uint8_t *p)
{
    const uint32_t bits = le32(p);
    float x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

/* CRC-32 bit by bit: the definition, apart from the library's table form. */
static uint32_t crc32_bitwise(const uint8_t *data, size_t length)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0u; i < length; ++i) {
        crc ^= data[i];
        for (unsigned k = 0u; k < 8u; ++k) { crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u))); }
    }
    return ~crc;
}

static bool within(float x, float lo, float hi) { return fz_finite(x) && (x >= lo) && (x <= hi); }

/* The values inside cal's bands, each checked here (not by wc_adapt_values_valid). */
static bool in_bands(const wc_adapt_values_t *v, const wc_shift_calibration_t *cal)
{
    bool ok = within(v->film_factor, cal->adapt_film_factor_min, cal->adapt_film_factor_max) &&
              within(v->kiss_offset_Pa, -cal->adapt_kiss_band_Pa, cal->adapt_kiss_band_Pa);
    for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
        ok = ok && within(v->friction_scale[i], 1.0f - cal->adapt_scale_band, 1.0f + cal->adapt_scale_band) &&
             within(v->confidence[i], 0.0f, 1.0f);
    }
    return ok;
}

/* What the load must find in image[0 .. n), read independently of the
 * library; the decoded values in *v when the bytes hold them. */
static uint32_t expected_result(const uint8_t *image, size_t n, uint32_t clutch_id, const wc_shift_calibration_t *cal,
                                wc_adapt_values_t *v)
{
    if (n == 0u) { return WC_IMAGE_MISSING; }
    if (n < 16u) { return WC_IMAGE_TRUNCATED; }
    if (le32(image) != WC_ADAPT_IMAGE_MAGIC) { return WC_IMAGE_BAD_MAGIC; }
    if (le32(&image[4]) != WC_ADAPT_IMAGE_VERSION) { return WC_IMAGE_BAD_VERSION; }
    if ((le32(&image[8]) != PAYLOAD) || (le32(&image[12]) != 0u)) { return WC_IMAGE_BAD_LENGTH; }
    if (n < IMAGE) { return WC_IMAGE_TRUNCATED; }
    if (le32(&image[16u + PAYLOAD]) != crc32_bitwise(image, 16u + PAYLOAD)) { return WC_IMAGE_BAD_CRC; }
    if (le32(&image[16]) != clutch_id) { return WC_ADAPT_IMAGE_WRONG_CLUTCH; }
    for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
        v->friction_scale[i] = f32_at(&image[20u + 4u * i]);
        v->confidence[i] = f32_at(&image[40u + 4u * i]);
    }
    v->film_factor = f32_at(&image[60]);
    v->kiss_offset_Pa = f32_at(&image[64]);
    v->shifts_learned = le32(&image[68]);
    return in_bands(v, cal) ? (uint32_t)WC_IMAGE_OK : WC_ADAPT_IMAGE_BAD_VALUES;
}

/* A well-formed image around payload[0 .. PAYLOAD). */
static void seal(uint8_t image[IMAGE])
{
    put_le32(image, WC_ADAPT_IMAGE_MAGIC);
    put_le32(&image[4], WC_ADAPT_IMAGE_VERSION);
    put_le32(&image[8], PAYLOAD);
    put_le32(&image[12], 0u);
    put_le32(&image[16u + PAYLOAD], crc32_bitwise(image, 16u + PAYLOAD));
}

static void put_f32(uint8_t *p, float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    put_le32(p, bits);
}

void fz_adapt_image_input(const uint8_t *data, size_t size, bool verbose)
{
    fz_reader_t r;
    fz_reader_init(&r, data, size);
    (void)fz_u8(&r);  /* byte 0: the marker */
    const uint8_t how = fz_u8(&r);
    wc_shift_calibration_t cal = ((how & 0x10u) != 0u) ? wc_shift_1_2_full : wc_shift_1_2_adaptive;
    const uint32_t other_clutch = ((how & 0x04u) != 0u) ? fz_u32(&r) : 0u;
    bool bands_edited = false;
    if ((how & 0x08u) != 0u) {
        wc_shift_calibration_t edited = cal;
        edited.adapt_scale_band = fz_float(&r, 0.0f, WC_CORRECTION_SCALE_MAX);
        edited.adapt_film_factor_min = fz_float(&r, 0.0f, 1.0f);
        edited.adapt_film_factor_max = fz_float(&r, 1.0f, 10.0f);
        edited.adapt_kiss_band_Pa = fz_float(&r, 0.0f, 1e6f);
        if (wc_shift_calibration_check(&edited) == WC_SHIFT_CAL_OK) {
            cal = edited;
            bands_edited = true;
        }
    }

    uint8_t *copy = NULL;
    const uint8_t *image = &data[r.pos < size ? r.pos : size];
    size_t length = size - (r.pos < size ? r.pos : size);
    if ((how & 3u) != 0u) {
        uint8_t built[IMAGE];
        memset(built, 0, sizeof built);
        if ((how & 3u) == 3u) {
            put_le32(&built[16], fz_u32(&r));
            for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
                put_f32(&built[20u + 4u * i], fz_float(&r, 1.0f - cal.adapt_scale_band, 1.0f + cal.adapt_scale_band));
                put_f32(&built[40u + 4u * i], fz_float(&r, 0.0f, 1.0f));
            }
            put_f32(&built[60], fz_float(&r, cal.adapt_film_factor_min, cal.adapt_film_factor_max));
            put_f32(&built[64], fz_float(&r, -cal.adapt_kiss_band_Pa, cal.adapt_kiss_band_Pa));
            put_le32(&built[68], fz_u32(&r));
        } else {
            for (unsigned i = 0u; (i < PAYLOAD) && fz_more(&r); ++i) { built[16u + i] = fz_u8(&r); }
        }
        seal(built);
        length = IMAGE;
        if ((how & 3u) == 2u) {
            built[fz_u8(&r) % IMAGE] ^= fz_u8(&r);
            length = fz_u8(&r) % (IMAGE + 1u);
        }
        copy = (uint8_t *)malloc(length > 0u ? length : 1u);  /* exactly length bytes for ASan */
        if (copy == NULL) { abort(); }
        memcpy(copy, built, length);
        image = copy;
    }
    const uint32_t clutch_id = ((how & 0x04u) != 0u) ? other_clutch : ((length >= 20u) ? le32(&image[16]) : 0u);

    wc_adapt_values_t decoded;
    memset(&decoded, 0, sizeof decoded);
    const uint32_t expected = expected_result(image, length, clutch_id, &cal, &decoded);

    wc_adapt_t adapt;
    memset(&adapt, 0, sizeof adapt);
    wc_adapt_reset(&adapt);
    adapt.values.friction_scale[0] = 1.1f;  /* learned before: a failed load must reset it */
    adapt.values.shifts_learned = 7u;
    adapt.status = WC_ADAPT_STATUS_RESET | WC_ADAPT_STATUS_IMAGE_INVALID;
    fz_context("wc_adapt_image_load", 0u);
    fz_ctx.iargs[0] = (long)length;
    fz_ctx.iargs[1] = (long)clutch_id;
    const uint32_t result = wc_adapt_image_load(&adapt, &cal, clutch_id, image, length);
    images++;
    if (verbose) {
        fprintf(stderr, "fuzz_adapt_image: %zu bytes, clutch %u, mode %u, %s bands: result %u (expected %u)\n",
                length, (unsigned)clutch_id, (unsigned)(how & 3u), bands_edited ? "fuzzed" : "the calibration's",
                (unsigned)result, (unsigned)expected);
    }

    FZ_CHECK(result < WC_ADAPT_IMAGE_RESULTS, "result %u not a documented code", (unsigned)result);
    FZ_CHECK(result == expected, "result %u, the bytes say %u", (unsigned)result, (unsigned)expected);
    const wc_adapt_values_t *v = &adapt.values;
    FZ_CHECK(in_bands(v, &cal), "a value outside its band or not finite after the load: scale[0] %g conf[0] %g "
             "film %g kiss %g", (double)v->friction_scale[0], (double)v->confidence[0], (double)v->film_factor,
             (double)v->kiss_offset_Pa);
    FZ_CHECK(wc_adapt_values_valid(v, &cal), "wc_adapt_values_valid refuses the loaded values");
    const uint32_t image_bits = adapt.status & (WC_ADAPT_STATUS_IMAGE_MISSING | WC_ADAPT_STATUS_IMAGE_INVALID);
    const uint32_t want_bits = (result == (uint32_t)WC_IMAGE_OK) ? 0u
                             : (result == (uint32_t)WC_IMAGE_MISSING) ? WC_ADAPT_STATUS_IMAGE_MISSING
                                                                      : WC_ADAPT_STATUS_IMAGE_INVALID;
    FZ_CHECK((image_bits == want_bits) && ((adapt.status & WC_ADAPT_STATUS_RESET) != 0u),
             "status 0x%x after result %u", (unsigned)adapt.status, (unsigned)result);
    if (result == (uint32_t)WC_IMAGE_OK) {
        images_loaded++;
        FZ_CHECK(memcmp(v, &decoded, sizeof decoded) == 0, "loaded values differ from the image's bits");
        uint8_t again[IMAGE];
        FZ_CHECK(wc_adapt_image_write(&adapt, clutch_id, again, sizeof again) == IMAGE, "write refused");
        FZ_CHECK(memcmp(again, image, IMAGE) == 0, "writing the loaded values does not give the image back");
    } else {
        wc_adapt_t reference;
        memset(&reference, 0, sizeof reference);
        wc_adapt_reset(&reference);
        FZ_CHECK(memcmp(v, &reference.values, sizeof reference.values) == 0, "a failed load kept learned values");
        for (unsigned i = 0u; i < WC_ADAPT_NODES; ++i) {
            FZ_CHECK((v->friction_scale[i] == 1.0f) && (v->confidence[i] == 0.0f), "default node %u", i);
        }
        FZ_CHECK((v->film_factor == 1.0f) && (v->kiss_offset_Pa == 0.0f) && (v->shifts_learned == 0u),
                 "defaults: film %g kiss %g shifts %u", (double)v->film_factor, (double)v->kiss_offset_Pa,
                 (unsigned)v->shifts_learned);
    }
    free(copy);
}
