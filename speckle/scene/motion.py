"""Scatterers in motion: Brownian, ballistic, flow (Poiseuille) and bulk motion, mixed per region.

Each model returns the scene with its positions ``z``, ``x`` [, ``y``] given at every time of
``times`` (s): a new leading dim ``time`` (coordinate in s) on the positions, amplitudes and
regions unchanged (a scatterer keeps its identity). The scene at ``times[0]`` is the input.
Models compose: a scene that already has a ``time`` dim (with the same times) gets the new
displacements added, so a phantom with static layers, Brownian "cells" and a vessel is
``flow_motion(brownian_motion(scene, t, regions=[cells], ...), t, regions=[vessel], ...)``.
:func:`speckle.imaging.timeseries.bscan_series` and :func:`~speckle.imaging.timeseries.mmode`
image such a scene.

Models (displacement ``d(t)`` of a moving scatterer since ``times[0]``, per axis it has):

* :func:`brownian_motion` -- independent Gaussian increments of variance ``2 D dt`` per axis
  (diffusion coefficient ``D`` in µm^2/s);
* :func:`ballistic_motion` -- straight lines at a constant random velocity per scatterer:
  ``distribution="gaussian"`` (Maxwell: every component ``N(0, speed^2/d)`` in a ``d``-D
  scene, so the rms speed is ``speed``) or ``"constant"`` (speed ``speed``, isotropic
  direction);
* :func:`flow_motion` -- a velocity vector (µm/s, one for all, or one per scatterer as
  :func:`poiseuille_velocity` gives for a vessel of given radius, centre and direction,
  flow through the imaging plane included in a 3-D scene);
* :func:`bulk_motion` -- the same displacement (µm) of every moving scatterer at each time
  (patient or sample motion).

Which scatterers move: ``regions`` (labels of :mod:`speckle.scene.regions`; default all) and,
in those, a ``fraction`` in ``[0, 1]`` drawn with the model's ``seed`` (:func:`moving_mask`):
the static and moving fractions of each region. The FEM or uniaxial deformation of
:mod:`speckle.scene.deformation` applies to the scene before motion (``displace`` then move),
or to any single time (``displace(moved.isel(time=i), field)``).

Bounds (refused before any work): ``times`` 1-D, finite and strictly increasing; ``D``, speeds
>= 0; and no scatterer may move by more than half the scene's extent along an axis between
two consecutive times (:data:`MAX_STEP_FRACTION`: with ``wrap`` the scene is periodic, and
a step above half its period is indistinguishable from a step the other way). The scene's
extent is its window (attributes ``z_min``/``z_max``, ...) or, without them, the span of its
positions. For Brownian motion the step bounded is the rms step ``sqrt(2 D dt)``.

``wrap`` (flow, ballistic and bulk motion; default ``True`` when the scene has its window
attributes): positions are taken modulo the window along each axis, so scatterers leaving
the window on one side re-enter on the other and the density stays steady (a re-entering
scatterer is a new, uncorrelated one for every line that saw it leave).

Randomness: one generator per call, ``SeedSequence(seed)``, draws the model's increments or
velocities for every scatterer (moving or not, so the draws do not depend on ``regions`` or
``fraction``); the moving fraction comes from the stream ``SeedSequence(seed,
spawn_key=(1,))``. Same scene, times and seed: same positions, whatever the workers or chunks
of the imaging that follows.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from .._validate import (
    as_finite_array,
    check_bool,
    check_choice,
    check_int,
    check_memory,
    check_real,
)
from ..conventions import coord, units_of
from .shared import check_not_empty

__all__ = [
    "BALLISTIC_DISTRIBUTIONS",
    "MAX_STEP_FRACTION",
    "ballistic_motion",
    "brownian_motion",
    "bulk_motion",
    "check_times",
    "flow_motion",
    "moving_mask",
    "poiseuille_velocity",
    "scene_extent",
]

#: Largest displacement between consecutive times, as a fraction of the scene's extent per axis.
MAX_STEP_FRACTION = 0.5
#: Speed distributions of :func:`ballistic_motion`.
BALLISTIC_DISTRIBUTIONS = ("gaussian", "constant")
_AXES = ("z", "x", "y")
#: bytes per scatterer per time per axis held while moving: the moved positions of every axis
#: (kept) plus one axis's increments in flight, counted as 3 arrays of float64 to be safe
_BYTES = 3 * 8


def check_times(times: object, name: str = "times") -> np.ndarray:
    """Times in s as a 1-D float array: finite, non-empty and strictly increasing.

    Raises
    ------
    TypeError
        If ``times`` is not an array of real numbers.
    ValueError
        Naming ``name``, if it is not 1-D, empty, or not strictly increasing.

    Examples
    --------
    >>> check_times([0.0, 0.01, 0.02])
    array([0.  , 0.01, 0.02])
    """
    t = as_finite_array(times, name)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D sequence of times in s, got {t.shape}")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise ValueError(
            f"{name} must be strictly increasing (s); times[{i}] = {t[i]!r} >= times[{i + 1}] = "
            f"{t[i + 1]!r}"
        )
    return t


def _axes(scene: xr.Dataset) -> list[str]:
    """Position variables of ``scene`` (shared: z, x[, y]; independent lines: z[, x])."""
    if not isinstance(scene, xr.Dataset) or "z" not in scene.data_vars:
        raise TypeError(
            "scene must be a scatterer Dataset with a position variable 'z' (a shared scene from "
            "speckle.shared_scene or independent lines from speckle.random_scatterers)"
        )
    check_not_empty(scene)
    return [a for a in _AXES if a in scene.data_vars]


def scene_extent(scene: xr.Dataset, axis: str) -> tuple[float, float] | None:
    """Window ``(lo, hi)`` of ``scene`` along ``axis`` in µm, or None if it has no such attrs.

    Examples
    --------
    >>> import xarray as xr
    >>> scene_extent(xr.Dataset(attrs={"z_min": 0.0, "z_max": 100.0}), "z")
    (0.0, 100.0)
    """
    lo, hi = scene.attrs.get(f"{axis}_min"), scene.attrs.get(f"{axis}_max")
    if lo is None or hi is None or not float(hi) > float(lo):
        return None
    return float(lo), float(hi)


def _extent(scene: xr.Dataset, axis: str) -> float:
    win = scene_extent(scene, axis)
    if win is not None:
        return win[1] - win[0]
    v = scene[axis].values
    return float(np.ptp(v)) if v.size else 0.0


def _check_step(scene: xr.Dataset, axes: Sequence[str], steps: dict[str, float], what: str):
    """Refuse a largest per-frame displacement above MAX_STEP_FRACTION of the scene's extent."""
    for a in axes:
        ext = _extent(scene, a)
        s = float(steps.get(a, 0.0))
        if s > MAX_STEP_FRACTION * ext:
            raise ValueError(
                f"{what} moves scatterers by up to {s:.4g} µm along {a} between two times, "
                f"above {MAX_STEP_FRACTION:g} x the scene's extent {ext:.4g} µm along {a} "
                "(speckle.scene.motion.MAX_STEP_FRACTION): use shorter intervals, a smaller "
                "velocity or a larger scene"
            )


def _check_scene_times(scene: xr.Dataset, times: np.ndarray) -> None:
    if "time" in scene.dims:
        have = np.asarray(scene["time"].values, float)
        if have.shape != times.shape or not np.allclose(have, times, rtol=1e-12, atol=0):
            raise ValueError(
                "scene already has a time dim with other times: motions combine only on the same "
                f"times (scene: {have.size} times from {have[0]:g} s; times: {times.size} from "
                f"{times[0]:g} s)"
            )


def moving_mask(
    scene: xr.Dataset,
    *,
    regions: Sequence[int] | None = None,
    fraction: float = 1.0,
    seed: int = 0,
) -> np.ndarray:
    """Which scatterers move: those in ``regions`` (all if None), a ``fraction`` of them.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (``region`` per scatterer) or independent lines (``regions`` must be None).
    regions : sequence of int, optional
        Region labels (:mod:`speckle.scene.regions`) whose scatterers move.
    fraction : float
        Moving fraction in ``[0, 1]`` of those scatterers (each independently, probability
        ``fraction``), drawn from ``SeedSequence(seed, spawn_key=(1,))``.
    seed : int
        Non-negative seed.

    Returns
    -------
    numpy.ndarray of bool
        Shaped like one time of the scene's ``z`` (``(scatterer,)`` or ``(aline, scatterer)``).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> sc = xr.Dataset({"z": ("scatterer", [1.0, 2.0]), "region": ("scatterer", [0, 1])})
    >>> moving_mask(sc, regions=[1]).tolist()
    [False, True]
    """
    _axes(scene)
    f = check_real(fraction, "fraction", low=0.0, high=1.0)
    sd = check_int(seed, "seed", low=0)
    z = scene.z.isel(time=0) if "time" in scene.z.dims else scene.z
    shape = z.shape
    if regions is None:
        mask = np.ones(shape, bool)
    else:
        if "region" not in scene:
            raise ValueError("regions= needs a scene with a 'region' variable (a shared scene)")
        labels = np.asarray(
            [check_int(r, "regions[i]", low=0) for r in np.atleast_1d(np.asarray(regions))]
        )
        reg = scene.region.values
        if reg.shape != shape:
            reg = np.broadcast_to(reg, shape)
        mask = np.isin(reg, labels)
    if f < 1.0:
        rng = np.random.default_rng(np.random.SeedSequence(sd, spawn_key=(1,)))
        mask &= rng.random(shape) < f
    return mask


def _moved(
    scene: xr.Dataset,
    times: np.ndarray,
    displacement: dict[str, np.ndarray],
    mask: np.ndarray,
    *,
    wrap: bool,
    model: dict,
) -> xr.Dataset:
    """The scene with ``time`` on its positions: position + displacement where ``mask``."""
    out = {}
    has_time = "time" in scene.dims
    everyone = bool(mask.all())
    for a, make in displacement.items():  # in order: the generator's draws follow the axes
        v = scene[a]
        base = v.transpose("time", ...).values if has_time else v.values[None]
        dims = ("time", *(v.dims if not has_time else [x for x in v.dims if x != "time"]))
        d = make() if callable(make) else make  # a fresh (time, ...) array, updated in place
        pos = d if everyone else np.where(mask[None], d, 0.0)
        if pos.shape == np.broadcast_shapes(pos.shape, base.shape):
            pos += base  # in place: one (time, ...) array per axis, memory T x M per axis
        else:
            pos = pos + base  # a displacement broadcast over the scatterers (one velocity)
        if wrap:
            win = scene_extent(scene, a)
            if win is not None:
                pos -= win[0]
                np.mod(pos, win[1] - win[0], out=pos)
                pos += win[0]
        out[a] = (dims, pos, v.attrs)
        del d
    res = scene.assign(out)
    if not has_time:
        res = res.assign_coords(time=coord("time", times, "time of the positions"))
    before = str(scene.attrs.get("motion", ""))
    res.attrs["motion"] = f"{before}+{model['name']}" if before else model["name"]
    for k, v in model.items():
        if k != "name":
            res.attrs[f"{model['name']}_{k}"] = v
    res.attrs["moving_count"] = int(res.attrs.get("moving_count", 0)) + int(mask.sum())
    return res


def _prepare(scene, times, regions, fraction, seed):
    axes = _axes(scene)
    t = check_times(times)
    _check_scene_times(scene, t)
    mask = moving_mask(scene, regions=regions, fraction=fraction, seed=seed)
    check_memory(
        _BYTES * t.size * mask.size * len(axes),
        "times or the scene's scatterers",
        f"{t.size} times x {mask.size} scatterers x {len(axes)} axes",
    )
    return axes, t, mask


def _wrap_default(scene: xr.Dataset, wrap: bool | None, axes: Sequence[str]) -> bool:
    if wrap is None:
        return all(scene_extent(scene, a) is not None for a in axes)
    return check_bool(wrap, "wrap")


def brownian_motion(
    scene: xr.Dataset,
    times: object,
    *,
    diffusion: float,
    seed: int,
    regions: Sequence[int] | None = None,
    fraction: float = 1.0,
) -> xr.Dataset:
    """Scatterers in Brownian motion: Gaussian increments of variance ``2 D dt`` per axis.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (``z``, ``x`` [, ``y``] move) or independent lines (``z`` moves), with or
        without a ``time`` dim from another motion (then on the same times).
    times : array_like
        Times in s, strictly increasing; the scene is the positions at ``times[0]``.
    diffusion : float
        Diffusion coefficient ``D`` in µm^2/s, >= 0.
    seed : int
        Non-negative seed of the increments (and of the moving fraction).
    regions, fraction
        Which scatterers move (:func:`moving_mask`).

    Returns
    -------
    xarray.Dataset
        Positions over ``(time, ...)``; coordinate ``time`` (s); attrs record the model.

    Raises
    ------
    ValueError
        ``D < 0``, times not strictly increasing, or an rms step ``sqrt(2 D dt)`` above
        :data:`MAX_STEP_FRACTION` of the scene's extent.

    Notes
    -----
    A dense scene's field autocorrelation is ``exp(-q^2 D tau)``, ``q = 2 k0``
    (:func:`speckle.analysis.dynamics.g1_brownian`). Without ``regions``/``fraction`` and with
    uniform times, the positions are those of the former ``brownian_frames`` bit for bit.

    Examples
    --------
    >>> import speckle
    >>> sc = speckle.random_scatterers(2, 4.0, n_pixels=8, depth_range=64.0, seed=1)
    >>> brownian_motion(sc, [0.0, 0.1], diffusion=1.0, seed=2).z.dims
    ('time', 'aline', 'scatterer')
    """
    d = check_real(diffusion, "diffusion", low=0)
    sd = check_int(seed, "seed", low=0)
    axes, t, mask = _prepare(scene, times, regions, fraction, sd)
    dts = np.diff(t)
    if dts.size:
        _check_step(scene, axes, {a: np.sqrt(2 * d * dts.max()) for a in axes}, "diffusion")
    if dts.size and np.allclose(dts, dts[0], rtol=1e-12, atol=0):  # uniform: one step size
        step: float | np.ndarray = np.sqrt(2 * d * dts[0])
    else:
        step = np.sqrt(2 * d * np.concatenate([[0.0], dts]))
    rng = np.random.default_rng(np.random.SeedSequence(sd))
    scale = step if np.ndim(step) == 0 else step.reshape(-1, *[1] * mask.ndim)

    def increments() -> np.ndarray:  # drawn when its axis is moved (z, then x, then y)
        inc = rng.standard_normal((t.size, *mask.shape))
        inc *= scale
        inc[0] = 0.0
        return np.cumsum(inc, axis=0, out=inc)

    disp = dict.fromkeys(axes, increments)
    model = {"name": "brownian", "diffusion": d, "seed": sd, "fraction": float(fraction)}
    model["diffusion_units"] = units_of("diffusion")
    return _moved(scene, t, disp, mask, wrap=False, model=model)


def _velocity_steps(scene, axes, velocity: np.ndarray, t: np.ndarray, what: str):
    """Check the largest per-frame displacement of velocities (M, d) or (d,) in µm/s."""
    if t.size < 2:
        return
    dt = float(np.diff(t).max())
    v = np.abs(np.asarray(velocity)).reshape(-1, len(axes))
    vmax = v.max(axis=0) if v.size else np.zeros(len(axes))
    _check_step(scene, axes, {a: vmax[i] * dt for i, a in enumerate(axes)}, what)


def _check_velocity(velocity: object, axes: Sequence[str], shape: tuple[int, ...]) -> np.ndarray:
    """A velocity vector (d,) or per-scatterer vectors (*shape, d) in µm/s, axes (z, x[, y])."""
    v = as_finite_array(velocity, "velocity")
    d = len(axes)
    if v.shape == (d,) or v.shape == (*shape, d):
        return v
    raise ValueError(
        f"velocity must be one vector of {d} components ({', '.join(axes)}) in µm/s or one per "
        f"scatterer, shape {(*shape, d)}; got shape {v.shape}"
        + (
            " (a 2-D scene has no y axis: flow through the imaging plane needs a 3-D scene)"
            if d == 2 and v.shape[-1:] == (3,)
            else ""
        )
    )


def flow_motion(
    scene: xr.Dataset,
    times: object,
    *,
    velocity: object,
    regions: Sequence[int] | None = None,
    fraction: float = 1.0,
    seed: int = 0,
    wrap: bool | None = None,
) -> xr.Dataset:
    """Directed flow: every moving scatterer at its velocity, ``r(t) = r0 + v (t - t0)``.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (or independent lines, moving along ``z`` only).
    times : array_like
        Times in s, strictly increasing.
    velocity : array_like
        µm/s: one vector ``(v_z, v_x[, v_y])`` for all, or one per scatterer (shape of ``z``
        plus the axis), e.g. :func:`poiseuille_velocity`. ``v_z > 0`` moves deeper.
    regions, fraction, seed
        Which scatterers move (:func:`moving_mask`).
    wrap : bool, optional
        Periodic window (see the module docstring); default: when the scene has its window.

    Returns
    -------
    xarray.Dataset
        Positions over ``(time, ...)``, coordinate ``time`` in s.

    Raises
    ------
    ValueError
        A velocity of the wrong shape (a through-plane component in a 2-D scene), times not
        strictly increasing, or a step ``|v| dt`` above :data:`MAX_STEP_FRACTION` of the
        scene's extent along an axis.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene.regions import background, make_regions
    >>> sc = speckle.shared_scene(make_regions(background(density=0.1)), z_range=(0, 32),
    ...                           x_range=(0, 32), seed=1)
    >>> flow_motion(sc, [0.0, 0.01], velocity=[0.0, 100.0]).x.sizes["time"]
    2
    """
    axes, t, mask = _prepare(scene, times, regions, fraction, seed)
    v = _check_velocity(velocity, axes, mask.shape)
    _velocity_steps(scene, axes, v, t, "velocity")
    w = _wrap_default(scene, wrap, axes)
    dt = (t - t[0]).reshape(-1, *[1] * mask.ndim)
    disp = {a: dt * (v[..., i] if v.ndim > 1 else v[i]) for i, a in enumerate(axes)}
    vmax = float(np.max(np.linalg.norm(v.reshape(-1, len(axes)), axis=-1))) if v.size else 0.0
    model = {"name": "flow", "peak_speed": vmax, "wrap": int(w)}
    if v.ndim == 1:
        model["velocity"] = v.tolist()
    model["peak_speed_units"] = units_of("velocity")
    return _moved(scene, t, disp, mask, wrap=w, model=model)


def poiseuille_velocity(
    scene: xr.Dataset,
    *,
    peak_velocity: float,
    radius: float,
    centre: Sequence[float],
    direction: Sequence[float],
) -> np.ndarray:
    """Per-scatterer velocity of laminar (Poiseuille) flow in a straight vessel.

    ``v(r) = v_max (1 - r^2/R^2) e`` inside the vessel (``r < R``, ``r`` the distance to its
    axis: the line through ``centre`` along the unit vector ``e`` of ``direction``), 0 outside.
    The mean velocity over the cross-section is ``v_max/2``.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (2-D ``(z, x)`` or 3-D ``(z, x, y)``), without a ``time`` dim.
    peak_velocity : float
        Centre-line speed ``v_max`` in µm/s (>= 0).
    radius : float
        Vessel radius ``R`` in µm (> 0).
    centre : sequence of float
        A point of the axis, ``(z, x[, y])`` in µm.
    direction : sequence of float
        Flow direction ``(z, x[, y])`` (normalised here, non-zero). In a 3-D scene
        ``(0, 0, 1)`` is flow through the B-scan plane (along ``y``); a 2-D scene has no
        through-plane direction.

    Returns
    -------
    numpy.ndarray
        Velocities in µm/s, shape ``(scatterer, d)``, for :func:`flow_motion`.

    Examples
    --------
    >>> import xarray as xr
    >>> sc = xr.Dataset({"z": ("scatterer", [50.0, 55.0, 70.0]), "x": ("scatterer", [0.0] * 3),
    ...                  "amplitude": ("scatterer", [1.0 + 0j] * 3)})
    >>> poiseuille_velocity(sc, peak_velocity=1000.0, radius=10.0, centre=(50.0, 0.0),
    ...                     direction=(0.0, 1.0))[:, 1].tolist()
    [1000.0, 750.0, 0.0]
    """
    axes = _axes(scene)
    if scene.z.dims != ("scatterer",):
        raise ValueError("poiseuille_velocity needs a shared scene without a time dim")
    vmax = check_real(peak_velocity, "peak_velocity", low=0)
    rad = check_real(radius, "radius", low=0, low_inclusive=False)
    d = len(axes)
    c = as_finite_array(centre, "centre")
    e = as_finite_array(direction, "direction")
    if c.shape != (d,) or e.shape != (d,):
        raise ValueError(
            f"centre and direction must have {d} components ({', '.join(axes)}) for this "
            f"{d}-D scene, got shapes {c.shape}, {e.shape}"
            + (" (flow through the imaging plane needs a 3-D scene)" if d == 2 else "")
        )
    norm = float(np.linalg.norm(e))
    if norm == 0:
        raise ValueError("direction must be a non-zero vector")
    e = e / norm
    p = np.stack([scene[a].values for a in axes], axis=-1) - c
    along = p @ e
    r2 = np.sum(p**2, axis=-1) - along**2
    speed = np.where(r2 < rad**2, vmax * (1 - r2 / rad**2), 0.0)
    return speed[:, None] * e[None, :]


def ballistic_motion(
    scene: xr.Dataset,
    times: object,
    *,
    speed: float,
    seed: int,
    distribution: str = "gaussian",
    regions: Sequence[int] | None = None,
    fraction: float = 1.0,
    wrap: bool | None = None,
) -> xr.Dataset:
    """Random ballistic motion: each scatterer in a straight line at its own random velocity.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene (``d`` = 2 or 3 axes) or independent lines (``d`` = 1, ``z`` only).
    times : array_like
        Times in s, strictly increasing.
    speed : float
        µm/s, >= 0. ``distribution="gaussian"``: the rms speed; each velocity component is
        ``N(0, speed^2/d)`` (Maxwell speeds in 3-D, Rayleigh in 2-D). ``"constant"``: every
        scatterer's speed, in an isotropic random direction.
    seed : int
        Non-negative seed of the velocities (and the moving fraction).
    distribution : {"gaussian", "constant"}
        Speed distribution (above).
    regions, fraction
        Which scatterers move (:func:`moving_mask`).
    wrap : bool, optional
        Periodic window (module docstring); default when the scene has its window.

    Returns
    -------
    xarray.Dataset
        Positions over ``(time, ...)``.

    Notes
    -----
    Gaussian velocities give the Gaussian decay ``g1 = exp(-q^2 sigma^2 tau^2/2)``,
    ``sigma^2 = speed^2/d``, ``q = 2 k0`` (:func:`speckle.analysis.dynamics.g1_ballistic`).
    The step bound uses ``speed`` (rms) for "gaussian", the speed itself for "constant".

    Examples
    --------
    >>> import speckle
    >>> sc = speckle.random_scatterers(2, 4.0, n_pixels=8, depth_range=64.0, seed=1)
    >>> ballistic_motion(sc, [0.0, 0.1], speed=1.0, seed=2).z.sizes["time"]
    2
    """
    s = check_real(speed, "speed", low=0)
    sd = check_int(seed, "seed", low=0)
    check_choice(distribution, "distribution", BALLISTIC_DISTRIBUTIONS)
    axes, t, mask = _prepare(scene, times, regions, fraction, sd)
    d = len(axes)
    if t.size > 1:
        step = s * float(np.diff(t).max())
        _check_step(scene, axes, dict.fromkeys(axes, step), "speed")
    rng = np.random.default_rng(np.random.SeedSequence(sd))
    g = rng.standard_normal((*mask.shape, d))
    if distribution == "gaussian":
        v = g * (s / np.sqrt(d))
    else:
        n = np.linalg.norm(g, axis=-1, keepdims=True)
        v = s * g / np.where(n > 0, n, 1.0)
    w = _wrap_default(scene, wrap, axes)
    dt = (t - t[0]).reshape(-1, *[1] * mask.ndim)
    disp = {a: dt * v[..., i] for i, a in enumerate(axes)}
    model = {"name": "ballistic", "speed": s, "distribution": distribution, "seed": sd}
    model["speed_units"] = units_of("velocity")
    return _moved(scene, t, disp, mask, wrap=w, model=model)


def bulk_motion(
    scene: xr.Dataset,
    times: object,
    *,
    displacement: object,
    regions: Sequence[int] | None = None,
    fraction: float = 1.0,
    seed: int = 0,
    wrap: bool | None = None,
) -> xr.Dataset:
    """Bulk (rigid) motion: every moving scatterer displaced by the same vector at each time.

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene or independent lines.
    times : array_like
        Times in s, strictly increasing.
    displacement : array_like
        Shape ``(len(times), d)``: the displacement ``(dz, dx[, dy])`` in µm at each time,
        relative to the scene (row 0 is usually zeros).
    regions, fraction, seed
        Which scatterers move (:func:`moving_mask`).
    wrap : bool, optional
        Periodic window (module docstring); default when the scene has its window.

    Returns
    -------
    xarray.Dataset
        Positions over ``(time, ...)``.

    Examples
    --------
    >>> import speckle
    >>> sc = speckle.random_scatterers(1, 4.0, n_pixels=8, depth_range=64.0, seed=1)
    >>> out = bulk_motion(sc, [0.0, 1.0], displacement=[[0.0], [2.0]], wrap=False)
    >>> float((out.z.isel(time=1) - out.z.isel(time=0)).max())
    2.0
    """
    axes, t, mask = _prepare(scene, times, regions, fraction, seed)
    u = as_finite_array(displacement, "displacement")
    if u.shape != (t.size, len(axes)):
        raise ValueError(
            f"displacement must have shape (len(times), {len(axes)}) = {(t.size, len(axes))} "
            f"(µm along {', '.join(axes)}), got {u.shape}"
        )
    if t.size > 1:
        jumps = np.abs(np.diff(u, axis=0)).max(axis=0)
        _check_step(scene, axes, dict(zip(axes, jumps, strict=True)), "displacement")
    w = _wrap_default(scene, wrap, axes)
    shape = (-1, *[1] * mask.ndim)
    disp = {a: u[:, i].reshape(shape) + np.zeros((1, *mask.shape)) for i, a in enumerate(axes)}
    model = {"name": "bulk", "max_displacement": float(np.abs(u).max()) if u.size else 0.0}
    model["max_displacement_units"] = units_of("displacement")
    return _moved(scene, t, disp, mask, wrap=w, model=model)
