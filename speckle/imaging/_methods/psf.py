"""Truncated point-spread-function (PSF) synthesis: each scatterer written into nearby pixels.

Eq. 4 is a sum of shifted copies of one periodic PSF,

    A(q) = sum_j c_j K(u_j - q),   K(y) = sum_n S_n exp(2i pi n y / N),

with ``c_j = a_j exp(2i k0 z_j)`` and ``u_j = N frac(z_j/H)`` the scatterer position in pixels.
The ``"psf"`` method writes each scatterer only into the ``2 hw + 1`` pixels nearest to it
(``hw`` = half-width in pixels) and reads ``K`` from a table linearly interpolated in the
sub-pixel offset (rows of the table share one offset, so the inner loop vectorises).

Errors (relative, ``||dA||_2/||A||_2``; expectations for scatterers with independent uniform
positions, as in :func:`speckle.random_scatterers`, whose cross terms average out):

* truncation: ``e_t^2 = < sum_{|d| > hw} |K(t - d)|^2 >_t / (N sum S^2)`` -- the PSF tail energy
  beyond the half-width over its total energy (Parseval: ``sum_d |K(t-d)|^2 = N sum S^2`` for
  every offset ``t``), averaged over the sub-pixel offset ``t``. For a smooth (Gaussian)
  spectrum the tail falls off like the spectrum's Fourier transform; for a rectangular one ``K``
  is a Dirichlet kernel with ``|K| ~ N/(pi d)``, so ``e_t ~ 1/(pi sqrt(hw))``: no useful
  half-width reaches a tight ``tol`` (:func:`half_width` then covers the whole A-line, and the
  method costs as much as the direct sum, which ``method="auto"`` sees in its cost model).
* interpolation: linear interpolation with ``L`` rows per pixel errs by
  ``K'' tau (1 - tau)/(2 L^2)``; averaging ``(tau (1-tau))^2 = 1/30`` and Parseval for ``K''``
  gives ``e_i^2 = (2 pi/N)^4 sum n^4 S_n^2 / (120 L^4 sum S_n^2)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ...system.source import index_shift_phase, spectral_index
from .._rules import psf_slots, resolve_tol
from ._kernels import carrier_and_position, parallel_section
from .nufft import check_float64_placement

__all__ = [
    "MAX_ROWS",
    "half_width",
    "psf_ascan",
    "psf_error_estimate",
    "psf_method",
    "tail_error",
]

#: Largest number of interpolation rows per pixel (bounds table memory; sets the error floor).
MAX_ROWS = 1 << 14
_OFFSETS = 32  # sub-pixel offsets averaged in the truncation-error estimate


def _tail_energy(spectrum: np.ndarray) -> np.ndarray:
    """Mean over sub-pixel offsets of the PSF energy beyond each half-width, relative.

    Returns ``r[hw]`` for ``hw = 0 ... N//2``: ``< sum_{|d| > hw} |K(t-d)|^2 >_t / (N sum S^2)``.
    """
    n_pix = spectrum.size
    n = spectral_index(n_pix)
    t = (np.arange(_OFFSETS) + 0.5) / _OFFSETS - 0.5
    # K(t - d) = sum_n S_n e^{2i pi n t/N} e^{-2i pi n d/N}: one FFT per offset
    k = np.fft.fft(spectrum * np.exp(2j * np.pi * np.outer(t, n) / n_pix), axis=-1)
    energy = np.abs(k) ** 2  # index d (mod N)
    d = np.arange(n_pix)
    dist = np.minimum(d, n_pix - d)  # |d| on the circle
    total = n_pix * np.sum(spectrum**2)
    inside = np.bincount(dist, weights=energy.mean(axis=0), minlength=n_pix // 2 + 1)
    # energy strictly beyond each half-width, summed from the far end (no cancellation)
    tail = np.concatenate([np.cumsum(inside[::-1])[::-1][1:], [0.0]])
    return tail / total


def tail_error(spectrum: np.ndarray, hw: int) -> float:
    """Expected relative truncation error ``e_t`` of half-width ``hw`` pixels (see module)."""
    r = _tail_energy(np.asarray(spectrum, dtype=float))
    return float(math.sqrt(r[min(hw, r.size - 1)]))


def _interp_error(spectrum: np.ndarray, rows: int) -> float:
    n_pix = spectrum.size
    n = spectral_index(n_pix)
    ratio = np.sum(n**4 * spectrum**2) / np.sum(spectrum**2)
    return float(math.sqrt((2 * np.pi / n_pix) ** 4 * ratio / 120.0) / rows**2)


def half_width(spectrum: np.ndarray, tol: float, *, _tail: np.ndarray | None = None) -> int:
    """Smallest half-width (pixels) whose expected truncation error is <= ``tol/3``.

    Returns ``N//2`` (every pixel: no truncation) when no smaller half-width reaches it.
    """
    r = _tail_energy(np.asarray(spectrum, dtype=float)) if _tail is None else _tail
    ok = np.nonzero(r <= (tol / 3.0) ** 2)[0]
    return int(ok[0]) if ok.size else spectrum.size // 2


def _rows(spectrum: np.ndarray, tol: float) -> int:
    """Interpolation rows per pixel giving interpolation error <= tol/6 (capped at MAX_ROWS).

    The margins (tol/3 + tol/6) cover single scatterers at the worst sub-pixel offset, where the
    errors reach ~2x their offset averages.
    """
    e1 = _interp_error(spectrum, 1)
    return int(min(MAX_ROWS, max(8, math.ceil(math.sqrt(6.0 * e1 / tol)))))


#: Single scatterers at the worst sub-pixel offset reach ~2x the offset-averaged errors.
WORST_CASE = 2.0


def psf_error_estimate(spectrum: np.ndarray, tol: float) -> tuple[float, int, int]:
    """``(predicted error bound, half-width, rows)`` the ``"psf"`` method uses at ``tol``.

    The bound is :data:`WORST_CASE` times the offset-averaged truncation plus interpolation
    error: with the interpolation rows capped at :data:`MAX_ROWS` the averaged error alone
    may sit just below ``tol`` while a scene's error exceeds it (found by Hypothesis: N = 4,
    a narrow Gaussian spectrum, tol 1e-9, error 1.09e-9), so the method is admissible only
    where this bound is within ``tol``.
    """
    s = np.asarray(spectrum, dtype=float)
    tail = _tail_energy(s)
    hw = half_width(s, tol, _tail=tail)
    rows = _rows(s, tol)
    err = math.sqrt(tail[min(hw, tail.size - 1)]) + _interp_error(s, rows)
    return WORST_CASE * err, hw, rows


def _table(spectrum: np.ndarray, lo: int, nk: int, rows: int) -> np.ndarray:
    """Interpolation table ``T[it, k] = K(t_it - (k - lo))``, ``t_it = it/rows - 1/2``.

    Returned as float64 (rows + 1, 2 nk) with real and imaginary parts interleaved. Each row is
    one exact FFT, ``K(t - d) = sum_n [S_n exp(2i pi n t/N)] exp(-2i pi n d/N)`` for every
    ``d`` (a chirp-z transform over all rows at once loses ~1e-9 in its chirp phases at the
    lengths tight tolerances need).
    """
    n_pix = spectrum.size
    n = spectral_index(n_pix)
    d = np.arange(nk) - lo
    # FFT index m = n + N//2: exp(-2i pi n d/N) = exp(-2i pi m d/N) exp(2i pi (N//2) d/N)
    shift = index_shift_phase(n_pix, d)
    out = np.empty((rows + 1, 2 * nk))
    step = max(1, (1 << 20) // n_pix)
    for r0 in range(0, rows + 1, step):
        t = np.arange(r0, min(rows + 1, r0 + step)) / rows - 0.5
        k = np.fft.fft(spectrum * np.exp(2j * np.pi * np.outer(t, n) / n_pix), axis=-1)
        tab = k[:, np.mod(d, n_pix)] * shift
        out[r0 : r0 + len(t), 0::2] = tab.real
        out[r0 : r0 + len(t), 1::2] = tab.imag
    return out


@numba.njit(parallel=True, fastmath=True, cache=True)
def _psf_lines(z, a, k0, depth_range, n_pix, lo, nk, rows, table, out):
    """Write every scatterer into its ``nk`` nearest pixels; ``out`` (B, 2N) interleaved."""
    nlines, m = z.shape
    pad = lo + 1
    for b in numba.prange(nlines):
        cr = np.empty(m)
        ci = np.empty(m)
        u = np.empty(m)
        carrier_and_position(z[b], a[b], k0, depth_range, n_pix, cr, ci, u)
        g = np.zeros(2 * (n_pix + 2 * nk + 2))
        ker = np.empty(2 * nk)
        for j in range(m):
            vr = cr[j]
            vi = ci[j]
            if vr == 0.0 and vi == 0.0:
                continue
            p0 = np.floor(u[j] + 0.5)
            pos = (u[j] - p0 + 0.5) * rows
            it = min(np.int64(pos), rows - 1)
            fr = pos - it
            r0 = table[it]
            r1 = table[it + 1]
            for i in range(2 * nk):
                ker[i] = r0[i] + fr * (r1[i] - r0[i])
            s = 2 * (np.int64(p0) - lo + pad)
            for i in range(nk):
                kr = ker[2 * i]
                ki = ker[2 * i + 1]
                g[s + 2 * i] += vr * kr - vi * ki
                g[s + 2 * i + 1] += vr * ki + vi * kr
        ob = out[b]
        # fold the padded line back onto the N periodic pixels
        for i in range(g.shape[0] // 2):
            q = (i - pad) % n_pix
            ob[2 * q] += g[2 * i]
            ob[2 * q + 1] += g[2 * i + 1]


def psf_ascan(
    z: np.ndarray,
    amplitude: np.ndarray,
    n_pixels: int,
    depth_range: float,
    k0: float,
    spectrum: np.ndarray,
    *,
    tol: float | None = 1e-6,
    hw: int | None = None,
    rows: int | None = None,
) -> np.ndarray:
    """A-scans by the truncated PSF (see module docstring).

    Parameters
    ----------
    z, amplitude : numpy.ndarray, shape (B, M)
        Depths (µm, float64) and complex amplitudes.
    n_pixels, depth_range, k0, spectrum
        ``N``, ``H`` (µm), ``k0`` (rad/µm), ``N`` spectral weights.
    tol : float, optional
        Requested relative accuracy; sets ``hw`` and ``rows`` unless they are given.
    hw : int, optional
        Half-width in pixels (explicit knob, e.g. to chart the failure on a rectangular
        spectrum); clipped to ``N//2``.
    rows : int, optional
        Interpolation rows per pixel.

    Returns
    -------
    numpy.ndarray
        complex128 (B, N).
    """
    s = np.asarray(spectrum, dtype=float)
    if hw is None:
        hw = half_width(s, tol)
    lo, nk = psf_slots(n_pixels, int(hw))
    if rows is None:
        rows = _rows(s, tol if tol is not None else 1e-6)
    table = _table(s, lo, nk, int(rows))
    out = np.zeros((z.shape[0], n_pixels), dtype=np.complex128)
    with parallel_section():
        _psf_lines(
            z,
            amplitude,
            float(k0),
            float(depth_range),
            n_pixels,
            lo,
            nk,
            int(rows),
            table,
            out.view(np.float64),
        )
    return out


def psf_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """``ascan(..., method="psf")`` on validated arrays (``tol`` None: the default)."""
    tolv = resolve_tol(tol)
    err, hw, rows = psf_error_estimate(spectrum, tolv)
    if err > tolv:
        raise ValueError(
            f"method='psf' cannot reach tol={tolv:g} on this spectrum: its expected error is "
            f"{err:.1e} (half-width {hw} px, {rows} interpolation rows per pixel, the cap); "
            "use a looser tol or method='nufft'"
        )
    check_float64_placement(z, amplitude, depth_range, k0, spectrum, tolv - err, tolv, "psf")
    out = psf_ascan(z, amplitude, n_pixels, depth_range, k0, spectrum, hw=hw, rows=rows)
    # The estimate is relative to the incoherent energy sum_j |a_j|^2 N sum S^2 (each
    # scatterer's error has its own phase, so error energies add); the scene's own energy can
    # be far below it (few independent speckle samples, e.g. a spectrum with one dominant
    # component). Rescale by that ratio and refine once where the bound is not met.
    norm = float(np.linalg.norm(out))
    incoherent = math.sqrt(float(np.sum(np.abs(amplitude) ** 2)) * n_pixels * np.sum(spectrum**2))
    c = incoherent / norm if norm > 0 else math.inf
    if err * c <= tolv:
        return out
    err2, hw, rows = psf_error_estimate(spectrum, tolv / c) if np.isfinite(c) else (c, hw, rows)
    if err2 * c > tolv:
        raise ValueError(
            f"method='psf' cannot reach tol={tolv:g} on this scene: its scatterers nearly cancel "
            f"(image energy {1 / c:.1e} of the incoherent sum), which needs an error of "
            f"{tolv / c:.1e} per scatterer; use method='nufft' or 'direct'"
        )
    return psf_ascan(z, amplitude, n_pixels, depth_range, k0, spectrum, hw=hw, rows=rows)
