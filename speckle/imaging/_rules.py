"""Rules shared by the imaging methods (private): tolerances, refusals, choosing a method.

The A-scan methods (:mod:`speckle.imaging._methods.nufft`, :mod:`speckle.imaging._methods.psf`) and
the beam methods (:mod:`speckle.imaging._methods.beam_nufft`) refuse the same things with the same
words, and ``method="auto"`` picks the fastest admissible method of either family with
:func:`choose` over that family's error and cost estimates.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from .. import _validate
from .._validate import check_real

__all__ = [
    "DEFAULT_TOL",
    "METHODS_INSTEAD",
    "NUFFT_TOL_FLOOR",
    "check_carrier_phase",
    "check_tol",
    "choose",
    "estimate_table",
    "finufft_threads",
    "memory_limit",
    "psf_slots",
    "refuse_below_floor",
    "refuse_float32",
    "refuse_memory",
    "resolve_tol",
]

#: Tolerance used by approximate methods when ``tol`` is None (close to float64 exactness).
DEFAULT_TOL = 1e-12
#: Tightest tolerance the NUFFT kernels reach (kernel width cap 16); below it use "direct".
NUFFT_TOL_FLOOR = 1e-13
#: What the retired paths of the method modules (``speckle.imaging.<module>``) say to use.
METHODS_INSTEAD = "methods by name: speckle.ascan(method=...), speckle.beam_scan(method=...)"

#: ``estimate(name) -> (predicted relative error, predicted time in ns)``.
Estimate = Callable[[str], "tuple[float, float]"]


def check_tol(tol: object) -> float | None:
    """``tol`` as a float in (0, 1), or None (``ValueError``/``TypeError`` naming ``tol``)."""
    if tol is None:
        return None
    return check_real(tol, "tol", low=0, high=1, low_inclusive=False, high_inclusive=False)


def check_carrier_phase(z: np.ndarray, k0: float) -> None:
    """``ValueError`` when the carrier phase ``2 k0 z`` of some depth is infinite in float64."""
    if z.size and not np.isfinite(2.0 * k0 * float(np.max(np.abs(z)))):
        raise ValueError(
            f"k0 = {k0:g} rad/µm and depths z up to {float(np.max(np.abs(z))):g} µm give an "
            "infinite carrier phase 2 k0 z in float64; use a smaller k0 or z"
        )


def resolve_tol(tol: float | None) -> float:
    """The tolerance an approximate method works to: ``tol`` (checked by :func:`check_tol`),
    or :data:`DEFAULT_TOL`."""
    return DEFAULT_TOL if tol is None else check_tol(tol)


def refuse_below_floor(tol: float, method: str) -> float:
    """``tol``, or ``ValueError`` when it is below :data:`NUFFT_TOL_FLOOR`."""
    if tol < NUFFT_TOL_FLOOR:
        raise ValueError(
            f"method={method!r} reaches tol >= {NUFFT_TOL_FLOOR:g} only, got tol={tol:g}; "
            "use method='direct' (exact) or method='auto'"
        )
    return tol


def refuse_float32(rounding: float, tol: float) -> None:
    """``ValueError`` when the float32 rounding estimate exceeds its ``tol/2`` budget."""
    if rounding > 0.5 * tol:
        raise ValueError(
            f"method='nufft32' cannot reach tol={tol:g} here: its float32 rounding error is "
            f"~{rounding:.1e}; use tol >= {2 * rounding:.1e} or method='nufft'"
        )


def memory_limit() -> float:
    """:data:`speckle._validate.MAX_BYTES`, read at call time (tests lower it)."""
    return float(_validate.MAX_BYTES)


def refuse_memory(method: str, parts: dict[str, float], advice: dict[str, str]) -> float:
    """Total of the peak-memory estimate ``parts`` (bytes per use), or ``ValueError`` when it
    exceeds :data:`speckle._validate.MAX_BYTES`, naming the estimate, its largest part and
    ``advice[part]``: the parameter to change."""
    total = float(sum(parts.values()))
    cap = memory_limit()
    if total > cap:
        big = max(parts, key=parts.get)
        detail = ", ".join(
            f"{k} {v / 2**30:.3g} GiB" for k, v in sorted(parts.items(), key=lambda kv: -kv[1])
            if v >= 0.01 * total
        )  # fmt: skip
        raise ValueError(
            f"method={method!r} would need ~{total / 2**30:.3g} GiB ({detail}), above the "
            f"{cap / 2**30:.3g} GiB limit (speckle._validate.MAX_BYTES); {advice[big]}"
        )
    return total


def psf_slots(n_pixels: int, hw: int) -> tuple[int, int]:
    """``(lo, nk)``: pixels ``p0 - lo ... p0 - lo + nk - 1`` receive a scatterer nearest ``p0``
    in the ``"psf"`` method.

    ``2 hw + 1`` symmetric slots, or exactly the ``N`` pixels of the A-line once ``hw`` reaches
    ``N//2`` (no pixel written twice).
    """
    if 2 * hw + 1 >= n_pixels:
        return n_pixels // 2, n_pixels
    return hw, 2 * hw + 1


def estimate_table(candidates: Iterable[str], estimate: Estimate, tol: float) -> dict[str, dict]:
    """``{name: {"error": e, "cost_ns": t, "admissible": e <= tol}}`` over ``candidates``."""
    out = {}
    for name in candidates:
        err, cost = estimate(name)
        out[name] = {"error": err, "cost_ns": cost, "admissible": bool(err <= tol)}
    return out


def choose(
    candidates: Iterable[str],
    estimate: Estimate,
    tol: float,
    *,
    cost_floor: dict[str, float] | None = None,
) -> str:
    """Name of the fastest candidate whose predicted error is within ``tol``; runs none.

    ``cost_floor[name]``, when given, is a lower bound of that candidate's cost: a candidate
    whose floor is no better than the best admissible cost so far is not estimated. The first
    candidate must always be admissible (the exact method).
    """
    floors = cost_floor or {}
    ok: dict[str, float] = {}
    for name in candidates:
        if name in floors and ok and floors[name] >= min(ok.values()):
            continue  # cannot win: no need to estimate it
        err, cost = estimate(name)
        if err <= tol:
            ok[name] = cost
    return min(ok, key=ok.get)


def finufft_threads() -> int:
    """Threads to give FINUFFT by default: numba's thread count, capped by OpenMP's limit.

    FINUFFT runs on OpenMP, whose limit is ``OMP_NUM_THREADS`` when it is set (Snakemake sets it
    to a job's ``threads``); asking for more prints "nthreads=..., more than the ... physically
    cores available" on every call. Explicit ``nthreads`` arguments are passed on unchanged.
    """
    import os

    import numba

    threads = numba.get_num_threads()
    omp = os.environ.get("OMP_NUM_THREADS", "").split(",")[0].strip()
    if omp.isdigit() and int(omp) > 0:
        threads = min(threads, int(omp))
    return max(1, threads)
