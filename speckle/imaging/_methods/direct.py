"""The exact float64 references: Eq. 4 by explicit phase factors, for A-lines and for a beam.

:func:`direct_method` is ``ascan(..., method="direct")`` and :func:`beam_direct_method` is
``beam_scan(..., method="direct")`` on validated arrays (the method tables of
:mod:`speckle.imaging.methods`); every fast method is tested against them.
"""

from __future__ import annotations

import numpy as np

from ...system.source import index_shift_phase, spectral_index
from ..gaussian_beam import Beam, BeamScene

__all__ = [
    "DIRECT_CHUNK_ELEMENTS",
    "beam_direct_method",
    "direct_method",
    "spectral_field_to_pixels",
]

#: Largest number of complex phase factors the direct method holds in memory at once.
DIRECT_CHUNK_ELEMENTS = 1 << 22
#: Double-pass weights below ``exp(-_UNDERFLOW)`` are exactly zero in float64.
_UNDERFLOW = 745.2


def spectral_field_to_pixels(field: np.ndarray, n_pixels: int) -> np.ndarray:
    """Sum spectral components into pixels: ``A(q) = sum_n F_n exp(-2i pi n q/N)``.

    ``field`` has shape (..., N) ordered ``n = -(N//2) ... N-1-(N//2)``. The sum over ``n`` is an
    exact DFT evaluated with an FFT (rounding error ~1e-16 relative).
    """
    return np.fft.fft(field, axis=-1) * index_shift_phase(n_pixels, np.arange(n_pixels))


def direct_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """Exact float64 double sum: spectral field by explicit phase factors, then an exact DFT.

    ``z`` float64 and ``amplitude`` complex128 of shape (B, M), ``spectrum`` the ``N`` weights;
    ``tol`` is ignored (exact up to rounding). Returns complex128 (B, N).
    """
    del tol  # exact up to rounding whatever tol asks
    batch, m = z.shape
    n_idx = spectral_index(n_pixels).astype(float)
    field = np.empty((batch, n_pixels), dtype=np.complex128)
    # Split the k0 phase from the spectral phase: 2 k_n z = 2 k0 z + 2 pi n z / H, and the
    # second factor is H-periodic in z, so z mod H keeps its argument small and accurate.
    carrier = amplitude * np.exp(2j * k0 * z)
    zr = np.mod(z, depth_range) * (2 * np.pi / depth_range)
    step = max(1, DIRECT_CHUNK_ELEMENTS // max(1, m * n_pixels))
    for b0 in range(0, batch, step):
        sl = slice(b0, b0 + step)
        phase = np.exp(1j * zr[sl, :, None] * n_idx)  # (b, M, N)
        field[sl] = np.einsum("bm,bmn->bn", carrier[sl], phase)
    return spectral_field_to_pixels(field * spectrum, n_pixels)


def beam_direct_method(scene: BeamScene, beam: Beam, tol: float | None) -> np.ndarray:
    """Exact reference of a scanned beam: each line is :func:`direct_method` of its weighted
    scatterers (those whose weight underflows to zero are skipped). Returns complex128 (L, N)."""
    del tol
    w0 = beam.waist
    gam = beam.gamma(scene.z)
    # widest beam over the scene: lateral reach beyond which every weight underflows
    wmax = w0 if gam is None else w0 / np.sqrt(np.min(gam.real))
    reach = wmax * np.sqrt(_UNDERFLOW / 2)
    lines = scene.lines if scene.lines.ndim == 2 else scene.lines[:, None]
    out = np.empty((lines.shape[0], scene.n_pixels), dtype=np.complex128)
    order = np.argsort(scene.x, kind="stable")
    xs = scene.x[order]
    for i, line in enumerate(lines):
        lo, hi = np.searchsorted(xs, [line[0] - reach, line[0] + reach])
        sel = order[lo:hi]
        r2 = (scene.x[sel] - line[0]) ** 2
        if scene.y is not None:
            r2 = r2 + (scene.y[sel] - line[1]) ** 2
            near = r2 < reach**2  # the other weights underflow to exactly zero
            sel, r2 = sel[near], r2[near]
        if gam is None:
            weight = np.exp(-2 * r2 / w0**2)
        else:
            g = gam[sel]
            weight = g**2 * np.exp(-2 * g * r2 / w0**2)
        out[i] = 0.0
        # scatterers in chunks: the direct sum holds (scatterers x pixels) phase factors
        step = max(1, DIRECT_CHUNK_ELEMENTS // scene.n_pixels)
        for c0 in range(0, sel.size, step):
            part = slice(c0, c0 + step)
            out[i] += direct_method(
                np.ascontiguousarray(scene.z[sel[part]])[None, :],
                np.ascontiguousarray(scene.amplitude[sel[part]] * weight[part])[None, :],
                scene.n_pixels,
                scene.depth_range,
                scene.k0,
                scene.spectrum,
                None,
            )[0]
    return out
