"""The plant file (tools/plants/*.toml): schema, ranges, PlantParams, load_plant; the step constants (DT_S, SUBSTEPS).

A plant file names every parameter of SCHEMA as { value, unit, source }, except the OPTIONAL ones (the whole
shift's: engine, off-going clutch's own VFS, on-coming fill; issue 22), which take their documented DEFAULTS
when absent, so that a plant file written before them loads with unchanged behaviour (the fill off, the
off-going clutch's VFS only used when the TCU drives it, the engine only when a torque request is given).

A file may start with ``extends = "base.toml"`` (a path relative to the file): it then holds only what differs
from its base, parameter by parameter (a parameter given replaces the base's whole entry; [clutch] and
[offgoing] calibration paths stay relative to the file that names them). A base may itself extend another;
a missing base or a loop is a PlantError naming the file and 'extends'."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

from ... import calibration
from ...reference import model
from ...util.tomlfile import extends_path, read_toml


RPM = model.RAD_S_PER_RPM          # rad/s per rpm
DT_S = 1e-3
SUBSTEPS = 4
GRAVITY = 9.81
NOISE_BLOCK = 1000
DEFAULT_PLANT = Path(__file__).resolve().parents[3] / "plants" / "upshift_1_2.toml"


class PlantError(Exception):
    """A plant file that cannot be used; the message names the file and the parameter."""


# (section, name, unit, constraint). Constraints: pos (> 0), nonneg (>= 0), finite, seed (whole number >= 0).
SCHEMA: tuple[tuple[str, str, str, str], ...] = (
    ("clutch", "friction_scale", "1", "pos"),
    ("clutch", "housing_offset", "K", "finite"),
    ("driveline", "turbine_inertia", "kg*m^2", "pos"),
    ("driveline", "output_inertia", "kg*m^2", "pos"),
    ("driveline", "ratio_1st", "1", "pos"),
    ("driveline", "ratio_2nd", "1", "pos"),
    ("driveline", "final_drive", "1", "pos"),
    ("driveline", "shaft_stiffness", "N*m/rad", "pos"),
    ("driveline", "shaft_damping", "N*m*s/rad", "nonneg"),
    ("driveline", "wheel_radius", "m", "pos"),
    ("driveline", "vehicle_mass", "kg", "pos"),
    ("driveline", "rolling_resistance", "1", "nonneg"),
    ("driveline", "drag_area", "m^2", "nonneg"),
    ("driveline", "air_density", "kg/m^3", "nonneg"),
    ("driveline", "road_grade", "%", "finite"),
    ("offgoing", "holding_factor", "1", "pos"),
    ("offgoing", "holding_min", "N*m", "nonneg"),
    ("offgoing", "kinetic_ratio", "1", "pos"),
    ("offgoing", "release_start", "s", "nonneg"),
    ("offgoing", "release_time", "s", "pos"),
    ("hydraulics", "vfs_gain", "Pa/mA", "pos"),
    ("hydraulics", "vfs_time_constant", "s", "pos"),
    ("hydraulics", "pressure_noise", "Pa", "nonneg"),
    ("sensors", "slip_noise", "rpm", "nonneg"),
    ("sensors", "slip_resolution", "rpm", "pos"),
    ("sensors", "temperature_noise", "K", "nonneg"),
    ("sensors", "temperature_resolution", "K", "pos"),
    ("sensors", "torque_estimate_bias", "1", "finite"),
    ("sensors", "torque_estimate_noise", "N*m", "nonneg"),
    ("scenario", "turbine_speed", "rpm", "pos"),
    ("scenario", "preroll_time", "s", "nonneg"),
    ("scenario", "shift_duration", "s", "pos"),
    ("scenario", "turbine_torque_full", "N*m", "pos"),
    ("scenario", "oil_temperature", "degC", "finite"),
    ("scenario", "seed", "1", "seed"),
    # the whole shift (issue 22, DESIGN 14): OPTIONAL, see DEFAULTS
    ("engine", "engine_time_constant", "s", "pos"),
    ("engine", "engine_delay", "s", "nonneg"),
    ("engine", "engine_torque_max", "N*m", "finite"),
    ("engine", "engine_torque_min", "N*m", "finite"),
    ("offgoing", "offgoing_friction_scale", "1", "pos"),
    ("offgoing", "offgoing_vfs_gain", "Pa/mA", "pos"),
    ("offgoing", "offgoing_vfs_time_constant", "s", "pos"),
    ("hydraulics", "fill_volume", "m^3", "nonneg"),
    ("hydraulics", "fill_flow_gain", "m^3/(s*Pa)", "pos"),
    ("hydraulics", "fill_flow_max", "m^3/s", "nonneg"),
)

# The optional parameters: name -> (default value, or a function of the other values; the source recorded).
DEFAULTS = {
    "engine_time_constant": (0.08, "default: engine torque follows a request with a first-order lag of 80 ms "
                             "(a mix of the fast spark path and the slow air path)"),
    "engine_delay": (0.0, "default: no dead time"),
    "engine_torque_max": (lambda v: 1.2 * v["turbine_torque_full"],
                          "default: 1.2 x scenario.turbine_torque_full (headroom of a torque increase)"),
    "engine_torque_min": (0.0, "default: a reduction down to zero torque at most (no drag torque requested)"),
    "offgoing_friction_scale": (1.0, "default: the off-going clutch's friction as its calibration"),
    "offgoing_vfs_gain": (lambda v: v["vfs_gain"], "default: as the on-coming clutch's VFS (hydraulics.vfs_gain)"),
    "offgoing_vfs_time_constant": (lambda v: v["vfs_time_constant"],
                                   "default: as the on-coming clutch's VFS (hydraulics.vfs_time_constant)"),
    "fill_volume": (0.0, "default: 0, no fill (the plates touch at the return spring's pressure at once, "
                    "as before issue 22)"),
    "fill_flow_gain": (2.625e-8, "default: the nominal vehicle's (tools/plants/vehicles/nominal.toml); "
                       "used only with fill_volume > 0"),
    "fill_flow_max": (2.55e-4, "default: the nominal vehicle's (tools/plants/vehicles/nominal.toml); "
                      "used only with fill_volume > 0"),
}
OPTIONAL = frozenset(DEFAULTS)


# Narrower physical ranges (inclusive): (low, high).
RANGES = {
    "friction_scale": (0.2, 5.0),
    "housing_offset": (-100.0, 100.0),
    "kinetic_ratio": (0.1, 1.0),
    "road_grade": (-30.0, 30.0),
    "vfs_time_constant": (1e-4, 10.0),
    "turbine_speed": (0.0, 8000.0),
    "oil_temperature": (-40.0, 150.0),
    "torque_estimate_bias": (-0.5, 0.5),
    "engine_time_constant": (1e-4, 10.0),
    "engine_delay": (0.0, 1.0),
    "engine_torque_max": (0.0, 5000.0),
    "engine_torque_min": (-1000.0, 5000.0),
    "offgoing_friction_scale": (0.2, 5.0),
    "offgoing_vfs_time_constant": (1e-4, 10.0),
    "fill_volume": (0.0, 1e-3),
}


@dataclass(frozen=True)
class PlantParams:
    """A validated plant file (SI units except where the name says: rpm, %, degC)."""

    clutch_cal: calibration.Calibration     # the TRUE on-coming clutch
    calibration_path: str
    friction_scale: float
    housing_offset: float
    turbine_inertia: float
    output_inertia: float
    ratio_1st: float
    ratio_2nd: float
    final_drive: float
    shaft_stiffness: float
    shaft_damping: float
    wheel_radius: float
    vehicle_mass: float
    rolling_resistance: float
    drag_area: float
    air_density: float
    road_grade: float
    holding_factor: float
    holding_min: float
    kinetic_ratio: float
    release_start: float
    release_time: float
    vfs_gain: float
    vfs_time_constant: float
    pressure_noise: float
    slip_noise: float
    slip_resolution: float
    temperature_noise: float
    temperature_resolution: float
    torque_estimate_bias: float
    torque_estimate_noise: float
    turbine_speed: float
    preroll_time: float
    shift_duration: float
    turbine_torque_full: float
    oil_temperature: float
    seed: int
    # the whole shift (issue 22): optional in the file (DEFAULTS)
    offgoing_cal: calibration.Calibration   # the off-going clutch ([offgoing] calibration, default [clutch]'s)
    engine_time_constant: float
    engine_delay: float                     # s, a whole number of periods
    engine_torque_max: float
    engine_torque_min: float
    offgoing_friction_scale: float
    offgoing_vfs_gain: float
    offgoing_vfs_time_constant: float
    fill_volume: float                      # m^3; 0 = no fill
    fill_flow_gain: float                   # m^3/(s*Pa)
    fill_flow_max: float                    # m^3/s; 0 = no limit
    offgoing_calibration_path: str = ""
    sources: dict = field(default_factory=dict, compare=False)
    path: str = ""


_FIELDS = {f.name for f in fields(PlantParams)}
assert {n for _, n, _, _ in SCHEMA} <= _FIELDS


_PATH_KEYS = (("clutch", "calibration"), ("offgoing", "calibration"))


def _read_doc(path: Path, chain: tuple) -> dict:
    """The document of path with its extends= chain merged in (the file's own entries win); the path-valued
    entries made absolute (relative to the file naming them)."""
    where = str(path)
    doc = read_toml(path, PlantError, "plant file")
    for section, key in _PATH_KEYS:
        table = doc.get(section)
        if isinstance(table, dict) and isinstance(table.get(key), str) and table[key].strip():
            table[key] = str((path.parent / table[key]).resolve())
    base_entry = doc.get("extends")
    base_path = extends_path(path, doc, chain, PlantError)
    if base_path is None:
        return doc
    try:
        base = _read_doc(base_path, chain + (base_path,))
    except PlantError as e:
        raise PlantError(f"{where}: 'extends' {base_entry!r}: {e}") from None
    for section, table in doc.items():
        if isinstance(table, dict) and isinstance(base.get(section), dict):
            base[section] = {**base[section], **table}
        else:
            base[section] = table
    return base


def load_plant(path) -> PlantParams:
    """Read and validate a plant file (every parameter { value, unit, source }, the OPTIONAL ones defaulted;
    [clutch].calibration and [offgoing].calibration paths relative to the plant file; extends = a base plant
    file). Raises PlantError naming the file and the parameter."""
    path = Path(path)
    where = str(path)
    doc = _read_doc(path, (path.resolve(),))

    known = {(s, n) for s, n, _, _ in SCHEMA} | set(_PATH_KEYS)
    sections = {s for s, _ in known}
    for section, table in doc.items():
        if section not in sections:
            raise PlantError(f"{where}: unknown section [{section}]")
        if not isinstance(table, dict):
            raise PlantError(f"{where}: '{section}' must be a table of parameters")
        for name in table:
            if (section, name) not in known:
                raise PlantError(f"{where}: unknown parameter '{section}.{name}'")

    def load_cal(section):
        entry = doc.get(section, {}).get("calibration")
        if not isinstance(entry, str) or not entry.strip():
            raise PlantError(f"{where}: parameter '{section}.calibration' must be a path string (relative to the "
                             f"plant file)")
        cal_path = (path.parent / entry).resolve()
        try:
            return calibration.load(cal_path), str(cal_path)
        except calibration.CalibrationError as e:
            raise PlantError(f"{where}: parameter '{section}.calibration': {e}") from None

    values: dict = {}
    sources: dict = {}
    if doc.get("clutch", {}).get("calibration") is None:
        raise PlantError(f"{where}: missing parameter 'clutch.calibration' (path of the true clutch calibration)")
    cal, cal_path = load_cal("clutch")
    if doc.get("offgoing", {}).get("calibration") is None:
        off_cal, off_path = cal, cal_path
    else:
        off_cal, off_path = load_cal("offgoing")

    deferred = []
    for section, name, unit, constraint in SCHEMA:
        q = f"{section}.{name}"
        entry = doc.get(section, {}).get(name)
        if entry is None:
            if name in OPTIONAL:
                deferred.append(name)
                continue
            raise PlantError(f"{where}: missing parameter '{q}' (unit {unit})")
        if not isinstance(entry, dict) or "value" not in entry:
            raise PlantError(f"{where}: parameter '{q}' must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
        extra = set(entry) - {"value", "unit", "source"}
        if extra:
            raise PlantError(f"{where}: parameter '{q}': unknown key(s) {', '.join(sorted(extra))}")
        if entry.get("unit") != unit:
            raise PlantError(f"{where}: parameter '{q}': unit {entry.get('unit')!r}, expected {unit!r}")
        src = entry.get("source")
        if not isinstance(src, str) or not src.strip():
            raise PlantError(f"{where}: parameter '{q}': missing 'source' (reference or reasoning)")
        raw = entry["value"]
        if isinstance(raw, bool) or not isinstance(raw, (int, float)):
            raise PlantError(f"{where}: parameter '{q}': value {raw!r} is not a number")
        v = float(raw)
        if not math.isfinite(v):
            raise PlantError(f"{where}: parameter '{q}': value {raw!r} is not finite")
        if constraint == "pos" and not v > 0:
            raise PlantError(f"{where}: parameter '{q}': value {raw!r} must be > 0 {unit}")
        if constraint == "nonneg" and not v >= 0:
            raise PlantError(f"{where}: parameter '{q}': value {raw!r} must be >= 0 {unit}")
        if constraint == "seed":
            if v != int(v) or v < 0:
                raise PlantError(f"{where}: parameter '{q}': value {raw!r} must be a whole number >= 0")
            v = int(v)
        if name in RANGES:
            lo, hi = RANGES[name]
            if not lo <= v <= hi:
                raise PlantError(f"{where}: parameter '{q}': value {raw!r} must be in [{lo:g}, {hi:g}] {unit}")
        values[name] = v
        sources[name] = src
    for name in deferred:
        default, src = DEFAULTS[name]
        values[name] = float(default(values) if callable(default) else default)
        sources[name] = src

    if not values["ratio_1st"] > values["ratio_2nd"]:
        raise PlantError(f"{where}: parameter 'driveline.ratio_2nd' must be < driveline.ratio_1st (an upshift)")
    if not values["turbine_speed"] * RPM / values["ratio_1st"] > 0:
        raise PlantError(f"{where}: parameter 'scenario.turbine_speed' must be > 0 rpm")
    if not values["engine_torque_min"] < values["engine_torque_max"]:
        raise PlantError(f"{where}: parameter 'engine.engine_torque_min' must be < engine.engine_torque_max")
    periods = values["engine_delay"] / DT_S
    if abs(periods - round(periods)) > 1e-6:
        raise PlantError(f"{where}: parameter 'engine.engine_delay': {values['engine_delay']!r} s is not a whole "
                         f"number of {DT_S:g} s periods")
    return PlantParams(clutch_cal=cal, calibration_path=cal_path, offgoing_cal=off_cal,
                       offgoing_calibration_path=off_path, sources=sources, path=where, **values)
