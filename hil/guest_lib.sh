# Shell helpers for what runs inside the emulated guest (sourced by hil/vcan_guest.sh, replay_guest.sh,
# uds_guest.sh, xcp_guest.sh, vcan_slow.sh). In the guest every exec costs 0.2-1 s of emulated CPU, which
# is the host's CPU too: a wait is a bash builtin, never a `sleep` or a `grep` in a loop.

# pause SECONDS: sleep without a process (read -t on a FIFO nothing writes, on the guest's own tmpfs: a
# FIFO on a 9p share is not one); `sleep` where no FIFO can be made
pause() {
  if [ -z "${_pause_fd:-}" ]; then
    local fifo
    fifo=$(mktemp -u /dev/shm/pause.XXXXXX) && mkfifo "$fifo" 2>/dev/null && exec {_pause_fd}<>"$fifo"
    rm -f "$fifo"
    _pause_fd=${_pause_fd:-none}
  fi
  if [ "$_pause_fd" = none ]; then sleep "$1"; else read -r -t "$1" -u "$_pause_fd" _ || true; fi
}

# file_has FILE TEXT: FILE holds TEXT (read by the shell itself)
file_has() {
  local content
  [ -r "$1" ] || return 1
  content=$(<"$1")
  [[ $content == *"$2"* ]]
}

# await_line FILE TEXT PID: wait until FILE holds TEXT (a program's "I am ready" line) or PID is gone;
# returns 0 once it holds it (an event, not a time)
await_line() {
  while kill -0 "$3" 2>/dev/null && ! file_has "$1" "$2"; do pause 0.05; done
  file_has "$1" "$2"
}

# guest_python ARG...: the project's Python (.venv) with the guest's tmpfs copy of the modules the tools
# import (hil/guest_pylib.py; .venv/guest-pylib.tar, written by scripts/setup.sh) first on PYTHONPATH, so
# their imports need no 9p (tens of seconds of the emulated CPU a start); unpacked once a boot, again when the
# tar is newer. Natively (no VCAN_IN_GUEST from hil/vcan_guest.sh) or without the tar (setup.sh not run
# since): the Python as it is.
guest_python() {
  local root tar lib=/dev/shm/wc-pylib
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  tar=$root/.venv/guest-pylib.tar
  if [ -n "${VCAN_IN_GUEST:-}" ] && [ -r "$tar" ] && [ -d /dev/shm ] && { { [ -e "$lib/.unpacked" ] && ! [ "$tar" -nt "$lib/.unpacked" ]; } ||
       { rm -rf "$lib" && mkdir -p "$lib" && tar -xf "$tar" -C "$lib" && : > "$lib/.unpacked"; }; }; then
    PYTHONPATH="$lib${PYTHONPATH:+:$PYTHONPATH}" "$root/.venv/bin/python" "$@"
  else
    "$root/.venv/bin/python" "$@"
  fi
}

# ---- The start-up and shut-down of a session against wc_tcu (hil/uds_guest.sh, hil/xcp_guest.sh): the
# common options, the inputs and programs checked, wc_tcu started (frame clock) and awaited, the player
# started, and at the end both stopped and waited for. Sets and reads the caller's globals: guest_name,
# iface, tcu, player, dir, tcu_pid, play, rc.

# guest_init NAME: the session's name (messages) and the common options' defaults
guest_init() {
  guest_name=$1 iface=vcan0 tcu="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/build/host-release/src/port/wc_tcu"
  rc=0
}

guest_die() { echo "$guest_name: $*" >&2; exit 2; }

# guest_option OPTION VALUE: takes a common option (--iface NAME, --tcu PATH); 1 when OPTION is not one
guest_option() {
  case $1 in
    --iface) iface=$2 ;;
    --tcu) tcu=$2 ;;
    *) return 1 ;;
  esac
}

# guest_check DIR FILE...: dir (absolute) holds every FILE; wc_tcu and wc_canplay (player) are built; cd dir
guest_check() {
  dir=$(cd "$1" && pwd) || guest_die "no directory $1"
  shift
  player=$(dirname "$tcu")/wc_canplay
  local f program
  for f in "$@"; do [ -r "$dir/$f" ] || guest_die "cannot read $dir/$f"; done
  for program in "$tcu" "$player"; do
    [ -x "$program" ] || guest_die "$program not built (cmake --preset host-release && cmake --build --preset host-release)"
  done
  cd "$dir" || guest_die "cannot enter $dir"
}

# guest_start_tcu ARG...: wc_tcu on iface with the frame clock and ARGs in the background (stderr in
# tcu.txt, pid in tcu_pid), awaited until it says it runs (an event, not a time)
guest_start_tcu() {
  "$tcu" --iface "$iface" --clock frame "$@" 2> tcu.txt &
  tcu_pid=$!
  await_line tcu.txt "clock frame" "$tcu_pid" || { cat tcu.txt >&2; guest_die "wc_tcu did not start"; }
}

# guest_start_player LOG ARG...: wc_canplay plays LOG in a loop on iface, each period once wc_tcu's
# VfsCommand for the last one is on the bus and never faster than the log (DESIGN 5: a slower guest makes
# the session slower, never different); it stops wc_tcu when it stops; ARGs add to it (--record ...).
# stderr in play.txt, pid in play.
guest_start_player() {
  local log=$1
  shift
  "$player" "$log" --iface "$iface" --loops 0 --pace log --stop-pid "$tcu_pid" "$@" 2> play.txt &
  play=$!
}

# guest_stop: the player stopped (it stops wc_tcu, which writes its files, and records the last frames),
# both waited for, play.txt shown; rc keeps the session's code, else the first program's failure
guest_stop() {
  kill -TERM "$play" 2>/dev/null
  local play_rc=0 tcu_rc=0
  wait "$play" || play_rc=$?
  wait "$tcu_pid" || tcu_rc=$?
  cat play.txt >&2
  if [ "$play_rc" -ne 0 ]; then
    echo "$guest_name: wc_canplay failed (exit $play_rc), see $PWD/play.txt" >&2
    [ "$rc" -ne 0 ] || rc=$play_rc
  fi
  if [ "$tcu_rc" -ne 0 ]; then
    echo "$guest_name: wc_tcu failed (exit $tcu_rc), see $PWD/tcu.txt" >&2
    [ "$rc" -ne 0 ] || rc=$tcu_rc
  fi
}
