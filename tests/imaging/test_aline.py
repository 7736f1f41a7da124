"""Physics of the A-scan model (the paper's Eq. 4) against exact results."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import speckle

# private: the exact reference method, called directly
from speckle.imaging._methods import direct
from speckle.imaging.aline import ascan

N, H = 32, 256.0  # 8 µm pixels
PIX = H / N


def dirichlet(theta: np.ndarray, n: int) -> np.ndarray:
    """sum_{m=-(n//2)}^{n-1-n//2} exp(i m theta), in closed form (theta not a multiple of 2 pi)."""
    centre = (n - 1) / 2 - n // 2
    return np.exp(1j * centre * theta) * np.sin(n * theta / 2) / np.sin(theta / 2)


def literal_eq4(z, a, n, h, k0, s):
    """The paper's Eq. 4 written out literally: a loop over scatterers, pixels and components."""
    idx = np.arange(n) - n // 2
    k = k0 + idx * np.pi / h
    out = np.zeros(n, complex)
    for zj, aj in zip(z, a, strict=True):
        for q in range(n):
            out[q] += np.sum(s * aj * np.exp(2j * k * zj) * np.exp(-2j * np.pi * idx * q / n))
    return out


@pytest.mark.parametrize("k0", [0.0, 0.7, 2 * np.pi])
@pytest.mark.parametrize("p", [0, 1, 5, N - 1])
def test_pixel_centred_scatterer_is_a_delta(k0, p):
    a = ascan([p * PIX], [1.0], n_pixels=N, depth_range=H, k0=k0)
    expected = np.zeros(N, complex)
    expected[p] = N * np.exp(2j * k0 * p * PIX)  # sum over N unit harmonics, carrier phase
    np.testing.assert_allclose(a, expected, atol=1e-11 * N)


@pytest.mark.parametrize("n", [31, 32])  # odd and even N: the index range differs
@pytest.mark.parametrize("offset", [1.25, 0.5, 3.9])
def test_subpixel_scatterer_gives_dirichlet_kernel(n, offset):
    k0 = 1.3
    z = offset * H / n
    a = ascan([z], [1.0], n_pixels=n, depth_range=H, k0=k0)
    q = np.arange(n)
    expected = np.exp(2j * k0 * z) * dirichlet(2 * np.pi * (offset - q) / n, n)
    np.testing.assert_allclose(a, expected, atol=1e-10 * n)


def test_figure1_single_scatterer_at_1_25_pixels_spreads_over_neighbours():
    a = np.abs(ascan([1.25 * PIX], [1.0], n_pixels=N, depth_range=H, k0=0.0))
    # |D(theta)| at distances 0.25 and 0.75 pixel: |sin(pi d)/sin(pi d/N)|
    np.testing.assert_allclose(a[1], abs(np.sin(np.pi * 0.25) / np.sin(np.pi * 0.25 / N)))
    np.testing.assert_allclose(a[2], abs(np.sin(np.pi * 0.75) / np.sin(np.pi * 0.75 / N)))
    assert a[1] > a[2] > a[3]


def test_matches_literal_transcription_with_gaussian_spectrum():
    rng = np.random.default_rng(0)
    z = rng.uniform(-H, 2 * H, 12)
    a = rng.normal(size=12) + 1j * rng.normal(size=12)
    s = speckle.spectrum(N, H, k0=4.0, shape="gaussian", fwhm=0.3 * speckle.delta_k(N, H))
    got = ascan(z, a, n_pixels=N, depth_range=H, k0=4.0, spectrum=s)
    ref = literal_eq4(z, a, N, H, 4.0, s.values)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10 * np.abs(ref).max())


@given(
    z=st.floats(-3 * H, 3 * H, allow_nan=False),
    k0=st.floats(0, 20),
    amp=st.complex_numbers(min_magnitude=0.1, max_magnitude=10),
)
def test_parseval_single_scatterer(z, k0, amp):
    """sum_q |A(q)|^2 = N * sum_n |S_n a|^2 for one scatterer anywhere (DFT Parseval)."""
    s = np.linspace(0.2, 1.0, N)
    a = ascan([z], [amp], n_pixels=N, depth_range=H, k0=k0, spectrum=s)
    np.testing.assert_allclose(np.sum(np.abs(a) ** 2), N * np.sum(s**2) * abs(amp) ** 2, rtol=1e-10)


@given(seed=st.integers(0, 2**32 - 1), k0=st.floats(0, 20))
def test_parseval_many_scatterers(seed, k0):
    """sum_q |A(q)|^2 = N * sum_n |S_n F_n|^2 with F_n = sum_j a_j exp(2i k_n z_j)."""
    rng = np.random.default_rng(seed)
    z = rng.uniform(0, H, 20)
    a = rng.normal(size=20) + 1j * rng.normal(size=20)
    s = rng.uniform(0, 1, N)
    k = k0 + (np.arange(N) - N // 2) * np.pi / H
    f = (a[:, None] * np.exp(2j * np.outer(z, k))).sum(0)
    got = ascan(z, a, n_pixels=N, depth_range=H, k0=k0, spectrum=s)
    np.testing.assert_allclose(np.sum(np.abs(got) ** 2), N * np.sum(np.abs(s * f) ** 2), rtol=1e-10)


@given(
    seed=st.integers(0, 2**32 - 1),
    c1=st.complex_numbers(max_magnitude=5),
    c2=st.complex_numbers(max_magnitude=5),
)
def test_linearity(seed, c1, c2):
    rng = np.random.default_rng(seed)
    z1, z2 = rng.uniform(0, H, 7), rng.uniform(0, H, 5)
    a1, a2 = rng.normal(size=7), rng.normal(size=5)
    kw = {"n_pixels": N, "depth_range": H, "k0": 3.0}
    both = ascan(np.r_[z1, z2], np.r_[c1 * a1, c2 * a2], **kw)
    parts = c1 * ascan(z1, a1, **kw) + c2 * ascan(z2, a2, **kw)
    np.testing.assert_allclose(both, parts, atol=1e-9 * (1 + np.abs(parts).max()))


@pytest.mark.parametrize("wraps", [1, -1, 3])
def test_wrap_around_beyond_depth(wraps):
    """A scatterer at z + m H lands where z does, with carrier phase exp(2i k0 m H)."""
    rng = np.random.default_rng(1)
    z, a, k0 = rng.uniform(0, H, 9), rng.normal(size=9), 0.9
    kw = {"n_pixels": N, "depth_range": H, "k0": k0}
    shifted = ascan(z + wraps * H, a, **kw)
    np.testing.assert_allclose(
        shifted, ascan(z, a * np.exp(2j * k0 * wraps * H), **kw), atol=1e-10 * N * 9
    )


def test_one_pixel_translation_rolls_the_image():
    """Shift theorem: z -> z + H/N rolls A by one pixel, each term gaining exp(2i k0 H/N)."""
    rng = np.random.default_rng(2)
    z, a, k0 = rng.uniform(0, H, 15), rng.normal(size=15), 2.2
    kw = {"n_pixels": N, "depth_range": H, "k0": k0}
    moved = ascan(z + PIX, a, **kw)
    np.testing.assert_allclose(
        moved, np.roll(ascan(z, a * np.exp(2j * k0 * PIX), **kw), 1), atol=1e-10 * N * 15
    )


def test_changing_k0_only_rephases_each_scatterer():
    rng = np.random.default_rng(3)
    z, a = rng.uniform(0, H, 10), rng.normal(size=10)
    kw = {"n_pixels": N, "depth_range": H}
    np.testing.assert_allclose(
        ascan(z, a, k0=5.0, **kw),
        ascan(z, a * np.exp(2j * 1.5 * z), k0=3.5, **kw),
        atol=1e-9 * N * 10,
    )


def test_batch_dims_and_padding():
    rng = np.random.default_rng(4)
    z = rng.uniform(0, H, (2, 3, 6))
    a = rng.normal(size=(2, 3, 6))
    a[0, 1, 4:] = 0  # a ragged line, padded with zero amplitudes
    out = ascan(z, a, n_pixels=N, depth_range=H, k0=1.0)
    assert out.shape == (2, 3, N) and out.dtype == np.complex128
    np.testing.assert_allclose(
        out[0, 1], ascan(z[0, 1, :4], a[0, 1, :4], n_pixels=N, depth_range=H, k0=1.0), atol=1e-10
    )
    scalar_amp = ascan(z, 2.0, n_pixels=N, depth_range=H, k0=1.0)
    np.testing.assert_allclose(
        scalar_amp, ascan(z, np.full(z.shape, 2.0), n_pixels=N, depth_range=H, k0=1.0)
    )


def test_direct_result_does_not_depend_on_chunking(monkeypatch):
    rng = np.random.default_rng(5)
    z, a = rng.uniform(0, H, (9, 40)), rng.normal(size=(9, 40))
    full = ascan(z, a, n_pixels=N, depth_range=H, k0=1.0)
    monkeypatch.setattr(direct, "DIRECT_CHUNK_ELEMENTS", 1)
    np.testing.assert_array_equal(ascan(z, a, n_pixels=N, depth_range=H, k0=1.0), full)


def test_empty_scene_gives_zeros():
    out = ascan(np.zeros((3, 0)), np.zeros((3, 0)), n_pixels=N, depth_range=H, k0=1.0)
    assert out.shape == (3, N) and not out.any()


def test_spectrum_dataarray_is_accepted():
    s = speckle.spectrum(N, H, k0=1.0, shape="gaussian", fwhm=0.5)
    a1 = ascan([10.0], [1.0], n_pixels=N, depth_range=H, k0=1.0, spectrum=s)
    a2 = ascan([10.0], [1.0], n_pixels=N, depth_range=H, k0=1.0, spectrum=s.values)
    np.testing.assert_array_equal(a1, a2)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"n_pixels": 1}, ValueError, "n_pixels"),
        ({"n_pixels": 32.0}, TypeError, "n_pixels"),
        ({"n_pixels": True}, TypeError, "n_pixels"),
        ({"depth_range": 0.0}, ValueError, "depth_range"),
        ({"depth_range": np.inf}, ValueError, "depth_range"),
        ({"k0": -1.0}, ValueError, "k0"),
        ({"k0": np.nan}, ValueError, "k0"),
        ({"k0": np.inf}, ValueError, "k0"),
        ({"spectrum": np.ones(N - 1)}, ValueError, "spectrum"),
        ({"spectrum": -np.ones(N)}, ValueError, "non-negative"),
        ({"spectrum": np.r_[np.nan, np.ones(N - 1)]}, ValueError, "spectrum"),
        ({"method": "fast"}, ValueError, "method"),
        ({"tol": 0.0}, ValueError, "tol"),
        ({"tol": 2.0}, ValueError, "tol"),
        ({"z": [np.nan]}, ValueError, "z"),
        ({"z": 3.0}, ValueError, "z"),
        ({"z": [1j]}, TypeError, "z"),
        ({"amplitude": [1.0, 2.0]}, ValueError, "amplitude"),
        ({"amplitude": [np.inf]}, ValueError, "amplitude"),
    ],
)
def test_bad_input_raises_clear_error(kwargs, exc, match):
    args = {"z": [1.0], "amplitude": [1.0], "n_pixels": N, "depth_range": H, "k0": 1.0, **kwargs}
    z, a = args.pop("z"), args.pop("amplitude")
    with pytest.raises(exc, match=match):
        ascan(z, a, **args)


def test_k0_zero_is_the_formal_fourier_transform():
    """k0 = 0: A(q) = N a at the pixel and the spectral components have no carrier."""
    a = ascan([2 * PIX], [1.0], n_pixels=N, depth_range=H, k0=0.0)
    assert np.argmax(np.abs(a)) == 2 and np.isclose(a[2], N)
