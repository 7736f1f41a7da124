"""Phase tools for strain estimation: complex noise, the image's depth autocorrelation and the lag.

Complex noise
-------------
:func:`speckle.add_complex_noise` adds circular complex Gaussian noise of power
``sigma^2 = <|A|^2> / 10^(snr_db/10)`` to a complex image (SNR = mean image intensity over noise
power). At high SNR a pixel of intensity ``I`` has phase noise of variance ``sigma^2/(2 I)``.

Why adjacent-pixel phase gradients are biased low, and the lag
---------------------------------------------------------------
For fully developed (circular Gaussian) speckle the interframe four-product at depth lag ``L``,
``C = A1(z) A2*(z) A1*(z+L) A2(z+L)``, has by the Gaussian moment theorem the expectation

    E[C] = |E A1 A2*|^2 exp(i dphi_L)  +  E[A1(z) A1*(z+L)] E[A2*(z) A2(z+L)],

with ``dphi_L = 2 k0 (u(z+L) - u(z))``. The second term is the field's own depth
autocorrelation ``rho(L)`` (times the mean intensity squared): real and positive for a symmetric
spectrum, it carries no strain phase. The correlated part of pixel ``z+L`` *is* pixel ``z``'s
field, and it pulls the phase of the sum towards zero: for small phases the estimate is the
truth times ``gamma^2/(gamma^2 + rho(L)^2)`` (``gamma`` = interframe correlation). With a
rectangular spectrum ``rho(1) = 0`` (the Dirichlet kernel vanishes at whole pixels) and the
adjacent pixel is unbiased; a Gaussian spectrum of FWHM ``f*delta_k`` has
``rho(L) = exp(-pi^2 f^2 L^2 / (8 ln 2))`` (the transform of ``S^2``): 0.64 at ``L = 1`` for
``f = 0.5``, a 29 % low bias ``rho^2/(1 + rho^2)``, and ``rho(3)^2 = 3e-4``. :func:`choose_lag`
therefore measures ``|rho(L)|`` on the reference image itself (no knowledge of the source needed, so
it works on measured images) and returns the smallest lag with ``rho(L)^2 <= max_bias``.

At a finite scatterer density ``rho_d`` (per pixel) a third, single-scatterer term
``kappa rho_d int |P(x)|^2 |P(x+L)|^2 dx`` (each scatterer in all four factors; also without
strain phase) adds to the low bias: the lag-1 factor is ``1/(1 + rho(1)^2 + D1/(rho_d A^2))``
with ``A = int |P|^2``, 0.685 for ``f = 0.5`` and ``rho_d = 4`` (``tests/test_strain.py``
checks it). Both terms fall with the lag.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_int, check_real

__all__ = ["DEFAULT_MAX_BIAS", "choose_lag", "depth_autocorrelation", "noise_power"]

#: Largest relative low bias ``rho(L)^2`` accepted by :func:`choose_lag` (0.5 %).
DEFAULT_MAX_BIAS = 0.005


def noise_power(field: object, snr_db: float) -> float:
    """Noise power ``sigma^2 = mean(|field|^2) / 10^(snr_db/10)`` (:func:`speckle.add_noise`)."""
    snr = check_real(snr_db, "snr_db")
    return float(np.mean(np.abs(np.asarray(field)) ** 2)) / 10 ** (snr / 10)


def depth_autocorrelation(image: np.ndarray, max_lag: int) -> np.ndarray:
    """``|rho(L)|``, ``L = 0 ... max_lag``: normalised depth autocorrelation of a complex image.

    ``rho(L) = sum A(z) A*(z+L) / sqrt(sum |A(z)|^2 sum |A(z+L)|^2)`` over all pixel pairs of
    every A-line (axis 0 is depth).
    """
    a = np.asarray(image)
    m = check_int(max_lag, "max_lag", low=0, high=a.shape[0] - 1)
    out = np.empty(m + 1)
    for lag in range(m + 1):
        x, y = a[: a.shape[0] - lag], a[lag:]
        num = np.abs(np.sum(x * np.conj(y)))
        out[lag] = num / np.sqrt(np.sum(np.abs(x) ** 2) * np.sum(np.abs(y) ** 2))
    return out


def choose_lag(image: np.ndarray, *, max_bias: float = DEFAULT_MAX_BIAS, max_lag: int = 64) -> int:
    """Smallest depth lag (pixels) whose field autocorrelation obeys ``rho(L)^2 <= max_bias``.

    Parameters
    ----------
    image : numpy.ndarray, shape (depth, aline)
        Complex reference image.
    max_bias : float
        Largest accepted relative low bias of the vector estimator, in (0, 1).
    max_lag : int
        Largest lag considered; capped at a quarter of the image depth.

    Raises
    ------
    ValueError
        If no lag up to the cap decorrelates enough (speckle larger than the image allows).
    """
    eps = check_real(max_bias, "max_bias", low=0, high=1, low_inclusive=False, high_inclusive=False)
    cap = min(check_int(max_lag, "max_lag", low=1), max(1, image.shape[0] // 4))
    a = np.asarray(image)
    rows = np.sum(np.abs(a) ** 2, axis=1)  # power per depth row: each lag's norms from it
    total, n = rows.sum(), a.shape[0]
    head = total - np.concatenate([[0.0], np.cumsum(rows[::-1])])  # sum of rows[: n - lag]
    tail = total - np.concatenate([[0.0], np.cumsum(rows)])  # sum of rows[lag:]
    rho = 1.0
    for lag in range(1, cap + 1):  # the first lag that decorrelates: later lags are not needed
        rho = np.abs(np.vdot(a[lag:], a[: n - lag])) / np.sqrt(head[lag] * tail[lag])
        if rho**2 <= eps:
            return lag
    raise ValueError(
        f"the field stays correlated (|rho| = {rho:.3f}) up to lag {cap} pixels; give "
        "lag= explicitly or a deeper image"
    )
