"""Axial strain and displacement from a pair of complex OCT images, behind one API.

Conventions
-----------
Images are complex fields over ``(depth, aline)`` (axis 0 = depth). A scatterer at depth ``z``
contributes ``exp(2i k0 z)`` (``k0`` = central wavenumber in the medium, rad/µm), so a
displacement ``u`` (µm, positive = deeper, as in :mod:`speckle.scene.deformation`) turns the
phase of the interframe product ``A2 A1*`` by ``dphi = 2 k0 u``. Under compression ``s`` by a
probe at ``z = 0`` a scatterer moves to ``z (1 - s)``: ``u = -s z``, ``dphi = -2 k0 s z`` and

    s = -du/dz = -(1 / (2 k0)) d(dphi)/dz        (positive for compression).

Methods (``method=``)
---------------------
``"vector"`` (default)
    Phase-sensitive vector method: window sums of ``C = A1(z) A2*(z) A1*(z+L) A2(z+L)``; the
    phase of the sum is ``2 k0 (u(z+L) - u(z)) = -2 k0 s L p`` (``p`` = pixel size), so
    ``s = -arg(sum C) / (2 k0 L p)``. No unwrapping. The lag ``L`` is chosen from the reference
    image's depth autocorrelation (:func:`speckle.analysis.phase.choose_lag`: the smallest lag
    whose correlation ``rho(L)^2`` is below 0.5 %, so the low bias
    ``rho^2/(gamma^2 + rho^2)`` of correlated neighbours is below 0.5 %). It wraps when
    ``|2 k0 s L p| > pi``, i.e. ``|s| > 1/(2 R L)`` with ``R = k0 p / pi = k0/delta_k``; the
    lag-1 phase (wraps only at ``1/(2R)``), times ``L`` and its known low-bias factor
    ``1 + rho(1)^2``, picks the ``2 pi`` branch (multi-lag unwrapping, ``wrap_check``), so the
    range extends to ``1/(2R)``. Quality: ``|sum C| / sum |C|``; NaN below ``min_quality``
    (0.5; decorrelated windows).
``"wls"``
    Weighted least-squares gradient of the unwrapped interframe phase: ``A2 A1*`` is summed
    over ``L`` depth pixels (the speckle size), unwrapped along depth, and a line
    ``dphi = a_line + b z`` (one intercept per A-line, one slope per window) is fitted with
    weights ``I1 I2 / (I1 + I2)`` (the inverse phase-noise variance at high SNR, up to the
    noise power). ``s = -b / (2 k0 p)``. Unwrapping needs ``2 pi R |s| < pi`` per pixel plus
    the speckle phase noise; NaN where the fitted step disagrees by more than ``pi/4`` with the
    complex-averaged lag-1 step (Gaussian cross term removed) or the phasors do not follow the
    fitted line (quality = their coherence, below ``min_quality``). Every window is fitted at
    once (running sums of the moments); the coherence is a polynomial in ``exp(-i slope)``
    evaluated by Horner's rule over the window (single precision: 1e-6).
``"tracking"``
    :func:`speckle.track` (sub-pixel amplitude registration, axial refinement only) in windows
    stepped by ``step`` pixels in depth and side by side in aline, interpolated to every pixel,
    then a least-squares gradient over the window (unit weights: closed form from two running
    sums). Serves supra-pixel displacements; its noise floor is set by the registration error.
    Quality: ``1 - registration error``; NaN below ``min_quality`` (:data:`TRACK_MIN_QUALITY`,
    0.1: unrelated images stay below it).
``"correlation"``
    Correlation stability: the deformed image is compensated with the tracked displacement
    (:func:`speckle.compensate`, no carrier; tracked every 16 px by default, the displacement
    being smooth), the local amplitude correlation is measured
    (:func:`speckle.correlation_map`) and the theory :func:`speckle.expected_correlation` for
    the spectrum measured from the reference image (computed by
    :func:`speckle.analysis.expected_gamma`: the same integrals, one NUFFT for every strain)
    is inverted: returns the strain *magnitude*. Quality = the local correlation; NaN where it
    is below the theory's range or below ``min_quality`` (:data:`CORRELATION_MIN_QUALITY`,
    0.25: unrelated images reach lower correlations by chance).

Alignment (``align=``, vector and wls)
-------------------------------------
The phase methods compare pixel ``z`` of both images; once the displacement ``|u|`` reaches a
fair fraction of the speckle size the pair decorrelates there (at 1 % strain and 256 pixels,
half of the depth is lost without alignment). ``align=True`` first resamples the deformed image
at the tracked displacement (:func:`speckle.analysis.tracking.track_axial` on
:data:`ALIGN_TRACKING` windows, interpolated once; the deformed image is interpolated from the
tracker's half-pixel samples by an 8-point Lagrange polynomial, without carrier removal, so the
strain phase ``2 k0 u`` is kept); ``"auto"`` (default) does
this only when the tracked displacement exceeds :data:`AUTO_ALIGN_PIXELS` (0.5 px) somewhere.
Alignment costs about as much as the vector pass itself (``benchmarks/bench_strain.py``).

Every method returns NaN where its window does not fit in the image or it has no answer.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import xarray as xr
from scipy import ndimage

from .._validate import check_choice, check_int, check_real
from ..conventions import attrs
from ..system.source import spectrum
from ._common import depth_major, parse_window
from ._kernels import MARGIN, box_sums, lagrange_resample, vector_phase
from .correlation import amplitude_from_gamma, correlation_array, expected_gamma, resample_depth
from .phase import DEFAULT_MAX_BIAS, choose_lag, depth_autocorrelation, lag_and_rho
from .tracking import interpolate_windows, track_array, track_axial

__all__ = [
    "DEFAULT_METHOD",
    "DEFAULT_WINDOWS",
    "DISPLACEMENT_METHODS",
    "METHODS",
    "accumulate_strain",
    "estimate_displacement",
    "estimate_strain",
    "predicted_strain_std",
]

METHODS = ("vector", "wls", "tracking", "correlation")
DISPLACEMENT_METHODS = ("phase", "tracking")
DEFAULT_METHOD = "vector"
#: Tracking quality ``1 - registration error`` below which a tracked window has no answer
#: (tracking and correlation methods): ``1 - sqrt(1 - rho^2)`` = 0.1 is a normalised peak
#: correlation ``rho`` = 0.44. Measured (issue 36; 256 x 32 pixels, Gaussian spectrum, R = 10):
#: unrelated scenes give at most 0.042 (99 % below 0.034); 2 % strain at least 0.13 (1st
#: percentile), 1 % 0.37; at 4 % strain (0.02, as unrelated) the tracked strain is wrong.
#: Narrower windows have a higher null (single A-line windows: 56 % of unrelated pixels pass
#: 0.1): raise ``min_quality`` with them.
TRACK_MIN_QUALITY = 0.1
#: Local amplitude correlation (the correlation method's quality) below which it has no answer:
#: unrelated scenes reach it by chance. Measured (issue 36; 256 x 32 pixels, R = 10, windows
#: 32 x 8): unrelated scenes give correlations up to 0.26 (99 % below 0.17; 31 % of the pixels
#: answered a median strain of 0.048 without this bound, 0.09 % with it); 3 % strain has median
#: 0.37 (its median estimate moves from 0.0275 to 0.0268), 2 % 0.64 (unchanged).
CORRELATION_MIN_QUALITY = 0.25
#: Default window (depth, aline) in pixels of each method.
DEFAULT_WINDOWS = {
    "vector": (32, 4),
    "wls": (32, 4),
    "tracking": (64, 8),
    "correlation": (32, 8),
}
#: Options each method accepts (besides k0, pixel_size, method, window, return_quality).
OPTIONS = {
    "vector": {
        "lag": None,
        "max_bias": DEFAULT_MAX_BIAS,
        "min_quality": 0.5,
        "wrap_check": True,
        "align": "auto",
    },
    "wls": {"lag": None, "max_bias": DEFAULT_MAX_BIAS, "min_quality": 0.5, "align": "auto"},
    "tracking": {
        "track_window": 32,
        "step": 8,
        "upsample": 20,
        "oversample": 2,
        "min_quality": TRACK_MIN_QUALITY,
    },
    # the correlation method tracks only to compensate: a smooth displacement, so coarser steps
    # do (step 16: same rms error as 8 on the benchmark pair, half the registrations)
    "correlation": {
        "track_window": 32,
        "step": 16,
        "upsample": 20,
        "oversample": 2,
        "min_quality": CORRELATION_MIN_QUALITY,
    },
}
#: Tracking that aligns the pair for the phase methods (``align``): window (depth, aline)
#: pixels, step (depth, aline) pixels; the displacement field is smooth, so coarse steps do.
ALIGN_TRACKING = {"window": (64, 8), "step": (64, 8), "upsample": 20, "oversample": 2}


# --------------------------------------------------------------------------------------------
# Input checks
# --------------------------------------------------------------------------------------------


def _as_images(reference: object, deformed: object) -> tuple[np.ndarray, np.ndarray, object]:
    """Both images as complex (depth, aline) arrays, plus the DataArray template (or None)."""
    arrays, template = [], None
    kinds = {type(reference) is xr.DataArray, type(deformed) is xr.DataArray}
    if kinds == {True, False}:
        raise TypeError("reference and deformed must both be numpy arrays or both DataArrays")
    for name, img in (("reference", reference), ("deformed", deformed)):
        if isinstance(img, xr.DataArray):
            if set(img.dims) != {"depth", "aline"}:
                raise ValueError(f"{name} must have dims (depth, aline), got {img.dims}")
            img = img.transpose("depth", "aline")
            template = img if template is None else template
            values = img.values
        elif isinstance(img, np.ndarray):
            values = img
        else:
            raise TypeError(
                f"{name} must be a complex numpy array or xarray.DataArray (depth, aline), got "
                f"{type(img).__name__}"
            )
        if not np.iscomplexobj(values):
            raise TypeError(
                f"{name} must be a complex image (the phase carries the strain), got dtype "
                f"{values.dtype}"
            )
        if values.ndim != 2:
            raise ValueError(f"{name} must be 2-D (depth, aline), got shape {values.shape}")
        finite = np.isfinite(values)
        if not finite.all():
            raise ValueError(
                f"{name} holds {int(finite.size - finite.sum())} NaN or infinite pixels of "
                f"{finite.size}; the phase methods cannot bridge them (crop or fill them first)"
            )
        # the input's own layout: the numba kernels handle both (a C-order copy of a transposed
        # B-scan cost more than it saved once the lag and the sums left numpy)
        arrays.append(values.astype(np.complex128, copy=False))
    if arrays[0].shape != arrays[1].shape:
        raise ValueError(
            f"reference and deformed must have the same shape, got {arrays[0].shape} and "
            f"{arrays[1].shape}"
        )
    if template is not None:
        d = deformed.transpose("depth", "aline")
        for dim in ("depth", "aline"):
            if dim in template.coords or dim in d.coords:
                if not np.array_equal(template[dim].values, d[dim].values):
                    raise ValueError(f"reference and deformed have different {dim} coordinates")
    return arrays[0], arrays[1], template


def _check_window(window: object, default: tuple[int, int], shape: tuple[int, int]):
    """(depth, aline) window in pixels (an int is square), checked against the image size."""
    return parse_window(default if window is None else window, shape=shape)


def _options(method: str, options: dict) -> dict:
    allowed = OPTIONS[method]
    unknown = set(options) - set(allowed)
    if unknown:
        raise TypeError(
            f"method {method!r} takes options {sorted(allowed)}; got unknown {sorted(unknown)}"
        )
    opts = {**allowed, **options}
    if "min_quality" in opts:
        opts["min_quality"] = check_real(opts["min_quality"], "min_quality", low=0, high=1)
    if "max_bias" in opts:
        check_real(
            opts["max_bias"], "max_bias", low=0, high=1, low_inclusive=False, high_inclusive=False
        )
    if "wrap_check" in opts and not isinstance(opts["wrap_check"], (bool, np.bool_)):
        raise TypeError(f"wrap_check must be True or False, got {opts['wrap_check']!r}")
    if "align" in opts and not (
        isinstance(opts["align"], (bool, np.bool_)) or opts["align"] == "auto"
    ):
        raise ValueError(f"align must be True, False or 'auto', got {opts['align']!r}")
    return opts


# --------------------------------------------------------------------------------------------
# Window sums and least-squares slopes
# --------------------------------------------------------------------------------------------


def _box(x: np.ndarray, wz: int, wx: int, n_out: int | None = None, offset: int = 0):
    """Sum over the (wz, wx) window starting at ``c - w//2``; NaN where it leaves the image.

    A running sum in depth (cumulative sum and one difference: one pass for real and complex
    data alike), then along aline, in one numba pass (:func:`~._kernels.box_sums`; NaN input:
    direct window sums). With ``n_out``, the sums are placed ``offset`` rows lower in an
    ``n_out``-row array (NaN elsewhere), without a copy.
    """
    n, m = x.shape
    dtype = np.result_type(x.dtype, np.float64)
    x = x.astype(dtype, copy=False)
    # the input's layout for the output (a depth-contiguous image stays depth-contiguous)
    order = "F" if x.flags.f_contiguous and not x.flags.c_contiguous else "C"
    out = np.empty((n if n_out is None else n_out, m), dtype=dtype, order=order)
    if wz > n or wx > m:
        out.fill(np.nan)
        return out
    k = m - wx + 1
    r0 = wz // 2 + offset
    rows = n - wz + 1
    target = out[r0 : r0 + rows, wx // 2 : wx // 2 + k]
    if np.isfinite(x).all():  # running sums (a NaN would be carried down the whole column)
        box_sums(x, wz, wx, order == "F", target)
    else:
        depth = x
        if wz > 1:
            depth = np.lib.stride_tricks.sliding_window_view(x, wz, axis=0).sum(axis=-1)
        target[...] = depth[:, :k]
        for j in range(1, wx):
            target += depth[:, j : j + k]
    out[:r0] = np.nan
    out[r0 + rows :] = np.nan
    out[r0 : r0 + rows, : wx // 2] = np.nan
    out[r0 : r0 + rows, wx // 2 + k :] = np.nan
    return out


def _place(values: np.ndarray, offset: int, n: int) -> np.ndarray:
    """Rows ``values[i]`` at output row ``i + offset`` of an ``n``-row array (NaN elsewhere)."""
    out = np.full((n, values.shape[1]), np.nan, dtype=values.dtype)
    out[offset : offset + values.shape[0]] = values
    return out


def _pooled_slope(
    y: np.ndarray, w: np.ndarray | None, wz: int, wx: int, *, weight_sums: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Weighted least-squares slope of ``y`` against depth index in each (wz, wx) window.

    One intercept per A-line, one slope per window: minimises
    ``sum_lines sum_depth w (y - a_line - b q)^2``, in closed form from running sums of the
    moments ``w q^k`` and ``w q^k y`` (every window at once). NaN where the window leaves the
    image or holds NaN. With ``weight_sums``, also the per-line window sums of ``w``.
    ``w=None``: unit weights (:func:`_unit_weight_slope`).
    """
    if w is None:
        return _unit_weight_slope(y, wz, wx)
    q = np.arange(y.shape[0], dtype=float)[:, None] - 0.5 * y.shape[0]
    bad = None
    if not (np.isfinite(y).all() and np.isfinite(w).all()):
        bad = ~np.isfinite(y) | ~np.isfinite(w)
        w = np.where(bad, 0.0, w)
        y = np.where(bad, 0.0, y)
    s0, s1, s2 = (_box(w * q**k, wz, 1) for k in range(3))
    t0, t1 = _box(w * y, wz, 1), _box(w * q * y, wz, 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        num = t1 - s1 * t0 / s0
        den = s2 - s1**2 / s0
    num = np.where(s0 > 0, num, np.nan)
    slope = _box(num, 1, wx) / _box(den, 1, wx)
    if bad is not None:
        slope = np.where(_box(bad.astype(float), wz, wx) == 0, slope, np.nan)
    return (slope, s0) if weight_sums else slope


def _unit_weight_slope(y: np.ndarray, wz: int, wx: int) -> np.ndarray:
    """:func:`_pooled_slope` with unit weights: ``sum_k (k - kbar) y_k / sum_k (k - kbar)^2``.

    With unit weights the depth moments of a window are known exactly
    (``sum (k - kbar)^2 = wz (wz^2 - 1)/12``), so two running sums (of ``y`` and ``q y``) give
    every window's numerator. NaN where the window leaves the image or holds NaN.
    """
    bad = ~np.isfinite(y)
    has_bad = bool(bad.any())
    y0 = np.where(bad, 0.0, y) if has_bad else y
    n = y.shape[0]
    q = np.arange(n, dtype=float)[:, None]
    t0, t1 = _box(y0, wz, 1), _box(q * y0, wz, 1)
    centre = np.arange(n, dtype=float)[:, None] - wz // 2 + 0.5 * (wz - 1)  # mean row index
    num = t1 - centre * t0
    slope = _box(num, 1, wx) / (wx * wz * (wz**2 - 1) / 12.0)
    if has_bad:
        slope = np.where(_box(bad.astype(float), wz, wx) == 0, slope, np.nan)
    return slope


# --------------------------------------------------------------------------------------------
# Methods
# --------------------------------------------------------------------------------------------


def _lag(a1: np.ndarray, opts: dict) -> int:
    if opts["lag"] is None:
        return choose_lag(a1, max_bias=opts["max_bias"])
    return check_int(opts["lag"], "lag", low=1, high=a1.shape[0] - 2)


def _four_product_sums(a1, a2, lag, wz, wx, terms=("C", "absC", "R1", "R2")):
    """Window sums of ``C_L`` and, as asked by ``terms``, ``|C_L|`` and the two
    autocorrelation terms, at row centres."""
    n = a1.shape[0]
    x1, y1, x2, y2 = a1[:-lag], a1[lag:], a2[:-lag], a2[lag:]
    c = x1 * np.conj(x2) * np.conj(y1) * y2
    make = {
        "C": lambda: c,
        "absC": lambda: np.abs(c),
        "R1": lambda: x1 * np.conj(y1),
        "R2": lambda: x2 * np.conj(y2),
    }
    sums = {k: _box(make[k](), wz, wx, n_out=n, offset=lag // 2) for k in terms}
    return sums, wz * wx


def _vector(a1, a2, k0, p, wz, wx, opts):
    a1 = depth_major(a1)  # once: the lag's pass and the kernel read depth-contiguous A-lines
    if opts["lag"] is None:
        lag, rho = lag_and_rho(a1, max_bias=opts["max_bias"])
    else:
        lag, rho = _lag(a1, opts), None
    a2 = _aligned(a1, a2, p, opts)
    wrap = bool(opts["wrap_check"]) and lag > 1
    if wrap and rho is None:
        rho = depth_autocorrelation(a1, 1)
    # the lag-1 phase wraps only at 1/(2R); scaled by L and by its known low bias
    # 1 + rho(1)^2 (image autocorrelation) it picks the 2 pi branch of the lag-L phase
    # (multi-lag unwrapping); a branch error needs a predictor error > pi
    cfac = lag * (1 + rho[1] ** 2) if wrap else 1.0
    n, m = a1.shape
    strain = np.full((m, n), np.nan).T  # depth contiguous, as the kernel writes
    quality = np.full((m, n), np.nan).T
    vector_phase(
        a1,
        depth_major(a2),
        lag,
        wz,
        wx,
        2 * k0 * lag * p,
        cfac,
        np.tan(MARGIN * 0.5 * np.pi / cfac),
        opts["min_quality"],
        wrap,
        strain,
        quality,
    )
    return strain, quality, {"lag": lag}


def _smoothed_phasor(a1, a2, lag):
    """``A2 A1*`` summed over ``lag`` depth pixels (centred), and SNR weights summed alike."""
    c = a2 * np.conj(a1)
    i1, i2 = np.abs(a1) ** 2, np.abs(a2) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(i1 + i2 > 0, i1 * i2 / (i1 + i2), 0.0)
    # one filter call for the real part, the imaginary part and the weights
    parts = (
        ndimage.uniform_filter1d(np.stack([c.real, c.imag, w]), lag, axis=1, mode="nearest") * lag
    )
    return parts[0] + 1j * parts[1], parts[2]


def _unwrapped_phase(a1, a2, lag):
    """Unwrapped (along depth) phase of the smoothed interframe phasor, and its weights."""
    cs, w = _smoothed_phasor(a1, a2, lag)
    return np.unwrap(np.angle(cs), axis=0), w


def _fit_coherence(phasor, w, w_sums, slope, wz, wx):
    """``|sum w exp(i(phase - slope q))| / sum w`` per A-line, averaged over ``wx`` lines.

    ``phasor`` carries the phase (``exp(i phase) = phasor/|phasor|``), ``w_sums`` the window sums
    of ``w`` (:func:`_pooled_slope`). 1 when the (wrapped) phasors follow the fitted line; an
    unwrapping error inside the window gives a wrong slope and a low value. The window sum at
    pixel ``q`` is the polynomial ``sum_k u(q - wz//2 + k) E^k`` in ``E = exp(-i slope(q))``
    (``u = w exp(i phase)``; the factor ``E^(-wz//2)`` has modulus 1), evaluated by Horner's
    rule for all pixels at once: ``wz - 1`` multiply-adds of whole images. NaN where the window
    leaves the image.
    """
    n = phasor.shape[0]
    rows = n - wz + 1  # windows inside the image: rows h ... h + rows - 1 of the output
    h = wz // 2
    per_line = np.full(phasor.shape, np.nan)
    if rows < 1:
        return per_line
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(w > 0, phasor * (w / np.abs(phasor)), 0.0).astype(np.complex64)
    b = slope[h : h + rows]
    e = np.empty(b.shape, dtype=np.complex64)
    np.cos(b, out=e.real)
    np.sin(-b, out=e.imag)
    acc = u[wz - 1 : wz - 1 + rows].copy()
    for k in range(wz - 2, -1, -1):
        acc *= e
        acc += u[k : k + rows]
    with np.errstate(invalid="ignore", divide="ignore"):
        per_line[h : h + rows] = np.abs(acc) / w_sums[h : h + rows]
    return _box(per_line, 1, wx) / wx


def _wls(a1, a2, k0, p, wz, wx, opts):
    lag = _lag(a1, opts)
    a2 = _aligned(a1, a2, p, opts)
    phasor, w = _smoothed_phasor(a1, a2, lag)
    phase = np.unwrap(np.angle(phasor), axis=0)
    slope, w_sums = _pooled_slope(phase, w, wz, wx, weight_sums=True)
    strain = -slope / (2 * k0 * p)
    quality = _fit_coherence(phasor, w, w_sums, np.nan_to_num(slope), wz, wx)
    quality = np.where(np.isfinite(slope), quality, np.nan)
    # unwrapping guard: the fitted phase step per pixel must agree (within pi/4) with the
    # complex-averaged lag-1 step (Gaussian cross term removed), which needs no unwrapping
    s1, count = _four_product_sums(a1, a2, 1, wz, wx, ("C", "R1", "R2"))
    step = np.angle(s1["C"] - s1["R1"] * np.conj(s1["R2"]) / count)
    with np.errstate(invalid="ignore"):
        unwrap_failed = np.abs(np.remainder(step - slope + np.pi, 2 * np.pi) - np.pi) > np.pi / 4
    strain = np.where((quality >= opts["min_quality"]) & ~unwrap_failed, strain, np.nan)
    return strain, quality, {"lag": lag}


def _tracked(a1, a2, window, step, upsample, oversample, lateral=True, outside="nan"):
    """Tracked axial displacement (pixels) and 1 - registration error at every pixel.

    :func:`speckle.analysis.tracking.track_array` on ``window`` (depth, aline) windows every
    ``step`` pixels, interpolated bilinearly to every pixel
    (:func:`speckle.analysis.tracking.interpolate_windows`); beyond the outer window centres
    NaN (``outside="nan"``) or the nearest centre's value (``"nearest"``).
    """
    tr = track_array(
        a1,
        a2,
        window=window,
        step=step,
        upsample=upsample,
        oversample=oversample,
        lateral=lateral,
    )
    qz, qx = np.arange(a1.shape[0], dtype=float), np.arange(a1.shape[1], dtype=float)
    out = []
    for values in (tr["uz"], 1.0 - tr["error"]):
        out.append(
            interpolate_windows(
                values, tr["centre_depth"], tr["centre_aline"], qz, qx, outside=outside
            )
        )
    return out[0], out[1], tr


def _check_shape_options(opts: dict, n: int) -> None:
    """Options whose range depends on the image's ``n`` depth pixels (``lag``,
    ``track_window``, ``step``), checked as the methods will (:func:`_lag`,
    :func:`_track_options`) but up front: a lazy frame stack would meet them at ``compute``."""
    if opts.get("lag") is not None:
        check_int(opts["lag"], "lag", low=1, high=n - 2)
    if "track_window" in opts:
        tw = check_int(opts["track_window"], "track_window", low=4, high=n)
        check_int(opts["step"], "step", low=1, high=tw)


def _track_options(a1, wx, opts):
    tw = check_int(opts["track_window"], "track_window", low=4, high=a1.shape[0])
    step = check_int(opts["step"], "step", low=1, high=tw)
    # windows side by side in aline (A-line-independent images: overlapping them laterally
    # doubled the registrations for no lower error, measured), depth refined only (uz is used)
    return {
        "window": (tw, wx),
        "step": (step, wx),
        "upsample": check_int(opts["upsample"], "upsample", low=1),
        "oversample": check_int(opts["oversample"], "oversample", low=1),
        "lateral": False,
    }


def _tracking(a1, a2, k0, p, wz, wx, opts):
    kw = _track_options(a1, wx, opts)
    uz, quality, _ = _tracked(a1, a2, **kw)
    uz = np.where(quality >= opts["min_quality"], uz, np.nan)  # no answer below the threshold
    strain = -_pooled_slope(uz, None, wz, 1)
    return strain, quality, {"track_window": kw["window"][0]}


def _measured_spectrum(a1: np.ndarray, k0: float, p: float) -> xr.DataArray:
    """Source spectrum S(k_n) estimated as sqrt(mean |F_n|^2) of the reference A-lines."""
    n = a1.shape[0]
    shift = n // 2
    q = np.arange(n)
    spec = np.fft.ifft(a1 * np.exp(-2j * np.pi * shift * q / n)[:, None], axis=0)
    weights = np.sqrt(np.mean(np.abs(spec) ** 2, axis=1))
    return spectrum(n, n * p, k0=k0, shape="array", weights=weights / weights.max())


def correlation_theory(spectrum: xr.DataArray, num: int = 81) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude correlation after exact compensation versus strain, up to its first minimum.

    The Gaussian-speckle amplitude correlation (independent of density) of
    :func:`speckle.expected_correlation`, computed by
    :func:`speckle.analysis.correlation.expected_gamma` (the same integrals, one NUFFT for every
    strain), on strains ``0 ... 1.5/R`` (``R = k0/delta_k``), cut at the first minimum so that
    it is monotonic and can be inverted.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        Strains and the amplitude correlation at each.
    """
    r = max(float(spectrum.attrs["k0_dk"]), 1.0)
    grid = np.linspace(0.0, min(0.9, 1.5 / r), num)
    vals = amplitude_from_gamma(expected_gamma(grid, spectrum=spectrum))
    rising = np.flatnonzero(np.diff(vals) >= 0)
    stop = rising[0] + 1 if rising.size else len(vals)
    return grid[:stop], vals[:stop]


def _resampled(a2, uz_pixels, samples=None):
    """The deformed image taken where each reference pixel's material went,
    ``A2(q + u(q))`` (envelope only: the carrier ``exp(2i k0 u)`` of the moved scatterers and so
    the strain phase are kept). With ``samples`` (the alignment tracker's oversampled deformed
    A-lines, :func:`track_axial` ``keep_samples``), interpolated from them by the 8-point
    Lagrange polynomial of :func:`resample_depth` (no second oversampling); else by
    :func:`resample_depth`.

    On the tracker's 2 samples per pixel the error is within 6e-4 of the peak amplitude of the
    exact interpolant for a Gaussian spectrum of FWHM half the band, 4e-3 for a rectangular one
    (:func:`resample_depth`'s 4 per pixel: 3e-6 and 2e-5); the strain's rms error on the
    benchmark pair is the same to 1e-5 of the strain.
    """
    q = np.arange(a2.shape[0], dtype=float)[:, None]
    if samples is None:
        return resample_depth(a2, q + uz_pixels)
    y = np.ascontiguousarray((q + uz_pixels).T)  # (aline, depth), as the samples
    out = np.empty(y.shape, dtype=np.complex128)
    lagrange_resample(samples, y, ALIGN_TRACKING["oversample"], out)
    return out.T


def _align_tracking(a1: np.ndarray) -> dict:
    """:data:`ALIGN_TRACKING` fitted to the image (windows no larger than the image)."""
    n, m = a1.shape
    wz = min(ALIGN_TRACKING["window"][0], n)
    wx = min(ALIGN_TRACKING["window"][1], m)
    sz = min(ALIGN_TRACKING["step"][0], wz)
    sx = min(ALIGN_TRACKING["step"][1], wx)
    return {**ALIGN_TRACKING, "window": (wz, wx), "step": (sz, sx)}


def _alignment(a1, a2):
    """Tracked displacement (pixels) at every pixel for the alignment (nearest-centre values
    beyond the outer windows; failed windows filled from their neighbours), the largest
    row median of its magnitude, the steepest tracked strain, and the tracker's oversampled
    deformed A-lines (resampled by :func:`_resampled`).

    One coarse tracking pass (:data:`ALIGN_TRACKING`: displacement only, no registration
    error), interpolated once, laid out with depth contiguous for the resampling.
    """
    tr = track_axial(a1, a2, keep_samples=True, **_align_tracking(a1))
    qz, qx = np.arange(a1.shape[0], dtype=float), np.arange(a1.shape[1], dtype=float)
    uz = interpolate_windows(  # transposed: (aline, depth), each A-line contiguous
        tr["uz"].T, tr["centre_aline"], tr["centre_depth"], qx, qz, outside="nearest"
    ).T
    uz, _ = _alignment_fill(uz)  # windows without texture: filled from their neighbours
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows
        rows = np.nanmedian(np.abs(tr["uz"]), axis=1)
        grad = np.abs(np.diff(tr["uz"], axis=0) / np.diff(tr["centre_depth"])[:, None])
    reach = float(np.nanmax(rows)) if np.isfinite(rows).any() else 0.0
    steepest = float(np.nanmax(grad)) if np.isfinite(grad).any() else np.inf
    return uz, reach, steepest, tr["deformed_samples"]


def _aligned(a1, a2, p, opts):
    """With ``align``: the deformed image resampled where the tracked displacement moved each
    reference pixel, so displacements beyond the speckle size no longer decorrelate the pair."""
    if not opts["align"]:
        return a2
    uz, _, _, samples = _alignment(a1, a2)
    return _resampled(a2, uz, samples)


#: ``align="auto"`` aligns when the tracked displacement (row median of the window estimates)
#: exceeds this many pixels somewhere (the field correlation of a Gaussian-spectrum pair falls
#: to ~0.9 at 0.5 px).
AUTO_ALIGN_PIXELS = 0.5


def _auto_aligned(method, a1, a2, k0, p, wz, wx, opts):
    """Track once (coarse windows); align only if the displacement reaches
    :data:`AUTO_ALIGN_PIXELS`, then estimate."""
    if method == "vector":  # depth-contiguous once, for the tracker's transforms and the kernels
        a1 = depth_major(a1)
    uz, reach, steepest, samples = _alignment(a1, a2)
    if method == "vector" and opts["wrap_check"]:
        # the lag-L phase wraps at |s| = 1/(2 R L) (R = k0 p / pi); far below it (half, with
        # the tracked strain's noise of ~1e-3) the multi-lag check cannot change a branch
        lag = _lag(a1, opts)
        if steepest < 0.5 * np.pi / (2 * k0 * p * lag):
            opts = {**opts, "wrap_check": False, "lag": lag}
    if reach <= AUTO_ALIGN_PIXELS:
        out = _METHOD_FUNCS[method](a1, a2, k0, p, wz, wx, {**opts, "align": False})
        return out[0], out[1], {**out[2], "aligned": 0}
    a2 = _resampled(a2, uz, samples)
    out = _METHOD_FUNCS[method](a1, a2, k0, p, wz, wx, {**opts, "align": False})
    return out[0], out[1], {**out[2], "aligned": 1}


def _correlation(a1, a2, k0, p, wz, wx, opts):
    # nearest-centre values beyond the outer windows compensate the image edges too; the
    # strain is given only between the outer centres (as the tracked displacement is)
    uz, _, tr = _tracked(a1, a2, outside="nearest", **_track_options(a1, wx, opts))
    cz, cx = tr["centre_depth"], tr["centre_aline"]
    qz, qx = np.arange(a1.shape[0]), np.arange(a1.shape[1])
    inside = ((qz >= cz[0]) & (qz <= cz[-1]))[:, None] & ((qx >= cx[0]) & (qx <= cx[-1]))
    covered = inside & np.isfinite(uz)
    filled, _ = _alignment_fill(uz)  # failed windows: filled from their neighbours in depth
    comp = _resampled(a2, filled)
    r = correlation_array(np.abs(a1), np.abs(comp), (wz, wx))
    ts, tv = (x[::-1] for x in correlation_theory(_measured_spectrum(a1, k0, p)))
    strain = np.interp(r, tv, ts, left=np.nan, right=0.0)
    strain = np.where(covered & np.isfinite(r) & (r >= opts["min_quality"]), strain, np.nan)
    return strain, r, {"theory_min_correlation": float(tv[0])}


def _alignment_fill(uz):
    """NaN displacements (outside the tracked windows) filled by the nearest value along depth
    (constant extrapolation, only for resampling); and the mask of original values."""
    ok = np.isfinite(uz)
    out = uz.copy(order="K")
    for j in np.flatnonzero(~ok.all(axis=0)):
        col, good = uz[:, j], np.flatnonzero(ok[:, j])
        out[:, j] = np.interp(np.arange(col.size), good, col[good]) if good.size else 0.0
    return out, ok


_METHOD_FUNCS = {
    "vector": _vector,
    "wls": _wls,
    "tracking": _tracking,
    "correlation": _correlation,
}


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------


def _no_answer_reason(method: str, quality: np.ndarray, opts: dict, window) -> str:
    """Why an estimate has no finite pixel, for the warning."""
    q = quality[np.isfinite(quality)]
    head = f"estimate_strain(method={method!r}) has no answer at any pixel: "
    if "min_quality" in opts and q.size and q.max() < opts["min_quality"]:
        return head + (
            f"every window's quality is below min_quality={opts['min_quality']:g} (highest "
            f"{q.max():.3f}); lower min_quality or use a larger window"
        )
    if not q.size:
        return head + f"no window {tuple(window)} has a finite quality (image too small?)"
    return head + (
        "the pair is decorrelated beyond the method's range (correlation below its theory or "
        "unwrapping failed everywhere); try method='tracking' or align=True"
    )


def _strain_attrs(method: str, wz: int, wx: int) -> dict:
    """Attrs of a strain estimate: what it is, the method and the window (pixels)."""
    long_name = (
        "axial strain (compression > 0)" if method != "correlation" else "axial strain magnitude"
    )
    return {
        **attrs("strain", long_name),
        "method": method,
        "window_depth_pixels": wz,
        "window_aline_pixels": wx,
    }


def _wrap(values: np.ndarray, template, name: str, meta: dict) -> object:
    if template is None:
        return values
    return xr.DataArray(values, dims=("depth", "aline"), coords=template.coords, attrs=meta)


def estimate_strain(
    reference: np.ndarray | xr.DataArray,
    deformed: np.ndarray | xr.DataArray,
    *,
    k0: float,
    pixel_size: float,
    method: str = DEFAULT_METHOD,
    window: int | tuple[int, int] | None = None,
    return_quality: bool = False,
    **options,
):
    """Axial strain between two complex OCT images (positive for compression).

    Parameters
    ----------
    reference, deformed : numpy.ndarray or xarray.DataArray
        Complex images ``(depth, aline)`` of the same shape (DataArrays: dims ``depth`` and
        ``aline``, identical coordinates). Axis 0 is depth with pixel size ``pixel_size``.
    k0 : float
        Central wavenumber in the medium, rad/µm (> 0), as in :func:`speckle.ascan`.
    pixel_size : float
        Axial pixel size in the medium, µm (> 0); ``H/N`` for the model's images.
    method : {"vector", "wls", "tracking", "correlation"}
        Estimator (see the module docstring); default ``"vector"``.
    window : int or (int, int), optional
        Window (depth, aline) in pixels over which each estimate is taken; default
        :data:`DEFAULT_WINDOWS` of the method. An int means (int, 1).
    return_quality : bool
        Also return the quality map (correlation or phase coherence, 0-1).
    **options
        Method options (:data:`OPTIONS`): ``lag`` (pixels; default from the image's
        autocorrelation), ``max_bias``, ``min_quality`` (NaN below it; every method),
        ``align`` (True, False or "auto", default), ``wrap_check`` (vector: multi-lag
        unwrapping); ``track_window``, ``step``, ``upsample``, ``oversample`` (tracking,
        correlation).

    Returns
    -------
    numpy.ndarray or xarray.DataArray
        Strain (dimensionless) with the input's shape (DataArray: same coords, attrs give the
        method, window and chosen lag; a ``quality`` coordinate holds the quality map).
        ``"correlation"`` gives the magnitude. NaN where the method has no answer. With
        ``return_quality``, a tuple ``(strain, quality)``.

    Raises
    ------
    TypeError
        Real instead of complex images, mixed or unknown input types, unknown options.
    ValueError
        Shapes or coordinates that differ, non-positive ``k0`` or ``pixel_size``, a window
        larger than the image, an unknown method.
    """
    has_frame = [isinstance(x, xr.DataArray) and "frame" in x.dims for x in (reference, deformed)]
    if any(has_frame):
        out = _strain_frames(
            reference, deformed, has_frame, k0, pixel_size, method, window, options
        )
        if return_quality:
            return out, out["quality"].reset_coords(drop=True).rename("quality")
        return out
    a1, a2, template = _as_images(reference, deformed)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    check_choice(method, "method", METHODS)
    wz, wx = _check_window(window, DEFAULT_WINDOWS[method], a1.shape)
    opts = _options(method, options)
    if opts.get("align") == "auto":
        strain, quality, info = _auto_aligned(method, a1, a2, k, p, wz, wx, opts)
    else:
        strain, quality, info = _METHOD_FUNCS[method](a1, a2, k, p, wz, wx, opts)
    if not np.isfinite(strain).any():
        warnings.warn(_no_answer_reason(method, quality, opts, (wz, wx)), stacklevel=2)
    out = _wrap(strain, template, "strain", {**_strain_attrs(method, wz, wx), **info})
    if template is not None:
        out = out.assign_coords(
            quality=(("depth", "aline"), quality, attrs("dimensionless", "quality"))
        )
    if return_quality:
        return out, _wrap(quality, template, "quality", attrs("dimensionless", "quality"))
    return out


def _strain_block(f1, f2, k0, p, method, window, options):
    s, q = estimate_strain(
        f1[0],
        f2[0],
        k0=k0,
        pixel_size=p,
        method=method,
        window=window,
        return_quality=True,
        **options,
    )
    return np.stack([s, q])[None]


def _strain_frames(reference, deformed, has_frame, k0, pixel_size, method, window, options):
    """:func:`estimate_strain` frame by frame (pairs ``reference[i]``, ``deformed[i]``), lazily.

    Returns a Dask-backed DataArray (frame, depth, aline) with a lazy ``quality`` coordinate;
    everything is checked before any work.
    """
    if not all(has_frame):
        which = "reference" if has_frame[0] else "deformed"
        raise ValueError(
            f"only {which} has a 'frame' dim: give both inputs a frame dim of the same size "
            "(pairs reference[i], deformed[i]) or select one frame (.isel(frame=i))"
        )
    arrays = []
    for name, x in (("reference", reference), ("deformed", deformed)):
        try:
            data, coords = _frames_input(x)
        except (TypeError, ValueError) as err:
            raise type(err)(f"{name}: {err}") from None
        arrays.append((data, coords))
    (d1, c1), (d2, c2) = arrays
    if d1.shape != d2.shape:
        raise ValueError(
            f"reference and deformed frames differ in shape: {d1.shape} vs {d2.shape} "
            "(frame, depth, aline)"
        )
    for dim in ("depth", "aline"):
        if dim in c1 and dim in c2 and not np.array_equal(c1[dim].values, c2[dim].values):
            raise ValueError(f"reference and deformed have different {dim} coordinates")
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    check_choice(method, "method", METHODS)
    n_frames, n, m = d1.shape
    wz, wx = _check_window(window, DEFAULT_WINDOWS[method], (n, m))
    _options(method, options)
    _check_finite_frames(d1)
    _check_finite_frames(d2)
    if _is_dask(d1) or _is_dask(d2):
        if not (_is_dask(d1) and _is_dask(d2)):
            raise TypeError(
                "reference and deformed must both be Dask-backed or both in memory (use "
                ".chunk({'frame': 1}) on both)"
            )
        d1 = d1.rechunk({0: 1, 1: -1, 2: -1})
        d2 = d2.rechunk({0: 1, 1: -1, 2: -1})
        both = d1.map_blocks(
            _strain_block,
            d2,
            k,
            p,
            method,
            (wz, wx),
            options,
            dtype=float,
            new_axis=1,
            chunks=((1,) * n_frames, (2,), (n,), (m,)),
        )
    else:
        both = np.concatenate(
            [
                _strain_block(d1[i : i + 1], d2[i : i + 1], k, p, method, (wz, wx), options)
                for i in range(n_frames)
            ]
        )
    frame = reference["frame"] if "frame" in reference.coords else np.arange(n_frames)
    coords = {"frame": frame, **c1}
    out = xr.DataArray(
        both[:, 0],
        dims=("frame", "depth", "aline"),
        coords=coords,
        attrs=_strain_attrs(method, wz, wx),
    )
    return out.assign_coords(
        quality=(("frame", "depth", "aline"), both[:, 1], attrs("dimensionless", "quality"))
    )


def estimate_displacement(
    reference: np.ndarray | xr.DataArray,
    deformed: np.ndarray | xr.DataArray,
    *,
    k0: float,
    pixel_size: float,
    method: str = "tracking",
    window: int | tuple[int, int] | None = None,
    **options,
):
    """Axial displacement (µm, positive = deeper) of every pixel's material between two images.

    Parameters
    ----------
    reference, deformed, k0, pixel_size
        As in :func:`estimate_strain`.
    method : {"tracking", "phase"}
        ``"tracking"``: :func:`speckle.track` in ``(track_window, window[aline])`` windows
        stepped by ``step`` pixels, interpolated linearly (NaN beyond the outer window
        centres). ``"phase"``: the interframe phase ``A2 A1*`` summed over ``lag`` pixels,
        unwrapped along depth from the top pixel and divided by ``2 k0``; exact up to a
        multiple of ``pi/k0`` (half a wavelength) set by the top pixel (zero for a probe at
        ``z = 0``), and only while the phase changes by less than ``pi`` per pixel.
    window : int or (int, int), optional
        Only the aline size is used (default 1): A-lines per tracking window.
    **options
        ``track_window``, ``step``, ``upsample``, ``oversample`` (tracking); ``lag``,
        ``max_bias`` (phase).

    Returns
    -------
    numpy.ndarray or xarray.DataArray
        Displacement in µm, the input's shape.
    """
    a1, a2, template = _as_images(reference, deformed)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    check_choice(method, "method", DISPLACEMENT_METHODS)
    _, wx = _check_window(window, (2, 1), a1.shape)
    if method == "tracking":
        opts = _options("tracking", options)
        uz, quality, _ = _tracked(a1, a2, **_track_options(a1, wx, opts))
        uz = np.where(quality >= opts["min_quality"], uz, np.nan) * p  # no answer below it
    else:
        allowed = {"lag": None, "max_bias": DEFAULT_MAX_BIAS}
        unknown = set(options) - set(allowed)
        if unknown:
            raise TypeError(f"method 'phase' takes options {sorted(allowed)}; got {unknown}")
        opts = {**allowed, **options}
        phase, _ = _unwrapped_phase(a1, a2, _lag(a1, opts))
        uz = phase / (2 * k)
    meta = attrs("displacement", "axial displacement (+z deeper)", method=method)
    return _wrap(uz, template, "uz", meta)


def predicted_strain_std(
    reference: np.ndarray,
    deformed: np.ndarray,
    *,
    noise_power: float,
    k0: float,
    pixel_size: float,
    window: int | tuple[int, int] | None = None,
    lag: int | None = None,
) -> np.ndarray:
    """Strain noise of the vector method predicted from additive phase noise, per window.

    At high SNR a pixel of intensity ``I`` carries phase noise of variance ``sigma^2/(2 I)``
    (``sigma^2`` = noise power), so the interframe phase ``arg A1 A2*`` at pixel ``q`` has
    variance ``v_q = sigma^2/2 (1/I1 + 1/I2)``, independent between pixels. The phase of
    ``sum_i w_i exp(i(theta + e_{i+L} - e_i))`` (``w_i = |C_i|``) errs by
    ``sum_q (w_{q-L} - w_q) e_q / sum_i w_i`` (``w`` = 0 outside the window), so

        var(strain) = sum_q (w_{q-L} - w_q)^2 v_q / (sum_i w_i)^2 / (2 k0 L p)^2,

    conditioned on the intensities of the given (noise-free) images.

    Returns
    -------
    numpy.ndarray
        Predicted standard deviation of the strain at each pixel (NaN where the window does not
        fit), same shape and placement as :func:`estimate_strain` with ``method="vector"``.
    """
    a1, a2, _ = _as_images(reference, deformed)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    sigma2 = check_real(noise_power, "noise_power", low=0)
    wz, wx = _check_window(window, DEFAULT_WINDOWS["vector"], a1.shape)
    big_l = _lag(a1, {"lag": lag, "max_bias": DEFAULT_MAX_BIAS})
    n = a1.shape[0]
    i1, i2 = np.abs(a1) ** 2, np.abs(a2) ** 2
    with np.errstate(divide="ignore"):
        v = 0.5 * sigma2 * (1 / i1 + 1 / i2)
    w = np.sqrt(i1[:-big_l] * i2[:-big_l] * i1[big_l:] * i2[big_l:])  # |C_i|, i = 0..n-L-1
    # window of C rows [i0, i0 + wz) touches phase pixels [i0, i0 + wz + L)
    zero = np.zeros((big_l, w.shape[1]))
    wl = np.vstack([zero, w])  # w_{q-L}, q = 0 .. n-1
    wq = np.vstack([w, zero])  # w_q
    inner = (wl - wq) ** 2 * v  # both terms present
    head = wq**2 * v  # q in [i0, i0+L): only -w_q
    tail = wl**2 * v  # q in [i0+wz, i0+wz+L): only w_{q-L}

    def csum(x):
        return np.vstack([np.zeros((1, x.shape[1])), np.cumsum(x, axis=0)])

    ci, ch, ct, cw = csum(inner), csum(head), csum(tail), csum(w)
    i0 = np.arange(n - big_l - wz + 1)
    var_num = (
        ci[i0 + wz] - ci[i0 + big_l] + ch[i0 + big_l] - ch[i0] + ct[i0 + wz + big_l] - ct[i0 + wz]
    )
    wsum = cw[i0 + wz] - cw[i0]
    num = ndimage.uniform_filter1d(var_num, wx, axis=1, mode="constant") * wx
    den = ndimage.uniform_filter1d(wsum, wx, axis=1, mode="constant") * wx
    std = np.sqrt(num) / den / (2 * k * big_l * p)
    valid = np.zeros(std.shape, bool)
    valid[:, wx // 2 : std.shape[1] - (wx - 1) // 2] = True
    std = np.where(valid, std, np.nan)
    # row i0 of the C-window sums sits at C row i0 + wz//2, placed at pixel + L//2
    return _place(std, wz // 2 + big_l // 2, n)


def _frames_input(frames: object) -> tuple[object, dict]:
    """``frames`` as a (frame, depth, aline) array (numpy or Dask) and its coordinates.

    Refused before any work: a wrong type or dims, fewer than two frames, real data, Dask
    chunks that split depth or aline.
    """
    coords: dict = {}
    if isinstance(frames, xr.DataArray):
        if set(frames.dims) != {"frame", "depth", "aline"}:
            raise ValueError(f"frames must have dims (frame, depth, aline), got {frames.dims}")
        frames = frames.transpose("frame", "depth", "aline")
        coords = {d: frames[d] for d in ("depth", "aline") if d in frames.coords}
        data = frames.data
    elif isinstance(frames, np.ndarray):
        data = frames
    else:
        raise TypeError(f"frames must be a numpy array or DataArray, got {type(frames).__name__}")
    if data.ndim != 3 or data.shape[0] < 2:
        raise ValueError(f"frames must be (frame >= 2, depth, aline), got shape {data.shape}")
    if not np.issubdtype(data.dtype, np.complexfloating):
        raise TypeError(
            f"frames must be complex images (the phase carries the strain), got dtype {data.dtype}"
        )
    chunks = getattr(data, "chunks", None)
    if chunks is not None and (len(chunks[1]) > 1 or len(chunks[2]) > 1):
        raise ValueError(
            f"frames' Dask chunks split depth or aline (chunks {chunks[1]} x {chunks[2]}): a "
            "pair needs whole images; rechunk with frames.chunk({'frame': 1, 'depth': -1, "
            "'aline': -1})"
        )
    return data, coords


def _pair_fields(f1, f2, k0, p, method, window, options):
    """Interframe strain, its quality and the tracked displacement (µm) of one pair."""
    a1, a2 = np.asarray(f1), np.asarray(f2)
    s, q = estimate_strain(
        a1, a2, k0=k0, pixel_size=p, method=method, window=window, return_quality=True, **options
    )
    u = estimate_displacement(a1, a2, k0=k0, pixel_size=p, method="tracking")
    return np.stack([s, q, u])


def _pair_block(f1, f2, k0, p, method, window, options):
    return _pair_fields(f1[0], f2[0], k0, p, method, window, options)[None]


def _advance(state, fields, p):
    """One step of the material-point scan: (position, kept length) after pair ``fields``."""
    y, keep = state
    s, _, u = fields
    q = np.arange(y.shape[0], dtype=float)
    s_at = np.column_stack([np.interp(y[:, j], q, s[:, j]) for j in range(y.shape[1])])
    u_at = np.column_stack([np.interp(y[:, j], q, u[:, j]) for j in range(y.shape[1])])
    return y + u_at / p, keep * (1 - s_at)


def _check_finite_frames(data) -> None:
    """ValueError naming the frames holding NaN/inf (computed lazily for Dask input)."""
    finite = np.isfinite(data).all(axis=(1, 2))
    if hasattr(finite, "compute"):
        finite = finite.compute()
    bad = np.flatnonzero(~np.asarray(finite))
    if bad.size:
        raise ValueError(
            f"frames {bad[:10].tolist()}{' ...' if bad.size > 10 else ''} ({bad.size} of "
            f"{len(finite)}) hold NaN or infinite pixels; drop or repair them first"
        )


def accumulate_strain(
    frames: np.ndarray | xr.DataArray,
    *,
    k0: float,
    pixel_size: float,
    method: str = DEFAULT_METHOD,
    window: int | tuple[int, int] | None = None,
    path: str | None = None,
    progress: bool = False,
    **options,
) -> xr.Dataset:
    """Cumulative strain over a compression sequence, following the material with tracking.

    Frame ``i+1`` is compared with frame ``i`` (interframe strain ``s_i`` with
    :func:`estimate_strain`, displacement ``u_i`` with :func:`estimate_displacement`,
    ``method="tracking"``). A material point starting at pixel ``q`` of frame 0 sits at
    ``y_i`` in frame ``i`` (``y_{i+1} = y_i + u_i(y_i)/p``), and its total strain relative to
    frame 0 is ``1 - prod_i (1 - s_i(y_i))`` (compressions compose multiplicatively).

    Parameters
    ----------
    frames : numpy.ndarray or xarray.DataArray
        Complex images ``(frame, depth, aline)``, at least two frames, all finite. A Dask-backed
        DataArray (e.g. ``speckle.io.open_dataset(path, load=False)["field"]`` or
        ``xarray.open_zarr(...)``) is processed lazily, one pair per task; its chunks must hold
        whole images (``frames.chunk({"frame": 1, "depth": -1, "aline": -1})``).
    k0, pixel_size, method, window, **options
        As in :func:`estimate_strain` (``options`` go to the strain estimator).
    path : str, optional
        Stream the result to this chunked NetCDF file (one chunk per frame, written atomically
        by :func:`speckle.io.stream_to_netcdf` on the active Dask scheduler: threads,
        processes or a ``dask.distributed`` cluster) and return it opened lazily. Memory then
        holds the pairs in flight, not the sequence. Without ``path`` the result is computed
        in memory.
    progress : bool
        Progress bar while streaming (``path`` given).

    Returns
    -------
    xarray.Dataset
        ``interframe`` (``frame`` = pair index, depth, aline; on each earlier frame's grid),
        ``quality`` (of each interframe estimate), ``cumulative`` (strain of frame ``i+1``
        relative to frame 0 on frame 0's pixels) and ``position`` (pixel ``y_{i+1}`` of each
        frame-0 pixel in frame ``i+1``). The input's depth and aline coordinates are kept
        (else depth = pixel index times ``pixel_size``). The numbers do not depend on the
        scheduler or the number of workers. Read the variables by key
        (``result["cumulative"]``): ``result.cumulative`` is xarray's
        :meth:`xarray.Dataset.cumulative` method, not the variable.

    Raises
    ------
    TypeError, ValueError
        Before any work: bad types or dims, real data, chunks splitting depth or aline, frames
        holding NaN (named), bad estimator parameters.
    """
    data, coords = _frames_input(frames)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    check_choice(method, "method", METHODS)
    n_frames, n, m = data.shape
    wz, wx = _check_window(window, DEFAULT_WINDOWS[method], (n, m))
    opts = _options(method, options)  # unknown or malformed options: refused before any work
    _check_shape_options(opts, n)  # and those bounded by the image, before a lazy graph
    _check_finite_frames(data)
    if path is not None and not isinstance(path, (str, bytes)) and not hasattr(path, "__fspath__"):
        raise TypeError(f"path must be a file path, got {type(path).__name__}")
    if not isinstance(progress, (bool, np.bool_)):
        raise TypeError(f"progress must be True or False, got {progress!r}")
    args = (k, p, method, (wz, wx), options)
    dims = ("frame", "depth", "aline")
    depth = coords.get("depth", xr.DataArray(np.arange(n) * p, dims="depth"))
    out_coords = {"frame": np.arange(1, n_frames), "depth": depth}
    if "aline" in coords:
        out_coords["aline"] = coords["aline"]
    variables = {
        "interframe": attrs("strain", "interframe strain"),
        "quality": attrs("dimensionless", "interframe quality"),
        "cumulative": attrs("strain", "strain to frame 0"),
        "position": attrs("pixels", "position in frame"),
    }
    meta = {
        "method": method,
        "k0": k,
        "pixel_size": p,
        "window_depth_pixels": wz,
        "window_aline_pixels": wx,
    }
    frames_out = _scan(data, args, p, batch=_batch_size())
    if path is None:
        rows = list(frames_out)
        return xr.Dataset(
            {name: (dims, np.array([r[name] for r in rows]), a) for name, a in variables.items()},
            coords=out_coords,
            attrs=meta,
        )
    from ..io import open_dataset, write_frames

    template = xr.Dataset(
        {
            name: (dims, np.broadcast_to(np.nan, (n_frames - 1, n, m)), a)
            for name, a in variables.items()
        },
        coords=out_coords,
        attrs=meta,
    )
    write_frames(path, frames_out, n_frames=n_frames - 1, template=template, progress=progress)
    return open_dataset(path, load=False)


def _batch_size() -> int:
    """Pairs computed at once: two per core (bounded memory)."""
    return max(2, 2 * (os.cpu_count() or 1))


def _is_dask(data) -> bool:
    """A Dask array (duck-typed: the analysis group does not import Dask; the user's data
    brings it)."""
    return hasattr(data, "dask") and hasattr(data, "map_blocks") and hasattr(data, "rechunk")


def _scan(data, args, p, batch: int):
    """Yield each pair's interframe strain, quality, cumulative strain and position, in order.

    The pairs are computed ``batch`` at a time on the active Dask scheduler (numpy input: in
    this process); the scan over material positions runs here, one pair after the other.
    """
    n_frames, n, m = data.shape
    state = _start(n, m)
    if _is_dask(data):
        data = data.rechunk({0: 1})
        fields = data[:-1].map_blocks(
            _pair_block,
            data[1:],
            *args,
            dtype=float,
            new_axis=1,
            chunks=((1,) * (n_frames - 1), (3,), (n,), (m,)),
        )
        for start in range(0, n_frames - 1, batch):  # one compute per batch: frames shared
            for block in fields[start : start + batch].compute():
                state = _advance(state, block, p)
                yield _frame(block, state)
    else:
        for i in range(n_frames - 1):
            f = _pair_fields(data[i], data[i + 1], *args)
            state = _advance(state, f, p)
            yield _frame(f, state)


def _frame(fields, state) -> dict:
    return {
        "interframe": fields[0],
        "quality": fields[1],
        "cumulative": 1 - state[1],
        "position": state[0],
    }


def _start(n: int, m: int):
    """Scan state before the first pair: every frame-0 pixel at its own position, unstrained."""
    return np.repeat(np.arange(n, dtype=float)[:, None], m, axis=1), np.ones((n, m))
