"""Users' OCT images from files: one loader for numpy, MATLAB, NetCDF, Zarr and TIFF.

The implementation of :func:`speckle.io.load_image` (the one loader of measured images; its
readers' libraries load only when a file of their format is read).

:func:`load_image` returns a labelled ``(depth, x)`` DataArray (``(frame, depth, x)`` for pairs
and sequences) with coordinates in µm and the image's ``kind`` recorded, so that
:func:`speckle.studies.twin.fit_system` and the other analyses know what the numbers are:

``complex``
    the complex field ``A`` (complex dtype);
``amplitude``
    ``|A|`` (real, >= 0);
``intensity``
    ``|A|^2`` (real, >= 0);
``log``
    log-compressed data ``D = g ln I + c`` with unknown gain ``g`` and offset ``c`` (what most
    commercial engines write, often 8-bit).

Readers (picked by the file suffix):

============================  ===========================================================
``.npy``                      :func:`numpy.load` (no pickles)
``.mat`` v4-v7                :func:`scipy.io.loadmat`
``.mat`` v7.3 (HDF5)          :mod:`h5py`; MATLAB stores arrays column-major (axes reversed
                              on disk, restored here) and complex arrays as a compound type
                              with fields ``real`` and ``imag``
``.nc``, ``.nc4``, ``.cdf``   :func:`xarray.open_dataset` (``engine="netcdf4"``, complex
                              variables restored)
``.zarr`` (a folder)          :func:`xarray.open_zarr`, or a bare :mod:`zarr` array
``.tif``, ``.tiff``           :func:`tifffile.imread` (a multi-page stack is one array)
============================  ===========================================================

Axis order is never guessed: files that name their dims (NetCDF, Zarr written by xarray, with
names among ``depth``, ``x``, ``frame``; the retired ``aline`` is read as ``x`` with a
``FutureWarning``, :func:`speckle.conventions.canonical_dims`) are read by name; for every
other array ``dims`` must be given, e.g. ``("depth", "x")`` or ``("frame", "x", "depth")``.
Pixel size and pitch are never guessed either: they are taken from µm coordinates of the file
or must be passed. The central wavenumber ``k0`` (rad/µm in the medium) is taken from a NetCDF or
Zarr file's attributes (the image variable's, else the file's: what the package writes,
:func:`speckle.conventions.with_grid`) or from ``k0=``; the image then carries its grid
(``k0``, and ``n_pixels``/``depth_range`` when the file holds them) and goes to
:func:`speckle.estimate_strain` or :func:`speckle.accumulate_strain` without ``k0=``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from ._validate import check_choice, check_real
from ._wrap import GRID_RTOL
from .conventions import GRID_ATTRS, attrs, canonical_dims, coord, grid_attrs, units_of

__all__ = ["IMAGE_DIMS", "IMAGE_KINDS", "load_image"]

#: Kinds of image values (module docstring).
IMAGE_KINDS = ("complex", "amplitude", "intensity", "log")
#: Dim names an image may have (a retired name, e.g. ``aline``, is read as its new one, warning).
IMAGE_DIMS = ("frame", "depth", "x")
_SUFFIXES = {
    ".npy": "npy",
    ".mat": "mat",
    ".nc": "netcdf",
    ".nc4": "netcdf",
    ".cdf": "netcdf",
    ".zarr": "zarr",
    ".tif": "tiff",
    ".tiff": "tiff",
}
_DIMS_HINT = (
    "pass dims=('depth', 'x') (axis 0 = depth) or dims=('x', 'depth'); a pair or sequence "
    "of frames: dims=('frame', 'depth', 'x')"
)


def _is_image(shape: tuple[int, ...]) -> bool:
    """An array that can be an image: at least 2 axes of 2 or more (MATLAB scalars are 1 x 1)."""
    return sum(n >= 2 for n in shape) >= 2


def _pick(names: list[str], variable: str | None, path: Path) -> str:
    if variable is not None:
        if variable not in names:
            raise ValueError(f"variable {variable!r} not in {path.name}; it holds {names}")
        return variable
    if len(names) != 1:
        raise ValueError(
            f"{path.name} holds {len(names)} arrays {names}; pass variable= one of them"
        )
    return names[0]


def _read_mat(path: Path, variable: str | None) -> np.ndarray:
    import h5py

    if h5py.is_hdf5(path):  # MATLAB v7.3
        with h5py.File(path, "r") as f:
            names = [
                k
                for k, v in f.items()
                if isinstance(v, h5py.Dataset) and not k.startswith("#") and _is_image(v.shape)
            ]
            ds = f[_pick(names, variable, path)]
            raw = ds[()]
        if raw.dtype.names is not None:
            if set(raw.dtype.names) != {"real", "imag"}:
                raise TypeError(
                    f"{path.name}: compound array with fields {raw.dtype.names}; only MATLAB "
                    "complex arrays (fields real, imag) are read"
                )
            raw = raw["real"] + 1j * raw["imag"]
        return np.asarray(raw).transpose()  # MATLAB is column-major: restore its axis order
    from scipy import io as sio

    content = sio.loadmat(path)
    names = [k for k, v in content.items() if not k.startswith("__") and _is_image(np.shape(v))]
    return np.asarray(content[_pick(names, variable, path)])


def _from_xarray(ds: xr.Dataset, variable: str | None, path: Path) -> xr.DataArray:
    names = [k for k, v in ds.data_vars.items() if _is_image(v.shape)]
    da = ds[_pick(names, variable, path)].load()
    # the grid the file stores (the variable's attributes first, then the file's)
    stored = {k: v for k, v in {**ds.attrs, **da.attrs}.items() if k in GRID_ATTRS}
    return canonical_dims(da.assign_attrs(stored), f"image in {path.name}")


def _read(path: Path, fmt: str, variable: str | None) -> np.ndarray | xr.DataArray:
    if fmt == "npy":
        return np.load(path, allow_pickle=False)
    if fmt == "mat":
        return _read_mat(path, variable)
    if fmt == "netcdf":
        with xr.open_dataset(path, engine="netcdf4", auto_complex=True) as ds:
            return _from_xarray(ds, variable, path)
    if fmt == "zarr":
        import zarr

        try:
            with xr.open_zarr(path) as ds:
                return _from_xarray(ds, variable, path)
        except (KeyError, ValueError, TypeError):
            node = zarr.open(str(path), mode="r")
            if isinstance(node, zarr.Array):
                return np.asarray(node[...])
            names = sorted(k for k, v in node.arrays())
            return np.asarray(node[_pick(names, variable, path)][...])
    import tifffile

    return tifffile.imread(path)


def _axis_coord(da: xr.DataArray, dim: str, step: float | None, name: str) -> float:
    """The step of ``dim`` in µm: from ``step`` or from a µm coordinate in the file."""
    given = None if step is None else check_real(step, name, low=0, low_inclusive=False)
    c = da.coords.get(dim)
    if c is not None and c.attrs.get("units") in ("um", "µm", "micrometre", "micrometer"):
        v = np.asarray(c.values, dtype=float)
        if v.size >= 2 and np.allclose(np.diff(v), v[1] - v[0], rtol=1e-9) and v[1] > v[0]:
            own = float(v[1] - v[0])
            if given is not None and not np.isclose(given, own, rtol=1e-9, atol=0):
                raise ValueError(
                    f"{name} = {given:g} µm contradicts the file's {dim!r} coordinate (step "
                    f"{own:g} µm); omit {name} to use the file's, or correct the file"
                )
            return own
    if given is not None:
        return given
    what = "axial pixel size" if dim == "depth" else "lateral A-line pitch"
    raise ValueError(
        f"{name} missing: the file gives no {dim!r} coordinate in um; pass {name}= the {what} "
        "in µm (> 0)"
    )


def _check_kind(data: np.ndarray, kind: str) -> None:
    if kind == "complex":
        if data.dtype.kind != "c":
            raise TypeError(f"kind='complex' needs a complex array, got dtype {data.dtype}")
        return
    if data.dtype.kind == "c":
        raise TypeError(
            f"a complex array was given with kind={kind!r}; pass kind='complex' (or the "
            "amplitude abs(A) with kind='amplitude')"
        )
    if data.dtype.kind not in "iuf" and data.dtype != bool:
        raise TypeError(f"image values must be numbers, got dtype {data.dtype}")
    if kind in ("amplitude", "intensity") and np.nanmin(data) < 0:
        raise ValueError(
            f"kind={kind!r} values must be >= 0, found {np.nanmin(data):.4g}; log-compressed "
            "data (any sign) are kind='log'"
        )


def _grid_of(raw: object, k0: float | None, path: Path) -> dict[str, object]:
    """The grid attributes of the loaded image: the file's, with ``k0`` (given, or the file's;
    both: they must agree to :data:`speckle._wrap.GRID_RTOL`)."""
    stored = dict(raw.attrs) if isinstance(raw, xr.DataArray) else {}
    own = stored.get("k0")
    if own is not None:  # a file's k0 is checked as a given one is
        own = check_real(
            np.asarray(own).item(), f"k0 stored in {path.name}", low=0, low_inclusive=False
        )
        if k0 is not None and not np.isclose(k0, own, rtol=GRID_RTOL, atol=0):
            raise ValueError(
                f"k0 = {k0!r} rad/µm contradicts the k0 = {own!r} rad/µm stored in "
                f"{path.name}; omit k0 to use the file's, or correct the file"
            )
    k = own if own is not None else k0
    if "n_pixels" in stored and "depth_range" in stored:
        return grid_attrs(int(stored["n_pixels"]), float(stored["depth_range"]), k)
    if k is None:
        return {}
    # k0 alone: a measured image's A-scan length and depth range are not known
    return {"k0": float(k), "k0_units": units_of("wavenumber")}


def load_image(
    path: str | os.PathLike,
    *,
    kind: str,
    pixel_size: float | None = None,
    pitch: float | None = None,
    dims: tuple[str, ...] | None = None,
    variable: str | None = None,
    k0: float | None = None,
) -> xr.DataArray:
    """Load a measured OCT image as a labelled DataArray ``(depth, x)`` (module docstring).

    Parameters
    ----------
    path : str or path-like
        ``.npy``, ``.mat`` (v4-v7.3), ``.nc``/``.nc4``/``.cdf``, ``.zarr`` or ``.tif``/``.tiff``.
    kind : {"complex", "amplitude", "intensity", "log"}
        What the values are; ``"log"``: log-compressed with unknown gain and offset.
    pixel_size : float, optional
        Axial pixel size in µm (> 0); needed unless the file has a ``depth`` coordinate in µm.
    pitch : float, optional
        Lateral A-line pitch in µm (> 0); needed unless the file has an ``x`` coordinate
        in µm.
    dims : tuple of str, optional
        Name of each axis of the stored array, from ``("frame", "depth", "x")`` (the retired
        ``"aline"`` is read as ``"x"``, warning); needed unless the file names its dims.
    variable : str, optional
        Which array of a file holding several (MATLAB, NetCDF, Zarr group).
    k0 : float, optional
        Central wavenumber of the scanner in the medium, rad/µm (> 0; ``n k_vacuum``),
        recorded as the image's ``k0`` attribute so that :func:`speckle.estimate_strain`,
        :func:`speckle.estimate_displacement` and :func:`speckle.accumulate_strain` read it
        (no ``k0=`` at each call). A NetCDF/Zarr file that stores ``k0`` in its attributes
        gives it; a different value given as well is refused.

    Returns
    -------
    xarray.DataArray
        Float64 (complex128 for ``kind="complex"``) values with dims ``(depth, x)`` or
        ``(frame, depth, x)``; coordinates ``depth`` and ``x`` in µm from 0 (units and long
        names of :data:`speckle.conventions.COORDS`), ``frame`` 0, 1, ...; attributes
        ``kind``, ``source``, ``format``, ``dtype`` (as stored), ``pixel_size``, ``pitch``,
        for integer data ``clip_low``/``clip_high`` (the dtype's limits), and the grid
        (:func:`speckle.conventions.grid_attrs`): ``k0`` (given or stored) and the file's
        ``n_pixels``/``depth_range`` when it stores them.

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    ValueError
        Unknown suffix or ``kind``; ``dims`` missing or not matching the array; a missing
        ``pixel_size``/``pitch``; several arrays and no ``variable``; non-finite values;
        fewer than 2 x 2 pixels; ``k0`` not > 0, or not the ``k0`` the file stores.
    TypeError
        Values that do not match ``kind`` (complex for a real kind, or the reverse).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "scan.npy")
    >>> np.save(path, np.random.default_rng(0).exponential(size=(16, 8)))
    >>> img = speckle.load_image(
    ...     path, kind="intensity", pixel_size=5.0, pitch=10.0, dims=("depth", "x")
    ... )
    >>> img.dims, img.shape, float(img.x[1] - img.x[0])
    (('depth', 'x'), (16, 8), 10.0)

    With the scanner's ``k0`` the image carries its grid; strain then needs no ``k0=``:

    >>> np.save(path, np.random.default_rng(0).normal(size=(64, 16)).view(complex))
    >>> field = speckle.load_image(path, kind="complex", pixel_size=5.0, pitch=10.0,
    ...                            dims=("depth", "x"), k0=10.0)
    >>> field.attrs["k0"], field.attrs["k0_units"]
    (10.0, 'rad/um')
    >>> float(np.nanmax(np.abs(speckle.estimate_strain(field, field, window=(16, 4)))))
    0.0
    """
    check_choice(kind, "kind", IMAGE_KINDS)
    k0 = None if k0 is None else check_real(k0, "k0", low=0, low_inclusive=False)
    if not isinstance(path, str | os.PathLike):
        raise TypeError(f"path must be a str or path-like, got {type(path).__name__} {path!r}")
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"image not found: {p}")
    fmt = _SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise ValueError(
            f"path suffix {p.suffix!r} not readable; use one of {sorted(set(_SUFFIXES))}"
        )
    try:
        raw = _read(p, fmt, variable)
    except Exception as exc:  # a truncated or corrupt file: name it, whatever the reader said
        if isinstance(exc, ValueError | TypeError) and p.name in str(exc):
            raise  # our own message (variable, compound arrays), naming the file already
        raise ValueError(
            f"path {str(p)!r} could not be read as a {fmt} image (truncated or corrupt?): "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    if np.size(raw) == 0:
        raise ValueError(
            f"image in {p.name} must have at least 2 x 2 pixels; it holds none (empty, or a "
            f"{fmt} file the reader found no image in)"
        )
    if isinstance(raw, xr.DataArray) and dims is None:
        if not set(raw.dims) <= set(IMAGE_DIMS) or not {"depth", "x"} <= set(raw.dims):
            raise ValueError(
                f"{p.name}: array dims {raw.dims} are not named ('depth', 'x'[, 'frame']); "
                + _DIMS_HINT
            )
        da = raw
    else:
        values = raw.values if isinstance(raw, xr.DataArray) else np.asarray(raw)
        if dims is None:
            raise ValueError(
                f"axis order of the {values.shape} array in {p.name} is ambiguous; " + _DIMS_HINT
            )
        names = tuple(dims)
        if len(names) != values.ndim or len(set(names)) != len(names):
            raise ValueError(
                f"dims {tuple(dims)} do not name each of the {values.ndim} axes of the "
                f"{values.shape} array once; " + _DIMS_HINT
            )
        names = canonical_dims(xr.DataArray(np.empty((0,) * len(names)), dims=names), "dims").dims
        if not set(names) <= set(IMAGE_DIMS) or not {"depth", "x"} <= set(names):
            raise ValueError(f"dims must be 'depth', 'x' and optionally 'frame'; {_DIMS_HINT}")
        da = (
            raw.rename(dict(zip(raw.dims, names, strict=True)))
            if isinstance(raw, xr.DataArray)
            else xr.DataArray(values, dims=names)
        )
    dz = _axis_coord(da, "depth", pixel_size, "pixel_size")
    dx = _axis_coord(da, "x", pitch, "pitch")
    order = ("frame", "depth", "x") if "frame" in da.dims else ("depth", "x")
    data = np.asarray(da.transpose(*order).values)
    stored = data.dtype
    if data.shape[-2] < 2 or data.shape[-1] < 2 or data.size == 0:
        raise ValueError(
            f"image in {p.name} must have at least 2 x 2 pixels, got {data.shape} {order}"
        )
    _check_kind(data, kind)
    if not np.all(np.isfinite(data)):
        raise ValueError(f"image in {p.name} has NaN or infinite values; crop or fill them")
    if data.shape[-2] < 2 or data.shape[-1] < 2:
        raise ValueError(f"image must have at least 2 x 2 pixels, got {data.shape} {order}")
    data = data.astype(np.complex128 if kind == "complex" else np.float64)
    nz, nx = data.shape[-2:]
    coords = {
        "depth": coord("depth", np.arange(nz) * dz),
        "x": coord("x", np.arange(nx) * dx),
    }
    if "frame" in order:
        coords["frame"] = coord("count", np.arange(data.shape[0]), "frame index", dims="frame")
    meta = {
        "kind": kind,
        "source": str(p),
        "format": fmt,
        "dtype": str(stored),
        "pixel_size": dz,
        "pitch": dx,
        **attrs(
            "dimensionless",
            "measured OCT " + ("log-compressed signal" if kind == "log" else kind),
        ),
    }
    if np.issubdtype(stored, np.integer):
        info = np.iinfo(stored)
        meta.update(clip_low=int(info.min), clip_high=int(info.max))
    meta.update(_grid_of(raw, k0, p))
    return xr.DataArray(data, dims=order, coords=coords, name="image", attrs=meta)
