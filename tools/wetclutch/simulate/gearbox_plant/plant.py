"""Plant8: the 8-speed vehicle stepped at the TCU's period (the package docstring has the whole model; the
mechanics module the constrained step and the stick-slip rules)."""
from __future__ import annotations

import math
import operator

import numpy as np

from ...gearbox import kinematics
from ..plant import GRAVITY
from . import mechanics
from .element import TrueElement
from .mechanics import LOCK_BAND, LOCK_MIN_NM, Driveline
from .params import Plant8Params
from .powertrain import Converter, Engine, Lockup, WheelBrake
from .truth import Recorder

DT_S = 1e-3
SUBSTEPS = 4
ROLL_SPEED_M_S = 0.05       # rolling resistance ramps in over +-0.05 m/s (as the 1->2 plant: no stiction)
TINY_SLIP = 1e-9            # rad/s: a slip this small keeps its last direction
IMPLICIT_STIFFNESS = 0.05   # a slipping joint whose h x slope x mobility exceeds this is taken implicitly
E_ROW, IN_ROW, WH_ROW, SH_ROW, OUT_ROW, J0 = range(6)     # R_all: engine, input, wheel, driveshaft, output, joints


class Plant8:
    """The 8-speed vehicle; see the package docstring. Start it with in_gear(...), then step(...)."""

    def __init__(self, params: Plant8Params, *, oil_degC: float | None = None,
                 friction_scale: dict | None = None, substeps: int = SUBSTEPS, record: bool = True):
        p = params
        v = p.vehicle
        self.params = p
        self.gb = p.gearbox
        self.dt = DT_S
        self.n_sub = int(substeps)
        if self.n_sub < 1:
            raise ValueError(f"substeps {substeps!r} must be >= 1")
        self.hs = DT_S / self.n_sub
        self.oil_degC = v.oil_temperature if oil_degC is None else float(oil_degC)
        if not math.isfinite(self.oil_degC):
            raise ValueError(f"oil_degC {oil_degC!r} is not finite")
        self.housing_degC = self.oil_degC + v.housing_offset
        scales = dict(p.friction_scale)
        for name, value in (friction_scale or {}).items():
            if name not in scales or not float(value) > 0.0:
                raise ValueError(f"friction_scale: {name!r} {value!r} (elements {list(scales)}, a factor > 0)")
            scales[name] = float(value)
        # the fill: the vehicle file's piston (its true clutch's) and its fill volume give the stroke; the rates
        # per fill volume apply to every element (each fills in the same time)
        if v.fill_volume > 0.0:
            rate_gain, rate_max = v.fill_flow_gain / v.fill_volume, v.fill_flow_max / v.fill_volume
            stroke = v.fill_volume / v.clutch_cal.piston_area
        else:
            rate_gain, rate_max, stroke = 0.0, 0.0, 0.0
        self.elements = [TrueElement(e.name, p.truth[e.name], friction_scale=scales[e.name],
                                     oil_degC=self.oil_degC, housing_degC=self.housing_degC,
                                     fill_rate_gain=rate_gain, fill_rate_max=rate_max, stroke_m=stroke,
                                     aeration_speed=p.aeration_speed, dt_s=DT_S,
                                     substeps=self.n_sub)
                         for e in self.gb.elements]
        self.names = tuple(e.name for e in self.gb.elements)
        self.engine = Engine(p, DT_S, self.n_sub)
        self.converter = Converter(p)
        self.lockup = Lockup(p, DT_S, self.n_sub)
        self.brake = WheelBrake()
        self.joints = self.elements + [self.lockup, self.brake]
        self.joint_names = self.names + ("lockup", "brake")
        j = kinematics.inertias(self.gb, output=v.output_inertia)
        j[self.gb.shaft_index(self.gb.input_shaft)] += p.converter_turbine_inertia
        self.rw, self.rf = v.wheel_radius, v.final_drive
        self.Iv = v.vehicle_mass * v.wheel_radius ** 2
        self.J_out = float(j[self.gb.shaft_index(self.gb.output_shaft)])
        self.dl = Driveline(self.gb, engine_inertia=p.engine_inertia, shaft_inertias=j, vehicle_inertia=self.Iv,
                            final_drive=self.rf)
        self.rows = np.vstack([self.dl.element_rows, self.dl.lockup_row, self.dl.brake_row])
        dl = self.dl
        self.R_all = np.vstack([dl.engine_row, dl.input_row, dl.wheel_row, dl.shaft_row, dl.output_row, self.rows])
        self.R_allT = self.R_all.T.copy()
        self._out_row = self.R_all[OUT_ROW].copy()      # the output speed's row (the same numbers as R_all's)
        m_inv = np.linalg.inv(dl.M)
        self.mob = [float(r @ m_inv @ r) for r in self.rows]     # unconstrained slip mobility per joint
        self.ks, self.cs = v.shaft_stiffness, v.shaft_damping
        self.ch = self.cs + self.hs * self.ks        # the driveshaft taken implicitly: T_s(u1) = k phi0 + ch g u1
        self.K0 = dl.M + (self.hs * self.ch) * np.outer(dl.shaft_row, dl.shaft_row)
        self._kkt_cache: dict = {}
        g = math.atan(v.road_grade / 100.0)
        self.road_const = v.wheel_radius * v.vehicle_mass * GRAVITY * math.sin(g)
        self.road_roll = v.wheel_radius * v.vehicle_mass * GRAVITY * v.rolling_resistance * math.cos(g)
        self.road_drag = v.wheel_radius ** 3 * 0.5 * v.air_density * v.drag_area
        self.ratios = kinematics.check(self.gb)
        n_j = len(self.joints)
        self.n_u, self.n_all = self.dl.n, self.R_all.shape[0]      # sizes the substep reads every time
        self._joint_zeros = [0.0] * n_j                             # f's joint entries before the friction
        self.locked = [False] * n_j
        self.dir = [1.0] * n_j
        self.cand = [False] * n_j
        self.torque = [0.0] * n_j          # each joint's torque (> 0 opposing positive slip), last substep
        self.u = np.zeros(self.dl.n)
        self.phi = 0.0
        self.t = 0.0
        self.accel = 0.0
        self.jerk = 0.0
        self.gear = None
        self.e = {k: 0.0 for k in ("engine", "converter", "road", "damping")}
        self.e_joint = [0.0] * n_j          # friction energy per joint (elements, lock-up, brake), J
        self.ke0 = self.pe0 = 0.0
        self._last = {}
        self._sp_of_u = (None, None)        # (u, (R_all @ u).tolist()) as truth.state_of left it
        self.recorder = Recorder(self, keep=record)   # a drive cycle keeps its own (1.8 M periods)

    # ------------------------------------------------------------------ initialisers
    @classmethod
    def in_gear(cls, params: Plant8Params, gear: str, speed_m_s: float, *, pedal: float = 0.0,
                currents_mA: dict | None = None, lockup_current_mA: float | None = None,
                brake_Nm: float = 0.0, oil_degC: float | None = None, theta_degC: dict | float | None = None,
                friction_scale: dict | None = None, substeps: int = SUBSTEPS, record: bool = True) -> "Plant8":
        """The plant in gear at a vehicle speed (negative in R), in a steady state: the gear's elements at
        currents_mA (default: the gear's elements at their maximum current, the others at 0), the lock-up at
        lockup_current_mA (default: its maximum above the idle speed, 0 below), the engine at the speed where
        its torque at pedal meets the converter's (locked: the turbine's; below the idle speed the idle
        governor's torque), the driveshaft wound to the torque the common acceleration needs, brake_Nm held
        (locked at standstill), the elements' packs at theta_degC (default the oil's)."""
        plant = cls(params, oil_degC=oil_degC, friction_scale=friction_scale, substeps=substeps, record=record)
        plant._start(str(gear), float(speed_m_s), float(pedal), currents_mA, lockup_current_mA, float(brake_Nm),
                     theta_degC)
        return plant

    def _start(self, gear, speed, pedal, currents, lockup_mA, brake_Nm, theta):
        if gear not in self.gb.gears:
            raise ValueError(f"gear {gear!r} is not a gear of {self.gb.path} ({', '.join(self.gb.gears)})")
        for name, val in (("speed_m_s", speed), ("pedal", pedal)):
            if not math.isfinite(val):
                raise ValueError(f"{name} {val!r} is not finite")
        self.gear = gear
        pedal = min(max(pedal, 0.0), 1.0)
        closed = self.gb.gears[gear]
        cur = {n: (e.i_max if n in closed else 0.0) for n, e in zip(self.names, self.elements)}
        cur.update(self._currents(currents, partial=True))
        for k, el in enumerate(self.elements):
            th = theta.get(self.names[k]) if isinstance(theta, dict) else theta
            el.set_steady(cur[self.names[k]], th)
        w_w = speed / self.rw
        w_o = self.rf * w_w
        w_t = self.ratios[gear] * w_o
        shafts = kinematics.gear_speeds(self.gb, gear) * w_t
        eng = self.engine
        if lockup_mA is None:
            lockup_mA = self.lockup.i_max if w_t >= eng.idle else 0.0
        self.lockup.set_current(lockup_mA)
        self.brake.set(brake_Nm)
        if self.lockup.static >= LOCK_MIN_NM:
            w_e = w_t
            eng.settle(w_e, pedal, self._idle_need(w_e, pedal, 0.0))
        else:
            w_e, gov = self._converter_balance(w_t, pedal)
            eng.settle(w_e, pedal, gov)
        self.u = self.dl.coordinates(w_e, shafts, w_w)
        self.locked = [self.names[k] in closed and el.static >= LOCK_MIN_NM for k, el in enumerate(self.elements)]
        self.locked += [self.lockup.static >= LOCK_MIN_NM and w_e == w_t, speed == 0.0 and brake_Nm > 0.0]
        s = self.rows @ self.u
        self.dir = [1.0 if x >= 0.0 else -1.0 for x in s]
        self.cand = [False] * len(self.joints)
        # the driveshaft wound to the torque of the common acceleration (the driveshaft held rigid)
        idx = [k for k, lk in enumerate(self.locked) if lk]
        B = np.vstack([self.rows[idx], self.dl.shaft_row[None, :]])
        sp = (self.R_all @ self.u).tolist()
        f, _, parts = self._applied(sp, self.locked, 0.0, None, with_shaft=False)
        acc, lam = mechanics.solve(self.dl.M, B, self.R_allT @ np.asarray(f), np.zeros(B.shape[0]))
        t_s = -float(lam[-1])
        self.phi = t_s / self.ks
        self.accel = self.rw * float(acc[-1])
        for k, lk in zip(idx, lam[:-1]):
            self.torque[k] = -float(lk)
        for k, (d, tk, _) in parts[-1].items():
            self.torque[k] = d * tk
        self.jerk = 0.0
        self.ke0 = self.dl.kinetic_energy(self.u)
        self.pe0 = 0.5 * self.ks * self.phi ** 2
        self._last = {"t_s_Nm": t_s, "road": parts[3],
                      "out_Nm": t_s + self.J_out * float(self.dl.output_row @ acc)}
        self._state = self.recorder.append()

    def _idle_need(self, w_e, pedal, load):
        """The idle governor's steady torque at w_e (> 0 only at or below the idle speed)."""
        if w_e > self.engine.idle:
            return 0.0
        eng = self.engine
        return min(max(load - eng.drag_Nm(w_e) - pedal * (eng.full_Nm(w_e) - eng.drag_Nm(w_e)), 0.0), eng.idle_max)

    def _converter_balance(self, w_t, pedal):
        """(w_e, idle torque): the engine speed where the engine's torque meets the pump's."""
        eng, conv = self.engine, self.converter

        def excess(w):
            return eng.drag_Nm(w) + eng.indicated_target(w, pedal, 0.0, 0.0) - conv.torques(w, w_t)[0]
        lo = eng.idle
        if excess(lo) <= 0.0:
            gov = self._idle_need(lo, pedal, conv.torques(lo, w_t)[0])
            return lo, gov
        hi = float(eng.axis[-1])
        if excess(hi) > 0.0:
            return hi, 0.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if excess(mid) > 0.0 else (lo, mid)
        return 0.5 * (lo + hi), 0.0

    # ------------------------------------------------------------------ forces
    def _road(self, w_w):
        x = w_w * self.rw / ROLL_SPEED_M_S
        return self.road_const + self.road_roll * (1.0 if x > 1.0 else -1.0 if x < -1.0 else x) \
            + self.road_drag * w_w * abs(w_w)

    def _applied(self, sp, locked, h, k_half, with_shaft=True):
        """The applied torques at the speeds sp = R_all u, as the factors f of R_all's rows (Q = R_all^T f);
        the slipping joints to take implicitly [(k, slope)]; the parts the bookkeeping needs, a plain tuple
        (t_e, t_p, t_tb, t_road, t_s0, fric) (a dict cost more than the rest of the bookkeeping): the engine's,
        pump's, turbine's, road's and driveshaft's torques, fric {slipping joint: (direction, |T|, slope)}."""
        eng = self.engine
        w_e, w_t, w_w, gu = sp[0], sp[1], sp[2], sp[3]
        t_ind = eng.t_ind if k_half is None else eng.indicated_at(k_half)
        t_e = t_ind + eng.drag_Nm(w_e)
        t_p, t_tb = self.converter.torques(w_e, w_t)
        t_road = self._road(w_w)
        t_s0 = self.ks * self.phi + self.ch * gu if with_shaft else 0.0
        f = [t_e - t_p, t_tb, -t_road, -t_s0, 0.0] + self._joint_zeros
        implicit = []
        fric = {}
        dirs, mob = self.dir, self.mob
        for k, joint in enumerate(self.joints):
            if locked[k]:
                continue
            sk = sp[J0 + k]
            w = abs(sk)
            d = dirs[k] if w <= TINY_SLIP else (1.0 if sk > 0.0 else -1.0)
            tk, slope = joint.kinetic_slope(w)
            f[J0 + k] = -d * tk
            if slope > 0.0 and h * slope * mob[k] > IMPLICIT_STIFFNESS:
                implicit.append((k, slope))
                fric[k] = (d, tk, slope)
            else:
                fric[k] = (d, tk, 0.0)
        return f, implicit, (t_e, t_p, t_tb, t_road, t_s0, fric)

    def _constrained(self, u0, sp, locked, f, implicit, h):
        """(du, dsp, lam, idx): the constrained step (mechanics docstring) with the locked joints idx: the change
        of u, of the speeds R_all u, and the reactions. Without implicit joints the linear map from (f, the
        locked slips) to all three is cached per locked set (M, h and the driveshaft are constant)."""
        n = self.n_u
        if implicit:
            idx = [k for k, lk in enumerate(locked) if lk]
            K = self.K0.copy()
            for k, slope in implicit:
                r = self.rows[k]
                K += (h * slope) * np.outer(r, r)
            du, lam = mechanics.solve(K, self.rows[idx], h * (self.R_allT @ np.asarray(f)),
                                      np.array([-sp[J0 + k] for k in idx]))
            return du, (self.R_all @ du).tolist(), (lam / h).tolist(), idx
        key = tuple(locked)
        cached = self._kkt_cache.get(key)
        if cached is None:
            idx = [k for k, lk in enumerate(locked) if lk]
            z = self._kkt_map(idx, h)
            # the columns of the locked slips negated (exact), so the slips go in as they are: Z [f; -s] =
            # Z' [f; s] to the bit (each product only changes sign)
            z[:, len(f):] *= -1.0
            slips = operator.itemgetter(*(J0 + k for k in idx)) if len(idx) > 1 else \
                (lambda s, i=J0 + idx[0]: (s[i],)) if idx else (lambda s: ())
            cached = (z, idx, slips)        # idx with it: the callers only read it
            if len(self._kkt_cache) > 256:
                self._kkt_cache.clear()
            self._kkt_cache[key] = cached
        z, idx, slips = cached
        x = z @ np.array([*f, *slips(sp)])
        n_all = self.n_all
        xl = x.tolist()         # one conversion for both lists (slicing the list gives the same numbers)
        return x[:n], xl[n:n + n_all], xl[n + n_all:], idx

    def _kkt_map(self, idx, h):
        """Z with [du; R_all du; lam] = Z [f; -B u0] for the locked rows idx (K = K0)."""
        n = self.dl.n
        B = self.rows[idx]
        m = len(idx)
        kkt = np.zeros((n + m, n + m))
        kkt[:n, :n] = self.K0
        kkt[:n, n:] = B.T
        kkt[n:, :n] = B
        inv = np.linalg.inv(kkt)
        # [du; -Lam] = inv [h R_all^T f; c];  lam = Lam / h
        w = np.hstack([h * (inv[:, :n] @ self.R_allT), inv[:, n:]])
        return np.vstack([w[:n], self.R_all @ w[:n], -w[n:] / h])

    # ------------------------------------------------------------------ one substep
    def _try_lock(self, k_half):
        """Lock the candidates that can hold (module mechanics: projection, then the reaction within the
        static capacity). Returns the energy the projection took out per joint."""
        cands = [k for k, c in enumerate(self.cand)
                 if c and not self.locked[k] and self.joints[k].static >= LOCK_MIN_NM]
        self.cand = [False] * len(self.joints)
        lost = {}
        h = self.hs
        while cands:
            trial = list(self.locked)
            for k in cands:
                trial[k] = True
            idx = [k for k, lk in enumerate(trial) if lk]
            B = self.rows[idx]
            if not mechanics.independent(B):
                cands.pop()        # the last candidate's slip is held by the others already
                continue
            u0 = self.u
            du_p, lam_p = mechanics.solve(self.dl.M, B, np.zeros(self.dl.n), -(B @ u0))
            u_p = u0 + du_p
            sp = (self.R_all @ u_p).tolist()
            f, implicit, _ = self._applied(sp, trial, h, k_half)
            _, _, lam, _ = self._constrained(u_p, sp, trial, f, implicit, h)
            bad = [k for k, lk in zip(idx, lam) if k in cands and abs(lk) > self.joints[k].static]
            if bad:
                cands = [k for k in cands if k not in bad]
                continue
            s0 = self.rows @ u0
            for k, lp in zip(idx, lam_p):
                lost[k] = lost.get(k, 0.0) - 0.5 * float(lp) * float(s0[k])
            self.u = u_p
            self.locked = trial
            break
        return lost

    def _substep(self, j, fric_e):
        h = self.hs
        self.lockup.at(2 * j)
        if True in self.cand:                   # any(self.cand): a candidate to lock
            for k, loss in self._try_lock(2 * j + 1).items():
                fric_e[k] += loss
        u0 = self.u
        # R_all u0: state_of computed it already for the u the last period ended with (u is only ever
        # replaced, never changed in place, so the same object is the same speeds)
        u_known, sp = self._sp_of_u
        if u_known is not u0:
            sp = (self.R_all @ u0).tolist()
        locked = self.locked                    # the list itself: a break-loose below updates self.locked
        joints = self.joints
        f, implicit, parts = self._applied(sp, locked, h, 2 * j + 1)
        t_e, t_p, t_tb, t_road, t_s0, fric = parts
        while True:
            du, dsp, lam, idx = self._constrained(u0, sp, locked, f, implicit, h)
            worst, ratio, sign = None, 1.0, 0.0
            for k, lk in zip(idx, lam):
                cap = joints[k].static
                a = abs(lk)
                if a <= cap:        # within its capacity: the ratio below would be <= 1, never the worst
                    continue
                r = a / cap if cap > 0.0 else (math.inf if lk != 0.0 else 0.0)
                if r > ratio:
                    worst, ratio, sign = k, r, lk
            if worst is None:
                break
            # breaks loose, slipping against its reaction, at the kinetic torque of zero slip
            locked[worst] = False
            d = -1.0 if sign > 0.0 else 1.0
            self.dir[worst] = d
            joint = joints[worst]
            tk, slope = joint.kinetic(0.0), joint.slope(0.0)
            f[J0 + worst] = -d * tk
            if slope > 0.0 and h * slope * self.mob[worst] > IMPLICIT_STIFFNESS:
                implicit.append((worst, slope))
                fric[worst] = (d, tk, slope)
            else:
                fric[worst] = (d, tk, 0.0)
        u1 = u0 + du
        sp1 = list(map(operator.add, sp, dsp))      # sp + dsp element by element
        gu0, gu1 = sp[3], sp1[3]
        t_s = t_s0 + self.ch * (gu1 - gu0)
        self.phi += h * gu1
        gum = 0.5 * (gu0 + gu1)
        w_e_m, w_t_m, w_w_m = 0.5 * (sp[0] + sp1[0]), 0.5 * (sp[1] + sp1[1]), 0.5 * (sp[2] + sp1[2])
        e = self.e
        e["engine"] += t_e * w_e_m * h
        e["converter"] += (t_p * w_e_m - t_tb * w_t_m) * h
        e["road"] += t_road * w_w_m * h
        e["damping"] += self.cs * gum * gum * h
        torque, dirs, cand = self.torque, self.dir, self.cand
        for k, (d, tk, slope) in fric.items():      # the slipping joints (fric holds exactly those)
            a, b = sp[J0 + k], sp1[J0 + k]
            fa = -d * tk - slope * (b - a)           # the applied (linearly implicit) torque along the row
            torque[k] = -fa
            fric_e[k] -= fa * 0.5 * (a + b) * h
            if abs(b) > TINY_SLIP:
                dirs[k] = 1.0 if b > 0.0 else -1.0
            cand[k] = (a * b <= 0.0 and a != 0.0) or abs(b) < LOCK_BAND
        for k, lk in zip(idx, lam):
            torque[k] = -lk
        self.u = u1
        self._sp = sp1
        return parts, t_s

    # ------------------------------------------------------------------ public
    def _currents(self, currents, partial=False) -> dict:
        if currents is None:
            if partial:
                return {}
            raise ValueError("currents_mA: one current per element")
        if isinstance(currents, dict):
            unknown = [n for n in currents if n not in self.names]
            if unknown:
                raise ValueError(f"currents_mA: unknown element(s) {unknown} (elements {list(self.names)})")
            if not partial and set(currents) != set(self.names):
                raise ValueError(f"currents_mA: give every element {list(self.names)}")
            out = {n: float(v) for n, v in currents.items()}
        else:
            vals = [float(v) for v in currents]
            if len(vals) != len(self.names):
                raise ValueError(f"currents_mA: {len(vals)} values for elements {list(self.names)}")
            out = dict(zip(self.names, vals))
        for n, v in out.items():
            if not math.isfinite(v):
                raise ValueError(f"currents_mA[{n!r}] {v!r} is not finite")
        return out

    def step(self, currents_mA, lockup_current_mA: float = 0.0, pedal: float = 0.0,
             engine_delta_Nm: float = 0.0, brake_Nm: float = 0.0) -> dict:
        """Advance one period (1 ms) with the inputs held: currents_mA per element (a dict by name or a
        sequence in the description's order; clamped to each solenoid's range), the lock-up's current, the
        pedal (0..1), the TCU's engine torque intervention (a change against the driver's torque, N*m) and
        the brake torque at the wheels (N*m, >= 0). Returns the state (truth.STATE_DOC)."""
        if self.gear is None:
            raise RuntimeError("start the plant with Plant8.in_gear(...)")
        cur = self._currents(currents_mA)
        for name, val in (("lockup_current_mA", lockup_current_mA), ("pedal", pedal),
                          ("engine_delta_Nm", engine_delta_Nm)):
            if not math.isfinite(float(val)):
                raise ValueError(f"{name} {val!r} is not finite")
        pedal = min(max(float(pedal), 0.0), 1.0)
        u = self.u
        self.engine.step_begin(float(u[0]), pedal, float(engine_delta_Nm))
        elements = self.elements
        for name, el in zip(self.names, elements):
            el.step_begin(cur[name])
        self.lockup.step_begin(lockup_current_mA)
        self.brake.set(brake_Nm)
        fric_e = [0.0] * len(self.joints)
        w_w0 = float(u[-1])
        w_o0 = float(self._out_row @ u)
        t_s_sum = 0.0
        # the elements whose substeps would change something (TrueElement.step_begin's _idle: the others'
        # substeps return at once, all period)
        busy = [el for el in elements if not el._idle]
        substep = self._substep
        for j in range(self.n_sub):
            parts, t_s = substep(j, fric_e)
            t_s_sum += t_s
            for el in busy:
                el.substep(j)
        self.engine.step_end()
        self.lockup.step_end()
        dt = self.dt
        e_joint = self.e_joint
        for k, el in enumerate(elements):
            el.step_end(fric_e[k], dt)
        for k, e in enumerate(fric_e):
            e_joint[k] += e
        self.t += dt
        accel = self.rw * (float(self.u[-1]) - w_w0) / dt
        self.jerk = (accel - self.accel) / dt
        self.accel = accel
        t_s_mean = t_s_sum / self.n_sub
        self._last = {"t_s_Nm": t_s_mean, "road": parts[3],
                      "out_Nm": t_s_mean + self.J_out * (self._sp[OUT_ROW] - w_o0) / dt}
        self._state = self.recorder.append()
        return dict(self._state)

    # ------------------------------------------------------------------ reading the truth
    def element_slip_rad_s(self, name: str) -> float:
        """An element's true slip as the gearbox defines it: w_S (a brake), w_S1 - w_S2 (a clutch)."""
        return float(self.dl.element_rows[self.names.index(name)] @ self.u)

    def shaft_speeds_rad_s(self) -> dict:
        return dict(zip((s.name for s in self.gb.shafts), self.dl.shaft_speeds(self.u).tolist()))

    def gear_turbine_speed_rpm(self, gear: str) -> float:
        """The turbine speed gear would have at the present output speed."""
        return self.ratios[gear] * float(self.dl.output_row @ self.u) / (math.pi / 30.0)

    def energy(self) -> dict:
        """Energies since the start, J: engine work in (brake torque x speed); kinetic and driveshaft spring
        energy changes; road-load work (rolling, aero, grade); brake, element, lock-up friction; converter
        loss; driveshaft damping (c x twist rate^2); residual = engine - the rest (the scheme's error)."""
        ke = self.dl.kinetic_energy(self.u) - self.ke0
        pe = 0.5 * self.ks * self.phi ** 2 - self.pe0
        el = {n: self.e_joint[k] for k, n in enumerate(self.names)}
        out = {"engine": self.e["engine"], "kinetic": ke, "spring": pe, "road": self.e["road"],
               "brake": self.e_joint[-1], "lockup": self.e_joint[-2], "converter": self.e["converter"],
               "damping": self.e["damping"], "elements": sum(el.values())}
        out["residual"] = out["engine"] - sum(out[k] for k in ("kinetic", "spring", "road", "brake", "lockup",
                                                               "converter", "damping", "elements"))
        out.update({f"element_{n}": v for n, v in el.items()})
        return out

    @property
    def state(self) -> dict:
        """The state now (after the last step or the initialiser): truth.STATE_DOC."""
        return dict(self._state)

    def record(self) -> dict:
        """Every state channel per period, the initial state first: {name: numpy array} (empty arrays when
        the plant was made with record=False)."""
        return self.recorder.arrays()
