"""The firmware's calibration rules (wc_calibration_check, src/model/wc_calibration.c) on the values it will
hold (float32): one value against its range, the relations between fields, and the film table's rules."""
from __future__ import annotations

import math

import numpy as np

from .parameters import (C_NAMES, FILM_MAX_NODES, FORCE_MAX_N, OFF_OR_MIN, RANGES, THETA_MAX_DEGC, THETA_MIN_DEGC,
                         Calibration, CalibrationError, _L, f32)


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
    if name in OFF_OR_MIN and checked != 0.0 and not checked >= f32(OFF_OR_MIN[name]):   # WC_FIELD_OR_ZERO
        raise CalibrationError(f"{where}: value {raw!r} must be 0 (off) or in"
                               f" {_range_text(OFF_OR_MIN[name], True, high)} {unit}")
    return value


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
