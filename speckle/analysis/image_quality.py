"""Image-quality metrics against a known truth: speckle, contrast, fidelity, resolution, time.

* speckle in a uniform region: contrast ``std/mean`` of the intensity and the equivalent number
  of looks ``ENL = mean^2/var`` (1 for one look of fully developed speckle);
* contrast-to-noise between two regions on dB images, ``|m_a - m_b| / sqrt(v_a + v_b)``;
* fidelity to the speckle-free image: PSNR and SSIM (:mod:`skimage.metrics`) of dB images
  referred to the truth's mean in a reference region and clipped to a window of ``db_range``
  dB below ``db_top`` (what is displayed), ``data_range = db_range``;
* resolution: FWHM of a point target's intensity (:func:`peak_fwhm`; on an Eq. 4 image, the
  band-limited interpolation :func:`bandlimited` first) and the 10-90 % width of a step edge
  (:func:`edge_width`: an error-function fit to the line-averaged profile, ``2.563 sigma``);
* time per megapixel (:func:`time_per_megapixel`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable

import numpy as np
import scipy.optimize as opt
import scipy.special as sp

from .._deprecate import keyword_only
from .._validate import check_int, check_memory, check_real
from .._wrap import ArraySpec, preprocess_and_wrap

__all__ = [
    "EDGE_10_90",
    "bandlimited",
    "cnr",
    "contrast",
    "edge_width",
    "enl",
    "peak_fwhm",
    "psnr_db",
    "ssim_db",
    "time_per_megapixel",
    "to_db",
]

#: 10-90 % width of an error-function edge in units of its sigma: 2 * 1.2816.
EDGE_10_90 = 2 * float(sp.ndtri(0.9))


#: A real, finite, non-empty image or profile (the decorator's checks).
_REAL = ArraySpec(kind="real")


def _masked(img: np.ndarray, mask: object, name: str = "intensity", mask_name: str = "mask"):
    """The pixels of the (decorator-checked) image ``img`` selected by ``mask``."""
    a = np.asarray(img, dtype=float)
    m = np.asarray(mask)
    if m.dtype != bool:
        raise TypeError(f"{mask_name} must be a boolean array, got dtype {m.dtype}")
    if m.shape != a.shape:
        raise ValueError(f"{mask_name} shape {m.shape} differs from {name}'s {a.shape}")
    if m.sum() < 2:
        raise ValueError("mask must select at least 2 pixels")
    return a[m]


def _no_answer(func: str, why: str, value: float = np.nan) -> float:
    """``value`` (NaN: no answer) with a ``RuntimeWarning`` saying why."""
    warnings.warn(f"{func}: {why}; returning {value}", RuntimeWarning, stacklevel=3)
    return value


@preprocess_and_wrap(checks={"intensity": _REAL})
def contrast(intensity: object, mask: object) -> float:
    """Speckle contrast ``std/mean`` (ddof 0) of the intensities in ``mask``.

    NaN, with a ``RuntimeWarning``, where the mean intensity in the mask is zero.

    Examples
    --------
    >>> contrast(np.array([1.0, 3.0]), np.array([True, True]))
    0.5
    """
    v = _masked(intensity, mask)
    if v.mean() == 0:
        return _no_answer("contrast", "the mean intensity in the mask is zero (no contrast)")
    return float(v.std() / v.mean())


@preprocess_and_wrap(checks={"intensity": _REAL})
def enl(intensity: object, mask: object) -> float:
    """Equivalent number of looks ``mean^2/var`` of the intensities in ``mask``.

    ``inf``, with a ``RuntimeWarning``, for a constant non-zero region (no speckle); NaN,
    with a warning, for an all-zero one.

    Examples
    --------
    >>> enl(np.array([1.0, 3.0]), np.array([True, True]))  # mean 2, variance 1
    4.0
    """
    v = _masked(intensity, mask)
    if v.var() == 0:
        if v.mean() == 0:
            return _no_answer("enl", "the intensity in the mask is all zero (no looks)")
        return _no_answer("enl", "the intensity in the mask is constant (no speckle)", np.inf)
    return float(v.mean() ** 2 / v.var())


@preprocess_and_wrap(checks={"intensity": ArraySpec(kind="real", finite=False)})
def to_db(intensity: object, reference: float) -> np.ndarray:
    """``10 log10(I/reference)``, intensities floored at 1e-30 of the reference."""
    ref = check_real(reference, "reference", low=0, low_inclusive=False)
    return 10 * np.log10(np.maximum(np.asarray(intensity, dtype=float), 1e-30 * ref) / ref)


@preprocess_and_wrap(checks={"image_db": _REAL})
def cnr(image_db: object, mask_a: object, mask_b: object) -> float:
    """Contrast-to-noise ratio ``|m_a - m_b|/sqrt(v_a + v_b)`` of two regions of a dB image.

    Both regions constant: ``inf`` if their means differ, NaN if not (each with a
    ``RuntimeWarning``).

    Examples
    --------
    >>> img = np.array([[0.0, 2.0], [2.0, 4.0]])
    >>> cnr(img, img < 3, img > 1)  # means 4/3 and 8/3, variances 8/9 and 8/9
    1.0
    """
    a = _masked(image_db, mask_a, "image_db", "mask_a")
    b = _masked(image_db, mask_b, "image_db", "mask_b")
    if a.var() + b.var() == 0:
        if a.mean() == b.mean():
            return _no_answer("cnr", "both regions are constant and equal (no contrast, no noise)")
        return _no_answer("cnr", "both regions are constant (no noise)", np.inf)
    return float(abs(a.mean() - b.mean()) / np.sqrt(a.var() + b.var()))


def _window(db: np.ndarray, top: float, span: float) -> np.ndarray:
    return np.clip(db, top - span, top)


def _db_pair(image_db, truth_db, db_top, db_range, min_side: int = 1):
    """Both dB images checked (real, finite, same 2-D shape) and clipped to the window."""
    top = check_real(db_top, "db_top")
    span = check_real(db_range, "db_range", low=0, low_inclusive=False)
    i, t = np.asarray(image_db, dtype=float), np.asarray(truth_db, dtype=float)
    if i.ndim != 2 or min(i.shape) < min_side:
        raise ValueError(
            f"image_db and truth_db must be 2-D images of at least {min_side} x {min_side} "
            f"pixels, got shape {i.shape}"
        )
    return _window(i, top, span), _window(t, top, span), span


_PAIR = {"image_db": _REAL, "truth_db": ArraySpec(kind="real", same_as="image_db")}


@preprocess_and_wrap(checks=_PAIR)
def psnr_db(image_db: object, truth_db: object, *, db_top: float = 10.0, db_range: float = 40.0):
    """PSNR (dB) of a dB image against the truth's, both clipped to ``[top - range, top]``.

    ``db_range`` > 0 (dB) is the displayed window and the PSNR's data range; infinite when the
    clipped images are equal.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> truth = np.zeros((32, 32))
    >>> round(speckle.psnr_db(truth + 1.0, truth), 2)  # 20 log10(40 dB range / 1 dB error)
    32.04
    """
    from skimage.metrics import peak_signal_noise_ratio

    i, t, span = _db_pair(image_db, truth_db, db_top, db_range)
    with np.errstate(divide="ignore"):
        return float(peak_signal_noise_ratio(t, i, data_range=span))


@preprocess_and_wrap(checks=_PAIR)
def ssim_db(image_db: object, truth_db: object, *, db_top: float = 10.0, db_range: float = 40.0):
    """SSIM of a dB image against the truth's, both clipped to ``[top - range, top]``.

    The SSIM window is skimage's 7 x 7, or the largest odd size that fits an image smaller
    than that (at least 3 x 3 pixels).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> truth = np.linspace(-30, 10, 32 * 32).reshape(32, 32)
    >>> round(speckle.ssim_db(truth, truth), 3)
    1.0
    """
    from skimage.metrics import structural_similarity

    i, t, span = _db_pair(image_db, truth_db, db_top, db_range, min_side=3)
    side = min(7, min(i.shape))
    return float(structural_similarity(t, i, data_range=span, win_size=side - (1 - side % 2)))


@keyword_only("axis")
@preprocess_and_wrap(checks={"field": ArraySpec(kind="number")})
def bandlimited(field: object, factor: int, *, axis: int = -1) -> np.ndarray:
    """Exact interpolation of an Eq. 4 field along ``axis`` on a grid ``factor`` times finer.

    An ``N``-pixel A-scan is the trigonometric polynomial ``sum_n G_n exp(-2i pi n q/N)``,
    ``n = -(N//2) ... N-1-(N//2)``; its coefficients are the inverse DFT of the samples, and
    zero-padding them (keeping each at its own frequency ``n``) evaluates it at
    ``q = m/factor``, ``m = 0 ... factor N - 1``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> field = np.exp(-2j * np.pi * np.arange(8) / 8)
    >>> fine = speckle.bandlimited(field, 2)
    >>> fine.shape, np.allclose(fine[::2], field)
    ((16,), True)
    """
    nd = np.ndim(field)
    ax = check_int(axis, "axis", low=-max(nd, 1), high=max(nd, 1) - 1)
    f = np.moveaxis(np.asarray(field, dtype=np.complex128), ax, -1)
    k = check_int(factor, "factor", low=1)
    n = f.shape[-1]
    if n < 1:
        raise ValueError(
            f"field must hold at least 1 sample along axis {axis}, got shape {f.shape}"
        )
    check_memory(16.0 * k * f.size, "factor", "the interpolated field")
    g = np.fft.ifft(f, axis=-1)
    idx = np.arange(n) - n // 2
    big = np.zeros((*f.shape[:-1], k * n), dtype=np.complex128)
    big[..., idx % (k * n)] = g[..., idx % n]
    return np.moveaxis(np.fft.fft(big, axis=-1), -1, ax)


def _crossing(x: np.ndarray, y: np.ndarray, level: float, i: int, step: int) -> float:
    j = i
    while 0 <= j + step < y.size and y[j + step] > level:
        j += step
    k = j + step
    if not 0 <= k < y.size:
        return np.nan
    return float(x[j] + (level - y[j]) * (x[k] - x[j]) / (y[k] - y[j]))


@preprocess_and_wrap(checks={"profile": ArraySpec(kind="real", ndim=1)})
def peak_fwhm(profile: object, spacing: float = 1.0, *, background: float = 0.0) -> float:
    """FWHM of the highest peak of a profile (linear interpolation of the half-level crossings).

    The half level is ``background + (max - background)/2``; ``spacing`` is the sample step
    (µm or pixels). NaN, with a ``RuntimeWarning``, when a crossing lies outside the profile.
    ``background`` must lie below the maximum (``ValueError`` otherwise: there is no peak).

    Examples
    --------
    >>> peak_fwhm([0.0, 1.0, 2.0, 1.0, 0.0])  # half level 1 crossed at samples 1 and 3
    2.0
    """
    y = np.asarray(profile, dtype=float)
    if y.ndim != 1 or y.size < 3:
        raise ValueError(f"profile must be 1-D with at least 3 samples, got shape {y.shape}")
    dx = check_real(spacing, "spacing", low=0, low_inclusive=False)
    background = check_real(background, "background")
    i = int(np.argmax(y))
    if y[i] <= background:
        raise ValueError(
            f"background = {background:g} must be below the profile's maximum {y[i]:g} (no peak "
            "rises above it)"
        )
    level = background + (y[i] - background) / 2
    x = np.arange(y.size) * dx
    width = _crossing(x, y, level, i, 1) - _crossing(x, y, level, i, -1)
    if np.isnan(width):
        return _no_answer("peak_fwhm", "a half-level crossing lies outside the profile")
    return width


@preprocess_and_wrap(checks={"profile": ArraySpec(kind="real", ndim=1)})
def edge_width(profile: object, spacing: float = 1.0) -> float:
    """10-90 % width of a step edge: ``EDGE_10_90 * sigma`` of a fitted error-function step.

    ``profile`` is the edge profile averaged along the edge (``a + b Phi((x - x0)/sigma)``
    is fitted by least squares, starting at the steepest point). NaN, with a warning, where
    there is no edge: a flat profile, a fit that fails or leaves the width undetermined.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from scipy.special import ndtr
    >>> x = np.arange(-20.0, 21.0)
    >>> round(speckle.edge_width(ndtr(x / 3.0)), 2)  # 2 * 1.2816 * sigma for sigma = 3
    7.69
    """
    y = np.asarray(profile, dtype=float)
    if y.ndim != 1 or y.size < 5:
        raise ValueError(f"profile must be 1-D with at least 5 samples, got shape {y.shape}")
    dx = check_real(spacing, "spacing", low=0, low_inclusive=False)
    x = np.arange(y.size) * dx

    def model(x, a, b, x0, s):
        return a + b * sp.ndtr((x - x0) / s)

    def jac(x, a, b, x0, s):
        u = (x - x0) / s
        g = b * np.exp(-0.5 * u * u) / np.sqrt(2 * np.pi) / s
        return np.stack([np.ones_like(x), sp.ndtr(u), -g, -g * u], axis=-1)

    lo, hi = y[: y.size // 4].mean(), y[-(y.size // 4) :].mean()
    x0 = x[int(np.argmax(np.abs(np.gradient(y))))]
    if np.ptp(y) == 0:
        warnings.warn("edge_width: the profile is flat (no edge); returning NaN", stacklevel=2)
        return np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", opt.OptimizeWarning)  # checked below
        try:
            p, cov = opt.curve_fit(model, x, y, p0=[lo, hi - lo, x0, dx], jac=jac, maxfev=5000)
        except RuntimeError:
            p, cov = None, None
    if p is None or not np.isfinite(cov[3, 3]):
        warnings.warn(
            "edge_width: the step fit failed or left its width undetermined (no edge); "
            "returning NaN",
            stacklevel=2,
        )
        return np.nan
    return float(EDGE_10_90 * abs(p[3]))


def time_per_megapixel(func: Callable[[], object], n_pixels: int, *, repeat: int = 1) -> float:
    """Best wall time (s) of ``func()`` over ``repeat`` calls, per million pixels processed."""
    n = check_int(n_pixels, "n_pixels", low=1)
    r = check_int(repeat, "repeat", low=1)
    best = np.inf
    for _ in range(r):
        t = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t)
    return float(best * 1e6 / n)
