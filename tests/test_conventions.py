"""Units and long names come from ``speckle.conventions`` (one table, one helper)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from speckle import conventions

ROOT = Path(__file__).resolve().parents[1]
#: Modules whose labelled outputs are built with conventions.attrs/coord only (issue 17).
CONVERTED = [
    "speckle/figures/beam.py",
    "speckle/figures/deformation.py",
    "speckle/figures/histograms.py",
    "speckle/figures/speed.py",
    "speckle/figures/static.py",
    "speckle/figures/system.py",
]


def test_attrs_come_from_the_tables():
    assert conventions.attrs("depth") == {
        "units": "um",
        "long_name": "depth in the medium (pixel centre)",
    }
    assert conventions.attrs("level") == {"units": "dB", "long_name": "level 20 log10 |A|"}
    # a specific long name keeps the table's units
    assert conventions.attrs("length", "equivalent width") == {
        "units": "um",
        "long_name": "equivalent width",
    }
    for name, (units, long_name) in {**conventions.COORDS, **conventions.QUANTITIES}.items():
        assert conventions.attrs(name) == {"units": units, "long_name": long_name}


def test_unknown_quantity_is_refused_by_name():
    with pytest.raises(ValueError, match="'speed_of_light'"):
        conventions.attrs("speed_of_light")


def test_coord_along_its_own_or_another_dim():
    dims, values, attrs = conventions.coord("z", [1.0, 2.0], dims="position")
    assert dims == "position" and attrs == conventions.attrs("z")
    np.testing.assert_array_equal(values, [1.0, 2.0])
    dims, _, attrs = conventions.coord("depth", [0.0], "reflector depth")
    assert dims == "depth" and attrs == {"units": "um", "long_name": "reflector depth"}


def _literal(node: ast.expr) -> bool:
    return isinstance(node, ast.Constant | ast.JoinedStr)


@pytest.mark.parametrize("path", CONVERTED)
def test_no_hand_written_units(path):
    """No ``{"units": ...}`` literal and no ``units=`` keyword: attrs()/coord() instead."""
    tree = ast.parse((ROOT / path).read_text())
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                name = key.value if isinstance(key, ast.Constant) else None
                if isinstance(name, str) and name.endswith("units") and _literal(value):
                    found.append(value.lineno)
        elif isinstance(node, ast.keyword) and (node.arg or "").endswith("units"):
            if _literal(node.value):
                found.append(node.value.lineno)
    assert not found, f"{path}: hand-written units at lines {found}"
