"""Layered properties: lookups and exact path integrals (property-based)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import speckle
from speckle.scene._layers import layer_values, path_integral  # private: the profile helpers


@given(
    thickness=st.lists(st.floats(0.5, 200.0), min_size=1, max_size=6),
    mu=st.lists(st.floats(0.0, 0.05), min_size=7, max_size=7),
    z=st.floats(0.0, 1500.0),
)
def test_path_integral_equals_the_integral_of_the_lookup(thickness, mu, z):
    """int_0^z of the piecewise-constant profile: the analytic sum over layers vs a midpoint sum
    on a grid whose cells never straddle a layer edge (then the midpoint rule is exact)."""
    tops = np.concatenate([[0.0], np.cumsum(thickness)])
    stack = speckle.layer_stack(tops, attenuation=mu[: tops.size])
    edges = np.unique(np.concatenate([[0.0, z], tops[(tops > 0) & (tops < z)]]))
    mids = 0.5 * (edges[1:] + edges[:-1])
    exact = float(np.sum(layer_values(mids, stack, "attenuation") * np.diff(edges)))
    assert path_integral(z, stack, "attenuation") == pytest.approx(exact, rel=1e-12, abs=1e-15)


def test_first_layer_extends_up_to_the_surface_and_last_to_infinity():
    stack = speckle.layer_stack([50.0, 80.0], backscatter=[2.0, 3.0])
    np.testing.assert_array_equal(layer_values([0.0, 79.0, 1e9], stack, "backscatter"), [2, 2, 3])
    assert path_integral(100.0, stack, "backscatter") == pytest.approx(2 * 80 + 3 * 20)


def test_layers_refuse_bad_input():
    with pytest.raises(ValueError, match="at least one property"):
        speckle.layer_stack([0.0])
    with pytest.raises(ValueError, match="property must be one of"):
        speckle.layer_stack([0.0], colour=[1.0])
    with pytest.raises(ValueError, match="attenuation"):
        speckle.layer_stack([0.0], attenuation=[-0.1])
    with pytest.raises(TypeError, match="layers"):
        layer_values([1.0], {"top": [0.0]}, "attenuation")
