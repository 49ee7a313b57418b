"""The host's side of the XCP session against ``wc_tcu --xcp`` (DESIGN 13): the A2L read by pya2ldb, the
plan the guest's master follows (hil/xcp_master.py: addresses and the bytes the image holds at each
characteristic), the device secret of the XCP seed & key (wc_tcu --secret-file), and the run on vcan
(hil/xcp_guest.sh through hil/vcan_run.sh)."""
from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

from ..calibration import image_layout
from ..util import image as image_format

ROOT = Path(__file__).resolve().parents[3]


def read_a2l(path: Path) -> dict:
    """Characteristics, measurements and memory segments of the A2L as pya2ldb reads them:
    name -> (address, record layout, type), name -> (address, data type), name -> (address, size)."""
    import pya2l
    from pya2l import model
    session = pya2l.import_a2l(str(path), in_memory=True, progress_bar=False, loglevel="ERROR")
    chars = {c.name: (int(c.address), c.deposit, c.type) for c in session.query(model.Characteristic).all()}
    meas = {m.name: (int(m.ecu_address.address), m.datatype) for m in session.query(model.Measurement).all()}
    segments = {s.name: (int(s.address), int(s.size)) for s in session.query(model.MemorySegment).all()}
    return {"characteristics": chars, "measurements": meas, "segments": segments}


def write_plan(a2l: Path, image: Path, out: Path) -> dict:
    """The master's plan: each characteristic's A2L address and the 4 bytes the image holds there (an
    array's first element), each measurement's address, the memory segments."""
    desc = read_a2l(a2l)
    payload = image_format.read_image(Path(image).read_bytes(), image_layout.MAGIC, image_layout.VERSION,
                                      image_layout.payload_bytes(), what=str(image))
    base, size = desc["segments"]["calibration"]
    chars = {name: (address, payload[address - base:address - base + 4].hex())
             for name, (address, _deposit, _kind) in desc["characteristics"].items()
             if base <= address < base + size}   # the calibration page's (the gearbox region's: a transmission's)
    plan = {"characteristics": chars, "measurements": desc["measurements"], "segments": desc["segments"]}
    Path(out).write_text(json.dumps(plan, indent=1))
    return plan


def write_secret(path: Path, secret_bytes: int = 32) -> bytes:
    """A fresh device secret (wc_tcu --secret-file: 16..1024 bytes), written owner-only."""
    secret = os.urandom(secret_bytes)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(secret)
    return secret


def run_on_vcan(work: Path, tcu: Path, daq_samples: int = 5000) -> int:
    """hil/xcp_guest.sh on work (input.log, cal.img, plan.json; secret.bin written here when missing) on
    vcan: natively, in the serving guest (VCAN_SERVER) or in a guest of its own. Returns its exit code."""
    if not (Path(work) / "secret.bin").is_file():
        write_secret(Path(work) / "secret.bin")
    env = dict(os.environ, PATH=f"{ROOT / '.venv' / 'bin'}:{os.environ.get('PATH', '')}")
    cmd = ["bash", str(ROOT / "hil" / "vcan_run.sh"), "--rwdir", str(work), "--", "bash",
           str(ROOT / "hil" / "xcp_guest.sh"), str(work), "--tcu", str(tcu), "--daq-samples", str(daq_samples)]
    return subprocess.run(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL).returncode
