"""NetCDF input/output with the netCDF4 engine.

Complex variables are stored losslessly with netCDF4-python's ``auto_complex`` support (a
compound type with members ``r`` and ``i``, the nc-complex convention). Open outputs with

    xr.open_dataset(path, engine="netcdf4", auto_complex=True)

or :func:`open_dataset` below. Every numeric variable is zlib-compressed. Attribute values that
netCDF cannot store (``None``, booleans, nested mappings) are converted to strings or integers
by :func:`netcdf_safe_attrs`, so attributes survive the round trip.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping

import numpy as np
import xarray as xr

__all__ = ["ENGINE", "netcdf_safe_attrs", "open_dataset", "to_netcdf"]

ENGINE = "netcdf4"
COMPLEVEL = 4


def _safe_value(value: object) -> object:
    if value is None:
        return "none"
    if isinstance(value, bool | np.bool_):
        return int(value)
    if isinstance(value, Mapping):
        return json.dumps(value, sort_keys=True, default=str)
    if isinstance(value, list | tuple):
        arr = np.asarray(value)
        if arr.dtype.kind in "iuf" and arr.ndim == 1:
            return arr
        return json.dumps(list(value), default=str)
    if isinstance(value, np.generic):
        return value.item()
    return value


def netcdf_safe_attrs(attrs: Mapping) -> dict:
    """Return a copy of ``attrs`` whose values netCDF can store."""
    return {str(k): _safe_value(v) for k, v in attrs.items()}


def to_netcdf(ds: xr.Dataset | xr.DataArray, path: str | os.PathLike) -> None:
    """Write ``ds`` to ``path`` (netCDF4/HDF5, compressed, complex-capable).

    Parameters
    ----------
    ds : xarray.Dataset or xarray.DataArray
        Data to write; a DataArray is written as a one-variable dataset.
    path : str or path-like
        Output file; parent directories are created.
    """
    if isinstance(ds, xr.DataArray):
        ds = ds.to_dataset(name=ds.name or "data")
    ds = ds.copy()
    ds.attrs = netcdf_safe_attrs(ds.attrs)
    for name in ds.variables:
        ds[name].attrs = netcdf_safe_attrs(ds[name].attrs)
        # Drop encodings carried over from files the data were read from: a string variable
        # read as 8-character labels would otherwise truncate longer labels added since.
        ds[name].encoding = {}
    encoding = {
        name: {"zlib": True, "complevel": COMPLEVEL}
        for name, var in ds.data_vars.items()
        if var.dtype.kind in "iufc"
    }
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    ds.to_netcdf(path, engine=ENGINE, auto_complex=True, encoding=encoding)


def open_dataset(path: str | os.PathLike, *, load: bool = True) -> xr.Dataset:
    """Open a file written by :func:`to_netcdf` (complex variables restored).

    Parameters
    ----------
    path : str or path-like
        NetCDF file.
    load : bool
        Load into memory and close the file (default); ``False`` keeps it lazy.
    """
    ds = xr.open_dataset(path, engine=ENGINE, auto_complex=True)
    if load:
        with ds:
            return ds.load()
    return ds
