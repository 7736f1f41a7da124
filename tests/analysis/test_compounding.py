"""Compounding looks and the speckle-free truth against their theory.

Statistical errors are derived in each test: independent A-lines with a rectangular spectrum
and a dense scene give independent pixels across lines, so a statistic's standard error is the
spread of its value over blocks of lines divided by sqrt(blocks).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import compounding as cp
from speckle.imaging.truth import intensity_spectrum, speckle_free_image, speckle_free_lines
from speckle.studies import looks as looks_study

N = 128
H = N * 8.0
BLOCKS = 16


@pytest.fixture(scope="module")
def dense():
    """Independent lines, 64 scatterers per pixel (Poisson), rectangular spectrum: one image."""
    src = speckle.spectrum(N, H, k0_dk=10)
    sc = speckle.random_scatterers(256, 64.0, n_pixels=N, depth_range=H, seed=7, count="poisson")
    img = speckle.bscan(sc, src, method="finufft", tol=1e-9)
    return src, sc, img


def _blocked(stat, img2d: np.ndarray) -> tuple[float, float]:
    """Statistic on the whole image and its SE from BLOCKS blocks of lines (last axis)."""
    parts = [stat(b) for b in np.array_split(img2d, BLOCKS, axis=-1)]
    return float(stat(img2d)), float(np.std(parts, ddof=1) / np.sqrt(BLOCKS))


def _contrast(i):
    return i.std() / i.mean()


def test_truth_is_the_incoherent_sum_exactly():
    """sum_j |a_j|^2 |h_j|^2 with each scatterer imaged alone (beam + Gaussian spectrum)."""
    rng = np.random.default_rng(3)
    n, h, p = 32, 256.0, 8.0
    src = speckle.spectrum(n, h, k0_dk=3, shape="gaussian", fwhm_fraction=0.4)
    m = 40
    sc = xr.Dataset(
        {
            "z": ("scatterer", rng.uniform(0, h, m)),
            "x": ("scatterer", np.sort(rng.uniform(-20, 100, m))),
            "amplitude": ("scatterer", rng.uniform(0.5, 2, m) * np.exp(2j * np.pi * rng.random(m))),
            "region": ("scatterer", np.zeros(m, int)),
        }
    )
    x = speckle.scan_lines(10, p)
    truth = speckle_free_image(sc, src, waist=12.0, lines=x).values
    kw = dict(
        lines=x, waist=12.0, n_pixels=n, depth_range=h, k0=src.attrs["k0"], spectrum=src.values
    )
    ref = sum(
        np.abs(
            speckle.beam_scan([sc.z.values[j]], [sc.x.values[j]], [sc.amplitude.values[j]], **kw)
        )
        ** 2
        for j in range(m)
    ).T
    np.testing.assert_allclose(truth, ref, rtol=1e-9, atol=1e-12 * ref.max())
    # independent lines: the same identity through speckle.ascan
    z = rng.uniform(0, h, (3, m))
    a = rng.rayleigh(1, (3, m)) + 0j
    lines = speckle_free_lines(z, a, n_pixels=n, depth_range=h, spectrum=src.values)
    ref = sum(
        np.abs(
            speckle.ascan(
                z[:, j : j + 1],
                a[:, j : j + 1],
                n_pixels=n,
                depth_range=h,
                k0=src.attrs["k0"],
                spectrum=src.values,
            )
        )
        ** 2
        for j in range(m)
    )
    np.testing.assert_allclose(lines, ref, rtol=1e-9, atol=1e-12 * ref.max())


def test_intensity_spectrum_is_the_autocorrelation():
    s = np.array([1.0, 2.0, 0.5])
    r = intensity_spectrum(s)
    assert r.tolist() == pytest.approx([0, 0.5, 2 + 1.0, 1 + 4 + 0.25, 2 + 1.0, 0.5])


def test_truth_is_the_mean_over_phase_realisations():
    """The mean of R realisations converges to the truth as 1/sqrt(R).

    Per pixel Var_phases(I) = T^2 - sum_j |a_j h_j|^4 <= T^2, so z = (mean_R - T)/(T/sqrt(R))
    has E z^2 <= 1 (close to 1 when many scatterers share a pixel), whatever R.
    """
    n, h = 32, 256.0
    src = speckle.spectrum(n, h, k0_dk=10, shape="gaussian", fwhm_fraction=0.3)
    reg = speckle.make_regions(
        speckle.scene.regions.background(density=speckle.scene.regions.cell_density(4, 8, 8))
    )
    sc = speckle.shared_scene(reg, z_range=(0, h), x_range=(-80, 330.0), seed=1)
    x = speckle.scan_lines(32, 8.0)
    truth = speckle_free_image(sc, src, waist=16.0, lines=x, method="finufft", tol=1e-10).values
    rng = np.random.default_rng(0)
    kw = dict(
        lines=x,
        waist=16.0,
        n_pixels=n,
        depth_range=h,
        k0=src.attrs["k0"],
        spectrum=src.values,
        method="finufft",
        tol=1e-10,
    )
    total, stats = 0.0, {}
    for r in range(1, 257):
        a = sc.amplitude.values * np.exp(2j * np.pi * rng.random(sc.sizes["scatterer"]))
        total = total + np.abs(speckle.beam_scan(sc.z.values, sc.x.values, a, **kw).T) ** 2
        if r in (16, 256):
            z = (total / r - truth) / (truth / np.sqrt(r))
            stats[r] = (np.mean(z**2), np.sqrt(np.mean(((total / r - truth) / truth) ** 2)))
    # pixels are correlated over ~2 x 2 (beam and spectrum): >= 256 independent values of z^2,
    # whose variance is 2 for Gaussian z: SE of mean z^2 <= sqrt(2/256) = 0.09
    for r, (z2, _) in stats.items():
        assert 0.7 < z2 < 1.0 + 4 * 0.09, (r, z2)
    ratio = stats[16][1] / stats[256][1]
    assert ratio == pytest.approx(4.0, rel=4 * 0.09)


def test_single_look_statistics(dense):
    """ENL 1, amplitude mean/std sqrt(pi/(4 - pi)) = 1.913, std of 10 log10 I = 5.57 dB."""
    _, _, img = dense
    i = img.intensity.values
    # the finite density (Poisson, rho = 64) gives C^2 = 1 + (2/3)/rho: ENL 0.9897
    enl, se = _blocked(lambda b: b.mean() ** 2 / b.var(), i)
    expected = 1 / cp.split_spectrum_contrast(np.ones((1, N)), 64.0) ** 2
    assert abs(enl - expected) < 3 * se, (enl, expected, se)
    assert abs(enl - 1.0) < 3 * se + (1 - expected)
    amp, se = _blocked(lambda b: np.sqrt(b).mean() / np.sqrt(b).std(), i)
    assert abs(amp - np.sqrt(np.pi / (4 - np.pi))) < 3 * se + 0.01, (amp, se)  # O(1/rho) bias
    log, se = _blocked(lambda b: (10 * np.log10(b)).std(), i)
    assert abs(log - 10 / np.log(10) * np.pi / np.sqrt(6)) < 3 * se + 0.02, (log, se)
    assert 10 / np.log(10) * np.pi / np.sqrt(6) == pytest.approx(5.57, abs=0.005)


@pytest.mark.parametrize("looks", [2, 4, 8])
def test_uncorrelated_subbands_give_one_over_sqrt_n(dense, looks):
    src, _, img = dense
    w = cp.subband_apodizations(N, looks)
    assert np.allclose(cp.apodization_correlation(w), np.eye(looks))
    comp = cp.compound(cp.frequency_looks(img, w), "intensity").values
    c, se = _blocked(_contrast, comp)
    theory = cp.split_spectrum_contrast(w * src.values, 64.0)
    assert abs(c - theory) < 3 * se, (c, theory, se)
    assert cp.split_spectrum_contrast(w, np.inf) == pytest.approx(1 / np.sqrt(looks))
    assert abs(c - 1 / np.sqrt(looks)) < 3 * se + (theory - 1 / np.sqrt(looks))


@pytest.mark.parametrize("window,overlap", [("hann", 0.5), ("gaussian", 0.5), ("rectangular", 0.5)])
def test_partially_correlated_subbands(dense, window, overlap):
    """C_N = sqrt(sum |mu_ij|^2)/N, mu_ij the overlap of the windows."""
    src, _, img = dense
    w = cp.subband_apodizations(N, 4, apodization=window, overlap=overlap)
    mu = cp.apodization_correlation(w)
    dense_c = cp.compounded_contrast(mu)
    # the formula assumes equal look means E_i; with unequal ones (the Gaussian tails cut at
    # the band edges: 5 %) it reads sqrt(sum E_i E_j |mu_ij|^2) / sum E_i
    energy = (w**2).sum(axis=1)
    weighted = np.sqrt(np.sum(np.outer(energy, energy) * np.abs(mu) ** 2)) / energy.sum()
    assert cp.split_spectrum_contrast(w, np.inf) == pytest.approx(weighted, rel=1e-12)
    if np.ptp(energy) / energy.mean() < 1e-5:  # equal means: the formula, 2nd order
        assert weighted == pytest.approx(dense_c, rel=1e-9)
    # unequal look means (Gaussian tails cut at the band edge) are weighted exactly here
    theory = cp.split_spectrum_contrast(w * src.values, 64.0)
    comp = cp.compound(cp.frequency_looks(img, w), "intensity").values
    c, se = _blocked(_contrast, comp)
    assert abs(c - theory) < 3 * se, (c, theory, se)
    assert 0.5 < dense_c < 1.0


def test_frequency_looks_equal_imaging_with_the_subband_spectrum(dense):
    src, sc, img = dense
    w = cp.subband_apodizations(N, 4, apodization="hann", overlap=0.25)
    looks = cp.frequency_looks(img.isel(aline=slice(0, 4)), w)
    for i in range(4):
        s_i = speckle.spectrum(N, H, k0_dk=10, shape="array", weights=w[i] * src.values)
        ref = speckle.bscan(sc.isel(aline=slice(0, 4)), s_i, method="finufft", tol=1e-12).field
        err = np.abs(looks.isel(look=i).values - ref.values).max() / np.abs(ref.values).max()
        assert err < 1e-8


@pytest.mark.parametrize("looks", [1, 2, 4, 8])
def test_subband_widens_the_axial_psf_n_fold(looks):
    """Measured on the band-limited interpolation of one scatterer's compounded intensity."""
    from speckle.analysis.image_quality import bandlimited, peak_fwhm

    n = 256
    a = speckle.ascan([100.37 * 8], [1.0], n_pixels=n, depth_range=n * 8.0, k0=30.0)
    looks_f = cp.frequency_looks(xr.DataArray(a, dims=["depth"]), cp.subband_apodizations(n, looks))
    fine = bandlimited(looks_f.values, 64)
    fwhm = peak_fwhm((np.abs(fine) ** 2).sum(axis=0), 1 / 64)
    assert fwhm == pytest.approx(cp.subband_fwhm(n, n // looks), rel=1e-3)
    ratio = cp.subband_fwhm(n, n // looks) / cp.subband_fwhm(n, n)
    assert ratio == pytest.approx(looks, rel=2e-3)


def test_brownian_g1():
    """g1(tau) = exp(-q^2 D tau), q = 2 k0: the complex correlation of frames tau apart."""
    src = speckle.spectrum(N, H, k0_dk=10)
    k0 = src.attrs["k0"]
    d = 0.05  # µm^2/s
    dt = 1 / (4 * k0**2 * d) / 4  # q^2 D dt = 1/4
    sc = speckle.random_scatterers(128, 32.0, n_pixels=N, depth_range=H, seed=2, count="poisson")
    frames = cp.brownian_frames(sc, 9, diffusion=d, interval=dt, seed=5)
    img = (
        speckle.bscan(frames, src, method="finufft", tol=1e-10)
        .field.transpose("frame", "depth", "aline")
        .values
    )
    for m in (1, 2, 4, 8):

        def g(b, m=m):
            return np.real(
                np.sum(b[0] * b[1].conj())
                / np.sqrt(np.sum(np.abs(b[0]) ** 2) * np.sum(np.abs(b[1]) ** 2))
            )

        pair = np.stack([img[0], img[m]])
        est, se = _blocked(g, pair)
        theory = cp.brownian_g1(m * dt, d, k0)
        # PSF correction O((step/Lc)^2): rms step 0.2 µm against Lc = 16 µm, below 2e-4
        assert abs(est - theory) < 3 * se + 2e-4, (m, est, theory, se)


def test_polarization_looks_contrast():
    src = speckle.spectrum(N, H, k0_dk=10)
    sc = speckle.random_scatterers(256, 32.0, n_pixels=N, depth_range=H, seed=4, count="poisson")
    f = 0.3
    img = speckle.bscan(speckle.depolarize(sc, f, seed=1), src, method="finufft", tol=1e-9)
    i = img.intensity.sum("channel").transpose("depth", "aline").values
    c, se = _blocked(_contrast, i)
    p = abs(1 - 2 * f)
    dense_c = np.sqrt((1 + p**2) / 2)
    assert dense_c**2 == pytest.approx((1 - f) ** 2 + f**2)
    # Poisson, rho = 32: both channels share the scatterers, so the fourth-order (Campbell)
    # term of the total intensity is that of one full look: C^2 = (1-f)^2 + f^2 + (C1^2 - 1)
    c1 = cp.split_spectrum_contrast(np.ones((1, N)), 32.0)
    theory = np.sqrt(dense_c**2 + c1**2 - 1)
    assert abs(c - theory) < 3 * se, (c, theory, se)


def test_complex_averaging():
    """One realisation: complex averaging removes no speckle; noisy looks: SNR x L."""
    src = speckle.spectrum(N, H, k0_dk=10)
    sc = speckle.random_scatterers(64, 16.0, n_pixels=N, depth_range=H, seed=4)
    img = speckle.bscan(sc, src, method="finufft", tol=1e-10)
    f = img.field.transpose("depth", "aline")
    looks = xr.concat([f] * 8, "look")
    same = cp.compound(looks, "complex").values
    np.testing.assert_allclose(same, np.abs(f.values) ** 2, rtol=1e-12)
    snr_in = 10.0  # dB
    noisy = cp.noisy_looks(looks, snr_in, seed=3)
    avg = noisy.mean("look").values
    noise = avg - f.values
    snr_out = np.mean(np.abs(f.values) ** 2) / np.mean(np.abs(noise) ** 2)
    # mean of 8 x 8192 complex Gaussian noise powers: relative SE 1/sqrt(65536/8... ) per look
    se = snr_out / np.sqrt(f.size)
    assert abs(snr_out - 8 * 10 ** (snr_in / 10)) < 4 * se


def test_spatial_and_angular_looks_register_a_point():
    n, h, p = 64, 512.0, 8.0
    src = speckle.spectrum(n, h, k0_dk=10)
    sc = xr.Dataset(
        {
            "z": ("scatterer", [200.0]),
            "x": ("scatterer", [256.0]),
            "amplitude": ("scatterer", [1.0 + 0j]),
            "region": ("scatterer", [0]),
        }
    )
    x = speckle.scan_lines(64, p)
    looks = looks_study.angular_looks(
        sc, src, [-3.0, 0.0, 3.0], waist=16.0, lines=x, method="direct"
    )
    peaks = [np.unravel_index(np.argmax(np.abs(lk)), lk.shape) for lk in looks.values]
    assert all(pk == (25, 32) for pk in peaks), peaks
    sp = looks_study.spatial_looks(sc, src, [0.0, 8.0], waist=16.0, lines=x)
    assert np.argmax(np.abs(sp.values[1, 25])) == 31


@pytest.mark.parametrize(
    "call,name",
    [
        (lambda: cp.subband_apodizations(16, 17), "n_looks"),
        (lambda: cp.subband_apodizations(16, 4, overlap=1.5), "overlap"),
        (lambda: cp.subband_apodizations(16, 4, overlap=1.0), "overlap"),
        (lambda: cp.subband_apodizations(16, 4, apodization="kaiser"), "apodization"),
        (lambda: cp.brownian_g1(1.0, -1.0, 5.0), "diffusion"),
        (
            lambda: cp.brownian_frames(
                xr.Dataset({"z": ("scatterer", [1.0])}), 3, diffusion=-0.1, interval=0.1, seed=0
            ),
            "diffusion",
        ),
        (
            lambda: cp.brownian_frames(
                xr.Dataset({"z": ("scatterer", [1.0])}), 3, diffusion=0.1, interval=0.0, seed=0
            ),
            "interval",
        ),
        (
            lambda: cp.compound(xr.DataArray(np.ones((2, 2)), dims=["look", "depth"]), "geometric"),
            "mode",
        ),
    ],
)
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_truth_carries_the_polarization_channels():
    """Each channel's truth is its intensity fraction of the total (1 - f, f)."""
    n, h = 32, 256.0
    src = speckle.spectrum(n, h, k0_dk=10)
    sc = speckle.random_scatterers(8, 4.0, n_pixels=n, depth_range=h, seed=3)
    f = 0.3
    both = speckle_free_image(speckle.depolarize(sc, f, seed=2), src)
    total = speckle_free_image(sc, src)
    assert both.dims == ("channel", "depth", "aline")
    np.testing.assert_allclose(both.sel(channel="co"), (1 - f) * total, rtol=1e-10)
    np.testing.assert_allclose(both.sel(channel="cross"), f * total, rtol=1e-10)
    with pytest.raises(ValueError, match="waist"):
        speckle_free_image(sc, src, waist=10.0, lines=[0.0])
