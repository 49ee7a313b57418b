/* The persistent image format (include/wetclutch/wc_image.h; DESIGN 12, 13). */
#include "wetclutch/wc_image.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define WC_IMAGE_OFFSET_MAGIC 0u
#define WC_IMAGE_OFFSET_VERSION 4u
#define WC_IMAGE_OFFSET_LENGTH 8u
#define WC_IMAGE_OFFSET_RESERVED 12u

WC_STATIC_ASSERT(WC_IMAGE_HEADER_BYTES == WC_IMAGE_OFFSET_RESERVED + 4u, image_header_is_four_words);
WC_STATIC_ASSERT(sizeof(float) == sizeof(uint32_t), image_float_is_32_bits);
/* WC_IMAGE_BYTES(WC_IMAGE_PAYLOAD_MAX_BYTES) fits a size_t and a uint32_t on every target. */
WC_STATIC_ASSERT(WC_IMAGE_PAYLOAD_MAX_BYTES <= 0x7FFFFFFFu, image_payload_max_fits);

/* CRC-32 of the reflected polynomial 0xEDB88320 for the 16 values of a
 * nibble: crc32_nibble[n] = the register after shifting n through four bit
 * steps (zlib's crc32 one nibble at a time). */
static const uint32_t crc32_nibble[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
    0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu, 0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
};

uint32_t wc_image_crc32(const uint8_t *data, size_t length)
{
    uint32_t crc = 0xFFFFFFFFu;
    const size_t n = (data != NULL) ? length : 0u;
    for (size_t i = 0u; i < n; ++i) {
        crc ^= (uint32_t)data[i];
        crc = (crc >> 4) ^ crc32_nibble[crc & 0x0Fu];
        crc = (crc >> 4) ^ crc32_nibble[crc & 0x0Fu];
    }
    return crc ^ 0xFFFFFFFFu;
}

void wc_image_put_u32(uint8_t *dst, uint32_t value)
{
    dst[0] = (uint8_t)(value & 0xFFu);
    dst[1] = (uint8_t)((value >> 8) & 0xFFu);
    dst[2] = (uint8_t)((value >> 16) & 0xFFu);
    dst[3] = (uint8_t)((value >> 24) & 0xFFu);
}

uint32_t wc_image_get_u32(const uint8_t *src)
{
    return (uint32_t)src[0] | ((uint32_t)src[1] << 8) | ((uint32_t)src[2] << 16) | ((uint32_t)src[3] << 24);
}

void wc_image_put_f32(uint8_t *dst, float value)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    wc_image_put_u32(dst, bits);
}

float wc_image_get_f32(const uint8_t *src)
{
    const uint32_t bits = wc_image_get_u32(src);
    float value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

/* The image of payload_length bytes fits capacity and the format's limit. */
static bool image_fits(const uint8_t *image, size_t capacity, uint32_t payload_length)
{
    return (image != NULL) && (payload_length <= WC_IMAGE_PAYLOAD_MAX_BYTES) &&
           (capacity >= (size_t)WC_IMAGE_BYTES(payload_length));
}

size_t wc_image_seal(uint8_t *image, size_t capacity, uint32_t magic, uint32_t version, uint32_t payload_length)
{
    if (!image_fits(image, capacity, payload_length)) { return 0u; }
    const size_t crc_offset = (size_t)WC_IMAGE_HEADER_BYTES + (size_t)payload_length;
    wc_image_put_u32(&image[WC_IMAGE_OFFSET_MAGIC], magic);
    wc_image_put_u32(&image[WC_IMAGE_OFFSET_VERSION], version);
    wc_image_put_u32(&image[WC_IMAGE_OFFSET_LENGTH], payload_length);
    wc_image_put_u32(&image[WC_IMAGE_OFFSET_RESERVED], 0u);
    wc_image_put_u32(&image[crc_offset], wc_image_crc32(image, crc_offset));
    return crc_offset + WC_IMAGE_CRC_BYTES;
}

size_t wc_image_write(uint8_t *image, size_t capacity, uint32_t magic, uint32_t version, const uint8_t *payload,
                      uint32_t payload_length)
{
    if (!image_fits(image, capacity, payload_length) || ((payload == NULL) && (payload_length > 0u))) { return 0u; }
    uint8_t *destination = &image[WC_IMAGE_HEADER_BYTES];
    if (payload != destination) {
        /* byte by byte: no C library call (the footprint check links only what the step uses) */
        for (uint32_t i = 0u; i < payload_length; ++i) { destination[i] = payload[i]; }
    }
    return wc_image_seal(image, capacity, magic, version, payload_length);
}

wc_image_status_t wc_image_read(const uint8_t *image, size_t length, uint32_t magic, uint32_t version,
                                uint32_t payload_length, const uint8_t **payload)
{
    wc_image_status_t status = WC_IMAGE_OK;
    if (payload != NULL) { *payload = NULL; }
    if ((image == NULL) || (length == 0u)) {
        status = WC_IMAGE_MISSING;
    } else if (length < (size_t)WC_IMAGE_HEADER_BYTES) {
        status = WC_IMAGE_TRUNCATED;
    } else if (wc_image_get_u32(&image[WC_IMAGE_OFFSET_MAGIC]) != magic) {
        status = WC_IMAGE_BAD_MAGIC;
    } else if (wc_image_get_u32(&image[WC_IMAGE_OFFSET_VERSION]) != version) {
        status = WC_IMAGE_BAD_VERSION;
    } else if ((wc_image_get_u32(&image[WC_IMAGE_OFFSET_LENGTH]) != payload_length) ||
               (payload_length > WC_IMAGE_PAYLOAD_MAX_BYTES) ||
               (wc_image_get_u32(&image[WC_IMAGE_OFFSET_RESERVED]) != 0u)) {
        status = WC_IMAGE_BAD_LENGTH;
    } else if (length < (size_t)WC_IMAGE_BYTES(payload_length)) {
        status = WC_IMAGE_TRUNCATED;
    } else {
        /* payload_length <= WC_IMAGE_PAYLOAD_MAX_BYTES: no overflow, and the CRC lies inside length */
        const size_t crc_offset = (size_t)WC_IMAGE_HEADER_BYTES + (size_t)payload_length;
        if (wc_image_get_u32(&image[crc_offset]) != wc_image_crc32(image, crc_offset)) {
            status = WC_IMAGE_BAD_CRC;
        } else if (payload != NULL) {
            *payload = &image[WC_IMAGE_HEADER_BYTES];
        } else {
            /* status only */
        }
    }
    return status;
}
