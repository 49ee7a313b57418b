"""Every shift type of the firmware's transmission on the 8-speed plant (wetclutch.shift.transmission8; issue
29, DESIGN 15): wc_transmission_step in process (ctypes) in lockstep with Plant8, one shift of each type on the
nominal vehicle. Asserted: the type the firmware picks, completion (AbortReason 0) in the target gear by the
plant's truth, the inertia phase within its target, the on-coming element's observer within 5 K of its true
temperature. The comfort targets of issue 29 that these shifts miss today are strict xfails with the figures."""
import pytest

from wetclutch.shift import transmission8 as t8

pytestmark = pytest.mark.slow   # needs the host-release build (libwc_transmission_host.so)

CASES = [(2, 3, "power-on upshift"), (2, 3, "power-off upshift"), (3, 2, "power-on downshift"),
         (3, 2, "power-off downshift"), (6, 4, "power-on downshift"), (4, 6, "power-off upshift")]


@pytest.fixture(scope="module")
def results():
    lib = t8._library()    # noqa: SLF001 (one load for the module)
    return {(s, t, k): t8.run_shift("nominal", s, t, k, lib=lib) for s, t, k in CASES}


@pytest.mark.parametrize("case", CASES, ids=[f"{s}-{t} {k}" for s, t, k in CASES])
def test_completes_in_the_target_gear(results, case):
    q = results[case]
    print(q)
    assert q["type"] == case[2]
    assert q["abort"] == 0
    assert q["end_gear"] == str(case[1])
    # the controller's inertia phase within +-10 % of its target (0.5 s; a kickdown's stretched one is longer:
    # the engine torque sets its pace, wc_shift.h) and the whole shift within 1.2 s of the request
    assert q["inertia_time_s"] >= 0.9 * q["target_s"]
    assert q["duration_s"] <= 1.2


@pytest.mark.parametrize("case", CASES, ids=[f"{s}-{t} {k}" for s, t, k in CASES])
def test_observer_within_5_K_of_the_truth(results, case):
    q = results[case]     # issue 31's observer target, on the on-coming element (the one that heats)
    assert abs(q["peak_theta_estimate_degC"] - q["peak_theta_truth_degC"]) <= 5.0


@pytest.mark.xfail(strict=True, reason="missed (2026-11-28, nominal vehicle): peak jerk 10.3-15.5 m/s^3 in the "
                   "tip-outs (target 5), 33-35 in the kickdowns (15), 29 in the coast downshift (5); the coast "
                   "downshift's turbine sags 45 rpm below the source gear's speed (30): the power-off and down "
                   "types are untuned (the power-on upshift's calibration, no engine request in the inertia-first "
                   "types)")
def test_comfort_targets(results):
    limits = {"power-on upshift": 10.0, "power-off upshift": 5.0, "power-on downshift": 15.0,
              "power-off downshift": 5.0}
    for case, q in results.items():
        assert q["peak_jerk_m_s3"] <= limits[case[2]], (case, q["peak_jerk_m_s3"])
        assert q["excursion_rpm"] <= 30.0, (case, q["excursion_rpm"])
