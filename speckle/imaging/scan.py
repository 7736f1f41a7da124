"""The labelled scan API: shared scene + Gaussian beam + scan geometry -> lazy image Dataset.

:func:`scan_image` images a shared scene (:mod:`speckle.scene.shared`) held in memory;
:func:`image_regions` draws the scene tile by tile inside each chunk, so a scene too large for
memory (a 3-D volume) is never built whole. Both return a Dataset over ``(depth, x[, y])`` in
µm whose ``field`` is a Dask array, one task per chunk of lines: a chunk's task gets only the
scatterers within the beam's reach of its lines (its halo, :func:`beam_reach`), and evaluates
:func:`speckle.beam_scan` (the contract, any of its methods, focus included); a 3-D chunk is
its ``(x, y)`` grid of lines in one call. Results do not depend on the chunking (tested to
rounding for the exact method).

:func:`speckle.io.stream_to_netcdf` writes such a Dataset chunk by chunk to a chunked NetCDF
file (on the local threads scheduler or a ``dask.distributed`` cluster).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable

import dask
import dask.array as da
import numpy as np
import xarray as xr

from .._deprecate import keyword_only, moved, renamed_parameters
from .._validate import as_finite_array, check_bool, check_int, check_real, check_size
from ..conventions import attrs, coord, grid_attrs, spacing, units_of, with_grid
from ..provenance import provenance_attrs
from ..scene.shared import check_scene, scene_window, shared_scene
from ..system.source import check_source
from ._rules import check_tol
from .aline import pixel_depths
from .beam import beam_scan
from .gaussian_beam import MAX_WAIST

__all__ = ["REACH_EPS", "beam_reach", "image_regions", "scan_image", "scan_kernel", "scan_lines"]

#: ``image`` (retired, :data:`speckle.conventions.RETIRED`) is now ``scan_image``.
__getattr__ = moved(__name__, __name__, [], {"image": "scan_image"})

#: Relative double-pass weight below which a scatterer is outside the beam's reach: below
#: float64 rounding (2^-53 = 1.1e-16), so the halo changes nothing beyond rounding.
REACH_EPS = 1e-17


def beam_reach(waist: float, eps: float = REACH_EPS, *, widening: float = 1.0) -> float:
    """Lateral distance (µm) beyond which the weight ``exp(-2 r^2/w^2)`` is below ``eps``.

    ``w * sqrt(ln(1/eps)/2)`` with ``w = widening * w0`` the widest beam over the imaged depths
    (``widening = 1`` without focus): 4.43 w for the default ``eps = 1e-17``.

    Examples
    --------
    >>> import speckle
    >>> round(speckle.beam_reach(10.0), 2)
    44.24
    """
    w0 = check_real(waist, "waist", low=0, high=MAX_WAIST, low_inclusive=False)
    e = check_real(eps, "eps", low=0, high=1, low_inclusive=False, high_inclusive=False)
    g = check_real(widening, "widening", low=1.0)
    return g * w0 * math.sqrt(math.log(1.0 / e) / 2.0)


def _widening(optics: dict, waist: float, k0: float, z_lo: float, z_hi: float) -> float:
    """Largest ``w(z)/w0 = sqrt(1 + ((z - z_f)/z_R)^2)`` over ``[z_lo, z_hi]`` (1 without focus).

    A focused beam's double-pass weight has modulus ``(w0/w)^2 exp(-2 r^2/w^2)`` (see
    :func:`speckle.beam_scan`), so the reach of the widest beam bounds every depth's.
    """
    zf = optics.get("focus")
    if zf is None:
        return 1.0
    zr = optics.get("rayleigh_range") or k0 * waist**2 / 2.0
    u = max(abs(z_lo - zf), abs(z_hi - zf)) / zr
    return math.sqrt(1.0 + u * u)


@keyword_only("start")
def scan_lines(n_lines: int, pitch: float, *, start: float = 0.0) -> np.ndarray:
    """Lateral positions ``start + i*pitch`` (µm) of ``n_lines`` A-lines, ``i = 0 ... n-1``.

    Examples
    --------
    >>> import speckle
    >>> speckle.scan_lines(4, 2.5, start=10.0)
    array([10. , 12.5, 15. , 17.5])
    """
    n = check_size(n_lines, "n_lines", low=1)
    p = check_real(pitch, "pitch", low=0, low_inclusive=False)
    return check_real(start, "start") + p * np.arange(n)


def _lines(values: object, name: str) -> np.ndarray:
    v = as_finite_array(values, name)
    if v.ndim != 1 or v.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array of line positions in µm")
    if v.size > 1:
        spacing(xr.DataArray(v, dims=name, coords={name: v}), name)  # increasing, uniform
    return v


def _source(source: object) -> dict:
    return check_source(source)


def _lines_field(
    part: tuple[np.ndarray, ...],
    xs: np.ndarray,
    ys: np.ndarray | None,
    *,
    waist: float,
    src: dict,
    method: str,
    tol: float | None,
    wrap: bool,
    optics: dict,
) -> np.ndarray:
    """Field of lines ``xs`` (x ``ys``) from scatterers ``part = (z, x, a[, y])``: (N, Lx[, Ly])."""
    z, x, a = part[:3]
    if not wrap:
        keep = (z >= 0) & (z < src["depth_range"])
        part = tuple(p[keep] for p in part)
        z, x, a = part[:3]
    kw = {"waist": waist, "method": method, "tol": tol, **src, **optics}
    if ys is None:
        return beam_scan(z, x, a, lines=xs, **kw).T
    grid = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1).reshape(-1, 2)
    out = beam_scan(z, x, a, y=part[3], lines=grid, **kw)
    return out.reshape(xs.size, ys.size, -1).transpose(2, 0, 1)


def _blocks(
    make_task: Callable[[np.ndarray, np.ndarray | None, tuple], object],
    xs: np.ndarray,
    ys: np.ndarray | None,
    chunk: int,
    n: int,
) -> da.Array:
    """Dask array (N, Lx[, Ly]) with one task per chunk of lines.

    ``make_task(cx, cy, (x0, x1, y0, y1))`` returns the Delayed field of lines ``cx`` (x
    ``cy``) spanning ``[x0, x1]`` (x ``[y0, y1]``) µm.
    """
    xsplit = [xs[i : i + chunk] for i in range(0, xs.size, chunk)]
    ysplit = [None] if ys is None else [ys[i : i + chunk] for i in range(0, ys.size, chunk)]
    rows = []
    for cx in xsplit:
        row = []
        for cy in ysplit:
            ylo, yhi = (-np.inf, np.inf) if cy is None else (cy[0], cy[-1])
            task = make_task(cx, cy, (cx[0], cx[-1], ylo, yhi))
            shape = (n, cx.size) if cy is None else (n, cx.size, cy.size)
            row.append(da.from_delayed(task, shape=shape, dtype=np.complex128))
        rows.append(row)
    if ys is None:
        return da.concatenate([r[0] for r in rows], axis=1)
    return da.block(rows)


def _dataset(
    field: da.Array, xs: np.ndarray, ys: np.ndarray | None, src: dict, meta: dict
) -> xr.Dataset:
    dims = ("depth", "x") if ys is None else ("depth", "x", "y")
    coords = {
        "depth": coord("depth", pixel_depths(src["n_pixels"], src["depth_range"])),
        "x": coord("x", xs),
    }
    if ys is not None:
        coords["y"] = coord("y", ys)
    f = xr.DataArray(field, dims=dims, attrs=attrs("field", "complex field A(q) of the beam"))
    ds = xr.Dataset({"field": f}, coords=coords)
    ds["intensity"] = (abs(ds.field) ** 2).assign_attrs(attrs("dimensionless", "intensity |A|^2"))
    ds.attrs.update(meta)
    ds.attrs.update(provenance_attrs())
    return with_grid(ds)  # field and intensity: each carries its grid


def _prepare(source, waist, lines, y, chunk, method, tol, wrap, focus, rayleigh_range):
    """Checked arguments, the per-chunk kernel and the attrs shared by both entry points."""
    tol = check_tol(tol)
    src = _source(source)
    w0 = check_real(waist, "waist", low=0, high=MAX_WAIST, low_inclusive=False)
    optics = {}
    if focus is not None:
        optics["focus"] = check_real(
            focus, "focus", low=0, high=src["depth_range"], high_inclusive=False
        )
    if rayleigh_range is not None:
        if focus is None:
            raise ValueError("rayleigh_range needs focus= (the focal depth in µm)")
        optics["rayleigh_range"] = check_real(
            rayleigh_range, "rayleigh_range", low=0, low_inclusive=False
        )
    xs = _lines(lines, "lines")
    ys = None if y is None else _lines(y, "y")
    c = check_int(chunk, "chunk", low=1)
    meta = {
        "waist": w0,
        "waist_units": units_of("length"),
        "beam": "Gaussian, double-pass amplitude exp(-2 r^2/w0^2)",
        **grid_attrs(src["n_pixels"], src["depth_range"], src["k0"]),
        "k0_dk": float(source.attrs.get("k0_dk", np.nan)),
        "spectrum_shape": source.attrs.get("shape", "array"),
        "method": method,
        "tol": np.nan if tol is None else float(tol),
        "chunk": c,
        "wrap": int(bool(wrap)),
        "focus": optics.get("focus", "none"),
        "rayleigh_range": optics.get("rayleigh_range", "default" if optics else "none"),
    }

    def kernel(part, cx, cy):
        return _lines_field(
            part, cx, cy, waist=w0, src=src, method=method, tol=tol, wrap=wrap, optics=optics
        )

    # beam_scan checks method, tol and optics before any work: an empty scene runs them now,
    # not in the first Dask task.
    empty = np.zeros(0)
    kernel((empty, empty, empty) + ((empty,) if ys is not None else ()), xs[:1], _first(ys))
    return src, w0, xs, ys, c, meta, kernel, optics


@renamed_parameters({"x": "lines"})
def scan_kernel(
    source: xr.DataArray,
    *,
    waist: float,
    lines: object,
    y: object | None = None,
    method: str = "direct",
    tol: float | None = None,
    wrap: bool = False,
    focus: float | None = None,
    rayleigh_range: float | None = None,
    z_bounds: tuple[float, float] | None = None,
) -> tuple[Callable, float, np.ndarray, np.ndarray | None, dict]:
    """The checked imaging kernel of :func:`scan_image`, for callers that pick the scatterers.

    Parameters
    ----------
    source, waist, lines, y, method, tol, wrap, focus, rayleigh_range
        As in :func:`scan_image` (checked here, before any work).
    z_bounds : (float, float), optional
        Depth range (µm) of the scatterers, for the reach of a focused beam with ``wrap``;
        default ``[0, H)``.

    Returns
    -------
    tuple
        ``(kernel, reach, xs, ys, meta)``: ``kernel((z, x, a[, y]), lines_x, lines_y)`` the
        field ``(N, Lx[, Ly])`` of lines from those scatterers (:func:`speckle.beam_scan`),
        ``reach`` the lateral distance (µm) beyond which a scatterer adds nothing
        (:func:`beam_reach` of the widest beam), the checked line positions, and the attrs
        :func:`scan_image` records (with ``n_pixels``, ``depth_range`` and ``k0``).

    Examples
    --------
    >>> import numpy as np, speckle
    >>> kernel, reach, xs, ys, meta = scan_kernel(speckle.spectrum(8, 64.0, k0_dk=4),
    ...                                           waist=4.0, lines=[0.0])
    >>> kernel((np.array([10.0]), np.array([0.0]), np.array([1.0 + 0j])), xs, ys).shape
    (8, 1)
    """
    src, w0, xs, ys, _, meta, kernel, optics = _prepare(
        source, waist, lines, y, 1, method, tol, check_bool(wrap, "wrap"), focus, rayleigh_range
    )
    lo, hi = (0.0, src["depth_range"]) if z_bounds is None else z_bounds
    reach = beam_reach(w0, widening=_widening(optics, w0, src["k0"], float(lo), float(hi)))
    meta = {k: v for k, v in meta.items() if k != "chunk"}
    return kernel, reach, xs, ys, meta


def _first(ys: np.ndarray | None) -> np.ndarray | None:
    return None if ys is None else ys[:1]


@renamed_parameters({"x": "lines"})
def scan_image(
    scene: xr.Dataset,
    source: xr.DataArray,
    *,
    waist: float,
    lines: object,
    y: object | None = None,
    chunk: int = 64,
    method: str = "direct",
    tol: float | None = None,
    wrap: bool = False,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> xr.Dataset:
    """Image a shared scene with a scanned Gaussian beam, lazily over chunks of lines.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (:func:`speckle.scene.shared.shared_scene`), possibly deformed; extra
        dims of the positions (e.g. ``strain`` from :func:`speckle.uniaxial_strain`) are
        carried to the output.
    source : xarray.DataArray
        Spectrum from :func:`speckle.spectrum` (gives ``N``, ``H`` in µm and ``k0`` in rad/µm).
    waist : float
        Beam waist ``w0`` in µm (> 0), as in :func:`speckle.beam_scan`.
    lines : array_like
        Lateral positions of the lines in µm (1-D, increasing, uniform: e.g.
        :func:`scan_lines`).
    y : array_like, optional
        Positions of the lines along ``y`` in µm for a 3-D scene: a C-scan over the grid
        ``lines`` x ``y`` (one ``y`` value: one B-scan at that ``y``).
    chunk : int
        Lines per Dask chunk along each lateral axis (>= 1).
    method, tol
        Passed to :func:`speckle.beam_scan` (``"direct"``: exact).
    wrap : bool
        ``False`` (default): only scatterers at depths in ``[0, H)`` are imaged (the tissue
        below the imaged depth does not alias in). ``True``: all, with SD-OCT wrap-around.
    focus, rayleigh_range : float, optional
        Focal depth ``z_f`` in ``[0, H)`` and Rayleigh range ``z_R`` in µm, passed to
        :func:`speckle.beam_scan` (default: a depth-independent beam). The halo of each chunk
        is that of the widest beam over the imaged depths.

    Returns
    -------
    xarray.Dataset
        ``field`` (complex128, Dask) and ``intensity`` over ``(..., depth, x[, y])``,
        coordinates in µm; attrs record beam, source, method and provenance.

    Raises
    ------
    TypeError, ValueError
        On a scene that is not a non-empty shared scene, a 3-D scene without ``y`` (or a 2-D
        one with it), a non-positive waist, lines that are not 1-D, increasing and uniform, a
        ``wrap`` that is not a bool, and a ``method``/``tol`` pair (or geometry) the method
        refuses whatever the scene: at call, not at compute.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> img = speckle.scan_image(scene, src, waist=4.0, lines=x)
    >>> img.field.dims, img.field.shape
    (('depth', 'x'), (32, 8))
    """
    if not isinstance(wrap, bool | np.bool_):  # "False" would be true
        raise TypeError(f"wrap must be True or False, got {wrap!r} ({type(wrap).__name__})")
    src, w0, xs, ys, c, meta, kernel, optics = _prepare(
        source, waist, lines, y, chunk, method, tol, bool(wrap), focus, rayleigh_range
    )
    if not isinstance(scene, xr.Dataset) or "z" not in scene:
        raise TypeError("scene must be a shared scene Dataset (see speckle.shared_scene)")
    extra = [d for d in scene.z.dims if d != "scatterer"]
    if extra:
        d = extra[0]
        parts = [
            scan_image(
                scene.isel({d: i}),
                source,
                waist=w0,
                lines=xs,
                y=ys,
                chunk=c,
                method=method,
                tol=tol,
                wrap=wrap,
                focus=focus,
                rayleigh_range=rayleigh_range,
            )
            for i in range(scene.sizes[d])
        ]
        return xr.concat(parts, dim=scene[d] if d in scene.coords else d, combine_attrs="override")
    ndim = check_scene(scene)
    if (ndim == 3) != (ys is not None):
        raise ValueError(
            f"a {ndim}-D scene needs {'y' if ndim == 3 else 'no y'} line positions "
            "(y given for 3-D scenes only)"
        )
    zs = scene.z.values
    z_lo, z_hi = (0.0, src["depth_range"]) if not wrap else (float(zs.min()), float(zs.max()))
    reach = beam_reach(w0, widening=_widening(optics, w0, src["k0"], z_lo, z_hi))
    _warn_outside(scene, xs, reach)
    order = np.argsort(scene.x.values, kind="stable")
    sc = scene.isel(scatterer=order)

    def get_part(x0: float, x1: float, y0: float, y1: float) -> tuple[np.ndarray, ...]:
        part = scene_window(sc, x0 - reach, np.nextafter(x1 + reach, np.inf))
        cols = [part.z.values, part.x.values, part.amplitude.values]
        if ndim == 3:
            keep = (part.y.values >= y0 - reach) & (part.y.values <= y1 + reach)
            cols = [c_[keep] for c_ in cols] + [part.y.values[keep]]
        return tuple(cols)

    def make_task(cx, cy, bounds):
        return dask.delayed(kernel, pure=True)(get_part(*bounds), cx, cy)

    field = _blocks(make_task, xs, ys, c, src["n_pixels"])
    meta.update({f"scene_{k}": v for k, v in scene.attrs.items()})
    return _dataset(field, xs, ys, src, meta)


def _warn_outside(scene: xr.Dataset, xs: np.ndarray, reach: float) -> None:
    """Warn when lines see none of the scene's x window (their image is empty space)."""
    if not {"x_min", "x_max"} <= set(scene.attrs):
        return
    lo, hi = float(scene.attrs["x_min"]), float(scene.attrs["x_max"])
    blind = (xs + reach < lo) | (xs - reach >= hi)
    if blind.any():
        warnings.warn(
            f"{int(blind.sum())} of {xs.size} lines (x from {xs[blind].min():g} µm) lie farther "
            f"than the beam reach {reach:.3g} µm from the scene's x window [{lo:g}, {hi:g}) µm: "
            "they image empty space (zeros); draw the scene over the lines plus the reach",
            UserWarning,
            stacklevel=3,
        )


@renamed_parameters({"x": "lines"})
def image_regions(
    regions: xr.Dataset,
    source: xr.DataArray,
    *,
    seed: int,
    tile: object = 64.0,
    waist: float,
    lines: object,
    y: object | None = None,
    chunk: int = 32,
    method: str = "direct",
    tol: float | None = None,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> xr.Dataset:
    """Like :func:`scan_image`, drawing the scene of ``regions`` tile by tile inside each chunk.

    Each chunk's task draws :func:`speckle.scene.shared.shared_scene` over depths ``[0, H)``
    and the lateral window of its lines plus the beam reach, and images it: memory holds one
    chunk's scatterers per worker, never the whole scene. The scene is the same whatever the
    chunking (tiles are seeded by their index), so the image is too.

    Parameters
    ----------
    regions : xarray.Dataset
        Regions (:mod:`speckle.scene.regions`); densities per µm^2 (2-D, no ``y``) or per µm^3.
    seed, tile
        As in :func:`speckle.scene.shared.shared_scene`.
    source, waist, lines, y, chunk, method, tol, focus, rayleigh_range
        As in :func:`scan_image` (``wrap`` is ``False``: the scene is drawn over ``[0, H)`` only).

    Returns
    -------
    xarray.Dataset
        As :func:`scan_image`.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> lines = speckle.scan_lines(8, 4.0)
    >>> img = speckle.image_regions(regions, src, seed=1, waist=4.0, lines=lines)
    >>> img.field.dims, img.field.shape
    (('depth', 'x'), (32, 8))
    """
    src, w0, xs, ys, c, meta, kernel, optics = _prepare(
        source, waist, lines, y, chunk, method, tol, False, focus, rayleigh_range
    )
    reach = beam_reach(w0, widening=_widening(optics, w0, src["k0"], 0.0, src["depth_range"]))
    h = src["depth_range"]
    sd = check_int(seed, "seed", low=0)

    def get_part(x0: float, x1: float, y0: float, y1: float) -> tuple[np.ndarray, ...]:
        yr = None if ys is None else (y0 - reach, np.nextafter(y1 + reach, np.inf))
        part = shared_scene(
            regions,
            z_range=(0.0, h),
            x_range=(x0 - reach, np.nextafter(x1 + reach, np.inf)),
            y_range=yr,
            seed=sd,
            tile=tile,
        )
        cols = [part.z.values, part.x.values, part.amplitude.values]
        return tuple(cols + ([part.y.values] if ys is not None else []))

    get_part(xs[0], xs[0], *((-1.0, -1.0) if ys is None else (ys[0], ys[0])))  # check inputs

    def make_task(cx, cy, bounds):
        part = dask.delayed(get_part, pure=True)(*bounds)
        return dask.delayed(kernel, pure=True)(part, cx, cy)

    field = _blocks(make_task, xs, ys, c, src["n_pixels"])
    meta.update(
        {"scene_seed": sd, "scene_tile": np.atleast_1d(np.asarray(tile, dtype=float)).tolist()}
    )
    meta["density_units"] = f"scatterers per um^{2 if ys is None else 3}"
    return _dataset(field, xs, ys, src, meta)
