"""In-gear hold at full load on the 8-speed plant with the firmware's transmission (issue 29's in-gear target).

Issue 29: "In a gear at full load, no closed element slips more than 5 rpm, and none is commanded above its
holding need plus the margin." Per vehicle (tools/plants/8hp), forward gear and oil temperature, the firmware's
transmission (transmission8.Transmission: wc_transmission_step in process) holds the gear (no shift request,
current gear = target gear = the gear) against the 8-speed plant (Plant8.in_gear) at full pedal, with
transmission8._simulate's plumbing: the turbine and output speeds with the vehicle file's sensor noise and 0.25
rpm steps, the engine's torque estimate with its bias and noise as T_t, the plant's oil and housing
temperatures, the TCU's five currents (and its engine request, none in a gear) applied to the plant each 1 ms
period, the converter's lock-up at LOCKUP_MA.

The operating point (stated, the module's choices):
  - the turbine at RPM_HOLD (2500 rpm, the power-on upshift's scenario speed of transmission8.SCENARIOS: on the
    engine's full-load plateau, 1500..4500 rpm), pedal 1.0;
  - DYNO (default): a brake torque at the wheels holds the vehicle's speed (a chassis dynamometer; a feed-forward
    from two steady solves of the initialiser, the zero-acceleration brake, plus a proportional term on the
    wheel speed). Without it, in 1st at full load the turbine would rise about 2200 rpm/s, past the plateau
    and the rev limiter within the run; held, every gear carries the whole engine torque, none of it spent on
    accelerating the engine side (the harder case for the closed elements), and T_t is the same in all gears;
  - the plant starts in a steady state with the closed elements at the TCU's own holding currents (the TCU
    stepped PREROLL_PERIODS on the initial state first: its lock-up dwell passed), not at their maximum: the
    true elements' squeeze film releases over seconds (element.py), a start from the maximum would carry its
    surplus capacity through the whole measurement;
  - SETTLE_S of the closed loop, then DURATION_S measured.

Per row (hold_gear): per closed element, after the settling (truth): the largest |slip| (rpm), the carried
torque, the static capacity (the plant's NAME_capacity_Nm: at the piston's actual pressure, in steady hold the
commanded current's), the true margin capacity / |carried| (its minimum and mean); and the TCU's side: its
commanded current, its need |holding_torque_per_Nm x T_t| (T_t its estimate; the gearbox table's holding
torque), the holding request max(need x HOLDING_MARGIN, HOLDING_FLOOR_NM) (wc_gearbox_holding_request_Nm),
the current that request implies through the clutch's locked inverse (wc_inverse_holding, DESIGN 9: the force
request x (1 + the element calibration's holding_margin) / its static capacity per N; the reference's
holding_inverse, vectorised), the TCU model's static capacity at the commanded current (the element's own
calibration, the TCU's temperature estimate) and that over the request and over the need.

Verdicts per row: slip_ok (every closed element's largest |slip| <= SLIP_LIMIT_RPM: the target), over_commanded
(the elements whose TCU-model capacity at the commanded current exceeds the request, need x margin or the floor,
by more than OVER_TOLERANCE: "commanded above its holding need plus the margin", judged on the TCU's own model),
follows_rule (the commanded current within RULE_TOLERANCE_MA of the locked inverse of the request: the TCU does
what its holding rule says, no gear-slip latch at the maximum), and the true margins to show over-holding.

    PYTHONPATH=tools .venv/bin/python -m wetclutch.shift.ingear8 [--vehicles nominal heavy light]
        [--oil 20 80 110] [--gears 1 .. 8] [--duration 2.0] [--out FILE.json]
Exit 0: every row meets both targets; 1: a row misses one (the table says which); 2: a row could not run.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from .. import gearbox as gearbox_pkg
from ..gearbox import kinematics, table as gearbox_table
from ..reference.model.friction import static_capacity_Nm
from ..reference.model.inverse import kiss_pressure_Pa
from ..simulate.gearbox_plant import Plant8
from .matrix8 import LOCKUP_MA, RPM, _plant_and_models, plant_path
from .scenarios import ShiftError
from .transmission8 import (ELEMENTS, HOLDING_FLOOR_NM, HOLDING_MARGIN, SCENARIOS, TCU_VEHICLE, Transmission,
                            _library, measured_speeds_rad_s)

SLIP_LIMIT_RPM = 5.0                 # issue 29: no closed element slips more than 5 rpm in a gear
RPM_HOLD = SCENARIOS["power-on upshift"][2]      # 2500 rpm: full load available (the plateau 1500..4500)
PEDAL = 1.0
SETTLE_S, DURATION_S = 0.5, 2.0
PREROLL_PERIODS = 50                 # the TCU on the initial state before the plant starts (its lock-up dwell: 10)
OVER_TOLERANCE = 0.02                # capacity over the request beyond this: commanded above need x margin
RULE_TOLERANCE_MA = 2.0              # commanded vs the rule's current (float32 vs double, the VFS steps)
DYNO_GAIN_NM_PER_RAD_S = 300.0       # the dyno's proportional term on the wheel speed (N m per rad/s)
GEARS = tuple(range(1, 9))
VEHICLES = ("nominal", "heavy", "light")
OILS = (20.0, 80.0, 110.0)


def _holding_table(gearbox_path: str) -> dict:
    """gear -> {element: holding torque per N m of T_t} of the TCU's gearbox table (transmission8.gearbox_image's
    source: the plant's gearbox description with TCU_VEHICLE)."""
    gb = gearbox_pkg.load(str(gearbox_path))
    table = tomllib.loads(gearbox_table.text(gb, gearbox_pkg.load_vehicle(str(TCU_VEHICLE))))
    return {g: dict(v["holding_torque"]) for g, v in table["gears"].items()}


def holding_request_Nm(per_Nm: float, torque_Nm, margin: float = HOLDING_MARGIN, floor: float = HOLDING_FLOOR_NM):
    """wc_gearbox_holding_request_Nm for a closed element: |per_Nm x T_t| x margin, at least floor (arrays)."""
    return np.maximum(np.abs(per_Nm * np.asarray(torque_Nm, dtype=float)) * abs(margin), abs(floor))


def holding_current_mA(cal, theta_degC, request_Nm):
    """The locked inverse's current for a request (the reference's holding_inverse, vectorised: the force request
    x (1 + holding_margin) / the static capacity per N at theta, at most the maximum current; the pressure of
    that force on the return spring, P = K i)."""
    per_N = static_capacity_Nm(cal, np.asarray(theta_degC, dtype=float), 1.0)
    force = np.asarray(request_Nm, dtype=float) * (1.0 + cal.holding_margin) / per_N
    current = kiss_pressure_Pa(cal, force) / cal.vfs_gain
    return np.clip(current, cal.vfs_current_min, cal.vfs_current_max)


def model_capacity_Nm(cal, theta_degC, current_mA):
    """The TCU model's static capacity at a current (steady pressure K i, contact force P A_p - F_s >= 0)."""
    force = np.maximum(cal.vfs_gain * np.asarray(current_mA, dtype=float) * cal.piston_area
                       - cal.return_spring_force, 0.0)
    return static_capacity_Nm(cal, np.asarray(theta_degC, dtype=float), force)


def _dyno_brake_Nm(params, gear: str, speed: float, currents: dict, oil_degC: float) -> float:
    """The wheel brake that makes the initial state's acceleration zero (two steady solves; linear in the brake)."""
    def accel(brake):
        p = Plant8.in_gear(params, gear, speed, pedal=PEDAL, currents_mA=currents, lockup_current_mA=LOCKUP_MA,
                           oil_degC=oil_degC, brake_Nm=brake, record=False)
        return p.state["vehicle_accel_m_s2"]
    b1 = 1000.0
    a0, a1 = accel(0.0), accel(b1)
    return max(-a0 * b1 / (a1 - a0), 0.0) if a1 != a0 else 0.0


def hold_gear(vehicle, gear: int, oil_degC: float, *, rpm: float = RPM_HOLD, settle_s: float = SETTLE_S,
              duration_s: float = DURATION_S, dyno: bool = True, seed: int = 1, lib=None,
              force_mA: dict | None = None, keep_traces: bool = False) -> dict:
    """One row: the gear held at full pedal for settle_s + duration_s (module docstring). force_mA: {element:
    current} sent to the PLANT instead of the TCU's (a fault to show the slip measure sees slipping; the TCU still
    computes its own). keep_traces: the per-period arrays under "traces" (not JSON-friendly)."""
    params, _models = _plant_and_models(str(plant_path(vehicle)))
    v = params.vehicle
    g = str(gear)
    closed = tuple(params.gearbox.gears[g])
    ratio = float(kinematics.ratio(params.gearbox, g))
    speed = rpm * RPM / ratio / v.final_drive * v.wheel_radius
    per_Nm = _holding_table(str(params.gearbox.path))[g]
    gb = gearbox_pkg.load(str(params.gearbox.path))
    cals = {e: gb.element(e).calibration for e in closed}
    lib = lib or _library()
    rng = np.random.default_rng(seed)

    def measure(st):
        z = rng.standard_normal(4)
        w_t, w_o = measured_speeds_rad_s(v, st, z)
        return w_t, w_o, st["engine_torque_Nm"] * (1.0 + v.torque_estimate_bias) + v.torque_estimate_noise * z[2]

    # the TCU's holding currents on the initial state, then the plant in steady state at them
    first = Plant8.in_gear(params, g, speed, pedal=PEDAL, lockup_current_mA=LOCKUP_MA, oil_degC=oil_degC,
                           record=False)
    tx = Transmission(params.gearbox.path, gear, oil_degC, lib)
    for _ in range(PREROLL_PERIODS):
        w_t, w_o, torque = measure(first.state)
        o = tx.step(False, gear, gear, torque, 0.5, w_t, w_o, first.oil_degC, first.housing_degC)
    currents = {e: float(o.current_mA[i]) for i, e in enumerate(ELEMENTS)}
    brake0 = _dyno_brake_Nm(params, g, speed, currents, oil_degC) if dyno else 0.0
    plant = Plant8.in_gear(params, g, speed, pedal=PEDAL, currents_mA=currents, lockup_current_mA=LOCKUP_MA,
                           oil_degC=oil_degC, brake_Nm=brake0)
    st = plant.state
    w_w0 = st["wheel_speed_rpm"] * RPM
    dt = plant.dt
    n_settle, n = int(round(settle_s / dt)), int(round((settle_s + duration_s) / dt))
    tcu = {"current": [], "theta": [], "model": [], "torque": [], "brake": []}
    for _k in range(n):
        w_t, w_o, torque = measure(st)
        o = tx.step(False, gear, gear, torque, 0.5, w_t, w_o, plant.oil_degC, plant.housing_degC)
        currents = {e: float(o.current_mA[i]) for i, e in enumerate(ELEMENTS)}
        tcu["current"].append(list(o.current_mA))
        tcu["theta"].append(list(o.theta_degC))
        tcu["model"].append(list(o.model_torque_Nm))
        tcu["torque"].append(torque)
        if force_mA:
            currents.update(force_mA)
        engine_delta = float(o.engine_delta_Nm) if o.engine_active else 0.0
        brake = max(brake0 + DYNO_GAIN_NM_PER_RAD_S * (st["wheel_speed_rpm"] * RPM - w_w0), 0.0) if dyno else 0.0
        tcu["brake"].append(brake)
        st = plant.step(currents, LOCKUP_MA, PEDAL, engine_delta, brake)
    truth = plant.record()
    return _row(vehicle, gear, oil_degC, closed, per_Nm, cals, truth, {k: np.asarray(a, dtype=float)
                                                                          for k, a in tcu.items()},
                n_settle, {"rpm": rpm, "settle_s": settle_s, "duration_s": duration_s, "dyno": dyno,
                           "forced_mA": dict(force_mA or {})}, keep_traces)


def _row(vehicle, gear, oil_degC, closed, per_Nm, cals, truth, tcu, n_settle, case, keep_traces) -> dict:
    # TCU row k (periods 0 .. n-1) computed from truth row k, applied over period k: the plant's answer is row
    # k + 1. The window: periods n_settle .. n-1 (TCU) and rows n_settle + 1 .. n (truth).
    win_t = slice(n_settle + 1, None)
    win_c = slice(n_settle, None)
    t_est = tcu["torque"][win_c]
    elements = {}
    for e in closed:
        i = ELEMENTS.index(e)
        cal = cals[e]
        slip = np.abs(truth[f"{e}_slip_rad_s"][win_t]) / RPM
        carried = truth[f"{e}_torque_Nm"][win_t]
        capacity = truth[f"{e}_capacity_Nm"][win_t]
        margin = capacity / np.maximum(np.abs(carried), 1e-9)
        current = tcu["current"][win_c, i]
        theta = tcu["theta"][win_c, i]
        need = np.abs(per_Nm[e] * t_est)
        request = holding_request_Nm(per_Nm[e], t_est)
        rule_mA = holding_current_mA(cal, theta, request)
        cap_model = model_capacity_Nm(cal, theta, current)
        over = float(np.max(cap_model / request))
        elements[e] = {
            "slip_max_rpm": float(np.max(slip)), "locked_fraction": float(np.mean(truth[f"{e}_locked"][win_t])),
            "carried_Nm": float(np.mean(carried)), "carried_abs_max_Nm": float(np.max(np.abs(carried))),
            "carried_per_input": float(np.mean(np.abs(carried)) / max(np.mean(np.abs(
                truth["input_torque_Nm"][win_t])), 1e-9)), "holding_torque_per_Nm": float(per_Nm[e]),
            "capacity_true_Nm": float(np.mean(capacity)), "capacity_true_min_Nm": float(np.min(capacity)),
            "margin_true_min": float(np.min(margin)), "margin_true_mean": float(np.mean(margin)),
            "current_mA": float(np.mean(current)), "current_max_mA": float(np.max(current)),
            "rule_current_mA": float(np.mean(rule_mA)),
            "current_minus_rule_max_mA": float(np.max(np.abs(current - rule_mA))),
            "theta_estimate_degC": float(np.mean(theta)),
            "theta_true_degC": float(np.mean(truth[f"{e}_theta_degC"][win_t])),
            "need_Nm": float(np.mean(need)), "request_Nm": float(np.mean(request)),
            "floor_governs": bool(np.any(request <= HOLDING_FLOOR_NM)),
            "model_torque_Nm": float(np.mean(tcu["model"][win_c, i])),
            "capacity_model_Nm": float(np.mean(cap_model)),
            "capacity_model_over_request_max": over,
            "capacity_model_over_need": float(np.mean(cap_model) / max(np.mean(need), 1e-9)),
            "over_commanded": bool(over > 1.0 + OVER_TOLERANCE),
        }
    worst = max(closed, key=lambda e: elements[e]["slip_max_rpm"])
    margins = [elements[e]["margin_true_min"] for e in closed]
    row = {"vehicle": str(vehicle), "gear": int(gear), "oil_degC": float(oil_degC), **case, "closed": list(closed),
           "turbine_rpm_mean": float(np.mean(truth["turbine_speed_rpm"][win_t])),
           "turbine_rpm_span": float(np.ptp(truth["turbine_speed_rpm"][win_t])),
           "engine_torque_Nm": float(np.mean(truth["engine_torque_Nm"][win_t])),
           "input_torque_Nm": float(np.mean(truth["input_torque_Nm"][win_t])),
           "torque_estimate_Nm": float(np.mean(t_est)), "brake_Nm": float(np.mean(tcu["brake"][win_c])),
           "elements": elements, "worst_slip_rpm": elements[worst]["slip_max_rpm"], "worst_slip_element": worst,
           "margin_true_min": float(min(margins)),
           "margin_true_max": float(max(elements[e]["margin_true_mean"] for e in closed)),
           "slip_ok": bool(all(elements[e]["slip_max_rpm"] <= SLIP_LIMIT_RPM for e in closed)),
           "over_commanded": [e for e in closed if elements[e]["over_commanded"]],
           "follows_rule": bool(all(elements[e]["current_minus_rule_max_mA"] <= RULE_TOLERANCE_MA for e in closed))}
    row["ok"] = row["slip_ok"] and not row["over_commanded"]
    if keep_traces:
        row["traces"] = {"truth": truth, "tcu": tcu, "n_settle": n_settle}
    return row


def run_grid(vehicles=VEHICLES, oils=OILS, gears=GEARS, **kwargs) -> list[dict]:
    lib = _library()
    rows = []
    for vehicle in vehicles:
        for oil in oils:
            for gear in gears:
                t0 = time.process_time()
                try:
                    row = hold_gear(vehicle, gear, oil, lib=lib, **kwargs)
                except (ShiftError, ValueError) as e:
                    row = {"vehicle": vehicle, "gear": gear, "oil_degC": oil, "error": f"not run: {e}", "ok": False}
                row["cpu_s"] = time.process_time() - t0
                rows.append(row)
                print(line(row), flush=True)
    return rows


def line(r: dict) -> str:
    if r.get("error"):
        return f"{r['vehicle']:8s} {r['oil_degC']:5.0f} degC gear {r['gear']}: {r['error']}"
    parts = " ".join(f"{e} {x['slip_max_rpm']:5.2f} rpm {x['current_mA']:5.0f}/{x['rule_current_mA']:5.0f} mA"
                     f" m {x['margin_true_min']:4.2f} mdl/req {x['capacity_model_over_request_max']:4.2f}"
                     for e, x in r["elements"].items())
    return (f"{r['vehicle']:8s} {r['oil_degC']:5.0f} degC gear {r['gear']} T_in {r['input_torque_Nm']:5.1f} N m"
            f" | {parts} | slip {'ok' if r['slip_ok'] else 'MISSED'}"
            f" over {','.join(r['over_commanded']) or '-'}{'' if r['follows_rule'] else ' (not the rule)'}")


def summary(rows: list[dict]) -> str:
    """Markdown: per vehicle and oil the worst slip (gear, element), the true margins' range, the verdicts."""
    lines = ["| vehicle | oil °C | worst slip rpm (gear, element) | true margin min / max | slip <= 5 rpm |"
             " over need x 1.3 (TCU model) |", "|---|---|---|---|---|---|"]
    for key in dict.fromkeys((r["vehicle"], r["oil_degC"]) for r in rows):
        rs = [r for r in rows if (r["vehicle"], r["oil_degC"]) == key and not r.get("error")]
        if not rs:
            lines.append(f"| {key[0]} | {key[1]:g} | not run | | | |")
            continue
        w = max(rs, key=lambda r: r["worst_slip_rpm"])
        over = sum(len(r["over_commanded"]) for r in rs)
        n_el = sum(len(r["closed"]) for r in rs)
        ratio = [x["capacity_model_over_request_max"] for r in rs for x in r["elements"].values()]
        lines.append(f"| {key[0]} | {key[1]:g} | {w['worst_slip_rpm']:.2f} ({w['gear']}, {w['worst_slip_element']})"
                     f" | {min(r['margin_true_min'] for r in rs):.2f} / {max(r['margin_true_max'] for r in rs):.2f}"
                     f" | {sum(r['slip_ok'] for r in rs)} of {len(rs)} gears | {over} of {n_el} elements"
                     f" ({min(ratio):.2f}-{max(ratio):.2f} x request) |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m wetclutch.shift.ingear8", description=__doc__.split("\n")[0])
    ap.add_argument("--vehicles", nargs="+", default=list(VEHICLES))
    ap.add_argument("--oil", nargs="+", type=float, default=list(OILS), help="oil temperatures, degC")
    ap.add_argument("--gears", nargs="+", type=int, default=list(GEARS))
    ap.add_argument("--duration", type=float, default=DURATION_S, help="measured seconds after the settling")
    ap.add_argument("--settle", type=float, default=SETTLE_S)
    ap.add_argument("--rpm", type=float, default=RPM_HOLD, help="turbine speed held")
    ap.add_argument("--no-dyno", dest="dyno", action="store_false", help="no brake: the vehicle accelerates")
    ap.add_argument("--out", type=Path, help="write the rows as JSON here")
    args = ap.parse_args(argv)
    t0 = time.process_time()
    rows = run_grid(args.vehicles, args.oil, args.gears, rpm=args.rpm, settle_s=args.settle,
                    duration_s=args.duration, dyno=args.dyno)
    print(summary(rows))
    print(f"ingear8: {sum(r['ok'] for r in rows)} of {len(rows)} rows meet both targets;"
          f" {time.process_time() - t0:.0f} s CPU")
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(rows, indent=1))
    if any(r.get("error") for r in rows):
        return 2
    return 0 if all(r["ok"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
