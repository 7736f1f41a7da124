"""Deformation of shared scenes: scatterers move continuously, nothing is re-binned."""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene import regions as R


def _scene(y=False):
    reg = speckle.make_regions(R.background(density=0.01 if not y else 0.0005))
    return speckle.shared_scene(
        reg,
        z_range=(0.0, 200.0),
        x_range=(0.0, 100.0),
        y_range=(0.0, 60.0) if y else None,
        seed=5,
        tile=50.0,
    )


def test_uniaxial_strain_with_poisson_expansion():
    scene = _scene()
    s = np.array([-0.02, 0.0, 0.05])
    out = speckle.uniaxial_strain(scene, s, poisson_ratio=0.4)
    assert out.z.dims == ("strain", "scatterer") and out.amplitude.dims == ("scatterer",)
    xr.testing.assert_identical(out.amplitude, scene.amplitude)
    xr.testing.assert_identical(out.region, scene.region)
    z, x = scene.z.values, scene.x.values
    for i, si in enumerate(s):
        np.testing.assert_allclose(out.z.values[i], z * (1 - si), rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            out.x.values[i], x + 0.4 * si * (x - 50.0), rtol=0, atol=1e-12
        )  # x_centre defaults to the middle of the x window
    assert out.attrs["x_centre"] == 50.0
    assert out.sizes["scatterer"] == scene.sizes["scatterer"]  # nothing dropped or re-binned


def test_uniaxial_strain_3d_expands_both_lateral_axes():
    scene = _scene(y=True)
    out = speckle.uniaxial_strain(scene, 0.1, poisson_ratio=0.5, x_centre=10.0, y_centre=20.0)
    np.testing.assert_allclose(out.y.values[0], scene.y.values + 0.05 * (scene.y.values - 20.0))
    np.testing.assert_allclose(out.x.values[0], scene.x.values + 0.05 * (scene.x.values - 10.0))
    np.testing.assert_allclose(out.z.values[0], 0.9 * scene.z.values)


def test_translate_moves_every_scatterer():
    scene = _scene()
    out = speckle.translate(scene, 1.25, dx=-0.3)
    np.testing.assert_allclose(out.z.values, scene.z.values + 1.25, rtol=0, atol=1e-13)
    np.testing.assert_allclose(out.x.values, scene.x.values - 0.3, rtol=0, atol=1e-13)
    many = speckle.translate(_scene(y=True), [0.0, 2.0])
    assert many.z.dims == ("shift", "scatterer")


def test_fem_field_over_depth_x_is_interpolated_exactly_when_linear():
    """A (depth, x) field as the mechanics solver writes it; linear fields interpolate exactly,
    also beyond the grid (linear extrapolation)."""
    scene = _scene()
    depth = np.arange(0.0, 150.0, 10.0)  # scene reaches 200 µm: extrapolated below 140
    x = np.arange(0.0, 101.0, 20.0)
    dd, xx = np.meshgrid(depth, x, indexing="ij")
    field = xr.Dataset(
        {
            "uz": (("depth", "x"), -0.01 * dd + 0.002 * xx),
            "ux": (("depth", "x"), 0.003 * (xx - 50.0) + 0.001 * dd),
        },
        coords={"depth": depth, "x": x},
    )
    out = speckle.displace(scene, field)
    z, xs = scene.z.values, scene.x.values
    np.testing.assert_allclose(out.z.values, z - 0.01 * z + 0.002 * xs, atol=1e-12)
    np.testing.assert_allclose(out.x.values, xs + 0.003 * (xs - 50.0) + 0.001 * z, atol=1e-12)


def test_callable_displacement_3d():
    scene = _scene(y=True)
    out = speckle.displace(scene, lambda z, x, y: (0.0 * z, 0.0 * x, np.sin(x)))
    np.testing.assert_allclose(out.y.values, scene.y.values + np.sin(scene.x.values))
    np.testing.assert_array_equal(out.z.values, scene.z.values)


def test_independent_lines_are_the_special_case_still_available():
    lines = speckle.deformable_scene(4, 2.0, n_pixels=16, depth_range=128.0, seed=0, strain=0.1)
    out = speckle.uniaxial_strain(lines, [0.0, 0.1])
    assert out.z.dims == ("strain", "aline", "scatterer")


@pytest.mark.parametrize(
    ("displacement", "match"),
    [
        (xr.DataArray(np.zeros(3), dims="aline", coords={"aline": [0.0, 1, 2]}), "dims among"),
        (xr.DataArray(np.zeros(3), dims="depth"), "coordinate 'depth'"),
        (
            xr.DataArray([0.0, np.nan, 1.0], dims="depth", coords={"depth": [0.0, 1, 2]}),
            "finite",
        ),
        (lambda z, x: (z, x, z), "3 components"),
        (lambda z, x: np.full(z.shape, np.inf), "finite"),
        ("up", "callable"),
    ],
)
def test_bad_displacements(displacement, match):
    with pytest.raises((ValueError, TypeError), match=match):
        speckle.displace(_scene(), displacement)


def test_bad_strain_on_shared_scenes():
    with pytest.raises(ValueError, match="strain"):
        speckle.uniaxial_strain(_scene(), 1.0)
    with pytest.raises(ValueError, match="poisson_ratio"):
        speckle.uniaxial_strain(_scene(), 0.1, poisson_ratio=0.7)
