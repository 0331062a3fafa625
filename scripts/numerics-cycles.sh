#!/usr/bin/env bash
# Cortex-M4F figures of model/NUMERICS.md "nalgebra and micromath: measured, not used":
# builds host-tests/m4-numerics (its own workspace) for thumbv7em-none-eabihf, runs it under
# QEMU mps2-an386 with the firmware's cycle-model plugin (firmware/qemu-plugin/cycles.c, the
# models of scripts/firmware-cycles.sh) and prints, per candidate, instructions and cycles per
# call (mean / max); then the flash each candidate adds (`.text` of its `size_*` program minus
# `size_base`'s, llvm-size).
#
# Needs: qemu-system-arm, gcc, llvm-nm, llvm-size. Usage: scripts/numerics-cycles.sh (~3 min
# the first time, the build; then seconds).
set -euo pipefail
cd "$(dirname "$0")/.."

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

TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
cargo build -q --manifest-path host-tests/m4-numerics/Cargo.toml --target-dir "$TARGET_DIR" \
  --target thumbv7em-none-eabihf --release --bins
BIN="$TARGET_DIR/thumbv7em-none-eabihf/release"
ELF="$BIN/m4-numerics"
OUT="$TARGET_DIR/numerics-cycles"
mkdir -p "$OUT"
gcc -O2 -Wall -shared -fPIC -o "$OUT/cycles.so" firmware/qemu-plugin/cycles.c

START=$("$NM" "$ELF" | awk '$3=="bench_start"{print $1}')
STOP=$("$NM" "$ELF" | awk '$3=="bench_stop"{print $1}')
[ -n "$START" ] && [ -n "$STOP" ] && [ "$START" != "$STOP" ] || { echo "bench markers not found" >&2; exit 1; }

timeout 600 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$ELF" \
  -plugin "$OUT/cycles.so,start=0x$START,stop=0x$STOP,out=$OUT/cycles.txt" \
  </dev/null >"$OUT/qemu.log"
grep -q '^DONE ok' "$OUT/qemu.log" || { echo "run did not finish: see $OUT/qemu.log" >&2; exit 1; }

echo "== Per call on the Cortex-M4F (QEMU mps2-an386, cycle models of firmware/qemu-plugin/cycles.c)"
echo "   instructions and cycles mean / max; core = zero wait states, art = 5 WS behind the ART,"
echo "   apess = pessimistic flash with the ART (the firmware's headline model)"
awk '
  FNR == NR { if ($1 == "BENCH") { label[++nb] = $2; n[nb] = $3 } next }
  /^TOTAL/ || /^MIX/ { next }
  { ++nc; for (j = 1; j <= 5; j++) v[nc, j] = $j }
  END {
    printf "%-24s %4s | %17s | %17s | %17s | %17s\n", "call", "n", "insn mean/max", "core mean/max", "art mean/max", "apess mean/max"
    k = 0
    for (b = 1; b <= nb; b++) {
      for (j = 1; j <= 4; j++) { s[j] = 0; m[j] = 0 }
      for (i = 1; i <= n[b]; i++) {
        ++k
        for (j = 1; j <= 4; j++) { x = v[k, j]; s[j] += x; if (x > m[j]) m[j] = x }
      }
      printf "%-24s %4d", label[b], n[b]
      for (j = 1; j <= 4; j++) printf " | %8.1f %8d", s[j] / n[b], m[j]
      printf "\n"
    }
    if (k != nc) { printf "count mismatch: %d intervals announced, %d measured\n", k, nc; exit 1 }
  }' "$OUT/qemu.log" "$OUT/cycles.txt"

echo
echo "== Flash added (.text of size_<candidate> minus size_base, bytes; llvm-size)"
base=$("$SIZE" -A "$BIN/size_base" | awk '$1==".text"{print $2}')
printf "%-14s %8s %8s\n" "candidate" ".text" "added"
for c in fastmath libm micromath solve5_f32 lu_f32 cholesky_f32 solve5_f64 lu_f64 cholesky_f64; do
  t=$("$SIZE" -A "$BIN/size_$c" | awk '$1==".text"{print $2}')
  printf "%-14s %8d %8d\n" "$c" "$t" "$((t - base))"
done
printf "%-14s %8d\n" "base" "$base"
