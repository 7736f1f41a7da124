"""NetCDF round trip: complex data lossless, attrs preserved, compression on."""

from __future__ import annotations

import netCDF4
import numpy as np
import xarray as xr

import speckle
from speckle.io import open_dataset, to_netcdf


def test_complex_roundtrip_is_lossless_and_attrs_survive(tmp_path):
    src = speckle.spectrum(32, 256.0, k0_dk=3)
    sc = speckle.random_scatterers(4, 2.0, n_pixels=32, depth=256.0, seed=1)
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
