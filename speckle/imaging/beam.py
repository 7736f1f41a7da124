"""A scanned Gaussian beam over a shared scene: overlapping A-lines.

Every A-line ``i`` of a B-scan is the paper's Eq. 4 with each scatterer weighted by the
double-pass (illumination and collection) amplitude of a Gaussian beam centred on the line,

    A(i, q) = sum_j a_j exp(-2 (x_j - X_i)^2 / w0^2) sum_n S(k_n) exp(2i k_n z_j) exp(-2i pi n q/N),

with ``w0`` the 1/e^2 intensity radius of the one-way beam at focus (so the one-way amplitude is
``exp(-r^2/w0^2)`` and the double-pass amplitude ``exp(-2 r^2/w0^2)``). Scatterers belong to no
A-line: neighbouring lines closer than ``w0`` see the same scatterers and are correlated. For a
dense uniform scene the complex correlation of lines ``dx`` apart is ``exp(-dx^2/w0^2)``.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_finite_array, check_real
from .aline import ascan

__all__ = ["beam_scan"]

#: Double-pass weights below this are exactly zero in float64 (exp(-745) underflows).
_UNDERFLOW = 745.2


def beam_scan(
    z: object,
    x: object,
    amplitude: object,
    *,
    lines: object,
    waist: float,
    n_pixels: int,
    depth: float,
    k0: float,
    spectrum: object | None = None,
    method: str = "direct",
    tol: float | None = None,
) -> np.ndarray:
    """Complex B-scan of a shared 2-D scene imaged by a scanned Gaussian beam.

    Parameters
    ----------
    z, x : array_like, shape (M,)
        Scatterer depths and lateral positions in µm.
    amplitude : array_like, shape (M,)
        Real or complex scattering amplitudes.
    lines : array_like, shape (L,)
        Lateral positions ``X_i`` of the A-lines in µm.
    waist : float
        Beam waist ``w0`` (1/e^2 intensity radius of the one-way beam at focus) in µm, > 0.
    n_pixels, depth, k0, spectrum
        As in :func:`speckle.ascan` (pixels, unambiguous depth ``H`` in µm, central wavenumber
        in rad/µm, spectral weights); same grid, wrap-around and pixel conventions.
    method : str
        ``"direct"``: the exact float64 reference (each line is :func:`speckle.ascan` of the
        scatterers whose weight does not underflow to zero).
    tol : float, optional
        Requested relative l2 accuracy for approximate methods.

    Returns
    -------
    numpy.ndarray
        Complex128, shape ``(L, n_pixels)``; no normalisation.
    """
    zz = as_finite_array(z, "z")
    xx = as_finite_array(x, "x")
    aa = as_finite_array(amplitude, "amplitude", dtype=np.complex128)
    xl = as_finite_array(lines, "lines")
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    for name, arr in (("z", zz), ("x", xx), ("amplitude", aa), ("lines", xl)):
        if arr.ndim != 1:
            raise ValueError(f"{name} must be 1-D, got shape {arr.shape}")
    if not (zz.shape == xx.shape == aa.shape):
        raise ValueError(
            f"z, x and amplitude must have the same shape (M,), got {zz.shape}, {xx.shape}, "
            f"{aa.shape}"
        )
    if method != "direct":
        raise ValueError(f"method must be 'direct', got {method!r}")
    out = np.empty((xl.size, int(n_pixels)), dtype=np.complex128)
    reach = w0 * np.sqrt(_UNDERFLOW / 2)
    order = np.argsort(xx, kind="stable")
    xs = xx[order]
    for i, xi in enumerate(xl):
        lo, hi = np.searchsorted(xs, [xi - reach, xi + reach])
        sel = order[lo:hi]
        weight = np.exp(-2 * (xx[sel] - xi) ** 2 / w0**2)
        out[i] = ascan(
            zz[sel] if sel.size else np.zeros(1),
            aa[sel] * weight if sel.size else np.zeros(1),
            n_pixels=n_pixels,
            depth=depth,
            k0=k0,
            spectrum=spectrum,
        )
    return out
