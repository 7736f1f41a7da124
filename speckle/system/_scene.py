"""Helpers shared by the system effects that act on scatterer fields (not public)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..scene._layers import region_values, sample_map
from ..scene.shared import check_not_empty


def check_scene(scene: object) -> xr.Dataset:
    """A scatterer field with variables ``z`` (µm) and ``amplitude`` (``TypeError`` otherwise)."""
    if not isinstance(scene, xr.Dataset) or not {"z", "amplitude"} <= set(scene.data_vars):
        raise TypeError("scene must be an xarray.Dataset with variables 'z' and 'amplitude'")
    check_not_empty(scene)
    return scene


def scale_amplitudes(scene: xr.Dataset, factor: object, **attrs: object) -> xr.Dataset:
    """Multiply scatterer amplitudes by ``factor`` (shaped like ``scene.z``), record ``attrs``."""
    amp = scene.amplitude * factor
    out = scene.assign(amplitude=amp.assign_attrs(scene.amplitude.attrs))
    return out.assign_attrs(attrs)


def line_rng(seed: int, line: int, stream: int) -> np.random.Generator:
    """Generator of A-line ``line`` for one effect (``stream``): independent of the scatterers'.

    The scatterers of line ``i`` use ``SeedSequence(seed, spawn_key=(i,))``; effects use
    ``spawn_key=(i, stream)``, so adding an effect never changes the scene.
    """
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(line, stream)))


def lateral_positions(scene: xr.Dataset) -> xr.DataArray:
    """Lateral position of every scatterer (µm): variable ``x``, else the ``aline`` coordinate."""
    if "x" in scene.data_vars:
        return scene.x
    if "aline" in scene.coords:
        return scene.aline.broadcast_like(scene.z)
    raise ValueError("scene needs a variable 'x' or an 'aline' coordinate (µm)")


def region_property(
    scene: xr.Dataset,
    labels: xr.DataArray | None,
    properties: xr.Dataset,
    name: str,
    outside: float | None = None,
) -> xr.DataArray:
    """Property ``name`` of the region holding each scatterer (label of the nearest pixel).

    ``labels`` has dims ``(depth, x)`` (µm coordinates, uniform depth step); ``properties`` is
    the per-region table (dim ``region``). Depths snap to the nearest row, so no value is
    blended across a boundary. ``outside`` is the value for label ``-1`` (no region).
    ``labels=None``: a shared scene's own ``region`` variable (the label of each scatterer).
    """
    if labels is None:
        if "region" not in scene.data_vars:
            raise ValueError("give labels (a label image) or a scene with a 'region' variable")
        return region_values(scene.region, properties, name, outside=outside)
    values = region_values(labels, properties, name, outside=outside)
    d = np.asarray(labels.depth.values, dtype=float)
    step = float(d[1] - d[0]) if d.size > 1 else 1.0

    def nearest(z, x):
        return sample_map(values, d[0] + np.rint((np.asarray(z) - d[0]) / step) * step, x)

    return xr.apply_ufunc(nearest, scene.z, lateral_positions(scene))
