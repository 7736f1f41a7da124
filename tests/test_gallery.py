"""The gallery runs from an installed package, outside the repository (issue 32).

Each example (``examples/plot_*.py``) reads what it needs from the package (the default config:
:func:`speckle.pipeline.default_config`, shipped as package data), never from a clone through
``speckle.__file__``. The slow test installs the package the way a wheel does (its modules,
stubs and declared package data, links resolved) into a temporary directory, copies the
examples to another, and runs each one there with a clean environment: the repository is on no
path, so an example that reaches into it fails.
"""

from __future__ import annotations

import fnmatch
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((REPO / "examples").glob("plot_*.py"))
#: Words that reach into a clone of the repository.
REPO_PATHS = re.compile(r"__file__|workflow/|\bparents\[")


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_examples_read_nothing_of_the_repository(path):
    found = REPO_PATHS.findall(path.read_text())
    assert not found, f"{path.name} reads the repository ({found}): use speckle.pipeline"


def _install(target: Path) -> Path:
    """Copy ``speckle`` as a wheel holds it: ``*.py``, ``*.pyi`` and the declared package data."""
    data = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    patterns = data.get("package-data", {})
    for path in sorted((REPO / "speckle").rglob("*")):
        rel = path.relative_to(REPO)
        if path.is_dir() or "__pycache__" in rel.parts:
            continue
        package = ".".join(rel.parent.parts)
        owner = next((p for p in patterns if package == p or package.startswith(p + ".")), None)
        inner = path.relative_to(REPO / owner.replace(".", "/")).as_posix() if owner else ""
        shipped = path.suffix in (".py", ".pyi") or (
            owner and any(fnmatch.fnmatch(inner, pat) for pat in patterns[owner])
        )
        if shipped:
            (target / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, target / rel)  # follows links, as a wheel build does
    return target


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    site = _install(tmp_path_factory.mktemp("site"))
    examples = tmp_path_factory.mktemp("gallery")
    for path in EXAMPLES:
        shutil.copy(path, examples)
    env = {
        "PATH": os.environ.get("PATH", ""),
        "HOME": os.environ.get("HOME", str(examples)),
        "PYTHONPATH": str(site),  # the installed copy only: never the repository
        "PYTHONNOUSERSITE": "1",
        "MPLBACKEND": "Agg",
        "OMP_NUM_THREADS": "1",
        "NUMBA_NUM_THREADS": "1",
    }
    return site, examples, env


def test_installed_copy_is_the_one_imported(installed):
    site, examples, env = installed
    out = subprocess.run(
        [sys.executable, "-P", "-c", "import speckle; print(speckle.__file__)"],
        cwd=examples,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert Path(out.strip()).is_relative_to(site), out


@pytest.mark.slow
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs_from_the_installed_package(installed, path):
    _site, examples, env = installed
    run = subprocess.run(
        [sys.executable, "-P", path.name],
        cwd=examples,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, f"{path.name} failed outside the repository:\n{run.stderr[-3000:]}"


def test_shipped_default_config_is_the_workflow_config():
    """``speckle/data/config.yaml`` links to the workflow's config: one file, never two."""
    import yaml

    from speckle.pipeline import default_config

    workflow = yaml.safe_load((REPO / "workflow/config/config.yaml").read_text())
    assert default_config() == workflow
    assert default_config() is not default_config()
