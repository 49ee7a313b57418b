"""The calibration's parameters: the Calibration type (validated values in SI units, derived quantities), the
parameter table of the file (section, name, unit, constraint, C field), the firmware's limits and ranges."""
from __future__ import annotations

import functools
import math
import struct
from dataclasses import dataclass


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
    ("engagement", "open_clearance", "m", "nonneg", "open_clearance_m"),
    ("engagement", "open_aeration_speed", "rad/s", "nonneg", "open_aeration_speed_rad_s"),
    ("film_lut", "nodes", "1", "count", None),
    ("film_lut", "contact_pressure_max", "Pa", "pos", None),
    ("film_lut", "separation_max_sigma", "1", "pos", None),
)


# Parameters a file may leave out: their value then (0: off, the firmware's model without them) and the source
# the loader records. The open element's drag (DESIGN 15; wc_calibration.h): a single clutch's file has no
# retracted piston to describe, a gearbox's elements do (tools/gearboxes/8hp.toml).
OPTIONAL: dict[str, float] = {"open_clearance": 0.0, "open_aeration_speed": 0.0}
OPTIONAL_SOURCE = "not in the file: 0, off (the open element's drag as the film's, DESIGN 15)"


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
    "OPEN_CLEARANCE_MAX_m": 5e-3,                # open drag: retracted stroke per gap, 0 (off) .. 5 mm
    "OPEN_AERATION_SPEED_MIN_rad_s": 1.0,        # open drag's aeration speed: 0 (off) or in [MIN, MAX]
    "OPEN_AERATION_SPEED_MAX_rad_s": 1e4,
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
    "open_clearance": (0.0, True, _L["OPEN_CLEARANCE_MAX_m"]),
    "open_aeration_speed": (0.0, True, _L["OPEN_AERATION_SPEED_MAX_rad_s"]),   # and 0 or >= the MIN
}
# Fields that are 0 (off) or at least their minimum (the firmware's WC_FIELD_OR_ZERO), checked with the range.
OFF_OR_MIN: dict[str, float] = {"open_aeration_speed": _L["OPEN_AERATION_SPEED_MIN_rad_s"]}


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

    @functools.cached_property   # a Calibration is immutable; the film's bisections read it ~10^6 times
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
