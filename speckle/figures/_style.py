"""Moved: the style is :mod:`speckle.figures.style`, saving :mod:`speckle.pipeline.outputs`.

Kept (private, no warning) for figure modules written against the old path; new code imports
the public modules.
"""

from ..pipeline.outputs import save
from ..pipeline.runner import log_to
from .style import *  # noqa: F403
from .style import __all__ as _STYLE_NAMES

__all__ = [*_STYLE_NAMES, "log_to", "save"]
