"""Pooled contrasts of a series, in memory or lazily on Dask chunks (private).

The engine of :mod:`speckle.analysis.dynamics`: a contrast is ``finish(pool(moments))`` --
per-pixel time statistics (``moments``: block-local once the time dim is whole in each
chunk), pooled over every pixel or by a boxcar (:func:`pool`), then finished pixel by pixel
(:func:`pooled_contrast`). Dask arrays are never imported here: the user's data brings them
(:func:`is_dask`).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.ndimage as ndi
import xarray as xr

from .._validate import check_int
from ._common import parse_window

__all__ = [
    "checked_series",
    "decibels",
    "frame_lags",
    "is_dask",
    "no_answer",
    "pool",
    "pooled_contrast",
    "ratio",
    "series_values",
    "spatial_window",
]


def is_dask(data: object) -> bool:
    """A Dask array (duck-typed: the analysis group does not import Dask; the user's data
    brings it)."""
    return hasattr(data, "dask") and hasattr(data, "map_blocks") and hasattr(data, "rechunk")


def series_values(da: xr.DataArray):
    """The series' values: its Dask array when chunked (nothing loaded), else numpy."""
    return da.data if is_dask(da.data) else da.values


def spatial_window(window: object, spatial: int) -> tuple[int, ...] | None:
    """None, or a boxcar size per spatial axis: the package's window parser for images
    ``(depth, x)``, one int per axis otherwise (an M-mode's depth, a C-scan)."""
    if window is None:
        return None
    if spatial == 2:
        return parse_window(window, low=1)
    w = tuple(np.atleast_1d(np.asarray(window)).tolist())
    if len(w) != spatial:
        raise ValueError(
            f"window must give one size (pixels) per spatial axis ({spatial}), got {window!r}"
        )
    return tuple(check_int(int(v) if float(v) == int(v) else v, "window", low=1) for v in w)


def pool(a: np.ndarray, window: tuple[int, ...] | None) -> np.ndarray:
    """Mean over every spatial element (``window`` None) or a boxcar map of it.

    A pixel without an answer (NaN) makes NaN exactly the windows that hold it: the boxcar's
    running sums would carry it along the rest of each line (one zero-intensity pixel made
    324 of 400 pixels of a 3 x 3 LIV map NaN), so it is filtered as 0 and its windows masked.
    """
    if window is None:
        return np.asarray(a.mean()) if a.ndim else np.asarray(a)
    if np.iscomplexobj(a):
        return pool(a.real, window) + 1j * pool(a.imag, window)
    bad = np.isnan(a)
    if not bad.any():
        return ndi.uniform_filter(a, size=window, mode="nearest")
    out = ndi.uniform_filter(np.where(bad, 0.0, a), size=window, mode="nearest")
    # the share of NaN pixels in each window: >= 1/size where it holds one (running sums
    # leave ~1e-17 behind where it does not)
    share = ndi.uniform_filter(bad.astype(float), size=window, mode="nearest")
    hit = share > 0.5 / np.prod(np.broadcast_to(window, (a.ndim,)))
    return np.where(hit, np.nan, out)


def pooled_contrast(x, moments, finish, window, *, core_axes: int = 1, whole=()):
    """``finish(pooled moments(x))``: a contrast from per-pixel time statistics.

    ``moments(block)`` maps a block (``core_axes`` leading axes whole: time, or band and time;
    any spatial extent) to a list of per-pixel maps (the time averages each contrast pools);
    ``finish(pooled)`` turns the pooled maps into the contrast, pixel by pixel. numpy: pooled
    by :func:`pool`. Dask (lazy, spatial chunks; the leading axes rechunked whole): the
    moments block by block, pooled by the mean over every pixel (``window`` None) or the
    boxcar with an overlap of ``window // 2`` pixels (``boundary="nearest"``: the numpy
    filter's edge mode), then finished block by block; the same numbers to rounding (the
    boxcar's running sums start at each block). NaN warnings come when it is computed.
    ``whole``: spatial axes the moments need entire (e.g. the A-line of a spectral split).
    """
    w = spatial_window(window, x.ndim - core_axes)
    if not is_dask(x):
        return finish([pool(v, w) for v in moments(x)])
    return _lazy(x, moments, finish, w, core_axes, whole)


def _lazy(x, moments, finish, w, core_axes: int, whole):
    """:func:`pooled_contrast` on a Dask array, lazily (its docstring)."""
    spatial = x.ndim - core_axes
    x = x.rechunk({i: -1 for i in (*range(core_axes), *whole)})
    shape = [n if i < core_axes or i in whole else 1 for i, n in enumerate(x.shape)]
    with warnings.catch_warnings():  # a probe one pixel wide: the moments' number and kinds
        warnings.simplefilter("ignore")
        probe = [np.asarray(v) for v in moments(np.ones(shape, dtype=x.dtype))]
        finished = np.asarray(finish([pool(v, w) for v in probe]))
    real = [not np.iscomplexobj(v) for v in probe]
    kind = np.float64 if all(real) else np.complex128
    k = len(probe)

    def stacked(block):
        return np.stack([np.asarray(v, dtype=kind) for v in moments(block)])

    def done(pooled):
        return np.asarray(finish([p.real if r else p for p, r in zip(pooled, real, strict=True)]))

    mom = x.map_blocks(
        stacked,
        drop_axis=list(range(1, core_axes)),
        chunks=((k,), *x.chunks[core_axes:]),
        dtype=kind,
    )
    if w is None:
        lead = finished.shape
        pooled = mom.mean(axis=tuple(range(1, mom.ndim)))  # (k,): one chunk
        if not lead:
            return pooled.map_blocks(done, drop_axis=0, dtype=finished.dtype)
        return pooled.map_blocks(done, chunks=tuple((n,) for n in lead), dtype=finished.dtype)
    lead = finished.shape[: finished.ndim - spatial]
    pooled = mom.map_overlap(
        lambda b: np.stack([pool(v, w) for v in b]),
        depth={0: 0, **{1 + i: n // 2 for i, n in enumerate(w)}},
        boundary={0: "none", **{1 + i: "nearest" for i in range(spatial)}},
        dtype=kind,
    )
    if not lead:
        return pooled.map_blocks(done, drop_axis=0, dtype=finished.dtype)
    return pooled.map_blocks(
        done, chunks=(*((n,) for n in lead), *pooled.chunks[1:]), dtype=finished.dtype
    )


def checked_series(
    a: object, name: str, *, complex_: bool = False, min_frames: int = 2
) -> np.ndarray:
    arr = a if is_dask(a) else np.asarray(a)
    if arr.ndim < 1 or arr.shape[0] < min_frames:
        raise ValueError(
            f"{name} needs at least {min_frames} frames along axis 0 (time), got shape {arr.shape}"
        )
    if complex_ and not np.iscomplexobj(arr):
        raise TypeError(f"{name} must be the complex field (phase needed), got dtype {arr.dtype}")
    if not complex_ and np.iscomplexobj(arr):
        arr = np.abs(arr) ** 2  # a field given where an intensity is used
    if not complex_ and bool((arr < 0).any()):  # (Dask: one streaming pass, nothing kept)
        raise ValueError(f"{name} intensities must be >= 0")
    return arr


def frame_lags(lags: object, n: int) -> np.ndarray:
    m = np.atleast_1d(np.asarray(lags))
    if m.ndim != 1 or m.size == 0 or m.dtype.kind not in "iu":
        raise TypeError(f"lags must be a 1-D sequence of integers (frames), got {lags!r}")
    if np.any(m < 0) or np.any(m >= n):
        raise ValueError(f"lags must be in [0, {n - 1}] frames for a series of {n}, got {lags!r}")
    return m.astype(int)


def no_answer(bad: np.ndarray, what: str, why: str) -> None:
    if np.any(bad):
        warnings.warn(
            f"{what}: NaN at {int(np.sum(bad))} value(s): {why}", RuntimeWarning, stacklevel=3
        )


def ratio(num: np.ndarray, den: np.ndarray, what: str, why: str) -> np.ndarray:
    bad = ~(den > 0)
    no_answer(bad, what, why)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(bad, np.nan, num / np.where(bad, 1.0, den))


def decibels(i: np.ndarray, what: str) -> np.ndarray:
    """``10 log10 I``; NaN (warned, naming ``what``) where ``I`` is zero."""
    bad = ~(i > 0)
    no_answer(bad, what, "zero intensity has no logarithm")
    with np.errstate(divide="ignore"):
        return np.where(bad, np.nan, 10.0 * np.log10(np.where(bad, 1.0, i)))
