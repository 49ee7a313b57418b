"""`wetclutch reference` applies the firmware's input rules row by row: the status bits of the reference
model (wetclutch.reference.model), the firmware's safe outputs, and the same status as wc_eval on each
side of every limit (where it is built)."""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from cli_support import ROOT, assert_one_line_error, run
from wetclutch.generate import lut
from wetclutch.reference import evaluate as reference, model


# --------------------------------------------------------------------------- reference: the firmware's rules

S = model


def _rows(cal, mode, rows):
    cols = {c: np.array([r[k] for r in rows], dtype=float) for k, c in enumerate(reference.INPUTS[mode])}
    return reference.MODES[mode](cal, cols)


def test_reference_torque_rejects_like_the_firmware(cal):
    rows = [(750, 65, 1188), (750, 65, -1000), (1e300, 1e300, 1e300), (750, np.nan, 1188), (750, 65, np.inf),
            (-10001, 65, 1188), (750, 251, 1188), (750, -41, 1188), (750, 65, 2e5)]
    r = _rows(cal, "torque", rows)
    assert list(r["status"]) == [0, S.STATUS_FORCE_INVALID,
                                 S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID | S.STATUS_FORCE_INVALID,
                                 S.STATUS_THETA_INVALID, S.STATUS_FORCE_INVALID, S.STATUS_SLIP_INVALID,
                                 S.STATUS_THETA_INVALID, S.STATUS_THETA_INVALID, S.STATUS_FORCE_INVALID]
    assert S.STATUS_FORCE_INVALID == 0x20 and S.STATUS_INPUT_INVALID == 0xF8   # include/wetclutch/wc_status.h
    assert r["torque_Nm"][0] == pytest.approx(154.7, rel=5e-4)
    rejected = slice(1, None)
    for name in ("torque_Nm", "coulomb_Nm", "viscous_Nm", "mu_f"):
        assert np.all(r[name][rejected] == 0.0), name            # was -72 Nm for -1000 N
    first_node_um = lut.build_table(cal).hbar_m[0] * 1e6          # the open clutch's film
    assert np.all(r["hbar_um"][rejected] == pytest.approx(first_node_um, rel=1e-12))
    for name in r:
        assert np.all(np.isfinite(r[name])), name


def test_reference_inverse_rejects_like_the_firmware(cal):
    rows = [(750, 90, 150), (750, 90, -1000), (1e300, 1e300, 1e300), (np.nan, 90, 150), (750, 90, np.nan),
            (20000, 90, 150), (750, 90, 1e6)]
    r = _rows(cal, "inverse", rows)
    assert list(r["status"]) == [0, S.STATUS_TORQUE_INVALID,
                                 S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID | S.STATUS_TORQUE_INVALID,
                                 S.STATUS_SLIP_INVALID, S.STATUS_TORQUE_INVALID, S.STATUS_SLIP_INVALID,
                                 S.STATUS_TORQUE_INVALID]
    preload_Pa = cal.return_spring_force / cal.piston_area
    assert np.all(r["force_N"][1:] == 0.0)
    assert np.all(r["pressure_kPa"][1:] == pytest.approx(preload_Pa * 1e-3))
    assert np.all(r["current_mA"][1:] == pytest.approx(preload_Pa / cal.vfs_gain))
    # a solenoid whose minimum current is above the preload's: the safe current is clamped, and says so
    high_min = cal.with_values(vfs_current_min=100.0)
    r = _rows(high_min, "inverse", [(750, 90, -1000)])
    assert int(r["status"][0]) == S.STATUS_TORQUE_INVALID | S.STATUS_CURRENT_CLAMPED
    assert float(r["current_mA"][0]) == 100.0 and float(r["force_N"][0]) == 0.0


def test_reference_thermal_holds_the_state_on_rejected_rows(cal):
    good = [(0.000, 750, 150, 40, 38), (0.001, 750, 150, 40, 38), (0.002, 750, 150, 40, 38)]
    bad = [(0.000, 750, 150, 40, 38), (0.001, 750, 1e38, 40, 38), (0.002, 750, 150, np.nan, 38),
           (0.003, 750, 150, 40, 38), (0.004, 750, 150, 40, 38)]
    g = _rows(cal, "thermal", good)
    b = _rows(cal, "thermal", bad)
    assert list(b["status"]) == [0, S.STATUS_POWER_INVALID, S.STATUS_THETA_INVALID, 0, 0]
    # the rejected rows change nothing: the accepted ones see the series without them
    assert b["theta_degC"][0] == g["theta_degC"][0] and b["theta_degC"][1] == g["theta_degC"][1]
    assert b["theta_degC"][2] == b["theta_degC"][3] == g["theta_degC"][1]
    assert b["theta_degC"][4] == g["theta_degC"][2]


def test_reference_cli_rejects_like_wc_eval(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,1188\n\n750,65,-1000\n1e300,1e300,1e300\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(["reference", "torque", "-i", src, "-o", out], capsys)
    assert_one_line_error(code, err, src, "line 4", "status 0x20", "force_N not within 0..100000 N",
                          "2 rows rejected")
    assert not out.exists() and stdout == ""
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,nan\n")      # NaN: not a number the firmware gets
    code, stdout, err = run(["reference", "torque", "-i", src], capsys)
    assert_one_line_error(code, err, src, "line 2", "not finite")


def test_reference_cli_keep_rejected(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("slip_rpm,theta_degC,force_N\n750,65,1188\n750,65,-1000\n1e300,1e300,1e300\n750,nan,1188\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(["reference", "torque", "-i", src, "-o", out, "--keep-rejected"], capsys)
    assert code == 0 and "3 row(s) rejected" in err and "line 3" in err, err
    lines = out.read_text().splitlines()
    assert lines[0] == "torque_Nm,coulomb_Nm,viscous_Nm,hbar_um,mu_f,status"
    status = [int(line.split(",")[-1]) for line in lines[1:]]
    assert status == [0, S.STATUS_FORCE_INVALID, S.STATUS_SLIP_INVALID | S.STATUS_THETA_INVALID
                      | S.STATUS_FORCE_INVALID, S.STATUS_THETA_INVALID]
    assert all(line.startswith("0,0,0,") and line.split(",")[4] == "0" for line in lines[2:])


def _wc_eval() -> Path | None:
    path = Path(os.environ.get("WC_EVAL") or ROOT / "build" / "host-debug" / "src" / "host" / "wc_eval")
    path = path if path.is_absolute() else ROOT / path
    return path if path.is_file() and os.access(path, os.X_OK) else None


BOUNDARY = {
    "torque": [(10000, 65, 100), (-10000, 65, 100), (10000.02, 65, 100), (10000.1, 65, 100), (10001, 65, 100),
               (750, -40, 100), (750, -40.00001, 100), (750, 250, 100), (750, 250.0001, 100), (750, 65, 0),
               (750, 65, -0.0), (750, 65, -1e-30), (750, 65, -1e-50), (750, 65, 1e5), (750, 65, 100000.004),
               (750, 65, 100000.01), (750, 65, 3.4e38), (750, 65, 3.5e38), (1e300, 1e300, 1e300),
               (750, 65, -1000)],
    "inverse": [(750, 90, 0), (750, 90, -0.0), (750, 90, -1e-30), (750, 90, 1e5), (750, 90, 100000.01),
                (750, 90, -1000), (10000.1, 90, 150), (10001, 90, 150), (750, 250.0001, 150),
                (1e300, 1e300, 1e300)],
    "thermal": [(0.001, 750, 1e34, 40, 38), (0.001, 750, 1e38, 40, 38), (0.001, 3e38, 2, 40, 38),
                (0.001, 750, 150, 250.0001, 38), (0.001, 750, 150, 40, -40.0001), (0.001, 1e300, 0, 40, 38)],
}


@pytest.mark.skipif(_wc_eval() is None, reason="wc_eval not built (cmake --build build/host-debug) or WC_EVAL")
@pytest.mark.parametrize("mode", sorted(BOUNDARY))
def test_reference_status_matches_wc_eval(mode, cal):
    """On each side of every limit, the reference accepts what wc_eval accepts and gives the status wc_eval
    reports for what it rejects."""
    header = ",".join(reference.INPUTS[mode])
    rows = BOUNDARY[mode]
    if mode == "thermal":   # a first row to start the observer, then the row under test one period later
        rows_in = [[(0.0, 750, 150, 40, 38), r] for r in rows]
    else:
        rows_in = [[r] for r in rows]
    for row_set in rows_in:
        text = header + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in row_set) + "\n"
        r = subprocess.run([str(_wc_eval()), mode], input=text, capture_output=True, text=True, timeout=30)
        got = _rows(cal, mode, row_set)["status"][-1] & S.STATUS_INPUT_INVALID
        rejected = re.search(r"status 0x([0-9a-f]+)", r.stderr)
        want = int(rejected.group(1), 16) & S.STATUS_INPUT_INVALID if rejected else 0
        assert r.returncode == (1 if rejected else 0), r.stderr
        assert got == want, (row_set[-1], r.stderr)
