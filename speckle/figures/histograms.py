"""Figs. 3 and 4: amplitude/intensity histograms, their fits and the measured image.

Data builders return the dataset a figure is drawn from (written to NetCDF by the pipeline);
``plot_*`` functions draw it. Fig. 3 sweeps the scatterer density with
:func:`speckle.sweep.sweep`; Fig. 4 compares density-4 speckle with a measured B-scan through
gain- and offset-free statistics of the log intensity (:mod:`speckle.analysis.measured`).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from scipy import stats

from ..analysis import measured as meas
from ..analysis.statistics import (
    contrast_standard_error,
    contrast_theory,
    exponential_pdf,
    fit_exponential,
    fit_rayleigh,
    histogram,
    rayleigh_pdf,
)
from ..conventions import attrs
from ..imaging._bscan import expected_intensity
from ..sweep import sweep
from ..system.detection import add_floor
from ._config import random_bscan
from .style import new_figure

__all__ = [
    "density_histograms",
    "density_point",
    "fig4_dataset",
    "measured_panels",
    "plot_density_histograms",
    "plot_fig4",
    "simulate_speckle",
    "simulated_panels",
]

log = logging.getLogger(__name__)


def _fit_vars(fit: xr.Dataset, prefix: str) -> dict:
    return {f"{prefix}_{k}": v for k, v in fit.data_vars.items()}


def simulate_speckle(
    density: float,
    *,
    n_alines: int,
    k0_dk: float,
    seed: int,
    n_pixels: int,
    pixel_size: float,
    shape: str = "rectangular",
    fwhm_fraction: float | None = None,
    method: str = "direct",
    normalise: str = "none",
) -> tuple[xr.Dataset, xr.DataArray]:
    """B-scan of equal-amplitude scatterers (fixed count) and its source spectrum.

    Parameters
    ----------
    density : float
        Scatterers per pixel ``N_sc/N``.
    n_alines, seed : int
        Independent A-lines and the root seed.
    k0_dk, n_pixels, pixel_size, shape, fwhm_fraction
        Source, as the pipeline's ``source`` config (pixel size in µm).
    method : str
        A-scan method (:data:`speckle.ASCAN_METHODS`).
    normalise : {"none", "density", "expected"}
        See :func:`speckle.imaging.bscan`.
    """
    source = {"n_pixels": n_pixels, "pixel_size": pixel_size, "k0_dk": k0_dk, "shape": shape}
    source["fwhm_fraction"] = fwhm_fraction
    return random_bscan(
        source, density, n_alines=n_alines, seed=seed, method=method, normalise=normalise
    )


def density_point(
    density: float,
    *,
    normalise: str = "density",
    bins: int = 60,
    amplitude_max: float = 3.5,
    **scene,
) -> xr.Dataset:
    """Amplitude histogram, Rayleigh fit and contrast (measured and theory) at one density.

    The histogram covers ``[0, amplitude_max * sqrt(<I>))`` where ``<I>`` is the expected
    intensity at density 1 under ``normalise="density"`` (``N * sum S^2``), so all densities
    share the bins. ``scene`` holds the keyword arguments of :func:`simulate_speckle`.
    Returns scalars and ``amplitude_density`` (dim ``bin``).
    """
    ds, src = simulate_speckle(density, normalise=normalise, **scene)
    n_pixels = int(src.attrs["n_pixels"])
    ref = np.sqrt(expected_intensity(1.0, n_pixels, src.values))
    hist = histogram(ds.amplitude, bins, range=(0.0, amplitude_max * ref))
    c, se = contrast_standard_error(ds.intensity)
    out = xr.Dataset(
        {
            "amplitude_density": hist,
            "contrast": ((), c, attrs("contrast")),
            "contrast_se": (
                (),
                se,
                attrs(
                    "contrast",
                    "standard error of the contrast (delta method over independent A-lines)",
                ),
            ),
            "contrast_theory": (
                (),
                contrast_theory(density, n_pixels, src.values),
                attrs("contrast", "contrast theory, fixed count"),
            ),
            **_fit_vars(fit_rayleigh(ds.amplitude), "rayleigh"),
        }
    )
    return out


def density_histograms(
    densities, *, dask: Mapping | None = None, progress: bool = False, **options
) -> xr.Dataset:
    """Fig. 3 data: :func:`density_point` for every density, run with :func:`speckle.sweep`.

    ``options`` are the keyword arguments of :func:`density_point` (all but ``density``);
    ``dask`` is the pipeline's ``dask`` config (scheduler, address, n_workers).

    The shared Rayleigh curve of the paper is the fit at the largest density
    (``rayleigh_sigma_shared``; the per-density fits are kept as ``rayleigh_sigma``).
    """
    fixed = dict(options)
    ds = sweep(
        density_point,
        {"density": list(densities)},
        fixed=fixed,
        progress=progress,
        **dict(dask or {}),
    )
    ds["density"].attrs.update(attrs("density", "density N_sc/N"))
    shared = ds.rayleigh_sigma.sel(density=ds.density.max())
    ds["rayleigh_sigma_shared"] = (
        (),
        float(shared),
        attrs("amplitude", "Rayleigh sigma shown in every panel (fit at the largest density)"),
    )
    ds.attrs.update({k: ("none" if v is None else v) for k, v in fixed.items()})
    return ds


def plot_density_histograms(ds: xr.Dataset) -> Figure:
    """Fig. 3: one panel per density, bars = histogram, line = the shared Rayleigh fit."""
    nd = ds.sizes["density"]
    ncols = 3
    fig, axes = new_figure(int(np.ceil(nd / ncols)), ncols, width=7.0, height=4.2)
    sigma = float(ds.rayleigh_sigma_shared)
    x = ds.bin.values
    for ax, rho in zip(axes.flat, ds.density.values, strict=False):
        p = ds.sel(density=rho)
        _stairs(ax, p.amplitude_density)
        ax.plot(
            x,
            rayleigh_pdf(x, sigma),
            "k-",
            lw=1.2,
            label=f"Rayleigh fit shared by all densities, σ = {sigma:.3g}",
        )
        ax.set_title(
            f"N_sc/N = {rho:g}\nC = {float(p.contrast):.3f} ± "
            f"{float(p.contrast_se):.3f} (theory {float(p.contrast_theory):.3f})"
        )
        ax.set_xlabel("amplitude / sqrt(density)")
        ax.set_ylabel("probability density")
    for ax in axes.flat[nd:]:
        ax.set_visible(False)
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="outside lower center", frameon=False)
    return fig


# --- Fig. 4 ------------------------------------------------------------------------------


def simulated_panels(
    density: float,
    *,
    floor: float | None = None,
    bins: int = 60,
    intensity_max: float = 8.0,
    amplitude_max: float = 3.0,
    z_range: tuple = (-5.0, 3.0),
    **scene,
) -> xr.Dataset:
    """Fig. 4 upper row: histograms and fits of simulated speckle, ``<I> = 1`` normalisation.

    ``floor`` (in units of ``<I>``, off by default) adds the intensity floor that explains the
    measured departure (:func:`speckle.system.detection.add_floor`). ``scene`` holds the keyword
    arguments of :func:`simulate_speckle`; ``z_range`` is the standardised log-intensity axis.
    """
    ds, src = simulate_speckle(density, normalise="expected", **scene)
    n_pixels = int(src.attrs["n_pixels"])
    intensity = ds.intensity
    if floor:
        intensity = add_floor(intensity, floor, mean_intensity=1.0)
    amplitude = np.sqrt(intensity)
    logi = np.log(intensity.where(intensity > 0))
    zs = ((logi - logi.mean()) / logi.std()).fillna(z_range[0] - 1.0)
    c, se = contrast_standard_error(intensity)
    return xr.Dataset(
        {
            "sim_intensity_density": histogram(intensity, bins, (0.0, intensity_max)).rename(
                bin="intensity_bin", bin_lower="intensity_lower", bin_upper="intensity_upper"
            ),
            "sim_amplitude_density": histogram(amplitude, bins, (0.0, amplitude_max)).rename(
                bin="amplitude_bin", bin_lower="amplitude_lower", bin_upper="amplitude_upper"
            ),
            "sim_log_density": histogram(zs, bins, z_range).rename(
                bin="z_bin", bin_lower="z_lower", bin_upper="z_upper"
            ),
            "sim_contrast": ((), c, attrs("contrast")),
            "sim_contrast_se": ((), se, attrs("contrast", "standard error of the contrast")),
            # a floor b adds b to <I> = 1 and leaves Var I unchanged: C -> C/(1 + b)
            "sim_contrast_theory": (
                (),
                contrast_theory(density, n_pixels, src.values) / (1.0 + (floor or 0.0)),
                attrs("contrast", "contrast theory, fixed count, with the floor"),
            ),
            **_fit_vars(fit_exponential(intensity), "sim_exponential"),
            **_fit_vars(fit_rayleigh(amplitude), "sim_rayleigh"),
            "sim_log_skewness": (
                (),
                float(stats.skew(zs.values.ravel())),
                attrs("dimensionless", "skewness of the standardised log intensity"),
            ),
            "sim_log_excess_kurtosis": (
                (),
                float(stats.kurtosis(zs.values.ravel())),
                attrs("dimensionless", "excess kurtosis of the standardised log intensity"),
            ),
        },
        attrs={
            "density": density,
            "n_alines": ds.sizes["x"],
            "floor": floor or 0.0,
            "normalisation": "expected (<I> = 1)",
        },
    )


def measured_panels(image: xr.DataArray, sim: xr.Dataset) -> xr.Dataset:
    """Fig. 4 lower row from a measured ROI, on the same bins as the simulated panels.

    The gain- and offset-free comparison is the standardised log-intensity histogram (with its
    skewness and excess kurtosis) against ``ln Exp(1)`` and the fitted floor law. The intensity
    and amplitude panels linearise the data with the floor fit's gain and offset,
    ``I/<I> = exp((D - c)/g)`` (this step assumes the floor model).
    """
    cmp_ = meas.compare_measured(image)
    d = meas.log_intensity(image)
    lin = np.exp((d - float(cmp_.offset)) / float(cmp_.gain)).assign_attrs(
        attrs("dimensionless", "intensity / <I>, linearised with the floor fit")
    )
    zs = meas.standardise(image)

    def level_bins(values, edges, name):
        # one bin per quantisation level of the data: no comb artefacts in linear units
        return histogram(values, edges).rename(
            bin=f"measured_{name}_bin",
            bin_lower=f"measured_{name}_lower",
            bin_upper=f"measured_{name}_upper",
        )

    if image.attrs.get("clip_high") is not None:
        levels = np.arange(float(d.min()) - 0.5, float(d.max()) + 1.0)
    else:
        levels = np.linspace(float(d.min()), float(d.max()), 61)
    lin_edges = np.exp((levels - float(cmp_.offset)) / float(cmp_.gain))
    edges = np.append(sim.z_lower.values, sim.z_upper.values[-1])
    out = xr.Dataset(
        {
            "measured_intensity_density": level_bins(lin, lin_edges, "intensity"),
            "measured_amplitude_density": level_bins(np.sqrt(lin), np.sqrt(lin_edges), "amplitude"),
            "measured_log_density": histogram(zs, edges).rename(
                bin="z_bin", bin_lower="z_lower", bin_upper="z_upper"
            ),
            **{f"measured_{k}": v for k, v in cmp_.data_vars.items()},
            **_fit_vars(fit_exponential(lin), "measured_exponential"),
            **_fit_vars(fit_rayleigh(np.sqrt(lin)), "measured_rayleigh"),
        }
    )
    out["floor_log_pdf"] = meas.standardised_log_pdf(out.z_bin, float(cmp_.floor))
    out.attrs = {f"measured_{k}": v for k, v in cmp_.attrs.items()}
    return out


def fig4_dataset(sim: xr.Dataset, image: xr.DataArray | None, reason: str = "") -> xr.Dataset:
    """Fig. 4 data: simulated panels, theory curves and (if given) the measured panels."""
    ds = sim.copy()
    ds["gumbel_log_pdf"] = meas.standardised_log_pdf(ds.z_bin, 0.0).assign_attrs(
        attrs("dimensionless", "standardised ln Exp(1) density (fully developed speckle)")
    )
    ds.attrs["compared"] = (
        "standardised log-intensity histogram, skewness and excess "
        "kurtosis (free of the unknown log gain and offset)"
    )
    if image is None:
        ds.attrs["measured"] = f"not available: {reason}"
        return ds
    mp = measured_panels(image, sim)
    merged = {**ds.attrs, **mp.attrs}
    ds = xr.merge([ds, mp], compat="override", join="outer", combine_attrs="override")
    ds.attrs = merged
    ds.attrs["measured"] = "available"
    return ds


def _stairs(ax, density: xr.DataArray, **kw) -> None:
    """Draw a histogram DataArray (from ``statistics.histogram``) as filled steps."""
    (dim,) = density.dims
    lower = [c for c in density.coords if c.endswith("_lower") and density[c].dims == (dim,)]
    upper = [c for c in density.coords if c.endswith("_upper") and density[c].dims == (dim,)]
    edges = np.append(density[lower[0]].values, density[upper[0]].values[-1])
    ax.stairs(density.values, edges, fill=True, color="0.75", **kw)


def plot_fig4(ds: xr.Dataset) -> Figure:
    """Fig. 4: rows simulated / measured; columns intensity (log y), amplitude, log intensity."""
    fig, axes = new_figure(2, 3, width=10.0, height=4.8)
    have = ds.attrs.get("measured") == "available"
    rows = [("sim", f"simulated, N_sc/N = {ds.attrs.get('density', np.nan):g}")]
    rows.append(("measured", "measured ROI") if have else (None, ds.attrs.get("measured")))
    for r, (pre, label) in enumerate(rows):
        ax_i, ax_a, ax_z = axes[r]
        if pre is None:
            for ax in axes[r]:
                ax.axis("off")
            fig.text(0.5, 0.25, f"measured image {label}", ha="center", va="center")
            continue
        x = ds.intensity_bin.values
        _stairs(ax_i, ds[f"{pre}_intensity_density"], label=f"{label.split(',')[0]} histogram")
        mean = float(ds[f"{pre}_exponential_mean"])
        ax_i.plot(
            x, exponential_pdf(x, mean), "k--", lw=1, label=f"exponential fit, <I> = {mean:.3g}"
        )
        ax_i.set_yscale("log")
        ax_i.set_xlabel("intensity / <I>")
        ax_a.set_ylabel("probability density")
        ax_i.set_xlim(0, float(ds.intensity_upper[-1]))
        ax_a.set_xlim(0, float(ds.amplitude_upper[-1]))
        ax_i.set_ylabel(f"{label}\nprobability density")
        x = ds.amplitude_bin.values
        _stairs(ax_a, ds[f"{pre}_amplitude_density"])
        sigma = float(ds[f"{pre}_rayleigh_sigma"])
        ax_a.plot(x, rayleigh_pdf(x, sigma), "k-.", lw=1, label=f"Rayleigh fit, σ = {sigma:.3g}")
        ax_a.set_xlabel("amplitude / sqrt(<I>)")
        x = ds.z_bin.values
        _stairs(ax_z, ds[f"{pre}_log_density"])
        ax_z.plot(
            x, ds.gumbel_log_pdf, "k-", lw=1, label="ln Exp(1): skewness -1.14, excess kurtosis 2.4"
        )
        if pre == "measured":
            ax_z.plot(
                x,
                ds.floor_log_pdf,
                "r--",
                lw=1,
                label=f"ln(Exp(1) + {float(ds.measured_floor):.4f}): with the fitted floor",
            )
            skew, kurt = float(ds.measured_skewness), float(ds.measured_excess_kurtosis)
        else:
            skew, kurt = float(ds.sim_log_skewness), float(ds.sim_log_excess_kurtosis)
        ax_z.set_yscale("log")
        ax_z.set_ylim(1e-4, 1)
        ax_z.set_xlabel("standardised log intensity")
        ax_z.set_ylabel("probability density")
        ax_z.set_title(f"skewness {skew:.3f}, excess kurtosis {kurt:.3f}")
        handles, labels = [], []
        for ax in (ax_i, ax_a, ax_z):
            h, lab = ax.get_legend_handles_labels()
            handles += h
            labels += lab
        ax_z.legend(handles, labels, loc="center left", bbox_to_anchor=(1.03, 0.5), frameon=False)
    if have:
        axes[1, 0].set_title("linearised with the floor fit's gain and offset")
    return fig
