"""Carrier phase ``exp(2i k0 z)`` and wrapped scatterer positions, shared by the fast methods.

Every fast synthesis method needs, for each scatterer ``j``, the complex strength
``c_j = a_j exp(2i k0 z_j)`` and the position of ``z_j`` on the periodic pixel (or fine) grid,
``u_j = frac(z_j/H) * G`` for a grid of ``G`` points over one unambiguous depth ``H`` (µm).

Accuracy (the float32 failure mode)
-----------------------------------
The carrier phase ``2 k0 z`` is large: with ``k0/delta_k = 10`` and 8 µm pixels,
``2 k0 H ~ 2e4`` rad at the bottom of a 1024-pixel A-line. A float32 phase has a spacing
(ulp) of ``2e4 * 2**-23 ~ 2e-3`` rad there, so a *naive* float32 evaluation
``exp(1j * float32(2 k0) * float32(z))`` carries a phase error ~``eps32 * 2 k0 z`` that grows
linearly with depth and with ``k0`` and reaches 1e-3 relative -- far above a 1e-6 tolerance
(see :func:`naive_float32_phase_error` and the failure map). Here the phase is reduced modulo
``2 pi`` in float64 (Cody-Waite, three-term ``2 pi``) *before* any cast, so the reduced phase lies
in ``[-pi, pi]`` and a float32 cast of ``exp(i phase)`` costs only ``eps32/2`` whatever ``k0 z``.

``exp(i phase)`` is evaluated with a branch-free polynomial (Taylor to degree 17 at a quarter
of the phase, then squared twice, relative error < 1e-15) so that numba vectorises the loop;
numba has no vectorised ``sin``/``cos`` without SVML.
"""

from __future__ import annotations

import math

import numpy as np

from ...system.source import spectral_index
from ._kernels import C2, INV_TWO_PI, carrier_and_position

__all__ = [
    "MAX_CARRIER_TURNS",
    "carrier_and_position",
    "float64_error_estimate",
    "naive_float32_phase_error",
    "naive_float32_phase_error_estimate",
]

_EPS64 = float(np.finfo(np.float64).eps)
#: Largest carrier phase ``|2 k0 z|`` in turns (units of 2 pi) that the float64 reduction of
#: :func:`carrier_and_position` handles with the error of :func:`float64_error_estimate`
#: (``n * C1`` is exact for ``n < 2**45``).
MAX_CARRIER_TURNS = 2.0**45


def float64_error_estimate(
    z: np.ndarray, amplitude: np.ndarray, depth_range: float, k0: float, spectrum: np.ndarray
) -> float:
    """Expected relative error of :func:`carrier_and_position` against the direct method.

    The fast methods (``nufft``, ``nufft32``, ``psf``) place scatterer ``j`` at
    ``f_j = frac(z_j/H)`` computed as ``z_j * (1/H)``: two float64 roundings of relative size
    ``eps/2`` leave an absolute error of rms ``eps |z_j|/(H sqrt(6))`` in ``f_j`` (the direct
    method reduces ``z mod H`` exactly). Spectral component ``n`` then carries a phase error
    ``2 pi n df``, i.e. a relative field error ``2 pi n_rms df`` with
    ``n_rms^2 = sum n^2 S_n^2 / sum S_n^2``. The carrier phase ``2 k0 z`` is reduced modulo
    ``2 pi`` with a three-term constant: the rounding of ``m * C2`` (``m`` turns) adds an rms
    phase error ``eps/(2 sqrt 3) |m C2|``. Both grow with depth; summed in quadrature over
    scatterers weighted by ``|a|^2``:

        e^2 = (2 pi n_rms eps z_rms / (sqrt(6) H))^2 + (eps z_rms 2 k0 C2 / (4 pi sqrt 3))^2,

    ``z_rms^2 = sum |a|^2 z^2 / sum |a|^2`` (µm). It is ~1e-14 for scatterers within a few
    ``H`` and reaches 1e-2 at ``|z| ~ 1e15`` µm (``H`` ~ 2 mm, ``N`` = 256): then no
    tolerance of interest holds. Beyond :data:`MAX_CARRIER_TURNS` the reduction itself is
    inexact and the estimate is ``inf``.

    Parameters
    ----------
    z, amplitude : numpy.ndarray
        Depths (µm) and amplitudes of the scatterers (same shape).
    depth_range : float
        Unambiguous depth ``H`` in µm.
    k0 : float
        Central wavenumber in rad/µm.
    spectrum : numpy.ndarray
        ``N`` spectral weights.
    """
    w = np.abs(np.asarray(amplitude))
    peak = float(np.max(w, initial=0.0))
    if peak == 0.0:
        return 0.0
    w = (w / peak) ** 2  # scaled: no overflow for huge amplitudes
    total = float(np.sum(w))
    zz = np.asarray(z, dtype=float)
    if 2.0 * k0 * float(np.max(np.abs(zz))) * INV_TWO_PI >= MAX_CARRIER_TURNS:
        return math.inf
    z_rms = math.sqrt(float(np.sum(w * zz**2)) / total)
    s = np.asarray(spectrum, dtype=float)
    n = spectral_index(s.size)
    n_rms = math.sqrt(float(np.sum(n**2 * s**2)) / float(np.sum(s**2)))
    position = 2.0 * math.pi * n_rms * _EPS64 * z_rms / (math.sqrt(6.0) * depth_range)
    carrier = _EPS64 * z_rms * 2.0 * k0 * C2 / (4.0 * math.pi * math.sqrt(3.0))
    return math.hypot(position, carrier)


def naive_float32_phase_error(z: np.ndarray, k0: float) -> float:
    """RMS error of ``exp(2i k0 z)`` evaluated naively in float32 (no float64 reduction).

    This is the failure mode the fast methods avoid: the float32 product ``2 k0 z`` is off by
    up to half an ulp of ``2 k0 z`` (~``eps32 * k0 z``), and the error passes unchanged into the
    carrier phase. Returns ``sqrt(mean |e32 - e64|^2)`` over ``z`` (µm), which is the relative
    field error of a scene of equal-amplitude scatterers.
    """
    z = np.asarray(z, dtype=float)
    exact = np.exp(2j * k0 * z)
    naive = np.exp(1j * (np.float32(2 * k0) * z.astype(np.float32))).astype(np.complex128)
    return float(np.sqrt(np.mean(np.abs(naive - exact) ** 2)))


def naive_float32_phase_error_estimate(z: np.ndarray, k0: float) -> float:
    """Predicted :func:`naive_float32_phase_error`, from float32 spacings (no synthesis).

    Rounding to nearest leaves an error uniform over one spacing ``ulp`` (rms ``ulp/sqrt(12)``):
    in ``z`` (times ``2 k0``), in the product ``2 k0 z``, plus the fixed relative rounding
    ``d`` of ``2 k0`` itself (a phase error ``2 k0 z d`` growing with depth). For small phase
    errors ``|exp(i e) - 1| ~ |e|``, so the field error is the rms phase error.
    """
    z = np.abs(np.asarray(z, dtype=float))
    two_k0 = 2.0 * float(k0)
    d = (float(np.float32(two_k0)) - two_k0) / two_k0 if two_k0 else 0.0
    ulp_z = np.spacing(z.astype(np.float32)).astype(float)
    ulp_ph = np.spacing((two_k0 * z).astype(np.float32)).astype(float)
    var = (two_k0 * ulp_z) ** 2 / 12 + ulp_ph**2 / 12 + (two_k0 * z * d) ** 2
    return float(np.sqrt(np.mean(var)))
