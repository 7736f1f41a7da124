"""Every public function of statistics, dynamics, dynamics_theory, sparse, filters,
image_quality and compounding goes through the one wrapping decorator
(``speckle._wrap.preprocess_and_wrap``: checks once, xarray in and out in one place), or is
listed here with the reason it does not (issue 32)."""

from __future__ import annotations

import importlib
import inspect

import pytest

MODULES = ("statistics", "dynamics", "dynamics_theory", "sparse", "filters", "image_quality")
MODULES += ("compounding",)

_NO_ARRAY = "no array argument: nothing to check or label"
_REDUCED = (
    "its result is not shaped like an argument (a reduction or new dims): the decorator's "
    "wrap_like labels same-shaped results only, and its body would lose the units/dims it needs"
)
_WRAPPER = (
    "the one xarray wrapper of a decorated numpy core (*_array): a Dataset gives its "
    "intensity or, without one, its field (two variables; the decorator's ArraySpec.variable "
    "names one)"
)
#: Public functions that are not decorated, and why.
EXCEPTIONS = {
    "filter_available": _NO_ARRAY,
    "time_per_megapixel": _NO_ARRAY,
    "subband_fwhm": _NO_ARRAY,
    "subband_windows": _NO_ARRAY,
    "rayleigh_pdf": "elementwise through xarray.apply_ufunc, which keeps any argument's labels",
    "exponential_pdf": "elementwise through xarray.apply_ufunc, which keeps any argument's labels",
    "brownian_frames": "scene: a scatterer Dataset (positions per scatterer), not an image",
    **{n: _WRAPPER for n in ("g2", "liv", "ocds", "speckle_variance")},
}


def _public():
    for m in MODULES:
        mod = importlib.import_module(f"speckle.analysis.{m}")
        for n in mod.__all__:
            f = getattr(mod, n)
            if callable(f) and not inspect.isclass(f):
                yield n, f


@pytest.mark.parametrize(("name", "func"), list(_public()), ids=lambda v: str(v)[:40])
def test_decorated_or_listed_with_a_reason(name, func):
    decorated = hasattr(func, "__speckle_checks__")
    assert decorated != (name in EXCEPTIONS), (
        f"{name}: decorate it with speckle._wrap.preprocess_and_wrap"
        if not decorated
        else f"{name} is decorated: remove it from EXCEPTIONS"
    )


def test_exceptions_are_public_names():
    names = {n for n, _ in _public()}
    assert set(EXCEPTIONS) <= names, sorted(set(EXCEPTIONS) - names)
