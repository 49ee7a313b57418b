"""GTR 15's speed-trace tolerance (WLTP Type 1 test; DESIGN 16) and who caused a violation.

The rule (GTR 15, Annex 6, the speed trace tolerances of the Type 1 test; the figures ±2.0 km/h and ±1.0 s
as DESIGN 16 and issue 31 state them): at every time t of the test the driven speed must lie inside the
envelope

    upper(t) = max of the trace over [t - 1 s, t + 1 s] + 2 km/h
    lower(t) = min of the trace over [t - 1 s, t + 1 s] - 2 km/h

The trace between its 1 Hz points is linear, so the extremes over a window are those of the samples inside it
and of the trace at the window's two ends. The same construction, with other numbers, is in the US EPA's
dynamometer schedules (40 CFR 600.109-08: 2 mph above the highest point on the trace within 1 s of the given
time, 2 mph below the lowest) and in the NEDC as the German StVZO states it (3.8.2 "Zulässige Abweichungen":
3.2 km/h about the highest and lowest speed within ±1 s). Both also accept excursions shorter than 2 s (the
EPA's "such as may occur during gear changes"); GTR 15's own text was not at hand. This module reports every
excursion with its duration and leaves such allowances to the caller: for a transmission, an excursion during a
shift is exactly what we want to see.

``find_violations`` returns each interval outside the envelope (start, end, duration, the largest excess in
km/h and where it was, above or below); ``attribute_violations`` names, for each, which of the caller's
per-time flags were set during it or in the tolerance window before it (for example "shift in progress",
"TCU in its safe state"): a violation with a flag set is the transmission's.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from .trace import SpeedTrace

SPEED_BAND_KMH = 2.0        # GTR 15 Annex 6: ±2.0 km/h ...
TIME_BAND_S = 1.0           # ... about the trace within ±1.0 s
EXCESS_EPS_KMH = 1e-9       # float noise: an excess at or below this is inside


@dataclass(frozen=True)
class Violation:
    """One interval outside the envelope: [start_s, end_s) with each sample covering up to the next."""

    start_s: float
    end_s: float
    max_excess_kmh: float       # how far outside the envelope at the worst sample
    worst_time_s: float
    side: str                   # "above", "below" or "both" (a long interval may leave on both sides)

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s


@dataclass(frozen=True)
class Attribution:
    """A violation and the flags that were set during it (or within lookback_s before it)."""

    violation: Violation
    flag_time_s: dict = field(default_factory=dict)     # {flag: seconds set in the window}, only flags set

    @property
    def causes(self) -> tuple[str, ...]:
        return tuple(self.flag_time_s)

    @property
    def transmission(self) -> bool:
        return bool(self.flag_time_s)


def _as_time(time_s, what: str, increasing: bool = True) -> np.ndarray:
    t = np.asarray(time_s, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"{what}: a non-empty 1-D array of times")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{what}: times must be finite")
    if increasing and t.size > 1 and not np.all(np.diff(t) > 0.0):
        raise ValueError(f"{what}: times must be strictly increasing")
    return t


def envelope(trace: SpeedTrace, time_s, speed_band_kmh: float = SPEED_BAND_KMH,
             time_band_s: float = TIME_BAND_S) -> tuple[np.ndarray, np.ndarray]:
    """(lower_kmh, upper_kmh) of the tolerance at each time of time_s (the window clipped to the trace)."""
    t = _as_time(time_s, "envelope", increasing=False)
    if speed_band_kmh < 0.0 or time_band_s < 0.0:
        raise ValueError("the tolerance bands must not be negative")
    v, h, t0 = trace.speed_kmh, trace.step_s, trace.t0_s
    grid = trace.time_s
    a = np.clip(t - time_band_s, t0, trace.end_s)
    b = np.clip(t + time_band_s, t0, trace.end_s)
    va, vb = np.interp(a, grid, v), np.interp(b, grid, v)
    hi_v, lo_v = np.maximum(va, vb), np.minimum(va, vb)
    first = np.ceil((a - t0) / h - 1e-9).astype(np.int64)
    last = np.floor((b - t0) / h + 1e-9).astype(np.int64)
    for j in range(int(math.ceil(2.0 * time_band_s / h)) + 2):    # every sample inside a window
        k = first + j
        inside = k <= last
        s = v[np.clip(k, 0, v.size - 1)]
        hi_v = np.where(inside, np.maximum(hi_v, s), hi_v)
        lo_v = np.where(inside, np.minimum(lo_v, s), lo_v)
    return lo_v - speed_band_kmh, hi_v + speed_band_kmh


def _sample_ends(t: np.ndarray) -> np.ndarray:
    """Each sample covers [t_i, t_i+1); the last one a step as long as the one before it (1 s if alone)."""
    last = t[-1] + (t[-1] - t[-2] if t.size > 1 else 1.0)
    return np.append(t[1:], last)


def excess_kmh(trace: SpeedTrace, time_s, speed_kmh, speed_band_kmh: float = SPEED_BAND_KMH,
               time_band_s: float = TIME_BAND_S) -> np.ndarray:
    """Signed distance outside the envelope at each sample: > 0 above it, < 0 below it, 0 inside."""
    t = _as_time(time_s, "excess_kmh")
    v = np.asarray(speed_kmh, dtype=float)
    if v.shape != t.shape or not np.all(np.isfinite(v)):
        raise ValueError("excess_kmh: speed_kmh must be finite and as long as time_s")
    lower, upper = envelope(trace, t, speed_band_kmh, time_band_s)
    return np.where(v > upper, v - upper, np.where(v < lower, v - lower, 0.0))


def find_violations(trace: SpeedTrace, time_s, speed_kmh, speed_band_kmh: float = SPEED_BAND_KMH,
                    time_band_s: float = TIME_BAND_S) -> list[Violation]:
    """Every interval where the driven speed (km/h at time_s) leaves the tolerance envelope of the trace."""
    t = _as_time(time_s, "find_violations")
    signed = excess_kmh(trace, t, speed_kmh, speed_band_kmh, time_band_s)
    outside = np.abs(signed) > EXCESS_EPS_KMH
    if not outside.any():
        return []
    ends = _sample_ends(t)
    edges = np.diff(np.concatenate(([0], outside.astype(np.int8), [0])))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    out = []
    for i0, i1 in zip(starts, stops):
        run = signed[i0:i1 + 1]
        k = int(np.argmax(np.abs(run)))
        side = "both" if (run > 0).any() and (run < 0).any() else ("above" if run[k] > 0 else "below")
        out.append(Violation(float(t[i0]), float(ends[i1]), float(abs(run[k])), float(t[i0 + k]), side))
    return out


def attribute_violations(violations, time_s, flags: Mapping[str, object],
                         lookback_s: float = TIME_BAND_S) -> list[Attribution]:
    """For each violation, the flags (name -> per-sample booleans on time_s) set during [start - lookback_s,
    end): a shift that ends just before the speed leaves the envelope is counted (the envelope's own time
    band is the default look-back)."""
    t = _as_time(time_s, "attribute_violations")
    width = _sample_ends(t) - t
    arrays = {}
    for name, values in flags.items():
        f = np.asarray(values, dtype=bool)
        if f.shape != t.shape:
            raise ValueError(f"attribute_violations: flag '{name}' has {f.size} samples, time_s {t.size}")
        arrays[name] = f
    out = []
    for v in violations:
        in_window = (t + width > v.start_s - lookback_s) & (t < v.end_s)
        set_s = {}
        for name, f in arrays.items():
            seconds = float(np.sum(width[in_window & f]))
            if seconds > 0.0:
                set_s[name] = seconds
        out.append(Attribution(v, set_s))
    return out


def summarize(violations, attributions=None) -> dict:
    """Counts and totals for a report: violations, seconds outside, the worst excess, the transmission's."""
    worst = max(violations, key=lambda v: v.max_excess_kmh, default=None)
    out = {
        "violations": len(violations),
        "seconds_outside": float(sum(v.duration_s for v in violations)),
        "max_excess_kmh": worst.max_excess_kmh if worst else 0.0,
        "worst_time_s": worst.worst_time_s if worst else None,
    }
    if attributions is not None:
        out["by_transmission"] = sum(1 for a in attributions if a.transmission)
    return out


def format_violations(violations, attributions=None) -> list[str]:
    """One line per violation (for a printed report)."""
    causes = {id(a.violation): a.causes for a in attributions or ()}
    lines = []
    for v in violations:
        c = causes.get(id(v))
        tail = "" if c is None else (f"  transmission: {', '.join(c)}" if c else "  not the transmission")
        lines.append(f"{v.start_s:8.2f} .. {v.end_s:8.2f} s  {v.duration_s:5.2f} s  {v.side:5s} "
                     f"by {v.max_excess_kmh:5.2f} km/h at {v.worst_time_s:.2f} s{tail}")
    return lines
