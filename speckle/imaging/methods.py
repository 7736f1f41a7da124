"""The method tables: every way :func:`speckle.ascan` and :func:`speckle.beam_scan` can image.

Two plain dicts, built here from the method functions (nothing registers itself on import):

:data:`ASCAN_METHODS`
    name -> ``callable(z, amplitude, n_pixels, depth_range, k0, spectrum, tol)`` with validated
    arrays ``z`` (float64, (B, M)), ``amplitude`` (complex128, (B, M)), the ``N`` spectral
    weights and ``tol`` (float or None), returning complex128 (B, N).
:data:`BEAM_METHODS`
    name -> ``callable(scene, beam, tol)`` with the validated
    :class:`~speckle.imaging.gaussian_beam.BeamScene` and
    :class:`~speckle.imaging.gaussian_beam.Beam` of
    :func:`~speckle.imaging.gaussian_beam.beam_problem`, returning complex128 (L, N).

``"auto"`` in each is the fastest method whose predicted error is within ``tol``
(:func:`speckle.imaging.synthesis.choose_method`,
:func:`speckle.imaging._methods.beam_nufft.choose_beam_method`).
"""

from __future__ import annotations

import numpy as np

from .._validate import check_choice
from ._methods.beam_nufft import (
    beam_finufft_method,
    beam_nufft32_method,
    beam_nufft_method,
    choose_beam_method,
)
from ._methods.carrier import float64_error_estimate
from ._methods.direct import beam_direct_method, direct_method
from ._methods.nufft import (
    finufft_method,
    float32_error_estimate,
    kernel_width,
    nufft32_method,
    nufft_method,
)
from ._methods.psf import psf_method
from ._rules import refuse_below_floor, refuse_float32, resolve_tol
from .gaussian_beam import Beam, BeamScene
from .synthesis import choose_method

__all__ = [
    "ASCAN_METHODS",
    "BEAM_METHODS",
    "ascan_auto_method",
    "beam_auto_method",
    "check_beam_call",
]


def ascan_auto_method(z, amplitude, n_pixels, depth_range, k0, spectrum, tol):
    """``ascan(..., method="auto")``: :func:`speckle.imaging.synthesis.choose_method`, then
    that method."""
    e64 = float64_error_estimate(z, amplitude, depth_range, k0, spectrum)
    name = choose_method(z.shape[0], z.shape[1], n_pixels, spectrum, tol, float64_error=e64)
    return ASCAN_METHODS[name](z, amplitude, n_pixels, depth_range, k0, spectrum, tol)


def beam_auto_method(scene: BeamScene, beam: Beam, tol: float | None) -> np.ndarray:
    """``beam_scan(..., method="auto")``:
    :func:`speckle.imaging._methods.beam_nufft.choose_beam_method`, then that method."""
    return BEAM_METHODS[choose_beam_method(scene, beam, tol)](scene, beam, tol)


#: A-scan synthesis methods of :func:`speckle.ascan` (module docstring).
ASCAN_METHODS = {
    "direct": direct_method,
    "nufft": nufft_method,
    "nufft32": nufft32_method,
    "finufft": finufft_method,
    "psf": psf_method,
    "auto": ascan_auto_method,
}

#: Methods of :func:`speckle.beam_scan` (module docstring).
BEAM_METHODS = {
    "direct": beam_direct_method,
    "nufft": beam_nufft_method,
    "nufft32": beam_nufft32_method,
    "auto": beam_auto_method,
    "finufft": beam_finufft_method,
}


def check_beam_call(
    method: str,
    tol: float | None,
    *,
    n_pixels: int,
    three_d: bool,
    focused: bool,
    n_scatterers: int = 0,
) -> None:
    """Refuse, before any work, a beam ``method`` that cannot run with this ``tol`` or
    geometry whatever the scene (``ValueError`` naming the method and what to change).

    The scene-dependent refusals (irregular lines, float32 rounding of a dense scene, memory)
    stay in the methods; this catches at call time what they would refuse on any scene, e.g.
    when :func:`speckle.scan_image` builds lazy tasks.
    """
    check_choice(method, "method", BEAM_METHODS)
    if method in ("nufft", "nufft32", "finufft"):
        tolv = refuse_below_floor(resolve_tol(tol), method)
        if method == "nufft32" and n_scatterers == 0:
            # rounding of a scene without scatterers, a lower bound of every scene's (the
            # method itself refuses a given scene with that scene's estimate)
            refuse_float32(float32_error_estimate(0, n_pixels, kernel_width(0.25 * tolv)), tolv)
    if method == "finufft" and (three_d or focused):
        raise ValueError(
            "method='finufft' (the FINUFFT beam reference) handles a 2-D scene without focus "
            f"only, got {'a 3-D scene' if three_d else 'a focus'}; use method='nufft', 'auto' "
            "or 'direct'"
        )
