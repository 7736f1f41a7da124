"""Log-intensity moments of sparse speckle (speckle.analysis.sparse) against exact results.

Dense limit: fully developed speckle, ``E ln(I/<I>) = -gamma``, ``var ln I = pi^2/6``, with or
without noise (circular Gaussian noise keeps the field Gaussian). Noise only (density -> 0 with
a finite noise power): Gaussian again. Low density: against the per-pixel field drawn directly
(Poisson scatterers, uniform phases, the same PSF), where ``var ln I`` has the sample error
``sqrt(var(c^2) / n)`` of the centred squares ``c^2``, to 4 SE. The closed loop of the twin
(tests/analysis/test_twin.py) checks the images of ``speckle.beam_scan``.
"""

from __future__ import annotations

import numpy as np
import pytest

from speckle.analysis import (
    depth_intensity_psf,
    log_intensity_moments,
    sparse_inverse_density,
)

N = 32


def gaussian_weights(fwhm, n=N):
    idx = (np.arange(n) - n // 2) / n
    return np.exp(-4 * np.log(2) * (idx / fwhm) ** 2)


@pytest.mark.parametrize("inverse_snr", [0.0, 0.1])
def test_dense_limit_is_fully_developed(inverse_snr):
    mean, var = log_intensity_moments(gaussian_weights(0.5), 2.0, 1e5, inverse_snr=inverse_snr)
    assert mean == pytest.approx(-np.euler_gamma, abs=1e-3)
    assert var == pytest.approx(np.pi**2 / 6, abs=1e-3)


def test_noise_only_is_gaussian():
    _, var = log_intensity_moments(gaussian_weights(1.0), 1.0, 1e-3, inverse_snr=1e4)
    assert var == pytest.approx(np.pi**2 / 6, abs=1e-3)


def direct_pixels(weights, waist_pitch, rho, n, seed=0):
    """|F|^2 of n independent pixels: Poisson scatterers over one depth period x +-3 waists."""
    rng = np.random.default_rng(seed)
    box = 3 * waist_pitch  # exp(-2 * 3^2) = 2e-8 of the peak amplitude
    counts = rng.poisson(rho * N * 2 * box, n)
    m = int(counts.sum())
    z, x = rng.uniform(0, N, m), rng.uniform(-box, box, m)
    hz = np.exp(2j * np.pi * np.outer(z, np.arange(N) - N // 2) / N) @ weights
    terms = hz * np.exp(-2 * x**2 / waist_pitch**2) * np.exp(2j * np.pi * rng.uniform(size=m))
    pixel = np.repeat(np.arange(n), counts)
    field = np.bincount(pixel, terms.real, n) + 1j * np.bincount(pixel, terms.imag, n)
    return np.abs(field) ** 2


@pytest.mark.parametrize(("fwhm", "waist", "rho"), [(1.0, 1.0, 0.5), (0.25, 1.0, 0.5)])
def test_low_density_against_the_field_drawn_directly(fwhm, waist, rho):
    w = gaussian_weights(fwhm)
    intensity = direct_pixels(w, waist, rho, 8000)
    ln = np.log(intensity / intensity.mean())
    c2 = (ln - ln.mean()) ** 2
    se = np.sqrt(np.var(c2) / c2.size)
    _, var = log_intensity_moments(w, waist, rho)
    assert abs(np.var(ln) - var) < 4 * se, (np.var(ln), var, se)
    assert var > np.pi**2 / 6 + 5 * se  # the departure from fully developed is resolved


def test_inversion_round_trip_and_monotone():
    w = gaussian_weights(0.5)
    v = [log_intensity_moments(w, 2.0, rho, inverse_snr=0.01)[1] for rho in (0.25, 0.5, 1.0, 4.0)]
    assert np.all(np.diff(v) < 0)
    for rho, var in zip((0.25, 0.5, 1.0, 4.0), v, strict=True):
        assert sparse_inverse_density(var, w, 2.0, inverse_snr=0.01) == pytest.approx(
            1 / rho, rel=1e-4
        )
    assert sparse_inverse_density(np.pi**2 / 6, w, 2.0) == pytest.approx(0.0, abs=1e-9)
    assert sparse_inverse_density(np.pi**2 / 6 - 0.01, w, 2.0) < 0


def test_depth_psf_is_the_direct_sum():
    w = gaussian_weights(0.3)
    u = np.arange(8 * N) / 8.0
    direct = np.abs(np.exp(2j * np.pi * np.outer(u, np.arange(N) - N // 2) / N) @ w) ** 2
    np.testing.assert_allclose(depth_intensity_psf(w), direct, rtol=0, atol=1e-12 * direct.max())


def test_bad_inputs_named():
    with pytest.raises(ValueError, match="density"):
        log_intensity_moments(gaussian_weights(0.5), 2.0, -1.0)
    with pytest.raises(ValueError, match="waist_pitch"):
        log_intensity_moments(gaussian_weights(0.5), 0.0, 1.0)
    with pytest.raises(ValueError, match="log_variance"):
        sparse_inverse_density(0.0, gaussian_weights(0.5), 2.0)
