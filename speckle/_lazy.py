"""Lazy public names for the package's ``__init__`` files (scientific Python's SPEC 1).

One call per package, through ``lazy_loader``: every public module and subpackage of the package
can be reached as an attribute (found on disk, so a new module needs no entry here), and the
names each module contributes load on first use. ``__all__`` lists the
names only (functions, classes, constants), never the modules.

Where a function has its module's name (``speckle.system.rolloff.rolloff``,
``speckle.imaging.bscan.bscan``, ...), the package attribute is the function, whatever the order
of imports: importing the module would otherwise rebind the attribute to the module. Import
such a module's other names with ``from speckle.system.rolloff import rolloff_curve``.
"""

from __future__ import annotations

import ast
import pkgutil
import sys
import types
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import lazy_loader


class _Package(types.ModuleType):
    """A package whose public names win over same-named submodules."""

    def __setattr__(self, name: str, value: object) -> None:
        if isinstance(value, types.ModuleType) and name in self.__dict__.get("__all__", ()):
            return  # the import system binding the submodule: the public name stays
        super().__setattr__(name, value)


def attach(
    package: str, names: Mapping[str, Sequence[str]]
) -> tuple[Callable, Callable, list[str]]:
    """``(__getattr__, __dir__, __all__)`` of a package whose public names load lazily.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : Mapping[str, Sequence[str]]
        Module (relative to the package) -> the public names it contributes.

    Returns
    -------
    tuple
        ``__getattr__`` and ``__dir__`` for the package's module, and its ``__all__``.
    """
    public = sorted({name for group in names.values() for name in group})
    module = sys.modules[package]
    found = {m.name for m in pkgutil.iter_modules(module.__path__)}
    modules = sorted({*names, *found} - set(public) - {m for m in found if m.startswith("_")})
    getattr_, dir_, _ = lazy_loader.attach(package, submodules=modules, submod_attrs=dict(names))
    module.__class__ = _Package
    module.__dict__["_lazy_table"] = {n: m for m, group in names.items() for n in group}
    return getattr_, dir_, public


def functions_of(package: str, module: str) -> list[str]:
    """The functions and classes in ``__all__`` of ``package.module``, read without importing it.

    The module's source is parsed (so a lazy ``__init__`` can list a module's names without
    loading it, and without writing them a second time); its constants stay out of the
    package's table (they may share a name with another module's, e.g. ``WINDOWS``).

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    module : str
        Module name relative to the package.

    Returns
    -------
    list of str
        The names, in ``__all__`` order.

    Raises
    ------
    ValueError
        If the module has no literal ``__all__`` list.
    """
    path = next(iter(sys.modules[package].__path__))
    tree = ast.parse(Path(path, f"{module}.py").read_text(encoding="utf-8"))
    defined = {
        node.name
        for node in tree.body
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
    }
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
        ):
            return [n for n in ast.literal_eval(node.value) if n in defined]
    raise ValueError(f"{package}.{module} has no literal __all__ list")


def defining_module(package: str, name: str) -> str | None:
    """The module that defines the lazy public name ``package.name`` (None if it is not one).

    Follows the tables through the levels (``speckle.ascan`` -> ``speckle.imaging`` ->
    ``speckle.imaging.aline``), importing only the packages' ``__init__`` files. Code tracking
    (``speckle.provenance.module_sources``) uses it, since an ``import speckle`` alone no
    longer says which modules a script needs.
    """
    import importlib
    import importlib.util

    try:
        # only packages hold a table: a plain module (often heavy) is not imported
        if package not in sys.modules:
            spec = importlib.util.find_spec(package)
            if spec is None or spec.submodule_search_locations is None:
                return None
        table = importlib.import_module(package).__dict__.get("_lazy_table", {})
    except (ImportError, AttributeError, ValueError):
        return None
    if name not in table:
        return None
    target = f"{package}.{table[name]}"
    return defining_module(target, name) or target
