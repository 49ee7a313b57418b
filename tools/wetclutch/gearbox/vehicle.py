"""The vehicle seen by a gearbox's reduced models: the five driveline values of a vehicle plant file.

A vehicle is a plant file (tools/plants/vehicles/*.toml, or any path): its [driveline] entries
turbine_inertia, output_inertia, vehicle_mass, wheel_radius and final_drive, each { value, unit, source },
following the plant's ``extends = "base.toml"`` chain (a path relative to the file naming it; the file's own
entries replace its base's, entry by entry). The rest of the plant file (clutch, engine, sensors, scenario)
is the simulator's: it is not read here, so this module needs nothing above the calibration layer.
tests/python/test_gearbox.py checks these values against wetclutch.simulate.plant.load_plant for every
vehicle of tools/plants/vehicles (one rule, two readers: the test keeps them the same).

How a shift's reduced model uses them (wetclutch.gearbox.reduction):
  turbine side  the vehicle's turbine_inertia is the whole turbine shaft (engine, converter locked, input
                shaft and its members, as the plant files state): it REPLACES the gearbox's own input-shaft
                inertia;
  output side   the vehicle's output_inertia (output shaft, output members, transfer gear) REPLACES the
                gearbox's own output-shaft inertia, and the vehicle's mass at the output shaft,
                m r_w^2 / r_f^2 (rigid driveline, as wetclutch.shift.vehicle_cal), is added to it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ..util.tomlfile import extends_path, read_toml
from .description import GearboxError

# (name in [driveline], unit)
FIELDS: tuple[tuple[str, str], ...] = (
    ("turbine_inertia", "kg*m^2"),
    ("output_inertia", "kg*m^2"),
    ("vehicle_mass", "kg"),
    ("wheel_radius", "m"),
    ("final_drive", "1"),
)


@dataclass(frozen=True)
class Vehicle:
    """The driveline values of a vehicle plant file (SI units)."""

    turbine_inertia: float
    output_inertia: float
    vehicle_mass: float
    wheel_radius: float
    final_drive: float
    path: str = ""

    @property
    def mass_at_output(self) -> float:
        """m r_w^2 / r_f^2: the vehicle referred to the transmission's output shaft, kg m^2."""
        return self.vehicle_mass * self.wheel_radius ** 2 / self.final_drive ** 2

    def jerk_per_torque_rate(self, output_ratio: float) -> float:
        """b r_f / (m r_w): vehicle jerk per rate of the turbine-referred element torque, (m/s^3)/(Nm/s)."""
        return output_ratio * self.final_drive / (self.vehicle_mass * self.wheel_radius)


def _driveline(path: Path, chain: tuple) -> dict:
    """[driveline] of path with its extends chain merged in (the file's own entries win)."""
    doc = read_toml(path, GearboxError, "vehicle plant file")
    table = doc.get("driveline", {})
    if not isinstance(table, dict):
        raise GearboxError(f"{path}: 'driveline' must be a table of parameters")
    base_path = extends_path(path, doc, chain, GearboxError)
    if base_path is None:
        return dict(table)
    return {**_driveline(base_path, chain + (base_path,)), **table}


def load_vehicle(path) -> Vehicle:
    """The driveline values of a vehicle plant file (any path). Raises GearboxError naming the file and the
    parameter ('driveline.vehicle_mass')."""
    path = Path(path)
    table = _driveline(path, (path.resolve(),))
    values = {}
    for name, unit in FIELDS:
        entry = table.get(name)
        where = f"{path}: parameter 'driveline.{name}'"
        if entry is None:
            raise GearboxError(f"{path}: missing parameter 'driveline.{name}' (unit {unit})")
        if not isinstance(entry, dict) or "value" not in entry:
            raise GearboxError(f"{where} must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
        if entry.get("unit") != unit:
            raise GearboxError(f"{where}: unit {entry.get('unit')!r}, expected {unit!r}")
        value = entry["value"]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value <= 0:
            raise GearboxError(f"{where}: value {value!r} must be a positive number")
        values[name] = float(value)
    return Vehicle(**values, path=str(path))
