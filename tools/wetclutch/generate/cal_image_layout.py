"""The calibration image's C codec, generated from its layout (calibration/image_layout.py):
src/can/generated/wc_cal_image_layout.h (each field's offset) and wc_cal_image_layout.c (encode and decode
of every field, little-endian byte by byte through wc_image_put/get_*; the loop's limits; the fields' names).

    python -m wetclutch.generate.cal_image_layout [--out ROOT]     (ROOT: the repository, by default)

tests/python/test_cal_image.py regenerates both into a temporary tree and compares them byte for byte.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..calibration import image_layout as layout
from ..util.atomic import Staged
from .lut import banner

COMMAND = "python -m wetclutch.generate.cal_image_layout"
HEADER = Path("src/can/generated/wc_cal_image_layout.h")
SOURCE = Path("src/can/generated/wc_cal_image_layout.c")
_BOUND = {layout.FILM_NODES: "WC_CAL_IMAGE_FILM_NODES", layout.ADAPT_NODES: "WC_ADAPT_NODES"}
_GROUP_STRUCT = {"clutch": "wc_calibration_t", "shift": "wc_shift_calibration_t"}


def macro(field: layout.Field) -> str:
    """The offset macro of a field: WC_CAL_IMAGE_OFFSET_CLUTCH_FILM_HBAR_M."""
    return "WC_CAL_IMAGE_OFFSET_" + field.name.upper().replace(".", "_")


def header_text() -> str:
    lines = [banner(COMMAND).rstrip("\n"),
             "/* The calibration image's payload layout (tools/wetclutch/calibration/image_layout.py): each",
             " * field's byte offset, and the codec of wc_cal_image_layout.c. Private to wetclutch_can: the",
             " * public API is include/wetclutch_can/wc_cal_image.h. */",
             "#ifndef WC_CAL_IMAGE_LAYOUT_H", "#define WC_CAL_IMAGE_LAYOUT_H", "",
             "#include <stdint.h>", "", "#include \"wetclutch_can/wc_cal_image.h\"", ""]
    for f in layout.FIELDS:
        size = f"  /* {f.ctype}[{f.count}] */" if f.count > 1 else ""
        lines.append(f"#define {macro(f)} {f.offset}u{size}")
    lines.append("")
    for group in ("clutch", "shift", "loop"):
        start, end = layout.group_span(group)
        lines.append(f"#define WC_CAL_IMAGE_{group.upper()}_BEGIN {start}u")
        lines.append(f"#define WC_CAL_IMAGE_{group.upper()}_END {end}u")
    loop = [f for f in layout.FIELDS if f.group == "loop"]
    lines += [f"#define WC_CAL_IMAGE_PAYLOAD_BYTES {layout.payload_bytes()}u",
              f"#define WC_CAL_IMAGE_LOOP_FIELDS {len(loop)}u", "",
              "/* A loop field's limits: the u32 at offset must lie in [lower, upper]. */",
              "typedef struct {", "    uint32_t offset;", "    uint32_t lower;", "    uint32_t upper;",
              "} wc_cal_image_limit_t;", "",
              "/* The loop's fields in the order of wc_cal_loop_error_t (entry i fails with code i + 1). */",
              "extern const wc_cal_image_limit_t wc_cal_image_loop_limits[WC_CAL_IMAGE_LOOP_FIELDS];", "",
              "/* Every field of set into payload (WC_CAL_IMAGE_PAYLOAD_BYTES), as the set holds it. */",
              "void wc_cal_image_layout_encode(const wc_cal_set_t *set, uint8_t *payload);", "",
              "/* Every field of payload into set, unchecked: the narrow members (bool, uint8_t) take the",
              " * low bits, so the caller checks wc_cal_image_loop_limits on the payload before it uses set. */",
              "void wc_cal_image_layout_decode(const uint8_t *payload, wc_cal_set_t *set);", "",
              "/* The name (image_layout.py) of the field holding payload byte offset; NULL past the payload. */",
              "const char *wc_cal_image_field_name(uint32_t offset);", "",
              "#endif /* WC_CAL_IMAGE_LAYOUT_H */"]
    return "\n".join(lines) + "\n"


def _put(f: layout.Field, index: str) -> str:
    value = f"set->{f.member}{index}"
    value = {"bool": f"{value} ? 1u : 0u", "": value}.get(f.c_type, f"(uint32_t){value}")
    return f"wc_image_put_{f.ctype}({_at(f, index)}, {value});"


def _get(f: layout.Field, index: str) -> str:
    value = f"wc_image_get_{f.ctype}({_at(f, index)})"
    value = {"bool": f"({value} != 0u)", "": value}.get(f.c_type, f"({f.c_type}){value}")
    return f"set->{f.member}{index} = {value};"


def _at(f: layout.Field, index: str) -> str:
    """The payload address of a field (of its element i in a loop)."""
    return f"&payload[{macro(f)}{' + 4u * i' if index else ''}]"


def _body(statement) -> list[str]:
    out = []
    for f in layout.FIELDS:
        if f.count == 1:
            out.append("    " + statement(f, ""))
        else:
            out += [f"    for (uint32_t i = 0u; i < {_BOUND[f.count]}; ++i) {{", "        " + statement(f, "[i]"),
                    "    }"]
    return out


def _struct_asserts() -> list[str]:
    """Each clutch/shift field at the word of the layout its struct has it at, and no field left out."""
    out = []
    for group, struct in _GROUP_STRUCT.items():
        for f in layout.FIELDS:
            if f.group == group and f.member.startswith(f"{group}.") and ".film." not in f.name:
                member = f.member.split(".", 1)[1]
                tag = member.replace(".", "_")
                out.append(f"WC_STATIC_ASSERT(offsetof({struct}, {member}) == {macro(f)} - WC_CAL_IMAGE_{group.upper()}_BEGIN,"
                           f" {group}_{tag}_in_struct_order);")
    clutch_words = sum(f.count for f in layout.FIELDS if f.member.startswith("clutch.") and ".film." not in f.name)
    shift_start, shift_end = layout.group_span("shift")
    out += [f"WC_STATIC_ASSERT(offsetof(wc_calibration_t, film) == {4 * clutch_words}u, every_clutch_field_in_the_layout);",
            f"WC_STATIC_ASSERT(sizeof(wc_shift_calibration_t) == {shift_end - shift_start}u,"
            " every_shift_field_in_the_layout);"]
    return out


def source_text() -> str:
    loop = [f for f in layout.FIELDS if f.group == "loop"]
    lines = [banner(COMMAND).rstrip("\n"),
             "/* The calibration image's payload codec (include/wetclutch_can/wc_cal_image.h), from the layout",
             " * tools/wetclutch/calibration/image_layout.py: every field little-endian, byte by byte. */",
             "#include \"wc_cal_image_layout.h\"", "",
             "#include <stddef.h>", "#include <stdint.h>", "",
             "#include \"wetclutch/wc_image.h\"", "#include \"wetclutch_can/wc_cal_image.h\"", "",
             "const uint32_t wc_cal_image_payload_bytes = WC_CAL_IMAGE_PAYLOAD_BYTES;", "",
             "WC_STATIC_ASSERT(WC_CAL_IMAGE_PAYLOAD_BYTES <= WC_CAL_IMAGE_PAYLOAD_MAX_BYTES, payload_fits_its_buffers);",
             f"WC_STATIC_ASSERT(WC_CAL_IMAGE_FILM_NODES == {layout.FILM_NODES}u, film_nodes_as_the_layout);",
             f"WC_STATIC_ASSERT(WC_ADAPT_NODES == {layout.ADAPT_NODES}u, adapt_nodes_as_the_layout);",
             *_struct_asserts(), "",
             "void wc_cal_image_layout_encode(const wc_cal_set_t *set, uint8_t *payload)", "{",
             *_body(_put), "}", "",
             "void wc_cal_image_layout_decode(const uint8_t *payload, wc_cal_set_t *set)", "{",
             *_body(_get), "}", "",
             "const wc_cal_image_limit_t wc_cal_image_loop_limits[WC_CAL_IMAGE_LOOP_FIELDS] = {",
             *(f"    {{ {macro(f)}, {int(f.lower)}u, {int(f.upper)}u }},  /* {f.name} */" for f in loop), "};", "",
             *field_name_lookup("wc_cal_image_field_name", ((macro(f), f.bytes, f.name) for f in layout.FIELDS))]
    return "\n".join(lines) + "\n"


def field_name_lookup(function: str, fields) -> list[str]:
    """C lines of `const char *FUNCTION(uint32_t offset)`: the name of the field (offset macro, bytes, name)
    holding a payload byte offset, NULL past the payload."""
    return ["typedef struct {", "    uint16_t offset;", "    uint16_t bytes;", "    const char *name;",
            "} field_name_t;", "",
            "static const field_name_t field_names[] = {",
            *(f"    {{ {offset}, {size}u, \"{name}\" }}," for offset, size, name in fields), "};", "",
            f"const char *{function}(uint32_t offset)", "{",
            "    for (size_t i = 0u; i < sizeof field_names / sizeof field_names[0]; ++i) {",
            "        if ((offset >= field_names[i].offset) && (offset < (uint32_t)field_names[i].offset + field_names[i].bytes)) {",
            "            return field_names[i].name;", "        }", "    }", "    return NULL;", "}"]


def files() -> dict[Path, str]:
    """The generated files (paths relative to the repository) and their text."""
    return {HEADER: header_text(), SOURCE: source_text()}


def write_generated(root: Path, generated: dict[Path, str]) -> list[Path]:
    """Generated files (paths relative to root) under root, atomically (all or nothing)."""
    written = []
    with Staged() as out:
        for rel, text in generated.items():
            (root / rel).parent.mkdir(parents=True, exist_ok=True)
            out.write_text(root / rel, text)
            written.append(root / rel)
    return written


def write(root: Path) -> list[Path]:
    """Both files under root, atomically (all or nothing)."""
    return write_generated(root, files())


def generator_main(command: str, doc: str, generated, argv: list[str] | None) -> int:
    """A generator's command line: --out ROOT (this repository by default); prints what it wrote."""
    parser = argparse.ArgumentParser(prog=command, description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(Path(__file__).resolve().parents[3]),
                        help="the repository root to write under (default: this repository)")
    args = parser.parse_args(argv)
    for path in write_generated(Path(args.out), generated()):
        print(f"wrote {path}")
    return 0


def main(argv: list[str] | None = None) -> int:
    return generator_main(COMMAND, __doc__, files, argv)


if __name__ == "__main__":
    sys.exit(main())
