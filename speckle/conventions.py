"""Names, units and attributes used across the package: one table, one place.

Every labelled object ``speckle`` returns uses these dimension and coordinate names, and their
``units``/``long_name`` attributes come from :data:`COORDS`. Spacing (pixel size, A-line pitch)
is read from coordinates, never from attributes (:func:`spacing`).

============  ==========  ===============================================================
name          units       meaning
============  ==========  ===============================================================
depth         um          depth of a pixel centre in the medium, ``q*H/N`` (pixel axis)
aline         um          lateral position of an independent A-line (the paper's B-scans)
x, y          um          lateral position in a shared scene or of a scanned beam line
z             um          depth of a scatterer (a variable, not a dim)
wavenumber    rad/um      spectral component ``k_n = k0 + n*pi/H``
strain        1           uniaxial strain, compression > 0
k0_dk         1           ``k0/delta_k`` (= ``Lc/lambda0``)
density       1           scatterers per pixel (independent lines) or per voxel
lag           1           lag in pixels or lines
region        1           region label of a shared scene (:mod:`speckle.scene.regions`)
============  ==========  ===============================================================

Units strings follow UDUNITS (``um``, ``rad/um``, ``1``) so that NetCDF readers understand
them; docstrings write µm.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__ = ["COORDS", "coord", "spacing"]

#: Coordinate/dimension name -> (units, long_name).
COORDS: dict[str, tuple[str, str]] = {
    "depth": ("um", "depth in the medium (pixel centre)"),
    "aline": ("um", "lateral position of the A-line"),
    "x": ("um", "lateral position x"),
    "y": ("um", "lateral position y"),
    "z": ("um", "scatterer depth"),
    "wavenumber": ("rad/um", "wavenumber k_n in the medium"),
    "strain": ("1", "uniaxial strain (compression > 0)"),
    "k0_dk": ("1", "k0/delta_k (= Lc/lambda0)"),
    "density": ("1", "scatterers per pixel"),
    "lag": ("1", "lag"),
    "region": ("1", "region label (speckle.scene.regions)"),
}


def coord(name: str, values: object) -> tuple[str, np.ndarray, dict[str, str]]:
    """A coordinate tuple ``(name, values, attrs)`` with the units and long name of :data:`COORDS`.

    >>> coord("depth", [0.0, 8.0])[2]["units"]
    'um'
    """
    units, long_name = COORDS[name]
    return (name, np.asarray(values), {"units": units, "long_name": long_name})


def spacing(obj: xr.DataArray | xr.Dataset, dim: str, default: float | None = None) -> float:
    """Uniform step of coordinate ``dim`` of ``obj`` (in its units, µm for lengths).

    Parameters
    ----------
    obj : xarray.DataArray or xarray.Dataset
        Object with a 1-D coordinate ``dim``.
    dim : str
        Coordinate name, e.g. ``"depth"`` (pixel size) or ``"aline"``/``"x"`` (line pitch).
    default : float, optional
        Returned when the coordinate has a single value (no step to read); without it a
        single-valued coordinate is an error.

    Raises
    ------
    ValueError
        If ``dim`` is missing, has no step to read and no ``default`` is given, or is not
        uniformly spaced (relative deviation above 1e-9).
    """
    if dim not in obj.coords:
        raise ValueError(
            f"{dim!r} coordinate missing; the object has coordinates {list(obj.coords)}"
        )
    v = np.asarray(obj[dim].values, dtype=float)
    if v.ndim != 1:
        raise ValueError(f"coordinate {dim!r} must be 1-D, got shape {v.shape}")
    if v.size < 2:
        if default is None:
            raise ValueError(f"coordinate {dim!r} has {v.size} value(s): its spacing is undefined")
        return float(default)
    d = np.diff(v)
    step = float(d.mean())
    if step <= 0 or np.max(np.abs(d - step)) > 1e-9 * abs(step):
        raise ValueError(f"coordinate {dim!r} must be increasing and uniformly spaced")
    return step
