# Bus capture for the guest scripts (sourced by hil/replay_guest.sh and hil/xcp_guest.sh):
#   capture_start FILE candump-args...    candump -L into a local tmpfs (/dev/shm, else a temporary
#                                         directory); FILE is where it ends up
#   capture_stop [POLLS]                  once the capture has stopped growing (polled every 0.25 s, at
#                                         most POLLS times, default 120), stop candump, move it to FILE
# In the QEMU guest the output directories are the host's file system over 9p, where every line costs a
# round trip: candump written there lagged the bus by seconds (one replay alone: 9.1 s, 6.9 s on tmpfs),
# and stopped early it drops what it still queues.
capture_dir=$(mktemp -d /dev/shm/capture.XXXXXX 2>/dev/null || mktemp -d)
trap 'rm -rf "$capture_dir"' EXIT
capture_pid="" capture_dest=""

capture_start() {
  capture_dest=$1
  shift
  candump -L -r 8388608 "$@" >"$capture_dir/capture.log" &
  capture_pid=$!
}

capture_stop() {
  local size=-1 new
  for _ in $(seq "${1:-120}"); do
    sleep 0.25
    new=$(stat -c %s "$capture_dir/capture.log")
    [ "$new" = "$size" ] && break
    size=$new
  done
  kill "$capture_pid" 2>/dev/null || true
  wait "$capture_pid" 2>/dev/null || true
  mv "$capture_dir/capture.log" "$capture_dest"
}
