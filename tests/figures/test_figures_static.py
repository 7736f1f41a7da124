"""Tests of speckle.figures.static (Figs. 1, 2, 5) against exact results."""

from __future__ import annotations

import matplotlib.figure
import numpy as np
import pytest
import xarray as xr

from speckle.figures import static

N = 16
PIXEL = 8.0


@pytest.fixture(scope="module")
def fig1():
    return static.single_scatterer(
        [0.0, 1.0, 1.25, 3.5], [0.0, 10.0, 2.5], n_pixels=N, pixel_size=PIXEL
    )


def test_pixel_centred_scatterer_is_one_pixel(fig1):
    # Rectangular spectrum: A(q) = sum_n exp(2i pi n (p - q)/N) = N delta_{pq} (times the
    # common phase exp(2i k0 z0)).
    for p in (0.0, 1.0):
        amp = np.abs(fig1.ascan.sel(position=p).values)
        expected = np.zeros(N)
        expected[int(p)] = N
        np.testing.assert_allclose(amp, np.broadcast_to(expected, amp.shape), atol=1e-11)


@pytest.mark.parametrize("p", [1.25, 3.5])
def test_subpixel_scatterer_gives_dirichlet_kernel(fig1, p):
    # |sum_{n} exp(2i pi n d/N)| over N consecutive n = |sin(pi d)/sin(pi d/N)|, d = p - q.
    d = p - np.arange(N)
    expected = np.abs(np.sin(np.pi * d) / np.sin(np.pi * d / N))
    for r in fig1.k0_dk.values:
        amp = np.abs(fig1.ascan.sel(position=p, k0_dk=r).values)
        np.testing.assert_allclose(amp, expected, rtol=1e-10, atol=1e-11)


def test_spectral_components_sum_to_the_ascan(fig1):
    # A(q) = sum_n F_n exp(-2i pi n q/N): the pixel image is the DFT of the components.
    n = fig1.n.values
    q = np.arange(N)
    kernel = np.exp(-2j * np.pi * np.outer(n, q) / N)
    direct = fig1.spectral_component.values @ kernel
    np.testing.assert_allclose(direct, fig1.ascan.values, atol=1e-10 * N)


def test_k0_is_a_common_phase(fig1):
    # k0 multiplies every component by exp(2i k0 z0); |F_n| = S_n and |A(q)| do not change.
    np.testing.assert_allclose(np.abs(fig1.spectral_component.values), 1.0, rtol=1e-12)
    ratio = fig1.ascan.sel(k0_dk=10.0) / fig1.ascan.sel(k0_dk=0.0)
    z0 = fig1.z0
    k0 = 10.0 * N * np.pi / (N * PIXEL)  # k0_dk * delta_k, delta_k = N pi/H, H = N * pixel
    peak = np.abs(fig1.ascan.sel(k0_dk=0.0)).argmax("depth")
    phase = ratio.isel(depth=peak)
    np.testing.assert_allclose(phase.values, np.exp(2j * k0 * z0.values), atol=1e-10)


def test_k0_sweep_images_the_same_scatterers():
    # One scatterer per A-line (density 1/N): the image of each line is one Dirichlet kernel
    # whose modulus does not depend on k0, so |A| agrees exactly across k0_dk iff the
    # scatterers are the same.
    ds = static.k0_sweep(
        [10.0, 1.0, 3.0],
        density=1 / N,
        n_alines=12,
        n_pixels=N,
        pixel_size=PIXEL,
        seed=3,
        bins=8,
        normalise="none",
        dask={"scheduler": "synchronous"},
    )
    amp = ds.amplitude.values
    np.testing.assert_allclose(amp[1], amp[0], atol=1e-11)
    np.testing.assert_allclose(amp[2], amp[0], atol=1e-11)
    assert ds.amplitude_density.dims == ("k0_dk", "bin")
    assert ds.rayleigh_sigma.dims == ("k0_dk",)


def test_density_sweep_is_normalised_and_scheduler_independent():
    kw = dict(k0_dk=10.0, n_alines=6, n_pixels=N, pixel_size=PIXEL, seed=5)
    a = static.density_sweep([0.5, 2.0], dask={"scheduler": "synchronous"}, **kw)
    b = static.density_sweep([0.5, 2.0], dask={"scheduler": "threads", "n_workers": 2}, **kw)
    np.testing.assert_array_equal(a.field.values, b.field.values)
    raw = static.speckle_image(2.0, normalise="none", **kw)
    np.testing.assert_allclose(
        a.field.sel(density=2.0).values * np.sqrt(2.0), raw.field.values, rtol=1e-12
    )
    assert a.field.dims == ("density", "depth", "x")


def test_fragment_bounds():
    ds = static.speckle_image(1.0, 10.0, n_alines=10, n_pixels=N, pixel_size=PIXEL, seed=1)
    assert static.fragment(ds, {"depth": 6, "x": 0, "size": 10}).amplitude.shape == (10, 10)
    with pytest.raises(ValueError, match=r"fragment\.depth"):
        static.fragment(ds, {"depth": 7, "x": 0, "size": 10})
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):  # retired key
        old = static.fragment(ds, {"depth": 6, "aline": 0, "size": 10})
    xr.testing.assert_identical(old, static.fragment(ds, {"depth": 6, "x": 0, "size": 10}))
    with pytest.raises(ValueError, match=r"fragment\.x"):
        static.fragment(ds, {"depth": 0, "x": 1, "size": 10})


def test_dask_options_cap_local_workers():
    cfg = {"scheduler": "threads", "address": None, "n_workers": 8}
    assert static.dask_options(cfg, 2)["n_workers"] == 2
    remote = {"scheduler": "distributed", "address": "tcp://h:8786", "n_workers": 8}
    assert static.dask_options(remote, 2) == remote


def test_gaussian_source_needs_fwhm():
    with pytest.raises(ValueError, match="fwhm_fraction"):
        static.source_spectrum(
            {"n_pixels": N, "pixel_size": PIXEL, "k0_dk": 10.0, "shape": "gaussian"}
        )


def test_plots_draw(fig1):
    frag = {"depth": 0, "x": 0, "size": 4}
    images = static.density_sweep(
        [1.0, 4.0],
        k0_dk=10.0,
        n_alines=4,
        n_pixels=N,
        pixel_size=PIXEL,
        seed=2,
        dask={"scheduler": "synchronous"},
    )
    k0 = static.k0_sweep(
        [10.0, 1.0],
        density=4.0,
        n_alines=4,
        n_pixels=N,
        pixel_size=PIXEL,
        seed=2,
        bins=10,
        dask={"scheduler": "synchronous"},
    )
    for fig in (
        static.plot_single_scatterer(fig1),
        static.plot_density_fragments(images, frag),
        static.plot_k0_fragments(k0, frag),
    ):
        assert isinstance(fig, matplotlib.figure.Figure)


def test_sweep_arguments_checked_before_work():
    with pytest.raises(TypeError, match="bogus"):
        static.density_sweep(
            [1.0], k0_dk=1.0, n_alines=2, n_pixels=N, pixel_size=PIXEL, seed=1, bogus=3
        )
    with pytest.raises(TypeError, match="density"):
        static.k0_sweep([1.0], n_alines=2, n_pixels=N, pixel_size=PIXEL, seed=1)
