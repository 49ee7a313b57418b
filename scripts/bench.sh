#!/usr/bin/env bash
# Instruction counts of wc_clutch_step and wc_inverse over a grid of operating
# points (bench/wc_bench.c: slip 0-3000 rpm, 10-120 degC, torque request from
# 0 to 1.1 x the capacity at the maximum current), measured with
# valgrind --tool=callgrind: every call is dumped on its own (client requests),
# so the figures are exact per call and independent of machine load. Also
# prints the host wall-clock median ns per call (noisy, secondary).
#
#   scripts/bench.sh          (needs cmake, ninja, valgrind, python3; ~5 s)
#
# Built with the host-release preset's settings in build/bench-release (its
# own tree, without the unit tests, so it does not need cmocka). The counts are
# x86-64 instructions of this host's compiler at -O3, not Cortex-M4 cycles:
# use them to compare versions and operating points.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
build="$repo/build/bench-release"

for tool in cmake ninja valgrind python3; do
  command -v "$tool" >/dev/null || { echo "bench: $tool not found (scripts/setup.sh installs it)" >&2; exit 2; }
done

log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { cmake --preset host-release -B "$build" -DWC_BUILD_TESTS=OFF &&
       cmake --build "$build" --target wc_bench; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "bench: FAIL: building wc_bench" >&2
  exit 1
fi
grep -q '^WC_HAVE_CALLGRIND_H:INTERNAL=1' "$build/CMakeCache.txt" ||
  { echo "bench: valgrind/callgrind.h missing (Debian package valgrind): no instruction counts" >&2; exit 1; }

bench="$build/bench/wc_bench"
echo "bench: native run (wall clock)"
"$bench"

echo "bench: callgrind run (instruction counts)"
out="$build/callgrind.wc_bench.out"
valgrind --tool=callgrind --collect-atstart=no --combine-dumps=yes \
  --callgrind-out-file="$out" "$bench" 2>"$log" || { cat "$log" >&2; echo "bench: FAIL: callgrind run" >&2; exit 1; }

compiler=$(sed -n 's/^CMAKE_C_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
python3 - "$out" "$(valgrind --version)" "$(basename "$compiler") $("$compiler" -dumpfullversion)" <<'EOF'
import re, statistics, sys
path, valgrind, cc = sys.argv[1:4]
parts, label = [], None
for line in open(path):
    if line.startswith("desc: Trigger: Client Request: "):
        label = line[len("desc: Trigger: Client Request: "):].strip()
    elif line.startswith("totals: ") and label is not None:
        parts.append((label, int(line.split()[1])))
        label = None
overhead = [n for l, n in parts if l == "overhead"]
if not overhead:
    sys.exit("bench: no dumps in the callgrind output")
base = statistics.median_low(overhead)

def calls(name, cond=lambda l: True):
    return [(n - base, l) for l, n in parts if l.startswith(name + " ") and cond(l)]

def row(title, rows):
    if not rows:
        return f"| {title} | 0 | - | - | - | |"
    counts = sorted(n for n, _ in rows)
    worst = max(n for n, _ in rows)
    at = [l for n, l in rows if n == worst]
    where = " ".join(at[0].split()[1:5])
    if len(at) > 1:
        where += f" and {len(at) - 1} more"
    return f"| {title} | {len(rows)} | {counts[0]} | {statistics.median_low(counts)} | {worst} | {where} |"

status = lambda s: (lambda l: re.search(r"status=(0x[0-9a-f]+)", l).group(1) == s)
iters = [int(m) for l, _ in parts for m in re.findall(r"iterations=(\d+)", l) if l.startswith("wc_inverse")]
print(f"""
## Instructions per call (scripts/bench.sh)

{valgrind} callgrind, x86-64, {cc} -O3 (host-release), table1 calibration.
Grid: slip 0-3000 rpm x oil 10-120 degC x request 0-1.1 x capacity at the
maximum current, {len(calls('wc_inverse'))} operating points, one call per dump,
client-request overhead ({base} instructions) subtracted.

| call | points | best Ir | median Ir | worst Ir | worst at |
|---|---:|---:|---:|---:|---|
{row("wc_clutch_step", calls("wc_clutch_step"))}
{row("wc_inverse", calls("wc_inverse"))}
{row("wc_inverse, solving (status 0)", calls("wc_inverse", status("0x00")))}
{row("wc_inverse, below drag", calls("wc_inverse", status("0x01")))}
{row("wc_inverse, saturated", calls("wc_inverse", status("0x02")))}

Newton steps seen: median {statistics.median_low(iters)}, worst {max(iters)}.""")
EOF
