"""The fitted parameters of :func:`~speckle.studies.twin.fit.fit_system`, from one table.

:data:`PARAMETERS` lists every variable of the fit's Dataset in order, with its quantity (units
from :mod:`speckle.conventions`) and long name; :func:`_values` computes each one's value and
standard error from the whole-region estimates and their jackknife, and :func:`_parameters`
labels them from the table (a ``<name>_se`` variable beside each one that has an error).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from ...conventions import attrs
from ._estimates import _Data
from ._theory import SPECTRUM_SHAPES


def _shape(whole: dict) -> str:
    return "gaussian" if whole["gaussian_rms"] <= whole["rectangular_rms"] else "rectangular"


#: Every fitted parameter, in the order of the Dataset: (name, quantity, long name). The long
#: name's ``{shape}`` is the spectrum shape kept, ``{how}`` how the inverse densities combined.
PARAMETERS = (
    ("spectrum_width", "dimensionless", "{shape} spectrum width (FWHM) / delta_k"),
    ("gaussian_fwhm_fraction", "dimensionless", "Gaussian spectrum FWHM / delta_k"),
    ("rectangular_width_fraction", "dimensionless", "rectangular spectrum width / delta_k"),
    *(
        (
            f"{s}_rms_residual",
            "dimensionless",
            f"rms residual of the {s} fit to the depth autocorrelation",
        )
        for s in SPECTRUM_SHAPES
    ),
    ("waist", "length", "beam waist w0 (1/e^2 intensity radius)"),
    ("waist_pitch", "dimensionless", "beam waist / A-line pitch"),
    (
        "waist_rms_residual",
        "dimensionless",
        "rms residual of the waist fit to the lateral autocorrelation",
    ),
    ("band_waist", "length", "waist fitted per depth band"),
    ("band_depth", "length", "band centre below the region's first row (medium)"),
    ("waist_depth_p_value", "probability", "p-value of one waist at every depth band"),
    ("snr_db", "level", "mean signal intensity / noise intensity"),
    ("noise_floor", "dimensionless", "mean noise level (log data units, or intensity)"),
    ("attenuation", "attenuation", "intensity attenuation mu_t (medium)"),
    ("floor", "dimensionless", "intensity floor / mean speckle intensity"),
    ("gain", "dimensionless", "g in D = g ln I + c"),
    ("offset", "dimensionless", "c in D = g ln I + c"),
    ("contrast_excess", "dimensionless", "<I_s^2>/<I_s>^2 - 2 (noise and floor removed)"),
    (
        "inverse_density_contrast",
        "dimensionless",
        "1 / scatterers per pixel per pitch, from the intensity contrast",
    ),
    (
        "inverse_density_log",
        "dimensionless",
        "1 / scatterers per pixel per pitch, from var ln I (linear data only)",
    ),
    ("inverse_density", "dimensionless", "1 / scatterers per pixel per pitch ({how})"),
    ("density", "dimensionless", "scatterers per pixel per pitch"),
    (
        "density_identified",
        "dimensionless",
        "1 if the inverse density exceeds 2 SE (density fitted)",
    ),
    ("density_lower_bound", "dimensionless", "density at 2 SE of the inverse density"),
    ("skewness", "dimensionless", "skewness of the log data"),
    ("excess_kurtosis", "dimensionless", "excess_kurtosis of the log data"),
)
#: Long names of a linear image's gain and offset (``ln I`` itself: 1 and 0, no error).
LINEAR_LONG_NAMES = {"gain": "linear image: ln I itself", "offset": "linear image"}
#: Parameters read straight from the estimate of the same key, with its jackknife SE.
DIRECT = (
    "gaussian_fwhm_fraction",
    "rectangular_width_fraction",
    "waist_pitch",
    "attenuation",
    "floor",
    "contrast_excess",
    "inverse_density_contrast",
    "inverse_density_log",
    "skewness",
    "excess_kurtosis",
)


def _values(whole, se, combined, data: _Data, reg, have_noise, shape) -> dict:
    """``name -> (dims, value, standard error or None)``; a parameter that does not apply
    (``noise_floor`` without signal-free rows, the bands' without bands) is left out.
    ``combined`` is :func:`_combined_inverse_density` of the estimates."""
    width_key = "gaussian_fwhm_fraction" if shape == "gaussian" else "rectangular_width_fraction"
    v: dict = {k: ((), float(whole[k]), float(se[k])) for k in DIRECT}
    v["spectrum_width"] = ((), float(whole[width_key]), float(se[width_key]))
    for s in SPECTRUM_SHAPES:
        v[f"{s}_rms_residual"] = ((), float(whole[f"{s}_rms"]), None)
    pitch = data.pitch
    v["waist"] = ((), float(whole["waist_pitch"] * pitch), float(se["waist_pitch"] * pitch))
    v["waist_rms_residual"] = ((), float(whole["waist_rms"]), None)
    bw, bse = np.asarray(whole["band_waist_pitch"]), np.asarray(se["band_waist_pitch"])
    if bw.size:
        nb = bw.size
        centre = np.array([r.mean() for r in np.array_split(np.arange(reg.sizes["depth"]), nb)])
        v["band_waist"] = (("band",), bw * pitch, bse * pitch)
        v["band_depth"] = (("band",), centre * data.dz, None)
        wm = np.sum(bw / bse**2) / np.sum(1 / bse**2)
        chi = float(np.sum(((bw - wm) / bse) ** 2))
        v["waist_depth_p_value"] = ((), float(stats.chi2.sf(chi, nb - 1)), None)
    v["snr_db"] = ((), float(whole["snr_db"]), float(se["snr_db"]) if have_noise else 0.0)
    if have_noise:
        v["noise_floor"] = ((), float(whole["noise_floor"]), float(se["noise_floor"]))
    log = data.kind == "log"
    for k, linear in (("gain", 1.0), ("offset", 0.0)):
        v[k] = ((), float(whole[k]) if log else linear, float(se[k]) if log else 0.0)
    inv, inv_se, _ = combined
    v["inverse_density"] = ((), float(inv), float(inv_se))
    significant = inv > 2 * inv_se
    v["density"] = (
        (),
        float(1 / inv if significant else np.nan),
        float(inv_se / inv**2 if significant else np.nan),
    )
    v["density_identified"] = ((), int(significant), None)
    bound = float(1 / (inv + 2 * inv_se)) if inv + 2 * inv_se > 0 else np.inf
    v["density_lower_bound"] = ((), bound, None)
    return v


def _parameters(whole, se, jack, data: _Data, reg, npx, have_noise) -> dict:
    """The Dataset variables of the fit: :data:`PARAMETERS` labelled, each with its SE."""
    shape = _shape(whole)
    combined = _combined_inverse_density(whole, jack)
    how = combined[2]
    values = _values(whole, se, combined, data, reg, have_noise, shape)
    p: dict = {}
    for name, quantity, long_name in PARAMETERS:
        if name not in values:
            continue
        dims, value, err = values[name]
        if data.kind != "log":
            long_name = LINEAR_LONG_NAMES.get(name, long_name)
        p[name] = (dims, value, attrs(quantity, long_name.format(shape=shape, how=how)))
        if err is not None:
            p[f"{name}_se"] = (dims, err, attrs(quantity, f"standard error of {name}"))
    p["inverse_density"][2]["method"] = how
    return p


def _combined_inverse_density(whole: dict, jack: list[dict]) -> tuple[float, float, str]:
    """Contrast and ``var ln I`` estimates of ``1/rho`` combined by their jackknife covariance.

    Weights ``C^-1 1 / (1' C^-1 1)`` (``C`` the delete-one-block covariance of the two
    estimates: they share every pixel); the combined SE is the jackknife SE of the weighted
    sum. One estimate alone when the other is missing (log data) or ``C`` is singular.
    """
    keys = ("inverse_density_contrast", "inverse_density_log")
    est = np.array([whole[k] for k in keys], dtype=float)
    reps = np.array([[j[k] for k in keys] for j in jack], dtype=float)
    n = len(jack)
    ok = np.isfinite(est) & np.all(np.isfinite(reps), axis=0)
    dev = reps - reps.mean(axis=0)
    if ok.all():
        cov = (n - 1) / n * dev.T @ dev
        if np.linalg.cond(cov) < 1e12:
            w = np.linalg.solve(cov, np.ones(2))
            w = w / w.sum()
            comb = reps @ w
            se = float(np.sqrt((n - 1) / n * np.sum((comb - comb.mean()) ** 2)))
            return (
                float(est @ w),
                se,
                (f"contrast and var ln I combined, weights {w[0]:.3f} and {w[1]:.3f}"),
            )
    i = int(np.flatnonzero(ok)[0]) if ok.any() else 0
    se = float(np.sqrt((n - 1) / n * np.sum(dev[:, i] ** 2)))
    how = "contrast only" if i == 0 else "var ln I only"
    if i == 0 and not ok[1]:
        how += " (var ln I not observed: log data with unknown gain)"
    return float(est[i]), se, how
