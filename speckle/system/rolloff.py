"""Sensitivity roll-off of an SD-OCT spectrometer: closed forms (µm, rad/µm).

A camera pixel of width ``w`` in ``k`` averages the carrier ``exp(2ikd)`` of a path difference
``d`` into ``exp(2i k_c d) sinc(w d)`` (``sinc x = sin x/x``), a Gaussian spectrometer line of
FWHM ``r`` in ``k`` into ``exp(-(r d)^2/(4 ln2))`` (its characteristic function). Kept apart from
:mod:`speckle.system.spectrometer` so that :mod:`speckle.system.datasheet` (and the pipeline's
source configuration) need not import the whole chain.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_finite_array, check_real

__all__ = ["carrier_response", "rolloff"]


def carrier_response(distance: object, pixel_width: object = 0.0, resolution: object = 0.0):
    """Pixel and spectrometer-line average of the carrier ``exp(2ikd)``, divided by it.

    ``g(d) = sinc(w d) exp(-(r d)^2/(4 ln2))`` with ``sinc x = sin x/x``: the mean of
    ``exp(2i kappa d)`` over a box of width ``w`` and over a Gaussian of FWHM ``r`` in ``kappa``.

    Parameters
    ----------
    distance : array_like
        Path difference ``d`` in µm (medium), one way.
    pixel_width, resolution : array_like
        Pixel width ``w`` and spectrometer-line FWHM ``r`` in rad/µm (>= 0), broadcast with
        ``distance``.
    """
    d = np.asarray(distance, dtype=float)
    w = np.asarray(pixel_width, dtype=float)
    r = np.asarray(resolution, dtype=float)
    return np.sinc(w * d / np.pi) * np.exp(-((r * d) ** 2) / (4 * np.log(2)))


def rolloff(depth: object, pixel_width: float, resolution: float = 0.0) -> np.ndarray:
    """Power roll-off of a point reflector, ``sinc^2(w z) exp(-(r z)^2/(2 ln2))`` (linear).

    With ``w = pi/(2 z_max)`` (100 % fill at ``lambda0``) and ``r = omega w`` (``omega`` the
    spectrometer FWHM over the wavelength step) this is Yun et al. (Opt. Express 11, 3598,
    2003): ``sinc^2(zeta) exp(-omega^2 zeta^2/(2 ln2))``, ``zeta = pi z/(2 z_max)``.

    Parameters
    ----------
    depth : array_like
        Depth ``z`` of the reflector from the zero delay, µm (medium).
    pixel_width : float
        Camera pixel width in ``k``, rad/µm (>= 0).
    resolution : float
        FWHM of the spectrometer line in ``k``, rad/µm (>= 0).
    """
    z = as_finite_array(depth, "depth")
    w = check_real(pixel_width, "pixel_width", low=0)
    r = check_real(resolution, "resolution", low=0)
    return carrier_response(z, w, r) ** 2
