"""The gearbox image (include/wetclutch_can/wc_gearbox_image.h): a gearbox's wc_gearbox_t (DESIGN 15; issue 29)
as a versioned, CRC-protected image in the persistent format of wc_image.h, the single source of its layout.

The same table the firmware compiles in from ``lut/wc_<name>_gearbox.h``, as data the TCU checks at start
(``wc_tcu --gearbox-image FILE``) and a calibration tool reads over XCP (the A2L's ``gearbox.*``
characteristics, a read-only segment: the gearbox is flashed, not tuned on the fly). The element
calibrations travel as one calibration image per element (``--element-image``); the shift calibration in
the calibration image.

Payload: the struct's fields in its declaration order, each 4 bytes a value, little-endian, arrays whole
at their bound (``WC_GEARBOX_GEARS_MAX`` gears by gear number, reverse 0; ``WC_GEARBOX_ELEMENTS_MAX``
elements; ``WC_GEARBOX_SHIFTS_MAX`` shifts), the shifts' fields each as one array over the shifts (a
calibration tool shows ``gearbox.shift.output_ratio`` as one table). What a gearbox does not use is 0:
gears it does not have, shifts past shift_count, elements past element_count.

What reads FIELDS: ``generate/gearbox_image_layout.py`` (the C codec, src/can/generated/
wc_gearbox_image_layout.c), this module's codec (``wetclutch gearbox ... --image FILE``), the A2L generator.

API: FIELDS, payload_bytes(), values_from_table(table) -> dict, encode(values) -> bytes,
decode(payload) -> dict, image_bytes_of(values) -> bytes, read_image(data) -> dict, write_file(path, table).
"""
from __future__ import annotations

import math
import struct
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..util.atomic import open_atomic
from ..util.image import ImageError, write_image
from ..util.image import read_image as read_image_payload

MAGIC = 0x42474357          # WC_GEARBOX_IMAGE_MAGIC, the bytes "WCGB"
VERSION = 1                 # WC_GEARBOX_IMAGE_VERSION
ELEMENTS = 6                # WC_GEARBOX_ELEMENTS_MAX
GEARS = 11                  # WC_GEARBOX_GEARS_MAX: reverse (0) and up to 10 forward
SHIFTS = 64                 # WC_GEARBOX_SHIFTS_MAX
REVERSE = "R"
WORD_BYTES = 4
BOUNDS = {"GEARS": GEARS, "ELEMENTS": ELEMENTS, "SHIFTS": SHIFTS}
RATIO_MAX = 20.0            # wc_gearbox.c: |ratio|, |a|, |b|, ratios of the reduced model
HOLDING_MAX = 20.0


class GearboxImageError(ValueError):
    """A gearbox the image cannot carry, or an image that cannot be used; ``status`` names the firmware's
    result (wc_image_status_t or wc_gearbox_image_result_t) where there is one."""

    def __init__(self, message: str, status: str = "") -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Field:
    """One field of wc_gearbox_t: name (A2L), member (C, with {0} {1} the indices over dims), wire type
    ("f32", "u32"), dims (bound names), C type where narrower (uint8_t, bool), unit, closed limits of each
    value (the A2L's: they include the 0 of an unused row; wc_gearbox_check's ranges for the rows in use are
    in the description), description; offset set by the order."""
    name: str
    member: str
    ctype: str
    dims: tuple[str, ...]
    unit: str
    lower: float
    upper: float
    description: str
    c_type: str = ""
    offset: int = 0

    @property
    def count(self) -> int:
        return math.prod(BOUNDS[d] for d in self.dims)

    @property
    def bytes(self) -> int:
        return WORD_BYTES * self.count


_G, _GE, _S, _SE = ("GEARS",), ("GEARS", "ELEMENTS"), ("SHIFTS",), ("SHIFTS", "ELEMENTS")
_FIELDS = (
    Field("gearbox.element_count", "element_count", "u32", (), "1", 3, ELEMENTS, "shift elements"),
    Field("gearbox.closed_per_gear", "closed_per_gear", "u32", (), "1", 1, ELEMENTS - 1,
          "elements closed in every gear"),
    Field("gearbox.forward_gears", "forward_gears", "u32", (), "1", 1, GEARS - 1, "forward gears 1..n"),
    Field("gearbox.has_reverse", "has_reverse", "u32", (), "1", 0, 1, "reverse gear (number 0) present",
          c_type="bool"),
    Field("gearbox.ratio", "ratio[{0}]", "f32", _G, "1", -RATIO_MAX, RATIO_MAX,
          "turbine / output speed per gear number (0 reverse, negative)"),
    Field("gearbox.closed_mask", "closed_mask[{0}]", "u32", _G, "1", 0, (1 << ELEMENTS) - 1,
          "the elements closed per gear number (bit e: element e)"),
    Field("gearbox.holding_torque_per_Nm", "holding_torque_per_Nm[{0}][{1}]", "f32", _GE, "Nm/Nm", -HOLDING_MAX,
          HOLDING_MAX, "torque an element holds per Nm of turbine torque, [gear][element]"),
    Field("gearbox.shift_count", "shift_count", "u32", (), "1", 0, SHIFTS, "shifts in the table"),
    Field("gearbox.shift.source_gear", "shift[{0}].source_gear", "u32", _S, "1", 0, GEARS - 1,
          "the shift's current gear (1..; 0: no shift in this row)", c_type="uint8_t"),
    Field("gearbox.shift.target_gear", "shift[{0}].target_gear", "u32", _S, "1", 0, GEARS - 1,
          "the shift's target gear (1..; 0: no shift in this row)", c_type="uint8_t"),
    Field("gearbox.shift.oncoming", "shift[{0}].oncoming", "u32", _S, "1", 0, ELEMENTS - 1,
          "the element that closes", c_type="uint8_t"),
    Field("gearbox.shift.offgoing", "shift[{0}].offgoing", "u32", _S, "1", 0, ELEMENTS - 1,
          "the element that opens", c_type="uint8_t"),
    Field("gearbox.shift.slip_a", "shift[{0}].slip[{1}].a", "f32", _SE, "1", -RATIO_MAX, RATIO_MAX,
          "element slip a w_t - b w_o: a, [shift][element]"),
    Field("gearbox.shift.slip_b", "shift[{0}].slip[{1}].b", "f32", _SE, "1", -RATIO_MAX, RATIO_MAX,
          "element slip a w_t - b w_o: b, [shift][element]"),
    Field("gearbox.shift.output_ratio", "shift[{0}].output_ratio", "f32", _S, "1", 0.0, RATIO_MAX,
          "reduced model: the target gear's ratio b (DESIGN 15; 0.05.. in a shift's row, 0 in an unused one)"),
    Field("gearbox.shift.offgoing_ratio", "shift[{0}].offgoing_ratio", "f32", _S, "1", 0.0, RATIO_MAX,
          "reduced model: the source gear's ratio b1 (0.05..; 0 unused)"),
    Field("gearbox.shift.oncoming_slip_scale", "shift[{0}].oncoming_slip_scale", "f32", _S, "1", -RATIO_MAX,
          RATIO_MAX, "the on-coming element's a (its slip per unit of the controller's)"),
    Field("gearbox.shift.offgoing_slip_scale", "shift[{0}].offgoing_slip_scale", "f32", _S, "1", -RATIO_MAX,
          RATIO_MAX, "the off-going element's a"),
    Field("gearbox.shift.turbine_inertia_kg_m2", "shift[{0}].turbine_inertia_kg_m2", "f32", _S, "kg*m^2",
          0.0, 100.0, "reduced model: turbine-side inertia (paper 2, Fig. 1; 1e-4.. in a shift's row, 0 unused)"),
    Field("gearbox.shift.output_inertia_kg_m2", "shift[{0}].output_inertia_kg_m2", "f32", _S, "kg*m^2",
          0.0, 1e5, "reduced model: output-side inertia with the vehicle (1e-4..; 0 unused)"),
    Field("gearbox.shift.jerk_per_torque_rate", "shift[{0}].jerk_per_torque_rate", "f32", _S,
          "(m/s^3)/(Nm/s)", 0.0, 1.0, "output jerk per rate of the controller's torque"),
)


def _laid_out(fields) -> tuple[Field, ...]:
    out, offset = [], 0
    for f in fields:
        out.append(Field(**{**f.__dict__, "offset": offset}))
        offset += f.bytes
    return tuple(out)


FIELDS = _laid_out(_FIELDS)
BY_NAME = {f.name: f for f in FIELDS}


def payload_bytes() -> int:
    """The payload's length (wc_gearbox_image_payload_bytes)."""
    return FIELDS[-1].offset + FIELDS[-1].bytes


# ------------------------------------------------------------------------------------------------ values
def _zeros() -> dict:
    return {f.name: ([0] * f.count if f.dims else 0) for f in FIELDS}


def table_parts(table: dict, table_name: str) -> tuple[list, dict, list, list]:
    """(elements, gears, forward gear numbers, shifts) of a generated shift table that fits wc_gearbox_t's
    bounds (the header's and the image's); GearboxImageError naming what does not."""
    elements = list(table["elements"])
    gears = table["gears"]
    forward = sorted(int(g) for g in gears if g != REVERSE)
    shifts = list(table.get("shifts", {}).values())
    if len(elements) > ELEMENTS or len(forward) > GEARS - 1 or len(shifts) > SHIFTS:
        raise GearboxImageError(f"{table_name}: {len(elements)} elements, {len(forward)} forward gears,"
                                f" {len(shifts)} shifts: more than wc_gearbox.h's bounds ({ELEMENTS}, {GEARS - 1},"
                                f" {SHIFTS})")
    if forward != list(range(1, len(forward) + 1)):
        raise GearboxImageError(f"{table_name}: forward gears {forward} are not 1..n")
    missing = [s["source"] + "-" + s["target"] for s in shifts if "turbine_inertia" not in s]
    if missing:
        raise GearboxImageError(f"{table_name}: no reduced model for {', '.join(missing[:3])}: generate the table"
                                " with --vehicle")
    return elements, gears, forward, shifts


def values_from_table(table: dict, table_name: str = "shift table") -> dict:
    """The image's values of a generated shift table (wetclutch.gearbox.table; the dict of its TOML), the
    same numbers lut/wc_<name>_gearbox.h carries. GearboxImageError if it does not fit the bounds."""
    elements, gears, forward, shifts = table_parts(table, table_name)
    index = {name: i for i, name in enumerate(elements)}
    per_gear = {len(g["closed"]) for g in gears.values()}
    v = _zeros()
    v["gearbox.element_count"] = len(elements)
    v["gearbox.closed_per_gear"] = per_gear.pop() if len(per_gear) == 1 else 0
    v["gearbox.forward_gears"] = len(forward)
    v["gearbox.has_reverse"] = 1 if REVERSE in gears else 0

    def gear_no(name: str) -> int:
        return 0 if name == REVERSE else int(name)

    for name, g in gears.items():
        n = gear_no(name)
        v["gearbox.ratio"][n] = float(g["ratio"])
        v["gearbox.closed_mask"][n] = sum(1 << index[e] for e in g["closed"])
        for e, h in g["holding_torque"].items():
            v["gearbox.holding_torque_per_Nm"][n * ELEMENTS + index[e]] = float(h)
    v["gearbox.shift_count"] = len(shifts)
    for i, s in enumerate(shifts):
        v["gearbox.shift.source_gear"][i] = gear_no(s["source"])
        v["gearbox.shift.target_gear"][i] = gear_no(s["target"])
        v["gearbox.shift.oncoming"][i] = index[s["oncoming"]]
        v["gearbox.shift.offgoing"][i] = index[s["offgoing"]]
        for e, (a, b) in s["slips"].items():
            v["gearbox.shift.slip_a"][i * ELEMENTS + index[e]] = float(a)
            v["gearbox.shift.slip_b"][i * ELEMENTS + index[e]] = float(b)
        for key, field in (("output_ratio", "output_ratio"), ("offgoing_ratio", "offgoing_ratio"),
                           ("oncoming_slip_scale", "oncoming_slip_scale"),
                           ("offgoing_slip_scale", "offgoing_slip_scale"),
                           ("turbine_inertia", "turbine_inertia_kg_m2"), ("output_inertia", "output_inertia_kg_m2"),
                           ("jerk_per_torque_rate", "jerk_per_torque_rate")):
            v[f"gearbox.shift.{field}"][i] = float(s[key])
    return v


_PACK = {"f32": "<f", "u32": "<I"}


def encode(values: dict) -> bytes:
    """The payload of values, in the layout's order (each array flattened row-major)."""
    out = bytearray(payload_bytes())
    for f in FIELDS:
        items = values[f.name] if f.dims else [values[f.name]]
        if len(items) != f.count:
            raise GearboxImageError(f"{f.name}: {len(items)} values, the layout has {f.count}")
        for i, x in enumerate(items):
            struct.pack_into(_PACK[f.ctype], out, f.offset + WORD_BYTES * i, x)
    return bytes(out)


def decode(payload: bytes) -> dict:
    """The values of a payload, unchecked."""
    values = {}
    for f in FIELDS:
        items = [struct.unpack_from(_PACK[f.ctype], payload, f.offset + WORD_BYTES * i)[0] for i in range(f.count)]
        values[f.name] = items if f.dims else items[0]
    return values


def image_bytes_of(values: dict) -> bytes:
    """The whole image of values (wc_gearbox_image_write)."""
    return write_image(MAGIC, VERSION, encode(values))


def read_image(data: bytes | None, what: str = "gearbox image") -> dict:
    """The values of an image whose header and CRC are good (the firmware checks the gearbox itself:
    wc_gearbox_image_load); GearboxImageError naming the image's status otherwise."""
    try:
        payload = read_image_payload(data, MAGIC, VERSION, payload_bytes(), what)
    except ImageError as e:
        raise GearboxImageError(str(e), e.status) from None
    return decode(payload)


def write_file(path, table_path) -> int:
    """The image of the shift table at table_path, written atomically to path; its length in bytes."""
    table_path = Path(table_path)
    with open(table_path, "rb") as f:
        table = tomllib.load(f)
    image = image_bytes_of(values_from_table(table, table_path.name))
    with open_atomic(path, "wb") as f:
        f.write(image)
    return len(image)


assert payload_bytes() <= 16384   # WC_IMAGE_PAYLOAD_MAX_BYTES
assert len(BY_NAME) == len(FIELDS)
