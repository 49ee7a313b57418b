"""model.FilmTable, the fast tabulated h_bar(p_c) and h(p_c), against the exact closed forms of model.py.

The table is what the bench simulator (20001 nodes) and the identification (4001 nodes) use for many
samples at once; model.hbar_from_pressure_m / separation_from_pressure_m solve eq. 15 by bisection.
"""
from __future__ import annotations

import numpy as np
import pytest

from wetclutch import calibration
from wetclutch.simulate import bench
from wetclutch.reference import model
from wetclutch.identify import friction

# Linear interpolation on nodes uniform in h: the error is at most dh^2/8 max|f''|, so it falls with the
# square of the node count. Measured maxima (Table 1 and bench_true, worst at the 4.2 MPa end, where h_bar
# curves most): h_bar 3.4e-6 relative and h 1.5e-6 sigma at 4001 nodes, 25 times less at 20001. The bounds
# are those measurements with a margin of about 1.5: a coarser grid or a wrong axis fails them.
BOUNDS = {  # nodes: (h_bar relative error, separation error in units of the roughness sigma)
    friction.FILM_TABLE_NODES: (5e-6, 2.2e-6),
    bench.BenchConfig().film_table_nodes: (2e-7, 9e-8),
}


def _pressures(cal, table):
    """The worst case of linear interpolation (midway between nodes in h) and a log grid over the domain."""
    _, _, p_min, p_max = model.film_domain(cal)
    h_mid = 0.5 * (table.separation_m[1:] + table.separation_m[:-1])
    return np.concatenate([model.contact_pressure_Pa(cal, h_mid), np.geomspace(p_min, p_max, 5000)])


@pytest.fixture(scope="module", params=["table1", "bench_true"])
def any_cal(request, root):
    return calibration.load(root / "tools" / "calibrations" / f"{request.param}.toml")


@pytest.mark.parametrize("nodes", sorted(BOUNDS))
def test_table_against_exact(any_cal, nodes):
    table = model.FilmTable(any_cal, nodes)
    p = _pressures(any_cal, table)
    hbar_bound, h_bound = BOUNDS[nodes]
    hbar_error = np.abs(table.hbar_from_pressure_m(p) / model.hbar_from_pressure_m(any_cal, p) - 1.0)
    h_error = np.abs(table.separation_from_pressure_m(p) - model.separation_from_pressure_m(any_cal, p))
    assert np.max(hbar_error) <= hbar_bound
    assert np.max(h_error) / any_cal.roughness_rms <= h_bound


def test_table_axis_and_clamping(cal):
    table = model.FilmTable(cal, friction.FILM_TABLE_NODES)
    assert np.all(np.diff(table.pressure_Pa) > 0.0)          # np.interp needs a strictly increasing axis
    h_min, h_max, p_min, p_max = model.film_domain(cal)
    # outside the film domain both forms clamp to its ends: an open clutch gets the thickest film
    for p in (0.0, 0.5 * p_min, p_min):
        assert table.separation_from_pressure_m(p) == h_max
        assert table.hbar_from_pressure_m(p) == pytest.approx(float(model.hbar_from_pressure_m(cal, p)), rel=1e-12)
    for p in (p_max, 2.0 * p_max):
        assert table.separation_from_pressure_m(p) == pytest.approx(h_min, rel=1e-12)
        assert table.hbar_from_pressure_m(p) == pytest.approx(float(model.hbar_from_pressure_m(cal, p)), rel=1e-9)


def test_identification_uses_the_table(cal):
    """identify's h_bar(F) is the model's table at its node count (one implementation)."""
    force = np.array([0.0, 903.0, 1188.0, 1613.0, 1e5])
    table = model.FilmTable(cal, friction.FILM_TABLE_NODES)
    assert np.array_equal(friction.hbar_of_force(cal, force), table.hbar_from_pressure_m(force / cal.friction_area))
