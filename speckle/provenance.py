"""Provenance: package version, configuration hash and seed recorded in every output."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from importlib import metadata

__all__ = ["config_hash", "package_version", "provenance_attrs"]


#: Distribution name on the package index. The import name is ``speckle``; the index's
#: ``speckle`` is an unrelated project (a client for Speckle servers).
DISTRIBUTION = "speckle-oct"


def package_version() -> str:
    """Installed version of the ``speckle-oct`` distribution (``"unknown"`` if not installed)."""
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown"


def config_hash(config: Mapping) -> str:
    """SHA-256 of a configuration mapping, independent of key order.

    Parameters
    ----------
    config : Mapping
        JSON-serialisable configuration (nested dicts, lists, numbers, strings).
    """
    text = json.dumps(config, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def provenance_attrs(config: Mapping | None = None, seed: int | None = None) -> dict[str, object]:
    """Attributes to attach to an output dataset: version, config hash and seed if given."""
    attrs: dict[str, object] = {"speckle_version": package_version()}
    if config is not None:
        attrs["config_sha256"] = config_hash(config)
    if seed is not None:
        attrs["seed"] = int(seed)
    return attrs


def _dotted(node) -> str | None:
    """``a.b.c`` of an attribute chain rooted at a name, else None."""
    import ast

    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    return ".".join([node.id, *reversed(parts)]) if isinstance(node, ast.Name) else None


def _imported_modules(tree, package: list[str]) -> list[str]:
    """Modules a parsed file may import, including what it reaches through lazy names.

    ``from x import y`` counts ``x`` and ``x.y``; ``import speckle`` followed by
    ``speckle.imaging.ascan(...)`` counts the module that defines ``ascan``
    (``speckle._lazy.defining_module``), as does ``from speckle import ascan``.
    """
    import ast

    from ._lazy import defining_module

    found: list[str] = []
    aliases: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            found.append(mod)
            for a in node.names:
                found.append(f"{mod}.{a.name}")
                found.append(defining_module(mod, a.name) or "")
                aliases[a.asname or a.name] = f"{mod}.{a.name}"
        elif isinstance(node, ast.Import):
            for a in node.names:
                found.append(a.name)
                # ``import a.b`` binds ``a``; ``import a.b as c`` binds ``c`` to ``a.b``
                aliases[a.asname or a.name.split(".")[0]] = (
                    a.name if a.asname else a.name.split(".")[0]
                )
    for node in ast.walk(tree):
        chain = _dotted(node) if isinstance(node, ast.Attribute) else None
        head = chain and chain.split(".")[0]
        if head not in aliases or not aliases[head].startswith("speckle"):
            continue
        parts = [aliases[head], *chain.split(".")[1:]]
        prefix = parts[0]
        for part in parts[1:]:
            lazy = defining_module(prefix, part)
            found.append(lazy or f"{prefix}.{part}")
            prefix = lazy or f"{prefix}.{part}"
    return [m for m in found if m]


def module_sources(*modules: str) -> list[str]:
    """Source files of ``speckle`` modules and every package module they import, recursively.

    Snakemake does not track code in installed packages; the workflow lists these files as
    rule inputs so that editing a module reruns exactly the rules whose scripts use it.

    Parameters
    ----------
    *modules : str
        Dotted module names inside the package, e.g. ``"speckle.figures.static"``.

    Returns
    -------
    list of str
        Absolute paths, sorted, including the package ``__init__`` files on the way.
    """
    import importlib.util
    from pathlib import Path

    root = Path(__file__).resolve().parent

    def find(name: str) -> Path | None:
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, AttributeError):
            return None
        return None if spec is None or spec.origin is None else Path(spec.origin).resolve()

    seen: set[Path] = set()
    todo = list(modules)
    for name in modules:
        if find(name) is None:
            raise ValueError(f"module {name!r} not found")
    while todo:
        name = todo.pop()
        path = find(name)
        if path is None or path in seen or not path.is_relative_to(root):
            continue
        seen.add(path)
        parts = name.split(".")
        # Parent package __init__ files count as sources, but their imports (the public
        # re-exports) are not followed: that would make every rule depend on every module.
        for i in range(1, len(parts)):
            parent = find(".".join(parts[:i]))
            if parent is not None:
                seen.add(parent)
        package = parts if path.name == "__init__.py" else parts[:-1]
        todo.extend(_file_imports(path, tuple(package)))
    return sorted(str(p) for p in seen)


#: ``_imported_modules`` of each parsed file, keyed by path, package and the file's
#: modification time and size (an edited file is parsed again). The workflow calls
#: ``module_sources`` once per rule; parsing each module once instead of once per rule
#: takes ``snakemake -n`` from ~30 s to a few seconds.
_IMPORTS_CACHE: dict[tuple, list[str]] = {}


def _file_imports(path, package: tuple[str, ...]) -> list[str]:
    """``_imported_modules`` of the file at ``path`` (a Path) in ``package``, memoised."""
    import ast

    stat = path.stat()
    key = (str(path), package, stat.st_mtime_ns, stat.st_size)
    if key not in _IMPORTS_CACHE:
        _IMPORTS_CACHE[key] = _imported_modules(ast.parse(path.read_text()), list(package))
    return _IMPORTS_CACHE[key]
