"""The ``phantom_fit`` section's checks, run when the workflow loads (``ValueError`` naming the
key): what :func:`speckle.phantom_closed_loop` refuses, so that a bad section stops the run
before any job. :func:`speckle.pipeline.checks.check_config` calls :func:`check_phantom_fit`."""

from __future__ import annotations

from collections.abc import Mapping

from ..studies.phantom.batch import CONFIGURATIONS, MAX_LAYERS
from ..studies.phantom.patients import SHAPES
from ..synthoct.configs import synthoct_config

__all__ = ["check_phantom_fit"]

#: Largest case seed (the table's ``case`` coordinate is int64).
MAX_SEED = 2**63 - 1


def check_phantom_fit(cfg: Mapping) -> None:
    """What the schema cannot say about the ``phantom_fit`` section (``ValueError`` naming it).

    The layer range is ordered and within 1..5 (the most the fit tries); the case seeds
    ``seed .. seed + cases - 1`` fit in int64; the configurations and the boundary shapes are
    those of :func:`speckle.synthoct_config` and :func:`speckle.virtual_patient`. The failure
    map's thicknesses are at most a third of its configuration's pixels, its energy times the
    largest contrast at most 100 %, and its seeds fit in int64
    (:func:`speckle.phantom_failure_map`).
    """
    low, high = (int(v) for v in cfg["layers"])
    if not 1 <= low <= high <= MAX_LAYERS:
        raise ValueError(
            f"config key phantom_fit.layers = {[low, high]} must be [fewest, most] with "
            f"1 <= fewest <= most <= {MAX_LAYERS}"
        )
    last = int(cfg["seed"]) + int(cfg["cases"]) - 1
    if last > MAX_SEED:
        raise ValueError(
            f"config key phantom_fit.seed = {cfg['seed']} with phantom_fit.cases = "
            f"{cfg['cases']} gives seeds above 2**63 - 1; lower the seed"
        )
    for key, values, known in (
        ("configurations", cfg["configurations"], CONFIGURATIONS),
        ("shapes", cfg["shapes"], SHAPES),
    ):
        for i, value in enumerate(values):
            if value not in known:
                raise ValueError(
                    f"config key phantom_fit.{key}[{i}] = {value!r} must be one of {list(known)}"
                )
    fm = cfg["failure_map"]
    n = synthoct_config(str(fm["configuration"])).n_pixels
    for i, t in enumerate(fm["thickness"]):
        if not 0 < float(t) <= n / 3:
            raise ValueError(
                f"config key phantom_fit.failure_map.thickness[{i}] = {t!r} must lie in "
                f"(0, {n / 3:g}] pixels (a third of the {fm['configuration']} scan's {n})"
            )
    top = float(fm["energy"]) * max(float(q) for q in fm["contrast"])
    if top > 100:
        raise ValueError(
            f"config key phantom_fit.failure_map.energy = {fm['energy']!r} times the largest "
            f"contrast gives {top:g} % for the middle layer; at most 100 %"
        )
    if int(fm["seed"]) + int(fm["seeds"]) - 1 > MAX_SEED:
        raise ValueError(
            f"config key phantom_fit.failure_map.seed = {fm['seed']} gives seeds above "
            "2**63 - 1; lower it"
        )
