"""The host's side of the UDS session against ``wc_tcu --uds`` (DESIGN 17): the run on vcan
(hil/uds_guest.sh through hil/vcan_run.sh); the tester is hil/uds_tester.py (udsoncan over
python-can-isotp)."""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def run_on_vcan(work: Path, tcu: Path) -> int:
    """hil/uds_guest.sh on work (input.log, cal.img, secret.key) on vcan: natively, in the serving guest
    (VCAN_SERVER) or in a guest of its own. Returns its exit code."""
    env = dict(os.environ, PATH=f"{ROOT / '.venv' / 'bin'}:{os.environ.get('PATH', '')}")
    cmd = ["bash", str(ROOT / "hil" / "vcan_run.sh"), "--rwdir", str(work), "--", "bash",
           str(ROOT / "hil" / "uds_guest.sh"), str(work), "--tcu", str(tcu)]
    return subprocess.run(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL).returncode
