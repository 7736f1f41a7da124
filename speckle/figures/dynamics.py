"""Speckle in time (results/dynamics/): the phantom's contrasts, g1 against theory, failure maps.

Builders turn the pipeline's ``dynamics`` config section into the studies of
:mod:`speckle.studies.dynamics` (``*_data(cfg, seed)``); ``plot_*`` draw them. Every target's
geometry is ``dynamics.geometry`` with the target's own ``geometry`` keys over it.
:func:`speckle.pipeline.dynamics_checks.check_dynamics_config` refuses at load what the jobs
would refuse (the key named).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..conventions import attrs, coord
from ..studies.dynamics import (
    contrast_floors,
    decorrelation_calibration,
    expected_contrast,
    flow_failure,
)
from ..studies.dynamics_series import g1_curves, phantom_series
from .style import mark_no_colorbar, new_figure

__all__ = [
    "calibration_data",
    "failure_data",
    "g1_data",
    "phantom_data",
    "plot_calibration",
    "plot_failure",
    "plot_g1",
    "plot_phantom",
    "target_geometry",
]

#: Words for the contrasts and their units (figure labels).
LABELS = {
    "speckle_variance": ("speckle variance", "var(I)/<I>²"),
    "decorrelation": ("amplitude decorrelation", "D"),
    "liv": ("log-intensity variance", "LIV (dB²)"),
}
#: Colours of the failure-map status codes (0 below the static floor, 1 measurable, 2 at the
#: noise floor).
STATUS = (
    ("#bdbdbd", "not told from static tissue"),
    ("#41ab5d", "velocity measurable"),
    ("#fd8d3c", "saturated (at the noise floor)"),
)


def target_geometry(cfg: Mapping, part: str | None = None) -> dict:
    """A target's geometry: ``dynamics.geometry`` with the target's own ``geometry`` keys
    (``part``: ``"g1"``, ``"failure"``, ``"calibration"``; None: the phantom's) over it."""
    geo = dict(cfg["geometry"])
    if part is not None:
        geo.update(cfg[part].get("geometry") or {})
    return geo


# --------------------------------------------------------------------------- builders
def g1_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """``results/dynamics/g1.nc``: :func:`speckle.studies.dynamics.g1_curves` of the config."""
    g = cfg["g1"]
    return g1_curves(
        target_geometry(cfg, "g1"),
        diffusion=g["diffusion"],
        velocity=g["velocity"],
        interval=g["interval"],
        n_frames=g["n_frames"],
        blocks=g["blocks"],
        snr_db=cfg["snr_db"],
        seed=seed,
    )


def phantom_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """``results/dynamics/phantom.nc``: the phantom's angiography and dOCT contrasts."""
    return phantom_series(target_geometry(cfg), cfg["phantom"], snr_db=cfg["snr_db"], seed=seed)


def failure_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """``results/dynamics/failure.nc``: :func:`speckle.studies.dynamics.flow_failure`."""
    f = cfg["failure"]
    return flow_failure(
        target_geometry(cfg, "failure"),
        velocities=f["velocities"],
        snr_db=f["snr_db"],
        intervals=f["intervals"],
        n_frames=f["n_frames"],
        window=tuple(f["window"]),
        repeats=f["repeats"],
        seed=seed,
        z=f["z"],
    )


def calibration_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """``results/dynamics/calibration.nc``: the decorrelation against velocity, its theory on
    a fine velocity grid (``theory_curve`` over ``velocity_fine``) and the two floors."""
    c = cfg["calibration"]
    geo = target_geometry(cfg, "calibration")
    ds = decorrelation_calibration(
        geo,
        velocities=c["velocities"],
        interval=c["interval"],
        snr_db=c["snr_db"],
        n_frames=c["n_frames"],
        repeats=c["repeats"],
        seed=seed,
    )
    from ..analysis.dynamics_theory import g1_transverse_flow

    fine = np.linspace(0.0, float(max(c["velocities"])), 200)
    curve = [
        expected_contrast(
            "decorrelation",
            g1_transverse_flow([c["interval"]], velocity=v, waist=geo["waist"]),
            snr_db=c["snr_db"],
        )
        for v in fine
    ]
    static, noise = contrast_floors("decorrelation", n_frames=2, snr_db=c["snr_db"])
    ds = ds.assign_coords(velocity_fine=coord("velocity", fine, dims="velocity_fine"))
    ds["theory_curve"] = ("velocity_fine", np.array(curve), attrs("dimensionless", "theory"))
    ds["static_floor_theory"] = ((), static, attrs("dimensionless", "static-tissue floor"))
    ds["noise_floor_theory"] = ((), noise, attrs("dimensionless", "noise floor"))
    return ds


# --------------------------------------------------------------------------- plots
def _mm(v: np.ndarray) -> np.ndarray:
    return np.asarray(v, float) / 1000.0


def plot_g1(ds: xr.Dataset) -> Figure:
    """Measured ``|g1|`` against lag with its standard error and theory, one panel per model."""
    models = [str(m) for m in ds.model.values]
    fig, axes = new_figure(1, len(models), width=3.4 * len(models), height=3.0)
    lag_ms = ds.lag.values * 1e3
    for ax, m in zip(axes[0], models, strict=True):
        sel = ds.sel(model=m)
        ax.errorbar(lag_ms, sel.g1, yerr=sel.g1_se, fmt="o", ms=3, capsize=2, label="measured ± SE")
        ax.plot(lag_ms, sel.g1_theory, "-", color="k", lw=1, label="theory")
        if m == "brownian":
            title = f"Brownian motion, D = {float(sel.diffusion):g} µm²/s"
        else:
            title = f"transverse flow, v = {float(sel.velocity) / 1000:g} mm/s"
        ax.set_title(title)
        ax.set_xlabel("lag τ (ms)")
        ax.set_ylabel("field autocorrelation |g1(τ)|")
        ax.set_ylim(-0.05, 1.05)
        ax.legend(loc="upper right", frameon=False)
    return fig


def plot_phantom(ds: xr.Dataset) -> Figure:
    """The phantom's regions, structure and contrast images (one colorbar per quantity)."""
    panels = [
        ("labels", "regions:\nlayers, cells, vessel", "region label", "tab10"),
        ("structure", "structure\n(mean intensity)", "dB re mean signal", "gray"),
        ("speckle_variance", "angiography:\nspeckle variance", "var(I)/<I>²", "magma"),
        ("ssada", "angiography:\nSSADA", "decorrelation D", "magma"),
        ("liv", "angiography: LIV\n(colour scale at right)", "LIV (dB²)", "viridis"),
        ("liv_doct", "dynamic OCT:\nLIV", "LIV (dB²)", "viridis"),
        ("ocds", "dynamic OCT:\nOCDS", "OCDS (1/s)", "viridis"),
    ]
    fig, axes = new_figure(2, 4, width=11.0, height=5.2)
    x, z = ds.x.values, ds.depth.values
    dx = x[1] - x[0] if x.size > 1 else 1.0
    dz = z[1] - z[0] if z.size > 1 else 1.0
    extent = (x[0] - dx / 2, x[-1] + dx / 2, z[-1] + dz / 2, z[0] - dz / 2)
    for k, (name, title, unit, cmap) in enumerate(panels):
        ax = axes.flat[k]
        values = ds[name].values
        if name == "labels":
            cmap = ListedColormap(["#9ecae1", "#3182bd", "#31a354", "#de2d26"])
            im = ax.imshow(values, extent=extent, cmap=cmap, vmin=-0.5, vmax=3.5, aspect="equal")
            bar = fig.colorbar(im, ax=ax, shrink=0.8, ticks=range(4))
            bar.ax.set_yticklabels(["layer 1", "layer 2", "cells", "vessel"])
        elif name == "structure":
            im = ax.imshow(values, extent=extent, cmap=cmap, aspect="equal")
            fig.colorbar(im, ax=ax, shrink=0.8, label=unit)
        else:
            # the two LIV panels share one scale and one colorbar (one quantity)
            same = ("liv", "liv_doct") if name.startswith("liv") else (name,)
            top = max(float(np.nanpercentile(ds[n].values, 99)) for n in same)
            im = ax.imshow(values, extent=extent, cmap=cmap, aspect="equal", vmin=0.0, vmax=top)
            if name != "liv":
                shared = [axes.flat[k - 1], ax] if name == "liv_doct" else ax
                fig.colorbar(im, ax=shared, shrink=0.8, label=unit)
        ax.set_title(title)
        ax.set_xlabel("x (µm)")
        ax.set_ylabel("depth (µm)")
    ax = axes.flat[7]
    names = ["speckle_variance", "ssada", "liv", "liv_doct", "ocds"]
    static = [float(ds[f"{n}_region"][:2].mean()) for n in names]
    width = 0.35
    idx = np.arange(len(names))
    for j, (r, label) in enumerate(((2, "cells"), (3, "vessel"))):
        ratio = [
            float(ds[f"{n}_region"][r]) / s if s > 0 else np.nan
            for n, s in zip(names, static, strict=True)
        ]
        ax.bar(idx + (j - 0.5) * width, ratio, width, label=label)
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_yscale("log")
    ax.set_xticks(idx, ["SV", "SSADA", "LIV", "LIV dOCT", "OCDS"], rotation=30)
    ax.set_xlabel("contrast (SV: speckle variance)")
    ax.set_ylabel("region mean / static layers' mean")
    ax.set_title("contrast of each moving region")
    ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), frameon=False)
    return fig


def _status_image(ax, status: np.ndarray, xlabels, ylabels, xname: str, yname: str) -> None:
    cmap = ListedColormap([c for c, _ in STATUS])
    # categories, told by the figure's legend of STATUS colours
    mark_no_colorbar(
        ax.imshow(status, origin="lower", cmap=cmap, vmin=-0.5, vmax=2.5, aspect="auto")
    )
    ax.set_xticks(range(len(xlabels)), xlabels, rotation=60)
    ax.set_yticks(range(len(ylabels)), ylabels)
    ax.set_xlabel(xname)
    ax.set_ylabel(yname)


def plot_failure(ds: xr.Dataset) -> Figure:
    """Failure maps of each contrast over velocity x SNR and velocity x interval, and the
    contrast against velocity with its SE, theory, floors and measurable range."""
    contrasts = [str(c) for c in ds.contrast.values]
    fig, axes = new_figure(3, len(contrasts), width=3.6 * len(contrasts), height=9.5)
    vel = ds.velocity.values
    vlab = [f"{v / 1000:g}" for v in vel]
    ji = int(ds.attrs.get("show_interval", ds.sizes["interval"] // 2))
    ks = int(ds.attrs.get("show_snr", ds.sizes["snr_db"] // 2))
    dt_ms = ds.interval.values[ji] * 1e3
    snr_show = float(ds.snr_db.values[ks])
    for c, name in enumerate(contrasts):
        words, unit = LABELS[name]
        sel = ds.sel(contrast=name)
        _status_image(
            axes[0, c],
            sel.status.isel(interval=ji).transpose("snr_db", "velocity").values,
            vlab,
            [f"{s:g}" for s in ds.snr_db.values],
            "velocity (mm/s)",
            "SNR (dB)",
        )
        axes[0, c].set_title(f"{words}: interval {dt_ms:g} ms")
        _status_image(
            axes[1, c],
            sel.status.isel(snr_db=ks).transpose("interval", "velocity").values,
            vlab,
            [f"{t * 1e3:g}" for t in ds.interval.values],
            "velocity (mm/s)",
            "time between frames (ms)",
        )
        axes[1, c].set_title(f"{words}: SNR {snr_show:g} dB")
        ax = axes[2, c]
        for k, snr in enumerate(ds.snr_db.values):
            line = ax.errorbar(
                _mm(vel),
                sel.measured.isel(snr_db=k, interval=ji),
                yerr=sel.measured_se.isel(snr_db=k, interval=ji),
                fmt="o",
                ms=3,
                capsize=2,
                label=f"{snr:g} dB",
            )
            col = line[0].get_color()
            ax.plot(_mm(vel), sel.theory.isel(snr_db=k, interval=ji), "-", color=col, lw=0.8)
            ax.axhline(float(sel.static_floor_theory[k]), color=col, lw=0.6, ls=":")
        ax.axhline(float(sel.noise_floor_theory[0]), color="k", lw=0.8, ls="--")
        vlo = float(sel.v_low.isel(snr_db=ks, interval=ji))
        vhi = float(sel.v_high.isel(snr_db=ks, interval=ji))
        if math.isfinite(vlo) and math.isfinite(vhi):
            ax.axvspan(vlo / 1000, vhi / 1000, color=STATUS[1][0], alpha=0.2, lw=0)
        positive = _mm(vel[vel > 0])
        if positive.size:
            ax.set_xscale("symlog", linthresh=float(positive.min()))
        ax.set_xlim(0.0, float(_mm(vel).max()) * 1.3 if vel.max() > 0 else 1.0)
        ax.set_xlabel("velocity (mm/s)")
        ax.set_ylabel(unit)
        ax.set_title(f"{words}, {dt_ms:g} ms between frames")
    floors = [
        Line2D([], [], color="0.4", ls=":", label="static-tissue floor (per SNR)"),
        Line2D([], [], color="k", ls="--", label="noise floor"),
        Line2D([], [], color="0.4", ls="-", label="theory"),
    ]
    handles, labels = axes[2, 0].get_legend_handles_labels()
    fig.legend(
        handles=handles + floors,
        labels=[f"SNR {lab}" for lab in labels] + [h.get_label() for h in floors],
        loc="outside lower center",
        ncol=len(handles) + len(floors),
        frameon=False,
    )
    handles = [Patch(color=col, label=label) for col, label in STATUS]
    fig.legend(handles=handles, loc="outside upper center", ncol=3, frameon=False)
    return fig


def plot_calibration(ds: xr.Dataset) -> Figure:
    """Decorrelation against velocity with its standard error, theory and floors."""
    fig, axes = new_figure(1, 1, width=4.5, height=3.2)
    ax = axes[0, 0]
    ax.errorbar(
        _mm(ds.velocity.values),
        ds.decorrelation,
        yerr=ds.decorrelation_se,
        fmt="o",
        ms=3,
        capsize=2,
        label="measured ± SE",
    )
    ax.plot(_mm(ds.velocity_fine.values), ds.theory_curve, "-", color="k", lw=1, label="theory")
    ax.axhline(float(ds.static_floor_theory), color="0.5", ls=":", lw=0.8, label="static floor")
    ax.axhline(float(ds.noise_floor_theory), color="0.3", ls="--", lw=0.8, label="noise floor")
    ax.set_xlabel("transverse velocity (mm/s)")
    ax.set_ylabel("amplitude decorrelation D")
    ax.set_title(
        f"decorrelation calibration: {ds.attrs['interval'] * 1e3:g} ms between frames, "
        f"SNR {ds.attrs['snr_db']:g} dB"
    )
    ax.legend(loc="lower right", frameon=False)
    return fig
