"""The documentation cannot go stale: its Python blocks run, and the README keeps its bound.

Every ```python block of README.md and of the docs' MyST pages (docs/**/*.md) is executed, the
blocks of one page in order in one namespace (a tutorial builds on its earlier blocks), in a
fresh temporary directory, so that a page that writes files leaves nothing in the repository.
The directory holds a link to the repository's ``workflow/``, so a block that reads
``workflow/config/config.yaml`` runs as it would from the repository root.
The gallery scripts (examples/) run when the site builds (``sphinx-build -W``, in CI).
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest

REPO = Path(__file__).resolve().parents[1]
README_MAX_LINES = 250
#: A fenced block that opens at the start of a line with exactly ```python.
BLOCK = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def pages() -> list[Path]:
    docs = REPO / "docs"
    found = sorted(
        p
        for p in docs.rglob("*.md")
        if not {"_build", "auto_examples", "generated"} & set(p.relative_to(docs).parts)
    )
    return [REPO / "README.md", *found]


def python_blocks(path: Path) -> list[str]:
    return BLOCK.findall(path.read_text(encoding="utf-8"))


PAGES_WITH_CODE = [p for p in pages() if python_blocks(p)]


def test_readme_within_its_bound():
    lines = (REPO / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines"


def test_the_pages_have_code_to_run():
    """The README and the tutorials have examples; a broken fence would hide them all."""
    names = {p.relative_to(REPO).as_posix() for p in PAGES_WITH_CODE}
    assert "README.md" in names
    assert any(n.startswith("docs/tutorials/") for n in names), names


def test_readme_lists_every_tutorial_and_howto():
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    pages = sorted([*REPO.glob("docs/tutorials/*.md"), *REPO.glob("docs/howto/*.md")])
    assert pages
    missing = [p.relative_to(REPO).as_posix() for p in pages]
    missing = [m for m in missing if f"]({m})" not in readme]
    assert not missing, f"README.md does not link {missing}"


def test_block_pattern_finds_only_python_fences():
    text = "```python\na = 1\n```\n\n```bash\nls\n```\n\n```pycon\n>>> 1\n```\n"
    assert BLOCK.findall(text) == ["a = 1\n"]


@pytest.mark.parametrize(
    "page", PAGES_WITH_CODE, ids=[p.relative_to(REPO).as_posix() for p in PAGES_WITH_CODE]
)
def test_page_code_runs(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    matplotlib.use("Agg")
    (tmp_path / "workflow").symlink_to(REPO / "workflow", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__main__"}
    for i, code in enumerate(python_blocks(page)):
        compiled = compile(code, f"{page.relative_to(REPO)} [python block {i + 1}]", "exec")
        exec(compiled, namespace)
    import matplotlib.pyplot as plt

    plt.close("all")
