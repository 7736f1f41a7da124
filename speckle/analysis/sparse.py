"""Log-intensity moments of sparse speckle: Poisson scatterers seen through the model's PSF.

A pixel's field is ``F = sum_j h(r_j) exp(i phi_j) + noise``: Poisson scatterers of unit
amplitude (``rho`` per pixel per pitch), uniform phases, the point-spread function ``h(z, x) =
P(z) exp(-2 x^2 / w0^2)`` (``P`` the depth PSF of the spectral weights, periodic over the model's
``N`` pixels; the round-trip Gaussian beam across A-lines) and circular Gaussian noise of power
``N_n``. Its two-dimensional characteristic function is exact (Campbell's theorem)::

    Phi(t) = E exp(i Re(t* F)) = exp(rho Lambda(t) - N_n t^2 / 4),
    Lambda(t) = int (J0(t |h(r)|) - 1) dr.

For an isotropic 2-D vector, ``E |F|^{-2s} = 2^{1 - 2s} Gamma(1 - s)/Gamma(s) int_0^inf
t^{2s - 1} Phi(t) dt`` (``0 < s < 1``, Parseval with the Fourier transform of ``|F|^{-2s}``).
Subtracting the Gaussian of the same power ``sigma^2 = rho int |h|^2 + N_n`` (``Phi_G =
exp(-sigma^2 t^2/4)``, fully developed speckle) and expanding at ``s = 0``, with
``D0 = int (Phi - Phi_G) dt/t`` and ``D1 = 2 int ln t (Phi - Phi_G) dt/t``::

    E ln I   = ln sigma^2 - gamma - 2 D0,
    E ln^2 I = (ln sigma^2 - gamma)^2 + pi^2/6 + 4 (D1 + 2 D0 (gamma - ln 2)),

``gamma`` Euler's constant. Dense speckle (``Phi -> Phi_G``) gives back ``var ln I = pi^2/6``;
at low density the pixels far from every scatterer make ``ln I`` heavier-tailed below, and
``var ln I`` rises (3.56 at 0.5 scatterers per pixel per pitch for a Gaussian spectrum filling
the band and a one-pitch waist). The K distribution of the same contrast predicts only 2.37
there: it is not used. ``Lambda`` is separable: ``int dx (J0(a exp(-2x^2/w0^2)) - 1) = w0
g(a)``, ``g`` tabulated once; the depth integral is a sum over 8 samples per pixel of ``|P|``.
"""

from __future__ import annotations

import inspect

import numpy as np

from .._deprecate import keyword_only
from .._validate import check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ._sparse_theory import (
    TAU,
    exponent,
    intensity_psf,
    invert_log_variance,
    moments_of,
)

__all__ = ["depth_intensity_psf", "log_intensity_moments", "sparse_inverse_density"]


#: Spectral weights: finite, real, 1-D, non-empty (the decorator's checks).
_WEIGHTS = {"weights": ArraySpec(kind="real", ndim=1)}


def _weights(weights: np.ndarray) -> np.ndarray:
    """The decorator-checked weights as floats, refused when all zero."""
    w = np.asarray(weights, dtype=float)
    if not np.any(w):
        raise ValueError("weights must not all be zero (no power: the PSF is undefined)")
    return w


@preprocess_and_wrap(checks=_WEIGHTS)
def depth_intensity_psf(weights: np.ndarray) -> np.ndarray:
    """``|P(u)|^2`` of the model's depth PSF over one period, 8 samples per pixel.

    Parameters
    ----------
    weights : numpy.ndarray
        Spectral weights of the ``N`` components, centred on ``N // 2`` (finite, real,
        1-D, not all zero).

    Returns
    -------
    numpy.ndarray
        ``8 N`` samples, ``u = 0, 1/8, ...`` pixels.

    Raises
    ------
    TypeError, ValueError
        ``weights`` not a finite real non-empty 1-D array, or all zero.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> psf = speckle.depth_intensity_psf(np.ones(8))
    >>> psf.shape, round(float(psf.max()), 6)  # 8 samples per pixel; (sum S)^2 at the peak
    ((64,), 64.0)
    """
    return intensity_psf(_weights(weights))


@keyword_only("inverse_snr")
@preprocess_and_wrap(checks=_WEIGHTS)
def log_intensity_moments(
    weights: np.ndarray, waist_pitch: float, density: float, *, inverse_snr: float = 0.0
) -> tuple[float, float]:
    """Mean and variance of ``ln(I / <I>)`` of sparse speckle (module docstring).

    Parameters
    ----------
    weights : numpy.ndarray
        Spectral weights ``S(k_n)`` of the model's ``N`` components (the depth PSF).
    waist_pitch : float
        Beam waist ``w0`` in A-line pitches (> 0).
    density : float
        Scatterers per pixel per pitch (> 0); ``inf`` is fully developed speckle.
    inverse_snr : float
        Noise power over the mean signal intensity (>= 0).

    Returns
    -------
    (float, float)
        ``E ln(I/<I>)`` and ``var ln I`` (``-gamma`` and ``pi^2/6`` for fully developed
        speckle).

    Raises
    ------
    TypeError, ValueError
        A non-positive waist or density, a negative ``inverse_snr``, or ``weights`` as
        :func:`depth_intensity_psf` refuses them.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> mean, var = speckle.log_intensity_moments(np.ones(64), 2.0, 1e4)
    >>> round(var, 3), round(np.pi**2 / 6, 3)  # dense speckle: var ln I = pi^2/6
    (1.645, 1.645)
    """
    wts = _weights(weights)
    w = check_real(waist_pitch, "waist_pitch", low=0, low_inclusive=False)
    rho = check_real(density, "density", low=0, low_inclusive=False)
    n = check_real(inverse_snr, "inverse_snr", low=0)
    g = np.euler_gamma
    if not np.isfinite(rho):
        return -g, np.pi**2 / 6
    lam, area = exponent(tuple(wts), w)
    t = np.exp(TAU) / np.sqrt(area)
    s2 = rho * area * (1 + n)
    phi = np.exp(rho * lam - rho * area * n * t**2 / 4)
    return moments_of(phi, s2, area)


@keyword_only("inverse_snr")
@preprocess_and_wrap(checks=_WEIGHTS)
def sparse_inverse_density(
    log_variance: float, weights: np.ndarray, waist_pitch: float, *, inverse_snr: float = 0.0
) -> float:
    """The inverse density ``1/rho`` whose ``var ln I`` (:func:`log_intensity_moments`) is given.

    ``var ln I`` falls monotonically with the density to ``pi^2/6``. Below its value at
    ``1/rho = 0.01`` the relation is taken linear in ``1/rho`` through ``(0, pi^2/6)`` (a
    variance under ``pi^2/6``, sampling error of dense speckle, gives a negative value, as the
    contrast estimate does); above the value at :data:`MAX_INVERSE_DENSITY` that bound is
    returned.

    Parameters
    ----------
    log_variance : float
        Measured ``var ln I`` (> 0).
    weights, waist_pitch, inverse_snr
        As in :func:`log_intensity_moments`.

    Returns
    -------
    float
        ``1/rho`` (scatterers per pixel per pitch, inverted).

    Raises
    ------
    ValueError
        A non-positive ``log_variance`` (and as :func:`log_intensity_moments`).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> w = np.ones(64)
    >>> _, var = speckle.log_intensity_moments(w, 2.0, 0.5)
    >>> round(speckle.sparse_inverse_density(var, w, 2.0), 4)  # back to 1/rho = 2
    2.0
    """
    v = check_real(log_variance, "log_variance", low=0, low_inclusive=False)
    log_intensity_moments(
        weights, waist_pitch, 1.0, inverse_snr=inverse_snr
    )  # checks every argument first

    def gap(y):
        # the body: the arguments were checked once, just above
        body = inspect.unwrap(log_intensity_moments)
        return body(weights, waist_pitch, 1 / y, inverse_snr=inverse_snr)[1] - v

    return invert_log_variance(gap, v)
