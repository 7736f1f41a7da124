"""A scanned Gaussian beam over a shared scene: overlapping A-lines.

Every A-line ``i`` of a B-scan is the paper's Eq. 4 with each scatterer weighted by the
double-pass (illumination and collection) amplitude of a Gaussian beam centred on the line,

    A(i, q) = sum_j a_j W(x_j - X_i, z_j) sum_n S(k_n) exp(2i k_n z_j) exp(-2i pi n q/N),

with, by default (no focus), ``W(r) = exp(-2 r^2 / w0^2)``: ``w0`` is the 1/e^2 intensity radius
of the one-way beam at focus, so the one-way amplitude is ``exp(-r^2/w0^2)`` and the double-pass
amplitude its square. Scatterers belong to no A-line: neighbouring lines closer than ``w0`` see
the same scatterers and are correlated. For a dense uniform scene the complex correlation of
lines ``dx`` apart is ``exp(-dx^2/w0^2)`` (the overlap integral of two double-pass weights).

Focus
-----
With ``focus=z_f`` (µm) the beam is a paraxial Gaussian beam with its waist ``w0`` at depth
``z_f`` and Rayleigh range ``z_R = k0 w0^2/2`` (``k0`` in the medium, rad/µm, i.e.
``pi n w0^2/lambda0``; ``rayleigh_range=`` overrides it, e.g. for a beam whose waist is set by
other optics). In the ``exp(+i k z)`` propagation convention of Eq. 4 (round trip
``exp(2i k z)``) the one-way field is the paraxial solution ``E ~ (q(z_f)/q(z))
exp(i k r^2 / (2 q(z)))`` with ``q(z) = (z - z_f) - i z_R``:

    E(r, z) = (w0/w) exp(-r^2/w^2) exp(+i k0 r^2/(2R)) exp(-i psi),
    w = w0 sqrt(1 + u^2),  R = (z - z_f)(1 + 1/u^2),  psi = arctan u,  u = (z - z_f)/z_R,

(the ``exp(-i omega t)`` convention flips the signs of the curvature and Gouy phases relative to
the engineering ``exp(+i omega t)`` form). The double-pass weight is ``E^2``, which simplifies to

    W(r, z) = gamma^2 exp(-2 gamma r^2 / w0^2),   gamma = 1/(1 + i u),

a Gaussian in ``r`` with a complex width: ``|W| = (w0/w)^2 exp(-2 r^2/w^2)``, phase
``k0 r^2/R - 2 psi``. At ``u = 0`` it is the contract weight. The beam parameters are those of
the central wavenumber ``k0`` (the chromatic change of ``z_R`` across the spectrum is ignored).
Consequences (tested): in a 3-D scene a dense laterally uniform layer (incoherent sum) or a
mirror (coherent sum over the plane) at depth ``z`` returns an intensity ``~ 1/(1 + u^2)``, the
confocal axial response; in a 2-D scene, which is the plane ``y = 0`` through the beam axis of
the same (circular) beam, a uniform layer returns ``(1 + u^2)^(-3/2)``.

3-D scenes (C-scans)
--------------------
Pass scatterer coordinates ``y=`` and ``lines`` of shape (L, 2) holding ``(X_i, Y_i)``: the
weight is ``W(r)`` with ``r^2 = (x - X)^2 + (y - Y)^2``; the result is still (L, N).

Methods
-------
``"direct"`` (:func:`beam_scan` default): the exact float64 reference, each line is
Eq. 4 of its weighted scatterers (:func:`speckle.imaging._methods.direct.beam_direct_method`; those
whose weight underflows to zero are skipped). ``"nufft"``, ``"nufft32"`` and ``"auto"``:
:mod:`speckle.imaging._methods.beam_nufft`. The table is
:data:`speckle.imaging.methods.BEAM_METHODS`; :func:`speckle.imaging.gaussian_beam.beam_problem`
validates the arguments into the scene and beam every method takes.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_choice, check_memory
from .gaussian_beam import Beam, BeamScene, beam_problem, beam_weight
from .methods import BEAM_METHODS, check_beam_call

__all__ = ["BEAM_METHODS", "Beam", "BeamScene", "beam_problem", "beam_scan", "beam_weight"]


def beam_scan(
    z: object,
    x: object,
    amplitude: object,
    *,
    lines: object,
    waist: float,
    n_pixels: int,
    depth_range: float,
    k0: float,
    spectrum: object | None = None,
    method: str = "direct",
    tol: float | None = None,
    y: object | None = None,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> np.ndarray:
    """Complex B-scan (or C-scan lines) of a shared scene imaged by a scanned Gaussian beam.

    ``A(i, q) = sum_j a_j W(x_j - X_i, z_j) sum_n S(k_n) exp(2i k_n z_j) exp(-2i pi n q/N)``,
    ``W = exp(-2 r^2/w0^2)`` by default (see the module docstring for focus and 3-D).

    Parameters
    ----------
    z, x : array_like, shape (M,)
        Scatterer depths and lateral positions in µm. ``M = 0`` (an empty scene) images to zeros.
    amplitude : array_like, shape (M,)
        Real or complex scattering amplitudes.
    lines : array_like, shape (L,), or (L, 2) with ``y``
        Lateral positions ``X_i`` (or ``(X_i, Y_i)``) of the A-lines in µm, L >= 1, any order.
        The fast methods need them on a uniform grid (a uniform row, or a uniform (x, y) raster
        in 3-D); ``"auto"`` falls back to ``"direct"`` otherwise.
    waist : float
        Beam waist ``w0`` (1/e^2 intensity radius of the one-way beam at focus) in µm, > 0.
    n_pixels, depth_range, k0, spectrum
        As in :func:`speckle.ascan` (pixels, unambiguous depth ``H`` in µm, central wavenumber
        in the medium in rad/µm, spectral weights); same grid, wrap-around and pixel
        conventions.
    method : {"direct", "nufft", "nufft32", "auto", "finufft"}
        ``"direct"``: the exact float64 reference. ``"nufft"`` / ``"nufft32"``: ES-kernel
        spreading in depth and exact Gaussian weights on the neighbouring lines, in double /
        single precision (:mod:`speckle.imaging._methods.beam_nufft`). ``"auto"``: the fastest
        method whose predicted error is within ``tol`` (rules, nothing is run to decide;
        ``"direct"`` for irregular lines). ``"finufft"``: one FINUFFT 2-D transform with the beam
        applied in lateral Fourier space (reference; 2-D scenes without focus only).
    tol : float, optional
        Requested relative accuracy in (0, 1), ``||A - A_direct||_2 / ||A_direct||_2`` over all
        lines and pixels, for approximate methods (``None``: 1e-12).
    y : array_like, shape (M,), optional
        Scatterer positions along y in µm: a 3-D scene (then ``lines`` is (L, 2)).
    focus : float, optional
        Focal depth ``z_f`` in µm, in ``[0, depth)``. ``None`` (default): a depth-independent
        beam (the contract).
    rayleigh_range : float, optional
        ``z_R`` in µm (> 0), with ``focus`` only; default ``k0 w0^2/2`` (needs ``k0 > 0``).

    Returns
    -------
    numpy.ndarray
        Complex128, shape ``(L, n_pixels)``; no normalisation.

    Raises
    ------
    TypeError, ValueError
        On invalid input, before any computation: including a ``method``/``tol`` pair the
        method cannot reach whatever the scene, and a result above
        :data:`speckle._validate.MAX_BYTES` (the methods estimate their own peak memory too,
        naming the parameter to change).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, x, a = np.array([100.0]), np.array([0.0]), np.array([1.0 + 0j])  # one scatterer
    >>> lines = speckle.scan_lines(3, 4.0, start=-4.0)
    >>> img = speckle.beam_scan(
    ...     z, x, a, lines=lines, waist=4.0, n_pixels=32, depth_range=256.0, k0=3.0
    ... )
    >>> img.shape, int(abs(img).max(axis=1).argmax())  # (lines, pixels); brightest on x = 0
    ((3, 32), 1)
    """
    check_choice(method, "method", BEAM_METHODS)
    scene, beam, tolv = beam_problem(
        z, x, amplitude, lines=lines, waist=waist, n_pixels=n_pixels, depth_range=depth_range,
        k0=k0, spectrum=spectrum, tol=tol, y=y, focus=focus, rayleigh_range=rayleigh_range,
    )  # fmt: skip
    n_lines = scene.lines.shape[0]
    check_beam_call(
        method, tolv, n_pixels=scene.n_pixels, three_d=scene.y is not None,
        focused=beam.focus is not None, n_scatterers=scene.z.size,
    )  # fmt: skip
    check_memory(
        16.0 * n_lines * scene.n_pixels, "lines", f"{n_lines} lines x {scene.n_pixels} "
        "complex128 pixels (the result)",
    )  # fmt: skip
    if scene.z.size == 0:
        return np.zeros((scene.lines.shape[0], scene.n_pixels), dtype=np.complex128)
    return BEAM_METHODS[method](scene, beam, tolv)
