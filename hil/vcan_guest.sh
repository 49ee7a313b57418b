#!/usr/bin/env bash
# Guest side of hil/vcan_run.sh (runs as root in the QEMU guest): bring up the
# vcan interface, restore the caller's environment and working directory, run
# the command and leave its exit code in STATE/rc for the host.
#   bash hil/vcan_guest.sh STATE IFACE    (STATE/env is written by vcan_run.sh)
set -euo pipefail
state=$1 VCAN_IFACE=$2
: > "$state/booted"
if ! { modprobe vcan &&
       { ip link show "$VCAN_IFACE" >/dev/null 2>&1 || ip link add dev "$VCAN_IFACE" type vcan; } &&
       ip link set up "$VCAN_IFACE"; }; then
  echo "vcan_guest: could not bring up $VCAN_IFACE in the guest kernel $(uname -r)" \
       "(it needs CONFIG_CAN_VCAN: modprobe vcan / ip link failed above)" >&2
  echo 125 > "$state/rc"; exit 125
fi
# shellcheck disable=SC1091
source "$state/env"
cd "$VCAN_CWD"
rc=0; "${VCAN_CMD[@]}" || rc=$?
echo "$rc" > "$state/rc"
exit "$rc"
