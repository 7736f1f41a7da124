"""Layered optical properties along depth, and per-region properties on a label image.

Independent-A-line scenes (the paper's B-scans) have no lateral structure, so their regions are
*layers*: depth intervals ``[top_i, top_{i+1})`` with constant properties (the last layer extends
to infinity, the first starts at its ``top``; depths above the first top take the first layer's
values). Shared 2-D scenes carry a label image ``(depth, x)`` and a property table with dim
``region`` (coordinate = integer label); :func:`region_values` looks properties up by label.

Property names used by the system effects:

=================  =========  ==================================================================
name               units      meaning
=================  =========  ==================================================================
attenuation        1/um       intensity attenuation coefficient ``mu_t`` (round trip
                              ``exp(-2 int mu_t dz)``, see :mod:`speckle.system.attenuation`)
backscatter        1          relative backscattered intensity (scatterer ``|a|^2`` factor)
depolarization     1          fraction of scattered intensity in the cross channel, in [0, 1]
=================  =========  ==================================================================
"""

from __future__ import annotations

import numbers

import numpy as np
import xarray as xr

from .._deprecate import keyword_only, moved
from .._validate import as_finite_array, check_real
from ..conventions import attrs, labelled, units_of

__all__ = [
    "PROPERTIES",
    "check_property",
    "layer_stack",
    "layer_values",
    "path_integral",
    "property_integral",
    "property_profile",
    "region_values",
    "sample_map",
]

#: ``layers`` (retired, :data:`speckle.conventions.RETIRED`) is now ``layer_stack``.
__getattr__ = moved(__name__, __name__, [], {"layers": "layer_stack"})

#: Property name -> (units, allowed interval (low, high), long name); the units are those of
#: the property's quantity in :data:`speckle.conventions.QUANTITIES`.
PROPERTIES: dict[str, tuple[str, tuple[float, float], str]] = {
    "attenuation": (
        units_of("attenuation"),
        (0.0, np.inf),
        "intensity attenuation coefficient mu_t",
    ),
    "backscatter": (units_of("dimensionless"), (0.0, np.inf), "relative backscattered intensity"),
    "depolarization": (
        units_of("dimensionless"),
        (0.0, 1.0),
        "cross-polarized fraction of scattered intensity",
    ),
}


def check_property(name: str, values: object) -> np.ndarray:
    """Finite values of a known property inside its allowed interval (``ValueError`` otherwise)."""
    if name not in PROPERTIES:
        raise ValueError(f"property must be one of {sorted(PROPERTIES)}, got {name!r}")
    v = as_finite_array(values, name)
    lo, hi = PROPERTIES[name][1]
    if np.any(v < lo) or np.any(v > hi):
        raise ValueError(
            f"{name} must lie in [{lo:g}, {hi:g}] ({PROPERTIES[name][0]}), got min {v.min():g}, "
            f"max {v.max():g}"
        )
    return v


def layer_stack(tops: object, **properties: object) -> xr.Dataset:
    """A stack of layers along depth with constant optical properties.

    Parameters
    ----------
    tops : array_like, shape (L,)
        Depth of the top of each layer in µm, strictly increasing (an empty, zero-thickness
        layer is refused).
    **properties : array_like, shape (L,)
        Values per layer of any of :data:`PROPERTIES` (``attenuation`` in 1/µm,
        ``backscatter``, ``depolarization``).

    Returns
    -------
    xarray.Dataset
        Dim ``layer``; coordinate ``top`` (µm); one variable per property with ``units``.

    Examples
    --------
    >>> import speckle
    >>> stack = speckle.layer_stack(
    ...     [0.0, 100.0], attenuation=[0.001, 0.004], backscatter=[1.0, 2.0]
    ... )
    >>> stack.sizes["layer"], stack.top.values
    (2, array([  0., 100.]))
    """
    t = as_finite_array(tops, "tops")
    if t.ndim != 1 or t.size < 1:
        raise ValueError(f"tops must be a 1-D array of at least one depth (µm), got {t.shape}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("tops must be strictly increasing: every layer needs a thickness > 0 µm")
    if not properties:
        raise ValueError(f"give at least one property of {sorted(PROPERTIES)}")
    data = {}
    for name, values in properties.items():
        v = check_property(name, values)
        if v.shape != t.shape:
            raise ValueError(f"{name} needs one value per layer ({t.size}), got shape {v.shape}")
        units, _, long_name = PROPERTIES[name]
        data[name] = ("layer", v, labelled(units, long_name))
    return xr.Dataset(
        data,
        coords={
            "layer": np.arange(t.size),
            "top": ("layer", t, attrs("length", "depth of layer top")),
        },
    )


def _check_layers(stack: xr.Dataset, name: str) -> np.ndarray:
    if not isinstance(stack, xr.Dataset) or "top" not in stack.coords or name not in stack:
        raise TypeError(f"layers must be a Dataset from speckle.layer_stack(...) holding {name!r}")
    return check_property(name, stack[name].values)


def layer_values(z: object, stack: xr.Dataset, name: str) -> np.ndarray:
    """Value of property ``name`` of the layer holding each depth ``z`` (µm)."""
    values = _check_layers(stack, name)
    idx = np.searchsorted(stack.top.values, np.asarray(z, dtype=float), side="right") - 1
    return values[np.clip(idx, 0, values.size - 1)]


def path_integral(z: object, stack: xr.Dataset, name: str) -> np.ndarray:
    """Exact ``int_0^z p(z') dz'`` of a piecewise-constant property (µm x property units).

    The first layer's value also holds above its top (down to ``z = 0``); negative ``z`` gives
    a negative integral (the same formula continued).
    """
    values = _check_layers(stack, name)
    tops = stack.top.values.astype(float)
    edges = np.concatenate([[0.0], np.maximum(tops[1:], 0.0)])  # layer starts, first at 0
    zz = np.asarray(z, dtype=float)
    # sum over layers of value * overlap of [edge_i, edge_{i+1}) with [0, z)
    upper = np.concatenate([edges[1:], [np.inf]])
    span = np.clip(zz[..., None], edges, upper) - edges
    out = np.sum(values * span, axis=-1)
    return np.where(zz < 0, values[0] * zz, out)


def property_profile(z: object, value: float | xr.Dataset, name: str) -> np.ndarray:
    """Property ``name`` at depths ``z``: a constant (float) or layered (Dataset) value."""
    if isinstance(value, xr.Dataset):
        return layer_values(z, value, name)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number or a layers Dataset, got {value!r}")
    v = float(check_property(name, value))
    return np.full(np.shape(z), v)


def property_integral(z: object, value: float | xr.Dataset, name: str) -> np.ndarray:
    """``int_0^z`` of a constant or layered property (see :func:`path_integral`)."""
    if isinstance(value, xr.Dataset):
        return path_integral(z, value, name)
    return property_profile(z, value, name) * np.asarray(z, dtype=float)


@keyword_only("outside")
def region_values(
    labels: xr.DataArray, properties: xr.Dataset, name: str, *, outside: float | None = None
) -> xr.DataArray:
    """Map a label image to property ``name`` by region label.

    Parameters
    ----------
    labels : xarray.DataArray
        Integer region labels, e.g. dims ``(depth, x)``.
    properties : xarray.Dataset
        Per-region properties with dim ``region`` whose coordinate holds the labels (e.g. the
        regions of :mod:`speckle.scene.regions`).
    outside : float, optional
        Value for label ``-1`` ("no region", e.g. air); without it ``-1`` is an error too.

    Raises
    ------
    ValueError
        If the table has no regions, a label of the image has no row in the table, or values are
        out of range.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.layer(100.0, 200.0, density=0.1, backscatter=4.0)
    ... )
    >>> labels = speckle.rasterize(regions, np.array([50.0, 150.0]), np.array([0.0]))
    >>> speckle.region_values(labels, regions, "backscatter").values[:, 0]
    array([1., 4.])
    """
    if not isinstance(properties, xr.Dataset) or "region" not in properties.dims:
        raise TypeError("properties must be a Dataset with dim 'region' (labels as coordinate)")
    if properties.sizes["region"] == 0:
        raise ValueError("properties hold no region: give at least one region")
    if not isinstance(name, str) or name not in properties:
        raise ValueError(
            f"name={name!r} is not a variable of properties; they hold {list(properties.data_vars)}"
        )
    if not isinstance(labels, xr.DataArray) or not np.issubdtype(labels.dtype, np.integer):
        raise TypeError("labels must be an integer DataArray (a label image)")
    if labels.size == 0:
        raise ValueError(f"labels is empty (sizes {dict(labels.sizes)}): no pixel to map")
    if outside is not None:
        try:
            outside = float(check_property(name, check_real(outside, "outside")))
        except ValueError as err:
            raise ValueError(f"outside: {err}") from None
    table = np.asarray(properties["region"].values)
    values = check_property(name, properties[name].values)
    order = np.argsort(table)
    pos = np.searchsorted(table[order], labels.values)
    pos = np.clip(pos, 0, table.size - 1)
    found = table[order][pos] == labels.values
    vals = values[order][pos]
    if outside is not None:
        none = (labels.values == -1) & ~found
        vals = np.where(none, outside, vals)
        found = found | none
    if not np.all(found):
        missing = np.unique(labels.values[~found])
        raise ValueError(f"labels {missing.tolist()} have no row in properties (regions {table})")
    return labels.copy(data=vals).assign_attrs(labelled(PROPERTIES[name][0], name))


def sample_map(field: xr.DataArray, z: object, x: object) -> np.ndarray:
    """Values of a ``(depth, x)`` map at points ``(z, x)`` (µm): linear in depth, nearest in x.

    Depths outside the map take its first/last row; ``x`` must lie within half a column step of
    the map's ``x`` range (a scatterer outside the labelled scene is an error).
    """
    if not isinstance(field, xr.DataArray) or {"depth", "x"} - set(field.dims):
        raise TypeError("field must be a DataArray with dims (depth, x)")
    f = field.transpose("depth", "x").values
    zd = np.asarray(field.depth.values, dtype=float)
    xd = np.asarray(field.x.values, dtype=float)
    zz, xx = np.broadcast_arrays(np.asarray(z, dtype=float), np.asarray(x, dtype=float))
    half = 0.5 * (xd[1] - xd[0]) if xd.size > 1 else 0.0
    if np.any(xx < xd[0] - half - 1e-9) or np.any(xx > xd[-1] + half + 1e-9):
        raise ValueError(f"x outside the labelled scene [{xd[0]:g}, {xd[-1]:g}] µm")
    col = np.clip(
        np.rint((xx - xd[0]) / (2 * half) if half else 0 * xx).astype(int), 0, xd.size - 1
    )
    out = np.empty(zz.shape)
    for c in np.unique(col):
        sel = col == c
        out[sel] = np.interp(zz[sel], zd, f[:, c])
    return out
