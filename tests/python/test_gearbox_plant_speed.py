"""The 8-speed plant's hot paths written for speed (issue 31 item 5) compute the same numbers, to the bit, as the
forms they replace: the steady film's table read in plain Python against FilmTable (numpy's clip and interp), the
element's contact, viscosity, kinetic torque and slope against the bench's _Physics and the original
expressions, and an idle element's skipped substeps against calling them."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from wetclutch.simulate.gearbox_plant import Plant8, load_plant8

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def plant():
    return Plant8.in_gear(load_plant8(ROOT / "tools" / "plants" / "8hp" / "nominal.toml"), "3", 12.0, pedal=0.3,
                          record=False)


def test_steady_separation_is_the_film_table_s(plant):
    rng = np.random.default_rng(7)
    for el in plant.elements:
        table = el._film_table
        p = table.pressure_Pa
        # random pressures over (and beyond) the table, every node exactly, and halfway between nodes
        pressures = np.concatenate([rng.uniform(-0.1 * p[-1], 1.1 * p[-1], 20000), p, 0.5 * (p[1:] + p[:-1]),
                                    [table.pressure_min_Pa, table.pressure_max_Pa, 0.0]])
        for force_N in (pressures * el.area).tolist() + (p * el.area).tolist():
            expected = float(table.separation_from_pressure_m(force_N / el.area))     # as the element had it
            assert el._steady_separation_m(force_N) == expected, (el.name, force_N)
        # the nodes themselves (a force whose pressure is a node exactly)
        for pa in p.tolist():
            assert el._steady_separation_m(pa * el.area) == float(
                table.separation_from_pressure_m(pa * el.area / el.area)), (el.name, pa)


def test_element_contact_viscosity_and_kinetic_are_the_physics(plant):
    rng = np.random.default_rng(3)
    for el in plant.elements:
        ph = el._ph
        for h in rng.uniform(ph.h_min, ph.h_max, 300).tolist():
            el._set_film(h)
            assert (el.f_c, el.hbar) == ph.contact(h)
        for theta in rng.uniform(-30.0, 250.0, 300).tolist():
            el._set_theta(theta)
            assert el.mu_v == float(ph.viscosity(theta))
            assert el.temp == 1.0 + ph.mu3_th2 * (theta - ph.th1)
            el._set_film(el.h)
            assert el.static == el.scale * ph.static_factor * ph.rn * ph.mu2 * el.temp * el.f_c
            coul_k = el.scale * ph.rn * el.temp * el.f_c
            assert el.coul_k == coul_k
            for w in rng.uniform(0.0, 600.0, 20).tolist():
                x = el.aer_q * w * w
                e = math.exp(-ph.r_eff * w / ph.vs)
                expected = (coul_k * (ph.mu1 + ph.dmu * e) + el.visc_c * w / (1.0 + x),
                            -coul_k * ph.dmu * (ph.r_eff / ph.vs) * e
                            + el.visc_c * (1.0 - x) / ((1.0 + x) * (1.0 + x)))
                assert el.kinetic_slope(w) == expected


def test_skipping_idle_substeps_changes_nothing():
    """plant.step calls substep only on the elements step_begin did not find idle: run a drive twice, once
    calling every element's substep, and compare every state channel exactly."""
    params = load_plant8(ROOT / "tools" / "plants" / "8hp" / "nominal.toml")
    runs = []
    for skip in (True, False):
        p = Plant8.in_gear(params, "2", 6.0, pedal=0.2)
        if not skip:
            for el in p.elements:
                step_begin = el.step_begin

                def begin(i, el=el, step_begin=step_begin):
                    step_begin(i)
                    el._idle_seen = el._idle
                    el._idle = False        # the plant calls substep; substep returns at the same branches

                el.step_begin = begin
        for k in range(1500):
            # 2 -> 3 by hand: the off-going element released, the on-coming filled, then the rest open
            cur = {n: (1000.0 if n in p.gb.gears["2"] else 0.0) for n in p.names}
            on = next(iter(set(p.gb.gears["3"]) - set(p.gb.gears["2"])))
            off = next(iter(set(p.gb.gears["2"]) - set(p.gb.gears["3"])))
            if k >= 300:
                cur[on] = min(1000.0, 200.0 + (k - 300) * 2.0)
                cur[off] = max(0.0, 1000.0 - (k - 300) * 4.0)
            p.step(cur, 0.0, 0.4)
        runs.append(p.record())
        if not skip:
            assert any(getattr(el, "_idle_seen", False) for el in p.elements)   # the rule did apply somewhere
    a, b = runs
    assert a.keys() == b.keys()
    for c in a:
        np.testing.assert_array_equal(a[c], b[c], err_msg=c)
