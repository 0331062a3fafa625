"""The package as a user installs it (issue 23, "install without Rust").

Always: one version everywhere (``python/Cargo.toml``, the installed distribution,
``crane_twin.__version__``, the top release of ``python/CHANGELOG.md``) and an abi3 extension.

With ``CRANE_TWIN_WHEEL_TEST=1`` (set by the python block of ``scripts/test.sh``, which runs
these tests against the wheel it built, with a PATH of only the test venv's ``bin``,
``/usr/bin`` and ``/bin``): ``crane_twin`` is imported from the venv's site-packages, installed
from a ``.whl`` file, with an abi3 manylinux tag, and no Rust toolchain is reachable."""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
import sysconfig
from importlib import metadata
from pathlib import Path

import pytest

import crane_twin

ROOT = Path(__file__).resolve().parents[2]
FROM_WHEEL = os.environ.get("CRANE_TWIN_WHEEL_TEST") == "1"
DIST = "crane-twin"

wheel_only = pytest.mark.skipif(
    not FROM_WHEEL, reason="CRANE_TWIN_WHEEL_TEST=1 is set by CI's wheel run only"
)


def _toml_value(path: Path, table: str, key: str) -> str:
    """A string value of a TOML table, without tomllib (Python 3.10 has none)."""
    text = path.read_text(encoding="utf-8")
    section = re.search(rf"^\[{re.escape(table)}\]\s*$(.*?)(?=^\[|\Z)", text, flags=re.M | re.S)
    assert section, f"{path}: no [{table}]"
    m = re.search(rf'^{re.escape(key)}\s*=\s*"([^"]*)"', section.group(1), flags=re.M)
    assert m, f"{path}: no {key} in [{table}]"
    return m.group(1)


def _cargo_version() -> str:
    return _toml_value(ROOT / "python" / "Cargo.toml", "package", "version")


def test_pyproject_takes_the_version_from_cargo():
    text = (ROOT / "python" / "pyproject.toml").read_text(encoding="utf-8")
    project = re.search(r"^\[project\]\s*$(.*?)(?=^\[|\Z)", text, flags=re.M | re.S).group(1)
    assert re.search(r'^dynamic\s*=\s*\[[^\]]*"version"', project, flags=re.M), (
        "pyproject.toml: [project] must declare dynamic = [\"version\"] (the version is Cargo.toml's)"
    )
    assert not re.search(r"^version\s*=", project, flags=re.M), (
        "pyproject.toml: a static [project] version would drift from python/Cargo.toml's"
    )


def test_installed_version_is_the_crates():
    cargo = _cargo_version()
    installed = metadata.version(DIST)
    assert installed == cargo, f"installed {DIST} {installed}, python/Cargo.toml says {cargo}: reinstall"
    assert crane_twin.__version__ == cargo, (
        f"crane_twin.__version__ is {crane_twin.__version__}, python/Cargo.toml says {cargo}"
    )


def test_changelog_has_the_version():
    text = (ROOT / "python" / "CHANGELOG.md").read_text(encoding="utf-8")
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+[^\]]*)\]", text, flags=re.M)
    assert releases, "python/CHANGELOG.md has no '## [X.Y.Z]' release heading"
    assert releases[0] == _cargo_version(), (
        f"python/CHANGELOG.md's latest release is {releases[0]}, python/Cargo.toml says {_cargo_version()}"
    )


def test_extension_is_abi3():
    native = Path(crane_twin._native.__file__).name
    if sys.platform.startswith("linux") or sys.platform == "darwin":
        assert native.endswith(".abi3.so"), f"{native}: not a stable-ABI (abi3) build"


def test_ci_passes_crane_bin():
    """In CI a missing CRANE_BIN must fail, not start a cargo build (issue 23, item 8)."""
    if not os.environ.get("CI"):
        pytest.skip("CI is not set")
    crane_bin = os.environ.get("CRANE_BIN")
    assert crane_bin, "CI is set but CRANE_BIN is not: scripts/test.sh passes it"


@wheel_only
def test_imported_from_site_packages_not_the_source_tree():
    pkg = Path(crane_twin.__file__).resolve().parent
    source = (ROOT / "python" / "crane_twin").resolve()
    assert pkg != source, f"crane_twin imported from the source tree {source}"
    site = {Path(sysconfig.get_path(k)).resolve() for k in ("platlib", "purelib")}
    assert pkg.parent in site, f"crane_twin imported from {pkg}, not from {sorted(map(str, site))}"
    assert Path(sys.prefix).resolve() != Path(sys.base_prefix).resolve(), "not run in a venv"


@wheel_only
def test_no_rust_toolchain_on_path():
    found = {t: shutil.which(t) for t in ("cargo", "rustc", "rustup")}
    assert all(v is None for v in found.values()), f"a Rust toolchain is reachable: {found}"


@wheel_only
def test_installed_from_an_abi3_manylinux_wheel():
    dist = metadata.distribution(DIST)
    direct = dist.read_text("direct_url.json")
    if direct is not None:  # pip writes it for a file path; absent for an index install
        url = json.loads(direct)["url"]
        assert url.endswith(".whl"), f"installed from {url}, not from a wheel"
    wheel = dist.read_text("WHEEL") or ""
    tags = re.findall(r"^Tag:\s*(\S+)", wheel, flags=re.M)
    assert tags and all("-abi3-" in t for t in tags), f"wheel tags {tags}: not abi3"
    if sys.platform.startswith("linux"):
        assert any("manylinux" in t for t in tags), f"wheel tags {tags}: not manylinux"


@wheel_only
def test_wheel_carries_both_licences():
    """The wheel holds the texts of both licences it is offered under (MIT OR Apache-2.0):
    a redistributed binary must carry them."""
    dist = metadata.distribution(DIST)
    names = {Path(str(f)).name for f in dist.files or []}
    for licence in ("LICENSE-MIT", "LICENSE-APACHE"):
        assert licence in names, f"{licence} is not in the installed wheel's files: {sorted(names)}"
    mit = next(f for f in dist.files if Path(str(f)).name == "LICENSE-MIT")
    assert "Permission is hereby granted" in mit.read_text(encoding="utf-8")
