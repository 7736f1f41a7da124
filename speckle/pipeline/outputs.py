"""Writing a pipeline job's figure: atomically, at the figures' resolution, then closed."""

from __future__ import annotations

import os

import matplotlib.pyplot as plt

from ..figures.style import DPI
from ..io import atomic_path

__all__ = ["save"]


def save(fig, path: str | os.PathLike) -> None:
    """Write ``fig`` to ``path`` (format from the suffix) atomically and close it.

    The figure goes to a temporary file beside ``path`` that replaces it only once complete
    (:func:`speckle.io.atomic_path`); parent directories are created.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (e.g. of a ``plot_<name>`` function of :mod:`speckle.figures`).
    path : str or os.PathLike
        The output file; its suffix (``.png``, ``.pdf``, ...) sets the format.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from speckle.figures.style import new_figure
    >>> fig, axes = new_figure(1, 1)
    >>> out = pathlib.Path(tempfile.mkdtemp(), "figure.png")
    >>> save(fig, out)
    >>> out.stat().st_size > 0
    True
    """
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=DPI, format=os.path.splitext(str(path))[1][1:] or None)
    finally:
        plt.close(fig)
