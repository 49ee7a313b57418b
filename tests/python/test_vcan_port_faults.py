"""Port faults on a live vcan (natively, or in the QEMU guest): the interface
is set down and up while wc_tcu runs. The TCU must keep running, say so
(stderr, bus_errors in its statistics, StatusBusError), reopen its socket, stay
in the safe state while its inputs resynchronise, and control again once they
are back (DESIGN.md section 8, issue 10 item 7). The frame clock, with the
inputs played by wc_canplay in lockstep with the TCU's answers, and every wait
on an event: a slower guest only makes it slower (DESIGN 5)."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
from vcan_support import needs_vcan

from wetclutch.hil import replay
from wetclutch.util import canlog

ROOT = Path(__file__).resolve().parents[2]


pytestmark = needs_vcan

GUEST = r"""
set -u
out=$1; tcu=$2; player=$(dirname "$tcu")/wc_canplay
# every wait is on an event (a line of wc_tcu's, an answer on the bus), never on the clock (DESIGN 5)
until_said() { while kill -0 "$tcu_pid" 2>/dev/null && ! grep -q "$1" "$out/tcu.txt"; do sleep 0.05; done; }
"$tcu" --iface vcan0 --clock frame --calibration table1 --stats-json "$out/stats.json" 2> "$out/tcu.txt" & tcu_pid=$!
until_said "clock frame"
"$player" "$out/before.log" --record "$out/capture.log" 2> "$out/play_before.txt" || echo "player failed" >> "$out/guest.txt"
ip link set vcan0 down
until_said "interface down"
ip link set vcan0 up
until_said "reopened"
"$player" "$out/after.log" --record "$out/capture_after.log" 2> "$out/play_after.txt" || echo "player failed" >> "$out/guest.txt"
# markers in their own file: wc_tcu's stderr (tcu.txt) has its own file offset
kill -0 "$tcu_pid" && echo "wc_tcu still running" >> "$out/guest.txt"
kill -TERM "$tcu_pid"; wait "$tcu_pid"; echo "wc_tcu exit $?" >> "$out/guest.txt"
"""


def _logs(out: Path) -> None:
    steps = 1500   # 1.5 s each side of the interface's down time
    t = np.arange(2 * steps) * 1e-3
    frames = canlog.input_log(t, np.full(t.size, 300.0), np.full(t.size, 60.0), np.full(t.size, 55.0),
                              np.full(t.size, 120.0))
    canlog.write_log(out / "before.log", frames[:2 * steps])
    canlog.write_log(out / "after.log", [(stamp - t[steps], m) for stamp, m in frames[2 * steps:]])


def test_interface_down_and_up(tmp_path, tcu):
    out = tmp_path / "port"
    out.mkdir()
    _logs(out)
    run = subprocess.run(["bash", str(ROOT / "hil" / "vcan_run.sh"), "--rwdir", str(out), "--",
                          "bash", "-c", GUEST, "guest", str(out), str(tcu)],
                         cwd=ROOT, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=900)
    text = (out / "tcu.txt").read_text()
    guest = (out / "guest.txt").read_text() if (out / "guest.txt").exists() else ""
    assert run.returncode == 0, run.stderr[-2000:] + text
    assert "player failed" not in guest, guest + (out / "play_before.txt").read_text() + (out / "play_after.txt").read_text()
    assert "wc_tcu still running" in guest, guest + text    # it did not exit when the interface went down
    assert "wc_tcu exit 0" in guest, guest + text          # and stopped cleanly on SIGTERM
    # No sends while no frames arrive (frame clock): the receive sees ENETDOWN.
    assert "interface down" in text and "reopened" in text, text
    stats = json.loads((out / "stats.json").read_text())
    assert stats["bus_errors"] >= 1, stats
    def status_of(name):
        return replay.output_frames(canlog.read_log(out / name))[canlog.COMMAND]["status"]

    safe_bit, bus_bit = replay.BIT["StatusSafeStateActive"], replay.BIT["StatusBusError"]
    before, after = status_of("capture.log"), status_of("capture_after.log")
    assert np.any((before & safe_bit) == 0), "no control before the interface went down"
    # after it came back: the lost interface reported in the first VfsCommand, control again (the
    # frame clock did not step while no frame came, so no input timed out: the safe state after a
    # timeout is the fault matrix's subject, tests/c/test_loop_faults.c)
    assert after[0] & bus_bit, f"first VfsCommand after the gap: status 0x{int(after[0]):04x}, no StatusBusError"
    assert (after[-1] & safe_bit) == 0, "no control after the interface came back"
