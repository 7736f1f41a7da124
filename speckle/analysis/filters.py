"""Digital speckle filters, each on linear or log (dB) intensity, with checked parameters.

=============  ===================================================  ==============================
filter         implementation                                       parameters (allowed range)
=============  ===================================================  ==============================
``median``     :func:`scipy.ndimage.median_filter`                  ``size`` odd int in [3, 31]
``nlm``        :func:`skimage.restoration.denoise_nl_means`         ``h`` (0, 10] (in units of the
                                                                    estimated noise sigma),
                                                                    ``patch_size`` [3, 15],
                                                                    ``patch_distance`` [1, 21]
``tv``         :func:`skimage.restoration.denoise_tv_chambolle`     ``weight`` (0, 10]
``wavelet``    :func:`skimage.restoration.denoise_wavelet`          ``sigma_scale`` (0, 10] (times
               (PyWavelets, BayesShrink, soft)                      the estimated sigma),
                                                                    ``wavelet`` db1-db8/sym2-sym8
``bilateral``  :func:`skimage.restoration.denoise_bilateral`        ``sigma_color`` (0, 1],
                                                                    ``sigma_spatial`` (0, 20]
``lee``        written here (local statistics)                      ``size`` odd int in [3, 31],
                                                                    ``looks`` (0, 1000]
``kuan``       written here                                         as ``lee``
``frost``      written here (exponential kernel)                    ``size`` odd int in [3, 31],
                                                                    ``damping`` (0, 100]
``bm3d``       optional: the ``bm3d`` package (licence: non-        ``sigma_scale`` (0, 10]
               commercial use only; not installed by default)
=============  ===================================================  ==============================

The skimage filters work on the data rescaled to [0, 1] (min-max) and back; ``domain="log"``
filters ``10 log10 I`` and returns ``10^(D/10)``, so every filter returns intensities.

Lee, Kuan and Frost use the local mean ``m`` and variance ``v`` of the intensity over a
``size`` x ``size`` window and the speckle contrast ``C_u = 1/sqrt(looks)`` of the input:
local contrast ``C_I^2 = v/m^2``; Lee: ``m + k (I - m)``, ``k = max(0, 1 - C_u^2/C_I^2)``;
Kuan: ``k = max(0, (1 - C_u^2/C_I^2)/(1 + C_u^2))``; Frost: weights
``exp(-damping C_I^2 |r|)`` over the window (``|r|`` in pixels), normalised. On log data ``looks``
has no meaning; they then use the local variance against the global one of a uniform area
(the noise variance of log-speckle, 5.57^2 dB^2 for one look).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import scipy.ndimage as ndi

from .._validate import check_bool, check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap

__all__ = ["DOMAINS", "FILTERS", "despeckle", "filter_available", "frost", "kuan", "lee"]

#: Data on which a filter works.
DOMAINS = ("linear", "log")
#: Std of ``10 log10 I`` of fully developed speckle (one look): 10/ln(10) * pi/sqrt(6) dB.
LOG_SPECKLE_STD_DB = 10 / np.log(10) * np.pi / np.sqrt(6)


def _odd(value: object, name: str) -> int:
    v = check_int(value, name, low=3, high=31)
    if v % 2 == 0:
        raise ValueError(f"{name} must be an odd integer in [3, 31], got {v}")
    return v


#: A 2-D real finite image of at least 2 x 2 pixels (the decorator's checks).
_IMAGE = ArraySpec(kind="real", ndim=2, min_shape=(2, 2))


def _image(img: np.ndarray, log: object) -> tuple[np.ndarray, bool]:
    """The decorator-checked image of the local-statistics filters as floats (non-negative
    intensities unless ``log``) and ``log`` as a bool (the front door's checks)."""
    log = check_bool(log, "log")
    a = np.asarray(img, dtype=float)
    if not log and np.any(a < 0):
        raise ValueError("img must hold non-negative intensities (or pass log=True for dB data)")
    return a, log


def _looks(value: object) -> float:
    return check_real(value, "looks", low=0, high=1000, low_inclusive=False)


def _local(img: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    m = ndi.uniform_filter(img, size, mode="reflect")
    v = np.maximum(ndi.uniform_filter(img * img, size, mode="reflect") - m * m, 0.0)
    return m, v


def _noise_ratio(img: np.ndarray, m: np.ndarray, v: np.ndarray, looks: float, log: bool):
    """``C_u^2 / C_I^2`` (linear) or ``sigma_u^2 / v`` (log data)."""
    tiny = np.finfo(float).tiny
    if log:
        return (LOG_SPECKLE_STD_DB**2 / looks) / np.maximum(v, tiny)
    cu2 = 1.0 / looks
    ci2 = v / np.maximum(m * m, tiny)
    return cu2 / np.maximum(ci2, tiny)


@preprocess_and_wrap(checks={"img": _IMAGE})
def lee(img: np.ndarray, *, size: int = 7, looks: float = 1.0, log: bool = False) -> np.ndarray:
    """Lee filter: ``m + k (I - m)``, ``k = max(0, 1 - C_u^2/C_I^2)`` (see module docstring).

    ``size``: odd window side in [3, 31] pixels; ``looks`` in (0, 1000]; ``img`` 2-D, finite,
    non-negative unless ``log`` (the checks of :func:`despeckle`).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> img = np.random.default_rng(0).exponential(size=(64, 64))
    >>> out = speckle.lee(img, size=7)
    >>> out.shape, bool(out.std() < img.std())
    ((64, 64), True)
    """
    a, log = _image(img, log)
    size, looks = _odd(size, "size"), _looks(looks)
    m, v = _local(a, size)
    k = np.clip(1.0 - _noise_ratio(a, m, v, looks, log), 0.0, 1.0)
    return m + k * (a - m)


@preprocess_and_wrap(checks={"img": _IMAGE})
def kuan(img: np.ndarray, *, size: int = 7, looks: float = 1.0, log: bool = False) -> np.ndarray:
    """Kuan filter: ``k = max(0, (1 - C_u^2/C_I^2)/(1 + C_u^2))`` (linear data); parameters
    and checks as :func:`lee`.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> img = np.random.default_rng(0).exponential(size=(64, 64))
    >>> out = speckle.kuan(img, size=7)
    >>> out.shape, bool(out.std() < img.std())
    ((64, 64), True)
    """
    a, log = _image(img, log)
    size, looks = _odd(size, "size"), _looks(looks)
    m, v = _local(a, size)
    cu2 = (LOG_SPECKLE_STD_DB**2 if log else 1.0) / looks
    denom = 1.0 if log else 1.0 + cu2
    k = np.clip((1.0 - _noise_ratio(a, m, v, looks, log)) / denom, 0.0, 1.0)
    return m + k * (a - m)


@preprocess_and_wrap(checks={"img": _IMAGE})
def frost(img: np.ndarray, *, size: int = 7, damping: float = 2.0, log: bool = False) -> np.ndarray:
    """Frost filter: weights ``exp(-damping C_I^2 |r|)`` over a ``size`` x ``size`` window.

    ``size``: odd in [3, 31]; ``damping`` in (0, 100]; ``img`` as :func:`lee`.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> img = np.random.default_rng(0).exponential(size=(64, 64))
    >>> out = speckle.frost(img, size=7)
    >>> out.shape, bool(out.std() < img.std())
    ((64, 64), True)
    """
    a, log = _image(img, log)
    size = _odd(size, "size")
    damping = check_real(damping, "damping", low=0, high=100, low_inclusive=False)
    m, v = _local(a, size)
    tiny = np.finfo(float).tiny
    ci2 = v / (LOG_SPECKLE_STD_DB**2) if log else v / np.maximum(m * m, tiny)
    h = size // 2
    pad = np.pad(a, h, mode="reflect")
    win = np.lib.stride_tricks.sliding_window_view(pad, (size, size))  # (Z, X, s, s)
    dz, dx = np.mgrid[-h : h + 1, -h : h + 1]
    r = np.hypot(dz, dx)
    w = np.exp(-damping * ci2[..., None, None] * r)
    return np.sum(w * win, axis=(-2, -1)) / np.sum(w, axis=(-2, -1))


def _unit(a: np.ndarray) -> tuple[np.ndarray, float, float]:
    lo, hi = float(a.min()), float(a.max())
    span = hi - lo if hi > lo else 1.0
    return (a - lo) / span, lo, span


def _skimage(func: Callable[[np.ndarray], np.ndarray]) -> Callable[[np.ndarray], np.ndarray]:
    def run(a: np.ndarray) -> np.ndarray:
        if np.ptp(a) == 0:
            return a.copy()  # a constant image is every filter's fixed point
        u, lo, span = _unit(a)
        return lo + span * func(u)

    return run


def _sigma(u: np.ndarray) -> float:
    """Noise sigma of ``u`` (skimage's wavelet estimate); 0 for a flat image."""
    from skimage.restoration import estimate_sigma

    if np.ptp(u) == 0:
        return 0.0
    return float(estimate_sigma(u))


def _nlm(a, *, h=0.8, patch_size=5, patch_distance=6, log=False):
    from skimage.restoration import denoise_nl_means

    def f(u):
        s = _sigma(u)
        return denoise_nl_means(
            u,
            h=h * s,
            sigma=s,
            patch_size=patch_size,
            patch_distance=patch_distance,
            fast_mode=True,
        )

    return _skimage(f)(a)


def _tv(a, *, weight=0.1, log=False):
    from skimage.restoration import denoise_tv_chambolle

    return _skimage(lambda u: denoise_tv_chambolle(u, weight=weight))(a)


def _wavelet(a, *, sigma_scale=1.0, wavelet="db2", log=False):
    from skimage.restoration import denoise_wavelet

    def f(u):
        s = _sigma(u) * sigma_scale
        return denoise_wavelet(
            u, sigma=s, wavelet=wavelet, mode="soft", method="BayesShrink", rescale_sigma=True
        )

    return _skimage(f)(a)


def _bilateral(a, *, sigma_color=0.1, sigma_spatial=2.0, log=False):
    from skimage.restoration import denoise_bilateral

    return _skimage(
        lambda u: denoise_bilateral(
            u, sigma_color=sigma_color, sigma_spatial=sigma_spatial, mode="reflect"
        )
    )(a)


def _median(a, *, size=5, log=False):
    return ndi.median_filter(a, size=size, mode="reflect")


def _bm3d(a, *, sigma_scale=1.0, log=False):
    import bm3d  # optional extra: non-commercial licence

    def f(u):
        return bm3d.bm3d(u, sigma_psd=_sigma(u) * sigma_scale)

    return _skimage(f)(a)


_WAVELETS = tuple(f"db{i}" for i in range(1, 9)) + tuple(f"sym{i}" for i in range(2, 9))


def _pos(high):
    return lambda v, n: check_real(v, n, low=0, high=high, low_inclusive=False)


#: Filter name -> (function, {parameter: checker(value, name)}).
FILTERS: dict[str, tuple[Callable, dict[str, Callable]]] = {
    "median": (_median, {"size": _odd}),
    "nlm": (
        _nlm,
        {
            "h": _pos(10),
            "patch_size": lambda v, n: check_int(v, n, low=3, high=15),
            "patch_distance": lambda v, n: check_int(v, n, low=1, high=21),
        },
    ),
    "tv": (_tv, {"weight": _pos(10)}),
    "wavelet": (
        _wavelet,
        {"sigma_scale": _pos(10), "wavelet": lambda v, n: check_choice(v, n, _WAVELETS)},
    ),
    "bilateral": (_bilateral, {"sigma_color": _pos(1), "sigma_spatial": _pos(20)}),
    "lee": (lee, {"size": _odd, "looks": _pos(1000)}),
    "kuan": (kuan, {"size": _odd, "looks": _pos(1000)}),
    "frost": (frost, {"size": _odd, "damping": _pos(100)}),
    "bm3d": (_bm3d, {"sigma_scale": _pos(10)}),
}


def filter_available(name: str) -> bool:
    """Whether filter ``name`` can run here (``bm3d`` needs the optional ``bm3d`` package).

    Examples
    --------
    >>> filter_available("median")
    True
    """
    check_choice(name, "filter name", FILTERS)
    if name != "bm3d":
        return True
    try:
        import bm3d  # noqa: F401
    except ImportError:
        return False
    return True


def check_filter(name: str, params: Mapping | None = None, domain: str = "linear") -> dict:
    """Checked parameters of filter ``name`` (``ValueError`` naming the bad one)."""
    check_choice(name, "filter name", FILTERS)
    check_choice(domain, "domain", DOMAINS)
    allowed = FILTERS[name][1]
    if params is not None and not isinstance(params, Mapping):
        raise TypeError(
            f"params must be a mapping of filter parameters (or None), got {type(params).__name__}"
        )
    params = dict(params or {})
    unknown = set(params) - set(allowed)
    if unknown:
        raise ValueError(
            f"unknown parameter(s) {sorted(unknown)} for filter {name!r}; allowed: "
            f"{sorted(allowed)}"
        )
    return {k: allowed[k](v, k) for k, v in params.items()}


@preprocess_and_wrap(
    checks={"intensity": _IMAGE},
    wrap_like="intensity",
    attrs_from={"filter": "name", "domain": "domain"},
)
def despeckle(
    intensity: object, name: str, params: Mapping | None = None, *, domain: str = "linear"
) -> object:
    """Filter an intensity image with filter ``name``.

    Parameters
    ----------
    intensity : array_like or xarray.DataArray, 2-D
        Non-negative intensities ``|A|^2`` (depth, lateral).
    name : str
        One of :data:`FILTERS` (``bm3d`` only if installed).
    params : mapping, optional
        Filter parameters (module table); missing ones take the defaults.
    domain : {"linear", "log"}
        Filter the intensity, or ``10 log10 I`` (then converted back).

    Returns
    -------
    numpy.ndarray or xarray.DataArray
        Filtered intensities, same shape (and coords).

    Raises
    ------
    ValueError
        Unknown filter, domain or parameter, a parameter out of range, a negative or
        non-finite image, or an image that is not 2-D.
    ImportError
        ``bm3d`` without the optional package.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> img = np.random.default_rng(0).exponential(size=(64, 64))
    >>> out = speckle.despeckle(img, "lee", {"size": 7})
    >>> out.shape, bool(out.std() < img.std())
    ((64, 64), True)
    """
    p = check_filter(name, params, domain)
    if name == "bm3d" and not filter_available("bm3d"):
        raise ImportError(
            "filter 'bm3d' needs the optional package: pip install bm3d "
            "(licence: non-commercial use only)"
        )
    a = np.asarray(intensity, dtype=float)
    if np.any(a < 0):
        raise ValueError("intensity must be non-negative")
    log = domain == "log"
    if a.max() == 0:  # no signal: every filter keeps an all-zero image (no log of it exists)
        return np.zeros_like(a)
    floor = a.max() * 1e-10  # 100 dB below the maximum
    data = 10 * np.log10(np.maximum(a, floor)) if log else a
    run = FILTERS[name][0]
    out = getattr(run, "__wrapped__", run)(data, log=log, **p)  # the image was checked once
    return 10 ** (out / 10) if log else np.maximum(out, 0.0)  # labelled like intensity
