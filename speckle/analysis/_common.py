"""Helpers shared by the analysis modules (private): the field of a B-scan, grid checks, the one
window parser and the pixel spacing read from coordinates.

``window`` means the same in every analysis function: an int ``w`` is a square window
``(w, w)`` of (depth, x) pixels, a pair is ``(depth, x)`` pixels.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import check_int, check_real
from .._wrap import check_same_grid
from ..conventions import attrs, spacing

__all__ = [
    "DEPTH",
    "LATERAL",
    "delay_selection",
    "depth_major",
    "grid_spacing",
    "label_looks",
    "matched",
    "parse_window",
    "same_grid",
]


#: The image dims of the analysis modules (issue 32: the lateral dim of every image is ``x``;
#: ``aline`` is accepted for one release through :func:`speckle.conventions.canonical_dims`).
DEPTH, LATERAL = "depth", "x"


def depth_major(image: object) -> np.ndarray:
    """A (depth, x) image as complex128 with depth the contiguous axis (the layout the
    kernels of :mod:`speckle.analysis._kernels` read fastest; no copy when it already is)."""
    a = np.asarray(image)
    if a.flags.f_contiguous and a.dtype == np.complex128:
        return a
    return np.asfortranarray(a, dtype=np.complex128)


def same_grid(x: xr.DataArray, y: xr.DataArray, names: tuple[str, str]) -> None:
    """``ValueError`` unless every dim ``x`` and ``y`` share has the same size and coordinates
    (:func:`speckle._wrap.check_same_grid`, the decorator's check)."""
    check_same_grid(x, y, names)


def matched(x: xr.DataArray, y: xr.DataArray) -> tuple[xr.DataArray, xr.DataArray]:
    """Broadcast two images after checking they cover the same pixels (else ``ValueError``).

    Both must have ``depth`` and ``x`` dims; every dim they share must have the same size
    and the same coordinate values. Nothing is aligned, padded or cut silently. A ``time`` dim
    (an image series, :mod:`speckle.imaging.timeseries`) in one input only is refused: it
    would broadcast one image against every frame.
    """
    timed = [n for n, f in (("reference", x), ("deformed", y)) if "time" in f.dims]
    if len(timed) == 1:
        raise ValueError(
            f"a 'time' dim in {timed[0]} only: give both as series on the same times, or "
            "select one frame of the series (.isel(time=i))"
        )
    for name, f in (("reference", x), ("deformed", y)):
        missing = [d for d in ("depth", "x") if d not in f.dims]
        if missing:
            raise ValueError(f"{name} must have dims 'depth' and 'x'; got dims {f.dims}")
    same_grid(x, y, ("reference", "deformed"))
    return xr.broadcast(x, y)


def parse_window(
    window: object,
    name: str = "window",
    *,
    low: int = 2,
    shape: tuple[int, int] | None = None,
) -> tuple[int, int]:
    """``(depth, x)`` pixel counts from an int (square window) or a pair.

    Parameters
    ----------
    window : int or (int, int)
        An int ``w`` means ``(w, w)``; a pair means ``(depth, x)`` pixels.
    name : str
        Parameter name used in error messages.
    low : int
        Smallest depth size (aline: 1).
    shape : (int, int), optional
        Image shape ``(depth, x)``: a window larger than it is refused.

    Raises
    ------
    TypeError, ValueError
        Not an int or a pair of ints, below ``low``, or larger than ``shape``.
    """
    if isinstance(window, (str, bytes)):
        raise TypeError(f"{name} must be an int or (depth, x) pixels, got {window!r}")
    w = np.atleast_1d(np.asarray(window, dtype=object))
    if w.ndim != 1 or w.size not in (1, 2):
        raise ValueError(f"{name} must be an int or (depth, x) pixels, got {window!r}")
    if w.size == 1:
        w = np.repeat(w, 2)
    out = (check_int(w[0], f"{name}[depth]", low=low), check_int(w[1], f"{name}[x]", low=1))
    if shape is not None and (out[0] > shape[0] or out[1] > shape[1]):
        raise ValueError(
            f"{name} {out} (depth, x) is larger than the image {tuple(shape)}; {name} must "
            f"be at most {tuple(shape)} pixels"
        )
    return out


def grid_spacing(field: xr.DataArray | xr.Dataset) -> tuple[float, float]:
    """Pixel size and A-line pitch (µm) read from the ``depth`` and ``x`` coordinates.

    Spacing comes only from coordinates (:func:`speckle.conventions.spacing`); with a single
    A-line the pitch defaults to the pixel size.
    """
    dz = spacing(field, "depth")
    return dz, spacing(field, LATERAL, default=dz)


def delay_selection(t: np.ndarray, delays: object) -> np.ndarray:
    """Lags ``t`` (s) within the delay range ``delays = (tau1, tau2)`` (s); at least two.

    The fit range of the correlation decay speed (:func:`speckle.analysis.dynamics.ocds`
    and its expected value).
    """
    if isinstance(delays, str) or not hasattr(delays, "__len__") or len(delays) != 2:
        raise ValueError(f"delays must be (tau1, tau2) in s, got {delays!r}")
    lo = check_real(delays[0], "delays[0]", low=0)
    hi = check_real(delays[1], "delays[1]", low=lo, low_inclusive=False)
    eps = 1e-9 * hi
    sel = (t >= lo - eps) & (t <= hi + eps)
    if sel.sum() < 2:
        raise ValueError(
            f"delays ({lo:g}, {hi:g}) s hold {int(sel.sum())} lag(s) of the series: OCDS fits a "
            "line through at least two"
        )
    return sel


def label_looks(looks: xr.DataArray, kind: str, **extra: object) -> xr.DataArray:
    """Looks (dim ``look``) numbered, named ``looks`` and labelled as complex ``kind`` looks."""
    return (
        looks.assign_coords(look=np.arange(looks.sizes["look"]))
        .rename("looks")
        .assign_attrs(attrs("field", f"complex {kind} looks", compounding=kind, **extra))
    )
