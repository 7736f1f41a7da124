"""Shared helpers for the figure modules: headless matplotlib, one look, saving, rule logs.

Every figure module imports this first, so matplotlib always runs on the Agg backend (no
screen). :func:`new_figure` and :func:`save` give all figures the same size, resolution and
style (applied to ``matplotlib.rcParams`` on import); :func:`log_to` sends a pipeline script's
output (including Dask progress bars) to its Snakemake ``log:`` file.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

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


@contextlib.contextmanager
def log_to(path: str | os.PathLike | None) -> Iterator[None]:
    """Send stdout, stderr and ``logging`` (INFO) to ``path`` while the block runs.

    Used by the pipeline scripts so that Dask progress bars and sweep progress lines end up in
    the rule's ``log:`` file. ``path=None`` leaves the streams alone.
    """
    if path is None:
        yield
        return
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    root = logging.getLogger()
    with (
        open(path, "w", buffering=1) as stream,
        contextlib.redirect_stdout(stream),
        contextlib.redirect_stderr(stream),
    ):
        handler = logging.StreamHandler(stream)
        handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(message)s"))
        old_level = root.level
        root.addHandler(handler)
        root.setLevel(logging.INFO)
        try:
            yield
        finally:
            root.removeHandler(handler)
            root.setLevel(old_level)
