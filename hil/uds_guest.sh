#!/usr/bin/env bash
# A service technician's UDS session against wc_tcu on a live SocketCAN interface (DESIGN 17), where the
# interface exists (natively, or inside the guest of hil/vcan_run.sh):
#   bash hil/uds_guest.sh DIR [--iface vcan0] [--tcu PATH]
# DIR holds input.log (the TCU's inputs, a hot clutch and a request timeout injected in each loop of it),
# restart.log (fault-free inputs), cal.img (the calibration image wc_tcu starts from) and secret.key (the
# device secret). wc_tcu --uds runs with the frame clock, the fault memory in DIR/dtc.img and the learned
# values in DIR/adapt.img; wc_canplay plays input.log in a loop, each period once the TCU's VfsCommand for
# the last one is on the bus and never faster than the log (DESIGN 5: a slower guest makes the session
# slower, never different), and records ClutchSensors, VfsCommand, AdaptationReport and the UDS frames;
# udsoncan over python-can-isotp runs the session (hil/uds_tester.py), waiting on the TCU's answers, never
# on the clock. Then wc_tcu starts again on the same dtc.img with restart.log playing (a restart: the fault
# memory from its image) and the tester's restart phase runs in DIR/restart. Output in DIR (and
# DIR/restart): result.json (the session), capture.log, stats.json and tcu.txt (wc_tcu), play.txt
# (wc_canplay), session.txt (the tester's messages); dtc.img, adapt.img. Exits with the sessions' code.
# The start-up and shut-down: hil/guest_lib.sh.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=hil/guest_lib.sh
source "$repo/hil/guest_lib.sh"
guest_init uds_guest
[ $# -ge 1 ] || guest_die "usage: $0 DIR [--iface vcan0] [--tcu PATH]"
work=$1; shift
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || guest_die "option '$1' needs a value"
  guest_option "$1" "$2" || guest_die "unknown option '$1'"
  shift 2
done
guest_check "$work" input.log restart.log cal.img secret.key
tester=(guest_python "$repo/hil/uds_tester.py" --secret "$dir/secret.key" --iface "$iface")
record=(--record capture.log --record-id 0x110 --record-id 0x120 --record-id 0x123 --record-id 0x7DF
        --record-id 0x7E1 --record-id 0x7E9)
# a short security delay (200 steps): the session waits it out at start, after a soft reset and after three
# wrong keys; DTCs age out after 5 fault-free cycles (the restart phase counts them with soft resets)
tcu_args=(--uds --secret-file "$dir/secret.key" --dtc-file "$dir/dtc.img" --serial WC0000004711
          --security-delay-ms 200 --dtc-aging-cycles 5 --calibration-image "$dir/cal.img" --adaptation-file "$dir/adapt.img"
          --theta-start 60 --stats-json stats.json)

guest_start_tcu "${tcu_args[@]}"
guest_start_player input.log "${record[@]}"
"${tester[@]}" --out result.json > session.txt 2>&1 || rc=$?
guest_stop
[ "$rc" -eq 0 ] || { echo "uds_guest: the UDS session failed (exit $rc), see $dir/session.txt" >&2; exit "$rc"; }

# The restart: the same fault memory image, fault-free inputs; the tester's restart phase
mkdir -p "$dir/restart" && cd "$dir/restart" || guest_die "cannot make $dir/restart"
guest_start_tcu "${tcu_args[@]}"
guest_start_player "$dir/restart.log" "${record[@]}"
"${tester[@]}" --phase restart --out result.json > session.txt 2>&1 || rc=$?
guest_stop
[ "$rc" -eq 0 ] || echo "uds_guest: the restart session failed (exit $rc), see $dir/restart/session.txt" >&2
exit "$rc"
