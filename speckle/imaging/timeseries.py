"""Imaging in time: M-mode, repeated B-scans (angiography protocol) and the raster's own timing.

The scene comes from :mod:`speckle.scene.motion`: positions with a ``time`` dim (s). Every
image here is the project's beam imaging (:func:`speckle.beam_scan` through the chunk kernel of
:func:`speckle.imaging.scan.scan_image`), evaluated on the positions at the right time:

* :func:`mmode` -- repeated A-lines at one lateral position, one per time of the scene (the
  A-line rate is the scene's time step): ``(time, depth)``;
* :func:`bscan_series` -- repeated B-scans. Without ``line_rate`` every B-scan is a snapshot
  at one time of the scene (the usual simplification); with ``line_rate`` (Hz) each A-line is
  imaged at its own time: the scene must hold ``n_frames x n_lines`` times, line ``i`` of
  frame ``f`` at time index ``f*n_lines + i`` (:func:`raster_times` builds them), and the
  output's ``time`` is each frame's first line time with a coordinate ``line_time`` (s) over
  ``(time, x)``. The moved scene then holds positions at every line time (``n_frames x
  n_lines x scatterers`` per axis, refused above :data:`speckle._validate.MAX_BYTES` by the
  motion functions): raster timing suits windows of a few hundred lines and frames; long
  series use snapshots.

Results are Datasets with ``field`` (complex, Dask) and ``intensity`` over ``(time, depth,
...)``, ``time`` in s, streamed as the strain sequences are: one task per frame (and chunk of
lines) or per chunk of times, so memory holds the scene and one task's field at a time
(:func:`speckle.io.stream_to_netcdf` writes them frame by frame). The numbers do not depend on
the scheduler: each task images fixed inputs with a deterministic method. M-mode and raster
series image each A-line from the same scatterers whatever the chunking, so they are
identical bit for bit under any chunking and scheduler (tested: synchronous, threads,
processes, streamed to NetCDF); snapshot series are :func:`speckle.scan_image` per time (the same
under any chunking to rounding). Independent-line scenes (dims ``aline, scatterer``) are
imaged by :func:`speckle.bscan`, one frame per time.
"""

from __future__ import annotations

import dask
import dask.array as da
import numpy as np
import xarray as xr

from .._deprecate import renamed_parameters
from .._validate import check_int, check_memory, check_real
from ..conventions import attrs, coord, units_of, with_grid
from ..provenance import provenance_attrs
from ..scene.motion import check_times
from ..scene.shared import is_shared
from ._bscan import bscan
from .aline import pixel_depths
from .scan import scan_image, scan_kernel

__all__ = ["bscan_series", "mmode", "raster_times"]


def raster_times(
    n_frames: int,
    n_lines: int,
    *,
    line_rate: float,
    frame_interval: float | None = None,
    start: float = 0.0,
) -> np.ndarray:
    """Times (s) of every A-line of ``n_frames`` raster B-scans of ``n_lines`` lines.

    Line ``i`` of frame ``f`` is at ``start + f*frame_interval + i/line_rate``.

    Parameters
    ----------
    n_frames, n_lines : int
        Frames and lines per frame (>= 1).
    line_rate : float
        A-line rate in Hz (> 0).
    frame_interval : float, optional
        Time between the first lines of consecutive frames in s; default ``n_lines/line_rate``
        (no flyback), and never shorter.
    start : float
        Time of the first line in s.

    Returns
    -------
    numpy.ndarray
        Shape ``(n_frames*n_lines,)``, strictly increasing, for :mod:`speckle.scene.motion`.

    Examples
    --------
    >>> raster_times(2, 3, line_rate=1000.0).tolist()
    [0.0, 0.001, 0.002, 0.003, 0.004, 0.005]
    """
    nf = check_int(n_frames, "n_frames", low=1)
    nl = check_int(n_lines, "n_lines", low=1)
    check_memory(24.0 * nf * nl, "n_frames x n_lines", f"{nf} x {nl} line times")
    rate = check_real(line_rate, "line_rate", low=0, low_inclusive=False)
    scan = nl / rate
    fi = scan if frame_interval is None else check_real(frame_interval, "frame_interval", low=0)
    if fi < scan * (1 - 1e-12):
        raise ValueError(
            f"frame_interval must be at least the scan time n_lines/line_rate = {scan:g} s, "
            f"got {fi:g} s"
        )
    t0 = check_real(start, "start")
    return (t0 + np.arange(nf)[:, None] * fi + np.arange(nl)[None, :] / rate).ravel()


def _timed_scene(scene: object, what: str) -> int:
    """Check a moved shared scene (positions over ``(time, scatterer)``); its dimension."""
    if not isinstance(scene, xr.Dataset) or "z" not in scene or "time" not in scene.z.dims:
        raise ValueError(
            f"{what} needs a scene whose positions have a 'time' dim (s): move it first with "
            "speckle.scene.motion (brownian_motion, flow_motion, ...)"
        )
    if set(scene.z.dims) != {"time", "scatterer"}:
        raise ValueError(
            f"{what} needs a shared scene with positions over (time, scatterer); got {scene.z.dims}"
        )
    check_times(scene["time"].values, "scene time")
    return 3 if "y" in scene else 2


def _columns(scene: xr.Dataset, ndim: int) -> tuple[np.ndarray, ...]:
    cols = [scene[a].transpose("time", "scatterer").values for a in ("z", "x", "y")[:ndim]]
    return (*cols, scene.amplitude.values)


def _series_dataset(field, times, xs, ys, meta, *, squeeze_x=False, extra=None):
    dims = ["time", "depth", "x"] + (["y"] if ys is not None else [])
    coords = {
        "time": coord("time", times, "time of the frame (first line)"),
        "depth": coord("depth", pixel_depths(meta["n_pixels"], meta["depth_range"])),
        "x": coord("x", xs),
    }
    if ys is not None:
        coords["y"] = coord("y", ys)
    f = xr.DataArray(field, dims=dims, coords=coords, attrs=attrs("field", "complex field A"))
    if squeeze_x:
        f = f.squeeze([d for d in ("x", "y") if d in f.dims])
    ds = xr.Dataset({"field": f})
    ds["intensity"] = (abs(ds.field) ** 2).assign_attrs(attrs("dimensionless", "intensity |A|^2"))
    if extra:
        ds = ds.assign_coords(extra)
    ds.attrs.update(meta)
    ds.attrs.update(provenance_attrs())
    return with_grid(ds)  # field and intensity: each carries its grid


def mmode(
    scene: xr.Dataset,
    source: xr.DataArray,
    *,
    waist: float,
    x: float,
    y: float | None = None,
    time_chunk: int = 256,
    method: str = "direct",
    tol: float | None = None,
    wrap: bool = False,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> xr.Dataset:
    """Repeated A-lines at one lateral position (M-mode), one per time of the moved scene.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene with positions over ``(time, scatterer)`` (:mod:`speckle.scene.motion`);
        its times are the A-lines' times (for an A-line rate ``r``, ``times = arange(n)/r``).
    source : xarray.DataArray
        Spectrum (:func:`speckle.spectrum`).
    waist : float
        Beam waist ``w0`` in µm, as in :func:`speckle.beam_scan`.
    x : float
        Lateral position of the beam in µm.
    y : float, optional
        Position along ``y`` in µm, for a 3-D scene (required there).
    time_chunk : int
        A-lines per Dask task (>= 1); the numbers do not depend on it.
    method, tol, wrap, focus, rayleigh_range
        As in :func:`speckle.imaging.scan.scan_image`.

    Returns
    -------
    xarray.Dataset
        ``field`` (complex, Dask) and ``intensity`` over ``(time, depth)``; scalar
        coordinates ``x`` (and ``y``); ``time`` in s.

    Raises
    ------
    ValueError
        A scene without a ``time`` dim (or not shared), ``y`` missing for a 3-D scene or given
        for a 2-D one, and the checks of :func:`~speckle.imaging.scan.scan_image`.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene.regions import background, make_regions
    >>> from speckle.scene.motion import brownian_motion
    >>> sc = speckle.shared_scene(make_regions(background(density=0.05)), z_range=(0, 64),
    ...                           x_range=(0, 64), seed=1)
    >>> moved = brownian_motion(sc, [0.0, 0.001, 0.002], diffusion=1.0, seed=2)
    >>> src = speckle.spectrum(16, 64.0, k0_dk=5)
    >>> mmode(moved, src, waist=8.0, x=32.0).field.dims
    ('time', 'depth')
    """
    ndim = _timed_scene(scene, "mmode")
    if (ndim == 3) != (y is not None):
        raise ValueError(f"a {ndim}-D scene needs {'y (µm)' if ndim == 3 else 'no y'} in mmode")
    x0 = check_real(x, "x")
    y0 = None if y is None else check_real(y, "y")
    tc = check_int(time_chunk, "time_chunk", low=1)
    cols = _columns(scene, ndim)
    times = np.asarray(scene["time"].values, float)
    kernel, reach, xs, ys, meta = scan_kernel(
        source,
        waist=waist,
        lines=[x0],
        y=None if y0 is None else [y0],
        method=method,
        tol=tol,
        wrap=wrap,
        focus=focus,
        rayleigh_range=rayleigh_range,
        z_bounds=(float(cols[0].min()), float(cols[0].max())) if wrap else None,
    )
    near = np.any(np.abs(cols[1] - x0) <= reach, axis=0)  # within reach at some time
    if ndim == 3:
        near &= np.any(np.abs(cols[2] - y0) <= reach, axis=0)
    pos = [c[:, near] for c in cols[:ndim]]
    amp = cols[-1][near]

    def task(rows: slice) -> np.ndarray:
        out = []
        for t in range(rows.start, rows.stop):
            part = (pos[0][t], pos[1][t], amp) + ((pos[2][t],) if ndim == 3 else ())
            out.append(kernel(part, xs, ys))
        return np.stack(out)

    n = meta["n_pixels"]
    shape_tail = (n, 1) if ndim == 2 else (n, 1, 1)
    parts = []
    for s in range(0, times.size, tc):
        rows = slice(s, min(s + tc, times.size))
        parts.append(
            da.from_delayed(
                dask.delayed(task, pure=True)(rows),
                shape=(rows.stop - rows.start, *shape_tail),
                dtype=np.complex128,
            )
        )
    meta.update({"protocol": "M-mode", "time_chunk": tc})
    return _series_dataset(da.concatenate(parts), times, xs, ys, meta, squeeze_x=True)


@renamed_parameters({"x": "lines"})
def bscan_series(
    scene: xr.Dataset,
    source: xr.DataArray,
    *,
    waist: float | None = None,
    lines: object = None,
    y: float | None = None,
    line_rate: float | None = None,
    chunk: int = 64,
    method: str = "direct",
    tol: float | None = None,
    wrap: bool = False,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> xr.Dataset:
    """Repeated B-scans of a moved scene: snapshots, or each A-line at its own time.

    Parameters
    ----------
    scene : xarray.Dataset
        Moved scene (:mod:`speckle.scene.motion`): a shared scene over ``(time, scatterer)``,
        or independent lines over ``(time, aline, scatterer)`` (imaged by
        :func:`speckle.bscan`; ``waist``, ``lines``, ``y`` and ``line_rate`` are then not used).
    source : xarray.DataArray
        Spectrum (:func:`speckle.spectrum`).
    waist : float
        Beam waist ``w0`` in µm (shared scenes).
    lines : array_like
        Line positions in µm (1-D, increasing, uniform).
    y : float, optional
        The B-scan's ``y`` in µm for a 3-D scene (required there).
    line_rate : float, optional
        A-line rate in Hz. None: one snapshot B-scan per time of the scene. Given: the
        scene's times are ``n_frames x len(lines)`` line times (:func:`raster_times`, checked:
        lines of a frame ``1/line_rate`` apart), each line imaged at its own time.
    chunk : int
        Lines per Dask task (>= 1); the numbers do not depend on it.
    method, tol, wrap, focus, rayleigh_range
        As in :func:`speckle.imaging.scan.scan_image`.

    Returns
    -------
    xarray.Dataset
        ``field`` (complex, Dask) and ``intensity`` over ``(time, depth, x)`` (independent
        lines too: their ``aline`` is the image's ``x``), ``time`` in s (a frame's first
        line); with ``line_rate`` a
        coordinate ``line_time`` (s) over ``(time, x)``.

    Raises
    ------
    ValueError
        A scene without a ``time`` dim, raster times that do not match ``len(lines)`` lines at
        ``line_rate``, and the checks of :func:`~speckle.imaging.scan.scan_image`.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene.regions import background, make_regions
    >>> from speckle.scene.motion import flow_motion
    >>> sc = speckle.shared_scene(make_regions(background(density=0.05)), z_range=(0, 64),
    ...                           x_range=(0, 64), seed=1)
    >>> t = raster_times(2, 4, line_rate=1e4)
    >>> moved = flow_motion(sc, t, velocity=[0.0, 1000.0])
    >>> src = speckle.spectrum(16, 64.0, k0_dk=5)
    >>> out = bscan_series(moved, src, waist=8.0, lines=[8.0, 16.0, 24.0, 32.0], line_rate=1e4)
    >>> out.field.dims, out.line_time.dims
    (('time', 'depth', 'x'), ('time', 'x'))
    """
    if (
        isinstance(scene, xr.Dataset)
        and "z" in scene
        and not is_shared(scene)
        and set(scene.z.dims) == {"time", "aline", "scatterer"}
    ):
        check_times(scene["time"].values, "scene time")
        out = bscan(scene, source, method=method, tol=tol)
        return out.assign_attrs(protocol="repeated B-scans (independent lines)")
    ndim = _timed_scene(scene, "bscan_series")
    if waist is None or lines is None:
        raise ValueError("bscan_series of a shared scene needs waist= (µm) and lines= (µm)")
    if (ndim == 3) != (y is not None):
        raise ValueError(
            f"a {ndim}-D scene needs {'y (µm, the B-scan plane)' if ndim == 3 else 'no y'}"
        )
    y0 = None if y is None else [check_real(y, "y")]
    if line_rate is None:
        out = scan_image(
            scene,
            source,
            waist=waist,
            lines=lines,
            y=y0,
            chunk=chunk,
            method=method,
            tol=tol,
            wrap=wrap,
            focus=focus,
            rayleigh_range=rayleigh_range,
        )
        if y0 is not None:
            out = out.squeeze("y", drop=False)
        out["time"].attrs.update(attrs("time", "time of the snapshot B-scan"))
        return out.assign_attrs(protocol="repeated B-scans (snapshots)")
    rate = check_real(line_rate, "line_rate", low=0, low_inclusive=False)
    c = check_int(chunk, "chunk", low=1)
    cols = _columns(scene, ndim)
    kernel, reach, xs, ys, meta = scan_kernel(
        source,
        waist=waist,
        lines=lines,
        y=y0,
        method=method,
        tol=tol,
        wrap=wrap,
        focus=focus,
        rayleigh_range=rayleigh_range,
        z_bounds=(float(cols[0].min()), float(cols[0].max())) if wrap else None,
    )
    times = np.asarray(scene["time"].values, float)
    nl = xs.size
    if times.size % nl:
        raise ValueError(
            f"with line_rate the scene needs n_frames x {nl} line times (raster_times); it has "
            f"{times.size} times"
        )
    nf = times.size // nl
    lt = times.reshape(nf, nl)
    if nl > 1 and not np.allclose(np.diff(lt, axis=1), 1.0 / rate, rtol=1e-9, atol=0):
        raise ValueError(
            f"the scene's line times are not 1/line_rate = {1.0 / rate:g} s apart within each "
            f"frame of {nl} lines: build them with raster_times(n_frames, {nl}, "
            f"line_rate={rate:g})"
        )

    def task(f: int, i0: int, i1: int) -> np.ndarray:
        out = []
        for i in range(i0, i1):
            r = f * nl + i
            keep = np.abs(cols[1][r] - xs[i]) <= reach
            if ndim == 3:
                keep &= np.abs(cols[2][r] - ys[0]) <= reach
            part = (cols[0][r][keep], cols[1][r][keep], cols[-1][keep])
            if ndim == 3:
                part = (*part, cols[2][r][keep])
            out.append(kernel(part, xs[i : i + 1], ys)[:, 0])
        return np.stack(out, axis=1)[None]

    n = meta["n_pixels"]
    frames = []
    for f in range(nf):
        row = []
        for i0 in range(0, nl, c):
            i1 = min(i0 + c, nl)
            shape = (1, n, i1 - i0) if ndim == 2 else (1, n, i1 - i0, 1)
            row.append(
                da.from_delayed(
                    dask.delayed(task, pure=True)(f, i0, i1), shape=shape, dtype=np.complex128
                )
            )
        frames.append(da.concatenate(row, axis=2))
    meta.update(
        {
            "protocol": "repeated B-scans (raster timing)",
            "line_rate": rate,
            "line_rate_units": units_of("line_rate"),
        }
    )
    extra = {"line_time": (("time", "x"), lt, attrs("time", "time of each A-line"))}
    out = _series_dataset(da.concatenate(frames), lt[:, 0], xs, ys, meta, extra=extra)
    if ys is not None:
        out = out.squeeze("y", drop=False)
    return out
