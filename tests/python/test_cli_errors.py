"""Bad input to the CLI: non-zero exit, a message naming parameter and file, nothing written."""
from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest


def _lut(root, cal_path, out_dir):
    return subprocess.run([sys.executable, "-m", "wetclutch.cli", "lut", str(cal_path), "--out", str(out_dir)],
                          capture_output=True, text=True, env={"PYTHONPATH": str(root / "tools")})


def _variant(root, tmp_path, pattern, replacement):
    text = (root / "tools" / "calibrations" / "table1.toml").read_text()
    new, count = re.subn(pattern, replacement, text, count=1, flags=re.M)
    assert count == 1, pattern
    path = tmp_path / "bad.toml"
    path.write_text(new)
    return path


CASES = [
    ("missing", r"^mu2 .*\n", "", "friction.mu2"),
    ("unknown", r"^\[friction\]\n", "[friction]\nmu9 = { value = 1.0, unit = \"1\", source = \"x\" }\n", "friction.mu9"),
    ("non-numeric", r"(^k1|^oil_conductance)( *= \{ value = )[^,]+", r'\1\2"fast"', "thermal.oil_conductance"),
    ("negative", r"(^youngs_modulus *= \{ value = )[^,]+", r"\1-1.0e6", "contact.youngs_modulus"),
    ("nan", r"(^stribeck_speed *= \{ value = )[^,]+", r"\1nan", "friction.stribeck_speed"),
    ("wrong unit", r"(^return_spring_force *= \{ value = [^,]+, unit = )\"N\"", r'\1"kN"', "hydraulics.return_spring_force"),
]


@pytest.mark.parametrize("label, pattern, replacement, param", CASES, ids=[c[0] for c in CASES])
def test_bad_parameter(root, tmp_path, label, pattern, replacement, param):
    bad = _variant(root, tmp_path, pattern, replacement)
    out = tmp_path / "out"
    out.mkdir()
    (out / "wc_bad_film.h").write_text("previous")  # an earlier good output must survive
    r = _lut(root, bad, out)
    assert r.returncode != 0
    assert param in r.stderr and str(bad) in r.stderr, r.stderr
    assert sorted(os.listdir(out)) == ["wc_bad_film.h"]
    assert (out / "wc_bad_film.h").read_text() == "previous"


def test_missing_file(root, tmp_path):
    r = _lut(root, tmp_path / "nope.toml", tmp_path / "out")
    assert r.returncode != 0 and "nope.toml" in r.stderr
    assert not (tmp_path / "out").exists()


def test_unreadable_file(root, tmp_path):
    path = tmp_path / "garbage.toml"
    path.write_bytes(b"\xff\xfe not toml [[[")
    r = _lut(root, path, tmp_path / "out")
    assert r.returncode != 0 and "garbage.toml" in r.stderr
    assert not (tmp_path / "out").exists()


def test_reference_bad_row_names_line(root):
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "reference", "torque",
                        "-c", str(root / "tools" / "calibrations" / "table1.toml")],
                       input="slip_rpm,theta_degC,force_N\n750,65,1188\n750,abc,1188\n",
                       capture_output=True, text=True, env={"PYTHONPATH": str(root / "tools")})
    assert r.returncode != 0 and "line 3" in r.stderr and "theta_degC" in r.stderr
    assert r.stdout == ""
