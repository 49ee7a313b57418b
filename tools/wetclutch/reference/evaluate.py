"""The ``reference`` subcommand: the model of reference/model on CSV columns, under the firmware's input rules.

Column names and units match the firmware's host program ``wc_eval`` so the
two can be compared file against file.

Input rules: those of the firmware's wc_torque, wc_inverse and wc_thermal_step
(include/wetclutch/wc_config.h, src/model/wc_internal.h), checked on the inputs
as the firmware receives them, rounded to float32 (a number beyond the float
range is infinite, as wc_eval's to_float makes it) and slip converted to rad/s
in float32:

  torque   slip |dw| <= 1047.2 rad/s (10000 rpm), theta in [-40, 250] degC, force in [0, 1e5] N
  inverse  slip as above, theta as above, torque request in [0, 1e5] Nm
  thermal  oil and housing temperatures in [-40, 250] degC, heat input |T dw| finite (in float) and >= 0

NaN and infinities break every rule. A row that breaks one gets the firmware's
status bits (model.STATUS_*_INVALID, include/wetclutch/wc_status.h) and its
documented safe outputs:

  torque   zero torque (coulomb, viscous, total), mu_f 0, h_bar of the film table's first node
           (the open clutch's film, film_thickness_m at the domain's h_max)
  inverse  force 0 with the return spring's preload pressure F_s / A_p and its solenoid current
           (clamped to the solenoid range like any current, STATUS_CURRENT_CLAMPED then)
  thermal  the estimate held: the state is left untouched, the row's output is the estimate before it

Every mode returns a 'status' column (inverse: also its own bits 1, 2, 4). The
command line (cli.py) by default fails on the first rejected row, naming its
line and the rule, as wc_eval does, and writes the columns wc_eval writes;
``--keep-rejected`` writes every row with its status instead.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from . import model
from ..util.csvio import CsvError

if TYPE_CHECKING:   # annotations only: the reference reads a calibration's attributes, the loader sits above it
    from ..calibration.parameters import Calibration

INPUTS = {
    "torque": ("slip_rpm", "theta_degC", "force_N"),
    "inverse": ("slip_rpm", "theta_degC", "torque_Nm"),
    "thermal": ("t_s", "slip_rpm", "torque_Nm", "theta_oil_degC", "theta_housing_degC"),
}
OUTPUTS = {  # the columns wc_eval writes
    "torque": ("torque_Nm", "coulomb_Nm", "viscous_Nm", "hbar_um", "mu_f"),
    "inverse": ("force_N", "pressure_kPa", "current_mA", "status"),
    "thermal": ("t_s", "theta_degC"),
}

_FLT_MAX = float(np.finfo(np.float32).max)


def as_float32(x) -> np.ndarray:
    """x as the firmware receives it: rounded to float32, beyond the float range infinite (wc_eval's to_float)."""
    x = np.asarray(x, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        f = np.where(x > _FLT_MAX, np.inf, np.where(x < -_FLT_MAX, -np.inf, x)).astype(np.float32)
    return f


def _slip_rad_s(slip_rpm) -> np.ndarray:
    with np.errstate(over="ignore", invalid="ignore"):
        return as_float32(slip_rpm) * np.float32(model.RAD_S_PER_RPM)   # float32 product, as the firmware


def _within(x32: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """wc_in_range: lo <= x <= hi in float32; false for NaN."""
    return (x32 >= np.float32(lo)) & (x32 <= np.float32(hi))


def _bit(bad: np.ndarray, bit: int) -> np.ndarray:
    return np.where(bad, bit, 0).astype(int)


def _slip_theta_status(slip_rpm, theta_degC) -> np.ndarray:
    return (_bit(~_within(_slip_rad_s(slip_rpm), -model.SLIP_MAX_RAD_S, model.SLIP_MAX_RAD_S),
                 model.STATUS_SLIP_INVALID)
            | _bit(~_within(as_float32(theta_degC), model.THETA_MIN_DEGC, model.THETA_MAX_DEGC),
                   model.STATUS_THETA_INVALID))


def torque_status(slip_rpm, theta_degC, force_N) -> np.ndarray:
    """wc_torque's input bits per row (0: accepted)."""
    return _slip_theta_status(slip_rpm, theta_degC) | _bit(
        ~_within(as_float32(force_N), 0.0, model.FORCE_MAX_N), model.STATUS_FORCE_INVALID)


def inverse_status(slip_rpm, theta_degC, torque_Nm) -> np.ndarray:
    """wc_inverse's input bits per row (0: accepted)."""
    return _slip_theta_status(slip_rpm, theta_degC) | _bit(
        ~_within(as_float32(torque_Nm), 0.0, model.TORQUE_MAX_NM), model.STATUS_TORQUE_INVALID)


def thermal_status(slip_rpm, torque_Nm, theta_oil_degC, theta_housing_degC) -> np.ndarray:
    """wc_thermal_step's input bits per row, with the heat input |T dw| in float32 as wc_eval computes it."""
    with np.errstate(over="ignore", invalid="ignore"):
        power = np.abs(as_float32(torque_Nm) * _slip_rad_s(slip_rpm))
        power_ok = np.isfinite(power) & (power >= 0)
    theta_ok = (_within(as_float32(theta_oil_degC), model.THETA_MIN_DEGC, model.THETA_MAX_DEGC)
                & _within(as_float32(theta_housing_degC), model.THETA_MIN_DEGC, model.THETA_MAX_DEGC))
    return _bit(~power_ok, model.STATUS_POWER_INVALID) | _bit(~theta_ok, model.STATUS_THETA_INVALID)


def rejection_text(status: int) -> str:
    """Which rule a status breaks, worded as wc_eval words it."""
    reasons = []
    if status & model.STATUS_SLIP_INVALID:
        reasons.append(f"slip_rpm not within +-{model.SLIP_MAX_RAD_S / model.RAD_S_PER_RPM:.0f} rpm")
    if status & model.STATUS_THETA_INVALID:
        reasons.append(f"a temperature not within {model.THETA_MIN_DEGC:g}..{model.THETA_MAX_DEGC:g} degC")
    if status & model.STATUS_FORCE_INVALID:
        reasons.append(f"force_N not within 0..{model.FORCE_MAX_N:g} N")
    if status & model.STATUS_TORQUE_INVALID:
        reasons.append(f"torque_Nm not within 0..{model.TORQUE_MAX_NM:g} Nm")
    if status & model.STATUS_POWER_INVALID:
        reasons.append("heat input |torque_Nm x slip| not finite")
    return "; ".join(reasons)


def _accepted(ok: np.ndarray, x) -> np.ndarray:
    """x where the row is accepted, a harmless 0 elsewhere (the model is not evaluated on rejected input)."""
    return np.where(ok, np.asarray(x, dtype=float), 0.0)


def open_film_hbar_m(cal: Calibration) -> float:
    """h_bar of the film table's first node (lut.build_table): the film at the domain's h_max."""
    return float(model.film_thickness_m(cal, model.film_domain(cal)[1]))


def torque(cal: Calibration, cols: dict, lines=None) -> dict:
    status = torque_status(cols["slip_rpm"], cols["theta_degC"], cols["force_N"])
    ok = status == 0
    r = model.torque_parts(cal, _accepted(ok, cols["slip_rpm"]), _accepted(ok, cols["theta_degC"]),
                           _accepted(ok, cols["force_N"]))
    return {"torque_Nm": np.where(ok, r["torque_Nm"], 0.0), "coulomb_Nm": np.where(ok, r["coulomb_Nm"], 0.0),
            "viscous_Nm": np.where(ok, r["viscous_Nm"], 0.0),
            "hbar_um": np.where(ok, r["hbar_m"], open_film_hbar_m(cal)) * 1e6,
            "mu_f": np.where(ok, r["mu_f"], 0.0), "status": status}


def inverse(cal: Calibration, cols: dict, lines=None) -> dict:
    rejected = inverse_status(cols["slip_rpm"], cols["theta_degC"], cols["torque_Nm"])
    ok = rejected == 0
    r = model.inverse(cal, _accepted(ok, cols["slip_rpm"]), _accepted(ok, cols["theta_degC"]),
                      _accepted(ok, cols["torque_Nm"]))
    # rejected: wc_inverse_rejected, force 0 -> the spring's preload pressure -> its current, clamped
    preload_Pa = (0.0 + cal.return_spring_force) / cal.piston_area
    preload_mA = preload_Pa / cal.vfs_gain
    clamped = (preload_mA < cal.vfs_current_min) or (preload_mA > cal.vfs_current_max)
    preload_mA = min(max(preload_mA, cal.vfs_current_min), cal.vfs_current_max)
    status = np.where(ok, r["status"], rejected | (model.STATUS_CURRENT_CLAMPED if clamped else 0)).astype(int)
    return {"force_N": np.where(ok, r["force_N"], 0.0),
            "pressure_kPa": np.where(ok, r["pressure_Pa"], preload_Pa) * 1e-3,
            "current_mA": np.where(ok, r["current_mA"], preload_mA), "status": status}


def thermal(cal: Calibration, cols: dict, lines=None) -> dict:
    """lines: the input line of each row, for the messages (default: row k on line k + 2)."""
    t = cols["t_s"]
    if t.size > 1:
        steps = np.diff(t)
        bad = np.flatnonzero(~(np.abs(steps - cal.period) <= 1e-6 * cal.period + 1e-9))   # NaN fails too
        if bad.size:
            line = lines[bad[0] + 1] if lines is not None else bad[0] + 3
            raise CsvError(f"line {line}: column t_s: step {steps[bad[0]]:.9g} s, expected one control"
                           f" period ({cal.period:g} s) per row")
    status = thermal_status(cols["slip_rpm"], cols["torque_Nm"], cols["theta_oil_degC"], cols["theta_housing_degC"])
    if t.size == 0:
        return {"t_s": t, "theta_degC": np.zeros(0), "status": status}
    # the observer starts at the first row's oil temperature; one the firmware rejects: theta1, as wc_clutch_init
    oil0 = float(cols["theta_oil_degC"][0])
    start = oil0 if _within(as_float32(oil0), model.THETA_MIN_DEGC, model.THETA_MAX_DEGC) else cal.theta1
    theta = model.thermal_observer(cal, cols["slip_rpm"], cols["torque_Nm"], cols["theta_oil_degC"],
                                   cols["theta_housing_degC"], theta_start_degC=start, held=status != 0)
    return {"t_s": t, "theta_degC": theta, "status": status}


MODES = {"torque": torque, "inverse": inverse, "thermal": thermal}
