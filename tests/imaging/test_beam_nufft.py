"""The general fast beam method (:mod:`speckle.imaging._methods.beam_nufft`) against exact
references.

Focused beams and the ``path="general"`` code, the FINUFFT lateral-Fourier reference, the line
grid and ``auto``'s choice. References: the direct sum
(:func:`speckle.imaging._methods.direct.beam_direct_method`) and closed forms with the beam's own
weight
(:func:`speckle.imaging.gaussian_beam.beam_weight`). Relative error throughout:
``||A - A_ref||_2 / ||A_ref||_2`` over all lines and pixels.
"""

from __future__ import annotations

import numpy as np
import pytest

import speckle

# private: the beam methods and their exact reference, called directly
from speckle.imaging._methods.beam_nufft import beam_nufft_method, choose_beam_method, line_grid

# private: the beam methods and their exact reference, called directly
from speckle.imaging._methods.direct import beam_direct_method
from speckle.imaging.beam import beam_problem, beam_weight

N, H = 32, 256.0  # pixels, depth_range (µm): 8 µm pixels
K0 = 10 * N * np.pi / H  # k0/delta_k = 10


def rel_err(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref)


@pytest.mark.parametrize("focus", [None, 40.0])
@pytest.mark.parametrize("three_d", [False, True])
def test_one_scatterer_is_a_depth_delta_times_the_beam_weight(focus, three_d):
    """A scatterer ``a`` at a pixel centre ``z = q0 H/N`` on the beam axis of one line: with
    S = 1, line ``i`` is ``N a exp(2i k0 z) W(X - X_i, Y - Y_i, z)`` at ``q0`` and 0 elsewhere
    (``W = exp(-2 r^2/w0^2)``, or ``gamma^2 exp(-2 gamma r^2/w0^2)`` with focus), on the
    general path."""
    tol, pitch, w0, zr = 1e-8, 2.0, 3.0, 30.0
    xs = np.arange(7) * pitch
    if three_d:
        gx, gy = np.meshgrid(xs, np.arange(3) * pitch)
        lines = np.stack([gx.ravel(), gy.ravel()], 1)
        x0, y0 = xs[3], pitch
        dx, dy, y = x0 - lines[:, 0], y0 - lines[:, 1], [y0]
    else:
        lines, x0 = xs, xs[3]
        dx, dy, y = x0 - lines, 0.0, None
    q0, a0 = 9, 1.3 + 0.4j
    z0 = q0 * H / N
    optics = {} if focus is None else {"focus": focus, "rayleigh_range": zr}
    sc, beam, _ = beam_problem([z0], [x0], [a0], y=y, lines=lines, waist=w0, n_pixels=N,
                               depth_range=H, k0=K0, **optics)  # fmt: skip
    weight = beam_weight(dx, z0, waist=w0, dy=dy, **optics)
    expected = np.zeros((len(lines), N), dtype=complex)
    expected[:, q0] = N * a0 * np.exp(2j * K0 * z0) * weight
    assert rel_err(beam_nufft_method(sc, beam, tol, path="general"), expected) <= tol
    np.testing.assert_allclose(beam_direct_method(sc, beam, None), expected, rtol=0, atol=1e-10)


def test_parseval_over_depth_with_focus():
    """``sum_q |A(i, q)|^2 = N sum_n |F_n(i)|^2`` with ``F_n(i) = sum_j a_j W_ij exp(2i k_n
    z_j)`` and the focused weight; a result within relative error ``e`` of the exact field
    has its energy within ``e (2 + e)``."""
    rng = np.random.default_rng(4)
    tol, pitch, w0, m = 1e-6, 2.0, 4.0, 300
    lines = np.arange(10) * pitch
    x = rng.uniform(-3 * w0, lines[-1] + 3 * w0, m)
    z = rng.uniform(0, H, m)
    a = rng.normal(size=m) + 1j * rng.normal(size=m)
    optics = {"focus": 100.0, "rayleigh_range": 20.0}
    w = beam_weight(x[None, :] - lines[:, None], z[None, :], waist=w0, **optics)
    k = K0 + (np.arange(N) - N // 2) * np.pi / H
    energy = N * np.sum(np.abs((w * a) @ np.exp(2j * np.outer(z, k))) ** 2, axis=1)
    sc, beam, _ = beam_problem(z, x, a, lines=lines, waist=w0, n_pixels=N, depth_range=H,
                               k0=K0, **optics)  # fmt: skip
    direct = beam_direct_method(sc, beam, None)
    np.testing.assert_allclose(np.sum(np.abs(direct) ** 2, axis=1), energy, rtol=1e-11)
    fast = beam_nufft_method(sc, beam, tol)
    e = rel_err(fast, direct)
    assert e <= tol
    assert abs(np.sum(np.abs(fast) ** 2) - energy.sum()) <= e * (2 + e) * energy.sum() * (1 + 1e-9)


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


def test_finufft_threads_respect_openmp_limit(monkeypatch):
    """FINUFFT gets no more threads than OpenMP allows (``OMP_NUM_THREADS``, which Snakemake
    sets to a job's threads): asking for more prints a warning on every call."""
    import numba

    from speckle.imaging._rules import finufft_threads  # private: the package's thread rule

    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    assert finufft_threads() == 1
    for unset in ("", "0", "x"):
        monkeypatch.setenv("OMP_NUM_THREADS", unset)
        assert finufft_threads() == numba.get_num_threads()
