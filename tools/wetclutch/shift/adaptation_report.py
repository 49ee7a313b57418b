"""The adaptation study's outputs (adaptation_study.py): adaptation_study.md, adaptation_study.json and one
PNG per plant variant (the learned values against the shift number, the plant's truth drawn in)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..util.atomic import Staged
from . import adaptation_runs as runs
from .adaptation_study import (LEARN_SHIFTS, MATCH_TOLERANCE, NEVER_WORSE, RECOVERY_FRACTION, RECOVERY_SHIFTS,
                               SETTLE_SHIFTS, SETTLE_WINDOW, SOAK_TOLERANCE_K, missed, values_series)


def _f(x, nd=1):
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return "n/a" if not math.isfinite(x) else f"{x:.{nd}f}"


def _met(t):
    return "-" if t is None or t.get("met") is None else ("met" if t["met"] else "**MISSED**")


def markdown(res: dict) -> str:
    tg = res["targets"]
    b = res["bands"]
    lines = ["# Adaptation study (issue 20, DESIGN 12)", "",
             f"`adaptive` (= `full` + adaptation) from the calibration's values on plants that differ from it;"
             f" {res['shifts']} consecutive shifts per plant with one TCU, oil temperature cycling over"
             f" {', '.join(f'{t:g}' for t in res['oil_cycle_degC'])} degC, {res['gap_s']:g} s between shifts,"
             f" the plant's seeded noise. The matrix and the faults start from the image learned in the first"
             f" {LEARN_SHIFTS} shifts. Quality from the plant's truth; learned values from the TCU's"
             f" AdaptationReport and adaptation file.", "",
             f"Bands: friction scale 1 +- {b['scale_band']:g} (step {b['scale_step']:g}/shift), film factor"
             f" {b['film_min']:g}..{b['film_max']:g} (step {100 * b['film_step']:g} %/shift), kiss offset +-"
             f" {b['kiss_band_Pa'] * 1e-3:g} kPa (step {b['kiss_step_Pa'] * 1e-3:g} kPa/shift); nodes"
             f" {', '.join(f'{t:g}' for t in b['theta_nodes_degC'])} degC.", "",
             "## Targets", "",
             f"| plant | slip RMSE within {100 * MATCH_TOLERANCE:g} % of matched after {LEARN_SHIFTS} shifts |"
             " beats feedback and blind (slip RMSE, inertia jerk), every scenario | inside bands |"
             f" settles ({SETTLE_SHIFTS} shifts) |", "|---|---|---|---|---|"]
    for name, t in tg.items():
        if name in ("never_worse", "faults", "soak"):
            continue
        mt = t["matched_within_10pct"]
        bf = t.get("beats_feedback_blind")
        lines.append(f"| {name} | {_met(mt)} (worst {_f(mt['worst_ratio_after_learning'], 3)}, within from shift"
                     f" {mt['first_shift_from_which_within'] or '-'}) | {_met(bf)}"
                     f"{' (' + '; '.join(bf['missed'][:6]) + (' ...' if len(bf['missed']) > 6 else '') + ')' if bf and bf['missed'] else ''}"
                     f" | {_met(t['inside_bands'])} | {_met(t['settles'])} |")
    nw = tg["never_worse"]
    lines += ["", f"- **never worse** (matched plant, {nw['compared']} shifts/scenarios, no figure worse by more than"
              f" {100 * NEVER_WORSE:g} %): {_met(nw)}; largest worsening "
              + ", ".join(f"{k} {100 * v:+.1f} %" for k, v in nw["max_worse"].items())
              + "; largest change either way " + ", ".join(f"{k} {100 * v:.1f} %" for k, v in nw["max_abs_change"].items())
              + (f"; worse than {100 * NEVER_WORSE:g} %: " + "; ".join(nw["missed"]) if nw["missed"] else "")]
    if "faults" in tg:
        lines.append(f"- **faults**: {_met(tg['faults'])}")
    if "soak" in tg:
        lines.append(f"- **heat soak** (observer within {SOAK_TOLERANCE_K:g} K all through the 10th shift): with adaptation"
                     f" {_met(tg['soak'])}, without {_met({'met': tg['soak']['met_without_adaptation']})}")
    left = missed(tg)
    lines += ["", f"Missed: {', '.join(left) if left else 'none'}.", ""]
    for name, v in res["variants"].items():
        lines += _variant_section(name, v, tg.get(name, {}), res)
    if res.get("faults"):
        lines += _fault_section(res, tg["faults"])
    if "soak" in tg:
        lines += ["## Heat soak: the observer against the plant's pack in the 10th shift", "",
                  "| plant | controller | max abs error K | peak error K | end error K |", "|---|---|---|---|---|"]
        for name, s in tg["soak"]["cases"].items():
            for ctrl, x in s.items():
                lines.append(f"| {name} | {ctrl} | {_f(x['max_error_K'], 2)} | {_f(x['peak_error_K'], 2)} |"
                             f" {_f(x['end_error_K'], 2)} |")
        lines.append("")
    lines += ["## Time", "", "| part | s |", "|---|---|"]
    lines += [f"| {k} | {v:.1f} |" for k, v in res["timing_s"].items()]
    return "\n".join(lines) + "\n"


def _variant_section(name: str, v: dict, t: dict, res: dict) -> list[str]:
    truth = v["truth"]
    seq = v["sequence"]
    series = values_series(seq)
    nodes = truth["theta_nodes_degC"]
    out = [f"## {name}: {v['description']}" + (" (the matched plant: its sequence only)" if v.get("matched_only") else ""),
           "", "| value | truth | after " + f"{LEARN_SHIFTS} | after {len(seq)} |", "|---|---|---|---|"]
    k8 = min(LEARN_SHIFTS, len(seq)) - 1
    for i, th in enumerate(nodes):
        out.append(f"| friction scale at {th:g} degC (confidence) | {truth['friction_scale'][i]:.3f} |"
                   f" {series['friction_scale'][k8, i]:.3f} ({series['confidence'][k8, i]:.2f}) |"
                   f" {series['friction_scale'][-1, i]:.3f} ({series['confidence'][-1, i]:.2f}) |")
    out.append(f"| film factor | {truth['film_factor']:.3f} | {series['film_factor'][k8]:.3f} | {series['film_factor'][-1]:.3f} |")
    out.append(f"| kiss offset kPa | {truth['kiss_offset_Pa'] * 1e-3:.1f} | {series['kiss_offset_Pa'][k8] * 1e-3:.1f} |"
               f" {series['kiss_offset_Pa'][-1] * 1e-3:.1f} |")
    ratios = t.get("matched_within_10pct", {}).get("ratios", [])
    full = v.get("sequence_full")
    out += ["", "| shift | oil degC | slip RMSE rpm: full | adaptive | matched (base, adaptive) | adaptive/matched |"
            " inertia jerk m/s^3: full | adaptive | result | node | scale | film | kiss kPa |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    base = res["variants"]["base"]["sequence"]
    shown = range(len(seq)) if len(seq) <= 32 else [*range(16), *range(len(seq) - 8, len(seq))]
    for i in shown:
        e = seq[i]
        if i == len(seq) - 8 and len(seq) > 32:
            out.append("| ... |" + " |" * 12)
        q, a = e["quality"], e["adaptation"] or {}
        qf = full[i]["quality"] if full else None
        out.append(f"| {e['shift']} | {e['oil_degC']:g} | {_f(qf['slip_rmse_rpm']) if qf else '-'} | {_f(q['slip_rmse_rpm'])} |"
                   f" {_f(base[i]['quality']['slip_rmse_rpm'])} | {_f(ratios[i], 3) if i < len(ratios) else '-'} |"
                   f" {_f(qf['peak_inertia_jerk_m_s3']) if qf else '-'} | {_f(q['peak_inertia_jerk_m_s3'])} |"
                   f" {runs.RESULT_NAMES.get(int(a['Result']), '?') if a else '-'} | {int(a['Node']) if a else '-'} |"
                   f" {_f(a.get('FrictionScale'), 3)} | {_f(a.get('FilmFactor'), 3)} | {_f(a.get('KissOffset'), 2)} |")
    if t.get("settles", {}).get("met") is not None:
        sp = t["settles"]["spread_last"]
        out += ["", f"Spread over the last {SETTLE_WINDOW} shifts: friction scale "
                + ", ".join(f"node {i} {x:.4f}" for i, x in sp["friction_scale"].items())
                + f"; film factor {100 * sp['film_factor']:.2f} %; kiss offset {sp['kiss_offset_Pa'] * 1e-3:.2f} kPa."]
    m = v.get("matrix")
    if m:
        ctrls = [c for c in ("feedback", "blind", "full", "adaptive") if c in m]
        out += ["", f"Matrix (issue 13's scenarios; adaptive from the image after {LEARN_SHIFTS} shifts; the soak row"
                " the worst of its shifts):", "",
                "| scenario | slip RMSE rpm: " + " | ".join(ctrls) + " | inertia jerk m/s^3: " + " | ".join(ctrls)
                + " | peak jerk: " + " | ".join(ctrls) + " | end (adaptive) |",
                "|---|" + "---|" * (3 * len(ctrls) + 1)]
        for sc in m[ctrls[0]]:
            qa = m.get("adaptive", {}).get(sc)
            out.append(f"| {sc} | " + " | ".join(_f(m[c][sc]["slip_rmse_rpm"]) for c in ctrls) + " | "
                       + " | ".join(_f(m[c][sc]["peak_inertia_jerk_m_s3"]) for c in ctrls) + " | "
                       + " | ".join(_f(m[c][sc]["peak_jerk_m_s3"]) for c in ctrls)
                       + f" | {qa['abort_reason'] if qa else '-'}{', flare' if qa and qa['flare'] else ''} |")
    return out + [""]


def _fault_section(res: dict, tf: dict) -> list[str]:
    f = res["faults"]
    out = [f"## Faults ({f['variant']}, from the image after {LEARN_SHIFTS} shifts; then {RECOVERY_SHIFTS} good"
           f" shifts, against the same shifts without the fault; recovered: within {RECOVERY_FRACTION:g} x the"
           " per-shift step of the fault-free run)", "",
           "| fault | what | TCU result | shift end | largest change: scale / film % / kiss kPa (limits) |"
           " off the fault-free run after the fault | after 5 good shifts | met |", "|---|---|---|---|---|---|---|---|"]
    for name, c in tf["cases"].items():
        ch, lim, d0, d5 = c["change"], c["limits"], c["deviation_after_fault"], c["deviation_after_recovery"]
        out.append(f"| {name} | {f['cases'][name]['description']} | {c['result']} | {c['abort']} |"
                   f" {ch['friction_scale']:.4f} / {100 * ch['film_factor']:.2f} / {ch['kiss_offset_Pa'] * 1e-3:.2f}"
                   f" ({lim['friction_scale']:g} / {100 * lim['film_factor']:g} / {lim['kiss_offset_Pa'] * 1e-3:g}) |"
                   f" {d0['friction_scale']:.4f} / {100 * d0['film_factor']:.2f} / {d0['kiss_offset_Pa'] * 1e-3:.2f} |"
                   f" {d5['friction_scale']:.4f} / {100 * d5['film_factor']:.2f} / {d5['kiss_offset_Pa'] * 1e-3:.2f} |"
                   f" {_met(c)} |")
    return out + [""]


# --------------------------------------------------------------------------------------------------- plots
def plot_variant(path: Path, name: str, v: dict, res: dict) -> str:
    """The learned values against the shift number, the truth dashed: friction scale per node, film factor,
    kiss offset; and the slip RMSE per shift against the matched plant's."""
    from ..util import plotting
    seq = v["sequence"]
    s = values_series(seq)
    n = np.array([e["shift"] for e in seq])
    truth = v["truth"]
    fig, axes = plotting.subplots(2, 2, figsize=(13, 9), sharex=True)
    ax = axes[0, 0]
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
    reported = [(e["shift"], int(e["adaptation"]["Node"]), e["adaptation"]["FrictionScale"]) for e in seq
                if e["adaptation"] and int(e["adaptation"]["Result"]) == 1]
    for i, th in enumerate(truth["theta_nodes_degC"]):
        if np.ptp(s["friction_scale"][:, i]) == 0.0 and not any(r[1] == i for r in reported):
            continue          # a node no shift reached
        ax.plot(n, s["friction_scale"][:, i], color=colors[i], marker=".", label=f"node {th:g} degC")
        ax.axhline(truth["friction_scale"][i], color=colors[i], ls="--", lw=1)
        pts = [(k, x) for k, node, x in reported if node == i]
        if pts:
            ax.plot(*zip(*pts), "o", mfc="none", color=colors[i], ms=7)
    plotting.style(ax, ylabel="friction scale", title="friction scale per node\n(line: adaptation file, circle:"
                   " AdaptationReport, dashed: truth)", legend={"fontsize": 7})
    ax = axes[0, 1]
    ax.plot(n, s["film_factor"], "k.-", label="learned")
    ax.axhline(truth["film_factor"], color="k", ls="--", lw=1, label="plant's truth")
    plotting.style(ax, ylabel="film factor (x calibration's)", title="squeeze-film factor", legend={"fontsize": 7})
    ax = axes[1, 0]
    ax.plot(n, s["kiss_offset_Pa"] * 1e-3, "k.-", label="learned")
    ax.axhline(truth["kiss_offset_Pa"] * 1e-3, color="k", ls="--", lw=1, label="plant's truth")
    plotting.style(ax, xlabel="shift", ylabel="kPa", title="kiss point offset", legend={"fontsize": 7})
    ax = axes[1, 1]
    ax.plot(n, [e["quality"]["slip_rmse_rpm"] for e in seq], "b.-", label="adaptive")
    if v.get("sequence_full"):
        ax.plot(n, [e["quality"]["slip_rmse_rpm"] for e in v["sequence_full"]], "r.-", label="full (no adaptation)")
    base = res["variants"]["base"]["sequence"]
    ax.plot(n, [e["quality"]["slip_rmse_rpm"] for e in base][:len(n)], "g.--", label="matched plant, adaptive")
    ax.axvline(LEARN_SHIFTS + 0.5, color="gray", lw=1)
    ax2 = ax.twinx()
    ax2.plot(n, [e["oil_degC"] for e in seq], color="gray", lw=0.8, ls=":")
    ax2.set_ylabel("oil degC (dotted)")
    plotting.style(ax, xlabel="shift", ylabel="slip RMSE (rpm)", title="slip tracking per shift",
                   legend={"fontsize": 7})
    fig.suptitle(f"Adaptation on plant {name}: {v['description']}")
    return plotting.save(fig, path)


def write(out_dir: Path, res: dict, plots: bool = True) -> list[str]:
    """adaptation_study.md, adaptation_study.json and the plots, all or nothing."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    with Staged() as staged:
        if plots:
            for name, v in res["variants"].items():
                written.append(plot_variant(out_dir / f"adaptation_{name}.png", name, v, res))
        res = dict(res, plots=written)
        staged.write_text(out_dir / "adaptation_study.json", json.dumps(res, indent=1, default=_json))
        staged.write_text(out_dir / "adaptation_study.md", markdown(res))
    return written


def _json(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.integer,)):
        return int(x)
    return float(x)
