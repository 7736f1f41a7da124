"""Speckle suppression against a known truth: the phantom, every method, where each one fails.

Datasets (``<name>_data(cfg, seed) -> Dataset``) and figures (``plot_<name>(ds) -> Figure``) of
``results/despeckle/``:

* :func:`phantom_data` / :func:`plot_phantom`: the phantom (air with point targets, two layers
  whose boundary is a step edge, an inclusion), its region map and speckle-free truth, the
  noisy single look and the best method of each family (highest SSIM);
* :func:`methods_data` / :func:`plot_methods`: every physical compounding (frequency, angular,
  spatial, polarization, temporal; averaged in intensity, magnitude or complex; with and
  without receiver noise) and every digital filter (linear and log data, parameters swept) by
  every metric of :mod:`speckle.analysis.image_quality`, with the Pareto charts of speckle
  reduction against resolution loss and against time;
* :func:`failure_data` / :func:`plot_failure`: each family's representative method against
  scatterer density, SNR and feature size, marking where it stops helping or erases the
  feature;
* :func:`frequency_compounding_data`: split-spectrum contrast and axial FWHM against
  ``looks`` = 1, 2, 4, 8, measured and theory.

Conventions. Every processed image is calibrated to the truth's mean in the uniform region
(one gain, as a user calibrates), then: contrast and ENL in the uniform region (linear
intensity), CNR inclusion/background and PSNR/SSIM on dB images referred to the truth's
uniform-region mean (window ``[-30, +15]`` dB), point-target FWHM (axial, lateral) on linear
intensity, and the 10-90 % width of the layer step edge with its standard error (4 blocks of
lines); ``resolution_loss`` is the larger of the two point-target FWHM ratios to the single
look's, and ``resolution_loss_with_edge`` the larger of that and the edge-width ratio (the
edge width of a speckled image carries an SE as large as itself, but a filter that widens the
edge 3 times loses resolution even where its point targets stay sharp); the Pareto charts use
``resolution_loss_with_edge``. Physical methods' ``time_per_mpx`` is the
processing of the acquired looks (splitting, registration, averaging), their acquisition
count is ``acquisitions``; filters' is the filter's run time.
"""

from __future__ import annotations

import textwrap
import time
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import compounding as cp
from ..analysis import filters as dsp
from ..analysis import image_quality as iq
from ..conventions import attrs, coord
from ..imaging._bscan import bscan
from ..imaging.aline import ascan
from ..imaging.scan import scan_image
from ..scene.scatterers import random_scatterers
from ..studies.looks import angular_looks, polarization_looks, spatial_looks, temporal_looks
from ..studies.suppression import DB_RANGE, DB_TOP, METRICS, build_phantom, quality
from ..system.source import spectrum
from .style import colorbar, mark_no_colorbar, new_figure, physical_image

__all__ = [
    "FAMILIES",
    "build_phantom",
    "failure_data",
    "frequency_compounding_data",
    "methods_data",
    "parameter_grid",
    "phantom_data",
    "plot_failure",
    "plot_methods",
    "plot_phantom",
]

#: Method families, physical then digital.
FAMILIES = ("frequency", "angular", "spatial", "polarization", "temporal", *dsp.FILTERS)
#: "Stops helping": speckle reduction (single-look contrast / contrast) below this.
HELPS = 1.1
#: "Erases the feature": less than this fraction of the truth's inclusion contrast (dB) kept.
ERASES = 0.5


# --------------------------------------------------------------------------- the methods
def _physical_looks(ph: dict, cfg: Mapping, seed: int, snr_db: float) -> dict:
    """Noise-free and noisy looks of every physical family (largest set of each), and the
    time spent processing them: {family: (looks, noisy, process_seconds_per_look_set)}."""
    src, sc, kw = ph["source"], ph["scene"], ph["kw"]
    single = scan_image(sc, src, **kw).field.values
    out = {"single": single}
    ref = float(np.mean(np.abs(single) ** 2))
    base = xr.DataArray(single[None], dims=("look", "depth", "x"))
    noisy_single = cp.noisy_looks(base, snr_db, seed=seed, signal_intensity=ref)
    out["single_noisy"] = noisy_single.values[0]
    phys = cfg["physical"]
    for fam in ("angular", "spatial", "polarization", "temporal"):
        out[fam] = _family_looks(fam, phys[fam], ph, seed)
    for fam in ("angular", "spatial", "polarization", "temporal"):
        out[fam + "_noisy"] = cp.noisy_looks(out[fam], snr_db, seed=seed + 3, signal_intensity=ref)
    out["ref_intensity"] = ref
    return out


def _family_looks(fam: str, spec: Mapping, ph: dict, seed: int) -> xr.DataArray:
    """Noise-free looks of physical family ``fam`` on phantom ``ph``, as its config ``spec`` says.

    The polarization and temporal looks are seeded by ``seed + 1`` and ``seed + 2``.
    """
    src, sc, kw = ph["source"], ph["scene"], ph["kw"]
    if fam == "angular":
        return angular_looks(sc, src, spec["angles"], **kw)
    if fam == "spatial":
        return spatial_looks(sc, src, spec["offsets"], **kw)
    if fam == "polarization":
        return polarization_looks(sc, src, spec["depolarization"], seed=seed + 1, **kw)
    if fam == "temporal":
        return temporal_looks(
            sc,
            src,
            spec["frames"],
            diffusion=spec["diffusion"],
            interval=spec["interval"],
            seed=seed + 2,
            **kw,
        )
    raise ValueError(f"unknown method family {fam!r}; allowed: {FAMILIES}")


def _central(looks: xr.DataArray, n: int) -> xr.DataArray:
    """The ``n`` central looks (symmetric sets of angles/offsets) or the first ``n`` frames."""
    size = looks.sizes["look"]
    if looks.attrs.get("compounding") == "temporal":
        return looks.isel(look=slice(0, n))
    lo = (size - n) // 2
    return looks.isel(look=slice(lo, lo + n))


def physical_methods(ph: dict, cfg: Mapping, seed: int, snr_db: float) -> tuple[dict, list]:
    """The acquired looks and (family, label, params, acquisitions, looks_fn) of every method.

    ``looks_fn(noisy) -> (looks, seconds)`` gives the complex looks and the processing time.
    """
    lk = _physical_looks(ph, cfg, seed, snr_db)
    return lk, list(_physical_methods(lk, ph, cfg))


def _physical_methods(lk: dict, ph: dict, cfg: Mapping):
    phys = cfg["physical"]
    fr = phys["frequency"]
    n = ph["geo"]["n_pixels"]
    for nlook in fr["looks"]:
        for win in fr["apodizations"]:
            for ov in fr["overlap"]:
                w = cp.subband_apodizations(n, nlook, apodization=win, overlap=ov)

                def fn(noisy, w=w):
                    f = lk["single_noisy" if noisy else "single"]
                    t = time.perf_counter()
                    out = cp.frequency_looks(xr.DataArray(f, dims=("depth", "x")), w)
                    return out, time.perf_counter() - t

                yield (
                    "frequency",
                    f"L={nlook} {win} overlap={ov:g}",
                    {"looks": nlook, "apodization": win, "overlap": ov},
                    1,
                    fn,
                )
    for fam in ("angular", "spatial", "temporal"):
        for m in phys[fam]["sets"]:

            def fn(noisy, fam=fam, m=m):
                t = time.perf_counter()
                out = _central(lk[fam + ("_noisy" if noisy else "")], m)
                return out, time.perf_counter() - t

            yield (fam, f"L={m}", {"looks": m}, m, fn)

    def pol(noisy):
        return lk["polarization" + ("_noisy" if noisy else "")], 0.0

    yield (
        "polarization",
        "co+cross",
        {"depolarization": phys["polarization"]["depolarization"]},
        1,
        pol,
    )


def parameter_grid(params: Mapping) -> list[dict]:
    """Every combination of a filter's swept parameters (``{name: [values]}``), in order.

    Examples
    --------
    >>> parameter_grid({"size": [3, 5], "k": [1.0]})
    [{'size': 3, 'k': 1.0}, {'size': 5, 'k': 1.0}]
    >>> parameter_grid({})
    [{}]
    """
    keys = list(params)
    if not keys:
        return [{}]
    out = [{}]
    for k in keys:
        out = [{**o, k: v} for o in out for v in params[k]]
    return out


def _table(rows: list[dict], extra: Mapping | None = None) -> xr.Dataset:
    labels = [r["method"] for r in rows]
    data = {}
    for k, (quantity, long) in {**METRICS, **(extra or {})}.items():
        data[k] = (
            "technique",
            np.array([r.get(k, np.nan) for r in rows], float),
            attrs(quantity, long),
        )
    coords = {"technique": ("technique", labels)}
    for k in ("family", "parameters", "averaging", "domain"):
        coords[k] = ("technique", [str(r.get(k, "")) for r in rows])
    coords["noise"] = (
        "technique",
        np.array([int(r.get("noise", 1)) for r in rows], np.int8),
        {"long_name": "receiver noise in the looks (1) or not (0)"},
    )
    return xr.Dataset(data, coords=coords)


def methods_data(cfg: Mapping, seed: int) -> tuple[xr.Dataset, xr.Dataset]:
    """Every method by every metric on the phantom; returns (methods, phantom) datasets."""
    ph = build_phantom(
        cfg["phantom"],
        seed=seed,
        margin_angle=max(abs(a) for a in cfg["physical"]["angular"]["angles"]),
    )
    snr = float(cfg["phantom"]["snr_db"])
    rows = []
    best: dict[str, tuple[float, np.ndarray, str]] = {}
    npx = int(ph["truth"].size)

    def add(row: dict, img: np.ndarray) -> None:
        row.update(quality(img, ph))
        rows.append(row)
        fam = row["family"]
        if row.get("noise", 1) and (fam not in best or row["ssim"] > best[fam][0]):
            best[fam] = (row["ssim"], img, row["method"])

    single, methods = physical_methods(ph, cfg, seed, snr)
    for noisy in (0, 1):
        img = np.abs(single["single_noisy" if noisy else "single"]) ** 2
        add(
            {
                "method": f"single look{' + noise' if noisy else ''}",
                "family": "single",
                "parameters": "",
                "averaging": "",
                "noise": noisy,
                "acquisitions": 1,
                "time_per_mpx": 0.0,
            },
            img,
        )
    for fam, label, _params, acq, fn in methods:
        for noisy in (0, 1):
            looks, secs = fn(bool(noisy))
            for mode in cfg["physical"]["averaging"]:
                t = time.perf_counter()
                img = cp.compound(looks, mode).values
                secs_all = secs + time.perf_counter() - t
                add(
                    {
                        "method": f"{fam} {label} {mode}{' + noise' if noisy else ''}",
                        "family": fam,
                        "parameters": label,
                        "averaging": mode,
                        "noise": noisy,
                        "acquisitions": acq,
                        "time_per_mpx": secs_all * 1e6 / npx,
                    },
                    img,
                )
    noisy_img = np.abs(single["single_noisy"]) ** 2
    for name, params in cfg["filters"].items():
        if not dsp.filter_available(name):
            continue
        for domain in cfg["domains"]:
            for p in parameter_grid(params):
                t = time.perf_counter()
                img = dsp.despeckle(noisy_img, name, p, domain=domain)
                secs = time.perf_counter() - t
                label = " ".join(f"{k}={v}" for k, v in p.items())
                add(
                    {
                        "method": f"{name} {domain} {label}",
                        "family": name,
                        "parameters": label,
                        "domain": domain,
                        "noise": 1,
                        "acquisitions": 1,
                        "time_per_mpx": secs * 1e6 / npx,
                    },
                    img,
                )
    extra = {
        "acquisitions": ("count", "acquisitions (looks acquired)"),
        "time_per_mpx": ("time", "processing time per megapixel"),
    }
    ds = _table(rows, extra)
    i_ref = int(np.flatnonzero(ds.technique.values == "single look + noise")[0])
    ref = {k: float(v) for k, v in ds.isel(technique=i_ref).data_vars.items()}
    ds["speckle_reduction"] = (ref["contrast"] / ds.contrast).assign_attrs(
        attrs("dimensionless", "single-look contrast over the method's")
    )
    for k in ("fwhm_axial", "fwhm_lateral", "edge_width"):
        ds[k + "_ratio"] = (ds[k] / ref[k]).assign_attrs(
            attrs("dimensionless", f"{k} over the single look's")
        )
    ds["resolution_loss"] = np.maximum(ds.fwhm_axial_ratio, ds.fwhm_lateral_ratio).assign_attrs(
        attrs(
            "dimensionless",
            "larger of the axial and lateral point-target FWHM ratios to the single look",
        )
    )
    ds["resolution_loss_with_edge"] = np.fmax(ds.resolution_loss, ds.edge_width_ratio).assign_attrs(
        attrs(
            "dimensionless",
            "larger of resolution_loss and edge_width_ratio (either where the other is NaN)",
        )
    )
    ds.attrs.update(
        snr_db=snr,
        helps_threshold=HELPS,
        erases_threshold=ERASES,
        db_window=f"[{DB_TOP - DB_RANGE}, {DB_TOP}] dB re the truth's uniform mean",
    )
    fams = [f for f in FAMILIES if f in best]
    x = ph["x"]
    depth = np.arange(ph["geo"]["n_pixels"]) * ph["pixel"]
    coords = {
        "depth": coord("depth", depth, "depth"),
        "x": coord("x", x),
    }
    phantom = xr.Dataset(
        {
            "labels": (
                ("depth", "x"),
                ph["labels"].values,
                attrs("label"),
            ),
            "truth": (
                ("depth", "x"),
                ph["truth"],
                attrs("dimensionless", "speckle-free intensity E|A|^2"),
            ),
            "single_look": (
                ("depth", "x"),
                noisy_img,
                attrs("dimensionless", "single look with noise"),
            ),
            "best": (
                ("family", "depth", "x"),
                np.stack([best[f][1] for f in fams]),
                attrs("dimensionless", "best method of each family (highest SSIM)"),
            ),
        },
        coords={
            **coords,
            "family": ("family", fams),
            "best_method": ("family", [best[f][2] for f in fams]),
        },
        attrs={
            "region_names": ", ".join(str(v) for v in ph["regions"]["name"].values),
            "reference_intensity": ph["ref"],
            "snr_db": snr,
        },
    )
    return ds, phantom


def phantom_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """The phantom dataset alone (:func:`methods_data` computes it with the table)."""
    return methods_data(cfg, seed)[1]


def _pareto(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Indices of the points not dominated (lower x, higher y), sorted by x."""
    idx = np.argsort(x)
    front, best = [], -np.inf
    for i in idx:
        if np.isfinite(x[i]) and np.isfinite(y[i]) and y[i] > best:
            front.append(i)
            best = y[i]
    return np.array(front, int)


#: One colour per method family in every speckle-suppression figure (methods, failure,
#: phantom): the single look black, physical compounding in the first five of matplotlib's
#: ``tab10``, digital filters in the other five and four dark colours; with the markers of
#: :data:`FAMILY_MARKERS` no two families look alike.
FAMILY_COLOURS = {
    "single": "#000000",
    "frequency": "#1f77b4",
    "angular": "#ff7f0e",
    "spatial": "#2ca02c",
    "polarization": "#d62728",
    "temporal": "#9467bd",
    "median": "#8c564b",
    "nlm": "#e377c2",
    "tv": "#7f7f7f",
    "wavelet": "#bcbd22",
    "bilateral": "#17becf",
    "lee": "#000080",
    "kuan": "#b8860b",
    "frost": "#006400",
    "bm3d": "#800080",
}
#: Markers: square for the single look, circles for physical compounding, triangles for filters.
FAMILY_MARKERS = {"single": "s", **dict.fromkeys(FAMILIES[:5], "o")}
#: Family names in words (legends).
FAMILY_NAMES = {
    "single": "single look",
    "frequency": "frequency compounding",
    "angular": "angular compounding",
    "spatial": "spatial compounding",
    "polarization": "polarization diversity",
    "temporal": "temporal averaging",
    "median": "median filter",
    "nlm": "non-local means",
    "tv": "total variation",
    "wavelet": "wavelet shrinkage",
    "bilateral": "bilateral filter",
    "lee": "Lee filter",
    "kuan": "Kuan filter",
    "frost": "Frost filter",
    "bm3d": "BM3D",
}


def _family_style(fam: str) -> dict:
    """Colour and marker of method family ``fam`` (the same in every figure of the family)."""
    return {"color": FAMILY_COLOURS.get(fam, "k"), "marker": FAMILY_MARKERS.get(fam, "^")}


def plot_methods(ds: xr.Dataset) -> Figure:
    """Pareto charts: speckle reduction against resolution loss (the worse of the point-target
    FWHM and edge-width ratios, ``resolution_loss_with_edge``) and against time per megapixel.
    """
    fig, axes = new_figure(1, 2, width=9.5, height=3.8)
    axes = axes[0]
    sel = ds.isel(technique=np.flatnonzero(ds.noise.values == 1))
    fams = list(dict.fromkeys(sel.family.values.tolist()))
    loss = "resolution_loss_with_edge" if "resolution_loss_with_edge" in sel else "resolution_loss"
    for ax, xv, xl in (
        (
            axes[0],
            loss,
            "resolution loss: worse of point FWHM\nand edge width, ratio to single look",
        ),
        (axes[1], "time_per_mpx", "processing time per megapixel (s)"),
    ):
        x = sel[xv].values.astype(float)
        y = sel.speckle_reduction.values.astype(float)
        if xv == "time_per_mpx":
            x = np.maximum(x, 1e-4)
            ax.set_xscale("log")
        for f in fams:
            m = sel.family.values == f
            ax.scatter(x[m], y[m], s=16, label=FAMILY_NAMES.get(f, f), **_family_style(f))
        front = _pareto(x, y)
        ax.plot(x[front], y[front], "k-", lw=0.8, label="Pareto front")
        ax.set_xlabel(xl)
        ax.set_ylabel("speckle reduction C_single / C")
        ax.axhline(1.0, color="0.6", lw=0.5)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside right center", frameon=False)
    fig.suptitle(f"Every method on the phantom, receiver SNR {ds.attrs.get('snr_db'):g} dB")
    return fig


def plot_phantom(ds: xr.Dataset) -> Figure:
    """Region map, truth, single look (with receiver noise) and the best method of each family
    (highest SSIM; noisy looks), in dB, at the physical aspect ratio with axes in µm and one
    intensity colorbar."""
    nb = ds.sizes["family"]
    ncol = 5
    nrow = int(np.ceil((3 + nb) / ncol))
    fig, axes = new_figure(nrow, ncol, width=11.0, height=2.3 * nrow + 0.3)
    axes = np.atleast_1d(axes).ravel()
    ref = float(ds.attrs["reference_intensity"])
    depth, x = ds.depth.values, ds.x.values
    im = None

    def show(ax, img, title, db=True, color="k"):
        data = iq.to_db(img, ref) if db else img
        kw = {"vmin": -30, "vmax": 15, "cmap": "gray"} if db else {"cmap": "tab10"}
        shown = physical_image(ax, data, depth, x, xlabel="x (µm)", **kw)
        ax.set_title(title, color=color)
        return shown

    regions = show(axes[0], ds.labels.values, "regions", db=False)
    mark_no_colorbar(regions)
    names = [n.strip() for n in str(ds.attrs.get("region_names", "")).split(",") if n.strip()]
    for k, name in enumerate(names):
        axes[0].plot([], [], "s", color=regions.cmap(regions.norm(k)), label=name)
    if names:
        axes[0].legend(
            loc="upper left",
            bbox_to_anchor=(1.0, 1.0),
            frameon=False,
            handlelength=0.8,
            borderaxespad=0.2,
        )
    im = show(axes[1], ds.truth.values, "truth E|A|²")
    show(axes[2], ds.single_look.values, "single look + noise")
    for i in range(nb):
        fam = str(ds.family.values[i])
        how = (
            str(ds.best_method.values[i])
            .removeprefix(fam)
            .removesuffix(" + noise")
            .strip()
            .replace("_", " ")
        )
        show(
            axes[3 + i],
            ds.best.isel(family=i).values,
            f"{FAMILY_NAMES.get(fam, fam)}\n{textwrap.shorten(how, 34, placeholder='...')}",
            color=FAMILY_COLOURS.get(fam, "k"),
        )
    for ax in axes[3 + nb :]:
        ax.axis("off")
    colorbar(
        fig, im, axes[: 3 + nb].tolist(), "intensity (dB re the truth's uniform mean)", shrink=0.6
    )
    return fig


# --------------------------------------------------------------------------- failure map
def _method_image(spec: Mapping, ph: dict, seed: int, snr_db: float, cache: dict) -> np.ndarray:
    """Intensity image of one failure-map method spec on phantom ``ph`` (noisy)."""
    src, sc, kw = ph["source"], ph["scene"], ph["kw"]
    if "single" not in cache:
        cache["single"] = scan_image(sc, src, **kw).field.values
        cache["ref"] = float(np.mean(np.abs(cache["single"]) ** 2))
    ref = cache["ref"]
    fam = spec["family"]

    def noisy(looks):
        return cp.noisy_looks(looks, snr_db, seed=seed + 3, signal_intensity=ref)

    single = xr.DataArray(cache["single"][None], dims=("look", "depth", "x"))
    mode = spec.get("averaging", "intensity")
    if fam == "single":
        return np.abs(noisy(single).values[0]) ** 2
    if fam == "frequency":
        w = cp.subband_apodizations(
            ph["geo"]["n_pixels"],
            spec["looks"],
            apodization=spec["apodization"],
            overlap=spec["overlap"],
        )
        f = noisy(single).isel(look=0)
        return cp.compound(cp.frequency_looks(f, w), mode).values
    if fam in dsp.FILTERS:
        img = np.abs(noisy(single).values[0]) ** 2
        return dsp.despeckle(img, fam, spec.get("params", {}), domain=spec.get("domain", "linear"))
    if fam not in cache:
        cache[fam] = _family_looks(fam, spec, ph, seed)
    return cp.compound(noisy(cache[fam]), mode).values


def failure_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """Each family's method against density, SNR and feature size (``despeckle.failure``)."""
    fc = cfg["failure"]
    geo = {**cfg["phantom"], **fc["phantom"]}
    specs = {"single": {"family": "single"}, **fc["methods"]}
    names = list(specs)
    angle = max([abs(a) for s in specs.values() for a in s.get("angles", [0.0])])
    base_snr = float(geo["snr_db"])
    sweeps = {
        "density": fc["density"],
        "snr_db": fc["snr_db"],
        "feature_radius": fc["feature_radius"],
    }
    out = {}
    for axis, values in sweeps.items():
        res = {
            k: np.full((len(names), len(values)), np.nan)
            for k in ("speckle_reduction", "feature_retained", "ssim", "resolution_loss")
        }
        base_cache: dict = {}
        base_ph = None
        for j, v in enumerate(values):
            if axis == "snr_db":
                if base_ph is None:
                    base_ph = build_phantom(geo, seed=seed, margin_angle=angle)
                ph, cache, snr = base_ph, base_cache, float(v)
            else:
                kwargs = {"density": float(v)} if axis == "density" else {"radius": float(v)}
                ph, cache, snr = (
                    build_phantom(geo, seed=seed, margin_angle=angle, **kwargs),
                    {},
                    base_snr,
                )
            q = {
                name: quality(_method_image(specs[name], ph, seed, snr, cache), ph, edge=False)
                for name in names
            }
            s = q["single"]
            loss_ref = [s["fwhm_axial"], s["fwhm_lateral"]]
            for i, name in enumerate(names):
                m = q[name]
                res["speckle_reduction"][i, j] = s["contrast"] / m["contrast"]
                res["feature_retained"][i, j] = m["feature_retained"]
                res["ssim"][i, j] = m["ssim"]
                res["resolution_loss"][i, j] = max(
                    m["fwhm_axial"] / loss_ref[0], m["fwhm_lateral"] / loss_ref[1]
                )
        dims = ("technique", axis)
        for k, arr in res.items():
            out[f"{k}_{axis}"] = (dims, arr, attrs("dimensionless", f"{k} against {axis}"))
        sr, fr = res["speckle_reduction"], res["feature_retained"]
        out[f"helps_{axis}"] = (
            dims,
            (sr >= HELPS).astype(np.int8),
            attrs("dimensionless", f"1 where speckle_reduction >= {HELPS}, against {axis}"),
        )
        out[f"erases_{axis}"] = (
            dims,
            (fr < ERASES).astype(np.int8),
            attrs("dimensionless", f"1 where feature_retained < {ERASES}, against {axis}"),
        )
    ds = xr.Dataset(
        out,
        coords={
            "technique": ("technique", names),
            "family": ("technique", [specs[n]["family"] for n in names]),
            "density": coord("density", np.asarray(fc["density"], float)),
            "snr_db": coord(
                "level", np.asarray(fc["snr_db"], float), "receiver SNR", dims="snr_db"
            ),
            "feature_radius": coord(
                "dimensionless",
                np.asarray(fc["feature_radius"], float),
                "inclusion radius (pixels)",
                dims="feature_radius",
            ),
        },
    )
    ds.attrs.update(
        helps_threshold=HELPS,
        erases_threshold=ERASES,
        helps="speckle_reduction >= helps_threshold",
        erases="feature_retained < erases_threshold",
    )
    return ds


def plot_failure(ds: xr.Dataset) -> Figure:
    """Speckle reduction and feature retained against density, SNR and feature size; each
    family in its colour of :data:`FAMILY_COLOURS`, one legend right of the panels."""
    axes_names = ("density", "snr_db", "feature_radius")
    fig, axes = new_figure(2, 3, width=11.0, height=5.5)
    names = [str(m) for m in ds.technique.values]
    fams = [str(f) for f in ds.family.values]
    methods = [m for m in names if m != "single"]
    for c, axis in enumerate(axes_names):
        xv = ds[axis].values
        for m in methods:
            i = names.index(m)
            style = _family_style(fams[i])
            sr = ds[f"speckle_reduction_{axis}"].values[i]
            fr = ds[f"feature_retained_{axis}"].values[i]
            label = FAMILY_NAMES.get(fams[i], m) if c == 0 else None
            axes[0, c].plot(xv, sr, "-", ms=3, label=label, **style)
            axes[1, c].plot(xv, fr, "-", ms=3, **style)
            bad = ds[f"helps_{axis}"].values[i] == 0
            axes[0, c].plot(xv[bad], sr[bad], "x", color="k", ms=6)
            er = ds[f"erases_{axis}"].values[i] == 1
            axes[1, c].plot(xv[er], fr[er], "x", color="r", ms=6)
        axes[0, c].axhline(
            ds.attrs["helps_threshold"],
            color="k",
            lw=0.6,
            ls="--",
            label="stops helping below" if c == 0 else None,
        )
        axes[1, c].axhline(ds.attrs["erases_threshold"], color="r", lw=0.6, ls="--")
        for r in range(2):
            if axis == "density":
                axes[r, c].set_xscale("log")
            axes[r, c].set_xlabel(
                {
                    "density": "scatterers per pixel",
                    "snr_db": "receiver SNR (dB)",
                    "feature_radius": "inclusion radius (pixels)",
                }[axis]
            )
        for r in range(2):
            axes[r, c].set_xticks(xv, [f"{v:g}" for v in xv])
            axes[r, c].minorticks_off()
        axes[0, c].set_ylabel("speckle reduction C_single / C")
        axes[1, c].set_ylabel("inclusion contrast kept (fraction)")
    axes[0, 0].plot([], [], "x", color="k", label="x: stops helping")
    axes[0, 0].plot([], [], "x", color="r", label="x: erases the inclusion")
    axes[0, 0].plot([], [], "--", color="r", lw=0.6, label="erased below")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside right center", frameon=False)
    fig.suptitle("Where each family's method stops helping (top) or erases the inclusion (bottom)")
    return fig


# --------------------------------------------------------------------------- split spectrum
def frequency_compounding_data(cfg: Mapping, seed: int) -> xr.Dataset:
    """Contrast and axial FWHM of split-spectrum compounding vs ``looks`` (the issue's file).

    Independent A-lines (``n_lines`` x ``n_pixels``, ``density`` >= 8 per pixel, Poisson,
    equal amplitudes), rectangular spectrum, non-overlapping equal rectangular sub-bands;
    contrast of the intensity average over the whole uniform image, its SE from 16 blocks of
    lines, the exact Poisson theory and the dense limit 1/sqrt(L); axial FWHM of one
    scatterer's compounded intensity on its band-limited interpolation (x64) and the Dirichlet
    kernel's.
    """
    n, nl, rho = int(cfg["n_pixels"]), int(cfg["n_lines"]), float(cfg["density"])
    p = float(cfg["pixel_size"])
    h = n * p
    src = spectrum(n, h, k0_dk=float(cfg["k0_dk"]))
    sc = random_scatterers(nl, rho, n_pixels=n, depth_range=h, seed=seed, count="poisson")
    field = bscan(sc, src, method=cfg["method"], tol=cfg["tol"]).field.transpose("depth", "x")
    point = ascan([(n / 2 + 0.37) * p], [1.0], n_pixels=n, depth_range=h, k0=src.attrs["k0"])
    looks = [int(v) for v in cfg["looks"]]
    c, se, ct, cd, fw, ft = ([] for _ in range(6))
    for nlk in looks:
        w = cp.subband_apodizations(n, nlk)
        comp = cp.compound(cp.frequency_looks(field, w), "intensity").values
        c.append(float(comp.std() / comp.mean()))
        blocks = [b.std() / b.mean() for b in np.array_split(comp, 16, axis=1)]
        se.append(float(np.std(blocks, ddof=1) / 4.0))
        ct.append(cp.split_spectrum_contrast(w * src.values, rho))
        cd.append(1 / np.sqrt(nlk))
        pl = cp.frequency_looks(xr.DataArray(point, dims=["depth"]), w).values
        fine = (np.abs(iq.bandlimited(pl, 64)) ** 2).sum(axis=0)
        fw.append(iq.peak_fwhm(fine, p / 64))
        ft.append(cp.subband_fwhm(n, n // nlk) * p)
    one = "dimensionless"
    ds = xr.Dataset(
        {
            "contrast": coord(
                one, c, "measured intensity contrast of the compounded image", dims="looks"
            ),
            "contrast_standard_error": coord(
                one, se, "SE of the contrast (16 blocks of lines)", dims="looks"
            ),
            "contrast_theory": coord(one, ct, "exact Poisson theory, finite density", dims="looks"),
            "contrast_dense": coord(one, cd, "dense limit 1/sqrt(looks)", dims="looks"),
            "axial_fwhm": coord(
                "length",
                fw,
                "axial FWHM of the compounded intensity PSF (band-limited interpolation)",
                dims="looks",
            ),
            "axial_fwhm_theory": coord(
                "length",
                ft,
                "FWHM of |sin(pi M x/N)/(M sin(pi x/N))|^2, M = N/looks",
                dims="looks",
            ),
        },
        coords={
            "looks": coord(one, looks, "sub-bands (non-overlapping, rectangular)", dims="looks")
        },
        attrs={
            "n_pixels": n,
            "n_lines": nl,
            "density": rho,
            "pixel_size": p,
            "k0_dk": float(cfg["k0_dk"]),
            "spectrum": "rectangular",
            "windows": "rectangular, no overlap",
            "count": "poisson",
        },
    )
    return ds
