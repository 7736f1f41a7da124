"""Beer-Lambert attenuation of the probing light (off unless applied).

Convention (the usual one in OCT): ``mu_t`` is the *intensity* attenuation (extinction)
coefficient in 1/µm; light reaching depth ``z`` and returning has travelled ``2 z``, so the
round-trip intensity factor is ``exp(-2 int_0^z mu_t dz')`` and the *amplitude* factor of a
scatterer at depth ``z`` is ``exp(-int_0^z mu_t dz')``. The mean log intensity then falls with
slope ``-2 mu_t`` (natural log per µm), i.e. ``-20 mu_t/ln 10`` dB per µm.

Attenuation acts on each scatterer by its own depth (exact: the light reaching a scatterer is
attenuated along its own path) rather than on the pixels after imaging (which would smear the
attenuation over the point-spread function and misplace it for wrapped-around scatterers). The
depth is measured from ``z = 0`` (the surface at the zero delay); a layered or per-region medium
uses the path integral of ``mu_t`` (exact for layers; for a label image a cumulative sum along
depth, midpoint rule per pixel).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array
from ..conventions import attrs, spacing, units_of
from ..scene._layers import property_integral, region_values, sample_map
from ._scene import check_scene, lateral_positions, scale_amplitudes

__all__ = ["attenuate", "attenuate_regions", "attenuation_map", "optical_depth"]


def optical_depth(z: object, attenuation: float | xr.Dataset) -> np.ndarray:
    """One-way optical depth ``tau(z) = int_0^z mu_t dz'`` (dimensionless).

    Parameters
    ----------
    z : array_like
        Depths in µm.
    attenuation : float or xarray.Dataset
        ``mu_t`` in 1/µm (>= 0), or layers from :func:`speckle.layer_stack` with ``attenuation``.

    Examples
    --------
    >>> import speckle
    >>> speckle.optical_depth([0.0, 100.0, 200.0], 0.002)  # mu z, mu in 1/µm
    array([0. , 0.2, 0.4])
    """
    return property_integral(as_finite_array(z, "z"), attenuation, "attenuation")


def attenuate(scene: xr.Dataset, attenuation: float | xr.Dataset) -> xr.Dataset:
    """Scale each scatterer's amplitude by the round-trip Beer-Lambert factor ``exp(-tau(z))``.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field (variables ``z`` in µm and ``amplitude``), any dims.
    attenuation : float or xarray.Dataset
        Intensity attenuation coefficient ``mu_t`` in 1/µm (>= 0, finite) or layers.

    Returns
    -------
    xarray.Dataset
        The scene with amplitudes ``a_j exp(-tau(z_j))`` (intensities ``|a_j|^2 exp(-2 tau)``);
        attribute ``attenuation`` records ``mu_t`` (NaN for layers).

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> dim = speckle.attenuate(scene, 0.002)
    >>> bool((abs(dim.amplitude) <= abs(scene.amplitude)).all())
    True
    """
    check_scene(scene)
    tau = xr.apply_ufunc(optical_depth, scene.z, kwargs={"attenuation": attenuation})
    mu = float(attenuation) if not isinstance(attenuation, xr.Dataset) else np.nan
    return scale_amplitudes(
        scene, np.exp(-tau), attenuation=mu, attenuation_units=units_of("attenuation")
    )


def attenuation_map(labels: xr.DataArray, properties: xr.Dataset) -> xr.DataArray:
    """Round-trip amplitude factor ``exp(-tau)`` at every pixel of a label image.

    ``tau`` at pixel ``q`` of each column is ``dz (sum_{p<q} mu_p + mu_q/2)`` (the path integral
    through the regions above, midpoint rule; exact for a constant ``mu``), with ``dz`` the
    ``depth`` spacing; above the first row (down from ``z = 0``) the top row's region is
    assumed, so a constant ``mu`` gives exactly ``tau = mu z``.

    Parameters
    ----------
    labels : xarray.DataArray
        Integer label image with a uniform ``depth`` coordinate (µm), e.g. dims ``(depth, x)``.
    properties : xarray.Dataset
        Per-region table with dim ``region`` holding ``attenuation`` (1/µm); label ``-1`` (no
        region) does not attenuate.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.layer(100.0, 200.0, density=0.1, attenuation=0.002)
    ... )
    >>> labels = speckle.rasterize(regions, np.arange(0.0, 300.0, 50.0), np.array([0.0]))
    >>> speckle.attenuation_map(labels, regions).values[:, 0].round(4)  # exp(-tau), tau = dz sum mu
    array([1.    , 1.    , 0.9512, 0.8607, 0.8187, 0.8187])
    """
    mu = region_values(labels, properties, "attenuation", outside=0.0)
    dz = spacing(labels, "depth")
    z0 = float(labels.depth.values[0])
    tau = dz * (mu.cumsum("depth") - mu / 2) + mu.isel(depth=0) * (z0 - dz / 2)
    return np.exp(-tau).assign_attrs(
        attrs("dimensionless", "round-trip amplitude factor exp(-int mu_t dz)")
    )


def attenuate_regions(
    scene: xr.Dataset, labels: xr.DataArray, properties: xr.Dataset
) -> xr.Dataset:
    """Attenuate each scatterer by the path integral of ``mu_t`` through a labelled scene.

    The optical depth of :func:`attenuation_map` (a fine label grid makes it exact at region
    boundaries) is interpolated linearly in depth at each scatterer, in the label column nearest
    its lateral position (variable ``x`` of a shared scene, else the ``aline`` coordinate).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05, attenuation=0.001))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> grid = np.arange(-32.0, 68.0, 4.0)  # label columns over the scene's lateral range
    >>> labels = speckle.rasterize(regions, speckle.pixel_depths(32, 256.0), grid)
    >>> dim = speckle.attenuate_regions(scene, labels, regions)
    >>> bool((abs(dim.amplitude) <= abs(scene.amplitude)).all())
    True
    """
    check_scene(scene)
    tau = -np.log(attenuation_map(labels, properties))
    x = lateral_positions(scene)
    factor = xr.apply_ufunc(lambda z, xx: np.exp(-sample_map(tau, z, xx)), scene.z, x)
    return scale_amplitudes(scene, factor, attenuation="by region")
