"""Fast scanned-beam B-scans and C-scans: ES-kernel spreading in depth, exact Gaussian lateral
weights on a uniform grid of lines.

For lines on a uniform grid ``X_o = X_0 + o p`` (and ``Y`` likewise in 3-D) the beam sum is

    A(o, q) = sum_n S_n e^{-2i pi n q/N} F_n(o),   F_n(o) = sum_j c_j e^{i n t_j} W_j(o),

``c_j = a_j exp(2i k0 z_j)``, ``t_j = 2 pi z_j/H``, ``W_j(o) = gamma_j^2 exp(-b_j (s_j - o)^2)``
the double-pass weight (``s_j = (x_j - X_0)/p`` in pitches, ``b_j = 2 gamma_j p^2/w0^2``,
``gamma_j = 1`` without focus; :mod:`speckle.imaging.beam`). For every line ``o``, ``F_n(o)``
is the type-1 NUFFT of :mod:`speckle.imaging._methods.nufft` of the strengths ``c_j W_j(o)``: so
each scatterer is spread once in depth with the ES kernel (width ``w`` from ``tol``) and written,
times its exact Gaussian weight, into the fine grids of the lines within its lateral reach;
one batched inverse FFT per line, the deconvolution-and-spectrum multiplier and the exact pixel
DFT follow (:func:`speckle.imaging._methods.nufft.fine_to_pixels`). There is no lateral FFT, hence
no lateral periodisation or padding: lines beyond the grid are simply not written. The weights are
formed by a two-exponential recurrence (re-anchored every 16 lines), scatterers are bucketed by
line (counting sort), and blocks of lines run in parallel (numba), each over the scatterers
within reach of its block, so no two threads write the same line. With a focus the weights are
complex Gaussians whose width ``w(z_j)`` follows the scatterer's depth: the same code, the
reach growing with ``w(z_j)``. 3-D: the weight factorises, ``W = gamma^2 exp(-b_x d_x^2)
exp(-b_y d_y^2)``, and each scatterer is written into the ``K_x K_y`` lines of its reach.

A row or raster of lines under a beam without focus (the common B-scan or C-scan) takes the
row path of :mod:`speckle.imaging._methods.beam_row` (:func:`uses_row_path`): the same sums and
error budget, laid out for throughput (1.9x less time than the general code on the benchmark
scene, 1.5x less CPU time on a 3-D tile). The code here serves focused beams, beams narrower
than ``p/sqrt(32)`` and tolerances near the float64 floor.

Errors (relative l2 over the B-scan, against ``"direct"``), budgeted to add up below ``tol``:

* depth kernel: the ES kernel at ``tol/2`` (``"nufft"``; measured worst 0.56 of its target on
  random scenes, :mod:`speckle.imaging._methods.nufft`) or ``tol/4`` (``"nufft32"``);
* lateral truncation: weights below ``tol/4`` of a scatterer's peak weight are dropped (reach
  ``w(z) sqrt(ln(4/tol)/2)``). For a scene whose scatterers cover the scanned lines the
  dropped energy fraction is ``erfc(2 R/w) < (tol/4)^2``, i.e. an error below ``tol/4``; a scene
  whose scatterers all lie beyond the reach of every line images to (almost) zero and has no
  meaningful relative error (the bound then does not apply);
* the line grid: positions are fitted by ``X_0 + o p``; a residual ``d`` changes weights by
  ``~ 2 d/w0``: admissible only while ``4 d/w0 <= tol/8`` (float64 rounding of ``linspace``
  grids is ~1e-16 relative);
* ``"nufft32"`` only: float32 rounding of the spreading and FFTs,
  :func:`speckle.imaging._methods.nufft.float32_error_estimate` with the number of terms per line
  weighted by their relative weight energy (``sum_k exp(-4 d_k^2/w0^2) ~ w0 sqrt(pi)/(2 p)``
  lines per axis), admissible while ``<= tol/2``; measured floors are 1.4-1.6x below it on five
  scenes (w0 = 1-6 pitches, 1-16 scatterers per pixel per line).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import finufft
import numba
import numpy as np
import scipy.fft

from .._rules import (
    NUFFT_TOL_FLOOR,
    choose,
    estimate_table,
    finufft_threads,
    memory_limit,
    refuse_below_floor,
    refuse_float32,
    refuse_memory,
    resolve_tol,
)
from ..gaussian_beam import Beam, BeamScene
from ._beam_kernels import _sort_scene, _spread_beam
from ._kernels import (
    C2,
    LANES,
    parallel_section,
)
from .beam_row import (
    ROW_MAX_B,
    row_fine_grids,
    row_lines,
    row_path_bytes,
    row_weight_error,
    weight_rate,
)
from .carrier import float64_error_estimate
from .nufft import (
    FLOAT64_SHARE,
    check_float64_placement,
    fine_grid_plan,
    fine_grid_size,
    fine_to_pixels,
    float32_error_estimate,
    kernel_width,
)

__all__ = [
    "BEAM_AUTO_CANDIDATES",
    "PATHS",
    "LineGrid",
    "beam_estimates",
    "beam_finufft_method",
    "beam_nufft32_method",
    "beam_nufft_method",
    "beam_nufft_scan",
    "choose_beam_method",
    "finufft_beam_scan",
    "line_grid",
    "uses_row_path",
]

#: Methods ``method="auto"`` chooses from.
BEAM_AUTO_CANDIDATES = ("direct", "nufft", "nufft32")
#: Largest fine-grid rows over scanned lines (grid with gaps) relative to distinct lines.
MAX_GRID_FILL = 4
#: Outer lines per parallel block (at least twice the halo of the beam reach).
_BLOCK = 64
#: Scatterer-line weights below which a scan runs on one thread.
SERIAL_BELOW = 200_000
#: Depth bins per line bucket in 2-D (cache locality of the spreading).
_DEPTH_BINS = 32
#: Paths of :func:`beam_nufft_scan`: ``"auto"`` (the row path where :func:`uses_row_path`),
#: ``"row"`` (:mod:`speckle.imaging._methods.beam_row`, refused where it does not apply) or
#: ``"general"`` (the code here).
PATHS = ("auto", "row", "general")


class LineGrid(NamedTuple):
    """A uniform grid holding every scanned line.

    ``origin``/``pitch``/``size`` per lateral axis (x, or x and y; µm), ``rows`` the fine-grid
    row of each line (``o * n_inner + i``), ``outer`` the axis index (0 = x, 1 = y) whose lines
    are split over threads, ``deviation`` the largest distance (µm) of a line from its grid
    point.
    """

    origin: tuple[float, ...]
    pitch: tuple[float, ...]
    size: tuple[int, ...]
    rows: np.ndarray
    outer: int
    deviation: float


def _axis_grid(values: np.ndarray, default_pitch: float):
    """(origin, pitch, n, index per value, deviation) of a uniform grid through ``values``."""
    u = np.unique(values)
    if u.size == 1:
        return float(u[0]), default_pitch, 1, np.zeros(values.size, dtype=np.int64), 0.0
    pitch = float(np.min(np.diff(u)))
    idx_u = np.rint((u - u[0]) / pitch)
    # least-squares origin and pitch through the grid indices (removes accumulated rounding)
    pitch, origin = np.polyfit(idx_u, u, 1) if u.size > 2 else (pitch, float(u[0]))
    idx = np.rint((values - origin) / pitch).astype(np.int64)
    dev = float(np.max(np.abs(values - (origin + idx * pitch))))
    return float(origin), float(pitch), int(idx.max()) + 1, idx, dev


def line_grid(lines: np.ndarray, waist: float) -> LineGrid | None:
    """The uniform grid of ``lines`` ((L,) or (L, 2), µm), or None when they do not lie on one.

    A grid may have gaps (lines not scanned), as long as it holds at most
    :data:`MAX_GRID_FILL` times more points than distinct lines along each axis; a line more
    than 1e-6 pitch from its grid point means the lines are irregular.
    """
    cols = lines[:, None] if lines.ndim == 1 else lines
    axes = [_axis_grid(cols[:, k], waist) for k in range(cols.shape[1])]
    for (_origin, pitch, n, _idx, dev), col in zip(axes, cols.T, strict=True):
        if n > MAX_GRID_FILL * np.unique(col).size or dev > 1e-6 * pitch:
            return None
    sizes = tuple(a[2] for a in axes)
    outer = int(np.argmax(sizes))
    if len(axes) == 1:
        rows = axes[0][3]
    else:
        inner = 1 - outer
        rows = axes[outer][3] * sizes[inner] + axes[inner][3]
    return LineGrid(
        origin=tuple(a[0] for a in axes),
        pitch=tuple(a[1] for a in axes),
        size=sizes,
        rows=rows,
        outer=outer,
        deviation=max(a[4] for a in axes),
    )


# --- the method --------------------------------------------------------------------------


def uses_row_path(beam: Beam, grid: LineGrid, tol: float) -> bool:
    """Whether a scan takes the row path (:mod:`speckle.imaging._methods.beam_row`): a row or raster
    of lines without focus, ``b = 2 p^2/w0^2 <= ROW_MAX_B`` along each axis and weights
    accurate to ``tol/8``."""
    if beam.focus is not None:
        return False
    w0 = beam.waist
    return (
        max(weight_rate(p, w0) for p in grid.pitch) <= ROW_MAX_B
        and sum(row_weight_error(p, w0) for p in grid.pitch) <= tol / 8
    )


class _Layout(NamedTuple):
    """Buckets and blocks of the general path (:func:`beam_nufft_scan`)."""

    gam: np.ndarray  # gamma per scatterer, or [1]
    wmax: float  # widest beam over the scene (µm)
    three_d: bool
    o_ax: int
    i_ax: int
    n_outer: int
    n_inner: int
    r_o: float  # reach in outer / inner pitches
    r_i: float
    halo: int
    bli: int
    nbi: int
    block: int
    kmax_i: int


def _general_layout(scene: BeamScene, beam: Beam, grid: LineGrid, ln_cut: float) -> _Layout:
    gam = beam.gamma(scene.z)
    gam = np.ones(1, dtype=np.complex128) if gam is None else np.ascontiguousarray(gam)
    # widest beam on the scene: sets the bucket halo and the weight buffers
    wmax = beam.waist / math.sqrt(float(np.min(gam.real)))
    reach = wmax * math.sqrt(ln_cut / 2.0)  # µm
    three_d = len(grid.size) == 2
    o_ax = grid.outer
    i_ax = 1 - o_ax if three_d else 0
    n_outer = grid.size[o_ax]
    n_inner = grid.size[i_ax] if three_d else 1
    r_o = reach / grid.pitch[o_ax]
    r_i = reach / grid.pitch[i_ax]
    halo = math.ceil(r_o) + 1
    bli = math.ceil(r_i) + 1
    nbi = n_inner + 2 * bli if three_d else _DEPTH_BINS
    # blocks of outer lines: independent of the thread count, so results are bitwise the same
    # on any number of threads (the vectorised loops would round differently per blocking)
    block = min(n_outer, max(_BLOCK, 2 * halo))
    kmax_i = int(2 * r_i) + 2 if three_d else 1
    return _Layout(gam, wmax, three_d, o_ax, i_ax, n_outer, n_inner, r_o, r_i, halo, bli, nbi,
                   block, kmax_i)  # fmt: skip


def _peak_bytes(scene, beam, grid, ln_cut, nf, w, precision, row):
    """Peak-memory estimate (bytes, by part) of :func:`beam_nufft_scan` and, per part, the
    parameter to change (for :func:`speckle.imaging._rules.refuse_memory`)."""
    rs = 8 if precision == "double" else 4
    m = scene.z.size
    n_rows = math.prod(grid.size)
    lines = (
        "reduce the number of lines per call (scan in parts, e.g. speckle.scan_image with a "
        "smaller chunk) or n_pixels"
    )
    advice = {
        "grids": lines,
        "pixels": lines,
        "scatterers": "reduce the number of scatterers per call (scan in parts)",
    }
    # fine_to_pixels: field, its FFT and the complex128 result, per fine-grid row
    pixels = 3.0 * n_rows * scene.n_pixels * 16
    if row:
        axes = (grid.outer, 1 - grid.outer) if len(grid.size) == 2 else (0,)
        parts = row_path_bytes(
            tuple(grid.size[k] for k in axes), tuple(grid.pitch[k] for k in axes), beam.waist,
            ln_cut, n_scatterers=m, nf=nf, w=w, itemsize=rs,
        )  # fmt: skip
        advice["buckets"] = lines
        return {**parts, "pixels": pixels}, advice
    lay = _general_layout(scene, beam, grid, ln_cut)
    nb = (lay.n_outer + 2 * lay.halo) * lay.nbi
    n_chunks = max(1, min(64, m // 16384))
    wp = LANES * -(-w // LANES)
    # scatterers one block reads: those of its block plus twice the halo of buckets
    m_block = m * min(1.0, (lay.block + 2 * lay.halo) / (lay.n_outer + 2 * lay.halo))
    per_thread = lay.block * lay.n_inner * 2 * (nf + 2 * wp) * rs + m_block * (32 + w * rs)
    parts = {
        "grids": float(n_rows * nf * 2 * rs),
        "pixels": pixels,
        "scatterers": float(m) * (16 + 56),
        "buckets": 16.0 * n_chunks * nb + numba.get_num_threads() * per_thread,
    }
    advice["buckets"] = (
        f"the beam's reach on this scene (widest beam {lay.wmax:.3g} µm over the scatterers' "
        f"depths, {lay.halo} pitches) sets buckets and blocks; use method='direct', or image "
        "depths nearer the focus (or a longer rayleigh_range)"
    )
    return parts, advice


def _row_path(beam: Beam, grid: LineGrid, tol: float, path: str) -> bool:
    """Whether ``path`` (one of :data:`PATHS`) runs the row path; ``ValueError`` for
    ``path="row"`` where the row path does not apply."""
    if path not in PATHS:
        raise ValueError(f"path must be one of {PATHS}, got {path!r}")
    row = uses_row_path(beam, grid, tol)
    if path == "row" and not row:
        raise ValueError(
            "path='row' needs a beam without focus, b = 2 pitch^2/waist^2 <= "
            f"{ROW_MAX_B:g} and weights accurate to tol/8 (see uses_row_path); use path='auto'"
        )
    return row and path != "general"


def beam_nufft_scan(
    scene: BeamScene,
    beam: Beam,
    grid: LineGrid,
    *,
    tol: float,
    precision: str = "double",
    path: str = "auto",
) -> np.ndarray:
    """Scanned-beam lines by depth spreading and exact lateral weights (module docstring).

    ``tol`` is the accuracy of the depth kernel and the weight cut-off is ``ln_cut``-derived
    from ``tol`` as in the error budget of :func:`beam_nufft_method`: here ``tol`` sets the
    kernel (``fine_grid_plan(tol)``) and lateral weights below ``tol/2`` of the peak are
    dropped. ``path`` (:data:`PATHS`): ``"auto"`` takes the row path of
    :mod:`speckle.imaging._methods.beam_row` where :func:`uses_row_path`, ``"general"`` the code
    here always (the benchmark's baseline of the row path), ``"row"`` the row path or a
    ``ValueError``. Returns complex128 (L, N) in the order of ``scene.lines``.
    """
    plan = fine_grid_plan(scene.n_pixels, scene.spectrum, tol, precision)
    ln_cut = math.log(2.0 / tol)
    w0 = beam.waist
    row = _row_path(beam, grid, tol, path)
    method = "nufft" if precision == "double" else "nufft32"
    parts, advice = _peak_bytes(scene, beam, grid, ln_cut, plan.nf, plan.w, precision, row)
    refuse_memory(method, parts, advice)
    if row:
        # the grid's axes, outer first (the row path splits blocks of outer lines over threads)
        axes = (grid.outer, 1 - grid.outer) if len(grid.size) == 2 else (0,)
        coords = (scene.x, scene.y)
        lines_per = row_lines(w0, grid.pitch, ln_cut)
        # small scans run on one thread: waking the pool costs more than it saves
        with parallel_section(serial=scene.z.size * lines_per < SERIAL_BELOW, slp=True):
            g = row_fine_grids(
                tuple(coords[k] for k in axes), scene.z, scene.amplitude,
                origin=tuple(grid.origin[k] for k in axes),
                pitch=tuple(grid.pitch[k] for k in axes),
                size=tuple(grid.size[k] for k in axes), waist=w0, k0=scene.k0,
                depth_range=scene.depth_range, plan=plan, ln_cut=ln_cut,
            )  # fmt: skip
        return fine_to_pixels(g, plan)[grid.rows]
    lay = _general_layout(scene, beam, grid, ln_cut)
    gam, three_d, o_ax, i_ax = lay.gam, lay.three_d, lay.o_ax, lay.i_ax
    n_outer, n_inner, r_o, r_i = lay.n_outer, lay.n_inner, lay.r_o, lay.r_i
    halo, bli, nbi, block, kmax_i = lay.halo, lay.bli, lay.nbi, lay.block, lay.kmax_i
    p_o, p_i = grid.pitch[o_ax], grid.pitch[i_ax]
    y = scene.y if three_d else np.zeros(1)
    g = np.zeros((n_outer * n_inner, plan.nf), dtype=plan.cplx)
    # small scans run on one thread: waking the pool costs more than it saves
    small = scene.z.size * (2 * r_o + 1) * ((2 * r_i + 1) if three_d else 1) < SERIAL_BELOW
    with parallel_section(serial=small, slp=True):
        z, a, so, si, gam, starts = _sort_scene(
            scene.x, y, scene.z, scene.amplitude, gam, three_d, o_ax, grid.origin[o_ax],
            p_o, r_o, n_outer, halo, grid.origin[i_ax], p_i, r_i, n_inner, bli, scene.depth_range,
            nbi,
        )  # fmt: skip
        _spread_beam(
            z, a, scene.k0, scene.depth_range, so, si, gam, weight_rate(p_o, w0),
            weight_rate(p_i, w0), ln_cut, starts, nbi, n_outer, n_inner, three_d, block, halo,
            kmax_i, plan.nf, plan.w, plan.coef, g.view(plan.real),
        )  # fmt: skip
    return fine_to_pixels(g, plan)[grid.rows]


# --- error and cost models, auto ---------------------------------------------------------


class _Setup(NamedTuple):
    grid: LineGrid | None
    n_rows: int  # fine-grid rows (lines of the grid)
    terms_per_row: float  # scatterer-line weights written per row (slots)
    weighted_terms: float  # the same weighted by relative weight energy (float32 rounding)


def _setup(scene: BeamScene, beam: Beam, tol: float) -> _Setup:
    grid = line_grid(scene.lines, beam.waist)
    if grid is None:
        return _Setup(None, 0, 0.0, 0.0)
    n_rows = int(np.prod(grid.size))
    gam = beam.gamma(scene.z)
    # mean beam width over the scatterers (w(z) = w0 / sqrt(Re gamma) with a focus)
    width = beam.waist * (1.0 if gam is None else float(np.mean(1.0 / np.sqrt(gam.real))))
    reach = width * math.sqrt(math.log(4.0 / tol) / 2.0)
    slots = 1.0
    energy = 1.0
    for p, n in zip(grid.pitch, grid.size, strict=True):
        slots *= min(n, 2 * reach / p + 1)
        # sum over lines of the squared relative weight exp(-4 d^2/w0^2) ~ w0 sqrt(pi)/(2 p)
        energy *= max(1.0, min(n, beam.waist * math.sqrt(math.pi) / (2 * p)))
    per_row = scene.z.size / n_rows
    return _Setup(grid, n_rows, per_row * slots, per_row * energy)


def _row_cost(setup, beam, m, nf, w, tol_arg, *, per_cell, per_slot):
    """Time (ns, one thread) of the row path: sort and weights per scatterer, two 8-wide
    axpys per line written and kernel group, FFTs per fine-grid cell (fitted to
    ``benchmarks/bench_beam.py``: 27 + 10 ns per scatterer, 17 ns per fine cell)."""
    lines = row_lines(beam.waist, setup.grid.pitch, math.log(2.0 / tol_arg))
    slots = 8 * -(-w // 8)
    return 8e5 + setup.n_rows * per_cell * nf + m * (37.0 + per_slot * lines * slots)


def _estimate(method: str, scene: BeamScene, beam: Beam, tol: float, setup: _Setup):
    """(predicted relative error, predicted time in ns) of a beam method on a scene."""
    n = scene.n_pixels
    n_lines = scene.lines.shape[0]
    m = scene.z.size
    if method == "direct":
        # scatterers within the underflow reach of a line, from the scene's lateral density
        span = float(np.ptp(scene.x)) + beam.waist
        frac = min(1.0, 2 * 19.3 * beam.waist / span)
        if scene.y is not None:
            frac *= min(1.0, 2 * 19.3 * beam.waist / (float(np.ptp(scene.y)) + beam.waist))
        return 0.0, n_lines * (62.0 * m * frac * n + 3000.0 + 300.0 * n + 5.0 * m)
    if setup.grid is None or tol < NUFFT_TOL_FLOOR:
        return math.inf, math.inf
    grid_err = 4.0 * setup.grid.deviation / beam.waist
    if grid_err > tol / 8:
        return math.inf, math.inf
    slots = setup.terms_per_row * setup.n_rows  # scatterer-line weights written
    if method == "nufft" and _placement_bound(scene) > FLOAT64_SHARE * tol:
        if float64_error_estimate(scene.z, scene.amplitude, scene.depth_range, scene.k0,
                                  scene.spectrum) > FLOAT64_SHARE * tol:  # fmt: skip
            return math.inf, math.inf
    if method in ("nufft", "nufft32"):
        # a method whose peak memory (with the beam's widest reach) exceeds MAX_BYTES is not
        # admissible: it would be refused (beam_nufft_scan)
        arg = 0.5 * tol if method == "nufft" else 0.25 * tol
        w = kernel_width(arg)
        precision = "double" if method == "nufft" else "single"
        row = uses_row_path(beam, setup.grid, arg)
        parts, _ = _peak_bytes(scene, beam, setup.grid, math.log(2.0 / arg),
                               fine_grid_size(n, w), w, precision, row)  # fmt: skip
        if sum(parts.values()) > memory_limit():
            return math.inf, math.inf
        # the buckets grow with the beam's widest reach (a short Rayleigh range): their
        # memory is written and read, a time the per-row model below does not see
        reach_cost = 0.0 if row else BUCKET_NS_PER_BYTE * parts["buckets"]
    if method == "nufft":
        w = kernel_width(0.5 * tol)
        nf = fine_grid_size(n, w)
        if uses_row_path(beam, setup.grid, 0.5 * tol):
            return tol, _row_cost(setup, beam, m, nf, w, 0.5 * tol, per_cell=17.0, per_slot=0.36)
        return tol, 8e5 + setup.n_rows * 40.0 * nf + m * 60.0 + slots * 1.2 * w + reach_cost
    if method == "nufft32":
        # float32 conversions cost per scatterer, narrower stores save per weight written
        # (measured: 10 % slower than "nufft" in 2-D at w0 = 2 pitches, 1.5x faster in 3-D;
        # on the row path, with Horner in float32, 1.1-1.2x faster than "nufft")
        w = kernel_width(0.25 * tol)
        rounding = float32_error_estimate(int(setup.weighted_terms), n, w)
        if rounding > 0.5 * tol:
            return math.inf, math.inf
        if _placement_bound(scene) > 0.5 * tol - rounding:
            e64 = float64_error_estimate(scene.z, scene.amplitude, scene.depth_range, scene.k0,
                                         scene.spectrum)  # fmt: skip
            if e64 > 0.5 * tol - rounding:
                return math.inf, math.inf
        nf = fine_grid_size(n, w)
        if uses_row_path(beam, setup.grid, 0.25 * tol):
            cost = _row_cost(setup, beam, m, nf, w, 0.25 * tol, per_cell=12.0, per_slot=0.28)
        else:
            cost = 8e5 + setup.n_rows * 30.0 * nf + m * 130.0 + slots * 0.75 * w + reach_cost
        return 0.5 * tol + rounding, cost
    raise ValueError(f"no error/cost model for beam method {method!r}")


#: Time (ns) per byte of the general path's buckets (:func:`_peak_bytes`), measured (issue 36:
#: 2000 scatterers, 64 lines, focus 10 µm, Rayleigh range 1 to 0.01 µm: 2.7 ns/byte as the
#: buckets grew from 56 to 553 MiB, 0.22 to 1.56 s). Without it ``auto`` took ``nufft`` at any
#: Rayleigh range, up to memory the machine did not have, where ``direct`` computed the image.
BUCKET_NS_PER_BYTE = 2.5


def _estimator(scene: BeamScene, beam: Beam, tol: float):
    setup = _setup(scene, beam, tol)

    def estimate(name: str) -> tuple[float, float]:
        return _estimate(name, scene, beam, tol, setup)

    return estimate


def beam_estimates(scene: BeamScene, beam: Beam, tol: float | None) -> dict[str, dict]:
    """Predicted relative error and time (ns) of every ``auto`` candidate on a scene:
    ``{method: {"error": e, "cost_ns": t, "admissible": e <= tol}}``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, x, a = np.array([100.0]), np.array([0.0]), np.array([1.0 + 0j])
    >>> lines = speckle.scan_lines(3, 4.0, start=-4.0)
    >>> scene, beam, tol = speckle.beam_problem(
    ...     z, x, a, lines=lines, waist=4.0, n_pixels=32, depth_range=256.0, k0=3.0, tol=1e-6
    ... )
    >>> estimates = speckle.beam_estimates(scene, beam, tol)
    >>> sorted(next(iter(estimates.values())))
    ['admissible', 'cost_ns', 'error']
    """
    tolv = resolve_tol(tol)
    return estimate_table(BEAM_AUTO_CANDIDATES, _estimator(scene, beam, tolv), tolv)


def choose_beam_method(scene: BeamScene, beam: Beam, tol: float | None) -> str:
    """Name of the fastest admissible beam method (:func:`beam_estimates`); never runs one.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, x, a = np.array([100.0]), np.array([0.0]), np.array([1.0 + 0j])
    >>> lines = speckle.scan_lines(3, 4.0, start=-4.0)
    >>> scene, beam, tol = speckle.beam_problem(
    ...     z, x, a, lines=lines, waist=4.0, n_pixels=32, depth_range=256.0, k0=3.0, tol=1e-6
    ... )
    >>> speckle.choose_beam_method(scene, beam, tol) in speckle.imaging.BEAM_METHODS
    True
    """
    tolv = resolve_tol(tol)
    return choose(BEAM_AUTO_CANDIDATES, _estimator(scene, beam, tolv), tolv)


def _placement_bound(scene: BeamScene) -> float:
    """Upper bound of :func:`speckle.imaging._methods.carrier.float64_error_estimate` from the
    deepest scatterer alone (``z_rms <= max |z|``, ``n_rms <= N/2``; one pass over the depths)."""
    zmax = float(np.max(np.abs(scene.z), initial=0.0))
    eps = float(np.finfo(np.float64).eps)
    position = math.pi * scene.n_pixels * eps * zmax / (math.sqrt(6.0) * scene.depth_range)
    carrier = eps * zmax * 2.0 * scene.k0 * C2 / (4.0 * math.pi * math.sqrt(3.0))
    return math.hypot(position, carrier) if 2.0 * scene.k0 * zmax < 2.0**47 else math.inf


def _check_placement(scene: BeamScene, budget: float, tol: float, method: str) -> None:
    """The float64 carrier/position refusal of the A-scan methods
    (:func:`speckle.imaging._methods.nufft.check_float64_placement`), on a beam scene; skipped when
    the deepest scatterer's bound is within the budget."""
    if _placement_bound(scene) > budget:
        check_float64_placement(scene.z, scene.amplitude, scene.depth_range, scene.k0,
                                scene.spectrum, budget, tol, method)  # fmt: skip


def _grid_or_refuse(scene: BeamScene, beam: Beam, tol: float, method: str) -> LineGrid:
    refuse_below_floor(tol, method)
    grid = line_grid(scene.lines, beam.waist)
    if grid is None:
        raise ValueError(
            f"method={method!r} needs lines on a uniform grid (a uniform row, or a uniform "
            "(x, y) raster in 3-D, gaps allowed); these are irregular: use method='direct' "
            "or method='auto' (which falls back to 'direct')"
        )
    if 4.0 * grid.deviation / beam.waist > tol / 8:
        raise ValueError(
            f"method={method!r}: lines deviate from a uniform grid by up to "
            f"{grid.deviation:.2e} µm, a weight error 4 deviation/waist = "
            f"{4 * grid.deviation / beam.waist:.1e} (waist {beam.waist:g} µm) above tol/8 = "
            f"{tol / 8:.1e}; use method='direct', a wider waist or a looser tol"
        )
    return grid


def beam_nufft_method(
    scene: BeamScene, beam: Beam, tol: float | None, *, path: str = "auto"
) -> np.ndarray:
    """``beam_scan(..., method="nufft")`` on a validated problem
    (:func:`speckle.imaging.gaussian_beam.beam_problem`); ``path`` as in
    :func:`beam_nufft_scan`."""
    tolv = resolve_tol(tol)
    grid = _grid_or_refuse(scene, beam, tolv, "nufft")
    _check_placement(scene, FLOAT64_SHARE * tolv, tolv, "nufft")
    # kernel at tol/2 (fine_grid_plan halves again internally), weights cut at tol/4
    return beam_nufft_scan(scene, beam, grid, tol=0.5 * tolv, path=path)


def beam_nufft32_method(
    scene: BeamScene, beam: Beam, tol: float | None, *, path: str = "auto"
) -> np.ndarray:
    """``beam_scan(..., method="nufft32")`` on a validated problem; ``path`` as in
    :func:`beam_nufft_scan`."""
    tolv = resolve_tol(tol)
    grid = _grid_or_refuse(scene, beam, tolv, "nufft32")
    setup = _setup(scene, beam, tolv)
    rounding = float32_error_estimate(int(setup.weighted_terms), scene.n_pixels,
                                      kernel_width(0.25 * tolv))  # fmt: skip
    refuse_float32(rounding, tolv)
    _check_placement(scene, 0.5 * tolv - rounding, tolv, "nufft32")
    # kernel at tol/4 and weights cut at tol/4 (beam_nufft_scan halves), rounding <= tol/2
    return beam_nufft_scan(scene, beam, grid, tol=0.25 * tolv, precision="single", path=path)


# --- FINUFFT: the lateral-Fourier way (reference and benchmark baseline) -----------------


def finufft_beam_scan(
    scene: BeamScene,
    beam: Beam,
    grid: LineGrid,
    *,
    tol: float,
    eps: float | None = None,
    nthreads: int | None = None,
    upsampfac: float | None = None,
) -> np.ndarray:
    """Depth-independent beam on a row of lines with one FINUFFT 2-D type-1 transform.

    ``T[n, m] = sum_j c_j exp(i n t_j) exp(i m phi_j)``, ``phi_j = 2 pi (x_j - X_0)/P`` over a
    lateral period ``P = L_p p`` padded by the beam reach on both sides (scatterers beyond the
    reach of every line are dropped, as in ``"nufft"``, so nothing wraps); the beam is applied in
    lateral Fourier space, ``g_hat(k) = w0 sqrt(pi/2) exp(-k^2 w0^2/8)`` at ``k = 2 pi m/P``
    with as many modes as keep ``g_hat`` above ``tol/4`` of its peak; the modes fold onto the
    ``L_p`` residues of the line grid and an FFT returns the lines, a second FFT the pixels.
    ``eps`` is FINUFFT's own tolerance (default ``tol/20``: FINUFFT's eps is not a bound on our
    relative error, see :func:`speckle.imaging._methods.nufft.finufft_ascan`).
    """
    if beam.focus is not None or len(grid.size) != 1:
        raise ValueError("the FINUFFT beam reference handles a 2-D scene without focus only")
    w0 = beam.waist
    p = grid.pitch[0]
    n_lines = grid.size[0]
    reach = w0 * math.sqrt(math.log(4.0 / tol) / 2.0)
    lp = scipy.fft.next_fast_len(n_lines + math.ceil(2 * reach / p) + 1)
    period = lp * p
    s = (scene.x - grid.origin[0]) / p
    kmax = math.sqrt(8.0 * math.log(4.0 / tol)) / w0
    n_modes = 2 * math.ceil(kmax * period / (2 * math.pi)) + 2
    # FINUFFT's upsampled grid (2x per axis), its modes, the folded modes and the lines
    parts = {
        "modes": 16.0 * scene.n_pixels * (4 * n_modes + n_modes + lp),
        "pixels": 3.0 * 16 * scene.n_pixels * n_lines,
    }
    refuse_memory("finufft", parts, {
        "modes": f"the beam's lateral modes ({n_modes} for waist {w0:g} µm over a period of "
        f"{period:.3g} µm) set it: use fewer lines per call or method='nufft'",
        "pixels": "reduce the number of lines per call or n_pixels",
    })  # fmt: skip
    keep = (s >= -reach / p) & (s <= n_lines - 1 + reach / p)
    if not np.any(keep):  # every scatterer beyond the reach of every line: a dark image
        return np.zeros((grid.rows.size, scene.n_pixels), dtype=np.complex128)
    z, a, s = scene.z[keep], scene.amplitude[keep], s[keep]
    c = a * np.exp(2j * scene.k0 * z)
    t = np.mod(z, scene.depth_range) * (2 * np.pi / scene.depth_range)
    phi = s * (2 * np.pi / lp)
    opts = {} if upsampfac is None else {"upsampfac": upsampfac}
    f = finufft.nufft2d1(
        t, phi, c, (scene.n_pixels, n_modes), eps=tol / 20 if eps is None else eps, isign=1,
        nthreads=finufft_threads() if nthreads is None else nthreads, **opts,
    )  # fmt: skip
    m = np.arange(n_modes) - n_modes // 2
    ghat = w0 * math.sqrt(math.pi / 2) * np.exp(-((2 * np.pi * m / period) ** 2) * w0**2 / 8)
    f *= ghat / period
    folded = np.zeros((scene.n_pixels, lp), dtype=np.complex128)
    for c0 in range(0, n_modes, lp):  # each run of < L_p modes has distinct residues
        folded[:, np.mod(m[c0 : c0 + lp], lp)] += f[:, c0 : c0 + lp]
    # lines: sum_r G_r exp(-2i pi r o/L_p) (weight g(x_j - X_o) = sum_m ... e^{-2 i pi m o/L_p})
    field = scipy.fft.fft(folded, axis=1, workers=-1)[:, :n_lines].T  # (lines, N)
    plan_phase = np.exp(2j * np.pi * (scene.n_pixels // 2) * np.arange(scene.n_pixels)
                        / scene.n_pixels)  # fmt: skip
    out = scipy.fft.fft(field * scene.spectrum, axis=-1, workers=-1) * plan_phase
    return out[grid.rows]


def beam_finufft_method(scene: BeamScene, beam: Beam, tol: float | None) -> np.ndarray:
    """``beam_scan(..., method="finufft")`` on a validated problem."""
    tolv = resolve_tol(tol)
    grid = _grid_or_refuse(scene, beam, tolv, "finufft")
    return finufft_beam_scan(scene, beam, grid, tol=tolv)
