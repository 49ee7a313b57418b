"""The quality vector of one shift from the plant's truth (the package docstring), and a scenario's worst."""
from __future__ import annotations

import math

import numpy as np

from ..simulate import plant as plant_mod
from .scenarios import (ABORT_NAMES, FLARE_RPM, JERK_CUTOFF_HZ, SYNC_BAND_RAD_S, TARGET_INERTIA_S,
                        TIE_UP_FRACTION)


def _lowpass_zero_phase(x: np.ndarray, dt: float, cutoff_hz: float) -> np.ndarray:
    from scipy.signal import butter, filtfilt
    b, a = butter(2, cutoff_hz * 2.0 * dt)
    return filtfilt(b, a, x)


def quality(rec: dict, target_s: float = TARGET_INERTIA_S) -> dict:
    """The quality vector of one shift from the plant's truth (module docstring)."""
    dt = rec["t_s"][1] - rec["t_s"][0]
    k0, ki = rec["command_step"], rec["inertia_step"]
    sync = (np.abs(rec["true_slip_rad_s"]) < SYNC_BAND_RAD_S) | (rec["true_oncoming_locked"] > 0.5)
    sync_idx = np.flatnonzero(sync[ki:])
    k_sync = ki + int(sync_idx[0]) if sync_idx.size else None
    inertia = (k_sync - ki) * dt if k_sync is not None else float("nan")
    k_end = k_sync if k_sync is not None else len(sync)
    err = rec["true_slip_rad_s"][ki:k_end] - rec["reference_slip_rad_s"][ki:k_end]
    accel = _lowpass_zero_phase(rec["true_vehicle_accel_m_s2"], dt, JERK_CUTOFF_HZ)
    jerk = np.gradient(accel, dt)
    k_jerk_end = k_sync + 1 if k_sync is not None else len(jerk)
    flare_rpm = float(np.max(rec["true_turbine_speed_rpm"][k0:] - rec["true_gear1_speed_rpm"][k0:]))
    t_t = max(abs(float(rec["true_turbine_torque_Nm"][0])), 1.0)   # the driver's torque, before any intervention
    fight = float(np.max(np.maximum(-rec["true_offgoing_torque_Nm"][k0:], 0.0)))
    report = rec["report"]
    abort = int(report["AbortReason"]) if report is not None else -1
    p_err = rec["true_pressure_Pa"][k0:] - rec["pressure_command_Pa"][k0:]
    whole = {}
    if rec.get("whole"):   # the whole shift (DESIGN 14): per phase, both clutches, the engine, the fallback
        k_end_tp = max(ki, k0 + 1)
        whole = {
            "torque_phase_jerk_m_s3": float(np.max(np.abs(jerk[k0:k_end_tp]))),
            "offgoing_energy_kJ": float(np.sum(rec["true_offgoing_power_W"][k0:]) * dt * 1e-3),
            "inertia_energy_kJ": float(np.sum(rec["true_friction_power_W"][ki:]) * dt * 1e-3),
            "tie_up_fraction": fight / t_t,
            "engine_torque_min_Nm": float(np.min(rec["true_engine_torque_Nm"][k0:])),
            "engine_torque_max_Nm": float(np.max(rec["true_engine_torque_Nm"][k0:])),
            "fallback": int(np.max(rec["tcu_fallback"][k0:])),
            "gear": 2 if bool(rec["true_oncoming_locked"][-1] > 0.5) else (1 if rec["true_offgoing_locked"][-1] > 0.5 else 0),
        }
    return {
        "inertia_time_s": inertia,
        "inertia_time_error": (inertia - target_s) / target_s if math.isfinite(inertia) else float("nan"),
        "slip_rmse_rpm": float(np.sqrt(np.mean(err ** 2)) / plant_mod.RPM) if err.size else float("nan"),
        "peak_jerk_m_s3": float(np.max(np.abs(jerk[k0:]))),
        "peak_inertia_jerk_m_s3": float(np.max(np.abs(jerk[ki:k_jerk_end]))),
        "friction_energy_kJ": float(np.sum(rec["true_friction_power_W"][k0:]) * dt * 1e-3),
        "peak_theta_degC": float(np.max(rec["true_theta_clutch_degC"][k0:])),
        "peak_theta_estimate_degC": float(np.max(rec["theta_estimate_degC"][k0:])),
        "flare": bool(flare_rpm > FLARE_RPM),
        "flare_rpm": flare_rpm,
        "tie_up": bool(fight > TIE_UP_FRACTION * t_t),
        "tie_up_Nm": fight,
        "abort": abort,
        "abort_reason": ABORT_NAMES.get(abort, str(abort)),
        "pressure_rmse_kPa": float(np.sqrt(np.mean(p_err ** 2)) * 1e-3),
        "tcu_report": {k: (float(v) if k != "step" else int(v)) for k, v in report.items()} if report else None,
        **whole,
    }


def worst(qs: list[dict]) -> dict:
    """A scenario's figures over its shifts (the soak): the worst of each."""
    if len(qs) == 1:
        return dict(qs[0])
    out = dict(qs[-1])
    for key in ("slip_rmse_rpm", "peak_jerk_m_s3", "peak_inertia_jerk_m_s3", "peak_theta_degC", "friction_energy_kJ",
                "pressure_rmse_kPa", "flare_rpm", "tie_up_Nm", "torque_phase_jerk_m_s3", "offgoing_energy_kJ",
                "inertia_energy_kJ", "tie_up_fraction"):
        if key in out:
            out[key] = max(q[key] for q in qs)
    out["inertia_time_error"] = max((q["inertia_time_error"] for q in qs), key=lambda e: abs(e) if math.isfinite(e) else 1e9)
    out["inertia_time_s"] = max((q["inertia_time_s"] for q in qs),
                                key=lambda t: abs(t - TARGET_INERTIA_S) if math.isfinite(t) else 1e9)
    out["flare"] = any(q["flare"] for q in qs)
    out["tie_up"] = any(q["tie_up"] for q in qs)
    aborts = [q["abort"] for q in qs if q["abort"] != 0]
    out["abort"] = aborts[0] if aborts else 0
    out["abort_reason"] = ABORT_NAMES.get(out["abort"], str(out["abort"]))
    out["shifts"] = len(qs)
    return out
