"""Measured OCT B-scans: loading, and speckle statistics that survive an unknown log mapping.

Commercial OCT engines output log-compressed, quantised images ``D = g*ln(I) + c`` with an
undocumented gain ``g > 0`` and offset ``c``. Statistics of ``D`` that do not depend on ``g`` and
``c`` are those of the *standardised* log intensity ``(D - mean D)/std D``: its histogram, its
skewness and its excess kurtosis. For fully developed speckle ``I = <I> E`` with ``E ~ Exp(1)``,
``Y = ln E`` has cumulants ``kappa_n = psi^(n-1)(1)``: mean ``-gamma``, variance ``pi^2/6``,
``kappa_3 = psi''(1) = -2 zeta(3)``, ``kappa_4 = psi'''(1) = pi^4/15``, so

    skewness        = -2 zeta(3) / (pi^2/6)^(3/2) = -1.13955
    excess kurtosis = (pi^4/15) / (pi^2/6)^2      = 36/15 = 2.4

and the standardised density is ``s*exp(s*z - gamma - exp(s*z - gamma))`` with
``s = pi/sqrt(6)`` (a reflected Gumbel law). Log-amplitude data (``20 log10 |A|``) give the same
standardised statistics.

Departure model (an intensity floor)
------------------------------------
The measured PDMS sample deviates from these values in its left tail: dark speckle pixels are
not as dark as an exponential law predicts. A constant floor ``b`` (in units of the mean speckle
intensity) added before the log, ``Y = ln(E + b)``, compresses exactly that tail. It has
``f_Y(y) = e^y exp(-(e^y - b))`` for ``y > ln b``; its moments are computed by quadrature.
:func:`fit_floor` solves ``skewness(b) = measured skewness`` for ``b`` and predicts the excess
kurtosis, an independent check of the explanation.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import xarray as xr
from scipy import integrate, optimize, special, stats

from .._deprecate import renamed_parameters
from .._validate import as_finite_array, check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, canonical_dims, canonical_keys, coord

__all__ = [
    "SCALES",
    "compare_measured",
    "fit_floor",
    "load_measured",
    "log_intensity",
    "log_speckle_moments",
    "log_statistics",
    "measured_shape",
    "roi_slices",
    "standardise",
    "standardised_log_pdf",
]

#: ``"linear"``: values proportional to intensity (or amplitude); ``"log"``: log-compressed.
SCALES = ("linear", "log")
#: Fully developed speckle: skewness and excess kurtosis of ln(I).
GUMBEL_SKEWNESS = float(-2.0 * special.zeta(3.0) / (np.pi**2 / 6.0) ** 1.5)
GUMBEL_EXCESS_KURTOSIS = 2.4
_BLOCKS = "from A-line blocks"
#: A measured image: a real ``(depth, x)`` DataArray (``x`` read from ``aline``, warning), its
#: labels kept (its ``kind`` or ``scale`` attribute says how to take its log).
_MEASURED = ArraySpec(
    kind="real", dims=("depth", "x"), min_shape=(2, 2), labelled=True, keep_labels=True
)


def _read(path: str | os.PathLike, *, mmap: bool = False) -> np.ndarray:
    """The 2-D array of a ``.npy`` or image file (memory-mapped ``.npy`` if ``mmap``)."""
    if not isinstance(path, str | os.PathLike):
        raise TypeError(f"path must be a str or path-like, got {type(path).__name__} {path!r}")
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"measured image not found: {p}")
    if p.suffix.lower() == ".npy":
        raw = np.load(p, allow_pickle=False, mmap_mode="r" if mmap else None)
    else:
        import matplotlib.image

        raw = matplotlib.image.imread(p)
        if raw.ndim == 3:
            raw = raw[..., :3].mean(axis=-1)
    if raw.ndim != 2:
        raise ValueError(f"measured image must be 2-D (depth, x), got shape {raw.shape}")
    return raw


def measured_shape(path: str | os.PathLike) -> tuple[int, int]:
    """Shape ``(depth, x)`` of a measured image file, without loading a ``.npy`` file.

    Raises
    ------
    FileNotFoundError
        If ``path`` is not a file.
    ValueError
        If the file does not hold a 2-D image.
    """
    shape = _read(path, mmap=True).shape
    return int(shape[0]), int(shape[1])


def roi_slices(roi: Mapping | None, shape: tuple[int, int]) -> dict[str, slice]:
    """Slices ``{"depth": ..., "x": ...}`` of a region of interest in an image of ``shape``.

    Parameters
    ----------
    roi : mapping, optional
        ``{"depth": [start, stop], "x": [start, stop]}`` in pixel indices (half-open, either
        key optional, ``None`` bounds allowed; the retired key ``aline`` is read as
        ``x``, warning).
    shape : (int, int)
        Image shape ``(depth, x)``.

    Raises
    ------
    TypeError
        If ``roi`` is not a mapping or a bound not an integer.
    ValueError
        Naming ``roi[key]``: unknown key, bounds beyond the image (never clipped), start not
        below stop, or fewer than 2 x 2 pixels left.
    """
    sl = {"depth": slice(None), "x": slice(None)}
    if roi is not None and not isinstance(roi, Mapping):
        raise TypeError(
            "roi must be a mapping {'depth': [start, stop], 'x': [start, stop]} of pixel "
            f"indices, got {type(roi).__name__} {roi!r}"
        )
    roi = canonical_keys(roi, "roi")
    for key, value in (roi or {}).items():
        if key not in sl:
            raise ValueError(f"roi keys must be 'depth' and/or 'x', got {key!r}")
        if value is None:
            continue
        if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
            raise ValueError(f"roi[{key!r}] must be [start, stop], got {value!r}")
        size = shape[0 if key == "depth" else 1]
        lo, hi = (
            None if v is None else check_int(v, f"roi[{key!r}]", low=0, high=size) for v in value
        )
        if lo is not None and hi is not None and hi <= lo:
            raise ValueError(f"roi[{key!r}] must have start < stop, got {value!r}")
        sl[key] = slice(lo, hi)
    rows = range(shape[0])[sl["depth"]]
    cols = range(shape[1])[sl["x"]]
    if len(rows) < 2 or len(cols) < 2:
        raise ValueError(f"roi {roi!r} leaves fewer than 2x2 pixels of a {tuple(shape)} image")
    return sl


@renamed_parameters({"aline_pitch": "pitch"})
def load_measured(
    path: str | os.PathLike,
    *,
    scale: str = "log",
    roi: dict | None = None,
    pixel_size: float | None = None,
    pitch: float | None = None,
) -> xr.DataArray:
    """Load a measured B-scan (``.npy`` or an image file) as a labelled ``(depth, x)`` array.

    Retired (issue 32): the one loader of measured images is :func:`speckle.io.load_image`
    (``kind="log"`` for ``scale="log"``, ``dims=("depth", "x")``, then ``.isel`` for a region);
    this one warns (``FutureWarning``) and keeps working for a release, for PNG files and images
    of unknown pixel size.

    Parameters
    ----------
    path : str or path-like
        A 2-D ``.npy`` array ordered ``[depth, x]`` (depth increasing with row index), or an
        image file readable by :func:`matplotlib.image.imread` (PNG; RGB is averaged to grey).
    scale : {"linear", "log"}
        ``"log"``: log-compressed data with unknown gain/offset; ``"linear"``: values
        proportional to intensity or amplitude.
    roi : dict, optional
        Region of interest ``{"depth": [start, stop], "x": [start, stop]}`` in pixel indices
        (half-open, either key optional, ``null`` bounds allowed). Bounds beyond the image
        (above its number of rows or columns) are refused, never clipped.
    pixel_size : float, optional
        Axial pixel size in µm (> 0); the ``depth`` coordinate is then in µm, else in pixels.
    pitch : float, optional
        Lateral A-line spacing in µm (> 0); the ``x`` coordinate is then in µm.

    Returns
    -------
    xarray.DataArray
        Float64 values, dims ``(depth, x)``, integer coordinates ``row`` and ``column``
        (indices in the file). Attributes: ``source`` (path), ``scale``, ``roi``, ``dtype`` of
        the file, and ``clip_low``/``clip_high`` (the dtype's limits for integer data).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "scan.npy")
    >>> np.save(path, np.random.default_rng(0).exponential(size=(16, 8)))
    >>> img = speckle.load_measured(path, scale="linear", pixel_size=5.75)
    >>> img.dims, img.shape
    (('depth', 'x'), (16, 8))
    """
    warnings.warn(
        "load_measured is retired: read measured images with speckle.io.load_image(path, "
        "kind=..., dims=('depth', 'x'), pixel_size=..., pitch=...) and select a region with "
        ".isel; load_measured will be removed in the next release",
        FutureWarning,
        stacklevel=3,
    )
    check_choice(scale, "scale", SCALES)
    raw = _read(path)
    data = as_finite_array(raw, "measured image")
    sl = roi_slices(roi, data.shape)
    rows = np.arange(data.shape[0])[sl["depth"]]
    cols = np.arange(data.shape[1])[sl["x"]]
    meta = {
        "source": str(path),
        "scale": scale,
        "roi": repr(roi or {}),
        "dtype": str(raw.dtype),
        **attrs("log_data" if scale == "log" else "dimensionless", "measured OCT signal"),
    }
    if np.issubdtype(raw.dtype, np.integer):
        info = np.iinfo(raw.dtype)
        meta.update(clip_low=int(info.min), clip_high=int(info.max))
    depth = (
        rows * check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
        if pixel_size is not None
        else rows
    )
    x = cols * check_real(pitch, "pitch", low=0, low_inclusive=False) if pitch is not None else cols
    return xr.DataArray(
        data[sl["depth"], sl["x"]],
        dims=("depth", "x"),
        coords={
            "depth": _axis_coord("depth", depth, pixel_size),
            "x": _axis_coord("x", x, pitch),
            "row": ("depth", rows),
            "column": ("x", cols),
        },
        name="measured",
        attrs=meta,
    )


def _axis_coord(dim: str, values: np.ndarray, step: float | None) -> tuple:
    """Coordinate ``dim`` in µm when its step is known, else in pixels."""
    if step:
        return coord(dim, values)
    return coord("pixels", values, f"{dim} in pixels", dims=dim)


def _scale_of(image: object) -> str:
    """``"log"`` or ``"linear"``: attribute ``scale`` (:func:`load_measured`) or ``kind``
    (:func:`speckle.io.load_image`: ``log``; ``amplitude``/``intensity`` are linear)."""
    if isinstance(image, xr.DataArray):
        if "scale" in image.attrs:
            return str(image.attrs["scale"])
        kind = image.attrs.get("kind")
        if kind == "complex":
            raise TypeError("image is complex: measure its amplitude, abs(image)")
        if kind in ("log", "amplitude", "intensity"):
            return "log" if kind == "log" else "linear"
    raise TypeError(
        "image must be a DataArray from speckle.io.load_image (attribute 'kind') or "
        "load_measured (attribute 'scale')"
    )


def log_intensity(image: xr.DataArray) -> xr.DataArray:
    """Log intensity up to an unknown gain and offset.

    Log-compressed data are returned as they are; linear data ``v`` (amplitude or intensity)
    give ``ln v`` (zeros are refused: the log of an exact zero is undefined; crop them out with
    the ROI). Images from :func:`speckle.io.load_image` (``kind``) and the retired
    :func:`load_measured` (``scale``) are accepted, ``(depth, x)`` (``x`` warns).
    """
    scale = _scale_of(image)
    image = canonical_dims(image).assign_attrs(scale=scale)
    if scale == "log":
        return image
    if np.any(image.values <= 0):
        raise ValueError("linear-scale image must be > 0 everywhere to take its log")
    long_name = image.attrs.get("long_name", "log intensity")
    return np.log(image).assign_attrs(
        {**image.attrs, **attrs("dimensionless", long_name)}, scale="log"
    )


def _floor_moment(k: int, floor: float) -> float:
    """``E[Y^k]`` for ``Y = ln(E + floor)``, ``E ~ Exp(1)``: quadrature over ``y > ln(floor)``."""

    def f(y):
        return y**k * np.exp(y - (np.exp(y) - floor))

    lo, hi = np.log(floor), np.log(floor + 60.0)  # P(E > 60) = 1e-26: negligible
    mid = max(lo, 0.0)
    return integrate.quad(f, lo, mid, limit=200)[0] + integrate.quad(f, mid, hi, limit=200)[0]


def log_speckle_moments(floor: float = 0.0) -> dict[str, float]:
    """Mean, variance, skewness and excess kurtosis of ``ln(E + floor)``, ``E ~ Exp(1)``.

    Parameters
    ----------
    floor : float
        Intensity floor in units of the mean speckle intensity (>= 0); 0 is fully developed
        speckle (closed form, see module docstring).
    """
    b = check_real(floor, "floor", low=0)
    if b == 0.0:
        var = np.pi**2 / 6.0
        return {
            "mean": -float(np.euler_gamma),
            "variance": float(var),
            "skewness": GUMBEL_SKEWNESS,
            "excess_kurtosis": GUMBEL_EXCESS_KURTOSIS,
        }
    m1, m2, m3, m4 = (_floor_moment(k, b) for k in (1, 2, 3, 4))
    var = m2 - m1**2
    c3 = m3 - 3 * m1 * m2 + 2 * m1**3
    c4 = m4 - 4 * m1 * m3 + 6 * m1**2 * m2 - 3 * m1**4
    return {
        "mean": m1,
        "variance": var,
        "skewness": c3 / var**1.5,
        "excess_kurtosis": c4 / var**2 - 3.0,
    }


def standardised_log_pdf(z: object, floor: float = 0.0) -> object:
    """Density of the standardised log intensity ``(Y - E Y)/std Y``, ``Y = ln(E + floor)``.

    ``z`` may be a number, array or DataArray. For ``floor = 0``:
    ``s exp(s z - gamma - exp(s z - gamma))`` with ``s = pi/sqrt(6)``.
    """
    mom = log_speckle_moments(floor)
    mu, sd = mom["mean"], np.sqrt(mom["variance"])
    b = float(floor)

    def pdf(v):
        y = mu + sd * np.asarray(v, dtype=float)
        ey = np.exp(y)
        out = sd * ey * np.exp(-(ey - b))
        return np.where(ey > b, out, 0.0)

    return xr.apply_ufunc(pdf, z)


def _checked(image: object) -> xr.DataArray:
    """A measured image (:func:`speckle.io.load_image` or :func:`load_measured`): real,
    finite, at least 8 pixels, refused naming ``image`` before any statistic."""
    _scale_of(image)  # a DataArray with attribute 'kind' or 'scale' (TypeError otherwise)
    as_finite_array(image.values, "image")
    if image.size < 8:
        raise ValueError(f"image must hold at least 8 pixels, got sizes {dict(image.sizes)}")
    return image


def _sample(values: object) -> np.ndarray:
    data = values.values if isinstance(values, xr.DataArray) else values
    x = as_finite_array(data, "values").ravel()
    if x.size < 8:
        raise ValueError(f"need at least 8 pixels, got {x.size}")
    return x


def log_statistics(image: xr.DataArray, *, n_blocks: int = 16) -> xr.Dataset:
    """Gain- and offset-free statistics of the log intensity of an image, with standard errors.

    Standard errors come from the spread of the statistic over ``n_blocks`` contiguous blocks of
    A-lines (speckle is correlated over a few A-lines, so blocks are nearly independent while
    single pixels are not): ``SE = std(block values)/sqrt(n_blocks)``.

    Returns
    -------
    xarray.Dataset
        Scalars ``n``, ``mean``, ``std`` (in the image's units), ``skewness``,
        ``excess_kurtosis``, their ``*_se``, ``clipped_fraction`` (pixels at the dtype limits),
        ``quantisation_variance_fraction`` (``(1/12)/var``: Sheppard's correction for unit
        steps) and, with theory for fully developed speckle, ``skewness_theory`` and
        ``excess_kurtosis_theory``.
    """
    return _log_statistics(image, log_intensity(_checked(image)), n_blocks)


def _log_statistics(image: xr.DataArray, d: xr.DataArray, n_blocks: int) -> xr.Dataset:
    """:func:`log_statistics` of a checked ``image`` whose log intensity is ``d``."""
    if "x" not in d.dims:
        raise TypeError("image must have an 'x' dim")
    nb = check_int(n_blocks, "n_blocks", low=2, high=d.sizes["x"])
    x = _sample(d)
    blocks = np.array_split(np.arange(d.sizes["x"]), nb)
    per_block = np.array(
        [[stats.skew(v), stats.kurtosis(v)] for v in (d.isel(x=b).values.ravel() for b in blocks)]
    )
    se = per_block.std(axis=0, ddof=1) / np.sqrt(nb)
    lo, hi = image.attrs.get("clip_low"), image.attrs.get("clip_high")
    raw = image.values
    clipped = float(np.mean((raw == lo) | (raw == hi))) if lo is not None else 0.0
    var = float(x.var())
    out = {
        "n": ((), x.size, {"long_name": "number of pixels"}),
        "mean": ((), float(x.mean()), {"long_name": "mean of log data"}),
        "std": ((), float(np.sqrt(var)), {"long_name": "std of log data"}),
        "skewness": ((), float(stats.skew(x)), attrs("dimensionless", "skewness of log data")),
        "skewness_se": (
            (),
            float(se[0]),
            attrs("dimensionless", "standard error of the skewness", note=_BLOCKS),
        ),
        "excess_kurtosis": (
            (),
            float(stats.kurtosis(x)),
            attrs("dimensionless", "excess kurtosis of log data"),
        ),
        "excess_kurtosis_se": (
            (),
            float(se[1]),
            attrs("dimensionless", "standard error of the excess kurtosis", note=_BLOCKS),
        ),
        "skewness_theory": ((), GUMBEL_SKEWNESS, {"long_name": "fully developed speckle"}),
        "excess_kurtosis_theory": (
            (),
            GUMBEL_EXCESS_KURTOSIS,
            {"long_name": "fully developed speckle"},
        ),
        "clipped_fraction": (
            (),
            clipped,
            attrs("dimensionless", "fraction of pixels at a clip level"),
        ),
        "quantisation_variance_fraction": (
            (),
            (1.0 / 12.0) / var if var > 0 else np.nan,
            attrs("dimensionless", "quantisation variance 1/12 over the variance"),
        ),
    }
    return xr.Dataset(out, attrs={"n_blocks": nb})


def fit_floor(image: xr.DataArray) -> xr.Dataset:
    """Fit the intensity-floor model ``D = g ln(E + b) + c`` by matching the skewness.

    Solves ``skewness(ln(E + b)) = skewness(D)`` for ``b`` (the skewness of ``ln(E + b)``
    increases monotonically from -1.1395 at ``b = 0``), then ``g = std D / std ln(E + b)`` and
    ``c = mean D - g mean ln(E + b)``. The excess kurtosis is then a prediction, not a fit.

    Returns
    -------
    xarray.Dataset
        ``floor`` (b, in units of the mean speckle intensity; ``floor_db = 10 log10 b``),
        ``gain`` g, ``offset`` c (image units per natural-log unit), ``excess_kurtosis_model``
        and ``skewness_model``. ``floor`` is 0 when the data are at least as skewed as fully
        developed speckle.
    """
    return _fit_floor(log_intensity(_checked(image)))


def _fit_floor(d: xr.DataArray) -> xr.Dataset:
    """:func:`fit_floor` of the log intensity ``d`` of a checked image."""
    x = _sample(d)
    target = float(stats.skew(x))
    if target <= GUMBEL_SKEWNESS:
        b = 0.0
    else:

        def gap(log_b):
            return log_speckle_moments(float(np.exp(log_b)))["skewness"] - target

        hi = 5.0
        if gap(hi) < 0:
            raise ValueError(f"skewness {target:.3f} is too high for the floor model")
        b = float(np.exp(optimize.brentq(gap, -30.0, hi, xtol=1e-6)))
    mom = log_speckle_moments(b)
    g = float(x.std() / np.sqrt(mom["variance"]))
    return xr.Dataset(
        {
            "floor": (
                (),
                b,
                attrs("mean_intensity", "intensity floor b in ln(I/<I> + b)"),
            ),
            "floor_db": (
                (),
                10 * np.log10(b) if b > 0 else -np.inf,
                attrs("level", "intensity floor 10 log10 b"),
            ),
            "gain": ((), g, attrs("data", "g in D = g ln(I) + c")),
            "offset": (
                (),
                float(x.mean() - g * mom["mean"]),
                attrs("data", "c in D = g ln(I) + c"),
            ),
            "skewness_model": (
                (),
                mom["skewness"],
                attrs("dimensionless", "skewness of the floor model"),
            ),
            "excess_kurtosis_model": (
                (),
                mom["excess_kurtosis"],
                attrs("dimensionless", "excess kurtosis of the floor model"),
            ),
        },
        attrs={"method": "skewness matched; excess kurtosis predicted"},
    )


def standardise(image: xr.DataArray) -> xr.DataArray:
    """``(D - mean D)/std D`` of the log intensity (gain- and offset-free)."""
    d = log_intensity(image)
    return ((d - d.mean()) / d.std()).assign_attrs(
        attrs("dimensionless", "standardised log intensity")
    )


@preprocess_and_wrap(checks={"image": _MEASURED})
def compare_measured(image: xr.DataArray, *, n_blocks: int = 16) -> xr.Dataset:
    """All measured-versus-model numbers for one image ROI.

    Combines :func:`log_statistics`, :func:`fit_floor`, the depth trend (least-squares slope of
    row means, per pixel, and the fraction of variance it explains), the moments after removing
    each depth row's mean (``*_detrended``), and the Kolmogorov-Smirnov distance of the
    standardised data to the fully developed law (``ks_pure``) and to the fitted floor law
    (``ks_floor``). Variables are prefixed by their origin; attributes say what was compared.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> import speckle
    >>> path = pathlib.Path(tempfile.mkdtemp(), "scan.npy")
    >>> np.save(path, np.random.default_rng(0).exponential(size=(64, 64)))
    >>> out = speckle.compare_measured(speckle.load_measured(path, scale="linear"))
    >>> sorted(out.data_vars)[:2]
    ['clipped_fraction', 'depth_slope']
    """
    scale = _scale_of(image)  # image: checked by the decorator (real, finite, (depth, x))
    if image.size < 8:
        raise ValueError(f"image must hold at least 8 pixels, got sizes {dict(image.sizes)}")
    d = log_intensity(image)
    st = _log_statistics(image, d, n_blocks)
    fl = _fit_floor(d)
    rows = d.mean("x").values
    t = np.arange(rows.size, dtype=float)
    slope, intercept = np.polyfit(t, rows, 1)
    trend_var = float(np.var(slope * t + intercept))
    detr = (d - d.mean("x")).values.ravel()
    z = np.sort(((d - d.mean()) / d.std()).values.ravel())  # standardise(image)
    ecdf_hi = np.arange(1, z.size + 1) / z.size
    ecdf_lo = np.arange(z.size) / z.size

    def ks(floor):
        cdf = _standardised_log_cdf(z, floor)
        return float(max(np.max(ecdf_hi - cdf), np.max(cdf - ecdf_lo)))

    extra = {
        "depth_slope": (
            (),
            float(slope),
            attrs("data_slope", "least-squares slope of row means"),
        ),
        "depth_trend_variance_fraction": (
            (),
            trend_var / float(st["std"]) ** 2,
            attrs("dimensionless", "fraction of the variance explained by the depth trend"),
        ),
        "skewness_detrended": (
            (),
            float(stats.skew(detr)),
            attrs("dimensionless", "skewness after removing each row's mean"),
        ),
        "excess_kurtosis_detrended": (
            (),
            float(stats.kurtosis(detr)),
            attrs("dimensionless", "excess kurtosis after removing each row's mean"),
        ),
        "ks_pure": ((), ks(0.0), attrs("dimensionless", "KS distance to ln Exp(1)")),
        "ks_floor": (
            (),
            ks(float(fl["floor"])),
            attrs("dimensionless", "KS distance to ln(Exp(1) + floor)"),
        ),
    }
    lo = image.attrs.get("clip_low")
    if lo is not None and scale == "log":
        # pure law fitted by moments: g = std/sqrt(pi^2/6), c = mean + gamma g; pixels whose
        # ln(I/<I>) lies below the lowest level (lo + 1/2) would be clipped to lo
        g_pure = float(st["std"]) / np.sqrt(np.pi**2 / 6.0)
        c_pure = float(st["mean"]) + np.euler_gamma * g_pure
        p_low = -np.expm1(-np.exp((lo + 0.5 - c_pure) / g_pure))
        extra["low_clip_count"] = (
            (),
            int(np.sum(d.values == lo)),
            attrs("count", "pixels at the low clip"),
        )
        extra["low_clip_count_pure"] = (
            (),
            float(d.size * p_low),
            attrs("count", "expected pixels at the low clip for ln Exp(1)"),
        )
    out = xr.merge([st, fl, xr.Dataset(extra)])
    out.attrs = {
        "compared": "standardised log-intensity histogram, skewness and excess kurtosis "
        "(independent of the unknown log gain and offset)",
        "source": image.attrs.get("source", ""),
        "roi": image.attrs.get("roi", ""),
        "scale": scale,
        "n_blocks": int(n_blocks),
    }
    return out


def _standardised_log_cdf(z: np.ndarray, floor: float) -> np.ndarray:
    """CDF of the standardised ``ln(E + floor)``: ``1 - exp(-(e^y - floor))`` for e^y > floor."""
    mom = log_speckle_moments(floor)
    y = mom["mean"] + np.sqrt(mom["variance"]) * z
    return np.clip(-np.expm1(-(np.exp(y) - floor)), 0.0, 1.0)
