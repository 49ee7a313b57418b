#!/usr/bin/env bash
# The whole closed-loop 1->2 upshift (issue 22, DESIGN 14): fill, the off-going
# clutch under the TCU's control, the engine torque intervention and the
# fallback of a lost input, the plants of the vehicle family
# (tools/plants/vehicles/) against the TCU's frame loop in-process, (a) feedback
# only, (b) 2-DOF thermal-blind, (c) 2-DOF full model; report in out/shift/
# (whole_shift_report.md, metrics.json, Fig. 4-style plots, MDF4). Exit 1 when a
# target is missed. Then the 8-speed's matrix (issue 29, DESIGN 15): every single step and skip in the four
# shift types with the firmware's transmission on the 8-speed plant (tools/plants/8hp/: nominal, heavy,
# light; power-on at 100 and 25 % load; 80 degC), report in out/transmission8/ (matrix.md, matrix.json);
# exit 1 when either misses a target. Then the 8-speed's fault matrix (wetclutch.shift.faults8: a lost input in
# each phase of each shift type against the documented fallback; exit 1 when a row differs).
#   bash scripts/shift.sh [--vehicles nominal soft ...] [--out DIR]
#   bash scripts/shift.sh --oncoming-only [--plant tools/plants/OTHER.toml]   (issue 13's comparison)
#   bash scripts/shift.sh --gearbox [--vehicles nominal] [--oil 20 80 110] [--loads 1.0] [--out DIR]
#                                                   (the 8-speed's matrix and its fault matrix alone)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh
.venv/bin/wetclutch lut tools/calibrations/bench_identified.toml --out lut >/dev/null
.venv/bin/wetclutch lut tools/calibrations/shift_1_2.toml --out lut >/dev/null
.venv/bin/wetclutch vehicle-cal >/dev/null   # the TCU's driveline model of each vehicle (committed; regenerated identically)
cmake --preset host-release >/dev/null
cmake --build --preset host-release >/dev/null
rc=0
if [ "${1:-}" = "--gearbox" ]; then
  shift
  PYTHONPATH=tools .venv/bin/python -m wetclutch.shift.transmission8 --matrix "$@" || rc=$?
else
  .venv/bin/wetclutch shift "$@" || rc=$?
  case " $* " in *" --oncoming-only "*) exit "$rc" ;; esac
  PYTHONPATH=tools .venv/bin/python -m wetclutch.shift.transmission8 --matrix || rc=$((rc > 0 ? rc : $?))
fi
# the 8-speed's fault matrix (issue 29 item 2): a lost input in each phase of each type, nominal vehicle, 80 degC
PYTHONPATH=tools .venv/bin/python -m wetclutch.shift.faults8 || rc=$((rc > 0 ? rc : $?))
exit "$rc"
