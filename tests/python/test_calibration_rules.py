"""The calibration rules in Python (calibration.load, wetclutch lut) are the firmware's (DESIGN.md section 8).

- the limits are the firmware's: LIMITS against the #defines of include/wetclutch/wc_calibration.h;
- C and Python agree: the variants of table1 listed in tests/c/test_calibration.c (rejected_variants,
  accepted_variants; parsed from that file, so there is one list) go through calibration.load here,
  and each is accepted or rejected as the C test expects, the message naming the parameter and the
  firmware's name of the failing check (wc_cal_error_name, parsed from src/model/wc_calibration.c);
- every parameter rejects NaN and infinities, naming itself;
- the film rules (calibration.film_problem, lut.check_table) on tables made by hand;
- `wetclutch lut` refuses out-of-limit counts before allocating, a non-identifier --name, a
  non-finite or non-positive --max-error, values the float32 headers cannot hold: exit 2, the file
  named, nothing written.
"""
from __future__ import annotations

import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from wetclutch import calibration
from wetclutch.generate import lut
from wetclutch.calibration import C_NAMES, LIMITS, CalibrationError

ROOT = Path(__file__).resolve().parents[2]
TABLE1 = ROOT / "tools" / "calibrations" / "table1.toml"
HEADER = ROOT / "include" / "wetclutch" / "wc_calibration.h"
CONFIG = ROOT / "include" / "wetclutch" / "wc_config.h"
SOURCE = ROOT / "src" / "model" / "wc_calibration.c"
C_TEST = ROOT / "tests" / "c" / "test_calibration.c"

SECTION = {name: section for section, name, *_ in calibration.PARAMETERS}
UNIT = {name: unit for _, name, unit, *_ in calibration.PARAMETERS}
BY_FIELD = {field: (section, name) for section, name, _, _, field in calibration.PARAMETERS if field}


# ---------------------------------------------------------------------------
# helpers

def c_float(text: str) -> float:
    return float(text.strip().rstrip("fF"))


def firmware_names() -> dict[str, str]:
    """WC_CAL_* code -> wc_cal_error_name, from the enum and the name table."""
    enum = re.search(r"typedef enum \{(.*?)\} wc_cal_error_t;", HEADER.read_text(), re.S).group(1)
    enum = re.sub(r"/\*.*?\*/", "", enum, flags=re.S)
    codes = re.findall(r"\b(WC_CAL_\w+)", enum)
    table = re.search(r"cal_error_names\[\] = \{(.*?)\};", SOURCE.read_text(), re.S).group(1)
    names = re.findall(r'"((?:[^"\\]|\\.)*)"', table)
    assert codes[-1] == "WC_CAL_ERRORS" and len(names) == len(codes) - 1
    return dict(zip(codes, names))


def c_variants(array: str) -> list[tuple[str, list[tuple[str, float]]]]:
    """(expected code, [(C field, value), ...]) of one variant list of tests/c/test_calibration.c."""
    block = re.search(rf"static const variant_t {array}\[\] = \{{(.*?)\n\}};", C_TEST.read_text(), re.S).group(1)
    block = re.sub(r"/\*.*?\*/", "", block, flags=re.S)
    out = []
    for m in re.finditer(r"V([123])\(\s*(WC_CAL_\w+)\s*,([^()]*)\)", block):
        args = [a.strip() for a in m.group(3).split(",")]
        assert len(args) == 2 * int(m.group(1)), m.group(0)
        out.append((m.group(2), [(args[k], c_float(args[k + 1])) for k in range(0, len(args), 2)]))
    return out


def toml_text(changes: dict[str, str], base: Path = TABLE1) -> str:
    """table1 with some values replaced (name -> TOML value text); an optional parameter the file leaves out
    (calibration.OPTIONAL) added to its section."""
    text = base.read_text()
    for name, value in changes.items():
        text, count = re.subn(rf"(^{name} *= \{{ value = )[^,]+", rf"\g<1>{value}", text, count=1, flags=re.M)
        if count == 0 and name in calibration.OPTIONAL:
            unit = UNIT[name]
            text, count = re.subn(rf"^\[{SECTION[name]}\]\s*$", rf'[{SECTION[name]}]\n{name} = {{ value = {value},'
                                  rf' unit = "{unit}", source = "test" }}', text, count=1, flags=re.M)
        assert count == 1, name
    return text


def write_variant(tmp_path: Path, changes: dict[str, str], stem: str = "variant") -> Path:
    path = tmp_path / f"{stem}.toml"
    path.write_text(toml_text(changes))
    return path


def toml_changes(settings: list[tuple[str, float]]) -> dict[str, str]:
    """The C test's field settings as changes of the TOML file (the heat capacity, derived in Python
    from the thermal section, through the two densities)."""
    changes = {}
    base = calibration.load(TABLE1)
    for field, value in settings:
        if field == "heat_capacity_J_per_K":
            factor = value / base.heat_capacity
            for name in ("separator_density", "lining_density"):
                changes[name] = repr(base.values[name] * factor)
        else:
            changes[BY_FIELD[field][1]] = repr(value)
    return changes


def run_lut(tmp_path: Path, cal_path: Path, *extra: str, timeout: float = 60.0):
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    (out / "previous.h").write_text("previous")          # an earlier output must survive
    started = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "wetclutch.cli", "lut", str(cal_path), "--out", str(out), *extra],
                       capture_output=True, text=True, env={"PYTHONPATH": str(ROOT / "tools")}, timeout=timeout)
    return r, out, time.monotonic() - started


def assert_refused(r, out: Path, *words: str) -> None:
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr, r.stderr
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("wetclutch lut: "), r.stderr
    for word in words:
        assert word in r.stderr, (word, r.stderr)
    assert sorted(os.listdir(out)) == ["previous.h"], os.listdir(out)
    assert (out / "previous.h").read_text() == "previous"


# ---------------------------------------------------------------------------
# the limits and names are the firmware's

def test_limits_are_the_firmware_defines():
    defines = dict(re.findall(r"#define WC_CAL_LIMIT_(\w+) ([-+0-9.eE]+)[fu]?\b", HEADER.read_text()))
    assert set(defines) == set(LIMITS)
    for key, value in LIMITS.items():
        assert float(defines[key]) == value, key
    config = {k: float(v) for k, v in
              re.findall(r"#define (WC_\w+) \(?([-+0-9.eE]+)[fu]?\)?", CONFIG.read_text())}
    assert config["WC_THETA_MIN_degC"] == calibration.THETA_MIN_DEGC
    assert config["WC_THETA_MAX_degC"] == calibration.THETA_MAX_DEGC
    assert config["WC_FILM_MAX_NODES"] == calibration.FILM_MAX_NODES
    assert config["WC_FORCE_MAX_N"] == calibration.FORCE_MAX_N


def test_python_quotes_the_firmware_names():
    names = set(firmware_names().values())
    for key, name in C_NAMES.items():
        assert name in names, key
    for _, _, _, _, field in calibration.PARAMETERS:
        assert field is None or field in names, field


@pytest.mark.parametrize("name", ["table1", "bench_identified", "bench_true"])
def test_bundled_calibrations_are_valid(name):
    cal = calibration.load(ROOT / "tools" / "calibrations" / f"{name}.toml")
    assert lut.build_table(cal).pressure_Pa.size == 64


# ---------------------------------------------------------------------------
# C and Python agree on the C test's variants

REJECTED = c_variants("rejected_variants")
ACCEPTED = c_variants("accepted_variants")


def test_variant_lists_parsed():
    assert len(REJECTED) >= 70 and len(ACCEPTED) >= 35
    fields = {f for _, settings in REJECTED for f, _ in settings}
    assert len(fields) == 30      # every float field of wc_calibration_t has a rejected variant


def _label(settings):
    return ", ".join(f"{f}={v:g}" for f, v in settings)


@pytest.mark.parametrize("code, settings", REJECTED, ids=[_label(s) for _, s in REJECTED])
def test_rejected_like_the_firmware(tmp_path, code, settings):
    path = write_variant(tmp_path, toml_changes(settings))
    with pytest.raises(CalibrationError) as e:
        calibration.load(path)
    message = str(e.value)
    if any(f == "heat_capacity_J_per_K" and v <= 0.0 for f, v in settings):
        # C = 0 is zero densities in the TOML file: each density's own rule
        assert "'thermal.separator_density'" in message, message
        return
    assert firmware_names()[code] in message, message      # the firmware's name of the failing check
    assert str(path) in message
    assert re.search(r"'(geometry|thermal|viscosity|friction|contact|hydraulics|control|engagement|film_lut)\.\w+'", message)
    if len(settings) == 1 and code not in ("WC_CAL_FRICTION_DOMAIN", "WC_CAL_VISCOSITY_RANGE",
                                           "WC_CAL_THERMAL_TIME_CONSTANT", "WC_CAL_FILM_COVERAGE",
                                           "WC_CAL_VFS_CURRENT_MAX", "WC_CAL_INNER_RADIUS",
                                           "WC_CAL_HEAT_CAPACITY"):
        section, name = BY_FIELD[settings[0][0]]
        assert f"'{section}.{name}'" in message, message   # a field's own rule names it


@pytest.mark.parametrize("code, settings", ACCEPTED, ids=[_label(s) for _, s in ACCEPTED])
def test_accepted_like_the_firmware(tmp_path, code, settings):
    assert code == "WC_CAL_OK"
    cal = calibration.load(write_variant(tmp_path, toml_changes(settings)))
    for field, value in settings:
        if field != "heat_capacity_J_per_K":
            assert cal.values[BY_FIELD[field][1]] == value


@pytest.mark.parametrize("section, name", [(s, n) for s, n, *_ in calibration.PARAMETERS])
@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_every_parameter_rejects_non_finite(tmp_path, section, name, value):
    path = write_variant(tmp_path, {name: value})
    with pytest.raises(CalibrationError, match=re.escape(f"'{section}.{name}'")):
        calibration.load(path)


# ---------------------------------------------------------------------------
# the issue's examples and the Python-only parameters

ISSUE = [
    # (changes, words the message must hold)
    ({"mv2": "0.36"}, ["'viscosity.mv2'", "viscosity_b1_per_K"]),
    ({"oil_conductance": "1e-40", "housing_conductance": "0.0"}, [C_NAMES["conductance_sum"]]),
    ({"theta2": "1e-38"}, ["'friction.theta2'", "theta2_K"]),
    ({"outer_radius": "1e30"}, ["'geometry.outer_radius'", "outer_radius_m"]),
    ({"mu3": "-0.52"}, [C_NAMES["friction_domain"]]),
    ({"friction_pairs": "1e30"}, ["'geometry.friction_pairs'"]),
    ({"friction_pairs": "65"}, ["'geometry.friction_pairs'"]),
    ({"friction_pairs": "8.5"}, ["'geometry.friction_pairs'", "whole number"]),
    ({"friction_pairs": "0"}, ["'geometry.friction_pairs'"]),
    ({"oil_conductance": "1e-300"}, ["'thermal.oil_conductance'", "float32"]),
    ({"housing_conductance": "1e-300"}, ["'thermal.housing_conductance'", "float32"]),
    ({"vfs_gain": "1e39"}, ["'hydraulics.vfs_gain'", "float32"]),
    ({"nodes": "100000"}, ["'film_lut.nodes'"]),
    ({"nodes": "1"}, ["'film_lut.nodes'"]),
    ({"nodes": "64.5"}, ["'film_lut.nodes'"]),
    ({"lining_density": "-1000.0"}, ["'thermal.lining_density'"]),
    ({"separator_density": "1e12"}, ["heat_capacity_J_per_K"]),               # C = 3.7e10 J/K
    # the film table made from the contact and film_lut sections breaks a film rule
    ({"roughness_rms": "1e-3"}, [C_NAMES["film_range"], "film table"]),      # h_bar up to 4 mm
    ({"contact_pressure_max": "1e12"}, [C_NAMES["film_range"]]),              # the last node 0 m
    ({"contact_pressure_max": "2.0e6"}, [C_NAMES["film_coverage"], "'film_lut.contact_pressure_max'"]),
    ({"separation_max_sigma": "1000"}, ["film"]),
    ({"youngs_modulus": "1e300", "asperity_density": "1e300"}, ["film"]),
]


@pytest.mark.parametrize("changes, words", ISSUE, ids=[",".join(f"{k}={v}" for k, v in c.items()) for c, _ in ISSUE])
def test_issue_examples_rejected(tmp_path, changes, words):
    path = write_variant(tmp_path, changes)
    with pytest.raises(CalibrationError) as e:
        calibration.load(path)
    for word in [*words, str(path)]:
        assert word in str(e.value), (word, str(e.value))


# ---------------------------------------------------------------------------
# the film rules on tables made by hand (the same cases as tests/c/test_calibration.c)

def _array(header: str, name: str) -> np.ndarray:
    body = re.search(name + r"\[\d+\] = \{(.*?)\};", header, re.S).group(1)
    return np.array([float(x.rstrip("f")) for x in re.findall(r"[-0-9.e+]+f", body)], dtype=np.float32)


@pytest.fixture()
def film():
    text = (ROOT / "lut" / "wc_table1_film.h").read_text()
    return [_array(text, f"wc_table1_film_{n}").astype(float) for n in ("pressure_Pa", "hbar_m", "slope_m_per_Pa")]


def _problem(p, h, s, cal=None):
    return calibration.film_problem(p, h, s, cal)


def test_film_table1_passes(film, cal):
    assert _problem(*film, cal) is None
    lut.check_table(lut.FilmTable(*film), cal)


@pytest.mark.parametrize("node", [0, 31, 63])
def test_film_rules_per_node(film, node):
    p, h, s = film
    for array, value, name in ((h, 0.0, "film_range"), (h, -3.7e-9, "film_range"), (h, 9.9e-10, "film_range"),
                               (h, 1.01e-3, "film_range"), (s, 1e-20, "film_not_monotone"),
                               (s, s[node] * 100.0, "film_not_monotone"), (p, math.nan, "film_table"),
                               (h, math.inf, "film_table"), (s, -math.inf, "film_table")):
        changed = [a.copy() for a in (p, h, s)]
        changed[[id(p), id(h), id(s)].index(id(array))][node] = value
        problem = _problem(*changed)
        assert problem is not None and problem.startswith(C_NAMES[name]), (name, value, problem)
    flat = [a.copy() for a in (p, h, s)]
    flat[2][node] = 0.0       # a flat node is monotone
    assert _problem(*flat) is None


def test_film_rules_table(film, cal):
    p, h, s = film
    assert _problem(p[:1], h[:1], s[:1]).startswith(C_NAMES["film_table"])
    long = np.arange(1, calibration.FILM_MAX_NODES + 2, dtype=float)
    assert _problem(long * 5000.0, 2e-5 - 1e-8 * long, np.full(long.size, -2e-12)).startswith(C_NAMES["film_table"])
    assert _problem(long[:-1] * 5000.0, 2e-5 - 1e-8 * long[:-1], np.full(long.size - 1, -2e-12), cal) is None
    q = p.copy(); q[10] = q[9]
    assert _problem(q, h, s).startswith(C_NAMES["film_axis"])
    q = p.copy(); q[0] = -1.0
    assert _problem(q, h, s).startswith(C_NAMES["film_range"])
    assert _problem(p - p[0], h, s, cal) is None                       # starting at 0 Pa
    g = h.copy(); g[20] = g[19]
    assert _problem(p, g, s).startswith(C_NAMES["film_not_monotone"])
    assert _problem(p, h * 0.1, s * 0.1).startswith(C_NAMES["film_range"])      # last node 0.7 nm
    assert _problem(p, h * 40.0, s * 40.0) is None                               # first node 0.96 mm
    assert _problem(p[:2], h[:2], s[:2], cal).startswith(C_NAMES["film_coverage"])
    assert _problem(p[[0, -1]], h[[0, -1]], np.zeros(2), cal) is None
    lut.check_table(lut.FilmTable(p[[0, -1]], h[[0, -1]], np.zeros(2)), cal)
    with pytest.raises(lut.TableError, match=re.escape(cal.path)):
        lut.check_table(lut.FilmTable(p[:2], h[:2], s[:2]), cal)


def test_film_fritsch_carlson_bound():
    p, h = np.array([0.0, 4.2e6]), np.array([2e-5, 1e-5])
    delta = float(np.float32((np.float32(h[1]) - np.float32(h[0])) / np.float32(4.2e6)))
    for alpha, beta in ((2.9999, 0.0), (0.0, 2.9999), (2.1, 2.1), (1.0, 1.0)):
        assert _problem(p, h, np.array([alpha, beta]) * delta) is None, (alpha, beta)
    for alpha, beta in ((3.01, 0.0), (0.0, 3.01), (2.2, 2.1), (10.0, 10.0)):
        assert _problem(p, h, np.array([alpha, beta]) * delta).startswith(C_NAMES["film_not_monotone"])


# ---------------------------------------------------------------------------
# wetclutch lut: refusals before anything is allocated or written

@pytest.mark.parametrize("nodes", ["100000", "10000000", "1025"])
def test_lut_refuses_too_many_nodes_before_allocating(tmp_path, nodes):
    r, out, seconds = run_lut(tmp_path, write_variant(tmp_path, {"nodes": nodes}), timeout=30)
    assert_refused(r, out, "'film_lut.nodes'", str(tmp_path / "variant.toml"))
    assert seconds < 20


def test_build_table_refuses_nodes_without_load(cal):
    # a Calibration made in code (with_values) bypasses load: build_table checks before linspace
    for nodes in (1e7, 1025, 1, 64.5, math.nan, math.inf):
        with pytest.raises(lut.TableError, match="film_lut.nodes"):
            lut.build_table(cal.with_values(nodes=nodes))


@pytest.mark.parametrize("changes, word", [
    ({"friction_pairs": "1e30"}, "'geometry.friction_pairs'"),
    ({"oil_conductance": "1e-300"}, "'thermal.oil_conductance'"),
    ({"mv2": "0.36"}, "'viscosity.mv2'"),
    ({"mu3": "-0.52"}, C_NAMES["friction_domain"]),
    ({"roughness_rms": "1e-3"}, C_NAMES["film_range"]),
])
def test_lut_refuses_invalid_calibration(tmp_path, changes, word):
    path = write_variant(tmp_path, changes)
    r, out, _ = run_lut(tmp_path, path)
    assert_refused(r, out, word, str(path))


@pytest.mark.parametrize("name", ["x\u00b2", "bad name", "1abc", "tab-le", "caf\u00e9", "a;b"])
def test_lut_refuses_a_name_that_is_not_a_c_identifier(tmp_path, name):
    r, out, _ = run_lut(tmp_path, TABLE1, "--name", name)
    assert_refused(r, out, "C identifier")
    with pytest.raises(lut.TableError):
        lut.c_identifier(name)


def test_lut_names_that_are_c_identifiers():
    assert lut.c_identifier("table1") == "table1"
    assert lut.c_identifier("Bench_2") == "bench_2"
    assert lut.c_identifier("_x") == "_x"


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 0.0, -1e-4, -0.0])
def test_max_error_must_be_finite_and_positive(value):
    with pytest.raises(lut.TableError, match="--max-error"):
        lut.check_max_error(value)
    assert lut.check_max_error(1e-4) == 1e-4


@pytest.mark.parametrize("value", ["nan", "inf", "0", "-1"])
def test_lut_refuses_max_error(tmp_path, value):
    r, out, _ = run_lut(tmp_path, TABLE1, "--max-error", value)
    assert_refused(r, out, "--max-error")
