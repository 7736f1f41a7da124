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
:func:`speckle.ascan` of its weighted scatterers (those whose weight underflows to zero are
skipped). ``"nufft"``, ``"nufft32"`` and ``"auto"``: :mod:`speckle.imaging.beam_nufft`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from .._validate import as_finite_array, check_choice, check_int, check_real
from ..system.source import check_weights
from .aline import DIRECT_CHUNK_ELEMENTS, ascan

__all__ = ["BEAM_METHODS", "Beam", "beam_scan", "beam_weight", "register_beam_method"]

#: Double-pass weights below ``exp(-_UNDERFLOW)`` are exactly zero in float64.
_UNDERFLOW = 745.2


class Beam(NamedTuple):
    """Validated beam: waist ``w0`` (µm), focal depth (µm, or None) and Rayleigh range (µm)."""

    waist: float
    focus: float | None
    rayleigh_range: float | None

    def gamma(self, z: np.ndarray) -> np.ndarray | None:
        """``1/(1 + i u)``, ``u = (z - z_f)/z_R``, per depth ``z`` (µm); None without focus."""
        if self.focus is None:
            return None
        return 1.0 / (1.0 + 1j * (np.asarray(z, dtype=float) - self.focus) / self.rayleigh_range)


class BeamScene(NamedTuple):
    """Validated scene and scan passed to every beam method (float64 / complex128 arrays)."""

    z: np.ndarray  # (M,) µm
    x: np.ndarray  # (M,) µm
    y: np.ndarray | None  # (M,) µm in 3-D, else None
    amplitude: np.ndarray  # (M,) complex
    lines: np.ndarray  # (L,) or (L, 2) µm
    n_pixels: int
    depth: float
    k0: float
    spectrum: np.ndarray  # (N,)


BeamMethod = Callable[[BeamScene, Beam, "float | None"], np.ndarray]

#: Registered beam methods: name -> callable(scene, beam, tol) -> complex128 (L, N).
BEAM_METHODS: dict[str, BeamMethod] = {}


def register_beam_method(name: str) -> Callable[[BeamMethod], BeamMethod]:
    """Decorator registering a method of :func:`beam_scan` under ``name``."""

    def deco(func: BeamMethod) -> BeamMethod:
        BEAM_METHODS[name] = func
        return func

    return deco


def beam_weight(
    dx: object,
    z: object,
    *,
    waist: float,
    dy: object = 0.0,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> np.ndarray:
    """Double-pass amplitude weight ``W`` of the beam at lateral offset ``(dx, dy)``, depth ``z``.

    ``exp(-2 r^2/w0^2)`` without focus; ``gamma^2 exp(-2 gamma r^2/w0^2)``,
    ``gamma = 1/(1 + i (z - z_f)/z_R)``, with one (see the module docstring). All lengths in µm;
    arrays broadcast. Returns complex128.
    """
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    r2 = np.asarray(dx, dtype=float) ** 2 + np.asarray(dy, dtype=float) ** 2
    if focus is None:
        return np.exp(-2.0 * r2 / w0**2) + 0j * np.asarray(z, dtype=float)
    zr = check_real(rayleigh_range, "rayleigh_range", low=0, low_inclusive=False)
    g = Beam(w0, float(focus), zr).gamma(z)
    return g**2 * np.exp(-2.0 * g * r2 / w0**2)


def _vector(value: object, name: str) -> np.ndarray:
    arr = as_finite_array(value, name)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-D of shape (M,), got shape {arr.shape}")
    return arr


def _validate(
    z, x, amplitude, y, lines, waist, n_pixels, depth, k0, spectrum, method, tol, focus, zr
) -> tuple[BeamScene, Beam, float | None]:
    n = check_int(n_pixels, "n_pixels", low=2)
    h = check_real(depth, "depth", low=0, low_inclusive=False)
    k0v = check_real(k0, "k0", low=0)
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    check_choice(method, "method", BEAM_METHODS)
    tolv = None if tol is None else check_real(tol, "tol", low=0, high=1, low_inclusive=False,
                                                high_inclusive=False)  # fmt: skip
    zz = _vector(z, "z")
    xx = _vector(x, "x")
    aa = as_finite_array(amplitude, "amplitude", dtype=np.complex128)
    if aa.ndim != 1:
        raise ValueError(f"amplitude must be 1-D of shape (M,), got shape {aa.shape}")
    yy = None if y is None else _vector(y, "y")
    shapes = [zz.shape, xx.shape, aa.shape] + ([] if yy is None else [yy.shape])
    if len(set(shapes)) != 1:
        names = "z, x, amplitude" + ("" if yy is None else ", y")
        got = ", ".join(map(str, shapes))
        raise ValueError(f"{names} must have the same shape (M,), got {got}")
    xl = as_finite_array(lines, "lines")
    if yy is None:
        if xl.ndim != 1:
            raise ValueError(
                f"lines must be 1-D (L,) lateral positions for a 2-D scene, got shape {xl.shape}; "
                "for a 3-D scene pass y= and lines of shape (L, 2)"
            )
    elif xl.ndim != 2 or xl.shape[1] != 2:
        raise ValueError(
            f"lines must have shape (L, 2) (X, Y) for a 3-D scene (y given), got shape {xl.shape}"
        )
    if xl.shape[0] == 0:
        raise ValueError("lines must hold at least one A-line position, got none")
    s = np.ones(n) if spectrum is None else check_weights(spectrum, n)
    if focus is None:
        if zr is not None:
            raise ValueError("rayleigh_range needs focus= (the focal depth in µm)")
        beam = Beam(w0, None, None)
    else:
        zf = check_real(focus, "focus", low=0, high=h, high_inclusive=False)
        if zr is None:
            if k0v == 0:
                raise ValueError(
                    "focus needs k0 > 0 (the Rayleigh range is k0 w0^2/2) or rayleigh_range="
                )
            zr = 0.5 * k0v * w0**2
        else:
            zr = check_real(zr, "rayleigh_range", low=0, low_inclusive=False)
        beam = Beam(w0, zf, zr)
    return BeamScene(zz, xx, yy, aa, xl, n, h, k0v, s), beam, tolv


def beam_scan(
    z: object,
    x: object,
    amplitude: object,
    *,
    lines: object,
    waist: float,
    n_pixels: int,
    depth: float,
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
    n_pixels, depth, k0, spectrum
        As in :func:`speckle.ascan` (pixels, unambiguous depth ``H`` in µm, central wavenumber
        in the medium in rad/µm, spectral weights); same grid, wrap-around and pixel
        conventions.
    method : {"direct", "nufft", "nufft32", "auto"}
        ``"direct"``: the exact float64 reference. ``"nufft"`` / ``"nufft32"``: ES-kernel
        spreading in depth and exact Gaussian weights on the neighbouring lines, in double /
        single precision (:mod:`speckle.imaging.beam_nufft`). ``"auto"``: the fastest method
        whose predicted error is within ``tol`` (rules, nothing is run to decide).
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
        On invalid input, before any computation.
    """
    scene, beam, tolv = _validate(
        z, x, amplitude, y, lines, waist, n_pixels, depth, k0, spectrum, method, tol, focus,
        rayleigh_range,
    )  # fmt: skip
    if scene.z.size == 0:
        return np.zeros((scene.lines.shape[0], scene.n_pixels), dtype=np.complex128)
    return BEAM_METHODS[method](scene, beam, tolv)


@register_beam_method("direct")
def _direct(scene: BeamScene, beam: Beam, tol: float | None) -> np.ndarray:
    """Exact reference: each line is :func:`speckle.ascan` of its weighted scatterers."""
    del tol
    w0 = beam.waist
    gam = beam.gamma(scene.z)
    # widest beam over the scene: lateral reach beyond which every weight underflows
    wmax = w0 if gam is None else w0 / np.sqrt(np.min(gam.real))
    reach = wmax * np.sqrt(_UNDERFLOW / 2)
    lines = scene.lines if scene.lines.ndim == 2 else scene.lines[:, None]
    out = np.empty((lines.shape[0], scene.n_pixels), dtype=np.complex128)
    order = np.argsort(scene.x, kind="stable")
    xs = scene.x[order]
    for i, line in enumerate(lines):
        lo, hi = np.searchsorted(xs, [line[0] - reach, line[0] + reach])
        sel = order[lo:hi]
        r2 = (scene.x[sel] - line[0]) ** 2
        if scene.y is not None:
            r2 = r2 + (scene.y[sel] - line[1]) ** 2
            near = r2 < reach**2  # the other weights underflow to exactly zero
            sel, r2 = sel[near], r2[near]
        if gam is None:
            weight = np.exp(-2 * r2 / w0**2)
        else:
            g = gam[sel]
            weight = g**2 * np.exp(-2 * g * r2 / w0**2)
        out[i] = 0.0
        # scatterers in chunks: the direct sum holds (scatterers x pixels) phase factors
        step = max(1, DIRECT_CHUNK_ELEMENTS // scene.n_pixels)
        for c0 in range(0, sel.size, step):
            out[i] += ascan(
                scene.z[sel[c0 : c0 + step]],
                scene.amplitude[sel[c0 : c0 + step]] * weight[c0 : c0 + step],
                n_pixels=scene.n_pixels,
                depth=scene.depth,
                k0=scene.k0,
                spectrum=scene.spectrum,
            )
    return out


# Fast methods register themselves on import (kept last: they import this module).
from . import beam_nufft as _beam_nufft  # noqa: E402, F401
