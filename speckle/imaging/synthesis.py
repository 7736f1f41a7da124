"""Choosing a synthesis method: error and cost models, and ``method="auto"``.

``speckle.ascan(..., method="auto", tol=tol)`` runs the fastest method whose *predicted*
relative error on this scene, ``||A - A_direct||_2 / ||A_direct||_2`` over all lines and pixels,
is at most ``tol``. Nothing is run to decide: the predictions come from each method's parameters.

Error rules (derivations in the method modules; checked in ``tests/test_synthesis.py``, the
benchmark and the failure map):

``direct``
    0 (float64 rounding, ~1e-15): always admissible.
``nufft``
    ES kernel of width ``w`` from :func:`~speckle.imaging.nufft.kernel_width` at upsampling 2:
    aliasing error ~``10**(1-w) <= tol/2``; the worst of 300 random scenes per tolerance
    (1e-1 ... 1e-12) is 0.1-0.56 ``tol``; the prediction is ``tol`` (a bound). Not admissible
    below ``1e-13`` (kernel width cap 16).
``nufft32``
    kernel at ``tol/2`` (so <= ``tol/2``) plus float32 rounding
    :func:`speckle.imaging.nufft.float32_error_estimate`
    (``~eps32/2 sqrt(2 + M w/(2N) + log2(2N) + log2 N)``, 3-6e-7 for 4-32 scatterers/pixel).
    The carrier phase is reduced in float64 first, so the error does not grow with
    ``2 k0 z``; a naive float32 phase would err by ~``eps32 2 k0 z``
    (:func:`speckle.imaging.carrier.naive_float32_phase_error`), a mode this package never uses.
    Admissible when the rounding estimate is <= ``tol/2``.
``psf``
    truncation (PSF tail energy beyond the half-width) plus interpolation error
    (:func:`speckle.imaging.psf.psf_error_estimate`). On a rectangular spectrum the tail decays like
    ``1/(pi sqrt(hw))``, so a tight ``tol`` needs the full A-line (``hw = N//2``): then ``psf``
    is exact but costs ``M N`` per line, so the cost model prefers it only for tiny lines
    (N of order 10), never a truncated one.

Deep scatterers: the fast methods place scatterers with ``z * (1/H)`` and reduce the carrier
phase with a three-term ``2 pi`` in float64, which loses ~``eps |z|/H`` (position) and
``eps |2 k0 z| 3e-4`` (carrier) of relative accuracy
(:func:`speckle.imaging.carrier.float64_error_estimate`, ~1e-14 for depths within a few ``H``,
1e-2 at ``|z|`` ~ 1e15 µm). ``nufft`` admits it up to ``tol/4``, ``nufft32`` within its
``tol/2`` rounding budget and ``psf`` within ``tol`` minus its own error; beyond that they
refuse and ``auto`` does not choose them. ``direct`` and ``finufft`` reduce ``z mod H``
exactly and stay within ``tol``.

Cost model: nanoseconds per call, fitted on the benchmark machine (Intel Xeon, 2 cores) for
``N = 64 ... 1024`` and 2-32 scatterers per pixel (within a factor ~1.5). It only orders methods, so
errors in it cost speed, never accuracy.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_int
from .aline import METHODS, register_method
from .carrier import float64_error_estimate
from .nufft import (
    DEFAULT_TOL,
    FLOAT64_SHARE,
    NUFFT_TOL_FLOOR,
    fine_grid_size,
    float32_error_estimate,
    kernel_width,
)
from .psf import _slots, psf_error_estimate

__all__ = ["AUTO_CANDIDATES", "choose_method", "method_estimates", "stream_ascans"]

#: Methods ``"auto"`` chooses from (``"finufft"`` is always slower than ``"nufft"``: benchmark).
AUTO_CANDIDATES = ("direct", "nufft", "nufft32", "psf")


def _estimate(
    method: str, n_lines: int, n_scat: int, n_pix: int, spectrum, tol: float, e64: float = 0.0
):
    """(predicted relative error, predicted time in ns) of one method on a scene.

    ``e64``: float64 carrier/position error of the fast methods on this scene's depths
    (:func:`speckle.imaging.carrier.float64_error_estimate`; 0 for depths within a few ``H``).
    """
    b, m, n = n_lines, n_scat, n_pix
    if method == "direct":
        return 0.0, 62.0 * b * m * n + 3000.0 * b
    if method == "nufft":
        if tol < NUFFT_TOL_FLOOR or e64 > FLOAT64_SHARE * tol:
            return math.inf, math.inf
        w = kernel_width(tol)
        nf = fine_grid_size(n, w)
        return tol, b * (15000.0 + 30.0 * nf) + b * m * (25.0 + 6.0 * w)
    if method == "nufft32":
        w = kernel_width(0.5 * tol)
        nf = fine_grid_size(n, w)
        rounding = float32_error_estimate(m, n, w) + e64
        err = 0.5 * tol + rounding if rounding <= 0.5 * tol else math.inf
        return err, b * (15000.0 + 20.0 * nf) + b * m * (18.0 + 3.5 * w)
    if method == "psf":
        err, hw, rows = psf_error_estimate(spectrum, tol)
        err += e64
        if err > tol:
            return math.inf, math.inf
        _, nk = _slots(n, hw)
        table = 40.0 * rows * nk
        return err, table + b * (5000.0 + 10.0 * n) + b * m * (20.0 + 3.0 * nk)
    raise ValueError(f"no error/cost model for method {method!r}")


def method_estimates(
    n_lines: int,
    n_scatterers: int,
    n_pixels: int,
    spectrum: np.ndarray | None,
    tol: float | None,
    *,
    float64_error: float = 0.0,
) -> dict[str, dict[str, float]]:
    """Predicted relative error and time (ns) of every ``auto`` candidate on a scene.

    Parameters
    ----------
    n_lines, n_scatterers, n_pixels : int
        A-lines ``B``, scatterers per line ``M`` (padding included) and pixels ``N``.
    spectrum : array_like or None
        ``N`` spectral weights (None: rectangular).
    tol : float or None
        Requested relative accuracy (None: :data:`speckle.imaging.nufft.DEFAULT_TOL`).
    float64_error : float
        :func:`speckle.imaging.carrier.float64_error_estimate` of the scene (depends on the
        depths; 0 means depths within a few ``H``): a method whose budget it exceeds is not
        admissible.

    Returns
    -------
    dict
        ``{method: {"error": e, "cost_ns": t, "admissible": e <= tol}}``.
    """
    tolv = DEFAULT_TOL if tol is None else float(tol)
    s = np.ones(n_pixels) if spectrum is None else np.asarray(spectrum, dtype=float)
    out = {}
    for name in AUTO_CANDIDATES:
        err, cost = _estimate(name, n_lines, n_scatterers, n_pixels, s, tolv, float64_error)
        out[name] = {"error": err, "cost_ns": cost, "admissible": bool(err <= tolv)}
    return out


def _psf_floor_ns(n_lines: int, n_scat: int, n_pix: int) -> float:
    """Lower bound of the psf cost (one slot per scatterer): skips its estimate when beaten."""
    return n_lines * (5000.0 + 10.0 * n_pix) + n_lines * n_scat * 23.0


def choose_method(
    n_lines: int,
    n_scatterers: int,
    n_pixels: int,
    spectrum: np.ndarray | None,
    tol: float | None,
    *,
    float64_error: float = 0.0,
) -> str:
    """Name of the fastest admissible method (see :func:`method_estimates`); never runs one."""
    tolv = DEFAULT_TOL if tol is None else float(tol)
    s = np.ones(n_pixels) if spectrum is None else np.asarray(spectrum, dtype=float)
    ok = {}
    for name in AUTO_CANDIDATES:
        if name == "psf" and _psf_floor_ns(n_lines, n_scatterers, n_pixels) >= min(ok.values()):
            continue  # cannot win whatever its half-width: no need to estimate it
        err, cost = _estimate(name, n_lines, n_scatterers, n_pixels, s, tolv, float64_error)
        if err <= tolv:
            ok[name] = cost
    return min(ok, key=ok.get)


@register_method("auto")
def _auto(z, amplitude, n_pixels, depth, k0, spectrum, tol):
    e64 = float64_error_estimate(z, amplitude, depth, k0, spectrum)
    name = choose_method(z.shape[0], z.shape[1], n_pixels, spectrum, tol, float64_error=e64)
    return METHODS[name](z, amplitude, n_pixels, depth, k0, spectrum, tol)


def stream_ascans(
    n_alines: int,
    density: float,
    *,
    n_pixels: int,
    depth: float,
    k0: float,
    seed: int,
    spectrum: np.ndarray | None = None,
    method: str = "auto",
    tol: float | None = None,
    amplitude: str = "equal",
    count: str = "fixed",
    chunk_lines: int = 256,
    lines: object | None = None,
) -> np.ndarray:
    """Random-scene A-scans generated and imaged ``chunk_lines`` lines at a time.

    Scatterers of lines ``i ... i + chunk_lines - 1`` are drawn with
    :func:`speckle.random_scatterers` (``first_aline=i``, so the result does not
    depend on ``chunk_lines``) and imaged with :func:`speckle.ascan`; only one chunk of
    scatterers is alive at a time, so peak memory is the output plus one chunk whatever
    ``n_alines`` (measured in ``benchmarks/bench_ascan.py``).

    Parameters
    ----------
    n_alines, density, n_pixels, depth, seed, amplitude, count
        Scene of :func:`speckle.random_scatterers` (``depth`` in µm).
    k0, spectrum, method, tol
        Imaging, as in :func:`speckle.ascan` (``k0`` in rad/µm).
    chunk_lines : int
        A-lines generated and imaged at once (>= 1).
    lines : sequence of int, optional
        Only these A-line indices (each in ``[0, n_alines)``) are generated and imaged, in the
        given order; the values equal the same rows of the full scene.

    Returns
    -------
    numpy.ndarray
        complex128 (n_alines, n_pixels), or (len(lines), n_pixels) with ``lines``.
    """
    from ..scene.scatterers import random_scatterers
    from .aline import ascan

    nl_total = check_int(n_alines, "n_alines", low=1)
    step = check_int(chunk_lines, "chunk_lines", low=1)
    if lines is None:
        wanted = np.arange(nl_total)
    else:
        wanted = np.asarray(lines)
        if wanted.ndim != 1 or not np.issubdtype(wanted.dtype, np.integer):
            raise TypeError("lines must be a 1-D sequence of integer A-line indices")
        if wanted.size and (wanted.min() < 0 or wanted.max() >= nl_total):
            raise ValueError(f"lines must lie in [0, {nl_total - 1}]")
    out = np.empty((wanted.size, n_pixels), dtype=np.complex128)
    order = np.argsort(wanted, kind="stable")
    sorted_lines = wanted[order]
    # consecutive runs of requested lines, each drawn in chunks of at most `step` lines
    breaks = np.flatnonzero(np.diff(sorted_lines) != 1) + 1
    pos = 0
    for run in np.split(sorted_lines, breaks):
        for c0 in range(0, run.size, step):
            first, nl = int(run[c0]), min(step, run.size - c0)
            scene = random_scatterers(
                nl,
                density,
                n_pixels=n_pixels,
                depth=depth,
                seed=seed,
                amplitude=amplitude,
                count=count,
                first_aline=first,
            )
            out[order[pos : pos + nl]] = ascan(
                scene["z"].values,
                scene["amplitude"].values,
                n_pixels=n_pixels,
                depth=depth,
                k0=k0,
                spectrum=spectrum,
                method=method,
                tol=tol,
            )
            pos += nl
    return out
