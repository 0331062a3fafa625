#!/usr/bin/env bash
# Cycle counts of the firmware's measured intervals (firmware/README.md "Cycles on a
# Cortex-M4"): runs the firmware under QEMU mps2-an386 with the cycle-model TCG plugin
# (firmware/qemu-plugin/cycles.c) and reports, per interval, mean and max in instructions and
# in cycles under three memory models (core = zero-wait, art = 5 wait states behind the ART
# cache and prefetch, pess = no ART, every line fetch and literal load 5 wait states), with the
# time at 168 MHz and the share of the 2 ms period.
#
# Needs: qemu-system-arm (Debian 7.2), gcc, llvm-nm. Usage: scripts/firmware-cycles.sh
set -euo pipefail
cd "$(dirname "$0")/.."
MHZ=168
PERIOD_US=2000

find_tool() {
  local name="$1" sysroot
  if command -v "$name" >/dev/null 2>&1; then command -v "$name"; return; fi
  sysroot="$(rustc --print sysroot)"
  for p in "$sysroot"/lib/rustlib/*/bin/"$name"; do
    [ -x "$p" ] && { echo "$p"; return; }
  done
  for v in 19 18 17 16 15 14; do
    command -v "$name-$v" >/dev/null 2>&1 && { command -v "$name-$v"; return; }
  done
  echo "missing $name (apt-get install llvm, or rustup component add llvm-tools)" >&2
  exit 1
}
NM="$(find_tool llvm-nm)"

cargo build -q -p firmware --target thumbv7em-none-eabihf --release
TARGET_DIR="${CARGO_TARGET_DIR:-target}"
ELF="$TARGET_DIR/thumbv7em-none-eabihf/release/firmware"
OUT="$TARGET_DIR/firmware-cycles"
mkdir -p "$OUT"
gcc -O2 -Wall -shared -fPIC -o "$OUT/cycles.so" firmware/qemu-plugin/cycles.c

START=$("$NM" "$ELF" | awk '$3=="bench_start"{print $1}')
STOP=$("$NM" "$ELF" | awk '$3=="bench_stop"{print $1}')
[ -n "$START" ] && [ -n "$STOP" ] && [ "$START" != "$STOP" ] || { echo "bench markers not found" >&2; exit 1; }

timeout 1800 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$ELF" \
  -plugin "$OUT/cycles.so,start=0x$START,stop=0x$STOP,out=$OUT/cycles.txt" \
  </dev/null >"$OUT/qemu.log"
grep -q '^DONE ok' "$OUT/qemu.log" || { echo "firmware did not finish: see $OUT/qemu.log" >&2; exit 1; }

echo "== Cycles per measured interval (Cortex-M4 TRM timings; flash models in cycles.c)"
echo "   mean / max in us at $MHZ MHz and CPI (cycles per instruction) per model:"
echo "   core = zero wait states; art = 5 WS behind the ART cache + prefetch;"
echo "   apess = pessimistic flash with the ART (every miss 5 WS, literal loads 5 WS, P = 3);"
echo "   pess = no ART at all (bound)"
awk -v mhz="$MHZ" -v per="$PERIOD_US" '
  FNR == NR { if ($1 == "BENCH") { label[++nb] = $2; n[nb] = $3 } next }
  /^TOTAL/ || /^MIX/ { next }
  { ++nc; for (j = 1; j <= 5; j++) v[nc, j] = $j }
  END {
    split("insn core art apess pess", name, " ")
    printf "%-30s %5s | %15s", "interval", "n", "insn mean/max"
    for (j = 2; j <= 5; j++) printf " | %-24s", name[j] " mean/max us CPI"
    printf "\n"
    k = 0
    lim = mhz * per
    for (b = 1; b <= nb; b++) {
      for (j = 1; j <= 5; j++) { s[j] = 0; m[j] = 0; o[j] = 0 }
      for (i = 1; i <= n[b]; i++) {
        ++k
        for (j = 1; j <= 5; j++) {
          x = v[k, j]; s[j] += x; if (x > m[j]) m[j] = x; if (j > 1 && x > lim) o[j]++
        }
      }
      printf "%-30s %5d | %7.0f %7d", label[b], n[b], s[1] / n[b], m[1]
      for (j = 2; j <= 5; j++) printf " | %7.1f %8.1f %5.2f", s[j] / n[b] / mhz, m[j] / mhz, s[j] / s[1]
      printf "\n"
      if (label[b] ~ /^period_/)
        per_line[++np] = sprintf("%-30s worst period %% of %d us: core %5.1f, art %5.1f, apess %5.1f, pess %5.1f; periods over: %d / %d / %d / %d of %d",
          label[b], per, 100 * m[2] / lim, 100 * m[3] / lim, 100 * m[4] / lim, 100 * m[5] / lim, o[2], o[3], o[4], o[5], n[b])
    }
    if (k != nc) { printf "count mismatch: %d intervals announced, %d measured\n", k, nc; exit 1 }
    print ""
    for (i = 1; i <= np; i++) print per_line[i]
  }' "$OUT/qemu.log" "$OUT/cycles.txt"

echo
echo "== Instruction mix of the whole run (executed)"
grep '^MIX' "$OUT/cycles.txt" | awk '{ s += $3; a[$2] = $3; o[++n] = $2 } END { for (i = 1; i <= n; i++) printf "%-14s %14.0f %5.1f %%\n", o[i], a[o[i]], 100 * a[o[i]] / s }'
