"""The twin's theory: spectrum weights, the autocorrelation models and their fits."""

from __future__ import annotations

import numpy as np
from scipy import optimize

from ..._validate import check_real, check_size
from ...analysis import autocorrelation as ac
from ...analysis.sparse import depth_intensity_psf

SPECTRUM_SHAPES = ("gaussian", "rectangular")
#: k0/delta_k assumed when ``k0`` is not given (the realism target's value).
DEFAULT_K0_DK = 10.0
#: Intensity contrast std/mean below which a linear image is suspected to be log data.
LOG_AS_LINEAR_CONTRAST = 0.5
FOCUS_P_VALUE = 0.01
FOCUS_NULL_DRAWS = 1000  # Monte-Carlo draws of the focus test's null (seeded)
FOCUS_SCAN_DEPTHS = 41  # focus depths scanned over the region and a quarter of it either side
FOCUS_SCAN_RAYLEIGH = 5  # Rayleigh ranges scanned, 1/2 to 2 times k0 w0^2/2
#: Rows above the region whose mean intensity is this many dB below the region's are candidate
#: signal-free rows (found when ``noise_rows`` is not given).
NOISE_ROW_DB = 10.0
#: Fewest contiguous signal-free rows accepted.
MIN_NOISE_ROWS = 4


def rectangular_weights(width_fraction: float, n_pixels: int) -> np.ndarray:
    """Spectral weights of a rectangular spectrum of full width ``width_fraction * delta_k``.

    Component ``n`` (offset ``(n - N//2)/N`` from the centre, in units of ``delta_k``) gets the
    fraction of its cell ``[offset - 1/(2N), offset + 1/(2N)]`` inside the band, so the weights
    change continuously with the width (1 fills the pixel band).
    """
    f = check_real(width_fraction, "width_fraction", low=0, low_inclusive=False, high=1.0)
    n = check_size(n_pixels, "n_pixels", low=8, bytes_per=64.0)
    off = (np.arange(n) - n // 2) / n
    lo, hi = np.maximum(off - 0.5 / n, -f / 2), np.minimum(off + 0.5 / n, f / 2)
    return np.sqrt(np.clip((hi - lo) * n, 0.0, 1.0))  # S^2 is the covered fraction


def _gaussian_weights(fwhm_fraction: float, n: int) -> np.ndarray:
    idx = (np.arange(n) - n // 2) / n
    return np.exp(-4 * np.log(2) * (idx / fwhm_fraction) ** 2)


def _weights(shape: str, width: float, n: int) -> np.ndarray:
    return _gaussian_weights(width, n) if shape == "gaussian" else rectangular_weights(width, n)


def _depth_theory(lags, weights, snr_db, excess):
    """Pearson intensity autocorrelation along depth at finite density (module docstring).

    ``(|gamma(m)|^2 + x d(m)) / ((1 + 1/r)^2 + x)`` with ``d`` the normalised autocorrelation of
    the intensity PSF; ``x <= 0`` is the dense limit of
    :func:`~speckle.analysis.autocorrelation.axial_correlation_theory`.
    """
    if excess <= 0:
        return ac.axial_correlation_theory(lags, weights, snr_db)
    g2 = ac.axial_correlation_theory(lags, weights, None)
    p2 = depth_intensity_psf(weights)
    circ = np.fft.ifft(np.abs(np.fft.fft(p2)) ** 2).real  # circular autocorrelation of |P|^2
    d = circ[(8 * np.asarray(lags, dtype=int)) % p2.size] / circ[0]
    inv_r = 0.0 if snr_db is None else 10 ** (-snr_db / 10)
    out = (g2 + excess * d) / ((1 + inv_r) ** 2 + excess)
    return np.where(np.asarray(lags) == 0, 1.0, out)


def _fit_gaussian(acf, n, snr_db, excess) -> tuple[float, float]:
    if excess <= 0:
        return ac.fit_spectral_width(acf, n, snr_db)
    lags = np.arange(1, acf.size)

    def residual(p):
        return _depth_theory(lags, _gaussian_weights(p[0], n), snr_db, excess) - acf[1:]

    res = optimize.least_squares(residual, 0.5, bounds=(0.02, 5.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _fit_waist(acf, snr_db, excess) -> tuple[float, float]:
    """Lateral: the incoherent term has the same shape, so only the denominator changes."""
    if excess <= 0:
        return ac.fit_waist(acf, snr_db)
    lags = np.arange(1, acf.size)
    inv_r = 0.0 if snr_db is None else 10 ** (-snr_db / 10)
    scale = (1 + excess) / ((1 + inv_r) ** 2 + excess)

    def residual(p):
        return scale * ac.lateral_correlation_theory(lags, p[0], 1.0) - acf[1:]

    res = optimize.least_squares(residual, 2.0, bounds=(0.05, 100.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _fit_rectangular(acf, n, snr_db, excess) -> tuple[float, float]:
    lags = np.arange(1, acf.size)

    def residual(p):
        return _depth_theory(lags, rectangular_weights(p[0], n), snr_db, excess) - acf[1:]

    best = min(np.linspace(0.1, 1.0, 19), key=lambda f: np.sum(residual([f]) ** 2))
    res = optimize.least_squares(residual, best, bounds=(2.0 / n, 1.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _psf_excess(shape: str, width: float, waist_pitch: float, n: int) -> float:
    """``A4/A^2`` of the model's point-spread function, per pixel x pitch (module docstring)."""
    p2 = depth_intensity_psf(_weights(shape, width, n))  # one period, 8 samples per pixel (exact)
    depth = np.sum(p2**2) / 8.0 / (np.sum(p2) / 8.0) ** 2
    lateral = np.sqrt(2 / np.pi) / waist_pitch  # int exp(-8x^2/w^2) / (int exp(-4x^2/w^2))^2
    return float(depth * lateral)


def _pearson_pooled(pairs: list[tuple[np.ndarray, np.ndarray]]) -> float:
    a = np.concatenate([p[0].ravel() for p in pairs])
    b = np.concatenate([p[1].ravel() for p in pairs])
    a = a - a.mean()
    b = b - b.mean()
    return float(np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b)))


def _acf(blocks: list[np.ndarray], max_lag: int, axis: str) -> np.ndarray:
    """Pearson autocorrelation pooled over column blocks (no pair crosses a block edge).

    One block is :func:`speckle.analysis.autocorrelation.intensity_autocorrelation`'s value.
    """
    out = np.ones(max_lag + 1)
    for m in range(1, max_lag + 1):
        if axis == "depth":
            pairs = [(b[:-m], b[m:]) for b in blocks]
        else:
            pairs = [(b[:, :-m], b[:, m:]) for b in blocks if b.shape[1] > m]
        out[m] = _pearson_pooled(pairs)
    return out
