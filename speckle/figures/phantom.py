"""The phantom fit's closed loop, its challenge scores and its failure map (results/phantom/).

``closed_loop_data`` runs :func:`speckle.phantom_closed_loop` for every scanner configuration
of the ``phantom_fit`` section (the case seeds ``seed .. seed + cases - 1``, on Dask) and
stacks them along ``configuration``. ``plot_closed_loop`` draws the fit against the truth (the
pulls of the attenuation, of ``rho E/100`` and of the boundaries' depths against a standard
normal, the boundaries' errors in pixels, the layer counts); ``plot_scores`` draws a challenge
metric of every map, target against the fitted phantom's scan and against the baseline's
two-layer phantom, over the floor (target against the true phantom drawn again).
``failure_map_data`` runs :func:`speckle.phantom_failure_map` (thickness x contrast of a middle
layer) one seed per Dask task and pools the seeds; ``plot_failure_map`` draws it.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..conventions import attrs, coord
from ..studies.phantom.batch import MARGIN, phantom_closed_loop, phantom_score_power
from ..studies.phantom.limits import phantom_failure_map
from ..sweep import sweep
from ..synthoct.metrics import METRIC_NAMES, SYNTHOCT_MAPS
from .style import new_figure

__all__ = [
    "closed_loop_data",
    "failure_map_data",
    "plot_closed_loop",
    "plot_failure_map",
    "plot_scores",
    "score_summary",
    "table_csv",
]

_MARKERS = ("o", "s", "^", "D")
_PER_CONFIG = ("n_pixels", "pixel_size", "n_lines", "beam_radius")


def closed_loop_data(cfg: Mapping, dask_cfg: Mapping | None = None) -> xr.Dataset:
    """The closed loop of every configuration of the ``phantom_fit`` section.

    Parameters
    ----------
    cfg : Mapping
        The ``phantom_fit`` section: ``configurations``, ``cases``, ``seed``, ``layers``,
        ``shapes``, ``inclusions``, ``rescans``, ``lpips``.
    dask_cfg : Mapping, optional
        The config's ``dask`` section (``scheduler``, ``n_workers``); default threads.

    Returns
    -------
    xarray.Dataset
        :func:`speckle.phantom_closed_loop`'s variables with a leading ``configuration`` dim,
        and per configuration ``n_pixels``, ``pixel_size`` (µm), ``n_lines``, ``beam_radius``
        (µm).
    """
    dask_cfg = dict(dask_cfg or {"scheduler": "threads", "n_workers": None})
    seeds = list(range(int(cfg["seed"]), int(cfg["seed"]) + int(cfg["cases"])))
    parts = []
    for name in cfg["configurations"]:
        ds = phantom_closed_loop(
            seeds,
            str(name),
            layers=tuple(int(v) for v in cfg["layers"]),
            shapes=tuple(cfg["shapes"]),
            inclusions=bool(cfg["inclusions"]),
            rescans=int(cfg["rescans"]),
            lpips=bool(cfg["lpips"]),
            scheduler=dask_cfg["scheduler"],
            n_workers=dask_cfg.get("n_workers"),
            progress=True,
        )
        extra = {
            "n_pixels": ((), ds.attrs["n_pixels"], attrs("count", "pixels per A-line")),
            "pixel_size": ((), ds.attrs["pixel_size"], attrs("length", "pixel size in depth")),
            "n_lines": ((), ds.attrs["n_lines"], attrs("count", "A-lines per B-scan")),
            "beam_radius": ((), ds.attrs["beam_radius"], attrs("length", "beam radius r")),
        }
        parts.append(ds.assign(extra))
    out = xr.concat(parts, "configuration", combine_attrs="drop_conflicts")
    out = out.assign_coords(configuration=coord("configuration", list(cfg["configurations"])))
    out.attrs.update({"cases": len(seeds), "rescans": int(cfg["rescans"])})
    return out


def _failure_seed(seed: int, **options) -> xr.Dataset:
    return phantom_failure_map(seeds=[int(seed)], **options)


def failure_map_data(cfg: Mapping, dask_cfg: Mapping | None = None) -> xr.Dataset:
    """The failure map of the ``phantom_fit.failure_map`` section, one seed per Dask task.

    Each seed's map (:func:`speckle.phantom_failure_map` with that seed only: its cases draw
    from ``(seed, thickness, contrast)``, so the pooled map equals one call with every seed) is
    computed apart; the fractions are their means, ``boundary_error`` the median over the
    seeds of the finite values, ``n_cases`` the number of seeds.

    Parameters
    ----------
    cfg : Mapping
        The ``failure_map`` subsection: ``configuration``, ``thickness`` (pixels),
        ``contrast``, ``seeds`` (how many, from ``seed``), ``seed``, ``energy`` (%).
    dask_cfg : Mapping, optional
        The config's ``dask`` section.
    """
    dask_cfg = dict(dask_cfg or {"scheduler": "threads", "n_workers": None})
    seeds = list(range(int(cfg["seed"]), int(cfg["seed"]) + int(cfg["seeds"])))
    options = {
        "config": str(cfg["configuration"]),
        "thickness": [float(t) for t in cfg["thickness"]],
        "contrast": [float(q) for q in cfg["contrast"]],
        "energy": float(cfg["energy"]),
    }
    per = sweep(_failure_seed, {"seed": seeds}, fixed=options, scheduler=dask_cfg["scheduler"],
                n_workers=dask_cfg.get("n_workers"), progress=True)  # fmt: skip
    out = per[["success", "count_right", "boundary_right"]].mean("seed", keep_attrs=True)
    out["boundary_error"] = per["boundary_error"].median("seed", skipna=True, keep_attrs=True)
    out["n_cases"] = xr.DataArray(len(seeds), attrs=per["n_cases"].attrs)
    out.attrs.update(
        {"configuration": options["config"], "energy": options["energy"], "seeds": seeds}
    )
    return out


def score_summary(ds: xr.Dataset, metric: str = "MS-SSIM") -> xr.Dataset:
    """Mean over the scored cases of ``metric``'s difference candidate minus floor, with its SE.

    Returns a Dataset of ``difference`` and ``difference_se`` along ``(configuration,
    candidate, map)`` (the floor's own row is zero), ``within`` (1 where the mean is above
    ``-0.02 - 2 SE``: the fitted phantom at the floor) and ``power``: the test's power against
    a true mean 0.03 below the margin at the measured per-case SD
    (:func:`speckle.phantom_score_power`; NaN with fewer than 2 cases).
    """
    values = ds[metric]
    diff = values - values.sel(candidate="floor")
    n = diff.count("case")  # refused cases (NaN scores) left out
    mean = diff.mean("case")
    se = (diff.std("case", ddof=1) / np.sqrt(n)).where(n > 1)
    within = (mean > -MARGIN - 2 * se.fillna(0.0)).astype(float)
    sd = (se * np.sqrt(n)).values
    ok = (n.values > 1) & np.isfinite(sd) & (sd > 0)
    power = np.full(sd.shape, np.nan)
    power[ok] = phantom_score_power(np.broadcast_to(n.values, sd.shape)[ok], sd[ok])
    q = attrs("dimensionless", f"mean {metric} difference, candidate minus floor")
    return xr.Dataset(
        {
            "difference": (mean.dims, mean.values, q),
            "difference_se": (se.dims, se.values, attrs("dimensionless", "its standard error")),
            "within": (mean.dims, within.values, attrs("dimensionless", "1: above -0.02 - 2 SE")),
            "power": (mean.dims, power, attrs("dimensionless", "power at 0.03 below the margin")),
        },
        coords=mean.coords,
    )


def table_csv(ds: xr.Dataset) -> str:
    """Per configuration, candidate, map and metric: the mean over cases, the mean difference
    to the floor and its SE, as CSV text (LPIPS left out where it is NaN)."""
    import csv
    import io

    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["configuration", "candidate", "map", "metric", "mean", "minus_floor",
                     "minus_floor_se", "cases"])  # fmt: skip
    for metric in METRIC_NAMES:
        if metric not in ds or not np.any(np.isfinite(ds[metric].values)):
            continue
        summary = score_summary(ds, metric)
        mean = ds[metric].mean("case")
        for conf in ds["configuration"].values:
            for cand in ds["candidate"].values:
                for name in ds["map"].values:
                    at = {"configuration": conf, "candidate": cand, "map": name}
                    writer.writerow([conf, cand, name, metric,
                                     repr(float(mean.sel(at))),
                                     repr(float(summary.difference.sel(at))),
                                     repr(float(summary.difference_se.sel(at))),
                                     ds.sizes["case"]])  # fmt: skip
    return text.getvalue()


def _pooled(ds: xr.Dataset, name: str) -> np.ndarray:
    v = np.asarray(ds[name].values, float).ravel()
    return v[np.isfinite(v)]


def plot_closed_loop(ds: xr.Dataset) -> Figure:
    """The fit against the truth: pulls, boundary errors and layer counts, per configuration."""
    fig, axes = new_figure(1, 3, width=11.0, height=3.4)
    a, b, c = axes[0]
    grid = np.linspace(-4.5, 4.5, 19)
    right = np.asarray(ds["layers_right"].values, float) > 0
    for name, label, colour in (
        ("attenuation_pull", "attenuation µ", "C0"),
        ("rho_e_pull", "ρE/100", "C1"),
        ("top_pull", "boundary depth", "C2"),
        ("window_top_pull", "window top", "C3"),
    ):
        pulls = np.asarray(ds[name].values, float)[right]
        pulls = pulls[np.isfinite(pulls)]
        if pulls.size:
            a.hist(np.clip(pulls, -4.5, 4.5), bins=grid, density=True, histtype="step",
                   color=colour, label=f"{label} ({pulls.size} pulls, rms "
                   f"{np.sqrt(np.mean(pulls**2)):.2f})")  # fmt: skip
    u = np.linspace(-4.5, 4.5, 200)
    a.plot(u, np.exp(-u * u / 2) / np.sqrt(2 * np.pi), "k-", lw=0.8, label="standard normal")
    a.set_xlabel("pull (fitted − true)/SE")
    a.set_ylabel("probability density")
    a.set_title("pulls (layer count right)")
    a.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.22))
    for i, conf in enumerate(ds["configuration"].values):
        sub = ds.sel(configuration=conf)
        depth = np.asarray(sub["true_top"].values, float).ravel()
        err = np.asarray(sub["boundary_error"].values, float).ravel()
        keep = np.isfinite(err) & (depth > 0)
        b.plot(depth[keep], err[keep], _MARKERS[i % 4], mfc="none", ms=5,
               label=f"{conf} ({float(sub.pixel_size):g} µm pixels)")  # fmt: skip
        true = np.asarray(sub["n_true"].values, float)
        fitted = np.asarray(sub["n_fit"].values, float)
        jitter = 0.08 * (i - (ds.sizes["configuration"] - 1) / 2)
        ok = int(np.sum(np.asarray(sub["success"].values) > 0))
        c.plot(true + jitter, fitted + jitter, _MARKERS[i % 4], mfc="none", ms=6,
               label=f"{conf}: {ok}/{true.size} cases succeed")  # fmt: skip
    b.axhline(1.0, color="k", lw=0.6, ls="--", label="one pixel")
    b.set_xlabel("true boundary depth, mean over x (µm)")
    b.set_ylabel("largest boundary error (pixels)")
    b.set_title("boundaries")
    b.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.22))
    top = int(max(np.nanmax(ds["n_true"].values), np.nanmax(ds["n_fit"].values))) + 1
    c.plot([0.5, top - 0.5], [0.5, top - 0.5], "k-", lw=0.5, label="count right")
    c.set_xlabel("true layers")
    c.set_ylabel("layers fitted")
    c.set_title("layer counts")
    c.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.22))
    fig.suptitle(
        f"Phantom fit's closed loop: {ds.sizes['case']} virtual patients per configuration, "
        "scanned and fitted back"
    )
    return fig


def plot_scores(ds: xr.Dataset, metric: str = "MS-SSIM") -> Figure:
    """``metric`` of every map: the fitted phantom and the baseline against the floor."""
    maps = [str(m) for m in ds["map"].values] if "map" in ds else list(SYNTHOCT_MAPS)
    fig, axes = new_figure(1, len(maps), width=11.0, height=3.4)
    for ax, name in zip(axes[0], maps, strict=True):
        lo, hi = np.inf, -np.inf
        for i, conf in enumerate(ds["configuration"].values):
            sub = ds[metric].sel(configuration=conf, map=name)
            floor = np.asarray(sub.sel(candidate="floor").values, float)
            for cand, colour in (("fitted", "C0"), ("baseline", "C3")):
                y = np.asarray(sub.sel(candidate=cand).values, float)
                ax.plot(floor, y, _MARKERS[i % 4], color=colour, mfc="none", ms=5,
                        label=f"{cand}, {conf}")  # fmt: skip
                both = np.concatenate([floor, y])
                both = both[np.isfinite(both)]
                if both.size:
                    lo, hi = min(lo, both.min()), max(hi, both.max())
        if np.isfinite(lo):
            line = np.array([lo, hi])
            ax.plot(line, line, "k-", lw=0.6, label="at the floor")
            ax.plot(line, line - MARGIN, "k--", lw=0.6, label="floor − 0.02")
        ax.set_title(name)
        ax.set_xlabel(f"{metric}, target vs true phantom (floor)")
        ax.set_ylabel(f"{metric}, target vs candidate")
    axes[0, 0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(0.0, -0.22), ncol=2)
    fig.suptitle(
        f"Scored as the challenge scores: {metric} of the scan (Struct) and its maps, each "
        "case's target against re-drawn phantoms"
    )
    return fig


def plot_failure_map(ds: xr.Dataset) -> Figure:
    """Where the fit fails: success, count and boundary fractions over thickness x contrast."""
    panels = (
        ("success", "cases fitted right (fraction)"),
        ("count_right", "layer count right (fraction)"),
        ("boundary_right", "boundaries within a pixel (fraction)"),
    )
    fig, axes = new_figure(1, len(panels), width=11.0, height=3.4)
    t = np.asarray(ds["thickness"].values, float)
    q = np.asarray(ds["energy_ratio"].values, float)
    xs, ys = np.arange(q.size), np.arange(t.size)
    for ax, (name, label) in zip(axes[0], panels, strict=True):
        values = ds[name].transpose("thickness", "energy_ratio").values
        im = ax.imshow(values, origin="lower", aspect="auto", cmap="viridis", vmin=0, vmax=1,
                       extent=[-0.5, q.size - 0.5, -0.5, t.size - 0.5])  # fmt: skip
        fig.colorbar(im, ax=ax, label=label)
        ax.set_xticks(xs, [f"{v:g}" for v in q])
        ax.set_yticks(ys, [f"{v:g}" for v in t])
        ax.set_xlabel("contrast q (ρE of the middle layer / its neighbours')")
        ax.set_ylabel("middle-layer thickness (µm)")
        if name == "success":
            err = ds["boundary_error"].transpose("thickness", "energy_ratio").values
            for (i, j), e in np.ndenumerate(err):
                if np.isfinite(e):
                    ax.text(j, i, f"{e:.1f} px", ha="center", va="center", fontsize=8,
                            color="w" if values[i, j] < 0.5 else "k")  # fmt: skip
    fig.suptitle(
        f"Where the phantom fit fails: three flat layers, a middle one of thickness T and "
        f"contrast q ({int(ds['n_cases'])} seeds per cell; numbers: median largest boundary "
        "error)"
    )
    return fig
