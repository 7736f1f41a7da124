"""Beer-Lambert attenuation and layered / per-region properties against exact results."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene._layers import layer_values, path_integral  # private: the profile helpers

N, H = 256, 1024.0


@pytest.fixture(scope="module")
def scene():
    return speckle.random_scatterers(64, 4.0, n_pixels=N, depth_range=H, seed=3)


def test_mean_log_intensity_falls_with_slope_minus_two_mu(scene):
    """E ln I(z) = ln <I(z)> - gamma with <I> ~ exp(-2 mu z): slope -2 mu per µm, per line."""
    mu = 2.0 / H  # 4 nepers of intensity over the image
    src = speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm_fraction=0.5)
    img = speckle.bscan(speckle.attenuate(scene, mu), src, method="nufft", tol=1e-9)
    rows = slice(32, N - 32)  # away from the wrap-around of the point-spread function
    z = img.depth.values[rows]
    logi = np.log(img.intensity.values[rows])  # (depth, aline)
    slopes = np.polyfit(z, logi, 1)[0]  # one slope per independent A-line
    se = slopes.std(ddof=1) / np.sqrt(slopes.size)
    assert abs(slopes.mean() + 2 * mu) < 4 * se
    assert se < 0.1 * 2 * mu  # the test resolves the slope to 10 %


def test_amplitudes_scale_by_exp_minus_tau(scene):
    mu = 1e-3
    out = speckle.attenuate(scene, mu)
    np.testing.assert_allclose(out.amplitude, scene.amplitude * np.exp(-mu * scene.z), rtol=1e-14)
    assert out.attrs["attenuation"] == mu and out.attrs["seed"] == scene.attrs["seed"]
    xr.testing.assert_identical(speckle.attenuate(scene, 0.0).amplitude, scene.amplitude)


def test_layers_path_integral_is_exact():
    stack = speckle.layer_stack([0.0, 100.0, 250.0], attenuation=[1e-3, 5e-3, 0.0])
    z = np.array([0.0, 50.0, 100.0, 200.0, 250.0, 400.0])
    expected = [0.0, 0.05, 0.1, 0.1 + 0.5, 0.1 + 0.75, 0.85]
    np.testing.assert_allclose(path_integral(z, stack, "attenuation"), expected, atol=1e-15)
    np.testing.assert_allclose(speckle.optical_depth(z, stack), expected, atol=1e-15)
    np.testing.assert_array_equal(
        layer_values([-5.0, 99.9, 100.0, 1e6], stack, "attenuation"), [1e-3, 1e-3, 5e-3, 0.0]
    )


def test_attenuation_map_from_labels():
    """Cumulative sum along depth: exp(-mu z) for one region, the exact integral for two."""
    dz, nz = 4.0, 50
    depth = np.arange(nz) * dz
    labels = xr.DataArray(
        np.zeros((nz, 3), dtype=int), dims=("depth", "x"), coords={"depth": depth, "x": [0, 1, 2]}
    )
    props = xr.Dataset({"attenuation": ("region", [2e-3, 8e-3])}, coords={"region": [0, 1]})
    np.testing.assert_allclose(
        speckle.attenuation_map(labels, props).isel(x=0), np.exp(-2e-3 * depth), rtol=1e-13
    )
    lab2 = labels.copy()
    lab2[25:, 1] = 1  # region 1 from the pixel edge at 98 µm down, in column 1
    edge = depth[25] - dz / 2
    tau = np.where(depth < edge, 2e-3 * depth, 2e-3 * edge + 8e-3 * (depth - edge))
    np.testing.assert_allclose(speckle.attenuation_map(lab2, props).isel(x=1), np.exp(-tau))


def test_bad_attenuation_inputs(scene):
    with pytest.raises(ValueError, match="attenuation"):
        speckle.attenuate(scene, -1e-3)
    with pytest.raises(ValueError, match="attenuation"):
        speckle.attenuate(scene, float("nan"))
    with pytest.raises(TypeError, match="scene"):
        speckle.attenuate(scene.z, 1e-3)
    with pytest.raises(ValueError, match="thickness"):
        speckle.layer_stack([0.0, 100.0, 100.0], attenuation=[1e-3, 1e-3, 1e-3])
    with pytest.raises(ValueError, match="one value per layer"):
        speckle.layer_stack([0.0, 100.0], attenuation=[1e-3])
    labels = xr.DataArray(np.array([[0], [2]]), dims=("depth", "x"), coords={"depth": [0.0, 1.0]})
    props = xr.Dataset({"attenuation": ("region", [1e-3])}, coords={"region": [0]})
    with pytest.raises(ValueError, match=r"labels \[2\]"):
        speckle.attenuation_map(labels, props)
    empty = xr.Dataset({"attenuation": ("region", np.zeros(0))}, coords={"region": np.zeros(0)})
    with pytest.raises(ValueError, match="no region"):
        speckle.attenuation_map(labels, empty)


def test_attenuation_and_backscatter_by_region_on_a_label_image():
    """Per scatterer: tau is the path integral through the regions of its column (linear
    interpolation of the cumulative sum: error <= |d mu| dz/4 next to a boundary inside a cell);
    backscatter is the value of the region holding the scatterer."""
    dz, nz = 1.0, 400
    depth = (np.arange(nz) + 0.5) * dz  # boundaries at pixel edges, tops at 0
    x = np.array([0.0, 8.0])
    lab = np.zeros((nz, 2), dtype=int)
    lab[150:, 1] = 1  # column x = 8: region 1 below 150 µm
    labels = xr.DataArray(lab, dims=("depth", "x"), coords={"depth": depth, "x": x})
    props = xr.Dataset(
        {"attenuation": ("region", [1e-3, 6e-3]), "backscatter": ("region", [1.0, 0.25])},
        coords={"region": [0, 1]},
    )
    z = np.array([[10.0, 149.0, 151.0, 300.0]] * 2)
    scene = xr.Dataset(
        {"z": (("aline", "scatterer"), z), "amplitude": (("aline", "scatterer"), np.ones((2, 4)))},
        coords={"aline": x},
    )
    att = speckle.attenuate_regions(scene, labels, props).amplitude.values
    tau = np.where(z < 150, 1e-3 * z, 0.15 + 6e-3 * (z - 150))
    np.testing.assert_allclose(att[0], np.exp(-1e-3 * z[0]), rtol=1e-12)
    np.testing.assert_allclose(-np.log(att[1]), tau[1], rtol=0, atol=5e-3 * dz / 4 + 1e-12)
    bs = speckle.backscatter_regions(scene, labels, props).amplitude.values
    np.testing.assert_allclose(bs**2, [[1, 1, 1, 1], [1, 1, 0.25, 0.25]])
    with pytest.raises(ValueError, match="outside the labelled scene"):
        speckle.attenuate_regions(scene.assign_coords(aline=[0.0, 30.0]), labels, props)


def test_layered_backscatter_scales_mean_intensity(scene):
    stack = speckle.layer_stack([0.0, 512.0], backscatter=[1.0, 4.0])
    out = speckle.backscatter(scene, stack)
    ratio = (abs(out.amplitude) / abs(scene.amplitude)).values
    np.testing.assert_allclose(ratio, np.where(scene.z.values < 512.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="backscatter"):
        speckle.backscatter(scene, -1.0)


def test_label_minus_one_is_no_medium():
    depth = np.arange(4) * 2.0
    labels = xr.DataArray(
        np.array([[-1], [-1], [0], [0]]), dims=("depth", "x"), coords={"depth": depth, "x": [0.0]}
    )
    props = xr.Dataset({"attenuation": ("region", [0.01])}, coords={"region": [0]})
    tau = -np.log(speckle.attenuation_map(labels, props).values[:, 0])
    np.testing.assert_allclose(tau, [0.0, 0.0, 0.01, 0.03], atol=1e-15)  # edge at 3 µm
    with pytest.raises(ValueError, match=r"labels \[-1\]"):
        speckle.region_values(labels, props, "attenuation")
