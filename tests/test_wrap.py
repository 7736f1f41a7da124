"""The one wrapping decorator (``speckle._wrap.preprocess_and_wrap``, as MetPy's)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle._wrap import preprocess_and_wrap  # private: the decorator the analysis modules use


@preprocess_and_wrap(arrays=["x"], wrap_like="x", name="y", quantity="contrast", long_name="y")
def _square(x, power=2):
    assert isinstance(x, np.ndarray | float | int)  # the body never sees a DataArray
    return np.asarray(x, float) ** power


def test_plain_values_stay_plain():
    assert _square(3.0) == 9.0 and isinstance(_square(3.0), float)
    np.testing.assert_array_equal(_square(np.arange(3)), [0.0, 1.0, 4.0])


def test_labelled_values_keep_their_labels_and_get_the_table_attrs():
    x = xr.DataArray([1.0, 2.0], dims="depth", coords={"depth": [0.0, 5.0]}, attrs={"note": "a"})
    out = _square(x, power=3)
    assert out.name == "y" and out.dims == ("depth",)
    np.testing.assert_array_equal(out.depth, [0.0, 5.0])
    assert out.attrs["note"] == "a" and out.attrs["long_name"] == "y"
    np.testing.assert_array_equal(out, [1.0, 8.0])


def test_unknown_argument_refused_when_decorating():
    with pytest.raises(TypeError, match=r"has no arguments \['z'\]"):
        preprocess_and_wrap(arrays=["z"])(lambda x: x)


def test_first_users_keep_their_behaviour():
    density = xr.DataArray([1.0, 4.0], dims="density", coords={"density": [1.0, 4.0]})
    c = speckle.contrast_theory(density, 64)
    assert c.name == "contrast_theory" and c.dims == ("density",)
    assert speckle.contrast_theory(4.0, 64) == float(c[1])
    img = xr.DataArray(np.ones((8, 8)), dims=("depth", "x"))
    out = speckle.despeckle(img, "lee")
    assert out.attrs["filter"] == "lee" and out.attrs["domain"] == "linear"
