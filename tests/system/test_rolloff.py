"""Sensitivity roll-off: the sinc^2 x Gaussian curve is what finite spectrometer pixels give."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.system._rolloff import rolloff_amplitude, rolloff_curve  # private: closed forms

N, H = 64, 256.0


def _point_scene(z):
    z = np.atleast_1d(np.asarray(z, dtype=float))
    return xr.Dataset(
        {
            "z": (("aline", "scatterer"), z[:, None]),
            "amplitude": (("aline", "scatterer"), np.ones((z.size, 1), dtype=complex)),
        },
        attrs={"depth_range": H, "n_pixels": N},
    )


def test_minus_3_9_db_at_the_nyquist_depth():
    assert rolloff_curve(H / 2, H / 2) == pytest.approx((2 / np.pi) ** 2, rel=1e-14)
    assert rolloff_curve(0.0, H / 2) == 1.0
    assert rolloff_curve(H, H / 2) == pytest.approx(0.0, abs=1e-30)


def test_box_pixels_give_the_sinc():
    """Eq. 4 with every spectral pixel integrated over its width pi/H equals the rolled-off scene.

    Reference: M sub-wavenumbers per pixel, whose average of exp(2ikz) is
    sin(z d)/(M sin(z d/M)) -> sin(z d)/(z d); relative deviation <= (z d)^2/(6 M^2) < 2e-6.
    """
    src = speckle.spectrum(N, H, k0_dk=5, shape="gaussian", fwhm_fraction=0.6)
    z = np.array([3.3, 40.0, 127.9, 200.5, 250.0])
    img = speckle.bscan(speckle.rolloff(_point_scene(z)), src).field.values  # (depth, aline)
    m = 1000
    d = np.pi / H
    sub = (np.arange(m) + 0.5) / m - 0.5  # offsets within a pixel, in units of d
    k = src.wavenumber.values[:, None] + sub[None, :] * d  # (n, m)
    n_idx = src.n.values
    q = np.arange(N)
    for i, zi in enumerate(z):
        fringe = np.exp(2j * k * zi).mean(axis=1)  # pixel-averaged spectral component
        ref = (src.values * fringe) @ np.exp(-2j * np.pi * np.outer(n_idx, q) / N)
        np.testing.assert_allclose(img[:, i], ref, rtol=0, atol=2e-6 * np.abs(ref).max())


def test_gaussian_spectral_resolution_factor():
    """A Gaussian blur of FWHM w*d applied to exp(2ikz) multiplies it by the Gaussian factor."""
    d, w = np.pi / H, 1.5
    sigma = w * d / (2 * np.sqrt(2 * np.log(2)))
    kappa = np.linspace(-8 * sigma, 8 * sigma, 20001)
    g = np.exp(-(kappa**2) / (2 * sigma**2))
    for z in (10.0, 80.0, 128.0):
        blur = np.sum(g * np.exp(2j * kappa * z)) / g.sum()
        expected = rolloff_amplitude(z, H / 2, w) / np.sinc(z * d / np.pi)
        assert blur.real == pytest.approx(expected, rel=1e-9)


def test_user_curve_and_errors():
    scene = _point_scene([0.0, 50.0, 100.0])
    out = speckle.rolloff(scene, curve=([0.0, 100.0], [1.0, 0.25]))
    np.testing.assert_allclose(abs(out.amplitude).values.ravel(), np.sqrt([1.0, 0.625, 0.25]))
    with pytest.raises(ValueError, match="z_max"):
        speckle.rolloff(scene, z_max=-1.0)
    with pytest.raises(ValueError, match="resolution"):
        speckle.rolloff(scene, resolution=float("inf"))
    with pytest.raises(ValueError, match="increasing"):
        speckle.rolloff(scene, curve=([0.0, 0.0], [1.0, 1.0]))
    with pytest.raises(ValueError, match="not both"):
        speckle.rolloff(scene, z_max=10.0, curve=([0.0, 1.0], [1.0, 1.0]))
