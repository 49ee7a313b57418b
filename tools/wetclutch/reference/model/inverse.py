"""The inverse: torque request -> contact force -> piston pressure -> VFS current, slipping (eq. 5-8 solved
exactly) and locked (the holding force)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .constants import RAD_S_PER_RPM, STATUS_BELOW_DRAG, STATUS_CURRENT_CLAMPED, STATUS_SATURATED
from .film import contact_pressure_Pa, film_domain, film_thickness_m, hbar_from_pressure_m, separation_from_pressure_m
from .friction import force_max_N, friction_coefficient, static_capacity_Nm, viscosity_Pa_s

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


def inverse(cal: Calibration, slip_rpm, theta_degC, torque_Nm, friction_factor: float = 1.0,
            kiss_offset_N: float = 0.0):
    """Torque request (magnitude, Nm) -> contact force -> piston pressure -> VFS current.

    friction_factor, kiss_offset_N: the adaptation's correction (model/correction.py): mu_f times the factor,
    the contact force F commanded as the pressure of the apply force F + kiss_offset_N, never below 0 (DESIGN 2,
    12: the return spring holds the pack open; a negative offset below -F is not commanded).

    Returns a dict: force_N, pressure_Pa, current_mA, status (bits above).
    Solves |T(F)| = request exactly. Where the film is clamped (p_c below the
    table's first node) T is linear in F and is solved directly; elsewhere the
    unknown is the nominal separation h, with F = A_f p_c(h) and h_bar(h) in
    closed form (eq. 9, 15), by vectorized bisection in double precision.
    """
    slip = np.abs(np.asarray(slip_rpm, dtype=float))
    theta = np.asarray(theta_degC, dtype=float)
    req = np.asarray(torque_Nm, dtype=float)
    slip, theta, req = np.broadcast_arrays(slip, theta, req)
    f_max = force_max_N(cal)
    _, h_max, p_min, _ = film_domain(cal)

    speed = cal.effective_radius * slip * RAD_S_PER_RPM
    arm = cal.effective_radius * cal.friction_pairs
    coulomb_per_N = arm * friction_coefficient(cal, speed, theta) * friction_factor   # eq. 6, 18 (DESIGN 12)
    viscous_m = arm * viscosity_Pa_s(cal, theta) * cal.friction_area * speed   # eq. 7 times h_bar

    def torque_at(force):
        return coulomb_per_N * force + viscous_m / hbar_from_pressure_m(cal, force / cal.friction_area)

    drag = torque_at(np.zeros(req.shape))
    cap = torque_at(np.full(req.shape, f_max))
    # Clamped-film region, 0 <= F <= A_f p_min: T = c F + V / h_bar(h_max).
    f_knee = min(cal.friction_area * p_min, f_max)
    hbar_open = float(film_thickness_m(cal, h_max))
    force_linear = (req - viscous_m / hbar_open) / coulomb_per_N
    # Beyond it: bisection on h, T(h) strictly decreasing in h.
    lo = np.full(req.shape, float(separation_from_pressure_m(cal, np.array([f_max / cal.friction_area]))[0]))
    hi = np.full(req.shape, h_max)
    for _ in range(100):  # 40 um / 2^100: exact in double
        mid = 0.5 * (lo + hi)
        t_mid = coulomb_per_N * cal.friction_area * contact_pressure_Pa(cal, mid) + viscous_m / film_thickness_m(cal, mid)
        high = t_mid > req
        lo_next = np.where(high, mid, lo)
        hi_next = np.where(high, hi, mid)
        if np.array_equal(lo_next, lo) and np.array_equal(hi_next, hi):
            break   # a fixed point (lo, hi adjacent or equal doubles): the remaining iterations change nothing
        lo, hi = lo_next, hi_next
    force_curve = cal.friction_area * contact_pressure_Pa(cal, 0.5 * (lo + hi))
    force = np.where(req <= torque_at(np.full(req.shape, f_knee)), force_linear, force_curve)

    status = np.zeros(req.shape, dtype=int)
    below = req <= drag
    above = req > cap
    force = np.where(below, 0.0, np.where(above, f_max, force))
    status |= np.where(below, STATUS_BELOW_DRAG, 0)
    status |= np.where(above, STATUS_SATURATED, 0)
    pressure = kiss_pressure_Pa(cal, force, kiss_offset_N)
    current = pressure / cal.vfs_gain                                 # P = K i
    clamped = (current < cal.vfs_current_min) | (current > cal.vfs_current_max)
    current = np.clip(current, cal.vfs_current_min, cal.vfs_current_max)
    status |= np.where(clamped, STATUS_CURRENT_CLAMPED, 0)
    return {"force_N": force, "pressure_Pa": pressure, "current_mA": current, "status": status}


def kiss_pressure_Pa(cal: Calibration, force_N, kiss_offset_N: float = 0.0):
    """The piston pressure of a contact force (wc_clutch.c kiss_pressure_Pa): F_app = P A_p - F_s; DESIGN 12: the
    kiss offset moves the spring's preload; the pressure at least 0."""
    return np.maximum(force_N + cal.return_spring_force + kiss_offset_N, 0.0) / cal.piston_area


def holding_inverse(cal: Calibration, theta_degC: float, torque_Nm: float, friction_factor: float = 1.0,
                    kiss_offset_N: float = 0.0) -> dict:
    """The inverse for a locked clutch (DESIGN 9): the force whose static capacity holds the request with the
    holding margin, at most the force at the maximum current (STATUS_SATURATED). friction_factor,
    kiss_offset_N: the adaptation's correction, as in inverse()."""
    per_N = float(static_capacity_Nm(cal, theta_degC, 1.0)) * friction_factor
    force = torque_Nm * (1.0 + cal.holding_margin) / per_N
    if not force <= force_max_N(cal):   # the maximum current itself (wc_inverse_holding)
        if kiss_offset_N == 0.0:
            return {"force_N": force_max_N(cal), "pressure_Pa": cal.vfs_gain * cal.vfs_current_max,
                    "current_mA": cal.vfs_current_max, "status": STATUS_SATURATED}
        force, status = force_max_N(cal), STATUS_SATURATED   # F_max commanded with the kiss offset too
    else:
        status = 0
    pressure = (max(force + kiss_offset_N, 0.0) + cal.return_spring_force) / cal.piston_area
    current = pressure / cal.vfs_gain
    if current < cal.vfs_current_min or current > cal.vfs_current_max:
        status |= STATUS_CURRENT_CLAMPED
    return {"force_N": force, "pressure_Pa": pressure, "current_mA": min(max(current, cal.vfs_current_min),
                                                                           cal.vfs_current_max), "status": status}
