"""Relative backscattering strength per layer or region (off by default).

A medium whose scatterers reflect ``b`` times more intensity has amplitudes ``sqrt(b) a_j``: the
mean speckle intensity scales by ``b`` and the speckle statistics are unchanged.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..scene._layers import property_profile
from ._scene import check_scene, region_property, scale_amplitudes

__all__ = ["backscatter", "backscatter_regions"]


def backscatter(scene: xr.Dataset, value: float | xr.Dataset) -> xr.Dataset:
    """Scale scatterer intensities by the backscatter of their layer.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field (``z`` in µm, ``amplitude``).
    value : float or xarray.Dataset
        Relative backscattered intensity (>= 0), or layers with ``backscatter``.

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> bright = speckle.backscatter(scene, 4.0)
    >>> float(abs(bright.amplitude).max() / abs(scene.amplitude).max())
    2.0
    """
    check_scene(scene)
    try:
        b = xr.apply_ufunc(
            property_profile, scene.z, kwargs={"value": value, "name": "backscatter"}
        )
    except (TypeError, ValueError) as exc:  # name the parameter as the caller wrote it
        raise type(exc)(f"value: {exc}") from None
    return scale_amplitudes(scene, np.sqrt(b))


def backscatter_regions(
    scene: xr.Dataset, labels: xr.DataArray | None, properties: xr.Dataset
) -> xr.Dataset:
    """Scale scatterer intensities by the ``backscatter`` of the region they lie in.

    The region of a scatterer is the label of the nearest pixel of ``labels`` (dims
    ``(depth, x)``, µm coordinates); ``properties`` is the per-region table (dim ``region``).
    Scatterers at label ``-1`` (no region) get amplitude 0. ``labels=None`` uses a shared
    scene's ``region`` variable (note that :func:`speckle.shared_scene` already scales its
    amplitudes by the regions' ``backscatter``: apply this only to scenes drawn without it).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05, backscatter=4.0))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> grid = np.arange(-32.0, 68.0, 4.0)  # label columns over the scene's lateral range
    >>> labels = speckle.rasterize(regions, speckle.pixel_depths(32, 256.0), grid)
    >>> bright = speckle.backscatter_regions(scene, labels, regions)
    >>> round(float(abs(bright.amplitude).max() / abs(scene.amplitude).max()), 6)  # sqrt(4)
    2.0
    """
    check_scene(scene)
    b = region_property(scene, labels, properties, "backscatter", outside=0.0)
    return scale_amplitudes(scene, np.sqrt(b), backscatter="by region")
