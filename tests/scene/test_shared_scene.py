"""Shared scenes: tile-seeded reproducibility, Poisson densities per region, bad inputs."""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene import regions as R
from speckle.scene.shared import check_scene, scene_window


def _regions():
    return speckle.make_regions(
        R.background(density=0.02),
        R.layer(100.0, 160.0, density=0.05, amplitude_model="equal"),
        R.circle(60.0, 150.0, 30.0, density=0.2, backscatter=4.0),
    )


def _scene(**kw):
    args = {"z_range": (0.0, 256.0), "x_range": (-50.0, 300.0), "seed": 7, "tile": 40.0}
    return speckle.shared_scene(_regions(), **{**args, **kw})


def test_same_scene_whatever_the_window_split():
    whole = _scene()
    left = _scene(x_range=(-50.0, 111.3))
    right = _scene(x_range=(111.3, 300.0))
    xr.testing.assert_identical(
        whole.drop_attrs(), xr.concat([left, right], "scatterer").drop_attrs()
    )
    top, bottom = _scene(z_range=(0.0, 97.0)), _scene(z_range=(97.0, 256.0))
    both = xr.concat([top, bottom], "scatterer")
    order = np.lexsort([both.z.values, both.x.values])
    xr.testing.assert_identical(whole.drop_attrs(), both.isel(scatterer=order).drop_attrs())
    assert np.all(np.diff(whole.x.values) >= 0)
    assert whole.attrs["kind"] == "shared" and whole.attrs["ndim"] == 2


def test_same_3d_scene_whatever_the_window_split():
    reg = speckle.make_regions(R.background(density=0.002))
    kw = {"z_range": (0.0, 64.0), "x_range": (0.0, 60.0), "seed": 3, "tile": 25.0}
    whole = speckle.shared_scene(reg, y_range=(-10.0, 50.0), **kw)
    parts = [speckle.shared_scene(reg, y_range=r, **kw) for r in ((-10.0, 12.5), (12.5, 50.0))]
    both = xr.concat(parts, "scatterer")
    order = np.lexsort([both.y.values, both.z.values, both.x.values])
    xr.testing.assert_identical(whole.drop_attrs(), both.isel(scatterer=order).drop_attrs())
    assert whole.attrs["ndim"] == 3 and set(whole.data_vars) >= {"x", "y", "z"}


def test_seed_and_tile_define_the_scene():
    a, b = _scene(), _scene()
    xr.testing.assert_identical(a, b)
    assert not np.array_equal(a.z.values[:10], _scene(seed=8).z.values[:10])


def test_region_counts_are_poisson_with_the_region_density():
    reg = _regions()
    scene = speckle.shared_scene(
        reg, z_range=(0.0, 400.0), x_range=(0.0, 2000.0), seed=11, tile=50.0
    )
    labels = speckle.region_label(reg, scene.z.values, scene.x.values)
    np.testing.assert_array_equal(scene.region.values, labels)
    # Inclusion (circle of radius 30 µm, density 0.2/µm^2): mean count rho*pi*r^2.
    mu = 0.2 * np.pi * 30.0**2
    n_incl = int((scene.region == 2).sum())
    assert abs(n_incl - mu) < 5 * np.sqrt(mu)
    # Background below the layer (z in [160, 400)): K equal cells, each count Poisson(mu_c).
    deep = scene.where((scene.z >= 160.0), drop=True)
    counts, _, _ = np.histogram2d(
        deep.z.values, deep.x.values, bins=[6, 50], range=[[160.0, 400.0], [0.0, 2000.0]]
    )
    mu_c = 0.02 * (240.0 / 6) * (2000.0 / 50)
    k = counts.size
    assert abs(counts.mean() - mu_c) < 5 * np.sqrt(mu_c / k)
    dispersion = counts.var(ddof=1) / counts.mean()  # 1 for Poisson, SE sqrt(2/(k-1))
    assert abs(dispersion - 1.0) < 5 * np.sqrt(2.0 / (k - 1))
    # Mean backscatter of the inclusion: E|a|^2 = 4 (Rayleigh: |a|^2 exponential, SE = mean/sqrt n).
    a2 = np.abs(scene.amplitude.values[scene.region.values == 2]) ** 2
    assert abs(a2.mean() - 4.0) < 5 * 4.0 / np.sqrt(a2.size)
    layer = np.abs(scene.amplitude.values[scene.region.values == 1])
    np.testing.assert_allclose(layer, 1.0)  # "equal" amplitudes


def test_window_slicing():
    scene = _scene()
    part = scene_window(scene, 10.0, 20.0)
    assert np.all((part.x >= 10.0) & (part.x < 20.0))
    assert part.sizes["scatterer"] == int(((scene.x >= 10.0) & (scene.x < 20.0)).sum())


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"x_range": (10.0, 10.0)}, r"x_range\[1\]"),
        ({"z_range": (5.0, 1.0)}, r"z_range\[1\]"),
        ({"z_range": (0.0, np.nan)}, "finite"),
        ({"tile": 0.0}, "tile"),
        ({"tile": (10.0, -1.0)}, "tile"),
        ({"seed": -1}, "seed"),
        ({"x_range": (0.0,)}, "x_range"),
    ],
)
def test_bad_inputs(kw, match):
    with pytest.raises((ValueError, TypeError), match=match):
        _scene(**kw)


def test_bad_regions_and_empty_scenes():
    with pytest.raises(TypeError, match="regions"):
        speckle.shared_scene(xr.Dataset(), z_range=(0, 1), x_range=(0, 1), seed=0)
    empty = speckle.shared_scene(
        speckle.make_regions(R.background(density=0.0)), z_range=(0, 10), x_range=(0, 10), seed=0
    )
    assert empty.sizes["scatterer"] == 0
    with pytest.raises(ValueError, match="no scatterers"):
        check_scene(empty)
    with pytest.raises(TypeError, match="shared scene"):
        check_scene(speckle.random_scatterers(2, 1.0, n_pixels=8, depth_range=64.0, seed=0))
