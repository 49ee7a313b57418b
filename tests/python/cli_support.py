"""What the command-line fault tests share (test_cli_bad_input.py, test_cli_output_faults.py,
test_reference_rules.py, test_mdf.py): cli.main in-process, the one-line error they all expect, a directory's
snapshot, a made-up replay capture."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from wetclutch import cli
from wetclutch.util import canlog


ROOT = Path(__file__).resolve().parents[2]
TABLE1 = ROOT / "tools" / "calibrations" / "table1.toml"
ENGAGEMENT_LOG = ROOT / "hil" / "logs" / "engagement_250rpm.log"


def run(argv, capsys) -> tuple[int, str, str]:
    """cli.main in-process: (exit code, stdout, stderr). An exception escaping main fails the test with its
    traceback, which is what the user would have seen."""
    try:
        code = cli.main([str(a) for a in argv])
    except SystemExit as e:   # argparse usage errors
        code = e.code
    out, err = capsys.readouterr()
    return code, out, err


def snapshot(directory: Path) -> dict[str, str]:
    """Every file under directory (relative path -> content hash); {} if it does not exist."""
    if not directory.exists():
        return {}
    return {str(p.relative_to(directory)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(directory.rglob("*")) if p.is_file()}


def temporaries(root: Path) -> list[str]:
    return [str(p) for p in root.rglob("*") if p.name.endswith(".tmp")]


def assert_one_line_error(code: int, err: str, *names) -> None:
    """Exit 2; the error is one line naming what is given (the lines before it, if any, are the command's
    progress messages, 'wetclutch <command>: ...' too); no traceback."""
    assert code == 2, err
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and all(line.startswith("wetclutch ") for line in lines), err
    for name in names:
        assert str(name) in lines[-1], (name, err)


def fake_capture(run_dir: Path, log: Path) -> None:
    """What `replay` finds in --out after a run on vcan, made up (plausible outputs, no TCU needed), for
    the analysis (--analyse-only --no-reference-check) to write its report from."""
    decoded = canlog.decode(canlog.read_log(log))
    steps = len(decoded[canlog.SENSORS]["_t"])
    torque = decoded[canlog.BENCH]["MeasuredTorque"]
    spec = canlog.database().get_message_by_name(canlog.COMMAND)
    status = {s.name: 0 for s in spec.signals if s.name.startswith("Status")}
    enc = canlog.Encoder()
    frames = []
    for k in range(steps):
        frames.append((k * 1e-3, enc.frame(canlog.COMMAND, VfsCurrent=100.0, PressureCommand=200.0, **status)))
        frames.append((k * 1e-3 + 1e-6, enc.frame(canlog.ESTIMATE, EstimatedClutchTemp=40.0, MuF=0.13,
                                                  ModelTorque=float(torque[min(k, torque.size - 1)]),
                                                  FilmThickness=5.0, LockState=0)))
    run_dir.mkdir(parents=True)
    canlog.write_log(run_dir / "frame1.log", frames)
    (run_dir / "frame1.json").write_text(json.dumps({
        "frames_in": 3 * steps, "frames_used": 3 * steps, "frames_out": 2 * steps, "rejected": 0,
        "rx_dropped_by_kernel": 0, "tx_errors": 0, "steps": steps}))
