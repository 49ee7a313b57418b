#!/usr/bin/env bash
# A calibration tool's XCP session against wc_tcu on a live SocketCAN interface (DESIGN 13), where the
# interface exists (natively, or inside the guest of hil/vcan_run.sh):
#   bash hil/xcp_guest.sh DIR [--iface vcan0] [--tcu PATH] [--daq-seconds S]
# DIR holds input.log (the TCU's inputs, played in a loop by canplayer), cal.img (the calibration image
# wc_tcu starts from) and plan.json (the A2L's addresses and the image's bytes there,
# tools/wetclutch/hil/xcp_session.py). While wc_tcu --xcp runs (frame clock) and candump captures
# ClutchSensors, VfsCommand and the XCP frames, pyxcp runs the session (hil/xcp_master.py). Output in DIR: result.json (the session), capture.log,
# stats.json and tcu.txt (wc_tcu), session.txt (the master's messages). Exits with the session's code.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
die() { echo "xcp_guest: $*" >&2; exit 2; }
[ $# -ge 1 ] || die "usage: $0 DIR [--iface vcan0] [--tcu PATH] [--daq-seconds S]"
dir=$(cd "$1" && pwd) || die "no directory $1"; shift
iface=vcan0 tcu="$repo/build/host-release/src/port/wc_tcu" daq_seconds=5
while [ $# -gt 0 ]; do
  case $1 in
    --iface) iface=$2; shift 2 ;;
    --tcu) tcu=$2; shift 2 ;;
    --daq-seconds) daq_seconds=$2; shift 2 ;;
    *) die "unknown option '$1'" ;;
  esac
done
for f in input.log cal.img plan.json; do [ -r "$dir/$f" ] || die "cannot read $dir/$f"; done
[ -x "$tcu" ] || die "TCU program $tcu not built (cmake --preset host-release && cmake --build --preset host-release)"
# Socket buffers: the master's Python may fall seconds behind 8 DAQ frames a millisecond on an emulated
# CPU; the frames wait in its socket instead of being dropped (where the system permits it).
sysctl -q -w net.core.rmem_max=67108864 net.core.rmem_default=67108864 2>/dev/null || true
cd "$dir"
. "$repo/hil/capture.sh"
capture_start capture.log "$iface,110:7FF,120:7FF,7F0:7FE"   # ClutchSensors, VfsCommand, XCP
"$tcu" --iface "$iface" --clock frame --xcp --calibration-image cal.img --theta-start 60 --idle-exit 1 \
  --stats-json stats.json 2> tcu.txt &
tcu_pid=$!
sleep 0.3
canplayer -l i -I input.log "$iface=$iface" &
play=$!
rc=0
"$repo/.venv/bin/python" "$repo/hil/xcp_master.py" --plan plan.json --out result.json --iface "$iface" \
  --daq-seconds "$daq_seconds" > session.txt 2>&1 || rc=$?
kill "$play" 2>/dev/null; wait "$play" 2>/dev/null
tcu_rc=0; wait "$tcu_pid" || tcu_rc=$?
if [ "$tcu_rc" -ne 0 ]; then echo "xcp_guest: wc_tcu failed (exit $tcu_rc), see $dir/tcu.txt" >&2; [ "$rc" -ne 0 ] || rc=$tcu_rc; fi
capture_stop 600
[ "$rc" -eq 0 ] || echo "xcp_guest: the XCP session failed (exit $rc), see $dir/session.txt" >&2
exit "$rc"
