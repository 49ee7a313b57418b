"""Closed-loop 1->2 upshifts (issue 13): the shift calibration, the comparison of the three controllers on
the plant (in-process, the full scenario matrix: `wetclutch shift --oncoming-only`), determinism. The vcan
against in-process test runs the whole shift (test_whole_shift.py), which takes the same frame loop's path
and the coordinator's."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from wetclutch import calibration, shift
from wetclutch.simulate import plant
from wetclutch.calibration import shift as shift_calibration
from wetclutch.reference import model

ROOT = Path(__file__).resolve().parents[2]


def test_shift_header_regenerates_byte_identically(tmp_path):
    subprocess.run([sys.executable, "-m", "wetclutch.cli", "lut", "tools/calibrations/shift_1_2.toml", "--out",
                    str(tmp_path)], cwd=ROOT, check=True, capture_output=True)
    name = "wc_shift_1_2_shift.h"
    assert (tmp_path / name).read_bytes().replace(str(tmp_path).encode(), b"lut") == (ROOT / "lut" / name).read_bytes()


@pytest.mark.parametrize("field, value, message", [
    ("kp", "-1.0", "kp = -1.0 outside"),
    ("lag_compensation_time", "0.0005", "lag_compensation_time = 0.0005.* outside"),
    ("theta_source", "2", "theta_source = 2 outside"),
    ("inertia_timeout_factor", "nan", "not finite"),
])
def test_shift_calibration_refuses_what_the_firmware_refuses(tmp_path, field, value, message):
    text = (ROOT / "tools" / "calibrations" / "shift_1_2.toml").read_text()
    lines = [(f'{field} = {{ value = {value}, unit = "{line.split("unit = ")[1].split(chr(34))[1]}", source = "x" }}'
              if line.split("=")[0].strip() == field and line.startswith(field) else line) for line in text.splitlines()]
    bad = tmp_path / "bad.toml"
    bad.write_text("\n".join(lines))
    with pytest.raises(shift_calibration.ShiftCalibrationError, match=message):
        shift_calibration.load(bad)


def test_unknown_and_missing_parameters_are_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[shift]\nkp = { value = 1.0, unit = "Nm/(rad/s)", source = "x" }\n')
    with pytest.raises(shift_calibration.ShiftCalibrationError, match="missing"):
        shift_calibration.load(bad)
    bad.write_text((ROOT / "tools" / "calibrations" / "shift_1_2.toml").read_text()
                   + '\n[variants.x]\nkq = { value = 1.0, unit = "1", source = "x" }\n')
    with pytest.raises(shift_calibration.ShiftCalibrationError, match="unknown parameter"):
        shift_calibration.load(bad)


def test_in_process_shift_is_deterministic():
    params = plant.load_plant(plant.DEFAULT_PLANT)
    nominal = next(s for s in shift.scenario_matrix() if s.name == shift.NOMINAL)
    a = shift.frame_sequence(shift.run_case(params, "shift_1_2_full", nominal))
    b = shift.frame_sequence(shift.run_case(params, "shift_1_2_full", nominal))
    assert len(a) > 3000 and a == b


@pytest.mark.parametrize("variant, scenario", [("full", "oil20"), ("full", "oil80"), ("blind", "oil110"),
                                               ("feedback", "oil80")])
def test_firmware_shift_matches_the_double_reference(variant, scenario):
    """The frame loop's shift (in-process, closed loop on the plant) against shift_reference.py + the clutch
    reference in double on the same received frames, step by step."""
    params = plant.load_plant(plant.DEFAULT_PLANT)
    sc = next(s for s in shift.scenario_matrix() if s.name == scenario)
    cal_set = shift_calibration.load(shift.SHIFT_TOML)
    rec = shift.run_case(params, f"shift_1_2_{variant}", sc)[0]
    out = shift.reference_run(rec, cal_set.variants[variant], calibration.load(
        ROOT / "tools" / "calibrations" / f"{shift.TCU_CALIBRATION}.toml"), sc.oil_degC)
    # 1 mA: float against double, the h_bar(p_c) table against eq. 9/15 in closed form (the film state and the
    # film lead), the lead of the VFS lag multiplying a pressure difference by 3.9, VfsCurrent's 1/32 mA
    # resolution; seen at most 0.36 mA (cold oil, the film lead). A wrong phase or gain is 10..500 mA.
    diff = np.abs(out["reference_mA"] - out["tcu_mA"])
    assert diff.max() <= 1.0, (int(diff.argmax()), float(diff.max()))
    ref, tcu = out["reference_report"], out["tcu_report"]
    assert ref is not None and tcu is not None and out["reference_report_step"] == out["tcu_report_step"]
    assert int(tcu["AbortReason"]) == ref["abort_reason"] == 0
    assert bool(tcu["Flare"]) == ref["flare"] and bool(tcu["TieUp"]) == ref["tie_up"]
    assert abs(tcu["InertiaPhaseTime"] - 1e3 * ref["inertia_time_s"]) <= 0.5           # 1 ms/bit
    # the signals' resolutions (0.5 rpm, 0.1 m/s^3, 10 J, 0.1 degC) plus float rounding
    assert abs(tcu["SlipRmse"] - ref["slip_rmse_rad_s"] / model.RAD_S_PER_RPM) <= 0.5
    assert abs(tcu["PeakJerk"] - ref["peak_jerk_m_s3"]) <= 0.1 + 0.01 * ref["peak_jerk_m_s3"]
    assert abs(tcu["FrictionEnergy"] - 1e-3 * ref["friction_energy_J"]) <= 0.01 + 1e-3 * 1e-3 * ref["friction_energy_J"]
    assert abs(tcu["PeakClutchTemp"] - ref["peak_theta_degC"]) <= 0.1


@pytest.fixture(scope="module")
def matrix(tmp_path_factory):
    """The README's shift command: the full matrix in-process (about a minute)."""
    out = tmp_path_factory.mktemp("shift")
    result = subprocess.run([sys.executable, "-m", "wetclutch.cli", "shift", "--oncoming-only", "--out", str(out)], cwd=ROOT,
                            capture_output=True, text=True)
    metrics = json.loads((out / "metrics.json").read_text())
    return out, result, metrics


def test_report_has_every_case_and_the_plots(matrix):
    out, result, metrics = matrix
    assert set(metrics["cases"]) == {"feedback", "blind", "full"}
    names = {s.name for s in shift.scenario_matrix()}
    for ctrl, cases in metrics["cases"].items():
        assert set(cases) == names, ctrl
    assert len(metrics["cases"]["full"]["soak"]["per_shift"]) == shift.SOAK_SHIFTS
    for png in ("shift_oil80.png", "shift_oil20.png", "shift_soak.png"):
        assert (out / png).stat().st_size > 50_000, png
    # the exit code says whether a target was missed
    assert result.returncode == (1 if metrics["missed"] else 0), result.stderr


def test_full_model_beats_the_others_where_the_model_matters(matrix):
    """The part of the first target that holds: (c) has the lowest slip RMSE at every oil temperature and
    load, and a peak jerk no higher than (a)'s or (b)'s anywhere (1 % for the float figures)."""
    ratios = matrix[2]["targets"]["c_beats_a_and_b"]["ratios"]
    for sc, r in ratios.items():
        if sc.startswith(("oil", "load")):
            assert r["vs_a"]["slip_rmse_rpm"] > 1.0 and r["vs_b"]["slip_rmse_rpm"] > 1.0, (sc, r)
        assert r["vs_a"]["peak_jerk_m_s3"] > 0.99 and r["vs_b"]["peak_jerk_m_s3"] > 0.99, (sc, r)


def test_inertia_time_within_5_percent_at_every_oil_temperature(matrix):
    t = matrix[2]["targets"]["c_inertia_time_within_5pct"]
    assert t["met"], t["errors"]


def test_full_model_no_flare_tie_up_or_abort(matrix):
    t = matrix[2]["targets"]["c_no_flare_tieup_abort"]
    assert t["met"], t["problems"]


# Targets measured and missed (closing note of issue 13); strict: passing them turns these into failures,
# so the marks come off when the controller meets them.
@pytest.mark.xfail(strict=True, reason="missed: (a) has a 4 % lower slip RMSE with +10 % plant friction, and (c)'s"
                   " peak jerk equals (b)'s (ratio 1.00) where it comes from the torque phase both share")
def test_full_model_beats_feedback_and_thermal_blind_everywhere(matrix):
    t = matrix[2]["targets"]["c_beats_a_and_b"]
    assert t["met"], json.dumps(t["ratios"], indent=1)


@pytest.mark.xfail(strict=True, reason="missed: pressure RMSE 38 kPa with / 80 kPa without the lag compensation"
                   " (2.1x; the hand-over to the holding pressure saturates the solenoid)")
def test_lag_compensation_tracks_pressure_3x_better(matrix):
    t = matrix[2]["targets"]["lag_compensation_3x"]
    assert t["met"] and t["ratio"] >= 3.0, t


@pytest.mark.xfail(strict=True, reason="missed: (c) nominal peak jerk 13.7 m/s^3 (target 10): the torque phase's"
                   " hand-over from the off-going clutch (its 0.1 s release)")
def test_nominal_peak_jerk_within_comfort_limit(matrix):
    t = matrix[2]["targets"]["c_nominal_jerk_le_10"]
    assert t["met"], t


def test_lag_compensation_tracks_pressure_better(matrix):
    """What holds of the pressure target: with the lag compensation the piston pressure tracks at least 2x
    better than without (the 3x target is missed, above)."""
    t = matrix[2]["targets"]["lag_compensation_3x"]
    assert t["ratio"] >= 2.0, t


def test_full_model_never_aborts(matrix):
    """The part of the last target that holds: (c) completes every shift of every scenario."""
    full = matrix[2]["cases"]["full"]
    assert {sc: q["abort_reason"] for sc, q in full.items() if q["abort"] != 0} == {}
    assert all(q["abort"] == 0 for q in full["soak"]["per_shift"])
