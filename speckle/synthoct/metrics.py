"""The SynthOCT 2026 challenge's comparison of two scans, as its orchestrator computes it.

The orchestrator (``Orchestrator.py`` of ``SynthOCTChallenge/SynthOCT_Baseline``) makes the
processor's maps of both scans (:func:`speckle.synthoct_maps`), reads each PNG back (the scan,
``Struct``, and its ``OAC``, ``SC``, ``RSC`` maps) and scores reference against target:

- ``MSE`` and ``PSNR`` (``data_range=1``) of the grey levels read as floats in 0..1, and
  ``SSIM`` (scikit-image's ``structural_similarity``: 7 x 7 uniform window, sample
  covariance, ``data_range=1``);
- ``MS-SSIM`` and ``VIF`` (pixel-domain VIF) of the same images converted back to 8 bit, as the
  package ``sewar`` (``msssim``, ``vifp``) computes them: reimplemented here with scipy, equal
  to sewar 0.4.10 to 1e-12 (``tests/synthoct/test_metrics.py``). MS-SSIM: five scales of an
  11 x 11 Gaussian (sigma 1.5) "valid" SSIM with ``MAX = 255``, weights
  0.0448, 0.2856, 0.3001, 0.2363, 0.1333, contrast terms of the first four scales times the
  full SSIM of the fifth, each raised as a complex power (a negative term gives a complex
  value; its real part is kept), halving by a 2 x 2 box filter (scipy's ``uniform_filter``,
  reflected edges) and every second pixel. VIF: four scales of Gaussian windows of 17, 9, 5 and
  3 pixels (sigma = size/5), ``sigma_n**2 = 2`` grey levels squared, each coarser scale
  filtered "valid" and decimated by two;
- ``LPIPS`` (AlexNet), only where the optional packages ``lpips`` and ``torch`` and their
  network weights are installed (``pip install speckle-oct[lpips]``); NaN with a warning
  saying why otherwise.

Quirks of the official reading (``variant="official"``; each one's measured effect is in
``docs/explanation/synthoct_metrics.md``):

1. Every PNG is an RGBA grey image read with ``as_gray=True``: the luminance
   ``(0.2125 v + 0.7154 v) + 0.0721 v`` of ``v = level/255``, which is ``v`` only to an ulp.
2. For MS-SSIM and VIF it is turned back into 8 bit by truncation, ``int(255 x lum)``: 18 of
   the 256 levels (e.g. 3, 6, 12, ...) come back one lower.
3. Target scans of another shape are resized to the reference (``transform.resize``); here
   they are refused.

``variant="physical"`` scores the maps of :func:`speckle.synthoct_maps` ``variant="physical"``
(51 dB, the stated limits kept), reading the levels exactly (``level/255``, no truncation).
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import xarray as xr

from .._validate import check_choice, check_path
from ..conventions import attrs, coord
from .maps import MAP_NAMES, VARIANTS, scan_grey, synthoct_maps

__all__ = [
    "METRIC_NAMES",
    "SYNTHOCT_EXPERIMENTS",
    "SYNTHOCT_MAPS",
    "read_metrics_report",
    "synthoct_metrics",
]

#: The images the orchestrator compares: the scan itself and the processor's three maps.
SYNTHOCT_MAPS = ("Struct", *MAP_NAMES)
#: The orchestrator's metrics (its CSV columns).
METRIC_NAMES = ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF", "LPIPS")

#: The orchestrator's three comparisons (reference, target scan): each phantom's seed A against
#: seed B, and "Cross_Uniform_vs_Layers" the uniform phantom's A against the layered one's A.
SYNTHOCT_EXPERIMENTS = {
    "Exp1_Uniform": ("Exp1_Uniform_A", "Exp1_Uniform_B"),
    "Exp2_Layers": ("Exp2_Layers_A", "Exp2_Layers_B"),
    "Cross_Uniform_vs_Layers": ("Exp1_Uniform_A", "Exp2_Layers_A"),
}

_MSSSIM_WEIGHTS = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333)
_LUMA = (0.2125, 0.7154, 0.0721)  # scikit-image's rgb2gray


def _luminance_table() -> np.ndarray:
    """``rgb2gray`` of an RGBA grey level, summed left to right as on the reference machine."""
    v = np.arange(256) / 255.0
    return (v * _LUMA[0] + v * _LUMA[1]) + v * _LUMA[2]


_LUMINANCE = _luminance_table()
_TRUNCATED = (_LUMINANCE * 255).astype(np.uint8)


def _gaussian(size: int, sigma: float) -> np.ndarray:
    """Normalised 1-D Gaussian of odd ``size``: MATLAB's ``fspecial`` window is its outer square.

    (``fspecial`` zeroes weights below ``eps`` times the peak: none at these sizes, the
    smallest corner weight is 4e-3 of the peak.)
    """
    r = np.arange(size) - size // 2
    g = np.exp(-(r**2) / (2.0 * sigma**2))
    return g / g.sum()


def _valid(image: np.ndarray, window: np.ndarray) -> np.ndarray:
    """Sums weighted by the separable window ``outer(window, window)`` where it fits whole."""
    from scipy.ndimage import correlate1d

    h = window.size // 2
    rows = correlate1d(image, window, axis=0)[h : image.shape[0] - h]
    return correlate1d(rows, window, axis=1)[:, h : image.shape[1] - h]


def _moments(a: np.ndarray, b: np.ndarray, window: np.ndarray):
    """Local means squared/product and (co)variances of ``a`` and ``b``: ``valid`` windows."""
    mu_a, mu_b = _valid(a, window), _valid(b, window)
    aa, bb, ab = mu_a * mu_a, mu_b * mu_b, mu_a * mu_b
    return (
        aa,
        bb,
        ab,
        _valid(a * a, window) - aa,
        _valid(b * b, window) - bb,
        _valid(a * b, window) - ab,
    )


def _ms_ssim(a: np.ndarray, b: np.ndarray, peak: float = 255.0) -> float:
    """MS-SSIM as ``sewar.full_ref.msssim`` of two 8-bit images (module docstring)."""
    from scipy.ndimage import uniform_filter

    smallest = 11 * 2 ** (len(_MSSSIM_WEIGHTS) - 1)
    if min(a.shape) < smallest:
        warnings.warn(
            f"MS-SSIM is NaN: its fifth scale needs images of at least {smallest} pixels a side "
            f"(the 11-pixel window after four halvings); got {a.shape}",
            RuntimeWarning,
            stacklevel=3,
        )
        return float("nan")
    window = _gaussian(11, 1.5)
    c1, c2 = (0.01 * peak) ** 2, (0.03 * peak) ** 2
    a, b = a.astype(float), b.astype(float)
    ssim, cs = [], []
    for _ in _MSSSIM_WEIGHTS:
        aa, bb, ab, va, vb, cov = _moments(a, b, window)
        contrast = (2 * cov + c2) / (va + vb + c2)
        ssim.append(np.mean((2 * ab + c1) / (aa + bb + c1) * contrast))
        cs.append(np.mean(contrast))
        # sewar filters its (H, W, 1) images: the box of 2 also spans the unit third axis
        a, b = (uniform_filter(x[..., None], 2)[::2, ::2, 0] for x in (a, b))
    w = np.asarray(_MSSSIM_WEIGHTS)
    terms = np.asarray(cs[:-1], dtype=complex) ** w[:-1]
    return float((np.prod(terms) * complex(ssim[-1]) ** w[-1]).real)


def _vif(a: np.ndarray, b: np.ndarray, noise: float = 2.0) -> float:
    """Pixel-domain VIF as ``sewar.full_ref.vifp`` of two 8-bit images (module docstring)."""
    eps = 1e-10
    a, b = a.astype(float), b.astype(float)
    num = den = 0.0
    for scale in range(4):
        size = 2 ** (4 - scale) + 1
        window = _gaussian(size, size / 5.0)
        if scale:
            a, b = _valid(a, window)[::2, ::2], _valid(b, window)[::2, ::2]
        _, _, _, va, vb, cov = _moments(a, b, window)
        va, vb = np.maximum(va, 0), np.maximum(vb, 0)
        g = cov / (va + eps)
        sv = vb - g * cov
        flat = va < eps
        g[flat], sv[flat], va[flat] = 0, vb[flat], 0
        blank = vb < eps
        g[blank], sv[blank] = 0, 0
        negative = g < 0
        sv[negative], g[negative] = vb[negative], 0
        sv[sv <= eps] = eps
        num += np.sum(np.log10(1.0 + g**2 * va / (sv + noise)))
        den += np.sum(np.log10(1.0 + va / noise))
    if den == 0:  # sewar's 0/0: NaN, here with its reason
        warnings.warn(
            "VIF is NaN: the reference has no variance at any scale (a constant image carries "
            "no information to preserve)",
            RuntimeWarning,
            stacklevel=4,
        )
        return float("nan")
    return float(num / den)


_LPIPS: dict[str, object] = {}


def _lpips(a: np.ndarray, b: np.ndarray) -> float:
    """LPIPS (AlexNet) of two images in 0..1; NaN with a warning when it cannot run."""
    model = _LPIPS.get("model")
    if model is None:
        try:
            import lpips
            import torch
        except ImportError as exc:
            _LPIPS["model"] = False
            _LPIPS["why"] = (
                f"LPIPS needs the optional packages lpips and torch ({exc}); install them with "
                "`pip install speckle-oct[lpips]` (AlexNet weights are downloaded on first use)"
            )
        else:
            try:
                _LPIPS["torch"] = torch
                _LPIPS["model"] = lpips.LPIPS(net="alex", verbose=False)
            except Exception as exc:  # weights not downloadable here
                _LPIPS["model"] = False
                _LPIPS["why"] = f"LPIPS could not load its AlexNet weights: {exc}"
        model = _LPIPS["model"]
    if model is False:
        warnings.warn(f"LPIPS is NaN: {_LPIPS['why']}", RuntimeWarning, stacklevel=3)
        return float("nan")
    torch = _LPIPS["torch"]

    def tensor(x: np.ndarray):
        return (torch.from_numpy(x).float()[None, None] * 2 - 1).repeat(1, 3, 1, 1)

    with torch.no_grad():
        return float(model(tensor(a), tensor(b)).item())


def _pair(a: np.ndarray, b: np.ndarray, *, official: bool, lpips: bool) -> dict[str, float]:
    """The orchestrator's metrics of two 8-bit images (reference ``a``, target ``b``)."""
    from skimage.metrics import structural_similarity

    if official:
        fa, fb = _LUMINANCE[a], _LUMINANCE[b]
        ua, ub = _TRUNCATED[a], _TRUNCATED[b]
    else:
        fa, fb = a / 255.0, b / 255.0
        ua, ub = a, b
    mse = float(np.mean((fa - fb) ** 2))
    psnr = float(10 * np.log10(1.0 / mse)) if mse > 0 else float("inf")  # equal images
    return {
        "SSIM": float(structural_similarity(fa, fb, data_range=1.0)),
        "MS-SSIM": _ms_ssim(ua, ub),
        "PSNR": psnr,
        "MSE": mse,
        "VIF": _vif(ua, ub),
        "LPIPS": _lpips(fa, fb) if lpips else float("nan"),
    }


#: (quantity, long name) of each metric's variable.
_DESCRIPTION = {
    "SSIM": ("dimensionless", "structural similarity (scikit-image, 7x7 uniform window)"),
    "MS-SSIM": ("dimensionless", "multi-scale SSIM (sewar's msssim, 5 scales)"),
    "PSNR": ("level", "peak signal-to-noise ratio, data range 1"),
    "MSE": ("dimensionless", "mean squared difference of the grey levels / 255"),
    "VIF": ("dimensionless", "pixel-domain visual information fidelity (sewar's vifp)"),
    "LPIPS": ("dimensionless", "learned perceptual image patch similarity (AlexNet)"),
}


def synthoct_metrics(
    reference: object,
    target: object,
    *,
    variant: str = "official",
    lpips: bool = True,
) -> xr.Dataset:
    """The SynthOCT challenge's scores of ``target`` against ``reference`` (module docstring).

    Parameters
    ----------
    reference, target : str, path-like, numpy.ndarray or xarray.DataArray
        The two scans: PNG files or their uint8 grey levels ``(depth, x)``, the same shape
        (at least 21 x 21 pixels, the contrast window plus one).
    variant : {"official", "physical"}
        ``"official"``: the orchestrator's numbers, quirks included (the published table to
        its last digit). ``"physical"``: the physical maps of :func:`speckle.synthoct_maps`
        read without the truncation quirk.
    lpips : bool
        Compute LPIPS (needs the optional ``lpips``/``torch`` packages and their weights; NaN
        with a warning when they are missing). ``False``: NaN without a warning.

    Returns
    -------
    xarray.Dataset
        One variable per metric (``SSIM``, ``MS-SSIM``, ``PSNR`` in dB, ``MSE``, ``VIF``,
        ``LPIPS``) along the dim ``map`` = ``Struct`` (the scan), ``OAC``, ``SC``, ``RSC``;
        attribute ``variant``.

    Raises
    ------
    TypeError
        If a scan is not a path, array or DataArray of uint8 grey levels.
    ValueError
        If a scan is empty or not 2-D, the shapes differ, or an option is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> a = rng.integers(0, 256, (176, 200), dtype=np.uint8)
    >>> scores = synthoct_metrics(a, a, lpips=False)
    >>> [float(v) for v in scores.SSIM.values]
    [1.0, 1.0, 1.0, 1.0]
    >>> round(float(scores.VIF.sel(map="OAC")), 6)
    1.0
    """
    variant = check_choice(variant, "variant", VARIANTS)
    if not isinstance(lpips, bool | np.bool_):
        raise TypeError(f"lpips must be True or False, got {lpips!r}")
    ref, _ = scan_grey(reference, "reference")
    tar, _ = scan_grey(target, "target")
    if ref.shape != tar.shape:
        raise ValueError(
            f"target must have the reference's shape {ref.shape}; got {tar.shape} (the "
            "orchestrator would resize it; resample it yourself if that is what you want)"
        )
    if min(ref.shape) < 21:
        raise ValueError(f"reference must be at least 21 x 21 pixels; got {ref.shape}")
    maps_ref = synthoct_maps(ref, variant=variant, images=True)
    maps_tar = synthoct_maps(tar, variant=variant, images=True)
    images = {"Struct": (ref, tar)}
    images.update({k: (maps_ref[k].values, maps_tar[k].values) for k in MAP_NAMES})
    official = variant == "official"
    rows = [_pair(a, b, official=official, lpips=bool(lpips)) for a, b in images.values()]
    return xr.Dataset(
        {
            m: ("map", [row[m] for row in rows], attrs(q, long_name=name))
            for m, (q, name) in _DESCRIPTION.items()
        },
        coords={"map": coord("map", list(SYNTHOCT_MAPS))},
        attrs={"variant": variant},
    )


def read_metrics_report(path: str | os.PathLike) -> xr.Dataset:
    """Read the orchestrator's ``Final_Metrics_Report.csv`` as a Dataset ``(experiment, map)``.

    Parameters
    ----------
    path : str or path-like
        A CSV with the columns ``Experiment``, ``Map_Type`` and one per metric
        (:data:`METRIC_NAMES`; an absent metric is NaN).

    Returns
    -------
    xarray.Dataset
        One variable per metric, as :func:`synthoct_metrics`, along ``experiment`` (in the
        file's order) and ``map``.

    Raises
    ------
    ValueError
        If a column ``Experiment`` or ``Map_Type`` is missing, a row is repeated or a value
        is not a number.

    Examples
    --------
    >>> from importlib.resources import files
    >>> folder = files("speckle.data") / "synthoct"
    >>> report = read_metrics_report(folder / "Final_Metrics_Report.csv")
    >>> report.sizes["experiment"], round(float(report.SSIM[1, 3]), 4)
    (3, 0.911)
    """
    check_path(path)  # an int would be a file descriptor to close
    import csv

    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or not {"Experiment", "Map_Type"} <= set(rows[0]):
        raise ValueError(f"path {str(path)!r}: needs the columns Experiment and Map_Type")
    experiments = list(dict.fromkeys(r["Experiment"] for r in rows))
    maps = list(dict.fromkeys(r["Map_Type"] for r in rows))
    values = {m: np.full((len(experiments), len(maps)), np.nan) for m in METRIC_NAMES}
    seen = set()
    for line, r in enumerate(rows, start=2):
        key = (r["Experiment"], r["Map_Type"])
        if key in seen:
            raise ValueError(f"path {str(path)!r} line {line}: row {key} repeated")
        seen.add(key)
        i, j = experiments.index(key[0]), maps.index(key[1])
        for m in METRIC_NAMES:
            text = (r.get(m) or "").strip()
            try:
                values[m][i, j] = float(text) if text else np.nan
            except ValueError:
                raise ValueError(
                    f"path {str(path)!r} line {line}: {m} = {text!r} is not a number"
                ) from None
    return xr.Dataset(
        {
            m: (("experiment", "map"), values[m], attrs(q, long_name=name))
            for m, (q, name) in _DESCRIPTION.items()
        },
        coords={"experiment": coord("experiment", experiments), "map": coord("map", maps)},
        attrs={"source": str(path)},
    )
