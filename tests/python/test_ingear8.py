"""The in-gear hold at full load (issue 29's in-gear target; wetclutch.shift.ingear8): the firmware's transmission
holding a gear on the 8-speed plant, the slip and margin measures and their verdicts."""
import json
import math

import numpy as np
import pytest

from wetclutch import gearbox as gearbox_pkg
from wetclutch.reference.model.inverse import holding_inverse
from wetclutch.shift import ingear8
from wetclutch.shift.matrix8 import _plant_and_models, plant_path

FAST = {"settle_s": 0.3, "duration_s": 0.3}


@pytest.fixture(scope="module")
def rows():
    return [ingear8.hold_gear("nominal", gear, 80.0, **FAST) for gear in (2, 7)]


def test_the_verdicts_follow_the_numbers(rows):
    for r in rows:
        assert len(r["elements"]) == 3 and set(r["elements"]) == set(r["closed"])
        for e, x in r["elements"].items():
            assert math.isfinite(x["slip_max_rpm"]) and x["slip_max_rpm"] >= 0.0, (r["gear"], e)
            assert x["over_commanded"] == (x["capacity_model_over_request_max"] > 1.0 + ingear8.OVER_TOLERANCE)
            assert x["margin_true_min"] <= x["margin_true_mean"]
        assert r["slip_ok"] == all(x["slip_max_rpm"] <= ingear8.SLIP_LIMIT_RPM for x in r["elements"].values())
        assert r["over_commanded"] == [e for e in r["closed"] if r["elements"][e]["over_commanded"]]
        assert r["ok"] == (r["slip_ok"] and not r["over_commanded"])
        assert r["worst_slip_rpm"] == max(x["slip_max_rpm"] for x in r["elements"].values())
        assert r["margin_true_min"] == min(x["margin_true_min"] for x in r["elements"].values())


def test_the_gear_holds_and_the_tcu_follows_its_holding_rule(rows):
    """At full load the closed elements stay locked; the TCU's current is its rule's (the locked inverse of
    max(need x 1.3, 30 N m)), whose capacity in the TCU's own model is the request x (1 + the clutch calibration's
    holding_margin): the two margins stack."""
    gb = gearbox_pkg.load(str(_plant_and_models(str(plant_path("nominal")))[0].gearbox.path))
    for r in rows:
        assert r["slip_ok"] and r["follows_rule"], ingear8.line(r)
        assert abs(r["turbine_rpm_mean"] - ingear8.RPM_HOLD) < 10.0           # the dyno holds the speed
        for e, x in r["elements"].items():
            assert x["locked_fraction"] == 1.0
            stacked = 1.0 + gb.element(e).calibration.holding_margin
            assert x["capacity_model_over_request_max"] == pytest.approx(stacked, rel=1e-3)
            assert x["margin_true_min"] > 1.0                                  # locked: capacity above the load


def test_the_closed_elements_carry_the_tables_shares(rows):
    """Physics: held at constant speed (no inertia torque) each closed element carries |holding torque per N m| x
    the gearbox input torque, within the open elements' drag (a few per cent at 80 degC)."""
    for r in rows:
        for e, x in r["elements"].items():
            assert x["carried_per_input"] == pytest.approx(abs(x["holding_torque_per_Nm"]), rel=0.05), (r["gear"], e)


def test_a_released_element_is_seen_slipping():
    """Negative: element C of 3rd (B, C, E) at 0 mA in the plant slips far beyond 5 rpm; the row misses the slip
    target and shows the TCU's gear-slip watch holding the gear at the maximum current (not its rule)."""
    r = ingear8.hold_gear("nominal", 3, 80.0, force_mA={"C": 0.0}, **FAST)
    assert r["elements"]["C"]["slip_max_rpm"] > 10 * ingear8.SLIP_LIMIT_RPM
    assert r["worst_slip_element"] == "C" and not r["slip_ok"] and not r["ok"]
    assert not r["follows_rule"] and r["elements"]["B"]["current_max_mA"] == pytest.approx(1000.0)


def test_the_rule_current_is_the_reference_holding_inverse():
    cal = gearbox_pkg.load(str(_plant_and_models(str(plant_path("nominal")))[0].gearbox.path)).element("D").calibration
    theta, request = np.array([20.0, 80.0, 110.0]), np.array([40.0, 180.0, 5000.0])
    got = ingear8.holding_current_mA(cal, theta, request)
    want = [holding_inverse(cal, float(t), float(q))["current_mA"] for t, q in zip(theta, request)]
    assert got == pytest.approx(want, rel=1e-9)
    assert ingear8.holding_request_Nm(-0.5, [10.0, 100.0]).tolist() == pytest.approx([30.0, 65.0])


def test_the_command_line_writes_its_rows(tmp_path, capsys):
    out = tmp_path / "ingear8.json"
    rc = ingear8.main(["--vehicles", "light", "--oil", "110", "--gears", "8", "--settle", "0.2", "--duration", "0.1",
                       "--out", str(out)])
    rows = json.loads(out.read_text())
    assert len(rows) == 1 and rows[0]["gear"] == 8 and rows[0]["vehicle"] == "light"
    assert rc == (0 if rows[0]["ok"] else 1)
    assert "| light | 110 |" in capsys.readouterr().out
