"""A scanned Gaussian beam as per-line weighted scatterer fields (imaged by :func:`speckle.bscan`).

:func:`speckle.beam_scan` is the exact direct reference for a shared 2-D scene imaged by a
scanned Gaussian beam: line ``i`` is Eq. 4 of the scatterers weighted by the double-pass
amplitude ``exp(-2 (x_j - X_i)^2/w0^2)``. This module builds, for every line, the field of the
scatterers whose weight exceeds ``cutoff`` (default 1e-17, i.e. within ``4.4 w0``) with their
weights folded into the amplitudes, as a ``(aline, scatterer)`` Dataset: any method of
:func:`speckle.ascan` (e.g. the fast ``nufft``) then images the beam scan, and every system
effect that acts on scatterers applies unchanged. Dropped scatterers contribute less than
``cutoff`` times their amplitude each (the tests compare with :func:`speckle.beam_scan`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_int, check_real, check_size
from ..conventions import attrs as labels
from ..conventions import coord

__all__ = ["beam_lines", "shared_scatterers"]


def shared_scatterers(
    n_lines: int,
    pitch: float,
    density: float,
    *,
    n_pixels: int,
    depth_range: float,
    waist: float,
    seed: int,
    margin: float = 4.5,
) -> dict[str, np.ndarray]:
    """Uniform scatterers of unit amplitude in depth ``[0, H)`` and across the scanned lines.

    ``density`` is per pixel (``H/N``) per line pitch; the lateral extent covers the lines plus
    ``margin`` waists either side. Returns ``{"z", "x", "amplitude", "lines"}`` (µm). One
    generator ``SeedSequence(seed)`` draws the whole scene (so ``n_lines`` changes the scene).
    """
    nl = check_int(n_lines, "n_lines", low=1)
    p = check_real(pitch, "pitch", low=0, low_inclusive=False)
    rho = check_real(density, "density", low=0, low_inclusive=False)
    n = check_size(n_pixels, "n_pixels", low=2, bytes_per=64.0)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    sd = check_int(seed, "seed", low=0)
    lines = np.arange(nl) * p
    x0, x1 = -margin * w0, lines[-1] + margin * w0
    count = round(rho * n * (x1 - x0) / p)
    rng = np.random.default_rng(np.random.SeedSequence(sd))
    return {
        "z": rng.uniform(0.0, h, count),
        "x": rng.uniform(x0, x1, count),
        "amplitude": np.ones(count, dtype=complex),
        "lines": lines,
    }


def beam_lines(
    z: object,
    x: object,
    amplitude: object,
    *,
    lines: object,
    waist: float,
    cutoff: float = 1e-17,
    attrs: dict | None = None,
) -> xr.Dataset:
    """Per-line scatterer fields of a scanned Gaussian beam.

    Parameters
    ----------
    z, x, amplitude : array_like, shape (M,)
        Scatterer depths and lateral positions (µm) and amplitudes.
    lines : array_like, shape (L,)
        Lateral positions of the A-lines (µm).
    waist : float
        ``w0``, 1/e^2 intensity radius of the one-way beam (µm, > 0).
    cutoff : float
        Smallest double-pass weight kept (0 < cutoff < 1).
    attrs : dict, optional
        Attributes of the returned scene (e.g. ``depth_range``, ``n_pixels``, ``density``).

    Returns
    -------
    xarray.Dataset
        ``z`` and weighted ``amplitude`` with dims ``(aline, scatterer)`` (lines padded with
        zero-amplitude scatterers), coordinate ``aline`` = ``lines``.
    """
    zz = as_finite_array(z, "z").ravel()
    xx = as_finite_array(x, "x").ravel()
    aa = as_finite_array(amplitude, "amplitude", dtype=np.complex128).ravel()
    xl = as_finite_array(lines, "lines").ravel()
    if not (zz.size == xx.size == aa.size):
        raise ValueError("z, x and amplitude must have the same length")
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    c = check_real(cutoff, "cutoff", low=0, high=1, low_inclusive=False, high_inclusive=False)
    reach = w0 * np.sqrt(-np.log(c) / 2)
    order = np.argsort(xx, kind="stable")
    xs = xx[order]
    bounds = np.searchsorted(xs, np.stack([xl - reach, xl + reach]))
    width = int(np.max(bounds[1] - bounds[0], initial=1))
    zo = np.zeros((xl.size, width))
    ao = np.zeros((xl.size, width), dtype=np.complex128)
    for i, (lo, hi) in enumerate(bounds.T):
        sel = order[lo:hi]
        zo[i, : sel.size] = zz[sel]
        ao[i, : sel.size] = aa[sel] * np.exp(-2 * (xx[sel] - xl[i]) ** 2 / w0**2)
    return xr.Dataset(
        {
            "z": (("aline", "scatterer"), zo, labels("z")),
            "amplitude": (
                ("aline", "scatterer"),
                ao,
                labels("amplitude", "scattering amplitude a_j times the beam weight"),
            ),
        },
        coords={"aline": coord("aline", xl, "lateral position")},
        attrs={**(attrs or {}), "waist": w0, "beam_cutoff": c},
    )
