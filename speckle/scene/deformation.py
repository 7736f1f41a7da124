"""Deformation of scatterer fields: uniaxial strain, rigid translations, arbitrary displacements.

Conventions
-----------
* Displacements are in µm and act on material (reference) positions: a scatterer at depth ``z``
  and lateral position ``x`` moves to ``z + u_z(z, x)``, ``x + u_x(z, x)``.
* ``strain`` is the *compressive* uniaxial strain applied by an OCT probe pressed on the surface
  (``z = 0`` held fixed by the probe): ``u_z = -strain * z``. Positive strain compresses
  (scatterers move up, deeper tissue is pulled into view); negative strain stretches. Allowed
  range ``-1 < strain < 1``. An optional lateral Poisson expansion
  ``u_x = poisson_ratio * strain * (x - x_centre)`` moves scatterers between A-lines.
* The tissue continues below the imaged depth ``H``: :func:`deformable_scene` populates depths
  ``[0, H / (1 - max(strain, 0)))`` -- exactly as deep as the largest compression needs.
* Wrap-around: the A-scan model is periodic in depth with period ``H``, so a scatterer deeper
  than ``H`` aliases into the top of the image (a real SD-OCT effect). With ``wrap=False``
  (default) scatterers whose displaced depth is outside ``[0, H)`` are given amplitude 0, so the
  deep population needed for compression never aliases into the image and only the deformation
  decorrelates it. ``wrap=True`` keeps them (aliasing on).

Scenes stay labelled: :func:`uniaxial_strain` returns one dataset with a ``strain`` dim, which
:func:`speckle.bscan` images in one call.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from .._deprecate import renamed_parameters
from .._validate import as_finite_array, check_bool, check_int, check_real
from ..conventions import attrs, canonical_dims, coord, depth_range_of, spacing
from .scatterers import line_generator, random_scatterers
from .shared import check_not_empty, check_scene, is_shared

__all__ = [
    "LATERAL_STREAM",
    "check_line_scene",
    "deformable_scene",
    "displace",
    "pixel_displacement",
    "required_depth",
    "translate",
    "uniaxial_displacement",
    "uniaxial_pixel_displacement",
    "uniaxial_strain",
]

#: Sub-stream of :func:`speckle.scene.scatterers.line_generator` for lateral positions in the beam.
LATERAL_STREAM = 1

#: Dims a displacement field given as an xarray object may have (material coordinates): a
#: quantity over the image, lateral dim ``x`` (issue 32; ``aline`` is read as ``x`` for a
#: release, warning).
FIELD_DIMS = ("depth", "x")

Displacement = Callable[..., object] | xr.DataArray | xr.Dataset


def check_strain(strain: object, name: str = "strain") -> np.ndarray:
    """Strain values as a 1-D float array after checking ``-1 < strain < 1`` for each."""
    s = as_finite_array(strain, name)
    if s.ndim > 1:
        raise ValueError(f"{name} must be a scalar or 1-D sequence, got shape {s.shape}")
    if s.size == 0:
        raise ValueError(f"{name} must hold at least one value in (-1, 1), got an empty sequence")
    bad = s[(s <= -1) | (s >= 1)]
    if bad.size:
        raise ValueError(
            f"{name} must lie in the open interval (-1, 1) (compressive strain, u_z = "
            f"-strain*z); got {bad.tolist()}"
        )
    return np.atleast_1d(s)


def required_depth(depth_range: float, strain: object) -> float:
    """Depth in µm to populate so that every strain in ``strain`` keeps ``[0, H)`` full.

    ``depth_range`` is the unambiguous depth ``H`` in µm. Compression ``s > 0`` pulls material
    from ``H / (1 - s)`` up to ``H``; stretching needs nothing beyond ``H``.
    """
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    s = check_strain(strain)
    return h / (1.0 - max(0.0, float(s.max())))


def deformable_scene(
    n_alines: int,
    density: float,
    *,
    n_pixels: int,
    depth_range: float,
    seed: int,
    strain: object = 0.0,
    poisson_ratio: float = 0.0,
    amplitude: str = "equal",
    count: str = "fixed",
) -> xr.Dataset:
    """Random scatterers populated as deep (and wide) as the given strains need, no further.

    Parameters
    ----------
    n_alines, density, n_pixels, depth_range, seed, amplitude, count
        As in :func:`speckle.random_scatterers` (density per pixel, depth ``H`` µm).
    strain : float or sequence of float
        Compressive strains the scene will be subjected to, each in (-1, 1). Depths
        ``[0, H/(1 - max(strain, 0)))`` are populated at the given density.
    poisson_ratio : float
        Lateral Poisson ratio in [0, 0.5]. With stretching (negative strain) the lateral
        contraction pulls material in from beyond the scan, so extra A-lines are populated on
        each side; they are dropped again by :func:`displace`.

    Returns
    -------
    xarray.Dataset
        As :func:`~speckle.scene.scatterers.random_scatterers`, plus ``x`` (lateral position of each
        scatterer in µm, uniform across the beam width ``aline_pitch`` around its A-line) and
        attrs ``imaged_first``/``imaged_count`` (the A-lines that are imaged), ``max_strain``,
        ``poisson_ratio``.

    Examples
    --------
    >>> import speckle
    >>> kw = dict(n_pixels=32, depth_range=256.0, seed=1)
    >>> scene = speckle.deformable_scene(4, 2.0, strain=0.01, **kw)
    >>> sorted(scene.data_vars), int(scene.sizes["aline"])
    (['amplitude', 'count', 'x', 'z'], 4)
    """
    n_alines = check_int(n_alines, "n_alines", low=1)
    s = check_strain(strain)
    nu = check_real(poisson_ratio, "poisson_ratio", low=0.0, high=0.5)
    zmax = required_depth(depth_range, s)
    smin = float(s.min())
    contraction = 1.0 + nu * min(smin, 0.0)  # lateral stretch factor < 1 for tension
    margin = 0 if contraction >= 1.0 else math.ceil(0.5 * n_alines * (1 / contraction - 1)) + 1
    scene = random_scatterers(
        n_alines + 2 * margin,
        density,
        n_pixels=n_pixels,
        depth_range=depth_range,
        seed=seed,
        amplitude=amplitude,
        count=count,
        z_range=(0.0, zmax),
    )
    pitch = _pitch(scene)
    offsets = np.zeros(scene.z.shape)
    for i in range(scene.sizes["aline"]):
        rng = line_generator(seed, i, LATERAL_STREAM)
        offsets[i] = rng.uniform(-0.5 * pitch, 0.5 * pitch, size=scene.sizes["scatterer"])
    x = scene.aline.values[:, None] + offsets
    scene["x"] = (("aline", "scatterer"), x, attrs("x", "lateral position"))
    scene.attrs.update(
        {
            "imaged_first": margin,
            "imaged_count": int(n_alines),
            "max_strain": float(s.max()),
            "min_strain": smin,
            "poisson_ratio": nu,
            "populated_depth": zmax,
        }
    )
    return scene


def uniaxial_displacement(
    strain: float,
    *,
    poisson_ratio: float = 0.0,
    x_centre: float = 0.0,
    y_centre: float = 0.0,
) -> Callable[..., tuple[np.ndarray, ...]]:
    """Displacement function of a probe compressing the tissue from ``z = 0``.

    Returns ``f(z, x[, y]) -> (u_z, u_x[, u_y])`` in µm with ``u_z = -strain*z``,
    ``u_x = poisson_ratio*strain*(x - x_centre)`` and, given ``y`` (3-D scenes),
    ``u_y = poisson_ratio*strain*(y - y_centre)``: lateral expansion under compression.
    """
    s = float(check_strain(strain)[0])
    nu = check_real(poisson_ratio, "poisson_ratio", low=0.0, high=0.5)
    xc = check_real(x_centre, "x_centre")
    yc = check_real(y_centre, "y_centre")

    def field(z: np.ndarray, x: np.ndarray, y: np.ndarray | None = None) -> tuple:
        out = (-s * np.asarray(z, float), nu * s * (np.asarray(x, float) - xc))
        return out if y is None else (*out, nu * s * (np.asarray(y, float) - yc))

    return field


def _component(value: object, shape: tuple[int, ...], label: str) -> np.ndarray:
    """A displacement function's component ``label``: finite, a scalar or shaped like ``z``."""
    v = as_finite_array(value, f"displacement {label}")
    try:
        return np.broadcast_to(v, shape)
    except ValueError:
        raise ValueError(
            f"displacement function returned {label} of shape {v.shape}; it must be a scalar or "
            f"shaped like its position arguments {shape} (µm)"
        ) from None


def _at_scatterers(values: np.ndarray, name: str) -> np.ndarray:
    """Field values interpolated at the scatterers: NaN there means the field is undefined
    where the scene has scatterers (NaN elsewhere in the field is allowed)."""
    bad = int(np.size(values) - np.count_nonzero(np.isfinite(values)))
    if bad:
        raise ValueError(
            f"displacement field {name} is NaN at {bad} scatterer(s) (NaN nodes of the field "
            "reach them through linear interpolation); give finite values wherever the scene "
            "has scatterers (NaN is allowed only where it has none)"
        )
    return values


def _field_values(
    displacement: Displacement, z: np.ndarray, x: np.ndarray, lines: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Evaluate a displacement (callable or xarray field) at material points (µm).

    A callable gets the scatterers' own lateral positions ``x``; an xarray field is read at
    their lines' positions ``lines`` (default ``x``) along its ``x`` dim."""
    if callable(displacement) and not isinstance(displacement, xr.DataArray | xr.Dataset):
        out = displacement(z, x)
        if isinstance(out, tuple) and len(out) != 2:
            raise ValueError(
                f"displacement function must return u_z or (u_z, u_x); got a {len(out)}-tuple"
            )
        uz, ux = out if isinstance(out, tuple) else (out, 0.0)
        return _component(uz, z.shape, "u_z"), _component(ux, z.shape, "u_x")
    if isinstance(displacement, xr.DataArray):
        displacement = xr.Dataset({"uz": displacement})
    if not isinstance(displacement, xr.Dataset):
        raise TypeError(
            "displacement must be a callable f(z, x) -> u_z or (u_z, u_x) in µm, or an xarray "
            f"DataArray/Dataset (variables uz[, ux]); got {type(displacement).__name__}"
        )
    displacement = canonical_dims(displacement, "displacement field")  # aline: x, warning
    check_field(displacement)
    line_pos = x if lines is None else lines
    out = []
    for name in ("uz", "ux"):
        if name not in displacement:
            out.append(np.zeros(z.shape))
            continue
        da = displacement[name]
        pts = {}
        if "depth" in da.dims:
            pts["depth"] = xr.DataArray(z.ravel(), dims="points")
        if "x" in da.dims:
            pts["x"] = xr.DataArray(np.broadcast_to(line_pos, z.shape).ravel(), dims="points")
        if pts:
            # linear extrapolation beyond the coordinates: scipy's interp1d spells it
            # "extrapolate" (one interpolated dim), interpn None (several)
            fill = "extrapolate" if len(pts) == 1 else None
            vals = da.interp(pts, method="linear", kwargs={"fill_value": fill})
            vals = np.broadcast_to(vals.values.reshape(z.shape), z.shape)
        else:
            vals = np.full(z.shape, float(da.values))
        out.append(_at_scatterers(vals, name))
    return out[0], out[1]


def check_line_scene(scene: object, name: str = "scene") -> None:
    """Check ``scene`` is a scatterer field: ``z``/``amplitude`` over ``(aline, scatterer)``
    and a ``depth_range`` attribute (``H``, µm), as :func:`speckle.random_scatterers` makes.

    Raises
    ------
    TypeError, ValueError
        Naming ``name`` and what is missing (e.g. a B-scan image passed instead of a scene).
    """
    if not isinstance(scene, xr.Dataset) or not {"z", "amplitude"} <= set(scene.data_vars):
        raise TypeError(
            f"{name} must be a scatterer field (xarray.Dataset with variables 'z' and "
            "'amplitude', from speckle.random_scatterers or deformable_scene), got "
            + (
                f"a Dataset with variables {list(scene.data_vars)}"
                if isinstance(scene, xr.Dataset)
                else type(scene).__name__
            )
        )
    if set(scene.z.dims) != {"aline", "scatterer"}:
        raise ValueError(f"{name} z must have dims (aline, scatterer), got {scene.z.dims}")
    check_not_empty(scene, name)
    depth_range_of(scene, name)


def check_field(displacement: xr.Dataset, extra_dims: Sequence[str] = ()) -> None:
    """Check a displacement field: variables ``uz``/``ux`` over dims ``depth``/``x`` only.

    Raises
    ------
    ValueError
        On a missing ``uz``, a dim other than ``depth``/``x`` (and ``extra_dims``), a
        missing coordinate or NaN/infinite values.
    """
    if "uz" not in displacement:
        raise ValueError("displacement field needs a variable 'uz' (axial displacement, µm)")
    allowed = (*FIELD_DIMS, *extra_dims)
    for name in ("uz", "ux"):
        if name not in displacement:
            continue
        _check_component(displacement[name], name, allowed, FIELD_DIMS)


def _check_component(
    da: xr.DataArray, name: str, allowed: Sequence[str], spatial: Sequence[str]
) -> None:
    """One component of a displacement field: dims among ``allowed``, a coordinate (µm) on
    each spatial dim, finite values."""
    wrong = [d for d in da.dims if d not in allowed]
    if wrong:
        raise ValueError(
            f"displacement field {name!r} must have dims among {tuple(allowed)} (material "
            f"coordinates in µm); got dims {da.dims}"
        )
    for d in da.dims:
        if d in spatial and d not in da.coords:
            raise ValueError(f"displacement field {name!r} needs a coordinate {d!r} in µm")
    try:
        vals = np.asarray(da.values, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(
            f"displacement field {name!r} must hold real numbers (µm), got dtype {da.dtype}"
        ) from None
    if da.dtype.kind in "bUSO" or np.any(np.isinf(vals)):
        raise ValueError(
            f"displacement field {name!r} must hold real, non-infinite values in µm (NaN marks "
            "points outside the sample and is allowed where no scatterer lies)"
        )


def displace(scene: xr.Dataset, displacement: Displacement, *, wrap: bool = False) -> xr.Dataset:
    """Move every scatterer of ``scene`` by a displacement field.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field (``z``, ``amplitude``; optional ``x``) with dims ``(aline, scatterer)``,
        e.g. from :func:`deformable_scene`.
    displacement : callable or xarray.DataArray or xarray.Dataset
        Either ``f(z, x) -> u_z`` or ``f(z, x) -> (u_z, u_x)`` (µm, arrays shaped like ``z``),
        or a field on material coordinates: a DataArray of ``u_z`` or a Dataset with ``uz`` and
        optionally ``ux``, with dims among ``depth`` and ``x`` (coordinates in µm, as an
        image's; a line scene reads it at its lines' positions), interpolated linearly
        (extrapolated linearly beyond its coordinates). A field over the retired dim name
        ``aline`` is read as ``x`` for a release, with a ``FutureWarning``.
    wrap : bool
        Keep scatterers displaced outside ``[0, H)`` so they alias into the image (``True``),
        or give them amplitude 0 (``False``, default; see module docstring).

    Returns
    -------
    xarray.Dataset
        The displaced field, restricted to the imaged A-lines. With a lateral displacement,
        scatterers are re-assigned to the A-line whose beam (width ``aline_pitch``) holds them.

    Notes
    -----
    A shared scene (:mod:`speckle.scene.shared`, dim ``scatterer`` only) is moved continuously:
    every scatterer keeps its amplitude and region and nothing is re-binned or dropped (the
    imaging step, :func:`speckle.imaging.scan.scan_image`, decides what the depth window shows).
    Callables get ``(z, x)`` in 2-D and ``(z, x, y)`` in 3-D and return ``u_z`` or a tuple
    ``(u_z, u_x[, u_y])``; xarray fields have dims among ``depth``, ``x`` (and ``y``) in µm,
    e.g. the FEM displacement ``uz``, ``ux`` over ``(depth, x)``.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> moved = speckle.displace(scene, lambda z, x: 4.0 + 0 * z)
    >>> round(float((moved.z - scene.z).max()), 9)
    4.0
    """
    check_bool(wrap, "wrap")
    if is_shared(scene):
        return _displace_shared(scene, displacement)
    check_line_scene(scene)
    z = scene.z.transpose("aline", "scatterer").values
    amp = scene.amplitude.transpose("aline", "scatterer").values
    aline = scene.aline.values
    x = (
        scene.x.transpose("aline", "scatterer").values
        if "x" in scene
        else np.broadcast_to(aline[:, None], z.shape)
    )
    uz, ux = _field_values(displacement, z, x, np.broadcast_to(aline[:, None], z.shape))
    z2, x2 = z + uz, x + ux
    h = depth_range_of(scene, "scene")
    first = int(scene.attrs.get("imaged_first", 0))
    count = int(scene.attrs.get("imaged_count", len(aline)))
    amp2 = np.where(amp != 0, amp, 0)
    if not wrap:
        amp2 = np.where((z2 >= 0) & (z2 < h), amp2, 0)
    if np.any(ux != 0):
        pitch = _pitch(scene)
        line = np.rint((x2 - aline[0]) / pitch).astype(int) - first
        keep = (line >= 0) & (line < count) & (amp2 != 0)
        z2, amp2, x2 = _rebin(line[keep], z2[keep], amp2[keep], x2[keep], count)
    else:
        sl = slice(first, first + count)
        z2, amp2, x2 = z2[sl], amp2[sl], x2[sl]
    out = xr.Dataset(
        {
            "z": (("aline", "scatterer"), z2, scene.z.attrs),
            "amplitude": (
                ("aline", "scatterer"),
                amp2.astype(np.complex128),
                scene.amplitude.attrs,
            ),
            "x": (("aline", "scatterer"), x2, attrs("x", "lateral position")),
        },
        coords={"aline": ("aline", aline[first : first + count], scene.aline.attrs)},
        attrs={**scene.attrs, "wrap": int(bool(wrap)), "imaged_first": 0, "imaged_count": count},
    )
    return out


#: Dims a displacement field of a shared scene may have (material coordinates, µm).
SHARED_FIELD_DIMS = ("depth", "x", "y")
_POSITIONS = ("z", "x", "y")


def _shared_field_values(displacement: Displacement, pos: list[np.ndarray]) -> list[np.ndarray]:
    """``[u_z, u_x[, u_y]]`` (µm) of a displacement at the material points ``pos`` of a scene."""
    shape = pos[0].shape
    names = [f"u_{a}" for a in _POSITIONS[: len(pos)]]
    if callable(displacement) and not isinstance(displacement, xr.DataArray | xr.Dataset):
        out = displacement(*pos)
        out = list(out) if isinstance(out, tuple) else [out]
        if len(out) > len(pos):
            raise ValueError(
                f"displacement returned {len(out)} components for a {len(pos)}-D scene"
            )
        out += [0.0] * (len(pos) - len(out))
        return [_component(u, shape, n) for u, n in zip(out, names, strict=True)]
    if isinstance(displacement, xr.DataArray):
        displacement = xr.Dataset({"uz": displacement})
    if not isinstance(displacement, xr.Dataset) or "uz" not in displacement:
        raise TypeError(
            "displacement must be a callable f(z, x[, y]) -> u_z or (u_z, u_x[, u_y]) in µm, or "
            "an xarray DataArray/Dataset (variables uz[, ux, uy]) over dims among "
            f"{SHARED_FIELD_DIMS}; got {type(displacement).__name__}"
        )
    where = dict(zip(("depth", "x", "y"), pos, strict=False))
    out = []
    for var in ("uz", "ux", "uy")[: len(pos)]:
        if var not in displacement:
            out.append(np.zeros(shape))
            continue
        da = displacement[var]
        _check_component(da, var, tuple(where), tuple(where))
        pts = {d: xr.DataArray(where[d], dims="points") for d in da.dims}
        if pts:
            # linear extrapolation beyond the coordinates: scipy's interp1d spells it
            # "extrapolate" (one interpolated dim), interpn None (several)
            fill = "extrapolate" if len(pts) == 1 else None
            vals = da.interp(pts, method="linear", kwargs={"fill_value": fill}).values
        else:
            vals = np.full(shape, float(da.values))
        out.append(_at_scatterers(vals, var))
    return out


def _displace_shared(scene: xr.Dataset, displacement: Displacement) -> xr.Dataset:
    """Move every scatterer of a shared scene (continuously; nothing dropped or re-binned)."""
    ndim = check_scene(scene)
    pos = [scene[a].values for a in _POSITIONS[:ndim]]
    moves = _shared_field_values(displacement, pos)
    out = scene.copy()
    for a, p, u in zip(_POSITIONS, pos, moves, strict=False):
        out[a] = ("scatterer", p + u, scene[a].attrs)
    return out


def _rebin(
    line: np.ndarray, z: np.ndarray, amp: np.ndarray, x: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group scatterers by A-line index into padded (count, width) arrays."""
    order = np.argsort(line, kind="stable")
    line, z, amp, x = line[order], z[order], amp[order], x[order]
    per_line = np.bincount(line, minlength=count)
    width = int(per_line.max(initial=0))
    start = np.concatenate([[0], np.cumsum(per_line)[:-1]])
    col = np.arange(line.size) - start[line]
    zz = np.zeros((count, width))
    aa = np.zeros((count, width), dtype=np.complex128)
    xx = np.zeros((count, width))
    zz[line, col], aa[line, col], xx[line, col] = z, amp, x
    return zz, aa, xx


def _stack(scenes: list[xr.Dataset], dim: str, values: np.ndarray, attrs: dict) -> xr.Dataset:
    """Concatenate displaced scenes along a new dim, padding the scatterer dim with zeros.

    Shared scenes keep ``amplitude`` and ``region`` without the new dim (only positions move).
    """
    if is_shared(scenes[0]):
        moved = [a for a in _POSITIONS if a in scenes[0]]
        out = xr.concat(
            scenes, dim=dim, data_vars=moved, coords="minimal", combine_attrs="override"
        )
        return out.assign_coords({dim: (dim, values, attrs)})
    width = max(s.sizes["scatterer"] for s in scenes)
    padded = [s.pad(scatterer=(0, width - s.sizes["scatterer"]), constant_values=0) for s in scenes]
    out = xr.concat(padded, dim=dim, combine_attrs="override")
    return out.assign_coords({dim: (dim, values, attrs)})


def uniaxial_strain(
    scene: xr.Dataset,
    strain: object,
    *,
    poisson_ratio: float = 0.0,
    x_centre: float | None = None,
    y_centre: float | None = None,
    wrap: bool = False,
) -> xr.Dataset:
    """Compress ``scene`` uniaxially from the surface ``z = 0`` for each strain.

    Works on the paper's independent A-lines (dims ``aline, scatterer``; a lateral Poisson
    expansion re-bins scatterers into lines) and on shared scenes (dim ``scatterer``; every
    scatterer moves continuously, ``z -> z(1 - s)``, ``x -> x + nu s (x - x_centre)`` and in
    3-D ``y -> y + nu s (y - y_centre)``; amplitudes and regions are unchanged).

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field, normally from :func:`deformable_scene` with the same strains (so it is
        populated deep enough; a warning-free check raises if it is not).
    strain : float or sequence of float
        Compressive strains in (-1, 1): ``u_z = -strain*z`` (see module docstring).
    poisson_ratio : float
        Lateral expansion ``u_x = poisson_ratio*strain*(x - x_centre)``, in [0, 0.5].
    x_centre : float, optional
        Lateral centre of the probe in µm; default the middle of the imaged A-lines (shared
        scenes: the middle of the scene's x window).
    y_centre : float, optional
        The same along ``y`` for 3-D shared scenes (default the middle of the y window).
    wrap : bool
        See :func:`displace` (independent A-lines only; for shared scenes the imaging step
        decides, :func:`speckle.imaging.scan.scan_image`).

    Returns
    -------
    xarray.Dataset
        Dims ``(strain, aline, scatterer)``; coordinate ``strain`` (dimensionless). Shared
        scenes: positions over ``(strain, scatterer)``, ``amplitude``/``region`` over
        ``scatterer``. Populate a shared scene down to :func:`required_depth` and laterally
        beyond the imaged lines by the expansion (``nu*s`` times the half-width) plus the beam.

    Raises
    ------
    ValueError
        If a strain is outside (-1, 1) or the scene is not populated deep enough for it.

    Examples
    --------
    >>> import speckle
    >>> kw = dict(n_pixels=32, depth_range=256.0, seed=1)
    >>> scene = speckle.deformable_scene(4, 2.0, strain=0.01, **kw)
    >>> frames = speckle.uniaxial_strain(scene, [0.0, 0.01])
    >>> frames.z.dims[0], frames.sizes[frames.z.dims[0]]
    ('strain', 2)
    """
    check_bool(wrap, "wrap")
    if not is_shared(scene):
        check_line_scene(scene)
    s = check_strain(strain)
    nu = check_real(poisson_ratio, "poisson_ratio", low=0.0, high=0.5)
    if is_shared(scene):
        return _uniaxial_shared(scene, s, nu, x_centre, y_centre)
    if y_centre is not None:
        check_real(y_centre, "y_centre")
        raise ValueError(
            "y_centre is for 3-D shared scenes; independent A-lines have no y (leave it None)"
        )
    h = depth_range_of(scene, "scene")
    need = required_depth(h, s)
    have = float(scene.attrs.get("z_max", h))
    if have < need * (1 - 1e-12):
        raise ValueError(
            f"scene is populated to {have:g} µm but strain up to {s.max():g} needs {need:g} µm; "
            "build it with deformable_scene(..., strain=...)"
        )
    if x_centre is None:
        first = int(scene.attrs.get("imaged_first", 0))
        count = int(scene.attrs.get("imaged_count", scene.sizes["aline"]))
        x_centre = float(scene.aline.values[first : first + count].mean())
    scenes = [
        displace(scene, uniaxial_displacement(si, poisson_ratio=nu, x_centre=x_centre), wrap=wrap)
        for si in s
    ]
    out = _stack(scenes, "strain", s, attrs("strain", "compressive strain"))
    out.attrs.update({"poisson_ratio": nu, "x_centre": x_centre, "deformation": "uniaxial"})
    return out


def _uniaxial_shared(
    scene: xr.Dataset, s: np.ndarray, nu: float, x_centre: float | None, y_centre: float | None
) -> xr.Dataset:
    ndim = check_scene(scene)

    def centre(value: float | None, axis: str) -> float:
        if value is not None:
            return check_real(value, f"{axis}_centre")
        lo, hi = scene.attrs.get(f"{axis}_min"), scene.attrs.get(f"{axis}_max")
        if lo is None or hi is None:
            return float(np.mean(scene[axis].values))
        return 0.5 * (float(lo) + float(hi))

    xc = centre(x_centre, "x")
    yc = centre(y_centre, "y") if ndim == 3 else 0.0
    fields = [uniaxial_displacement(si, poisson_ratio=nu, x_centre=xc, y_centre=yc) for si in s]
    out = _stack(
        [_displace_shared(scene, f) for f in fields],
        "strain",
        s,
        attrs("strain", "compressive strain"),
    )
    out.attrs.update({"poisson_ratio": nu, "x_centre": xc, "deformation": "uniaxial"})
    if ndim == 3:
        out.attrs["y_centre"] = yc
    return out


def translate(scene: xr.Dataset, dz: object, dx: float = 0.0, *, wrap: bool = False) -> xr.Dataset:
    """Rigid translation by ``dz`` µm in depth (scalar or sequence) and ``dx`` µm laterally.

    Returns a dataset with a ``shift`` dim (axial shift in µm) when ``dz`` is a sequence.
    Shared scenes move continuously (``wrap`` is then not used).

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(2, 2.0, n_pixels=16, depth_range=128.0, seed=1)
    >>> moved = speckle.translate(scene, 8.0)
    >>> round(float((moved.z - scene.z).max()), 9)
    8.0
    """
    check_bool(wrap, "wrap")
    if not is_shared(scene):
        check_line_scene(scene)
    dzs = as_finite_array(dz, "dz")
    if dzs.ndim > 1 or dzs.size == 0:
        raise ValueError(f"dz must be a scalar or a non-empty 1-D sequence (µm), got {dz!r}")
    dxv = check_real(dx, "dx")
    scenes = [
        displace(
            scene, lambda z, x, *_, d=d: (np.full(z.shape, d), np.full(z.shape, dxv)), wrap=wrap
        )
        for d in np.atleast_1d(dzs)
    ]
    if dzs.ndim == 0:
        return scenes[0]
    return _stack(scenes, "shift", np.atleast_1d(dzs), attrs("displacement", "axial translation"))


@renamed_parameters({"aline": "x"})
def pixel_displacement(displacement: Displacement, depth: np.ndarray, x: np.ndarray) -> xr.Dataset:
    """A displacement evaluated at pixel centres (material coordinates) of an image.

    Parameters
    ----------
    displacement : callable or xarray object
        As in :func:`displace`.
    depth, x : array_like
        Pixel-centre depths and lateral positions in µm (the image's coordinates ``depth``
        and ``x``; the retired keyword ``aline=`` is read as ``x=``, warning).

    Returns
    -------
    xarray.Dataset
        ``uz`` and ``ux`` in µm with dims ``(depth, x)``, on the image's grid.

    Examples
    --------
    >>> import numpy as np
    >>> from speckle.scene.deformation import pixel_displacement
    >>> u = pixel_displacement(lambda z, x: -0.01 * z, np.arange(3) * 8.0, np.arange(2) * 5.0)
    >>> u.uz.dims, u.uz.values[:, 0].tolist()
    (('depth', 'x'), [-0.0, -0.08, -0.16])
    """
    d = np.asarray(depth, float)
    a = np.asarray(x, float)
    zz, xx = np.meshgrid(d, a, indexing="ij")
    uz, ux = _field_values(displacement, zz, xx, xx)
    coords = {"depth": coord("depth", d), "x": coord("x", a)}
    return xr.Dataset(
        {
            "uz": (("depth", "x"), uz, attrs("displacement", "axial displacement")),
            "ux": (("depth", "x"), ux, attrs("displacement", "lateral displacement")),
        },
        coords=coords,
    )


@renamed_parameters({"aline": "x"})
def uniaxial_pixel_displacement(
    strain: object,
    depth: np.ndarray,
    x: np.ndarray,
    *,
    poisson_ratio: float = 0.0,
    x_centre: float | None = None,
) -> xr.Dataset:
    """Uniaxial-strain displacement at pixel centres, with a ``strain`` dim.

    Parameters
    ----------
    strain : float or array_like
        Uniaxial strain(s), compression > 0.
    depth, x : array_like
        Pixel-centre depths and lateral positions in µm (the image's coordinates ``depth``
        and ``x``; the retired keyword ``aline=`` is read as ``x=``, warning).
    poisson_ratio : float
        In ``[0, 0.5]``.
    x_centre : float, optional
        Lateral centre in µm; defaults to the middle of ``x`` (as in
        :func:`uniaxial_strain`).

    Returns
    -------
    xarray.Dataset
        ``uz``/``ux`` in µm with dims ``(strain, depth, x)``.

    Examples
    --------
    >>> import numpy as np
    >>> from speckle.scene.deformation import uniaxial_pixel_displacement
    >>> u = uniaxial_pixel_displacement([0.01, 0.02], np.arange(3) * 8.0, np.arange(2) * 5.0)
    >>> u.uz.dims, u.uz.sel(strain=0.02).values[:, 0].tolist()
    (('strain', 'depth', 'x'), [-0.0, -0.16, -0.32])
    """
    s = check_strain(strain)
    xc = float(np.mean(x)) if x_centre is None else x_centre
    fields = [
        pixel_displacement(
            uniaxial_displacement(si, poisson_ratio=poisson_ratio, x_centre=xc), depth, x
        )
        for si in s
    ]
    return xr.concat(fields, dim="strain").assign_coords(
        strain=coord("strain", s, "compressive strain")
    )


def _pitch(scene: xr.Dataset) -> float:
    """A-line pitch in µm from the ``aline`` coordinate (the attribute only for a single line)."""
    return spacing(scene, "aline", default=scene.attrs.get("aline_pitch", 1.0))
