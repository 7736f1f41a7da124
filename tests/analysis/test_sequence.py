"""Sequences: accumulate_strain and estimate_strain over a ``frame`` dim, lazily (Dask-backed
input opened from NetCDF or Zarr), streamed to a chunked file, with the same numbers under every
Dask scheduler; and the refusals before any work."""

import dask
import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.io import open_dataset, to_netcdf

N, PIXEL, LINES = 128, 8.0, 16
H = N * PIXEL
S = 2e-3


@pytest.fixture(scope="module")
def frames():
    src = speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm=0.5 * N * np.pi / H)
    totals = [1 - (1 - S) ** i for i in range(4)]
    scene = speckle.deformable_scene(
        LINES, 4.0, n_pixels=N, depth_range=H, seed=3, strain=max(totals)
    )
    b = speckle.bscan(speckle.uniaxial_strain(scene, totals), src, method="nufft", tol=1e-9)
    f = b.field.rename(strain="frame").transpose("frame", "depth", "aline")
    f = f.drop_vars("frame").assign_coords(depth=500.0 + f.depth)  # a window starting at 500 um
    return f.assign_attrs(k0=float(src.attrs["k0"]))


def kw(frames):
    return {"k0": frames.attrs["k0"], "pixel_size": PIXEL}


@pytest.fixture(scope="module")
def in_memory(frames):
    return speckle.accumulate_strain(frames.values, **kw(frames))


def test_coordinates_are_kept(frames):
    out = speckle.accumulate_strain(frames, **kw(frames))
    np.testing.assert_array_equal(out.depth.values, frames.depth.values)
    assert out.depth.values[0] == 500.0
    np.testing.assert_array_equal(out.aline.values, frames.aline.values)


def test_cumulative_follows_the_composed_truth(in_memory):
    truth = [1 - (1 - S) ** k for k in (1, 2, 3)]
    med = [float(np.nanmedian(c)) for c in in_memory["accumulated"].values]
    np.testing.assert_allclose(med, truth, rtol=0.05)


@pytest.mark.parametrize("store", ["netcdf", "zarr"])
@pytest.mark.parametrize("scheduler", ["threads", "processes"])
def test_lazy_streamed_identical_under_schedulers(frames, in_memory, tmp_path, store, scheduler):
    if store == "netcdf":
        to_netcdf(frames.to_dataset(name="field"), tmp_path / "frames.nc")
        lazy = open_dataset(tmp_path / "frames.nc", load=False)["field"]
    else:
        pytest.importorskip("zarr")
        ds = xr.Dataset({"re": frames.real, "im": frames.imag})
        ds.to_zarr(tmp_path / "frames.zarr")
        z = xr.open_zarr(tmp_path / "frames.zarr")
        lazy = z["re"] + 1j * z["im"]
    lazy = lazy.chunk({"frame": 1, "depth": -1, "aline": -1})
    assert lazy.chunks is not None
    with dask.config.set(scheduler=scheduler, num_workers=2):
        out = speckle.accumulate_strain(lazy, path=tmp_path / "seq.nc", **kw(frames))
    # one NetCDF chunk per frame, opened lazily (nothing loaded until asked)
    assert out["accumulated"].encoding["chunksizes"] == (1, N, LINES)
    assert not out["accumulated"].variable._in_memory
    for name in ("interframe", "quality", "accumulated", "position"):
        np.testing.assert_array_equal(out[name].values, in_memory[name].values)


def test_distributed_cluster_gives_the_same_numbers(frames, in_memory, tmp_path):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster),
    ):
        out = speckle.accumulate_strain(
            frames.chunk({"frame": 1}), path=tmp_path / "seq.nc", **kw(frames)
        )
        values = out["accumulated"].values
    np.testing.assert_array_equal(values, in_memory["accumulated"].values)


def test_estimate_strain_over_frames_is_lazy_and_equals_the_loop(frames):
    ref, dfm = frames.isel(frame=slice(0, 3)), frames.isel(frame=slice(1, 4))
    lazy = speckle.estimate_strain(ref.chunk({"frame": 1}), dfm.chunk({"frame": 1}), **kw(frames))
    assert lazy.chunks is not None and "quality" in lazy.coords
    got = lazy.compute()
    for i in range(3):
        one = speckle.estimate_strain(ref.values[i], dfm.values[i], **kw(frames))
        np.testing.assert_array_equal(got.values[i], one)
    np.testing.assert_array_equal(got.depth.values, frames.depth.values)


def test_bad_sequences_are_refused_before_work(frames):
    k = kw(frames)
    with pytest.raises(ValueError, match="only reference has a 'frame' dim"):
        speckle.estimate_strain(frames, frames.isel(frame=0), **k)
    with pytest.raises(ValueError, match="differ in shape"):
        speckle.estimate_strain(frames, frames.isel(depth=slice(0, 64)), **k)
    split = frames.chunk({"frame": 1, "depth": 64})
    with pytest.raises(ValueError, match=r"split depth or aline.*rechunk"):
        speckle.accumulate_strain(split, **k)
    bad = frames.copy()
    bad[2, 5, 5] = np.nan
    with pytest.raises(ValueError, match=r"frames \[2\]"):
        speckle.accumulate_strain(bad, **k)
    with pytest.raises(ValueError, match=r"frames \[2\]"):
        speckle.accumulate_strain(bad.chunk({"frame": 1}), **k)
    with pytest.raises(TypeError, match="complex"):
        speckle.accumulate_strain(abs(frames), **k)
    with pytest.raises(ValueError, match="frame >= 2"):
        speckle.accumulate_strain(frames.values[:1], **k)
