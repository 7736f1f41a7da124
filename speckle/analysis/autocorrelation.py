"""Intensity autocorrelation of B-scans along depth and across A-lines, and its theory.

Estimator: the Pearson correlation of pixel intensities ``lag`` pixels (or A-lines) apart,
pooled over the image, with a standard error from the spread over contiguous blocks of A-lines
(as :func:`speckle.analysis.measured.log_statistics`).

Theory for fully developed speckle (Siegert: intensity correlation = ``|gamma|^2``):

* along depth, ``gamma(m) = sum_n S_n^2 exp(2i pi n m/N) / sum_n S_n^2`` for the spectrum
  ``S`` (a rectangular spectrum filling the pixel band gives 0 at every lag >= 1; a Gaussian
  spectrum narrower than the band correlates neighbouring pixels);
* across A-lines of a scanned Gaussian beam (:func:`speckle.beam_scan`), lines ``m`` pitches
  ``p`` apart have ``gamma = exp(-(m p)^2/w0^2)``: intensity correlation ``exp(-2 m^2 p^2/w0^2)``;
* white receiver noise at pixel SNR ``r`` multiplies every lag >= 1 by ``(r/(1 + r))^2``; a
  constant intensity floor changes no Pearson correlation of intensities.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import optimize

from .._validate import check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, coord
from ._common import DEPTH, X

__all__ = [
    "axial_correlation_theory",
    "fit_spectral_width",
    "fit_waist",
    "intensity_autocorrelation",
    "lateral_correlation_theory",
    "noise_factor",
]


def _pearson(a: np.ndarray, b: np.ndarray) -> float:
    a = a - a.mean()
    b = b - b.mean()
    return float(np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b)))


@preprocess_and_wrap(checks={"intensity": ArraySpec(kind="real", dims=(DEPTH, X), labelled=True)})
def intensity_autocorrelation(
    intensity: xr.DataArray, *, max_lag: int = 8, n_blocks: int = 16
) -> xr.Dataset:
    """Pearson autocorrelation along ``depth`` and ``x`` at lags ``0 .. max_lag``.

    Parameters
    ----------
    intensity : xarray.DataArray
        Linear intensities with dims ``(depth, x)`` (``(depth, aline)`` warns).
    max_lag : int
        Largest lag in pixels / A-lines (>= 1, less than either size).
    n_blocks : int
        Contiguous A-line blocks for the standard error (>= 2).

    Returns
    -------
    xarray.Dataset
        ``autocorrelation`` and ``autocorrelation_se`` with dims ``(axis, lag)``, ``axis`` =
        ``("depth", "lateral")``.
    """
    x = intensity  # checked: a real, finite (depth, x) DataArray's values ('aline' warns)
    nz, nl = x.shape
    ml = check_int(max_lag, "max_lag", low=1, high=min(nz, nl) - 2)
    nb = check_int(n_blocks, "n_blocks", low=2, high=max(2, nl // (ml + 2)))

    def acf(block: np.ndarray) -> np.ndarray:
        out = np.empty((2, ml + 1))
        for m in range(ml + 1):
            out[0, m] = _pearson(block[: block.shape[0] - m], block[m:])
            out[1, m] = _pearson(block[:, : block.shape[1] - m], block[:, m:])
        return out

    whole = acf(x)
    blocks = np.stack([acf(x[:, b]) for b in np.array_split(np.arange(nl), nb)])
    se = blocks.std(axis=0, ddof=1) / np.sqrt(nb)
    coords = {
        "axis": ["depth", "lateral"],
        "lag": coord("lag", np.arange(ml + 1), "lag (pixels or lines)"),
    }
    return xr.Dataset(
        {
            "autocorrelation": (
                ("axis", "lag"),
                whole,
                attrs("correlation", "intensity autocorrelation"),
            ),
            "autocorrelation_se": (
                ("axis", "lag"),
                se,
                attrs("correlation", "standard error of the autocorrelation", note="A-line blocks"),
            ),
        },
        coords=coords,
        attrs={"n_blocks": nb},
    )


def noise_factor(snr_db: float | None) -> float:
    """``(r/(1 + r))^2``, ``r = 10^(snr_db/10)``: white noise's factor on lags >= 1 (1 if None)."""
    if snr_db is None:
        return 1.0
    r = 10 ** (check_real(snr_db, "snr_db") / 10)
    return (r / (1 + r)) ** 2


@preprocess_and_wrap(
    checks={"lags": ArraySpec(kind="real"), "spectrum": ArraySpec(kind="real", ndim=1)}
)
def axial_correlation_theory(
    lags: object, spectrum: object, snr_db: float | None = None
) -> np.ndarray:
    """Intensity correlation along depth at integer ``lags`` for spectral weights ``spectrum``."""
    s2 = spectrum**2  # checked: real, finite, 1-D
    n = s2.size
    idx = np.arange(n) - n // 2
    m = np.asarray(lags, dtype=float)
    g = np.exp(2j * np.pi * np.multiply.outer(m, idx) / n) @ s2 / s2.sum()
    return np.where(m == 0, 1.0, np.abs(g) ** 2 * noise_factor(snr_db))


@preprocess_and_wrap(checks={"lags": ArraySpec(kind="real")})
def lateral_correlation_theory(
    lags: object, waist: float, pitch: float = 1.0, snr_db: float | None = None
) -> np.ndarray:
    """``exp(-2 (m p)^2/w0^2)`` at lags ``m`` for waist ``w0`` and pitch ``p`` (same units)."""
    w = check_real(waist, "waist", low=0, low_inclusive=False)
    p = check_real(pitch, "pitch", low=0, low_inclusive=False)
    m = np.asarray(lags, dtype=float)
    return np.where(m == 0, 1.0, np.exp(-2 * (m * p / w) ** 2) * noise_factor(snr_db))


def _fit(residual, x0: float, lo: float, hi: float) -> tuple[float, float]:
    res = optimize.least_squares(residual, x0, bounds=(lo, hi))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


@preprocess_and_wrap(checks={"measured": ArraySpec(kind="real", ndim=1, min_shape=(2,))})
def fit_spectral_width(
    measured: object, n_pixels: int, snr_db: float | None = None
) -> tuple[float, float]:
    """Least-squares Gaussian ``fwhm_fraction`` (of ``delta_k``) to a depth autocorrelation.

    ``measured`` holds the correlation at lags ``0, 1, ...``; lags >= 1 are fitted with
    :func:`axial_correlation_theory` of ``speckle.spectrum(shape="gaussian")`` weights on
    ``n_pixels`` components. Returns ``(fwhm_fraction, rms residual)``.
    """
    y = measured  # checked: real, finite, lags 0 and 1 at least
    n = check_int(n_pixels, "n_pixels", low=8)
    lags = np.arange(1, y.size)
    idx = (np.arange(n) - n // 2) / n  # (k - k0)/delta_k

    def residual(p):
        s = np.exp(-4 * np.log(2) * (idx / p[0]) ** 2)
        return axial_correlation_theory.__wrapped__(lags, s, snr_db) - y[1:]  # checked

    return _fit(residual, 0.5, 0.02, 5.0)


@preprocess_and_wrap(checks={"measured": ArraySpec(kind="real", ndim=1, min_shape=(2,))})
def fit_waist(measured: object, snr_db: float | None = None) -> tuple[float, float]:
    """Least-squares beam waist in A-line pitches from a lateral autocorrelation (lags 0, 1, ...).

    Returns ``(waist / pitch, rms residual)``.
    """
    y = measured  # checked: real, finite, lags 0 and 1 at least
    lags = np.arange(1, y.size)
    return _fit(
        lambda p: lateral_correlation_theory.__wrapped__(lags, p[0], 1.0, snr_db) - y[1:],
        2.0,
        0.05,
        100.0,
    )
