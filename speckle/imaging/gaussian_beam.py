"""The scanned Gaussian beam as data: the validated beam and scene every beam method takes.

The physics (double-pass weight, focus, 3-D scenes) is described in :mod:`speckle.imaging.beam`,
whose :func:`speckle.beam_scan` validates its arguments with :func:`beam_problem` and passes
the resulting :class:`BeamScene` and :class:`Beam` to a method of
:data:`speckle.imaging.methods.BEAM_METHODS`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._validate import as_finite_array, broadcast, check_real, check_size
from ..system.source import check_weights
from ._rules import check_carrier_phase, check_tol

__all__ = ["MAX_WAIST", "Beam", "BeamScene", "beam_problem", "beam_weight"]

#: Widest waist accepted (µm): its square, and the Rayleigh range, stay finite in float64.
MAX_WAIST = 1e100


class Beam(NamedTuple):
    """Validated beam: waist ``w0`` (µm), focal depth (µm, or None) and Rayleigh range (µm).

    Examples
    --------
    >>> import speckle
    >>> speckle.Beam(8.0, None, None).waist
    8.0
    """

    waist: float
    focus: float | None
    rayleigh_range: float | None

    def gamma(self, z: np.ndarray) -> np.ndarray | None:
        """``1/(1 + i u)``, ``u = (z - z_f)/z_R``, per depth ``z`` (µm); None without focus."""
        if self.focus is None:
            return None
        return 1.0 / (1.0 + 1j * (np.asarray(z, dtype=float) - self.focus) / self.rayleigh_range)


class BeamScene(NamedTuple):
    """Validated scene and scan passed to every beam method (float64 / complex128 arrays).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, x, a = np.array([100.0]), np.array([0.0]), np.array([1.0 + 0j])
    >>> lines = speckle.scan_lines(3, 4.0, start=-4.0)
    >>> scene, beam, tol = speckle.beam_problem(
    ...     z, x, a, lines=lines, waist=4.0, n_pixels=32, depth_range=256.0, k0=3.0
    ... )
    >>> isinstance(scene, speckle.BeamScene), scene.n_pixels, scene.lines
    (True, 32, array([-4.,  0.,  4.]))
    """

    z: np.ndarray  # (M,) µm
    x: np.ndarray  # (M,) µm
    y: np.ndarray | None  # (M,) µm in 3-D, else None
    amplitude: np.ndarray  # (M,) complex
    lines: np.ndarray  # (L,) or (L, 2) µm
    n_pixels: int
    depth_range: float
    k0: float
    spectrum: np.ndarray  # (N,)


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

    Examples
    --------
    >>> import speckle
    >>> abs(speckle.beam_weight([0.0, 5.0, 10.0], 100.0, waist=10.0)).round(4)  # exp(-2 dx^2/w^2)
    array([1.    , 0.6065, 0.1353])
    """
    w0 = check_real(waist, "waist", low=0, high=MAX_WAIST, low_inclusive=False)
    dxa, dya, za = (as_finite_array(v, n) for v, n in ((dx, "dx"), (dy, "dy"), (z, "z")))
    broadcast(dx=dxa, dy=dya, z=za)  # mismatched shapes refused by name
    r2 = dxa**2 + dya**2
    if focus is None:
        if rayleigh_range is not None:
            raise ValueError("rayleigh_range needs a focus (focus=None: no focused beam)")
        return np.exp(-2.0 * r2 / w0**2) + 0j * za
    f = check_real(focus, "focus")
    zr = check_real(rayleigh_range, "rayleigh_range", low=0, low_inclusive=False)
    g = Beam(w0, f, zr).gamma(za)
    return g**2 * np.exp(-2.0 * g * r2 / w0**2)


def _vector(value: object, name: str) -> np.ndarray:
    arr = as_finite_array(value, name)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-D of shape (M,), got shape {arr.shape}")
    return arr


def beam_problem(
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
    tol: float | None = None,
    y: object | None = None,
    focus: float | None = None,
    rayleigh_range: float | None = None,
) -> tuple[BeamScene, Beam, float | None]:
    """Validated ``(scene, beam, tol)`` of :func:`speckle.beam_scan`'s arguments (same meaning).

    Every beam method takes these three (:data:`speckle.imaging.methods.BEAM_METHODS`), so a
    benchmark or a test can time or call one method on a validated problem.

    Raises
    ------
    TypeError, ValueError
        On invalid input, naming the parameter.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, x, a = np.array([100.0]), np.array([0.0]), np.array([1.0 + 0j])
    >>> lines = speckle.scan_lines(3, 4.0, start=-4.0)
    >>> scene, beam, tol = speckle.beam_problem(
    ...     z, x, a, lines=lines, waist=4.0, n_pixels=32, depth_range=256.0, k0=3.0
    ... )
    >>> type(scene).__name__, type(beam).__name__, beam.waist
    ('BeamScene', 'Beam', 4.0)
    """
    zr = rayleigh_range
    n = check_size(n_pixels, "n_pixels", low=2, bytes_per=64.0)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    k0v = check_real(k0, "k0", low=0)
    w0 = check_real(waist, "waist", low=0, high=MAX_WAIST, low_inclusive=False)
    tolv = check_tol(tol)
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
    check_carrier_phase(zz, k0v)
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
