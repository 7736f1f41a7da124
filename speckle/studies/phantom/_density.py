"""Density and energy of the phantom fit (private): each layer's ``var ln I`` (shadowing
spread removed), its inversion to the density and the energy (the window's top and the
brightness of layers without a measurable slope: :mod:`speckle.studies.phantom._window`).

The physics is in :mod:`speckle.studies.phantom._fit`'s docstring (steps 3 and 4); this module
holds the part of :func:`~speckle.studies.phantom._fit._fit_levels` after the segmentation and
the boundaries: ``layer_variances``, ``layer_densities``. What it
adds to that model (each measured against the scanner, docs/explanation/phantom_fit.md, "The
density"): the slab's exact sparse-speckle theory (:func:`slab_log_moments`, amplitudes
``exp(-y^2/r^2)`` integrated in the characteristic function); the row variance's loss to the
lines' correlation (:func:`lateral_variance_factor`); rows chosen by the layer's fitted level,
not by their own clipped pixels; ``var ln I``'s own jackknife over blocks of
:data:`BLOCK_RADII` beam radii; identification at :data:`IDENTIFY` SE, the density's SE to
the density of ``v - 2 SE`` and a one-sided lower bound where it is not identified; and,
where the floor clips the rows ``var ln I`` needs, a lower bound from the intensity's kurtosis
(:func:`kurtosis_density`, Campbell's theorem), which the inclusions' count test uses.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import special

# private: the sparse-speckle theory's numerical core, shared with analysis.sparse
from ...analysis._sparse_theory import TAU, exponent, invert_log_variance, moments_of
from ...analysis.sparse import depth_intensity_psf
from ...synthoct import _scan
from ...synthoct.files import ScannerConfig
from ._slab import depth_psf, slab_constants

__all__ = [
    "BLOCKS",
    "BLOCK_RADII",
    "DENSE_CLIP_RATE",
    "LAG",
    "MAX_PREDICTED_CLIPPED",
    "both_rule_variances",
    "clip_rates",
    "kurtosis_density",
    "kurtosis_volume",
    "lateral_variance_factor",
    "layer_densities",
    "layer_variances",
    "lines_per_block",
    "log_offset_se",
    "log_offsets",
    "slab_inverse_density",
    "slab_log_moments",
]  # fmt: skip

#: Rows whose predicted clipped fraction (fully developed speckle at the layer's fitted mean
#: level) exceeds this give no ``var ln I`` (:func:`layer_variances`).
MAX_PREDICTED_CLIPPED = 0.01
#: Fully developed speckle's rate ``A`` of clipped pixels, ``1 - exp(-A c/exp(E ln I))``:
#: ``exp(-gamma)`` (``<I> = exp(E ln I + gamma)``).
DENSE_CLIP_RATE = math.exp(-np.euler_gamma)
#: ``ln c`` of the window's floor (the top of level 0), relative to the window's top.
_CLIP = (_scan.DYNAMIC_RANGE / _scan.LEVELS - _scan.DYNAMIC_RANGE) * math.log(10) / 10
#: Row lag whose covariance estimates the shadowing streaks' variance.
LAG = 4
#: Significance (in SE) for a usable slope (and the layer criterion's steps).
SIGNIFICANCE = 3.0
#: Significance (in SE) of the excess ``var ln I - pi^2/6`` that identifies the density. With
#: ``rho`` about ``1/excess``, the pull of ``rho`` at its own SE is ``-Z (1 + Z/k)`` for an
#: excess ``k`` SEs above ``pi^2/6`` and a fluctuation ``Z``: at 3 SE (and selected by the
#: same data) the pulls of identified densities fail (4 of 7 beyond 2 in the reduced loop); at
#: 5 the relative SE is at most 0.2. (The SE itself is taken
#: to the density of ``v - 2 SE``, :func:`layer_densities`, so that no such stretch remains.)
IDENTIFY = 5.0
#: One-sided normal quantile of the density's lower bound (97.7 %).
BOUND_SE = 2.0
#: Least width (beam radii) of the lateral blocks of ``var ln I``'s own jackknife.
BLOCK_RADII = 8.0
#: Lateral blocks of the jackknife.
BLOCKS = 16


def _jackknife(values: np.ndarray) -> float:
    """SE of a statistic from its delete-one-block replicates ``values`` (blocks first axis)."""
    g = values.shape[0]
    return float(np.sqrt((g - 1) / g * np.sum((values - values.mean(0)) ** 2, axis=0)))


@functools.lru_cache(maxsize=16)
def _slab_lambda(n_pixels: int, radius: float, pitch: float) -> tuple[np.ndarray, float]:
    """``Lambda_slab(t) = int_{-r}^{r} Lambda(t exp(-y^2/r^2)) dy`` (µm) on the theory's ``t``
    grid, ``Lambda`` the 2-D unit-amplitude exponent of :mod:`speckle.analysis.sparse` (pixel
    and pitch units), and that module's ``int |h|^2`` (``area``)."""
    hann = _scan.hann_spectrum(n_pixels)
    lam, area = exponent(tuple(hann), math.sqrt(2) * radius / pitch)  # waist
    ln_t = TAU - 0.5 * math.log(area)
    nodes, weights = np.polynomial.legendre.leggauss(64)
    y = (nodes + 1) / 2 * radius  # 0 .. r, doubled by symmetry
    ln_t_a = ln_t[None, :] - (y[:, None] / radius) ** 2  # ln(t a(y))
    # below the grid, J0(u) - 1 = -u^2/4: Lambda(t) = -t^2 area/4
    lam_a = np.where(ln_t_a < ln_t[0], -np.exp(2 * ln_t_a) * area / 4,
                     np.interp(ln_t_a, ln_t, lam))  # fmt: skip
    return 2 * np.sum((weights * radius / 2)[:, None] * lam_a, axis=0), area


def slab_log_moments(density: float, cfg: ScannerConfig) -> tuple[float, float]:
    """``E ln(I/<I>)`` and ``var ln I`` of a slab's sparse speckle, exactly.

    Poisson scatterers of ``density`` per µm^3 in the slab ``|y| <= r`` have amplitudes
    ``exp(-y^2/r^2)`` (the double-pass weight's ``y`` factor) on top of the 2-D model of
    :mod:`speckle.analysis.sparse` (waist ``sqrt(2) r``, Hann spectrum): Campbell's theorem gives
    ``Phi(t) = exp(rho p d int_{-r}^{r} Lambda(t exp(-y^2/r^2)) dy)`` (``p`` the pixel, ``d`` the
    line pitch), and the moments follow from ``Phi`` as in that module. (The earlier
    kurtosis-equivalent density matched the fourth moment only: ``var ln I`` 3.17 against
    2.72 measured at 0.23 equivalent scatterers per pixel per pitch.)

    Parameters
    ----------
    density : float
        Scatterers per µm^3 (> 0; ``inf`` is fully developed speckle).
    cfg : ScannerConfig
        The scanner (``n_pixels``, ``beam_radius``, ``pixel_size``, line pitch).

    Returns
    -------
    (float, float)
        ``E ln(I/<I>)`` and ``var ln I`` (``-gamma`` and ``pi^2/6`` when dense).

    Examples
    --------
    >>> import speckle
    >>> from speckle.studies.phantom._density import slab_log_moments
    >>> cfg = speckle.synthoct_config("reduced")
    >>> round(slab_log_moments(3.18e-3, cfg)[1], 3)  # the reduced config's mean density
    1.692
    """
    if not np.isfinite(density):
        return -np.euler_gamma, np.pi**2 / 6
    lam, area = _slab_lambda(cfg.n_pixels, cfg.beam_radius, cfg.line_pitch)
    k = density * cfg.pixel_size * cfg.line_pitch  # per µm of y, per pixel per pitch
    s2 = k * slab_constants(cfg.beam_radius)["a2_y"] * area
    return moments_of(np.exp(k * lam), s2, area)


def _equivalent(cfg: ScannerConfig) -> float:
    """µm^3 per (equivalent scatterer per pixel per pitch): ``1/(t_eq p d)``."""
    return 1.0 / (slab_constants(cfg.beam_radius)["t_eq"] * cfg.pixel_size * cfg.line_pitch)


def slab_inverse_density(log_variance: float, cfg: ScannerConfig) -> float:
    """``1/rho_eq`` whose slab ``var ln I`` (:func:`slab_log_moments`) is ``log_variance``.

    ``rho_eq = rho t_eq p d`` (the kurtosis-equivalent scatterers per pixel per pitch, a scale
    only). As :func:`speckle.analysis.sparse.sparse_inverse_density`: linear in ``1/rho``
    through ``(0, pi^2/6)`` below the value at ``1/rho_eq = 0.01`` (negative under ``pi^2/6``,
    so that the estimate stays unbiased when dense), the bound
    :data:`~speckle.analysis.sparse.MAX_INVERSE_DENSITY` above its value there; NaN for a
    non-positive or non-finite variance.
    """
    v = float(log_variance)
    if not np.isfinite(v) or v <= 0:
        return np.nan
    to_3d = _equivalent(cfg)

    def gap(x):
        return slab_log_moments(to_3d / x, cfg)[1] - v

    return invert_log_variance(gap, v)


def lateral_variance_factor(cols: np.ndarray, cfg: ScannerConfig) -> float:
    """``E s^2 / var ln I`` of a row's sample variance over the lines ``cols`` (indices).

    Neighbouring lines see overlapping beams: their ``ln I`` are correlated, so the row's own
    mean removes part of the variance, ``E sum (x_i - xbar)^2 = var (n - sum_ij c_ij/n)``.
    ``c(Delta) = Li2(exp(-Delta^2/r^2))/(pi^2/6)``, exact for fully developed speckle (the
    field's correlation ``exp(-Delta^2/(2 r^2))`` between lines ``Delta`` apart; ``cov(ln I_1,
    ln I_2) = Li2(|g|^2)``). 0.987 for the 118 central lines of the reduced configuration
    (measured without the factor: 1.670 +- 0.007 against 1.692 exact, at its mean density).
    """
    cols = np.asarray(cols)
    n = cols.size
    ind = np.zeros(int(cols.max()) + 1)
    ind[cols] = 1.0
    pairs = np.correlate(ind, ind, mode="full")  # pairs at each index lag
    lag = (np.arange(pairs.size) - (ind.size - 1)) * cfg.line_pitch
    corr = special.spence(1 - np.exp(-(lag**2) / cfg.beam_radius**2)) / (np.pi**2 / 6)
    return float((n - np.sum(pairs * corr) / n) / (n - 1))


def layer_variances(
    li: np.ndarray,
    z: np.ndarray,
    segs: list[tuple[int, int]],
    keep: list[np.ndarray],
    cfg: ScannerConfig,
    *,
    rates: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``var ln I`` of each layer's speckle, its delete-one-block replicates and the layers'
    attenuations on the same replicates.

    The row variance minus the covariance of rows :data:`LAG` apart (the shadowing streaks,
    correlated over many rows; speckle is not, beyond the PSF), averaged over the segment's
    rows far enough above the window's floor, divided by :func:`lateral_variance_factor` of the
    lines used (the rows' own means).

    The floor clips the low tail of ``ln I``, where sparse speckle's excess lives; choosing
    rows by their own count of clipped pixels keeps the rows with a short low tail (a bias:
    -0.06 on average over the reduced closed loop's layers with rows of at most 1 % clipped,
    worse with none). Rows are chosen by the layer's fitted mean level instead (its straight
    line through the row means, independent of a row's own tail): the fully developed
    fraction below the clip ``c``, ``1 - exp(-c/<I>)`` with ``ln <I> = E ln I + gamma``, at most
    :data:`MAX_PREDICTED_CLIPPED`. Sparse speckle has more intensities near 0 than that: with
    ``rates`` (per layer, :func:`clip_rates`) the fraction is ``1 - exp(-A c/exp(line))`` with
    the layer's own rate ``A``, which the density needs (:func:`both_rule_variances`); without
    them, fully developed speckle's ``A = exp(-gamma)``: the rows' ``var ln I`` as the
    transitions' row means see it (their ``E ln(I/<I>)``, censored too).

    The replicates drop one of at least ``len(keep)`` lateral blocks, as many as fit blocks of
    :data:`BLOCK_RADII` beam radii (wider than the lines' correlation, a beam radius or two):
    a 16-block jackknife SE is itself uncertain (``t`` with 15 degrees of freedom) and the
    per-block variances of sparse, streaked speckle are heavy-tailed; the challenge's closed
    loop (70 flat patients) had ``var ln I`` pulls of SD 1.21 (89.3 % of 169 within 2 SE) with
    16 blocks, 1.07 (93.5 % of 170) with 32.

    Parameters
    ----------
    li : numpy.ndarray
        ``ln I`` of the fitted rows ``(rows, lines)``.
    z : numpy.ndarray
        The rows' depths (µm).
    segs : list of (int, int)
        Each layer's rows ``a .. b-1`` (indices into ``li``).
    keep : list of numpy.ndarray
        Lines kept by each replicate of the fit's jackknife (their number is the least).
    cfg : ScannerConfig
        The scanner (line pitch, beam radius).
    rates : numpy.ndarray, optional
        Each layer's rate ``A`` of clipped pixels (:func:`clip_rates`); None: fully developed
        speckle's.

    Returns
    -------
    v : numpy.ndarray
        ``(K,)``, NaN where a layer has fewer than 2 usable row pairs.
    v_jk : numpy.ndarray
        ``(blocks, K)``.
    mu_jk : numpy.ndarray
        ``(blocks, K)``: ``-slope/2`` of each layer's row-mean ``ln I`` on the same replicates.
    """

    (out,), mu_jk = _rule_variances(li, z, segs, keep, cfg, [rates])
    return (*out, mu_jk)


def _paired_rows(li: np.ndarray, z: np.ndarray, segs: list[tuple[int, int]], rates) -> np.ndarray:
    """The rows whose ``var ln I`` a row rule uses (bool, ``(rows,)``): a predicted clipped
    fraction of at most :data:`MAX_PREDICTED_CLIPPED` at the layer's rate (``rates`` per layer,
    None: fully developed speckle's), there and :data:`LAG` rows deeper in the same layer."""
    out = np.zeros(li.shape[0], bool)
    for k, (a, b) in enumerate(segs):
        if b - a > LAG:  # a row pair needs LAG + 1 rows
            rate = DENSE_CLIP_RATE if rates is None else rates[k]
            ok = -np.expm1(-rate * _floor_ratio(li, z, a, b)) <= MAX_PREDICTED_CLIPPED
            out[a : b - LAG] = ok[:-LAG] & ok[LAG:]
    return out


def _rule_variances(li, z, segs, keep, cfg, rules) -> tuple[list, np.ndarray]:
    """:func:`layer_variances`'s ``(v, v_jk)`` for each of ``rules`` (per-layer rates, None:
    fully developed speckle's), and its ``mu_jk``. A row's variance (with the row :data:`LAG`
    deeper) does not depend on the other rows chosen: each is computed once, on every
    replicate's lines, and a rule's ``var ln I`` is the mean over its rows."""
    chosen = [_paired_rows(li, z, segs, r) for r in rules]
    rows = np.flatnonzero(np.logical_or.reduce(chosen))  # any rule's rows, ascending
    pairs = li[rows], li[rows + LAG]
    ends = np.searchsorted(rows, segs)  # each layer's span of ``rows``
    picks = [[lo + np.flatnonzero(c[rows[lo:hi]]) for lo, hi in ends] for c in chosen]

    def rule_means(cols, drop=None):
        """Each rule's ``var ln I`` per layer over the lines ``cols`` (all but ``drop``'s)."""
        d, e = pairs
        if drop is not None:
            d = np.concatenate([d[:, : drop.start], d[:, drop.stop :]], axis=1)
            e = np.concatenate([e[:, : drop.start], e[:, drop.stop :]], axis=1)
        d = d - d.mean(axis=1, keepdims=True)
        e = e - e.mean(axis=1, keepdims=True)
        n = len(cols) - 1
        v = (np.sum(d * d, axis=1) + np.sum(e * e, axis=1)) / (2 * n) - np.sum(d * e, axis=1) / n
        factor = lateral_variance_factor(cols, cfg)
        return [[float(np.mean(v[i])) / factor if i.size >= 2 else np.nan for i in pick]
                for pick in picks]  # fmt: skip

    all_cols = np.arange(li.shape[1])
    width = BLOCK_RADII * cfg.beam_radius / cfg.line_pitch
    blocks = max(len(keep), int(all_cols.size // width))
    groups = np.array_split(all_cols, blocks)  # contiguous: a replicate drops a slice
    keep = [np.setdiff1d(all_cols, g) for g in groups]
    full = rule_means(all_cols)
    reps = [rule_means(k, slice(int(g[0]), int(g[-1]) + 1))
            for k, g in zip(keep, groups, strict=True)]  # fmt: skip
    mu_jk = np.array(
        [[-np.polyfit(z[a:b], li[a:b][:, k].mean(axis=1), 1)[0] / 2 for a, b in segs]
         for k in keep]
    )  # fmt: skip
    return [(np.array(f), np.array([rep[r] for rep in reps])) for r, f in enumerate(full)], mu_jk


def _floor_ratio(li: np.ndarray, z: np.ndarray, a: int, b: int) -> np.ndarray:
    """``c/exp(line)`` of the rows ``a .. b-1``: the clip ``c`` over the layer's straight line
    through its row-mean ``ln I`` (independent of a row's own tail)."""
    m = li[a:b].mean(axis=1)
    return np.exp(_CLIP - np.polyval(np.polyfit(z[a:b], m, 1), z[a:b]))


def clip_rates(li: np.ndarray, z: np.ndarray, segs: list[tuple[int, int]]) -> np.ndarray:
    """Each layer's rate ``A`` of clipped pixels (:func:`_clip_rate` over its rows; fully
    developed speckle's :data:`DENSE_CLIP_RATE` for a layer of fewer than 2 rows); ``li``,
    ``z``, ``segs`` as :func:`layer_variances` takes them."""
    out = np.full(len(segs), DENSE_CLIP_RATE)
    for k, (a, b) in enumerate(segs):
        if b - a >= 2:
            clipped = np.sum(li[a:b] < _CLIP - 0.5, axis=1)  # clipped pixels are at ln c - 1
            out[k] = _clip_rate(clipped, li.shape[1] * _floor_ratio(li, z, a, b))
    return out


def both_rule_variances(
    li: np.ndarray,
    z: np.ndarray,
    segs: list[tuple[int, int]],
    keep: list[np.ndarray],
    cfg: ScannerConfig,
    rates: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`layer_variances`'s ``v, v_jk, mu_jk`` (fully developed speckle's rate of clipped
    pixels), then ``v_own, v_own_jk``: ``var ln I`` and its replicates over the rows at each
    layer's own rate (``rates``, :func:`clip_rates`; the same numbers where that is fully developed
    speckle's), which the density needs: the censored low tail lowers ``var ln I`` (2025 patient
    5's sparse layer, 6.4 % of its pixels clipped in rows where fully developed speckle predicts
    at most 1 %, gave a density 11.6 % high, pull +9.8). Each row's variance is computed once
    for both row rules; the arguments as :func:`layer_variances` takes them."""
    (dense, own), mu_jk = _rule_variances(li, z, segs, keep, cfg, [None, rates])
    return (*dense, mu_jk, *own)


def _clip_rate(counts: np.ndarray, exposure: np.ndarray) -> float:
    """The rate ``A`` of a layer's clipped fraction ``1 - exp(-A c/<I>_q)``, ``<I>_q`` from
    its rows' fitted line (``exp(line)``: ``exposure`` is ``n c/exp(line)`` per row, ``n`` the
    lines, ``counts`` each row's clipped pixels): fully developed speckle's ``exp(-gamma)``
    unless the layer's clipped count exceeds that rate's Poisson count by more than 3 SDs,
    then the pooled rate ``sum counts / sum exposure`` (every row a ``1/n`` share of it, so
    that no row is chosen by its own tail). Sparse speckle has more intensities near 0 than
    fully developed speckle (2025 patient 5's sparse layer, 0.0011 per µm^3: 6.4 % of its
    pixels clipped in rows where fully developed speckle predicts at most 1 %)."""
    expected = DENSE_CLIP_RATE * float(np.sum(exposure))
    if float(np.sum(counts)) <= expected + 3.0 * math.sqrt(expected):
        return DENSE_CLIP_RATE
    return float(np.sum(counts)) / float(np.sum(exposure))


def layer_densities(
    v: np.ndarray,
    v_jk: np.ndarray,
    mu: np.ndarray,
    mu_jk: np.ndarray,
    cfg: ScannerConfig,
    *,
    kurtosis_bound: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Each layer's density and energy from its ``var ln I`` and attenuation.

    ``var ln I`` is inverted by :func:`slab_inverse_density` (the slab's exact theory); the
    density is identified where the excess over ``pi^2/6`` exceeds :data:`IDENTIFY` jackknife
    SEs, else NaN with the lower bound of the density whose ``var ln I`` is ``max(v, pi^2/6) +``
    :data:`BOUND_SE` SEs (the excess's one-sided 97.7 % upper limit); ``E = 100 mu/(rho A2)``.
    A layer without ``var ln I`` (NaN: the floor clips its rows) takes ``kurtosis_bound``
    (:func:`kurtosis_density`'s, per layer; NaN: none) as its bound.

    Returns
    -------
    dict
        ``v_se``, ``ident`` (bool), ``rho``, ``rho_se``, ``bound``, ``energy``,
        ``energy_se``, ``energy_bound``, each ``(K,)``, and ``rho_jk`` ``(blocks, K)``
        (per µm^3 and %).
    """
    consts = slab_constants(cfg.beam_radius)
    n_layers, blocks = v.size, v_jk.shape[0]

    def invert(value):
        inv = slab_inverse_density(value, cfg)  # NaN for a non-positive variance
        if not np.isfinite(inv):
            return np.nan
        return 1.0 / inv if inv > 0 else np.inf  # per pixel per pitch (equivalent)

    to_3d = _equivalent(cfg)
    v_se = np.array([_jackknife(v_jk[:, k]) for k in range(n_layers)])
    ident = (v - np.pi**2 / 6) > IDENTIFY * v_se
    rho = np.array([invert(v[k]) * to_3d if ident[k] else np.nan for k in range(n_layers)])
    energy_frac = np.where(ident, mu / (rho * consts["A2"]), np.nan)
    rho_jk = np.array(
        [[invert(v_jk[j, k]) * to_3d if ident[k] else np.nan for k in range(n_layers)]
         for j in range(blocks)]
    )  # fmt: skip
    # rho falls convexly with v (about 1/excess): the SE is half the distance to the density of
    # v - 2 SE, so that |pull| < 2 holds whenever v is within 2 SE (module note on IDENTIFY)
    rho_se = np.array(
        [(invert(v[k] - BOUND_SE * v_se[k]) * to_3d - rho[k]) / BOUND_SE if ident[k] else np.nan
         for k in range(n_layers)]
    )  # fmt: skip
    bound = np.array(
        [np.nan if ident[k] else invert(max(v[k], np.pi**2 / 6) + BOUND_SE * v_se[k]) * to_3d
         for k in range(n_layers)]
    )  # fmt: skip
    if kurtosis_bound is not None:  # no var ln I: the intensity kurtosis's bound
        bound = np.where(np.isnan(v), np.asarray(kurtosis_bound, float), bound)
    e_jk = mu_jk / (rho_jk * consts["A2"])
    energy = 100 * energy_frac
    energy_se = 100 * np.array([_jackknife(e_jk[:, k]) if ident[k] else np.nan
                                for k in range(n_layers)])  # fmt: skip
    energy_bound = np.where(ident, np.nan, 100 * mu / (bound * consts["A2"]))
    return {
        "v_se": v_se, "ident": ident, "rho": rho, "rho_se": rho_se, "rho_jk": rho_jk,
        "bound": bound, "energy": energy, "energy_se": energy_se, "energy_bound": energy_bound,
    }  # fmt: skip


def log_offsets(log_variance, cfg: ScannerConfig, *, kurtosis=None) -> np.ndarray:
    """``E ln(I/<I>)`` of each layer's speckle from its ``var ln I`` (shadowing removed).

    The slab's sparse-speckle theory (:func:`slab_log_moments`
    at the density whose ``var ln I`` is the measured one); ``-gamma`` (fully developed) where
    the variance does not exceed ``pi^2/6`` or is NaN. Sparse speckle's ``E ln I`` lies farther
    below ``ln <I>`` (-1.43 at 0.3 times the 2025 configuration's mean density, -0.70 at its
    mean, -0.58 dense): two layers' mean ``ln I`` differ from their mean intensities' by
    different offsets, which the transition between them must use. Where ``var ln I`` is NaN
    (the floor leaves the layer no rows for it) and its intensity excess ``kurtosis``
    (:func:`kurtosis_density`) is positive, at the density ``1/(V kurtosis)``
    (:func:`kurtosis_volume`): the 2025 configuration's flat loop (seeds 0-9) placed its
    boundaries next to such sparse, dim layers 2-3 SE deep with ``-gamma`` (session 46).
    """
    out = []
    v_all = np.atleast_1d(np.asarray(log_variance, float))
    kap = np.full(v_all.size, np.nan) if kurtosis is None else np.asarray(kurtosis, float)
    for v, k in zip(v_all, kap, strict=True):
        if not np.isfinite(v) and k > 0:  # no var ln I: the kurtosis's density
            out.append(slab_log_moments(1.0 / (kurtosis_volume(cfg) * k), cfg)[0])
            continue
        inv = slab_inverse_density(v, cfg) if np.isfinite(v) and v > np.pi**2 / 6 else 0.0
        if not np.isfinite(inv) or inv <= 0:
            out.append(-np.euler_gamma)
        else:
            out.append(slab_log_moments(_equivalent(cfg) / inv, cfg)[0])
    return np.array(out)


def log_offset_se(log_variance, log_variance_se, cfg: ScannerConfig) -> np.ndarray:
    """SE of :func:`log_offsets` from ``var ln I``'s SE: half the change of the offset between
    ``v - SE`` and ``v + SE`` (the central difference; one-sided where ``v - SE`` falls below
    ``pi^2/6``, where the offset stays ``-gamma``); 0 where ``v`` or its SE is NaN (the offset
    is then ``-gamma``, fully developed, by assumption).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.studies.phantom._density import log_offset_se
    >>> cfg = speckle.synthoct_config("2025")
    >>> log_offset_se([np.pi**2 / 6 - 1, np.nan], [0.1, 0.1], cfg)  # dense, unknown
    array([0., 0.])
    """
    v = np.atleast_1d(np.asarray(log_variance, float))
    se = np.nan_to_num(np.atleast_1d(np.asarray(log_variance_se, float)))
    out = (log_offsets(v + se, cfg) - log_offsets(v - se, cfg)) / 2
    return np.where(np.isfinite(v), np.abs(out), 0.0)


def _psf_area(cfg: ScannerConfig) -> float:
    """``int |h|^2`` of the scanner's depth PSF times its lateral Gaussian (µm^2)."""
    hann = _scan.hann_spectrum(cfg.n_pixels)
    r, p = cfg.beam_radius, cfg.pixel_size
    return float(np.sum(depth_intensity_psf(hann)) / 8 * p * r * math.sqrt(math.pi / 2))


def lines_per_block(radii: float, cfg: ScannerConfig) -> int:
    """Lines in a lateral jackknife block ``radii`` beam radii wide (at least one)."""
    return max(1, math.ceil(radii * cfg.beam_radius / cfg.line_pitch))


def kurtosis_volume(cfg: ScannerConfig) -> float:
    """µm^3 whose scatterer count is the inverse of one pixel's intensity excess kurtosis.

    Campbell's theorem for Poisson scatterers of amplitude ``a(u, x, y)`` and random phases:
    ``E I^2 = 2 (E I)^2 + rho int a^4``, so ``E I^2/(E I)^2 - 2 = 1/(rho V)``, ``V = (int
    a^2)^2 / int a^4``, separable: the depth PSF's ``(int |h|^2)^2/int |h|^4`` (pixels, times
    ``p``), the lines' ``exp(-x^2/r^2)`` (``r sqrt(pi)``) and the slab's ``t_eq``
    (:func:`slab_constants`). 3615 µm^3 in the reduced box (6 µm pixels, ``r`` = 10 µm).
    """
    u, w = depth_psf(cfg.n_pixels, 16)
    du = u[1] - u[0]
    along = float(np.sum(w) * du) ** 2 / float(np.sum(w**2) * du)
    r = cfg.beam_radius
    return along * cfg.pixel_size * r * math.sqrt(math.pi) * slab_constants(r)["t_eq"]


def kurtosis_density(
    intensity: np.ndarray, cfg: ScannerConfig, *, block_lines: int
) -> tuple[float, float, float]:
    """A layer's density from its pixels' intensity kurtosis, which the window's floor hardly
    touches: where ``var ln I`` has no rows (the floor clips its low tail), ``I^2`` lives in
    the bright tail.

    ``kappa = <I'^2>/<I'>^2/(1 + s) - 2 = 1/(rho V)`` (:func:`kurtosis_volume`; Campbell's
    theorem, exact for Poisson scatterers): ``I' = I/T(z)``, ``T`` the exponential through the
    rows' mean intensities (their attenuation), ``s = <I'_z I'_{z+LAG}>/<I'>^2 - 1`` the
    shadowing streaks' variance (rows :data:`LAG` apart share a line's shadow, not its speckle),
    which multiplies ``E I^2`` by ``1 + s``. Clipped pixels enter at their value in
    ``intensity`` (under the clip level ``c``: they change ``<I'^2>`` by less than ``f c^2``,
    ``f`` the clipped fraction). The SE is the delete-one-block jackknife over blocks of
    ``block_lines`` lines.

    Parameters
    ----------
    intensity : numpy.ndarray
        ``(rows, lines)`` intensities (any unit), NaN outside the layer's pixels; rows one
        pixel apart.
    cfg : ScannerConfig
        The scanner (pixel, beam radius, spectrum).
    block_lines : int
        Lines per jackknife block (>= 1; at least 2 blocks with pixels are needed).

    Returns
    -------
    (float, float, float)
        ``kappa``, its SE, and ``rho``'s lower bound ``1/(V (kappa + BOUND_SE SE))``
        (scatterers per µm^3; NaN where ``kappa + BOUND_SE SE <= 0``: ``kappa`` cannot be
        negative, so the estimate failed); all NaN without two blocks or :data:`LAG` + 2 rows.

    Examples
    --------
    >>> import numpy as np, speckle
    >>> from speckle.studies.phantom._density import kurtosis_density
    >>> cfg = speckle.synthoct_config("reduced")
    >>> i = np.random.default_rng(0).exponential(size=(40, 96))  # fully developed
    >>> kappa, se, bound = kurtosis_density(i, cfg, block_lines=4)
    >>> abs(kappa) < 3 * se
    True
    """
    i = np.asarray(intensity, float)
    if i.ndim != 2 or int(block_lines) < 1:
        raise ValueError("intensity must be (rows, lines) and block_lines >= 1")
    has = np.flatnonzero(np.isfinite(i).any(axis=0))
    groups = has.size // int(block_lines)
    nan = (np.nan, np.nan, np.nan)
    if groups < 2 or np.count_nonzero(np.isfinite(i).any(axis=1)) < LAG + 2:
        return nan

    def kappa(cols):
        sub = i[:, cols]
        ok = np.isfinite(sub)
        n_r = ok.sum(axis=1)
        rows = np.flatnonzero(n_r > 0)
        if rows.size < LAG + 2:
            return np.nan
        mean_r = np.nansum(sub[rows], axis=1) / n_r[rows]
        if np.any(mean_r <= 0):
            return np.nan
        trend = np.exp(np.polyval(np.polyfit(rows, np.log(mean_r), 1, w=np.sqrt(n_r[rows])),
                                  np.arange(i.shape[0])))  # fmt: skip
        v = sub / trend[:, None]
        m1 = np.nanmean(v)
        pair = v[:-LAG] * v[LAG:]
        if not np.isfinite(pair).any():
            return np.nan
        streak = np.nanmean(pair) / m1**2 - 1.0
        return float(np.nanmean(v**2) / m1**2 / (1.0 + streak) - 2.0)

    blocks = np.array_split(has, groups)
    k = kappa(has)
    k_jk = np.array([kappa(np.setdiff1d(has, b)) for b in blocks])
    if not (np.isfinite(k) and np.all(np.isfinite(k_jk))):
        return nan
    se = _jackknife(k_jk)
    top = k + BOUND_SE * se
    # kappa >= 0 for any density: below 0 by more than BOUND_SE SEs the estimate has failed
    # (its SE too small: sparse speckle's I^2 is heavy-tailed), and gives no bound
    bound = 1.0 / (kurtosis_volume(cfg) * top) if top > 0 else math.nan
    return k, se, bound
