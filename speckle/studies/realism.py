"""Which system effects a measured B-scan needs: the model against the image, effect by effect.

Both the measured region and every model image go through one estimator chain (gain- and
offset-free, see :mod:`speckle.analysis.measured`): log data ``D``; skewness and excess kurtosis
of ``D`` (:func:`~speckle.analysis.measured.log_statistics`); the intensity ``exp(D/g)`` with the
gain ``g`` of :func:`~speckle.analysis.measured.fit_floor` (the offset cancels) and its Pearson
autocorrelation along depth and across A-lines, lags ``0 .. max_lag``
(:func:`~speckle.analysis.autocorrelation.intensity_autocorrelation`); and the two-sample
Kolmogorov-Smirnov distance between the standardised log data of model and measurement.

Fitted to the measured image (each from its own statistic, before any simulation):

* ``fwhm_fraction``: a Gaussian spectrum's FWHM (fraction of ``delta_k``) from the depth
  autocorrelation (least squares over lags >= 1, including the noise factor);
* ``waist``: the beam waist in A-line pitches from the lateral autocorrelation;
* ``snr_db``: mean intensity of the region over that of air rows (noise only);
* ``floor``: the intensity floor matching the skewness (:func:`fit_floor`);
* ``attenuation``: ``mu_t`` from the slope of the mean log intensity, ``-2 mu_t`` per µm;
* ``gain``, ``offset``: the log mapping, used to quantise model images to 8 bits.

The model starts pure (rectangular spectrum filling the pixel band, independent A-lines) and the
effects are added one at a time in :data:`EFFECTS` order (``cumulative``). Misfit: the largest
``|model - measured| / sqrt(SE_model^2 + SE_measured^2)`` over the autocorrelations (lags >= 1)
and the two moments (``score``). An effect is *needed* when dropping it from the full model raises
the score by more than :data:`NEEDED_INCREASE` (two combined standard errors); the final model
keeps only the needed effects.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import stats

from .._adapters import scene_kwargs, spectrum_kwargs
from .._validate import check_choice, check_int, check_real
from ..analysis import autocorrelation as ac
from ..analysis import measured as ms
from ..conventions import attrs, coord
from ..imaging._bscan import bscan
from ..imaging.beam_lines import beam_lines, shared_scatterers
from ..scene.scatterers import random_scatterers
from ..system.attenuation import attenuate
from ..system.detection import add_floor, log_compress
from ..system.noise import add_noise
from ..system.phase import phase_perturb
from ..system.source import spectrum
from .twin.fit import fit_system
from .twin.system_fit import SystemFit

__all__ = [
    "EFFECTS",
    "NEEDED_INCREASE",
    "effect_parameters",
    "fit_parameters",
    "image_statistics",
    "realism_study",
]

#: Effects in the order they are added; each is off in the pure model.
EFFECTS = ("spectral_width", "beam", "noise", "floor", "attenuation", "quantisation", "phase")
NEEDED_INCREASE = 2.0
_PHASE_SEED_STREAM = 7


def image_statistics(log_data: xr.DataArray, *, max_lag: int, n_blocks: int) -> xr.Dataset:
    """The estimator chain of the module docstring for one image of log data ``(depth, x)``."""
    st = ms.log_statistics(log_data, n_blocks=n_blocks)
    g = float(ms.fit_floor(log_data)["gain"])
    d = log_data - log_data.mean()
    acf = ac.intensity_autocorrelation(np.exp(d / g), max_lag=max_lag, n_blocks=n_blocks)
    return xr.Dataset(
        {
            "autocorrelation": acf.autocorrelation,
            "autocorrelation_se": acf.autocorrelation_se,
            "skewness": st.skewness,
            "skewness_se": st.skewness_se,
            "excess_kurtosis": st.excess_kurtosis,
            "excess_kurtosis_se": st.excess_kurtosis_se,
        }
    )


def fit_parameters(
    roi: xr.DataArray,
    air: xr.DataArray | None,
    *,
    pixel_size: float,
    n_pixels: int,
    max_lag: int,
    n_blocks: int,
    snr_db: float | None = None,
) -> dict[str, float]:
    """Fit the effect parameters to a measured log-scale region: one use of :func:`fit_system`.

    ``air`` (log-scale rows of air over the same A-lines) sets the SNR; without it ``snr_db``
    (or no noise) is used in the autocorrelation fits. The air rows are stacked above the
    region into one image, fitted with ``noise_rows`` = the air rows and ``region`` = the rest.
    """
    dz = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    parts = [roi.values] if air is None else [air.values, roi.values]
    n_air = 0 if air is None else air.shape[0]
    values = np.vstack(parts)
    rows, cols = values.shape
    image = xr.DataArray(
        values,
        dims=("depth", "x"),
        coords={
            "depth": coord("depth", np.arange(rows) * dz),
            "x": coord("x", np.arange(cols, dtype=float)),  # pitch 1: only w0/pitch matters
        },
        attrs={"kind": "log", "pixel_size": dz, "pitch": 1.0, **_clip_attrs(roi)},
    )
    fit = fit_system(
        image,
        region={"depth": [n_air, values.shape[0]]},
        noise_rows=None if air is None else [0, n_air],
        snr_db=snr_db,
        n_pixels=n_pixels,
        max_lag=max_lag,
        n_blocks=n_blocks,
        n_bands=0,
    )
    return effect_parameters(fit)


def _clip_attrs(da: xr.DataArray) -> dict:
    return {k: da.attrs[k] for k in ("clip_low", "clip_high") if k in da.attrs}


def effect_parameters(fit: SystemFit) -> dict[str, float]:
    """The realism study's effect parameters from a :class:`SystemFit` (module docstring)."""
    p = fit.parameters
    snr = float(p.snr_db)
    return {
        "fwhm_fraction": float(p.gaussian_fwhm_fraction),
        "fwhm_fraction_rms": float(p.gaussian_rms_residual),
        "waist": float(p.waist_pitch),
        "waist_rms": float(p.get("waist_rms_residual", np.nan)),
        "snr_db": snr,
        "floor": float(p.floor),
        "attenuation": max(0.0, float(p.attenuation)),
        "gain": float(p.gain),
        "offset": float(p.offset),
    }


def simulate(
    effects: frozenset[str],
    fit: dict[str, float],
    *,
    n_pixels: int,
    n_alines: int,
    pixel_size: float,
    density: float,
    k0_dk: float,
    phase: dict,
    seed: int,
) -> xr.DataArray:
    """Log data ``(depth, x)`` of a model image with the given effects on."""
    for e in effects:
        check_choice(e, "effect", EFFECTS)
    section = {"n_pixels": n_pixels, "pixel_size": pixel_size, "k0_dk": k0_dk}
    if "spectral_width" in effects:
        section.update(shape="gaussian", fwhm_fraction=fit["fwhm_fraction"])
    src = spectrum(**spectrum_kwargs(section))
    grid = scene_kwargs(section)
    if "beam" in effects:
        w0 = fit["waist"] * pixel_size  # lines one pixel_size apart: only w0/pitch matters
        sc = shared_scatterers(n_alines, pixel_size, density, **grid, waist=w0, seed=seed)
        scene = beam_lines(sc["z"], sc["x"], sc["amplitude"], lines=sc["lines"], waist=w0)
        scene = scene.assign_attrs(**grid, density=density)
    else:
        scene = random_scatterers(n_alines, density, **grid, seed=seed)
    if "attenuation" in effects:
        scene = attenuate(scene, fit["attenuation"])
    if "phase" in effects:
        scene = phase_perturb(scene, k0=src.attrs["k0"], seed=seed + _PHASE_SEED_STREAM, **phase)
    img = bscan(scene, src, method="nufft", tol=1e-9)
    if "noise" in effects:
        img = add_noise(img, fit["snr_db"], seed=seed)
    intensity = img.intensity / img.intensity.mean()
    if "floor" in effects:
        intensity = add_floor(intensity, fit["floor"], mean_intensity=1.0)
    bits = 8 if "quantisation" in effects else None
    d = log_compress(intensity, fit["gain"], fit["offset"], bits=bits)
    return d.transpose("depth", "x").assign_attrs(scale="log", effects=",".join(sorted(effects)))


def _score(model: xr.Dataset, meas: xr.Dataset) -> float:
    lags = {"lag": slice(1, None)}
    za = abs(model.autocorrelation - meas.autocorrelation).sel(lags) / np.sqrt(
        model.autocorrelation_se.sel(lags) ** 2 + meas.autocorrelation_se.sel(lags) ** 2
    )
    zs = [
        abs(float(model[k] - meas[k])) / float(np.hypot(model[f"{k}_se"], meas[f"{k}_se"]))
        for k in ("skewness", "excess_kurtosis")
    ]
    return float(max(float(za.max()), *zs))


def _ks(a: xr.DataArray, b: xr.DataArray) -> float:
    za, zb = (ms.standardise(x).values.ravel() for x in (a, b))
    return float(stats.ks_2samp(za, zb).statistic)


def realism_study(
    measured: xr.DataArray | None,
    air: xr.DataArray | None,
    *,
    pixel_size: float,
    n_pixels: int,
    n_alines: int,
    density: float,
    k0_dk: float,
    max_lag: int,
    n_blocks: int,
    phase: dict,
    fallback: dict,
    seed: int,
    fit: SystemFit | None = None,
) -> xr.Dataset:
    """Measured against model, effect by effect (module docstring).

    ``fit`` (:func:`speckle.studies.twin.fit_system` of the measured image) gives the effect
    parameters; without it they are fitted here (:func:`fit_parameters`).

    ``measured`` is the log-scale region of interest (``None``: no measured image; the model is
    drawn with the ``fallback`` parameters and no comparison is made) and ``air`` the log-scale
    air rows for the noise level (``None``: ``fallback["snr_db"]``).
    """
    nb = check_int(n_blocks, "n_blocks", low=2)
    ml = check_int(max_lag, "max_lag", low=1)
    kw = {
        "n_pixels": n_pixels,
        "n_alines": n_alines,
        "pixel_size": pixel_size,
        "density": density,
        "k0_dk": k0_dk,
        "phase": phase,
        "seed": seed,
    }
    if measured is not None and fit is not None:
        fit = effect_parameters(fit)
        meas = image_statistics(measured, max_lag=ml, n_blocks=nb)
    elif measured is not None:
        fit = fit_parameters(
            measured,
            air,
            pixel_size=pixel_size,
            n_pixels=n_pixels,
            max_lag=ml,
            n_blocks=nb,
            snr_db=None if air is not None else float(fallback["snr_db"]),
        )
        meas = image_statistics(measured, max_lag=ml, n_blocks=nb)
    else:
        fit = {k: float(v) for k, v in fallback.items()}
        meas = None

    def run(effects):
        d = simulate(frozenset(effects), fit, **kw)
        st = image_statistics(d, max_lag=ml, n_blocks=nb)
        if meas is not None:
            st["score"] = _score(st, meas)
            st["ks_distance"] = _ks(d, measured)
        return st

    steps = ["pure"] + [f"+{e}" for e in EFFECTS]
    cumulative = [run(EFFECTS[:i]) for i in range(len(EFFECTS) + 1)]
    cum = xr.concat(cumulative, dim="step").assign_coords(step=steps)
    out = {f"cumulative_{k}": v for k, v in cum.data_vars.items()}
    final = list(EFFECTS)
    if meas is not None:
        full_score = float(cum.score.isel(step=-1))
        dropped = xr.concat([run([e for e in EFFECTS if e != d]) for d in EFFECTS], "effect")
        dropped = dropped.assign_coords(effect=list(EFFECTS))
        needed = dropped.score > full_score + NEEDED_INCREASE
        final = [e for e in EFFECTS if bool(needed.sel(effect=e))]
        out.update({f"dropped_{k}": v for k, v in dropped.data_vars.items()})
        out["needed"] = needed.assign_attrs(
            long_name="dropping the effect raises the misfit score by > 2 combined SE"
        )
        final_stats = run(final)
        out.update(
            {f"final_{k}": v for k, v in final_stats.data_vars.items() if k != "autocorrelation"}
        )
        model_acf = final_stats.autocorrelation
        out["measured_autocorrelation"] = meas.autocorrelation
        out["measured_autocorrelation_se"] = meas.autocorrelation_se
        for k in ("skewness", "skewness_se", "excess_kurtosis", "excess_kurtosis_se"):
            out[f"measured_{k}"] = meas[k]
    else:
        model_acf = cum.autocorrelation.isel(step=-1, drop=True)
    out["model_autocorrelation"] = model_acf.assign_attrs(
        attrs("correlation", "intensity autocorrelation of the final (smallest sufficient) model")
    )
    ds = xr.Dataset(out)
    for k, v in fit.items():
        ds[f"fit_{k}"] = ((), v)
    ds.attrs.update(final_effects=",".join(final), effects=",".join(EFFECTS))
    return ds
