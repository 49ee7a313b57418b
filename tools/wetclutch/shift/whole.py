"""The whole shift (issue 22, DESIGN 14): fill, the off-going clutch under the TCU's control, the engine torque
intervention and the fallback of a lost input, on a family of vehicles (``wetclutch shift``).

Each vehicle is a plant file in tools/plants/vehicles/ (``extends`` the base plant) and the TCU's driveline
model of it is the generated tools/calibrations/vehicles/<vehicle>.toml (``wetclutch vehicle-cal``), passed to
the firmware as shift calibration overrides (wc_replay --set) on the whole_* variants of
tools/calibrations/shift_1_2.toml: (a) whole_feedback, (b) whole_blind, (c) whole_full.

Scenarios: issue 13's matrix (oil 20..110 degC, load 25/50 %, plant friction -/+10 %, heat soak) plus the
engine ignoring the request, the off-going clutch's friction -/+20 % (a model error of the off-going clutch),
the scripted release of issue 13 (for comparison; the TCU's off-going command is then not used) and the
faults of scenarios.FAULTS (a lost input in the torque and the inertia phase).

Targets (TARGETS, checked by targets()):
  nominal_jerk_le_10      (c), nominal vehicle, nominal scenario: peak jerk <= 10 m/s^3
  engine_ignores_jerk_le_12  the same with the engine ignoring the request: <= 12 m/s^3
  no_flare_no_tie_up      (c), every vehicle x every scenario (faults and the scripted release apart): flare
                          <= 30 rpm, tie-up <= 10 % of the turbine torque, no abort
  family_jerk_le_12       (c), every vehicle, nominal scenario: peak jerk <= 12 m/s^3
  inertia_within_5pct     (c), nominal vehicle, every oil temperature: inertia phase within +-5 % of target
  energy_20pct_lower      (c), nominal vehicle: the on-coming clutch's friction energy with the intervention at
                          least 20 % below the same shift with the engine ignoring it
  c_beats_a_and_b         nominal vehicle, every scenario of issue 13's matrix: (c) lower slip RMSE and peak
                          jerk than (a) and (b)
  faults                  torque phase: handed back (1st gear, AbortReason 3, fallback 2), no flare; inertia
                          phase: finished on the model (2nd gear, fallback 1), no flare; longer than
                          fallback_time_s: released (fallback 3); lost early in the inertia phase and back:
                          locked in 2nd by the plant's truth (the finish looks at the slip again)
"""
from __future__ import annotations

import json
import math
import tomllib
from multiprocessing import Pool
from pathlib import Path

import numpy as np

from ..calibration import shift as shift_calibration
from ..simulate import plant as plant_mod
from ..util import mdf
from ..util.atomic import Staged
from .comparison import _fmt
from .plots import plot_whole_case
from .quality import quality, worst
from .runner import record_messages, run_case
from .scenarios import FAULTS, NOMINAL, ROOT, SHIFT_TOML, TARGET_INERTIA_S, Scenario, scenario_matrix

VEHICLES_DIR = ROOT / "tools" / "plants" / "vehicles"
VEHICLE_CALS_DIR = ROOT / "tools" / "calibrations" / "vehicles"
VEHICLES = ("nominal", "soft", "stiff", "light", "heavy", "torque350", "step1.3", "step1.75", "newuser")
NOMINAL_VEHICLE = "nominal"
CONTROLLERS = {"a": "whole_feedback", "b": "whole_blind", "c": "whole_full"}
FULL = CONTROLLERS["c"]

JERK_WITH_ENGINE_M_S3 = 10.0
JERK_WITHOUT_ENGINE_M_S3 = 12.0
FAMILY_JERK_M_S3 = 12.0
FLARE_MAX_RPM = 30.0
TIE_UP_MAX_FRACTION = 0.10
INERTIA_TOLERANCE = 0.05
ENERGY_CUT = 0.20
FALLBACK_NAMES = {0: "none", 1: "finished on the model", 2: "handed back", 3: "released"}
GEAR_NAMES = {0: "neutral", 1: "1st", 2: "2nd"}


def whole_scenarios() -> list[Scenario]:
    """Issue 13's matrix plus the whole shift's own rows (module docstring), faults apart (fault_scenarios)."""
    return scenario_matrix() + [
        Scenario("engine_ignores", 80.0, 1.0, engine_ignores=True, group="engine"),
        Scenario("offgoing-20pct", 80.0, 1.0, offgoing_friction=0.8, group="offgoing"),
        Scenario("offgoing+20pct", 80.0, 1.0, offgoing_friction=1.2, group="offgoing"),
        Scenario("scripted_release", 80.0, 1.0, scripted_release=True, group="scripted"),
    ]


def fault_scenarios() -> list[Scenario]:
    return [Scenario(f"fault_{name}", 80.0, 1.0, fault=name, group="fault") for name in FAULTS]


def plant_path(vehicle: str) -> Path:
    return VEHICLES_DIR / f"{vehicle}.toml"


def vehicle_overrides(vehicle: str) -> dict:
    """The TCU's driveline model of the vehicle, {C field: value}, from its generated shift calibration."""
    path = VEHICLE_CALS_DIR / f"{vehicle}.toml"
    with open(path, "rb") as f:
        table = tomllib.load(f)["shift"]
    c_field = {name: c for name, _, c, _ in shift_calibration.FIELDS}
    return {c_field[name]: float(entry["value"]) for name, entry in table.items()}


def _run(job):
    """One (vehicle, controller, scenario) in a worker: its quality (the worst of a soak) and its records."""
    vehicle, controller, scenario = job
    params = plant_mod.load_plant(plant_path(vehicle))
    cal = shift_calibration.load(SHIFT_TOML).variants[controller]
    recs = run_case(params, f"shift_1_2_{controller}", scenario, overrides=vehicle_overrides(vehicle), shift_cal=cal)
    qs = [quality(r) for r in recs]
    q = worst(qs)
    q["turbine_torque_Nm"] = params.turbine_torque_full * scenario.load
    return job, q, recs


def jobs(vehicles=VEHICLES, comparison=True) -> list[tuple]:
    """(vehicle, controller, scenario): (c) on every vehicle x scenario (faults on the nominal vehicle), (a) and
    (b) on the nominal vehicle's scenarios (the comparison)."""
    out = []
    for v in vehicles:
        for sc in whole_scenarios() + (fault_scenarios() if v == NOMINAL_VEHICLE else []):
            out.append((v, FULL, sc))
            if comparison and v == NOMINAL_VEHICLE and sc.group not in ("fault", "scripted"):
                out += [(v, CONTROLLERS["a"], sc), (v, CONTROLLERS["b"], sc)]
    return out


KEEP = {(NOMINAL_VEHICLE, NOMINAL), (NOMINAL_VEHICLE, "engine_ignores"), (NOMINAL_VEHICLE, "scripted_release"),
        (NOMINAL_VEHICLE, "fault_torque"), (NOMINAL_VEHICLE, "fault_inertia"), ("newuser", NOMINAL)}


def run_all(vehicles=VEHICLES, comparison=True, processes=2) -> dict:
    """Every job (jobs()) in a pool; {"cases": {vehicle: {controller: {scenario: quality}}}, "records": {...}}
    (records kept for KEEP)."""
    cases, records = {}, {}
    todo = jobs(vehicles, comparison)
    with Pool(processes) as pool:
        for (v, ctrl, sc), q, recs in pool.imap(_run, todo):
            cases.setdefault(v, {}).setdefault(ctrl, {})[sc.name] = q
            if (v, sc.name) in KEEP:
                records[(v, ctrl, sc.name)] = recs
    return {"cases": cases, "records": records}


def _bad(q) -> list[str]:
    out = []
    if q["flare_rpm"] > FLARE_MAX_RPM:
        out.append(f"flare {q['flare_rpm']:.0f} rpm")
    if q.get("tie_up_fraction", 0.0) > TIE_UP_MAX_FRACTION:
        out.append(f"tie-up {100 * q['tie_up_fraction']:.1f} %")
    if q["abort"] != 0:
        out.append(q["abort_reason"])
    return out


def targets(cases: dict) -> dict:
    """The issue's targets from the cases (module docstring): {name: {"met": bool, ...}}."""
    tg = {}
    nom = cases.get(NOMINAL_VEHICLE, {}).get(FULL, {})
    if NOMINAL in nom:
        j = nom[NOMINAL]["peak_jerk_m_s3"]
        tg["nominal_jerk_le_10"] = {"met": j <= JERK_WITH_ENGINE_M_S3, "peak_jerk_m_s3": j}
    if "engine_ignores" in nom:
        j = nom["engine_ignores"]["peak_jerk_m_s3"]
        tg["engine_ignores_jerk_le_12"] = {"met": j <= JERK_WITHOUT_ENGINE_M_S3 and nom["engine_ignores"]["abort"] == 0,
                                           "peak_jerk_m_s3": j, "abort": nom["engine_ignores"]["abort_reason"]}
    problems = {}
    for v, by_ctrl in cases.items():
        for sc, q in by_ctrl.get(FULL, {}).items():
            if sc.startswith("fault_") or sc == "scripted_release":
                continue
            if _bad(q):
                problems[f"{v}/{sc}"] = _bad(q)
    tg["no_flare_no_tie_up"] = {"met": not problems, "problems": problems}
    family = {v: by_ctrl[FULL][NOMINAL]["peak_jerk_m_s3"] for v, by_ctrl in cases.items() if NOMINAL in by_ctrl.get(FULL, {})}
    tg["family_jerk_le_12"] = {"met": all(j <= FAMILY_JERK_M_S3 for j in family.values()), "peak_jerk_m_s3": family}
    oil = {sc: q["inertia_time_error"] for sc, q in nom.items() if sc.startswith("oil")}
    tg["inertia_within_5pct"] = {"met": bool(oil) and all(math.isfinite(e) and abs(e) <= INERTIA_TOLERANCE
                                                          for e in oil.values()), "errors": oil}
    if NOMINAL in nom and "engine_ignores" in nom:
        e_with, e_without = nom[NOMINAL]["friction_energy_kJ"], nom["engine_ignores"]["friction_energy_kJ"]
        i_with, i_without = nom[NOMINAL]["inertia_energy_kJ"], nom["engine_ignores"]["inertia_energy_kJ"]
        tg["energy_20pct_lower"] = {"met": e_with <= (1.0 - ENERGY_CUT) * e_without, "with_kJ": e_with,
                                    "without_kJ": e_without, "change": e_with / e_without - 1.0,
                                    "inertia_phase_change": i_with / i_without - 1.0}
    by = cases.get(NOMINAL_VEHICLE, {})
    if all(c in by for c in CONTROLLERS.values()):
        ratios, lost = {}, []
        for sc in (s.name for s in scenario_matrix()):
            r = {}
            for other in ("a", "b"):
                for key in ("slip_rmse_rpm", "peak_jerk_m_s3"):
                    mine, theirs = by[FULL][sc][key], by[CONTROLLERS[other]][sc][key]
                    r[f"{key}_{other}/c"] = theirs / mine if mine > 0 else float("inf")
                    if not theirs > mine:
                        lost.append(f"{sc}: {key} vs ({other})")
            ratios[sc] = r
        tg["c_beats_a_and_b"] = {"met": not lost, "lost": lost, "ratios": ratios}
    faults = {}
    expect = {"fault_torque": (2, 1), "fault_inertia": (1, 2), "fault_inertia_long": (3, None),
              "fault_inertia_early": (1, 2)}
    for sc, (fallback, gear) in expect.items():
        if sc in nom:
            q = nom[sc]
            ok = q["fallback"] == fallback and (gear is None or (q["gear"] == gear and q["flare_rpm"] <= FLARE_MAX_RPM))
            faults[sc] = {"ok": ok, "fallback": FALLBACK_NAMES[q["fallback"]], "gear": GEAR_NAMES[q["gear"]],
                          "flare_rpm": q["flare_rpm"], "abort": q["abort_reason"],
                          "expected": f"{FALLBACK_NAMES[fallback]}" + (f", {GEAR_NAMES[gear]} gear, no flare" if gear else "")}
    if faults:
        tg["faults"] = {"met": all(f["ok"] for f in faults.values()), "rows": faults}
    return tg


def markdown(cases: dict, tg: dict) -> str:
    lines = ["# The whole 1->2 upshift (issue 22, DESIGN 14)", "",
             "From the plants' truth (tools/wetclutch/shift/quality.py). Jerk: the vehicle's, 10 Hz; torque phase from"
             " the command to the inertia phase, inertia phase from there to synchronism. Tie-up: the largest torque"
             " the off-going clutch carries against the shift, % of the turbine torque. Flare: turbine above the 1st-gear"
             " speed. Energy: friction energy of the on-coming / off-going clutch from the command on.", ""]
    head = ("| vehicle | scenario | ctrl | jerk total / torque ph. / inertia ph. m/s^3 | inertia s (err %) | slip RMSE rpm"
            " | tie-up % | flare rpm | energy on / off kJ | engine min..max Nm | fallback | end |")
    for title, rows in (("Nominal vehicle, the three controllers", [(NOMINAL_VEHICLE, c) for c in ("a", "b", "c")]),
                        ("Every vehicle, (c)", [(v, "c") for v in cases if v != NOMINAL_VEHICLE])):
        lines += [f"## {title}", "", head, "|" + "---|" * 12]
        for v, label in rows:
            ctrl = CONTROLLERS[label]
            for sc, q in cases.get(v, {}).get(ctrl, {}).items():
                lines.append(
                    f"| {v} | {sc} | {label} | {_fmt(q['peak_jerk_m_s3'])} / {_fmt(q.get('torque_phase_jerk_m_s3', float('nan')))}"
                    f" / {_fmt(q['peak_inertia_jerk_m_s3'])} | {_fmt(q['inertia_time_s'], 3)} ({_fmt(100 * q['inertia_time_error'])})"
                    f" | {_fmt(q['slip_rmse_rpm'])} | {_fmt(100 * q.get('tie_up_fraction', float('nan')))} | {_fmt(q['flare_rpm'], 0)}"
                    f" | {_fmt(q['friction_energy_kJ'], 2)} / {_fmt(q.get('offgoing_energy_kJ', float('nan')), 2)}"
                    f" | {_fmt(q.get('engine_torque_min_Nm', float('nan')), 0)}..{_fmt(q.get('engine_torque_max_Nm', float('nan')), 0)}"
                    f" | {FALLBACK_NAMES.get(q.get('fallback', 0), '?')} | {q['abort_reason']}, {GEAR_NAMES.get(q.get('gear', 0), '?')} |")
        lines.append("")
    if "c_beats_a_and_b" in tg:
        lines += ["## Ratios (a)/(c) and (b)/(c), nominal vehicle: > 1 means (c) is better", "",
                  "| scenario | slip RMSE a/c | jerk a/c | slip RMSE b/c | jerk b/c |", "|---|---|---|---|---|"]
        for sc, r in tg["c_beats_a_and_b"]["ratios"].items():
            lines.append(f"| {sc} | {_fmt(r['slip_rmse_rpm_a/c'], 2)} | {_fmt(r['peak_jerk_m_s3_a/c'], 2)} |"
                         f" {_fmt(r['slip_rmse_rpm_b/c'], 2)} | {_fmt(r['peak_jerk_m_s3_b/c'], 2)} |")
        lines.append("")
    lines += ["## Targets", ""]
    for name, t in tg.items():
        detail = {k: v for k, v in t.items() if k not in ("met", "ratios")}
        lines.append(f"- **{name}**: {'met' if t['met'] else 'MISSED'} {json.dumps(detail, default=float)[:600]}")
    return "\n".join(lines) + "\n"


def report(out_dir: Path, vehicles=VEHICLES, comparison=True, processes=2) -> dict:
    """Run everything, write metrics.json, whole_shift_report.md, the plots and the kept runs' MDF4 files."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    res = run_all(vehicles, comparison, processes)
    tg = targets(res["cases"])
    plots = []
    for v, sc, title in ((NOMINAL_VEHICLE, NOMINAL, "nominal vehicle, nominal scenario, (a) (b) (c)"),
                         (NOMINAL_VEHICLE, "engine_ignores", "nominal vehicle, the engine ignores the request"),
                         (NOMINAL_VEHICLE, "scripted_release", "nominal vehicle, scripted off-going release (issue 13)"),
                         (NOMINAL_VEHICLE, "fault_torque", "nominal vehicle, input lost in the torque phase"),
                         (NOMINAL_VEHICLE, "fault_inertia", "nominal vehicle, input lost in the inertia phase"),
                         ("newuser", NOMINAL, "the new user's vehicle (2000 kg, soft, step 1.75, 320 Nm)")):
        runs = {ctrl: recs[-1] for (vv, ctrl, name), recs in res["records"].items() if vv == v and name == sc}
        if runs:
            path = out_dir / f"whole_{v}_{sc}.png"
            plot_whole_case(path, runs, f"1->2 upshift, whole shift: {title}")
            plots.append(str(path))
    metrics = {"vehicles": list(vehicles), "target_inertia_s": TARGET_INERTIA_S, "cases": res["cases"], "targets": tg,
               "plots": plots, "missed": [k for k, t in tg.items() if not t["met"]]}
    with Staged() as staged:
        written = []
        for (v, ctrl, sc), recs in sorted(res["records"].items()):
            path = out_dir / f"whole_{v}_{sc}_{ctrl}.mf4"
            mdf.write(path, record_messages(recs), f"whole 1->2 upshift, vehicle {v}, scenario {sc}, controller {ctrl}")
            written.append(str(path))
        metrics["mdf"] = written
        staged.write_text(out_dir / "metrics.json", json.dumps(metrics, indent=1, default=float, sort_keys=True))
        staged.write_text(out_dir / "whole_shift_report.md", markdown(res["cases"], tg))
    return metrics
