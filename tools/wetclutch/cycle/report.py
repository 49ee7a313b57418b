"""The drive cycle's report (issue 31, item 4): the targets, markdown, JSON, plots and the cycle as MDF4.

Targets of one cycle (``missed``): no speed-trace violation caused by the transmission (a shift in progress
within the tolerance's look-back, tolerance.attribute_violations); every shift within issue 29's limits
(runner.shift_missed); every element's surface-temperature observer within OBSERVER_K of the plant's truth
through the whole cycle. With --adaptation N, adaptation_figures judges the chained cycles' learned values
(bands, settling, no shift worse than without); only the power-on upshifts learn so far (issue 31 item 1).
"""
from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path

import numpy as np

from ..shift.transmission8 import ELEMENTS
from ..util import atomic
from .scheduler import count_by_kind
from .tolerance import attribute_violations, find_violations

OBSERVER_K = 5.0          # issue 31: the observer within 5 K of every element's truth through the whole cycle
KINDS = ("power-on upshift", "power-off upshift", "power-on downshift", "power-off downshift")


def evaluate(result) -> dict:
    """The figures and the misses of one cycle (a runner.CycleResult)."""
    c = result.channels
    t, v = c["t_s"], c["speed_kmh"]
    shifting = c["phase"] != 0
    violations = find_violations(result.trace, t, v)
    attributed = attribute_violations(violations, t, {"shift in progress": shifting})
    theirs = [a for a in attributed if a.transmission]
    observer = {e: float(np.max(np.abs(c[f"{e}_theta_est_degC"] - c[f"{e}_theta_degC"]), initial=0.0))
                for e in ELEMENTS}
    shifts = result.shifts
    missed = []
    if theirs:
        missed.append(f"{len(theirs)} speed-trace violation(s) during a shift")
    bad = [q for q in shifts if q["missed"]]
    if bad:
        missed.append(f"{len(bad)} of {len(shifts)} shifts miss a limit")
    for e, err in observer.items():
        if err > OBSERVER_K:
            missed.append(f"element {e}: observer up to {err:.1f} K from the truth (> {OBSERVER_K:g} K)")
    if result.dropped:
        missed.append(f"{len(result.dropped)} shift request(s) never engaged")
    by_kind = {}
    for kind in KINDS:
        qs = [q for q in shifts if q["kind"] == kind]
        if qs:
            by_kind[kind] = {"shifts": len(qs), "meet every limit": sum(not q["missed"] for q in qs),
                             "peak jerk max m/s^3": max(q["peak_jerk_m_s3"] for q in qs),
                             "flare max rpm": max(q["flare_rpm"] for q in qs),
                             "tie-up max %": 100 * max(q["tie_up_fraction"] for q in qs)}
    causes = Counter(m.split(" ")[0] for q in shifts for m in q["missed"])
    return {"vehicle": result.vehicle, "trace": result.trace.name, "duration_s": float(t[-1] - t[0]) if t.size else 0.0,
            "cpu_s": result.cpu_s, "periods_per_cpu_s": result.periods / max(result.cpu_s, 1e-9),
            "violations": [vars(x) for x in violations],
            "violations_transmission": len(theirs), "largest_speed_error_kmh": float(np.max(np.abs(
                v - c["target_kmh"]), initial=0.0)),
            "requests": count_by_kind(result.requests), "dropped_requests": len(result.dropped),
            "dropped": [{"t_s": r.time_s, "shift": f"{r.from_gear}->{r.to_gear}", "reason": r.reason}
                        for r in result.dropped],
            "shifts": len(shifts), "shifts_meeting_every_limit": len(shifts) - len(bad), "by_kind": by_kind,
            "miss_causes": dict(causes), "observer_max_error_K": observer,
            "adaptation": ("on: power-on upshifts learn into their on-coming element; learned shifts per element "
                           + ", ".join(f"{e} {v['shifts_learned']}" for e, v in result.learned.items()))
            if result.adaptation else "off (wetclutch cycle --adaptation N runs N cycles with it)",
            "learned": evaluate_learned(result),
            "missed": missed}


def learned_truth(vehicle) -> dict:
    """Per element what its adaptation should learn on this vehicle (DESIGN 12; the adaptation study's
    simulate.plant.variants.VariantTruth): the friction scale at the shift calibration's temperature nodes (the
    plant's true clutch and friction scale against the element's own calibration in the gearbox description, eq.
    18's ratio at the inertia phase's slip), the film factor and the kiss-point offset."""
    from ..shift.adaptation_study import bands
    from ..shift.matrix8 import CONTROLLER, _plant_and_models, plant_path
    from ..shift.scenarios import SHIFT_TOML
    from ..calibration import shift as shift_calibration
    from ..simulate.plant.variants import clutch_truth
    params, _ = _plant_and_models(str(plant_path(vehicle)))
    nodes = bands(shift_calibration.load(SHIFT_TOML).variants[CONTROLLER])["theta_nodes_degC"]
    return {e: clutch_truth(params.truth[e], params.gearbox.element(e).calibration, params.friction_scale[e])
            .as_dict(nodes) for e in ELEMENTS}


def plot_learned(path: Path, learned: list, truth: dict, labels: list) -> str:
    """One panel per element: the learned friction scale at each node (one series per entry of ``learned``, e.g.
    per cycle) against the truth, the nodes without confidence hollow; the film factor and kiss offset, learned
    (the last) against the truth, in the panel's title."""
    from ..util import plotting
    fig, ax = plotting.subplots(1, len(ELEMENTS), figsize=(16, 4), sharey=True)
    for a, e in zip(ax, ELEMENTS):
        tr = truth[e]
        nodes = tr["theta_nodes_degC"]
        a.plot(nodes, tr["friction_scale"], "k-", lw=1.5, label="truth")
        for i, (values, label) in enumerate(zip(learned, labels)):
            v = values[e]
            conf = np.asarray(v["confidence"]) > 0.0
            sc = np.asarray(v["friction_scale"])
            a.plot(nodes, sc, "-", color=f"C{i}", lw=0.8, label=f"{label} ({v['shifts_learned']} shifts)")
            a.plot(np.asarray(nodes)[conf], sc[conf], "o", color=f"C{i}")
            a.plot(np.asarray(nodes)[~conf], sc[~conf], "o", color=f"C{i}", mfc="none")
        last = learned[-1][e]
        a.set_title(f"{e}: film {last['film_factor']:.2f} (truth {tr['film_factor']:.2f})\n"
                    f"kiss {last['kiss_offset_Pa'] / 1e3:+.0f} kPa (truth {tr['kiss_offset_Pa'] / 1e3:+.0f})", fontsize=9)
        a.set_xlabel("surface temperature node, degC")
        a.grid(True, alpha=0.3)
    ax[0].set_ylabel("friction scale")
    ax[-1].legend(fontsize=7)
    return plotting.save(fig, path)


def markdown(figures: dict, shifts: list) -> str:
    f = figures
    lines = [f"## {f['trace']} on {f['vehicle']}", "",
             f"- {f['duration_s']:.0f} s driven in {f['cpu_s']:.0f} s of CPU ({f['periods_per_cpu_s']:.0f} periods/s)",
             f"- speed-trace violations (GTR 15, +-2 km/h within +-1 s): {len(f['violations'])}, of them during a"
             f" shift: {f['violations_transmission']}; largest speed error {f['largest_speed_error_kmh']:.2f} km/h",
             f"- shift requests: {f['requests']}; never engaged: {f['dropped_requests']}" + "".join(
                 f" ({d['shift']} at {d['t_s']:.1f} s, {d['reason']})" for d in f["dropped"]),
             f"- shifts meeting every limit of issue 29: {f['shifts_meeting_every_limit']} of {f['shifts']};"
             f" misses by cause: {f['miss_causes'] or 'none'}",
             "- observer, max |estimate - truth| per element: " + ", ".join(
                 f"{e} {k:.1f} K" for e, k in f["observer_max_error_K"].items()),
             f"- adaptation: {f['adaptation']}",
             "- learned friction scale at the nodes " + ", ".join(f"{t:g}" for t in next(iter(
                 f["learned"].values()))["truth"]["theta_nodes_degC"]) + " degC, learned / truth: " + "; ".join(
                 f"{e} " + " ".join(f"{a:.3f}/{b:.3f}" for a, b in zip(
                     (v["learned"] or {}).get("friction_scale", [math.nan] * len(v["truth"]["friction_scale"])),
                     v["truth"]["friction_scale"])) for e, v in f["learned"].items()),
             f"- **missed: {'; '.join(f['missed']) or 'nothing'}**", "",
             "| type | shifts | every limit met | peak jerk max m/s^3 | flare max rpm | tie-up max % |",
             "|---|---|---|---|---|---|"]
    for kind, k in f["by_kind"].items():
        lines.append(f"| {kind} | {k['shifts']} | {k['meet every limit']} | {k['peak jerk max m/s^3']:.1f} | "
                     f"{k['flare max rpm']:.0f} | {k['tie-up max %']:.0f} |")
    lines += ["", "| t s | shift | type | reason | T_t Nm | lock-up | jerk per phase m/s^3 | flare rpm | tie-up % |"
              " inertia s (target) | on-coming theta est / truth degC | energy on / off kJ | missed |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for q in shifts:
        th = q["theta_oncoming_degC"]
        ph = " ".join(f"{p}:{j:.1f}" for p, j in q["jerk_per_phase_m_s3"].items())
        en = q["energy_kJ"]
        e_on = en.get(q["oncoming"], math.nan) if q["oncoming"] else math.nan
        e_off = en.get(q["offgoing"], math.nan) if q["offgoing"] else math.nan
        lines.append(f"| {q['t_s']:.1f} | {q['shift']} | {q['kind']} | {q['reason']} | {q['turbine_torque_Nm']:.0f} |"
                     f" {'closed' if q['lockup_locked'] else 'open'} | {ph} | {q['flare_rpm']:.0f} |"
                     f" {100 * q['tie_up_fraction']:.0f} | {q['inertia_time_s']:.2f} ({q['target_s']}) |"
                     f" {th.get('estimate', math.nan):.1f} / {th.get('truth', math.nan):.1f} |"
                     f" {e_on:.2f} / {e_off:.2f} | {'; '.join(q['missed']) or '-'} |")
    return "\n".join(lines) + "\n"


def plots(result, shifts: list, out: Path, learned: dict | None = None) -> list[Path]:
    """speed.png (trace, driven speed, gear), temperatures.png (each element's estimate and truth),
    jerk.png (peak jerk per shift by type against the type's limit), learned.png (each element's learned values at
    the cycle's end against their truth, plot_learned; learned: evaluate's "learned")."""
    from ..shift.transmission8 import LIMITS_JERK
    from ..util import plotting
    c = result.channels
    t = c["t_s"]
    paths = []
    fig, ax = plotting.subplots(2, 1, figsize=(14, 7), sharex=True)
    ax[0].plot(t, c["target_kmh"], "k-", lw=0.8, label="trace")
    ax[0].plot(t, c["speed_kmh"], "C0-", lw=0.8, label="driven")
    ax[0].set_ylabel("km/h")
    ax[0].legend(loc="upper left")
    ax[1].step(t, c["gear"], "C1-", where="post", lw=0.8)
    ax[1].set_ylabel("gear")
    ax[1].set_xlabel("s")
    paths.append(plotting.save(fig, out / "speed.png"))
    fig, ax = plotting.subplots(len(ELEMENTS), 1, figsize=(14, 12), sharex=True)
    for a, e in zip(ax, ELEMENTS):
        a.plot(t, c[f"{e}_theta_degC"], "k-", lw=0.8, label="truth")
        a.plot(t, c[f"{e}_theta_est_degC"], "C3--", lw=0.8, label="TCU estimate")
        a.set_ylabel(f"{e} degC")
    ax[0].legend(loc="upper left")
    ax[-1].set_xlabel("s")
    paths.append(plotting.save(fig, out / "temperatures.png"))
    fig, ax = plotting.subplots(1, 1, figsize=(10, 5))
    for i, kind in enumerate(KINDS):
        qs = [q for q in shifts if q["kind"] == kind]
        ax.plot([q["t_s"] for q in qs], [q["peak_jerk_m_s3"] for q in qs], "o", color=f"C{i}", label=kind)
        ax.axhline(LIMITS_JERK[kind], color=f"C{i}", lw=0.6, ls=":")
    ax.set_xlabel("s")
    ax.set_ylabel("peak jerk m/s^3")
    ax.legend()
    paths.append(plotting.save(fig, out / "jerk.png"))
    if result.learned and learned:
        paths.append(plot_learned(out / "learned.png", [result.learned], {e: v["truth"] for e, v in learned.items()},
                                  ["learned"]))
    return paths


def evaluate_learned(result) -> dict:
    """{element: {learned, truth}} of a cycle (evaluate's "learned")."""
    return {e: {"learned": result.learned.get(e), "truth": t} for e, t in learned_truth(result.vehicle).items()}


UNITS = {"t_s": "s", "target_kmh": "km/h", "speed_kmh": "km/h", "pedal": "1", "brake_Nm": "N*m", "gear": "1",
         "phase": "1", "engine_rpm": "rpm", "turbine_rpm": "rpm", "output_rpm": "rpm", "lockup_mA": "mA", "safe": "1"}


def write(result, out: Path, name: str) -> dict:
    """OUT/NAME.md, NAME.json, NAME.mf4 and OUT/NAME/*.png, all or none (atomic.Staged); the figures."""
    from ..util import mdf
    figures = evaluate(result)
    md = markdown(figures, result.shifts)
    (out / name).mkdir(parents=True, exist_ok=True)
    c = result.channels
    channels = {k: (c[k], UNITS.get(k, "degC" if "theta" in k else "mA")) for k in c if k != "t_s"}
    with atomic.Staged() as staged:
        staged.write_text(out / f"{name}.md", md)
        staged.write_text(out / f"{name}.json", json.dumps({"figures": figures, "shifts": result.shifts},
                                                           indent=1, default=float))
        mdf.write_channels(out / f"{name}.mf4", c["t_s"], channels, f"wetclutch cycle: {result.trace.name} on"
                           f" {result.vehicle}")
        plots(result, result.shifts, out / name, figures["learned"])
    return figures


WORSE_FRACTION, WORSE_FLOOR_M_S3 = 0.02, 0.1    # issue 31: no shift worse by more than 2 % (the jerk's noise floor)


def adaptation_figures(reference, cycles: list) -> dict:
    """Issue 31's adaptation targets over the chained cycles (reference: the same cycle without adaptation):
    the learned values per element after each cycle, inside their bands; from the second to the third cycle
    each within its per-shift step (settled); in the first, no shift's peak jerk more than 2 % above the same
    shift's (same gears, requested within 1 s) without adaptation."""
    from ..calibration import shift as shift_calibration
    from ..shift.matrix8 import CONTROLLER
    from ..shift.scenarios import SHIFT_TOML
    cal = shift_calibration.load(SHIFT_TOML).variants[CONTROLLER]
    learned = [c.learned for c in cycles]
    missed = []
    for k, values in enumerate(learned, 1):
        for e, v in values.items():
            if any(abs(x - 1.0) > cal.adapt_scale_band for x in v["friction_scale"]) or not (
                    cal.adapt_film_factor_min <= v["film_factor"] <= cal.adapt_film_factor_max) or \
                    abs(v["kiss_offset_Pa"]) > cal.adapt_kiss_band:
                missed.append(f"cycle {k}: element {e}'s learned values outside their bands")
    if len(learned) >= 3:
        for e in ELEMENTS:
            a, b = learned[1][e], learned[2][e]
            if max(abs(x - y) for x, y in zip(a["friction_scale"], b["friction_scale"])) > cal.adapt_scale_step or \
                    abs(a["film_factor"] - b["film_factor"]) > cal.adapt_film_step or \
                    abs(a["kiss_offset_Pa"] - b["kiss_offset_Pa"]) > cal.adapt_kiss_step:
                missed.append(f"element {e}: not settled from cycle 2 to 3")
    else:
        missed.append(f"settling not measured: {len(learned)} cycle(s) with adaptation (3 needed)")
    worse = []
    for q in cycles[0].shifts if cycles else []:
        same = [r for r in reference.shifts if r["shift"] == q["shift"] and abs(r["t_s"] - q["t_s"]) < 1.0]
        if same and q["peak_jerk_m_s3"] > (1 + WORSE_FRACTION) * same[0]["peak_jerk_m_s3"] + WORSE_FLOOR_M_S3:
            worse.append((q["t_s"], q["shift"], same[0]["peak_jerk_m_s3"], q["peak_jerk_m_s3"]))
    if worse:
        missed.append(f"cycle 1: {len(worse)} shift(s) worse than without adaptation by more than 2 %")
    return {"learned": learned, "truth": learned_truth(reference.vehicle), "worse_in_cycle_1": worse, "missed": missed,
            "shifts_per_cycle": [len(c.shifts) for c in cycles],
            "meeting_every_limit": [sum(not q["missed"] for q in c.shifts) for c in [reference, *cycles]]}


def command(vehicles, phase: str, oil_degC, out: Path, adaptation_cycles: int = 0) -> int:
    """`wetclutch cycle`: each vehicle driven through the phase ("all": the whole cycle), its report written;
    0 all targets met, 1 one missed, 2 an input error (one line on stderr naming it)."""
    import sys
    from ..shift.matrix8 import plant_path
    from ..shift.scenarios import ShiftError
    from ..simulate.gearbox_plant.params import PlantError
    from . import runner
    from .trace import TraceError, load_wltc_class3b
    missing = [str(plant_path(v)) for v in vehicles if not plant_path(v).is_file()]
    if missing:
        print(f"wetclutch cycle: --vehicle: no 8-speed plant file {', '.join(missing)}", file=sys.stderr)
        return 2
    if oil_degC is not None and not -40.0 <= oil_degC <= 150.0:
        print(f"wetclutch cycle: --oil {oil_degC:g} outside -40..150 degC", file=sys.stderr)
        return 2
    bad = 0
    try:
        trace = load_wltc_class3b()
        trace = trace if phase == "all" else trace.phase(phase)
        for vehicle in vehicles:
            result = runner.run_cycle(vehicle, trace, oil_degC=oil_degC)
            stem = Path(vehicle).stem
            name = f"{Path(vehicle).resolve().parent.name if stem == 'plant' else stem}_{phase}"
            figures = write(result, out, name)
            print(markdown(figures, []).split("\n| type")[0])
            print(f"wetclutch cycle: report {out / (name + '.md')}, plots {out / name}/, MDF4 {out / (name + '.mf4')}")
            bad += bool(figures["missed"])
            cycles, learned = [], None
            for k in range(1, adaptation_cycles + 1):   # each from the last one's learned values
                cycles.append(runner.run_cycle(vehicle, trace, oil_degC=oil_degC, adaptation=True, learned=learned))
                learned = cycles[-1].learned
                write(cycles[-1], out, f"{name}_adaptive{k}")
            if cycles:
                a = adaptation_figures(result, cycles)
                atomic.write_text(out / f"{name}_adaptation.json", json.dumps(a, indent=1, default=float))
                plot_learned(out / f"{name}_adaptation.png", a["learned"], a["truth"],
                             [f"cycle {k}" for k in range(1, len(cycles) + 1)])
                print(f"wetclutch cycle: adaptation over {len(cycles)} cycle(s): every limit met by"
                      f" {a['meeting_every_limit']} shifts (without, then cycle 1, 2, ...); missed:"
                      f" {'; '.join(a['missed']) or 'nothing'}; {out / (name + '_adaptation.json')}")
                bad += bool(a["missed"])
    except (TraceError, PlantError, ShiftError) as e:
        print(f"wetclutch cycle: {e}", file=sys.stderr)
        return 2
    return 1 if bad else 0
