#!/usr/bin/env bash
# Cortex-M4F check of the portable core, and its footprint figures.
#
#   scripts/check_arm.sh            (needs gcc-arm-none-eabi, libnewlib-arm-none-eabi,
#                                    cmake, ninja-build, python3)
#
# 1. Configures and builds the `cortex-m4f` preset with -Werror.
# 2. Compiles, with the library's own flags, three small ARM translation units:
#    the table1 calibration (the LUT is static const data in lut/ headers, so it
#    lands in the user's TU), a probe whose object sizes carry sizeof(wc_clutch_t)
#    and WC_INVERSE_MAX_ITERATIONS (and sizeof(wc_xcp_t) by part), and a firmware
#    main that inits and steps one clutch and the CAN frame loop (linked against a
#    baseline main to get the flash a user pays), once more with the XCP slave
#    stepped after the loop (wc_xcp.h; the difference is the slave's cost, and
#    the stack analysis reads this image, so that every library function's
#    C-library callees are in it).
# 3. FAILS (exit 1) if any of these ARM objects, or the part of the linked image
#    that the library brings in, references heap, stdio, a double-precision libm
#    function or a soft-double helper (__aeabi_d*, __aeabi_f2d, ...).
# 4. Prints text/data/bss, worst stack per public function (own frame from
#    -fstack-usage, summed along the call graph from -fcallgraph-info=su; libm
#    callees such as expf from their prologues in the linked image), state bytes
#    per clutch and the inverse's iteration bound, as a block to paste into
#    docs/results.md. Goals (issue 19): flash <= 10 KiB, stack <= 320 B, state <= 64 B. Set
#    WC_ARM_STRICT=1 to fail when a goal is missed as well.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
cd "$repo"

preset=cortex-m4f
build="$repo/build/$preset"
work="$build/check_arm"
lib="$build/src/model/libwetclutch.a"
can_lib="$build/src/can/libwetclutch_can.a"
prefix=arm-none-eabi-

for tool in cmake ninja python3 ${prefix}gcc ${prefix}nm ${prefix}size ${prefix}objdump; do
  command -v "$tool" >/dev/null || { echo "check_arm: $tool not found (scripts/setup.sh installs it)" >&2; exit 2; }
done

echo "check_arm: configure + build preset $preset (-Werror)"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { cmake --preset "$preset" -DWC_WERROR=ON && cmake --build --preset "$preset"; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "check_arm: FAIL: ARM build" >&2
  exit 1
fi

rm -rf "$work"
mkdir -p "$work"

# --- probe translation units --------------------------------------------------
cat >"$work/wc_arm_calibration.c" <<'EOF'
/* The table1 calibration and film LUT as a firmware TU holds them. */
#include "wc_table1_calibration.h"

extern const wc_calibration_t *const wc_arm_calibration;
const wc_calibration_t *const wc_arm_calibration = &wc_table1_calibration;
EOF
cat >"$work/wc_arm_probe.c" <<'EOF'
/* Compile-time figures, read back from the object's symbol sizes (nm -S). */
#include "wetclutch/wetclutch.h"
#include "wetclutch_can/wc_xcp.h"

extern const unsigned char wc_probe_sizeof_clutch[sizeof(wc_clutch_t)];
const unsigned char wc_probe_sizeof_clutch[sizeof(wc_clutch_t)] = {0u};
extern const unsigned char wc_probe_sizeof_model[sizeof(wc_model_t)];
const unsigned char wc_probe_sizeof_model[sizeof(wc_model_t)] = {0u};
extern const unsigned char wc_probe_inverse_max_iterations[WC_INVERSE_MAX_ITERATIONS];
const unsigned char wc_probe_inverse_max_iterations[WC_INVERSE_MAX_ITERATIONS] = {0u};
/* The XCP slave's state and its parts. */
#define XCP_FIELD(f) sizeof(((const wc_xcp_t *)0)->f)
extern const unsigned char wc_probe_sizeof_xcp[sizeof(wc_xcp_t)];
const unsigned char wc_probe_sizeof_xcp[sizeof(wc_xcp_t)] = {0u};
extern const unsigned char wc_probe_sizeof_xcp_page[XCP_FIELD(working_page)];
const unsigned char wc_probe_sizeof_xcp_page[XCP_FIELD(working_page)] = {0u};
extern const unsigned char wc_probe_sizeof_xcp_sets[XCP_FIELD(sets)];
const unsigned char wc_probe_sizeof_xcp_sets[XCP_FIELD(sets)] = {0u};
extern const unsigned char wc_probe_sizeof_xcp_daq[XCP_FIELD(lists) + XCP_FIELD(odts) + XCP_FIELD(entries)];
const unsigned char wc_probe_sizeof_xcp_daq[XCP_FIELD(lists) + XCP_FIELD(odts) + XCP_FIELD(entries)] = {0u};
extern const unsigned char wc_probe_sizeof_xcp_rx[XCP_FIELD(rx)];
const unsigned char wc_probe_sizeof_xcp_rx[XCP_FIELD(rx)] = {0u};
EOF
cat >"$work/wc_arm_main.c" <<'EOF'
/* Smallest firmware that uses the library: init one clutch from table1, step it,
 * and run the CAN frame loop once. */
#include "wetclutch/wetclutch.h"
#include "wetclutch_can/wc_loop.h"
#include "wc_table1_calibration.h"
#ifdef WC_PROBE_XCP
#include "wetclutch_can/wc_xcp.h"
#include "wc_table1_cal_image.h"
#endif

volatile float wc_probe_in[4];
volatile float wc_probe_out;
volatile uint8_t wc_probe_frame[8];
static wc_clutch_t clutch;
static wc_loop_t loop;
#ifdef WC_PROBE_XCP
static wc_xcp_t xcp;
#endif

int main(void)
{
    if (wc_clutch_init(&clutch, &wc_table1_calibration, wc_probe_in[1]) != WC_CAL_OK) { return 1; }
    const wc_step_input_t in = { .slip_rad_s = wc_probe_in[0], .theta_oil_degC = wc_probe_in[1],
                                 .theta_housing_degC = wc_probe_in[2], .torque_request_Nm = wc_probe_in[3],
                                 .mode = WC_MODE_TORQUE };
    wc_step_output_t out;
    (void)wc_clutch_step(&clutch, &in, &out);
    wc_probe_out = out.current_mA;

    /* The CAN frame loop too: one received frame, one step, two frames out. */
    const wc_loop_config_t config = WC_LOOP_CONFIG_DEFAULT;
    if (wc_loop_init(&loop, &wc_table1_calibration, &config, wc_probe_in[1]) != WC_CAL_OK) { return 1; }
    wc_can_frame_t rx = { WC_CAN_CLUTCH_SENSORS_FRAME_ID, 8u, 0u, {0u} };
    for (unsigned i = 0u; i < 8u; ++i) { rx.data[i] = wc_probe_frame[i]; }
    (void)wc_loop_receive(&loop, &rx);
    wc_can_frame_t tx[WC_LOOP_TX_FRAMES];
    (void)wc_loop_step(&loop, tx);
    wc_probe_frame[0] = tx[0].data[2];
#ifdef WC_PROBE_XCP
    /* The XCP slave after the loop step: the table1 image's payload as its reference page,
     * one command frame received, one step. */
    const wc_xcp_config_t xcp_config = WC_XCP_CONFIG_DEFAULT;
    if (!wc_xcp_init(&xcp, &loop, &wc_table1_cal_image[WC_IMAGE_HEADER_BYTES], &xcp_config)) { return 1; }
    wc_can_frame_t command = { WC_CAN_XCP_COMMAND_FRAME_ID, 8u, 0u, {0u} };
    for (unsigned i = 0u; i < 8u; ++i) { command.data[i] = wc_probe_frame[i]; }
    (void)wc_xcp_receive(&xcp, &command);
    wc_can_frame_t xcp_tx[WC_XCP_TX_FRAMES];
    const uint32_t xcp_frames = wc_xcp_step(&xcp, true, xcp_tx);
    wc_probe_frame[1] = (xcp_frames > 0u) ? xcp_tx[0].data[0] : 0u;
#endif
    return (int)out.status;
}
EOF
cat >"$work/wc_arm_baseline.c" <<'EOF'
/* The same firmware without the library: what startup and newlib cost alone. */
volatile float wc_probe_in[4];
volatile float wc_probe_out;

int main(void)
{
    wc_probe_out = wc_probe_in[0] + wc_probe_in[1] + wc_probe_in[2] + wc_probe_in[3];
    return 0;
}
EOF

# Compile each probe exactly as CMake compiled src/model/wc_clutch.c (same -mcpu,
# -O, warnings, -Werror, include paths).
mapfile -t cflags < <(python3 - "$build/compile_commands.json" <<'EOF'
import json, shlex, sys
for entry in json.load(open(sys.argv[1])):
    if entry["file"].endswith("src/model/wc_clutch.c"):
        args = shlex.split(entry["command"])[1:]
        out, skip = [], False
        for a in args:
            if skip: skip = False; continue
            if a in ("-o", "-c"): skip = True; continue
            if a.startswith("-fcallgraph-info") or a == "-fstack-usage": continue
            out.append(a)
        print("\n".join(out))
        break
else:
    sys.exit("compile_commands.json has no src/model/wc_clutch.c")
EOF
)
cpu_flags=(-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16)
for tu in wc_arm_calibration wc_arm_probe wc_arm_main wc_arm_baseline; do
  if ! (cd "$work" && ${prefix}gcc "${cflags[@]}" -c "$tu.c" -o "$tu.o") >"$log" 2>&1; then
    cat "$log" >&2; echo "check_arm: FAIL: compiling probe $tu.c" >&2; exit 1
  fi
done
if ! (cd "$work" && ${prefix}gcc "${cflags[@]}" -DWC_PROBE_XCP -c wc_arm_main.c -o wc_arm_main_xcp.o) >"$log" 2>&1; then
  cat "$log" >&2; echo "check_arm: FAIL: compiling probe wc_arm_main.c with the XCP slave" >&2; exit 1
fi
ldflags=("${cpu_flags[@]}" -Os --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections)
if ! { ${prefix}gcc "${ldflags[@]}" -o "$work/firmware.elf" "$work/wc_arm_main.o" "$can_lib" "$lib" -lm \
         -Wl,-Map="$work/firmware.map" &&
       ${prefix}gcc "${ldflags[@]}" -o "$work/firmware_xcp.elf" "$work/wc_arm_main_xcp.o" "$can_lib" "$lib" -lm \
         -Wl,-Map="$work/firmware_xcp.map" &&
       ${prefix}gcc "${ldflags[@]}" -o "$work/baseline.elf" "$work/wc_arm_baseline.o"; } >"$log" 2>&1; then
  cat "$log" >&2; echo "check_arm: FAIL: linking the probe firmware" >&2; exit 1
fi

# --- forbidden references -----------------------------------------------------
forbidden_re='^(malloc|free|calloc|realloc|aligned_alloc|memalign|_(malloc|free|calloc|realloc)_r'
forbidden_re+='|v?(s|f|sn|as)?i?printf|_v?(s|f|sn)?i?printf_r|puts|putchar|fputs|fputc|putc|fwrite'
forbidden_re+='|a?(cos|sin|tan)h?|atan2|exp|exp2|expm1|log|log10|log2|log1p|logb|pow|sqrt|cbrt|hypot'
forbidden_re+='|erfc?|[lt]gamma|ceil|floor|fmod|l?l?round|trunc|l?l?rint|nearbyint|fabs|fmin|fmax|fdim|fma'
forbidden_re+='|ldexp|frexp|modf|scalbn|copysign|remainder|nan'
forbidden_re+='|__aeabi_d[a-z0-9_]*|__aeabi_[a-z0-9]+2d|__[a-z]+df[0-9]?|__[a-z]+df[a-z]+[0-9]?)$'

status=0
# Undefined references of every ARM object of the library and of the probes.
undefined=$( { ${prefix}nm -u "$lib" "$can_lib"; ${prefix}nm -u "$work"/wc_arm_calibration.o "$work"/wc_arm_probe.o; } \
             | awk 'NF == 2 && $1 == "U" { print $2 }' | sort -u)
bad_objects=$(grep -E "$forbidden_re" <<<"$undefined" || true)
# Functions the library brings into a linked image (not in the baseline image).
defined() { ${prefix}nm --defined-only "$1" | awk '$2 ~ /^[TtWw]$/ { print $3 }' | sort -u; }
brought_in=$(comm -23 <( { defined "$work/firmware.elf"; defined "$work/firmware_xcp.elf"; } | sort -u) \
                      <(defined "$work/baseline.elf"))
bad_image=$(grep -E "$forbidden_re" <<<"$brought_in" || true)
if [ -n "$bad_objects" ]; then
  echo "check_arm: FAIL: ARM objects reference forbidden symbols:" >&2
  for s in $bad_objects; do
    echo "  $s  <- $( { ${prefix}nm -A -u "$lib" "$can_lib"; ${prefix}nm -A -u "$work"/wc_arm_calibration.o; } \
                       | awk -v s="$s" '$NF == s { sub(/:$/, "", $1); n = split($1, p, /[:\/]/); print p[n] }' \
                       | sort -u | tr '\n' ' ')" >&2
  done
  status=1
fi
if [ -n "$bad_image" ]; then
  echo "check_arm: FAIL: the linked image pulls in forbidden functions:" $bad_image >&2
  status=1
fi
external=$(comm -23 <(echo "$undefined") <( { ${prefix}nm --defined-only "$lib" "$can_lib" "$work"/*.o; } \
           | awk 'NF == 3 { print $3 }' | sort -u) | tr '\n' ' ')

# --- figures ------------------------------------------------------------------
sizes() { ${prefix}size -t "$@" | awk 'END { print $1, $2, $3 }'; }
read -r lib_text lib_data lib_bss < <(sizes "$lib")
read -r can_text can_data can_bss < <(sizes "$can_lib")
read -r cal_text cal_data cal_bss < <(sizes "$work/wc_arm_calibration.o")
read -r fw_text fw_data fw_bss < <(sizes "$work/firmware.elf")
read -r base_text base_data base_bss < <(sizes "$work/baseline.elf")
read -r xfw_text xfw_data xfw_bss < <(sizes "$work/firmware_xcp.elf")
# The XCP slave: its object in the CAN layer, and the firmware with it minus the one without
# (of which the table1 image, its reference page, in .wc_calibration).
read -r xcp_text xcp_data xcp_bss < <(${prefix}size "$can_lib" | awk '$6 == "wc_xcp.c.obj" || $6 == "wc_xcp_memory.c.obj" {
  t += $1; d += $2; b += $3; n++ } END { if (n == 2) print t, d, b }')
[ -n "${xcp_text:-}" ] || { echo "check_arm: FAIL: no wc_xcp.c.obj and wc_xcp_memory.c.obj in $can_lib" >&2; exit 1; }
xcp_flash=$(((xfw_text + xfw_data) - (fw_text + fw_data)))
xcp_ram=$(((xfw_data + xfw_bss) - (fw_data + fw_bss)))
xcp_image=$(${prefix}size -A "$work/firmware_xcp.elf" | awk '$1 == ".wc_calibration" { print $2 }')
xcp_image=${xcp_image:-0}
flash_total=$((lib_text + lib_data + cal_text + cal_data))
ram_static=$((lib_data + lib_bss + cal_data + cal_bss))
linked_flash=$(((fw_text + fw_data) - (base_text + base_data)))
linked_ram=$(((fw_data + fw_bss) - (base_data + base_bss)))

symsize() {
  local hex
  hex=$(${prefix}nm -S --defined-only "$work/wc_arm_probe.o" | awk -v s="$1" '$4 == s { print $2 }')
  [ -n "$hex" ] || { echo "check_arm: probe symbol $1 missing" >&2; exit 1; }
  echo $((16#$hex))
}
state_bytes=$(symsize wc_probe_sizeof_clutch)
model_bytes=$(symsize wc_probe_sizeof_model)
max_iterations=$(symsize wc_probe_inverse_max_iterations)
xcp_state=$(symsize wc_probe_sizeof_xcp)
xcp_page=$(symsize wc_probe_sizeof_xcp_page)
xcp_sets=$(symsize wc_probe_sizeof_xcp_sets)
xcp_daq=$(symsize wc_probe_sizeof_xcp_daq)
xcp_rx=$(symsize wc_probe_sizeof_xcp_rx)
xcp_rest=$((xcp_state - xcp_page - xcp_sets - xcp_daq - xcp_rx))

# Stack: own frames (.su) summed along the call graph (.ci); functions outside
# the library (expf and what it calls) from their prologues in the linked image.
stack_report=$(python3 - "$build/src/model/CMakeFiles/wetclutch.dir:$build/src/can/CMakeFiles/wetclutch_can.dir" "$work/firmware_xcp.elf" "${prefix}objdump" include <<'EOF'
import glob, os, re, subprocess, sys
objdir, elf, objdump, incdir = sys.argv[1:5]

nodes, edges, names = {}, {}, {}
for ci in [f for d in objdir.split(":") for f in glob.glob(os.path.join(d, "**", "*.ci"), recursive=True)]:
    text = open(ci).read()
    for m in re.finditer(r'node: \{ title: "([^"]+)" label: "([^"]*)"', text):
        title, label = m.groups()
        parts = label.split("\\n")
        size = re.match(r"(\d+) bytes \(([^)]*)\)", parts[2]) if len(parts) > 2 else None
        if size:
            nodes[title] = (int(size.group(1)), size.group(2))
            names.setdefault(parts[0], title)
    for m in re.finditer(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"', text):
        edges.setdefault(m.group(1), set()).add(m.group(2))

# Outside the library: frames from the prologue (push / vpush / sub sp),
# callees from bl / blx / tail b.w to another function's start.
dis = subprocess.run([objdump, "-d", "--no-show-raw-insn", elf], capture_output=True, text=True, check=True).stdout
ext_frame, ext_calls, current, prologue = {}, {}, None, 0
for line in dis.splitlines():
    m = re.match(r"^[0-9a-f]+ <([^>]+)>:$", line)
    if m:
        current, prologue = m.group(1), 0
        ext_frame[current], ext_calls[current] = 0, set()
        continue
    if current is None or not line.strip():
        continue
    insn = line.split("\t", 1)[-1].strip()
    if prologue < 8:
        prologue += 1
        if m := re.match(r"(?:push|stmdb\s+sp!,)\s*\{([^}]*)\}", insn):
            ext_frame[current] += 4 * len(m.group(1).split(","))
        elif m := re.match(r"vpush\s*\{([^}]*)\}", insn):
            regs = m.group(1).replace(" ", "").split(",")
            count = 0
            for r in regs:
                a, _, b = r.partition("-")
                n = int(b[1:]) - int(a[1:]) + 1 if b else 1
                count += n * (8 if a.startswith("d") else 4)
            ext_frame[current] += count
        elif m := re.match(r"sub(?:\.w)?\s+sp,\s*(?:sp,\s*)?#(\d+)", insn):
            ext_frame[current] += int(m.group(1))
    if m := re.search(r"\b(?:bl|blx|b\.w|b)\s+[0-9a-f]+ <([^>+]+)>", insn):
        if m.group(1) != current:
            ext_calls[current].add(m.group(1))

memo = {}
def worst(title, stack=()):
    """(bytes, path) of the deepest chain from title; raises on recursion."""
    if title in stack:
        raise SystemExit("recursion: " + " -> ".join(stack + (title,)))
    if title in memo:
        return memo[title]
    if title in nodes:
        own, qual = nodes[title]
        if qual != "static":
            raise SystemExit(f"{title}: {qual} stack")
        calls = edges.get(title, ())
        estimated = False
    else:
        name = title.split(":")[-1]
        if name in names and names[name] != title:
            return worst(names[name], stack)
        own, calls, estimated = ext_frame.get(name, 0), ext_calls.get(name, ()), True
        if name == "__indirect_call":
            # the only call through a pointer: the loop's adaptation hook (wc_loop_config_t.adaptation_changed,
            # DESIGN 12), the integrator's function: its own stack is the integrator's, added to this chain
            return (0, ("integrator's adaptation hook",), True)
        if name not in ext_frame:
            raise SystemExit(f"{name}: not found in the linked image")
    best = (0, (), False)
    for callee in sorted(calls):
        sub = worst(callee, stack + (title,))
        if sub[0] > best[0]:
            best = sub
    result = (own + best[0], (title.split(":")[-1],) + best[1], estimated or best[2])
    memo[title] = result
    return result

public = set()
for h in glob.glob(os.path.join(incdir, "*", "*.h")):
    if os.path.basename(h) == "wc_can.h":
        continue  # cantools' raw pack/unpack: leaf functions, listed as internal
    public |= set(re.findall(r"\b(wc_[A-Za-z0-9_]+)\s*\(", open(h).read()))
rows = []
for title in nodes:
    if ":" in title:
        continue  # static function
    total, path, estimated = worst(title)
    rows.append((total, title, nodes[title][0], title in public, " > ".join(path), estimated))
rows.sort(key=lambda r: (-r[0], r[1]))
for total, name, own, pub, path, estimated in rows:
    print(f"{'public' if pub else 'internal'}\t{name}\t{own}\t{total}\t{'~' if estimated else ''}\t{path}")
EOF
)
worst_public=$(awk -F'\t' '$1 == "public" { print $4; exit }' <<<"$stack_report")
worst_public_name=$(awk -F'\t' '$1 == "public" { print $2; exit }' <<<"$stack_report")
worst_public_path=$(awk -F'\t' '$1 == "public" { print $6; exit }' <<<"$stack_report")
step_stack=$(awk -F'\t' '$2 == "wc_clutch_step" { print $4 }' <<<"$stack_report")
xcp_step_stack=$(awk -F'\t' '$2 == "wc_xcp_step" { print $4 " B (" $6 ")" }' <<<"$stack_report")
xcp_init_stack=$(awk -F'\t' '$2 == "wc_xcp_init" { print $4 " B (" $6 ")" }' <<<"$stack_report")

# Goals (issue 19): model + LUT flash, worst stack of a public entry point, state per clutch.
flash_goal=10240
stack_goal=320
state_goal=64
goal() { if [ "$1" -le "$2" ]; then echo "ok, goal <= $2"; else echo "OVER the goal of $2"; fi; }
gcc_version=$(${prefix}gcc -dumpfullversion)

cat <<EOF

## Cortex-M4F footprint (scripts/check_arm.sh)

arm-none-eabi-gcc $gcc_version, preset $preset: -mcpu=cortex-m4 -mthumb -mfloat-abi=hard
-mfpu=fpv4-sp-d16 -Os -ffunction-sections -fdata-sections, -Werror.

| figure | value | |
|---|---|---|
| model library (libwetclutch.a) text/data/bss | $lib_text / $lib_data / $lib_bss B | all public functions |
| table1 calibration + film LUT text/data/bss | $cal_text / $cal_data / $cal_bss B | static const, in the user's TU |
| flash, library + LUT | $flash_total B ($(awk -v b="$flash_total" 'BEGIN { printf "%.2f", b / 1024 }') KiB) | $(goal "$flash_total" "$flash_goal") |
| static RAM, library + LUT | $ram_static B | state lives in the caller's wc_clutch_t |
| CAN layer (libwetclutch_can.a: codec, E2E, frame loop) text/data/bss | $can_text / $can_data / $can_bss B | optional; every frame's pack and unpack |
| flash of a linked firmware (clutch init+step, loop init+step), minus an empty one | $linked_flash B | gc-sections; includes newlib expf (used at init only) and memset |
| XCP slave (wc_xcp.o in the CAN layer) text/data/bss | $xcp_text / $xcp_data / $xcp_bss B | optional (wc_xcp.h) |
| flash of the same firmware with the XCP slave (init, receive, step), minus without | $xcp_flash B, of which the table1 image (the reference page, .wc_calibration) $xcp_image B | gc-sections; the slave + the image's decode and checks |
| RAM of that firmware, minus without | $xcp_ram B | its static wc_xcp_t |
| XCP slave state, sizeof(wc_xcp_t) | $xcp_state B: working page $xcp_page, two decoded sets $xcp_sets, DAQ tables $xcp_daq, rx ring $xcp_rx, the rest $xcp_rest | the caller's |
| state per clutch, sizeof(wc_clutch_t) | $state_bytes B (of which wc_model_t $model_bytes B) | $(goal "$state_bytes" "$state_goal") |
| worst stack, public entry point | $worst_public B, $worst_public_name | $(goal "$worst_public" "$stack_goal") |
| stack of wc_clutch_step | $step_stack B | |
| stack of wc_xcp_step | $xcp_step_stack | after wc_loop_step, not nested in it |
| stack of wc_xcp_init | $xcp_init_stack | |
| inverse: WC_INVERSE_MAX_ITERATIONS | $max_iterations | compile-time bound on the Newton steps |

Worst chain: $worst_public_path

Stack per public function (own frame from -fstack-usage, total along the
-fcallgraph-info call graph; ~ = includes newlib callees measured from their
prologues in the linked image):

| function | own B | total B | chain |
|---|---:|---:|---|
$(awk -F'\t' '$1 == "public" { printf "| %s | %d | %s%d | %s |\n", $2, $3, $5, $4, $6 }' <<<"$stack_report")

Undefined symbols the library needs from outside: ${external:-none}
EOF

if [ "${WC_ARM_STRICT:-0}" = 1 ]; then
  if [ "$flash_total" -gt "$flash_goal" ] || [ "$state_bytes" -gt "$state_goal" ] || [ "$worst_public" -gt "$stack_goal" ]; then
    echo "check_arm: FAIL: a footprint goal is missed (WC_ARM_STRICT=1)" >&2
    status=1
  fi
fi
if [ "$status" -eq 0 ]; then
  echo
  echo "check_arm: OK: no heap, stdio, double libm or soft-double references in the ARM objects or the image."
fi
exit "$status"
