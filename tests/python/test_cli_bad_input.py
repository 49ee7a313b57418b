"""Bad input to every CLI command: a one-line error naming the file, exit 2, no traceback, no partial file.

Every command of `wetclutch --help` (lut, reference, vectors, replay, identify, bench, convert) gets
binary junk, an empty file, NaN and infinite columns, a missing file and a directory where a file is
expected. After a failure the output directory must hold exactly what it held before (earlier outputs
intact, no partial, no temporary file). Output faults (an unwritable directory, an output path under a
regular file, a full disk) and convert's malformed lines: test_cli_output_faults.py; the reference's
input rules: test_reference_rules.py.
"""
from __future__ import annotations

import os
import random
import re
import subprocess
import sys
from pathlib import Path

import pytest

from cli_support import ENGAGEMENT_LOG, ROOT, TABLE1, assert_one_line_error, run, snapshot, temporaries


# binary junk: not UTF-8 from its first byte, control characters, no line structure to speak of
JUNK = b"\xff\xfe\x00\x01" + bytes(random.Random(10).randrange(256) for _ in range(4000))
MEASUREMENT_HEADER = ("t_s,slip_rpm,force_N,torque_Nm,theta_clutch_degC,theta_oil_degC,theta_housing_degC,"
                      "torque_request_Nm")


def toml_with(value: str) -> str:
    text = TABLE1.read_text()
    new, count = re.subn(r"(^youngs_modulus *= \{ value = )[^,]+", rf"\g<1>{value}", text, count=1, flags=re.M)
    assert count == 1
    return new


def write_measurement(path: Path, rows: int = 40, force: str | None = None) -> None:
    lines = [MEASUREMENT_HEADER]
    for k in range(rows):
        lines.append(f"{k * 0.01:.2f},100,{force or 903},50,40,40,40,0")
    path.write_text("\n".join(lines) + "\n")


def mini_campaign(root: Path) -> Path:
    """An index and one measurement file: enough to reach the reading of the data (not to identify)."""
    (root / "table2").mkdir(parents=True)
    (root / "table2" / "index.csv").write_text("id,force_N,slip_rpm,file\nrun1,903,100,run1.csv\n")
    write_measurement(root / "table2" / "run1.csv")
    return root


# Contents of NaN/inf "columns" per input kind.
def nan_content(kind: str, value: str) -> str:
    if kind == "toml":
        return toml_with(value)
    if kind == "torque":
        return f"slip_rpm,theta_degC,force_N\n750,65,{value}\n300,40,{value}\n"
    if kind == "inverse":
        return f"slip_rpm,theta_degC,torque_Nm\n{value},90,150\n{value},65,40\n"
    if kind == "thermal":
        return (f"t_s,slip_rpm,torque_Nm,theta_oil_degC,theta_housing_degC\n0,750,150,{value},38\n"
                f"0.001,750,150,{value},38\n")
    if kind == "log":
        return f"({value}) vcan0 110#0000000000000000\n({value}) vcan0 111#0000000000000000\n"
    if kind == "asc":
        return ("date Mon Jan 12 13:46:40.000 2026\nbase hex  timestamps absolute\ninternal events logged\n"
                "Begin Triggerblock Mon Jan 12 13:46:40.000 2026\n"
                f" {value} 1  111             Rx   d 8 00 00 00 00 00 00 00 00\nEnd TriggerBlock\n")
    raise AssertionError(kind)


# command -> (suffix of its bad input, its kind for nan_content, argv builder(bad, out, good))
COMMANDS = {
    "lut": (".toml", "toml", lambda bad, out, g: ["lut", bad, "--out", out]),
    "vectors": (".toml", "toml", lambda bad, out, g: ["vectors", bad, "--out", out]),
    "bench": (".toml", "toml", lambda bad, out, g: ["bench", "engagement", "--slip", "250", "--true", bad,
                                                    "--out", out]),
    "reference-calibration": (".toml", "toml", lambda bad, out, g: ["reference", "torque", "-c", bad, "-i",
                                                                    g["torque_csv"], "-o", out / "out.csv"]),
    "reference-torque": (".csv", "torque", lambda bad, out, g: ["reference", "torque", "-i", bad]),
    "reference-inverse": (".csv", "inverse", lambda bad, out, g: ["reference", "inverse", "-i", bad]),
    "reference-thermal": (".csv", "thermal", lambda bad, out, g: ["reference", "thermal", "-i", bad]),
    "replay": (".log", "log", lambda bad, out, g: ["replay", "--analyse-only", bad, "--out", out]),
    "replay-calibration": (".toml", "toml", lambda bad, out, g: ["replay", "--analyse-only", ENGAGEMENT_LOG,
                                                                 "-c", bad, "--out", out]),
    "convert-asc": (".asc", "asc", lambda bad, out, g: ["convert", bad, out / "out.log"]),
    "convert-blf": (".blf", None, lambda bad, out, g: ["convert", bad, out / "out.log"]),
    "convert-mdf4": (".log", "log", lambda bad, out, g: ["convert", "--to", "mdf4", bad, out / "out.mf4"]),
    "identify-calibration": (".toml", "toml", lambda bad, out, g: ["identify", "mu", g["campaign"], "-c", bad,
                                                                   "--out", out, "--jobs", "1", "--no-plots"]),
    "identify-true": (".toml", "toml", lambda bad, out, g: ["identify", "mu", g["campaign"], "--true", bad,
                                                            "--out", out, "--jobs", "1", "--no-plots"]),
    "shift-plant": (".toml", "toml", lambda bad, out, g: ["shift", "--plant", bad, "--out", out]),
}
KINDS = ("junk", "empty", "nan", "inf", "missing", "directory")
CASES = [(c, k) for c in COMMANDS for k in KINDS if not (COMMANDS[c][1] is None and k in ("nan", "inf"))]


@pytest.fixture
def good(tmp_path):
    g = tmp_path / "good"
    g.mkdir()
    (g / "torque.csv").write_text("slip_rpm,theta_degC,force_N\n750,65,1188\n")
    return {"torque_csv": g / "torque.csv", "campaign": mini_campaign(g / "campaign")}


def make_bad(tmp_path: Path, kind: str, suffix: str, content_kind: str | None) -> Path:
    path = tmp_path / f"bad_{kind}{suffix}"
    if kind == "junk":
        path.write_bytes(JUNK)
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind in ("nan", "inf"):
        path.write_text(nan_content(content_kind, kind))
    elif kind == "directory":
        path.mkdir()
    return path


@pytest.mark.parametrize("command, kind", CASES, ids=[f"{c}-{k}" for c, k in CASES])
def test_bad_input(command, kind, tmp_path, good, capsys):
    suffix, content_kind, argv = COMMANDS[command]
    bad = make_bad(tmp_path, kind, suffix, content_kind)
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.txt").write_text("an earlier output")
    before = snapshot(out)
    code, stdout, err = run(argv(bad, out, good), capsys)
    assert_one_line_error(code, err, bad)
    if command.startswith("reference"):
        assert stdout == ""                  # no partial CSV on stdout either
    assert snapshot(out) == before
    assert temporaries(tmp_path) == []


# identify reads a directory: the bad file is one of its CSVs (a measurement, the index, viscosity.csv)
IDENTIFY_DATA = [
    ("measurement", "junk"), ("measurement", "empty"), ("measurement", "nan"), ("measurement", "inf"),
    ("measurement", "header only"), ("measurement", "directory"), ("measurement", "missing"),
    ("index", "junk"), ("index", "empty"), ("viscosity", "junk"), ("viscosity", "empty"), ("viscosity", "nan"),
    ("data_dir", "junk"), ("data_dir", "missing"),
]


@pytest.mark.parametrize("which, kind", IDENTIFY_DATA, ids=[f"{w}-{k}" for w, k in IDENTIFY_DATA])
def test_identify_bad_data(which, kind, tmp_path, capsys):
    data = mini_campaign(tmp_path / "data")
    step = "mu"
    target = {"measurement": data / "table2" / "run1.csv", "index": data / "table2" / "index.csv",
              "viscosity": data / "table2" / "viscosity.csv", "data_dir": tmp_path / "not_a_dir"}[which]
    if which == "viscosity":
        step = "viscosity"
    named = target
    if kind == "junk":
        target.write_bytes(JUNK)
    elif kind == "empty":
        target.write_bytes(b"")
    elif kind in ("nan", "inf"):
        if which == "viscosity":
            target.write_text("theta_degC,viscosity_Pa_s\n" + "".join(f"{t},{kind}\n" for t in range(10, 130, 10)))
        else:
            write_measurement(target, force=kind)
    elif kind == "header only":
        target.write_text(MEASUREMENT_HEADER + "\n")
    elif kind == "directory":
        target.unlink()
        target.mkdir()
    elif kind == "missing" and which == "measurement":
        target.unlink()
        named = data / "table2" / "index.csv"   # the index lists only missing files: the index is named
    out = tmp_path / "out"
    code, _, err = run(["identify", step, data if which != "data_dir" else target, "--out", out, "--jobs", "1",
                        "--no-plots"], capsys)
    assert_one_line_error(code, err, named)
    assert not out.exists()
    assert temporaries(tmp_path) == []


def test_all_nan_force_column_names_file_and_column(tmp_path, capsys):
    """Was a ValueError traceback from np.bincount (identify/signals.py) on a force column of NaN."""
    data = mini_campaign(tmp_path / "data")
    write_measurement(data / "table2" / "run1.csv", force="nan")
    code, _, err = run(["identify", "mu", data, "--out", tmp_path / "out", "--jobs", "1"], capsys)
    assert_one_line_error(code, err, data / "table2" / "run1.csv", "force_N")


@pytest.mark.parametrize("command", ["lut", "vectors", "bench", "reference", "replay", "convert", "convert-mdf4",
                                     "identify"])
def test_junk_in_a_subprocess_has_no_traceback(command, tmp_path):
    """The real stderr of the real program (no in-process shortcut)."""
    suffix = {"reference": ".csv", "replay": ".log", "convert": ".asc", "convert-mdf4": ".log"}.get(command, ".toml")
    bad = tmp_path / f"junk{suffix}"
    bad.write_bytes(JUNK)
    out = tmp_path / "out"
    argv = {"lut": ["lut", bad, "--out", out], "vectors": ["vectors", bad, "--out", out],
            "bench": ["bench", "engagement", "--true", bad, "--out", out],
            "reference": ["reference", "torque", "-i", bad],
            "replay": ["replay", "--analyse-only", bad, "--out", out],
            "convert": ["convert", bad, out / "x.log"],
            "convert-mdf4": ["convert", "--to", "mdf4", bad, out / "x.mf4"],
            "identify": ["identify", "mu", tmp_path, "--out", out]}[command]   # the junk CSV is in the data dir
    if command == "identify":
        bad.rename(tmp_path / "junk.csv")
        bad = tmp_path / "junk.csv"
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", *map(str, argv)], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "tools")}, timeout=300)
    assert_one_line_error(r.returncode, r.stderr, bad)
    assert not out.exists()
