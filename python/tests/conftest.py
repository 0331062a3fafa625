"""Shared helpers: the repository root and the `crane` CLI built from it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _target_dir() -> Path:
    t = os.environ.get("CARGO_TARGET_DIR")
    return Path(t) if t else ROOT / "target"


@pytest.fixture(scope="session")
def crane_cli() -> Path:
    """The `crane` binary: `$CRANE_BIN` when set (CI passes the release binary its FMU block
    built), else built (or brought up to date) by cargo from this checkout in release, the
    same command as `scripts/test.sh` runs, so nothing is built twice.

    Skips with a reason when cargo is absent or `CRANE_NO_BUILD` is set (the installed
    package only), except under CI (`CI` set), where it fails. A build is announced on the
    terminal first: the first one takes minutes."""
    given = os.environ.get("CRANE_BIN")
    if given:
        exe = Path(given)
        assert exe.is_file(), f"CRANE_BIN={given} is not a file"
        return exe
    if os.environ.get("CI"):
        # CI passes the binary it built: a build here would hide a missing CRANE_BIN
        pytest.fail("CI is set but CRANE_BIN is not: pass the `crane` binary the CI built")
    if os.environ.get("CRANE_NO_BUILD"):
        pytest.skip("CRANE_NO_BUILD is set: the tests against the `crane` CLI need CRANE_BIN")
    cargo = shutil.which("cargo")
    if cargo is None:
        if os.environ.get("CI"):
            pytest.fail("cargo not found but CI is set: the bit-exactness test must run")
        pytest.skip("cargo not found: cannot build the `crane` CLI to compare against")
    print(
        "\ncrane_twin tests: CRANE_BIN is not set, so `cargo build --release --bin crane` "
        "runs now (minutes the first time; set CRANE_BIN to a built crane, or CRANE_NO_BUILD=1 "
        "to skip the tests that compare against it)",
        file=sys.__stderr__,
        flush=True,
    )
    subprocess.run(
        [cargo, "build", "-q", "--release", "--bin", "crane"],
        cwd=ROOT,
        check=True,
    )
    exe = _target_dir() / "release" / "crane"
    assert exe.is_file(), f"{exe} not built"
    return exe
