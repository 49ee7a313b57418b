"""The 1->2 upshift plant (DESIGN 10): a closed-loop simulator for the shift controller.

The reduced driveline of DESIGN 10 with BOTH shift elements, stepped at the
TCU's period (dt = 1 ms) with the VFS current held over the step:

    I_t dw_t/dt = T_t - a T_c - a1 T_off            turbine + engine (converter locked)
    I_o dw_o/dt = b T_c + b1 T_off - T_s            output shaft
    T_s = k_s phi_s + c_s (w_o - r_f w_w),  dphi_s/dt = w_o - r_f w_w   (driveshaft, referred to the output shaft)
    I_v dw_w/dt = r_f T_s - T_road                  vehicle, I_v = m r_w^2
    T_road = r_w (m g (c_rr cos g + sin g) + rho c_d A v |v| / 2)

On-coming (2nd-gear) clutch: slip = a w_t - b w_o, a = 1, b = i2; off-going
(1st-gear) clutch: slip_off = a1 w_t - b1 w_o, a1 = 1, b1 = i1. A clutch torque
is positive when it opposes positive slip (drive torque from the turbine to the
output). In 1st gear the off-going clutch is locked and the on-coming clutch
slips at (i1 - i2) w_o > 0; in the inertia phase the turbine falls, so slip_off
becomes negative: an off-going clutch not yet released then carries negative
torque (it fights the shift: tie-up).

The on-coming clutch is the TRUE clutch of the bench (bench._Physics with the
true calibration): eq. 8 torque from the nominal separation h (eq. 9, 15) at
|slip| and the true friction-surface temperature, the Coulomb part (and the
static capacity) times friction_scale; the Reynolds squeeze film advances h
under the apply force F = P A_p - F_s (>= 0) of the lagged piston pressure
(first-order VFS lag, exact within the step); the static capacity
static_friction_factor mu_f(0, theta) R_eff N_c F_c for its lock-up; its heat
into the lumped pack of eq. 1 (true k1, k2, C; exact zero-order hold with the
step's mean friction power, as bench.simulate), oil and housing held.

The off-going clutch: Coulomb, static capacity holding_factor x max(|T_t|,
the torque it carries at the start, holding_min), kinetic capacity
kinetic_ratio x that; scripted release: full until release_start after the
shift command, then linearly to 0 over release_time.

The whole shift (issue 22, DESIGN 14), each part off unless asked for, so that step(i, t) and a plant file
without the new parameters are bit for bit the plant before it:

  off-going clutch on its own VFS (step(..., offgoing_current_mA=i_off); constructor offgoing_current_mA the
      steady current before the first step): pressure P_off = K_off i_off through the lag tau_off (exact
      within the step), static capacity offgoing_friction_scale x static_friction_factor mu2 (1 + mu3
      (theta_oil - theta1) / theta2) x N_c R_eff x max(P_off A_p - F_s, 0) of the [offgoing] calibration
      (default: the [clutch] one), kinetic = kinetic_ratio x static. None: the scripted release above (its
      truth pressure/current then those of the equivalent capacity).
  engine (step(..., engine_request_Nm=delta)): the actual turbine torque follows clip(turbine_torque_Nm +
      delta, engine_torque_min, engine_torque_max) after engine_delay (whole periods) through the lag
      engine_time_constant (exact, the substeps' mid values); engine_ignores_request: delta taken as 0.
      None: the engine torque is turbine_torque_Nm at once (as before).
  on-coming fill ([hydraulics] fill_volume > 0): the piston's stroke fraction f = x / x_max,
      df/dt = clip(fill_flow_gain (P_vfs - P_s(f)), +-fill_flow_max) / fill_volume, P_s(f) = F_s / A_p
      (0.8 + 0.2 f) the return spring's pressure; no apply force before f = 1 (the kiss point), then as
      above; the piston retracts when P_vfs falls below the spring's pressure. The chamber pressure
      (truth pressure_Pa) is the spring's while filling, the lagged VFS pressure (vfs_pressure_Pa) once full.
  sensors: offgoing_slip_rpm (with the off-going current; its noise from a second generator).
  truth: engine_torque_Nm, engine_request_Nm, offgoing_current_mA, offgoing_pressure_Pa, fill_fraction,
      output_torque_Nm (i2 T_c + i1 T_off), vfs_pressure_Pa appended; turbine_torque_Nm = the actual engine torque.

Plant files may extend a base (extends = "base.toml"): tools/plants/vehicles/ is a family of vehicles on
nominal.toml (params has the rules; wetclutch.shift.vehicle_cal their TCU driveline models).

Stick-slip (each clutch): a locked clutch carries the torque the rigid
constraint needs (the constrained two-inertia system solved for it, the other
clutch's torque known) while that is within its static capacity, else it breaks
away and slips in the direction of the excess; a slipping clutch locks when its
slip crosses zero and the torque to hold it is within the static capacity (the
remaining slip removed by the momentum-conserving impulse). Both locked at once
is only possible at standstill (i1 != i2): a clutch whose slip crosses zero
while the other is locked keeps slipping (chatters about zero slip).

Integration: SUBSTEPS = 4 substeps of 0.25 ms per period, semi-implicit
(symplectic) Euler for the mechanics (largest rates: the driveshaft against the
output inertia alone, 110 rad/s, and the viscous slip damping up to about
500 1/s: below 0.13 per substep), classical RK4 for the film in each substep
with the pressure exact, the temperature held over the period. The initial state
is steady 1st gear under the turbine torque: all inertias accelerating together,
the driveshaft pre-wound to the torque that acceleration needs, the open
on-coming clutch's drag (film at h_max) included, pressure 0.

Deterministic: same parameters, arguments and seed -> bit-identical truth and
sensor values (plain float arithmetic, one seeded numpy Generator drawn in blocks).

Two modules, every name importable from here (``plant.load_plant``, ``plant.UpshiftPlant``):

params   the plant file: SCHEMA, RANGES, PlantParams, load_plant; DT_S, SUBSTEPS, DEFAULT_PLANT
upshift  UpshiftPlant (the equations above) and initial_turbine_speed_rpm
"""
from __future__ import annotations

from .params import (DEFAULTS, DEFAULT_PLANT, DT_S, GRAVITY, NOISE_BLOCK, RANGES, RPM, SCHEMA, SUBSTEPS, PlantError,
                     OPTIONAL, PlantParams, load_plant)
from .upshift import TRUTH_NAMES, UpshiftPlant, initial_turbine_speed_rpm

__all__ = ["DEFAULTS", "DEFAULT_PLANT", "OPTIONAL", "DT_S", "GRAVITY", "NOISE_BLOCK", "RANGES", "RPM", "SCHEMA", "SUBSTEPS", "TRUTH_NAMES",
           "PlantError", "PlantParams", "UpshiftPlant", "initial_turbine_speed_rpm", "load_plant"]
