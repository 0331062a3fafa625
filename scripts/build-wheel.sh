#!/usr/bin/env bash
# Builds the `crane_twin` abi3 wheel(s) with maturin (issue 23, "install without Rust").
#
#   scripts/build-wheel.sh OUT_DIR [PYTHON]
#
# OUT_DIR gets exactly one crane_twin-*.whl per target built (older ones there are removed);
# their paths are printed last, one a line, after a line "wheels:". PYTHON is an interpreter
# with maturin installed (default: python3 on PATH); the wheel is abi3 (CPython >= 3.10), so
# which CPython builds it does not matter.
#
# Linux x86_64, always. The manylinux tag:
#  - with zig (CRANE_WHEEL_ZIG=1, or `auto`, the default, when PYTHON can run `-m ziglang` or
#    `zig` is on PATH): `--zig --compatibility manylinux2014`, i.e. linked against glibc
#    2.17's symbol versions: manylinux2014_x86_64 (manylinux_2_17), for any glibc >= 2.17.
#    `pip install ziglang` brings zig (a PyPI package).
#  - without zig (CRANE_WHEEL_ZIG=0): maturin links against this machine's glibc (2.36 here)
#    and its built-in auditwheel check tags the lowest policy the symbols allow:
#    manylinux_2_34_x86_64 here (Rust's std pulls GLIBC_2.34 symbols), for glibc >= 2.34.
#    `--compatibility manylinux2014` without zig fails here ("too-recent versioned symbols");
#    the other way to it is a manylinux container, and no Docker engine runs on this machine.
# Other targets (aarch64 Linux, macOS) only if their Rust standard library is installed
# (`rustup target list --installed`); otherwise the script says which were not built and why.
set -euo pipefail
cd "$(dirname "$0")/.."

out="${1:?usage: scripts/build-wheel.sh OUT_DIR [PYTHON]}"
py="${2:-python3}"
zig="${CRANE_WHEEL_ZIG:-auto}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
# absolute (the builds run in python/), the venv's own path kept (no symlink resolved)
py="$(command -v "$py")" || { echo "build-wheel: no interpreter $py" >&2; exit 1; }
py="$(cd "$(dirname "$py")" && pwd)/$(basename "$py")"
rm -f "$out"/crane_twin-*.whl

have_zig() { command -v zig >/dev/null 2>&1 || "$py" -m ziglang version >/dev/null 2>&1; }
if [ "$zig" = auto ]; then
  if have_zig; then zig=1; else zig=0; fi
fi
if [ "$zig" = 1 ] && ! have_zig; then
  echo "build-wheel: CRANE_WHEEL_ZIG=1 but no zig (pip install ziglang)" >&2
  exit 1
fi

# maturin's zig support runs `python3 -m ziglang` when `zig` is not on PATH: put PYTHON's
# directory first so that python3 is the one with ziglang.
py_dir="$(dirname "$py")"
maturin() { PATH="$py_dir:$PATH" "$py" -m maturin "$@"; }

build() {  # build TARGET_TRIPLE extra-args...
  local triple="$1"; shift
  echo "build-wheel: $triple $*"
  (cd python && maturin build --release --target "$triple" -i "$py" -o "$out" "$@")
}

host="x86_64-unknown-linux-gnu"
if [ "$zig" = 1 ]; then
  build "$host" --zig --compatibility manylinux2014
else
  # No --target: the same artifact directory (target/release) as the workspace's release
  # builds, so the dependencies `crane` was built with are reused.
  echo "build-wheel: $host (no zig: tagged by maturin's auditwheel check)"
  (cd python && maturin build --release -i "$py" -o "$out")
fi

installed="$(rustup target list --installed 2>/dev/null || true)"
for triple in aarch64-unknown-linux-gnu x86_64-apple-darwin aarch64-apple-darwin; do
  if grep -qx "$triple" <<<"$installed"; then
    case "$triple" in
      *-linux-gnu)
        if [ "$zig" = 1 ]; then build "$triple" --zig --compatibility manylinux2014
        else echo "build-wheel: $triple not built: cross-linking needs zig (pip install ziglang)"; fi ;;
      *-apple-darwin)
        if [ "$zig" = 1 ] && [ -n "${SDKROOT:-}" ]; then build "$triple" --zig
        else echo "build-wheel: $triple not built: needs zig and a macOS SDK (SDKROOT)"; fi ;;
    esac
  else
    echo "build-wheel: $triple not built: its Rust standard library is not installed" \
      "(rustup target add $triple, which needs a download this machine cannot make)"
  fi
done

echo "wheels:"
ls -1 "$out"/crane_twin-*.whl
