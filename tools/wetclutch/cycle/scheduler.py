"""The shift schedule at work: from pedal and output speed to shift requests (current gear, target gear).

The integrator's side of DESIGN 16: the TCU shifts when it is asked; this decides when to ask. Stepped with
the time, the pedal (0..1), the output-shaft speed (rpm), the gear the transmission reports engaged and whether
a shift is in progress; ``step`` returns a ShiftRequest or None. Rules, in order:

  1. one request at a time: while a shift is in progress, or a request is neither engaged nor older than
     request_timeout (then it is dropped: the TCU refused it, e.g. in its safe state), nothing new;
  2. standstill: below the standstill output speed, above 1st, down toward 1st at once (skips allowed, no
     minimum time): the vehicle stands and launches in 1st, on the converter;
  3. minimum time in gear since the engaged gear last changed;
  4. kickdown (pedal past pedal_on until it is back under pedal_off): down toward the lowest gear whose engine
     speed stays at or below target_engine_speed_max, by the schedule's single-element skips where one
     fits (8->6, 7->5, ...), else one gear; no upshift while it lasts except at upshift_engine_speed (engine
     protection);
  5. the lines: below the down line of the engaged gear at this pedal, one gear down; above its up line, one
     up; but not against the direction of the last shift sooner than reversal_delay after it engaged (a
     driver's pedal rises after an upshift by the ratio step, and the down line must not take that for a
     demand: no up-down-up hunting).

Without a transmission (engaged_gear=None) the last request counts as engaged at once: the schedule alone on
a speed trace. ``count_by_kind`` and ``find_hunting`` read a run's requests for a report.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

from .schedule import ShiftSchedule


@dataclass(frozen=True)
class ShiftRequest:
    time_s: float
    from_gear: int
    to_gear: int
    pedal: float
    output_rpm: float
    reason: str             # "line", "kickdown", "standstill" or "overspeed"
    power_on: bool          # by the pedal (the schedule's view; the TCU's type follows the turbine torque)

    @property
    def upshift(self) -> bool:
        return self.to_gear > self.from_gear

    @property
    def skip(self) -> bool:
        return abs(self.to_gear - self.from_gear) > 1

    @property
    def kind(self) -> str:
        return f"power-{'on' if self.power_on else 'off'} {'upshift' if self.upshift else 'downshift'}"


class Scheduler:
    """The shift schedule's state: the engaged gear and since when, a pending request, kickdown."""

    def __init__(self, schedule: ShiftSchedule, gear: int = 1):
        if not 1 <= gear <= schedule.gears:
            raise ValueError(f"Scheduler: gear {gear} outside 1..{schedule.gears}")
        self.schedule = schedule
        self.gear = gear                # the gear last requested (or engaged at the start)
        self.engaged = gear
        self.engaged_since_s = -math.inf      # no shift yet: the minimum time does not hold the first
        self.pending: ShiftRequest | None = None
        self.kickdown = False
        self.requests: list[ShiftRequest] = []
        self.dropped: list[ShiftRequest] = []

    def _request(self, t_s: float, to_gear: int, pedal: float, output_rpm: float, reason: str) -> ShiftRequest:
        r = ShiftRequest(t_s, self.engaged, to_gear, pedal, output_rpm, reason,
                         pedal >= self.schedule.power_on_pedal_min)
        self.pending = r
        self.gear = to_gear
        self.requests.append(r)
        return r

    def step(self, t_s: float, pedal: float, output_rpm: float, engaged_gear: int | None = None,
             shift_active: bool = False) -> ShiftRequest | None:
        s = self.schedule
        if pedal >= s.kickdown_pedal_on:
            self.kickdown = True
        elif pedal < s.kickdown_pedal_off:
            self.kickdown = False

        if engaged_gear is None:            # no transmission: the request engaged when it was made
            if self.pending is not None:
                self.engaged, self.engaged_since_s = self.pending.to_gear, self.pending.time_s
            engaged = self.engaged
        else:
            engaged = engaged_gear
            if not 1 <= engaged <= s.gears:
                raise ValueError(f"Scheduler.step: engaged gear {engaged} outside 1..{s.gears}")
            if engaged != self.engaged:
                self.engaged, self.engaged_since_s = engaged, t_s

        if self.pending is not None:
            if engaged == self.pending.to_gear and not shift_active:
                self.pending = None
            elif t_s - self.pending.time_s >= s.request_timeout_s and not shift_active:
                self.dropped.append(self.pending)
                self.pending, self.gear = None, engaged
            else:
                return None
        if shift_active:
            return None

        g = engaged
        if g > 1 and output_rpm < s.standstill_output_rpm:
            return self._request(t_s, s.step_down_toward(g, 1), pedal, output_rpm, "standstill")
        if t_s - self.engaged_since_s < s.min_time_in_gear_s:
            return None
        if self.kickdown:
            target = s.kickdown_gear(g, output_rpm)
            if target < g:
                return self._request(t_s, s.step_down_toward(g, target), pedal, output_rpm, "kickdown")
            if g < s.gears and s.engine_rpm(g, output_rpm) >= s.kickdown_upshift_engine_rpm:
                return self._request(t_s, g + 1, pedal, output_rpm, "overspeed")
            return None
        last = self.requests[-1] if self.requests else None
        settled = t_s - self.engaged_since_s >= s.reversal_delay_s
        if g > 1 and output_rpm < s.down_line_rpm(g, pedal) and (settled or last is None or not last.upshift):
            return self._request(t_s, g - 1, pedal, output_rpm, "line")
        if g < s.gears and output_rpm > s.up_line_rpm(g, pedal) and (settled or last is None or last.upshift):
            return self._request(t_s, g + 1, pedal, output_rpm, "line")
        return None

    def lockup_allowed(self, output_rpm: float, shift_active: bool = False) -> bool:
        """The converter's lock-up clutch may close: from the schedule's lock-up gear and speed, not in a shift
        (1st below it: the launch on the open converter)."""
        s = self.schedule
        return (not shift_active and self.pending is None and self.engaged >= s.lockup_min_gear
                and output_rpm >= s.lockup_min_output_rpm)


def count_by_kind(requests) -> dict:
    """{"power-on upshift": n, ..., "skip": n, "kickdown": n, "standstill": n, "total": n}."""
    kinds = Counter(r.kind for r in requests)
    out = {k: kinds.get(k, 0) for k in ("power-on upshift", "power-off upshift", "power-on downshift",
                                         "power-off downshift")}
    out["skip"] = sum(1 for r in requests if r.skip)
    for reason in ("kickdown", "standstill", "overspeed"):
        out[reason] = sum(1 for r in requests if r.reason == reason)
    out["total"] = len(requests)
    return out


def find_hunting(requests, window_s: float) -> list[tuple[ShiftRequest, ShiftRequest, ShiftRequest]]:
    """Every up-down-up or down-up-down of three consecutive requests within window_s (first to last)."""
    out = []
    for a, b, c in zip(requests, requests[1:], requests[2:]):
        if a.upshift == c.upshift != b.upshift and c.time_s - a.time_s < window_s:
            out.append((a, b, c))
    return out
