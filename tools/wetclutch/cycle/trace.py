"""The WLTC class 3b speed trace (UN GTR 15, Annex 1; DESIGN 16) from PyPI's ``wltp`` package, checked.

Source: ``wltp.cycles.class3.class_data_b()`` of wltp 0.1.2a0 (JRC, EUPL 1.1+; a pinned dependency in
tools/pyproject.toml), pure data: the class 3b cycle as 1801 speeds in km/h at 1 Hz (t = 0 ... 1800 s), the
phases ("parts", start and end second of Low, Medium, High, Extra-high) and the checksum the GTR's table prints
(the sum of the 1 Hz speeds). Nothing is typed in here: the speeds come only from the package, and they are
accepted only if they pass every check of ``check_class3b``:

  - the sum of the 1801 speeds is the published checksum 83,758.6 km/h (GTR 15, Annex 1, class 3b; DESIGN 16)
    within half the printed digit, and the package's own ``checksum`` field says the same;
  - 1801 samples (1800 s at 1 Hz), the maximum 131.3 km/h (Extra-high phase), standing at both ends;
  - the phases are the class 3 ones, 0-589, 590-1022, 1023-1477, 1478-1800 s.

(Class 3a, ``class_data_a``, differs from 3b in 183 samples of the Medium and High phases; its checksum,
83,496.9, fails the first check.) A missing package or a failed check raises TraceError with what to do.

Between the 1 Hz points the trace is linear (``speed_kmh``); its acceleration (``acceleration_mps2``) is the
mean slope over a short window, what a driver reads off the driver's aid. Units: km/h as the GTR prints the
trace, m/s and m/s^2 where a model integrates.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# GTR 15, Annex 1, class 3b (DESIGN 16): the printed checksum of the 1 Hz speeds, km/h
CLASS3B_CHECKSUM_KMH = 83758.6
CLASS3B_SAMPLES = 1801
CLASS3B_MAX_KMH = 131.3
CLASS3_PHASES_S = {"low": (0, 589), "medium": (590, 1022), "high": (1023, 1477), "extra_high": (1478, 1800)}
KMH_PER_MPS = 3.6
WLTP_REQUIREMENT = "wltp==0.1.2a0"


class TraceError(Exception):
    """The speed trace cannot be had (package missing) or fails its published checks; the message says which."""


@dataclass(frozen=True)
class SpeedTrace:
    """A speed trace at a uniform step: ``speed_kmh[k]`` at ``t0_s + k * step_s``."""

    name: str
    speed_kmh: np.ndarray           # read-only
    step_s: float = 1.0
    t0_s: float = 0.0
    phases_s: tuple = ()            # ((name, start_s, end_s), ...)
    source: str = ""

    def __post_init__(self):
        v = np.array(self.speed_kmh, dtype=float)
        if v.ndim != 1 or v.size < 2:
            raise TraceError(f"{self.name}: a speed trace needs at least two samples")
        if not np.all(np.isfinite(v)) or np.any(v < 0.0):
            raise TraceError(f"{self.name}: speeds must be finite and not negative")
        if not (self.step_s > 0.0 and math.isfinite(self.step_s)):
            raise TraceError(f"{self.name}: step_s must be positive, not {self.step_s}")
        v.setflags(write=False)
        object.__setattr__(self, "speed_kmh", v)
        object.__setattr__(self, "_v", v.tolist())     # plain floats: the per-step lookups stay cheap

    @property
    def time_s(self) -> np.ndarray:
        return self.t0_s + self.step_s * np.arange(self.speed_kmh.size)

    @property
    def duration_s(self) -> float:
        return self.step_s * (self.speed_kmh.size - 1)

    @property
    def end_s(self) -> float:
        return self.t0_s + self.duration_s

    def speed_kmh_at(self, t_s: float) -> float:
        """The trace at t_s, linear between samples, held at its first and last value outside."""
        v = self._v
        x = (t_s - self.t0_s) / self.step_s
        if x <= 0.0:
            return v[0]
        k = int(x)
        if k >= len(v) - 1:
            return v[-1]
        f = x - k
        return v[k] + f * (v[k + 1] - v[k])

    def speed_mps_at(self, t_s: float) -> float:
        return self.speed_kmh_at(t_s) / KMH_PER_MPS

    def acceleration_mps2(self, t_s: float, half_window_s: float = 0.5) -> float:
        """Mean slope of the trace over [t - h, t + h] (h = half_window_s), m/s^2."""
        h = max(half_window_s, 1e-6)
        return (self.speed_kmh_at(t_s + h) - self.speed_kmh_at(t_s - h)) / (2.0 * h * KMH_PER_MPS)

    def segment(self, start_s: float, end_s: float, name: str | None = None) -> "SpeedTrace":
        """The samples from start_s to end_s inclusive (e.g. the Low phase, 0-589 s), keeping their times."""
        k0 = int(round((start_s - self.t0_s) / self.step_s))
        k1 = int(round((end_s - self.t0_s) / self.step_s))
        if not 0 <= k0 < k1 < self.speed_kmh.size:
            raise TraceError(f"{self.name}: segment {start_s}..{end_s} s outside the trace "
                             f"{self.t0_s}..{self.end_s} s")
        return SpeedTrace(name or f"{self.name} [{start_s:g}, {end_s:g}] s", self.speed_kmh[k0:k1 + 1],
                          self.step_s, self.t0_s + k0 * self.step_s,
                          tuple(p for p in self.phases_s if start_s <= p[1] and p[2] <= end_s), self.source)

    def phase(self, name: str) -> "SpeedTrace":
        for p_name, start, end in self.phases_s:
            if p_name == name:
                return self.segment(start, end, f"{self.name} {name}")
        raise TraceError(f"{self.name}: no phase '{name}' (phases: {[p[0] for p in self.phases_s]})")


def _class3_module():
    try:
        from wltp.cycles import class3        # pure data; wltp's own __init__ imports only its version
    except ImportError as e:
        raise TraceError(f"the WLTC class 3b trace comes from PyPI's wltp package ({WLTP_REQUIREMENT}, "
                         f"wltp.cycles.class3), which cannot be imported ({e}): run scripts/setup.sh, or "
                         f"pip install '{WLTP_REQUIREMENT}'") from None
    return class3


def check_class3b(speeds_kmh, package_checksum, parts, where: str) -> None:
    """Raise TraceError unless the data are the class 3b cycle (module docstring)."""
    v = [float(x) for x in speeds_kmh]
    total = math.fsum(v)
    problems = []
    if len(v) != CLASS3B_SAMPLES:
        problems.append(f"{len(v)} samples, not {CLASS3B_SAMPLES} (1800 s at 1 Hz)")
    if abs(total - CLASS3B_CHECKSUM_KMH) > 0.05:
        problems.append(f"the speeds sum to {total:.1f} km/h, not the published checksum {CLASS3B_CHECKSUM_KMH}")
    if package_checksum is None or abs(float(package_checksum) - CLASS3B_CHECKSUM_KMH) > 0.05:
        problems.append(f"the package's checksum field is {package_checksum}, not {CLASS3B_CHECKSUM_KMH}")
    if v and abs(max(v) - CLASS3B_MAX_KMH) > 1e-9:
        problems.append(f"the maximum is {max(v)} km/h, not {CLASS3B_MAX_KMH}")
    if v and (v[0] != 0.0 or v[-1] != 0.0):
        problems.append("the cycle does not start and end at standstill")
    if [tuple(p) for p in (parts or [])] != list(CLASS3_PHASES_S.values()):
        problems.append(f"phases {parts}, not {list(CLASS3_PHASES_S.values())}")
    if problems:
        raise TraceError(f"{where}: not the WLTC class 3b trace: " + "; ".join(problems))


def load_wltc_class3b() -> SpeedTrace:
    """The WLTC class 3b trace from wltp.cycles.class3, checked (module docstring); TraceError otherwise."""
    class3 = _class3_module()
    where = "wltp.cycles.class3.class_data_b()"
    try:
        data = class3.class_data_b()
        speeds, checksum, parts = data["cycle"], data.get("checksum"), data.get("parts")
    except (AttributeError, KeyError, TypeError) as e:
        raise TraceError(f"{where}: the wltp package does not have the layout of {WLTP_REQUIREMENT} ({e!r})") from None
    check_class3b(speeds, checksum, parts, where)
    try:
        from wltp import __version__ as version
    except ImportError:
        version = "?"
    return SpeedTrace("WLTC class 3b", np.asarray(speeds, dtype=float), 1.0, 0.0,
                      tuple((name, start, end) for name, (start, end) in CLASS3_PHASES_S.items()),
                      f"wltp {version}, {where}; checksum {CLASS3B_CHECKSUM_KMH} km/h (GTR 15 Annex 1)")
