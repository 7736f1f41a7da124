"""Closed forms of the correlation versus strain: continuum limit, two-peak source, carrier window.

The exact theory is :func:`speckle.expected_correlation` (:mod:`speckle.analysis.correlation`);
these closed forms explain its shape (the paper's Fig. 6): ``continuum_gamma`` is the
rectangular spectrum's triangle, ``two_peak_weights`` a source whose correlation revives, and
``carrier_window_factor`` the minima and revivals a window of uncompensated carrier phase adds.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..system.source import spectral_index

__all__ = ["carrier_window_factor", "continuum_gamma", "two_peak_weights"]


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
