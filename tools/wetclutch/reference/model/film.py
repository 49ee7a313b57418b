"""The steady film (eq. 9-16): contact pressure p_c(h), average film thickness h_bar(h), their inverses and
slope, the film domain, and FilmTable (the dense tabulated form for many samples)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import erf, erfc

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


def contact_pressure_Pa(cal: Calibration, separation_m):
    """p_c(h), eq. 15 (Greenwood-Williamson with eq. 11-14)."""
    h = np.asarray(separation_m, dtype=float)
    s = cal.roughness_rms
    x = h / (math.sqrt(2.0) * s)
    k = math.sqrt(math.pi / 2.0) * cal.youngs_modulus * cal.roughness_parameter
    return k * (np.exp(-x * x) - (h / s) * math.sqrt(math.pi / 2.0) * erfc(x))


def film_thickness_m(cal: Calibration, separation_m):
    """h_bar(h), eq. 9 (Patir-Cheng average film thickness)."""
    h = np.asarray(separation_m, dtype=float)
    s = cal.roughness_rms
    x = h / (math.sqrt(2.0) * s)
    return h / 2.0 * (1.0 + erf(x)) + s / math.sqrt(2.0 * math.pi) * np.exp(-x * x)


def film_slope_m_per_Pa(cal: Calibration, separation_m):
    """d h_bar / d p_c = (d h_bar/dh) / (d p_c/dh), exact, from eq. 9 and 15.

    d h_bar/dh = (1 + erf x)/2 and d p_c/dh = -(pi/2) E N beta erfc x.
    """
    h = np.asarray(separation_m, dtype=float)
    x = h / (math.sqrt(2.0) * cal.roughness_rms)
    enb = cal.youngs_modulus * cal.asperity_density * cal.asperity_tip_radius
    return -(1.0 + erf(x)) / (math.pi * enb * erfc(x))


_SCALAR_CACHE_SIZE = 4096


def separation_from_pressure_m(cal: Calibration, pressure_Pa):
    """Inverse of eq. 15 by vectorized bisection (p_c is strictly decreasing in h).

    A single pressure's answer is remembered per calibration (a Calibration is immutable, the
    bisection a pure function of p): the step-by-step references ask for the same few pressures
    (the film at zero force, at F_max, at the knee) every step."""
    p = np.asarray(pressure_Pa, dtype=float)
    if p.size == 1:
        cache = cal.__dict__.setdefault("_separation_of_pressure", {})
        key = float(p.reshape(-1)[0])
        if key not in cache:
            if len(cache) >= _SCALAR_CACHE_SIZE:
                cache.clear()
            cache[key] = float(_separation_bisection(cal, np.array([key]))[0])
        return np.full(p.shape, cache[key])
    return _separation_bisection(cal, p)


def _separation_bisection(cal: Calibration, p: np.ndarray):
    s = cal.roughness_rms
    lo = np.full(p.shape, -60.0 * s)
    hi = np.full(p.shape, 60.0 * s)
    for _ in range(64):  # 120 sigma / 2^64 < 1e-22 m: exact in double
        mid = 0.5 * (lo + hi)
        above = contact_pressure_Pa(cal, mid) > p
        lo_next = np.where(above, mid, lo)
        hi_next = np.where(above, hi, mid)
        if np.array_equal(lo_next, lo) and np.array_equal(hi_next, hi):
            break   # a fixed point: the remaining iterations change nothing
        lo, hi = lo_next, hi_next
    return 0.5 * (lo + hi)


def film_domain(cal: Calibration):
    """(separation_min_m, separation_max_m, pressure_min_Pa, pressure_max_Pa) of the modelled film.

    Outside it the film is clamped (eq. 16 steady state): below pressure_min
    (an open clutch) h_bar = h_bar(separation_max); above pressure_max the table end.
    """
    cached = cal.__dict__.get("_film_domain")   # a Calibration is immutable: computed once per object
    if cached is not None:
        return cached
    h_max = cal.separation_max_sigma * cal.roughness_rms
    p_max = cal.contact_pressure_max
    h_min = float(separation_from_pressure_m(cal, np.array([p_max]))[0])
    p_min = float(contact_pressure_Pa(cal, h_max))
    object.__setattr__(cal, "_film_domain", (h_min, h_max, p_min, p_max))
    return h_min, h_max, p_min, p_max


def hbar_from_pressure_m(cal: Calibration, pressure_Pa):
    """h_bar(p_c) exactly (eq. 9 at the h solving eq. 15), clamped to the film domain."""
    _, _, p_min, p_max = film_domain(cal)
    p = np.clip(np.asarray(pressure_Pa, dtype=float), p_min, p_max)
    return film_thickness_m(cal, separation_from_pressure_m(cal, p))


class FilmTable:
    """The fast form of separation_from_pressure_m and hbar_from_pressure_m for many samples.

    A dense table of the exact closed forms (eq. 9 and 15) at `nodes` separations uniform from the
    film domain's h_max down to h_min (so p_c increases along it), read by linear interpolation in p_c;
    the pressure is clamped to the film domain as in hbar_from_pressure_m. No per-sample bisection.
    Used by the bench simulator (20001 nodes) and the identification (4001 nodes); checked against
    the exact form in tests/python/test_model_film.py.
    """

    def __init__(self, cal: Calibration, nodes: int):
        h_min, h_max, self.pressure_min_Pa, self.pressure_max_Pa = film_domain(cal)
        self.separation_m = np.linspace(h_max, h_min, nodes)
        self.pressure_Pa = contact_pressure_Pa(cal, self.separation_m)      # increasing
        self.hbar_m = film_thickness_m(cal, self.separation_m)

    def _clamped(self, pressure_Pa):
        return np.clip(np.asarray(pressure_Pa, dtype=float), self.pressure_min_Pa, self.pressure_max_Pa)

    def separation_from_pressure_m(self, pressure_Pa):
        """Steady-state nominal separation h(p_c) (eq. 15 inverted), clamped to the film domain."""
        return np.interp(self._clamped(pressure_Pa), self.pressure_Pa, self.separation_m)

    def hbar_from_pressure_m(self, pressure_Pa):
        """h_bar(p_c) (eq. 9 at the h solving eq. 15), clamped to the film domain."""
        return np.interp(self._clamped(pressure_Pa), self.pressure_Pa, self.hbar_m)
