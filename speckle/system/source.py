"""Light source: central wavenumber, spectral sampling and spectrum shape.

Conventions (used everywhere in the package)
--------------------------------------------
* Lengths are in micrometres (µm); wavenumbers in rad/µm.
* An A-scan of ``N`` pixels over an unambiguous depth ``H`` is formed from ``N`` spectral
  components ``k_n = k0 + n*pi/H`` with ``n = -(N//2) ... N-1-(N//2)`` (low to high wavenumber).
  The spacing ``dk = pi/H`` is half of the formal-Fourier spacing because light travels to the
  scatterer and back (phase ``2 k_n z``).
* The pixel step is ``H/N``: pixel ``q`` sits at depth ``q*H/N``. The paper writes
  ``H/(N-1)``, which is not consistent with an ``N``-point discrete Fourier transform; with
  ``H/N`` a scatterer at a pixel centre is imaged into exactly one pixel.
* The spectral width is ``delta_k = N*dk = N*pi/H``, so that ``k0/delta_k = N*k0*H/(N*pi)``. The
  coherence length is ``Lc = 2*pi/delta_k = 2*H/N`` (two pixels) and ``Lc/lambda0 = k0/delta_k``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_choice, check_int, check_real, check_size
from ..conventions import attrs, coord, depth_range_of, grid_attrs

__all__ = [
    "SPECTRUM_SHAPES",
    "delta_k",
    "index_shift_phase",
    "k0_from_wavelength",
    "spectral_index",
    "spectrum",
    "wavelength_from_k0",
]

SPECTRUM_SHAPES = ("rectangular", "gaussian", "array")


def k0_from_wavelength(wavelength: float, refractive_index: float = 1.0) -> float:
    """Central wavenumber in the medium, ``k0 = 2*pi*n/lambda0``.

    Parameters
    ----------
    wavelength : float
        Central vacuum wavelength ``lambda0`` in µm, > 0.
    refractive_index : float
        Group/phase refractive index ``n`` of the tissue (>= 1 is typical; must be > 0).

    Returns
    -------
    float
        ``k0`` in rad/µm.

    Examples
    --------
    >>> import speckle
    >>> round(speckle.k0_from_wavelength(0.84, refractive_index=1.38), 4)
    10.3224
    """
    lam = check_real(wavelength, "wavelength", low=0, low_inclusive=False)
    n = check_real(refractive_index, "refractive_index", low=0, low_inclusive=False)
    return 2 * np.pi * n / lam


def wavelength_from_k0(k0: float, refractive_index: float = 1.0) -> float:
    """Vacuum central wavelength in µm for a central wavenumber ``k0`` (rad/µm) in a medium.

    Examples
    --------
    >>> import speckle
    >>> round(speckle.wavelength_from_k0(10.3227, refractive_index=1.38), 4)
    0.84
    """
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    n = check_real(refractive_index, "refractive_index", low=0, low_inclusive=False)
    return 2 * np.pi * n / k


def delta_k(n_pixels: int, depth_range: float) -> float:
    """Spectral width ``N*pi/H`` in rad/µm of ``n_pixels`` components spaced ``pi/H``.

    ``depth_range`` is the unambiguous depth ``H`` in µm (> 0).

    Examples
    --------
    >>> import speckle
    >>> round(speckle.delta_k(256, 2048.0), 6)
    0.392699
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    return n * np.pi / h


def spectral_index(n_pixels: int) -> np.ndarray:
    """Spectral indices ``n = -(N//2) ... N-1-(N//2)`` (low to high wavenumber)."""
    n = check_size(n_pixels, "n_pixels", low=2)
    return np.arange(n) - n // 2


def index_shift_phase(n_pixels: int, q: object) -> np.ndarray:
    """``exp(2i pi (N//2) q / N)``: converts an FFT over ``m = n + N//2`` to the sum over ``n``.

    ``sum_n F_n exp(-2i pi n q/N) = exp(2i pi (N//2) q/N) sum_m F_{m - N//2} exp(-2i pi m q/N)``
    for the spectral indices of :func:`spectral_index`; ``q`` is a pixel index or offset (any
    real array).
    """
    return np.exp(2j * np.pi * (n_pixels // 2) * np.asarray(q) / n_pixels)


def spectrum(
    n_pixels: int,
    depth_range: float,
    *,
    k0: float | None = None,
    k0_dk: float | None = None,
    wavelength: float | None = None,
    refractive_index: float = 1.0,
    shape: str = "rectangular",
    fwhm: float | None = None,
    fwhm_fraction: float | None = None,
    weights: object | None = None,
) -> xr.DataArray:
    """Sampled source spectrum ``S(k_n)`` as a labelled DataArray.

    Exactly one of ``k0``, ``k0_dk`` and ``wavelength`` sets the central wavenumber.

    Parameters
    ----------
    n_pixels : int
        Number of spectral components ``N`` (= pixels per A-scan), >= 2.
    depth_range : float
        Unambiguous depth ``H`` in µm, > 0.
    k0 : float, optional
        Central wavenumber in the medium, rad/µm, >= 0. ``k0 = 0`` is the formal Fourier
        transform of the paper's Fig. 1.
    k0_dk : float, optional
        Ratio ``k0/delta_k`` (= ``Lc/lambda0``), >= 0, with ``delta_k = N*pi/H``.
    wavelength : float, optional
        Central vacuum wavelength in µm (> 0); combined with ``refractive_index``.
    refractive_index : float
        Refractive index of the tissue, used with ``wavelength`` only.
    shape : {"rectangular", "gaussian", "array"}
        Spectrum shape. ``"gaussian"`` needs ``fwhm`` or ``fwhm_fraction``; ``"array"`` needs
        ``weights``.
    fwhm : float, optional
        Full width at half maximum of the Gaussian spectrum in rad/µm (> 0).
    fwhm_fraction : float, optional
        The same FWHM as a fraction of ``delta_k = N*pi/H`` (> 0); give ``fwhm`` or this.
    weights : array_like, optional
        ``N`` non-negative finite weights ordered low to high wavenumber, for ``shape="array"``.

    Returns
    -------
    xarray.DataArray
        Weights ``S(k_n)`` (dimensionless) with dim ``wavenumber`` (coordinate ``k_n`` in rad/µm)
        and a coordinate ``n`` (spectral index). Attributes hold ``n_pixels``, ``depth_range``,
        ``k0``, ``delta_k``, ``k0_dk``, ``shape`` and ``fwhm`` (NaN unless Gaussian).

    Raises
    ------
    ValueError
        On a missing or ambiguous ``k0`` specification, out-of-range values or a wrong
        ``weights`` length.

    Examples
    --------
    >>> import speckle
    >>> s = speckle.spectrum(64, 512.0, k0_dk=10.0, shape="gaussian", fwhm=0.5)
    >>> s.dims, s.sizes["wavenumber"], round(float(s.attrs["k0"] / s.attrs["delta_k"]), 6)
    (('wavenumber',), 64, 10.0)
    """
    n = check_size(n_pixels, "n_pixels", low=2, bytes_per=64.0)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    check_choice(shape, "shape", SPECTRUM_SHAPES)
    check_real(refractive_index, "refractive_index", low=0, low_inclusive=False)
    given = [
        name
        for name, v in (("k0", k0), ("k0_dk", k0_dk), ("wavelength", wavelength))
        if v is not None
    ]
    if len(given) != 1:
        raise ValueError(
            "give exactly one of k0 (rad/µm), k0_dk (k0/delta_k) or wavelength (µm); "
            f"got {given or 'none'}"
        )
    dk_total = delta_k(n, h)
    if k0 is not None:
        k0v = check_real(k0, "k0", low=0)
    elif k0_dk is not None:
        k0v = check_real(k0_dk, "k0_dk", low=0) * dk_total
    else:
        k0v = k0_from_wavelength(wavelength, refractive_index)
    idx = spectral_index(n)
    k = k0v + idx * np.pi / h
    fwhm_v = np.nan
    if fwhm is not None and fwhm_fraction is not None:
        raise ValueError("give fwhm (rad/µm) or fwhm_fraction (of delta_k), not both")
    if fwhm_fraction is not None:
        fwhm = check_real(fwhm_fraction, "fwhm_fraction", low=0, low_inclusive=False) * dk_total
    if shape == "rectangular":
        if weights is not None or fwhm is not None:
            raise ValueError("shape='rectangular' takes neither fwhm/fwhm_fraction nor weights")
        s = np.ones(n)
    elif shape == "gaussian":
        if fwhm is None:
            raise ValueError(
                "shape='gaussian' needs fwhm (rad/µm, > 0) or fwhm_fraction (of delta_k, > 0)"
            )
        fwhm_v = check_real(fwhm, "fwhm", low=0, low_inclusive=False)
        s = np.exp(-4 * np.log(2) * ((k - k0v) / fwhm_v) ** 2)
    else:
        if weights is None or fwhm is not None:
            raise ValueError("shape='array' needs weights (N non-negative values) and no fwhm")
        s = check_weights(weights, n)
    return xr.DataArray(
        s,
        dims=("wavenumber",),
        coords={
            "wavenumber": coord("wavenumber", k, "wavenumber k_n"),
            "n": coord("n", idx, dims="wavenumber"),
        },
        name="spectrum",
        attrs={
            **attrs("weight"),
            **grid_attrs(n, h, k0v),
            "delta_k": dk_total,
            "k0_dk": k0v / dk_total,
            "shape": shape,
            "fwhm": fwhm_v,
        },
    )


def check_weights(weights: object, n_pixels: int, name: str = "spectrum") -> np.ndarray:
    """Validate a user spectrum: ``n_pixels`` finite, non-negative weights, not all zero
    (errors name ``name``)."""
    s = as_finite_array(weights, name)
    if s.ndim != 1 or s.size != n_pixels:
        raise ValueError(
            f"{name} must hold exactly n_pixels={n_pixels} weights (1-D), got shape {s.shape}"
        )
    if np.any(s < 0):
        raise ValueError(f"{name} must hold non-negative weights")
    if not np.any(s > 0):
        raise ValueError(f"{name} must hold weights that are not all zero")
    return s


def check_source(source: object, name: str = "source") -> dict:
    """Check a source spectrum made by :func:`spectrum` and return its parts.

    Returns
    -------
    dict
        ``n_pixels``, ``depth_range`` (µm), ``k0`` (rad/µm) and ``spectrum`` (the checked
        weights, one per pixel).

    Raises
    ------
    TypeError, ValueError
        Naming ``name``: not a DataArray with the attributes of :func:`spectrum`, or weights
        that are not ``n_pixels`` finite, non-negative values, not all zero (e.g. an empty
        selection of a source).
    """
    if not isinstance(source, xr.DataArray) or not {"n_pixels", "k0"} <= set(source.attrs):
        raise TypeError(f"{name} must be a DataArray from speckle.spectrum")
    n = check_int(source.attrs["n_pixels"], f"{name} attribute n_pixels", low=1)
    return {
        "n_pixels": n,
        "depth_range": depth_range_of(source, name),
        "k0": check_real(source.attrs["k0"], f"{name} attribute k0"),
        "spectrum": check_weights(source.values, n, name),
    }
