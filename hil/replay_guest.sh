#!/usr/bin/env bash
# Replay a candump -L log to the TCU program on a live SocketCAN interface and
# capture the bus. Runs where the interface exists (natively or inside the VM
# started by hil/vcan_run.sh):
#   bash hil/replay_guest.sh LOG OUTDIR [--iface vcan0] [--log-iface NAME]
#                            [--frame-runs N] [--timer-runs N] [--tcu PATH] [--calibration NAME] [--bench]
#                            [--theta-start DEGC] [--calibration-image FILE --image-runs N]
# Each run: candump -L captures the bus, wc_tcu runs (frame clock: one step per
# ClutchSensors frame; timer clock: fixed period), canplayer plays LOG with its
# timing, wc_tcu stops when the bus has been idle for 1 s. Output per run:
# OUTDIR/<clock><n>.log (capture), .json (wc_tcu statistics), .txt (wc_tcu stderr); --image-runs: frame-clock
# runs with wc_tcu --calibration-image FILE instead of --calibration, OUTDIR/image<n>.*.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
die() { echo "replay_guest: $*" >&2; exit 2; }
[ $# -ge 2 ] || die "usage: $0 LOG OUTDIR [--iface vcan0] [--log-iface NAME] [--frame-runs N] [--timer-runs N] [--tcu PATH] [--calibration NAME] [--bench] [--theta-start DEGC]"
log=$1 out=$2; shift 2
iface=vcan0 log_iface="" frame_runs=2 timer_runs=1 tcu="$repo/build/host-release/src/port/wc_tcu" calibration=table1
bench=() theta=() image="" image_runs=0
while [ $# -gt 0 ]; do
  case $1 in
    --iface) iface=$2; shift 2 ;;
    --log-iface) log_iface=$2; shift 2 ;;
    --frame-runs) frame_runs=$2; shift 2 ;;
    --timer-runs) timer_runs=$2; shift 2 ;;
    --tcu) tcu=$2; shift 2 ;;
    --calibration) calibration=$2; shift 2 ;;
    --bench) bench=(--bench); shift ;;   # wc_tcu uses BenchMeasurement (the paper's validation)
    --theta-start) theta=(--theta-start "$2"); shift 2 ;;   # the observer's start (the log's first oil temperature)
    --calibration-image) image=$2; shift 2 ;;
    --image-runs) image_runs=$2; shift 2 ;;
    *) die "unknown option '$1'" ;;
  esac
done
[ -r "$log" ] || die "cannot read log $log"
[ -x "$tcu" ] || die "TCU program $tcu not built (cmake --preset host-release && cmake --build --preset host-release)"
for tool in candump canplayer; do command -v $tool >/dev/null || die "$tool not found (Debian package can-utils; bash scripts/setup.sh)"; done
[ -n "$log_iface" ] || log_iface=$(awk 'NF>=3 {print $2; exit}' "$log")
pin=""; command -v taskset >/dev/null && pin="taskset -c 0"
mkdir -p "$out"
. "$repo/hil/capture.sh"

one_run() { # clock name [calibration options]
  local clock=$1 name=$2 tcu_pid rc=0
  shift 2
  local cal=("$@")
  [ ${#cal[@]} -gt 0 ] || cal=(--calibration "$calibration")
  capture_start "$out/$name.log" "$iface"
  "$tcu" --iface "$iface" --clock "$clock" "${cal[@]}" "${bench[@]}" "${theta[@]}" --idle-exit 1.0 --stats-json "$out/$name.json" 2>"$out/$name.txt" &
  tcu_pid=$!
  for _ in $(seq 100); do grep -q "clock $clock" "$out/$name.txt" 2>/dev/null && break; sleep 0.05; done
  grep -q "clock $clock" "$out/$name.txt" || { cat "$out/$name.txt" >&2; kill "$capture_pid" $tcu_pid 2>/dev/null; die "wc_tcu did not start"; }
  sleep 0.2  # candump's socket is bound by now too
  # One CPU for the sender: vcan queues each frame on the sending CPU's backlog,
  # so a canplayer that migrates between CPUs can have two frames of the same
  # millisecond (BenchMeasurement, ClutchSensors) delivered out of order, and
  # the frame clock would step on a different bench value (seen in the
  # emulated guest under load). Pinned, the delivery order is the log's.
  $pin canplayer -I "$log" "$iface=$log_iface"
  wait $tcu_pid || rc=$?
  capture_stop
  [ "$rc" = 0 ] || { cat "$out/$name.txt" >&2; die "wc_tcu exited with $rc ($name)"; }
  echo "replay_guest: $name: $(grep -c . "$out/$name.log") frames captured" >&2
}
for i in $(seq "$frame_runs"); do one_run frame "frame$i"; done
for i in $(seq "$timer_runs"); do one_run timer "timer$i"; done
if [ "$image_runs" -gt 0 ]; then
  [ -r "$image" ] || die "--image-runs needs a readable --calibration-image"
  for i in $(seq "$image_runs"); do one_run frame "image$i" --calibration-image "$image"; done
fi
