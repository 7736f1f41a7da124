"""Receiver noise: SNR as defined, spectral shaping, phase noise of two looks vs theory."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import speckle
from speckle.system.noise import noise_autocorrelation, phase_difference_coherence

N, H = 128, 512.0


@pytest.fixture(scope="module")
def image():
    src = speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm_fraction=0.5)
    scene = speckle.random_scatterers(128, 4.0, n_pixels=N, depth_range=H, seed=5)
    return speckle.bscan(scene, src, normalise="expected", method="nufft", tol=1e-10), src


def test_measured_snr_is_the_requested_snr(image):
    img, _ = image
    out = speckle.add_noise(img, 10.0, seed=1)
    ratio = float((abs(out.noise) ** 2).mean() / img.intensity.mean())
    # noise intensity is exponential and independent between pixels: SE = mean/sqrt(count)
    assert ratio == pytest.approx(0.1, abs=4 * 0.1 / np.sqrt(out.noise.size))
    assert out.attrs["noise_intensity"] == pytest.approx(0.1 * float(img.intensity.mean()))
    np.testing.assert_allclose(out.field, img.field + out.noise)
    np.testing.assert_allclose(out.intensity, abs(out.field) ** 2)


@pytest.mark.parametrize("kind", ["white", "shot", "rin"])
def test_shaped_noise_autocorrelation(image, kind):
    img, src = image
    noise = speckle.add_noise(img, 0.0, seed=2, kind=kind, spectrum=src).noise.values
    sigma2 = float(img.intensity.mean())
    lags = np.arange(4)
    theory = noise_autocorrelation(N, lags, kind=kind, spectrum=src)
    count = noise.shape[1] * N  # the noise is periodic in depth: all N pairs per lag
    for m, t in zip(lags, theory, strict=True):
        est = np.mean(np.roll(noise, -m, axis=0) * np.conj(noise)) / sigma2
        assert abs(est - t) < 4 / np.sqrt(count)  # SE of a product of unit Gaussians


def test_phase_difference_of_two_looks_conditioned_on_pixel_snr(image):
    """E cos(phi1 - phi2) given r = |A|^2/sigma^2 equals the Rician-phase prediction; var ~ 1/r."""
    img, _ = image
    a, b = (speckle.add_noise(img, 10.0, seed=s) for s in (11, 12))
    dphi = np.angle((a.field * np.conj(b.field)).values).ravel()
    r = (img.intensity.values / a.attrs["noise_intensity"]).ravel()
    edges = np.array([0.0, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0])
    for lo, hi in itertools.pairwise(edges):
        sel = (r >= lo) & (r < hi)
        c = np.cos(dphi[sel])
        se = c.std(ddof=1) / np.sqrt(sel.sum())
        assert abs(c.mean() - phase_difference_coherence(r[sel]).mean()) < 4 * se
    high = r > 60.0  # var(phi1 - phi2) = 1/r (1 + O(1/r))
    x = dphi[high] ** 2 * r[high]
    assert x.mean() == pytest.approx(1.0, abs=4 * x.std() / np.sqrt(high.sum()) + 3 / 60.0)


def test_noise_of_a_line_does_not_depend_on_the_lines_imaged(image):
    img, _ = image
    full = speckle.add_noise(img, 5.0, seed=3, signal_intensity=1.0)
    part = speckle.add_noise(img.isel(x=slice(0, 10)), 5.0, seed=3, signal_intensity=1.0)
    np.testing.assert_array_equal(full.noise.isel(x=slice(0, 10)), part.noise)
    assert not np.allclose(full.noise, speckle.add_noise(img, 5.0, seed=4).noise)


def test_rician_phase_coherence_limits():
    assert phase_difference_coherence(0.0) == 0.0
    r = 1e4  # each look's phase has variance 1/(2r): E cos(dphi) = exp(-1/(2r)) (1 + O(r^-2))
    assert phase_difference_coherence(r) == pytest.approx(np.exp(-0.5 / r), rel=1e-6)


def test_bad_noise_inputs(image):
    img, _ = image
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match="snr_db"):
            speckle.add_noise(img, bad, seed=1)
    with pytest.raises(ValueError, match="spectrum"):
        speckle.add_noise(img, 10.0, seed=1, kind="shot")
    with pytest.raises(ValueError, match="kind"):
        speckle.add_noise(img, 10.0, seed=1, kind="pink")
    with pytest.raises(TypeError, match="image"):
        speckle.add_noise(img.field, 10.0, seed=1)
