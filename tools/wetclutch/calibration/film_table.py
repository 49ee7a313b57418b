"""The h_bar(p_c) table a calibration gives the firmware (``wetclutch lut`` writes it; ``load`` checks it).

The table: nodes uniform in the nominal separation h, from h(p_c_max) (h < 0:
asperities compressed past the mean plane) to separation_max; stored as
(p_c, h_bar, d h_bar/d p_c) per node with p_c strictly increasing, so the
firmware interpolates with a cubic Hermite that uses the exact slope.
Why Hermite: with the exact slope the error falls as (spacing)^4, so 64
nodes (768 B) reach < 1e-4 relative where linear interpolation in p_c
would need about 2000 nodes (24 KiB with the same three arrays).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..reference import model
from .parameters import FILM_MAX_NODES, Calibration
from .rules import film_problem


FLOAT_BYTES = 4
ARRAYS_PER_NODE = 3  # pressure, h_bar, slope
DENSITY = 100        # error is measured on a grid 100x denser than the table


@dataclass(frozen=True)
class FilmTable:
    pressure_Pa: np.ndarray
    hbar_m: np.ndarray
    slope_m_per_Pa: np.ndarray

    @property
    def size_bytes(self) -> int:
        return self.pressure_Pa.size * ARRAYS_PER_NODE * FLOAT_BYTES


class TableError(Exception):
    pass


def build_table(cal: Calibration) -> FilmTable:
    """The table of cal (its film_lut and contact sections), checked by the firmware's film rules."""
    nodes = cal.nodes
    if not (math.isfinite(nodes) and nodes == int(nodes) and 2 <= nodes <= FILM_MAX_NODES):   # before allocating
        raise TableError(f"{cal.path}: parameter 'film_lut.nodes': {nodes!r} must be a whole number in"
                         f" [2, {FILM_MAX_NODES}] (WC_FILM_MAX_NODES)")
    with np.errstate(all="ignore"):   # an unusable calibration gives non-finite values, rejected below
        h_min, h_max, _, _ = model.film_domain(cal)
        h = np.linspace(h_max, h_min, int(nodes))  # decreasing h = increasing p_c
        table = FilmTable(
            pressure_Pa=model.contact_pressure_Pa(cal, h),
            hbar_m=model.film_thickness_m(cal, h),
            slope_m_per_Pa=model.film_slope_m_per_Pa(cal, h),
        )
    check_table(table, cal)
    return table


def check_table(table: FilmTable, cal: Calibration | None = None) -> None:
    """The firmware's film rules (calibration.film_problem) on the table as stored (float32), the axis
    also strictly increasing before rounding; with cal, the table must reach the contact pressure at
    the maximum current."""
    where = f"{cal.path}: film table from the contact and film_lut sections" if cal is not None else "film table"
    with np.errstate(all="ignore"):
        axis = np.asarray(table.pressure_Pa, dtype=float)
        if axis.size >= 2 and not np.all(np.diff(axis) > 0):
            raise TableError(f"{where}: pressure axis is not strictly increasing (float64)")
    problem = film_problem(table.pressure_Pa, table.hbar_m, table.slope_m_per_Pa, cal)
    if problem is not None:
        raise TableError(f"{where}: {problem}")


def interpolate(table: FilmTable, pressure_Pa) -> np.ndarray:
    """Clamped cubic Hermite interpolation, the same scheme the firmware uses."""
    p = np.clip(np.asarray(pressure_Pa, dtype=float), table.pressure_Pa[0], table.pressure_Pa[-1])
    i = np.clip(np.searchsorted(table.pressure_Pa, p, side="right") - 1, 0, table.pressure_Pa.size - 2)
    p0, p1 = table.pressure_Pa[i], table.pressure_Pa[i + 1]
    width = p1 - p0
    t = (p - p0) / width
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * table.hbar_m[i] + (t3 - 2 * t2 + t) * width * table.slope_m_per_Pa[i]
            + (-2 * t3 + 3 * t2) * table.hbar_m[i + 1] + (t3 - t2) * width * table.slope_m_per_Pa[i + 1])


def max_relative_error(cal: Calibration, table: FilmTable) -> float:
    """Max |interpolated/exact - 1| on a grid DENSITY times denser than the table."""
    with np.errstate(all="ignore"):
        return _max_relative_error(cal, table)


def _max_relative_error(cal: Calibration, table: FilmTable) -> float:
    p = table.pressure_Pa
    fractions = np.arange(DENSITY) / DENSITY
    grid = np.concatenate([(p[:-1, None] + fractions[None, :] * np.diff(p)[:, None]).ravel(), p[-1:]])
    exact = model.hbar_from_pressure_m(cal, grid)
    # Measure the table as stored: every entry rounded to float32.
    stored = FilmTable(*(a.astype(np.float32).astype(float) for a in
                         (table.pressure_Pa, table.hbar_m, table.slope_m_per_Pa)))
    return float(np.max(np.abs(interpolate(stored, grid) / exact - 1.0)))
