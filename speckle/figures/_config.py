"""Moved to :mod:`speckle.pipeline.adapters` (kept, private, for the figure data builders that
still take config sections; they import it from here until they move to ``speckle.studies``)."""

from ..pipeline.adapters import (
    dask_options,
    random_bscan,
    resolve_source,
    scene_kwargs,
    source_options,
    source_spectrum,
    spectrum_kwargs,
    system_from_config,
)

__all__ = [
    "dask_options",
    "random_bscan",
    "resolve_source",
    "scene_kwargs",
    "source_options",
    "source_spectrum",
    "spectrum_kwargs",
    "system_from_config",
]
