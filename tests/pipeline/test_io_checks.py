"""Issue 21: speckle.io refuses bad arguments by name (no netCDF4 'Invalid argument', no
str/int comparison, no bare OSError), before writing anything."""

from __future__ import annotations

import dask.array as da
import numpy as np
import pytest
import xarray as xr

from speckle.io import open_dataset, stream_to_netcdf, to_netcdf

DS = xr.Dataset({"f": (("a",), da.ones(4, chunks=2))})


@pytest.mark.parametrize(
    ("complevel", "error", "match"),
    [(-3, ValueError, r"complevel must be an integer in \[0, 9\], got -3"),
     (10, ValueError, r"complevel must be an integer in \[0, 9\], got 10"),
     ("3", TypeError, "complevel must be an integer, got str"),
     (1.5, TypeError, "complevel must be an integer")],
)  # fmt: skip
def test_complevel_is_checked(tmp_path, complevel, error, match):
    with pytest.raises(error, match=match):
        stream_to_netcdf(DS, tmp_path / "x.nc", complevel=complevel, progress=False)
    assert not (tmp_path / "x.nc").exists()


def test_flags_are_booleans(tmp_path):
    with pytest.raises(TypeError, match="progress must be True or False"):
        stream_to_netcdf(DS, tmp_path / "x.nc", progress="no")
    to_netcdf(DS.compute(), tmp_path / "ok.nc")
    with pytest.raises(TypeError, match="load must be True or False"):
        open_dataset(tmp_path / "ok.nc", load="False")


def test_names_and_files_are_checked(tmp_path):
    with pytest.raises(ValueError, match="dimension name 1 cannot be stored"):
        to_netcdf(xr.Dataset({"a": ((1,), np.ones(3))}), tmp_path / "x.nc")
    bad = tmp_path / "bad.nc"
    bad.write_text("not a netCDF file")
    with pytest.raises(ValueError, match="is not a readable netCDF4/HDF5 file"):
        open_dataset(bad)
    with pytest.raises(FileNotFoundError, match="is not a file"):
        open_dataset(tmp_path / "missing.nc")
