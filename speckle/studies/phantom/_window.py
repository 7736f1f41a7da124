"""The 51 dB window's top and the brightness of the phantom fit's layers (private).

The scanner's 8-bit window puts its top at the image's maximum, so the fitted levels are
``ln I`` relative to an unknown ``wt`` (nepers re ``|A| = 1``). Every layer whose decay is
measured (a slope significant at :data:`~speckle.studies.phantom._density.SIGNIFICANCE` SE)
predicts its own absolute mean ``ln I`` from ``rho E/100 = mu/A2`` and so places ``wt``; the
layers without a measurable slope then take ``rho E`` from their rows' mean intensity under
that window (:func:`window_and_brightness`), and a top layer cut by the window's floor from the
mean intensity of its own rows (:func:`cut_top_rho_e`). How the layers' estimates of ``wt`` are
combined: :func:`window_weights`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, special

from ...synthoct.files import ScannerConfig
from ._density import SIGNIFICANCE, _jackknife, _psf_area
from ._slab import slab_constants

__all__ = ["cut_top_rho_e", "window_and_brightness", "window_weights"]


def window_and_brightness(
    m: np.ndarray,
    m_jk: np.ndarray,
    z: np.ndarray,
    segs: list[tuple[int, int]],
    fitted: dict[str, np.ndarray],
    cfg: ScannerConfig,
    *,
    cut_top: dict[str, np.ndarray] | None = None,
) -> dict[str, object]:
    """The 51 dB window's top and ``rho E/100`` of every layer.

    The window's top (nepers re ``|A| = 1``) is the predicted absolute ``E ln I`` of each
    layer with a significant slope (``ln(rho_e a2_y int|h|^2) - 2 C(z) + E ln(I/<I>)``) minus
    the observed level, the layers' estimates weighted by the inverse of their variances and a
    layer that disagrees with the others left out (:func:`window_weights`); ``rho E/100`` is
    ``mu/A2`` where the slope is significant, else the layer's brightness under that window.
    ``E ln(I/<I>)`` is each layer's own (``fitted["offsets"]``,
    :func:`~speckle.studies.phantom._density.log_offsets` of its ``var ln I``, as in the
    transition model), not ``-gamma``: a sparse layer's mean ``ln I`` lies farther below
    ``ln <I>`` (-1.03 at 0.0024 per µm^3 at the 2025 configuration), and with ``-gamma`` its
    brightness came out ``exp(-1.03 + 0.58) = 0.64`` times the truth. Every jackknife replicate
    repeats the chain (its slopes, boundaries, window); the offsets' SEs
    (``fitted["offsets_se"]``, from ``var ln I``'s) are added in quadrature, to the window's
    top through its weights and to each brightness directly.

    A top layer cut by the window's floor (``cut_top``: most of its rows had more than
    ``MAX_CLIPPED`` of their pixels clipped, so that its fitted rows are a few rows at its
    bottom, inside the next boundary's transition, whose slope is not the layer's) takes its
    ``rho E/100`` from the mean *intensity* of its own rows instead (:func:`cut_top_rho_e`),
    its attenuation ``mu = A2 rho E/100`` and the window's top with it (the top layer's shadow
    lowers every deeper layer's level by ``2 mu (t_1 - t_0)``); where no deeper layer has a
    significant slope to place the window, ``mu`` stays the fitted slope's, as for any layer.

    Parameters
    ----------
    m, m_jk : numpy.ndarray
        Row-mean ``ln I`` ``(rows,)`` and its replicates ``(blocks, rows)``.
    z : numpy.ndarray
        The rows' depths (µm).
    segs : list of (int, int)
        Each layer's rows.
    fitted : dict
        ``mu``, ``mu_se``, ``mu_jk``, ``tops``, ``tops_jk``, ``offsets`` and ``offsets_se``
        (each layer's ``E ln(I/<I>)`` and its SE, :func:`log_offsets`); ``floor`` (optional):
        the layers under the window's floor, ``{layer: {"z", "theta", "theta_jk", "bound"}}``
        (:func:`~speckle.studies.phantom._floor.floor_layers`; their ``segs`` entry None),
        whose ``rho E/100`` is their censored mean intensity's.
    cfg : ScannerConfig
        The scanner's configuration.
    cut_top : dict, optional
        The cut top layer's own rows: ``z`` (µm), ``intensity`` (their mean ``I/I_max`` over
        the lines) and ``intensity_jk`` (``(blocks, rows)``, on the jackknife's lines).

    Returns
    -------
    dict
        ``wt``, ``wt_se`` (nepers), ``wt_jk``, ``rho_e``, ``rho_e_se`` (per µm^3) and ``mu``,
        ``mu_se``, ``mu_jk`` (1/µm; the cut top layer's from its ``rho_e``, the others as
        ``fitted``), ``rho_e_bound`` (a floor layer's upper bound where its ``theta`` is NaN).
    """
    consts = slab_constants(cfg.beam_radius)
    mu, mu_se, mu_jk = (np.array(fitted[k], float) for k in ("mu", "mu_se", "mu_jk"))
    tops, tops_jk = fitted["tops"], fitted["tops_jk"]
    offsets, offsets_se = fitted["offsets"], fitted["offsets_se"]
    n_layers, blocks = mu.size, m_jk.shape[0]
    psf_area = _psf_area(cfg)
    floor = fitted.get("floor", {})  # layers under the window's floor (_floor.py): no rows
    slope_ok = (mu > SIGNIFICANCE * mu_se) & np.array([s_ is not None for s_ in segs])
    if cut_top is not None:
        slope_ok[0] = False  # its few fitted rows' slope is the transition's

    def cum_shadow(zz, k, mu_, tops_):
        c = sum(mu_[j] * (tops_[j + 1] - tops_[j]) for j in range(k))
        return c + mu_[k] * (zz - tops_[k])

    # layers that place the window: a significant, positive slope
    used = [k for k in range(n_layers) if slope_ok[k] and mu[k] > 0]

    def layer_windows(mm, mu_, tops_):
        """Each placing layer's window top: its predicted absolute mean ``ln I`` minus the
        observed (NaN where a replicate's ``mu`` is not positive)."""
        out = np.full(len(used), np.nan)
        for i, k in enumerate(used):
            if mu_[k] > 0:
                a, b = segs[k]
                pred = (np.log(mu_[k] / consts["A2"] * consts["a2_y"] * psf_area)
                        - 2 * cum_shadow(z[a:b], k, mu_, tops_) + offsets[k])  # fmt: skip
                out[i] = float(np.mean(pred - mm[a:b]))
        return out

    # each layer's estimate on the fit and on every replicate, without a cut top layer's
    # shadow (which moves every estimate alike: added in chain below); the weights from them
    mu_w, mu_jk_w = mu.copy(), mu_jk.copy()
    if cut_top is not None:
        mu_w[0], mu_jk_w[:, 0] = 0.0, 0.0
    est = layer_windows(m, mu_w, tops)
    est_jk = [layer_windows(m_jk[j], mu_jk_w[j], tops_jk[j]) for j in range(blocks)]
    weights = window_weights(est, est_jk, offsets_se[used])
    share = weights / weights.sum() if weights.sum() > 0 else weights

    def combined(e):
        """The weighted mean of the layers' estimates ``e`` (NaN where none has weight)."""
        w = np.where(np.isfinite(e), weights, 0.0)
        return float(np.sum(w * np.nan_to_num(e)) / w.sum()) if w.sum() > 0 else np.nan

    def brightness(k, ii, mu_, tops_, wt_):
        """``rho E/100`` of layer ``k`` from its rows' mean intensity ``ii`` under the window's
        top ``wt_`` (a floor layer's: ``ii`` its censored mean, over its inner rows)."""
        if segs[k] is None:
            zz = floor[k]["z"]
            ii = np.full(zz.size, ii)
        else:
            a, b = segs[k]
            zz, ii = z[a:b], ii[a:b]
        unshadowed = ii * np.exp(wt_ + 2 * cum_shadow(zz, k, mu_, tops_))
        return float(np.mean(unshadowed)) / (consts["a2_y"] * psf_area)

    def chain(wt0, mu_, tops_, intensity):
        """The window's top from ``wt0``, the layers' without a cut top layer's shadow, and
        that layer's ``mu`` from its brightness (``mu_`` updated in place)."""
        if cut_top is None or not np.isfinite(wt0):  # no deeper layer places it: mu stays
            return wt0
        mu_[0] = consts["A2"] * cut_top_rho_e(
            intensity, cut_top["z"], tops_[1] - tops_[0], wt0, cfg, psf_area=psf_area
        )
        return wt0 - 2 * mu_[0] * (tops_[1] - tops_[0])

    top_i, top_i_jk = (None, [None] * blocks) if cut_top is None else (
        cut_top["intensity"], cut_top["intensity_jk"])  # fmt: skip
    wt = chain(combined(est), mu, tops, top_i)
    wt_jk = np.array([chain(combined(est_jk[j]), mu_jk[j], tops_jk[j], top_i_jk[j])
                      for j in range(blocks)])  # fmt: skip
    # the offsets' own uncertainty (var ln I's), through the placing layers' weights
    wt_var_offsets = float(np.sum((share * offsets_se[used]) ** 2))
    wt_se = math.hypot(_jackknife(wt_jk), math.sqrt(wt_var_offsets))

    # rho E/100 per layer: from mu where the slope is significant, else from the brightness
    rho_e = mu / consts["A2"]
    rho_e_se = mu_se / consts["A2"]
    if cut_top is not None and np.isfinite(wt):
        rho_e_se[0] = math.hypot(_jackknife(np.log(mu_jk[:, 0])), math.sqrt(wt_var_offsets))
        rho_e_se[0] *= rho_e[0]
        mu_se[0] = consts["A2"] * rho_e_se[0]
    rho_e_bound = np.full(n_layers, np.nan)
    for k in floor:  # no slope: from the brightness below, where a window is placed
        rho_e[k], rho_e_se[k] = np.nan, np.nan
    for k in range(n_layers):
        if slope_ok[k] or not np.isfinite(wt) or (k == 0 and cut_top is not None):
            continue
        ii, ii_jk = (fitted["intensity"], fitted["intensity_jk"]) if k not in floor else (
            floor[k]["theta"], floor[k]["theta_jk"])  # fmt: skip
        rho_e[k] = brightness(k, ii, mu, tops, wt)
        reps = [brightness(k, ii_jk[j], mu_jk[j], tops_jk[j], wt_jk[j]) for j in range(blocks)]
        log_se = _jackknife(np.log(np.array(reps)))
        rho_e_se[k] = math.sqrt(log_se**2 + wt_var_offsets) * rho_e[k]
        if k in floor and np.isfinite(floor[k]["bound"]):  # not identified: its upper bound
            rho_e_bound[k] = brightness(k, floor[k]["bound"], mu, tops, wt)
    return {"wt": wt, "wt_se": wt_se, "wt_jk": wt_jk, "rho_e": rho_e, "rho_e_se": rho_e_se,
            "mu": mu, "mu_se": mu_se, "mu_jk": mu_jk, "rho_e_bound": rho_e_bound}  # fmt: skip


def window_weights(estimates, replicates, offsets_se) -> np.ndarray:
    """Weights of the layers' estimates of the window's top: inverse variance, 0 for outliers.

    Each layer that places the window predicts its top from its own ``mu`` (and the ``mu`` of
    the layers above, through their shadow). A layer's variance is its estimate's
    delete-one-block jackknife plus its offset's ``E ln(I/<I>)`` variance, so a layer whose
    slope is barely significant (``ln mu`` uncertain by tens of per cent) no longer counts as
    much as a well-measured one of as many rows. While more than two layers remain, the one
    whose estimate differs most from the others' weighted mean, by more than
    :data:`~speckle.studies.phantom._density.SIGNIFICANCE` SE of the difference (its jackknife
    and both sides' offsets' SEs), is left out: its slope is not its brightness's (selected by
    its own noise at the significance threshold, or a floor's or a neighbour's rows in it, as
    in challenge patient 32, whose bottom layer's ``mu`` came out 21 times the truth at 3.6 SE
    and put the window 6 dB high).

    Parameters
    ----------
    estimates : array_like
        Each layer's estimate (nepers), ``(layers,)``; NaN where it has none.
    replicates : array_like
        The estimates of every jackknife replicate, ``(blocks, layers)``.
    offsets_se : array_like
        Each layer's ``E ln(I/<I>)`` SE (nepers), ``(layers,)``.

    Returns
    -------
    numpy.ndarray
        Weights ``(layers,)``, 0 for a layer left out (or without an estimate in every
        replicate); all 0 when no layer has one.

    Examples
    --------
    Three layers, the third 1.4 neper off at a variance like the others':

    >>> import numpy as np
    >>> from speckle.studies.phantom._window import window_weights
    >>> rng = np.random.default_rng(0)
    >>> est = np.array([0.0, 0.02, 1.4])
    >>> reps = est + 0.02 * rng.standard_normal((16, 3))
    >>> w = window_weights(est, reps, np.full(3, 0.01))
    >>> bool(w[2] == 0 and w[0] > 0 and w[1] > 0)
    True
    """
    est = np.asarray(estimates, float)
    weights = np.zeros(est.size)
    if est.size == 0:  # no layer places the window
        return weights
    reps = np.asarray(replicates, float).reshape(-1, est.size)
    osd = np.asarray(offsets_se, float)
    g = reps.shape[0]
    keep = np.isfinite(est) & np.all(np.isfinite(reps), axis=0)
    if not keep.any():
        return weights
    var = (g - 1) / g * np.sum((reps - reps.mean(0)) ** 2, axis=0) + osd**2
    weights[keep] = 1.0 / np.maximum(var[keep], 1e-12)
    while np.count_nonzero(weights) > 2:
        worst, worst_z = -1, SIGNIFICANCE
        for k in np.flatnonzero(weights):
            w = weights.copy()
            w[k] = 0.0
            w /= w.sum()
            diff = reps[:, k] - np.nan_to_num(reps) @ w
            var_d = (g - 1) / g * np.sum((diff - diff.mean()) ** 2) + osd[k] ** 2
            var_d += float(np.sum((w * osd) ** 2))
            z = abs(est[k] - float(np.nan_to_num(est) @ w)) / math.sqrt(max(var_d, 1e-24))
            if z > worst_z:
                worst, worst_z = k, z
        if worst < 0:
            break
        weights[worst] = 0.0
    return weights


def cut_top_rho_e(
    intensity: np.ndarray,
    z: np.ndarray,
    thickness: float,
    window_top: float,
    cfg: ScannerConfig,
    *,
    psf_area: float | None = None,
) -> float:
    """``rho E/100`` of a top layer from the mean intensity of its rows (per µm^3).

    The layer (from ``z = 0`` to ``thickness``) shadows itself and every layer below it: with
    ``mu = A2 rho E/100`` and ``wt0`` the window's top (nepers) as the deeper layers place it
    without this layer's shadow, the window's top is ``wt0 - 2 mu thickness`` and the layer's
    mean intensity ``<I>(z) = rho E/100 a2_y int|h|^2 exp(2 mu (thickness - z) - wt0)``.
    Summed over the rows, ``ln(rho E/100) + ln sum_r exp(2 A2 rho E/100 (thickness - z_r))``
    rises monotonically from minus infinity, so the measured sum has one root (Brent's method
    in ``ln rho E``). The mean of ``I`` needs no speckle statistics (``E ln(I/<I>)`` of sparse
    speckle is far below ``-gamma`` and not identified where the layer is cut by the floor).

    Parameters
    ----------
    intensity : numpy.ndarray
        The rows' mean ``I/I_max`` over the lines (clipped pixels at half the clip level: the
        intensity density flat below it, as ``ln I``'s ``ln c - 1``).
    z : numpy.ndarray
        The rows' depths (µm), in ``[0, thickness)``.
    thickness : float
        The layer's thickness (µm, its fitted bottom boundary).
    window_top : float
        ``wt0``, the window's top without this layer's shadow (nepers re ``|A| = 1``).
    cfg : ScannerConfig
        The scanner's configuration.
    psf_area : float, optional
        ``int |h|^2`` of the scanner's PSF (µm^2; computed from ``cfg`` when not given).

    Returns
    -------
    float
        ``rho E/100`` (per µm^3); NaN when the rows hold no intensity.

    Examples
    --------
    A model layer's rows (``rho E/100 = 2e-6``, 150 µm thick, ``wt0 = 3``), inverted back:

    >>> import numpy as np
    >>> import speckle
    >>> from speckle.studies.phantom._density import _psf_area
    >>> from speckle.studies.phantom._window import cut_top_rho_e
    >>> from speckle.studies.phantom._slab import slab_constants
    >>> cfg = speckle.synthoct_config("2025")
    >>> consts = slab_constants(cfg.beam_radius)
    >>> z = np.arange(3, 60) * cfg.pixel_size
    >>> mu = consts["A2"] * 2e-6
    >>> i = 2e-6 * consts["a2_y"] * _psf_area(cfg) * np.exp(2 * mu * (150.0 - z) - 3.0)
    >>> round(cut_top_rho_e(i, z, 150.0, 3.0, cfg) / 2e-6, 9)
    1.0
    """
    consts = slab_constants(cfg.beam_radius)
    area = _psf_area(cfg) if psf_area is None else psf_area
    total = float(np.sum(intensity))
    if not total > 0:
        return np.nan
    target = math.log(total) - math.log(consts["a2_y"] * area) + window_top
    depth = thickness - np.asarray(z, float)

    def gap(u):
        x = math.exp(u)
        return u + special.logsumexp(2 * consts["A2"] * x * depth) - target

    # gap(target) >= ln(rows) >= 0 and gap(target - ln(rows) - 50) < 0
    low = target - math.log(depth.size) - 50.0
    return math.exp(optimize.brentq(gap, low, target, xtol=1e-12, rtol=1e-14))
