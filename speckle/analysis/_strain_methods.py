"""The strain estimators behind :func:`speckle.analysis.strain.estimate_strain` (private).

Their tables (methods, default windows, options), input checks, window sums and least-squares
slopes, and the four methods (``vector``, ``wls``, ``tracking``, ``correlation``) with the
alignment of the pair; :mod:`speckle.analysis.strain` documents them and is the public API.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import xarray as xr
from scipy import ndimage, special

from .._validate import check_int, check_real
from .._wrap import ArraySpec
from ..system.source import spectrum
from ._common import DEPTH, LATERAL, depth_major, parse_window
from ._kernels import MARGIN, box_sums, lagrange_resample, vector_phase
from .correlation import correlation_array, resample_depth
from .correlation_forms import amplitude_from_gamma, expected_gamma
from .phase import DEFAULT_MAX_BIAS, choose_lag, depth_autocorrelation, lag_and_rho
from .tracking import interpolate_windows, track_array, track_axial

STRAIN_METHODS = ("vector", "wls", "tracking", "correlation")
DISPLACEMENT_METHODS = ("phase", "tracking")
DEFAULT_METHOD = "vector"
#: Default window (depth, x) in pixels of each method.
#: Tracking quality ``1 - registration error`` below which a tracked window has no answer
#: (tracking and correlation methods): ``1 - sqrt(1 - rho^2)`` = 0.1 is a normalised peak
#: correlation ``rho`` = 0.44. Measured (issue 36; 256 x 32 pixels, Gaussian spectrum, R = 10):
#: unrelated scenes give at most 0.042 (99 % below 0.034); 2 % strain at least 0.13 (1st
#: percentile), 1 % 0.37; at 4 % strain (0.02, as unrelated) the tracked strain is wrong.
#: Narrower windows have a higher null (single A-line windows: 56 % of unrelated pixels passed
#: 0.1), so a tracked window also needs its chance level (:func:`_chance_quality`, at
#: :data:`TRACK_FALSE_RATE`): 0.02 for the default (64, 8), 0.13 for (64, 1), 0.24 for (32, 1).
TRACK_MIN_QUALITY = 0.1
#: Probability that a tracked window of two unrelated images passes its chance level.
TRACK_FALSE_RATE = 0.01
#: Pixels on which the chance level's correlation lengths are measured.
CHANCE_SAMPLES = 4096
#: Local amplitude correlation (the correlation method's quality) below which it has no answer:
#: unrelated scenes reach it by chance. Measured (issue 36; 256 x 32 pixels, R = 10, windows
#: 32 x 8): unrelated scenes give correlations up to 0.26 (99 % below 0.17; 31 % of the pixels
#: answered a median strain of 0.048 without this bound, 0.09 % with it); 3 % strain has median
#: 0.37 (its median estimate moves from 0.0275 to 0.0268), 2 % 0.64 (unchanged).
CORRELATION_MIN_QUALITY = 0.25
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
#: Tracking that aligns the pair for the phase methods (``align``): window (depth, x)
#: pixels, step (depth, x) pixels; the displacement field is smooth, so coarse steps do.
ALIGN_TRACKING = {"window": (64, 8), "step": (64, 8), "upsample": 20, "oversample": 2}


# --------------------------------------------------------------------------------------------
# Input checks
# --------------------------------------------------------------------------------------------


#: A complex (depth, x) image of the strain estimators: finite, at least 2 x 1 pixels.
IMAGE = ArraySpec(kind="complex", dims=(DEPTH, LATERAL), min_shape=(2, 1))


def _image_pair(*, lazy: bool = False) -> dict[str, ArraySpec]:
    """The decorator's checks of ``reference`` and ``deformed``: complex images, same grid."""
    image = dataclasses.replace(IMAGE, lazy=lazy)
    return {"reference": image, "deformed": dataclasses.replace(image, same_as="reference")}


def _frames_spec() -> dict[str, ArraySpec]:
    """The decorator's check of a compression sequence: complex (frame >= 2, depth, x)."""
    return {
        "frames": ArraySpec(
            kind="complex",
            dims=("frame", DEPTH, LATERAL),
            min_shape=(2, 2, 1),
            lazy=True,
            keep_labels=True,
        )
    }


def _check_window(window: object, default: tuple[int, int], shape: tuple[int, int]):
    """(depth, x) window in pixels (an int is square), checked against the image size."""
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
        return choose_lag.__wrapped__(a1, max_bias=opts["max_bias"])  # checked image
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
        lag, rho = lag_and_rho.__wrapped__(a1, max_bias=opts["max_bias"])  # checked image
    else:
        lag, rho = _lag(a1, opts), None
    a2 = _aligned(a1, a2, p, opts)
    wrap = bool(opts["wrap_check"]) and lag > 1
    if wrap and rho is None:
        rho = depth_autocorrelation.__wrapped__(a1, 1)  # checked image
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

    :func:`speckle.analysis.tracking.track_array` on ``window`` (depth, x) windows every
    ``step`` pixels, interpolated bilinearly to every pixel
    (:func:`speckle.analysis.tracking.interpolate_windows`); beyond the outer window centres
    NaN (``outside="nan"``) or the nearest centre's value (``"nearest"``).
    """
    tr = track_array.__wrapped__(  # the numpy body: the images are checked already
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
            interpolate_windows.__wrapped__(  # the numpy body: the centres are the tracker's
                values, tr["centre_depth"], tr["centre_x"], qz, qx, outside=outside
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


def _coherence_length(a: np.ndarray, width: int) -> float:
    """``sum_L rho_A(L)^2`` over lags ``|L| < width`` along axis 0 (pixels): the amplitude
    correlation ``rho_A`` from the field's (:func:`amplitude_from_gamma` of
    :func:`~speckle.analysis.phase.depth_autocorrelation`); 1 for independent pixels."""
    m = min(width, a.shape[0]) - 1
    if m < 1:
        return 1.0
    # the numpy bodies (the image is checked); lags until |gamma|^2 <= 0.5 % (rho_A^2 ~
    # |gamma|^4 <= 3e-5 beyond: the sum is complete), all of them if it stays correlated
    try:
        _, gamma = lag_and_rho.__wrapped__(a, max_lag=m)
    except ValueError:
        gamma = depth_autocorrelation.__wrapped__(a, m)
    rho = amplitude_from_gamma.__wrapped__(gamma)
    return float(1.0 + 2.0 * np.sum(rho[1:] ** 2))


def _chance_quality(a1: np.ndarray, window: tuple[int, int]) -> float:
    """Tracking quality that two unrelated images reach in a window with probability
    :data:`TRACK_FALSE_RATE`.

    The registration quality is ``1 - sqrt(1 - r^2)`` with ``r`` the peak normalised
    cross-correlation of the windows' mean-removed amplitudes. For unrelated images the
    correlation at one lag has (Fisher) ``atanh(r) ~ N(0, 1/(n - 3))`` with ``n = wz wx /
    (Lz Lx)`` independent speckle cells in the window (``L = sum rho_A^2``, the amplitude
    correlation length of the reference along depth and along the lines), and the peak is the
    largest of ``m = (wz/Lz)(wx/Lx)`` independent lags, so ``P(max |atanh r| > t) =
    TRACK_FALSE_RATE`` at ``t = z / sqrt(n - 3)``, ``z = Phi^-1(1 - rate / (2 m))``.
    Measured (``tests/analysis/test_strain_inputs.py``): at the 98th-99th percentile of
    unrelated scenes' quality for windows of 1 to 8 lines. ``Lz``, ``Lx`` are measured on
    :data:`CHANCE_SAMPLES` pixels of the reference (every k-th line or row).
    """
    wz, wx = window
    # measured on about CHANCE_SAMPLES pixels (every k-th line, or row): Sum rho^2 to ~2 %,
    # at a fraction of the tracking's cost
    k = max(1, a1.size // CHANCE_SAMPLES)
    lz = _coherence_length(a1[:, ::k], wz)
    lx = _coherence_length(a1[::k].T, wx) if wx > 1 else 1.0
    n = wz * wx / (lz * lx)
    m = max(wz / lz, 1.0) * max(wx / lx, 1.0)
    z = float(special.ndtri(1.0 - TRACK_FALSE_RATE / (2.0 * m)))
    r = np.tanh(z / np.sqrt(max(n - 3.0, 1.0)))
    return float(1.0 - np.sqrt(1.0 - r * r))


def _track_threshold(a1: np.ndarray, window: tuple[int, int], opts: dict) -> float:
    """Quality below which a tracked window has no answer: ``min_quality`` or its chance
    level, the higher."""
    return max(opts["min_quality"], _chance_quality(a1, window))


def _tracking(a1, a2, k0, p, wz, wx, opts):
    kw = _track_options(a1, wx, opts)
    uz, quality, _ = _tracked(a1, a2, **kw)
    threshold = _track_threshold(a1, kw["window"], opts)
    uz = np.where(quality >= threshold, uz, np.nan)  # no answer below the threshold
    strain = -_pooled_slope(uz, None, wz, 1)
    return strain, quality, {"track_window": kw["window"][0], "min_quality": threshold}


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
        return resample_depth.__wrapped__(a2, q + uz_pixels)  # the numpy body: checked
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
    # the numpy body: the images are checked already
    tr = track_axial.__wrapped__(a1, a2, keep_samples=True, **_align_tracking(a1))
    qz, qx = np.arange(a1.shape[0], dtype=float), np.arange(a1.shape[1], dtype=float)
    uz = interpolate_windows(  # transposed: (aline, depth), each A-line contiguous
        tr["uz"].T, tr["centre_x"], tr["centre_depth"], qx, qz, outside="nearest"
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
    cz, cx = tr["centre_depth"], tr["centre_x"]
    qz, qx = np.arange(a1.shape[0]), np.arange(a1.shape[1])
    inside = ((qz >= cz[0]) & (qz <= cz[-1]))[:, None] & ((qx >= cx[0]) & (qx <= cx[-1]))
    covered = inside & np.isfinite(uz)
    filled, _ = _alignment_fill(uz)  # failed windows: filled from their neighbours in depth
    comp = _resampled(a2, filled)
    r = correlation_array.__wrapped__(np.abs(a1), np.abs(comp), (wz, wx))  # the numpy body
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
