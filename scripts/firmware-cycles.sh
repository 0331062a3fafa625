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
echo "   us and % at $MHZ MHz of the ${PERIOD_US} us period; CPI = cycles / instructions"
awk -v mhz="$MHZ" -v per="$PERIOD_US" '
  FNR == NR { if ($1 == "BENCH") { label[++nb] = $2; n[nb] = $3 } next }
  /^TOTAL/ || /^MIX/ { next }
  { ins[++nc] = $1; core[nc] = $2; art[nc] = $3; pess[nc] = $4 }
  END {
    printf "%-28s %6s | %9s %9s | %-26s | %-26s | %-26s\n", "interval", "n", "insn mean", "insn max",
      "core mean/max [us] CPI", "ART mean/max [us] CPI", "pess mean/max [us] CPI"
    k = 0
    for (b = 1; b <= nb; b++) {
      si = 0; mi = 0; sc = 0; mc = 0; sa = 0; ma = 0; sp = 0; mp = 0
      for (i = 1; i <= n[b]; i++) {
        ++k
        si += ins[k]; sc += core[k]; sa += art[k]; sp += pess[k]
        if (ins[k] > mi) mi = ins[k]
        if (core[k] > mc) mc = core[k]
        if (art[k] > ma) ma = art[k]
        if (pess[k] > mp) mp = pess[k]
      }
      m = n[b]
      printf "%-28s %6d | %9.0f %9d | %7.1f %7.1f %5.2f   | %7.1f %7.1f %5.2f   | %7.1f %7.1f %5.2f\n",
        label[b], m, si / m, mi,
        sc / m / mhz, mc / mhz, sc / si, sa / m / mhz, ma / mhz, sa / si, sp / m / mhz, mp / mhz, sp / si
      if (label[b] ~ /^period_/)
        periods[++np] = sprintf("%-28s worst period: core %5.1f %%, ART %5.1f %%, pess %5.1f %% of %d us; overruns (pess > period): %d of %d",
          label[b], 100 * mc / mhz / per, 100 * ma / mhz / per, 100 * mp / mhz / per, per, over[b], m)
    }
    if (k != nc) { printf "count mismatch: %d intervals announced, %d measured\n", k, nc; exit 1 }
    print ""
    for (i = 1; i <= np; i++) print periods[i]
  }' "$OUT/qemu.log" "$OUT/cycles.txt"

echo
echo "== Periods over 2 ms per model"
off=0
grep '^BENCH' "$OUT/qemu.log" | while read -r _ label n; do
  if [[ "$label" == period_* ]]; then
    sed -n "$((off + 1)),$((off + n))p" "$OUT/cycles.txt" |
      awk -v l="$label" -v lim="$((MHZ * PERIOD_US))" '
        { if ($2 > lim) c++; if ($3 > lim) a++; if ($4 > lim) p++ }
        END { printf "%-28s core %d, ART %d, pess %d of %d\n", l, c, a, p, NR }'
  fi
  off=$((off + n))
done

echo
echo "== Instruction mix of the whole run (executed)"
grep '^MIX' "$OUT/cycles.txt" | awk '{ s += $3; a[$2] = $3; o[++n] = $2 } END { for (i = 1; i <= n; i++) printf "%-14s %12d %5.1f %%\n", o[i], a[o[i]], 100 * a[o[i]] / s }'
