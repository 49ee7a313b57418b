# Shell helpers for what runs inside the emulated guest (sourced by hil/vcan_guest.sh, replay_guest.sh,
# xcp_guest.sh, vcan_slow.sh). In the guest every exec costs 0.2-1 s of emulated CPU, which is the host's
# CPU too: a wait is a bash builtin, never a `sleep` or a `grep` in a loop.

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
