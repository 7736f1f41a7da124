"""The ``phantom_fit`` section's checks, run when the workflow loads (``ValueError`` naming the
key): what :func:`speckle.phantom_closed_loop` refuses, so that a bad section stops the run
before any job. :func:`speckle.pipeline.checks.check_config` calls :func:`check_phantom_fit`."""

from __future__ import annotations

from collections.abc import Mapping

from ..studies.phantom_loop import CONFIGURATIONS, INCLUSIONS, MAX_LAYERS, SHAPES

__all__ = ["check_phantom_fit"]

#: Largest case seed (``numpy.random.SeedSequence`` takes any non-negative integer; the table's
#: ``case`` coordinate is int64).
MAX_SEED = 2**63 - 1


def check_phantom_fit(cfg: Mapping) -> None:
    """What the schema cannot say about the ``phantom_fit`` section (``ValueError`` naming it).

    The layer range is ordered and within 1..5; the case seeds ``seed .. seed + cases - 1`` fit
    in int64; the configurations are known; the shapes are those the package's virtual
    patients draw and inclusions are off unless they draw them.
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
    for i, name in enumerate(cfg["configurations"]):
        if name not in CONFIGURATIONS:
            raise ValueError(
                f"config key phantom_fit.configurations[{i}] = {name!r} must be one of "
                f"{sorted(CONFIGURATIONS)}"
            )
    for i, shape in enumerate(cfg["shapes"]):
        if shape not in SHAPES:
            raise ValueError(
                f"config key phantom_fit.shapes[{i}] = {shape!r}: the virtual patients of this "
                f"version draw {list(SHAPES)} boundaries only"
            )
    if cfg["inclusions"] and not INCLUSIONS:
        raise ValueError(
            "config key phantom_fit.inclusions = true: the virtual patients of this version "
            "draw no inclusions (set it false)"
        )
