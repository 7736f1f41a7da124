"""The package layout keeps its layers honest (in the spirit of prysm's import allow-list).

The flow is scene -> system -> imaging -> analysis -> figures. A module may import from its own
group and the groups before it, never from a later one; only ``speckle.figures`` draws
(matplotlib); third-party imports are limited per group, each with its reason.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "speckle"

#: Group -> rank in the flow; top-level modules are infrastructure (rank 0).
RANK = {"scene": 1, "system": 1, "imaging": 2, "analysis": 3, "figures": 4}

#: Third-party packages each group may import, and why.
ALLOWED = {
    # infrastructure: arrays, I/O, sweeps and streaming on a dask.distributed cluster
    None: {"numpy", "xarray", "dask", "distributed", "netCDF4", "yaml"},
    "scene": {"numpy", "xarray", "dask", "scipy", "skfem"},  # geometry, FEM mechanics
    "system": {"numpy", "xarray", "scipy", "finufft"},  # spectra, noise, fast camera model
    "imaging": {"numpy", "xarray", "dask", "scipy", "numba", "finufft"},  # fast synthesis
    # statistics, registration and filters (skimage), reading PNG measured images
    # (matplotlib.image), the optional BM3D filter (bm3d: non-commercial licence, not required)
    "analysis": {"numpy", "xarray", "scipy", "skimage", "matplotlib", "bm3d"},
    "figures": {"numpy", "xarray", "scipy", "matplotlib", "dask"},  # drawing
}
STDLIB = set(sys.stdlib_module_names)


def _modules():
    for path in sorted(ROOT.rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        yield path, (["speckle", *rel.parts])


def _imports(path: Path, parts: list[str]):
    package = parts[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                yield ".".join(base + ([node.module] if node.module else []))
            else:
                yield node.module or ""
        elif isinstance(node, ast.Import):
            yield from (a.name for a in node.names)


def _group(name: str) -> str | None:
    parts = name.split(".")
    return parts[1] if len(parts) > 2 and parts[1] in RANK else None


@pytest.mark.parametrize("path,parts", list(_modules()), ids=lambda v: str(v)[-40:])
def test_imports_follow_the_flow(path, parts):
    if parts[-1] == "__init__" and len(parts) == 2:
        return  # the public API re-exports everything
    group = _group(".".join(parts))
    rank = RANK.get(group, 0)
    for name in _imports(path, parts):
        top = name.split(".")[0]
        if top == "speckle":
            target = _group(name)
            if target is None:
                continue  # infrastructure (io, sweep, provenance, conventions, _validate)
            assert RANK[target] <= rank or target == group, (
                f"{'.'.join(parts)} imports {name}: {group or 'top level'} may not import "
                f"from the later group {target}"
            )
            assert not (group is None and parts[1] not in ("figures",)), (
                f"infrastructure module {'.'.join(parts)} imports {name}"
            )
        elif top not in STDLIB:
            assert top in ALLOWED[group], f"{'.'.join(parts)} imports {top}: not allowed in {group}"
