"""Fit a SynthOCT phantom to a measured OCT image (issue 34, "On real tissue").

A measured B-scan (:func:`speckle.load_image`) is not a SynthOCT scan: its log compression has
an unknown gain and offset, its floor is the detection noise, not a 51 dB window under the
brightest pixel, and its pixel size, pitch and beam are the device's. :func:`equivalent_system`
maps it onto the scanner's terms, stating each choice:

* **geometry**: ``n_pixels`` the fitted rows ``rows``, ``pixel_size`` and the pitch from the
  image's coordinates (``x_max = n_lines x pitch``); the beam radius ``r = w0/sqrt(2)`` from the
  twin's waist (:func:`speckle.fit_system` on the same rows) unless ``beam_radius`` is given;
* **log intensity**: ``ln I = (D - c)/g`` with the twin's gain ``g`` and offset ``c`` (the
  skewness of the log data, :func:`speckle.analysis.measured.fit_floor`) for ``kind="log"``;
  ``ln I`` itself for linear data;
* **the window**: its bottom (level 0) at the noise floor, the mean ``ln I`` of the
  signal-free rows ``noise_rows``, its top 51 dB above (or, if the image spans more than
  51 dB above its noise, the top at the brightest pixel, as the scanner puts it, and the
  bottom above the noise). A pixel at or below the bottom is clipped (as the scanner clips
  below its window), so :func:`speckle.fit_phantom` leaves out the rows where more than 10 %
  of the pixels are (signal less than ~7 dB above the noise's mean ``ln I``; unless each
  block's mean is far above the floor, as a sparse layer's is) and its fitted
  ``window_top`` places the phantom's field on the measured scale;
* **the noise**: complex Gaussian noise of the measured mean power (``<|n|^2> = exp(<ln I_n>
  + gamma)``, Euler's gamma) added to the fitted phantom's field (:meth:`EquivalentSystem.scan`),
  so that its scan has the measured floor. Not to count it twice, the fit sees the signal
  alone (``denoise``): circular Gaussian speckle plus circular Gaussian noise is exponential
  in intensity with mean ``s + n``, so a row's mean ``ln I`` is ``ln(s + n) - gamma`` and
  shifting the row by ``ln(1 - n/(s + n))`` (``s + n`` from the row's mean) gives the
  signal's row, of the same shape; rows with ``s + n <= n`` are clipped. Exact for developed
  speckle; a measured image whose log statistics are not Gumbel (a floor, multiple
  scattering) keeps part of the bias;
* **density**: ``per_cell`` kurtosis-equivalent scatterers per pixel per pitch (default 2, at
  which speckle is within 3 % of fully developed in ``var ln I``): the measured image does not
  identify the density (its log gain is fitted assuming developed speckle), so the phantom's
  ``n_scatterers`` is a stated choice.

:func:`real_tissue_phantom` is the study: the fit, the fitted phantom's scans (several seeds)
beside the measured one, the challenge's maps of both, their metrics against the floor of the
fitted phantom's own re-scans, and the measured limits of the scanner (depth profile residuals,
``var ln I``, speckle grain, lateral heterogeneity).
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import xarray as xr

from ..._validate import check_real
from ...conventions import attrs, coord
from ...synthoct import _scan
from ...synthoct.files import ScannerConfig
from ._fit import GAP, PhantomFit, fit_phantom
from ._slab import slab_constants

__all__ = ["EquivalentSystem", "equivalent_system", "real_tissue_phantom"]

_NEPER_DB = 10.0 / math.log(10.0)  # dB per neper of intensity
_STEP = _scan.DYNAMIC_RANGE / _scan.LEVELS  # dB per 8-bit level
#: Lateral blocks of the measured row means' jackknife (limits).
BLOCKS = 16


def _range(value, name: str, n: int, least: int) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in value)
    except (TypeError, ValueError):
        raise TypeError(
            f"{name} must be a (start, stop) pair of row indices, got {value!r}"
        ) from None
    if not (0 <= a < b <= n and b - a >= least):
        raise ValueError(
            f"{name} must be a half-open row range [start, stop) within 0..{n} holding at "
            f"least {least} rows, got {value!r}"
        )
    return a, b


def _log_image(image: xr.DataArray) -> np.ndarray:
    kind = image.attrs.get("kind")
    values = np.asarray(image.values)
    if kind in ("complex", "amplitude"):
        return np.log(np.maximum(np.abs(values) ** 2, np.finfo(float).tiny))
    if kind == "intensity":
        return np.log(np.maximum(values, np.finfo(float).tiny))
    return values.astype(np.float64)  # log data: (D - c)/g applied by the caller


@dataclasses.dataclass(frozen=True)
class EquivalentSystem:
    """The SynthOCT scanner equivalent to a measured image (:func:`equivalent_system`).

    Attributes
    ----------
    config : ScannerConfig
        The scanner's configuration (fitted rows, lines, pitch, beam radius, scatterers).
    rows : tuple of int
        The measured rows ``[start, stop)`` the configuration covers.
    gain, offset : float
        ``D = g ln I + c`` of log data (1 and 0 for linear data).
    noise_log : float
        Mean ``ln I`` of the signal-free rows, in ``ln I`` of the data.
    window_top_log : float
        ``ln I`` of the 51 dB window's top: the noise floor plus 51 dB, or the brightest pixel
        of the fitted rows if that is higher (the window's bottom is then above the noise).
    denoise : bool
        Shift each row's ``ln I`` by ``ln(1 - <N>/<S + N>)`` before the fit (module docstring).
    kind : str
        The image's kind (``load_image``'s).
    waist : float
        The twin's fitted waist ``w0`` (µm; NaN when ``beam_radius`` was given).

    Examples
    --------
    >>> import speckle
    >>> from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
    >>> image = speckle.load_image(sample_path("pdms"), kind="log", dims=("depth", "x"),
    ...                            pixel_size=SAMPLE_PIXEL_SIZE, pitch=SAMPLE_PITCH["pdms"])
    >>> system = speckle.equivalent_system(image, (90, 290), noise_rows=(5, 40), beam_radius=8.0)
    >>> type(system).__name__, system.rows, system.kind
    ('EquivalentSystem', (90, 290), 'log')
    """

    config: ScannerConfig
    rows: tuple[int, int]
    gain: float
    offset: float
    noise_log: float
    kind: str
    waist: float

    window_top_log: float
    denoise: bool = True

    def scan_levels(self, image: xr.DataArray) -> xr.DataArray:
        """The measured rows of ``image`` as an 8-bit scan in the system's 51 dB window."""
        if not isinstance(image, xr.DataArray) or set(image.dims) != {"depth", "x"}:
            raise TypeError("image must be a (depth, x) DataArray as speckle.load_image returns")
        image = image.transpose("depth", "x")
        n_rows = self.config.n_pixels
        a = self.rows[0]
        if image.sizes["depth"] < a + n_rows or image.sizes["x"] != self.config.n_lines:
            raise ValueError(
                f"image has shape {image.shape}; the system expects rows {self.rows} of "
                f"{self.config.n_lines} lines"
            )
        li = _log_image(image.isel(depth=slice(a, a + n_rows)))
        if self.kind == "log":
            li = (li - self.offset) / self.gain
        if self.denoise:
            # S + N of circular Gaussian speckle and noise is exponential of mean s + n, so a
            # row's mean ln I is ln(s + n) - gamma; ln(1 - n/(s + n)) takes it to ln s - gamma
            total = np.exp(li.mean(axis=1, keepdims=True) + np.euler_gamma)
            frac = 1.0 - math.exp(self.noise_log + np.euler_gamma) / total
            with np.errstate(divide="ignore"):
                li = li + np.where(frac > 0, np.log(np.maximum(frac, 0.0)), -np.inf)
        levels = _window_levels(li - self.window_top_log)
        return _labelled(levels, self.config)

    def scan(self, fit: PhantomFit, seed: int) -> xr.DataArray:
        """``fit``'s phantom drawn with ``seed``, scanned, the measured noise added, and
        mapped to 8 bits in the measured window (the field placed by ``fit``'s
        ``window_top``)."""
        from ...synthoct.scanner import synthoct_scan

        field = synthoct_scan(fit.phantom(seed), self.config, field=True).values
        top_abs = float(fit.layers.attrs["window_top"]) / _NEPER_DB  # ln I of the top, absolute
        noise = math.exp(top_abs + self.noise_log - self.window_top_log + np.euler_gamma)
        rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(1,)))
        field = field + math.sqrt(noise / 2) * (
            rng.standard_normal(field.shape) + 1j * rng.standard_normal(field.shape)
        )
        with np.errstate(divide="ignore"):
            li = np.log(np.abs(field) ** 2)
        return _labelled(_window_levels(li - top_abs), self.config)


def _window_levels(rel: np.ndarray) -> np.ndarray:
    """8-bit levels of ``ln I`` relative to the window's top (as ``_scan.to_levels``)."""
    scaled = np.floor((rel * _NEPER_DB + _scan.DYNAMIC_RANGE) / _STEP)
    return np.clip(scaled, 0, _scan.LEVELS - 1).astype(np.uint8)


def _labelled(levels: np.ndarray, cfg: ScannerConfig) -> xr.DataArray:
    return xr.DataArray(
        levels,
        dims=("depth", "x"),
        coords={
            "depth": coord("depth", np.arange(cfg.n_pixels) * cfg.pixel_size),
            "x": coord("x", cfg.line_positions),
        },
        name="scan",
        attrs=attrs("dimensionless", "8-bit logarithmic OCT scan (51 dB)"),
    )


def equivalent_system(
    image: xr.DataArray,
    rows: tuple[int, int],
    *,
    noise_rows: tuple[int, int],
    beam_radius: float | None = None,
    per_cell: float = 2.0,
    wavelength: float = 1.3,
    denoise: bool = True,
) -> EquivalentSystem:
    """The SynthOCT scanner equivalent to a measured image (module docstring).

    Parameters
    ----------
    image : xarray.DataArray
        A measured B-scan ``(depth, x)`` from :func:`speckle.load_image` (coordinates in µm).
    rows : (int, int)
        Half-open pixel rows ``[start, stop)`` of the tissue to fit (below its surface; at
        least 32 rows).
    noise_rows : (int, int)
        Half-open signal-free rows (air above the sample): the noise floor (at least 4 rows).
    beam_radius : float, optional
        ``r`` of the scanner's weight ``exp(-d^2/r^2)`` in µm (> 0). Default: the twin's waist
        (:func:`speckle.fit_system` on ``rows``) over ``sqrt(2)``.
    per_cell : float
        Kurtosis-equivalent scatterers per pixel per pitch of the phantom (0.1..50).
    wavelength : float
        Central wavelength in µm (> 0); only the phases depend on it.
    denoise : bool
        Remove the noise's share of each row's mean before the fit (module docstring), so that
        the noise added to the fitted phantom's scans is not counted twice.

    Returns
    -------
    EquivalentSystem
        ``.config`` (a :class:`speckle.ScannerConfig`), ``.scan_levels(image)`` (the measured
        rows in the 51 dB window), ``.scan(fit, seed)``; pass it as ``config`` to
        :func:`speckle.fit_phantom` with the image.

    Raises
    ------
    TypeError, ValueError
        If ``image`` is not a ``(depth, x)`` DataArray with ``kind`` and µm coordinates, or a
        range or option is out of bounds.

    Examples
    --------
    >>> import speckle
    >>> from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
    >>> image = speckle.load_image(sample_path("pdms"), kind="log", dims=("depth", "x"),
    ...                            pixel_size=SAMPLE_PIXEL_SIZE, pitch=SAMPLE_PITCH["pdms"])
    >>> system = speckle.equivalent_system(image, (90, 290), noise_rows=(5, 40))
    >>> system.config.n_pixels, system.config.n_lines, round(system.config.pixel_size, 2)
    (200, 512, 5.75)
    """
    from ...analysis.measured import fit_floor
    from ..twin.fit import fit_system

    if not isinstance(image, xr.DataArray) or set(image.dims) != {"depth", "x"}:
        raise TypeError(
            "image must be a (depth, x) DataArray as speckle.load_image returns, got "
            f"{type(image).__name__}"
        )
    kind = image.attrs.get("kind")
    if kind not in ("complex", "amplitude", "intensity", "log"):
        raise ValueError(f"image must carry load_image's 'kind' attribute, got {kind!r}")
    image = image.transpose("depth", "x")
    nz, nx = image.shape
    if nz < 2 or nx < 2:
        raise ValueError(f"image must have at least 2 x 2 pixels (depth, x), got {image.shape}")
    if np.iscomplexobj(image.values) and kind != "complex":
        raise TypeError(f"image of kind {kind!r} must be real, got complex values")
    if not np.isfinite(image.values).all():
        raise ValueError("image holds NaN or inf: give a measured image of finite values")
    check_real(wavelength, "wavelength", low=0.0, low_inclusive=False)
    a, b = _range(rows, "rows", nz, 32)
    na, nb = _range(noise_rows, "noise_rows", nz, 4)
    if not isinstance(denoise, bool):
        raise TypeError(f"denoise must be True or False, got {denoise!r}")
    if isinstance(per_cell, bool) or not isinstance(per_cell, (int, float)):
        raise TypeError(f"per_cell must be a real number, got {per_cell!r}")
    if not 0.1 <= per_cell <= 50:
        raise ValueError(
            f"per_cell must be in 0.1..50 scatterers per pixel per pitch, got {per_cell}"
        )
    dz = float(image.depth[1] - image.depth[0])
    pitch = float(image.x[1] - image.x[0])
    if not (dz > 0 and pitch > 0):
        raise ValueError("image's depth and x coordinates must increase (µm)")
    if beam_radius is None:
        fit = fit_system(image, region={"depth": [a, b], "x": [0, nx]}, noise_rows=[na, nb])
        waist = float(fit.parameters.waist)
        if not (np.isfinite(waist) and waist > 0):
            raise ValueError("the twin's waist is not identified; give beam_radius (µm)")
        radius = waist / math.sqrt(2.0)
    else:
        if isinstance(beam_radius, bool) or not isinstance(beam_radius, (int, float)):
            raise TypeError(f"beam_radius must be a real number (µm), got {beam_radius!r}")
        if not (math.isfinite(beam_radius) and beam_radius > 0):
            raise ValueError(f"beam_radius must be > 0 µm, got {beam_radius}")
        radius, waist = float(beam_radius), math.nan
    if kind == "log":  # the twin's gain and offset: the skewness of the log data (fit_floor)
        region = xr.DataArray(
            np.asarray(image.values[a:b], float), dims=("depth", "x"), attrs={"scale": "log"}
        )
        floor = fit_floor(region)
        gain, offset = float(floor["gain"]), float(floor["offset"])
    else:
        gain, offset = 1.0, 0.0
    noise = _log_image(image.isel(depth=slice(na, nb)))
    noise_log = float(np.mean((noise - offset) / gain))
    brightest = float(np.max((_log_image(image.isel(depth=slice(a, b))) - offset) / gain))
    top_log = max(noise_log + _scan.DYNAMIC_RANGE / _NEPER_DB, brightest)
    t_eq = slab_constants(radius)["t_eq"]
    n_scatterers = math.ceil(per_cell * (b - a) * nx * 2 * radius / t_eq)
    cfg = ScannerConfig(
        n_pixels=b - a,
        pixel_size=dz,
        wavelength=float(wavelength),
        n_lines=nx,
        x_max=nx * pitch,
        beam_radius=radius,
        n_scatterers=n_scatterers,
    )
    return EquivalentSystem(
        config=cfg,
        rows=(a, b),
        gain=gain,
        offset=offset,
        noise_log=noise_log,
        kind=kind,
        waist=waist,
        window_top_log=top_log,
        denoise=denoise,
    )


# --- the study --------------------------------------------------------------------------


def _row_stats(li: np.ndarray):
    """Row means of ``ln I`` and their jackknife SE over :data:`BLOCKS` blocks of lines."""
    m = li.mean(axis=1)
    groups = np.array_split(np.arange(li.shape[1]), BLOCKS)
    jk = np.stack([np.delete(li, g, axis=1).mean(axis=1) for g in groups])
    se = np.sqrt((BLOCKS - 1) / BLOCKS * np.sum((jk - jk.mean(0)) ** 2, axis=0))
    return m, se


def _corr_length(li: np.ndarray, axis: int) -> float:
    """Lag (pixels or lines, interpolated) where the autocorrelation of ``ln I`` (each row's
    mean removed) falls to 1/e."""
    d = li - li.mean(axis=1, keepdims=True)
    var = float(np.mean(d * d))
    prev = 1.0
    for lag in range(1, 64):
        a = d[lag:] if axis == 0 else d[:, lag:]
        b = d[:-lag] if axis == 0 else d[:, :-lag]
        c = float(np.mean(a * b)) / var
        if c < 1 / math.e:
            return lag - 1 + (prev - 1 / math.e) / (prev - c)
        prev = c
    return math.nan


def _limits(levels: np.ndarray, rows: np.ndarray) -> dict[str, float | np.ndarray]:
    """Statistics of an 8-bit scan's ``ln I`` (relative to the window top) over ``rows``."""
    step = _STEP / _NEPER_DB
    li = (levels.astype(float) + 0.5) * step - _scan.DYNAMIC_RANGE / _NEPER_DB
    sub = li[rows]
    m, se = _row_stats(li)
    blocks = np.array_split(np.arange(sub.shape[1]), BLOCKS)
    block_means = np.stack([sub[:, g].mean(axis=1) for g in blocks], axis=1)  # (rows, blocks)
    return {
        "profile": m * _NEPER_DB,
        "profile_se": se * _NEPER_DB,
        "log_variance": float(np.mean(np.var(sub, axis=1))),
        "axial": _corr_length(sub, 0),
        "lateral": _corr_length(sub, 1),
        # lateral heterogeneity: spread of the block means of ln I around the row mean (dB)
        "lateral_spread": float(np.sqrt(np.mean(np.var(block_means, axis=1, ddof=1)))) * _NEPER_DB,
    }


def real_tissue_phantom(
    image: xr.DataArray,
    rows: tuple[int, int],
    *,
    noise_rows: tuple[int, int],
    seeds: tuple[int, ...] = (1, 2, 3),
    beam_radius: float | None = None,
    per_cell: float = 2.0,
    max_layers: int = 5,
    variant: str = "physical",
) -> xr.Dataset:
    """A SynthOCT phantom fitted to a measured image, its scans and where they differ.

    Parameters
    ----------
    image : xarray.DataArray
        A measured B-scan ``(depth, x)`` from :func:`speckle.load_image`.
    rows : (int, int)
        Half-open rows ``[start, stop)`` of the tissue fitted (:func:`equivalent_system`).
    noise_rows : (int, int)
        Half-open signal-free rows (the noise floor).
    seeds : tuple of int
        Seeds of the fitted phantom's draws (2..16 distinct non-negative integers); each is
        scanned and compared with the measured scan, every pair gives the floor.
    beam_radius, per_cell
        As :func:`equivalent_system`.
    max_layers : int
        As :func:`speckle.fit_phantom`.
    variant : {"physical", "official"}
        Maps and metrics of :func:`speckle.synthoct_metrics`.

    Returns
    -------
    xarray.Dataset
        ``measured`` ``(depth, x)`` (as measured, not denoised) and ``fitted`` ``(seed, depth, x)``
        (with the measured noise): 8-bit scans in the measured window; the maps ``OAC``, ``SC``,
        ``RSC`` of ``measured`` (``measured_*``) and of the first seed (``fitted_*``); the fitted
        layers (dim ``layer``, as ``fit_phantom``'s); the metrics ``MS-SSIM``, ``SSIM``, ``PSNR``,
        ``MSE``, ``VIF`` of measured vs fitted ``(seed, map)``, of the floor (fit vs fit, ``(pair,
        map)``), their means and the ``gap`` (measured vs fitted minus floor) with its SE; the
        limits: row-mean ``profile`` of both (dB re the window's top) and its residual in dB and in
        the measured row means' SE, ``var ln I``, speckle grain (1/e lengths) along depth and x,
        lateral spread of 16 blocks' mean levels (dB). Attributes: the system's configuration, gain,
        noise floor and the fit's window top.

    Raises
    ------
    TypeError, ValueError
        As :func:`equivalent_system` and :func:`speckle.fit_phantom`; bad ``seeds``.

    Examples
    --------
    >>> import speckle
    >>> from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
    >>> image = speckle.load_image(sample_path("pdms"), kind="log", dims=("depth", "x"),
    ...                            pixel_size=SAMPLE_PIXEL_SIZE, pitch=SAMPLE_PITCH["pdms"])
    >>> ds = speckle.real_tissue_phantom(image[:, :256], (90, 290), noise_rows=(5, 40),
    ...                                  seeds=(1, 2))  # doctest: +SKIP
    >>> ds.fitted.sizes["seed"]  # doctest: +SKIP
    2
    """
    from ...synthoct.maps import synthoct_maps
    from ...synthoct.metrics import synthoct_metrics

    try:
        seeds = tuple(seeds)
    except TypeError:
        raise TypeError(f"seeds must be a tuple of integers, got {seeds!r}") from None
    if (
        not 2 <= len(seeds) <= 16
        or len(set(seeds)) != len(seeds)
        or any(isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0 for s in seeds)
    ):
        raise ValueError(f"seeds must be 2..16 distinct non-negative integers, got {seeds!r}")
    if variant not in ("physical", "official"):
        raise ValueError(f"variant must be 'physical' or 'official', got {variant!r}")
    system = equivalent_system(
        image, rows, noise_rows=noise_rows, beam_radius=beam_radius, per_cell=per_cell
    )
    # the measured scan as it is (signal plus noise), beside the fitted phantom's scans plus
    # the same noise; the fit itself sees the denoised rows
    measured = dataclasses.replace(system, denoise=False).scan_levels(image)
    fit = fit_phantom(image, system, max_layers=max_layers)
    fitted = [system.scan(fit, s) for s in seeds]

    def metrics(a, b):
        return synthoct_metrics(a, b, variant=variant, lpips=False).drop_vars("LPIPS")

    versus = xr.concat([metrics(measured, f) for f in fitted], dim="seed")
    pairs = list(itertools.combinations(range(len(seeds)), 2))
    floor = xr.concat([metrics(fitted[i], fitted[j]) for i, j in pairs], dim="pair")
    maps_m = synthoct_maps(measured, variant=variant)
    maps_f = synthoct_maps(fitted[0], variant=variant)

    # the limits over the rows the fit used (above its floor)
    used = np.arange(GAP + 1, GAP + 1 + int(fit.layers.attrs["rows"]))
    lim_m = _limits(measured.values, used)
    lim_f = [_limits(f.values, used) for f in fitted]
    prof_f = np.mean([f["profile"] for f in lim_f], axis=0)
    prof_f_se = np.std([f["profile"] for f in lim_f], axis=0, ddof=1) / math.sqrt(len(seeds))
    resid = lim_m["profile"] - prof_f
    resid_se = np.hypot(lim_m["profile_se"], prof_f_se)
    pull = resid[used] / resid_se[used]

    gap = versus.mean("seed") - floor.mean("pair")
    gap_se = np.sqrt(
        versus.var("seed", ddof=1) / len(seeds) + floor.var("pair", ddof=1) / len(pairs)
    )
    out = xr.Dataset(
        {
            "measured": measured,
            "fitted": xr.concat(fitted, dim="seed"),
            **{f"measured_{k}": maps_m[k] for k in ("OAC", "SC", "RSC")},
            **{f"fitted_{k}": maps_f[k] for k in ("OAC", "SC", "RSC")},
            **fit.layers.data_vars,
            **{f"{k}_versus": versus[k] for k in versus.data_vars},
            **{f"{k}_floor": floor[k] for k in floor.data_vars},
            **{f"{k}_gap": gap[k] for k in gap.data_vars},
            **{f"{k}_gap_se": gap_se[k] for k in gap_se.data_vars},
            "profile_measured": (
                "depth",
                lim_m["profile"],
                attrs("level", "row-mean level of the measured scan re the window top"),
            ),
            "profile_fitted": (
                "depth",
                prof_f,
                attrs("level", "row-mean level of the fitted phantom's scans (mean of the seeds)"),
            ),
            "profile_residual": (
                "depth",
                resid,
                attrs("level", "measured minus fitted row-mean level"),
            ),
            "profile_residual_se": (
                "depth",
                resid_se,
                attrs("level", "standard error of profile_residual"),
            ),
        },
        coords={
            "seed": coord("seed", list(seeds)),
            "pair": coord("pair", [f"{seeds[i]}-{seeds[j]}" for i, j in pairs]),
        },
    )
    scalars = {
        "log_variance": ("dimensionless", "var ln I over the lines, mean over the fitted rows"),
        "axial": ("pixels", "1/e length of the ln I autocorrelation along depth"),
        "lateral": ("pixels", "1/e length of the ln I autocorrelation along x (lines)"),
        "lateral_spread": (
            "level",
            "rms spread of 16 lateral blocks' mean level about the row mean",
        ),
    }
    for key, (q, name) in scalars.items():
        out[f"{key}_measured"] = ((), lim_m[key], attrs(q, name + ", measured"))
        vals = [f[key] for f in lim_f]
        out[f"{key}_fitted"] = ((), float(np.mean(vals)), attrs(q, name + ", fitted (seed mean)"))
        out[f"{key}_fitted_se"] = (
            (),
            float(np.std(vals, ddof=1) / math.sqrt(len(vals))),
            attrs(q, "standard error of " + key + "_fitted"),
        )
    out["profile_pull_rms"] = (
        (),
        float(np.sqrt(np.mean(pull**2))),
        attrs("dimensionless", "rms of profile_residual/SE over the fitted rows"),
    )
    out["profile_residual_rms"] = (
        (),
        float(np.sqrt(np.mean(resid[used] ** 2))),
        attrs("level", "rms of profile_residual over the fitted rows"),
    )
    cfg = system.config
    out.attrs.update(
        rows=list(system.rows),
        fitted_rows=[int(used[0]), int(used[-1]) + 1],
        noise_rows=[int(v) for v in noise_rows],
        gain=system.gain,
        offset=system.offset,
        beam_radius=cfg.beam_radius,
        waist=system.waist,
        n_scatterers=cfg.n_scatterers,
        pixel_size=cfg.pixel_size,
        line_pitch=cfg.line_pitch,
        window_top=float(fit.layers.attrs["window_top"]),
        variant=variant,
    )
    return out
