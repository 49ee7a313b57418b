"""Steps film and static: the engagement edges (DESIGN 9) from engagement and breakaway runs.

film    the squeeze-film factor phi from the engagement runs: the torque of eq. 8 on the film state
        (model.FilmDynamics: D dh_bar/dt = -(F_app - F_c(h_bar)) h_bar^3, D = 3 pi phi mu_v K / 2), driven
        by the load cell, the measured slip and the observer's temperature (eq. 1 with the measured torque as
        heat input, as the firmware on a bench), fitted to the measured torque over the transient after
        contact (a one-parameter least squares in log phi). The period is divided into FILM_SUBSTEPS so the
        fit finds the continuous law's phi, not one biased by the firmware's 1 ms step.
static  the static friction factor from the breakaway runs: at the breakaway the shaft torque equals the
        static capacity, static factor mu_f(0, theta) R_eff N_c F_c (eq. 18 at v = 0 with the identified
        friction map), so each run gives the factor from the torque at breakaway (breakaway_torque), the
        load cell and the thermistor; the runs' mean, with a t interval over the runs.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.stats import t as student_t

from ..reference import model
from ..calibration import Calibration
from .campaign import MEASUREMENT_COLUMNS, OPTIONAL_COLUMNS, Campaign, read_table
from .settings import IdentifyError
from .statistics import confidence

TRANSIENT_S = 0.3          # the paper's transient: contact at 0.9 s, steady from 1.2 s (report.FILM_TRANSIENT_S)
SLIPPING_RPM = 10.0        # the transient ends at the lock
FILM_SUBSTEPS = 8          # the continuous law: 1/8 ms steps change the fitted phi by < 0.1 % (tests)
PHI_BOUNDS = (1e-3, 1.0)   # the search; the calibration takes 1e-4 .. 1
BREAKAWAY_SLIP_RPM = 5.0   # the hub has moved: the clutch broke away
RAMP_FIT_S = 0.06          # the line through the torque ramp before the breakaway
DROP_SIGMAS = 6.0          # the breakaway: the torque falls this far below the ramp's line


def read_runs(campaigns: list[Campaign], kind: str) -> list[dict]:
    """Every listed measurement CSV of the campaigns of this kind, as arrays, with the index's columns."""
    runs = []
    for c in campaigns:
        if c.kind != kind:
            continue
        for row in c.rows:
            path = Path(row["file"])
            if not path.is_file():
                raise IdentifyError(f"{c.index}: line {row['line']}: listed file {path} does not exist")
            cols = read_table(path, MEASUREMENT_COLUMNS, OPTIONAL_COLUMNS)
            bad = [k for k in MEASUREMENT_COLUMNS if not np.all(np.isfinite(cols[k]))]
            if bad:
                raise IdentifyError(f"{path}: column {bad[0]} has empty or non-finite cells: an {kind} run is used"
                                    " whole (its transient cannot be cut around a gap)")
            runs.append({"id": row["id"], "file": str(path), **{k: cols[k] for k in MEASUREMENT_COLUMNS}})
    return runs


def _stack(runs: list[dict], key: str) -> np.ndarray:
    """steps x runs, each run padded with its last value to the longest."""
    n = max(r[key].size for r in runs)
    return np.column_stack([np.concatenate([r[key], np.full(n - r[key].size, r[key][-1])]) for r in runs])


def film_inputs(runs: list[dict], cal: Calibration, force_min_N: float = 50.0) -> dict:
    """What the film fit needs, steps x runs: force, slip, observer temperature, measured torque, the window."""
    if not runs:
        raise IdentifyError("film: no engagement runs (an index CSV in a directory or file named 'engagement')")
    dt = np.array([float(np.median(np.diff(r["t_s"]))) for r in runs])
    if np.any(np.abs(dt / cal.period - 1.0) > 1e-3):
        raise IdentifyError(f"film: the engagement runs are sampled every {dt.max():g} s; the film state steps"
                            f" every control period ({cal.period:g} s): record at that rate")
    force = np.maximum(_stack(runs, "force_N"), 0.0)
    slip = _stack(runs, "slip_rpm")
    torque = _stack(runs, "torque_Nm")
    theta = _stack([{"x": model.thermal_observer(cal, r["slip_rpm"], r["torque_Nm"], r["theta_oil_degC"],
                                                 r["theta_housing_degC"],
                                                 theta_start_degC=float(r["theta_clutch_degC"][0]))}
                    for r in runs], "x")
    t = _stack(runs, "t_s")
    window = np.zeros(force.shape, bool)
    for j, r in enumerate(runs):
        on = np.flatnonzero(force[:, j] > force_min_N)
        if on.size == 0:
            raise IdentifyError(f"{r['file']}: the load cell never exceeds {force_min_N:g} N: no contact")
        t_contact = t[on[0], j]
        window[:, j] = (t[:, j] >= t_contact) & (t[:, j] < t_contact + TRANSIENT_S) & (np.abs(slip[:, j]) > SLIPPING_RPM)
    return {"force": force, "slip": slip, "theta": theta, "torque": torque, "window": window}


def film_torque(cal: Calibration, fd: model.FilmDynamics, x: dict, phi: float, substeps: int = FILM_SUBSTEPS):
    """Model torque (steps x runs) with the film state at phi (0: the steady film of eq. 16)."""
    hbar, contact = fd.run(x["force"], x["theta"], phi, substeps=substeps)
    return model.torque_at_film_Nm(cal, x["slip"], x["theta"], contact, hbar)


def identify_film(runs: list[dict], cal: Calibration) -> dict:
    x = film_inputs(runs, cal)
    fd = model.FilmDynamics(cal)
    w = x["window"]
    measured = x["torque"][w]

    def residual(phi):
        return film_torque(cal, fd, x, phi)[w] - measured

    def sse(log_phi):
        r = residual(10.0 ** log_phi)
        return float(r @ r)

    best = minimize_scalar(sse, bounds=tuple(math.log10(b) for b in PHI_BOUNDS), method="bounded",
                           options={"xatol": 1e-5})
    phi = 10.0 ** float(best.x)
    if phi >= 0.98 * PHI_BOUNDS[1] or phi <= 1.02 * PHI_BOUNDS[0]:
        raise IdentifyError(f"film: the fitted phi {phi:.4g} sits on the search bound {PHI_BOUNDS}: the engagement"
                            " transient does not determine it")
    res = residual(phi)
    step = 1e-3 * phi
    jac = ((residual(phi + step) - residual(phi - step)) / (2.0 * step))[:, None]
    groups = np.broadcast_to(np.arange(w.shape[1]), w.shape)[w]
    ci, rho, _, method = confidence(jac, res, groups)
    steady = film_torque(cal, fd, x, 0.0)
    fitted = film_torque(cal, fd, x, phi)
    per_run = []
    for j, r in enumerate(runs):
        m = w[:, j]
        per_run.append({"id": r["id"], "samples": int(m.sum()),
                        "transient_max_error_steady_Nm": float(np.max(np.abs(steady[m, j] - x["torque"][m, j]))),
                        "transient_max_error_film_Nm": float(np.max(np.abs(fitted[m, j] - x["torque"][m, j])))})
    return {
        "values": {"film_squeeze_factor": phi},
        "ci95": {"film_squeeze_factor": float(ci[0])},
        "ci_method": method, "residual_rho": rho,
        "rmse_Nm": float(np.sqrt(np.mean(res * res))),
        "rmse_steady_Nm": float(np.sqrt(np.mean((steady[w] - measured) ** 2))),
        "samples": int(w.sum()), "runs": per_run, "substeps": FILM_SUBSTEPS,
        "reynolds_factor_m4": fd.reynolds_m4,
    }


def breakaway_torque(r: dict) -> dict:
    """The torque at breakaway of one run. Locked, the shaft torque follows the drive's ramp; at breakaway it
    drops to the kinetic torque at zero speed (the static factor's excess) while the hub only starts to move,
    so the breakaway is the first drop of the torque below the ramp's line by DROP_SIGMAS of its scatter,
    and the torque there is the line's value, refitted over the ramp's last RAMP_FIT_S (the noisy maximum
    would be biased up). Without a drop (a static factor of 1), the line's value where the slip first
    exceeds BREAKAWAY_SLIP_RPM."""
    slip = np.abs(r["slip_rpm"])
    torque = np.abs(r["torque_Nm"])
    t = r["t_s"]
    moved = np.flatnonzero(slip > BREAKAWAY_SLIP_RPM)
    if moved.size == 0:
        raise IdentifyError(f"{r['file']}: the slip never exceeds {BREAKAWAY_SLIP_RPM:g} rpm: no breakaway")
    dt = float(np.median(np.diff(t)))
    t_move = t[moved[0]]
    ramp = (t >= t_move - 0.5) & (t < t_move - 0.25)
    if ramp.sum() < 20 or np.ptp(torque[ramp]) < 1.0:
        raise IdentifyError(f"{r['file']}: no rising torque ramp in the 0.5 s before the slip starts")
    slope, offset = np.polyfit(t[ramp], torque[ramp], 1)
    scatter = float(np.std(torque[ramp] - (slope * t[ramp] + offset)))
    smooth = np.convolve(torque, np.ones(3) / 3.0, mode="same")
    after = np.flatnonzero((t >= t_move - 0.25) & (t <= t_move) &
                           (smooth < slope * t + offset - DROP_SIGMAS * scatter / math.sqrt(3.0)))
    k = int(after[0]) - 1 if after.size else int(moved[0])  # the last sample before the drop (smoothing: +-1)
    fit = (t >= t[k] - RAMP_FIT_S) & (t < t[k] - 2.0 * dt)
    slope, offset = np.polyfit(t[fit], torque[fit], 1)
    before = (t >= t[k] - 0.3) & (t < t[k] - 0.05)
    return {"torque_Nm": float(slope * t[k] + offset), "t_s": float(t[k]), "ramp_Nm_s": float(slope),
            "force_N": float(np.median(r["force_N"][before])),
            "theta_degC": float(np.median(r["theta_clutch_degC"][before])), "drop": bool(after.size)}


def identify_static(runs: list[dict], cal: Calibration) -> dict:
    if len(runs) < 2:
        raise IdentifyError(f"static: {len(runs)} breakaway run(s); at least 2 are needed for an interval")
    rows = []
    for r in runs:
        b = breakaway_torque(r)
        per_N = float(model.static_capacity_Nm(cal.with_values(static_friction_factor=1.0), b["theta_degC"], 1.0))
        rows.append({"id": r["id"], **b, "static_factor": b["torque_Nm"] / (per_N * b["force_N"])})
    f = np.array([row["static_factor"] for row in rows])
    n = f.size
    half = float(student_t.ppf(0.975, n - 1) * np.std(f, ddof=1) / math.sqrt(n))
    return {"values": {"static_friction_factor": float(np.mean(f))},
            "ci95": {"static_friction_factor": half},
            "ci_method": f"t interval over {n} breakaway runs", "runs": rows,
            "spread_rel": float(np.ptp(f) / np.mean(f))}
