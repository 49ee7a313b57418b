"""The persistent image format of the firmware (include/wetclutch/wc_image.h): the same bytes.

Layout, every field little-endian::

    offset 0            magic           u32   which image this is
    offset 4            layout version  u32   of the payload's layout
    offset 8            payload length  u32   bytes
    offset 12           reserved        u32   0 (a nonzero value is invalid)
    offset 16           payload         payload length bytes
    offset 16 + length  CRC-32          u32   zlib.crc32 over bytes [0, 16 + length)

Bytes after the CRC are ignored (the rest of a flash sector). ``read_image`` checks in the firmware's order
and names what it found with the firmware's status names (``wc_image_status_t``).
"""
from __future__ import annotations

import enum
import struct
import zlib

HEADER_BYTES = 16
CRC_BYTES = 4
PAYLOAD_MAX_BYTES = 16384       # WC_IMAGE_PAYLOAD_MAX_BYTES

_HEADER = struct.Struct("<IIII")
_U32 = struct.Struct("<I")


class ImageStatus(enum.IntEnum):
    """wc_image_status_t: the codes and names of the firmware."""
    OK = 0
    MISSING = 1         # no image (empty)
    TRUNCATED = 2       # shorter than the header, or than header + declared payload + CRC
    BAD_MAGIC = 3
    BAD_VERSION = 4
    BAD_LENGTH = 5      # declared length not the expected one, or reserved != 0
    BAD_CRC = 6


class ImageError(ValueError):
    """An image that cannot be used; ``status`` says why (an ImageStatus, or a payload's own reason)."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(message)
        self.status = status


def image_bytes(payload_length: int) -> int:
    """The whole image of a payload of payload_length bytes (WC_IMAGE_BYTES)."""
    return HEADER_BYTES + payload_length + CRC_BYTES


def crc32(data: bytes) -> int:
    """CRC-32 (IEEE 802.3, zlib), as wc_image_crc32."""
    return zlib.crc32(data) & 0xFFFFFFFF


def write_image(magic: int, version: int, payload: bytes) -> bytes:
    """The image of payload: header, payload, CRC (wc_image_write)."""
    if len(payload) > PAYLOAD_MAX_BYTES:
        raise ValueError(f"image payload of {len(payload)} bytes, longer than {PAYLOAD_MAX_BYTES}")
    body = _HEADER.pack(magic, version, len(payload), 0) + bytes(payload)
    return body + _U32.pack(crc32(body))


def check_image(image: bytes | None, magic: int, version: int,
                payload_length: int) -> tuple[ImageStatus, bytes | None]:
    """(status, payload) of image as wc_image_read finds it; payload is None unless the status is OK."""
    if not image:
        return ImageStatus.MISSING, None
    if len(image) < HEADER_BYTES:
        return ImageStatus.TRUNCATED, None
    got_magic, got_version, got_length, reserved = _HEADER.unpack_from(image, 0)
    if got_magic != magic:
        return ImageStatus.BAD_MAGIC, None
    if got_version != version:
        return ImageStatus.BAD_VERSION, None
    if got_length != payload_length or payload_length > PAYLOAD_MAX_BYTES or reserved != 0:
        return ImageStatus.BAD_LENGTH, None
    end = HEADER_BYTES + payload_length
    if len(image) < end + CRC_BYTES:
        return ImageStatus.TRUNCATED, None
    if _U32.unpack_from(image, end)[0] != crc32(bytes(image[:end])):
        return ImageStatus.BAD_CRC, None
    return ImageStatus.OK, bytes(image[HEADER_BYTES:end])


_REASONS = {
    ImageStatus.MISSING: "no image (empty)",
    ImageStatus.TRUNCATED: "truncated",
    ImageStatus.BAD_MAGIC: "not this kind of image (magic)",
    ImageStatus.BAD_VERSION: "another layout version",
    ImageStatus.BAD_LENGTH: "payload length not the expected one, or reserved field not 0",
    ImageStatus.BAD_CRC: "CRC-32 mismatch: the bytes changed since they were written",
}


def read_image(image: bytes | None, magic: int, version: int, payload_length: int, what: str = "image") -> bytes:
    """The payload of image; an ImageError naming the status (``BAD_CRC: ...``) when check_image does not
    find it OK. what names the image in the message (a file name)."""
    status, payload = check_image(image, magic, version, payload_length)
    if status is not ImageStatus.OK:
        detail = _detail(image, magic, version, payload_length, status)
        raise ImageError(status.name, f"{what}: {status.name}: {_REASONS[status]}{detail}")
    assert payload is not None
    return payload


def _detail(image: bytes | None, magic: int, version: int, payload_length: int, status: ImageStatus) -> str:
    """What was found against what was expected, for the message."""
    if status is ImageStatus.TRUNCATED:
        return f" ({len(image or b'')} bytes)"
    if status in (ImageStatus.MISSING, ImageStatus.BAD_CRC):
        return ""
    got_magic, got_version, got_length, reserved = _HEADER.unpack_from(image, 0)
    if status is ImageStatus.BAD_MAGIC:
        return f" (0x{got_magic:08X}, expected 0x{magic:08X})"
    if status is ImageStatus.BAD_VERSION:
        return f" ({got_version}, expected {version})"
    return f" ({got_length} bytes, expected {payload_length}; reserved 0x{reserved:08X})"


def hex_text(data: bytes, comments: list[str], words_per_line: int = 8) -> str:
    """An image as a golden vector's text (tests/vectors/*.hex, read by tests/c/wc_test_support.h's
    wc_test_read_hex): each comment a '# ' line, then the bytes in file order, 4 a group, words_per_line a line."""
    words = [data[i:i + 4].hex() for i in range(0, len(data), 4)]
    lines = [" ".join(words[i:i + words_per_line]) for i in range(0, len(words), words_per_line)]
    return "".join(f"# {c}\n" for c in comments) + "\n".join(lines) + "\n"
