"""Bad input to every CLI command: a one-line error naming the file, exit 2, no traceback, no partial file.

Every command of `wetclutch --help` (lut, reference, vectors, replay, identify, bench, convert) gets
binary junk, an empty file, NaN and infinite columns, a missing file and a directory where a file is
expected; every command that writes gets an unwritable output directory, an output path under a regular
file and a full disk. The disk faults are simulated in-process (cli.main with builtins.open, io.open,
os.open and os.mkdir patched for the paths under the output directory: no root, no tmpfs): a full disk
raises ENOSPC once a byte budget is spent, like write(2) does (the OS names no file), an unwritable
directory raises EACCES on creating anything in it. After a failure the output directory must hold
exactly what it held before (earlier outputs intact, no partial, no temporary file).

Also: `reference` applies the firmware's input rules row by row (status bits of model.py, the
firmware's safe outputs; against wc_eval where it is built), and `convert` names a malformed ASC line
and warns about out-of-order timestamps.
"""
from __future__ import annotations

import builtins
import errno
import hashlib
import io
import json
import os
import random
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from wetclutch import cli
from wetclutch.generate import lut
from wetclutch.reference import evaluate as reference, model
from wetclutch.util import atomic, canlog

ROOT = Path(__file__).resolve().parents[2]
TABLE1 = ROOT / "tools" / "calibrations" / "table1.toml"
ENGAGEMENT_LOG = ROOT / "hil" / "logs" / "engagement_250rpm.log"
# binary junk: not UTF-8 from its first byte, control characters, no line structure to speak of
JUNK = b"\xff\xfe\x00\x01" + bytes(random.Random(10).randrange(256) for _ in range(4000))
MEASUREMENT_HEADER = ("t_s,slip_rpm,force_N,torque_Nm,theta_clutch_degC,theta_oil_degC,theta_housing_degC,"
                      "torque_request_Nm")


# --------------------------------------------------------------------------- helpers

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


@pytest.mark.parametrize("command", ["lut", "vectors", "bench", "reference", "replay", "convert", "identify"])
def test_junk_in_a_subprocess_has_no_traceback(command, tmp_path):
    """The real stderr of the real program (no in-process shortcut)."""
    suffix = {"reference": ".csv", "replay": ".log", "convert": ".asc"}.get(command, ".toml")
    bad = tmp_path / f"junk{suffix}"
    bad.write_bytes(JUNK)
    out = tmp_path / "out"
    argv = {"lut": ["lut", bad, "--out", out], "vectors": ["vectors", bad, "--out", out],
            "bench": ["bench", "engagement", "--true", bad, "--out", out],
            "reference": ["reference", "torque", "-i", bad],
            "replay": ["replay", "--analyse-only", bad, "--out", out],
            "convert": ["convert", bad, out / "x.log"],
            "identify": ["identify", "mu", tmp_path, "--out", out]}[command]   # the junk CSV is in the data dir
    if command == "identify":
        bad.rename(tmp_path / "junk.csv")
        bad = tmp_path / "junk.csv"
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", *map(str, argv)], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "tools")}, timeout=300)
    assert_one_line_error(r.returncode, r.stderr, bad)
    assert not out.exists()


# --------------------------------------------------------------------------- output faults

class Disk:
    """builtins.open, io.open, os.open and os.mkdir patched for the paths under root.

    full disk (budget): a write beyond the budget (bytes or characters, over all files) raises ENOSPC
    without a file name, as write(2) does; unwritable (deny): creating a file or directory in root raises
    EACCES naming the path, as open(2) and mkdir(2) do."""

    def __init__(self, monkeypatch, root: Path, budget: float = float("inf"), deny: bool = False):
        self.root = str(root.resolve())
        self.budget = budget
        self.deny = deny
        self.used = 0
        real_open, real_os_open, real_mkdir = io.open, os.open, os.mkdir
        disk = self

        def inside(file) -> str | None:
            if isinstance(file, int):
                try:
                    name = os.readlink(f"/proc/self/fd/{file}")
                except OSError:
                    return None
            else:
                name = os.path.abspath(os.fspath(file))
            return name if name.startswith(disk.root + os.sep) else None

        def fake_open(file, mode="r", *args, **kwargs):
            name = inside(file)
            writing = any(c in mode for c in "wax+")
            if name and writing and disk.deny and not isinstance(file, int):
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(file))
            f = real_open(file, mode, *args, **kwargs)
            return _Budgeted(f, disk) if name and writing else f

        def fake_os_open(path, flags, *args, **kwargs):
            if disk.deny and flags & os.O_CREAT and inside(path):
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
            return real_os_open(path, flags, *args, **kwargs)

        def fake_mkdir(path, *args, **kwargs):
            if disk.deny and inside(path) and not os.path.exists(path):
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
            return real_mkdir(path, *args, **kwargs)

        monkeypatch.setattr(builtins, "open", fake_open)
        monkeypatch.setattr(io, "open", fake_open)
        monkeypatch.setattr(os, "open", fake_os_open)
        monkeypatch.setattr(os, "mkdir", fake_mkdir)


class _Budgeted:
    def __init__(self, f, disk: Disk):
        self._f = f
        self._disk = disk

    def write(self, data):
        if self._disk.used + len(data) > self._disk.budget:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._disk.used += len(data)
        return self._f.write(data)

    def writelines(self, lines):
        for line in lines:
            self.write(line)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return self._f.__exit__(*exc)

    def __iter__(self):
        return iter(self._f)

    def __getattr__(self, name):
        return getattr(self._f, name)


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """A small synthetic Table 2 campaign that identifies (test_identify.py's generator)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("_identify_data", Path(__file__).with_name("test_identify.py"))
    generator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generator)
    return generator.make_campaign(tmp_path_factory.mktemp("campaign"), forces=(903.0, 1613.0), speeds=(100,),
                         temps=(20, 80), thermal=False)


@pytest.fixture(scope="module")
def asc_log(tmp_path_factory) -> Path:
    import can
    path = tmp_path_factory.mktemp("asc") / "bench.asc"
    with can.ASCWriter(str(path)) as writer:
        for m in canlog.read_log(ENGAGEMENT_LOG)[:300]:
            writer.on_message_received(can.Message(timestamp=m.timestamp, arbitration_id=m.arbitration_id,
                                                   data=bytes(m.data), is_extended_id=False, channel=0))
    return path


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


# command -> argv builder(out, fixtures); out is the directory the command writes in
WRITERS = {
    "lut": lambda out, f: ["lut", TABLE1, "--out", out],
    "vectors": lambda out, f: ["vectors", TABLE1, "--out", out],
    "bench": lambda out, f: ["bench", "engagement", "--slip", "250", "--out", out],
    "identify": lambda out, f: ["identify", "mu", f["campaign"], "--out", out, "--jobs", "1"],   # PNGs too
    "convert": lambda out, f: ["convert", f["asc"], out / "bench.log"],
    "reference": lambda out, f: ["reference", "inverse", "-i", f["csv"], "-o", out / "inverse.csv"],
    "replay": lambda out, f: ["replay", "--analyse-only", "--no-reference-check", ENGAGEMENT_LOG, "--out", out],
}
@pytest.fixture
def writer_inputs(tmp_path, request):
    csv_in = tmp_path / "inverse_in.csv"
    csv_in.write_text("slip_rpm,theta_degC,torque_Nm\n750,90,150\n300,65,40\n0,40,0\n")
    inputs = {"csv": csv_in}
    if "identify" in request.node.name:
        inputs["campaign"] = request.getfixturevalue("campaign")
    if "convert" in request.node.name:
        inputs["asc"] = request.getfixturevalue("asc_log")
    return inputs


def _prepare_out(command: str, out: Path) -> None:
    out.mkdir()
    if command == "replay":   # the captures of the run on vcan are the analysis' input
        fake_capture(out / ENGAGEMENT_LOG.stem, ENGAGEMENT_LOG)


@pytest.mark.parametrize("command", sorted(WRITERS))
def test_full_disk(command, tmp_path, writer_inputs, monkeypatch, capsys):
    """A full disk at the first byte, half way and near the end: the message names the output file (not a temporary,
    not 'None') and the reason; the directory holds what it held before, earlier outputs intact."""
    out = tmp_path / "out"
    _prepare_out(command, out)
    argv = WRITERS[command](out, writer_inputs)
    inputs = snapshot(out)
    with monkeypatch.context() as m:   # a good run first, counting what it writes
        disk = Disk(m, out)
        code, _, err = run(argv, capsys)
    assert code in (0, 1), err          # 1: replay's made-up capture misses a target; the report is written
    total = disk.used
    written = {name for name, digest in snapshot(out).items() if inputs.get(name) != digest}
    assert total > 0 and written
    for name in written:                # the earlier outputs, to be left as they are
        (out / name).write_bytes(b"previous " + name.encode())
    before = snapshot(out)
    for budget in (0, total // 2, total * 9 // 10):   # (identify: timings make the sizes vary a little)
        with monkeypatch.context() as m:
            Disk(m, out, budget=budget)
            code, _, err = run(argv, capsys)
        assert_one_line_error(code, err, "No space left on device")
        named = re.search(r": (\S+): No space left on device", err)
        assert named, err
        path = Path(named.group(1))
        assert not path.name.endswith(".tmp") and path.is_relative_to(out), err
        assert str(path.relative_to(out)) in written, (err, written)
        assert snapshot(out) == before, budget
        assert temporaries(tmp_path) == []


@pytest.mark.parametrize("command", sorted(WRITERS))
def test_unwritable_output_directory(command, tmp_path, writer_inputs, monkeypatch, capsys):
    out = tmp_path / "out"
    _prepare_out(command, out)
    before = snapshot(out)
    with monkeypatch.context() as m:
        Disk(m, out, deny=True)
        code, _, err = run(WRITERS[command](out, writer_inputs), capsys)
    assert_one_line_error(code, err, out, "Permission denied")
    assert snapshot(out) == before
    assert temporaries(tmp_path) == []


@pytest.mark.parametrize("command", sorted(WRITERS))
def test_output_directory_is_a_file(command, tmp_path, writer_inputs, capsys):
    out = tmp_path / "out"
    out.write_text("a file, not a directory")
    code, _, err = run(WRITERS[command](out, writer_inputs), capsys)
    assert_one_line_error(code, err, out)
    assert out.read_text() == "a file, not a directory"
    assert temporaries(tmp_path) == []


def test_identify_all_or_nothing_message(tmp_path, campaign, monkeypatch, capsys):
    """The reported defect: a full disk after calibration.toml left it and a 0-byte figures.json behind,
    with 'None: No space left on device'."""
    out = tmp_path / "out"
    with monkeypatch.context() as m:
        disk = Disk(m, tmp_path)
        assert run(["identify", "mu", campaign, "--out", out, "--jobs", "1", "--no-plots"], capsys)[0] == 0
    cal_bytes = (out / "calibration.toml").stat().st_size + (out / "exclusions.csv").stat().st_size
    shutil.rmtree(out)
    with monkeypatch.context() as m:
        Disk(m, tmp_path, budget=cal_bytes + 10)
        code, _, err = run(["identify", "mu", campaign, "--out", out, "--jobs", "1", "--no-plots"], capsys)
    assert_one_line_error(code, err, f"{out / 'figures.json'}: No space left on device")
    assert "None" not in err
    assert snapshot(out) == {}
    assert disk.used > 0


# --------------------------------------------------------------------------- the atomic writer

def test_staged_all_or_nothing(tmp_path):
    (tmp_path / "a.txt").write_text("old a")
    with pytest.raises(RuntimeError):
        with atomic.Staged() as out:
            out.write_text(tmp_path / "a.txt", "new a")
            atomic.write_text(tmp_path / "b.txt", "new b")   # joins the block
            raise RuntimeError("half way")
    assert sorted(os.listdir(tmp_path)) == ["a.txt"] and (tmp_path / "a.txt").read_text() == "old a"
    with atomic.Staged() as out:
        out.write_text(tmp_path / "a.txt", "new a")
        with atomic.open_atomic(tmp_path / "b.txt") as f:
            f.write("new b")
        assert (tmp_path / "a.txt").read_text() == "old a" and not (tmp_path / "b.txt").exists()   # not yet
    assert (tmp_path / "a.txt").read_text() == "new a" and (tmp_path / "b.txt").read_text() == "new b"
    assert temporaries(tmp_path) == []


def test_atomic_mode_and_named_error(tmp_path):
    mask = os.umask(0o022)
    try:
        atomic.write_text(tmp_path / "x.txt", "x")
    finally:
        os.umask(mask)
    assert (tmp_path / "x.txt").stat().st_mode & 0o777 == 0o644   # as open() makes it, not mkstemp's 0600
    with pytest.raises(OSError) as e:
        atomic.write_text(tmp_path / "no" / "x.txt", "x")
    assert e.value.filename == str(tmp_path / "no" / "x.txt") and e.value.strerror == "No such file or directory"
    (tmp_path / "d").mkdir()
    with pytest.raises(OSError) as e:
        atomic.write_text(tmp_path / "d", "a directory in the way")
    assert e.value.filename == str(tmp_path / "d")
    assert temporaries(tmp_path) == []


# --------------------------------------------------------------------------- convert

def _asc_lines(asc_log: Path) -> list[str]:
    return asc_log.read_text().splitlines()


def test_convert_garbage_line_is_an_error(asc_log, tmp_path, capsys):
    lines = _asc_lines(asc_log)
    frame = next(i for i, line in enumerate(lines) if " Rx " in line) + 5
    for garbage in ("this is garbage", "   12.5 garbage line here", "   0.004000 1 111 Xx d 8 00", "   0.0"):
        bad = tmp_path / "bad.asc"
        bad.write_text("\n".join(lines[:frame] + [garbage] + lines[frame:]) + "\n")
        out = tmp_path / "out.log"
        out.write_text("previous")
        code, _, err = run(["convert", bad, out], capsys)
        assert_one_line_error(code, err, bad, f"line {frame + 1}")
        assert out.read_text() == "previous"
        assert temporaries(tmp_path) == []


def test_convert_accepts_and_counts_other_events(asc_log, tmp_path, capsys):
    lines = _asc_lines(asc_log)
    frame = next(i for i, line in enumerate(lines) if " Rx " in line) + 5
    events = ["   0.004000 1 Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%",
              "   0.004001 CAN 1 Status:chip status error active", "// a comment"]
    asc = tmp_path / "events.asc"
    asc.write_text("\n".join(lines[:frame] + events + lines[frame:]) + "\n")
    code, stdout, err = run(["convert", asc, tmp_path / "out.log"], capsys)
    assert code == 0, err
    assert "300 frames" in stdout and "2 non-CAN event line(s)" in stdout


def test_convert_warns_out_of_order(asc_log, tmp_path, capsys):
    lines = _asc_lines(asc_log)
    rx = [i for i, line in enumerate(lines) if " Rx " in line]
    lines[rx[10]], lines[rx[20]] = lines[rx[20]], lines[rx[10]]
    asc = tmp_path / "order.asc"
    asc.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out.log"
    code, stdout, err = run(["convert", asc, out], capsys)
    assert code == 0, err
    assert "Traceback" not in err
    warned = [line for line in err.splitlines() if "out of order" in line]
    assert warned and str(asc) in warned[0] and f"line {rx[11] + 1}" in err, err   # the frame after the early one
    assert f"line {rx[20] + 1}" in err                                          # and the one moved back
    back = canlog.read_log(out)
    assert len(back) == 300
    stamps = [m.timestamp for m in back]
    assert any(b < a for a, b in zip(stamps, stamps[1:]))   # copied as is, in the file's order
    assert temporaries(tmp_path) == []


# --------------------------------------------------------------------------- reference: the firmware's rules

S = model


def _rows(cal, mode, rows):
    cols = {c: np.array([r[k] for r in rows], dtype=float) for k, c in enumerate(reference.INPUTS[mode])}
    return reference.MODES[mode](cal, cols)


def test_reference_torque_rejects_like_the_firmware(cal):
    rows = [(750, 65, 1188), (750, 65, -1000), (1e300, 1e300, 1e300), (750, np.nan, 1188), (750, 65, np.inf),
            (-10001, 65, 1188), (750, 251, 1188), (750, -41, 1188), (750, 65, 2e5)]
    r = _rows(cal, "torque", rows)
    assert list(r["status"]) == [0, S.STATUS_FORCE_INVALID,
                                 S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID | S.STATUS_FORCE_INVALID,
                                 S.STATUS_THETA_INVALID, S.STATUS_FORCE_INVALID, S.STATUS_SLIP_INVALID,
                                 S.STATUS_THETA_INVALID, S.STATUS_THETA_INVALID, S.STATUS_FORCE_INVALID]
    assert S.STATUS_FORCE_INVALID == 0x20 and S.STATUS_INPUT_INVALID == 0xF8   # include/wetclutch/wc_status.h
    assert r["torque_Nm"][0] == pytest.approx(154.7, rel=5e-4)
    rejected = slice(1, None)
    for name in ("torque_Nm", "coulomb_Nm", "viscous_Nm", "mu_f"):
        assert np.all(r[name][rejected] == 0.0), name            # was -72 Nm for -1000 N
    first_node_um = lut.build_table(cal).hbar_m[0] * 1e6          # the open clutch's film
    assert np.all(r["hbar_um"][rejected] == pytest.approx(first_node_um, rel=1e-12))
    for name in r:
        assert np.all(np.isfinite(r[name])), name


def test_reference_inverse_rejects_like_the_firmware(cal):
    rows = [(750, 90, 150), (750, 90, -1000), (1e300, 1e300, 1e300), (np.nan, 90, 150), (750, 90, np.nan),
            (20000, 90, 150), (750, 90, 1e6)]
    r = _rows(cal, "inverse", rows)
    assert list(r["status"]) == [0, S.STATUS_TORQUE_INVALID,
                                 S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID | S.STATUS_TORQUE_INVALID,
                                 S.STATUS_SLIP_INVALID, S.STATUS_TORQUE_INVALID, S.STATUS_SLIP_INVALID,
                                 S.STATUS_TORQUE_INVALID]
    preload_Pa = cal.return_spring_force / cal.piston_area
    assert np.all(r["force_N"][1:] == 0.0)
    assert np.all(r["pressure_kPa"][1:] == pytest.approx(preload_Pa * 1e-3))
    assert np.all(r["current_mA"][1:] == pytest.approx(preload_Pa / cal.vfs_gain))
    # a solenoid whose minimum current is above the preload's: the safe current is clamped, and says so
    high_min = cal.with_values(vfs_current_min=100.0)
    r = _rows(high_min, "inverse", [(750, 90, -1000)])
    assert int(r["status"][0]) == S.STATUS_TORQUE_INVALID | S.STATUS_CURRENT_CLAMPED
    assert float(r["current_mA"][0]) == 100.0 and float(r["force_N"][0]) == 0.0


def test_reference_thermal_holds_the_state_on_rejected_rows(cal):
    good = [(0.000, 750, 150, 40, 38), (0.001, 750, 150, 40, 38), (0.002, 750, 150, 40, 38)]
    bad = [(0.000, 750, 150, 40, 38), (0.001, 750, 1e38, 40, 38), (0.002, 750, 150, np.nan, 38),
           (0.003, 750, 150, 40, 38), (0.004, 750, 150, 40, 38)]
    g = _rows(cal, "thermal", good)
    b = _rows(cal, "thermal", bad)
    assert list(b["status"]) == [0, S.STATUS_POWER_INVALID, S.STATUS_THETA_INVALID, 0, 0]
    # the rejected rows change nothing: the accepted ones see the series without them
    assert b["theta_degC"][0] == g["theta_degC"][0] and b["theta_degC"][1] == g["theta_degC"][1]
    assert b["theta_degC"][2] == b["theta_degC"][3] == g["theta_degC"][1]
    assert b["theta_degC"][4] == g["theta_degC"][2]


def test_reference_cli_rejects_like_wc_eval(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,1188\n\n750,65,-1000\n1e300,1e300,1e300\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(["reference", "torque", "-i", src, "-o", out], capsys)
    assert_one_line_error(code, err, src, "line 4", "status 0x20", "force_N not within 0..100000 N",
                          "2 rows rejected")
    assert not out.exists() and stdout == ""
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,nan\n")      # NaN: not a number the firmware gets
    code, stdout, err = run(["reference", "torque", "-i", src], capsys)
    assert_one_line_error(code, err, src, "line 2", "not finite")


def test_reference_cli_keep_rejected(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,1188\n750,65,-1000\n1e300,1e300,1e300\n750,nan,1188\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(["reference", "torque", "-i", src, "-o", out, "--keep-rejected"], capsys)
    assert code == 0 and "3 row(s) rejected" in err and "line 3" in err, err
    lines = out.read_text().splitlines()
    assert lines[0] == "torque_Nm,coulomb_Nm,viscous_Nm,hbar_um,mu_f,status"
    status = [int(line.split(",")[-1]) for line in lines[1:]]
    assert status == [0, S.STATUS_FORCE_INVALID, S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID
                      | S.STATUS_FORCE_INVALID, S.STATUS_THETA_INVALID]
    assert all(line.startswith("0,0,0,") and line.split(",")[4] == "0" for line in lines[2:])


def _wc_eval() -> Path | None:
    path = Path(os.environ.get("WC_EVAL") or ROOT / "build" / "host-debug" / "src" / "host" / "wc_eval")
    path = path if path.is_absolute() else ROOT / path
    return path if path.is_file() and os.access(path, os.X_OK) else None


BOUNDARY = {
    "torque": [(10000, 65, 100), (-10000, 65, 100), (10000.02, 65, 100), (10000.1, 65, 100), (10001, 65, 100),
               (750, -40, 100), (750, -40.00001, 100), (750, 250, 100), (750, 250.0001, 100), (750, 65, 0),
               (750, 65, -0.0), (750, 65, -1e-30), (750, 65, -1e-50), (750, 65, 1e5), (750, 65, 100000.004),
               (750, 65, 100000.01), (750, 65, 3.4e38), (750, 65, 3.5e38), (1e300, 1e300, 1e300),
               (750, 65, -1000)],
    "inverse": [(750, 90, 0), (750, 90, -0.0), (750, 90, -1e-30), (750, 90, 1e5), (750, 90, 100000.01),
                (750, 90, -1000), (10000.1, 90, 150), (10001, 90, 150), (750, 250.0001, 150),
                (1e300, 1e300, 1e300)],
    "thermal": [(0.001, 750, 1e34, 40, 38), (0.001, 750, 1e38, 40, 38), (0.001, 3e38, 2, 40, 38),
                (0.001, 750, 150, 250.0001, 38), (0.001, 750, 150, 40, -40.0001), (0.001, 1e300, 0, 40, 38)],
}


@pytest.mark.skipif(_wc_eval() is None, reason="wc_eval not built (cmake --build build/host-debug) or WC_EVAL")
@pytest.mark.parametrize("mode", sorted(BOUNDARY))
def test_reference_status_matches_wc_eval(mode, cal):
    """On each side of every limit, the reference accepts what wc_eval accepts and gives the status wc_eval
    reports for what it rejects."""
    header = ",".join(reference.INPUTS[mode])
    rows = BOUNDARY[mode]
    if mode == "thermal":   # a first row to start the observer, then the row under test one period later
        rows_in = [[(0.0, 750, 150, 40, 38), r] for r in rows]
    else:
        rows_in = [[r] for r in rows]
    for row_set in rows_in:
        text = header + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in row_set) + "\n"
        r = subprocess.run([str(_wc_eval()), mode], input=text, capture_output=True, text=True, timeout=30)
        got = _rows(cal, mode, row_set)["status"][-1] & S.STATUS_INPUT_INVALID
        rejected = re.search(r"status 0x([0-9a-f]+)", r.stderr)
        want = int(rejected.group(1), 16) & S.STATUS_INPUT_INVALID if rejected else 0
        assert r.returncode == (1 if rejected else 0), r.stderr
        assert got == want, (row_set[-1], r.stderr)
