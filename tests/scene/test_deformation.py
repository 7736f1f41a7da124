"""Tests of speckle.scene.deformation: strain, translations, displacement fields, depth population,
wrap-around aliasing kept out of correlations, and bad input."""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import correlation as corr
from speckle.scene import deformation as D

N, PIXEL = 64, 8.0
H = N * PIXEL


def scene(n_alines=8, density=2.0, strain=0.0, **kw):
    return D.deformable_scene(
        n_alines, density, n_pixels=N, depth_range=H, seed=3, strain=strain, **kw
    )


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [1.0, -1.0, 1.5, [0.0, 1.0], -2.0])
def test_strain_out_of_range_is_refused(bad):
    sc = scene()
    with pytest.raises(ValueError, match=r"strain must lie in the open interval \(-1, 1\)"):
        D.uniaxial_strain(sc, bad)
    with pytest.raises(ValueError, match="strain"):
        D.deformable_scene(4, 1.0, n_pixels=N, depth_range=H, seed=0, strain=bad)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_strain_is_refused(bad):
    with pytest.raises(ValueError, match="strain must be finite"):
        D.uniaxial_strain(scene(), bad)


def test_scene_not_deep_enough_is_refused():
    with pytest.raises(ValueError, match=r"populated to .* needs"):
        D.uniaxial_strain(scene(strain=0.01), 0.1)


def test_displacement_field_with_wrong_dims_is_refused():
    field = xr.DataArray(
        np.zeros((3, 4)), dims=("y", "x"), coords={"y": np.arange(3.0), "x": np.arange(4.0)}
    )
    with pytest.raises(ValueError, match=r"must have dims among \('depth', 'x'\)"):
        D.displace(scene(), field)


def test_displacement_field_with_nan_is_refused():
    depth = np.linspace(0, H, 5)
    field = xr.DataArray([0.0, 1.0, np.nan, 0.0, 0.0], dims="depth", coords={"depth": depth})
    with pytest.raises(ValueError, match="NaN"):
        D.displace(scene(), field)
    with pytest.raises(ValueError, match="NaN"):
        D.displace(scene(), lambda z, x: np.where(z > H / 2, np.nan, 0.0))


def test_displacement_field_without_uz_or_coords_is_refused():
    with pytest.raises(ValueError, match="'uz'"):
        D.displace(scene(), xr.Dataset({"ux": ("depth", np.zeros(3))}))
    with pytest.raises(ValueError, match="coordinate 'depth'"):
        D.displace(scene(), xr.DataArray(np.zeros(3), dims="depth"))
    with pytest.raises(TypeError, match="displacement must be a callable"):
        D.displace(scene(), 3.0)


def test_poisson_ratio_out_of_range_is_refused():
    with pytest.raises(ValueError, match="poisson_ratio"):
        D.uniaxial_strain(scene(), 0.01, poisson_ratio=0.7)


# --- population depth ------------------------------------------------------------------------


def test_required_depth_is_what_the_largest_compression_needs():
    assert D.required_depth(H, [0.0, 0.1]) == pytest.approx(H / 0.9)
    assert D.required_depth(H, [-0.2, 0.0]) == H  # stretching needs nothing deeper
    sc = scene(strain=[0.0, 0.2], density=4.0)
    assert sc.attrs["z_max"] == pytest.approx(H / 0.8)
    # fixed count: round(rho * N * span / H) per line, all inside [0, H/0.8)
    assert sc.sizes["scatterer"] == round(4.0 * N / 0.8)
    assert float(sc.z.max()) < H / 0.8


def test_compression_keeps_the_image_full_and_moves_scatterers_by_minus_s_z():
    s = 0.2
    sc = scene(strain=[0.0, s], density=4.0)
    out = D.uniaxial_strain(sc, [0.0, s])
    assert out.z.dims == ("strain", "aline", "scatterer")
    np.testing.assert_allclose(out.z.sel(strain=s), (1 - s) * sc.z.values, rtol=1e-15)
    inside = out.amplitude != 0
    # wrap=False: only scatterers displaced into [0, H) are imaged ...
    assert bool(((out.z < H) | ~inside).all())
    # ... and at the largest strain all populated scatterers are inside: the count per line is
    # the full-depth count, i.e. nothing is missing at the bottom of the image
    assert int(inside.sel(strain=s).sum("scatterer").min()) == sc.sizes["scatterer"]
    ref_count = inside.sel(strain=0.0).sum("scatterer")
    assert int(abs(ref_count - 4.0 * N).max()) < 4 * np.sqrt(4.0 * N)  # binomial spread


def test_deep_scatterers_never_alias_unless_asked():
    """Extra scatterers below the needed depth change nothing with wrap=False, and alias with
    wrap=True (they land in the top rows)."""
    s = 0.05
    sc = scene(strain=[0.0, s], n_alines=4)
    rng = np.random.default_rng(0)
    extra = sc.isel(scatterer=slice(0, 40)).copy(deep=True)
    extra["z"] = (("aline", "scatterer"), rng.uniform(H / (1 - s), 1.5 * H, extra.z.shape))
    deeper = xr.concat([sc, extra], dim="scatterer", data_vars="all", combine_attrs="override")
    src = speckle.spectrum(N, H, k0_dk=10)
    for wrap, same in ((False, True), (True, False)):
        a = speckle.bscan(D.uniaxial_strain(sc, [0.0, s], wrap=wrap), src).field
        b = speckle.bscan(D.uniaxial_strain(deeper, [0.0, s], wrap=wrap), src).field
        assert np.allclose(a, b, rtol=0, atol=1e-9 * float(abs(a).max())) is same


def test_wrap_around_would_decorrelate_the_top_rows():
    """In a strain sweep the deep population needed for 5 % compression aliases into the top
    ~5 % of the reference image with wrap=True. There, half of the speckle power comes from
    aliased scatterers that move by ~s*H instead of ~s*z: |gamma| drops to about half its
    exact-compensation value, the intensity correlation to about a quarter of it plus the
    incoherent floor (< 0.5 here), against the theory value 0.83 with wrap=False."""
    smax, s, n = 0.05, 0.01, 128
    h = n * PIXEL
    sc = D.deformable_scene(128, 4.0, n_pixels=n, depth_range=h, seed=5, strain=[0.0, smax])
    src = speckle.spectrum(n, h, k0_dk=10)
    # rows 2..6: inside the aliased band of 0.05*n = 6.4 px, away from the first two rows where
    # the periodic kernel's tail also sees the moving bottom of the image; 640 pixels, so the
    # Pearson standard error is ~ (1 - r^2)/sqrt(640) * sqrt(2) < 0.05
    top = slice(2, 7)
    disp = D.uniaxial_pixel_displacement([s], speckle.pixel_depths(n, h), sc.aline.values).isel(
        strain=0
    )
    result = {}
    for wrap in (False, True):
        b = speckle.bscan(D.uniaxial_strain(sc, [0.0, s], wrap=wrap), src)
        comp = corr.compensate(b.isel(strain=1), disp)
        result[wrap] = float(corr.pearson(b.field.isel(strain=0, depth=top), comp.isel(depth=top)))
    theory = float(corr.expected_correlation(s, spectrum=src, density=4.0).intensity[0])
    assert result[False] == pytest.approx(theory, abs=0.15)  # 3 standard errors
    assert result[True] < 0.5


# --- displacement fields ---------------------------------------------------------------------


def test_xarray_and_callable_fields_agree_with_uniaxial_strain():
    s = 0.03
    sc = scene(strain=[0.0, s])
    depth = np.linspace(0, 2 * H, 9)
    field = xr.DataArray(-s * depth, dims="depth", coords={"depth": depth})
    by_field = D.displace(sc, field)
    by_func = D.displace(sc, lambda z, x: -s * z)
    by_strain = D.uniaxial_strain(sc, s).isel(strain=0)
    for other in (by_func, by_strain):
        np.testing.assert_allclose(by_field.z, other.z, rtol=1e-12)
        np.testing.assert_array_equal(by_field.amplitude, other.amplitude)


def test_field_over_depth_and_x_is_interpolated_in_both():
    """A field is a quantity over the image, dims (depth, x): a line scene reads it at its
    lines' positions (its dim ``aline``)."""
    sc = scene()
    depth = np.linspace(0, H, 5)
    x = sc.aline.values
    uz = xr.DataArray(
        np.add.outer(0.01 * depth, 0.5 * x), dims=("depth", "x"), coords={"depth": depth, "x": x}
    )
    out = D.displace(sc, uz, wrap=True)
    expected = sc.z + 0.01 * sc.z + 0.5 * sc.aline
    np.testing.assert_allclose(out.z, expected.transpose("aline", "scatterer"), rtol=1e-12)
    # a field written before issue 32, over (depth, aline): read as x for a release, warning
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        old = D.displace(sc, uz.rename(x="aline"), wrap=True)
    xr.testing.assert_identical(old, out)


def test_pixel_displacement_is_over_the_image_grid():
    depth, x = np.arange(4) * 8.0, np.arange(3) * 5.0
    u = D.pixel_displacement(lambda z, x: (-0.01 * z, 0.001 * x), depth, x)
    assert u.uz.dims == u.ux.dims == ("depth", "x") and "aline" not in u.coords
    np.testing.assert_array_equal(u.x, x)
    np.testing.assert_allclose(u.ux.values, np.broadcast_to(0.001 * x, (4, 3)), rtol=1e-15)
    s = D.uniaxial_pixel_displacement([0.01, 0.02], depth, x)
    assert s.uz.dims == ("strain", "depth", "x")
    for f, args in (
        (D.pixel_displacement, (lambda z, x: -0.01 * z, depth)),
        (
            D.uniaxial_pixel_displacement,
            ([0.01], depth),
        ),
    ):
        with pytest.warns(FutureWarning, match="parameter 'aline' is now 'x'"):
            old = f(*args, aline=x)
        xr.testing.assert_identical(old, f(*args, x=x))


def test_rigid_translation_and_shift_dim():
    sc = scene()
    out = D.translate(sc, [0.0, 2.5, -4.0], wrap=True)
    assert out.sizes["shift"] == 3
    np.testing.assert_allclose(out.z.sel(shift=2.5), sc.z + 2.5)
    np.testing.assert_array_equal(out.amplitude.sel(shift=-4.0), sc.amplitude)
    cut = D.translate(sc, -4.0)  # wrap=False: scatterers pushed above the surface vanish
    assert bool(((cut.z >= 0) | (cut.amplitude == 0)).all())


def test_lateral_poisson_expansion_moves_scatterers_between_alines():
    s, nu = 0.2, 0.5
    sc = scene(strain=[0.0, s], n_alines=16)
    out = D.uniaxial_strain(sc, s, poisson_ratio=nu).isel(strain=0)
    xc = float(sc.aline.mean())
    keep = out.amplitude != 0
    # every imaged scatterer sits in the beam of its A-line
    dist = abs(out.x - out.aline).where(keep)
    assert float(dist.max()) <= 0.5 * PIXEL + 1e-9
    # positions follow x' = xc + (x - xc)(1 + nu s): compare the sorted sets of one line
    moved = xc + (sc.x - xc) * (1 + nu * s)
    line = float(out.aline[5])
    want = np.sort(moved.values[np.abs(moved.values - line) <= 0.5 * PIXEL])
    got = np.sort(out.x.sel(aline=line).values[keep.sel(aline=line).values])
    np.testing.assert_allclose(got, want[: got.size] if got.size < want.size else want)
    # compression expands laterally: scatterers leave at the sides, none arrive
    assert int(keep.sum()) < int((sc.amplitude != 0).sum())


def test_stretching_with_poisson_contraction_populates_side_margins():
    sc = scene(strain=[-0.2, 0.0], poisson_ratio=0.5, n_alines=10)
    assert sc.attrs["imaged_first"] > 0
    assert sc.sizes["aline"] == 10 + 2 * sc.attrs["imaged_first"]
    out = D.uniaxial_strain(sc, [-0.2, 0.0], poisson_ratio=0.5)
    assert out.sizes["aline"] == 10
    # the edge lines receive scatterers from the margins, so they stay full (binomial spread)
    counts = (out.amplitude.sel(strain=-0.2) != 0).sum("scatterer")
    assert int(counts.min()) > 0.5 * 2.0 * N / 1.2


def test_strain_sweep_is_independent_of_scheduler_and_workers():
    """Each sweep point rebuilds the seeded scene, so the numbers do not depend on Dask."""
    from speckle.sweep import sweep

    src = speckle.spectrum(N, H, k0_dk=3)

    def point(strain):
        sc = D.deformable_scene(8, 2.0, n_pixels=N, depth_range=H, seed=9, strain=[0.0, 0.05])
        b = speckle.bscan(D.uniaxial_strain(sc, [0.0, strain]), src)
        disp = D.uniaxial_pixel_displacement([strain], b.depth.values, b.x.values)
        comp = corr.compensate(b.isel(strain=1), disp.isel(strain=0))
        return corr.pearson(b.isel(strain=0), comp).drop_vars("strain", errors="ignore").rename("r")

    grid = {"strain": [0.0, 0.02, 0.05]}
    one = sweep(point, grid, scheduler="synchronous")
    two = sweep(point, grid, scheduler="threads", n_workers=2)
    xr.testing.assert_identical(one, two)
    assert float(one.r.sel(strain=0.0)) == pytest.approx(1.0)
