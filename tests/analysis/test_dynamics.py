"""Contrasts of speckle in time against their theory, within derived standard errors.

Statistics. Every estimate pools pixels whose speckle is independent: the paper's independent
A-lines (no lateral coupling), or, under a beam, blocks of depth pixels (a rectangular
spectrum's pixels are uncorrelated: the field correlation between pixels ``p`` apart is the
Dirichlet kernel, zero at every non-zero integer ``p`` on the periodic grid). The standard
error of a pooled estimate is then the spread of its value over ``K`` such blocks divided by
``sqrt(K)`` (the SE of a mean of ``K`` independent estimates); each check is
``|measured - expected| < 3 SE`` (plus a derived bias where one is stated). Expected values are
the exact expectations of :mod:`speckle.analysis.dynamics_theory` (band-averaged over the
sampled spectrum where the test says so); finite-sample ratio-estimator biases are
``O(1/pixels)``, below 1e-4 here.

Densities: developed speckle needs many scatterers per resolution cell; the fourth-order
(Poisson) term of the intensity is ``(2N^2 + 1)/(3 rho N^2) ~ 2/(3 rho)`` for ``rho``
scatterers per pixel with a rectangular spectrum (``int |h|^4 = H (2N^3 + N)/3``), added to
``g2`` exactly; log-intensity statistics move by about that fraction of the excess kurtosis,
below 0.4 SE at the densities used.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import dynamics as dy
from speckle.analysis import dynamics_theory as th
from speckle.imaging import timeseries as ts
from speckle.scene import motion as mo
from speckle.scene.regions import background, make_regions

N = 128
H = N * 8.0
K = 16  # blocks


def _lines_series(motion, *, density, n_lines, frames, dt, seed=3, k0_dk=10):
    src = speckle.spectrum(N, H, k0_dk=k0_dk)
    sc = speckle.random_scatterers(
        n_lines, density, n_pixels=N, depth_range=H, seed=seed, count="poisson"
    )
    moved = motion(sc, np.arange(frames) * dt)
    img = ts.bscan_series(moved, src, method="finufft", tol=1e-11)
    return src, img.field.transpose("time", "depth", "aline").load()


def _report(name: str, measured: float, expected: float, se: float) -> None:
    """One theory check's numbers (shown with ``pytest -s``)."""
    z = (measured - expected) / se if se > 0 else np.nan
    print(
        f"CHECK {name}: measured {measured:.6g}, expected {expected:.6g}, SE {se:.3g}, z {z:+.2f}"
    )


def _blocked(stat, field: xr.DataArray, dim: str, k: int = K) -> tuple[np.ndarray, np.ndarray]:
    """Statistic on the whole series and its SE from ``k`` blocks along ``dim``."""
    parts = np.array_split(np.arange(field.sizes[dim]), k)
    est = np.stack([np.asarray(stat(field.isel({dim: p}))) for p in parts])
    return np.asarray(stat(field)), est.std(axis=0, ddof=1) / np.sqrt(k)


# ------------------------------------------------------------------------------------------
# Brownian motion, independent lines: g1, g2 (Siegert), speckle variance, LIV, OCDS
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def brownian():
    src0 = speckle.spectrum(N, H, k0_dk=10)
    k0 = src0.attrs["k0"]
    d = 0.05  # µm^2/s
    dt = 0.3 / (4 * k0**2 * d)  # q^2 D dt = 0.3 per frame
    src, f = _lines_series(
        lambda sc, t: mo.brownian_motion(sc, t, diffusion=d, seed=5),
        density=128.0,
        n_lines=64,
        frames=8,
        dt=dt,
    )
    return src, f, d, dt, k0


def test_g1_brownian(brownian):
    src, f, d, dt, k0 = brownian
    m = np.arange(8)
    res = dy.g1(f, blocks=K)
    theory = th.g1_brownian(m * dt, diffusion=d, k0=k0, spectrum=src)
    meas = np.abs(res.g1.values)
    np.testing.assert_allclose(res.lag.values, m * dt)
    for i in m[1:]:
        _report(f"Brownian |g1|, lag {i}", meas[i], theory[i], res.g1_se.values[i])
        assert abs(meas[i] - theory[i]) < 3 * res.g1_se.values[i], (
            i,
            meas[i],
            theory[i],
            res.g1_se.values[i],
        )
    # the narrow-band formula exp(-q^2 D tau) against the band average: with k_n = k0 (1 + u),
    # E exp(-x (2u + u^2)) = 1 - 2x E[u] + (2x^2 - x) E[u^2] + O(x^3 E[u^3]), x = q^2 D tau
    simple = th.g1_brownian(m * dt, diffusion=d, k0=k0)
    u = (src.wavenumber.values - k0) / k0
    x = 4 * k0**2 * d * m * dt
    second = -2 * x * u.mean() + (2 * x**2 - x) * np.mean(u**2)
    np.testing.assert_allclose(theory / simple - 1, second, rtol=0, atol=1e-5)
    # the old name gives the same numbers (one implementation)
    from speckle.analysis.compounding import brownian_g1

    np.testing.assert_array_equal(brownian_g1(m * dt, d, k0), simple)


def test_siegert_g2(brownian):
    src, f, d, dt, k0 = brownian
    m = np.arange(8)
    g2m, se = _blocked(lambda x: dy.g2(x).values, f, "aline")
    g1t = th.g1_brownian(m * dt, diffusion=d, k0=k0, spectrum=src)
    poisson = (2 * N**2 + 1) / (3 * 128.0 * N**2)  # fourth-order term of the Poisson scene
    expect = th.siegert_g2(g1t) + poisson
    for i in m:
        _report(f"Brownian g2 (Siegert + Poisson term), lag {i}", g2m[i], expect[i], se[i])
        assert abs(g2m[i] - expect[i]) < 3 * se[i], (i, g2m[i], expect[i], se[i])


def test_speckle_variance_and_liv_of_a_brownian_region(brownian):
    src, f, d, dt, k0 = brownian
    g1t = th.g1_brownian(np.arange(8) * dt, diffusion=d, k0=k0, spectrum=src)
    intensity = np.abs(f) ** 2
    mean_i = float(intensity.mean())
    sv, sv_se = _blocked(lambda x: dy.speckle_variance(x).values, intensity, "aline")
    sv_exp = th.speckle_variance_expected(g1t) * mean_i**2
    _report(
        "Brownian speckle variance / <I>^2", sv / mean_i**2, sv_exp / mean_i**2, sv_se / mean_i**2
    )
    assert abs(sv - sv_exp) < 3 * sv_se, (sv, sv_exp, sv_se)
    lv, lv_se = _blocked(lambda x: dy.liv(x).values, intensity, "aline")
    lv_exp = th.liv_expected(g1t)
    _report("Brownian LIV (dB^2)", lv, lv_exp, lv_se)
    assert abs(lv - lv_exp) < 3 * lv_se, (lv, lv_exp, lv_se)
    # uncorrelated frames would give (1 - 1/N) 31.0 dB^2: the Brownian region is well below
    assert lv_exp < 0.9 * th.liv_expected(np.r_[1.0, np.zeros(7)])


def test_ocds_of_a_brownian_region(brownian):
    src, f, d, dt, k0 = brownian
    lags = np.arange(8) * dt
    g1t = th.g1_brownian(lags, diffusion=d, k0=k0, spectrum=src)
    delays = (dt, 4 * dt)
    intensity = np.abs(f) ** 2
    oc, oc_se = _blocked(lambda x: dy.ocds(x, delays=delays).values, intensity, "aline")
    oc_exp = th.ocds_expected(g1t, lags, delays=delays)
    _report("Brownian OCDS (1/s)", oc, oc_exp, oc_se)
    assert abs(oc - oc_exp) < 3 * oc_se, (oc, oc_exp, oc_se)


def test_ssada_of_a_brownian_region(brownian):
    """SSADA against 1 - mean_b (E(m_b) - (1 - m_b) K(m_b))/m_b, m_b = |g1_b(dt)|^2 of each
    sub-band's spectrum S W_b (frequency_looks is exact: imaging with S W_b)."""
    from speckle.analysis.compounding import subband_apodizations

    src, f, d, dt, k0 = brownian
    windows = subband_apodizations(N, 4, apodization="hann", overlap=0.5)
    bands = [
        th.g1_brownian(dt, diffusion=d, k0=k0, spectrum=src.copy(data=src.values * w))
        for w in windows
    ]
    expect = th.ssada_expected(bands)
    est, se = _blocked(lambda x: dy.ssada(x, n_bands=4).values, f, "aline")
    _report("SSADA of a Brownian region (4 Hann bands)", est, expect, se)
    assert abs(est - expect) < 3 * se, (est, expect, se)
    assert 0 < expect < 1 - np.pi / 4


# ------------------------------------------------------------------------------------------
# Ballistic motion and axial flow (independent lines)
# ------------------------------------------------------------------------------------------


def test_ballistic_gaussian_decay():
    k0 = speckle.spectrum(N, H, k0_dk=10).attrs["k0"]
    s = 1.0  # µm/s, one axis: sigma = s
    dt = 0.35 / (2 * k0 * s)  # q sigma dt = 0.35: exp(-0.06 m^2)
    src, f = _lines_series(
        lambda sc, t: mo.ballistic_motion(sc, t, speed=s, seed=2),
        density=32.0,
        n_lines=128,
        frames=6,
        dt=dt,
    )
    res = dy.g1(f, blocks=K)
    theory = th.g1_ballistic(np.arange(6) * dt, speed=s, k0=k0, ndim=1, spectrum=src)
    for i in range(1, 6):
        _report(f"ballistic |g1|, lag {i}", abs(res.g1.values[i]), theory[i], res.g1_se.values[i])
        assert abs(abs(res.g1.values[i]) - theory[i]) < 3 * res.g1_se.values[i], i
    # Gaussian in tau, not exponential: log g1 is quadratic in the lag
    lg = -np.log(th.g1_ballistic(np.arange(1, 6) * dt, speed=s, k0=k0, ndim=1))
    np.testing.assert_allclose(lg / lg[0], np.arange(1, 6) ** 2, rtol=1e-12)


def test_ballistic_constant_speed_oscillates():
    """Speed s along +-z (independent lines, one axis): g1 = cos(q s tau), band-averaged."""
    k0 = speckle.spectrum(N, H, k0_dk=10).attrs["k0"]
    s = 1.0
    dt = 0.5 / (2 * k0 * s)  # q s dt = 0.5 rad
    src, f = _lines_series(
        lambda sc, t: mo.ballistic_motion(sc, t, speed=s, seed=4, distribution="constant"),
        density=32.0,
        n_lines=128,
        frames=6,
        dt=dt,
    )
    lags = np.arange(6) * dt
    re, se = _blocked(lambda x: dy.g1(x).values.real, f, "aline")
    theory = th.g1_ballistic(lags, speed=s, k0=k0, ndim=1, distribution="constant", spectrum=src)
    np.testing.assert_allclose(
        th.g1_ballistic(lags, speed=s, k0=k0, ndim=1, distribution="constant"),
        np.cos(2 * k0 * s * lags),
        atol=1e-12,
    )
    for i in range(1, 6):
        _report(f"ballistic constant-speed Re g1, lag {i}", re[i], theory[i], se[i])
        assert abs(re[i] - theory[i]) < 3 * se[i], (i, re[i], theory[i], se[i])
    assert theory[5] < -0.7  # cos(2.5): the correlation changes sign


def test_static_and_moving_fractions_mix():
    """A moving fraction f of equal-amplitude scatterers: g1 = (1 - f) + f g1_moving."""
    src0 = speckle.spectrum(N, H, k0_dk=10)
    k0 = src0.attrs["k0"]
    d, frac = 0.05, 0.4
    dt = 0.5 / (4 * k0**2 * d)
    src, f = _lines_series(
        lambda sc, t: mo.brownian_motion(sc, t, diffusion=d, seed=6, fraction=frac),
        density=32.0,
        n_lines=128,
        frames=5,
        dt=dt,
    )
    res = dy.g1(f, blocks=K)
    moving = th.g1_brownian(np.arange(5) * dt, diffusion=d, k0=k0, spectrum=src)
    expect = (1 - frac) + frac * moving
    for i in range(1, 5):
        g, se = abs(res.g1.values[i]), res.g1_se.values[i]
        _report(f"static + moving fraction 0.4 |g1|, lag {i}", g, expect[i], se)
        assert abs(g - expect[i]) < 3 * se, (i, g, expect[i], se)


@pytest.fixture(scope="module")
def axial():
    k0 = speckle.spectrum(N, H, k0_dk=10).attrs["k0"]
    return k0


def test_axial_flow_through_the_coherence_gate(axial):
    """Complex g1 of uniform axial flow: the Dirichlet kernel of the band times the carrier."""
    v, dt = 1.5, 1.0  # 1.5 µm per frame against 8 µm pixels
    src, f = _lines_series(
        lambda sc, t: mo.flow_motion(sc, t, velocity=[v]),
        density=32.0,
        n_lines=128,
        frames=6,
        dt=dt,
    )
    lags = np.arange(6)
    g = dy.g1(f).values
    theory = th.g1_axial_flow(lags * dt, velocity=v, spectrum=src)
    _, re_se = _blocked(lambda x: dy.g1(x).values.real, f, "aline")
    _, im_se = _blocked(lambda x: dy.g1(x).values.imag, f, "aline")
    for i in lags[1:]:
        _report(f"axial flow Re g1, lag {i}", g[i].real, theory[i].real, re_se[i])
        _report(f"axial flow Im g1, lag {i}", g[i].imag, theory[i].imag, im_se[i])
        assert abs(g[i].real - theory[i].real) < 3 * re_se[i], (i, g[i], theory[i], re_se[i])
        assert abs(g[i].imag - theory[i].imag) < 3 * im_se[i], (i, g[i], theory[i], im_se[i])
    assert abs(theory[5]) < 0.25  # the coherence gate decorrelates 7.5 µm of flow


def test_doppler_phase_kasai(axial):
    k0 = axial
    phase = 0.6  # rad per frame
    dt = 1e-3
    v = phase / (2 * k0 * dt)  # µm/s
    src, f = _lines_series(
        lambda sc, t: mo.flow_motion(sc, t, velocity=[v]),
        density=32.0,
        n_lines=128,
        frames=4,
        dt=dt,
    )
    est, se = _blocked(lambda x: dy.doppler_phase(x).values, f, "aline")
    exact = np.angle(th.g1_axial_flow(dt, velocity=v, spectrum=src))
    _report("Doppler phase (Kasai) vs arg G_z", est, exact, se)
    _report(
        "Doppler phase (Kasai) vs 2 k0 v tau",
        est,
        shift := th.doppler_shift(dt, velocity=v, k0=k0),
        se,
    )
    assert abs(est - exact) < 3 * se, (est, exact, se)
    # 2 k0 v tau up to the band's asymmetry (index -N/2 ... N/2-1): centre k0 - pi/(2H)
    assert abs(est - shift) < 3 * se + shift * np.pi / (2 * H * k0), (est, shift, se)


# ------------------------------------------------------------------------------------------
# Shared scenes under a beam: transverse flow, and the Tsukuba finding
# ------------------------------------------------------------------------------------------

NS, HS = 64, 256.0  # pixels, depth: 4 µm pixels
PITCH = 2.0


@pytest.fixture(scope="module")
def shared():
    regs = make_regions(background(density=1.0))
    return speckle.shared_scene(regs, z_range=(0.0, HS), x_range=(0.0, 300.0), seed=4)


def _beam_g1(moved, *, k0_dk, waist, lags):
    """|g1| at ``lags`` and its SE from K blocks of depth pixels (independent speckle)."""
    src = speckle.spectrum(NS, HS, k0_dk=k0_dk)
    x = speckle.scan_lines(96, PITCH, start=54.0)
    f = ts.bscan_series(moved, src, waist=waist, lines=x, method="finufft", tol=1e-11, wrap=True)
    res = dy.g1(f.field, lags=lags, blocks=K, block_dim="depth")
    return np.abs(res.g1.values), res.g1_se.values, src


def test_transverse_flow_decorrelates_through_the_beam(shared):
    w0, v, dt = 6.0, 1000.0, 2e-3  # 2 µm per frame
    moved = mo.flow_motion(shared, np.arange(5) * dt, velocity=[0.0, v])
    lags = [1, 2, 4]
    g, se, _ = _beam_g1(moved, k0_dk=10, waist=w0, lags=lags)
    expect = th.g1_transverse_flow(np.array(lags) * dt, velocity=v, waist=w0)
    for i, lag in enumerate(lags):
        _report(f"transverse flow g1, lag {lag}", g[i], expect[i], se[i])
        assert abs(g[i] - expect[i]) < 3 * se[i], (lag, g[i], expect[i], se[i])


def test_flow_through_the_imaging_plane():
    """3-D scene, flow along y through the B-scan plane: the same exp(-(v tau)^2/w0^2)."""
    regs = make_regions(background(density=0.1))
    sc = speckle.shared_scene(
        regs, z_range=(0.0, 128.0), x_range=(0.0, 100.0), y_range=(0.0, 80.0), seed=1, tile=32.0
    )
    src = speckle.spectrum(32, 128.0, k0_dk=10)
    v, dt, w0 = 1000.0, 3e-3, 6.0
    moved = mo.flow_motion(sc, np.arange(3) * dt, velocity=[0.0, 0.0, v])
    x = speckle.scan_lines(32, PITCH, start=18.0)
    f = ts.bscan_series(moved, src, waist=w0, lines=x, y=40.0, method="nufft", tol=1e-9, wrap=True)
    res = dy.g1(f.field, lags=[1, 2], blocks=K, block_dim="depth")
    expect = th.g1_transverse_flow(np.array([1, 2]) * dt, velocity=v, waist=w0)
    for i in range(2):
        g, se = abs(res.g1.values[i]), res.g1_se.values[i]
        _report(f"through-plane flow |g1|, lag {i + 1}", g, expect[i], se)
        assert abs(g - expect[i]) < 3 * se, (i, g, expect[i], se)


def test_ballistic_in_a_shared_scene_under_the_beam(shared):
    """2-D Gaussian ballistic motion: axial exp(-q^2 sigma^2 tau^2/2) x lateral factor."""
    k0 = speckle.spectrum(NS, HS, k0_dk=10).attrs["k0"]
    s = 1.0  # rms speed over 2 axes: sigma = s/sqrt(2)
    dt = 0.4 * np.sqrt(2) / (2 * k0 * s)  # q sigma dt = 0.4
    moved = mo.ballistic_motion(shared, np.arange(4) * dt, speed=s, seed=9, wrap=True)
    g, se, src = _beam_g1(moved, k0_dk=10, waist=6.0, lags=[1, 2, 3])
    expect = th.g1_ballistic(np.arange(1, 4) * dt, speed=s, k0=k0, ndim=2, waist=6.0, spectrum=src)
    for i in range(3):
        _report(f"ballistic 2-D under the beam |g1|, lag {i + 1}", g[i], expect[i], se[i])
        assert abs(g[i] - expect[i]) < 3 * se[i], (i, g[i], expect[i], se[i])


def test_liv_and_ocds_of_a_brownian_layer_in_static_tissue():
    """A Brownian layer (region 1) in static tissue under the beam: LIV and OCDS of its interior
    rows against their expected values from g1.

    Interior rows are >= 15 pixels from the layer's edges: the static intensity leaking in
    through the rectangular band's PSF tails is ~ 1/(2 pi^2 m) < 0.4 % there (0.1 dB^2 of LIV
    at most, below 0.3 SE); blocks of depth rows are independent (module docstring).
    """
    from speckle.scene.regions import layer

    regs = make_regions(background(density=1.0), layer(40.0, 216.0, density=1.0))
    sc = speckle.shared_scene(regs, z_range=(0.0, HS), x_range=(0.0, 300.0), seed=8)
    src = speckle.spectrum(NS, HS, k0_dk=10)
    k0, d, w0 = src.attrs["k0"], 0.05, 6.0
    dt = 0.3 / (4 * k0**2 * d)
    n = 8
    moved = mo.brownian_motion(sc, np.arange(n) * dt, diffusion=d, seed=3, regions=[1])
    x = speckle.scan_lines(96, PITCH, start=54.0)
    f = ts.bscan_series(moved, src, waist=w0, lines=x, method="finufft", tol=1e-11, wrap=True)
    intensity = f.intensity.transpose("time", "depth", "x").load()
    rows = np.arange(NS)[
        (np.arange(NS) * 4.0 >= 40.0 + 60.0) & (np.arange(NS) * 4.0 < 216.0 - 60.0)
    ]
    inner = intensity.isel(depth=rows)
    g1t = th.g1_brownian(
        np.arange(n) * dt, diffusion=d, k0=k0, spectrum=src, waist=w0, lateral_axes=1
    )
    lv, lv_se = _blocked(lambda x: dy.liv(x).values, inner, "depth", k=len(rows))
    _report("LIV of a Brownian layer under the beam (dB^2)", lv, th.liv_expected(g1t), lv_se)
    assert abs(lv - th.liv_expected(g1t)) < 3 * lv_se
    delays = (dt, 4 * dt)
    oc, oc_se = _blocked(lambda x: dy.ocds(x, delays=delays).values, inner, "depth", k=len(rows))
    oc_exp = th.ocds_expected(g1t, np.arange(n) * dt, delays=delays)
    _report("OCDS of a Brownian layer under the beam (1/s)", oc, oc_exp, oc_se)
    assert abs(oc - oc_exp) < 3 * oc_se


def test_tsukuba_wavelength_and_resolution_dependence(shared):
    """Diffusion decorrelates with k0 (wavelength), not with the waist; transverse flow with
    the waist (resolution), not with k0 (Fujimura et al. 2025)."""
    k0 = speckle.spectrum(NS, HS, k0_dk=10).attrs["k0"]
    d = 0.05
    dt = 0.5 / (4 * k0**2 * d)  # q^2 D dt = 0.5 at k0_dk = 10
    times = np.arange(3) * dt
    brown = mo.brownian_motion(shared, times, diffusion=d, seed=7)
    v, dtf = 1000.0, 5e-3  # 5 µm per frame
    flow = mo.flow_motion(shared, np.arange(3) * dtf, velocity=[0.0, v])
    out = {}
    for name, moved in (("brownian", brown), ("flow", flow)):
        for k0_dk, w0 in ((10, 6.0), (5, 6.0), (10, 12.0)):
            gs, ses, src = _beam_g1(moved, k0_dk=k0_dk, waist=w0, lags=[1])
            g, se = float(gs[0]), float(ses[0])
            if name == "brownian":
                expect = float(
                    th.g1_brownian(
                        dt,
                        diffusion=d,
                        k0=src.attrs["k0"],
                        spectrum=src,
                        waist=w0,
                        lateral_axes=1,
                    )
                )
            else:
                expect = float(th.g1_transverse_flow(dtf, velocity=v, waist=w0))
            _report(f"Tsukuba {name} |g1|, k0_dk {k0_dk}, w0 {w0}", g, expect, se)
            assert abs(g - expect) < 3 * se, (name, k0_dk, w0, g, expect, se)
            out[name, k0_dk, w0] = (g, se)

    def differ(a, b):
        return abs(out[a][0] - out[b][0]) / np.hypot(out[a][1], out[b][1])

    # Brownian: wavelength dependence far above the noise, none on the waist within it
    assert differ(("brownian", 10, 6.0), ("brownian", 5, 6.0)) > 10
    assert differ(("brownian", 10, 6.0), ("brownian", 10, 12.0)) < 3
    # flow: waist dependence far above the noise, none on the wavelength within it
    assert differ(("flow", 10, 6.0), ("flow", 10, 12.0)) > 10
    assert differ(("flow", 10, 6.0), ("flow", 5, 6.0)) < 3


# ------------------------------------------------------------------------------------------
# Limits, SSADA, and bad input
# ------------------------------------------------------------------------------------------


def test_ssada_limits():
    """Static speckle: 0 exactly; independent developed speckle: 1 - pi/4."""
    src = speckle.spectrum(N, H, k0_dk=10)
    frames = []
    for seed in (1, 2, 3):
        sc = speckle.random_scatterers(
            64, 32.0, n_pixels=N, depth_range=H, seed=seed, count="poisson"
        )
        frames.append(speckle.bscan(sc, src, method="finufft", tol=1e-11).field)
    f = xr.concat(frames, "time").assign_coords(time=[0.0, 1.0, 2.0])
    f = f.transpose("time", "depth", "aline")
    static = xr.concat([frames[0]] * 3, "time").transpose("time", "depth", "aline")
    assert float(dy.ssada(static, n_bands=4)) == pytest.approx(0.0, abs=1e-12)
    est, se = _blocked(lambda x: dy.ssada(x, n_bands=4).values, f, "aline")
    _report("SSADA of independent frames", est, 1 - np.pi / 4, se)
    assert abs(est - (1 - np.pi / 4)) < 3 * se, (est, 1 - np.pi / 4, se)


def test_no_answer_is_nan_with_a_reason():
    z = xr.DataArray(np.zeros((3, 4), complex), dims=("time", "x"), coords={"time": [0, 1, 2.0]})
    with pytest.warns(RuntimeWarning, match="no signal"):
        assert np.isnan(dy.g1(z, lags=[1]).values).all()
    with pytest.warns(RuntimeWarning, match="logarithm"):
        assert np.isnan(float(dy.liv(abs(z) ** 2)))
    with pytest.warns(RuntimeWarning, match="undefined"):
        assert np.isnan(float(dy.doppler_phase(z)))


def test_a_time_dim_in_one_input_only_is_refused():
    img = xr.DataArray(
        np.exp(1j * np.arange(64.0)).reshape(8, 8),
        dims=("depth", "aline"),
        coords={"depth": np.arange(8.0), "aline": np.arange(8.0)},
    )
    series = xr.concat([img, img], "time").assign_coords(time=[0.0, 1.0])
    with pytest.raises(ValueError, match="'time' dim in deformed only"):
        speckle.correlation_map(img, series, window=4)
    both = speckle.correlation_map(series, series, window=4)  # same times: fine
    assert both.sizes["time"] == 2


@pytest.mark.parametrize(
    "call,exc,match",
    [
        (lambda f: dy.g1(f.isel(time=0)), ValueError, "'time' dim"),
        (lambda f: dy.liv(f.isel(time=0)), ValueError, "'time' dim"),
        (lambda f: dy.g1(f.assign_coords(time=[0.0, 1.0, 3.0])), ValueError, "equally spaced"),
        (lambda f: dy.ocds(abs(f), delays=(0.0, 0.5)), ValueError, "two"),
        (lambda f: dy.g1(abs(f)), TypeError, "complex"),
        (lambda f: dy.g1(f, lags=[5]), ValueError, "lags"),
        (lambda f: dy.doppler_phase(f, lag=3), ValueError, "lag"),
        (lambda f: dy.g1(f, window=(3, 3, 3)), ValueError, "window"),
        (lambda f: dy.g1(f, blocks=1), ValueError, "blocks"),
        (lambda f: th.g1_brownian(1.0, diffusion=-1.0, k0=1.0), ValueError, "diffusion"),
        (lambda f: th.g1_brownian(-1.0, diffusion=1.0, k0=1.0), ValueError, "lag"),
        (lambda f: th.siegert_g2(0.5, beta=2.0), ValueError, "beta"),
        (lambda f: th.liv_expected([0.5]), ValueError, "N >= 2"),
    ],
)
def test_bad_input_is_refused(call, exc, match):
    f = xr.DataArray(
        np.exp(1j * np.arange(12.0)).reshape(3, 4),
        dims=("time", "x"),
        coords={"time": [0.0, 1.0, 2.0]},
    )
    with pytest.raises(exc, match=match):
        call(f)
