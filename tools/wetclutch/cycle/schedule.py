"""A shift schedule file (the integrator's side, DESIGN 16): reading it, checking it, the ShiftSchedule type.

The format is documented at the head of tools/wetclutch/cycle/schedule_8hp.toml (the nominal 8-speed
vehicle's schedule, DEFAULT_SCHEDULE): up and down lines of output-shaft speed (rpm) over the pedal, the
gearbox's forward ratios and the kickdown skips it allows, minimum time in gear and before a reversal,
kickdown, standstill, power-on pedal, lock-up.

Checks (each a ScheduleError naming the file and the key, no traceback): the TOML, every key known, every
number { value, unit, source } in its unit, finite and in range; ratios positive and strictly decreasing; the
pedal axis in 0..1, strictly increasing; one up line per gear but the top, one down line per gear but 1st, each
as long as the axis, positive and not falling with the pedal; at every pedal point the up lines rising with the
gear and so the down lines; every up line G-H at least hysteresis_min above the down line H-G (no hunting
between two gears); skip downshifts two or more gears down inside the box; kickdown pedal_off < pedal_on <= 1.
"""
from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass
from pathlib import Path

from ..util.tomlfile import read_toml

DEFAULT_SCHEDULE = Path(__file__).with_name("schedule_8hp.toml")

# section -> {key: unit}; "lines" and "gears" are read apart
_SCALARS = {
    "timing": {"min_time_in_gear": "s", "reversal_delay": "s", "request_timeout": "s"},
    "kickdown": {"pedal_on": "1", "pedal_off": "1", "target_engine_speed_max": "rpm",
                 "upshift_engine_speed": "rpm"},
    "standstill": {"output_speed": "rpm"},
    "power": {"on_pedal_min": "1"},
    "lockup": {"min_gear": "1", "min_output_speed": "rpm"},
    "checks": {"hysteresis_min": "1"},
}
_TOP = {"name", "gears", "lines", *_SCALARS}


class ScheduleError(Exception):
    """A shift schedule file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class ShiftSchedule:
    """A checked shift schedule; lines are output-shaft speeds (rpm) over ``pedal_axis``."""

    name: str
    ratios: tuple[float, ...]                   # gear 1 first
    skip_downshifts: frozenset                  # {(from, to), ...}
    pedal_axis: tuple[float, ...]
    up_rpm: dict                                # {G: line of G -> G+1}
    down_rpm: dict                              # {G: line of G -> G-1}
    min_time_in_gear_s: float
    reversal_delay_s: float
    request_timeout_s: float
    kickdown_pedal_on: float
    kickdown_pedal_off: float
    kickdown_target_engine_rpm_max: float
    kickdown_upshift_engine_rpm: float
    standstill_output_rpm: float
    power_on_pedal_min: float
    lockup_min_gear: int
    lockup_min_output_rpm: float
    hysteresis_min: float
    path: str = ""

    @property
    def gears(self) -> int:
        return len(self.ratios)

    def _line(self, line: tuple[float, ...], pedal: float) -> float:
        axis = self.pedal_axis
        if not pedal > axis[0]:             # also NaN: the pedal released
            return line[0]
        if pedal >= axis[-1]:
            return line[-1]
        k = bisect_right(axis, pedal) - 1
        f = (pedal - axis[k]) / (axis[k + 1] - axis[k])
        return line[k] + f * (line[k + 1] - line[k])

    def up_line_rpm(self, gear: int, pedal: float) -> float:
        """Output speed above which gear -> gear + 1 is due at this pedal."""
        return self._line(self.up_rpm[gear], pedal)

    def down_line_rpm(self, gear: int, pedal: float) -> float:
        """Output speed below which gear -> gear - 1 is due at this pedal."""
        return self._line(self.down_rpm[gear], pedal)

    def engine_rpm(self, gear: int, output_rpm: float) -> float:
        return output_rpm * self.ratios[gear - 1]

    def kickdown_gear(self, gear: int, output_rpm: float) -> int:
        """The lowest gear at or below ``gear`` whose engine speed stays at or below the kickdown's maximum."""
        for g in range(1, gear + 1):
            if self.engine_rpm(g, output_rpm) <= self.kickdown_target_engine_rpm_max:
                return g
        return gear

    def step_down_toward(self, gear: int, target: int) -> int:
        """The gear one request may go to on the way from gear down to target: the largest allowed skip that
        does not pass the target, else one gear."""
        best = gear - 1
        for frm, to in self.skip_downshifts:
            if frm == gear and target <= to < best:
                best = to
        return max(best, target)


def _where(path, key: str) -> str:
    return f"{path}: {key}"


def _number(doc: dict, section: str, key: str, unit: str, path) -> float:
    where = _where(path, f"{section}.{key}")
    entry = doc.get(key)
    if not isinstance(entry, dict) or set(entry) - {"value", "unit", "source"} or "value" not in entry:
        raise ScheduleError(f"{where}: must be {{ value, unit = \"{unit}\", source }}")
    if entry.get("unit") != unit:
        raise ScheduleError(f"{where}: unit must be \"{unit}\", not {entry.get('unit')!r}")
    value = entry["value"]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ScheduleError(f"{where}: value must be a finite number, not {value!r}")
    return float(value)


def _curve(doc: dict, section: str, key: str, unit: str, path) -> tuple[float, ...]:
    where = _where(path, f"{section}.{key}")
    entry = doc.get(key)
    if not isinstance(entry, dict) or set(entry) - {"value", "unit", "source"} or "value" not in entry:
        raise ScheduleError(f"{where}: must be {{ value = [...], unit = \"{unit}\", source }}")
    if entry.get("unit") != unit:
        raise ScheduleError(f"{where}: unit must be \"{unit}\", not {entry.get('unit')!r}")
    values = entry["value"]
    if not isinstance(values, list) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                               and math.isfinite(v) for v in values):
        raise ScheduleError(f"{where}: value must be a list of finite numbers")
    return tuple(float(v) for v in values)


def _unknown(table: dict, known, where: str) -> None:
    extra = sorted(set(table) - set(known))
    if extra:
        raise ScheduleError(f"{where}: unknown key(s) {extra} (known: {sorted(known)})")


def _lines(doc: dict, n: int, axis: tuple, path) -> tuple[dict, dict]:
    out = []
    for kind, step in (("up", 1), ("down", -1)):
        table = doc.get(kind)
        if not isinstance(table, dict):
            raise ScheduleError(f"{_where(path, 'lines.' + kind)}: missing table")
        gears = range(1, n) if step > 0 else range(2, n + 1)
        names = {f"{g}-{g + step}": g for g in gears}
        _unknown(table, names, _where(path, f"lines.{kind}"))
        lines = {}
        for name, g in names.items():
            if name not in table:
                raise ScheduleError(f"{_where(path, f'lines.{kind}')}: missing line \"{name}\"")
            line = _curve(table, f"lines.{kind}", name, "rpm", path)
            where = _where(path, f"lines.{kind}.{name}")
            if len(line) != len(axis):
                raise ScheduleError(f"{where}: {len(line)} points, the pedal axis has {len(axis)}")
            if min(line) <= 0.0:
                raise ScheduleError(f"{where}: output speeds must be positive")
            if any(b < a for a, b in zip(line, line[1:])):
                raise ScheduleError(f"{where}: must not fall as the pedal rises")
            lines[g] = line
        out.append(lines)
    return out[0], out[1]


def _check_order(up: dict, down: dict, axis: tuple, hysteresis: float, path) -> None:
    for lines, kind in ((up, "up"), (down, "down")):
        gears = sorted(lines)
        for g, h in zip(gears, gears[1:]):
            for k, pedal in enumerate(axis):
                if not lines[h][k] > lines[g][k]:
                    raise ScheduleError(f"{_where(path, f'lines.{kind}')}: at pedal {pedal} the line of gear {h} "
                                        f"({lines[h][k]} rpm) is not above gear {g}'s ({lines[g][k]} rpm)")
    for g, line in up.items():
        for k, pedal in enumerate(axis):
            lo = down[g + 1][k]
            if line[k] < (1.0 + hysteresis) * lo:
                raise ScheduleError(f"{_where(path, f'lines.up.{g}-{g + 1}')}: at pedal {pedal} {line[k]} rpm is "
                                    f"less than {1.0 + hysteresis:g} x the down line {g + 1}-{g} ({lo} rpm): "
                                    "the two gears would hunt")


def load_schedule(path: str | Path = DEFAULT_SCHEDULE) -> ShiftSchedule:
    """Read and check a shift schedule file (module docstring); ScheduleError on the first problem."""
    doc = read_toml(path, ScheduleError, "shift schedule (TOML)")
    _unknown(doc, _TOP, str(path))
    name = doc.get("name", "")
    if not isinstance(name, str):
        raise ScheduleError(f"{_where(path, 'name')}: must be text")

    gears = doc.get("gears")
    if not isinstance(gears, dict):
        raise ScheduleError(f"{_where(path, 'gears')}: missing table")
    _unknown(gears, {"ratios", "skip_downshifts"}, _where(path, "gears"))
    ratios = _curve(gears, "gears", "ratios", "1", path)
    if len(ratios) < 2 or min(ratios) <= 0.0 or any(b >= a for a, b in zip(ratios, ratios[1:])):
        raise ScheduleError(f"{_where(path, 'gears.ratios')}: at least two positive ratios, strictly decreasing")
    n = len(ratios)
    skips = set()
    for pair in gears.get("skip_downshifts", []):
        if (not isinstance(pair, list) or len(pair) != 2 or not all(isinstance(g, int) and not isinstance(g, bool)
                                                                     for g in pair)
                or not 1 <= pair[1] < pair[0] - 1 or pair[0] > n):
            raise ScheduleError(f"{_where(path, 'gears.skip_downshifts')}: {pair!r} is not [from, to] with "
                                f"1 <= to < from - 1, from <= {n}")
        skips.add((pair[0], pair[1]))

    lines = doc.get("lines")
    if not isinstance(lines, dict):
        raise ScheduleError(f"{_where(path, 'lines')}: missing table")
    _unknown(lines, {"pedal", "up", "down"}, _where(path, "lines"))
    axis = _curve(lines, "lines", "pedal", "1", path)
    if len(axis) < 2 or axis[0] < 0.0 or axis[-1] > 1.0 or any(b <= a for a, b in zip(axis, axis[1:])):
        raise ScheduleError(f"{_where(path, 'lines.pedal')}: at least two points in 0..1, strictly increasing")
    up, down = _lines(lines, n, axis, path)

    s = {}
    for section, keys in _SCALARS.items():
        table = doc.get(section)
        if not isinstance(table, dict):
            raise ScheduleError(f"{_where(path, section)}: missing table")
        _unknown(table, keys, _where(path, section))
        for key, unit in keys.items():
            s[f"{section}.{key}"] = _number(table, section, key, unit, path)
    positive = ("timing.request_timeout", "kickdown.target_engine_speed_max", "kickdown.upshift_engine_speed",
                "standstill.output_speed")
    for key in positive:
        if s[key] <= 0.0:
            raise ScheduleError(f"{_where(path, key)}: must be positive")
    for key in ("timing.min_time_in_gear", "timing.reversal_delay", "lockup.min_output_speed",
                "checks.hysteresis_min"):
        if s[key] < 0.0:
            raise ScheduleError(f"{_where(path, key)}: must not be negative")
    if not 0.0 < s["kickdown.pedal_off"] < s["kickdown.pedal_on"] <= 1.0:
        raise ScheduleError(f"{_where(path, 'kickdown')}: need 0 < pedal_off < pedal_on <= 1")
    if not 0.0 <= s["power.on_pedal_min"] < 1.0:
        raise ScheduleError(f"{_where(path, 'power.on_pedal_min')}: must be in 0..1")
    lockup_gear = s["lockup.min_gear"]
    if lockup_gear != int(lockup_gear) or not 1 <= lockup_gear <= n:
        raise ScheduleError(f"{_where(path, 'lockup.min_gear')}: a gear 1..{n}")
    _check_order(up, down, axis, s["checks.hysteresis_min"], path)

    return ShiftSchedule(
        name=name, ratios=ratios, skip_downshifts=frozenset(skips), pedal_axis=axis, up_rpm=up, down_rpm=down,
        min_time_in_gear_s=s["timing.min_time_in_gear"], reversal_delay_s=s["timing.reversal_delay"],
        request_timeout_s=s["timing.request_timeout"],
        kickdown_pedal_on=s["kickdown.pedal_on"], kickdown_pedal_off=s["kickdown.pedal_off"],
        kickdown_target_engine_rpm_max=s["kickdown.target_engine_speed_max"],
        kickdown_upshift_engine_rpm=s["kickdown.upshift_engine_speed"],
        standstill_output_rpm=s["standstill.output_speed"], power_on_pedal_min=s["power.on_pedal_min"],
        lockup_min_gear=int(lockup_gear), lockup_min_output_rpm=s["lockup.min_output_speed"],
        hysteresis_min=s["checks.hysteresis_min"], path=str(path))
