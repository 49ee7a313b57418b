#!/usr/bin/env bash
# A service technician's UDS session against wc_tcu on a live SocketCAN interface (DESIGN 17), where the
# interface exists (natively, or inside the guest of hil/vcan_run.sh):
#   bash hil/uds_guest.sh DIR [--iface vcan0] [--tcu PATH]
# DIR holds input.log (the TCU's inputs, a request timeout injected in it), cal.img (the calibration image
# wc_tcu starts from) and secret.key (the device secret). wc_tcu --uds runs with the frame clock and the
# fault memory in DIR/dtc.img; wc_canplay plays input.log in a loop, each period once the TCU's VfsCommand
# for the last one is on the bus and never faster than the log (DESIGN 5: a slower guest makes the session
# slower, never different), and records ClutchSensors, VfsCommand, AdaptationReport and the UDS frames;
# udsoncan over python-can-isotp runs the session (hil/uds_tester.py), waiting on the TCU's answers, never
# on the clock. Output in DIR: result.json (the session), capture.log, stats.json and tcu.txt (wc_tcu),
# play.txt (wc_canplay), session.txt (the tester's messages), dtc.img. Exits with the session's code.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=hil/guest_lib.sh
source "$repo/hil/guest_lib.sh"
die() { echo "uds_guest: $*" >&2; exit 2; }
[ $# -ge 1 ] || die "usage: $0 DIR [--iface vcan0] [--tcu PATH]"
dir=$(cd "$1" && pwd) || die "no directory $1"; shift
iface=vcan0 tcu="$repo/build/host-release/src/port/wc_tcu"
while [ $# -gt 0 ]; do
  case $1 in
    --iface) iface=$2; shift 2 ;;
    --tcu) tcu=$2; shift 2 ;;
    *) die "unknown option '$1'" ;;
  esac
done
player=$(dirname "$tcu")/wc_canplay
for f in input.log cal.img secret.key; do [ -r "$dir/$f" ] || die "cannot read $dir/$f"; done
for program in "$tcu" "$player"; do
  [ -x "$program" ] || die "$program not built (cmake --preset host-release && cmake --build --preset host-release)"
done
cd "$dir"
# a short security delay (200 steps): the session waits it out twice, at start and after three wrong keys
"$tcu" --iface "$iface" --clock frame --uds --secret-file secret.key --dtc-file dtc.img --serial WC0000004711 \
  --security-delay-ms 200 --calibration-image cal.img --theta-start 60 --stats-json stats.json 2> tcu.txt &
tcu_pid=$!
await_line tcu.txt "clock frame" "$tcu_pid" || { cat tcu.txt >&2; die "wc_tcu did not start"; }
"$player" input.log --iface "$iface" --loops 0 --pace log --stop-pid "$tcu_pid" --record capture.log \
  --record-id 0x110 --record-id 0x120 --record-id 0x123 --record-id 0x7DF --record-id 0x7E1 --record-id 0x7E9 \
  2> play.txt &
play=$!
rc=0
"$repo/.venv/bin/python" "$repo/hil/uds_tester.py" --secret secret.key --out result.json --iface "$iface" \
  > session.txt 2>&1 || rc=$?
kill -TERM "$play" 2>/dev/null   # the player stops, then stops wc_tcu (which writes dtc.img) and records its last frames
play_rc=0; wait "$play" || play_rc=$?
tcu_rc=0; wait "$tcu_pid" || tcu_rc=$?
cat play.txt >&2
if [ "$play_rc" -ne 0 ]; then echo "uds_guest: wc_canplay failed (exit $play_rc), see $dir/play.txt" >&2; [ "$rc" -ne 0 ] || rc=$play_rc; fi
if [ "$tcu_rc" -ne 0 ]; then echo "uds_guest: wc_tcu failed (exit $tcu_rc), see $dir/tcu.txt" >&2; [ "$rc" -ne 0 ] || rc=$tcu_rc; fi
[ "$rc" -eq 0 ] || echo "uds_guest: the UDS session failed (exit $rc), see $dir/session.txt" >&2
exit "$rc"
