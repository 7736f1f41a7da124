"""Issue 21: malformed inputs to scenes, regions and deformation give a TypeError/ValueError
naming a parameter, or a finite answer; never another exception or a hang."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st

import speckle.scene.deformation as dfm
import speckle.scene.regions as reg
import speckle.scene.shared as sh

REGIONS = reg.make_regions(reg.background(density=0.01), reg.circle(20.0, 20.0, 8.0, density=0.02))
SCENE = sh.shared_scene(REGIONS, z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile=20.0)
LINES = dfm.deformable_scene(4, 1.0, n_pixels=8, depth_range=64.0, seed=0, strain=0.01)

VALID = {
    "shared_scene": dict(z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile=20.0),
    "background": dict(density=0.01, backscatter=1.0, depolarization=0.2, youngs_modulus=10.0),
    "layer": dict(z_top=1.0, z_bottom=5.0, density=0.01),
    "circle": dict(centre_z=2.0, centre_x=2.0, radius=1.0, density=0.01),
    "region_label": dict(z=np.array([1.0, 30.0]), x=np.array([1.0, 20.0])),
    "rasterize": dict(depth_coord=np.arange(4.0), x_coord=np.arange(3.0)),
    "displace": dict(displacement=lambda z, x: 0.1 * z, wrap=False),
    "translate": dict(dz=1.0, dx=0.5, wrap=True),
    "uniaxial_strain": dict(strain=0.01, poisson_ratio=0.3, wrap=False),
    "cell_density": dict(per_cell=2.0, pixel_size=4.0, pitch=4.0, ndim=2),
}


PROPS = ["density", "backscatter", "attenuation", "depolarization", "youngs_modulus"]


def _call(name: str, kw: dict):
    if name == "shared_scene":
        return sh.shared_scene(REGIONS, **kw)
    if name == "background":
        return reg.make_regions(reg.background(**kw))[PROPS]  # geometry columns are NaN
    if name == "layer":
        return reg.make_regions(reg.layer(kw.pop("z_top"), kw.pop("z_bottom"), **kw))[PROPS]
    if name == "circle":
        shape = reg.circle(kw.pop("centre_z"), kw.pop("centre_x"), kw.pop("radius"), **kw)
        return reg.make_regions(reg.background(density=0.01), shape)[PROPS]
    if name == "region_label":
        return reg.region_label(REGIONS, kw["z"], kw["x"])
    if name == "rasterize":
        return reg.rasterize(REGIONS, kw["depth_coord"], kw["x_coord"])
    if name == "displace":
        return dfm.displace(SCENE, **kw)
    if name == "translate":
        return dfm.translate(LINES, kw.pop("dz"), **kw)
    if name == "uniaxial_strain":
        return dfm.uniaxial_strain(SCENE, kw.pop("strain"), **kw)
    return reg.cell_density(**kw)


@given(data=st.data())
def test_malformed_scene_inputs(malformed_target, data, malformed):
    malformed.run(VALID, _call, malformed_target, data)


def test_valid_calls_work():
    for name, kw in VALID.items():
        _call(name, dict(kw))


@given(
    shape=st.sampled_from([(3,), (2, 2), (SCENE.sizes["scatterer"] + 1,)]),
    fill=st.sampled_from([0.1, np.nan]),
)
def test_displacement_functions_of_any_shape(shape, fill, malformed):
    """A callable returning an array of the wrong shape or NaN: named, never numpy's error."""
    malformed.check(
        lambda: dfm.displace(SCENE, lambda z, x: np.full(shape, fill)), "displacement", shape
    )


def test_field_nan_outside_the_scene_is_accepted():
    """Issue 21: a field NaN where no scatterer lies (outside the sample) is valid."""
    depth = np.arange(0.0, 60.0, 4.0)
    x = np.arange(-4.0, 48.0, 4.0)
    uz = np.tile(0.01 * depth[:, None], (1, x.size))
    uz[-2:] = np.nan  # below the scene's 40 µm: no scatterer there
    field = xr.Dataset({"uz": (("depth", "x"), uz)}, coords={"depth": depth, "x": x})
    moved = dfm.displace(SCENE, field)
    np.testing.assert_allclose(moved.z - SCENE.z, 0.01 * SCENE.z, rtol=1e-12, atol=1e-12)
    uz[5, 5] = np.nan  # inside the scene: the scatterers it reaches are counted
    with pytest.raises(ValueError, match=r"uz is NaN at \d+ scatterer"):
        dfm.displace(SCENE, field)


def test_tile_counts_it_cannot_finish_are_refused():
    with pytest.raises(ValueError, match=r"tile too small.*1e\+10 tiles"):
        sh.shared_scene(REGIONS, z_range=(0.0, 1e5), x_range=(0.0, 1e5), seed=1, tile=1.0)
    with pytest.raises(TypeError, match="tile"):
        sh.shared_scene(REGIONS, z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile="64")
    dense = reg.make_regions(reg.background(density=10.0))
    with pytest.raises(ValueError, match="GiB"):
        sh.shared_scene(dense, z_range=(0.0, 1e5), x_range=(0.0, 1e5), seed=1, tile=1e4)


def test_strings_are_not_booleans():
    for bad in ("False", 0.5, 1):
        with pytest.raises(TypeError, match="wrap must be True or False"):
            dfm.displace(SCENE, lambda z, x: 0.0 * z, wrap=bad)


def test_depolarization_of_a_region_is_a_fraction():
    with pytest.raises(ValueError, match="depolarization"):
        reg.background(density=1.0, depolarization=1.5)
