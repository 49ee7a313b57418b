/* A persistent image: a versioned, length-checked, CRC-protected byte block
 * that the firmware keeps in flash or EEPROM and checks before it trusts it
 * (DESIGN 12, 13). One format for every image: the adaptation's
 * (wc_adapt_image.h) and, next, the whole calibration's.
 *
 * Layout, every field little-endian, written and read byte by byte (the same
 * bytes on every host and target, whatever its endianness or alignment; no
 * struct is copied):
 *     offset 0              magic           u32   which image this is
 *     offset 4              layout version  u32   of the payload's layout
 *     offset 8              payload length  u32   bytes
 *     offset 12             reserved        u32   0 (a nonzero value is invalid)
 *     offset 16             payload         payload length bytes
 *     offset 16 + length    CRC-32          u32   over bytes [0, 16 + length)
 * CRC-32: IEEE 802.3, as zlib's crc32 (reflected polynomial 0xEDB88320, init
 * and final xor 0xFFFFFFFF; check value "123456789" -> 0xCBF43926), computed
 * with a 16-entry table (64 bytes of flash, two lookups a byte). Bytes after
 * the CRC (the rest of a flash sector) are ignored.
 * tools/wetclutch/util/image.py writes and reads the same bytes.
 *
 * Calls: pure functions of their arguments, no state; safe from any context
 * on distinct buffers. Every loop is bounded by its length argument, and the
 * reader by WC_IMAGE_PAYLOAD_MAX_BYTES: it never reads past `length`. */
#ifndef WC_IMAGE_H
#define WC_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "wc_config.h"

#define WC_IMAGE_HEADER_BYTES 16u
#define WC_IMAGE_CRC_BYTES 4u
/* The whole image of a payload of n bytes. */
#define WC_IMAGE_BYTES(payload_bytes) (WC_IMAGE_HEADER_BYTES + (payload_bytes) + WC_IMAGE_CRC_BYTES)

/* The longest payload an image may declare: a longer one is BAD_LENGTH (and
 * so the CRC loop's bound). Enough for a calibration with a film table of
 * WC_FILM_MAX_NODES nodes (3 floats each) and its scalar fields. */
#ifndef WC_IMAGE_PAYLOAD_MAX_BYTES
#define WC_IMAGE_PAYLOAD_MAX_BYTES 16384u
#endif

/* What wc_image_read found, in the order it checks (tools/wetclutch/util/image.py
 * uses the same codes and names). */
typedef enum {
    WC_IMAGE_OK = 0,
    WC_IMAGE_MISSING = 1,       /* no image: NULL or length 0 (an erased or never written store) */
    WC_IMAGE_TRUNCATED = 2,     /* shorter than the header, or than the header + declared payload + CRC */
    WC_IMAGE_BAD_MAGIC = 3,     /* not this kind of image */
    WC_IMAGE_BAD_VERSION = 4,   /* another layout version */
    WC_IMAGE_BAD_LENGTH = 5,    /* declared length not the expected one, or reserved != 0 */
    WC_IMAGE_BAD_CRC = 6,       /* the bytes changed since they were written */
    WC_IMAGE_STATUSES = 7       /* number of codes; extensions (wc_adapt_image.h) start here */
} wc_image_status_t;

/* CRC-32 (IEEE 802.3 / zlib) of length bytes; 0 for length 0. data may be
 * NULL only with length 0. */
uint32_t wc_image_crc32(const uint8_t *data, size_t length);

/* Writes the image of payload (payload_length bytes) to image[0 ..): header,
 * payload, CRC. Returns the bytes written, WC_IMAGE_BYTES(payload_length);
 * 0 (nothing written) when image is NULL, capacity is too small, the payload
 * is longer than WC_IMAGE_PAYLOAD_MAX_BYTES or NULL with a nonzero length.
 * payload must not overlap image, unless it is already in place at
 * image + WC_IMAGE_HEADER_BYTES (then it is left as it is: wc_image_seal). */
size_t wc_image_write(uint8_t *image, size_t capacity, uint32_t magic, uint32_t version, const uint8_t *payload,
                      uint32_t payload_length);

/* The same, for a payload already in place at image + WC_IMAGE_HEADER_BYTES
 * (encoded there by the caller, no copy and no buffer): writes the header
 * and the CRC around it. Same return value. */
size_t wc_image_seal(uint8_t *image, size_t capacity, uint32_t magic, uint32_t version, uint32_t payload_length);

/* Checks image (length bytes available) in this order: MISSING, TRUNCATED
 * (no whole header), BAD_MAGIC, BAD_VERSION, BAD_LENGTH (the declared length
 * must be payload_length, at most WC_IMAGE_PAYLOAD_MAX_BYTES, and reserved
 * 0), TRUNCATED (fewer than WC_IMAGE_BYTES(payload_length) bytes), BAD_CRC.
 * On OK *payload points at the payload inside image; otherwise *payload is
 * NULL. payload may be NULL (status only). Never reads past image[length - 1]. */
wc_image_status_t wc_image_read(const uint8_t *image, size_t length, uint32_t magic, uint32_t version,
                                uint32_t payload_length, const uint8_t **payload);

/* Little-endian fields, byte by byte: 4 bytes at dst / from src. A float
 * travels as its IEEE-754 bit pattern (NaN payloads and -0 kept). */
void wc_image_put_u32(uint8_t *dst, uint32_t value);
uint32_t wc_image_get_u32(const uint8_t *src);
void wc_image_put_f32(uint8_t *dst, float value);
float wc_image_get_f32(const uint8_t *src);

#endif /* WC_IMAGE_H */
