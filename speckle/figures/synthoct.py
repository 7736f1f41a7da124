"""The SynthOCT challenge's self-consistency check and a participant's search (results/synthoct/).

``self_consistency_data`` scores the challenge's three comparisons (:data:`speckle.synthoct.
metrics.SYNTHOCT_EXPERIMENTS`) three ways: the published ``Final_Metrics_Report.csv``, the
same comparisons recomputed from the published scans by :func:`speckle.synthoct_metrics`, and
(given) the drop-in scanner's scans of the regenerated phantoms. ``batch_data`` runs a grid of
two-layer candidate phantoms (boundary depth x bottom-layer energy) through the drop-in scanner
and scores each against a published scan, on Dask with a progress bar, as a participant's
search loop would. The candidates share one random draw of positions (common random numbers,
the generator's recipe with one seed), so their scores differ by the parameters only.
"""

from __future__ import annotations

import csv
import dataclasses
from collections.abc import Mapping
from importlib.resources import files
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..conventions import attrs, coord
from ..sweep import sweep
from ..synthoct.files import ScannerConfig, baseline_phantom, read_scan
from ..synthoct.maps import MAP_NAMES, synthoct_maps
from ..synthoct.metrics import (
    METRIC_NAMES,
    SYNTHOCT_EXPERIMENTS,
    SYNTHOCT_MAPS,
    read_metrics_report,
    synthoct_metrics,
)
from .style import new_figure

__all__ = [
    "PHANTOMS",
    "batch_data",
    "batch_point",
    "plot_batch",
    "plot_self_consistency",
    "published_scan",
    "self_consistency_data",
    "table_csv",
]

#: The self-consistency check's phantoms: name -> (baseline kind, seed name).
PHANTOMS = {
    "Exp1_Uniform_A": ("uniform", "A"),
    "Exp1_Uniform_B": ("uniform", "B"),
    "Exp2_Layers_A": ("layers", "A"),
    "Exp2_Layers_B": ("layers", "B"),
}
#: The published two-layer phantom: boundary (µm) and bottom-layer energy (%).
LAYERS = (400.0, 2.5)
#: The phantom whose maps the figure shows.
SHOWN = "Exp2_Layers_A"


def _data() -> Path:
    return Path(str(files("speckle.data") / "synthoct"))


def published_scan(name: str) -> xr.DataArray:
    """The published scan ``Scan_<name>.png`` (shipped in ``speckle/data/synthoct``)."""
    if name not in PHANTOMS:
        raise ValueError(f"name must be one of {list(PHANTOMS)}, got {name!r}")
    return read_scan(_data() / f"Scan_{name}.png")


def _scores(pairs: Mapping[str, tuple[object, object]], lpips: bool) -> xr.Dataset:
    out = [synthoct_metrics(a, b, lpips=lpips) for a, b in pairs.values()]
    return xr.concat(out, dim="experiment", combine_attrs="drop_conflicts").assign_coords(
        experiment=coord("experiment", list(pairs))
    )


def self_consistency_data(
    cfg: Mapping, scans: Mapping[str, str | Path] | None = None
) -> xr.Dataset:
    """Scores of the challenge's three comparisons: published, recomputed and drop-in.

    Parameters
    ----------
    cfg : Mapping
        The config's ``synthoct`` section (``lpips``).
    scans : mapping of phantom name to PNG path, optional
        The drop-in scanner's scans of the four regenerated phantoms (:data:`PHANTOMS`).

    Returns
    -------
    xarray.Dataset
        Each metric along ``(origin, experiment, map)`` with ``origin`` = ``published`` (the
        CSV), ``recomputed`` (the published scans through :func:`speckle.synthoct_metrics`)
        and, with ``scans``, ``drop-in``; the scans ``scan (origin_scan, phantom, depth, x)``
        and the official maps of :data:`SHOWN` (``OAC``, ``SC``, ``RSC``).
    """
    lpips = bool(cfg.get("lpips", False))
    published = read_metrics_report(_data() / "Final_Metrics_Report.csv")
    published = published.sel(experiment=list(SYNTHOCT_EXPERIMENTS), map=list(SYNTHOCT_MAPS))
    images = {"published": {n: published_scan(n) for n in PHANTOMS}}
    if scans:
        images["drop-in"] = {n: read_scan(scans[n]) for n in PHANTOMS}
    scored = [published.drop_attrs(deep=False)]
    for scan in images.values():
        pairs = {e: (scan[a], scan[b]) for e, (a, b) in SYNTHOCT_EXPERIMENTS.items()}
        scored.append(_scores(pairs, lpips).drop_attrs(deep=False))
    origins = ["published", "recomputed", *(["drop-in"] if scans else [])]
    ds = xr.concat(scored, dim="origin", coords="minimal", compat="override").assign_coords(
        origin=coord("origin", origins)
    )
    stack = xr.concat(
        [xr.concat(list(s.values()), dim="phantom") for s in images.values()], dim="origin_scan"
    )
    ds["scan"] = stack.drop_attrs().assign_attrs(
        attrs("dimensionless", long_name="8-bit logarithmic scan (51 dB)")
    )
    ds = ds.assign_coords(
        phantom=coord("phantom", list(PHANTOMS)),
        origin_scan=coord("origin", list(images), dims="origin_scan"),
    )
    maps = [synthoct_maps(s[SHOWN]) for s in images.values()]
    for name in MAP_NAMES:
        ds[name] = xr.concat([m[name] for m in maps], dim="origin_scan")
    ds.attrs["shown_phantom"] = SHOWN
    for origin in origins[1:]:
        deviation = np.abs(ds.sel(origin=origin) - ds.sel(origin="published"))
        tag = origin.replace("-", "_")
        for m in ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF"):
            ds.attrs[f"max_abs_deviation_{tag}_{m}"] = float(deviation[m].max())
    return ds


def table_csv(ds: xr.Dataset) -> str:
    """The scores side by side as CSV text: experiment, map, metric, one column per origin."""
    import io

    origins = [str(o) for o in ds["origin"].values]
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["experiment", "map", "metric", *origins])
    for e in ds["experiment"].values:
        for m in ds["map"].values:
            for metric in METRIC_NAMES:
                values = ds[metric].sel(experiment=e, map=m).values
                writer.writerow([e, m, metric, *(repr(float(v)) for v in values)])
    return text.getvalue()


# ------------------------------------------------------------------------------ batch
def batch_config(cfg: Mapping) -> ScannerConfig:
    """The scanner's configuration of the batch's phantoms (the challenge's, resized).

    The scatterer count is the challenge's density over the batch's box (``n_scatterers``
    of the config, or 300,000 scaled by the image area).
    """
    b = cfg["batch"]
    base = ScannerConfig()
    return dataclasses.replace(
        base,
        n_pixels=int(b["n_pixels"]),
        n_lines=int(b["n_lines"]),
        x_max=int(b["n_lines"]) * base.line_pitch,
        n_scatterers=int(b["n_scatterers"]),
    )


def _reference(cfg: Mapping) -> np.ndarray:
    """The published reference scan, cut to the batch's size (top rows, central lines)."""
    b = cfg["batch"]
    scan = published_scan(b["reference"]).values
    n, m = int(b["n_pixels"]), int(b["n_lines"])
    start = (scan.shape[1] - m) // 2
    return np.ascontiguousarray(scan[:n, start : start + m])


def batch_point(
    boundary: float,
    energy: float,
    *,
    phantom: xr.Dataset,
    config: ScannerConfig,
    reference: np.ndarray,
    top_energy: float,
    lpips: bool = False,
) -> xr.Dataset:
    """One candidate of the search: a two-layer phantom scanned and scored against ``reference``.

    ``phantom``'s scatterers get energy ``top_energy`` (%) down to ``boundary`` (µm) and
    ``energy`` (%) below (the baseline generator's two-layer recipe), are scanned by
    :func:`speckle.synthoct_scan` and compared by :func:`speckle.synthoct_metrics`.
    """
    from ..synthoct.scanner import synthoct_scan

    e = np.where(phantom["z"].values > boundary, energy, top_energy)
    candidate = phantom.assign(amplitude=phantom["amplitude"].copy(data=np.sqrt(e / 100.0) + 0j))
    scan = synthoct_scan(candidate, config, nthreads=1)  # Dask runs the candidates in parallel
    return synthoct_metrics(reference, np.asarray(scan.values), lpips=lpips)


def batch_data(cfg: Mapping, dask_cfg: Mapping | None = None) -> xr.Dataset:
    """Scores of every candidate of the grid ``boundary x energy`` against the reference.

    Parameters
    ----------
    cfg : Mapping
        The ``synthoct`` section: ``batch`` (``reference``, ``boundary`` and ``energy``
        linspaces, ``top_energy``, ``n_pixels``, ``n_lines``, ``n_scatterers``, ``seed``)
        and ``lpips``.
    dask_cfg : Mapping, optional
        The config's ``dask`` section (scheduler, address, n_workers).

    Returns
    -------
    xarray.Dataset
        Each metric along ``(boundary, energy, map)``.
    """
    b = cfg["batch"]
    config = batch_config(cfg)
    phantom = baseline_phantom("uniform", int(b["seed"]), config=config)
    dask_cfg = dict(dask_cfg or {"scheduler": "threads", "address": None, "n_workers": None})
    grid = {
        "boundary": np.linspace(**b["boundary"]).tolist(),
        "energy": np.linspace(**b["energy"]).tolist(),
    }
    ds = sweep(
        batch_point,
        grid,
        fixed={
            "phantom": phantom,
            "config": config,
            "reference": _reference(cfg),
            "top_energy": float(b["top_energy"]),
            "lpips": bool(cfg.get("lpips", False)),
        },
        scheduler=dask_cfg["scheduler"],
        address=dask_cfg.get("address"),
        n_workers=dask_cfg.get("n_workers"),
        progress=True,
    )
    ds = ds.assign_coords(
        boundary=coord("boundary", grid["boundary"]),
        energy=coord("energy", grid["energy"], long_name="bottom-layer energy per scatterer"),
        map=coord("map", list(SYNTHOCT_MAPS)),
    )
    ds.attrs.update(
        {
            "reference": str(b["reference"]),
            "top_energy_percent": float(b["top_energy"]),
            "n_phantoms": int(ds.sizes["boundary"] * ds.sizes["energy"]),
            "n_pixels": config.n_pixels,
            "n_lines": config.n_lines,
            "n_scatterers": config.n_scatterers,
        }
    )
    return ds


# --------------------------------------------------------------------------- figures
def _extent(da: xr.DataArray) -> list[float]:
    dz, dx = float(da.depth[1] - da.depth[0]), float(da.x[1] - da.x[0])
    return [
        float(da.x[0]) - dx / 2,
        float(da.x[-1]) + dx / 2,
        float(da.depth[-1]) + dz / 2,
        float(da.depth[0]) - dz / 2,
    ]


def plot_self_consistency(ds: xr.Dataset) -> Figure:
    """Scans and maps of :data:`SHOWN` per origin; each score recomputed against published."""
    origins = [str(o) for o in ds["origin_scan"].values]
    rows = len(origins)
    fig = new_figure(1, 1, width=11.0, height=2.0 * rows + 2.4)[0]
    fig.clear()
    grid = fig.add_gridspec(rows + 1, 5, height_ratios=[1.0] * rows + [1.1])
    panels = [
        ("scan", "grey level", "gray", None),
        ("OAC", "OAC (1/µm)", "magma", 99),
        ("SC", "SC", "viridis", None),
        ("RSC", "RSC", "viridis", None),
    ]
    for i, origin in enumerate(origins):
        row = grid[i, :].subgridspec(1, len(panels))
        for j, (name, label, cmap, pct) in enumerate(panels):
            ax = fig.add_subplot(row[0, j])
            da = ds[name].sel(origin_scan=origin)
            if name == "scan":
                da = da.sel(phantom=str(ds.attrs["shown_phantom"]))
            values = np.asarray(da.values, dtype=float)
            vmax = np.percentile(values, pct) if pct else None
            im = ax.imshow(values, extent=_extent(da), aspect="equal", cmap=cmap, vmax=vmax)
            fig.colorbar(im, ax=ax, label=label, shrink=0.7)
            ax.set_title(f"{origin} {name}")
            ax.set_xlabel("x (µm)")
            ax.set_ylabel("depth (µm)")
    metrics = ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF")
    others = [str(o) for o in ds["origin"].values if str(o) != "published"]
    for j, metric in enumerate(metrics):
        ax = fig.add_subplot(grid[rows, j])
        ref = ds[metric].sel(origin="published").values.ravel()
        for origin, marker in zip(others, ("o", "s"), strict=False):
            ax.plot(ref, ds[metric].sel(origin=origin).values.ravel(), marker, ms=4, mfc="none",
                    label=origin)  # fmt: skip
        lo, hi = np.nanmin(ref), np.nanmax(ref)
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.5)
        unit = " (dB)" if metric == "PSNR" else ""
        ax.set_xlabel(f"{metric} published{unit}")
        ax.set_ylabel(f"{metric} here{unit}")
        if j == 0:  # above the diagonal's upper-left end, where no point falls
            ax.legend(loc="upper left", frameon=False)
    fig.suptitle(
        f"SynthOCT self-consistency check: {ds.attrs['shown_phantom']} (official maps); "
        "3 comparisons x 4 images scored here against the published table"
    )
    return fig


def plot_batch(ds: xr.Dataset, metric: str = "SSIM") -> Figure:
    """``metric`` of every candidate against the reference, one panel per image."""
    fig, axes = new_figure(1, len(SYNTHOCT_MAPS), width=11.0, height=2.8)
    b, e = ds["boundary"].values, ds["energy"].values
    for ax, name in zip(axes[0], SYNTHOCT_MAPS, strict=True):
        values = ds[metric].sel(map=name).transpose("energy", "boundary").values
        db, de = (b[1] - b[0] if b.size > 1 else 1.0), (e[1] - e[0] if e.size > 1 else 1.0)
        extent = [b[0] - db / 2, b[-1] + db / 2, e[0] - de / 2, e[-1] + de / 2]
        im = ax.imshow(values, origin="lower", extent=extent, aspect="auto", cmap="viridis")
        fig.colorbar(im, ax=ax, label=f"{metric} against {ds.attrs['reference']}")
        i = np.unravel_index(np.nanargmax(values), values.shape)
        ax.plot(b[i[1]], e[i[0]], "r+", ms=8, label="best candidate")
        if str(ds.attrs["reference"]).startswith("Exp2_Layers"):  # the published phantom
            ax.plot(LAYERS[0], LAYERS[1], "wx", ms=6, label="published phantom")
        ax.set_title(name)
        ax.set_xlabel("boundary depth (µm)")
        ax.set_ylabel("bottom-layer energy (%)")
    # outside the images (it hid a corner), on grey so that the white cross shows
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncols=2,
               facecolor="0.6", framealpha=1.0)  # fmt: skip
    fig.suptitle(
        f"{ds.attrs['n_phantoms']} two-layer candidates "
        f"({ds.attrs['n_pixels']} x {ds.attrs['n_lines']} px) scored as the challenge does"
    )
    return fig


# ----------------------------------------------------------------------- config check
