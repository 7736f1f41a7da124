"""The number of layers of the phantom fit (private): a change-point test of stated level.

The row-mean ``ln I`` profile of the central lines is cut into ``K`` straight segments by
dynamic programming (:func:`segment`, each boundary leaving out
``gap`` rows, the PSF's main lobe). The number of layers is chosen by a sequence of tests,
``K + 1`` against ``K`` for ``K = 1, 2, ...``, each at the level :data:`FALSE_LAYER_RATE`,
stopping at the first that does not reject.

**The null and the statistic.** Under ``K`` layers the profile is the best ``K``-segmentation's
lines plus noise: the rows' speckle (correlated over about a row by the depth PSF) and the
shadowing streaks (each line's shadow ``C_i(z)`` sums the scatterers above it: a random walk
in depth, correlated over the whole profile, which makes straight segments look like layers
to a criterion that takes the rows as independent, BIC's among them). The statistic is the
best split's improvement,

    T = max over segments and split rows e of  RSS_w(one line on L u R) - RSS_w(L) - RSS_w(R),

``L`` the segment's rows above ``e``, ``R`` those from ``e + gap`` on (each at least
``min_rows`` rows), ``RSS_w`` the residual sum of squares of the least-squares line weighted by
``1/v_q`` (``v_q`` below). Adding any straight line to a segment leaves ``T`` unchanged, so it
sees only the noise under the null, whatever the layers' levels and slopes.

**Its null distribution, derived.** The central lines are cut into :data:`COUNT_BLOCKS`
lateral blocks (:func:`count_blocks`); the lines within :data:`GUARD_RADII` beam radii of a
neighbouring block are left out, so the nearest lines of two blocks are more than a beam radius
apart and the blocks' noise profiles ``e_b`` are independent (the speckle's correlation between
lines ``dx`` apart is ``Li2(exp(-dx^2/r^2))/(pi^2/6)``, the streaks' ``exp(-dx^2/r^2)``: without
the guard, 16 blocks of the reduced box share enough to make the variance of their mean 11 %
larger than the sum of theirs, and the test rejected 7.5 % of uniform scans; with it, less
than 1 %). Each ``e_b`` is symmetric (a mean over many pixels' ``ln I`` and many scatterers'
shadows). The tested profile is ``m = sum_b c_b m_b`` (``c_b`` the block's share of the
tested lines) and ``T(m) = T(sum_b c_b r_b)``, ``r_b`` the block's own residual about its
segments' least-squares lines: under the null a linear function of ``e_b`` alone. Given the
residuals up to their signs, every sign vector ``s`` is then equally likely, so ``T(sum_b s_b
c_b r_b)`` over random ``s`` is the exact null distribution of ``T`` (a sign-flip
randomisation test: no Gaussian model and no covariance to estimate; the correlation along
depth is the blocks' own). The weights (``v_q``: ``sum_b c_b^2 (r_bq - sum_b' c_b' r_b'q)^2``,
the row mean's variance, a running median over 9 rows) are computed once and serve every
draw; they are centred across the blocks, so that a layer the null lacks does not inflate
them (uncentred, which the flips leave exactly unchanged, a faint 43-pixel top layer of the
2025 configuration went unseen, p = 0.23); under the null the centring moves them by about
``1/g`` of themselves, and the measured rates below hold the level.
The p-value ``(1 + #{T_s >= T})/(1 + draws)`` over :data:`DRAWS` seeded draws is uniform or
larger under the null, so each test rejects with probability at most :data:`FALSE_LAYER_RATE`:
a uniform scan is given a second layer in 5 % of scans, and a scan of ``K`` layers a
``(K + 1)``-th in 5 % (there the ``K`` boundaries are estimated; the rows beyond the ``gap``
must hold no transition).

**Rows near the floor.** Rows enter the fit when at most 10 % of their pixels are clipped
(or a sparse layer's empty pixels: :func:`~speckle.studies.phantom._floor._above_floor`),
judged on their own pixels: near the floor that choice keeps the rows that fluctuated up (a
dip of 0.155 ± 0.028 at the first row left out, +0.04 in the last 4 kept, over 105 uniform
reduced scans reaching the floor), and a clipped pixel's value ``ln c - 1`` assumes a density
flat near zero. The test uses each segment's rows whose *predicted* clipped fraction (fully
developed speckle at the segment's line, ``1 - exp(-c/<I>)``) is at most
:data:`TEST_CLIPPED`, where that choice is all but certain.

**BIC's row variance** (:func:`bic_row_variance`): the default criterion's (``"bic"``) weights,
the blocks' row means about their quadratic trend across the lines, so that a tilted or curved
boundary's depth in each block does not count as noise.
"""

from __future__ import annotations

import itertools

import numpy as np

from ._shapes import SHAPE_DEGREE

__all__ = [
    "ACF_LAGS",
    "COUNT_BLOCKS",
    "CRITERION",
    "DRAWS",
    "FALSE_LAYER_RATE",
    "GUARD_RADII",
    "TEST_CLIPPED",
    "bic_row_variance",
    "count_blocks",
    "layer_count",
    "running_median",
    "segment",
    "segment_rss",
    "split_p_value",
]  # fmt: skip

#: Stated probability per scan of a layer more than the scan holds (each test's level).
FALSE_LAYER_RATE = 0.05
#: Random sign vectors of the randomisation test (the p-value's resolution 1/(DRAWS + 1)).
DRAWS = 1999
#: Lateral blocks of the test (at most: each at least BLOCK_RADII beam radii wide).
COUNT_BLOCKS = 16
#: Least width of a test block, beam radii.
BLOCK_RADII = 2.0
#: Fewest blocks: 2^(MIN_BLOCKS - 1) = 32 distinct sign vectors, so that a p-value can reach
#: 1/32 < FALSE_LAYER_RATE.
MIN_BLOCKS = 6
#: Lines within this many beam radii of a neighbouring block's edge are left out of the test:
#: the nearest lines of two blocks are then more than a beam radius apart, and the blocks'
#: correlation adds less than 1 % to the variance of their mean (``test_phantom_count.py``).
GUARD_RADII = 0.5
#: Rows whose predicted clipped fraction exceeds this are left out of the test.
TEST_CLIPPED = 0.03
#: The criterion, as the fit's ``criterion`` attribute states it.
CRITERION = (
    f"K + 1 against K layers while the best split's weighted least-squares improvement of the "
    f"row-mean ln I profile exceeds its sign-flip randomisation null over {COUNT_BLOCKS} "
    f"independent lateral blocks at level {FALSE_LAYER_RATE} (a false layer in 5 % of scans)"
)
#: Rows of the running median of the row-mean variance.
_SMOOTH = 9
#: Lags of the row means' integrated autocorrelation (BIC's variance inflation).
ACF_LAGS = 8
#: Degree of the trend across the lateral blocks that BIC's row variance leaves out: the
#: most curved boundary shape's (:data:`speckle.studies.phantom._shapes.SHAPE_DEGREE`).
TREND_DEGREE = max(SHAPE_DEGREE.values())
#: Entropy of the sign vectors' seed: the same draws for every scan (the test is exact for
#: any set of draws drawn independently of the data).
_SEED = 3_420_527
#: Draws processed at once (memory: ``_CHUNK`` x rows).
_CHUNK = 500


def _block_residuals(z: np.ndarray, mb: np.ndarray, segs) -> np.ndarray:
    """Each block's profile minus its own least-squares line per segment (0 outside them)."""
    r = np.zeros_like(mb)
    for a, b in segs:
        if b - a < 2:
            continue
        zz = z[a:b] - z[a:b].mean()
        y = mb[:, a:b]
        slope = (y @ zz) / (zz @ zz)
        r[:, a:b] = y - y.mean(axis=1, keepdims=True) - slope[:, None] * zz
    return r


def running_median(values: np.ndarray, width: int = _SMOOTH) -> np.ndarray:
    """Running median over ``width`` (odd) rows, the edge rows repeated."""
    pad = np.pad(values, width // 2, mode="edge")
    return np.median(np.lib.stride_tricks.sliding_window_view(pad, width), axis=1)


def bic_row_variance(li: np.ndarray, groups: list[np.ndarray]) -> np.ndarray:
    """The variance of each row's mean ``ln I`` that weights BIC's segments (``criterion="bic"``).

    Parameters
    ----------
    li : ndarray, shape (rows, lines)
        ``ln I`` of the fitted rows' central lines (neper).
    groups : list of ndarray
        The lines (column indices of ``li``) of each of ``g`` lateral blocks, contiguous and
        in order across the scan.

    Returns
    -------
    ndarray, shape (rows,)
        ``s_q^2`` (neper^2): the blocks' row means ``B_bq`` about their least-squares trend
        of degree :data:`TREND_DEGREE` in the blocks' mean line, ``sum_b r_bq^2 / (g (g - 3))``
        (for independent blocks of equal size an unbiased variance of the row mean with
        ``g - 3`` degrees of freedom; the delete-one-block jackknife about the blocks' mean
        has ``g - 1``), a running median of :data:`_SMOOTH` rows (it grows with depth: the
        streaks), times the integrated autocorrelation ``1 + 2 sum_{L=1..ACF_LAGS} rho_L``
        (at least 1) of the residuals along depth (the PSF and the streaks correlate the row
        means).

    Notes
    -----
    A tilted or curved boundary puts each block's rows at another depth of it: below the
    boundary a block's mean is shifted by the layers' slope difference times its boundary
    depth there, a smooth function of the block's position, not a fluctuation. About the
    blocks' mean (the plain jackknife) that shift counted as noise and weighted the rows of
    a bright steep layer under a curved top 7 to 40 times less than the rest (challenge
    patient 64, whose third layer BIC then missed); about the trend it is left out, exactly
    where the shift is quadratic in the lines.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> li = rng.normal(size=(50, 320)) + np.linspace(-1, 1, 320) ** 2  # noise + a trend
    >>> v = bic_row_variance(li, np.array_split(np.arange(320), 16))
    >>> bool(abs(np.median(v) * 320 - 1) < 0.2)  # the row mean's variance, 1/320
    True
    """
    g = len(groups)
    if g <= TREND_DEGREE + 1:
        raise ValueError(f"groups must hold more than {TREND_DEGREE + 1} blocks, got {g}")
    means = np.stack([li[:, k].mean(axis=1) for k in groups])  # (blocks, rows)
    xb = np.array([np.mean(k) for k in groups], dtype=float)
    basis = np.vander((xb - xb.mean()) / np.ptp(xb), TREND_DEGREE + 1)
    r = means - basis @ np.linalg.lstsq(basis, means, rcond=None)[0]
    v = running_median(np.sum(r**2, axis=0) / (g * (g - TREND_DEGREE - 1)))
    acf = [np.sum(r[:, :-lag] * r[:, lag:]) / np.sum(r**2) for lag in range(1, ACF_LAGS + 1)]
    return v * max(1.0, 1.0 + 2.0 * float(np.sum(acf)))


def _row_variance(r: np.ndarray, c: np.ndarray, a: int, b: int) -> np.ndarray:
    """The row mean's variance on rows ``a .. b-1``: the blocks' residuals about their mean,
    ``sum_b c_b^2 (r_bq - sum_b' c_b' r_b'q)^2``, a running median of :data:`_SMOOTH` rows (a
    floor of 1e-12 of its largest keeps the weights finite)."""
    dev = r[:, a:b] - c @ r[:, a:b]  # about the blocks' mean: a layer's misfit left out
    v = running_median((c**2) @ dev**2)
    return np.maximum(v, 1e-12 * max(float(np.max(v)), 1e-300))


class _Splits:
    """The splits of one segment: rows ``0 .. e-1`` (``L``) and ``e + gap ..`` (``R``), each
    at least ``min_rows``, with the weighted sums that do not depend on the profile.

    With ``S = [[s0, sz], [sz, szz]]`` the sums of ``w``, ``w z``, ``w z^2`` over a set of rows
    and ``u = (sum w y, sum w z y)``, the weighted least-squares line explains ``u S^-1 u``
    of ``sum w y^2``, so the improvement ``RSS_w(L u R) - RSS_w(L) - RSS_w(R)`` is
    ``q_L + q_R - q_{L u R}`` (the ``sum w y^2`` cancel).
    """

    def __init__(self, zz: np.ndarray, w: np.ndarray, gap: int, min_rows: int):
        n = zz.size
        self.n, self.gap = n, gap
        self.e = np.arange(min_rows, n - gap - min_rows + 1)
        cum = [np.concatenate([[0.0], np.cumsum(v)]) for v in (w, w * zz, w * zz * zz)]
        left = [c[self.e] for c in cum]
        right = [c[n] - c[self.e + gap] for c in cum]
        both = [u + v for u, v in zip(left, right, strict=True)]
        self.quad = [self._quadratic(*sums) for sums in (left, right, both)]
        self.w, self.wz = w, w * zz

    @staticmethod
    def _quadratic(s0, sz, szz):
        det = s0 * szz - sz * sz
        return szz / det, -2 * sz / det, s0 / det

    def best(self, y: np.ndarray) -> np.ndarray:
        """The best split's improvement for each profile (row of ``y``); -inf if none."""
        if self.e.size == 0:
            return np.full(y.shape[0], -np.inf)
        cy = np.cumsum(y * self.w, axis=1)
        czy = np.cumsum(y * self.wz, axis=1)
        e, end = self.e - 1, self.n - 1  # inclusive cumulative sums: rows 0 .. e-1
        right_from = self.e + self.gap - 1
        u_left = (cy[:, e], czy[:, e])
        u_right = (cy[:, end, None] - cy[:, right_from], czy[:, end, None] - czy[:, right_from])
        u_both = (u_left[0] + u_right[0], u_left[1] + u_right[1])
        gain = 0.0
        for sign, (a, b, c), (s, t) in zip((1, 1, -1), self.quad, (u_left, u_right, u_both),
                                           strict=True):  # fmt: skip
            gain = gain + sign * (a * s * s + b * s * t + c * t * t)
        return gain.max(axis=1)


def split_p_value(
    z: np.ndarray,
    mb: np.ndarray,
    c: np.ndarray,
    segs,
    *,
    gap: int,
    min_rows: int,
    draws: int = DRAWS,
    rows: np.ndarray | None = None,
) -> tuple[float, float]:
    """p-value of ``K + 1`` layers against the ``K`` segments ``segs`` (module docstring).

    ``z`` (rows, µm), ``mb`` the blocks' row means ``(blocks, rows)``, ``c`` the blocks'
    shares of the lines (summing to 1), ``segs`` ``[(a, b), ...]`` row ranges, ``rows`` the
    rows tested (a boolean mask; default all). Returns ``(p, T)``: the randomisation p-value
    and the observed best split's improvement (``p = 1``, ``T = -inf`` when no segment can be
    split).
    """
    if rows is not None:  # the tested rows of each segment, taken as consecutive
        idx = [np.arange(a, b)[rows[a:b]] for a, b in segs]
        ends = np.cumsum([0] + [i.size for i in idx])
        segs = list(itertools.pairwise(ends))
        z, mb = z[np.concatenate(idx)], mb[:, np.concatenate(idx)]
    r = _block_residuals(z, mb, segs)
    rng = np.random.default_rng(np.random.SeedSequence(_SEED))
    signs = rng.choice(np.array([-1.0, 1.0]), size=(draws, c.size))
    parts = []
    for a, b in segs:
        if b - a < 2 * min_rows + gap:
            continue
        zz = z[a:b] - z[a:b].mean()
        zz = zz / max(float(np.ptp(zz)), 1e-300)
        w = 1.0 / _row_variance(r, c, a, b)
        parts.append((a, b, _Splits(zz, w, gap, min_rows)))

    def statistic(s):
        y = (s * c) @ r  # (draws, rows): the flipped profiles' residuals
        out = np.full(s.shape[0], -np.inf)
        for a, b, splits in parts:
            out = np.maximum(out, splits.best(y[:, a:b]))
        return out

    t_obs = float(statistic(np.ones((1, c.size)))[0])
    if not np.isfinite(t_obs):
        return 1.0, t_obs
    exceed = sum(int(np.sum(statistic(signs[i : i + _CHUNK]) >= t_obs))
                 for i in range(0, draws, _CHUNK))  # fmt: skip
    return (1 + exceed) / (1 + draws), t_obs


def count_blocks(x: np.ndarray, radius: float) -> list[np.ndarray]:
    """The test's lateral blocks: :data:`COUNT_BLOCKS` contiguous blocks of the central lines
    at ``x`` (µm; fewer if a block would be narrower than :data:`BLOCK_RADII` beam radii),
    each without its lines within :data:`GUARD_RADII` beam radii of a neighbouring block's
    edge (indices into ``x``).

    Raises
    ------
    ValueError
        Fewer than :data:`MIN_BLOCKS` blocks fit: the sign flips could not reach the level.
    """
    n = x.size
    width = float(np.ptp(x)) + (float(x[1] - x[0]) if n > 1 else 0.0)
    g = int(min(COUNT_BLOCKS, width // (BLOCK_RADII * radius)))
    if g < MIN_BLOCKS:
        raise ValueError(
            f"the scan's central lines span {width:.0f} um; the layer count's test needs "
            f"{MIN_BLOCKS} blocks of {BLOCK_RADII:g} beam radii "
            f"({MIN_BLOCKS * BLOCK_RADII * radius:.0f} um)"
        )
    groups = np.array_split(np.arange(n), g)
    guard = GUARD_RADII * radius - 1e-9
    out = []
    for b, gg in enumerate(groups):
        ok = np.ones(gg.size, bool)
        if b > 0:
            ok &= x[gg] - x[gg[0]] >= guard
        if b < len(groups) - 1:
            ok &= x[gg[-1]] - x[gg] >= guard
        out.append(gg[ok])
    return out


def layer_count(
    z: np.ndarray,
    li: np.ndarray,
    x: np.ndarray,
    radius: float,
    best: dict,
    *,
    gap: int,
    min_rows: int,
    level: float = FALSE_LAYER_RATE,
    draws: int = DRAWS,
    clip: float | None = None,
    start: int = 1,
) -> tuple[int, list[float]]:
    """The number of layers: ``K + 1`` against ``K`` from ``K = start`` (the fewest ``best``
    holds: 1 but for forced cuts) at ``level`` until a test does not reject (module
    docstring). ``z`` (rows, µm) and ``li`` ``(rows, lines)`` the
    fitted rows' ``ln I`` on the central lines at ``x`` (µm), ``radius`` the beam radius (µm),
    ``best`` ``{K: (rss, segs)}`` of the segmentation; returns ``(K, p-values of the tests
    made)``."""
    blocks = count_blocks(x, radius)
    mb = np.stack([li[:, g].mean(axis=1) for g in blocks])
    c = np.array([g.size for g in blocks], float)
    c /= c.sum()
    m = c @ mb
    k, p_values = start, []
    while k + 1 in best:
        ok = None
        if clip is not None:
            ok = np.zeros(z.size, bool)
            for a, b in best[k][1]:
                line = np.polyval(np.polyfit(z[a:b], m[a:b], 1), z[a:b])
                ok[a:b] = -np.expm1(-np.exp(clip - line - np.euler_gamma)) <= TEST_CLIPPED
        p, _ = split_p_value(z, mb, c, best[k][1], gap=gap, min_rows=min_rows, draws=draws,
                             rows=ok)  # fmt: skip
        p_values.append(p)
        if p > level:
            break
        k += 1
    return k, p_values


# --- the segmentation ---------------------------------------------------------------------


def segment_rss(z: np.ndarray, m: np.ndarray, w: np.ndarray, *, min_rows: int) -> np.ndarray:
    """``rss[a, b]``: weighted residual sum of squares of the weighted least-squares line of
    slope <= 0 fitted to rows ``a .. b-1`` (weights ``w``; infinite below ``min_rows`` rows): a
    layer's mean ln I cannot rise with depth (its shadowing only grows), so where the free line
    would rise, the mean's."""
    n = z.size
    terms = (w, w * z, w * m, w * z * z, w * z * m, w * m * m)
    c = [np.concatenate([[0.0], np.cumsum(v)]) for v in terms]
    count = np.concatenate([[0], np.arange(1, n + 1)])
    a, b = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    s0, sz, sm, szz, szm, smm = (cc[b] - cc[a] for cc in c)
    with np.errstate(invalid="ignore", divide="ignore"):
        vzz = szz - sz * sz / s0
        vzm = szm - sz * sm / s0
        vmm = smm - sm * sm / s0
        rss = vmm - np.where((vzz > 0) & (vzm < 0), vzm * vzm / vzz, 0.0)  # slope <= 0
    rss[(count[b] - count[a]) < min_rows] = np.inf
    return np.maximum(rss, 0.0)


def segment(
    z: np.ndarray,
    m: np.ndarray,
    w: np.ndarray,
    max_layers: int,
    *,
    gap: int,
    min_rows: int,
    cuts: tuple[int, ...] = (),
) -> dict[int, tuple[float, list[tuple[int, int]]]]:
    """Best cuts of the profile ``m`` (rows at ``z``, weights ``w``) for each ``K``:
    ``{K: (rss, [(a, b), ...])}``, segments of row indices into ``z``, consecutive segments
    separated by ``gap`` rows, each of at least ``min_rows``. ``cuts``: rows where a segment
    must begin, the segment above ending there, with no ``gap`` left out (the first row below
    a layer under the window's floor,
    :mod:`speckle.studies.phantom._floor`); ``K`` then starts at ``len(cuts) + 1``."""
    n = z.size
    rss = segment_rss(z, m, w, min_rows=min_rows)
    forced = np.zeros(n + 1, bool)
    forced[list(cuts)] = True
    blocked = np.zeros(n + 1, bool)  # ends that would leave out rows at a forced cut
    for c in cuts:  # no segment holds rows on both sides of a forced cut
        rss[:c, c + 1 :] = np.inf
        blocked[max(c - gap, 0) : c] = True
    best = {1: (rss[0, n], [(0, n)])} if not cuts else {}
    # cost[b]: best rss of k segments covering rows 0 .. b-1 (last segment ends at b)
    cost = rss[0].copy()
    back = []
    for k in range(2, max_layers + 1):
        new = np.full(n + 1, np.inf)
        arg = np.zeros(n + 1, int)
        for b in range(n + 1):
            # previous segment ends at e, this one is e + gap .. b - 1 (e at a forced cut)
            e = np.arange(0, max(b - gap, 0) + 1)
            if e.size == 0:
                continue
            total = np.where(blocked[e], np.inf, cost[e] + rss[_starts(e, forced, gap, n), b])
            i = int(np.argmin(total))
            new[b], arg[b] = total[i], e[i]
        back.append(arg)
        cost = new
        if not np.isfinite(cost[n]):
            if k > len(cuts):  # too few rows for more segments
                break
            continue
        segs, b = [], n
        for kk in range(k, 1, -1):
            e = back[kk - 2][b]
            segs.append((int(_starts(np.array([e]), forced, gap, n)[0]), int(b)))
            b = e
        segs.append((0, int(b)))
        best[k] = (cost[n], segs[::-1])
    return best


def _starts(e: np.ndarray, forced: np.ndarray, gap: int, n: int) -> np.ndarray:
    """The first row of the segment after one ending at ``e``: ``e + gap``, or ``e`` at a
    forced cut."""
    return np.where(forced[e], e, np.minimum(e + gap, n))
