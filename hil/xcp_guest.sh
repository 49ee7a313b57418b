#!/usr/bin/env bash
# A calibration tool's XCP session against wc_tcu on a live SocketCAN interface (DESIGN 13), where the
# interface exists (natively, or inside the guest of hil/vcan_run.sh):
#   bash hil/xcp_guest.sh DIR [--iface vcan0] [--tcu PATH] [--daq-samples N]
# DIR holds input.log (the TCU's inputs), cal.img (the calibration image wc_tcu starts from), plan.json
# (the A2L's addresses and the image's bytes there, tools/wetclutch/hil/xcp_session.py) and secret.bin (the
# device secret: wc_tcu --secret-file locks CAL/PAG behind XCP seed & key, the master computes the key). wc_tcu --xcp runs
# with the frame clock; wc_canplay plays input.log in a loop, each period once the TCU's VfsCommand for the
# last one is on the bus, never faster than the log, only as far as the master needs steps (to its
# SETTLE_STEPS from the start, then held between its waits) and, during DAQ, never more than a few hundred
# steps ahead of its decoding (DESIGN 5: a slower guest makes the session slower, never different),
# and records ClutchSensors, VfsCommand and the XCP frames; pyxcp runs the session
# (hil/xcp_master.py), waiting on the TCU's steps, never on the clock. Output in DIR: result.json (the
# session), capture.log, stats.json and tcu.txt (wc_tcu), play.txt (wc_canplay), session.txt (the master's
# messages). Exits with the session's code. The start-up and shut-down: hil/guest_lib.sh.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=hil/guest_lib.sh
source "$repo/hil/guest_lib.sh"
guest_init xcp_guest
[ $# -ge 1 ] || guest_die "usage: $0 DIR [--iface vcan0] [--tcu PATH] [--daq-samples N]"
work=$1; shift
daq_samples=5000
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || guest_die "option '$1' needs a value"
  case $1 in
    --daq-samples) daq_samples=$2 ;;
    *) guest_option "$1" "$2" || guest_die "unknown option '$1'" ;;
  esac
  shift 2
done
guest_check "$work" input.log cal.img plan.json secret.bin
# Socket buffers: the master's Python may fall behind 8 DAQ frames a step on an emulated CPU; the frames
# wait in its socket instead of being dropped (where the system permits it).
sysctl -q -w net.core.rmem_max=67108864 net.core.rmem_default=67108864 2>/dev/null || true
# the master's flow control of the inputs during DAQ, on the guest's own tmpfs (a FIFO over 9p is not one)
fifo_dir=$(mktemp -d /dev/shm/xcp.XXXXXX 2>/dev/null || mktemp -d)
trap 'rm -rf "$fifo_dir"' EXIT
mkfifo "$fifo_dir/limit"
guest_start_tcu --xcp --secret-file secret.bin --calibration-image cal.img --theta-start 60 --stats-json stats.json
# the player and the master on one CPU (--cpu 0): a raw command reaches the TCU in order with the inputs
guest_start_player input.log --cpu 0 --limit-fifo "$fifo_dir/limit" --record capture.log \
  --record-id 0x110 --record-id 0x120 --record-id 0x7F0 --record-id 0x7F1
# The inputs held from the start at the step the master downloads the new margin at the earliest (its
# SETTLE_STEPS, read by the shell): the TCU steps there while the master's Python starts, then waits for it
# (the master lets the inputs through as far as it needs steps). The FIFO kept open (read-write: no wait for
# the player's open) until the end, so the line stays in it until the player reads it.
[[ $(<"$repo/hil/xcp_master.py") =~ SETTLE_STEPS\ =\ ([0-9]+) ]] || guest_die "no SETTLE_STEPS in hil/xcp_master.py"
exec {hold_fd}<>"$fifo_dir/limit"
echo "${BASH_REMATCH[1]}" >&"$hold_fd"
guest_python "$repo/hil/xcp_master.py" --plan plan.json --out result.json --iface "$iface" --secret-file secret.bin \
  --daq-samples "$daq_samples" --limit-fifo "$fifo_dir/limit" --cpu 0 > session.txt 2>&1 || rc=$?
guest_stop
exec {hold_fd}>&-
[ "$rc" -eq 0 ] || echo "xcp_guest: the XCP session failed (exit $rc), see $dir/session.txt" >&2
exit "$rc"
