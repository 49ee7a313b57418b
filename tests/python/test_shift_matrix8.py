"""The 8-speed's power-on upshifts with today's whole-shift controller (issue 29 item 5; tools/wetclutch/shift/
matrix8.py): the equivalent clutch of an element in the controller's coordinates against the element's own clutch
(the reference model), the images wc_replay gets, wc_replay --offgoing-calibration-image, and three closed-loop
upshifts of the nominal vehicle at full load: 1->2 (E on, C off), 3->4 (D on, a > 0; C off, a < 0) and 5->6
(both elements slipping backwards, a < 0), each against issue 29's targets from the plant's truth.

A missed target is an xfail(strict) with the measured figure, so that meeting it later fails the test and the
marker has to go. About 10 s.

Rerun the whole matrix (1->2 ... 7->8 at 100 and 25 % load, the three vehicles; about 40 s on two cores):
    .venv/bin/python -m wetclutch.shift.matrix8_report --out out/matrix8"""
from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import built_program
from wetclutch import gearbox
from wetclutch.calibration import cal_image
from wetclutch.calibration.parameters import f32
from wetclutch.reference import model as ref
from wetclutch.shift import matrix8
from wetclutch.util import canlog

ROOT = Path(__file__).resolve().parents[2]
GEARBOX = ROOT / "tools" / "gearboxes" / "8hp.toml"
SHIFTS = (1, 3, 5)          # from-gear of the closed-loop upshifts at full load


@pytest.fixture(scope="module")
def wc_replay() -> Path:
    return built_program("host-release", "src/host/wc_replay")


@pytest.fixture(scope="module")
def models():
    return matrix8._plant_and_models(str(matrix8.plant_path("nominal")))[1]     # noqa: SLF001


@pytest.fixture(scope="module")
def records(wc_replay):
    """The closed-loop records of SHIFTS on the nominal vehicle, full load, 80 degC (about 5 s each)."""
    return {g: matrix8.run_upshift_record("nominal", g, 1.0) for g in SHIFTS}


@pytest.fixture(scope="module")
def qualities(records):
    return {g: matrix8.quality8(rec) for g, rec in records.items()}


# ---------------------------------------------------------------------------------------------- the mapping
def _equivalent(cal, a):
    """The element's calibration as matrix8's equivalent clutch in double (radii x |a|, phi / a^4)."""
    s = abs(a)
    return cal.with_values(outer_radius=cal.outer_radius * s, inner_radius=cal.inner_radius * s,
                           film_squeeze_factor=cal.film_squeeze_factor / s ** 4)


@pytest.mark.parametrize("element, a", [("A", 6.21739), ("B", -3.51458), ("C", -1.52475), ("E", 1.5)])
def test_the_equivalent_clutch_is_the_element_times_a(element, a):
    """For every slip, temperature and force the equivalent clutch at slip / |a| carries |a| x the element's
    torque (Coulomb and viscous: the sliding speed is the element's) and |a| x its static capacity; the inverse
    of |a| T at slip / |a| is the element's current for T; the friction power and the squeeze film's Reynolds
    factor x phi are the element's. To 1e-12 in double (the firmware's float rounds the radii once more)."""
    cal = gearbox.load(GEARBOX).element(element).calibration
    eq = _equivalent(cal, a)
    s = abs(a)
    slip_rpm = np.array([1.0, 30.0, 300.0, 1500.0, 2500.0])
    for theta in (40.0, 80.0, 120.0):
        for force in (0.0, 50.0, 500.0, 3000.0):
            el = ref.torque_parts(cal, slip_rpm, theta, force)
            q = ref.torque_parts(eq, slip_rpm / s, theta, force)
            assert np.allclose(q["torque_Nm"], s * el["torque_Nm"], rtol=1e-12, atol=0.0)
            assert np.allclose(q["torque_Nm"] * slip_rpm / s, el["torque_Nm"] * slip_rpm, rtol=1e-12)   # power
        assert ref.static_capacity_Nm(eq, theta, 800.0) == pytest.approx(s * ref.static_capacity_Nm(cal, theta, 800.0),
                                                                         rel=1e-12)
        inv_el = ref.inverse(cal, slip_rpm, theta, 40.0)
        inv_eq = ref.inverse(eq, slip_rpm / s, theta, 40.0 * s)
        assert np.allclose(inv_eq["current_mA"], inv_el["current_mA"], rtol=1e-9)
    phi = 0.1
    assert phi / s ** 4 * ref.reynolds_factor_m4(eq) == pytest.approx(phi * ref.reynolds_factor_m4(cal), rel=1e-9)


def test_the_images_carry_each_element_in_the_controller_s_coordinates(tmp_path, models):
    """6->7 (A on, a = 6.2; E off, a = -2.6): the on-coming image the element's clutch with radii x |a|, its own
    heat capacity (not the loader's from the larger annulus), lock bands unscaled (the measured slip's), and the
    shift calibration whole_full with the row's reduced model; the off-going image E's clutch, shift off."""
    m = models["6-7"]
    on_path, off_path = matrix8.write_images(tmp_path, m, GEARBOX)
    on, off = cal_image.read_file(on_path), cal_image.read_file(off_path)
    gb = gearbox.load(GEARBOX)
    for values, name, a in ((on, "A", m.oncoming_slip_scale), (off, "E", m.offgoing_slip_scale)):
        cal = gb.element(name).calibration
        assert values["clutch.outer_radius_m"] == f32(f32(cal.outer_radius) * abs(a))
        assert values["clutch.inner_radius_m"] == f32(f32(cal.inner_radius) * abs(a))
        assert values["clutch.heat_capacity_J_per_K"] == f32(cal.heat_capacity)
        assert values["clutch.piston_area_m2"] == f32(cal.piston_area)
        assert values["clutch.return_spring_force_N"] == f32(cal.return_spring_force)
        assert values["clutch.friction_pairs"] == cal.friction_pairs
        assert values["clutch.lock_slip_rad_s"] == f32(cal.lock_slip)
    assert on["loop.shift_enabled"] == 1 and off["loop.shift_enabled"] == 0
    assert on["shift.output_ratio"] == f32(m.output_ratio) and on["shift.offgoing_ratio"] == f32(m.offgoing_ratio)
    assert on["shift.turbine_ratio"] == 1.0 and on["shift.coordinator"] == 1
    assert on["shift.turbine_inertia_kg_m2"] == f32(m.turbine_inertia)


# ---------------------------------------------------------------------------------------------- wc_replay
def _replay(program, log: Path, *args) -> tuple[int, list[tuple[int, str]], str]:
    """wc_replay on log with the closed loop's start temperature (the oil's): exit code, frames, stderr."""
    res = subprocess.run([str(program), str(log), "--theta-start", "80", *map(str, args)], capture_output=True,
                         text=True)
    frames = []
    for line in res.stdout.splitlines():
        ident, data = line.split()[2].split("#")
        frames.append((int(ident, 16), data))
    return res.returncode, frames, res.stderr


def test_offgoing_calibration_image(wc_replay, records, models, tmp_path):
    """wc_replay --offgoing-calibration-image: the 1->2's inputs replayed open loop give the closed loop's frames
    bit for bit with the two images; with the on-coming image alone (the off-going an instance of E's clutch, not
    C's) the off-going commands differ, and an off-going image of E's clutch gives exactly that; an image with
    shift control on, or no whole shift, is refused (exit 2, one line)."""
    rec, m = records[1], models["1-2"]
    log = tmp_path / "inputs.log"
    canlog.write_log(log, [(k * 1e-3, canlog.can.Message(arbitration_id=fid, data=data, is_extended_id=False))
                           for k, frames in enumerate(rec["frames_in"]) for fid, data in frames])
    on, off = matrix8.write_images(tmp_path, m, GEARBOX)
    rc, both, err = _replay(wc_replay, log, "--calibration-image", on, "--offgoing-calibration-image", off)
    assert rc == 0, err
    assert both == [(fid, data) for _, fid, data in rec["frames"]]
    rc, alone, err = _replay(wc_replay, log, "--calibration-image", on)
    assert rc == 0, err
    off_id = canlog.database().get_message_by_name(canlog.OFFGOING_COMMAND).frame_id
    assert [f for f in alone if f[0] == off_id] != [f for f in both if f[0] == off_id]
    same = tmp_path / "e_alone.img"
    cal_image.write_file(same, {**matrix8.equivalent_clutch_values(GEARBOX, "E", m.oncoming_slip_scale),
                                **cal_image._shift_values(None), **cal_image.loop_values(None, False)})  # noqa: SLF001
    rc, as_default, err = _replay(wc_replay, log, "--calibration-image", on, "--offgoing-calibration-image", same)
    assert rc == 0, err
    assert as_default == alone
    rc, _, err = _replay(wc_replay, log, "--calibration-image", on, "--offgoing-calibration-image", on)
    assert rc == 2 and "carries shift control" in err and err.count("\n") == 1
    rc, _, err = _replay(wc_replay, log, "--offgoing-calibration-image", off)
    assert rc == 2 and "needs shift control with the coordinator" in err
    rc, _, err = _replay(wc_replay, log, "--calibration-image", on, "--offgoing-calibration-image", tmp_path / "none")
    assert rc == 2 and f"--offgoing-calibration-image {tmp_path / 'none'}: No such file" in err   # the option named


# ---------------------------------------------------------------------------------------------- closed loop
@pytest.mark.parametrize("g", SHIFTS)
def test_the_controller_sees_the_element_slips_divided_by_a(records, g):
    """The plant's on-coming and off-going element slips / a are the controller's w_t - b w_o and w_t - b1 w_o
    (the sign of a handled: 3->4's C and 5->6's both elements slip backwards), and the held elements stay locked
    by truth through the shift at full current (matrix8: held at their maximum, for now)."""
    rec = records[g]
    m, t = rec["model"], rec["truth"]
    rpm = math.pi / 30.0
    w_t, w_o = t["turbine_speed_rpm"] * rpm, t["output_speed_rpm"] * rpm
    scale = np.max(np.abs(w_t))
    assert np.max(np.abs(rec["true_slip_rad_s"] - (w_t - m.output_ratio * w_o))) <= 1e-9 * scale
    assert np.max(np.abs(rec["true_offgoing_slip_rad_s"] - (w_t - m.offgoing_ratio * w_o))) <= 1e-9 * scale
    k0 = rec["command_step"]
    assert rec["true_slip_rad_s"][k0] > 30.0                   # an upshift's slip: positive for the controller
    for e in m.held:
        assert t[f"{e}_locked"].min() == 1.0, e


# known misses: (shift, target) -> reason with the measured figure (out/matrix8/matrix8.md has them all)
KNOWN_MISSES = {
    (3, "tie_up"): "missed: 14.6 % of the input torque (target 10 %): late in the torque phase D's torque (a = 2.5) "
                   "runs ahead, C slips 1.8 rad/s forward, the flare correction re-applies C (222 mA) and C holds "
                   "-35 N*m against D at the inertia phase's start (+292 ms; D 278 N*m at the turbine, T_t 237)",
}
TARGET_CHECKS = {
    "completes_in_target_gear": lambda q: q["abort"] == 0 and q["end_gear"] == q["shift"].split("->")[1],
    "jerk": lambda q: q["peak_jerk_m_s3"] <= matrix8.TARGETS["jerk_m_s3"],
    "flare": lambda q: q["flare_rpm"] <= matrix8.TARGETS["flare_rpm"],
    "tie_up": lambda q: q["tie_up_fraction"] <= matrix8.TARGETS["tie_up_fraction"],
    "inertia_time": lambda q: abs(q["inertia_time_error"]) <= matrix8.TARGETS["time_tolerance"],
}


def _cases():
    for g in SHIFTS:
        for name in TARGET_CHECKS:
            reason = KNOWN_MISSES.get((g, name))
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            yield pytest.param(g, name, marks=marks, id=f"{g}-{g + 1}-{name}")


@pytest.mark.parametrize("g, target", list(_cases()))
def test_issue_29_targets_at_full_load(qualities, g, target):
    q = qualities[g]
    assert TARGET_CHECKS[target](q), {k: q[k] for k in ("abort_reason", "end_gear", "peak_jerk_m_s3", "flare_rpm",
                                                        "tie_up_fraction", "inertia_time_s", "missed")}


def test_quality_vector_per_shift(qualities, models):
    """The quality vector's parts are there and plausible: every element's friction energy (the on-coming the
    largest, the held ones none), the on-coming's peak temperature estimate within 2 K of its truth."""
    for g, q in qualities.items():
        e = q["energy_kJ"]
        assert set(e) == set("ABCDE")
        assert max(e, key=lambda n: abs(e[n])) == q["oncoming"]
        held = set(models[f"{g}-{g + 1}"].held)
        assert all(abs(e[n]) < 1e-6 for n in held)
        assert abs(q["peak_theta_estimate_degC"] - q["peak_theta_truth_degC"]) <= 2.0
        assert q["torque_phase_jerk_m_s3"] > 0.0 and q["peak_inertia_jerk_m_s3"] > 0.0
