"""The 8-speed plant's state as the caller reads it (state_of) and its record per period (Recorder).

STATE_DOC names every channel. Per element NAME (A .. E of the description) the channels NAME_slip_rad_s (the
gearbox's own slip: w_S for a brake, w_S1 - w_S2 for a clutch), NAME_torque_Nm (> 0 opposing positive slip;
locked: the constraint's reaction), NAME_capacity_Nm (static), NAME_locked (0/1), NAME_current_mA,
NAME_pressure_Pa (the piston's), NAME_fill (stroke fraction, 1 at the kiss point), NAME_theta_degC (the pack's
true temperature, eq. 1), NAME_power_W (the period's mean friction power) and NAME_energy_J (friction energy since
the start).
"""
from __future__ import annotations

import math

import numpy as np

RPM = math.pi / 30.0
J0 = 5          # the joints' slips in R_all u follow engine, input, wheel, driveshaft and output (plant.J0)

STATE_DOC = {
    "t_s": "s, plant time (0 at the initialiser)",
    "engine_speed_rpm": "crank and converter pump",
    "turbine_speed_rpm": "converter turbine and gearbox input shaft",
    "output_speed_rpm": "gearbox output shaft",
    "wheel_speed_rpm": "wheels",
    "vehicle_speed_m_s": "w_w r_w",
    "vehicle_accel_m_s2": "the period's mean acceleration",
    "vehicle_jerk_m_s3": "change of the period's mean acceleration per period",
    "engine_torque_Nm": "brake torque T_i + T_drag(w_e) at the period's end",
    "engine_indicated_Nm": "T_i after the dead time and lag, end of the period",
    "engine_request_Nm": "the indicated target asked this period (pedal map + idle governor + intervention)",
    "idle_torque_Nm": "the idle governor's part",
    "pump_torque_Nm": "converter pump torque (load on the engine)",
    "converter_turbine_torque_Nm": "converter turbine torque (into the gearbox input)",
    "converter_speed_ratio": "w_turbine / w_pump",
    "lockup_torque_Nm": "lock-up clutch torque (> 0 from the engine to the turbine)",
    "lockup_capacity_Nm": "lock-up static capacity",
    "lockup_locked": "0/1",
    "lockup_pressure_Pa": "lock-up piston pressure",
    "input_torque_Nm": "converter turbine + lock-up torque: the gearbox input torque T_t",
    "driveshaft_torque_Nm": "T_s = k phi + c (w_o - r_f w_w), the period's mean",
    "output_torque_Nm": "the gear set's torque on the output shaft: J_o dw_o/dt + T_s, the period's mean",
    "road_load_Nm": "at the wheels (rolling, aero, grade)",
    "brake_torque_Nm": "the brake's torque at the wheels (> 0 against forward motion)",
    "brake_locked": "0/1 (held at standstill)",
    "gear_ratio_actual": "w_turbine / w_output (nan at a standing output)",
}
ELEMENT_CHANNELS = ("slip_rad_s", "torque_Nm", "capacity_Nm", "locked", "current_mA", "pressure_Pa", "fill",
                    "theta_degC", "power_W", "energy_J")


def state_of(plant) -> dict:
    u = plant.u
    sp = (plant.R_all @ u).tolist()             # engine, input, wheel, driveshaft, output, joints' slips
    plant._sp_of_u = (u, sp)                    # the next period's first substep starts from the same speeds
    w_e, w_t, w_w, w_o = sp[0], sp[1], sp[2], sp[4]
    eng = plant.engine
    t_p, t_tb = plant.converter.torques(w_e, w_t)
    n_el = len(plant.elements)
    lu = n_el
    t_lu = float(plant.torque[lu]) if (plant.locked[lu] or plant.lockup.kin > 0.0) else 0.0
    st = {
        "t_s": plant.t,
        "engine_speed_rpm": w_e / RPM,
        "turbine_speed_rpm": w_t / RPM,
        "output_speed_rpm": w_o / RPM,
        "wheel_speed_rpm": w_w / RPM,
        "vehicle_speed_m_s": w_w * plant.rw,
        "vehicle_accel_m_s2": float(plant.accel),
        "vehicle_jerk_m_s3": plant.jerk,
        "engine_torque_Nm": eng.t_ind + eng.drag_Nm(w_e),
        "engine_indicated_Nm": eng.t_ind,
        "engine_request_Nm": eng.request,
        "idle_torque_Nm": eng.idle_torque,
        "pump_torque_Nm": t_p,
        "converter_turbine_torque_Nm": t_tb,
        "converter_speed_ratio": w_t / w_e if w_e > 0.0 else 0.0,
        "lockup_torque_Nm": t_lu,
        "lockup_capacity_Nm": plant.lockup.static,
        "lockup_locked": float(plant.locked[lu]),
        "lockup_pressure_Pa": plant.lockup.P,
        "input_torque_Nm": t_tb + t_lu,
        "driveshaft_torque_Nm": float(plant._last["t_s_Nm"]),
        "output_torque_Nm": float(plant._last["out_Nm"]),
        "road_load_Nm": plant._last["road"],
        "brake_torque_Nm": float(plant.torque[-1]) if (plant.locked[-1] or plant.brake.kin > 0.0) else 0.0,
        "brake_locked": float(plant.locked[-1]),
        "gear_ratio_actual": w_t / w_o if w_o != 0.0 else math.nan,
    }
    keys = _element_keys(plant.names)
    torque, locked, e_joint = plant.torque, plant.locked, plant.e_joint
    for k, el in enumerate(plant.elements):
        st.update(zip(keys[k], (                # ELEMENT_CHANNELS' order
            float(sp[J0 + k]), float(torque[k]), el.static, float(locked[k]), el.current, el.chamber_pressure(),
            el.fill, el.theta, el.power, e_joint[k])))
    return st


_KEYS: dict = {}


def _element_keys(names: tuple) -> list:
    """Per element its channels' names (NAME_slip_rad_s ...), made once per set of names: formatting them every
    period cost as much as the rest of state_of."""
    keys = _KEYS.get(names)
    if keys is None:
        keys = _KEYS[names] = [tuple(f"{name}_{c}" for c in ELEMENT_CHANNELS) for name in names]
    return keys


class Recorder:
    """Every state channel per period (rows appended by the plant); keep=False: the state only, no rows."""

    def __init__(self, plant, keep: bool = True):
        self.plant = plant
        self.keep = keep
        self.rows: list = []
        self.names: tuple = ()

    def append(self) -> dict:
        st = state_of(self.plant)
        if not self.names:
            self.names = tuple(st)
        if self.keep:
            self.rows.append(tuple(st[c] for c in self.names))
        return st

    def arrays(self) -> dict:
        arr = np.array(self.rows, dtype=float).reshape(len(self.rows), len(self.names))
        return {c: arr[:, k].copy() for k, c in enumerate(self.names)}
