"""Choosing a synthesis method: error and cost models, and ``method="auto"``.

``speckle.ascan(..., method="auto", tol=tol)`` runs the fastest method whose *predicted*
relative error on this scene, ``||A - A_direct||_2 / ||A_direct||_2`` over all lines and pixels,
is at most ``tol``. Nothing is run to decide: the predictions come from each method's parameters.

Error rules (derivations in the method modules; checked in ``tests/test_synthesis.py``, the
benchmark and the failure map):

``direct``
    0 (float64 rounding, ~1e-15): always admissible.
``nufft``
    ES kernel of width ``w`` from :func:`~speckle.imaging._methods.nufft.kernel_width` at upsampling
    2: aliasing error ~``10**(1-w) <= tol/2``; the worst of 300 random scenes per tolerance
    (1e-1 ... 1e-12) is 0.1-0.56 ``tol``; the prediction is ``tol`` (a bound). Not admissible
    below ``1e-13`` (kernel width cap 16).
``nufft32``
    kernel at ``tol/2`` (so <= ``tol/2``) plus float32 rounding
    :func:`speckle.imaging._methods.nufft.float32_error_estimate`
    (``~eps32/2 sqrt(2 + M w/(2N) + log2(2N) + log2 N)``, 3-6e-7 for 4-32 scatterers/pixel).
    The carrier phase is reduced in float64 first, so the error does not grow with
    ``2 k0 z``; a naive float32 phase would err by ~``eps32 2 k0 z``
    (:func:`speckle.imaging._methods.carrier.naive_float32_phase_error`), a mode this package never
    uses. Admissible when the rounding estimate is <= ``tol/2``.
``psf``
    truncation (PSF tail energy beyond the half-width) plus interpolation error
    (:func:`speckle.imaging._methods.psf.psf_error_estimate`). On a rectangular spectrum the tail
    decays like ``1/(pi sqrt(hw))``, so a tight ``tol`` needs the full A-line (``hw = N//2``): then
    ``psf`` is exact but costs ``M N`` per line, so the cost model prefers it only for tiny lines
    (N of order 10), never a truncated one.

Deep scatterers: the fast methods place scatterers with ``z * (1/H)`` and reduce the carrier
phase with a three-term ``2 pi`` in float64, which loses ~``eps |z|/H`` (position) and
``eps |2 k0 z| 3e-4`` (carrier) of relative accuracy
(:func:`speckle.imaging._methods.carrier.float64_error_estimate`, ~1e-14 for depths within a few
``H``, 1e-2 at ``|z|`` ~ 1e15 µm). ``nufft`` admits it up to ``tol/4``, ``nufft32`` within its
``tol/2`` rounding budget and ``psf`` within ``tol`` minus its own error; beyond that they
refuse and ``auto`` does not choose them. ``direct`` and ``finufft`` reduce ``z mod H``
exactly and stay within ``tol``.

Cost model: nanoseconds per call, fitted on the benchmark machine (Intel Xeon, 2 cores) for
``N = 64 ... 1024`` and 2-32 scatterers per pixel (within a factor ~1.5). It only orders methods, so
errors in it cost speed, never accuracy.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .._validate import check_int, check_memory, check_real
from ..system.source import check_weights
from ._methods.nufft import FLOAT64_SHARE, fine_grid_size, float32_error_estimate, kernel_width
from ._methods.psf import psf_error_estimate
from ._rules import NUFFT_TOL_FLOOR, check_tol, choose, estimate_table, psf_slots, resolve_tol

__all__ = ["AUTO_CANDIDATES", "choose_method", "method_estimates"]

#: Methods ``"auto"`` chooses from (``"finufft"`` is always slower than ``"nufft"``: benchmark).
AUTO_CANDIDATES = ("direct", "nufft", "nufft32", "psf")


def _estimate(
    method: str, n_lines: int, n_scat: int, n_pix: int, spectrum, tol: float, e64: float = 0.0
):
    """(predicted relative error, predicted time in ns) of one method on a scene.

    ``e64``: float64 carrier/position error of the fast methods on this scene's depths
    (:func:`speckle.imaging._methods.carrier.float64_error_estimate`; 0 for depths within a few
    ``H``).
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
        _, nk = psf_slots(n, hw)
        table = 40.0 * rows * nk
        return err, table + b * (5000.0 + 10.0 * n) + b * m * (20.0 + 3.0 * nk)
    raise ValueError(f"no error/cost model for method {method!r}")


def _estimator(
    n_lines: int,
    n_scatterers: int,
    n_pixels: int,
    spectrum: np.ndarray | None,
    tol: float | None,
    float64_error: float,
) -> tuple[float, Callable[[str], tuple[float, float]]]:
    """``(tol, estimate)``: the resolved tol and ``estimate(method) -> (error, cost_ns)``.

    The arguments are checked first (counts, the spectrum's ``n_pixels`` finite weights, tol
    in (0, 1), ``float64_error`` >= 0 or inf), naming the bad one.
    """
    n_lines = check_int(n_lines, "n_lines", low=1)
    n_scatterers = check_int(n_scatterers, "n_scatterers", low=0)
    n_pixels = check_int(n_pixels, "n_pixels", low=1)
    check_memory(8.0 * n_pixels, "n_pixels", "the spectrum's weights")
    if float64_error != math.inf:  # inf: depths beyond float64 (no fast method admissible)
        float64_error = check_real(float64_error, "float64_error", low=0.0)
    tolv = resolve_tol(check_tol(tol))
    s = np.ones(n_pixels) if spectrum is None else check_weights(spectrum, n_pixels)

    def estimate(name):
        return _estimate(name, n_lines, n_scatterers, n_pixels, s, tolv, float64_error)

    return tolv, estimate


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
        Requested relative accuracy (None: :data:`speckle.imaging._methods.nufft.DEFAULT_TOL`).
    float64_error : float
        :func:`speckle.imaging._methods.carrier.float64_error_estimate` of the scene (depends on the
        depths; 0 means depths within a few ``H``): a method whose budget it exceeds is not
        admissible.

    Returns
    -------
    dict
        ``{method: {"error": e, "cost_ns": t, "admissible": e <= tol}}``.

    Examples
    --------
    >>> import speckle
    >>> sorted(speckle.method_estimates(64, 1000, 256, None, None))
    ['direct', 'nufft', 'nufft32', 'psf']
    """
    tolv, estimate = _estimator(n_lines, n_scatterers, n_pixels, spectrum, tol, float64_error)
    return estimate_table(AUTO_CANDIDATES, estimate, tolv)


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
    """Name of the fastest admissible method (see :func:`method_estimates`); never runs one.

    Examples
    --------
    >>> import speckle
    >>> speckle.choose_method(64, 1000, 256, None, None)
    'nufft'
    """
    tolv, estimate = _estimator(n_lines, n_scatterers, n_pixels, spectrum, tol, float64_error)
    # psf cannot win when its floor (one slot per scatterer) is beaten: not estimated then
    floor = {"psf": _psf_floor_ns(n_lines, n_scatterers, n_pixels)}
    return choose(AUTO_CANDIDATES, estimate, tolv, cost_floor=floor)
