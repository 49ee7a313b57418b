"""Shift calibration (TOML) of the on-coming clutch's shift controller (DESIGN 10).

One file holds the base calibration in ``[shift]`` and named variants in
``[variants.NAME]`` (each overrides some base values): the controllers the
comparison of ``wetclutch shift`` runs on the same plant. Every value is
``name = { value = ..., unit = "...", source = "..." }`` like the clutch
calibration; the unit is checked. ``load`` applies the firmware's
``wc_shift_calibration_check`` rules (include/wetclutch/wc_shift.h) to the
float32 values, so a file the firmware would refuse is refused here.

``generate/shift_header.py`` writes its header (``wetclutch lut`` on this file).
"""
from __future__ import annotations

import math
import struct
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..util.tomlfile import read_toml


class ShiftCalibrationError(Exception):
    """A shift calibration that cannot be used; the message names file, variant and parameter."""


TIME_MAX_S = 10.0
INERTIA_TIME_MIN_S, INERTIA_TIME_MAX_S = 0.05, 5.0
GAIN_MAX = 1e5
TORQUE_MAX_NM = 1.0e5      # WC_TORQUE_MAX_Nm
SLIP_MAX_RAD_S = 1047.2    # WC_SLIP_MAX_rad_s
THETA_MIN_DEGC, THETA_MAX_DEGC = -40.0, 250.0   # WC_THETA_MIN_degC, WC_THETA_MAX_degC
ADAPT_NODES = 5            # WC_ADAPT_NODES
CORRECTION_SCALE_MAX = 0.5  # WC_CORRECTION_SCALE_MAX
KISS_BAND_MAX_PA = 1e6     # WC_SHIFT_LIMIT_KISS_BAND_MAX_Pa
CURRENT_MAX_MA = 2000.0    # WC_SHIFT_LIMIT_CURRENT_MAX_mA
ENGINE_DELTA_MAX_NM = 1000.0  # WC_SHIFT_LIMIT_ENGINE_DELTA_MAX_Nm
GEAR_STEP_MIN = 0.01         # WC_SHIFT_GEAR_STEP_MIN: the off-going and the target ratio differ by 1 % at least

# (name in the file, unit, C field, check) in the C struct's order. check(value, values) -> bool.
FIELDS: tuple[tuple[str, str, str, object], ...] = (
    ("turbine_inertia", "kg*m^2", "turbine_inertia_kg_m2", lambda v, c: 1e-4 <= v <= 100.0),
    ("turbine_ratio", "1", "turbine_ratio", lambda v, c: 0.05 <= v <= 20.0),
    ("output_inertia", "kg*m^2", "output_inertia_kg_m2", lambda v, c: 1e-4 <= v <= 1e5),
    ("output_ratio", "1", "output_ratio", lambda v, c: 0.05 <= v <= 20.0),
    ("jerk_per_torque_rate", "(m/s^3)/(Nm/s)", "jerk_per_torque_rate", lambda v, c: 0.0 <= v <= 1.0),
    ("prepare_time", "s", "prepare_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("torque_phase_time", "s", "torque_phase_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("inertia_time_min", "s", "inertia_time_min_s", lambda v, c: INERTIA_TIME_MIN_S <= v <= INERTIA_TIME_MAX_S),
    ("inertia_time_max", "s", "inertia_time_max_s",
     lambda v, c: c["inertia_time_min"] <= v <= INERTIA_TIME_MAX_S),
    ("inertia_timeout_factor", "1", "inertia_timeout_factor", lambda v, c: 1.05 <= v <= 10.0),
    ("lockup_ramp_time", "s", "lockup_ramp_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("holding_torque_factor", "1", "holding_torque_factor", lambda v, c: 1.0 <= v <= 5.0),
    ("min_start_slip", "rad/s", "min_start_slip_rad_s", lambda v, c: 0.0 <= v <= SLIP_MAX_RAD_S),
    ("feedforward_gain", "1", "feedforward_gain", lambda v, c: 0.0 <= v <= 2.0),
    ("kp", "Nm/(rad/s)", "kp_Nm_per_rad_s", lambda v, c: 0.0 <= v <= GAIN_MAX),
    ("ki", "Nm/rad", "ki_Nm_per_rad", lambda v, c: 0.0 <= v <= GAIN_MAX),
    ("integral_limit", "Nm", "integral_limit_Nm", lambda v, c: 0.0 <= v <= TORQUE_MAX_NM),
    ("lag_compensation_time", "s", "lag_compensation_time_s", lambda v, c: v == 0.0 or 1e-3 <= v <= TIME_MAX_S),
    ("theta_source", "1", "theta_source", lambda v, c: v in (0, 1)),
    ("flare_slip", "rad/s", "flare_slip_rad_s", lambda v, c: 0.0 <= v <= SLIP_MAX_RAD_S),
    ("tie_up_factor", "1", "tie_up_factor", lambda v, c: 1.0 <= v <= 10.0),
    ("jerk_filter_time", "s", "jerk_filter_time_s", lambda v, c: v == 0.0 or 1e-3 <= v <= TIME_MAX_S),
    # Adaptation (DESIGN 12, include/wetclutch/wc_adapt.h)
    ("adaptation", "1", "adaptation", lambda v, c: v in (0, 1)),
    ("adapt_theta_node0", "degC", "adapt_theta_node_degC[0]", lambda v, c: THETA_MIN_DEGC <= v <= THETA_MAX_DEGC),
    *((f"adapt_theta_node{i}", "degC", f"adapt_theta_node_degC[{i}]",
       (lambda i: lambda v, c: c[f"adapt_theta_node{i - 1}"] < v <= THETA_MAX_DEGC)(i)) for i in range(1, ADAPT_NODES)),
    ("adapt_scale_band", "1", "adapt_scale_band", lambda v, c: 0.0 < v <= CORRECTION_SCALE_MAX),
    ("adapt_scale_step", "1", "adapt_scale_step", lambda v, c: 0.0 <= v <= CORRECTION_SCALE_MAX),
    ("adapt_scale_gain", "1", "adapt_scale_gain", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_confidence_gain", "1", "adapt_confidence_gain", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_film_factor_min", "1", "adapt_film_factor_min", lambda v, c: _f32(0.01) <= v <= 1.0),
    ("adapt_film_factor_max", "1", "adapt_film_factor_max", lambda v, c: 1.0 <= v <= 20.0),
    ("adapt_film_step", "1", "adapt_film_step", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_film_gain", "1", "adapt_film_gain", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_kiss_band", "Pa", "adapt_kiss_band_Pa", lambda v, c: 0.0 <= v <= KISS_BAND_MAX_PA),
    ("adapt_kiss_step", "Pa", "adapt_kiss_step_Pa", lambda v, c: 0.0 <= v <= KISS_BAND_MAX_PA),
    ("adapt_kiss_gain", "1", "adapt_kiss_gain", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_window_skip", "s", "adapt_window_skip_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("adapt_film_window", "s", "adapt_film_window_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("adapt_min_slip_drop", "1", "adapt_min_slip_drop", lambda v, c: 0.0 <= v <= 1.0),
    ("adapt_min_conditioning", "1", "adapt_min_conditioning", lambda v, c: 0.0 <= v <= 1.0),
    # The whole shift (DESIGN 14, wc_shift.h): coordinator 0 = the on-coming clutch alone
    ("coordinator", "1", "coordinator", lambda v, c: v in (0, 1)),
    ("offgoing_ratio", "1", "offgoing_ratio",
     lambda v, c: (v == 0.0 or 0.05 <= v <= 20.0) and
     (c["coordinator"] == 0 or (v != 0.0 and abs(v - c["output_ratio"]) >= GEAR_STEP_MIN * c["output_ratio"]))),
    ("fill_pulse_current", "mA", "fill_pulse_current_mA", lambda v, c: 0.0 <= v <= CURRENT_MAX_MA),
    ("fill_pulse_time", "s", "fill_pulse_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S and v <= c["prepare_time"]),
    ("offgoing_holding_factor", "1", "offgoing_holding_factor", lambda v, c: 0.0 <= v <= 5.0),
    ("offgoing_margin_factor", "1", "offgoing_margin_factor", lambda v, c: 0.0 <= v <= 1.0),
    ("offgoing_lag_compensation_time", "s", "offgoing_lag_compensation_time_s",
     lambda v, c: v == 0.0 or 1e-3 <= v <= TIME_MAX_S),
    ("flare_kp", "Nm/(rad/s)", "flare_kp_Nm_per_rad_s", lambda v, c: 0.0 <= v <= GAIN_MAX),
    ("flare_ki", "Nm/rad", "flare_ki_Nm_per_rad", lambda v, c: 0.0 <= v <= GAIN_MAX),
    ("handover_slip", "rad/s", "handover_slip_rad_s", lambda v, c: 0.0 <= v <= SLIP_MAX_RAD_S),
    ("engine_intervention", "1", "engine_intervention", lambda v, c: v in (0, 1)),
    ("engine_increase_max", "Nm", "engine_increase_max_Nm", lambda v, c: 0.0 <= v <= ENGINE_DELTA_MAX_NM),
    ("engine_reduction_max", "Nm", "engine_reduction_max_Nm", lambda v, c: 0.0 <= v <= ENGINE_DELTA_MAX_NM),
    ("engine_fill_fraction", "1", "engine_fill_fraction", lambda v, c: 0.0 <= v <= 1.0),
    ("engine_reduction_fraction", "1", "engine_reduction_fraction", lambda v, c: 0.0 <= v <= 2.0),
    ("engine_recovery_time", "s", "engine_recovery_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
    ("engine_lead_time", "s", "engine_lead_time_s", lambda v, c: 0.0 <= v <= 1.0),
    ("fallback_time", "s", "fallback_time_s", lambda v, c: 0.0 <= v <= TIME_MAX_S),
)
INTEGER_FIELDS = ("theta_source", "adaptation", "coordinator", "engine_intervention")
THETA_SOURCES = {0: "observer", 1: "oil"}


def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


@dataclass(frozen=True)
class ShiftCalibration:
    name: str                 # variant name
    values: dict              # file name -> value (float32-rounded; theta_source int)
    sources: dict             # file name -> source text

    def __getattr__(self, key):
        try:
            return self.__dict__["values"][key]
        except KeyError:
            raise AttributeError(key) from None

    def c_fields(self) -> list[tuple[str, float | int]]:
        return [(c_field, self.values[name]) for name, _, c_field, _ in FIELDS]


@dataclass(frozen=True)
class ShiftCalibrationSet:
    path: Path
    variants: dict            # name -> ShiftCalibration, in file order


def _entry(path, where, name, raw, unit):
    if not isinstance(raw, dict) or "value" not in raw or "unit" not in raw:
        raise ShiftCalibrationError(f"{path}: {where}.{name}: expected {{ value = ..., unit = \"{unit}\", source = ... }}")
    if raw["unit"] != unit:
        raise ShiftCalibrationError(f"{path}: {where}.{name}: unit '{raw['unit']}', expected '{unit}'")
    value = raw["value"]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ShiftCalibrationError(f"{path}: {where}.{name}: value {value!r} is not a number")
    return value, str(raw.get("source", ""))


def _check(path, variant, values):
    for name, _, _, check in FIELDS:
        v = values[name]
        if name in INTEGER_FIELDS:
            if v != int(v):
                raise ShiftCalibrationError(f"{path}: variant '{variant}': {name} = {v!r}: a whole number required")
        elif not math.isfinite(v):
            raise ShiftCalibrationError(f"{path}: variant '{variant}': {name} = {v!r}: not finite")
        if not check(v, values):
            raise ShiftCalibrationError(f"{path}: variant '{variant}': {name} = {v!r} outside the firmware's limits"
                                        " (wc_shift_calibration_check, include/wetclutch/wc_shift.h)")


def load(path: str | Path) -> ShiftCalibrationSet:
    path = Path(path)
    doc = read_toml(path, ShiftCalibrationError, "shift calibration file")
    base = doc.get("shift")
    if not isinstance(base, dict):
        raise ShiftCalibrationError(f"{path}: no [shift] table")
    unknown = set(doc) - {"shift", "variants"}
    if unknown:
        raise ShiftCalibrationError(f"{path}: unknown table(s) {sorted(unknown)}")
    units = {name: unit for name, unit, _, _ in FIELDS}
    values, sources = {}, {}
    for name in base:
        if name not in units:
            raise ShiftCalibrationError(f"{path}: shift.{name}: unknown parameter")
    for name, unit, _, _ in FIELDS:
        if name not in base:
            raise ShiftCalibrationError(f"{path}: shift.{name}: missing")
        values[name], sources[name] = _entry(path, "shift", name, base[name], unit)
    variants_doc = doc.get("variants", {"base": {}})
    if not isinstance(variants_doc, dict) or not variants_doc:
        raise ShiftCalibrationError(f"{path}: [variants] must hold at least one [variants.NAME] table")
    variants = {}
    for vname, overrides in variants_doc.items():
        if not (vname.isidentifier() and vname.isascii()):
            raise ShiftCalibrationError(f"{path}: variant name '{vname}' is not a C identifier")
        if not isinstance(overrides, dict):
            raise ShiftCalibrationError(f"{path}: variants.{vname} must be a table")
        v, s = dict(values), dict(sources)
        for name, raw in overrides.items():
            if name == "description":
                continue
            if name not in units:
                raise ShiftCalibrationError(f"{path}: variants.{vname}.{name}: unknown parameter")
            v[name], s[name] = _entry(path, f"variants.{vname}", name, raw, units[name])
        v = {k: (int(x) if k in INTEGER_FIELDS else _f32(float(x))) for k, x in v.items()}
        _check(path, vname, v)
        s["description"] = str(overrides.get("description", ""))
        variants[vname] = ShiftCalibration(vname, v, s)
    return ShiftCalibrationSet(path, variants)


def is_shift_calibration(path: str | Path) -> bool:
    """A file with a [shift] table (the clutch calibrations have none)."""
    try:
        with open(path, "rb") as f:
            return isinstance(tomllib.load(f).get("shift"), dict)
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return False   # not one: the clutch calibration's loader reports what is wrong with the file
