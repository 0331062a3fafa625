"""Every Python snippet of the README that uses crane_twin runs as written after
``pip install ./python``, in an empty folder (issue 23: the first one needed a params.toml
and matplotlib)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def _snippets():
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    return [b for b in blocks if "crane_twin" in b]


def test_the_readme_has_crane_twin_snippets():
    assert len(_snippets()) >= 2


@pytest.mark.parametrize("code", _snippets(), ids=lambda c: c.splitlines()[0][:40])
def test_readme_snippet_runs_as_written(code, tmp_path, monkeypatch):
    if "gymnasium" in code:
        pytest.importorskip("gymnasium")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"__name__": "__readme__"})
