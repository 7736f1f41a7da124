"""The scanner's twin (results/twin/): fit, measured against twin, predicted failure maps.

:func:`twin_datasets` runs :func:`speckle.studies.twin.fit_system` on the image named in the
pipeline's ``twin`` config section and returns the three datasets the rule writes;
:func:`plot_compare` and :func:`plot_failure` draw them (the failure maps as the elastography
failure maps' strain column: rms error over strain, and the answered fraction).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..io import load_image
from ..studies.twin.fit import fit_system
from ..studies.twin.system_fit import SystemFit
from .style import ESTIMATOR_NAMES, colorbar, estimator_colour, new_figure, physical_image

__all__ = ["fit_from_config", "plot_compare", "plot_failure", "twin_datasets"]


def fit_from_config(cfg: Mapping) -> tuple[xr.DataArray, SystemFit]:
    """Load ``cfg["image"]`` and fit it (keys as in the config's ``twin`` section)."""
    image = load_image(
        cfg["image"],
        kind=cfg["kind"],
        pixel_size=cfg.get("pixel_size"),
        pitch=cfg.get("pitch"),
        dims=None if cfg.get("dims") is None else tuple(cfg["dims"]),
        variable=cfg.get("variable"),
    )
    fit = fit_system(
        image,
        k0=cfg.get("k0"),
        refractive_index=cfg.get("refractive_index", 1.0),
        region=cfg.get("region"),
        noise_rows=cfg.get("noise_rows"),
        snr_db=cfg.get("snr_db"),
        n_pixels=cfg["n_pixels"],
        max_lag=cfg["max_lag"],
        n_blocks=cfg["n_blocks"],
        n_bands=cfg["n_bands"],
    )
    return image, fit


def twin_datasets(cfg: Mapping, seed: int) -> tuple[xr.Dataset, xr.Dataset, xr.Dataset]:
    """``(fit, compare, failure)`` datasets of the config's image (module docstring)."""
    image, fit = fit_from_config(cfg)
    fc = cfg["failure"]
    failure = fit.failure_maps(
        strains=[float(s) for s in fc["strains"]],
        methods=list(fc["methods"]),
        shape=tuple(fc["shape"]),
        window=None if fc.get("window") is None else tuple(fc["window"]),
        seed=seed,
    )
    return fit.parameters, fit.compare(image, seed=seed), failure


def plot_compare(ds: xr.Dataset) -> Figure:
    """Image panels (physical aspect ratio), autocorrelations (2 SE bars), log-data histograms
    and depth profiles: measured (black) against twin (red), one legend right of the panels."""
    fig, axes = new_figure(2, 3, width=11.0, height=5.6)
    for ax, name in zip(axes[0, :2], ("measured", "twin"), strict=True):
        img = ds[f"{name}_image"]
        lo, hi = np.percentile(ds["measured_image"], [1, 99])
        physical_image(
            ax, img, ds.depth.values, ds.x.values, xlabel="x (µm)", cmap="gray", vmin=lo, vmax=hi
        )
        ax.set_title(f"{name} region")
    colorbar(fig, axes[0, 1].images[-1], axes[0, :2].tolist(), "log data (file's grey levels)")
    ax = axes[0, 2]
    for name, style in (("measured", "ko"), ("twin", "r-")):
        ax.plot(ds.bin, ds[f"{name}_log_histogram"], style, ms=2, lw=1)
    ax.set(
        xlabel="standardised log intensity",
        ylabel="probability density",
        title=f"log data: skewness z = {float(ds.z_skewness):.1f}, "
        f"kurtosis z = {float(ds.z_excess_kurtosis):.1f}",
    )
    for ax, axis in zip(axes[1, :2], ("depth", "lateral"), strict=True):
        for name, fmt in (("measured", "ko"), ("twin", "rs")):
            ax.errorbar(
                ds.lag + (0.1 if name == "twin" else 0.0),
                ds.autocorrelation.sel(source=name, axis=axis),
                yerr=2 * ds.autocorrelation_se.sel(source=name, axis=axis),
                fmt=fmt,
                ms=3,
                label=f"{name} (± 2 SE)",
            )
        ax.axhline(0, color="0.7", lw=0.5)
        ax.set(
            xlabel="lag (pixels)" if axis == "depth" else "lag (A-lines)",
            ylabel="intensity autocorrelation",
            title=f"{axis} autocorrelation",
        )
    ax = axes[1, 2]
    for name, fmt in (("measured", "ko"), ("twin", "rs")):
        ax.errorbar(
            ds.row,
            ds.mean_log_profile.sel(source=name),
            yerr=2 * ds.mean_log_profile_se.sel(source=name),
            fmt=fmt,
            ms=2,
        )
    ax.set(xlabel="row of the region", ylabel="mean ln I (minus its mean)", title="depth profile")
    fig.legend(*axes[1, 0].get_legend_handles_labels(), loc="outside right center", frameon=False)
    return fig


def plot_failure(ds: xr.Dataset) -> Figure:
    """rms error / strain and the answered fraction against strain, one line per estimator
    (colours of the elastography figures), one legend right of the panels."""
    fig, axes = new_figure(2, 1, width=5.6, height=5.0, sharex=True)
    s = ds.strain.values
    for m in ds.method.values:
        style = {"color": estimator_colour(m), "ms": 3, "lw": 0.8}
        label = ESTIMATOR_NAMES.get(str(m), str(m))
        axes[0, 0].plot(s, ds.rms_error.sel({"method": m}) / np.abs(s), "o-", label=label, **style)
        axes[1, 0].plot(s, ds.answered.sel({"method": m}), "o-", **style)
    axes[0, 0].axhline(1.0, color="k", ls=":", lw=0.7, label="error = strain")
    axes[0, 0].set(
        xscale="log",
        yscale="log",
        ylabel="rms strain error / strain",
        title="Strain estimators on the digital twin",
    )
    axes[1, 0].set(xscale="log", xlabel="interframe strain", ylabel="fraction of pixels answered")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside right center", frameon=False)
    return fig
