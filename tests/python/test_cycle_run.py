"""The drive cycle run (issue 31, items 3-5; DESIGN 16): `wetclutch cycle` on the WLTC's low phase (0-589 s),
the firmware's transmission in process at 1 kHz on the 8-speed plant, and its report.

What holds is asserted; what the cycle shows missed is a strict xfail with its figures (a fix makes it pass and
the xfail fail, so it cannot go stale). The whole 1800 s and the second vehicle are run by the command
(`wetclutch cycle --vehicle nominal examples/unseen_8hp_suv/plant.toml`), not here: 2 x 15 min of CPU.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from wetclutch import cli
from wetclutch.cycle import load_wltc_class3b, runner

ROOT = Path(__file__).resolve().parents[2]
UNSEEN = ROOT / "examples" / "unseen_8hp_suv"


@pytest.fixture(scope="module")
def low(tmp_path_factory):
    out = tmp_path_factory.mktemp("cycle")
    rc = cli.main(["cycle", "--phase", "low", "--out", str(out)])
    data = json.loads((out / "nominal_low.json").read_text())
    return rc, out, data["figures"], data["shifts"]


def test_the_low_phase_runs_through_and_reports(low):
    rc, out, figures, shifts = low
    assert rc == (1 if figures["missed"] else 0)          # exit 1 exactly when a target is missed
    for name in ("nominal_low.md", "nominal_low.mf4", "nominal_low/speed.png", "nominal_low/temperatures.png",
                 "nominal_low/jerk.png", "nominal_low/learned.png"):
        assert (out / name).stat().st_size > 0, name
    assert figures["duration_s"] == pytest.approx(589.0, abs=0.02)
    # the low phase's trace asks for a few dozen shifts of both directions; every one is reported
    assert figures["requests"]["total"] >= 40
    assert len(shifts) == figures["shifts"] >= figures["requests"]["total"] - figures["dropped_requests"] - 1
    kinds = {q["kind"] for q in shifts}
    assert {"power-on upshift", "power-off downshift"} <= kinds


def test_the_mdf_holds_the_cycle(low):
    from asammdf import MDF
    _, out, figures, _ = low
    with MDF(out / "nominal_low.mf4") as mdf:
        speed = mdf.get("speed_kmh")
        target = mdf.get("target_kmh")
        theta = mdf.get("A_theta_est_degC")
    assert speed.samples.size == target.samples.size == theta.samples.size > 58_000   # every 10 ms
    assert speed.unit == "km/h"
    # the channels are the ones the report was made of (not a copy of the trace)
    assert np.max(np.abs(speed.samples - target.samples)) == pytest.approx(figures["largest_speed_error_kmh"],
                                                                          rel=1e-9)


def test_no_speed_trace_violation_is_the_transmissions(low):
    _, _, figures, _ = low
    assert figures["violations_transmission"] == 0, figures["violations"]


def test_every_request_engages(low):
    assert low[2]["dropped_requests"] == len(low[2]["dropped"]) == 0     # each one listed with its time


@pytest.mark.xfail(strict=True, reason="missed (2026-11-29, 8d21ac8): 1 of 76 shifts of the low phase ends in lock-up"
                   " failed, a 4->5 upshift at 9 N*m (tie-up 41 %); the five coast downshifts that had failed (the"
                   " engine still pulling, 5..31 N*m, the turbine run past the new gear's speed) now lock")
def test_every_shift_completes(low):
    assert [q for q in low[3] if q["abort"] != 0] == []


@pytest.mark.xfail(strict=True, reason="missed (2026-11-29, 8d21ac8): 42 of 76 shifts meet every limit of issue 29;"
                   " misses: tie-up 24 (light-load upshifts: > 10 % of T_t, at least 20 N*m; the on-coming element's"
                   " fill overshoot), inertia 13, jerk 9, flare 7, not completed 1")
def test_every_shift_within_the_limits(low):
    assert [(q["t_s"], q["shift"], q["missed"]) for q in low[3] if q["missed"]] == []


def test_the_observer_within_5_K_of_every_element(low):
    # (met since the open element's clearance and aeration are calibration fields: A 0.9, B 0.1, C 1.3, D 1.6,
    # E 1.4 K over the low phase; up to 48.5 K before)
    assert max(low[2]["observer_max_error_K"].values()) <= 5.0


def _copy_outside(dst: Path) -> Path:
    """The unseen SUV's two files copied to dst, their paths into the repository made absolute: a vehicle given
    as files outside the repository."""
    for name in ("vehicle.toml", "plant.toml"):
        text = (UNSEEN / name).read_text()
        text = re.sub(r'^(extends|vehicle) = "([^"]+)"', lambda m: f'{m[1]} = "{(UNSEEN / m[2]).resolve()}"'
                      if m[2].startswith("..") else m[0], text, flags=re.M)
        (dst / name).write_text(text)
    return dst / "plant.toml"


def test_a_vehicle_from_files_outside_the_repository(tmp_path):
    plant = _copy_outside(tmp_path)
    assert not str(plant).startswith(str(ROOT))
    trace = load_wltc_class3b().segment(0, 30, "WLTC class 3b, first 30 s")
    r = runner.run_cycle(str(plant), trace)
    n = runner.run_cycle("nominal", trace)
    # it drove the SUV (2150 kg on 0.35 m wheels, the same trace): the launch needs more pedal than the nominal
    # car's, and the 1->2 comes at another output speed
    c, d = r.channels, n.channels
    launch = (c["t_s"] > 11.5) & (c["t_s"] < 16.0)
    assert np.mean(c["pedal"][launch]) > 1.1 * np.mean(d["pedal"][launch])
    assert r.requests and n.requests and r.requests[0].output_rpm != n.requests[0].output_rpm
    assert np.max(np.abs(c["speed_kmh"] - c["target_kmh"])) < 4.0


def test_a_bad_vehicle_is_an_input_error(tmp_path, capsys):
    assert cli.main(["cycle", "--vehicle", str(tmp_path / "none.toml"), "--out", str(tmp_path)]) == 2
    assert "no 8-speed plant file" in capsys.readouterr().err
    bad = _copy_outside(tmp_path)
    bad.write_text(bad.read_text().replace("vfs_time_constant_scale = { value = 1.3", "vfs_time_constant_scale = {"
                                           " value = 9.0"))
    assert cli.main(["cycle", "--vehicle", str(bad), "--phase", "low", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "wetclutch cycle:" in err and "Traceback" not in err


def test_the_type_the_request_assumes_is_the_firmwares():
    """The inertia time a request carries is the type's (transmission8.TARGET_S): the runner types a shift as
    wc_gearbox_shift_type does, with the header's threshold."""
    header = (ROOT / "include" / "wetclutch" / "wc_gearbox.h").read_text()
    value = float(re.search(r"#define WC_GEARBOX_POWER_ON_DOWN_MIN_Nm ([0-9.]+)f", header)[1])
    assert runner.POWER_ON_DOWN_MIN_NM == value
    assert runner._kind(-1, value) == "power-off downshift"
    assert runner._kind(-1, value + 1.0) == "power-on downshift"
    assert runner._kind(+1, 1.0) == "power-on upshift"


def _fake(shifts, scales):
    """A CycleResult with these shifts (t_s, shift, peak jerk) and every element's friction scales."""
    values = {e: {"friction_scale": list(scales), "confidence": [0.5] * 5, "film_factor": 1.0, "kiss_offset_Pa": 0.0,
                  "shifts_learned": 3} for e in runner.ELEMENTS}
    qs = [{"t_s": t, "shift": s, "peak_jerk_m_s3": j, "missed": []} for t, s, j in shifts]
    return runner.CycleResult("nominal", None, {}, qs, [], [], 0.0, 0, True, values)


def test_the_adaptation_targets_are_judged():
    """Issue 31's adaptation targets from the chained cycles: bands, settling from cycle 2 to 3 (the per-shift
    steps of tools/calibrations/shift_1_2.toml: scale 0.05), no shift more than 2 % worse in cycle 1."""
    from wetclutch.cycle.report import adaptation_figures
    ref = _fake([(10.0, "1->2", 5.0), (20.0, "2->3", 4.0)], [1.0] * 5)
    good = [_fake([(10.2, "1->2", 5.05), (20.1, "2->3", 3.0)], [1.02] * 5), _fake([], [1.03] * 5),
            _fake([], [1.04] * 5)]
    assert adaptation_figures(ref, good)["missed"] == []
    worse = [_fake([(10.2, "1->2", 5.3), (20.1, "2->3", 3.0)], [1.02] * 5), *good[1:]]
    a = adaptation_figures(ref, worse)
    assert a["worse_in_cycle_1"] == [(10.2, "1->2", 5.0, 5.3)] and len(a["missed"]) == 1
    drifting = [good[0], _fake([], [1.10] * 5), _fake([], [1.20] * 5)]
    assert any("not settled" in m for m in adaptation_figures(ref, drifting)["missed"])
    outside = [good[0], good[1], _fake([], [1.35] * 5)]
    assert any("outside their bands" in m for m in adaptation_figures(ref, outside)["missed"])
    assert any("3 needed" in m for m in adaptation_figures(ref, good[:2])["missed"])


def test_the_learned_values_truth_is_the_plants_lining_against_the_model():
    """What each element should learn (report.learned_truth, the report's learned values against truth): the
    friction scale at the nodes is the plant file's lining factor times the true material's friction against
    the model's (eq. 18's ratio); so the SUV's over the nominal's is its [truth.friction_scale] factor exactly
    (both plants share the material), read here from the file itself."""
    import tomllib
    from wetclutch.cycle.report import learned_truth
    suv, nominal = learned_truth(str(UNSEEN / "plant.toml")), learned_truth("nominal")
    factors = tomllib.loads((UNSEEN / "plant.toml").read_text())["truth"]["friction_scale"]
    for e in runner.ELEMENTS:
        assert suv[e]["theta_nodes_degC"] == nominal[e]["theta_nodes_degC"]
        for a, b in zip(suv[e]["friction_scale"], nominal[e]["friction_scale"]):
            assert a / b == pytest.approx(factors[e]["value"], rel=1e-9), e     # float64 ratio: rounding only
        assert suv[e]["kiss_offset_Pa"] == nominal[e]["kiss_offset_Pa"] == 0.0   # the elements' own springs


def test_a_bad_adaptation_count_is_an_input_error(tmp_path, capsys):
    assert cli.main(["cycle", "--adaptation", "11", "--out", str(tmp_path)]) == 2
    assert "--adaptation 11" in capsys.readouterr().err
