"""Regions: geometry, painter's order, label images, properties and bad inputs."""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene import regions as R


def _regions():
    return speckle.make_regions(
        R.background(density=0.01),
        R.layer(40.0, 80.0, density=0.02, amplitude_model="equal"),
        R.circle(60.0, 100.0, 15.0, density=0.05, backscatter=4.0, name="inclusion"),
    )


def test_table_has_properties_and_room_for_other_columns():
    reg = _regions()
    assert list(reg.region.values) == [0, 1, 2]
    assert list(reg["shape"].values) == ["background", "layer", "ellipse"]
    np.testing.assert_array_equal(reg.density.values, [0.01, 0.02, 0.05])
    assert reg.backscatter.values.tolist() == [1.0, 1.0, 4.0]
    assert reg.amplitude_model.values.tolist() == ["rayleigh", "equal", "rayleigh"]
    for name in ("attenuation", "depolarization", "youngs_modulus", "poisson_ratio"):
        assert name in reg and np.all(np.isfinite(reg[name].values))
    extra = speckle.make_regions(R.background(density=0.1, refractive_index=1.38))
    assert float(extra.refractive_index[0]) == 1.38


def test_painter_order_and_boundaries():
    reg = _regions()
    z = np.array([0.0, 39.999, 40.0, 79.999, 80.0, 60.0, 60.0, 60.0, 74.9, 75.1])
    x = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 100.0, 114.9, 115.1, 100.0, 100.0])
    expected = [0, 0, 1, 1, 0, 2, 2, 1, 2, 1]  # (75.1, 100): outside the circle, in the layer
    np.testing.assert_array_equal(speckle.region_label(reg, z, x), expected)


def test_ellipsoid_and_cylinder_in_3d():
    reg = speckle.make_regions(
        R.background(density=0.0),
        R.ellipse(10.0, 0.0, 5.0, 5.0, centre_y=0.0, radius_y=2.0, density=1.0),
        R.circle(30.0, 0.0, 5.0, density=1.0),
    )
    z = np.array([10.0, 10.0, 30.0, 30.0])
    x = np.zeros(4)
    y = np.array([1.9, 2.1, 100.0, -100.0])  # circle without centre_y: cylinder along y
    np.testing.assert_array_equal(speckle.region_label(reg, z, x, y), [1, 0, 2, 2])


def test_rasterize_and_label_image_round_trip():
    reg = _regions()
    depth = np.arange(0.0, 128.0, 4.0)
    x = np.arange(0.0, 160.0, 4.0)
    img = speckle.rasterize(reg, depth, x)
    assert img.dims == ("depth", "x") and img.dtype == np.int32
    assert img.depth.attrs["units"] == "um"
    zz, xx = np.meshgrid(depth, x, indexing="ij")
    np.testing.assert_array_equal(img.values, speckle.region_label(reg, zz, xx))
    props = [{"density": float(d)} for d in reg.density.values]
    from_img = R.from_label_image(img, props)
    # Nearest pixel: points within half a pixel of a centre take its label; outside: -1.
    np.testing.assert_array_equal(speckle.rasterize(from_img, depth, x).values, img.values)
    jitter = speckle.region_label(from_img, zz + 1.9, xx - 1.9)
    np.testing.assert_array_equal(jitter, img.values)
    outside = speckle.region_label(from_img, np.array([-2.1, 0.0]), np.array([0.0, 158.1]))
    np.testing.assert_array_equal(outside, [-1, -1])
    box = R.bounding_box(from_img, 0)
    assert box["z"] == (-2.0, 126.0) and box["x"] == (-2.0, 158.0)


def test_cell_density():
    assert R.cell_density(2.0, 8.0, 4.0) == pytest.approx(2.0 / 32.0)
    assert R.cell_density(1.0, 8.0, 4.0, ndim=3) == pytest.approx(1.0 / 128.0)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: speckle.make_regions(), "at least one shape"),
        (lambda: R.background(density=-1.0), "density"),
        (lambda: R.layer(10.0, 10.0, density=1.0), "z_bottom"),
        (lambda: R.circle(0.0, 0.0, 0.0, density=1.0), "radius_z"),
        (lambda: R.background(density=1.0, amplitude_model="gauss"), "amplitude_model"),
        (lambda: R.background(density=1.0, backscatter=-2.0), "backscatter"),
        (lambda: R.ellipse(0.0, 0.0, 1.0, 1.0, centre_y=0.0, density=1.0), "together"),
        (lambda: speckle.make_regions({"shape": "star"}), "shape 0"),
        (lambda: speckle.region_label(_regions(), [1.0, 2.0], [1.0]), "same shape"),
        (lambda: speckle.region_label(_regions(), [np.nan], [1.0]), "finite"),
        (lambda: speckle.rasterize(_regions(), [], [1.0]), "non-empty"),
    ],
)
def test_bad_inputs(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_bad_label_images():
    img = xr.DataArray(
        np.array([[0, 1], [2, 0]]), dims=("depth", "x"), coords={"depth": [0.0, 4.0], "x": [0, 4.0]}
    )
    with pytest.raises(ValueError, match=r"\[-1, 1\]"):
        R.from_label_image(img, [{"density": 1.0}, {"density": 1.0}])
    with pytest.raises(TypeError, match="integers"):
        R.from_label_image(img.astype(float), [{"density": 1.0}] * 3)
    with pytest.raises(ValueError, match="dims"):
        R.from_label_image(img.rename(x="aline"), [{"density": 1.0}] * 3)
    with pytest.raises(ValueError, match="density"):
        R.from_label_image(img, [{"density": 1.0}, {}, {"density": 1.0}])
