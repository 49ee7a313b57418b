"""The gearbox image's C codec, generated from its layout (calibration/gearbox_image.py):
src/can/generated/wc_gearbox_image_layout.h (each field's offset, the rows a gear or a shift owns) and
wc_gearbox_image_layout.c (encode and decode of every field of wc_gearbox_t, little-endian byte by byte
through wc_image_put/get_*; the fields' names).

    python -m wetclutch.generate.gearbox_image_layout [--out ROOT]     (ROOT: the repository, by default)

tests/python/test_gearbox_image.py regenerates both into a temporary tree and compares them byte for byte.
"""
from __future__ import annotations

import sys
from pathlib import Path

from ..calibration import gearbox_image as layout
from .cal_image_layout import field_name_lookup, generator_main, write_generated
from .lut import banner

COMMAND = "python -m wetclutch.generate.gearbox_image_layout"
HEADER = Path("src/can/generated/wc_gearbox_image_layout.h")
SOURCE = Path("src/can/generated/wc_gearbox_image_layout.c")
_BOUND = {"GEARS": "WC_GEARBOX_GEARS_MAX", "ELEMENTS": "WC_GEARBOX_ELEMENTS_MAX", "SHIFTS": "WC_GEARBOX_SHIFTS_MAX"}
_INDEX = ("i", "j")


def macro(field: layout.Field) -> str:
    """The offset macro of a field: WC_GEARBOX_IMAGE_OFFSET_SHIFT_SLIP_A."""
    return "WC_GEARBOX_IMAGE_OFFSET_" + field.name.removeprefix("gearbox.").upper().replace(".", "_")


def _rows(dim: str) -> list[layout.Field]:
    return [f for f in layout.FIELDS if f.dims and f.dims[0] == dim]


def _narrow() -> list[layout.Field]:
    """The fields whose C member is narrower than the wire's u32 (bool, uint8_t): the loader checks their words."""
    return [f for f in layout.FIELDS if f.c_type]


_NARROW_MAX = {"bool": 1, "uint8_t": 255}
_C_BYTES = {"bool": 1, "uint8_t": 1, "": 4}
SHIFT_BYTES = 4 + 4 * (2 * layout.ELEMENTS + 7)   # wc_gearbox_shift_t: four uint8_t, the slip maps, seven floats


def _struct_bytes() -> int:
    """sizeof(wc_gearbox_t) by C's layout rules of its members as the layout lists them (4-byte alignment for
    u32 and float, 1 for bool and uint8_t; a shift row is SHIFT_BYTES): a member the layout lacks changes it."""
    size = 0
    for f in layout.FIELDS:
        if f.name.startswith("gearbox.shift."):
            continue
        elem = _C_BYTES[f.c_type]
        size = (size + elem - 1) // elem * elem + elem * f.count
        if f.name == "gearbox.shift_count":
            size += SHIFT_BYTES * layout.SHIFTS
    return (size + 3) // 4 * 4


# every array is a gear's or a shift's rows (the loader's unused-word rule covers it), its second index an element
for _f in layout.FIELDS:
    assert not _f.dims or (_f.dims[0] in ("GEARS", "SHIFTS") and _f.dims[1:] in ((), ("ELEMENTS",))), _f.name
    assert _f.c_type in _NARROW_MAX or _f.c_type == "", _f.name


def header_text() -> str:
    lines = [banner(COMMAND).rstrip("\n"),
             "/* The gearbox image's payload layout (tools/wetclutch/calibration/gearbox_image.py): each field's",
             " * byte offset, the rows a gear or a shift owns, and the codec of wc_gearbox_image_layout.c.",
             " * Private to wetclutch_can: the public API is include/wetclutch_can/wc_gearbox_image.h. */",
             "#ifndef WC_GEARBOX_IMAGE_LAYOUT_H", "#define WC_GEARBOX_IMAGE_LAYOUT_H", "",
             "#include <stdint.h>", "", "#include \"wetclutch/wc_gearbox.h\"", ""]
    for f in layout.FIELDS:
        size = f"  /* {f.ctype}[{']['.join(f.dims)}] */" if f.dims else ""
        lines.append(f"#define {macro(f)} {f.offset}u{size}")
    lines += ["", f"#define WC_GEARBOX_IMAGE_PAYLOAD_BYTES {layout.payload_bytes()}u",
              f"#define WC_GEARBOX_IMAGE_GEAR_FIELDS {len(_rows('GEARS'))}u",
              f"#define WC_GEARBOX_IMAGE_SHIFT_FIELDS {len(_rows('SHIFTS'))}u", "",
              "/* A field indexed by gear or by shift: row r's words start at offset + 4 row_words r; with",
              " * per_element the row's word e belongs to element e. */",
              "typedef struct {", "    uint16_t offset;", "    uint8_t row_words;", "    uint8_t per_element;",
              "} wc_gearbox_image_rows_t;", "",
              "extern const wc_gearbox_image_rows_t wc_gearbox_image_gear_rows[WC_GEARBOX_IMAGE_GEAR_FIELDS];",
              "extern const wc_gearbox_image_rows_t wc_gearbox_image_shift_rows[WC_GEARBOX_IMAGE_SHIFT_FIELDS];", "",
              "/* Every field of gearbox into payload (WC_GEARBOX_IMAGE_PAYLOAD_BYTES), as the struct holds it. */",
              "void wc_gearbox_image_layout_encode(const wc_gearbox_t *gearbox, uint8_t *payload);", "",
              "/* A narrow member (bool, uint8_t): count words from offset, each at most max. */",
              "typedef struct {", "    uint16_t offset;", "    uint8_t count;", "    uint8_t max;",
              "} wc_gearbox_image_narrow_t;", "",
              f"#define WC_GEARBOX_IMAGE_NARROW_FIELDS {len(_narrow())}u",
              "extern const wc_gearbox_image_narrow_t wc_gearbox_image_narrow[WC_GEARBOX_IMAGE_NARROW_FIELDS];", "",
              "/* Every field of payload into gearbox, unchecked: the narrow members (bool, uint8_t) take the",
              " * low bits, so the caller checks wc_gearbox_image_narrow's words before it decodes. */",
              "void wc_gearbox_image_layout_decode(const uint8_t *payload, wc_gearbox_t *gearbox);", "",
              "/* The name (gearbox_image.py) of the field holding payload byte offset; NULL past the payload. */",
              "const char *wc_gearbox_image_field_name(uint32_t offset);", "",
              "#endif /* WC_GEARBOX_IMAGE_LAYOUT_H */"]
    return "\n".join(lines) + "\n"


def _member(f: layout.Field) -> str:
    return "gearbox->" + f.member.format(*_INDEX[:len(f.dims)])


def _at(f: layout.Field) -> str:
    if not f.dims:
        return f"&payload[{macro(f)}]"
    if len(f.dims) == 1:
        return f"&payload[{macro(f)} + 4u * i]"
    return f"&payload[{macro(f)} + 4u * ((i * {_BOUND[f.dims[1]]}) + j)]"


def _put(f: layout.Field) -> str:
    value = {"bool": f"{_member(f)} ? 1u : 0u", "": _member(f)}.get(f.c_type, f"(uint32_t){_member(f)}")
    return f"wc_image_put_{f.ctype}({_at(f)}, {value});"


def _get(f: layout.Field) -> str:
    value = f"wc_image_get_{f.ctype}({_at(f)})"
    value = {"bool": f"({value} != 0u)", "": value}.get(f.c_type, f"({f.c_type}){value}")
    return f"{_member(f)} = {value};"


def _body(statement) -> list[str]:
    out = []
    for f in layout.FIELDS:
        if not f.dims:
            out.append("    " + statement(f))
            continue
        out.append(f"    for (uint32_t i = 0u; i < {_BOUND[f.dims[0]]}; ++i) {{")
        if len(f.dims) == 1:
            out.append("        " + statement(f))
        else:
            out += [f"        for (uint32_t j = 0u; j < {_BOUND[f.dims[1]]}; ++j) {{", "            " + statement(f),
                    "        }"]
        out.append("    }")
    return out


def _row_table(dim: str) -> list[str]:
    return [f"    {{ {macro(f)}, {len(f.dims) == 2 and layout.ELEMENTS or 1}u, {1 if len(f.dims) == 2 else 0}u }},"
            f"  /* {f.name} */" for f in _rows(dim)]


def source_text() -> str:
    lines = [banner(COMMAND).rstrip("\n"),
             "/* The gearbox image's payload codec (include/wetclutch_can/wc_gearbox_image.h), from the layout",
             " * tools/wetclutch/calibration/gearbox_image.py: every field little-endian, byte by byte. */",
             "#include \"wc_gearbox_image_layout.h\"", "",
             "#include <stddef.h>", "#include <stdint.h>", "",
             "#include \"wetclutch/wc_config.h\"", "#include \"wetclutch/wc_image.h\"",
             "#include \"wetclutch_can/wc_gearbox_image.h\"", "",
             "const uint32_t wc_gearbox_image_payload_bytes = WC_GEARBOX_IMAGE_PAYLOAD_BYTES;", "",
             "WC_STATIC_ASSERT(WC_GEARBOX_IMAGE_PAYLOAD_BYTES <= WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES,"
             " payload_fits_its_buffers);",
             "WC_STATIC_ASSERT(WC_GEARBOX_IMAGE_MAX_PAYLOAD_BYTES <= WC_IMAGE_PAYLOAD_MAX_BYTES, payload_fits_an_image);",
             f"WC_STATIC_ASSERT(WC_GEARBOX_ELEMENTS_MAX == {layout.ELEMENTS}u, elements_as_the_layout);",
             f"WC_STATIC_ASSERT(WC_GEARBOX_GEARS_MAX == {layout.GEARS}u, gears_as_the_layout);",
             f"WC_STATIC_ASSERT(WC_GEARBOX_SHIFTS_MAX == {layout.SHIFTS}u, shifts_as_the_layout);",
             f"WC_STATIC_ASSERT(sizeof(wc_gearbox_shift_t) == {SHIFT_BYTES}u, every_shift_field_in_the_layout);",
             f"WC_STATIC_ASSERT(sizeof(wc_gearbox_t) == {_struct_bytes()}u, every_gearbox_field_in_the_layout);", "",
             "void wc_gearbox_image_layout_encode(const wc_gearbox_t *gearbox, uint8_t *payload)", "{",
             *_body(_put), "}", "",
             "void wc_gearbox_image_layout_decode(const uint8_t *payload, wc_gearbox_t *gearbox)", "{",
             *_body(_get), "}", "",
             "const wc_gearbox_image_rows_t wc_gearbox_image_gear_rows[WC_GEARBOX_IMAGE_GEAR_FIELDS] = {",
             *_row_table("GEARS"), "};", "",
             "const wc_gearbox_image_rows_t wc_gearbox_image_shift_rows[WC_GEARBOX_IMAGE_SHIFT_FIELDS] = {",
             *_row_table("SHIFTS"), "};", "",
             "const wc_gearbox_image_narrow_t wc_gearbox_image_narrow[WC_GEARBOX_IMAGE_NARROW_FIELDS] = {",
             *(f"    {{ {macro(f)}, {f.count}u, {_NARROW_MAX[f.c_type]}u }},  /* {f.name} ({f.c_type}) */"
               for f in _narrow()), "};", "",
             *field_name_lookup("wc_gearbox_image_field_name", ((macro(f), f.bytes, f.name) for f in layout.FIELDS))]
    return "\n".join(lines) + "\n"


def files() -> dict[Path, str]:
    """The generated files (paths relative to the repository) and their text."""
    return {HEADER: header_text(), SOURCE: source_text()}


def write(root: Path) -> list[Path]:
    """Both files under root, atomically (all or nothing)."""
    return write_generated(root, files())


def main(argv: list[str] | None = None) -> int:
    return generator_main(COMMAND, __doc__, files, argv)


if __name__ == "__main__":
    sys.exit(main())
