"""Detection chain after image formation: an intensity floor and log compression (optional).

The paper's model images ideal single-scattering speckle. A measured log-compressed B-scan of a
PDMS phantom (see :mod:`speckle.analysis.measured`) departs from it only in the dark tail of the
log-intensity histogram, which a constant intensity floor ``b <I>`` added before the log explains
(skewness matched, kurtosis predicted). This module adds that floor, and the 8-bit log
compression of commercial engines, to simulated intensities. Both are off unless configured.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._deprecate import keyword_only
from .._validate import as_finite_array, check_int, check_real
from ..conventions import attrs

__all__ = ["add_floor", "log_compress", "log_expand"]


def _intensity(intensity: object, name: str = "intensity") -> xr.DataArray:
    """Real, finite, non-negative intensities ``|A|^2`` (the shared check of this module)."""
    if not isinstance(intensity, xr.DataArray):
        raise TypeError(f"{name} must be an xarray.DataArray of intensities |A|^2")
    if np.iscomplexobj(intensity):
        raise TypeError(
            f"{name} must be real intensities |A|^2, got a complex array (a field): pass "
            "abs(field) ** 2 or the image's 'intensity' variable"
        )
    values = as_finite_array(intensity.values, name)  # NaN/inf refused with their count
    negative = int(np.count_nonzero(values < 0))
    if negative:
        raise ValueError(
            f"{name} must be >= 0 (an intensity); it holds {negative} negative value(s)"
        )
    return intensity


@keyword_only("mean_intensity")
def add_floor(
    intensity: xr.DataArray, floor: float, *, mean_intensity: float | None = None
) -> xr.DataArray:
    """Add a constant intensity floor ``floor * <I>`` to speckle intensities.

    Parameters
    ----------
    intensity : xarray.DataArray
        Pixel intensities ``|A|^2``.
    floor : float
        Floor in units of the mean speckle intensity (>= 0).
    mean_intensity : float, optional
        ``<I>`` (> 0), e.g. :func:`speckle.expected_intensity`; default: the sample mean.

    Returns
    -------
    xarray.DataArray
        ``I + floor * <I>`` with attrs ``floor`` and ``floor_intensity`` recorded.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(scene, src, normalise="density")
    >>> floored = speckle.add_floor(img.intensity, 0.01)
    >>> round(float((floored - img.intensity).mean() / img.intensity.mean()), 6)  # 0.01 <I>
    0.01
    """
    _intensity(intensity)
    b = check_real(floor, "floor", low=0)
    if mean_intensity is None and intensity.size == 0:
        raise ValueError("intensity is empty: its sample mean is undefined; give mean_intensity")
    mean = (
        float(intensity.mean())
        if mean_intensity is None
        else check_real(mean_intensity, "mean_intensity", low=0, low_inclusive=False)
    )
    return (intensity + b * mean).assign_attrs(intensity.attrs, floor=b, floor_intensity=b * mean)


@keyword_only("bits")
def log_compress(
    intensity: xr.DataArray, gain: float, offset: float, *, bits: int | None = 8
) -> xr.DataArray:
    """Log-compress intensities as an OCT engine does: ``D = gain*ln(I) + offset``.

    Parameters
    ----------
    intensity : xarray.DataArray
        Real intensities ``|A|^2`` (>= 0, finite; zeros map to the low clip). A complex field,
        negative or NaN values are refused (with their count).
    gain : float
        Data units per natural-log unit of intensity (> 0).
    offset : float
        Data value of ``I = 1``.
    bits : int or None
        Round to integers and clip to ``[0, 2**bits - 1]`` (1..16); ``None`` keeps floats.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> import speckle
    >>> i = xr.DataArray(np.array([[1.0, np.e, np.e**2]]), dims=("depth", "x"))
    >>> speckle.log_compress(i, 20.0, 100.0).values  # 20 ln I + 100, quantised to 8 bits
    array([[100., 120., 140.]])
    """
    _intensity(intensity)
    g = check_real(gain, "gain", low=0, low_inclusive=False)
    c = check_real(offset, "offset")
    with np.errstate(divide="ignore"):
        d = g * np.log(intensity) + c
    if bits is not None:
        nb = check_int(bits, "bits", low=1, high=16)
        d = np.clip(np.round(d.fillna(0.0).where(np.isfinite(d), 0.0)), 0, 2**nb - 1)
    return d.assign_attrs(
        attrs("dimensionless", "log-compressed intensity"),
        scale="log",
        gain=g,
        offset=c,
        bits=-1 if bits is None else bits,
    )


def log_expand(data: xr.DataArray, gain: float, offset: float) -> xr.DataArray:
    """Invert :func:`log_compress`: ``I = exp((D - offset)/gain)``.

    Without quantisation the round trip is exact; after rounding to integers the relative
    error of ``I`` is at most ``exp(1/(2 gain)) - 1`` inside the clip range.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> import speckle
    >>> i = xr.DataArray(np.array([[0.5, 1.0, 2.0]]), dims=("depth", "x"))
    >>> d = speckle.log_compress(i, 20.0, 100.0, bits=None)
    >>> speckle.log_expand(d, 20.0, 100.0).values.round(6)
    array([[0.5, 1. , 2. ]])
    """
    if not isinstance(data, xr.DataArray):
        raise TypeError("data must be an xarray.DataArray")
    as_finite_array(data.values, "data")  # real and finite (complex, NaN, inf refused)
    g = check_real(gain, "gain", low=0, low_inclusive=False)
    c = check_real(offset, "offset")
    return np.exp((data - c) / g).assign_attrs(
        attrs("dimensionless", "intensity from log-compressed data"), scale="linear"
    )
