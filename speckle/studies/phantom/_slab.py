"""The slab's integrals of the scanner's double-pass weight (private): ``slab_constants``, the
depth PSF on a fine grid (``depth_psf``) and the speckle's correlation area (``speckle_cell``)."""

from __future__ import annotations

import math

import numpy as np
from scipy import special

from ...synthoct import _scan

__all__ = ["ERF2", "depth_psf", "slab_constants", "speckle_cell"]

#: ``erf(sqrt 2)``: the slab ``|y| <= r``'s cut of the beam's ``W^2``.
ERF2 = special.erf(math.sqrt(2.0))


def slab_constants(radius: float) -> dict[str, float]:
    """Integrals of the double-pass weight over a slab ``|y| <= r``, infinite in ``x`` (µm^2).

    ``A2 = int W^2 = (pi r^2/2) erf(sqrt 2)`` (``mu = rho (E/100) A2``), ``A4 = int W^4 = (pi
    r^2/4) erf(2)``, ``a2_y = int_{-r}^{r} exp(-2 y^2/r^2) dy`` and the kurtosis-equivalent
    thickness ``t_eq = a2_y^2 / int exp(-4 y^2/r^2) dy = r sqrt(pi) erf(sqrt 2)^2/erf(2)``.
    """
    r = float(radius)
    a2y = r * math.sqrt(math.pi / 2) * ERF2
    a4y = r * math.sqrt(math.pi) / 2 * special.erf(2.0)
    return {
        "A2": a2y * r * math.sqrt(math.pi / 2),
        "A4": a4y * r * math.sqrt(math.pi) / 2,
        "a2_y": a2y,
        "t_eq": a2y**2 / a4y,
    }


def depth_psf(n_pixels: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The scanner's depth intensity PSF ``|sum_n S_n exp(-2 pi i n u/N)|^2`` (Eq. 4, the Hann
    spectrum ``S``) on the midpoints ``u`` of a grid of ``1/samples`` pixel over the main lobe
    and 15 side lobes each way (``|u| < 16`` pixels): returns ``(u, w)``."""
    spectrum = _scan.hann_spectrum(n_pixels)
    orders = np.arange(n_pixels) - n_pixels // 2
    u = (np.arange(-16 * samples, 16 * samples) + 0.5) / samples
    return u, np.abs(np.exp(-2j * np.pi * np.outer(u, orders) / n_pixels) @ spectrum) ** 2


def speckle_cell(n_pixels: int, radius: float, pitch: float) -> float:
    """The intensity's correlation area in pixels x lines: the sum of its correlation
    coefficient over every lag, so that a mean over ``n`` pixels has the variance of ``n /
    speckle_cell`` independent ones (fully developed speckle).

    Along depth the field's autocorrelation is ``sum_n S_n^2 exp(-2 pi i n d/N)`` (Eq. 4), and
    by Parseval the intensity's ``sum_d |rho(d)|^2 = N sum S^4/(sum S^2)^2`` (35/18 pixels for
    the Hann spectrum); across lines ``d`` apart (amplitude ``exp(-x^2/r^2)``) it is
    ``exp(-d^2/r^2)``, summed over the lines' lags (``r sqrt(pi)/pitch`` when ``r >> pitch``).
    """
    s2 = _scan.hann_spectrum(n_pixels) ** 2
    along = n_pixels * float(np.sum(s2**2)) / float(np.sum(s2)) ** 2
    lags = np.arange(-math.ceil(6 * radius / pitch), math.ceil(6 * radius / pitch) + 1)
    return along * float(np.sum(np.exp(-((lags * pitch / radius) ** 2))))
