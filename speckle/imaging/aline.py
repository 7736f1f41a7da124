"""A-line formation: the paper's Eq. 4 on plain numpy arrays.

    A(q) = sum_j sum_n S(k_n) a_j exp(2i k_n z_j) exp(-2i pi n q / N),   k_n = k0 + n*pi/H,

with ``n = -(N//2) ... N-1-(N//2)`` and pixel ``q`` at depth ``q*H/N`` (µm). See
:mod:`speckle.system.source` for the conventions and why the pixel step is ``H/N``.

:func:`ascan` is the stable entry point. ``method`` selects how the double sum is evaluated,
from the table :data:`speckle.imaging.methods.ASCAN_METHODS`; ``"direct"``
is the exact float64 reference (:mod:`speckle.imaging._methods.direct`). :func:`stream_ascans`
images a random scene too large for memory, a chunk of A-lines at a time.
"""

from __future__ import annotations

import numpy as np

from .._deprecate import moved
from .._validate import (
    as_finite_array,
    check_choice,
    check_int,
    check_memory,
    check_real,
    check_size,
)
from ..scene.scatterers import random_scatterers
from ..system.source import check_weights
from ._rules import check_carrier_phase, check_tol
from .methods import ASCAN_METHODS

__all__ = ["ascan", "pixel_depths", "stream_ascans"]

#: ``METHODS`` (retired, :data:`speckle.conventions.RETIRED`) is now ``ASCAN_METHODS``.
__getattr__ = moved(__name__, "speckle.imaging.methods", [], {"METHODS": "ASCAN_METHODS"})


def pixel_depths(n_pixels: int, depth_range: float) -> np.ndarray:
    """Pixel-centre depths ``q*H/N`` in µm, ``q = 0 ... N-1``, for ``depth_range`` ``H`` (µm).

    Examples
    --------
    >>> import speckle
    >>> speckle.pixel_depths(4, 32.0)
    array([ 0.,  8., 16., 24.])
    """
    n = check_size(n_pixels, "n_pixels", low=2)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    return np.arange(n) * (h / n)


def ascan(
    z: object,
    amplitude: object,
    *,
    n_pixels: int,
    depth_range: float,
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
        outside ``[0, depth_range)`` are allowed and wrap around (finite unambiguous depth ``H``):
        a scatterer at ``z + H`` lands in the same pixel with a different carrier phase
        ``exp(2i k0 H)``.
    amplitude : array_like
        Real or complex scattering amplitudes ``a_j``, broadcastable to ``z``. Zero amplitudes
        pad ragged A-lines.
    n_pixels : int
        Number of pixels (= spectral components) ``N`` >= 2.
    depth_range : float
        Unambiguous depth ``H`` in µm (> 0). Pixel ``q`` sits at ``q*H/N``.
    k0 : float
        Central wavenumber in rad/µm (finite, >= 0; 0 gives the formal Fourier transform).
    spectrum : array_like, optional
        ``N`` non-negative weights ``S(k_n)`` ordered ``n = -(N//2) ... N-1-(N//2)``; ``None``
        means rectangular (all ones). A :func:`speckle.system.source.spectrum` DataArray works too.
    method : str
        Synthesis method, one of :data:`speckle.ASCAN_METHODS`: ``"direct"`` (the exact float64
        reference),
        ``"nufft"`` / ``"nufft32"`` (folded type-1 NUFFT in double / single precision,
        :mod:`speckle.imaging._methods.nufft`), ``"finufft"`` (FINUFFT, one plan per call),
        ``"psf"`` (truncated point-spread function, :mod:`speckle.imaging._methods.psf`) or
        ``"auto"`` (the fastest method whose predicted error on this scene is within ``tol``,
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

    >>> a = ascan([8.0], [1.0], n_pixels=8, depth_range=64.0, k0=0.0)
    >>> np.round(np.abs(a), 12).tolist()
    [0.0, 8.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    n = check_size(n_pixels, "n_pixels", low=2, bytes_per=64.0)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    k0v = check_real(k0, "k0", low=0)
    check_choice(method, "method", ASCAN_METHODS)
    tolv = check_tol(tol)
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
    check_carrier_phase(zz, k0v)
    batch_shape = zz.shape[:-1]
    m = zz.shape[-1]
    lines = int(np.prod(batch_shape, dtype=float))
    check_memory(16.0 * lines * n, "n_pixels", f"{lines} A-scans x {n} complex128 pixels")
    if zz.size == 0:
        return np.zeros((*batch_shape, n), dtype=np.complex128)
    z2 = np.ascontiguousarray(zz.reshape(-1, m))
    a2 = np.ascontiguousarray(aa.reshape(-1, m))
    out = ASCAN_METHODS[method](z2, a2, n, h, k0v, s, tolv)
    return np.asarray(out, dtype=np.complex128).reshape(*batch_shape, n)


def stream_ascans(
    n_alines: int,
    density: float,
    *,
    n_pixels: int,
    depth_range: float,
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
    n_alines, density, n_pixels, depth_range, seed, amplitude, count
        Scene of :func:`speckle.random_scatterers` (``depth_range`` ``H`` in µm).
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

    Examples
    --------
    >>> import speckle
    >>> lines = speckle.stream_ascans(
    ...     16, 4.0, n_pixels=32, depth_range=256.0, k0=3.0, seed=1, chunk_lines=4
    ... )
    >>> lines.shape
    (16, 32)
    """
    nl_total = check_int(n_alines, "n_alines", low=1)
    n = check_int(n_pixels, "n_pixels", low=2)
    check_real(density, "density", low=0)
    step = check_int(chunk_lines, "chunk_lines", low=1)
    if lines is None:
        check_memory(
            16.0 * nl_total * n, "n_alines or n_pixels", f"{nl_total} A-lines x {n} pixels"
        )
        wanted = np.arange(nl_total)
    else:
        wanted = np.asarray(lines)
        if wanted.ndim != 1 or not np.issubdtype(wanted.dtype, np.integer):
            raise TypeError("lines must be a 1-D sequence of integer A-line indices")
        if wanted.size and (wanted.min() < 0 or wanted.max() >= nl_total):
            raise ValueError(f"lines must lie in [0, {nl_total - 1}]")
        check_memory(16.0 * wanted.size * n, "n_pixels", f"{wanted.size} lines x {n} pixels")
    out = np.empty((wanted.size, n), dtype=np.complex128)
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
                depth_range=depth_range,
                seed=seed,
                amplitude=amplitude,
                count=count,
                first_aline=first,
            )
            out[order[pos : pos + nl]] = ascan(
                scene["z"].values,
                scene["amplitude"].values,
                n_pixels=n_pixels,
                depth_range=depth_range,
                k0=k0,
                spectrum=spectrum,
                method=method,
                tol=tol,
            )
            pos += nl
    return out
