"""The squeeze-film state (DESIGN 9): Reynolds' squeeze film between annular plates, the firmware's film
update (film_advance_m) and FilmDynamics (the same update vectorized over runs)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import erf, erfc

from .film import contact_pressure_Pa, film_domain, film_thickness_m, hbar_from_pressure_m
from .friction import viscosity_Pa_s

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


# --------------------------------------------------------------------------- engagement edges (DESIGN 9)

def reynolds_factor_m4(cal: Calibration) -> float:
    """K = Ro^4 - Ri^4 - (Ro^2 - Ri^2)^2 / ln(Ro/Ri): Reynolds' squeeze film between annular plates.
    Narrow annuli cancel: with s = (Ro - Ri)/(Ro + Ri) < 0.01 the series 8 m^4 s^3 (4/3 + 4/45 s^2 + 44/945 s^4)
    (m = (Ro + Ri)/2, from ln(Ro/Ri) = 2 atanh s), truncated at about 2e-14 relative there."""
    ro, ri = cal.outer_radius, cal.inner_radius
    s = (ro - ri) / (ro + ri)
    if s < 0.01:
        m = 0.5 * (ro + ri)
        return 8.0 * m**4 * s**3 * (4.0 / 3.0 + s * s * (4.0 / 45.0 + s * s * 44.0 / 945.0))
    return ro**4 - ri**4 - (ro**2 - ri**2) ** 2 / math.log(ro / ri)


def film_damping_N_s_m2(cal: Calibration, theta_degC, squeeze_factor: float | None = None):
    """D = 3 pi phi mu_v(theta) K / 2: F_h = D (-dh_bar/dt) / h_bar^3 (DESIGN 9)."""
    phi = cal.film_squeeze_factor if squeeze_factor is None else squeeze_factor
    return 1.5 * math.pi * phi * reynolds_factor_m4(cal) * viscosity_Pa_s(cal, theta_degC)


def separation_from_hbar_m(cal: Calibration, hbar_m):
    """Inverse of eq. 9 by vectorized bisection (h_bar strictly increases with h)."""
    hb = np.asarray(hbar_m, dtype=float)
    s = cal.roughness_rms
    if hb.ndim == 0:   # one film (the per-step reference): the same bisection in scalar arithmetic, 50x faster
        lo, hi = -60.0 * s, max(60.0 * s, 2.0 * float(hb))
        k = 1.0 / (math.sqrt(2.0) * s)
        c = s / math.sqrt(2.0 * math.pi)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            x = mid * k
            if 0.5 * mid * (1.0 + math.erf(x)) + c * math.exp(-x * x) < float(hb):
                lo = mid
            else:
                hi = mid
        return np.float64(0.5 * (lo + hi))
    lo = np.full(hb.shape, -60.0 * s)
    hi = np.full(hb.shape, np.maximum(60.0 * s, 2.0 * hb))
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        below = film_thickness_m(cal, mid) < hb
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def film_contact_pressure_Pa(cal: Calibration, hbar_m):
    """(p_c, dp_c/dh_bar) of the asperities at film h_bar (eq. 9, 15), on the film domain: 0 at or above the
    open-clutch film, the domain's last pressure at or below its thinnest film (wc_film_pressure_Pa)."""
    h_min, h_max, _, p_max = film_domain(cal)
    hb = np.asarray(hbar_m, dtype=float)
    h = np.clip(separation_from_hbar_m(cal, hb), h_min, h_max)
    x = h / (math.sqrt(2.0) * cal.roughness_rms)
    enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
    slope = -(math.pi / 2.0) * enb * erfc(x) / (0.5 * (1.0 + erf(x)))       # (dp_c/dh) / (dh_bar/dh)
    p = np.where(hb >= film_thickness_m(cal, h_max), 0.0, contact_pressure_Pa(cal, h))
    return p, slope


def film_advance_m(cal: Calibration, hbar_m: float, apply_force_N: float, theta_degC: float,
                   squeeze_factor: float | None = None, dt_s: float | None = None) -> float:
    """One control period of the squeeze film, the firmware's scheme (wc_film_advance_m) in double with the
    exact eq. 9/15 (no table) and the exact dp_c/dh_bar where the firmware takes its table's secant: in
    u = 1/h_bar^2, D du/dt = 2 (F_app - F_c), linearly implicit in F_c, never past the settled film."""
    dt = cal.period if dt_s is None else dt_s
    area = cal.friction_area
    settled = float(hbar_from_pressure_m(cal, apply_force_N / area))
    p, slope = film_contact_pressure_Pa(cal, hbar_m)
    squeeze = apply_force_N - area * float(p)
    damping = float(film_damping_N_s_m2(cal, theta_degC, squeeze_factor))
    u = 1.0 / hbar_m**2
    u_next = u + 2.0 * dt * squeeze / (damping - dt * area * float(slope) * hbar_m**3)
    u_settled = 1.0 / settled**2
    closing = u_settled > u
    if not (u_next < u_settled if closing else u_next > u_settled):
        return settled
    return 1.0 / math.sqrt(u_next) if (u_next > u if closing else u_next < u) else hbar_m


class FilmDynamics:
    """The squeeze-film state (DESIGN 9) of many runs at once, in double: the firmware's update
    (film_advance_m) vectorized over runs, with eq. 9/15 on a dense table in h (linear interpolation,
    `nodes` separations over the film domain) instead of the exact closed forms. For the identification
    and the plant-family study, where a run is thousands of steps and a fit hundreds of runs."""

    def __init__(self, cal: Calibration, nodes: int = 4001):
        h_min, h_max, _, _ = film_domain(cal)
        h = np.linspace(h_max, h_min, nodes)
        self.cal = cal
        self.hbar_m = film_thickness_m(cal, h)                 # decreasing along the table
        self.pressure_Pa = contact_pressure_Pa(cal, h)         # increasing
        x = h / (math.sqrt(2.0) * cal.roughness_rms)
        enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
        self.slope_Pa_per_m = -(math.pi / 2.0) * enb * erfc(x) / (0.5 * (1.0 + erf(x)))   # dp_c/dh_bar
        self.reynolds_m4 = reynolds_factor_m4(cal)

    def contact_pressure_Pa(self, hbar_m):
        """(p_c, dp_c/dh_bar) at film h_bar: 0 at or above the open film (wc_film_pressure_Pa)."""
        hb = np.asarray(hbar_m, dtype=float)
        p = np.interp(-hb, -self.hbar_m, self.pressure_Pa)
        slope = np.interp(-hb, -self.hbar_m, self.slope_Pa_per_m)
        return np.where(hb >= self.hbar_m[0], 0.0, p), slope

    def settled_m(self, force_N):
        """The steady film under an apply force (eq. 16), clamped to the table."""
        return np.interp(np.asarray(force_N, dtype=float) / self.cal.friction_area, self.pressure_Pa, self.hbar_m)

    def advance_m(self, hbar_m, force_N, damping_N_s_m2, dt_s):
        """film_advance_m for arrays (same scheme: linearly implicit in u = 1/h_bar^2, never past settled)."""
        area = self.cal.friction_area
        settled = self.settled_m(force_N)
        p, slope = self.contact_pressure_Pa(hbar_m)
        squeeze = force_N - area * p
        u = 1.0 / hbar_m**2
        with np.errstate(divide="ignore", invalid="ignore"):
            u_next = u + 2.0 * dt_s * squeeze / (damping_N_s_m2 - dt_s * area * slope * hbar_m**3)
        u_settled = 1.0 / settled**2
        closing = u_settled > u
        short = np.where(closing, u_next < u_settled, u_next > u_settled)
        forward = np.where(closing, u_next > u, u_next < u)
        with np.errstate(invalid="ignore"):
            moved = np.where(forward, 1.0 / np.sqrt(np.where(u_next > 0, u_next, 1.0)), hbar_m)
        return np.where(short, moved, settled)

    def run(self, force_N, theta_degC, squeeze_factor: float, dt_s: float | None = None, substeps: int = 1):
        """Film h_bar and asperity force F_c per row (steps x runs), each row the state the torque of that
        step uses (before its update, as wc_clutch_step); starts settled under the first row's force.
        squeeze_factor 0: the steady film (eq. 16). substeps > 1 divides each period (the continuous law)."""
        force = np.atleast_2d(np.asarray(force_N, dtype=float).T).T
        theta = np.broadcast_to(np.atleast_2d(np.asarray(theta_degC, dtype=float).T).T, force.shape)
        if squeeze_factor <= 0.0:
            hbar = self.settled_m(force)
            return hbar, force.copy()
        dt = (self.cal.period if dt_s is None else dt_s) / substeps
        damping = 1.5 * math.pi * squeeze_factor * self.reynolds_m4 * viscosity_Pa_s(self.cal, theta)
        out = np.empty(force.shape)
        h = self.settled_m(force[0])
        for k in range(force.shape[0]):
            out[k] = h
            for _ in range(substeps):
                h = self.advance_m(h, force[k], damping[k], dt)
        return out, self.cal.friction_area * self.contact_pressure_Pa(out)[0]
