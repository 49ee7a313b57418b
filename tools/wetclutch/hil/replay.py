"""Replay a bench log to the TCU program on vcan and compare with the reference.

Pieces, usable alone:
  check_log      validate a candump -L log: parseable, time-ordered, no gaps,
                 ids known (what is wrong is reported with its line)
  run_on_vcan    hil/vcan_run.sh + hil/replay_guest.sh: wc_tcu on a live vcan0
                 (native, or inside the QEMU guest), wc_canplay in (lockstep on the
                 TCU's answers with the frame clock) and recording the bus
  run_in_process the same frame-clock runs with the same loop in-process (wc_replay):
                 no kernel, no guest, the same frames
  loop_reference the frame loop of src/wc_loop.c re-implemented here (E2E,
                 plausibility, freshness, safe state) feeding model.clutch_steps
  compare        the TCU's output frames against the reference, step by step
"""
from __future__ import annotations

import json
import os
import shlex
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..reference import model
from ..util import canlog
from ..calibration import Calibration

ROOT = canlog.ROOT
RX_NAMES = (canlog.SENSORS, canlog.REQUEST, canlog.BENCH)  # what wc_tcu's kernel filter lets in (--bench)
RX_CAPACITY = 32  # WC_LOOP_RX_CAPACITY: frames queued between two steps
# VfsCommand's status word, bit n = the n-th 1-bit Status* signal (from the DBC, as the C codec).
STATUS_BITS = tuple(sig.name for sig in canlog.database().get_message_by_name(canlog.COMMAND).signals
                    if sig.name.startswith("Status") and sig.length == 1)
BIT = {name: 1 << i for i, name in enumerate(STATUS_BITS)}


# --------------------------------------------------------------------------- log checks

@dataclass
class LogCheck:
    frames: int = 0
    by_name: dict = field(default_factory=dict)
    unknown_ids: dict = field(default_factory=dict)     # id -> (count, first line)
    out_of_order: list = field(default_factory=list)    # line numbers
    gaps: list = field(default_factory=list)            # (line, gap_s)
    span_s: float = 0.0

    def problems(self) -> list[str]:
        out = []
        for ident, (count, line) in sorted(self.unknown_ids.items()):
            out.append(f"unknown id 0x{ident:X}: {count} frame(s), first at line {line} (not in hil/wetclutch.dbc;"
                       " the TCU's receive filter drops them)")
        for line in self.out_of_order[:5]:
            out.append(f"line {line}: timestamp earlier than the line before (out of order)")
        if len(self.out_of_order) > 5:
            out.append(f"... {len(self.out_of_order) - 5} more out-of-order lines")
        for line, gap in self.gaps[:5]:
            out.append(f"line {line}: {gap * 1e3:.1f} ms since the previous ClutchSensors frame (gap)")
        if len(self.gaps) > 5:
            out.append(f"... {len(self.gaps) - 5} more gaps")
        return out


def check_log(path: Path, period_s: float = 1e-3, gap_periods: float = 5.0) -> LogCheck:
    """Raises canlog.LogError for a missing or malformed file; returns what it found."""
    db = canlog.database()
    messages = canlog.read_log(path)
    if not messages:
        raise canlog.LogError(f"{path}: empty log")
    check = LogCheck(frames=len(messages), span_s=messages[-1].timestamp - messages[0].timestamp)
    last_t = None
    last_sensor_t = None
    sensors_id = db.get_message_by_name(canlog.SENSORS).frame_id
    for line, msg in enumerate(messages, start=1):
        if last_t is not None and msg.timestamp < last_t:
            check.out_of_order.append(line)
        last_t = msg.timestamp
        try:
            name = db.get_message_by_frame_id(msg.arbitration_id).name
        except KeyError:
            count, first = check.unknown_ids.get(msg.arbitration_id, (0, line))
            check.unknown_ids[msg.arbitration_id] = (count + 1, first)
            continue
        check.by_name[name] = check.by_name.get(name, 0) + 1
        if msg.arbitration_id == sensors_id:
            if last_sensor_t is not None and msg.timestamp - last_sensor_t > gap_periods * period_s:
                check.gaps.append((line, msg.timestamp - last_sensor_t))
            last_sensor_t = msg.timestamp
    return check


# --------------------------------------------------------------------------- running on vcan

def run_on_vcan(jobs, frame_runs: int = 2, timer_runs: int = 1, tcu: Path | None = None,
                calibration: str = "table1", bench: bool = True, calibration_image: Path | None = None,
                image_runs: int = 0, shift: str | None = None, theta_start_degC: float | None = None) -> None:
    """Bring up vcan0 once (native, or one QEMU boot) and replay each (log, out_dir)
    of jobs, wc_tcu with --bench unless bench is False, --shift shift when given; image_runs more
    frame-clock runs with wc_tcu --calibration-image calibration_image (image<n>.*). theta_start_degC:
    the observer's start (default: the log's, theta_start_degC_of). Progress goes to stderr.
    Raises on failure."""
    tcu = Path(tcu or ROOT / "build" / "host-release" / "src" / "port" / "wc_tcu")
    for program in (tcu, tcu.parent / "wc_canplay"):
        if not program.is_file():
            raise FileNotFoundError(f"{program}: not built (cmake --preset host-release &&"
                                    " cmake --build --preset host-release)")
    script = []
    shared = []   # one writable share per output parent: every share is on the guest kernel's command line
    for job_log, job_out in jobs:
        job_out = Path(job_out).resolve()
        job_out.mkdir(parents=True, exist_ok=True)
        if job_out.parent not in shared:
            shared.append(job_out.parent)
        theta = theta_start_degC_of(canlog.read_log(job_log)) if theta_start_degC is None else theta_start_degC
        script.append(shlex.join(["bash", str(ROOT / "hil" / "replay_guest.sh"), str(Path(job_log).resolve()),
                                  str(job_out), "--frame-runs", str(frame_runs), "--timer-runs", str(timer_runs),
                                  "--tcu", str(tcu), "--calibration", calibration, *(["--bench"] if bench else []),
                                  *(["--shift", shift] if shift else []),
                                  "--theta-start", f"{theta:.6g}",
                                  *(["--calibration-image", str(Path(calibration_image).resolve()), "--image-runs",
                                     str(image_runs)] if image_runs else [])]))
    rw = [arg for d in shared for arg in ("--rwdir", str(d))]
    cmd = ["bash", str(ROOT / "hil" / "vcan_run.sh"), *rw, "--", "bash", "-c", " && ".join(script)]
    env = dict(os.environ, PATH=f"{ROOT / '.venv' / 'bin'}:{os.environ.get('PATH', '')}")
    result = subprocess.run(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL)
    if result.returncode != 0:
        raise RuntimeError(f"replay on vcan failed (exit {result.returncode}); see the messages above and"
                           f" the wc_tcu logs (*.txt) in {', '.join(str(o) for _, o in jobs)}")


def wc_replay_program() -> Path:
    """The in-process loop (src/host/wc_replay), release build first."""
    for build in ("host-release", "host-debug"):
        path = ROOT / "build" / build / "src" / "host" / "wc_replay"
        if path.is_file():
            return path
    raise FileNotFoundError("wc_replay not built (cmake --preset host-release && cmake --build --preset host-release)")


def run_in_process(jobs, frame_runs: int = 2, calibration: str = "table1", bench: bool = True) -> None:
    """What run_on_vcan's frame-clock runs write (frame<n>.log: the inputs the TCU receives and its output
    frames; frame<n>.json: its counters), from the same loop in-process (wc_replay): the HIL report without a
    kernel or a guest. No timer-clock run (there is no time in-process). Raises on failure."""
    program = wc_replay_program()
    for job_log, job_out in jobs:
        job_out = Path(job_out)
        job_out.mkdir(parents=True, exist_ok=True)
        messages = canlog.read_log(job_log)
        theta = theta_start_degC_of(messages)
        for i in range(1, frame_runs + 1):
            stats = job_out / f"frame{i}.json"
            run = subprocess.run([str(program), str(job_log), "--calibration", calibration,
                                  "--theta-start", f"{theta:.6g}", "--stats-json", str(stats),
                                  *(["--bench"] if bench else [])], capture_output=True, text=True)
            if run.returncode != 0:
                raise RuntimeError(f"wc_replay failed on {job_log} (exit {run.returncode}): {run.stderr.strip()}")
            # the bus as a recording on vcan holds it: the replayed frames, then the TCU's of each step
            outputs = canlog.read_log_lines(run.stdout.splitlines(), f"wc_replay {job_log}")
            canlog.write_log(job_out / f"frame{i}.log", _interleave(messages, outputs))
        for stale in job_out.glob("timer*.*"):   # a timer run of an earlier vcan replay is not this run's
            stale.unlink()


def _interleave(inputs, outputs) -> list:
    """(timestamp, message) of the inputs and each step's outputs after the frame that stepped it (wc_replay
    stamps its outputs with that frame's timestamp)."""
    by_time: dict[float, list] = {}
    for m in outputs:
        by_time.setdefault(round(m.timestamp, 6), []).append(m)
    sensors_id = canlog.database().get_message_by_name(canlog.SENSORS).frame_id
    out = []
    for m in inputs:
        out.append((m.timestamp, m))
        if m.arbitration_id == sensors_id and not (m.is_extended_id or m.is_remote_frame):
            out += [(m.timestamp, o) for o in by_time.pop(round(m.timestamp, 6), [])]
    return out


# --------------------------------------------------------------------------- reference of the loop

DEFAULT_THETA_START_DEGC = 40.0   # wc_tcu --theta-start's default


def theta_start_degC_of(messages) -> float:
    """Where the observer starts for a log: its first ClutchSensors oil temperature to 0.1 degC (a pack
    soaked at oil temperature; wc_tcu/wc_replay --theta-start), else wc_tcu's default."""
    spec = canlog.database().get_message_by_name(canlog.SENSORS)
    for m in messages:
        if m.arbitration_id == spec.frame_id and not m.is_extended_id and len(m.data) == spec.length:
            oil = float(spec.decode(bytes(m.data), decode_choices=False)["OilTemp"])
            if -40.0 <= oil <= 200.0:
                return round(oil, 1)
    return DEFAULT_THETA_START_DEGC

@dataclass
class _Input:
    """One input of the loop: its E2E receiver (wc_e2e.h, AUTOSAR E2E Profile 1)
    and its freshness, as src/can/wc_loop.c and src/can/wc_e2e.c."""
    timeout: int
    max_delta: int = 2
    sync_counter: int = 3
    age: int = 0
    seen: bool = False
    stale: bool = True
    state: str = "init"          # init, nosync, syncing, valid
    previous: int = 0
    in_sequence: int = 0
    lost_last: bool = False

    def receive(self, counter: int) -> str:
        """The receiver's status for this counter: ok, oksomelost, initial (used),
        sync, repeated, wrongsequence (not used)."""
        delta = (counter - self.previous) % 16
        if self.state == "init":
            self.previous, self.state = counter, "valid"
            return "initial"
        if self.state == "nosync":
            return self._resync(counter, "sync")
        if delta == 0:
            return "repeated"
        if self.state == "syncing":
            if delta != 1:
                return self._resync(counter, "wrongsequence")
            self.previous, self.in_sequence = counter, self.in_sequence + 1
            if self.in_sequence < self.sync_counter:
                return "sync"
            self.state, self.lost_last = "valid", False
            return "ok"
        if delta == 1:
            self.previous, self.lost_last = counter, False
            return "ok"
        if delta <= self.max_delta and not self.lost_last:
            self.previous, self.lost_last = counter, True
            return "oksomelost"
        return self._resync(counter, "wrongsequence")

    def _resync(self, counter: int, status: str) -> str:
        self.previous, self.state, self.in_sequence, self.lost_last = counter, "syncing", 0, False
        return status

    def freshness(self) -> tuple[bool, bool]:
        """(stale, timed_out_now), then one period older; a timeout restarts the receiver."""
        stale = (not self.seen) or self.age >= self.timeout
        timed_out = stale and not self.stale and self.seen
        if timed_out:
            self.seen, self.state = False, "nosync"
        self.stale = stale
        self.age += 1
        return stale, timed_out


def loop_reference(cal: Calibration, messages, theta_start: float | None = None,
                   sensor_timeout: int = 10, request_timeout: int = 10, recovery_periods: int = 20,
                   bench: bool = True) -> dict:
    """What wc_tcu --clock frame [--bench] computes for this sequence of received frames
    (WC_LOOP_CONFIG_DEFAULT: MaxDeltaCounter 2, SyncCounter 3, recovery 20 periods). theta_start: wc_tcu's
    --theta-start (default: the log's, theta_start_degC_of)."""
    theta_start_degC = theta_start_degC_of(messages) if theta_start is None else float(theta_start)
    db = canlog.database()
    names = RX_NAMES if bench else tuple(n for n in RX_NAMES if n != canlog.BENCH)  # wc_tcu's kernel filter
    specs = {db.get_message_by_name(n).frame_id: db.get_message_by_name(n) for n in names}
    sensors_id = db.get_message_by_name(canlog.SENSORS).frame_id
    inputs = {n: _Input(request_timeout if n == canlog.REQUEST else sensor_timeout) for n in RX_NAMES}
    held = {"SlipSpeed": 0.0, "OilTemp": theta_start_degC, "HousingTemp": theta_start_degC,
            "TorqueRequest": 0.0, "Mode": float(canlog.MODE_OPEN), "LoadCellForce": 0.0, "MeasuredTorque": 0.0}
    e2e = set(canlog.E2E_FRAMES)
    rejected = {k: 0 for k in ("crc", "counter", "short", "format", "implausible", "overflow", "sync")}
    pending = 0
    fresh_periods = 0
    queue = []                            # the loop's receive ring, WC_LOOP_RX_CAPACITY frames
    rows = []

    def process(spec, msg):
        nonlocal pending
        if msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
            rejected["format"] += 1
            pending |= BIT["StatusFrameLost"]
        elif len(msg.data) < 8:
            rejected["short"] += 1
            pending |= BIT["StatusFrameLost"]
        elif spec.name in e2e and canlog.crc8_j1850(bytes([spec.frame_id & 0xFF]) + bytes(msg.data[1:8])) != msg.data[0]:
            rejected["crc"] += 1
            pending |= BIT["StatusCrcError"]
        else:
            state = inputs[spec.name]
            values = spec.decode(bytes(msg.data), decode_choices=False, scaling=True)
            status = state.receive(int(values["AliveCounter"])) if spec.name in e2e else "ok"
            if status == "sync":
                rejected["sync"] += 1
            elif status in ("repeated", "wrongsequence"):
                rejected["counter"] += 1
                pending |= BIT["StatusCounterError"]
            elif any(not (sig.minimum <= values[sig.name] <= sig.maximum)
                     for sig in spec.signals if sig.name not in ("Crc", "AliveCounter")):
                # plausibility: every signal inside its DBC [min|max] (SNA values lie outside)
                rejected["implausible"] += 1
                pending |= BIT["StatusImplausibleInput"]
            else:
                state.age, state.seen = 0, True
                held.update({k: float(v) for k, v in values.items() if k in held})

    for msg in messages:
        spec = specs.get(msg.arbitration_id)
        if spec is None:
            continue                      # the kernel filter of wc_tcu drops it
        if len(queue) < RX_CAPACITY:
            queue.append((spec, msg))
        else:                             # ring full: lost before its check (only silent sensors fill it)
            rejected["overflow"] += 1
            pending |= BIT["StatusFrameLost"]
        if msg.arbitration_id != sensors_id or msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
            continue
        for queued in queue:
            process(*queued)
        queue.clear()
        bits, pending = pending, 0        # one step per ClutchSensors frame
        s_stale, _ = inputs[canlog.SENSORS].freshness()
        r_stale, _ = inputs[canlog.REQUEST].freshness()
        b_stale = inputs[canlog.BENCH].freshness()[0] if bench else True  # optional: staleness is no fault
        bits |= BIT["StatusSensorTimeout"] if s_stale else 0
        bits |= BIT["StatusRequestTimeout"] if r_stale else 0
        fresh_periods = 0 if (s_stale or r_stale) else fresh_periods + 1
        safe = s_stale or r_stale or fresh_periods < recovery_periods   # debounce (wc_loop.h)
        bits |= 0 if b_stale else BIT["StatusBenchInput"]
        mode = int(held["Mode"])  # model.MODE_* are the DBC's values
        rows.append((held["SlipSpeed"], held["OilTemp"], held["HousingTemp"], held["TorqueRequest"],
                     model.MODE_OPEN if safe else mode, bits | (BIT["StatusSafeStateActive"] if safe else 0),
                     np.nan if b_stale else max(held["LoadCellForce"], 0.0),
                     np.nan if b_stale else held["MeasuredTorque"]))
    if not rows:
        return {"steps": 0, "rejected": rejected}
    slip, oil, housing, request, mode, bits, load, measured_torque = (np.array(c) for c in zip(*rows))
    steps = model.clutch_steps(cal, slip, oil, housing, request, mode=mode.astype(int),
                               theta_start_degC=theta_start_degC, bench_force_N=load,
                               bench_torque_Nm=measured_torque)
    status = np.asarray(steps["status"])
    bits = bits.astype(int)
    bits |= np.where(status & model.STATUS_SATURATED, BIT["StatusSaturated"], 0)
    bits |= np.where(status & model.STATUS_CURRENT_CLAMPED, BIT["StatusCurrentClamped"], 0)
    bits |= np.where(status & model.STATUS_BELOW_DRAG, BIT["StatusBelowDrag"], 0)
    bits |= np.where(status & model.STATUS_OVER_TEMPERATURE, BIT["StatusOverTemperature"], 0)
    bits |= np.where(status & model.STATUS_LOCKED, BIT["StatusLocked"], 0)
    return {"steps": len(rows), "rejected": rejected, "film_state": cal.film_squeeze_factor > 0.0, "slip_rpm": slip, "theta_oil_degC": oil,
            "bench_force_N": load, "bench_torque_Nm": measured_torque,
            "theta_housing_degC": housing, "torque_request_Nm": request, "mode": mode, "status_bits": bits, **steps}


def output_frames(capture) -> dict:
    """VfsCommand and ClutchEstimate of a capture, with the status word rebuilt from its bits."""
    decoded = canlog.decode(capture)
    out = {}
    for name in (canlog.COMMAND, canlog.ESTIMATE):
        if name not in decoded:
            raise canlog.LogError(f"the capture holds no {name} frame: did wc_tcu run?")
        out[name] = decoded[name]
    cmd = out[canlog.COMMAND]
    cmd["status"] = sum(cmd[name].astype(int) << i for i, name in enumerate(STATUS_BITS))
    return out


def raw_payloads(capture, names=(canlog.COMMAND, canlog.ESTIMATE)) -> list[tuple[int, bytes]]:
    db = canlog.database()
    ids = {db.get_message_by_name(n).frame_id for n in names}
    return [(m.arbitration_id, bytes(m.data)) for m in capture if m.arbitration_id in ids]


def compare(reference: dict, outputs: dict) -> dict:
    """Per-signal worst differences between the TCU's frames and the reference."""
    cmd, est = outputs[canlog.COMMAND], outputs[canlog.ESTIMATE]
    n = reference["steps"]
    if len(cmd["VfsCurrent"]) != n or len(est["ModelTorque"]) != n:
        raise canlog.LogError(f"step count differs: reference {n}, TCU VfsCommand {len(cmd['VfsCurrent'])},"
                              f" ClutchEstimate {len(est['ModelTorque'])} (frames lost in capture?)")
    pairs = {
        "current_mA": (cmd["VfsCurrent"], reference["current_mA"]),
        "pressure_command_kPa": (cmd["PressureCommand"], reference["pressure_command_Pa"] * 1e-3),
        "theta_degC": (est["EstimatedClutchTemp"], reference["theta_degC"]),
        "torque_Nm": (est["ModelTorque"], reference["torque_Nm"]),
        "mu_f": (est["MuF"], reference["mu_f"]),
        "hbar_um": (est["FilmThickness"], reference["hbar_m"] * 1e6),
    }
    result = {k: float(np.max(np.abs(a - b))) for k, (a, b) in pairs.items()}
    result["status_mismatches"] = int(np.sum((cmd["status"] & ~BIT["StatusDeadlineMiss"]) != reference["status_bits"]))
    result["steps"] = n
    return result


def load_stats(path: Path) -> dict:
    try:
        return json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise canlog.LogError(f"{path}: wc_tcu statistics unreadable: {e}") from None
