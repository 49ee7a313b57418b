"""Viscosity (eq. 2), friction coefficient (eq. 18), torque (eq. 3-8), static capacity and the force at the
maximum current."""
from __future__ import annotations

from typing import TYPE_CHECKING

import math

import numpy as np

from .constants import RAD_S_PER_RPM
from .film import hbar_from_pressure_m

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


def viscosity_Pa_s(cal: Calibration, theta_degC):
    """mu_v(theta), eq. 2."""
    th = np.asarray(theta_degC, dtype=float)
    return cal.mv1 * np.exp(cal.mv2 * th) + cal.mv3 * np.exp(cal.mv4 * th)


def viscosity_slope_Pa_s_per_K(cal: Calibration, theta_degC):
    """d mu_v / d theta, from eq. 2."""
    th = np.asarray(theta_degC, dtype=float)
    return cal.mv1 * cal.mv2 * np.exp(cal.mv2 * th) + cal.mv3 * cal.mv4 * np.exp(cal.mv4 * th)


def friction_coefficient(cal: Calibration, speed_m_s, theta_degC):
    """mu_f(v, theta), eq. 18 (Stribeck exponential x linear temperature)."""
    v = np.abs(np.asarray(speed_m_s, dtype=float))
    th = np.asarray(theta_degC, dtype=float)
    stribeck = cal.mu1 + (cal.mu2 - cal.mu1) * np.exp(-v / cal.stribeck_speed)
    return stribeck * (1.0 + cal.mu3 * (th - cal.theta1) / cal.theta2)


def torque_at_film_Nm(cal: Calibration, slip_rpm, theta_degC, contact_force_N, hbar_m):
    """Eq. 5-8 for a contact force and the film it stands on, signed with the slip (arrays)."""
    return torque_parts(cal, slip_rpm, theta_degC, contact_force_N, hbar_m=hbar_m)["torque_Nm"]


def static_capacity_Nm(cal: Calibration, theta_degC, contact_force_N):
    """Static capacity: static factor mu_f(0, theta) R_eff N_c F_c (DESIGN 9; eq. 18 at v = 0)."""
    return (cal.static_friction_factor * friction_coefficient(cal, 0.0, theta_degC)
            * cal.effective_radius * cal.friction_pairs * np.asarray(contact_force_N, dtype=float))


SPRING_PRELOAD_FRACTION = 0.8   # DESIGN 15: the return spring's force at the retracted piston, of F_s (wc_clutch.c)


def retracted_fraction(cal: Calibration, pressure_Pa: float) -> float:
    """How far the modelled piston stands off the pack (DESIGN 15; wc_clutch_step): its return spring's force
    rises from the preload SPRING_PRELOAD_FRACTION F_s at the retracted end to F_s at the pack (the kiss point),
    so with P A_p between the two the piston stands in between, retracted by (F_s - P A_p) / ((1 - preload) F_s)
    in [0, 1]; 0 from P A_p >= F_s on, 1 at or below the preload (and for a NaN pressure); without a spring
    (F_s 0) 1 without pressure, else 0."""
    piston_N = pressure_Pa * cal.piston_area
    band_N = (1.0 - SPRING_PRELOAD_FRACTION) * cal.return_spring_force
    if not band_N > 0.0:                      # no spring (F_s 0): no band
        return 0.0 if piston_N > 0.0 else 1.0
    r = (cal.return_spring_force - piston_N) / band_N
    return 1.0 if math.isnan(r) else min(max(r, 0.0), 1.0)


def open_gap_m(cal: Calibration, hbar_m, slip_rpm, retracted: float = 1.0):
    """The viscous gap of an element whose piston stands off the pack by the fraction ``retracted`` (DESIGN 15;
    wc_clutch_step): the film plus that fraction of the retracted piston's clearance per gap, times that
    fraction of the open pack's aeration, (h_bar + r open_clearance) (1 + r (slip / w_a)^2), w_a =
    open_aeration_speed (0: no aeration factor). Both 0, or r = 0: h_bar itself."""
    gap = np.asarray(hbar_m, dtype=float) + retracted * cal.open_clearance
    if cal.open_aeration_speed > 0.0:
        gap = gap * (1.0 + retracted * (np.asarray(slip_rpm, dtype=float) * RAD_S_PER_RPM
                                        / cal.open_aeration_speed) ** 2)
    return gap


def band_fraction(cal: Calibration, viscous_Nm: float, viscous_Nm_m: float, hbar_m: float, slip_rpm: float) -> float:
    """The release into the spring's band (DESIGN 15; wc_step_input_t.band_release): the retracted fraction r
    in [0, 1] whose open gap makes the viscous drag viscous_Nm, viscous_Nm_m / open_gap_m(r) = viscous_Nm
    (viscous_Nm_m: the viscous torque times its gap at this slip and temperature). The gap rises with r, so
    bisection on it (60 halvings: below a double's resolution); 0 where the film alone drags less than wanted,
    1 where the whole gap drags more, and for a wanted drag at or below 0."""
    if not viscous_Nm > 0.0:
        return 1.0
    wanted_gap = viscous_Nm_m / viscous_Nm
    if float(open_gap_m(cal, hbar_m, slip_rpm, 1.0)) <= wanted_gap:
        return 1.0
    if float(open_gap_m(cal, hbar_m, slip_rpm, 0.0)) >= wanted_gap:
        return 0.0
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(open_gap_m(cal, hbar_m, slip_rpm, mid)) < wanted_gap else (lo, mid)
    return 0.5 * (lo + hi)


def band_pressure_Pa(cal: Calibration, retracted: float) -> float:
    """The piston pressure that stands the piston off the pack by ``retracted`` (retracted_fraction's inverse)."""
    return cal.return_spring_force * (1.0 - retracted * (1.0 - SPRING_PRELOAD_FRACTION)) / cal.piston_area


def torque_parts(cal: Calibration, slip_rpm, theta_degC, force_N, hbar_m=None, friction_factor: float = 1.0,
                 open_element: float = 0.0):
    """Eq. 3-8: dict of total/coulomb/viscous torque (Nm), h_bar (m), mu_f.

    hbar_m: the film the contact force stands on; default the steady film of eq. 16 (the squeeze-film
    state of DESIGN 9 passes its own). friction_factor: the adaptation's scale of mu_f (DESIGN 12; the
    returned mu_f carries it). open_element: how far the piston stands off the pack (DESIGN 15,
    retracted_fraction; True: all the way): the viscous term shears open_gap_m instead of the film (the
    returned h_bar stays the film's).

    Torques carry the sign of the slip speed (slip >= 0 counts as positive):
    the torque transmitted through the slipping clutch, which acts against
    the slip on the faster member. At zero slip the Coulomb part is the
    static capacity mu_f(0, theta) F_c R_eff N_c and the viscous part is 0.
    """
    slip = np.asarray(slip_rpm, dtype=float)
    force = np.asarray(force_N, dtype=float)
    theta = np.asarray(theta_degC, dtype=float)
    sign = np.where(slip < 0.0, -1.0, 1.0)
    speed = cal.effective_radius * np.abs(slip) * RAD_S_PER_RPM          # eq. 4
    mu_f = friction_coefficient(cal, speed, theta) * friction_factor     # eq. 18 (x the learned scale)
    hbar = (hbar_from_pressure_m(cal, force / cal.friction_area)          # eq. 9, 15, 16
            if hbar_m is None else np.asarray(hbar_m, dtype=float))
    rn = cal.effective_radius * cal.friction_pairs
    coulomb = rn * mu_f * force                                          # eq. 6
    gap = open_gap_m(cal, hbar, slip, float(open_element)) if open_element else hbar   # DESIGN 15: open drag
    viscous = rn * viscosity_Pa_s(cal, theta) * cal.friction_area * speed / gap   # eq. 7
    return {
        "torque_Nm": sign * (coulomb + viscous),                         # eq. 5, 8
        "coulomb_Nm": sign * coulomb,
        "viscous_Nm": sign * viscous,
        "hbar_m": hbar,
        "mu_f": mu_f,
    }


def force_max_N(cal: Calibration) -> float:
    """Contact force at the solenoid's maximum current: K i_max A_p - F_s."""
    return max(cal.vfs_gain * cal.vfs_current_max * cal.piston_area - cal.return_spring_force, 0.0)
