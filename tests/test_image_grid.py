"""Images carry their grid (issue 32): k0, n_pixels and depth_range on every image DataArray.

``speckle.conventions.grid(img.field)`` finds ``k0`` on the DataArray alone (not only on the
B-scan Dataset), through ``isel``/``sel``, so that ``estimate_strain``, ``estimate_displacement``
and ``accumulate_strain`` read ``k0`` and the pixel size from labelled images. Exact checks: the
call without ``k0``/``pixel_size`` gives the same numbers, bit for bit, as the call with them.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.conventions import GRID_ATTRS, grid, grid_attrs, with_grid
from speckle.scene.regions import background, make_regions
from speckle.synthoct.files import ScannerConfig

N, H = 64, 512.0  # pixels, depth range (µm): pixel 8 µm


@pytest.fixture(scope="module")
def compressed(compressed_pair):
    """The README's call, small (``tests/conftest.py``: N x 16 px over H)."""
    return compressed_pair


def _same(a, b):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_every_variable_of_a_bscan_carries_its_grid_through_isel_and_sel(compressed):
    src, img = compressed
    k0 = float(src.attrs["k0"])
    for name in ("field", "amplitude", "intensity"):
        for da in (img[name], img[name].isel(strain=0), img[name].sel(depth=slice(0.0, 200.0))):
            g = grid(da)
            assert (g.k0, g.n_pixels, g.depth_range, g.pixel_size) == (k0, N, H, H / N)
            assert da.attrs["k0_units"] == "rad/um" and da.attrs["depth_range_units"] == "um"
    assert grid(img).k0 == k0  # the Dataset keeps them too


def test_the_readme_call_without_k0_equals_the_explicit_call(compressed):
    src, img = compressed
    ref, dfm = img.field.isel(strain=0), img.field.isel(strain=1)
    kw = {"k0": float(src.attrs["k0"]), "pixel_size": H / N}
    read = speckle.estimate_strain(ref, dfm, window=(16, 4))
    _same(read, speckle.estimate_strain(ref.values, dfm.values, window=(16, 4), **kw))
    _same(read, speckle.estimate_strain(ref, dfm, window=(16, 4), **kw))
    assert 0.003 < float(np.nanmedian(read)) < 0.005  # the applied 4e-3 (window noise)
    u = speckle.estimate_displacement(ref, dfm, method="phase")
    _same(u, speckle.estimate_displacement(ref.values, dfm.values, method="phase", **kw))
    frames = img.field.rename(strain="frame")
    acc = speckle.accumulate_strain(frames, window=(16, 4))
    explicit = speckle.accumulate_strain(frames.values, window=(16, 4), **kw)
    for var in ("interframe", "quality", "accumulated", "position"):
        _same(acc[var], explicit[var])


def test_a_disagreeing_k0_is_refused_naming_both_values(compressed):
    src, img = compressed
    ref, dfm = img.field.isel(strain=0), img.field.isel(strain=1)
    k0 = float(src.attrs["k0"])
    with pytest.raises(ValueError, match=rf"k0=1\.0 disagrees with reference's attributes \({k0}"):
        speckle.estimate_strain(ref, dfm, k0=1.0)
    with pytest.raises(ValueError, match=r"k0=2\.0 disagrees with frames's attributes"):
        speckle.accumulate_strain(img.field.rename(strain="frame"), k0=2.0)
    speckle.estimate_strain(ref, dfm, k0=k0 * (1 + 1e-12), window=(16, 4))  # within 1e-9: agrees


def test_numpy_images_and_measured_images_without_k0_are_refused_naming_k0(compressed, tmp_path):
    _, img = compressed
    ref, dfm = img.field.isel(strain=0).values, img.field.isel(strain=1).values
    with pytest.raises(ValueError, match="estimate_strain needs k0: give k0="):
        speckle.estimate_strain(ref, dfm, pixel_size=8.0)
    np.save(tmp_path / "measured.npy", ref)
    measured = speckle.load_image(
        tmp_path / "measured.npy", kind="complex", pixel_size=8.0, pitch=4.0, dims=("depth", "x")
    )
    assert grid(measured).k0 is None and grid(measured).pixel_size == 8.0
    with pytest.raises(ValueError, match=r"needs k0: give k0= \(reference does not carry it"):
        speckle.estimate_strain(measured, measured)
    with pytest.raises(ValueError, match="needs k0: give k0="):
        speckle.accumulate_strain(xr.concat([measured, measured], "frame"))
    out = speckle.estimate_strain(measured, measured, k0=3.0, window=(16, 4))
    assert out.shape == measured.shape  # k0 given: the measured image's pixel from its depth


def test_every_image_producer_writes_the_grid_on_its_images():
    src = speckle.spectrum(32, 128.0, k0_dk=6)
    k0 = float(src.attrs["k0"])
    sc = speckle.shared_scene(
        make_regions(background(density=0.05)), z_range=(0.0, 128.0), x_range=(0.0, 32.0), seed=2
    )
    lines = speckle.scan_lines(4, 4.0, start=10.0)
    moved = speckle.scene.motion.brownian_motion(sc, [0.0, 1e-3], diffusion=1.0, seed=1)
    images = {
        "scan_image": speckle.scan_image(sc, src, waist=4.0, lines=lines).field,
        "bscan_series": speckle.bscan_series(moved, src, waist=4.0, lines=lines).intensity,
        "mmode": speckle.mmode(moved, src, waist=4.0, x=16.0).field,
        "speckle_free_image": speckle.speckle_free_image(sc, src, waist=4.0, lines=lines),
        "spatial_looks": speckle.spatial_looks(sc, src, [0.0, 2.0], waist=4.0, lines=lines),
        "angular_looks": speckle.angular_looks(sc, src, [0.0, 3.0], waist=4.0, lines=lines),
        "polarization_looks": speckle.polarization_looks(
            sc, src, 0.5, seed=1, waist=4.0, lines=lines
        ),
        "temporal_looks": speckle.temporal_looks(
            sc, src, 2, diffusion=1.0, interval=1e-3, seed=1, waist=4.0, lines=lines
        ),
    }
    for name, da in images.items():
        g = grid(da.isel(depth=slice(1, None)))
        assert (g.k0, g.n_pixels, g.depth_range) == (k0, 32, 128.0), name
    cfg = ScannerConfig(n_pixels=16, pixel_size=4.0, n_lines=4, x_max=16.0, n_scatterers=4)
    table = np.array([[0.0, 0.0, 20.0, 30.0], [2.0, 0.0, 40.0, 30.0]] * 2)
    field = speckle.synthoct_scan(table, cfg, field=True)
    g = grid(field)
    assert (g.k0, g.n_pixels, g.depth_range, g.pixel_size) == (cfg.k0, 16, 64.0, 4.0)


def test_with_grid_spreads_the_dataset_grid_and_grid_attrs_match_the_source():
    src = speckle.spectrum(16, 64.0, k0_dk=5)
    made = grid_attrs(16, 64.0, float(src.attrs["k0"]))
    assert made == {k: src.attrs[k] for k in GRID_ATTRS}  # the spectrum's own grid attrs
    assert "k0" not in grid_attrs(16, 64.0)
    ds = xr.Dataset(
        {"field": (("depth", "x"), np.ones((2, 3))), "lines": ("x", np.arange(3.0))},
        attrs={"n_pixels": 2, "depth_range": 4.0, "k0": 1.5, "other": 1},
    )
    out = with_grid(ds)
    assert out.field.attrs == {"n_pixels": 2, "depth_range": 4.0, "k0": 1.5}
    assert out.lines.attrs == {} and ds.field.attrs == {}  # no depth: none; the input unchanged
    _same(out.field, ds.field)
    with pytest.raises(TypeError, match="n_pixels, depth_range and k0"):
        with_grid(ds, pitch=3.0)
    assert dataclasses.asdict(grid(with_grid(ds.field, n_pixels=2, depth_range=4.0)))["k0"] is None


def test_g1_models_read_k0_from_the_spectrum():
    src = speckle.spectrum(32, 256.0, k0_dk=8)
    k0, t = float(src.attrs["k0"]), np.array([0.0, 1e-3, 4e-3])
    kw = {"spectrum": src, "waist": 5.0}
    _same(
        speckle.g1_brownian(t, diffusion=2.0, **kw),
        speckle.g1_brownian(t, diffusion=2.0, k0=k0, **kw),
    )
    _same(
        speckle.g1_ballistic(t, speed=50.0, ndim=2, **kw),
        speckle.g1_ballistic(t, speed=50.0, ndim=2, k0=k0, **kw),
    )
    with pytest.raises(ValueError, match=r"k0=1\.0 disagrees with spectrum's attributes"):
        speckle.g1_brownian(t, diffusion=2.0, k0=1.0, spectrum=src)
    with pytest.raises(TypeError, match="k0 is needed"):
        speckle.g1_brownian(t, diffusion=2.0)
