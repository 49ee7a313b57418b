"""A standard drive cycle (DESIGN 16; issue 31, item 3): the WLTC class 3b trace, GTR 15's tolerance on it,
the driver and the integrator's shift schedule.

One module per concern:

trace       the WLTC class 3b speed trace from PyPI's wltp package (wltp.cycles.class3), checked against its
            published checksum; SpeedTrace (linear between the 1 Hz points), TraceError
tolerance   GTR 15's speed-trace tolerance (±2 km/h about the trace's extremes within ±1 s): the violations
            with their duration and excess, and which of them were the transmission's (per-time flags)
driver      the driver: speed PI with the trace's acceleration fed forward through a mass estimate, preview,
            anti-windup -> pedal 0..1 and brake torque
schedule    the shift schedule file (schedule_8hp.toml: up and down lines of output speed over the pedal,
            kickdown, minimum time in gear, ...): reading and checking it, ShiftSchedule, ScheduleError
scheduler   the schedule at work: pedal and output speed -> shift requests (current gear, target gear)

How a vehicle plugs in (the loop a cycle runner steps, at 1 ms with the TCU or 10 ms alone):

    cmd = driver.step(t, v_mps, pedal_force_N=vehicle.pedal_force_range(v))   # (F at pedal 0, at pedal 1)
    req = scheduler.step(t, cmd.pedal, vehicle.output_rpm, vehicle.engaged_gear, vehicle.shift_active)
    if req: tcu.request_shift(req.from_gear, req.to_gear)
    vehicle.step(dt, cmd.pedal, cmd.brake_torque_Nm, lockup=scheduler.lockup_allowed(vehicle.output_rpm))

then find_violations(trace, t, v_kmh) and attribute_violations(..., {"shift in progress": ..., "TCU safe
state": ...}). Only util is imported from the package: the layer sits above the simulators and the shift
runner (tests/python/test_package_layout.py) so that the runner of the whole cycle can live here.
"""
from __future__ import annotations

from .driver import Driver, DriverCommand, DriverParams
from .schedule import DEFAULT_SCHEDULE, ScheduleError, ShiftSchedule, load_schedule
from .scheduler import Scheduler, ShiftRequest, count_by_kind, find_hunting
from .tolerance import (Attribution, Violation, attribute_violations, envelope, find_violations,
                        format_violations, summarize)
from .trace import SpeedTrace, TraceError, load_wltc_class3b

__all__ = ["Attribution", "DEFAULT_SCHEDULE", "Driver", "DriverCommand", "DriverParams", "ScheduleError",
           "Scheduler", "ShiftRequest", "ShiftSchedule", "SpeedTrace", "TraceError", "Violation",
           "attribute_violations", "count_by_kind", "envelope", "find_hunting", "find_violations",
           "format_violations", "load_schedule", "load_wltc_class3b", "summarize"]
