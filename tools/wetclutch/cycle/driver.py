"""The driver of a drive cycle: a speed PI with feed-forward → pedal 0..1 and brake torque (DESIGN 16).

What a driver on a chassis dynamometer does with the driver's aid in front of them: look a little ahead on the
trace, press the pedal for the acceleration the trace asks for and correct the speed error; brake when the
engine's drag is not enough. Deterministic (no noise, no state but the integrator and the pedal), stepped at
a fixed dt_s (1 ms on the TCU's loop, 10 ms standalone; the same law, tested at both).

The law, in the acceleration domain (the mass estimate m turns it into a force at the wheels):

    v_ref = trace(t + preview_s)                            the speed a little ahead (m/s)
    a_ff  = mean slope of the trace about t + preview_s     feed-forward of the trace's acceleration
    e     = v_ref - v
    F_dem = m (a_ff + K_p e + I) + F_road(v_ref)            F_road: the WLTP road-load f0 + f1 v + f2 v^2 estimate
    dI/dt = K_i e + (F_done - F_dem) / (m T_aw)             back-calculation anti-windup

F_dem is split by the vehicle's pedal map at the present speed and gear, (F_0, F_1) = the force at the wheels at
pedal 0 (engine drag, or creep) and at pedal 1 (full load), which the vehicle side passes to ``step`` (the
interface the plant plugs into; without it a constant full-pedal force and F_0 = 0): pedal =
(F_dem - F_0) / (F_1 - F_0) in 0..1, rate limited as a foot is; below F_0 the brake gives the rest, up to its
maximum. F_done is what that pedal and brake give: where the pedal or the brake saturates, the integrator is
pulled back to match instead of winding up. At standstill with the trace standing the driver holds the brake
and the integrator is cleared.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .trace import KMH_PER_MPS, SpeedTrace


@dataclass(frozen=True)
class DriverParams:
    vehicle_mass_kg: float = 1600.0             # the driver's estimate: feed-forward and loop gain
    road_load_f0_N: float = 0.0                 # the driver's road-load estimate, WLTP form, v in km/h
    road_load_f1_N_per_kmh: float = 0.0
    road_load_f2_N_per_kmh2: float = 0.0
    wheel_radius_m: float = 0.31                # brake force -> brake torque at the wheels
    speed_gain_per_s: float = 1.2               # K_p: demanded acceleration per m/s of speed error
    integral_gain_per_s2: float = 0.3           # K_i
    antiwindup_time_s: float = 0.3              # T_aw of the back-calculation
    preview_s: float = 0.3                      # how far ahead the driver reads the trace
    accel_half_window_s: float = 0.5            # the feed-forward's slope: mean over ±this about t + preview
    full_pedal_force_N: float = 6000.0          # pedal map when the vehicle gives none: F_0 = 0, F_1 = this
    pedal_rate_max_per_s: float = 4.0           # a foot: 0 -> 1 in 0.25 s
    brake_torque_max_Nm: float = 9000.0         # all wheels
    standstill_hold_torque_Nm: float = 1500.0   # held at standstill
    standstill_speed_mps: float = 0.1           # below this with the trace standing: hold

    def check(self) -> None:
        positive = ("vehicle_mass_kg", "wheel_radius_m", "antiwindup_time_s", "full_pedal_force_N",
                    "pedal_rate_max_per_s", "brake_torque_max_Nm", "accel_half_window_s")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"DriverParams.{name} must be positive and finite, not {value}")
        for name in ("speed_gain_per_s", "integral_gain_per_s2", "preview_s", "standstill_hold_torque_Nm",
                     "standstill_speed_mps", "road_load_f0_N", "road_load_f1_N_per_kmh",
                     "road_load_f2_N_per_kmh2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"DriverParams.{name} must be >= 0 and finite, not {value}")

    def road_load_N(self, speed_mps: float) -> float:
        if speed_mps <= 0.0:
            return 0.0
        v = speed_mps * KMH_PER_MPS
        return self.road_load_f0_N + v * (self.road_load_f1_N_per_kmh + v * self.road_load_f2_N_per_kmh2)


@dataclass(frozen=True)
class DriverCommand:
    pedal: float                # 0..1
    brake_torque_Nm: float      # at the wheels, >= 0; never together with pedal > 0
    target_speed_kmh: float     # the trace at t (what the tolerance is checked against)
    demand_force_N: float       # F_dem
    holding: bool = False       # standstill hold


class Driver:
    """A driver following ``trace`` at a fixed step dt_s (module docstring)."""

    def __init__(self, trace: SpeedTrace, params: DriverParams | None = None, dt_s: float = 0.01):
        self.trace = trace
        self.params = params or DriverParams()
        self.params.check()
        if not (math.isfinite(dt_s) and 0.0 < dt_s <= 0.02):
            raise ValueError(f"Driver: dt_s must be in (0, 0.02] s, not {dt_s}")
        self.dt_s = dt_s
        self.reset()

    def reset(self) -> None:
        self.integral_mps2 = 0.0
        self.pedal = 0.0

    def step(self, t_s: float, speed_mps: float, pedal_force_N: tuple[float, float] | None = None
             ) -> DriverCommand:
        """The command for the next dt_s, from the time and the vehicle's speed (m/s). pedal_force_N =
        (force at the wheels at pedal 0, at pedal 1) in the present gear and speed, N."""
        p, tr, dt = self.params, self.trace, self.dt_s
        target_kmh = tr.speed_kmh_at(t_s)
        t_ahead = t_s + p.preview_s
        v_ref = tr.speed_mps_at(t_ahead)
        if v_ref <= 0.0 and target_kmh <= 0.0 and speed_mps < p.standstill_speed_mps:
            self.integral_mps2 = 0.0
            self.pedal = 0.0
            return DriverCommand(0.0, p.standstill_hold_torque_Nm, target_kmh, 0.0, True)

        a_ff = tr.acceleration_mps2(t_ahead, p.accel_half_window_s)
        error = v_ref - speed_mps
        m = p.vehicle_mass_kg
        demand = m * (a_ff + p.speed_gain_per_s * error + self.integral_mps2) + p.road_load_N(v_ref)

        f0, f1 = pedal_force_N if pedal_force_N is not None else (0.0, p.full_pedal_force_N)
        if demand > f0:
            wanted = (demand - f0) / (f1 - f0) if f1 > f0 else 1.0
            brake_force = 0.0
        else:
            wanted = 0.0
            brake_force = min(f0 - demand, p.brake_torque_max_Nm / p.wheel_radius_m)
        step_max = p.pedal_rate_max_per_s * dt
        pedal = min(1.0, max(0.0, wanted, self.pedal - step_max), self.pedal + step_max)
        if brake_force > 0.0 and pedal > 0.0:       # the foot leaves the pedal before it brakes
            brake_force = 0.0
        self.pedal = pedal
        done = f0 + pedal * (f1 - f0) - brake_force
        self.integral_mps2 += dt * (p.integral_gain_per_s2 * error + (done - demand) / (m * p.antiwindup_time_s))
        return DriverCommand(pedal, brake_force * p.wheel_radius_m, target_kmh, demand)
