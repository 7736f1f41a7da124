"""Density, energy and the window of the phantom fit (private): each layer's ``var ln I``
(shadowing spread removed), its inversion to the density, the energy, the 51 dB window's top
and the brightness of layers without a measurable slope.

The physics is in :mod:`speckle.studies.phantom._fit`'s docstring (steps 3 and 4); this module
holds the part of :func:`~speckle.studies.phantom._fit._fit_levels` after the segmentation and
the boundaries: ``layer_variances``, ``layer_densities``, ``window_and_brightness``.
"""

from __future__ import annotations

import math

import numpy as np

from ...analysis.sparse import depth_intensity_psf, log_intensity_moments, sparse_inverse_density
from ...synthoct import _scan
from ...synthoct.files import ScannerConfig
from ._slab import slab_constants

__all__ = ["LAG", "MAX_CLIPPED_VARIANCE", "layer_densities", "layer_variances",
           "window_and_brightness"]  # fmt: skip

#: Rows with more clipped pixels than this fraction give no ``var ln I``.
MAX_CLIPPED_VARIANCE = 0.01
#: Row lag whose covariance estimates the shadowing streaks' variance.
LAG = 4
#: Significance (in SE) for the density's excess and for a usable slope.
SIGNIFICANCE = 3.0


def _jackknife(values: np.ndarray) -> float:
    """SE of a statistic from its delete-one-block replicates ``values`` (blocks first axis)."""
    g = values.shape[0]
    return float(np.sqrt((g - 1) / g * np.sum((values - values.mean(0)) ** 2, axis=0)))


def _waist(cfg: ScannerConfig) -> float:
    """The beam's waist in line pitches (the 2-D theory's ``sqrt(2) r``)."""
    return math.sqrt(2) * cfg.beam_radius / cfg.line_pitch


def layer_variances(
    li: np.ndarray,
    z: np.ndarray,
    segs: list[tuple[int, int]],
    var_ok: np.ndarray,
    keep: list[np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """``var ln I`` of each layer's speckle and its delete-one-block replicates.

    The row variance minus the covariance of rows :data:`LAG` apart (the shadowing streaks,
    correlated over many rows; speckle is not, beyond the PSF), averaged over the segment's
    rows ``var_ok`` (at most :data:`MAX_CLIPPED_VARIANCE` clipped).

    Parameters
    ----------
    li : numpy.ndarray
        ``ln I`` of the fitted rows ``(rows, lines)``.
    z : numpy.ndarray
        The rows' depths (µm).
    segs : list of (int, int)
        Each layer's rows ``a .. b-1`` (indices into ``li``).
    var_ok : numpy.ndarray
        Rows that give a variance (bool).
    keep : list of numpy.ndarray
        Lines kept by each jackknife replicate.

    Returns
    -------
    v : numpy.ndarray
        ``(K,)``, NaN where a layer has fewer than 2 usable row pairs.
    v_jk : numpy.ndarray
        ``(blocks, K)``.
    """

    def layer_var(cols, a, b):
        sel = np.arange(a, b)[var_ok[a:b]]
        sel = sel[np.isin(sel + LAG, sel)]
        if sel.size < 2:
            return np.nan
        d = li[np.ix_(sel, cols)]
        d = d - d.mean(axis=1, keepdims=True)
        e = li[np.ix_(sel + LAG, cols)]
        e = e - e.mean(axis=1, keepdims=True)
        n = len(cols) - 1
        v = (np.sum(d * d, axis=1) + np.sum(e * e, axis=1)) / (2 * n) - np.sum(d * e, axis=1) / n
        return float(np.mean(v))

    all_cols = np.arange(li.shape[1])
    v = np.array([layer_var(all_cols, a, b) for a, b in segs])
    v_jk = np.array([[layer_var(k, a, b) for a, b in segs] for k in keep])
    return v, v_jk


def layer_densities(
    v: np.ndarray,
    v_jk: np.ndarray,
    mu: np.ndarray,
    mu_jk: np.ndarray,
    cfg: ScannerConfig,
) -> dict[str, np.ndarray]:
    """Each layer's density and energy from its ``var ln I`` and attenuation.

    ``var ln I`` is inverted by :func:`speckle.analysis.sparse.sparse_inverse_density` with the
    slab's kurtosis-equivalent density; the density is identified where the excess over
    ``pi^2/6`` exceeds :data:`SIGNIFICANCE` jackknife SEs, else NaN with the lower bound of
    the density whose excess is that many SEs; ``E = 100 mu/(rho A2)``.

    Returns
    -------
    dict
        ``v_se``, ``ident`` (bool), ``rho``, ``rho_se``, ``bound``, ``energy``,
        ``energy_se``, ``energy_bound``, each ``(K,)``, and ``rho_jk`` ``(blocks, K)``
        (per µm^3 and %).
    """
    consts = slab_constants(cfg.beam_radius)
    hann = _scan.hann_spectrum(cfg.n_pixels)
    waist = _waist(cfg)
    n_layers, blocks = v.size, v_jk.shape[0]

    def invert(value):
        if not np.isfinite(value) or value <= 0:
            return np.nan
        inv = sparse_inverse_density(value, hann, waist)
        return 1.0 / inv if inv > 0 else np.inf  # per pixel per pitch (equivalent)

    to_3d = 1.0 / (consts["t_eq"] * cfg.pixel_size * cfg.line_pitch)
    v_se = np.array([_jackknife(v_jk[:, k]) for k in range(n_layers)])
    ident = (v - np.pi**2 / 6) > SIGNIFICANCE * v_se
    rho = np.array([invert(v[k]) * to_3d if ident[k] else np.nan for k in range(n_layers)])
    energy_frac = np.where(ident, mu / (rho * consts["A2"]), np.nan)
    rho_jk = np.array(
        [[invert(v_jk[j, k]) * to_3d if ident[k] else np.nan for k in range(n_layers)]
         for j in range(blocks)]
    )  # fmt: skip
    rho_se = np.array([_jackknife(rho_jk[:, k]) if ident[k] else np.nan for k in range(n_layers)])
    bound = np.array(
        [np.nan if ident[k] else invert(np.pi**2 / 6 + SIGNIFICANCE * v_se[k]) * to_3d
         for k in range(n_layers)]
    )  # fmt: skip
    e_jk = mu_jk / (rho_jk * consts["A2"])
    energy = 100 * energy_frac
    energy_se = 100 * np.array([_jackknife(e_jk[:, k]) if ident[k] else np.nan
                                for k in range(n_layers)])  # fmt: skip
    energy_bound = np.where(ident, np.nan, 100 * mu / (bound * consts["A2"]))
    return {
        "v_se": v_se, "ident": ident, "rho": rho, "rho_se": rho_se, "rho_jk": rho_jk,
        "bound": bound, "energy": energy, "energy_se": energy_se, "energy_bound": energy_bound,
    }  # fmt: skip


def window_and_brightness(
    m: np.ndarray,
    m_jk: np.ndarray,
    z: np.ndarray,
    segs: list[tuple[int, int]],
    fitted: dict[str, np.ndarray],
    dens: dict[str, np.ndarray],
    cfg: ScannerConfig,
) -> dict[str, object]:
    """The 51 dB window's top and ``rho E/100`` of every layer.

    The window's top (nepers re ``|A| = 1``) is the predicted absolute ``E ln I`` of each
    layer with a significant slope (``ln(rho_e a2_y int|h|^2) - 2 C(z) + E ln(I/<I>)``) minus
    the observed level, weighted by rows; ``rho E/100`` is ``mu/A2`` where the slope is
    significant, else the layer's brightness under that window. Every jackknife replicate
    repeats the chain (its slopes, boundaries, window).

    Parameters
    ----------
    m, m_jk : numpy.ndarray
        Row-mean ``ln I`` ``(rows,)`` and its replicates ``(blocks, rows)``.
    z : numpy.ndarray
        The rows' depths (µm).
    segs : list of (int, int)
        Each layer's rows.
    fitted : dict
        ``mu``, ``mu_se``, ``mu_jk``, ``tops``, ``tops_jk``.
    dens : dict
        :func:`layer_densities`' result (``ident``, ``rho``).
    cfg : ScannerConfig
        The scanner's configuration.

    Returns
    -------
    dict
        ``wt``, ``wt_se`` (nepers), ``wt_jk``, ``rho_e``, ``rho_e_se`` (per µm^3).
    """
    r, p = cfg.beam_radius, cfg.pixel_size
    consts = slab_constants(r)
    hann = _scan.hann_spectrum(cfg.n_pixels)
    waist = _waist(cfg)
    mu, mu_se, mu_jk = fitted["mu"], fitted["mu_se"], fitted["mu_jk"]
    tops, tops_jk = fitted["tops"], fitted["tops_jk"]
    ident, rho = dens["ident"], dens["rho"]
    n_layers, blocks = mu.size, m_jk.shape[0]
    psf_area = float(np.sum(depth_intensity_psf(hann)) / 8 * p * r * math.sqrt(math.pi / 2))
    slope_ok = mu > SIGNIFICANCE * mu_se

    def cum_shadow(zz, k, mu_, tops_):
        c = sum(mu_[j] * (tops_[j + 1] - tops_[j]) for j in range(k))
        return c + mu_[k] * (zz - tops_[k])

    def mean_log(k):
        """``E ln(I/<I>)`` of layer ``k`` (fully developed where the density is unknown)."""
        if not ident[k] or not np.isfinite(rho[k]):
            return -np.euler_gamma
        return log_intensity_moments(hann, waist, rho[k] * consts["t_eq"] * p * cfg.line_pitch)[0]

    def window_top(mm, mu_, tops_):
        offs, wts = [], []
        for k, (a, b) in enumerate(segs):
            if not slope_ok[k] or mu_[k] <= 0:
                continue
            rho_e = mu_[k] / consts["A2"]
            zz = z[a:b]
            pred = (np.log(rho_e * consts["a2_y"] * psf_area) - 2 * cum_shadow(zz, k, mu_, tops_)
                    + mean_log(k))  # fmt: skip
            offs.append(float(np.mean(pred - mm[a:b])))
            wts.append(b - a)
        return float(np.average(offs, weights=wts)) if offs else np.nan

    def brightness(k, mm, mu_, tops_, wt_):
        """``rho E/100`` of layer ``k`` from its mean level under the window's top ``wt_``."""
        a, b = segs[k]
        zz = z[a:b]
        ln_re = mm[a:b] + wt_ + 2 * cum_shadow(zz, k, mu_, tops_) - mean_log(k)
        return float(np.exp(np.mean(ln_re))) / (consts["a2_y"] * psf_area)

    wt = window_top(m, mu, tops)
    wt_jk = np.array([window_top(m_jk[j], mu_jk[j], tops_jk[j]) for j in range(blocks)])
    wt_se = _jackknife(wt_jk)

    # rho E/100 per layer: from mu where the slope is significant, else from the brightness
    rho_e = mu / consts["A2"]
    rho_e_se = mu_se / consts["A2"]
    for k in range(n_layers):
        if slope_ok[k] or not np.isfinite(wt):
            continue
        rho_e[k] = brightness(k, m, mu, tops, wt)
        reps = [brightness(k, m_jk[j], mu_jk[j], tops_jk[j], wt_jk[j]) for j in range(blocks)]
        rho_e_se[k] = _jackknife(np.log(np.array(reps))) * rho_e[k]
    return {"wt": wt, "wt_se": wt_se, "wt_jk": wt_jk, "rho_e": rho_e, "rho_e_se": rho_e_se}
