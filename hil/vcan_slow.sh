#!/usr/bin/env bash
# A serving vcan guest slowed to 1/FACTOR of its speed (DESIGN 5: a test in the guest passes or fails on
# what the code does, never on how fast the host is; issue 28). Used by hil/vcan_run.sh --slow FACTOR
# --serve DIR; the two sides:
#   host   (sourced by vcan_run.sh)  slow_queue DIR              before the boot: the calibration job first
#                                    slow_apply DIR FACTOR PID   after it: the guest's processes (QEMU) in
#                                                                a CPU cgroup whose quota makes the guest's
#                                                                benchmark FACTOR times slower (measured)
#   guest  bash hil/vcan_slow.sh --guest DIR   the calibration job: the benchmark unthrottled, then after
#                                              each quota the host sets, until the host says done
# The benchmark: wc_replay (the frame loop in-process, the TCU's own code) over the bundled 750 rpm log,
# three times: CPU-bound, the same instructions every time. The factor reached is written to DIR/slow
# (a line "slowed FACTOR x, quota Q us per 100000 us") and printed by vcan_run.sh.
set -uo pipefail

_slow_repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

if [ "${1:-}" = --guest ]; then   # the calibration job, in the guest
  # shellcheck source=hil/guest_lib.sh
  source "$_slow_repo/hil/guest_lib.sh"
  dir=$2
  replay="$_slow_repo/build/host-release/src/host/wc_replay"
  log="$_slow_repo/hil/logs/engagement_750rpm.log"
  bench() {  # wall time of the benchmark, in ms
    local t0 t1
    t0=$(date +%s%N)
    for _ in 1 2 3; do "$replay" "$log" --bench --calibration table1 >/dev/null || return 1; done
    t1=$(date +%s%N)
    echo $(((t1 - t0) / 1000000))
  }
  bench >/dev/null || { echo "vcan_slow: $replay failed" >&2; exit 1; }   # warm the page cache
  bench > "$dir/reference_ms" || exit 1
  for attempt in 1 2 3 4 5; do
    : > "$dir/request.$attempt"
    while [ ! -e "$dir/applied.$attempt" ]; do pause 0.1; done
    [ -e "$dir/done" ] && exit 0
    bench > "$dir/result.$attempt.tmp" && mv "$dir/result.$attempt.tmp" "$dir/result.$attempt" || exit 1
  done
  exit 0
fi

slow_queue() {  # DIR: the calibration job, named to be taken before every client's (theirs are dated)
  local serve=$1 job=$1/jobs/0000-slow
  mkdir -p "$job" "$serve/slow" || return 1
  { VCAN_CWD=/ VCAN_CMD=(bash "$_slow_repo/hil/vcan_slow.sh" --guest "$serve/slow"); declare -p VCAN_CWD VCAN_CMD; } \
    > "$job/env"
  : > "$job/submitted"
}

_slow_cgroup=""
_slow_set_quota() {  # QUOTA_US (per 100000 us)
  if [ -e "$_slow_cgroup/cpu.cfs_quota_us" ]; then
    echo 100000 > "$_slow_cgroup/cpu.cfs_period_us" && echo "$1" > "$_slow_cgroup/cpu.cfs_quota_us"
  else
    echo "$1 100000" > "$_slow_cgroup/cpu.max"
  fi
}

slow_apply() {  # DIR FACTOR VNG_PID: runs until the factor is reached (or given up, said so)
  local serve=$1 factor=$2 pid=$3 dir=$1/slow reference result quota=100000 attempt p reached=0
  if [ -d /sys/fs/cgroup/cpu ] && [ -w /sys/fs/cgroup/cpu ]; then
    _slow_cgroup=/sys/fs/cgroup/cpu/vcan_slow.$$
  elif grep -qw cpu /sys/fs/cgroup/cgroup.controllers 2>/dev/null; then
    _slow_cgroup=/sys/fs/cgroup/vcan_slow.$$
  else
    echo "vcan_slow: no CPU cgroup to limit the guest with (cgroup v1 cpu or v2 cpu controller, as root)" > "$dir/failed"
    : > "$dir/done"; : > "$dir/applied.1"; return 1
  fi
  mkdir -p "$_slow_cgroup" || { echo "vcan_slow: cannot create $_slow_cgroup" > "$dir/failed"; : > "$dir/done"; : > "$dir/applied.1"; return 1; }
  for attempt in 1 2 3 4 5; do
    while [ ! -e "$dir/request.$attempt" ]; do kill -0 "$pid" 2>/dev/null || return 1; sleep 0.1; done
    reference=$(cat "$dir/reference_ms")
    if [ "$attempt" = 1 ]; then  # a first guess: the guest ran on about one CPU's time
      quota=$((100000 / factor))
    fi
    # every process of the guest's session (vng, QEMU and its threads) into the cgroup, then the quota
    for p in $(ps -o pid= -s "$pid"); do echo "$p" > "$_slow_cgroup/cgroup.procs" 2>/dev/null; done
    _slow_set_quota "$quota"
    : > "$dir/applied.$attempt"
    while [ ! -e "$dir/result.$attempt" ]; do kill -0 "$pid" 2>/dev/null || return 1; sleep 0.1; done
    result=$(cat "$dir/result.$attempt")
    # slowed by result/reference; reached when at least FACTOR (to 5 %: the benchmark's noise)
    if [ $((result * 100)) -ge $((reference * factor * 95)) ]; then reached=1; break; fi
    quota=$((quota * result / (reference * factor)))   # the quota that would have given FACTOR
    [ "$quota" -ge 1000 ] || quota=1000
  done
  printf 'slowed %s.%02d x (benchmark %s ms unthrottled, %s ms slowed), quota %s us per 100000 us%s\n' \
    $((result / reference)) $((result * 100 / reference % 100)) "$reference" "$result" "$quota" \
    "$([ "$reached" = 1 ] || echo ", FACTOR $factor NOT reached")" > "$dir/factor"
  : > "$dir/done"; : > "$dir/applied.$((attempt + 1))"
  [ "$reached" = 1 ]
}

slow_release() {  # the cgroup, once the guest is gone
  [ -n "$_slow_cgroup" ] && rmdir "$_slow_cgroup" 2>/dev/null
  return 0
}
