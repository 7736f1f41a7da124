"""Scoring strain estimators where they may fail: method labels and error summaries.

Failure maps (``speckle.figures.elastography``) and a fitted system's predicted maps
(``speckle.studies.twin``) run each strain estimator of ``speckle.analysis.strain`` on image
pairs of known strain and summarise how far each answer is from the truth.
"""

from __future__ import annotations

import itertools

import numpy as np
import xarray as xr

from .._validate import check_int, check_real
from ..analysis.tracking import interpolate_windows
from ..conventions import depth_range_of

__all__ = [
    "mean_and_se",
    "method_options",
    "predicted_tracking_quantization",
    "predicted_vector_floor",
    "strain_scores",
]

#: Label suffix -> the ``align`` option of ``estimate_strain`` it stands for.
_ALIGN_SUFFIXES = {"_unaligned": False, "_aligned": True}


def method_options(label: str) -> tuple[str, dict]:
    """Estimator name and ``estimate_strain`` options of a method label.

    Parameters
    ----------
    label : str
        An estimator of ``speckle.analysis.strain.STRAIN_METHODS``, optionally with the suffix
        ``"_aligned"`` or ``"_unaligned"`` (``align=True`` / ``align=False``).

    Returns
    -------
    tuple of (str, dict)
        The estimator's name and the keyword options the suffix stands for.
    """
    for suffix, align in _ALIGN_SUFFIXES.items():
        if label.endswith(suffix):
            return label.removesuffix(suffix), {"align": align}
    return label, {}


def strain_scores(estimate: np.ndarray, truth: np.ndarray | float) -> tuple[float, float, float]:
    """Median error, rms error and the answered fraction of a strain map.

    Parameters
    ----------
    estimate : numpy.ndarray
        Estimated strain (dimensionless); NaN where the estimator gave no answer.
    truth : numpy.ndarray or float
        True strain, broadcastable to ``estimate``.

    Returns
    -------
    tuple of float
        Median and rms of ``estimate - truth`` over the answered pixels (NaN when none), and
        the fraction of pixels answered.
    """
    ok = np.isfinite(estimate)
    if not ok.any():
        return np.nan, np.nan, 0.0
    err = estimate[ok] - np.broadcast_to(truth, estimate.shape)[ok]
    return float(np.median(err)), float(np.sqrt(np.mean(err**2))), float(ok.mean())


def mean_and_se(values: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """Mean over independent repeats (seeds) and its standard error, ignoring NaN repeats.

    Parameters
    ----------
    values : numpy.ndarray
        Repeated measurements, the repeats along ``axis``; NaN where a repeat gave no value.
    axis : int
        The axis of the repeats.

    Returns
    -------
    tuple of numpy.ndarray
        The mean of the finite repeats (NaN when none) and its standard error
        ``std(ddof=1) / sqrt(n)`` over the ``n`` finite repeats (NaN when ``n < 2``).
    """
    v = np.asarray(values, dtype=float)
    n = np.isfinite(v).sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        total = np.where(np.isfinite(v), v, 0.0).sum(axis=axis)
        mean = np.where(n > 0, total / np.maximum(n, 1), np.nan)
        dev = np.where(np.isfinite(v), v - np.expand_dims(mean, axis), 0.0)
        var = (dev**2).sum(axis=axis) / np.maximum(n - 1, 1)
        se = np.where(n >= 2, np.sqrt(var / np.maximum(n, 1)), np.nan)
    return mean, se


#: The 24 permutations of four indices (permanent of a 4 x 4 matrix: Isserlis' theorem for
#: circular complex Gaussian variables).
_PERMS4 = np.array(list(itertools.permutations(range(4))))


def _permanent4(m: np.ndarray) -> np.ndarray:
    """Permanents of a stack of 4 x 4 matrices ``m[..., 4, 4]``."""
    rows = np.arange(4)
    return np.prod(m[..., rows, _PERMS4], axis=-1).sum(axis=-1)


def _field_covariances(weights, n_index, k0p, n_pixels, oversample):
    """Covariances of the field ``A`` and of its strain derivative ``B = dA2/ds`` (s = 0).

    A scatterer at ``x`` pixels contributes ``exp(2i k0 p x) h(q - x)`` with the periodic kernel
    ``h(y) = sum_n S_n exp(-2i pi n y/N)``; compressed by ``s`` it sits at ``x (1 - s)``, so
    ``B`` has kernel ``x (-2i k0 p h(q - x) + h'(q - x))``. Scatterers uniform over ``[0, N)``
    with independent uniform phases (the Gaussian limit) give the covariances as integrals over
    ``x`` (midpoint rule, ``oversample`` points per pixel; ``h`` on that grid by one FFT).
    Returns the ``2N x 2N`` matrix ``E[Z_i Z_j*]`` of ``Z = (A_0 .. A_{N-1}, B_0 .. B_{N-1})``.
    """
    size = n_pixels * oversample
    n_index = np.asarray(n_index, int)
    w = 2j * np.pi * n_index / n_pixels
    half = np.exp(w * 0.5 / oversample)  # midpoints x_m = (m + 1/2) / oversample
    spec = np.zeros(size, complex)
    dspec = np.zeros(size, complex)
    spec[n_index % size] = weights * half
    dspec[n_index % size] = -w * weights * half
    # h(j / oversample - 1/(2 oversample)) for j = 0 .. size-1: sum_n S_n exp(-2i pi n j/size)
    h_fine, dh_fine = np.fft.fft(spec), np.fft.fft(dspec)
    x = (np.arange(size) + 0.5) / oversample
    j = (np.arange(n_pixels)[:, None] * oversample - np.arange(size)[None, :]) % size
    h, dh = h_fine[j], dh_fine[j]
    b = x[None, :] * (-2j * k0p * h + dh)
    z = np.concatenate([h, b]) / np.sqrt(oversample)
    return z @ z.conj().T


def _pair_moments(cov, n, lag, kappa, wz):
    """Sums over the term pairs of c-rows ``z`` and ``z + d`` (|d| < wz) of ``E[T_a T_b*]``
    and ``E[T_a T_b]``, as arrays ``[z, d + wz - 1]`` (zero where a row leaves the image), and
    the mean ``E[T0 + T1 + T2]`` of every c-row."""
    rows = n - lag  # c-rows z = 0 .. n - lag - 1
    z = np.arange(rows)

    def terms(zz):
        zl = zz + lag
        return [
            (1j * kappa, (zz, zl), (zz, zl)),  # T0 = i kappa I_z I_{z+L}
            (1.0, (zz, zl), (n + zz, zl)),  # T1 = A_z B*_z A*_{z+L} A_{z+L}
            (1.0, (zz, n + zl), (zz, zl)),  # T2 = I_z A*_{z+L} B_{z+L}
        ]

    p1 = np.zeros((rows, 2 * wz - 1), complex)
    p2 = np.zeros_like(p1)
    mean = np.zeros(rows, complex)  # E[T0 + T1 + T2] per c-row: fourth moments, 2 x 2 permanents
    for ca, pa, qa in terms(z):
        m = cov[np.stack(pa, 1)[:, :, None], np.stack(qa, 1)[:, None]]
        mean += ca * (m[:, 0, 0] * m[:, 1, 1] + m[:, 0, 1] * m[:, 1, 0])
    for k, d in enumerate(range(-(wz - 1), wz)):
        za = z[(z + d >= 0) & (z + d < rows)]
        for ca, pa, qa in terms(za):
            for cb, pb, qb in terms(za + d):
                # E[T_a T_b*]: non-conjugated N_a + C_b, conjugated C_a + N_b
                m1 = cov[np.stack([*pa, *qb], 1)[:, :, None], np.stack([*qa, *pb], 1)[:, None]]
                # E[T_a T_b]: non-conjugated N_a + N_b, conjugated C_a + C_b
                m2 = cov[np.stack([*pa, *pb], 1)[:, :, None], np.stack([*qa, *qb], 1)[:, None]]
                p1[za, k] += ca * np.conj(cb) * _permanent4(m1)
                p2[za, k] += ca * cb * _permanent4(m2)
    return p1, p2, mean


def predicted_vector_floor(
    spectrum: xr.DataArray, *, lag: int, window: tuple[int, int], oversample: int = 8
) -> np.ndarray:
    """Relative rms strain error of the unaligned vector method at small strain, per depth row.

    Noise-free pair, uniform compression ``s`` by a probe at ``z = 0``, ``s -> 0``: the error is
    linear in ``s``, so ``error / s`` has a floor that does not shrink with strain. To first
    order in ``s`` the deformed field is ``A2 = A1 + s B`` (``B``: displaced envelopes and the
    phase ``-2 k0 s z`` of every scatterer, see :func:`_field_covariances`), and the estimate
    ``-arg(sum C) / (2 k0 L p)`` over a window has ``error / s = -V / (2 k0 L p sum I_z I_{z+L})``
    with ``V = Im sum (dC/ds + 2i k0 L p I_z I_{z+L})``. Its mean square follows from the
    Gaussian moment theorem (fourth and eighth moments as permanents of covariances), with the
    window sum in the denominator replaced by its mean (relative error O(1/N_eff)) and the
    A-lines independent.

    Parameters
    ----------
    spectrum : xarray.DataArray
        Source spectrum of :func:`speckle.spectrum` (weights, coordinate ``n``, attrs
        ``n_pixels``, ``depth`` in µm and ``k0`` in rad/µm).
    lag : int
        The vector method's lag ``L`` in pixels, in [1, n_pixels // 4].
    window : tuple of int
        Estimator window (depth, aline) in pixels, depth in [2, n_pixels // 2], aline >= 1.
    oversample : int
        Integration points per pixel over the scatterer depth, in [2, 64].

    Returns
    -------
    numpy.ndarray
        Predicted ``sqrt(E[(estimate - s)^2]) / s`` at each depth row (``n_pixels``; NaN where
        the vector method gives no estimate: within half a window of the edges).

    Raises
    ------
    TypeError, ValueError
        If ``spectrum`` is not a labelled spectrum or an argument is out of range.
    """
    if not isinstance(spectrum, xr.DataArray) or "n" not in spectrum.coords:
        raise TypeError("spectrum must be a DataArray of speckle.spectrum (coordinate 'n')")
    n = check_int(spectrum.attrs.get("n_pixels", spectrum.size), "spectrum n_pixels", low=8)
    p = check_real(
        depth_range_of(spectrum, "spectrum") / n, "pixel size", low=0, low_inclusive=False
    )
    k0 = check_real(float(spectrum.attrs["k0"]), "k0", low=0, low_inclusive=False)
    lag = check_int(lag, "lag", low=1, high=n // 4)
    if not isinstance(window, (tuple, list)) or len(window) != 2:
        raise TypeError(f"window must be (depth, aline) pixels; got {window!r}")
    wz = check_int(window[0], "window[0] (depth)", low=2, high=n // 2)
    wx = check_int(window[1], "window[1] (aline)", low=1)
    oversample = check_int(oversample, "oversample", low=2, high=64)
    cov = _field_covariances(
        np.asarray(spectrum.values, complex), spectrum["n"].values, k0 * p, n, oversample
    )
    kappa = 2 * k0 * p * lag
    p1, p2, mean = _pair_moments(cov, n, lag, kappa, wz)
    z = np.arange(n - lag)
    d_rows = cov[z, z].real * cov[z + lag, z + lag].real + np.abs(cov[z, z + lag]) ** 2
    offsets = np.arange(-(wz - 1), wz)
    out = np.full(n, np.nan)
    for r in range(n):
        i0 = r - wz // 2 - lag // 2
        if i0 < 0 or i0 + wz - 1 + lag > n - 1:
            continue
        rows = np.arange(i0, i0 + wz)
        inside = (rows[:, None] + offsets[None, :] >= i0) & (
            rows[:, None] + offsets[None, :] < i0 + wz
        )
        uu = np.sum(p1[rows] * inside)
        u2 = np.sum(p2[rows] * inside)
        v2 = 0.5 * (uu.real - u2.real)  # E[(Im U)^2], U = sum_z (T0 + T1 + T2), one A-line
        m = np.sum(mean[rows]).imag  # E[Im U]: the same on every A-line (a bias)
        # the window's wx independent A-lines: variance / wx, the bias squared whole
        ms = max(v2 - m * m, 0.0) / wx + m * m
        out[r] = np.sqrt(ms) / (kappa * d_rows[rows].sum())
    return out


def predicted_tracking_quantization(
    strain: float,
    n_pixels: int,
    *,
    track_window: int = 32,
    step: int = 8,
    window: int = 64,
    grid: float = 1 / 40,
) -> float:
    """Relative rms strain error of the tracking method from its registration grid alone.

    The tracker (:func:`speckle.analysis.tracking.track_array`) reads each window's
    displacement on a grid of ``grid`` pixels (``1/(upsample * oversample)``, 1/40 by
    default). This model takes the exact displacement ``s z`` of a uniform compression at the
    window centres, rounds it to that grid, interpolates it to every pixel as the estimator does
    (:func:`speckle.analysis.tracking.interpolate_windows`) and fits the unit-weight
    least-squares slope over ``window`` pixels. Where ``s * n_pixels < grid / 2`` every window
    reads 0 and the result is exactly 1. The speckle's own registration jitter is not in it,
    so it is a lower bound of the measured error.

    Parameters
    ----------
    strain : float
        Uniform compression ``s`` (dimensionless, > 0).
    n_pixels : int
        Image depth in pixels (>= ``track_window + window``).
    track_window, step : int
        Depth size and step of the tracking windows (pixels).
    window : int
        Depth size of the strain slope fit (pixels, >= 2).
    grid : float
        Registration grid (pixels, > 0).

    Returns
    -------
    float
        rms of (estimate - s) / s over the depths where the slope fit is inside the image.
    """
    s = check_real(strain, "strain", low=0.0, low_inclusive=False)
    wz = check_int(window, "window", low=2)
    tw = check_int(track_window, "track_window", low=1)
    st = check_int(step, "step", low=1)
    n = check_int(n_pixels, "n_pixels", low=tw + wz)
    g = check_real(grid, "grid", low=0.0, low_inclusive=False)
    centres = np.arange(0, n - tw + 1, st) + 0.5 * (tw - 1)
    u = np.round(s * centres / g) * g
    q = np.arange(n, dtype=float)
    line = interpolate_windows(u[:, None], centres, np.zeros(1), q, np.zeros(1), outside="nan")
    y = np.lib.stride_tricks.sliding_window_view(line[:, 0], wz)
    k = np.arange(wz) - 0.5 * (wz - 1)
    slope = (y @ k) / np.sum(k**2)
    slope = slope[np.isfinite(slope)]
    return float(np.sqrt(np.mean((slope - s) ** 2)) / s)
