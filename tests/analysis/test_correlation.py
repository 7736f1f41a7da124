"""Tests of speckle.analysis.correlation against exact references and the theory derived in its
module docstring (Campbell's theorem for Poisson scatterers).

Statistical tolerances: the sample Pearson coefficient of ``n`` independent pairs has standard
error ``(1 - r^2)/sqrt(n)`` for Gaussian variables; speckle intensities are exponential-like,
which at most doubles the variance, so we take ``SE = sqrt(2) (1 - r^2)/sqrt(n_eff)`` with
``n_eff`` the number of pixels divided by the speckle size in pixels (1 for the rectangular
spectrum, whose field is uncorrelated between pixels; 3 for the Gaussian one used here), and
allow 4 SE.
"""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import correlation as corr
from speckle.analysis import correlation_forms as forms
from speckle.scene import deformation as D

N, PIXEL = 64, 8.0
H = N * PIXEL
DK = N * np.pi / H


def tolerance(r, n_pixels, speckle_pixels=1.0):
    return 4 * np.sqrt(2) * (1 - r**2) / np.sqrt(n_pixels / speckle_pixels) + 1e-3


def strained_images(strains, src, *, n_alines=512, density=4.0, seed=11, count="poisson"):
    sc = D.deformable_scene(
        n_alines, density, n_pixels=N, depth_range=H, seed=seed, strain=strains, count=count
    )
    b = speckle.bscan(D.uniaxial_strain(sc, strains), src)
    disp = D.uniaxial_pixel_displacement(strains, b.depth.values, b.x.values)
    return b, corr.compensate(b, disp)


# --- exact evaluation and compensation -------------------------------------------------------


def test_sample_field_is_eq4_at_any_depth():
    rng = np.random.default_rng(0)
    z = rng.uniform(0, H, (3, 40))
    k0 = 10 * DK
    a = speckle.ascan(z, 1.0, n_pixels=N, depth_range=H, k0=k0)
    y = rng.uniform(-3, N + 3, (3, 25))
    got = corr.sample_field(a, y)
    # Eq. 4 at z_q = y*p: move the scatterers up by y*p and read pixel 0, carrier restored
    want = np.array(
        [
            [
                speckle.ascan(z[i] - yj * PIXEL, 1.0, n_pixels=N, depth_range=H, k0=k0)[0]
                * np.exp(2j * k0 * yj * PIXEL)
                for yj in y[i]
            ]
            for i in range(3)
        ]
    )
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(want).max())
    np.testing.assert_allclose(corr.sample_field(a, np.arange(N)), a, atol=1e-10 * N)


def test_exact_compensation_undoes_a_rigid_subpixel_shift():
    sc = D.deformable_scene(6, 3.0, n_pixels=N, depth_range=H, seed=2)
    src = speckle.spectrum(N, H, k0_dk=10)
    u = 0.37 * PIXEL
    ref = speckle.bscan(D.translate(sc, 0.0, wrap=True), src)
    moved = speckle.bscan(D.translate(sc, u, wrap=True), src)
    disp = D.pixel_displacement(lambda z, x: np.full(z.shape, u), ref.depth, ref.x)
    comp = corr.compensate(moved, disp)
    np.testing.assert_allclose(comp, ref.field, atol=1e-9 * float(abs(ref.field).max()))
    assert float(corr.pearson(ref, comp, kind="complex")) == pytest.approx(1.0, abs=1e-12)
    no_carrier = corr.compensate(moved, disp, carrier=False)
    # without removing exp(2i k0 u) the field differs by exactly that phase
    np.testing.assert_allclose(
        no_carrier,
        ref.field * np.exp(2j * src.attrs["k0"] * u),
        atol=1e-9 * float(abs(ref.field).max()),
    )


# --- correlation versus strain: simulation against theory ------------------------------------


@pytest.mark.parametrize(("shape", "speckle_pixels"), [("rectangular", 1.0), ("gaussian", 3.0)])
def test_exact_compensation_correlation_matches_theory(shape, speckle_pixels):
    strains = [0.0, 0.01, 0.03, 0.05]
    kw = {"fwhm": 0.5 * DK} if shape == "gaussian" else {}
    src = speckle.spectrum(N, H, k0_dk=10, shape=shape, **kw)
    b, comp = strained_images(strains, src)
    ref = b.field.sel(strain=0.0)
    theory = corr.expected_correlation(strains, spectrum=src, density=4.0)
    for kind in ("intensity", "complex"):
        sim = corr.pearson(ref, comp, kind=kind)
        for s in strains[1:]:
            r = float(theory[kind].sel(strain=s))
            assert float(sim.sel(strain=s)) == pytest.approx(
                r, abs=tolerance(r, ref.size, speckle_pixels)
            ), (kind, s)


def test_theory_matches_the_continuum_closed_forms():
    """Rectangular: |gamma| = (1 - s/2 - R s)/sqrt(1 - s) (overlap of the spectrum with its
    copy shifted by R s delta_k and scaled by a = 1 - s). Gaussian of rms width sigma (units
    of delta_k): the overlap of two Gaussians, sqrt(2a/(1 + a^2)) exp(-(R s)^2/(2 sigma^2
    (1 + a^2))). Finite N = 256 (and the truncation of the Gaussian at +-delta_k/2 = 4.7
    sigma) limit agreement: the periodic kernel lets the first pixels see the bottom of the
    image, which moves by s*N pixels, so a fraction ~(kernel width)/N of the pixels departs
    from the bulk value -- ~1e-2 (rectangular, long 1/x tails) and ~5e-3 (Gaussian)."""
    n, h = 256, 256 * PIXEL
    strains = np.array([0.005, 0.01, 0.03, 0.05, 0.08])
    rect = speckle.spectrum(n, h, k0_dk=10)
    got = corr.expected_correlation(strains, spectrum=rect, density=1e6).complex.values
    np.testing.assert_allclose(got, forms.continuum_gamma(strains, 10), atol=0.01)
    fwhm = 0.3
    sigma = fwhm / (2 * np.sqrt(2 * np.log(2)))
    gauss = speckle.spectrum(n, h, k0_dk=10, shape="gaussian", fwhm=fwhm * n * np.pi / h)
    got = corr.expected_correlation(strains, spectrum=gauss, density=1e6).complex.values
    a = 1 - strains
    want = np.sqrt(2 * a / (1 + a**2)) * np.exp(
        -((10 * strains) ** 2) / (2 * sigma**2 * (1 + a**2))
    )
    np.testing.assert_allclose(got, want, atol=5e-3)
    # high density: Siegert relation, intensity correlation = |gamma|^2 (the pooled intensity
    # averages |C_q|^2 over pixels, |gamma| is |mean C_q|: they differ by the spread of C_q
    # among the few edge pixels, ~1e-3)
    th = corr.expected_correlation(strains, spectrum=rect, density=1e6)
    np.testing.assert_allclose(th.intensity, th.complex**2, atol=2e-3)


def test_low_density_floor():
    """Beyond R s = 1 (rectangular spectrum) gamma = 0, but every scatterer keeps its own
    intensity |a|^2 |P|^2: the correlation floor is kappa D/(rho A^2 + kappa A4), in the
    continuum ~ (2/3)/(rho + 2/3) for equal amplitudes (A4/A^2 = 2/3 for sinc^2)."""
    strains = [0.0, 0.2]
    src = speckle.spectrum(N, H, k0_dk=10)
    density = 0.5
    b, comp = strained_images(strains, src, density=density, n_alines=512)
    th = corr.expected_correlation(strains, spectrum=src, density=density)
    r_floor = float(th.floor.sel(strain=0.2))
    assert float(th.intensity.sel(strain=0.2)) == pytest.approx(r_floor, abs=1e-3)
    # continuum value, with the 1 - s scaling of the deformed kernel (~10 % at s = 0.2)
    assert r_floor == pytest.approx((2 / 3) / (density + 2 / 3), rel=0.12)
    sim = float(corr.pearson(b.field.sel(strain=0.0), comp.sel(strain=0.2)))
    assert sim == pytest.approx(r_floor, abs=tolerance(r_floor, b.field.sel(strain=0).size))
    # the floor falls as 1/density: at density 4 it is ~0.14 (Fig. 6c)
    dense = corr.expected_correlation(0.2, spectrum=src, density=4.0).floor.item()
    assert dense < r_floor / 3


def test_one_pixel_shift_without_compensation():
    """Rectangular spectrum, rigid shift by one pixel (exact roll with wrap-around): the field
    correlation sum_n S_n^2 exp(2i pi n/N) / sum_n S_n^2 vanishes exactly (N-th roots of
    unity); the intensity keeps only the incoherent term, kappa D1/(rho A^2 + kappa A4) with
    D1 = int |P(x)|^2 |P(x+1)|^2, in the continuum D1/A^2 = 1/pi^2: (1/pi^2)/(rho + 2/3)."""
    density = 0.5
    sc = D.deformable_scene(512, density, n_pixels=N, depth_range=H, seed=4, count="poisson")
    src = speckle.spectrum(N, H, k0_dk=10)
    ref = speckle.bscan(D.translate(sc, 0.0, wrap=True), src)
    moved = speckle.bscan(D.translate(sc, PIXEL, wrap=True), src)
    np.testing.assert_allclose(abs(moved.field), abs(ref.field).roll(depth=1), rtol=1e-9)
    th = corr.expected_correlation(
        0.0, spectrum=src, density=density, compensation="none", shift=1.0
    )
    assert th.complex.item() == pytest.approx(0.0, abs=1e-6)
    expected = th.intensity.item()
    assert expected == pytest.approx((1 / np.pi**2) / (density + 2 / 3), rel=0.05)
    n = ref.field.size
    sim = corr.pearson(ref, moved)
    assert float(sim) == pytest.approx(expected, abs=tolerance(expected, n))
    # complex coefficient ~ 0: |r| of n pairs with true 0 has mean sqrt(pi/(4 n))
    assert float(corr.pearson(ref, moved, kind="complex")) < 4 * np.sqrt(np.pi / (4 * n))
    # half a pixel: |gamma| = |sum_n exp(i pi n/N)|/N ~ 2/pi
    th_half = corr.expected_correlation(
        0.0, spectrum=src, density=1e6, compensation="none", shift=0.5
    )
    assert th_half.complex.item() == pytest.approx(2 / np.pi, rel=1e-3)


def test_correlation_decreases_with_k0_over_delta_k():
    """After exact compensation |gamma| depends on R s only (plus the small 1 - s scaling):
    a larger k0/delta_k decorrelates faster at the same strain."""
    strains = np.linspace(0.0, 0.03, 7)
    curves = [
        corr.expected_correlation(
            strains, spectrum=speckle.spectrum(N, H, k0_dk=r), density=4.0
        ).intensity.values
        for r in (1, 3, 10)
    ]
    assert np.all(curves[0][1:] > curves[1][1:]) and np.all(curves[1][1:] > curves[2][1:])
    sc = D.deformable_scene(256, 4.0, n_pixels=N, depth_range=H, seed=8, strain=[0.0, 0.02])
    sims = []
    for r in (1, 3, 10):
        src = speckle.spectrum(N, H, k0_dk=r)
        b = speckle.bscan(D.uniaxial_strain(sc, [0.0, 0.02]), src)
        disp = D.uniaxial_pixel_displacement([0.02], b.depth.values, b.x.values)
        comp = corr.compensate(b.isel(strain=1), disp.isel(strain=0))
        sims.append(float(corr.pearson(b.isel(strain=0), comp)))
    assert sims[0] > sims[1] > sims[2]


def test_two_peak_spectrum_revives_and_carrier_window_factor():
    """A spectrum with two peaks separated by 0.5 delta_k has an autocorrelation side peak at
    lag 0.5: at R = 10 the compensated correlation revives near s = 5 % after a minimum near
    2.5 % -- the only single-spectrum way to a non-monotonic curve."""
    w = forms.two_peak_weights(256, separation=0.5, fwhm=0.15)
    src = speckle.spectrum(256, 256 * PIXEL, k0_dk=10, shape="array", weights=w)
    th = corr.expected_correlation([0.025, 0.05], spectrum=src, density=1e6).complex.values
    assert th[1] > 0.4 > 0.1 > th[0]
    f = forms.carrier_window_factor([0.0, 0.025, 0.0375, 0.05], 10, 4)
    np.testing.assert_allclose(f[[0, 1, 3]], [1.0, 0.0, 0.0], atol=1e-12)
    assert f[2] == pytest.approx(1 / (4 * np.sin(np.pi * 0.375)), rel=1e-12)


# --- maps and estimators ---------------------------------------------------------------------


def test_correlation_map_windows_and_edges():
    sc = D.deformable_scene(20, 2.0, n_pixels=N, depth_range=H, seed=1)
    b = speckle.bscan(sc, speckle.spectrum(N, H, k0_dk=3))
    for kind in corr.KINDS:
        m = corr.correlation_map(b, b, window=(8, 5), kind=kind)
        valid = np.isfinite(m.values)
        assert valid.sum() == (N - 8 + 1) * (20 - 5 + 1)
        np.testing.assert_allclose(m.values[valid], 1.0, atol=1e-9)
        assert not valid[:4].any() and not valid[:, :2].any()
    other = speckle.bscan(
        D.deformable_scene(20, 2.0, n_pixels=N, depth_range=H, seed=99),
        speckle.spectrum(N, H, k0_dk=3),
    )
    m = corr.correlation_map(b, other, window=16)
    # independent images: windowed Pearson of 256 pixels scatters around 0 with SE ~ 1/16
    assert abs(float(m.mean())) < 0.05


def test_pearson_kinds_and_conjugation():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(32, 8)) + 1j * rng.normal(size=(32, 8))
    xa = xr.DataArray(x, dims=("depth", "x"))
    assert float(corr.pearson(xa, xa * np.exp(0.7j), kind="complex")) == pytest.approx(1.0)
    assert float(corr.pearson(xa, 3 * xa, kind="amplitude")) == pytest.approx(1.0)
    assert float(corr.pearson(xa, np.conj(xa), kind="intensity")) == pytest.approx(1.0)


def test_bad_correlation_input():
    xa = xr.DataArray(np.ones((8, 4), complex), dims=("depth", "x"))
    with pytest.raises(ValueError, match="kind must be one of"):
        corr.pearson(xa, xa, kind="phase")
    with pytest.raises(ValueError, match="larger than the image"):
        corr.correlation_map(xa, xa, window=16)
    with pytest.raises(ValueError, match="window"):
        corr.correlation_map(xa, xa, window=(2, 2, 2))
    with pytest.raises(ValueError, match="strain"):
        corr.expected_correlation(1.0, spectrum=speckle.spectrum(N, H, k0_dk=1), density=1.0)
    with pytest.raises(ValueError, match="density"):
        corr.expected_correlation(0.1, spectrum=speckle.spectrum(N, H, k0_dk=1), density=0.0)


def test_lateral_compensation_of_poisson_expansion():
    """With a lateral Poisson expansion the material of A-line j moves to line
    j + rint(u_x/pitch); taking each pixel from there restores the correlation that the axial
    compensation alone loses (lines whose source is beyond the scan become NaN and are
    skipped). Scatterers within |r_j| = |u_x/pitch - rint(u_x/pitch)| of a beam edge still
    change line, so line j keeps a fraction f_j = 1 - |r_j| of its scatterers: the Gaussian part
    of the correlation scales by f_j^2 and the incoherent floor by f_j, i.e. about
    (corr - floor) <f^2> + floor <f> (pooling lines of equal variance)."""
    s, nu, n_alines = 0.1, 0.5, 64
    src = speckle.spectrum(N, H, k0_dk=1)
    sc = D.deformable_scene(n_alines, 4.0, n_pixels=N, depth_range=H, seed=6, strain=[0.0, s])
    b = speckle.bscan(D.uniaxial_strain(sc, [0.0, s], poisson_ratio=nu), src)
    ref, dfm = b.isel(strain=0), b.isel(strain=1)
    disp = D.uniaxial_pixel_displacement([s], b.depth.values, b.x.values, poisson_ratio=nu)
    disp = disp.isel(strain=0)
    lateral = corr.compensate(dfm, disp)
    axial = corr.compensate(dfm, disp.drop_vars("ux"))
    assert bool(np.isnan(lateral).any()) and not bool(np.isnan(axial).any())
    with_x = float(corr.pearson(ref, lateral))
    without_x = float(corr.pearson(ref, axial))
    th = corr.expected_correlation(s, spectrum=src, density=4.0)
    u = nu * s * (b.x.values - b.x.values.mean()) / PIXEL
    source_line = np.arange(n_alines) + np.rint(u)
    f = (1 - np.abs(u - np.rint(u)))[(source_line >= 0) & (source_line < n_alines)]
    floor = th.floor.item()
    expected = (th.intensity.item() - floor) * np.mean(f**2) + floor * np.mean(f)
    # 4096 pixels: SE ~ sqrt(2)(1 - r^2)/64 ~ 0.02; the line-pooling model is approximate,
    # so allow 3 SE
    assert with_x == pytest.approx(expected, abs=0.06)
    assert without_x < with_x - 0.2


# --- fast |gamma| for the correlation strain method --------------------------------------------


@pytest.mark.parametrize(
    ("n", "shape"), [(64, "gaussian"), (256, "rectangular"), (512, "gaussian")]
)
def test_expected_gamma_equals_the_pixel_averaged_integrals(n, shape):
    """``expected_gamma`` reorganises the midpoint sums of ``expected_correlation`` (pixel
    average as triangle weights, one NUFFT for every strain): the two agree to rounding
    (absolute 1e-13 on |gamma| <= 1; the NUFFT is asked for 1e-14 relative)."""
    h = n * PIXEL
    kw = {"shape": "gaussian", "fwhm": 0.5 * n * np.pi / h} if shape == "gaussian" else {}
    src = speckle.spectrum(n, h, k0_dk=10, **kw)
    strains = np.linspace(-0.05, 0.15, 17)
    ref = corr.expected_correlation(strains, spectrum=src, density=1.0)
    got = speckle.expected_gamma(strains, spectrum=src)
    np.testing.assert_allclose(got, ref["complex"].values, rtol=0, atol=1e-13)
    np.testing.assert_allclose(
        speckle.amplitude_from_gamma(got), ref["amplitude"].values, rtol=0, atol=1e-12
    )


def test_amplitude_from_gamma_limits():
    """0 and 1 at |gamma| = 0 and 1 (a rounding excess above 1 counts as 1); for small |gamma|
    2F1(-1/2, -1/2; 1; g^2) = 1 + g^2/4 + ..., so the amplitude correlation starts as
    (pi/16)/(1 - pi/4) g^2."""
    assert speckle.amplitude_from_gamma(0.0) == pytest.approx(0.0, abs=1e-15)
    assert speckle.amplitude_from_gamma(1.0) == pytest.approx(1.0, abs=1e-15)
    assert speckle.amplitude_from_gamma(1.0 + 1e-15) == pytest.approx(1.0, abs=1e-15)
    g = 1e-3
    assert speckle.amplitude_from_gamma(g) == pytest.approx(
        np.pi / (16 - 4 * np.pi) * g**2, rel=1e-6
    )
    with pytest.raises(ValueError, match="strain"):
        speckle.expected_gamma(1.0, spectrum=speckle.spectrum(N, H, k0_dk=1))
    with pytest.raises(ValueError, match="oversample"):
        speckle.expected_gamma(0.1, spectrum=speckle.spectrum(N, H, k0_dk=1), oversample=1)
