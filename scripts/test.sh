#!/usr/bin/env bash
# The project's test command (README, .ci/run): installs what a fresh machine lacks, then
# runs formatting, lints, the firmware cross build, every host test and the QEMU cross-checks.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "toolchain parts"
rustup target add thumbv7em-none-eabihf
rustup component add rustfmt clippy >/dev/null 2>&1 || true
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  step "installing qemu-system-arm (Debian)"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends qemu-system-arm
fi

step "cargo fmt --check"
cargo fmt --all -- --check

step "clippy (host crates, all targets)"
cargo clippy --workspace --exclude board-stm32 --all-targets -- -D warnings  # board-stm32: thumbv7em only (its block below)

step "clippy (firmware, thumbv7em-none-eabihf)"
cargo clippy -p firmware --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p firmware --target thumbv7em-none-eabihf --features probe -- -D warnings && cargo build -p firmware --target thumbv7em-none-eabihf --release --features probe

step "firmware cross build (release)"
cargo build -p firmware --target thumbv7em-none-eabihf --release

step "firmware under QEMU (mps2-an386)"
qemu_log="${CARGO_TARGET_DIR:-target}/qemu-run.log"
timeout 300 cargo run -q -p firmware --target thumbv7em-none-eabihf --release > "$qemu_log"
tail -n 3 "$qemu_log"

# --- board-stm32 (issue 14): the STM32F405/407 firmware. Lints every feature set, links the
# real-board build (`board`: clock, TIM1 PWM, encoder timers, pins; `probe`: defmt over RTT),
# then builds the QEMU netduinoplus2 build LAST (same ELF path) for
# host-tests/tests/stm32_board.rs (the `stm32_*` tests, run with --include-ignored below).
step "board-stm32: clippy, board build, QEMU build"
for feats in "" "board" "probe" "board,probe"; do
  cargo clippy -p board-stm32 --target thumbv7em-none-eabihf --features "$feats" -- -D warnings
done
cargo clippy -p board-stm32 --target thumbv7em-none-eabihf --features board,probe --all-targets -- -D warnings
cargo build -p board-stm32 --target thumbv7em-none-eabihf --release --features board,probe
# the defmt-test on-target tests: built here, run on a board by `probe-rs run`
cargo build -p board-stm32 --target thumbv7em-none-eabihf --release --features board,probe --tests
cargo build -p board-stm32 --target thumbv7em-none-eabihf --release
# --- end board-stm32

step "host tests (including the QEMU cross-checks, marked ignored for plain cargo test)"
cargo test --workspace --exclude firmware --exclude board-stm32 -- --include-ignored
