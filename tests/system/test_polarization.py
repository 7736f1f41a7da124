"""Co- and cross-polarized channels: intensity ratio, degree of polarization, total law."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from scipy import integrate

import speckle
from speckle.system.polarization import total_intensity_contrast, total_intensity_pdf

N, H, RHO = 128, 512.0, 4.0


@pytest.fixture(scope="module")
def channels():
    src = speckle.spectrum(N, H, k0_dk=10)
    scene = speckle.random_scatterers(160, RHO, n_pixels=N, depth_range=H, seed=7)
    f = 0.3
    img = speckle.bscan(speckle.depolarize(scene, f, seed=1), src, method="nufft", tol=1e-10)
    return img, f, src


def _block_se(values):
    """SE of the mean of a per-A-line statistic (lines are independent)."""
    return values.std(ddof=1) / np.sqrt(values.size)


def test_cross_to_co_ratio_and_degree_of_polarization(channels):
    img, f, _ = channels
    i_co = img.intensity.sel(channel="co").mean("depth").values
    i_x = img.intensity.sel(channel="cross").mean("depth").values
    assert i_x.mean() / i_co.mean() == pytest.approx(
        f / (1 - f), rel=4 * _block_se(i_x) / i_x.mean() + 4 * _block_se(i_co) / i_co.mean()
    )
    p_line = speckle.degree_of_polarization(img, dims="depth").values
    # pooled over all lines: the |S2 + i S3| bias of a finite sample is negligible there
    p_all = float(speckle.degree_of_polarization(img))
    assert abs(p_all - (1 - 2 * f)) < 4 * _block_se(p_line)


def test_total_intensity_contrast_at_finite_density(channels):
    """C^2 = C0^2 - 2 c^2 d^2 (1 - 1/M), c^2 = 1 - f, d^2 = f; C0 of one channel (exact, fixed M).

    Derived like the package's contrast_theory: sums of M independent random phasors.
    """
    img, f, src = channels
    total = img.intensity.sum("channel")
    c0 = float(speckle.contrast_theory(RHO, N, src.values))
    m = round(RHO * N)
    expected = np.sqrt(c0**2 - 2 * f * (1 - f) * (1 - 1 / m))
    per_line = (total.std("depth") / total.mean("depth")).values  # pooled below
    pooled = float(total.std() / total.mean())
    assert pooled == pytest.approx(expected, abs=4 * _block_se(per_line))
    p = 1 - 2 * f
    assert total_intensity_contrast(p) == pytest.approx(np.sqrt(1 - 2 * f * (1 - f)))


@pytest.mark.parametrize("p", [0.0, 1e-9, 0.4, 1.0])
def test_total_intensity_pdf_is_normalised_with_the_right_moments(p):
    m = 2.0
    norm = integrate.quad(lambda i: total_intensity_pdf(i, m, p), 0, np.inf)[0]
    mean = integrate.quad(lambda i: i * total_intensity_pdf(i, m, p), 0, np.inf)[0]
    second = integrate.quad(lambda i: i**2 * total_intensity_pdf(i, m, p), 0, np.inf)[0]
    assert norm == pytest.approx(1.0, rel=1e-8)
    assert mean == pytest.approx(m, rel=1e-8)
    assert np.sqrt(second - mean**2) / mean == pytest.approx(total_intensity_contrast(p), rel=1e-7)


def test_layered_depolarization_routes_each_layer():
    scene = speckle.random_scatterers(4, 2.0, n_pixels=N, depth_range=H, seed=1)
    stack = speckle.layer_stack([0.0, 200.0], depolarization=[0.0, 1.0])
    out = speckle.depolarize(scene, stack, seed=3)
    top = scene.z < 200.0
    co, x = out.amplitude.sel(channel="co"), out.amplitude.sel(channel="cross")
    np.testing.assert_array_equal(x.where(top, 0.0), 0.0)
    np.testing.assert_array_equal(co.where(~top, 0.0), 0.0)
    np.testing.assert_allclose(abs(x).where(~top, 0.0), abs(scene.amplitude).where(~top, 0.0))


def test_bad_depolarization():
    scene = speckle.random_scatterers(2, 1.0, n_pixels=N, depth_range=H, seed=1)
    for bad in (-0.1, 1.2, float("nan")):
        with pytest.raises(ValueError, match="depolarization"):
            speckle.depolarize(scene, bad, seed=1)
    with pytest.raises(ValueError, match="depolarization"):
        speckle.layer_stack([0.0, 10.0], depolarization=[0.5, 1.5])


def test_depolarization_by_region_label():
    depth = np.arange(64) * 8.0 + 4.0
    lab = np.zeros((64, 4), dtype=int)
    lab[:, 2:] = 1  # right half: fully depolarizing region
    labels = xr.DataArray(
        lab, dims=("depth", "x"), coords={"depth": depth, "x": [0.0, 4.0, 8.0, 12.0]}
    )
    props = xr.Dataset({"depolarization": ("region", [0.0, 1.0])}, coords={"region": [0, 1]})
    scene = speckle.random_scatterers(4, 1.0, n_pixels=N, depth_range=H, seed=2, aline_pitch=4.0)
    out = speckle.depolarize(scene, props, seed=1, labels=labels)
    co, x = (abs(out.amplitude.sel(channel=c)) for c in ("co", "cross"))
    left = (scene.aline < 6.0).broadcast_like(scene.z)
    np.testing.assert_allclose(co.where(left, 0.0), abs(scene.amplitude).where(left, 0.0))
    np.testing.assert_array_equal(x.where(left, 0.0), 0.0)
    np.testing.assert_array_equal(co.where(~left, 0.0), 0.0)


def test_depolarization_by_region_of_a_shared_scene():
    """A shared scene's own region labels select f: region 1 fully depolarizing."""
    from speckle.scene.regions import layer, make_regions
    from speckle.scene.shared import shared_scene

    regions = make_regions(
        layer(0.0, 100.0, density=0.05, depolarization=0.0),
        layer(100.0, 200.0, density=0.05, depolarization=1.0),
    )
    scene = shared_scene(regions, z_range=(0.0, 200.0), x_range=(0.0, 50.0), seed=3)
    out = speckle.depolarize(scene, regions, seed=1)
    deep = scene.region == 1
    co, x = (abs(out.amplitude.sel(channel=c)) for c in ("co", "cross"))
    np.testing.assert_array_equal(co.where(deep, 0.0), 0.0)
    np.testing.assert_array_equal(x.where(~deep, 0.0), 0.0)
    np.testing.assert_allclose(x.where(deep, 0.0), abs(scene.amplitude).where(deep, 0.0))
