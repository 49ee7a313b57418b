"""The adaptation study (issue 20, DESIGN 12; ``wetclutch shift --adaptation-study``): the shift controller
with adaptation (`adaptive` = `full` + adaptation 1) on plants that differ from its calibration
(simulate/plant/variants.py), from the calibration's values, and the issue's targets.

Per variant (adaptation_runs.py has the runs):
  sequence   `shifts` consecutive shifts with one TCU, the oil temperature cycling over OIL_CYCLE_DEGC (20 to
             110 degC, every 8 shifts), seeded noise; per shift the quality (the plant's truth) and the
             learned values as the TCU reports them (AdaptationReport, and all nodes from its adaptation file);
             the base plant's sequence is run too, with adaptation (the matched plant) and without (`full`);
  matrix     issue 13's scenario matrix: `adaptive` from the image learned in the first LEARN_SHIFTS shifts
             (wc_replay --adaptation-file), against `feedback`, `blind` (and `full`, the before); in the
             friction -/+10 % scenarios (a clutch that changed by 10 % after it was learned) from that image
             after LEARN_SHIFTS more shifts of the sequence on the changed plant: the target is "after at
             most LEARN_SHIFTS shifts" on every plant, and a friction change is one;
  faults     from the same image: one shift with a fault (adaptation_runs.FAULTS), then RECOVERY_SHIFTS good
             shifts, against the same shifts without the fault;
  soak       the matrix's heat soak (10 back-to-back shifts at 80 degC) with and without adaptation.

Targets (targets(), evaluated on what ran):
  matched_within_10pct  after LEARN_SHIFTS shifts, slip RMSE within 10 % of the same controller on the base
                        plant at the same oil temperature (the sequence's shifts LEARN_SHIFTS + 1 .. shifts);
  beats_feedback_blind  in every scenario of the matrix, lower slip RMSE and inertia-phase peak jerk than
                        `feedback` and `blind`;
  never_worse           base plant: no quality figure worse by more than 2 % with adaptation than without
                        (per shift of the sequence; the matrix's scenarios on it too when base is among the
                        variants, not the friction -/+10 % ones: those are other plants);
  inside_bands          every learned value of every shift inside its band;
  settles               with shifts >= SETTLE_SHIFTS: each value's spread over the last SETTLE_WINDOW shifts
                        no more than its per-shift step (the friction scale: the nodes that learned);
  faults                the faulted shift moves no value by more than its per-shift step, and after
                        RECOVERY_SHIFTS good shifts each value is within RECOVERY_FRACTION of its step of the
                        fault-free run;
  soak                  with adaptation, the observer within SOAK_TOLERANCE_K of the plant's pack all through
                        the 10th shift of the heat soak (without: reported, met_without_adaptation).
"""
from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from ..calibration import load as load_clutch_calibration
from ..simulate import plant as plant_mod
from ..simulate.plant import variants as variants_mod
from . import adaptation_runs as runs
from .quality import worst
from .scenarios import ROOT, TARGET_INERTIA_S, TCU_CALIBRATION, ShiftError, scenario_matrix


LEARN_SHIFTS = 8
DEFAULT_SHIFTS = 16              # two oil cycles: shifts 9..16 see every oil temperature once after learning
MATCH_TOLERANCE = 0.10
NEVER_WORSE = 0.02
SETTLE_SHIFTS, SETTLE_WINDOW = 200, 50
RECOVERY_SHIFTS = 5
RECOVERY_FRACTION = 0.25
SOAK_TOLERANCE_K = 5.0
CONTROLLERS = ("adaptive", "full", "feedback", "blind")
# Figures compared for "never worse": lower is better (the inertia time: its distance from the target).
NEVER_WORSE_FIGURES = ("slip_rmse_rpm", "peak_inertia_jerk_m_s3", "peak_jerk_m_s3", "inertia_time_s",
                       "friction_energy_kJ", "pressure_rmse_kPa", "peak_theta_degC")
SCALE_EPS, FILM_EPS, KISS_EPS_PA = 1e-4, 1e-4, 1.0    # float32 and the report's rounding


def _say(progress, text):
    if progress:
        progress(text)


def bands(cal) -> dict:
    """The adaptation's bands and per-shift steps of the shift calibration (adapt_*)."""
    return {"scale_band": cal.adapt_scale_band, "scale_step": cal.adapt_scale_step,
            "film_min": cal.adapt_film_factor_min, "film_max": cal.adapt_film_factor_max,
            "film_step": cal.adapt_film_step, "kiss_band_Pa": cal.adapt_kiss_band, "kiss_step_Pa": cal.adapt_kiss_step,
            "theta_nodes_degC": [getattr(cal, f"adapt_theta_node{i}") for i in range(runs.adaptation_image.NODES)]}


def values_series(entries: list[dict], nodes: int = runs.adaptation_image.NODES) -> dict:
    """Per shift: every node's friction scale and confidence, the film factor and kiss offset (Pa). From the
    adaptation file when the TCU wrote one, else from the AdaptationReport (its node; the others held)."""
    scale = np.ones((len(entries), nodes))
    conf = np.zeros((len(entries), nodes))
    film, kiss = np.ones(len(entries)), np.zeros(len(entries))
    held_s, held_c, held_f, held_k = np.ones(nodes), np.zeros(nodes), 1.0, 0.0
    for i, e in enumerate(entries):
        v, a = e.get("values"), e.get("adaptation")
        if v is not None:
            held_s, held_c = np.array(v["friction_scale"]), np.array(v["confidence"])
            held_f, held_k = v["film_factor"], v["kiss_offset_Pa"]
        elif a is not None and int(a["Result"]) != 0:
            n = int(a["Node"])
            held_s[n], held_c[n] = a["FrictionScale"], a["Confidence"]
            held_f, held_k = a["FilmFactor"], a["KissOffset"] * 1e3
        scale[i], conf[i], film[i], kiss[i] = held_s, held_c, held_f, held_k
    return {"friction_scale": scale, "confidence": conf, "film_factor": film, "kiss_offset_Pa": kiss}


# --------------------------------------------------------------------------------------------------- the runs
def run_study(out_dir: Path, variants=None, shifts: int = DEFAULT_SHIFTS, *, controllers=CONTROLLERS,
              sequence_full: bool = True, faults_on: str | None = "friction+20", soak_on=None,
              plant_path=plant_mod.DEFAULT_PLANT, progress=print) -> dict:
    """Run the study (module docstring) and return its results (JSON-able but for numpy floats). controllers:
    the matrix's (none: no matrix); sequence_full: also the sequences without adaptation (the base's always);
    faults_on: the variant of the fault cases (None: none); soak_on: the variants of the soak target (None:
    every variant; from the matrix's soak where it ran)."""
    if shifts < LEARN_SHIFTS + 1:
        raise ValueError(f"--shifts {shifts}: at least {LEARN_SHIFTS + 1} (learning, then the comparison)")
    names = list(variants or [v.name for v in variants_mod.VARIANTS])
    for n in names:
        variants_mod.variant(n)          # an unknown name fails before the work
    if not runs.adaptive_supported():
        raise ShiftError("the adaptation study needs the firmware's adaptation: the DBC's AdaptationReport and"
                              " wc_replay --adaptation-file (rebuild: cmake --build --preset host-release)")
    out_dir = Path(out_dir)
    work = out_dir / "work"
    base_params = plant_mod.load_plant(plant_path)
    tcu_cal = load_clutch_calibration(ROOT / "tools" / "calibrations" / f"{TCU_CALIBRATION}.toml")
    cal = runs.shift_calibrations()["adaptive"]
    res = {"shifts": shifts, "learn_shifts": LEARN_SHIFTS, "oil_cycle_degC": list(runs.OIL_CYCLE_DEGC),
           "gap_s": runs.STUDY_GAP_S, "bands": bands(cal), "variants": {}, "faults": None, "soak": {},
           "timing_s": {}}
    t_start = time.monotonic()

    # the matched plant: with and without adaptation, the same shifts
    order = ["base"] + [n for n in names if n != "base"]
    for name in order:
        t0 = time.monotonic()
        v = variants_mod.variant(name)
        params = variants_mod.apply(base_params, v)
        entry = {"description": v.description,
                 "truth": variants_mod.truth(params, tcu_cal).as_dict(res["bands"]["theta_nodes_degC"])}
        _say(progress, f"[{name}] {shifts} shifts with adaptation")
        seq = runs.learn(params, "shift_1_2_adaptive", shifts, work / name / "adaptive", keep_after=LEARN_SHIFTS)
        entry["sequence"] = seq["shifts"]
        entry["image_after_learning"] = seq["image_after"]
        if sequence_full or name == "base":
            _say(progress, f"[{name}] the same {shifts} shifts without adaptation (full)")
            entry["sequence_full"] = runs.learn(params, "shift_1_2_full", shifts, work / name / "full")["shifts"]
        if name in names and controllers:
            entry["matrix"] = _matrix(params, controllers, seq["image_after"], work / name / "matrix", progress, name)
        res["variants"][name] = entry
        res["timing_s"][name] = time.monotonic() - t0
    if "base" not in names:
        res["variants"]["base"]["matched_only"] = True

    if faults_on:
        t0 = time.monotonic()
        params = variants_mod.apply(base_params, variants_mod.variant(faults_on))
        image = res["variants"][faults_on]["image_after_learning"]
        _say(progress, f"[faults] on {faults_on} from the image after {LEARN_SHIFTS} shifts")
        res["faults"] = {"variant": faults_on, "cases": _faults(params, image, work / "faults")}
        res["timing_s"]["faults"] = time.monotonic() - t0
    soak_sc = next(sc for sc in scenario_matrix() if sc.name == "soak")
    for name in (names if soak_on is None else soak_on):
        if name not in res["variants"]:
            continue
        t0 = time.monotonic()
        params = variants_mod.apply(base_params, variants_mod.variant(name))
        image = res["variants"][name]["image_after_learning"]
        matrix = res["variants"][name].get("matrix", {})
        res["soak"][name] = {}
        for ctrl in ("adaptive", "full"):
            if "soak" in matrix.get(ctrl, {}):
                entries = matrix[ctrl]["soak"]["per_shift"]
            else:
                _say(progress, f"[soak] {name}: {ctrl}")
                recs = runs.matrix_case(params, f"shift_1_2_{ctrl}", soak_sc, work / "soak" / name / ctrl,
                                        image if ctrl == "adaptive" else None)
                entries = [runs.shift_entry(i + 1, r) for i, r in enumerate(recs)]
            res["soak"][name][ctrl] = entries
        if time.monotonic() - t0 > 0.1:            # not all from the matrix
            res["timing_s"][f"soak {name}"] = time.monotonic() - t0
    res["timing_s"]["total"] = time.monotonic() - t_start
    res["targets"] = targets(res)
    return res


def _relearned(params, image, sc, work: Path) -> Path:
    """The image after LEARN_SHIFTS more shifts of the sequence (oil cycle, gaps) on the plant of a friction
    scenario (the variant's friction times the scenario's), from the variant's learned image."""
    changed = dataclasses.replace(params, friction_scale=params.friction_scale * sc.friction_scale)
    seq = runs.learn(changed, "shift_1_2_adaptive", LEARN_SHIFTS, work, image=Path(image),
                     keep_after=LEARN_SHIFTS)
    return Path(seq["image_after"])


def _matrix(params, controllers, image, work: Path, progress, name) -> dict:
    """Every controller on every scenario; `adaptive` from the learned image (a copy per scenario), in the
    friction scenarios from the image relearned on that plant (_relearned)."""
    out = {}
    relearned = {}
    for ctrl in controllers:
        _say(progress, f"[{name}] matrix: {ctrl}")
        out[ctrl] = {}
        for sc in scenario_matrix():
            start = image
            if ctrl == "adaptive" and not math.isclose(sc.friction_scale, 1.0):
                if sc.name not in relearned:
                    _say(progress, f"[{name}] relearning {LEARN_SHIFTS} shifts for {sc.name}")
                    relearned[sc.name] = _relearned(params, image, sc, work / "relearn" / sc.name)
                start = relearned[sc.name]
            recs = runs.matrix_case(params, f"shift_1_2_{ctrl}", sc, work / ctrl / sc.name,
                                    start if ctrl == "adaptive" else None)
            es = [runs.shift_entry(i + 1, r) for i, r in enumerate(recs)]
            q = worst([e["quality"] for e in es])
            if sc.shifts > 1:
                q["per_shift"] = es
            out[ctrl][sc.name] = q
    return out


def _faults(params, image, work: Path) -> dict:
    """The fault-free run and one run per fault: shifts LEARN_SHIFTS + 1 .. + RECOVERY_SHIFTS + 1 from image."""
    first = LEARN_SHIFTS + 1
    out = {"none": runs.learn(params, "shift_1_2_adaptive", RECOVERY_SHIFTS + 1, work / "none", image=image,
                              first=first)}
    for f in runs.FAULTS:
        r = runs.learn(params, "shift_1_2_adaptive", RECOVERY_SHIFTS + 1, work / f.name, image=image, first=first,
                       faults={first: f})
        r["description"] = f.description
        out[f.name] = r
    return out


# --------------------------------------------------------------------------------------------------- targets
def _rel(a: float, b: float) -> float:
    return (a - b) / b if b else (0.0 if a == b else math.inf)


def _worse(qa: dict, qf: dict) -> dict:
    """Per figure: how much worse with adaptation (qa) than without (qf), relative; the flags."""
    out = {}
    for k in NEVER_WORSE_FIGURES:
        if k == "inertia_time_s":
            out[k] = (abs(qa[k] - TARGET_INERTIA_S) - abs(qf[k] - TARGET_INERTIA_S)) / TARGET_INERTIA_S
        else:
            out[k] = _rel(qa[k], qf[k])
    out["new_flag"] = [k for k in ("flare", "tie_up") if qa[k] and not qf[k]] + (
        ["abort"] if qa["abort"] != 0 and qf["abort"] == 0 else [])
    return out


def _bands_ok(series: dict, b: dict) -> bool:
    s, f, k = series["friction_scale"], series["film_factor"], series["kiss_offset_Pa"]
    return bool(np.all(np.abs(s - 1.0) <= b["scale_band"] + SCALE_EPS)
                and np.all((f >= b["film_min"] - FILM_EPS) & (f <= b["film_max"] + FILM_EPS))
                and np.all(np.abs(k) <= b["kiss_band_Pa"] + KISS_EPS_PA))


def _changes(before: dict, after: dict) -> dict:
    """|change| of each value between two value sets: per node scale, the film factor (relative), kiss (Pa)."""
    return {"friction_scale": float(np.max(np.abs(np.array(after["friction_scale"]) - np.array(before["friction_scale"])))),
            "film_factor": abs(after["film_factor"] / before["film_factor"] - 1.0),
            "kiss_offset_Pa": abs(after["kiss_offset_Pa"] - before["kiss_offset_Pa"])}


def _limits(b: dict) -> dict:
    return {"friction_scale": b["scale_step"], "film_factor": b["film_step"], "kiss_offset_Pa": b["kiss_step_Pa"]}


def targets(res: dict) -> dict:
    """The issue's targets on what ran: {name: {"met": bool or None (not run), ...}}."""
    b = res["bands"]
    out = {}
    base = res["variants"]["base"]
    n_learn = res["learn_shifts"]
    for name, v in res["variants"].items():
        rm = [e["quality"]["slip_rmse_rpm"] for e in v["sequence"]]
        rb = [e["quality"]["slip_rmse_rpm"] for e in base["sequence"]]
        ratios = [a / m for a, m in zip(rm, rb)]
        after = ratios[n_learn:]
        first = next((i + 1 for i in range(len(ratios)) if all(r <= 1.0 + MATCH_TOLERANCE for r in ratios[i:])), None)
        t = {"matched_within_10pct": {"met": bool(after) and max(after) <= 1.0 + MATCH_TOLERANCE,
                                      "worst_ratio_after_learning": max(after) if after else None,
                                      "first_shift_from_which_within": first, "ratios": ratios}}
        series = values_series(v["sequence"])
        t["inside_bands"] = {"met": _bands_ok(series, b)}
        n = len(v["sequence"])
        if n >= SETTLE_SHIFTS:
            last = slice(n - SETTLE_WINDOW, n)
            learned = [i for i in range(series["friction_scale"].shape[1])
                       if np.ptp(series["friction_scale"][:, i]) > 0.0]
            spread = {"friction_scale": {i: float(np.ptp(series["friction_scale"][last, i])) for i in learned},
                      "film_factor": float(np.ptp(series["film_factor"][last]) / np.mean(series["film_factor"][last])),
                      "kiss_offset_Pa": float(np.ptp(series["kiss_offset_Pa"][last]))}
            ok = (all(s <= b["scale_step"] for s in spread["friction_scale"].values())
                  and spread["film_factor"] <= b["film_step"] and spread["kiss_offset_Pa"] <= b["kiss_step_Pa"])
            t["settles"] = {"met": ok, "spread_last": spread, "window": SETTLE_WINDOW}
        else:
            t["settles"] = {"met": None, "why": f"needs --shifts >= {SETTLE_SHIFTS}"}
        m = v.get("matrix")
        if m and "adaptive" in m and "feedback" in m and "blind" in m:
            ratios = {}
            for sc, q in m["adaptive"].items():
                ratios[sc] = {f"{k} {o}/adaptive": (m[o][sc][k] / q[k] if q[k] > 0 else math.inf)
                              for o in ("feedback", "blind") for k in ("slip_rmse_rpm", "peak_inertia_jerk_m_s3")}
            t["beats_feedback_blind"] = {"met": all(r > 1.0 for rs in ratios.values() for r in rs.values()),
                                         "ratios": ratios,
                                         "missed": sorted(f"{sc}: {k}" for sc, rs in ratios.items()
                                                          for k, r in rs.items() if not r > 1.0)}
        out[name] = t
    # never worse: the matched plant, per shift of the sequence (and the matrix when it ran)
    worse = [dict(_worse(a["quality"], f["quality"]), where=f"shift {a['shift']} ({a['oil_degC']:g} degC)")
             for a, f in zip(base["sequence"], base["sequence_full"])]
    if base.get("matrix") and "full" in base["matrix"]:
        matched = {sc.name for sc in scenario_matrix() if math.isclose(sc.friction_scale, 1.0)}   # not the +-10 %
        worse += [dict(_worse(base["matrix"]["adaptive"][sc], base["matrix"]["full"][sc]), where=f"matrix {sc}")
                  for sc in base["matrix"]["full"] if sc in matched]
    max_worse = {k: max(w[k] for w in worse) for k in NEVER_WORSE_FIGURES}
    max_change = {k: max(abs(w[k]) for w in worse) for k in NEVER_WORSE_FIGURES}
    out["never_worse"] = {"met": all(x <= NEVER_WORSE for x in max_worse.values()) and not any(w["new_flag"] for w in worse),
                          "max_worse": max_worse, "max_abs_change": max_change, "compared": len(worse),
                          "missed": sorted(f"{k} {100 * w[k]:+.1f} % at {w['where']}" for w in worse
                                           for k in NEVER_WORSE_FIGURES if w[k] > NEVER_WORSE)
                          + [f"{', '.join(w['new_flag'])} at {w['where']}" for w in worse if w["new_flag"]]}
    if res.get("faults"):
        out["faults"] = _fault_targets(res["faults"]["cases"], b)
    soak = {}
    for name, s in res.get("soak", {}).items():
        soak[name] = {ctrl: {"max_error_K": entries[-1]["theta_error_max_K"], "peak_error_K": entries[-1]["theta_peak_error_K"],
                             "end_error_K": entries[-1]["theta_error_end_K"]} for ctrl, entries in s.items()}
    if soak:
        within = {ctrl: all(abs(s[ctrl]["max_error_K"]) <= SOAK_TOLERANCE_K for s in soak.values()) for ctrl in ("adaptive", "full")}
        out["soak"] = {"met": within["adaptive"], "met_without_adaptation": within["full"], "cases": soak}
    return out


def _fault_targets(cases: dict, b: dict) -> dict:
    limits = _limits(b)
    none_after = cases["none"]["shifts"][-1]["values"]
    out = {}
    for name, c in cases.items():
        if name == "none":
            continue
        before = c["values_before"]
        first = c["shifts"][0]
        change = _changes(before, first["values"])
        moved = {k: change[k] <= limits[k] * (1 + 1e-4) + (KISS_EPS_PA if k == "kiss_offset_Pa" else 0.0) for k in limits}
        dev_fault = _changes(cases["none"]["shifts"][0]["values"], first["values"])
        dev_after = _changes(none_after, c["shifts"][-1]["values"])
        recovered = {k: dev_after[k] <= RECOVERY_FRACTION * limits[k] for k in limits}
        out[name] = {"met": all(moved.values()) and all(recovered.values()),
                     "result": runs.RESULT_NAMES.get(int(first["adaptation"]["Result"]), "?") if first["adaptation"] else None,
                     "abort": first["quality"]["abort_reason"], "change": change, "limits": limits,
                     "deviation_after_fault": dev_fault, "deviation_after_recovery": dev_after}
    return {"met": all(c["met"] for c in out.values()), "cases": out}


def missed(tg: dict) -> list[str]:
    """The names of the targets missed (None: not run)."""
    out = []
    for name, t in tg.items():
        if "met" in t:
            if t["met"] is False:
                out.append(name)
        else:
            out += [f"{name}: {k}" for k, x in t.items() if x.get("met") is False]
    return out
