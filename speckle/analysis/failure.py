"""Scoring strain estimators where they may fail: method labels and error summaries.

Failure maps (``speckle.figures.elastography``) and a fitted system's predicted maps
(``speckle.analysis.twin``) run each strain estimator of ``speckle.analysis.strain`` on image
pairs of known strain and summarise how far each answer is from the truth.
"""

from __future__ import annotations

import numpy as np

__all__ = ["method_options", "strain_scores"]

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
