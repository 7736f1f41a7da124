"""Fit the model's system to a measured image (:func:`fit_system`)."""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from ..._validate import check_int, check_real, check_size
from ...conventions import attrs
from ._estimates import _estimate, _jackknife
from ._focus import _fit_focus, _focus_test, _refit_focus, _row_mean_covariance
from ._inputs import _as_image, _check_values, _column_groups, _data, _find_noise_rows, _region
from ._parameters import _parameters, _shape
from ._theory import (
    DEFAULT_K0_DK,
    FOCUS_P_VALUE,
    LOG_AS_LINEAR_CONTRAST,
    MIN_NOISE_ROWS,
    NOISE_ROW_DB,
)
from .system_fit import SystemFit

__all__ = ["fit_system"]


#: Share of the region's pixels at the stored dtype's limits above which the fit warns.
MAX_CLIPPED = 0.01


def _warn_clipped(reg: xr.DataArray) -> None:
    """Warn when the region holds clipped pixels (``load_image``'s ``clip_low``/``clip_high``:
    the integer dtype's limits): their statistics are not those of speckle."""
    lo, hi = reg.attrs.get("clip_low"), reg.attrs.get("clip_high")
    if lo is None or hi is None:
        return
    v = reg.values
    share = float(np.mean((v <= lo) | (v >= hi)))
    if share > MAX_CLIPPED:
        warnings.warn(
            f"{share:.1%} of the region's pixels sit at the stored dtype's limits "
            f"({lo}, {hi}): clipped data bias every statistic of the fit (waist, spectrum, "
            "SNR); choose a region without saturation",
            UserWarning,
            stacklevel=3,
        )


def _outside_region(rows: Sequence[int], depth: Sequence | None, nz: int) -> None:
    """Noise rows must not overlap the fitted region's rows (they would be signal)."""
    lo, hi = (0, nz) if depth is None else (depth[0] or 0, nz if depth[1] is None else depth[1])
    if rows[0] < hi and rows[1] > lo:
        raise ValueError(
            f"noise_rows = {list(rows)} overlap the region's rows [{lo}, {hi}): signal-free "
            "rows must lie outside the fitted speckle"
        )


def fit_system(
    image: xr.DataArray,
    *,
    k0: float | None = None,
    refractive_index: float = 1.0,
    region: Mapping | None = None,
    noise_rows: Sequence[int] | None = None,
    snr_db: float | None = None,
    n_pixels: int = 64,
    max_lag: int = 8,
    n_blocks: int = 16,
    n_bands: int = 4,
    max_density: float = 16.0,
) -> SystemFit:
    """Fit the model's system to a measured image (module docstring).

    Parameters
    ----------
    image : xarray.DataArray or sequence of xarray.DataArray
        From :func:`speckle.load_image`: dims ``(depth, x)``, ``attrs["kind"]`` one of
        ``complex``, ``amplitude``, ``intensity``, ``log``. A ``frame`` dim (or a list of
        same-shaped images): every frame is fitted, the statistics pooled over all frames'
        pixel pairs and the jackknife deleting one block of A-lines from every frame at once
        (frames of one sample share speckle: their SE is not divided by sqrt(frames)).
    k0 : float, optional
        Central wavenumber in vacuum (rad/µm, > 0); the model uses ``refractive_index * k0``.
        Default: ``k0/delta_k = 10`` (:data:`DEFAULT_K0_DK`). It sets the twin's carrier (the
        strain estimators' phase) and nothing that a single intensity image shows.
    refractive_index : float
        Of the medium (>= 1): depths in the medium are ``pixel_size / refractive_index``.
    region : mapping, optional
        Homogeneous speckle to fit, ``{"depth": [start, stop], "x": [start, stop]}`` (pixel
        indices, half-open); default the whole image.
    noise_rows : [start, stop], optional
        Signal-free rows (air above the sample), same columns as the region: SNR and noise
        floor. Without them and without ``snr_db`` they are looked for above the region
        (:data:`NOISE_ROW_DB` below its mean intensity, flat, >= :data:`MIN_NOISE_ROWS`
        contiguous rows); the rows used and how they were chosen are in the attributes
        ``noise_rows`` and ``noise_rows_source``. None found: a warning, SNR not fitted.
    snr_db : float, optional
        A known SNR (dB) when there are no signal-free rows (not with ``noise_rows``).
    n_pixels : int
        Spectral components of the model A-scan used in the theory and the twin (>= 16).
    max_lag : int
        Largest autocorrelation lag (>= 2).
    n_blocks : int
        A-line blocks of the jackknife (>= 4).
    n_bands : int
        Depth bands of the per-band waist (0 or >= 2).
    max_density : float
        Largest density the twin simulates (the image cannot tell denser scenes apart).

    Returns
    -------
    SystemFit
        The fitted twin: parameters with their standard errors (see :class:`SystemFit`).

    Raises
    ------
    TypeError
        ``image`` not a DataArray.
    ValueError
        Unknown kind; frames of different shapes; a region or noise rows outside the image;
        NaN, constant or (linear) zero pixels; a region too small for ``max_lag`` and
        ``n_blocks``; bad settings. All before any fitting.

    Warns
    -----
    UserWarning
        A linear image (amplitude/intensity) whose intensity contrast std/mean is below
        :data:`LOG_AS_LINEAR_CONTRAST` (fully developed speckle: 1): probably log data. No
        signal-free rows found (``noise_rows`` and ``snr_db`` not given).

    Examples
    --------
    >>> import speckle
    >>> from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
    >>> image = speckle.load_image(
    ...     sample_path("pdms"),
    ...     kind="log",
    ...     pixel_size=SAMPLE_PIXEL_SIZE,
    ...     pitch=SAMPLE_PITCH["pdms"],
    ...     dims=("depth", "x"),
    ... )
    >>> fit = speckle.fit_system(image, region={"depth": [95, 135]}, noise_rows=[5, 40])
    >>> type(fit).__name__, str(fit.parameters.attrs["kind"])
    ('SystemFit', 'log')
    """
    img = _as_image(image)
    kind = img.attrs["kind"]
    n_med = check_real(refractive_index, "refractive_index", low=1.0)
    k0v = None if k0 is None else check_real(k0, "k0", low=0, low_inclusive=False)
    npx = check_size(n_pixels, "n_pixels", low=16, bytes_per=64.0)
    ml = check_int(max_lag, "max_lag", low=2)
    nb = check_int(n_blocks, "n_blocks", low=4)
    nbands = check_int(n_bands, "n_bands", low=0)
    if nbands == 1:
        raise ValueError("n_bands must be 0 (no per-band waist) or >= 2, got 1")
    rmax = check_real(max_density, "max_density", low=0, low_inclusive=False)
    reg = _region(img, region)
    nz, nx = reg.sizes["depth"], reg.sizes["x"]
    nf = reg.sizes.get("frame", 1)
    if nz < ml + 4 or nx < nb * (ml + 2):
        raise ValueError(
            f"region of {nz} x {nx} pixels (depth, x) is too small for max_lag = {ml} and "
            f"n_blocks = {nb}: need depth >= max_lag + 4 = {ml + 4} and x >= n_blocks * "
            f"(max_lag + 2) = {nb * (ml + 2)}; enlarge the region or lower max_lag/n_blocks"
        )
    if nbands and nz // nbands < 2:
        raise ValueError(f"n_bands = {nbands} leaves fewer than 2 rows per band in {nz} rows")
    _check_values(reg, "image region", kind)
    noise = None
    noise_source = "given"
    if noise_rows is None and snr_db is None:
        noise_rows = _find_noise_rows(img, region)
        noise_source = "found automatically" if noise_rows is not None else "none found"
        if noise_rows is None:
            warnings.warn(
                "no signal-free rows found above the region (rows "
                f"{NOISE_ROW_DB:g} dB below it, >= {MIN_NOISE_ROWS} contiguous): SNR and "
                "noise floor are not fitted (pass noise_rows=[start, stop] or snr_db=)",
                UserWarning,
                stacklevel=2,
            )
    elif noise_rows is None:
        noise_source = "none (snr_db given)"
    if noise_rows is not None and snr_db is not None:
        raise ValueError(
            "give noise_rows or snr_db, not both: noise_rows measure the SNR that snr_db states"
        )
    if noise_rows is not None:
        if isinstance(noise_rows, str) or len(noise_rows) != 2:
            raise ValueError(f"noise_rows must be [start, stop], got {noise_rows!r}")
        cols = (region or {}).get("x")
        noise = _region(img, {"depth": list(noise_rows), "x": cols})
        if noise.sizes["depth"] < 2:
            raise ValueError(f"noise_rows = {list(noise_rows)} must hold at least 2 rows")
        _check_values(noise, "noise_rows", kind)
        _outside_region(noise_rows, (region or {}).get("depth"), img.sizes["depth"])
        snr_db = None
    elif snr_db is not None:
        snr_db = check_real(snr_db, "snr_db")
    _warn_clipped(reg)
    data = _data(reg, noise, n_med)
    if kind in ("amplitude", "intensity"):
        c = float(np.std(data.signal) / np.mean(data.signal))
        if c < LOG_AS_LINEAR_CONTRAST:
            warnings.warn(
                f"image given as kind={kind!r} has intensity contrast std/mean = {c:.3f} "
                "(fully developed speckle: 1; noise and a floor keep it near 1): it looks "
                "log-compressed; pass kind='log' if it is",
                UserWarning,
                stacklevel=2,
            )
    blocks = np.array_split(np.arange(nx), nb)
    kw = {"n_pixels": npx, "max_lag": ml, "n_bands": nbands, "snr_db": snr_db}
    # every pair of the region (of every frame); the jackknife deletes a block of A-lines from
    # every frame at once, so frames of one sample (correlated speckle) do not shrink the SE
    whole = _estimate(data, _column_groups(nx, nf, [np.arange(nx)]), **kw)
    if noise is not None and not np.isfinite(whole["snr_db"]):
        warnings.warn(
            f"noise_rows {list(noise_rows)} are as bright as the region (not signal-free): the "
            "SNR and the noise floor have no answer (NaN)",
            UserWarning,
            stacklevel=2,
        )
    jack = [
        _estimate(data, _column_groups(nx, nf, blocks[:i] + blocks[i + 1 :]), **kw)
        for i in range(nb)
    ]
    keys = [k for k, v in whole.items()]
    se = _jackknife(jack, keys)
    params = _parameters(whole, se, jack, data, reg, npx, noise is not None)
    # focus and attenuation: row means of ln I, their covariance from the region's 2-D
    # autocovariance (rows are correlated along depth by the point-spread function)
    dk = np.pi / data.dz  # delta_k = N pi / H = pi / pixel
    k_model = DEFAULT_K0_DK * dk if k0v is None else n_med * k0v
    z = np.arange(nz) * data.dz
    g = float(whole["gain"]) if kind == "log" else 1.0
    # the frame average: its row means are those of every frame, and its autocovariance holds
    # whatever correlation the frames share (none to all)
    log_mean = np.mean(
        [
            data.signal[:, c] / g if kind == "log" else np.log(data.signal[:, c])
            for c in _column_groups(nx, nf, [np.arange(nx)])
        ],
        axis=0,
    )
    log_rows = log_mean.mean(axis=1)
    focused = False
    if nz >= 8:
        cov = _row_mean_covariance(log_mean)
        # attenuation: least-squares slope, sandwich variance with the rows' covariance
        x = np.column_stack([np.ones_like(z), z])
        h = np.linalg.solve(x.T @ x, x.T)
        params["attenuation_se"] = (
            (),
            float(np.sqrt((h @ cov @ h.T)[1, 1]) / 2),
            params["attenuation_se"][2],
        )
        rayleigh = k_model * (float(whole["waist_pitch"]) * data.pitch) ** 2 / 2
        p_focus, zf_scan, zr_scan = _focus_test(z, log_rows, cov, rayleigh)
        params["focus_p_value"] = (
            (),
            p_focus,
            attrs(
                "probability",
                "p-value of a focus in the row means of ln I (scan statistic, Monte-Carlo "
                "null with the rows' covariance)",
            ),
        )
        rows = np.asarray(whole["row_mean_intensity"])
        rows_se = se["row_mean_intensity"]
        snr_v = float(whole["snr_db"])
        noise_level = float(rows.mean() / (1 + 10 ** (snr_v / 10))) if np.isfinite(snr_v) else 0.0
        best = None
        if p_focus < FOCUS_P_VALUE and np.all(rows_se > 0):
            best = _fit_focus(z, rows, rows_se, noise_level, (zf_scan, zr_scan))
        if best is not None:
            focused = True
            _, p, _ = best
            # errors: the same fit on each jackknife sample (rows are correlated along depth
            # by the point-spread function, so the least-squares covariance would be too small)
            refits = [
                {
                    "p": _refit_focus(
                        z, np.asarray(j["row_mean_intensity"]), rows_se, noise_level, p
                    )[0]
                }
                for j in jack
            ]
            pse = _jackknife(refits, ["p"])["p"]
            params["attenuation"] = ((), float(p[1]), params["attenuation"][2])
            params["attenuation_se"] = ((), float(pse[1]), params["attenuation"][2])
            for name, i, ln in (
                ("focus_depth", 2, "focal depth in the medium below the region's first row"),
                ("rayleigh_range", 3, "Rayleigh range in the medium"),
            ):
                params[name] = ((), float(p[i]), attrs("length", ln))
                params[f"{name}_se"] = (
                    (),
                    float(pse[i]),
                    attrs("length", f"standard error of {name}"),
                )
    if not focused:
        for name in ("focus_depth", "rayleigh_range"):
            params[name] = ((), np.nan, attrs("length", "no focus detected"))
            params[f"{name}_se"] = ((), np.nan, attrs("length", "no focus detected"))
    ds = xr.Dataset(params)
    ds.attrs.update(
        kind=kind,
        spectrum_shape=_shape(whole),
        focused=int(focused),
        k0=float(k_model),
        k0_dk=float(k_model / dk),
        k0_given=int(k0v is not None),
        refractive_index=n_med,
        pixel_size=float(data.dz * n_med),
        depth_step_medium=float(data.dz),
        pitch=float(data.pitch),
        region=repr(dict(region or {})),
        noise_rows=repr(None if noise_rows is None else list(noise_rows)),
        noise_rows_source=noise_source,
        n_pixels=npx,
        max_lag=ml,
        n_blocks=nb,
        source=str(img.attrs.get("source", "")),
        method="delete-one-block jackknife standard errors (speckle.analysis.twin)",
    )
    mean_i = (
        float(np.mean(np.abs(reg.values) ** 2))
        if kind == "complex"
        else float(np.mean(data.signal))
    )
    settings = {
        "region": dict(region) if region else None,
        "n_pixels": npx,
        "max_lag": ml,
        "n_blocks": nb,
        "refractive_index": n_med,
        "max_density": rmax,
        "mean_intensity": mean_i,
    }
    ds.attrs["n_frames"] = nf
    out = SystemFit(ds, reg.isel(frame=0) if "frame" in reg.dims else reg, settings)
    out._fit_detection(reg)
    return out
