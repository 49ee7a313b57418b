"""What the command-line fault tests share (test_cli_bad_input.py, test_cli_output_faults.py,
test_reference_rules.py): cli.main in-process, the one-line error they all expect, a directory's snapshot."""
from __future__ import annotations

import hashlib
from pathlib import Path

from wetclutch import cli


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
