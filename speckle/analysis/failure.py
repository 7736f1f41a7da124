"""Scoring strain estimators where they may fail: method labels and error summaries.

Failure maps (``speckle.figures.elastography``) and a fitted system's predicted maps
(``speckle.analysis.twin``) run each strain estimator of ``speckle.analysis.strain`` on image
pairs of known strain and summarise how far each answer is from the truth.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mean_and_se", "method_options", "strain_scores"]

#: Label suffix -> the ``align`` option of ``estimate_strain`` it stands for.
_ALIGN_SUFFIXES = {"_unaligned": False, "_aligned": True}


def method_options(label: str) -> tuple[str, dict]:
    """Estimator name and ``estimate_strain`` options of a method label.

    Parameters
    ----------
    label : str
        An estimator of ``speckle.analysis.strain.METHODS``, optionally with the suffix
        ``"_aligned"`` or ``"_unaligned"`` (``align=True`` / ``align=False``).

    Returns
    -------
    tuple of (str, dict)
        The estimator's name and the keyword options the suffix stands for.
    """
    for suffix, align in _ALIGN_SUFFIXES.items():
        if label.endswith(suffix):
            return label.removesuffix(suffix), {"align": align}
    return label, {}


def strain_scores(estimate: np.ndarray, truth: np.ndarray | float) -> tuple[float, float, float]:
    """Median error, rms error and the answered fraction of a strain map.

    Parameters
    ----------
    estimate : numpy.ndarray
        Estimated strain (dimensionless); NaN where the estimator gave no answer.
    truth : numpy.ndarray or float
        True strain, broadcastable to ``estimate``.

    Returns
    -------
    tuple of float
        Median and rms of ``estimate - truth`` over the answered pixels (NaN when none), and
        the fraction of pixels answered.
    """
    ok = np.isfinite(estimate)
    if not ok.any():
        return np.nan, np.nan, 0.0
    err = estimate[ok] - np.broadcast_to(truth, estimate.shape)[ok]
    return float(np.median(err)), float(np.sqrt(np.mean(err**2))), float(ok.mean())


def mean_and_se(values: np.ndarray, axis: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """Mean over independent repeats (seeds) and its standard error, ignoring NaN repeats.

    Parameters
    ----------
    values : numpy.ndarray
        Repeated measurements, the repeats along ``axis``; NaN where a repeat gave no value.
    axis : int
        The axis of the repeats.

    Returns
    -------
    tuple of numpy.ndarray
        The mean of the finite repeats (NaN when none) and its standard error
        ``std(ddof=1) / sqrt(n)`` over the ``n`` finite repeats (NaN when ``n < 2``).
    """
    v = np.asarray(values, dtype=float)
    n = np.isfinite(v).sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        total = np.where(np.isfinite(v), v, 0.0).sum(axis=axis)
        mean = np.where(n > 0, total / np.maximum(n, 1), np.nan)
        dev = np.where(np.isfinite(v), v - np.expand_dims(mean, axis), 0.0)
        var = (dev**2).sum(axis=axis) / np.maximum(n - 1, 1)
        se = np.where(n >= 2, np.sqrt(var / np.maximum(n, 1)), np.nan)
    return mean, se
