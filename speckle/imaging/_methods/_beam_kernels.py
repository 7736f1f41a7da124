"""The numba kernels of :mod:`speckle.imaging._methods.beam_nufft` (private): bucketing and sorting
the scene by line, the lines' exact Gaussian weights (re-anchored every :data:`_ANCHOR` lines) and
the spreading of every scatterer's beam weights onto the fine grid."""

from __future__ import annotations

import cmath
import math

import numba
import numpy as np

from ._kernels import (
    LANES,
    axpy8,
    bucket_sort,
    carrier_and_position,
    es_kernel_values,
    fold_padded,
)

#: Gaussian weights are re-anchored by a direct exponential every this many lines.
_ANCHOR = 16


@numba.njit(cache=True)
def _bucket(x, y, z, j, three_d, o_ax, xo, po, r_o, n_outer, halo, yo, pi_, r_i, n_inner, bli,
            depth_range, nbi):  # fmt: skip
    """Bucket of scatterer ``j`` (see :func:`_sort_scene`), or -1 beyond the reach of the grid."""
    so = ((x[j] if o_ax == 0 else y[j]) - xo) / po
    if so < -r_o or so > n_outer - 1 + r_o:
        return -1
    ko = min(max(np.int64(math.floor(so)) + halo, 0), n_outer + 2 * halo - 1)
    if three_d:
        si = ((y[j] if o_ax == 0 else x[j]) - yo) / pi_
        if si < -r_i or si > n_inner - 1 + r_i:
            return -1
        ki = min(max(np.int64(math.floor(si)) + bli, 0), nbi - 1)
    else:
        f = z[j] / depth_range
        ki = min(max(np.int64((f - math.floor(f)) * nbi), 0), nbi - 1)
    return ko * nbi + ki


@numba.njit(parallel=True, cache=True)
def _scene_keys(x, y, z, three_d, o_ax, xo, po, r_o, n_outer, halo, yo, pi_, r_i, n_inner, bli,
                depth_range, nbi):  # fmt: skip
    """:func:`_bucket` of every scatterer (-1 beyond the reach of the grid)."""
    m = z.size
    key = np.empty(m, dtype=np.int64)
    for j in numba.prange(m):
        key[j] = _bucket(x, y, z, j, three_d, o_ax, xo, po, r_o, n_outer, halo, yo, pi_, r_i,
                         n_inner, bli, depth_range, nbi)  # fmt: skip
    return key


@numba.njit(parallel=True, cache=True)
def _scatter_scene(dest, total, x, y, z, a, gam, three_d, o_ax, xo, po, yo, pi_):
    """``(z, a, so, si, gam)`` of the ``total`` scatterers kept by the sort, scatterer ``j`` at
    slot ``dest[j]`` (``si``/``gam`` of size 1 when not per scatterer), lateral coordinates in
    pitches; the input is streamed in order."""
    zs = np.empty(total)
    as_ = np.empty(total, dtype=np.complex128)
    sos = np.empty(total)
    sis = np.empty(total if three_d else 1)
    gams = np.empty(total if gam.size > 1 else 1, dtype=np.complex128)
    if gam.size == 1:
        gams[0] = gam[0]
    for j in numba.prange(z.size):
        t = dest[j]
        if t < 0:
            continue
        zs[t] = z[j]
        as_[t] = a[j]
        sos[t] = ((x[j] if o_ax == 0 else y[j]) - xo) / po
        if three_d:
            sis[t] = ((y[j] if o_ax == 0 else x[j]) - yo) / pi_
        if gam.size > 1:
            gams[t] = gam[j]
    return zs, as_, sos, sis, gams


def _sort_scene(
    x, y, z, a, gam, three_d, o_ax, xo, po, r_o, n_outer, halo, yo, pi_, r_i, n_inner, bli,
    depth_range, nbi,
):  # fmt: skip
    """Scatterers within reach of the grid, in bucket order, by a stable counting sort.

    Lateral coordinates in pitches ``so = (x - X_0)/p`` along the outer axis (and ``si`` along
    the inner one in 3-D, ``y`` of size 1 in 2-D); bucket ``(floor(so) + halo) * nbi + sub``
    with ``sub`` the inner-axis bucket (3-D) or one of ``nbi`` depth bins (2-D, cache
    locality). :func:`speckle.imaging._methods._kernels.bucket_sort`: the order within a bucket is
    the input order whatever the number of threads. Returns ``(z, a, so, si, gam, starts)``
    sorted (``si``/``gam`` of size 1 when not per scatterer).
    """
    key = _scene_keys(x, y, z, three_d, o_ax, xo, po, r_o, n_outer, halo, yo, pi_, r_i,
                      n_inner, bli, depth_range, nbi)  # fmt: skip
    nb = (n_outer + 2 * halo) * nbi
    starts, dest = bucket_sort(key, nb)
    scene = _scatter_scene(dest, starts[nb], x, y, z, a, gam, three_d, o_ax, xo, po, yo, pi_)
    return (*scene, starts)


@numba.njit(cache=True, fastmath=False)
def _gauss(s, b, lo, hi, out):
    """``out[k] = exp(-b (s - lo - k)^2)`` for ``k = 0 ... hi - lo`` (complex ``b``).

    Two exponentials per run of :data:`_ANCHOR` lines: ``g(d - 1) = g(d) exp(b (2d - 1))`` and
    the ratio itself steps by ``exp(-2b)``. A very narrow beam (``Re b > 50``: at most two lines
    within reach) uses one exponential per line, since the ratio would overflow.
    """
    n = hi - lo + 1
    step = cmath.exp(-2.0 * b)
    k = 0
    while k < n:
        d = s - (lo + k)
        g = cmath.exp(-b * d * d)
        out[k] = g
        if b.real > 50.0:
            k += 1
            continue
        ratio = cmath.exp(b * (2.0 * d - 1.0))
        stop = min(n, k + _ANCHOR)
        for kk in range(k + 1, stop):
            g *= ratio
            ratio *= step
            out[kk] = g
        k = stop


@numba.njit(fastmath=True, cache=True)
def _line_weights(c, s, b, lo, hi, focused, wr, wi):
    """``wr + i wi = c exp(-b (s - o)^2)`` for lines ``o = lo ... hi`` (index ``o - lo``).

    Recurrence ``g(o + 1) = g(o) r(o)``, ``r(o + 1) = r(o) exp(-2b)`` with
    ``r(o) = exp(b (2 (s - o) - 1))``, re-anchored by direct exponentials every
    :data:`_ANCHOR` lines (every line when ``Re b > 50``: a beam so narrow that ``r`` could
    overflow, at most two lines within reach). Real arithmetic without focus (``focused``
    False: ``b`` real).
    """
    every = 1 if b.real > 50.0 else _ANCHOR
    if focused:
        step = cmath.exp(-2.0 * b)
        k = 0
        while k <= hi - lo:
            d = s - (lo + k)
            gw = c * cmath.exp(-b * d * d)
            rt = cmath.exp(b * (2.0 * d - 1.0))
            for kk in range(k, min(hi - lo + 1, k + every)):
                wr[kk] = gw.real
                wi[kk] = gw.imag
                gw *= rt
                rt *= step
            k += every
    else:
        br = b.real
        step = math.exp(-2.0 * br)
        k = 0
        while k <= hi - lo:
            d = s - (lo + k)
            gw = math.exp(-br * d * d)
            rt = math.exp(br * (2.0 * d - 1.0))
            for kk in range(k, min(hi - lo + 1, k + every)):
                wr[kk] = c.real * gw
                wi[kk] = c.imag * gw
                gw *= rt
                rt *= step
            k += every


@numba.njit(parallel=True, fastmath=True, cache=True)
def _spread_beam(
    z, a, k0, depth_range, so, si, gam, bo_scale, bi_scale, ln_cut, starts, nbi, n_outer, n_inner,
    inner, block, halo, kmax_i, nf, w, coef, out,
):  # fmt: skip
    """Spread every scatterer into the fine grids of the lines within its reach.

    Scatterers come sorted by bucket ``(floor(so) + halo) * nbi + sub-bucket`` with bucket
    offsets ``starts``, as carriers ``cr + i ci`` and fine-grid depths ``u``; ``out``
    (n_outer * n_inner, 2 nf) in ``coef.dtype``, interleaved re/im. Block ``[r0, r1)`` of outer
    lines reads the contiguous scatterers of buckets ``r0 ... r1 - 1 + 2 halo`` and writes its
    own lines only, into planar (real, imaginary) padded grids so that each line update is two
    contiguous ``w``-long axpys. Per scatterer: ES kernel values by Horner (vectorised over the
    ``w`` slots), then the Gaussian weights of its lines by the recurrence
    ``g(o + 1) = g(o) r(o)``, ``r(o + 1) = r(o) exp(-2b)`` (re-anchored every :data:`_ANCHOR`
    lines, every line for a very narrow beam).
    """
    half = 0.5 * w
    wp = LANES * ((w + LANES - 1) // LANES)  # kernel padded with zeros to whole vectors
    pad = wp
    plane = nf + 2 * pad
    nblocks = (n_outer + block - 1) // block
    nbo = (starts.size - 1) // nbi
    per = gam.size > 1
    # complex weights with focus: gam is per scatterer, or the one scatterer's (never ones(1)
    # then unless it sits at the focus, where gamma = 1 is real)
    focused = per or gam[0].imag != 0.0
    kmax_o = 2 * halo + 2
    for blk in numba.prange(nblocks):
        r0 = blk * block
        r1 = min(n_outer, r0 + block)
        k_hi = min(nbo - 1, r1 - 1 + 2 * halo)
        j0 = starts[r0 * nbi]
        j1 = starts[(k_hi + 1) * nbi]
        m = j1 - j0
        g = np.zeros((r1 - r0) * n_inner * 2 * plane, dtype=coef.dtype)
        cr = np.empty(m)
        ci = np.empty(m)
        u = np.empty(m)
        carrier_and_position(z[j0:j1], a[j0:j1], k0, depth_range, nf, cr, ci, u)
        # ES kernel values of every scatterer of the block, Horner vectorised over scatterers
        xk = np.empty(m)
        for t in range(m):
            x0 = u[t] - half
            xk[t] = 2.0 * (math.ceil(x0) - x0) - 1.0
        ker = np.empty((w, m), dtype=coef.dtype)
        es_kernel_values(xk, coef, ker)
        gi = np.ones(kmax_i, dtype=np.complex128)
        kv = np.zeros(wp, dtype=coef.dtype)
        wr = np.empty(kmax_o, dtype=coef.dtype)
        wi = np.empty(kmax_o, dtype=coef.dtype)
        for t in range(m):
            tt = j0 + t
            if cr[t] == 0.0 and ci[t] == 0.0:
                continue
            gm = gam[tt] if per else gam[0]
            bo = gm * bo_scale
            ro = math.sqrt(ln_cut / bo.real)
            s_o = so[tt]
            lo = max(r0, np.int64(math.ceil(s_o - ro)))
            hi = min(r1 - 1, np.int64(math.floor(s_o + ro)))
            if lo > hi:
                continue
            ilo = 0
            ihi = 0
            if inner:
                bi = gm * bi_scale
                ri = math.sqrt(ln_cut / bi.real)
                s_i = si[tt]
                ilo = max(0, np.int64(math.ceil(s_i - ri)))
                ihi = min(n_inner - 1, np.int64(math.floor(s_i + ri)))
                if ilo > ihi:
                    continue
                _gauss(s_i, bi, ilo, ihi, gi)
            _line_weights(complex(cr[t], ci[t]) * gm * gm, s_o, bo, lo, hi, focused, wr, wi)
            for i in range(w):
                kv[i] = ker[i, t]
            st = np.int64(math.ceil(u[t] - half)) + pad
            for o in range(lo, hi + 1):
                rbase = (o - r0) * n_inner
                vr = wr[o - lo]
                vi = wi[o - lo]
                for ii in range(ilo, ihi + 1):
                    if inner:
                        v = complex(vr, vi) * gi[ii - ilo]
                        wr[kmax_o - 1] = v.real  # cast to the working precision on store
                        wi[kmax_o - 1] = v.imag
                        vr2 = wr[kmax_o - 1]
                        vi2 = wi[kmax_o - 1]
                    else:
                        vr2 = vr
                        vi2 = vi
                    re = (rbase + ii) * 2 * plane + st
                    im = re + plane
                    for i0 in range(0, wp, LANES):
                        k0_, k1_, k2_, k3_ = kv[i0], kv[i0 + 1], kv[i0 + 2], kv[i0 + 3]
                        k4_, k5_, k6_, k7_ = kv[i0 + 4], kv[i0 + 5], kv[i0 + 6], kv[i0 + 7]
                        axpy8(g, np.uint64(re + i0), vr2, k0_, k1_, k2_, k3_, k4_, k5_, k6_, k7_)
                        axpy8(g, np.uint64(im + i0), vi2, k0_, k1_, k2_, k3_, k4_, k5_, k6_, k7_)
        # fold each padded line back onto its periodic fine grid, interleaving re/im
        for rr in range((r1 - r0) * n_inner):
            re = rr * 2 * plane
            fold_padded(g[re : re + plane], g[re + plane : re + 2 * plane], nf, pad,
                        out[r0 * n_inner + rr])  # fmt: skip
