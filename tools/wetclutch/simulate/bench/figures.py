"""Figures of a simulated run from its truth and measurements: the engagement (Fig. 15) and the breakaway."""
from __future__ import annotations

import numpy as np

from ...calibration import Calibration
from ...reference import model
from .experiments import BREAKAWAY_RAMP_S, Result
from .physics import film_time_constant_s


def engagement_figures(result: Result, contact_force_N: float = 50.0, true_cal: Calibration | None = None,
                       transient_Nm: float = 2.25) -> dict:
    """Fig. 15 figures of an engagement from the truth and the measurements.

    Contact: the force passes contact_force_N. film_90_s: from contact until the asperities carry 90 % of
    the applied force (the squeeze film's approach). With true_cal also: transient_s, from contact to the
    last slipping instant where the torque differs from the steady model (eq. 8, the true parameters at
    the true slip, temperature and force) by more than transient_Nm (the paper's steady-state RMSE at
    750 rpm), and film_tau_s, the film's equivalent time constant near contact (film_time_constant_s)
    at the initial temperature.
    """
    tr, t = result.truth, result.t_s
    contact = np.flatnonzero(tr["force_N"] > contact_force_N)
    t_contact = float(t[contact[0]])
    lock = np.flatnonzero((t > t_contact) & (tr["locked"] > 0.5))
    t_lock = float(t[lock[0]]) if lock.size else float("nan")
    slipping = (t >= t_contact) & (tr["locked"] < 0.5)
    carried = np.flatnonzero((t >= t_contact) & (tr["contact_force_N"] >= 0.9 * result.experiment.force_N))
    out = {
        "t_contact_s": t_contact,
        "t_lock_s": t_lock,
        "peak_torque_Nm": float(np.max(tr["torque_Nm"][slipping])),
        "peak_torque_measured_Nm": float(np.max(result.measured["torque_Nm"][t >= t_contact])),
        "peak_viscous_Nm": float(np.max(tr["viscous_Nm"][(t >= t_contact) & (t < t_contact + 0.3)])),
        "theta_at_lock_degC": float(tr["theta_degC"][lock[0]]) if lock.size else float("nan"),
        "film_90_s": float(t[carried[0]]) - t_contact if carried.size else float("nan"),
    }
    if true_cal is not None:
        steady = model.torque_parts(true_cal, tr["slip_rpm"][slipping], tr["theta_degC"][slipping],
                                    tr["force_N"][slipping])["torque_Nm"]
        off = np.flatnonzero(np.abs(steady - tr["torque_Nm"][slipping]) > transient_Nm)
        out["transient_s"] = float(t[slipping][off[-1]]) - t_contact if off.size else 0.0
        out["film_tau_s"] = float(film_time_constant_s(true_cal, result.experiment.force_N,
                                                       result.experiment.theta0_degC))
    return out


def breakaway_figures(result: Result) -> dict:
    """A breakaway run: the true breakaway instant (the locked clutch lets go) and the static capacity
    then; the measured torque's peak while locked (ramp start to breakaway: the breakaway torque a bench
    reads); the motor switch-off (measured slip > BREAKAWAY_OFF_RPM) and the lock after it. The peak of the
    whole run is later: this lining's kinetic friction rises with the slip past the static capacity."""
    tr, t, m = result.truth, result.t_s, result.measured
    ramp = t >= BREAKAWAY_RAMP_S - 1e-9
    slipping = np.flatnonzero(ramp & (tr["locked"] < 0.5))
    if not slipping.size:
        nan = float("nan")
        return {"t_breakaway_s": nan, "static_capacity_Nm": nan, "breakaway_torque_measured_Nm": nan,
                "t_motor_off_s": nan, "t_relock_s": nan, "peak_torque_measured_Nm": float(np.max(m["torque_Nm"]))}
    k = int(slipping[0])
    on = np.flatnonzero(ramp & (t > t[k]) & (tr["motor_torque_Nm"] == 0.0))
    t_off = float(t[on[0]]) if on.size else float("nan")
    relock = np.flatnonzero((t > t_off) & (tr["locked"] > 0.5)) if on.size else np.array([], dtype=int)
    return {
        "t_breakaway_s": float(t[k]),
        "static_capacity_Nm": float(tr["static_capacity_Nm"][k]),
        "breakaway_torque_measured_Nm": float(np.max(m["torque_Nm"][ramp & (t <= t[k])])),
        "t_motor_off_s": t_off,
        "t_relock_s": float(t[relock[0]]) if relock.size else float("nan"),
        "peak_torque_measured_Nm": float(np.max(m["torque_Nm"])),
    }
