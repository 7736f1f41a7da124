"""The twin's inputs: the image, its region, its data kind and signal-free rows."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from ...analysis import measured as ms
from ...conventions import spacing
from ...io import IMAGE_KINDS
from ._estimates import _Data
from ._theory import MIN_NOISE_ROWS, NOISE_ROW_DB


def _as_image(image: object) -> xr.DataArray:
    if (
        isinstance(image, (list, tuple))
        and image
        and all(isinstance(x, xr.DataArray) for x in image)
    ):
        shapes = [x.shape for x in image]
        if len(set(shapes)) > 1:
            raise ValueError(
                f"image frames must all have the same shape, got {shapes}; crop them to one "
                "shape (the frames are fitted together)"
            )
        image = xr.concat([_as_image(x) for x in image], dim="frame", join="override")
    if not isinstance(image, xr.DataArray):
        raise TypeError(
            f"image must be an xarray.DataArray from speckle.load_image, got {type(image).__name__}"
        )
    kind = image.attrs.get("kind")
    if kind not in IMAGE_KINDS:
        raise ValueError(
            f"image.attrs['kind'] must be one of {IMAGE_KINDS} (load it with "
            f"speckle.load_image(path, kind=...)); got {kind!r}"
        )
    if "aline" in image.dims:
        image = image.rename({"aline": "x"})
    if set(image.dims) - {"frame"} != {"depth", "x"}:
        raise ValueError(
            f"image must have dims (depth, x) (and optionally frame), got {image.dims}"
        )
    return image.transpose(*(("frame",) if "frame" in image.dims else ()), "depth", "x")


def _region(image: xr.DataArray, region: Mapping | None) -> xr.DataArray:
    """The half-open pixel ranges ``{"depth": [a, b], "x": [a, b]}`` of ``image``, checked."""
    if region is None:
        return image
    if not isinstance(region, Mapping):
        raise TypeError(
            f"region must be a mapping {{'depth': [start, stop], 'x': [start, stop]}}, got "
            f"{region!r}"
        )
    sl = {}
    for key, value in region.items():
        if key not in ("depth", "x"):
            raise ValueError(f"region keys must be 'depth' and/or 'x', got {key!r}")
        size = image.sizes[key]
        if value is None:
            continue
        if isinstance(value, str) or len(value) != 2:
            raise ValueError(f"region[{key!r}] must be [start, stop], got {value!r}")
        lo, hi = (0 if value[0] is None else value[0]), (size if value[1] is None else value[1])
        if not (0 <= lo < hi <= size):
            raise ValueError(
                f"region[{key!r}] = {list(value)} lies outside the image ({key}: 0..{size}); need "
                f"0 <= start < stop <= {size}"
            )
        sl[key] = slice(int(lo), int(hi))
    return image.isel(sl)


def _log_data(image: xr.DataArray) -> np.ndarray:
    v = image.values
    if image.attrs["kind"] == "log":
        return v
    inten = np.abs(v) ** 2 if image.attrs["kind"] in ("complex", "amplitude") else v
    return np.log(inten)


def _display(image: xr.DataArray) -> np.ndarray:
    if image.attrs["kind"] == "log":
        return image.values.astype(float)
    lg = _log_data(image)
    return 10 / np.log(10) * (lg - np.log(np.mean(np.exp(lg))))


def _data(image: xr.DataArray, noise: xr.DataArray | None, n_medium: float) -> _Data:
    kind = image.attrs["kind"]

    def values(x):
        v = x.values
        if kind == "complex":
            v = np.abs(v) ** 2
        elif kind == "amplitude":
            v = v**2
        return v.astype(float)

    sig = _side_by_side(values(image))
    one = image.isel(frame=0) if "frame" in image.dims else image
    dz, pitch = _step(one, "depth"), _step(one, "x")
    noise_values = None if noise is None else _side_by_side(values(noise))
    return _Data(kind, sig, noise_values, dz / n_medium, pitch)


def _side_by_side(v: np.ndarray) -> np.ndarray:
    """``(frame, depth, x)`` -> ``(depth, frame * x)``: frame ``f`` in columns ``f nx ..``."""
    return v if v.ndim == 2 else np.concatenate(list(v), axis=1)


def _column_groups(nx: int, n_frames: int, blocks: list[np.ndarray]) -> list[np.ndarray]:
    """The column blocks of every frame (no pixel pair crosses a block or a frame edge)."""
    return [b + f * nx for f in range(n_frames) for b in blocks]


def _step(image: xr.DataArray, dim: str) -> float:
    """Pixel size (``depth``) or line pitch (``x``) in µm, read from the coordinate ``dim``.

    Spacing is never read from attributes (:func:`speckle.conventions.spacing`): a missing,
    non-uniform or non-µm coordinate is refused with a ``ValueError`` naming it.
    """
    if dim not in image.coords:
        raise ValueError(
            f"image has no {dim!r} coordinate (µm) to read its spacing from; load it with "
            "speckle.load_image(..., pixel_size=..., pitch=...)"
        )
    units = image[dim].attrs.get("units")
    if units is not None and units not in ("um", "µm", "micrometre", "micrometer"):
        raise ValueError(
            f"coordinate {dim!r} is in {units!r}, not µm; load the image with "
            "speckle.load_image(..., pixel_size=..., pitch=...)"
        )
    return spacing(image, dim)


def _find_noise_rows(img: xr.DataArray, region: Mapping | None) -> list[int] | None:
    """Signal-free rows above the region, or ``None`` (module docstring of :func:`fit_system`).

    Rows ``0 .. start`` of the region's columns whose mean intensity is :data:`NOISE_ROW_DB`
    below the region's; of those, the rows within a factor 2 of their median level (no depth
    structure: the rising tails of the sample's point-spread function are left out), and of
    these the longest contiguous run of at least :data:`MIN_NOISE_ROWS` rows.
    """
    reg = region or {}
    start = (reg.get("depth") or [0])[0] or 0
    if start < MIN_NOISE_ROWS:
        return None
    above = _region(img, {"depth": [0, start], "x": reg.get("x")})
    inside = _region(img, {"depth": reg.get("depth"), "x": reg.get("x")})
    kind = img.attrs["kind"]
    if not (np.all(np.isfinite(above.values)) and np.all(np.isfinite(inside.values))):
        return None
    if kind == "log":
        d_in = inside.values.astype(float)
        g = float(
            ms.fit_floor(
                xr.DataArray(
                    d_in.reshape(-1, d_in.shape[-1]),
                    attrs={"scale": "log"},
                    dims=("depth", "aline"),
                )
            )["gain"]
        )
        i_above, i_in = (np.exp((v.astype(float) - d_in.mean()) / g) for v in (above.values, d_in))
    else:
        i_above, i_in = (_data(x, None, 1.0).signal for x in (above, inside))
    axes = tuple(i for i in range(i_above.ndim) if i != i_above.ndim - 2)  # all but depth
    level = np.mean(i_above, axis=axes)
    low = level < np.mean(i_in) * 10 ** (-NOISE_ROW_DB / 10)
    if not low.any():
        return None
    flat = low & (level <= 2 * np.median(level[low]))
    best, run = None, None
    for i, ok in enumerate(np.append(flat, False)):
        if ok and run is None:
            run = i
        elif not ok and run is not None:
            if best is None or i - run > best[1] - best[0]:
                best = (run, i)
            run = None
    if best is None or best[1] - best[0] < MIN_NOISE_ROWS:
        return None
    return [int(best[0]), int(best[1])]


def _check_values(region: xr.DataArray, name: str, kind: str) -> None:
    v = region.values
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} has NaN or infinite pixels; choose a region without them")
    if np.ptp(np.abs(v)) == 0:
        raise ValueError(f"{name} is constant ({np.abs(v).flat[0]!r}); it holds no speckle")
    if kind in ("amplitude", "intensity", "complex") and np.any(np.abs(v) == 0):
        raise ValueError(
            f"{name} has exact zeros (their log is undefined); choose a region without them"
        )
