"""Motion models of the scene layer: statistics of the displacements, composition, bounds.

Statistical checks use the derived standard error of the estimated quantity: the mean square
of ``M`` independent Gaussian increments of variance ``s^2`` has SE ``s^2 sqrt(2/M)``.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene import motion as mo
from speckle.scene.regions import background, circle, layer, make_regions


@pytest.fixture(scope="module")
def scene():
    regs = make_regions(
        background(density=0.05),
        layer(20.0, 40.0, density=0.05),
        circle(80.0, 64.0, 16.0, density=0.05),
    )
    return speckle.shared_scene(regs, z_range=(0.0, 128.0), x_range=(0.0, 128.0), seed=3)


def test_brownian_increments_have_variance_2_d_dt(scene):
    d, t = 2.0, np.array([0.0, 0.1, 0.25, 0.3])
    out = mo.brownian_motion(scene, t, diffusion=d, seed=1)
    assert out.z.dims == ("time", "scatterer") and out.time.attrs["units"] == "s"
    np.testing.assert_array_equal(out.z.isel(time=0), scene.z)
    for a in ("z", "x"):
        inc = np.diff(out[a].values, axis=0)  # (3, M): independent N(0, 2 D dt)
        for k, dt in enumerate(np.diff(t)):
            s2 = 2 * d * dt
            m = inc.shape[1]
            ms = np.mean(inc[k] ** 2)
            assert abs(ms - s2) < 4 * s2 * np.sqrt(2 / m), (a, k, ms, s2)
    # amplitudes and regions unchanged, reproducible
    xr.testing.assert_identical(out.amplitude, scene.amplitude)
    again = mo.brownian_motion(scene, t, diffusion=d, seed=1)
    xr.testing.assert_identical(out, again)


def test_regions_and_fraction_select_the_movers(scene):
    t = [0.0, 1.0]
    out = mo.brownian_motion(scene, t, diffusion=1.0, seed=4, regions=[2], fraction=0.5)
    moved = out.z.values[1] != out.z.values[0]
    reg = scene.region.values
    assert not moved[reg != 2].any()
    n2 = int((reg == 2).sum())
    frac = moved[reg == 2].mean()
    assert abs(frac - 0.5) < 4 * np.sqrt(0.25 / n2), (frac, n2)
    # the draws do not depend on the selection: the movers move as in the all-moving call
    full = mo.brownian_motion(scene, t, diffusion=1.0, seed=4)
    np.testing.assert_array_equal(out.z.values[1][moved], full.z.values[1][moved])


def test_motions_compose_on_the_same_times(scene):
    t = np.linspace(0, 0.01, 5)
    cells = mo.brownian_motion(scene, t, diffusion=1.0, seed=1, regions=[1])
    both = mo.flow_motion(cells, t, velocity=[0.0, 500.0], regions=[2], wrap=False)
    assert both.attrs["motion"] == "brownian+flow"
    reg = scene.region.values
    np.testing.assert_array_equal(both.z.values[:, reg == 1], cells.z.values[:, reg == 1])
    dx = both.x.values[:, reg == 2] - scene.x.values[reg == 2]
    np.testing.assert_allclose(dx, (t * 500.0)[:, None] * np.ones((1, int((reg == 2).sum()))))
    assert np.all(both.z.values[:, reg == 0] == scene.z.values[reg == 0])  # static background
    with pytest.raises(ValueError, match="same times"):
        mo.flow_motion(cells, t * 2, velocity=[0.0, 1.0])


def test_flow_wraps_in_the_window(scene):
    t = np.array([0.0, 0.5, 1.0])
    out = mo.flow_motion(scene, t, velocity=[0.0, 60.0])
    x = out.x.values
    assert x.min() >= 0.0 and x.max() < 128.0
    np.testing.assert_allclose(
        np.mod(scene.x.values + 30.0 - x[1] + 64.0, 128.0) - 64.0, 0.0, atol=1e-9
    )


def test_poiseuille_profile_and_through_plane_flow():
    regs = make_regions(background(density=0.002))
    sc3 = speckle.shared_scene(
        regs, z_range=(0, 64), x_range=(0, 64), y_range=(0, 64), seed=1, tile=32.0
    )
    v = mo.poiseuille_velocity(
        sc3, peak_velocity=100.0, radius=20.0, centre=(32.0, 32.0, 0.0), direction=(0, 0, 2.0)
    )
    r2 = (sc3.z.values - 32) ** 2 + (sc3.x.values - 32) ** 2
    expect = np.where(r2 < 400, 100 * (1 - r2 / 400), 0.0)
    np.testing.assert_allclose(v[:, 2], expect)
    np.testing.assert_array_equal(v[:, :2], 0.0)
    out = mo.flow_motion(sc3, [0.0, 0.1], velocity=v)
    np.testing.assert_array_equal(out.z.values[1], sc3.z.values)  # only y moves
    sc2 = speckle.shared_scene(regs, z_range=(0, 64), x_range=(0, 64), seed=1)
    with pytest.raises(ValueError, match="3-D scene"):
        mo.poiseuille_velocity(
            sc2, peak_velocity=1.0, radius=5.0, centre=(1, 2, 3), direction=(0, 0, 1)
        )
    with pytest.raises(ValueError, match="3-D scene"):
        mo.flow_motion(sc2, [0.0, 1.0], velocity=[0.0, 0.0, 1.0])


def test_ballistic_gaussian_velocity_variance(scene):
    t = np.array([0.0, 0.1])
    s = 20.0
    out = mo.ballistic_motion(scene, t, speed=s, seed=2, wrap=False)
    d = np.stack([out[a].values[1] - scene[a].values for a in ("z", "x")], -1) / 0.1
    m = d.shape[0]
    for i in range(2):  # each component N(0, s^2/2)
        ms = np.mean(d[:, i] ** 2)
        assert abs(ms - s**2 / 2) < 4 * (s**2 / 2) * np.sqrt(2 / m)
    const = mo.ballistic_motion(scene, t, speed=s, seed=2, distribution="constant", wrap=False)
    sp = np.hypot(*(const[a].values[1] - scene[a].values for a in ("z", "x"))) / 0.1
    np.testing.assert_allclose(sp, s)


def test_bulk_motion_and_deformation_still_apply(scene):
    t = [0.0, 1.0, 2.0]
    u = [[0.0, 0.0], [1.0, -2.0], [2.0, -4.0]]
    out = mo.bulk_motion(scene, t, displacement=u, wrap=False)
    np.testing.assert_allclose(out.x.values[2] - scene.x.values, -4.0)
    # deform (uniaxial strain, the FEM route takes the same displace) then move
    deformed = speckle.uniaxial_strain(scene, [0.01]).isel(strain=0, drop=True)
    moved = mo.brownian_motion(deformed, t, diffusion=0.1, seed=1)
    np.testing.assert_array_equal(moved.z.values[0], deformed.z.values)
    # or move then deform one time
    one = speckle.displace(moved.isel(time=1, drop=True), lambda z, x: 0.5 * np.ones_like(z))
    np.testing.assert_allclose(one.z.values, moved.z.values[1] + 0.5)


def test_independent_lines_move_in_depth_only():
    sc = speckle.random_scatterers(4, 8.0, n_pixels=16, depth_range=128.0, seed=1)
    out = mo.brownian_motion(sc, [0.0, 1.0], diffusion=1.0, seed=0)
    assert out.z.dims == ("time", "aline", "scatterer") and "x" not in out


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda s: mo.brownian_motion(s, [0.0, 1.0], diffusion=-1.0, seed=0), "diffusion"),
        (lambda s: mo.brownian_motion(s, [0.0, 1.0, 1.0], diffusion=1.0, seed=0), "increasing"),
        (lambda s: mo.brownian_motion(s, [1.0, 0.0], diffusion=1.0, seed=0), "increasing"),
        (lambda s: mo.brownian_motion(s, [0.0, 1.0], diffusion=1e5, seed=0), "extent"),
        (lambda s: mo.flow_motion(s, [0.0, 1.0], velocity=[0.0, 100.0]), "extent"),
        (lambda s: mo.flow_motion(s, [0.0, 1.0], velocity=[0.0]), "velocity"),
        (lambda s: mo.ballistic_motion(s, [0.0, 1.0], speed=-1.0, seed=0), "speed"),
        (lambda s: mo.ballistic_motion(s, [0.0, 1.0], speed=1e3, seed=0), "extent"),
        (
            lambda s: mo.ballistic_motion(s, [0.0, 1.0], speed=1.0, seed=0, distribution="levy"),
            "distribution",
        ),
        (lambda s: mo.bulk_motion(s, [0.0, 1.0], displacement=[[0, 0]]), "shape"),
        (lambda s: mo.brownian_motion(s, [0, 1], diffusion=1.0, seed=0, fraction=2), "fraction"),
        (lambda s: mo.brownian_motion(s, [[0, 1]], diffusion=1.0, seed=0), "1-D"),
        (lambda s: mo.brownian_motion(s, [0, np.nan], diffusion=1.0, seed=0), "finite"),
    ],
)
def test_bad_input_is_refused(scene, call, match):
    with pytest.raises(ValueError, match=match):
        call(scene)
