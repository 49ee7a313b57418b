#!/usr/bin/env bash
# libFuzzer harnesses with AddressSanitizer + UndefinedBehaviorSanitizer
# (tests/fuzz, DESIGN.md section 8): builds them into build/fuzz with clang,
# then runs each for a bounded time from a temporary copy of its committed
# seed corpus (tests/fuzz/corpus/<name>, never modified).
#
#   bash scripts/fuzz.sh                      # model, loop, calibration: 60 s each
#   FUZZ_SECONDS=600 bash scripts/fuzz.sh loop   # one (or several) by name, longer
#   bash scripts/fuzz.sh gearbox              # the transmission's harness: by name only
#
# Environment:
#   FUZZ_SECONDS   time per harness (libFuzzer -max_total_time), default 60
#   FUZZ_RUNS      stop a harness after this many executions instead (-runs)
#   FUZZ_FLAGS     extra libFuzzer flags, e.g. "-seed=1 -max_len=8192"
#   FUZZ_PARALLEL  harnesses run side by side (default 1), one core each
#   FUZZ_BUILD_ONLY=1  build the harnesses and stop
#   WC_FUZZ_LAX=1  fuzz_model checks the arithmetic helpers only inside the
#                  domain the library calls them with (default: every input)
#
# Prints per harness: executions, exec/s, coverage (cov: edges, ft: features),
# corpus size, time. Exits non-zero when a harness crashes or an oracle is
# violated, naming the reproducer (build/fuzz/artifacts/<name>/crash-...) and
# the command that replays it. One process per harness (no -jobs/-workers);
# FUZZ_PARALLEL=2 runs two harnesses side by side (scripts/test.sh on 2 cores).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"

# the default run; gearbox (the transmission, fuzz_gearbox.c) by name: built with the others, not run by
# default (scripts/test.sh names the ones it runs, 60 s each)
all=(model loop calibration)
known=("${all[@]}" gearbox)
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=("${all[@]}")
for h in "${harnesses[@]}"; do
  case " ${known[*]} " in
    *" $h "*) ;;
    *) echo "fuzz: unknown harness '$h' (one of: ${known[*]})" >&2; exit 2 ;;
  esac
done
seconds=${FUZZ_SECONDS:-60}
build=build/fuzz

# --- toolchain: Debian's clang plus its compiler-rt (libFuzzer, ASan, UBSan)
command -v clang >/dev/null || { echo "fuzz: clang not found (bash scripts/setup.sh installs it)" >&2; exit 1; }
command -v cmake >/dev/null || { echo "fuzz: cmake not found (bash scripts/setup.sh installs it)" >&2; exit 1; }
probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT
printf '#include <stddef.h>\n#include <stdint.h>\nint LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }\n' \
  > "$probe/probe.c"
if ! clang -fsanitize=fuzzer,address,undefined "$probe/probe.c" -o "$probe/probe" 2>"$probe/err"; then
  major=$(clang -dumpversion | cut -d. -f1)
  pkg="libclang-rt-${major}-dev"
  # Debian ships libFuzzer and the sanitizer runtimes apart from clang.
  if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null && apt-cache show "$pkg" >/dev/null 2>&1; then
    echo "fuzz: clang's libFuzzer/sanitizer runtimes are missing: installing $pkg"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$pkg" >/dev/null
    clang -fsanitize=fuzzer,address,undefined "$probe/probe.c" -o "$probe/probe"
  else
    cat "$probe/err" >&2
    echo "fuzz: clang cannot link a libFuzzer program: install $pkg (Debian) as root" >&2
    exit 1
  fi
fi

# --- build
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [ -f "$build/CMakeCache.txt" ] && ! grep -q '^CMAKE_C_COMPILER:[A-Z]*=.*clang' "$build/CMakeCache.txt"; then
  rm -rf "$build"  # configured with another compiler
fi
echo "== fuzz: build ($build)"
if [ ! -f "$build/CMakeCache.txt" ]; then
  if ! CC=clang cmake -S tests/fuzz -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$probe/cmake.log" 2>&1; then
    cat "$probe/cmake.log" >&2
    echo "fuzz: configuring tests/fuzz failed" >&2
    exit 1
  fi
fi
if ! cmake --build "$build" --parallel 2 >"$probe/build.log" 2>&1; then
  cat "$probe/build.log" >&2
  echo "fuzz: building the harnesses failed" >&2
  exit 1
fi

# --- run
[ "${FUZZ_BUILD_ONLY:-0}" = 1 ] && { echo "== fuzz: built (FUZZ_BUILD_ONLY=1)"; exit 0; }

work=$(mktemp -d)
trap 'rm -rf "$probe" "$work"' EXIT
mkdir -p "$build/logs"
# One harness: its findings replayed, then fuzzed; its summary line goes to
# $work/summary_<h>, a failure to $work/failed_<h> (so harnesses can run side by side).
fuzz_one() {
  local h=$1 exe corpus artifacts log limit bound max_len schedule findings start rc elapsed execs rate covline cov ft corp line own repro
  local -a summary_line
  exe="$build/fuzz_$h"
  corpus="$work/corpus_$h"
  artifacts="$build/artifacts/$h"
  log="$build/logs/fuzz_$h.log"
  mkdir -p "$corpus" "$artifacts"
  cp tests/fuzz/corpus/"$h"/* "$corpus"/ 2>/dev/null || true
  limit=(-max_total_time="$seconds")
  bound="$seconds s"
  if [ -n "${FUZZ_RUNS:-}" ]; then
    limit=(-runs="$FUZZ_RUNS")
    bound="$FUZZ_RUNS executions"
  fi
  max_len=4096
  schedule=()
  # The loop's inputs run from one to a thousand loop steps (fuzz_loop.h MAX_RECORDS): libFuzzer runs the fast
  # ones more often (tests/fuzz/README.md, "Speed"). Not reproducible with -seed then:
  # FUZZ_FLAGS=-entropic_scale_per_exec_time=0
  # Inputs of at most 2 KB (the seeds fit; fuzz_loop.h MAX_RECORDS): libFuzzer's length limit starts at the
  # longest seed and grows while nothing new is found, and every byte can be a sanitized loop step; in 60 s it
  # stays near the seeds' either way, a longer run (FUZZ_SECONDS) stays at 2 KB (README, "Speed again").
  [ "$h" = loop ] && { max_len=2048; schedule=(-entropic_scale_per_exec_time=1); }
  # Regression first: the recorded findings (tests/fuzz/findings/<name>-*) must pass.
  findings=(tests/fuzz/findings/"$h"-*)
  if [ -e "${findings[0]}" ]; then
    if ! "$exe" "${findings[@]}" >"$build/logs/fuzz_${h}_findings.log" 2>&1; then
      echo 1 >"$work/failed_$h"
      grep -E -B2 -A6 'ORACLE VIOLATION|WC_ASSERT FAILED|ERROR: AddressSanitizer|runtime error' \
        "$build/logs/fuzz_${h}_findings.log" | head -30 || true
      echo "fuzz: $h FAILED on a recorded finding (tests/fuzz/findings/README.md); log: $build/logs/fuzz_${h}_findings.log"
      summary_line=("$(printf '%-12s' "$h") FAILED: a recorded finding fails again (tests/fuzz/findings)")
      printf '%s\n' "${summary_line[@]}" >"$work/summary_$h"
      return
    fi
    echo "== fuzz: $h: ${#findings[@]} recorded findings replayed, ok"
  fi
  echo "== fuzz: $h ($bound, seeds: tests/fuzz/corpus/$h, log: $log)"
  start=$(date +%s)
  set +e
  # shellcheck disable=SC2086  # FUZZ_FLAGS is a list of flags
  "$exe" "$corpus" "${limit[@]}" -max_len=$max_len "${schedule[@]}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" ${FUZZ_FLAGS:-} >"$log" 2>&1
  rc=$?
  set -e
  elapsed=$(( $(date +%s) - start ))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  covline=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$covline")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$covline")
  corp=$(sed -n 's/.* corp: \([^ ]*\).*/\1/p' <<<"$covline")
  line=$(printf '%-12s executions %-10s exec/s %-7s cov %-5s ft %-6s corpus %-12s %4ss' "$h" "${execs:-?}" \
    "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$elapsed")
  # a harness's own summary at exit (fuzz_calibration: how many calibrations were accepted)
  own=$(grep -E "^fuzz_$h: [0-9]+ inputs" "$log" | tail -1 || true)
  [ -n "$own" ] && echo "   $own"
  if [ $rc -ne 0 ]; then
    echo 1 >"$work/failed_$h"
    repro=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)
    [ -n "$repro" ] || repro=$(ls -t "$artifacts"/* 2>/dev/null | head -1 || true)
    echo "$line  FAILED (exit $rc)"
    grep -E -A8 'ORACLE VIOLATION|WC_ASSERT FAILED|ERROR: AddressSanitizer|runtime error|ERROR: libFuzzer' "$log" | head -30 || true
    echo "fuzz: $h FAILED: reproducer ${repro:-<none written; see $log>}"
    [ -n "$repro" ] && echo "fuzz: replay with: $exe $repro"
    summary_line=("$line  FAILED: ${repro:-see $log}")
  else
    echo "$line  ok"
    summary_line=("$line  ok")
  fi
  printf '%s\n' "${summary_line[@]}" >"$work/summary_$h"
}

# FUZZ_PARALLEL harnesses at a time (default 1); each is one libFuzzer process
# on one core for its full time, so running two on two cores gives each the
# executions it has alone. The output of each is printed when it ends, whole.
parallel=${FUZZ_PARALLEL:-1}
case $parallel in ''|*[!0-9]*|0) echo "fuzz: FUZZ_PARALLEL must be a positive integer" >&2; exit 2 ;; esac
pending=("${harnesses[@]}")
while [ ${#pending[@]} -gt 0 ]; do
  batch=("${pending[@]:0:$parallel}")
  pending=("${pending[@]:$parallel}")
  if [ ${#batch[@]} -eq 1 ]; then
    fuzz_one "${batch[0]}"
  else
    pids=()
    for h in "${batch[@]}"; do fuzz_one "$h" >"$work/out_$h" 2>&1 & pids+=($!); done
    for i in "${!batch[@]}"; do wait "${pids[$i]}" || true; cat "$work/out_${batch[$i]}"; done
  fi
done
failed=0
summary=()
for h in "${harnesses[@]}"; do
  [ -f "$work/failed_$h" ] && failed=1
  [ -f "$work/summary_$h" ] && summary+=("$(cat "$work/summary_$h")")
  [ -f "$work/summary_$h" ] || { failed=1; summary+=("$(printf '%-12s' "$h") FAILED: no summary (the harness's run died)"); }
done

echo "== fuzz: summary"
printf '%s\n' "${summary[@]}"
exit $failed
