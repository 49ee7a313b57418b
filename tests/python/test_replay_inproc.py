"""The TCU's frame loop in-process (src/host/wc_replay: the same wc_loop_iterate
as wc_tcu --clock frame, without SocketCAN) against the double-precision
reference of the loop (wetclutch.hil.replay.loop_reference), on the bundled bench
logs and on logs with injected faults. No VM: this is the fast check that the
C loop and its Python reference implement the same policy (E2E receiver,
debounce, bench input, status bits); the HIL replay repeats it on vcan.

Tolerances: those of the vcan test (tests/python/frames_check.py): half a raw
step plus 1e-4 relative per signal, identical status words."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from frames_check import assert_frames_match_reference
from wetclutch import calibration
from wetclutch.hil import replay
from wetclutch.util import canlog

ROOT = Path(__file__).resolve().parents[2]
LOGS = ROOT / "hil" / "logs"
CAL = ROOT / "tools" / "calibrations" / "bench_identified.toml"


@pytest.fixture(scope="module")
def wc_replay() -> Path:
    try:
        return replay.wc_replay_program()
    except FileNotFoundError as e:
        if os.environ.get("CI"):
            pytest.fail(str(e))
        pytest.skip(str(e))


def run_inproc(exe: Path, log: Path, tmp_path: Path, bench: bool = True) -> list:
    out = tmp_path / (log.stem + ".out.log")
    theta = replay.theta_start_degC_of(canlog.read_log(log))   # as wetclutch replay passes wc_tcu
    args = [str(exe), str(log), "--calibration", "bench_identified", "--theta-start", f"{theta:.1f}"] + (
        ["--bench"] if bench else [])
    proc = subprocess.run(args, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    out.write_text(proc.stdout)
    return canlog.read_log(out)


def check_against_reference(frames, log_messages, bench: bool = True) -> None:
    cal = calibration.load(CAL)
    ref = replay.loop_reference(cal, log_messages, bench=bench)
    assert_frames_match_reference(ref, replay.output_frames(frames))


@pytest.mark.parametrize("name", ["engagement_750rpm", "engagement_500rpm", "engagement_250rpm",
                                  "engagement_750rpm_80degC", "engagement_500rpm_80degC", "engagement_250rpm_80degC"])
def test_bundled_logs_match_reference(wc_replay, tmp_path, name):
    log = LOGS / f"{name}.log"
    frames = run_inproc(wc_replay, log, tmp_path)
    check_against_reference(frames, canlog.read_log(log))
    assert len(replay.raw_payloads(frames)) == 2 * 2500
    # the bench input was used, and said so
    status = replay.output_frames(frames)[canlog.COMMAND]["status"]
    assert np.any(status & replay.BIT["StatusBenchInput"])
    # deterministic: a second run gives the same frames
    again = run_inproc(wc_replay, log, tmp_path)
    assert replay.raw_payloads(frames) == replay.raw_payloads(again)


def _faulty_log(tmp_path: Path, fault: str) -> Path:
    """The first 1.4 s of the 250 rpm engagement with one fault injected into the
    ClutchSensors frames from 1.0 s to 1.2 s (contact is at 0.9 s: torque control)."""
    messages = canlog.read_log(LOGS / "engagement_250rpm.log")
    db = canlog.database()
    sensors = db.get_message_by_name(canlog.SENSORS)
    out, frozen = [], None
    for msg in messages:
        t = msg.timestamp - messages[0].timestamp
        if t >= 1.4:
            break
        if msg.arbitration_id == sensors.frame_id and 1.0 <= t < 1.2:
            data = bytearray(msg.data)
            if fault == "stop":
                continue
            if fault == "frozen":
                frozen = frozen or bytes(data)
                data = bytearray(frozen)
            elif fault == "crc":
                data[3] ^= 0x10
            msg.data = data
        out.append((msg.timestamp, msg))
    path = tmp_path / f"fault_{fault}.log"
    canlog.write_log(path, out)
    return path


@pytest.mark.parametrize("fault", ["stop", "frozen", "crc"])
def test_faults_match_reference(wc_replay, tmp_path, fault):
    log = _faulty_log(tmp_path, fault)
    frames = run_inproc(wc_replay, log, tmp_path)
    check_against_reference(frames, canlog.read_log(log))
    status = replay.output_frames(frames)[canlog.COMMAND]["status"]
    safe = (status & replay.BIT["StatusSafeStateActive"]) != 0
    # start-up debounce, then the fault's safe state: entered and left once each
    assert np.count_nonzero(np.diff(safe.astype(int))) == (1 if fault == "stop" else 3)


def test_bench_input_off_ignores_bench_frames(wc_replay, tmp_path):
    log = LOGS / "engagement_750rpm.log"
    frames = run_inproc(wc_replay, log, tmp_path, bench=False)
    check_against_reference(frames, canlog.read_log(log), bench=False)
    status = replay.output_frames(frames)[canlog.COMMAND]["status"]
    assert not np.any(status & replay.BIT["StatusBenchInput"])
