"""Port faults on a live vcan (natively, or in the QEMU guest): the interface
is set down and up while wc_tcu runs with the timer clock. The TCU must keep
running, say so (stderr, bus_errors in its statistics, StatusBusError), stay in
the safe state while its inputs are gone, and control again once they are back
(DESIGN.md section 8, issue 10 item 7)."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
from vcan_support import needs_vcan

from wetclutch import canlog, replay

ROOT = Path(__file__).resolve().parents[2]


pytestmark = needs_vcan

GUEST = r"""
set -u
out=$1; tcu=$2
candump -L vcan0 > "$out/capture.log" & dump=$!
"$tcu" --iface vcan0 --clock timer --calibration table1 --stats-json "$out/stats.json" 2> "$out/tcu.txt" & tcu_pid=$!
sleep 0.5
canplayer -I "$out/before.log" vcan0=vcan0
ip link set vcan0 down
sleep 0.5
ip link set vcan0 up
sleep 0.3
canplayer -I "$out/after.log" vcan0=vcan0
sleep 0.5
# markers in their own file: wc_tcu's stderr (tcu.txt) has its own file offset
kill -0 "$tcu_pid" && echo "wc_tcu still running" >> "$out/guest.txt"
kill -TERM "$tcu_pid"; wait "$tcu_pid"; echo "wc_tcu exit $?" >> "$out/guest.txt"
sleep 0.5; kill "$dump"; wait "$dump" 2>/dev/null || true
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
    assert "wc_tcu still running" in guest, guest + text    # it did not exit when the interface went down
    assert "wc_tcu exit 0" in guest, guest + text          # and stopped cleanly on SIGTERM
    # The kernel reports the down interface to whichever call comes first: a
    # receive (ENETDOWN: closed and reopened) or, usually, a send (counted).
    assert ("interface down" in text) or ("Network is down" in text), text
    stats = json.loads((out / "stats.json").read_text())
    assert stats["bus_errors"] >= 1, stats
    status = replay.output_frames(canlog.read_log(out / "capture.log"))[canlog.COMMAND]["status"]
    assert np.any(status & replay.BIT["StatusBusError"])
    safe = (status & replay.BIT["StatusSafeStateActive"]) != 0
    # control before the fault, the safe state across it, control again at the end
    assert not np.all(safe) and safe[-1] == False, "no control after the interface came back"  # noqa: E712
    assert np.any(safe[np.argmax(~safe):]), "the gap did not bring the safe state"
