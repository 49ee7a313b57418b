#!/usr/bin/env bash
# All tests: installs what is missing, builds the host (sanitized) and the
# Cortex-M4F presets, runs static analysis, the Cortex-M4F checks and
# instruction counts, the package check, the fuzzers (60 s each), the C unit
# tests (ctest) and the Python tests (pytest), then prints the time per stage.
#
#   bash scripts/test.sh           # everything: the README's and CI's test command
#   bash scripts/test.sh --quick   # the edit-compile-test loop (under 3 min): static analysis,
#                                  # ctest and the Python tests not marked slow (no vcan, HIL,
#                                  # shift matrix, film study, identification, in-process replays)
#   bash scripts/test.sh --slow-guest  # the vcan tests alone, in a QEMU guest slowed to a third of its
#                                  # speed (hil/vcan_slow.sh: a CPU cgroup quota, the factor measured
#                                  # and printed; fails when it is not reached): they must pass there too
#
# Both cores are used where that weakens nothing: two fuzzers side by side
# (each on its own core for its full 60 s, so each gets the executions it gets
# alone), the third beside the static analysis and the Cortex-M4F and package
# checks, and pytest on two workers (pytest-xdist; each test module on one
# worker, tests/python/conftest.py).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"

quick=0 slow_guest=0
case "${1:-}" in
  "") ;;
  --quick) quick=1 ;;
  --slow-guest) slow_guest=1 ;;
  *) echo "test: unknown option '$1' (usage: bash scripts/test.sh [--quick|--slow-guest])" >&2; exit 2 ;;
esac

stage_names=()
stage_seconds=()
started_s=$SECONDS
report() {  # the time per stage, also after a failure
  local rc=$?
  echo
  echo "== time per stage (wall clock, s)"
  for i in "${!stage_names[@]}"; do printf '%6d  %s\n' "${stage_seconds[$i]}" "${stage_names[$i]}"; done
  printf '%6d  total%s\n' "$((SECONDS - started_s))" "$([ "$rc" -eq 0 ] || echo ", FAILED (exit $rc)")"
  # The Python runner's summary closes the output (tests/python ran, and how many).
  if [ -s "${pytest_log:-}" ]; then tail -n 1 "$pytest_log"; fi
}
pytest_log=$(mktemp)
trap 'report; rm -f "$pytest_log"; vcan_server_stop >/dev/null' EXIT
stage() {  # stage NAME CMD...: run CMD, record its wall time
  local name=$1 t0=$SECONDS
  shift
  echo "== $name"
  "$@"
  stage_names+=("$name")
  stage_seconds+=("$((SECONDS - t0))")
}

build() {
  cmake --preset host-debug >/dev/null
  cmake --build --preset host-debug
  if [ "$quick" = 0 ]; then  # wc_tcu for the vcan and HIL tests, wc_replay, wc_eval
    cmake --preset host-release >/dev/null
    cmake --build --preset host-release
  fi
}

checks() {  # one core's worth, run beside the third fuzzer (in the background: each step returns its failure)
  echo "== static analysis (cppcheck gating; MISRA C:2012 counts)"
  bash scripts/static_analysis.sh build/host-debug || return
  echo "== build: cortex-m4f (-Werror, no heap/stdio/double libm)"
  bash scripts/check_arm.sh || return
  echo "== Cortex-M4F instruction counts (QEMU -icount; fails above bench/arm_ceilings.txt)"
  bash scripts/bench_arm.sh || return
  echo "== package: find_package(wetclutch) after install, and add_subdirectory(), host and Cortex-M4F"
  bash scripts/check_package.sh
}

vcan_dir=""
vcan_server_start() {  # one guest for every vcan test (hil/vcan_run.sh --serve), booting before pytest
  vcan_dir=$(mktemp -d /tmp/vcan_server.XXXXXX)
  local slow=()
  [ "$slow_guest" = 0 ] || slow=(--slow 3)
  bash hil/vcan_run.sh "${slow[@]}" --serve "$vcan_dir" >"$vcan_dir/log" 2>&1 &
  vcan_pid=$!
  export VCAN_SERVER=$vcan_dir
}
vcan_server_stop() {
  [ -n "$vcan_dir" ] || return 0
  : > "$vcan_dir/stop"
  for _ in $(seq 600); do kill -0 "$vcan_pid" 2>/dev/null || break; sleep 0.1; done
  kill "$vcan_pid" 2>/dev/null || true
  wait "$vcan_pid" 2>/dev/null || true
  echo "vcan: one guest ran $(find "$vcan_dir/jobs" -name rc 2>/dev/null | wc -l) vcan commands ($(tail -n 1 "$vcan_dir/log"))"
  local j cmd  # each command's time in the guest (taken -> rc, the guest's clock): where the vcan stage goes
  for j in "$vcan_dir"/jobs/*/; do
    [ -e "$j/taken" ] && [ -e "$j/rc" ] || continue
    cmd=$(sed -n 's/^declare -a VCAN_CMD=(//p' "$j/env" 2>/dev/null | sed 's/\[[0-9]*\]=//g; s/"//g' | cut -c1-110)
    printf 'vcan: %6d s  exit %s  %s\n' "$(( $(stat -c %Y "$j/rc") - $(stat -c %Y "$j/taken") ))" "$(cat "$j/rc")" "$cmd"
  done
  local slowed_ok=0
  if [ "$slow_guest" = 1 ]; then
    echo "vcan: $(cat "$vcan_dir/slow/factor" "$vcan_dir/slow/failed" 2>/dev/null)"
    grep -q "^slowed" "$vcan_dir/slow/factor" 2>/dev/null && ! grep -q "NOT reached" "$vcan_dir/slow/factor" || slowed_ok=1
  fi
  rm -rf "$vcan_dir"
  vcan_dir=""
  return "$slowed_ok"
}

fuzz_and_checks() {  # the last fuzzer and the checks side by side, then the guest's boot beside the checks
  local dir rc_fuzz=0 rc_checks=0
  dir=$(mktemp -d)
  FUZZ_BUILD_ONLY=0 bash scripts/fuzz.sh calibration >"$dir/fuzz" 2>&1 & local fuzz_pid=$!
  checks >"$dir/checks" 2>&1 & local checks_pid=$!
  wait "$fuzz_pid" || rc_fuzz=$?
  vcan_server_start  # the vcan guest boots on the core the fuzzer leaves (its 60 s), while the checks go on
  wait "$checks_pid" || rc_checks=$?
  cat "$dir/checks" "$dir/fuzz"
  rm -rf "$dir"
  [ "$rc_checks" -eq 0 ] || { echo "test: the checks FAILED (exit $rc_checks)" >&2; return "$rc_checks"; }
  [ "$rc_fuzz" -eq 0 ] || { echo "test: fuzz calibration FAILED (exit $rc_fuzz)" >&2; return "$rc_fuzz"; }
}

python_tests() {
  export WC_EVAL="$repo/build/host-debug/src/host/wc_eval"
  export WC_IDENTIFY_FULL=1   # the identification targets on the full 184-experiment campaign
  # the vcan tests on one worker, every other module on one worker, the longest first
  # (tests/python/conftest.py); the 15 slowest tests listed
  local args=(-n 2 --dist loadgroup --no-loadscope-reorder -ra --durations=15)
  [ "$quick" = 1 ] && args+=(-m "not slow")
  [ "$slow_guest" = 1 ] && args=(-ra --durations=15 -m vcan)   # one guest: one worker
  [ "$quick" = 1 ] || [ -n "$vcan_dir" ] || vcan_server_start
  # pytest's own exit code, its output shown as it comes (and its summary kept for the end)
  local rc=0
  .venv/bin/python -m pytest tests/python "${args[@]}" | tee "$pytest_log" || rc=$?
  vcan_server_stop || { echo "test: the guest was not slowed as asked (above)" >&2; [ "$rc" -ne 0 ] || rc=1; }
  return "$rc"
}

stage "setup (scripts/setup.sh)" bash scripts/setup.sh
if [ "$slow_guest" = 1 ]; then
  stage "build: host-release" bash -c 'cmake --preset host-release >/dev/null && cmake --build --preset host-release'
  stage "vcan tests in a guest slowed to a third (pytest -m vcan)" python_tests
  exit 0
fi
stage "build: host-debug (address + undefined sanitizers)$([ "$quick" = 0 ] && echo ", host-release")" build
if [ "$quick" = 1 ]; then
  stage "static analysis (cppcheck gating; MISRA C:2012 counts)" bash scripts/static_analysis.sh build/host-debug
else
  stage "build: libFuzzer harnesses (ASan + UBSan)" env FUZZ_BUILD_ONLY=1 bash scripts/fuzz.sh
  stage "fuzz: model and loop side by side (60 s each)" env FUZZ_PARALLEL=2 bash scripts/fuzz.sh model loop
  stage "fuzz: calibration (60 s) beside static analysis, Cortex-M4F checks and counts, package check" \
    fuzz_and_checks
fi
stage "C unit tests (ctest)" ctest --test-dir build/host-debug --output-on-failure
stage "Python tests (pytest on 2 workers)" python_tests
