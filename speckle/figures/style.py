"""The figures' look: headless matplotlib, one style, one figure shape.

Every figure module imports this first, so matplotlib always runs on the Agg backend (no
screen). :func:`new_figure` gives all figures the same size and style (applied to
``matplotlib.rcParams`` on import) and :data:`DPI` their resolution; the pipeline writes them
with :func:`speckle.pipeline.outputs.save`.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

__all__ = ["DPI", "STYLE", "new_figure"]

DPI = 150
#: rcParams shared by all figures (small fonts: panels are small multiples).
STYLE = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "legend.fontsize": 7,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "image.interpolation": "nearest",
    "savefig.bbox": "tight",
}
plt.rcParams.update(STYLE)


def new_figure(nrows: int, ncols: int, *, width: float = 7.0, height: float = 3.0, **kw):
    """A figure of ``nrows`` x ``ncols`` panels in the shared style (size in inches).

    Returns
    -------
    (matplotlib.figure.Figure, numpy.ndarray of Axes)
        The axes array is always 2-D (``squeeze=False``).
    """
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(width, height), squeeze=False, layout="constrained", **kw
    )
    return fig, axes
