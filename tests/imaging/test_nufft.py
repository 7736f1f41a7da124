"""NUFFT methods ("nufft", "nufft32", "finufft") against the exact direct sum.

Relative error throughout: ||A - A_direct||_2 / ||A_direct||_2 over all lines and pixels.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

# private: the NUFFT method's internals (imaging/_methods)
from speckle.imaging._methods.nufft import (
    NUFFT_TOL_FLOOR,
    es_kernel,
    float32_error_estimate,
    kernel_width,
    nufft_ascan,
)
from speckle.imaging.aline import ascan


def rel_err(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref)


def spectrum_of(shape, n, rng):
    idx = np.arange(n) - n // 2
    if shape == "rectangular":
        return np.ones(n)
    if shape == "gaussian":
        return np.exp(-4 * np.log(2) * (idx / (0.3 * n)) ** 2)
    return rng.uniform(0.0, 1.0, n)  # arbitrary non-negative array


def random_scene(seed, n, m, lines, k0_dk):
    """Random depths over [-H, 3H) (wrap-around both ways), complex Gaussian amplitudes."""
    rng = np.random.default_rng(seed)
    h = 8.0 * n
    z = rng.uniform(-h, 3 * h, (lines, m))
    a = rng.normal(size=(lines, m)) + 1j * rng.normal(size=(lines, m))
    return z, a, h, k0_dk * n * np.pi / h, rng


scenes = dict(
    seed=st.integers(0, 2**31),
    n=st.integers(4, 300),
    m=st.integers(1, 200),
    lines=st.integers(1, 3),
    k0_dk=st.sampled_from([0.0, 1.0, 10.0, 137.3]),
    shape=st.sampled_from(["rectangular", "gaussian", "array"]),
)


@settings(max_examples=60, deadline=None)
@given(
    tol=st.sampled_from([1e-2, 1e-4, 1e-6, 1e-9, 1e-12]),
    method=st.sampled_from(["nufft", "finufft"]),
    **scenes,
)
# found by hypothesis: FINUFFT's width rule ceil(log10(1/tol)) + 1 gave 1.07 tol here
@example(tol=1e-2, method="nufft", seed=128, n=4, m=128, lines=1, k0_dk=1.0, shape="gaussian")
def test_double_precision_within_tol(seed, n, m, lines, k0_dk, shape, tol, method):
    z, a, h, k0, rng = random_scene(seed, n, m, lines, k0_dk)
    s = spectrum_of(shape, n, rng)
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s)
    out = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s, method=method, tol=tol)
    assert out.shape == ref.shape and out.dtype == np.complex128
    assert rel_err(out, ref) <= tol


@settings(max_examples=30, deadline=None)
@given(tol=st.sampled_from([1e-2, 1e-4, 3e-6]), **scenes)
def test_single_precision_within_tol(seed, n, m, lines, k0_dk, shape, tol):
    z, a, h, k0, rng = random_scene(seed, n, m, lines, k0_dk)
    s = spectrum_of(shape, n, rng)
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s)
    out = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s, method="nufft32", tol=tol)
    assert rel_err(out, ref) <= tol


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-9])
def test_single_scatterer_worst_offset(tol):
    """Hardest case: one scatterer, rectangular spectrum (largest deconvolution at band edge)."""
    n, h = 64, 512.0
    z = np.linspace(0, 2 * h / n, 257)[:, None]
    a = np.ones_like(z)
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=3.0)
    out = ascan(z, a, n_pixels=n, depth_range=h, k0=3.0, method="nufft", tol=tol)
    per_line = np.linalg.norm(out - ref, axis=1) / np.linalg.norm(ref, axis=1)
    assert per_line.max() <= tol


def test_pixel_centre_is_delta_within_tol():
    """A scatterer at a pixel centre images to N in that pixel (exact), up to tol."""
    n, h = 32, 256.0
    out = ascan([[5 * h / n]], [[1.0]], n_pixels=n, depth_range=h, k0=0.0, method="nufft", tol=1e-8)
    expected = np.zeros(n)
    expected[5] = n
    assert np.linalg.norm(out[0] - expected) <= 1e-8 * n


def test_chunking_and_padding_do_not_change_result():
    z, a, h, k0, _ = random_scene(3, 64, 100, 9, 10.0)
    s = np.ones(64)
    whole = nufft_ascan(z, a, 64, h, k0, s, tol=1e-8)
    chunked = nufft_ascan(z, a, 64, h, k0, s, tol=1e-8, chunk_elements=300)
    np.testing.assert_allclose(chunked, whole, rtol=0, atol=1e-12 * np.abs(whole).max())
    zp = np.concatenate([z, np.full((9, 7), 17.0)], axis=1)
    ap = np.concatenate([a, np.zeros((9, 7))], axis=1)  # zero-amplitude padding (ragged lines)
    np.testing.assert_allclose(
        nufft_ascan(zp, ap, 64, h, k0, s, tol=1e-8), whole, atol=1e-12 * np.abs(whole).max()
    )


def test_kernel_width_rule():
    # ceil(log10(2/tol)) + 1: FINUFFT's rule at tol/2
    assert [kernel_width(t) for t in (3e-2, 1e-2, 1e-6, 1e-7, 1e-12)] == [3, 4, 8, 9, 14]
    assert kernel_width(1e-30) == 16
    # ES kernel: 1 at the centre, exp(-beta) at the edge, zero outside
    assert es_kernel(0.0, 7) == 1.0
    assert np.isclose(es_kernel(3.5, 7), np.exp(-2.30 * 7))
    assert es_kernel(3.6, 7) == 0.0


def test_nufft32_refuses_tol_below_its_rounding_floor():
    floor = float32_error_estimate(64, 32, kernel_width(1e-7))
    assert 1e-8 < floor < 1e-5
    with pytest.raises(ValueError, match=r"nufft32.*float32"):
        ascan(
            np.ones((1, 64)),
            np.ones((1, 64)),
            n_pixels=32,
            depth_range=256.0,
            k0=1.0,
            method="nufft32",
            tol=1e-8,
        )


@pytest.mark.parametrize("method", ["nufft", "finufft"])
def test_nufft_refuses_tol_below_floor(method):
    with pytest.raises(ValueError, match="direct"):
        ascan(
            [1.0],
            [1.0],
            n_pixels=8,
            depth_range=64.0,
            k0=1.0,
            method=method,
            tol=NUFFT_TOL_FLOOR / 10,
        )


def test_loose_tol_error_grows_as_predicted():
    """At loose tol the error is large -- and of the size the rule predicts (auto uses tol/2)."""
    z, a, h, k0, _ = random_scene(5, 128, 512, 4, 10.0)
    ref = ascan(z, a, n_pixels=128, depth_range=h, k0=k0)
    for tol in (1e-1, 1e-2, 1e-3):
        err = rel_err(ascan(z, a, n_pixels=128, depth_range=h, k0=k0, method="nufft", tol=tol), ref)
        assert 0.05 * tol < err <= tol  # not vacuous: the error really is of order tol
