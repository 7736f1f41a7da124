"""Numba kernels shared by the fast imaging methods (private: the one copy of each).

* :func:`carrier_and_position`: carrier ``a exp(2i k0 z)`` (phase reduced in float64 first,
  :mod:`speckle.imaging._methods.carrier` explains why) and the wrapped position on a periodic grid;
* :func:`es_kernel_values`: the ES kernel's slot values by Horner's scheme, vectorised over
  scatterers (:func:`speckle.imaging._methods.nufft.fine_grid_plan` builds the table);
* :func:`axpy8`: one 8-wide update ``g[p:p + 8] += v * k`` of a fine grid;
* :func:`fold_padded`: a padded fine grid (real and imaginary parts) folded back onto the
  periodic, interleaved fine grid;
* :func:`bucket_sort` and :func:`bucket_offsets`: the stable parallel counting sort of
  scatterers by bucket;
* :data:`PARALLEL_LOCK` and :func:`parallel_section`: how every parallel kernel is called.
"""

from __future__ import annotations

import contextlib
import threading

import numba
import numpy as np

__all__ = [
    "C1",
    "C2",
    "C3",
    "INV_TWO_PI",
    "LANES",
    "PARALLEL_LOCK",
    "axpy8",
    "bucket_offsets",
    "bucket_sort",
    "carrier_and_position",
    "es_kernel_values",
    "fold_padded",
    "parallel_section",
]

#: Held around every numba-parallel kernel call: each call already uses every core (prange over
#: A-lines), and numba's fallback "workqueue" threading layer aborts on concurrent calls (e.g.
#: from dask threads in :func:`speckle.bscan`); serialising costs nothing and is always safe.
PARALLEL_LOCK = threading.Lock()
#: Vector length of the spreading loops (kernel tables padded with zeros to a multiple).
LANES = 8
#: Scatterers per chunk of the vectorised Horner evaluation (chunks stay in L1).
_HORNER_CHUNK = 256

# 2 pi = C1 + C2 + C3 with C1 = 201/32 exact in 8 bits, so n * C1 is exact for n < 2**45
C1 = 6.28125
C2 = 0.001935307179586477
C3 = -1.0033115225336665e-19
INV_TWO_PI = 0.15915494309189535


@contextlib.contextmanager
def parallel_section(serial: bool = False, slp: bool = False):
    """Hold :data:`PARALLEL_LOCK` around numba-parallel calls.

    ``serial``: run them on one thread (a small problem: waking the pool costs more than it
    saves); the thread count is restored afterwards. ``slp``: enable LLVM's SLP vectoriser
    while numba compiles (numba turns it off by default): the 8-wide updates of :func:`axpy8`
    become single vector instructions only with it (measured 1.8-2x on the spreading loops).
    The flag is read when a function is compiled, so it matters at the first call (or a cache
    miss) only.
    """
    with PARALLEL_LOCK:
        old_slp = numba.config.SLP_VECTORIZE
        threads = numba.get_num_threads()
        if slp:
            numba.config.SLP_VECTORIZE = 1
        if serial:
            numba.set_num_threads(1)
        try:
            yield
        finally:
            numba.set_num_threads(threads)
            numba.config.SLP_VECTORIZE = old_slp


@numba.njit(fastmath=False, cache=True)
def _wrap_phase(ph):
    """``ph`` mod 2 pi into [-pi, pi] in float64 (three-term Cody-Waite reduction, no fastmath)."""
    n = np.floor(ph * INV_TWO_PI + 0.5)
    return ((ph - n * C1) - n * C2) - n * C3


@numba.njit(fastmath=True, cache=True)
def carrier_and_position(z, a, k0, depth_range, grid, cr, ci, u):
    """Fill ``cr + 1j*ci = a * exp(2i k0 z)`` and ``u = frac(z/depth) * grid`` for one line.

    ``z`` (float64, µm) and ``a`` (complex128) have shape (M,); outputs are float64 arrays of
    shape (M,). ``u`` lies in ``[0, grid)``. ``exp(i phase)`` is a branch-free polynomial
    (Taylor to degree 17 at a quarter of the phase, then squared twice, relative error
    < 1e-15) so that numba vectorises the loop.
    """
    inv_h = 1.0 / depth_range
    two_k0 = 2.0 * k0
    for j in range(z.shape[0]):
        zj = z[j]
        ph = _wrap_phase(two_k0 * zj)
        y = 0.25 * ph
        y2 = y * y
        # Taylor series of cos and sin at |y| <= pi/4 (truncation < 1e-17)
        c = 1.0 + y2 * (
            -1 / 2
            + y2
            * (
                1 / 24
                + y2
                * (
                    -1 / 720
                    + y2
                    * (1 / 40320 + y2 * (-1 / 3628800 + y2 * (1 / 479001600 - y2 / 87178291200)))
                )
            )
        )
        s = y * (
            1.0
            + y2
            * (
                -1 / 6
                + y2
                * (
                    1 / 120
                    + y2
                    * (
                        -1 / 5040
                        + y2
                        * (
                            1 / 362880
                            + y2 * (-1 / 39916800 + y2 * (1 / 6227020800 - y2 / 1307674368000))
                        )
                    )
                )
            )
        )
        # (c + i s)^4 by two squarings
        c, s = c * c - s * s, 2.0 * c * s
        c, s = c * c - s * s, 2.0 * c * s
        ar = a[j].real
        ai = a[j].imag
        cr[j] = ar * c - ai * s
        ci[j] = ar * s + ai * c
        f = zj * inv_h
        f = (f - np.floor(f)) * grid
        u[j] = f if f < grid else f - grid


@numba.njit(fastmath=True, inline="always")
def es_kernel_values(x, coef, ker):
    """``ker[i, t]`` = slot ``i`` of the ES kernel at ``x[t]`` (``x = 2s - 1``, see
    :func:`speckle.imaging._methods.nufft.fine_grid_plan`), for every slot of ``coef`` (degree + 1,
    slots) and ``t < x.size``.

    Horner's scheme per slot, vectorised over scatterers in chunks of ``_HORNER_CHUNK`` (1-D
    views indexed from 0: no wrap-around checks). The arithmetic is that of ``x`` and ``coef``
    (float64 or float32), cast on store into ``ker``.
    """
    deg1, nslot = coef.shape
    m = x.size
    for t0 in range(0, m, _HORNER_CHUNK):
        t1 = min(m, t0 + _HORNER_CHUNK)
        xs = x[t0:t1]
        for i in range(nslot):
            kr = ker[i, t0:t1]
            c = coef[deg1 - 1, i]
            for t in range(t1 - t0):
                kr[t] = c
            for k in range(deg1 - 2, -1, -1):
                c = coef[k, i]
                for t in range(t1 - t0):
                    kr[t] = kr[t] * xs[t] + c


@numba.njit(fastmath=True, inline="always")
def axpy8(gf, p, v, k0, k1, k2, k3, k4, k5, k6, k7):
    """``gf[p:p + 8] += v * k`` written out (flat unsigned index ``p``: no wrap-around
    checks; LLVM's SLP vectoriser packs the eight updates)."""
    gf[p] += v * k0
    gf[p + np.uint64(1)] += v * k1
    gf[p + np.uint64(2)] += v * k2
    gf[p + np.uint64(3)] += v * k3
    gf[p + np.uint64(4)] += v * k4
    gf[p + np.uint64(5)] += v * k5
    gf[p + np.uint64(6)] += v * k6
    gf[p + np.uint64(7)] += v * k7


@numba.njit(fastmath=True, inline="always")
def fold_padded(re, im, nf, pad, ob):
    """Padded grid (``re``, ``im``: ``nf + 2 pad`` cells each, cell ``i`` of the periodic grid
    at ``i + pad``) folded onto the periodic interleaved fine grid ``ob`` (2 nf)."""
    for i in range(nf):
        ob[2 * i] = re[i + pad]
        ob[2 * i + 1] = im[i + pad]
    for i in range(pad):
        ob[2 * (nf - pad + i)] += re[i]
        ob[2 * (nf - pad + i) + 1] += im[i]
        ob[2 * i] += re[nf + pad + i]
        ob[2 * i + 1] += im[nf + pad + i]


@numba.njit(cache=True)
def bucket_offsets(counts):
    """Offsets of a parallel counting sort: ``counts`` (chunks, buckets) -> ``starts``
    (buckets + 1) of every bucket and ``offset`` (chunks, buckets) where each chunk writes its
    scatterers of each bucket (chunks in input order within a bucket)."""
    n_chunks, nb = counts.shape
    starts = np.zeros(nb + 1, dtype=np.int64)
    offset = np.empty((n_chunks, nb), dtype=np.int64)
    total = 0
    for k in range(nb):
        starts[k] = total
        for c in range(n_chunks):
            offset[c, k] = total
            total += counts[c, k]
    starts[nb] = total
    return starts, offset


@numba.njit(parallel=True, cache=True)
def bucket_sort(key, nb):
    """Stable parallel counting sort: ``key`` (M,) bucket of each scatterer in ``[0, nb)``, or
    -1 (dropped) -> ``(starts, dest)``: the slot ``dest[j]`` of input ``j`` in bucket order
    (-1 when dropped) and the offsets ``starts`` (nb + 1) of every bucket.

    Each chunk of a fixed chunking of the input (:func:`sort_chunks`) counts its buckets, then
    numbers its scatterers from its own offsets (:func:`bucket_offsets`): the order within a
    bucket is the input order whatever the number of threads. Callers then stream the input in
    order and scatter each record to ``dest[j]``: a gather through the inverse permutation
    reads the scene at random and costs about three times as much.
    """
    m = key.size
    n_chunks, size = sort_chunks(m)
    counts = np.zeros((n_chunks, nb), dtype=np.int64)
    for c in numba.prange(n_chunks):
        for j in range(c * size, min(m, (c + 1) * size)):
            k = key[j]
            if k >= 0:
                counts[c, k] += 1
    starts, offset = bucket_offsets(counts)
    dest = np.empty(m, dtype=np.int64)
    for c in numba.prange(n_chunks):
        pos = offset[c]
        for j in range(c * size, min(m, (c + 1) * size)):
            k = key[j]
            if k >= 0:
                dest[j] = pos[k]
                pos[k] += 1
            else:
                dest[j] = -1
    return starts, dest


@numba.njit(cache=True)
def sort_chunks(m):
    """``(n_chunks, size)``: the fixed chunking of ``m`` inputs that :func:`bucket_sort` and the
    loops streaming its input use (independent of the number of threads)."""
    n_chunks = max(1, min(64, m // 16384))
    return n_chunks, (m + n_chunks - 1) // n_chunks
