"""Contrasts of speckle in time: g1, g2, Doppler phase, speckle variance, SSADA, LIV and OCDS.

Every contrast takes images with a ``time`` dim (from :mod:`speckle.imaging.timeseries`, or a
user's series) and has a numpy core (``*_array``, time on axis 0, the other axes spatial) and
one xarray wrapper. Options shared by all:

* ``window`` -- ``None``: pool every pixel (one value or curve for the image, the estimate for
  a homogeneous region); sizes in pixels, one per spatial axis (an int or ``(depth, x)`` pair
  for B-scans, as everywhere in :mod:`speckle.analysis`): a boxcar of that size pools each
  pixel's neighbours (a map).
* ``stride`` -- use every ``stride``-th frame: the inter-frame time of the contrast is
  ``stride`` times the acquisition's (the "time interval" choice of angiography protocols).

Definitions (``<.>`` the pooled average over time pairs and the window):

* ``g1(tau) = <A*(t) A(t+tau)> / sqrt(<|A(t)|^2> <|A(t+tau)|^2>)`` (complex; its phase grows
  as ``+2 k0 v_z tau`` for motion to larger depth);
* ``g2(tau) = <I(t) I(t+tau)> / (<I(t)> <I(t+tau)>)``;
* ``doppler_phase`` -- Kasai's lag-one estimator ``arg <A*(t) A(t+lag)>`` (rad); the axial
  velocity is ``phase / (2 k0 lag dt)``;
* ``speckle_variance`` -- the time variance of the intensity (or of ``10 log10 I``) per pixel;
* ``ssada`` -- split-spectrum amplitude decorrelation (Jia et al., Opt. Express 20, 4710,
  2012): the spectrum split into ``n_bands`` sub-bands (:func:`speckle.subband_apodizations`,
  :func:`speckle.frequency_looks`), ``D = 1 - <A_b(t) A_b(t+1) / ((A_b(t)^2 +
  A_b(t+1)^2)/2)>`` over bands and consecutive frames;
* ``liv`` -- logarithmic intensity variance, ``var_t(10 log10 I)`` in dB^2, and ``ocds`` -- OCT
  correlation decay speed, minus the slope (1/s) of the correlation coefficient of
  ``10 log10 I`` between frames ``tau`` apart against ``tau`` over a delay range
  ``[tau1, tau2]``: the dynamic-OCT contrasts of the Tsukuba group (El-Sadek et al.,
  "Optical coherence tomography-based tissue dynamics imaging for longitudinal and drug
  response evaluation of tumor spheroids", Biomed. Opt. Express 11, 6231-6248, 2020; their
  wavelength and resolution dependence: Fujimura et al., arXiv:2503.21539, 2025).

Estimators with no answer (a pixel whose intensity is zero, a window with no signal) return
NaN with a ``RuntimeWarning`` saying why.

Every contrast (and ``*_array`` core) computes a Dask-backed series lazily, chunk by chunk (the
time dim whole in each chunk; SSADA also each A-line): per-pixel time moments, pooled by the
mean (``window=None``) or the boxcar with an overlap of ``window // 2`` pixels, then finished
per pixel; the result is a Dask array with the numpy path's numbers to rounding (1e-12), and NaN
warnings come when it is computed (:mod:`speckle.analysis._pooling`).
The expected values of each contrast for developed speckle are in
:mod:`speckle.analysis.dynamics_theory` (re-exported here).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from .._deprecate import renamed_parameters
from .._validate import check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, coord, spacing
from ._common import delay_selection
from ._pooling import (
    checked_series,
    decibels,
    frame_lags,
    is_dask,
    no_answer,
    pooled_contrast,
    ratio,
    series_values,
)
from .compounding import SUBBAND_APODIZATIONS, frequency_looks, subband_apodizations
from .dynamics_theory import (
    doppler_shift,
    g1_axial_flow,
    g1_ballistic,
    g1_brownian,
    g1_transverse_flow,
    liv_expected,
    log_intensity_correlation,
    ocds_expected,
    siegert_g2,
    speckle_variance_expected,
    ssada_expected,
)

__all__ = [
    "doppler_phase",
    "doppler_phase_array",
    "g1",
    "g1_array",
    "g2",
    "g2_array",
    "liv",
    "liv_array",
    "ocds",
    "ocds_array",
    "speckle_variance",
    "speckle_variance_array",
    "ssada",
    "ssada_array",
]

_THEORY = (
    doppler_shift,
    g1_axial_flow,
    g1_ballistic,
    g1_brownian,
    g1_transverse_flow,
    liv_expected,
    log_intensity_correlation,
    ocds_expected,
    siegert_g2,
    speckle_variance_expected,
    ssada_expected,
)


# ------------------------------------------------------------------------------------------
# shared helpers
# ------------------------------------------------------------------------------------------


#: A series (time on axis 0): finite, non-empty numbers; the field complex (the decorator's
#: checks). :func:`_series` adds the frame count and the intensity's sign.
_INTENSITY = ArraySpec(kind="number", lazy=True)
_FIELD = ArraySpec(kind="complex", lazy=True)
#: A labelled complex series (a DataArray with a time dim, or a Dataset's field).
_FIELD_SERIES = {
    "images": ArraySpec(
        kind="complex", labelled=True, keep_labels=True, variable="field", lazy=True
    )
}


# ------------------------------------------------------------------------------------------
# numpy cores (Dask arrays too: lazily, :func:`pooled_contrast`)
# ------------------------------------------------------------------------------------------


@preprocess_and_wrap(checks={"field": _FIELD})
def g1_array(field: object, lags: object, *, window: object = None) -> np.ndarray:
    """Complex field autocorrelation at integer frame ``lags`` (module docstring).

    Parameters
    ----------
    field : array_like
        Complex, time on axis 0, then the spatial axes.
    lags : sequence of int
        Lags in frames, in ``[0, T-1]``.
    window : tuple of int, optional
        Boxcar (pixels per spatial axis); None pools every pixel.

    Returns
    -------
    numpy.ndarray
        Complex, shape ``(len(lags),)`` or ``(len(lags), *spatial)``; NaN (with a warning)
        where the pooled intensity is zero.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.exp(1j * np.arange(4))[:, None] * np.ones((4, 3))
    >>> np.round(g1_array(a, [1]), 12).tolist()
    [(0.540302305868+0.841470984808j)]
    """
    f = checked_series(field, "field", complex_=True)
    n = f.shape[0]
    m = frame_lags(lags, n)

    def moments(f):
        out = []
        for lag in m:
            a, b = f[: n - lag], f[lag:]
            out += [np.mean(a.conj() * b, axis=0), np.mean(np.abs(a) ** 2, axis=0)]
            out.append(np.mean(np.abs(b) ** 2, axis=0))
        return out

    def finish(p):
        why = "no signal (zero intensity) to correlate"
        return np.stack(
            [ratio(p[i], np.sqrt(p[i + 1] * p[i + 2]), "g1", why) for i in range(0, len(p), 3)]
        )

    return pooled_contrast(f, moments, finish, window)


@preprocess_and_wrap(checks={"intensity": _INTENSITY})
def g2_array(intensity: object, lags: object, *, window: object = None) -> np.ndarray:
    """Intensity autocorrelation ``<I(t) I(t+tau)> / (<I(t)> <I(t+tau)>)`` at frame ``lags``.

    Parameters as :func:`g1_array` (``intensity`` real >= 0, or a complex field whose
    ``|A|^2`` is used).

    Examples
    --------
    >>> import numpy as np
    >>> g2_array(np.ones((3, 2)), [0, 2]).tolist()
    [1.0, 1.0]
    """
    i = checked_series(intensity, "intensity")
    n = i.shape[0]
    m = frame_lags(lags, n)

    def moments(i):
        out = []
        for lag in m:
            a, b = i[: n - lag], i[lag:]
            out += [np.mean(a * b, axis=0), np.mean(a, axis=0), np.mean(b, axis=0)]
        return out

    def finish(p):
        why = "zero mean intensity"
        return np.stack([ratio(p[j], p[j + 1] * p[j + 2], "g2", why) for j in range(0, len(p), 3)])

    return pooled_contrast(i, moments, finish, window)


@preprocess_and_wrap(checks={"field": _FIELD})
def doppler_phase_array(field: object, *, lag: int = 1, window: object = None) -> np.ndarray:
    """Kasai's phase estimator ``arg <A*(t) A(t+lag)>`` in rad, in ``(-pi, pi]``.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.exp(0.3j * np.arange(5))[:, None] * np.ones((5, 2))
    >>> round(float(doppler_phase_array(a)), 12)
    0.3
    """
    f = checked_series(field, "field", complex_=True)
    n = f.shape[0]
    lg = check_int(lag, "lag", low=1, high=n - 1)

    def finish(p):
        bad = ~(np.abs(p[0]) > 0)
        no_answer(bad, "doppler_phase", "zero lag correlation (no signal): the phase is undefined")
        return np.where(bad, np.nan, np.angle(p[0]))

    def moments(f):
        return [np.mean(f[: n - lg].conj() * f[lg:], axis=0)]

    return pooled_contrast(f, moments, finish, window)


@preprocess_and_wrap(checks={"intensity": _INTENSITY})
def speckle_variance_array(
    intensity: object, *, ddof: int = 0, log: bool = False, window: object = None
) -> np.ndarray:
    """Time variance of the intensity per pixel (``log``: of ``10 log10 I``, dB^2).

    ``ddof`` 0 (the angiography convention ``1/N sum (I - mean)^2``) or 1; ``window`` a
    boxcar applied to the variance map (None: the mean over every pixel).

    Examples
    --------
    >>> import numpy as np
    >>> float(speckle_variance_array(np.array([[1.0], [3.0]]), window=(1,))[0])
    1.0
    """
    i = checked_series(intensity, "intensity")
    d = check_int(ddof, "ddof", low=0, high=1)
    if not isinstance(log, bool):
        raise TypeError(f"log must be True or False, got {log!r}")

    def moments(i):
        return [np.var(decibels(i, "speckle_variance") if log else i, axis=0, ddof=d)]

    return pooled_contrast(i, moments, lambda p: p[0], window)


@preprocess_and_wrap(checks={"intensity": _INTENSITY})
def liv_array(intensity: object, *, ddof: int = 0, window: object = None) -> np.ndarray:
    """Logarithmic intensity variance ``var_t(10 log10 I)`` (dB^2) per pixel.

    NaN (warned) where an intensity is zero. See :func:`liv`.

    Examples
    --------
    >>> import numpy as np
    >>> float(liv_array(np.array([[1.0], [10.0]]), window=(1,))[0])  # (10 dB)^2 / 4
    25.0
    """
    i = checked_series(intensity, "intensity")
    d = check_int(ddof, "ddof", low=0, high=1)

    def moments(i):
        return [np.var(decibels(i, "liv"), axis=0, ddof=d)]

    return pooled_contrast(i, moments, lambda p: p[0], window)


@preprocess_and_wrap(
    checks={"amplitudes": ArraySpec(kind="number", ndim=tuple(range(2, 8)), lazy=True)}
)
def ssada_array(amplitudes: object, *, window: object = None) -> np.ndarray:
    """Split-spectrum amplitude decorrelation from sub-band amplitudes ``(band, time, ...)``.

    ``D = 1 - mean over bands and consecutive frames of A(t) A(t+1) / ((A(t)^2 + A(t+1)^2)/2)``
    per pixel (Jia et al. 2012), then ``window`` (boxcar; None: mean over pixels). Static
    speckle gives 0; independent frames of developed speckle ``1 - pi/4`` (``I1/(I1 + I2)``
    is uniform for independent exponential intensities, and ``E 2 sqrt(u (1 - u)) = pi/4``).

    Examples
    --------
    >>> import numpy as np
    >>> float(ssada_array(np.ones((2, 3, 4))))
    0.0
    """
    a = np.abs(amplitudes if is_dask(amplitudes) else np.asarray(amplitudes))
    if a.shape[1] < 2:
        raise ValueError(
            f"amplitudes must be (band, time, ...) with at least 2 frames, got {a.shape}"
        )
    return pooled_contrast(a, lambda b: [_decorrelation(b)], lambda p: p[0], window, core_axes=2)


def _decorrelation(a: np.ndarray) -> np.ndarray:
    """SSADA's per-pixel ``D`` from sub-band amplitudes ``(band, time, ...)``."""
    num = a[:, :-1] * a[:, 1:]
    den = 0.5 * (a[:, :-1] ** 2 + a[:, 1:] ** 2)
    r = ratio(num, den, "ssada", "zero amplitude in both frames of a band")
    return 1.0 - np.mean(r, axis=(0, 1))


@preprocess_and_wrap(checks={"intensity": _INTENSITY})
def ocds_array(
    intensity: object,
    lags: object,
    *,
    interval: float,
    delays: tuple[float, float],
    window: object = None,
) -> np.ndarray:
    """OCT correlation decay speed (1/s) from an intensity series (see :func:`ocds`).

    Parameters
    ----------
    intensity : array_like
        Real >= 0 (or a complex field), time on axis 0.
    lags : sequence of int
        Frame lags whose correlation is computed (those in ``delays`` are fitted).
    interval : float
        Time between frames in s (> 0).
    delays : (float, float)
        Delay range ``[tau1, tau2]`` in s of the linear fit.
    window : tuple of int, optional
        Boxcar pooling the correlation's moments (None: every pixel).

    Returns
    -------
    numpy.ndarray
        ``-slope`` of the correlation of ``10 log10 I`` against ``tau``: a scalar or a map.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> static = np.repeat(rng.exponential(size=(1, 50)), 6, axis=0)
    >>> abs(float(ocds_array(static, [1, 2, 3], interval=0.1, delays=(0.1, 0.3)))) < 1e-9
    True
    """
    i = checked_series(intensity, "intensity")
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    m = frame_lags(lags, i.shape[0])
    sel = delay_selection(m * dt, delays)
    m = m[sel]
    n = i.shape[0]

    def moments(i):
        x = decibels(i, "ocds")
        out = []
        for lag in m:
            a, b = x[: n - lag], x[lag:]
            out += [a.mean(0), b.mean(0), (a * b).mean(0), (a * a).mean(0), (b * b).mean(0)]
        return out

    def finish(p):
        rho = []
        for j in range(0, len(p), 5):
            ma, mb, ab, aa, bb = p[j : j + 5]
            cov, va, vb = ab - ma * mb, aa - ma**2, bb - mb**2
            why = "no intensity variation"
            rho.append(ratio(cov, np.sqrt(np.maximum(va * vb, 0)), "ocds", why))
        rho = np.stack(rho)
        tau = (m * dt).reshape(-1, *[1] * (rho.ndim - 1))
        tc = tau - tau.mean()
        return -np.sum(tc * (rho - rho.mean(axis=0)), axis=0) / np.sum(tc**2)

    return pooled_contrast(i, moments, finish, window)


# ------------------------------------------------------------------------------------------
# xarray wrappers
# ------------------------------------------------------------------------------------------


def _timed(images: object, what: str, *, complex_: bool, uniform: bool, stride: int):
    """The DataArray (``field`` or ``intensity`` of a Dataset) with time first, strided."""
    if isinstance(images, xr.Dataset):
        name = "field" if complex_ or "intensity" not in images else "intensity"
        if name not in images:
            raise ValueError(f"{what} needs a 'field' variable (complex), got {list(images)}")
        images = images[name]
    if not isinstance(images, xr.DataArray):
        raise TypeError(
            f"images must be an xarray DataArray or Dataset with a 'time' dim ({what}), got "
            f"{type(images).__name__}"
        )
    if "time" not in images.dims:
        raise ValueError(
            f"{what} needs images with a 'time' dim (s), got dims {images.dims}: image a moved "
            "scene with speckle.imaging.timeseries, or add the frames' times"
        )
    st = check_int(stride, "stride", low=1)
    da = images.transpose("time", ...).isel(time=slice(None, None, st))
    if da.sizes["time"] < 2 or da.size == 0:
        raise ValueError(
            f"images must hold at least 2 frames along 'time' (every {st}-th taken) and a "
            f"pixel ({what}), got sizes {dict(images.sizes)}"
        )
    dt = None
    if uniform:
        if "time" not in da.coords:
            raise ValueError(f"{what} needs a 'time' coordinate in s")
        try:
            dt = spacing(da, "time")
        except ValueError as err:
            raise ValueError(
                f"{what} needs equally spaced times (its lags are whole frames): {err}"
            ) from None
    return da, dt


def _spatial(da: xr.DataArray) -> dict:
    return {d: da[d] for d in da.dims[1:] if d in da.coords}


def _map(values: np.ndarray, da: xr.DataArray, window, name: str, quantity: tuple) -> xr.DataArray:
    if window is None:
        return xr.DataArray(values, name=name, attrs=attrs(*quantity))
    return xr.DataArray(
        values, dims=da.dims[1:], coords=_spatial(da), name=name, attrs=attrs(*quantity)
    )


def _lag_da(values, m, dt, da, window, name, quantity) -> xr.DataArray:
    dims = ("lag",) if window is None else ("lag", *da.dims[1:])
    coords = {"lag": coord("time_lag", m * dt, dims="lag")}
    coords["lag_frames"] = coord("lag", m, "lag in frames", dims="lag")
    if window is not None:
        coords.update(_spatial(da))
    return xr.DataArray(values, dims=dims, coords=coords, name=name, attrs=attrs(*quantity))


@preprocess_and_wrap(checks=_FIELD_SERIES)
def g1(
    images: xr.DataArray | xr.Dataset,
    *,
    lags: Sequence[int] | None = None,
    window: object = None,
    stride: int = 1,
    blocks: int | None = None,
    block_dim: str | None = None,
) -> xr.DataArray | xr.Dataset:
    """Complex field autocorrelation ``g1(tau)`` of an image series (module docstring).

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        Complex ``field`` with a ``time`` dim (equally spaced, s), e.g. from
        :func:`speckle.imaging.timeseries.bscan_series` or
        :func:`~speckle.imaging.timeseries.mmode`; Dask-backed: lazily (module docstring).
    lags : sequence of int, optional
        Lags in frames (of the strided series); default ``0 ... T-1``.
    window : tuple of int, optional
        Boxcar per spatial dim (pixels): a map; None: pooled over the image.
    stride : int
        Use every ``stride``-th frame.
    blocks : int, optional
        With ``window=None``: also the standard error, from ``blocks`` (>= 2) contiguous
        blocks along ``block_dim``: ``std(|g1_b|)/sqrt(blocks)``, returned with ``g1`` in a
        Dataset. Valid when the blocks' speckle is independent: blocks of depth pixels (a
        rectangular spectrum's pixels are uncorrelated) or of lines much wider than the beam.
    block_dim : str, optional
        The spatial dim split into blocks (default: the last); only with ``blocks``.

    Returns
    -------
    xarray.DataArray or xarray.Dataset
        ``g1`` over ``lag`` (coordinate in s; ``lag_frames`` in frames) [and the spatial
        dims]; with ``blocks`` a Dataset of ``g1`` and ``g1_se``.

    Raises
    ------
    ValueError
        No ``time`` dim, unequal time steps, lags out of range, a real (intensity) input.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> f = xr.DataArray(np.ones((3, 4), complex), dims=("time", "x"),
    ...                  coords={"time": [0.0, 0.1, 0.2]})
    >>> g1(f).lag.values.tolist()
    [0.0, 0.1, 0.2]
    """
    da, dt = _timed(images, "g1", complex_=True, uniform=True, stride=stride)
    if block_dim is not None:
        if not isinstance(block_dim, str):
            raise TypeError(f"block_dim must be a dim name, got {block_dim!r}")
        if block_dim not in da.dims[1:]:
            raise ValueError(f"block_dim must be a spatial dim of {da.dims[1:]}, got {block_dim!r}")
        if blocks is None:
            raise ValueError("block_dim is used only with blocks (the standard error)")
    n = da.sizes["time"]
    m = np.arange(n) if lags is None else frame_lags(lags, n)
    arr = series_values(da)  # numpy: loaded once (not per block); Dask: lazy
    values = g1_array.__wrapped__(arr, m, window=window)  # checked here once
    out = _lag_da(values, m, dt, da, window, "g1", ("correlation", "field autocorrelation g1"))
    if blocks is None:
        return out
    k = check_int(blocks, "blocks", low=2)
    if window is not None or da.ndim < 2:
        raise ValueError("blocks needs window=None and a spatial dim to split")
    last = da.dims[-1] if block_dim is None else block_dim
    if da.sizes[last] < k:
        raise ValueError(f"blocks={k} exceeds the {da.sizes[last]} elements along {last!r}")
    axis = da.dims.index(last)
    parts = np.array_split(np.arange(da.sizes[last]), k)
    est = np.stack([np.abs(g1_array.__wrapped__(np.take(arr, p, axis=axis), m)) for p in parts])
    se = est.std(axis=0, ddof=1) / np.sqrt(k)
    se_da = out.copy(data=se).rename("g1_se")
    se_da.attrs = attrs("correlation", f"standard error of |g1| from {k} blocks along {last}")
    return xr.Dataset({"g1": out, "g1_se": se_da})


def g2(
    images: xr.DataArray | xr.Dataset,
    *,
    lags: Sequence[int] | None = None,
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """Intensity autocorrelation ``g2(tau)`` of an image series (``1 + beta |g1|^2``).

    Parameters as :func:`g1` (``intensity`` or a complex ``field``, whose ``|A|^2`` is used).

    Returns
    -------
    xarray.DataArray
        ``g2`` over ``lag`` (s) [and the spatial dims].

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> i = xr.DataArray(np.ones((3, 4)), dims=("time", "x"), coords={"time": [0.0, 1, 2]})
    >>> g2(i, lags=[1]).values.tolist()
    [1.0]
    """
    da, dt = _timed(images, "g2", complex_=False, uniform=True, stride=stride)
    n = da.sizes["time"]
    m = np.arange(n) if lags is None else frame_lags(lags, n)
    values = g2_array(series_values(da), m, window=window)
    return _lag_da(values, m, dt, da, window, "g2", ("correlation", "intensity autocorrelation"))


@preprocess_and_wrap(checks=_FIELD_SERIES)
def doppler_phase(
    images: xr.DataArray | xr.Dataset,
    *,
    lag: int = 1,
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """Doppler phase shift between frames ``lag`` apart (Kasai), rad in ``(-pi, pi]``.

    The axial velocity is ``phase / (2 k0 lag dt)`` (``k0`` in the medium, positive: deeper;
    :func:`speckle.analysis.dynamics_theory.doppler_shift`), unambiguous for
    ``|v_z| < pi / (2 k0 lag dt)``.

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        Complex ``field`` with an equally spaced ``time`` dim.
    lag, window, stride
        Frames between the pair, boxcar (None: pooled), frame stride.

    Returns
    -------
    xarray.DataArray
        Phase (rad): a map (with ``window``) or a scalar; attribute ``interval`` (s) is
        ``lag`` times the frame step.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> f = xr.DataArray(np.exp(0.2j * np.arange(4))[:, None] * np.ones((4, 2)),
    ...                  dims=("time", "x"), coords={"time": [0.0, 1, 2, 3]})
    >>> round(float(doppler_phase(f)), 12)
    0.2
    """
    da, dt = _timed(images, "doppler_phase", complex_=True, uniform=True, stride=stride)
    v = doppler_phase_array.__wrapped__(series_values(da), lag=lag, window=window)
    out = _map(v, da, window, "doppler_phase", ("phase", "Doppler phase shift (Kasai)"))
    return out.assign_attrs(interval=float(lag * dt))


def speckle_variance(
    images: xr.DataArray | xr.Dataset,
    *,
    ddof: int = 0,
    log: bool = False,
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """Speckle variance: the time variance of the intensity per pixel (angiography).

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        ``intensity`` (or a complex ``field``) with a ``time`` dim (any sampling).
    ddof : {0, 1}
        Divisor ``N - ddof``.
    log : bool
        Variance of ``10 log10 I`` (dB^2) instead of ``I``.
    window, stride
        Boxcar on the map (None: mean over the image), frame stride.

    Returns
    -------
    xarray.DataArray
        Map (or scalar) in the intensity's units squared (``log``: dB^2). Expected value for
        developed speckle: :func:`speckle.analysis.dynamics_theory.speckle_variance_expected`
        times ``<I>^2``.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> i = xr.DataArray([[1.0], [3.0]], dims=("time", "x"))
    >>> float(speckle_variance(i))
    1.0
    """
    da, _ = _timed(images, "speckle_variance", complex_=False, uniform=False, stride=stride)
    v = speckle_variance_array(series_values(da), ddof=ddof, log=log, window=window)
    q = ("log_variance", "speckle variance of 10 log10 I") if log else ("dimensionless", "SV")
    return _map(v, da, window, "speckle_variance", q)


def liv(
    images: xr.DataArray | xr.Dataset,
    *,
    ddof: int = 0,
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """Logarithmic intensity variance (LIV, dB^2): ``var_t(10 log10 I)`` per pixel.

    The Tsukuba group's dynamic-OCT contrast (El-Sadek et al., Biomed. Opt. Express 11, 6231,
    2020): the time variance of the dB-scaled intensity over the acquisition, sensitive to the
    magnitude of the fluctuations. Developed, fully decorrelated speckle gives
    ``(1 - 1/N) (10/ln 10)^2 pi^2/6 = (1 - 1/N) 31.0 dB^2``; the expected value for any
    ``g1`` is :func:`speckle.analysis.dynamics_theory.liv_expected`.

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        ``intensity`` (or complex ``field``) with a ``time`` dim.
    ddof, window, stride
        As in :func:`speckle_variance`.

    Returns
    -------
    xarray.DataArray
        LIV map (or its mean over the image with ``window=None``), dB^2.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> i = xr.DataArray([[1.0], [10.0]], dims=("time", "x"))
    >>> float(liv(i))
    25.0
    """
    da, _ = _timed(images, "liv", complex_=False, uniform=False, stride=stride)
    v = liv_array(series_values(da), ddof=ddof, window=window)
    return _map(v, da, window, "liv", ("log_variance", "logarithmic intensity variance"))


@renamed_parameters({"band_window": "band_apodization"})
@preprocess_and_wrap(checks=_FIELD_SERIES)
def ssada(
    images: xr.DataArray | xr.Dataset,
    *,
    n_bands: int = 4,
    band_apodization: str = "hann",
    overlap: float = 0.5,
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """Split-spectrum amplitude decorrelation (SSADA, Jia et al., Opt. Express 20, 4710, 2012).

    The depth spectrum of each frame is split into ``n_bands`` sub-bands
    (:func:`speckle.subband_apodizations`, applied by :func:`speckle.frequency_looks`: exact, as
    imaging with the apodized spectrum), and the amplitude decorrelation of consecutive frames
    is averaged over bands and frame pairs (:func:`ssada_array`).

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        Complex ``field`` with dims ``time`` and ``depth`` (the full A-line of ``N`` pixels).
    n_bands : int
        Sub-bands (>= 1).
    band_apodization : {"rectangular", "gaussian", "hann"}
        Sub-band apodization shape; ``overlap`` in ``[0, 1)``.
    window, stride
        Boxcar on the decorrelation map (None: its mean), frame stride.

    Returns
    -------
    xarray.DataArray
        Decorrelation ``D`` (0 static; ``1 - pi/4`` for independent developed speckle).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> f = xr.DataArray(np.ones((3, 8, 2), complex), dims=("time", "depth", "x"))
    >>> float(ssada(f, n_bands=2))
    0.0
    """
    da, _ = _timed(images, "ssada", complex_=True, uniform=False, stride=stride)
    if "depth" not in da.dims:
        raise ValueError("ssada needs a 'depth' dim (the A-line, to split its spectrum)")
    n_bands = check_int(n_bands, "n_bands", low=1, high=da.sizes["depth"])
    check_choice(band_apodization, "band_apodization", SUBBAND_APODIZATIONS)
    w = subband_apodizations(
        da.sizes["depth"], n_bands, apodization=band_apodization, overlap=overlap
    )
    if is_dask(da.data):  # the looks per block of whole A-lines (the split is along depth)

        def moments(block):
            looks = frequency_looks(xr.DataArray(block, dims=da.dims), w)  # (look, time, ...)
            return [_decorrelation(np.abs(looks.transpose("look", *da.dims).values))]

        axis = da.dims.index("depth")
        v = pooled_contrast(da.data, moments, lambda p: p[0], window, whole=(axis,))
    else:
        looks = frequency_looks(da, w)  # (look, time, ...)
        amplitudes = np.abs(looks.transpose("look", *da.dims).values)
        v = ssada_array.__wrapped__(amplitudes, window=window)
    out = _map(v, da, window, "ssada", ("dimensionless", "split-spectrum amplitude decorrelation"))
    return out.assign_attrs(
        n_bands=int(n_bands), band_apodization=band_apodization, overlap=float(overlap)
    )


def ocds(
    images: xr.DataArray | xr.Dataset,
    *,
    delays: tuple[float, float],
    window: object = None,
    stride: int = 1,
) -> xr.DataArray:
    """OCT correlation decay speed (OCDS, 1/s), the Tsukuba group's dynamic-OCT contrast.

    The correlation coefficient ``rho(tau)`` of the dB-scaled intensity ``10 log10 I`` between
    frames ``tau`` apart (pooled over the time pairs and the ``window``) is computed for every
    lag in ``delays = [tau1, tau2]`` and OCDS is minus the slope of its least-squares line
    against ``tau`` (El-Sadek et al., Biomed. Opt. Express 11, 6231, 2020: early and late OCDS
    are two choices of the delay range). Expected value for developed speckle:
    ``rho = Li2(|g1|^2)/Li2(1)`` (:func:`speckle.analysis.dynamics_theory.ocds_expected`).

    Parameters
    ----------
    images : xarray.DataArray or Dataset
        ``intensity`` (or complex ``field``) with an equally spaced ``time`` dim.
    delays : (float, float)
        Delay range in s (at least two lags of the series inside).
    window : tuple of int, optional
        Boxcar (pixels per spatial dim) pooling the correlation (None: the whole image).
    stride : int
        Frame stride.

    Returns
    -------
    xarray.DataArray
        OCDS in 1/s (a map with ``window``).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> rng = np.random.default_rng(0)
    >>> i = xr.DataArray(np.repeat(rng.exponential(size=(1, 40)), 5, 0), dims=("time", "x"),
    ...                  coords={"time": np.arange(5) * 0.1})
    >>> abs(float(ocds(i, delays=(0.1, 0.4)))) < 1e-9  # static: no decay
    True
    """
    da, dt = _timed(images, "ocds", complex_=False, uniform=True, stride=stride)
    n = da.sizes["time"]
    v = ocds_array(series_values(da), np.arange(1, n), interval=dt, delays=delays, window=window)
    out = _map(v, da, window, "ocds", ("decay_speed", "OCT correlation decay speed"))
    return out.assign_attrs(delay_min=float(delays[0]), delay_max=float(delays[1]))
