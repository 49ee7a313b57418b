"""The comparison (issue 13): the scenario matrix x controllers, the feedback gains' search, the targets,
shift_report.md, metrics.json, the plots and the kept runs' frames as MDF4 (``wetclutch shift``)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..calibration import shift as shift_calibration
from ..simulate import plant as plant_mod
from ..util import mdf
from ..util.atomic import Staged
from .plots import plot_case
from .quality import quality, worst
from .runner import record_messages, run_case
from .scenarios import NOMINAL, SHIFT_TOML, TARGET_INERTIA_S, scenario_matrix


# ---------------------------------------------------------------------------------------------------------
# The comparison (issue 13): scenario matrix x controllers, targets, report.

INERTIA_TOLERANCE = 0.05         # (c) inertia phase within +-5 % of its target at every oil temperature
JERK_LIMIT_M_S3 = 10.0           # (c) peak jerk in the nominal scenario (comfort limit about 10-12 m/s^3)
PRESSURE_RATIO_TARGET = 3.0      # pressure tracking RMSE without / with the lag compensation


FEEDBACK_KP = (1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0)
FEEDBACK_KI = (10.0, 20.0, 40.0, 80.0, 160.0, 320.0, 640.0)


def tune_feedback(plant_path=plant_mod.DEFAULT_PLANT, kps=FEEDBACK_KP, kis=FEEDBACK_KI) -> dict:
    """The fair tuning of (a): every (kp, ki) of the grid on the nominal scenario; the best is the lowest slip
    RMSE among the shifts that complete without flare or tie-up. Returns {"grid": [...], "best": {...}}."""
    params = plant_mod.load_plant(plant_path)
    cal = shift_calibration.load(SHIFT_TOML).variants["feedback"]
    nominal = next(s for s in scenario_matrix() if s.name == NOMINAL)
    grid = []
    for kp in kps:
        for ki in kis:
            q = quality(run_case(params, "shift_1_2_feedback", nominal, shift_cal=cal,
                                 overrides={"kp_Nm_per_rad_s": kp, "ki_Nm_per_rad": ki})[0])
            grid.append({"kp": kp, "ki": ki, **{k: q[k] for k in ("slip_rmse_rpm", "peak_jerk_m_s3",
                                                                   "inertia_time_error", "flare", "tie_up", "abort")}})
    fair = [g for g in grid if g["abort"] == 0 and not g["flare"] and not g["tie_up"]]
    best = min(fair or grid, key=lambda g: g["slip_rmse_rpm"])
    return {"grid": grid, "best": best, "criterion": "lowest slip RMSE on the nominal scenario, no flare, tie-up or abort"
            + ("" if fair else " (none qualified: lowest slip RMSE overall)")}


def run_matrix(plant_path=plant_mod.DEFAULT_PLANT, controllers=("feedback", "blind", "full"),
               scenarios=None, keep_records=("oil80", "oil20", "soak")) -> dict:
    """Every controller on every scenario (in-process); returns {"cases": {controller: {scenario: quality}},
    "records": {(controller, scenario): [records]}} (records kept only for keep_records)."""
    params = plant_mod.load_plant(plant_path)
    cal_set = shift_calibration.load(SHIFT_TOML)
    scenarios = scenarios or scenario_matrix()
    cases, records = {}, {}
    for ctrl in controllers:
        cases[ctrl] = {}
        for sc in scenarios:
            recs = run_case(params, f"shift_1_2_{ctrl}", sc, shift_cal=cal_set.variants[ctrl])
            qs = [quality(r) for r in recs]
            cases[ctrl][sc.name] = worst(qs)
            if sc.shifts > 1:
                cases[ctrl][sc.name]["per_shift"] = qs
            if sc.name in keep_records:
                records[(ctrl, sc.name)] = recs
    return {"plant": str(plant_path), "scenarios": [sc.__dict__ for sc in scenarios], "cases": cases,
            "records": records}


def targets(cases: dict, nolag: dict | None) -> dict:
    """Issue 13's targets from the matrix: {name: {"met": bool, "detail": ...}}."""
    out = {}
    full, a, b = cases["full"], cases.get("feedback", {}), cases.get("blind", {})
    ratios = {}
    for sc, q in full.items():
        ra = {k: (a[sc][k] / q[k] if q[k] > 0 else float("inf")) for k in ("slip_rmse_rpm", "peak_jerk_m_s3")} if sc in a else {}
        rb = {k: (b[sc][k] / q[k] if q[k] > 0 else float("inf")) for k in ("slip_rmse_rpm", "peak_jerk_m_s3")} if sc in b else {}
        ratios[sc] = {"vs_a": ra, "vs_b": rb}
    beats = all(v > 1.0 for r in ratios.values() for side in r.values() for v in side.values())
    out["c_beats_a_and_b"] = {"met": beats, "ratios": ratios,
                              "what": "(c) lower slip RMSE and peak jerk than (a) and (b) in every scenario"}
    oil = {sc: q["inertia_time_error"] for sc, q in full.items() if sc.startswith("oil")}
    out["c_inertia_time_within_5pct"] = {"met": all(math.isfinite(e) and abs(e) <= INERTIA_TOLERANCE for e in oil.values()),
                                         "errors": oil}
    nominal = full.get(NOMINAL)
    out["c_nominal_jerk_le_10"] = {"met": bool(nominal and nominal["peak_jerk_m_s3"] <= JERK_LIMIT_M_S3),
                                   "peak_jerk_m_s3": nominal["peak_jerk_m_s3"] if nominal else None}
    bad = {sc: [k for k in ("flare", "tie_up") if q[k]] + ([q["abort_reason"]] if q["abort"] != 0 else [])
           for sc, q in full.items()}
    out["c_no_flare_tieup_abort"] = {"met": not any(bad.values()), "problems": {k: v for k, v in bad.items() if v}}
    if nolag is not None and NOMINAL in full:
        with_lc, without = full[NOMINAL]["pressure_rmse_kPa"], nolag["pressure_rmse_kPa"]
        out["lag_compensation_3x"] = {"met": without >= PRESSURE_RATIO_TARGET * with_lc, "with_kPa": with_lc,
                                      "without_kPa": without, "ratio": without / with_lc if with_lc > 0 else float("inf")}
    return out


def _fmt(x, nd=1):
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(x)
    return "n/a" if not math.isfinite(x) else f"{x:.{nd}f}"


def markdown(cases: dict, tg: dict) -> str:
    lines = ["# 1->2 upshift: (a) feedback only, (b) 2-DOF thermal-blind, (c) 2-DOF full model", "",
             "Quality per controller and scenario, from the plant's truth (tools/wetclutch/shift/quality.py); the heat soak"
             " row is the worst of its shifts.", "",
             "| scenario | ctrl | inertia s (err %) | slip RMSE rpm | peak jerk m/s^3 | energy kJ | peak theta degC"
             " (est.) | p RMSE kPa | flare | tie-up | end |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    names = list(next(iter(cases.values())).keys())
    for sc in names:
        for ctrl, label in (("feedback", "a"), ("blind", "b"), ("full", "c")):
            if ctrl not in cases:
                continue
            q = cases[ctrl][sc]
            lines.append(f"| {sc} | {label} | {_fmt(q['inertia_time_s'], 3)} ({_fmt(100 * q['inertia_time_error'])}) |"
                         f" {_fmt(q['slip_rmse_rpm'])} | {_fmt(q['peak_jerk_m_s3'])} | {_fmt(q['friction_energy_kJ'], 2)} |"
                         f" {_fmt(q['peak_theta_degC'])} ({_fmt(q['peak_theta_estimate_degC'])}) |"
                         f" {_fmt(q['pressure_rmse_kPa'])} | {_fmt(q['flare'])} | {_fmt(q['tie_up'])} | {q['abort_reason']} |")
    lines += ["", "## Ratios (a)/(c) and (b)/(c): > 1 means (c) is better", "",
              "| scenario | slip RMSE a/c | jerk a/c | slip RMSE b/c | jerk b/c |", "|---|---|---|---|---|"]
    for sc, r in tg["c_beats_a_and_b"]["ratios"].items():
        lines.append(f"| {sc} | {_fmt(r['vs_a'].get('slip_rmse_rpm', float('nan')), 2)} |"
                     f" {_fmt(r['vs_a'].get('peak_jerk_m_s3', float('nan')), 2)} |"
                     f" {_fmt(r['vs_b'].get('slip_rmse_rpm', float('nan')), 2)} |"
                     f" {_fmt(r['vs_b'].get('peak_jerk_m_s3', float('nan')), 2)} |")
    lines += ["", "## Targets", ""]
    for name, t in tg.items():
        detail = {k: v for k, v in t.items() if k not in ("met", "ratios")}
        lines.append(f"- **{name}**: {'met' if t['met'] else 'MISSED'} {json.dumps(detail, default=float)[:400]}")
    return "\n".join(lines) + "\n"


def report(out_dir: Path, plant_path=plant_mod.DEFAULT_PLANT, scenarios=None) -> dict:
    """Run the comparison and write metrics.json, shift_report.md and the Fig. 4-style plots."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    res = run_matrix(plant_path, scenarios=scenarios)
    params = plant_mod.load_plant(plant_path)
    cal_set = shift_calibration.load(SHIFT_TOML)
    nominal = next((sc for sc in (scenarios or scenario_matrix()) if sc.name == NOMINAL), None)
    nolag = None
    if nominal is not None:
        nolag_recs = run_case(params, "shift_1_2_nolag", nominal, shift_cal=cal_set.variants["nolag"])
        nolag = quality(nolag_recs[0])
        res["records"][("nolag", NOMINAL)] = nolag_recs
    tg = targets(res["cases"], nolag)
    plots = []
    for sc in ("oil80", "oil20", "soak"):
        runs = {ctrl: recs[-1] for (ctrl, name), recs in res["records"].items() if name == sc}
        if runs:
            path = out_dir / f"shift_{sc}.png"
            plot_case(path, runs, f"1->2 upshift, scenario {sc} ({Path(plant_path).name})"
                      + (" - last shift of the soak" if sc == "soak" else ""))
            plots.append(str(path))
    metrics = {"plant": str(plant_path), "target_inertia_s": TARGET_INERTIA_S, "cases": res["cases"],
               "nolag_nominal": nolag, "targets": tg, "plots": plots,
               "missed": [k for k, t in tg.items() if not t["met"]]}
    with Staged() as staged:   # the MDF4 files, metrics.json and shift_report.md: all or none
        metrics["mdf"] = write_mdf(out_dir, res["records"], Path(plant_path).name)
        staged.write_text(out_dir / "metrics.json", json.dumps(metrics, indent=1, default=float, sort_keys=True))
        staged.write_text(out_dir / "shift_report.md", markdown(res["cases"], tg) + _mdf_paragraph(metrics["mdf"]))
    return metrics


def mdf_name(scenario: str, controller: str) -> str:
    return f"shift_{scenario}_{controller}.mf4"


def write_mdf(out_dir: Path, records: dict, plant_name: str) -> list[str]:
    """One MDF4 file per kept run (controller x scenario, runner.record_messages: the frames both ways of
    every shift of the run, decoded by the DBC, util/mdf.py) in out_dir; returns their paths."""
    written = []
    for (ctrl, sc), recs in sorted(records.items(), key=lambda item: (item[0][1], item[0][0])):
        path = out_dir / mdf_name(sc, ctrl)
        mdf.write(path, record_messages(recs), f"1->2 upshift, scenario {sc}, controller {ctrl}, plant {plant_name}"
                  f" ({len(recs)} shift(s), the time between them left out)")
        written.append(str(path))
    return written


def _mdf_paragraph(paths: list[str]) -> str:
    return ("\n## Signals (MDF4)\n\nThe frames both ways of each kept run (what the TCU received and sent, every"
            " shift of the run; the idle time between the soak's shifts is not kept), one file per controller and"
            " scenario, one channel group per frame, physical values and units from hil/wetclutch.dbc: "
            + ", ".join(Path(p).name for p in paths) + ".\n")
