"""Physical compounding looks that image one scene differently: angle, offset, polarization, time.

The looks of :mod:`speckle.analysis.compounding` that form images (they call
:func:`speckle.image`), moved here from ``analysis`` (issue 32) so that the estimators and theory
they are measured with import no imaging. Every look function returns a complex ``DataArray``
with a leading dim ``look`` on the pixel grid of the reference image, ready for
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

from .._validate import as_finite_array
from ..analysis._common import label_looks
from ..analysis.compounding import brownian_frames
from ..conventions import coord, depth_range_of
from ..imaging.scan import image
from ..system.polarization import depolarize

__all__ = ["angular_looks", "polarization_looks", "spatial_looks", "temporal_looks"]


def _image_kw(waist, x, method, tol, chunk) -> dict:
    return {"waist": waist, "x": x, "method": method, "tol": tol, "chunk": chunk}


def _moved_field(scene: xr.Dataset, source: xr.DataArray, kw: dict) -> np.ndarray:
    """Complex field of a shared scene whose scatterers moved (sorted by ``x`` again first)."""
    order = np.argsort(scene.x.values, kind="stable")
    return image(scene.isel(scatterer=order), source, **kw).field.values


def _stacked_looks(
    fields: list[np.ndarray], kind: str, name: str, coordinate: tuple, **extra: object
) -> xr.DataArray:
    """Looks ``(look, depth, x)`` of the fields, coordinate ``name`` along ``look``."""
    looks = xr.DataArray(np.stack(fields), dims=("look", "depth", "x"), coords={name: coordinate})
    return label_looks(looks, kind, **extra)


def angular_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    angles: Sequence[float],
    *,
    waist: float,
    x: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """Looks at beam angles ``angles`` (degrees): rotated scene, image resampled back.

    The scene is rotated by ``-angle`` about the centre of the image (depths ``[0, H)``, the
    lines ``x``), so the beam crosses it at ``angle`` to the depth axis; the complex image is
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
    >>> looks = speckle.angular_looks(scene, src, [0.0, 5.0], waist=4.0, x=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    ang = as_finite_array(angles, "angles")
    if ang.ndim != 1 or ang.size == 0 or np.any(np.abs(ang) >= 90):
        raise ValueError("angles must be a non-empty 1-D list of degrees in (-90, 90)")
    n = int(source.attrs["n_pixels"])
    h = depth_range_of(source, "source")
    xs = np.asarray(x, dtype=float)
    p = h / n
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
    return _stacked_looks(out, "angular", "angle", angle)


def spatial_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    offsets: Sequence[float],
    *,
    waist: float,
    x: object,
    method: str = "direct",
    tol: float | None = None,
    chunk: int = 64,
) -> xr.DataArray:
    """Looks of A-lines offset laterally by ``offsets`` (µm), kept at the lines ``x``.

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
    >>> looks = speckle.spatial_looks(scene, src, [0.0, 4.0], waist=4.0, x=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    off = as_finite_array(offsets, "offsets")
    if off.ndim != 1 or off.size == 0:
        raise ValueError("offsets must be a non-empty 1-D list of lateral offsets in µm")
    xs = np.asarray(x, dtype=float)
    out = [
        image(scene, source, **_image_kw(waist, xs + d, method, tol, chunk)).field.values
        for d in off
    ]
    offset = coord("length", off, "lateral offset of the lines", dims="look")
    return _stacked_looks(out, "spatial", "offset", offset)


def polarization_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    depolarization: float,
    *,
    seed: int,
    waist: float,
    x: object,
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
    >>> looks = speckle.polarization_looks(scene, src, 0.5, seed=2, waist=4.0, x=x)
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    dep = depolarize(scene, depolarization, seed=seed)
    f = image(dep, source, **_image_kw(waist, np.asarray(x, float), method, tol, chunk)).field
    looks = f.rename(channel="look").transpose("look", "depth", "x")
    looks = looks.assign_coords(channel=("look", looks.look.values)).drop_vars("look")
    return label_looks(looks, "polarization", depolarization=float(depolarization))


def temporal_looks(
    scene: xr.Dataset,
    source: xr.DataArray,
    n_frames: int,
    *,
    diffusion: float,
    interval: float,
    seed: int,
    waist: float,
    x: object,
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
    >>> x = speckle.scan_lines(8, 4.0)
    >>> looks = speckle.temporal_looks(
    ...     scene, src, 3, diffusion=1.0, interval=1e-3, seed=2, waist=4.0, x=x
    ... )
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 3)
    """
    frames = brownian_frames(scene, n_frames, diffusion=diffusion, interval=interval, seed=seed)
    xs = np.asarray(x, dtype=float)
    kw = _image_kw(waist, xs, method, tol, chunk)
    out = [
        _moved_field(frames.isel(frame=i).drop_vars("time"), source, kw)
        for i in range(frames.sizes["frame"])
    ]
    time = ("look", frames.time.values, frames.time.attrs)
    return _stacked_looks(
        out, "temporal", "time", time, diffusion=float(diffusion), frame_interval=float(interval)
    )
