"""One meaning per name: ``depth_range`` is the unambiguous depth H, ``depth`` the pixel dim."""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import numpy as np
import pytest

import speckle
from speckle.conventions import QUANTITIES, depth_range_of

PACKAGES = [
    "speckle",
    "speckle.scene",
    "speckle.system",
    "speckle.imaging",
    "speckle.analysis",
    "speckle.studies",
]


def _public_modules() -> list[str]:
    from speckle.conventions import RETIRED

    names = ["speckle"]
    for info in pkgutil.walk_packages(speckle.__path__, "speckle."):
        retired = RETIRED.get(info.name, ("", ""))[1] == "module"  # a shim: its names live on
        if not retired and not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return names


def _callables() -> dict[str, object]:
    """Every public function, class and public method: the lazy ``__all__`` of each package,
    and the public names defined in every public module (``speckle.figures.*`` included)."""
    found: dict[str, object] = {}
    for package in PACKAGES:
        module = importlib.import_module(package)
        for name in module.__all__:
            found[f"{package}.{name}"] = getattr(module, name)
    for mod_name in _public_modules():
        module = importlib.import_module(mod_name)
        for name, obj in vars(module).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod_name:
                continue
            if inspect.isfunction(obj) or inspect.isclass(obj):
                found[f"{mod_name}.{name}"] = obj
    out = {}
    for qual, obj in found.items():
        if inspect.isclass(obj):
            out[qual] = obj
            for name, member in vars(obj).items():
                if not name.startswith("_") and inspect.isfunction(member):
                    out[f"{qual}.{name}"] = member
        elif callable(obj):
            out[qual] = obj
    return out


def _parameters(obj: object) -> list[inspect.Parameter]:
    try:
        return list(inspect.signature(obj).parameters.values())
    except (TypeError, ValueError):  # builtins without a signature
        return []


def _documents_coordinate_values(obj: object) -> bool:
    """Whether the numpydoc entry of ``depth`` is an array (the pixel-depth coordinate)."""
    doc = inspect.getdoc(obj) or ""
    return bool(re.search(r"^\s*depth(, \w+)* : array_like", doc, flags=re.MULTILINE))


def test_no_public_function_takes_H_as_depth():
    """A public ``depth`` parameter, if any, holds the values of the ``depth`` coordinate
    (pixel-centre depths, an array): never the scalar H, which is ``depth_range``."""
    callables = _callables()
    assert len(callables) > 200  # the walk found the package
    wrong = []
    for qual, obj in callables.items():
        for p in _parameters(obj):
            if p.name != "depth":
                continue
            scalar = p.annotation in (float, int, "float", "int", "float | None")
            if scalar or not _documents_coordinate_values(obj):
                wrong.append(qual)
    assert wrong == [], f"parameters named depth that are not the depth coordinate: {wrong}"


def test_the_functions_taking_H_call_it_depth_range():
    for func in (
        speckle.ascan,
        speckle.stream_ascans,
        speckle.pixel_depths,
        speckle.delta_k,
        speckle.spectrum,
        speckle.random_scatterers,
        speckle.deformable_scene,
        speckle.beam_scan,
        speckle.speckle_free_lines,
    ):
        assert "depth_range" in inspect.signature(func).parameters, func.__name__
    assert "depth_range" in speckle.imaging.BeamScene._fields
    assert "depth_range" in speckle.datasheet(840.0, 50.0, 256, imaging_depth=500.0).to_dict()


def test_the_old_keyword_is_a_type_error():
    with pytest.raises(TypeError, match="depth"):
        speckle.ascan([8.0], [1.0], n_pixels=8, depth=64.0, k0=0.0)


def test_spectra_scenes_and_bscans_carry_depth_range_only():
    src = speckle.spectrum(16, 128.0, k0_dk=3.0)
    scene = speckle.random_scatterers(3, 2.0, n_pixels=16, depth_range=128.0, seed=1)
    moved = speckle.deformable_scene(3, 2.0, n_pixels=16, depth_range=128.0, seed=1, strain=0.01)
    img = speckle.bscan(scene, src)
    for what, obj in (("spectrum", src), ("scene", scene), ("deformable scene", moved)):
        assert obj.attrs["depth_range"] == 128.0, what
        assert "depth" not in obj.attrs, what
    assert img.attrs["depth_range"] == 128.0 and "depth" not in img.attrs
    assert src.attrs["depth_range_units"] == QUANTITIES["depth_range"][0] == "um"
    # the pixel dim keeps its name: q*H/N
    np.testing.assert_allclose(img.depth.values, np.arange(16) * 8.0)


def test_a_file_written_before_the_rename_is_refused_clearly():
    src = speckle.spectrum(16, 128.0, k0_dk=3.0)
    old = src.copy()
    old.attrs["depth"] = old.attrs.pop("depth_range")
    scene = speckle.random_scatterers(3, 2.0, n_pixels=16, depth_range=128.0, seed=1)
    with pytest.raises(ValueError, match=r"attribute 'depth'.*renamed it 'depth_range'"):
        speckle.bscan(scene, old)
    old_scene = scene.copy()
    old_scene.attrs["depth"] = old_scene.attrs.pop("depth_range")
    with pytest.raises(ValueError, match=r"scene has attribute 'depth'"):
        speckle.bscan(old_scene, src)
    with pytest.raises(ValueError, match=r"needs attribute 'depth_range'"):
        depth_range_of(src.drop_attrs(), "source")
    assert depth_range_of(src.drop_attrs(), required=False) is None
    assert depth_range_of(src) == 128.0


def test_canonical_dims_renames_the_retired_lateral_dim_with_a_warning():
    from speckle.conventions import RETIRED, canonical_dims

    assert RETIRED["aline"] == ("x", "dim")
    old = speckle.__class__  # any non-xarray object passes unchanged
    assert canonical_dims(old) is old
    import xarray as xr

    img = xr.DataArray(np.ones((2, 3)), dims=("depth", "aline"), coords={"aline": [0.0, 5.0, 10.0]})
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        new = canonical_dims(img)
    assert new.dims == ("depth", "x")
    np.testing.assert_array_equal(new.x.values, [0.0, 5.0, 10.0])
    current = img.rename({"aline": "x"})
    assert canonical_dims(current) is current  # no copy, no warning
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        assert canonical_dims(img.to_dataset(name="a")).sizes["x"] == 3
    both = img.expand_dims(x=[1.0])
    with pytest.raises(ValueError, match=r"both dims 'aline'.*and 'x'"):
        canonical_dims(both)


RETIRED_PUBLIC = [
    ("METHODS", "ASCAN_METHODS", "imaging"),
    ("image", "scan_image", "imaging"),
    ("process", "process_interferogram", "system"),
    ("compress", "compress_phantom", "scene"),
    ("layers", "layer_stack", "scene"),
]


@pytest.mark.parametrize(("old", "new", "package"), RETIRED_PUBLIC)
def test_a_retired_public_name_warns_naming_the_new_one(old, new, package):
    from speckle.conventions import RETIRED

    assert RETIRED[old][0] == new
    sub = importlib.import_module(f"speckle.{package}")
    assert old not in speckle.__all__ and old not in sub.__all__
    assert new in speckle.__all__ and new in sub.__all__
    with pytest.warns(FutureWarning, match=rf"speckle\.{old} is now speckle\.{new}"):
        assert getattr(speckle, old) is getattr(speckle, new)
    if old != "layers":  # speckle.scene.layers is the module
        with pytest.warns(FutureWarning, match=rf"speckle\.{package}\.{old} is now"):
            assert getattr(sub, old) is getattr(sub, new)
    module = importlib.import_module(
        getattr(speckle, new).__module__
        if callable(getattr(speckle, new))
        else "speckle.imaging.aline"
    )
    with pytest.warns(FutureWarning, match=rf"{old} moved to .*\.{new}"):
        assert getattr(module, old) is getattr(speckle, new)


def _retired_parameters():
    from speckle.conventions import RETIRED

    return sorted(
        (key.split(".")[0], key.split(".")[1], new)
        for key, (new, kind) in RETIRED.items()
        if kind == "parameter"
    )


@pytest.mark.parametrize(("func", "old", "new"), _retired_parameters())
def test_a_retired_parameter_is_renamed_and_its_old_keyword_warns(func, old, new):
    """``lines`` for line positions, ``apodization`` for spectral windows: the function takes
    the new name, and the old keyword still works for a release, warning."""
    f = (
        getattr(speckle, func, None)
        or getattr(speckle.system.spectrometer, func, None)
        or getattr(speckle.scene.deformation, func)
    )
    params = inspect.signature(f).parameters
    assert new in params and old not in params, (func, list(params))
    with pytest.warns(FutureWarning, match=rf"{func}: parameter '{old}' is now '{new}'"):
        with pytest.raises((TypeError, ValueError)):  # fails later (no other arguments)
            f(**{old: None})


def test_the_old_keyword_gives_the_same_result():
    k = np.linspace(5.0, 5.5, 16)
    sig = np.cos(2 * k * 40.0)[None]
    new = speckle.process_interferogram(sig, grid=k, k0=5.25, apodization="hann")
    with pytest.warns(FutureWarning, match="'window' is now 'apodization'"):
        old = speckle.process_interferogram(sig, grid=k, k0=5.25, window="hann")
    np.testing.assert_array_equal(new, old)
    with pytest.raises(TypeError, match="both 'window' \\(retired\\) and 'apodization'"):
        speckle.process_interferogram(sig, grid=k, k0=5.25, window="hann", apodization="hann")


# --- no module uses a retired name (speckle.conventions.RETIRED) outside its shim ----------------
PACKAGE_ROOT = Path(speckle.__file__).parent
#: Files allowed to spell retired names: the table itself and the deprecation machinery.
SHIM_FILES = {"conventions.py", "_deprecate.py"}
#: Files spelling ``aline`` as a string, and how many times: only as the SCENE dim of independent
#: lines (scatterers per line), never an image's or a field's lateral dim (that is ``x``). The
#: count only shrinks (a new use fails); remove a file's row when it is 0.
ALINE_LEFT = {
    "imaging/_bscan.py": 2,  # map_lines: the one place a line scene's aline becomes the image's x
    "imaging/beam_lines.py": 4,  # builds a line scene (aline, scatterer) from a shared scene
    "imaging/timeseries.py": 1,  # recognises a line scene over (time, aline, scatterer)
    "scene/deformation.py": 13,  # deforms and re-bins line scenes over (aline, scatterer)
    "scene/scatterers.py": 5,  # random_scatterers: makes the line scene (aline, scatterer)
    "scene/shared.py": 3,  # from_lines: reads a line scene (aline, scatterer)
    "system/_scene.py": 1,  # a line scene's lateral positions: its aline coordinate
    "system/phase.py": 2,  # a line scene's lines (aline) get their phase noise
    "system/polarization.py": 2,  # a line scene's lines (aline) each draw one stream
}


#: Calls whose arguments spell retired names on purpose: the deprecation shims.
SHIM_CALLS = {"moved", "renamed_parameters"}


def _sources():
    """``(file, tree)`` of every package module, the arguments of shim calls cut out."""
    for path in sorted(PACKAGE_ROOT.rglob("*.py")):
        rel = path.relative_to(PACKAGE_ROOT).as_posix()
        if rel in SHIM_FILES:
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) in SHIM_CALLS:
                node.args, node.keywords = [], []
        yield rel, tree


def _retired(*kinds):
    from speckle.conventions import RETIRED

    return {old: new for old, (new, kind) in RETIRED.items() if kind in kinds}


def _speckle_chain(node):
    """Whether an attribute chain starts at the name ``speckle`` (``speckle.x.y``)."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return isinstance(node, ast.Name) and node.id == "speckle"


def test_no_module_defines_imports_or_calls_a_retired_public_name():
    names = {old.split(".")[-1]: new for old, new in _retired("function", "constant").items()}
    found = []
    for rel, tree in _sources():
        for node in ast.walk(tree):
            bad = None
            if isinstance(node, ast.FunctionDef | ast.ClassDef) and node.name in names:
                bad = f"def {node.name}"
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                ("speckle", "")
            ):
                if node.level or (node.module or "").startswith("speckle"):
                    bad = next((f"import {a.name}" for a in node.names if a.name in names), None)
            elif isinstance(node, ast.Attribute) and node.attr in names and _speckle_chain(node):
                bad = f"speckle...{node.attr}"
            if bad and not (rel == "imaging/__init__.py" and bad == "import aline"):
                found.append(
                    f"{rel}:{node.lineno} {bad} (now {names[bad.split()[-1].split('.')[-1]]})"
                )
    assert found == [], "retired names in use:\n" + "\n".join(found)


def test_no_public_all_lists_a_retired_name():
    names = {old.split(".")[-1] for old in _retired("function", "constant")}
    found = []
    for rel, tree in _sources():
        for node in tree.body:
            if (
                isinstance(node, ast.Assign)
                and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
                and isinstance(node.value, ast.List | ast.Tuple)
            ):
                found += [
                    f"{rel}: {e.value}"
                    for e in node.value.elts
                    if isinstance(e, ast.Constant) and e.value in names
                ]
    assert found == [], found
    for package in PACKAGES:
        assert not names & set(importlib.import_module(package).__all__), package


def test_no_public_function_takes_a_retired_parameter():
    callables = _callables()
    wrong = []
    for key in _retired("parameter"):
        func, old = key.split(".")
        for qual, obj in callables.items():
            if qual.split(".")[-1] == func and old in {p.name for p in _parameters(obj)}:
                wrong.append(f"{qual}({old}=)")
    assert wrong == [], wrong


def test_no_module_writes_a_retired_attribute():
    attrs_ = _retired("attr")
    found = [
        f"{rel}:{node.lineno} {node.value!r}"
        for rel, tree in _sources()
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and node.value in attrs_
    ]
    found += [
        f"{rel}:{node.lineno} keyword {node.arg}"
        for rel, tree in _sources()
        for node in ast.walk(tree)
        if isinstance(node, ast.keyword) and node.arg in attrs_
    ]
    assert found == [], found


def test_the_retired_dim_only_leaves_the_package():
    """``aline`` as a string (a dim, coordinate or key) only in the files of :data:`ALINE_LEFT`,
    never more often than recorded there (the rename to ``x`` is under way)."""
    dims = _retired("dim")
    assert dims == {"aline": "x"}
    now = {}
    for rel, tree in _sources():
        n = sum(isinstance(node, ast.Constant) and node.value == "aline" for node in ast.walk(tree))
        if n:
            now[rel] = n
    grown = {f: (n, ALINE_LEFT.get(f, 0)) for f, n in now.items() if n > ALINE_LEFT.get(f, 0)}
    assert not grown, f"more uses of the retired dim 'aline' (now, recorded): {grown}; use 'x'"
    done = sorted(f for f in ALINE_LEFT if f not in now)
    assert not done, f"no 'aline' left in {done}: remove their rows from ALINE_LEFT"


# --- no file uses a retired module path (kind ``module`` of RETIRED) outside its shim ------------
REPO = PACKAGE_ROOT.parent
#: Files that spell retired module paths on purpose: the table, the deprecation machinery, the
#: map of rooms (a row per module, shims too) and the tests of names and shims (the changelog,
#: history, is not read).
PATH_SHIMS = {
    "docs/explanation/design.md",
    "speckle/conventions.py",
    "speckle/_deprecate.py",
    "tests/test_names.py",
    "tests/test_retired_modules.py",
}


def _retired_paths() -> dict[str, bool]:
    """Retired module path -> whether its last part is a public name of its package (then
    ``package.name`` is that name, not the old module, and is fine to spell)."""
    out = {}
    for old in _retired("module"):
        package, _, child = old.rpartition(".")
        out[old] = child in importlib.import_module(package).__all__
    return out


def _path_users() -> list[Path]:
    files = [*PACKAGE_ROOT.rglob("*.py"), *(REPO / "tests").rglob("*.py")]
    files += [*(REPO / "benchmarks").glob("*.py"), *(REPO / "examples").glob("*.py")]
    files += [
        *(REPO / "workflow").rglob("*.py"),
        *(REPO / "docs").rglob("*.md"),
        REPO / "README.md",
    ]
    shims = {f"speckle/{old.split('.', 1)[1].replace('.', '/')}.py" for old in _retired("module")}
    return [f for f in files if f.relative_to(REPO).as_posix() not in PATH_SHIMS | shims]


def _absolute_imports(path: Path):
    """(line, module, names) of every import in a Python file, relative ones made absolute."""
    parts = path.relative_to(REPO).with_suffix("").parts
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = list(parts[: len(parts) - node.level])
                module = ".".join([*base, *([module] if module else [])])
            yield node.lineno, module, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            yield from ((node.lineno, a.name, []) for a in node.names)


def test_no_file_uses_a_retired_module_path():
    """Package, tests, benchmarks, examples, workflow and docs use the new paths: only the shim
    at an old path (and the tests of the shims) spell it. ``speckle.system.rolloff`` is the
    function (a public name), ``speckle.imaging.nufft`` the retired module."""
    paths = _retired_paths()
    modules = [old for old, public in paths.items() if not public]
    spelled = re.compile(r"\b(" + "|".join(map(re.escape, modules)) + r")\b(?!\w)")
    from_package = re.compile(r"from\s+(speckle[\w.]*)\s+import\s+\(?([\w\s,]+)")
    found = []
    for path in _path_users():
        rel = path.relative_to(REPO).as_posix()
        text = path.read_text()
        found += [f"{rel}: {m.group(1)}" for m in spelled.finditer(text)]
        for m in from_package.finditer(text):
            names = [n.strip() for n in m.group(2).replace("\n", ",").split(",") if n.strip()]
            found += [f"{rel}: from {m.group(1)} import {n}" for n in names
                      if f"{m.group(1)}.{n}" in modules]  # fmt: skip
        if path.suffix != ".py":
            continue
        for line, module, names in _absolute_imports(path):
            hits = [module] if module in paths or module.rpartition(".")[0] in paths else []
            hits += [f"{module}.{n}" for n in names if f"{module}.{n}" in modules]
            found += [f"{rel}:{line} imports {h}" for h in hits]
    assert not found, "retired module paths in use (use the new module):\n" + "\n".join(found)
