#!/usr/bin/env bash
# Run a command with a SocketCAN interface (vcan0) up; see DESIGN.md section 5.
#   bash hil/vcan_run.sh [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS...
# Native when the host kernel has vcan, otherwise inside a QEMU guest booted by
# virtme-ng (vng) on the kernel image in /boot. The guest sees the host file
# system read-only, except the repository, the working directory and each
# --rwdir DIR. CMD gets the caller's environment and working directory, and
# stdin is /dev/null in the guest. Exits with CMD's exit code.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
iface=vcan0 force_vm=0 rwdirs=("$repo")
die() { echo "vcan_run: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --iface) [ $# -ge 2 ] || die "--iface needs a name"; iface=$2; shift 2 ;;
    --rwdir) [ -d "${2:-}" ] || die "--rwdir needs an existing directory"; rwdirs+=("$(cd "$2" && pwd)"); shift 2 ;;
    --vm) force_vm=1; shift ;;
    --) shift; break ;;
    *) die "unknown option '$1'; usage: $0 [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS..." ;;
  esac
done
[ $# -gt 0 ] || die "no command given; usage: $0 [--iface vcan0] [--rwdir DIR]... [--vm] -- CMD ARGS..."
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
  echo "vcan_run: $iface is up on the host kernel; running natively" >&2
  rc=0; "$@" || rc=$?
  finish "$rc"
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

# stdin: /dev/null (no tty needed). stdout/stderr: through fifos, because QEMU
# reopens /proc/self/fd/1 and 2 with O_TRUNC: a log file would be clobbered.
mkfifo "$state/out" "$state/err"
cat "$state/out" & cat_pids=$!
cat "$state/err" >&2 & cat_pids+=" $!"
setsid vng "${vng_args[@]}" --exec "$guest_cmd" </dev/null >"$state/out" 2>"$state/err" & vng_pid=$!
msg="vcan_run: booting QEMU guest $(basename "$kernel") (no CAN in host kernel)..."
while kill -0 "$vng_pid" 2>/dev/null && [ ! -e "$state/booted" ]; do
  t=$((SECONDS - start))
  if [ -t 2 ]; then printf '\r%s %d s' "$msg" "$t" >&2; elif [ $((t % 5)) = 0 ]; then echo "$msg $t s" >&2; fi
  sleep 1
done
[ -t 2 ] && printf '\n' >&2
[ -e "$state/booted" ] && echo "vcan_run: guest up after $((SECONDS - start)) s, running: $*" >&2
vng_rc=0; wait "$vng_pid" || vng_rc=$?; vng_pid=; wait; cat_pids=
if [ -s "$state/rc" ]; then finish "$(cat "$state/rc")"; fi
echo "vcan_run: the guest did not report an exit code (vng exit $vng_rc: QEMU failed to start," \
     "kernel panic, or the guest was killed). Boot log: PATH=$repo/.venv/bin:\$PATH" \
     "vng --verbose --run $kernel --disable-kvm --user root --exec true </dev/null" >&2
finish $((vng_rc ? vng_rc : 1))
