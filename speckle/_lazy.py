"""Lazy public names for the package's ``__init__`` files (scientific Python's SPEC 1).

Each subpackage lists its public modules and names once, in its ``__init__.pyi`` stub
(``from . import module as module`` for a public module, ``from .module import name`` for a
name; ``__all__`` for type checkers), and attaches it with ``lazy_loader.attach_stub``, as
scikit-image does: modules and names load on first use. A module never shares its package's
public name (the function ``bscan`` lives in the private ``imaging/_bscan.py``), so importing a
module never rebinds a public name; the shim kept at a retired path of the same name
(``imaging/bscan.py``) leaves the function in place (``speckle._deprecate.retired_module``).
``__all__`` lists the names only (functions, classes, constants), never the modules.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import pkgutil
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import lazy_loader


def attach(package: str, file: str) -> tuple[Callable, Callable, list[str]]:
    """``(__getattr__, __dir__, __all__)`` of a package, read from its ``__init__.pyi`` stub.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    file : str
        The package's ``__file__`` (the stub is beside it).

    Returns
    -------
    tuple
        ``__getattr__`` and ``__dir__`` for the package's module, and its ``__all__`` (the
        stub's names without its modules).
    """
    getattr_, dir_, everything = lazy_loader.attach_stub(package, file)
    stub = ast.parse(Path(file).with_suffix(".pyi").read_text(encoding="utf-8"))
    # the stub's modules (``from . import module``), not every file on disk: a retired
    # module's shim may keep the name of a public function (``system/rolloff.py``)
    modules = {
        alias.name
        for node in stub.body
        if isinstance(node, ast.ImportFrom) and not node.module
        for alias in node.names
    }
    return getattr_, dir_, [n for n in everything if n not in modules]


def gather(
    package: str, names: Mapping[str, Sequence[str]]
) -> tuple[Callable, Callable, list[str]]:
    """``(__getattr__, __dir__, __all__)`` of the top level: subpackage -> the names it gives.

    Every public module and subpackage (found on disk) is an attribute too.
    """
    found = pkgutil.iter_modules(sys.modules[package].__path__)
    modules = sorted(m.name for m in found if not m.name.startswith("_"))
    getattr_, dir_, _ = lazy_loader.attach(package, modules, dict(names))
    sys.modules[package].__dict__["_lazy_table"] = {
        n: module for module, group in names.items() for n in group
    }
    return getattr_, dir_, sorted({n for group in names.values() for n in group})


def _table(package: str) -> dict[str, str]:
    """Public name -> module of a package: its stub's imports (or the top level's table)."""
    module = sys.modules[package]
    if "_lazy_table" in module.__dict__:
        return module.__dict__["_lazy_table"]
    stub = Path(module.__file__ or "").with_suffix(".pyi")
    if not stub.is_file():
        return {}
    return {
        alias.name: node.module
        for node in ast.parse(stub.read_text(encoding="utf-8")).body
        if isinstance(node, ast.ImportFrom) and node.module
        for alias in node.names
    }


def defining_module(package: str, name: str) -> str | None:
    """The module that defines the lazy public name ``package.name`` (None if it is not one).

    Follows the tables through the levels (``speckle.ascan`` -> ``speckle.imaging`` ->
    ``speckle.imaging.aline``), importing only the packages' ``__init__`` files. Code tracking
    (``speckle.provenance.module_sources``) uses it, since an ``import speckle`` alone no
    longer says which modules a script needs.
    """
    try:
        # only packages hold a table: a plain module (often heavy) is not imported
        if package not in sys.modules:
            spec = importlib.util.find_spec(package)
            if spec is None or spec.submodule_search_locations is None:
                return None
        importlib.import_module(package)
        table = _table(package)
    except (ImportError, AttributeError, ValueError):
        return None
    if name not in table:
        return None
    target = f"{package}.{table[name]}"
    return defining_module(target, name) or target
