"""Integration on a real kernel's vcan: wc_tcu on vcan0 (natively, or in the
QEMU guest that hil/vcan_run.sh boots), frames in with wc_canplay (with the
frame clock in lockstep with the TCU's answers, DESIGN 5), the bus recorded by
it, decoded with cantools and checked against the reference model; and a
bundled bench log replayed frame-identical to the same loop in-process
(wc_replay).

The input log is an engagement with faults injected on purpose: one TorqueRequest
with a bad CRC, one short TorqueRequest, one frame of an unknown id, and a
15-period gap of TorqueRequest frames (a request timeout).
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from frames_check import assert_frames_match_reference
from conftest import TABLE1
from wetclutch.calibration import cal_image
from wetclutch.hil import replay
from wetclutch.util import canlog

STEPS = 800
BAD_CRC_STEP, SHORT_STEP, UNKNOWN_STEP = 300, 400, 500
REQUEST_GAP = range(600, 615)


def _input_log(path: Path) -> list:
    t = np.arange(STEPS) * 1e-3
    slip = np.clip(750.0 * (1.0 - (t - 0.05) / 0.7), 0.0, 750.0)
    request = np.clip((t - 0.05) * 400.0, 0.0, 180.0)
    mode = np.where(t < 0.05, canlog.MODE_OPEN, canlog.MODE_TORQUE_CONTROL)
    frames = canlog.input_log(t, slip, np.full(STEPS, 40.0), np.full(STEPS, 38.0), request, mode=mode)
    out = []
    for k in range(STEPS):
        request_frame, sensors_frame = frames[2 * k], frames[2 * k + 1]
        if k not in REQUEST_GAP:
            out.append(request_frame)
        stamp, msg = request_frame
        if k == BAD_CRC_STEP:   # an extra copy with one bit flipped in the payload: CRC mismatch
            bad = bytearray(msg.data)
            bad[3] ^= 0x10
            out.append((stamp + 1e-6, canlog.can.Message(arbitration_id=msg.arbitration_id, data=bytes(bad),
                                                         is_extended_id=False)))
        if k == SHORT_STEP:
            out.append((stamp + 1e-6, canlog.can.Message(arbitration_id=msg.arbitration_id, data=bytes(msg.data[:5]),
                                                         is_extended_id=False)))
        if k == UNKNOWN_STEP:
            out.append((stamp + 1e-6, canlog.can.Message(arbitration_id=0x7FF, data=b"\x01\x02", is_extended_id=False)))
        out.append(sensors_frame)
    canlog.write_log(path, out)
    return out


@pytest.fixture(scope="module")
def replayed(tmp_path_factory, root, tcu):
    work = tmp_path_factory.mktemp("vcan")
    log = work / "input.log"
    _input_log(log)
    image = work / "table1.img"   # the same calibration as an image file (DESIGN 13)
    cal_image.write_file(image, cal_image.build(TABLE1))
    replay.run_on_vcan([(log, work / "out")], frame_runs=2, timer_runs=1, tcu=tcu, calibration_image=image,
                       image_runs=1)
    return log, work / "out"


def test_frame_clock_outputs_match_reference(replayed, cal):
    log, out = replayed
    ref = replay.loop_reference(cal, canlog.read_log(log))
    frames = replay.output_frames(canlog.read_log(out / "frame1.log"))
    assert_frames_match_reference(ref, frames, steps=STEPS)
    cmd = frames[canlog.COMMAND]
    # The injected faults were seen where they were injected.
    assert cmd["status"][BAD_CRC_STEP] & replay.BIT["StatusCrcError"]
    safe = np.flatnonzero(cmd["status"] & replay.BIT["StatusSafeStateActive"])
    assert set(range(REQUEST_GAP.start + 10, REQUEST_GAP.stop)) <= set(safe.tolist())
    assert np.all(cmd["VfsCurrent"][REQUEST_GAP.start + 10:REQUEST_GAP.stop] == cal.vfs_current_min)


def test_frame_clock_replay_is_deterministic(replayed):
    _, out = replayed
    first = replay.raw_payloads(canlog.read_log(out / "frame1.log"))
    second = replay.raw_payloads(canlog.read_log(out / "frame2.log"))
    assert len(first) == 2 * STEPS
    assert first == second


def test_calibration_image_gives_the_same_frames(replayed):
    """wc_tcu --calibration-image of table1 and the compiled-in table1: byte-identical output frames."""
    _, out = replayed
    compiled = replay.raw_payloads(canlog.read_log(out / "frame1.log"))
    from_image = replay.raw_payloads(canlog.read_log(out / "image1.log"))
    assert len(from_image) == 2 * STEPS
    assert from_image == compiled


def test_tcu_counts_frames_and_rejects(replayed):
    log, out = replayed
    stats = json.loads((out / "frame1.json").read_text())
    received = [m for m in canlog.read_log(log) if m.arbitration_id in (0x110, 0x111, 0x130)]  # the kernel filter's ids
    assert stats["frames_in"] == len(received)
    assert stats["rejected"]["crc"] == 1 and stats["rejected"]["short"] == 1
    assert stats["rejected"]["unknown_id"] == 0   # 0x7FF never passes the kernel filter
    assert stats["request_timeouts"] == 1 and stats["sensor_timeouts"] == 0
    assert stats["rx_dropped_by_kernel"] == 0 and stats["tx_errors"] == 0
    assert stats["steps"] == STEPS and stats["frames_out"] == 2 * STEPS


BUNDLED = "engagement_750rpm"


def test_bundled_log_on_vcan_is_frame_identical_to_wc_replay(tmp_path, root, tcu):
    """The bundled 750 rpm engagement with its bench input: every frame wc_tcu sends on vcan (VfsCommand,
    ClutchEstimate), byte for byte and in order, is the frame the same loop sends in-process."""
    log = root / "hil" / "logs" / f"{BUNDLED}.log"
    replay.run_on_vcan([(log, tmp_path / "vcan")], frame_runs=1, timer_runs=0, tcu=tcu, calibration="table1")
    on_vcan = replay.raw_payloads(canlog.read_log(tmp_path / "vcan" / "frame1.log"))
    replay.run_in_process([(log, tmp_path / "inproc")], frame_runs=1, calibration="table1")
    in_process = replay.raw_payloads(canlog.read_log(tmp_path / "inproc" / "frame1.log"))
    assert len(on_vcan) == 2 * 2500
    assert on_vcan == in_process
    stats = json.loads((tmp_path / "vcan" / "frame1.json").read_text())
    assert stats["rx_dropped_by_kernel"] == 0 and stats["steps"] == 2500


def test_timer_clock_runs_and_reports_step_times(replayed):
    _, out = replayed
    stats = json.loads((out / "timer1.json").read_text())
    assert stats["steps"] > 0 and stats["frames_out"] == 2 * stats["steps"]
    times = stats["step_time_us"]
    assert 0.0 < times["p50"] <= times["p90"] <= times["p99"] <= times["max"]
    print(f"\ntimer clock on vcan: {stats['steps']} steps, deadline misses {stats['deadline_misses']},"
          f" step time p50 {times['p50']} us, p99 {times['p99']} us, max {times['max']} us"
          f" ({'QEMU guest' if not os.path.exists('/sys/class/net/vcan0') else 'host vcan'})")
