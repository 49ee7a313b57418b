"""MDF4 output (issue 21, util/mdf.py): `wetclutch convert --to mdf4`, the HIL replay report's capture.mf4 and
the shift report's files, read back with asammdf and checked signal by signal against cantools' decode of the
same frames (hil/wetclutch.dbc); the convert command's bad input and unwritable outputs."""
from __future__ import annotations

import json
from datetime import timezone

import numpy as np
import pytest
from asammdf import MDF
from cantools.database.namedsignalvalue import NamedSignalValue

from cli_support import ENGAGEMENT_LOG, TABLE1, assert_one_line_error, fake_capture, run, temporaries
from wetclutch.util import canlog, mdf

# The DBC's enumerations (value names for every raw value of the valid range): stored with a value-to-text
# conversion. The other value names (SNA) make a status-string table: the name reads as NaN.
# The DBC's enumerations (a value table naming every raw value of the range, no scaling: Mode, LockState,
# AbortReason, Fallback, the transmission's ShiftType, Refusal, Role, Locked), read from the DBC itself.
ENUMS = {s.name for m in canlog.database().messages for s in m.signals
         if s.choices and s.scale == 1 and s.offset == 0 and s.minimum is not None
         and all(v in s.choices for v in range(int(s.minimum), int(s.maximum) + 1))}
assert {"Mode", "LockState", "AbortReason", "Fallback", "ShiftType", "Refusal", "Role", "Locked"} <= ENUMS


def assert_matches_dbc(path, messages) -> dict:
    """Every frame of the DBC in messages is in the file at path, signal by signal: one group per message
    (acquisition name), one channel per signal with the DBC's unit and comment, the raw samples the bus
    values and the physical ones cantools' decode, the time the timestamps minus the earliest (the header's
    start time). Returns {message: frames}."""
    db = canlog.database()
    frames: dict[str, list] = {}
    for m in messages:
        try:
            spec = db.get_message_by_frame_id(m.arbitration_id)
        except KeyError:
            continue
        if len(m.data) == spec.length and not m.is_extended_id:
            frames.setdefault(spec.name, []).append(m)
    t0 = min(m.timestamp for msgs in frames.values() for m in msgs)
    with MDF(path) as f:
        assert abs(f.header.start_time.astimezone(timezone.utc).timestamp() - t0) <= 1e-6   # ns in the file, float here
        groups = {g.channel_group.acq_name: i for i, g in enumerate(f.groups)}
        assert set(groups) == set(frames)
        for name, msgs in frames.items():
            spec = db.get_message_by_name(name)
            gi = groups[name]
            assert spec.comment in f.groups[gi].channel_group.comment
            assert [c.name for c in f.groups[gi].channels] == ["time"] + [s.name for s in spec.signals]
            msgs = sorted(msgs, key=lambda m: m.timestamp)
            # exact: the writer subtracts the same float64 t0 (and t - t0 is exact within a factor 2, Sterbenz)
            t = np.array([m.timestamp for m in msgs]) - t0
            raw = [spec.decode(bytes(m.data), decode_choices=False, scaling=False) for m in msgs]
            phys = [spec.decode(bytes(m.data), decode_choices=True, scaling=True) for m in msgs]
            for sig in spec.signals:
                got = f.get(sig.name, group=gi)
                assert got.unit == (sig.unit or ""), sig.name
                assert got.comment == (sig.comment or ""), sig.name
                assert np.array_equal(got.timestamps, t), sig.name
                assert np.array_equal(f.get(sig.name, group=gi, raw=True).samples, [r[sig.name] for r in raw]), sig.name
                values = [p[sig.name] for p in phys]
                if sig.name in ENUMS:
                    expect = [v.name.encode() if isinstance(v, NamedSignalValue) else mdf.UNDEFINED_TEXT.encode()
                              for v in values]
                    assert list(got.samples) == expect, sig.name
                    continue
                expect = np.array([np.nan if isinstance(v, NamedSignalValue) else float(v) for v in values])
                # exact, no tolerance: raw values stored as integers, the DBC's factor and offset as float64, and
                # asammdf computes factor * raw + offset as cantools does (the same IEEE operations)
                assert np.array_equal(got.samples.astype(float), expect, equal_nan=True), sig.name
                if sig.scale == 1 and sig.offset == 0 and not sig.choices:
                    assert got.samples.dtype.kind in "iu", sig.name    # counters, status bits, ms: integers
    return {name: len(msgs) for name, msgs in frames.items()}


def test_convert_bundled_log(tmp_path, capsys):
    out = tmp_path / "engagement.mf4"
    code, stdout, err = run(["convert", "--to", "mdf4", ENGAGEMENT_LOG, out], capsys)
    assert code == 0 and err == "", err
    messages = canlog.read_log(ENGAGEMENT_LOG)
    counts = assert_matches_dbc(out, messages)
    assert counts == {canlog.SENSORS: 2500, canlog.REQUEST: 2500, canlog.BENCH: 2500}
    assert stdout.startswith(f"wrote {out}: 7500 of 7500 frames over 2.499 s in 3 channel groups")
    assert temporaries(tmp_path) == []


@pytest.fixture
def every_frame_log(tmp_path):
    """Every frame of the DBC with random payloads (every raw value decodes; the enumerations' reserved values
    too), frames with SNA in every signal that has it, every enumeration's names, two frames of ids not in the
    DBC, one of a wrong length and one extended; a candump -L log, its messages."""
    db = canlog.database()
    rng = np.random.default_rng(21)
    frames = []
    t = 1.7e9                                    # a real capture's epoch seconds
    for k in range(200):
        for spec in db.messages:
            payload = rng.integers(0, 256, 8).astype(np.uint8).tobytes()
            frames.append((t + k * 1e-3 + spec.frame_id * 1e-7, canlog.can.Message(
                arbitration_id=spec.frame_id, is_extended_id=False, data=payload)))
    t_end = t + 0.2
    for spec in db.messages:
        named = {s.name: max(s.choices) for s in spec.signals if s.choices}
        for raw in range(8):                     # SNA (the largest value name) in every signal with names, and 0..7
            values = {s.name: named.get(s.name, 0) if raw == 0 else raw & ((1 << s.length) - 1) for s in spec.signals}
            data = spec.encode(values, scaling=False, strict=False)
            frames.append((t_end + raw * 1e-3, canlog.can.Message(arbitration_id=spec.frame_id, is_extended_id=False,
                                                                  data=data)))
    frames += [(t_end + 0.01, canlog.can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"\x01\x02")),
               (t_end + 0.011, canlog.can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b"")),
               (t_end + 0.012, canlog.can.Message(arbitration_id=0x110, is_extended_id=False, data=b"\x00" * 4)),
               (t_end + 0.013, canlog.can.Message(arbitration_id=0x110, is_extended_id=True, data=b"\x00" * 8))]
    path = tmp_path / "every_frame.log"
    canlog.write_log(path, frames)
    return path, canlog.read_log(path)


def test_every_signal_of_the_dbc(every_frame_log, tmp_path, capsys):
    log, messages = every_frame_log
    out = tmp_path / "every.mf4"
    code, stdout, err = run(["convert", "--to", "mdf4", log, out], capsys)
    assert code == 0, err
    counts = assert_matches_dbc(out, messages)
    db = canlog.database()
    assert set(counts) == {m.name for m in db.messages} and set(counts.values()) == {208}
    # the frames left out: one warning line, per id
    assert err.splitlines() == [f"wetclutch convert: warning: {log}: left out 3 frame(s) with an id not in"
                                " hil/wetclutch.dbc (0x110: 1, 0x7FF: 2); 1 frame(s) of a wrong length (0x110: 1)"]
    assert f"{208 * len(db.messages)} of {208 * len(db.messages) + 4} frames" in stdout
    with MDF(out) as f:    # the value names read as text (enumerations) and SNA as NaN, raw as the bus value
        g = next(i for i, gr in enumerate(f.groups) if gr.channel_group.acq_name == canlog.REQUEST)
        assert {b"Open", b"TorqueControl", b"Locked", b"Shift", b"undefined"} <= set(f.get("Mode", group=g).samples)
        g = next(i for i, gr in enumerate(f.groups) if gr.channel_group.acq_name == canlog.SENSORS)
        assert np.isnan(f.get("SlipSpeed", group=g).samples).sum() >= 1
        assert -32768 in f.get("SlipSpeed", group=g, raw=True).samples


def test_replay_report_writes_the_capture(tmp_path, capsys):
    """wetclutch replay --analyse-only on a made-up capture (no vcan): capture.mf4 beside the report, the
    bus of frame-clock run 1."""
    out = tmp_path / "replay"
    run_dir = out / ENGAGEMENT_LOG.stem
    fake_capture(run_dir, ENGAGEMENT_LOG)
    code, stdout, err = run(["replay", "--analyse-only", "--no-reference-check", ENGAGEMENT_LOG, "--out", out,
                             "-c", TABLE1], capsys)
    assert code in (0, 1), err            # 1: the made-up capture misses targets; the report is written
    counts = assert_matches_dbc(run_dir / "capture.mf4", canlog.read_log(run_dir / "frame1.log"))
    assert set(counts) == {canlog.COMMAND, canlog.ESTIMATE}
    metrics = json.loads((run_dir / "metrics.json").read_text())
    assert metrics["mdf"] == {"path": str(run_dir / "capture.mf4"), "groups": counts, "left_out": ""}
    assert "capture.mf4" in (run_dir / "summary.md").read_text() and "capture.mf4" in stdout


def test_shift_run_frames(tmp_path):
    """A shift report's file: the frames both ways of a run (one shift, nominal oil), at the TCU's time."""
    from wetclutch import shift
    from wetclutch.shift import comparison, runner
    from wetclutch.simulate import plant
    params = plant.load_plant(plant.DEFAULT_PLANT)
    scenario = next(s for s in shift.scenario_matrix() if s.name == "oil80")
    records = shift.run_case(params, "shift_1_2_full", scenario)
    paths = comparison.write_mdf(tmp_path, {("full", "oil80"): records}, "upshift_1_2.toml")
    assert paths == [str(tmp_path / "shift_oil80_full.mf4")]
    messages = runner.record_messages(records)
    counts = assert_matches_dbc(paths[0], messages)
    steps = len(records[0]["t_s"])
    assert counts[canlog.SENSORS] == counts[canlog.SHIFT_COMMAND] == counts[canlog.COMMAND] == steps
    assert counts[canlog.SHIFT_REPORT] == 1
    with MDF(paths[0]) as f:   # the TCU's step k at k ms
        g = next(i for i, gr in enumerate(f.groups) if gr.channel_group.acq_name == canlog.COMMAND)
        assert np.array_equal(f.get("VfsCurrent", group=g).timestamps, records[0]["t_s"])


# --------------------------------------------------------------------------- bad input, unwritable output

def _lines(n: int) -> list[str]:
    return ENGAGEMENT_LOG.read_text().splitlines()[:n]


@pytest.mark.parametrize("case, text, message", [
    ("malformed", "\n".join(_lines(3) + ["(1000000.003000) vcan0 110#XYZ"] + _lines(10)[3:]) + "\n",
     "line 4: not a candump -L line"),
    ("empty", "", "empty log"),
    ("blank", "\n\n", "empty log"),
    ("unknown ids", "(1.000000) vcan0 7FF#0102\n(1.001000) vcan0 1FFFFFFF#00\n",
     "no frame of hil/wetclutch.dbc (2 frame(s) with other ids or lengths)"),
    ("infinite time", "(inf) vcan0 110#0000000000000000\n", "line 1: timestamp inf is not finite"),
])
def test_bad_input_is_one_line(case, text, message, tmp_path, capsys):
    log = tmp_path / "in.log"
    log.write_text(text)
    out = tmp_path / "out.mf4"
    out.write_bytes(b"previous")
    code, stdout, err = run(["convert", "--to", "mdf4", log, out], capsys)
    assert_one_line_error(code, err, log, message)
    assert err.startswith("wetclutch convert: ") and stdout == ""
    assert out.read_bytes() == b"previous" and temporaries(tmp_path) == []


def test_missing_input(tmp_path, capsys):
    code, _, err = run(["convert", "--to", "mdf4", tmp_path / "none.log", tmp_path / "out.mf4"], capsys)
    assert_one_line_error(code, err, tmp_path / "none.log", "no such log file")
    assert list(tmp_path.iterdir()) == []


def test_unwritable_output(tmp_path, capsys):
    """Under a regular file, and a directory where the file should go: one line naming the path, nothing left.
    (A full disk and an unwritable directory: test_cli_output_faults.py, command convert-mdf4.)"""
    (tmp_path / "file").write_text("a file")
    code, _, err = run(["convert", "--to", "mdf4", ENGAGEMENT_LOG, tmp_path / "file" / "out.mf4"], capsys)
    assert_one_line_error(code, err, tmp_path / "file")
    (tmp_path / "dir.mf4").mkdir()
    code, _, err = run(["convert", "--to", "mdf4", ENGAGEMENT_LOG, tmp_path / "dir.mf4"], capsys)
    assert_one_line_error(code, err, tmp_path / "dir.mf4")
    assert (tmp_path / "file").read_text() == "a file" and list((tmp_path / "dir.mf4").iterdir()) == []
    assert temporaries(tmp_path) == []


def test_vector_log_to_mdf4(tmp_path, capsys):
    """--to mdf4 reads a Vector ASC log as the candump conversion does."""
    import can
    asc = tmp_path / "bench.asc"
    messages = canlog.read_log(ENGAGEMENT_LOG)[:300]
    with can.ASCWriter(str(asc)) as writer:
        for m in messages:
            writer.on_message_received(can.Message(timestamp=m.timestamp, arbitration_id=m.arbitration_id,
                                                   data=bytes(m.data), is_extended_id=False, channel=0))
    code, stdout, err = run(["convert", "--to", "mdf4", asc, tmp_path / "bench.mf4"], capsys)
    assert code == 0, err
    # the ASC file keeps its own time (from its start), so the read frames are compared, not the log's
    from wetclutch.hil import convert
    pairs, _ = convert.read_vector_log(asc)
    assert assert_matches_dbc(tmp_path / "bench.mf4", [m for _, m in pairs]) == {
        canlog.SENSORS: 100, canlog.REQUEST: 100, canlog.BENCH: 100}
