#!/usr/bin/env bash
# Closed-loop 1->2 upshifts (issue 13): the plant simulator against the TCU's
# frame loop in-process, (a) feedback only, (b) 2-DOF thermal-blind, (c) 2-DOF
# full model, over the scenario matrix; report in out/shift/ (shift_report.md,
# metrics.json, Fig. 4-style plots). Exit 1 when a target is missed.
#   bash scripts/shift.sh [--plant tools/plants/OTHER.toml] [--out DIR]
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh
.venv/bin/wetclutch lut tools/calibrations/bench_identified.toml --out lut >/dev/null
.venv/bin/wetclutch lut tools/calibrations/shift_1_2.toml --out lut >/dev/null
cmake --preset host-release >/dev/null
cmake --build --preset host-release >/dev/null
exec .venv/bin/wetclutch shift "$@"
