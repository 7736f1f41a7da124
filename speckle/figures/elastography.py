"""Elastography on simulated phantoms: strain maps, failure maps, speed-accuracy chart, sequence.

Each ``*_data`` function takes the pipeline's ``elastography`` config section and the seed and
returns the dataset its ``plot_<name>`` function draws (every figure is drawn from a NetCDF file).
Images are made with the package API (:func:`speckle.deformable_scene`,
:func:`speckle.displace`, :func:`speckle.bscan`) on a Gaussian spectrum, and every estimator
runs through :func:`speckle.estimate_strain`.

Method labels: ``vector``, ``wls``, ``tracking``, ``correlation`` are the estimators with their
defaults (``align="auto"`` for the phase methods); ``*_aligned`` / ``*_unaligned`` force
``align=True`` / ``align=False``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from scipy import ndimage

from ..analysis.correlation import expected_correlation
from ..analysis.phase import choose_lag, depth_autocorrelation, noise_power
from ..analysis.strain import accumulate_strain, predicted_strain_std
from ..conventions import attrs, coord
from ..imaging._bscan import bscan
from ..provenance import provenance_attrs
from ..scene.deformation import displace
from ..studies.failure import mean_and_se, method_options, strain_scores
from ..sweep import sweep
from ._config import dask_options
from ._elastography import (
    _estimate,
    _images,
    _inclusion_fe,
    _noisy,
    _scene,
    _source,
    _uniform,
    _window,
)
from .style import ESTIMATOR_NAMES as METHOD_NAMES
from .style import colorbar, estimator_colour, legend_outside, new_figure, physical_image

__all__ = [
    "FAILURE_SWEEPS",
    "failure_config",
    "failure_data",
    "failure_point",
    "inclusion_data",
    "phantom_data",
    "plot_failure",
    "plot_inclusion",
    "plot_phantom",
    "plot_sequence",
    "plot_sequence_large",
    "plot_speed",
    "point_seeds",
    "sequence_data",
    "sequence_large_data",
    "sequence_large_frames",
    "speed_data",
]

STRAIN = attrs("strain", "axial strain (compression > 0)")
STRAIN_ERROR = attrs("strain", "estimate minus truth")


# --------------------------------------------------------------------------------------------
# Phantom: layers in series under a flat probe
# --------------------------------------------------------------------------------------------


def layered_field(moduli: list[float], mean_strain: float, depth_range: float):
    """Axial displacement of equal-thickness layers in series compressed from ``z = 0``.

    Equal stress in every layer: strain ``s_i = s_mean * E_h / E_i`` (``E_h`` = harmonic mean
    of the moduli, so the layers shorten the stack by ``s_mean * depth``). Below the imaged
    depth the last layer continues. Returns ``(f(z, x) -> u_z, edges, strains)``.
    """
    e = np.asarray(moduli, float)
    strains = mean_strain * (len(e) / np.sum(1 / e)) / e
    edges = np.linspace(0.0, depth_range, len(e) + 1)
    offsets = np.concatenate([[0.0], np.cumsum(strains * np.diff(edges))])[:-1]

    def field(z, x):
        i = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, len(e) - 1)
        return -(offsets[i] + strains[i] * (z - edges[i]))

    return field, edges, strains


def _maps(cfg, seed, fields, modulus, truth, n_alines=None) -> xr.Dataset:
    """Strain and error maps of every method for a reference/deformed pair."""
    (ref, dfm), k0 = _images(cfg, seed, fields, n_alines=n_alines)
    est = np.array([_estimate(ref, dfm, k0, cfg, m) for m in cfg["methods"]])
    dims = ("method", "depth", "x")
    p = float(cfg["pixel_size"])
    return xr.Dataset(
        {
            "modulus": (("depth", "x"), modulus, attrs("modulus")),
            "true_strain": (("depth", "x"), truth, STRAIN),
            "strain": (dims, est, STRAIN),
            "error": (dims, est - truth, attrs("strain", "estimate minus truth")),
        },
        coords={
            "method": list(cfg["methods"]),
            "depth": coord("depth", np.arange(ref.shape[0]) * p),
            "x": np.arange(ref.shape[1]),
        },
        attrs={"k0": k0, "pixel_size": p, "seed": seed, **provenance_attrs()},
    )


def phantom_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """Layers in series (analytic displacement): modulus, true strain, strain and error maps."""
    ph = cfg["phantom"]
    n, lines = int(cfg["n_pixels"]), int(cfg["n_alines"])
    p = float(cfg["pixel_size"])
    field, edges, strains = layered_field(ph["moduli"], float(ph["mean_strain"]), n * p)
    z = np.arange(n) * p
    layer = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, len(strains) - 1)
    truth = np.repeat(strains[layer][:, None], lines, axis=1)
    modulus = np.repeat(np.asarray(ph["moduli"], float)[layer][:, None], lines, axis=1)
    return _maps(cfg, seed, [_uniform(0.0), field], modulus, truth)


def inclusion_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """Circular inclusion compressed by a flat probe (:func:`speckle.compress_phantom`, plane-strain
    finite elements): modulus, FE strain ``strain_zz`` as the truth, strain and error maps, and
    the truth averaged over each method's window (what a windowed estimator can resolve)."""
    ic = cfg["inclusion"]
    lines = int(ic.get("n_alines", cfg["n_alines"]))
    labels, fe = _inclusion_fe(cfg, lines, float(ic["strain"]))
    disp = fe[["uz", "ux"]]  # over (depth, x): read at the scene's line positions
    truth = fe["strain_zz"].values
    ds = _maps(cfg, seed, [_uniform(0.0), disp], fe["youngs_modulus"].values, truth, lines)
    wz, wx = _window(cfg)
    smooth = ndimage.uniform_filter(truth, size=(wz, wx), mode="nearest")
    ds["window_mean_strain"] = (
        ("depth", "x"),
        smooth,
        {**STRAIN, "long_name": "FE strain averaged over the estimator window"},
    )
    ds["label"] = (("depth", "x"), labels.values, {"long_name": "region label"})
    ds.attrs.update(
        {
            "fe_contact": ic["contact"],
            "fe_n_dofs": int(fe.attrs.get("n_dofs", 0)),
            "inclusion_radius_um": float(ic["radius"]),
        }
    )
    return ds


def _lateral(ds: xr.Dataset) -> np.ndarray:
    """Lateral A-line positions (µm): the A-line pitch of the scenes is the pixel size."""
    return np.arange(ds.sizes["x"]) * float(ds.attrs["pixel_size"])


def _map_figure(n_columns: int, ds: xr.Dataset):
    """Two rows of ``n_columns`` depth x lateral maps sized to their physical aspect ratio."""
    depth = float(ds.depth[-1] - ds.depth[0]) + float(ds.attrs["pixel_size"])
    ratio = depth / (ds.sizes["x"] * float(ds.attrs["pixel_size"]))
    width = 1.5 + 1.9 * n_columns
    panel = min(max((width / n_columns - 0.9) * ratio, 1.6), 4.0)
    return new_figure(2, n_columns, width=width, height=2 * panel + 0.9, sharey=True)


def plot_phantom(ds: xr.Dataset) -> Figure:
    """True strain and each method's strain map (top), modulus and each method's error map
    (bottom), at the physical aspect ratio (1 µm depth = 1 µm lateral), each with its colorbar.
    """
    methods = list(ds.method.values)
    fig, axes = _map_figure(len(methods) + 1, ds)
    depth, x = ds.depth.values, _lateral(ds)
    vmax = float(ds.true_strain.max()) * 1.3
    lim = vmax / 4
    strain_kw = {"vmin": 0, "vmax": vmax, "cmap": "viridis"}
    units = ds.modulus.attrs.get("units", "")

    def show(ax, img, title, label, **kw):
        im = physical_image(ax, img, depth, x, **kw)
        ax.set_title(title)
        ax.xaxis.set_major_locator(MaxNLocator(2))
        if ax.get_subplotspec().colspan.start > 0:
            ax.set_ylabel("")  # the depth axis is shared along the row
        colorbar(fig, im, ax, label)

    show(axes[0, 0], ds.true_strain, "true strain", "axial strain", **strain_kw)
    show(axes[1, 0], ds.modulus, "Young's modulus", f"modulus ({units})", cmap="cividis")
    for i, m in enumerate(methods, start=1):
        name = METHOD_NAMES.get(str(m), str(m))
        show(
            axes[0, i], ds.strain.sel({"method": m}), f"{name}\nstrain", "axial strain", **strain_kw
        )
        err = ds.error.sel({"method": m})
        rms = float(np.sqrt((err**2).mean()))
        show(
            axes[1, i],
            err,
            f"{name}\nerror (rms {rms:.1e})",
            "strain error",
            cmap="RdBu_r",
            vmin=-lim,
            vmax=lim,
        )
    return fig


def plot_inclusion(ds: xr.Dataset) -> Figure:
    """As :func:`plot_phantom`, for the finite-element inclusion phantom."""
    return plot_phantom(ds)


# --------------------------------------------------------------------------------------------
# Failure maps
# --------------------------------------------------------------------------------------------


#: The one-parameter sweeps of the failure maps; a sweep's index is part of its points' seeds.
FAILURE_SWEEPS = ("strain", "snr_db", "window", "k0_dk", "fwhm_fraction", "density")


def failure_config(cfg: Mapping) -> dict:
    """The ``elastography`` section with the failure maps' own image size
    (``failure.n_pixels`` x ``failure.n_alines``, depth x A-lines)."""
    fc = cfg["failure"]
    return {**cfg, "n_pixels": int(fc["n_pixels"]), "n_alines": int(fc["n_alines"])}


def point_seeds(seed: int, sweep_index: int, point: int, replicate: int) -> tuple[int, int, int]:
    """Scene and the two noise seeds of one failure-map image pair.

    Drawn from ``SeedSequence(seed, spawn_key=(sweep_index, point, replicate))`` (the sweep's
    index in :data:`FAILURE_SWEEPS`, the point's in its sweep): every point and repeat has its
    own independent stream, whatever the order or the Dask worker that runs it.
    """
    key = (sweep_index, point, replicate)
    state = np.random.SeedSequence(seed, spawn_key=key).generate_state(3)
    return int(state[0]), int(state[1]), int(state[2])


def _failure_point(cfg, seeds, methods, *, strain, snr_db=None, window=None, **scene_kw):
    scene_seed, noise1, noise2 = seeds
    (ref, dfm), k0 = _images(cfg, scene_seed, [_uniform(0.0), _uniform(strain)], **scene_kw)
    a1, a2 = _noisy(ref, snr_db, noise1), _noisy(dfm, snr_db, noise2)
    out = []
    for m in methods:
        est = _estimate(a1, a2, k0, cfg, m, window)
        truth = abs(strain) if method_options(m)[0] == "correlation" else strain
        out.append(strain_scores(est, truth))
    return np.array(out)  # (method, 3)


def failure_point(
    case: int, replicate: int, *, cases: list, cfg: Mapping, seed: int, methods: list
) -> xr.Dataset:
    """Scores of every method on one seeded image pair of a failure-map point.

    ``cases[case]`` is ``(sweep index, point index, keyword arguments)``; the pair is drawn
    from :func:`point_seeds` (``seed``, sweep, point, ``replicate``). Returns
    ``median_error``, ``rms_error`` and ``answered`` over ``method`` (a task of
    :func:`speckle.sweep.sweep`).
    """
    sweep_i, point_i, kw = cases[case]
    res = _failure_point(cfg, point_seeds(seed, sweep_i, point_i, replicate), methods, **kw)
    return xr.Dataset(
        {
            "median_error": ("method", res[:, 0]),
            "rms_error": ("method", res[:, 1]),
            "answered": ("method", res[:, 2]),
        },
        coords={"method": list(methods)},
    )


def predicted_limits(cfg: Mapping) -> dict[str, float]:
    """Where theory puts each limit at the base parameters (strain values).

    ``wrap_single_lag`` = 1/(2 R L) (vector, one lag L), ``wrap_lag1`` = 1/(2 R) (multi-lag
    vector and the per-pixel unwrapping of wls), ``decorrelation`` = strain where the theory
    complex correlation after compensation falls to 0.5, ``speckle_displacement`` = strain
    at which the displacement at mid-depth reaches the half-width of the field's depth
    autocorrelation (where an unaligned pair has decorrelated to 0.5 there).
    """
    src = _source(cfg)
    r = float(src.attrs["k0_dk"])
    n = int(cfg["n_pixels"])
    (ref,), _ = _images(cfg, 0, [_uniform(0.0)])
    lag = choose_lag(ref)
    grid = np.geomspace(1e-4, 0.5, 200)
    gamma = expected_correlation(grid, spectrum=src, density=float(cfg["density"]))
    below = np.flatnonzero(gamma["complex"].values < 0.5)
    return {
        "lag": lag,
        "wrap_single_lag": 1 / (2 * r * lag),
        "wrap_lag1": 1 / (2 * r),
        "decorrelation": float(grid[below[0]]) if below.size else np.nan,
        "speckle_displacement": _half_width(ref) / (n / 2),
    }


def _half_width(image: np.ndarray) -> float:
    """Lag (pixels, linear interpolation) where the depth autocorrelation falls to 0.5."""
    rho = depth_autocorrelation(image, min(32, image.shape[0] // 4))
    below = np.flatnonzero(rho < 0.5)
    if not below.size:
        return np.nan
    i = below[0]
    return float(i - 1 + (rho[i - 1] - 0.5) / (rho[i - 1] - rho[i]))


def _over_seeds(key: str, dim: str, values: np.ndarray, long_name: str) -> dict:
    """``key`` (mean over seeds), ``key_se`` (its standard error) and ``key_per_seed`` of the
    per-seed ``values`` over ``(dim, method, replicate)``."""
    mean, se = mean_and_se(values)
    dims = (dim, "method")
    return {
        key: (dims, mean, attrs("dimensionless", f"{long_name}, mean over seeds")),
        f"{key}_se": (dims, se, attrs("dimensionless", f"standard error of {key} (seeds)")),
        f"{key}_per_seed": (
            (*dims, "replicate"),
            values,
            attrs("dimensionless", f"{long_name}, per seed"),
        ),
    }


def failure_data(
    cfg: Mapping,
    seed: int,
    *,
    dask: Mapping | None = None,
    threads: int | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Error and answered fraction of every method along one-parameter sweeps, over seeds.

    Sweeps (others at the base): interframe strain, SNR (null = noise-free), depth window,
    k0/delta_k, spectrum FWHM (fraction of delta_k) and scatterer density, on images of
    ``failure.n_pixels`` x ``failure.n_alines`` px. Every point is repeated on
    ``failure.n_seeds`` independent scenes (:func:`point_seeds`); the points and repeats run
    in parallel on the Dask scheduler of ``dask`` (the pipeline's ``dask`` section, workers
    capped at ``threads``) through :func:`speckle.sweep.sweep`, so the numbers do not depend on
    the scheduler or the number of workers.

    Parameters
    ----------
    cfg : Mapping
        The pipeline's ``elastography`` section.
    seed : int
        The pipeline seed.
    dask : Mapping, optional
        The pipeline's ``dask`` section (default: Dask's threads).
    threads : int, optional
        Cap on local Dask workers (the rule's Snakemake threads).
    progress : bool
        Show a Dask progress bar.

    Returns
    -------
    xarray.Dataset
        For each sweep ``<s>``, over ``(<s>, method)``: ``relative_rms_error_<s>`` (rms error
        over the answered pixels divided by the true strain, mean over seeds) and
        ``relative_rms_error_<s>_se`` (its standard error), ``answered_<s>`` and
        ``answered_<s>_se``, ``median_error_<s>`` and ``rms_error_<s>`` (means over seeds);
        per seed over ``(<s>, method, replicate)``: ``relative_rms_error_<s>_per_seed`` and
        ``answered_<s>_per_seed``. Also ``predicted_noise_snr_db`` and the predicted limits
        (attributes ``limit_*``).
    """
    fc = cfg["failure"]
    fcfg = failure_config(cfg)
    methods = list(cfg["methods"])
    n_seeds = int(fc["n_seeds"])
    base = {"strain": float(fc["base_strain"]), "snr_db": fc.get("base_snr_db")}
    sweeps = {
        "strain": [{"strain": float(s)} for s in fc["strain"]],
        "snr_db": [{"snr_db": s} for s in fc["snr_db"]],
        "window": [{"window": _window(fcfg, w)} for w in fc["windows"]],
        "k0_dk": [{"k0_dk": float(v)} for v in fc["k0_dk"]],
        "fwhm_fraction": [{"fwhm": float(v)} for v in fc["fwhm_fraction"]],
        "density": [{"density": float(v)} for v in fc["density"]],
    }
    coords = {
        "strain": fc["strain"],
        "snr_db": [np.inf if s is None else float(s) for s in fc["snr_db"]],
        "window": fc["windows"],
        "k0_dk": fc["k0_dk"],
        "fwhm_fraction": fc["fwhm_fraction"],
        "density": fc["density"],
    }
    cases = [
        (i, j, {**base, **pt})
        for i, name in enumerate(FAILURE_SWEEPS)
        for j, pt in enumerate(sweeps[name])
    ]
    scores = sweep(
        failure_point,
        {"case": list(range(len(cases))), "replicate": list(range(n_seeds))},
        fixed={"cases": cases, "cfg": fcfg, "seed": int(seed), "methods": methods},
        progress=progress,
        **dask_options(dask or {}, threads),
    )
    data = {}
    for i, name in enumerate(FAILURE_SWEEPS):
        rows = [c for c, (si, _, _) in enumerate(cases) if si == i]
        part = scores.isel(case=rows).transpose("case", "method", "replicate")
        scale = np.abs(np.asarray(coords["strain"], float)) if name == "strain" else base["strain"]
        scale = np.reshape(scale, (-1, 1, 1)) if name == "strain" else scale
        what = "true strain" if name == "strain" else "base strain"
        for var, long_name in (
            ("median_error", "median of estimate minus truth, mean over seeds"),
            ("rms_error", "rms of estimate minus truth, mean over seeds"),
        ):
            mean = mean_and_se(part[var].values)[0]
            data[f"{var}_{name}"] = (
                (name, "method"),
                mean,
                {**STRAIN_ERROR, "long_name": long_name},
            )
        data.update(
            _over_seeds(
                f"relative_rms_error_{name}",
                name,
                part["rms_error"].values / scale,
                f"rms error / {what}",
            )
        )
        data.update(
            _over_seeds(
                f"answered_{name}", name, part["answered"].values, "fraction of pixels answered"
            )
        )
    # predicted strain noise of the vector method at each SNR (noise-free images, base strain)
    (ref, dfm), k0 = _images(fcfg, seed, [_uniform(0.0), _uniform(base["strain"])])
    pred = []
    for s in coords["snr_db"]:
        if np.isinf(s):
            pred.append(np.nan)
            continue
        std = predicted_strain_std(
            ref,
            dfm,
            noise_power=noise_power(ref, s),
            k0=k0,
            pixel_size=float(cfg["pixel_size"]),
            window=_window(fcfg),
        )
        pred.append(float(np.sqrt(np.nanmean(std**2))))
    data["predicted_noise_snr_db"] = (
        ("snr_db",),
        np.array(pred),
        attrs("strain", "predicted rms strain noise, vector method"),
    )
    limits = predicted_limits(fcfg)
    coord_attrs = {
        "strain": attrs("strain", "interframe strain (compression > 0)"),
        "snr_db": attrs("level", "SNR, mean intensity / noise power (inf: noise-free)"),
        "window": attrs("axial_lag", "depth window of the estimators (pixels)"),
        "k0_dk": attrs("k0_dk"),
        "fwhm_fraction": attrs("dimensionless", "spectrum FWHM / delta_k"),
        "density": attrs("density"),
    }
    return xr.Dataset(
        data,
        coords={
            "method": methods,
            "replicate": ("replicate", np.arange(n_seeds), attrs("dimensionless", "seed index")),
            **{k: (k, np.asarray(v, float), coord_attrs[k]) for k, v in coords.items()},
        },
        attrs={
            **{f"limit_{k}": v for k, v in limits.items()},
            "base_strain": base["strain"],
            "n_pixels": fcfg["n_pixels"],
            "n_alines": fcfg["n_alines"],
            "n_seeds": n_seeds,
            "seed": seed,
            "seeds": "SeedSequence(seed, spawn_key=(sweep, point, replicate)), "
            "sweeps in the order " + ", ".join(FAILURE_SWEEPS),
            **provenance_attrs(),
        },
    )


def _seed_bars(ax, ds: xr.Dataset, var: str, sel: dict, x: np.ndarray, **style):
    """Mean over seeds of ``var`` against ``x`` with its ``<var>_se`` error bars."""
    mean, se = (ds[v].isel(sel).values for v in (var, f"{var}_se"))
    return ax.errorbar(x, mean, yerr=se, fmt="o-", ms=3, lw=0.8, capsize=2, **style)


#: Axis labels of the failure maps' sweeps, in words with units.
SWEEP_LABELS = {
    "strain": "applied strain",
    "snr_db": "SNR (dB; noise-free drawn right)",
    "window": "depth window (pixels)",
    "k0_dk": "k0/Δk",
    "fwhm_fraction": "spectrum FWHM / Δk",
    "density": "scatterers per pixel",
}
#: Predicted strain limits (``limit_<key>`` attributes) in words.
LIMIT_LABELS = {
    "wrap_single_lag": "phase wraps (single lag)",
    "wrap_lag1": "phase wraps (lag 1)",
    "decorrelation": "decorrelation",
    "speckle_displacement": "speckle displacement",
}


def plot_failure(ds: xr.Dataset) -> Figure:
    """Failure maps: rms error / strain (top) and fraction answered (bottom) per sweep, with
    limits. Points are the means over seeds, bars +- one standard error; one legend, right."""
    fig, axes = new_figure(
        2,
        len(FAILURE_SWEEPS),
        width=2.3 * len(FAILURE_SWEEPS) + 2.2,
        height=5.0,
        sharex="col",
    )
    handles: dict = {}
    for j, name in enumerate(FAILURE_SWEEPS):
        x = ds[name].values.astype(float)
        xplot = (
            np.where(np.isinf(x), np.nanmax(x[np.isfinite(x)]) + 10, x) if name == "snr_db" else x
        )
        for i, m in enumerate(ds.method.values):
            sel = {"method": i}  # by position: a str index read back from NetCDF may not select
            style = {"color": estimator_colour(m)}
            var = f"relative_rms_error_{name}"
            line = _seed_bars(axes[0, j], ds, var, sel, xplot, **style)
            _seed_bars(axes[1, j], ds, f"answered_{name}", sel, xplot, **style)
            handles.setdefault(METHOD_NAMES.get(str(m), str(m)), line)
        axes[0, j].set_yscale("log")
        axes[0, j].set_title(f"against {SWEEP_LABELS[name].split(' (')[0]}")
        axes[1, j].set_xlabel(SWEEP_LABELS[name])
        if name in ("strain", "density"):
            axes[0, j].set_xscale("log")
            axes[1, j].set_xscale("log")
        if name == "snr_db" and np.isinf(x).any():
            ticks = [v for v in xplot if np.isfinite(v)]
            labels = ["∞" if np.isinf(v) else f"{v:g}" for v in x]
            for ax in axes[:, j]:
                ax.set_xticks(ticks, labels)
        if name == "strain":
            for key, ls in (
                ("wrap_single_lag", ":"),
                ("wrap_lag1", "--"),
                ("decorrelation", "-."),
                ("speckle_displacement", "-"),
            ):
                v = ds.attrs[f"limit_{key}"]
                if np.isfinite(v):
                    line = axes[0, j].axvline(v, color="k", ls=ls, lw=0.7)
                    handles.setdefault(f"predicted limit: {LIMIT_LABELS[key]}", line)
        if name == "snr_db":
            pred = ds["predicted_noise_snr_db"].values / ds.attrs["base_strain"]
            (line,) = axes[0, j].plot(xplot, pred, "k--", lw=0.8)
            handles.setdefault("predicted noise error (vector)", line)
    for ax in axes[0]:
        ax.set_ylabel("rms strain error / strain")
    for ax in axes[1]:
        ax.set_ylabel("fraction of pixels answered")
    fig.legend(list(handles.values()), list(handles), loc="outside right center", frameon=False)
    fig.suptitle(
        f"Where each strain estimator fails: {ds.attrs['n_pixels']} x {ds.attrs['n_alines']} "
        f"pixel images, mean ± standard error over {ds.attrs['n_seeds']} seeds"
    )
    return fig


# --------------------------------------------------------------------------------------------
# Speed versus accuracy
# --------------------------------------------------------------------------------------------


def speed_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """rms strain error against time per megapixel, for every method and depth window."""
    sc = cfg["speed"]
    s = float(sc["strain"])
    (ref, dfm), k0 = _images(cfg, seed, [_uniform(0.0), _uniform(s)])
    methods, windows = list(cfg["methods"]), list(sc["windows"])
    times = np.full((len(methods), len(windows)), np.nan)
    errors = np.full_like(times, np.nan)
    for i, m in enumerate(methods):
        for j, w in enumerate(windows):
            best = np.inf
            for _ in range(int(sc["repeat"])):
                t0 = time.perf_counter()
                est = _estimate(ref, dfm, k0, cfg, m, _window(cfg, w))
                best = min(best, time.perf_counter() - t0)
            times[i, j] = best / (ref.size / 1e6)
            errors[i, j] = strain_scores(est, s)[1] / s
    return xr.Dataset(
        {
            "time_per_megapixel": (
                ("method", "window"),
                times,
                attrs("time", "time per megapixel"),
            ),
            "relative_rms_error": (
                ("method", "window"),
                errors,
                attrs("dimensionless", "rms strain error / strain"),
            ),
        },
        coords={"method": methods, "window": windows},
        attrs={"strain": s, "image_pixels": ref.size, "seed": seed, **provenance_attrs()},
    )


def plot_speed(ds: xr.Dataset) -> Figure:
    """Rms strain error against time per megapixel for each method and window."""
    fig, axes = new_figure(1, 1, width=4.5, height=3.5)
    ax = axes[0, 0]
    for m in ds.method.values:
        t = ds.time_per_megapixel.sel({"method": m}).values
        e = ds.relative_rms_error.sel({"method": m}).values
        ax.plot(t, e, "o-", ms=4, lw=0.8, label=str(m))
        for w, ti, ei in zip(ds.window.values, t, e, strict=True):
            ax.annotate(str(int(w)), (ti, ei), fontsize=7)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per megapixel (s)")
    ax.set_ylabel(f"rms strain error / strain (strain {ds.attrs['strain']:g})")
    ax.set_title("numbers: depth window (pixels)")
    for line in ax.get_lines():
        line.set_color(estimator_colour(line.get_label()))
        line.set_label(METHOD_NAMES.get(line.get_label(), line.get_label()))
    legend_outside(ax)
    return fig


# --------------------------------------------------------------------------------------------
# Compression sequence
# --------------------------------------------------------------------------------------------


def sequence_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """Cumulative strain of a compression sequence against the truth ``1 - (1 - s)^k``."""
    sq = cfg["sequence"]
    s, n_frames = float(sq["strain"]), int(sq["n_frames"])
    totals = [1 - (1 - s) ** k for k in range(n_frames)]
    frames, k0 = _images(cfg, seed, [_uniform(t) for t in totals], max_strain=max(totals))
    out = accumulate_strain(
        np.array(frames),
        k0=k0,
        pixel_size=float(cfg["pixel_size"]),
        method=sq.get("method", "vector"),
        window=_window(cfg),
    )
    truth = np.array(totals[1:])
    cum = out["accumulated"].values
    med = np.array([np.nanmedian(c) for c in cum])
    rms = np.array([np.sqrt(np.nanmean((c - t) ** 2)) for c, t in zip(cum, truth, strict=True)])
    out["true_cumulative"] = ("frame", truth, STRAIN)
    out["median_cumulative"] = ("frame", med, STRAIN)
    out["rms_error_cumulative"] = (
        "frame",
        rms,
        attrs("strain", "rms error of the cumulative strain"),
    )
    out.attrs.update({"interframe_strain": s, "seed": seed, **provenance_attrs()})
    return out


def plot_sequence(ds: xr.Dataset) -> Figure:
    """Accumulated strain of a compression sequence against the truth, per frame."""
    fig, axes = new_figure(1, 2, width=7.0, height=3.0)
    f = ds.frame.values
    axes[0, 0].plot(f, ds.true_cumulative, "k-", label="truth 1 - (1 - s)^k")
    axes[0, 0].plot(f, ds.median_cumulative, "o", label="accumulated (median)")
    axes[0, 0].set_xlabel("frame")
    axes[0, 0].set_ylabel("cumulative axial strain")
    legend_outside(axes[0, 0])
    rel = (ds.median_cumulative - ds.true_cumulative) / ds.true_cumulative
    axes[0, 1].plot(f, rel, "o-", label="median error / truth")
    axes[0, 1].plot(f, ds.rms_error_cumulative / ds.true_cumulative, "s-", label="rms / truth")
    axes[0, 1].set_xlabel("frame")
    axes[0, 1].set_ylabel("relative error of the cumulative strain")
    for ax in axes[0]:
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    legend_outside(axes[0, 1])
    return fig


# --------------------------------------------------------------------------------------------
# A long compression sequence of the FE inclusion phantom, lazily (Dask) and streamed
# --------------------------------------------------------------------------------------------


def _inclusion_frame(cfg: Mapping, seed: int, disp: xr.Dataset, k: int, max_strain: float):
    """Frame ``k``: the seeded inclusion scene displaced by ``k`` times the per-frame FE field
    (linear elasticity: the displacement is proportional to the applied strain)."""
    ic = cfg["inclusion"]
    lines = int(cfg["sequence_large"].get("n_alines", ic.get("n_alines", cfg["n_alines"])))
    scene = _scene(cfg, seed, lines, float(cfg["density"]), max_strain)
    img = bscan(
        displace(scene, disp * k), _source(cfg, None, None), method=cfg["method"], tol=cfg["tol"]
    )
    return img.field.transpose("depth", "x").values[None]


def sequence_large_frames(cfg: Mapping, seed: int) -> tuple[xr.DataArray, float]:
    """The compression sequence of the FE inclusion phantom as a lazy (Dask) DataArray
    ``(frame, depth, x)`` (each frame one task), and ``k0`` (rad/µm)."""
    import dask
    import dask.array as da

    sq, ic = cfg["sequence_large"], cfg["inclusion"]
    n = int(cfg["n_pixels"])
    lines = int(sq.get("n_alines", ic.get("n_alines", cfg["n_alines"])))
    n_frames, s = int(sq["n_frames"]), float(sq["strain"])
    p = float(cfg["pixel_size"])
    depth, x = np.arange(n) * p, np.arange(lines) * p
    _, fe = _inclusion_fe(cfg, lines, s)
    disp = fe[["uz", "ux"]].load()
    max_strain = min(0.5, 2 * n_frames * s)
    parts = [
        da.from_delayed(
            dask.delayed(_inclusion_frame)(cfg, seed, disp, k, max_strain), (1, n, lines), complex
        )
        for k in range(n_frames)
    ]
    frames = xr.DataArray(
        da.concatenate(parts),
        dims=("frame", "depth", "x"),
        coords={"frame": np.arange(n_frames), "depth": depth, "x": x},
    )
    return frames, float(_source(cfg, None, None).attrs["k0"])


def sequence_large_data(cfg: Mapping, seed: int, path: str) -> xr.Dataset:
    """Simulate and process the sequence on the active Dask scheduler, streaming the result
    (interframe and cumulative strain, quality, positions) to ``path``; returns it, lazily."""
    frames, k0 = sequence_large_frames(cfg, seed)
    return accumulate_strain(
        frames,
        k0=k0,
        pixel_size=float(cfg["pixel_size"]),
        method=cfg["sequence_large"].get("method", "vector"),
        window=_window(cfg),
        path=path,
        progress=True,
    )


def plot_sequence_large(ds: xr.Dataset, per_frame: float) -> Figure:
    """Cumulative strain of the last frame (physical aspect ratio), and its median per frame
    against the nominal ``1 - (1 - s)^k``."""
    fig, axes = new_figure(1, 2, width=7.0, height=3.6, width_ratios=[1, 1.4])
    last = ds["accumulated"].isel(frame=-1)
    im = physical_image(axes[0, 0], last.values, ds.depth.values, ds.x.values, cmap="viridis")
    axes[0, 0].xaxis.set_major_locator(MaxNLocator(2))
    colorbar(fig, im, axes[0, 0], "cumulative axial strain")
    axes[0, 0].set_title(f"frame {int(ds.frame[-1])} against frame 0")
    med = [
        float(np.nanmedian(ds["accumulated"].isel(frame=i).values))
        for i in range(ds.sizes["frame"])
    ]
    f = ds.frame.values
    axes[0, 1].plot(f, med, "o", label="accumulated (median)")
    axes[0, 1].plot(f, 1 - (1 - per_frame) ** f, "k-", label="nominal 1 - (1 - s)^k")
    axes[0, 1].set_xlabel("frame k")
    axes[0, 1].xaxis.set_major_locator(MaxNLocator(integer=True))
    axes[0, 1].set_ylabel("cumulative axial strain")
    axes[0, 1].set_title(f"s = {per_frame:g} per frame")
    legend_outside(axes[0, 1])
    return fig
