"""The numba kernels of :mod:`speckle.studies.phantom._shapes` (private): its joint search.

:func:`nelder_mead` minimises the blocks' summed misfit ``sum_b rss_b(shift_b . phi - origin)``,
each block's misfit a table on a grid of trial positions (``u`` in grid steps), linear between
them (:func:`_total`), by Nelder-Mead compiled with its objective: the steps of scipy's
``_minimize_neldermead`` (scipy 1.17, non-adaptive) one for one, so that it ends where scipy
ends, on the same vertex, up to round-off:

- reflection, expansion, contraction outside and inside and shrink with ``rho = 1``,
  ``chi = 2``, ``psi = 0.5``, ``sigma = 0.5`` and scipy's expressions (no fused
  multiply-adds: numba compiles without ``fastmath``);
- from the given initial simplex; stop when ``max |sim[1:] - sim[0]| <= xatol`` and
  ``max |fsim[0] - fsim[1:]| <= fatol``, or after ``maxfun`` evaluations or ``maxiter``
  iterations (scipy counts from 1), an evaluation past ``maxfun`` dropped as scipy's wrapper
  drops it (a shrink's vertex moved but not evaluated keeps its old value);
- the simplex sorted by ``np.argsort`` of its values (twice at the start, as scipy does). NumPy's
  default sort is not stable (on AVX-512 a sorting network orders ties of 4 values its own way),
  so the order of ties is ``np.argsort``'s own, tabulated once per simplex size from every
  pattern of ranks (:func:`argsort_table`) and looked up by the values' ranks.

The objective repeats ``_shapes._joint``'s numpy expressions in their order of rounding:
``shift @ phi`` by the same BLAS ``dgemv`` (numba's ``np.dot``), the blocks' sum by NumPy's
pairwise summation (8 accumulators, :func:`_pairwise_sum`).
"""

from __future__ import annotations

import functools
import itertools

import numba
import numpy as np

__all__ = ["argsort_table", "nelder_mead"]


@functools.lru_cache(maxsize=8)
def argsort_table(n: int) -> np.ndarray:
    """``np.argsort`` of every pattern of ranks of ``n`` values (row ``sum_k r_k n^k`` for ranks
    ``r``, each ``0 ... n - 1``): the order, ties included, that NumPy's default sort gives."""
    patterns = np.array(list(itertools.product(range(n), repeat=n)), float)[:, ::-1]
    return np.array([np.argsort(row) for row in patterns], np.int64)


@numba.njit(cache=True)
def _pairwise_sum(a):
    """``a.sum()`` in NumPy's order: 8 accumulators, combined pairwise, then the tail."""
    n = a.size
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
    r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
    i = 8
    while i < n - n % 8:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res


@numba.njit(cache=True)
def _total(phi, shift, origin, flat, first, last, big, work):
    """The blocks' misfits at ``u = shift . phi - origin`` (grid steps), linear between the
    grid's positions (``flat[first_b + i]`` block ``b``'s table padded with ``big``), ``big``
    for a block off the grid (``u < 0`` or ``u > last``); ``work`` scratch of the blocks."""
    u = np.dot(shift, phi)  # the BLAS dgemv of numpy's ``shift @ phi``
    n = u.size
    inside = True
    for b in range(n):
        u[b] = u[b] - origin
        if u[b] < 0 or u[b] > last:
            inside = False
    for b in range(n):
        if inside:
            i = int(u[b])  # u >= 0: the floor
            f = u[b] - i
        elif u[b] < 0 or u[b] > last:
            work[b] = big
            continue
        else:
            i = min(max(int(np.floor(u[b])), 0), last)
            f = min(max(u[b] - i, 0.0), 1.0)
        j = first[b] + i
        work[b] = (1 - f) * flat[j] + f * flat[j + 1]
    return _pairwise_sum(work)


@numba.njit(cache=True)
def _sort(sim, fsim, table):
    """Reorder the simplex by ``np.argsort(fsim)`` (its tie order from ``table``)."""
    m = fsim.size
    key = 0
    power = 1
    for k in range(m):
        rank = 0  # dense rank: the distinct values below fsim[k]
        for q in range(m):
            below = fsim[q] < fsim[k]
            for r in range(q):
                if fsim[r] == fsim[q]:
                    below = False  # counted once, at its first occurrence
                    break
            if below:
                rank += 1
        key += rank * power
        power *= m
    old_sim = sim.copy()
    old_f = fsim.copy()
    for k in range(m):
        q = table[key, k]
        fsim[k] = old_f[q]
        for i in range(sim.shape[1]):
            sim[k, i] = old_sim[q, i]


@numba.njit(cache=True)
def _step(out, xbar, worst, a, b):
    """``out = a xbar - b worst`` elementwise (scipy's moves, in its order of rounding)."""
    for k in range(out.size):
        out[k] = a * xbar[k] - b * worst[k]


@numba.njit(cache=True)
def nelder_mead(
    shift, origin, flat, first, last, big, simplex, xatol, fatol, maxiter, maxfun, table
):
    """Nelder-Mead from ``simplex`` (``N + 1`` rows of ``N``) on :func:`_total` (module
    docstring): the best vertex, its value and the number of evaluations."""
    sim = simplex.copy()
    n = sim.shape[1]
    m = n + 1
    work = np.empty(shift.shape[0])
    fsim = np.empty(m)
    fsim[:] = np.inf
    xbar, xr, xe, xc = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    fcalls = 0
    for k in range(m):
        if fcalls >= maxfun:
            break
        fcalls += 1
        fsim[k] = _total(sim[k].copy(), shift, origin, flat, first, last, big, work)
    _sort(sim, fsim, table)
    _sort(sim, fsim, table)
    rho, chi, psi, sigma = 1.0, 2.0, 0.5, 0.5
    iterations = 1
    while fcalls < maxfun and iterations < maxiter:
        span = 0.0
        spread = 0.0
        for j in range(1, m):
            for k in range(n):
                span = max(span, abs(sim[j, k] - sim[0, k]))
            d = abs(fsim[0] - fsim[j])
            if d != d or spread != spread:  # np.max: a NaN is the maximum
                spread = np.nan
            else:
                spread = max(spread, d)
        if span <= xatol and spread <= fatol:
            break
        for k in range(n):  # np.add.reduce(sim[:-1], 0) / N: row by row
            acc = sim[0, k]
            for j in range(1, n):
                acc += sim[j, k]
            xbar[k] = acc / n
        worst = sim[n]
        _step(xr, xbar, worst, 1 + rho, rho)
        if fcalls >= maxfun:
            _sort(sim, fsim, table)
            continue
        fcalls += 1
        fxr = _total(xr, shift, origin, flat, first, last, big, work)
        if fxr < fsim[0]:
            _step(xe, xbar, worst, 1 + rho * chi, rho * chi)
            if fcalls >= maxfun:
                _sort(sim, fsim, table)
                continue
            fcalls += 1
            fxe = _total(xe, shift, origin, flat, first, last, big, work)
            if fxe < fxr:
                sim[n] = xe
                fsim[n] = fxe
            else:
                sim[n] = xr
                fsim[n] = fxr
        elif fxr < fsim[n - 1]:
            sim[n] = xr
            fsim[n] = fxr
        else:
            doshrink = False
            if fxr < fsim[n]:  # contraction outside
                _step(xc, xbar, worst, 1 + psi * rho, psi * rho)
                if fcalls >= maxfun:
                    _sort(sim, fsim, table)
                    continue
                fcalls += 1
                fxc = _total(xc, shift, origin, flat, first, last, big, work)
                if fxc <= fxr:
                    sim[n] = xc
                    fsim[n] = fxc
                else:
                    doshrink = True
            else:  # contraction inside: (1 - psi) xbar + psi worst
                for k in range(n):
                    xc[k] = (1 - psi) * xbar[k] + psi * worst[k]
                if fcalls >= maxfun:
                    _sort(sim, fsim, table)
                    continue
                fcalls += 1
                fxcc = _total(xc, shift, origin, flat, first, last, big, work)
                if fxcc < fsim[n]:
                    sim[n] = xc
                    fsim[n] = fxcc
                else:
                    doshrink = True
            if doshrink:
                stopped = False
                for j in range(1, m):
                    for k in range(n):
                        sim[j, k] = sim[0, k] + sigma * (sim[j, k] - sim[0, k])
                    if fcalls >= maxfun:
                        stopped = True
                        break
                    fcalls += 1
                    fsim[j] = _total(sim[j].copy(), shift, origin, flat, first, last, big, work)
                if stopped:
                    _sort(sim, fsim, table)
                    continue
        iterations += 1
        _sort(sim, fsim, table)
    best = fsim[0]  # np.min(fsim), NaN first
    for k in range(m):
        if fsim[k] != fsim[k]:
            best = fsim[k]
            break
        best = min(best, fsim[k])
    return sim[0].copy(), best, fcalls
