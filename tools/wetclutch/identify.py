"""Identification from bench data (``wetclutch identify``): the paper's sections 3.2-3.4.

Input: a data directory as ``wetclutch bench`` writes it: per campaign an index
CSV (columns ``id`` and ``file``, optionally ``force_N``, ``slip_rpm``,
``loading_s``, ``theta0_degC``, ...) beside one measurement CSV per experiment
(``t_s, slip_rpm, force_N, torque_Nm, theta_clutch_degC, theta_oil_degC,
theta_housing_degC[, torque_request_Nm]``), and ``viscosity.csv``
(``theta_degC, viscosity_Pa_s``). The index may be in the directory itself or
in its sub-directories (``table2/``, ``thermal/``); a campaign whose directory
or index name says ``thermal`` holds the thermal runs, ``engagement`` runs are
not used, every other campaign is a friction campaign (Table 2).

Steps, each usable alone; ``all`` runs them in the order
thermal -> viscosity -> asperity -> mu, each using what the previous found:

thermal    k1, k2 (and C on request) by the multiple linear regression of
           eq. 19. Every signal is convolved with the same smooth kernel g
           (a modulating function), and theta', theta'' with g', g'': by parts
           (g * x') = (g' * x) exactly, so eq. 19 holds exactly for the filtered
           signals; smoothing adds no bias, it only removes noise. (Savitzky-
           Golay derivatives are not the derivatives of the SG smoothing, which
           biased the lag by 7 %.)
           The thermistor is a first-order lag, tau theta_m' + theta_m = theta,
           so the surface temperature is theta_m + tau theta_m'; substituted in
           eq. 19 this adds the regressors theta_m' and theta_m'', and tau is
           fitted with k1 and k2 (or fixed with --thermistor-lag).
viscosity  eq. 2 fitted to the (theta, mu_v) points, relative (log) residuals.
asperity   N from the viscous drag: in the flat part of eq. 18 (v >> v_s)
           T / (R N_c) = mu1 F + mu1 mu3 F (theta - theta1)/theta2
                         + mu_v(theta) A_f v / h_bar(F)
           is linear in mu1, mu1 mu3 and 1/h_bar per force level, so one linear
           regression over all runs gives h_bar at each applied force (the slope
           of torque against mu_v v). Eq. 9 and 15 then give N for each level
           in closed form, and N is fitted to the h_bar(F) points by weighted
           least squares. Without a known lag (asperity alone), tau is the
           value that minimises the regression's residual.
mu         eq. 17 samples (viscous part removed with mu_v at the lag-corrected
           temperature and h_bar at the measured force), eq. 18 fitted by
           scipy.optimize.least_squares; mu2 and v_s corrected for the slip
           noise (errors in variables) by SIMEX. The slip is a 0.1 s moving
           average (the stuck test needs it: the encoder noise alone would
           let stuck samples through).

Samples a step cannot use are excluded by rule and every exclusion is counted
and named (experiment, reason, time range) in the report: non-finite values,
the edges of records and NaN stretches (the temperature derivative is
undefined there), slip below a threshold (the clutch is stopped or stuck and
the measured torque is static friction, which eq. 17 does not describe), no
contact force, and the squeeze-film transient after every load change.
"""
from __future__ import annotations

import csv
import json
import math
import os
import re
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares, minimize_scalar
from scipy.signal import fftconvolve, savgol_filter
from scipy.stats import t as student_t

from . import lut, model
from .calibration import PARAMETERS, Calibration, CalibrationError, load as load_calibration

RAD_S_PER_RPM = model.RAD_S_PER_RPM
STEPS = ("thermal", "viscosity", "asperity", "mu")
PAPER = {"r2": 0.9858, "rmse": 0.002102}       # Shin & Choi, section 3.3
TARGETS = {"rel_error": 0.03, "r2": 0.985, "runtime_s": 60.0}

MEASUREMENT_COLUMNS = ("t_s", "slip_rpm", "force_N", "torque_Nm", "theta_clutch_degC", "theta_oil_degC",
                       "theta_housing_degC")
OPTIONAL_COLUMNS = ("torque_request_Nm",)
QUANTITY_UNIT = {  # column -> (quantity prefix, unit), to recognise a column in other units
    "t_s": ("t", "s"), "slip_rpm": ("slip", "rpm"), "force_N": ("force", "N"), "torque_Nm": ("torque", "Nm"),
    "theta_clutch_degC": ("theta_clutch", "degC"), "theta_oil_degC": ("theta_oil", "degC"),
    "theta_housing_degC": ("theta_housing", "degC"), "torque_request_Nm": ("torque_request", "Nm"),
    "theta_degC": ("theta", "degC"), "viscosity_Pa_s": ("viscosity", "Pa_s"),
}
VISCOSITY_COLUMNS = ("theta_degC", "viscosity_Pa_s")
VISCOSITY_FILE = "viscosity.csv"

SYMBOLS = {  # calibration name -> the paper's symbol
    "oil_conductance": "k1", "housing_conductance": "k2", "mv1": "mu_v1", "mv2": "mu_v2", "mv3": "mu_v3",
    "mv4": "mu_v4", "asperity_density": "N", "mu1": "mu1", "mu2": "mu2", "mu3": "mu3", "stribeck_speed": "v_s",
    "separator_specific_heat": "c_p,separator", "lining_specific_heat": "c_p,lining",
}
TARGET_PARAMETERS = ("mu1", "mu2", "mu3", "stribeck_speed", "oil_conductance", "housing_conductance")
WHAT = {
    "thermal": "the thermal runs, eq. 19 multiple linear regression",
    "viscosity": "viscosity.csv, eq. 2 least squares",
    "asperity": "the viscous drag of the friction runs (flat-mu region, eq. 8, 9, 15)",
    "mu": "the friction runs, eq. 17 samples fitted with eq. 18",
}


class IdentifyError(RuntimeError):
    """Data that cannot be identified from; the message says which file, line or column and why.
    (A RuntimeError, so the command line prints it without a traceback and exits 2.)"""


@dataclass(frozen=True)
class Settings:
    slip_min_rpm: float = 1.0        # |slip| (smoothed) below: stopped or stuck (static friction), not eq. 17
    smooth_slip_s: float = 0.1       # moving average of the slip (encoder noise) for v and the stuck test
    force_min_N: float = 50.0        # below: no contact
    film_settle_s: float = 0.5       # 5x the squeeze-film time constant (0.05-0.1 s, DESIGN 7)
    force_rate_N_s: float = 500.0    # |dF/dt| above this (50 ms average) is a load change
    bin_s: float = 0.01              # friction samples are averaged over bins of this length
    smooth_friction_s: float = 0.5   # Savitzky-Golay window for theta' in the friction runs
    smooth_thermal_s: float = 1.0    # half-width of the eq. 19 modulating function (kernel filter)
    thermal_step_s: float = 0.02     # the thermal regression's sample spacing after filtering
    flat_speed_m_s: float = 0.16     # asperity step: mu_f flat above max(this, 6 v_s) (paper: 20 rpm)
    thermistor_lag_s: float | None = None   # fixed lag instead of fitting it
    lag_all_thermistors: bool = True        # oil and housing thermistors lag like the clutch one
    simex: bool = True               # mu: correct mu2, v_s for the slip noise (errors in variables)
    fit_heat_capacity: bool = False
    jobs: int = 2


# ---------------------------------------------------------------------------
# Exclusions

REASONS = {
    "missing_file": "measurement file listed in the index does not exist",
    "nan": "non-finite value (NaN stretch) in a needed column",
    "edge": "within half a smoothing window of a record edge or NaN stretch (temperature derivative undefined)",
    "short": "segment shorter than the smoothing window",
    "static": "slip below the threshold: clutch stopped or stuck, the torque is static friction (eq. 17 does not apply)",
    "no_contact": "load-cell force below the contact threshold",
    "film": "squeeze-film transient after a load change or at the record start (eq. 16 steady film not reached)",
    "viscosity_row": "viscosity.csv row with a non-finite or non-positive value",
}


@dataclass
class Exclusion:
    step: str
    experiment: str
    reason: str
    t_from_s: float
    t_to_s: float
    samples: int
    seconds: float = 0.0

    def row(self) -> dict:
        return {"step": self.step, "experiment": self.experiment, "reason": self.reason,
                "t_from_s": round(self.t_from_s, 4), "t_to_s": round(self.t_to_s, 4), "samples": self.samples,
                "seconds": round(self.seconds, 4)}


def _runs(mask: np.ndarray):
    """(start, stop) index pairs of the True runs of a boolean array."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def _exclusions_from_codes(step: str, exp_id: str, t: np.ndarray, codes: np.ndarray, names: list[str], dt: float):
    """One Exclusion per contiguous run of the same non-zero code."""
    out = []
    if codes.size == 0:
        return out
    change = np.flatnonzero(np.diff(codes)) + 1
    starts = np.concatenate([[0], change])
    stops = np.concatenate([change, [codes.size]])
    tt = np.where(np.isfinite(t), t, np.nan)
    for a, b in zip(starts, stops):
        c = int(codes[a])
        if c == 0:
            continue
        seg = tt[a:b]
        finite = seg[np.isfinite(seg)]
        lo = float(finite[0]) if finite.size else float("nan")
        hi = float(finite[-1]) if finite.size else float("nan")
        out.append(Exclusion(step, exp_id, names[c], lo, hi, int(b - a), float((b - a) * dt)))
    return out


# ---------------------------------------------------------------------------
# Reading

def _header_problems(header: list[str], required, source: str) -> None:
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise IdentifyError(f"{source}: line 1: duplicate column(s) {', '.join(dup)}")
    problems = []
    known = set(QUANTITY_UNIT)
    for c in required:
        if c in header:
            continue
        quantity, unit = QUANTITY_UNIT[c]
        other = [h for h in header if h not in known and h.startswith(quantity + "_")]
        if other:
            problems.append(f"column '{other[0]}' is in {other[0][len(quantity) + 1:]} where '{c}' ({unit}) is"
                            f" expected: convert the column to {unit} and name it {c}")
        else:
            problems.append(f"missing column '{c}'")
    if problems:
        raise IdentifyError(f"{source}: line 1: " + "; ".join(problems) + f" (expected columns: {','.join(required)})")


def _read_header(path: Path) -> list[str]:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            first = f.readline()
    except OSError as e:
        raise IdentifyError(f"{path}: cannot read: {e.strerror}") from None
    except UnicodeDecodeError:
        raise IdentifyError(f"{path}: not UTF-8 text: not a CSV file") from None
    if not first.strip():
        raise IdentifyError(f"{path}: empty file, expected a CSV header")
    return [h.strip() for h in next(csv.reader([first]))]


def _parse_slow(path: Path, header: list[str], columns) -> np.ndarray:
    """Row by row, for files numpy refuses: names line and column of the bad cell; empty cell = NaN."""
    index = [header.index(c) for c in columns]
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        for line_no, row in enumerate(reader, start=2):
            if not row or all(not cell.strip() for cell in row):
                continue
            if len(row) != len(header):
                raise IdentifyError(f"{path}: line {line_no}: {len(row)} fields, the header has {len(header)}")
            values = []
            for c, i in zip(columns, index):
                cell = row[i].strip()
                if cell == "" or cell.lower() in ("nan", "na", "null"):
                    values.append(math.nan)
                    continue
                try:
                    values.append(float(cell))
                except ValueError:
                    raise IdentifyError(f"{path}: line {line_no}: column {c}: {row[i]!r} is not a number") from None
            rows.append(values)
    return np.array(rows, dtype=float).reshape(-1, len(columns))


def read_table(path: Path, required, optional=()) -> dict[str, np.ndarray]:
    header = _read_header(path)
    _header_problems(header, required, str(path))
    columns = list(required) + [c for c in optional if c in header]
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[header.index(c) for c in columns],
                          dtype=float, ndmin=2, encoding="utf-8")
    except ValueError:
        data = _parse_slow(path, header, columns)
    if data.shape[0] == 0:
        raise IdentifyError(f"{path}: no data rows")
    return {c: data[:, k] for k, c in enumerate(columns)}


@dataclass
class Campaign:
    kind: str             # "friction", "thermal" or "engagement"
    index: Path
    rows: list[dict]      # index rows: id, file (Path), and the other columns


def _is_index(path: Path) -> bool:
    try:
        header = _read_header(path)
    except IdentifyError:
        return False
    return "id" in header and "file" in header


def _kind(index: Path) -> str:
    name = (index.parent.name + "/" + index.name).lower()
    if "thermal" in name:
        return "thermal"
    if "engagement" in name:
        return "engagement"
    return "friction"


def _read_index(index: Path) -> Campaign:
    with open(index, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        rows = []
        for line_no, row in enumerate(reader, start=2):
            if not row or all(not (v or "").strip() for v in row.values()):
                continue
            ident, fname = (row.get("id") or "").strip(), (row.get("file") or "").strip()
            if not ident or not fname:
                raise IdentifyError(f"{index}: line {line_no}: empty id or file")
            entry = {"id": ident, "file": index.parent / fname, "line": line_no}
            for k, v in row.items():
                if k in ("id", "file") or k is None:
                    continue
                try:
                    entry[k.strip()] = float(v)
                except (TypeError, ValueError):
                    entry[k.strip()] = v
            rows.append(entry)
    ids = [r["id"] for r in rows]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise IdentifyError(f"{index}: duplicate experiment id(s) {', '.join(dup[:5])}")
    if not rows:
        raise IdentifyError(f"{index}: the index lists no experiments")
    return Campaign(_kind(index), index, rows)


def _is_measurement(path: Path) -> bool:
    try:
        header = _read_header(path)
    except IdentifyError:
        return False
    return "t_s" in header and ("slip_rpm" in header or any(h.startswith("slip_") for h in header))


def find_campaigns(data_dir: Path, notes: list[str] | None = None) -> list[Campaign]:
    """Index CSVs in data_dir and its sub-directories; thermal runs may come without an index
    (every measurement CSV of a directory, or with a file name, that says 'thermal')."""
    data_dir = Path(data_dir)
    if not data_dir.is_dir():
        raise IdentifyError(f"{data_dir}: no such data directory")
    notes = [] if notes is None else notes
    campaigns = []
    for folder in [data_dir] + sorted(p for p in data_dir.iterdir() if p.is_dir() and not p.name.startswith(".")):
        csvs = sorted(p for p in folder.glob("*.csv") if p.name != VISCOSITY_FILE)
        indexes = [p for p in csvs if _is_index(p)]
        listed = set()
        for p in indexes:
            c = _read_index(p)
            campaigns.append(c)
            listed |= {Path(r["file"]).resolve() for r in c.rows}
        loose = [p for p in csvs if p not in indexes and p.resolve() not in listed and _is_measurement(p)]
        thermal = [p for p in loose if "thermal" in (folder.name + "/" + p.name).lower()]
        if thermal:
            rows = [{"id": p.stem, "file": p, "line": 0} for p in thermal]
            campaigns.append(Campaign("thermal", folder, rows))
        for p in loose:
            if p in thermal:
                continue
            why = "engagement run" if "engagement" in p.name.lower() else "measurement file in no index"
            notes.append(f"{p}: {why}, not used")
    if not campaigns:
        raise IdentifyError(f"{data_dir}: no index CSV (a CSV with columns 'id' and 'file' listing the experiments)"
                            " and no thermal runs in the directory or its sub-directories")
    return campaigns


def find_viscosity(data_dir: Path) -> Path:
    data_dir = Path(data_dir)
    for p in [data_dir / VISCOSITY_FILE] + sorted(data_dir.glob(f"*/{VISCOSITY_FILE}")):
        if p.is_file():
            return p
    raise IdentifyError(f"{data_dir}: no {VISCOSITY_FILE} (columns theta_degC, viscosity_Pa_s)"
                        " in the directory or its sub-directories")


# ---------------------------------------------------------------------------
# Per-experiment preparation (runs in worker processes)

def _odd_window(seconds: float, dt: float, polyorder: int) -> int:
    n = max(int(round(seconds / dt)), polyorder + 2)
    return n + 1 if n % 2 == 0 else n


def _prepare(job: tuple) -> dict:
    """Read one measurement CSV and reduce it to what the steps use. Returns plain arrays."""
    exp_id, path, purpose, cal_dims, s = job
    effective_radius, friction_area = cal_dims
    path = Path(path)
    cols = read_table(path, MEASUREMENT_COLUMNS, OPTIONAL_COLUMNS)
    t = cols["t_s"]
    finite_t = np.isfinite(t)
    if finite_t.sum() < 3:
        raise IdentifyError(f"{path}: fewer than 3 rows with a finite time t_s")
    tf = t[finite_t]
    steps = np.diff(tf)
    if np.any(steps <= 0):
        bad = int(np.flatnonzero(finite_t)[np.flatnonzero(steps <= 0)[0] + 1]) + 2
        raise IdentifyError(f"{path}: line {bad}: t_s does not increase")
    dt = float(np.median(steps))
    if np.mean(np.abs(steps - dt) > 0.1 * dt) > 0.01:
        raise IdentifyError(f"{path}: t_s is not uniformly sampled (median step {dt:g} s): resample the record")
    # NaN in t: fill by the sample clock so the rest of the row can be named by time
    if not finite_t.all():
        k = np.arange(t.size)
        t = np.interp(k, k[finite_t], tf)
    needed = [cols[c] for c in MEASUREMENT_COLUMNS[1:]]
    valid = finite_t & np.all(np.isfinite(np.vstack(needed)), axis=0)
    out = {"id": exp_id, "file": str(path), "dt": dt, "rows": int(t.size), "t0": float(t[0]), "t1": float(t[-1])}

    if purpose == "friction":
        out.update(_prepare_friction(exp_id, t, cols, valid, dt, effective_radius, s))
    else:
        out.update(_prepare_thermal(exp_id, t, cols, valid, dt, s))
    return out


def _segment_smooth(x: np.ndarray, valid: np.ndarray, window: int, polyorder: int, derivs, dt: float):
    """Savitzky-Golay per valid segment; returns (arrays per deriv, interior mask, short mask)."""
    outs = [np.full(x.shape, np.nan) for _ in derivs]
    interior = np.zeros(x.shape, bool)
    short = np.zeros(x.shape, bool)
    half = window // 2
    for a, b in _runs(valid):
        if b - a < window + 2:
            short[a:b] = True
            continue
        for o, d in zip(outs, derivs):
            o[a:b] = savgol_filter(x[a:b], window, polyorder, deriv=d, delta=dt, mode="interp")
        interior[a + half:b - half] = True
    return outs, interior, short


def _moving_average(x: np.ndarray, valid: np.ndarray, n: int) -> np.ndarray:
    """Centred moving average over n samples of the valid ones (NaN where none is valid); n odd keeps it
    centred (np.convolve 'same' with an even n is off by half a sample)."""
    if n <= 1:
        return np.where(valid, x, np.nan)
    w = np.ones(n)
    cnt = np.convolve(valid.astype(float), w, "same")
    tot = np.convolve(np.where(valid, x, 0.0), w, "same")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(valid & (cnt > 0), tot / cnt, np.nan)


def _kernel_filter(x: np.ndarray, valid: np.ndarray, half_s: float, dt: float, derivs):
    """Modulating-function filter: x convolved with g(s) = (1 - (s/H)^2)^3 on [-H, H] (unit area), and with
    g' and g'' for the first and second derivatives. g and g' vanish at +-H, so by parts
    (g * x') = (g' * x) and (g * x'') = (g'' * x) exactly: a linear ODE such as eq. 1 holds exactly for
    the filtered signals, and the derivatives of noisy data come without differencing.
    Returns (arrays per deriv, interior mask, short mask); per valid segment, H trimmed at both ends."""
    m = max(int(round(half_s / dt)), 2)
    s = np.arange(-m, m + 1) * dt
    u = s / (m * dt)
    g0 = (1.0 - u * u) ** 3
    area = g0.sum() * dt
    kernels = {0: g0 / area,
               1: -6.0 * u * (1.0 - u * u) ** 2 / (m * dt) / area,
               2: (-6.0 * (1.0 - u * u) ** 2 + 24.0 * u * u * (1.0 - u * u)) / (m * dt) ** 2 / area}
    outs = [np.full(x.shape, np.nan) for _ in derivs]
    interior = np.zeros(x.shape, bool)
    short = np.zeros(x.shape, bool)
    for a, b in _runs(valid):
        if b - a < 2 * m + 3:
            short[a:b] = True
            continue
        for o, d in zip(outs, derivs):
            # a true convolution (the kernel flipped): sum_j x[k - j] K[j] dt = integral g(s) x(t - s) ds
            o[a + m:b - m] = fftconvolve(x[a:b], kernels[d] * dt, mode="valid")
        interior[a + m:b - m] = True
    return outs, interior, short


def _load_changes(force: np.ndarray, dt: float, s: Settings) -> np.ndarray:
    """Samples inside a load change or within film_settle_s after one. The record start and the end of
    a gap in the force are treated as load changes too (the film state is unknown there)."""
    n = force.size
    ok = np.isfinite(force)
    w = 2 * int(round(0.05 / dt / 2.0)) + 1
    avg = _moving_average(force, ok, w)
    rate = np.zeros(n)
    for a, b in _runs(ok):
        if b - a > 1:
            rate[a:b] = np.abs(np.gradient(avg[a:b], dt))
    changing = rate > s.force_rate_N_s
    changing[[a for a, _ in _runs(ok)]] = True
    settle = int(round(s.film_settle_s / dt))
    # extend every changing sample forward by the settle time
    idx = np.flatnonzero(changing)
    mark = np.zeros(n + 1, int)
    np.add.at(mark, idx, 1)
    np.add.at(mark, np.minimum(idx + settle + 1, n), -1)
    return np.cumsum(mark[:n]) > 0


FRICTION_CODES = ["", "nan", "short", "edge", "static", "no_contact", "film"]


def _prepare_friction(exp_id, t, cols, valid, dt, effective_radius, s: Settings) -> dict:
    slip, force, torque, theta = cols["slip_rpm"], cols["force_N"], cols["torque_Nm"], cols["theta_clutch_degC"]
    window = _odd_window(s.smooth_friction_s, dt, 2)
    (theta_sm, dtheta), interior, short = _segment_smooth(theta, valid, window, 2, (0, 1), dt)
    sign = np.where(np.nansum(slip) < 0, -1.0, 1.0)     # the record's slip direction
    n_avg = 2 * int(round(s.smooth_slip_s / dt / 2.0)) + 1     # odd: an even window shifts by half a sample
    slip_avg = _moving_average(slip * sign, valid, n_avg)
    # stuck: the averaged slip below the threshold, widened by half the averaging window so that the
    # average is only used where it does not straddle the lock (a moving average is biased at the kink)
    stuck = ~(slip_avg >= s.slip_min_rpm)
    if n_avg > 1:
        stuck = np.convolve(stuck.astype(float), np.ones(2 * (n_avg // 2) + 1), "same") > 0
    film = _load_changes(force, dt, s)
    # one reason per sample, the first that applies: nan > short > static > no_contact > film > edge
    codes = np.zeros(t.size, np.int8)
    codes[valid & ~interior] = 3
    codes[film] = 6
    codes[force < s.force_min_N] = 5
    codes[stuck] = 4
    codes[short] = 2
    codes[~valid] = 1
    use = codes == 0
    # slip noise: robust sample-to-sample differences over the slipping samples (a smooth signal adds
    # only its slope to the differences, which the median removes)
    dif = np.diff(slip[use])[np.diff(np.flatnonzero(use)) == 1] if use.sum() > 2 else np.zeros(0)
    slip_noise = float(1.4826 * np.median(np.abs(dif - np.median(dif))) / math.sqrt(2.0)) if dif.size > 20 else math.nan
    k = np.floor((t - t[0]) / s.bin_s + 1e-6).astype(np.int64)
    k = k[use]
    # bins of consecutive usable samples: average; a bin never spans excluded samples
    breaks = np.concatenate([[True], (np.diff(k) != 0) | (np.diff(np.flatnonzero(use)) != 1)])
    group = np.cumsum(breaks) - 1
    count = np.bincount(group).astype(float)

    def mean(x):
        return np.bincount(group, weights=x[use]) / count if count.size else np.zeros(0)

    return {
        "bins": {
            "t_s": mean(t), "slip_rpm": mean(slip_avg), "force_N": mean(force),
            "torque_Nm": mean(torque * sign), "theta_m_degC": mean(theta), "dtheta_m_K_s": mean(dtheta),
            "count": count,
        },
        "exclusions": [e.row() for e in _exclusions_from_codes("friction", exp_id, t, codes, FRICTION_CODES, dt)],
        "used_samples": int(use.sum()),
        # the noise left on a bin's slip: a moving average of n_avg white samples, averaged over the bin
        "slip_noise_rpm": slip_noise,
        "slip_noise_bin_rpm": slip_noise * math.sqrt(float(np.sum(np.convolve(
            np.ones(n_avg) / n_avg, np.ones(max(int(round(s.bin_s / dt)), 1)) / max(int(round(s.bin_s / dt)), 1)) ** 2))),
    }


THERMAL_CODES = ["", "nan", "short", "edge"]


def _prepare_thermal(exp_id, t, cols, valid, dt, s: Settings) -> dict:
    # heat input T dw (W): the signed product is unbiased under speed and torque noise (|T dw| is not
    # where the slip is near zero); the sign convention of the record is taken from its mean
    product = cols["torque_Nm"] * cols["slip_rpm"] * RAD_S_PER_RPM
    power = product * (1.0 if np.nansum(product) >= 0 else -1.0)
    half = s.smooth_thermal_s
    (th_f, d1, d2), interior, short = _kernel_filter(cols["theta_clutch_degC"], valid, half, dt, (0, 1, 2))
    (p_f,), _, _ = _kernel_filter(power, valid, half, dt, (0,))
    (oil_f, oil_d1), _, _ = _kernel_filter(cols["theta_oil_degC"], valid, half, dt, (0, 1))
    (hou_f, hou_d1), _, _ = _kernel_filter(cols["theta_housing_degC"], valid, half, dt, (0, 1))
    codes = np.zeros(t.size, np.int8)
    codes[valid & ~interior] = 3
    codes[short] = 2
    codes[~valid] = 1
    stride = max(int(round(s.thermal_step_s / dt)), 1)
    use = np.flatnonzero(codes == 0)
    use = use[::stride]
    # raw series, averaged over stride-long blocks, for the output-error check (simulation of eq. 1)
    nb = t.size // stride
    blk = slice(0, nb * stride)

    def block(x):
        return x[blk].reshape(nb, stride).mean(axis=1)
    seg = np.concatenate([[0], np.cumsum(np.diff(use) > stride)]) if use.size else np.zeros(0, int)
    return {
        "regression": {"t_s": t[use], "power_W": p_f[use], "theta_m_degC": th_f[use], "dtheta_K_s": d1[use],
                       "d2theta_K_s2": d2[use], "theta_oil_degC": oil_f[use], "theta_housing_degC": hou_f[use],
                       "dtheta_oil_K_s": oil_d1[use], "dtheta_housing_K_s": hou_d1[use], "segment": seg},
        "series": {"t_s": block(t), "power_W": block(power), "theta_m_degC": block(cols["theta_clutch_degC"]),
                   "theta_oil_degC": block(cols["theta_oil_degC"]), "theta_housing_degC": block(cols["theta_housing_degC"])},
        "exclusions": [e.row() for e in _exclusions_from_codes("thermal", exp_id, t, codes, THERMAL_CODES, dt)],
        "used_samples": int((codes == 0).sum()),
    }


def prepare_campaign(campaign: Campaign, purpose: str, cal: Calibration, s: Settings,
                     log: list[Exclusion]) -> list[dict]:
    jobs = []
    for row in campaign.rows:
        if not Path(row["file"]).is_file():
            log.append(Exclusion("load", f"{row['id']} ({row['file']})", "missing_file", math.nan, math.nan, 0))
            continue
        jobs.append((row["id"], str(row["file"]), purpose, (cal.effective_radius, cal.friction_area), s))
    if not jobs:
        raise IdentifyError(f"{campaign.index}: none of the {len(campaign.rows)} listed measurement files exists")
    if s.jobs > 1 and len(jobs) > 1:
        with ProcessPoolExecutor(max_workers=s.jobs) as pool:
            prepared = list(pool.map(_prepare, jobs, chunksize=max(1, len(jobs) // (4 * s.jobs))))
    else:
        prepared = [_prepare(j) for j in jobs]
    meta = {r["id"]: r for r in campaign.rows}
    for p in prepared:
        p["meta"] = {k: v for k, v in meta[p["id"]].items() if k not in ("file", "line")}
        for e in p.pop("exclusions"):
            log.append(Exclusion(e["step"], e["experiment"], e["reason"], e["t_from_s"], e["t_to_s"], e["samples"],
                                 e["seconds"]))
    return prepared


# ---------------------------------------------------------------------------
# Statistics

def _ar1_factor(residual: np.ndarray, groups: np.ndarray | None = None) -> tuple[float, float]:
    """Lag-1 autocorrelation rho of the residuals (within groups) and the variance factor (1+rho)/(1-rho)."""
    r = residual
    same = np.ones(r.size - 1, bool) if groups is None else (np.diff(groups) == 0)
    num = float(np.sum((r[:-1] * r[1:])[same]))
    den = float(np.sum(r * r))
    rho = min(max(num / den if den > 0 else 0.0, 0.0), 0.999)
    return rho, (1.0 + rho) / (1.0 - rho)


def _confidence(jac: np.ndarray, residual: np.ndarray, groups=None, level: float = 0.95):
    """Half-widths of the confidence intervals from the Jacobian at the solution.

    With 10 or more groups (experiments): the cluster-robust (sandwich) covariance
    (J'J)^-1 (sum_g J_g' r_g r_g' J_g) (J'J)^-1 G/(G-1), which allows any correlation of the residuals
    within an experiment (lag-correction error, film state, sensor offsets), with a t quantile on G-1
    degrees of freedom. Otherwise the Gauss-Newton covariance s^2 (J'J)^-1 with s^2 inflated by
    (1+rho)/(1-rho) for the lag-1 autocorrelation rho of the residuals.
    Returns (half-widths, rho, covariance, method)."""
    n, p = jac.shape
    rho, factor = _ar1_factor(residual, groups)
    try:
        inv = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(p, np.inf), rho, np.full((p, p), np.inf), "singular"
    n_groups = 0 if groups is None else int(np.unique(groups).size)
    if n_groups >= 10:
        _, inv_idx = np.unique(groups, return_inverse=True)
        scores = np.zeros((n_groups, p))
        np.add.at(scores, inv_idx, jac * residual[:, None])
        cov = inv @ (scores.T @ scores) @ inv * n_groups / (n_groups - 1)
        q = float(student_t.ppf(0.5 + level / 2.0, n_groups - 1))
        method = f"cluster-robust over {n_groups} experiments"
    else:
        s2 = float(residual @ residual) / max(n - p, 1)
        cov = inv * s2 * factor
        n_eff = max(n / factor, p + 1.0)
        q = float(student_t.ppf(0.5 + level / 2.0, max(n_eff - p, 1.0)))
        method = f"Gauss-Newton, AR(1)-inflated (rho {rho:.3f})"
    return q * np.sqrt(np.abs(np.diag(cov))), rho, cov, method


def _r2_rmse(y: np.ndarray, fit: np.ndarray) -> tuple[float, float]:
    res = y - fit
    ss = float(np.sum((y - y.mean()) ** 2))
    return (1.0 - float(res @ res) / ss if ss > 0 else float("nan")), float(np.sqrt(np.mean(res * res)))


def _identifiable(name: str, jac: np.ndarray, labels) -> None:
    sv = np.linalg.svd(jac / np.maximum(np.linalg.norm(jac, axis=0), 1e-300), compute_uv=False)
    if sv[-1] < 1e-8 * sv[0]:
        raise IdentifyError(f"{name}: parameters {', '.join(labels)} are not identifiable from this data"
                            f" (the regressors are collinear, condition {sv[0] / max(sv[-1], 1e-300):.3g})")


# ---------------------------------------------------------------------------
# Film thickness as a function of force (eq. 9, 15, 16) for many samples

def hbar_of_force(cal: Calibration, force_N):
    """h_bar(F/A_f) by interpolation in a dense table of the exact closed forms (no per-sample bisection)."""
    h_min, h_max, p_min, p_max = model.film_domain(cal)
    h = np.linspace(h_max, h_min, 4001)
    p = model.contact_pressure_Pa(cal, h)
    hb = model.film_thickness_m(cal, h)
    return np.interp(np.clip(np.asarray(force_N, float) / cal.friction_area, p_min, p_max), p, hb)


def _viscosity_slope(cal: Calibration, theta):
    th = np.asarray(theta, float)
    return cal.mv1 * cal.mv2 * np.exp(cal.mv2 * th) + cal.mv3 * cal.mv4 * np.exp(cal.mv4 * th)


# ---------------------------------------------------------------------------
# Step: viscosity (eq. 2)

def identify_viscosity(path: Path, cal: Calibration, log: list[Exclusion]) -> dict:
    cols = read_table(Path(path), VISCOSITY_COLUMNS)
    th, mu = cols["theta_degC"], cols["viscosity_Pa_s"]
    bad = ~(np.isfinite(th) & np.isfinite(mu) & (mu > 0))
    for k in np.flatnonzero(bad):
        log.append(Exclusion("viscosity", f"{Path(path).name} line {k + 2}", "viscosity_row",
                             float(th[k]), float(th[k]), 1))
    th, mu = th[~bad], mu[~bad]
    if th.size < 6:
        raise IdentifyError(f"{path}: {th.size} usable (theta, viscosity) points; eq. 2 has 4 parameters,"
                            " at least 6 points over the temperature range are needed")
    if np.ptp(th) < 30.0:
        raise IdentifyError(f"{path}: the points span {np.ptp(th):.3g} K; eq. 2 (two exponentials) needs"
                            " at least 30 K")
    if np.median(mu) > 5.0:
        raise IdentifyError(f"{path}: median viscosity {np.median(mu):.4g}: column viscosity_Pa_s looks like"
                            " mPa*s, expected Pa*s")
    p0 = np.array([cal.mv1, cal.mv2, cal.mv3, cal.mv4])

    def fun(p):
        return np.log(p[0] * np.exp(p[1] * th) + p[2] * np.exp(p[3] * th)) - np.log(mu)

    best = None
    starts = [p0, np.array([p0[0] * 2, p0[1] * 1.5, p0[2] * 0.5, p0[3] * 0.7]),
              np.array([p0[0] * 0.5, p0[1] * 0.7, p0[2] * 2, p0[3] * 1.3])]
    for start in starts:
        r = least_squares(fun, start, bounds=([0, -1, 0, -1], [10, 0.1, 10, 0.1]), x_scale="jac",
                          xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=5000)
        if best is None or r.cost < best.cost:
            best = r
    p, jac = best.x.copy(), best.jac
    if p[1] > p[3]:   # the steeper exponential first, as in the paper's table
        p, jac = p[[2, 3, 0, 1]], jac[:, [2, 3, 0, 1]]
    fit = p[0] * np.exp(p[1] * th) + p[2] * np.exp(p[3] * th)
    r2, rmse = _r2_rmse(mu, fit)
    ci, _, _, ci_method = _confidence(jac, fun(p))
    return {
        "values": {"mv1": p[0], "mv2": p[1], "mv3": p[2], "mv4": p[3]},
        "ci95": {"mv1": ci[0], "mv2": ci[1], "mv3": ci[2], "mv4": ci[3]},
        "r2": r2, "rmse_Pa_s": rmse, "max_rel_error": float(np.max(np.abs(fit / mu - 1.0))), "ci_method": ci_method,
        "points": int(th.size), "theta_range_degC": [float(th.min()), float(th.max())],
        "data": {"theta_degC": th, "viscosity_Pa_s": mu},
        "source": str(path),
    }


# ---------------------------------------------------------------------------
# Step: thermal (eq. 19)

def _stack(prepared: list[dict], key: str) -> dict[str, np.ndarray]:
    names = prepared[0][key].keys()
    out = {n: np.concatenate([p[key][n] for p in prepared]) for n in names}
    out["experiment"] = np.concatenate([np.full(p[key]["t_s"].size, i) for i, p in enumerate(prepared)])
    return out


def identify_thermal(prepared: list[dict], cal: Calibration, s: Settings) -> dict:
    if not prepared:
        raise IdentifyError("thermal: no thermal runs")
    d = _stack(prepared, "regression")
    n = d["t_s"].size
    if n < 50:
        raise IdentifyError(f"thermal: {n} usable samples after filtering: the runs are too short"
                            f" (the eq. 19 filter window is {s.smooth_thermal_s} s)")
    P, th, d1, d2 = d["power_W"], d["theta_m_degC"], d["dtheta_K_s"], d["d2theta_K_s2"]
    x1, x2 = th - d["theta_oil_degC"], th - d["theta_housing_degC"]
    # lag terms of the temperature differences: theta_s - theta_oil_s = x1 + tau (d1 - d_oil), ...
    if s.lag_all_thermistors:
        e1, e2 = d1 - d["dtheta_oil_K_s"], d1 - d["dtheta_housing_K_s"]
    else:
        e1, e2 = d1, d1
    if np.ptp(P) < 1.0:
        raise IdentifyError("thermal: the heat input |T dw| does not vary: eq. 19 needs slip-speed steps")
    c_known = cal.heat_capacity
    fit_c = s.fit_heat_capacity
    groups = d["experiment"] * 100000 + d["segment"]

    # Unconstrained linear form: P = c1 th' + c2 th'' + k1 (th_m - th_oil) + k2 (th_m - th_h), with
    # c1 = C + (k1 + k2) tau and c2 = C tau (first-order thermistor, theta = theta_m + tau theta_m').
    if fit_c:
        A = np.column_stack([x1, x2, d1, d2])
        y = P
    else:
        A = np.column_stack([x1, x2, d1, d2])
        y = P - c_known * d1
    _identifiable("thermal (eq. 19)", A, ["k1", "k2", "theta'", "theta''"])
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

    fixed_tau = s.thermistor_lag_s

    def unpack(q):
        k1, k2 = q[0], q[1]
        tau = fixed_tau if fixed_tau is not None else q[2]
        c = q[-1] if fit_c else c_known
        return k1, k2, tau, c

    def fun(q):
        k1, k2, tau, c = unpack(q)
        return k1 * (x1 + tau * e1) + k2 * (x2 + tau * e2) + c * (d1 + tau * d2) - P

    def jac(q):
        k1, k2, tau, c = unpack(q)
        cols = [x1 + tau * e1, x2 + tau * e2]
        if fixed_tau is None:
            cols.append(k1 * e1 + k2 * e2 + c * d2)
        if fit_c:
            cols.append(d1 + tau * d2)
        return np.column_stack(cols)

    q0 = [k1_0, k2_0] + ([tau0] if fixed_tau is None else []) + ([c0] if fit_c else [])
    labels = ["k1", "k2"] + (["tau"] if fixed_tau is None else []) + (["C"] if fit_c else [])
    res = least_squares(fun, q0, jac=jac, x_scale="jac", method="lm")
    k1, k2, tau, c = unpack(res.x)
    _identifiable("thermal (eq. 19)", res.jac, labels)
    ci, rho, _, ci_method = _confidence(res.jac, res.fun, groups)
    ci_map = dict(zip(labels, ci))
    lhs = P - c * (d1 + tau * d2)
    rhs = k1 * (x1 + tau * e1) + k2 * (x2 + tau * e2)
    r2, rmse = _r2_rmse(lhs, rhs)

    # Output-error check: eq. 1 simulated (exact ZOH) with the measured heat input and oil/housing
    # temperatures, then the thermistor lag, against the measured thermistor temperature.
    sim = [simulate_thermistor(p["series"], k1, k2, c, tau) for p in prepared]
    errors = np.concatenate([m - x for _, m, x in sim])
    # what ignoring the thermistor lag would give (the bias the lag correction removes)
    naive, *_ = np.linalg.lstsq(np.column_stack([x1, x2]), P - c * d1, rcond=None)
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


# ---------------------------------------------------------------------------
# Friction data (mu and asperity steps)

@dataclass
class FrictionData:
    t_s: np.ndarray
    slip_rpm: np.ndarray
    speed_m_s: np.ndarray
    force_N: np.ndarray
    torque_Nm: np.ndarray
    theta_m_degC: np.ndarray
    dtheta_m_K_s: np.ndarray
    experiment: np.ndarray          # index into ids
    level: np.ndarray               # force level index
    level_force_N: np.ndarray       # nominal force per level
    ids: list[str]
    slip_noise_bin_rpm: float = math.nan   # std of the noise on a bin's slip (for the SIMEX correction)

    def theta(self, tau: float) -> np.ndarray:
        """Surface temperature from the thermistor: theta_m + tau theta_m' (first-order lag)."""
        return self.theta_m_degC + tau * self.dtheta_m_K_s

    def subset(self, mask: np.ndarray) -> "FrictionData":
        return FrictionData(*(getattr(self, f)[mask] for f in ("t_s", "slip_rpm", "speed_m_s", "force_N", "torque_Nm",
                                                               "theta_m_degC", "dtheta_m_K_s", "experiment", "level")),
                            self.level_force_N, self.ids, self.slip_noise_bin_rpm)


def friction_data(prepared: list[dict], cal: Calibration, notes: list[str] | None = None) -> FrictionData:
    for p in prepared:
        if p["bins"]["t_s"].size == 0 and notes is not None:
            notes.append(f"friction: experiment {p['id']} has no usable sample (every sample excluded, see the"
                         " exclusions): it does not enter the fits")
    prepared = [p for p in prepared if p["bins"]["t_s"].size > 0]
    if not prepared:
        raise IdentifyError("friction: no usable samples in any experiment (see the exclusions)")
    d = _stack(prepared, "bins")
    # force levels: the index's nominal force, else the experiment's median measured force (1 % clusters)
    nominal = []
    for i, p in enumerate(prepared):
        f = p["meta"].get("force_N")
        nominal.append(float(f) if isinstance(f, float) and math.isfinite(f) else
                       float(np.median(d["force_N"][d["experiment"] == i])))
    nominal = np.array(nominal)
    levels = []
    for f in sorted(nominal):
        if not levels or abs(f - levels[-1]) > 0.01 * levels[-1]:
            levels.append(f)
    levels = np.array(levels)
    level_of_exp = np.array([int(np.argmin(np.abs(levels - f))) for f in nominal])
    noise = [p["slip_noise_bin_rpm"] for p in prepared if math.isfinite(p["slip_noise_bin_rpm"])]
    return FrictionData(d["t_s"], d["slip_rpm"], cal.effective_radius * d["slip_rpm"] * RAD_S_PER_RPM,
                        d["force_N"], d["torque_Nm"], d["theta_m_degC"], d["dtheta_m_K_s"], d["experiment"],
                        level_of_exp[d["experiment"]], levels, [p["id"] for p in prepared],
                        float(np.median(noise)) if noise else math.nan)


def mu_samples(fd: FrictionData, cal: Calibration, tau: float) -> np.ndarray:
    """Eq. 17: mu_f = (T - R N_c mu_v(theta) A_f v / h_bar(F)) / (R N_c F)."""
    rn = cal.effective_radius * cal.friction_pairs
    theta = fd.theta(tau)
    viscous = rn * model.viscosity_Pa_s(cal, theta) * cal.friction_area * fd.speed_m_s / hbar_of_force(cal, fd.force_N)
    return (fd.torque_Nm - viscous) / (rn * fd.force_N)


def _eq18(p, v, theta, theta1, theta2):
    mu1, mu2, mu3, vs = p
    e = np.exp(-v / vs)
    stribeck = mu1 + (mu2 - mu1) * e
    g = 1.0 + mu3 * (theta - theta1) / theta2
    return stribeck * g, e, stribeck, g


def _simex(fd: FrictionData, cal: Calibration, p: np.ndarray, tau: float, seed: int = 0) -> dict:
    """SIMEX correction of mu2 and v_s for the noise on the measured slip (a regressor of eq. 18).

    Noise on v biases a nonlinear fit (errors in variables): here v_s up and mu2 up, most at the steep
    low-speed end that carries their information. SIMEX adds more noise of known size (lambda times the
    noise already there), refits, and extrapolates the trend quadratically back to lambda = -1 (no noise).
    Done on the low-speed samples (v < 8 v_s) with mu1, mu3 held (the flat part fixes them and they do not
    move with the noise); the noise level comes from the data (robust sample-to-sample differences)."""
    sigma_rpm = fd.slip_noise_bin_rpm
    if not (math.isfinite(sigma_rpm) and sigma_rpm > 0):
        return {"applied": False, "why": "slip noise not estimable"}
    mu1, mu2, mu3, vs = p
    low = fd.speed_m_s < 8.0 * vs
    if low.sum() < 50:
        return {"applied": False, "why": "too few low-speed samples"}
    d = fd.subset(low)
    th1, th2 = cal.theta1, cal.theta2
    rn = cal.effective_radius * cal.friction_pairs
    theta = d.theta(tau)
    g = 1.0 + mu3 * (theta - th1) / th2
    t_per = d.torque_Nm / (rn * d.force_N)
    visc = model.viscosity_Pa_s(cal, theta) * cal.friction_area / hbar_of_force(cal, d.force_N) / (rn * d.force_N) * rn
    sigma_v = sigma_rpm * cal.effective_radius * RAD_S_PER_RPM

    def fit(v):
        y = t_per - visc * v          # eq. 17 with this v

        def fun(q):
            return (mu1 + (q[0] - mu1) * np.exp(-v / q[1])) * g - y
        return least_squares(fun, [mu2, vs], bounds=([0.0, 1e-5], [1.0, 1.0]), x_scale="jac").x

    rng = np.random.default_rng(seed)
    lams = (0.0, 0.5, 1.0, 1.5, 2.0)
    est = [fit(d.speed_m_s)]
    for lam in lams[1:]:
        est.append(np.mean([fit(d.speed_m_s + rng.normal(0.0, math.sqrt(lam) * sigma_v, d.speed_m_s.size))
                            for _ in range(4)], axis=0))
    est = np.array(est)
    extrap = np.array([np.polyval(np.polyfit(lams, est[:, j], 2), -1.0) for j in range(2)])
    delta = extrap - est[0]
    return {"applied": True, "slip_noise_rpm": sigma_rpm, "samples": int(low.sum()),
            "delta_mu2": float(delta[0]), "delta_stribeck_speed": float(delta[1]),
            "trend": {"lambda": list(lams), "mu2": est[:, 0].tolist(), "stribeck_speed": est[:, 1].tolist()}}


def identify_mu(fd: FrictionData, cal: Calibration, tau: float | None, tau_source: str = "given",
                simex: bool = True) -> dict:
    """Fit of eq. 18 to the eq. 17 samples; tau None: the thermistor lag is fitted with them."""
    n_exp = len(set(fd.experiment.tolist()))
    if n_exp < 2:
        raise IdentifyError(f"mu: {n_exp} usable experiment(s): eq. 18 needs runs at several temperatures"
                            " and speeds (the Table 2 campaign has 184)")
    vs0 = cal.stribeck_speed
    low = fd.speed_m_s < 3.0 * vs0
    if low.sum() < 20:
        raise IdentifyError(f"mu: {int(low.sum())} samples below {3 * vs0 / cal.effective_radius / RAD_S_PER_RPM:.3g}"
                            " rpm (3 v_s): mu2 and v_s are not identifiable (no low-speed ramp-down data?)")
    if np.ptp(fd.theta_m_degC) < 10.0:
        raise IdentifyError(f"mu: the temperature spans only {np.ptp(fd.theta_m_degC):.3g} K: mu3 is not identifiable")
    th1, th2 = cal.theta1, cal.theta2
    rn = cal.effective_radius * cal.friction_pairs
    v, F = fd.speed_m_s, fd.force_N
    hb = hbar_of_force(cal, F)
    visc_per_pa_s = rn * cal.friction_area * v / hb / (rn * F)     # mu_v -> its share of mu (eq. 17)
    T_per = fd.torque_Nm / (rn * F)
    free_tau = tau is None

    def split(q):
        return q[:4], (q[4] if free_tau else tau)

    def fun(q):
        p, tq = split(q)
        theta = fd.theta_m_degC + tq * fd.dtheta_m_K_s
        m, *_ = _eq18(p, v, theta, th1, th2)
        return m - (T_per - model.viscosity_Pa_s(cal, theta) * visc_per_pa_s)

    def jac(q):
        p, tq = split(q)
        mu1, mu2, mu3, vs = p
        theta = fd.theta_m_degC + tq * fd.dtheta_m_K_s
        m, e, stribeck, g = _eq18(p, v, theta, th1, th2)
        cols = [(1 - e) * g, e * g, stribeck * (theta - th1) / th2, (mu2 - mu1) * e * v / vs ** 2 * g]
        if free_tau:
            cols.append((stribeck * mu3 / th2 + _viscosity_slope(cal, theta) * visc_per_pa_s) * fd.dtheta_m_K_s)
        return np.column_stack(cols)

    q0 = [cal.mu1, cal.mu2, cal.mu3, cal.stribeck_speed] + ([0.0] if free_tau else [])
    lo = [0.0, 0.0, -5.0, 1e-5] + ([0.0] if free_tau else [])
    hi = [1.0, 1.0, 5.0, 1.0] + ([20.0] if free_tau else [])
    res = least_squares(fun, q0, jac=jac, bounds=(lo, hi), x_scale="jac", xtol=1e-12, ftol=1e-12)
    p, tq = split(res.x)
    labels = ["mu1", "mu2", "mu3", "v_s"] + (["tau"] if free_tau else [])
    _identifiable("mu (eq. 18)", res.jac, labels)
    ci, rho, cov, ci_method = _confidence(res.jac, res.fun, fd.experiment)
    uncorrected = dict(zip(("mu1", "mu2", "mu3", "stribeck_speed"), map(float, p)))
    sx = _simex(fd, cal, np.array(p, float), float(tq)) if simex else {"applied": False, "why": "--no-simex"}
    if sx["applied"]:
        p = np.array(p, float)
        p[1] += sx["delta_mu2"]
        p[3] += sx["delta_stribeck_speed"]
    theta = fd.theta(tq)
    samples = mu_samples(fd, cal, tq)
    fitted, *_ = _eq18(p, v, theta, th1, th2)
    r2, rmse = _r2_rmse(samples, fitted)
    names = ("mu1", "mu2", "mu3", "stribeck_speed")
    return {
        "values": dict(zip(names, map(float, p))),
        "ci95": dict(zip(names, map(float, ci[:4]))),
        "thermistor_lag_s": float(tq),
        "thermistor_lag_ci95": float(ci[4]) if free_tau else 0.0,
        "thermistor_lag_source": "fitted with eq. 18" if free_tau else tau_source,
        "r2": r2, "rmse": rmse, "residual_rho": rho, "ci_method": ci_method,
        "simex": sx, "without_simex": uncorrected,
        "samples": int(samples.size), "experiments": n_exp,
        "mu_samples": samples, "mu_fit": fitted, "theta_degC": theta,
    }


def identify_asperity(fd: FrictionData, cal: Calibration, tau: float | None, s: Settings,
                      tau_source: str = "given") -> dict:
    """h_bar per force level from the viscous slope in the flat-mu region, then N (eq. 9, 15).
    tau None: the thermistor lag is found by a bounded 1-D search on the regression's residual."""
    v_flat = max(s.flat_speed_m_s, 6.0 * cal.stribeck_speed)
    flat = fd.speed_m_s >= v_flat
    d = fd.subset(flat)
    if d.t_s.size < 50:
        raise IdentifyError(f"asperity: {d.t_s.size} samples above {v_flat:.3g} m/s (flat mu_f region): no drag data")
    rn = cal.effective_radius * cal.friction_pairs
    th1, th2 = cal.theta1, cal.theta2
    y = d.torque_Nm / rn
    used_levels = sorted(set(d.level.tolist()))
    labels = ["mu1", "mu1*mu3"] + [f"1/h_bar({fd.level_force_N[lv]:.0f} N)" for lv in used_levels]

    def design(tq):
        theta = d.theta(tq)
        cols = [d.force_N, d.force_N * (theta - th1) / th2]
        visc = model.viscosity_Pa_s(cal, theta) * cal.friction_area * d.speed_m_s
        for lv in used_levels:
            cols.append(np.where(d.level == lv, visc, 0.0))
        return np.column_stack(cols)

    def ssr(tq):
        A = design(tq)
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        r = A @ coef - y
        return float(r @ r)

    if tau is None:
        found = minimize_scalar(ssr, bounds=(0.0, 5.0), method="bounded", options={"xatol": 1e-3})
        tau, tau_source = float(found.x), "fitted in the drag regression"
    A = design(tau)
    _identifiable("asperity (drag regression)", A, labels)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    resid = A @ coef - y
    ci, rho, cov, ci_method = _confidence(A, resid, d.experiment)
    r2, rmse = _r2_rmse(y * rn, (A @ coef) * rn)
    g = coef[2:]
    g_se = np.sqrt(np.abs(np.diag(cov)[2:]))
    force_mean = np.array([float(np.mean(d.force_N[d.level == lv])) for lv in used_levels])
    hbar = 1.0 / g
    # closed form per level: h from h_bar (eq. 9, monotone), then N from eq. 15 at p_c = F/A_f
    n_level = np.array([_density_from_hbar(cal, hb, f / cal.friction_area) for hb, f in zip(hbar, force_mean)])

    def fun(logn):
        c = cal.with_values(asperity_density=math.exp(logn[0]))
        return (1.0 / hbar_of_force(c, force_mean) - g) / g_se

    start = math.log(np.exp(np.mean(np.log(n_level[np.isfinite(n_level)])))) if np.any(np.isfinite(n_level)) \
        else math.log(cal.asperity_density)
    res = least_squares(fun, [start], x_scale=[1.0], diff_step=1e-6)
    n_fit = math.exp(res.x[0])
    # CI: delta method on log N; chi2 scaled when the levels disagree more than their errors say
    j = res.jac[:, 0]
    dof = max(len(used_levels) - 1, 1)
    scale = max(float(res.fun @ res.fun) / dof, 1.0) if len(used_levels) > 1 else 1.0
    se_log = math.sqrt(scale / float(j @ j)) if float(j @ j) > 0 else float("inf")
    ci_n = 1.96 * se_log * n_fit
    hbar_model = hbar_of_force(cal.with_values(asperity_density=n_fit), force_mean)
    return {
        "values": {"asperity_density": n_fit},
        "ci95": {"asperity_density": ci_n},
        "levels": [{"force_N": float(f), "hbar_m": float(h), "hbar_ci95_m": float(1.96 * se / gg ** 2),
                    "hbar_model_m": float(hm), "asperity_density": float(nl)}
                   for f, h, se, gg, hm, nl in zip(force_mean, hbar, g_se, g, hbar_model, n_level)],
        "flat_mu1": float(coef[0]), "flat_mu3": float(coef[1] / coef[0]),
        "r2_torque": r2, "rmse_torque_Nm": rmse, "residual_rho": rho, "ci_method": ci_method,
        "samples": int(d.t_s.size), "flat_speed_m_s": v_flat, "thermistor_lag_s": tau,
        "thermistor_lag_source": tau_source,
        "levels_spread_rel": float(np.std(n_level) / np.mean(n_level)) if len(n_level) > 1 else float("nan"),
    }


def _density_from_hbar(cal: Calibration, hbar: float, pressure: float) -> float:
    """N from one (h_bar, p_c) pair: invert eq. 9 for h (bisection), then eq. 15 for N."""
    s = cal.roughness_rms
    lo, hi = -60.0 * s, 60.0 * s
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if float(model.film_thickness_m(cal, mid)) < hbar:
            lo = mid
        else:
            hi = mid
    h = 0.5 * (lo + hi)
    x = h / (math.sqrt(2.0) * s)
    shape = math.sqrt(math.pi / 2.0) * cal.youngs_modulus * cal.asperity_tip_radius * s * (
        math.exp(-x * x) - (h / s) * math.sqrt(math.pi / 2.0) * math.erfc(x))
    return pressure / shape if shape > 0 else float("nan")


# ---------------------------------------------------------------------------
# Calibration file out

_LINE = re.compile(r'^(\s*)([A-Za-z_][A-Za-z0-9_]*)(\s*=\s*)\{.*\}\s*(#.*)?$')


def _fmt(x: float) -> str:
    return repr(float(f"{x:.7g}"))


def render_calibration(base_path: Path, cal: Calibration, changes: dict[str, float], sources: dict[str, str],
                       header: str) -> str:
    """The base file with the identified values and sources replaced (comments kept)."""
    units = {name: (section, unit) for section, name, unit, *_ in PARAMETERS}
    text = Path(base_path).read_text(encoding="utf-8")
    section = None
    done = set()
    lines = []
    for line in text.splitlines():
        m_sec = re.match(r'^\s*\[([^\]]+)\]\s*(#.*)?$', line)
        if m_sec:
            section = m_sec.group(1).strip()
        m = _LINE.match(line)
        if m and m.group(2) in changes and units[m.group(2)][0] == section:
            name = m.group(2)
            src = sources[name].replace("\\", "/").replace('"', "'")
            line = f'{m.group(1)}{name}{m.group(3)}{{ value = {_fmt(changes[name])}, unit = "{units[name][1]}",' \
                   f' source = "{src}" }}'
            done.add(name)
        lines.append(line)
    if done != set(changes):
        # the base is not in the one-line-per-parameter form: write every parameter out instead
        return _render_full(cal.with_values(**changes), {**cal.sources, **sources}, header)
    return header + "\n".join(lines) + "\n"


def _render_full(cal: Calibration, sources: dict[str, str], header: str) -> str:
    out = [header.rstrip("\n")]
    section = None
    for sec, name, unit, constraint, _ in PARAMETERS:
        if sec != section:
            out.append(f"\n[{sec}]")
            section = sec
        value = cal.values[name]
        text = str(int(value)) if constraint == "count" else _fmt(value)
        src = sources[name].replace("\\", "/").replace('"', "'")
        out.append(f'{name} = {{ value = {text}, unit = "{unit}", source = "{src}" }}')
    return "\n".join(out) + "\n"


def read_true(path: Path) -> dict[str, float]:
    """True parameters: a calibration file (the bench's, e.g. bench_true.toml)."""
    try:
        return dict(load_calibration(path).values)
    except CalibrationError as e:
        raise IdentifyError(str(e)) from None


# ---------------------------------------------------------------------------
# The command

@dataclass
class Result:
    step: str
    data_dir: Path
    base: Calibration
    cal: Calibration                 # base with the identified values
    results: dict = field(default_factory=dict)
    exclusions: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    campaigns: list = field(default_factory=list)
    settings: Settings | None = None


def run(step: str, data_dir: Path, base: Calibration, s: Settings) -> Result:
    """Identify; nothing is written here."""
    if step not in STEPS + ("all",):
        raise IdentifyError(f"unknown step {step!r}")
    data_dir = Path(data_dir)
    steps = STEPS if step == "all" else (step,)
    res = Result(step, data_dir, base, base, settings=s)
    clock = time.perf_counter()
    need_friction = any(x in steps for x in ("asperity", "mu"))
    need_thermal = "thermal" in steps
    campaigns = find_campaigns(data_dir, res.notes) if (need_friction or need_thermal) else []
    res.campaigns = [{"index": str(c.index), "kind": c.kind, "experiments": len(c.rows)} for c in campaigns]
    for c in campaigns:
        if c.kind == "engagement":
            res.notes.append(f"{c.index}: engagement runs ({len(c.rows)}) are not used for identification")
    cal = base
    tau = s.thermistor_lag_s
    tau_source = "--thermistor-lag" if tau is not None else None

    if need_thermal:
        t0 = time.perf_counter()
        thermal = [c for c in campaigns if c.kind == "thermal"]
        if not thermal:
            if step == "thermal":
                thermal = [c for c in campaigns if c.kind == "friction"]
                res.notes.append("thermal: no campaign named 'thermal': the friction runs are used for eq. 19")
            else:
                raise IdentifyError(f"{data_dir}: no thermal campaign (an index in a directory or file named"
                                    " 'thermal') for the thermal step")
        prepared = []
        for c in thermal:
            prepared += prepare_campaign(c, "thermal", cal, s, res.exclusions)
        r = identify_thermal(prepared, cal, s)
        r["ids"] = [p["id"] for p in prepared]
        res.results["thermal"] = r
        cal = cal.with_values(**r["values"])
        if tau is None:
            tau, tau_source = r["thermistor_lag_s"], "from the thermal step (eq. 19)"
        res.timings["thermal"] = time.perf_counter() - t0

    if "viscosity" in steps:
        t0 = time.perf_counter()
        r = identify_viscosity(find_viscosity(data_dir), cal, res.exclusions)
        res.results["viscosity"] = r
        cal = cal.with_values(**r["values"])
        res.timings["viscosity"] = time.perf_counter() - t0

    if need_friction:
        t0 = time.perf_counter()
        friction = [c for c in campaigns if c.kind == "friction"]
        if not friction:
            raise IdentifyError(f"{data_dir}: no friction campaign (Table 2 runs) for the {'/'.join(steps)} step")
        prepared = []
        for c in friction:
            prepared += prepare_campaign(c, "friction", cal, s, res.exclusions)
        fd = friction_data(prepared, cal, res.notes)
        res.timings["friction load"] = time.perf_counter() - t0
        if "asperity" in steps:
            t0 = time.perf_counter()
            r = identify_asperity(fd, cal, tau, s, tau_source or "given")
            tau, tau_source = r["thermistor_lag_s"], r["thermistor_lag_source"]
            res.results["asperity"] = r
            cal = cal.with_values(**r["values"])
            res.timings["asperity"] = time.perf_counter() - t0
        if "mu" in steps:
            t0 = time.perf_counter()
            r = identify_mu(fd, cal, tau, tau_source or "given", simex=s.simex)
            r["fd"] = fd
            res.results["mu"] = r
            cal = cal.with_values(**r["values"])
            res.timings["mu"] = time.perf_counter() - t0
    res.cal = cal
    res.timings["total"] = time.perf_counter() - clock
    return res


def identified_values(res: Result) -> dict[str, float]:
    return {name: float(v) for r in res.results.values() for name, v in r["values"].items()}


def identified_sources(res: Result) -> dict[str, str]:
    out = {}
    for step, r in res.results.items():
        for name in r["values"]:
            extra = r.get("source_notes", {}).get(name)
            out[name] = f"identified from {res.data_dir} by wetclutch identify on {WHAT[step]}" + (
                f"; {extra}" if extra else "")
    return out


def write_outputs(res: Result, base_path: Path, out_dir: Path, command: str, true_path: Path | None,
                  plots: bool = True) -> dict:
    """calibration.toml (checked by calibration.load and a LUT build), report.md, figures.json, PNGs."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    changes = identified_values(res)
    sources = identified_sources(res)
    header = (f"# Calibration identified from bench data: `{command}`\n"
              f"# Base: {base_path}; identified values carry their source below.\n")
    text = render_calibration(base_path, res.base, changes, sources, header)
    cal_path = out_dir / "calibration.toml"
    tmp = out_dir / ".calibration.toml.tmp"
    tmp.write_text(text, encoding="utf-8")
    try:
        check = load_calibration(tmp)
    except CalibrationError as e:
        tmp.unlink()
        raise IdentifyError(f"the identified calibration is rejected by calibration.load: {e}") from None
    os.replace(tmp, cal_path)
    check = load_calibration(cal_path)
    table = lut.build_table(check)
    lut_error = lut.max_relative_error(check, table)
    truth = read_true(true_path) if true_path else None
    return write_report(res, out_dir, command, truth, str(true_path) if true_path else None,
                                 {"path": str(cal_path), "lut_max_rel_error": lut_error,
                                  "lut_nodes": int(table.pressure_Pa.size)}, plots)


# ---------------------------------------------------------------------------
# Report: report.md, figures.json, exclusions.csv, PNG plots

def _num(x):
    """JSON-safe float."""
    x = float(x)
    return x if math.isfinite(x) else None


def _exclusion_summary(exclusions: list[Exclusion]) -> dict:
    out = {}
    for e in exclusions:
        key = f"{e.step}/{e.reason}"
        d = out.setdefault(key, {"step": e.step, "reason": e.reason, "meaning": REASONS.get(e.reason, e.reason),
                                 "events": 0, "samples": 0, "seconds": 0.0, "experiments": set()})
        d["events"] += 1
        d["samples"] += e.samples
        d["seconds"] += e.seconds
        d["experiments"].add(e.experiment)
    for d in out.values():
        d["experiments"] = len(d["experiments"])
        d["seconds"] = round(d["seconds"], 3)
    return out


def write_report(res: Result, out_dir: Path, command: str, truth: dict | None, true_path: str | None,
                 calinfo: dict, plots: bool = True) -> dict:
    out_dir = Path(out_dir)
    values = identified_values(res)
    params = {}
    ci_all = {}
    for step, r in res.results.items():
        ci_all.update(r.get("ci95", {}))
    for name, v in values.items():
        entry = {"symbol": SYMBOLS.get(name, name), "step": next(st for st, r in res.results.items() if name in r["values"]),
                 "base": _num(res.base.values[name]), "identified": _num(v), "ci95": _num(ci_all.get(name, float("nan")))}
        if truth and name in truth:
            entry["true"] = truth[name]
            entry["error_pct"] = _num((v / truth[name] - 1.0) * 100.0)
            if name in TARGET_PARAMETERS:
                entry["within_3pct"] = bool(abs(v / truth[name] - 1.0) <= TARGETS["rel_error"])
        params[name] = entry
    fig = {
        "command": command, "data_dir": str(res.data_dir), "base_calibration": res.base.path,
        "true_parameters": true_path, "steps": list(res.results), "campaigns": res.campaigns,
        "runtime_s": {k: round(v, 3) for k, v in res.timings.items()},
        "parameters": params, "notes": res.notes, "calibration": calinfo,
        "settings": dict(vars(res.settings)) if res.settings else {},
    }
    targets = {}
    if "mu" in res.results:
        r = res.results["mu"]
        grid = _mu_grid(r)
        fig["mu"] = {"r2": _num(r["r2"]), "rmse": _num(r["rmse"]), "paper_r2": PAPER["r2"],
                     "paper_rmse": PAPER["rmse"], "samples": r["samples"], "experiments": r["experiments"],
                     "residual_rho": _num(r["residual_rho"]), "thermistor_lag_s": _num(r["thermistor_lag_s"]),
                     "thermistor_lag_source": r["thermistor_lag_source"],
                     "simex": {k: v for k, v in r["simex"].items()},
                     "without_simex": r["without_simex"],
                     "grid_5rpm_5K": {"cells": grid["cells"], "r2": _num(grid["r2"]), "rmse": _num(grid["rmse"])}}
        targets["mu_r2>=0.985"] = bool(r["r2"] >= TARGETS["r2"])
        names = ("mv1", "mv2", "mv3", "mv4", "asperity_density")
        if truth and all(k in truth for k in names + tuple(r["values"])):
            exact = identify_mu(r["fd"], res.cal.with_values(**{k: truth[k] for k in names}), r["thermistor_lag_s"])
            fig["mu"]["with_true_viscosity_and_N"] = {k: _num((v / truth[k] - 1.0) * 100.0)
                                                      for k, v in exact["values"].items()}
    if "thermal" in res.results:
        r = res.results["thermal"]
        fig["thermal"] = {k: (_num(v) if isinstance(v, (float, np.floating)) else v) for k, v in r.items()
                          if k in ("thermistor_lag_s", "thermistor_lag_ci95", "thermistor_lag_source", "heat_capacity_J_K",
                                   "heat_capacity_ci95", "heat_capacity_source", "r2_eq19", "rmse_eq19_W",
                                   "residual_rho", "samples", "runs", "theta_oil_housing_spread_K", "sim_rmse_K",
                                   "without_lag_correction", "ids")}
    if "viscosity" in res.results:
        r = res.results["viscosity"]
        fig["viscosity"] = {"r2": _num(r["r2"]), "rmse_Pa_s": _num(r["rmse_Pa_s"]),
                            "max_rel_error": _num(r["max_rel_error"]), "points": r["points"],
                            "theta_range_degC": r["theta_range_degC"], "source": r["source"]}
        if truth and all(k in truth for k in ("mv1", "mv2", "mv3", "mv4")):
            th = np.linspace(*r["theta_range_degC"], 200)
            tcal = res.base.with_values(**{k: truth[k] for k in ("mv1", "mv2", "mv3", "mv4")})
            ical = res.base.with_values(**r["values"])
            fig["viscosity"]["curve_max_rel_error_vs_true"] = _num(np.max(np.abs(
                model.viscosity_Pa_s(ical, th) / model.viscosity_Pa_s(tcal, th) - 1.0)))
    if "asperity" in res.results:
        r = res.results["asperity"]
        fig["asperity"] = {k: r[k] for k in ("levels", "flat_speed_m_s", "samples")}
        fig["asperity"].update({k: _num(r[k]) for k in ("flat_mu1", "flat_mu3", "r2_torque", "rmse_torque_Nm",
                                                         "residual_rho", "levels_spread_rel", "thermistor_lag_s")})
    ex = _exclusion_summary(res.exclusions)
    fig["exclusions"] = {"events": len(res.exclusions), "by_reason": ex}
    if truth:
        for name in TARGET_PARAMETERS:
            if name in params and "within_3pct" in params[name]:
                targets[f"{SYMBOLS[name]} within 3%"] = params[name]["within_3pct"]
    targets[f"runtime < {TARGETS['runtime_s']:g} s"] = bool(res.timings["total"] < TARGETS["runtime_s"])
    fig["targets"] = targets
    with open(out_dir / "exclusions.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["step", "experiment", "reason", "t_from_s", "t_to_s", "samples", "seconds"],
                           lineterminator="\n")
        w.writeheader()
        for e in res.exclusions:
            w.writerow(e.row())
    fig["plots"] = _plots(res, out_dir, truth) if plots else []
    (out_dir / "figures.json").write_text(json.dumps(fig, indent=2, default=_json_default) + "\n")
    (out_dir / "report.md").write_text(_markdown(res, fig, truth))
    return fig


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, set):
        return sorted(o)
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def _mu_grid(r: dict, slip_step=5.0, theta_step=5.0) -> dict:
    """Fig. 12: averages over a 5 rpm x 5 degC grid, and R2/RMSE of the fit on the cell averages."""
    fd = r["fd"]
    i = np.floor(fd.slip_rpm / slip_step).astype(int)
    j = np.floor(r["theta_degC"] / theta_step).astype(int)
    key = i * 10000 + (j + 1000)
    uniq, inv = np.unique(key, return_inverse=True)
    cnt = np.bincount(inv)
    mean_mu = np.bincount(inv, weights=r["mu_samples"]) / cnt
    mean_fit = np.bincount(inv, weights=r["mu_fit"]) / cnt
    slip_c = (uniq // 10000 + 0.5) * slip_step
    theta_c = (uniq % 10000 - 1000 + 0.5) * theta_step
    r2, rmse = _r2_rmse(mean_mu, mean_fit)
    return {"cells": int(uniq.size), "r2": r2, "rmse": rmse, "slip_rpm": slip_c, "theta_degC": theta_c,
            "mu": mean_mu, "count": cnt}


def _fmt_val(x) -> str:
    if x is None:
        return "-"
    return f"{x:.5g}"


def _markdown(res: Result, fig: dict, truth: dict | None) -> str:
    L = [f"# Identification from bench data: {', '.join(fig['steps'])}", "",
         f"Command: `{fig['command']}`  ",
         f"Data: `{fig['data_dir']}`; base calibration `{fig['base_calibration']}`"
         + (f"; true parameters `{fig['true_parameters']}`" if fig["true_parameters"] else "") + "  ",
         f"Identification time: {fig['runtime_s']['total']:.2f} s on {os.cpu_count()} CPU(s) ("
         + ", ".join(f"{k} {v:.2f} s" for k, v in fig["runtime_s"].items() if k != "total") + ")", ""]
    for c in fig["campaigns"]:
        L.append(f"- campaign `{c['index']}`: {c['kind']}, {c['experiments']} experiment(s)")
    L += ["", "## Parameters", "",
          "| parameter | symbol | step | base | identified | 95 % CI (±) | true | error | target |",
          "|---|---|---|---|---|---|---|---|---|"]
    for name, p in fig["parameters"].items():
        err = f"{p['error_pct']:+.2f} %" if p.get("error_pct") is not None else "-"
        tgt = ("met" if p["within_3pct"] else "MISSED") + " (3 %)" if "within_3pct" in p else "-"
        L.append(f"| {name} | {p['symbol']} | {p['step']} | {_fmt_val(p['base'])} | {_fmt_val(p['identified'])} |"
                 f" {_fmt_val(p['ci95'])} | {_fmt_val(p.get('true'))} | {err} | {tgt} |")
    methods = "; ".join(f"{st}: {r['ci_method']}" for st, r in res.results.items() if "ci_method" in r)
    L += ["", "95 % confidence intervals from the Jacobian at the solution (" + methods + "). Cluster-robust"
          " means the sandwich covariance summed per experiment, which allows any correlation of the"
          " residuals within a run. They cover the noise, not the systematic effects discussed below"
          " (errors carried over from the viscosity curve and N, model error).", ""]
    if fig["targets"]:
        L += ["Targets: " + "; ".join(f"{k}: {'met' if v else 'MISSED'}" for k, v in fig["targets"].items()), ""]
    if "mu" in fig:
        m = fig["mu"]
        L += ["## Coulomb friction coefficient (eq. 17, 18)", "",
              "| | this fit | paper |", "|---|---|---|",
              f"| R² | {m['r2']:.4f} | {m['paper_r2']} |", f"| RMSE | {m['rmse']:.6f} | {m['paper_rmse']} |",
              f"| samples / experiments | {m['samples']} / {m['experiments']} | 184 experiments |",
              f"| on the Fig. 12 grid (5 rpm x 5 °C cell means, {m['grid_5rpm_5K']['cells']} cells) |"
              f" R² {m['grid_5rpm_5K']['r2']:.4f}, RMSE {m['grid_5rpm_5K']['rmse']:.6f} | |", "",
              "Each sample (10 ms bin of the measurement) gives mu_f by eq. 17 with the measured torque, slip and"
              " load-cell force, the viscous part removed with mu_v at the clutch temperature and h_bar at the"
              " measured force (eq. 9, 15, 16, with the asperity density of this calibration). The clutch"
              " temperature is the thermistor corrected for its first-order lag, theta_m + tau theta_m'"
              f" (tau = {m['thermistor_lag_s']:.4g} s, {m['thermistor_lag_source']}; theta_m' from a 0.5 s"
              " Savitzky-Golay derivative). Eq. 18 is fitted to the samples with"
              " scipy.optimize.least_squares (analytic Jacobian).", ""]
        sx = m["simex"]
        if sx.get("applied"):
            L += [f"Errors in variables: the slip is a regressor of eq. 18 and carries noise ({sx['slip_noise_rpm']:.3g}"
                  " rpm on a sample after the moving average, estimated from the sample-to-sample differences);"
                  " at the steep low-speed end this biases mu2 and v_s upward. SIMEX (refits with 0.5..2 times more"
                  " noise added, quadratic extrapolation to no noise, on the"
                  f" {sx['samples']} samples below 8 v_s with mu1, mu3 held) corrects mu2 by {sx['delta_mu2']:+.3g}"
                  f" and v_s by {sx['delta_stribeck_speed']:+.3g} m/s (uncorrected: mu2"
                  f" {m['without_simex']['mu2']:.5g}, v_s {m['without_simex']['stribeck_speed']:.5g} m/s).", ""]
        else:
            L += [f"No errors-in-variables (SIMEX) correction: {sx.get('why')}.", ""]
        if m.get("with_true_viscosity_and_N"):
            w = m["with_true_viscosity_and_N"]
            L += ["Where the errors come from: the same fit with the true viscosity curve and N (the viscous part"
                  " of eq. 17 exact) gives " + ", ".join(f"{SYMBOLS[k]} {v:+.2f} %" for k, v in w.items())
                  + ": the rest of the errors above is carried over from the identified viscosity and N.", ""]
    if "thermal" in fig:
        t = fig["thermal"]
        L += ["## Thermal conductances (eq. 19)", "",
              f"Runs: {t['runs']} ({', '.join(map(str, t.get('ids', [])))}), {t['samples']} regression samples;"
              f" std of theta_oil - theta_housing {t['theta_oil_housing_spread_K']:.3g} K (what separates k1 from k2).",
              "",
              "Method: P = T dw (measured torque times slip; the signed product, unbiased under sensor noise),"
              " the thermistor temperatures and their derivatives all pass through the same modulating function"
              f" g(s) = (1-(s/H)²)³, H = {res.results['thermal']['filter_half_width_s']:g} s: (g*x)' = g'*x and"
              " (g*x)'' = g''*x exactly, so eq. 19 holds exactly for the filtered signals and no noisy"
              " differencing is needed. Thermistor lag: every thermistor is a first-order lag"
              " (tau theta_m' + theta_m = theta), so theta = theta_m + tau theta_m'; substituted in eq. 19 this"
              " adds theta_m' and theta_m'' terms, and tau is estimated with k1 and k2 (nonlinear least squares"
              " started from the unconstrained linear regression)"
              + (" — here fixed by --thermistor-lag." if "fixed" in t["thermistor_lag_source"] else "."), "",
              "| | value |", "|---|---|",
              f"| thermistor lag tau | {t['thermistor_lag_s']:.4g} s (± {t['thermistor_lag_ci95']:.2g}), {t['thermistor_lag_source']} |",
              f"| heat capacity C | {t['heat_capacity_J_K']:.5g} J/K, {t['heat_capacity_source']} |",
              f"| eq. 19 fit | R² {t['r2_eq19']:.6f}, RMSE {t['rmse_eq19_W']:.4g} W |",
              f"| eq. 1 + lag simulated vs thermistor | RMSE {t['sim_rmse_K']:.4g} K |",
              f"| without the lag correction | k1 {t['without_lag_correction']['oil_conductance']:.5g},"
              f" k2 {t['without_lag_correction']['housing_conductance']:.5g} W/K |", "",
              "Bias that remains: the lag model is first order with one tau for the three thermistors; a sensor"
              " with a different dynamic would leave a bias of the order of the 'without the lag correction'"
              " row times the relative error of the lag model. With C from the calibration, an error in C goes"
              " into k1 and k2 through the theta' term (use --fit-heat-capacity to estimate C).", ""]
    if "viscosity" in fig:
        v = fig["viscosity"]
        L += ["## Viscosity (eq. 2)", "",
              f"{v['points']} points, {v['theta_range_degC'][0]:g}..{v['theta_range_degC'][1]:g} °C from `{v['source']}`;"
              " least squares on log(mu_v) (equal relative weight at every temperature).",
              f"R² {v['r2']:.6f}, RMSE {v['rmse_Pa_s']:.4g} Pa s, largest relative error {v['max_rel_error'] * 100:.2f} %"
              + (f"; the fitted curve is within {v['curve_max_rel_error_vs_true'] * 100:.2f} % of the true one over"
                 " the range" if v.get("curve_max_rel_error_vs_true") is not None else "") + ".",
              "The four parameters of a double exponential are strongly correlated: individually they scatter"
              " more than the curve (which is what the model uses).", ""]
    if "asperity" in fig:
        a = fig["asperity"]
        L += ["## Asperity density N (from the viscous drag)", "",
              f"In the flat part of eq. 18 (v ≥ {a['flat_speed_m_s']:.3g} m/s, where e^(-v/v_s) is negligible)"
              " eq. 8 reads T/(R N_c) = mu1 F + mu1 mu3 F (theta-theta1)/theta2 + mu_v(theta) A_f v / h_bar(F):"
              " linear in mu1, mu1 mu3 and one 1/h_bar per applied force. One linear regression over all runs"
              " (temperature from the lag-corrected thermistor) gives h_bar at each force; inverting eq. 9 gives"
              " h and eq. 15 with p_c = F/A_f gives N per force; N is then fitted to the h_bar(F) points"
              " (weighted by their standard errors).", "",
              f"Drag regression: {a['samples']} samples, torque R² {a['r2_torque']:.5f}, RMSE {a['rmse_torque_Nm']:.3g} Nm;"
              f" it also gives mu1 = {a['flat_mu1']:.5g}, mu3 = {a['flat_mu3']:.5g} (a check on the eq. 18 fit).", "",
              "| force (N) | h_bar from the slope (µm) | ± (95 %) | h_bar(F; N fitted) (µm) | N from this level (1/m²) |",
              "|---|---|---|---|---|"]
        for lv in a["levels"]:
            L.append(f"| {lv['force_N']:.1f} | {lv['hbar_m'] * 1e6:.4f} | {lv['hbar_ci95_m'] * 1e6:.4f} |"
                     f" {lv['hbar_model_m'] * 1e6:.4f} | {lv['asperity_density']:.5g} |")
        spread = a["levels_spread_rel"]
        L += ["", "Accuracy: N's 95 % interval in the parameter table; spread of the per-force values"
              + (f" {spread * 100:.2f} %" if spread is not None else " (one force level only)")
              + ". h_bar changes by only about half the relative change of N (eq. 15 is steep in h), so N is"
              " about twice as uncertain as the drag slope; it also inherits the viscosity curve's error one"
              " to one (mu_v/h_bar is what the slope measures).", ""]
    ex = fig["exclusions"]["by_reason"]
    st = fig["settings"]
    L += ["## Exclusions", "",
          f"Rules: slip (moving average over {st.get('smooth_slip_s')} s) below {st.get('slip_min_rpm')} rpm = stuck;"
          f" force below {st.get('force_min_N')} N = no contact; a load change is |dF/dt| > {st.get('force_rate_N_s')} N/s"
          f" (50 ms average), the film is taken as settled {st.get('film_settle_s')} s after it (and after the"
          " record start); NaN or empty cells exclude their row; a smoothing window needs valid samples on both"
          " sides.", "",
          f"{fig['exclusions']['events']} excluded stretches; every one is listed below and in exclusions.csv.", "",
          "| step | reason | meaning | stretches | samples | seconds | experiments |", "|---|---|---|---|---|---|---|"]
    for d in ex.values():
        L.append(f"| {d['step']} | {d['reason']} | {d['meaning']} | {d['events']} | {d['samples']} | {d['seconds']:g} |"
                 f" {d['experiments']} |")
    if not ex:
        L.append("| - | - | none | 0 | 0 | 0 | 0 |")
    if res.notes:
        L += ["", "## Notes", ""] + [f"- {n}" for n in res.notes]
    c = fig["calibration"]
    L += ["", "## Output", "",
          f"- `{c['path']}`: the base calibration with the identified values (sources say so); accepted by"
          f" calibration.load, film LUT built from it: {c['lut_nodes']} nodes, max relative error"
          f" {c['lut_max_rel_error']:.3e}. Headers: `wetclutch lut {c['path']} --out DIR`.",
          "- `figures.json`: every number of this report; `exclusions.csv`: the exclusions."]
    for p in fig["plots"]:
        L.append(f"- ![{Path(p).stem}]({Path(p).name})")
    L += ["", "## Appendix: every exclusion", "", "| step | experiment | reason | t from (s) | t to (s) | samples |",
          "|---|---|---|---|---|---|"]
    for e in res.exclusions:
        t_from = f"{e.t_from_s:.3f}" if math.isfinite(e.t_from_s) else "-"
        t_to = f"{e.t_to_s:.3f}" if math.isfinite(e.t_to_s) else "-"
        L.append(f"| {e.step} | {e.experiment} | {e.reason} | {t_from} | {t_to} | {e.samples} |")
    return "\n".join(L) + "\n"


def _plots(res: Result, out_dir: Path, truth: dict | None) -> list[str]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    files = []

    def save(f, name):
        path = out_dir / name
        f.tight_layout()
        f.savefig(path, dpi=110)
        plt.close(f)
        files.append(str(path))

    rng = np.random.default_rng(0)
    cal = res.cal
    if "mu" in res.results:
        r = res.results["mu"]
        fd = r["fd"]
        n = r["mu_samples"].size
        pick = rng.choice(n, size=min(n, 30000), replace=False)
        slip, theta, mu = fd.slip_rpm[pick], r["theta_degC"][pick], r["mu_samples"][pick]
        vgrid = np.linspace(0, max(fd.slip_rpm.max(), 1), 600)
        # Fig. 11a: mu_f against slip speed, coloured by temperature, fitted curves at 20..100 degC
        f, axs = plt.subplots(1, 2, figsize=(12, 4.8))
        for ax, xmax in zip(axs, (vgrid[-1], 30.0)):
            sc = ax.scatter(slip, mu, c=theta, s=1, cmap="coolwarm", rasterized=True)
            for th in (20, 40, 60, 80, 100):
                ax.plot(vgrid, model.friction_coefficient(cal, cal.effective_radius * vgrid * RAD_S_PER_RPM, th),
                        "k-", lw=0.8)
            ax.set_xlim(0, xmax)
            ax.set_xlabel("slip speed (rpm)")
            ax.set_ylabel("mu_f (eq. 17)")
            ax.grid(alpha=0.3)
        axs[0].set_title(f"Fig. 11a: mu_f vs slip ({pick.size} of {n} samples), eq. 18 at 20..100 °C")
        axs[1].set_title("low-speed (Stribeck) detail")
        f.colorbar(sc, ax=axs[1], label="temperature (°C)")
        save(f, "fig11a_mu_vs_slip.png")
        # Fig. 11b: against temperature, coloured by slip
        f, ax = plt.subplots(figsize=(7.5, 4.8))
        sc = ax.scatter(theta, mu, c=slip, s=1, cmap="viridis", rasterized=True)
        tg = np.linspace(theta.min(), theta.max(), 100)
        ax.plot(tg, model.friction_coefficient(cal, 1.0, tg), "k-", lw=1, label="eq. 18, flat (v >> v_s)")
        ax.plot(tg, model.friction_coefficient(cal, 0.0, tg), "k--", lw=1, label="eq. 18, v = 0")
        ax.set_xlabel("clutch temperature (°C)")
        ax.set_ylabel("mu_f (eq. 17)")
        ax.set_title("Fig. 11b: mu_f vs temperature")
        ax.legend()
        ax.grid(alpha=0.3)
        f.colorbar(sc, ax=ax, label="slip (rpm)")
        save(f, "fig11b_mu_vs_temperature.png")
        # Fig. 11c: 3D samples and the fitted surface
        sg, tg2 = np.meshgrid(np.linspace(0, vgrid[-1], 40), np.linspace(theta.min(), theta.max(), 30))
        surf = model.friction_coefficient(cal, cal.effective_radius * sg * RAD_S_PER_RPM, tg2)
        f = plt.figure(figsize=(8, 6))
        ax = f.add_subplot(projection="3d")
        few = pick[:8000]
        ax.scatter(fd.slip_rpm[few], r["theta_degC"][few], r["mu_samples"][few], s=1, c="tab:blue", alpha=0.3)
        ax.plot_wireframe(sg, tg2, surf, color="k", lw=0.4)
        ax.set_xlabel("slip (rpm)")
        ax.set_ylabel("temperature (°C)")
        ax.set_zlabel("mu_f")
        ax.set_title(f"Fig. 11c: samples and eq. 18 (R² {r['r2']:.4f}, RMSE {r['rmse']:.5f})")
        save(f, "fig11c_mu_surface.png")
        # Fig. 12: 5 rpm x 5 degC grid averages and the fitted surface
        g = _mu_grid(r)
        f = plt.figure(figsize=(13, 5.5))
        ax = f.add_subplot(1, 2, 1, projection="3d")
        ax.scatter(g["slip_rpm"], g["theta_degC"], g["mu"], c=g["mu"], cmap="viridis", s=8)
        ax.plot_wireframe(sg, tg2, surf, color="k", lw=0.3)
        ax.set_xlabel("slip (rpm)")
        ax.set_ylabel("temperature (°C)")
        ax.set_zlabel("mu_f")
        ax.set_title("Fig. 12: cell means (5 rpm x 5 °C) and eq. 18")
        ax = f.add_subplot(1, 2, 2)
        fit_cells = model.friction_coefficient(cal, cal.effective_radius * g["slip_rpm"] * RAD_S_PER_RPM,
                                               g["theta_degC"])
        sc = ax.scatter(g["slip_rpm"], g["theta_degC"], c=g["mu"] - fit_cells, cmap="RdBu_r", s=14,
                        vmin=-0.004, vmax=0.004)
        ax.set_xlabel("slip (rpm)")
        ax.set_ylabel("temperature (°C)")
        ax.set_title(f"cell mean - eq. 18 (grid R² {g['r2']:.4f}, RMSE {g['rmse']:.5f})")
        f.colorbar(sc, ax=ax, label="mu_f residual")
        save(f, "fig12_mu_grid.png")
    if "thermal" in res.results:
        r = res.results["thermal"]
        k = len(r["sim"])
        f, axs = plt.subplots(k + 1, 1, figsize=(10, 3.0 * (k + 1)))
        axs = np.atleast_1d(axs)
        for ax, (tt, meas, sim), ident in zip(axs, r["sim"], r.get("ids", [""] * k)):
            ax.plot(tt, meas, lw=0.8, label="thermistor (measured)")
            ax.plot(tt, sim, lw=0.8, label="eq. 1 + lag, identified k1, k2")
            ax.set_ylabel("°C")
            ax.set_xlabel("time (s)")
            ax.set_title(f"Fig. 13 style: {ident}: RMSE {np.sqrt(np.mean((meas - sim) ** 2)):.3f} K")
            ax.legend(loc="best")
            ax.grid(alpha=0.3)
        ax = axs[-1]
        sel = rng.choice(r["lhs"].size, size=min(r["lhs"].size, 20000), replace=False)
        ax.scatter(r["rhs"][sel], r["lhs"][sel], s=1)
        lim = [min(r["rhs"].min(), r["lhs"].min()), max(r["rhs"].max(), r["lhs"].max())]
        ax.plot(lim, lim, "k-", lw=0.8)
        ax.set_xlabel("k1 (theta-theta_oil) + k2 (theta-theta_housing)  (W)")
        ax.set_ylabel("T dw - C dtheta/dt  (W)")
        ax.set_title(f"eq. 19, filtered: R² {r['r2_eq19']:.5f}")
        ax.grid(alpha=0.3)
        save(f, "thermal_eq19.png")
    if "viscosity" in res.results:
        r = res.results["viscosity"]
        th = np.linspace(*r["theta_range_degC"], 200)
        f, ax = plt.subplots(figsize=(7, 4.5))
        ax.semilogy(r["data"]["theta_degC"], r["data"]["viscosity_Pa_s"] * 1e3, "o", label="data")
        ax.semilogy(th, model.viscosity_Pa_s(res.base.with_values(**r["values"]), th) * 1e3, "-", label="eq. 2 fit")
        ax.semilogy(th, model.viscosity_Pa_s(res.base, th) * 1e3, ":", label="base calibration")
        if truth and all(n in truth for n in ("mv1", "mv2", "mv3", "mv4")):
            tc = res.base.with_values(**{n: truth[n] for n in ("mv1", "mv2", "mv3", "mv4")})
            ax.semilogy(th, model.viscosity_Pa_s(tc, th) * 1e3, "--", label="true")
        ax.set_xlabel("temperature (°C)")
        ax.set_ylabel("viscosity (mPa s)")
        ax.set_title(f"eq. 2: R² {r['r2']:.5f}, max rel. error {r['max_rel_error'] * 100:.2f} %")
        ax.legend()
        ax.grid(alpha=0.3, which="both")
        save(f, "viscosity_eq2.png")
    if "asperity" in res.results:
        r = res.results["asperity"]
        lv = r["levels"]
        F = np.array([x["force_N"] for x in lv])
        fg = np.linspace(F.min() * 0.8, F.max() * 1.2, 100)
        f, ax = plt.subplots(figsize=(7, 4.5))
        ax.errorbar(F, [x["hbar_m"] * 1e6 for x in lv], yerr=[x["hbar_ci95_m"] * 1e6 for x in lv], fmt="o",
                    label="h_bar from the drag slope (95 %)")
        ax.plot(fg, hbar_of_force(res.base.with_values(asperity_density=r["values"]["asperity_density"]), fg) * 1e6,
                "-", label=f"eq. 9/15, N = {r['values']['asperity_density']:.4g}")
        ax.plot(fg, hbar_of_force(res.base, fg) * 1e6, ":", label=f"base N = {res.base.asperity_density:.4g}")
        if truth and "asperity_density" in truth:
            ax.plot(fg, hbar_of_force(res.base.with_values(asperity_density=truth["asperity_density"]), fg) * 1e6,
                    "--", label=f"true N = {truth['asperity_density']:.4g}")
        ax.set_xlabel("applied force (N)")
        ax.set_ylabel("h_bar (µm)")
        ax.set_title("average film thickness from the viscous drag")
        ax.legend()
        ax.grid(alpha=0.3)
        save(f, "asperity_hbar.png")
    return files
