"""The whole drive cycle in lockstep (issue 31, items 3-4; DESIGN 16): the WLTC class 3b trace driven by the
driver, the integrator's shift schedule sending the shift requests, the firmware's transmission
(wc_transmission_step in process, wetclutch.shift.transmission8.Transmission) and the 8-speed vehicle plant
(wetclutch.simulate.gearbox_plant.Plant8, richer than the TCU's model), every 1 ms period.

Per period k (dt = 1 ms):
  sensors    the plant's turbine and output speed with the vehicle file's noise and 0.25 rpm steps, its oil and
             housing temperature; the turbine-torque estimate the integrator sends: the engine's torque estimate
             (the vehicle file's bias and noise) with the lock-up closed, the converter's turbine torque with
             it open (what an engine ECU's converter model gives; its bias applies too)
  TCU        wc_transmission_step with the request the scheduler made (held until the TCU reports the shift
             ended or refused, then 0 for one period: the next request's rising edge), the current gear the
             TCU last reported, the commanded inertia time per type (transmission8.TARGET_S, the type from the
             direction and the estimate's sign, as the TCU decides it)
  plant      the five currents, the engine intervention, the lock-up's current (the schedule's lock-up rule,
             ramped at LOCKUP_RAMP_MA_PER_S; held through a shift that started locked), pedal and brake
  driver     every DRIVER_PERIOD periods (10 ms): speed PI on the trace -> pedal and brake, with the pedal map
             of the present gear and engine speed
  scheduler  every DRIVER_PERIOD periods: pedal, output speed, the TCU's gear and whether it shifts -> requests

What is kept (the plant keeps no record: 1.8 M periods would not fit): every 10 ms the cycle's channels
(CHANNELS: speeds, gear, pedal, brake, each element's θ estimate and truth, ...); per shift its 1 ms window
(from the request to SHIFT_AFTER_S after its end) reduced to the quality vector of ``shift_quality``.
"""
from __future__ import annotations

import ctypes
import math
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from ..shift.matrix8 import CONTROLLER, END_RATIO_TOLERANCE, LOCKUP_MA, RPM, _plant_and_models, plant_path
from ..shift.quality import JERK_CUTOFF_HZ, _lowpass_zero_phase
from ..calibration import shift as shift_calibration
from ..shift.scenarios import SHIFT_TOML, ShiftError
from ..shift import transmission8
# issue 29's limits, which issue 31 applies to every shift of the cycle
from ..shift.transmission8 import (ELEMENTS, EXCURSION_RPM, INERTIA_TOLERANCE, LIMITS_JERK, TARGET_S, THETA_K,
                                   TIE_UP_FRACTION, TYPES, AdaptValues, Transmission, excursion_rpm, tie_up_fraction,
                                   tie_up_Nm)
from ..simulate.gearbox_plant import Plant8
from .driver import Driver, DriverParams
from .schedule import DEFAULT_SCHEDULE, load_schedule
from .scheduler import Scheduler
from .trace import KMH_PER_MPS, SpeedTrace

DT_S = 1e-3
DRIVER_PERIOD = 10                 # the driver and the schedule every 10 ms (a driver's and a TCU's shift logic pace)
LOCKUP_RAMP_MA_PER_S = 500.0       # the lock-up closes in 2 s (the integrator's side: not the TCU's shift) ...
LOCKUP_DELAY_S = 1.0               # ... and not sooner than this after a shift ended (the shift's jerk is the TCU's)
SHIFT_BEFORE_S, SHIFT_AFTER_S = 0.1, 0.3    # a shift's window about its request and its end
SHIFT_TIMEOUT_S = 5.0              # a shift that has not ended by then is recorded as hung
GRAVITY = 9.81
AIR_DENSITY = 1.2


@dataclass
class CycleResult:
    vehicle: str
    trace: SpeedTrace
    channels: dict                  # name -> array every DRIVER_PERIOD periods
    shifts: list                    # quality dict per shift
    requests: list                  # the scheduler's ShiftRequests
    dropped: list                   # requests the TCU never engaged
    cpu_s: float
    periods: int
    adaptation: bool = False
    learned: dict = field(default_factory=dict)      # element -> its learned values at the end (AdaptValues.as_dict)
    notes: list = field(default_factory=list)


def _driver_params(params) -> DriverParams:
    v = params.vehicle
    f0 = v.vehicle_mass * GRAVITY * v.rolling_resistance
    f2 = 0.5 * getattr(v, "air_density", AIR_DENSITY) * v.drag_area / KMH_PER_MPS ** 2
    return DriverParams(vehicle_mass_kg=v.vehicle_mass, road_load_f0_N=f0, road_load_f2_N_per_kmh2=f2,
                        wheel_radius_m=v.wheel_radius)


def _turbine_torque_estimate(st, bias: float, noise: float) -> float:
    """What the integrator sends as the turbine torque (module docstring)."""
    true_Nm = st["engine_torque_Nm"] if st["lockup_locked"] > 0.5 else st["converter_turbine_torque_Nm"]
    return true_Nm * (1.0 + bias) + noise


POWER_ON_DOWN_MIN_NM = 50.0       # include/wetclutch/wc_gearbox.h WC_GEARBOX_POWER_ON_DOWN_MIN_Nm


def _kind(direction: int, torque_Nm: float) -> str:
    """The type the TCU will choose (wc_gearbox_shift_type), for the inertia time the request carries."""
    power_on = torque_Nm > (0.0 if direction > 0 else POWER_ON_DOWN_MIN_NM)
    return f"power-{'on' if power_on else 'off'} {'upshift' if direction > 0 else 'downshift'}"


class _ShiftWindow:
    """A shift's 1 ms samples, from SHIFT_BEFORE_S before its request to SHIFT_AFTER_S after its end."""

    COLUMNS = ("t_s", "accel", "w_t_rpm", "w_o_rpm", "phase") + tuple(
        f"{e}_{c}" for e in ELEMENTS for c in ("torque", "energy", "theta", "theta_est", "fill"))

    def __init__(self, request, kind: str, torque_Nm: float, pre_rows: list, lockup_locked: bool):
        self.request, self.kind, self.torque_Nm = request, kind, torque_Nm
        self.rows = list(pre_rows)
        self.k_request = len(self.rows)
        self.end_row = None
        self.report = None
        self.type_seen = None
        self.refusal = 0
        self.lockup_locked = lockup_locked

    def arrays(self) -> dict:
        a = np.asarray(self.rows, dtype=float)
        return {c: a[:, i] for i, c in enumerate(self.COLUMNS)}


def _row(t_s, st, o) -> tuple:
    row = [t_s, st["vehicle_accel_m_s2"], st["turbine_speed_rpm"], st["output_speed_rpm"], float(o.phase)]
    for i, e in enumerate(ELEMENTS):
        row += [st[f"{e}_torque_Nm"], st[f"{e}_energy_J"], st[f"{e}_theta_degC"], float(o.theta_degC[i]),
                st[f"{e}_fill"]]
    return tuple(row)


def shift_quality(w: _ShiftWindow, gearbox, ratios: dict) -> dict:
    """The quality vector of one shift of the cycle (issue 31 item 4): type, gears, peak jerk per phase, flare,
    tie-up, duration, friction energy per element, the on-coming element's θ estimate and truth."""
    a = w.arrays()
    r = w.request
    src, tgt = str(r.from_gear), str(r.to_gear)
    on = next(iter(set(gearbox.gears[tgt]) - set(gearbox.gears[src])), None)
    off = next(iter(set(gearbox.gears[src]) - set(gearbox.gears[tgt])), None)
    k0 = w.k_request
    k1 = (w.end_row if w.end_row is not None else len(w.rows) - 1)
    jerk = np.gradient(_lowpass_zero_phase(a["accel"], DT_S, JERK_CUTOFF_HZ), DT_S) if len(w.rows) > 2 else \
        np.zeros(len(w.rows))
    sl = slice(k0, min(k1 + int(round(0.2 / DT_S)) + 1, len(w.rows)))
    per_phase = {}
    for ph in np.unique(a["phase"][sl]):
        mask = a["phase"][sl] == ph
        per_phase[PHASES.get(int(ph), str(int(ph)))] = float(np.max(np.abs(jerk[sl][mask]), initial=0.0))
    flare = excursion_rpm(a["w_t_rpm"][sl], a["w_o_rpm"][sl], ratios[src], ratios[tgt])
    tie_up, drag = tie_up_Nm(a[f"{off}_torque"][sl], a[f"{off}_fill"][sl], float(a[f"{off}_torque"][k0])) \
        if off is not None else (0.0, 0.0)
    energy = {e: float(a[f"{e}_energy"][min(k1, len(w.rows) - 1)] - a[f"{e}_energy"][k0]) * 1e-3 for e in ELEMENTS}
    theta = {}
    if on is not None:
        theta = {"truth": float(np.max(a[f"{on}_theta"][sl])), "estimate": float(np.max(a[f"{on}_theta_est"][sl]))}
    report = w.report
    q = {"t_s": r.time_s, "shift": f"{src}->{tgt}", "kind": w.type_seen or w.kind, "type_requested": w.kind, "reason": r.reason,
         "oncoming": on, "offgoing": off, "turbine_torque_Nm": w.torque_Nm, "lockup_locked": w.lockup_locked,
         "refusal": w.refusal, "abort": int(report[7]) if report else -1,
         "duration_s": (k1 - k0) * DT_S if w.end_row is not None else math.nan,
         "inertia_time_s": float(report[0]) if report else math.nan, "target_s": TARGET_S[w.kind],
         "peak_jerk_m_s3": max(per_phase.values(), default=0.0), "jerk_per_phase_m_s3": per_phase,
         "flare_rpm": flare, "tie_up_Nm": tie_up, "offgoing_drag_Nm": drag,
         "tie_up_fraction": tie_up_fraction(tie_up, w.torque_Nm),
         "energy_kJ": energy, "theta_oncoming_degC": theta}
    q["missed"] = shift_missed(q)
    return q


def shift_missed(q: dict) -> list[str]:
    """Issue 29's limits a shift of the cycle misses ([] = every one met)."""
    m = []
    if q["refusal"]:
        return [f"refused (wc_gearbox_shift_result_t {q['refusal']})"]
    if q["abort"] != 0:
        m.append(f"not completed (abort {q['abort']})")
    if q["peak_jerk_m_s3"] > LIMITS_JERK[q["kind"]]:
        m.append(f"jerk {q['peak_jerk_m_s3']:.1f} > {LIMITS_JERK[q['kind']]:g}")
    if q["flare_rpm"] > EXCURSION_RPM:
        m.append(f"flare/sag {q['flare_rpm']:.0f} rpm")
    if q["tie_up_fraction"] > TIE_UP_FRACTION:
        m.append(f"tie-up {100 * q['tie_up_fraction']:.0f} %")
    t, target = q["inertia_time_s"], q["target_s"]
    stretched = q["kind"] == "power-on downshift"      # a kickdown's pace is the engine's (wc_shift.h)
    if math.isfinite(t) and (t < (1 - INERTIA_TOLERANCE) * target or
                             (not stretched and t > (1 + INERTIA_TOLERANCE) * target)):
        m.append(f"inertia {t:.2f} s of {target} s")
    th = q["theta_oncoming_degC"]
    if th and abs(th["estimate"] - th["truth"]) > THETA_K:
        m.append(f"theta est - truth {th['estimate'] - th['truth']:+.1f} K")
    return m


# wc_shift_phase_t's names (transmission8.PHASES); IDLE inside a shift's window: the 0.2 s after its end
PHASES = {0: "after", **{k: name for k, name in enumerate(transmission8.PHASES) if k > 0}}

CHANNELS = ("t_s", "target_kmh", "speed_kmh", "pedal", "brake_Nm", "gear", "phase", "engine_rpm", "turbine_rpm",
            "output_rpm", "lockup_mA", "safe") + tuple(f"{e}_{c}" for e in ELEMENTS
                                                       for c in ("theta_degC", "theta_est_degC", "current_mA"))


def _transmission(gearbox_path, oil_degC: float, lib, adaptation: bool, learned: dict | None) -> Transmission:
    """The firmware's transmission on the controller's shift calibration, with its adaptation (DESIGN 12) on or
    off, each element's learned values loaded from ``learned`` (element -> AdaptValues.as_dict)."""
    base = shift_calibration.load(SHIFT_TOML).variants[CONTROLLER]
    shift = shift_calibration.ShiftCalibration(f"{base.name}+adaptation", {**base.values, "adaptation": 1},
                                               base.sources) if adaptation else base
    tx = Transmission(gearbox_path, 1, oil_degC, lib, shift=shift)
    for name, v in (learned or {}).items():
        values = AdaptValues((ctypes.c_float * 5)(*v["friction_scale"]), (ctypes.c_float * 5)(*v["confidence"]),
                             v["film_factor"], v["kiss_offset_Pa"], int(v["shifts_learned"]))
        if name not in ELEMENTS or not tx.load_learned(ELEMENTS.index(name), values):
            raise ShiftError(f"learned values of element {name!r} refused (not an element, or outside the bands)")
    return tx


def run_cycle(vehicle="nominal", trace: SpeedTrace | None = None, *, oil_degC: float | None = None,
              schedule_path=DEFAULT_SCHEDULE, seed: int = 1, lib=None, progress=None, adaptation: bool = False,
              learned: dict | None = None) -> CycleResult:
    """Drive ``trace`` (default: the WLTC class 3b from wltp) on the vehicle (a name of tools/plants/8hp or an
    8-speed plant file anywhere); progress(t_s) is called every simulated second. adaptation: the TCU learns
    (a power-on upshift into its on-coming element), starting from ``learned`` (a previous result's)."""
    from .trace import load_wltc_class3b
    trace = trace if trace is not None else load_wltc_class3b()
    params, _models = _plant_and_models(str(plant_path(vehicle)))
    v = params.vehicle
    gb = params.gearbox
    schedule = load_schedule(schedule_path)
    ratios = {g: float(r) for g, r in zip(map(str, range(1, schedule.gears + 1)), schedule.ratios)}
    oil = v.oil_temperature if oil_degC is None else float(oil_degC)
    t0 = trace.t0_s
    standing = trace.speed_kmh_at(t0) <= 0.0
    plant = Plant8.in_gear(params, "1", trace.speed_mps_at(t0), lockup_current_mA=0.0, oil_degC=oil,
                           brake_Nm=1500.0 if standing else 0.0, record=False)
    tx = _transmission(gb.path, oil, lib, adaptation, learned)
    driver = Driver(trace, _driver_params(params), dt_s=DT_S * DRIVER_PERIOD)
    scheduler = Scheduler(schedule, 1)
    rng = np.random.default_rng(seed)
    eng = plant.engine
    n = int(round((trace.end_s - t0) / DT_S))
    keep = {c: [] for c in CHANNELS}
    shifts, window = [], None
    pre = deque(maxlen=int(round(SHIFT_BEFORE_S / DT_S)))     # the last periods before a request
    n_after = int(round(SHIFT_AFTER_S / DT_S))
    request = None                 # the request the TCU is being sent
    req_flag, gear_reported, lockup_mA, t_shift_end = 0, 1, 0.0, -math.inf
    pedal, brake = 0.0, 1500.0 if standing else 0.0
    st = plant.state
    torque_est = 0.0
    k_lift = None
    cpu0 = time.process_time()
    o = None
    for k in range(n):
        t = t0 + k * DT_S
        if k % DRIVER_PERIOD == 0:
            w_e = st["engine_speed_rpm"] * RPM
            to_wheel = ratios[str(gear_reported)] * v.final_drive / v.wheel_radius
            locked = st["lockup_locked"] > 0.5
            f0 = (eng.drag_Nm(w_e) if locked else 0.0) * to_wheel
            f1 = eng.full_Nm(w_e) * to_wheel
            cmd = driver.step(t, st["vehicle_speed_m_s"], (f0, f1))
            pedal, brake = cmd.pedal, cmd.brake_torque_Nm
            shifting = o is not None and (o.phase != 0 or request is not None)
            new = scheduler.step(t, pedal, st["output_speed_rpm"], gear_reported, shifting)
            if new is not None and request is None:
                if window is not None:      # the last shift's run-on cut short by the next request
                    shifts.append(shift_quality(window, gb, ratios))
                    window, k_lift = None, None
                request, req_flag = new, 1
                direction = 1 if new.to_gear > new.from_gear else -1
                kind = _kind(direction, torque_est)
                window = _ShiftWindow(new, kind, torque_est, pre, locked)
            # the lock-up (the integrator's side): closed from the schedule's gear and speed and kept closed
            # through a shift that started with it closed, also below the speed (the TCU's reduced model of a
            # shift has the engine's inertia turning with the turbine: matrix8); it starts closing only between
            # shifts, LOCKUP_DELAY_S after the last one ended
            wanted = (gear_reported >= schedule.lockup_min_gear and st["output_speed_rpm"] >= schedule.lockup_min_output_rpm) \
                or (window is not None and window.lockup_locked)
            if not wanted:
                lockup_mA = 0.0
            elif lockup_mA > 0.0 or (request is None and window is None and t - t_shift_end >= LOCKUP_DELAY_S):
                lockup_mA = min(LOCKUP_MA, lockup_mA + LOCKUP_RAMP_MA_PER_S * DT_S * DRIVER_PERIOD)
            if progress is not None and k % 1000 == 0:
                progress(t)
        z = rng.standard_normal(3)
        w_t, w_o = transmission8.measured_speeds_rad_s(v, st, z)
        torque_est = _turbine_torque_estimate(st, v.torque_estimate_bias, v.torque_estimate_noise * z[2])
        if request is not None:
            kind_now = window.kind
            o = tx.step(req_flag, gear_reported, request.to_gear, torque_est, TARGET_S[kind_now], w_t, w_o,
                        plant.oil_degC, plant.housing_degC)
            if window.type_seen is None:
                window.type_seen = TYPES.get(o.type)
                window.refusal = int(o.refusal)
            ended = bool(o.ended) or window.refusal != 0
            if ended and window.end_row is None:
                window.end_row = len(window.rows)
                window.report = list(o.report) if o.ended else None
                req_flag, request, k_lift, t_shift_end = 0, None, k, t
            elif (len(window.rows) - window.k_request) * DT_S > SHIFT_TIMEOUT_S and window.end_row is None:
                window.end_row = len(window.rows)
                req_flag, request, k_lift, t_shift_end = 0, None, k, t
        else:
            o = tx.step(0, gear_reported, gear_reported, torque_est, 0.5, w_t, w_o, plant.oil_degC,
                        plant.housing_degC)
        gear_reported = int(o.gear) if 1 <= o.gear <= schedule.gears else gear_reported
        currents = [float(o.current_mA[i]) for i in range(5)]
        delta = float(o.engine_delta_Nm) if o.engine_active else 0.0
        st = plant.step(currents, lockup_mA, pedal, delta, brake)
        row = _row(t + DT_S, st, o)
        if window is not None:
            window.rows.append(row)
            if k_lift is not None and k - k_lift >= n_after:
                shifts.append(shift_quality(window, gb, ratios))
                window, k_lift = None, None
        pre.append(row)
        if k % DRIVER_PERIOD == 0:
            vals = (t + DT_S, trace.speed_kmh_at(t + DT_S), st["vehicle_speed_m_s"] * KMH_PER_MPS, pedal, brake,
                    gear_reported, int(o.phase), st["engine_speed_rpm"], st["turbine_speed_rpm"],
                    st["output_speed_rpm"], lockup_mA, 0.0)
            for c, x in zip(CHANNELS, vals):
                keep[c].append(x)
            for i, e in enumerate(ELEMENTS):
                keep[f"{e}_theta_degC"].append(st[f"{e}_theta_degC"])
                keep[f"{e}_theta_est_degC"].append(float(o.theta_degC[i]))
                keep[f"{e}_current_mA"].append(currents[i])
    if window is not None:
        shifts.append(shift_quality(window, gb, ratios))
    channels = {c: np.asarray(x, dtype=float) for c, x in keep.items()}
    return CycleResult(str(vehicle), trace, channels, shifts, list(scheduler.requests), list(scheduler.dropped),
                       time.process_time() - cpu0, n, adaptation,
                       {e: tx.learned(i).as_dict() for i, e in enumerate(ELEMENTS)})
