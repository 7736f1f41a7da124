"""The compiled Nelder-Mead of the boundaries' joint search (issue 34) against scipy's."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

# private: the joint search and its kernel have no public entry (fit_phantom runs them)
from speckle.studies.phantom import _shape_kernels, _shapes


def reference(rss, taus, basis, start, steps, maxfun=None):
    """``_shapes._joint`` as it was (numpy objective, scipy's Nelder-Mead): ``(theta, fun,
    nfev)``."""
    finite = np.isfinite(rss)
    big = 10 * float(np.max(rss[finite]))
    table = np.where(finite, rss, big)
    step, last, rows = taus[1] - taus[0], taus.size - 1, np.arange(table.shape[0])
    padded = np.pad(table, ((0, 0), (0, 1)), constant_values=big)
    scale = np.asarray(steps[: len(start)], float)
    shift = (basis[:, : len(start)] * scale) / step
    origin = taus[0] / step
    flat, first = padded.ravel(), rows * padded.shape[1]

    def total(phi):
        u = shift @ phi - origin
        if u.min() < 0 or u.max() > last:
            out = (u < 0) | (u > last)
            i = np.clip(np.floor(u), 0, last).astype(int)
            f = np.clip(u - i, 0.0, 1.0)
            v = (1 - f) * padded[rows, i] + f * padded[rows, i + 1]
            return float(np.sum(np.where(out, big, v)))
        i = u.astype(int)
        f = u - i
        j = i + first
        return float(((1 - f) * flat[j] + f * flat[j + 1]).sum())

    phi0 = np.asarray(start, float) / scale
    options = {"initial_simplex": np.vstack([phi0, phi0 + np.eye(phi0.size)]),
               "xatol": _shapes._XATOL, "fatol": np.inf}  # fmt: skip
    if maxfun is not None:
        options["maxfev"] = maxfun
    res = optimize.minimize(total, phi0, method="Nelder-Mead", options=options)
    return res.x * scale, float(res.fun), res.nfev, (shift, origin, flat, first, last, big)


def problem(seed, blocks=16):
    """Random blocks' misfit tables on a quarter-pixel grid: a noisy bowl about a curved
    boundary per block, inf outside each block's own window, as ``_boundary_shape`` sees them."""
    rng = np.random.default_rng(seed)
    p, x_max = 2.0, 1000.0
    taus = np.arange(100.0, 160.0, p / 4)
    xb = np.sort(rng.uniform(-x_max / 2, x_max / 2, blocks))
    basis = np.column_stack([np.ones_like(xb), xb, xb**2 - x_max**2 / 12])
    truth = basis @ [130.0, rng.normal(0, 0.01), rng.normal(0, 2e-5)]
    rss = rng.uniform(0.5, 2.0, (blocks, 1)) * (taus - truth[:, None]) ** 2 / 10
    rss += rng.exponential(0.5, rss.shape)  # kinks and local minima
    rss[:, : rng.integers(0, 10)] = np.inf  # windows that start late or end early
    rss[rng.integers(0, blocks), -rng.integers(1, 20) :] = np.inf
    rss[rng.integers(0, blocks), :] = np.inf  # a block with no window
    steps = np.array([p, p / (x_max / 2), p / (x_max / 2) ** 2])
    return rss, taus, basis, steps, truth


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("d", [1, 2, 3])
def test_joint_search_matches_scipy(seed, d):
    rss, taus, basis, steps, truth = problem(seed)
    starts = ([125.0, 0.0, 0.0], [truth.mean() + 1.3, 0.002, -1e-5], [101.0, 0.05, 0.0])
    for start in starts:  # the last one starts with blocks off the grid
        want, want_fun, _, _ = reference(rss, taus, basis, start[:d], steps)
        got, got_fun = _shapes._joint(rss, taus, basis, start[:d], steps)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
        assert got_fun == pytest.approx(want_fun, rel=1e-13)


@pytest.mark.parametrize("maxfun", range(4, 80))
def test_evaluation_limit_as_scipy(maxfun):
    """Stopped by the evaluation limit (after each of its first 80 evaluations, some within a
    step), it returns scipy's vertex and counts scipy's evaluations."""
    rss, taus, basis, steps, _ = problem(11)
    start = [126.0, 0.004, 1e-5]
    want, want_fun, nfev, args = reference(rss, taus, basis, start, steps, maxfun)
    phi0 = np.asarray(start) / steps
    simplex = np.vstack([phi0, phi0 + np.eye(3)])
    table = _shape_kernels.argsort_table(4)
    phi, fun, calls = _shape_kernels.nelder_mead(*args, simplex, _shapes._XATOL, np.inf, 600,
                                                 maxfun, table)  # fmt: skip
    assert calls == nfev
    np.testing.assert_allclose(phi * steps, want, rtol=1e-12)
    assert fun == pytest.approx(want_fun, rel=1e-13)


@pytest.mark.parametrize("n", [2, 3, 4])
def test_tie_order_is_numpys(n):
    """Ties of the simplex's values are ordered as ``np.argsort`` orders them (not stable on
    every machine), looked up by the values' ranks."""
    rng = np.random.default_rng(n)
    table = _shape_kernels.argsort_table(n)
    for _ in range(200):
        values = rng.integers(0, 3, n).astype(float) * 0.1
        sim = np.arange(n, dtype=float)[:, None] * np.ones(n - 1)  # row k holds k
        fsim = values.copy()
        _shape_kernels._sort(sim, fsim, table)
        np.testing.assert_array_equal(sim[:, 0], np.argsort(values))
        np.testing.assert_array_equal(fsim, values[np.argsort(values)])
