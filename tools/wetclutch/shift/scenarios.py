"""What the shift runner compares: the paths, the targets' thresholds, the scenario matrix (issue 13)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


ROOT = Path(__file__).resolve().parents[3]
WC_REPLAY = ROOT / "build" / "host-release" / "src" / "host" / "wc_replay"
SHIFT_TOML = ROOT / "tools" / "calibrations" / "shift_1_2.toml"
TCU_CALIBRATION = "bench_identified"     # the TCU's clutch model: identified from the bench (truth: bench_true)
CONTROLLERS = {"a": "feedback", "b": "blind", "c": "full"}
TARGET_INERTIA_S = 0.5
FLARE_RPM = 20.0
SYNC_BAND_RAD_S = 0.3            # the clutch calibration's lock_slip: synchronised
TIE_UP_FRACTION = 0.1
JERK_CUTOFF_HZ = 10.0
SOAK_SHIFTS = 10
ABORT_NAMES = {0: "completed", 1: "inertia timeout", 2: "lockup failed", 3: "input lost", 4: "cancelled",
               5: "invalid command", 6: "no slip", -1: "no report"}


class ShiftError(RuntimeError):
    pass


@dataclass(frozen=True)
class Scenario:
    name: str
    oil_degC: float
    load: float                  # turbine torque / full load
    friction_scale: float = 1.0
    shifts: int = 1              # > 1: back-to-back shifts, temperatures carried over (heat soak)
    group: str = ""
    # the whole shift (DESIGN 14)
    engine_ignores: bool = False         # the engine ignores the TCU's torque request
    offgoing_friction: float = 1.0       # x the plant's off-going friction (a model error of the off-going clutch)
    scripted_release: bool = False       # the off-going clutch released by the plant's script (issue 13's way)
    fault: str = ""                      # a lost input in the middle of the shift (FAULTS), "" none


# Faults in the middle of a whole shift (DESIGN 14): ClutchSensors.SlipSpeed SNA (an implausible frame,
# dropped: the input goes stale, the loop's sensor timeout and safe state follow) from the phase's nominal
# start (the command + prepare time, + half the torque phase for "torque") + offset_s, for duration_s.
# name: (phase, offset_s, duration_s)
FAULTS = {
    "torque": ("torque", 0.0, 0.2),          # hand back to the off-going gear
    "inertia": ("inertia", 0.15, 0.2),       # finish on the model, the input back before the shift's end
    "inertia_long": ("inertia", 0.15, 2.0),  # longer than fallback_time_s: released at last
    # issue 29 item 7 (the fault probe): lost early in the inertia phase and back while ~60 rad/s of slip
    # remain; the finish must look at the slip again (locked in 2nd, never reported locked while slipping)
    "inertia_early": ("inertia", 0.02, 0.05),
}


def scenario_matrix(nominal_oil_degC: float = 80.0) -> list[Scenario]:
    """Issue 13's matrix: oil 20..110 degC at full load, load 25/50/100 % at the nominal oil, plant friction
    -/+10 % (model error), a heat soak of SOAK_SHIFTS full-load shifts. Nominal: 80 degC, 100 %, friction 1."""
    out = [Scenario(f"oil{int(t)}", t, 1.0, group="oil") for t in (20.0, 40.0, 60.0, 80.0, 100.0, 110.0)]
    out += [Scenario(f"load{int(x * 100)}", nominal_oil_degC, x, group="load") for x in (0.25, 0.5)]
    out += [Scenario(f"friction{round((s - 1.0) * 100):+d}pct", nominal_oil_degC, 1.0, s, group="friction")
            for s in (0.9, 1.1)]
    out.append(Scenario("soak", nominal_oil_degC, 1.0, shifts=SOAK_SHIFTS, group="soak"))
    return out


NOMINAL = "oil80"
