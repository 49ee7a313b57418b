"""The 1->2 upshift plant (tools/wetclutch/simulate/plant, DESIGN 10): steady 1st gear, lock-up into 2nd,
energy bookkeeping, the hydraulic lag, determinism, tie-up, flare, the true clutch against the bench's,
and bad plant files."""
from __future__ import annotations

import math
import re
from dataclasses import replace

import numpy as np
import pytest

from wetclutch.simulate import bench, plant

RPM = plant.RPM
DT = plant.DT_S


@pytest.fixture(scope="module")
def params():
    return plant.load_plant(plant.DEFAULT_PLANT)


def run(params, current, *, n_pre=50, n_shift=1000, release=True, oil=80.0, torque=250.0, seed=None, **kw):
    """Pre-roll in 1st gear with the on-coming open, then n_shift periods after the shift command with
    current(s) mA (s: time since the command); the off-going released by its schedule if release."""
    pl = plant.UpshiftPlant(params, oil_degC=oil, turbine_torque_Nm=torque, seed=seed, **kw)
    sensors = [pl.sensors()]
    for _ in range(n_pre):
        pl.step(0.0, None)
        sensors.append(pl.sensors())
    for k in range(n_shift):
        s = k * DT
        pl.step(current(s), s if release else None)
        sensors.append(pl.sensors())
    return pl, pl.record(), sensors


def test_default_plant_loads(params):
    assert params.ratio_1st == 4.7 and params.ratio_2nd == 3.1
    assert params.clutch_cal.film_squeeze_factor > 0          # the true clutch, Reynolds film on
    assert params.release_start == 0.10 and params.release_time == 0.10
    assert params.vfs_time_constant == 0.06 and params.vfs_gain == 2300.0
    assert set(params.sources) == {name for _, name, _, _ in plant.SCHEMA}


def test_truth_and_sensor_channels(params):
    pl = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0)
    assert tuple(pl.truth) == plant.TRUTH_NAMES
    assert set(pl.sensors()) == {"slip_rpm", "oil_degC", "housing_degC", "turbine_torque_estimate_Nm"}
    assert pl.dt_s == 1e-3
    tr = pl.truth
    assert tr["turbine_speed_rpm"] == pytest.approx(2500.0)
    assert tr["gear1_speed_rpm"] == pytest.approx(2500.0)
    assert tr["gear2_speed_rpm"] == pytest.approx(2500.0 * 3.1 / 4.7)
    assert tr["oncoming_locked"] == 0.0 and tr["offgoing_locked"] == 1.0
    assert tr["pressure_Pa"] == 0.0 and tr["theta_clutch_degC"] == 80.0


def test_steady_first_gear(params):
    """On-coming open, no shift: the driveline starts in its steady 1st-gear state (no start transient),
    the off-going holds, and the on-coming slip grows only with the vehicle's acceleration."""
    pl, r, s = run(params, lambda s: 0.0, n_pre=300, n_shift=0)
    assert np.all(r["offgoing_locked"] == 1.0) and np.all(r["oncoming_locked"] == 0.0)
    assert np.max(np.abs(r["offgoing_slip_rad_s"])) < 1e-9
    ts = r["driveshaft_torque_Nm"]
    # pre-wound to the steady torque: T_s follows the rigid 1st-gear model (all inertias accelerating
    # together) with no shuffle (2.7 Hz) start transient; what is left (about 0.4 Nm) is the quasi-static
    # drift dT_s/dt / omega_shuffle of the road load and the open clutch's drag, which the start ignores
    p = params
    iv = p.vehicle_mass * p.wheel_radius ** 2
    ww = r["vehicle_speed_m_s"] / p.wheel_radius
    road = np.array([pl._road(w) for w in ww])
    j_w = iv + p.final_drive ** 2 * (p.output_inertia + p.turbine_inertia * p.ratio_1st ** 2)
    alpha = (p.final_drive * (p.ratio_1st * 250.0 - (p.ratio_1st - p.ratio_2nd) * r["clutch_torque_Nm"])
             - road) / j_w
    rigid = (iv * alpha + road) / p.final_drive
    assert np.max(np.abs(ts - rigid)) < 1e-3 * ts[0]
    assert np.ptp(ts) < 5e-3 * ts[0]
    acc = r["vehicle_accel_m_s2"]
    assert 3.0 < acc[0] < 8.0                              # full load in 1st gear
    assert np.ptp(acc) < 5e-3 * acc[0]
    # slip = (i1 - i2) w_o: its change is the integral of the vehicle's acceleration
    k = (params.ratio_1st - params.ratio_2nd) * params.final_drive / params.wheel_radius
    predicted = r["slip_rad_s"][0] + k * np.concatenate(([0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1])) * DT))
    assert np.max(np.abs(r["slip_rad_s"] - predicted)) < 1e-3 * r["slip_rad_s"][0]
    # the open clutch drags (film at h_max), a few Nm at 80 degC, and warms the pack a little
    assert 2.0 < r["clutch_torque_Nm"][0] < 20.0
    assert r["theta_clutch_degC"][-1] > r["theta_clutch_degC"][0]
    assert np.all(r["pressure_Pa"] == 0.0)


def test_locks_into_second_gear_and_stays(params):
    """Off-going released, on-coming at a constant high pressure: the slip goes to zero, the on-coming
    locks (w_t = i2 w_o) and stays locked."""
    pl, r, _ = run(params, lambda s: 600.0, n_shift=1200)
    locked = r["oncoming_locked"]
    first = int(np.argmax(locked > 0.5))
    assert first > 0 and np.all(locked[first:] == 1.0)
    t_lock = r["t_s"][first] - 50 * DT
    assert 0.1 < t_lock < 0.6
    after = slice(first, None)
    assert np.max(np.abs(r["slip_rad_s"][after])) < 1e-9
    np.testing.assert_allclose(r["turbine_speed_rpm"][after], r["gear2_speed_rpm"][after], rtol=1e-12)
    assert np.all(np.abs(r["clutch_torque_Nm"][after]) <= r["clutch_capacity_Nm"][after])
    assert np.all(r["offgoing_locked"][after] == 0.0) and np.all(r["offgoing_torque_Nm"][-100:] == 0.0)
    assert np.all(r["friction_power_W"][first + 1:] == 0.0)
    # the turbine torque drives 2nd gear: the driveshaft ends near i2 T_t less the inertia share
    assert 0.7 * 3.1 * 250 < r["driveshaft_torque_Nm"][-1] < 3.1 * 250


def test_friction_energy_bookkeeping(params):
    """The heat fed to eq. 1 equals the integral of |T_c| |slip| (1 ms samples) within 1 %, and the
    mechanical energy balance closes (turbine work = kinetic + spring energy + road + damping + friction)."""
    pl, r, _ = run(params, lambda s: 450.0, n_shift=800)
    heat = np.sum(r["friction_power_W"][1:]) * DT
    slipping = 1.0 - r["oncoming_locked"]
    integral = np.trapezoid(np.abs(r["clutch_torque_Nm"] * r["slip_rad_s"]) * slipping, dx=DT)
    assert heat > 1000.0
    assert heat == pytest.approx(integral, rel=0.01)

    p = params
    wt = r["turbine_speed_rpm"] * RPM
    wo = r["output_speed_rpm"] * RPM
    ww = r["vehicle_speed_m_s"] / p.wheel_radius
    iv = p.vehicle_mass * p.wheel_radius ** 2
    ts = r["driveshaft_torque_Nm"]
    twist_rate = wo - p.final_drive * ww
    phi = (ts - p.shaft_damping * twist_rate) / p.shaft_stiffness
    ke = (0.5 * p.turbine_inertia * wt ** 2 + 0.5 * p.output_inertia * wo ** 2 + 0.5 * iv * ww ** 2
          + 0.5 * p.shaft_stiffness * phi ** 2)
    road = p.final_drive * ts - iv * r["vehicle_accel_m_s2"] / p.wheel_radius
    e_in = np.trapezoid(r["turbine_torque_Nm"] * wt, dx=DT)
    e_road = np.trapezoid(road * ww, dx=DT)
    e_damp = np.trapezoid(p.shaft_damping * twist_rate ** 2, dx=DT)
    e_fric = heat + np.sum(r["offgoing_power_W"][1:]) * DT
    residual = e_in - e_road - e_damp - e_fric - (ke[-1] - ke[0])
    assert abs(residual) < 0.01 * e_fric


def test_pressure_follows_the_lag(params):
    """P follows K i through the first-order lag: 63.2 % after tau (within 2 %), settled after 5 tau."""
    pl, r, _ = run(params, lambda s: 500.0, n_pre=0, n_shift=1000)
    cmd = 500.0 * params.vfs_gain
    assert np.all(r["pressure_cmd_Pa"][1:] == cmd)
    n_tau = int(round(params.vfs_time_constant / DT))
    assert r["pressure_Pa"][n_tau] / cmd == pytest.approx(1.0 - math.exp(-1.0), rel=0.02)
    assert r["pressure_Pa"][5 * n_tau] / cmd == pytest.approx(1.0, abs=0.01)
    assert np.all(np.diff(r["pressure_Pa"]) >= 0.0)
    cal = params.clutch_cal
    assert r["apply_force_N"][-1] == pytest.approx(cmd * cal.piston_area - cal.return_spring_force, rel=3e-3)
    # the squeeze film hands the force to the asperities slowly near contact (h_bar^3 law): about 74 %
    # at 0.1 s, 95 % at 0.4 s, 99.7 % at 1 s under 5.1 kN at 80 degC; never more than the apply force
    ratio = r["contact_force_N"][1:] / np.maximum(r["apply_force_N"][1:], 1.0)
    assert np.all(ratio <= 1.0 + 1e-9)
    assert 0.5 < ratio[100] < 0.9
    assert ratio[-1] == pytest.approx(1.0, abs=0.01)


def test_current_is_clamped_and_checked(params):
    pl = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0)
    pl.step(5000.0, 0.0)
    assert pl.truth["current_mA"] == params.clutch_cal.vfs_current_max
    pl.step(-3.0, 0.001)
    assert pl.truth["current_mA"] == params.clutch_cal.vfs_current_min
    with pytest.raises(ValueError):
        pl.step(float("nan"), 0.002)


def test_deterministic(params):
    def current(s):
        return 0.0 if s < 0.02 else 700.0 if s < 0.08 else 350.0

    _, r1, s1 = run(params, current, n_shift=600, seed=7)
    _, r2, s2 = run(params, current, n_shift=600, seed=7)
    for c in plant.TRUTH_NAMES:
        assert np.array_equal(r1[c], r2[c]), c
    assert s1 == s2
    _, _, s3 = run(params, current, n_shift=600, seed=8)
    assert s3 != s1


def test_sensors_quantised_noisy_and_biased(params):
    _, r, sensors = run(params, lambda s: 0.0, n_pre=500, n_shift=0)
    slip = np.array([s["slip_rpm"] for s in sensors])
    oil = np.array([s["oil_degC"] for s in sensors])
    house = np.array([s["housing_degC"] for s in sensors])
    torque = np.array([s["turbine_torque_estimate_Nm"] for s in sensors])
    assert np.allclose(slip / 0.25, np.round(slip / 0.25), atol=1e-9)
    assert np.allclose(oil / 0.1, np.round(oil / 0.1), atol=1e-6)
    err = slip - r["slip_rad_s"] / RPM
    assert 0.3 < np.std(err) < 0.7 and abs(np.mean(err)) < 0.1
    assert np.mean(oil) == pytest.approx(80.0, abs=0.02)
    assert np.mean(house) == pytest.approx(80.0 + params.housing_offset, abs=0.02)
    assert np.mean(torque) == pytest.approx(250.0 * (1.0 + params.torque_estimate_bias), abs=0.2)


def test_tie_up(params):
    """The off-going never released and the on-coming applied hard: the off-going clutch is dragged
    backwards (negative torque: it fights the shift) and the output torque dips far below both gears'."""
    _, tie, _ = run(params, lambda s: 1000.0, n_shift=500, release=False)
    _, clean, _ = run(params, lambda s: 1000.0, n_shift=500, release=True)
    assert tie["offgoing_torque_Nm"].min() < -0.8 * tie["offgoing_capacity_Nm"][0] * params.kinetic_ratio
    assert np.any(tie["offgoing_slip_rad_s"] < -1.0)          # slipping backwards: tie-up
    ts0 = tie["driveshaft_torque_Nm"][0]
    assert tie["driveshaft_torque_Nm"].min() < 0.25 * ts0
    assert tie["driveshaft_torque_Nm"].min() < clean["driveshaft_torque_Nm"].min() - 100.0
    heat_tie = np.sum(tie["offgoing_power_W"]) * DT
    heat_clean = np.sum(clean["offgoing_power_W"]) * DT
    assert heat_tie > 5.0 * heat_clean


def test_flare(params):
    """Off-going released, no on-coming pressure: the turbine runs away from the 1st-gear speed (flare)."""
    _, r, _ = run(params, lambda s: 0.0, n_shift=500)
    release_end = 50 + int(round((params.release_start + params.release_time) / DT))
    assert np.all(r["offgoing_locked"][release_end:] == 0.0)
    assert r["turbine_speed_rpm"][-1] - r["gear1_speed_rpm"][-1] > 500.0
    assert r["slip_rad_s"][-1] > r["slip_rad_s"][release_end] + 50.0
    assert np.all(r["oncoming_locked"] == 0.0)


def test_heat_soak_start_and_friction_scale(params):
    pl = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0, theta_clutch_degC=120.0)
    assert pl.truth["theta_clutch_degC"] == 120.0
    for _ in range(20):
        pl.step(0.0, None)
    assert 80.0 < pl.truth["theta_clutch_degC"] < 120.0      # cooling towards the oil/housing
    # friction_scale scales the Coulomb part and the static capacity, not the viscous part
    hi = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0, friction_scale=1.1)
    lo = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0)
    assert hi.truth["clutch_capacity_Nm"] == pytest.approx(1.1 * lo.truth["clutch_capacity_Nm"], rel=1e-12)
    for p_ in (hi, lo):
        for k in range(150):
            p_.step(800.0, k * DT)
    assert hi.truth["turbine_speed_rpm"] < lo.truth["turbine_speed_rpm"]      # pulled down faster


def test_clutch_torque_matches_bench_physics(params):
    """The plant's scalar clutch equals bench._Physics.clutch (the bench's TRUE clutch) at its state."""
    pl = plant.UpshiftPlant(params, oil_degC=60.0, turbine_torque_Nm=200.0)
    for k in range(150):
        pl.step(400.0, k * DT)
    tr = pl.truth
    assert tr["oncoming_locked"] == 0.0
    phys = bench._Physics(params.clutch_cal, DT, 1.0, 1)
    total, coulomb, viscous, f_c, hbar, static = phys.clutch(np.array([tr["separation_m"]]),
                                                             np.array([abs(tr["slip_rad_s"])]),
                                                             np.array([tr["theta_clutch_degC"]]))
    assert tr["clutch_torque_Nm"] == pytest.approx(float(total[0]), rel=1e-12)
    assert tr["clutch_capacity_Nm"] == pytest.approx(float(static[0]), rel=1e-12)
    assert tr["contact_force_N"] == pytest.approx(float(f_c[0]), rel=1e-12)
    assert tr["hbar_m"] == pytest.approx(float(hbar[0]), rel=1e-12)


# --------------------------------------------------------------------------- bad plant files

def _write_variant(tmp_path, edit):
    text = plant.DEFAULT_PLANT.read_text(encoding="utf-8")
    cal = (plant.DEFAULT_PLANT.parent / "../calibrations/bench_true.toml").resolve()
    text = text.replace('"../calibrations/bench_true.toml"', f'"{cal.as_posix()}"')
    text = edit(text)
    path = tmp_path / "plant.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _set_line(name, new):
    pattern = re.compile(rf"^{name}\s*=.*$", re.MULTILINE)

    def edit(text):
        assert pattern.search(text), name
        return pattern.sub(new, text, count=1)
    return edit


@pytest.mark.parametrize("edit, key", [
    (_set_line("turbine_inertia", ""), "driveline.turbine_inertia"),
    (_set_line("output_inertia", 'output_inertia = { value = 0.1, unit = "kg*m2", source = "x" }'),
     "driveline.output_inertia"),
    (_set_line("shaft_stiffness", 'shaft_stiffness = { value = nan, unit = "N*m/rad", source = "x" }'),
     "driveline.shaft_stiffness"),
    (_set_line("vehicle_mass", 'vehicle_mass = { value = -1600.0, unit = "kg", source = "x" }'),
     "driveline.vehicle_mass"),
    (_set_line("ratio_2nd", 'ratio_2nd = { value = 5.0, unit = "1", source = "x" }'), "driveline.ratio_2nd"),
    (_set_line("release_time", 'release_time = { value = "0.1", unit = "s", source = "x" }'),
     "offgoing.release_time"),
    (_set_line("vfs_gain", 'vfs_gain = { value = 2300.0, unit = "Pa/mA" }'), "hydraulics.vfs_gain"),
    (_set_line("seed", 'seed = { value = 1.5, unit = "1", source = "x" }'), "scenario.seed"),
    (_set_line("kinetic_ratio", 'kinetic_ratio = { value = 1.5, unit = "1", source = "x" }'),
     "offgoing.kinetic_ratio"),
    (lambda t: t + '\n[driveline2]\nx = { value = 1, unit = "1", source = "x" }\n', "driveline2"),
    (lambda t: t.replace("[sensors]", '[sensors]\nbogus = { value = 1.0, unit = "1", source = "x" }'),
     "sensors.bogus"),
    (_set_line("calibration", 'calibration = "no_such_calibration.toml"'), "clutch.calibration"),
    (_set_line("calibration", ""), "clutch.calibration"),
])
def test_bad_plant_file(tmp_path, edit, key):
    path = _write_variant(tmp_path, edit)
    with pytest.raises(plant.PlantError, match=re.escape(key)):
        plant.load_plant(path)


def test_bad_plant_file_not_toml(tmp_path):
    path = tmp_path / "plant.toml"
    path.write_text("[driveline\nturbine_inertia = 1\n", encoding="utf-8")
    with pytest.raises(plant.PlantError, match="not valid TOML"):
        plant.load_plant(path)
    with pytest.raises(plant.PlantError, match="cannot read"):
        plant.load_plant(tmp_path / "missing.toml")


def test_variant_file_loads_like_the_default(tmp_path, params):
    path = _write_variant(tmp_path, lambda t: t)
    other = plant.load_plant(path)
    assert replace(other, path=params.path, calibration_path=params.calibration_path) == params


def test_initial_speed_for_the_shift_command(params):
    start = plant.initial_turbine_speed_rpm(params, oil_degC=80.0, turbine_torque_Nm=250.0)
    assert start < params.turbine_speed - 300.0            # full load in 1st: about 2500 rpm/s
    pl = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0, turbine_speed_rpm=start)
    for _ in range(int(round(params.preroll_time / DT))):
        pl.step(0.0, None)
    assert pl.truth["turbine_speed_rpm"] == pytest.approx(params.turbine_speed, abs=0.1)
