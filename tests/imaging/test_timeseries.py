"""Imaging in time: M-mode, snapshot and raster B-scan series against the project's imaging.

Exact checks: each frame (or A-line) is the image of the positions at its time, the same
numbers whatever the chunking and the Dask scheduler.
"""

from __future__ import annotations

import dask
import numpy as np
import pytest

import speckle
from speckle.imaging import timeseries as ts
from speckle.scene import motion as mo
from speckle.scene.regions import background, make_regions

N, H, W0, P = 32, 128.0, 6.0, 3.0


@pytest.fixture(scope="module")
def setup():
    sc = speckle.shared_scene(
        make_regions(background(density=0.2)), z_range=(0.0, H), x_range=(0.0, 96.0), seed=2
    )
    src = speckle.spectrum(N, H, k0_dk=6)
    return sc, src


def test_mmode_is_the_image_at_each_time(setup):
    sc, src = setup
    t = np.arange(6) * 1e-3
    moved = mo.brownian_motion(sc, t, diffusion=5.0, seed=1)
    m = ts.mmode(moved, src, waist=W0, x=48.0, time_chunk=4)
    assert m.field.dims == ("time", "depth") and m.time.attrs["units"] == "s"
    ref = np.stack(
        [
            speckle.scan_image(
                moved.isel(time=i, drop=True), src, waist=W0, lines=[48.0]
            ).field.values[:, 0]
            for i in range(t.size)
        ]
    )
    np.testing.assert_allclose(m.field.values, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    # chunking and scheduler do not change a bit
    m2 = ts.mmode(moved, src, waist=W0, x=48.0, time_chunk=1)
    with dask.config.set(scheduler="synchronous"):
        a = m2.field.values
    with dask.config.set(scheduler="threads"):
        b = m.field.values
    np.testing.assert_array_equal(a, b)


def test_snapshot_series_carries_time(setup):
    sc, src = setup
    t = np.arange(3) * 1e-3
    moved = mo.flow_motion(sc, t, velocity=[0.0, 500.0])
    x = speckle.scan_lines(16, P, start=24.0)
    out = ts.bscan_series(moved, src, waist=W0, lines=x)
    assert out.field.dims == ("time", "depth", "x")
    np.testing.assert_array_equal(out.time.values, t)
    one = speckle.scan_image(moved.isel(time=2, drop=True), src, waist=W0, lines=x).field.values
    np.testing.assert_array_equal(out.field.values[2], one)


def test_raster_lines_at_their_own_times(setup):
    sc, src = setup
    x = speckle.scan_lines(8, P, start=30.0)
    t = ts.raster_times(2, x.size, line_rate=2000.0, frame_interval=0.01)
    moved = mo.flow_motion(sc, t, velocity=[0.0, 400.0])
    out = ts.bscan_series(moved, src, waist=W0, lines=x, line_rate=2000.0, chunk=3)
    assert out.field.dims == ("time", "depth", "x")
    np.testing.assert_allclose(out.time.values, [0.0, 0.01])
    np.testing.assert_allclose(out.line_time.values, t.reshape(2, -1))
    f = out.field.values
    for fr, i in [(0, 0), (0, 5), (1, 7)]:
        pos = moved.isel(time=fr * x.size + i, drop=True)
        ref = speckle.scan_image(pos, src, waist=W0, lines=[x[i]]).field.values[:, 0]
        np.testing.assert_allclose(f[fr, :, i], ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    again = ts.bscan_series(moved, src, waist=W0, lines=x, line_rate=2000.0, chunk=8)
    np.testing.assert_array_equal(again.field.values, f)


def test_independent_lines_series():
    src = speckle.spectrum(N, H, k0_dk=6)
    sc = speckle.random_scatterers(4, 8.0, n_pixels=N, depth_range=H, seed=1)
    moved = mo.brownian_motion(sc, [0.0, 1.0], diffusion=0.01, seed=0)
    out = ts.bscan_series(moved, src)
    assert out.field.sizes["time"] == 2
    assert out.field.dims == ("time", "depth", "x")  # the scene's lines are the image's x


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda sc, src: ts.mmode(sc, src, waist=W0, x=1.0), "time"),
        (lambda sc, src: ts.bscan_series(sc, src, waist=W0, lines=[1.0, 2.0]), "time"),
        (lambda sc, src: ts.raster_times(2, 4, line_rate=0.0), "line_rate"),
        (lambda sc, src: ts.raster_times(2, 4, line_rate=10.0, frame_interval=0.1), "scan"),
    ],
)
def test_bad_input_is_refused(setup, call, match):
    sc, src = setup
    with pytest.raises(ValueError, match=match):
        call(sc, src)


def test_raster_times_must_match(setup):
    sc, src = setup
    x = speckle.scan_lines(4, P, start=30.0)
    moved = mo.flow_motion(sc, np.arange(8) * 1e-3, velocity=[0.0, 1.0])
    with pytest.raises(ValueError, match="line_rate"):
        ts.bscan_series(moved, src, waist=W0, lines=x, line_rate=2000.0)
    with pytest.raises(ValueError, match="n_frames"):
        ts.bscan_series(moved, src, waist=W0, lines=speckle.scan_lines(3, P), line_rate=1000.0)


def test_series_streams_to_netcdf_with_the_same_numbers(setup, tmp_path):
    """Raster series: synchronous, threads and processes schedulers, and the file streamed
    chunk by chunk, hold the same numbers bit for bit."""
    sc, src = setup
    x = speckle.scan_lines(6, P, start=30.0)
    t = ts.raster_times(3, x.size, line_rate=5000.0)
    moved = mo.brownian_motion(sc, t, diffusion=2.0, seed=3)
    out = ts.bscan_series(moved, src, waist=W0, lines=x, line_rate=5000.0, chunk=4)
    values = {}
    for sched in ("synchronous", "threads", "processes"):
        with dask.config.set(scheduler=sched):
            values[sched] = out.field.values
    np.testing.assert_array_equal(values["synchronous"], values["threads"])
    np.testing.assert_array_equal(values["synchronous"], values["processes"])
    path = tmp_path / "series.nc"
    speckle.stream_to_netcdf(out, path, progress=False)
    back = speckle.open_dataset(path)
    np.testing.assert_array_equal(back.field.values, values["synchronous"])
    np.testing.assert_array_equal(back.line_time.values, out.line_time.values)
