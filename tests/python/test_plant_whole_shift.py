"""The plant of the whole 1->2 upshift (issue 22, DESIGN 14): the off-going clutch on its own VFS, the engine's
torque intervention, the on-coming fill against the return spring, the off-going slip sensor, the vehicle
family (extends=) and the vehicles' driveline calibrations generated from their plant files."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from wetclutch.shift import vehicle_cal
from wetclutch.simulate import plant

DT = plant.DT_S
VEHICLES = Path(plant.DEFAULT_PLANT).parent / "vehicles"
FAMILY = ("heavy", "light", "newuser", "nominal", "soft", "step1.3", "step1.75", "stiff", "torque350")


@pytest.fixture(scope="module")
def base():
    return plant.load_plant(plant.DEFAULT_PLANT)


@pytest.fixture(scope="module")
def nominal():
    return plant.load_plant(VEHICLES / "nominal.toml")


def _run(pl, n, current, shift_at=50, **step_kw):
    sensors = [pl.sensors()]
    for k in range(n):
        s = (k - shift_at) * DT if k >= shift_at else None
        pl.step(current(s) if s is not None else 0.0, s, **step_kw)
        sensors.append(pl.sensors())
    return pl.record(), sensors


# ------------------------------------------------------------------ the old plant unchanged
def test_default_plant_keeps_the_old_behaviour(base):
    assert base.fill_volume == 0.0 and base.engine_delay == 0.0
    assert base.engine_torque_max == pytest.approx(1.2 * base.turbine_torque_full) and base.engine_torque_min == 0.0
    assert base.offgoing_cal == base.clutch_cal and base.offgoing_friction_scale == 1.0
    assert (base.offgoing_vfs_gain, base.offgoing_vfs_time_constant) == (base.vfs_gain, base.vfs_time_constant)
    assert set(base.sources) == {n for _, n, _, _ in plant.SCHEMA}
    assert plant.TRUTH_NAMES[-7:] == ("engine_torque_Nm", "engine_request_Nm", "offgoing_current_mA",
                                      "offgoing_pressure_Pa", "fill_fraction", "output_torque_Nm", "vfs_pressure_Pa")


def test_new_inputs_none_bit_identical(base):
    def current(s):
        return 300.0 + 600.0 * min(s / 0.2, 1.0)
    kw = dict(oil_degC=80.0, turbine_torque_Nm=250.0)
    rec_a, sens_a = _run(plant.UpshiftPlant(base, **kw), 300, current)
    pl = plant.UpshiftPlant(base, **kw)
    sens_b = [pl.sensors()]
    for k in range(300):
        s = (k - 50) * DT if k >= 50 else None
        pl.step(current(s) if s is not None else 0.0, s, None, None)
        sens_b.append(pl.sensors())
    rec_b = pl.record()
    for c in plant.TRUTH_NAMES:
        assert np.array_equal(rec_a[c], rec_b[c]), c
    assert sens_a == sens_b
    assert set(sens_a[0]) == {"slip_rpm", "oil_degC", "housing_degC", "turbine_torque_estimate_Nm"}
    assert np.array_equal(rec_a["engine_torque_Nm"], rec_a["turbine_torque_Nm"])
    assert not rec_a["engine_request_Nm"].any() and (rec_a["fill_fraction"] == 1.0).all()
    # the off-going slip sensor has its own noise: the old sensors stay bit for bit
    pl = plant.UpshiftPlant(base, offgoing_slip_sensor=True, **kw)
    _, sens_c = _run(pl, 300, current)
    assert [{k: v for k, v in s.items() if k != "offgoing_slip_rpm"} for s in sens_c] == sens_a
    rec_c = pl.record()
    off = np.array([s["offgoing_slip_rpm"] for s in sens_c])
    assert np.abs(off - rec_c["offgoing_slip_rad_s"] / plant.RPM).max() < 3.0      # 0.5 rpm noise, 0.25 steps


# ------------------------------------------------------------------ engine
def test_engine_follows_a_request_with_its_lag_and_limits(nominal):
    p = dataclasses.replace(nominal, engine_delay=0.0)
    pl = plant.UpshiftPlant(p, oil_degC=80.0, turbine_torque_Nm=250.0, offgoing_current_mA=1000.0)
    n_tau = int(round(p.engine_time_constant / DT))
    for _ in range(n_tau):
        pl.step(0.0, None, 1000.0, 30.0)
    tr = pl.truth
    assert tr["engine_request_Nm"] == 30.0
    assert tr["engine_torque_Nm"] == pytest.approx(250.0 + 30.0 * (1.0 - math.exp(-1.0)), rel=1e-9)
    assert tr["turbine_torque_Nm"] == tr["engine_torque_Nm"]
    est = pl.sensors()["turbine_torque_estimate_Nm"]
    assert est == pytest.approx(tr["engine_torque_Nm"] * (1.0 + p.torque_estimate_bias), abs=6.0)
    for _ in range(1000):
        pl.step(0.0, None, 1000.0, 500.0)          # far above the maximum
    assert pl.truth["engine_torque_Nm"] == pytest.approx(p.engine_torque_max, abs=1e-2)
    for _ in range(1000):
        pl.step(0.0, None, 1000.0, -500.0)         # below zero
    assert pl.truth["engine_torque_Nm"] == pytest.approx(p.engine_torque_min, abs=1e-2)


def test_engine_dead_time(nominal):
    assert nominal.engine_delay == 0.01
    pl = plant.UpshiftPlant(nominal, oil_degC=80.0, turbine_torque_Nm=250.0, offgoing_current_mA=1000.0)
    for _ in range(10):
        pl.step(0.0, None, 1000.0, -50.0)
    assert pl.truth["engine_torque_Nm"] == 250.0
    pl.step(0.0, None, 1000.0, -50.0)
    assert pl.truth["engine_torque_Nm"] < 250.0


def test_engine_ignores_request(nominal):
    pl = plant.UpshiftPlant(nominal, oil_degC=80.0, turbine_torque_Nm=250.0, offgoing_current_mA=1000.0,
                            engine_ignores_request=True)
    for _ in range(200):
        pl.step(0.0, None, 1000.0, -100.0)
    rec = pl.record()
    assert (rec["engine_torque_Nm"] == 250.0).all()
    assert (rec["engine_request_Nm"][1:] == -100.0).all()


# ------------------------------------------------------------------ off-going clutch
def test_offgoing_holds_with_a_high_current_and_flares_at_the_minimum(nominal):
    pl = plant.UpshiftPlant(nominal, oil_degC=80.0, turbine_torque_Nm=250.0, offgoing_current_mA=1000.0)
    assert set(pl.sensors()) >= {"offgoing_slip_rpm"}
    assert pl.truth["offgoing_capacity_Nm"] == pytest.approx(900.0, rel=0.01)
    assert pl.truth["offgoing_pressure_Pa"] == 2300.0 * 1000.0
    for _ in range(200):
        pl.step(0.0, None, 1000.0)
    tr = pl.truth
    assert tr["offgoing_locked"] == 1.0
    assert tr["turbine_speed_rpm"] == pytest.approx(tr["gear1_speed_rpm"], abs=1e-6)
    assert tr["output_torque_Nm"] == pytest.approx(nominal.ratio_1st * tr["offgoing_torque_Nm"]
                                                   + nominal.ratio_2nd * tr["clutch_torque_Nm"], rel=1e-9)
    assert 0.0 < tr["clutch_torque_Nm"] < 0.1 * tr["offgoing_torque_Nm"]        # the open clutch's drag
    for _ in range(300):
        pl.step(0.0, 0.0, 0.0)                      # the current to its minimum, the on-coming open: flare
    rec = pl.record()
    tr = pl.truth
    assert tr["offgoing_locked"] == 0.0 and tr["offgoing_capacity_Nm"] == 0.0
    assert tr["turbine_speed_rpm"] - tr["gear1_speed_rpm"] > 500.0
    assert pl.sensors()["offgoing_slip_rpm"] == pytest.approx(tr["offgoing_slip_rad_s"] / plant.RPM, abs=3.0)
    # the capacity falls with the pressure's lag: still holding shortly after the drop
    assert rec["offgoing_locked"][205] == 1.0


# ------------------------------------------------------------------ fill
def _fill_time_ms(params, current_mA):
    pl = plant.UpshiftPlant(params, oil_degC=80.0, turbine_torque_Nm=250.0, offgoing_current_mA=1000.0)
    k = 0
    while pl.truth["fill_fraction"] < 1.0 and k < 1000:
        assert pl.truth["apply_force_N"] == 0.0 and pl.truth["contact_force_N"] < 1.0
        pl.step(current_mA, k * DT, 1000.0)
        k += 1
    return k, pl


def test_fill_pulse_and_kiss_current(nominal):
    p_kiss = nominal.clutch_cal.return_spring_force / nominal.clutch_cal.piston_area
    n_pulse, pl = _fill_time_ms(nominal, 500.0)
    n_kiss, _ = _fill_time_ms(nominal, 1.2 * p_kiss / nominal.vfs_gain)
    assert 30 <= n_pulse <= 40
    assert 110 <= n_kiss <= 130
    rec = pl.record()
    filling = rec["fill_fraction"] < 1.0
    assert (rec["apply_force_N"][filling] == 0.0).all()
    assert (rec["pressure_Pa"][filling] <= p_kiss + 1e-6).all()       # the spring's pressure while filling
    assert (np.diff(rec["fill_fraction"]) >= 0.0).all()
    for _ in range(20):
        pl.step(500.0, None, 1000.0)
    assert pl.truth["apply_force_N"] > 0.0
    for _ in range(300):                          # the current off: the piston retracts
        pl.step(0.0, None, 1000.0)
    assert pl.truth["fill_fraction"] < 0.5 and pl.truth["apply_force_N"] == 0.0


def test_fill_below_the_spring_preload_never_fills(nominal):
    p_kiss = nominal.clutch_cal.return_spring_force / nominal.clutch_cal.piston_area
    pl = plant.UpshiftPlant(nominal, oil_degC=80.0, turbine_torque_Nm=250.0)
    for k in range(300):
        pl.step(0.7 * p_kiss / nominal.vfs_gain, k * DT)
    assert pl.truth["fill_fraction"] == 0.0


# ------------------------------------------------------------------ plant files: extends, the family
def _entry(value, unit):
    return f'{{ value = {value}, unit = "{unit}", source = "test" }}'


def test_extends_overrides_and_keeps_paths(tmp_path, base):
    sub = tmp_path / "deep"
    sub.mkdir()
    child = sub / "child.toml"
    child.write_text(f'extends = "{Path(plant.DEFAULT_PLANT).as_posix()}"\n[driveline]\n'
                     f'vehicle_mass = {_entry(2000.0, "kg")}\n[hydraulics]\nfill_volume = {_entry(1e-5, "m^3")}\n',
                     encoding="utf-8")
    p = plant.load_plant(child)
    assert p.vehicle_mass == 2000.0 and p.fill_volume == 1e-5
    assert p.sources["vehicle_mass"] == "test" and p.sources["ratio_1st"] == base.sources["ratio_1st"]
    assert p.calibration_path == base.calibration_path and p.clutch_cal == base.clutch_cal
    assert dataclasses.replace(p, vehicle_mass=base.vehicle_mass, fill_volume=0.0, path=base.path) == base


def test_extends_errors(tmp_path):
    a, b = tmp_path / "a.toml", tmp_path / "b.toml"
    a.write_text('extends = "missing.toml"\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match=r"a\.toml: 'extends': base plant file .*missing\.toml not found"):
        plant.load_plant(a)
    a.write_text('extends = "b.toml"\n', encoding="utf-8")
    b.write_text('extends = "a.toml"\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match="'extends' loop"):
        plant.load_plant(a)
    a.write_text('extends = "a.toml"\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match="'extends' loop"):
        plant.load_plant(a)
    a.write_text('extends = 3\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match="'extends' must be the path"):
        plant.load_plant(a)
    b.write_text(f'extends = "{Path(plant.DEFAULT_PLANT).as_posix()}"\n[engine]\n'
                 f'engine_delay = {_entry(0.0015, "s")}\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match="engine.engine_delay.*whole number"):
        plant.load_plant(b)
    b.write_text(f'extends = "{Path(plant.DEFAULT_PLANT).as_posix()}"\n[engine]\n'
                 f'engine_torque_min = {_entry(400.0, "N*m")}\n', encoding="utf-8")
    with pytest.raises(plant.PlantError, match="engine.engine_torque_min"):
        plant.load_plant(b)


def test_vehicle_family(nominal):
    files = sorted(f.stem for f in VEHICLES.glob("*.toml"))
    assert tuple(files) == FAMILY
    for name in FAMILY:
        p = plant.load_plant(VEHICLES / f"{name}.toml")
        assert p.fill_volume > 0.0 and p.clutch_cal == nominal.clutch_cal, name
        assert all(s.strip() for s in p.sources.values())
        assert not any(s.startswith("default:") for s in p.sources.values()), name
    nu = plant.load_plant(VEHICLES / "newuser.toml")
    assert (nu.vehicle_mass, nu.ratio_1st / nu.ratio_2nd, nu.turbine_torque_full) == (2000.0, pytest.approx(1.75), 320.0)
    assert nu.shaft_stiffness == pytest.approx(0.6 * nominal.shaft_stiffness)


def test_vehicle_calibrations_regenerate_byte_identically(tmp_path):
    written = vehicle_cal.generate_all(VEHICLES, tmp_path)
    committed = sorted(vehicle_cal.OUT_DIR.glob("*.toml"))
    assert [w.name for w in written] == [c.name for c in committed] == [f"{n}.toml" for n in FAMILY]
    for w, c in zip(written, committed):
        assert w.read_bytes() == c.read_bytes(), c.name


def test_vehicle_driveline_fields(nominal):
    f = vehicle_cal.driveline_fields(nominal)
    assert f == {"turbine_inertia_kg_m2": 0.25, "turbine_ratio": 1.0,
                 "output_inertia_kg_m2": pytest.approx(0.1 + 1600 * 0.31 ** 2 / 3.2 ** 2, rel=1e-5),
                 "output_ratio": 3.1, "offgoing_ratio": 4.7,
                 "jerk_per_torque_rate": pytest.approx(3.1 * 3.2 / (1600 * 0.31), rel=1e-5)}
    assert vehicle_cal.main([str(VEHICLES / "nonexistent"), "--out", "/nonexistent"]) == 1
