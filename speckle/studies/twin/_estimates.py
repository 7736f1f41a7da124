"""The twin's statistics of one region and their delete-one-block jackknife."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import stats

from ...analysis import measured as ms
from ...analysis.sparse import sparse_inverse_density
from ._theory import _acf, _fit_gaussian, _fit_rectangular, _fit_waist, _psf_excess, _weights


@dataclass
class _Data:
    """The region (and noise rows) of one image, as log data and intensity (``kind``-aware)."""

    kind: str
    signal: np.ndarray  # log data D (log kind) or intensity (linear kinds), (depth, x)
    noise: np.ndarray | None
    dz: float  # depth step in the medium, µm
    pitch: float

    def pieces(self, cols: list[np.ndarray]) -> tuple[list, list | None, float, dict]:
        """Intensity blocks, noise intensity blocks, gain and floor fit over columns ``cols``."""
        sig = [self.signal[:, c] for c in cols]
        flat = np.concatenate([s.ravel() for s in sig])
        if self.kind == "log":
            d = xr.DataArray(np.hstack(sig), dims=("depth", "x"), attrs={"scale": "log"})
            fl = ms.fit_floor(d)
            g, mean = float(fl["gain"]), float(flat.mean())
            inten = [np.exp((s - mean) / g) for s in sig]
            noise = (
                None
                if self.noise is None
                else [np.exp((self.noise[:, c] - mean) / g) for c in cols]
            )
        else:
            d = xr.DataArray(np.log(np.hstack(sig)), dims=("depth", "x"), attrs={"scale": "log"})
            fl = ms.fit_floor(d)
            g = 1.0
            inten = sig
            noise = None if self.noise is None else [self.noise[:, c] for c in cols]
        return inten, noise, g, {k: float(fl[k]) for k in ("floor", "gain", "offset")}


def _estimate(
    data: _Data,
    cols: list[np.ndarray],
    *,
    n_pixels: int,
    max_lag: int,
    n_bands: int,
    snr_db: float | None,
) -> dict[str, object]:
    """Every fitted quantity from the columns ``cols`` of the region (module docstring)."""
    inten, noise, g, fl = data.pieces(cols)
    i_all = np.hstack(inten)
    out: dict[str, object] = {"gain": fl["gain"], "offset": fl["offset"], "floor": fl["floor"]}
    log_i = np.log(i_all) if data.kind != "log" else (np.hstack([data.signal[:, c] for c in cols]))
    out["skewness"] = float(stats.skew(log_i.ravel()))
    out["excess_kurtosis"] = float(stats.kurtosis(log_i.ravel()))
    if noise is not None:
        n_all = np.hstack(noise)
        ratio = float(i_all.mean() / n_all.mean())
        snr_db = 10 * np.log10(ratio - 1) if ratio > 1 else np.nan
        out["noise_floor"] = float(
            np.hstack([data.noise[:, c] for c in cols]).mean()
            if data.kind == "log"
            else n_all.mean()
        )
    out["snr_db"] = np.nan if snr_db is None else float(snr_db)
    snr = None if snr_db is None or not np.isfinite(snr_db) else float(snr_db)
    depth_acf = _acf(inten, max_lag, "depth")
    lat_acf = _acf(inten, max_lag, "lateral")
    out["depth_autocorrelation"], out["lateral_autocorrelation"] = depth_acf, lat_acf
    # contrast excess x (noise and floor removed): the low-density term of every correlation
    r = 10 ** (snr / 10) if snr is not None else np.inf
    s_mean = i_all.mean() / (1 + fl["floor"] + 1 / r)
    excess = float((i_all.var() - (s_mean * (1 + 1 / r)) ** 2) / s_mean**2)
    out["contrast_excess"] = excess
    out["gaussian_fwhm_fraction"], out["gaussian_rms"] = _fit_gaussian(
        depth_acf, n_pixels, snr, excess
    )
    out["rectangular_width_fraction"], out["rectangular_rms"] = _fit_rectangular(
        depth_acf, n_pixels, snr, excess
    )
    out["waist_pitch"], out["waist_rms"] = _fit_waist(lat_acf, snr, excess)
    bands = np.array_split(np.arange(i_all.shape[0]), n_bands) if n_bands >= 2 else []
    out["band_waist_pitch"] = np.array(
        [
            _fit_waist(_acf([b[rb] for b in inten], max_lag, "lateral"), snr, excess)[0]
            for rb in bands
        ]
    )
    rows = np.mean(log_i, axis=1) / g
    z = np.arange(rows.size) * data.dz
    out["attenuation"] = float(-np.polyfit(z, rows, 1)[0] / 2)
    out["row_mean_intensity"] = i_all.mean(axis=1)
    shape = "gaussian" if out["gaussian_rms"] <= out["rectangular_rms"] else "rectangular"
    width = out[f"{shape}_{'fwhm' if shape == 'gaussian' else 'width'}_fraction"]
    psf = _psf_excess(shape, float(width), float(out["waist_pitch"]), n_pixels)
    out["inverse_density_contrast"] = float(excess / psf)
    # var ln I of sparse speckle (speckle.analysis.sparse): linear data only (for log data the
    # unknown gain g scales var D = g^2 var ln I, so var ln I is not observed)
    if data.kind == "log":
        out["inverse_density_log"] = np.nan
    else:
        out["inverse_density_log"] = sparse_inverse_density(
            float(np.var(log_i)),
            _weights(shape, float(width), n_pixels),
            float(out["waist_pitch"]),
            inverse_snr=0.0 if snr is None else 1 / r,
        )
    return out


def _jackknife(values: list[dict], keys: Sequence[str]) -> dict[str, np.ndarray]:
    n = len(values)
    se = {}
    for k in keys:
        v = np.array([np.asarray(d[k], dtype=float) for d in values])
        se[k] = np.sqrt((n - 1) / n * np.sum((v - v.mean(axis=0)) ** 2, axis=0))
    return se
