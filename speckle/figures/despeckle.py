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
look's (the edge width of a speckled image carries an SE as large as itself, so it is reported,
not used). Physical methods' ``time_per_mpx`` is the
processing of the acquired looks (splitting, registration, averaging), their acquisition
count is ``acquisitions``; filters' is the filter's run time.
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import compounding as cp
from ..analysis import filters as dsp
from ..analysis import image_quality as iq
from ..conventions import attrs, coord
from ..imaging.aline import ascan
from ..imaging.bscan import bscan
from ..imaging.scan import beam_reach, image, scan_lines
from ..imaging.truth import speckle_free_image
from ..scene import regions as rg
from ..scene.scatterers import random_scatterers
from ..scene.shared import shared_scene
from ..system.source import spectrum
from ._style import new_figure

__all__ = [
    "FAMILIES",
    "build_phantom",
    "check_despeckle_config",
    "failure_data",
    "frequency_compounding_data",
    "methods_data",
    "phantom_data",
    "plot_failure",
    "plot_methods",
    "plot_phantom",
]

#: Method families, physical then digital.
FAMILIES = ("frequency", "angular", "spatial", "polarization", "temporal", *dsp.FILTERS)
#: dB window of PSNR/SSIM, relative to the truth's mean in the uniform region.
DB_TOP, DB_RANGE = 15.0, 45.0
#: "Stops helping": speckle reduction (single-look contrast / contrast) below this.
HELPS = 1.1
#: "Erases the feature": less than this fraction of the truth's inclusion contrast (dB) kept.
ERASES = 0.5


# --------------------------------------------------------------------------- the phantom
def build_phantom(
    geo: Mapping,
    *,
    seed: int,
    density: float | None = None,
    radius: float | None = None,
    margin_angle: float = 0.0,
) -> dict:
    """The phantom of a ``despeckle`` geometry section: scene, source, lines, truth, masks.

    ``geo`` keys: ``n_pixels``, ``n_lines``, ``pixel_size`` (µm; the line pitch too),
    ``k0_dk``, ``waist`` (µm), ``density`` (scatterers per pixel cell), ``air_rows``,
    ``layer_row``, ``backscatter`` ([layer 1, layer 2]), ``inclusion`` ({row, line, radius
    (pixels), backscatter}), ``points`` ({row, lines, db: peak over the layer-1 mean}),
    ``method``, ``tol``. ``density``/``radius`` override the section's; ``margin_angle``
    (degrees) widens the drawn scene for rotated looks.
    """
    n, nl, p = int(geo["n_pixels"]), int(geo["n_lines"]), float(geo["pixel_size"])
    h = n * p
    rho = float(geo["density"] if density is None else density)
    inc = dict(geo["inclusion"])
    r_inc = float(inc["radius"] if radius is None else radius)
    w0 = float(geo["waist"])
    src = spectrum(n, h, k0_dk=float(geo["k0_dk"]))
    x = scan_lines(nl, p)
    dens = rg.cell_density(rho, p, p)
    b1, b2 = (float(v) for v in geo["backscatter"])
    z_air, z_layer = geo["air_rows"] * p, geo["layer_row"] * p
    sin = abs(np.sin(np.deg2rad(margin_angle)))
    zmax = h * (1 + sin) + p
    regions = rg.make_regions(
        rg.background(density=0.0, name="air"),
        rg.layer(z_air, zmax, density=dens, backscatter=b1, name="layer 1"),
        rg.layer(z_layer, zmax, density=dens, backscatter=b2, name="layer 2"),
        rg.circle(
            inc["row"] * p,
            inc["line"] * p,
            r_inc * p,
            density=dens,
            backscatter=float(inc["backscatter"]),
            name="inclusion",
        ),
    )
    reach = beam_reach(w0) + h * sin
    sc = shared_scene(
        regions,
        z_range=(0.0, zmax),
        x_range=(x[0] - reach, x[-1] + reach + p),
        seed=seed,
        tile=64.0 * p,
    )
    # point targets: peak intensity `db` above the layer-1 mean rho N sum S^2 w0 sqrt(pi)/(2 p)
    s2 = float(np.sum(src.values**2))
    mean1 = b1 * rho * n * s2 * w0 * np.sqrt(np.pi) / (2 * p)
    pts = geo["points"]
    amp = np.sqrt(10 ** (pts["db"] / 10) * mean1) / float(np.sum(src.values))
    zp = np.full(len(pts["lines"]), (pts["row"] + 0.3) * p)
    xp = np.asarray(pts["lines"], float) * p + 0.2 * p
    sc = xr.concat(
        [
            sc,
            xr.Dataset(
                {
                    "z": ("scatterer", zp),
                    "x": ("scatterer", xp),
                    "amplitude": ("scatterer", np.full(zp.size, amp + 0j)),
                    "region": ("scatterer", np.full(zp.size, -1, sc.region.dtype)),
                }
            ),
        ],
        dim="scatterer",
        data_vars="all",
        combine_attrs="override",
    )
    sc = sc.isel(scatterer=np.argsort(sc.x.values, kind="stable"))
    kw = {"waist": w0, "x": x, "method": geo["method"], "tol": geo["tol"]}
    truth = speckle_free_image(sc, src, **kw).values
    labels = rg.rasterize(regions, np.arange(n) * p, x)
    rows, cols = np.mgrid[0:n, 0:nl]
    d_inc = np.hypot(rows - inc["row"], cols - inc["line"])
    a, lr = int(geo["air_rows"]), int(geo["layer_row"])
    gap = max(1, min(6, (lr - a) // 4))  # rows kept clear of the layer-1 boundaries
    half = max(2, min(12, (lr - a) // 2, (n - lr) // 2))  # half-height of the edge window
    masks = {
        "uniform": (rows >= a + gap) & (rows < lr - gap),
        "inclusion": d_inc <= max(0.5 * r_inc, 1.0),
        "background": (d_inc >= r_inc + 4) & (d_inc <= r_inc + 10) & (rows > lr + 4),
    }
    ref = float(truth[masks["uniform"]].mean())
    return {
        "geo": geo,
        "source": src,
        "scene": sc,
        "x": x,
        "truth": truth,
        "labels": labels,
        "masks": masks,
        "ref": ref,
        "kw": kw,
        "pixel": p,
        "points": pts,
        "edge_rows": (lr - half, lr + half),
        "regions": regions,
        # lines clear of the inclusion where it reaches into the edge window
        "edge_lines": (np.abs(np.arange(nl) - inc["line"]) > r_inc + 2)
        | (inc["row"] - r_inc - 2 >= lr + half),
    }


def _point_fwhm(img: np.ndarray, ph: dict) -> tuple[float, float]:
    """Mean axial and lateral FWHM (µm) of the point targets (linear intensity)."""
    pts, p = ph["points"], ph["pixel"]
    ax, lat = [], []
    for line in pts["lines"]:
        r0, c0 = int(pts["row"]), int(line)
        win = img[max(r0 - 6, 0) : r0 + 7, max(c0 - 10, 0) : c0 + 11]
        i, j = np.unravel_index(np.argmax(win), win.shape)
        ax.append(iq.peak_fwhm(win[:, j], p))
        lat.append(iq.peak_fwhm(win[i, :], p))
    return _finite_mean(ax), _finite_mean(lat)


def _finite_mean(values: list[float]) -> float:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else np.nan


def quality(intensity: np.ndarray, ph: dict, *, edge: bool = True) -> dict:
    """Every metric of one processed intensity image of phantom ``ph`` (module docstring).

    ``edge``: also the step-edge width and its standard error from 4 blocks of lines (NaN
    otherwise; the failure map does not use them).
    """
    m = ph["masks"]
    img = np.asarray(intensity, float)
    img = img * ph["ref"] / max(float(img[m["uniform"]].mean()), 1e-300)
    db = iq.to_db(img, ph["ref"])
    tdb = iq.to_db(ph["truth"], ph["ref"])
    fa, fl = _point_fwhm(img, ph)
    e0, e1 = ph["edge_rows"]
    band = img[e0:e1, ph["edge_lines"]]
    width, se = np.nan, np.nan
    if edge:
        width = iq.edge_width(band.mean(axis=1), ph["pixel"])
        parts = np.array_split(band, 4, axis=1)
        blocks = np.array([iq.edge_width(b.mean(axis=1), ph["pixel"]) for b in parts])
        if np.isfinite(blocks).sum() > 1:
            se = float(np.nanstd(blocks, ddof=1) / np.sqrt(np.isfinite(blocks).sum()))
    inc = db[m["inclusion"]].mean() - db[m["background"]].mean()
    tinc = tdb[m["inclusion"]].mean() - tdb[m["background"]].mean()
    return {
        "contrast": iq.contrast(img, m["uniform"]),
        "enl": iq.enl(img, m["uniform"]),
        "cnr": iq.cnr(db, m["inclusion"], m["background"]),
        "psnr": iq.psnr_db(db, tdb, db_top=DB_TOP, db_range=DB_RANGE),
        "ssim": iq.ssim_db(db, tdb, db_top=DB_TOP, db_range=DB_RANGE),
        "fwhm_axial": fa,
        "fwhm_lateral": fl,
        "edge_width": width,
        "edge_width_se": se,
        "feature_retained": float(inc / tinc) if tinc != 0 else np.nan,
    }


#: metric -> (its quantity in :data:`speckle.conventions.QUANTITIES`, long name)
METRICS = {
    "contrast": ("contrast", "speckle contrast std/mean in the uniform region"),
    "enl": ("dimensionless", "equivalent number of looks mean^2/var in the uniform region"),
    "cnr": ("dimensionless", "contrast-to-noise ratio inclusion/background (dB images)"),
    "psnr": ("level", "PSNR against the truth (dB images)"),
    "ssim": ("dimensionless", "SSIM against the truth (dB images)"),
    "fwhm_axial": ("length", "axial FWHM of the point targets"),
    "fwhm_lateral": ("length", "lateral FWHM of the point targets"),
    "edge_width": ("length", "10-90 % width of the layer step edge"),
    "edge_width_se": ("length", "standard error of edge_width (4 blocks of lines)"),
    "feature_retained": ("dimensionless", "inclusion contrast (dB) kept, over the truth's"),
}


# --------------------------------------------------------------------------- the methods
def _physical_looks(ph: dict, cfg: Mapping, seed: int, snr_db: float) -> dict:
    """Noise-free and noisy looks of every physical family (largest set of each), and the
    time spent processing them: {family: (looks, noisy, process_seconds_per_look_set)}."""
    src, sc, kw = ph["source"], ph["scene"], ph["kw"]
    single = image(sc, src, **kw).field.values
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
        return cp.angular_looks(sc, src, spec["angles"], **kw)
    if fam == "spatial":
        return cp.spatial_looks(sc, src, spec["offsets"], **kw)
    if fam == "polarization":
        return cp.polarization_looks(sc, src, spec["depolarization"], seed=seed + 1, **kw)
    if fam == "temporal":
        return cp.temporal_looks(
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
        for win in fr["windows"]:
            for ov in fr["overlap"]:
                w = cp.subband_windows(n, nlook, window=win, overlap=ov)

                def fn(noisy, w=w):
                    f = lk["single_noisy" if noisy else "single"]
                    t = time.perf_counter()
                    out = cp.frequency_looks(xr.DataArray(f, dims=("depth", "x")), w)
                    return out, time.perf_counter() - t

                yield (
                    "frequency",
                    f"L={nlook} {win} overlap={ov:g}",
                    {"looks": nlook, "window": win, "overlap": ov},
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


def _grid(params: Mapping) -> list[dict]:
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
            for p in _grid(params):
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


def _colours(fams) -> dict:
    import matplotlib.pyplot as plt

    cmap = plt.get_cmap("tab20")
    return {f: cmap(i % 20) for i, f in enumerate(fams)}


def plot_methods(ds: xr.Dataset) -> Figure:
    """Pareto charts: speckle reduction vs resolution loss, and vs time per megapixel."""
    fig, axes = new_figure(1, 2, width=9.0, height=3.8)
    axes = axes[0]
    sel = ds.isel(technique=np.flatnonzero(ds.noise.values == 1))
    fams = list(dict.fromkeys(sel.family.values.tolist()))
    col = _colours(fams)
    for ax, xv, xl in (
        (axes[0], "resolution_loss", "resolution loss (ratio to single look)"),
        (axes[1], "time_per_mpx", "processing time per megapixel (s)"),
    ):
        x = sel[xv].values.astype(float)
        y = sel.speckle_reduction.values.astype(float)
        if xv == "time_per_mpx":
            x = np.maximum(x, 1e-4)
            ax.set_xscale("log")
        for f in fams:
            m = sel.family.values == f
            ax.scatter(x[m], y[m], s=12, color=col[f], label=f)
        front = _pareto(x, y)
        ax.plot(x[front], y[front], "k-", lw=0.8, label="Pareto front")
        ax.set_xlabel(xl)
        ax.set_ylabel("speckle reduction C_single / C")
        ax.axhline(1.0, color="0.6", lw=0.5)
    axes[0].legend(ncol=2, fontsize=6, loc="best")
    fig.suptitle(f"every method on the phantom (receiver noise at {ds.attrs.get('snr_db')} dB)")
    return fig


def plot_phantom(ds: xr.Dataset) -> Figure:
    """Region map, truth, single look and the best method of each family, in dB."""
    nb = ds.sizes["family"]
    ncol = 5
    nrow = int(np.ceil((3 + nb) / ncol))
    fig, axes = new_figure(nrow, ncol, width=10.0, height=2.1 * nrow)
    axes = np.atleast_1d(axes).ravel()
    ref = float(ds.attrs["reference_intensity"])
    ext = [float(ds.x[0]), float(ds.x[-1]), float(ds.depth[-1]), float(ds.depth[0])]

    def show(ax, img, title, db=True):
        data = iq.to_db(img, ref) if db else img
        kw = {"vmin": -30, "vmax": 15, "cmap": "gray"} if db else {"cmap": "tab10"}
        ax.imshow(data, extent=ext, aspect="auto", **kw)
        ax.set_title(title, fontsize=6)
        ax.set_xticks([])
        ax.set_yticks([])

    show(axes[0], ds.labels.values, "region map", db=False)
    show(axes[1], ds.truth.values, "truth E|A|^2")
    show(axes[2], ds.single_look.values, "single look + noise")
    for i in range(nb):
        show(axes[3 + i], ds.best.isel(family=i).values, str(ds.best_method.values[i]))
    for ax in axes[3 + nb :]:
        ax.axis("off")
    return fig


# --------------------------------------------------------------------------- failure map
def _method_image(spec: Mapping, ph: dict, seed: int, snr_db: float, cache: dict) -> np.ndarray:
    """Intensity image of one failure-map method spec on phantom ``ph`` (noisy)."""
    src, sc, kw = ph["source"], ph["scene"], ph["kw"]
    if "single" not in cache:
        cache["single"] = image(sc, src, **kw).field.values
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
        w = cp.subband_windows(
            ph["geo"]["n_pixels"], spec["looks"], window=spec["window"], overlap=spec["overlap"]
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
    """Speckle reduction and feature retained against density, SNR and feature size."""
    axes_names = ("density", "snr_db", "feature_radius")
    fig, axes = new_figure(2, 3, width=10.0, height=5.5)
    names = [str(m) for m in ds.technique.values]
    methods = [m for m in names if m != "single"]
    col = _colours(methods)
    for c, axis in enumerate(axes_names):
        xv = ds[axis].values
        for m in methods:
            i = names.index(m)
            sr = ds[f"speckle_reduction_{axis}"].values[i]
            fr = ds[f"feature_retained_{axis}"].values[i]
            axes[0, c].plot(xv, sr, "-o", ms=3, color=col[m], label=m)
            axes[1, c].plot(xv, fr, "-o", ms=3, color=col[m])
            bad = ds[f"helps_{axis}"].values[i] == 0
            axes[0, c].plot(xv[bad], sr[bad], "x", color="k", ms=6)
            er = ds[f"erases_{axis}"].values[i] == 1
            axes[1, c].plot(xv[er], fr[er], "x", color="r", ms=6)
        axes[0, c].axhline(ds.attrs["helps_threshold"], color="k", lw=0.6, ls="--")
        axes[1, c].axhline(ds.attrs["erases_threshold"], color="r", lw=0.6, ls="--")
        for r in range(2):
            if axis == "density":
                axes[r, c].set_xscale("log")
            axes[r, c].set_xlabel(
                {
                    "density": "scatterers per pixel",
                    "snr_db": "SNR (dB)",
                    "feature_radius": "inclusion radius (pixels)",
                }[axis]
            )
        axes[0, c].set_ylabel("speckle reduction (x: stops helping)")
        axes[1, c].set_ylabel("feature contrast kept (x: erased)")
    axes[0, 0].legend(fontsize=5, ncol=2)
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
    field = bscan(sc, src, method=cfg["method"], tol=cfg["tol"]).field.transpose("depth", "aline")
    point = ascan([(n / 2 + 0.37) * p], [1.0], n_pixels=n, depth_range=h, k0=src.attrs["k0"])
    looks = [int(v) for v in cfg["looks"]]
    c, se, ct, cd, fw, ft = ([] for _ in range(6))
    for nlk in looks:
        w = cp.subband_windows(n, nlk)
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


# --------------------------------------------------------------------------- config checks
def _key(path: str, check) -> None:
    try:
        check()
    except (ValueError, TypeError) as err:
        raise ValueError(f"config key despeckle.{path}: {err}") from None


def _check_geometry(geo: Mapping, path: str) -> None:
    n, nl = int(geo["n_pixels"]), int(geo["n_lines"])
    a, lr = int(geo["air_rows"]), int(geo["layer_row"])
    inc, pts = geo["inclusion"], geo["points"]
    if not (0 < a and a + 4 <= lr and lr + 4 <= n):
        raise ValueError(
            f"config key despeckle.{path}: need 0 < air_rows ({a}), air_rows + 4 "
            f"<= layer_row ({lr}), layer_row + 4 <= n_pixels ({n})"
        )
    if not (lr < inc["row"] < n and 0 <= inc["line"] < nl):
        raise ValueError(
            f"config key despeckle.{path}.inclusion: centre (row {inc['row']}, line "
            f"{inc['line']}) must lie in layer 2 (rows {lr}..{n}) and lines 0..{nl}"
        )
    if not pts["row"] < a or any(not 0 <= v < nl for v in pts["lines"]):
        raise ValueError(
            f"config key despeckle.{path}.points: row must be < air_rows ({a}) and "
            f"lines in [0, n_lines={nl})"
        )


def _check_radii(geo: Mapping, radii) -> None:
    """The failure sweep's inclusion radii (pixels) keep the inclusion inside layer 2 and the
    lines of the failure phantom."""
    n, nl, lr = int(geo["n_pixels"]), int(geo["n_lines"]), int(geo["layer_row"])
    row, line = geo["inclusion"]["row"], geo["inclusion"]["line"]
    room = min(row - lr, n - row, line + 1, nl - line)
    for i, r in enumerate(radii):
        if r >= room:
            raise ValueError(
                f"config key despeckle.failure.feature_radius[{i}] = {r} does not fit in the "
                f"failure phantom: the inclusion at (row {row}, line {line}) must stay inside "
                f"layer 2 (rows {lr}..{n}) and lines 0..{nl}; need radius < {room}"
            )


def _check_spec(spec: Mapping, n: int, path: str) -> None:
    fam = spec["family"]
    if fam == "frequency":
        _key(
            path,
            lambda: cp.subband_windows(
                n, spec["looks"], window=spec["window"], overlap=spec["overlap"]
            ),
        )
    elif fam in dsp.FILTERS:
        _key(path, lambda: dsp.check_filter(fam, spec.get("params"), spec.get("domain", "linear")))
    elif fam == "temporal":
        _key(
            path,
            lambda: cp.brownian_frames(
                xr.Dataset({"z": ("scatterer", [0.0])}),
                spec["frames"],
                diffusion=spec["diffusion"],
                interval=spec["interval"],
                seed=0,
            ),
        )


def check_despeckle_config(cfg: Mapping) -> None:
    """What the schema cannot say about the ``despeckle`` section (``ValueError`` naming it).

    Geometry inside the image; sub-bands: ``looks`` at most the spectrum's samples, the
    windows and overlaps valid, ``frequency_compounding.n_pixels`` a multiple of every
    ``looks`` (equal sub-bands); subsets no larger than their sets; every filter parameter in
    its range (:func:`speckle.analysis.filters.check_filter`); failure methods complete.
    """
    from .config_check import _tol

    geo = cfg["phantom"]
    _check_geometry(geo, "phantom")
    _tol(geo["method"], geo.get("tol"), "despeckle.phantom.tol", int(geo["n_pixels"]), False)
    fgeo = {**geo, **cfg["failure"]["phantom"]}
    _check_geometry(fgeo, "failure.phantom")
    _check_radii(fgeo, cfg["failure"]["feature_radius"])
    n = int(geo["n_pixels"])
    fr = cfg["physical"]["frequency"]
    for nl in fr["looks"]:
        for w in fr["windows"]:
            for ov in fr["overlap"]:
                _key(
                    "physical.frequency",
                    lambda nl=nl, w=w, ov=ov: cp.subband_windows(n, nl, window=w, overlap=ov),
                )
    phys = cfg["physical"]
    for fam, key in (("angular", "angles"), ("spatial", "offsets")):
        size = len(phys[fam][key])
        for m in phys[fam]["sets"]:
            if m > size or (size - m) % 2:
                raise ValueError(
                    f"config key despeckle.physical.{fam}.sets: {m} central {key} of {size} "
                    f"(need sets <= {size} with the same parity)"
                )
    tm = phys["temporal"]
    if max(tm["sets"]) > tm["frames"]:
        raise ValueError(
            f"config key despeckle.physical.temporal.sets must be <= frames "
            f"({tm['frames']}); got {tm['sets']}"
        )
    for name, params in cfg["filters"].items():
        for p in _grid(params):
            _key(f"filters.{name}", lambda name=name, p=p: dsp.check_filter(name, p))
    for name, spec in cfg["failure"]["methods"].items():
        _check_spec(spec, int(fgeo["n_pixels"]), f"failure.methods.{name}")
    fc = cfg["frequency_compounding"]
    for nl in fc["looks"]:
        _key("frequency_compounding.looks", lambda nl=nl: cp.subband_windows(fc["n_pixels"], nl))
        if fc["n_pixels"] % nl:
            raise ValueError(
                f"config key despeckle.frequency_compounding.looks: {nl} equal sub-bands need "
                f"n_pixels ({fc['n_pixels']}) to be a multiple of it"
            )
