"""Autocorrelation estimator, its theory along depth and across beam-scanned lines, and fits."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import autocorrelation as ac
from speckle.imaging.beam_lines import beam_lines, shared_scatterers
from speckle.system.noise import noise_autocorrelation

N, H = 64, 256.0


def _field_correlation(field: np.ndarray, lag: int, axis: int) -> tuple[complex, float]:
    """E[A(i + lag) A*(i)] / E|A|^2 along ``axis`` and its SE.

    One estimate per independent unit (an A-line for ``axis=0``, periodic in depth; a depth row
    of a rectangular-spectrum image, whose rows are uncorrelated, for ``axis=1``); SE from
    their spread.
    """
    f = np.moveaxis(field, axis, 0)
    if axis == 0:
        g = np.roll(f, -lag, axis=0)
    else:
        f, g = f[: f.shape[0] - lag], f[lag:]
    per_unit = np.sum(g * np.conj(f), axis=0) / np.sum(abs(f) ** 2, axis=0)
    return per_unit.mean(), abs(per_unit).std(ddof=1) / np.sqrt(per_unit.size)


def test_gaussian_field_intensity_autocorrelation_is_siegert():
    """Exactly Gaussian, stationary fields (shaped noise): intensity acf = |gamma|^2, 0 across."""
    src = speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm_fraction=0.3)
    zero = speckle.bscan(
        speckle.random_scatterers(512, 0.0, n_pixels=N, depth_range=H, seed=1), src
    )
    img = speckle.add_noise(zero, 0.0, seed=3, kind="rin", spectrum=src, signal_intensity=1.0)
    est = ac.intensity_autocorrelation(img.intensity, max_lag=6)
    gamma = noise_autocorrelation(N, np.arange(7), kind="rin", spectrum=src)
    # the rin-shaped noise has spectral weights S^2: its |gamma|^2 is the theory for spectrum S
    np.testing.assert_allclose(
        ac.axial_correlation_theory(np.arange(7), src.values), abs(gamma) ** 2
    )
    for axis, theory in (("depth", abs(gamma) ** 2), ("lateral", np.r_[1.0, np.zeros(6)])):
        diff = abs(est.autocorrelation.sel(axis=axis) - theory)
        assert bool((diff <= 4 * est.autocorrelation_se.sel(axis=axis) + 1e-12).all())


def test_depth_field_correlation_matches_spectrum_theory():
    """E[A(q+m) A*(q)] = sum S^2 exp(-2i pi n m/N)/sum S^2 for any density (k0 H = 10 N pi)."""
    src = speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm_fraction=0.4)
    scene = speckle.random_scatterers(400, 2.0, n_pixels=N, depth_range=H, seed=2)
    f = speckle.bscan(scene, src, method="nufft", tol=1e-10).field.values  # (depth, aline)
    theory = np.sqrt(ac.axial_correlation_theory(np.arange(4), src.values))
    for m in range(1, 4):
        est, se = _field_correlation(f, m, axis=0)
        assert abs(abs(est) - theory[m]) < 4 * se


def test_beam_lines_field_correlation_is_gaussian_in_lag():
    """Lines m pitches apart: complex correlation exp(-(m p)^2/w0^2) (beam_scan's theory)."""
    p, w0 = 1.0, 3.0
    sc = shared_scatterers(300, p, 4.0, n_pixels=N, depth_range=H, waist=w0, seed=5)
    scene = beam_lines(sc["z"], sc["x"], sc["amplitude"], lines=sc["lines"], waist=w0)
    src = speckle.spectrum(N, H, k0_dk=10)
    f = speckle.bscan(scene.assign_attrs(depth_range=H, n_pixels=N), src, method="nufft", tol=1e-10)
    f = f.field.transpose("depth", "aline").values
    for m in range(1, 5):
        theory = float(np.sqrt(ac.lateral_correlation_theory(m, w0, p)))
        est, se = _field_correlation(f, m, axis=1)
        assert abs(abs(est) - theory) < 4 * se


def test_fits_recover_the_generating_parameters():
    lags = np.arange(9)
    idx = (np.arange(N) - N // 2) / N
    s = np.exp(-4 * np.log(2) * (idx / 0.27) ** 2)
    fwhm, rms = ac.fit_spectral_width(ac.axial_correlation_theory(lags, s, 12.0), N, 12.0)
    assert fwhm == pytest.approx(0.27, rel=1e-5) and rms < 1e-8
    waist, rms = ac.fit_waist(ac.lateral_correlation_theory(lags, 3.7, 1.0, 12.0), 12.0)
    assert waist == pytest.approx(3.7, rel=1e-5) and rms < 1e-8
    assert ac.noise_factor(0.0) == 0.25 and ac.noise_factor(None) == 1.0


def test_bad_autocorrelation_inputs():
    img = xr.DataArray(np.ones((10, 40)), dims=("depth", "aline"))
    with pytest.raises(ValueError, match="max_lag"):
        ac.intensity_autocorrelation(img, max_lag=9)
    with pytest.raises(ValueError, match="dims"):
        ac.intensity_autocorrelation(img.rename(aline="lateral"))
    big = xr.DataArray(np.random.default_rng(0).exponential(size=(40, 40)), dims=("depth", "x"))
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        old = ac.intensity_autocorrelation(big.rename(x="aline"), n_blocks=4)
    assert old.equals(ac.intensity_autocorrelation(big, n_blocks=4))
    with pytest.raises(ValueError, match="snr_db"):
        ac.noise_factor(float("nan"))
