"""h_bar(p_c) table and the firmware headers (``wetclutch lut``).

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
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import model
from .util.atomic import Staged
from .calibration import FILM_MAX_NODES, PARAMETERS, Calibration, film_problem

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


# ---------------------------------------------------------------------------
# Header emission. Values go out as the shortest decimal that round-trips the
# float32 the firmware stores: exact, readable, and the same on every machine.

def c_float(x: float) -> str:
    v = np.float32(x)
    if v == 0 or 1e-4 <= abs(v) < 1e7:
        text = np.format_float_positional(v, unique=True, trim="0")
    else:
        text = np.format_float_scientific(v, unique=True, trim="0")
    return text + "f"


_C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def c_identifier(name: str) -> str:
    """The calibration's C name, lower case (wc_<name>_calibration, WC_<NAME>_FILM_NODES): name must be a
    C identifier in ASCII (letters, digits, '_', not starting with a digit); nothing is mapped."""
    if not _C_IDENTIFIER.fullmatch(name):
        raise TableError(f"calibration name {name!r} is not a C identifier (ASCII letters, digits and '_', not"
                         " starting with a digit): pass --name, or rename the calibration file")
    return name.lower()


def check_max_error(value: float) -> float:
    """The --max-error bound: a finite number > 0 (NaN would disable the check)."""
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            and value > 0):
        raise TableError(f"--max-error {value!r}: must be a finite number > 0")
    return float(value)


def banner(command: str) -> str:
    return f"/* generated by `{command}`, do not edit */\n"


def _array(name: str, values: np.ndarray, unit: str) -> str:
    rows = []
    for start in range(0, values.size, 4):
        rows.append("    " + ", ".join(c_float(v) for v in values[start:start + 4]) + ",")
    return f"/* {unit} */\nstatic const float {name}[{values.size}] = {{\n" + "\n".join(rows) + "\n};\n"


def film_header(cal: Calibration, table: FilmTable, ident: str, command: str, error: float) -> str:
    up = ident.upper()
    h_min, h_max, p_min, p_max = model.film_domain(cal)
    return (
        banner(command)
        + f"/* h_bar(p_c) for calibration '{ident}': eq. 9 at the h solving eq. 15 (steady film, eq. 16).\n"
        f" * {table.pressure_Pa.size} nodes uniform in h from {h_min * 1e6:.4f} um to {h_max * 1e6:.4f} um,\n"
        f" * p_c from {p_min:.6g} Pa to {p_max:.6g} Pa; {table.size_bytes} bytes.\n"
        f" * Cubic Hermite with the exact slope: max relative error {error:.3e} (grid {DENSITY}x denser). */\n"
        f"#ifndef WC_LUT_{up}_FILM_H\n#define WC_LUT_{up}_FILM_H\n\n"
        f"#define WC_{up}_FILM_NODES {table.pressure_Pa.size}u\n\n"
        + _array(f"wc_{ident}_film_pressure_Pa", table.pressure_Pa, "contact pressure p_c, Pa, strictly increasing")
        + "\n" + _array(f"wc_{ident}_film_hbar_m", table.hbar_m, "average film thickness h_bar, m")
        + "\n" + _array(f"wc_{ident}_film_slope_m_per_Pa", table.slope_m_per_Pa, "d h_bar / d p_c, m/Pa")
        + f"\n#endif /* WC_LUT_{up}_FILM_H */\n"
    )


def calibration_header(cal: Calibration, ident: str, command: str) -> str:
    up = ident.upper()
    lines = []
    for section, name, unit, constraint, field in PARAMETERS:
        if field is None:
            continue
        value = str(int(cal.values[name])) + "u" if constraint == "count" else c_float(cal.values[name])
        lines.append(f"    .{field} = {value}, /* {unit}; {cal.sources[name]} */")
    lines.append(f"    .heat_capacity_J_per_K = {c_float(cal.heat_capacity)}, /* J/K; eq. 1: N_c((m c_p)_lining"
                 " + (m c_p)_separator) from the thermal section */")
    lines.append(f"    .film = {{ wc_{ident}_film_pressure_Pa, wc_{ident}_film_hbar_m,"
                 f" wc_{ident}_film_slope_m_per_Pa, WC_{up}_FILM_NODES }},")
    return (
        banner(command)
        + f"/* Calibration '{ident}' from {Path(cal.path).name}. Include in one translation unit. */\n"
        f"#ifndef WC_LUT_{up}_CALIBRATION_H\n#define WC_LUT_{up}_CALIBRATION_H\n\n"
        "#include <wetclutch/wc_calibration.h>\n"
        f"#include \"wc_{ident}_film.h\"\n\n"
        f"static const wc_calibration_t wc_{ident}_calibration = {{\n" + "\n".join(lines) + "\n};\n\n"
        f"#endif /* WC_LUT_{up}_CALIBRATION_H */\n"
    )


def generate(cal: Calibration, out_dir: Path, name: str, command: str) -> dict:
    """Write both headers atomically (all or nothing); returns the figures. Every check (name, counts,
    film rules) runs before anything is written."""
    ident = c_identifier(name)
    table = build_table(cal)
    error = max_relative_error(cal, table)
    files = {
        f"wc_{ident}_film.h": film_header(cal, table, ident, command, error),
        f"wc_{ident}_calibration.h": calibration_header(cal, ident, command),
    }
    out_dir.mkdir(parents=True, exist_ok=True)
    with Staged() as out:
        for fname, text in files.items():
            out.write_text(out_dir / fname, text)
    return {"nodes": table.pressure_Pa.size, "bytes": table.size_bytes, "max_rel_error": error,
            "files": [str(out_dir / f) for f in files]}
