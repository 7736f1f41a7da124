"""Moved to :mod:`speckle.pipeline.adapters` (kept, private, for the figure data builders that
still take config sections; they import it from here until they move to ``speckle.studies``)."""

from ..pipeline.adapters import *  # noqa: F403 (the old path: every name of the new one)
from ..pipeline.adapters import __all__  # noqa: F401
