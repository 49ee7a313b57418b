"""The whole 1->2 upshift (issue 22, DESIGN 14): the coordinator (fill, the off-going clutch, the engine torque
intervention, the fallback of a lost input) on the nominal vehicle's scenarios with the three controllers, the
family of vehicles at the nominal scenario, the generated vehicle calibrations, the report's files, and one
shift on vcan against the same case in-process (identical frames).

Every number comes from the plant's truth (tools/wetclutch/shift/quality.py); the targets are the issue's
(tools/wetclutch/shift/whole.py). A missed target is an xfail(strict) with the measured figure, so that
meeting it later fails the test and the marker has to go."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from vcan_support import needs_vcan
from wetclutch import shift
from wetclutch.shift import whole
from wetclutch.simulate import plant

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """`wetclutch shift --vehicles nominal`: the nominal vehicle's scenarios, (a) (b) (c), faults (about 20 s)."""
    out = tmp_path_factory.mktemp("whole")
    result = subprocess.run([sys.executable, "-m", "wetclutch.cli", "shift", "--vehicles", "nominal", "--out", str(out)],
                            cwd=ROOT, capture_output=True, text=True)
    metrics = json.loads((out / "metrics.json").read_text())
    return out, result, metrics


def _c(metrics, scenario):
    return metrics["cases"]["nominal"][whole.FULL][scenario]


def test_report_files_and_exit_code(report):
    out, result, metrics = report
    assert set(metrics["cases"]["nominal"]) == set(whole.CONTROLLERS.values())
    names = {s.name for s in whole.whole_scenarios() + whole.fault_scenarios()}
    assert set(metrics["cases"]["nominal"][whole.FULL]) == names
    for png in metrics["plots"]:
        assert Path(png).stat().st_size > 50_000, png
    assert (out / "whole_shift_report.md").read_text().startswith("# The whole 1->2 upshift")
    assert len(metrics["mdf"]) >= 5
    assert result.returncode == (1 if metrics["missed"] else 0), result.stderr
    assert set(metrics["missed"]) == {k for k, t in metrics["targets"].items() if not t["met"]}


def test_nominal_peak_jerk_with_the_intervention_within_10(report):
    q = _c(report[2], shift.NOMINAL)
    assert q["abort"] == 0 and q["gear"] == 2
    assert q["peak_jerk_m_s3"] <= whole.JERK_WITH_ENGINE_M_S3, q["peak_jerk_m_s3"]
    assert q["engine_torque_max_Nm"] > q["turbine_torque_Nm"] + 5.0   # the engine was asked for more ...
    assert q["engine_torque_min_Nm"] < q["turbine_torque_Nm"] - 30.0  # ... and for less


def test_engine_that_ignores_the_request_still_completes_without_flare(report):
    q = _c(report[2], "engine_ignores")
    assert q["abort"] == 0 and q["gear"] == 2
    assert q["flare_rpm"] <= whole.FLARE_MAX_RPM
    assert q["engine_torque_min_Nm"] == q["engine_torque_max_Nm"]   # the engine did ignore it


@pytest.mark.xfail(strict=True, reason="missed: 14-16 m/s^3 without the intervention (target 12): the turbine's"
                   " inertia torque I_t dref/dt, which the engine takes out otherwise, rises and falls at both ends"
                   " of the 0.5 s inertia phase (about 15 m/s^3 from 6 s0/T^2 at 125 rad/s of slip)")
def test_engine_ignores_peak_jerk_within_12(report):
    assert _c(report[2], "engine_ignores")["peak_jerk_m_s3"] <= whole.JERK_WITHOUT_ENGINE_M_S3


def test_inertia_phase_within_5_percent_at_every_oil_temperature(report):
    errors = {sc: q["inertia_time_error"] for sc, q in report[2]["cases"]["nominal"][whole.FULL].items()
              if sc.startswith("oil")}
    assert len(errors) == 6 and all(abs(e) <= whole.INERTIA_TOLERANCE for e in errors.values()), errors


def test_intervention_lowers_the_oncoming_friction_energy(report):
    t = report[2]["targets"]["energy_20pct_lower"]
    assert t["change"] < -0.03 and t["inertia_phase_change"] < -0.10, t


@pytest.mark.xfail(strict=True, reason="missed: -7 % over the shift (-13 % in the inertia phase; target -20 %):"
                   " the torque phase at full slip is a third of the energy and the engine cannot lower it, and"
                   " taking more than the inertia torque out dips the output torque (1.6 x: 10.2 m/s^3, -10 %)")
def test_intervention_cuts_the_friction_energy_by_20_percent(report):
    assert report[2]["targets"]["energy_20pct_lower"]["met"]


def test_fallback_of_a_lost_input_per_phase(report):
    """DESIGN 14: torque phase -> handed back to 1st gear; inertia phase -> finished on the model in 2nd gear;
    longer than fallback_time_s -> released; the engine request withdrawn in all (its torque back to the
    driver's)."""
    rows = report[2]["targets"]["faults"]["rows"]
    assert rows["fault_torque"]["ok"] and rows["fault_torque"]["abort"] == "input lost", rows
    assert rows["fault_inertia"]["ok"] and rows["fault_inertia"]["abort"] == "completed", rows
    assert rows["fault_inertia_long"]["ok"], rows
    # issue 29 item 7: lost early in the inertia phase and back: locked in 2nd by the plant's truth, not only reported
    assert rows["fault_inertia_early"]["ok"] and rows["fault_inertia_early"]["abort"] == "completed", rows
    for sc in ("fault_torque", "fault_inertia"):
        assert _c(report[2], sc)["flare_rpm"] <= whole.FLARE_MAX_RPM


def test_full_model_beats_feedback_only_in_slip_tracking_where_the_model_matters(report):
    """Issue 13's comparison on the whole shift: (c) tracks the slip better than (a) and (b) at the extreme oil
    temperatures, where the thermal model matters, and (a) and (b) lose the 20 degC shift altogether."""
    cases = report[2]["cases"]["nominal"]
    full, fb, blind = cases[whole.FULL], cases[whole.CONTROLLERS["a"]], cases[whole.CONTROLLERS["b"]]
    for sc in ("oil20", "oil40", "oil110"):
        assert full[sc]["slip_rmse_rpm"] < fb[sc]["slip_rmse_rpm"], sc
        assert full[sc]["slip_rmse_rpm"] < blind[sc]["slip_rmse_rpm"], sc
    assert full["oil20"]["abort"] == 0 and fb["oil20"]["abort"] != 0 and blind["oil20"]["abort"] != 0


@pytest.mark.xfail(strict=True, reason="missed: (b) has the same torque phase as (c), which sets the peak jerk at"
                   " 40..80 degC, and a lower slip RMSE at 25/50 % load")
def test_full_model_beats_the_others_everywhere(report):
    assert report[2]["targets"]["c_beats_a_and_b"]["met"]


@pytest.mark.xfail(strict=True, reason="missed: plant friction +10 % ties up 10.7 % of T_t (target 10 %) on the"
                   " nominal vehicle; on the family also flares of 38-60 rpm on the soft drivelines at 100-110 degC")
def test_no_flare_no_tie_up_in_any_scenario(report):
    assert report[2]["targets"]["no_flare_no_tie_up"]["met"]


def test_offgoing_friction_error_of_20_percent(report):
    """The off-going clutch's friction -/+20 % against its model: no flare (its capacity is the carried torque
    plus a margin, times its lock-up margin), tie-up within 10 % of T_t."""
    for sc in ("offgoing-20pct", "offgoing+20pct"):
        q = _c(report[2], sc)
        assert q["abort"] == 0 and q["flare_rpm"] <= whole.FLARE_MAX_RPM, (sc, q["flare_rpm"])
        assert q["tie_up_fraction"] <= whole.TIE_UP_MAX_FRACTION, (sc, q["tie_up_fraction"])


def test_scripted_release_is_the_comparison(report):
    """Issue 13's way (the plant's scripted release) with the same controller flares: the off-going clutch's
    control is what the whole shift adds."""
    scripted, nominal = _c(report[2], "scripted_release"), _c(report[2], shift.NOMINAL)
    assert scripted["flare_rpm"] > 100.0 and nominal["flare_rpm"] <= whole.FLARE_MAX_RPM
    assert scripted["peak_jerk_m_s3"] > 1.5 * nominal["peak_jerk_m_s3"]


def test_every_vehicle_at_nominal_load():
    """The family (tools/plants/vehicles/), each with its generated driveline calibration: completed, no flare,
    no tie-up above 10 %, peak jerk within 12 m/s^3."""
    nominal = next(s for s in whole.whole_scenarios() if s.name == shift.NOMINAL)
    for v in whole.VEHICLES:
        _, q, _ = whole._run((v, whole.FULL, nominal))
        assert q["abort"] == 0 and q["gear"] == 2, v
        assert q["flare_rpm"] <= whole.FLARE_MAX_RPM, (v, q["flare_rpm"])
        assert q["tie_up_fraction"] <= whole.TIE_UP_MAX_FRACTION, (v, q["tie_up_fraction"])
        assert q["peak_jerk_m_s3"] <= whole.FAMILY_JERK_M_S3, (v, q["peak_jerk_m_s3"])


def test_vehicle_driveline_reaches_the_firmware():
    """The generated driveline model is what the TCU gets (wc_replay --set): another vehicle's values change the
    frames."""
    nominal = next(s for s in whole.whole_scenarios() if s.name == shift.NOMINAL)
    params = plant.load_plant(whole.plant_path("nominal"))
    cal = whole.shift_calibration.load(whole.SHIFT_TOML).variants[whole.FULL]
    a = shift.frame_sequence(shift.run_case(params, f"shift_1_2_{whole.FULL}", nominal,
                                            overrides=whole.vehicle_overrides("nominal"), shift_cal=cal))
    b = shift.frame_sequence(shift.run_case(params, f"shift_1_2_{whole.FULL}", nominal,
                                            overrides=whole.vehicle_overrides("heavy"), shift_cal=cal))
    assert len(a) == len(b) and a != b
    assert whole.vehicle_overrides("heavy")["output_inertia_kg_m2"] > whole.vehicle_overrides("nominal")["output_inertia_kg_m2"]


@needs_vcan
def test_vcan_whole_shift_equals_in_process(tmp_path):
    """One whole shift (both clutches, the engine request): the closed loop's inputs replayed to wc_tcu on vcan
    (natively or in the QEMU guest) in lockstep give exactly the frames of the same case with the frame loop
    in-process, run here again (so wc_tcu would have driven the plant to the same inputs: runner.run_on_vcan)."""
    path = shift.run_on_vcan(tmp_path, f"shift_1_2_{whole.FULL}", shift.NOMINAL, whole.plant_path("nominal"))
    vcan = json.loads(path.read_text())
    params = plant.load_plant(whole.plant_path("nominal"))
    nominal = next(s for s in shift.scenario_matrix() if s.name == shift.NOMINAL)
    inproc = [list(f) for f in shift.frame_sequence(shift.run_case(params, f"shift_1_2_{whole.FULL}", nominal))]
    assert len(vcan["frames"]) == len(inproc) > 6000
    assert vcan["frames"] == inproc
    assert vcan["quality"][0]["abort"] == 0


def test_unknown_vehicle_is_one_line_and_exit_2(tmp_path):
    res = subprocess.run([sys.executable, "-m", "wetclutch.cli", "shift", "--vehicles", "nominal", "nope",
                          "--out", str(tmp_path / "o")], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "nope" in res.stderr and "Traceback" not in res.stderr
    assert not (tmp_path / "o").exists()
