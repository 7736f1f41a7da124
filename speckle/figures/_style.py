"""Moved: the style is :mod:`speckle.figures.style`, saving :mod:`speckle.pipeline.outputs`.

Kept (private, no warning) for figure modules written against the old path; new code imports
the public modules.
"""

from ..pipeline.outputs import save
from ..pipeline.runner import log_to
from .style import DPI, STYLE, new_figure

__all__ = ["DPI", "STYLE", "log_to", "new_figure", "save"]
