"""The twin's focus: the confocal fit and its generalised least-squares test."""

from __future__ import annotations

import numpy as np
from scipy import linalg, optimize, signal

from ._theory import FOCUS_NULL_DRAWS, FOCUS_SCAN_DEPTHS, FOCUS_SCAN_RAYLEIGH


def _confocal(z, a, mu, zf, zr, noise):
    return a * np.exp(-2 * mu * z) * (1 + ((z - zf) / zr) ** 2) ** -1.5 + noise


def _refit_focus(z, rows, rows_se, noise_level, p0):
    """The focused profile fitted from ``p0`` to the intensity row means: (parameters,
    covariance)."""
    span = z[-1] - z[0] + (z[1] - z[0])
    return optimize.curve_fit(
        lambda zz, a, mu, zf, zr: _confocal(zz, a, mu, zf, zr, noise_level),
        z, rows, p0=p0, sigma=rows_se, absolute_sigma=True,
        bounds=([0, -1, z[0] - 2 * span, span / 50], [np.inf, 1, z[-1] + 2 * span, 20 * span]),
        maxfev=20000,
    )  # fmt: skip


def _fit_focus(z, rows, rows_se, noise_level, start):
    """Weighted least squares of the focused profile to the intensity row means.

    Started from the focus test's best ``start = (z_f, z_R)`` and a few other points; returns
    ``(chi^2, parameters, covariance)`` of the best fit, or None.
    """
    mean = float(rows.mean())
    span = z[-1] - z[0] + (z[1] - z[0])
    grid = [(a, b) for a in np.linspace(z[0], z[-1], 5) for b in (span / 8, span / 3, span)]
    best = None
    for zf0, zr0 in [start, *grid]:
        try:
            p, cov = _refit_focus(z, rows, rows_se, noise_level, [mean, 0.0, zf0, zr0])
        except (RuntimeError, ValueError):
            continue
        chi = float(np.sum(((_confocal(z, *p, noise_level) - rows) / rows_se) ** 2))
        if best is None or chi < best[0]:
            best = (chi, p, cov)
    return best


def _row_mean_covariance(log_image: np.ndarray) -> np.ndarray:
    """Covariance of the row means of ``ln I`` (depth, x) from its 2-D autocovariance.

    The rows' means are removed; the autocovariance (FFT, :func:`scipy.signal.correlate`, over
    overlapping pairs) is summed over x-lags up to the first non-positive lateral lag ``L``,
    which gives ``S(m) = nx cov(row_i, row_{i+m})``; removing the row means scales the truncated
    sum by ``1 - (2 L + 1)/nx`` (corrected). ``S`` is kept up to its first non-positive depth
    lag (the point-spread function's correlation length) and the Toeplitz matrix
    ``S(|i - j|)/nx`` is returned (eigenvalues clipped to stay positive).
    """
    nz, nx = log_image.shape
    r = log_image - log_image.mean(axis=1, keepdims=True)
    count = signal.correlate(np.ones_like(r), np.ones_like(r), mode="full", method="fft")
    cxz = signal.correlate(r, r, mode="full", method="fft") / np.maximum(np.round(count), 1)
    z0, x0 = nz - 1, nx - 1
    lat = cxz[z0, x0:]
    stop = np.flatnonzero(lat[1:] <= 0)
    lx = min(int(stop[0]) if stop.size else lat.size - 1, nx // 4)
    s = cxz[z0:, x0 - lx : x0 + lx + 1].sum(axis=1) / (1 - (2 * lx + 1) / nx)
    stop = np.flatnonzero(s[1:] <= 0)
    lz = int(stop[0]) + 1 if stop.size else s.size
    col = np.zeros(nz)
    col[:lz] = s[:lz]
    w, v = linalg.eigh(linalg.toeplitz(col) / nx)
    return (v * np.maximum(w, 1e-6 * w.max())) @ v.T


def _focus_test(
    z: np.ndarray, rows: np.ndarray, cov: np.ndarray, rayleigh: float, seed: int = 0
) -> tuple[float, float, float]:
    """Scan test of a confocal term in the log row means (module docstring).

    Returns the p-value and the best focus depth and Rayleigh range (µm).
    """
    span = z[-1] - z[0] + (z[1] - z[0])
    chol = linalg.cholesky(cov, lower=True)
    x = np.column_stack([np.ones_like(z), z])
    q, _ = np.linalg.qr(linalg.solve_triangular(chol, x, lower=True))
    zf, zr = np.meshgrid(
        np.linspace(z[0] - span / 4, z[-1] + span / 4, FOCUS_SCAN_DEPTHS),
        rayleigh * 2.0 ** np.linspace(-1, 1, FOCUS_SCAN_RAYLEIGH),
    )
    zf, zr = zf.ravel(), zr.ravel()
    term = -1.5 * np.log1p(((z[:, None] - zf) / zr) ** 2)  # ln of (1 + u^2)^(-3/2)
    tw = linalg.solve_triangular(chol, term, lower=True)
    tw -= q @ (q.T @ tw)
    norm = np.linalg.norm(tw, axis=0)
    keep = norm > 1e-9 * norm.max()
    tw, zf, zr = tw[:, keep] / norm[keep], zf[keep], zr[keep]

    def statistic(white):  # largest one-sided GLS reduction of the residual sum of squares
        return np.max(np.maximum(white @ tw, 0.0) ** 2, axis=-1)

    yw = linalg.solve_triangular(chol, rows, lower=True)
    obs = float(statistic(yw))
    best = int(np.argmax(np.maximum(yw @ tw, 0.0)))
    null = statistic(np.random.default_rng(seed).standard_normal((FOCUS_NULL_DRAWS, z.size)))
    p = (1 + int(np.sum(null >= obs))) / (1 + FOCUS_NULL_DRAWS)
    return float(p), float(zf[best]), float(zr[best])
