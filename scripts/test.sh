#!/usr/bin/env bash
# The project's test command (README, .ci/run): installs what a fresh machine lacks, then
# runs formatting, lints, the firmware cross build, every host test and the QEMU cross-checks.
set -euo pipefail
cd "$(dirname "$0")/.."

# Each step prints the elapsed seconds and the disk left (a CI machine once ran out of it).
step() { printf '\n==> [%ss, %s free] %s\n' "$SECONDS" "$(df -Ph . | awk 'NR==2{print $4}')" "$*"; }

# A test run is not an edit loop: incremental caches would add gigabytes to the target dir.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

# Steps that run in the background (QEMU, the strangers sweep) do not outlive a failed step.
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT

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

# The firmware's QEMU run (mps2-an386) is one emulator thread for about a minute: it runs in
# the background on a copy of the ELF while the firmware and board-stm32 lints and links below
# (mostly one crate at a time, one core) use the other core; it is waited for, and its exit
# status checked, after the board-stm32 block. The command is the runner of .cargo/config.toml
# (`cargo run -p firmware --target thumbv7em-none-eabihf --release` runs the same).
step "firmware cross build (release), then under QEMU (mps2-an386) in the background"
cargo build -p firmware --target thumbv7em-none-eabihf --release
fw_dir="${CARGO_TARGET_DIR:-target}/thumbv7em-none-eabihf/release"
cp "$fw_dir/firmware" "$fw_dir/firmware-qemu-run.elf"
qemu_log="${CARGO_TARGET_DIR:-target}/qemu-run.log"
timeout 300 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic \
  -semihosting-config enable=on,target=native -kernel "$fw_dir/firmware-qemu-run.elf" \
  > "$qemu_log" 2>&1 < /dev/null &
qemu_pid=$!

step "clippy (firmware, thumbv7em-none-eabihf)"
cargo clippy -p firmware --target thumbv7em-none-eabihf -- -D warnings
cargo clippy -p firmware --target thumbv7em-none-eabihf --features probe -- -D warnings && cargo build -p firmware --target thumbv7em-none-eabihf --release --features probe
cargo build -p firmware --target thumbv7em-none-eabihf --release  # the ELF the host tests run

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

step "firmware under QEMU (mps2-an386): the run started after the cross build"
qemu_rc=0; wait "$qemu_pid" || qemu_rc=$?
tail -n 3 "$qemu_log"
[ "$qemu_rc" -eq 0 ] || { echo "firmware under QEMU failed (exit $qemu_rc; 124 = the 300 s timeout): $qemu_log" >&2; exit 1; }

step "host tests (including the QEMU cross-checks, marked ignored for plain cargo test)"
# `cargo test` runs its binaries one after another and holds the build lock while they run: a
# binary whose last test runs alone leaves a core idle. The binaries are built here and run
# two at a time, the slowest first (scripts/run-test-binaries.py; same binaries, arguments,
# working directories), then the doctests. Plain `cargo test --workspace --exclude firmware
# --exclude board-stm32 -- --include-ignored` runs the same tests one binary at a time.
host_tests_json="${CARGO_TARGET_DIR:-target}/host-tests.json"
cargo test --workspace --exclude firmware --exclude board-stm32 --no-run --message-format=json-render-diagnostics > "$host_tests_json"
python3 scripts/run-test-binaries.py --jobs 2 -- --include-ignored < "$host_tests_json"
cargo test --workspace --exclude firmware --exclude board-stm32 --doc
# The `crane` binary the test build made (test profile: opt-level 2, no LTO, debug assertions
# and overflow checks on), for the strangers sweep, the FMU's and the wheel's comparisons
# below. A release build of it took 288 s of the CI (4m48s, 2026-11-28) and runs no faster:
# `crane diagnose` on six stranger cases took 0.92-1.01 times the release binary's wall time,
# with byte-identical reports, and the FMU's and the wheel's bit-for-bit tests pass with it
# (2026-11-29, idle). The path is read from the build's own messages, not guessed.
crane_bin="$(python3 -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line) if line.startswith("{") else {}
    t = m.get("target", {})
    if m.get("reason") == "compiler-artifact" and t.get("name") == "crane" and "bin" in t.get("kind", []) and not m["profile"]["test"]:
        print(m["executable"])
' < "$host_tests_json")"
[ -x "$crane_bin" ] || { echo "the test build made no crane binary (read from $host_tests_json)" >&2; exit 1; }
echo "crane: $crane_bin"

# ---- FMU (issue 13): build crane.fmu, FMPy validates and simulates it ------------------
# The C-ABI tests (`cargo test -p crane-fmu`) ran with the host tests above. Here: the packed
# FMU through FMPy (validation, bit-exact trajectory against `crane simulate`, wrong
# parameter, step not a multiple of h, 1,000 instantiate/reset/free cycles without RSS
# growth). Measured on the 2-core dev machine: 6.5 s warm (builds up to date, venv present;
# pytest itself 3 s); cold, add the venv with fmpy + pytest (36 s) and the release build of
# the FMU (1.4 min). `crane` is the test build's ($crane_bin, above).
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
ensure_venv "fmpy>=0.3.32,<0.4" pytest==9.2.0 numpy==2.4.6
# ---- strangers (issue 20), started as soon as numpy is there (`crane` is), waited for at the
# end: an independent single-axis plant (tools/strangers: numpy only, written from a physics
# spec without reading diagnose/): its physics tests, and the sweep of `crane diagnose` (the
# test build's) over its 70 seeded cases (about 5 min on 2 idle cores): no crash or timeout, no
# honesty failure (a diverged figure, a delay in samples only, a finding at a grid edge), and
# the per-cause floors of test_strangers.py. It runs beside the FMU and python blocks below,
# which wait on downloads, single-threaded pytest runs and link-time optimisation much of
# their time. The shared venv gets numpy and pytest at the versions the python block pins, so
# that block installs nothing over them while the sweep runs. The per-case timeout is a hang
# guard, not a speed figure: 300 s, where the slowest case took 101 s alone on 2 idle cores
# (the published set, 2026-11-27; s032, 6.3 s since 2026-11-29: a refinement no longer
# simulates an inertia the log cannot resolve; now s023, 27 s with 2 jobs) and may share
# them with the FMU's and the wheel's builds.
# The binary is the test build's `crane` (debug assertions on: one failing is a crash here).
strangers_log="$fmu_target/strangers.log"
CRANE_BIN="$crane_bin" STRANGERS_TIMEOUT=300 \
  "$VENV_PY" -m pytest -q -p no:cacheprovider tools/strangers/test_strangers.py \
  > "$strangers_log" 2>&1 < /dev/null &
strangers_pid=$!
bash scripts/build-fmu.sh "$fmu_target/crane.fmu"
# (its pytest runs after the python block: the FMU with stiction and the tanh law is compared
# bit for bit with `crane_twin`, which is installed there)
# ---- end FMU ------------------------------------------------------------------------------

# ---- python (issue 12; issue 23 "install without Rust"): the `crane_twin` wheel, built once,
# tested as a user installs it, then its API reference --------------------------------------
# scripts/build-wheel.sh builds the abi3 wheel (CPython >= 3.10) with maturin and zig (PyPI's
# ziglang): manylinux2014 (glibc >= 2.17). It goes into a clean venv, new each run, with only
# its dependencies and the test tools, and python/tests run against it with a PATH of that
# venv's bin, /usr/bin and /bin: no cargo, no rustc (test_wheel.py checks that, and that
# crane_twin comes from that venv's site-packages, installed from the .whl). CRANE_BIN is the
# test build's `crane` (above; test_bits.py compares with it; without it the tests would
# fail here, not build). The shared venv gets the same wheel (the FMU comparison below, the
# API reference, the blocks after). Measured 2026-11-27 (2 shared cores, load average 3; fresh
# venv, `crane` built, the extension not): 107 s, of which the wheel build 78 s and pytest 10 s;
# the former block (pip install ./python, pytest in the shared venv) took 80 s. CRANE_WHEEL_ZIG=0
# builds without zig (manylinux_2_34 tag, glibc >= 2.34): 95 s.
python_venv() {
  # The one shared venv of the CI; created if missing (other blocks may call this too).
  local venv="${CARGO_TARGET_DIR:-target}/venv"
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
  (cd "$venv" && pwd)
}
step "python: crane_twin wheel (scripts/build-wheel.sh; maturin + zig, manylinux2014)"
venv="$(python_venv)"
"$venv/bin/python" -m pip install -q --disable-pip-version-check \
  maturin==1.16.0 ziglang==0.17.1 numpy==2.4.6 gymnasium==1.4.0 pytest==9.2.0 pdoc==16.0.0
# The clean venv, new each run, has no pip of its own (the shared venv's pip installs into it,
# 5 s less); its dependencies download and install while the wheel builds (10 s less). mypy:
# test_stubs.py's stubtest of the installed _native.pyi (skipped without it; 5 s).
wheel_venv="$fmu_target/venv-wheel"
rm -rf "$wheel_venv"
python3 -m venv --without-pip "$wheel_venv"
wheel_pip() { "$venv/bin/python" -m pip --python "$wheel_venv/bin/python" "$@"; }
wheel_pip install -q --disable-pip-version-check \
  numpy==2.4.6 gymnasium==1.4.0 ray==2.60.0 pytest==9.2.0 mypy==2.4.1 > "$fmu_target/venv-wheel.log" 2>&1 &
wheel_deps=$!
bash scripts/build-wheel.sh "$fmu_target/wheels-ci" "$venv/bin/python" || { kill "$wheel_deps"; exit 1; }
wheel="$(ls "$fmu_target"/wheels-ci/crane_twin-*-abi3-manylinux*_x86_64.whl)"
ls -l "$wheel"
wait "$wheel_deps" || { cat "$fmu_target/venv-wheel.log" >&2; exit 1; }
wheel_pip install -q --disable-pip-version-check --no-deps "$wheel"
wheel_pip check --disable-pip-version-check
"$venv/bin/python" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$wheel"

step "python: the wheel in a clean venv without cargo on the PATH, pytest python/tests"
no_rust_path="$wheel_venv/bin:/usr/bin:/bin"
rust_found="$(env PATH="$no_rust_path" bash -c 'command -v cargo rustc rustup' || true)"
[ -z "$rust_found" ] || { echo "Rust is reachable on $no_rust_path: $rust_found" >&2; exit 1; }
PATH="$no_rust_path" CRANE_TWIN_WHEEL_TEST=1 CRANE_BIN="$crane_bin" RAY_USAGE_STATS_ENABLED=0 \
  "$wheel_venv/bin/python" -m pytest -q -p no:cacheprovider python/tests

step "python: API reference (pdoc) into ${CARGO_TARGET_DIR:-target}/api"
rm -rf "$fmu_target/api"
"$venv/bin/python" scripts/build-api-docs.py "$fmu_target/api"
step "FMU: FMPy + pytest (against crane simulate and crane_twin)"
CRANE_FMU="$fmu_target/crane.fmu" CRANE_BIN="$crane_bin" \
  "$VENV_PY" -m pytest -q -p no:cacheprovider fmu/tests/test_fmu.py
# ---- end python ----------------------------------------------------------------------------

# ---- scipy peer (issue 15): tools/scripts/scipy_peer.py's physics and event loop, in the
# shared venv (numpy from the block above). The full timing run is not for CI (~100 s loaded).
step "scipy peer: pytest tools/scripts/test_scipy_peer.py"
"$venv/bin/python" -m pip install -q --disable-pip-version-check scipy==1.17.1
"$venv/bin/python" -m pytest -q -p no:cacheprovider tools/scripts/test_scipy_peer.py
# ---- end scipy peer ------------------------------------------------------------------------

step "strangers: the independent plant's tests and the diagnose sweep (started after the FMU block's venv)"
strangers_rc=0; wait "$strangers_pid" || strangers_rc=$?
cat "$strangers_log"
[ "$strangers_rc" -eq 0 ] || { echo "strangers: pytest failed (exit $strangers_rc)" >&2; exit 1; }
# ---- end strangers -------------------------------------------------------------------------

step "done (target directory: $(du -sh "${CARGO_TARGET_DIR:-target}" | cut -f1))"
