"""The package layout keeps its layers honest (in the spirit of prysm's import allow-list).

The flow is scene -> system -> imaging -> analysis -> studies (and the SynthOCT drop-in) ->
figures -> pipeline. A module may import from its own group and the groups before it, never from
a later one; only ``speckle.figures`` and ``speckle.pipeline`` draw (matplotlib); third-party
imports are limited per group, each with its reason.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "speckle"

#: Group -> rank in the flow; top-level modules are infrastructure (rank 0).
RANK = {
    "scene": 1,
    "system": 1,
    "imaging": 2,
    "analysis": 3,
    "studies": 4,
    "synthoct": 4,
    "figures": 5,
    "pipeline": 6,
}

#: Third-party packages each group may import, and why.
ALLOWED = {
    # infrastructure: arrays, I/O, sweeps and streaming on a dask.distributed cluster
    None: {"numpy", "xarray", "dask", "distributed", "netCDF4", "yaml", "lazy_loader"}
    # reading users' image files (speckle.io.load_image): MATLAB (scipy.io, h5py), Zarr, TIFF,
    # each imported only when a file of its format is read
    | {"scipy", "h5py", "zarr", "tifffile"},
    "scene": {"numpy", "xarray", "dask", "scipy", "skfem"},  # geometry, FEM mechanics
    "system": {"numpy", "xarray", "scipy", "finufft"},  # spectra, noise, fast camera model
    "imaging": {"numpy", "xarray", "dask", "scipy", "numba", "finufft"},  # fast synthesis
    # statistics, registration and filters (skimage), reading PNG measured images
    # (matplotlib.image), the optional BM3D filter (bm3d: non-commercial licence, not required),
    # reading users' files (h5py: MATLAB v7.3, zarr, tifffile), the correlation theory's
    # Fourier series at non-uniform frequencies (finufft, expected_gamma), the strain
    # estimators' fused window sums (numba: speckle.analysis._kernels)
    "analysis": {
        "finufft",
        "numba",
        "numpy",
        "xarray",
        "scipy",
        "skimage",
        "matplotlib",
        "bm3d",
        "h5py",
        "zarr",
        "tifffile",
    },
    # experiments on methods: scenes, images and measurements, on Dask; the phantom fit's
    # compiled boundary search (numba: speckle.studies.phantom._shape_kernels)
    "studies": {"numpy", "xarray", "dask", "distributed", "scipy", "numba"},
    # the challenge's files (PNG: Pillow), its scanner (finufft) and maps (scipy, skimage);
    # its LPIPS metric (lpips, torch) only where the optional extra speckle-oct[lpips] is installed
    "synthoct": {"numpy", "xarray", "scipy", "finufft", "PIL", "skimage", "dask", "lpips", "torch"},
    "figures": {"numpy", "xarray", "scipy", "matplotlib", "dask"},  # drawing
    # config checks (yaml, jsonschema), running scripts, figure style (matplotlib)
    "pipeline": {"numpy", "xarray", "yaml", "jsonschema", "matplotlib", "dask", "distributed"},
}
#: Modules kept at an old path after their names moved (issue 32), and why they import against
#: the flow: each only re-exports the new module's names (public ones warn, ``speckle._deprecate``).
SHIMS = {
    "speckle._workflow": "old path of speckle.pipeline.runner (scripts of other branches)",
    "speckle.figures._style": "old path of speckle.figures.style and speckle.pipeline.outputs",
    "speckle.figures._config": (
        "old path of speckle.pipeline.adapters; the figure data builders still take config "
        "sections through it until they move to speckle.studies"
    ),
    "speckle.figures.config_check": "old path of speckle.pipeline.checks (FutureWarning)",
}
STDLIB = set(sys.stdlib_module_names)
#: Every subpackage ``__init__`` declares its names lazily (SPEC 1).
LAZY = "lazy_loader"


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
    if ".".join(parts) in SHIMS:
        return  # a re-export of names that moved (SHIMS says why)
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
            assert not (group is None and parts[1] not in ("figures", "pipeline")), (
                f"infrastructure module {'.'.join(parts)} imports {name}"
            )
        elif top not in STDLIB and top != LAZY:
            assert top in ALLOWED[group], f"{'.'.join(parts)} imports {top}: not allowed in {group}"


#: Groups that may not import a group ranked before them, and why (issue 32).
FORBIDDEN = {
    "analysis": {"imaging": "analysis measures images; experiments that image are studies"},
}


@pytest.mark.parametrize("path,parts", list(_modules()), ids=lambda v: str(v)[-40:])
def test_analysis_imports_no_imaging(path, parts):
    group = _group(".".join(parts))
    for name in _imports(path, parts):
        target = _group(name) if name.startswith("speckle.") else None
        reason = FORBIDDEN.get(group, {}).get(target)
        assert reason is None, f"{'.'.join(parts)} imports {name}: {reason}"


def _module_name(parts: list[str]) -> str:
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(parts): path for path, parts in _modules()}


def _import_edges(path: Path, parts: list[str]):
    """(imported module, imported names) for every import of a ``speckle`` module in a file.

    ``from .pkg import name`` counts as an import of ``pkg.name`` when that is a module, else of
    ``pkg``; every import counts, at module level or inside a function.
    """
    package = parts[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = ".".join(package[: len(package) - node.level + 1])
                module = ".".join(filter(None, [base, node.module]))
            else:
                module = node.module or ""
            if not module.startswith("speckle"):
                continue
            names = [a.name for a in node.names]
            submodules = [f"{module}.{n}" for n in names if f"{module}.{n}" in MODULES]
            yield from ((m, []) for m in submodules)
            rest = [n for n in names if f"{module}.{n}" not in MODULES]
            if rest:
                yield module, rest
        elif isinstance(node, ast.Import):
            yield from ((a.name, []) for a in node.names if a.name.startswith("speckle"))


GRAPH = {
    _module_name(parts): {m for m, _ in _import_edges(path, parts)} - {_module_name(parts)}
    for path, parts in _modules()
}


def test_no_import_cycle_between_modules():
    """No module reaches itself through imports (Tarjan's strongly connected components)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in GRAPH.get(node, ()):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for node in sorted(GRAPH):
        if node not in index:
            visit(node)
    assert not cycles, f"import cycles: {cycles}"


def _is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


@pytest.mark.parametrize("path,parts", list(_modules()), ids=lambda v: str(v)[-40:])
def test_no_private_name_imported_from_a_public_module(path, parts):
    """Helpers shared between modules live in a private module (``_kernels``, ``_validate``)."""
    for module, names in _import_edges(path, parts):
        if any(_is_private(p) for p in module.split(".")) or module == _module_name(parts):
            continue
        private = [n for n in names if _is_private(n)]
        assert not private, f"{_module_name(parts)} imports {private} from public {module}"


@pytest.mark.parametrize("path,parts", list(_modules()), ids=lambda v: str(v)[-40:])
def test_package_modules_import_from_the_defining_module(path, parts):
    """Inside the package, names come from the module that defines them, not a lazy __init__.

    (The lazy ``__init__`` tables are for users; importing through them would hide the real
    dependency from the cycle test above.)
    """
    if parts[-1] == "__init__":
        return
    for module, names in _import_edges(path, parts):
        if names and MODULES.get(module, Path()).name == "__init__.py":
            raise AssertionError(f"{_module_name(parts)} imports {names} from package {module}")


TESTS = Path(__file__).resolve().parent
PRIVATE_IMPORT = re.compile(
    r"^\s*(from\s+(speckle[\w.]*)\s+import\s+(.+)|import\s+(speckle[\w.]*))"
)


def _private_imports(path: Path, *, explained_ok: bool = True):
    """(line number, line) of imports of private speckle modules or names, unless explained.

    An explained import carries a ``# private: <why>`` comment on its line or the line above
    (accepted only with ``explained_ok``).
    """
    lines = path.read_text().splitlines()
    for i, line in enumerate(lines):
        match = PRIVATE_IMPORT.match(line)
        if not match:
            continue
        module = match.group(2) or match.group(4)
        names = [n.strip().split(" as ")[0] for n in (match.group(3) or "").strip("()").split(",")]
        private = any(_is_private(p) for p in module.split(".")) or any(map(_is_private, names))
        explained = explained_ok and ("# private:" in line or (i and "# private:" in lines[i - 1]))
        if private and not explained:
            yield i + 1, line.strip()


@pytest.mark.parametrize(
    "path",
    sorted([*TESTS.rglob("*.py"), *(TESTS.parent / "benchmarks").glob("*.py")]),
    ids=lambda p: str(p.relative_to(TESTS.parent)),
)
def test_tests_and_benchmarks_use_public_names_or_say_why(path):
    found = list(_private_imports(path))
    assert not found, f"private imports without a '# private: <why>' comment: {found}"


def test_every_shim_exists_and_only_re_exports():
    """A shim holds no code of its own: imports, ``__all__`` and ``__getattr__ = moved(...)``."""
    for name in SHIMS:
        path = MODULES[name]
        for node in ast.parse(path.read_text()).body[1:]:
            assert isinstance(node, ast.Import | ast.ImportFrom | ast.Assign), (
                f"{name}:{node.lineno} is more than a re-export"
            )


WORKFLOW = TESTS.parent / "workflow"
WORKFLOW_FILES = sorted(
    [TESTS.parent / "Snakefile", *WORKFLOW.glob("rules/*.smk"), *WORKFLOW.glob("scripts/*.py")]
)


@pytest.mark.parametrize("path", WORKFLOW_FILES, ids=lambda p: str(p.relative_to(TESTS.parent)))
def test_workflow_uses_public_names_only(path):
    """The Snakefile, rule files and scripts import only public speckle modules and names."""
    found = list(_private_imports(path, explained_ok=False))
    assert not found, f"private speckle names imported by the workflow: {found}"


FIGURES = [(path, parts) for path, parts in _modules() if parts[1] == "figures"]


@pytest.mark.parametrize("path,parts", FIGURES, ids=lambda v: str(v)[-40:])
def test_figures_only_draw(path, parts):
    """Config checks live in ``speckle.pipeline.checks``: no figure module checks a config."""
    name = ".".join(parts)
    if name in SHIMS:
        return
    source = path.read_text()
    checks = [
        n.name
        for n in ast.walk(ast.parse(source))
        if isinstance(n, ast.FunctionDef) and n.name.lstrip("_").startswith("check")
    ]
    assert not checks, f"{name} defines config checks {checks}: they belong in speckle.pipeline"
    assert "config key" not in source, f"{name} words a config error: speckle.pipeline.checks"
    imported = {m for m, _ in _import_edges(path, parts)}
    assert not {m for m in imported if m.startswith("speckle.pipeline")}, (
        f"{name} imports the pipeline: figures draw, the pipeline calls them"
    )
