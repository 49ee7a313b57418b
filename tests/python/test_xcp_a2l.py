"""The A2L of the XCP slave (DESIGN 13), read by a parser nobody here wrote (pya2ldb): generated from the
calibration image's layout and the measured signals' table, with the addresses wc_tcu --xcp-layout prints
(resolved by the compiler in the linked program). The session against a running wc_tcu, where the addresses
are read back over XCP, is tests/python/test_xcp_session.py."""
from __future__ import annotations

import json
import pytest

from cli_support import assert_one_line_error, run
from wetclutch.calibration import gearbox_image, image_layout
from wetclutch.calibration.measurements import SIGNALS, TYPES
from wetclutch.generate import a2l, xcp_signals
from wetclutch.hil import xcp_session


@pytest.fixture(scope="module")
def layout(tcu):
    return a2l.read_layout(tcu=tcu)


@pytest.fixture(scope="module")
def parsed(layout, tmp_path_factory):
    path = tmp_path_factory.mktemp("a2l") / "wetclutch.a2l"
    a2l.write_a2l(layout, path)
    return path, xcp_session.read_a2l(path)


def test_signal_table_regenerates_byte_identically(tmp_path):
    out = xcp_signals.write(tmp_path / "wc_xcp_signals.c")
    assert out.read_text() == xcp_signals.DEFAULT_OUT.read_text(), \
        "src/port/wc_xcp_signals.c differs from its generator: python -m wetclutch.generate.xcp_signals"


def test_program_layout_matches_the_sources(layout):
    assert layout["regions"]["cal"]["size"] == image_layout.payload_bytes()
    assert [s["name"] for s in layout["signals"]] == [s.name for s in SIGNALS]
    bases = sorted(r["base"] for r in layout["regions"].values())
    spans = sorted((r["base"], r["base"] + r["size"]) for r in layout["regions"].values())
    assert all(a[1] <= b[0] for a, b in zip(spans, spans[1:])), "regions overlap"
    assert len(set(bases)) == 5 + a2l.ELEMENTS
    assert layout["regions"]["gearbox"]["size"] == gearbox_image.payload_bytes()


def test_every_characteristic_at_its_layout_offset(layout, parsed):
    _, desc = parsed
    chars = desc["characteristics"]
    base = layout["regions"]["cal"]["base"]
    gearbox_base = layout["regions"]["gearbox"]["base"]
    element_names = {f"element{e}.{f.name}" for e in range(a2l.ELEMENTS) for f in image_layout.FIELDS
                     if f.group == "clutch"}
    assert set(chars) == {f.name for f in image_layout.FIELDS} | {f.name for f in gearbox_image.FIELDS} | element_names
    for f in image_layout.FIELDS:
        address, deposit, kind = chars[f.name]
        assert address == base + f.offset, f.name
        assert deposit == a2l.A2L_TYPES[f.ctype][1], f.name
        assert kind == ("VALUE" if f.count == 1 else "VAL_BLK"), f.name
    for f in gearbox_image.FIELDS:   # the gearbox region (issue 29 item 1)
        address, deposit, kind = chars[f.name]
        assert address == gearbox_base + f.offset, f.name
        assert deposit == a2l.A2L_TYPES[f.ctype][1], f.name
        assert kind == ("VAL_BLK" if f.dims else "VALUE"), f.name
    for e in range(a2l.ELEMENTS):    # each element's clutch: its calibration payload's clutch fields
        element_base = layout["regions"][f"element{e}"]["base"]
        assert layout["regions"][f"element{e}"]["size"] == image_layout.payload_bytes()
        for f in image_layout.FIELDS:
            if f.group == "clutch":
                assert chars[f"element{e}.{f.name}"][0] == element_base + f.offset, (e, f.name)


def test_gearbox_characteristics_are_read_only_tables(parsed):
    """The gearbox's characteristics: READ_ONLY (the slave refuses a write there), and a tool that reshapes a
    table's bytes by the A2L (pya2ldb's shape and order) sees each value where the C struct has it: the 8HP
    image's gearbox.shift.slip_a[shift][element] is the table's slip a of that shift's element."""
    import numpy as np
    import pya2l
    from pya2l import model
    from pya2l.api import inspect
    path, _ = parsed
    session = pya2l.import_a2l(str(path), in_memory=True, progress_bar=False, loglevel="ERROR")
    chars = {c.name: c for c in session.query(model.Characteristic).all()}
    values = gearbox_image.read_image(_8hp_gearbox_image())
    for f in gearbox_image.FIELDS:
        c = chars[f.name]
        assert c.read_only is True, f.name
        if not f.dims:
            continue
        view = inspect.Characteristic(session, f.name)
        table = np.asarray(values[f.name]).reshape(view.fnc_np_shape, order=view.fnc_np_order)
        assert table.shape == tuple(gearbox_image.BOUNDS[d] for d in f.dims), f.name
    slip_a = np.asarray(values["gearbox.shift.slip_a"]).reshape(
        inspect.Characteristic(session, "gearbox.shift.slip_a").fnc_np_shape,
        order=inspect.Characteristic(session, "gearbox.shift.slip_a").fnc_np_order)
    # lut/wc_8hp_gearbox.h's second row, 1-3 (E on, A off): slip a of A -0.811765, of D 1.34725, of E 0.905882
    assert slip_a[1, 0] == pytest.approx(-0.811765, rel=1e-6) and slip_a[1, 3] == pytest.approx(1.34725, rel=1e-6)
    assert slip_a[1, 4] == pytest.approx(0.905882, rel=1e-6) and slip_a[1, 1] == 0.0
    for c in chars.values():   # read only: the gearbox and the elements; the calibration page is written
        assert c.read_only is c.name.startswith(("gearbox.", "element")), c.name


def test_every_measurement_at_the_programs_address(layout, parsed):
    _, desc = parsed
    meas = desc["measurements"]
    offsets = {s["name"]: s["offset"] for s in layout["signals"]}
    assert set(meas) == {s.name for s in SIGNALS}
    for s in SIGNALS:
        address, datatype = meas[s.name]
        assert address == layout["regions"][s.region]["base"] + offsets[s.name], s.name
        assert datatype == TYPES[s.ctype][0], s.name


def _8hp_gearbox_image() -> bytes:
    import tomllib
    from pathlib import Path
    table = Path(__file__).resolve().parents[2] / "tools" / "gearboxes" / "8hp_shifts.toml"
    with open(table, "rb") as f:
        return gearbox_image.image_bytes_of(gearbox_image.values_from_table(tomllib.load(f)))


def test_units_and_limits_from_the_sources(parsed):
    """Each characteristic's conversion carries the layout's unit, its limits the layout's limits."""
    import pya2l
    from pya2l import model
    path, _ = parsed
    session = pya2l.import_a2l(str(path), in_memory=True, progress_bar=False, loglevel="ERROR")
    units = {c.name: c.unit for c in session.query(model.CompuMethod).all()}
    for c in session.query(model.Characteristic).all():
        name = c.name.split(".", 1)[1] if c.name.startswith("element") else c.name   # element3.clutch.mu1
        f = image_layout.BY_NAME.get(name) or gearbox_image.BY_NAME[name]
        assert units[c.conversion] == f.unit, c.name
        # the A2L writes the float's repr: the limit exactly
        assert (c.lowerLimit, c.upperLimit) == (pytest.approx(f.lower, rel=0), pytest.approx(f.upper, rel=0)), c.name


def test_a_layout_of_another_build_is_refused(layout, tmp_path):
    other = json.loads(json.dumps(layout))
    other["regions"]["cal"]["size"] += 4
    bad = tmp_path / "layout.json"
    bad.write_text(json.dumps(other))
    with pytest.raises(a2l.A2lError, match="calibration page has"):
        a2l.read_layout(layout_file=bad)
    other = json.loads(json.dumps(layout))
    other["signals"] = other["signals"][1:]
    bad.write_text(json.dumps(other))
    with pytest.raises(a2l.A2lError, match="does not know the signal slip_rad_s"):
        a2l.read_layout(layout_file=bad)
    bad.write_text("{not json")
    with pytest.raises(a2l.A2lError, match="not JSON"):
        a2l.read_layout(layout_file=bad)


def test_cli_writes_the_a2l_or_says_why(tcu, tmp_path, capsys):
    out = tmp_path / "x" / "wetclutch.a2l"
    code, stdout, err = run(["a2l", "--tcu", tcu, "--out", out], capsys)
    assert code == 0, err
    assert out.read_text().startswith("ASAP2_VERSION 1 71")
    code, stdout, err = run(["a2l", "--tcu", tmp_path / "no_such_tcu", "--out", out], capsys)
    assert_one_line_error(code, err, "cannot read the XCP layout")
