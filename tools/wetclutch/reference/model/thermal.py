"""The thermal model (eq. 1): exact zero-order-hold decay, steady state, the observer over a series."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .constants import RAD_S_PER_RPM

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


def thermal_decay(cal: Calibration, dt_s: float) -> float:
    """a = exp(-(k1 + k2) dt / C): the exact ZOH discretization of eq. 1."""
    return math.exp(-(cal.oil_conductance + cal.housing_conductance) * dt_s / cal.heat_capacity)


def thermal_steady_degC(cal: Calibration, power_W, theta_oil_degC, theta_housing_degC):
    """Steady-state temperature of eq. 1 for constant inputs."""
    k1, k2 = cal.oil_conductance, cal.housing_conductance
    return (np.asarray(power_W) + k1 * np.asarray(theta_oil_degC)
            + k2 * np.asarray(theta_housing_degC)) / (k1 + k2)


def thermal_observer(cal: Calibration, slip_rpm, torque_Nm, theta_oil_degC, theta_housing_degC,
                     theta_start_degC=None, held=None):
    """Eq. 1 over a series of control periods, exact for inputs held over each period.

    Row k's inputs are held from step k to k+1. Returns theta[k], the estimate
    before row k is applied; theta[0] is theta_start (default: first oil temperature).
    Heat input P = |T dw| (W). held: rows whose input is rejected (the firmware's
    wc_thermal_step leaves its state untouched there); default none.
    """
    slip = np.asarray(slip_rpm, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):   # only in held rows, whose result is not used
        power = np.abs(np.asarray(torque_Nm, dtype=float) * slip * RAD_S_PER_RPM)
        steady = thermal_steady_degC(cal, power, theta_oil_degC, theta_housing_degC)
    a = thermal_decay(cal, cal.period)
    out = np.empty(slip.shape)
    theta = float(np.asarray(theta_oil_degC, dtype=float).flat[0]) if theta_start_degC is None else theta_start_degC
    hold = np.zeros(slip.shape, bool) if held is None else np.asarray(held, bool)
    for k in range(slip.size):
        out[k] = theta
        if not hold[k]:
            theta = steady[k] + (theta - steady[k]) * a
    return out
