"""An experiment set run and written (``wetclutch bench``): measurement CSVs, CAN logs, index and viscosity
files, all or nothing."""
from __future__ import annotations

import os
import zlib
from pathlib import Path

import numpy as np

from ... import calibration
from ...calibration import Calibration
from ...reference import model
from ...util import atomic, canlog
from .experiments import (BREAKAWAY_THETAS_DEGC, CAMPAIGN_EVERY, CSV_COLUMNS, CSV_FORMATS, DEFAULT_SEED,
                          DEFAULT_TRUE, ENGAGEMENT_SLIPS_RPM, ENGAGEMENT_THETAS_DEGC, EXPERIMENTS, BenchConfig,
                          BenchError, Result, breakaway_experiments, check_seed, engagement_experiments,
                          table2_experiments, thermal_experiments)
from .simulation import simulate


# --------------------------------------------------------------------------- files

def _prepare_dir(out_dir) -> Path:
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".wetclutch-bench-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise BenchError(f"{out}: cannot write to the output directory: {e.strerror or e}") from None
    return out


def write_csv(path: Path, result: Result) -> None:
    """The measurement CSV: CSV_COLUMNS, rounded to CSV_FORMATS (no '-0.000')."""
    cols = [np.round(result.measured[c], int(f[2])) + 0.0 for c, f in zip(CSV_COLUMNS, CSV_FORMATS)]
    fmt = ",".join(CSV_FORMATS)
    lines = [",".join(CSV_COLUMNS)]
    lines += [fmt % tuple(row) for row in np.column_stack(cols).tolist()]
    atomic.write_text(path, "\n".join(lines) + "\n")


def write_log(path: Path, result: Result) -> int:
    """The frames the TCU receives (candump -L, 1 ms): TorqueRequest (Mode Open before
    contact, TorqueControl from contact on), BenchMeasurement, ClutchSensors."""
    if result.every != 1:
        raise BenchError(f"{path}: a CAN log needs every 1 ms step (rows every {result.every} steps)")
    m = result.measured
    msgs = canlog.input_log(result.t_s, m["slip_rpm"], m["theta_oil_degC"], m["theta_housing_degC"],
                            m["torque_request_Nm"], mode=result.mode,
                            bench={"load_cell_N": m["force_N"], "torque_Nm": m["torque_Nm"],
                                   "thermistor_degC": m["theta_clutch_degC"]})
    with atomic.atomic_path(path) as tmp:
        canlog.write_log(tmp, msgs)
    return len(msgs)


# The index columns of each kind (an index CSV lists a campaign's runs: `wetclutch identify` finds them by it).
_PRESSURE_kPa = ("pressure_kPa", lambda e, cal: f"{e.force_N / cal.friction_area * 1e-3:.1f}")
INDEX_COLUMNS = {
    "table2": (_PRESSURE_kPa, ("slip_rpm", lambda e, cal: f"{e.slip_rpm:.0f}"),
               ("loading_s", lambda e, cal: f"{e.loading_s:.0f}"), ("theta0_degC", lambda e, cal: f"{e.theta0_degC:.0f}")),
    "engagement": (_PRESSURE_kPa, ("slip_rpm", lambda e, cal: f"{e.slip_rpm:g}"),
                   ("theta0_degC", lambda e, cal: f"{e.theta0_degC:g}")),
    "breakaway": (_PRESSURE_kPa, ("theta0_degC", lambda e, cal: f"{e.theta0_degC:g}")),
}
INDEX_FILE = {"table2": "index.csv", "engagement": "engagement_index.csv", "breakaway": "breakaway_index.csv"}


def write_index(path: Path, cal: Calibration, results: list[Result], kind: str = "table2") -> None:
    """id, force_N, the kind's columns (INDEX_COLUMNS), file."""
    columns = INDEX_COLUMNS[kind]
    lines = [",".join(["id", "force_N", *(name for name, _ in columns), "file"])]
    for r in results:
        e = r.experiment
        lines.append(",".join([str(e.id), f"{e.force_N:.1f}", *(fmt(e, cal) for _, fmt in columns), f"{e.name}.csv"]))
    atomic.write_text(path, "\n".join(lines) + "\n")


def write_viscosity(path: Path, cal: Calibration, seed: int, noise: float = 0.01) -> None:
    """Viscosity points for the eq. 2 fit: the true curve with ~1% (1 sigma) noise, 10..120 degC."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(b"viscosity")]))
    theta = np.arange(10.0, 121.0, 10.0)
    mu = model.viscosity_Pa_s(cal, theta) * (1.0 + noise * rng.standard_normal(theta.size))
    atomic.write_text(path, "theta_degC,viscosity_Pa_s\n" + "".join(f"{t:.0f},{m:.6e}\n" for t, m in zip(theta, mu)))


def run(kind: str, out_dir, true_path=DEFAULT_TRUE, seed=DEFAULT_SEED, slips_rpm=None, logs: bool | None = None,
        every: int | None = None, config: BenchConfig = BenchConfig(), experiments=None, thetas_degC=None) -> dict:
    """Generate one experiment set into out_dir. Returns {'files': [...], 'results': [...]}.

    Defaults: the engagement writes CSV and log at 1 ms, at 40 and 80 degC
    (thetas_degC); the breakaway CSVs at 1 ms and breakaway_index.csv; table2
    and thermal write CSVs decimated to 10 ms (table2 also index.csv and
    viscosity.csv). CAN logs (with 1 ms CSVs) for the others only if asked:
    184 x 35 s at 1 ms would be about 19 million frames (0.8 GB, an hour of
    encoding), the thermal runs 1.4 million.
    """
    if kind not in EXPERIMENTS:
        raise BenchError(f"unknown experiment {kind!r}: expected one of {', '.join(EXPERIMENTS)}")
    seed = check_seed(seed)
    if slips_rpm is not None and kind != "engagement":
        raise BenchError(f"--slip applies to the engagement only, not to {kind}")
    if thetas_degC is not None and kind not in ("engagement", "breakaway"):
        raise BenchError(f"--theta applies to the engagement and the breakaway only, not to {kind}")
    true_cal = calibration.load(true_path)
    if experiments is None:
        if kind == "engagement":
            experiments = engagement_experiments(ENGAGEMENT_SLIPS_RPM if slips_rpm is None else slips_rpm,
                                                 ENGAGEMENT_THETAS_DEGC if thetas_degC is None else thetas_degC)
        elif kind == "breakaway":
            experiments = breakaway_experiments(thetas_degC=BREAKAWAY_THETAS_DEGC if thetas_degC is None
                                                else thetas_degC)
        elif kind == "table2":
            experiments = table2_experiments()
        else:
            experiments = thermal_experiments(seed)
    if logs is None:
        logs = kind == "engagement"
    if every is None:
        every = 1 if logs or kind in ("engagement", "breakaway") else CAMPAIGN_EVERY
    if logs and every != 1:
        raise BenchError("CAN logs need the 1 ms rows: use every=1 with logs")
    out = _prepare_dir(out_dir)
    results = simulate(true_cal, experiments, seed, config, every)
    files = []
    with atomic.Staged():   # all files or none (a full disk leaves no truncated CSV)
        for r in results:
            path = out / f"{r.experiment.name}.csv"
            write_csv(path, r)
            files.append(path)
            if logs:
                path = out / f"{r.experiment.name}.log"
                write_log(path, r)
                files.append(path)
        if kind in INDEX_FILE:
            path = out / INDEX_FILE[kind]
            write_index(path, true_cal, results, kind)
            files.append(path)
        if kind == "table2":
            path = out / "viscosity.csv"
            write_viscosity(path, true_cal, seed)
            files.append(path)
    return {"files": files, "results": results}
