"""hil/vcan_run.sh: a candump capture round trip on vcan0 (natively or in a QEMU guest)."""
from __future__ import annotations

import subprocess
from pathlib import Path

from vcan_support import needs_vcan

ROOT = Path(__file__).resolve().parents[2]
RUNNER = ROOT / "hil" / "vcan_run.sh"


pytestmark = needs_vcan

FRAMES = ["123#DEADBEEF", "7FF#0102030405060708", "010#"]

# Inside the runner: capture in the background, send, stop, check the log. It
# ends with exit 7 when everything worked, to also check that the runner
# hands back the command's own exit code (a failing check exits with 1).
CAPTURE = f"""
set -eu
log=$(mktemp)
candump -L vcan0 > "$log" & pid=$!
sleep 1
for f in {' '.join(FRAMES)}; do cansend vcan0 "$f"; done
sleep 1
kill "$pid"; wait "$pid" || true
cat "$log"
test "$(wc -l < "$log")" -eq {len(FRAMES)}
exit 7
"""


def test_candump_captures_cansend_frames():
    r = subprocess.run(
        ["bash", str(RUNNER), "--", "sh", "-c", CAPTURE],
        cwd=ROOT, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=600,
    )
    print(r.stderr)
    assert r.returncode == 7, r.stdout + r.stderr
    captured = [line.split()[2] for line in r.stdout.splitlines() if " vcan0 " in line]
    assert captured == FRAMES, r.stdout

