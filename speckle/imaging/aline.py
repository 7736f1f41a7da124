"""A-line formation: the paper's Eq. 4 on plain numpy arrays.

    A(q) = sum_j sum_n S(k_n) a_j exp(2i k_n z_j) exp(-2i pi n q / N),   k_n = k0 + n*pi/H,

with ``n = -(N//2) ... N-1-(N//2)`` and pixel ``q`` at depth ``q*H/N`` (µm). See
:mod:`speckle.system.source` for the conventions and why the pixel step is ``H/N``.

:func:`ascan` is the stable entry point. ``method`` selects how the double sum is evaluated;
``"direct"`` is the exact float64 reference. Faster methods register themselves in
:data:`METHODS` (see :func:`register_method`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._validate import as_finite_array, check_choice, check_int, check_memory, check_real
from ..system.source import check_weights, index_shift_phase, spectral_index

__all__ = ["METHODS", "ascan", "pixel_depths", "register_method"]

#: Largest number of complex phase factors the direct method holds in memory at once.
DIRECT_CHUNK_ELEMENTS = 1 << 22

Method = Callable[..., np.ndarray]

#: Registered A-scan synthesis methods: name -> callable(z, a, n_pixels, depth, k0, s, tol).
METHODS: dict[str, Method] = {}


def register_method(name: str) -> Callable[[Method], Method]:
    """Decorator registering a synthesis method under ``name`` for :func:`ascan`.

    The callable receives validated arguments ``(z, amplitude, n_pixels, depth, k0, spectrum,
    tol)`` with ``z`` float64 of shape (B, M), ``amplitude`` complex128 of shape (B, M),
    ``spectrum`` float64 of shape (N,) (never None) and ``tol`` a float or None, and returns a
    complex128 array of shape (B, N).
    """

    def deco(func: Method) -> Method:
        METHODS[name] = func
        return func

    return deco


def pixel_depths(n_pixels: int, depth: float) -> np.ndarray:
    """Pixel-centre depths ``q*H/N`` in µm, ``q = 0 ... N-1``."""
    n = check_int(n_pixels, "n_pixels", low=2)
    h = check_real(depth, "depth", low=0, low_inclusive=False)
    return np.arange(n) * (h / n)


def spectral_field_to_pixels(field: np.ndarray, n_pixels: int) -> np.ndarray:
    """Sum spectral components into pixels: ``A(q) = sum_n F_n exp(-2i pi n q/N)``.

    ``field`` has shape (..., N) ordered ``n = -(N//2) ... N-1-(N//2)``. The sum over ``n`` is an
    exact DFT evaluated with an FFT (rounding error ~1e-16 relative).
    """
    return np.fft.fft(field, axis=-1) * index_shift_phase(n_pixels, np.arange(n_pixels))


@register_method("direct")
def _direct(z, amplitude, n_pixels, depth, k0, spectrum, tol):
    """Exact float64 double sum: spectral field by explicit phase factors, then an exact DFT."""
    del tol  # exact up to rounding whatever tol asks
    batch, m = z.shape
    n_idx = spectral_index(n_pixels).astype(float)
    field = np.empty((batch, n_pixels), dtype=np.complex128)
    # Split the k0 phase from the spectral phase: 2 k_n z = 2 k0 z + 2 pi n z / H, and the
    # second factor is H-periodic in z, so z mod H keeps its argument small and accurate.
    carrier = amplitude * np.exp(2j * k0 * z)
    zr = np.mod(z, depth) * (2 * np.pi / depth)
    step = max(1, DIRECT_CHUNK_ELEMENTS // max(1, m * n_pixels))
    for b0 in range(0, batch, step):
        sl = slice(b0, b0 + step)
        phase = np.exp(1j * zr[sl, :, None] * n_idx)  # (b, M, N)
        field[sl] = np.einsum("bm,bmn->bn", carrier[sl], phase)
    return spectral_field_to_pixels(field * spectrum, n_pixels)


def _check_tol(tol: object) -> float | None:
    if tol is None:
        return None
    return check_real(tol, "tol", low=0, high=1, low_inclusive=False, high_inclusive=False)


def ascan(
    z: object,
    amplitude: object,
    *,
    n_pixels: int,
    depth: float,
    k0: float,
    spectrum: object | None = None,
    method: str = "direct",
    tol: float | None = None,
) -> np.ndarray:
    """Complex A-scan(s) of point scatterers, the paper's Eq. 4.

    Parameters
    ----------
    z : array_like, shape (..., M)
        Scatterer depths in µm. Leading dimensions are batch dimensions (e.g. A-lines). Depths
        outside ``[0, depth)`` are allowed and wrap around (finite unambiguous imaging depth):
        a scatterer at ``z + depth`` lands in the same pixel with a different carrier phase
        ``exp(2i k0 depth)``.
    amplitude : array_like
        Real or complex scattering amplitudes ``a_j``, broadcastable to ``z``. Zero amplitudes
        pad ragged A-lines.
    n_pixels : int
        Number of pixels (= spectral components) ``N`` >= 2.
    depth : float
        Unambiguous imaging depth ``H`` in µm (> 0). Pixel ``q`` sits at ``q*H/N``.
    k0 : float
        Central wavenumber in rad/µm (finite, >= 0; 0 gives the formal Fourier transform).
    spectrum : array_like, optional
        ``N`` non-negative weights ``S(k_n)`` ordered ``n = -(N//2) ... N-1-(N//2)``; ``None``
        means rectangular (all ones). A :func:`speckle.system.source.spectrum` DataArray works too.
    method : str
        Synthesis method, one of :data:`METHODS`: ``"direct"`` (the exact float64 reference),
        ``"nufft"`` / ``"nufft32"`` (folded type-1 NUFFT in double / single precision,
        :mod:`speckle.imaging.nufft`), ``"finufft"`` (FINUFFT, one plan per call), ``"psf"``
        (truncated point-spread function, :mod:`speckle.imaging.psf`) or ``"auto"`` (the fastest
        method whose predicted error on this scene is within ``tol``,
        :mod:`speckle.imaging.synthesis`). Approximate methods refuse (``ValueError``) a
        ``tol`` they cannot reach.
    tol : float, optional
        Requested relative accuracy in (0, 1), ``||A - A_direct||_2 / ||A_direct||_2`` over all
        lines and pixels, for approximate methods; ignored by ``"direct"``. ``None`` means
        ``1e-12`` for approximate methods.

    Returns
    -------
    numpy.ndarray
        Complex128 array of shape (..., N); no normalisation beyond Eq. 4.

    Raises
    ------
    TypeError, ValueError
        On invalid input, before any computation (including an output above
        :data:`speckle._validate.MAX_BYTES`).

    Examples
    --------
    A scatterer at a pixel centre is imaged into that pixel only:

    >>> a = ascan([8.0], [1.0], n_pixels=8, depth=64.0, k0=0.0)
    >>> np.round(np.abs(a), 12).tolist()
    [0.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    h = check_real(depth, "depth", low=0, low_inclusive=False)
    k0v = check_real(k0, "k0", low=0)
    check_choice(method, "method", METHODS)
    tolv = _check_tol(tol)
    zz = as_finite_array(z, "z")
    if zz.ndim == 0:
        raise ValueError("z must have at least one dimension (the scatterer axis), got a scalar")
    aa = as_finite_array(amplitude, "amplitude", dtype=np.complex128)
    z_shape = zz.shape
    try:
        zz, aa = np.broadcast_arrays(zz, aa)
    except ValueError:
        raise ValueError(
            f"amplitude of shape {aa.shape} does not broadcast to z of shape {zz.shape}"
        ) from None
    if zz.shape != z_shape:
        raise ValueError(
            f"amplitude must broadcast to the shape of z {z_shape}; broadcasting gave {zz.shape}"
        )
    s = np.ones(n) if spectrum is None else check_weights(spectrum, n)
    if zz.size and not np.isfinite(2.0 * k0v * float(np.max(np.abs(zz)))):
        raise ValueError(
            f"k0 = {k0v:g} rad/µm and depths z up to {float(np.max(np.abs(zz))):g} µm give an "
            "infinite carrier phase 2 k0 z in float64; use a smaller k0 or z"
        )
    batch_shape = zz.shape[:-1]
    m = zz.shape[-1]
    lines = int(np.prod(batch_shape, dtype=float))
    check_memory(16.0 * lines * n, "n_pixels", f"{lines} A-scans x {n} complex128 pixels")
    if zz.size == 0:
        return np.zeros((*batch_shape, n), dtype=np.complex128)
    z2 = np.ascontiguousarray(zz.reshape(-1, m))
    a2 = np.ascontiguousarray(aa.reshape(-1, m))
    out = METHODS[method](z2, a2, n, h, k0v, s, tolv)
    return np.asarray(out, dtype=np.complex128).reshape(*batch_shape, n)


# Fast methods register themselves in METHODS on import (kept last: they import this module).
from . import nufft as _nufft  # noqa: E402, F401
from . import psf as _psf  # noqa: E402, F401
from . import synthesis as _synthesis  # noqa: E402, F401
