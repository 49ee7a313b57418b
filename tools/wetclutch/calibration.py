"""Calibration file (TOML): loading and validation, and writing one back.

A calibration file holds one inline table per parameter:
``name = { value = ..., unit = "...", source = "..." }``. The unit is checked
against the one this module expects, so a file written in other units (kPa
where Pa is expected) is rejected rather than silently misread.
``render_calibration`` writes a base file with some values and sources
replaced (``wetclutch identify``), keeping its layout and comments.
"""
from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path


class CalibrationError(Exception):
    """A calibration file that cannot be used; the message names file and parameter."""


# (section, name, unit, constraint, C field). Constraints:
# "pos" > 0, "nonneg" >= 0, "finite" any finite, "count" positive integer.
PARAMETERS: tuple[tuple[str, str, str, str, str | None], ...] = (
    ("geometry", "outer_radius", "m", "pos", "outer_radius_m"),
    ("geometry", "inner_radius", "m", "pos", "inner_radius_m"),
    ("geometry", "friction_area", "m^2", "pos", "friction_area_m2"),
    ("geometry", "piston_area", "m^2", "pos", "piston_area_m2"),
    ("geometry", "friction_pairs", "1", "count", "friction_pairs"),
    ("thermal", "oil_conductance", "W/K", "pos", "oil_conductance_W_per_K"),
    ("thermal", "housing_conductance", "W/K", "nonneg", "housing_conductance_W_per_K"),
    ("thermal", "separator_thickness", "m", "pos", None),
    ("thermal", "lining_thickness", "m", "pos", None),
    ("thermal", "separator_density", "kg/m^3", "pos", None),
    ("thermal", "separator_specific_heat", "J/(kg*K)", "pos", None),
    ("thermal", "lining_density", "kg/m^3", "pos", None),
    ("thermal", "lining_specific_heat", "J/(kg*K)", "pos", None),
    ("viscosity", "mv1", "Pa*s", "nonneg", "viscosity_a1_Pa_s"),
    ("viscosity", "mv2", "1/K", "finite", "viscosity_b1_per_K"),
    ("viscosity", "mv3", "Pa*s", "nonneg", "viscosity_a2_Pa_s"),
    ("viscosity", "mv4", "1/K", "finite", "viscosity_b2_per_K"),
    ("friction", "mu1", "1", "pos", "mu1"),
    ("friction", "mu2", "1", "pos", "mu2"),
    ("friction", "mu3", "1", "finite", "mu3"),
    ("friction", "stribeck_speed", "m/s", "pos", "stribeck_speed_m_s"),
    ("friction", "theta1", "degC", "finite", "theta1_degC"),
    ("friction", "theta2", "K", "pos", "theta2_K"),
    ("contact", "youngs_modulus", "Pa", "pos", None),
    ("contact", "asperity_tip_radius", "m", "pos", None),
    ("contact", "roughness_rms", "m", "pos", None),
    ("contact", "asperity_density", "1/m^2", "pos", None),
    ("hydraulics", "vfs_gain", "Pa/mA", "pos", "vfs_gain_Pa_per_mA"),
    ("hydraulics", "vfs_time_constant", "s", "pos", "vfs_time_constant_s"),
    ("hydraulics", "return_spring_force", "N", "nonneg", "return_spring_force_N"),
    ("hydraulics", "vfs_current_min", "mA", "nonneg", "vfs_current_min_mA"),
    ("hydraulics", "vfs_current_max", "mA", "pos", "vfs_current_max_mA"),
    ("control", "period", "s", "pos", "control_period_s"),
    ("film_lut", "nodes", "1", "count", None),
    ("film_lut", "contact_pressure_max", "Pa", "pos", None),
    ("film_lut", "separation_max_sigma", "1", "pos", None),
)


@dataclass(frozen=True)
class Calibration:
    """Validated parameters in SI units (temperatures in degC), plus derived values."""

    values: dict[str, float]
    sources: dict[str, str]
    path: str

    def __getattr__(self, name: str) -> float:
        try:
            return self.values[name]
        except KeyError:
            raise AttributeError(name) from None

    # Derived quantities -------------------------------------------------
    @property
    def effective_radius(self) -> float:
        """R_eff (eq. 3), m."""
        ro, ri = self.outer_radius, self.inner_radius
        return 2.0 / 3.0 * (ro**3 - ri**3) / (ro**2 - ri**2)

    @property
    def heat_capacity(self) -> float:
        """C of eq. 1: N_c ((m c_p)_lining + (m c_p)_separator), J/K."""
        annulus = math.pi * (self.outer_radius**2 - self.inner_radius**2)
        separator = annulus * self.separator_thickness * self.separator_density * self.separator_specific_heat
        lining = self.friction_area * self.lining_thickness * self.lining_density * self.lining_specific_heat
        return self.friction_pairs * (separator + lining)

    @property
    def roughness_parameter(self) -> float:
        """N beta sigma, dimensionless (Greenwood-Williamson)."""
        return self.asperity_density * self.asperity_tip_radius * self.roughness_rms

    def with_values(self, **changes: float) -> "Calibration":
        """A copy with some values replaced (for tests and identification)."""
        values = dict(self.values)
        for k, v in changes.items():
            if k not in values:
                raise KeyError(k)
            values[k] = float(v)
        return Calibration(values, dict(self.sources), self.path)


def _check_value(path: str, qualified: str, raw: object, constraint: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise CalibrationError(f"{path}: parameter '{qualified}': value {raw!r} is not a number")
    value = float(raw)
    if not math.isfinite(value):
        raise CalibrationError(f"{path}: parameter '{qualified}': value {raw!r} is not finite")
    if constraint in ("pos", "count") and value <= 0.0:
        raise CalibrationError(f"{path}: parameter '{qualified}': value {raw!r} must be > 0")
    if constraint == "nonneg" and value < 0.0:
        raise CalibrationError(f"{path}: parameter '{qualified}': value {raw!r} must be >= 0")
    if constraint == "count" and value != int(value):
        raise CalibrationError(f"{path}: parameter '{qualified}': value {raw!r} must be a whole number")
    return value


def load(path: str | Path) -> Calibration:
    """Read and validate a calibration file. Raises CalibrationError."""
    path = str(path)
    try:
        with open(path, "rb") as f:
            doc = tomllib.load(f)
    except OSError as e:
        raise CalibrationError(f"{path}: cannot read calibration file: {e.strerror}") from None
    except tomllib.TOMLDecodeError as e:
        raise CalibrationError(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:
        raise CalibrationError(f"{path}: not UTF-8 text (byte {e.start}): not a calibration file") from None

    known = {(s, n) for s, n, *_ in PARAMETERS}
    for section, table in doc.items():
        if not isinstance(table, dict):
            raise CalibrationError(f"{path}: '{section}' must be a table of parameters")
        for name in table:
            if (section, name) not in known:
                raise CalibrationError(f"{path}: unknown parameter '{section}.{name}'")

    values: dict[str, float] = {}
    sources: dict[str, str] = {}
    for section, name, unit, constraint, _ in PARAMETERS:
        qualified = f"{section}.{name}"
        entry = doc.get(section, {}).get(name)
        if entry is None:
            raise CalibrationError(f"{path}: missing parameter '{qualified}' (unit {unit})")
        if not isinstance(entry, dict) or "value" not in entry:
            raise CalibrationError(
                f"{path}: parameter '{qualified}' must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
        if entry.get("unit") != unit:
            raise CalibrationError(
                f"{path}: parameter '{qualified}': unit {entry.get('unit')!r}, expected {unit!r}")
        source = entry.get("source")
        if not isinstance(source, str) or not source.strip():
            raise CalibrationError(f"{path}: parameter '{qualified}': missing 'source' (paper table or reason)")
        values[name] = _check_value(path, qualified, entry["value"], constraint)
        sources[name] = source

    cal = Calibration(values, sources, path)
    _check_relations(cal)
    return cal


def _check_relations(cal: Calibration) -> None:
    p = cal.path
    if cal.inner_radius >= cal.outer_radius:
        raise CalibrationError(f"{p}: parameter 'geometry.inner_radius' must be < geometry.outer_radius")
    if cal.vfs_current_max <= cal.vfs_current_min:
        raise CalibrationError(f"{p}: parameter 'hydraulics.vfs_current_max' must be > hydraulics.vfs_current_min")
    force_max = cal.vfs_gain * cal.vfs_current_max * cal.piston_area - cal.return_spring_force
    if force_max / cal.friction_area > cal.contact_pressure_max:
        raise CalibrationError(f"{p}: parameter 'film_lut.contact_pressure_max' must cover the contact pressure at"
                               f" the maximum current ({force_max / cal.friction_area:.6g} Pa)")
    if cal.nodes < 2:
        raise CalibrationError(f"{p}: parameter 'film_lut.nodes' must be >= 2")


# ---------------------------------------------------------------------------
# Writing a calibration file

_LINE = re.compile(r'^(\s*)([A-Za-z_][A-Za-z0-9_]*)(\s*=\s*)\{.*\}\s*(#.*)?$')


def _fmt(x: float) -> str:
    return repr(float(f"{x:.7g}"))


def render_calibration(base_path: Path, cal: Calibration, changes: dict[str, float], sources: dict[str, str],
                       header: str) -> str:
    """The base file with the changed values and their sources replaced (comments kept)."""
    units = {name: (section, unit) for section, name, unit, *_ in PARAMETERS}
    text = Path(base_path).read_text(encoding="utf-8")
    section = None
    done = set()
    lines = []
    for line in text.splitlines():
        m_sec = re.match(r'^\s*\[([^\]]+)\]\s*(#.*)?$', line)
        if m_sec:
            section = m_sec.group(1).strip()
        m = _LINE.match(line)
        if m and m.group(2) in changes and units[m.group(2)][0] == section:
            name = m.group(2)
            src = sources[name].replace("\\", "/").replace('"', "'")
            line = f'{m.group(1)}{name}{m.group(3)}{{ value = {_fmt(changes[name])}, unit = "{units[name][1]}",' \
                   f' source = "{src}" }}'
            done.add(name)
        lines.append(line)
    if done != set(changes):
        # the base is not in the one-line-per-parameter form: write every parameter out instead
        return _render_full(cal.with_values(**changes), {**cal.sources, **sources}, header)
    return header + "\n".join(lines) + "\n"


def _render_full(cal: Calibration, sources: dict[str, str], header: str) -> str:
    out = [header.rstrip("\n")]
    section = None
    for sec, name, unit, constraint, _ in PARAMETERS:
        if sec != section:
            out.append(f"\n[{sec}]")
            section = sec
        value = cal.values[name]
        text = str(int(value)) if constraint == "count" else _fmt(value)
        src = sources[name].replace("\\", "/").replace('"', "'")
        out.append(f'{name} = {{ value = {text}, unit = "{unit}", source = "{src}" }}')
    return "\n".join(out) + "\n"
