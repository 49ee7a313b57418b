"""One closed-loop shift and a scenario's shifts (run_case), the frames both ways, the double-precision
reference on the TCU's inputs (reference_run), and the case on vcan (run_on_vcan)."""
from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path

import numpy as np

from ..calibration import shift as shift_calibration
from ..reference import shift as shift_reference
from ..simulate import plant as plant_mod
from ..util import canlog
from .quality import quality
from .scenarios import (FAULTS, NOMINAL, SHIFT_TOML, TARGET_INERTIA_S, TCU_CALIBRATION, Scenario, ShiftError,
                        scenario_matrix)
from .tcu import InprocTcu


def frame_sequence(records: list[dict]) -> list[tuple[int, str]]:
    """The TCU's output frames of a case in order (id, hex), for the in-process / vcan comparison."""
    return [(fid, data) for rec in records for _, fid, data in rec["frames"]]


def run_on_vcan(out_dir: Path, shift_name: str = "shift_1_2_full", scenario_name: str = NOMINAL,
                plant_path=plant_mod.DEFAULT_PLANT) -> Path:
    """One closed-loop shift on vcan0 (natively or in the QEMU guest, hil/vcan_run.sh). The case runs in closed
    loop with the frame loop in-process (InprocTcu); the frames the TCU received there, period by period, go to
    wc_tcu --shift on vcan0 in lockstep with its answers (wc_canplay, hil/replay_guest.sh), the bus recorded.
    If wc_tcu on vcan answers these inputs with exactly the in-process frames, the plant would have received
    the same commands in a closed loop over vcan, so it would have sent the same inputs: the same case, with
    nothing but the TCU and the player in the guest (the plant in the guest's Python took 350 s on a slow
    host). Writes out_dir/vcan_frames.json ({"frames": what wc_tcu sent on vcan, (id, hex) in order,
    "inproc_frames": the in-process case's, "quality": the in-process case's}) and returns its path."""
    from ..hil import replay
    out_dir = Path(out_dir).resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    sc = next(s for s in scenario_matrix() if s.name == scenario_name)
    if sc.shifts != 1:
        raise ShiftError(f"scenario {scenario_name}: {sc.shifts} shifts; run_on_vcan replays one")
    recs = run_case(plant_mod.load_plant(plant_path), shift_name, sc)
    inputs = [(rec["t0_s"] + rec["t_s"][k], canlog.can.Message(arbitration_id=fid, data=data, is_extended_id=False))
              for rec in recs for k, frames in enumerate(rec["frames_in"]) for fid, data in frames]
    canlog.write_log(out_dir / "inputs.log", inputs)
    replay.run_on_vcan([(out_dir / "inputs.log", out_dir / "vcan")], frame_runs=1, timer_runs=0,
                       calibration=TCU_CALIBRATION, bench=False, shift=shift_name, theta_start_degC=sc.oil_degC)
    sent_ids = {m.arbitration_id for _, m in inputs}
    frames = [(m.arbitration_id, bytes(m.data).hex().upper()) for m in canlog.read_log(out_dir / "vcan" / "frame1.log")
              if m.arbitration_id not in sent_ids]
    payload = {"frames": frames, "inproc_frames": frame_sequence(recs), "quality": [quality(r) for r in recs]}
    (out_dir / "vcan_frames.json").write_text(json.dumps(payload, default=float))
    return out_dir / "vcan_frames.json"


def _fault_injector(fault: str, k_torque: int, k_inertia: int, dt: float, then=None):
    """The injector of scenarios.FAULTS[fault]: SlipSpeed SNA over its window (then: another injector after it)."""
    phase, offset_s, duration_s = FAULTS[fault]
    k0 = (k_torque if phase == "torque" else k_inertia) + int(round(offset_s / dt))
    k1 = k0 + int(round(duration_s / dt))

    def inject(k, k_i, signals):
        if k0 <= k < k1:
            signals[canlog.SENSORS]["SlipSpeed"] = "SNA"
        if then is not None:
            then(k, k_i, signals)
    return inject


def _one_shift(params, tcu, enc, db, scenario: Scenario, theta_clutch_degC, t0_s: float, seed: int,
               target_s: float, shift_cal, inject=None) -> dict:
    """One shift on a fresh plant (1st gear, steady): pre-roll, command, shift_duration. Returns the record.
    inject(k, k_inertia, signals): a fault injector (the adaptation study's faults), called each period with
    the step, the step the controller enters the inertia phase at and {frame name: its signals} before they
    are encoded; it may change the signals in place (a DBC choice name such as "SNA" encodes its raw value)."""
    p = params
    full = p.turbine_torque_full * scenario.load
    # the whole shift (DESIGN 14): the TCU drives the off-going clutch and asks the engine for torque
    whole = int(getattr(shift_cal, "coordinator", 0)) == 1
    drive_offgoing = whole and not scenario.scripted_release
    if scenario.offgoing_friction != 1.0:
        p = dataclasses.replace(p, offgoing_friction_scale=p.offgoing_friction_scale * scenario.offgoing_friction)
    pl = plant_mod.UpshiftPlant(p, oil_degC=scenario.oil_degC, turbine_torque_Nm=full,
                                friction_scale=p.friction_scale * scenario.friction_scale, seed=seed,
                                theta_clutch_degC=theta_clutch_degC,
                                offgoing_current_mA=p.offgoing_cal.vfs_current_max if drive_offgoing else None,
                                engine_ignores_request=scenario.engine_ignores, offgoing_slip_sensor=whole)
    dt = pl.dt_s
    n_pre = int(round(p.preroll_time / dt))
    n = n_pre + int(round(p.shift_duration / dt))
    msg_cmd = db.get_message_by_name(canlog.COMMAND)
    msg_est = db.get_message_by_name(canlog.ESTIMATE)
    msg_rep = db.get_message_by_name(canlog.SHIFT_REPORT)
    msg_off = db.get_message_by_name(canlog.OFFGOING_COMMAND)
    msg_eng = db.get_message_by_name(canlog.ENGINE_REQUEST)
    rec = {k: np.empty(n) for k in ("t_s", "sensor_slip_rad_s", "current_mA", "pressure_command_Pa",
                                    "theta_estimate_degC", "model_torque_Nm", "locked_tcu")}
    rec.update({k: np.zeros(n) for k in ("offgoing_current_cmd_mA", "engine_delta_cmd_Nm", "tcu_phase",
                                         "tcu_fallback")})
    offgoing_current = p.offgoing_cal.vfs_current_max
    engine_delta = 0.0
    truth = {}
    frames_out = []
    frames_in = []          # what the TCU received, for the reference (reference/shift.py)
    report = None
    current = 0.0
    n_prep = int(shift_cal.prepare_time / dt + 0.5)
    n_tp = int(shift_cal.torque_phase_time / dt + 0.5)
    k_i = n_pre + n_prep + n_tp           # the controller enters the inertia phase at this step (wc_shift.c)
    if scenario.fault:                    # a lost input in the middle of the shift (scenarios.FAULTS)
        inject = _fault_injector(scenario.fault, n_pre + n_prep + n_tp // 2, k_i, dt, inject)
    for k in range(n):
        t = t0_s + k * dt
        s = pl.sensors()
        signals = {canlog.REQUEST: {"TorqueRequest": 0.0, "Mode": canlog.MODE_SHIFT},
                   canlog.SHIFT_COMMAND: {"ShiftRequest": int(k >= n_pre), "AdaptationReset": 0, "TargetGear": 2, "CurrentGear": 1,
                                          "TurbineTorque": float(np.clip(s["turbine_torque_estimate_Nm"], -1000.0, 1000.0)),
                                          "TargetInertiaTime": round(target_s * 1e3)},
                   canlog.SENSORS: {"SlipSpeed": float(np.clip(s["slip_rpm"], -8000.0, 8000.0)),
                                    "OilTemp": float(s["oil_degC"]), "HousingTemp": float(s["housing_degC"])}}
        if whole:   # before ClutchSensors, which steps the loop
            sensors = signals.pop(canlog.SENSORS)
            signals[canlog.OFFGOING_SENSORS] = {"OffgoingSlipSpeed": float(np.clip(s["offgoing_slip_rpm"], -8000.0, 8000.0))}
            signals[canlog.SENSORS] = sensors
        if inject is not None:
            inject(k, k_i, signals)
        frames = [enc.frame(name, **sig) for name, sig in signals.items()]
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
            elif fid == msg_off.frame_id:
                o = msg_off.decode(data, decode_choices=False)
                offgoing_current = float(o["VfsCurrent"])
                rec["tcu_phase"][k] = float(o["ShiftPhase"])
                rec["tcu_fallback"][k] = float(o["Fallback"])
            elif fid == msg_eng.frame_id:
                e = msg_eng.decode(data, decode_choices=False)
                engine_delta = float(e["TorqueDelta"]) if int(e["InterventionActive"]) else 0.0
        rec["t_s"][k] = k * dt
        rec["sensor_slip_rad_s"][k] = s["slip_rpm"] * plant_mod.RPM
        rec["offgoing_current_cmd_mA"][k] = offgoing_current
        rec["engine_delta_cmd_Nm"][k] = engine_delta
        pl.step(current, (k - n_pre) * dt if k >= n_pre else None,
                offgoing_current if drive_offgoing else None, engine_delta if whole else None)
        for name, v in pl.truth.items():
            truth.setdefault(name, np.empty(n))[k] = v
    rec.update({f"true_{k}": v for k, v in truth.items()})
    rec["frames"] = frames_out
    rec["frames_in"] = frames_in
    rec["report"] = report
    rec["t0_s"] = t0_s           # the TCU's time of step k: t0_s + t_s[k]
    rec["command_step"] = n_pre
    if whole:   # the coordinator may enter the inertia phase early (the hand-over): the TCU's phase says when
        entered = np.flatnonzero(rec["tcu_phase"] >= 3)
        k_i = int(entered[0]) if entered.size else k_i
    rec["inertia_step"] = k_i
    rec["whole"] = whole
    start = rec["sensor_slip_rad_s"][k_i]
    ref = np.full(n, np.nan)
    ref[k_i:] = [shift_reference.reference_slip(start, target_s, j * dt)[0] for j in range(n - k_i)]
    rec["reference_slip_rad_s"] = ref
    rec["end_theta_degC"] = float(truth["theta_clutch_degC"][-1])
    return rec


def record_messages(records: list[dict]) -> list:
    """The frames of a case's shifts both ways, per step what the TCU received then what it sent, as
    python-can Messages stamped with the TCU's time (t0_s + t_s[k]), for util/mdf. The frames between two
    shifts (between_shifts: idle, no slip) are not kept by the records, so not here either."""
    out = []
    for rec in records:
        sent: dict[int, list] = {}
        for k, fid, data in rec["frames"]:
            sent.setdefault(k, []).append((fid, bytes.fromhex(data)))
        for k, received in enumerate(rec["frames_in"]):
            t = rec["t0_s"] + rec["t_s"][k]
            out += [canlog.can.Message(timestamp=t, arbitration_id=fid, is_extended_id=False, data=data)
                    for fid, data in received + sent.get(k, [])]
    return out


BETWEEN_SHIFTS_S = 0.5   # back-to-back shifts: the 2->1 downshift's release between them (see between_shifts)
IDLE_FRAMES = (canlog.REQUEST, canlog.SHIFT_COMMAND, canlog.SENSORS)
IDLE_FRAMES_WHOLE = (canlog.REQUEST, canlog.SHIFT_COMMAND, canlog.OFFGOING_SENSORS, canlog.SENSORS)


@functools.lru_cache(maxsize=32)
def _idle_frames(oil_degC: float, housing_degC: float, target_ms: int) -> dict:
    """The idle period's frames for each alive counter (their signals do not change): {name: [16 messages]}."""
    db = canlog.database()
    out = {}
    for name, sig in ((canlog.REQUEST, {"TorqueRequest": 0.0, "Mode": canlog.MODE_SHIFT}),
                      (canlog.SHIFT_COMMAND, {"ShiftRequest": 0, "AdaptationReset": 0, "TargetGear": 2, "CurrentGear": 1,
                                              "TurbineTorque": 0.0, "TargetInertiaTime": target_ms}),
                      (canlog.OFFGOING_SENSORS, {"OffgoingSlipSpeed": 0.0}),
                      (canlog.SENSORS, {"SlipSpeed": 0.0, "OilTemp": oil_degC, "HousingTemp": housing_degC})):
        msg = db.get_message_by_name(name)
        frames = []
        for count in range(16):
            data = bytearray(msg.encode({"Crc": 0, "AliveCounter": count, **sig}, scaling=True, strict=True))
            canlog.protect(msg.frame_id, data)
            frames.append(canlog.can.Message(arbitration_id=msg.frame_id, is_extended_id=False, data=bytes(data)))
        out[name] = frames
    return out


def between_shifts(params, tcu, enc, oil_degC: float, theta_clutch_degC: float | None, t0_s: float,
                   gap_s: float = BETWEEN_SHIFTS_S, target_s: float = TARGET_INERTIA_S,
                   whole: bool = False) -> tuple[float | None, float]:
    """The time between two shifts, where a vehicle's 2->1 downshift releases the on-coming clutch: gap_s
    of frames with ShiftRequest 0 and no slip (the released clutch in 2nd gear, before 1st gear's slip
    builds up), so the TCU's VFS and film release the clutch without slip (no model heat); the plant's pack
    relaxes with eq. 1 and no friction power over the same time, towards the steady state of oil_degC.
    Without it the next shift's plant starts in 1st gear at full slip while the TCU's model still holds the
    clutch locked, and the observer takes tens of kW of drag heat that no real clutch sees (about +12 K per
    shift). The frames go out written ahead where the TCU can take them so (InprocTcu.run_open_loop), else
    one period at a time. Returns the pack temperature after it (None stays None: the oil's) and the time."""
    dt = 1e-3
    n = int(round(gap_s / dt))
    if n <= 0:
        return theta_clutch_degC, t0_s
    housing = oil_degC + params.housing_offset
    frames = _idle_frames(round(oil_degC, 1), round(housing, 1), round(target_s * 1e3))
    steps = []
    for _ in range(n):
        batch = []
        for name in (IDLE_FRAMES_WHOLE if whole else IDLE_FRAMES):
            count = enc.counters.get(name, 0)
            batch.append(frames[name][count])
            enc.counters[name] = (count + 1) % 16      # as Encoder.frame counts
        steps.append(batch)
    if hasattr(tcu, "run_open_loop"):
        tcu.run_open_loop(t0_s, steps)
    else:
        for k, batch in enumerate(steps):
            tcu.exchange(t0_s + k * dt, batch)
    theta = theta_clutch_degC
    if theta is not None:
        cal = params.clutch_cal
        k_total = cal.oil_conductance + cal.housing_conductance
        steady = (cal.oil_conductance * oil_degC + cal.housing_conductance * housing) / k_total  # eq. 1, no power
        theta = float(steady + (theta - steady) * np.exp(-k_total * n * dt / cal.heat_capacity))
    return theta, t0_s + n * dt


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
            if i > 0:
                theta, t0 = between_shifts(params, tcu, enc, scenario.oil_degC, theta, t0, target_s=target_s,
                                           whole=int(getattr(shift_cal, "coordinator", 0)) == 1)
            rec = _one_shift(params, tcu, enc, db, scenario, theta, t0, params.seed + i, target_s, shift_cal)
            records.append(rec)
            theta = rec["end_theta_degC"]
            t0 += rec["t_s"][-1] + 1e-3
        return records
    finally:
        if own:
            tcu.close()


def reference_run(rec: dict, shift_cal, clutch_cal, theta_start_degC: float, reference=None) -> dict:
    """The double-precision reference (reference/shift.py) on the inputs the TCU received in rec, with the
    TCU's safe state from its VfsCommand: per step the reference's current and the TCU's (decoded), and the
    reports of both. reference: a ShiftReference to go on with (the next shift of a run_case: the clutch
    state and the learned values carried over, theta_start_degC unused); out["reference"] is the one used."""
    db = canlog.database()
    msgs = {n: db.get_message_by_name(n) for n in (canlog.SENSORS, canlog.SHIFT_COMMAND, canlog.COMMAND,
                                                   canlog.SHIFT_REPORT)}
    ids = {m.frame_id: n for n, m in msgs.items()}
    ref = reference or shift_reference.ShiftReference(shift_cal, clutch_cal, theta_start_degC)
    n = len(rec["frames_in"])
    out = {"reference_mA": np.empty(n), "tcu_mA": np.empty(n), "reference_report": None, "tcu_report": None,
           "reference_report_step": None, "tcu_report_step": None, "reference": ref}
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
