"""Truncated-PSF method against the direct sum, and its error model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

# private: the PSF method's internals (imaging/_methods)
from speckle.imaging._methods.psf import half_width, psf_ascan, psf_error_estimate, tail_error
from speckle.imaging.aline import ascan


def gaussian(n, fraction):
    idx = np.arange(n) - n // 2
    return np.exp(-4 * np.log(2) * (idx / (fraction * n)) ** 2)


def rel_err(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref)


@settings(max_examples=25, deadline=None)
@example(seed=362880, n=4, m=114, fraction=0.1, tol=1e-9)  # one dominant spectral component
@given(
    seed=st.integers(0, 2**31),
    n=st.integers(4, 200),
    m=st.integers(1, 150),
    fraction=st.sampled_from([0.1, 0.15, 0.25]),
    tol=st.sampled_from([1e-2, 1e-4, 1e-6, 1e-9]),
)
def test_within_tol_on_smooth_spectra(seed, n, m, fraction, tol):
    rng = np.random.default_rng(seed)
    h = 8.0 * n
    z = rng.uniform(-h, 2 * h, (2, m))
    a = rng.normal(size=(2, m)) + 1j * rng.normal(size=(2, m))
    s = gaussian(n, fraction)
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=3.7, spectrum=s)
    out = ascan(z, a, n_pixels=n, depth_range=h, k0=3.7, spectrum=s, method="psf", tol=tol)
    assert rel_err(out, ref) <= tol


def test_full_width_is_exact_on_any_spectrum():
    """hw >= N//2 covers every pixel once: only the interpolation error remains."""
    rng = np.random.default_rng(0)
    for n in (16, 17):
        h = 8.0 * n
        z, a = rng.uniform(0, h, (3, 40)), rng.normal(size=(3, 40)) + 0j
        ref = ascan(z, a, n_pixels=n, depth_range=h, k0=1.0)
        out = psf_ascan(z, a, n, h, 1.0, np.ones(n), hw=n, rows=4096)
        assert rel_err(out, ref) < 1e-6


def test_rectangular_spectrum_tail_is_dirichlet():
    """|K(y)| = |sin(pi y)/sin(pi y/N)| ~ N/(pi |d|): tail energy beyond hw ~ 1/(pi^2 hw) of the
    total (the mean of sin^2 over offsets is 1/2, and sum_{|d|>hw} 1/d^2 ~ 2/hw), so the
    truncation error is ~1/(pi sqrt(hw)) whatever N >> hw: no useful half-width meets a tight
    tol."""
    n = 1024
    for hw in (4, 16, 64):
        assert tail_error(np.ones(n), hw) == pytest.approx(1 / (np.pi * np.sqrt(hw)), rel=0.15)
    assert half_width(np.ones(n), 1e-3) == n // 2  # needs the whole A-line


def test_truncated_rectangular_error_matches_estimate():
    """Measured error of a too-narrow PSF on a rectangular spectrum equals the tail estimate.

    Random scene of B*M = 4*256 scatterers: the relative error is an average over scatterers
    (relative spread ~1/sqrt(1024) ~ 3 %); allow 20 %."""
    rng = np.random.default_rng(1)
    n, h = 128, 1024.0
    z, a = rng.uniform(0, h, (4, 256)), np.exp(2j * np.pi * rng.uniform(size=(4, 256)))
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=2.0)
    out = psf_ascan(z, a, n, h, 2.0, np.ones(n), hw=4, rows=4096)
    assert rel_err(out, ref) == pytest.approx(tail_error(np.ones(n), 4), rel=0.2)
    assert rel_err(out, ref) > 0.1  # the failure is real


def test_refuses_unreachable_tol():
    with pytest.raises(ValueError, match=r"psf.*cannot reach"):
        ascan([[1.0]], [[1.0]], n_pixels=64, depth_range=512.0, k0=1.0, method="psf", tol=1e-11)


def test_estimate_components():
    err, hw, rows = psf_error_estimate(gaussian(256, 0.15), 1e-6)
    assert err <= 1e-6 and 0 < hw < 40 and rows >= 8
    # narrower spectrum -> wider PSF in pixels -> larger half-width
    assert half_width(gaussian(256, 0.1), 1e-6) > half_width(gaussian(256, 0.2), 1e-6)
