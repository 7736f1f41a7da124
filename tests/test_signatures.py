"""Public functions and classes: an Examples section, and options after the first two keyword-only.

Over ``speckle.__all__`` (issue 32). The Examples run as doctests in the default tier
(``--doctest-modules``). ``NO_EXAMPLES`` lists names still without one (empty now): it may
only shrink (a name listed that has gained an Example fails, so that it is struck off).
"""

from __future__ import annotations

import dataclasses
import inspect

import pytest

import speckle

PUBLIC = [
    n
    for n in speckle.__all__
    if inspect.isfunction(getattr(speckle, n)) or inspect.isclass(getattr(speckle, n))
]

#: Public names with no Examples section yet (shrink-only; issue 32): empty since every public
#: function and class has one; a name merged without one goes here until it gets one.
NO_EXAMPLES: set[str] = set()

#: Options after the first two parameters that stay positional, and why.
POSITIONAL_OPTIONS = {
    "System": "a frozen record built by speckle.datasheet: its fields in order, as a dataclass",
    "EquivalentSystem": "a frozen record built by speckle.equivalent_system: its fields in order",
    "ScannerConfig": "the challenge's INI file as a frozen record: its keys in the file's order",
    "contrast_theory": "spectrum: the third input of the theory, S(k_n) (docs pass it so)",
    "despeckle": "params: the named filter's own parameters, despeckle(I, 'lee', {'size': 7})",
    "region_label": "y: the third coordinate of a 3-D point, (z, x, y) in order",
    "translate": "dx: the lateral part of the displacement (dz, dx), in order",
}


def _has_examples(obj) -> bool:
    return "Examples\n" in inspect.cleandoc(obj.__doc__ or "")


@pytest.mark.parametrize("name", PUBLIC)
def test_public_name_has_an_examples_section(name):
    has = _has_examples(getattr(speckle, name))
    if name in NO_EXAMPLES:
        assert not has, f"{name} has Examples now: strike it off NO_EXAMPLES"
    else:
        assert has, f"speckle.{name} has no Examples section (numpydoc)"


def test_no_examples_lists_only_public_names():
    assert NO_EXAMPLES <= set(PUBLIC), sorted(NO_EXAMPLES - set(PUBLIC))


def _positional_options(obj) -> list[str]:
    """Parameters with a default, after the first two, that may still be passed by position."""
    params = [
        p
        for p in inspect.signature(obj).parameters.values()
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name != "self"
    ]
    return [p.name for p in params[2:] if p.default is not p.empty]


@pytest.mark.parametrize("name", PUBLIC)
def test_options_after_the_first_two_arguments_are_keyword_only(name):
    found = _positional_options(getattr(speckle, name))
    if name in POSITIONAL_OPTIONS:
        assert found, f"{name} needs no POSITIONAL_OPTIONS entry now: strike it off"
    else:
        assert not found, f"speckle.{name}: options {found} should be keyword-only (after *)"


def test_listed_exceptions_are_public_and_records_are_dataclasses():
    assert set(POSITIONAL_OPTIONS) <= set(PUBLIC)
    assert dataclasses.is_dataclass(speckle.System)
    assert dataclasses.is_dataclass(speckle.ScannerConfig)


def _intensity():
    import numpy as np
    import xarray as xr

    return xr.DataArray(np.ones((2, 3)), dims=("depth", "x"))


@pytest.mark.parametrize(
    "call, keywords",
    [
        (lambda: speckle.scan_lines(4, 2.0, 1.0), "start="),
        (lambda: speckle.add_floor(_intensity(), 0.1, 2.0), "mean_intensity="),
        (lambda: speckle.contrast_theory(4.0, 64, None, "equal", "poisson"), "amplitude=, count="),
        (lambda: speckle.interferogram_bytes(2, 3, 8, "direct"), "method="),
    ],
)
def test_positional_options_still_work_for_a_release_with_a_future_warning(call, keywords):
    with pytest.warns(FutureWarning, match=f"pass {keywords} by keyword"):
        call()


def test_positional_and_keyword_calls_agree():
    with pytest.warns(FutureWarning, match="start="):
        old = speckle.scan_lines(4, 2.0, 1.0)
    assert list(old) == list(speckle.scan_lines(4, 2.0, start=1.0)) == [1.0, 3.0, 5.0, 7.0]
    with pytest.warns(FutureWarning):
        assert speckle.contrast_theory(4.0, 64, None, "equal", "poisson") == (
            speckle.contrast_theory(4.0, 64, amplitude="equal", count="poisson")
        )
    with pytest.raises(TypeError, match="positional"):
        speckle.scan_lines(4, 2.0, 1.0, 5.0)
    with pytest.raises(TypeError, match="multiple values"):
        speckle.scan_lines(4, 2.0, 1.0, start=1.0)
