"""The gear-set kinematics of a gearbox description, with numpy: speeds, ratios, element slips, mass matrix,
the torques a gear's closed elements carry.

Shaft speeds w (rad/s, one per [shafts] entry, in the file's order) obey, per simple planetary set, Willis'
equation

    w_sun + k w_ring - (1 + k) w_carrier = 0,        k = z_ring / z_sun

and per closed element one more: w_S = 0 (a brake on S), w_S1 - w_S2 = 0 (a clutch between S1 and S2). An
element's slip is the same row applied to w: slip = c_e . w. With the sets alone the box has
(shafts - sets) degrees of freedom; a gear closes enough elements to leave one (its speeds are a multiple of one
vector, ratio = w_input / w_output); a shift holds one element fewer, leaving two: every shaft speed, and so
every element's slip, is then a linear function of the turbine and output speeds,

    w = T [w_t, w_o]^T,        slip_e = c_e T [w_t, w_o]^T = a_e w_t - b_e w_o

(speed_map gives T, slip_coefficients a_e, b_e). Degrees of freedom are the null space of the constraint rows
(an SVD; a singular value below RANK_TOL times the largest counts as zero).

Kinetic energy: 1/2 sum_s J_s w_s^2 plus each set's planets spinning about their own axes,
1/2 J_p w_p^2 with w_p = w_carrier - (z_sun / z_planet)(w_sun - w_carrier), z_planet = (z_ring - z_sun) / 2
(their orbit is in the carrier's inertia). With w = T q, q = (w_t, w_o): KE = 1/2 q^T M q, M = T^T J T + sum
J_p p^T p (mass_matrix): the 2 x 2 mass matrix of the 2-DOF system.

Statics (gear_torques): in a gear without acceleration every shaft's torques balance; the meshes of a set act on
sun, ring and carrier in the proportion 1 : k : -(1 + k) (they do no work: the Willis row), a closed element
carries lambda_e along its own row (on S1, and -lambda_e on S2 for a clutch: the torque it exerts on its first
shaft), the turbine drives the input with T_t and the load takes T_out from the output. Shafts - sets - closed
= 1 unknown is left for T_out: a square linear system, one solution.
"""
from __future__ import annotations

import numpy as np

from .description import Element, Gearbox, GearboxError

RANK_TOL = 1e-9


def willis_rows(gb: Gearbox) -> np.ndarray:
    """One row per set: w_sun + k w_ring - (1 + k) w_carrier = 0."""
    rows = np.zeros((len(gb.sets), len(gb.shafts)))
    for i, ps in enumerate(gb.sets):
        rows[i, gb.shaft_index(ps.sun)] += 1.0
        rows[i, gb.shaft_index(ps.ring)] += ps.k
        rows[i, gb.shaft_index(ps.carrier)] -= 1.0 + ps.k
    return rows


def element_row(gb: Gearbox, element: Element | str) -> np.ndarray:
    """c_e: slip_e = c_e . w (w_S for a brake, w_S1 - w_S2 for a clutch)."""
    e = gb.element(element) if isinstance(element, str) else element
    row = np.zeros(len(gb.shafts))
    row[gb.shaft_index(e.shafts[0])] = 1.0
    if e.kind == "clutch":
        row[gb.shaft_index(e.shafts[1])] = -1.0
    return row


def constraints(gb: Gearbox, closed) -> np.ndarray:
    """The Willis rows and one row per closed element."""
    return np.vstack([willis_rows(gb)] + [element_row(gb, e)[None, :] for e in closed])


def null_space(a: np.ndarray) -> np.ndarray:
    """An orthonormal basis (columns) of the speeds a allows."""
    _, s, vt = np.linalg.svd(a)
    scale = s[0] if s.size else 1.0
    rank = int(np.sum(s > RANK_TOL * scale))
    return vt[rank:].T


def _clean(a: np.ndarray) -> np.ndarray:
    """Round-off (below RANK_TOL of the largest entry) set to exact zero: a held shaft's speed is 0, not 1e-16."""
    a = np.array(a, dtype=float)
    a[np.abs(a) <= RANK_TOL * np.max(np.abs(a))] = 0.0
    return a


def _where(gb: Gearbox, key: str) -> str:
    return f"{gb.path}: {key}"


def gear_speeds(gb: Gearbox, gear: str) -> np.ndarray:
    """Every shaft's speed per unit turbine speed in gear (input = 1). Raises GearboxError when the gear does not
    leave exactly one degree of freedom, holds the input or does not turn the output (a singular ratio)."""
    closed = gb.gears[gear]
    basis = null_space(constraints(gb, closed))
    dof = basis.shape[1]
    key = f"gears.{gear}"
    if dof != 1:
        detail = ("the box is locked" if dof == 0 else
                  "its elements' constraints are not independent of the sets'")
        raise GearboxError(f"{_where(gb, key)}: {list(closed)} leave {dof} degrees of freedom, a gear must leave "
                           f"exactly 1 ({detail}: a singular kinematics)")
    v = basis[:, 0]
    i_in, i_out = gb.shaft_index(gb.input_shaft), gb.shaft_index(gb.output_shaft)
    big = np.max(np.abs(v))
    if abs(v[i_in]) <= RANK_TOL * big:
        raise GearboxError(f"{_where(gb, key)}: {list(closed)} hold the input shaft '{gb.input_shaft}' (ratio 0: "
                           "a singular kinematics)")
    if abs(v[i_out]) <= RANK_TOL * big:
        raise GearboxError(f"{_where(gb, key)}: {list(closed)} hold the output shaft '{gb.output_shaft}' (an "
                           "infinite ratio: a singular kinematics)")
    return _clean(v / v[i_in])


def ratio(gb: Gearbox, gear: str) -> float:
    """i = w_turbine / w_output of gear, from the kinematics."""
    return 1.0 / float(gear_speeds(gb, gear)[gb.shaft_index(gb.output_shaft)])


def check(gb: Gearbox) -> dict:
    """Every gear's ratio ({gear: ratio}); raises GearboxError for the first gear that is not a gear."""
    return {g: ratio(gb, g) for g in gb.gears}


def speed_map(gb: Gearbox, held, key: str = "") -> np.ndarray:
    """T (shafts x 2): w = T [w_t, w_o] with the elements held closed and the others open. Raises GearboxError
    unless they leave exactly two degrees of freedom that the turbine and output speeds name."""
    basis = null_space(constraints(gb, held))
    where = _where(gb, key or f"elements held {list(held)}")
    if basis.shape[1] != 2:
        raise GearboxError(f"{where}: {list(held)} held leave {basis.shape[1]} degrees of freedom, a shift "
                           "needs 2 (turbine and output speed)")
    ends = basis[[gb.shaft_index(gb.input_shaft), gb.shaft_index(gb.output_shaft)], :]
    if abs(np.linalg.det(ends)) <= RANK_TOL * np.max(np.abs(ends)) ** 2:
        raise GearboxError(f"{where}: with {list(held)} held the turbine and output speeds are tied to each other "
                           "(they do not name the two degrees of freedom: a singular kinematics)")
    return _clean(basis @ np.linalg.inv(ends))


def slip_coefficients(gb: Gearbox, t_map: np.ndarray, element) -> tuple[float, float]:
    """(a_e, b_e) with slip_e = a_e w_t - b_e w_o in the 2-DOF system of t_map."""
    s = element_row(gb, element) @ t_map
    s[np.abs(s) <= RANK_TOL * np.max(np.abs(t_map))] = 0.0     # a held element's slip: exactly 0
    return float(s[0]), float(-s[1])


def inertias(gb: Gearbox, turbine: float | None = None, output: float | None = None,
             output_extra: float = 0.0) -> np.ndarray:
    """J per shaft: the description's, the input and output shafts' replaced when given (a vehicle's), plus
    output_extra on the output shaft (the vehicle's mass referred to it)."""
    j = np.array([s.inertia for s in gb.shafts], dtype=float)
    if turbine is not None:
        j[gb.shaft_index(gb.input_shaft)] = turbine
    if output is not None:
        j[gb.shaft_index(gb.output_shaft)] = output
    j[gb.shaft_index(gb.output_shaft)] += output_extra
    return j


def planet_rows(gb: Gearbox) -> list[tuple[float, np.ndarray]]:
    """(J_p, row) per set with planet inertia: the planets' own speed w_p = row . w."""
    out = []
    for ps in gb.sets:
        if ps.planet_spin_inertia <= 0.0:
            continue
        sun_per_planet = 2.0 / (ps.k - 1.0)              # z_sun / z_planet, z_planet = (z_ring - z_sun) / 2
        row = np.zeros(len(gb.shafts))
        row[gb.shaft_index(ps.carrier)] = 1.0 + sun_per_planet
        row[gb.shaft_index(ps.sun)] = -sun_per_planet
        out.append((ps.planet_spin_inertia, row))
    return out


def mass_matrix(gb: Gearbox, t_map: np.ndarray, j: np.ndarray | None = None) -> np.ndarray:
    """M (2 x 2) in (w_t, w_o): KE = 1/2 [w_t, w_o] M [w_t, w_o]^T, shafts (j, default the description's) and
    planets."""
    j = inertias(gb) if j is None else j
    m = t_map.T @ np.diag(j) @ t_map
    for jp, row in planet_rows(gb):
        p = row @ t_map
        m += jp * np.outer(p, p)
    return 0.5 * (m + m.T)


def full_mass(gb: Gearbox, j: np.ndarray | None = None) -> np.ndarray:
    """The shafts' mass matrix (shafts x shafts) with the planets' spin: KE = 1/2 w^T J w."""
    j = inertias(gb) if j is None else j
    full = np.diag(j).astype(float)
    for jp, row in planet_rows(gb):
        full += jp * np.outer(row, row)
    return full


def gear_torques(gb: Gearbox, gear: str, turbine_torque_Nm: float = 1.0) -> tuple[float, dict]:
    """(T_out, {element: lambda_e}) in gear without acceleration: the output torque and the torque each closed
    element carries (exerted on its first shaft; a brake's on its shaft from the housing), for a turbine torque
    T_t on the input. Virtual work: T_t w_t = T_out w_o (closed elements do not slip, meshes do no work)."""
    closed = gb.gears[gear]
    n = len(gb.shafts)
    e_in = np.zeros(n)
    e_in[gb.shaft_index(gb.input_shaft)] = 1.0
    e_out = np.zeros(n)
    e_out[gb.shaft_index(gb.output_shaft)] = 1.0
    columns = np.hstack([willis_rows(gb).T, constraints(gb, closed)[len(gb.sets):].T, -e_out[:, None]])
    if columns.shape[0] != columns.shape[1] or np.linalg.matrix_rank(columns) < n:
        raise GearboxError(f"{_where(gb, f'gears.{gear}')}: the torques of {list(closed)} are not determined "
                           "(a singular kinematics)")
    x = np.linalg.solve(columns, -turbine_torque_Nm * e_in)
    lam = x[len(gb.sets):len(gb.sets) + len(closed)]
    return float(x[-1]), {e: float(v) for e, v in zip(closed, lam)}


def constrained_accelerations(gb: Gearbox, held, torques: np.ndarray, j: np.ndarray | None = None) -> np.ndarray:
    """dw/dt of every shaft under external shaft torques (shafts,) with the sets and the held elements as ideal
    constraints (Lagrange multipliers): [J A^T; A 0][dw/dt; mu] = [tau; 0]. The reference the reduced 2-DOF model
    is checked against."""
    a = constraints(gb, held)
    full = full_mass(gb, j)
    n, m = full.shape[0], a.shape[0]
    kkt = np.block([[full, a.T], [a, np.zeros((m, m))]])
    rhs = np.concatenate([torques, np.zeros(m)])
    return np.linalg.lstsq(kkt, rhs, rcond=None)[0][:n]
