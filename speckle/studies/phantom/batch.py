"""The phantom fit's closed loop as a batch, scored as the SynthOCT challenge scores (issue 34).

:func:`phantom_closed_loop` runs :func:`speckle.phantom_closed_loop_case` for every seed (a
virtual patient of :func:`speckle.virtual_patient` scanned by the drop-in scanner and fitted
back by :func:`speckle.fit_phantom`: the pulls of each layer's parameters, each boundary's
error in pixels, the layer count, the failure class) and scores each case as the challenge
scores (:func:`speckle.synthoct_metrics`, every metric of every map), the target scan against

* ``fitted``: the fitted phantom drawn with another seed and scanned;
* ``floor``: the *true* patient drawn again with that seed and scanned (what no phantom can
  beat: two independent speckle patterns of one tissue);
* ``baseline``: the baseline generator's two-layer phantom
  (:func:`speckle.synthoct.files.baseline_table`, 0.01 % above 400 µm and 2.5 % below, in the
  case's box and count), drawn with that seed.

With ``rescans`` > 1 the scores are means over that many seeds (the case is fitted again for
each: the fit is deterministic, so only the draws differ). The cases run on Dask
(:func:`speckle.sweep.sweep`, one task per seed); every random number of a case comes from its
seed (``numpy.random.SeedSequence``), so the table is the same whatever the scheduler, the
workers or the order and grouping of the seeds. The case's variables along ``layer`` are padded
with NaN (``""`` for the shapes) to :data:`MAX_LAYERS` layers, the most the fit tries.

The issue's acceptance is tested on the mean over the cases of ``fitted - floor``: above
``-MARGIN - 2 SE``, the SE from the cases' spread. :func:`phantom_score_power` is that test's
power against a true mean ``beyond`` below the margin, for a number of cases and the per-case
SD of the difference (a noncentral t): what sizes the closed loop.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr
from scipy import stats

from ..._validate import check_bool, check_choice, check_int
from ...conventions import attrs, coord
from ...sweep import SCHEDULERS, sweep
from ...synthoct.configs import SYNTHOCT_CONFIGS
from ...synthoct.files import baseline_table
from ...synthoct.metrics import METRIC_NAMES, SYNTHOCT_MAPS, synthoct_metrics
from ...synthoct.scanner import synthoct_scan
from .loop import INCLUSION_SCALARS, PULLED, WINDOW_SCALARS, phantom_closed_loop_case
from .patients import MAX_PATIENT_INCLUSIONS, SHAPES, scanner_config_of, virtual_patient

__all__ = ["MARGIN", "phantom_closed_loop", "phantom_score_power"]

#: Named scanner configurations of the closed loop (:func:`speckle.synthoct_config`).
CONFIGURATIONS = tuple(SYNTHOCT_CONFIGS)
#: Candidates scored against each target scan.
CANDIDATES = ("fitted", "floor", "baseline")
#: Most layers of a patient (the fit tries up to 5); the case's ``layer`` dim is padded to it.
MAX_LAYERS = 5
#: Failure classes (``failure_class``): success, a wrong layer count, a boundary a pixel off,
#: a scan the fit refused (e.g. too few rows above the window's floor).
FAILURES = ("none", "layer count", "boundary", "refused")
FAILURE_NAME = "failure class: none, layer count, boundary (a pixel or more off), refused"
#: MS-SSIM margin of the issue's acceptance: the fitted phantom within 0.02 of the floor.
MARGIN = 0.02
#: Variables of the case with the patient's layer count, padded; their fill value.
_FILL = {"true_shape": "", "fit_shape": ""}


def _layers(layers: object) -> tuple[int, int]:
    if not isinstance(layers, Sequence) or isinstance(layers, str) or len(layers) != 2:
        raise TypeError(f"layers must be a pair (fewest, most), got {layers!r}")
    low = check_int(layers[0], "layers[0]", low=1, high=MAX_LAYERS)
    high = check_int(layers[1], "layers[1]", low=low, high=MAX_LAYERS)
    return low, high


def _seed_of(child: np.random.SeedSequence) -> int:
    return int(child.generate_state(1)[0])


def _padded(da: xr.DataArray) -> xr.DataArray:
    n = da.sizes["layer"]
    fill = _FILL.get(str(da.name), np.nan)
    values = np.asarray(da.values)
    if isinstance(fill, str):
        out = np.full(MAX_LAYERS, fill, dtype=object)
        out[:n] = values.astype(str)
    else:
        out = np.full(MAX_LAYERS, np.nan)
        out[:n] = values.astype(float)
    return xr.DataArray(out, dims="layer", attrs=da.attrs)


def _refused(seed, why, *, config, patient, score) -> xr.Dataset:
    """The row of a case whose scan the fit refused: the truth, NaN for the fit and scores."""
    _, truth = virtual_patient(seed, config=config, **patient)
    n = truth.sizes["layer"]
    data = {}
    for p in PULLED:
        true = truth["top_mean"] if p == "top" else truth[p]
        data[f"true_{p}"] = _padded(true.rename(f"true_{p}"))
        units = {k: v for k, v in true.attrs.items() if k != "long_name"}
        for name, extra in ((f"fit_{p}", units), (f"fit_{p}_se", units),
                            (f"{p}_pull", attrs("dimensionless", "pull"))):  # fmt: skip
            data[name] = xr.DataArray(np.full(MAX_LAYERS, np.nan), dims="layer", attrs=extra)
    data["boundary_error"] = xr.DataArray(
        np.full(MAX_LAYERS, np.nan), dims="layer", attrs=attrs("pixels", "boundary error")
    )
    shapes = np.full(MAX_LAYERS, "", dtype=object)
    shapes[:n] = truth["shape"].values.astype(str)
    data["true_shape"] = xr.DataArray(shapes, dims="layer", attrs=attrs("label", "true shape"))
    data["fit_shape"] = xr.DataArray(np.full(MAX_LAYERS, "", dtype=object), dims="layer")
    data["n_true"] = xr.DataArray(n, attrs=attrs("count", "true layers"))
    data["n_fit"] = xr.DataArray(0, attrs=attrs("count", "fitted layers"))
    for k in (*INCLUSION_SCALARS, *WINDOW_SCALARS):  # the fit's: none
        data[k] = xr.DataArray(np.nan, attrs=attrs("label", k.replace("_", " ")))
    data["n_inclusions_true"] = xr.DataArray(truth.sizes["inclusion"])
    for k in ("layers_right", "boundaries_right", "success"):
        data[k] = xr.DataArray(0, attrs=attrs("label", k.replace("_", " ")))
    data["failure"] = xr.DataArray(f"refused: {why}")
    data["failure_class"] = xr.DataArray("refused", attrs=attrs("label", FAILURE_NAME))
    if score:
        nan = np.full((len(CANDIDATES), len(SYNTHOCT_MAPS)), np.nan)
        for name in METRIC_NAMES:
            data[name] = xr.DataArray(nan.copy(), dims=("candidate", "map"))
    ds = xr.Dataset(data, coords={"layer": coord("layer", np.arange(MAX_LAYERS))})
    if score:
        ds = ds.assign_coords(
            candidate=coord("candidate", list(CANDIDATES)), map=coord("map", list(SYNTHOCT_MAPS))
        )
    return ds


def _case(case, *, config, patient, rescans, score, lpips) -> xr.Dataset:
    """One case of :func:`phantom_closed_loop` (its seed ``case``)."""
    seed = int(case)
    draws = [_seed_of(c) for c in np.random.SeedSequence([int(seed), 1]).spawn(rescans)]
    try:
        case = phantom_closed_loop_case(int(seed), config=config, fit_seed=draws[0], **patient)
    except ValueError as err:  # the options were checked: the fit refused this scan
        return _refused(seed, str(err), config=config, patient=patient, score=score)
    data = {k: _padded(v) for k, v in case.data_vars.items() if v.dims == ("layer",)}
    for k in ("n_true", "n_fit", *INCLUSION_SCALARS, *WINDOW_SCALARS):
        data[k] = case[k]
    for k in ("layers_right", "boundaries_right", "success"):  # NetCDF has no bool: 0/1
        data[k] = xr.DataArray(int(bool(case[k])), attrs=case[k].attrs)
    failure = "none" if bool(case.success) else FAILURES[1 + bool(case.layers_right)]
    data["failure"] = case["failure"].astype(str)
    data["failure_class"] = xr.DataArray(failure, attrs=attrs("label", FAILURE_NAME))
    if score:
        target = case["target_scan"].values
        scores = {c: [] for c in CANDIDATES}
        for i, draw in enumerate(draws):
            if i:
                case = phantom_closed_loop_case(int(seed), config=config, fit_seed=draw, **patient)
            base = baseline_table("layers", draw, config=config)
            scans = {
                "fitted": case["fitted_scan"].values,
                "floor": case["floor_scan"].values,
                "baseline": synthoct_scan(base, config, nthreads=1).values,
            }
            for c in CANDIDATES:
                scores[c].append(synthoct_metrics(target, scans[c], lpips=lpips))
        per = [xr.concat(scores[c], "rescan").mean("rescan", keep_attrs=True) for c in CANDIDATES]
        metrics = xr.concat(per, "candidate", combine_attrs="override").drop_vars("map")
        for name, da in metrics.data_vars.items():
            data[name] = xr.DataArray(da.values, dims=("candidate", "map"), attrs=da.attrs)
    ds = xr.Dataset(data, coords={"layer": coord("layer", np.arange(MAX_LAYERS))})
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
    shapes: Sequence[str] = SHAPES,
    inclusions: bool | int = False,
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
        The scanner configuration (:func:`speckle.synthoct_config`).
    layers : (int, int)
        Fewest and most layers of the patients (1..5).
    shapes : sequence of {"flat", "tilted", "curved"}
        Boundary shapes the patients draw from (:func:`speckle.virtual_patient`).
    inclusions : bool or int
        Elliptical inclusions of each patient: ``True`` one, or their number
        (0..:data:`~speckle.studies.phantom.patients.MAX_PATIENT_INCLUSIONS`).
    rescans : int
        Draws (seeds) whose scores are averaged (1..16).
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
        Dims ``case`` (the seeds) and ``layer`` (0..4, NaN beyond the patient's layers): the
        per-layer variables of :func:`speckle.phantom_closed_loop_case` (``true_<p>``,
        ``fit_<p>``, ``fit_<p>_se``, ``<p>_pull`` for ``top`` in µm, ``attenuation`` in 1/µm,
        ``rho_e``, ``density`` in µm^-3, ``energy`` in %; ``boundary_error`` in pixels;
        ``true_shape``, ``fit_shape``); per case ``n_true``, ``n_fit``, ``layers_right``,
        ``boundaries_right``, ``success`` (0/1), ``failure`` (why, empty on success) and
        ``failure_class`` (``"none"``, ``"layer count"``, ``"boundary"`` or ``"refused"``: the
        fit refused the scan, its reason in ``failure``, NaN for the fit and the scores);
        the inclusion scalars of :func:`speckle.phantom_closed_loop_case` (found, false alarms,
        centre error, pulls; the fit looks for inclusions when ``inclusions``); the window's
        top, fitted and true, in dB, and its pull
        (:data:`~speckle.studies.phantom.loop.WINDOW_SCALARS`); with ``score`` each metric of
        :data:`speckle.METRIC_NAMES` along ``(case, candidate, map)``, candidates ``fitted``,
        ``floor``, ``baseline``.

    Raises
    ------
    TypeError, ValueError
        Bad seeds, config or options (named), before any work.

    Examples
    --------
    >>> import speckle
    >>> small = speckle.ScannerConfig(n_pixels=96, n_lines=96, x_max=576.0, n_scatterers=20_000)
    >>> ds = phantom_closed_loop([1, 2], small, layers=(2, 2), score=False,
    ...                          scheduler="synchronous")
    >>> ds.sizes["case"], ds["failure_class"].dims, ds["n_true"].values.tolist()
    (2, ('case',), [2, 2])
    """
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, (Sequence, np.ndarray)):
        raise TypeError(f"seeds must be a sequence of non-negative integers, got {seeds!r}")
    seeds = [check_int(s, f"seeds[{i}]", low=0) for i, s in enumerate(seeds)]
    if not seeds or len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must hold at least one seed, each once; got {seeds!r}")
    if isinstance(config, str):
        check_choice(config, "config", CONFIGURATIONS)
    cfg = scanner_config_of(config)
    layers = _layers(layers)
    if isinstance(shapes, str) or not isinstance(shapes, Sequence) or not shapes:
        raise TypeError(f"shapes must be a non-empty sequence of {list(SHAPES)}, got {shapes!r}")
    for i, shape in enumerate(shapes):
        check_choice(shape, f"shapes[{i}]", SHAPES)
    if not isinstance(inclusions, bool):
        inclusions = check_int(inclusions, "inclusions", low=0, high=MAX_PATIENT_INCLUSIONS)
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
    patient = {"layers": layers, "shapes": tuple(shapes), "inclusions": inclusions}
    fixed = {"config": cfg, "patient": patient, "rescans": rescans, "score": score,
             "lpips": lpips}  # fmt: skip
    ds = sweep(_case, {"case": seeds}, fixed=fixed, scheduler=scheduler,
               n_workers=n_workers, progress=progress)  # fmt: skip
    ds = ds.assign_coords(case=coord("case", seeds))
    ds.attrs.update(
        {
            "n_pixels": cfg.n_pixels,
            "pixel_size": cfg.pixel_size,
            "n_lines": cfg.n_lines,
            "beam_radius": cfg.beam_radius,
            "rescans": rescans,
            "patients": f"{layers[0]} to {layers[1]} layers, boundaries {', '.join(shapes)}, "
            f"inclusions {'on' if inclusions else 'off'} (speckle.virtual_patient)"
            + ("" if isinstance(inclusions, bool) or inclusions < 2 else f", {inclusions} each"),
        }
    )
    return ds


def phantom_score_power(cases: object, sd: object, *, beyond: float = 0.03) -> float | np.ndarray:
    """Power of the closed loop's score test: the probability that it fails a fitted phantom
    whose true mean ``fitted - floor`` lies ``beyond`` below the margin.

    The test passes when the mean over ``n`` cases of the difference ``d`` (one map's MS-SSIM,
    fitted minus floor) lies above ``-MARGIN - 2 s/sqrt(n)``, ``s`` the cases' sample SD. With
    ``d`` normal of mean ``delta = -MARGIN - beyond`` and SD ``sd``, ``(mean + MARGIN)/(s/
    sqrt(n))`` is noncentral t with ``n - 1`` degrees of freedom and noncentrality ``-beyond
    sqrt(n)/sd``; the power is its probability below -2 (the margin drops out). For large ``n``
    it tends to ``Phi(beyond sqrt(n)/sd - 2)``: 80 % needs ``n >= (2.84 sd/beyond)^2``.

    Parameters
    ----------
    cases : int or array of int
        Cases of the closed loop (>= 2).
    sd : float or array
        SD of one case's difference (> 0; measured, docs/explanation/phantom_fit.md).
    beyond : float
        How far below the margin the true mean lies (> 0).

    Returns
    -------
    float or numpy.ndarray
        The power (0..1), broadcast over ``cases`` and ``sd``.

    Raises
    ------
    TypeError, ValueError
        Non-numeric input, fewer than 2 cases, a non-positive SD or ``beyond``.

    Examples
    --------
    >>> import numpy as np
    >>> from speckle.studies.phantom.batch import phantom_score_power
    >>> round(float(phantom_score_power(8, 0.055)), 2)  # the former default: 8 cases
    0.37
    >>> n = np.arange(2, 100)
    >>> int(n[np.argmax(phantom_score_power(n, 0.055) >= 0.8)])  # least cases for 80 %
    28
    """
    arrays = {}
    for name, value in (("cases", cases), ("sd", sd), ("beyond", beyond)):
        if isinstance(value, (bool, str, bytes)):
            raise TypeError(f"{name} must be numeric, got {value!r}")
        try:
            arrays[name] = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be numeric, got {value!r}") from None
    n, s, b = arrays["cases"], arrays["sd"], arrays["beyond"]
    if not np.all(np.isfinite(n)) or np.any(n < 2) or np.any(n != np.round(n)):
        raise ValueError(f"cases must be integers >= 2 (an SD needs two), got {cases!r}")
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise ValueError(f"sd must be finite and > 0, got {sd!r}")
    if b.ndim or not np.isfinite(b) or b <= 0:
        raise ValueError(f"beyond must be a finite number > 0, got {beyond!r}")
    power = stats.nct.cdf(-2.0, n - 1, -b * np.sqrt(n) / s)
    return float(power) if np.ndim(power) == 0 else power
