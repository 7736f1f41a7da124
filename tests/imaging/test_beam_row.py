"""The row path of the scanned beam (:mod:`speckle.imaging._methods.beam_row`) against exact
references.

A row (or raster) of lines without focus takes the row path of ``beam_scan(method="nufft")``;
``path="row"`` forces it and ``path="general"`` runs the general code of
:mod:`speckle.imaging._methods.beam_nufft` on the same scene. References: the direct sum
(:func:`speckle.imaging._methods.direct.beam_direct_method`, exact in float64) and closed forms.
Relative error throughout: ``||A - A_ref||_2 / ||A_ref||_2`` over all lines and pixels.
"""

from __future__ import annotations

import numpy as np
import pytest

import speckle

# private: the beam methods and their exact reference, called directly
from speckle.imaging._methods.beam_nufft import beam_nufft_method, line_grid, uses_row_path

# private: the beam methods and their exact reference, called directly
from speckle.imaging._methods.direct import beam_direct_method
from speckle.imaging.beam import beam_problem
from speckle.imaging.methods import BEAM_METHODS

N, H = 32, 256.0  # pixels, depth_range (µm): 8 µm pixels
K0 = 10 * N * np.pi / H  # k0/delta_k = 10


def rel_err(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref)


def spectral_coefficients(z, x, a, lines, w0):
    """``F_n(i) = sum_j a_j exp(-2 (x_j - X_i)^2/w0^2) exp(2i k_n z_j)`` (rectangular S = 1):
    line ``i`` is ``A(i, q) = sum_n F_n(i) exp(-2i pi n q/N)``, so by Parseval
    ``sum_q |A(i, q)|^2 = N sum_n |F_n(i)|^2``."""
    k = K0 + (np.arange(N) - N // 2) * np.pi / H
    w = np.exp(-2 * (np.asarray(x)[None, :] - np.asarray(lines)[:, None]) ** 2 / w0**2)
    return (w * a) @ np.exp(2j * np.outer(z, k))


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
@pytest.mark.parametrize("waist_pitch", [0.5, 2.0])
def test_one_scatterer_on_a_line_is_a_depth_delta_times_the_gaussian_profile(waist_pitch, tol):
    """A scatterer ``a`` at a pixel centre ``z = q0 H/N`` on line ``X_i0``: with S = 1 the sum
    over ``n`` of ``exp(2i pi n (q0 - q)/N)`` is ``N delta(q, q0)``, so line ``i`` is
    ``N a exp(2i k0 z) exp(-2 (X_i0 - X_i)^2/w0^2)`` at ``q0`` and 0 elsewhere: the amplitude
    (not the intensity) follows the double-pass weight ``exp(-2 dx^2/w0^2)``."""
    pitch = 3.0
    w0 = waist_pitch * pitch
    lines = np.arange(11) * pitch - 6.0
    q0, a0 = 11, 0.7 - 0.2j
    z0, x0 = q0 * H / N, lines[5]
    sc, beam, _ = beam_problem([z0], [x0], [a0], lines=lines, waist=w0, n_pixels=N,
                               depth_range=H, k0=K0)  # fmt: skip
    expected = np.zeros((lines.size, N), dtype=complex)
    expected[:, q0] = N * a0 * np.exp(2j * K0 * z0) * np.exp(-2 * (x0 - lines) ** 2 / w0**2)
    assert uses_row_path(beam, line_grid(sc.lines, w0), tol / 2)
    row = beam_nufft_method(sc, beam, tol, path="row")
    assert rel_err(row, expected) <= tol
    # the direct sum: exact up to the rounding of the carrier phase 2 k_n z (~1e-13 here)
    np.testing.assert_allclose(beam_direct_method(sc, beam, None), expected, rtol=0, atol=1e-10)


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
def test_parseval_over_depth_for_a_row_of_lines(tol):
    """``sum_q |A(i, q)|^2 = N sum_n |F_n(i)|^2`` line by line. For a result within relative
    error ``e`` of the exact field (whose energy Parseval gives), the total energy differs by at
    most ``e (2 + e)`` relatively; the direct sum meets it to rounding."""
    rng = np.random.default_rng(3)
    pitch, w0, m = 2.0, 5.0, 400
    lines = np.arange(16) * pitch
    x = rng.uniform(lines[0] - 4 * w0, lines[-1] + 4 * w0, m)
    z = rng.uniform(-H, 2 * H, m)  # wrap-around on both sides
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    energy = N * np.sum(np.abs(spectral_coefficients(z, x, a, lines, w0)) ** 2, axis=1)
    sc, beam, _ = beam_problem(z, x, a, lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0)
    direct = beam_direct_method(sc, beam, None)
    np.testing.assert_allclose(np.sum(np.abs(direct) ** 2, axis=1), energy, rtol=1e-11)
    row = beam_nufft_method(sc, beam, tol, path="row")
    e = rel_err(row, direct)
    assert e <= tol
    assert abs(np.sum(np.abs(row) ** 2) - energy.sum()) <= e * (2 + e) * energy.sum() * (1 + 1e-9)


def test_row_path_equals_the_general_path_and_the_direct_sum():
    """The same scene on both paths of ``method="nufft"``: each within ``tol`` of the direct
    sum, hence within ``2 tol`` of each other; ``path="row"`` is what ``auto`` takes here."""
    rng = np.random.default_rng(8)
    tol, pitch, w0, m = 1e-8, 3.0, 4.0, 600
    lines = np.arange(12) * pitch
    x = rng.uniform(-3 * w0, lines[-1] + 3 * w0, m)
    z = rng.uniform(0, H, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    sc, beam, _ = beam_problem(z, x, a, lines=lines, waist=w0, n_pixels=N, depth_range=H, k0=K0)
    ref = beam_direct_method(sc, beam, None)
    row = beam_nufft_method(sc, beam, tol, path="row")
    general = beam_nufft_method(sc, beam, tol, path="general")
    assert rel_err(row, ref) <= tol and rel_err(general, ref) <= tol
    assert rel_err(row, general) <= 2 * tol
    np.testing.assert_array_equal(beam_nufft_method(sc, beam, tol), row)


def test_path_row_is_refused_where_the_row_path_does_not_apply():
    sc, beam, _ = beam_problem([10.0], [0.0], [1.0], lines=np.arange(4) * 3.0, waist=4.0,
                               n_pixels=N, depth_range=H, k0=K0, focus=100.0)  # fmt: skip
    with pytest.raises(ValueError, match="path='row' needs a beam without focus"):
        beam_nufft_method(sc, beam, 1e-6, path="row")
    with pytest.raises(ValueError, match="path must be one of"):
        beam_nufft_method(sc, beam, 1e-6, path="rows")


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
