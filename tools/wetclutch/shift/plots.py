"""The Fig. 4-style panels of one scenario, the controllers overlaid."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..simulate import plant as plant_mod
from .quality import _lowpass_zero_phase
from .scenarios import JERK_CUTOFF_HZ


def plot_case(path: Path, runs: dict, title: str) -> None:
    """Fig. 4-style panels of one scenario, the controllers overlaid: speeds, slip and its reference, clutch
    torque, pressure and current, vehicle acceleration and jerk, clutch temperature (true and estimated)."""
    from ..util import plotting
    fig, axes = plotting.subplots(3, 2, figsize=(13, 11), sharex=True)
    colors = {"feedback": "tab:red", "blind": "tab:orange", "full": "tab:blue", "nolag": "tab:gray"}
    for ctrl, rec in runs.items():
        c = colors.get(ctrl, "k")
        k0 = rec["command_step"]
        t = rec["t_s"] - rec["t_s"][k0]
        lab = {"feedback": "(a) feedback", "blind": "(b) 2-DOF blind", "full": "(c) 2-DOF full", "nolag": "(c) no lag comp."}[ctrl]
        _speeds_and_slip(axes, t, rec, c, lab, "slip", ctrl == "full")
        ax = axes[1, 0]
        ax.plot(t, rec["true_clutch_torque_Nm"], color=c, label=f"true {lab}")
        ax.plot(t, rec["model_torque_Nm"], color=c, ls=":", lw=1)
        ax = axes[1, 1]
        ax.plot(t, rec["pressure_command_Pa"] * 1e-3, color=c, ls="--", lw=1)
        ax.plot(t, rec["true_pressure_Pa"] * 1e-3, color=c, label=f"piston {lab}")
        _accel_and_temperature(axes, t, rec, c, lab)
    plotting.style(axes[0, 0], ylabel="speed (rpm)", title="turbine and synchronous speeds", legend={"fontsize": 7})
    plotting.style(axes[0, 1], ylabel="slip (rpm)", title="slip (solid) and reference (dashed)", legend={"fontsize": 7})
    plotting.style(axes[1, 0], ylabel="torque (Nm)", title="on-coming clutch torque: true (solid), TCU model (dotted)",
                   legend={"fontsize": 7})
    plotting.style(axes[1, 1], ylabel="pressure (kPa)", title="piston pressure (solid) and TCU's wanted pressure (dashed)",
                   legend={"fontsize": 7})
    _finish(fig, axes, "clutch temperature: true (solid), TCU estimate (dashed)", 1.0, title, path)


def plot_whole_case(path: Path, runs: dict, title: str) -> None:
    """Fig. 4-style panels of a whole shift (DESIGN 14), the controllers overlaid: speeds, slip and reference,
    both clutches' torques and the engine's, both pistons' pressures, vehicle acceleration and jerk, the
    on-coming clutch's temperature (true and estimated)."""
    from ..util import plotting
    fig, axes = plotting.subplots(3, 2, figsize=(13, 11), sharex=True)
    colors = {"whole_feedback": "tab:red", "whole_blind": "tab:orange", "whole_full": "tab:blue"}
    labels = {"whole_feedback": "(a)", "whole_blind": "(b)", "whole_full": "(c)"}
    for ctrl, rec in runs.items():
        c = colors.get(ctrl, "k")
        lab = labels.get(ctrl, ctrl)
        k0 = rec["command_step"]
        t = rec["t_s"] - rec["t_s"][k0]
        full = ctrl == "whole_full"
        _speeds_and_slip(axes, t, rec, c, lab, "on-coming slip", full)
        ax = axes[1, 0]
        ax.plot(t, rec["true_clutch_torque_Nm"], color=c, label=f"on-coming {lab}")
        ax.plot(t, rec["true_offgoing_torque_Nm"], color=c, ls="-.", label=f"off-going {lab}")
        if full:
            ax.plot(t, rec["true_engine_torque_Nm"], color="tab:green", label="engine (turbine) torque (c)")
        ax = axes[1, 1]
        ax.plot(t, rec["true_pressure_Pa"] * 1e-3, color=c, label=f"on-coming piston {lab}")
        ax.plot(t, rec["true_offgoing_pressure_Pa"] * 1e-3, color=c, ls="-.", label=f"off-going piston {lab}")
        if full:
            ax.plot(t, rec["pressure_command_Pa"] * 1e-3, color=c, ls="--", lw=1, label="on-coming wanted (c)")
        _accel_and_temperature(axes, t, rec, c, lab)
    plotting.style(axes[0, 0], ylabel="speed (rpm)", title="turbine and synchronous speeds", legend={"fontsize": 7})
    plotting.style(axes[0, 1], ylabel="slip (rpm)", title="on-coming slip (solid) and reference (dashed)",
                   legend={"fontsize": 7})
    plotting.style(axes[1, 0], ylabel="torque (Nm)", title="clutch torques (on-coming solid, off-going dash-dot), engine",
                   legend={"fontsize": 7})
    plotting.style(axes[1, 1], ylabel="pressure (kPa)", title="piston pressures (on-coming solid, off-going dash-dot)",
                   legend={"fontsize": 7})
    _finish(fig, axes, "on-coming clutch temperature: true (solid), TCU estimate (dashed)", 1.3, title, path)


def _speeds_and_slip(axes, t, rec, c, lab, slip_label: str, sync: bool) -> None:
    """The top panels of both figures: turbine speed (and once the synchronous speeds), slip and its reference."""
    ax = axes[0, 0]
    ax.plot(t, rec["true_turbine_speed_rpm"], color=c, label=f"turbine {lab}")
    if sync:
        ax.plot(t, rec["true_gear1_speed_rpm"], "k:", lw=1, label="1st-gear sync (i1 w_o)")
        ax.plot(t, rec["true_gear2_speed_rpm"], "k--", lw=1, label="2nd-gear sync (i2 w_o)")
    ax = axes[0, 1]
    ax.plot(t, rec["true_slip_rad_s"] / plant_mod.RPM, color=c, label=f"{slip_label} {lab}")
    ax.plot(t, rec["reference_slip_rad_s"] / plant_mod.RPM, color=c, ls="--", lw=1)


def _accel_and_temperature(axes, t, rec, c, lab) -> None:
    """The bottom panels of both figures: vehicle acceleration (10 Hz) and jerk / 10, clutch temperature."""
    ax = axes[2, 0]
    dt = rec["t_s"][1] - rec["t_s"][0]
    acc = _lowpass_zero_phase(rec["true_vehicle_accel_m_s2"], dt, JERK_CUTOFF_HZ)
    ax.plot(t, acc, color=c, label=f"accel {lab}")
    ax.plot(t, np.gradient(acc, dt) / 10.0, color=c, ls=":", lw=1)
    ax = axes[2, 1]
    ax.plot(t, rec["true_theta_clutch_degC"], color=c, label=f"true {lab}")
    ax.plot(t, rec["theta_estimate_degC"], color=c, ls="--", lw=1)


def _finish(fig, axes, temperature_title: str, x_max_s: float, title: str, path: Path) -> None:
    """The bottom panels' style, the time window (the records run from the pre-roll on: fit what it shows), save."""
    from ..util import plotting
    plotting.style(axes[2, 0], xlabel="time from shift command (s)", ylabel="m/s^2  |  jerk / 10 (m/s^3)",
                   title="vehicle acceleration (10 Hz) and jerk/10 (dotted)", legend={"fontsize": 7})
    plotting.style(axes[2, 1], xlabel="time from shift command (s)", ylabel="degC", title=temperature_title,
                   legend={"fontsize": 7})
    for ax in axes.flat:
        ax.set_xlim(-0.05, x_max_s)
        plotting.fit_y_to_x(ax)
    fig.suptitle(title)
    plotting.save(fig, path)
