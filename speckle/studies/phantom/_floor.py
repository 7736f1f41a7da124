"""Layers under the window's floor, between or below the fitted ones (private).

The scanner's 51 dB window clips a layer dimmer than its floor: most of its pixels sit at
level 0, its rows are left out of the row-mean profile (:func:`_above_floor`), and without
this module the fitted layers above and below met somewhere inside
the gap (session 52: a middle layer 1e-4 times as bright as its neighbours, 45-66 % of its
pixels clipped, gave boundaries 29 and 54 µm off and a middle ``rho E`` 30 times its
neighbours'). A gap in the fitted rows is not always such a layer: a faint layer's bottom may
reach the floor above a brighter one (the 2025 configuration's sparse layers), one layer
fading out. The two differ where the rows enter the gap.

**Entering the gap.** A layer's row-mean ``ln I`` falls linearly with depth (its shadowing),
so its last row above a floor gap lies on the line of the rows before it; a boundary into a
layer below the floor instead drops it by the PSF's step: the row just below the boundary holds
only the tail of the bright layer's PSF (the failure map's phantom: -0.56, -0.98 and -3.28
neper below the line over the gap's last three rows). Measured over
every internal floor gap of the closed loops (2025 flat patient 2, ``layers=(1, 3)`` patients
2, 4 and 5; none in the challenge's seeds 0-79 nor the 2025 ``visible=4`` seeds 0-15), where no
true boundary lies within 3 rows: the last row within -0.57 to +0.83 of the line. A gap whose
last row above it is more than :data:`DARK_DROP` below the line of the :data:`LINE_ROWS` rows
before its transition, and whose first row below it more than :data:`RISE_STEP` below the line
of the rows after (the step up into the next layer; a dim layer whose own rows come back above
the floor has none), each line one layer's (:data:`LINE_SCATTER`), is a layer under the floor
(:func:`dark_gaps`): the segmentation must cut there
(:func:`speckle.studies.phantom._count.segment`'s ``cuts``), and the fit inserts a layer between
the rows above and below.

**Its brightness.** Its pixels are censored, not lost: a pixel at level 0 has ``I < c`` (the
window's clip). Fully developed speckle is exponential in ``I``; a row ``r`` of the gap holds
the layer's own mean ``theta`` plus its bright neighbours' PSF tails ``a_r`` (the transition
model of their fitted lines: two independent fully developed fields sum to an exponential of
the summed mean), so its pixels give the censored likelihood

    L(theta) = sum_r [n_cr ln(1 - exp(-c/(theta + a_r))) - n_ur ln(theta + a_r)
                      - sum_u I_i/(theta + a_r)],

``n_cr`` clipped pixels, ``n_ur`` unclipped of intensities ``I_i`` (:func:`censored_mean`, its
SE by the fit's jackknife over lateral blocks), over the rows whose tails are at most
:data:`TAIL_SHARE` of ``theta`` (without the tails, a 40 dB darker layer's rows 3 and 4 pixels
from a boundary gave 1.5 and 1.2 times the inner rows' censored mean at the 2025
configuration; with them, a layer of 8 pixels is identified). ``theta`` is then the layer's
mean intensity under the window, from which
:func:`~speckle.studies.phantom._window.window_and_brightness` takes ``rho E/100`` as for any
layer without a measurable slope (its shadow on the layers below is ``A2 rho E/100`` times its
thickness: from the first pass's brightness). Where every pixel of those rows is clipped,
``rho E`` is not identified and
``rho_e_bound`` gives its upper bound: the smaller of 95 % one-sided from its rows whose
every pixel is clipped (:func:`all_clipped_bound`) and the censored mean of all its rows, its
neighbours' tails kept (they only add intensity), plus 2 SE.

**Its boundaries.** Each from the rows on its bright side (the transition model of
:mod:`speckle.studies.phantom._shapes` with the floor layer's mean ``ln I`` on the other side:
:func:`floor_boundary`).

Not done: a layer of about 4 pixels (every row's tails above its own mean: a bound only), the
floor layer's attenuation (its slope is not seen; ``A2 rho E/100``, the scanner's relation, is
taken), its density (the censored speckle cannot tell sparse from dim), shapes
(a fit with a floor layer is flat) and inclusions in a floor layer.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy import optimize

from ...synthoct import _scan
from ._density import _CLIP, BLOCKS, _jackknife

__all__ = [
    "BOUND_LEVEL",
    "DARK_DROP",
    "LINE_ROWS",
    "LINE_SCATTER",
    "MAX_CLIPPED",
    "RISE_STEP",
    "SPARSE_CLIPPED",
    "TAIL_ROWS",
    "TAIL_SHARE",
    "all_clipped_bound",
    "censored_mean",
    "dark_gaps",
    "floor_boundary",
]

#: Rows with more clipped (level 0) pixels than this fraction are below the floor, unless
#: their mean intensity sets the clip below fully developed speckle's :data:`SPARSE_CLIPPED`.
MAX_CLIPPED = 0.1
#: Fully developed speckle's clipped fraction (``1 - exp(-c/<I>)``, ``<I>`` the row's mean
#: intensity) below which a row is above the floor however many of its pixels are clipped
#: (sparse speckle's empty pixels: a fully developed row there clips 5 +- 0.7 % of 964 lines,
#: never 10 %).
SPARSE_CLIPPED = 0.05
#: Drop (nepers) of the last row above a floor gap below the line of the rows before it that
#: marks a boundary into a layer under the floor (module docstring: the loops' gaps lie within
#: -0.57 to +0.83, a boundary's step at -3.3).
DARK_DROP = 1.5
#: Rows of the line that the last row above a floor gap is compared with.
LINE_ROWS = 10
#: Step (nepers) of the first row below a floor gap under the line of the rows after it that
#: marks the boundary out of a layer under the floor (40 dB darker middle layers: -1.48 at the
#: 2025 configuration's seed 3, -3.02 at the reduced box's seed 10; a dim layer whose rows come
#: back above the floor, 2025 patient 3: -0.12).
RISE_STEP = DARK_DROP / 2
#: Largest residual (nepers) of those rows about their line for the comparison to be made:
#: rows that hold a boundary's transition are not one layer's line (reduced box, a middle
#: layer 1e-3 times as bright whose first 4 rows are above the floor: residual 2.95 through
#: the step, which put its last row 2.1 neper low; one layer's rows: 0.51 in the reduced
#: box's seed 10, whose 7 lines per block make the row means noisy).
LINE_SCATTER = 2 * DARK_DROP / 3
#: Rows (pixels) from the box's bottom within which a floor layer below the last fitted one
#: gives no brightness: they see the surface through the periodic PSF (not in the tails).
TAIL_ROWS = 5
#: Largest share of a floor layer's own mean intensity that its neighbours' PSF tails may add
#: to a row whose pixels its brightness takes (the tails subtracted).
TAIL_SHARE = 1.0
#: ``ln <I>`` that stands for a layer under the floor in the tails' transition model.
_NO_LEVEL = -60.0
#: One-sided level of the upper bound of an entirely clipped layer's brightness.
BOUND_LEVEL = 0.05
_NEPER_DB = 10.0 / math.log(10.0)  # dB per neper of intensity


# --- the window's floor: the pixels' ln I and the rows above it ---------------------------


def _log_intensity(levels: np.ndarray) -> np.ndarray:
    """``ln I - ln I_max`` of each pixel (bin midpoints; clipped pixels ``ln c - 1``)."""
    step = _scan.DYNAMIC_RANGE / _scan.LEVELS
    db = (levels.astype(np.float64) + 0.5) * step - _scan.DYNAMIC_RANGE
    out = db / _NEPER_DB
    clip = (step - _scan.DYNAMIC_RANGE) / _NEPER_DB
    out[levels == 0] = clip - 1.0
    return out


def _above_floor(levels: np.ndarray) -> np.ndarray:
    """Rows of ``levels`` (pixels, lines) above the window's floor: at most :data:`MAX_CLIPPED`
    of their pixels clipped; or, in each of :data:`BLOCKS` lateral blocks of lines, at most
    that many or a block mean intensity over which fully developed speckle would clip at most
    :data:`SPARSE_CLIPPED` of them. The clipped pixels are then a sparse layer's empty ones,
    spread over the lines, whose ``ln c - 1`` is the mean ``ln I`` below the clip of a density
    flat near 0 (2025 patient 4 of ``layers=(1, 3)``: a layer of 0.0012 scatterers per µm^3
    under a dim one clips 12-20 % of its pixels where its mean is 150-200 times the clip, and
    was left out whole), not a floor that holds some of the lines (a boundary sweeping into
    it, or the rows that flattening brings from beyond the scan)."""
    clipped, intensity = levels == 0, _intensity(levels)
    sparse = np.ones(levels.shape[0], bool)
    for g in np.array_split(np.arange(levels.shape[1]), min(BLOCKS, levels.shape[1])):
        fully_developed = -np.expm1(-math.exp(_CLIP) / intensity[:, g].mean(axis=1))
        sparse &= (clipped[:, g].mean(axis=1) <= MAX_CLIPPED) | (fully_developed <= SPARSE_CLIPPED)
    return (clipped.mean(axis=1) <= MAX_CLIPPED) | sparse


def _intensity(levels: np.ndarray) -> np.ndarray:
    """``I/I_max`` of each pixel (bin midpoints; clipped pixels at half the clip level ``c``:
    an intensity density flat below ``c``, as :func:`_log_intensity`'s ``ln c - 1``)."""
    out = np.exp(_log_intensity(levels))
    step = _scan.DYNAMIC_RANGE / _scan.LEVELS
    out[levels == 0] = 0.5 * math.exp((step - _scan.DYNAMIC_RANGE) / _NEPER_DB)
    return out


# --- layers under the floor --------------------------------------------------------------


def dark_gaps(
    m: np.ndarray, runs: list[tuple[int, int]], n_pixels: int, *, gap: int
) -> list[tuple[int, int]]:
    """The floor gaps entered and left by a boundary: ``[(lo, hi)]``, rows ``lo .. hi - 1``
    under the floor below the run ending at ``lo`` (``hi`` the next run's first row, or
    ``n_pixels - gap - 1`` below the last run), where row ``lo - 1``'s mean ``ln I`` (``m``,
    every row) lies more than :data:`DARK_DROP` below the line of the :data:`LINE_ROWS` rows
    ending ``gap + 1`` rows above it, and row ``hi``'s more than :data:`RISE_STEP` below the
    line of the rows from ``gap + 1`` rows below it (at least 4 rows in each line's run, none
    farther than :data:`LINE_SCATTER` from it): the PSF's steps of a layer's two boundaries
    (a dim layer whose rows come back above the floor below the gap has no step up there)."""

    def step(q, row):  # row's mean ln I minus the line of rows q there (NaN: too few rows,
        # or rows that are not one layer's line: a boundary's transition among them)
        if q.size < 4:
            return math.nan
        slope, icpt = np.polyfit(q, m[q], 1)
        if np.max(np.abs(m[q] - (slope * q + icpt))) > LINE_SCATTER:
            return math.nan
        return m[row] - (slope * row + icpt)

    out = []
    for (a, b), after in itertools.zip_longest(runs, runs[1:]):
        hi = n_pixels - gap - 1 if after is None else after[0]
        if (
            hi <= b
            or not step(np.arange(max(a, b - gap - 1 - LINE_ROWS), b - gap - 1), b - 1) < -DARK_DROP
        ):
            continue
        if after is not None:  # and leaving it into a brighter layer: the step up
            q = np.arange(hi + gap + 1, min(after[1], hi + gap + 1 + LINE_ROWS))
            if not step(q, hi) < -RISE_STEP:
                continue
        out.append((int(b), int(hi)))
    return out


def censored_mean(intensity: np.ndarray, clipped: np.ndarray, tail=None) -> float:
    """Maximum-likelihood mean of exponential intensities (fully developed speckle) left-censored
    at the window's clip ``c = exp(_CLIP)`` (``I/I_max``): ``intensity`` ``(rows, lines)``
    (clipped entries ignored), ``clipped`` where a pixel is at level 0, ``tail`` (optional,
    per row) a known mean intensity added to each row's (the bright neighbours' PSF tails: the
    sum of two independent fully developed fields is exponential with the summed mean). NaN
    where every pixel is clipped (the likelihood grows as ``theta -> 0``)."""
    c = math.exp(_CLIP)
    intensity, clipped = np.atleast_2d(intensity), np.atleast_2d(clipped)
    n_c = np.count_nonzero(clipped, axis=1).astype(float)
    n_u = clipped.shape[1] - n_c
    total = np.where(clipped, 0.0, intensity).sum(axis=1)
    if not n_u.any():
        return math.nan
    if tail is None and not n_c.any():
        return float(total.sum() / n_u.sum())
    extra = np.zeros(n_c.size) if tail is None else np.asarray(tail, float)

    def minus_log_l(u):  # u = ln(theta/c)
        mean = c * math.exp(u) + extra
        return -float(np.sum(n_c * np.log(-np.expm1(-c / mean)) - n_u * np.log(mean)
                             - total / mean))  # fmt: skip

    res = optimize.minimize_scalar(minus_log_l, bounds=(-12.0, 12.0), method="bounded",
                                   options={"xatol": 1e-6})  # fmt: skip
    return c * math.exp(float(res.x))


def all_clipped_bound(n_cells: float) -> float:
    """Upper bound (``I/I_max``) of the mean intensity of exponential speckle whose
    ``n_cells`` independent cells are all below the clip: ``(1 - exp(-c/theta))^n_cells =``
    :data:`BOUND_LEVEL`."""
    c = math.exp(_CLIP)
    return c / -math.log1p(-(BOUND_LEVEL ** (1.0 / n_cells)))


def floor_brightness(
    intensity: np.ndarray, clipped: np.ndarray, inner: np.ndarray, keep: list[np.ndarray],
    *, cells: float, tail=None,
) -> dict[str, object]:  # fmt: skip
    """The floor layer's mean intensity from its gap's pixels ``(rows, lines)``: ``theta`` and
    its replicates over the jackknife's line sets ``keep`` (:func:`censored_mean`, the rows'
    known ``tail`` intensity subtracted) from the ``inner`` rows (a boolean mask: NaN where
    none, or every pixel of the fit or a replicate clipped); ``bound`` (NaN where ``theta`` is
    identified): the smaller of two upper bounds, the censored mean of all its rows with the
    tails kept (they only add intensity) plus 2 SE, and :func:`all_clipped_bound` of ``cells``
    cells per row over its rows whose every pixel is clipped."""
    tail = np.zeros(intensity.shape[0]) if tail is None else np.asarray(tail, float)

    def with_jk(sel, t):
        i, cl = intensity[sel], clipped[sel]
        est = censored_mean(i, cl, t)
        jk = np.array([censored_mean(i[:, k], cl[:, k], t) for k in keep])
        return est, jk

    theta, theta_jk = math.nan, np.full(len(keep), math.nan)
    if inner.any():
        theta, theta_jk = with_jk(inner, tail[inner])
    bound = math.nan
    if not (np.isfinite(theta) and np.all(np.isfinite(theta_jk))):
        theta, theta_jk = math.nan, np.full(len(keep), math.nan)
        bounds = []
        est, jk = with_jk(slice(None), None)
        if np.isfinite(est) and np.all(np.isfinite(jk)):
            bounds.append(est + 2 * _jackknife(jk))
        dark = int(np.count_nonzero(clipped.all(axis=1)))
        if dark:
            bounds.append(all_clipped_bound(dark * cells))
        bound = min(bounds, default=math.nan)
    return {"theta": theta, "theta_jk": theta_jk, "bound": bound}


def floor_boundary(mm, z, line, dark, offsets, model, p, *, below: bool, mixing=None) -> float:
    """A floor layer's boundary (µm) from the row means ``mm`` at depths ``z`` (µm) on its
    bright side: the transition between the bright layer's ``line`` (slope, intercept of its
    mean ``ln I``) and the floor layer's mean ``ln I`` ``dark`` (flat), ``offsets`` the two
    layers' ``E ln(I/<I>)`` in depth order (and ``mixing``, the mixed rows' own speckle, as
    the fit's boundaries take it); ``below``: the floor layer lies below the rows."""
    s, i = line
    lines = [(s, i), (0.0, dark)] if below else [(0.0, dark), (s, i)]
    (s1, i1), (s2, i2) = lines
    lo, hi = (z[0] - p, z[-1] + 2 * p) if below else (z[0] - 2 * p, z[-1] + p)

    def misfit(t):
        return float(np.sum((model.log_mean(z, t, s1, i1, s2, i2, p, offsets, mixing) - mm) ** 2))

    res = optimize.minimize_scalar(misfit, bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-3})  # fmt: skip
    return float(res.x)


def with_floor_layers(values, after: list[int], fill=np.nan, axis: int = -1) -> np.ndarray:
    """``values`` of the fitted row layers with a ``fill`` entry inserted after each row layer
    in ``after`` (a floor layer's position; ``len(values)`` for one below the last)."""
    out = np.asarray(values)
    for shift, k in enumerate(sorted(after)):
        out = np.insert(out, k + 1 + shift, fill, axis=axis)
    return out


def floor_positions(segs, cuts, terminal: bool) -> list[int]:
    """The row layers after which a floor layer lies: each segment ending at a forced cut
    (between it and the next segment), and the last one if a floor gap lies below the last
    run (``terminal``)."""
    after = [
        k for k, ((_, b), (a, _)) in enumerate(itertools.pairwise(segs))
        if any(b <= c <= a for c in cuts)
    ]  # fmt: skip
    if terminal:
        after.append(len(segs) - 1)
    return after


def floor_layers(
    dark, segs, cuts, m_all, m_all_jk, intensity, clipped, est, rep, offsets, keep, model, p,
    *, gap: int, cells: float, mixing=None,
) -> dict[str, object]:  # fmt: skip
    """The floor layers of the gaps ``dark`` (:func:`dark_gaps`) among the row layers ``segs``:
    their positions (``after``, :func:`floor_positions`), the boundaries of every layer, row
    and floor in depth order, on the fit and each jackknife replicate (``tops``, ``tops_jk``),
    and the floor layers' brightness (``floor``: ``{layer: {"z", "theta", "theta_jk",
    "bound"}}``, :func:`floor_brightness` of their pixels' ``intensity`` and ``clipped``,
    ``(n_pixels, lines)``, over the gap's rows whose neighbours' PSF tails are at most
    :data:`TAIL_SHARE` of it, ``z`` their depths in µm). A floor layer's boundaries come from
    the rows on its bright sides (every row's mean ``ln I`` ``m_all`` and its replicates
    ``m_all_jk``: :func:`floor_boundary`, its level first from all its rows, then from the
    rows its brightness takes), the others as fitted (``est``: the row layers' lines and tops,
    ``rep`` per replicate)."""
    after = floor_positions(segs, cuts, len(dark) > len(cuts))  # the last below the last run
    gaps = dict(zip(after, dark, strict=True))
    c_dark = -np.euler_gamma  # fully developed speckle's E ln(I/<I>)
    n_pixels = intensity.shape[0]

    def brightness(k, inner, tail=None):
        lo, hi = gaps[k]
        return floor_brightness(intensity[lo:hi], clipped[lo:hi], inner, keep, cells=cells,
                                tail=tail)  # fmt: skip

    def tails(k, tops_):
        """The mean intensity of floor layer ``k``'s gap rows from its bright neighbours' PSF
        tails: the transition model of their fitted lines (``ln <I> = line - offset``)."""
        z, f = np.arange(*gaps[k]) * p, full[k]
        (sa, ia), ca = est[0][k], offsets[k]
        if f + 1 < tops_.size:  # a row layer below it
            (sb, ib), cb = est[0][k + 1], offsets[k + 1]
            ln = model.log_mean_layers(z, [tops_[f], tops_[f + 1]], [sa, 0.0, sb],
                                       [ia - ca, _NO_LEVEL, ib - cb], p)  # fmt: skip
        else:
            ln = model.log_mean_layers(z, [tops_[f]], [sa, 0.0], [ia - ca, _NO_LEVEL], p)
        return np.exp(ln)

    def tops_of(mm, fits, tops, bright, j=None):
        def level(f):  # the floor layer's mean ln I (its bound where not identified)
            b = bright[f]
            theta = b["theta"] if j is None else b["theta_jk"][j]
            return math.log(theta if np.isfinite(theta) else b["bound"]) + c_dark

        def boundary(idx, k, f, below):
            pair = (offsets[k], c_dark) if below else (c_dark, offsets[k])
            return floor_boundary(mm[idx], idx * p, fits[k], level(f), pair, model, p,
                                  below=below, mixing=mixing)  # fmt: skip

        out = []
        for k in range(len(segs)):
            if k - 1 in gaps:  # the floor layer above it: its bottom from this layer's rows
                lo, hi = gaps[k - 1]
                out.append(boundary(np.arange(hi, hi + gap + 3), k, k - 1, below=False))
            else:
                out.append(tops[k])
            if k in gaps:  # the floor layer below it
                lo, hi = gaps[k]
                out.append(boundary(np.arange(lo - gap - 3, lo), k, k, below=True))
        return out

    def all_tops(bright):
        return np.array(tops_of(m_all, *est, bright)), np.array(
            [tops_of(m_all_jk[j], *rep[j], bright, j=j) for j in range(len(rep))]
        )

    full = {k: k + 1 + i for i, k in enumerate(after)}  # a floor layer's index among all
    # the boundaries with each floor layer's level from all its rows, then its brightness
    # over the rows whose neighbours' PSF tails (subtracted) are at most TAIL_SHARE of it,
    # then the boundaries again
    tops, _ = all_tops({k: brightness(k, np.ones(hi - lo, bool)) for k, (lo, hi) in gaps.items()})
    floor, bright = {}, {}
    for k, (lo, hi) in gaps.items():
        z, tail = np.arange(lo, hi) * p, tails(k, tops)
        # below the last layer, the rows that see the surface through the periodic PSF: out
        rows = z <= n_pixels * p - TAIL_ROWS * p if full[k] + 1 == tops.size else z >= 0
        first = censored_mean(intensity[lo:hi][rows], clipped[lo:hi][rows], tail[rows])
        inner = rows & (tail <= TAIL_SHARE * first) if np.isfinite(first) else rows
        bright[k] = brightness(k, inner, tail)
        floor[full[k]] = {"z": z[inner] if inner.any() else z, **bright[k]}
    tops, tops_jk = all_tops(bright)
    return {"after": after, "tops": tops, "tops_jk": tops_jk, "floor": floor}
