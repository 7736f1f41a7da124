"""The labelled scan API: image == beam_scan, 3-D lines, laziness, chunk invariance, lateral
correlation against Campbell's theorem, streamed NetCDF (local and distributed), bad inputs."""

import os

import dask
import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis.beam import axial_correlation, lateral_correlation
from speckle.imaging import scan
from speckle.io import open_dataset, stream_to_netcdf
from speckle.scene import regions as R

N, H = 32, 256.0  # pixel 8 µm
SRC = speckle.spectrum(N, H, k0_dk=10)
ARGS = {"n_pixels": N, "depth_range": H, "k0": SRC.attrs["k0"], "spectrum": SRC.values}


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def _scene(density=0.05, x_range=(-50.0, 200.0), y_range=None, seed=1, z_range=(0.0, H)):
    reg = speckle.make_regions(R.background(density=density))
    return speckle.shared_scene(
        reg, z_range=z_range, x_range=x_range, y_range=y_range, seed=seed, tile=64.0
    )


@pytest.mark.parametrize("chunk", [1, 7, 64])
def test_image_equals_beam_scan(chunk):
    scene = _scene()
    xs = speckle.scan_lines(30, 5.0)
    ds = speckle.scan_image(scene, SRC, waist=9.0, lines=xs, chunk=chunk)
    assert ds.field.dims == ("depth", "x") and ds.x.attrs["units"] == "um"
    assert ds.depth.values[1] == H / N
    ref = speckle.beam_scan(
        scene.z.values, scene.x.values, scene.amplitude.values, lines=xs, waist=9.0, **ARGS
    )
    assert _rel(ds.field.values, ref.T) < 1e-13
    np.testing.assert_allclose(ds.intensity.values, np.abs(ref.T) ** 2, rtol=1e-12)


def test_wrap_keeps_or_drops_the_tissue_below_the_image():
    scene = _scene(z_range=(-20.0, 1.5 * H))
    xs = speckle.scan_lines(6, 10.0, start=20.0)
    z, x, a = scene.z.values, scene.x.values, scene.amplitude.values
    inside = (z >= 0) & (z < H)
    for wrap, keep in ((True, np.ones(z.size, bool)), (False, inside)):
        ds = speckle.scan_image(scene, SRC, waist=6.0, lines=xs, wrap=wrap, chunk=4)
        ref = speckle.beam_scan(z[keep], x[keep], a[keep], lines=xs, waist=6.0, **ARGS)
        assert _rel(ds.field.values, ref.T) < 1e-13


def test_lines_beyond_the_scene_window_warn_that_they_image_empty_space():
    """Lines farther than the beam reach from the scene's x window see no scatterer: their
    image is zeros (right) and a warning says why; lines within reach do not warn."""
    scene = _scene(x_range=(0.0, 100.0))
    reach = scan.beam_reach(6.0)
    far = np.array([100.0 + reach + 1.0, 100.0 + reach + 5.0])
    with pytest.warns(UserWarning, match="2 of 2 lines .* image empty space"):
        ds = speckle.scan_image(scene, SRC, waist=6.0, lines=far)
    assert np.all(ds.field.values == 0)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        speckle.scan_image(scene, SRC, waist=6.0, lines=np.array([100.0 + reach - 1.0]))


def test_one_line_on_the_scatterers_is_an_ascan():
    scene = _scene().isel(scatterer=slice(0, 40))
    scene = scene.assign(x=("scatterer", np.full(40, 12.5)))
    ds = speckle.scan_image(scene, SRC, waist=3.0, lines=[12.5])
    ref = speckle.ascan(scene.z.values, scene.amplitude.values, **ARGS)
    assert _rel(ds.field.values[:, 0], ref) < 1e-13


def test_3d_grid_of_lines_against_the_full_gaussian_weight():
    scene = _scene(density=0.001, x_range=(-36.0, 70.0), y_range=(-36.0, 60.0))
    xs, ys = speckle.scan_lines(5, 6.0), speckle.scan_lines(4, 6.0, start=3.0)
    w0 = 8.0
    ds = speckle.scan_image(scene, SRC, waist=w0, lines=xs, y=ys, chunk=3)
    assert ds.field.dims == ("depth", "x", "y") and ds.field.shape == (N, 5, 4)
    z, x, y, a = (scene[v].values for v in ("z", "x", "y", "amplitude"))
    for i, xi in enumerate(xs):
        for k, yk in enumerate(ys):
            w = np.exp(-2 * ((x - xi) ** 2 + (y - yk) ** 2) / w0**2)
            ref = speckle.ascan(z, a * w, **ARGS)
            assert _rel(ds.field.values[:, i, k], ref) < 1e-12


def test_lazy_until_computed(monkeypatch):
    calls = []
    real = speckle.beam_scan

    def counting(*args, **kw):
        if np.size(args[0]):  # the empty call that checks the arguments up front is no work
            calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(scan, "beam_scan", counting)  # the function the chunks' tasks call
    reg = speckle.make_regions(R.background(density=0.05))
    ds = speckle.image_regions(
        reg, SRC, seed=1, waist=6.0, lines=speckle.scan_lines(12, 4.0), chunk=4
    )
    ds2 = speckle.scan_image(_scene(), SRC, waist=6.0, lines=speckle.scan_lines(12, 4.0), chunk=4)
    assert calls == [] and ds.field.chunks == ((N,), (4, 4, 4)) and ds2.field.chunks[1] == (4,) * 3
    first = ds.field[:, :4].values
    assert first.shape == (N, 4)
    assert len(calls) == 1  # one chunk computed, the others untouched


def test_image_regions_is_the_same_whatever_the_chunking_and_scheduler():
    reg = speckle.make_regions(
        R.background(density=0.04), R.circle(100.0, 40.0, 20.0, density=0.3, backscatter=2.0)
    )
    xs = speckle.scan_lines(20, 4.0)
    a = speckle.image_regions(reg, SRC, seed=9, tile=50.0, waist=7.0, lines=xs, chunk=3)
    b = speckle.image_regions(reg, SRC, seed=9, tile=50.0, waist=7.0, lines=xs, chunk=20)
    with dask.config.set(scheduler="threads", num_workers=2):
        fa = a.field.values
    with dask.config.set(scheduler="synchronous"):
        fb = b.field.values
    assert _rel(fa, fb) < 1e-13
    scene = speckle.shared_scene(reg, z_range=(0.0, H), x_range=(-50.0, 130.0), seed=9, tile=50.0)
    ref = speckle.scan_image(scene, SRC, waist=7.0, lines=xs).field.values
    assert _rel(fa, ref) < 1e-13


def test_extra_dims_of_a_deformed_scene_are_carried():
    scene = _scene()
    xs = speckle.scan_lines(8, 5.0, start=40.0)
    strained = speckle.uniaxial_strain(scene, [0.0, 0.02], poisson_ratio=0.5)
    ds = speckle.scan_image(strained, SRC, waist=6.0, lines=xs, chunk=4)
    assert ds.field.dims == ("strain", "depth", "x")
    one = speckle.scan_image(strained.isel(strain=1), SRC, waist=6.0, lines=xs)
    np.testing.assert_array_equal(ds.field.sel(strain=0.02).values, one.field.values)


def test_lateral_correlation_matches_campbell():
    """Lines dx apart in a uniform Poisson scene: complex correlation exp(-dx^2/w0^2) and the
    intensity correlation of Campbell's theorem (its square plus the finite-density term);
    pixels apart in depth: the axial theory with the beam's lateral integrals.
    Independent scenes (seeds) give the standard error the test uses; the Pearson estimator's
    O(1/n) bias (n ~ 2000 pixel pairs) is below 1e-3."""
    pitch, w0, cell = 4.0, 8.0, 4.0
    rho = R.cell_density(cell, H / N, pitch)
    xs = speckle.scan_lines(64, pitch)
    lags = np.array([1, 2, 3])
    est = {"complex": [], "intensity": []}
    for seed in range(6):
        scene = _scene(density=rho, x_range=(-40.0, 300.0), seed=seed)
        f = speckle.scan_image(scene, SRC, waist=w0, lines=xs, chunk=16).field.values
        i = np.abs(f) ** 2
        for kind, q in (("complex", f), ("intensity", i)):
            row = []
            for lag in lags:
                row.append(_corr(q[:, :-lag], q[:, lag:], kind))
            if kind == "intensity":  # depth lags (periodic image); the complex one is 0, and
                for lag in lags:  # the modulus of a noisy 0 is biased, so it is not compared
                    row.append(_corr(q, np.roll(q, -lag, axis=0), kind))
            est[kind].append(row)
    theory = lateral_correlation(
        lags * pitch, w0, density=rho, spectrum=SRC.values, pixel_size=H / N, kurtosis=2.0
    )
    np.testing.assert_allclose(theory.complex.values, np.exp(-((lags * pitch) ** 2) / w0**2))
    # The finite-density term has the lateral profile exp(-2 dx^2/w0^2) = gamma^2 too, so the
    # pooled intensity correlation is gamma^2 at any density.
    np.testing.assert_allclose(theory.intensity.values, theory.complex.values**2, rtol=1e-12)
    axial = axial_correlation(
        lags, SRC.values, density=rho, pixel_size=H / N, waist=w0, kurtosis=2.0
    )
    for kind in est:
        e = np.array(est[kind])
        mean, se = e.mean(0), e.std(0, ddof=1) / np.sqrt(e.shape[0])
        expected = theory[kind].values
        if kind == "intensity":
            expected = np.concatenate([expected, axial[kind].values])
        assert np.all(np.abs(mean - expected) < 4 * se + 1e-3), (kind, mean, expected, se)


def _corr(a, b, kind):
    a, b = a.ravel() - a.mean(), b.ravel() - b.mean()
    r = np.vdot(b, a) / np.sqrt(np.vdot(a, a).real * np.vdot(b, b).real)
    return abs(r) if kind == "complex" else r.real


def test_axial_correlation_of_independent_lines():
    """Campbell's theorem along depth for the paper's independent lines: complex correlation
    sum S^2 exp(2i pi n d/N) (0 at integer lags for a rectangular spectrum) and the intensity
    correlation left by the finite density. Standard error from independent seeds."""
    lags = np.array([1, 2, 3])
    est = []
    for seed in range(12):
        sc = speckle.random_scatterers(
            1000,
            4.0,
            n_pixels=N,
            depth_range=H,
            seed=100 + seed,
            amplitude="rayleigh",
            count="poisson",
        )
        i = np.abs(speckle.bscan(sc, SRC, method="nufft", tol=1e-12).field.values) ** 2
        est.append([_corr(i, np.roll(i, -d, axis=0), "intensity") for d in lags])
    e = np.array(est)
    mean, se = e.mean(0), e.std(0, ddof=1) / np.sqrt(e.shape[0])
    theory = axial_correlation(lags, SRC.values, density=4.0, pixel_size=H / N, kurtosis=2.0)
    np.testing.assert_allclose(theory.complex.values, 0.0, atol=1e-14)
    assert np.all(np.abs(mean - theory.intensity.values) < 4 * se + 1e-3), (mean, se)
    assert theory.intensity.values[0] > 5 * se[0]  # the finite-density term is resolved


def test_streamed_netcdf_local_atomic(tmp_path):
    reg = speckle.make_regions(R.background(density=R.cell_density(1.0, H / N, 4.0, 3)))
    xs = speckle.scan_lines(6, 4.0)
    ds = speckle.image_regions(reg, SRC, seed=2, waist=8.0, lines=xs, y=xs, chunk=4)
    path = tmp_path / "vol.nc"
    stream_to_netcdf(ds[["field"]], path, progress=False)
    out = open_dataset(path)
    assert out.field.encoding["chunksizes"] == (N, 4, 4)
    np.testing.assert_array_equal(out.field.values, ds.field.values)
    assert os.listdir(tmp_path) == ["vol.nc"]
    bad = ds[["field"]].copy()
    bad["field"] = bad.field.copy(data=bad.field.data.map_blocks(_fail, dtype=complex))
    with pytest.raises(RuntimeError, match="boom"):
        stream_to_netcdf(bad, path, progress=False)
    np.testing.assert_array_equal(open_dataset(path).field.values, out.field.values)
    assert os.listdir(tmp_path) == ["vol.nc"]  # old file intact, no temporary left


def _fail(block):
    raise RuntimeError("boom")


def test_streamed_netcdf_on_a_distributed_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    reg = speckle.make_regions(R.background(density=0.05))
    ds = speckle.image_regions(
        reg, SRC, seed=4, waist=6.0, lines=speckle.scan_lines(10, 4.0), chunk=4
    )
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster),
    ):
        stream_to_netcdf(ds[["field"]], tmp_path / "d.nc", progress=False)
    with dask.config.set(scheduler="synchronous"):
        ref = ds.field.values
    np.testing.assert_array_equal(open_dataset(tmp_path / "d.nc").field.values, ref)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"waist": -1.0}, "waist"),
        ({"lines": [[0.0, 1.0]]}, "1-D"),
        ({"lines": [0.0, np.nan]}, "finite"),
        ({"lines": [0.0, 1.0, 3.0]}, "uniformly"),
        ({"lines": []}, "non-empty"),
        ({"chunk": 0}, "chunk"),
        ({"y": [0.0, 1.0]}, "needs no y"),
        ({"method": "fastest"}, "method"),
        ({"method": "auto", "tol": 2.0}, "tol"),
    ],
)
def test_bad_inputs(kw, match):
    args = {"waist": 5.0, "lines": [0.0, 4.0]}
    with pytest.raises((ValueError, TypeError), match=match):
        speckle.scan_image(_scene(), SRC, **{**args, **kw})


def test_bad_scenes_and_sources():
    empty = _scene(density=0.0)
    with pytest.raises(ValueError, match="no scatterers"):
        speckle.scan_image(empty, SRC, waist=5.0, lines=[0.0])
    with pytest.raises(TypeError, match="source"):
        speckle.scan_image(_scene(), SRC.values, waist=5.0, lines=[0.0])
    with pytest.raises(ValueError, match="needs y"):
        speckle.scan_image(_scene(y_range=(0.0, 10.0), density=0.001), SRC, waist=5.0, lines=[0.0])
    with pytest.raises(TypeError, match="shared scene"):
        speckle.scan_image(xr.Dataset(), SRC, waist=5.0, lines=[0.0])


@pytest.mark.parametrize("three_d", [False, True])
def test_focus_is_passed_and_its_halo_is_the_widest_beam(three_d):
    """A focused beam widens away from z_f: chunked images equal beam_scan on the whole scene."""
    y_range = (-60.0, 70.0) if three_d else None
    scene = _scene(density=0.001 if three_d else 0.05, x_range=(-60.0, 90.0), y_range=y_range)
    xs = speckle.scan_lines(6, 5.0)
    ys = speckle.scan_lines(3, 5.0) if three_d else None
    kw = {"focus": 60.0, "rayleigh_range": 40.0}  # w(z=H)/w0 = sqrt(1 + (196/40)^2) = 5
    ds = speckle.scan_image(scene, SRC, waist=4.0, lines=xs, y=ys, chunk=2, **kw)
    assert ds.attrs["focus"] == 60.0
    extra = {}
    lines = xs
    if three_d:
        extra["y"] = scene.y.values
        lines = np.stack(np.meshgrid(xs, ys, indexing="ij"), -1).reshape(-1, 2)
    ref = speckle.beam_scan(
        scene.z.values, scene.x.values, scene.amplitude.values, lines=lines, waist=4.0,
        **ARGS, **kw, **extra,
    )  # fmt: skip
    got = ds.field.values.reshape(N, -1).T
    assert _rel(got, ref) < 1e-13


def test_fast_method_within_tol():
    scene = _scene(density=0.05)
    xs = speckle.scan_lines(24, 4.0)
    exact = speckle.scan_image(scene, SRC, waist=8.0, lines=xs, chunk=16).field.values
    fast = speckle.scan_image(scene, SRC, waist=8.0, lines=xs, chunk=16, method="auto", tol=1e-6)
    assert _rel(fast.field.values, exact) <= 1e-6


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"focus": H}, "focus"),
        ({"focus": -1.0}, "focus"),
        ({"rayleigh_range": 10.0}, "needs focus"),
        ({"focus": 10.0, "rayleigh_range": 0.0}, "rayleigh_range"),
    ],
)
def test_bad_focus(kw, match):
    with pytest.raises(ValueError, match=match):
        speckle.scan_image(_scene(), SRC, waist=5.0, lines=[0.0, 4.0], **kw)


def test_independent_lines_are_a_beam_much_narrower_than_the_pitch():
    """The paper's B-scan is the shared-scene image of its scatterers put on their lines, with
    a beam whose weight on the neighbouring line, exp(-2 p^2/w0^2) = exp(-200), is negligible."""
    from speckle.scene.shared import from_lines

    lines = speckle.random_scatterers(12, 3.0, n_pixels=N, depth_range=H, seed=4, aline_pitch=8.0)
    scene = from_lines(lines)
    assert scene.sizes["scatterer"] == int(lines["count"].sum())
    ds = speckle.scan_image(scene, SRC, waist=0.8, lines=lines.aline.values, chunk=5)
    ref = speckle.bscan(lines, SRC).field.transpose("depth", "aline").values
    assert _rel(ds.field.values, ref) < 1e-13
