"""The rigid-body part of the 8-speed plant: coordinates, mass matrix, constraint rows and the constrained
(Lagrange multiplier) step.

COORDINATES. The physical speeds are x = [w_e, w_1 .. w_S, w_w]: the engine (crank, flywheel, converter pump),
every gearbox shaft of the description (the input shaft carries the converter's turbine wheel, the output
shaft the vehicle's output inertia) and the wheels. The planetary sets' Willis equations are always active,
so they are eliminated exactly: w = N q with N an orthonormal basis of their null space (wetclutch.gearbox.
kinematics.null_space; shafts - sets columns), x = G u, u = [w_e, q, w_w]. The meshes do no work, their
forces are not needed. Mass matrix M = G^T diag(J_e, J_box, I_v) G, J_box the shafts' inertias plus the
planets' spin (kinematics.full_mass), I_v = m r_w^2 (the vehicle at the wheels).

CONSTRAINTS (Lagrange multipliers). A friction joint j (the five elements, the lock-up clutch, the wheel brake)
has a row r_j (its slip s_j = r_j . u: kinematics.element_row for an element, w_e - w_input for the lock-up,
w_w for the brake). A locked joint adds r_j . u = 0 and carries the multiplier lambda_j (the torque it exerts
along its row, > 0 on its first shaft; the element's torque as the 1->2 plant signs it, > 0 opposing positive
slip, is -lambda_j). A slipping joint applies -sgn(s_j) T_j(|s_j|) r_j.

STEP (h = dt / substeps). Linearly implicit Euler in the velocities, the velocity-level constraint exact:

    [ M + h D   B^T ] [  du ]   [ h Q(u0)  ]
    [ B         0   ] [ -Lam] = [ -B u0    ]            lambda = Lam / h

Q: every applied torque at u0; D: the stiff linear parts taken implicitly (each slipping joint's friction slope
dT/d|s| r r^T, the driveshaft's damping and stiffness (c + h k) g g^T with g . u = w_o - r_f w_w). B: the locked
joints' rows. u1 = u0 + du satisfies B u1 = 0 exactly (no drift).

STICK-SLIP, deterministic: a locked joint stays locked while |lambda| <= its static capacity; else the one with
the largest |lambda| / capacity breaks loose (slipping against lambda: sgn(s) = -sgn(lambda), T = T_kinetic(0)),
and the step is solved again. A slipping joint becomes a candidate when its slip changed sign over the last
substep or is within LOCK_BAND of zero and its static capacity is at least LOCK_MIN_NM; a candidate locks if the
momentum-conserving projection onto its constraint (the impulse removing the remaining slip, [M B^T; B 0]) is
possible (its row independent of the other locked rows) and, in the projected state, the constrained step's
lambda is within its capacity. The projection's kinetic energy loss is that joint's friction loss
(-Lam_j s_j / 2). No state flips back and forth at zero slip: locking needs |lambda| <= static capacity,
breaking |lambda| > it, and the kinetic torque at zero slip is below the static capacity.
"""
from __future__ import annotations

import numpy as np

from ...gearbox import kinematics

LOCK_BAND = 1e-3            # rad/s: a slipping joint this close to zero slip is tested for lock-up
LOCK_MIN_NM = 0.5           # a joint whose static capacity is below this never locks (an open element's drag)


class Driveline:
    """The mass matrix and the rows in u = [w_e, q, w_w] (module docstring)."""

    def __init__(self, gb, *, engine_inertia: float, shaft_inertias: np.ndarray, vehicle_inertia: float,
                 final_drive: float):
        self.gb = gb
        n_s = len(gb.shafts)
        self.n_shafts = n_s
        basis = kinematics.null_space(kinematics.willis_rows(gb))
        self.N = basis                                     # shafts x dof
        dof = basis.shape[1]
        self.n = dof + 2
        G = np.zeros((n_s + 2, self.n))
        G[0, 0] = 1.0
        G[1:1 + n_s, 1:1 + dof] = basis
        G[-1, -1] = 1.0
        self.G = G
        full = np.zeros((n_s + 2, n_s + 2))
        full[0, 0] = engine_inertia
        full[1:1 + n_s, 1:1 + n_s] = kinematics.full_mass(gb, shaft_inertias)
        full[-1, -1] = vehicle_inertia
        self.M = G.T @ full @ G
        self.M = 0.5 * (self.M + self.M.T)
        self.i_in = gb.shaft_index(gb.input_shaft)
        self.i_out = gb.shaft_index(gb.output_shaft)
        self.engine_row = self._row(engine=1.0)
        self.input_row = self._row(shafts={self.i_in: 1.0})
        self.output_row = self._row(shafts={self.i_out: 1.0})
        self.wheel_row = self._row(wheel=1.0)
        self.shaft_row = self.output_row - final_drive * self.wheel_row        # g: driveshaft twist rate
        self.element_rows = np.array([self.reduce(0.0, kinematics.element_row(gb, e), 0.0) for e in gb.elements])
        self.lockup_row = self.engine_row - self.input_row
        self.brake_row = self.wheel_row.copy()

    def reduce(self, engine: float, shafts: np.ndarray, wheel: float) -> np.ndarray:
        """A row over the physical speeds x, in u."""
        return np.concatenate([[engine], shafts, [wheel]]) @ self.G

    def _row(self, engine: float = 0.0, shafts: dict | None = None, wheel: float = 0.0) -> np.ndarray:
        s = np.zeros(self.n_shafts)
        for k, v in (shafts or {}).items():
            s[k] = v
        return self.reduce(engine, s, wheel)

    def coordinates(self, w_engine: float, shaft_speeds: np.ndarray, w_wheel: float) -> np.ndarray:
        """u for physical speeds (the shaft speeds must satisfy the Willis equations)."""
        return np.concatenate([[w_engine], self.N.T @ shaft_speeds, [w_wheel]])

    def shaft_speeds(self, u: np.ndarray) -> np.ndarray:
        return self.N @ u[1:-1]

    def kinetic_energy(self, u: np.ndarray) -> float:
        return 0.5 * float(u @ self.M @ u)


def solve(K: np.ndarray, B: np.ndarray | None, rhs_u: np.ndarray, rhs_c: np.ndarray | None):
    """(du, Lam) of [K B^T; B 0][du; -Lam] = [rhs_u; rhs_c] (B None or empty: du = K^-1 rhs_u)."""
    if B is None or B.shape[0] == 0:
        return np.linalg.solve(K, rhs_u), np.zeros(0)
    n, m = K.shape[0], B.shape[0]
    kkt = np.zeros((n + m, n + m))
    kkt[:n, :n] = K
    kkt[:n, n:] = B.T
    kkt[n:, :n] = B
    x = np.linalg.solve(kkt, np.concatenate([rhs_u, rhs_c]))
    return x[:n], -x[n:]


def independent(B: np.ndarray) -> bool:
    """Whether the rows of B are linearly independent (a joint whose row depends on the locked ones cannot add
    a constraint of its own: its slip is already held at zero by them)."""
    if B.shape[0] <= 1:
        return bool(B.shape[0] == 0 or np.any(B != 0.0))
    s = np.linalg.svd(B, compute_uv=False)
    return bool(s[-1] > 1e-9 * s[0])
