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
from .._wrap import ArraySpec, preprocess_and_wrap
from ._common import depth_major
from ._kernels import lag_sums

__all__ = ["DEFAULT_MAX_BIAS", "choose_lag", "depth_autocorrelation", "lag_and_rho", "noise_power"]

#: Largest relative low bias ``rho(L)^2`` accepted by :func:`choose_lag` (0.5 %).
DEFAULT_MAX_BIAS = 0.005
#: A complex (depth, aline) image, finite, at least two depth pixels.
_IMAGE = ArraySpec(kind="complex", ndim=2, min_shape=(2, 1))


@preprocess_and_wrap(checks={"field": ArraySpec()})
def noise_power(field: object, snr_db: float) -> float:
    """Noise power ``sigma^2 = mean(|field|^2) / 10^(snr_db/10)`` (:func:`speckle.add_noise`)."""
    snr = check_real(snr_db, "snr_db")
    return float(np.mean(np.abs(np.asarray(field)) ** 2)) / 10 ** (snr / 10)


@preprocess_and_wrap(checks={"image": _IMAGE})
def depth_autocorrelation(image: np.ndarray, max_lag: int) -> np.ndarray:
    """``|rho(L)|``, ``L = 0 ... max_lag``: normalised depth autocorrelation of a complex image.

    ``rho(L) = sum A(z) A*(z+L) / sqrt(sum |A(z)|^2 sum |A(z+L)|^2)`` over all pixel pairs of
    every A-line (axis 0 is depth).
    """
    m = check_int(max_lag, "max_lag", low=0, high=np.shape(image)[0] - 1)
    a = depth_major(image)
    power = np.empty(a.shape[0])
    sums = lag_sums(a, 0, m + 1, power)
    head, tail = _norms(power)
    lags = np.arange(m + 1)
    return np.abs(sums) / np.sqrt(head[lags] * tail[lags])


def _norms(power: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``sum |A|^2`` over depth rows ``[0, n - L)`` and ``[L, n)`` for every lag ``L`` (index)
    from the power per depth row."""
    total = power.sum()
    head = total - np.concatenate([[0.0], np.cumsum(power[::-1])])
    tail = total - np.concatenate([[0.0], np.cumsum(power)])
    return head, tail


#: Lags measured per pass over the image by :func:`lag_and_rho`.
_LAG_BLOCK = 4


@preprocess_and_wrap(checks={"image": _IMAGE})
def lag_and_rho(
    image: np.ndarray, *, max_bias: float = DEFAULT_MAX_BIAS, max_lag: int = 64
) -> tuple[int, np.ndarray]:
    """:func:`choose_lag` and ``|rho(L)|`` for ``L = 0 ... lag`` (the lags it measured).

    Same parameters and errors as :func:`choose_lag`.
    """
    eps = check_real(max_bias, "max_bias", low=0, high=1, low_inclusive=False, high_inclusive=False)
    cap = min(check_int(max_lag, "max_lag", low=1), max(1, np.shape(image)[0] // 4))
    a = depth_major(image)
    power = np.empty(a.shape[0])
    rho = [1.0]
    for lo in range(1, cap + 1, _LAG_BLOCK):  # a few lags per pass; stop at the first that
        sums = lag_sums(a, lo, min(lo + _LAG_BLOCK, cap + 1), power if lo == 1 else power[:0])
        head, tail = _norms(power)
        for k, lag in enumerate(range(lo, lo + sums.size)):  # decorrelates
            rho.append(float(np.abs(sums[k]) / np.sqrt(head[lag] * tail[lag])))
            if rho[-1] ** 2 <= eps:
                return lag, np.array(rho)
    raise ValueError(
        f"the field stays correlated (|rho| = {rho[-1]:.3f}) up to lag {cap} pixels; give "
        "lag= explicitly or a deeper image"
    )


@preprocess_and_wrap(checks={"image": _IMAGE})
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

    Returns
    -------
    int
        The lag (see :func:`lag_and_rho` for the correlations measured on the way).

    Raises
    ------
    ValueError
        If no lag up to the cap decorrelates enough (speckle larger than the image allows).
    """
    return lag_and_rho.__wrapped__(image, max_bias=max_bias, max_lag=max_lag)[0]  # checked
