"""wc_eval (the firmware's float arithmetic, src/host/wc_eval.c) against the
double-precision reference (tools/wetclutch, `wetclutch reference`).

Builds nothing: the binary comes from the environment variable WC_EVAL
(default build/host-debug/src/host/wc_eval under the repository root), e.g.

    cmake -S . -B build/host-debug -G Ninja -DCMAKE_BUILD_TYPE=Debug
    cmake --build build/host-debug
    WC_EVAL=build/host-debug/src/host/wc_eval .venv/bin/python -m pytest tests/python/test_wc_eval.py
"""
from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
try:
    from wetclutch import calibration
    from wetclutch.reference import evaluate as reference
except ImportError:  # the tool not installed in this interpreter: use the source tree
    sys.path.insert(0, str(ROOT / "tools"))
    from wetclutch import calibration
    from wetclutch.reference import evaluate as reference


def _find_wc_eval() -> Path:
    given = os.environ.get("WC_EVAL")
    if not given:
        return ROOT / "build" / "host-debug" / "src" / "host" / "wc_eval"
    path = Path(given)
    if path.is_absolute() or path.exists():
        return path.resolve() if path.exists() else path
    return ROOT / path  # relative to the repository root


WC_EVAL = _find_wc_eval()
pytestmark = pytest.mark.skipif(
    not (WC_EVAL.is_file() and os.access(WC_EVAL, os.X_OK)),
    reason=f"wc_eval not found at {WC_EVAL}: build it (cmake --build build/host-debug) or set WC_EVAL",
)

SEED = 20261121
CAL = calibration.load(ROOT / "tools" / "calibrations" / "table1.toml")

# Tolerances (the same reasoning as tests/c/test_torque.c and test_inverse.c):
# the film LUT's max relative error is 3.9e-5 (`wetclutch lut`), float
# rounding adds ~1e-6, so torque, viscous torque and h_bar are within 1e-4
# relative; the inverse's bisection stops once its force bracket is narrower
# than 0.01 N (WC_INVERSE_FORCE_TOLERANCE_N), hence the force's 0.01 N
# absolute on top of 1e-4 relative.
REL_TOL = 1e-4
FORCE_ABS_TOL_N = 0.01


def run_wc_eval(mode: str, text: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(WC_EVAL), mode], input=text, capture_output=True, text=True, timeout=120)


def to_csv(cols: dict[str, np.ndarray]) -> str:
    names = list(cols)
    out = io.StringIO()
    out.write(",".join(names) + "\n")
    for k in range(len(cols[names[0]])):
        out.write(",".join(repr(float(cols[n][k])) for n in names) + "\n")
    return out.getvalue()


def parse_output(stdout: str) -> tuple[list[str], list[list[str]]]:
    rows = list(csv.reader(io.StringIO(stdout)))
    return rows[0], rows[1:]


def evaluate(mode: str, cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    result = run_wc_eval(mode, to_csv(cols))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    header, rows = parse_output(result.stdout)
    assert len(rows) == len(next(iter(cols.values())))
    data = np.array([[float(x) for x in row] for row in rows]).reshape(-1, len(header))
    return {name: data[:, k] for k, name in enumerate(header)}


def assert_close(name: str, got: np.ndarray, want: np.ndarray, rel: float, abs_: float = 0.0) -> None:
    got = np.asarray(got, dtype=float)
    want = np.asarray(want, dtype=float)
    err = np.abs(got - want)
    bad = ~(err <= abs_ + rel * np.abs(want))
    if np.any(bad):
        k = int(np.argmax(bad))
        pytest.fail(f"{name}: {int(bad.sum())} rows outside {rel:g} relative + {abs_:g}; first row {k}: "
                    f"wc_eval {got[k]!r}, reference {want[k]!r}")


# ---------------------------------------------------------------------------
# Against the reference, on a seeded random grid


def test_torque_matches_reference():
    rng = np.random.default_rng(SEED)
    n = 600
    cols = {
        "slip_rpm": rng.uniform(-3000.0, 3000.0, n),
        "theta_degC": rng.uniform(10.0, 120.0, n),
        "force_N": rng.uniform(0.0, 3000.0, n),
    }
    cols["slip_rpm"][:20] = 0.0      # static capacity, no drag
    cols["force_N"][20:40] = 0.0     # open clutch: drag only
    cols["force_N"][40:60] = rng.uniform(3000.0, 10863.0, 20)  # up to the solenoid's force
    got = evaluate("torque", cols)
    want = reference.torque(CAL, cols)
    assert list(got) == ["torque_Nm", "coulomb_Nm", "viscous_Nm", "hbar_um", "mu_f"]
    for name in got:
        assert_close(name, got[name], want[name], REL_TOL)


def test_inverse_matches_reference():
    rng = np.random.default_rng(SEED + 1)
    n = 600
    cols = {
        "slip_rpm": rng.uniform(-3000.0, 3000.0, n),
        "theta_degC": rng.uniform(10.0, 120.0, n),
        "torque_Nm": rng.uniform(0.0, 1500.0, n),
    }
    cols["torque_Nm"][:20] = 0.0                              # below the drag
    cols["torque_Nm"][20:40] = rng.uniform(5000.0, 20000.0, 20)  # above the capacity
    cols["slip_rpm"][40:60] = 0.0
    got = evaluate("inverse", cols)
    want = reference.inverse(CAL, cols)
    assert list(got) == ["force_N", "pressure_kPa", "current_mA", "status"]
    assert_close("force_N", got["force_N"], want["force_N"], REL_TOL, FORCE_ABS_TOL_N)
    assert_close("pressure_kPa", got["pressure_kPa"], want["pressure_kPa"], REL_TOL)
    assert_close("current_mA", got["current_mA"], want["current_mA"], REL_TOL)
    status = got["status"].astype(int)
    mismatch = np.flatnonzero(status != want["status"])
    assert mismatch.size == 0, f"status differs in {mismatch.size} rows, first {mismatch[:5]}"
    # the grid reaches all three branches
    assert np.any(status & 1) and np.any(status & 2) and np.any(status == 0)


def test_thermal_matches_reference():
    """Random steps of slip, torque, oil and housing over 4 s (4000 periods).

    Tolerance 1e-4 relative: the float observer's worst case is the float
    decay factor's share (1.9e-5 of a step) plus a dead band of half an ulp
    over (1 - a), 6.8 mK at 64..128 degC (tests/c/test_thermal.c), i.e.
    < 1e-4 of the temperature over the range reached here.
    """
    rng = np.random.default_rng(SEED + 2)
    n = 4000
    segment = 200
    steps = n // segment

    def steps_of(lo, hi):
        return np.repeat(rng.uniform(lo, hi, steps), segment)

    cols = {
        "t_s": np.arange(n) * CAL.period,
        "slip_rpm": steps_of(-500.0, 500.0),
        "torque_Nm": steps_of(0.0, 200.0),
        "theta_oil_degC": steps_of(20.0, 100.0),
        "theta_housing_degC": steps_of(20.0, 100.0),
    }
    got = evaluate("thermal", cols)
    want = reference.thermal(CAL, cols)
    assert list(got) == ["t_s", "theta_degC"]
    assert_close("t_s", got["t_s"], cols["t_s"], 1e-8)  # echoed with %.9g: 9 significant digits
    assert_close("theta_degC", got["theta_degC"], want["theta_degC"], REL_TOL)
    # starts at the first oil temperature, as a float (9 digits round-trip a float32)
    assert np.float32(got["theta_degC"][0]) == np.float32(cols["theta_oil_degC"][0])


def test_columns_by_name_any_order_extra_columns():
    text_canonical = "slip_rpm,theta_degC,force_N\n750,65,1188\n-300,40,903\n"
    text_shuffled = "note, force_N ,theta_degC,slip_rpm,more\nx,1188,65,750,1\ny,903,40,-300,2\n"
    a = run_wc_eval("torque", text_canonical)
    b = run_wc_eval("torque", text_shuffled)
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    assert a.stdout == b.stdout


def test_crlf_and_blank_lines():
    a = run_wc_eval("inverse", "slip_rpm,theta_degC,torque_Nm\n750,90,150\n0,10,0\n")
    b = run_wc_eval("inverse", "slip_rpm,theta_degC,torque_Nm\r\n750,90,150\r\n\r\n0,10,0\r\n")
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    assert a.stdout == b.stdout


# ---------------------------------------------------------------------------
# Bad rows: reported with the line number, non-zero exit, no partial row

GOOD = {
    "torque": ("slip_rpm,theta_degC,force_N", ["750,65,1188", "-300,40,903"], "100,90,500"),
    "inverse": ("slip_rpm,theta_degC,torque_Nm", ["750,90,150", "0,10,0"], "300,65,40"),
    "thermal": ("t_s,slip_rpm,torque_Nm,theta_oil_degC,theta_housing_degC",
                ["0,750,150,40,38", "0.001,750,150,40,38"], "0.003,750,150,40,38"),
}
OUTPUT_FIELDS = {"torque": 5, "inverse": 4, "thermal": 2}

BAD_ROWS = [
    ("torque", "750,65", "2 fields"),
    ("torque", "750,65,1188,7", "4 fields"),
    ("torque", "750,abc,1188", "not a number"),
    ("torque", "750,,1188", "not a number"),
    ("torque", "750,65,nan", "not finite"),
    ("torque", "inf,65,1188", "not finite"),
    ("torque", "750,-inf,1188", "not finite"),
    ("torque", "1e400,65,1188", "not finite"),
    ("torque", "20000,65,1188", "slip_rpm"),
    ("torque", "-10001,65,1188", "slip_rpm"),
    ("torque", "750,300,1188", "temperature"),
    ("torque", "750,-41,1188", "temperature"),
    ("torque", "750,65,-1", "force_N"),
    ("torque", "750,65,2e5", "force_N"),
    ("inverse", "750,90", "2 fields"),
    ("inverse", "750,90,-150", "torque_Nm"),
    ("inverse", "750,90,1e6", "torque_Nm"),
    ("inverse", "750,NaN,150", "not finite"),
    ("inverse", "1e6,90,150", "slip_rpm"),
    ("inverse", "750,251,150", "temperature"),
    ("thermal", "0.002,750,150,40", "4 fields"),
    ("thermal", "0.0025,750,150,40,38", "t_s"),   # not one period after the last row
    ("thermal", "0.001,750,150,40,38", "t_s"),    # repeated time
    ("thermal", "0.002,750,150,x,38", "not a number"),
    ("thermal", "0.002,750,150,40,nan", "not finite"),
    ("thermal", "0.002,750,150,40,300", "temperature"),
    ("thermal", "0.002,750,150,-41,38", "temperature"),
    ("thermal", "0.002,750,1e38,40,38", "heat input"),
]


def check_complete_rows(stdout: str, mode: str, expected_rows: int) -> None:
    assert stdout == "" or stdout.endswith("\n"), f"partial row at the end: {stdout[-80:]!r}"
    lines = stdout.splitlines()
    if expected_rows < 0:
        assert lines == []
        return
    assert len(lines) == 1 + expected_rows, lines
    for line in lines[1:]:
        fields = line.split(",")
        assert len(fields) == OUTPUT_FIELDS[mode], line
        for f in fields:
            float(f)


@pytest.mark.parametrize("mode,bad,message", BAD_ROWS, ids=[f"{m}:{b}" for m, b, _ in BAD_ROWS])
def test_bad_row(mode, bad, message):
    header, good, after = GOOD[mode]
    text = "\n".join([header, *good, bad, after]) + "\n"
    result = run_wc_eval(mode, text)
    assert result.returncode != 0
    assert "line 4" in result.stderr, result.stderr
    assert message in result.stderr, result.stderr
    check_complete_rows(result.stdout, mode, expected_rows=len(good))


def test_thermal_bad_first_row():
    header, _, _ = GOOD["thermal"]
    result = run_wc_eval("thermal", header + "\n0,750,150,-100,38\n0.001,750,150,40,38\n")
    assert result.returncode != 0
    assert "line 2" in result.stderr and "temperature" in result.stderr, result.stderr
    check_complete_rows(result.stdout, "thermal", expected_rows=0)


@pytest.mark.parametrize("mode", sorted(GOOD))
def test_missing_column(mode):
    header, good, _ = GOOD[mode]
    columns = header.split(",")
    text = ",".join(columns[1:]) + "\n" + "\n".join(",".join(r.split(",")[1:]) for r in good) + "\n"
    result = run_wc_eval(mode, text)
    assert result.returncode != 0
    assert "line 1" in result.stderr and columns[0] in result.stderr, result.stderr
    check_complete_rows(result.stdout, mode, expected_rows=-1)


def test_empty_input():
    result = run_wc_eval("torque", "")
    assert result.returncode != 0
    assert "header" in result.stderr
    assert result.stdout == ""


def test_usage():
    result = subprocess.run([str(WC_EVAL), "--help"], capture_output=True, text=True, timeout=30)
    assert result.returncode == 0
    for mode in GOOD:
        assert mode in result.stdout
    result = subprocess.run([str(WC_EVAL), "bogus"], capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
    assert "usage" in result.stderr and result.stdout == ""
    result = subprocess.run([str(WC_EVAL)], capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
