"""The SynthOCT scanner's numpy core: numpy and finufft only (the ``speckle-scan`` command's path).

Field of B-scan ``b`` (at ``Y_b``), A-line ``i`` (at ``X_i``), pixel ``q``:

    A(i, q) = sum_j a_j W_ij T_i(z_j) sum_n S_n exp(2i k_n z_j) exp(-2i pi n q/N),

``a_j = sqrt(E_j/100)``, ``W_ij = exp(-((x_j - X_i)^2 + (y_j - Y_b)^2)/r^2)`` (the double-pass
amplitude weight of a Gaussian beam of waist ``sqrt(2) r``), ``k_n = k0 + n pi/H`` for
``n = -(N//2) ... N-1-(N//2)``, ``S_n`` the Hann window over the ``N`` samples
(``numpy.hanning(N)``), and the energy shadowing ``T_i(z) = exp(-C_i(z))``,

    C_i(z) = sum_{l: z_l < z} (E_l/100) W_il^2

(line by line: each scatterer above removes its energy fraction, weighted by the beam's
double-pass intensity ``W^2`` at it; ``"line"``, the identified law) or its mean over the lines,
``C(z) = sum_{l: z_l < z} (E_l/100) mean_i W_il^2`` (``"mean"``), or 0 (``"none"``).
:mod:`speckle.synthoct.scanner` documents the identification.

Evaluation (exact up to two stated truncations): every (scatterer, line) pair with
``W_ij >= tol`` is kept (a dropped pair's weight is below ``tol``); per line the pairs are taken
in depth order (scatterers sorted by ``z`` once, pairs stably sorted by line), so ``C_i(z_j)`` is
an exclusive cumulative sum, equal depths sharing the same value (strict ``<``). Each pair is then
one point of a 2-D type-1 NUFFT (FINUFFT, tolerance ``eps``) whose lateral coordinate is its
line's index on the grid ``2 pi i/L``: the inverse DFT over the ``L`` lateral modes returns
every line's own spectral sum exactly, so shadowing may differ from line to line. One FFT over
``n`` gives the pixels.
"""

from __future__ import annotations

import math
import os

import finufft
import numpy as np

#: Shadowing laws: line by line (the official scanner's), mean over the lines, none.
SHADOWING = ("line", "mean", "none")
#: The scan's dynamic range (dB) and gray levels (the official 8-bit PNG).
DYNAMIC_RANGE = 51.0
LEVELS = 256
#: Pairs below this double-pass weight are dropped, and FINUFFT's tolerance (defaults).
TOL = 1e-4
EPS = 1e-4


def threads(nthreads: int | None) -> int:
    """FINUFFT threads: ``nthreads``, else the CPUs this process may use."""
    if nthreads is not None:
        return int(nthreads)
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def hann_spectrum(n_pixels: int) -> np.ndarray:
    """The scanner's spectrum: ``numpy.hanning(N)`` ordered ``n = -(N//2) ... N-1-(N//2)``."""
    return np.hanning(n_pixels)


def beam_pairs(x, y, line_x, line_y, radius, tol):
    """``(j, line, w)``: scatterer index, line index and double-pass weight ``W_ij`` of every
    pair with ``W_ij >= tol``, ordered by line, then by scatterer index."""
    n_lines = line_x.size
    reach = radius * math.sqrt(math.log(1.0 / tol))
    if n_lines > 1:
        pitch = float(line_x[1] - line_x[0])
        offsets = math.ceil(2 * reach / pitch) + 1
        first = np.ceil((x - reach - line_x[0]) / pitch).astype(np.int64)
    else:  # one line: every scatterer's only candidate
        pitch, offsets, first = 1.0, 1, np.zeros(x.size, np.int64)
    lines = first[:, None] + np.arange(offsets)  # (M, K)
    # x_j - X_{first + o} = s_j - o p with s_j = x_j - X_first (no gather of line positions)
    s = x - (line_x[0] + first * pitch)
    d = s[:, None] - pitch * np.arange(offsets)
    w = np.exp((d * d + ((y - line_y) ** 2)[:, None]) * (-1.0 / radius**2))
    keep = ((lines >= 0) & (lines < n_lines) & (w >= tol)).ravel()  # scatterer-major
    j = np.repeat(np.arange(x.size), offsets)[keep]
    line, w = lines.ravel()[keep], w.ravel()[keep]
    # stable sort by line (radix sort of small integers): within a line, by scatterer
    order = np.argsort(line.astype(np.int16 if n_lines < 2**15 else np.int64), kind="stable")
    return j[order], line[order], w[order]


def _exclusive_by_run(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Exclusive cumulative sum of ``values``, every element of a run (``starts`` True at its
    first element) taking its run's first value."""
    before = np.cumsum(values) - values
    first = np.where(starts, np.arange(values.size), 0)
    return before[np.maximum.accumulate(first)]


def shadowing(zs, energy, j, line, w, n_lines, mode):
    """``T`` of every pair ``(j, line)`` (pairs ordered by line, then by depth ``zs[j]``)."""
    if mode == "none":
        return np.ones_like(w)
    loss = (energy * 0.01)[j] * (w * w)
    if mode == "mean":
        per = np.bincount(j, weights=loss, minlength=zs.size) / n_lines
        starts = np.ones(zs.size, bool)
        starts[1:] = zs[1:] != zs[:-1]
        return np.exp(-_exclusive_by_run(per, starts))[j]
    zj = zs[j]
    starts = np.ones(j.size, bool)
    starts[1:] = (line[1:] != line[:-1]) | (zj[1:] != zj[:-1])
    c = _exclusive_by_run(loss, starts)
    # subtract each line's total before it (runs never cross lines)
    new_line = np.ones(j.size, bool)
    new_line[1:] = line[1:] != line[:-1]
    total_before = np.cumsum(loss) - loss
    c -= total_before[np.maximum.accumulate(np.where(new_line, np.arange(j.size), 0))]
    return np.exp(-c)


def bscan_field(
    table: np.ndarray,
    *,
    n_pixels: int,
    depth_range: float,
    k0: float,
    line_x: np.ndarray,
    line_y: float,
    radius: float,
    spectrum: np.ndarray | None = None,
    shadow: str = "line",
    tol: float = TOL,
    eps: float = EPS,
    nthreads: int | None = None,
) -> np.ndarray:
    """Complex field ``(n_lines, n_pixels)`` of one B-scan (the module docstring's formula).

    ``table`` is ``(M, 4)``: X, Y, Z (µm), Energy (%). Depths outside ``[0, H)`` wrap around in
    the image (the model's finite unambiguous depth) and shadow by their ``Z``.
    """
    if shadow not in SHADOWING:
        raise ValueError(f"shadow must be one of {SHADOWING}, got {shadow!r}")
    spec = hann_spectrum(n_pixels) if spectrum is None else np.asarray(spectrum, float)
    order = np.argsort(table[:, 2], kind="stable")
    x, y, z, energy = (np.ascontiguousarray(table[order, c]) for c in range(4))
    n_lines = line_x.size
    j, line, w = beam_pairs(x, y, line_x, line_y, radius, tol)
    if j.size == 0:
        return np.zeros((n_lines, n_pixels), np.complex128)
    t = shadowing(z, energy, j, line, w, n_lines, shadow)
    base = np.sqrt(energy * 0.01) * np.exp(2j * k0 * z)
    # theta in [-pi, pi): e^{i n (theta + pi)} = (-1)^n e^{i n theta}, corrected below
    theta = np.mod(z * (2 * math.pi / depth_range), 2 * math.pi) - math.pi
    phi = line * (2 * math.pi / n_lines) - math.pi
    f = finufft.nufft2d1(theta[j], phi, base[j] * (w * t), (n_pixels, n_lines), eps=eps,
                         isign=1, nthreads=threads(nthreads))  # fmt: skip
    n = np.arange(n_pixels) - n_pixels // 2
    m = np.arange(n_lines) - n_lines // 2
    f *= (spec * (-1.0) ** n)[:, None] * (((-1.0) ** m) / n_lines)[None, :]
    # lines: G[n, i] = (1/L) sum_m F[n, m] e^{-2 i pi m i/L}
    g = np.fft.fft(np.fft.ifftshift(f, axes=1), axis=1)
    # pixels: A[i, q] = sum_n S_n G[n, i] e^{-2 i pi n q/N}
    return np.fft.fft(np.fft.ifftshift(g, axes=0), axis=0).T


def direct_field(
    table: np.ndarray,
    *,
    n_pixels: int,
    depth_range: float,
    k0: float,
    line_x: np.ndarray,
    line_y: float,
    radius: float,
    spectrum: np.ndarray | None = None,
    shadow: str = "line",
) -> np.ndarray:
    """The same field by the direct double sum, every pair, shadowing by explicit comparisons
    of depths (the exact reference of :func:`bscan_field`; O(M^2 L) memory-light loops)."""
    spec = hann_spectrum(n_pixels) if spectrum is None else np.asarray(spectrum, float)
    x, y, z, e = (table[:, c] for c in range(4))
    w = np.exp(-((x[None, :] - line_x[:, None]) ** 2 + (y - line_y)[None, :] ** 2) / radius**2)
    loss = (e / 100.0)[None, :] * w**2  # (lines, M)
    above = z[None, :] < z[:, None]  # above[j, l]: l strictly above j
    if shadow == "line":
        c = loss @ above.T  # c[i, j] = sum_l loss[i, l] [z_l < z_j]
    elif shadow == "mean":
        c = np.broadcast_to(loss.mean(axis=0) @ above.T, w.shape)
    else:
        c = np.zeros_like(w)
    amp = np.sqrt(e / 100.0)[None, :] * w * np.exp(-c)  # (lines, M)
    n = np.arange(n_pixels) - n_pixels // 2
    k = k0 + n * math.pi / depth_range
    q = np.arange(n_pixels)
    psf = np.exp(2j * np.outer(z, k)) * spec  # (M, N)
    spectra = amp @ psf  # (lines, N): sum_j amp_ij S_n e^{2 i k_n z_j}
    return spectra @ np.exp(-2j * np.pi * np.outer(n, q) / n_pixels)


def to_levels(field: np.ndarray, dynamic_range: float = DYNAMIC_RANGE) -> np.ndarray:
    """8-bit levels of ``20 log10 |A|`` in a window ``dynamic_range`` dB deep whose top is the
    field's maximum: ``floor(256 (L - L_max + DR)/DR)`` clipped to 0..255 (Matplotlib's
    256-entry gray map, as the official scanner writes). An all-zero field gives 0."""
    mag = np.abs(field)
    peak = float(mag.max(initial=0.0))
    if peak == 0.0:
        return np.zeros(mag.shape, np.uint8)
    with np.errstate(divide="ignore"):
        level = 20.0 * np.log10(mag / peak)  # <= 0 dB
    scaled = np.floor((level + dynamic_range) * (LEVELS / dynamic_range))
    return np.clip(scaled, 0, LEVELS - 1).astype(np.uint8)


def scan_fields(table: np.ndarray, config, **options) -> np.ndarray:
    """Complex fields ``(n_bscans, depth, x)`` of a phantom table under ``config`` (a
    :class:`speckle.synthoct.files.ScannerConfig`); ``options`` as :func:`bscan_field`'s."""
    fields = [
        bscan_field(
            table,
            n_pixels=config.n_pixels,
            depth_range=config.depth_range,
            k0=config.k0,
            line_x=config.line_positions,
            line_y=float(yb),
            radius=config.beam_radius,
            **options,
        ).T
        for yb in config.bscan_positions
    ]
    return np.stack(fields)


def scan_levels(table: np.ndarray, config, **options) -> np.ndarray:
    """The official scan: uint8 ``(depth, x)`` (several B-scans: stacked down the rows, one
    window over them all)."""
    levels = to_levels(scan_fields(table, config, **options))
    return np.ascontiguousarray(levels.reshape(-1, config.n_lines))
