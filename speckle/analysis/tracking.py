"""Correlational speckle tracking: sub-pixel displacement of every window between two B-scans.

Two methods (``method=``), the same estimator:

``"fft"`` (default)
    Every window in one vectorised pass. The complex A-scans are oversampled in depth exactly
    (zero-padding of their spectrum: the same trigonometric interpolant as
    :func:`speckle.analysis.correlation.sample_field`), the amplitude windows (means removed)
    are cross-correlated by one batched FFT, the whole-pixel peak is taken, and the peak is
    refined on a ``1/upsample`` grid by matrix-multiply DFTs around it (Guizar-Sicairos et al.
    2008), batched over windows: axial offsets at the lateral peak, then lateral offsets at the
    axial one, then axial again. The DFT phase factors factor into one per window and one table
    shared by all windows, so the refinement is two matrix products.
``"reference"``
    One :func:`skimage.registration.phase_cross_correlation` per window (the same plain,
    not phase-normalised, cross-correlation with a 2-D ``1.5 upsample``-point search region):
    what a user does with measured images, kept to test the fast path against.

The two agree to the registration grid ``1/(upsample*oversample)`` pixel where the peak is well
defined (``tests/analysis/test_tracking_fast.py``). :func:`track_array` is the numpy core;
:func:`track` its labelled wrapper. The estimates, interpolated to every pixel by
:func:`interpolate_displacement` (the only displacement interpolation of
:mod:`speckle.analysis`), feed :func:`speckle.analysis.correlation.compensate`.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
import xarray as xr
from skimage.registration import phase_cross_correlation

from .._validate import check_choice, check_int, check_real
from ..conventions import attrs, coord
from ._common import field_of, grid_spacing, matched, parse_window
from .correlation import oversample_depth, sample_field

__all__ = [
    "TRACK_METHODS",
    "interpolate_displacement",
    "interpolate_windows",
    "track",
    "track_array",
]

#: Tracking methods: the vectorised pass and the per-window skimage reference.
TRACK_METHODS = ("fft", "reference")
#: A window whose amplitude variance (at whole pixels) is below this fraction of the image's mean
#: variance per window has no texture to register: its estimate is NaN.
LOW_SIGNAL = 1e-6


def _starts(n: int, w: int, s: int) -> np.ndarray:
    return np.arange(0, n - w + 1, s)


def _windows(img: np.ndarray, step: tuple[int, int], count: tuple[int, int], wz: int, wx: int):
    """Windows ``img[z0:z0+wz, x0:x0+wx]`` at ``z0 = i*step[0]``, ``x0 = j*step[1]`` (i, j below
    ``count``): a strided view of shape (count[0], count[1], wz, wx), no copy."""
    view = np.lib.stride_tricks.sliding_window_view(img, (wz, wx))
    return view[: (count[0] - 1) * step[0] + 1 : step[0], : (count[1] - 1) * step[1] + 1 : step[1]]


def _refine(p: np.ndarray, shift: np.ndarray, axis: int, other: np.ndarray, m, up: int):
    """Upsampled cross-correlation along ``axis`` (0 aline, 1 depth) around ``shift`` at the
    offset ``other`` along the other axis; returns (best offset, its CC value).

    ``p``: half cross-power spectra (W, Mx, Mz//2+1) of real windows of shape ``m = (Mx, Mz)``
    (depth last), weighted by the multiplicity of each depth frequency, so that
    ``CC(s) = Re sum_f p_f exp(2i pi f.s/M)`` (the depth Nyquist term taken as a cosine).
    """
    mx, mz = m
    ctype = p.dtype
    fx = np.fft.fftfreq(mx, 1 / mx)
    fz = np.arange(p.shape[2], dtype=float)
    if axis == 1:  # depth: contract the aline frequencies at the aline offset
        e = np.exp(2j * np.pi * other[:, None] * fx[None] / mx).astype(ctype)
        q = np.einsum("wx,wxz->wz", e, p)
        f, size = fz, mz
    else:
        e = np.exp(2j * np.pi * other[:, None] * fz[None] / mz).astype(ctype)
        q = np.einsum("wxz,wz->wx", p, e)
        f, size = fx, mx
    region = int(np.ceil(1.5 * up))
    centre = region // 2
    base = np.round(shift * up) / up
    # exp(2i pi f (base + (u - centre)/up)/M) = exp(2i pi f base/M) * table[f, u]
    q = q * np.exp(2j * np.pi * base[:, None] * f[None] / size).astype(ctype)
    table = np.exp(2j * np.pi * f[:, None] * (np.arange(region) - centre)[None] / (up * size))
    cc = (q @ table.astype(ctype)).real
    best = np.argmax(np.abs(cc), axis=1)
    return base + (best - centre) / up, cc[np.arange(p.shape[0]), best].astype(float)


def _fft_shifts(pa, pb, up: int, va, vb, lateral: bool = True):
    """Displacement (pixels, aline and depth) of ``pb`` relative to ``pa`` for every window, and
    the normalised RMS error ``sqrt(1 - CC^2/(|a|^2 |b|^2))``; pa, pb: real (W, Mx, Mz),
    va, vb: their sums of squares."""
    w, mx, mz = pa.shape
    fa = sfft.rfft2(pa)
    fb = sfft.rfft2(pb)
    p = np.conj(fa) * fb  # CC(s) = sum a(z) b(z+s): peaks at the displacement
    cc = sfft.irfft2(p, s=(mx, mz))
    peak = np.argmax(np.abs(cc).reshape(w, -1), axis=1)
    ix, iz = np.unravel_index(peak, (mx, mz))
    sz = np.where(iz > mz // 2, iz - mz, iz).astype(float)
    sx = np.where(ix > mx // 2, ix - mx, ix).astype(float)
    if mx == 1:
        sx[:] = 0.0
    value = cc.reshape(w, -1)[np.arange(w), peak].astype(float) * (mz * mx)
    if up > 1:
        mult = np.full(p.shape[2], 2.0, dtype=pa.dtype)  # depth frequencies f, -f: one column
        mult[0] = 1.0
        if mz % 2 == 0:
            mult[-1] = 1.0
        p = p * mult
        sz, value = _refine(p, sz, 1, sx, (mx, mz), up)
        if mx > 1 and lateral:
            sx, value = _refine(p, sx, 0, sz, (mx, mz), up)
            sz, value = _refine(p, sz, 1, sx, (mx, mz), up)
    with np.errstate(invalid="ignore", divide="ignore"):  # Parseval: |F|^2 = M sum a^2
        err = np.sqrt(np.abs(1.0 - value**2 / ((mz * mx) ** 2 * va * vb)))
    return sz, sx, err


def _reference_shifts(pa: np.ndarray, pb: np.ndarray, up: int):
    out = np.empty((pa.shape[0], 3))
    for i, (a, b) in enumerate(zip(pa, pb, strict=True)):
        # skimage returns the shift registering b onto a: minus the displacement
        shift, err, _ = phase_cross_correlation(
            a.astype(float), b.astype(float), upsample_factor=up, normalization=None
        )
        out[i] = (-shift[1], -shift[0], err)
    return out[:, 0], out[:, 1], out[:, 2]


def track_array(
    reference: np.ndarray,
    deformed: np.ndarray,
    *,
    window: int | tuple[int, int] = (32, 16),
    step: int | tuple[int, int] = (16, 8),
    upsample: int = 20,
    oversample: int = 2,
    quantity: str = "amplitude",
    method: str = "fft",
    lateral: bool = True,
) -> dict[str, np.ndarray]:
    """Displacement of every window between two complex images (numpy core of :func:`track`).

    Parameters
    ----------
    reference, deformed : numpy.ndarray
        Complex images ``(depth, aline)`` of the same shape (axis 0 = depth). NaN pixels are
        allowed: they are zeroed before the registration and every window holding one gets a
        NaN estimate.
    window : int or (int, int)
        Window size in pixels (depth, aline); an int means a square window.
    step : int or (int, int)
        Distance between window starts in pixels.
    upsample : int
        Registration grid ``1/(upsample*oversample)`` pixel in depth, ``1/upsample`` laterally.
    oversample : int
        Depth samples per pixel of the registered amplitude (see :func:`oversample_depth`):
        ``|A|`` has twice the field's bandwidth, so at one sample per pixel it is aliased.
    quantity : {"amplitude", "intensity"}
        Image registered.
    method : {"fft", "reference"}
        See the module docstring.
    lateral : bool
        ``"fft"``: refine the lateral offset too (default). ``False`` keeps the lateral
        estimate at the whole-pixel peak and refines depth only (A-line-independent images,
        or when only ``uz`` is used: one refinement instead of three).

    Returns
    -------
    dict
        ``uz``, ``ux`` (displacement of the deformed image's content, pixels, positive deeper /
        towards higher aline index) and ``error`` (normalised RMS error, 0-1), each of shape
        (windows in depth, windows in aline); ``centre_depth``, ``centre_aline`` (window
        centres in pixels). NaN where a window holds a NaN pixel or has no texture (amplitude
        variance below :data:`LOW_SIGNAL` of the image's mean).

    Raises
    ------
    TypeError, ValueError
        Real or mismatched images, a window larger than the image, bad parameters.
    """
    a = np.asarray(reference)
    b = np.asarray(deformed)
    for name, x in (("reference", a), ("deformed", b)):
        if x.ndim != 2:
            raise ValueError(f"{name} must be a 2-D (depth, aline) array, got shape {x.shape}")
        if not np.issubdtype(x.dtype, np.complexfloating):
            raise TypeError(f"{name} must be a complex image, got dtype {x.dtype}")
    if a.shape != b.shape:
        raise ValueError(f"reference and deformed differ in shape: {a.shape} vs {b.shape}")
    check_choice(quantity, "quantity", ("amplitude", "intensity"))
    check_choice(method, "method", TRACK_METHODS)
    if not isinstance(lateral, (bool, np.bool_)):
        raise TypeError(f"lateral must be True or False, got {lateral!r}")
    wz, wx = parse_window(window, shape=a.shape)
    stz, stx = parse_window(step, "step", low=1)
    up = check_int(upsample, "upsample", low=1)
    ov = check_int(oversample, "oversample", low=1)
    bad = ~(np.isfinite(a) & np.isfinite(b))
    if bad.any():
        a, b = np.where(bad, 0, a), np.where(bad, 0, b)
    # (aline, depth) layout: depth, the long axis, is contiguous for the FFTs
    if method == "reference":  # today's path: per-sample trigonometric interpolation
        fine = np.arange(0, a.shape[0], 1 / ov)
        ha, hb = np.abs(sample_field(a.T, fine)), np.abs(sample_field(b.T, fine))
    else:  # the same interpolant by zero-padded FFT, in single precision
        ha = np.abs(oversample_depth(a.T.astype(np.complex64), ov, axis=-1))
        hb = np.abs(oversample_depth(b.T.astype(np.complex64), ov, axis=-1))
    if quantity == "intensity":
        ha, hb = ha**2, hb**2
    nz, nx = a.shape
    z0, x0 = _starts(nz, wz, stz), _starts(nx, wx, stx)
    shape = (z0.size, x0.size)
    pa = _windows(ha, (stx, stz * ov), shape[::-1], wx, wz * ov)
    pb = _windows(hb, (stx, stz * ov), shape[::-1], wx, wz * ov)
    pa = pa.transpose(1, 0, 2, 3).reshape(-1, wx, wz * ov)
    pb = pb.transpose(1, 0, 2, 3).reshape(-1, wx, wz * ov)
    pa = pa - pa.mean(axis=(1, 2), keepdims=True, dtype=float).astype(pa.dtype)
    pb = pb - pb.mean(axis=(1, 2), keepdims=True, dtype=float).astype(pb.dtype)
    va = np.einsum("wij,wij->w", pa, pa, dtype=float)
    vb = np.einsum("wij,wij->w", pb, pb, dtype=float)
    if method == "fft":
        uz, ux, err = _fft_shifts(pa, pb, up, va, vb, lateral)
    else:
        uz, ux, err = _reference_shifts(pa, pb, up)
    # texture from the whole-pixel samples (there the interpolant is the data, exactly: a
    # region without signal is zero there, whatever the band-limited ringing between pixels)
    ta, tb = (np.var(x[:, :, ::ov], axis=(1, 2), dtype=float) for x in (pa, pb))
    textured = (ta > LOW_SIGNAL * max(ta.mean(), 1e-300)) & (
        tb > LOW_SIGNAL * max(tb.mean(), 1e-300)
    )
    if bad.any():
        nbad = _windows(bad.astype(np.int32), (stz, stx), shape, wz, wx).sum(axis=(2, 3))
        textured &= nbad.ravel() == 0
    out = {
        "uz": np.where(textured, uz / ov, np.nan).reshape(shape),
        "ux": np.where(textured, ux, np.nan).reshape(shape),
        "error": np.where(textured, err, np.nan).reshape(shape),
        "centre_depth": z0 + (wz - 1) / 2,
        "centre_aline": x0 + (wx - 1) / 2,
    }
    return out


def track(
    reference: xr.Dataset | xr.DataArray,
    deformed: xr.Dataset | xr.DataArray,
    *,
    window: int | tuple[int, int] = (32, 16),
    step: int | tuple[int, int] = (16, 8),
    upsample: int = 20,
    oversample: int = 2,
    quantity: str = "amplitude",
    max_error: float = 0.5,
    truth: xr.Dataset | None = None,
    method: str = "fft",
) -> xr.Dataset:
    """Axial (and lateral) displacement of every window by sub-pixel cross-correlation.

    Parameters
    ----------
    reference, deformed : xarray.Dataset or xarray.DataArray
        Complex fields with dims exactly ``(depth, aline)`` on the same pixel grid, finite
        (``ValueError`` otherwise, with the count of bad pixels). The pixel size and A-line
        pitch are read from the ``depth`` and ``aline`` coordinates (µm).
    window, step, upsample, oversample, quantity, method
        As in :func:`track_array` (an int window or step means a square one).
    max_error : float
        A window counts as failed when its estimate is more than ``max_error`` pixels from
        ``truth`` (if given); without ``truth`` the registration error metric is reported only.
    truth : xarray.Dataset, optional
        Known displacement (``uz`` in µm on the pixel grid) to score the estimates.

    Returns
    -------
    xarray.Dataset
        On window centres (dims ``depth``, ``aline`` with µm coordinates): ``uz`` and ``ux``
        (µm), ``uz_pixels``, ``registration_error`` (normalised RMS error) and, with ``truth``,
        ``uz_residual`` (pixels) and ``failed`` (bool).
    """
    tol = check_real(max_error, "max_error", low=0, low_inclusive=False)
    ref = field_of(reference)
    dfm = field_of(deformed)
    for name, f in (("reference", ref), ("deformed", dfm)):
        if set(f.dims) != {"depth", "aline"}:
            raise ValueError(f"{name} must have dims exactly (depth, aline), got {f.dims}")
    ref, dfm = matched(ref, dfm)
    ref, dfm = ref.transpose("depth", "aline"), dfm.transpose("depth", "aline")
    for name, f in (("reference", ref), ("deformed", dfm)):
        bad = int(np.size(f) - np.count_nonzero(np.isfinite(f.values)))
        if bad:
            raise ValueError(
                f"{name} must be finite: {bad} NaN or infinite pixels of {f.size} (crop them, "
                "or use speckle.analysis.track_array, which gives the windows holding them NaN)"
            )
    pixel, pitch = grid_spacing(ref)
    res = track_array(
        ref.values,
        dfm.values,
        window=window,
        step=step,
        upsample=upsample,
        oversample=oversample,
        quantity=quantity,
        method=method,
    )
    wz, wx = parse_window(window)
    sz, sx = parse_window(step, "step", low=1)
    cz = ref.depth.values[0] + res["centre_depth"] * pixel
    cx = ref.aline.values[0] + res["centre_aline"] * pitch
    dims = ("depth", "aline")
    out = xr.Dataset(
        {
            "uz": (dims, res["uz"] * pixel, attrs("depth", "tracked axial displacement")),
            "ux": (dims, res["ux"] * pitch, attrs("aline", "tracked lateral displacement")),
            "uz_pixels": (dims, res["uz"], attrs("pixels", "tracked axial displacement")),
            "registration_error": (
                dims,
                res["error"],
                attrs("dimensionless", "cross-correlation RMS error"),
            ),
        },
        coords={
            "depth": coord("depth", cz, "window centre depth"),
            "aline": coord("aline", cx, "window centre"),
        },
        attrs={
            "window_depth_pixels": wz,
            "window_aline_pixels": wx,
            "step_depth_pixels": sz,
            "step_aline_pixels": sx,
            "upsample": int(upsample),
            "oversample": int(oversample),
            "quantity": quantity,
            "method": method,
        },
    )
    if truth is not None:
        exact = (
            truth["uz"].interp(depth=out.depth, aline=out.aline, kwargs={"fill_value": None})
            / pixel
        )
        resid = out["uz_pixels"] - exact
        out["uz_residual"] = resid.assign_attrs(attrs("pixels", "tracked minus exact displacement"))
        out["failed"] = (~(abs(resid) <= tol)).assign_attrs(
            long_name=f"tracking failed (|error| > {tol:g} pixel or no estimate)"
        )
        out.attrs["max_error_pixels"] = tol
    return out


def interpolate_windows(
    values: np.ndarray,
    centre_depth: np.ndarray,
    centre_aline: np.ndarray,
    depth: np.ndarray,
    aline: np.ndarray,
    *,
    outside: str = "linear",
) -> np.ndarray:
    """Window values interpolated bilinearly to the pixel grid ``depth x aline``.

    Separable linear interpolation along depth then aline, in the units of the centres (one
    window column: depth only, the same for every A-line). Beyond the outer window centres
    (``outside``): ``"linear"`` extrapolation, the ``"nearest"`` centre's value, or ``"nan"``.
    A NaN window spreads only to the pixels whose interpolation uses it.

    Parameters
    ----------
    values : array_like, shape (n_depth_windows, n_aline_windows)
        One value per window.
    centre_depth, centre_aline : array_like
        Window centres (increasing), in the units of the pixel coordinates.
    depth, aline : array_like
        The pixel grid: values of the ``depth`` and ``aline`` coordinates (µm).
    outside : {"linear", "nearest", "nan"}
        Beyond the outer centres.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(depth), len(aline))``.
    """
    check_choice(outside, "outside", ("linear", "nearest", "nan"))
    v = np.asarray(values, float)
    out = _interp_axis(v, np.asarray(centre_depth, float), np.asarray(depth, float), 0, outside)
    if v.shape[1] == 1:
        return np.repeat(out, len(aline), axis=1)
    return _interp_axis(out, np.asarray(centre_aline, float), np.asarray(aline, float), 1, outside)


def _interp_axis(v: np.ndarray, xp: np.ndarray, x: np.ndarray, axis: int, outside: str):
    if xp.size == 1:
        return np.repeat(np.take(v, [0], axis=axis), x.size, axis=axis)
    if outside == "nearest":
        x = np.clip(x, xp[0], xp[-1])
    i = np.clip(np.searchsorted(xp, x) - 1, 0, xp.size - 2)
    t = (x - xp[i]) / (xp[i + 1] - xp[i])
    lo, hi = np.take(v, i, axis=axis), np.take(v, i + 1, axis=axis)
    shape = [1, 1]
    shape[axis] = -1
    t = t.reshape(shape)
    out = lo + t * (hi - lo)
    if outside == "nan":
        beyond = ((x < xp[0]) | (x > xp[-1])).reshape(shape)
        out = np.where(beyond, np.nan, out)
    return out


def interpolate_displacement(
    tracked: xr.Dataset, depth: np.ndarray, aline: np.ndarray, *, axial_only: bool = True
) -> xr.Dataset:
    """Tracked window displacements interpolated (and extrapolated) linearly to every pixel.

    Parameters
    ----------
    tracked : xarray.Dataset
        Window displacements ``uz`` (and ``ux``) over the window centres ``depth``/``aline``.
    depth, aline : array_like
        The pixel grid: values of the ``depth`` and ``aline`` coordinates (µm).
    axial_only : bool
        Drop the lateral estimate (A-lines are independent in the model, so the lateral
        registration carries no sub-line information).

    Returns
    -------
    xarray.Dataset
        ``uz`` (and ``ux``) over ``(depth, aline)``.
    """
    out = {}
    names = ("uz",) if axial_only else ("uz", "ux")
    for name in names:
        vals = tracked[name].transpose("depth", "aline").values
        grid = interpolate_windows(
            vals, tracked.depth.values, tracked.aline.values, np.asarray(depth), np.asarray(aline)
        )
        out[name] = (("depth", "aline"), grid, dict(tracked[name].attrs))
    return xr.Dataset(out, coords={"depth": coord("depth", depth), "aline": coord("aline", aline)})
