"""The first rows of the 8-speed's shift matrix (issue 29 item 5, DESIGN 15): every single-step power-on upshift
1->2 ... 7->8 on the 8-speed plant (wetclutch.simulate.gearbox_plant.Plant8), closed in a loop with TODAY's
whole-shift controller (variant whole_full of tools/calibrations/shift_1_2.toml) through the in-process frame
loop (wc_replay --lockstep), each shift given its row of the gearbox's reduced model.

THE MAPPING (DESIGN 15's normalisation, wetclutch.gearbox.reduction). The controller knows two clutches, the
on-coming and the off-going one, each with slip w_t - b w_o (b = the target's, b1 = the source's ratio). An
element's own slip is a w_t - b_e w_o = a (w_t - (b_e / a) w_o), so the controller's slip is the element's
divided by a (oncoming_slip_scale, offgoing_slip_scale; signed: an element that slips backwards, a < 0, still
gives the controller a positive upshift slip) and, by virtual work, the controller's torque is a x the element's.
The TCU's clutch model of each element is that element's own clutch (wetclutch.gearbox.description: its pack,
piston, return spring and VFS merged into the description's base calibration) as an EQUIVALENT CLUTCH in
controller coordinates (equivalent_clutch_values), so that for every current the model's torque is |a| x the
element's and every other quantity is the element's:

  radii R_o, R_i x |a|      R_eff (eq. 3) x |a|; the sliding speed v = R_eff |dw| (eq. 4) unchanged (the slip
                            is / |a|), so mu_f (eq. 18), the viscous term mu_v A_f v / h_bar (eq. 5-8) and the
                            Stribeck speed are the element's; the torque arm R_eff N_c and with it the Coulomb
                            and viscous torque and the static capacity x |a|; eq. 1's power |T dw| unchanged
  heat capacity             the element's C (the image carries C itself; the loader's C from the radii would
                            grow by a^2 with the separator's annulus)
  friction area, piston,    unchanged: F_c = P A_p - F_s, p_c = F_c / A_f and h_bar(p_c) (eq. 9-16, the film
  spring, VFS, film table   table) are forces and pressures, not torques
  film_squeeze_factor / a^4 the squeeze film's Reynolds factor K (wc_model.c) is homogeneous of degree 4 in the
                            radii: phi K stays the element's (0 here: the description's base, table1, has the
                            film state off)
  open_aeration_speed / |a| the open drag's factor 1 / (1 + (slip / w_a)^2) (DESIGN 15) takes the element's slip,
                            a |a| x the controller's; the open clearance (a gap) is the element's
So the equivalent clutch's torque, capacity, film and heat are the element's, exact in real arithmetic; in
float32 the radii, R_eff and K round once more (relative 1e-7). NOT scaled, on purpose: the lock and breakaway
bands (lock_slip 0.3, breakaway_slip 0.8 rad/s: "6 sigma of a 0.5 rpm speed sensor") are detection bands of
the MEASURED slip, and the TCU measures the controller's slip w_t - b w_o (turbine and output speed sensors),
whose noise does not grow with |a|; scaled by 1/|a| (scale_bands=True) brake A's band in 6->7 (a = 6.2) is
0.46 rpm, inside the sensors' noise, and the lock is never confirmed (measured: "lockup failed", released, the
turbine flared 1059 rpm). Likewise the controller's own thresholds (flare_slip, handover_slip, min_start_slip)
stay in its coordinates, as the shift calibration states them.

What the runner does beyond the TCU (stated, a later step's work): the source gear's HELD elements (the two the
shift keeps closed) are commanded at their maximum current throughout (not at holding need + margin); the two
open elements at 0; the converter's lock-up at its maximum (locked: the shift table's turbine inertia counts the
engine). The controller's ShiftCommand says TargetGear 2 (today's controller knows one shift: the reduced model
makes every row that shift). Sensors: the controller's two slips from the plant's element slips / a with the
vehicle file's speed-sensor noise and the DBC's 0.25 rpm step, the oil and housing temperatures with their
noise, the turbine torque estimate the engine's torque with the vehicle file's bias and noise. The shift is
commanded at 2500 rpm turbine speed after 0.2 s in the source gear (the 1->2 runs' point); load: the fraction of
the full-load torque at that speed (pedal from the engine map); target inertia time 0.5 s for every shift.

Quality (quality8): the 1->2 runs' quality vector (quality.quality) on the controller's coordinates from the
plant's truth, plus per element its friction energy from the command on, the end gear by truth (every element of
the target gear locked, the turbine / output ratio the target's within 0.5 %) and the on-coming element's peak
temperature, estimate and truth. Targets (issue 29): TARGETS.

One shift: run_upshift(vehicle, from_gear, load, oil_degC) -> quality dict. The matrix and its report:
``.venv/bin/python -m wetclutch.shift.matrix8_report --out out/matrix8`` (matrix8_report).
"""
from __future__ import annotations

import functools
import math
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from .. import gearbox as gearbox_pkg
from ..calibration import cal_image, shift as shift_calibration
from ..calibration.parameters import f32
from ..gearbox import kinematics, reduction
from ..reference import shift as shift_reference
from ..simulate.gearbox_plant import Plant8, load_plant8
from ..util import canlog
from .quality import quality
from .scenarios import ROOT, SHIFT_TOML, WC_REPLAY, ShiftError
from .tcu import InprocTcu

PLANTS_8HP = ROOT / "tools" / "plants" / "8hp"
VEHICLES = ("nominal", "heavy", "light")
CONTROLLER = "whole_full"
UPSHIFTS = tuple((g, g + 1) for g in range(1, 8))
LOADS = (1.0, 0.25)
OIL_DEGC = 80.0
COMMAND_TURBINE_RPM = 2500.0
TARGET_INERTIA_S = 0.5
LOCKUP_MA = 1000.0
RPM = math.pi / 30.0
END_RATIO_TOLERANCE = 0.005
# issue 29's targets for a power-on upshift
TARGETS = {"jerk_m_s3": 10.0, "flare_rpm": 30.0, "tie_up_fraction": 0.10, "time_tolerance": 0.10}


# ---------------------------------------------------------------------------------------------- the TCU's side
@functools.lru_cache(maxsize=16)
def _element_clutch_values(gearbox_path: str, element: str) -> dict:
    """The image's clutch fields of an element's own calibration (the film table is built once per element)."""
    gb = gearbox_pkg.load(gearbox_path)
    return cal_image._clutch_values(gb.element(element).calibration)   # noqa: SLF001 (the image's own builder)


def equivalent_clutch_values(gearbox_path, element: str, slip_scale: float, scale_bands: bool = False) -> dict:
    """The image's clutch fields of the element's EQUIVALENT clutch in the controller's coordinates (module
    docstring): radii x |a|, film_squeeze_factor / a^4, the open drag's aeration speed / |a| (a slip; 0 stays
    off), everything else (the heat capacity and the open clearance included) the element's own; the lock and breakaway bands / |a| only with scale_bands (they are the measured slip's
    bands, not the plates'). Raises ShiftError when a scaled value leaves the firmware's limits (wc_replay
    checks the image again)."""
    s = abs(float(slip_scale))
    if not (math.isfinite(s) and s > 0.0):
        raise ShiftError(f"element {element}: slip scale {slip_scale!r} cannot be normalised")
    values = dict(_element_clutch_values(str(gearbox_path), element))
    for name in ("clutch.outer_radius_m", "clutch.inner_radius_m"):
        values[name] = f32(values[name] * s)
    if scale_bands:
        for name in ("clutch.lock_slip_rad_s", "clutch.breakaway_slip_rad_s"):
            values[name] = f32(values[name] / s)
    values["clutch.open_aeration_speed_rad_s"] = f32(values["clutch.open_aeration_speed_rad_s"] / s)
    phi = values["clutch.film_squeeze_factor"]
    if phi > 0.0:
        values["clutch.film_squeeze_factor"] = f32(phi / s ** 4)
        if values["clutch.film_squeeze_factor"] < 1e-4:   # FILM_SQUEEZE_FACTOR_MIN
            raise ShiftError(f"element {element}: film_squeeze_factor {phi:g} / |a|^4 ({s:g}) falls below the "
                             "firmware's 1e-4: no exact equivalent clutch")
    if values["clutch.outer_radius_m"] > 1.0:                   # RADIUS_MAX_m
        raise ShiftError(f"element {element}: R_o x |a| = {values['clutch.outer_radius_m']:.4g} m above the "
                         "firmware's 1 m: no equivalent clutch")
    return values


def shift_calibration_for(model, base=None) -> shift_calibration.ShiftCalibration:
    """The controller's calibration for one shift (wc_gearbox_shift_calibration's twin): base (whole_full) with
    its driveline model replaced by the row's reduced one (turbine_ratio 1, output_ratio b, offgoing_ratio b1,
    the two inertias, the jerk factor), checked as the firmware checks it."""
    base = base or shift_calibration.load(SHIFT_TOML).variants[CONTROLLER]
    values = dict(base.values)
    values.update({"turbine_ratio": 1.0, "output_ratio": f32(model.output_ratio),
                   "offgoing_ratio": f32(model.offgoing_ratio), "turbine_inertia": f32(model.turbine_inertia),
                   "output_inertia": f32(model.output_inertia),
                   "jerk_per_torque_rate": f32(model.jerk_per_torque_rate)})
    name = f"{base.name}_{model.name}"
    try:
        shift_calibration._check(SHIFT_TOML, name, values)        # noqa: SLF001 (the firmware's rules)
    except shift_calibration.ShiftCalibrationError as e:
        raise ShiftError(str(e)) from None
    return shift_calibration.ShiftCalibration(name, values, dict(base.sources))


def write_images(directory: Path, model, gearbox_path) -> tuple[Path, Path]:
    """(on-coming image with the shift calibration, off-going image with its clutch alone) in directory."""
    directory = Path(directory)
    on = {**equivalent_clutch_values(gearbox_path, model.oncoming, model.oncoming_slip_scale),
          **cal_image._shift_values(shift_calibration_for(model)),     # noqa: SLF001
          **cal_image.loop_values(None, True)}
    off = {**equivalent_clutch_values(gearbox_path, model.offgoing, model.offgoing_slip_scale),
           **cal_image._shift_values(None), **cal_image.loop_values(None, False)}     # noqa: SLF001
    paths = directory / f"oncoming_{model.oncoming}.img", directory / f"offgoing_{model.offgoing}.img"
    cal_image.write_file(paths[0], on)
    cal_image.write_file(paths[1], off)
    return paths


class ImageTcu(InprocTcu):
    """wc_replay --lockstep on two calibration images: the on-coming clutch with the shift calibration, and the
    off-going clutch (--offgoing-calibration-image)."""

    def __init__(self, oncoming_image: Path, offgoing_image: Path, theta_start_degC: float,
                 program: Path = WC_REPLAY):
        if not Path(program).is_file():
            raise ShiftError(f"{program} not built (cmake --preset host-release && cmake --build --preset"
                             " host-release)")
        cmd = [str(program), "-", "--lockstep", "--calibration-image", str(oncoming_image),
               "--offgoing-calibration-image", str(offgoing_image), "--theta-start", f"{theta_start_degC:.6g}"]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, bufsize=1)


# ---------------------------------------------------------------------------------------------- the plant's side
def plant_path(vehicle) -> Path:
    """A vehicle of the family by name (tools/plants/8hp/NAME.toml) or an 8-speed plant file anywhere."""
    p = Path(vehicle)
    return p if p.suffix == ".toml" else PLANTS_8HP / f"{vehicle}.toml"


@functools.lru_cache(maxsize=8)
def _plant_and_models(path: str):
    params = load_plant8(path)
    veh = gearbox_pkg.load_vehicle(params.vehicle.path)
    models = {m.name: m for m in reduction.shift_models(params.gearbox, veh)[0]}
    return params, models


def pedal_for_load(params, load: float, turbine_rpm: float) -> float:
    """The pedal that makes the engine's brake torque load x its full-load torque at turbine_rpm (locked)."""
    eng = Plant8(params).engine
    w = turbine_rpm * RPM
    full, drag = eng.full_Nm(w), eng.drag_Nm(w)
    return min(max((load * full - drag) / (full - drag), 0.0), 1.0)


def _signals(s: dict, target_ms: int, request: bool, torque_Nm: float) -> dict:
    return {canlog.REQUEST: {"TorqueRequest": 0.0, "Mode": canlog.MODE_SHIFT},
            canlog.SHIFT_COMMAND: {"ShiftRequest": int(request), "AdaptationReset": 0, "TargetGear": 2, "CurrentGear": 1,
                                   "TurbineTorque": float(np.clip(torque_Nm, -1000.0, 1000.0)),
                                   "TargetInertiaTime": target_ms},
            canlog.OFFGOING_SENSORS: {"OffgoingSlipSpeed": float(np.clip(s["off"], -8000.0, 8000.0))},
            canlog.SENSORS: {"SlipSpeed": float(np.clip(s["on"], -8000.0, 8000.0)), "OilTemp": s["oil"],
                             "HousingTemp": s["housing"]}}   # last: it steps the loop


class _Sensors:
    """What the TCU receives (module docstring), from the plant's state, the vehicle file's sensor figures."""

    def __init__(self, vehicle, seed: int):
        self.v = vehicle
        self.rng = np.random.default_rng(seed)

    def read(self, st: dict, model, oil_degC: float, housing_degC: float) -> dict:
        v = self.v
        z = self.rng.standard_normal(5)
        q, tq = v.slip_resolution, v.temperature_resolution
        on = st[f"{model.oncoming}_slip_rad_s"] / model.oncoming_slip_scale / RPM + v.slip_noise * z[0]
        off = st[f"{model.offgoing}_slip_rad_s"] / model.offgoing_slip_scale / RPM + v.slip_noise * z[1]
        return {"on": round(on / q) * q, "off": round(off / q) * q,
                "oil": round((oil_degC + v.temperature_noise * z[2]) / tq) * tq,
                "housing": round((housing_degC + v.temperature_noise * z[3]) / tq) * tq,
                "torque": st["engine_torque_Nm"] * (1.0 + v.torque_estimate_bias) + v.torque_estimate_noise * z[4]}


def run_upshift_record(vehicle, from_gear: int, load: float, oil_degC: float = OIL_DEGC, *, seed: int = 1,
                       target_s: float = TARGET_INERTIA_S, turbine_rpm: float = COMMAND_TURBINE_RPM,
                       shift_duration_s: float | None = None) -> dict:
    """One power-on upshift from_gear -> from_gear + 1 in closed loop (module docstring); the record (the
    controller's view per period, the plant's truth, the shift's model) for quality8."""
    params, models = _plant_and_models(str(plant_path(vehicle)))
    src, tgt = str(from_gear), str(from_gear + 1)
    model = models.get(f"{src}-{tgt}")
    if model is None or model.direction != "up":
        raise ShiftError(f"{src}->{tgt}: not a single-element upshift of {params.gearbox.path}")
    v = params.vehicle
    pedal = pedal_for_load(params, load, turbine_rpm)
    rw, rf = v.wheel_radius, v.final_drive
    ratio_src = float(kinematics.ratio(params.gearbox, src))
    speed = turbine_rpm * RPM / ratio_src / rf * rw
    plant = Plant8.in_gear(params, src, speed, pedal=pedal, lockup_current_mA=LOCKUP_MA, oil_degC=oil_degC)
    names = plant.names
    i_max = {n: el.i_max for n, el in zip(names, plant.elements)}
    currents = {n: (i_max[n] if n in params.gearbox.gears[src] else 0.0) for n in names}
    dt = plant.dt
    n_pre = int(round(v.preroll_time / dt))
    n = n_pre + int(round((v.shift_duration if shift_duration_s is None else shift_duration_s) / dt))
    sensors = _Sensors(v, seed)
    enc = canlog.Encoder()
    db = enc.db
    msgs = {name: db.get_message_by_name(name) for name in (canlog.COMMAND, canlog.ESTIMATE, canlog.SHIFT_REPORT,
                                                           canlog.OFFGOING_COMMAND, canlog.ENGINE_REQUEST)}
    ids = {m.frame_id: name for name, m in msgs.items()}
    rec = {k: np.zeros(n) for k in ("t_s", "sensor_slip_rad_s", "current_mA", "pressure_command_Pa",
                                    "theta_estimate_degC", "model_torque_Nm", "locked_tcu", "offgoing_current_cmd_mA",
                                    "engine_delta_cmd_Nm", "tcu_phase", "tcu_fallback")}
    report, engine_delta = None, 0.0
    frames_in, frames_out = [], []      # what the TCU received per period, and what it sent (period, id, hex)
    target_ms = round(target_s * 1e3)
    with tempfile.TemporaryDirectory(prefix="matrix8_") as tmp:
        on_img, off_img = write_images(Path(tmp), model, params.gearbox.path)
        tcu = ImageTcu(on_img, off_img, oil_degC)
        try:
            st = plant.state
            for k in range(n):
                s = sensors.read(st, model, plant.oil_degC, plant.housing_degC)
                frames = [enc.frame(name, **sig) for name, sig in _signals(s, target_ms, k >= n_pre,
                                                                               s["torque"]).items()]
                frames_in.append([(m.arbitration_id, bytes(m.data)) for m in frames])
                for fid, data in tcu.exchange(k * dt, frames):
                    frames_out.append((k, fid, data.hex().upper()))
                    name = ids.get(fid)
                    if name == canlog.COMMAND:
                        c = msgs[name].decode(data)
                        currents[model.oncoming] = float(c["VfsCurrent"])
                        rec["current_mA"][k] = currents[model.oncoming]
                        rec["pressure_command_Pa"][k] = float(c["PressureCommand"]) * 1e3
                        rec["locked_tcu"][k] = float(c["StatusLocked"])
                    elif name == canlog.ESTIMATE:
                        e = msgs[name].decode(data, decode_choices=False)
                        rec["theta_estimate_degC"][k] = float(e["EstimatedClutchTemp"])
                        rec["model_torque_Nm"][k] = float(e["ModelTorque"])
                    elif name == canlog.SHIFT_REPORT and report is None:
                        report = msgs[name].decode(data, decode_choices=False)
                        report["step"] = k
                    elif name == canlog.OFFGOING_COMMAND:
                        o = msgs[name].decode(data, decode_choices=False)
                        currents[model.offgoing] = float(o["VfsCurrent"])
                        rec["tcu_phase"][k] = float(o["ShiftPhase"])
                        rec["tcu_fallback"][k] = float(o["Fallback"])
                    elif name == canlog.ENGINE_REQUEST:
                        e = msgs[name].decode(data, decode_choices=False)
                        engine_delta = float(e["TorqueDelta"]) if int(e["InterventionActive"]) else 0.0
                rec["t_s"][k] = k * dt
                rec["sensor_slip_rad_s"][k] = s["on"] * RPM
                rec["offgoing_current_cmd_mA"][k] = currents[model.offgoing]
                rec["engine_delta_cmd_Nm"][k] = engine_delta
                st = plant.step(currents, LOCKUP_MA, pedal, engine_delta)
        finally:
            tcu.close()
    truth = {k: a[1:] for k, a in plant.record().items()}      # the state after step k, as the 1->2 runner's
    rec["frames_in"], rec["frames"] = frames_in, frames_out
    return _finish_record(rec, truth, plant, model, report, n_pre, target_s, vehicle, load, oil_degC, pedal)


def _finish_record(rec, truth, plant, model, report, n_pre, target_s, vehicle, load, oil_degC, pedal) -> dict:
    """The record in the 1->2 runner's keys (quality.quality reads them) plus the 8-speed's own."""
    dt = plant.dt
    n = rec["t_s"].size
    on, off = model.oncoming, model.offgoing
    a_on, a_off = model.oncoming_slip_scale, model.offgoing_slip_scale
    ratio_src = plant.ratios[model.source]
    rec.update({
        "true_slip_rad_s": truth[f"{on}_slip_rad_s"] / a_on,
        "true_offgoing_slip_rad_s": truth[f"{off}_slip_rad_s"] / a_off,
        "true_oncoming_locked": truth[f"{on}_locked"],
        "true_offgoing_locked": truth[f"{off}_locked"],
        "true_vehicle_accel_m_s2": truth["vehicle_accel_m_s2"],
        "true_turbine_speed_rpm": truth["turbine_speed_rpm"],
        "true_output_speed_rpm": truth["output_speed_rpm"],
        "true_gear1_speed_rpm": ratio_src * truth["output_speed_rpm"],
        "true_turbine_torque_Nm": truth["input_torque_Nm"],
        "true_offgoing_torque_Nm": a_off * truth[f"{off}_torque_Nm"],    # the controller's: > 0 holds the source
        "true_clutch_torque_Nm": a_on * truth[f"{on}_torque_Nm"],
        "true_pressure_Pa": truth[f"{on}_pressure_Pa"],
        "true_friction_power_W": truth[f"{on}_power_W"],
        "true_offgoing_power_W": truth[f"{off}_power_W"],
        "true_engine_torque_Nm": truth["engine_torque_Nm"],
        "true_theta_clutch_degC": truth[f"{on}_theta_degC"],
        "truth": truth,
    })
    rec["report"] = report
    rec["command_step"] = n_pre
    rec["whole"] = True
    entered = np.flatnonzero(rec["tcu_phase"] >= 3)       # the controller's inertia phase (wc_shift.h phases)
    k_i = int(entered[0]) if entered.size else n - 1
    rec["inertia_step"] = k_i
    start = rec["sensor_slip_rad_s"][k_i]
    ref = np.full(n, np.nan)
    ref[k_i:] = [shift_reference.reference_slip(start, target_s, j * dt)[0] for j in range(n - k_i)]
    rec["reference_slip_rad_s"] = ref
    rec["model"] = model
    rec["elements"] = plant.names
    rec["ratios"] = dict(plant.ratios)
    rec["gears_closed"] = {g: tuple(c) for g, c in plant.gb.gears.items()}
    rec["case"] = {"vehicle": str(vehicle), "shift": f"{model.source}->{model.target}", "load": load,
                   "oil_degC": oil_degC, "pedal": pedal, "target_s": target_s}
    return rec


def end_gear(rec) -> str | None:
    """The gear the plant ends in by truth: every element it closes locked and the turbine / output speed ratio
    its own within END_RATIO_TOLERANCE; None: no gear."""
    t = rec["truth"]
    for gear, closed in rec["gears_closed"].items():
        if all(t[f"{e}_locked"][-1] > 0.5 for e in closed):
            ratio = t["turbine_speed_rpm"][-1] / t["output_speed_rpm"][-1]
            if abs(ratio / rec["ratios"][gear] - 1.0) <= END_RATIO_TOLERANCE:
                return gear
    return None


def quality8(rec) -> dict:
    """The quality vector of one 8-speed shift (module docstring)."""
    target_s = rec["case"]["target_s"]
    q = quality(rec, target_s)
    k0 = rec["command_step"]
    t = rec["truth"]
    q["energy_kJ"] = {e: float(t[f"{e}_energy_J"][-1] - t[f"{e}_energy_J"][k0]) * 1e-3 for e in rec["elements"]}
    q["end_gear"] = end_gear(rec)
    q["gear"] = q["end_gear"]
    q["peak_theta_truth_degC"] = q["peak_theta_degC"]
    q["turbine_torque_Nm"] = float(rec["true_turbine_torque_Nm"][0])
    q.update(rec["case"])
    m = rec["model"]
    q.update({"oncoming": m.oncoming, "offgoing": m.offgoing, "oncoming_slip_scale": m.oncoming_slip_scale,
              "offgoing_slip_scale": m.offgoing_slip_scale})
    # the tie-up split: while the off-going piston is on its pack (applied, the controller's doing) and after it
    # left (the released element's open drag, slipping backwards in the inertia phase)
    t_t = max(abs(q["turbine_torque_Nm"]), 1.0)
    fight = np.maximum(-rec["true_offgoing_torque_Nm"][k0:], 0.0)
    applied = t[f"{m.offgoing}_fill"][k0:] >= 1.0
    q["tie_up_applied_fraction"] = float(np.max(fight[applied], initial=0.0)) / t_t
    q["offgoing_drag_fraction"] = float(np.max(fight[~applied], initial=0.0)) / t_t
    q["missed"] = missed(q)
    return q


def missed(q) -> list[str]:
    """Issue 29's targets this shift misses, each with its figure ([] = every target met)."""
    out = []
    if q["abort"] != 0:
        out.append(f"abort: {q['abort_reason']}")
    if q["end_gear"] != str(int(q["shift"].split("->")[1])):
        out.append(f"ends in gear {q['end_gear']} by truth")
    if not q["peak_jerk_m_s3"] <= TARGETS["jerk_m_s3"]:
        out.append(f"peak jerk {q['peak_jerk_m_s3']:.1f} m/s^3 > {TARGETS['jerk_m_s3']:g}")
    if not q["flare_rpm"] <= TARGETS["flare_rpm"]:
        out.append(f"flare {q['flare_rpm']:.0f} rpm > {TARGETS['flare_rpm']:g}")
    if not q["tie_up_fraction"] <= TARGETS["tie_up_fraction"]:
        out.append(f"tie-up {100 * q['tie_up_fraction']:.1f} % > {100 * TARGETS['tie_up_fraction']:g} %")
    err = q["inertia_time_error"]
    if not (math.isfinite(err) and abs(err) <= TARGETS["time_tolerance"]):
        out.append(f"inertia time {q['inertia_time_s']:.3f} s ({100 * err:+.1f} % of {q['target_s']:g} s)")
    return out


def run_upshift(vehicle, from_gear: int, load: float, oil_degC: float = OIL_DEGC, **kwargs) -> dict:
    """One power-on upshift from_gear -> from_gear + 1 of the vehicle (a name of tools/plants/8hp or a path) at
    load (fraction of full load) and oil_degC, in closed loop with today's whole-shift controller: its quality
    dict (quality8)."""
    return quality8(run_upshift_record(vehicle, from_gear, load, oil_degC, **kwargs))
