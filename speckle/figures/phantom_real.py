"""Phantoms fitted to measured images (results/phantom/real/): the study and its figure.

:func:`phantom_real_data` loads one image of the pipeline's ``phantom_real.images`` section and
runs :func:`speckle.real_tissue_phantom` on it; :func:`plot_phantom_real` draws the measured scan
beside the fitted phantom's, their speckle-contrast maps, the row-mean profiles with the
residual, and the metrics of measured against fitted beside the floor of the fit's re-scans.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..io import load_image
from ..studies.phantom.real import real_tissue_phantom
from .style import colorbar, legend_outside, new_figure, physical_image

__all__ = ["phantom_real_data", "plot_phantom_real"]


def phantom_real_data(
    image: Mapping, *, seeds, per_cell: float, max_layers: int, variant: str
) -> xr.Dataset:
    """The study of one image (keys of a ``phantom_real.images`` entry; module docstring)."""
    da = load_image(
        image["image"],
        kind=image["kind"],
        pixel_size=image.get("pixel_size"),
        pitch=image.get("pitch"),
        dims=None if image.get("dims") is None else tuple(image["dims"]),
    )
    lo, hi = image["lines"]
    ds = real_tissue_phantom(
        da.isel(x=slice(int(lo), int(hi))),
        tuple(image["rows"]),
        noise_rows=tuple(image["noise_rows"]),
        seeds=tuple(int(s) for s in seeds),
        beam_radius=image.get("beam_radius"),
        per_cell=float(per_cell),
        max_layers=int(max_layers),
        variant=variant,
    )
    ds.attrs["lines"] = [int(lo), int(hi)]
    return ds


def plot_phantom_real(ds: xr.Dataset) -> Figure:
    """Measured and fitted scans (same 51 dB window), their SC maps, the row-mean profiles
    (measured, fitted, the fit's rows shaded) and MS-SSIM of measured vs fitted against the
    floor (fit vs fit), means with 2 SE bars."""
    fig, axes = new_figure(2, 3, width=13.0, height=6.0)
    depth, x = ds.depth.values, ds.x.values
    hi = float(max(ds.measured.max(), ds.fitted.max()))
    for ax, img, title in (
        (axes[0, 0], ds.measured, "measured (51 dB window from its noise)"),
        (axes[0, 1], ds.fitted.isel(seed=0), f"fitted phantom, seed {int(ds.seed[0])}"),
    ):
        physical_image(ax, img, depth, x, xlabel="x (µm)", cmap="gray", vmin=0, vmax=hi)
        ax.set_title(title)
    colorbar(fig, axes[0, 1].images[-1], axes[0, :2].tolist(), "8-bit level")
    for ax, name in ((axes[1, 0], "measured_SC"), (axes[1, 1], "fitted_SC")):
        physical_image(ax, ds[name], depth, x, xlabel="x (µm)", cmap="magma", vmin=0, vmax=1.5)
        ax.set_title(name.replace("_", " "))
    colorbar(fig, axes[1, 1].images[-1], axes[1, :2].tolist(), "speckle contrast SC")
    ax = axes[0, 2]
    ax.plot(depth, ds.profile_measured, "k", lw=1, label="measured")
    ax.plot(depth, ds.profile_fitted, "r", lw=1, label="fitted (mean of seeds)")
    a, b = ds.attrs["fitted_rows"]
    ax.axvspan(depth[a], depth[b - 1], color="0.9", label="rows fitted")
    ax.set_xlabel("depth (µm)")
    ax.set_ylabel("row-mean level (dB re window top)")
    legend_outside(ax)
    ax = axes[1, 2]
    maps = list(ds["map"].values)
    pos = np.arange(len(maps))
    for off, name, colour, label in (
        (-0.15, "versus", "r", "measured vs fitted"),
        (0.15, "floor", "0.4", "floor: fitted vs fitted"),
    ):
        v = ds[f"MS-SSIM_{name}"]
        dim = "seed" if name == "versus" else "pair"
        mean = v.mean(dim).values
        se = v.std(dim, ddof=1).values / np.sqrt(v.sizes[dim])
        ax.errorbar(pos + off, mean, yerr=2 * se, fmt="o", color=colour, label=label)
    if not np.isfinite(ds["MS-SSIM_versus"].values).any():
        ax.text(0.5, 0.5, "MS-SSIM undefined: it needs images of\nat least 176 pixels a side "
                f"(these: {ds.sizes['depth']} x {ds.sizes['x']})", transform=ax.transAxes,
                ha="center", va="center")  # fmt: skip
    ax.set_xticks(pos, maps)
    ax.set_xlabel("map (the challenge's four)")
    ax.set_ylabel("MS-SSIM")
    legend_outside(ax)
    return fig
