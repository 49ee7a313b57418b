#!/usr/bin/env bash
# Install everything the project needs on a fresh Debian machine (run as root).
# Idempotent and quick when everything is present: apt is only touched when a
# package is missing, pip only when tools/pyproject.toml changed.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"

mapfile -t pkgs < <(grep -v '^\s*#' scripts/apt-packages.txt | sed '/^\s*$/d')
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  [ "$(id -u)" -eq 0 ] || { echo "setup: need root to apt-get install (missing: ${missing[*]})" >&2; exit 1; }
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

venv="$repo/.venv"
stamp="$venv/.installed-pyproject"
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating Python virtual environment in .venv"
  python3 -m venv "$venv"
fi
if [ ! -f "$stamp" ] || ! cmp -s tools/pyproject.toml "$stamp"; then
  echo "setup: installing the Python tool (tools/) into .venv"
  "$venv/bin/python" -m pip install -q --upgrade pip
  "$venv/bin/python" -m pip install -q -e "tools[test]"
  cp tools/pyproject.toml "$stamp"
fi
# the guest tools' modules in one tar for the emulated guest's tmpfs (hil/guest_pylib.py): again after an install
pylib="$venv/guest-pylib.tar"
if [ ! -f "$pylib" ] || [ "$stamp" -nt "$pylib" ] || [ hil/guest_pylib.py -nt "$pylib" ]; then
  "$venv/bin/python" hil/guest_pylib.py "$pylib"
fi
