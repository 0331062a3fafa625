#!/usr/bin/env bash
# The project's test command (README, .ci/run): installs what a fresh machine lacks, then
# runs formatting, lints, the firmware cross build, every host test and the QEMU cross-checks.
set -euo pipefail
cd "$(dirname "$0")/.."

# Each step prints the elapsed seconds and the disk left (a CI machine once ran out of it).
step() { printf '\n==> [%ss, %s free] %s\n' "$SECONDS" "$(df -Ph . | awk 'NR==2{print $4}')" "$*"; }

# A test run is not an edit loop: incremental caches would add gigabytes to the target dir.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

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
# real-board build (`board`: clock, TIM1 PWM, encoder timers, pins; `probe`: defmt over RTT)
# and the on-target tests, then the QEMU netduinoplus2 build LAST (same ELF path) for
# host-tests/tests/stm32_board.rs (the `stm32_*` tests, run with --include-ignored below).
# Every board-stm32 link goes through flip-link (stack below .data/.bss: an overflow faults),
# passed to this crate's links only (`cargo rustc -- -C linker=flip-link`): the firmware/
# crate keeps the target's default linker. `cargo install flip-link` if missing: 16 s.
step "board-stm32: clippy, flip-link, board build, QEMU build"
if ! command -v flip-link >/dev/null 2>&1; then
  step "installing flip-link (cargo install)"
  cargo install flip-link --locked
fi
for feats in "" "board" "probe" "board,probe"; do
  cargo clippy -p board-stm32 --target thumbv7em-none-eabihf --features "$feats" -- -D warnings
done
cargo clippy -p board-stm32 --target thumbv7em-none-eabihf --features board,probe --all-targets -- -D warnings
board_link() { cargo rustc -p board-stm32 --target thumbv7em-none-eabihf --release "$@" -- -C linker=flip-link; }
board_link --bin board-stm32 --features board,probe
# the defmt-test on-target tests: built here, run on a board by `probe-rs run`
board_link --test on_target --features board,probe
board_link --bin board-stm32
# --- end board-stm32

step "host tests (including the QEMU cross-checks, marked ignored for plain cargo test)"
cargo test --workspace --exclude firmware --exclude board-stm32 -- --include-ignored

# ---- FMU (issue 13): build crane.fmu, FMPy validates and simulates it ------------------
# The C-ABI tests (`cargo test -p crane-fmu`) ran with the host tests above. Here: the packed
# FMU through FMPy (validation, bit-exact trajectory against `crane simulate`, wrong
# parameter, step not a multiple of h, 1,000 instantiate/reset/free cycles without RSS
# growth). Measured on the 2-core dev machine: 6.5 s warm (builds up to date, venv present;
# pytest itself 3 s); cold, add the venv with fmpy + pytest (36 s) and the release builds of
# the FMU (1.4 min) and of `crane` (user time 1.5 min; 6 min wall at load average 10).
step "FMU: build crane.fmu, FMPy + pytest"
ensure_venv() {
  local venv="${CARGO_TARGET_DIR:-target}/venv"
  if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" || {
      SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
      $SUDO apt-get update -qq
      DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends python3-venv
      python3 -m venv "$venv"
    }
  fi
  "$venv/bin/python" -m pip install -q "$@"
  VENV_PY="$venv/bin/python"
}
fmu_target="${CARGO_TARGET_DIR:-target}"
case "$fmu_target" in /*) ;; *) fmu_target="$PWD/$fmu_target" ;; esac
bash scripts/build-fmu.sh "$fmu_target/crane.fmu"
cargo build --release --bin crane
ensure_venv "fmpy>=0.3.32,<0.4" pytest
# (its pytest runs after the python block: the FMU with stiction and the tanh law is compared
# bit for bit with `crane_twin`, which is installed there)
# ---- end FMU ------------------------------------------------------------------------------

# ---- python (issue 12): the `crane_twin` package in the shared venv, then its pytest -------
# (bit-exactness against the `crane` CLI built above, Gymnasium check_env, seeded episodes,
# bad input, the Ray example with 2 local workers). Measured: see BENCHMARKS.md "Python".
python_venv() {
  # The one shared venv of the CI; created if missing (other blocks may call this too).
  local venv="${CARGO_TARGET_DIR:-target}/venv"
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
  (cd "$venv" && pwd)
}
step "python: crane_twin (venv, pip install ./python, pytest python/tests)"
venv="$(python_venv)"
"$venv/bin/python" -m pip install -q --disable-pip-version-check \
  maturin==1.16.0 numpy==2.4.6 gymnasium==1.4.0 ray==2.60.0 pytest==9.2.0
# Built with the venv's maturin (its PEP 517 hook runs `maturin` from PATH).
PATH="$venv/bin:$PATH" "$venv/bin/python" -m pip install -q --disable-pip-version-check \
  --no-build-isolation ./python
CRANE_BIN="$fmu_target/release/crane" RAY_USAGE_STATS_ENABLED=0 \
  "$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests
step "FMU: FMPy + pytest (against crane simulate and crane_twin)"
CRANE_FMU="$fmu_target/crane.fmu" CRANE_BIN="$fmu_target/release/crane" \
  "$VENV_PY" -m pytest -q -p no:cacheprovider fmu/tests/test_fmu.py
# ---- end python ----------------------------------------------------------------------------

# ---- scipy peer (issue 15): tools/scripts/scipy_peer.py's physics and event loop, in the
# shared venv (numpy from the block above). The full timing run is not for CI (~100 s loaded).
step "scipy peer: pytest tools/scripts/test_scipy_peer.py"
"$venv/bin/python" -m pip install -q --disable-pip-version-check scipy==1.17.1
"$venv/bin/python" -m pytest -q -p no:cacheprovider tools/scripts/test_scipy_peer.py
# ---- end scipy peer ------------------------------------------------------------------------

# ---- strangers (issue 20): an independent single-axis plant (tools/strangers: numpy only,
# written from a physics spec without reading diagnose/): its physics tests, and the sweep of
# the release `crane diagnose` over its 70 seeded cases (about 5 min on 2 idle cores): no
# crash or timeout, no honesty failure (a diverged figure, a delay in samples only, a finding
# at a grid edge), and the per-cause floors of test_strangers.py.
step "strangers: the independent plant's tests and the diagnose sweep"
CRANE_BIN="$fmu_target/release/crane" STRANGERS_TIMEOUT=200 \
  "$venv/bin/python" -m pytest -q -p no:cacheprovider tools/strangers/test_strangers.py
# ---- end strangers -------------------------------------------------------------------------

step "done (target directory: $(du -sh "${CARGO_TARGET_DIR:-target}" | cut -f1))"
