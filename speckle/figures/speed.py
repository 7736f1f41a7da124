"""Figures of the speed-versus-accuracy chart and of the failure map (datasets of
:mod:`speckle.studies.speed`)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .style import legend_outside, new_figure

__all__ = ["pareto_front", "plot_failure_map", "plot_speed_accuracy"]

#: Errors below this are drawn at it (the direct sum is exact: error 0).
ERROR_FLOOR = 1e-16
#: Failure-map errors below this are drawn at it (naive float32 at k0 = 0 is exact).
MAP_FLOOR = 1e-12
_MARKERS = {"direct": "*", "nufft": "o", "nufft32": "s", "finufft": "^", "psf": "D", "auto": "x"}


def _color(method: str) -> str | None:
    """The same colour for a method in every panel (A-scan and beam rows list different ones)."""
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    names = list(_MARKERS)
    return cycle[names.index(method) % len(cycle)] if method in names else None


def pareto_front(time: np.ndarray, error: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both time and error, by time."""
    ok = np.flatnonzero(np.isfinite(time) & np.isfinite(error))
    order = ok[np.argsort(time[ok], kind="stable")]
    front, best = [], np.inf
    for i in order:
        if error[i] < best:
            front.append(i)
            best = error[i]
    return np.array(front, dtype=int)


def _chart_panel(ax, sc: xr.Dataset, title: str, *, legend: bool) -> None:
    """One scene of a chart: time vs error per method (a line over tol), the Pareto front."""
    all_t, all_e = [], []
    for method in sc["method"].values:
        t = sc["time"].sel({"method": method}).values
        e = np.maximum(sc["error"].sel({"method": method}).values, ERROR_FLOOR)
        if method == "direct":
            t, e = t[:1], e[:1]
        ax.plot(
            t,
            e,
            _MARKERS.get(str(method), "."),
            color=_color(str(method)),
            ls="-" if method != "direct" else "",
            lw=0.8,
            ms=5,
            label=str(method),
            alpha=0.85,
        )
        all_t.extend(t)
        all_e.extend(e)
    all_t, all_e = np.array(all_t), np.array(all_e)
    front = pareto_front(all_t, all_e)
    ax.step(
        all_t[front], all_e[front], where="post", color="k", lw=2, alpha=0.35, label="Pareto front"
    )
    for tol in sc["tol"].values:
        ax.axhline(tol, color="0.8", lw=0.5, zorder=0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_title(title)
    if legend:
        ax.set_ylabel("relative error against the direct sum")
        legend_outside(ax)


def plot_speed_accuracy(ds: xr.Dataset, beam: xr.Dataset | None = None) -> Figure:
    """Time versus relative error, one panel per scene size, Pareto front as a line.

    ``ds``: the A-scan chart (:func:`speckle.studies.speed.speed_accuracy`), first row;
    ``beam``: the scanned-beam chart (:func:`speckle.studies.speed.beam_speed_accuracy`),
    second row, if given.
    """
    rows = [ds] if beam is None else [ds, beam]
    n_col = max(r.sizes["scene"] for r in rows)
    fig, axes = new_figure(len(rows), n_col, width=3.4 * n_col, height=3.4 * len(rows))
    for i in range(ds.sizes["scene"]):
        sc = ds.isel(scene=i)
        title = f"N={int(sc.n_pixels)} px, {int(sc.n_lines)} lines, {float(sc.density):g}/px"
        _chart_panel(axes[0, i], sc, title, legend=i == 0)
    for i in range(0 if beam is None else beam.sizes["scene"]):
        sc = beam.isel(scene=i)
        title = (
            f"beam: N={int(sc.n_pixels)} px, {int(sc.n_lines)} lines, "
            f"{float(sc.density):g}/px/line, w0={float(sc.waist_pitch):g} pitch"
        )
        _chart_panel(axes[1, i], sc, title, legend=i == 0)
    for r, row in enumerate(rows):  # rows with fewer scenes than columns
        for ax in axes[r, row.sizes["scene"] :]:
            ax.remove()
    tols = ds["tol"].values
    what = "A-scan methods (top) and scanned-beam methods (bottom)" if beam is not None else ""
    fig.suptitle(
        f"Speed vs accuracy{', ' + what if what else ''}, knob tol = "
        f"{', '.join(f'{t:g}' for t in tols)} (grey lines); spectrum "
        f"{ds.attrs.get('spectrum_shape')}, k0/Δk = {ds.attrs.get('k0_dk')}; pipeline timings "
        "are noisy",
        fontsize=8,
    )
    return fig


def plot_failure_map(ds: xr.Dataset) -> Figure:
    """Measured (markers) and predicted (dashed) error of each case versus N, density, k0/dk."""
    axes_names = [
        ("n_pixels", "pixels N"),
        ("density", "scatterers per pixel"),
        ("k0_dk", "k0/Δk"),
    ]
    fig, axes = new_figure(1, 3, width=10.5, height=3.6, sharey=True)
    axes = axes[0]
    cases = ds["case"].values
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (axis, label) in zip(axes, axes_names, strict=True):
        x = ds[axis].values.astype(float)
        xplot = np.where(x > 0, x, np.nan) if axis != "k0_dk" else np.maximum(x, 0.1)
        for c, case in enumerate(cases):
            col = colors[c % len(colors)]
            err = np.maximum(ds[f"error_vs_{axis}"].sel(case=case).values, MAP_FLOOR)
            pred = np.maximum(ds[f"predicted_vs_{axis}"].sel(case=case).values, MAP_FLOOR)
            ax.plot(xplot, err, "o-", color=col, lw=1, ms=4, label=str(case))
            ax.plot(xplot, pred, "--", color=col, lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label + (" (0 drawn at 0.1)" if axis == "k0_dk" else ""))
        ax.axhline(1e-6, color="0.6", lw=0.6, ls=":")
        if axis == "n_pixels":
            ax.set_ylabel("relative error against the direct sum")
    fig.legend(
        *axes[0].get_legend_handles_labels(),
        loc="outside right upper",
        frameon=False,
        title="case (dashed: predicted)",
    )
    fig.suptitle(
        "Failure map: markers measured, dashed predicted (auto's rules; < 1e-12 drawn "
        "at 1e-12); dotted: "
        f"tol = 1e-6. Base N={ds.attrs.get('base_n_pixels')}, "
        f"density={ds.attrs.get('base_density')}, k0/Δk={ds.attrs.get('base_k0_dk')}, "
        "depths over [0, 2H)",
        fontsize=8,
    )
    return fig
