"""Random phase perturbations along depth: screen statistics and decorrelation vs theory."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.system.phase import phase_screens, phase_structure, shared_phase_screen

S2, ELL, K0 = 1e-6, 20.0, 6.0  # index variance, correlation length (µm), k0 (rad/µm)


def test_structure_function_limits():
    u = np.array([1e-3, 0.01]) * ELL
    np.testing.assert_allclose(phase_structure(u, S2, ELL, K0), 4 * K0**2 * S2 * u**2, rtol=1e-4)
    big = 1e3 * ELL
    expected = 4 * K0**2 * S2 * (big * ELL * np.sqrt(np.pi) - ELL**2)
    assert phase_structure(big, S2, ELL, K0) == pytest.approx(expected, rel=1e-12)


def test_screen_variance_and_increments_match_theory():
    """Var phi(z) = 4 k0^2 D(z) and Var[phi(b) - phi(a)] = 4 k0^2 D(b - a), within sampling SE."""
    z = np.arange(0, 41) * ELL / 8  # grid nodes (exact draws), 0 .. 5 l
    phi = phase_screens(z, n_screens=4000, index_variance=S2, correlation_length=ELL, k0=K0, seed=2)
    n = phi.shape[0]
    for j in (4, 8, 20, 40):
        for est, theory in (
            (phi[:, j].var(), phase_structure(z[j], S2, ELL, K0)),
            ((phi[:, j] - phi[:, 8]).var(), phase_structure(z[j] - z[8], S2, ELL, K0)),
        ):
            se = theory * np.sqrt(2 / (n - 1))  # SE of a Gaussian sample variance
            assert abs(est - theory) < 4 * se + 1e-15


def test_independent_screens_decorrelate_scatterers_as_exp_minus_variance():
    """Two acquisitions, independent screens: E exp(i dphi) = exp(-4 k0^2 D(z)) per scatterer."""
    scene = speckle.random_scatterers(200, 1.0, n_pixels=64, depth_range=640.0, seed=4)
    kw = {"index_variance": S2, "correlation_length": ELL, "k0": K0}
    a = speckle.phase_perturb(scene, seed=1, **kw).amplitude
    b = speckle.phase_perturb(scene, seed=2, **kw).amplitude
    g = (a * np.conj(b) / abs(scene.amplitude) ** 2).values  # (aline, scatterer)
    z = scene.z.values
    for lo, hi in ((0, 40), (100, 160), (300, 400), (560, 640)):
        sel = (z >= lo) & (z < hi)
        theory = np.exp(-phase_structure(z[sel], S2, ELL, K0)).mean()
        # scatterers of one line share its screen: lines are the independent samples
        per_line = np.array([g[i, sel[i]].mean() for i in range(g.shape[0]) if sel[i].any()])
        for part, expected in ((per_line.real, theory), (per_line.imag, 0.0)):
            assert abs(part.mean() - expected) < 4 * part.std(ddof=1) / np.sqrt(part.size)


def test_pixel_field_correlation_between_acquisitions():
    """Complex correlation of two images (independent screens) in a depth band ~ exp(-Var phi)."""
    n, h = 64, 640.0
    src = speckle.spectrum(n, h, k0=K0, shape="gaussian", fwhm_fraction=0.6)
    scene = speckle.random_scatterers(300, 4.0, n_pixels=n, depth_range=h, seed=9)
    kw = {"index_variance": S2, "correlation_length": ELL, "k0": K0}
    a, b = (
        speckle.bscan(speckle.phase_perturb(scene, seed=s, **kw), src, method="nufft", tol=1e-10)
        for s in (1, 2)
    )
    for rows in (slice(20, 26), slice(44, 50)):
        fa, fb = a.field.isel(depth=rows).values, b.field.isel(depth=rows).values
        per_line = np.sum(fa * np.conj(fb), axis=0) / np.sqrt(
            np.sum(abs(fa) ** 2, axis=0) * np.sum(abs(fb) ** 2, axis=0)
        )
        z = a.depth.values[rows]
        # band average of exp(-V) over the pixel depths (V nearly linear over 6 px and the PSF)
        theory = np.exp(-phase_structure(z, S2, ELL, K0)).mean()
        se = per_line.real.std(ddof=1) / np.sqrt(per_line.size)
        assert abs(per_line.real.mean() - theory) < 4 * se + 0.01


def test_screens_reproducible_and_bad_inputs():
    kw = {"n_screens": 3, "index_variance": S2, "correlation_length": ELL, "k0": K0}
    z = [0.0, 10.0, 50.0]
    np.testing.assert_array_equal(phase_screens(z, seed=1, **kw), phase_screens(z, seed=1, **kw))
    with pytest.raises(ValueError, match="index_variance"):
        phase_screens(z, seed=1, **{**kw, "index_variance": -1.0})
    with pytest.raises(ValueError, match="correlation_length"):
        phase_screens(z, seed=1, **{**kw, "correlation_length": 0.0})
    with pytest.raises(ValueError, match=">= 0"):
        phase_screens([-1.0], seed=1, **kw)


def test_shared_screen_variance_and_lateral_correlation():
    """2-D screen: Var phi(z, x) = 4 k0^2 D(z) at every x, correlation exp(-dx^2/l_x^2)."""
    k0, s2, ell, lx, n = 7.5, 1e-6, 20.0, 30.0, 2000
    z = np.array([50.0, 50.0, 50.0, 120.0])
    x = np.array([0.0, 15.0, 45.0, 15.0])
    draws = np.array(
        [
            shared_phase_screen(
                z,
                x,
                index_variance=s2,
                correlation_length=ell,
                k0=k0,
                seed=s,
                lateral_correlation_length=lx,
            )
            for s in range(n)
        ]
    )
    var = phase_structure(z, s2, ell, k0)
    # sample variance of a Gaussian: relative SE sqrt(2/n)
    assert np.all(np.abs(draws.var(axis=0) / var - 1) < 4 * np.sqrt(2 / n))
    rho = np.corrcoef(draws.T)
    for j, dx in ((1, 15.0), (2, 45.0)):
        expected = np.exp(-(dx**2) / lx**2)
        assert abs(rho[0, j] - expected) < 4 * (1 - expected**2) / np.sqrt(n) + 0.01
    # the same depth process at every x: phi(50, 15) and phi(120, 15) as for one line
    c_z = 0.5 * (var[1] + var[3] - phase_structure(70.0, s2, ell, k0)) / np.sqrt(var[1] * var[3])
    assert abs(rho[1, 3] - c_z) < 4 * (1 - c_z**2) / np.sqrt(n) + 0.01


def test_phase_perturb_on_shared_scene():
    regions = speckle.make_regions(speckle.scene.regions.background(density=0.01))
    scene = speckle.shared_scene(regions, z_range=(0.0, 200.0), x_range=(0.0, 100.0), seed=3)
    kw = dict(index_variance=1e-6, correlation_length=20.0, k0=7.5, seed=4)
    out = speckle.phase_perturb(scene, **kw)
    phi = shared_phase_screen(scene.z.values, scene.x.values, **kw)
    np.testing.assert_allclose(out.amplitude.values, scene.amplitude.values * np.exp(1j * phi))
    with pytest.raises(ValueError, match="lateral_correlation_length"):
        speckle.phase_perturb(scene, **kw, lateral_correlation_length=-1.0)
    lines = speckle.random_scatterers(2, 1.0, n_pixels=16, depth_range=128.0, seed=0)
    with pytest.raises(ValueError, match="shared scenes only"):
        speckle.phase_perturb(lines, **kw, lateral_correlation_length=10.0)
