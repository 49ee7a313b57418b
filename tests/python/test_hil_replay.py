"""The HIL report of the bundled engagement logs (paper Fig. 15): the targets of
the HIL issue and of the engagement edges (issue 12: transient error with the
squeeze-film state, a locked estimate of stable sign within the static
capacity), checked by the same command as the README's main job, all six logs
(40 and 80 degC) with --in-process: the frame loop in wc_replay, the same code
and the same frames as wc_tcu on vcan (test_vcan_integration.py shows it for a
bundled log; the main job runs on vcan)."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

LOGS = ("engagement_750rpm", "engagement_500rpm", "engagement_250rpm",
        "engagement_750rpm_80degC", "engagement_500rpm_80degC", "engagement_250rpm_80degC")


@pytest.fixture(scope="module")
def replayed(root, tmp_path_factory, tcu):
    out = tmp_path_factory.mktemp("hil")
    run = subprocess.run([sys.executable, "-m", "wetclutch.cli", "replay",
                          *[str(root / "hil" / "logs" / f"{name}.log") for name in LOGS], "--out", str(out),
                          "--calibration", str(root / "tools" / "calibrations" / "bench_identified.toml"),
                          "--in-process"],
                         cwd=root, capture_output=True, text=True,
                         env=dict(os.environ, PYTHONPATH=str(root / "tools")))
    print(run.stdout[-4000:], run.stderr[-4000:])
    return run, out


def test_replay_meets_all_targets(replayed):
    run, _ = replayed
    assert run.returncode == 0, run.stderr[-2000:]


@pytest.mark.parametrize("name", LOGS)
def test_replay_report(replayed, name):
    _, out = replayed
    m = json.loads((out / name / "metrics.json").read_text())
    assert m["torque_rmse_steady_Nm"] <= m["torque_rmse_steady_target_Nm"]
    assert m["theta_rmse_K"] <= 2.0
    assert m["frames_dropped"] == 0
    assert m["deterministic_frame_clock"]
    assert m["tcu_vs_reference_max_abs"]["status_mismatches"] == 0
    # issue 12: the squeeze-film state and the lock-up
    assert m["torque_max_abs_error_transient_Nm"] <= 28.9 < m["torque_max_abs_error_transient_steady_model_Nm"]
    assert m["locked"]["sign_changes"] == 0 and m["locked"]["locked_samples"] > 100
    assert m["locked"]["max_abs_over_capacity_Nm"] <= 0.1
    for png in ("torque.png", "temperature.png", "command.png", "status.png"):
        assert (out / name / png).stat().st_size > 1000
    assert "paper" in (out / name / "summary.md").read_text()
