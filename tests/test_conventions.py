"""Units and long names come from ``speckle.conventions`` (one table, one helper)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from speckle import conventions

ROOT = Path(__file__).resolve().parents[1]
#: Every module of the package builds its labelled outputs with conventions.attrs/coord (or
#: conventions.labelled for units carried over from an input or a property table); only the
#: tables' own module writes a ``units`` attribute (issue 17).
MODULES = sorted(
    str(p.relative_to(ROOT)) for p in (ROOT / "speckle").rglob("*.py") if p.name != "conventions.py"
)


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


def test_extra_attrs_follow_and_may_not_replace_the_table():
    assert conventions.attrs("probability", "KS p-value", note="n") == {
        "units": "1",
        "long_name": "KS p-value",
        "note": "n",
    }
    with pytest.raises(ValueError, match="units"):
        conventions.attrs("length", units="mm")


def test_units_carried_over_from_an_input():
    assert conventions.units_of("wavenumber") == "rad/um"
    assert conventions.labelled("um", "bin centre") == {"units": "um", "long_name": "bin centre"}
    assert conventions.inverse_units("um") == "1/(um)" and conventions.inverse_units("1") == "1"
    with pytest.raises(TypeError, match="units"):
        conventions.labelled(None, "x")
    with pytest.raises(TypeError, match="long_name"):
        conventions.labelled("um", "")


def test_coord_along_its_own_or_another_dim():
    dims, values, attrs = conventions.coord("z", [1.0, 2.0], dims="position")
    assert dims == "position" and attrs == conventions.attrs("z")
    np.testing.assert_array_equal(values, [1.0, 2.0])
    dims, _, attrs = conventions.coord("depth", [0.0], "reflector depth")
    assert dims == "depth" and attrs == {"units": "um", "long_name": "reflector depth"}


def _literal(node: ast.expr) -> bool:
    """A hand-written string: a constant, an f-string or a choice between such."""
    if isinstance(node, ast.IfExp):
        return _literal(node.body) or _literal(node.orelse)
    return isinstance(node, ast.Constant | ast.JoinedStr)


def _hand_written_units(tree: ast.AST) -> list[int]:
    """Lines that write a units attribute by hand.

    A ``"units"`` key of a dict display (whatever its value), a ``units=`` keyword
    (``assign_attrs(units=...)``, ``dict(units=...)``), an assignment to ``[...]["units"]``,
    any other ``*units`` key or keyword given a string literal, and ``labelled`` given literal
    units (it is for units carried over from an input; a fixed quantity takes ``attrs``).
    """
    found = []
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and getattr(node.func, "id", getattr(node.func, "attr", None)) == "labelled"
            and node.args
            and _literal(node.args[0])
        ):
            found.append(node.args[0].lineno)
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                name = key.value if isinstance(key, ast.Constant) else None
                if name == "units" or (
                    isinstance(name, str) and name.endswith("units") and _literal(value)
                ):
                    found.append(value.lineno)
        elif isinstance(node, ast.keyword) and node.arg:
            if node.arg == "units" or (node.arg.endswith("units") and _literal(node.value)):
                found.append(node.value.lineno)
        elif isinstance(node, ast.Assign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                if (
                    isinstance(t, ast.Subscript)
                    and isinstance(t.slice, ast.Constant)
                    and t.slice.value == "units"
                ):
                    found.append(t.lineno)
    return sorted(found)


def test_the_check_finds_every_form():
    src = """
a = {"units": "um"}
b = {"units": u, "long_name": n}
c = {"pitch_units": "um"}
d = x.assign_attrs(units="1")
e = dict(units=u)
f = {"units": "um" if p else "pixel"}
x.attrs["units"] = "1"
h = conventions.labelled("um", "a length")
ok = {"pitch_units": attrs("length")["units"], "v": x.attrs.get("units")}
g = attrs("length")
i = labelled(units, "carried over")
"""
    assert _hand_written_units(ast.parse(src)) == [2, 3, 4, 5, 6, 7, 8, 9]


@pytest.mark.parametrize("path", MODULES)
def test_no_hand_written_units(path):
    """No ``units`` written by hand: conventions.attrs()/coord()/labelled() instead."""
    found = _hand_written_units(ast.parse((ROOT / path).read_text()))
    assert not found, f"{path}: hand-written units at lines {found}"
