"""The gearbox description file (tools/gearboxes/*.toml): reading and checking it, the Gearbox type.

A description names the box by its gear-set kinematics (the format is documented at the head of
tools/gearboxes/8hp.toml; DESIGN 15):

  name, input_shaft, output_shaft       strings; the two shafts must be in [shafts]
  clutch_calibration                    default clutch calibration file of the elements (table1.toml format),
                                        a path relative to the description
  [shafts.NAME]                         inertia = { value, unit = "kg*m^2", source }; members = "..." (text)
  [sets.NAME]                           a simple (minus) planetary set: sun, ring, carrier = shaft names;
                                        sun_teeth and ring_teeth = { value, unit = "1", source } OR
                                        stationary_ratio = { value < -1, unit = "1", source } (i0 = -z_r/z_s);
                                        planet_spin_inertia = { value, unit = "kg*m^2", source } (optional, 0)
  [elements.NAME]                       kind = "brake" with shaft = "S" (S to the housing), or kind = "clutch"
                                        with shafts = ["S1", "S2"]; slip = w_S (brake), w_S1 - w_S2 (clutch);
                                        calibration = path (optional, default clutch_calibration);
                                        [elements.NAME.overrides.SECTION] entries replace the calibration's
                                        SECTION.entry (same { value, unit, source }, same checks), or add an
                                        optional one the file leaves out (calibration.parameters.OPTIONAL)
  [gears]                               NAME = ["E1", "E2", ...]: the elements closed in that gear

Checks (each a GearboxError naming the file and the key, no traceback): the TOML, every key known, every
shaft a set or an element names is in [shafts], the input and output shafts in it, each set's members on three
different shafts and its ring larger than its sun, every element's kind and shafts, every element's clutch
calibration (the firmware's rules, wetclutch.calibration, with the overrides merged in), every gear's elements
known, none twice, and as many as the kinematics need: a gear closes exactly (shafts - sets - 1) elements (3
for four sets on eight shafts). The kinematic checks (one degree of freedom per gear, a turning output, no
singular gear) are wetclutch.gearbox.kinematics.check, which load runs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ..calibration import Calibration, CalibrationError
from ..calibration.loader import from_document
from ..calibration.parameters import OPTIONAL, PARAMETERS
from ..util.tomlfile import read_toml


# a calibration's optional parameters (the open element's drag): an override may add them to a base file without
_OPTIONAL = {(section, name) for section, name, *_ in PARAMETERS if name in OPTIONAL}


class GearboxError(Exception):
    """A gearbox description (or a vehicle file) that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class Shaft:
    name: str
    inertia: float              # kg m^2: the shaft and every member turning with it
    source: str
    members: str = ""


@dataclass(frozen=True)
class PlanetarySet:
    """A simple planetary set. Willis: w_sun + k w_ring - (1 + k) w_carrier = 0, k = z_ring / z_sun > 1."""

    name: str
    sun: str
    ring: str
    carrier: str
    k: float
    sun_teeth: int | None
    ring_teeth: int | None
    planet_spin_inertia: float  # kg m^2: all planets about their own axes (their orbit is the carrier's)
    source: str


@dataclass(frozen=True)
class Element:
    name: str
    kind: str                   # "brake" | "clutch"
    shafts: tuple               # (S,) for a brake, (S1, S2) for a clutch: slip = w_S1 - w_S2
    calibration: Calibration    # this element's own clutch calibration (pack, piston, spring, VFS)
    calibration_path: str       # the base file
    overrides: tuple            # the "section.name" entries this element replaces


@dataclass(frozen=True)
class Gearbox:
    path: str
    name: str
    input_shaft: str
    output_shaft: str
    shafts: tuple               # Shaft, in the file's order (the kinematics' index)
    sets: tuple                 # PlanetarySet
    elements: tuple             # Element, in the file's order
    gears: dict                 # gear name -> tuple of closed element names, in the file's order

    def shaft_index(self, name: str) -> int:
        return [s.name for s in self.shafts].index(name)

    def element(self, name: str) -> Element:
        for e in self.elements:
            if e.name == name:
                return e
        raise KeyError(name)

    @property
    def element_names(self) -> tuple:
        return tuple(e.name for e in self.elements)

    @property
    def closed_per_gear(self) -> int:
        """Elements a gear closes: one degree of freedom left of (shafts - sets)."""
        return len(self.shafts) - len(self.sets) - 1


_TOP = {"name", "input_shaft", "output_shaft", "clutch_calibration", "shafts", "sets", "elements", "gears"}
_SHAFT_KEYS = {"inertia", "members"}
_SET_KEYS = {"sun", "ring", "carrier", "sun_teeth", "ring_teeth", "stationary_ratio", "planet_spin_inertia"}
_ELEMENT_KEYS = {"kind", "shaft", "shafts", "calibration", "overrides"}


class _Reader:
    def __init__(self, path: Path):
        self.path = path

    def fail(self, key: str, message: str):
        raise GearboxError(f"{self.path}: {key}: {message}")

    def table(self, doc: dict, key: str, where: str, required: bool = True) -> dict:
        value = doc.get(key)
        if value is None and not required:
            return {}
        if not isinstance(value, dict) or (required and not value):
            self.fail(f"{where}{key}", "missing (a table)" if value is None else "must be a non-empty table")
        return value

    def string(self, doc: dict, key: str, where: str) -> str:
        value = doc.get(key)
        if not isinstance(value, str) or not value.strip():
            self.fail(f"{where}{key}", "missing (a string)" if value is None else f"{value!r} must be a string")
        return value

    def unknown(self, doc: dict, known: set, where: str) -> None:
        for key in doc:
            if key not in known:
                self.fail(f"{where}{key}", f"unknown key (known: {', '.join(sorted(known))})")

    def quantity(self, doc: dict, key: str, where: str, unit: str, check, what: str,
                 required: bool = True) -> tuple[float, str] | None:
        entry = doc.get(key)
        qualified = f"{where}{key}"
        if entry is None:
            if required:
                self.fail(qualified, f"missing (value in {unit})")
            return None
        if not isinstance(entry, dict) or "value" not in entry:
            self.fail(qualified, f"must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
        if entry.get("unit") != unit:
            self.fail(qualified, f"unit {entry.get('unit')!r}, expected {unit!r}")
        source = entry.get("source")
        if not isinstance(source, str) or not source.strip():
            self.fail(qualified, "missing 'source' (where the value comes from)")
        for extra in entry:
            if extra not in ("value", "unit", "source"):
                self.fail(qualified, f"unknown key '{extra}' (value, unit, source)")
        value = entry["value"]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or not check(value):
            self.fail(qualified, f"value {value!r} must be {what}")
        return float(value), source

    def shaft_name(self, name: object, key: str, shafts: dict) -> str:
        if not isinstance(name, str) or not name.strip():
            self.fail(key, f"{name!r} must be a shaft name (a string)")
        if name not in shafts:
            self.fail(key, f"shaft '{name}' is not in [shafts] ({', '.join(shafts)})")
        return name


def _shafts(r: _Reader, doc: dict) -> dict:
    out = {}
    for name, table in r.table(doc, "shafts", "").items():
        where = f"shafts.{name}."
        if not isinstance(table, dict):
            r.fail(f"shafts.{name}", "must be a table (inertia = { value, unit, source })")
        r.unknown(table, _SHAFT_KEYS, where)
        inertia, source = r.quantity(table, "inertia", where, "kg*m^2", lambda v: v >= 0, ">= 0")
        members = table.get("members", "")
        if not isinstance(members, str):
            r.fail(f"{where}members", "must be a string")
        out[name] = Shaft(name, inertia, source, members)
    return out


def _sets(r: _Reader, doc: dict, shafts: dict) -> list:
    out = []
    for name, table in r.table(doc, "sets", "").items():
        where = f"sets.{name}."
        if not isinstance(table, dict):
            r.fail(f"sets.{name}", "must be a table (sun, ring, carrier, teeth)")
        r.unknown(table, _SET_KEYS, where)
        members = {m: r.shaft_name(table.get(m), f"{where}{m}", shafts) for m in ("sun", "ring", "carrier")}
        if len(set(members.values())) != 3:
            r.fail(f"sets.{name}", f"sun, ring and carrier on {members}: a set's members turn on three different "
                                   "shafts (two on one shaft lock the set: connect them with a clutch instead)")
        whole = (lambda v: v == int(v) and v > 0)
        teeth = [r.quantity(table, k, where, "1", whole, "a whole number > 0", required=False)
                 for k in ("sun_teeth", "ring_teeth")]
        i0 = r.quantity(table, "stationary_ratio", where, "1", lambda v: v < -1.0,
                        "< -1 (i0 = -z_ring / z_sun of a simple set)", required=False)
        if i0 is not None and any(t is not None for t in teeth):
            r.fail(f"sets.{name}", "give sun_teeth and ring_teeth, or stationary_ratio, not both")
        if i0 is None:
            if any(t is None for t in teeth):
                missing = "sun_teeth" if teeth[0] is None else "ring_teeth"
                r.fail(f"{where}{missing}", "missing (or give stationary_ratio instead of the teeth)")
            zs, zr = int(teeth[0][0]), int(teeth[1][0])
            if zr <= zs:
                r.fail(f"{where}ring_teeth", f"{zr} must exceed sun_teeth {zs} (a ring around its sun)")
            k, source, zs_out, zr_out = zr / zs, f"{teeth[0][1]}; {teeth[1][1]}", zs, zr
        else:
            k, source, zs_out, zr_out = -i0[0], i0[1], None, None
        spin = r.quantity(table, "planet_spin_inertia", where, "kg*m^2", lambda v: v >= 0, ">= 0", required=False)
        out.append(PlanetarySet(name, members["sun"], members["ring"], members["carrier"], k, zs_out, zr_out,
                                0.0 if spin is None else spin[0], source))
    return out


def _calibration(r: _Reader, path: Path, where: str, cal_entry: str, overrides: object):
    """The element's clutch calibration: the base file's document with the overrides merged in, checked as a
    calibration file is (wetclutch.calibration)."""
    cal_path = (path.parent / cal_entry).resolve()
    try:
        doc = read_toml(cal_path, CalibrationError, "calibration file")
    except CalibrationError as e:
        r.fail(f"{where}calibration", str(e))
    replaced = []
    if overrides is not None:
        if not isinstance(overrides, dict):
            r.fail(f"{where}overrides", "must be a table of calibration sections ([...overrides.geometry])")
        for section, entries in overrides.items():
            if not isinstance(entries, dict) or not isinstance(doc.get(section), dict):
                r.fail(f"{where}overrides.{section}", f"not a section of the calibration file {cal_path.name}")
            for name, entry in entries.items():
                if name not in doc[section] and (section, name) not in _OPTIONAL:
                    r.fail(f"{where}overrides.{section}.{name}", f"not a parameter of {cal_path.name}")
                doc[section][name] = entry
                replaced.append(f"{section}.{name}")
    label = f"{cal_path}" + (f" with {where}overrides" if replaced else "")
    try:
        cal = from_document(doc, label)
    except CalibrationError as e:
        r.fail(f"{where}calibration", str(e))
    return cal, str(cal_path), tuple(replaced)


def _elements(r: _Reader, doc: dict, shafts: dict, path: Path) -> list:
    default_cal = doc.get("clutch_calibration")
    out = []
    for name, table in r.table(doc, "elements", "").items():
        where = f"elements.{name}."
        if not isinstance(table, dict):
            r.fail(f"elements.{name}", "must be a table (kind, shaft or shafts, calibration)")
        r.unknown(table, _ELEMENT_KEYS, where)
        kind = table.get("kind")
        if kind == "brake":
            if "shafts" in table:
                r.fail(f"{where}shafts", "a brake holds one shaft to the housing: give shaft = \"NAME\"")
            members = (r.shaft_name(table.get("shaft"), f"{where}shaft", shafts),)
        elif kind == "clutch":
            if "shaft" in table:
                r.fail(f"{where}shaft", "a clutch joins two shafts: give shafts = [\"NAME1\", \"NAME2\"]")
            pair = table.get("shafts")
            if not isinstance(pair, list) or len(pair) != 2:
                r.fail(f"{where}shafts", f"{pair!r} must be a list of two shaft names")
            members = tuple(r.shaft_name(s, f"{where}shafts", shafts) for s in pair)
            if members[0] == members[1]:
                r.fail(f"{where}shafts", f"both ends on shaft '{members[0]}'")
        else:
            r.fail(f"{where}kind", f"{kind!r} must be \"brake\" or \"clutch\"")
        cal_entry = table.get("calibration", default_cal)
        if not isinstance(cal_entry, str) or not cal_entry.strip():
            r.fail(f"{where}calibration", "missing: give it here or a clutch_calibration for every element "
                                          "(a path relative to the description)")
        cal, cal_path, replaced = _calibration(r, path, where, cal_entry, table.get("overrides"))
        out.append(Element(name, kind, members, cal, cal_path, replaced))
    return out


def _gears(r: _Reader, doc: dict, elements: list, closed: int) -> dict:
    names = [e.name for e in elements]
    out = {}
    for gear, listed in r.table(doc, "gears", "").items():
        key = f"gears.{gear}"
        if not isinstance(listed, list) or not all(isinstance(e, str) for e in listed):
            r.fail(key, f"{listed!r} must be a list of element names")
        for e in listed:
            if e not in names:
                r.fail(key, f"unknown element '{e}' (elements: {', '.join(names)})")
        if len(set(listed)) != len(listed):
            r.fail(key, f"an element listed twice in {listed}")
        if len(listed) != closed:
            r.fail(key, f"{len(listed)} closed elements {listed}: a gear of this box closes exactly {closed} "
                        f"(one degree of freedom left)")
        out[str(gear)] = tuple(listed)
    return out


def read(path) -> Gearbox:
    """Read and check a description's structure and its element calibrations (not yet its kinematics:
    load does both). Raises GearboxError."""
    path = Path(path)
    r = _Reader(path)
    doc = read_toml(path, GearboxError, "gearbox description")
    r.unknown(doc, _TOP, "")
    name = r.string(doc, "name", "")
    shafts = _shafts(r, doc)
    ends = [r.shaft_name(doc.get(k), k, shafts) if k in doc else r.fail(k, "missing (a shaft name)")
            for k in ("input_shaft", "output_shaft")]
    if ends[0] == ends[1]:
        r.fail("output_shaft", f"the same shaft as input_shaft ('{ends[0]}')")
    sets = _sets(r, doc, shafts)
    if "clutch_calibration" in doc:
        r.string(doc, "clutch_calibration", "")
    elements = _elements(r, doc, shafts, path)
    used = {ends[0], ends[1]} | {s for p in sets for s in (p.sun, p.ring, p.carrier)} | \
           {s for e in elements for s in e.shafts}
    for s in shafts:
        if s not in used:
            r.fail(f"shafts.{s}", "connected to no set member, element, input or output (a free shaft)")
    closed = len(shafts) - len(sets) - 1
    if closed < 1:
        r.fail("sets", f"{len(sets)} sets on {len(shafts)} shafts leave no degree of freedom to shift")
    gears = _gears(r, doc, elements, closed)
    return Gearbox(str(path), name, ends[0], ends[1], tuple(shafts.values()), tuple(sets), tuple(elements), gears)
