#!/usr/bin/env bash
# Builds the crane model as an FMI 2.0 co-simulation FMU (issue 13):
#   scripts/build-fmu.sh [OUT.fmu]      (default: crane.fmu in the workspace root)
# Needs only cargo (the packer is a Rust binary of the `fmu/` crate; no zip tool).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/crane.fmu}"
target="${CARGO_TARGET_DIR:-$root/target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
cd "$root"
cargo build --release -p crane-fmu --lib --bin crane-fmu-pack
"$target/release/crane-fmu-pack" --lib "$target/release/libcrane_fmu.so" --out "$out"
