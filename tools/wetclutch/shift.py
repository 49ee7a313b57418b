"""Closed-loop 1->2 upshifts: the plant simulator (plant.py) against the TCU's frame loop (``wetclutch shift``).

Lockstep on the frame clock: each period the plant's VCU/sensor side sends
TorqueRequest (Mode 3, Shift), ShiftCommand and ClutchSensors (last: it steps
the loop), the TCU answers VfsCommand, ClutchEstimate and, in the step a shift
ends, ShiftReport; the plant then advances one period with that VFS current.
Two TCUs run the same firmware code:

  InprocTcu  `wc_replay --lockstep --shift NAME` through a pipe (the frame loop
             linked into a host program): fast, for the scenario matrix;
  VcanTcu    `wc_tcu --clock frame --shift NAME` on a SocketCAN interface
             (python-can), natively or in the QEMU guest (hil/shift_guest.sh).

For the same case both give the same output frames (tests/python/test_shift.py).

Controllers compared (issue 13), variants of tools/calibrations/shift_1_2.toml:
(a) feedback: PI only; (b) blind: 2-DOF, clutch temperature = oil; (c) full:
2-DOF with observer, film state, lock-up and lag compensation; plus nolag ((c)
without the lag compensation) for the pressure-tracking figure.

Quality per shift, from the plant's truth (DESIGN 10):
  inertia_time_s   from the controller's inertia-phase start (the command +
                   prepare + torque-phase time) to synchronisation: the true
                   slip inside SYNC_BAND_RAD_S (the TCU's lock band, 2.9 rpm)
                   for the first time (the plates lock there, or within the
                   lock-up hand-over that follows);
  slip_rmse_rpm    RMS(true slip - reference slip) over the inertia phase
                   (the reference is the controller's: a smoothstep from the
                   measured slip at the phase start to 0 in the target time);
  peak_jerk_m_s3   max |d/dt of the vehicle acceleration| from the command to
                   the end, the acceleration low-passed at 10 Hz (2nd-order
                   Butterworth, zero phase): the band ride-comfort ratings
                   weight (ISO 2631-1 up to about 8 Hz), above it driveline
                   ringing the occupants do not feel as jerk;
  friction_energy_kJ, peak_theta_degC (true pack temperature);
  flare            turbine speed above the 1st-gear synchronous speed by more
                   than FLARE_RPM (the engine runs up: too little clutch torque);
  tie_up           the off-going clutch carrying torque against its release
                   direction (negative, fighting the shift) above TIE_UP_FRACTION
                   of the turbine torque;
  abort            the TCU's ShiftReport AbortReason (or no report at all);
  pressure_rmse_kPa RMS(true piston pressure - the TCU's PressureCommand, the
                   pressure it wants) from the command to the end.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from . import plant as plant_mod
from .calibration import shift as shift_calibration
from .reference import shift as shift_reference
from .util import canlog
from .util.atomic import Staged

ROOT = Path(__file__).resolve().parents[2]
WC_REPLAY = ROOT / "build" / "host-release" / "src" / "host" / "wc_replay"
SHIFT_TOML = ROOT / "tools" / "calibrations" / "shift_1_2.toml"
TCU_CALIBRATION = "bench_identified"     # the TCU's clutch model: identified from the bench (truth: bench_true)
CONTROLLERS = {"a": "feedback", "b": "blind", "c": "full"}
TARGET_INERTIA_S = 0.5
FLARE_RPM = 20.0
SYNC_BAND_RAD_S = 0.3            # the clutch calibration's lock_slip: synchronised
TIE_UP_FRACTION = 0.1
JERK_CUTOFF_HZ = 10.0
SOAK_SHIFTS = 10
ABORT_NAMES = {0: "completed", 1: "inertia timeout", 2: "lockup failed", 3: "input lost", 4: "cancelled",
               5: "invalid command", 6: "no slip", -1: "no report"}


class ShiftError(RuntimeError):
    pass


@dataclass(frozen=True)
class Scenario:
    name: str
    oil_degC: float
    load: float                  # turbine torque / full load
    friction_scale: float = 1.0
    shifts: int = 1              # > 1: back-to-back shifts, temperatures carried over (heat soak)
    group: str = ""


def scenario_matrix(nominal_oil_degC: float = 80.0) -> list[Scenario]:
    """Issue 13's matrix: oil 20..110 degC at full load, load 25/50/100 % at the nominal oil, plant friction
    -/+10 % (model error), a heat soak of SOAK_SHIFTS full-load shifts. Nominal: 80 degC, 100 %, friction 1."""
    out = [Scenario(f"oil{int(t)}", t, 1.0, group="oil") for t in (20.0, 40.0, 60.0, 80.0, 100.0, 110.0)]
    out += [Scenario(f"load{int(x * 100)}", nominal_oil_degC, x, group="load") for x in (0.25, 0.5)]
    out += [Scenario(f"friction{round((s - 1.0) * 100):+d}pct", nominal_oil_degC, 1.0, s, group="friction")
            for s in (0.9, 1.1)]
    out.append(Scenario("soak", nominal_oil_degC, 1.0, shifts=SOAK_SHIFTS, group="soak"))
    return out


NOMINAL = "oil80"


class InprocTcu:
    """The frame loop in-process: wc_replay --lockstep through a pipe."""

    def __init__(self, shift_name: str, theta_start_degC: float, overrides: dict | None = None,
                 calibration: str = TCU_CALIBRATION, program: Path = WC_REPLAY):
        if not Path(program).is_file():
            raise ShiftError(f"{program} not built (cmake --preset host-release && cmake --build --preset host-release)")
        cmd = [str(program), "-", "--lockstep", "--calibration", calibration, "--theta-start",
               f"{theta_start_degC:.6g}", "--shift", shift_name]
        for k, v in (overrides or {}).items():
            cmd += ["--set", f"{k}={v:.9g}"]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, bufsize=1)

    def exchange(self, t_s: float, frames) -> list[tuple[int, bytes]]:
        lines = "".join(f"({t_s:.6f}) vcan0 {m.arbitration_id:03X}#{bytes(m.data).hex().upper()}\n" for m in frames)
        try:
            self.proc.stdin.write(lines)
            self.proc.stdin.flush()
        except BrokenPipeError:
            raise ShiftError(f"wc_replay stopped: {self.proc.stderr.read().strip()}") from None
        out = []
        while True:
            line = self.proc.stdout.readline()
            if not line:
                raise ShiftError(f"wc_replay stopped: {self.proc.stderr.read().strip()}")
            line = line.strip()
            if line == ".":
                return out
            ident, data = line.split()[2].split("#")
            out.append((int(ident, 16), bytes.fromhex(data)))

    def close(self):
        if self.proc.stdin:
            self.proc.stdin.close()
        self.proc.wait(timeout=10)
        self.proc.stdout.close()
        self.proc.stderr.close()


class VcanTcu:
    """The TCU program on a SocketCAN interface: wc_tcu --clock frame --shift NAME, frames through python-can.
    Each exchange sends the period's frames and returns what the TCU sent up to its ClutchEstimate (a
    ShiftReport, sent after it, comes with the next exchange: the frame sequence is the same as in-process)."""

    def __init__(self, shift_name: str, theta_start_degC: float, overrides: dict | None = None,
                 calibration: str = TCU_CALIBRATION, iface: str = "vcan0", log_dir: Path | None = None):
        import can
        if overrides:
            raise ShiftError("wc_tcu takes compiled-in shift calibrations only (no overrides)")
        program = ROOT / "build" / "host-release" / "src" / "port" / "wc_tcu"
        if not program.is_file():
            raise ShiftError(f"{program} not built (cmake --preset host-release && cmake --build --preset host-release)")
        db = canlog.database()
        self.ids = {db.get_message_by_name(n).frame_id for n in (canlog.COMMAND, canlog.ESTIMATE, canlog.SHIFT_REPORT)}
        self.estimate_id = db.get_message_by_name(canlog.ESTIMATE).frame_id
        self.bus = can.Bus(interface="socketcan", channel=iface,
                           can_filters=[{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in sorted(self.ids)])
        self.log = Path(log_dir or ".") / "wc_tcu_shift.txt"
        self.log_file = open(self.log, "w")
        self.proc = subprocess.Popen([str(program), "--iface", iface, "--clock", "frame", "--calibration", calibration,
                                      "--shift", shift_name, "--theta-start", f"{theta_start_degC:.6g}"],
                                     stdout=subprocess.DEVNULL, stderr=self.log_file)
        import time
        for _ in range(200):
            if "clock frame" in self.log.read_text() or self.proc.poll() is not None:
                break
            time.sleep(0.05)
        if self.proc.poll() is not None or "clock frame" not in self.log.read_text():
            raise ShiftError(f"wc_tcu did not start: {self.log.read_text().strip()}")

    def exchange(self, t_s: float, frames) -> list[tuple[int, bytes]]:
        for m in frames:
            self.bus.send(m)
        out = []
        while True:
            msg = self.bus.recv(timeout=10.0)
            if msg is None:
                raise ShiftError(f"no answer from wc_tcu at t = {t_s:.3f} s: {self.log.read_text().strip()[-400:]}")
            if msg.arbitration_id not in self.ids or msg.is_error_frame:
                continue
            out.append((msg.arbitration_id, bytes(msg.data)))
            if msg.arbitration_id == self.estimate_id:
                return out

    def close(self):
        import signal
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=10)
        finally:
            self.bus.shutdown()
            self.log_file.close()


def frame_sequence(records: list[dict]) -> list[tuple[int, str]]:
    """The TCU's output frames of a case in order (id, hex), for the in-process / vcan comparison."""
    return [(fid, data) for rec in records for _, fid, data in rec["frames"]]


def run_on_vcan(out_dir: Path, shift_name: str = "shift_1_2_full", scenario_name: str = NOMINAL,
                plant_path=plant_mod.DEFAULT_PLANT) -> Path:
    """One closed-loop shift against wc_tcu on vcan0 (natively or in the QEMU guest, hil/vcan_run.sh);
    writes out_dir/vcan_frames.json and returns its path."""
    out_dir = Path(out_dir).resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    cmd = ["bash", str(ROOT / "hil" / "vcan_run.sh"), "--rwdir", str(out_dir), "--",
           str(ROOT / ".venv" / "bin" / "python"), "-m", "wetclutch.shift", "--vcan-guest", str(out_dir),
           shift_name, scenario_name, str(plant_path)]
    env = dict(os.environ, PATH=f"{ROOT / '.venv' / 'bin'}:{os.environ.get('PATH', '')}")
    result = subprocess.run(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL)
    if result.returncode != 0:
        raise ShiftError(f"closed-loop shift on vcan failed (exit {result.returncode}); see {out_dir}")
    return out_dir / "vcan_frames.json"


def _vcan_guest(out_dir: str, shift_name: str, scenario_name: str, plant_path: str) -> int:
    """Guest side of run_on_vcan: the case against wc_tcu on vcan0, frames and quality to JSON."""
    sc = next(s for s in scenario_matrix() if s.name == scenario_name)
    params = plant_mod.load_plant(plant_path)
    tcu = VcanTcu(shift_name, sc.oil_degC, log_dir=Path(out_dir))
    try:
        recs = run_case(params, shift_name, sc, tcu=tcu)
    finally:
        tcu.close()
    payload = {"frames": frame_sequence(recs), "quality": [quality(r) for r in recs]}
    Path(out_dir, "vcan_frames.json").write_text(json.dumps(payload, default=float))
    return 0


def _one_shift(params, tcu, enc, db, scenario: Scenario, theta_clutch_degC, t0_s: float, seed: int,
               target_s: float, shift_cal) -> dict:
    """One shift on a fresh plant (1st gear, steady): pre-roll, command, shift_duration. Returns the record."""
    p = params
    full = p.turbine_torque_full * scenario.load
    pl = plant_mod.UpshiftPlant(p, oil_degC=scenario.oil_degC, turbine_torque_Nm=full,
                                friction_scale=p.friction_scale * scenario.friction_scale, seed=seed,
                                theta_clutch_degC=theta_clutch_degC)
    dt = pl.dt_s
    n_pre = int(round(p.preroll_time / dt))
    n = n_pre + int(round(p.shift_duration / dt))
    msg_cmd = db.get_message_by_name(canlog.COMMAND)
    msg_est = db.get_message_by_name(canlog.ESTIMATE)
    msg_rep = db.get_message_by_name(canlog.SHIFT_REPORT)
    rec = {k: np.empty(n) for k in ("t_s", "sensor_slip_rad_s", "current_mA", "pressure_command_Pa",
                                    "theta_estimate_degC", "model_torque_Nm", "locked_tcu")}
    truth = {}
    frames_out = []
    frames_in = []          # what the TCU received, for the reference (shift_reference.py)
    report = None
    current = 0.0
    for k in range(n):
        t = t0_s + k * dt
        s = pl.sensors()
        frames = [enc.frame(canlog.REQUEST, TorqueRequest=0.0, Mode=canlog.MODE_SHIFT),
                  enc.frame(canlog.SHIFT_COMMAND, ShiftRequest=int(k >= n_pre), TargetGear=2,
                            TurbineTorque=float(np.clip(s["turbine_torque_estimate_Nm"], -1000.0, 1000.0)),
                            TargetInertiaTime=round(target_s * 1e3)),
                  enc.frame(canlog.SENSORS, SlipSpeed=float(np.clip(s["slip_rpm"], -8000.0, 8000.0)),
                            OilTemp=float(s["oil_degC"]), HousingTemp=float(s["housing_degC"]))]
        frames_in.append([(m.arbitration_id, bytes(m.data)) for m in frames])
        out = tcu.exchange(t, frames)
        for fid, data in out:
            frames_out.append((k, fid, data.hex().upper()))
            if fid == msg_cmd.frame_id:
                c = msg_cmd.decode(data)
                current = float(c["VfsCurrent"])
                rec["current_mA"][k] = current
                rec["pressure_command_Pa"][k] = float(c["PressureCommand"]) * 1e3
                rec["locked_tcu"][k] = float(c["StatusLocked"])
            elif fid == msg_est.frame_id:
                e = msg_est.decode(data, decode_choices=False)
                rec["theta_estimate_degC"][k] = float(e["EstimatedClutchTemp"])
                rec["model_torque_Nm"][k] = float(e["ModelTorque"])
            elif fid == msg_rep.frame_id:
                report = msg_rep.decode(data, decode_choices=False)
                report["step"] = k
        rec["t_s"][k] = k * dt
        rec["sensor_slip_rad_s"][k] = s["slip_rpm"] * plant_mod.RPM
        pl.step(current, (k - n_pre) * dt if k >= n_pre else None)
        for name, v in pl.truth.items():
            truth.setdefault(name, np.empty(n))[k] = v
    rec.update({f"true_{k}": v for k, v in truth.items()})
    rec["frames"] = frames_out
    rec["frames_in"] = frames_in
    rec["report"] = report
    rec["command_step"] = n_pre
    n_prep = int(shift_cal.prepare_time / dt + 0.5)
    n_tp = int(shift_cal.torque_phase_time / dt + 0.5)
    k_i = n_pre + n_prep + n_tp           # the controller enters the inertia phase at this step (wc_shift.c)
    rec["inertia_step"] = k_i
    start = rec["sensor_slip_rad_s"][k_i]
    ref = np.full(n, np.nan)
    ref[k_i:] = [shift_reference.reference_slip(start, target_s, j * dt)[0] for j in range(n - k_i)]
    rec["reference_slip_rad_s"] = ref
    rec["end_theta_degC"] = float(truth["theta_clutch_degC"][-1])
    return rec


def run_case(params, shift_name: str, scenario: Scenario, overrides: dict | None = None, tcu=None,
             target_s: float = TARGET_INERTIA_S, shift_cal=None) -> list[dict]:
    """All shifts of a scenario (one, or the soak's back-to-back shifts with one TCU and the clutch
    temperature carried over); returns one record per shift."""
    shift_cal = shift_cal or shift_calibration.load(SHIFT_TOML).variants[shift_name.split("shift_1_2_")[-1]]
    own = tcu is None
    tcu = tcu or InprocTcu(shift_name, scenario.oil_degC, overrides)
    try:
        enc = canlog.Encoder()
        db = enc.db
        theta = None
        t0 = 0.0
        records = []
        for i in range(scenario.shifts):
            rec = _one_shift(params, tcu, enc, db, scenario, theta, t0, params.seed + i, target_s, shift_cal)
            records.append(rec)
            theta = rec["end_theta_degC"]
            t0 += rec["t_s"][-1] + 1e-3
        return records
    finally:
        if own:
            tcu.close()


def reference_run(rec: dict, shift_cal, clutch_cal, theta_start_degC: float) -> dict:
    """The double-precision reference (shift_reference.py) on the inputs the TCU received in rec, with the
    TCU's safe state from its VfsCommand: per step the reference's current and the TCU's (decoded), and the
    reports of both."""
    db = canlog.database()
    msgs = {n: db.get_message_by_name(n) for n in (canlog.SENSORS, canlog.SHIFT_COMMAND, canlog.COMMAND,
                                                   canlog.SHIFT_REPORT)}
    ids = {m.frame_id: n for n, m in msgs.items()}
    ref = shift_reference.ShiftReference(shift_cal, clutch_cal, theta_start_degC)
    n = len(rec["frames_in"])
    out = {"reference_mA": np.empty(n), "tcu_mA": np.empty(n), "reference_report": None, "tcu_report": None,
           "reference_report_step": None, "tcu_report_step": None}
    outputs = {}
    for k, fid, data in rec["frames"]:
        outputs.setdefault(k, []).append((fid, bytes.fromhex(data)))
    for k, frames in enumerate(rec["frames_in"]):
        got = {ids[fid]: msgs[ids[fid]].decode(data, decode_choices=False) for fid, data in frames if fid in ids}
        c, s = got[canlog.SHIFT_COMMAND], got[canlog.SENSORS]
        tcu = {ids[fid]: msgs[ids[fid]].decode(data, decode_choices=False) for fid, data in outputs.get(k, []) if fid in ids}
        vfs = tcu[canlog.COMMAND]
        step_out, report = ref.step(bool(c["ShiftRequest"]), int(c["TargetGear"]), float(c["TurbineTorque"]),
                                    float(c["TargetInertiaTime"]) * 1e-3, bool(vfs["StatusSafeStateActive"]),
                                    float(s["SlipSpeed"]), float(s["OilTemp"]), float(s["HousingTemp"]))
        out["reference_mA"][k] = step_out["current_mA"]
        out["tcu_mA"][k] = float(vfs["VfsCurrent"])
        if report is not None and out["reference_report"] is None:
            out["reference_report"], out["reference_report_step"] = report, k
        if canlog.SHIFT_REPORT in tcu and out["tcu_report"] is None:
            out["tcu_report"], out["tcu_report_step"] = tcu[canlog.SHIFT_REPORT], k
    return out


def _lowpass_zero_phase(x: np.ndarray, dt: float, cutoff_hz: float) -> np.ndarray:
    from scipy.signal import butter, filtfilt
    b, a = butter(2, cutoff_hz * 2.0 * dt)
    return filtfilt(b, a, x)


def quality(rec: dict, target_s: float = TARGET_INERTIA_S) -> dict:
    """The quality vector of one shift from the plant's truth (module docstring)."""
    dt = rec["t_s"][1] - rec["t_s"][0]
    k0, ki = rec["command_step"], rec["inertia_step"]
    sync = (np.abs(rec["true_slip_rad_s"]) < SYNC_BAND_RAD_S) | (rec["true_oncoming_locked"] > 0.5)
    sync_idx = np.flatnonzero(sync[ki:])
    k_sync = ki + int(sync_idx[0]) if sync_idx.size else None
    inertia = (k_sync - ki) * dt if k_sync is not None else float("nan")
    k_end = k_sync if k_sync is not None else len(sync)
    err = rec["true_slip_rad_s"][ki:k_end] - rec["reference_slip_rad_s"][ki:k_end]
    accel = _lowpass_zero_phase(rec["true_vehicle_accel_m_s2"], dt, JERK_CUTOFF_HZ)
    jerk = np.gradient(accel, dt)
    flare_rpm = float(np.max(rec["true_turbine_speed_rpm"][k0:] - rec["true_gear1_speed_rpm"][k0:]))
    t_t = max(abs(float(np.mean(rec["true_turbine_torque_Nm"]))), 1.0)
    fight = float(np.max(np.maximum(-rec["true_offgoing_torque_Nm"][k0:], 0.0)))
    report = rec["report"]
    abort = int(report["AbortReason"]) if report is not None else -1
    p_err = rec["true_pressure_Pa"][k0:] - rec["pressure_command_Pa"][k0:]
    return {
        "inertia_time_s": inertia,
        "inertia_time_error": (inertia - target_s) / target_s if math.isfinite(inertia) else float("nan"),
        "slip_rmse_rpm": float(np.sqrt(np.mean(err ** 2)) / plant_mod.RPM) if err.size else float("nan"),
        "peak_jerk_m_s3": float(np.max(np.abs(jerk[k0:]))),
        "friction_energy_kJ": float(np.sum(rec["true_friction_power_W"][k0:]) * dt * 1e-3),
        "peak_theta_degC": float(np.max(rec["true_theta_clutch_degC"][k0:])),
        "peak_theta_estimate_degC": float(np.max(rec["theta_estimate_degC"][k0:])),
        "flare": bool(flare_rpm > FLARE_RPM),
        "flare_rpm": flare_rpm,
        "tie_up": bool(fight > TIE_UP_FRACTION * t_t),
        "tie_up_Nm": fight,
        "abort": abort,
        "abort_reason": ABORT_NAMES.get(abort, str(abort)),
        "pressure_rmse_kPa": float(np.sqrt(np.mean(p_err ** 2)) * 1e-3),
        "tcu_report": {k: (float(v) if k != "step" else int(v)) for k, v in report.items()} if report else None,
    }


def worst(qs: list[dict]) -> dict:
    """A scenario's figures over its shifts (the soak): the worst of each."""
    if len(qs) == 1:
        return dict(qs[0])
    out = dict(qs[-1])
    for key in ("slip_rmse_rpm", "peak_jerk_m_s3", "peak_theta_degC", "friction_energy_kJ", "pressure_rmse_kPa",
                "flare_rpm", "tie_up_Nm"):
        out[key] = max(q[key] for q in qs)
    out["inertia_time_error"] = max((q["inertia_time_error"] for q in qs), key=lambda e: abs(e) if math.isfinite(e) else 1e9)
    out["inertia_time_s"] = max((q["inertia_time_s"] for q in qs),
                                key=lambda t: abs(t - TARGET_INERTIA_S) if math.isfinite(t) else 1e9)
    out["flare"] = any(q["flare"] for q in qs)
    out["tie_up"] = any(q["tie_up"] for q in qs)
    aborts = [q["abort"] for q in qs if q["abort"] != 0]
    out["abort"] = aborts[0] if aborts else 0
    out["abort_reason"] = ABORT_NAMES.get(out["abort"], str(out["abort"]))
    out["shifts"] = len(qs)
    return out


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
             "Quality per controller and scenario, from the plant's truth (tools/wetclutch/shift.py); the heat soak"
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


def plot_case(path: Path, runs: dict, title: str) -> None:
    """Fig. 4-style panels of one scenario, the controllers overlaid: speeds, slip and its reference, clutch
    torque, pressure and current, vehicle acceleration and jerk, clutch temperature (true and estimated)."""
    from .util import plotting
    fig, axes = plotting.subplots(3, 2, figsize=(13, 11), sharex=True)
    colors = {"feedback": "tab:red", "blind": "tab:orange", "full": "tab:blue", "nolag": "tab:gray"}
    for ctrl, rec in runs.items():
        c = colors.get(ctrl, "k")
        k0 = rec["command_step"]
        t = rec["t_s"] - rec["t_s"][k0]
        lab = {"feedback": "(a) feedback", "blind": "(b) 2-DOF blind", "full": "(c) 2-DOF full", "nolag": "(c) no lag comp."}[ctrl]
        ax = axes[0, 0]
        ax.plot(t, rec["true_turbine_speed_rpm"], color=c, label=f"turbine {lab}")
        if ctrl == "full":
            ax.plot(t, rec["true_gear1_speed_rpm"], "k:", lw=1, label="1st-gear sync (i1 w_o)")
            ax.plot(t, rec["true_gear2_speed_rpm"], "k--", lw=1, label="2nd-gear sync (i2 w_o)")
        ax = axes[0, 1]
        ax.plot(t, rec["true_slip_rad_s"] / plant_mod.RPM, color=c, label=f"slip {lab}")
        ax.plot(t, rec["reference_slip_rad_s"] / plant_mod.RPM, color=c, ls="--", lw=1)
        ax = axes[1, 0]
        ax.plot(t, rec["true_clutch_torque_Nm"], color=c, label=f"true {lab}")
        ax.plot(t, rec["model_torque_Nm"], color=c, ls=":", lw=1)
        ax = axes[1, 1]
        ax.plot(t, rec["pressure_command_Pa"] * 1e-3, color=c, ls="--", lw=1)
        ax.plot(t, rec["true_pressure_Pa"] * 1e-3, color=c, label=f"piston {lab}")
        ax = axes[2, 0]
        dt = rec["t_s"][1] - rec["t_s"][0]
        acc = _lowpass_zero_phase(rec["true_vehicle_accel_m_s2"], dt, JERK_CUTOFF_HZ)
        ax.plot(t, acc, color=c, label=f"accel {lab}")
        ax.plot(t, np.gradient(acc, dt) / 10.0, color=c, ls=":", lw=1)
        ax = axes[2, 1]
        ax.plot(t, rec["true_theta_clutch_degC"], color=c, label=f"true {lab}")
        ax.plot(t, rec["theta_estimate_degC"], color=c, ls="--", lw=1)
    plotting.style(axes[0, 0], ylabel="speed (rpm)", title="turbine and synchronous speeds", legend={"fontsize": 7})
    plotting.style(axes[0, 1], ylabel="slip (rpm)", title="slip (solid) and reference (dashed)", legend={"fontsize": 7})
    plotting.style(axes[1, 0], ylabel="torque (Nm)", title="on-coming clutch torque: true (solid), TCU model (dotted)",
                   legend={"fontsize": 7})
    plotting.style(axes[1, 1], ylabel="pressure (kPa)", title="piston pressure (solid) and TCU's wanted pressure (dashed)",
                   legend={"fontsize": 7})
    plotting.style(axes[2, 0], xlabel="time from shift command (s)", ylabel="m/s^2  |  jerk / 10 (m/s^3)",
                   title="vehicle acceleration (10 Hz) and jerk/10 (dotted)", legend={"fontsize": 7})
    plotting.style(axes[2, 1], xlabel="time from shift command (s)", ylabel="degC",
                   title="clutch temperature: true (solid), TCU estimate (dashed)", legend={"fontsize": 7})
    for ax in axes.flat:
        ax.set_xlim(-0.05, 1.0)
    fig.suptitle(title)
    plotting.save(fig, path)


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
    with Staged() as staged:
        staged.write_text(out_dir / "metrics.json", json.dumps(metrics, indent=1, default=float, sort_keys=True))
        staged.write_text(out_dir / "shift_report.md", markdown(res["cases"], tg))
    return metrics


if __name__ == "__main__":
    if len(sys.argv) == 6 and sys.argv[1] == "--vcan-guest":
        sys.exit(_vcan_guest(*sys.argv[2:]))
    print("usage: python -m wetclutch.shift --vcan-guest OUT_DIR SHIFT_NAME SCENARIO PLANT_TOML", file=sys.stderr)
    sys.exit(2)
