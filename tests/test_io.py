"""NetCDF round trip: complex data lossless, attrs preserved, compression on."""

from __future__ import annotations

import netCDF4
import numpy as np
import xarray as xr

import speckle
from speckle.io import open_dataset, to_netcdf


def test_complex_roundtrip_is_lossless_and_attrs_survive(tmp_path):
    src = speckle.spectrum(32, 256.0, k0_dk=3)
    sc = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
    ds = speckle.bscan(sc, src)
    ds.attrs.update({"flag": True, "nothing": None, "cfg": {"a": 1}, "values": [1.0, 2.0]})
    path = tmp_path / "sub" / "b.nc"
    to_netcdf(ds, path)
    back = open_dataset(path)
    np.testing.assert_array_equal(back.field.values, ds.field.values)
    assert back.field.dtype == np.complex128
    assert back.attrs["flag"] == 1 and back.attrs["nothing"] == "none"
    assert back.attrs["cfg"] == '{"a": 1}'
    np.testing.assert_array_equal(back.attrs["values"], [1.0, 2.0])
    assert back.depth.attrs["units"] == "um" and back.attrs["k0_dk"] == ds.attrs["k0_dk"]
    plain = xr.open_dataset(path, engine="netcdf4", auto_complex=True)
    np.testing.assert_array_equal(plain.field.values, ds.field.values)
    plain.close()
    with netCDF4.Dataset(path) as nc:
        assert nc.variables["intensity"].filters()["zlib"]


def test_dataarray_is_written_as_dataset(tmp_path):
    da = xr.DataArray(np.arange(3.0), dims="x", name="v")
    to_netcdf(da, tmp_path / "v.nc")
    np.testing.assert_array_equal(open_dataset(tmp_path / "v.nc").v, da)


def test_labels_read_from_a_file_can_grow(tmp_path):
    """Encodings of data read from a file do not constrain what is written next.

    A string coordinate read back as 8-character labels ("gaussian") and combined with a longer
    label ("rectangular") must not be truncated on writing.
    """
    short = xr.Dataset({"v": ("spectrum", [1.0])}, coords={"spectrum": ["gaussian"]})
    to_netcdf(short, tmp_path / "short.nc")
    long = xr.Dataset({"v": ("spectrum", [2.0])}, coords={"spectrum": ["rectangular"]})
    both = xr.concat([open_dataset(tmp_path / "short.nc"), long], dim="spectrum")
    to_netcdf(both, tmp_path / "both.nc")
    back = open_dataset(tmp_path / "both.nc")
    assert back.spectrum.values.tolist() == ["gaussian", "rectangular"]
    assert back.v.sel(spectrum="rectangular").item() == 2.0


def test_stream_to_netcdf_refuses_the_processes_scheduler_and_runs_on_threads(tmp_path):
    """The netCDF file lock cannot be pickled to other processes: refused before any file is
    made, naming the way out; threads and synchronous write the same numbers."""
    import dask
    import pytest

    from speckle.io import stream_to_netcdf

    src = speckle.spectrum(16, 128.0, k0_dk=3)
    sc = speckle.random_scatterers(4, 2.0, n_pixels=16, depth_range=128.0, seed=1)
    ds = speckle.bscan(sc, src).chunk({"x": 2})
    with dask.config.set(scheduler="processes"):
        with pytest.raises(ValueError, match=r"'processes' scheduler.*threads"):
            stream_to_netcdf(ds, tmp_path / "p.nc", progress=False)
    assert not list(tmp_path.iterdir())  # nothing written, not even a temporary file
    for scheduler in ("threads", "synchronous"):
        with dask.config.set(scheduler=scheduler):
            stream_to_netcdf(ds, tmp_path / f"{scheduler}.nc", progress=False)
        back = open_dataset(tmp_path / f"{scheduler}.nc")
        np.testing.assert_array_equal(back.field.values, ds.field.values)


def test_empty_dataset_round_trips(tmp_path):
    """Zero-length dims are valid netCDF: an empty selection is written and read back as is
    (the contract's documented answer for an empty ``ds``)."""
    from speckle.io import stream_to_netcdf

    src = speckle.spectrum(16, 128.0, k0_dk=3)
    sc = speckle.random_scatterers(4, 2.0, n_pixels=16, depth_range=128.0, seed=1)
    ds = speckle.bscan(sc, src)
    empty = ds.isel(depth=slice(0, 0), x=slice(0, 0))
    to_netcdf(empty, tmp_path / "e.nc")
    stream_to_netcdf(empty, tmp_path / "s.nc", progress=False)
    for name in ("e.nc", "s.nc"):
        back = open_dataset(tmp_path / name)
        assert dict(back.sizes) == {"depth": 0, "x": 0}
        xr.testing.assert_equal(back, empty)
