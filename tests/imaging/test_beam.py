"""The scanned Gaussian beam (`speckle.beam_scan`): contract, focus, 3-D lines, fast methods.

Relative error throughout: ||A - A_direct||_2 / ||A_direct||_2 over all lines and pixels.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import speckle
from speckle.imaging.beam import beam_problem, beam_weight
from speckle.imaging.beam_nufft import choose_beam_method, line_grid, uses_row_path
from speckle.imaging.methods import BEAM_METHODS

N, H = 32, 256.0  # pixels, depth (µm): 8 µm pixels
K0 = 10 * N * np.pi / H  # k0/delta_k = 10


def rel_err(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref)


def eq4_beam(z, x, a, lines, w0, n, h, k0, s, weight=None):
    """The contract written out: explicit phase matrix, explicit DFT, explicit weights."""
    idx = np.arange(n) - n // 2
    k = k0 + idx * np.pi / h
    dft = np.exp(-2j * np.pi * np.outer(idx, np.arange(n)) / n)  # (n, q)
    field = np.exp(2j * np.outer(z, k)) * s  # (M, n)
    if weight is None:
        weight = np.exp(-2 * (x[None, :] - np.asarray(lines)[:, None]) ** 2 / w0**2)
    return (weight * a) @ field @ dft


# --- the contract --------------------------------------------------------------------------


def test_direct_equals_ascan_for_one_line_through_every_scatterer():
    rng = np.random.default_rng(1)
    z = rng.uniform(-H, 2 * H, 50)
    a = rng.normal(size=50) + 1j * rng.normal(size=50)
    out = speckle.beam_scan(z, np.full(50, 3.7), a, lines=[3.7], waist=5.0, n_pixels=N,
                            depth_range=H, k0=K0)  # fmt: skip
    ref = speckle.ascan(z, a, n_pixels=N, depth_range=H, k0=K0)
    assert out.shape == (1, N) and out.dtype == np.complex128
    assert rel_err(out[0], ref) < 1e-14


def test_direct_equals_the_written_out_contract():
    rng = np.random.default_rng(2)
    m = 80
    z, x = rng.uniform(0, H, m), rng.uniform(-10, 30, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    lines = np.array([-3.0, 0.0, 4.5, 11.0, 20.0])
    s = rng.uniform(0.2, 1.0, N)
    out = speckle.beam_scan(z, x, a, lines=lines, waist=6.0, n_pixels=N, depth_range=H, k0=K0,
                            spectrum=s)  # fmt: skip
    assert rel_err(out, eq4_beam(z, x, a, lines, 6.0, N, H, K0, s)) < 1e-12


def test_focus_weight_is_the_squared_paraxial_field():
    """gamma^2 exp(-2 gamma r^2/w0^2) equals E^2 built from w(z), R(z) and the Gouy phase."""
    rng = np.random.default_rng(3)
    w0, zf, zr, k0 = 4.0, 120.0, 60.0, 2 * 60.0 / 4.0**2  # z_R = k0 w0^2/2
    dx, z = rng.uniform(-15, 15, 200), rng.uniform(0, 400, 200)
    u = (z - zf) / zr
    w = w0 * np.sqrt(1 + u**2)
    curv = np.where(u == 0, 0.0, 1.0 / ((z - zf) * (1 + 1 / u**2)))  # 1/R
    e = (w0 / w) * np.exp(-(dx**2) / w**2 + 1j * k0 * dx**2 * curv / 2 - 1j * np.arctan(u))
    got = beam_weight(dx, z, waist=w0, focus=zf, rayleigh_range=zr)
    np.testing.assert_allclose(got, e**2, rtol=1e-12, atol=1e-300)
    # the default Rayleigh range is k0 w0^2/2, and u = 0 gives the contract weight
    h = 512.0
    one = speckle.beam_scan([zf], [1.0], [1.0], lines=[0.0], waist=w0, n_pixels=64, depth_range=h,
                            k0=k0, focus=zf)  # fmt: skip
    ref = speckle.beam_scan([zf], [1.0], [1.0], lines=[0.0], waist=w0, n_pixels=64, depth_range=h,
                            k0=k0)  # fmt: skip
    assert rel_err(one, ref) < 1e-14


@pytest.mark.parametrize("three_d", [True, False])
def test_confocal_axial_response_of_a_mirror(three_d):
    """A mirror (dense regular sheet of equal scatterers, coherent sum) at depth z.

    3-D: |sum W|^2 -> |int int gamma^2 exp(-2 gamma r^2/w0^2) d^2r|^2 = (pi w0^2/2)^2/(1 + u^2),
    the confocal response; its phase is arg(gamma) = -arctan(u). 2-D (a line mirror in the
    plane through the axis): |gamma|^3 = (1 + u^2)^(-3/2). The grid step w0/4 makes the sum
    equal the integral to exp(-8 pi^2) (Poisson summation).
    """
    n, h, w0, zr = 64, 512.0, 4.0, 50.0
    zf = 200.0
    q = np.array([8, 18, 25, 28, 34, 40])  # pixels: depths q H/N = 64 ... 320 µm
    step = w0 / 4
    got, want, phase = [], [], []
    for zq in q * h / n:
        u = (zq - zf) / zr
        half = 8 * w0 * np.sqrt(1 + u**2)
        g = np.arange(-half, half + step / 2, step)
        if three_d:
            xx, yy = (v.ravel() for v in np.meshgrid(g, g))
            kw = dict(y=yy, lines=[[0.0, 0.0]])
            area = step**2
        else:
            xx, kw, area = g, dict(lines=[0.0]), step
        a = speckle.beam_scan(np.full(xx.size, zq), xx, np.full(xx.size, area), waist=w0,
                              n_pixels=n, depth_range=h, k0=1.0, focus=zf, rayleigh_range=zr,
                              **kw)[0]  # fmt: skip
        peak = a[round(zq * n / h)] / np.exp(2j * 1.0 * zq) / n  # one pixel, carrier removed
        got.append(abs(peak) ** 2)
        phase.append(np.angle(peak))
        want.append(1 / (1 + u**2) if three_d else (1 + u**2) ** -1.5)
        if three_d:
            assert np.isclose(np.angle(peak), -np.arctan(u), atol=1e-10)
    norm = (np.pi * w0**2 / 2) ** 2 if three_d else np.pi * w0**2 / 2
    np.testing.assert_allclose(np.array(got) / norm, want, rtol=1e-9)


def test_3d_lines_reduce_to_2d_and_separate():
    rng = np.random.default_rng(4)
    m = 60
    z, x, y = rng.uniform(0, H, m), rng.uniform(-5, 5, m), rng.uniform(-5, 5, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    lines = np.array([[0.0, 1.0], [2.0, -1.0], [-3.0, 0.5]])
    kw = dict(waist=3.0, n_pixels=N, depth_range=H, k0=K0)
    out = speckle.beam_scan(z, x, a, y=y, lines=lines, **kw)
    for i, (xl, yl) in enumerate(lines):
        a_y = a * np.exp(-2 * (y - yl) ** 2 / 3.0**2)  # the y factor of the weight
        ref = speckle.beam_scan(z, x, a_y, lines=[xl], **kw)[0]
        assert rel_err(out[i], ref) < 1e-13


# --- lateral correlation of a dense uniform scene ------------------------------------------


def test_lateral_correlation_of_a_dense_uniform_scene():
    """Complex correlation of lines dx apart = exp(-dx^2/w0^2); intensity: Campbell's theorem.

    Poisson scatterers (density rho per µm per pixel), complex Gaussian amplitudes
    (kappa = E|a|^4/E^2|a|^2 = 2), depths uniform over one period: with h = g(x) P(u),
    the pooled intensity correlation is (rho^2 |C|^2 + rho kappa D)/(rho^2 A^2 + rho kappa A4),
    C = int g g' int |P|^2, D = int g^2 g'^2 int |P|^4, A = int g^2 int |P|^2,
    A4 = int g^4 int |P|^4 (int g g' = w0 sqrt(pi)/2 exp(-dx^2/w0^2),
    int g^2 g'^2 = w0 sqrt(pi/8) exp(-2 dx^2/w0^2)); the first term alone is exp(-2 dx^2/w0^2).
    The error bar is the standard error over independent scenes (4 of them).
    """
    n, h, w0, pitch, n_lines, rho = 64, 512.0, 4.0, 2.0, 48, 2.0  # rho per µm per pixel
    margin = 6 * w0
    lags = np.array([1, 2, 3])
    cplx, inten = [], []
    for seed in range(4):
        rng = np.random.default_rng(100 + seed)
        span = (n_lines - 1) * pitch + 2 * margin
        m = rng.poisson(rho * span * n)
        x = rng.uniform(-margin, (n_lines - 1) * pitch + margin, m)
        z = rng.uniform(0, h, m)
        a = (rng.normal(size=m) + 1j * rng.normal(size=m)) / np.sqrt(2)
        img = speckle.beam_scan(z, x, a, lines=np.arange(n_lines) * pitch, waist=w0, n_pixels=n,
                                depth_range=h, k0=K0, method="nufft", tol=1e-10)  # fmt: skip
        i_ = np.abs(img) ** 2
        row_c, row_i = [], []
        for lag in lags:
            p, q = img[:-lag], img[lag:]
            norm = np.sqrt(np.sum(abs(p) ** 2) * np.sum(abs(q) ** 2))
            row_c.append(np.sum(p * q.conj()).real / norm)
            ip, iq = i_[:-lag] - i_[:-lag].mean(), i_[lag:] - i_[lag:].mean()
            row_i.append(np.sum(ip * iq) / np.sqrt(np.sum(ip**2) * np.sum(iq**2)))
        cplx.append(row_c)
        inten.append(row_i)
    cplx, inten = np.array(cplx), np.array(inten)
    dx = lags * pitch
    gamma = np.exp(-(dx**2) / w0**2)
    # Campbell terms (rectangular spectrum: int |P|^2 = N sum S^2 = N^2 per pixel length N,
    # int |P|^4 = N sum_m (N - |m|)^2; rho counts per µm and per pixel)
    s2 = n * n
    s4 = n * np.sum((n - np.abs(np.arange(-n + 1, n))) ** 2.0)
    kappa = 2.0
    c_ = w0 * np.sqrt(np.pi) / 2 * gamma * s2
    d_ = w0 * np.sqrt(np.pi / 8) * gamma**2 * s4
    a_ = w0 * np.sqrt(np.pi) / 2 * s2
    a4 = w0 * np.sqrt(np.pi / 8) * s4
    theory_i = (rho**2 * c_**2 + rho * kappa * d_) / (rho**2 * a_**2 + rho * kappa * a4)
    for est, theory in ((cplx, gamma), (inten, theory_i)):
        mean = est.mean(axis=0)
        se = est.std(axis=0, ddof=1) / np.sqrt(est.shape[0])
        assert np.all(np.abs(mean - theory) < 4 * se + 1e-3), (mean, theory, se)
    # the non-Gaussian (finite density) term is small here: the square of gamma within 2 %
    assert np.allclose(theory_i, gamma**2, atol=0.02)


# --- fast methods -------------------------------------------------------------------------


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**31),
    n=st.integers(8, 48),
    n_lines=st.integers(1, 16),
    n_y=st.sampled_from([0, 1, 3]),  # 0: 2-D scene; else lines on an (x, y) raster
    density=st.sampled_from([0.5, 2.0, 6.0]),
    pitch_ratio=st.floats(0.1, 1.0),  # pitch / w0
    tol=st.sampled_from([1e-3, 1e-6, 1e-9]),
    shape=st.sampled_from(["rectangular", "gaussian", "array"]),
    focus=st.sampled_from([None, 0.0, 0.4]),  # focal depth as a fraction of H
    method=st.sampled_from(["nufft", "nufft32", "auto"]),
)
def test_fast_methods_stay_within_tol(
    seed, n, n_lines, n_y, density, pitch_ratio, tol, shape, focus, method
):
    rng = np.random.default_rng(seed)
    h = 8.0 * n
    w0 = rng.uniform(2.0, 20.0)
    pitch = pitch_ratio * w0
    xs = rng.uniform(-50, 50) + np.arange(n_lines) * pitch
    ys = np.arange(max(n_y, 1)) * pitch * 0.8
    m = min(3000, max(1, round(density * n * n_lines * max(n_y, 1))))
    z = rng.uniform(-h, 2 * h, m)
    x = rng.uniform(xs[0] - 0.5 * pitch, xs[-1] + 0.5 * pitch, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    idx = np.arange(n) - n // 2
    s = {
        "rectangular": np.ones(n),
        "gaussian": np.exp(-4 * np.log(2) * (idx / (0.3 * n)) ** 2),
        "array": rng.uniform(0.0, 1.0, n),
    }[shape]
    kw = dict(waist=w0, n_pixels=n, depth_range=h, k0=10 * n * np.pi / h, spectrum=s)
    if focus is not None:
        kw.update(focus=focus * h, rayleigh_range=rng.uniform(0.05, 1.0) * h)
    if n_y:
        gx, gy = np.meshgrid(xs, ys)
        kw.update(lines=np.stack([gx.ravel(), gy.ravel()], 1)[rng.permutation(gx.size)],
                  y=rng.uniform(ys[0] - 0.5 * pitch, ys[-1] + 0.5 * pitch, m))  # fmt: skip
    else:
        kw.update(lines=rng.permutation(xs))
    ref = speckle.beam_scan(z, x, a, **kw)
    try:
        out = speckle.beam_scan(z, x, a, method=method, tol=tol, **kw)
    except ValueError as exc:  # nufft32 refuses a tol below its rounding floor
        assert method == "nufft32" and "rounding" in str(exc)
        return
    assert rel_err(out, ref) <= tol


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
@pytest.mark.parametrize(
    ("waist_pitch", "row"),
    [(0.15, False), (0.2, True), (1.0, True), (2.0, True), (6.0, True)],
)
def test_row_path_stays_within_tol_and_agrees_with_the_general_path(waist_pitch, row, tol):
    """The row path (2-D, no focus, b = 2 p^2/w0^2 <= 64) against direct, on lines with gaps
    and scatterers beyond both ends of the scan (within and beyond the beam's reach); a beam
    narrower than p/sqrt(32) takes the general path. Both paths meet tol on the same scene."""
    rng = np.random.default_rng(11)
    pitch = 3.0
    w0 = waist_pitch * pitch
    lines = np.array([0, 1, 2, 5, 6, 9, 10, 11]) * pitch + 7.0  # a grid with gaps
    reach = w0 * np.sqrt(np.log(8 / tol) / 2)
    m = 3000
    x = rng.uniform(lines[0] - reach - 2 * pitch, lines[-1] + reach + 2 * pitch, m)
    z = rng.uniform(-H, 2 * H, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    kw = dict(lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0)
    ref = speckle.beam_scan(z, x, a, **kw)
    sc, beam, _ = beam_problem(z, x, a, lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0)
    assert uses_row_path(beam, line_grid(sc.lines, w0), 0.5 * tol) is row
    fast = speckle.beam_scan(z, x, a, method="nufft", tol=tol, **kw)
    assert rel_err(fast, ref) <= tol
    if row:  # the same scene on the general path
        general = BEAM_METHODS["nufft"](sc, beam, tol, path="general")
        assert rel_err(general, ref) <= tol
        assert rel_err(fast, general) <= 2 * tol


@pytest.mark.parametrize("method", ["nufft", "nufft32"])
@pytest.mark.parametrize(("n_y", "pitch_y"), [(1, 3.0), (5, 2.0), (4, 5.0)])
def test_raster_row_path_stays_within_tol_and_agrees_with_the_general_path(n_y, pitch_y, method):
    """C-scans without focus take the row path too (outer x inner weights): against direct on
    a raster with different pitches per axis (and a single y line), scatterers beyond every
    edge; the general path on the same scene meets tol as well."""
    rng = np.random.default_rng(12)
    tol = {"nufft": 1e-6, "nufft32": 1e-5}[method]  # float32 rounding ~7e-7 on this scene
    w0, pitch_x = 6.0, 3.0
    xs, ys = np.arange(7) * pitch_x, np.arange(n_y) * pitch_y - 4.0
    gx, gy = np.meshgrid(xs, ys)
    lines = np.stack([gx.ravel(), gy.ravel()], 1)[rng.permutation(gx.size)]
    m = 4000
    x = rng.uniform(xs[0] - 4 * w0, xs[-1] + 4 * w0, m)
    y = rng.uniform(ys[0] - 4 * w0, ys[-1] + 4 * w0, m)
    z = rng.uniform(0, H, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    kw = dict(y=y, lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0)
    ref = speckle.beam_scan(z, x, a, **kw)
    sc, beam, _ = beam_problem(
        z, x, a, y=y, lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0
    )
    assert uses_row_path(beam, line_grid(sc.lines, w0), 0.25 * tol)
    fast = speckle.beam_scan(z, x, a, method=method, tol=tol, **kw)
    assert rel_err(fast, ref) <= tol
    general = BEAM_METHODS[method](sc, beam, tol, path="general")
    assert rel_err(general, ref) <= tol
    np.testing.assert_array_equal(BEAM_METHODS[method](sc, beam, tol, path="row"), fast)


def test_finufft_reference_within_tol():
    rng = np.random.default_rng(5)
    m = 4 * N * 30
    x, z = rng.uniform(-2, 60, m), rng.uniform(0, 2 * H, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    kw = dict(lines=np.arange(30) * 2.0, waist=4.0, n_pixels=N, depth_range=H, k0=K0)
    ref = speckle.beam_scan(z, x, a, **kw)
    for tol in (1e-4, 1e-8):
        assert rel_err(speckle.beam_scan(z, x, a, method="finufft", tol=tol, **kw), ref) <= tol


def test_irregular_lines_fall_back_to_direct_or_are_refused():
    rng = np.random.default_rng(6)
    z, x = rng.uniform(0, H, 100), rng.uniform(0, 10, 100)
    a = rng.normal(size=100) + 0j
    lines = np.array([0.0, 1.0, 2.5, 7.3])  # no uniform grid holds them
    kw = dict(lines=lines, waist=2.0, n_pixels=N, depth_range=H, k0=K0)
    sc, beam, _ = beam_problem(z, x, a, **kw)
    assert line_grid(sc.lines, 2.0) is None
    assert choose_beam_method(sc, beam, 1e-6) == "direct"
    np.testing.assert_array_equal(
        speckle.beam_scan(z, x, a, method="auto", tol=1e-6, **kw), speckle.beam_scan(z, x, a, **kw)
    )
    with pytest.raises(ValueError, match="uniform grid"):
        speckle.beam_scan(z, x, a, method="nufft", tol=1e-6, **kw)


def test_auto_picks_a_fast_method_on_a_large_scan_and_direct_on_a_tiny_one():
    rng = np.random.default_rng(7)
    m = 4 * 512 * 512
    x, z = rng.uniform(0, 511, m), rng.uniform(0, 4096, m)
    lines = np.arange(512.0)
    big = beam_problem(z, x, np.ones(m), lines=lines, waist=2.0, n_pixels=512, depth_range=4096.0,
                       k0=3.9, tol=1e-6)  # fmt: skip
    assert choose_beam_method(*big) in ("nufft", "nufft32")
    tiny = beam_problem(z[:3], x[:3], np.ones(3), lines=[0.0], waist=2.0, n_pixels=16,
                        depth_range=128.0, k0=3.9, tol=1e-6)  # fmt: skip
    assert choose_beam_method(*tiny) == "direct"


# --- bad input ----------------------------------------------------------------------------


GOOD = dict(lines=[0.0, 1.0], waist=2.0, n_pixels=N, depth_range=H, k0=K0)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (dict(waist=-1.0), "waist"),
        (dict(waist=0.0), "waist"),
        (dict(lines=[[0.0, 1.0]]), "lines must be 1-D"),
        (dict(lines=[]), "at least one"),
        (dict(lines=[0.0, np.nan]), "lines"),
        (dict(x=[0.0, np.nan]), "x"),
        (dict(z=[0.0]), "same shape"),
        (dict(y=[0.0, 1.0]), r"\(L, 2\)"),
        (dict(y=[0.0, 1.0], lines=[[0.0, 1.0, 2.0]]), r"\(L, 2\)"),
        (dict(focus=H), "focus"),
        (dict(focus=-1.0), "focus"),
        (dict(focus=10.0, k0=0.0), "k0 > 0"),
        (dict(rayleigh_range=5.0), "needs focus"),
        (dict(focus=10.0, rayleigh_range=0.0), "rayleigh_range"),
        (dict(method="fast"), "method"),
        (dict(method="finufft", tol=1e-6, focus=10.0), "without focus"),
        (dict(tol=0.0), "tol"),
        (dict(n_pixels=1), "n_pixels"),
    ],
)
def test_bad_input_is_refused(change, match):
    args = dict(z=[1.0, 2.0], x=[0.0, 0.5], amplitude=[1.0, 1.0], **GOOD)
    args.update(change)
    with pytest.raises(ValueError, match=match):
        speckle.beam_scan(args.pop("z"), args.pop("x"), args.pop("amplitude"), **args)


def test_empty_scene_images_to_zeros():
    out = speckle.beam_scan([], [], [], **GOOD)
    assert out.shape == (2, N) and not out.any()


@pytest.mark.parametrize("raster", [False, True])
def test_fast_result_does_not_depend_on_the_thread_count(raster):
    numba = pytest.importorskip("numba")
    rng = np.random.default_rng(8)
    n, n_lines = 64, 128
    m = 4 * n * n_lines  # above the serial threshold: blocks of lines run in parallel
    x, z = rng.uniform(0, 4.0 * n_lines, m), rng.uniform(0, 8.0 * n, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    kw = dict(lines=np.arange(n_lines) * 4.0, waist=8.0, n_pixels=n, depth_range=8.0 * n,
              k0=10 * np.pi / 8, method="nufft", tol=1e-6)  # fmt: skip
    if raster:  # 32 x 4 lines of a C-scan
        gx, gy = np.meshgrid(np.arange(32) * 4.0, np.arange(4) * 4.0)
        kw.update(lines=np.stack([gx.ravel(), gy.ravel()], 1), y=rng.uniform(-8, 20, m))
        x = rng.uniform(-8, 132, m)
    threads = numba.get_num_threads()
    many = speckle.beam_scan(z, x, a, **kw)
    try:
        numba.set_num_threads(1)
        one = speckle.beam_scan(z, x, a, **kw)
    finally:
        numba.set_num_threads(threads)
    np.testing.assert_array_equal(one, many)
