#!/usr/bin/env bash
# Main job: the HIL replay of the bundled 750 rpm engagement (paper Fig. 15).
# Builds the TCU program, brings up vcan0 (natively, or in a QEMU guest where
# the kernel has no CAN), replays hil/logs/engagement_750rpm.log with
# wc_canplay (in lockstep with the TCU's answers; it records the bus), decodes
# with cantools and writes the report to out/replay/engagement_750rpm/
# (summary.md, metrics.json, PNG plots).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh

# The TCU runs the calibration identified from the bench's campaign (bench
# data -> wetclutch identify -> calibration -> LUT headers -> firmware).
cal=tools/calibrations/bench_identified.toml
.venv/bin/wetclutch lut "$cal" --out lut
cmake --preset host-release >/dev/null
cmake --build --preset host-release >/dev/null
exec .venv/bin/wetclutch replay hil/logs/engagement_750rpm.log --calibration "$cal" --out out/replay "$@"
