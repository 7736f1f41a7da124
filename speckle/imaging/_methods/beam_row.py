"""The fast path of ``"nufft"``/``"nufft32"`` for a row or raster of lines, beam without focus.

A scene scanned along a row (B-scan) or a raster (C-scan) of lines by a depth-independent beam
is the common case; every scatterer then costs the same, so the work is laid out for
throughput rather than generality (the general code, for focused beams and the rare cases
below, is :mod:`speckle.imaging._methods.beam_nufft`; both compute the same sums within ``tol``):

1. **Sort** (:func:`_sort_rows`): one stable parallel counting sort of the scatterers within
   reach of the line grid by their bucket ``floor(s)`` along each axis (``s = (x - X_0)/p``
   in pitches; outer axis first), writing records ``(Re c, Im c, u, s_o[, s_i])`` with
   ``c = a exp(2i k0 z)`` (:mod:`speckle.imaging._methods.carrier`) and ``u`` the fine-grid depth.
   The records live in a numpy-allocated buffer (huge pages: page faults cost more than the sort
   itself in a buffer allocated inside numba).
2. **Spread** (:func:`_spread_rows`): buckets in blocks of outer lines; even blocks first, then
   odd ones, in parallel, so that no two threads write the same line and the order of every
   sum is fixed (bitwise the same on any number of threads). Within a bucket the records are
   visited by depth bin (cache locality of the lines they write); per chunk of 128 scatterers
   the lateral weights are computed vectorised: with ``delta = s - floor(s)`` and
   ``b = 2 p^2/w0^2``, line ``floor(s) + m - h`` (``m = 0 ... 2h + 1``) has weight
   ``exp(-b (delta + h - m)^2)``, by fast Gaussian gridding: ``exp(-b delta^2)`` at ``m = h``
   and ratios ``exp(+-2 b delta)`` times constants to either side (three exponentials per
   scatterer and axis, each a branch-free Taylor polynomial and squarings that numba
   vectorises). A raster's weight is the product of its two axes' weights. The ES kernel's
   slot values come from Horner's scheme vectorised over the chunk, in the working precision
   (:func:`speckle.imaging._methods._kernels.es_kernel_values`), then each of its
   ``(2h_o + 2)(2h_i + 2)`` lines (``2h + 2`` for a row) gets two 8-wide axpys (real and
   imaginary planes of a padded grid).
3. **Fold** (:func:`_fold_rows`): padded planar rows back onto periodic interleaved fine grids,
   which :func:`speckle.imaging._methods.nufft.fine_to_pixels` turns into pixels.

Weights: ``h = floor(r)`` with ``r = sqrt(ln_cut/b)`` the reach (pitches) of the weight cut of
:func:`speckle.imaging._methods.beam_nufft.beam_nufft_scan`: every line within reach is written (a
few more, whose weights are below the cut, are written too). The exponentials carry a relative
error ``~ 2^nsq eps`` (``nsq = ceil(log2(8 b))`` squarings; :func:`row_weight_error`, summed
over the axes, admissible while ``<= tol/8`` of the kernel's share of the budget); a beam
narrower than ``p/sqrt(32)`` (``b > 64``) or a tol below that bound takes the general path.

Measured (``benchmarks/bench_beam.py``, same run): 512 px x 512 lines x 4 per pixel per line,
w0 = 2 pitches, tol 1e-6: 1.9x less time than the general code (1 or 2 threads); one
64 x 64-line 3-D tile (3 M scatterers, 144 lines each): 1.5x less CPU time, 2.2x less wall
time (the general code runs a 64-line tile on one thread).
"""

from __future__ import annotations

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
    sort_chunks,
)

__all__ = [
    "ROW_MAX_B",
    "row_fine_grids",
    "row_lines",
    "row_path_bytes",
    "row_weight_error",
    "weight_rate",
]

#: Largest ``b = 2 p^2/w0^2`` of the row path (``exp(2b)`` stays far from overflow).
ROW_MAX_B = 64.0
#: Scatterers per vectorised chunk of the spreading.
_CH = 128
#: Depth bins per line bucket (cache locality of the spreading).
_NBINS = 8
#: Scatterers per vectorised carrier chunk of the sort.
_SUB = 256
#: Lines per block of the spreading (at least the 2h + 2 lines a scatterer writes).
_BLOCK = 16


@numba.njit(cache=True)
def _squarings(b: float) -> int:
    """Squarings of the exponentials: ``|2 b delta| 2^-nsq <= 1/4`` for ``delta`` in [0, 1)."""
    return max(0, math.ceil(math.log2(8.0 * b)))


def weight_rate(pitch: float, waist: float) -> float:
    """``b = 2 p^2/w0^2``: the double-pass weight of a line ``d`` pitches away is
    ``exp(-b d^2)`` (pitch ``p`` and waist ``w0`` in µm)."""
    return 2.0 * pitch**2 / waist**2


def _reach(waist: float, pitch: float, ln_cut: float) -> tuple[float, float, int]:
    """``(b, reach, h)``: :func:`weight_rate`, the reach ``sqrt(ln_cut/b)`` (pitches) of the
    weight cut ``exp(-ln_cut)`` and ``h = floor(reach)``."""
    b = weight_rate(pitch, waist)
    reach = math.sqrt(ln_cut / b)
    return b, reach, math.floor(reach)


def row_lines(waist: float, pitches: tuple[float, ...], ln_cut: float) -> int:
    """Lines written per scatterer on the row path: ``2h + 2`` per axis of the line grid
    (pitches in µm; module docstring), multiplied over the axes."""
    return math.prod(2 * _reach(waist, p, ln_cut)[2] + 2 for p in pitches)


def row_path_bytes(
    size: tuple[int, ...],
    pitch: tuple[float, ...],
    waist: float,
    ln_cut: float,
    *,
    n_scatterers: int,
    nf: int,
    w: int,
    itemsize: int,
) -> dict[str, float]:
    """Peak memory (bytes) of :func:`row_fine_grids` by part: ``"grids"`` (the padded planar
    grid and the fine grids it folds into), ``"scatterers"`` (records, keys and order) and
    ``"buckets"`` (the counting sort's counts and offsets). ``size``/``pitch`` per axis of the
    line grid, ``nf`` and ``w`` of the plan, ``itemsize`` of its real type (8 or 4)."""
    hs = [_reach(waist, p, ln_cut)[2] for p in pitch]
    nb = [n + 2 * h + 1 for n, h in zip(size, hs, strict=True)]
    k_n = [2 * h + 2 for h in hs]
    if len(size) == 1:
        nb, k_n = [*nb, 1], [*k_n, 1]
    pad = LANES * -(-w // LANES)
    padded_rows = (nb[0] + k_n[0] - 1) * (nb[1] + k_n[1] - 1)
    n_chunks = max(1, min(64, n_scatterers // 16384))
    return {
        "grids": float(padded_rows * 2 * (nf + 2 * pad) + math.prod(size) * 2 * nf) * itemsize,
        "scatterers": float(n_scatterers) * (8 * (len(size) + 3) + 16),
        "buckets": 16.0 * n_chunks * nb[0] * nb[1],
    }


def row_weight_error(pitch: float, waist: float) -> float:
    """Bound on the relative error of the row path's lateral weights (``2^nsq`` x 8 eps)."""
    return 2.0 ** _squarings(weight_rate(pitch, waist)) * 8.0 * float(np.finfo(np.float64).eps)


@numba.njit(fastmath=True, inline="always")
def _exp_poly(y):
    """Taylor polynomial of ``exp(y)`` to degree 12 (``|y| <= 1/4``: truncation < 3e-18)."""
    p = 1.0 / 479001600.0
    p = p * y + 1.0 / 39916800.0
    p = p * y + 1.0 / 3628800.0
    p = p * y + 1.0 / 362880.0
    p = p * y + 1.0 / 40320.0
    p = p * y + 1.0 / 5040.0
    p = p * y + 1.0 / 720.0
    p = p * y + 1.0 / 120.0
    p = p * y + 1.0 / 24.0
    p = p * y + 1.0 / 6.0
    p = p * y + 0.5
    p = p * y + 1.0
    return p * y + 1.0


@numba.njit(fastmath=True, inline="always")
def _exp_into(out, factor, d, square, n, scale, nsq):
    """``out[t] = exp(factor * (d[t]^2 if square else d[t]))`` for ``t < n``, vectorised:
    the polynomial at ``scale = 2^-nsq`` of the argument, then ``nsq`` squarings."""
    if square:
        for t in range(n):
            out[t] = _exp_poly(factor * scale * d[t] * d[t])
    else:
        for t in range(n):
            out[t] = _exp_poly(factor * scale * d[t])
    for _ in range(nsq):
        for t in range(n):
            out[t] = out[t] * out[t]


@numba.njit(parallel=True, cache=True)
def _row_keys(x, y, origin, pitch, reach, size, h, two_d):
    """Bucket of every scatterer, ``(floor(s_o) + h_o + 1) * nb_i + floor(s_i) + h_i + 1``,
    or -1 beyond the reach (see :func:`_sort_rows`)."""
    m = x.size
    nbo = size[0] + 2 * h[0] + 1
    nbi = size[1] + 2 * h[1] + 1 if two_d else 1
    key = np.empty(m, dtype=np.int64)
    inv_o = 1.0 / pitch[0]
    inv_i = 1.0 / pitch[1]
    for j in numba.prange(m):
        so = (x[j] - origin[0]) * inv_o
        si = (y[j] - origin[1]) * inv_i if two_d else 0.0
        if (
            so < -reach[0]
            or so > size[0] - 1 + reach[0]
            or (two_d and (si < -reach[1] or si > size[1] - 1 + reach[1]))
        ):
            key[j] = -1
            continue
        k = min(max(np.int64(math.floor(so)) + h[0] + 1, 0), nbo - 1) * nbi
        if two_d:
            k += min(max(np.int64(math.floor(si)) + h[1] + 1, 0), nbi - 1)
        key[j] = k
    return key


@numba.njit(parallel=True, cache=True)
def _row_records(dest, x, y, z, a, k0, depth_range, nf, origin, pitch, two_d, rec):
    """``rec[dest[j]] = (Re c, Im c, u, s_o[, s_i])`` of every scatterer ``j`` kept by the sort
    (``dest[j] >= 0``): the input streamed in order, carriers vectorised over runs of
    :data:`_SUB` scatterers, records scattered to their slots."""
    m = z.size
    n_chunks, chunk = sort_chunks(m)
    inv_o = 1.0 / pitch[0]
    inv_i = 1.0 / pitch[1]
    for c in numba.prange(n_chunks):
        bcr = np.empty(_SUB)
        bci = np.empty(_SUB)
        bu = np.empty(_SUB)
        hi = min(m, (c + 1) * chunk)
        for j0 in range(c * chunk, hi, _SUB):
            j1 = min(hi, j0 + _SUB)
            carrier_and_position(z[j0:j1], a[j0:j1], k0, depth_range, nf, bcr, bci, bu)
            for j in range(j0, j1):
                t = dest[j]
                if t < 0:
                    continue
                r = rec[t]
                r[0] = bcr[j - j0]
                r[1] = bci[j - j0]
                r[2] = bu[j - j0]
                r[3] = (x[j] - origin[0]) * inv_o
                if two_d:
                    r[4] = (y[j] - origin[1]) * inv_i


def _sort_rows(x, y, z, a, k0, depth_range, nf, origin, pitch, reach, size, h, two_d, rec):
    """Records ``(Re c, Im c, u, s_o[, s_i])`` of the scatterers within reach, by bucket.

    Lateral positions in pitches along the outer axis, ``s_o = (x_o - X_o)/p_o`` (``x`` holds
    the outer coordinate, ``y`` the inner one, used when ``two_d``: a raster of lines); bucket
    ``(floor(s_o) + h_o + 1) * nb_i + floor(s_i) + h_i + 1`` with ``nb = size + 2h + 1`` per
    axis, for ``s`` in ``[-reach, size - 1 + reach]`` on both axes; others are dropped. The
    stable parallel counting sort of :func:`speckle.imaging._methods._kernels.bucket_sort`: the
    order within a bucket is the input order whatever the number of threads. Fills the first
    ``starts[-1]`` rows of ``rec`` (M, 4 or 5) and returns the offsets.
    """
    nbo = size[0] + 2 * h[0] + 1
    nbi = size[1] + 2 * h[1] + 1 if two_d else 1
    key = _row_keys(x, y, origin, pitch, reach, size, h, two_d)
    starts, dest = bucket_sort(key, int(nbo * nbi))
    _row_records(dest, x, y, z, a, k0, depth_range, nf, origin, pitch, two_d, rec)
    return starts


@numba.njit(fastmath=True, inline="always")
def _ratios(b, h, kk):
    """``up[m]``, ``dn[m]``: weight(m +- 1) = weight(m) exp(+-2 b delta) up/dn[m]."""
    up = np.empty(kk)
    dn = np.empty(kk)
    for m in range(kk):
        up[m] = math.exp(b * (2.0 * (h - m) - 1.0))
        dn[m] = math.exp(-b * (2.0 * (h - m) + 1.0))
    return up, dn


@numba.njit(fastmath=True, inline="always")
def _weights(wd, wl, e2, ld, nc, b, h, kk, up, dn, nsq):
    """Weights ``exp(-b (delta + h - m)^2)`` of lines ``m = 0 ... kk - 1`` for the chunk's
    offsets ``ld`` (vectorised over the chunk): ``exp(-b delta^2)`` at ``m = h``, ratios
    ``exp(+-2 b delta)`` times constants to either side; into ``wd`` (float64), then ``wl``
    (working precision)."""
    scale = 2.0 ** (-nsq)
    _exp_into(wd[h], -b, ld, True, nc, scale, nsq)
    _exp_into(e2, 2.0 * b, ld, False, nc, scale, nsq)
    for m in range(h, kk - 1):
        wa = wd[m]
        wb = wd[m + 1]
        f = up[m]
        for t in range(nc):
            wb[t] = wa[t] * e2[t] * f
    _exp_into(e2, -2.0 * b, ld, False, nc, scale, nsq)
    for m in range(h, 0, -1):
        wa = wd[m]
        wb = wd[m - 1]
        f = dn[m]
        for t in range(nc):
            wb[t] = wa[t] * e2[t] * f
    for m in range(kk):
        wa = wd[m]
        wc = wl[m]
        for t in range(nc):
            wc[t] = wa[t]


@numba.njit(parallel=True, fastmath=True, cache=True)
def _spread_rows(rec, starts, size, h, b, two_d, w, coef, nf, pad, block, g):
    """Spread the bucketed records into the padded planar grid ``g`` (rows, 2, nf + 2 pad).

    Outer bucket ``ko`` writes outer rows ``ko ... ko + 2h_o + 1`` (line ``o`` is row
    ``o + 2h_o + 1``), likewise inner; padded row ``(r_o, r_i)`` is ``r_o * n_i + r_i`` with
    ``n_i = nb_i + 2h_i + 1`` (1 in 2-D); fine-grid offset ``pad`` (``coef``: the Horner table
    zero-padded to ``pad``, a whole number of groups of 8 slots, in the working precision).
    Blocks of ``block >= 2h_o + 2`` outer buckets: even blocks in parallel, then odd ones (their
    rows never overlap in a phase).
    """
    half = 0.5 * w
    ngrp = coef.shape[1] // LANES
    ko_n = 2 * h[0] + 2
    ki_n = 2 * h[1] + 2 if two_d else 1
    nbo = size[0] + 2 * h[0] + 1
    nbi = size[1] + 2 * h[1] + 1 if two_d else 1
    n_i = nbi + ki_n - 1
    nsq_o = _squarings(b[0])
    nsq_i = _squarings(b[1])
    up_o, dn_o = _ratios(b[0], h[0], ko_n)
    up_i, dn_i = _ratios(b[1], h[1], ki_n)
    plane = g.shape[2]
    rowlen = 2 * plane
    gf = g.reshape(-1)
    bin_scale = _NBINS / nf
    nblk = (nbo + block - 1) // block
    for phase in range(2):
        for bb in numba.prange((nblk - phase + 1) // 2):
            blk = 2 * bb + phase
            cnt = np.zeros(_NBINS + 1, dtype=np.int64)
            perm = np.empty(0, dtype=np.int64)
            wd = np.empty((max(ko_n, ki_n), _CH))
            wo = np.empty((ko_n, _CH), dtype=coef.dtype)
            wi = np.ones((ki_n, _CH), dtype=coef.dtype)
            ld = np.empty(_CH)  # sub-pitch offsets, outer axis
            li = np.empty(_CH)  # and inner axis (rasters)
            e2 = np.empty(_CH)
            lcr = np.empty(_CH, dtype=coef.dtype)
            lci = np.empty(_CH, dtype=coef.dtype)
            base = np.empty(_CH, dtype=np.uint64)
            xk = np.empty(_CH, dtype=coef.dtype)  # Horner in the working precision
            ker = np.empty((coef.shape[1], _CH), dtype=coef.dtype)
            for ko in range(blk * block, min(nbo, (blk + 1) * block)):
                for ki in range(nbi):
                    kb = ko * nbi + ki
                    j0 = starts[kb]
                    n = starts[kb + 1] - j0
                    if n == 0:
                        continue
                    # the bucket's records by depth bin (stable counting sort of indices)
                    cnt[:] = 0
                    for t in range(j0, j0 + n):
                        cnt[min(np.int64(rec[t, 2] * bin_scale), _NBINS - 1) + 1] += 1
                    for i in range(_NBINS):
                        cnt[i + 1] += cnt[i]
                    if perm.size < n:
                        perm = np.empty(n, dtype=np.int64)
                    for t in range(j0, j0 + n):
                        bn = min(np.int64(rec[t, 2] * bin_scale), _NBINS - 1)
                        perm[cnt[bn]] = t
                        cnt[bn] += 1
                    rowb = (ko * n_i + ki) * rowlen + pad
                    for c0 in range(0, n, _CH):
                        nc = min(_CH, n - c0)
                        for t in range(nc):
                            r = rec[perm[c0 + t]]
                            lcr[t] = r[0]
                            lci[t] = r[1]
                            ld[t] = r[3] - math.floor(r[3])
                            x0 = r[2] - half
                            cx = math.ceil(x0)
                            xk[t] = 2.0 * (cx - x0) - 1.0
                            base[t] = np.uint64(rowb + np.int64(cx))
                            if two_d:
                                li[t] = r[4] - math.floor(r[4])
                        _weights(wd, wo, e2, ld, nc, b[0], h[0], ko_n, up_o, dn_o, nsq_o)
                        if two_d:
                            _weights(wd, wi, e2, li, nc, b[1], h[1], ki_n, up_i, dn_i, nsq_i)
                        es_kernel_values(xk[:nc], coef, ker)
                        for t in range(nc):
                            _spread_one(gf, base[t], lcr[t], lci[t], wo, wi, ker, t, ngrp,
                                        ko_n, ki_n, n_i * rowlen, plane, rowlen)  # fmt: skip


@numba.njit(fastmath=True, inline="always")
def _spread_one(gf, base, c_r, c_i, wo, wi, ker, t, ngrp, ko_n, ki_n, ostride, plane, rowlen):
    """One scatterer ``t`` of the chunk: per group of 8 kernel slots (``ker``, slot-major),
    two 8-wide axpys per line. Flat unsigned indices: no wrap-around checks."""
    for gi in range(ngrp):
        o = gi * LANES
        k0 = ker[o, t]
        k1 = ker[o + 1, t]
        k2 = ker[o + 2, t]
        k3 = ker[o + 3, t]
        k4 = ker[o + 4, t]
        k5 = ker[o + 5, t]
        k6 = ker[o + 6, t]
        k7 = ker[o + 7, t]
        po = base + np.uint64(o)
        for mo in range(ko_n):
            p0 = po
            wm_o = wo[mo, t]
            for mi in range(ki_n):
                p1 = p0 + np.uint64(plane)
                wm = wm_o * wi[mi, t]
                axpy8(gf, p0, c_r * wm, k0, k1, k2, k3, k4, k5, k6, k7)
                axpy8(gf, p1, c_i * wm, k0, k1, k2, k3, k4, k5, k6, k7)
                p0 += np.uint64(rowlen)
            po += np.uint64(ostride)


@numba.njit(parallel=True, cache=True)
def _fold_rows(g, src, nf, pad, out):
    """Padded planar rows ``src`` of ``g`` -> periodic interleaved fine grids ``out``
    (len(src), 2 nf)."""
    for o in numba.prange(src.size):
        fold_padded(g[src[o], 0], g[src[o], 1], nf, pad, out[o])


def _padded(coef: np.ndarray) -> np.ndarray:
    """The Horner table with zero slots up to a whole number of groups of 8."""
    wp = LANES * -(-coef.shape[1] // LANES)
    out = np.zeros((coef.shape[0], wp), dtype=coef.dtype)
    out[:, : coef.shape[1]] = coef
    return out


def row_fine_grids(
    lateral: tuple[np.ndarray, ...],
    z: np.ndarray,
    amplitude: np.ndarray,
    *,
    origin: tuple[float, ...],
    pitch: tuple[float, ...],
    size: tuple[int, ...],
    waist: float,
    k0: float,
    depth_range: float,
    plan,
    ln_cut: float,
) -> np.ndarray:
    """Fine grids of the lines ``origin + o * pitch`` (µm) of a row or raster under the beam.

    ``lateral`` holds the scatterers' coordinates (µm, shape (M,) each) along the grid's axes:
    ``(x,)`` for a row, ``(outer, inner)`` for a raster of ``size = (n_outer, n_inner)`` lines
    (``origin`` and ``pitch`` per axis, µm); ``z`` (µm) and complex ``amplitude`` of shape
    (M,); ``waist`` w0 (µm); ``k0`` (rad/µm) and ``depth_range`` H (µm) as in
    :func:`speckle.ascan`; ``plan`` a :class:`speckle.imaging._methods.nufft.FineGridPlan`; weights
    below ``exp(-ln_cut)`` of a scatterer's peak may be dropped. Returns ``plan.cplx`` grids
    (prod(size), nf), line ``(o, i)`` at row ``o * n_inner + i``, for
    :func:`speckle.imaging._methods.nufft.fine_to_pixels`. Call inside
    :func:`speckle.imaging._methods.beam_nufft._slp_vectorize` and the parallel lock.
    """
    raster = len(size) == 2
    axes = [_reach(waist, p, ln_cut) for p in pitch]
    if max(a[0] for a in axes) > ROW_MAX_B:
        raise ValueError(f"row path: b = 2 pitch^2/waist^2 > {ROW_MAX_B:g} on pitch {pitch}")
    if not raster:  # a row: one inner "line" at the origin, weight 1, unit pitch
        axes.append((1.0, 0.0, 0))
        size, origin, pitch = (size[0], 1), (origin[0], 0.0), (pitch[0], 1.0)
    b, reach, h = (np.array(v) for v in zip(*axes, strict=True))
    h = h.astype(np.int64)
    size2 = np.array(size, dtype=np.int64)
    k_n = 2 * h + 2  # lines per scatterer and axis: bucket k writes padded rows k ... k + 2h + 1
    nb = size2 + 2 * h + 1  # buckets per axis
    if not raster:
        k_n[1], nb[1] = 1, 1
    coef = _padded(plan.coef)
    pad = coef.shape[1]  # >= w: a scatterer writes at most pad cells past its first one
    # numpy buffers (huge pages): faulting in pages allocated inside numba costs more
    rec = np.empty((z.size, 5 if raster else 4))
    inner = lateral[1] if raster else np.zeros(1)
    starts = _sort_rows(lateral[0], inner, z, amplitude, k0, depth_range, plan.nf, np.array(origin),
                        np.array(pitch), reach, size2, h, raster, rec)  # fmt: skip
    n_i = int(nb[1] + k_n[1] - 1)
    g = np.zeros(((nb[0] + k_n[0] - 1) * n_i, 2, plan.nf + 2 * pad), dtype=plan.real)
    _spread_rows(rec, starts, size2, h, b, raster, plan.w, coef, plan.nf, pad,
                 max(_BLOCK, int(k_n[0])), g)  # fmt: skip
    # line (o, i) sits at padded row (o + 2h_o + 1, i + 2h_i + 1), i.e. k_n - 1 past the origin
    o, i = np.divmod(np.arange(size2[0] * size2[1]), size2[1])
    src = (o + k_n[0] - 1) * n_i + (i + k_n[1] - 1)
    out = np.empty((src.size, plan.nf), dtype=plan.cplx)
    _fold_rows(g, src, plan.nf, pad, out.view(plan.real))
    return out
