"""Closed forms of the spectrometer chain (private; public through
:mod:`speckle.system.spectrometer`): dispersion phase, spectral apodizations, the axial intensity
correlation of speckle and the error of k-linearisation by resampling."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._validate import (
    as_finite_array,
    check_choice,
    check_int,
    check_real,
)

#: Spectral apodizations of :func:`spectral_apodization`.
APODIZATIONS = ("none", "hann", "gaussian")
#: Largest number of complex phase factors held in memory at once.
CHUNK_ELEMENTS = 1 << 22


def check_dispersion(dispersion: Mapping | None) -> dict[int, float]:
    """Validate ``{order: coefficient}`` (orders integers >= 2, coefficients in µm^order)."""
    if dispersion is None:
        return {}
    if not isinstance(dispersion, Mapping):
        raise TypeError(
            "dispersion must be a mapping {order: coefficient in µm^order}, e.g. {2: 50.0}; "
            f"got {type(dispersion).__name__}"
        )
    out = {}
    for order, coef in dispersion.items():
        p = check_int(order, "dispersion order", low=2)
        out[p] = check_real(coef, f"dispersion coefficient of order {p}")
    return out


def dispersion_phase(wavenumber: object, k0: float, dispersion: Mapping | None) -> np.ndarray:
    """Dispersion-mismatch phase ``phi(k) = sum_p c_p (k - k0)^p`` in rad.

    Parameters
    ----------
    wavenumber : array_like
        ``k`` in rad/µm (medium).
    k0 : float
        Expansion centre in rad/µm.
    dispersion : mapping or None
        ``{order p: c_p}`` with integer orders >= 2 and ``c_p`` in µm^p (``None``: no phase).
    """
    coefs = check_dispersion(dispersion)
    k = as_finite_array(wavenumber, "wavenumber")
    kc = check_real(k0, "k0", low=0)
    return sum((c * (k - kc) ** p for p, c in coefs.items()), np.zeros_like(k))


def spectral_apodization(n_pixels: int, apodization: str = "none", fwhm_fraction: float = 0.5):
    """Spectral apodization over the ``N`` grid components, peak 1 at ``n = 0`` (index ``N//2``).

    ``"hann"``: ``cos^2(pi n/N)`` (zero at ``n = -N/2``); ``"gaussian"``:
    ``exp(-4 ln2 (n/(f N))^2)`` with FWHM ``f N`` components (``fwhm_fraction`` = f > 0).
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    check_choice(apodization, "apodization", APODIZATIONS)
    idx = np.arange(n) - n // 2
    if apodization == "none":
        return np.ones(n)
    if apodization == "hann":
        return np.cos(np.pi * idx / n) ** 2
    f = check_real(fwhm_fraction, "fwhm_fraction", low=0, low_inclusive=False)
    return np.exp(-4 * np.log(2) * (idx / (f * n)) ** 2)


def axial_intensity_correlation(
    weights: object, lags: object, density: float, kappa: float = 1.0
) -> np.ndarray:
    """Pearson correlation of speckle intensity between pixels ``lag`` apart in depth.

    For Poisson scatterers (``density`` per pixel, uniform depths, uniform carrier phases,
    ``kappa = E|a|^4/E^2|a|^2``) imaged with spectral weights ``u_n`` (spectrum times window),
    Campbell's theorem gives exactly (finite ``N``, finite density)
    ``(rho^2 |C(l)|^2 + rho kappa D(l)) / (rho^2 C(0)^2 + rho kappa D(0))`` with, for the PSF
    ``P(x) = sum_n u_n exp(2i pi n x/N)`` (x in pixels), ``C(l) = int_0^N P(x) P^*(x + l) dx =
    N sum_n |u_n|^2 exp(-2i pi n l/N)`` (the PSF autocorrelation: Siegert's term) and
    ``D(l) = int_0^N |P(x)|^2 |P(x + l)|^2 dx = N sum_m |c_m|^2 exp(2i pi m l/N)``,
    ``c_m = sum_n u_{n+m} u_n^*`` (the overlap of single-scatterer intensities). As
    ``density -> inf`` it tends to Siegert's ``|gamma|^2``.

    Parameters
    ----------
    weights : array_like
        ``N`` spectral weights ``u_n`` (window-weighted spectrum), ``n = -(N//2) ...``.
    lags : array_like
        Depth lags in pixels (any real values).
    density : float
        Scatterers per pixel (> 0).
    kappa : float
        ``E|a|^4/(E|a|^2)^2`` of the amplitudes (1 for equal amplitudes, 2 for complex Gaussian).
    """
    u = as_finite_array(weights, "weights", dtype=np.complex128)
    lag = as_finite_array(lags, "lags")
    rho = check_real(density, "density", low=0, low_inclusive=False)
    kap = check_real(kappa, "kappa", low=1)
    n = u.size
    idx = np.arange(n) - n // 2
    # integrals over one period x in [0, N) pixels: Parseval for trigonometric polynomials
    c = n * (np.abs(u) ** 2 @ np.exp(-2j * np.pi * np.outer(idx, lag) / n))
    acf = np.correlate(u, u, mode="full")  # c_m for m = -(N-1) ... N-1
    m = np.arange(-(n - 1), n)
    d = n * (np.abs(acf) ** 2 @ np.exp(2j * np.pi * np.outer(m, lag) / n)).real
    c0 = n * np.sum(np.abs(u) ** 2)
    d0 = n * np.sum(np.abs(acf) ** 2)
    return (rho**2 * np.abs(c) ** 2 + rho * kap * d) / (rho**2 * c0**2 + rho * kap * d0)


def _b3(x: np.ndarray) -> np.ndarray:
    """Cubic B-spline ``beta3(x)`` (support ``|x| < 2``)."""
    a = np.abs(x)
    return np.where(a < 1, 2 / 3 - a**2 + a**3 / 2, np.where(a < 2, (2 - a) ** 3 / 6, 0.0))


def interpolation_gain(theta: object, t: object, method: str) -> np.ndarray:
    """Complex gain of the interpolation kernel on a tone: the kernel's closed-form response.

    A tone ``exp(i theta j)`` sampled at the integers (``theta`` rad per input sample) and
    interpolated at ``j0 + t`` (``0 <= t < 1``) gives ``sum_j h(t - j) exp(i theta j)``; divided
    by the true value ``exp(i theta t)`` this is

    * ``"linear"`` (hat kernel): ``H = (1 - t) exp(-i theta t) + t exp(i theta (1 - t))``;
      its mean over ``t`` is the hat's Fourier transform ``sinc^2(theta/2)``;
    * ``"cubic"`` (interpolating cubic spline, the cardinal spline of the not-a-knot spline away
      from the ends): ``H = sum_{j=-1}^{2} beta3(t - j) exp(i theta (j - t)) / ((2 + cos theta)/3)``
      (B-spline weights, divided by the B-spline's response at the samples); its mean over
      ``t`` is ``sinc^4(theta/2) 3/(2 + cos theta)``;
    * ``"exact"``: 1.

    ``sinc x = sin x / x``. ``H = 1`` at ``t = 0`` (both kernels interpolate).

    Parameters
    ----------
    theta : array_like
        Tone phase per input sample, rad.
    t : array_like
        Fractional position of the output point between input samples, in [0, 1]; broadcast
        with ``theta``.
    method : {"linear", "cubic", "exact"}
        The interpolation.

    Returns
    -------
    numpy.ndarray
        Complex gain, the broadcast shape of ``theta`` and ``t``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> complex(speckle.interpolation_gain(np.pi / 4, 0.0, "linear"))  # 1 at the samples
    (1+0j)
    """
    th = as_finite_array(theta, "theta")
    tt = as_finite_array(t, "t")
    check_choice(method, "method", ("linear", "cubic", "exact"))
    if tt.size and (tt.min() < 0 or tt.max() > 1):
        raise ValueError(f"t must lie in [0, 1], got values in [{tt.min():g}, {tt.max():g}]")
    th, tt = np.broadcast_arrays(th, tt)
    if method == "exact":
        return np.ones(th.shape, complex)
    if method == "linear":
        return (1 - tt) * np.exp(-1j * th * tt) + tt * np.exp(1j * th * (1 - tt))
    s = sum(np.exp(1j * th * (j - tt)) * _b3(tt - j) for j in (-1, 0, 1, 2))
    return s / ((2 + np.cos(th)) / 3)


def resampling_error(theta: object, method: str) -> np.ndarray:
    """RMS error of resampling a unit tone, from the interpolation kernel's response.

    ``|H(theta, t) - 1|`` (:func:`interpolation_gain`) in RMS over ``t`` uniform in [0, 1)
    (128-point Gauss-Legendre quadrature). For small ``theta`` it grows as
    ``theta^2/(2 sqrt 30)`` (linear) and ``theta^4`` (cubic): with ``theta = 2 z h`` (``h`` the
    camera step in ``k``), errors grow with depth as ``z^2`` and ``z^4``.
    """
    th = as_finite_array(theta, "theta")[..., None]
    check_choice(method, "method", ("linear", "cubic"))
    x, wq = np.polynomial.legendre.leggauss(128)
    t, wq = (x + 1) / 2, wq / 2
    err2 = np.abs(interpolation_gain(th, t, method) - 1) ** 2
    return np.sqrt(err2 @ wq)
