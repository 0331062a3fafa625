"""Renders the API reference of the installed ``crane_twin`` with pdoc (issue 23).

    python scripts/build-api-docs.py [OUT_DIR]        # default: target/api

Writes ``OUT_DIR/crane_twin.html`` (the package: ``Crane``, ``rollout``, ...), one page per
public submodule (``crane_twin/envs.html``, ...) and ``index.html``. Exits non-zero when pdoc
warns (an import error, a stub or annotation it cannot read, a broken cross-reference) or a
page is missing. Public names without a docstring are listed; with ``--strict`` they fail too.
pdoc reads the signatures and types of the extension module from ``_native.pyi``.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
import warnings
from pathlib import Path

import pdoc
import pdoc.doc
import pdoc.render

MODULE = "crane_twin"


def public_modules() -> list[str]:
    """The package and its submodules without a leading underscore (``crane_twin.envs``, ...;
    pdoc itself lists none because the package's ``__all__`` names no submodule)."""
    pkg = importlib.import_module(MODULE)
    subs = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))
    return [MODULE] + [f"{MODULE}.{s}" for s in subs]


def undocumented(module: pdoc.doc.Module) -> list[str]:
    """Public classes, functions and methods (pdoc's own selection: ``__all__``, no leading
    underscore) whose docstring is empty."""
    missing: list[str] = []

    def walk(ns: pdoc.doc.Namespace) -> None:
        for m in ns.members.values():
            if m.name.startswith("_") or m.is_inherited:
                continue
            if isinstance(m, (pdoc.doc.Class, pdoc.doc.Function)) and not m.docstring.strip():
                missing.append(m.fullname)
            if isinstance(m, pdoc.doc.Class) and m.modulename.startswith(MODULE):
                walk(m)

    walk(module)
    return missing


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", nargs="?", default="target/api", type=Path)
    ap.add_argument("--strict", action="store_true", help="fail on public names without a docstring")
    args = ap.parse_args()

    # The docstrings are Markdown-compatible reST (``code``, *emphasis*); "markdown" renders
    # ``x`` as code and leaves :class:`X` roles readable.
    pdoc.render.configure(docformat="markdown", search=True, show_source=False, footer_text="crane_twin API")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        names = public_modules()
        pdoc.pdoc(*names, output_directory=args.out)
        missing = [n for name in names for n in undocumented(pdoc.doc.Module.from_name(name))]
    problems = [w for w in caught if "pdoc" in (w.filename or "") or issubclass(w.category, UserWarning)]
    for w in problems:
        print(f"build-api-docs: pdoc warning: {w.category.__name__}: {w.message}", file=sys.stderr)

    pages = [args.out / "index.html"] + [args.out / (n.replace(".", "/") + ".html") for n in names]
    absent = [str(p) for p in pages if not p.is_file()]
    for p in absent:
        print(f"build-api-docs: page not written: {p}", file=sys.stderr)

    if missing:
        print(f"build-api-docs: {len(missing)} public names without a docstring: {', '.join(missing)}")
    print(f"build-api-docs: {len(names)} pages in {args.out} ({', '.join(names)}); {len(problems)} pdoc warnings")
    failed = bool(problems or absent or (args.strict and missing))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
