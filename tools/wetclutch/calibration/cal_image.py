"""The calibration image (include/wetclutch_can/wc_cal_image.h, DESIGN 13): a clutch calibration, optionally a
shift calibration, and the frame loop's settings as one versioned, CRC-protected image, the bytes the
firmware's wc_cal_image_load reads (``wetclutch cal-image``).

The payload is the layout of ``image_layout.py`` (its single source) in the image format of ``util/image.py``
(magic "WCCI", layout version 1). Values are a dict ``{field name: value}`` (arrays as lists), e.g.
``values["clutch.outer_radius_m"]``, ``values["clutch.film.hbar_m"][3]``, ``values["loop.e2e.sync_counter"]``.

``build`` refuses what the firmware would refuse, with the messages of ``wetclutch lut``: the clutch file
through the calibration loader (``calibration.load``: the firmware's rules), the shift file through
``shift.load`` (wc_shift_calibration_check's), and the image's own rules here: at most FILM_NODES film
nodes, the loop's limits (``image_layout.LOOP_LIMITS``). ``read_image`` checks an image as the firmware does,
but for wc_calibration_check and wc_shift_calibration_check, which need the files (or the firmware:
``wc_replay --calibration-image``): the image format, the film length and the unused bytes (0), shift_enabled
and the loop's limits.
"""
from __future__ import annotations

import struct
from pathlib import Path

from ..util.atomic import open_atomic
from ..util.image import ImageError, image_bytes, write_image
from ..util.image import read_image as read_image_payload
from . import film_table, image_layout as layout, shift as shift_calibration
from .loader import load as load_clutch
from .parameters import PARAMETERS, CalibrationError, f32

MAGIC, VERSION = layout.MAGIC, layout.VERSION
PAYLOAD_BYTES = layout.payload_bytes()
IMAGE_BYTES = image_bytes(PAYLOAD_BYTES)
DEFAULT_SHIFT_TOML = Path(__file__).resolve().parents[2] / "calibrations" / "shift_1_2.toml"
_PACK = {"f32": "<f", "u32": "<I"}


class CalImageError(CalibrationError):
    """A calibration image that cannot be written or used; ``status`` names the firmware's result when it is
    one (BAD_CRC, BAD_CLUTCH, BAD_SHIFT, BAD_LOOP, ...)."""

    def __init__(self, message: str, status: str = "") -> None:
        super().__init__(message)
        self.status = status


def _clutch_values(cal) -> dict:
    """The clutch fields of a loaded calibration and its film table, padded to FILM_NODES with 0."""
    c_to_toml = {c_field: name for _, name, _, _, c_field in PARAMETERS if c_field}
    table = film_table.build_table(cal)
    nodes = int(table.pressure_Pa.size)
    if nodes > layout.FILM_NODES:
        raise CalImageError(f"{cal.path}: parameter 'film_lut.nodes': {nodes} nodes, the calibration image holds"
                            f" at most {layout.FILM_NODES} (WC_CAL_IMAGE_FILM_NODES; a longer table: `wetclutch"
                            " lut` and a compiled-in calibration)")
    values = {}
    for f in layout.FIELDS:
        if f.group != "clutch" or ".film." in f.name:
            continue
        c_field = f.member.split(".", 1)[1]
        raw = cal.heat_capacity if c_field == "heat_capacity_J_per_K" else cal.values[c_to_toml[c_field]]
        values[f.name] = int(raw) if f.ctype == "u32" else f32(raw)
    pad = [0.0] * (layout.FILM_NODES - nodes)
    values["clutch.film.length"] = nodes
    values["clutch.film.pressure_Pa"] = [f32(x) for x in table.pressure_Pa] + pad
    values["clutch.film.hbar_m"] = [f32(x) for x in table.hbar_m] + pad
    values["clutch.film.slope_m_per_Pa"] = [f32(x) for x in table.slope_m_per_Pa] + pad
    return values


def _shift_values(shift) -> dict:
    """The shift fields of a ShiftCalibration (None: shift control off, every field 0)."""
    c_values = dict(shift.c_fields()) if shift is not None else {}
    values = {}
    for f in layout.FIELDS:
        if f.group != "shift":
            continue
        base = f.member.split(".", 1)[1]
        items = [c_values.get(f"{base}[{i}]", 0) for i in range(f.count)] if f.count > 1 else [c_values.get(base, 0)]
        items = [int(x) if f.ctype == "u32" else f32(x) for x in items]
        values[f.name] = items if f.count > 1 else items[0]
    return values


def loop_values(overrides: dict | None = None, shift_enabled: bool = False) -> dict:
    """The loop's fields: WC_LOOP_CONFIG_DEFAULT with overrides ({"sync_counter": 4, ...}: the names after
    ``loop.`` or the last part of them), each a whole number within the layout's LOOP_LIMITS."""
    values = {f"loop.{k}": v for k, v in layout.LOOP_DEFAULTS.items()}
    values["loop.shift_enabled"] = 1 if shift_enabled else 0
    short = {k.rsplit(".", 1)[-1]: k for k in layout.LOOP_DEFAULTS}
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        name = short.get(key, key)
        if name not in layout.LOOP_LIMITS or name == "shift_enabled":
            raise CalImageError(f"unknown loop setting {key!r}")
        low, high = layout.LOOP_LIMITS[name]
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise CalImageError(f"loop.{name} = {value!r}: must be a whole number in [{low}, {high}] (the firmware's"
                                " limit, wc_cal_image.h)")
        values[f"loop.{name}"] = value
    return values


def build(calibration_path, shift_path=None, shift_variant: str | None = None, loop: dict | None = None) -> dict:
    """The values of an image: the clutch calibration file (checked as `wetclutch lut` checks it), the shift
    calibration's variant (its name in the file, or with the file's stem: ``full``, ``shift_1_2_full``; None:
    shift control off) and the loop's settings (loop_values)."""
    cal = load_clutch(calibration_path)
    shift = None
    if shift_variant is not None:
        shift_path = Path(shift_path or DEFAULT_SHIFT_TOML)
        variants = shift_calibration.load(shift_path).variants
        name = shift_variant.removeprefix(f"{shift_path.stem}_")
        if name not in variants:
            raise CalImageError(f"{shift_path}: no variant '{shift_variant}' (variants: {', '.join(variants)})")
        shift = variants[name]
    elif shift_path is not None:
        raise CalImageError("--shift-toml needs --shift-variant NAME (the variant the image carries)")
    return {**_clutch_values(cal), **_shift_values(shift), **loop_values(loop, shift is not None)}


def encode(values: dict) -> bytes:
    """The payload of values, in the layout's order."""
    out = bytearray(PAYLOAD_BYTES)
    for f in layout.FIELDS:
        items = values[f.name] if f.count > 1 else [values[f.name]]
        if len(items) != f.count:
            raise CalImageError(f"{f.name}: {len(items)} values, the layout has {f.count}")
        for i, x in enumerate(items):
            struct.pack_into(_PACK[f.ctype], out, f.offset + 4 * i, x)
    return bytes(out)


def decode(payload: bytes) -> dict:
    """The values of a payload, unchecked (read_image checks)."""
    values = {}
    for f in layout.FIELDS:
        items = [struct.unpack_from(_PACK[f.ctype], payload, f.offset + 4 * i)[0] for i in range(f.count)]
        values[f.name] = items if f.count > 1 else items[0]
    return values


def write_image_bytes(values: dict) -> bytes:
    """The whole image of values (wc_cal_image_write)."""
    return write_image(MAGIC, VERSION, encode(values))


def _problem(values: dict, payload: bytes) -> tuple[str, str] | None:
    """(result, what) of the image's own rules, in the firmware's order (wc_cal_image.h)."""
    n = values["clutch.film.length"]
    if n > layout.FILM_NODES:
        return "BAD_CLUTCH", f"clutch.film.length {n} > {layout.FILM_NODES}"
    for name in ("clutch.film.pressure_Pa", "clutch.film.hbar_m", "clutch.film.slope_m_per_Pa"):
        f = layout.BY_NAME[name]
        if any(payload[f.offset + 4 * n:f.offset + f.bytes]):
            return "BAD_CLUTCH", f"{name}: a node past the length {n} is not 0"
    limits = layout.LOOP_LIMITS
    if values["loop.shift_enabled"] not in (0, 1):
        return "BAD_LOOP", f"loop.shift_enabled {values['loop.shift_enabled']} is neither 0 nor 1"
    if values["loop.shift_enabled"] == 0:
        begin, end = layout.group_span("shift")
        nonzero = [o for o in range(begin, end, 4) if any(payload[o:o + 4])]
        if nonzero:
            field = next(f for f in layout.FIELDS if f.offset <= nonzero[0] < f.offset + f.bytes)
            return "BAD_SHIFT", f"{field.name} is not 0 with shift control off"
    for name, (low, high) in limits.items():
        if not low <= values[f"loop.{name}"] <= high:
            return "BAD_LOOP", f"loop.{name} {values[f'loop.{name}']} outside [{low}, {high}]"
    return None


def read_image(data: bytes | None, what: str = "calibration image") -> dict:
    """The values of an image, checked as the module's text says; CalImageError naming the firmware's result."""
    try:
        payload = read_image_payload(data, MAGIC, VERSION, PAYLOAD_BYTES, what)
    except ImageError as e:
        raise CalImageError(str(e), e.status) from None
    values = decode(payload)
    problem = _problem(values, payload)
    if problem is not None:
        raise CalImageError(f"{what}: {problem[0]}: {problem[1]}", problem[0])
    return values


def read_file(path) -> dict:
    """read_image of a file (one that does not exist: its OSError)."""
    return read_image(Path(path).read_bytes(), what=str(path))


def write_file(path, values: dict) -> int:
    """The image written atomically (a reader sees the old file or the whole new one); returns its bytes."""
    image = write_image_bytes(values)
    with open_atomic(path, "wb") as f:
        f.write(image)
    return len(image)


def describe(values: dict) -> str:
    """One line a field (the film arrays: the nodes in use), for ``wetclutch cal-image --show``."""
    nodes = values["clutch.film.length"]
    lines = []
    for f in layout.FIELDS:
        v = values[f.name]
        if f.count > 1:
            items = v[:nodes] if ".film." in f.name else v
            v = "[" + ", ".join(f"{x:.9g}" for x in items) + "]"
        elif f.ctype == "f32":
            v = f"{v:.9g}"
        lines.append(f"{f.name} = {v} {f.unit}")
    return "\n".join(lines)
