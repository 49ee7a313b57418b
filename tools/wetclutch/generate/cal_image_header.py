"""A calibration image as a committed C header (``wetclutch cal-image ... --out lut/NAME.h``): the image's bytes as
a static const array in the calibration's linker section (WC_CAL_IMAGE_SECTION, ``.wc_calibration`` on the
target), for firmware that links its calibration image rather than reading it from a store."""
from __future__ import annotations

import struct
from pathlib import Path

from ..util.atomic import write_text
from .lut import banner, c_identifier


def header_text(image: bytes, ident: str, command: str, what: str) -> str:
    up = ident.upper()
    crc = struct.unpack_from("<I", image, len(image) - 4)[0]
    rows = [", ".join(f"0x{b:02X}" for b in image[i:i + 16]) for i in range(0, len(image), 16)]
    return (banner(command)
            + f"/* The calibration image (wc_cal_image.h) of {what}:\n"
            f" * {len(image)} bytes, CRC-32 0x{crc:08X}. In its own linker section (WC_CAL_IMAGE_SECTION:\n"
            f" * .wc_calibration on the target), checked at init by wc_cal_image_load({ident},\n"
            f" * {up}_BYTES, &set). Include in one translation unit. */\n"
            f"#ifndef WC_LUT_{up}_H\n#define WC_LUT_{up}_H\n\n#include <stdint.h>\n\n"
            "#include <wetclutch_can/wc_cal_image.h>\n\n"
            f"#define {up}_BYTES {len(image)}u\n\n"
            f"static const uint8_t {ident}[{up}_BYTES] WC_CAL_IMAGE_SECTION = {{\n"
            + "".join(f"    {row},\n" for row in rows) + "};\n\n"
            f"#endif /* WC_LUT_{up}_H */\n")


def write_header(path, image: bytes, command: str, what: str) -> Path:
    """The header of image at path (its stem is the array's C name), written atomically."""
    path = Path(path)
    write_text(path, header_text(image, c_identifier(path.stem), command, what))
    return path
