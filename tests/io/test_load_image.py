"""speckle.load_image: every reader on a file written in its format, and the refusals.

Each test writes a small known array in one format (MATLAB v7.3 through h5py as MATLAB lays it
out: column-major, complex as a compound of ``real`` and ``imag``) and checks that the loaded
DataArray holds exactly those values, in (depth, x) order, with µm coordinates.
"""

from __future__ import annotations

import hashlib

import h5py
import numpy as np
import pytest
import tifffile
import xarray as xr
import zarr
from scipy import io as sio

from speckle.data import SAMPLES, sample_path
from speckle.io import load_image

RNG = np.random.default_rng(5)
NZ, NX = 6, 4
FIELD = RNG.normal(size=(NZ, NX)) + 1j * RNG.normal(size=(NZ, NX))  # (depth, x)
KW = {"pixel_size": 5.75, "pitch": 2.0}


def check(da, expected, kind="complex"):
    assert da.dims == ("depth", "x")
    np.testing.assert_array_equal(da.values, expected)
    np.testing.assert_allclose(da.depth, np.arange(NZ) * 5.75)
    np.testing.assert_allclose(da.x, np.arange(NX) * 2.0)
    assert da.depth.attrs["units"] == "um" and da.x.attrs["units"] == "um"
    assert da.attrs["kind"] == kind


def test_npy(tmp_path):
    np.save(tmp_path / "a.npy", FIELD.T)  # stored (x, depth)
    check(load_image(tmp_path / "a.npy", kind="complex", dims=("x", "depth"), **KW), FIELD)


def test_mat_v5(tmp_path):
    sio.savemat(tmp_path / "a.mat", {"bscan": np.abs(FIELD), "other": 1.0})
    da = load_image(tmp_path / "a.mat", kind="amplitude", dims=("depth", "x"), **KW)
    check(da, np.abs(FIELD), "amplitude")


def test_mat_v73_complex_compound_as_matlab_writes_it(tmp_path):
    """MATLAB writes an m x n complex array column-major: an HDF5 (n, m) compound real/imag."""
    path = tmp_path / "a.mat"
    compound = np.dtype([("real", "<f8"), ("imag", "<f8")])
    disk = np.empty((NX, NZ), dtype=compound)  # MATLAB's (depth, x) = (NZ, NX) reversed
    disk["real"], disk["imag"] = FIELD.real.T, FIELD.imag.T
    with h5py.File(path, "w", userblock_size=512) as f:
        f.create_dataset("field", data=disk).attrs["MATLAB_class"] = np.bytes_("double")
        f.create_group("#refs#")
    with open(path, "r+b") as fh:  # MATLAB's 128-byte text header in the user block
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: test HDF5 schema 1.00 .")
    check(load_image(path, kind="complex", dims=("depth", "x"), **KW), FIELD)


def test_mat_v73_real_and_choice_of_variable(tmp_path):
    path = tmp_path / "b.mat"
    with h5py.File(path, "w") as f:
        f["a"] = np.abs(FIELD).T
        f["b"] = np.abs(FIELD).T ** 2
    with pytest.raises(ValueError, match="variable="):
        load_image(path, kind="intensity", dims=("depth", "x"), **KW)
    da = load_image(path, kind="intensity", dims=("depth", "x"), variable="b", **KW)
    check(da, np.abs(FIELD) ** 2, "intensity")


def test_netcdf_named_dims_and_um_coordinates(tmp_path):
    da0 = xr.DataArray(
        FIELD.T,
        dims=("aline", "depth"),
        coords={
            "depth": ("depth", np.arange(NZ) * 5.75, {"units": "um"}),
            "aline": ("aline", np.arange(NX) * 2.0, {"units": "um"}),
        },
        name="field",
    )
    da0.to_dataset().to_netcdf(tmp_path / "a.nc", engine="netcdf4", auto_complex=True)
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):  # a file of old releases
        check(load_image(tmp_path / "a.nc", kind="complex"), FIELD)  # no dims, no sizes needed
    da0.rename(aline="x").to_dataset().to_netcdf(
        tmp_path / "b.nc", engine="netcdf4", auto_complex=True
    )
    check(load_image(tmp_path / "b.nc", kind="complex"), FIELD)


def test_the_retired_dim_name_in_dims_is_read_as_x(tmp_path):
    np.save(tmp_path / "a.npy", np.abs(FIELD).T)
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        da = load_image(tmp_path / "a.npy", kind="amplitude", dims=("aline", "depth"), **KW)
    check(da, np.abs(FIELD), "amplitude")


def test_zarr_xarray_and_bare_array(tmp_path):
    xr.DataArray(np.abs(FIELD), dims=("depth", "x"), name="amp").to_dataset().to_zarr(
        tmp_path / "a.zarr"
    )
    check(load_image(tmp_path / "a.zarr", kind="amplitude", **KW), np.abs(FIELD), "amplitude")
    z = zarr.open_array(str(tmp_path / "b.zarr"), mode="w", shape=(NX, NZ), dtype="f8")
    z[...] = np.abs(FIELD).T
    da = load_image(tmp_path / "b.zarr", kind="amplitude", dims=("x", "depth"), **KW)
    check(da, np.abs(FIELD), "amplitude")


def test_tiff_stack_is_a_frame_dim(tmp_path):
    frames = (np.abs(RNG.normal(size=(3, NZ, NX))) * 100).astype(np.uint16)
    tifffile.imwrite(tmp_path / "s.tif", frames)
    da = load_image(tmp_path / "s.tif", kind="log", dims=("frame", "depth", "x"), **KW)
    assert da.dims == ("frame", "depth", "x") and list(da.frame.values) == [0, 1, 2]
    np.testing.assert_array_equal(da.values, frames)
    assert da.attrs["clip_high"] == 65535 and da.attrs["dtype"] == "uint16"


def test_refusals_name_what_to_pass(tmp_path):
    np.save(tmp_path / "a.npy", np.abs(FIELD))
    path = tmp_path / "a.npy"
    with pytest.raises(ValueError, match=r"ambiguous; pass dims="):
        load_image(path, kind="amplitude", **KW)
    with pytest.raises(ValueError, match=r"pixel_size missing.*pass pixel_size="):
        load_image(path, kind="amplitude", dims=("depth", "x"), pitch=1.0)
    with pytest.raises(ValueError, match=r"pitch missing.*pass pitch="):
        load_image(path, kind="amplitude", dims=("depth", "x"), pixel_size=1.0)
    with pytest.raises(ValueError, match="kind"):
        load_image(path, kind="decibel", dims=("depth", "x"), **KW)
    with pytest.raises(ValueError, match="dims"):
        load_image(path, kind="amplitude", dims=("depth",), **KW)
    with pytest.raises(TypeError, match="kind='complex'"):
        np.save(tmp_path / "c.npy", FIELD)
        load_image(tmp_path / "c.npy", kind="amplitude", dims=("depth", "x"), **KW)
    bad = np.abs(FIELD)
    bad[0, 0] = np.nan
    np.save(tmp_path / "n.npy", bad)
    with pytest.raises(ValueError, match="NaN"):
        load_image(tmp_path / "n.npy", kind="amplitude", dims=("depth", "x"), **KW)
    with pytest.raises(ValueError, match="suffix"):
        (tmp_path / "a.png").write_bytes(b"")
        load_image(tmp_path / "a.png", kind="log", dims=("depth", "x"), **KW)


def test_shipped_sample_matches_its_readme():
    """The package data are the documented files (sha256 in their README) and load."""
    readme = (sample_path("pdms").parent / "README.md").read_text()
    for name in SAMPLES:
        digest = hashlib.sha256(sample_path(name).read_bytes()).hexdigest()
        assert digest in readme, name
    assert (sample_path().parent / "LICENSE").read_text().startswith("MIT License")
    da = load_image(sample_path("pdms"), kind="log", dims=("depth", "x"), **KW)
    assert da.shape == (512, 512) and da.attrs["dtype"] == "uint8"
