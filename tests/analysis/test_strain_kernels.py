"""The fused numba paths of the strain estimators against plain-numpy references.

The vector method's window sums, its phase and quality, the multi-lag branch (with its
pre-test), the lag's autocorrelation, the resampling and the axial tracker are each compared
with the direct formula they replace (exact references, or the analytic displacement).
"""

import numpy as np
import pytest

import speckle
from speckle.analysis import correlation, phase, sample_field, tracking
from speckle.analysis._kernels import (  # private: the kernels' atan2 and taps, tested here
    LAGRANGE_TAPS,
    atan2_array,
)

# private: box_sums' caller, tested here
from speckle.analysis._strain_methods import _box
from speckle.scene import deformation as D

N, PIXEL, R = 256, 8.0, 10.0
H = N * PIXEL


def source(shape="gaussian"):
    if shape == "gaussian":
        return speckle.spectrum(N, H, k0_dk=R, shape="gaussian", fwhm=0.5 * N * np.pi / H)
    return speckle.spectrum(N, H, k0_dk=R)


def pair(strain, lines=16, shape="gaussian", seed=4):
    scene = D.deformable_scene(
        lines, 4.0, n_pixels=N, depth_range=H, seed=seed, strain=[0.0, strain]
    )
    b = speckle.bscan(D.uniaxial_strain(scene, [0.0, strain]), source(shape), method="nufft")
    img = b.field.transpose("strain", "depth", "x").values
    return img[0], img[1]


def vector_reference(a1, a2, k0, lag, wz, wx, min_quality=0.5, wrap=True):
    """The vector method written out: window sums of C_L = A1 A2* A1*(z+L) A2(z+L) and |C_L|
    by explicit slices, the lag-1 predictor evaluated at every window (no pre-test)."""
    n, m = a1.shape

    def sums(lag_):
        c = a1[:-lag_] * np.conj(a2[:-lag_]) * np.conj(a1[lag_:]) * a2[lag_:]
        rows = c.shape[0] - wz + 1
        out_c = np.array([c[i : i + wz].sum(axis=0) for i in range(rows)])
        out_a = np.array([np.abs(c[i : i + wz]).sum(axis=0) for i in range(rows)])
        cols = m - wx + 1
        lat = [
            np.stack([x[:, j : j + wx].sum(axis=1) for j in range(cols)], 1) for x in (out_c, out_a)
        ]
        return lat

    s, a = sums(lag)
    phase_ = np.angle(s)
    quality = np.abs(s) / a
    if wrap and lag > 1:
        s1, _ = sums(1)
        h = lag // 2
        rho1 = phase.depth_autocorrelation(a1, 1)[1]
        pred = lag * np.angle(s1[h : h + s.shape[0]]) * (1 + rho1**2)
        phase_ = phase_ + 2 * np.pi * np.round((pred - phase_) / (2 * np.pi))
    strain = np.where(quality >= min_quality, -phase_ / (2 * k0 * lag * PIXEL), np.nan)
    full_s, full_q = np.full((n, m), np.nan), np.full((n, m), np.nan)
    r0, c0 = wz // 2 + lag // 2, wx // 2
    full_s[r0 : r0 + s.shape[0], c0 : c0 + s.shape[1]] = strain
    full_q[r0 : r0 + s.shape[0], c0 : c0 + s.shape[1]] = quality
    return full_s, full_q


def test_atan2_within_two_ulp_of_numpy():
    rng = np.random.default_rng(1)
    y = rng.normal(size=200_000) * np.exp(4 * rng.normal(size=200_000))
    x = rng.normal(size=200_000)
    edges = [(0.0, 1.0), (1.0, 0.0), (-1.0, 0.0), (0.0, -1.0), (-0.0, -1.0), (0.0, 0.0)]
    edges += [(1.0, 1.0), (-1.0, -1.0), (1e-300, 1.0), (1.0, -1e-300), (3.0, -3.0)]
    y = np.concatenate([y, [e[0] for e in edges]])
    x = np.concatenate([x, [e[1] for e in edges]])
    out = np.empty_like(y)
    atan2_array(y, x, out)
    exact = np.arctan2(y, x)
    assert np.all(np.abs(out - exact) <= 2 * np.spacing(np.abs(exact)) + 1e-300)
    assert np.array_equal(np.signbit(out), np.signbit(exact))


@pytest.mark.parametrize("strain, wrap", [(2e-3, True), (2e-3, False), (2.2e-2, True)])
@pytest.mark.parametrize("layout", ["F", "C"])
def test_vector_kernel_equals_the_written_out_method(strain, wrap, layout):
    """Bit-level agreement (1e-12) with the direct formula, also where the lag-3 phase wraps
    (2.2 %: beyond 1/(2 R L) = 1.7 %, the multi-lag branch is needed) and for C-ordered
    images."""
    a1, a2 = pair(strain)
    a1, a2 = (np.asarray(x, order=layout) for x in (a1, a2))
    k0 = float(source().attrs["k0"])
    got, q = speckle.estimate_strain(
        a1, a2, k0=k0, pixel_size=PIXEL, align=False, wrap_check=wrap, return_quality=True
    )
    want, wq = vector_reference(a1, a2, k0, phase.choose_lag(a1), 32, 4, wrap=wrap)
    assert np.array_equal(np.isnan(got), np.isnan(want))
    assert np.array_equal(np.isnan(q), np.isnan(wq))
    ok = np.isfinite(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(q[np.isfinite(wq)], wq[np.isfinite(wq)], rtol=1e-12)
    if strain > 1 / (2 * R * 3):
        assert np.nanmedian(got) == pytest.approx(strain, rel=0.05)  # unwrapped


@pytest.mark.parametrize("layout", ["F", "C"])
def test_lag_autocorrelation_equals_its_definition(layout):
    a1, _ = pair(1e-3)
    a = np.asarray(a1, order=layout)
    lag, rho = phase.lag_and_rho(a)
    for k in range(lag + 1):
        x, y = a[: a.shape[0] - k], a[k:]
        exact = np.abs(np.sum(x * np.conj(y))) / np.sqrt(
            np.sum(np.abs(x) ** 2) * np.sum(np.abs(y) ** 2)
        )
        assert rho[k] == pytest.approx(exact, rel=1e-12)
    assert lag == phase.choose_lag(a) == 3
    np.testing.assert_allclose(phase.depth_autocorrelation(a, lag), rho, rtol=1e-12)


def lagrange_error(omega: np.ndarray, taps: int) -> np.ndarray:
    """Largest error over the interval of ``taps``-point Lagrange interpolation (nodes
    ``-(taps//2 - 1) ... taps//2``, as the kernel) of ``exp(i omega s)``, per ``omega``
    (radians per sample): ``max_t |exp(i omega t) - sum_k w_k(t) exp(i omega s_k)|``."""
    t = np.linspace(0.0, 1.0, 257)
    nodes = np.arange(taps) - (taps // 2 - 1)
    w = np.ones((t.size, taps))
    for k in range(taps):
        for i in range(taps):
            if i != k:
                w[:, k] *= (t - nodes[i]) / (nodes[k] - nodes[i])
    e = np.exp(1j * omega[:, None] * t[None]) - np.exp(1j * omega[:, None] * nodes[None]) @ w.T
    return np.abs(e).max(axis=1)


@pytest.mark.parametrize("shape", ["gaussian", "rectangular"])
@pytest.mark.parametrize("path", ["resample_depth", "alignment"])
def test_resampling_within_its_lagrange_bound(shape, path):
    """Both resamplings against the exact interpolant, at positions that wrap around the period
    and move by up to 3 px: ``resample_depth`` (4 samples per pixel) and the alignment's (the
    tracker's half-pixel samples, which are the exact interpolant: whole pixels the data, half
    pixels to float32 rounding). The error is below the bound of each A-line's own spectrum,
    ``sum_n |F_n| max_t |e(omega_n, t)|`` with ``omega_n = 2 pi n / (F N)`` per sample (every
    frequency's worst error of the 8-point polynomial added in phase), and of its order."""
    # private: the alignment's resampling
    from speckle.analysis._strain_methods import _resampled

    a1, a2 = pair(1e-3, lines=6, shape=shape)
    q = np.arange(N, dtype=float)[:, None]
    uz = q * 0.004 + 3 * np.sin(np.arange(6))[None] - 1.5
    scale = np.abs(a2).max()
    if path == "resample_depth":
        factor, got = 4, correlation.resample_depth(a2, q + uz)
    else:
        tr = tracking.track_axial(a1, a2, window=(64, 6), step=(64, 6), keep_samples=True)
        samples = tr["deformed_samples"]
        assert samples.shape == (6, 2 * N) and samples.dtype == np.complex64
        assert np.abs(samples[:, 0::2] - a2.T).max() <= 1e-6 * scale  # float32 rounding
        half = sample_field(a2.T, np.arange(N) + 0.5)
        assert np.abs(samples[:, 1::2] - half).max() <= 1e-5 * scale
        factor, got = 2, _resampled(a2, uz, samples)
    exact = sample_field(a2.T, (q + uz).T).T
    n = np.arange(N) - N // 2  # model indices of the spectrum F_n
    spec = np.abs(np.fft.fft(a2, axis=0, norm="forward"))  # |F_n| at bin n mod N
    bound = spec[n % N].T @ lagrange_error(2 * np.pi * n / (factor * N), LAGRANGE_TAPS)
    err = np.abs(got - exact).max(axis=0)
    assert np.all(err <= bound + 1e-5 * scale)  # + float32 rounding of the samples
    assert np.all(err >= 0.05 * bound)  # the bound is of the error's order, not a loose one


def test_keep_samples_must_be_a_bool():
    a1, a2 = pair(1e-3, lines=6)
    with pytest.raises(TypeError, match="keep_samples"):
        tracking.track_axial(a1, a2, window=(64, 6), keep_samples="yes")


@pytest.mark.parametrize("shift", [0.3, -1.7])
def test_track_axial_rigid_shift_and_uniform_strain(shift):
    scene = D.deformable_scene(32, 4.0, n_pixels=N, depth_range=H, seed=9)
    ref = speckle.bscan(D.translate(scene, 0.0, wrap=True), source()).field.values
    moved = speckle.bscan(D.translate(scene, shift * PIXEL, wrap=True), source()).field.values
    out = tracking.track_axial(ref, moved, window=(64, 8), step=(32, 8))
    err = out["uz"] - shift
    assert abs(float(err.mean())) < 0.02 and float(np.sqrt((err**2).mean())) < 0.05
    # uniaxial strain: u = -s z at the window centres
    s = 0.01
    a1, a2 = pair(s, lines=32)
    tr = tracking.track_axial(a1, a2, window=(64, 8), step=(32, 8))
    exact = -s * tr["centre_depth"][:, None]
    assert float(np.sqrt(np.mean((tr["uz"] - exact) ** 2))) < 0.05


def test_track_axial_equals_track_array_where_the_lateral_peak_is_zero():
    """The same estimator restricted to lateral offset 0: where track_array (depth refined at
    the whole-pixel lateral peak) finds that peak at 0, both give the same grid point."""
    a1, a2 = pair(5e-3, lines=32)
    kw = {"window": (32, 8), "step": (16, 8)}
    axial = tracking.track_axial(a1, a2, **kw)
    full = tracking.track_array(a1, a2, lateral=False, **kw)
    at_zero = full["ux"] == 0
    assert at_zero.mean() > 0.95
    diff = np.abs(axial["uz"] - full["uz"])[at_zero]
    assert np.mean(diff < 1e-9) > 0.95 and diff.max() <= 1 / 40 + 1e-9


def test_track_axial_low_signal_nan_and_bad_input():
    a1, a2 = pair(2e-3, lines=16)
    a, b = a1.copy(), a2.copy()
    a[:64] = b[:64] = 0.0
    a[150, 5] = np.nan
    out = tracking.track_axial(a, b, window=(32, 8), step=(16, 8))
    z0 = out["centre_depth"] - 15.5
    assert np.isnan(out["uz"][z0 + 32 <= 64]).all()
    x0 = out["centre_x"] - 3.5
    holds = ((z0 <= 150) & (z0 + 32 > 150))[:, None] & ((x0 <= 5) & (x0 + 8 > 5))[None]
    assert np.isnan(out["uz"][holds]).all()
    assert np.isfinite(out["uz"][(z0 >= 64)[:, None] & ~holds]).all()
    with pytest.raises(TypeError, match="complex"):
        tracking.track_axial(a1.real, a2.real)
    with pytest.raises(ValueError, match="shape"):
        tracking.track_axial(a1, a2[:-1])
    with pytest.raises(ValueError, match="window"):
        tracking.track_axial(a1, a2, window=(512, 8))


def _box_numpy(x, wz, wx):
    """The window sums as numpy running sums (the code the kernel replaced): depth, then aline."""
    c = np.zeros((x.shape[0] + 1, x.shape[1]), dtype=x.dtype)
    np.cumsum(x, axis=0, out=c[1:])
    d = c[wz:] - c[:-wz]
    k = x.shape[1] - wx + 1
    if wx <= 3:
        out = d[:, :k].copy()
        for j in range(1, wx):
            out += d[:, j : j + k]
        return out
    r = np.cumsum(d, axis=1)
    return np.concatenate([r[:, wx - 1 : wx], r[:, wx:] - r[:, : k - 1]], axis=1)


@pytest.mark.parametrize("layout", ["C", "F"])
@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
@pytest.mark.parametrize("wz, wx", [(1, 1), (32, 1), (1, 4), (32, 4), (7, 3), (5, 9)])
def test_box_sums_bit_identical_to_numpy_running_sums(layout, dtype, wz, wx):
    """Same additions in the same order: equal bit for bit, in either memory layout; and equal
    to the direct window sum to rounding."""
    rng = np.random.default_rng(7)
    x = rng.standard_normal((97, 23))
    if dtype is np.complex128:
        x = x + 1j * rng.standard_normal((97, 23))
    x = np.asarray(x.astype(dtype), order=layout)
    got = _box(x, wz, wx)
    core = got[wz // 2 : wz // 2 + 97 - wz + 1, wx // 2 : wx // 2 + 23 - wx + 1]
    np.testing.assert_array_equal(core, _box_numpy(x, wz, wx))
    direct = np.lib.stride_tricks.sliding_window_view(x, (wz, wx)).sum(axis=(-2, -1))
    np.testing.assert_allclose(core, direct, rtol=0, atol=1e-12)
    assert np.isnan(got[: wz // 2]).all() and np.isnan(got[:, : wx // 2]).all()
    assert got.flags.f_contiguous == (layout == "F")
    # NaN input: direct sums, NaN where a window holds it
    x[40, 10] = np.nan
    nan = _box(x, wz, wx)
    assert np.isnan(nan[40 - wz // 2 + wz // 2, 10]) and np.isfinite(nan[wz // 2, wx // 2])
