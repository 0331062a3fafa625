#!/usr/bin/env bash
# Reproduces the firmware cost figures of firmware/README.md: instruction counts per model step
# and per control period (f64 soft float and f32 FPU) under QEMU mps2-an386 with an
# instruction-counting TCG plugin, flash/RAM sizes and the painted-stack high-water marks.
#
# Needs: qemu-system-arm (Debian 7.2), gcc, llvm-nm + llvm-size (Debian `llvm`, or rustup's
# llvm-tools). Usage: scripts/firmware-costs.sh [CPI] (cycles per instruction assumed, default 1.25)
set -euo pipefail
cd "$(dirname "$0")/.."
CPI="${1:-1.25}"
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
SIZE="$(find_tool llvm-size)"

cargo build -q -p firmware --target thumbv7em-none-eabihf --release
TARGET_DIR="${CARGO_TARGET_DIR:-target}"
ELF="$TARGET_DIR/thumbv7em-none-eabihf/release/firmware"
OUT="$TARGET_DIR/firmware-costs"
mkdir -p "$OUT"
gcc -O2 -Wall -shared -fPIC -o "$OUT/icount.so" firmware/qemu-plugin/icount.c

START=$("$NM" "$ELF" | awk '$3=="bench_start"{print $1}')
STOP=$("$NM" "$ELF" | awk '$3=="bench_stop"{print $1}')
[ -n "$START" ] && [ -n "$STOP" ] && [ "$START" != "$STOP" ] || { echo "bench markers not found" >&2; exit 1; }

timeout 900 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$ELF" \
  -plugin "$OUT/icount.so,start=0x$START,stop=0x$STOP,out=$OUT/counts.txt" \
  </dev/null >"$OUT/qemu.log"
grep -q '^DONE ok' "$OUT/qemu.log" || { echo "firmware did not finish: see $OUT/qemu.log" >&2; exit 1; }

echo "== Instructions per measured interval (QEMU TCG count, exact)"
echo "   cycles = instructions x CPI $CPI (assumed: Cortex-M4F at $MHZ MHz); budget = ${PERIOD_US} us period"
awk -v cpi="$CPI" -v mhz="$MHZ" -v per="$PERIOD_US" '
  FNR == NR { if ($1 == "BENCH") { label[++nb] = $2; n[nb] = $3 } next }
  /^TOTAL/ { next }
  { c[++nc] = $1 }
  END {
    printf "%-32s %6s %10s %10s %10s %9s %9s\n", "interval", "n", "min", "mean", "max", "max [us]", "max/2ms"
    k = 0
    for (b = 1; b <= nb; b++) {
      min = -1; max = 0; sum = 0
      for (i = 1; i <= n[b]; i++) {
        v = c[++k]; sum += v
        if (min < 0 || v < min) min = v
        if (v > max) max = v
      }
      us = max * cpi / mhz
      printf "%-32s %6d %10d %10.0f %10d %9.1f %8.1f%%\n", label[b], n[b], min, sum / n[b], max, us, 100 * us / per
    }
    if (k != nc) { printf "count mismatch: %d intervals announced, %d measured\n", k, nc; exit 1 }
  }' "$OUT/qemu.log" "$OUT/counts.txt"

echo
echo "== Percentiles of the same intervals (instructions)"
off=0
grep '^BENCH' "$OUT/qemu.log" | while read -r _ label n; do
  sed -n "$((off + 1)),$((off + n))p" "$OUT/counts.txt" | sort -n |
    awk -v l="$label" '{ a[NR] = $1 } END {
      i50 = int((NR + 1) / 2); i99 = int(NR * 0.99); i999 = int(NR * 0.999)
      if (i99 < 1) i99 = 1
      if (i999 < 1) i999 = 1
      printf "%-32s p50 %9d  p99 %9d  p99.9 %9d\n", l, a[i50], a[i99], a[i999] }'
  off=$((off + n))
done

echo
echo "== Stack high-water marks (painted 64 KiB window, bytes below main's frame)"
grep '^STACK' "$OUT/qemu.log" | awk '{printf "%-16s %6d bytes\n", $2, $3}'

echo
echo "== Flash / RAM (llvm-size; text+rodata+vector table in flash, data+bss in RAM)"
"$SIZE" -A "$ELF" | awk '$1 ~ /^\.(vector_table|text|rodata|data|bss|uninit)$/ {printf "%-14s %8d\n", $1, $2}'
"$SIZE" -B "$ELF"
