"""wetclutch identify: recovery on synthetic data, bad input, the calibration it writes.

The synthetic campaign comes from the reference model (model.py) with a known
"true" parameter set that differs from Table 1: steady film (eq. 16), the
thermal model of eq. 1 driven by the model torque, a first-order thermistor
lag and Gaussian sensor noise. It is a reduced Table 2 (3 forces, short
ramps, 100 Hz), so the whole file runs in well under 40 s.

When the bench simulator (tools/wetclutch/simulate/bench) is present, one test runs
the full chain on a reduced subset of its Table 2 campaign; the full 184-run
campaign is measured by test_full_campaign, which only runs with
WC_IDENTIFY_FULL=1 (see its docstring).
"""
from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from wetclutch import calibration, identify
from wetclutch.generate import lut
from wetclutch.reference import model

ROOT = Path(__file__).resolve().parents[2]
TABLE1 = ROOT / "tools" / "calibrations" / "table1.toml"
COLUMNS = ("t_s", "slip_rpm", "force_N", "torque_Nm", "theta_clutch_degC", "theta_oil_degC",
           "theta_housing_degC", "torque_request_Nm")

TRUE = {  # the synthetic bench's "true" parameters (Table 1 changed by a few per cent)
    "mu1": 0.1210, "mu2": 0.0925, "mu3": 0.5500, "stribeck_speed": 0.0262,
    "oil_conductance": 115.0, "housing_conductance": 45.0, "asperity_density": 1.9e7,
    "mv1": 0.160, "mv2": -0.0800, "mv3": 0.0560, "mv4": -0.0215,
}
LAG_S = 0.4          # thermistor time constant
NOISE = {"slip_rpm": 0.05, "force_N": 3.0, "torque_Nm": 0.3, "theta": 0.05}
RATE_HZ = 100.0


def true_cal():
    return calibration.load(TABLE1).with_values(**TRUE)


def _thermal_loop(cal, dt, slip, force, oil, housing, theta0, lag_s):
    """Eq. 1 (exact ZOH) with the model torque; returns torque, surface and thermistor temperature."""
    rn = cal.effective_radius * cal.friction_pairs
    k1, k2, c = cal.oil_conductance, cal.housing_conductance, cal.heat_capacity
    a = math.exp(-(k1 + k2) * dt / c)
    b = math.exp(-dt / lag_s)
    hbar = model.hbar_from_pressure_m(cal, np.asarray(force, float) / cal.friction_area)
    n = slip.size
    torque, theta, sensor = np.empty(n), np.empty(n), np.empty(n)
    th = sens = theta0
    for k in range(n):
        v = cal.effective_radius * abs(slip[k]) * model.RAD_S_PER_RPM
        mu_f = (cal.mu1 + (cal.mu2 - cal.mu1) * math.exp(-v / cal.stribeck_speed)) * (
            1.0 + cal.mu3 * (th - cal.theta1) / cal.theta2)
        mu_v = cal.mv1 * math.exp(cal.mv2 * th) + cal.mv3 * math.exp(cal.mv4 * th)
        tq = rn * (mu_f * force[k] + mu_v * cal.friction_area * v / hbar[k]) if slip[k] != 0 else \
            0.6 * rn * mu_f * force[k]   # stuck: some static torque below the capacity
        torque[k], theta[k], sensor[k] = tq, th, sens
        power = tq * abs(slip[k]) * model.RAD_S_PER_RPM
        steady = (power + k1 * oil[k] + k2 * housing[k]) / (k1 + k2)
        th_next = steady + (th - steady) * a
        sens = 0.5 * (th + th_next) + (sens - 0.5 * (th + th_next)) * b
        th = th_next
    return torque, theta, sensor


def friction_run(cal, rng, force_N, slip_rpm, loading_s, theta0, ramp_down_s=6.0, rate=RATE_HZ):
    """Table 2 style: force from t=0, ramp to speed at 0.5-1 s, hold, ramp down, 0.5 s at rest."""
    dt = 1.0 / rate
    t_end = 1.0 + loading_s + ramp_down_s + 0.5
    t = np.arange(0.0, t_end, dt)
    slip = np.interp(t, [0, 0.5, 1.0, 1.0 + loading_s, 1.0 + loading_s + ramp_down_s, t_end],
                     [0, 0, slip_rpm, slip_rpm, 0, 0])
    force = np.full(t.size, float(force_N))
    oil = np.full(t.size, float(theta0))
    housing = theta0 + 0.02 * t
    torque, _, sensor = _thermal_loop(cal, dt, slip, force, oil, housing, float(theta0), LAG_S)
    return _noisy(rng, t, slip, force, torque, sensor, oil, housing)


def thermal_run(cal, rng, seconds=150.0, small=True, rate=RATE_HZ):
    """Fig. 13 style: slip-speed steps at 903 N, oil and housing temperatures moving independently."""
    dt = 1.0 / rate
    t = np.arange(0.0, seconds, dt)
    levels = [60, 120, 40, 160, 80, 140, 20, 100] if small else [0, 300, 0, 250, 50]
    period = 6.0 if small else 25.0
    slip = np.array([levels[int(x // period) % len(levels)] for x in t], float)
    force = np.full(t.size, 903.0)
    oil = 40.0 + 8.0 * np.sin(2 * np.pi * t / 90.0)
    housing = 55.0 - 12.0 * np.exp(-t / 50.0)
    torque, _, sensor = _thermal_loop(cal, dt, slip, force, oil, housing, 45.0, LAG_S)
    return _noisy(rng, t, slip, force, torque, sensor, oil, housing)


def _noisy(rng, t, slip, force, torque, sensor, oil, housing):
    n = t.size
    return {
        "t_s": t,
        "slip_rpm": slip + np.where(slip != 0, rng.normal(0, NOISE["slip_rpm"], n), 0.0),
        "force_N": force + rng.normal(0, NOISE["force_N"], n),
        "torque_Nm": torque + rng.normal(0, NOISE["torque_Nm"], n),
        "theta_clutch_degC": sensor + rng.normal(0, NOISE["theta"], n),
        "theta_oil_degC": oil + rng.normal(0, NOISE["theta"], n),
        "theta_housing_degC": housing + rng.normal(0, NOISE["theta"], n),
        "torque_request_Nm": np.zeros(n),
    }


def write_run(path: Path, run: dict, columns=COLUMNS) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(columns)
        src = [run[c] for c in columns]
        for row in zip(*src):
            w.writerow(["nan" if isinstance(x, float) and math.isnan(x) else f"{x:.6g}" for x in row])


def write_index(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["id", "force_N", "pressure_kPa", "slip_rpm", "loading_s", "theta0_degC",
                                          "file"], lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow(r)


def write_viscosity(path: Path, cal, rng) -> None:
    theta = np.arange(0.0, 121.0, 10.0)
    mu = model.viscosity_Pa_s(cal, theta) * (1 + rng.normal(0, 0.005, theta.size))
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["theta_degC", "viscosity_Pa_s"])
        for a, b in zip(theta, mu):
            w.writerow([f"{a:g}", f"{b:.6g}"])


def make_campaign(root: Path, seed=1, forces=(903.0, 1350.0, 1613.0), speeds=(100, 300), temps=(20, 50, 80),
                  loading=(3.0,), thermal=True):
    rng = np.random.default_rng(seed)
    cal = true_cal()
    (root / "table2").mkdir(parents=True, exist_ok=True)
    rows = []
    for f in forces:
        for sp in speeds:
            for ld in loading:
                for th in temps:
                    ident = f"t2_{int(f)}N_{sp}rpm_{ld:g}s_{th}C"
                    write_run(root / "table2" / f"{ident}.csv", friction_run(cal, rng, f, sp, ld, th))
                    rows.append({"id": ident, "force_N": f, "pressure_kPa": round((f + 593.3) / 4.981, 1),
                                 "slip_rpm": sp, "loading_s": ld, "theta0_degC": th, "file": f"{ident}.csv"})
    write_index(root / "table2" / "index.csv", rows)
    write_viscosity(root / "table2" / "viscosity.csv", cal, rng)
    if thermal:
        (root / "thermal").mkdir(exist_ok=True)
        trows = []
        for name, small in (("small_steps", True), ("large_steps", False)):
            write_run(root / "thermal" / f"{name}.csv", thermal_run(cal, rng, small=small))
            trows.append({"id": name, "force_N": 903.0, "file": f"{name}.csv"})
        write_index(root / "thermal" / "index.csv", trows)
    return root


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    return make_campaign(tmp_path_factory.mktemp("synthetic"))


def write_true_toml(path: Path) -> Path:
    base = calibration.load(TABLE1)
    text = identify.render_calibration(TABLE1, base, TRUE, {k: "synthetic truth (test_identify.py)" for k in TRUE},
                                       "# synthetic bench truth\n")
    path.write_text(text)
    return path


def _run(step, data, **kw):
    return identify.run(step, Path(data), calibration.load(TABLE1), identify.Settings(jobs=1, **kw))


def _rel(a, b):
    return abs(a / b - 1.0)


# --------------------------------------------------------------------------- recovery

def test_recovery_all_steps(campaign):
    """Known parameters back within the stated tolerances (noise: 0.3 Nm, 3 N, 0.05 rpm, 0.05 K)."""
    res = _run("all", campaign)
    got = identify.identified_values(res)
    for name in ("mu1", "mu2", "mu3", "stribeck_speed", "oil_conductance", "housing_conductance"):
        assert _rel(got[name], TRUE[name]) < 0.03, (name, got[name], TRUE[name])   # the 3 % target
    assert _rel(got["asperity_density"], TRUE["asperity_density"]) < 0.05            # N: 5 %
    th = np.linspace(0, 120, 50)                                                      # viscosity curve: 2 %
    fitted = model.viscosity_Pa_s(calibration.load(TABLE1).with_values(**{k: got[k] for k in ("mv1", "mv2", "mv3", "mv4")}), th)
    assert np.max(np.abs(fitted / model.viscosity_Pa_s(true_cal(), th) - 1)) < 0.02
    assert res.results["mu"]["r2"] >= 0.985
    assert abs(res.results["thermal"]["thermistor_lag_s"] - LAG_S) < 0.1 * LAG_S
    # every excluded sample is accounted for: the ends at rest are 'static', nothing else here
    assert {e.reason for e in res.exclusions if e.step == "friction"} <= {"static", "film"}


@pytest.mark.parametrize("step, changed", [
    ("thermal", {"oil_conductance", "housing_conductance"}),
    ("viscosity", {"mv1", "mv2", "mv3", "mv4"}),
    ("asperity", {"asperity_density"}),
    ("mu", {"mu1", "mu2", "mu3", "stribeck_speed"}),
])
def test_each_step_alone(campaign, step, changed):
    """Each step on its own; mu takes viscosity and N from the calibration it is given (the "current" one:
    here the true ones, as after the viscosity and asperity steps), the others need nothing else."""
    base = calibration.load(TABLE1)
    if step == "mu":
        base = base.with_values(**{k: TRUE[k] for k in ("mv1", "mv2", "mv3", "mv4", "asperity_density")})
    res = identify.run(step, campaign, base, identify.Settings(jobs=1))
    got = identify.identified_values(res)
    assert set(got) == changed
    if step in ("mu", "asperity", "thermal"):   # the thermistor lag is found without the thermal step too
        lag = res.results[step]["thermistor_lag_s"]
        assert abs(lag - LAG_S) < 0.15 * LAG_S, lag
    if step == "asperity":
        assert _rel(got["asperity_density"], TRUE["asperity_density"]) < 0.1
    if step in ("mu", "thermal"):
        for name in changed:
            assert _rel(got[name], TRUE[name]) < 0.03, (name, got[name])


def test_cli_chain_calibration_loads_and_makes_lut(campaign, tmp_path):
    """bench data -> identify all -> calibration.toml -> wetclutch lut, as a user runs it."""
    out = tmp_path / "id"
    truth = write_true_toml(tmp_path / "true.toml")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "tools")}
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "identify", "all", str(campaign), "--calibration",
                        str(TABLE1), "--out", str(out), "--true", str(truth)], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr + r.stdout
    cal = calibration.load(out / "calibration.toml")
    assert "identified from" in cal.sources["mu1"] and "identified from" in cal.sources["asperity_density"]
    assert cal.sources["friction_area"] == calibration.load(TABLE1).sources["friction_area"]
    fig = identify.json.loads((out / "figures.json").read_text())
    assert all(fig["targets"].values()), fig["targets"]
    assert fig["mu"]["paper_r2"] == 0.9858 and fig["mu"]["paper_rmse"] == 0.002102
    for png in ("fig11a_mu_vs_slip.png", "fig11b_mu_vs_temperature.png", "fig11c_mu_surface.png", "fig12_mu_grid.png",
                "thermal_eq19.png", "viscosity_eq2.png", "asperity_hbar.png"):
        assert (out / png).stat().st_size > 10000, png
    text = (out / "report.md").read_text()
    assert "0.9858" in text and "0.002102" in text and "static" in text
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "lut", str(out / "calibration.toml"), "--out",
                        str(tmp_path / "lut"), "--name", "identified"], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    header = (tmp_path / "lut" / "wc_identified_calibration.h").read_text()
    assert lut.c_float(cal.mu1) in header


# --------------------------------------------------------------------------- bad input

@pytest.fixture()
def small(tmp_path):
    """Four friction runs (two forces, two temperatures), no thermal runs."""
    return make_campaign(tmp_path / "small", seed=5, forces=(903.0, 1613.0), speeds=(200,), temps=(30, 80),
                         thermal=False)


def _rewrite(path: Path, edit):
    rows = list(csv.reader(open(path, newline="")))
    rows = edit(rows)
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def _first_run(root: Path) -> Path:
    return sorted((root / "table2").glob("t2_*.csv"))[0]


def test_missing_column(small):
    path = _first_run(small)
    _rewrite(path, lambda rows: [r[:6] + r[7:] for r in rows])      # drop theta_housing_degC
    with pytest.raises(identify.IdentifyError, match=r"missing column 'theta_housing_degC'") as e:
        _run("mu", small)
    assert str(path) in str(e.value)


def test_wrong_unit_in_header(small, tmp_path):
    """A force column in kPa: rejected with the column, its unit and the expected one; CLI exit 2, no traceback."""
    path = _first_run(small)

    def to_kpa(rows):
        rows[0][2] = "force_kPa"
        for r in rows[1:]:
            r[2] = f"{float(r[2]) / 4.053:.4g}"
        return rows
    _rewrite(path, to_kpa)
    with pytest.raises(identify.IdentifyError, match=r"'force_kPa' is in kPa where 'force_N' \(N\) is expected"):
        _run("mu", small)
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "identify", "mu", str(small), "--out",
                        str(tmp_path / "o")], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "tools")})
    assert r.returncode == 2 and "force_kPa" in r.stderr and "Traceback" not in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()


def test_viscosity_in_wrong_unit(small):
    path = small / "table2" / "viscosity.csv"
    _rewrite(path, lambda rows: [["theta_degC", "viscosity_mPa_s"]] + rows[1:])
    with pytest.raises(identify.IdentifyError, match=r"'viscosity_mPa_s' is in mPa_s"):
        _run("viscosity", small)


def test_nan_stretch_is_excluded_and_named(small):
    path = _first_run(small)
    ident = path.stem

    def holes(rows):
        for r in rows[1:]:
            if 2.0 <= float(r[0]) < 3.0:
                r[3] = "nan"                        # 1 s of torque lost
            if 4.0 <= float(r[0]) < 4.5:
                r[4] = ""                           # 0.5 s of empty temperature cells
        return rows
    _rewrite(path, holes)
    res = _run("mu", small)
    nan = [e for e in res.exclusions if e.reason == "nan" and e.experiment == ident]
    assert [(round(e.t_from_s, 2), round(e.t_to_s, 2), e.samples) for e in nan] == [(2.0, 2.99, 100), (4.0, 4.49, 50)]
    edges = [e for e in res.exclusions if e.reason == "edge" and e.experiment == ident]
    assert len(edges) == 4 and all(0.2 <= e.seconds <= 0.3 for e in edges)   # half the 0.5 s derivative window
    assert res.results["mu"]["r2"] > 0.985


def test_zero_speed_segment_is_excluded(tmp_path):
    """A stop in the middle of the loading period: counted as 'static' (widened by half the slip average)."""
    rng = np.random.default_rng(3)
    cal = true_cal()
    root = tmp_path / "stop"
    (root / "table2").mkdir(parents=True)
    rows = []
    for i, (force, th0) in enumerate([(903.0, 30), (1350.0, 70), (1613.0, 50)]):
        run = friction_run(cal, rng, force, 200, 3.0, th0)
        if i == 0:
            stop = (run["t_s"] >= 2.0) & (run["t_s"] < 3.0)
            run["slip_rpm"][stop] = rng.normal(0, 0.3, stop.sum())    # encoder noise around zero
            run["torque_Nm"][stop] = 40.0                             # static torque, any value
        write_run(root / "table2" / f"r{i}.csv", run)
        rows.append({"id": f"r{i}", "force_N": force, "slip_rpm": 200, "loading_s": 3, "theta0_degC": th0,
                     "file": f"r{i}.csv"})
    write_index(root / "table2" / "index.csv", rows)
    res = _run("mu", root)
    stops = [e for e in res.exclusions if e.experiment == "r0" and e.reason == "static" and 1.5 < e.t_from_s < 2.5]
    assert len(stops) == 1 and stops[0].t_from_s <= 2.0 and stops[0].t_to_s >= 2.99
    assert res.results["mu"]["r2"] > 0.985


def test_load_change_film_transient_is_excluded(tmp_path):
    """A force step while slipping: the film_settle_s after it are excluded and named."""
    rng = np.random.default_rng(4)
    cal = true_cal()
    root = tmp_path / "step"
    (root / "table2").mkdir(parents=True)
    run = friction_run(cal, rng, 903.0, 200, 3.0, 50)
    late = run["t_s"] >= 2.5
    run["force_N"][late] += 300.0
    write_run(root / "table2" / "a.csv", run)
    write_run(root / "table2" / "b.csv", friction_run(cal, rng, 1350.0, 200, 3.0, 80))
    write_index(root / "table2" / "index.csv", [{"id": "a", "force_N": 903.0, "file": "a.csv"},
                                                 {"id": "b", "force_N": 1350.0, "file": "b.csv"}])
    res = _run("mu", root)
    film = [e for e in res.exclusions if e.experiment == "a" and e.reason == "film" and e.t_from_s > 2.0]
    assert len(film) == 1
    assert 2.4 <= film[0].t_from_s <= 2.5 and 2.95 <= film[0].t_to_s <= 3.1


def test_single_experiment(small):
    index = small / "table2" / "index.csv"
    _rewrite(index, lambda rows: rows[:2])
    with pytest.raises(identify.IdentifyError, match=r"mu: 1 usable experiment"):
        _run("mu", small)


def test_missing_index(small):
    (small / "table2" / "index.csv").unlink()
    with pytest.raises(identify.IdentifyError, match=r"no index CSV"):
        _run("mu", small)


def test_missing_listed_file_is_counted(small):
    victim = _first_run(small)
    victim.unlink()
    res = _run("viscosity", small)         # no friction step: nothing read
    assert not res.exclusions
    res = _run("mu", small)
    missing = [e for e in res.exclusions if e.reason == "missing_file"]
    assert [e.experiment for e in missing] == [f"{victim.stem} ({victim})"]
    assert res.results["mu"]["experiments"] == 3


def test_unnumeric_cell_and_time_order(small):
    path = _first_run(small)

    def garbage(rows):
        rows[10][3] = "12.5Nm"
        return rows
    _rewrite(path, garbage)
    with pytest.raises(identify.IdentifyError, match=r"line 11: column torque_Nm: '12.5Nm' is not a number"):
        _run("mu", small)

    def backwards(rows):
        rows[10][3] = "1.0"
        rows[20][0] = "0.05"
        return rows
    _rewrite(path, backwards)
    with pytest.raises(identify.IdentifyError, match=r"line 21: t_s does not increase"):
        _run("mu", small)


def test_unindexed_measurement_is_named(small):
    """A measurement file no index lists is reported, not silently ignored."""
    stray = small / "table2" / "stray_run.csv"
    stray.write_text(_first_run(small).read_text())
    res = _run("mu", small)
    assert any("stray_run.csv" in n and "not used" in n for n in res.notes)


# --------------------------------------------------------------------------- the bench simulator

def _bench():
    try:
        from wetclutch.simulate import bench
    except ImportError:
        return None
    needed = ("run", "table2_experiments", "thermal_experiments", "Experiment", "DEFAULT_TRUE")
    return bench if all(hasattr(bench, n) for n in needed) else None


def _bench_job(args):
    kind, out, names, thermal_s = args
    from dataclasses import replace
    bench = _bench()
    if kind == "table2":
        exps = [e for e in bench.table2_experiments() if e.name in names]
    else:
        exps = [replace(e, duration_s=thermal_s, speed_steps=tuple(s for s in e.speed_steps if s[0] < thermal_s))
                for e in bench.thermal_experiments(1)]
        exps[1] = replace(exps[1], speed_steps=((0.0, 60.0), (8.0, 400.0), (18.0, 60.0)))
    bench.run(kind, out, logs=False, experiments=exps)
    return kind


@pytest.mark.skipif(_bench() is None, reason="bench simulator (tools/wetclutch/simulate/bench) not available")
def test_bench_chain_reduced_campaign(tmp_path):
    """The bench simulator's data through identify all and lut: 16 Table 2 runs (4 forces x 100/300 rpm x
    40/80 degC, 5 s loading) and the two thermal runs cut to 30 s. About 15 s."""
    from concurrent.futures import ProcessPoolExecutor
    bench = _bench()
    names = [e.name for e in bench.table2_experiments()
             if e.loading_s == 5.0 and e.theta0_degC in (40.0, 80.0) and e.slip_rpm in (100.0, 300.0)]
    data = tmp_path / "bench"
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(_bench_job, [("table2", data / "table2", names, 0), ("thermal", data / "thermal", [], 30.0)]))
    out = tmp_path / "id"
    env = {**os.environ, "PYTHONPATH": str(ROOT / "tools")}
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "identify", "all", str(data), "--out", str(out),
                        "--true", str(bench.DEFAULT_TRUE), "--no-plots"], capture_output=True, text=True, env=env)
    fig = identify.json.loads((out / "figures.json").read_text())
    errors = {k: v.get("error_pct") for k, v in fig["parameters"].items()}
    print("reduced bench campaign, error %:", {k: round(v, 3) for k, v in errors.items()}, "R2", fig["mu"]["r2"])
    assert r.returncode == 0, (r.stderr, errors)
    for name in ("mu1", "mu2", "mu3", "stribeck_speed"):
        assert abs(errors[name]) < 3.0, (name, errors)
    # 30 s of thermal data instead of 2 x 240 s: k1, k2 come out 0.5..1.2 % off here, so 6 %; the 3 % target
    # is measured on the full campaign (test_full_campaign: within 0.15 %)
    for name in ("oil_conductance", "housing_conductance"):
        assert abs(errors[name]) < 6.0, (name, errors)
    assert abs(errors["asperity_density"]) < 5.0, errors
    assert fig["mu"]["r2"] >= 0.985
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "lut", str(out / "calibration.toml"), "--out",
                        str(tmp_path / "lut")], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr


@pytest.mark.skipif(os.environ.get("WC_IDENTIFY_FULL") != "1" or _bench() is None,
                    reason="full 184-run campaign: set WC_IDENTIFY_FULL=1 (about 45 s to simulate, once)")
def test_full_campaign():
    """All 184 Table 2 experiments and the two 240 s thermal runs, as the issue's targets ask.

    Run: WC_IDENTIFY_FULL=1 .venv/bin/python -m pytest tests/python/test_identify.py -k full -s
    The bench data are simulated once into $WC_IDENTIFY_DATA (default out/bench_campaign, about 45 s) and
    reused; the identification itself takes 3-6 s (15 s for the test with the report and plots). The report
    goes to out/identify_full.
    """
    bench = _bench()
    data = Path(os.environ.get("WC_IDENTIFY_DATA", ROOT / "out" / "bench_campaign"))
    for kind in ("table2", "thermal"):
        if not (data / kind).is_dir() or not any((data / kind).glob("*.csv")):
            bench.run(kind, data / kind, logs=False)
    out = ROOT / "out" / "identify_full"
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "identify", "all", str(data), "--out", str(out),
                        "--true", str(bench.DEFAULT_TRUE)], capture_output=True, text=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "tools")})
    print(r.stdout)
    fig = identify.json.loads((out / "figures.json").read_text())
    assert r.returncode == 0, r.stderr
    assert fig["mu"]["experiments"] == 184
    assert all(fig["targets"].values()), fig["targets"]
    # the runtime is printed, not asserted: a wall-clock time depends on the host (issue 28)
    print(f"identification time {fig['runtime_s']['total']:.1f} s (goal 60 s)")


def test_identify_engagement_edges_from_the_bench(tmp_path):
    """issue 12: `identify film` on engagement runs and `identify static` on breakaway runs, as the bench
    writes them (their index CSVs), recover the bench's phi and static factor within 5 %; the film state
    cuts the transient error several-fold."""
    from wetclutch.simulate import bench as bench_sim
    data = tmp_path / "data"
    bench_sim.run("engagement", data / "engagement", slips_rpm=[750.0], logs=False)
    bench_sim.run("breakaway", data / "breakaway")
    true = calibration.load(bench_sim.DEFAULT_TRUE)
    cal = ROOT / "tools" / "calibrations" / "bench_identified.toml"
    for step, name in (("film", "film_squeeze_factor"), ("static", "static_friction_factor")):
        out = tmp_path / step
        r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "identify", step, str(data), "--calibration",
                            str(cal), "--out", str(out), "--true", str(bench_sim.DEFAULT_TRUE)],
                           capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT / "tools")})
        assert r.returncode == 0, r.stderr
        fig = identify.json.loads((out / "figures.json").read_text())
        p = fig["parameters"][name]
        assert abs(p["identified"] / getattr(true, name) - 1.0) <= 0.05 and p["within_5pct"], p
        assert 0 < p["ci95"] < 0.05 * p["identified"]
        assert calibration.load(out / "calibration.toml").values[name] == pytest.approx(p["identified"], rel=1e-6)
    film = identify.json.loads((tmp_path / "film" / "figures.json").read_text())["film"]
    for run in film["runs"]:
        assert run["transient_max_error_film_Nm"] * 3.0 < run["transient_max_error_steady_Nm"], run
