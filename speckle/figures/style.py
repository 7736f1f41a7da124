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
import numpy as np

__all__ = [
    "DPI",
    "ESTIMATOR_COLOURS",
    "ESTIMATOR_NAMES",
    "MIN_LEGEND_PT",
    "NO_COLORBAR",
    "STYLE",
    "colorbar",
    "estimator_colour",
    "legend_outside",
    "mark_no_colorbar",
    "new_figure",
    "physical_image",
]

DPI = 150
#: rcParams shared by all figures (small fonts: panels are small multiples).
STYLE = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "legend.fontsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "image.interpolation": "nearest",
    "savefig.bbox": "tight",
}
plt.rcParams.update(STYLE)
#: Smallest legend font (points at :data:`DPI`) a reader can read; the figure checks hold it.
MIN_LEGEND_PT = 8.0
#: Strain estimators of the elastography figures (and the twin's failure chart): one colour per
#: method in every figure of the family; ``*_aligned`` / ``*_unaligned`` share their method's
#: hue family.
ESTIMATOR_COLOURS = {
    "vector": "#1f77b4",
    "vector_aligned": "#17becf",
    "vector_unaligned": "#9edae5",
    "wls": "#ff7f0e",
    "wls_aligned": "#bcbd22",
    "wls_unaligned": "#ffbb78",
    "tracking": "#2ca02c",
    "correlation": "#d62728",
}
#: Strain estimators (``method`` coordinates) in words, for titles and legends.
ESTIMATOR_NAMES = {
    "vector": "vector (phase)",
    "vector_aligned": "vector, aligned",
    "vector_unaligned": "vector, unaligned",
    "wls": "weighted least squares",
    "wls_aligned": "WLS, aligned",
    "wls_unaligned": "WLS, unaligned",
    "tracking": "speckle tracking",
    "correlation": "correlation",
}
#: Gid of an image that needs no colorbar (a region map, a grey-level fragment with a scale bar
#: drawn elsewhere): the figure checks skip it.
NO_COLORBAR = "no-colorbar"


def estimator_colour(method: str) -> str:
    """The colour of strain estimator ``method`` in every elastography figure (black if new)."""
    return ESTIMATOR_COLOURS.get(str(method), "k")


def colorbar(fig, mappable, ax, label: str, **kw):
    """A colorbar beside ``ax`` (an Axes or a list of them) labelled with its quantity and unit."""
    return fig.colorbar(mappable, ax=ax, label=label, **kw)


def mark_no_colorbar(image):
    """Mark ``image`` (an AxesImage) as needing no colorbar: its values are categories (a
    region map) or its scale is given another way; returns it."""
    image.set_gid(NO_COLORBAR)
    return image


def physical_image(ax, img, depth, lateral, *, xlabel: str = "lateral position (µm)", **kw):
    """``img`` (depth x lateral) drawn at its physical aspect ratio (1 µm = 1 µm on both axes).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    img : array_like
        The image, depth along its first axis.
    depth, lateral : array_like
        The pixel centres (µm) along depth and laterally: the ``depth`` and lateral coordinates.
    xlabel : str
        The lateral axis' label.
    **kw
        Passed on to :meth:`~matplotlib.axes.Axes.imshow`.

    Returns
    -------
    matplotlib.image.AxesImage
        The image, both axes labelled.
    """
    depth, lateral = np.asarray(depth, float), np.asarray(lateral, float)
    dz = float(depth[1] - depth[0]) if depth.size > 1 else 1.0
    dx = float(lateral[1] - lateral[0]) if lateral.size > 1 else 1.0
    extent = [lateral[0] - dx / 2, lateral[-1] + dx / 2, depth[-1] + dz / 2, depth[0] - dz / 2]
    im = ax.imshow(img, extent=extent, aspect="equal", **kw)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("depth (µm)")
    return im


def legend_outside(ax, *, where: str = "right", **kw):
    """The legend of ``ax`` off its data: to the right of the axes (``where="right"``) or
    below them (``"below"``), in the shared legend font (>= :data:`MIN_LEGEND_PT`)."""
    if where == "below":
        place = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.22)}
    else:
        place = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0)}
    return ax.legend(**place, borderaxespad=0.0, frameon=False, **kw)


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
