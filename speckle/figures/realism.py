"""Realism figures: the measured image against the model effect by effect, and a showcase.

:func:`realism_dataset` / :func:`plot_realism` draw :func:`speckle.studies.realism.realism_study`
(autocorrelations along depth and across A-lines, the misfit score of each step and of the full
model without each effect). :func:`showcase_dataset` / :func:`plot_showcase` image a layered
phantom with an inclusion under the pure model and with attenuation, roll-off and noise, in dB.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..conventions import attrs
from ..imaging.beam import beam_scan
from ..scene.regions import cell_density, ellipse, layer, make_regions, rasterize
from ..scene.shared import shared_scene
from ..studies.realism import EFFECTS, realism_study
from ..studies.twin.system_fit import SystemFit
from ..system._rolloff import rolloff
from ..system.attenuation import attenuate_regions
from ..system.noise import add_noise
from ._config import scene_kwargs, source_spectrum
from .style import colorbar, legend_outside, new_figure, physical_image

__all__ = [
    "phantom_regions",
    "plot_realism",
    "plot_showcase",
    "realism_dataset",
    "showcase_dataset",
]

#: Regions of the showcase phantom (labels 0, 1, 2; air above the surface is label -1).
REGIONS = ("top", "bottom", "inclusion")


def realism_dataset(
    measured: xr.DataArray | None,
    air: xr.DataArray | None,
    cfg: Mapping,
    seed: int,
    reason: str,
    fit: SystemFit | None = None,
) -> xr.Dataset:
    """Run the realism study from the pipeline's ``realism`` config section.

    ``fit``: the measured image's :func:`speckle.studies.twin.fit_system` (its effect
    parameters are used; ``None``: fitted from ``measured`` and ``air``).
    """
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
        fit=fit,
    )
    ds.attrs["measured"] = (
        measured.attrs.get("source", "yes") if measured is not None else f"none: {reason}"
    )
    return ds


#: Model effects (:data:`speckle.analysis.realism.EFFECTS`) in words.
EFFECT_NAMES = {
    "spectral_width": "spectral width",
    "beam": "Gaussian beam",
    "noise": "receiver noise",
    "floor": "intensity floor",
    "attenuation": "attenuation",
    "quantisation": "8-bit quantisation",
    "phase": "phase perturbation",
}


def _effect(name: str) -> str:
    return EFFECT_NAMES.get(name, name.replace("_", " "))


def _step(step: str) -> str:
    """A cumulative step (``pure``, ``+beam``) in words."""
    return "pure model" if step == "pure" else f"+ {_effect(step.lstrip('+'))}"


def plot_realism(ds: xr.Dataset) -> Figure:
    """Autocorrelations (depth, lateral) and the misfit of each model; model only without data."""
    have = "measured_autocorrelation" in ds
    fig, axes = new_figure(1, 3 if have else 2, width=11.0 if have else 8.0, height=3.4)
    lags = ds.lag.values
    steps = list(ds.step.values)
    cmap = plt.get_cmap("viridis")
    for ax, axis in zip(axes[0], ("depth", "lateral"), strict=False):
        for k, step in enumerate(steps):
            ax.plot(
                lags,
                ds.cumulative_autocorrelation.sel(step=step, axis=axis),
                lw=0.9,
                color=cmap(k / max(len(steps) - 1, 1)),
                label=_step(str(step)),
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
                label="measured (± 2 SE)",
            )
        ax.set(
            xlabel="depth lag (pixels)" if axis == "depth" else "lateral lag (A-lines)",
            ylabel="intensity autocorrelation",
            title=f"{axis} autocorrelation",
        )
        ax.axhline(0, color="0.7", lw=0.5)
    if not have:
        legend_outside(axes[0, 0], where="below", ncols=3)
        axes[0, 1].text(
            0.02,
            0.98,
            f"measured image {ds.attrs['measured']}",
            transform=axes[0, 1].transAxes,
            va="top",
            wrap=True,
        )
        return fig
    ax = axes[0, 2]
    y = np.arange(len(EFFECTS))
    ax.barh(y + 0.2, ds.dropped_score, height=0.4, label="full model without it")
    ax.barh(y - 0.2, ds.cumulative_score.values[1:], height=0.4, label="added (cumulative)")
    full = float(ds.cumulative_score.isel(step=-1))
    ax.axvline(full, color="k", lw=0.8, label=f"full model ({full:.1f})")
    ax.axvline(full + 2, color="k", ls=":", lw=0.8, label="threshold for 'needed'")
    ax.set_yticks(
        y,
        [f"{_effect(e)}{' *' if bool(ds.needed.sel(effect=e)) else ''}" for e in EFFECTS],
    )
    needed = [_effect(e) for e in str(ds.attrs["final_effects"]).split(",") if e]
    ax.set(
        xlabel="misfit score (largest deviation in combined SE)",
        ylabel="model effect",
        title="effects needed (*): " + (", ".join(needed) or "none"),
    )
    handles, labels = axes[0, 0].get_legend_handles_labels()
    more = ax.get_legend_handles_labels()
    fig.legend(
        handles + more[0], labels + more[1], loc="outside lower center", ncols=5, frameon=False
    )
    fig.suptitle("Measured image against the model, effect by effect")
    return fig


def phantom_regions(cfg: Mapping) -> xr.Dataset:
    """Regions of the showcase phantom: two layers below the surface and an elliptic inclusion.

    ``cfg`` gives ``surface``, ``interface`` and ``bottom`` depths, the inclusion's ``centre``
    and ``radii`` (depth, lateral) in µm, ``density`` (scatterers per pixel x pitch cell) and
    per region ``backscatter`` and ``attenuation`` (``mu_t``, 1/µm). Above the surface is no
    region (label -1: air, no scatterers, no attenuation).
    """
    rho = cell_density(cfg["density"], cfg["pixel_size"], cfg["pitch"])
    props = {r: dict(cfg["regions"][r]) for r in REGIONS}
    (cz, cx), (rz, rx) = cfg["inclusion"]["centre"], cfg["inclusion"]["radii"]
    return make_regions(
        layer(cfg["surface"], cfg["interface"], density=rho, **props["top"]),
        layer(cfg["interface"], cfg["bottom"], density=rho, **props["bottom"]),
        ellipse(cz, cx, rz, rx, density=rho, **props["inclusion"]),
    ).assign_coords(name=("region", list(REGIONS)))


def showcase_dataset(cfg: Mapping, seed: int) -> xr.Dataset:
    """The phantom under the pure model and with focus and system effects, in dB.

    A shared scene of :func:`phantom_regions` imaged by a scanned Gaussian beam
    (:func:`speckle.beam_scan`). Pure: the depth-independent beam of waist ``w0``, no system
    effect. System: the beam focused at ``focus`` (Rayleigh range ``k0 w0^2/2``), Beer-Lambert
    attenuation integrated through the regions (:func:`speckle.attenuate_regions` on a label
    image four times finer than the pixels in depth), the roll-off and white receiver noise.
    """
    grid = scene_kwargs(cfg)
    n, h = grid["n_pixels"], grid["depth_range"]
    p, nl, pitch, w0 = cfg["pixel_size"], cfg["n_lines"], cfg["pitch"], cfg["waist"]
    regions = phantom_regions(cfg)
    lines = np.arange(nl) * pitch
    margin = 5 * w0
    x_range = (lines[0] - margin, lines[-1] + margin)
    scene = shared_scene(regions, z_range=(0.0, h), x_range=x_range, seed=seed)
    src = source_spectrum(cfg, shape="gaussian")
    fine = np.arange(4 * n) * p / 4
    xl = np.arange(x_range[0], x_range[1] + pitch, pitch)
    labels = rasterize(regions, fine, xl)
    beam = {
        "lines": lines,
        "waist": w0,
        **grid,
        "k0": src.attrs["k0"],
        "spectrum": src.values,
        "method": cfg["method"],
        "tol": cfg["tol"],
    }

    def beam_image(sc, **kw):
        f = beam_scan(sc.z.values, sc.x.values, sc.amplitude.values, **beam, **kw)
        field = xr.DataArray(
            f.T, dims=("depth", "x"), coords={"depth": np.arange(n) * p, "x": lines}
        )
        return xr.Dataset({"field": field, "intensity": abs(field) ** 2})

    pure = beam_image(scene)
    sys_scene = rolloff(attenuate_regions(scene, labels, regions), z_max=cfg["rolloff_z_max"])
    system = beam_image(sys_scene, focus=cfg["focus"])
    tissue = rasterize(regions, pure.depth.values, lines).values >= 0
    ref = float(pure.intensity.where(tissue).mean())
    system = add_noise(system, cfg["snr_db"], seed=seed, signal_intensity=ref)

    def db(img):
        return (10 * np.log10(img.intensity / ref)).assign_attrs(
            attrs("level", "10 log10 intensity re mean tissue intensity")
        )

    label = rasterize(regions, pure.depth.values, lines)
    return xr.Dataset(
        {
            "pure_db": db(pure),
            "system_db": db(system),
            "label": label.drop_attrs(),
            "attenuation": regions.attenuation,  # units and long name from the regions table
            "backscatter": regions.backscatter,
        },
        attrs={
            "snr_db": float(cfg["snr_db"]),
            "rolloff_z_max": float(cfg["rolloff_z_max"]),
            "waist": float(w0),
            "focus": float(cfg["focus"]),
            "rayleigh_range": float(src.attrs["k0"] * w0**2 / 2),
            "scatterers": int(scene.sizes["scatterer"]),
        },
    )


def plot_showcase(ds: xr.Dataset, dynamic_range: float = 40.0) -> Figure:
    """Pure model beside the model with system effects, same dB scale."""
    fig, axes = new_figure(1, 2, width=7.0, height=3.4)
    for ax, var, title in zip(
        axes[0],
        ("pure_db", "system_db"),
        (
            "pure model (unfocused beam)",
            f"focus at {ds.attrs['focus']:g} µm + attenuation\n"
            f"+ roll-off + noise ({ds.attrs['snr_db']:g} dB)",
        ),
        strict=True,
    ):
        im = physical_image(
            ax,
            ds[var].values,
            ds.depth.values,
            ds.x.values,
            xlabel="x (µm)",
            cmap="gray",
            vmin=-dynamic_range + 10,
            vmax=10,
        )
        ax.contour(ds.x, ds.depth, ds.label, levels=[-0.5, 0.5, 1.5], colors="y", linewidths=0.4)
        ax.set_title(title)
    colorbar(fig, im, axes[0].tolist(), "intensity (dB re mean tissue intensity)")
    return fig
