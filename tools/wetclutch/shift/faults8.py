"""The 8-speed's fault matrix (issue 29 item 2, DESIGN 14 and 15): a lost input in each phase of each shift type,
on the 8-speed plant with the firmware's transmission in process (transmission8), against the fallback the
shift layer documents (include/wetclutch/wc_shift.h, wc_shift_fallback_t):

- before the on-coming element has the gear (the torque-first shift's prepare and torque phases, the
  inertia-first one's prepare and inertia phases): handed back to the source gear;
- after it (the torque-first shift's inertia phase, the inertia-first one's hand-over): finished on the model,
  the target gear once the input is back;
- a loss longer than the shift calibration's fallback_time_s after that: the shift released, and the
  transmission's safe state then holds the gear the on-coming element had taken at the maximum current
  (include/wetclutch/wc_transmission.h: the gear kept without inputs).

The lost input is both speeds at once (NaN: the loop's safe state, as when GearboxSensors goes stale or
fails its E2E check), from FAULTS' offset after the TCU first reports the phase, for its duration. Each row
also checks that the fallback does not flap: while the input is lost the TCU's phase never returns to one it
left, and the fault adds no flare: the turbine's excursion beyond the two gears' speeds stays within issue 29's
30 rpm, or within the same shift's without the fault (+ FLARE_ADDED_RPM) where that one flares already.

    python -m wetclutch.shift.faults8 [--vehicle nominal] [--oil 80] [--out FILE.json]   (exit 1: a row missed)
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import sys
from pathlib import Path

from ..calibration import shift as shift_calibration
from . import transmission8 as t8

# wc_shift_fallback_t (include/wetclutch/wc_shift.h), by value
FALLBACKS = ("none", "finished on the model", "handed back", "released")
NONE, FINISH, HANDBACK, RELEASED = range(4)

# one shift per type (DESIGN 15's four), at full load where the engine pulls
SHIFTS = ((3, 4, "power-on upshift", 1.0), (3, 4, "power-off upshift", 1.0), (4, 3, "power-on downshift", 1.0),
          (4, 3, "power-off downshift", 1.0))
TORQUE_FIRST = ("power-on upshift",)       # the others are inertia-first (wc_shift_inertia_first.c)

# name: (phase of transmission8.PHASES, offset_s, duration_s)
FAULTS = {
    "prepare": ("prepare", 0.01, 0.02),
    "torque": ("torque", 0.02, 0.05),
    "inertia": ("inertia", 0.05, 0.1),
    "torque_long": ("torque", 0.02, 2.0),
    "inertia_long": ("inertia", 0.05, 2.0),
}
# the faults run per family: the phases the family goes through, the long loss after the gear is the on-coming's
FAMILY_FAULTS = {"torque-first": ("prepare", "torque", "inertia", "inertia_long"),
                 "inertia-first": ("prepare", "inertia", "torque", "torque_long")}
EXCURSION_RPM = t8.EXCURSION_RPM           # no flare or sag beyond issue 29's 30 rpm ...
FLARE_ADDED_RPM = 5.0                      # ... or beyond the fault-free shift's + this (its speed sensors' resolution)


def family(kind: str) -> str:
    return "torque-first" if kind in TORQUE_FIRST else "inertia-first"


@functools.lru_cache(maxsize=1)
def fallback_time_s() -> float:
    """The controller's shift calibration's fallback_time_s: a finish on the model longer than this releases."""
    base = shift_calibration.load(t8.SHIFT_TOML).variants[t8.CONTROLLER]
    return float(base.values["fallback_time"])


def expected(kind: str, fault: str, source: int, target: int) -> tuple[int, str]:
    """(the fallback, the gear held at the end) the shift layer and the transmission document for fault in
    kind (module docstring)."""
    phase, _offset_s, duration_s = FAULTS[fault]
    first = family(kind) == "torque-first"
    before_gear = phase == "prepare" or (phase == "torque" if first else phase == "inertia")
    if before_gear:
        return HANDBACK, str(source)
    return (RELEASED if duration_s > fallback_time_s() else FINISH), str(target)


def _phases_while_lost(trace: t8.ShiftTrace) -> list[str] | None:
    """The TCU's phases in the periods whose input was lost (ShiftTrace.lost), each once in their order (None:
    the fault's phase never came)."""
    if trace.lost is None:
        return None
    window = [t8.PHASES[int(p)] for p in trace.tcu["phase"][trace.lost[0]:trace.lost[1]]]
    return [p for i, p in enumerate(window) if i == 0 or p != window[i - 1]]


def run_row(vehicle: str, source: int, target: int, kind: str, load: float, fault: str, oil_degC: float,
            lib=None, fault_free_rpm: float = 0.0) -> dict:
    """One shift with one fault: the measured fallback, end gear, excursion, phases while lost, and whether each
    is as documented; fault_free_rpm: the same shift's excursion without the fault."""
    spec = FAULTS[fault]
    trace = t8.trace_shift(vehicle, source, target, kind, load=load, oil_degC=oil_degC, lib=lib, fault=spec)
    q = trace.quality
    fallback, gear = expected(kind, fault, source, target)
    seen = _phases_while_lost(trace)
    row = {"vehicle": vehicle, "shift": q["shift"], "type": q["type"], "fault": fault, "phase": spec[0],
           "offset_s": spec[1], "duration_s": spec[2], "fallback": FALLBACKS[q["fallback"]] if q["fallback"] >= 0
           else "no report", "abort": q["abort"], "end_gear": q["end_gear"], "excursion_rpm": q["excursion_rpm"],
           "phases_while_lost": seen, "expected": f"{FALLBACKS[fallback]}, gear {gear}, no flare, no flapping"}
    row["fault_free_excursion_rpm"] = fault_free_rpm
    excursion_max = max(EXCURSION_RPM, fault_free_rpm + FLARE_ADDED_RPM)
    row["ok"] = bool(q["fallback"] == fallback and q["end_gear"] == gear and q["excursion_rpm"] <= excursion_max
                     and seen is not None and len(set(seen)) == len(seen))
    return row


def run_faults(vehicle: str = "nominal", oil_degC: float = t8.OIL_DEGC, lib=None) -> list[dict]:
    lib = lib or t8._library()                                  # noqa: SLF001 (one library for every row)
    rows = []
    for s, t, kind, load in SHIFTS:
        free = t8.run_shift(vehicle, s, t, kind, load=load, oil_degC=oil_degC, lib=lib)["excursion_rpm"]
        rows += [run_row(vehicle, s, t, kind, load, fault, oil_degC, lib, free) for fault in FAMILY_FAULTS[family(kind)]]
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m wetclutch.shift.faults8", description=__doc__.split("\n")[0])
    ap.add_argument("--vehicle", default="nominal", help="a vehicle of tools/plants/8hp or an 8-speed plant file")
    ap.add_argument("--oil", type=float, default=t8.OIL_DEGC, help="oil temperature, degC")
    ap.add_argument("--out", type=Path, help="write the rows as JSON here")
    args = ap.parse_args(argv)
    try:
        rows = run_faults(args.vehicle, args.oil)
    except t8.ShiftError as e:
        print(f"faults8: {e}", file=sys.stderr)
        return 2
    for r in rows:
        print(f"{r['shift']:>5} {r['type']:20s} {r['fault']:13s} {r['fallback']:22s} abort {r['abort']:2d} "
              f"gear {str(r['end_gear']):4s} excursion {r['excursion_rpm']:4.0f} rpm  while lost "
              f"{'>'.join(r['phases_while_lost'] or ['-']):28s} {'ok' if r['ok'] else 'MISSED'}")
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(rows, indent=1, default=lambda x: None if isinstance(x, float)
                                       and not math.isfinite(x) else x))
    missed = [r for r in rows if not r["ok"]]
    print(f"faults8: {len(rows) - len(missed)} of {len(rows)} rows as documented")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
