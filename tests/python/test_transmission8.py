"""Every shift type of the firmware's transmission on the 8-speed plant (wetclutch.shift.transmission8; issue
29, DESIGN 15): wc_transmission_step in process (ctypes) in lockstep with Plant8, one shift of each type on the
nominal vehicle. Asserted: the type the firmware picks, completion (AbortReason 0) in the target gear by the
plant's truth, the inertia phase within its target, the on-coming element's observer within 5 K of its true
temperature, issue 29's comfort targets (peak jerk by type, flare and sag) and the kickdown's new gear's speed
within 0.6 s; a part-load downshift (the off-going element released into its spring's band); a target
missed is a strict xfail with its figures. The plots per type (transmission8_plots): one
PNG per type, drawn from traces that are the run's (the quality recomputed from them); the command line's --plots."""
import json

import numpy as np
import pytest

from wetclutch.shift import transmission8 as t8
from wetclutch.shift import transmission8_plots as t8_plots
from wetclutch.shift.quality import JERK_CUTOFF_HZ, _lowpass_zero_phase

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
    # the controller's inertia phase within +-10 % of its commanded target (transmission8.TARGET_S per type; a
    # kickdown's is stretched to what the engine torque can do, wc_shift.h: only the lower bound holds) and the
    # whole shift within 0.7 s more (prepare, the hand-over, the lock-up's dwell)
    assert q["inertia_time_s"] >= 0.9 * q["target_s"]
    if case[2] != "power-on downshift":
        assert q["inertia_time_s"] <= 1.1 * q["target_s"]
    assert q["duration_s"] <= q["target_s"] + 0.7


# (the kickdowns' 5.8-6.0 K over, an open element's drag through h_bar(0), met since the open clearance and
# aeration are calibration fields: 0.00 K)
@pytest.mark.parametrize("case", CASES, ids=[f"{s}-{t} {k}" for s, t, k in CASES])
def test_observer_within_5_K_of_the_truth(results, case):
    q = results[case]     # issue 31's observer target, on the on-coming element (the one that heats)
    assert abs(q["peak_theta_estimate_degC"] - q["peak_theta_truth_degC"]) <= 5.0


LIMITS = {"power-on upshift": 10.0, "power-off upshift": 5.0, "power-on downshift": 15.0, "power-off downshift": 5.0}
JERK_MISSED = {(4, 6, "power-off upshift"): pytest.mark.xfail(
    strict=True, reason="missed (2026-11-28): the 4->6 tip-out's peak jerk 5.6 m/s^3 (limit 5; 4.1 before the tip-out "
    "filled its on-coming element without the fill pulse, which cut the matrix's tip-outs from 3.8-22.1 to 2.4-10.9 m/s^3): "
    "the off-going element's release at the push's start, 40 N m of output torque in 40 ms at 0.15 s")}


@pytest.mark.parametrize("case", [pytest.param(c, marks=JERK_MISSED[c]) if c in JERK_MISSED else c for c in CASES],
                         ids=[f"{s}-{t} {k}" for s, t, k in CASES])
def test_comfort_targets(results, case):
    """Issue 29's comfort targets by type: peak output jerk, no flare or sag beyond 30 rpm outside the band
    between the two gears' speeds, no tie-up above 10 % of the turbine torque."""
    q = results[case]
    print(f"{q['shift']} {case[2]}: jerk {q['peak_jerk_m_s3']:.1f} m/s^3 (limit {LIMITS[case[2]]}), excursion "
          f"{q['excursion_rpm']:.0f} rpm, tie-up {q['tie_up_Nm']:.1f} N m of {q['turbine_torque_Nm']:.0f}, inertia "
          f"{q['inertia_time_s']:.3f} s of {q['target_s']} s, new gear's speed at {q['new_speed_s']:.3f} s")
    # flare and tie-up first: a shift whose jerk is a strict xfail (4->6) is still held to them
    assert q["excursion_rpm"] <= 30.0, (case, q["excursion_rpm"])
    assert q["tie_up_fraction"] <= t8.TIE_UP_FRACTION, (case, q["tie_up_fraction"])
    assert q["peak_jerk_m_s3"] <= LIMITS[case[2]], (case, q["peak_jerk_m_s3"])


def test_part_load_downshift_releases_the_off_going_element_into_its_band():
    """A power-on downshift at 25 % load (the drive cycle's most frequent power-on downshift, on its down line):
    at its kiss point the off-going element A of the 7->6 drags 11 N m at the element, all of the turbine torque,
    so the turbine stalled 230 rpm short of the 6th gear's speed and the shift timed out back into 7th (the WLTC's
    dropped requests). Released into its spring's band (wc_step_input_t.band_release, DESIGN 15) it completes in
    6th within every target of its type."""
    q = t8.run_shift("nominal", 7, 6, "power-on downshift", load=0.25)
    print(q)
    assert (q["type"], q["abort"], q["end_gear"]) == ("power-on downshift", 0, "6")
    assert q["excursion_rpm"] <= 30.0 and q["tie_up_fraction"] <= t8.TIE_UP_FRACTION
    assert q["peak_jerk_m_s3"] <= LIMITS["power-on downshift"]
    assert t8.missed({**q, "load": 0.25}) == []


def test_cold_coast_downshift_ends_with_every_element_of_the_new_gear_locked():
    """The 8->7 coast downshift at 20 degC: its on-coming element C carries 15.6 N m in 7th by the plant's truth,
    of which T_t's share is 8.7 (the rest is the open elements' cold drag). Held at that share x 1.3 and at least
    10 N m it slipped 0.6 rad/s for good (under the gear-slip watch at the turbine) while the TCU reported the
    shift done, a slipping element counted locked; at least 30 N m (transmission8.HOLDING_FLOOR_NM) locks it."""
    q = t8.run_shift("nominal", 8, 7, "power-off downshift", load=0.0, oil_degC=20.0)
    print(q)
    assert (q["type"], q["abort"], q["end_gear"]) == ("power-off downshift", 0, "7")
    assert t8.missed({**q, "load": 0.0}) == []


def test_light_load_upshift_releases_the_on_coming_element_into_its_band():
    """The 6->7 at 25 % load and 110 degC: in the inertia phase the on-coming element A's request (the engine
    takes most of the turbine torque out) is below A's drag at its kiss point at 180-260 rad/s of slip. Held at
    the kiss point the slip stalled at 17 rad/s and the shift ended in lock-up failed (AbortReason 2); released
    into its spring's band (wc_step_input_t.band_release on the on-coming element, DESIGN 15) it completes."""
    from wetclutch.gearbox import description
    tr = t8.trace_shift("nominal", 6, 7, "power-on upshift", load=0.25, oil_degC=110.0)
    q = tr.quality
    print(q)
    assert (q["type"], q["abort"], q["end_gear"]) == ("power-on upshift", 0, "7")
    assert abs(q["inertia_time_s"] / q["target_s"] - 1.0) <= t8.INERTIA_TOLERANCE
    # (the tie-up is not asserted: the fill pulse's residual at the landing, the light-load upshifts' known miss)
    assert q["excursion_rpm"] <= t8.EXCURSION_RPM and q["peak_jerk_m_s3"] <= LIMITS["power-on upshift"]
    # released into the band: in the inertia phase A's current went below its kiss point's (F_s / A_p / K,
    # 52.2 mA); 5 mA below it is a tenth of the band (the spring's 0.8..1 F_s: 41.7..52.2 mA), far from the noise
    cal = next(e for e in description.read(t8.ROOT / "tools" / "gearboxes" / "8hp.toml").elements
               if e.name == "A").calibration
    kiss_mA = cal.return_spring_force / cal.piston_area / cal.vfs_gain
    inertia = np.asarray(tr.tcu["phase"]) == t8.PHASES.index("inertia")
    assert float(np.min(tr.tcu["A_current_mA"][inertia])) < kiss_mA - 5.0


def test_light_load_upshift_takes_the_engine_no_lower_than_its_zero_torque():
    """The 6->7 at 25 % load and 80 degC: the inertia torque of a 0.5 s inertia phase is 149 N m at the turbine,
    more than the engine's 62. Asked for all of it the engine went into its drag (delta -149 N m), the on-coming
    element A's request fell below its drag at the kiss point and the slip stalled: lock-up failed. The engine
    reduction now stops at the engine's zero torque (-T_t0) and the shift completes."""
    tr = t8.trace_shift("nominal", 6, 7, "power-on upshift", load=0.25, oil_degC=80.0)
    q = tr.quality
    print(q, float(np.min(tr.tcu["engine_delta_Nm"])))
    assert (q["type"], q["abort"], q["end_gear"]) == ("power-on upshift", 0, "7")
    # T_t0 is the TCU's estimate of the turbine torque at the request: the truth's x (1 + the nominal
    # vehicle's 3 % estimate bias), 5 % allowed for the bias and the torque's drift before the request
    assert float(np.min(tr.tcu["engine_delta_Nm"])) >= -1.05 * q["turbine_torque_Nm"]


def test_cold_coast_downshift_closes_the_slip_its_drag_holds_open():
    """The 6->5 coast downshift at 20 degC: after synchronism the on-coming element B, at its kiss point, carried
    the coast torque by its cold drag at 9 rad/s of slip, and the slip correction's integral, capped at |T_t|,
    could never ask for more than that drag: lock-up failed (AbortReason 2). Capped at |T_t| beyond what the
    element carries, it closes the slip."""
    q = t8.run_shift("nominal", 6, 5, "power-off downshift", load=0.0, oil_degC=20.0)
    print(q)
    assert (q["type"], q["abort"], q["end_gear"]) == ("power-off downshift", 0, "5")
    assert t8.missed({**q, "load": 0.0}) == []


KICKDOWNS = [c for c in CASES if c[2] == "power-on downshift"]
SLOW_KICKDOWN = pytest.mark.xfail(
    strict=True, reason="missed (2026-11-28): the 3->2 kickdown's turbine at the 2nd gear's speed 0.625 s after the "
    "request (0.6 s; was 0.70-0.76 s): its inertia phase is stretched to the trapezoid the engine's full-load torque and "
    "the 12 m/s^3 design jerk allow (0.658 s from 0.05 s): T_t / I_t = 250 / 0.98 rad/s^2 at the 3->2's 98 rad/s of "
    "slip; a faster ramp (0.637 s) flared 31 rpm at synchronism, a higher flat rate 14-15 m/s^3. The converter's lock-up "
    "stays closed: the engine's inertia turns with the turbine")


@pytest.mark.parametrize("case", [pytest.param(c, marks=SLOW_KICKDOWN) if c[:2] == (3, 2) else c for c in KICKDOWNS],
                         ids=[f"{s}-{t}" for s, t, _ in KICKDOWNS])
def test_kickdown_reaches_the_new_gear_in_time(results, case):
    """Issue 29: a kickdown's turbine at the new gear's speed within 0.6 s of the request at full load (the first
    period within END_RATIO_TOLERANCE of the target ratio by the plant's truth)."""
    q = results[case]
    print(f"{q['shift']}: new gear's speed at {q['new_speed_s']:.3f} s")
    assert q["new_speed_s"] <= t8.KICKDOWN_NEW_SPEED_S


def test_matrix_covers_every_shift_and_type():
    """Issue 29 item 5's matrix (transmission8 --matrix): every single step up and down in both power-on and
    power-off, the single-element skips both ways, the power-on types at each load."""
    cases = t8.matrix_cases(loads=(1.0, 0.25))
    keys = {(s, t, k) for s, t, k, _ in cases}
    for g in range(1, 8):
        assert {(g, g + 1, "power-on upshift"), (g, g + 1, "power-off upshift"), (g + 1, g, "power-on downshift"),
                (g + 1, g, "power-off downshift")} <= keys
    for a, b in t8.SKIP_DOWNS:
        assert {(a, b, "power-on downshift"), (a, b, "power-off downshift"), (b, a, "power-on upshift"),
                (b, a, "power-off upshift")} <= keys
    loads = {(s, t, k): set() for s, t, k, _ in cases}
    for s, t, k, load in cases:
        loads[(s, t, k)].add(load)
    assert all(v == ({1.0, 0.25} if k.startswith("power-on") else {0.0}) for (_, _, k), v in loads.items())
    assert len(cases) == (14 + 12) * 3


def test_matrix_names_every_missed_target():
    good = {"kind": "power-off upshift", "shift": "2->3", "abort": 0, "end_gear": "3", "peak_jerk_m_s3": 4.9,
            "excursion_rpm": 29.0, "inertia_time_s": 1.19, "target_s": 1.2, "peak_theta_estimate_degC": 84.0,
            "peak_theta_truth_degC": 80.0, "tie_up_fraction": 0.099}
    assert t8.missed(good) == []
    for change, says in (({"abort": 2}, "not completed"), ({"end_gear": "2"}, "not completed"),
                         ({"peak_jerk_m_s3": 5.1}, "jerk"), ({"excursion_rpm": 31.0}, "flare/sag"),
                         ({"tie_up_fraction": 0.101}, "tie-up"),
                         ({"inertia_time_s": 1.4}, "inertia"), ({"peak_theta_estimate_degC": 85.1}, "theta")):
        m = t8.missed({**good, **change})
        assert len(m) == 1 and says in m[0], (change, m)
    # a kickdown's stretched inertia phase is not a miss (the engine torque sets its pace), a short one is
    kick = {**good, "kind": "power-on downshift", "peak_jerk_m_s3": 12.0, "inertia_time_s": 0.9, "target_s": 0.5}
    assert t8.missed(kick) == []
    assert "inertia" in t8.missed({**kick, "inertia_time_s": 0.4})[0]
    # a kickdown at full load reaches the new gear's speed within 0.6 s (never: NaN, a miss); at 25 % load no bound
    assert t8.missed({**kick, "new_speed_s": 0.58}) == []
    for late in (0.65, float("nan")):
        m = t8.missed({**kick, "new_speed_s": late})
        assert len(m) == 1 and "new gear's speed" in m[0], (late, m)
    assert t8.missed({**kick, "new_speed_s": 0.65, "load": 0.25}) == []


def test_tie_up_is_the_applied_off_going_element_fighting_its_direction():
    """tie_up_Nm: the off-going element's torque against the sign it carried at the request, only while its piston
    is applied (fill 1); what it drags once retracted is its open drag, apart. The fraction's denominator is the
    turbine torque at the request, at least TIE_UP_TORQUE_MIN_NM."""
    torque = [-40.0, -10.0, 25.0, 30.0, 5.0]          # carried -40 N m, then fights with +25 (applied), +30 open
    fill = [1.0, 1.0, 1.0, 0.5, 0.0]
    assert t8.tie_up_Nm(torque, fill, -40.0) == (25.0, 30.0)
    assert t8.tie_up_Nm([-x for x in torque], fill, 40.0) == (25.0, 30.0)     # the mirror: same figures
    assert t8.tie_up_Nm([-40.0, -20.0, 0.0], [1.0, 1.0, 1.0], -40.0) == (0.0, 0.0)   # released without a fight
    assert t8.tie_up_fraction(25.0, 250.0) == pytest.approx(0.1)
    assert t8.tie_up_fraction(5.0, -2.0) == pytest.approx(5.0 / t8.TIE_UP_TORQUE_MIN_NM)
    assert t8.excursion_rpm(np.array([3000.0, 3035.0, 1990.0]), np.array([1000.0, 1000.0, 1000.0]), 3.0, 2.0) == \
        pytest.approx(35.0)


def test_plots_per_type_drawn_from_the_runs_traces(results, tmp_path):
    """Issue 29 item 5: one Fig. 4-style PNG per shift type (transmission8_plots.write_plots, what --plots writes),
    drawn from traces that are the run's: trace_shift's quality dict is run_shift's, the quality's figures
    recomputed from the traces agree with it, and the plant recorded the currents the TCU commanded."""
    lib = t8._library()    # noqa: SLF001
    assert sorted(k for _, _, k in t8.PLOT_CASES) == sorted(t8.TYPES.values())
    traces = [t8.trace_shift("nominal", s, t, k, lib=lib) for s, t, k in t8.PLOT_CASES]
    paths = t8_plots.write_plots(tmp_path / "plots", traces)
    assert sorted(p.name for p in paths) == ["power-off-downshift.png", "power-off-upshift.png",
                                             "power-on-downshift.png", "power-on-upshift.png"]
    assert sorted((tmp_path / "plots").iterdir()) == sorted(paths)   # no temporary left behind
    for path in paths:
        data = path.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000, (path, len(data))
    for case, trace in zip(t8.PLOT_CASES, traces):
        q = trace.quality
        # the same run as run_shift's (the same seed): the same dict, NaN and the energy per element included
        assert json.dumps(q, sort_keys=True) == json.dumps(results[case], sort_keys=True), case
        truth, tcu, k0, end = trace.truth, trace.tcu, trace.request_index, trace.end_index
        dt = truth["t_s"][1] - truth["t_s"][0]
        assert end is not None and tcu["phase"].size == truth["t_s"].size - 1
        window = slice(k0 + 1, end + round(0.2 / dt) + 1)      # the quality's: the request to 0.2 s after the end
        jerk = np.gradient(_lowpass_zero_phase(truth["vehicle_accel_m_s2"], dt, JERK_CUTOFF_HZ), dt)
        # rel 1e-9: dt here is the record's time step, the quality's the plant's period (equal to rounding)
        assert float(np.max(np.abs(jerk[window]))) == pytest.approx(q["peak_jerk_m_s3"], rel=1e-9), case
        assert (end - k0) * dt == pytest.approx(q["duration_s"], rel=1e-9)
        on = trace.oncoming
        assert float(np.max(tcu[f"{on}_theta_degC"][k0:])) == q["peak_theta_estimate_degC"]
        assert float(np.max(truth[f"{on}_theta_degC"][window])) == q["peak_theta_truth_degC"]
        # truth row k + 1 holds the currents of period k: the TCU's commands (within both's ranges: exact)
        for e in t8.ELEMENTS:
            assert np.array_equal(truth[f"{e}_current_mA"][1:], tcu[f"{e}_current_mA"]), (case, e)
        assert trace.phase_changes()[0] == (k0, "prepare")
        assert t8.PHASES[int(tcu["phase"][end])] == "locked" and "inertia" in dict(trace.phase_changes()).values()
        assert q["oncoming"] == on != trace.offgoing


def test_plots_option_and_exit_codes(monkeypatch, tmp_path):
    """--plots: on with --matrix (OUT/plots) unless --no-plots; the matrix's exit code kept (1: a miss), 2 when a
    plotted shift cannot run (run_matrix and run_plots stubbed: the wiring only)."""
    calls = []
    monkeypatch.setattr(t8, "run_matrix", lambda out, *a: calls.append(("matrix", out)) or 1)
    monkeypatch.setattr(t8, "run_plots", lambda out, vehicle: calls.append(("plots", out, vehicle)) or [])
    assert t8.main(["--matrix", "--out", str(tmp_path)]) == 1
    assert calls == [("matrix", tmp_path), ("plots", tmp_path / "plots", "nominal")]
    calls.clear()
    assert t8.main(["--matrix", "--out", str(tmp_path), "--no-plots"]) == 1
    assert calls == [("matrix", tmp_path)]

    def refused(out, vehicle):
        raise t8.ShiftError("refused")
    monkeypatch.setattr(t8, "run_plots", refused)
    assert t8.main(["--matrix", "--out", str(tmp_path)]) == 2
    monkeypatch.setattr(t8, "run_matrix", lambda out, *a: 0)
    assert t8.main(["--matrix", "--out", str(tmp_path)]) == 2


def _user_box(tmp_path, *replace: tuple[str, str]) -> str:
    """The 8HP description copied outside the repository with text changes, and a plant file using it."""
    text = (t8.ROOT / "tools" / "gearboxes" / "8hp.toml").read_text()
    for old, new in replace:
        assert old in text
        text = text.replace(old, new)
    text = text.replace(
        'clutch_calibration = "../calibrations/table1.toml"',
        f'clutch_calibration = "{t8.ROOT / "tools" / "calibrations" / "table1.toml"}"')
    (tmp_path / "box.toml").write_text(text)
    (tmp_path / "plant.toml").write_text(f'extends = "{t8.ROOT / "tools" / "plants" / "8hp" / "nominal.toml"}"\n'
                                         f'gearbox = "{tmp_path / "box.toml"}"\n')
    return str(tmp_path / "plant.toml")


def test_the_tcu_runs_the_table_of_the_plants_own_gearbox_file(tmp_path):
    """Issue 29 item 1: a user's gearbox is a file anywhere, and the in-process TCU gets its table as a gearbox
    image generated from that file (not the compiled-in 8HP's): set 3's sun with 72 teeth instead of 69 moves
    the 5th and 7th ratios (measured), and the TCU's ratios are the plant's kinematics'; a 4->5 upshift
    completes in the new 5th. A box whose elements are not A..E is refused with the reason."""
    from wetclutch.calibration import gearbox_image
    from wetclutch.gearbox import kinematics
    plant = _user_box(tmp_path, ('sun_teeth = { value = 69,', 'sun_teeth = { value = 72,'))
    params = t8._plant_and_models(plant)[0]      # noqa: SLF001
    image = gearbox_image.read_image(t8.gearbox_image(str(params.gearbox.path)))
    nominal = gearbox_image.read_image(t8.gearbox_image(str(t8._plant_and_models(str(t8.plant_path("nominal")))[0].gearbox.path)))  # noqa: SLF001,E501
    for gear in range(1, 9):
        truth = float(kinematics.ratio(params.gearbox, str(gear)))
        # the image holds the table's 6 significant digits as a float
        assert image["gearbox.ratio"][gear] == pytest.approx(truth, rel=2e-6), gear
    moved = [g for g in range(1, 9) if abs(image["gearbox.ratio"][g] / nominal["gearbox.ratio"][g] - 1) > 1e-3]
    assert moved == [5, 7]
    r = t8.run_shift(plant, 4, 5, "power-on upshift")
    assert r["abort"] == 0 and r["end_gear"] == "5"
    (tmp_path / "renamed").mkdir()
    _user_box(tmp_path / "renamed", ('elements.E', 'elements.F'), ('"E"]', '"F"]'))
    with pytest.raises(t8.ShiftError, match="elements A, B, C, D, F; the in-process TCU"):
        t8.gearbox_image(str(tmp_path / "renamed" / "box.toml"))


@pytest.mark.parametrize("load", [0.25, 1.0])
def test_cold_powerup_into_a_closes_the_slip_the_model_overrates(load):
    """A power-on upshift into A at 20 degC (6->7): the TCU's model gives A's cold pack 1.6 times the torque it
    has at its kiss point (controller coordinates, 6.2 x A's slip). At full load the slip PI's integral, bound
    at 150 N m, could not ask for that error: the inertia phase timed out (AbortReason 1); at 25 % the inertia
    phase closed under the engine's reduction, and the lock-up's ramp to the holding margin, with no feedback,
    left A slipping at its kiss point as the engine's torque came back (AbortReason 2). The bound is 300 N m on
    the whole shift, the lock-up's integral goes on on the slip left, its ramp carries the error the integral
    found and the modelled drag that vanishes as the slip closes (wc_shift.c): both complete in 7th."""
    r = t8.run_shift("nominal", 6, 7, "power-on upshift", load=load, oil_degC=20.0)
    assert r["type"] == "power-on upshift"
    assert r["abort"] == 0 and r["end_gear"] == "7", r
    assert r["excursion_rpm"] <= 30.0, r  # no flare: the error is corrected by more torque, never by a release


def test_cold_kickdown_hands_over_without_the_offgoing_drag():
    """A part-load kickdown at 20 degC (7->5 at 25 %: A off-going, its slip at the new gear's speed some 280
    rad/s): in the hand-over A's request ramps to 0, and held at its kiss point its cold pack's drag fought the
    on-coming element, 51 m/s^3 of output jerk. It releases into its spring's band there as in the inertia phase
    (wc_shift_inertia_first.c): within the kickdown's 15 m/s^3."""
    r = t8.run_shift("nominal", 7, 5, "power-on downshift", load=0.25, oil_degC=20.0)
    assert r["type"] == "power-on downshift"
    assert r["abort"] == 0 and r["end_gear"] == "5", r
    assert r["peak_jerk_m_s3"] <= 15.0, r  # the kickdown's limit (issue 29); 5.7 measured, 51.2 before
    assert r["excursion_rpm"] <= 30.0, r


def test_coast_downshift_with_the_pedal_pressed_takes_the_drive_away_smoothly():
    """A coast downshift requested with the pedal pressed (the WLTC's 2->1 on the down line, the converter open,
    T_t 31 N m, below the power-on type's 50): the off-going element was released at once and the engine could
    only add torque, so the turbine ran ahead of the reference on its own (synchronised at 0.57 s of 2.0, flare
    93 rpm, 13.2 m/s^3; in the cycle such shifts failed to lock). The engine now takes the drive back to its
    zero torque and the off-going element ramps out with it, at WC_SHIFT_PRESSED_RATE_Nm_per_s."""
    r = t8.trace_shift("nominal", 2, 1, "power-off downshift", oil_degC=80.0, pedal=0.2, lockup_current_mA=0.0,
                       rpm=1300.0).quality
    assert r["type"] == "power-off downshift" and r["turbine_torque_Nm"] > 25.0, r   # the pedal pressed
    assert r["abort"] == 0 and r["end_gear"] == "1", r
    assert abs(r["inertia_time_s"] / r["target_s"] - 1.0) <= t8.INERTIA_TOLERANCE, r  # 1.99 of 2.0 (0.57 before)
    assert r["excursion_rpm"] <= t8.EXCURSION_RPM, r                                   # 0 (93 before)
    assert r["peak_jerk_m_s3"] <= t8.LIMITS_JERK["power-off downshift"], r             # 3.6 (13.2 before)


def test_cold_tipout_closes_the_slip_its_drag_holds_open():
    """A tip-out's hand-over at 20 degC (6->7: A on-coming at 6.2 x the controller's slip): at its kiss point A's
    viscous drag carried the engine's drag (T_t -21 N m) at 4 rad/s of its own slip, which never closed, and
    the shift ended in lock-up failed (AbortReason 2) although the plant reached 7th. The on-coming clutch is
    asked for that drag on top of what it holds (wc_shift_inertia_first.c), and the shift completes."""
    r = t8.run_shift("nominal", 6, 7, "power-off upshift", oil_degC=20.0)
    assert r["type"] == "power-off upshift"
    assert r["abort"] == 0 and r["end_gear"] == "7", r
    assert r["tie_up_fraction"] <= 0.10 and r["excursion_rpm"] <= 30.0



def _braking_2_1():
    """The drive cycle's 2->1 while braking to a stop (about 5 km/h, pedal 0, brake 700 N m at the wheels, the
    converter open): the idling engine's creep (T_t0 33 N m, below the power-on type's 50) drives the turbine."""
    return t8.trace_shift("nominal", 2, 1, "power-off downshift", oil_degC=80.0, pedal=0.0, lockup_current_mA=0.0,
                          rpm=480.0, brake_Nm=700.0).quality


def test_braking_coast_downshift_near_a_stop_locks():
    """Once the coast law released the off-going element, the creep ran the turbine up past the new gear's speed,
    and the on-coming element, corrected only for a turbine dragged back below it, never pulled it down: the
    lock-up failed (AbortReason 2) at 561 rpm past, as 12 of the nominal cycle's and 31 of the SUV's coast
    downshifts did. The hand-over's correction now takes the slip past synchronism on either side."""
    r = _braking_2_1()
    assert r["type"] == "power-off downshift" and r["turbine_torque_Nm"] > 25.0, r   # the creep drives
    assert r["abort"] == 0, r                                                          # 2 before
    assert r["excursion_rpm"] < 100.0, r                                               # 69 (561 before)


@pytest.mark.xfail(strict=True, reason=(
    "known miss: the shift locks (above) but the turbine crosses the new gear's speed in 0.18 s of the coast's 2 s "
    "(the idling engine cannot take its creep back) and runs 69 rpm past it (12.0 m/s^3); typed as a kickdown "
    "(the off-going element holding the turbine back) the same shift meets the coast's limits (4.8 m/s^3, "
    "29 rpm), but a kickdown cannot raise the turbine above the engine's speed (600 rpm in 2nd without the "
    "brake: the creep vanishes at 750 rpm, below 1st's 950): the type wants the engine speed, which the "
    "transmission does not get"))
def test_braking_coast_downshift_near_a_stop_meets_the_coast_limits():
    r = _braking_2_1()
    assert r["excursion_rpm"] <= t8.EXCURSION_RPM, r
    assert r["peak_jerk_m_s3"] <= t8.LIMITS_JERK["power-off downshift"], r
