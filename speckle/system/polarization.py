"""Polarization: co- and cross-polarized detection channels (off by default).

A polarization-sensitive OCT measures the backscattered field in the polarization of the
illumination (``co``) and the orthogonal one (``cross``). Here each scatterer sends the fraction
``1 - f`` of its intensity into the co channel and ``f`` (the *depolarization fraction*, per
layer or region) into the cross channel with an independent, uniformly distributed phase:

    a_co = sqrt(1 - f) a_j,     a_cross = sqrt(f) |a_j| exp(i theta_j),   theta_j ~ U[0, 2 pi).

The two channels are then uncorrelated speckle patterns with mean intensities ``(1 - f) <I>`` and
``f <I>``: cross/co ratio ``f/(1 - f)``. For fully developed speckle in both (Goodman, *Speckle
Phenomena in Optics*, sec. 3.4-3.5) the degree of polarization of the pooled Stokes vector is
``P = |1 - 2 f|``, the polarization-insensitive intensity ``I = I_co + I_cross`` has contrast
``sqrt((1 + P^2)/2)`` and density

    p(I) = [exp(-2 I/((1 + P) <I>)) - exp(-2 I/((1 - P) <I>))] / (P <I>)

(``exp(-I/<I>)/<I>`` for ``P = 1``; ``4 I/<I>^2 exp(-2 I/<I>)`` for ``P = 0``).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_int, check_real
from ..conventions import attrs
from ..scene._layers import property_profile
from ._scene import check_scene, line_rng, region_property

__all__ = [
    "CHANNELS",
    "degree_of_polarization",
    "depolarize",
    "total_intensity_contrast",
    "total_intensity_pdf",
]

CHANNELS = ("co", "cross")
_STREAM = 102


def depolarize(
    scene: xr.Dataset,
    depolarization: float | xr.Dataset,
    *,
    seed: int,
    labels: xr.DataArray | None = None,
) -> xr.Dataset:
    """Split each scatterer into co- and cross-polarized amplitudes (new dim ``channel``).

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field, e.g. dims ``(aline, scatterer)`` (others carried through), or a
        shared scene (variable ``x``).
    depolarization : float or xarray.Dataset
        Cross-polarized fraction ``f`` in [0, 1]; or layers with ``depolarization``; or, with
        ``labels``, a per-region table (dim ``region``).
    seed : int
        Seed of the cross-channel phases (A-line ``i`` uses its own stream; a scene without
        an ``aline`` dim uses one stream).
    labels : xarray.DataArray, optional
        Label image ``(depth, x)``: ``f`` of the region holding each scatterer. A per-region
        table without ``labels`` uses a shared scene's own ``region`` variable.

    Returns
    -------
    xarray.Dataset
        ``amplitude`` with a leading dim ``channel`` = ``("co", "cross")``; image it with
        :func:`speckle.bscan` to get both channels.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> both = speckle.depolarize(scene, 0.3, seed=2)
    >>> both.amplitude.dims[0], [str(c) for c in both.channel.values]
    ('channel', ['co', 'cross'])
    """
    check_scene(scene)
    if "channel" in scene.amplitude.dims:
        raise ValueError(
            "scene is already depolarized (its amplitude has a 'channel' dim, co and cross): "
            "depolarize the original scene once, with the total depolarization"
        )
    sd = check_int(seed, "seed", low=0)
    by_region = isinstance(depolarization, xr.Dataset) and "region" in depolarization.dims
    if labels is not None or by_region:
        f = region_property(scene, labels, depolarization, "depolarization", outside=0.0)
    else:
        f = xr.apply_ufunc(
            property_profile, scene.z, kwargs={"value": depolarization, "name": "depolarization"}
        )
    if "aline" in scene.amplitude.dims:
        amp = scene.amplitude.transpose("aline", ...)
        theta = np.stack(
            [
                line_rng(sd, i, _STREAM).uniform(0, 2 * np.pi, amp.shape[1:])
                for i in range(amp.shape[0])
            ]
        )
    else:
        amp = scene.amplitude
        theta = line_rng(sd, 0, _STREAM).uniform(0, 2 * np.pi, amp.shape)
    cross = abs(amp) * np.exp(1j * theta) * np.sqrt(f)
    co = amp * np.sqrt(1 - f)
    both = xr.concat([co, cross.transpose(*co.dims)], dim="channel").assign_coords(
        channel=list(CHANNELS)
    )
    mean_f = np.nan if isinstance(depolarization, xr.Dataset) else float(depolarization)
    dims = ("channel", *scene.amplitude.dims)
    z = scene.z.broadcast_like(both).transpose(*dims)  # both channels see the same depths
    out = scene.assign(amplitude=both.transpose(*dims), z=z.assign_attrs(scene.z.attrs))
    return out.assign_attrs(depolarization=mean_f, polarization_seed=sd)


def degree_of_polarization(image: xr.Dataset, dims: object = None) -> xr.DataArray:
    """Degree of polarization of the pooled Stokes vector of a two-channel image.

    ``P = sqrt(S1^2 + S2^2 + S3^2)/S0`` with ``S0 = <I_co + I_x>``, ``S1 = <I_co - I_x>``,
    ``S2 + i S3 = 2 <A_co A_x*>``, averages over ``dims`` (default: all but ``channel``).

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(speckle.depolarize(scene, 0.0, seed=2), src)
    >>> round(float(speckle.degree_of_polarization(img)), 6)  # no cross channel: fully polarized
    1.0
    """
    if not isinstance(image, xr.Dataset) or "channel" not in image.field.dims:
        raise TypeError("image must be a Dataset with a complex 'field' and dim 'channel'")
    if set(CHANNELS) - set(np.asarray(image.channel.values).tolist()):
        raise ValueError(
            f"image must hold the channels {CHANNELS} (speckle.depolarize), got "
            f"{image.channel.values.tolist()}"
        )
    others = [d for d in image.field.dims if d != "channel"]
    if image.field.size == 0:
        raise ValueError(f"image holds no pixel (sizes {dict(image.field.sizes)})")
    if dims is not None:
        names = [dims] if isinstance(dims, str) else dims
        if not isinstance(names, list | tuple) or any(d not in others for d in names):
            raise ValueError(f"dims must be None or dims of the image among {others}, got {dims!r}")
    co, x = image.field.sel(channel="co"), image.field.sel(channel="cross")
    s0 = (abs(co) ** 2 + abs(x) ** 2).mean(dims)
    s1 = (abs(co) ** 2 - abs(x) ** 2).mean(dims)
    s23 = 2 * (co * np.conj(x)).mean(dims)
    return (np.sqrt(s1**2 + abs(s23) ** 2) / s0).assign_attrs(
        attrs("dimensionless", "degree of polarization")
    )


def total_intensity_contrast(p: object) -> np.ndarray:
    """Contrast of ``I_co + I_cross`` for fully developed speckle: ``sqrt((1 + P^2)/2)``."""
    pp = as_finite_array(p, "P")
    if np.any(pp < 0) or np.any(pp > 1):
        raise ValueError("degree of polarization P must lie in [0, 1]")
    return np.sqrt((1 + pp**2) / 2)


def total_intensity_pdf(intensity: object, mean: float, p: float) -> np.ndarray:
    """Density of ``I_co + I_cross`` with mean ``mean`` (> 0) and degree of polarization ``p``."""
    i = as_finite_array(intensity, "intensity")
    m = check_real(mean, "mean", low=0, low_inclusive=False)
    pp = check_real(p, "p", low=0, high=1)
    if pp == 1:
        return np.exp(-i / m) / m * (i >= 0)
    if pp < 1e-6:  # the limit P -> 0 (the difference formula cancels)
        return 4 * i / m**2 * np.exp(-2 * i / m) * (i >= 0)
    a, b = (1 + pp) * m / 2, (1 - pp) * m / 2
    return (np.exp(-i / a) - np.exp(-i / b)) / (pp * m) * (i >= 0)
