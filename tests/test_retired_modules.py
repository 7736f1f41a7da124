"""Retired module paths keep working for a release (issue 32): one ``FutureWarning``, same names.

Every key of kind ``module`` of :data:`speckle.conventions.RETIRED` is a shim at the old path
(``speckle._deprecate.retired_module``). Importing it warns once, naming the new import; its
names are the new module's objects. Where the old module shared its name with a public function
of its package (``speckle.system.rolloff``), the package keeps the function before and after
the old path is imported, in either order. Each case runs in a fresh interpreter: a clean
``sys.modules``, so the first import (the one that warns) is the test's.
"""

from __future__ import annotations

import ast
import functools
import json
import subprocess
import sys
from pathlib import Path

import pytest

from speckle.conventions import RETIRED

REPO = Path(__file__).resolve().parents[1]
MODULES = sorted(old for old, (_, kind) in RETIRED.items() if kind == "module")


def _run(code: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO
    )
    return json.loads(out.stdout.splitlines()[-1])


#: In a fresh interpreter, for every retired path: resolve the package's public name first
#: (``first``) or not, import the old path twice, read every name it gives; report what was seen.
#: The paths do not share a module, so one interpreter serves them all.
PROBE = """
import importlib, json, sys, types, warnings
first, report = {first!r}, {{}}
for old, new in {pairs!r}:
    package, _, child = old.rpartition(".")
    pkg = importlib.import_module(package)
    public = child in pkg.__all__
    before = getattr(pkg, child) if public and first else None
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        exec(f"import {{old}}\\nimport {{old}}", {{}})
        shim = sys.modules[old]
        values = {{name: getattr(shim, name) for name in shim.__all__}}
        exec(f"from {{old}} import *", {{}})
    target = importlib.import_module(new)
    after = getattr(pkg, child)
    import speckle
    space = {{}}
    exec(f"from {{package}} import {{child}} as imported", space)
    report[old] = {{
        "warnings": [[w.category.__name__, str(w.message), w.filename] for w in seen],
        "same": all(values[n] is getattr(target, n) for n in target.__all__),
        "names": sorted(values) == sorted(target.__all__),
        "public": public,
        "kept": public and after is getattr(target, child) and (before is None or before is after)
            and space["imported"] is after and getattr(speckle, child) is after,
        "module_bound": isinstance(after, types.ModuleType) and after is shim,
    }}
print(json.dumps(report))
"""


@functools.cache
def _probe(first: bool) -> dict:
    return _run(PROBE.format(first=first, pairs=[(old, RETIRED[old][0]) for old in MODULES]))


@pytest.mark.parametrize("first", [True, False], ids=["name-first", "old-path-first"])
@pytest.mark.parametrize("old", MODULES)
def test_a_retired_module_path_warns_once_and_keeps_the_function(old, first):
    new = RETIRED[old][0]
    seen = _probe(first)[old]
    future = [w for w in seen["warnings"] if w[0] == "FutureWarning"]
    assert len(future) == 1, seen["warnings"]  # once, though imported twice and read fully
    (_, message, filename) = future[0]
    assert f"the module {old} is retired (now the private {new}): use " in message
    assert filename == "<string>", "the warning points at the line that imports the old path"
    assert seen["names"] and seen["same"], "the old path gives the new module's names"
    if seen["public"]:  # a function of the package shares the old module's name
        assert seen["kept"], f"{old} replaced the function {old} on its package"
        package, _, child = old.rpartition(".")
        assert f"from {package} import " in message and child in message
    else:
        assert seen["module_bound"], f"{old} as an attribute is the shim module"


def test_the_method_modules_name_the_methods_by_name():
    from speckle.imaging._rules import METHODS_INSTEAD  # private: the shims' advice

    assert METHODS_INSTEAD in _probe(False)["speckle.imaging.nufft"]["warnings"][0][1]
    assert "speckle.ascan(method=" in METHODS_INSTEAD


def test_the_function_behaves_the_same_before_and_after_the_old_path():
    """``speckle.system.rolloff(...)`` gives identical numbers before and after ``import
    speckle.system.rolloff``; ``import ... as`` gives the function, as in the release before."""
    code = """
import json, warnings
import numpy as np
import speckle
from speckle.system import rolloff as before
scene = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
a = speckle.system.rolloff(scene, z_max=256.0, resolution=2.0).amplitude.values
with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    import speckle.system.rolloff as aliased
    from speckle.system.rolloff import rolloff_curve
from speckle.system import rolloff as after
b = speckle.system.rolloff(scene, z_max=256.0, resolution=2.0).amplitude.values
c = after(scene, z_max=256.0, resolution=2.0).amplitude.values
print(json.dumps({"same": bool(np.array_equal(a, b) and np.array_equal(a, c)),
                  "identity": before is after is speckle.rolloff is aliased,
                  "curve": callable(rolloff_curve), "function": type(after).__name__}))
"""
    seen = _run(code)
    assert seen == {"same": True, "identity": True, "curve": True, "function": "function"}


def test_a_package_attribute_of_a_retired_path_is_the_shim():
    """``speckle.imaging.nufft`` (no import) is the shim module, warning once; ``speckle.scene
    .layers`` stays the module of the old path (its function's old name is ``layer_stack``)."""
    code = """
import json, types, warnings
import speckle
with warnings.catch_warnings(record=True) as seen:
    warnings.simplefilter("always")
    nufft = speckle.imaging.nufft
    again = speckle.imaging.nufft
    layers = speckle.scene.layers
print(json.dumps({"modules": [type(m).__name__ for m in (nufft, layers)],
                  "same": nufft is again,
                  "kernel_width": callable(nufft.kernel_width),
                  "warned": [str(w.message).split(" is retired")[0] for w in seen],
                  "where": [(w.filename, w.lineno) for w in seen]}))
"""
    seen = _run(code)
    assert seen["modules"] == ["module", "module"] and seen["same"] and seen["kernel_width"]
    assert seen["warned"] == ["the module speckle.imaging.nufft", "the module speckle.scene.layers"]
    assert seen["where"] == [["<string>", 6], ["<string>", 8]], "the lines that ask for them"


def test_unknown_names_of_a_retired_path_are_attribute_errors():
    code = """
import json, warnings
warnings.simplefilter("ignore", FutureWarning)
import speckle.imaging.nufft as shim
try:
    shim.no_such_name
except AttributeError as err:
    print(json.dumps({"error": str(err)}))
"""
    assert "'speckle.imaging.nufft' has no attribute 'no_such_name'" in _run(code)["error"]


def test_every_shim_is_listed_and_every_listed_path_has_a_shim():
    """The files that call ``retired_module`` are exactly the paths of kind ``module``."""

    def calls_it(path: Path) -> bool:
        return any(
            isinstance(node, ast.Assign)
            and isinstance(node.value, ast.Call)
            and getattr(node.value.func, "id", None) == "retired_module"
            for node in ast.parse(path.read_text()).body
        )

    shims = sorted(
        ".".join(path.relative_to(REPO).with_suffix("").parts)
        for path in (REPO / "speckle").rglob("*.py")
        if calls_it(path)
    )
    assert shims == MODULES
