"""Tests of speckle.scene.mechanics: FE phantoms compressed by a flat probe (plane strain).

Every physical check is against an analytic solution derived in the docstrings of
speckle/scene/mechanics.py: uniform uniaxial strain of a homogeneous block (exact for bilinear
elements), confined / uniaxial limits of a bonded block away from the ends (Saint-Venant decay),
layered stacks (layer_strains) and a circular inclusion (Eshelby, inclusion_strain) whose error
falls with refinement.
"""

import functools
import itertools
import math

import numpy as np
import pytest
import xarray as xr

import speckle

E0, NU, S = 10.0, 0.25, 0.02


def grid(n_depth, n_x, pixel=5.0, first=0.0):
    """Pixel centres: depths first, first + pixel, ...; lateral centred on 0."""
    d = first + pixel * np.arange(n_depth)
    x = pixel * (np.arange(n_x) - (n_x - 1) / 2)
    return d, x


def block(n_depth=24, n_x=16, pixel=5.0, first=0.0):
    d, x = grid(n_depth, n_x, pixel, first)
    return speckle.layered_labels(d, x, [])


# --- bad input -------------------------------------------------------------------------------


def test_bad_labels_are_refused():
    lab = block()
    with pytest.raises(TypeError, match=r"labels must be an integer xarray\.DataArray"):
        speckle.compress_phantom(lab.values, E0, NU, strain=S)
    with pytest.raises(ValueError, match=r"dims \(depth, x\)"):
        speckle.compress_phantom(lab.rename(x="y"), E0, NU, strain=S)
    with pytest.raises(TypeError, match="labels must hold integers"):
        speckle.compress_phantom(lab.astype(float), E0, NU, strain=S)
    with pytest.raises(ValueError, match="strictly increasing"):
        speckle.compress_phantom(lab.isel(x=slice(None, None, -1)), E0, NU, strain=S)
    with pytest.raises(ValueError, match="coordinate 'x'"):
        speckle.compress_phantom(lab.drop_vars("x"), E0, NU, strain=S)
    for first in (-1.0, 6.0):  # above the probe, or more than a step below it
        with pytest.raises(ValueError, match="must start at the probe z = 0"):
            speckle.compress_phantom(block(first=first), E0, NU, strain=S)


def test_bad_materials_and_options_are_refused():
    lab = speckle.layered_labels(*grid(10, 6), [20.0])
    with pytest.raises(ValueError, match=r"youngs_modulus has no value for label\(s\) \[1\]"):
        speckle.compress_phantom(lab, {0: E0}, NU, strain=S)
    with pytest.raises(ValueError, match=r"youngs_modulus\[1\] must be in \(0, inf\)"):
        speckle.compress_phantom(lab, {0: E0, 1: 0.0}, NU, strain=S)
    with pytest.raises(ValueError, match=r"0\.5 \(incompressible\) makes the Lamé parameter"):
        speckle.compress_phantom(lab, E0, 0.5, strain=S)
    with pytest.raises(ValueError, match=r"poisson_ratio\[0\] must be in \[0, inf\)"):
        speckle.compress_phantom(lab, E0, {0: -0.1, 1: 0.3}, strain=S)
    with pytest.raises(ValueError, match=r"strain must be in \(-1, 1\)"):
        speckle.compress_phantom(lab, E0, NU, strain=1.0)
    with pytest.raises(ValueError, match="contact must be one of 'bonded', 'sliding'"):
        speckle.compress_phantom(lab, E0, NU, strain=S, contact="glued")
    with pytest.raises(ValueError, match=r"mesh_size must be <= the largest label pixel"):
        speckle.compress_phantom(lab, E0, NU, strain=S, mesh_size=6.0)
    with pytest.raises(ValueError, match=r"mesh_size must be in \(0, inf\)"):
        speckle.compress_phantom(lab, E0, NU, strain=S, mesh_size=0.0)


def test_points_outside_the_sample_are_refused():
    res = speckle.compress_phantom(block(), E0, NU, strain=S)
    zmax = res.attrs["sample_depth"]
    with pytest.raises(ValueError, match=r"z must lie inside the sample, \[0, 117.5\] µm"):
        speckle.displacement_at(res, zmax + 1.0, 0.0)
    with pytest.raises(ValueError, match="x must lie inside the sample"):
        speckle.displacement_at(res, 10.0, 100.0)
    with pytest.raises(TypeError, match=r"result must be the xarray\.Dataset"):
        speckle.displacement_at(res.uz, 10.0, 0.0)


def test_label_helpers_refuse_bad_geometry():
    d, x = grid(8, 8)
    with pytest.raises(ValueError, match="interfaces must be a 1-D strictly increasing"):
        speckle.layered_labels(d, x, [20.0, 10.0])
    with pytest.raises(ValueError, match="radii must be one positive radius"):
        speckle.inclusion_labels(d, x, (10.0, 0.0), -1.0)
    with pytest.raises(ValueError, match="center must be"):
        speckle.inclusion_labels(d, x, (10.0,), 5.0)
    with pytest.raises(ValueError, match="exactly the given depth and x"):
        speckle.inclusion_labels(d, x + 1, (10.0, 0.0), 5.0, background=block(8, 8))


# --- label images ----------------------------------------------------------------------------


def test_label_helpers():
    d, x = grid(10, 9)
    lay = speckle.layered_labels(d, x, [10.0, 30.0])
    assert lay.dims == ("depth", "x") and lay.depth.attrs["units"] == "um"
    np.testing.assert_array_equal(lay.isel(x=0).values, [0, 0, 1, 1, 1, 1, 2, 2, 2, 2])
    inc = speckle.inclusion_labels(d, x, (20.0, 0.0), (10.0, 5.0), label=7, background=lay)
    inside = ((d[:, None] - 20) / 10) ** 2 + (x[None, :] / 5) ** 2 <= 1
    np.testing.assert_array_equal(inc.values, np.where(inside, 7, lay.values))
    assert inside.sum() == 7  # (15, 0), (20, 0), (25, 0), (20, +-5), (10, 0), (30, 0)


# --- homogeneous block ------------------------------------------------------------------------


@pytest.mark.parametrize("mesh_size", [None, 2.0])
def test_homogeneous_sliding_block_is_uniform_uniaxial_strain(mesh_size):
    """Sliding probe/base, free sides: u_z = -s z, u_x = nu/(1-nu) s (x - x_c) (plane strain,
    sigma_xx = 0), bilinear, so reproduced to rounding; stress_zz = E s / (1 - nu^2)."""
    d = np.concatenate([[0.0, 3.0], 3.0 + 5.0 * np.arange(1, 20)])  # non-uniform grid
    x = 5.0 * np.arange(12) - 20.0
    res = speckle.compress_phantom(
        speckle.layered_labels(d, x, []), E0, NU, strain=S, contact="sliding", mesh_size=mesh_size
    )
    lateral = NU / (1 - NU) * S
    xc = res.attrs["x_centre"]
    assert xc == pytest.approx(0.5 * (x[0] + x[-1]))
    tol = 1e-12
    np.testing.assert_allclose(res.uz, -S * res.depth.broadcast_like(res.uz), atol=tol * 100)
    np.testing.assert_allclose(res.ux, lateral * (res.x - xc).broadcast_like(res.ux), atol=1e-11)
    np.testing.assert_allclose(
        res.uz_node, -S * res.node_depth.broadcast_like(res.uz_node), atol=1e-11
    )
    np.testing.assert_allclose(res.strain_zz, S, rtol=1e-11)
    np.testing.assert_allclose(res.strain_xx, -lateral, rtol=1e-11)
    np.testing.assert_allclose(res.strain_xz, 0.0, atol=1e-13)
    stress = E0 * S / (1 - NU**2)
    np.testing.assert_allclose(res.stress_zz, stress, rtol=1e-11)
    np.testing.assert_allclose(res.stress_xx, 0.0, atol=1e-11 * stress)
    width = float(np.diff(res.attrs["lateral_extent"])[0])
    assert res.attrs["probe_force"] == pytest.approx(stress * width, rel=1e-11)
    assert res.attrs["sample_depth"] == d[-1] + 2.5
    if mesh_size is not None:
        assert res.attrs["mesh_size"] <= mesh_size
        assert res.sizes["node_x"] == 3 * 12 + 1  # 5 µm pixels split into 3 elements
    for name in ("uz", "ux", "strain_zz", "stress_zz", "youngs_modulus", "uz_node"):
        assert "units" in res[name].attrs


def test_tall_bonded_block_is_uniaxial_away_from_the_ends():
    """Bonded probe and base clamp u_x = 0 at the ends; the perturbation is self-equilibrated
    and decays (Saint-Venant; Papkovich-Fadle eigenvalue 2.106 for a free-sided strip of
    half-width c) as exp(-2.106 z / c) = exp(-4.21 z / W). At 1.75 W from both ends this is
    6e-4, so there the block is in uniform uniaxial plane strain, strain_xx / strain_zz =
    -nu / (1 - nu), to a few 1e-4. The stiffer clamped ends take less strain, so the centre
    carries a little more than the nominal strain; the total is the nominal one."""
    width, height = 40, 160  # pixels of 1 µm
    d, x = grid(height, width, pixel=1.0, first=0.5)
    res = speckle.compress_phantom(speckle.layered_labels(d, x, []), E0, 0.3, strain=0.01)
    centre = res.sel(depth=slice(70, 90))
    ratio = centre.strain_xx / centre.strain_zz
    np.testing.assert_allclose(ratio, -0.3 / 0.7, rtol=2e-3)
    assert float(centre.strain_zz.std() / centre.strain_zz.mean()) < 2e-3
    assert float(centre.strain_zz.min()) > 0.01
    np.testing.assert_allclose(res.uz_node.isel(node_depth=-1), -0.01 * 160.0, rtol=1e-12)
    np.testing.assert_allclose(res.ux_node.isel(node_depth=[0, -1]), 0.0, atol=1e-15)
    # the compressive strain averages to the nominal one over the depth
    mean = (res.strain_zz.mean("x") * 1.0).sum() / res.attrs["sample_depth"]
    assert float(mean) == pytest.approx(0.01, rel=1e-10)


def test_wide_bonded_block_is_confined_at_the_centre():
    """A wide bonded slab: u = (0, -s z) satisfies the bonded ends exactly, only the free sides
    perturb it, by a self-equilibrated field decaying exponentially over ~ the height L.
    At 10 L from the sides any decay rate >= 1/L leaves < e^-10 of the edge perturbation
    (< 0.1 s at the edge): strain_zz = s, strain_xx = 0 to 1e-5 relative."""
    d, x = grid(10, 200, pixel=1.0, first=0.5)
    res = speckle.compress_phantom(speckle.layered_labels(d, x, []), E0, 0.3, strain=0.01)
    centre = res.sel(x=slice(-10, 10))
    np.testing.assert_allclose(centre.strain_zz, 0.01, rtol=1e-5)
    np.testing.assert_allclose(centre.strain_xx, 0.0, atol=1e-7)


# --- layers ------------------------------------------------------------------------------------


def test_layers_without_poisson_effect_strain_inversely_to_modulus():
    """nu = 0: no lateral coupling; the uniform axial stress gives strain_zz_i = sigma / E_i in
    every pixel, exact for bilinear elements (interfaces on element edges)."""
    d, x = grid(30, 10)
    lab = speckle.layered_labels(d, x, [40.0, 100.0])
    moduli = {0: 5.0, 1: 20.0, 2: 10.0}
    res = speckle.compress_phantom(lab, moduli, 0.0, strain=S, contact="sliding")
    edges = [0.0, 37.5, 97.5, res.attrs["sample_depth"]]  # interfaces on pixel edges
    t = np.diff(edges)
    e = np.array(list(moduli.values()))
    sigma = S * edges[-1] / np.sum(t / e)
    expect = sigma / e[res.label.values]
    np.testing.assert_allclose(res.strain_zz, expect, rtol=1e-10)
    zz, xx, szz = speckle.layer_strains(t, e, [0.0, 0.0, 0.0], S)
    np.testing.assert_allclose(zz, sigma / e, rtol=1e-12)
    assert xx == 0.0 and szz == pytest.approx(sigma)
    np.testing.assert_allclose(res.stress_zz, sigma, rtol=1e-10)
    # total displacement = nominal: sum of layer strains * thickness
    assert float(np.sum(zz * t)) == pytest.approx(S * edges[-1], rel=1e-12)


def test_layers_with_poisson_effect_match_the_interior_solution():
    """nu = 0.45: bonded layers share the lateral strain; interior solution of layer_strains
    (self-equilibrated lateral stresses; edge effects decay over ~ the height L, e^-10 at the
    centre of a 20 L wide stack). The soft layer is confined by the stiff one, so its strain
    ratio is below the E' ratio."""
    d, x = grid(12, 240, pixel=1.0, first=0.5)
    lab = speckle.layered_labels(d, x, [4.0])  # interface on the pixel edge at 4 µm
    res = speckle.compress_phantom(lab, {0: 5.0, 1: 20.0}, 0.45, strain=S, contact="sliding")
    zz, xx, szz = speckle.layer_strains([4.0, 8.0], [5.0, 20.0], [0.45, 0.45], S)
    centre = res.sel(x=slice(-10, 10))
    np.testing.assert_allclose(centre.strain_zz, zz[centre.label.values], rtol=1e-6)
    np.testing.assert_allclose(centre.strain_xx, xx, rtol=1e-5)
    np.testing.assert_allclose(centre.stress_zz, szz, rtol=1e-6)
    assert zz[0] / zz[1] < 4.0  # E ratio (= E' ratio for equal nu)


def test_layer_strains_reduce_to_uniaxial_plane_strain_for_one_material():
    zz, xx, szz = speckle.layer_strains([3.0, 7.0], [8.0, 8.0], [0.3, 0.3], 0.01)
    np.testing.assert_allclose(zz, 0.01, rtol=1e-14)
    assert xx == pytest.approx(-0.3 / 0.7 * 0.01, rel=1e-14)
    assert szz == pytest.approx(8.0 * 0.01 / (1 - 0.09), rel=1e-14)


# --- circular inclusion -------------------------------------------------------------------------


def test_inclusion_strain_limits():
    """Equal materials: the far field; a rigid inclusion: no deviatoric strain; a hole: the
    deviator amplified by 1 + kappa (Eshelby S_dev = kappa / (kappa + 1))."""
    zz, xx = speckle.inclusion_strain(0.01, 10.0, 0.3, 10.0, 0.3)
    assert (zz, xx) == pytest.approx((0.01, -0.3 / 0.7 * 0.01), rel=1e-13)
    zz, xx = speckle.inclusion_strain(0.01, 10.0, 0.3, 1e12, 0.3)
    assert zz - xx == pytest.approx(0.0, abs=1e-12)
    zz, xx = speckle.inclusion_strain(0.01, 10.0, 0.3, 1e-12, 0.3)
    kappa = 3 - 4 * 0.3
    assert (zz - xx) == pytest.approx((1 + kappa) * 0.01 * (1 + 0.3 / 0.7), rel=1e-9)


def graded_axis(radius, pixel, plate, ratio=1.15):
    """Pixel centres: uniform ``pixel`` within 1.5 radius of the centre, then widths growing by
    ``ratio`` out to half the plate, symmetric; returns centres relative to the plate centre."""
    nodes, step = [*np.arange(0.0, 1.5 * radius + pixel / 2, pixel)], pixel
    while nodes[-1] < plate / 2:
        step *= ratio
        nodes.append(nodes[-1] + step)
    nodes = np.array(nodes)
    nodes = np.concatenate([-nodes[:0:-1], nodes])
    return 0.5 * (nodes[1:] + nodes[:-1]), nodes[-1] - nodes[0]


def inclusion_error(n_radius, offset, radius=100.0, plate=40.0, nu=0.3, e_ratio=3.0):
    """Relative errors (strain_zz, strain_xx) of the FE strain (mean over pixels within R/2 of
    the centre) against Eshelby, for a circle of ``n_radius`` pixels offset by ``offset`` pixels."""
    pixel = radius / n_radius
    axis, size = graded_axis(radius, pixel, plate * radius)
    depth = axis + size / 2
    centre = np.array([size / 2, 0.0]) + np.asarray(offset) * pixel
    lab = speckle.inclusion_labels(depth, axis, centre, radius)
    res = speckle.compress_phantom(
        lab, {0: E0, 1: e_ratio * E0}, nu, strain=0.01, contact="sliding"
    )
    r2 = (res.depth - centre[0]) ** 2 + (res.x - centre[1]) ** 2
    core = res[["strain_zz", "strain_xx"]].where(r2 <= (radius / 2) ** 2)
    zz, xx = speckle.inclusion_strain(0.01, E0, nu, e_ratio * E0, nu)
    return float(core.strain_zz.mean()) / zz - 1, float(core.strain_xx.mean()) / xx - 1


def test_circular_inclusion_converges_to_eshelby():
    """Stiff circular inclusion (E1 = 3 E, nu = 0.3) of radius R in a 40 R x 40 R plate (graded
    mesh, sliding contact) under nominal strain 1 %: inside, the strain is Eshelby's uniform
    value. The label image makes the circle a staircase, an O(h/R) error that depends on where
    the circle sits on the pixel grid, so the error is the worst over 4 sub-pixel offsets.
    Measured: 5.7 %, 2.4 %, 1.3 % at R = 4, 8, 16 pixels (0.7 % at 32; first order). The
    finite plate P x P adds about 0.5 pi (R/P)^2, 0.1 % here (benchmarks/mechanics_accuracy.py:
    1.6 %, 0.4 %, 0.08 % for P = 10, 20, 40 R against P = 80 R)."""
    offsets = [(0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (0.25, 0.25)]
    errors = [max(np.abs(inclusion_error(n, o)).max() for o in offsets) for n in (4, 8, 16)]
    rates = [math.log2(a / b) for a, b in itertools.pairwise(errors)]
    assert errors[0] > errors[1] > errors[2]
    assert min(rates) > 0.7  # first order (staircase interface) expected
    assert errors[2] < 0.02


def test_near_incompressible_inclusion_does_not_lock():
    """nu = 0.4999 (tissue): with the volumetric term integrated at element centres the
    inclusion strain still converges at first order like nu = 0.3; plain 2x2 integration locks
    (measured 4 % error at nu = 0.499, 79 % at 0.49999 for R = 16 pixels)."""
    errors = [np.abs(inclusion_error(n, (0.25, 0.25), nu=0.4999)).max() for n in (8, 16)]
    assert errors[1] < errors[0] / 1.6
    assert errors[1] < 0.01


# --- displacement fields for scenes ------------------------------------------------------------


def test_displacement_at_is_the_bilinear_fe_field():
    lab = speckle.inclusion_labels(*grid(12, 10), (30.0, 0.0), 12.0)
    res = speckle.compress_phantom(lab, {0: E0, 1: 4 * E0}, 0.3, strain=S)
    zn, xn = np.meshgrid(res.node_depth, res.node_x, indexing="ij")
    uz, ux = speckle.displacement_at(res, zn, xn)
    np.testing.assert_array_equal(uz, res.uz_node.values)
    np.testing.assert_array_equal(ux, res.ux_node.values)
    # midpoint of a cell = mean of its four nodes (bilinear); pixel centres = uz, ux
    zm, xm = 0.5 * (zn[3, 4] + zn[4, 5]), 0.5 * (xn[3, 4] + xn[4, 5])
    uzm, _ = speckle.displacement_at(res, zm, xm)
    assert uzm == pytest.approx(res.uz_node.values[3:5, 4:6].mean(), rel=1e-14)
    dd, xx = np.meshgrid(res.depth, res.x, indexing="ij")
    np.testing.assert_allclose(speckle.displacement_at(res, dd, xx)[0], res.uz, rtol=1e-14)


def test_displace_with_fe_field_reproduces_uniaxial_strain(tmp_path):
    """A homogeneous sliding block: the FE field moved through speckle.displace equals
    speckle.uniaxial_strain with the plane-strain lateral ratio nu / (1 - nu) (= 1/3 for
    nu = 1/4), also after a NetCDF round trip of the result."""
    n, pixel, n_alines, s = 32, 4.0, 8, 0.05
    scene = speckle.deformable_scene(
        n_alines, 2.0, n_pixels=n, depth_range=n * pixel, seed=5, strain=s, poisson_ratio=1 / 3
    )
    pitch = scene.attrs["aline_pitch"]
    zmax = scene.attrs["populated_depth"]
    depth = np.arange(0.0, zmax + pixel, pixel)
    lab = speckle.layered_labels(depth, scene.aline.values, [])
    assert lab.x.values[1] - lab.x.values[0] == pitch
    res = speckle.compress_phantom(lab, E0, NU, strain=s, contact="sliding")
    path = tmp_path / "phantom.nc"
    speckle.to_netcdf(res, path)
    res = xr.open_dataset(path, engine="netcdf4").load()
    moved = speckle.displace(scene, functools.partial(speckle.displacement_at, res))
    ref = speckle.uniaxial_strain(
        scene, s, poisson_ratio=NU / (1 - NU), x_centre=res.attrs["x_centre"]
    ).isel(strain=0)
    assert moved.sizes == ref.sizes
    np.testing.assert_allclose(moved.z, ref.z, atol=1e-11)
    np.testing.assert_allclose(moved.x, ref.x, atol=1e-11)
    np.testing.assert_array_equal(moved.amplitude, ref.amplitude)


def test_aline_labels_warn_and_give_a_field_displace_accepts():
    """Labels over the retired dim (depth, aline) are read as (depth, x), warning; the FE field
    over (depth, x) is one speckle.displace takes directly for a line scene (read at its lines;
    linear interpolation between pixel centres: exact for a linear field)."""
    n, pixel, s = 16, 4.0, 0.02
    scene = speckle.deformable_scene(6, 2.0, n_pixels=n, depth_range=n * pixel, seed=2, strain=s)
    depth = np.arange(0.0, scene.attrs["populated_depth"] + pixel, pixel)
    lab = speckle.layered_labels(depth, scene.aline.values, [])
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        old = speckle.compress_phantom(lab.rename(x="aline"), E0, 0.0, strain=s, contact="sliding")
    res = speckle.compress_phantom(lab, E0, 0.0, strain=s, contact="sliding")
    xr.testing.assert_identical(old, res)
    assert res.uz.dims == ("depth", "x")
    moved = speckle.displace(scene, res)
    ref = speckle.uniaxial_strain(scene, s).isel(strain=0)
    np.testing.assert_allclose(moved.z, ref.z, atol=1e-11)


def test_fe_field_deforms_a_shared_scene_of_regions():
    """Regions -> rasterize -> compress -> displace(shared scene): the exact FE field at each
    scatterer (displacement_at) and the pixel-centre grid field interpolated linearly agree to
    the bilinear interpolation error between pixel centres (second order in the pixel size)."""
    import functools

    from speckle.scene import regions as R

    reg = speckle.make_regions(
        R.background(density=0.02, youngs_modulus=10.0),
        R.circle(60.0, 80.0, 25.0, density=0.02, youngs_modulus=40.0),
    )
    depth = np.arange(0.0, 128.0, 4.0) + 2.0
    x = np.arange(0.0, 160.0, 4.0) + 2.0
    labels = speckle.rasterize(reg, depth, x)
    fe = speckle.compress_phantom(labels, {0: 10.0, 1: 40.0}, 0.3, strain=0.01, contact="sliding")
    scene = speckle.shared_scene(reg, z_range=(8.0, 120.0), x_range=(8.0, 152.0), seed=5)
    exact = speckle.displace(scene, functools.partial(speckle.displacement_at, fe))
    gridded = speckle.displace(scene, fe[["uz", "ux"]])
    uz = exact.z.values - scene.z.values
    # uniform strain away from the inclusion: u_z = -0.01 z at the probe-fixed convention
    assert np.all(np.isfinite(uz)) and np.median(uz / scene.z.values) == pytest.approx(
        -0.01, rel=0.1
    )
    # linear interpolation between pixel centres errs by less than the field's variation over
    # two neighbouring cells (the FE field is bilinear on elements offset by half a pixel)
    for var, pos in (("uz", "z"), ("ux", "x")):
        u = fe[var].values
        bound = 2 * max(np.abs(np.diff(u, axis=0)).max(), np.abs(np.diff(u, axis=1)).max())
        assert np.max(np.abs(gridded[pos].values - exact[pos].values)) < bound
