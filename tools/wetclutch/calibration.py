"""Calibration file (TOML): loading and validation, and writing one back.

A calibration file holds one inline table per parameter:
``name = { value = ..., unit = "...", source = "..." }``. The unit is checked
against the one this module expects, so a file written in other units (kPa
where Pa is expected) is rejected rather than silently misread.
``render_calibration`` writes a base file with some values and sources
replaced (``wetclutch identify``), keeping its layout and comments.

Validation applies the rules of the firmware's ``wc_calibration_check``
(src/model/wc_calibration.c; DESIGN.md section 8, "Calibration validity")
with the same limits (``LIMITS``, include/wetclutch/wc_calibration.h) to the
values the firmware will hold (rounded to float32), and the film-table rules
to the table ``wetclutch lut`` would write: ``load`` refuses what the firmware
would refuse. Every message names the parameter (``section.name``) and the
firmware's name for it (``wc_cal_error_name``).
"""
from __future__ import annotations

import math
import re
import struct
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class CalibrationError(Exception):
    """A calibration file that cannot be used; the message names file and parameter."""


# (section, name, unit, constraint, C field). Constraints:
# "pos" > 0, "nonneg" >= 0, "finite" any finite, "count" positive integer; RANGES (below) narrows
# them to the firmware's limits, and _check_relations adds the rules between fields.
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
    ("engagement", "film_squeeze_factor", "1", "nonneg", "film_squeeze_factor"),
    ("engagement", "static_friction_factor", "1", "pos", "static_friction_factor"),
    ("engagement", "lock_slip", "rad/s", "pos", "lock_slip_rad_s"),
    ("engagement", "breakaway_slip", "rad/s", "pos", "breakaway_slip_rad_s"),
    ("engagement", "lock_dwell", "1", "count", "lock_dwell_periods"),
    ("engagement", "holding_margin", "1", "nonneg", "holding_margin"),
    ("film_lut", "nodes", "1", "count", None),
    ("film_lut", "contact_pressure_max", "Pa", "pos", None),
    ("film_lut", "separation_max_sigma", "1", "pos", None),
)


# ---------------------------------------------------------------------------
# The firmware's limits (include/wetclutch/wc_calibration.h: WC_CAL_LIMIT_<key>, same numbers and
# reasons there; tests/python/test_calibration_rules.py compares them) and its model domain
# (include/wetclutch/wc_config.h).
THETA_MIN_DEGC, THETA_MAX_DEGC = -40.0, 250.0    # WC_THETA_MIN_degC, WC_THETA_MAX_degC
FORCE_MAX_N = 1.0e5                              # WC_FORCE_MAX_N: the inverse's force range
FILM_MAX_NODES = 1024                            # WC_FILM_MAX_NODES: longest table the firmware takes
LIMITS: dict[str, float] = {
    "RADIUS_MAX_m": 1.0,                         # R_o: R_eff N_c <= 64 m, v <= 1047 m/s
    "PISTON_AREA_MAX_m2": 1.0,
    "PI": 3.14159265,                            # A_f <= pi R_o^2
    "FRICTION_PAIRS_MAX": 64,
    "CONDUCTANCE_MAX_W_per_K": 1e5,              # k1, k2: steady temperature far from overflow
    "CONDUCTANCE_SUM_MIN_W_per_K": 1e-3,         # k1 + k2: eq. 1 at rest divides by it
    "HEAT_CAPACITY_MAX_J_per_K": 1e7,
    "TIME_CONSTANT_MAX_s": 1e5,                  # C / (k1 + k2), at least the control period
    "VISCOSITY_EXPONENT_MAX_per_K": 0.3,         # |b theta| <= 75: the firmware's exp is valid on [-87, 88]
    "VISCOSITY_MAX_Pa_s": 100.0,                 # mu_v on the domain: bounds the viscous torque
    "MU_MIN": 1e-3,                              # mu1, mu2: mu_f > 0 in float (Stribeck blend rounding)
    "MU_MAX": 1.0,                               # mu1, mu2, and mu_f on the domain
    "STRIBECK_SPEED_MIN_m_s": 1e-6,
    "STRIBECK_SPEED_MAX_m_s": 100.0,
    "THETA2_MIN_K": 1.0,
    "VFS_GAIN_MAX_Pa_per_mA": 1e6,
    "VFS_TIME_CONSTANT_MIN_s": 1e-4,
    "VFS_TIME_CONSTANT_MAX_s": 10.0,
    "SPRING_FORCE_MAX_N": 1e5,
    "CURRENT_MAX_mA": 1e4,
    "CONTROL_PERIOD_MIN_s": 1e-4,
    "CONTROL_PERIOD_MAX_s": 0.1,
    "FILM_HBAR_MIN_m": 1e-9,                     # h_bar at every node: T_v = ... / h_bar bounded
    "FILM_HBAR_MAX_m": 1e-3,
    "FRITSCH_CARLSON": 9.0,                      # alpha^2 + beta^2 on every interval: monotone Hermite
    "FILM_SQUEEZE_FACTOR_MIN": 1e-4,             # phi: 0 (film state off) or in [MIN, MAX] (DESIGN 9)
    "FILM_SQUEEZE_FACTOR_MAX": 1.0,              # phi <= 1: grooves and lining only speed the squeeze up
    "STATIC_FRICTION_FACTOR_MIN": 0.5,           # static capacity / (mu_f(0, theta) R_eff N_c F_c)
    "STATIC_FRICTION_FACTOR_MAX": 2.0,
    "LOCK_SLIP_MAX_rad_s": 10.0,                 # lock band (95 rpm): a lock-up, not a slip controller
    "BREAKAWAY_SLIP_MAX_rad_s": 20.0,            # breakaway band, above the lock band (hysteresis)
    "LOCK_DWELL_MAX_periods": 255,               # the firmware counts the dwell in 8 bits
    "HOLDING_MARGIN_MIN": 0.05,                  # half of it is the lock-up's torque hysteresis
    "HOLDING_MARGIN_MAX": 1.0,                   # holding force up to twice the request's
}
_L = LIMITS

# The firmware's names of the checks that involve several fields (wc_cal_error_name).
C_NAMES = {
    "heat_capacity": "heat_capacity_J_per_K",
    "conductance_sum": "oil_conductance_W_per_K + housing_conductance_W_per_K",
    "time_constant": "heat_capacity_J_per_K / (oil_conductance_W_per_K + housing_conductance_W_per_K)",
    "viscosity_range": "viscosity_a1_Pa_s..viscosity_b2_per_K (mu_v on the temperature domain)",
    "friction_domain": "mu1, mu2, mu3, theta1_degC, theta2_K (mu_f on the temperature domain)",
    "film_table": "film (table arrays, length or entries)",
    "film_axis": "film.pressure_Pa (not strictly increasing)",
    "film_range": "film.hbar_m, film.pressure_Pa (outside the physical range)",
    "film_not_monotone": "film.hbar_m, film.slope_m_per_Pa (not monotone: Fritsch-Carlson)",
    "film_coverage": "film.pressure_Pa (last node below the contact pressure at vfs_current_max_mA)",
}

# Range of each parameter: (low, low included, high or None). High limits are included, as in the
# firmware. Parameters without a C field (the film_lut, contact and thermal-material ones) are
# Python's own: positive, finite, and the film table they make must pass the film rules.
RANGES: dict[str, tuple[float, bool, float | None]] = {
    "outer_radius": (0.0, False, _L["RADIUS_MAX_m"]),
    "inner_radius": (0.0, False, None),                      # and < outer_radius
    "friction_area": (0.0, False, None),                     # and <= pi outer_radius^2
    "piston_area": (0.0, False, _L["PISTON_AREA_MAX_m2"]),
    "friction_pairs": (1.0, True, _L["FRICTION_PAIRS_MAX"]),
    "oil_conductance": (0.0, False, _L["CONDUCTANCE_MAX_W_per_K"]),
    "housing_conductance": (0.0, True, _L["CONDUCTANCE_MAX_W_per_K"]),
    "mv1": (0.0, True, _L["VISCOSITY_MAX_Pa_s"]),
    "mv2": (-_L["VISCOSITY_EXPONENT_MAX_per_K"], True, _L["VISCOSITY_EXPONENT_MAX_per_K"]),
    "mv3": (0.0, True, _L["VISCOSITY_MAX_Pa_s"]),
    "mv4": (-_L["VISCOSITY_EXPONENT_MAX_per_K"], True, _L["VISCOSITY_EXPONENT_MAX_per_K"]),
    "mu1": (_L["MU_MIN"], True, _L["MU_MAX"]),
    "mu2": (_L["MU_MIN"], True, _L["MU_MAX"]),
    "mu3": (-math.inf, False, None),
    "stribeck_speed": (_L["STRIBECK_SPEED_MIN_m_s"], True, _L["STRIBECK_SPEED_MAX_m_s"]),
    "theta1": (THETA_MIN_DEGC, True, THETA_MAX_DEGC),
    "theta2": (_L["THETA2_MIN_K"], True, None),
    "vfs_gain": (0.0, False, _L["VFS_GAIN_MAX_Pa_per_mA"]),
    "vfs_time_constant": (_L["VFS_TIME_CONSTANT_MIN_s"], True, _L["VFS_TIME_CONSTANT_MAX_s"]),
    "return_spring_force": (0.0, True, _L["SPRING_FORCE_MAX_N"]),
    "vfs_current_min": (0.0, True, _L["CURRENT_MAX_mA"]),
    "vfs_current_max": (0.0, False, _L["CURRENT_MAX_mA"]),   # and > vfs_current_min
    "period": (_L["CONTROL_PERIOD_MIN_s"], True, _L["CONTROL_PERIOD_MAX_s"]),
    "nodes": (2.0, True, FILM_MAX_NODES),
    "film_squeeze_factor": (0.0, True, _L["FILM_SQUEEZE_FACTOR_MAX"]),   # and 0 or >= the MIN
    "static_friction_factor": (_L["STATIC_FRICTION_FACTOR_MIN"], True, _L["STATIC_FRICTION_FACTOR_MAX"]),
    "lock_slip": (0.0, False, _L["LOCK_SLIP_MAX_rad_s"]),
    "breakaway_slip": (0.0, False, _L["BREAKAWAY_SLIP_MAX_rad_s"]),    # and > lock_slip
    "lock_dwell": (1.0, True, _L["LOCK_DWELL_MAX_periods"]),
    "holding_margin": (_L["HOLDING_MARGIN_MIN"], True, _L["HOLDING_MARGIN_MAX"]),
}


def f32(x: float) -> float:
    """x rounded to float32 as a C cast does (+-inf beyond the float range), as a Python float."""
    try:
        return struct.unpack("f", struct.pack("f", x))[0]
    except OverflowError:
        return math.copysign(math.inf, x)


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


def _range_text(low: float, low_in: bool, high: float | None) -> str:
    lo = "(-inf" if low == -math.inf else ("[" if low_in else "(") + f"{low:g}"
    return f"{lo}, {'inf)' if high is None else f'{high:g}]'}"


def _check_value(path: str, qualified: str, raw: object, constraint: str, field: str | None, unit: str) -> float:
    """One parameter: a finite number in its range; a firmware field checked as the float32 it becomes."""
    where = f"{path}: parameter '{qualified}'" + (f" ({field})" if field else "")
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise CalibrationError(f"{where}: value {raw!r} is not a number")
    value = float(raw)
    if not math.isfinite(value):
        raise CalibrationError(f"{where}: value {raw!r} is not finite")
    if constraint == "count" and value != int(value):
        raise CalibrationError(f"{where}: value {raw!r} must be a whole number")
    name = qualified.split(".", 1)[1]
    checked = value
    if field is not None and constraint != "count":
        checked = f32(value)      # what the firmware will hold
        if math.isinf(checked):
            raise CalibrationError(f"{where}: value {raw!r} is beyond the float32 range of the firmware")
        if checked == 0.0 and value != 0.0:
            raise CalibrationError(f"{where}: value {raw!r} rounds to 0 in float32 (the firmware would see 0)")
    low, low_in, high = RANGES.get(name, (0.0, False, None) if constraint in ("pos", "count") else
                                   (0.0, True, None) if constraint == "nonneg" else (-math.inf, False, None))
    if field is not None and constraint != "count":
        low, high = f32(low), (None if high is None else f32(high))
    if not ((checked >= low if low_in else checked > low) and (high is None or checked <= high)):
        raise CalibrationError(f"{where}: value {raw!r} must be in {_range_text(low, low_in, high)} {unit}")
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
    for section, name, unit, constraint, field in PARAMETERS:
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
        values[name] = _check_value(path, qualified, entry["value"], constraint, field, unit)
        sources[name] = source

    cal = Calibration(values, sources, path)
    _check_relations(cal)
    _check_film(cal)
    return cal


def _check_relations(cal: Calibration) -> None:
    """The firmware's checks of several fields, in float32 as it computes them (wc_calibration.c)."""
    p = cal.path
    v = cal.values
    F = np.float32
    with np.errstate(all="ignore"):
        c = {name: F(v[name]) for name in RANGES if name in v}
        # geometry
        if not c["inner_radius"] < c["outer_radius"]:
            raise CalibrationError(f"{p}: parameter 'geometry.inner_radius' (inner_radius_m) must be <"
                                   " geometry.outer_radius")
        disc = F(_L["PI"]) * c["outer_radius"] * c["outer_radius"]
        if not c["friction_area"] <= disc:
            raise CalibrationError(f"{p}: parameter 'geometry.friction_area' (friction_area_m2) must be <= pi"
                                   f" geometry.outer_radius^2 = {float(disc):.6g} m^2 (the lining within the disc)")
        # thermal (eq. 1)
        k = c["oil_conductance"] + c["housing_conductance"]
        if not k >= F(_L["CONDUCTANCE_SUM_MIN_W_per_K"]):
            raise CalibrationError(
                f"{p}: parameters 'thermal.oil_conductance' + 'thermal.housing_conductance'"
                f" ({C_NAMES['conductance_sum']}) = {float(k):.6g} W/K must be >="
                f" {_L['CONDUCTANCE_SUM_MIN_W_per_K']:g} W/K (the observer's steady state divides by it)")
        heat = F(f32(cal.heat_capacity))
        if not (heat > 0 and heat <= F(_L["HEAT_CAPACITY_MAX_J_per_K"])):
            raise CalibrationError(
                f"{p}: parameters 'thermal.separator_thickness' .. 'thermal.lining_specific_heat'"
                f" ({C_NAMES['heat_capacity']} = N_c((m c_p)_lining + (m c_p)_separator) = {float(heat):.6g} J/K)"
                f" must be in (0, {_L['HEAT_CAPACITY_MAX_J_per_K']:g}] J/K")
        # viscosity (eq. 2): each term monotone in theta, so its extremes are at the domain's ends
        low = high = F(0.0)
        for a, b in (("mv1", "mv2"), ("mv3", "mv4")):
            ends = [c[a] * np.exp(c[b] * F(t)) for t in (THETA_MIN_DEGC, THETA_MAX_DEGC)]
            low, high = low + min(ends), high + max(ends)
        if not (low > 0 and high <= F(_L["VISCOSITY_MAX_Pa_s"])):
            raise CalibrationError(
                f"{p}: parameters 'viscosity.mv1' .. 'viscosity.mv4' ({C_NAMES['viscosity_range']}): mu_v on"
                f" {THETA_MIN_DEGC:g}..{THETA_MAX_DEGC:g} degC spans {float(low):.6g}..{float(high):.6g} Pa s,"
                f" must be in (0, {_L['VISCOSITY_MAX_Pa_s']:g}]")
        # friction (eq. 18): the temperature factor is linear in theta, so its ends bound it
        ends = [F(1.0) + c["mu3"] * (F(t) - c["theta1"]) / c["theta2"] for t in (THETA_MIN_DEGC, THETA_MAX_DEGC)]
        mu_max = max(c["mu1"], c["mu2"]) * max(ends)
        if not (ends[0] > 0 and ends[1] > 0 and mu_max <= F(_L["MU_MAX"])):
            raise CalibrationError(
                f"{p}: parameters 'friction.mu1' .. 'friction.theta2' ({C_NAMES['friction_domain']}): the"
                f" temperature factor 1 + mu3 (theta - theta1)/theta2 is {float(ends[0]):.6g} at"
                f" {THETA_MIN_DEGC:g} degC and {float(ends[1]):.6g} at {THETA_MAX_DEGC:g} degC, must be > 0;"
                f" mu_f up to {float(mu_max):.6g}, must be <= {_L['MU_MAX']:g}")
        # hydraulics: the piston applies and stays within the inverse's force range
        if not c["vfs_current_max"] > c["vfs_current_min"]:
            raise CalibrationError(f"{p}: parameter 'hydraulics.vfs_current_max' (vfs_current_max_mA) must be >"
                                   " hydraulics.vfs_current_min")
        piston = c["vfs_gain"] * c["vfs_current_max"] * c["piston_area"]
        if not piston <= F(FORCE_MAX_N):
            raise CalibrationError(
                f"{p}: parameter 'hydraulics.vfs_current_max' (vfs_current_max_mA): the piston force K i_max A_p ="
                f" {float(piston):.6g} N must be <= {FORCE_MAX_N:g} N (WC_FORCE_MAX_N, the inverse's range)")
        force = piston - c["return_spring_force"]
        if not force > 0:
            raise CalibrationError(
                f"{p}: parameter 'hydraulics.vfs_current_max' (vfs_current_max_mA): the piston force K i_max A_p ="
                f" {float(piston):.6g} N must exceed hydraulics.return_spring_force (the clutch must apply)")
        # thermal time constant, between the control period and its limit
        tc = heat / k
        if not (tc >= c["period"] and tc <= F(_L["TIME_CONSTANT_MAX_s"])):
            raise CalibrationError(
                f"{p}: parameters 'thermal.oil_conductance', 'thermal.housing_conductance', the heat capacity of"
                f" the thermal section and 'control.period' ({C_NAMES['time_constant']}): the thermal time"
                f" constant {float(tc):.6g} s must be in [control.period, {_L['TIME_CONSTANT_MAX_s']:g}] s")
        # engagement edges (DESIGN 9): the film state off (0) or a squeeze factor the update resolves;
        # breakaway outside the lock band (hysteresis)
        phi = c["film_squeeze_factor"]
        if not (phi == 0 or phi >= F(_L["FILM_SQUEEZE_FACTOR_MIN"])):
            raise CalibrationError(
                f"{p}: parameter 'engagement.film_squeeze_factor' (film_squeeze_factor) must be 0 (film state off)"
                f" or in [{_L['FILM_SQUEEZE_FACTOR_MIN']:g}, {_L['FILM_SQUEEZE_FACTOR_MAX']:g}]")
        if not c["breakaway_slip"] > c["lock_slip"]:
            raise CalibrationError(f"{p}: parameter 'engagement.breakaway_slip' (breakaway_slip_rad_s) must be >"
                                   " engagement.lock_slip (the hysteresis between locking and breakaway)")
        # the film table reaches the contact pressure at the maximum current
        pressure = force / c["friction_area"]
        if not F(v["contact_pressure_max"]) >= pressure:
            raise CalibrationError(
                f"{p}: parameter 'film_lut.contact_pressure_max' ({C_NAMES['film_coverage']}) must cover the"
                f" contact pressure at the maximum current ({float(pressure):.6g} Pa)")


def film_problem(pressure_Pa, hbar_m, slope_m_per_Pa, cal: Calibration | None = None) -> str | None:
    """The firmware's film-table rules (wc_calibration.c, check_film) on the table as stored (float32):
    None if it passes, else what fails, naming the firmware's field."""
    F = np.float32
    with np.errstate(all="ignore"):
        p, h, s = (np.asarray(a, dtype=float).astype(np.float32) for a in (pressure_Pa, hbar_m, slope_m_per_Pa))
        n = p.size
        if not (h.size == n and s.size == n and 2 <= n <= FILM_MAX_NODES):
            return f"{C_NAMES['film_table']}: {n} nodes, must be 2..{FILM_MAX_NODES}"
        for name, a in (("pressure_Pa", p), ("hbar_m", h), ("slope_m_per_Pa", s)):
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                return f"{C_NAMES['film_table']}: film.{name}[{bad[0]}] = {a[bad[0]]} is not finite"
        up = np.diff(p)
        if not np.all(up > 0):
            return f"{C_NAMES['film_axis']}: at node {int(np.argmin(up > 0)) + 1}"
        if not p[0] >= 0:
            return f"{C_NAMES['film_range']}: film.pressure_Pa[0] = {float(p[0]):.6g} Pa is negative"
        inside = (h >= F(_L["FILM_HBAR_MIN_m"])) & (h <= F(_L["FILM_HBAR_MAX_m"]))
        if not np.all(inside):
            k = int(np.argmin(inside))
            return (f"{C_NAMES['film_range']}: film.hbar_m[{k}] = {float(h[k]):.6g} m outside"
                    f" [{_L['FILM_HBAR_MIN_m']:g}, {_L['FILM_HBAR_MAX_m']:g}] m")
        if not np.all(s <= 0):
            k = int(np.argmin(s <= 0))
            return f"{C_NAMES['film_not_monotone']}: film.slope_m_per_Pa[{k}] = {float(s[k]):.6g} m/Pa is positive"
        delta = (h[1:] - h[:-1]) / up
        if not np.all(delta < 0):
            k = int(np.argmin(delta < 0))
            return f"{C_NAMES['film_not_monotone']}: h_bar does not fall from node {k} to {k + 1}"
        alpha, beta = s[:-1] / delta, s[1:] / delta
        fc = alpha * alpha + beta * beta
        if not np.all(fc <= F(_L["FRITSCH_CARLSON"])):
            k = int(np.argmin(fc <= F(_L["FRITSCH_CARLSON"])))
            return (f"{C_NAMES['film_not_monotone']}: interval {k}: alpha^2 + beta^2 = {float(fc[k]):.6g} > "
                    f"{_L['FRITSCH_CARLSON']:g}, its cubic Hermite is not monotone")
        if cal is not None:
            force = F(cal.vfs_gain) * F(cal.vfs_current_max) * F(cal.piston_area) - F(cal.return_spring_force)
            if not p[-1] >= force / F(cal.friction_area):
                return (f"{C_NAMES['film_coverage']}: the last node {float(p[-1]):.6g} Pa is below the contact"
                        f" pressure at the maximum current {float(force / F(cal.friction_area)):.6g} Pa")
    return None


def _check_film(cal: Calibration) -> None:
    """The film table `wetclutch lut` would write from this calibration must pass the firmware's rules."""
    from . import lut   # lut imports this module
    try:
        lut.build_table(cal)
    except lut.TableError as e:
        raise CalibrationError(str(e)) from None


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
