"""Every figure explains itself (issue 37): each ``plot_*`` function of every figure module,
drawn from a small Dataset, is checked for

* x and y labels on every axes that holds data (a label may sit on a shared axis' sibling);
* a colorbar for every image (AxesImage, QuadMesh), or one shared with an image of the same
  colour map and limits, unless the image is marked as needing none
  (``speckle.figures.style.mark_no_colorbar``);
* no "um" for micrometres and no raw config key (``snr_db``, ``k0_dk``, ...: every key of the
  pipeline's config files with an underscore) in any text;
* legend text of at least ``MIN_LEGEND_PT`` points, and no legend inside an axes covering its
  data points;
* the physical aspect ratio (1:1) for an image whose two axes are lengths in the same unit.

Small inputs: the cheap data builders run at a few pixels; the expensive ones (sweeps over many
methods, fits to the measured image) are replaced by Datasets of the same layout filled with
seeded random numbers, since the checks are about the drawing, not the numbers.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
import yaml
from matplotlib.collections import QuadMesh
from matplotlib.image import AxesImage

from speckle.figures import style as _style

ROOT = Path(__file__).resolve().parents[2]
MODULES = (
    "beam",
    "deformation",
    "despeckle",
    "dynamics",
    "elastography",
    "histograms",
    "realism",
    "speed",
    "static",
    "synthoct",
    "system",
    "twin",
    "phantom",
    "phantom_real",
)
RNG_SEED = 37


def _config_keys() -> set[str]:
    """Every key with an underscore in the pipeline's config files (raw identifiers)."""
    keys: set[str] = set()

    def walk(node):
        if isinstance(node, dict):
            for k, v in node.items():
                if "_" in str(k):
                    keys.add(str(k))
                walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)

    for path in sorted((ROOT / "workflow/config").glob("*.yaml")):
        walk(yaml.safe_load(path.read_text()))
    return keys


RAW_KEYS = _config_keys()
MICRON = re.compile(r"(?<![A-Za-z])um(?![A-Za-z])")
#: An axis label in a length unit (an image with lengths on both axes is drawn 1:1).
LENGTH = re.compile(r"\((µm|mm)\b")


# --------------------------------------------------------------------------- the checks
def _colorbar_axes(fig) -> set:
    out = set()
    for ax in fig.axes:
        for m in [*ax.images, *ax.collections]:
            cb = getattr(m, "colorbar", None)
            if cb is not None:
                out.add(cb.ax)
    return out


def _has_data(ax) -> bool:
    return bool(ax.lines or ax.collections or ax.images or ax.patches or ax.containers)


def _labelled(ax, which: str) -> bool:
    get = "get_xlabel" if which == "x" else "get_ylabel"
    shared = ax.get_shared_x_axes() if which == "x" else ax.get_shared_y_axes()
    return any(getattr(a, get)().strip() for a in shared.get_siblings(ax))


def _images(fig, skip) -> list:
    return [
        m
        for ax in fig.axes
        if ax not in skip
        for m in [*ax.images, *[c for c in ax.collections if isinstance(c, QuadMesh)]]
        if isinstance(m, AxesImage | QuadMesh)
    ]


def _key(m) -> tuple:
    return (m.get_cmap().name, tuple(np.round(m.get_clim(), 12)))


def _legends(fig) -> list:
    return [*fig.legends, *[ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]]


def _anchored_outside(legend) -> bool:
    """A legend anchored (``bbox_to_anchor``) to a point outside its axes: off the data."""
    ax = legend.axes
    box = legend.get_bbox_to_anchor()
    if box is ax.bbox:
        return False
    corners = ax.transAxes.inverted().transform(box.get_points())
    return bool(np.any((corners < 0) | (corners > 1)))


def _covers_data(legend) -> bool:
    """A legend drawn inside its axes over a data point (or line) of that axes."""
    ax = legend.axes
    box = legend.get_window_extent()
    if not ax.bbox.contains(*box.p0) or not ax.bbox.contains(*box.p1):
        return False  # placed outside the axes
    for line in ax.lines:
        xy = line.get_xydata()
        if xy.size == 0 or line.get_label().startswith("_child"):
            continue
        pts = ax.transData.transform(xy[np.all(np.isfinite(xy), axis=1)])
        if line.get_linestyle() not in ("None", "", " ") and len(pts) > 1:  # along the segments
            t = np.linspace(0, 1, 50)[:, None, None]
            pts = (pts[:-1] * (1 - t) + pts[1:] * t).reshape(-1, 2)
        inside = (
            (pts[:, 0] > box.x0)
            & (pts[:, 0] < box.x1)
            & (pts[:, 1] > box.y0)
            & (pts[:, 1] < box.y1)
        )
        if inside.any():
            return True
    return False


def _texts(fig) -> list:
    """Titles, axis labels, annotations and legend entries (tick labels are numbers)."""
    out = [*fig.texts]
    for title in ("_suptitle", "_supxlabel", "_supylabel"):
        if getattr(fig, title, None) is not None:
            out.append(getattr(fig, title))
    for ax in fig.axes:
        out += [ax.title, ax._left_title, ax._right_title, ax.xaxis.label, ax.yaxis.label]
        out += ax.texts
    for legend in _legends(fig):
        out += [*legend.get_texts(), legend.get_title()]
    return out


def figure_problems(fig) -> list[str]:
    """What a reader could not read off ``fig`` without the code (the module docstring)."""
    inside = [
        ax.get_legend()
        for ax in fig.axes
        if ax.get_legend() is not None and not _anchored_outside(ax.get_legend())
    ]
    if inside:
        fig.canvas.draw()  # where the legends inside an axes fall
    problems = []
    bars = _colorbar_axes(fig)
    for i, ax in enumerate(fig.axes):
        if ax in bars or not ax.get_visible() or not ax.axison or not _has_data(ax):
            continue
        name = f"axes {i} ({ax.get_title()!r})"
        for which in ("x", "y"):
            if not _labelled(ax, which):
                problems.append(f"{name}: no {which} label")
    for ax in fig.axes:
        lengths = [LENGTH.search(lab) for lab in (ax.get_xlabel(), ax.get_ylabel())]
        if ax.images and all(lengths) and lengths[0][1] == lengths[1][1]:
            if ax.get_aspect() != 1.0:
                problems.append(f"image in {ax.get_title()!r}: lengths on both axes, not 1:1")
    images = _images(fig, bars)
    covered = {_key(m) for m in images if m.colorbar is not None}
    for m in images:
        if m.get_gid() == _style.NO_COLORBAR or m.colorbar is not None or _key(m) in covered:
            continue
        problems.append(
            f"image in axes {fig.axes.index(m.axes)} ({m.axes.get_title()!r}): no colorbar"
        )
    for text in _texts(fig):
        s = text.get_text()
        if not text.get_visible() or not s:
            continue
        if MICRON.search(s):
            problems.append(f"'um' for micrometres in {s!r}")
        words = set(re.findall(r"[A-Za-z0-9]+(?:_[A-Za-z0-9]+)+", s))
        raw = words & RAW_KEYS
        if raw:
            problems.append(f"raw config key {sorted(raw)} in {s!r}")
    for legend in _legends(fig):
        for t in legend.get_texts():
            if t.get_fontsize() < _style.MIN_LEGEND_PT:
                problems.append(f"legend text {t.get_text()!r} at {t.get_fontsize():g} pt")
        if legend in inside and _covers_data(legend):
            problems.append(f"legend {[t.get_text() for t in legend.get_texts()][:3]} covers data")
    return problems


# --------------------------------------------------------------------------- small Datasets
def _rng():
    return np.random.default_rng(RNG_SEED)


def _fake(coords: dict, data: dict, attrs: dict | None = None, low=0.05, high=1.0) -> xr.Dataset:
    """A Dataset of the given layout: ``data`` maps a name to its dims (random positive values)
    or to ``(dims, values)``."""
    rng = _rng()
    sizes = {k: len(np.atleast_1d(v)) for k, v in coords.items()}
    out = {}
    for name, spec in data.items():
        if isinstance(spec, tuple) and len(spec) == 2 and not isinstance(spec[1], str):
            out[name] = spec
        else:
            dims = spec
            out[name] = (dims, rng.uniform(low, high, [sizes[d] for d in dims]))
    return xr.Dataset(out, coords=coords, attrs=attrs or {})


def _merged_config() -> dict:
    import copy

    def merge(a, b):
        out = copy.deepcopy(a)
        for k, v in b.items():
            out[k] = merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
        return out

    base = yaml.safe_load((ROOT / "workflow/config/config.yaml").read_text())
    return merge(base, yaml.safe_load((ROOT / "workflow/config/ci.yaml").read_text()))


SYNC = {"scheduler": "synchronous"}
SCENE = {"n_alines": 8, "k0_dk": 10.0, "seed": 3, "n_pixels": 32, "pixel_size": 8.0}
SHEET = {
    "wavelength_nm": 840.0,
    "bandwidth_nm": 50.0,
    "camera_pixels": 256,
    "camera_range_nm": [790.0, 890.0],
    "imaging_depth": None,
    "refractive_index": 1.38,
    "spectral_resolution_nm": 0.2,
    "fill_factor": 1.0,
}


def _static():
    from speckle.figures import static

    frag = {"depth": 0, "x": 0, "size": 4}
    fig1 = static.single_scatterer([0.0, 1.25], [0.0, 10.0], n_pixels=8, pixel_size=8.0)
    images = static.density_sweep(
        [1.0, 4.0], k0_dk=10.0, n_alines=4, n_pixels=32, pixel_size=8.0, seed=2, dask=SYNC
    )
    k0 = static.k0_sweep(
        [10.0, 1.0], density=4.0, n_alines=4, n_pixels=32, pixel_size=8.0, seed=2, bins=10,
        dask=SYNC,
    )  # fmt: skip
    return {
        "plot_single_scatterer": (fig1,),
        "plot_density_fragments": (images, frag),
        "plot_k0_fragments": (k0, frag),
    }


def _histograms():
    from speckle.figures import histograms

    sim = histograms.simulated_panels(4.0, floor=0.01, bins=20, **SCENE)
    return {
        "plot_density_histograms": (histograms.density_histograms([0.5, 4.0], bins=20, **SCENE),),
        "plot_fig4": (histograms.fig4_dataset(sim, None, "not configured"),),
    }


def _system():
    import speckle
    from speckle.figures import system as fs

    sheet = {k: v for k, v in SHEET.items() if v is not None}
    system = speckle.datasheet(**{**sheet, "camera_range_nm": tuple(SHEET["camera_range_nm"])})
    bscan = {**_merged_config()["system"]["bscan"], "n_alines": 8, "seed": 1, "dispersion": {}}
    return {
        "plot_psf": (fs.psf_dataset(system, [0.2, 0.6], {}),),
        "plot_rolloff": (fs.rolloff_dataset(system, 4),),
        "plot_artefact_bscan": (fs.artefact_bscan(system, **bscan),),
    }


def _beam():
    depth, x, y = np.arange(16) * 8.0, np.arange(6) * 4.0, np.arange(5) * 4.0
    lag = np.arange(4)
    rng = _rng()
    field = rng.normal(size=(2, 16, 6)) + 1j * rng.normal(size=(2, 16, 6))
    corr = {
        f"{n}_{k}{s}": (("waist_pitch", "lag"), rng.uniform(0, 1, (2, 4)))
        for n in ("lateral", "axial")
        for k in ("complex", "intensity")
        for s in ("", "_theory")
    }
    indep = {
        f"{n}_{k}_independent{s}": (("lag",), rng.uniform(0, 1, 4))
        for n in ("lateral", "axial")
        for k in ("complex", "intensity")
        for s in ("", "_theory")
    }
    bscans = xr.Dataset(
        {
            "field": (("waist_pitch", "depth", "x"), field),
            "independent": (("depth", "x"), field[0]),
            **corr,
            **indep,
            "lateral_lag": ("lag", lag),
            "axial_lag": ("lag", lag),
        },
        coords={"waist_pitch": [1.0, 2.0], "depth": depth, "x": x},
    )
    names = [
        f"{k}_{w}" for k in ("complex", "intensity") for w in ("beam", "beam_poisson", "lines")
    ]
    strain = _fake(
        {"strain": [0.0, 0.01, 0.02]},
        {n: ("strain",) for n in [*names, "complex_theory", "complex_poisson_theory",
                                  "intensity_lines_theory"]},
        {"poisson_ratio": 0.45},
    )  # fmt: skip
    volume = xr.Dataset(
        {"field": (("depth", "x", "y"), rng.normal(size=(16, 6, 5)) + 1j)},
        coords={"depth": depth, "x": x, "y": y},
    )
    return {"plot_bscans": (bscans,), "plot_strain": (strain,), "plot_volume": (volume,)}


def _deformation():
    depth, x = np.arange(24) * 8.0, np.arange(8) * 8.0
    strain = np.array([0.0, 0.01, 0.02])
    fig6a = _fake(
        {
            "compensation": ["none", "exact", "tracked"],
            "depth": depth,
            "x": x,
            "window_depth": depth[::8],
            "window_x": x[::4],
        },
        {
            "correlation": ("compensation", "depth", "x"),
            "reference_amplitude": ("depth", "x"),
            "tracked_failed": (
                ("window_depth", "window_x"),
                np.array([[True, False], [False, False], [False, True]]),
            ),
        },
        {"kind": "intensity", "strain": 0.01, "k0_dk": 10.0, "density": 4.0,
         "window_pixels": 8, "tracking_rms_error_pixels": 0.1},
    )  # fmt: skip
    fig6b = _fake(
        {"k0_dk": [1.0, 10.0], "strain": strain},
        {
            "intensity_correlation": ("k0_dk", "strain"),
            "intensity_correlation_theory": ("k0_dk", "strain"),
            "intensity_correlation_uncompensated": ("k0_dk", "strain"),
        },
        {"density": 4.0, "spectrum_shape": "rectangular", "n_pixels": 32, "n_alines": 8},
    )
    spectra = ["rectangular", "gaussian"]
    fig6c = _fake(
        {"spectrum": spectra, "strain": strain, "n": np.arange(-4, 4)},
        {
            "spectrum_weight": ("spectrum", "n"),
            "intensity_correlation": ("spectrum", "strain"),
            "intensity_correlation_theory": ("spectrum", "strain"),
            "incoherent_floor_theory": ("spectrum", "strain"),
            "complex_correlation": ("spectrum", "strain"),
            "complex_correlation_theory": ("spectrum", "strain"),
            "complex_correlation_windowed_no_carrier": ("spectrum", "strain"),
            "complex_correlation_no_carrier_theory": ("spectrum", "strain"),
        },
        {"n_pixels": 8, "s_ret_paper": 0.05, "carrier_window_pixels": 8, "k0_dk": 10.0,
         "density": 4.0},
    )  # fmt: skip
    scan = _fake(
        {"density": [1.0, 4.0], "k0_dk": [3.0, 10.0], "spectrum": spectra, "strain": strain},
        {
            "intensity_correlation": ("density", "k0_dk", "spectrum", "strain"),
            "intensity_correlation_theory": ("density", "k0_dk", "spectrum", "strain"),
            "incoherent_floor_theory": ("density", "k0_dk", "spectrum", "strain"),
        },
        {"scan_points": 3},
    )
    return {
        "plot_fig6a": (fig6a,),
        "plot_fig6b": (fig6b,),
        "plot_fig6c": (fig6c,),
        "plot_scan": (scan,),
    }


def _despeckle():
    from speckle.figures import despeckle as dsp

    fams = ["single", *dsp.FAMILIES]
    tech = [f"{f} {i}" for f in fams for i in range(2)]
    family = [f for f in fams for _ in range(2)]
    rng = _rng()
    metrics = {
        k: ("technique", rng.uniform(0.5, 4.0, len(tech)))
        for k in ("speckle_reduction", "resolution_loss", "resolution_loss_with_edge")
    }
    methods = xr.Dataset(
        {**metrics, "time_per_mpx": ("technique", rng.uniform(1e-3, 1.0, len(tech)))},
        coords={
            "technique": tech,
            "family": ("technique", family),
            "noise": ("technique", np.ones(len(tech), np.int8)),
        },
        attrs={"snr_db": 30.0},
    )
    n = 16
    labels = np.zeros((n, n), int)
    labels[4:8], labels[8:], labels[10:14, 6:10] = 1, 2, 3
    phantom = xr.Dataset(
        {
            "labels": (("depth", "x"), labels),
            "truth": (("depth", "x"), rng.uniform(0.5, 2.0, (n, n))),
            "single_look": (("depth", "x"), rng.exponential(1.0, (n, n))),
            "best": (("family", "depth", "x"), rng.exponential(1.0, (3, n, n))),
        },
        coords={
            "depth": np.arange(n) * 8.0,
            "x": np.arange(n) * 8.0,
            "family": ["frequency", "tv", "lee"],
            "best_method": (
                "family",
                ["frequency L=4 intensity", "tv log weight=0.1", "lee linear size=7"],
            ),
        },
        attrs={"region_names": "air, layer 1, layer 2, inclusion", "reference_intensity": 1.0},
    )
    sweeps = {"density": [0.5, 4.0], "snr_db": [10.0, 30.0], "feature_radius": [2.0, 4.0]}
    data = {}
    for axis in sweeps:
        dims = ("technique", axis)
        for k in ("speckle_reduction", "feature_retained", "ssim", "resolution_loss"):
            data[f"{k}_{axis}"] = (dims, rng.uniform(0.3, 3.0, (len(fams), 2)))
        for k in ("helps", "erases"):
            data[f"{k}_{axis}"] = (dims, rng.integers(0, 2, (len(fams), 2)).astype(np.int8))
    failure = xr.Dataset(
        data,
        coords={"technique": fams, "family": ("technique", fams), **sweeps},
        attrs={"helps_threshold": 1.1, "erases_threshold": 0.5},
    )
    return {
        "plot_methods": (methods,),
        "plot_phantom": (phantom,),
        "plot_failure": (failure,),
    }


def _dynamics():
    n = 12
    pos = {"depth": np.arange(n) * 4.0, "x": np.arange(n) * 4.0, "region": np.arange(4)}
    names = ("speckle_variance", "ssada", "liv", "liv_doct", "ocds")
    phantom = _fake(
        pos,
        {
            "labels": (("depth", "x"), np.repeat(np.arange(n) // 3, n).reshape(n, n)),
            "structure": ("depth", "x"),
            **{k: ("depth", "x") for k in names},
            **{f"{k}_region": ("region",) for k in names},
        },
    )
    lag = np.arange(6) * 1e-3
    decay = np.exp(-np.stack([lag, lag**2 / 4e-3]) / 2e-3)  # as measured: 1 at lag 0, falling
    g1 = _fake(
        {"model": ["brownian", "transverse_flow"], "lag": lag},
        {
            "g1": (("model", "lag"), decay),
            "g1_se": (("model", "lag"), 0.01 + 0 * decay),
            "g1_theory": (("model", "lag"), decay),
            "diffusion": ("model",),
            "velocity": ("model",),
        },
    )
    cube = ("contrast", "snr_db", "interval", "velocity")
    failure = _fake(
        {
            "contrast": ["speckle_variance", "decorrelation", "liv"],
            "snr_db": [20.0, 40.0],
            "interval": [1e-3, 4e-3],
            "velocity": [0.0, 100.0, 1000.0],
        },
        {
            "status": (cube, _rng().integers(0, 3, (3, 2, 2, 3))),
            "measured": cube,
            "measured_se": cube,
            "theory": cube,
            "static_floor_theory": ("contrast", "snr_db"),
            "noise_floor_theory": ("contrast", "snr_db"),
            "v_low": ("contrast", "snr_db", "interval"),
            "v_high": ("contrast", "snr_db", "interval"),
        },
        low=0.05,
        high=1.0,
    )
    v, fine = np.array([0.0, 2000.0, 4000.0, 8000.0]), np.linspace(0.0, 8000.0, 9)

    def rise(u):  # as measured: from the static floor up to the noise floor
        return 0.2 * (1 - np.exp(-((u / 3000.0) ** 2)))

    calibration = _fake(
        {"velocity": v, "velocity_fine": fine},
        {
            "decorrelation": (("velocity",), rise(v)),
            "decorrelation_se": (("velocity",), 0.002 + 0 * v),
            "theory_curve": (("velocity_fine",), rise(fine)),
            "static_floor_theory": ((), 0.003),
            "noise_floor_theory": ((), 0.2),
        },
        {"interval": 1e-3, "snr_db": 30.0},
    )
    return {
        "plot_phantom": (phantom,),
        "plot_g1": (g1,),
        "plot_failure": (failure,),
        "plot_calibration": (calibration,),
    }


def _elastography():
    from speckle.figures import elastography as el

    methods = ["vector", "wls", "tracking", "correlation"]
    sweeps = {
        "strain": [1e-3, 1e-2],
        "snr_db": [20.0, np.inf],
        "window": [16.0, 32.0],
        "k0_dk": [10.0],
        "fwhm_fraction": [0.5],
        "density": [4.0],
    }
    data = {"predicted_noise_snr_db": ("snr_db",)}
    for name in el.FAILURE_SWEEPS:
        for v in ("relative_rms_error", "answered"):
            data[f"{v}_{name}"] = (name, "method")
            data[f"{v}_{name}_se"] = (name, "method")
    failure = _fake(
        {"method": methods, **sweeps},
        data,
        {"limit_wrap_single_lag": 0.017, "limit_wrap_lag1": 0.05, "limit_decorrelation": 0.035,
         "limit_speckle_displacement": 0.02, "base_strain": 2e-3, "n_pixels": 128,
         "n_alines": 8, "n_seeds": 2},
    )  # fmt: skip
    depth, aline = np.arange(32) * 8.0, np.arange(8)
    maps = _fake(
        {"method": ["vector", "wls"], "depth": depth, "x": aline},
        {
            "modulus": ("depth", "x"),
            "true_strain": ("depth", "x"),
            "strain": ("method", "depth", "x"),
            "error": ("method", "depth", "x"),
        },
        {"pixel_size": 8.0},
    )
    maps["modulus"].attrs["units"] = "kPa"
    speed = _fake(
        {"method": ["vector", "wls"], "window": [16, 32]},
        {"time_per_megapixel": ("method", "window"), "relative_rms_error": ("method", "window")},
        {"strain": 2e-3},
    )
    sequence = _fake(
        {"frame": [1, 2, 3]},
        {f"{v}_cumulative": ("frame",) for v in ("true", "median", "rms_error")},
    )
    large = _fake(
        {"frame": [1, 2], "depth": np.arange(32) * 8.0, "x": np.arange(8) * 8.0},
        {"accumulated": ("frame", "depth", "x")},
        {"pixel_size": 8.0},
    )
    return {
        "plot_phantom": (maps,),
        "plot_inclusion": (maps,),
        "plot_failure": (failure,),
        "plot_speed": (speed,),
        "plot_sequence": (sequence,),
        "plot_sequence_large": (large, 5e-4),
    }


def _realism():
    from speckle.analysis.realism import EFFECTS

    steps = ["pure", *[f"+{e}" for e in EFFECTS]]
    rng = _rng()
    ds = _fake(
        {"step": steps, "axis": ["depth", "lateral"], "lag": np.arange(5), "effect": list(EFFECTS)},
        {
            "cumulative_autocorrelation": ("step", "axis", "lag"),
            "model_autocorrelation": ("axis", "lag"),
            "measured_autocorrelation": ("axis", "lag"),
            "measured_autocorrelation_se": ("axis", "lag"),
            "dropped_score": ("effect",),
            "cumulative_score": ("step",),
            "needed": (("effect",), rng.integers(0, 2, len(EFFECTS)).astype(bool)),
        },
        {"final_effects": "spectral_width,beam", "measured": "test image"},
    )
    n = 12
    showcase = _fake(
        {"depth": np.arange(n) * 4.0, "x": np.arange(n) * 4.0},
        {
            "pure_db": ("depth", "x"),
            "system_db": ("depth", "x"),
            "label": (("depth", "x"), np.repeat(np.arange(n) // 6, n).reshape(n, n)),
        },
        {"focus": 400.0, "snr_db": 30.0},
    )
    return {"plot_realism": (ds,), "plot_showcase": (showcase, 40.0)}


def _speed():
    from speckle.imaging.speed import speed_accuracy

    kw = {"pixel_size": 8.0, "k0_dk": 10.0, "shape": "gaussian", "fwhm_fraction": 0.15}
    chart = speed_accuracy(
        [{"n_pixels": 32, "n_lines": 2, "density": 1}], ["direct", "nufft"], [1e-6], seed=1,
        repeat=1, **kw,
    )  # fmt: skip
    axes = {"n_pixels": [32.0, 64.0], "density": [1.0, 4.0], "k0_dk": [0.0, 10.0]}
    data = {}
    for a in axes:
        data[f"error_vs_{a}"] = ("case", a)
        data[f"predicted_vs_{a}"] = ("case", a)
    fmap = _fake(
        {"case": ["nufft", "psf"], **axes},
        data,
        {"base_n_pixels": 64, "base_density": 1.0, "base_k0_dk": 10.0},
        low=1e-10,
        high=1e-3,
    )
    return {"plot_speed_accuracy": (chart,), "plot_failure_map": (fmap,)}


def _synthoct():
    metrics = ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF", "LPIPS")
    maps = ["Struct", "OAC", "SC", "RSC"]
    n = 8
    image = ("origin_scan", "depth", "x")
    diagonal = np.linspace(0.1, 0.9, 8).reshape(2, 4)
    consistency = _fake(
        {
            "origin": ["published", "recomputed", "drop-in"],
            "experiment": ["Exp1", "Exp2"],
            "map": maps,
            "origin_scan": ["published", "drop-in"],
            "phantom": ["Exp2_Layers_A"],
            "depth": np.arange(n) * 6.0,
            "x": (np.arange(2 * n) - n) * 6.0,
        },
        {
            # as measured: each comparison's score equals the published one, on the diagonal
            **{m: (("origin", "experiment", "map"), np.stack([diagonal] * 3)) for m in metrics},
            "scan": ("origin_scan", "phantom", "depth", "x"),
            **{m: image for m in ("OAC", "SC", "RSC")},
        },
        {"shown_phantom": "Exp2_Layers_A"},
    )
    batch = _fake(
        {"boundary": [200.0, 400.0, 600.0], "energy": [0.5, 2.5, 5.0], "map": maps},
        {m: ("boundary", "energy", "map") for m in metrics},
        {"reference": "Exp2_Layers_A", "n_phantoms": 9, "n_pixels": 256, "n_lines": 512},
    )
    return {"plot_self_consistency": (consistency,), "plot_batch": (batch,)}


def _twin():
    n_depth, n_x = 10, 24
    compare = _fake(
        {
            "source": ["measured", "twin"],
            "axis": ["depth", "lateral"],
            "lag": np.arange(5),
            "row": np.arange(n_depth),
            "bin": np.linspace(-4, 3, 20),
            "depth": 500.0 + 5.75 * np.arange(n_depth),
            "x": 4.0 * np.arange(n_x),
        },
        {
            "autocorrelation": ("source", "axis", "lag"),
            "autocorrelation_se": ("source", "axis", "lag"),
            "mean_log_profile": ("source", "row"),
            "mean_log_profile_se": ("source", "row"),
            "z_skewness": (),
            "z_excess_kurtosis": (),
            "measured_log_histogram": ("bin",),
            "twin_log_histogram": ("bin",),
            "measured_image": ("depth", "x"),
            "twin_image": ("depth", "x"),
        },
    )
    failure = _fake(
        {"strain": [1e-3, 1e-2], "method": ["vector", "wls"]},
        {"rms_error": ("strain", "method"), "answered": ("strain", "method")},
    )
    return {"plot_compare": (compare,), "plot_failure": (failure,)}


def _phantom():
    coords = {
        "configuration": ["challenge", "2025"],
        "case": [0, 1, 2],
        "layer": np.arange(5),
        "candidate": ["fitted", "floor", "baseline"],
        "map": ["Struct", "OAC", "SC", "RSC"],
    }
    layer = ("configuration", "case", "layer")
    ds = _fake(
        coords,
        {
            "true_top": layer,
            "boundary_error": layer,
            "attenuation_pull": layer,
            "rho_e_pull": layer,
            "top_pull": layer,
            "window_top_pull": ("configuration", "case"),
            "pixel_size": ("configuration",),
            "MS-SSIM": ("configuration", "case", "candidate", "map"),
        },
    )
    counts = np.array([[1, 2, 3], [1, 2, 2]])
    right = np.array([[1, 1, 1], [1, 0, 1]])
    return ds.assign(
        n_true=(("configuration", "case"), counts),
        n_fit=(("configuration", "case"), counts + 1 - right),
        layers_right=(("configuration", "case"), right),
        success=(("configuration", "case"), right * np.array([1, 1, 0])),
    )


def _phantom_real():
    image = ("depth", "x")
    ds = _fake(
        {
            "depth": np.arange(40) * 3.0,
            "x": np.arange(30) * 4.0,
            "seed": [1, 2, 3],
            "pair": [0, 1, 2],
            "map": ["Struct", "OAC", "SC", "RSC"],
        },
        {
            "measured": image,
            "fitted": ("seed", *image),
            "measured_SC": image,
            "fitted_SC": image,
            "profile_measured": ("depth",),
            "profile_fitted": ("depth",),
            "MS-SSIM_versus": ("seed", "map"),
            "MS-SSIM_floor": ("pair", "map"),
        },
        attrs={"fitted_rows": [5, 35]},
    )
    return {"plot_phantom_real": (ds,)}


BUILDERS = {
    "beam": _beam,
    "deformation": _deformation,
    "despeckle": _despeckle,
    "dynamics": _dynamics,
    "elastography": _elastography,
    "histograms": _histograms,
    "realism": _realism,
    "speed": _speed,
    "static": _static,
    "synthoct": _synthoct,
    "system": _system,
    "twin": _twin,
    "phantom_real": _phantom_real,
    "phantom": lambda: {
        "plot_closed_loop": (_phantom(),),
        "plot_scores": (_phantom(),),
        "plot_failure_map": (
            _fake(
                {"thickness": [12.0, 24.0, 48.0], "energy_ratio": [1.5, 4.0]},
                {
                    "success": ("thickness", "energy_ratio"),
                    "count_right": ("thickness", "energy_ratio"),
                    "boundary_right": ("thickness", "energy_ratio"),
                    "boundary_error": ("thickness", "energy_ratio"),
                    "n_cases": ((), 4),
                },
            ),
        ),
    },
}


# --------------------------------------------------------------------------- the tests
@pytest.mark.parametrize("name", MODULES)
def test_every_plot_function_explains_itself(name):
    mod = importlib.import_module(f"speckle.figures.{name}")
    plots = {n for n in mod.__all__ if n.startswith("plot_")}
    inputs = BUILDERS[name]()
    assert plots == set(inputs), f"figure checks must draw every plot function of {name}"
    problems = []
    for fn, args in sorted(inputs.items()):
        fig = getattr(mod, fn)(*args)
        try:
            problems += [f"{name}.{fn}: {p}" for p in figure_problems(fig)]
        finally:
            plt.close(fig)
    assert not problems, "\n".join(problems)


def test_the_checks_find_what_they_look_for():
    """A figure with each fault is caught; its corrected version passes."""
    fig, axes = _style.new_figure(1, 2)
    axes[0, 0].plot([0, 1], [1, 0], label="a")  # through the upper left corner
    axes[0, 0].legend(fontsize=5, loc="upper left")
    axes[0, 0].set_title("depth (um) against snr_db")
    axes[0, 1].imshow(np.eye(3), aspect="auto", extent=[0, 1, 1, 0])
    axes[0, 1].set(xlabel="x (µm)", ylabel="depth (µm)")
    found = "\n".join(figure_problems(fig))
    for what in ("no x label", "no colorbar", "'um'", "snr_db", "5 pt", "covers", "not 1:1"):
        assert what in found, what
    plt.close(fig)
    fig, axes = _style.new_figure(1, 2)
    axes[0, 0].plot([0, 1], [0, 1], label="a")
    _style.legend_outside(axes[0, 0])
    axes[0, 0].set(title="depth (µm) against SNR (dB)", xlabel="SNR (dB)", ylabel="depth (µm)")
    im = _style.physical_image(axes[0, 1], np.eye(3), [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    _style.colorbar(fig, im, axes[0, 1], "intensity (a.u.)")
    assert figure_problems(fig) == []
    plt.close(fig)
