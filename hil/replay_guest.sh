#!/usr/bin/env bash
# Replay a candump -L log to the TCU program on a live SocketCAN interface and
# record the bus. Runs where the interface exists (natively or inside the VM
# started by hil/vcan_run.sh):
#   bash hil/replay_guest.sh LOG OUTDIR [--iface vcan0] [--frame-runs N] [--timer-runs N] [--tcu PATH]
#                            [--calibration NAME] [--shift NAME] [--bench] [--theta-start DEGC]
#                            [--calibration-image FILE --image-runs N] [--window N]
# Each run: wc_tcu starts, then wc_canplay plays LOG and records the bus (what it
# sends and what it receives, its socket bound before the first frame) and at the
# end stops wc_tcu, recording until it has exited.
#   frame clock (one step per ClutchSensors frame): wc_canplay sends each period's
#     frames once the TCU's VfsCommand for the one WINDOW periods back is on the bus
#     (lockstep, DESIGN 5): a slower guest makes the run slower, never different;
#     the TCU steps on each ClutchSensors frame in order, so its frames do not
#     depend on the window, which only saves the guest a wake-up each period
#   timer clock (fixed period): wc_canplay at the log's own pace (canplayer's), so
#     what it shows depends on the guest keeping real time: its figures are printed,
#     never asserted
# Output per run: OUTDIR/<clock><n>.log (the record), .json (wc_tcu statistics),
# .txt (wc_tcu's stderr), .play.txt (wc_canplay's); --image-runs: frame-clock runs
# with wc_tcu --calibration-image FILE instead of --calibration, OUTDIR/image<n>.*.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
die() { echo "replay_guest: $*" >&2; exit 2; }
# shellcheck source=hil/guest_lib.sh
source "$repo/hil/guest_lib.sh"
[ $# -ge 2 ] || die "usage: $0 LOG OUTDIR [--iface vcan0] [--frame-runs N] [--timer-runs N] [--tcu PATH] [--calibration NAME] [--shift NAME] [--bench] [--theta-start DEGC]"
log=$1 out=$2; shift 2
iface=vcan0 frame_runs=2 timer_runs=1 tcu="$repo/build/host-release/src/port/wc_tcu" calibration=table1
player="$repo/build/host-release/src/port/wc_canplay"
bench=() theta=() shift_opt=() image="" image_runs=0 window=16
while [ $# -gt 0 ]; do
  case $1 in
    --iface) iface=$2; shift 2 ;;
    --frame-runs) frame_runs=$2; shift 2 ;;
    --timer-runs) timer_runs=$2; shift 2 ;;
    --tcu) tcu=$2; player=$(dirname "$2")/wc_canplay; shift 2 ;;
    --calibration) calibration=$2; shift 2 ;;
    --shift) shift_opt=(--shift "$2"); shift 2 ;;   # shift control with this compiled-in shift calibration
    --bench) bench=(--bench); shift ;;   # wc_tcu uses BenchMeasurement (the paper's validation)
    --theta-start) theta=(--theta-start "$2"); shift 2 ;;   # the observer's start (the log's first oil temperature)
    --calibration-image) image=$2; shift 2 ;;
    --image-runs) image_runs=$2; shift 2 ;;
    --window) window=$2; shift 2 ;;   # wc_canplay --window (1: strict lockstep)
    *) die "unknown option '$1'" ;;
  esac
done
[ -r "$log" ] || die "cannot read log $log"
for program in "$tcu" "$player"; do
  [ -x "$program" ] || die "$program not built (cmake --preset host-release && cmake --build --preset host-release)"
done
[ -d "$out" ] || mkdir -p "$out"

one_run() { # clock name [calibration options]
  local clock=$1 name=$2 tcu_pid rc=0 play_rc=0
  shift 2
  local cal=("$@") pace=(--answer-id none --pace log)
  [ ${#cal[@]} -gt 0 ] || cal=(--calibration "$calibration" "${shift_opt[@]}")
  [ "$clock" = frame ] && pace=(--window "$window")
  "$tcu" --iface "$iface" --clock "$clock" "${cal[@]}" "${bench[@]}" "${theta[@]}" --stats-json "$out/$name.json" \
    2>"$out/$name.txt" &
  tcu_pid=$!
  trap 'kill "$tcu_pid" 2>/dev/null' EXIT   # a run that dies leaves no TCU answering on the bus
  # started once it says so (or gone): an event, not a time
  await_line "$out/$name.txt" "clock $clock" "$tcu_pid" || { cat "$out/$name.txt" >&2; die "wc_tcu did not start ($name)"; }
  "$player" "$log" --iface "$iface" "${pace[@]}" --record "$out/$name.log" --stop-pid "$tcu_pid" \
    2>"$out/$name.play.txt" || play_rc=$?
  [ "$play_rc" = 0 ] || kill "$tcu_pid" 2>/dev/null || true
  wait "$tcu_pid" || rc=$?
  [ "$play_rc" = 0 ] || { cat "$out/$name.play.txt" "$out/$name.txt" >&2; die "wc_canplay failed with $play_rc ($name)"; }
  trap - EXIT
  [ "$rc" = 0 ] || { cat "$out/$name.txt" >&2; die "wc_tcu exited with $rc ($name)"; }
  echo "replay_guest: $name: $(<"$out/$name.play.txt")" >&2
}
for ((i = 1; i <= frame_runs; i++)); do one_run frame "frame$i"; done
for ((i = 1; i <= timer_runs; i++)); do one_run timer "timer$i"; done
if [ "$image_runs" -gt 0 ]; then
  [ -r "$image" ] || die "--image-runs needs a readable --calibration-image"
  for ((i = 1; i <= image_runs; i++)); do one_run frame "image$i" --calibration-image "$image"; done
fi
