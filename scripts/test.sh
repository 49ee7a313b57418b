#!/usr/bin/env bash
# All tests: installs what is missing, builds the host (sanitized) and the
# Cortex-M4F presets, runs static analysis, the Cortex-M4F checks and
# instruction counts, the package check, the fuzzers (60 s each), the C unit
# tests (ctest) and the Python tests (pytest).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
bash scripts/setup.sh

echo "== build: host-debug (address + undefined sanitizers)"
cmake --preset host-debug >/dev/null
cmake --build --preset host-debug

echo "== static analysis (cppcheck gating; MISRA C:2012 counts)"
bash scripts/static_analysis.sh build/host-debug

echo "== build: host-release (wc_tcu for the vcan and HIL tests, wc_eval)"
cmake --preset host-release >/dev/null
cmake --build --preset host-release

echo "== build: cortex-m4f (-Werror, no heap/stdio/double libm)"
bash scripts/check_arm.sh

echo "== Cortex-M4F instruction counts (QEMU -icount; fails above bench/arm_ceilings.txt)"
bash scripts/bench_arm.sh

echo "== package: find_package(wetclutch) after install, and add_subdirectory(), host and Cortex-M4F"
bash scripts/check_package.sh

echo "== libFuzzer harnesses (ASan + UBSan), 60 s each from the committed corpora (scripts/fuzz.sh)"
bash scripts/fuzz.sh

echo "== C unit tests (ctest)"
ctest --test-dir build/host-debug --output-on-failure

echo "== Python tests (pytest)"
export WC_EVAL="$repo/build/host-debug/src/host/wc_eval"
export WC_IDENTIFY_FULL=1   # the identification targets on the full 184-experiment campaign
exec .venv/bin/python -m pytest tests/python -ra
