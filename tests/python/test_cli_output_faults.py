"""Output faults of every CLI command that writes: an unwritable output directory, an output path under a
regular file and a full disk give a one-line error naming the output file, exit 2, no traceback, and leave
the output directory as it was (earlier outputs intact, no partial, no temporary file).

The disk faults are simulated in-process (cli.main with builtins.open, io.open, os.open and os.mkdir
patched for the paths under the output directory: no root, no tmpfs): a full disk raises ENOSPC once a
byte budget is spent, like write(2) does (the OS names no file), an unwritable directory raises EACCES on
creating anything in it. Also: the atomic writer itself, and `convert` names a malformed ASC line and
warns about out-of-order timestamps.
"""
from __future__ import annotations

import builtins
import errno
import io
import os
import re
import shutil
from pathlib import Path

import pytest

from cli_support import ENGAGEMENT_LOG, TABLE1, assert_one_line_error, fake_capture, run, snapshot, temporaries
from wetclutch.generate import vectors
from wetclutch.util import atomic, canlog


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


# command -> argv builder(out, fixtures); out is the directory the command writes in
WRITERS = {
    "lut": lambda out, f: ["lut", TABLE1, "--out", out],
    "vectors": lambda out, f: ["vectors", TABLE1, "--out", out],
    "bench": lambda out, f: ["bench", "engagement", "--slip", "250", "--out", out],
    "identify": lambda out, f: ["identify", "mu", f["campaign"], "--out", out, "--jobs", "1"],   # PNGs too
    "convert": lambda out, f: ["convert", f["asc"], out / "bench.log"],
    "convert-mdf4": lambda out, f: ["convert", "--to", "mdf4", ENGAGEMENT_LOG, out / "bench.mf4"],
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
    if command == "vectors":   # the faults are in the writing: its 20 s of reference tables once, not in each run
        real, texts = vectors.header_text, {}

        def once(cal, command_line):
            key = (str(cal.path), command_line)
            if key not in texts:
                texts[key] = real(cal, command_line)
            return texts[key]
        monkeypatch.setattr(vectors, "header_text", once)
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
