#!/usr/bin/env bash
# Run a command with a SocketCAN interface (vcan0) up; see DESIGN.md section 5.
#   bash hil/vcan_run.sh [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS...
#   bash hil/vcan_run.sh [--iface vcan0] [--slow FACTOR] --serve DIR      # one guest for many commands
# Native when the host kernel has vcan, otherwise inside a QEMU guest booted by
# virtme-ng (vng) on the kernel image in /boot. The guest sees the host file
# system read-only, except the repository, the working directory and each
# --rwdir DIR. CMD gets the caller's environment and working directory, and
# stdin is /dev/null in the guest. Exits with CMD's exit code.
#
# One boot for many commands (scripts/test.sh): `--serve DIR` boots one guest
# (the repository and /tmp writable) that runs, one at a time, the commands of
# every `vcan_run.sh -- CMD` whose environment has VCAN_SERVER=DIR, until DIR/stop
# exists. Such a command waits for its turn (the guest's CPU is not shared
# between two replays), then behaves as with its own guest: its output, its exit
# code. A --rwdir outside the repository and /tmp, or no server up: its own guest.
# --slow FACTOR (with --serve, a QEMU guest): before the first command the guest is slowed to 1/FACTOR of
# its speed by a CPU cgroup's quota, measured (hil/vcan_slow.sh; DIR/slow/factor says what was reached).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
iface=vcan0 force_vm=0 rwdirs=("$repo") serve="" slow=""
die() { echo "vcan_run: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --iface) [ $# -ge 2 ] || die "--iface needs a name"; iface=$2; shift 2 ;;
    --rwdir) [ -d "${2:-}" ] || die "--rwdir needs an existing directory"; rwdirs+=("$(cd "$2" && pwd)"); shift 2 ;;
    --vm) force_vm=1; shift ;;
    --slow) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--slow needs a whole factor (e.g. 3)"; slow=$2; force_vm=1; shift 2 ;;
    --serve) [ -n "${2:-}" ] || die "--serve needs a directory"; serve=$2; shift 2; break ;;
    --) shift; break ;;
    *) die "unknown option '$1'; usage: $0 [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS..." ;;
  esac
done
[ $# -gt 0 ] || [ -n "$serve" ] || die "no command given; usage: $0 [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS..."
start=$SECONDS
finish() { echo "vcan_run: finished in $((SECONDS - start)) s, exit code $1" >&2; exit "$1"; }

# 1. Native: the host kernel has vcan and the interface is (or can be made) up.
native_vcan() (
  export PATH=$PATH:/usr/sbin:/sbin
  modprobe vcan 2>/dev/null || true
  ip link show "$iface" >/dev/null 2>&1 || ip link add dev "$iface" type vcan 2>/dev/null || exit 1
  ip link show dev "$iface" up | grep -q . || ip link set up "$iface" 2>/dev/null
)
if [ "$force_vm" = 0 ] && native_vcan; then
  if [ -n "$serve" ]; then
    echo "vcan_run: $iface is up on the host kernel: no guest to serve (commands run natively)" >&2
    exit 0
  fi
  echo "vcan_run: $iface is up on the host kernel; running natively" >&2
  rc=0; "$@" || rc=$?
  finish "$rc"
fi

# 2a. A serving guest (VCAN_SERVER): submit the command as a job, wait for its turn and its end.
server_takes() {  # every writable directory the command needs is one the server shares
  local d
  for d in "${rwdirs[@]}" "$PWD"; do
    case $d/ in "$repo"/*|/tmp/*) ;; *) return 1 ;; esac
  done
}
if [ -z "$serve" ] && [ -n "${VCAN_SERVER:-}" ] && [ -f "$VCAN_SERVER/serving" ] && server_takes; then
  server=$VCAN_SERVER
  job=$(mktemp -d "$server/jobs/$(date +%s%N).XXXX" 2>/dev/null) || die "cannot create a job in $server/jobs"
  { for v in $(compgen -e); do
      case $v in PWD|OLDPWD|SHLVL|_|SHELLOPTS|BASHOPTS) ;; *) declare -p "$v" ;; esac
    done
    VCAN_CWD=$PWD VCAN_CMD=("$@")
    declare -p VCAN_CWD VCAN_CMD
  } > "$job/env"
  : > "$job/submitted"
  echo "vcan_run: job $(basename "$job") for the serving guest ($server): $*" >&2
  while [ ! -e "$job/rc" ]; do
    if [ -e "$server/failed" ] || ! kill -0 "$(cat "$server/serving")" 2>/dev/null; then
      die "the serving guest ($server) is gone; its log: $server/log"
    fi
    sleep 0.1
  done
  cat "$job/out"; cat "$job/err" >&2
  finish "$(cat "$job/rc")"
fi

# 2. QEMU guest via virtme-ng.
export PATH="$repo/.venv/bin:$PATH"
setup_hint="run 'bash scripts/setup.sh' (as root) to install it"
kernel=$(ls /boot/vmlinuz-* 2>/dev/null | sort -V | tail -n 1 || true)
[ -n "$kernel" ] || die "the host kernel has no vcan and there is no kernel image /boot/vmlinuz-* to boot in QEMU; $setup_hint (Debian package linux-image-amd64)"
[ -r "$kernel" ] || die "cannot read $kernel (run as root or make it readable)"
command -v vng >/dev/null || die "virtme-ng (vng) not found in $repo/.venv/bin; $setup_hint"
command -v qemu-system-x86_64 >/dev/null || die "qemu-system-x86_64 not found; $setup_hint (Debian package qemu-system-x86)"
bb=$(command -v busybox || true)
{ [ -n "$bb" ] && ! ldd "$bb" >/dev/null 2>&1; } || die "virtme-ng needs a statically linked busybox; $setup_hint (Debian package busybox-static)"

state=$(mktemp -d /tmp/vcan_run.XXXXXX)
cleanup() { # vng runs in its own session: stop it, virtme-run and QEMU together
  if [ -n "${vng_pid:-}" ]; then kill -- -"$vng_pid" 2>/dev/null || kill "$vng_pid" 2>/dev/null || true; fi
  if [ -n "${cat_pids:-}" ]; then kill $cat_pids 2>/dev/null || true; fi
  rm -rf "$state"
}
trap cleanup EXIT
cwd=$PWD
case $cwd/ in "$repo"/*) ;; /) ;; *) rwdirs+=("$cwd") ;; esac
{ # The caller's environment, the interface and the command, for vcan_guest.sh.
  for v in $(compgen -e); do
    case $v in PWD|OLDPWD|SHLVL|_|SHELLOPTS|BASHOPTS) ;; *) declare -p "$v" ;; esac
  done
  VCAN_CWD=$cwd VCAN_CMD=("$@")
  declare -p VCAN_CWD VCAN_CMD
} > "$state/env"
vng_args=(--run "$kernel" --disable-kvm --user root --cwd / --rwdir "$state")
for d in "${rwdirs[@]}"; do # vng splits its --rwdir on spaces: only plain paths
  if [[ $d =~ ^[A-Za-z0-9_+/.-]+$ ]]; then vng_args+=(--rwdir "$d")
  else echo "vcan_run: warning: '$d' stays read-only in the guest (vng cannot share paths with such characters)" >&2; fi
done
guest_cmd="bash $(printf %q "$repo/hil/vcan_guest.sh") $(printf %q "$state") $(printf %q "$iface")"
if [ -n "$serve" ]; then  # the guest serves DIR's jobs; /tmp writable for the jobs' outputs
  mkdir -p "$serve/jobs" || die "cannot create $serve/jobs"
  serve=$(cd "$serve" && pwd)
  vng_args+=(--rwdir /tmp)
  [[ $serve/ == /tmp/* || $serve/ == "$repo"/* ]] || vng_args+=(--rwdir "$serve")
  guest_cmd="bash $(printf %q "$repo/hil/vcan_guest.sh") --serve $(printf %q "$serve") $(printf %q "$iface")"
  if [ -n "$slow" ]; then
    . "$repo/hil/vcan_slow.sh"
    slow_queue "$serve" || die "cannot queue the slowing job in $serve"
  fi
fi
[ -z "$slow" ] || [ -n "$serve" ] || die "--slow goes with --serve"

# stdin: /dev/null (no tty needed). stdout/stderr: through fifos, because QEMU
# reopens /proc/self/fd/1 and 2 with O_TRUNC: a log file would be clobbered.
mkfifo "$state/out" "$state/err"
cat "$state/out" & cat_pids=$!
cat "$state/err" >&2 & cat_pids+=" $!"
setsid vng "${vng_args[@]}" --exec "$guest_cmd" </dev/null >"$state/out" 2>"$state/err" & vng_pid=$!
msg="vcan_run: booting QEMU guest $(basename "$kernel") (no CAN in host kernel)..."
booted=$state/booted
[ -z "$serve" ] || { booted=$serve/booted; echo "$vng_pid" > "$serve/serving"; }
while kill -0 "$vng_pid" 2>/dev/null && [ ! -e "$booted" ]; do
  t=$((SECONDS - start))
  if [ -t 2 ]; then printf '\r%s %d s' "$msg" "$t" >&2; elif [ $((t % 5)) = 0 ]; then echo "$msg $t s" >&2; fi
  sleep 1
done
[ -t 2 ] && printf '\n' >&2
[ -e "$booted" ] && echo "vcan_run: guest up after $((SECONDS - start)) s, running: ${serve:+serving $serve}$*" >&2
if [ -n "$slow" ]; then
  if slow_apply "$serve" "$slow" "$vng_pid"; then echo "vcan_run: $(cat "$serve/slow/factor")" >&2
  else echo "vcan_run: slowing the guest failed: $(cat "$serve/slow/factor" "$serve/slow/failed" 2>/dev/null)" >&2; fi
fi
vng_rc=0; wait "$vng_pid" || vng_rc=$?; vng_pid=; wait; cat_pids=
if [ -n "$slow" ]; then slow_release; fi
if [ -n "$serve" ]; then rm -f "$serve/serving"; finish "$vng_rc"; fi
if [ -s "$state/rc" ]; then finish "$(cat "$state/rc")"; fi
echo "vcan_run: the guest did not report an exit code (vng exit $vng_rc: QEMU failed to start," \
     "kernel panic, or the guest was killed). Boot log: PATH=$repo/.venv/bin:\$PATH" \
     "vng --verbose --run $kernel --disable-kvm --user root --exec true </dev/null" >&2
finish $((vng_rc ? vng_rc : 1))
