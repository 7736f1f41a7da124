"""Issue 13: nothing silently wrong, nothing lost.

Each reproducer of the issue is a test here: atomic writes (the bytes of an existing file survive
a failed and a killed write), the complex64-after-complex128 guard, NaN-local correlation maps,
refusal of mismatched images and scenes, the float64 depth limit of the fast synthesis
methods, the scan stacking keeping its attributes, and clear errors naming the parameter.
A property test throws malformed inputs at the public functions.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st

import speckle
from speckle.figures.deformation import scan_combine

# private: the fast methods' internals (imaging/_methods)
from speckle.imaging._methods.carrier import float64_error_estimate
from speckle.io import open_dataset, to_netcdf

N, H = 32, 256.0


@pytest.fixture(scope="module")
def src():
    return speckle.spectrum(N, H, k0_dk=3)


@pytest.fixture(scope="module")
def scene():
    return speckle.random_scatterers(16, 2.0, n_pixels=N, depth_range=H, seed=1)


@pytest.fixture(scope="module")
def img(scene, src):
    return speckle.bscan(scene, src)


@pytest.fixture(scope="module")
def pair(src):
    """A reference and a rigidly shifted B-scan, 64 x 32 pixels."""
    sc = speckle.random_scatterers(32, 4.0, n_pixels=64, depth_range=512.0, seed=2)
    s64 = speckle.spectrum(64, 512.0, k0_dk=3)
    return speckle.bscan(sc, s64), speckle.bscan(speckle.translate(sc, 3.0, wrap=True), s64)


# --- 1. atomic writes ----------------------------------------------------------------------


def test_failed_write_keeps_the_existing_file(img, tmp_path):
    path = tmp_path / "k.nc"
    to_netcdf(img, path)
    before = path.read_bytes()
    with pytest.raises(TypeError, match="attribute 'bad'"):
        to_netcdf(img.assign_attrs(bad=1j), path)
    with pytest.raises(TypeError, match=r"attribute 'field.m'"):
        to_netcdf(img.assign(field=img.field.assign_attrs(m=np.zeros((2, 2)))), path)
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["k.nc"]  # no temporary file left behind
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask  # a new file's usual mode


def test_exception_mid_write_keeps_the_existing_file(img, tmp_path, monkeypatch):
    path = tmp_path / "k.nc"
    to_netcdf(img, path)
    before = path.read_bytes()

    def half_then_fail(self, target, **kw):
        with open(target, "wb") as f:
            f.write(b"\x89HDF partial")
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        to_netcdf(img, path)
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["k.nc"]


def test_killed_writer_leaves_the_existing_file_intact(img, tmp_path):
    """A writer SIGKILLed in the middle of writing: the old file is byte-for-byte intact."""
    path = tmp_path / "k.nc"
    to_netcdf(img, path)
    before = path.read_bytes()
    script = textwrap.dedent(
        f"""
        import sys, time
        import numpy as np, xarray as xr
        from speckle.io import to_netcdf

        def slow(self, target, **kw):
            with open(target, "wb") as f:
                f.write(b"\\x89HDF" + bytes(1000))
                f.flush()
                print("writing", flush=True)
                time.sleep(60)

        xr.Dataset.to_netcdf = slow
        to_netcdf(xr.Dataset({{"v": ("x", np.arange(10.0))}}), {str(path)!r})
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    assert path.read_bytes() == before
    np.testing.assert_array_equal(open_dataset(path).field.values, img.field.values)


def test_figure_save_is_atomic(tmp_path, monkeypatch):
    import matplotlib.figure

    from speckle.figures.style import new_figure
    from speckle.pipeline.outputs import save

    path = tmp_path / "f.png"
    fig, _ = new_figure(1, 1)
    save(fig, path)
    before = path.read_bytes()
    assert before.startswith(b"\x89PNG")

    def fail(self, target, **kw):
        open(target, "wb").write(b"partial")
        raise RuntimeError("renderer died")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", fail)
    with pytest.raises(RuntimeError):
        save(new_figure(1, 1)[0], path)
    assert path.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["f.png"]


def test_to_netcdf_refuses_non_datasets_and_directories(img, tmp_path):
    with pytest.raises(TypeError, match="ds must be an xarray"):
        to_netcdf(5, tmp_path / "x.nc")
    with pytest.raises(ValueError, match="path must be a file path"):
        to_netcdf(img, tmp_path)


# --- 2. complex64 after complex128 ---------------------------------------------------------


def test_mixed_complex_precisions_round_trip(tmp_path):
    ds = xr.Dataset({"a": ("x", np.array([1 + 2j])), "b": ("x", np.array([3 + 4j], np.complex64))})
    to_netcdf(ds, tmp_path / "c.nc")
    back = open_dataset(tmp_path / "c.nc")
    assert back.a.item() == 1 + 2j and back.b.item() == 3 + 4j  # was 5.12e+02+3e-05j
    assert back.b.dtype == np.complex128  # promoted (lossless), as documented
    ds["b"].attrs["units"] = "1"
    to_netcdf(ds.assign_attrs(title="t"), tmp_path / "c.nc")
    back = open_dataset(tmp_path / "c.nc")
    assert back.b.attrs["units"] == "1" and back.attrs["title"] == "t"  # attrs kept
    single = xr.Dataset({"b": ("x", np.array([3 + 4j], np.complex64))})
    to_netcdf(single, tmp_path / "s.nc")
    assert open_dataset(tmp_path / "s.nc").b.dtype == np.complex64  # one precision: kept


# --- 3. NaN in correlation maps ------------------------------------------------------------


def _nan_count(m):
    return int(np.isnan(m.values).sum())


@pytest.mark.parametrize("kind", ["intensity", "complex"])
def test_nan_pixel_blanks_only_the_windows_holding_it(pair, kind):
    ref, dfm = pair
    clean = speckle.correlation_map(ref, dfm, window=4, kind=kind)
    field = ref.field.copy()
    field[32, 16] = np.nan
    m = speckle.correlation_map(field.assign_attrs(ref.attrs), dfm, window=4, kind=kind)
    assert _nan_count(m) - _nan_count(clean) == 16  # 4 x 4 windows contain pixel (32, 16)
    blank = np.isnan(m.values) & ~np.isnan(clean.values)
    rows, cols = np.nonzero(blank)
    assert set(rows) == {31, 32, 33, 34} and set(cols) == {15, 16, 17, 18}
    keep = ~np.isnan(m.values)
    np.testing.assert_allclose(m.values[keep], clean.values[keep], rtol=1e-9, atol=1e-12)
    corner = ref.field.copy()
    corner[0, 0] = np.nan
    mc = speckle.correlation_map(corner.assign_attrs(ref.attrs), dfm, window=4, kind=kind)
    # windows start at c - 2: only the first valid centre (2, 2) holds pixel (0, 0)
    assert _nan_count(mc) - _nan_count(clean) == 1 and np.isnan(mc.values[2, 2])


# --- 4. mismatched images ------------------------------------------------------------------


def test_mismatched_images_are_refused(pair, src):
    ref, dfm = pair
    with pytest.raises(ValueError, match="differ along 'x': 32 vs 8"):
        speckle.pearson(ref, dfm.isel(x=slice(0, 8)))
    with pytest.raises(ValueError, match="differ along 'x'"):
        speckle.correlation_map(ref, dfm.isel(x=slice(0, 8)), window=4)
    sc = speckle.random_scatterers(32, 4.0, n_pixels=128, depth_range=512.0, seed=2)
    fine = speckle.bscan(sc, speckle.spectrum(128, 512.0, k0_dk=3))
    with pytest.raises(ValueError, match="differ along 'depth': 64 vs 128"):
        speckle.pearson(ref, fine)
    shifted = dfm.assign_coords(x=dfm.x + 1.0)
    with pytest.raises(ValueError, match="different 'x' coordinates"):
        speckle.pearson(ref, shifted)
    # an extra dim (strain) still broadcasts
    stack = xr.concat([dfm, ref], dim="strain")
    assert speckle.pearson(ref, stack).sizes == {"strain": 2}


def test_compensate_refuses_other_grids_and_a_missing_k0(pair):
    ref, dfm = pair
    disp = speckle.scene.deformation.pixel_displacement(lambda z, x: 3.0 + 0 * z, ref.depth, ref.x)
    assert speckle.compensate(dfm, disp).shape == dfm.field.shape
    with pytest.raises(ValueError, match="different 'depth' coordinates"):
        speckle.compensate(dfm, disp.assign_coords(depth=disp.depth * 2))
    # the field carries its grid (k0) itself now (issue 32): the same as the B-scan's
    np.testing.assert_array_equal(
        speckle.compensate(dfm.field, disp), speckle.compensate(dfm, disp)
    )
    bare = dfm.field.copy()
    del bare.attrs["k0"]  # an image without k0 (e.g. a measured one)
    with pytest.raises(ValueError, match="deformed needs attribute k0"):
        speckle.compensate(bare, disp)


# --- 5. scene against source ---------------------------------------------------------------


def test_bscan_checks_scene_against_source(scene):
    big = speckle.spectrum(128, 2048.0, k0_dk=3)
    with pytest.raises(ValueError, match=r"n_pixels=32.*n_pixels=128"):
        speckle.bscan(scene, big)
    other_depth = speckle.spectrum(N, 512.0, k0_dk=3)
    with pytest.raises(ValueError, match=r"depth_range=256.0.*depth_range=512.0"):
        speckle.bscan(scene, other_depth)


def test_bscan_checks_before_building_a_dask_graph(scene, src):
    lazy = scene.chunk({"aline": 4})
    with pytest.raises(ValueError, match="method must be one of"):
        speckle.bscan(lazy, src, method="bogus")
    with pytest.raises(ValueError, match="tol must be in"):
        speckle.bscan(lazy, src, method="nufft", tol=2.0)
    with pytest.raises(ValueError, match="'scatterer' dim"):
        speckle.bscan(scene.rename(scatterer="s"), src)


# --- 6. fast methods at depths float64 cannot hold -----------------------------------------


@pytest.fixture(scope="module")
def deep():
    n, h = 256, 2048.0
    k0 = 10 * n * np.pi / h
    z = np.random.default_rng(1).uniform(0, 1e15, (4, 256))
    return z, np.ones_like(z), dict(n_pixels=n, depth_range=h, k0=k0)


@pytest.mark.parametrize("method", ["nufft", "nufft32", "psf"])
def test_fast_methods_refuse_depths_beyond_float64(deep, method):
    z, a, kw = deep
    with pytest.raises(ValueError, match=f"method='{method}' cannot reach tol=1e-06"):
        speckle.ascan(z, a, **kw, method=method, tol=1e-6)


def test_auto_and_finufft_stay_within_tol_at_huge_depths(deep):
    z, a, kw = deep
    from speckle.imaging.synthesis import choose_method

    e64 = float64_error_estimate(z, a, kw["depth_range"], kw["k0"], np.ones(kw["n_pixels"]))
    assert choose_method(4, 256, kw["n_pixels"], None, 1e-6, float64_error=e64) == "direct"
    ref = speckle.ascan(z, a, **kw)
    for method in ("auto", "finufft"):
        out = speckle.ascan(z, a, **kw, method=method, tol=1e-6)
        assert np.linalg.norm(out - ref) / np.linalg.norm(ref) <= 1e-6


@pytest.mark.parametrize("zmax", [1e8, 1e10, 1e12])
def test_float64_error_estimate_bounds_the_measured_error(zmax):
    """Prediction vs the nufft error at a kernel tolerance far below it (H not a power of 2).

    The estimate is an rms bound: the measured error lies between 1/4 of it and it.
    """
    # private: the fast methods' internals (imaging/_methods)
    from speckle.imaging._methods.nufft import nufft_ascan

    n, h = 128, 1000.0
    k0 = 10 * n * np.pi / h
    z = np.random.default_rng(3).uniform(0, zmax, (16, 512))
    a = np.ones_like(z, complex)
    ref = speckle.ascan(z, a, n_pixels=n, depth_range=h, k0=k0)
    out = nufft_ascan(z, a, n, h, k0, np.ones(n), tol=1e-13)
    err = np.linalg.norm(out - ref) / np.linalg.norm(ref)
    pred = float64_error_estimate(z, a, h, k0, np.ones(n))
    assert pred / 4 <= err <= pred


def test_near_depths_keep_every_method(src):
    """Ordinary depths (within a few H) cost nothing: every method still runs at tol 1e-10."""
    z = np.random.default_rng(0).uniform(-H, 3 * H, (4, 64))
    ref = speckle.ascan(z, 1.0, n_pixels=N, depth_range=H, k0=src.attrs["k0"])
    for method in ("nufft", "auto"):
        out = speckle.ascan(
            z, 1.0, n_pixels=N, depth_range=H, k0=src.attrs["k0"], method=method, tol=1e-10
        )
        assert np.linalg.norm(out - ref) / np.linalg.norm(ref) <= 1e-10


# --- 7. the stacked scan keeps its attributes ----------------------------------------------


def _point(density, sha):
    ds = xr.Dataset(
        {
            "intensity_correlation": (
                ("density", "k0_dk", "spectrum", "strain"),
                np.ones((1, 1, 1, 2)),
                {"units": "1", "long_name": "intensity correlation"},
            )
        },
        coords={
            "density": ("density", [density], {"units": "1", "long_name": "scatterers per pixel"}),
            "k0_dk": ("k0_dk", [10.0], {"units": "1"}),
            "spectrum": ("spectrum", ["rectangular"]),
            "strain": ("strain", [0.0, 0.1], {"units": "1", "long_name": "compressive strain"}),
        },
    )
    return ds.assign_attrs(config_sha256=sha, n_pixels=32, density=density)


def test_scan_combine_keeps_units_long_names_and_config_hash(tmp_path):
    points = [_point(1.0, "a" * 64), _point(4.0, "b" * 64)]
    paths = []
    for i, p in enumerate(points):
        paths.append(tmp_path / f"p{i}.nc")
        to_netcdf(p, paths[-1])
    to_netcdf(scan_combine([open_dataset(p) for p in paths]), tmp_path / "scan.nc")
    ds = open_dataset(tmp_path / "scan.nc")
    assert ds.intensity_correlation.attrs["units"] == "1"
    assert ds.intensity_correlation.attrs["long_name"] == "intensity correlation"
    assert ds.density.attrs["units"] == "1" and ds.strain.attrs["long_name"] == "compressive strain"
    assert len(ds.attrs["config_sha256"]) == 64 and ds.attrs["n_pixels"] == 32
    assert "density" not in ds.attrs  # differs between points
    other = scan_combine([_point(1.0, "a" * 64), _point(4.0, "c" * 64)])
    assert other.attrs["config_sha256"] != ds.attrs["config_sha256"]


def test_scan_combine_refuses_duplicate_points():
    with pytest.raises(ValueError, match="appear more than once"):
        scan_combine([_point(1.0, "a" * 64), _point(1.0, "a" * 64)])


# --- unclear errors now name the parameter -------------------------------------------------


def _cases(scene, src, img, pair):
    ref, dfm = pair
    disp = speckle.scene.deformation.pixel_displacement(lambda z, x: 0 * z, ref.depth, ref.x)
    return [
        (
            lambda: speckle.random_scatterers(
                4, 1.0, n_pixels=N, depth_range=H, seed=0, z_range=5.0
            ),
            TypeError,
            "z_range",
        ),
        (lambda: speckle.uniaxial_strain(scene, []), ValueError, "strain must hold"),
        (lambda: speckle.translate(scene, []), ValueError, "dz must be"),
        (lambda: speckle.uniaxial_strain(img, 0.01), TypeError, "scene must be a scatterer field"),
        (
            lambda: speckle.displace(scene, lambda z, x: np.zeros(3)),
            ValueError,
            "displacement function returned u_z of shape",
        ),
        (lambda: speckle.track(ref, dfm, step=(0, 1)), ValueError, r"step\[depth\]"),
        (
            lambda: speckle.track(ref.field.where(ref.depth > 8).assign_attrs(ref.attrs), dfm),
            ValueError,
            r"reference holds \d+ NaN or infinite pixels",
        ),
        (
            lambda: speckle.ascan(["8.0"], [1.0], n_pixels=8, depth_range=64.0, k0=0.0),
            TypeError,
            "z ",
        ),
        (
            lambda: speckle.ascan([True, False], [1.0, 1.0], n_pixels=8, depth_range=64.0, k0=0.0),
            TypeError,
            "z ",
        ),
        (lambda: speckle.uniaxial_strain(scene, "0.01"), TypeError, "strain"),
        (lambda: speckle.uniaxial_strain(scene, [True]), TypeError, "strain"),
        (
            lambda: speckle.random_scatterers(10**6, 4.0, n_pixels=4096, depth_range=H, seed=0),
            ValueError,
            "n_alines, density or z_range too large.*GiB",
        ),
        (
            lambda: speckle.ascan(np.zeros((2**20, 1)), 1.0, n_pixels=2**20, depth_range=H, k0=0.0),
            ValueError,
            "n_pixels too large.*1048576 A-scans",
        ),
        (
            lambda: speckle.compensate(dfm, disp.isel(depth=slice(0, 10))),
            ValueError,
            "differ along 'depth'",
        ),
    ]


def test_unclear_errors_now_name_the_parameter(scene, src, img, pair):
    for call, exc, match in _cases(scene, src, img, pair):
        with pytest.raises(exc, match=match):
            call()


def test_tracking_accepts_a_one_pixel_step(pair):
    ref, dfm = pair
    out = speckle.track(ref, dfm, window=(16, 8), step=(1, 8))
    assert out.sizes["depth"] == 64 - 16 + 1
    coarse = speckle.track(ref, dfm, window=(16, 8), step=(16, 8))
    np.testing.assert_array_equal(out.uz.values[::16], coarse.uz.values)  # the same windows
    assert float(abs(out.uz - 3.0).mean()) < 0.05 * 8.0  # rigid 3 µm shift, < 0.05 px mean


@pytest.mark.filterwarnings("ignore:load_measured is retired:FutureWarning")
def test_measured_roi_must_be_a_mapping_inside_the_image(tmp_path):
    from speckle.analysis.measured import load_measured

    path = tmp_path / "m.npy"
    np.save(path, np.random.default_rng(0).uniform(1, 2, (20, 30)))
    assert load_measured(path, roi={"depth": [0, 20], "x": [5, 30]}).shape == (20, 25)
    with pytest.raises(TypeError, match="roi must be a mapping"):
        load_measured(path, roi=[0, 5])
    with pytest.raises(ValueError, match=r"roi\['depth'\] must be an integer in \[0, 20\]"):
        load_measured(path, roi={"depth": [0, 40]})
    with pytest.raises(ValueError, match=r"roi\['x'\] must be an integer in \[0, 30\]"):
        load_measured(path, roi={"x": [31, None]})


# --- property test: malformed inputs -------------------------------------------------------

BAD_VALUES = st.sampled_from(
    [None, "8", True, -1, 0, 1.5, np.nan, np.inf, -np.inf, 1e300, [], [1, 2, 3], {"a": 1}, 1j]
)
PARAMS = {
    "ascan": ("z", "amplitude", "n_pixels", "depth_range", "k0", "method", "tol"),
    "random_scatterers": ("n_alines", "density", "n_pixels", "depth_range", "seed", "z_range"),
    "spectrum": ("n_pixels", "depth_range", "k0_dk"),
    "uniaxial_strain": ("strain", "poisson_ratio"),
    "correlation_map": ("window", "kind"),
    "pearson": ("kind",),
    "bscan": ("normalise", "method", "tol"),
    "translate": ("dz", "dx"),
    "track": ("window", "step", "upsample", "max_error"),
}


def _call(name, param, value, scene, pair):
    ref, dfm = pair
    valid = {
        "ascan": dict(
            z=[8.0, 13.0],
            amplitude=[1.0, 0.5],
            n_pixels=8,
            depth_range=64.0,
            k0=0.1,
            method="nufft",
            tol=1e-6,
        ),
        "random_scatterers": dict(
            n_alines=2, density=1.0, n_pixels=8, depth_range=64.0, seed=0, z_range=(0.0, 64.0)
        ),
        "spectrum": dict(n_pixels=8, depth_range=64.0, k0_dk=3.0),
        "uniaxial_strain": dict(strain=[0.0, 0.01], poisson_ratio=0.0),
        "correlation_map": dict(window=4, kind="intensity"),
        "pearson": dict(kind="intensity"),
        "bscan": dict(normalise="none", method="nufft", tol=1e-6),
        "translate": dict(dz=1.0, dx=0.0),
        "track": dict(window=(16, 8), step=(16, 8), upsample=4, max_error=0.5),
    }[name]
    kw = {**valid, param: value}
    if name == "ascan":
        return speckle.ascan(kw.pop("z"), kw.pop("amplitude"), **kw)
    if name == "random_scatterers":
        return speckle.random_scatterers(kw.pop("n_alines"), kw.pop("density"), **kw)
    if name == "spectrum":
        return speckle.spectrum(kw.pop("n_pixels"), kw.pop("depth_range"), **kw)
    if name == "uniaxial_strain":
        return speckle.uniaxial_strain(scene, kw.pop("strain"), **kw)
    if name == "bscan":
        return speckle.bscan(scene, speckle.spectrum(8, 64.0, k0_dk=3.0), **kw)
    if name == "translate":
        return speckle.translate(scene, kw.pop("dz"), **kw)
    if name == "track":
        return speckle.track(ref, dfm, **kw)
    return getattr(speckle, name)(ref, dfm, **kw)


def _is_valid_result(out) -> bool:
    if isinstance(out, np.ndarray):
        return bool(np.all(np.isfinite(out)))
    if isinstance(out, xr.DataArray | xr.Dataset):
        arrays = [out] if isinstance(out, xr.DataArray) else list(out.data_vars.values())
        return all(a.dtype.kind in "fcbiu" for a in arrays)
    return False


@given(target=st.sampled_from([(n, p) for n, ps in PARAMS.items() for p in ps]), value=BAD_VALUES)
def test_malformed_inputs_raise_naming_a_parameter_or_give_valid_results(target, value, pair):
    name, param = target
    scene = speckle.deformable_scene(4, 1.0, n_pixels=8, depth_range=64.0, seed=0, strain=0.01)
    try:
        out = _call(name, param, value, scene, pair)
    except (TypeError, ValueError) as err:
        assert param.split("_")[0] in str(err) or param in str(err), (param, value, str(err))
    else:
        assert _is_valid_result(out), (name, param, value)


@pytest.mark.parametrize("dtype", [float, complex])
def test_finite_check_takes_huge_finite_values_and_finds_every_bad_one(dtype):
    """The finite check sums first (NaN and inf propagate) and checks elementwise only when the
    sum is not finite: huge finite values whose sum overflows are accepted, bad values among
    them are still found and counted."""
    from speckle._validate import as_finite_array  # private: the shared input check

    huge = np.array([1e308, 1e308, -1.0], dtype=dtype)
    np.testing.assert_array_equal(as_finite_array(huge, "v", dtype=dtype), huge)
    for bad, count in (([1e308, 1e308, np.nan], 1), ([np.inf, -np.inf, 1.0], 2), ([np.nan], 1)):
        with pytest.raises(ValueError, match=f"v must be finite; it holds {count} NaN"):
            as_finite_array(np.array(bad, dtype=dtype), "v", dtype=dtype)
