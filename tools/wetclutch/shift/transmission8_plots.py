"""One figure per shift type of the 8-speed (issue 29 item 5) in the style of the paper's Fig. 4: the major
variables of a shift over time with its phases marked, from a ShiftTrace (transmission8.trace_shift: the
firmware's transmission on the 8-speed plant). Six panels, time from the shift request:
  speeds       the true turbine speed and the two gears' synchronous speeds (ratio x the true output speed)
  currents     the on-coming and the off-going element's current, the TCU's command
  torques      the two elements' true torques (the plant's sign: > 0 against the element's positive slip) and
               the true gearbox input torque T_t
  engine       the engine's true torque and the TCU's intervention (the requested change while active)
  vehicle      acceleration (10 Hz) and jerk / 10, as the 1->2 figures (plots.py) and the quality's peak jerk
  temperature  the on-coming element's surface temperature: the plant's truth and the TCU's observer
On every panel a vertical line where the TCU's shift phase changes, named on the top two.
`python -m wetclutch.shift.transmission8 --plots` (with --matrix by default) writes them:
out/transmission8/plots/<type>.png.
"""
from __future__ import annotations

from pathlib import Path

from .plots import _accel_and_temperature, _finish

ONCOMING, OFFGOING = "tab:blue", "tab:red"


def file_name(kind: str) -> str:
    """The PNG of a shift type: "power-off upshift" -> "power-off-upshift.png"."""
    return kind.replace(" ", "-") + ".png"


def plot_shift(path: Path, trace) -> str:
    """Fig. 4-style panels of one traced shift (module docstring), written to path. Returns the path."""
    from ..util import plotting
    q = trace.quality
    n = trace.tcu["phase"].size            # the TCU's rows are the truth's rows 0 .. n - 1
    t = trace.time_s()[:n]
    truth = {name: values[:n] for name, values in trace.truth.items()}
    on, off = trace.oncoming, trace.offgoing
    source, target = q["shift"].split("->")
    fig, axes = plotting.subplots(3, 2, figsize=(13, 11), sharex=True)

    ax = axes[0, 0]
    ax.plot(t, truth["turbine_speed_rpm"], color=ONCOMING, label="turbine")
    ax.plot(t, trace.ratios[0] * truth["output_speed_rpm"], "k:", lw=1, label=f"gear {source} sync (i{source} w_o)")
    ax.plot(t, trace.ratios[1] * truth["output_speed_rpm"], "k--", lw=1, label=f"gear {target} sync (i{target} w_o)")
    plotting.style(ax, ylabel="speed (rpm)", title="turbine and synchronous speeds (true)", legend={"fontsize": 7})

    ax = axes[0, 1]
    ax.plot(t, trace.tcu[f"{on}_current_mA"], color=ONCOMING, label=f"on-coming {on}")
    ax.plot(t, trace.tcu[f"{off}_current_mA"], color=OFFGOING, ls="-.", label=f"off-going {off}")
    plotting.style(ax, ylabel="current (mA)", title="element currents: the TCU's command", legend={"fontsize": 7})

    ax = axes[1, 0]
    ax.plot(t, truth[f"{on}_torque_Nm"], color=ONCOMING, label=f"on-coming {on}")
    ax.plot(t, truth[f"{off}_torque_Nm"], color=OFFGOING, ls="-.", label=f"off-going {off}")
    ax.plot(t, truth["input_torque_Nm"], color="tab:gray", lw=1, label="gearbox input T_t")
    plotting.style(ax, ylabel="torque (Nm)", title="element torques (true; > 0 against the element's positive slip)",
                   legend={"fontsize": 7})

    ax = axes[1, 1]
    ax.plot(t, truth["engine_torque_Nm"], color="tab:green", label="engine torque (true)")
    ax.plot(t, trace.tcu["engine_delta_Nm"] * (trace.tcu["engine_active"] > 0.5), color="tab:purple", ls="--",
            label="TCU's intervention (change requested)")
    plotting.style(ax, ylabel="torque (Nm)", title="engine torque and the TCU's intervention", legend={"fontsize": 7})

    record = {"t_s": truth["t_s"], "true_vehicle_accel_m_s2": truth["vehicle_accel_m_s2"],
              "true_theta_clutch_degC": truth[f"{on}_theta_degC"], "theta_estimate_degC": trace.tcu[f"{on}_theta_degC"]}
    _accel_and_temperature(axes, t, record, ONCOMING, q["shift"])
    _mark_phases(axes, t, trace)
    title = (f"{q['kind']} {q['shift']} ({q['vehicle']} vehicle, oil {q['oil_degC']:g} degC, pedal {q['pedal']:.2f}): "
             f"peak jerk {q['peak_jerk_m_s3']:.1f} m/s^3, inertia {q['inertia_time_s']:.2f} s "
             f"(target {q['target_s']:g}), flare/sag {q['excursion_rpm']:.0f} rpm")
    _finish(fig, axes, f"on-coming element {on}: true (solid), TCU estimate (dashed)", float(t[-1]), title, path)
    return str(path)


def _mark_phases(axes, t, trace) -> None:
    """A vertical line on every panel where the TCU's shift phase changes; the new phase's name on the top two
    (changes closer than 2 % of the window, as LOCKED then IDLE a period later, share one line: "locked / idle")."""
    marks = []                             # [period, name]
    for k, name in trace.phase_changes():
        if marks and t[k] - t[marks[-1][0]] < 0.02 * (t[-1] - t[0]):
            marks[-1][1] += f" / {name}"
        else:
            marks.append([k, name])
    for k, name in marks:
        for ax in axes.flat:
            ax.axvline(t[k], color="0.55", lw=0.8, ls=(0, (4, 3)))
        for ax in axes[0]:
            ax.text(t[k], 0.98, f" {name}", transform=ax.get_xaxis_transform(), rotation=90, va="top", ha="right",
                    fontsize=7, color="0.35")


def write_plots(out: Path, traces) -> list[Path]:
    """One PNG per traced shift, OUT/<its type>.png (file_name): all or none (util.atomic.Staged, which
    plotting.save joins). Returns the paths."""
    from ..util.atomic import Staged
    kinds = [trace.quality["kind"] for trace in traces]
    if len(set(kinds)) != len(kinds):
        raise ValueError(f"one trace per shift type: {kinds}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / file_name(kind) for kind in kinds]
    with Staged():
        for path, trace in zip(paths, traces):
            plot_shift(path, trace)
    return paths
