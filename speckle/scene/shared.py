"""Shared scenes: point scatterers over a 2-D (z, x) or 3-D (z, x, y) region, in no A-line.

A shared scene is an ``xarray.Dataset`` with one dim ``scatterer`` holding

* ``z``, ``x`` [, ``y``] -- scatterer positions in µm (float64),
* ``amplitude`` -- complex scattering amplitude (real positive as drawn; the phase of each
  contribution comes from its depth),
* ``region`` -- the label of the region (see :mod:`speckle.scene.regions`) that holds it,

sorted by ``x`` (then ``z``, ``y``), so that the scatterers a beam at lateral position ``X``
reaches are one contiguous slice. Attributes record the window, the tile size, the seed and
``kind = "shared"``. Any beam position images it (:func:`speckle.imaging.scan.scan_image`); the
deformation functions of :mod:`speckle.scene.deformation` move its scatterers continuously.

Tiles and reproducibility
-------------------------
Space is cut into a fixed grid of tiles of ``tile`` µm (``tile`` is part of the scene, like the
seed), with tile ``(iz, ix[, iy])`` covering ``[iz*tz, (iz+1)*tz) x [ix*tx, (ix+1)*tx) ...``.
Region ``r`` draws its scatterers in a tile from its own generator,
``SeedSequence(seed, spawn_key=(d, iz', ix'[, iy'], r))`` (``d`` the dimension, ``i'`` the tile
index folded to a non-negative integer): a Poisson number with mean ``density_r`` times the
volume of the tile inside the region's bounding box, placed uniformly there and kept where
:func:`~speckle.scene.regions.region_label` is ``r`` (exact thinning: a Poisson process of
intensity ``density_r`` on the region's visible part). A window of the scene is the union of
the tiles it touches, cut to the window, so the scatterers in any window do not depend on the
window, the chunking or the number of workers (tested).

The paper's independent A-lines (:func:`speckle.random_scatterers`) are the special case of a
beam much narrower than the line pitch with every scatterer on its line: each line sees only its
own scatterers (:func:`from_lines` makes that shared scene; tested against
:func:`speckle.bscan`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_int, check_memory, check_real
from ..conventions import attrs
from .regions import compile_regions, labels_of
from .scatterers import draw_amplitudes

__all__ = [
    "AXES",
    "MAX_TILES",
    "check_not_empty",
    "check_scene",
    "from_lines",
    "is_shared",
    "scene_window",
    "shared_scene",
    "tile_generator",
]

#: Position variables of a shared scene, in order of the tile index.
AXES = ("z", "x", "y")
#: Most tiles one :func:`shared_scene` call visits (each is a Python-level draw per region).
MAX_TILES = 10**6
#: Bytes per scatterer while a scene is built: the complex table of (z, x[, y], amplitude,
#: region) per tile, its concatenation, the sorted copy and the output variables.
SCATTERER_BYTES = 5 * 16 * 4

_ATTRS = {
    "z": attrs("z"),
    "x": attrs("x", "scatterer lateral position x"),
    "y": attrs("y", "scatterer lateral position y"),
    "amplitude": attrs("amplitude", "scattering amplitude a_j"),
    "region": attrs("label"),
}


def _fold(i: int) -> int:
    """Map a tile index in Z to N (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...)."""
    return 2 * i if i >= 0 else -2 * i - 1


def tile_generator(seed: int, tile: Sequence[int], region: int) -> np.random.Generator:
    """Generator of region ``region`` in tile ``tile`` = ``(iz, ix[, iy])`` for ``seed``."""
    key = (len(tile), *(_fold(int(i)) for i in tile), int(region))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def _range(value: object, name: str) -> tuple[float, float]:
    if isinstance(value, str | bytes) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name} must be (min, max) in µm, got {value!r}")
    lo = check_real(value[0], f"{name}[0]")
    hi = check_real(value[1], f"{name}[1]", low=lo, low_inclusive=False)
    return lo, hi


def _draw_tile(
    compiled: list[dict], seed: int, index: tuple[int, ...], tile: np.ndarray, ndim: int
) -> list[np.ndarray]:
    """Scatterers of one tile: columns z, x[, y], amplitude, region."""
    lo = np.array(index) * tile
    hi = lo + tile
    parts = []
    for r, row in enumerate(compiled):
        rho = float(row["density"])
        box = row["box"]
        blo = np.maximum(lo, [box[a][0] for a in AXES[:ndim]])
        bhi = np.minimum(hi, [box[a][1] for a in AXES[:ndim]])
        if rho == 0 or np.any(bhi <= blo):
            continue
        rng = tile_generator(seed, index, r)
        count = rng.poisson(rho * float(np.prod(bhi - blo)))
        pos = rng.uniform(blo, bhi, size=(count, ndim))
        amp = draw_amplitudes(rng, row["amplitude_model"], count)
        amp = amp * math.sqrt(float(row["backscatter"]))
        y = pos[:, 2] if ndim == 3 else None
        if row["shape"] == "background" and r == len(compiled) - 1:
            keep = slice(None)  # nothing painted over it
        else:
            keep = labels_of(compiled, pos[:, 0], pos[:, 1], y) == r
        sel = pos[keep]
        parts.append(np.column_stack([sel, amp[keep], np.full(sel.shape[0], float(r))]))
    return parts


def shared_scene(
    regions: xr.Dataset,
    *,
    z_range: tuple[float, float],
    x_range: tuple[float, float],
    y_range: tuple[float, float] | None = None,
    seed: int,
    tile: float | Sequence[float] = 64.0,
) -> xr.Dataset:
    """Random point scatterers of ``regions`` in a window of a 2-D or 3-D scene.

    Parameters
    ----------
    regions : xarray.Dataset
        Region geometry and properties (:func:`speckle.scene.regions.make_regions` or
        :func:`~speckle.scene.regions.from_label_image`); ``density`` is per µm^2 in 2-D and
        per µm^3 in 3-D.
    z_range, x_range : (float, float)
        Window ``[min, max)`` in depth and lateral position, µm.
    y_range : (float, float), optional
        Second lateral window in µm; given, the scene is 3-D.
    seed : int
        Non-negative seed; with ``tile`` it fixes the scene everywhere in space.
    tile : float or sequence of float
        Tile edge(s) in µm, one value or one per axis ``(z, x[, y])``, > 0. Part of the
        scene's identity (a different tile grid is a different random scene).

    Returns
    -------
    xarray.Dataset
        Dim ``scatterer``: ``z``, ``x`` [, ``y``] (µm), ``amplitude`` (complex128), ``region``
        (int32), sorted by ``x`` then ``z`` (then ``y``); attrs record the window, ``tile``,
        ``seed``, ``ndim`` and ``kind = "shared"``.

    Raises
    ------
    ValueError
        On an empty or inverted window, a non-positive tile or negative seed.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.layer(100.0, 200.0, density=0.1, attenuation=0.002)
    ... )
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(0.0, 64.0), seed=1)
    >>> sorted(scene.data_vars)[:3], scene.attrs.get("ndim", 2)
    (['amplitude', 'region', 'x'], 2)
    """
    compiled = compile_regions(regions)
    sd = check_int(seed, "seed", low=0)
    ranges = [_range(z_range, "z_range"), _range(x_range, "x_range")]
    if y_range is not None:
        ranges.append(_range(y_range, "y_range"))
    ndim = len(ranges)
    tv = np.atleast_1d(as_finite_array(tile, "tile"))
    if tv.ndim != 1 or tv.size not in (1, ndim):
        raise ValueError(
            f"tile must be one edge or one per axis ({ndim} for a {ndim}-D scene) in µm, got "
            f"shape {tv.shape}"
        )
    tiles = np.broadcast_to(tv, (ndim,)).copy()
    for i, t in enumerate(tiles):
        check_real(float(t), f"tile[{i}]", low=0, low_inclusive=False)
    lo = np.array([r[0] for r in ranges])
    hi = np.array([r[1] for r in ranges])
    first = np.floor(lo / tiles)
    last = np.ceil(hi / tiles)
    n_tiles = float(np.prod(last - first))
    if n_tiles > MAX_TILES:
        raise ValueError(
            f"tile too small for the window: the scene would visit {n_tiles:.3g} tiles (each "
            f"drawn in Python), above MAX_TILES = {MAX_TILES:g}; use a larger tile (µm) or a "
            "smaller window"
        )
    # every visited tile is drawn whole (then cropped to the window)
    volume = float(np.prod((last - first) * tiles))
    expected = volume * sum(max(float(row["density"]), 0.0) for row in compiled)
    check_memory(
        SCATTERER_BYTES * (expected + 6 * np.sqrt(expected + 1)),
        "tile, the window (z_range, x_range) or the densities",
        f"drawing ~{expected:.3g} scatterers in the tiles covering the window",
    )
    first, last = first.astype(int), last.astype(int)
    parts = []
    for index in np.ndindex(*(last - first)):
        idx = tuple(int(i) for i in np.array(index) + first)
        parts += _draw_tile(compiled, sd, idx, tiles, ndim)
    cols = ndim + 2
    table = np.concatenate(parts) if parts else np.zeros((0, cols))
    pos = table[:, :ndim].real
    inside = np.all((pos >= lo) & (pos < hi), axis=1)
    table, pos = table[inside], pos[inside]
    # Canonical order: x, then z, then y. Ties in x are rare (continuous draws): sort by x and
    # fall back to the (slower) full lexicographic sort only when there is one.
    order = np.argsort(pos[:, 1])
    if np.any(np.diff(pos[order, 1]) == 0):
        keys = [pos[:, 2]] if ndim == 3 else []
        order = np.lexsort([*keys, pos[:, 0], pos[:, 1]])  # the last key sorts first
    table, pos = table[order], pos[order]
    data = {a: ("scatterer", pos[:, i].copy(), _ATTRS[a]) for i, a in enumerate(AXES[:ndim])}
    data["amplitude"] = ("scatterer", table[:, ndim].astype(np.complex128), _ATTRS["amplitude"])
    data["region"] = ("scatterer", table[:, ndim + 1].real.astype(np.int32), _ATTRS["region"])
    attrs = {"kind": "shared", "ndim": ndim, "seed": sd, "tile": tiles.tolist()}
    for a, (r0, r1) in zip(AXES, ranges, strict=False):
        attrs[f"{a}_min"], attrs[f"{a}_max"] = r0, r1
    attrs["density_units"] = f"scatterers per um^{ndim}"
    return xr.Dataset(data, attrs=attrs)


def is_shared(scene: object) -> bool:
    """Whether ``scene`` is a shared scene (dim ``scatterer`` only, positions ``z`` and ``x``)."""
    return (
        isinstance(scene, xr.Dataset)
        and {"z", "x", "amplitude"} <= set(scene.data_vars)
        and scene.z.dims == ("scatterer",)
    )


def check_not_empty(scene: xr.Dataset, name: str = "scene") -> None:
    """Refuse a scatterer Dataset with nothing to image: a shared scene without scatterers or an
    independent-line field without A-lines (``ValueError`` naming ``name``). A line field with
    A-lines but no scatterers (zero density) is a valid, empty medium."""
    if is_shared(scene):
        dims = ["scatterer"]
    else:  # the lines' dims: every dim of z but the scatterers (aline, and strain, time, ...)
        dims = [d for d in (scene.z.dims if "z" in scene else ()) if d != "scatterer"]
    empty = [d for d in dims if scene.sizes[d] == 0]
    if empty:
        what = "scatterers" if empty == ["scatterer"] else "A-lines"
        raise ValueError(f"{name} holds no {what} (dim {empty[0]!r} has size 0): nothing to act on")


def check_scene(scene: object) -> int:
    """Check a shared scene and return its dimension (2 or 3).

    Raises
    ------
    TypeError
        If ``scene`` is not a Dataset with ``z``, ``x``, ``amplitude`` over dim ``scatterer``.
    ValueError
        If it holds no scatterer or non-finite positions.
    """
    if not is_shared(scene):
        raise TypeError(
            "scene must be a shared scene: an xarray.Dataset with variables z, x[, y], "
            "amplitude over the single dim 'scatterer' (see shared_scene)"
        )
    if scene.sizes["scatterer"] == 0:
        raise ValueError("scene holds no scatterers (empty window or zero densities)")
    for a in AXES:
        if a in scene and not np.all(np.isfinite(scene[a].values)):
            raise ValueError(f"scene {a} must be finite (µm); it holds NaN or infinite values")
    return 3 if "y" in scene else 2


def scene_window(scene: xr.Dataset, x_lo: float, x_hi: float) -> xr.Dataset:
    """The scatterers with ``x_lo <= x < x_hi`` (µm): a contiguous slice of the x-sorted scene."""
    x = scene.x.values
    if x.size > 1 and np.any(np.diff(x) < 0):
        order = np.argsort(x, kind="stable")
        scene, x = scene.isel(scatterer=order), x[order]
    i0, i1 = np.searchsorted(x, [x_lo, x_hi])
    return scene.isel(scatterer=slice(int(i0), int(i1)))


def from_lines(scene: xr.Dataset) -> xr.Dataset:
    """The paper's independent A-lines as a shared scene: every scatterer at ``x`` = its line.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field with dims ``(aline, scatterer)`` (:func:`speckle.random_scatterers`);
        zero-amplitude padding is dropped.

    Returns
    -------
    xarray.Dataset
        A 2-D shared scene (``region`` 0). Imaged with a waist ``w0`` much smaller than the line
        pitch ``p`` (a neighbour's weight is ``exp(-2 p^2/w0^2)``), it gives the paper's B-scan.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> shared = speckle.from_lines(scene)
    >>> sorted(shared.data_vars)[:3]
    ['amplitude', 'region', 'x']
    """
    if not isinstance(scene, xr.Dataset) or set(scene.z.dims) != {"aline", "scatterer"}:
        raise TypeError("scene must be an independent-line field with dims (aline, scatterer)")
    check_not_empty(scene)
    z = scene.z.transpose("aline", "scatterer").values
    a = scene.amplitude.transpose("aline", "scatterer").values
    x = np.broadcast_to(scene.aline.values[:, None], z.shape)
    keep = a != 0
    order = np.argsort(x[keep], kind="stable")
    data = {
        "z": ("scatterer", z[keep][order], _ATTRS["z"]),
        "x": ("scatterer", x[keep][order].copy(), _ATTRS["x"]),
        "amplitude": ("scatterer", a[keep][order].astype(np.complex128), _ATTRS["amplitude"]),
        "region": ("scatterer", np.zeros(int(keep.sum()), np.int32), _ATTRS["region"]),
    }
    attrs = {"kind": "shared", "ndim": 2, "source": "independent A-lines", **scene.attrs}
    return xr.Dataset(data, attrs=attrs)
