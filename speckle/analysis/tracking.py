"""Correlational speckle tracking: sub-pixel displacement of every window between two B-scans.

Two methods (``method=``), the same estimator:

``"fft"`` (default)
    Every window in one vectorised pass. The complex A-scans are oversampled in depth exactly
    (zero-padding of their spectrum: the same trigonometric interpolant as
    :func:`speckle.analysis.correlation.sample_field`), the amplitude windows (means removed)
    are cross-correlated by batched FFTs (each A-line's depth transform shared by the windows
    that overlap it), the whole-pixel peak is taken, and the peak is refined on a ``1/upsample``
    grid by the upsampled DFT around it (Guizar-Sicairos et al. 2008): axial offsets at the
    lateral peak, then lateral offsets at the axial one, then axial again, one window at a time
    in a numba kernel, the phase factors split into one per window and one table shared by all.
``"reference"``
    One :func:`skimage.registration.phase_cross_correlation` per window (the same plain,
    not phase-normalised, cross-correlation with a 2-D ``1.5 upsample``-point search region):
    what a user does with measured images, kept to test the fast path against.

The two agree to the registration grid ``1/(upsample*oversample)`` pixel where the peak is well
defined (``tests/analysis/test_tracking_fast.py``). :func:`track_array` is the numpy core;
:func:`track` its labelled wrapper; :func:`track_axial` the same estimator at lateral offset 0
(the alignment of the phase strain methods). The estimates, interpolated to every pixel by
:func:`interpolate_displacement` (the only displacement interpolation of
:mod:`speckle.analysis`), feed :func:`speckle.analysis.correlation.compensate`.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
import xarray as xr
from skimage.registration import phase_cross_correlation

from .._deprecate import renamed_parameters
from .._validate import (
    check_bool,
    check_choice,
    check_int,
    check_memory,
    check_real,
)
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, canonical_dims, coord
from ._common import DEPTH, LATERAL, grid_spacing, parse_window
from ._kernels import refine_shifts, window_moments
from .correlation import oversample_depth, sample_field

__all__ = [
    "TRACK_METHODS",
    "interpolate_displacement",
    "interpolate_windows",
    "track",
    "track_array",
    "track_axial",
]

#: The images of :func:`track_array` and :func:`track_axial`: complex (depth, x), NaN
#: allowed (their windows get NaN).
_IMAGES = {
    "reference": ArraySpec(kind="complex", dims=(DEPTH, LATERAL), finite=False),
    "deformed": ArraySpec(kind="complex", dims=(DEPTH, LATERAL), finite=False, same_as="reference"),
}
#: The B-scans of :func:`track`: labelled (a field DataArray or a B-scan Dataset), finite.
_SCANS = {
    name: ArraySpec(
        dims=(DEPTH, LATERAL),
        labelled=True,
        variable="field",
        keep_labels=True,
        same_as=None if name == "reference" else "reference",
    )
    for name in ("reference", "deformed")
}

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


def _depth_spectra(h: np.ndarray, nz: int, mz: int, sz: int) -> np.ndarray:
    """Half spectra of the ``nz`` depth windows (``mz`` samples every ``sz``) of every A-line
    of ``h`` (aline, depth): shape (aline, nz, mz//2 + 1)."""
    cols = np.lib.stride_tricks.sliding_window_view(h, mz, axis=1)[:, : (nz - 1) * sz + 1 : sz]
    return sfft.rfft(cols, axis=-1)


def _multiplicity(nf: int, mz: int) -> np.ndarray:
    """Weight of each depth frequency of a real window's half spectrum: 2 (f and -f), 1 for
    0 and the Nyquist term (``mz`` even)."""
    mult = np.full(nf, 2.0)
    mult[0] = 1.0
    if mz % 2 == 0:
        mult[-1] = 1.0
    return mult


def _abs_argmax(flat: np.ndarray) -> np.ndarray:
    """Index of the largest ``|value|`` of every row (the maximum and the minimum compared)."""
    hi, lo = np.argmax(flat, axis=1), np.argmin(flat, axis=1)
    rows = np.arange(flat.shape[0])
    return np.where(flat[rows, hi] >= -flat[rows, lo], hi, lo)


def _column_spectra(h: np.ndarray, count: tuple[int, int], size: tuple[int, int], step):
    """2-D spectra of every window of ``h`` (aline, depth), shape (windows in aline, windows in
    depth, depth frequencies, aline frequencies).

    The depth transform of each A-line's window is computed once and shared by the windows
    that overlap it laterally (real input: a half spectrum); the lateral transform of every
    window follows, batched.
    """
    (nx, nz), (mx, mz), (sx, sz) = count, size, step
    spec = _depth_spectra(h, nz, mz, sz)
    lat = np.lib.stride_tricks.sliding_window_view(spec, mx, axis=0)[: (nx - 1) * sx + 1 : sx]
    return sfft.fft(lat, axis=-1)  # (windows in aline, windows in depth, fz, fx)


def _fft_shifts(ha, hb, count, size, step, up: int, lateral: bool, want_error: bool):
    """Displacement (samples, depth and aline) of ``hb`` relative to ``ha`` for every window,
    and the normalised RMS error ``sqrt(1 - CC^2/(|a|^2 |b|^2))`` (windows' means removed);
    ha, hb: real (aline, depth samples) images, windows ``count`` x ``size`` every ``step``
    (aline, depth). Outputs are flat over windows ordered (depth, x)."""
    (nx, nz), (mx, mz) = count, size
    w = nx * nz
    p = np.conj(_column_spectra(ha, count, size, step))
    p *= _column_spectra(hb, count, size, step)  # CC(s) = sum a(z) b(z+s): peaks at the shift
    p[:, :, 0, 0] = 0  # the windows' means removed
    h = sfft.ifft(p, axis=-1)  # lateral offsets (whole pixels), depth frequencies
    cc = sfft.irfft(h, n=mz, axis=-2)  # (nx, nz, mz, mx)
    flat = cc.reshape(w, mz * mx)
    rows = np.arange(w)
    peak = _abs_argmax(flat)
    iz, ix = np.divmod(peak, mx)
    sz = np.where(iz > mz // 2, iz - mz, iz).astype(float)
    sx = np.where(ix > mx // 2, ix - mx, ix).astype(float)
    if mx == 1:
        sx[:] = 0.0
    value = flat[rows, peak].astype(float) * (mz * mx)
    if up > 1:
        mult = _multiplicity(p.shape[2], mz)
        fz, fx = np.arange(p.shape[2], dtype=float), np.fft.fftfreq(mx, 1 / mx)
        tz, tx = _table(fz, mz, up), _table(fx, mx, up)
        refine_shifts(
            p.reshape(w, p.shape[2], mx),
            mult,
            fz,
            fx,
            mz,
            mx,
            up,
            bool(lateral),
            tz.real.copy(),
            tz.imag.copy(),
            tx.real.copy(),
            tx.imag.copy(),
            sz,
            sx,
            value,
        )

    def order(v):  # (aline, depth) windows -> flat over (depth, x)
        return v.reshape(nx, nz).T.ravel()

    if not want_error:
        return order(sz), order(sx), np.full(w, np.nan)
    va, vb = (_window_power(x, count, size, step).ravel() for x in (ha, hb))
    with np.errstate(invalid="ignore", divide="ignore"):  # Parseval: |F|^2 = M sum a^2
        err = np.sqrt(np.abs(1.0 - value**2 / ((mz * mx) ** 2 * va * vb)))
    return order(sz), order(sx), order(err)


def _window_power(x: np.ndarray, count, size, step) -> np.ndarray:
    """Sum of squares of every window of ``x`` (aline, depth) with its mean removed, shape
    (windows in aline, windows in depth); float64 sums."""
    s1, s2 = np.empty(count), np.empty(count)
    window_moments(x, *count, *size, *step, s1, s2)
    return np.maximum(s2 - s1 * s1 / (size[0] * size[1]), 0.0)


def _check_upsample(up: int, nf: int, mx: int) -> None:
    """The refinement tables' memory (``ceil(1.5 up)`` offsets x the depth frequencies ``nf``
    and lateral ``mx``, complex and its real/imaginary copies) within the bound."""
    region = float(np.ceil(1.5 * up))
    check_memory(32.0 * region * (nf + mx), "upsample", "the sub-pixel refinement tables")


def _table(f: np.ndarray, size: int, up: int) -> np.ndarray:
    """``exp(2i pi f (u - centre)/(up size))`` for the ``ceil(1.5 up)`` offsets ``u`` of the
    refinement region (centre ``region//2``): the factor shared by every window."""
    region = int(np.ceil(1.5 * up))
    u = np.arange(region) - region // 2
    return np.exp(2j * np.pi * f[:, None] * u[None] / (up * size))


def _reference_shifts(pa: np.ndarray, pb: np.ndarray, up: int):
    out = np.empty((pa.shape[0], 3))
    for i, (a, b) in enumerate(zip(pa, pb, strict=True)):
        # skimage returns the shift registering b onto a: minus the displacement
        shift, err, _ = phase_cross_correlation(
            a.astype(float), b.astype(float), upsample_factor=up, normalization=None
        )
        out[i] = (-shift[1], -shift[0], err)
    return out[:, 0], out[:, 1], out[:, 2]


@preprocess_and_wrap(checks=_IMAGES)
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
    error: bool = True,
) -> dict[str, np.ndarray]:
    """Displacement of every window between two complex images (numpy core of :func:`track`).

    Parameters
    ----------
    reference, deformed : numpy.ndarray
        Complex images ``(depth, x)`` of the same shape (axis 0 = depth). NaN pixels are
        allowed: they are zeroed before the registration and every window holding one gets a
        NaN estimate.
    window : int or (int, int)
        Window size in pixels (depth, x); an int means a square window.
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
    error : bool
        ``"fft"``: compute the registration error (default). ``False`` leaves ``error`` NaN
        and skips the windows' power sums (when only the displacement is used).

    Returns
    -------
    dict
        ``uz``, ``ux`` (displacement of the deformed image's content, pixels, positive deeper /
        towards higher aline index) and ``error`` (normalised RMS error, 0-1), each of shape
        (windows in depth, windows in aline); ``centre_depth``, ``centre_x`` (window
        centres in pixels). NaN where a window holds a NaN pixel or has no texture (amplitude
        variance below :data:`LOW_SIGNAL` of the image's mean).

    Raises
    ------
    TypeError, ValueError
        Real or mismatched images, a window larger than the image, bad parameters.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> rng = np.random.default_rng(0)
    >>> a = rng.normal(size=(64, 32)) + 1j * rng.normal(size=(64, 32))
    >>> out = speckle.track_array(a, np.roll(a, 3, axis=0), window=(32, 16), step=(16, 8))
    >>> round(float(np.median(out["uz"])), 2)  # a shift of 3 pixels in depth
    3.0
    """
    a, b = reference, deformed  # checked by the decorator
    check_choice(quantity, "quantity", ("amplitude", "intensity"))
    check_choice(method, "method", TRACK_METHODS)
    for name, flag in (("lateral", lateral), ("error", error)):
        if not isinstance(flag, (bool, np.bool_)):
            raise TypeError(f"{name} must be True or False, got {flag!r}")
    wz, wx = parse_window(window, shape=a.shape)
    stz, stx = parse_window(step, "step", low=1)
    up = check_int(upsample, "upsample", low=1)
    ov = check_int(oversample, "oversample", low=1)
    _check_upsample(up, wz * ov, wx)
    a, b, bad = _zero_bad(a, b)
    if method == "reference":  # today's path: per-sample trigonometric interpolation
        fine = np.arange(0, a.shape[0], 1 / ov)
        sample = sample_field.__wrapped__  # the numpy body: the images are checked
        ha, hb = np.abs(sample(a.T, fine)), np.abs(sample(b.T, fine))
    else:
        ha, hb, _ = _amplitudes(a, b, ov)
    if quantity == "intensity":
        ha, hb = ha**2, hb**2
    nz, nx = a.shape
    z0, x0 = _starts(nz, wz, stz), _starts(nx, wx, stx)
    shape = (z0.size, x0.size)
    if method == "fft":
        count, size, steps = (x0.size, z0.size), (wx, wz * ov), (stx, stz * ov)
        uz, ux, err = _fft_shifts(ha, hb, count, size, steps, up, lateral, bool(error))
    else:
        pa = _windows(ha, (stx, stz * ov), shape[::-1], wx, wz * ov)
        pb = _windows(hb, (stx, stz * ov), shape[::-1], wx, wz * ov)
        pa = pa.transpose(1, 0, 2, 3).reshape(-1, wx, wz * ov)
        pb = pb.transpose(1, 0, 2, 3).reshape(-1, wx, wz * ov)
        pa = pa - pa.mean(axis=(1, 2), keepdims=True, dtype=float).astype(pa.dtype)
        pb = pb - pb.mean(axis=(1, 2), keepdims=True, dtype=float).astype(pb.dtype)
        uz, ux, err = _reference_shifts(pa, pb, up)
    textured = _textured(ha, hb, ov, bad, (z0.size, x0.size), (wz, wx), (stz, stx))
    return {
        "uz": np.where(textured, uz / ov, np.nan).reshape(shape),
        "ux": np.where(textured, ux, np.nan).reshape(shape),
        "error": np.where(textured, err, np.nan).reshape(shape),
        "centre_depth": z0 + (wz - 1) / 2,
        "centre_x": x0 + (wx - 1) / 2,
    }


@preprocess_and_wrap(checks=_IMAGES)
def track_axial(
    reference: np.ndarray,
    deformed: np.ndarray,
    *,
    window: int | tuple[int, int] = (32, 8),
    step: int | tuple[int, int] = (16, 8),
    upsample: int = 20,
    oversample: int = 2,
    keep_samples: bool = False,
) -> dict[str, np.ndarray]:
    """Axial displacement of every window, each A-line compared with itself (no lateral search).

    The estimator of :func:`track_array` (``method="fft"``, amplitude) restricted to lateral
    offset 0: the cross-correlation of a window is the sum of its A-lines' depth
    cross-correlations (windows' means removed), so one depth transform per A-line window and
    no lateral transform are needed. Serves the alignment of the phase strain methods, which
    compare A-line ``j`` of both images in place as well.

    Parameters
    ----------
    reference, deformed : numpy.ndarray
        Complex images ``(depth, x)`` of the same shape; NaN pixels as in
        :func:`track_array`.
    window, step, upsample, oversample
        As in :func:`track_array` (window default (32, 8)).
    keep_samples : bool
        Also return ``deformed_samples``: the deformed image's complex samples every
        ``1/oversample`` pixel from which its amplitude was tracked (the band-limited interpolant
        of :func:`oversample_depth`, complex64, shape (aline, oversample x depth), each A-line
        contiguous; NaN pixels zeroed). The alignment of :func:`estimate_strain` resamples the
        deformed image from them instead of oversampling it a second time.

    Returns
    -------
    dict
        ``uz`` (pixels, windows in depth x windows in aline; NaN without texture or with a NaN
        pixel), ``centre_depth``, ``centre_x`` (pixels), and with ``keep_samples``
        ``deformed_samples``.

    Raises
    ------
    TypeError, ValueError
        As :func:`track_array`.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> rng = np.random.default_rng(0)
    >>> a = rng.normal(size=(64, 32)) + 1j * rng.normal(size=(64, 32))
    >>> out = speckle.track_axial(a, np.roll(a, 3, axis=0), window=(32, 8), step=(16, 8))
    >>> round(float(np.median(out["uz"])), 2)  # a shift of 3 pixels in depth
    3.0
    """
    a, b = reference, deformed  # checked by the decorator
    wz, wx = parse_window(window, shape=a.shape)
    stz, stx = parse_window(step, "step", low=1)
    up = check_int(upsample, "upsample", low=1)
    ov = check_int(oversample, "oversample", low=1)
    _check_upsample(up, wz * ov, 1)
    if not isinstance(keep_samples, (bool, np.bool_)):
        raise TypeError(f"keep_samples must be True or False, got {keep_samples!r}")
    a, b, bad = _zero_bad(a, b)
    ha, hb, samples = _amplitudes(a, b, ov, keep=bool(keep_samples))
    nz, nx = a.shape
    z0, x0 = _starts(nz, wz, stz), _starts(nx, wx, stx)
    mz, sz = wz * ov, stz * ov
    sa, sb = (_depth_spectra(h, z0.size, mz, sz) for h in (ha, hb))  # (aline, nz, f)
    cross = np.conj(sa)
    cross *= sb
    last = (x0.size - 1) * stx + 1
    p = sum(cross[k : k + last : stx] for k in range(wx))  # (windows in aline, nz, f)
    dc_a = sum(sa[k : k + last : stx, :, 0].real for k in range(wx))
    dc_b = sum(sb[k : k + last : stx, :, 0].real for k in range(wx))
    p[:, :, 0] -= dc_a * dc_b / wx  # the window's mean removed (its 2-D mean, every A-line)
    cc = sfft.irfft(p, n=mz, axis=-1)  # (windows in aline, nz, mz): CC(s) / mz
    flat = cc.reshape(-1, mz)
    peak = _abs_argmax(flat)
    shift = np.where(peak > mz // 2, peak - mz, peak).astype(float)
    if up > 1:
        w = flat.shape[0]
        fz = np.arange(p.shape[2], dtype=float)
        tz = _table(fz, mz, up)
        value = np.empty(w)
        zero = np.zeros(w)
        refine_shifts(
            p.reshape(w, -1, 1),
            _multiplicity(p.shape[2], mz),
            fz,
            np.zeros(1),
            mz,
            1,
            up,
            False,
            tz.real.copy(),
            tz.imag.copy(),
            np.ones((1, 1)),
            np.zeros((1, 1)),
            shift,
            zero,
            value,
        )
    uz = shift.reshape(x0.size, z0.size).T.ravel()
    shape = (z0.size, x0.size)
    textured = _textured(ha, hb, ov, bad, shape, (wz, wx), (stz, stx))
    out = {
        "uz": np.where(textured, uz / ov, np.nan).reshape(shape),
        "centre_depth": z0 + (wz - 1) / 2,
        "centre_x": x0 + (wx - 1) / 2,
    }
    if keep_samples:
        out["deformed_samples"] = samples
    return out


def _zero_bad(a, b):
    """NaN/inf pixels of either image zeroed in both, and their mask (None when all finite:
    a finite sum means every pixel is, one pass without a mask)."""
    if np.isfinite(a.sum()) and np.isfinite(b.sum()):
        return a, b, None
    bad = ~(np.isfinite(a) & np.isfinite(b))
    return np.where(bad, 0, a), np.where(bad, 0, b), bad


def _amplitudes(a, b, ov: int, keep: bool = False):
    """``|A|`` of both images oversampled ``ov`` times in depth (zero-padded spectrum, single
    precision), laid out (aline, depth samples): depth contiguous for the FFTs. With ``keep``,
    also the deformed image's complex samples of which its amplitude is taken (else None).

    For ``ov = 2`` the whole-pixel samples are the data and only the half-pixel ones are
    transformed: ``A(q + 1/2)`` is the N-point inverse transform of the spectrum times the
    half-pixel phase ramp (the same interpolant as :func:`oversample_depth`, half the work).
    """
    out = []
    for x, want in ((a, False), (b, keep)):
        lines = np.ascontiguousarray(x.T, dtype=np.complex64)
        if ov != 2:
            fine = oversample_depth.__wrapped__(lines, ov, axis=-1)  # checked images
            out.append((np.abs(fine), fine if want else None))
            continue
        n = lines.shape[1]
        spec = sfft.fft(lines, axis=-1)
        spec *= _half_pixel_ramp(n)
        half = sfft.ifft(spec, axis=-1, overwrite_x=True)
        h = np.empty((lines.shape[0], 2 * n), dtype=np.float32)
        fine = None
        if want:  # interleaved: sample 2q is pixel q, sample 2q + 1 is q + 1/2
            fine = np.empty((lines.shape[0], 2 * n), dtype=np.complex64)
            fine[:, 0::2] = lines
            fine[:, 1::2] = half
            np.abs(fine, out=h)
        else:
            np.abs(lines, out=h[:, 0::2])
            np.abs(half, out=h[:, 1::2])
        out.append((h, fine))
    (ha, _), (hb, samples) = out
    return ha, hb, samples


def _half_pixel_ramp(n: int) -> np.ndarray:
    """``exp(-i pi n_m / N)`` for FFT bin ``m`` of model index ``n_m`` (``-m`` up to
    ``m = N//2``, ``N - m`` above, as in :func:`oversample_depth`): shifts by half a pixel."""
    m = np.arange(n)
    index = np.where(m <= n // 2, -m, n - m)
    return np.exp(-1j * np.pi * index / n).astype(np.complex64)


def _textured(ha, hb, ov, bad, shape, window, step) -> np.ndarray:
    """Windows with texture in both images and no bad pixel, flat over (depth, x).

    Texture from the whole-pixel samples (there the interpolant is the data, exactly: a region
    without signal is zero there, whatever the band-limited ringing between pixels): the
    window's variance above :data:`LOW_SIGNAL` of the image's mean.
    """
    (nz, nx), (wz, wx), (stz, stx) = shape, window, step
    whole = ((nx, nz), (wx, wz), (stx, stz))
    ta, tb = (_window_power(h[:, ::ov], *whole).T.ravel() for h in (ha, hb))
    ok = (ta > LOW_SIGNAL * max(ta.mean(), 1e-300)) & (tb > LOW_SIGNAL * max(tb.mean(), 1e-300))
    if bad is not None:
        nbad = _windows(bad.astype(np.int32), (stz, stx), shape, wz, wx).sum(axis=(2, 3))
        ok &= nbad.ravel() == 0
    return ok


@preprocess_and_wrap(checks=_SCANS)
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
        Complex fields with dims exactly ``(depth, x)`` on the same pixel grid, finite
        (``ValueError`` otherwise, with the count of bad pixels). The pixel size and A-line
        pitch are read from the ``depth`` and ``x`` coordinates (µm).
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
        On window centres (dims ``depth``, ``x`` with µm coordinates): ``uz`` and ``ux``
        (µm), ``uz_pixels``, ``registration_error`` (normalised RMS error) and, with ``truth``,
        ``uz_residual`` (pixels) and ``failed`` (bool).

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(32, 4.0, n_pixels=64, depth_range=512.0, seed=1)
    >>> ref = speckle.bscan(scene, src).field
    >>> moved = speckle.bscan(speckle.translate(scene, 16.0), src).field
    >>> out = speckle.track(ref, moved, window=(32, 16), step=(16, 8))
    >>> round(float(out.uz.median()), 1)  # µm: the scene moved 16 µm deeper
    16.0
    """
    tol = check_real(max_error, "max_error", low=0, low_inclusive=False)
    if truth is not None and not (isinstance(truth, xr.Dataset) and "uz" in truth):
        raise TypeError(
            f"truth must be an xarray.Dataset with 'uz' (µm) on the pixel grid, got "
            f"{type(truth).__name__}"
        )
    truth = canonical_dims(truth, "truth")  # a field over (depth, aline): x, warning
    ref, dfm = reference, deformed  # fields (depth, x), finite, same grid: the decorator
    pixel, pitch = grid_spacing(ref)
    res = track_array.__wrapped__(  # the numpy body: checked by track's decorator
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
    cz = ref[DEPTH].values[0] + res["centre_depth"] * pixel
    cx = ref[LATERAL].values[0] + res["centre_x"] * pitch
    dims = (DEPTH, LATERAL)
    out = xr.Dataset(
        {
            "uz": (dims, res["uz"] * pixel, attrs("depth", "tracked axial displacement")),
            "ux": (dims, res["ux"] * pitch, attrs("x", "tracked lateral displacement")),
            "uz_pixels": (dims, res["uz"], attrs("pixels", "tracked axial displacement")),
            "registration_error": (
                dims,
                res["error"],
                attrs("dimensionless", "cross-correlation RMS error"),
            ),
        },
        coords={
            "depth": coord("depth", cz, "window centre depth"),
            "x": coord("x", cx, "window centre"),
        },
        attrs={
            "window_depth_pixels": wz,
            "window_x_pixels": wx,
            "step_depth_pixels": sz,
            "step_x_pixels": sx,
            "upsample": int(upsample),
            "oversample": int(oversample),
            "quantity": quantity,
            "method": method,
        },
    )
    if truth is not None:
        exact = truth["uz"].interp(depth=out.depth, x=out.x, kwargs={"fill_value": None}) / pixel
        resid = out["uz_pixels"] - exact
        out["uz_residual"] = resid.assign_attrs(attrs("pixels", "tracked minus exact displacement"))
        out["failed"] = (~(abs(resid) <= tol)).assign_attrs(
            long_name=f"tracking failed (|error| > {tol:g} pixel or no estimate)"
        )
        out.attrs["max_error_pixels"] = tol
    return out


#: A pixel grid (µm): real, finite, 1-D; empty allowed (no pixel asked).
_GRID = ArraySpec(kind="real", ndim=1, nonempty=False)


@renamed_parameters({"centre_aline": "centre_x", "aline": "x"})
@preprocess_and_wrap(
    checks={
        "values": ArraySpec(kind="real", ndim=2, finite=False, nonempty=False),
        "centre_depth": ArraySpec(kind="real", ndim=1),
        "centre_x": ArraySpec(kind="real", ndim=1),
        "depth": _GRID,
        "x": _GRID,
    }
)
def interpolate_windows(
    values: np.ndarray,
    centre_depth: np.ndarray,
    centre_x: np.ndarray,
    depth: np.ndarray,
    x: np.ndarray,
    *,
    outside: str = "linear",
) -> np.ndarray:
    """Window values interpolated bilinearly to the pixel grid ``depth`` x ``x``.

    Separable linear interpolation along depth then x, in the units of the centres (one
    window column: depth only, the same for every A-line). Beyond the outer window centres
    (``outside``): ``"linear"`` extrapolation, the ``"nearest"`` centre's value, or ``"nan"``.
    A NaN window spreads only to the pixels whose interpolation uses it.

    Parameters
    ----------
    values : array_like, shape (n_depth_windows, n_x_windows)
        One value per window.
    centre_depth, centre_x : array_like
        Window centres (increasing), in the units of the pixel coordinates.
    depth, x : array_like
        The pixel grid: values of the ``depth`` and ``x`` coordinates (µm).
    outside : {"linear", "nearest", "nan"}
        Beyond the outer centres.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(depth), len(x))``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> values = np.array([[0.0], [1.0]])  # two windows in depth, one column
    >>> speckle.interpolate_windows(values, [10.0, 20.0], [0.0], [10.0, 15.0, 20.0], [0.0])
    array([[0. ],
           [0.5],
           [1. ]])
    """
    check_choice(outside, "outside", ("linear", "nearest", "nan"))
    v, z = values, depth  # checked: real, finite grids (values: NaN allowed)
    cz, cx = (_axis(c, n) for c, n in ((centre_depth, "centre_depth"), (centre_x, "centre_x")))
    if v.shape != (cz.size, cx.size):
        raise ValueError(
            f"values must have shape (centre_depth, centre_x) = {(cz.size, cx.size)}, got {v.shape}"
        )
    out = _interp_axis(v.astype(float), cz, z, 0, outside)
    if v.shape[1] == 1:
        return np.repeat(out, len(x), axis=1)
    return _interp_axis(out, cx, x, 1, outside)


def _axis(a: np.ndarray, name: str) -> np.ndarray:
    """Window centres (finite, 1-D, checked): increasing, else ValueError."""
    if np.any(np.diff(a) <= 0):
        raise ValueError(f"{name} must be an increasing 1-D array of window centres, got {a}")
    return a


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


@renamed_parameters({"aline": "x"})
@preprocess_and_wrap(checks={"depth": _GRID, "x": _GRID})
def interpolate_displacement(
    tracked: xr.Dataset, depth: np.ndarray, x: np.ndarray, *, axial_only: bool = True
) -> xr.Dataset:
    """Tracked window displacements interpolated (and extrapolated) linearly to every pixel.

    Parameters
    ----------
    tracked : xarray.Dataset
        Window displacements ``uz`` (and ``ux``) over the window centres ``depth``/``x``.
    depth, x : array_like
        The pixel grid: values of the ``depth`` and ``x`` coordinates (µm).
    axial_only : bool
        Drop the lateral estimate (A-lines are independent in the model, so the lateral
        registration carries no sub-line information).

    Returns
    -------
    xarray.Dataset
        ``uz`` (and ``ux``) over ``(depth, x)``.

    Examples
    --------
    >>> import numpy as np
    >>> import xarray as xr
    >>> import speckle
    >>> uz = xr.DataArray([[1.0], [2.0]], dims=("depth", "x"))
    >>> tracked = xr.Dataset({"uz": uz}, coords={"depth": [10.0, 20.0], "x": [0.0]})  # windows
    >>> out = speckle.interpolate_displacement(tracked, np.array([10.0, 15.0, 20.0]), np.zeros(1))
    >>> out.uz.values[:, 0]
    array([1. , 1.5, 2. ])
    """
    out = {}
    if not isinstance(tracked, xr.Dataset) or "uz" not in tracked:
        raise TypeError(
            f"tracked must be the Dataset of speckle.track (variable 'uz'), got "
            f"{type(tracked).__name__}"
        )
    if min(tracked["uz"].shape) < 1:
        raise ValueError(f"tracked holds no window (sizes {dict(tracked.sizes)})")
    axial_only = check_bool(axial_only, "axial_only")
    names = ("uz",) if axial_only else ("uz", "ux")
    for name in names:
        vals = tracked[name].transpose(DEPTH, LATERAL).values
        grid = interpolate_windows(vals, tracked[DEPTH].values, tracked[LATERAL].values, depth, x)
        out[name] = ((DEPTH, LATERAL), grid, dict(tracked[name].attrs))
    return xr.Dataset(out, coords={DEPTH: coord(DEPTH, depth), LATERAL: coord(LATERAL, x)})
