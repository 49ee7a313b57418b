"""Step thermal: k1, k2 (and C on request) by the multiple linear regression of eq. 19.

Every signal is convolved with the same smooth kernel g (a modulating
function, signals._kernel_filter), and theta', theta'' with g', g'': by parts
(g * x') = (g' * x) exactly, so eq. 19 holds exactly for the filtered signals;
smoothing adds no bias, it only removes noise. (Savitzky-Golay derivatives are
not the derivatives of the SG smoothing, which biased the lag by 7 %.)
The thermistor is a first-order lag, tau theta_m' + theta_m = theta, so the
surface temperature is theta_m + tau theta_m'; substituted in eq. 19 this adds
the regressors theta_m' and theta_m'', and tau is fitted with k1 and k2 (or
fixed with --thermistor-lag).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..calibration import Calibration
from .campaign import stack
from .settings import IdentifyError, Settings
from .statistics import check_identifiable, confidence, r2_rmse


@dataclass
class _Eq19:
    """The filtered regressors of eq. 19 with the thermistor lag tau:
    P = k1 (x1 + tau e1) + k2 (x2 + tau e2) + C (d1 + tau d2)."""
    P: np.ndarray       # heat input T dw (W)
    d1: np.ndarray      # theta_m'
    d2: np.ndarray      # theta_m''
    x1: np.ndarray      # theta_m - theta_oil
    x2: np.ndarray      # theta_m - theta_housing
    e1: np.ndarray      # lag term of x1
    e2: np.ndarray      # lag term of x2


def _regressors(d: dict[str, np.ndarray], s: Settings) -> _Eq19:
    P, th, d1, d2 = d["power_W"], d["theta_m_degC"], d["dtheta_K_s"], d["d2theta_K_s2"]
    x1, x2 = th - d["theta_oil_degC"], th - d["theta_housing_degC"]
    # lag terms of the temperature differences: theta_s - theta_oil_s = x1 + tau (d1 - d_oil), ...
    if s.lag_all_thermistors:
        e1, e2 = d1 - d["dtheta_oil_K_s"], d1 - d["dtheta_housing_K_s"]
    else:
        e1, e2 = d1, d1
    return _Eq19(P, d1, d2, x1, x2, e1, e2)


def _linear_start(q: _Eq19, c_known: float, fit_c: bool):
    """The unconstrained linear regression and the start values (k1, k2, tau, C) it gives."""
    # Unconstrained linear form: P = c1 th' + c2 th'' + k1 (th_m - th_oil) + k2 (th_m - th_h), with
    # c1 = C + (k1 + k2) tau and c2 = C tau (first-order thermistor, theta = theta_m + tau theta_m').
    A = np.column_stack([q.x1, q.x2, q.d1, q.d2])
    y = q.P if fit_c else q.P - c_known * q.d1
    check_identifiable("thermal (eq. 19)", A, ["k1", "k2", "theta'", "theta''"])
    lin, *_ = np.linalg.lstsq(A, y, rcond=None)
    k1_0, k2_0 = lin[0], lin[1]
    if fit_c:
        ksum = k1_0 + k2_0
        disc = lin[2] ** 2 - 4.0 * ksum * lin[3]
        c0 = 0.5 * (lin[2] + math.sqrt(max(disc, 0.0)))
        tau0 = max(lin[3] / c0, 0.0) if c0 > 0 else 0.0
    else:
        c0 = c_known
        tau0 = max(lin[3] / c_known, 0.0)
    return lin, (k1_0, k2_0, tau0, c0)


def _fit_lag(q: _Eq19, start, c_known: float, fit_c: bool, fixed_tau: float | None):
    """Eq. 19 with the lag, nonlinear least squares from the linear start.
    Returns (k1, k2, tau, C), the least_squares result and the labels of its parameters."""
    k1_0, k2_0, tau0, c0 = start

    def unpack(x):
        k1, k2 = x[0], x[1]
        tau = fixed_tau if fixed_tau is not None else x[2]
        c = x[-1] if fit_c else c_known
        return k1, k2, tau, c

    def fun(x):
        k1, k2, tau, c = unpack(x)
        return k1 * (q.x1 + tau * q.e1) + k2 * (q.x2 + tau * q.e2) + c * (q.d1 + tau * q.d2) - q.P

    def jac(x):
        k1, k2, tau, c = unpack(x)
        cols = [q.x1 + tau * q.e1, q.x2 + tau * q.e2]
        if fixed_tau is None:
            cols.append(k1 * q.e1 + k2 * q.e2 + c * q.d2)
        if fit_c:
            cols.append(q.d1 + tau * q.d2)
        return np.column_stack(cols)

    x0 = [k1_0, k2_0] + ([tau0] if fixed_tau is None else []) + ([c0] if fit_c else [])
    labels = ["k1", "k2"] + (["tau"] if fixed_tau is None else []) + (["C"] if fit_c else [])
    res = least_squares(fun, x0, jac=jac, x_scale="jac", method="lm")
    return unpack(res.x), res, labels


def identify_thermal(prepared: list[dict], cal: Calibration, s: Settings) -> dict:
    if not prepared:
        raise IdentifyError("thermal: no thermal runs")
    d = stack(prepared, "regression")
    n = d["t_s"].size
    if n < 50:
        raise IdentifyError(f"thermal: {n} usable samples after filtering: the runs are too short"
                            f" (the eq. 19 filter window is {s.smooth_thermal_s} s)")
    q = _regressors(d, s)
    if np.ptp(q.P) < 1.0:
        raise IdentifyError("thermal: the heat input |T dw| does not vary: eq. 19 needs slip-speed steps")
    c_known = cal.heat_capacity
    fit_c = s.fit_heat_capacity
    groups = d["experiment"] * 100000 + d["segment"]
    lin, start = _linear_start(q, c_known, fit_c)
    fixed_tau = s.thermistor_lag_s
    (k1, k2, tau, c), res, labels = _fit_lag(q, start, c_known, fit_c, fixed_tau)
    check_identifiable("thermal (eq. 19)", res.jac, labels)
    ci, rho, _, ci_method = confidence(res.jac, res.fun, groups)
    ci_map = dict(zip(labels, ci))
    lhs = q.P - c * (q.d1 + tau * q.d2)
    rhs = k1 * (q.x1 + tau * q.e1) + k2 * (q.x2 + tau * q.e2)
    r2, rmse = r2_rmse(lhs, rhs)

    # Output-error check: eq. 1 simulated (exact ZOH) with the measured heat input and oil/housing
    # temperatures, then the thermistor lag, against the measured thermistor temperature.
    sim = [simulate_thermistor(p["series"], k1, k2, c, tau) for p in prepared]
    errors = np.concatenate([m - x for _, m, x in sim])
    # what ignoring the thermistor lag would give (the bias the lag correction removes)
    naive, *_ = np.linalg.lstsq(np.column_stack([q.x1, q.x2]), q.P - c * q.d1, rcond=None)
    values = {"oil_conductance": k1, "housing_conductance": k2}
    out = {
        "values": values,
        "ci95": {"oil_conductance": ci_map["k1"], "housing_conductance": ci_map["k2"]},
        "thermistor_lag_s": tau, "thermistor_lag_ci95": ci_map.get("tau", 0.0),
        "thermistor_lag_source": "fixed (--thermistor-lag)" if fixed_tau is not None else "fitted with k1, k2",
        "heat_capacity_J_K": c, "heat_capacity_ci95": ci_map.get("C", 0.0),
        "heat_capacity_source": "fitted (--fit-heat-capacity)" if fit_c else "calibration (thermal section)",
        "linear_unconstrained": {"k1": float(lin[0]), "k2": float(lin[1]), "c1": float(lin[2]), "c2": float(lin[3])},
        "without_lag_correction": {"oil_conductance": float(naive[0]), "housing_conductance": float(naive[1])},
        "r2_eq19": r2, "rmse_eq19_W": rmse, "residual_rho": rho, "filter_half_width_s": s.smooth_thermal_s,
        "ci_method": ci_method,
        "samples": int(n), "runs": len(prepared),
        "theta_oil_housing_spread_K": float(np.std(d["theta_oil_degC"] - d["theta_housing_degC"])),
        "sim_rmse_K": float(np.sqrt(np.mean(errors ** 2))) if errors.size else float("nan"),
        "sim": sim, "lhs": lhs, "rhs": rhs,
    }
    if fit_c:
        # the calibration holds C through masses and specific heats: scale both specific heats
        factor = c / cal.heat_capacity
        out["values"]["separator_specific_heat"] = cal.separator_specific_heat * factor
        out["values"]["lining_specific_heat"] = cal.lining_specific_heat * factor
        out["source_notes"] = {n: f"scaled by {factor:.5f} so that C = {c:.5g} J/K as identified with k1, k2"
                               for n in ("separator_specific_heat", "lining_specific_heat")}
    return out


def simulate_thermistor(series: dict, k1: float, k2: float, c: float, tau: float):
    """Eq. 1 (exact ZOH) and a first-order thermistor; returns (t, measured, simulated thermistor)."""
    t, P = series["t_s"], series["power_W"]
    oil, hou, meas = series["theta_oil_degC"], series["theta_housing_degC"], series["theta_m_degC"]
    ok = np.isfinite(P) & np.isfinite(oil) & np.isfinite(hou) & np.isfinite(meas)
    if ok.sum() < 3:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    t, P, oil, hou, meas = t[ok], P[ok], oil[ok], hou[ok], meas[ok]
    dt = np.diff(t, append=t[-1] + (t[-1] - t[-2]))
    a = np.exp(-(k1 + k2) * dt / c)
    b = np.exp(-dt / tau) if tau > 1e-6 else np.zeros_like(dt)
    steady = (P + k1 * oil + k2 * hou) / (k1 + k2)
    n = t.size
    # start: sensor at the measured value, surface = sensor (record starts from rest or after a NaN gap)
    th = float(np.mean(meas[:5]))
    sensor = th
    out = np.empty(n)
    for k in range(n):
        out[k] = sensor
        th_next = steady[k] + (th - steady[k]) * a[k]
        sensor = 0.5 * (th + th_next) + (sensor - 0.5 * (th + th_next)) * b[k]
        th = th_next
    return t, meas, out
