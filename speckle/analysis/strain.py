"""Axial strain and displacement from a pair of complex OCT images, behind one API.

Conventions
-----------
Images are complex fields over ``(depth, x)`` (axis 0 = depth). A scatterer at depth ``z``
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
    0.1) or below the window's chance level, whichever is higher: the quality two unrelated
    images reach in that window with probability :data:`TRACK_FALSE_RATE` (1 %), from the
    number of independent speckle cells it holds (0.02 for the default 64 x 8 window, 0.13
    for 64 x 1, 0.24 for 32 x 1; :func:`estimate_displacement` too).
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

Every method returns NaN where its window does not fit in the image or it has no answer. With
no answer at any pixel a warning says why (which quality fell below which threshold, or which
range was exceeded) and what to try, naming only what the call did not use: ``align=True``
for the phase methods when the pair was not aligned, ``method='tracking'`` for the others, a
smaller ``track_window`` for a decorrelated registration, a larger one at its chance level, a
lower ``min_quality`` when the option alone refused a correlated pair.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import xarray as xr
from scipy import ndimage

from .._deprecate import moved
from .._validate import check_choice, check_real
from .._wrap import Out, map_frames, preprocess_and_wrap
from ..conventions import attrs
from ._common import DEPTH, LATERAL
from ._strain_methods import (
    _METHOD_FUNCS,
    ALIGN_TRACKING,
    AUTO_ALIGN_PIXELS,
    CORRELATION_MIN_QUALITY,
    DEFAULT_METHOD,
    DEFAULT_WINDOWS,
    DISPLACEMENT_METHODS,
    OPTIONS,
    STRAIN_METHODS,
    TRACK_FALSE_RATE,
    TRACK_MIN_QUALITY,
    _auto_aligned,
    _check_shape_options,
    _check_window,
    _frames_spec,
    _image_pair,
    _lag,
    _options,
    _place,
    _track_options,
    _track_threshold,
    _tracked,
    _unwrapped_phase,
)
from .phase import DEFAULT_MAX_BIAS

__all__ = [
    "ALIGN_TRACKING",
    "AUTO_ALIGN_PIXELS",
    "CORRELATION_MIN_QUALITY",
    "DEFAULT_METHOD",
    "DEFAULT_WINDOWS",
    "DISPLACEMENT_METHODS",
    "STRAIN_METHODS",
    "TRACK_FALSE_RATE",
    "TRACK_MIN_QUALITY",
    "accumulate_strain",
    "estimate_displacement",
    "estimate_strain",
    "predicted_strain_std",
]

#: ``METHODS`` (retired, :data:`speckle.conventions.RETIRED`) is now ``STRAIN_METHODS``.
__getattr__ = moved(__name__, __name__, [], {"METHODS": "STRAIN_METHODS"})


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------


def _advice(method: str, opts: dict, info: dict, *, decorrelated: bool) -> str:
    """What to try when an estimate has no answer: only what this call did not use.

    ``decorrelated``: the pair lost its correlation (quality below its threshold, or the
    method's range exceeded), as opposed to a window too small for its chance level.
    """
    tips = []
    if method in ("vector", "wls"):
        aligned = opts.get("align") is True or info.get("aligned") == 1
        if not aligned:
            how = "'auto' found no displacement to align" if opts.get("align") == "auto" else "off"
            tips.append(
                f"align=True ({how}; a displacement beyond the speckle size decorrelates the pair)"
            )
        tips.append("method='tracking' (supra-pixel displacements, no phase wrapping)")
    elif method == "tracking":
        tw = opts["track_window"]
        if decorrelated:
            tips.append(
                f"a smaller track_window than {tw} pixels (a strain decorrelates the "
                "registration window less)"
            )
        else:  # the chance level of the (track_window, window x) registration window
            tips.append(
                f"a larger track_window than {tw} pixels or a wider window (x) (the chance "
                "level falls with the speckle cells the registration window holds)"
            )
    else:  # correlation: the magnitude, from the tracked and compensated pair
        tips.append(
            f"a smaller track_window than {opts['track_window']} pixels or step than "
            f"{opts['step']} (the compensation follows the displacement more closely)"
        )
        tips.append("method='tracking' (the displacement's gradient, no correlation theory)")
    return "; try " + " or ".join(tips)


def _no_answer_reason(method: str, quality: np.ndarray, opts: dict, window, info=None) -> str:
    """Why an estimate has no finite pixel, and what to try (only what was not used)."""
    info = {} if info is None else info
    q = quality[np.isfinite(quality)]
    head = f"estimate_strain(method={method!r}) has no answer at any pixel: "
    threshold = info.get("min_quality", opts["min_quality"])
    if not q.size:
        return head + f"no window {tuple(window)} has a finite quality (image too small?)"
    if q.max() < threshold:
        what = {
            "vector": "phase coherence",
            "wls": "phase coherence",
            "tracking": "registration quality",
            "correlation": "compensated amplitude correlation",
        }[method]
        limit = (
            f"the registration window's chance level {threshold:.3g} "
            f"(above min_quality={opts['min_quality']:g})"
            if threshold > opts["min_quality"]
            else f"min_quality={threshold:g}"
        )
        default = OPTIONS[method]["min_quality"]
        lower = (
            f"; try a lower min_quality (the default is {default:g})"
            if opts["min_quality"] > default and threshold <= opts["min_quality"]
            else ""
        )
        advice = _advice(method, opts, info, decorrelated=threshold <= opts["min_quality"])
        if not lower:
            tail = advice
        elif q.max() >= default:  # correlated: the option alone refused it
            tail = lower
        else:
            tail = lower + advice.replace("; try ", " or ", 1)
        return head + f"every window's {what} is below {limit}; highest {q.max():.3f}" + tail
    why = {
        "vector": "the lag phase could not be unwrapped anywhere (strain beyond the method's "
        "range 1/(2 R), R = k0/delta_k, or the pair decorrelated)",
        "wls": "unwrapping failed everywhere (the fitted phase step disagrees with the lag-1 "
        "step: strain beyond the method's range or the pair decorrelated)",
        "tracking": f"every depth window of {window[0]} pixels holds a tracked pixel without "
        "an answer (the least-squares gradient needs all of them)",
        "correlation": "the local correlation is below its theory's range everywhere (a strain "
        "beyond what the theory inverts) or outside the tracked windows",
    }[method]
    return head + why + _advice(method, opts, info, decorrelated=True)


def _strain_attrs(method: str, wz: int, wx: int) -> dict:
    """Attrs of a strain estimate: what it is, the method and the window (pixels)."""
    long_name = (
        "axial strain (compression > 0)" if method != "correlation" else "axial strain magnitude"
    )
    return {
        **attrs("strain", long_name),
        "method": method,
        "window_depth_pixels": wz,
        "window_x_pixels": wx,
    }


def _strain_pair(a1, a2, k, p, method, wz, wx, opts):
    """Strain, quality and attrs of one pair of (depth, x) numpy images (checked)."""
    a1, a2 = a1.astype(np.complex128, copy=False), a2.astype(np.complex128, copy=False)
    if opts.get("align") == "auto":
        strain, quality, info = _auto_aligned(method, a1, a2, k, p, wz, wx, opts)
    else:
        strain, quality, info = _METHOD_FUNCS[method](a1, a2, k, p, wz, wx, opts)
    if not np.isfinite(strain).any():
        warnings.warn(_no_answer_reason(method, quality, opts, (wz, wx), info), stacklevel=4)
    return strain, quality, info


@preprocess_and_wrap(
    checks=_image_pair(lazy=True),
    stack=("frame",),
    from_grid={"k0": "reference", "pixel_size": "reference"},
    wrap_like="reference",
)
def estimate_strain(
    reference: np.ndarray | xr.DataArray,
    deformed: np.ndarray | xr.DataArray,
    *,
    k0: float | None = None,
    pixel_size: float | None = None,
    method: str = DEFAULT_METHOD,
    window: int | tuple[int, int] | None = None,
    return_quality: bool = False,
    **options,
):
    """Axial strain between two complex OCT images (positive for compression).

    Parameters
    ----------
    reference, deformed : numpy.ndarray or xarray.DataArray
        Complex images ``(depth, x)`` of the same shape (DataArrays: dims ``depth`` and
        ``x``, identical coordinates; refused, never aligned, when they differ), all
        finite. Axis 0 is depth with pixel size ``pixel_size``. DataArrays with a leading
        ``frame`` dim on both are pairs ``reference[i]``, ``deformed[i]``, checked once and
        estimated frame by frame (Dask-backed: lazily, one task per frame).
    k0 : float, optional
        Central wavenumber in the medium, rad/µm (> 0), as in :func:`speckle.ascan`. Read
        from the ``k0`` attribute of labelled images (every image the package makes carries
        it: :func:`speckle.conventions.with_grid`; a value given as well must agree with it);
        required for numpy images and for measured images without it
        (:func:`speckle.load_image`).
    pixel_size : float, optional
        Axial pixel size in the medium, µm (> 0); ``H/N`` for the model's images. Read from
        the ``depth`` coordinate of labelled images (a value given as well must agree with
        it); required for numpy images.
    method : {"vector", "wls", "tracking", "correlation"}
        Estimator (see the module docstring); default ``"vector"``.
    window : int or (int, int), optional
        Window (depth, x) in pixels over which each estimate is taken; default
        :data:`DEFAULT_WINDOWS` of the method. An int ``w`` means the square window
        ``(w, w)``.
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

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> kw = dict(n_pixels=64, depth_range=512.0, seed=1)
    >>> scene = speckle.deformable_scene(16, 4.0, strain=2e-3, **kw)
    >>> img = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 2e-3]), src).field
    >>> ref, moved = img.isel(strain=0), img.isel(strain=1)
    >>> strain = speckle.estimate_strain(ref, moved, window=(16, 4))  # k0, pixel: from the image
    >>> round(float(np.nanmedian(strain)), 3)  # the applied 2e-3
    0.002
    >>> k0, pixel = float(src.attrs["k0"]), 8.0  # numpy images: give them
    >>> same = speckle.estimate_strain(ref.values, moved.values, k0=k0, pixel_size=pixel,
    ...                                window=(16, 4))
    >>> bool(np.array_equal(strain.values, same, equal_nan=True))
    True
    """
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    check_choice(method, "method", STRAIN_METHODS)
    if not isinstance(return_quality, (bool, np.bool_)):
        raise TypeError(f"return_quality must be True or False, got {return_quality!r}")
    wz, wx = _check_window(window, DEFAULT_WINDOWS[method], reference.shape[-2:])
    opts = _options(method, options)
    if reference.ndim == 3:  # a frame stack: pairs reference[i], deformed[i], checked once
        _check_shape_options(opts, reference.shape[1])
        strain, quality = map_frames(
            lambda a1, a2: _strain_pair(a1, a2, k, p, method, wz, wx, opts)[:2],
            reference,
            deformed,
            ndim=2,
            n_out=2,
        )
        info = {}
    else:
        strain, quality, info = _strain_pair(reference, deformed, k, p, method, wz, wx, opts)
    q_attrs = attrs("dimensionless", "quality")
    meta = {**_strain_attrs(method, wz, wx), **info}
    out = Out(strain, None, meta, coords={"quality": (quality, q_attrs)})
    if return_quality:
        return out, Out(quality, "quality", q_attrs)
    return out


@preprocess_and_wrap(
    checks=_image_pair(),
    from_grid={"k0": "reference", "pixel_size": "reference"},
    wrap_like="reference",
)
def estimate_displacement(
    reference: np.ndarray | xr.DataArray,
    deformed: np.ndarray | xr.DataArray,
    *,
    k0: float | None = None,
    pixel_size: float | None = None,
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
        ``"tracking"``: :func:`speckle.track` in ``(track_window, window[x])`` windows
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

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> kw = dict(n_pixels=64, depth_range=512.0, seed=1)
    >>> scene = speckle.deformable_scene(16, 4.0, strain=2e-3, **kw)
    >>> img = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 2e-3]), src).field
    >>> ref, moved = img.isel(strain=0), img.isel(strain=1)
    >>> k0, pixel = float(src.attrs["k0"]), 8.0
    >>> u = speckle.estimate_displacement(ref, moved, k0=k0, pixel_size=pixel, method="phase")
    >>> u.shape == ref.shape
    True
    """
    a1, a2 = reference.astype(np.complex128, copy=False), deformed.astype(np.complex128, copy=False)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    check_choice(method, "method", DISPLACEMENT_METHODS)
    _, wx = _check_window(window, (2, 1), a1.shape)
    if method == "tracking":
        opts = _options("tracking", options)
        kw = _track_options(a1, wx, opts)
        uz, quality, _ = _tracked(a1, a2, **kw)
        # no answer below min_quality or the window's chance level (single lines: higher)
        uz = np.where(quality >= _track_threshold(a1, kw["window"], opts), uz, np.nan) * p
    else:
        allowed = {"lag": None, "max_bias": DEFAULT_MAX_BIAS}
        unknown = set(options) - set(allowed)
        if unknown:
            raise TypeError(f"method 'phase' takes options {sorted(allowed)}; got {unknown}")
        opts = {**allowed, **options}
        phase, _ = _unwrapped_phase(a1, a2, _lag(a1, opts))
        uz = phase / (2 * k)
    meta = attrs("displacement", "axial displacement (+z deeper)", method=method)
    return Out(uz, None, meta)


@preprocess_and_wrap(checks=_image_pair(), from_grid={"k0": "reference", "pixel_size": "reference"})
def predicted_strain_std(
    reference: np.ndarray,
    deformed: np.ndarray,
    *,
    noise_power: float,
    k0: float | None = None,
    pixel_size: float | None = None,
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
    a1, a2 = reference.astype(np.complex128, copy=False), deformed.astype(np.complex128, copy=False)
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


@preprocess_and_wrap(checks=_frames_spec(), from_grid={"k0": "frames", "pixel_size": "frames"})
def accumulate_strain(
    frames: np.ndarray | xr.DataArray,
    *,
    k0: float | None = None,
    pixel_size: float | None = None,
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
        Complex images ``(frame, depth, x)``, at least two frames, all finite. A Dask-backed
        DataArray (e.g. ``speckle.io.open_dataset(path, load=False)["field"]`` or
        ``xarray.open_zarr(...)``) is processed lazily, one pair per task; its chunks must hold
        whole images (``frames.chunk({"frame": 1, "depth": -1, "x": -1})``).
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
        ``interframe`` (``frame`` = pair index, depth, x; on each earlier frame's grid),
        ``quality`` (of each interframe estimate), ``accumulated`` (strain of frame ``i+1``
        relative to frame 0 on frame 0's pixels) and ``position`` (pixel ``y_{i+1}`` of each
        frame-0 pixel in frame ``i+1``). The input's depth and aline coordinates are kept
        (else depth = pixel index times ``pixel_size``). The numbers do not depend on the
        scheduler or the number of workers. The accumulated strain was named ``cumulative``
        before: that name is :meth:`xarray.Dataset.cumulative`, a method, so
        ``result.cumulative`` did not give the variable; ``result.accumulated`` does (files
        written before hold ``cumulative``).

    Raises
    ------
    TypeError, ValueError
        Before any work: bad types or dims, real data, chunks splitting depth or aline, frames
        holding NaN (named), bad estimator parameters.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> kw = dict(n_pixels=64, depth_range=512.0, seed=1)
    >>> scene = speckle.deformable_scene(16, 4.0, strain=4e-3, **kw)
    >>> img = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 2e-3, 4e-3]), src)
    >>> frames = img.field.rename(strain="frame")
    >>> total = speckle.accumulate_strain(frames, k0=float(src.attrs["k0"]), pixel_size=8.0)
    >>> round(float(np.nanmedian(total["accumulated"].isel(frame=-1))), 3)  # 4e-3 after two steps
    0.004
    """
    labelled = isinstance(frames, xr.DataArray)  # checked and transposed by the decorator
    coords = {d: frames[d] for d in (DEPTH, LATERAL) if labelled and d in frames.coords}
    data = frames.data if labelled else frames  # numpy, or Dask from a lazy DataArray
    chunks = getattr(data, "chunks", None)
    if chunks is not None and (len(chunks[1]) > 1 or len(chunks[2]) > 1):
        raise ValueError(
            f"frames' Dask chunks split depth or aline (chunks {chunks[1]} x {chunks[2]}): a "
            "pair needs whole images; rechunk with frames.chunk({'frame': 1, 'depth': -1, "
            "'x': -1})"
        )
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    k = check_real(k0, "k0", low=0, low_inclusive=False)
    check_choice(method, "method", STRAIN_METHODS)
    n_frames, n, m = data.shape
    wz, wx = _check_window(window, DEFAULT_WINDOWS[method], (n, m))
    opts = _options(method, options)  # unknown or malformed options: refused before any work
    _check_shape_options(opts, n)  # and those bounded by the image, before a lazy graph
    if path is not None and not isinstance(path, (str, bytes)) and not hasattr(path, "__fspath__"):
        raise TypeError(f"path must be a file path, got {type(path).__name__}")
    if not isinstance(progress, (bool, np.bool_)):
        raise TypeError(f"progress must be True or False, got {progress!r}")
    args = (k, p, method, (wz, wx), options)
    dims = ("frame", DEPTH, LATERAL)
    depth = coords.get(DEPTH, xr.DataArray(np.arange(n) * p, dims=DEPTH))
    out_coords = {"frame": np.arange(1, n_frames), DEPTH: depth}
    if LATERAL in coords:
        out_coords[LATERAL] = coords[LATERAL]
    variables = {
        "interframe": attrs("strain", "interframe strain"),
        "quality": attrs("dimensionless", "interframe quality"),
        "accumulated": attrs("strain", "strain to frame 0"),
        "position": attrs("pixels", "position in frame"),
    }
    meta = {
        "method": method,
        "k0": k,
        "pixel_size": p,
        "window_depth_pixels": wz,
        "window_x_pixels": wx,
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
        "accumulated": 1 - state[1],
        "position": state[0],
    }


def _start(n: int, m: int):
    """Scan state before the first pair: every frame-0 pixel at its own position, unstrained."""
    return np.repeat(np.arange(n, dtype=float)[:, None], m, axis=1), np.ones((n, m))
