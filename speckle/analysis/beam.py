"""Correlation theory of a scanned Gaussian beam over a shared scene.

A scatterer at lateral offset ``u`` from line ``X`` and depth offset ``v`` pixels contributes
``a exp(2i k0 z) w(u) P(v)`` with ``w(u) = exp(-2 u^2/w0^2)`` (double pass) and
``P(v) = sum_n S_n exp(2i pi n v/N)``. For a Poisson scene of number density ``rho`` (µm^-2),
amplitude moments ``E|a|^2 = 1``, ``E|a|^4 = kappa``, depths uniform over one period ``[0, H)``
(the carrier averages the non-conjugate moments to zero), Campbell's theorem gives for two
lines ``dx`` apart

    E[A1 A2*] = rho Wx(dx) Az,                 Wx(dx) = int w(u) w(u - dx) du
                                                      = (sqrt(pi)/2) w0 exp(-dx^2/w0^2),
    Cov(I1, I2) = |E[A1 A2*]|^2 + rho kappa W4(dx) A4,
                                                W4(dx) = int w^2(u) w^2(u - dx) du
                                                       = sqrt(pi/8) w0 exp(-2 dx^2/w0^2),

with the axial integrals over one period ``Az = p N sum S_n^2`` and
``A4 = p N sum_m c_m^2`` (``c`` the autocorrelation of ``S``, ``p = H/N``). So the complex
correlation is exactly ``exp(-dx^2/w0^2)`` and the intensity correlation is its square plus
the finite-density term (which vanishes as ``rho -> inf``).

Lateral Poisson expansion ``x -> a x + b`` (``a = 1 + nu s``) seen by a fixed line ``X``
multiplies the complex correlation by ``sqrt(2a/(1 + a^2)) exp(-2 d^2/(w0^2 (1 + a^2)))``,
``d = nu s (X - x_centre)`` the lateral displacement under the line; it multiplies the axial
factor (the kernel is separable).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, coord

__all__ = ["axial_correlation", "lateral_correlation", "poisson_lateral_factor"]


#: Spectral weights S_n: real, finite, 1-D (a spectrum DataArray also gives its pixel size).
_WEIGHTS = ArraySpec(kind="real", ndim=1)


def _axial_integrals(s: np.ndarray, pixel_size: float) -> tuple[float, float]:
    n = s.size
    c = np.correlate(s, s, mode="full")
    return pixel_size * n * float(np.sum(s**2)), pixel_size * n * float(np.sum(c**2))


@preprocess_and_wrap(
    checks={"dx": ArraySpec(kind="real"), "spectrum": dataclasses.replace(_WEIGHTS, optional=True)},
    from_grid={"pixel_size": "spectrum"},
)
def lateral_correlation(
    dx: object,
    waist: float,
    *,
    density: float | None = None,
    spectrum: object | None = None,
    pixel_size: float | None = None,
    kurtosis: float = 2.0,
) -> xr.Dataset:
    """Expected correlation of two beam lines ``dx`` µm apart (module docstring).

    Parameters
    ----------
    dx : array_like
        Line separations in µm.
    waist : float
        Beam waist ``w0`` in µm (> 0).
    density : float, optional
        Scatterer number density in µm^-2; ``None``: the dense (Gaussian speckle) limit.
    spectrum : array_like, optional
        Spectral weights ``S_n`` (needed with ``density``); a spectrum DataArray
        (:func:`speckle.spectrum`) also gives ``pixel_size``.
    pixel_size : float, optional
        ``H/N`` in µm (needed with ``density``; read from a spectrum DataArray, a value given
        as well must agree with it).
    kurtosis : float
        ``E|a|^4/(E|a|^2)^2`` of the amplitudes (2 for Rayleigh, 1 for equal), >= 1.

    Returns
    -------
    xarray.Dataset
        ``complex`` (``exp(-dx^2/w0^2)``) and ``intensity`` over dim ``lag`` (µm).
    """
    d = np.atleast_1d(dx).astype(float)  # checked: real, finite
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    kappa = check_real(kurtosis, "kurtosis", low=1.0)
    gamma = np.exp(-(d**2) / w0**2)
    if density is None:
        intensity = gamma**2
    else:
        rho = check_real(density, "density", low=0, low_inclusive=False)
        if spectrum is None or pixel_size is None:
            raise ValueError("density needs spectrum and pixel_size (µm) for the axial integrals")
        p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
        az, a4 = _axial_integrals(spectrum, p)
        wx0 = np.sqrt(np.pi) / 2 * w0
        w40 = np.sqrt(np.pi / 8) * w0
        c = rho * wx0 * az
        var = c**2 + rho * kappa * w40 * a4
        intensity = ((c * gamma) ** 2 + rho * kappa * w40 * np.exp(-2 * d**2 / w0**2) * a4) / var
    lag = coord("length", d, "line separation", dims="lag")
    return xr.Dataset(
        {
            "complex": ("lag", gamma, attrs("correlation", "complex correlation")),
            "intensity": ("lag", intensity, attrs("correlation", "intensity correlation")),
        },
        coords={"lag": lag},
        attrs={"waist": w0, "density": np.nan if density is None else float(density)},
    )


@preprocess_and_wrap(
    checks={"lags": ArraySpec(kind="real"), "spectrum": _WEIGHTS},
    from_grid={"pixel_size": "spectrum"},
)
def axial_correlation(
    lags: object,
    spectrum: object,
    *,
    density: float,
    pixel_size: float | None = None,
    waist: float | None = None,
    kurtosis: float = 2.0,
) -> xr.Dataset:
    """Expected correlation of pixels ``lag`` apart in depth along one line (pooled).

    With ``g_d = sum_n S_n^2 exp(2i pi n d/N)`` and ``h_d = sum_m c_m^2 exp(2i pi m d/N)``
    (``c`` the autocorrelation of ``S``), Campbell's theorem gives the complex correlation
    ``|g_d|/g_0`` and the intensity correlation
    ``(rho^2 W2^2 p^2 N^2 |g_d|^2 + rho kappa W4 p N h_d) / (same at d = 0)``, with the
    lateral integrals ``W2 = (sqrt(pi)/2) w0``, ``W4 = sqrt(pi/8) w0`` of a beam of waist
    ``w0`` (density in µm^-2) or ``W2 = W4 = 1`` for the paper's independent lines
    (``waist=None``, density in scatterers per µm of line, i.e. per pixel / ``pixel_size``).

    Parameters
    ----------
    lags : array_like
        Depth lags in pixels (integers or not).
    spectrum : array_like
        Spectral weights ``S_n``; a spectrum DataArray (:func:`speckle.spectrum`) also gives
        ``pixel_size``.
    density : float
        Scatterers per µm^2 (beam) or per pixel (independent lines), > 0.
    pixel_size : float, optional
        ``H/N`` in µm; read from a spectrum DataArray (a value given as well must agree), else
        required.
    waist : float, optional
        Beam waist in µm; ``None``: independent lines.
    kurtosis : float
        ``E|a|^4/(E|a|^2)^2``, >= 1.

    Returns
    -------
    xarray.Dataset
        ``complex`` and ``intensity`` over dim ``lag`` (pixels).
    """
    d = np.atleast_1d(lags).astype(float)  # checked: real, finite
    s = spectrum  # checked: real, finite, 1-D
    rho = check_real(density, "density", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    kappa = check_real(kurtosis, "kurtosis", low=1.0)
    n = s.size
    idx = np.arange(n) - n // 2
    c = np.correlate(s, s, mode="full")
    m = np.arange(-(n - 1), n)
    g = np.abs(np.exp(2j * np.pi * np.outer(d, idx) / n) @ (s**2))
    h = (np.exp(2j * np.pi * np.outer(d, m) / n) @ (c**2)).real
    if waist is None:
        w2, w4, rho = 1.0, 1.0, rho / p
    else:
        w0 = check_real(waist, "waist", low=0, low_inclusive=False)
        w2, w4 = np.sqrt(np.pi) / 2 * w0, np.sqrt(np.pi / 8) * w0
    g0, h0 = float(np.sum(s**2)), float(np.sum(c**2))
    scale = (rho * w2 * p * n) ** 2
    incoh = rho * kappa * w4 * p * n
    intensity = (scale * g**2 + incoh * h) / (scale * g0**2 + incoh * h0)
    lag = coord("lag", d, "depth lag (pixels)")
    return xr.Dataset(
        {
            "complex": ("lag", g / g0, attrs("correlation", "complex correlation")),
            "intensity": ("lag", intensity, attrs("correlation", "intensity correlation")),
        },
        coords={"lag": lag},
    )


@preprocess_and_wrap(checks={"strain": ArraySpec(kind="real"), "lines": ArraySpec(kind="real")})
def poisson_lateral_factor(
    strain: object, poisson_ratio: float, lines: object, x_centre: float, waist: float
) -> np.ndarray:
    """Complex-correlation factor of lateral Poisson expansion for each line and strain.

    Returns an array ``(strain, line)``: ``sqrt(2a/(1+a^2)) exp(-2 d^2/(w0^2 (1+a^2)))`` with
    ``a = 1 + nu s``, ``d = nu s (X - x_centre)`` (µm).
    """
    s = np.atleast_1d(as_finite_array(strain, "strain"))[:, None]
    nu = check_real(poisson_ratio, "poisson_ratio", low=0.0, high=0.5)
    x = np.atleast_1d(as_finite_array(lines, "lines"))[None, :]
    xc = check_real(x_centre, "x_centre")
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    a = 1.0 + nu * s
    d = nu * s * (x - xc)
    return np.sqrt(2 * a / (1 + a**2)) * np.exp(-2 * d**2 / (w0**2 * (1 + a**2)))
