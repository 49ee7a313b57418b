"""The engine (torque map, idle governor, dead time and lag, the TCU's intervention), the torque converter
(K-factor and torque-ratio curves) and its lock-up clutch (a Coulomb friction element on its own VFS).

ENGINE. Brake torque T_e = T_i + T_drag(w_e): the drag (friction and pumping at closed throttle, fuel cut) is a
function of the speed, at once; the indicated part T_i follows its target

    T_i,target = clip(pedal (T_full(w_e) - T_drag(w_e)) + T_idle + delta, 0, T_full(w_e) - T_drag(w_e))

after the dead time (whole periods) and through the first-order lag tau_e (exact within the period: T_i(s) =
target + (T_i0 - target) e^(-s/tau_e)); delta is the TCU's torque intervention (a change against the driver's
torque). So at pedal 1 the engine gives its full-load curve, at pedal 0 its drag, and a reduction cannot take
it below the drag nor an increase above the full load. T_idle: the idle governor, a PI on (w_idle - w_e) >= 0,
its integral clamped to [0, idle_torque_max] (anti-windup), the output to [0, idle_torque_max].

CONVERTER. Speed ratio nu = w_t / w_p (pump on the engine). Driving (nu <= 1): pump torque T_p = C(nu) w_p^2
(C = 1 / K^2, the K-factor in rad/s per sqrt(N m)), turbine torque T_t = TR(nu) T_p. Overrun (nu > 1, the
turbine drives): a fluid coupling the other way, T_t = -overrun_capacity C(1/nu) w_t^2, T_p = T_t (torque ratio 1:
the stator freewheels). C(1) = 0: continuous through synchronism; linear interpolation in the tables, clamped.

LOCK-UP. Piston pressure P through the VFS lag (exact within the step) from K_lu i; apply force F = max(P A - F_s,
0); kinetic torque mu R N F, static capacity static_friction_factor x that (Coulomb: no speed dependence).
"""
from __future__ import annotations

import bisect
import math


def interp(x: float, xs: list, ys: list) -> float:
    """Linear interpolation in a table, clamped at both ends (numpy.interp for one scalar, without its cost)."""
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    k = bisect.bisect_right(xs, x)
    x0, x1 = xs[k - 1], xs[k]
    return ys[k - 1] + (ys[k] - ys[k - 1]) * (x - x0) / (x1 - x0)


class Engine:
    """The engine's torque (module docstring). step_begin(...) once per period, then torque_at(j) per substep."""

    def __init__(self, params, dt_s: float, substeps: int):
        p = params
        self.axis = p.speed_axis.tolist()
        self.full = p.full_load_Nm.tolist()
        self.drag = p.drag_Nm.tolist()
        self.idle = p.idle_speed
        self.kp, self.ki, self.idle_max = p.idle_gain, p.idle_integral_gain, p.idle_torque_max
        self.dt = dt_s
        tau = p.vehicle.engine_time_constant
        hs = dt_s / substeps
        self.lag = [math.exp(-j * 0.5 * hs / tau) for j in range(2 * substeps + 1)]
        self.delay = int(round(p.vehicle.engine_delay / dt_s))
        self.fifo: list = []
        self.t_ind = 0.0            # indicated torque now
        self.target = 0.0           # the target the lag follows this period
        self.d0 = 0.0
        self.idle_int = 0.0
        self.idle_torque = 0.0
        self.request = 0.0          # the driver's + governor's + intervention's target (before the dead time)

    def drag_Nm(self, w: float) -> float:
        return interp(w, self.axis, self.drag)

    def full_Nm(self, w: float) -> float:
        return interp(w, self.axis, self.full)

    def indicated_target(self, w: float, pedal: float, delta: float, idle_torque: float) -> float:
        span = self.full_Nm(w) - self.drag_Nm(w)
        t = pedal * span + idle_torque + delta
        return span if t > span else 0.0 if t < 0.0 else t

    def settle(self, w: float, pedal: float, idle_torque: float = 0.0) -> None:
        """A steady state at speed w and pedal (no intervention): the lag and the dead time at their target."""
        self.idle_int = min(max(idle_torque, 0.0), self.idle_max)
        self.idle_torque = self.idle_int
        self.target = self.indicated_target(w, pedal, 0.0, self.idle_torque)
        self.request = self.target
        self.t_ind = self.target
        self.fifo = [self.target] * self.delay
        self.d0 = 0.0

    def step_begin(self, w: float, pedal: float, delta: float) -> None:
        """The idle governor at speed w, the target of this period (after the dead time)."""
        err = self.idle - w
        integ = min(max(self.idle_int + self.ki * err * self.dt, 0.0), self.idle_max)
        self.idle_int = integ
        gov = self.kp * err + integ
        self.idle_torque = gov if 0.0 < gov < self.idle_max else (0.0 if gov <= 0.0 else self.idle_max)
        self.request = self.indicated_target(w, pedal, delta, self.idle_torque)
        if self.delay:
            self.fifo.append(self.request)
            self.target = self.fifo.pop(0)
        else:
            self.target = self.request
        self.d0 = self.t_ind - self.target

    def indicated_at(self, k: int) -> float:
        """The indicated torque at half-substep k of this period (0 .. 2 substeps)."""
        return self.target + self.d0 * self.lag[k]

    def step_end(self) -> None:
        self.t_ind = self.target + self.d0 * self.lag[-1]


class Converter:
    """Pump and turbine torques of the converter (module docstring)."""

    def __init__(self, params):
        self.nu = params.speed_ratio.tolist()
        self.cap = params.capacity.tolist()
        self.tr = params.torque_ratio.tolist()
        self.overrun = params.overrun_capacity

    def capacity(self, nu: float) -> float:
        return interp(nu, self.nu, self.cap)

    def torques(self, w_p: float, w_t: float) -> tuple[float, float]:
        """(T_pump, T_turbine): the load on the engine and the drive into the gearbox input."""
        if w_p <= 0.0 and w_t <= 0.0:
            return 0.0, 0.0
        if w_t <= w_p:
            nu = w_t / w_p if w_t > 0.0 else 0.0
            t_p = interp(nu, self.nu, self.cap) * w_p * w_p
            return t_p, interp(nu, self.nu, self.tr) * t_p
        inv = w_p / w_t if w_p > 0.0 else 0.0
        t = -self.overrun * interp(inv, self.nu, self.cap) * w_t * w_t
        return t, t


class Lockup:
    """The converter's lock-up clutch: its VFS, apply force, kinetic torque and static capacity."""

    def __init__(self, params, dt_s: float, substeps: int):
        lu = params.lockup
        self.gain = lu["vfs_gain"]
        self.i_max = lu["vfs_current_max"]
        self.area = lu["piston_area"]
        self.spring = lu["return_spring_force"]
        self.per_N = lu["friction_coefficient"] * lu["effective_radius"] * lu["friction_surfaces"]
        self.static_factor = lu["static_friction_factor"]
        hs = dt_s / substeps
        self.lag = [math.exp(-j * 0.5 * hs / lu["vfs_time_constant"]) for j in range(2 * substeps + 1)]
        self.P = 0.0
        self.p_cmd = 0.0
        self.dp = 0.0
        self.current = 0.0
        self.kin = 0.0
        self.static = 0.0

    def set_current(self, current_mA: float) -> None:
        """A steady state at current_mA."""
        self.current = min(max(float(current_mA), 0.0), self.i_max)
        self.P = self.p_cmd = self.gain * self.current
        self.dp = 0.0
        self.at(0)

    def step_begin(self, current_mA: float) -> None:
        self.current = min(max(float(current_mA), 0.0), self.i_max)
        self.p_cmd = self.gain * self.current
        self.dp = self.P - self.p_cmd

    def at(self, k: int) -> None:
        """Capacity at half-substep k."""
        f = (self.p_cmd + self.dp * self.lag[k]) * self.area - self.spring
        self.kin = self.per_N * f if f > 0.0 else 0.0
        self.static = self.static_factor * self.kin

    def step_end(self) -> None:
        self.P = self.p_cmd + self.dp * self.lag[-1]

    def kinetic(self, w_abs: float) -> float:
        return self.kin

    @staticmethod
    def slope(w_abs: float) -> float:
        return 0.0

    def kinetic_slope(self, w_abs: float) -> tuple[float, float]:
        return self.kin, 0.0


class WheelBrake:
    """The service brake as a friction element between the wheels and the ground: static = kinetic = the
    commanded brake torque (at the wheels, >= 0)."""

    def __init__(self):
        self.kin = 0.0
        self.static = 0.0

    def set(self, brake_Nm: float) -> None:
        b = float(brake_Nm)
        if not (math.isfinite(b) and b >= 0.0):
            raise ValueError(f"brake_Nm {brake_Nm!r} must be a finite torque >= 0")
        self.kin = self.static = b

    def kinetic(self, w_abs: float) -> float:
        return self.kin

    @staticmethod
    def slope(w_abs: float) -> float:
        return 0.0

    def kinetic_slope(self, w_abs: float) -> tuple[float, float]:
        return self.kin, 0.0
