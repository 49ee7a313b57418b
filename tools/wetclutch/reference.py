"""The ``reference`` subcommand: the model of model.py on CSV columns.

Column names and units match the firmware's host program ``wc_eval`` so the
two can be compared file against file.
"""
from __future__ import annotations

import numpy as np

from . import model
from .calibration import Calibration
from .csvio import CsvError

INPUTS = {
    "torque": ("slip_rpm", "theta_degC", "force_N"),
    "inverse": ("slip_rpm", "theta_degC", "torque_Nm"),
    "thermal": ("t_s", "slip_rpm", "torque_Nm", "theta_oil_degC", "theta_housing_degC"),
}


def torque(cal: Calibration, cols: dict) -> dict:
    r = model.torque_parts(cal, cols["slip_rpm"], cols["theta_degC"], cols["force_N"])
    return {"torque_Nm": r["torque_Nm"], "coulomb_Nm": r["coulomb_Nm"], "viscous_Nm": r["viscous_Nm"],
            "hbar_um": r["hbar_m"] * 1e6, "mu_f": r["mu_f"]}


def inverse(cal: Calibration, cols: dict) -> dict:
    if np.any(cols["torque_Nm"] < 0):
        row = int(np.argmax(cols["torque_Nm"] < 0)) + 2
        raise CsvError(f"line {row}: column torque_Nm: a torque request is a magnitude, must be >= 0")
    r = model.inverse(cal, cols["slip_rpm"], cols["theta_degC"], cols["torque_Nm"])
    return {"force_N": r["force_N"], "pressure_kPa": r["pressure_Pa"] * 1e-3,
            "current_mA": r["current_mA"], "status": r["status"].astype(int)}


def thermal(cal: Calibration, cols: dict) -> dict:
    t = cols["t_s"]
    if t.size > 1:
        steps = np.diff(t)
        bad = np.flatnonzero(np.abs(steps - cal.period) > 1e-6 * cal.period + 1e-9)
        if bad.size:
            raise CsvError(f"line {bad[0] + 3}: column t_s: step {steps[bad[0]]:.9g} s, expected one control"
                           f" period ({cal.period:g} s) per row")
    theta = model.thermal_observer(cal, cols["slip_rpm"], cols["torque_Nm"], cols["theta_oil_degC"],
                                   cols["theta_housing_degC"])
    return {"t_s": t, "theta_degC": theta}


MODES = {"torque": torque, "inverse": inverse, "thermal": thermal}
