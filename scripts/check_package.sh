#!/usr/bin/env bash
# Prove that firmware can consume the library both ways (tests/consumer/):
#   1. install it to a temporary prefix and build the consumer with
#      find_package(wetclutch) against that prefix;
#   2. build the consumer with add_subdirectory() of this source tree.
# Each consumer is run once. Then, if arm-none-eabi-gcc is installed, the same
# two ways cross-compiled for the Cortex-M4F (cmake/arm-none-eabi.cmake), built
# and linked but not run. Needs cmake, ninja and a host C compiler.
#   scripts/check_package.sh
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

step() { echo "check_package: $*"; }
quiet() {  # run quietly; show the output only on failure
  if ! "$@" >"$tmp/log" 2>&1; then cat "$tmp/log" >&2; echo "check_package: FAIL: $*" >&2; exit 1; fi
}

step "build + install wetclutch to a temporary prefix"
quiet cmake -S "$repo" -B "$tmp/lib" -G Ninja -DCMAKE_BUILD_TYPE=Release -DWC_BUILD_HOST_TOOLS=OFF \
  -DCMAKE_INSTALL_PREFIX="$tmp/prefix"
quiet cmake --build "$tmp/lib"
quiet cmake --install "$tmp/lib"
(cd "$tmp/prefix" && find . -type f | sort | sed 's/^\./    /')

step "consumer via find_package(wetclutch)"
quiet cmake -S "$repo/tests/consumer" -B "$tmp/consumer-package" -G Ninja -DWC_CONSUMER_MODE=package \
  -DCMAKE_PREFIX_PATH="$tmp/prefix"
grep -h 'wetclutch .* from' "$tmp/log" | sed 's/^-- /    /'
quiet cmake --build "$tmp/consumer-package"
"$tmp/consumer-package/wc_consumer"

step "consumer via add_subdirectory()"
quiet cmake -S "$repo/tests/consumer" -B "$tmp/consumer-subdir" -G Ninja -DWC_CONSUMER_MODE=subdirectory
quiet cmake --build "$tmp/consumer-subdir"
"$tmp/consumer-subdir/wc_consumer"

if command -v arm-none-eabi-gcc >/dev/null; then
  toolchain="$repo/cmake/arm-none-eabi.cmake"
  step "Cortex-M4F: install the cross-built library, consumer via find_package(wetclutch)"
  quiet cmake -S "$repo" -B "$tmp/arm-lib" -G Ninja --toolchain "$toolchain" -DCMAKE_BUILD_TYPE=MinSizeRel \
    -DCMAKE_INSTALL_PREFIX="$tmp/arm-prefix"
  quiet cmake --build "$tmp/arm-lib"
  quiet cmake --install "$tmp/arm-lib"
  quiet cmake -S "$repo/tests/consumer" -B "$tmp/arm-consumer-package" -G Ninja --toolchain "$toolchain" \
    -DCMAKE_BUILD_TYPE=MinSizeRel -DWC_CONSUMER_MODE=package -DCMAKE_PREFIX_PATH="$tmp/arm-prefix"
  quiet cmake --build "$tmp/arm-consumer-package"
  arm-none-eabi-readelf -h "$tmp/arm-consumer-package/wc_consumer" | sed -n 's/^ *Machine: */    wc_consumer machine: /p'
  step "Cortex-M4F: consumer via add_subdirectory()"
  quiet cmake -S "$repo/tests/consumer" -B "$tmp/arm-consumer-subdir" -G Ninja --toolchain "$toolchain" \
    -DCMAKE_BUILD_TYPE=MinSizeRel -DWC_CONSUMER_MODE=subdirectory
  quiet cmake --build "$tmp/arm-consumer-subdir"
else
  step "arm-none-eabi-gcc not found: cross-compiled consumers skipped"
fi

step "OK: find_package and add_subdirectory both work"
