"""The 8-speed vehicle plant (issue 29, item 4; DESIGN 15): richer than the TCU's per-shift reduced model.

The TCU knows per shift a, b, b1 and two inertias (wetclutch.gearbox.reduction). This plant simulates the whole
vehicle from the gearbox description (tools/gearboxes/8hp.toml), a vehicle file (tools/plants/vehicles/*.toml)
and an 8-speed plant file (tools/plants/8hp/*.toml: engine map, converter curves, lock-up, the elements' true
friction material), stepped at the TCU's period (1 ms, SUBSTEPS = 4 substeps):

  engine      T_e = T_i + T_drag(w_e); T_i follows clip(pedal (T_full - T_drag) + T_idle + delta, 0, T_full -
              T_drag) after the vehicle's dead time, through its first-order lag (exact within the period);
              delta is the TCU's intervention; T_idle a PI idle governor (powertrain)
  converter   nu = w_t / w_p; T_p = w_p^2 / K(nu)^2, T_t = TR(nu) T_p (nu <= 1); overrun a reversed coupling;
              the lock-up clutch a Coulomb friction element on its own VFS (powertrain)
  elements    each its own TRUE clutch: VFS lag, fill against the return spring (kiss point), Reynolds squeeze
              film, eq. 8/18 torque, static capacity, eq. 1 temperature (element)
  gear sets   every shaft of the description, the Willis equations eliminated exactly (null-space
              coordinates); locked elements, the locked lock-up and the held brake as constraints with
              Lagrange multipliers (their reaction torques); slipping ones apply their friction against the
              slip; deterministic stick-slip (mechanics)
  driveline   output shaft -> final drive r_f -> torsional compliance k_s, c_s (at the output shaft:
              T_s = k_s phi + c_s (w_o - r_f w_w), dphi/dt = w_o - r_f w_w) -> wheels and vehicle,
              I_v dw_w/dt = r_f T_s - T_road - T_brake, I_v = m r_w^2,
              T_road = r_w (m g (c_rr cos a sat(v / 0.05 m/s) + sin a) + rho c_d A v |v| / 2)

API:
  load_plant8(path) -> Plant8Params                              (params; PlantError for a bad file)
  Plant8.in_gear(params, gear, speed_m_s, pedal=, currents_mA=, lockup_current_mA=, brake_Nm=, oil_degC=,
                 theta_degC=, friction_scale=) -> Plant8         (a steady state in a gear)
  plant.step(currents_mA, lockup_current_mA, pedal, engine_delta_Nm, brake_Nm) -> state dict (truth.STATE_DOC,
                 per element NAME_slip_rad_s, NAME_torque_Nm, NAME_capacity_Nm, NAME_locked, NAME_theta_degC ...)
  plant.element_slip_rad_s(name), plant.shaft_speeds_rad_s(), plant.gear_turbine_speed_rpm(gear),
  plant.energy() (engine work, kinetic, spring, road, brake, friction per element, lock-up, converter,
                 damping, residual), plant.record() -> {channel: array per period}

Modules: params (the plant file), powertrain (engine, converter, lock-up, brake), element (the true clutch of an
element), mechanics (coordinates, mass matrix, constrained step, stick-slip), plant (Plant8), truth (state and
record).
"""
from __future__ import annotations

from .mechanics import LOCK_BAND, LOCK_MIN_NM
from .params import Plant8Params, load_plant8
from .plant import DT_S, SUBSTEPS, Plant8
from .truth import ELEMENT_CHANNELS, STATE_DOC

__all__ = ["DT_S", "ELEMENT_CHANNELS", "LOCK_BAND", "LOCK_MIN_NM", "Plant8", "Plant8Params", "STATE_DOC", "SUBSTEPS",
           "load_plant8"]
