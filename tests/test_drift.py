"""Drift kept fixed (issue 32): what the docs list stays what the repository holds.

The README and the docs index list every tutorial and how-to; ``docs/explanation/design.md``
has a row for every module of ``speckle/`` (the map of rooms); no module grows past
:data:`MAX_LINES`; docstrings say what the code does.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "speckle"
DESIGN = REPO / "docs/explanation/design.md"
#: Longest module (lines): past it a module is split along its seams.
MAX_LINES = 800
PAGES = sorted([*(REPO / "docs/tutorials").glob("*.md"), *(REPO / "docs/howto").glob("*.md")])


def _module_names() -> list[str]:
    names = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(REPO).with_suffix("").parts
        names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_readme_lists_every_tutorial_and_howto(page):
    link = str(page.relative_to(REPO))
    assert f"]({link})" in (REPO / "README.md").read_text(), (
        f"README.md does not link {link}: add '  - [<title>]({link})' to its "
        f"{page.parent.name} list"
    )


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_docs_index_lists_every_tutorial_and_howto(page):
    index = (REPO / "docs/index.md").read_text()
    folder = page.parent.name
    entries = re.findall(r"^\s*([\w./*-]+)\s*$", index, flags=re.MULTILINE)
    listed = any(
        Path(folder, page.stem).match(e.removesuffix(".md")) or e == f"{folder}/*" for e in entries
    )
    assert listed, f"docs/index.md lists no {folder}/{page.stem}: add it to the {folder} toctree"


@pytest.mark.parametrize("module", _module_names())
def test_design_lists_every_module(module):
    rows = {
        m.group(1)
        for m in re.finditer(r"^\|\s*`([\w.]+)`\s*\|", DESIGN.read_text(), flags=re.MULTILINE)
    }
    parts = module.split(".")
    room = (
        f"speckle.{parts[1]}" if len(parts) > 1 and (PACKAGE / parts[1]).is_dir() else "top level"
    )
    assert module in rows, (
        f"docs/explanation/design.md has no row for {module}: add the row "
        f"'| `{module}` | <the kind of code it holds> |' to the table of its room ({room})"
    )


def test_design_lists_no_module_that_is_gone():
    rows = re.findall(r"^\|\s*`(speckle[\w.]*)`\s*\|", DESIGN.read_text(), flags=re.MULTILINE)
    gone = sorted(set(rows) - set(_module_names()))
    assert not gone, f"docs/explanation/design.md lists modules that do not exist: {gone}"


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: p.name)
def test_no_module_over_max_lines(path):
    n = len(path.read_text().splitlines())
    assert n <= MAX_LINES, (
        f"{path.relative_to(REPO)} has {n} lines (> {MAX_LINES}): split it along its seams"
    )


def test_estimate_strain_documents_its_int_window():
    """An int window is square (``parse_window``), and the docstring says so."""
    import speckle
    from speckle.analysis._common import parse_window  # private: the one window parser

    assert parse_window(4, shape=(16, 16)) == (4, 4)
    doc = " ".join(speckle.estimate_strain.__doc__.split())
    assert "An int ``w`` means the square window ``(w, w)``" in doc
    assert "(int, 1)" not in doc
