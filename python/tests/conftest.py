"""Shared helpers: the repository root and the `crane` CLI built from it."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _target_dir() -> Path:
    t = os.environ.get("CARGO_TARGET_DIR")
    return Path(t) if t else ROOT / "target"


@pytest.fixture(scope="session")
def crane_cli() -> Path:
    """The `crane` binary, built (or brought up to date) by cargo from this checkout with the
    `test` profile (the artifacts `cargo test --workspace` already built in CI).

    Skips with a reason when cargo is absent, except under CI (`CI` set), where it fails."""
    cargo = shutil.which("cargo")
    if cargo is None:
        if os.environ.get("CI"):
            pytest.fail("cargo not found but CI is set: the bit-exactness test must run")
        pytest.skip("cargo not found: cannot build the `crane` CLI to compare against")
    subprocess.run(
        [cargo, "build", "-q", "--profile", "test", "-p", "crane-tools", "--bin", "crane"],
        cwd=ROOT,
        check=True,
    )
    exe = _target_dir() / "debug" / "crane"
    assert exe.is_file(), f"{exe} not built"
    return exe
