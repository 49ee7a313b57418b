"""Reading bench data: campaign discovery, index and measurement tables, one reduction per record.

A data directory as ``wetclutch bench`` writes it: per campaign an index CSV
(columns ``id`` and ``file``, optionally ``force_N``, ``slip_rpm``,
``loading_s``, ``theta0_degC``, ...) beside one measurement CSV per experiment
(``t_s, slip_rpm, force_N, torque_Nm, theta_clutch_degC, theta_oil_degC,
theta_housing_degC[, torque_request_Nm]``), and ``viscosity.csv``
(``theta_degC, viscosity_Pa_s``). The index may be in the directory itself or
in its sub-directories (``table2/``, ``thermal/``); a campaign whose directory
or index name says ``thermal`` holds the thermal runs, ``engagement`` the
engagement runs (the film step), ``breakaway`` the breakaway runs (the static
step), every other campaign is a friction campaign (Table 2).
The CSV parsing itself is csvio's; errors from it are raised as IdentifyError.
"""
from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..util import csvio
from ..calibration import Calibration
from .settings import IdentifyError, Settings
from .signals import Exclusion, prepare_friction, prepare_thermal

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


# ---------------------------------------------------------------------------
# Tables

def read_table(path: Path, required, optional=()) -> dict[str, np.ndarray]:
    """csvio.read_table with the column units of bench data; an empty or nan cell is NaN."""
    try:
        return csvio.read_table(path, required, optional, units=QUANTITY_UNIT)
    except csvio.CsvError as e:
        raise IdentifyError(str(e)) from None


def _header(path: Path) -> list[str] | None:
    """The column names, None for a file that is not a readable CSV."""
    try:
        return csvio.read_header(path)
    except csvio.CsvError:
        return None


# ---------------------------------------------------------------------------
# Campaigns

@dataclass
class Campaign:
    kind: str             # "friction", "thermal", "engagement" or "breakaway"
    index: Path
    rows: list[dict]      # index rows: id, file (Path), and the other columns


def _is_index(path: Path) -> bool:
    header = _header(path)
    return header is not None and "id" in header and "file" in header


def _kind(index: Path) -> str:
    name = (index.parent.name + "/" + index.name).lower()
    if "thermal" in name:
        return "thermal"
    if "engagement" in name:
        return "engagement"
    if "breakaway" in name:
        return "breakaway"
    return "friction"


def _read_index(index: Path) -> Campaign:
    rows = []
    for line_no, row in csvio.read_records(index):
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
    header = _header(path)
    return header is not None and "t_s" in header and ("slip_rpm" in header
                                                       or any(h.startswith("slip_") for h in header))


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
        for p in csvs:   # a CSV that cannot be read (binary, empty, a directory) is named, not skipped
            try:
                csvio.read_header(p)
            except csvio.CsvError as e:
                raise IdentifyError(str(e)) from None
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
    for c, x in zip(MEASUREMENT_COLUMNS[1:], needed):
        if not np.isfinite(x).any():
            raise IdentifyError(f"{path}: column {c}: no finite value (every cell empty, NaN or infinite)")
    valid = finite_t & np.all(np.isfinite(np.vstack(needed)), axis=0)
    out = {"id": exp_id, "file": str(path), "dt": dt, "rows": int(t.size), "t0": float(t[0]), "t1": float(t[-1])}

    if purpose == "friction":
        out.update(prepare_friction(exp_id, t, cols, valid, dt, effective_radius, s))
    else:
        out.update(prepare_thermal(exp_id, t, cols, valid, dt, s))
    return out


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


def stack(prepared: list[dict], key: str) -> dict[str, np.ndarray]:
    """The prepared experiments' arrays under key, concatenated, with the experiment's index."""
    names = prepared[0][key].keys()
    out = {n: np.concatenate([p[key][n] for p in prepared]) for n in names}
    out["experiment"] = np.concatenate([np.full(p[key]["t_s"].size, i) for i, p in enumerate(prepared)])
    return out
