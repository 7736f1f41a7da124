"""Shared helpers for the figure modules: headless matplotlib, one look, saving, rule logs.

Every figure module imports this first, so matplotlib always runs on the Agg backend (no
screen). :func:`new_figure` and :func:`save` give all figures the same size, resolution and
style (applied to ``matplotlib.rcParams`` on import); :func:`log_to` (re-exported from
:mod:`speckle._workflow`) sends a pipeline script's output, including Dask progress bars and
tracebacks, to its ``log:`` file.
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from .._workflow import log_to
from ..io import atomic_path

__all__ = ["DPI", "STYLE", "log_to", "new_figure", "save"]

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


def save(fig, path: str | os.PathLike) -> None:
    """Write ``fig`` to ``path`` (format from the suffix) atomically and close it.

    The figure goes to a temporary file beside ``path`` that replaces it only once complete
    (:func:`speckle.io.atomic_path`); parent directories are created.
    """
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=DPI, format=os.path.splitext(str(path))[1][1:] or None)
    finally:
        plt.close(fig)
