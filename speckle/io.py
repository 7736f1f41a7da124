"""NetCDF input/output with the netCDF4 engine.

Complex variables are stored losslessly with netCDF4-python's ``auto_complex`` support (a
compound type with members ``r`` and ``i``, the nc-complex convention). Open outputs with

    xr.open_dataset(path, engine="netcdf4", auto_complex=True)

or :func:`open_dataset` below. Every numeric variable is zlib-compressed. Attribute values that
netCDF cannot store (``None``, booleans, nested mappings) are converted to strings or integers
by :func:`netcdf_safe_attrs`, so attributes survive the round trip; values it cannot convert
(complex numbers, arrays of 2 or more dims, arbitrary objects) are refused before writing,
naming the attribute.

Nothing lost
------------
Every file is written atomically (:func:`atomic_path`): into a temporary file in the same
directory, flushed to disk, then renamed over the target. A failed or killed write leaves an
existing file byte for byte as it was (a killed process may leave its ``.*.tmp`` file behind),
and a file at the target path is always complete.

netCDF4-python's ``auto_complex`` corrupts a complex64 variable written after a complex128 one
in the same file (two compound types ``r``/``i``; the second reads back wrong). :func:`to_netcdf`
therefore promotes every complex variable of a dataset that mixes complex precisions to
complex128 (lossless); a dataset with one complex precision is written as is.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from ._atomic import atomic_path
from ._image_files import IMAGE_DIMS, IMAGE_KINDS, load_image
from ._validate import check_bool, check_int, check_path
from .conventions import canonical_dims

__all__ = [
    "ENGINE",
    "IMAGE_DIMS",
    "IMAGE_KINDS",
    "atomic_path",
    "load_image",
    "netcdf_safe_attrs",
    "open_dataset",
    "stream_to_netcdf",
    "to_netcdf",
    "write_frames",
]

ENGINE = "netcdf4"
COMPLEVEL = 4


def _safe_value(value: object, name: str) -> object:
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
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "iuf" and value.ndim <= 1:
            return value
        raise TypeError(
            f"attribute {name!r} cannot be stored in netCDF: arrays must be 1-D integer or real, "
            f"got a {value.ndim}-D {value.dtype} array; store it as a variable instead"
        )
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, str | int | float):
        return value
    raise TypeError(
        f"attribute {name!r} cannot be stored in netCDF: allowed are str, int, float, bool, "
        f"None, mappings, sequences and 1-D real arrays; got {type(value).__name__} {value!r}"
    )


def netcdf_safe_attrs(attrs: Mapping, where: str = "") -> dict:
    """Return a copy of ``attrs`` whose values netCDF can store.

    Raises
    ------
    TypeError
        Naming the attribute (prefixed by ``where``) whose value netCDF cannot store.
    """
    return {str(k): _safe_value(v, f"{where}{k}") for k, v in attrs.items()}


def _complex_guard(ds: xr.Dataset) -> xr.Dataset:
    """Promote complex variables to complex128 when the dataset mixes complex precisions."""
    kinds = {v.dtype for v in ds.variables.values() if v.dtype.kind == "c"}
    if len(kinds) <= 1:
        return ds
    return ds.assign(
        {name: v.astype(np.complex128) for name, v in ds.data_vars.items() if v.dtype.kind == "c"}
    )


def to_netcdf(ds: xr.Dataset | xr.DataArray, path: str | os.PathLike) -> None:
    """Write ``ds`` to ``path`` (netCDF4/HDF5, compressed, complex-capable).

    Parameters
    ----------
    ds : xarray.Dataset or xarray.DataArray
        Data to write; a DataArray is written as a one-variable dataset.
    path : str or path-like
        Output file; parent directories are created. Written atomically (:func:`atomic_path`):
        an existing file is replaced only by a complete new one.

    Raises
    ------
    TypeError
        If ``ds`` is not an xarray object or an attribute cannot be stored (named).
    ValueError
        If ``path`` is a directory.

    Notes
    -----
    Complex variables of mixed precision are all written as complex128 (module docstring).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import xarray as xr
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "out.nc")
    >>> speckle.to_netcdf(xr.Dataset({"a": ("x", [1.0, 2.0])}), path)
    >>> speckle.open_dataset(path).a.values
    array([1., 2.])
    """
    if isinstance(ds, xr.DataArray):
        ds = ds.to_dataset(name=ds.name or "data")
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray Dataset or DataArray, got {type(ds).__name__}")
    ds = _prepared(ds, path)
    encoding = {
        name: {"zlib": True, "complevel": COMPLEVEL}
        for name, var in ds.data_vars.items()
        if var.dtype.kind in "iufc"
    }
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine=ENGINE, auto_complex=True, encoding=encoding)


def _prepared(ds: xr.Dataset, path: str | os.PathLike) -> xr.Dataset:
    """A copy of ``ds`` ready to write: checked path, one complex precision, storable attrs."""
    if Path(path).is_dir():
        raise ValueError(f"path must be a file path, got the directory {str(path)!r}")
    for kind, names in (("variable", ds.variables), ("dimension", ds.dims)):
        for name in names:
            if not isinstance(name, str) or not name or "/" in name:
                raise ValueError(
                    f"{kind} name {name!r} cannot be stored in netCDF: names must be non-empty "
                    "strings without '/'; rename it (Dataset.rename)"
                )
    ds = _complex_guard(ds.copy())
    ds.attrs = netcdf_safe_attrs(ds.attrs)
    for name in ds.variables:
        ds[name].attrs = netcdf_safe_attrs(ds[name].attrs, f"{name}.")
        # Drop encodings carried over from files the data were read from: a string variable
        # read as 8-character labels would otherwise truncate longer labels added since.
        ds[name].encoding = {}
    return ds


def open_dataset(path: str | os.PathLike, *, load: bool = True) -> xr.Dataset:
    """Open a file written by :func:`to_netcdf` (complex variables restored).

    Parameters
    ----------
    path : str or path-like
        NetCDF file.
    load : bool
        Load into memory and close the file (default); ``False`` keeps it lazy.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import xarray as xr
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "out.nc")
    >>> speckle.to_netcdf(xr.Dataset({"a": ("x", [1.0, 2.0])}), path)
    >>> speckle.open_dataset(path).a.values
    array([1., 2.])
    """
    check_bool(load, "load")
    check_path(path)
    if not Path(path).is_file():
        raise FileNotFoundError(f"path {str(path)!r} is not a file")
    try:
        ds = xr.open_dataset(path, engine=ENGINE, auto_complex=True)
    except OSError as exc:
        raise ValueError(
            f"path {str(path)!r} is not a readable netCDF4/HDF5 file (as speckle.io.to_netcdf "
            f"writes): {exc}"
        ) from None
    if load:
        with ds:
            return ds.load()
    return ds


def stream_to_netcdf(
    ds: xr.Dataset, path: str | os.PathLike, *, progress: bool = True, complevel: int = 1
) -> None:
    """Write a Dask-backed dataset chunk by chunk to a chunked NetCDF file, atomically.

    Each Dask chunk is computed and written as it comes, so memory holds the chunks in flight,
    not the dataset. Runs on the active Dask scheduler: the local threads scheduler by default,
    or a ``dask.distributed`` cluster when a ``distributed.Client`` is active (then the
    file lock is distributed too). The local ``"processes"`` scheduler is refused
    (``ValueError``): the file lock cannot be shared between processes. The file is written
    to a temporary name in the same directory and renamed when complete, so a crash never
    leaves a partial ``path``.

    Parameters
    ----------
    ds : xarray.Dataset
        Data to write; each Dask-backed variable is stored with NetCDF chunks equal to its
        Dask chunks (first chunk size along each dim).
    path : str or path-like
        Output file; parent directories are created.
    progress : bool
        Show a progress bar (``dask.diagnostics.ProgressBar`` locally,
        ``distributed.progress`` on a cluster) on stderr.
    complevel : int
        zlib level, 0-9 (speckle fields barely compress: 1 is a good trade-off).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import xarray as xr
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "out.nc")
    >>> speckle.stream_to_netcdf(xr.Dataset({"a": ("x", [1.0, 2.0])}).chunk(), path, progress=False)
    >>> speckle.open_dataset(path).a.values
    array([1., 2.])
    """
    import dask
    from dask.diagnostics import ProgressBar

    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray Dataset, got {type(ds).__name__}")
    check_bool(progress, "progress")
    complevel = check_int(complevel, "complevel", low=0, high=9)
    check_path(path)
    if _on_processes():
        raise ValueError(
            "stream_to_netcdf cannot run on Dask's 'processes' scheduler: the netCDF file lock "
            "cannot be shared between processes. Use the 'threads' or 'synchronous' scheduler "
            "(dask.config.set(scheduler='threads')), or a distributed.Client, whose workers "
            "may be processes (its lock is distributed)"
        )
    ds = _prepared(ds, path)
    encoding = {}
    for name, var in ds.data_vars.items():
        enc: dict = {"zlib": complevel > 0, "complevel": complevel} if complevel > 0 else {}
        if var.chunks is not None:
            enc["chunksizes"] = tuple(int(c[0]) for c in var.chunks)
        encoding[name] = enc
    with atomic_path(path) as tmp:
        job = ds.to_netcdf(tmp, engine=ENGINE, auto_complex=True, encoding=encoding, compute=False)
        client = _distributed_client()
        if client is not None:
            future = client.compute(job)
            if progress:
                from distributed import progress as dprogress

                dprogress(future)
            future.result()
        elif progress:
            with ProgressBar(dt=1.0, out=_stderr()):
                dask.compute(job)
        else:
            dask.compute(job)


def _on_processes() -> bool:
    """Whether the active Dask scheduler is the local multiprocessing one."""
    import dask.base
    import dask.multiprocessing

    return dask.base.get_scheduler() is dask.multiprocessing.get


def _stderr():
    import sys

    return sys.stderr


def _distributed_client():
    """The active ``distributed.Client`` or None (distributed is optional)."""
    try:
        from distributed import default_client
    except ImportError:
        return None
    try:
        return default_client()
    except ValueError:
        return None


def write_frames(
    path: str | os.PathLike,
    frames: Iterator[Mapping[str, np.ndarray]],
    *,
    n_frames: int,
    template: xr.Dataset,
    progress: bool = False,
    complevel: int = 1,
) -> None:
    """Write a sequence frame by frame to a chunked NetCDF file (one chunk per frame), atomically.

    Memory holds one frame, not the sequence: ``frames`` yields, for each index along
    ``frame``, a mapping from variable name to its ``(depth, x)`` array.

    Parameters
    ----------
    path : str or path-like
        Output file (written to a temporary name beside it and renamed when complete).
    frames : iterator of mappings
        One mapping per frame, in order, with every variable of ``template``.
    n_frames : int
        Number of frames ``frames`` yields.
    template : xarray.Dataset
        Coordinates (``frame``, ``depth``, ``x``, ...), attrs, and the variables' names,
        dims ``(frame, depth, x)`` and attrs (their data is not read).
    progress : bool
        A text progress bar on stderr.
    complevel : int
        zlib level, 0-9.
    """
    import netCDF4

    level = int(complevel)
    if isinstance(complevel, bool) or not 0 <= level <= 9 or level != complevel:
        raise ValueError(f"complevel must be an integer in [0, 9], got {complevel!r}")
    skeleton = template.drop_vars(list(template.data_vars))
    names = list(template.data_vars)
    template = canonical_dims(template, "template")  # (frame, depth, aline) warns: now x
    shape = tuple(template.sizes[d] for d in ("depth", "x"))
    with atomic_path(path) as tmp:
        skeleton.to_netcdf(tmp, engine=ENGINE)  # coordinates and attrs, the xarray way
        with netCDF4.Dataset(tmp, "a") as nc:
            for d, size in template.sizes.items():  # dims without a coordinate variable
                if d not in nc.dimensions:
                    nc.createDimension(d, size)
            out = {}
            for name in names:
                var = template[name]
                out[name] = nc.createVariable(
                    name,
                    "f8",
                    var.dims,
                    zlib=level > 0,
                    complevel=max(level, 1),
                    chunksizes=(1, *shape),
                    fill_value=np.nan,
                )
                out[name].setncatts(netcdf_safe_attrs(var.attrs, name))
            done = 0
            for i, fields in enumerate(frames):
                for name in names:
                    out[name][i] = np.asarray(fields[name], dtype=float)
                done = i + 1
                if progress:
                    bar = "#" * (40 * done // n_frames)
                    print(f"\r[{bar:<40}] {done}/{n_frames} frames", end="", file=_stderr())
            if progress:
                print(file=_stderr())
            if done != n_frames:
                raise ValueError(f"frames yielded {done} frames, expected n_frames={n_frames}")
