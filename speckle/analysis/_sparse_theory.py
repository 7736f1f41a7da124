"""The numerical core of :mod:`speckle.analysis.sparse` (private), shared with the phantom fit.

The theory (Campbell's characteristic function of sparse speckle and the log-intensity moments
from it) is in :mod:`speckle.analysis.sparse`'s docstring. Here: the ``ln t`` grid
(:data:`TAU`), the lateral table, the unit-amplitude exponent ``Lambda`` of a depth PSF
(:func:`exponent`), the moments from a characteristic function (:func:`moments_of`) and the
inversion of ``var ln I`` to an inverse density (:func:`invert_log_variance`), which
``sparse_inverse_density`` and the phantom fit's slab theory
(:mod:`speckle.studies.phantom._density`) both use.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np
from scipy import optimize, special

__all__ = [
    "MAX_INVERSE_DENSITY",
    "TAU",
    "exponent",
    "intensity_psf",
    "invert_log_variance",
    "moments_of",
]

#: Largest inverse density (1 / scatterers per pixel per pitch) the inversion searches.
MAX_INVERSE_DENSITY = 20.0
#: ``ln t`` grid of the characteristic function, ``t`` in units of ``1/sqrt(area)``.
TAU = np.linspace(np.log(1e-4), np.log(1e10), 4000)
#: Smallest inverse density of the root search; below it ``var ln I`` is continued linearly.
_LOW = 0.01


@lru_cache(maxsize=1)
def _lateral_table() -> tuple[np.ndarray, np.ndarray]:
    """``ln(-g(a))``, ``g(a) = int (J0(a exp(-2 y^2)) - 1) dy`` (``y = x / w0``), on ``ln a``.

    ``-g > 0`` rises as ``a^2`` then slowly: ``ln(-g)`` is nearly linear in ``ln a``, so the
    linear interpolation is accurate to ~1e-6.
    """
    la = np.linspace(np.log(1e-5), np.log(1e16), 2000)
    out = np.empty_like(la)
    for i, v in enumerate(la):
        y = np.linspace(0.0, np.sqrt(max(v + 25.0, 1.0) / 2), 3001)
        out[i] = 2 * np.trapezoid(special.j0(np.exp(v - 2 * y**2)) - 1, y)
    return la, np.log(-out)


def _lateral(a: np.ndarray) -> np.ndarray:
    la, g = _lateral_table()
    lna = np.log(np.maximum(a, 1e-300))
    # below the table J0(u) - 1 = -u^2/4: g(a) = -a^2/4 int exp(-4 y^2) dy = -a^2 sqrt(pi)/8
    return np.where(lna < la[0], -(a**2) * np.sqrt(np.pi) / 8, -np.exp(np.interp(lna, la, g)))


def intensity_psf(weights: np.ndarray) -> np.ndarray:
    """``|P(u)|^2`` over one period, 8 samples per pixel, of checked float ``weights``."""
    n = weights.size
    # P(k/8) = sum_n w_n exp(2 pi i k (n - N//2) / (8 N)): a zero-padded inverse FFT
    padded = np.zeros(8 * n, complex)
    padded[(np.arange(n) - n // 2) % (8 * n)] = weights
    return np.abs(np.fft.ifft(padded) * (8 * n)) ** 2


@lru_cache(maxsize=64)
def exponent(weights: tuple, waist_pitch: float) -> tuple[np.ndarray, float]:
    """``Lambda(t)`` of unit amplitudes on ``t = exp(TAU)/sqrt(area)`` and ``area = int |h|^2``
    (pixels x pitches), for the spectral ``weights`` and the waist in pitches."""
    amp = np.sqrt(intensity_psf(np.array(weights, dtype=float)))
    area = float(np.sum(amp**2) / 8 * waist_pitch * np.sqrt(np.pi) / 2)  # int |h|^2
    t = np.exp(TAU) / np.sqrt(area)
    lam = _lateral(np.outer(t, amp)).sum(axis=1) / 8 * waist_pitch
    return lam, area


def moments_of(phi: np.ndarray, s2: float, area: float) -> tuple[float, float]:
    """``E ln(I/<I>)`` and ``var ln I`` from the characteristic function ``phi`` on
    ``t = exp(TAU)/sqrt(area)`` and the mean intensity ``s2`` (sparse's module docstring)."""
    g = np.euler_gamma
    t = np.exp(TAU) / np.sqrt(area)
    dphi = phi - np.exp(-s2 * t**2 / 4)
    ln_t = TAU - 0.5 * np.log(area)
    d0 = float(np.trapezoid(dphi, TAU))
    d1 = float(2 * np.trapezoid(ln_t * dphi, TAU))
    mean = np.log(s2) - g - 2 * d0
    second = (np.log(s2) - g) ** 2 + np.pi**2 / 6 + 4 * (d1 + 2 * d0 * (g - np.log(2)))
    return float(mean - np.log(s2)), float(second - mean**2)


def invert_log_variance(gap: Callable[[float], float], v: float) -> float:
    """The inverse density ``y`` with ``gap(y) = var_ln_I(y) - v = 0``.

    Between ``pi^2/6`` and the value at ``y = 0.01``, linear in ``1/rho`` (continued below 0
    for a variance under ``pi^2/6``, so that the estimate stays unbiased at high density);
    :data:`MAX_INVERSE_DENSITY` above its value there; otherwise Brent's root.
    """
    g_lo = gap(_LOW)
    if g_lo >= 0:
        return float(_LOW * (v - np.pi**2 / 6) / (g_lo + v - np.pi**2 / 6))
    if gap(MAX_INVERSE_DENSITY) <= 0:
        return MAX_INVERSE_DENSITY
    return float(optimize.brentq(gap, _LOW, MAX_INVERSE_DENSITY, xtol=1e-6))
