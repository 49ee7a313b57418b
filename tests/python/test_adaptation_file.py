"""The host programs' persistence of the adaptation image (DESIGN 12; src/port/wc_adapt_file.c, wc_replay
--adaptation-file): learned values written at each shift's end and read by the next process; a missing,
corrupt, truncated or wrong-version file gives the calibration's values, a one-line message and
AdaptationReport.ImageInvalid, never a crash; a file that cannot be written is reported and the control goes
on. Closed loop on the shift plant (shift/runner.run_case), a few shifts each."""
from __future__ import annotations

import struct

import pytest

from wetclutch.calibration.adaptation_image import (AdaptationValues, encode_adaptation, read_adaptation_file)
from wetclutch.shift import runner
from wetclutch.shift.scenarios import Scenario
from wetclutch.shift.tcu import InprocTcu
from wetclutch.simulate import plant as plant_mod
from wetclutch.util import canlog

SHIFT = "shift_1_2_adaptive"
PLUS_20 = Scenario("friction+20", 80.0, 1.0, 1.2)


@pytest.fixture(scope="module")
def params():
    return plant_mod.load_plant(plant_mod.DEFAULT_PLANT)


def _run(params, path, shifts: int = 1) -> tuple[list[dict], str, list[dict]]:
    """shifts on the +20 % plant with one wc_replay on the adaptation file; the records, its stderr and the
    AdaptationReports."""
    tcu = InprocTcu(SHIFT, PLUS_20.oil_degC, adaptation_file=path)
    try:
        sc = Scenario(PLUS_20.name, PLUS_20.oil_degC, PLUS_20.load, PLUS_20.friction_scale, shifts=shifts)
        recs = runner.run_case(params, SHIFT, sc, tcu=tcu)
    finally:
        tcu.proc.stdin.close()
        err = tcu.proc.stderr.read()
        assert tcu.proc.wait(timeout=10) == 0, err
        tcu.proc.stdout.close()
        tcu.proc.stderr.close()
    msg = canlog.database().get_message_by_name("AdaptationReport")
    reports = [msg.decode(bytes.fromhex(d), decode_choices=False) for r in recs for _, fid, d in r["frames"]
               if fid == msg.frame_id]
    return recs, err, reports


def test_learned_values_persist_across_processes(params, tmp_path):
    path = tmp_path / "clutch0.wcap"
    recs, err, reports = _run(params, path, shifts=2)
    assert err == ""                                             # a missing file is the normal first start
    assert [r["report"]["AbortReason"] for r in recs] == [0, 0]
    assert len(reports) == 2 and reports[0]["ImageMissing"] == 1 and reports[0]["Result"] == 1
    first = read_adaptation_file(path, 0)
    assert first.shifts_learned == 2
    assert max(first.friction_scale) > 1.0                       # the +20 % clutch: the scale went up
    # a new process starts from the file, not the calibration
    _, err, reports = _run(params, path)
    assert err == "" and reports[0]["ImageMissing"] == 0 and reports[0]["ImageInvalid"] == 0
    second = read_adaptation_file(path, 0)
    assert second.shifts_learned == 3
    assert max(second.friction_scale) >= max(first.friction_scale)   # kept learning from where it was
    assert not (tmp_path / "clutch0.wcap.tmp").exists()             # written through a temporary, renamed


def _bad_images() -> dict[str, bytes]:
    good = encode_adaptation(AdaptationValues(friction_scale=(1.1,) * 5, confidence=(0.5,) * 5), 0)
    flipped = bytearray(good)
    flipped[20] ^= 0x01                                          # a payload bit: the CRC-32 says so
    wrong_version = bytearray(good)
    wrong_version[4:8] = struct.pack("<I", 2)
    return {"bad CRC-32": bytes(flipped), "truncated": good[:-3], "bad layout version": bytes(wrong_version),
            "bad magic": b"not an adaptation image at all, but long enough to hold one.............",
            "a value outside its band": encode_adaptation(AdaptationValues(friction_scale=(5.0,) * 5), 0)}


@pytest.mark.parametrize("why", list(_bad_images()))
def test_a_bad_image_gives_the_calibrations_values(params, tmp_path, why):
    path = tmp_path / "clutch0.wcap"
    path.write_bytes(_bad_images()[why])
    recs, err, reports = _run(params, path)
    assert f"not used ({why})" in err, err                         # one line naming the reason
    assert recs[0]["report"]["AbortReason"] == 0                    # the shift runs on the calibration's values
    assert reports[0]["ImageInvalid"] == 1 and reports[0]["Result"] == 1
    assert reports[0]["FrictionScale"] - reports[0]["FrictionScaleChange"] == pytest.approx(1.0, abs=5e-4)
    assert read_adaptation_file(path, 0).shifts_learned == 1      # replaced by a good image after the shift


def test_an_unwritable_file_is_reported_and_control_goes_on(params, tmp_path):
    path = tmp_path / "no such directory" / "clutch0.wcap"
    recs, err, reports = _run(params, path)
    assert "adaptation image" in err and "not written (open: No such file or directory)" in err, err
    assert recs[0]["report"]["AbortReason"] == 0 and reports[0]["Result"] == 1
    assert not path.parent.exists()
