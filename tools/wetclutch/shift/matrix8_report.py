"""The 8-speed's power-on upshift matrix (matrix8) run whole and reported: per vehicle of the family a markdown
table (shift, load, the driver's turbine torque, peak jerk total / torque phase / inertia phase, flare, tie-up
with its split, inertia time against the target, friction energy per element, peak on-coming temperature
estimate / truth, the TCU's report, the end gear by truth, the targets missed) and the figures as JSON.

    .venv/bin/python -m wetclutch.shift.matrix8_report --out out/matrix8 [--vehicles nominal heavy light]
        [--loads 1.0 0.25] [--oil 80] [--processes 2]

writes OUT/matrix8.md and OUT/matrix8.json, prints the tables and exits 1 when a shift misses one of issue
29's targets (matrix8.TARGETS), 0 when every shift meets them.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from multiprocessing import Pool
from pathlib import Path

from ..util.atomic import Staged
from . import matrix8
from .scenarios import ShiftError


def _one(job):
    vehicle, from_gear, load, oil = job
    try:
        return job, matrix8.run_upshift(vehicle, from_gear, load, oil)
    except ShiftError as e:      # a shift that cannot run is a row with its reason, not a lost matrix
        return job, {"error": str(e)}


def jobs(vehicles=matrix8.VEHICLES, loads=matrix8.LOADS, oil_degC: float = matrix8.OIL_DEGC,
         shifts=matrix8.UPSHIFTS) -> list[tuple]:
    return [(v, src, load, oil_degC) for v in vehicles for load in loads for src, _ in shifts]


def run_matrix(vehicles=matrix8.VEHICLES, loads=matrix8.LOADS, oil_degC: float = matrix8.OIL_DEGC,
               processes: int = 2, shifts=matrix8.UPSHIFTS) -> dict:
    """{vehicle: [quality dict per (load, shift)]} in the jobs' order (each dict names its shift and load)."""
    out: dict = {}
    todo = jobs(vehicles, loads, oil_degC, shifts)
    with Pool(processes) as pool:
        for (v, src, load, oil), q in pool.imap(_one, todo):
            if "error" in q:
                q = {**q, "vehicle": v, "shift": f"{src}->{src + 1}", "load": load, "oil_degC": oil,
                     "missed": [f"not run: {q['error']}"]}
            out.setdefault(v, []).append(q)
    return out


def _f(x, digits=1) -> str:
    return f"{x:.{digits}f}" if isinstance(x, (int, float)) and math.isfinite(x) else "-"


HEAD = ("| shift | on/off (a) | load | T_t Nm | jerk total / torque ph. / inertia ph. m/s^3 | flare rpm"
        " | tie-up % (applied / drag) | inertia s (err %) | energy A / B / C / D / E kJ"
        " | peak theta est / truth degC | TCU report | end | missed |")


def _row(q) -> str:
    if "error" in q:
        return f"| {q['shift']} | | {100 * q['load']:.0f} % | | | | | | | | | | {q['missed'][0]} |"
    e = q["energy_kJ"]
    return (f"| {q['shift']} | {q['oncoming']} ({q['oncoming_slip_scale']:.2f}) / {q['offgoing']}"
            f" ({q['offgoing_slip_scale']:.2f}) | {100 * q['load']:.0f} % | {_f(q['turbine_torque_Nm'], 0)}"
            f" | {_f(q['peak_jerk_m_s3'])} / {_f(q['torque_phase_jerk_m_s3'])} / {_f(q['peak_inertia_jerk_m_s3'])}"
            f" | {_f(max(q['flare_rpm'], 0.0))} | {_f(100 * q['tie_up_fraction'])}"
            f" ({_f(100 * q['tie_up_applied_fraction'])} / {_f(100 * q['offgoing_drag_fraction'])})"
            f" | {_f(q['inertia_time_s'], 3)} ({_f(100 * q['inertia_time_error'])})"
            f" | {' / '.join(_f(abs(e[n]), 2) for n in sorted(e))}"
            f" | {_f(q['peak_theta_estimate_degC'])} / {_f(q['peak_theta_truth_degC'])}"
            f" | {q['abort_reason']} | {q['end_gear'] or 'none'} | {'; '.join(q['missed']) or 'none'} |")


def markdown(cases: dict) -> str:
    t = matrix8.TARGETS
    lines = ["# The 8-speed's power-on upshifts with today's whole-shift controller (issue 29 item 5)", "",
             f"Closed loop: wetclutch.simulate.gearbox_plant.Plant8 against wc_replay --lockstep (variant "
             f"{matrix8.CONTROLLER} of tools/calibrations/shift_1_2.toml with each shift's reduced model; each element"
             " its own clutch as an equivalent clutch in the controller's coordinates:"
             " tools/wetclutch/shift/matrix8.py)."
             f" Commanded at {matrix8.COMMAND_TURBINE_RPM:.0f} rpm turbine speed, target inertia time "
             f"{matrix8.TARGET_INERTIA_S:g} s, oil as stated; held elements at full current, lock-up locked.", "",
             "From the plant's truth in the controller's coordinates (slip / a, torque x a): jerk of the vehicle"
             " (10 Hz low-pass), torque phase from the command to the controller's inertia phase, inertia phase"
             " from there to synchronism, total from the command to the end (1.5 s); flare: turbine above the source"
             " gear's speed; tie-up: the largest torque the off-going element carries against the shift, % of the"
             " gearbox input torque before the command (applied: while its piston is on the pack; drag: after, the"
             " released element's open drag); energy: each element's friction energy from the command on; theta:"
             " the on-coming element (the TCU's ClutchEstimate / the plant). a: the element's slip per rad/s of"
             " turbine speed in the shift (matrix8's normalisation).", "",
             f"Targets (issue 29, power-on upshift): peak jerk <= {t['jerk_m_s3']:g} m/s^3,"
             f" flare <= {t['flare_rpm']:g} rpm,"
             f" tie-up <= {100 * t['tie_up_fraction']:g} % (the whole shift, applied and drag), inertia time within"
             f" +-{100 * t['time_tolerance']:g} % of the target, completed, in the target gear by truth.", ""]
    for v, rows in cases.items():
        oil = rows[0].get("oil_degC", matrix8.OIL_DEGC) if rows else matrix8.OIL_DEGC
        met = sum(1 for q in rows if not q["missed"])
        lines += [f"## {v} (oil {oil:g} degC): {met} of {len(rows)} shifts meet every target", "", HEAD,
                  "|" + "---|" * 13]
        lines += [_row(q) for q in rows]
        lines.append("")
    return "\n".join(lines)


def report(out_dir, vehicles=matrix8.VEHICLES, loads=matrix8.LOADS, oil_degC: float = matrix8.OIL_DEGC,
           processes: int = 2) -> dict:
    """Run the matrix; write out_dir/matrix8.md and matrix8.json; return {"cases", "missed"}."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = run_matrix(vehicles, loads, oil_degC, processes)
    missed = {f"{v} {q['shift']} {100 * q['load']:.0f} %": q["missed"] for v, rows in cases.items() for q in rows
              if q["missed"]}
    payload = {"targets": matrix8.TARGETS, "cases": cases, "missed": missed}
    with Staged() as staged:
        staged.write_text(out_dir / "matrix8.json", json.dumps(payload, indent=1, default=float, sort_keys=True))
        staged.write_text(out_dir / "matrix8.md", markdown(cases))
    return payload


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m wetclutch.shift.matrix8_report",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, required=True, help="directory for matrix8.md and matrix8.json")
    ap.add_argument("--vehicles", nargs="+", default=list(matrix8.VEHICLES),
                    help="names of tools/plants/8hp/ or 8-speed plant files")
    ap.add_argument("--loads", nargs="+", type=float, default=list(matrix8.LOADS), help="fractions of full load")
    ap.add_argument("--oil", type=float, default=matrix8.OIL_DEGC, help="oil temperature, degC")
    ap.add_argument("--processes", type=int, default=2)
    args = ap.parse_args(argv)
    res = report(args.out, args.vehicles, args.loads, args.oil, args.processes)
    print((args.out / "matrix8.md").read_text(encoding="utf-8"))
    return 1 if res["missed"] else 0


if __name__ == "__main__":
    sys.exit(main())
