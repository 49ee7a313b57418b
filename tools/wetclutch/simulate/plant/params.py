"""The plant file (tools/plants/*.toml): schema, ranges, PlantParams, load_plant; the step constants (DT_S, SUBSTEPS)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

from ... import calibration
from ...reference import model
from ...util.tomlfile import read_toml


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
)

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
    sources: dict = field(default_factory=dict, compare=False)
    path: str = ""


_FIELDS = {f.name for f in fields(PlantParams)}
assert {n for _, n, _, _ in SCHEMA} <= _FIELDS


def load_plant(path) -> PlantParams:
    """Read and validate a plant file (every parameter { value, unit, source }; [clutch].calibration a
    path relative to the plant file). Raises PlantError naming the file and the parameter."""
    path = Path(path)
    where = str(path)
    doc = read_toml(path, PlantError, "plant file")

    known = {(s, n) for s, n, _, _ in SCHEMA} | {("clutch", "calibration")}
    sections = {s for s, _ in known}
    for section, table in doc.items():
        if section not in sections:
            raise PlantError(f"{where}: unknown section [{section}]")
        if not isinstance(table, dict):
            raise PlantError(f"{where}: '{section}' must be a table of parameters")
        for name in table:
            if (section, name) not in known:
                raise PlantError(f"{where}: unknown parameter '{section}.{name}'")

    values: dict = {}
    sources: dict = {}
    cal_entry = doc.get("clutch", {}).get("calibration")
    if cal_entry is None:
        raise PlantError(f"{where}: missing parameter 'clutch.calibration' (path of the true clutch calibration)")
    if not isinstance(cal_entry, str) or not cal_entry.strip():
        raise PlantError(f"{where}: parameter 'clutch.calibration' must be a path string (relative to the plant file)")
    cal_path = (path.parent / cal_entry).resolve()
    try:
        cal = calibration.load(cal_path)
    except calibration.CalibrationError as e:
        raise PlantError(f"{where}: parameter 'clutch.calibration': {e}") from None

    for section, name, unit, constraint in SCHEMA:
        q = f"{section}.{name}"
        entry = doc.get(section, {}).get(name)
        if entry is None:
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

    if not values["ratio_1st"] > values["ratio_2nd"]:
        raise PlantError(f"{where}: parameter 'driveline.ratio_2nd' must be < driveline.ratio_1st (an upshift)")
    if not values["turbine_speed"] * RPM / values["ratio_1st"] > 0:
        raise PlantError(f"{where}: parameter 'scenario.turbine_speed' must be > 0 rpm")
    return PlantParams(clutch_cal=cal, calibration_path=str(cal_path), sources=sources, path=where, **values)
