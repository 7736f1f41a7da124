"""The phantom fit's closed loop as a batch, scored as the SynthOCT challenge scores (issue 34).

:func:`phantom_closed_loop` draws one virtual patient per seed, scans it with the drop-in
scanner (:func:`speckle.synthoct_scan`), fits it back (:func:`speckle.fit_phantom`) and scores
the fit twice over:

* against the truth: the layer count, each boundary's error in pixels, the pulls
  ``(fitted - true)/SE`` of the one-way attenuation ``mu = rho (E/100) A2`` and of ``rho E/100``
  (``A2`` of :func:`speckle.studies.phantom.slab_constants`);
* as the challenge scores (:func:`speckle.synthoct_metrics`, every metric of every map): the
  target scan against the fitted phantom's scan (``fitted``, another draw of positions), against
  the *true* phantom drawn again with the same other seed (``floor``: what no phantom can beat,
  two independent speckle patterns of one tissue) and against the baseline generator's
  two-layer phantom (``baseline``, :func:`speckle.synthoct.files.baseline_table` in the case's
  box and count). With ``rescans`` > 1 the scores are means over that many re-draws.

The cases run on Dask (:func:`speckle.sweep.sweep`, one task per seed); every random number of
a case comes from its seed (``numpy.random.SeedSequence``) and every scan runs on one FINUFFT
thread, so the table is the same whatever the scheduler, the workers or the order of the seeds.

The virtual patients here are flat-layer ones (:func:`_flat_patient`): 1 to 5 layers of one
density, boundaries at least 15 pixels apart between 5 % and 35 % of the depth range,
neighbouring energies at least 2.5 times apart (0.2 to 3 %), the density drawn over a factor
of three around the challenge's. A boundary counts as shown when it lies at least 4 pixels above
the last fitted row (below, the 51 dB window's floor hides it); one within those 4 pixels may be
found or not (the count is right either way, and a found one is compared with the truth).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import xarray as xr

from .._validate import check_bool, check_choice, check_int
from ..conventions import attrs, coord
from ..sweep import SCHEDULERS, sweep
from ..synthoct.files import ScannerConfig, baseline_table
from ..synthoct.metrics import SYNTHOCT_MAPS, synthoct_metrics
from .phantom._fit import fit_phantom, slab_constants

__all__ = ["phantom_closed_loop"]

#: The scanner configurations of the closed loop by name: the challenge's (the shipped INI's
#: defaults) and the group's 2025 digital phantoms' (601 pixels of 2.2 µm, 975 A-lines over
#: 3000 µm, beam radius 6 µm, 255,000 scatterers).
CONFIGURATIONS: dict[str, ScannerConfig] = {
    "challenge": ScannerConfig(),
    "2025": ScannerConfig(
        n_pixels=601, pixel_size=2.2, n_lines=975, x_max=3000.0, beam_radius=6.0,
        n_scatterers=255_000,
    ),
}  # fmt: skip
#: Boundary shapes the virtual patients draw, and whether they draw inclusions.
SHAPES = ("flat",)
INCLUSIONS = False
#: Candidates scored against each target scan.
CANDIDATES = ("fitted", "floor", "baseline")
#: Most layers of a virtual patient (the fit tries up to 5).
MAX_LAYERS = 5
#: Scatterers per µm^2 of the (x, z) box: the range of the virtual patients' densities (the
#: challenge's is 0.0636).
AREA_DENSITY = (0.034, 0.102)
#: Long name of the failure class.
FAILURE_NAME = "failure class (none, layer count, boundary: an error of a pixel or more)"
#: Thinnest layer of a virtual patient, pixels.
MIN_THICKNESS = 15
#: A boundary is shown when it lies this many pixels above the fit's last row.
SHOWN_MARGIN = 4


def _configuration(config: object) -> ScannerConfig:
    if isinstance(config, ScannerConfig):
        return config
    if isinstance(config, str):
        return CONFIGURATIONS[check_choice(config, "config", CONFIGURATIONS)]
    raise TypeError(
        f"config must be a ScannerConfig or one of {sorted(CONFIGURATIONS)}, "
        f"got {type(config).__name__}"
    )


def _layers(layers: object) -> tuple[int, int]:
    if not isinstance(layers, Sequence) or isinstance(layers, str) or len(layers) != 2:
        raise TypeError(f"layers must be a pair (fewest, most), got {layers!r}")
    low = check_int(layers[0], "layers[0]", low=1, high=MAX_LAYERS)
    high = check_int(layers[1], "layers[1]", low=low, high=MAX_LAYERS)
    return low, high


def _flat_patient(
    seed: int | np.random.SeedSequence,
    config: object = "challenge",
    *,
    layers: tuple[int, int] = (1, 3),
) -> tuple[ScannerConfig, xr.Dataset]:
    """A random flat-layer virtual patient: its scanner configuration and its truth.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        Seed of the patient's structure (layers, energies, density).
    config : ScannerConfig or {"challenge", "2025"}
        The scanner (:data:`CONFIGURATIONS`); its ``n_scatterers`` is replaced by the
        patient's count.
    layers : (int, int)
        Fewest and most layers (1..5).

    Returns
    -------
    config : ScannerConfig
        ``config`` with the patient's scatterer count.
    truth : xarray.Dataset
        Dim ``layer``: ``top`` (µm), ``energy`` (%), ``attenuation`` (one-way ``mu``, 1/µm) and
        ``rho_e`` (``rho E/100``, per µm^3); attribute ``density`` (scatterers per µm^3 in the
        slab ``|y| <= r``). Draw its scatterers with :func:`_draw_patient`.

    Examples
    --------
    >>> cfg, truth = _flat_patient(3, "challenge", layers=(2, 2))
    >>> truth.sizes["layer"], float(truth.top[0])
    (2, 0.0)
    """
    cfg = _configuration(config)
    low, high = _layers(layers)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer, np.random.SeedSequence)):
        raise TypeError(f"seed must be a non-negative integer or a SeedSequence, got {seed!r}")
    if not isinstance(seed, np.random.SeedSequence):
        seed = np.random.SeedSequence(check_int(seed, "seed", low=0))
    rng = np.random.default_rng(seed)
    k = int(rng.integers(low, high + 1))
    h, gap = cfg.depth_range, MIN_THICKNESS * cfg.pixel_size
    while True:
        tops = np.concatenate([[0.0], np.sort(rng.uniform(0.05 * h, 0.35 * h, k - 1))])
        if k == 1 or (np.min(np.diff(tops)) >= gap and tops[1] >= gap):
            break
    energy = np.exp(rng.uniform(np.log(0.2), np.log(3.0), k))
    for i in range(1, k):
        while max(energy[i] / energy[i - 1], energy[i - 1] / energy[i]) < 2.5:
            energy[i] = np.exp(rng.uniform(np.log(0.2), np.log(3.0)))
    m = int(rng.uniform(*AREA_DENSITY) * cfg.x_max * h)
    cfg = dataclasses.replace(cfg, n_scatterers=m)
    rho = m / (cfg.x_max * 2 * cfg.beam_radius * h)
    rho_e = rho * energy / 100
    truth = xr.Dataset(
        {
            "top": ("layer", tops, attrs("length", "upper boundary of the layer")),
            "energy": ("layer", energy, attrs("percent", "energy per scatterer")),
            "attenuation": ("layer", rho_e * slab_constants(cfg.beam_radius)["A2"],
                            attrs("attenuation", "one-way amplitude attenuation mu")),
            "rho_e": ("layer", rho_e, attrs("volume_density", "rho E/100")),
        },
        coords={"layer": coord("layer", np.arange(k))},
        attrs={"density": rho, "n_scatterers": m},
    )  # fmt: skip
    return cfg, truth


def _draw_patient(truth: xr.Dataset, config: ScannerConfig, seed: int) -> np.ndarray:
    """The four-column phantom (X, Y, Z in µm, Energy in %) of a flat-layer truth.

    Scatterers uniform in ``|x| <= x_max/2``, ``|y| <= r`` and ``0 <= z < H``, each with its
    layer's energy; ``seed`` draws the positions.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    m, cfg = config.n_scatterers, config
    z = rng.uniform(0, cfg.depth_range, m)
    layer = np.searchsorted(truth.top.values, z, side="right") - 1
    return np.column_stack([
        rng.uniform(-0.5, 0.5, m) * cfg.x_max,
        rng.uniform(-1, 1, m) * cfg.beam_radius,
        z,
        truth.energy.values[layer],
    ])  # fmt: skip


def _seeds(children: list[np.random.SeedSequence]) -> list[int]:
    return [int(c.generate_state(1)[0]) for c in children]


def _scan(table: np.ndarray, cfg: ScannerConfig):
    from ..synthoct.scanner import synthoct_scan

    return np.asarray(synthoct_scan(table, cfg, nthreads=1).values)


def _padded(values, n: int) -> np.ndarray:
    out = np.full(n, np.nan)
    values = np.asarray(values, float)[:n]
    out[: values.size] = values
    return out


def _closed_loop_case(
    case: int,
    *,
    config: ScannerConfig,
    layers: tuple[int, int],
    rescans: int,
    score: bool,
    lpips: bool,
) -> xr.Dataset:
    """One case of :func:`phantom_closed_loop` (its seed ``case``); see its Returns."""
    ss = np.random.SeedSequence(int(case))
    structure, target_ss, *others = ss.spawn(2 + rescans)
    cfg, truth = _flat_patient(structure, config, layers=layers)
    target = _scan(_draw_patient(truth, cfg, _seeds([target_ss])[0]), cfg)
    fit = fit_phantom(target, cfg)
    fl = fit.layers
    end = (fl.attrs["rows"] + 2) * cfg.pixel_size
    shown = int(np.sum(truth.top.values < end - SHOWN_MARGIN * cfg.pixel_size))
    near = int(np.sum(truth.top.values < end)) - shown  # boundaries at the window's floor
    n_fit = fl.sizes["layer"]
    right = shown <= n_fit <= shown + near
    n = MAX_LAYERS
    t = truth.isel(layer=slice(0, n_fit))
    if right:
        top_err = (fl.top.values - t.top.values) / cfg.pixel_size
        mu_pull = (fl.attenuation.values - t.attenuation.values) / fl.attenuation_se.values
        re_pull = (fl.rho_e.values - t.rho_e.values) / fl.rho_e_se.values
    else:
        top_err = mu_pull = re_pull = []
    failure = "none"
    if not right:
        failure = "layer count"
    elif np.any(np.abs(top_err) >= 1.0):
        failure = "boundary"
    layer = {
        "top_true": (_padded(truth.top, n), "length", "true upper boundary"),
        "top_fit": (_padded(fl.top, n), "length", "fitted upper boundary"),
        "top_se": (_padded(fl.top_se, n), "length", "standard error of the fitted boundary"),
        "top_error": (_padded(top_err, n), "pixels", "fitted minus true boundary"),
        "attenuation_true": (_padded(truth.attenuation, n), "attenuation", "true one-way mu"),
        "attenuation_fit": (_padded(fl.attenuation, n), "attenuation", "fitted one-way mu"),
        "attenuation_se": (_padded(fl.attenuation_se, n), "attenuation", "standard error of mu"),
        "attenuation_pull": (_padded(mu_pull, n), "dimensionless", "(fitted - true)/SE of mu"),
        "rho_e_true": (_padded(truth.rho_e, n), "volume_density", "true rho E/100"),
        "rho_e_fit": (_padded(fl.rho_e, n), "volume_density", "fitted rho E/100"),
        "rho_e_se": (_padded(fl.rho_e_se, n), "volume_density", "standard error of rho E/100"),
        "rho_e_pull": (_padded(re_pull, n), "dimensionless", "(fitted - true)/SE of rho E/100"),
    }
    data = {k: ("layer", v, attrs(q, name)) for k, (v, q, name) in layer.items()}
    data.update(
        {
            "n_layers": ((), truth.sizes["layer"], attrs("count", "layers of the patient")),
            "n_shown": ((), shown, attrs("count", "layers above the window's floor")),
            "n_near": ((), near, attrs("count", "boundaries within 4 pixels of the floor")),
            "n_fit": ((), n_fit, attrs("count", "layers fitted")),
            "density": ((), truth.attrs["density"], attrs("volume_density", "true density")),
            "failure": ((), failure, attrs("label", FAILURE_NAME)),
        }
    )
    if score:
        scores = {c: [] for c in CANDIDATES}
        for s in _seeds(others):
            scores["fitted"].append(_scan(fit.phantom(s), cfg))
            scores["floor"].append(_scan(_draw_patient(truth, cfg, s), cfg))
            scores["baseline"].append(_scan(baseline_table("layers", s, config=cfg), cfg))
        per = {
            c: xr.concat([synthoct_metrics(target, b, lpips=lpips) for b in scans], "rescan")
            .mean("rescan", keep_attrs=True)
            for c, scans in scores.items()
        }  # fmt: skip
        metrics = xr.concat([per[c] for c in CANDIDATES], "candidate", combine_attrs="override")
        metrics = metrics.drop_vars("map")
        for name in metrics.data_vars:
            data[name] = (("candidate", "map"), metrics[name].values, metrics[name].attrs)
    ds = xr.Dataset(data, coords={"layer": coord("layer", np.arange(n))})
    if score:
        ds = ds.assign_coords(
            candidate=coord("candidate", list(CANDIDATES)), map=coord("map", list(SYNTHOCT_MAPS))
        )
    return ds


def phantom_closed_loop(
    seeds: Sequence[int],
    config: object = "challenge",
    *,
    layers: tuple[int, int] = (1, 3),
    shapes: Sequence[str] = ("flat",),
    inclusions: bool = False,
    rescans: int = 1,
    score: bool = True,
    lpips: bool = False,
    scheduler: str = "threads",
    n_workers: int | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """The phantom fit's closed loop over virtual patients, on Dask (module docstring).

    Parameters
    ----------
    seeds : sequence of int
        One virtual patient per seed (distinct non-negative integers); the dim ``case``.
    config : ScannerConfig or {"challenge", "2025"}
        The scanner configuration (:data:`CONFIGURATIONS`); each patient sets its own count.
    layers : (int, int)
        Fewest and most layers of the patients (1..5).
    shapes : sequence of str
        Boundary shapes of the patients: :data:`SHAPES` (``"flat"`` in this version).
    inclusions : bool
        Inclusions in the patients: only False in this version (:data:`INCLUSIONS`).
    rescans : int
        Re-draws of positions whose scores are averaged (1..16).
    score : bool
        Score as the challenge scores (the variables along ``candidate`` and ``map``); False:
        the truth-vs-fit table only.
    lpips : bool
        Compute LPIPS (optional packages); False: NaN.
    scheduler : {"synchronous", "threads", "processes", "distributed"}
        Dask scheduler (:func:`speckle.sweep.sweep`).
    n_workers : int, optional
        Dask workers (>= 1).
    progress : bool
        Report progress (a Dask progress bar).

    Returns
    -------
    xarray.Dataset
        Dims ``case`` (the seeds) and ``layer`` (0..4, NaN beyond the patient's layers):
        ``top_true``, ``top_fit``, ``top_se`` (µm), ``top_error`` (pixels), ``attenuation_*``
        (1/µm; ``attenuation_pull``), ``rho_e_*`` (per µm^3; ``rho_e_pull``), pulls NaN where
        the layer count is wrong; per case ``n_layers``, ``n_shown`` (above the window's floor),
        ``n_near`` (boundaries within 4 pixels of the floor, found or not), ``n_fit``,
        ``density`` (per µm^3) and ``failure`` (``"none"``, ``"layer count"`` or
        ``"boundary"``); with ``score`` each metric of :data:`speckle.METRIC_NAMES` along
        ``(case, candidate, map)``, candidates ``fitted``, ``floor``, ``baseline``.

    Raises
    ------
    TypeError, ValueError
        Bad seeds, config or options (named), before any work.

    Examples
    --------
    >>> import speckle
    >>> small = speckle.ScannerConfig(n_pixels=64, n_lines=96, x_max=576.0)
    >>> ds = phantom_closed_loop([1, 2], small, score=False, scheduler="synchronous")
    >>> ds.sizes["case"], ds["failure"].dims
    (2, ('case',))
    """
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, (Sequence, np.ndarray)):
        raise TypeError(f"seeds must be a sequence of non-negative integers, got {seeds!r}")
    seeds = [check_int(s, f"seeds[{i}]", low=0) for i, s in enumerate(seeds)]
    if not seeds or len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must hold at least one seed, each once; got {seeds!r}")
    cfg = _configuration(config)
    layers = _layers(layers)
    if isinstance(shapes, str) or not isinstance(shapes, Sequence) or not shapes:
        raise TypeError(f"shapes must be a non-empty sequence of {list(SHAPES)}, got {shapes!r}")
    for i, shape in enumerate(shapes):
        check_choice(shape, f"shapes[{i}]", SHAPES)
    if check_bool(inclusions, "inclusions") and not INCLUSIONS:
        raise ValueError("inclusions must be False: this version's patients draw none")
    rescans = check_int(rescans, "rescans", low=1, high=16)
    check_bool(score, "score")
    check_bool(lpips, "lpips")
    check_choice(scheduler, "scheduler", SCHEDULERS)
    if n_workers is not None:
        check_int(n_workers, "n_workers", low=1)
    check_bool(progress, "progress")
    if score and min(cfg.n_pixels, cfg.n_lines) < 21:
        raise ValueError(
            f"config's scan ({cfg.n_pixels} x {cfg.n_lines}) must be at least 21 x 21 pixels to "
            "be scored (the contrast window + 1); use score=False"
        )
    fixed = {"config": cfg, "layers": layers, "rescans": rescans, "score": score,
             "lpips": lpips}  # fmt: skip
    ds = sweep(_closed_loop_case, {"case": seeds}, fixed=fixed, scheduler=scheduler,
               n_workers=n_workers, progress=progress)  # fmt: skip
    ds = ds.assign_coords(case=coord("case", seeds))
    ds.attrs.update(
        {
            "n_pixels": cfg.n_pixels,
            "pixel_size": cfg.pixel_size,
            "n_lines": cfg.n_lines,
            "beam_radius": cfg.beam_radius,
            "rescans": rescans,
            "patients": f"flat layers, {layers[0]} to {layers[1]} (_flat_patient)",
        }
    )
    return ds
