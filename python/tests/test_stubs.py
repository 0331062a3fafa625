"""The type stubs ``crane_twin/_native.pyi`` match the extension module (issue 23: "mypy.stubtest
reports 39 mismatches"): ``python -m mypy.stubtest crane_twin._native`` reports none."""

from __future__ import annotations

import filecmp
import subprocess
import sys
from pathlib import Path

import pytest

import crane_twin

SOURCE_STUB = Path(__file__).resolve().parents[1] / "crane_twin" / "_native.pyi"


def test_stubtest_finds_no_mismatch(tmp_path):
    pytest.importorskip("mypy.stubtest", reason="mypy is not installed (pip install mypy)")
    installed = Path(crane_twin.__file__).resolve().parent / "_native.pyi"
    # stubtest reads the installed stub: it must be this checkout's
    assert installed.is_file(), f"{installed} is not installed with the package"
    if installed != SOURCE_STUB.resolve():
        assert filecmp.cmp(installed, SOURCE_STUB, shallow=False), (
            f"the installed {installed} differs from {SOURCE_STUB}: reinstall the package"
        )
    p = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "crane_twin._native"],
        cwd=tmp_path,  # away from python/, whose crane_twin has no built module
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stdout[-6000:] + p.stderr[-2000:]
    assert "Success: no issues found" in p.stdout
