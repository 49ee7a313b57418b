#!/usr/bin/env bash
# Guest side of hil/vcan_run.sh (runs as root in the QEMU guest): bring up the
# vcan interface, restore the caller's environment and working directory, run
# the command and leave its exit code in STATE/rc for the host.
#   bash hil/vcan_guest.sh STATE IFACE            (STATE/env is written by vcan_run.sh)
#   bash hil/vcan_guest.sh --serve DIR IFACE      (one guest for many commands: vcan_run.sh --serve)
# Serving, it runs the jobs that hosts submit as DIR/jobs/<name>/ (env, then an
# empty `submitted`), one at a time in name order, each with the interface up
# again (a job may have set it down), its output in out/err and its exit code
# in rc; it stops once DIR/stop exists and no job is waiting.
set -euo pipefail
# shellcheck source=hil/guest_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/guest_lib.sh"
iface_up() {  # up already (IFF_UP in its flags): no modprobe and no ip, whose execs cost the guest a second a job
  local flags
  [ -r "/sys/class/net/$1/flags" ] && read -r flags < "/sys/class/net/$1/flags" && (( flags & 1 ))
}
up_iface() {
  iface_up "$1" && return 0
  modprobe vcan &&
    { ip link show "$1" >/dev/null 2>&1 || ip link add dev "$1" type vcan; } &&
    ip link set up "$1"
}
fail_iface() {
  echo "vcan_guest: could not bring up $1 in the guest kernel $(uname -r)" \
       "(it needs CONFIG_CAN_VCAN: modprobe vcan / ip link failed above)" >&2
}

export VCAN_IN_GUEST=1   # for hil/guest_lib.sh's guest_python: the tmpfs copy of the modules only in the guest

if [ "${1:-}" = --serve ]; then
  dir=$2 VCAN_IFACE=$3
  if ! up_iface "$VCAN_IFACE"; then fail_iface "$VCAN_IFACE"; echo 125 > "$dir/failed"; exit 125; fi
  : > "$dir/booted"
  while :; do
    job=""
    for j in "$dir"/jobs/*/; do
      [ -e "$j/submitted" ] && [ ! -e "$j/taken" ] && { job=${j%/}; break; }
    done
    if [ -z "$job" ]; then
      [ -e "$dir/stop" ] && exit 0
      pause 0.1
      continue
    fi
    : > "$job/taken"
    rc=0
    if ! up_iface "$VCAN_IFACE" 2>"$job/err"; then fail_iface "$VCAN_IFACE" 2>>"$job/err"; rc=125; else
      # shellcheck disable=SC1091
      ( source "$job/env"; cd "$VCAN_CWD"; "${VCAN_CMD[@]}" ) </dev/null >"$job/out" 2>"$job/err" || rc=$?
    fi
    echo "$rc" > "$job/rc.tmp" && mv "$job/rc.tmp" "$job/rc"
  done
fi

state=$1 VCAN_IFACE=$2
: > "$state/booted"
if ! up_iface "$VCAN_IFACE"; then
  fail_iface "$VCAN_IFACE"
  echo 125 > "$state/rc"; exit 125
fi
# shellcheck disable=SC1091
source "$state/env"
cd "$VCAN_CWD"
rc=0; "${VCAN_CMD[@]}" || rc=$?
echo "$rc" > "$state/rc"
exit "$rc"
