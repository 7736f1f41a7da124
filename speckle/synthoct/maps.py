"""The SynthOCT 2026 challenge's maps of a scan: OAC, SC and RSC, as its processor makes them.

The challenge's processor (``Part3_Processor.py`` of ``SynthOCTChallenge/SynthOCT_Baseline``)
turns an 8-bit logarithmic scan into three maps, which its orchestrator then compares between
two scans (:func:`speckle.synthoct_metrics`):

- **OAC**, the depth-resolved (optical) attenuation coefficient of the linearised intensity
  ``I``: ``mu_i = I_i / (2 h (sum_{j >= i} I_j - I_i / 2))`` (µm⁻¹, ``h`` the pixel size);
- **SC**, the speckle contrast ``std/mean`` of ``I`` in a 20 x 20 pixel sliding window;
- **RSC**, the same contrast of the OAC map ("refined" speckle contrast).

``variant="official"`` reproduces the processor to the bit, quirks included (measured on the
four published scans: the 12 map PNGs equal, every pixel); ``variant="physical"`` keeps the
estimators but removes what contradicts the scan. The quirks (each one's measured effect is in
``docs/explanation/synthoct_metrics.md``):

1. The linearisation assumes grey levels ``0..255`` span **40 dB** (``I = 10**(4 g/255)``),
   whereas the scanner writes **51 dB**: every intensity is raised to the power 40/51. On a
   smooth exponential decay the OAC is 40/51 of the 51 dB one (tested); on speckle the power
   also narrows the intensity distribution (the published scans: mean OAC 0.87 and 0.72 of
   the physical one, SC median 0.77-0.82 against 0.94-1.06). Physical: 51 dB.
2. The arithmetic is single precision (``plt.imread`` gives float32); the reference machine's
   ``10**x`` in float32 is correctly rounded (numpy's SIMD one on Linux is not, for 49 of the
   256 grey levels, which moved 4 of the 1.6 million map pixels by one or two grey levels):
   the linear intensity is therefore taken from a table of correctly rounded values.
3. The pixel size is the constant 6 µm whatever the scan (the challenge's INI has 6 µm).
4. The OAC's sum includes half the current pixel and nothing below the image, so the last row
   is ``1/(2 h x 1/2) = 1/h`` whatever the tissue; the OAC PNG is scaled from the map's minimum
   to its 99th percentile, clipped.
5. The contrast window is 20 px (even: it spans ``i-10 .. i+9``, reflected at the edges); a
   10-pixel border is then replaced by the nearest inner value (edge padding).
6. SC and RSC are clipped to the "standard limits" 0.5..5 and then saved with
   ``matplotlib.pyplot.imsave`` without limits, which stretches each PNG again from its own
   minimum to its own maximum: the stated limits do not hold, and two scans' maps are on
   different grey scales. Physical: the limits hold (no second stretch).
7. The PNG's grey level is matplotlib's ``gray`` colormap: ``floor(256 v)`` (``v = 1`` -> 255)
   through a table in which 24 of the 256 levels are one lower (``int(255 * (i/255))``), so
   the levels 33, 37, ... never occur.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from .._validate import check_choice, check_int, check_real
from ..conventions import attrs, coord, spacing

__all__ = [
    "MAP_NAMES",
    "OFFICIAL_DYNAMIC_RANGE",
    "SCAN_DYNAMIC_RANGE",
    "SYNTHOCT_PIXEL_SIZE",
    "synthoct_maps",
]

#: The maps of the processor, in the orchestrator's order (after the structural image).
MAP_NAMES = ("OAC", "SC", "RSC")
#: Dynamic range (dB) the processor's linearisation assumes for grey levels 0..255.
OFFICIAL_DYNAMIC_RANGE = 40.0
#: Dynamic range (dB) of the scanner's PNG (the challenge's README: 51 dB).
SCAN_DYNAMIC_RANGE = 51.0
#: Pixel size (µm) the processor assumes (its constant ``HPX``), also the challenge's A-line pitch.
SYNTHOCT_PIXEL_SIZE = 6.0
#: Contrast window (pixels) of the processor.
WINDOW = 20
#: The processor's "standard limits" of the SC and RSC maps.
CONTRAST_LIMITS = (0.5, 5.0)
#: Percentile of the OAC map at which its PNG saturates.
OAC_PERCENTILE = 99
VARIANTS = ("official", "physical")
_EPS = 1e-10  # the processor's guard against division by zero (OAC, contrast, scaling)


def _png_grey(path: Path) -> np.ndarray:
    """8-bit grey levels of a PNG file (grey, grey+alpha, or RGB(A) with equal channels)."""
    from PIL import Image

    with Image.open(path) as im:
        mode = im.mode
        if mode not in ("L", "LA", "RGB", "RGBA"):
            raise TypeError(
                f"scan {str(path)!r} must be an 8-bit grey PNG (modes L, LA, RGB, RGBA); "
                f"got mode {mode!r}"
            )
        a = np.asarray(im)
    if a.ndim == 3:
        if mode in ("LA", "RGBA") and np.any(a[..., -1] != 255):
            raise ValueError(f"scan {str(path)!r} has transparent pixels (alpha below 255)")
        if mode in ("RGB", "RGBA") and not (
            np.array_equal(a[..., 0], a[..., 1]) and np.array_equal(a[..., 0], a[..., 2])
        ):
            raise ValueError(f"scan {str(path)!r} is a colour image: R, G and B differ")
        a = a[..., 0]
    return np.ascontiguousarray(a)


def scan_grey(scan: object, name: str = "scan") -> tuple[np.ndarray, xr.DataArray | None]:
    """Grey levels (uint8, ``(depth, x)``) of a scan given as a PNG path, array or DataArray.

    Returns the levels and the DataArray (for its coordinates) or ``None``.
    """
    da = None
    if isinstance(scan, str | os.PathLike):
        path = Path(scan)
        if not path.is_file():
            raise ValueError(f"{name}: no such file {str(path)!r}")
        grey = _png_grey(path)
    elif isinstance(scan, xr.DataArray):
        da = scan
        grey = np.asarray(scan.values)
    elif isinstance(scan, np.ndarray):
        grey = scan
    else:
        raise TypeError(
            f"{name} must be a PNG path, an 8-bit numpy array or an xarray.DataArray; "
            f"got {type(scan).__name__}"
        )
    if grey.dtype != np.uint8:
        raise TypeError(f"{name} must hold 8-bit grey levels (dtype uint8); got {grey.dtype}")
    if grey.ndim != 2:
        raise ValueError(f"{name} must be 2-D (depth, x); got shape {grey.shape}")
    if grey.size == 0:
        raise ValueError(f"{name} is empty (shape {grey.shape})")
    return grey, da


def _linear_table(dynamic_range: float, official: bool) -> np.ndarray:
    """Linear intensity of each grey level 0..255 (float32 as the processor, or float64)."""
    levels = np.arange(256)
    if not official:
        return 10.0 ** (dynamic_range / 10.0 * levels / 255.0)
    # plt.imread: level/255 in float32; the processor averages the three equal channels
    v = np.divide(levels, 255, dtype=np.float32)
    v = np.stack([v, v, v], axis=-1).mean(axis=-1)
    exponent = v * np.float32(dynamic_range / 10.0)  # float32 product, as the processor's
    # 10**x rounded once to float32 (the reference machine's float32 power is exact)
    return (10.0 ** exponent.astype(np.float64)).astype(np.float32)


def _oac(intensity: np.ndarray, pixel_size: float) -> np.ndarray:
    """Depth-resolved attenuation (1/µm): ``I_i / (2 h (sum_{j>=i} I_j - I_i/2))``, per column."""
    below = np.cumsum(intensity[::-1], axis=0)[::-1]
    return intensity / (2 * pixel_size * ((below - 0.5 * intensity) + _EPS))


def _contrast(data: np.ndarray, window: int) -> np.ndarray:
    """``std/mean`` in a ``window``-pixel square (reflected edges), border edge-padded."""
    from scipy.ndimage import uniform_filter

    mean = uniform_filter(data, size=window, mode="reflect")
    mean_sq = uniform_filter(data * data, size=window, mode="reflect")
    var = np.maximum(mean_sq - mean * mean, 0)
    sc = np.sqrt(var) / (mean + _EPS)
    b = window // 2
    if b == 0:
        return sc
    return np.pad(sc[b:-b, b:-b], b, mode="edge")


def _gray_lut() -> np.ndarray:
    """matplotlib's ``gray`` colormap as bytes: ``int(255 * lut_i)`` of its 256 float entries."""
    lut = (255.0 * np.linspace(0.0, 1.0, 256)) / 255.0
    return (lut * 255).astype(np.uint8)


_LUT = _gray_lut()


def _grey_levels(values: np.ndarray, low: float, high: float, *, stretch: bool) -> np.ndarray:
    """The processor's ``save_map``: clip to ``low..high`` and write through the gray colormap.

    ``stretch``: ``plt.imsave`` (no limits) maps the clipped values' own min..max to 0..1 again.
    """
    v = np.clip((values - low) / (high - low + _EPS), 0, 1)
    if stretch:
        lo, hi = np.float64(v.min()), np.float64(v.max())
        if lo == hi:
            v = np.zeros_like(v)
        else:  # matplotlib's Normalize, in place on the map's dtype
            v = v.copy()
            v -= lo
            v /= hi - lo
    scaled = v * v.dtype.type(256)
    scaled[scaled == 256] = 255
    return _LUT[np.clip(scaled.astype(np.int64), 0, 255)]


def synthoct_maps(
    scan: object,
    *,
    variant: str = "official",
    images: bool = False,
    pixel_size: float | None = None,
    window: int = WINDOW,
    dynamic_range: float | None = None,
) -> xr.Dataset:
    """The SynthOCT challenge's maps OAC, SC and RSC of an 8-bit scan (module docstring).

    Parameters
    ----------
    scan : str, path-like, numpy.ndarray or xarray.DataArray
        The scan: a PNG file (grey, or RGBA with equal channels as the scanner writes them) or
        its grey levels, uint8 ``(depth, x)``, 0 = the floor, 255 = the brightest pixel.
    variant : {"official", "physical"}
        ``"official"``: the processor's maps, bit for bit (40 dB linearisation, float32,
        6 µm pixels, PNG scaling re-stretched by ``imsave``). ``"physical"``: the scan's
        51 dB linearisation, double precision, the pixel size of the scan's ``depth``
        coordinate (a DataArray) and, with ``images``, the stated limits kept.
    images : bool
        ``False``: the maps' values (OAC in µm⁻¹, SC and RSC dimensionless). ``True``: their
        8-bit grey levels as the processor writes them to ``*_OAC.png``, ``*_SC.png`` and
        ``*_RSC.png`` (the orchestrator's input).
    pixel_size : float, optional
        Axial pixel size in µm (> 0). Default: 6 µm (the processor's constant) for
        ``"official"``; the ``depth`` coordinate's step of a DataArray, else 6 µm, for
        ``"physical"``.
    window : int
        Side of the contrast window in pixels (2..min(shape) - 1); the processor's is 20.
    dynamic_range : float, optional
        Dynamic range in dB (> 0) that grey levels 0..255 span: default 40 (``"official"``,
        the processor's assumption) or 51 (``"physical"``, the scanner's).

    Returns
    -------
    xarray.Dataset
        Variables ``OAC``, ``SC``, ``RSC`` on ``(depth, x)`` (coordinates in µm: those of a
        DataArray scan, else ``depth = i h`` and ``x`` centred with pitch 6 µm); attributes
        ``variant``, ``dynamic_range_db``, ``window_px``, ``pixel_size_um``.

    Raises
    ------
    TypeError
        If ``scan`` is not a path, array or DataArray of uint8 levels.
    ValueError
        If ``scan`` is empty, not 2-D, smaller than ``window + 1`` in a dimension, or an
        option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> scan = np.random.default_rng(0).integers(0, 256, (64, 48), dtype=np.uint8)
    >>> maps = synthoct_maps(scan)
    >>> maps.OAC.attrs["units"], maps.SC.dims
    ('1/um', ('depth', 'x'))
    >>> synthoct_maps(scan, images=True).RSC.dtype
    dtype('uint8')
    """
    variant = check_choice(variant, "variant", VARIANTS)
    if not isinstance(images, bool | np.bool_):
        raise TypeError(f"images must be True or False, got {images!r}")
    grey, da = scan_grey(scan)
    if min(grey.shape) < 3:
        raise ValueError(
            f"scan must be at least 3 x 3 pixels (a window >= 2 needs window + 1 pixels a "
            f"side); got {grey.shape}"
        )
    official = variant == "official"
    window = check_int(window, "window", low=2, high=min(grey.shape) - 1)
    if dynamic_range is None:
        dynamic_range = OFFICIAL_DYNAMIC_RANGE if official else SCAN_DYNAMIC_RANGE
    dynamic_range = check_real(dynamic_range, "dynamic_range", low=0, low_inclusive=False)
    if pixel_size is None:
        pixel_size = SYNTHOCT_PIXEL_SIZE
        if not official and da is not None and "depth" in da.coords and da.sizes["depth"] > 1:
            pixel_size = spacing(da, "depth")
    pixel_size = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)

    intensity = _linear_table(dynamic_range, official)[grey]
    oac = _oac(intensity, pixel_size)
    sc = _contrast(intensity, window)
    rsc = _contrast(oac, window)
    names = {"OAC": oac, "SC": sc, "RSC": rsc}
    if images:
        low, high = CONTRAST_LIMITS
        limits = {
            "OAC": (np.min(oac), np.percentile(oac, OAC_PERCENTILE)),
            "SC": (low, high),
            "RSC": (low, high),
        }
        names = {k: _grey_levels(v, *limits[k], stretch=official) for k, v in names.items()}
        described = {
            k: attrs("dimensionless", long_name=f"grey level of the {k} map's PNG (0-255)")
            for k in names
        }
    else:
        described = {
            "OAC": attrs("attenuation", long_name="depth-resolved attenuation coefficient (OAC)"),
            "SC": attrs("contrast", long_name="speckle contrast std(I)/<I> of the intensity"),
            "RSC": attrs("contrast", long_name="refined speckle contrast: contrast of the OAC"),
        }
    if da is not None and {"depth", "x"} <= set(da.coords) and da.dims == ("depth", "x"):
        coords = {"depth": da["depth"], "x": da["x"]}
    else:
        n_depth, n_x = grey.shape
        x = (np.arange(n_x) - n_x / 2) * SYNTHOCT_PIXEL_SIZE
        coords = {
            "depth": coord("depth", pixel_size * np.arange(n_depth)),
            "x": coord("x", x, long_name="lateral position of the A-line"),
        }
    return xr.Dataset(
        {k: (("depth", "x"), v, described[k]) for k, v in names.items()},
        coords=coords,
        attrs={
            "variant": variant,
            "dynamic_range_db": dynamic_range,
            "window_px": window,
            "pixel_size_um": pixel_size,
        },
    )
