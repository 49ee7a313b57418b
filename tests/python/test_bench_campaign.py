"""The bench simulator's campaigns and command (tools/wetclutch/simulate/bench, DESIGN 7): the Table 2
campaign, reproducibility, the bundled logs, bad input. The physics (engagement, film, breakaway, thermal),
the CAN logs and the ASC/BLF converter: test_bench.py."""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from wetclutch import calibration, cli
from wetclutch.simulate import bench
from wetclutch.util.csvio import read_columns


@pytest.fixture(scope="module")
def true_cal():
    return calibration.load(bench.DEFAULT_TRUE)


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
    # An experiment gives the same numbers alone or in a batch (the settled film is skipped per experiment).
    both = bench.simulate(true_cal, [replace(e, duration_s=1.2) for e in bench.engagement_experiments()], seed=7)
    assert both[0].experiment.name == "engagement_750rpm" and len(both) == 6
    assert np.array_equal(both[0].measured["torque_Nm"], a.measured["torque_Nm"])
    hot = bench.simulate(true_cal, [replace(e, duration_s=1.2) for e in bench.engagement_experiments((250.0,), (80.0,))],
                         seed=7)[0]
    assert hot.experiment.name == "engagement_250rpm_80degC"
    for col in bench.CSV_COLUMNS:
        assert np.array_equal(both[5].measured[col], hot.measured[col]), col
    assert np.array_equal(both[5].truth["separation_m"], hot.truth["separation_m"])


def test_bundled_logs_regenerate(root, tmp_path):
    """hil/logs/README.md's command regenerates the bundled files byte-identically (750 rpm at 40 and
    80 degC here: --slip 750 runs both temperatures)."""
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "bench", "engagement", "--out", str(tmp_path),
                        "--seed", "1", "--true", "tools/calibrations/bench_true.toml", "--slip", "750"],
                       cwd=root, capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(root / "tools")))
    assert r.returncode == 0, r.stderr
    names = ("engagement_750rpm.log", "engagement_750rpm.csv", "engagement_750rpm_80degC.log",
             "engagement_750rpm_80degC.csv")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names + ("engagement_index.csv",))
    for name in names:
        assert (tmp_path / name).read_bytes() == (root / "hil" / "logs" / name).read_bytes(), name
    readme = (root / "hil" / "logs" / "README.md").read_text()
    assert "--out hil/logs --seed 1" in readme
    bundled = sorted(p.name for p in (root / "hil" / "logs").iterdir()
                     if p.suffix in (".log", ".csv") and not p.name.endswith("_index.csv"))
    assert (root / "hil" / "logs" / "engagement_index.csv").is_file()   # identify film finds the runs by it
    assert len(bundled) == 12 and all(f"`{name[:-4]}.log`" in readme for name in bundled)


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
    assert cli.main(["bench", "engagement", "--out", str(tmp_path), "--theta", "200"]) == 2
    assert "temperature 200.0 degC out of range" in capsys.readouterr().err
    assert cli.main(["bench", "breakaway", "--out", str(tmp_path), "--theta", "80", "--theta", "80"]) == 2
    assert "80 degC given twice" in capsys.readouterr().err
    assert cli.main(["bench", "thermal", "--out", str(tmp_path), "--theta", "40"]) == 2
    assert "engagement and the breakaway only" in capsys.readouterr().err
    with pytest.raises(bench.BenchError, match="'hot' is not a number"):
        bench.engagement_experiments((750.0,), ("hot",))
    assert list(tmp_path.iterdir()) == []
