"""Issue 21: malformed inputs to the FEM mechanics give a TypeError/ValueError naming a
parameter, or a finite answer; never another exception or a hang. Plus one unit of Young's
modulus (kPa), label -1 refused, and the solve's memory estimated before meshing."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st

import speckle.scene.mechanics as mech
import speckle.scene.regions as reg

DEPTH = np.arange(4.0, 64.0, 8.0)
X = np.arange(0.0, 48.0, 8.0)
LABELS = mech.inclusion_labels(DEPTH, X, (32.0, 24.0), 10.0)
FE = mech.compress_phantom(LABELS, {0: 10.0, 1: 40.0}, 0.3, strain=0.01)

VALID = {
    "compress_phantom": dict(
        youngs_modulus={0: 10.0, 1: 40.0},
        poisson_ratio=0.3,
        strain=0.01,
        contact="sliding",
        mesh_size=4.0,
    ),
    "inclusion_labels": dict(depth=DEPTH, x=X, center=(32.0, 24.0), radii=10.0),
    "layered_labels": dict(depth=DEPTH, x=X, interfaces=[20.0, 40.0]),
    "layer_strains": dict(
        thickness=[10.0, 20.0], youngs_modulus=[10.0, 30.0], poisson_ratio=[0.2, 0.3], strain=0.01
    ),
    "inclusion_strain": dict(
        strain=0.01,
        youngs_modulus=10.0,
        poisson_ratio=0.3,
        inclusion_modulus=40.0,
        inclusion_poisson_ratio=0.3,
    ),
    "displacement_at": dict(z=[10.0, 20.0], x=[5.0, 30.0]),
}


def _call(name: str, kw: dict):
    if name == "compress_phantom":
        return mech.compress_phantom(LABELS, **kw)[["uz", "ux", "strain_zz"]]
    if name == "inclusion_labels":
        return mech.inclusion_labels(kw["depth"], kw["x"], kw["center"], kw["radii"])
    if name == "layered_labels":
        return mech.layered_labels(**kw)
    if name == "layer_strains":
        return mech.layer_strains(**kw)
    if name == "inclusion_strain":
        return mech.inclusion_strain(**kw)
    return mech.displacement_at(FE, **kw)


@given(data=st.data())
def test_malformed_fem_inputs(malformed_target, data, malformed):
    malformed.run(VALID, _call, malformed_target, data)


def test_valid_calls_work():
    for name, kw in VALID.items():
        _call(name, dict(kw))


def test_one_unit_of_youngs_modulus():
    """Regions store kPa, as compress takes: a table passed through gives the same stress as
    the values typed in; a table in Pa is refused, and so are values implausible in kPa."""
    table = reg.make_regions(
        reg.background(density=1.0, youngs_modulus=10.0),
        reg.circle(32.0, 24.0, 10.0, density=1.0, youngs_modulus=40.0),
    )
    assert table.youngs_modulus.attrs["units"] == "kPa"
    fe = mech.compress_phantom(LABELS, table.youngs_modulus, 0.3, strain=0.01)
    np.testing.assert_allclose(fe.stress_zz, FE.stress_zz, rtol=1e-12)
    pa = table.youngs_modulus * 1e3
    pa.attrs["units"] = "Pa"
    with pytest.raises(ValueError, match="youngs_modulus is given in 'Pa'"):
        mech.compress_phantom(LABELS, pa, 0.3, strain=0.01)
    with pytest.raises(ValueError, match="kPa"):
        mech.compress_phantom(LABELS, 2e7, 0.3, strain=0.01)
    with pytest.raises(ValueError, match="kPa"):
        reg.background(density=1.0, youngs_modulus=5e9)


def test_label_minus_one_is_refused():
    empty = xr.full_like(LABELS, -1)
    with pytest.raises(ValueError, match=r"labels hold 48 of 48 pixel\(s\) with label -1"):
        mech.compress_phantom(empty, 10.0, 0.3, strain=0.01)


def test_memory_is_estimated_before_meshing():
    with pytest.raises(ValueError, match=r"mesh_size.*GiB"):
        mech.compress_phantom(LABELS, 10.0, 0.3, strain=0.01, mesh_size=0.01)
    # the estimate's fill model bounds the measured SuperLU fill (16x16 .. 128x128 pixels)
    assert mech.fem_bytes(129 * 129) > 12 * 5_204_623
