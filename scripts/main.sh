#!/usr/bin/env bash
# Main job: generate the LUT headers, build the library, and evaluate the
# firmware's torque model (wc_eval) on the bundled 750 rpm engagement,
# beside the double-precision reference.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh

.venv/bin/wetclutch lut tools/calibrations/table1.toml --out lut
cmake --preset host-release >/dev/null
cmake --build --preset host-release >/dev/null

example=tools/examples/engagement_750rpm.csv
firmware=$(cut -d, -f2-4 "$example" | build/host-release/src/host/wc_eval torque)
reference=$(cut -d, -f2-4 "$example" | .venv/bin/wetclutch reference torque)
echo "Model torque on $example (firmware float32 vs double reference):"
paste -d, "$example" <(echo "$firmware") <(echo "$reference" | cut -d, -f1) | .venv/bin/python -c '
import csv, sys
rows = list(csv.reader(sys.stdin))
print(f"{\"t_s\":>6} {\"slip_rpm\":>9} {\"theta_degC\":>10} {\"force_N\":>8} {\"torque_Nm\":>10} {\"viscous_Nm\":>10} {\"hbar_um\":>8} {\"mu_f\":>7} {\"ref_Nm\":>9}")
worst = 0.0
for r in rows[1:]:
    t, slip, theta, force, torque, coul, visc, hbar, mu, ref = map(float, r)
    worst = max(worst, abs(torque - ref) / max(abs(ref), 1e-9))
    print(f"{t:6.2f} {slip:9.1f} {theta:10.2f} {force:8.1f} {torque:10.3f} {visc:10.3f} {hbar:8.3f} {mu:7.4f} {ref:9.3f}")
print(f"max relative difference firmware vs reference: {worst:.2e}")
'
