"""The A2L (ASAM MCD-2 MC) of the TCU's XCP slave (DESIGN 13), from the single sources: the calibration
image's layout (``calibration/image_layout.py``: one CHARACTERISTIC a field, at the calibration page's base
plus its offset), the gearbox image's layout (``calibration/gearbox_image.py``: one READ_ONLY CHARACTERISTIC
a field of the gearbox region, issue 29) and the measured signals (``calibration/measurements.py``: one MEASUREMENT each), with the
addresses resolved from the linked program: ``wc_tcu --xcp-layout`` prints the regions' bases (on a 64-bit
host offsets of the slave's address space, src/can/wc_xcp.h) and each signal's ``offsetof``.

    wetclutch a2l [--tcu PATH | --layout FILE] --out FILE.a2l

No IF_DATA XCP block: the transport (CAN ids 0x7F0/0x7F1 from the DBC, classic CAN, MAX_CTO = MAX_DTO = 8)
is given to the master by its own configuration (docs/calibrating.md, "XCP on CAN")."""
from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

from ..calibration import gearbox_image, image_layout
from ..calibration.measurements import SIGNALS, TYPES
from ..util.atomic import Staged

A2L_TYPES = {"f32": ("FLOAT32_IEEE", "RL_F32"), "u32": ("ULONG", "RL_U32")}
ELEMENTS = 6                 # WC_GEARBOX_ELEMENTS_MAX: the elements' regions element0 .. element5
REGION_KEYS = ("cal", "loop", "xcp", "id", "gearbox", *(f"element{e}" for e in range(ELEMENTS)))


class A2lError(RuntimeError):
    """The program's XCP layout cannot be read or does not match this tool's sources (the CLI reports a
    RuntimeError in one line)."""


def read_layout(tcu: Path | None = None, layout_file: Path | None = None) -> dict:
    """The linked program's layout: ``tcu --xcp-layout`` or a saved copy of its output."""
    try:
        if layout_file is not None:
            text = Path(layout_file).read_text()
        else:
            result = subprocess.run([str(tcu), "--xcp-layout"], capture_output=True, text=True, timeout=30)
            if result.returncode != 0:
                raise A2lError(f"{tcu} --xcp-layout failed (exit {result.returncode}): {result.stderr.strip()}")
            text = result.stdout
        layout = json.loads(text)
    except (OSError, subprocess.SubprocessError) as e:
        raise A2lError(f"cannot read the XCP layout: {e}") from e
    except json.JSONDecodeError as e:
        raise A2lError(f"the XCP layout is not JSON: {e}") from e
    _check(layout)
    return layout


def _check(layout: dict) -> None:
    """The program and this tool describe the same calibration page and signals (else: rebuild one)."""
    try:
        regions = {k: (int(layout["regions"][k]["base"]), int(layout["regions"][k]["size"])) for k in REGION_KEYS}
        signals = {s["name"]: (s["region"], int(s["offset"]), int(s["size"])) for s in layout["signals"]}
    except (KeyError, TypeError, ValueError) as e:
        raise A2lError(f"the XCP layout lacks {e}") from e
    if regions["cal"][1] != image_layout.payload_bytes():
        raise A2lError(f"the program's calibration page has {regions['cal'][1]} bytes, the image layout"
                        f" {image_layout.payload_bytes()}: rebuild the program or regenerate the layout")
    if regions["gearbox"][1] != gearbox_image.payload_bytes():
        raise A2lError(f"the program's gearbox region has {regions['gearbox'][1]} bytes, the gearbox image layout"
                       f" {gearbox_image.payload_bytes()}: rebuild the program or regenerate the layout")
    for e in range(ELEMENTS):
        if regions[f"element{e}"][1] != image_layout.payload_bytes():
            raise A2lError(f"the program's element{e} region has {regions[f'element{e}'][1]} bytes, the image layout"
                           f" {image_layout.payload_bytes()}: rebuild the program or regenerate the layout")
    for s in SIGNALS:
        if s.name not in signals:
            raise A2lError(f"the program does not know the signal {s.name}: regenerate src/port/wc_xcp_signals.c")
        region, offset, size = signals[s.name]
        if region != s.region or size != s.size or offset + size > regions[region][1]:
            raise A2lError(f"signal {s.name}: the program has it in {region} at {offset} ({size} bytes)")


def _ident(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", text)


def _compu_method(unit: str) -> str:
    return "CM_" + (_ident(unit.replace("/", "_per_").replace("^", "")) if unit != "1" else "one")


def _string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', "'") + '"'


def _number(value: float) -> str:
    return repr(float(value))


def a2l_text(layout: dict) -> str:
    regions = {k: (int(layout["regions"][k]["base"]), int(layout["regions"][k]["size"])) for k in REGION_KEYS}
    offsets = {s["name"]: int(s["offset"]) for s in layout["signals"]}
    fields = image_layout.FIELDS
    units = sorted({f.unit for f in fields} | {f.unit for f in gearbox_image.FIELDS} | {s.unit for s in SIGNALS})
    out = ["ASAP2_VERSION 1 71",
           "/* generated by `wetclutch a2l` from tools/wetclutch/calibration/image_layout.py, gearbox_image.py and"
           " measurements.py",
           f"   with the addresses of {layout.get('program', 'the TCU program')}, do not edit */",
           '/begin PROJECT wetclutch "Wet-clutch TCU library (Shin & Choi model): one clutch or a transmission"',
           '  /begin HEADER "XCP on CAN slave, src/can/wc_xcp.h"',
           f'    VERSION "calibration image layout {image_layout.VERSION}, gearbox image layout {gearbox_image.VERSION}"',
           "  /end HEADER",
           '  /begin MODULE wetclutch "calibration page, gearbox (read only) and measurements"',
           '    /begin MOD_COMMON ""',
           "      BYTE_ORDER MSB_LAST",
           "      ALIGNMENT_BYTE 1", "      ALIGNMENT_WORD 1", "      ALIGNMENT_LONG 1", "      ALIGNMENT_FLOAT32_IEEE 1",
           "    /end MOD_COMMON",
           '    /begin MOD_PAR "TCU memory as the XCP slave maps it (extension 0)"']
    segments = (("calibration", "calibration image payload: page 0 RAM working page, page 1 flash reference",
                 "DATA", "RAM", "cal"),
                ("loop", "the frame loop's state (wc_loop_t), read only", "VARIABLES", "RAM", "loop"),
                ("xcp_status", "the XCP slave's status (wc_xcp_status_t), read only", "VARIABLES", "RAM", "xcp"),
                ("gearbox", "the gearbox image's payload (wc_gearbox_image.h) of the transmission the TCU runs, read"
                 " only; without one ERR_ACCESS_DENIED", "DATA", "FLASH", "gearbox"),
                *((f"element{e}", f"element {e}'s calibration image payload (its clutch) of the transmission the TCU"
                   " runs, read only; without one ERR_ACCESS_DENIED", "DATA", "FLASH", f"element{e}")
                  for e in range(ELEMENTS)))
    for name, text, prg, mem, key in segments:
        base, size = regions[key]
        out.append(f"      /begin MEMORY_SEGMENT {name} {_string(text)} {prg} {mem} INTERN 0x{base:08X} {size}"
                   " -1 -1 -1 -1 -1 /end MEMORY_SEGMENT")
    out.append("    /end MOD_PAR")
    for unit in units:
        out.append(f'    /begin COMPU_METHOD {_compu_method(unit)} "physical value in {unit}" IDENTICAL "%.9g"'
                   f" {_string(unit)} /end COMPU_METHOD")
    for ctype, (datatype, layout_name) in A2L_TYPES.items():
        out.append(f"    /begin RECORD_LAYOUT {layout_name} FNC_VALUES 1 {datatype} ROW_DIR DIRECT /end RECORD_LAYOUT")
    cal_base = regions["cal"][0]
    for f in fields:
        kind = "VALUE" if f.count == 1 else "VAL_BLK"
        desc = f.description + (f" ({f.note})" if f.note else "")
        lines = [f"    /begin CHARACTERISTIC {f.name} {_string(desc)} {kind} 0x{cal_base + f.offset:08X}"
                 f" {A2L_TYPES[f.ctype][1]} 0 {_compu_method(f.unit)} {_number(f.lower)} {_number(f.upper)}"]
        if f.count > 1:
            lines.append(f"      MATRIX_DIM {f.count}")
        lines.append("    /end CHARACTERISTIC")
        out.extend(lines)
    gearbox_base = regions["gearbox"][0]
    for f in gearbox_image.FIELDS:   # read only; arrays as C has them: MATRIX_DIM in C's index order, ROW_DIR
        kind = "VAL_BLK" if f.dims else "VALUE"
        lines = [f"    /begin CHARACTERISTIC {f.name} {_string(f.description)} {kind} 0x{gearbox_base + f.offset:08X}"
                 f" {A2L_TYPES[f.ctype][1]} 0 {_compu_method(f.unit)} {_number(f.lower)} {_number(f.upper)}",
                 "      READ_ONLY"]
        if f.dims:
            lines.append("      MATRIX_DIM " + " ".join(str(gearbox_image.BOUNDS[d]) for d in f.dims))
        lines.append("    /end CHARACTERISTIC")
        out.extend(lines)
    element_fields = [f for f in fields if f.group == "clutch"]   # an element image's: its clutch (shift off)
    for e in range(ELEMENTS):
        base = regions[f"element{e}"][0]
        for f in element_fields:
            kind = "VALUE" if f.count == 1 else "VAL_BLK"
            lines = [f"    /begin CHARACTERISTIC element{e}.{f.name} {_string(f'element {e}: ' + f.description)} {kind}"
                     f" 0x{base + f.offset:08X} {A2L_TYPES[f.ctype][1]} 0 {_compu_method(f.unit)} {_number(f.lower)}"
                     f" {_number(f.upper)}", "      READ_ONLY"]
            if f.count > 1:
                lines.append(f"      MATRIX_DIM {f.count}")
            lines.append("    /end CHARACTERISTIC")
            out.extend(lines)
    for s in SIGNALS:
        address = regions[s.region][0] + offsets[s.name]
        out.append(f"    /begin MEASUREMENT {s.name} {_string(s.description)} {TYPES[s.ctype][0]}"
                   f" {_compu_method(s.unit)} 0 0 {_number(s.lower)} {_number(s.upper)}")
        out.append(f"      ECU_ADDRESS 0x{address:08X}")
        out.append("    /end MEASUREMENT")
    for group, title in (("clutch", "clutch model (wc_calibration_t)"), ("shift", "shift control"),
                         ("loop", "frame loop")):
        names = " ".join(f.name for f in fields if f.group == group)
        out.append(f'    /begin GROUP {group} "{title}" ROOT /begin REF_CHARACTERISTIC {names}'
                   " /end REF_CHARACTERISTIC /end GROUP")
    out.append('    /begin GROUP gearbox "the gearbox (wc_gearbox_t), read only" ROOT /begin REF_CHARACTERISTIC '
               + " ".join(f.name for f in gearbox_image.FIELDS) + " /end REF_CHARACTERISTIC /end GROUP")
    for e in range(ELEMENTS):
        out.append(f'    /begin GROUP element{e} "element {e}\'s clutch (wc_calibration_t), read only" ROOT'
                   " /begin REF_CHARACTERISTIC " + " ".join(f"element{e}.{f.name}" for f in element_fields)
                   + " /end REF_CHARACTERISTIC /end GROUP")
    out.append('    /begin GROUP measurements "measured signals" ROOT /begin REF_MEASUREMENT '
               + " ".join(s.name for s in SIGNALS) + " /end REF_MEASUREMENT /end GROUP")
    out += ["  /end MODULE", "/end PROJECT", ""]
    return "\n".join(out)


def write_a2l(layout: dict, out: Path) -> Path:
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with Staged() as staged:
        staged.write_text(Path(out), a2l_text(layout))
    return Path(out)
