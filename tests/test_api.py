"""The public API: curated, lazy (SPEC 1), and complete for what the README and docs use."""

from __future__ import annotations

import importlib
import pkgutil
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

import speckle

REPO = Path(__file__).resolve().parents[1]
SUBPACKAGES = ["scene", "system", "imaging", "analysis", "studies"]
#: Heavy dependencies that ``import speckle`` must not load (they load on first use).
HEAVY = ["numba", "dask", "scipy", "skfem", "matplotlib", "skimage", "finufft", "netCDF4"]


def _run(code: str) -> str:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO
    ).stdout


def test_import_speckle_loads_no_heavy_dependency():
    loaded = _run(
        f"import sys, speckle; print(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    ).split()
    assert loaded == [], f"import speckle loads {loaded}"


def test_import_time_within_bound_of_numpy_and_xarray():
    """``import speckle`` takes at most 1.5x ``import numpy, xarray`` (best of 3 processes)."""
    timer = "import time; t = time.perf_counter(); import {}; print(time.perf_counter() - t)"
    best = {
        mods: min(float(_run(timer.format(mods))) for _ in range(3))
        for mods in ("numpy, xarray", "speckle")
    }
    assert best["speckle"] <= 1.5 * best["numpy, xarray"], best


@pytest.mark.parametrize("package", ["speckle", *(f"speckle.{g}" for g in SUBPACKAGES)])
def test_every_lazy_name_resolves(package):
    module = importlib.import_module(package)
    assert module.__all__, package
    for name in module.__all__:
        value = getattr(module, name)
        assert not isinstance(value, types.ModuleType), f"{package}.{name} is a module"
        assert name in dir(module)


def test_top_level_gathers_every_subpackage_name():
    for group in SUBPACKAGES:
        sub = importlib.import_module(f"speckle.{group}")
        assert set(sub.__all__) <= set(speckle.__all__), group
        for name in sub.__all__:
            assert getattr(speckle, name) is getattr(sub, name)


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_function"):
        speckle.no_such_function  # noqa: B018


def _documented_names() -> set[str]:
    """``speckle.<name>`` used as a call or attribute in the README and the docs' pages."""
    texts = [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]
    names = set()
    for path in texts:
        names |= set(re.findall(r"\bspeckle\.([A-Za-z_]\w*)\b", path.read_text()))
    modules = {m.name for m in pkgutil.iter_modules(speckle.__path__)}
    return {n for n in names if n not in modules and not n.startswith("_")}


def test_every_documented_top_level_name_is_public():
    missing = sorted(_documented_names() - set(speckle.__all__))
    assert not missing, f"used as speckle.<name> in README/docs but not exported: {missing}"


def test_distribution_name_is_not_the_index_speckle():
    """The index's ``speckle`` is another project: the distribution is ``speckle-oct``."""
    import tomllib

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["name"] == "speckle-oct" == speckle.provenance.DISTRIBUTION
    assert speckle.__version__ == project["version"]


def test_a_function_stays_a_function_whatever_the_import_order():
    """``speckle.system.rolloff`` is the function even after its (private) module was imported."""
    out = _run(
        "import speckle.system._rolloff, speckle.imaging._bscan, speckle.scene._layers\n"
        "import speckle\n"
        "print(callable(speckle.system.rolloff), callable(speckle.rolloff),"
        " callable(speckle.imaging.bscan), callable(speckle.layer_stack))"
    )
    assert out.split() == ["True"] * 4


def _stub(package: str) -> tuple[set[str], dict[str, list[str]], list[str]]:
    """(modules, module -> names, ``__all__``) declared by a package's ``__init__.pyi``."""
    import ast

    path = Path(importlib.import_module(package).__file__).with_suffix(".pyi")
    tree = ast.parse(path.read_text())
    modules = {
        a.name for n in tree.body if isinstance(n, ast.ImportFrom) and not n.module for a in n.names
    }
    names: dict[str, list[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.module:
            names.setdefault(node.module, []).extend(a.name for a in node.names)
    (all_,) = [
        ast.literal_eval(n.value)
        for n in tree.body
        if isinstance(n, ast.Assign) and [t.id for t in n.targets] == ["__all__"]
    ]
    return modules, names, all_


STUBBED = [f"speckle.{g}" for g in [*SUBPACKAGES, "synthoct", "pipeline", "studies.twin"]]


def _retired_modules(package: str) -> set[str]:
    """Names of the package's retired module paths (shims, kind ``module`` of ``RETIRED``)."""
    from speckle.conventions import RETIRED

    return {
        old.rpartition(".")[2]
        for old, (_, kind) in RETIRED.items()
        if kind == "module" and old.rpartition(".")[0] == package
    }


@pytest.mark.parametrize("package", STUBBED)
def test_each_stub_lists_exactly_its_public_names_and_modules(package):
    """The ``__init__.pyi`` stub is the one list: public names, their modules, public modules."""
    module = importlib.import_module(package)
    modules, names, all_ = _stub(package)
    on_disk = {m.name for m in pkgutil.iter_modules(module.__path__) if not m.name.startswith("_")}
    on_disk -= _retired_modules(package)  # shims at retired paths: not listed, they warn
    assert modules == on_disk, f"{package}.__init__.pyi: modules {modules ^ on_disk}"
    listed = [n for group in names.values() for n in group]
    assert sorted(listed) == sorted(set(listed)) == sorted(all_) == sorted(module.__all__)
    for mod, group in names.items():
        source = importlib.import_module(f"{package}.{mod}")
        exported = getattr(source, "__all__", None)  # a private module may have none
        missing = [n for n in group if n not in (exported or vars(source))]
        assert not missing, f"{package}.{mod} does not export {missing}"


@pytest.mark.parametrize("package", ["speckle", *STUBBED])
def test_no_public_name_is_also_a_module(package):
    """Importing a module binds it on its package: a same-named function would be replaced.

    Only the shim at a retired path may share a public name; its package keeps the name
    (``test_a_retired_module_path_warns_once_and_keeps_the_function``)."""
    module = importlib.import_module(package)
    on_disk = {m.name for m in pkgutil.iter_modules(module.__path__)}
    on_disk -= _retired_modules(package)
    assert not set(module.__all__) & on_disk, f"{package}: rename the module private"
