#!/usr/bin/env bash
# Cortex-M4F instruction counts of the library in QEMU (DESIGN.md section 11).
#
#   scripts/bench_arm.sh     (needs gcc-arm-none-eabi, libnewlib-arm-none-eabi,
#                             qemu-system-arm, cmake, ninja-build)
#
# 1. Builds the probe firmware bench/arm (its CMake project pulls the library
#    in with add_subdirectory, so libraries and probe share the flags) at -Os
#    and at -O2, into build/arm-bench-Os and build/arm-bench-O2, -Werror.
# 2. Runs each firmware twice under
#      qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -semihosting
#                      -icount shift=8,sleep=off -kernel wc_arm_bench.elf
#    (with a timeout) and FAILS unless both runs print RESULT OK (the 1000-nop
#    calibration reads 1000, the naive inverse agrees with wc_inverse, every
#    loop frame was accepted) and their outputs are byte-identical.
# 3. Prints one table (function | -Os median / worst | -O2 median / worst),
#    the naive/library ratio of the inverse, the state sizes (the probe's RAM
#    lines, which must agree between the levels: the whole shift's, the
#    diagnostic server's) and the flash of each library (and of the XCP
#    slave's, ISO-TP's, the UDS server's and the fault memory's objects in the
#    CAN layer) per level, and writes it to build/arm-bench/report.md.
# 4. FAILS when a worst case exceeds its ceiling in bench/arm_ceilings.txt, or
#    when a measured function has no ceiling there (for either level); the
#    same for the flash (text + data) of the diagnostic objects (lines
#    flash:wc_isotp.c, flash:wc_uds.c, flash:wc_dtc.c) and their RAM (lines
#    ram:wc_isotp_t, ram:wc_uds_t, ram:wc_dtc_t).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"
start_s=$(date +%s)

prefix=arm-none-eabi-
levels=(Os O2)
ceilings=${WC_ARM_BENCH_CEILINGS:-bench/arm_ceilings.txt}  # override: tests of the gate
report_dir=build/arm-bench
report=$report_dir/report.md
qemu_timeout_s=${WC_ARM_BENCH_TIMEOUT:-60}
cpu_flags="-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16"

for tool in cmake ninja timeout qemu-system-arm ${prefix}gcc ${prefix}size; do
  command -v "$tool" >/dev/null || { echo "bench_arm: $tool not found (scripts/setup.sh installs it)" >&2; exit 2; }
done
[ -f "$ceilings" ] || { echo "bench_arm: FAIL: $ceilings is missing" >&2; exit 1; }

mkdir -p "$report_dir"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0

declare -A median worst samples
declare -A flash_text flash_data flash_bss ratio_median ratio_worst force_diff nop empty ram
names=()
ram_names=()

for level in "${levels[@]}"; do
  build=build/arm-bench-$level
  echo "bench_arm: build -$level ($build)"
  if ! { cmake -S bench/arm -B "$build" -G Ninja --toolchain "$repo/cmake/arm-none-eabi.cmake" \
           -DCMAKE_C_FLAGS="$cpu_flags -ffunction-sections -fdata-sections" \
           -DWC_ARM_BENCH_OPT="$level" &&
         cmake --build "$build"; } >"$log" 2>&1; then
    cat "$log" >&2
    echo "bench_arm: FAIL: build at -$level" >&2
    exit 1
  fi

  elf=$build/wc_arm_bench.elf
  for run in 1 2; do
    out=$report_dir/run-$level-$run.txt
    rc=0
    # Semihosting output goes to QEMU's stderr; stdin closed (-nographic reads it).
    timeout "$qemu_timeout_s" qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -semihosting \
      -icount shift=8,sleep=off -kernel "$elf" </dev/null >"$out" 2>&1 || rc=$?
    if [ "$rc" -ne 0 ] || ! grep -qx 'RESULT OK' "$out"; then
      cat "$out" >&2
      if [ "$rc" -eq 124 ]; then
        echo "bench_arm: FAIL: -$level run $run timed out after ${qemu_timeout_s}s" >&2
      else
        echo "bench_arm: FAIL: -$level run $run (QEMU exit $rc, no RESULT OK)" >&2
      fi
      exit 1
    fi
  done
  if ! cmp -s "$report_dir/run-$level-1.txt" "$report_dir/run-$level-2.txt"; then
    diff "$report_dir/run-$level-1.txt" "$report_dir/run-$level-2.txt" >&2 || true
    echo "bench_arm: FAIL: the two -$level runs differ (instruction counts must be deterministic)" >&2
    exit 1
  fi

  out=$report_dir/run-$level-1.txt
  while read -r tag name n med wst; do
    [ "$tag" = ROW ] || continue
    median[$level,$name]=$med
    worst[$level,$name]=$wst
    samples[$level,$name]=$n
    if [ "$level" = "${levels[0]}" ]; then names+=("$name"); fi
  done <"$out"
  while read -r tag name bytes; do
    [ "$tag" = RAM ] || continue
    ram[$level,$name]=$bytes
    if [ "$level" = "${levels[0]}" ]; then ram_names+=("$name"); fi
  done <"$out"
  nop[$level]=$(awk '$1 == "NOP" { print $2 }' "$out")
  empty[$level]=$(awk '$1 == "EMPTY" { print $2 }' "$out")
  ratio_median[$level]=$(awk '$1 == "NAIVE" && $2 == "ratio_solve_median" { print $3 }' "$out")
  ratio_worst[$level]=$(awk '$1 == "NAIVE" && $2 == "ratio_solve_median" { print $5 }' "$out")
  force_diff[$level]=$(awk '$1 == "NAIVE" && $2 == "force_diff_worst_N" { print $3 }' "$out")

  for lib in model can xcp isotp uds dtc cal; do
    member=
    case $lib in
      model) archive=$build/wetclutch/src/model/libwetclutch.a ;;
      can) archive=$build/wetclutch/src/can/libwetclutch_can.a ;;
      isotp|uds|dtc) archive=$build/wetclutch/src/can/libwetclutch_can.a; member="^wc_${lib}[.]c[.]obj$" ;;
      xcp) archive=$build/wetclutch/src/can/libwetclutch_can.a; member='^wc_xcp(_memory)?[.]c[.]obj$' ;;  # its two files
      cal) archive=$build/libwc_arm_calibration.a ;;
    esac
    t=
    if [ -n "$member" ]; then  # one object of the archive
      read -r t d b < <(${prefix}size "$archive" | awk -v m="$member" '$6 ~ m { t += $1; d += $2; b += $3; n++ }
                                                           END { if (n) print t, d, b }') || true
    else
      read -r t d b < <(${prefix}size -t "$archive" | awk 'END { print $1, $2, $3 }')
    fi
    if [ -z "${t:-}" ]; then echo "bench_arm: FAIL: no $lib object in $archive" >&2; exit 1; fi
    flash_text[$level,$lib]=$t
    flash_data[$level,$lib]=$d
    flash_bss[$level,$lib]=$b
  done
done

# The whole shift's state sizes (RAM lines): the layout, the same at both levels.
if [ -z "${ram[${levels[0]},wc_loop_t]:-}" ]; then
  echo "bench_arm: FAIL: the probe printed no RAM wc_loop_t line" >&2
  status=1
fi
for name in "${ram_names[@]}"; do
  if [ "${ram[Os,$name]:-}" != "${ram[O2,$name]:-}" ]; then
    echo "bench_arm: FAIL: RAM $name differs between -Os (${ram[Os,$name]:-none}) and -O2 (${ram[O2,$name]:-none})" >&2
    status=1
  fi
done

# --- ceilings -----------------------------------------------------------------
declare -A ceiling
while read -r fn lvl max extra; do
  case $fn in ''|'#'*) continue ;; esac
  if [ -n "$extra" ] || ! [[ $lvl =~ ^(Os|O2)$ ]] || ! [[ $max =~ ^[0-9]+$ ]]; then
    echo "bench_arm: FAIL: $ceilings: bad line: '$(echo "$fn" "$lvl" "$max" "$extra" | xargs)'" \
         "(want: function level max_instructions, level Os or O2)" >&2
    status=1
    continue
  fi
  ceiling[$fn,$lvl]=$max
done <"$ceilings"

violations=()
# gate NAME UNIT: NAME's worst at each level against its ceiling; missing or above it: a violation
gate() {
  local name=$1 unit=$2 level
  for level in "${levels[@]}"; do
    if [ -z "${worst[$level,$name]:-}" ]; then
      violations+=("$name was not measured at -$level")
    elif [ -z "${ceiling[$name,$level]:-}" ]; then
      violations+=("no ceiling for '$name' at level $level in $ceilings (add a line: $name $level <max_$unit>)")
    elif [ "${worst[$level,$name]}" -gt "${ceiling[$name,$level]}" ]; then
      violations+=("$name at -$level: worst ${worst[$level,$name]} $unit > ceiling ${ceiling[$name,$level]}")
    fi
  done
}
for name in "${names[@]}"; do gate "$name" instructions; done
# The diagnostic server's flash (text + data of its objects) and RAM (sizeof), gated like the rows.
for level in "${levels[@]}"; do
  for lib in isotp uds dtc; do
    worst[$level,flash:wc_$lib.c]=$(( flash_text[$level,$lib] + flash_data[$level,$lib] ))
  done
  for type in wc_isotp_t wc_uds_t wc_dtc_t; do
    worst[$level,ram:$type]=${ram[$level,$type]:-}
  done
done
for gated in flash:wc_isotp.c flash:wc_uds.c flash:wc_dtc.c ram:wc_isotp_t ram:wc_uds_t ram:wc_dtc_t; do
  gate "$gated" bytes
done
for key in "${!ceiling[@]}"; do
  if [ -z "${worst[${key#*,},${key%,*}]:-}" ]; then
    echo "bench_arm: note: $ceilings has a ceiling for '${key%,*}' at ${key#*,}, which the probe does not measure" >&2
  fi
done

# --- report -------------------------------------------------------------------
gcc_version=$(${prefix}gcc -dumpfullversion)
qemu_version=$(qemu-system-arm --version | awk 'NR == 1 { print $4 }')
{
  echo "## Cortex-M4F instruction counts (scripts/bench_arm.sh)"
  echo
  echo "QEMU $qemu_version \`-M mps2-an386 -cpu cortex-m4 -icount shift=8,sleep=off\`, arm-none-eabi-gcc $gcc_version,"
  echo "\`$cpu_flags -ffunction-sections -fdata-sections\`, library and probe at the level shown."
  echo "Instructions (not cycles) per call, SysTick window minus the empty window"
  echo "(${empty[Os]} / ${empty[O2]} instructions at -Os / -O2); 1000 nops read ${nop[Os]} / ${nop[O2]}."
  echo "Grid: slip {-3000, -750, -0.25, 0, 0.25, 50, 750, 3000} rpm x theta {10, 40, 80, 120} degC"
  echo "x request {0, 0.05, 0.3, 0.6, 0.9, 1.1} x capacity (192 points); two runs per level, byte-identical."
  echo
  echo "| function | samples | -Os median / worst | -O2 median / worst | ceiling -Os / -O2 |"
  echo "|---|---:|---:|---:|---:|"
  for name in "${names[@]}"; do
    printf '| `%s` | %s | %s / %s | %s / %s | %s / %s |\n' "$name" "${samples[Os,$name]}" \
      "${median[Os,$name]}" "${worst[Os,$name]}" "${median[O2,$name]}" "${worst[O2,$name]}" \
      "${ceiling[$name,Os]:-none}" "${ceiling[$name,O2]:-none}"
  done
  echo
  echo "Inverse without the h̄(p_c) table (naive_inverse: bisection on F_c, eq. 15 solved for h by"
  echo "bisection with erfcf/expf, eq. 9 with erff, at every torque evaluation) over wc_inverse,"
  echo "the solve cases (neither below drag nor saturated):"
  echo
  echo "| level | naive / library, median | naive / library, worst | worst force difference |"
  echo "|---|---:|---:|---:|"
  for level in "${levels[@]}"; do
    echo "| -$level | ${ratio_median[$level]} | ${ratio_worst[$level]} | ${force_diff[$level]} N |"
  done
  echo
  echo "RAM (sizeof on the target, the probe's RAM lines): the whole shift (DESIGN 14), the diagnostic server (DESIGN 17):"
  echo
  echo "| state | bytes |"
  echo "|---|---:|"
  for name in "${ram_names[@]}"; do
    case $name in
      wc_loop_t) label='`wc_loop_t` (one per clutch pair: holds the off-going clutch too)' ;;
      wc_loop_t.offgoing_parts) label='of which the off-going clutch, its input, output, E2E input and sensors' ;;
      whole_shift_step_state) label='`wc_shift_step` caller: `wc_shift_t` + two clutches with input and output' ;;
      wc_isotp_t) label='`wc_isotp_t` (ISO-TP: receive ring, request and response buffers)' ;;
      wc_uds_t) label='`wc_uds_t` (the UDS server)' ;;
      wc_dtc_t) label='`wc_dtc_t` (the fault memory)' ;;
      *) label="\`$name\`" ;;
    esac
    gate=
    [ -n "${ceiling[ram:$name,${levels[0]}]:-}" ] && gate=" (ceiling ${ceiling[ram:$name,${levels[0]}]})"
    echo "| $label | ${ram[${levels[0]},$name]}$gate |"
  done
  echo
  echo "Flash (arm-none-eabi-size, text / data / bss in bytes):"
  echo
  echo "| library | -Os | -O2 |"
  echo "|---|---:|---:|"
  for lib in model can xcp isotp uds dtc cal; do
    case $lib in
      model) label='model, `libwetclutch.a`' ;;
      can) label='CAN layer, `libwetclutch_can.a`' ;;
      xcp) label='of which the XCP slave, `wc_xcp.c` + `wc_xcp_memory.c`' ;;
      isotp) label='of which ISO-TP, `wc_isotp.c`' ;;
      uds) label='of which the UDS server, `wc_uds.c`' ;;
      dtc) label='of which the fault memory, `wc_dtc.c`' ;;
      cal) label='table1 calibration + h̄ LUT (`wc_arm_calibration.c`)' ;;
    esac
    gate=
    [ -n "${ceiling[flash:wc_$lib.c,Os]:-}" ] && gate=" (text + data ceiling ${ceiling[flash:wc_$lib.c,Os]} / ${ceiling[flash:wc_$lib.c,O2]})"
    echo "| $label$gate | ${flash_text[Os,$lib]} / ${flash_data[Os,$lib]} / ${flash_bss[Os,$lib]} | ${flash_text[O2,$lib]} / ${flash_data[O2,$lib]} / ${flash_bss[O2,$lib]} |"
  done
} >"$report"

echo
cat "$report"
echo
echo "bench_arm: report written to $report; runtime $(( $(date +%s) - start_s )) s"

if [ "${#violations[@]}" -gt 0 ]; then
  for v in "${violations[@]}"; do echo "bench_arm: FAIL: $v" >&2; done
  echo "bench_arm: FAIL: ceilings in $ceilings" >&2
  status=1
fi
if [ "$status" -eq 0 ]; then
  echo "bench_arm: OK: deterministic counts, every worst case within its ceiling"
fi
exit "$status"
