"""Non-uniform FFT synthesis of A-scans: a type-1 NUFFT folded onto the pixel grid.

Eq. 4 splits into a scatterer sum and a spectral sum,

    F_n = sum_j c_j exp(i n x_j),   c_j = a_j exp(2i k0 z_j),   x_j = 2 pi z_j / H,
    A(q) = sum_n S_n F_n exp(-2i pi n q / N),

and ``F`` is a type-1 non-uniform FFT of the strengths ``c_j`` at the points ``x_j``. Two
implementations live here:

``"nufft"`` / ``"nufft32"`` (:func:`nufft_ascan`)
    Our own type-1 NUFFT, *folded* into the pixel synthesis: each scatterer is spread with an
    "exponential of semicircle" (ES) kernel ``phi`` of width ``w`` onto a fine periodic grid of
    ``nf >= max(2N, 64)`` points (numba, parallel over A-lines, kernel by Horner polynomials
    so the loop vectorises), one inverse FFT per line gives ``phi_hat(n) F_n``, and a single
    multiplier ``S_n / phi_hat(n)`` applies deconvolution *and* spectrum before the exact pixel DFT.
    A whole B-scan is one numba call and two batched FFTs, with no per-line plan or sort (a
    line's fine grid fits in cache). ``tol`` sets ``w`` (:func:`kernel_width`, about
    ``log10(1/tol) + 1``) and ``beta = 2.30 w`` (FINUFFT's rule for upsampling 2, error
    ~10**(1-w)).
    ``"nufft32"`` spreads, and FFTs, in single precision after float64 reduction of the
    carrier phase (:mod:`speckle.imaging._methods.carrier`); its rounding floor is ~2e-7 measured,
    ~4e-7 estimated (:func:`float32_error_estimate`).

``"finufft"`` (:func:`finufft_ascan`)
    The same transform with FINUFFT: one guru plan for the whole B-scan, ``setpts``/``execute``
    per line (FINUFFT's many-vector interface needs shared points, which A-lines do not have).
    It is the reference for "calling FINUFFT directly" in the benchmark.

Relative error is defined everywhere as ``||A - A_direct||_2 / ||A_direct||_2`` over the whole
B-scan (all lines and pixels).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import finufft
import numba
import numpy as np
import scipy.fft

from ...system.source import index_shift_phase, spectral_index
from .._rules import (
    DEFAULT_TOL,
    NUFFT_TOL_FLOOR,
    refuse_below_floor,
    refuse_float32,
    resolve_tol,
)
from ._kernels import carrier_and_position, es_kernel_values, fold_padded, parallel_section
from .carrier import float64_error_estimate

__all__ = [
    "DEFAULT_TOL",
    "NUFFT_TOL_FLOOR",
    "FineGridPlan",
    "check_float64_placement",
    "es_kernel",
    "fine_grid_plan",
    "fine_to_pixels",
    "finufft_ascan",
    "finufft_method",
    "float32_error_estimate",
    "kernel_width",
    "nufft32_method",
    "nufft_ascan",
    "nufft_method",
]
#: FINUFFT ``eps`` per unit ``tol`` for method "finufft" (FINUFFT's error reaches ~9 eps).
FINUFFT_EPS_FACTOR = 0.05
#: Fine-grid upsampling factor.
UPSAMPLING = 2
#: Smallest fine grid (small N: see :func:`fine_grid_size`).
MIN_FINE_GRID = 64
#: Largest fine-grid elements (lines x nf) held at once; bounds memory on large B-scans.
CHUNK_ELEMENTS = 1 << 21
_EPS32 = float(np.finfo(np.float32).eps)


def kernel_width(tol: float) -> int:
    """ES kernel width ``w`` (fine-grid points) reaching relative accuracy ``tol`` at upsampling 2.

    ``w = ceil(log10(2/tol)) + 1``: FINUFFT's rule (aliasing error ~``10**(1-w)``) applied to
    ``tol/2`` (a safety factor of 2). The plain rule
    ``ceil(log10(1/tol)) + 1`` was measured to exceed ``tol`` by up to 1.4x on random scenes at
    decade tolerances (1e-3, 1e-5, 1e-6; worst at small N and band-edge-heavy spectra); with the
    factor 2 the worst of 300 random scenes per tolerance stays below ``0.6 tol`` (tests).
    """
    w = math.ceil(math.log10(2.0 / tol)) + 1
    return int(min(16, max(2, w)))


def es_kernel(y: np.ndarray, w: int) -> np.ndarray:
    """ES kernel ``exp(beta (sqrt(1 - (2y/w)^2) - 1))`` on ``|y| <= w/2`` (fine-grid units)."""
    beta = 2.30 * w
    y = np.asarray(y, dtype=float)
    arg = 1.0 - (2.0 * y / w) ** 2
    return np.where(arg >= 0, np.exp(beta * (np.sqrt(np.clip(arg, 0, None)) - 1.0)), 0.0)


@functools.lru_cache(maxsize=32)
def _horner_table(w: int) -> np.ndarray:
    """Polynomial coefficients ``C[k, i]`` of the kernel at slot ``i`` in ``x = 2s - 1``.

    A point at fine-grid position ``u`` touches grid points ``l0 + i`` (``i < w``) with
    ``l0 = ceil(u - w/2)`` and ``s = l0 - u + w/2`` in [0, 1); slot ``i`` sees
    ``phi(s + i - w/2)``. Degree ``w + 1`` fits each slot to < 0.05 of the kernel's own error
    ``10**(1-w)`` (checked for w = 2 ... 16 on 2001 points).
    """
    deg = w + 1
    nodes = np.cos(np.pi * (np.arange(4 * deg) + 0.5) / (4 * deg))  # Chebyshev in [-1, 1]
    s = 0.5 * (nodes + 1.0)
    coef = np.zeros((deg + 1, w))
    for i in range(w):
        coef[:, i] = np.polynomial.polynomial.polyfit(nodes, es_kernel(s + i - w / 2, w), deg)
    coef.setflags(write=False)  # cached: shared by every call
    return coef


def _kernel_fourier(w: int, nf: int, n: np.ndarray) -> np.ndarray:
    """``phi_hat(n) = int phi(y) exp(2i pi n y/nf) dy`` by Gauss-Legendre quadrature (real)."""
    x, wt = np.polynomial.legendre.leggauss(4 * w + 16)
    y = 0.25 * w * (x + 1.0)  # [0, w/2]
    vals = es_kernel(y, w) * wt * (0.25 * w)
    return 2.0 * np.cos(2 * np.pi * np.outer(n, y) / nf) @ vals


@numba.njit(parallel=True, fastmath=True, cache=True)
def _spread(z, a, k0, depth_range, nf, w, coef, out):
    """Spread lines of scatterers onto ``out`` (B, 2*nf): interleaved re/im fine grids.

    Per line: carrier and positions in float64 (vectorised), kernel values by Horner vectorised
    over the scatterers (slot-major), then a scalar scatter into a padded, interleaved grid.
    Arithmetic after the carrier is in ``coef.dtype`` (float64 or float32): values are cast on
    store into arrays of that type.
    """
    nlines, m = z.shape
    half = 0.5 * w
    pad = w
    for b in numba.prange(nlines):
        cr = np.empty(m)
        ci = np.empty(m)
        u = np.empty(m)
        carrier_and_position(z[b], a[b], k0, depth_range, nf, cr, ci, u)
        vr = np.empty(m, dtype=coef.dtype)
        vi = np.empty(m, dtype=coef.dtype)
        x = np.empty(m, dtype=coef.dtype)
        start = np.empty(m, dtype=np.int64)
        for j in range(m):
            x0 = u[j] - half
            l0 = np.ceil(x0)
            x[j] = 2.0 * (l0 - x0) - 1.0
            start[j] = 2 * (np.int64(l0) + pad)
            vr[j] = cr[j]
            vi[j] = ci[j]
        ker = np.empty((w, m), dtype=coef.dtype)
        es_kernel_values(x, coef, ker)
        g = np.zeros(2 * (nf + 2 * pad), dtype=coef.dtype)
        for j in range(m):
            pr = vr[j]
            pi = vi[j]
            if pr == 0 and pi == 0:
                continue  # zero-amplitude padding of ragged lines
            s = start[j]
            for i in range(w):
                kk = ker[i, j]
                g[s + 2 * i] += pr * kk
                g[s + 2 * i + 1] += pi * kk
        # fold the padded grid back onto the periodic fine grid
        fold_padded(g[0::2], g[1::2], nf, pad, out[b])


def fine_grid_size(n_pixels: int, w: int) -> int:
    """Fine grid ``nf``: an FFT-friendly even size >= max(2N, 2w, 64).

    Below N = 32 the rule error ~10**(1-w) fails at upsampling 2 (measured up to 1.8 tol at
    N = 4 ... 16): small lines get a finer grid instead, which costs nothing there.
    """
    nf = scipy.fft.next_fast_len(max(UPSAMPLING * n_pixels, 2 * w, MIN_FINE_GRID))
    return nf + (nf % 2)


def _pixel_phase(n_pixels: int) -> np.ndarray:
    return index_shift_phase(n_pixels, np.arange(n_pixels))


def float32_error_estimate(n_scatterers: int, n_pixels: int, w: int) -> float:
    """Relative-error estimate of the single-precision NUFFT (rounding only).

    Sources, each a sum of independent roundings of relative size ``eps32/2`` (so they add in
    quadrature): the carrier and kernel casts (1 each), the accumulation of ``~M w / nf`` terms
    per fine-grid cell (a random walk: their count), and two FFTs of ``log2`` stages each:
    ``eps32/2 * sqrt(2 + M w/(2N) + log2(2N) + log2(N))``. Measured floors (benchmark, failure
    map) are 2-3 times below it for N = 64 ... 1024 and 4-32 scatterers per pixel, whatever
    ``k0 z``, because the carrier phase is reduced in float64 first.
    """
    terms = (
        2.0 + n_scatterers * w / (2.0 * n_pixels) + math.log2(2 * n_pixels) + math.log2(n_pixels)
    )
    return 0.5 * _EPS32 * math.sqrt(terms)


def nufft_ascan(
    z: np.ndarray,
    amplitude: np.ndarray,
    n_pixels: int,
    depth_range: float,
    k0: float,
    spectrum: np.ndarray,
    *,
    tol: float = 1e-6,
    precision: str = "double",
    chunk_elements: int = CHUNK_ELEMENTS,
) -> np.ndarray:
    """A-scans by the folded ES-kernel NUFFT (see module docstring).

    Parameters
    ----------
    z, amplitude : numpy.ndarray, shape (B, M)
        Depths in µm (float64) and complex amplitudes (complex128).
    n_pixels, depth_range, k0, spectrum
        ``N``, ``H`` (µm), ``k0`` (rad/µm) and the ``N`` spectral weights.
    tol : float
        Requested relative accuracy (sets the kernel width).
    precision : {"double", "single"}
        Arithmetic of the spreading and FFTs (the carrier phase is always reduced in float64).
    chunk_elements : int
        Lines are processed in chunks of about this many fine-grid elements (memory bound).

    Returns
    -------
    numpy.ndarray
        complex128 (B, N).
    """
    plan = fine_grid_plan(n_pixels, spectrum, tol, precision)
    nlines = z.shape[0]
    out = np.empty((nlines, n_pixels), dtype=np.complex128)
    step = max(1, chunk_elements // plan.nf)
    for b0 in range(0, nlines, step):
        sl = slice(b0, min(nlines, b0 + step))
        nb = sl.stop - sl.start
        g = np.empty((nb, plan.nf), dtype=plan.cplx)
        with parallel_section():
            _spread(
                z[sl],
                amplitude[sl],
                float(k0),
                float(depth_range),
                plan.nf,
                plan.w,
                plan.coef,
                g.view(plan.real),
            )
        out[sl] = fine_to_pixels(g, plan)
    return out


class FineGridPlan(NamedTuple):
    """What a folded type-1 NUFFT needs besides the scatterers (:func:`fine_grid_plan`)."""

    w: int  # ES kernel width (fine-grid points)
    nf: int  # fine grid size over one unambiguous depth
    coef: np.ndarray  # Horner table of the kernel, in the working precision
    mult: np.ndarray  # S_n / phi_hat(n): deconvolution and spectrum, (N,)
    modes: np.ndarray  # fine-grid index of each spectral index n, (N,)
    phase: np.ndarray  # pixel index-shift phase, (N,)
    real: type  # np.float64 or np.float32
    cplx: type  # np.complex128 or np.complex64


def fine_grid_plan(
    n_pixels: int, spectrum: np.ndarray, tol: float, precision: str = "double"
) -> FineGridPlan:
    """Kernel width, fine grid, Horner table and spectral multiplier for accuracy ``tol``.

    Shared by every method that spreads scatterers with the ES kernel onto a fine periodic
    grid of one unambiguous depth (A-lines here, scanned-beam lines in
    :mod:`speckle.imaging._methods.beam_nufft`); ``precision`` is ``"double"`` or ``"single"``.
    """
    real = np.float64 if precision == "double" else np.float32
    cplx = np.complex128 if precision == "double" else np.complex64
    w = kernel_width(tol)
    nf = fine_grid_size(n_pixels, w)
    n = spectral_index(n_pixels)
    return FineGridPlan(
        w=w,
        nf=nf,
        coef=_horner_table(w).astype(real),
        mult=(spectrum / _kernel_fourier(w, nf, n)).astype(cplx),
        modes=np.mod(n, nf),
        phase=_pixel_phase(n_pixels).astype(cplx),
        real=real,
        cplx=cplx,
    )


def fine_to_pixels(g: np.ndarray, plan: FineGridPlan) -> np.ndarray:
    """Spread fine grids ``g`` (B, nf) -> pixels (B, N), complex128: inverse FFT, modes,
    deconvolution and spectrum, exact pixel DFT. ``g`` is overwritten."""
    fine = scipy.fft.ifft(g, axis=-1, norm="forward", overwrite_x=True, workers=-1)
    field = fine[:, plan.modes] * plan.mult
    out = scipy.fft.fft(field, axis=-1, overwrite_x=True, workers=-1) * plan.phase
    return out.astype(np.complex128, copy=False)


def finufft_ascan(
    z: np.ndarray,
    amplitude: np.ndarray,
    n_pixels: int,
    depth_range: float,
    k0: float,
    spectrum: np.ndarray,
    *,
    tol: float = 1e-6,
    eps: float | None = None,
    nthreads: int = 1,
) -> np.ndarray:
    """A-scans with FINUFFT: one type-1 guru plan, ``setpts``/``execute`` per A-line.

    The carrier ``a exp(2i k0 z)`` and points ``2 pi (z mod H)/H`` are formed with numpy in
    float64, FINUFFT returns ``F_n`` (mode order ``-(N//2) ... N-1-(N//2)``, matching
    :func:`speckle.system.source.spectral_index`), then ``S_n F_n`` goes to pixels by an FFT.
    ``nthreads=1`` per line is fastest for A-line sized problems (threads cost more than they
    save at a few thousand points; measured in ``benchmarks/bench_ascan.py``).

    FINUFFT's ``eps`` is not a bound on our relative l2 error: with ``eps = tol/2`` the worst of
    300 random scenes per tolerance (N = 4 ... 300, arbitrary spectra) reached 1.0-4.4 ``tol``
    at most tolerances from 1e-1 to 1e-12, i.e. up to ~9 ``eps``. ``eps`` therefore defaults to
    ``tol * FINUFFT_EPS_FACTOR`` (1/20) so that ``tol`` holds; pass ``eps`` to call FINUFFT at
    its own tolerance (the benchmark does, to give FINUFFT its loosest setting).
    """
    eps = FINUFFT_EPS_FACTOR * tol if eps is None else eps
    nlines = z.shape[0]
    c = amplitude * np.exp(2j * k0 * z)
    x = np.mod(z, depth_range) * (2 * np.pi / depth_range)
    plan = finufft.Plan(1, (n_pixels,), eps=max(eps, 1e-14), isign=1, nthreads=nthreads)
    field = np.empty((nlines, n_pixels), dtype=np.complex128)
    for b in range(nlines):
        plan.setpts(x[b])
        field[b] = plan.execute(c[b])
    return scipy.fft.fft(field * spectrum, axis=-1, workers=-1) * _pixel_phase(n_pixels)


#: Share of ``tol`` left to float64 placement errors by "nufft" (its kernel takes ``tol/2``,
#: measured worst 0.56 ``tol``).
FLOAT64_SHARE = 0.25


def check_float64_placement(z, amplitude, depth_range, k0, spectrum, budget, tol, method) -> float:
    """Refuse scenes whose float64 carrier/position error exceeds ``budget`` (deep scatterers).

    See :func:`speckle.imaging._methods.carrier.float64_error_estimate`; returns the estimate.
    """
    err = float64_error_estimate(z, amplitude, depth_range, k0, spectrum)
    if err > budget:
        zmax = float(np.max(np.abs(z)))
        loss = (
            f"~{err:.1e} of relative accuracy"
            if math.isfinite(err)
            else "all accuracy (more than 2**45 turns of carrier phase)"
        )
        raise ValueError(
            f"method={method!r} cannot reach tol={tol:g} on these depths: scatterers up to "
            f"|z| = {zmax:.3g} µm (= {zmax / depth_range:.3g} H; carrier phase 2 k0 |z| up to "
            f"{2 * k0 * zmax:.3g} rad with k0 = {k0:g} rad/µm) lose {loss} in the float64 "
            "carrier/position reduction; use method='direct' or 'finufft' (exact reduction) "
            "or method='auto'"
        )
    return err


def nufft_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """``ascan(..., method="nufft")`` on validated arrays (``tol`` None: the default)."""
    tolv = refuse_below_floor(resolve_tol(tol), "nufft")
    check_float64_placement(
        z, amplitude, depth_range, k0, spectrum, FLOAT64_SHARE * tolv, tolv, "nufft"
    )
    return nufft_ascan(z, amplitude, n_pixels, depth_range, k0, spectrum, tol=tolv)


def nufft32_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """``ascan(..., method="nufft32")`` on validated arrays."""
    tolv = resolve_tol(tol)
    floor = float32_error_estimate(z.shape[1], n_pixels, kernel_width(0.5 * tolv))
    refuse_float32(floor, tolv)
    check_float64_placement(
        z, amplitude, depth_range, k0, spectrum, 0.5 * tolv - floor, tolv, "nufft32"
    )
    # half of tol for the kernel, half for rounding
    return nufft_ascan(
        z, amplitude, n_pixels, depth_range, k0, spectrum, tol=0.5 * tolv, precision="single"
    )


def finufft_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """``ascan(..., method="finufft")`` on validated arrays."""
    tolv = refuse_below_floor(resolve_tol(tol), "finufft")
    return finufft_ascan(z, amplitude, n_pixels, depth_range, k0, spectrum, tol=tolv)
