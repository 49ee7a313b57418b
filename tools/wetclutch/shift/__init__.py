"""Closed-loop 1->2 upshifts: the plant simulator (simulate/plant) against the TCU's frame loop (``wetclutch shift``).

Lockstep on the frame clock: each period the plant's VCU/sensor side sends
TorqueRequest (Mode 3, Shift), ShiftCommand and ClutchSensors (last: it steps
the loop), the TCU answers VfsCommand, ClutchEstimate and, in the step a shift
ends, ShiftReport; the plant then advances one period with that VFS current.
The TCU is InprocTcu: `wc_replay --lockstep --shift NAME` through a pipe (the
frame loop linked into a host program). runner.run_on_vcan replays a case's
inputs to `wc_tcu --clock frame --shift NAME` on a SocketCAN interface
(natively or in the QEMU guest, hil/vcan_run.sh) in lockstep with its answers:
for the same case both give the same output frames
(tests/python/test_whole_shift.py, the whole shift).

Controllers compared (issue 13), variants of tools/calibrations/shift_1_2.toml:
(a) feedback: PI only; (b) blind: 2-DOF, clutch temperature = oil; (c) full:
2-DOF with observer, film state, lock-up and lag compensation; plus nolag ((c)
without the lag compensation) for the pressure-tracking figure.

Quality per shift, from the plant's truth (DESIGN 10):
  inertia_time_s   from the controller's inertia-phase start (the command +
                   prepare + torque-phase time) to synchronisation: the true
                   slip inside SYNC_BAND_RAD_S (the TCU's lock band, 2.9 rpm)
                   for the first time (the plates lock there, or within the
                   lock-up hand-over that follows);
  slip_rmse_rpm    RMS(true slip - reference slip) over the inertia phase
                   (the reference is the controller's: a smoothstep from the
                   measured slip at the phase start to 0 in the target time);
  peak_jerk_m_s3   max |d/dt of the vehicle acceleration| from the command to
                   the end, the acceleration low-passed at 10 Hz (2nd-order
                   Butterworth, zero phase): the band ride-comfort ratings
                   weight (ISO 2631-1 up to about 8 Hz), above it driveline
                   ringing the occupants do not feel as jerk;
  peak_inertia_jerk_m_s3  the same over the inertia phase only: from its start to
                   synchronisation (the torque phase's jerk, shared by the
                   controllers, is the whole-shift figure's);
  friction_energy_kJ, peak_theta_degC (true pack temperature);
  flare            turbine speed above the 1st-gear synchronous speed by more
                   than FLARE_RPM (the engine runs up: too little clutch torque);
  tie_up           the off-going clutch carrying torque against its release
                   direction (negative, fighting the shift) above TIE_UP_FRACTION
                   of the turbine torque;
  abort            the TCU's ShiftReport AbortReason (or no report at all);
  pressure_rmse_kPa RMS(true piston pressure - the TCU's PressureCommand, the
                   pressure it wants) from the command to the end.

One module per concern, every name importable from here (``shift.run_case``, ``shift.report``):

scenarios   paths, thresholds, ShiftError, the scenario matrix
tcu         InprocTcu (wc_replay --lockstep)
runner      one shift and a scenario's shifts (run_case), their frames (record_messages), reference_run,
            run_on_vcan (the case's inputs replayed to wc_tcu on vcan)
quality     the quality vector of a shift, a scenario's worst
comparison  the matrix x controllers, the feedback gains' search, the targets, the report (and its MDF4 files)
plots       the Fig. 4-style panels of a scenario (plot_case; plot_whole_case: both clutches and the engine)
whole       the whole shift (issue 22, DESIGN 14): the vehicle family, its scenarios and faults, targets, report
vehicle_cal the TCU's driveline model of each vehicle plant (`wetclutch vehicle-cal`)
matrix8     the 8-speed's power-on upshifts (issue 29 item 5): each element its own clutch as an equivalent clutch
            in the controller's coordinates, wc_replay on two images, the plant's truth; run_upshift (not imported
            here: it loads the 8-speed plant)
matrix8_report  the matrix 1->2 ... 7->8 x loads x vehicles, its markdown and JSON
"""
from __future__ import annotations

from .comparison import (FEEDBACK_KI, FEEDBACK_KP, INERTIA_TOLERANCE, JERK_LIMIT_M_S3, PRESSURE_RATIO_TARGET,
                         markdown, report, run_matrix, targets, tune_feedback)
from .plots import plot_case
from .quality import quality, worst
from .runner import frame_sequence, record_messages, reference_run, run_case, run_on_vcan
from .scenarios import (ABORT_NAMES, CONTROLLERS, FLARE_RPM, JERK_CUTOFF_HZ, NOMINAL, ROOT, SHIFT_TOML, SOAK_SHIFTS,
                        SYNC_BAND_RAD_S, TARGET_INERTIA_S, TCU_CALIBRATION, TIE_UP_FRACTION, WC_REPLAY, Scenario,
                        ShiftError, scenario_matrix)
from .tcu import InprocTcu

__all__ = [
    "ABORT_NAMES", "CONTROLLERS", "FEEDBACK_KI", "FEEDBACK_KP", "FLARE_RPM", "INERTIA_TOLERANCE", "JERK_CUTOFF_HZ",
    "JERK_LIMIT_M_S3", "NOMINAL", "PRESSURE_RATIO_TARGET", "ROOT", "SHIFT_TOML", "SOAK_SHIFTS", "SYNC_BAND_RAD_S",
    "TARGET_INERTIA_S", "TCU_CALIBRATION", "TIE_UP_FRACTION", "WC_REPLAY", "InprocTcu", "Scenario", "ShiftError",
    "frame_sequence", "markdown", "plot_case", "quality", "record_messages", "reference_run", "report",
    "run_case", "run_matrix", "run_on_vcan", "scenario_matrix", "targets", "tune_feedback", "worst",
]
