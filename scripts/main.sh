#!/usr/bin/env bash
# Main job: the HIL replay of the bundled 750 rpm engagement (paper Fig. 15).
# Builds the TCU program, brings up vcan0 (natively, or in a QEMU guest where
# the kernel has no CAN), replays hil/logs/engagement_750rpm.log with
# canplayer, captures with candump, decodes with cantools and writes the
# report to out/replay/engagement_750rpm/ (summary.md, metrics.json, PNG plots).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh

.venv/bin/wetclutch lut tools/calibrations/table1.toml --out lut
cmake --preset host-release >/dev/null
cmake --build --preset host-release >/dev/null
exec .venv/bin/wetclutch replay hil/logs/engagement_750rpm.log --out out/replay "$@"
