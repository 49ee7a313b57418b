"""The bench simulator (tools/wetclutch/bench.py, DESIGN 7): campaign, engagement
(paper Fig. 15), film transient, steady state against the model, thermal
energy balance, CAN logs, bad input, and the ASC/BLF converter."""
from __future__ import annotations

import math
import os
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from wetclutch import bench, calibration, canlog, cli, model
from wetclutch.csvio import read_columns
from wetclutch.errors import LogError


@pytest.fixture(scope="module")
def true_cal():
    return calibration.load(bench.DEFAULT_TRUE)


@pytest.fixture(scope="module")
def engagement(tmp_path_factory):
    """The three engagements as bundled in hil/logs (seed 1), files and results."""
    out = tmp_path_factory.mktemp("engagement")
    run = bench.run("engagement", out, seed=1)
    return out, {r.experiment.slip_rpm: r for r in run["results"]}


# --------------------------------------------------------------------------- the true parameters

def test_true_parameters_differ_from_table1_by_a_few_percent(true_cal, cal):
    changed = {k for k in cal.values if cal.values[k] != true_cal.values[k]}
    assert {"mu1", "mu2", "mu3", "stribeck_speed", "oil_conductance", "housing_conductance",
            "asperity_density"} <= changed
    assert changed & {"mv1", "mv2", "mv3", "mv4"}
    for k in changed:
        rel = abs(true_cal.values[k] / cal.values[k] - 1.0)
        assert 0.005 <= rel <= 0.06, (k, rel)
    for k in changed:
        assert "bench truth" in true_cal.sources[k]


# --------------------------------------------------------------------------- the campaign

def test_campaign_has_184_experiments_as_table2():
    exps = bench.table2_experiments()
    assert len(exps) == 184 == bench.TABLE2_COUNT
    assert len({e.name for e in exps}) == 184 and [e.id for e in exps] == list(range(1, 185))
    for e in exps:
        assert e.force_N in (903.0, 1076.0, 1350.0, 1613.0) and e.loading_s in (5.0, 10.0)
        if e.theta0_degC <= 30.0:
            assert e.force_N == 903.0
        if e.theta0_degC == 10.0:
            assert e.slip_rpm in (100.0, 200.0)
    assert sorted({e.theta0_degC for e in exps}) == [float(t) for t in range(10, 101, 10)]
    assert sum(e.theta0_degC == 10.0 for e in exps) == 4
    assert sum(e.theta0_degC > 30.0 for e in exps) == 7 * 24


def test_campaign_files_for_all_184(tmp_path):
    """All 184 through the file writer (0.2 s each, to keep the test short)."""
    exps = [replace(e, duration_s=0.2) for e in bench.table2_experiments()]
    out = bench.run("table2", tmp_path, seed=3, experiments=exps)
    index = (tmp_path / "index.csv").read_text().splitlines()
    assert index[0] == "id,force_N,pressure_kPa,slip_rpm,loading_s,theta0_degC,file"
    assert len(index) == 185
    assert index[1].startswith("1,903.0,222.8,100,5,10,t2_001_")
    rows = [line.split(",") for line in index[1:]]
    kpa = sorted({float(r[2]) for r in rows})                                 # F / A_f
    assert kpa == pytest.approx([222.8, 265.4, 333.1, 397.9], abs=0.11)        # Table 2 (rounded there)
    assert all((tmp_path / r[6]).is_file() for r in rows)
    assert len(out["files"]) == 184 + 2
    visc = (tmp_path / "viscosity.csv").read_text().splitlines()
    assert visc[0] == "theta_degC,viscosity_Pa_s" and [int(v.split(",")[0]) for v in visc[1:]] == list(range(10, 121, 10))


def test_campaign_experiments_full_length(tmp_path, true_cal):
    """Two of the 184 at full length (the coldest and the hardest): ramp, hold, 20 s ramp
    down, motor off at zero, locked."""
    picks = [e for e in bench.table2_experiments() if e.id in (1, 183)]
    assert [(e.force_N, e.slip_rpm, e.loading_s, e.theta0_degC) for e in picks] == [
        (903.0, 100.0, 5.0, 10.0), (1613.0, 300.0, 5.0, 100.0)]
    out = bench.run("table2", tmp_path, seed=1, experiments=picks)
    for r in out["results"]:
        e, tr = r.experiment, r.truth
        cols = read_columns(open(tmp_path / f"{e.name}.csv"), bench.CSV_COLUMNS, e.name)
        assert len(cols["t_s"]) == round(e.duration_s / 0.01)                    # 10 ms rows
        assert np.allclose(np.diff(cols["t_s"]), 0.01)
        t = r.t_s
        hold = (t > bench.CAMPAIGN_HOLD_S + 0.5) & (t < bench.CAMPAIGN_HOLD_S + e.loading_s)
        assert np.all(np.abs(tr["slip_rpm"][hold] - e.slip_rpm) < 2.0)
        assert np.all(np.abs(tr["force_N"][t > 1.0] - e.force_N) < 1e-6)
        t_zero = bench.CAMPAIGN_HOLD_S + e.loading_s + bench.CAMPAIGN_RAMP_DOWN_S
        mid = np.argmin(np.abs(t - (t_zero - 10.0)))
        assert tr["slip_rpm"][mid] == pytest.approx(e.slip_rpm / 2, abs=3.0)     # linear ramp down
        assert tr["locked"][-1] == 1.0 and tr["motor_torque_Nm"][-1] == 0.0
        assert np.max(np.abs(tr["motor_torque_Nm"])) < BenchLimits.motor
        assert tr["theta_degC"].max() > e.theta0_degC + 3.0                      # the loading heats the pack


class BenchLimits:
    motor = bench.BenchConfig().motor_torque_limit_Nm


# --------------------------------------------------------------------------- reproducibility

def test_seeded_reproducibility(true_cal):
    exps = [replace(e, duration_s=1.2) for e in bench.engagement_experiments((750.0,))]
    a = bench.simulate(true_cal, exps, seed=7)[0]
    b = bench.simulate(true_cal, exps, seed=7)[0]
    c = bench.simulate(true_cal, exps, seed=8)[0]
    for col in bench.CSV_COLUMNS:
        assert np.array_equal(a.measured[col], b.measured[col])
    assert not np.array_equal(a.measured["torque_Nm"], c.measured["torque_Nm"])
    assert np.max(np.abs(a.truth["torque_Nm"] - c.truth["torque_Nm"])) < 2.0    # only the noise differs
    # An experiment gives the same numbers alone or in a batch.
    both = bench.simulate(true_cal, [replace(e, duration_s=1.2) for e in bench.engagement_experiments()], seed=7)
    assert np.array_equal(both[0].measured["torque_Nm"], a.measured["torque_Nm"])


def test_bundled_logs_regenerate(root, tmp_path):
    """hil/logs/README.md's command regenerates the bundled files byte-identically (750 rpm here)."""
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "bench", "engagement", "--out", str(tmp_path),
                        "--seed", "1", "--true", "tools/calibrations/bench_true.toml", "--slip", "750"],
                       cwd=root, capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(root / "tools")))
    assert r.returncode == 0, r.stderr
    for name in ("engagement_750rpm.log", "engagement_750rpm.csv"):
        assert (tmp_path / name).read_bytes() == (root / "hil" / "logs" / name).read_bytes(), name
    assert "--out hil/logs --seed 1" in (root / "hil" / "logs" / "README.md").read_text()


# --------------------------------------------------------------------------- the engagement (Fig. 15)

def test_engagement_750(engagement):
    r = engagement[1][750.0]
    f = bench.engagement_figures(r)
    assert f["t_contact_s"] == pytest.approx(0.9, abs=0.005)
    assert f["t_lock_s"] == pytest.approx(1.9, abs=0.3)
    assert 150.0 <= f["peak_torque_Nm"] <= 200.0
    assert 40.0 <= f["peak_viscous_Nm"] <= 70.0                                  # paper 54.6 Nm
    t, tr = r.t_s, r.truth
    assert np.all(tr["slip_rpm"][t < 0.9] > 740.0)                              # speed held before contact
    assert np.all(tr["motor_torque_Nm"][t >= 0.9] == 0.0)                      # motor off from contact
    after = t > f["t_lock_s"]
    assert np.all(tr["slip_rpm"][after] == 0.0) and np.all(tr["locked"][after] == 1.0)
    # After lock the shaft rings down to nothing (motor off): Fig. 15's vibration.
    late = t > f["t_lock_s"] + 0.3
    assert np.max(np.abs(tr["torque_Nm"][late])) < 1.0
    ring = (t > f["t_lock_s"]) & (t < f["t_lock_s"] + 0.1)
    assert tr["torque_Nm"][ring].min() < 0.0 < tr["torque_Nm"][ring].max()


def test_engagement_slower_speeds_lock_earlier(engagement):
    figs = {s: bench.engagement_figures(r) for s, r in engagement[1].items()}
    assert figs[250.0]["t_lock_s"] < figs[500.0]["t_lock_s"] < figs[750.0]["t_lock_s"]
    assert figs[250.0]["peak_viscous_Nm"] < figs[500.0]["peak_viscous_Nm"] < figs[750.0]["peak_viscous_Nm"]


def test_film_transient_lags_by_the_time_constant(engagement, true_cal):
    r = engagement[1][750.0]
    t, tr = r.t_s, r.truth
    tau = bench.BenchConfig().film_time_constant_s
    # Once the force has settled (15 ms lag; 0.2 s after the step) h - h_ss decays as exp(-t/tau).
    i0, i1 = np.searchsorted(t, [1.1, 1.1 + tau])
    gap = tr["separation_m"] - tr["separation_ss_m"]
    assert gap[i0] > 0.0
    assert gap[i1] / gap[i0] == pytest.approx(math.exp(-(t[i1] - t[i0]) / tau), rel=1e-3)
    rate = np.polyfit(t[i0:i0 + 100], np.log(gap[i0:i0 + 100]), 1)[0]
    assert rate == pytest.approx(-1.0 / tau, rel=2e-3)
    # The true h_bar lags the steady-state one: above it after contact, converged after ~9 tau.
    hbar_ss = model.film_thickness_m(true_cal, tr["separation_ss_m"])
    window = (t > 0.92) & (t < 1.2)
    assert np.all(tr["hbar_m"][window] > hbar_ss[window])
    assert tr["hbar_m"][i0 + int(tau / 1e-3)] - hbar_ss[i0] > 0.1e-6
    settled = t > 0.9 + 9 * tau
    assert np.max(np.abs(tr["hbar_m"][settled] / hbar_ss[settled] - 1.0)) < 1e-3


def test_steady_state_torque_is_the_model_with_the_true_parameters(engagement, true_cal, cal):
    """With the film settled (11 tau after contact) the bench is eq. 8 with the true
    parameters: within 0.05 Nm (the dense film table and the residual film lag).
    (250 rpm locks 0.52 s after contact, before that: not used here.)"""
    tau = bench.BenchConfig().film_time_constant_s
    for slip in (750.0, 500.0):
        r = engagement[1][slip]
        t, tr = r.t_s, r.truth
        sel = (t > 0.9 + 11 * tau) & (tr["locked"] < 0.5) & (tr["slip_rpm"] > 10.0)
        assert sel.sum() > 100, slip
        true_model = model.torque_parts(true_cal, tr["slip_rpm"][sel], tr["theta_degC"][sel], tr["force_N"][sel])
        assert np.max(np.abs(true_model["torque_Nm"] - tr["torque_Nm"][sel])) < 0.05, slip
        assert np.max(np.abs(true_model["viscous_Nm"] - tr["viscous_Nm"][sel])) < 0.05, slip
        # Table 1 is not the bench: a few Nm off.
        table1 = model.torque_parts(cal, tr["slip_rpm"][sel], tr["theta_degC"][sel], tr["force_N"][sel])["torque_Nm"]
        assert 1.0 < np.sqrt(np.mean((table1 - tr["torque_Nm"][sel]) ** 2)) < 5.0, slip


def test_thermal_model_energy_balance(engagement, true_cal):
    """C dtheta/dt = P - k1 (theta - theta_oil) - k2 (theta - theta_housing), eq. 1 with the true values."""
    k1, k2, c = true_cal.oil_conductance, true_cal.housing_conductance, true_cal.heat_capacity
    for r in engagement[1].values():
        tr = r.truth
        dt = 1e-3
        mid = 0.5 * (tr["theta_degC"][1:] + tr["theta_degC"][:-1])
        lhs = c * np.diff(tr["theta_degC"]) / dt
        rhs = tr["power_W"][:-1] - k1 * (mid - tr["theta_oil_degC"][:-1]) - k2 * (mid - tr["theta_housing_degC"][:-1])
        assert np.max(np.abs(lhs - rhs)) < 1e-3 * np.max(np.abs(tr["power_W"])) + 1e-6
        # The heat is the clutch torque times the slip.
        slipping = tr["locked"] < 0.5
        p = np.abs(tr["clutch_torque_Nm"] * tr["slip_rpm"] * model.RAD_S_PER_RPM)
        assert np.allclose(tr["power_W"][slipping], p[slipping], rtol=1e-9, atol=1e-9)


def test_thermal_runs_recover_k1_k2_from_the_true_states(true_cal):
    """The Fig. 13 runs (shortened): constant force, steps of slip; eq. 19 on the true states gives k1, k2."""
    exps = [replace(e, duration_s=25.0) for e in bench.thermal_experiments(1)]
    results = bench.simulate(true_cal, exps, seed=1, every=10)
    small = results[0]
    t, tr = small.t_s, small.truth
    levels = np.unique(np.round(tr["slip_rpm"][t > 5.0]))
    assert len(levels) > 3                                                      # several steps
    assert np.all(np.abs(tr["force_N"][t > 1.0] - bench.THERMAL_FORCE_N) < 1e-6)
    rows, rhs = [], []
    for r in results:
        tr = r.truth
        sel = r.t_s > 3.0
        dth = np.gradient(tr["theta_degC"], 0.01)
        rhs.append((tr["power_W"] - true_cal.heat_capacity * dth)[sel])
        rows.append(np.column_stack([tr["theta_degC"] - tr["theta_oil_degC"],
                                     tr["theta_degC"] - tr["theta_housing_degC"]])[sel])
    k, *_ = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)
    assert k[0] == pytest.approx(true_cal.oil_conductance, rel=0.02)
    assert k[1] == pytest.approx(true_cal.housing_conductance, rel=0.05)


# --------------------------------------------------------------------------- files and CAN logs

def test_csv_columns_and_log_decode_to_the_csv(engagement):
    out, results = engagement
    steps = {"SlipSpeed": 0.25, "OilTemp": 0.1, "HousingTemp": 0.1, "TorqueRequest": 0.05,
             "LoadCellForce": 0.1, "MeasuredTorque": 0.01, "ClutchThermistorTemp": 0.1}
    pairs = ((canlog.SENSORS, "SlipSpeed", "slip_rpm"), (canlog.SENSORS, "OilTemp", "theta_oil_degC"),
             (canlog.SENSORS, "HousingTemp", "theta_housing_degC"),
             (canlog.REQUEST, "TorqueRequest", "torque_request_Nm"),
             (canlog.BENCH, "LoadCellForce", "force_N"), (canlog.BENCH, "MeasuredTorque", "torque_Nm"),
             (canlog.BENCH, "ClutchThermistorTemp", "theta_clutch_degC"))
    for slip in results:
        name = f"engagement_{slip:g}rpm"
        header = (out / f"{name}.csv").read_text().splitlines()[0]
        assert header == "t_s,slip_rpm,force_N,torque_Nm,theta_clutch_degC,theta_oil_degC,theta_housing_degC,torque_request_Nm"
        csv = read_columns(open(out / f"{name}.csv"), bench.CSV_COLUMNS, name)
        messages = canlog.read_log(out / f"{name}.log")
        assert len(messages) == 3 * 2500
        assert [m.arbitration_id for m in messages[:3]] == [0x111, 0x130, 0x110]
        frames = canlog.decode(messages)
        assert frames["_unknown"]["count"] == 0 and frames["_malformed"]["count"] == 0
        for frame, signal, column in pairs:
            assert len(frames[frame][signal]) == 2500
            assert np.max(np.abs(frames[frame][signal] - csv[column])) <= steps[signal], (name, signal)
        mode = frames[canlog.REQUEST]["Mode"]
        before = csv["t_s"] < 0.9 - 1e-9
        assert np.all(mode[before] == canlog.MODE_OPEN) and np.all(mode[~before] == canlog.MODE_TORQUE_CONTROL)
        stamps = frames[canlog.SENSORS]["_t"]
        assert np.allclose(np.diff(stamps), 1e-3)
        assert np.all(csv["torque_request_Nm"] >= 0.0)


def test_torque_request_is_the_filtered_measured_torque(engagement):
    r = engagement[1][750.0]
    m = r.measured
    a = math.exp(-1e-3 / bench.BenchConfig().request_filter_s)
    y = np.empty_like(m["torque_Nm"])
    y[0] = m["torque_Nm"][0]
    for k in range(1, y.size):
        y[k] = m["torque_Nm"][k] + (y[k - 1] - m["torque_Nm"][k]) * a
    assert np.allclose(m["torque_request_Nm"], np.maximum(y, 0.0), atol=1e-9)


def test_sensor_noise_levels(engagement):
    r = engagement[1][750.0]
    m, tr, t = r.measured, r.truth, r.t_s
    cfg = bench.BenchConfig()
    assert np.std(m["force_N"] - tr["force_N"]) == pytest.approx(cfg.load_cell_noise_N, rel=0.1)
    assert np.std(m["torque_Nm"] - tr["torque_Nm"]) == pytest.approx(cfg.torque_noise_Nm, rel=0.1)
    assert np.std(m["slip_rpm"] - tr["slip_rpm"]) == pytest.approx(cfg.speed_noise_rpm, rel=0.1)
    # The thermistor lags the clutch while it heats.
    heating = (t > 1.0) & (t < 1.5)
    assert np.all(m["theta_clutch_degC"][heating] < tr["theta_degC"][heating])


# --------------------------------------------------------------------------- bad input

def test_unknown_experiment(tmp_path, capsys):
    with pytest.raises(bench.BenchError, match="unknown experiment 'fig99'"):
        bench.run("fig99", tmp_path)
    with pytest.raises(SystemExit) as e:
        cli.main(["bench", "fig99", "--out", str(tmp_path)])
    assert e.value.code == 2 and "invalid choice: 'fig99'" in capsys.readouterr().err


@pytest.mark.parametrize("seed, message", [("-1", "seed -1 is negative"), ("abc", "seed 'abc' is not a whole number"),
                                           ("1.5", "seed '1.5' is not a whole number")])
def test_bad_seed(tmp_path, capsys, seed, message):
    assert cli.main(["bench", "engagement", "--out", str(tmp_path / "out"), "--seed", seed]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_unwritable_output_directory(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    target = blocker / "sub"
    assert cli.main(["bench", "engagement", "--out", str(target), "--slip", "250"]) == 2
    err = capsys.readouterr().err
    assert str(target) in err and "cannot write" in err


def test_bad_slip_and_true_file(tmp_path, capsys):
    assert cli.main(["bench", "engagement", "--out", str(tmp_path), "--slip", "0"]) == 2
    assert "out of range" in capsys.readouterr().err
    assert cli.main(["bench", "table2", "--out", str(tmp_path), "--slip", "100"]) == 2
    assert "engagement only" in capsys.readouterr().err
    assert cli.main(["bench", "engagement", "--out", str(tmp_path), "--true", str(tmp_path / "nope.toml")]) == 2
    assert "nope.toml" in capsys.readouterr().err


# --------------------------------------------------------------------------- convert

def _asc_from(messages, path):
    import can
    with can.ASCWriter(str(path)) as writer:
        for m in messages:
            writer.on_message_received(can.Message(timestamp=m.timestamp, arbitration_id=m.arbitration_id,
                                                   data=bytes(m.data), is_extended_id=m.is_extended_id, channel=0))


def test_convert_asc_round_trip(engagement, tmp_path, capsys):
    import can
    original = canlog.read_log(engagement[0] / "engagement_750rpm.log")[:600]
    extra = can.Message(timestamp=original[-1].timestamp + 1e-3, arbitration_id=0x1ABCDEF, data=b"\x01\x02\x03",
                        is_extended_id=True)
    asc = tmp_path / "bench.asc"
    _asc_from(original + [extra], asc)
    out = tmp_path / "bench.log"
    assert cli.main(["convert", str(asc), str(out)]) == 0
    assert "601 frames" in capsys.readouterr().out
    back = canlog.read_log(out)
    assert len(back) == 601
    t0 = original[0].timestamp
    for a, b in zip(original + [extra], back):
        assert (a.arbitration_id, bytes(a.data), a.is_extended_id) == (b.arbitration_id, bytes(b.data), b.is_extended_id)
        assert b.timestamp == pytest.approx(a.timestamp - t0, abs=2e-6)
    assert out.read_text().splitlines()[0].split()[1:] == ["vcan0", "111#" + bytes(original[0].data).hex().upper()]
    # The converted frames decode like the originals.
    assert np.array_equal(canlog.decode(back[:600])[canlog.SENSORS]["SlipSpeed"],
                          canlog.decode(original)[canlog.SENSORS]["SlipSpeed"])


def test_convert_blf(engagement, tmp_path):
    import can
    original = canlog.read_log(engagement[0] / "engagement_250rpm.log")[:90]
    blf = tmp_path / "bench.blf"
    with can.BLFWriter(str(blf)) as writer:
        for m in original:
            writer.on_message_received(can.Message(timestamp=m.timestamp, arbitration_id=m.arbitration_id,
                                                   data=bytes(m.data), channel=0))
    stats = bench.convert_log(blf, tmp_path / "blf.log")
    back = canlog.read_log(tmp_path / "blf.log")
    assert stats["frames"] == len(back) == 90
    assert [bytes(m.data) for m in back] == [bytes(m.data) for m in original]


def test_convert_malformed_asc(engagement, tmp_path, capsys):
    asc = tmp_path / "bench.asc"
    _asc_from(canlog.read_log(engagement[0] / "engagement_750rpm.log")[:20], asc)
    lines = asc.read_text().splitlines()
    bad_line = next(i for i, line in enumerate(lines) if " Rx " in line) + 3
    fields = lines[bad_line - 1].split()
    fields[-1] = "ZZ"
    lines[bad_line - 1] = " ".join(fields)
    bad = tmp_path / "broken.asc"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out.log"
    assert cli.main(["convert", str(bad), str(out)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and f"line {bad_line}" in err
    assert not out.exists()
    garbage = tmp_path / "garbage.asc"
    garbage.write_text("this is not\na vector log\n")
    with pytest.raises(LogError, match="garbage.asc: no CAN data frames"):
        bench.convert_log(garbage, out)
    with pytest.raises(LogError, match="expected a Vector .asc or .blf"):
        bench.convert_log(tmp_path / "x.trc", out)
    assert not out.exists()
