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
    import ast
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
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package[: len(package) - node.level + 1]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                todo.append(mod)
                todo.extend(f"{mod}.{a.name}" for a in node.names)
            elif isinstance(node, ast.Import):
                todo.extend(a.name for a in node.names)
    return sorted(str(p) for p in seen)
