"""Closed forms and fast theory of the correlation versus strain.

The exact theory is :func:`speckle.expected_correlation` (:mod:`speckle.analysis.correlation`);
these closed forms explain its shape (the paper's Fig. 6): ``continuum_gamma`` is the
rectangular spectrum's triangle, ``two_peak_weights`` a source whose correlation revives, and
``carrier_window_factor`` the minima and revivals a window of uncompensated carrier phase adds;
``expected_gamma`` is the exact-compensation ``|gamma|`` by one NUFFT and
``amplitude_from_gamma`` the amplitude correlation of Gaussian speckle it implies.
"""

from __future__ import annotations

import finufft
import numpy as np
import scipy.fft as sfft
import xarray as xr
from scipy import special

from .._validate import check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..system.source import spectral_index

__all__ = [
    "GAMMA_EPS",
    "amplitude_from_gamma",
    "carrier_window_factor",
    "continuum_gamma",
    "expected_gamma",
    "two_peak_weights",
]

_STRAIN = ArraySpec(kind="real")
_SPECTRUM = ArraySpec(kind="real", dims=("wavenumber",), labelled=True, keep_labels=True)


def _k0_dk(spectrum: xr.DataArray) -> float:
    """``R = k0/delta_k`` of a source spectrum (ValueError naming ``spectrum`` without it)."""
    if "k0_dk" not in spectrum.attrs:
        raise ValueError(
            "spectrum needs attribute k0_dk (a spectrum from speckle.spectrum); it has "
            f"{sorted(spectrum.attrs)}"
        )
    return float(spectrum.attrs["k0_dk"])


@preprocess_and_wrap(checks={"strain": ArraySpec(kind="real")})
def continuum_gamma(strain: object, k0_dk: float) -> np.ndarray:
    """Continuum-limit ``|gamma|`` after exact compensation, rectangular spectrum.

    ``max(0, 1 - s/2 - R s)/sqrt(1 - s)`` for ``R >= 1/2`` (overlap of the spectrum with its
    copy shifted by ``R s`` and scaled by ``1 - s``).
    """
    s = np.asarray(strain, float)
    r = check_real(k0_dk, "k0_dk", low=0.5)
    return np.maximum(0.0, 1 - s / 2 - r * s) / np.sqrt(1 - s)


def two_peak_weights(n_pixels: int, *, separation: float, fwhm: float) -> np.ndarray:
    """Two equal Gaussian peaks at ``k0 -/+ separation/2`` (a two-SLD source), as weights.

    Parameters
    ----------
    n_pixels : int
        Number of spectral components ``N``.
    separation, fwhm : float
        Peak separation and each peak's FWHM as fractions of ``delta_k`` (> 0).

    Returns
    -------
    numpy.ndarray
        ``N`` weights for ``speckle.system.source.spectrum(..., shape="array", weights=...)``. Its
        autocorrelation has a side peak at lag ``separation``: after exact compensation the
        correlation revives near ``k0_dk * strain = separation``.
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    sep = check_real(separation, "separation", low=0, low_inclusive=False)
    width = check_real(fwhm, "fwhm", low=0, low_inclusive=False)
    nu = spectral_index(n) / n  # offset from k0 in units of delta_k
    peak = lambda c: np.exp(-4 * np.log(2) * ((nu - c) / width) ** 2)  # noqa: E731
    return peak(-sep / 2) + peak(sep / 2)


@preprocess_and_wrap(checks={"strain": ArraySpec(kind="real")})
def carrier_window_factor(strain: object, k0_dk: float, window: int) -> np.ndarray:
    """``|sum_{q<W} exp(2i pi R s q)|/W``: a W-pixel window of uncompensated carrier phase.

    Without removing ``exp(2i k0 u_z)`` the compensated field's phase turns by ``2 pi R s`` per
    pixel of depth, so a complex correlation over ``W`` pixels of depth is multiplied by this
    Dirichlet factor, zero at ``R s W = 1, 2, ...``: minima and revivals set by the window.
    """
    s = np.asarray(strain, float)
    w = check_int(window, "window", low=1)
    r = check_real(k0_dk, "k0_dk", low=0)
    phase = np.pi * r * s
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.abs(np.sin(w * phase) / (w * np.sin(phase)))
    return np.where(np.abs(np.sin(phase)) < 1e-12, 1.0, f)


@preprocess_and_wrap(checks={"gamma": ArraySpec()})
def amplitude_from_gamma(gamma: object) -> np.ndarray:
    """Amplitude correlation of Gaussian speckle whose fields correlate by ``|gamma|``.

    ``(pi/4) (2F1(-1/2, -1/2; 1; |gamma|^2) - 1) / (1 - pi/4)``: 0 at ``gamma = 0``, 1 at 1.
    ``|gamma| <= 1`` (Cauchy-Schwarz): a computed value above 1 by rounding counts as 1.

    Examples
    --------
    >>> import speckle
    >>> speckle.amplitude_from_gamma(np.array([0.0, 1.0])).round(6)
    array([0., 1.])
    """
    g = np.minimum(np.abs(gamma), 1.0)  # checked: numbers (|gamma| of complex), finite
    return (np.pi / 4) * (special.hyp2f1(-0.5, -0.5, 1.0, g**2) - 1) / (1 - np.pi / 4)


def _kernel_on_grid(weights: np.ndarray, x0: float, oversample: int, count: int) -> np.ndarray:
    """The point-spread kernel ``P`` at ``x0 + j/oversample``, ``j < count``, by one inverse FFT.

    ``P(x0 + j/f) = sum_n [S_n exp(2i pi n x0/N)] exp(2i pi n j/(f N))``: a length-``f N``
    inverse DFT of the spectrum (exact: the same trigonometric polynomial), periodic in ``j``.
    """
    n = weights.size
    length = oversample * n
    idx = spectral_index(n)
    coef = np.zeros(length, dtype=np.complex128)
    coef[np.mod(idx, length)] = weights * np.exp(2j * np.pi * idx * x0 / n)
    one_period = sfft.ifft(coef) * length
    return np.resize(one_period, count)


#: Relative accuracy asked of the NUFFT in :func:`expected_gamma`.
GAMMA_EPS = 1e-14


@preprocess_and_wrap(checks={"strain": _STRAIN, "spectrum": _SPECTRUM})
def expected_gamma(strain: object, *, spectrum: xr.DataArray, oversample: int = 8) -> np.ndarray:
    """``|gamma|`` after exact compensation, as ``expected_correlation(...)["complex"]``, fast.

    The same midpoint-rule integrals as :func:`expected_correlation` (``compensation="exact"``),
    reorganised: the pixel average of ``C_q = int_{-q}^{N-q} P(x) h*(x) dx`` is
    ``sum_j P(x_j) T_j h*(x_j) dx`` with ``T_j`` the fraction of pixels ``q`` whose range holds
    sample ``x_j``; with ``h*(x) = exp(2i pi R s x) sum_n S_n exp(-2i pi n (1-s) x/N)`` it is
    ``sum_n S_n V(R s - (1-s) n/N)``, ``V(f) = sum_j P(x_j) T_j exp(2i pi x_j f) dx``, the
    Fourier series of one strain-independent sequence evaluated at ``N`` frequencies per strain:
    one type-2 NUFFT (FINUFFT, relative accuracy :data:`GAMMA_EPS`) for every strain at once,
    instead of ``2 N`` kernel evaluations per strain. Independent of density and kurtosis.

    Parameters
    ----------
    strain : float or sequence of float
        Compressive uniaxial strain(s) in (-1, 1).
    spectrum : xarray.DataArray
        Source spectrum (:func:`speckle.system.source.spectrum`); its ``k0_dk`` is ``R``.
    oversample : int
        Integration points per pixel, as in :func:`expected_correlation`.

    Returns
    -------
    numpy.ndarray
        ``|gamma|`` for each strain.

    Raises
    ------
    ValueError
        A strain outside (-1, 1) or ``oversample`` below 2.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> speckle.expected_gamma([0.0, 0.01], spectrum=src).round(3)
    array([1.   , 0.892])
    """
    s = np.atleast_1d(strain).astype(float)  # checked: real, finite, not empty
    if np.any((s <= -1) | (s >= 1)):
        raise ValueError(f"strain must lie in (-1, 1), got {s.tolist()}")
    ov = check_int(oversample, "oversample", low=2)
    w = np.asarray(spectrum, float)
    r_ratio = _k0_dk(spectrum)
    n = w.size
    dx = 1.0 / ov
    count = 2 * n * ov  # x_j = -N + (j + 1/2) dx, j < count: the grid of _integrals
    x0 = -n + 0.5 * dx
    p = _kernel_on_grid(w, x0, ov, count)
    # pixels q = 0 ... N-1 whose sample range [(N - q) ov, (2N - q) ov) holds j
    j = np.arange(count)
    lo = np.maximum(n - j // ov, 0)
    hi = np.minimum(2 * n - j // ov, n)
    v = p * (np.maximum(hi - lo, 0) * (dx / n))
    # x_j = (k + 1/2) dx with k = j - count/2 (the NUFFT's centred modes), t = 2 pi dx f:
    # V(f) = exp(i pi f dx) sum_k v_k exp(i k t)
    f = ((r_ratio * s)[:, None] - (1 - s)[:, None] * spectral_index(n)[None, :] / n).ravel()
    t = 2 * np.pi * dx * f
    series = finufft.nufft1d2(t, v, isign=1, eps=GAMMA_EPS, modeord=0, nthreads=1)
    big_v = (series * np.exp(1j * np.pi * dx * f)).reshape(s.size, n)
    # an elementwise sum, not ``big_v @ w``: the BLAS call spins threads that cost twice the
    # CPU of the product here (a 2-core machine: 210 ms CPU against 86 ms for this)
    c_mean = (big_v * w).sum(axis=1)
    a = n * float(np.sum(w**2))
    return np.abs(c_mean) / np.sqrt(a * a / (1 - s))
