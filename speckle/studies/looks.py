"""Physical compounding looks that image one scene differently: angle, offset, polarization, time.

The looks of :mod:`speckle.analysis.compounding` that form images (they call
:func:`speckle.scan_image`), moved here from ``analysis`` (issue 32) so that the estimators and
theory they are measured with import no imaging. Every look function returns a complex
``DataArray`` with a leading dim ``look`` on the pixel grid of the reference image, ready for
:func:`speckle.compound`.

* **angular** (:func:`angular_looks`): the scene is rotated by each angle about the image centre
  (the beam tilted the other way), imaged, and the complex image resampled back onto the
  reference grid (cubic spline, registration as in a scanner).
* **spatial** (:func:`spatial_looks`): lines offset laterally by each offset, kept at the
  reference line positions (averaging them is a lateral blur).
* **polarization** (:func:`polarization_looks`): the co and cross channels of
  :func:`speckle.depolarize`.
* **temporal** (:func:`temporal_looks`): frames of :func:`speckle.brownian_frames` as looks.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.ndimage as ndi
import xarray as xr

from .._deprecate import renamed_parameters
from .._validate import as_finite_array, check_int, check_memory
from ..analysis._common import label_looks
from ..analysis.compounding import brownian_frames
from ..conventions import coord, grid, grid_attrs
from ..imaging.scan import scan_image
from ..scene.shared import check_scene
from ..system.polarization import depolarize
from ..system.source import check_source

__all__ = ["angular_looks", "polarization_looks", "spatial_looks", "temporal_looks"]


def _image_kw(waist, lines, method, tol, chunk) -> dict:
    return {"waist": waist, "lines": lines, "method": method, "tol": tol, "chunk": chunk}


def _moved_field(scene: xr.Dataset, source: xr.DataArray, kw: dict) -> np.ndarray:
    """Complex field of a shared scene whose scatterers moved (sorted by ``x`` again first)."""
    order = np.argsort(scene.x.values, kind="stable")
    return scan_image(scene.isel(scatterer=order), source, **kw).field.values


def _inputs(scene: object, source: object, lines: object) -> tuple[np.ndarray, dict]:
    """The checked ``lines`` (µm) and source of a look function (a shared scene only)."""
    check_scene(scene)
    src = check_source(source)
    xs = as_finite_array(lines, "lines")  # spacing is checked by the imaging (scan_image)
    if xs.ndim != 1 or xs.size == 0:
        raise ValueError("lines must be a non-empty 1-D array of line positions in µm")
    return xs, src


def _stacked_looks(
    fields: list[np.ndarray], kind: str, name: str, coordinate: tuple, src: dict, **extra: object
) -> xr.DataArray:
    """Looks ``(look, depth, x)`` of the fields, coordinate ``name`` along ``look``; the
    source's grid (``src`` from ``check_source``) in their attributes, as every image."""
    looks = xr.DataArray(np.stack(fields), dims=("look", "depth", "x"), coords={name: coordinate})
    grid_of = grid_attrs(src["n_pixels"], src["depth_range"], src["k0"])
    return label_looks(looks, kind, **extra).assign_attrs(grid_of)


@renamed_parameters({"x": "lines"})
def angular_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    angles: Sequence[float],
    *,
    waist: float,
    lines: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """Looks at beam angles ``angles`` (degrees): rotated scene, image resampled back.

    The scene is rotated by ``-angle`` about the centre of the image (depths ``[0, H)``, the
    ``lines``), so the beam crosses it at ``angle`` to the depth axis; the complex image is
    then sampled at the rotated pixel positions (cubic spline of its real and imaginary parts)
    onto the reference grid. Draw the scene with a margin of ``H |sin(angle)|`` in x (and the
    beam reach), or the corners come from empty space.

    Returns
    -------
    xarray.DataArray
        Complex looks ``(look, depth, x)``; coordinate ``angle`` (degrees) along ``look``.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> looks = speckle.angular_looks(scene, src, [0.0, 5.0], waist=4.0, lines=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    xs, src = _inputs(scene, source, lines)
    ang = as_finite_array(angles, "angles")
    if ang.ndim != 1 or ang.size == 0 or np.any(np.abs(ang) >= 90):
        raise ValueError("angles must be a non-empty 1-D list of degrees in (-90, 90)")
    g = grid(source, need=("n_pixels", "pixel_size"), what="source")  # from its attributes
    n, p = g.n_pixels, g.pixel_size
    pitch = xs[1] - xs[0] if xs.size > 1 else p
    zc, xc = (n - 1) / 2 * p, (xs[0] + xs[-1]) / 2
    zz, xx = np.meshgrid(np.arange(n) * p - zc, xs - xc, indexing="ij")
    out = []
    for a in np.deg2rad(ang):
        c, s = np.cos(a), np.sin(a)
        z, xv = scene.z.values - zc, scene.x.values - xc
        rot = scene.assign(
            z=("scatterer", zc + c * z + s * xv), x=("scatterer", xc - s * z + c * xv)
        )
        f = _moved_field(rot, source, _image_kw(waist, xs, method, tol, chunk))
        # object point (z, x) sits at the rotated position in the look's image
        zr, xr_ = zc + c * zz + s * xx, xc - s * zz + c * xx
        coords = np.stack([zr / p, (xr_ - xs[0]) / pitch])
        part = [
            ndi.map_coordinates(comp, coords, order=3, mode="constant", cval=0.0)
            for comp in (f.real, f.imag)
        ]
        out.append(part[0] + 1j * part[1])
    angle = coord("angle", ang, "beam angle", dims="look")
    return _stacked_looks(out, "angular", "angle", angle, src)


@renamed_parameters({"x": "lines"})
def spatial_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    offsets: Sequence[float],
    *,
    waist: float,
    lines: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """Looks of A-lines offset laterally by ``offsets`` (µm), kept at the ``lines``.

    The complex correlation of two looks ``d`` apart is ``exp(-d^2/w0^2)`` (dense scene).

    Returns
    -------
    xarray.DataArray
        Complex looks ``(look, depth, x)``; coordinate ``offset`` (µm) along ``look``.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> looks = speckle.spatial_looks(scene, src, [0.0, 4.0], waist=4.0, lines=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    xs, src = _inputs(scene, source, lines)
    off = as_finite_array(offsets, "offsets")
    if off.ndim != 1 or off.size == 0:
        raise ValueError("offsets must be a non-empty 1-D list of lateral offsets in µm")
    out = [
        scan_image(scene, source, **_image_kw(waist, xs + d, method, tol, chunk)).field.values
        for d in off
    ]
    offset = coord("length", off, "lateral offset of the lines", dims="look")
    return _stacked_looks(out, "spatial", "offset", offset, src)


@renamed_parameters({"x": "lines"})
def polarization_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    depolarization: float,
    *,
    seed: int,
    waist: float,
    lines: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """The co and cross channels of :func:`speckle.depolarize` as two looks.

    Intensity-averaged they give the polarization-insensitive image, contrast
    ``sqrt((1 + P^2)/2)``, ``P = |1 - 2 f|`` (dense scene).

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> looks = speckle.polarization_looks(scene, src, 0.5, seed=2, waist=4.0, lines=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    xs, _ = _inputs(scene, source, lines)
    dep = depolarize(scene, depolarization, seed=seed)
    f = scan_image(dep, source, **_image_kw(waist, xs, method, tol, chunk)).field
    looks = f.rename(channel="look").transpose("look", "depth", "x")
    looks = looks.assign_coords(channel=("look", looks.look.values)).drop_vars("look")
    return label_looks(looks, "polarization", depolarization=float(depolarization))


@renamed_parameters({"x": "lines"})
def temporal_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    n_frames: int,
    *,
    diffusion: float,
    interval: float,
    seed: int,
    waist: float,
    lines: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """Frames of a shared scene in Brownian motion (:func:`brownian_frames`) as looks.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> lines = speckle.scan_lines(8, 4.0)
    >>> looks = speckle.temporal_looks(
    ...     scene, src, 3, diffusion=1.0, interval=1e-3, seed=2, waist=4.0, lines=lines
    ... )
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 3)
    """
    xs, src = _inputs(scene, source, lines)
    nf = check_int(n_frames, "n_frames", low=1)
    # the frames hold z, x and the amplitude (complex) of every scatterer: 32 bytes each
    check_memory(32.0 * nf * scene.sizes["scatterer"], "n_frames", f"{nf} frames of the scene")
    frames = brownian_frames(scene, nf, diffusion=diffusion, interval=interval, seed=seed)
    kw = _image_kw(waist, xs, method, tol, chunk)
    out = [
        _moved_field(frames.isel(frame=i).drop_vars("time"), source, kw)
        for i in range(frames.sizes["frame"])
    ]
    time = ("look", frames.time.values, frames.time.attrs)
    return _stacked_looks(
        out,
        "temporal",
        "time",
        time,
        src,
        diffusion=float(diffusion),
        frame_interval=float(interval),
    )
