"""Tilted and curved boundaries of the phantom fit (private): per-block positions, BIC, flatten.

Each boundary ``k`` of the flat fit (:func:`speckle.fit_phantom`'s first pass) is located again
in each of ``blocks`` lateral blocks of the central lines: the block's row-mean ``ln I`` in a
window around it (half-way to its neighbours) is fitted by the two layers' lines (slopes
``-2 mu`` of the flat fit, levels free per block) mixed through the depth PSF at the trial
position ``tau`` (:class:`TransitionModel`); ``tau`` on a grid of a quarter pixel, levels
from the rows more than 3 pixels from ``tau``, the least squares over every row of the window.
The blocks' misfits are summed along ``tau_b = a``, ``a + b x_b`` and
``a + b x_b + c (x_b^2 - X^2/12)`` (``x_b`` the blocks' mean ``x``) and minimised jointly
(Nelder-Mead, compiled with its objective in :mod:`._shape_kernels`: scipy's steps one for
one, the same fits bitwise on the published scans and 2025 patients 0-3, about 30 times
faster than scipy's; the tilted and curved fits start from the simpler shape's fit and from
the least-squares polynomial through the blocks' own best positions, the better end kept); the
shape is the one of least ``BIC = -chi^2 + d ln n`` (``n`` the rows used, ``d`` the terms
beyond ``a``, ``chi^2`` the Wald statistic of ``b`` or ``(b, c)``) among those allowed, the
covariance (and the SEs) from the delete-one-block jackknife of the joint fit.
The transition model mixes the layers' mean intensities ``exp(level - c)``, ``c = E ln(I/<I>)``
of the layer's sparse speckle (the flat fit's ``log_offset``:
:func:`~speckle.studies.phantom._density.log_offsets`).
Two neighbouring boundaries of the flat fit merge into one tilted or curved boundary (a ramp:
a steep boundary's sweep across the lines, which the flat fit cuts in two with a layer
between) where that boundary, located between the layers above and below, sweeps at least half
the layer between and fits the blocks at least as well as the two located boundaries with the
layer between them (one level per block more).
Where a shaped boundary's block finds its least misfit at its window's end, or the joint fit
places it at that end (its position may lie beyond: a steep boundary's outer blocks, its depth
sweeping past the window half-way to a neighbour; such a block finds a spurious least misfit
inside its window, which the joint fit follows to the window's end), the boundary is located
once more in windows moved along the located shape: the
window edge at the flat fit's depth ``z'`` moves to ``z' + delta(x_b, z')``, ``delta`` as in
the flattening below with this boundary's shape only, so that an edge half-way between two
boundaries stays half-way between them (within the flat fit's rows). A boundary whose block its
window still cuts then is located once more with every boundary's located shape in ``delta``
(the neighbours' whose depth is located within a pixel; the others flat): neighbours that sweep
with it (challenge patient 73) no longer leave its window's edge in their own transition.
A boundary whose mean ``ln I`` level step is within 3 SEs but whose speckle contrast (the
rows' ``ln var ln I`` in each block) steps by more than 3 (the SEs from the spread over the
blocks) is located by both statistics: each block's misfit table is the transition model's
over its least misfit per row plus the contrast's change point (a level above, one below)
over its own, and the flattening takes that boundary's located depth (the flat fit's can be
far: a dense dim layer over a sparse bright one, whose mean ``ln I`` hardly steps). A boundary
whose mean ``ln I`` steps but locates it to worse than a pixel (its depth's jackknife SE) is
located by both statistics too where the contrast steps by more than 3 SEs, and the more
precise of the two kept (2025 patient 7's sparse bright layer over a dense dim one: the
blocks' own positions by the mean scatter over 120 µm, its depth's SE 40 µm).

With any boundary not flat, the levels are flattened: line ``x``'s row at depth
``z' + delta(x, z')`` moves to ``z'``, ``delta`` linear in ``z'`` between the boundaries'
offsets ``delta_k(x) = b (x - <x>) + c (x^2 - <x^2>)`` (0 at the surface, constant below the last
boundary), rows taken whole (nearest row: no interpolation, which would average speckle and bias
``var ln I``); rows from beyond the scan are clipped. The flat fit of the flattened levels
gives the layers; its tops are the boundaries' depths at the central lines' mean offset, so
``a = top - b <x> - c (<x^2> - X^2/12)``, and ``a``'s SE adds ``b``'s and ``c``'s in
quadrature (times ``<x>`` and ``<x^2> - X^2/12``) to the flattened fit's.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import xarray as xr

from ...conventions import attrs
from ...synthoct.files import ScannerConfig
from ._mixing import REACH, TAPER, mixed_rows
from ._shape_kernels import argsort_table, nelder_mead
from ._slab import depth_psf

__all__ = [
    "BOUNDARY_BLOCKS",
    "SHAPE_DEGREE",
    "TransitionModel",
    "fit_shapes",
    "flat_shapes",
]

#: Polynomial degree of each boundary shape.
SHAPE_DEGREE = {"flat": 0, "tilted": 1, "curved": 2}
#: Rounds of locating the boundaries and refitting the flattened levels (at most).
ITERATIONS = 3
#: Lateral blocks in which each boundary is located.
BOUNDARY_BLOCKS = 16
#: Samples per pixel of the transition model's PSF.
_SAMPLES = 64
#: Nelder-Mead's tolerance on a boundary's coefficients, as displacements (pixels) at the
#: blocks' edge (:func:`_joint`).
_XATOL = 1e-9
#: Rows (pixels) from the trial position beyond which a row sets a layer's level.
_LEVEL_ROWS = 3
#: SEs of a boundary's steps: a mean ``ln I`` level step within this many and a ``ln var ln
#: I`` step beyond it locate the boundary by its contrast too (as the flat fit's
#: ``SIGNIFICANCE``).
_CONTRAST_SE = 3.0
#: Jackknife SE (pixels) of a boundary's depth located by the mean ``ln I`` beyond which a
#: boundary whose contrast steps (beyond :data:`_CONTRAST_SE`) is located by both statistics
#: too, the more precise kept.
_PRECISE_PIXELS = 1.0
_CRITERION = (
    "least BIC = n ln(RSS/n) + (d + 1) ln n of the boundary's positions in 16 lateral blocks, "
    "d = 0 (flat), 1 (tilted), 2 (curved)"
)


class TransitionModel:
    """Mean intensity of rows across a boundary: the depth PSF's share of each layer.

    Row ``q`` (depth ``z_q``) collects scatterers at offsets ``u = z - z_q`` (pixels) with the
    intensity PSF's weight ``w(u)`` (:func:`speckle.depth_intensity_psf`, symmetric). A layer
    whose row-mean intensity is ``exp(i + s z)`` (``s`` per pixel here) has scatterers of mean
    intensity ``exp(i + s z)/M(s)``, ``M(s) = int w(u) e^{s u} du``, so the rows near a boundary
    at ``t`` hold

        exp(i1 + s1 z_q) G(t - z_q; s1) + exp(i2 + s2 z_q) (1 - G(t - z_q; s2)),
        G(v; s) = int_{u < v} w(u) e^{s u} du / M(s),

    (the upper layer's scatterers above ``t``, the lower's below). ``G(v; 0)`` is the PSF's
    cumulative intensity. Neglecting the tilt ``e^{s u}`` shifts the boundary by ``s sigma^2``
    (``sigma^2 = 0.336`` pixel^2 of the Hann PSF: 0.1 pixel at ``s = 0.3`` per pixel). The
    PSF is summed directly (:func:`speckle.depth_intensity_psf`'s formula) on a midpoint grid
    of 1/64 pixel and its cumulative sums are trapezoidal (a plain cumulative sum of
    ``depth_intensity_psf``'s 8 samples per pixel counts each sample whole: ``G`` 1/16 pixel
    early, which placed every boundary 0.06 pixel high).
    """

    def __init__(self, n_pixels: int):
        # the main lobe and 15 side lobes each way, on a midpoint grid of 1/SAMPLES pixel
        self.u, self.w = depth_psf(n_pixels, _SAMPLES)
        self._tables = {}  # G(u; s) on the grid, per slope s (a fit uses a few slopes)

    def cdf(self, v, s: float = 0.0):
        """``G(v; s)``: ``v`` offsets (pixels), ``s`` the layer's slope of ``ln I`` per pixel."""
        return np.interp(v, self.u, self._table(s), left=0.0, right=1.0)

    def _table(self, s: float) -> np.ndarray:
        """``G(u; s)`` on the PSF's grid :attr:`u`, computed once per slope."""
        table = self._tables.get(float(s))
        if table is None:
            tilted = self.w * np.exp(s * self.u - abs(s) * self.u[-1])  # scaled: no overflow
            c = np.cumsum(tilted) - 0.5 * tilted
            if len(self._tables) >= 256:  # a shared model (:func:`_transition_model`)
                self._tables.clear()
            table = self._tables[float(s)] = c / tilted.sum()
        return table

    def _cdf_within(self, v, within, s: float) -> np.ndarray:
        """:meth:`cdf` looked up only at ``v[within]`` (``within``: ``v`` inside the PSF's
        grid), 0 and 1 elsewhere as :meth:`cdf` gives them: the same values, the lookup of the
        rows far from the boundary (most of a block's window) skipped."""
        out = (v > self.u[-1]).astype(float)
        out[within] = np.interp(v[within], self.u, self._table(s), left=0.0, right=1.0)
        return out

    def log_mean_layers(self, z, tops, slopes, levels, p, offsets=None, mixing=None):
        """Rows' mean ``ln I`` across several boundaries ``tops`` (µm, rising) between layers
        whose mean ``ln I`` is ``levels + slopes z`` (``slopes`` per µm) and whose
        ``E ln(I/<I>)`` is ``offsets`` (``log_offset``; None: all equal). Each layer's
        mean intensity is ``exp(level + slope z - offset)``; a mixed row's ``E ln(I/<I>)`` is
        the exact one of its two nearest layers' speckle with ``mixing``
        (:class:`~speckle.studies.phantom._mixing.MixedRows`, within its ``REACH`` of a
        boundary; the layers' densities from ``offsets``, so not without them), else the
        layers' offsets weighted by their shares of its mean intensity (exact far from a
        boundary)."""
        edges = [None, *tops, None]
        z = np.asarray(z, float)
        off = np.zeros(len(slopes)) if offsets is None else np.asarray(offsets, float)
        logs = np.array([s * z + i - c for s, i, c in zip(slopes, levels, off, strict=True)])
        top = logs.max(axis=0)  # factored out: no overflow
        total = np.zeros(z.shape)
        weighted = np.zeros(z.shape)
        for j, s in enumerate(slopes):
            above = 1.0 if edges[j + 1] is None else self.cdf((edges[j + 1] - z) / p, s * p)
            below = 0.0 if edges[j] is None else self.cdf((edges[j] - z) / p, s * p)
            share = np.exp(logs[j] - top) * (above - below)
            total = total + share
            weighted = weighted + off[j] * share
        out = top + np.log(total) + weighted / total
        if mixing is None or offsets is None or not len(tops):  # the mixing needs densities
            return out
        # the nearest boundary's two layers, exactly (_mixing.py), blended into the weighted
        # offset over the last TAPER pixels of its reach (no step in the misfit there)
        out = np.array(out, float)
        v = np.array(np.broadcast_arrays(*[(t - z) / p for t in tops], out))[:-1]
        nearest = np.argmin(np.abs(v), axis=0)
        for j in range(len(tops)):
            sel = (nearest == j) & (np.abs(v[j]) < REACH)
            if sel.any():
                x = np.broadcast_to(logs[j + 1] - logs[j], out.shape)[sel]
                mixed = mixing.offset(v[j][sel], x, off[j], off[j + 1])
                plain = np.broadcast_to(weighted / total, out.shape)[sel]
                w = np.clip((REACH - np.abs(v[j][sel])) / TAPER, 0.0, 1.0)
                out[sel] = out[sel] + w * (mixed - plain)
        return out

    def log_mean(self, z, t, s1, i1, s2, i2, p, offsets=None, mixing=None):
        """Rows' mean ``ln I`` (class docstring) at depths ``z`` (µm) for a boundary at ``t``
        (µm), layers ``i + s z`` (``s`` per µm), pixel ``p`` (µm), the layers' ``E ln(I/<I>)``
        ``offsets`` and ``mixing`` (:meth:`log_mean_layers`)."""
        return self.log_mean_layers(z, [t], [s1, s2], [i1, i2], p, offsets, mixing)


@functools.lru_cache(maxsize=4)
def _transition_model(n_pixels: int) -> TransitionModel:
    """The :class:`TransitionModel` of ``n_pixels``, built once (0.04 s at 975 pixels) and shared
    by the fit's passes (read only, but for its tables' cache)."""
    return TransitionModel(n_pixels)


def _shape_variables(ds, shape, tilt, tilt_se, curv, curv_se, criterion):
    def var(values, quantity, long_name):
        return ("layer",), np.asarray(values), attrs(quantity, long_name)

    return ds.assign(
        top_tilt=var(tilt, "dimensionless", "tilt b of the upper boundary (um per um)"),
        top_tilt_se=var(tilt_se, "dimensionless", "standard error of top_tilt"),
        top_curvature=var(curv, "curvature", "curvature c of the upper boundary"),
        top_curvature_se=var(curv_se, "curvature", "standard error of top_curvature"),
        shape=var(np.asarray(shape, dtype=object), "label", "shape of the upper boundary"),
    ).assign_attrs(shape_criterion=criterion)


def flat_shapes(ds: xr.Dataset) -> xr.Dataset:
    """The shape variables of flat boundaries (tilt and curvature 0, their SEs NaN)."""
    k = ds.sizes["layer"]
    nan = np.full(k, np.nan)
    return _shape_variables(ds, ["flat"] * k, np.zeros(k), nan, np.zeros(k), nan, _CRITERION)


def _blocks_rss(mbs, z, taus, s1, s2, p, model, offsets=None, mixing=None):
    """Least-squares misfit of blocks' row-mean profiles ``mbs`` (blocks x rows ``z``, the
    same rows for every block) for each trial boundary position in ``taus`` (blocks x taus;
    inf where a layer has fewer than 2 level rows).

    Each value is :meth:`TransitionModel.log_mean`'s least squares at that position, bit for
    bit (the same operations on the same numbers): the rows' offsets from each position, the
    PSF's shares (looked up only within the PSF's grid, 0 and 1 beyond as
    :meth:`~TransitionModel.cdf` gives them) and the mixed rows' table positions are computed
    once for the blocks; the levels, the layers' lines and the predictions of the rows beyond
    the PSF once per group of positions with the same level rows (a row enters or leaves them
    every fourth position), only the rows within the PSF or mixed at each position. 2025
    patient 1's 208 block tables, the mixed rows' columns cached: 5.2-5.5 s block by block
    through ``log_mean``, 1.3 s so (session 46).
    """
    above = z < taus[:, None] - _LEVEL_ROWS * p  # (taus, rows)
    below = z > taus[:, None] + _LEVEL_ROWS * p
    n1, n2 = above.sum(axis=1), below.sum(axis=1)
    ok = (n1 >= 2) & (n2 >= 2)
    out = np.full((len(mbs), taus.size), np.inf)
    if not ok.any():
        return out
    above, below, n1, n2 = above[ok], below[ok], n1[ok], n2[ok]
    v = (taus[ok, None] - z) / p  # the boundary's offset below each row (pixels)
    within = (v >= model.u[0]) & (v <= model.u[-1])
    g1 = model._cdf_within(v, within, s1 * p)  # the upper layer's share
    g2 = 1.0 - model._cdf_within(v, within, s2 * p)  # the lower layer's
    c1, c2 = (0.0, 0.0) if offsets is None else np.asarray(offsets, float)
    mixed_rows = mixing is not None and offsets is not None
    sel = (np.abs(v) < REACH) if mixed_rows else np.zeros(v.shape, bool)  # the mixed rows
    # the rows' levels change only where a row enters or leaves a layer's level rows (every
    # fourth trial position): the levels, their lines and the PSF-free shares per group
    new = np.concatenate([[True], (n1[1:] != n1[:-1]) | (n2[1:] != n2[:-1])])
    group, rep = np.cumsum(new) - 1, np.flatnonzero(new)
    # rows beyond the PSF (the shares exactly 1 and 0: the same prediction at each of the
    # group's positions, from the group's) and the rows within it or mixed (each its own)
    own = within | sel
    own_t, own_r = np.nonzero(own)
    at_own = group[own_t] * z.size + own_r  # in the groups' (flattened) arrays
    own_at = np.flatnonzero(own)
    # each row's prediction in the groups' below-the-PSF ones followed by the above-the-PSF
    far = np.where(v > model.u[-1], rep.size * z.size, 0) + group[:, None] * z.size
    far += np.arange(z.size)
    g1, g2 = g1[own], g2[own]
    mixed = sel[own]
    at_mixed = at_own[mixed]
    if mixed_rows:
        near = v[sel]
        at = mixing.v_index(near)
        w = np.clip((REACH - np.abs(near)) / TAPER, 0.0, 1.0)
    above, below, n1, n2 = above[rep], below[rep], n1[rep], n2[rep]
    for b, mb in enumerate(mbs):
        i1 = np.where(above, mb - s1 * z, 0.0).sum(axis=1) / n1  # the levels' means
        i2 = np.where(below, mb - s2 * z, 0.0).sum(axis=1) / n2
        log1 = s1 * z + i1[:, None] - c1
        log2 = s2 * z + i2[:, None] - c2
        top = np.maximum(log1, log2)  # factored out: no overflow
        e1, e2 = np.exp(log1 - top), np.exp(log2 - top)
        pred = np.concatenate([_predict(top, e1, e2, g, 1.0 - g, c1, c2)[0].ravel()
                               for g in (0.0, 1.0)]).take(far)  # fmt: skip
        mine, plain = _predict(top.take(at_own), e1.take(at_own), e2.take(at_own), g1, g2, c1,
                               c2)  # fmt: skip
        if mixed_rows:
            x = log2.take(at_mixed) - log1.take(at_mixed)
            mine[mixed] = mine[mixed] + w * (mixing.offset_at(at, x, c1, c2) - plain[mixed])
        pred.ravel()[own_at] = mine
        out[b, ok] = np.sum(np.square(np.subtract(mb, pred, out=pred), out=pred), axis=1)
    return out


def _contrast_rss(lv, z, taus):
    """Change-point misfit of one block's row ``ln var ln I`` ``lv`` (rows at depths ``z``,
    ascending) for each trial boundary position in ``taus``: a constant level above and one
    below (the rows' means), the squares summed over every row; inf where a side has fewer
    than 2 rows."""
    out = np.full(taus.size, np.inf)
    c1, c2 = np.cumsum(lv), np.cumsum(lv**2)
    n = lv.size
    k = np.searchsorted(z, taus)  # rows above: 0..k-1
    ok = (k >= 2) & (k <= n - 2)
    k = k[ok]
    sa, qa = c1[k - 1], c2[k - 1]
    sb, qb = c1[-1] - sa, c2[-1] - qa
    out[ok] = qa - sa**2 / k + qb - sb**2 / (n - k)
    return out


def _predict(top, e1, e2, g1, g2, c1, c2):
    """:meth:`TransitionModel.log_mean_layers`'s mean ``ln I`` of rows (one boundary, no mixed
    rows) from ``top`` (the larger layer line), ``e = exp(line - top)``, the PSF's shares ``g``
    of the layers and their offsets ``c``; and the weighted offset (the same operations)."""
    share1, share2 = e1 * g1, e2 * g2
    total = share1 + share2
    plain = (0.0 + c1 * share1 + c2 * share2) / total
    return top + np.log(total) + plain, plain


def _split_rss(mb, zs, t1, t2, slopes, p, model, offsets=None, mixing=None):
    """Least-squares misfit, summed over the blocks' row means ``mb`` (at depths ``zs``, per
    block), of two
    boundaries at ``t1[b] < t2[b]`` (per block) with a layer between them (the three layers'
    ``slopes``, levels free per block from the rows more than :data:`_LEVEL_ROWS` pixels from a
    boundary); inf where a layer has fewer than 2 such rows."""
    total = 0.0
    for row, z, a, b in zip(mb, zs, t1, t2, strict=True):
        edges = [-np.inf, a, b, np.inf]
        masks = [(z > edges[j] + _LEVEL_ROWS * p) & (z < edges[j + 1] - _LEVEL_ROWS * p)
                 for j in range(3)]  # fmt: skip
        if min(int(mk.sum()) for mk in masks) < 2:
            return np.inf
        levels = [float(np.mean(row[mk] - s * z[mk])) for mk, s in zip(masks, slopes, strict=True)]
        pred = model.log_mean_layers(z, [a, b], slopes, levels, p, offsets, mixing)
        total += float(np.sum((row - pred) ** 2))
    return total


def _joint(rss, taus, basis, start, steps):
    """Coefficients minimising ``sum_b rss_b(basis_b . theta)`` (rss interpolated on ``taus``),
    Nelder-Mead from ``start`` (initial simplex ``start + steps``); and the minimum.

    The search is scipy's Nelder-Mead (non-adaptive, its default limits of ``200 n``
    iterations and evaluations) compiled with the misfit (:func:`._shape_kernels.nelder_mead`:
    the same steps and order of rounding, so the same end; 0.14-0.19 ms a search against
    scipy's 4.1-5.7 ms, session 46).

    The search runs on ``theta / steps`` (each term's displacement at the blocks' edge, in
    pixels for the ``steps`` of :func:`_boundary_shape`: Nelder-Mead's moves are unchanged by
    the scaling) and stops when the simplex spans less than :data:`_XATOL` of them (1e-9
    pixel: the same fits as the earlier 1e-9 µm on ``a`` and 1e-9 on ``b``, ``c``, within
    1e-5 of their SEs on the published scans and 2025 patients; a looser 1e-6 pixel saves
    only a tenth of the time and moves the end of this search on a piecewise-linear function
    by up to 0.005 SE, enough to flip a flattened row)."""
    finite = np.isfinite(rss)
    big = 10 * float(np.max(rss[finite])) if finite.any() else 1.0
    table = np.where(finite, rss, big)

    step = taus[1] - taus[0]
    last = taus.size - 1
    rows = np.arange(table.shape[0])
    padded = np.pad(table, ((0, 0), (0, 1)), constant_values=big)
    start = np.asarray(start, float)
    scale = np.asarray(steps[: start.size], float)
    shift = (basis[:, : start.size] * scale) / step  # u = shift . phi - taus[0] / step
    origin = taus[0] / step
    flat, first = padded.ravel(), rows * padded.shape[1]  # padded[rows, i] = flat[first + i]
    phi0 = start / scale
    simplex = np.vstack([phi0, phi0 + np.eye(start.size)])
    n = start.size  # scipy's defaults: 200 iterations and evaluations per coefficient
    phi, fun, _ = nelder_mead(np.ascontiguousarray(shift), origin, flat, first, last, big, simplex,
                              _XATOL, np.inf, 200 * n, 200 * n, argsort_table(n + 1))  # fmt: skip
    return phi * scale, float(fun)


def _boundary_shape(rss, taus, xb, x_max, shapes, p, n_rows):
    """Shape, coefficients ``(a, b, c)`` and their jackknife SEs of one boundary; and the least
    joint misfit over the shapes tried."""
    basis = np.column_stack([np.ones_like(xb), xb, xb**2 - x_max**2 / 12])
    half = x_max / 2
    steps = np.array([p, p / half, p / half**2])

    def chain(table, base):
        """Every allowed shape's fit and misfit from the blocks' misfits ``table``: the flat
        one from the best common position; the tilted and curved ones from two starts, the
        simpler shape's fit and the least-squares polynomial through the blocks' own best
        positions (a steep boundary's flat fit sits at the window's edge, a start from which
        Nelder-Mead does not reach it), the better end kept."""
        flat = taus[int(np.argmin(np.sum(np.where(np.isfinite(table), table, 1e9), axis=0)))]
        finite = np.isfinite(table).any(axis=1)
        own = taus[np.argmin(np.where(np.isfinite(table), table, np.inf)[finite], axis=1)]

        def best_of(d, nested):
            through = np.linalg.lstsq(base[finite, :d], own, rcond=None)[0]
            tries = [_joint(table, taus, base, start, steps) for start in (nested, through)]
            return min(tries, key=lambda fit: fit[1])

        fits, misfit = {}, {}
        fits["flat"], misfit["flat"] = _joint(table, taus, base, [flat], steps)
        if "tilted" in shapes or "curved" in shapes:
            fits["tilted"], misfit["tilted"] = best_of(2, [fits["flat"][0], 0.0])
        if "curved" in shapes:
            fits["curved"], misfit["curved"] = best_of(3, [*fits["tilted"], 0.0])
        return fits, misfit

    fits, misfit = chain(rss, basis)
    g = xb.size
    # the delete-one-block jackknife repeats the whole chain (both starts: a replicate may
    # end in another local minimum, which the spread must show)
    replicas = [chain(rss[np.arange(g) != b], basis[np.arange(g) != b])[0] for b in range(g)]
    cov, bic = {}, {"flat": 0.0}
    for shape in shapes:
        d = SHAPE_DEGREE[shape] + 1
        reps = np.array([rep[shape] for rep in replicas])
        # delete-one-block jackknife: (g - 1)/g sum (theta_b - mean)^2 = (g - 1) x biased cov
        cov[shape] = (g - 1) * np.atleast_2d(np.cov(reps.T, bias=True))
        if d > 1:  # Wald chi-square of the shape's terms (tilt, curvature) against 0
            theta = fits[shape][1:]
            sub = cov[shape][1:, 1:]
            # a singular covariance (a term the replicates never move): no evidence for it
            ok = np.all(np.diag(sub) > 0) and np.linalg.cond(sub) < 1e12
            chi2 = float(theta @ np.linalg.solve(sub, theta)) if ok else 0.0
            bic[shape] = -chi2 + (d - 1) * math.log(n_rows)
    best = min((s for s in shapes), key=lambda s: bic[s])
    d = SHAPE_DEGREE[best] + 1
    coef = np.pad(fits[best], (0, 3 - d))
    se = np.full(3, np.nan)
    se[:d] = np.sqrt(np.diag(cov[best]))
    return best, coef, se, min(misfit.values())


def fit_shapes(
    lev: np.ndarray,
    li: np.ndarray,
    ds: xr.Dataset,
    cfg: ScannerConfig,
    shapes: tuple[str, ...],
    refit,
) -> xr.Dataset:
    """The boundaries' shapes (module docstring) and the layers refitted on flattened levels.

    ``lev``/``li``: the central lines' levels and ``ln I`` (pixels, lines); ``ds`` the flat
    fit; ``refit(levels)`` the flat fit of other levels.
    """
    p, r = cfg.pixel_size, cfg.beam_radius
    x = cfg.line_positions[np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * r]
    n_pix = lev.shape[0]
    z = np.arange(n_pix) * p
    cdf = _transition_model(cfg.n_pixels)
    mixing = mixed_rows(cfg)  # the mixed rows' own speckle (_mixing.py)
    groups = np.array_split(np.arange(x.size), BOUNDARY_BLOCKS)
    xb = np.array([x[g].mean() for g in groups])
    mb = np.stack([li[:, g].mean(axis=1) for g in groups])  # (blocks, pixels)
    # each block's rows' ln var ln I: the speckle contrast, which steps with the density
    with np.errstate(divide="ignore"):
        lv = np.log(np.stack([li[:, g].var(axis=1) for g in groups]))
    m1, m2 = float(np.mean(x)), float(np.mean(x**2))
    last = ds.attrs["last_row"] * p  # the flat fit's last row (µm): windows end there

    def locate(lo, hi, s_above, s_below, offsets, contrast=False):
        """Shape, coefficients, SEs and joint misfit of one boundary in rows ``lo..hi`` (µm,
        per block) between layers of slopes ``s_above``, ``s_below`` and ``E ln(I/<I>)``
        ``offsets``; None if every block's window is too short."""
        lo, hi = np.broadcast_to(lo, xb.shape), np.broadcast_to(hi, xb.shape)
        margin = (_LEVEL_ROWS + 2) * p
        # one grid of trial positions over every block's window (each block's misfit inf
        # outside its own): the joint search interpolates the blocks' misfits on one grid
        taus = np.arange(np.min(lo) + margin, np.max(hi) - margin + 1e-9, p / 4)
        if taus.size < 2:
            return None
        rss = np.full((BOUNDARY_BLOCKS, taus.size), np.inf)
        rows = (z >= lo[:, None]) & (z <= hi[:, None])  # each block's window (blocks, pixels)
        n_rows = int(rows.sum())
        # the blocks of one window together (all of them in a flat window)
        for w_lo, w_hi in dict.fromkeys(zip(lo.tolist(), hi.tolist(), strict=True)):
            same = np.flatnonzero((lo == w_lo) & (hi == w_hi))
            sel = (z >= w_lo) & (z <= w_hi)
            inside = (taus >= w_lo + margin - 1e-9) & (taus <= w_hi - margin + 1e-9)
            if inside.any():
                rss[np.ix_(same, inside)] = _blocks_rss(mb[np.ix_(same, sel)], z[sel],
                                                        taus[inside], s_above, s_below, p, cdf,
                                                        offsets, mixing)  # fmt: skip
        if not np.isfinite(rss).any():
            return None
        if contrast:
            # both misfits, each over its block's residual variance (its least misfit per
            # row): the sum of the two statistics' chi-squares
            rc = np.stack([_contrast_rss(lv[b, r], z[r], taus) for b, r in enumerate(rows)])
            both = np.isfinite(rss) & np.isfinite(rc)
            n_b = np.maximum(1, rows.sum(axis=1, keepdims=True))
            s_m = np.min(np.where(both, rss, np.inf), axis=1, keepdims=True) / n_b
            s_c = np.min(np.where(both, rc, np.inf), axis=1, keepdims=True) / n_b
            with np.errstate(divide="ignore", invalid="ignore"):
                rss = np.where(both, rss / s_m + rc / s_c, np.inf)
            if not np.isfinite(rss).any():
                return None
        fit = _boundary_shape(rss, taus, xb, cfg.x_max, shapes, p, n_rows)
        # a block whose least misfit, or whose place on the joint fit, is at its window's
        # end: its position may lie beyond (a block whose boundary lies outside its window
        # finds a spurious least misfit inside it, which the joint fit follows to the end)
        cf = fit[1]
        joint = (cf[0] + cf[1] * xb + cf[2] * (xb**2 - cfg.x_max**2 / 12) - taus[0]) / (p / 4)
        cut = False
        for r, f, j in zip(rss, np.isfinite(rss), joint, strict=True):
            if f.any():
                end = np.flatnonzero(f)[[0, -1]]
                cut |= np.argmin(np.where(f, r, np.inf)) in end
                cut |= not end[0] + 0.5 < j < end[1] - 0.5
        return (*fit, cut)

    def anchor(cf):
        """Depth of a located boundary at the central lines' mean offset."""
        return float(cf[0] + cf[1] * m1 + cf[2] * (m2 - cfg.x_max**2 / 12))

    def detect(cur):
        """Each boundary's anchor depth, shape, coefficients and SEs, located around ``cur``'s
        tops (again in windows that follow its shape where a block's window cut it off:
        :func:`window`); two neighbouring boundaries merge into one shaped boundary where that
        fits the blocks' profiles at least as well as the two flat ones with a layer between
        them (a tilted or curved boundary that the flat fit saw as a ramp: one level per block
        fewer)."""
        # the row means' slopes (a sparse layer's clipped pixels make them shallower)
        tops, slope = cur.top.values, -2 * cur.attenuation.values * cur.log_slope_gain.values
        off = cur.log_offset.values
        end = cur.attrs["last_row"] * p  # the last fitted row
        bottom = np.append(tops, max(end, tops[-1]))

        def mid(k):
            return 0.5 * (bottom[k] + bottom[k + 1])

        def step_z(k):
            """Boundary ``k``'s steps in SEs: of the mean ``ln I`` level at the boundary (the
            two layers' lines of the flat fit's slopes, levels per block) and of the rows'
            ``ln var ln I`` (per block); the SEs from the spread over the (independent)
            lateral blocks. NaN where a layer has fewer than 2 rows."""
            margin = (_LEVEL_ROWS + 2) * p
            ra = (z > bottom[k - 1] + margin) & (z < tops[k] - margin) & (z <= last)
            rb = (z > tops[k] + margin) & (z < bottom[k + 1] - margin) & (z <= last)
            if ra.sum() < 2 or rb.sum() < 2:
                return np.nan, np.nan
            above = np.mean(mb[:, ra] - slope[k - 1] * z[ra], axis=1)
            below = np.mean(mb[:, rb] - slope[k] * z[rb], axis=1)
            level = (slope[k] - slope[k - 1]) * tops[k] + below - above
            contrast = lv[:, rb].mean(axis=1) - lv[:, ra].mean(axis=1)
            return tuple(abs(d.mean()) * math.sqrt(d.size) / d.std(ddof=1)
                         for d in (level, contrast))  # fmt: skip

        def window(zf, along=None):
            """Depths (µm, per block) of the depth ``zf`` of ``cur``: ``zf`` itself, or with
            ``along`` (coefficients per boundary) ``zf + delta`` at the block's mean offset,
            ``delta`` linear in depth between the boundaries' offsets (:func:`flatten`'s), so
            that a window half-way between two boundaries stays half-way between them; within
            the flat fit's rows."""
            if along is None:
                return np.full(xb.shape, zf)
            d = along[:, 1, None] * (xb - m1) + along[:, 2, None] * (xb**2 - m2)
            d[0] = 0.0
            moved = zf + np.array([np.interp(zf, tops, d[:, j]) for j in range(xb.size)])
            return np.clip(moved, 0.0, last)

        def place_by(k, con):
            """Boundary ``k`` located half-way to its neighbours (by the contrast too with
            ``con``; in windows moved along ``base``'s shapes); where a shaped boundary's block
            was cut by its window (:func:`locate`), located again in windows moved along that
            shape too."""
            one = locate(window(mid(k - 1), base), window(mid(k), base), slope[k - 1],
                         slope[k], off[k - 1 : k + 1], con)  # fmt: skip
            if one is not None and one[0] != "flat" and one[4]:
                along = np.zeros((tops.size, 3)) if base is None else base.copy()
                along[k] = one[1]
                again = locate(window(mid(k - 1), along), window(mid(k), along), slope[k - 1],
                               slope[k], off[k - 1 : k + 1], con)  # fmt: skip
                one = one if again is None else again
            return None if one is None else (*one, con)  # [5]: located by the contrast too

        def place(k):
            """Boundary ``k`` located by the mean ``ln I``, or by its contrast too: where the
            level hardly steps (:data:`_CONTRAST_SE`), or where the mean locates it to worse
            than :data:`_PRECISE_PIXELS` (its depth's jackknife SE) and the contrast steps,
            the more precise of the two."""
            z_level, z_contrast = step_z(k)
            if z_level < _CONTRAST_SE < z_contrast:
                return place_by(k, True)
            one = place_by(k, False)
            if z_contrast > _CONTRAST_SE and (one is None or one[2][0] > _PRECISE_PIXELS * p):
                both = place_by(k, True)
                if both is not None and (one is None or both[2][0] < one[2][0]):
                    return both
            return one

        anchors, shape, coef, ses = [0.0], ["flat"], [np.zeros(3)], [np.full(3, np.nan)]
        base = None  # the shapes the windows follow (None: every boundary flat)
        located = [None] + [place(k) for k in range(1, tops.size)]
        if any(one is not None and one[0] != "flat" for one in located):
            # a boundary whose block its window still cuts is located once more in windows
            # that follow its neighbours' located shapes too (those within a pixel): two
            # boundaries sweeping together (challenge patient 73: tilts -0.035 and -0.042,
            # 130 µm apart) leave a window half-way between flat ones in the wrong rows
            base = np.array([np.zeros(3) if one is None or not one[2][0] <= _PRECISE_PIXELS * p
                             else np.array([0.0, *one[1][1:]]) for one in located])  # fmt: skip
            located = [None] + [place(k) if one is not None and one[4] else one
                                for k, one in enumerate(located[1:], 1)]  # fmt: skip

        def at_blocks(k):
            if located[k] is None:
                return window(tops[k])
            cf = located[k][1]
            return cf[0] + cf[1] * xb + cf[2] * (xb**2 - cfg.x_max**2 / 12)

        k = 1
        while k < tops.size:
            if k + 1 < tops.size:
                lo, hi = window(mid(k - 1)), window(mid(k + 1))
                merged = locate(lo, hi, slope[k - 1], slope[k + 1], off[[k - 1, k + 1]])
                if merged is not None and merged[0] != "flat":
                    # the merged profile must sweep at least half the layer between (a ramp
                    # is the boundary's sweep across the lines) and fit the blocks as well as
                    # the two located boundaries with the layer between them
                    cf = merged[1]
                    sweep = np.ptp(cf[1] * x + cf[2] * x**2)
                    rows = [(z >= lo[b]) & (z <= hi[b]) for b in range(BOUNDARY_BLOCKS)]
                    split = _split_rss([mb[b, r] for b, r in enumerate(rows)],
                                       [z[r] for r in rows], at_blocks(k), at_blocks(k + 1),
                                       slope[k - 1 : k + 2], p, cdf,
                                       off[k - 1 : k + 2], mixing)  # fmt: skip
                    if sweep >= 0.5 * (tops[k + 1] - tops[k]) and merged[3] <= split:
                        anchors.append(anchor(cf))
                        shape.append(merged[0])
                        coef.append(cf)
                        ses.append(merged[2])
                        k += 2
                        continue
            one = located[k]
            # a boundary located by its contrast too: its own depth (the flat fit's may be far)
            anchors.append(anchor(one[1]) if one is not None and one[5] else tops[k])
            if one is None:
                shape.append("flat")
                coef.append(np.array([tops[k], 0.0, 0.0]))
                ses.append(np.full(3, np.nan))
            else:
                shape.append(one[0])
                coef.append(one[1])
                ses.append(one[2])
            k += 1
        return np.array(anchors), shape, np.array(coef), ses

    def flatten(tops, coef):
        delta = coef[:, 1, None] * (x - m1) + coef[:, 2, None] * (x**2 - m2)  # (K, lines)
        delta[0] = 0.0
        # delta(x, z') linear between the boundaries, constant below the last one
        raw = np.stack([np.rint((z + np.interp(z, tops, delta[:, j])) / p).astype(int)
                        for j in range(x.size)], axis=1)  # fmt: skip
        inside = (raw >= 0) & (raw < n_pix)
        out = np.where(inside, lev[np.clip(raw, 0, n_pix - 1), np.arange(x.size)], 0)
        return out.astype(np.uint8)

    current = ds
    for _ in range(ITERATIONS):
        tops, shape, coef, ses = detect(current)
        if all(sh == "flat" for sh in shape):
            return flat_shapes(ds)
        new = refit(flatten(tops, coef))
        same = new.sizes["layer"] == tops.size and np.all(np.abs(new.top.values - tops) < p)
        if same:
            break
        current = new
    # each refitted boundary takes the shape of the nearest located one (within 3 pixels)
    pick = [0] + [
        int(np.argmin(np.abs(tops - t))) if np.min(np.abs(tops[1:] - t)) < 3 * p else -1
        for t in new.top.values[1:]
    ]
    out_shape = [shape[i] if i >= 0 else "flat" for i in pick]
    b = np.array([coef[i, 1] if i > 0 else 0.0 for i in pick])
    c = np.array([coef[i, 2] if i > 0 else 0.0 for i in pick])
    b_se = np.array([ses[i][1] if i > 0 else np.nan for i in pick])
    c_se = np.array([ses[i][2] if i > 0 else np.nan for i in pick])
    top = new.top.values - b * m1 - c * (m2 - cfg.x_max**2 / 12)
    top[0] = 0.0
    # the flattened fit measures the boundary at the central lines' mean offset, t_c; the
    # mean depth over the box a = t_c - b <x> - c (<x^2> - X^2/12) carries the shape's
    # errors too (b and c from other data: the blocks' positions, independent of t_c's rows)
    shape_var = np.nan_to_num((b_se * m1) ** 2 + (c_se * (m2 - cfg.x_max**2 / 12)) ** 2)
    top_se = np.sqrt(new.top_se.values**2 + shape_var)
    new = new.assign(
        top=(("layer",), top, new.top.attrs), top_se=(("layer",), top_se, new.top_se.attrs)
    )
    return _shape_variables(new, out_shape, b, b_se, c, c_se, _CRITERION)
