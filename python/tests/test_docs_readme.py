"""Every Python snippet of ``python/README.md`` runs as written, each in a fresh interpreter in
an empty folder (no params.toml) where ``import matplotlib`` fails (no dependency), after
``pip install`` of the wheel (issue 23: "every README snippet runs in a test"; the repository
README's snippets are ``test_readme.py``'s)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "python" / "README.md"


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)


def _snippets() -> list[str]:
    return [b for b in _blocks("python") if "crane_twin" in b]


def test_the_readme_has_a_short_quick_start():
    snippets = _snippets()
    assert len(snippets) >= 2
    lines = [line for line in snippets[0].splitlines() if line.strip()]
    assert len(lines) <= 10, f"the quick start has {len(lines)} lines of code, not 10 or fewer"


def test_the_install_line_names_this_versions_wheel():
    cargo = (ROOT / "python" / "Cargo.toml").read_text(encoding="utf-8")
    version = re.search(r'^version\s*=\s*"([^"]+)"', cargo, flags=re.M).group(1)
    named = set(re.findall(r"crane_twin-(\d+\.\d+\.\d+)-cp\d+-abi3-", "".join(_blocks("sh"))))
    assert named == {version}, f"python/README.md installs wheel version(s) {named}, the crate is {version}"


@pytest.mark.parametrize("code", _snippets(), ids=lambda c: c.splitlines()[0][:40])
def test_python_readme_snippet_runs_as_written(code, tmp_path):
    if "gymnasium" in code:
        pytest.importorskip("gymnasium")
    blocked = tmp_path / "blocked"
    (blocked / "matplotlib").mkdir(parents=True)
    (blocked / "matplotlib" / "__init__.py").write_text(
        'raise ImportError("matplotlib is not a dependency of crane_twin: a README snippet imported it")\n'
    )
    work = tmp_path / "empty"
    work.mkdir()
    env = dict(os.environ, PYTHONPATH=str(blocked), MPLBACKEND="Agg")
    run = subprocess.run(
        [sys.executable, "-c", code],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, f"snippet failed:\n{code}\n--- stderr ---\n{run.stderr[-3000:]}"
