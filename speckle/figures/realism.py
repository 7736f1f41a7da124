"""Realism figures: the measured image against the model effect by effect, and a showcase.

:func:`realism_dataset` / :func:`plot_realism` draw :func:`speckle.analysis.realism.realism_study`
(autocorrelations along depth and across A-lines, the misfit score of each step and of the full
model without each effect). :func:`showcase_dataset` / :func:`plot_showcase` image a layered
phantom with an inclusion under the pure model and with attenuation, roll-off and noise, in dB.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from ..analysis.realism import EFFECTS, realism_study
from ..imaging.bscan import bscan
from ..scene.scatterers import random_scatterers
from ..system.attenuation import attenuate_regions
from ..system.backscatter import backscatter_regions
from ..system.noise import add_noise
from ..system.rolloff import rolloff
from ..system.source import spectrum
from ._style import new_figure

__all__ = ["phantom_labels", "plot_realism", "plot_showcase", "realism_dataset", "showcase_dataset"]

#: Region labels of the showcase phantom, in the order of the config's ``regions``.
REGIONS = ("air", "top", "bottom", "inclusion")


def realism_dataset(
    measured: xr.DataArray | None, air: xr.DataArray | None, cfg: Mapping, seed: int, reason: str
) -> xr.Dataset:
    """Run the realism study from the pipeline's ``realism`` config section."""
    ds = realism_study(
        measured,
        air,
        pixel_size=cfg["pixel_size"],
        n_pixels=cfg["n_pixels"],
        n_alines=cfg["n_alines"],
        density=cfg["density"],
        k0_dk=cfg["k0_dk"],
        max_lag=cfg["max_lag"],
        n_blocks=cfg["n_blocks"],
        phase=dict(cfg["phase"]),
        fallback=dict(cfg["fallback"]),
        seed=seed,
    )
    ds.attrs["measured"] = (
        measured.attrs.get("source", "yes") if measured is not None else f"none: {reason}"
    )
    return ds


def plot_realism(ds: xr.Dataset):
    """Autocorrelations (depth, lateral) and the misfit of each model; model only without data."""
    have = "measured_autocorrelation" in ds
    fig, axes = new_figure(1, 3 if have else 2, width=10.0 if have else 7.0, height=3.2)
    lags = ds.lag.values
    for ax, axis in zip(axes[0], ("depth", "lateral"), strict=False):
        for step in ds.step.values:
            ax.plot(
                lags,
                ds.cumulative_autocorrelation.sel(step=step, axis=axis),
                lw=0.7,
                alpha=0.5,
                label=str(step),
            )
        ax.plot(
            lags,
            ds.model_autocorrelation.sel(axis=axis),
            "k-",
            lw=2,
            label="final model",
        )
        if have:
            ax.errorbar(
                lags,
                ds.measured_autocorrelation.sel(axis=axis),
                yerr=2 * ds.measured_autocorrelation_se.sel(axis=axis),
                fmt="ro",
                ms=3,
                label="measured (2 SE)",
            )
        ax.set(
            xlabel="lag (pixels)" if axis == "depth" else "lag (A-lines)",
            ylabel="intensity autocorrelation",
            title=f"{axis} autocorrelation",
        )
        ax.axhline(0, color="0.7", lw=0.5)
    axes[0, 0].legend(fontsize=5, ncol=2)
    if not have:
        axes[0, 1].text(
            0.02,
            0.98,
            f"measured image {ds.attrs['measured']}",
            transform=axes[0, 1].transAxes,
            va="top",
            fontsize=6,
            wrap=True,
        )
        return fig
    ax = axes[0, 2]
    y = np.arange(len(EFFECTS))
    ax.barh(y + 0.2, ds.dropped_score, height=0.4, label="full model without it")
    ax.barh(y - 0.2, ds.cumulative_score.values[1:], height=0.4, label="added (cumulative)")
    full = float(ds.cumulative_score.isel(step=-1))
    ax.axvline(full, color="k", lw=0.8, label=f"full model {full:.1f}")
    ax.axvline(full + 2, color="k", ls=":", lw=0.8, label="needed threshold")
    ax.set_yticks(
        y,
        [f"{e}{' *' if bool(ds.needed.sel(effect=e)) else ''}" for e in EFFECTS],
    )
    ax.set(
        xlabel="misfit score (largest deviation in combined SE)",
        title=f"needed (*): {ds.attrs['final_effects']}",
    )
    ax.legend(fontsize=5)
    return fig


def phantom_labels(
    n_pixels: int, pixel_size: float, n_alines: int, pitch: float, cfg: Mapping, oversample: int = 4
) -> xr.DataArray:
    """Label image ``(depth, x)``: air, top layer, bottom layer and an elliptic inclusion.

    The depth grid is ``oversample`` times finer than the pixels (for the attenuation path
    integral); ``cfg`` gives ``surface`` and ``interface`` depths and the inclusion's ``centre``
    and ``radii`` (depth, lateral), all in µm.
    """
    dz = pixel_size / oversample
    depth = np.arange(n_pixels * oversample) * dz
    x = np.arange(n_alines) * pitch
    zz, xx = np.meshgrid(depth, x, indexing="ij")
    lab = np.where(zz < cfg["surface"], 0, np.where(zz < cfg["interface"], 1, 2))
    (cz, cx), (rz, rx) = cfg["inclusion"]["centre"], cfg["inclusion"]["radii"]
    lab = np.where(((zz - cz) / rz) ** 2 + ((xx - cx) / rx) ** 2 < 1, 3, lab)
    return xr.DataArray(
        lab.astype(int),
        dims=("depth", "x"),
        coords={"depth": ("depth", depth, {"units": "um"}), "x": ("x", x, {"units": "um"})},
        name="label",
        attrs={"regions": ",".join(REGIONS)},
    )


def showcase_dataset(cfg: Mapping, seed: int) -> xr.Dataset:
    """The layered phantom under the pure model and with the system effects, in dB."""
    n, p, nl = cfg["n_pixels"], cfg["pixel_size"], cfg["n_alines"]
    h = n * p
    labels = phantom_labels(n, p, nl, p, cfg)
    props = xr.Dataset(
        {
            k: ("region", [float(cfg["regions"][r][k]) for r in REGIONS])
            for k in ("backscatter", "attenuation")
        },
        coords={"region": np.arange(len(REGIONS)), "name": ("region", list(REGIONS))},
    )
    src = spectrum(n, h, k0_dk=cfg["k0_dk"], shape="gaussian", fwhm_fraction=cfg["fwhm_fraction"])
    scene = random_scatterers(nl, cfg["density"], n_pixels=n, depth=h, seed=seed, aline_pitch=p)
    scene = backscatter_regions(scene, labels, props)
    pure = bscan(scene, src, method="nufft", tol=1e-9)
    sys_scene = rolloff(attenuate_regions(scene, labels, props), z_max=cfg["rolloff_z_max"])
    system = bscan(sys_scene, src, method="nufft", tol=1e-9)
    ref = float(pure.intensity.where(labels.isel(depth=slice(None, None, 4)).values > 0).mean())
    system = add_noise(system, cfg["snr_db"], seed=seed, signal_intensity=ref)

    def db(img):
        return (10 * np.log10(img.intensity / ref)).assign_attrs(units="dB re mean tissue")

    return xr.Dataset(
        {
            "pure_db": db(pure),
            "system_db": db(system),
            "label": labels.isel(depth=slice(None, None, 4))
            .rename(x="aline")
            .assign_coords(depth=pure.depth.values, aline=pure.aline.values),
            "attenuation": props.attenuation.assign_attrs(units="1/um"),
            "backscatter": props.backscatter.assign_attrs(units="1"),
        },
        attrs={
            "snr_db": float(cfg["snr_db"]),
            "rolloff_z_max": float(cfg["rolloff_z_max"]),
            "focus": "not modelled (independent A-lines; the beam focus comes with the beam issue)",
        },
    )


def plot_showcase(ds: xr.Dataset, dynamic_range: float = 40.0):
    """Pure model beside the model with system effects, same dB scale."""
    fig, axes = new_figure(1, 2, width=7.0, height=3.4)
    extent = [ds.aline.values[0], ds.aline.values[-1], ds.depth.values[-1], ds.depth.values[0]]
    for ax, var, title in zip(
        axes[0],
        ("pure_db", "system_db"),
        ("pure model", f"attenuation + roll-off + noise ({ds.attrs['snr_db']:g} dB)"),
        strict=True,
    ):
        im = ax.imshow(
            ds[var], cmap="gray", vmin=-dynamic_range + 10, vmax=10, extent=extent, aspect="auto"
        )
        ax.contour(ds.aline, ds.depth, ds.label, levels=[0.5, 1.5, 2.5], colors="y", linewidths=0.4)
        ax.set(xlabel="x (µm)", ylabel="depth (µm)", title=title)
    fig.colorbar(im, ax=axes[0, 1], label="dB re mean tissue intensity")
    return fig
