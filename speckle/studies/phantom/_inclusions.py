"""Inclusions of the phantom fit (private): detection and fit of ellipses of other ``rho E``.

After the layer fit (:func:`speckle.fit_phantom` with ``inclusions=True``), each pixel's
``ln I`` (central lines, rows above the floor) is compared with its layer's model: the level of
the layer at the same depth *below the layer's fitted upper boundary* (so tilted and curved
layers are followed), over the lines not masked by an inclusion already found; pixels within
:data:`EDGE` rows of a fitted boundary are left out (the transition is the layer fit's). Under
the scanner's shadowing an ellipse ``((x - x_c)/w)^2 + ((z - z_c)/h)^2 < 1`` of ``rho_i E_i``
inside a host of ``rho_h E_h`` changes the mean ``ln I`` by

    ln(1 + (e^a - 1) chi(x, z)) + b L(x, z),   a = ln(rho_i E_i/(rho_h E_h)),
                                               b = -2 (mu_i - mu_h),

``chi`` the share of the depth PSF's intensity inside line ``x``'s chord (the level step mixes
intensities, not logs), ``L`` the length of the chord above ``z`` (inside the ellipse the extra
attenuation, below it the shadow ``-2 (mu_i - mu_h) x chord``, on every layer below), both
smoothed laterally by the double-pass weight's ``exp(-2 dx^2/r^2)`` (a Gaussian of SD ``r/2``).
The two coefficients are two independent estimates of ``rho_i E_i``: the level step,
``rho_h E_h e^a`` (it assumes the inclusion's ``E ln(I/<I>)`` is the host's, i.e. both in the
same speckle regime), and the shadow, ``rho_h E_h + (-b/2)/A2`` (``mu = rho E A2``,
:func:`slab_constants`).

Detection: the residual against a robust layer model (the median over the lines plus the
mean's offset: an unfound inclusion hardly moves it), each line's running median over
:data:`DETREND_ROWS` rows removed (the shadowing streaks), is smoothed by Gaussians of SD
:data:`SMOOTH_ROWS` rows and :data:`SMOOTH_CELLS` lateral speckle cells (``r/pitch`` lines),
times each of :data:`SCALES`, and divided by the RMS of the smoothed values over
:data:`SD_ROWS` rows around it and every line (the streaks grow with depth; each square capped
at 16 robust variances of its row), giving fields ``Z`` that are N(0, 1) without inclusions (a
row-wise SD, from ~20 independent values of a smooth field, is itself so noisy that it raised
the false-alarm rate of smoothed white noise from 4 % to 26-36 %; over 41 rows 3.0 +- 0.6 %
against 5 %, 800 fields of 120 x 118). The extreme of such a field follows the random-field
theory of a smooth Gaussian field (Worsley 1996): the expected Euler characteristic of
``{|Z| > t}``,

    2 [(A sqrt(l_x l_z) t/(2 pi)^{3/2} + P/2 sqrt(l)/(2 pi)) e^{-t^2/2} + Phi(-t)],

(``A`` the area in pixels, ``P`` its perimeter, ``l`` the variances of ``Z``'s differences
along each axis) bounds the probability that a scan without inclusion shows one, at high
``t``; ``t`` makes it :data:`FALSE_ALARM` (shared by the scales). The connected regions of
``|Z|`` above the threshold of :data:`CANDIDATE_REGIONS` expected null regions
(:func:`scipy.ndimage.label`; the studies' room imports no scikit-image) are candidates, the
most significant first (a shadow, of the other sign and below, gives way to the region above
it); each is fitted and kept when its level step ``|a|`` exceeds ``t`` of its standard errors
(the fit is the matched filter), its model removed, and the search repeated (at most
:data:`MAX_INCLUSIONS` kept). A kept ellipse must also differ from its host by more than the
host's Poisson count of scatterers and the ellipse's own speckle cells give
(:func:`_count_significant`, :func:`_count_tail`, where the host's density is identified):
in sparse layers the count's voids are dark ellipses of ln contrast -2 to -7 that the
speckle's SEs call significant (the 2025 configuration's false alarms, measured in
docs/explanation/phantom_fit.md). A dark ellipse in a host whose density is not identified is
tested with its lower bound (a wider count); where ``var ln I`` gives no bound either (its
rows clipped by the window's floor: a dim layer, or a top layer cut by it), the bound is the
host's intensity kurtosis's (:func:`~speckle.studies.phantom._density.kurtosis_density`: ``E
I^2`` lives in the bright tail the floor leaves), and without any bound a dark ellipse is not
kept (it cannot be told from a void).

Fit: the ellipse's ``(x_c, z_c, w, h)`` minimise the residual sum of squares in a window
around the region and every row below it (the shadow), ``a`` and ``b`` by Gauss-Newton for each
trial (Nelder-Mead from four starts at the region's box and from the :data:`GRID_STARTS` best
points of a coarse grid of shifted and larger ellipses, then again with the layer model taken,
as a mean, without the ellipse's lines). Standard errors: the sandwich
``(J'J)^-1 J' S J (J'J)^-1`` of the linearised model, ``S`` the residual's covariance
estimated from the pixels outside the inclusion and its shadow: the speckle's (lags up to
:data:`SHORT_ROWS` rows and the lateral cell), plus the shadowing streaks' covariance (rows
:data:`LAG` to ``2 LAG`` apart), taken as constant along depth on a line and its neighbours (a
streak is the line's shadowing deficit, shared by every row below), plus the layer model's own
error (:func:`_level_meat`: each row's level is a mean over the other lines, common to the
row). Measured (docs/explanation/phantom_fit.md): the shadow's ``rho E`` holds its SE; the
level step's and the geometry's pulls have tails where the fit stopped in a smaller ellipse
than the true one; over 8-12 draws of the same three patients (seeds 0, 2, 4) the sandwich
without the level term gave 0.6-1.0 of the draws' SD for ``centre_x``, ``axis_x`` and ``a``,
0.5-0.8 for ``centre_z`` and ``axis_z``.

Density: :func:`inclusion_density`, the layers' ``var ln I`` inversion on the ellipse's
inscribed rectangle: a lower bound (97.7 %) and the energy's upper bound; the identified
density (5 SE) is switched off (:data:`DENSITY_IDENTIFIED`, measured wrong in its one case).
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import xarray as xr
from scipy import ndimage, optimize, special

from ...conventions import attrs, coord
from ...synthoct.files import ScannerConfig

# private: the layers' inversion and its bound's rule, called (not copied)
from ._density import (
    BOUND_SE,
    _equivalent,
    kurtosis_density,
    layer_densities,
    layer_variances,
    lines_per_block,
    slab_inverse_density,
)
from ._slab import slab_constants, speckle_cell
from .patients import profiles

__all__ = [
    "FALSE_ALARM",
    "MAX_INCLUSIONS",
    "fit_inclusions",
    "no_inclusions",
    "remove_inclusions",
    "untouched_lines",
]

#: Beam radii beyond an inclusion's lateral semi-axis where its level and shadow end.
UNTOUCHED_RADII = 2.0
#: Probability that a scan without inclusion reports one (the detection threshold's).
FALSE_ALARM = 0.05
#: Expected number of regions of ``|Z|`` above the candidates' threshold in a scan without
#: inclusion (each candidate is fitted and kept when its level step exceeds ``t`` SEs).
CANDIDATE_REGIONS = 1.0
#: Most inclusions fitted in one scan.
MAX_INCLUSIONS = 3
#: Rows of each fitted boundary (either side) left out of the residual.
EDGE = 2
#: Gaussian SD of the detection's smoothing: rows, and lateral speckle cells (``r/pitch``).
SMOOTH_ROWS = 2.0
SMOOTH_CELLS = 2.0
#: Rows of each line's running median removed before the detection (the streaks).
DETREND_ROWS = 41
#: Rows over which the smoothed residual's mean square is taken (its SD at each row).
SD_ROWS = 41
#: Scales of the detection's smoothing (times SMOOTH_ROWS and SMOOTH_CELLS): small and large
#: inclusions.
SCALES = (1.0, 2.0)
#: Row lags of the speckle's covariance; beyond, the shadowing streaks' (rows LAG..2 LAG).
SHORT_ROWS = 2
LAG = 4
#: The fit's coarse grid of starts (module docstring, Fit): lateral shifts (region half-widths),
#: scales of the semi-axes, and how many of its best points start a Nelder-Mead.
GRID_SHIFTS = (-1.0, -0.5, 0.0, 0.5, 1.0)
GRID_SCALES = (0.75, 1.0, 1.5, 2.0, 3.0)
GRID_STARTS = 2

#: Variables of the inclusions' Dataset: name -> (quantity, long name).
VARIABLES = {
    "centre_x": ("length", "lateral centre of the inclusion"),
    "centre_z": ("length", "depth of the inclusion's centre"),
    "axis_x": ("length", "lateral semi-axis of the inclusion"),
    "axis_z": ("length", "depth semi-axis of the inclusion"),
    "rho_e": ("volume_density", "rho E/100 of the inclusion from its level step"),
    "rho_e_shadow": ("volume_density", "rho E/100 of the inclusion from its shadow"),
    "log_contrast": ("dimensionless", "ln of the inclusion's rho E over its host's (level step)"),
    "shadow_step": ("attenuation", "mu of the inclusion minus its host's (from the shadow)"),
    "density": ("volume_density", "scatterers per um^3 of the inclusion"),
    "energy": ("percent", "energy per scatterer of the inclusion"),
}
#: Bounds where the density is not identified: name -> (quantity, long name).
BOUNDS = {
    "density_bound": ("volume_density", "lower bound of the inclusion's density (97.7 %)"),
    "energy_bound": ("percent", "upper bound of the inclusion's energy (from the density's)"),
}
#: Margins of the inclusion's density rectangle: rows (the depth PSF) and beam radii (the
#: lateral blur) inside the inscribed rectangle of the ellipse.
DENSITY_ROWS = 1
DENSITY_RADII = 1.0
#: Whether an excess of ``var ln I`` above 5 SE reports the inclusion's density (else its lower
#: bound only). Off: measured on the reduced closed loop (seeds 0-29), the one identified
#: density (seed 28, a bright inclusion of ln contrast 5.2) was 17 times low (pull -151): its
#: shadowing streaks grow within the LAG rows that the streaks' removal assumes constant (its
#: own strong attenuation), inflating ``var ln I``; the lower bounds held (11 of 11).
DENSITY_IDENTIFIED = False
#: Least lateral width of the density's jackknife blocks (beam radii: the lines' correlation).
DENSITY_BLOCK_RADII = 2.0


def remove_inclusions(lev: np.ndarray, model: np.ndarray, db_per_neper: float) -> np.ndarray:
    """The 8-bit levels with the inclusions' model of ``ln I`` removed (the levels the layers
    would give without them): each level moved by ``-model`` in dB, rounded to the level grid
    (the scanner's 51 dB over 255 levels); clipped (0) and saturated (255) levels kept."""
    from ...synthoct import _scan

    step = _scan.DYNAMIC_RANGE / _scan.LEVELS
    moved = np.rint(lev - model * db_per_neper / step)
    out = np.where((lev > 0) & (lev < 255), np.clip(moved, 1, 254), lev)
    return out.astype(np.uint8)


def untouched_lines(x: np.ndarray, found: xr.Dataset, radius: float) -> np.ndarray:
    """The lines (positions ``x``, µm) farther than :data:`UNTOUCHED_RADII` beam radii
    (``radius``, µm) beyond every found inclusion's lateral semi-axis: an inclusion's level
    and shadow do not reach them (the double-pass weight ``exp(-2 dx^2/r^2)`` is 3e-4 at 2
    radii), so :func:`remove_inclusions` leaves their levels as they are."""
    far = np.ones(x.size, bool)
    for cx, ax in zip(found.centre_x.values, found.axis_x.values, strict=True):
        far &= np.abs(x - cx) > ax + UNTOUCHED_RADII * radius
    return far


def no_inclusions(criterion: str = "") -> xr.Dataset:
    """The inclusions' Dataset with none (dim ``inclusion`` of size 0)."""
    return _dataset([], [], criterion)


def _dataset(rows: list[dict], hosts: list[int], criterion: str) -> xr.Dataset:
    data = {}
    for name, (quantity, long_name) in VARIABLES.items():
        values = np.array([r[name] for r in rows], float)
        ses = np.array([r[f"{name}_se"] for r in rows], float)
        data[name] = (("inclusion",), values, attrs(quantity, long_name))
        data[f"{name}_se"] = (("inclusion",), ses, attrs(quantity, f"standard error of {name}"))
    for name, (quantity, long_name) in BOUNDS.items():
        values = np.array([r.get(name, np.nan) for r in rows], float)
        data[name] = (("inclusion",), values, attrs(quantity, long_name))
    data["host"] = (("inclusion",), np.array(hosts, int), attrs("label", "host layer"))
    data["significance"] = (
        ("inclusion",),
        np.array([r["significance"] for r in rows], float),
        attrs("dimensionless", "the level step |a| over its SE (kept above the threshold t)"),
    )
    return xr.Dataset(
        data,
        coords={"inclusion": coord("inclusion", np.arange(len(rows)))},
        attrs={"criterion": criterion, "false_alarm": FALSE_ALARM},
    )


def inclusion_density(
    li: np.ndarray,
    z: np.ndarray,
    theta: np.ndarray,
    x: np.ndarray,
    cfg: ScannerConfig,
    rho_e: float,
    rho_e_se: float,
) -> dict:
    """The inclusion's density and energy from its own speckle (the layers' inversion).

    The pixels of the ellipse's inscribed rectangle ``|x - x_c| <= w/sqrt 2 - DENSITY_RADII r``,
    ``|z - z_c| <= h/sqrt 2 -`` :data:`DENSITY_ROWS` pixels (whole intensity inside: ``chi = 1``
    and no lateral blur of the edges), ``li`` there with the shadow's ``b L`` removed, are a
    layer of their own: :func:`~speckle.studies.phantom._density.layer_variances` (``var ln I``
    without the streaks, rows chosen by their predicted clipping, the lines' correlation) and
    :func:`~speckle.studies.phantom._density.layer_densities` (inverted by the slab's exact
    theory, identified at its :data:`~speckle.studies.phantom._density.IDENTIFY` SE, else NaN
    and the lower bound; the bound only unless :data:`DENSITY_IDENTIFIED`), its jackknife
    over blocks of :data:`DENSITY_BLOCK_RADII` beam radii (at least 2). The energy is
    ``100 rho_e/rho`` (``rho_e`` the level step's), its SE from both relative SEs; where the
    density is a bound, the energy's is an upper bound.

    ``li`` (rows, lines): ``ln I`` with the inclusion's shadow removed; ``z``, ``x`` (µm): its
    rows' and lines' positions; ``theta``: ``(x_c, z_c, w, h)``. Returns ``density``,
    ``density_se``, ``density_bound``, ``energy``, ``energy_se``, ``energy_bound``.
    """
    xc, zc, w, h = theta
    out = dict.fromkeys(
        ("density", "density_se", "density_bound", "energy", "energy_se", "energy_bound"), np.nan
    )
    half_x = w / math.sqrt(2) - DENSITY_RADII * cfg.beam_radius
    half_z = h / math.sqrt(2) - DENSITY_ROWS * cfg.pixel_size
    cols = np.flatnonzero(np.abs(x - xc) <= half_x)
    rows = np.flatnonzero(np.abs(z - zc) <= half_z)
    block = lines_per_block(DENSITY_BLOCK_RADII, cfg)
    groups = cols.size // block
    if groups < 2 or rows.size < 2 + LAG:
        return out
    sub = li[np.ix_(rows, cols)]
    keep = [np.setdiff1d(np.arange(cols.size), g) for g in np.array_split(np.arange(cols.size),
                                                                           groups)]  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # too few rows: NaN
        v, v_jk, mu_jk = layer_variances(sub, z[rows], [(0, rows.size)], keep, cfg)
        if not np.isfinite(v[0]) or not np.all(np.isfinite(v_jk)):
            return out
        d = layer_densities(v, v_jk, mu_jk.mean(axis=0), mu_jk, cfg)
    rho, rho_se, bound = float(d["rho"][0]), float(d["rho_se"][0]), float(d["bound"][0])
    identified = bool(d["ident"][0]) and np.isfinite(rho) and rho > 0
    if identified and not DENSITY_IDENTIFIED:
        # the layers' bound rule (var ln I + 2 SE) where the excess would identify
        excess = max(float(v[0]), np.pi**2 / 6) + BOUND_SE * float(d["v_se"][0])
        inv = slab_inverse_density(excess, cfg)
        bound = _equivalent(cfg) / inv if np.isfinite(inv) and inv > 0 else np.nan
        identified = False
    if identified:
        energy = 100 * rho_e / rho
        out.update(density=rho, density_se=rho_se, energy=energy,
                   energy_se=energy * math.hypot(rho_e_se / rho_e, rho_se / rho))  # fmt: skip
    elif np.isfinite(bound) and bound > 0:
        out.update(density_bound=bound, energy_bound=100 * (rho_e + 2 * rho_e_se) / bound)
    return out


def _threshold(z: np.ndarray, alpha: float) -> float:
    """``t`` whose expected Euler characteristic of ``{|Z| > t}`` is ``alpha`` (module doc)."""
    valid = np.isfinite(z)
    dz = np.diff(z, axis=0)
    dx = np.diff(z, axis=1)
    lz = float(np.nanmean(dz**2))
    lx = float(np.nanmean(dx**2))
    area = float(valid.sum())
    perimeter = 2.0 * (valid.any(axis=1).sum() + valid.any(axis=0).sum())

    def ec(t):
        two = area * math.sqrt(lx * lz) * t / (2 * math.pi) ** 1.5
        one = perimeter / 2 * math.sqrt(0.5 * (lx + lz)) / (2 * math.pi)
        return 2 * ((two + one) * math.exp(-t * t / 2) + 0.5 * special.erfc(t / math.sqrt(2)))

    return float(optimize.brentq(lambda t: ec(t) - alpha, 1.0, 20.0))


def _count_tail(ratio: float, n_exp: float, cells: float = math.inf) -> float:
    """``P(R <= ratio)`` (``ratio < 1``) or ``P(R >= ratio)``: ``R = (n/N) S`` the mean
    intensity over its expectation of ``n ~ Poisson(N = n_exp)`` scatterers, ``S`` the mean of
    ``cells`` independent speckle cells (gamma of mean 1 and shape ``cells``; infinite: 1)."""
    if not math.isfinite(n_exp):  # dense: the speckle alone
        below = special.gammainc(cells, cells * ratio) if math.isfinite(cells) else ratio >= 1
        return float(below if ratio < 1 else 1 - below)
    n = np.arange(1, math.ceil(n_exp + 12 * math.sqrt(n_exp) + 30))
    pmf = np.exp(n * math.log(n_exp) - n_exp - special.gammaln(n + 1))
    s = ratio * n_exp / n  # the speckle factor that count needs
    below = special.gammainc(cells, cells * s) if math.isfinite(cells) else (s >= 1) * 1.0
    if ratio < 1:
        return math.exp(-n_exp) + float(np.sum(pmf * below))  # no scatterer: the darkest
    return float(np.sum(pmf * (1 - below)))


def _count_significant(
    ratio: float,
    area: float,
    rho: float,
    t_eq: float,
    t: float,
    *,
    cells: float = math.inf,
    bound: float = math.nan,
) -> bool:
    """Whether an ellipse's pixels (``area`` µm^2 of them) whose mean intensity is ``ratio``
    times their host's is more than the host's Poisson count and its speckle can give.

    ``N = rho area t_eq`` kurtosis-equivalent scatterers are expected (``rho`` the host's
    identified density); a count ``n`` gives the mean intensity ``(n/N) S``, ``S`` the mean of
    ``cells`` speckle cells (:func:`_count_tail`; the interference of the ``n``). The
    probability of a ratio at most (``ratio < 1``) or at least the one seen, as a normal
    deviate, must exceed ``t`` (module docstring, Detection). ``rho`` NaN: a bright ellipse
    (``ratio >= 1``) is kept; a dark one (where the voids of a sparse host's Poisson process
    lie: every false alarm measured) is tested with the host's lower ``bound`` of the density
    (fewer scatterers: a wider count, a larger tail, so the test errs on the side of fewer
    detections), and without a bound it cannot be told from a void and is not significant.
    (The bound taken for bright ellipses too refused a true one: reduced patient 0, ``rho E``
    8.9 times its host's, whose bound was 11 times below the host's density.)"""
    if not np.isfinite(ratio):
        return True
    if not (np.isfinite(rho) and rho > 0):
        if ratio >= 1 or not bound > 0:
            return bool(ratio >= 1)
        rho = bound
    return bool(_count_tail(ratio, rho * area * t_eq, cells) < special.ndtr(-t))


def _detrended(r: np.ndarray) -> np.ndarray:
    """``r`` minus each line's running median over :data:`DETREND_ROWS` rows (NaN left out):
    the shadowing streaks, smooth along a line, go; an inclusion (shorter) stays."""
    half = DETREND_ROWS // 2
    pad = np.pad(r, ((half, half), (0, 0)), constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(pad, DETREND_ROWS, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows: NaN
        return r - np.nanmedian(windows, axis=-1)


def _smooth(r: np.ndarray, sigma: tuple[float, float]) -> np.ndarray:
    """Gaussian smoothing of ``r`` with NaN left out (normalised convolution), scaled so that
    white noise keeps one SD everywhere (near the edges and the left-out rows the kernel holds
    fewer pixels: its SD is ``sqrt(sum w^2)/sum w``, relative to the full kernel's)."""
    valid = np.isfinite(r)
    num = ndimage.gaussian_filter(np.where(valid, r, 0.0), sigma, mode="constant")
    den = ndimage.gaussian_filter(valid.astype(float), sigma, mode="constant")
    half = tuple(s / math.sqrt(2) for s in sigma)  # the squared Gaussian kernel's SD
    den2 = ndimage.gaussian_filter(valid.astype(float), half, mode="constant")
    # sum w^2 / (sum w)^2 relative to the full kernel's: (den2/den^2) / (1/1) with the squared
    # kernel normalised as the kernel is (both filters sum to one over the full support)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = num / den / np.sqrt(den2 / den**2)
    out[~valid | (den < 0.25)] = np.nan
    return out


def _standardised(s: np.ndarray) -> np.ndarray:
    """Each row of ``s`` (zero mean: the layer model is the rows' mean) over its RMS, the mean
    square over :data:`SD_ROWS` rows around it and every line (the shadowing streaks grow
    with depth), each square capped at 16 robust variances of its row (1.4826 MAD: an
    inclusion's pixels)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # rows left out: all NaN
        mad = 1.4826 * np.nanmedian(np.abs(s - np.nanmedian(s, axis=1, keepdims=True)), axis=1)
        sq = np.minimum(s**2, 16 * mad[:, None] ** 2)
        half = SD_ROWS // 2
        pad = np.pad(sq, ((half, half), (0, 0)), constant_values=np.nan)
        windows = np.lib.stride_tricks.sliding_window_view(pad, SD_ROWS, axis=0)
        var = np.nanmean(windows.reshape(s.shape[0], -1), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return s / np.sqrt(var)[:, None]


@dataclasses.dataclass(frozen=True)
class _Region:
    """A connected region: ``bbox`` (row0, col0, row1, col1), ``coords`` (pixels, 2),
    ``centroid`` (row, col)."""

    bbox: tuple[int, int, int, int]
    coords: np.ndarray
    centroid: tuple[float, float]


def _regions(mask: np.ndarray) -> list[_Region]:
    """Connected regions of ``mask`` (8-connectivity)."""
    labels, _ = ndimage.label(mask, structure=np.ones((3, 3), int))
    out = []
    for i, sl in enumerate(ndimage.find_objects(labels)):
        coords = np.argwhere(labels[sl] == i + 1) + np.array([sl[0].start, sl[1].start])
        out.append(
            _Region(
                (sl[0].start, sl[1].start, sl[0].stop, sl[1].stop),
                coords,
                tuple(coords.mean(axis=0)),
            )
        )
    return out


class _Geometry:
    """The ellipse's ``chi`` and ``L`` on a window of the scan (rows ``z``, lines ``x``):
    ``chi`` the share of the depth PSF's intensity (cumulative ``cdf``, pixels) inside the
    chord, ``L`` the chord's length above the row; both smoothed laterally (Gaussian of SD
    ``sigma_lines``: the double-pass weight)."""

    def __init__(self, z, x, p, sigma_lines, cdf):
        self.z, self.x, self.p, self.sigma, self.cdf = z, x, p, sigma_lines, cdf

    def basis(self, theta: np.ndarray) -> np.ndarray:
        xc, zc, w, h = theta
        u = np.clip(1 - ((self.x - xc) / w) ** 2, 0, None)
        top, bottom = zc - h * np.sqrt(u), zc + h * np.sqrt(u)  # (lines,)
        zz = self.z[:, None]
        chi = self.cdf((bottom - zz) / self.p) - self.cdf((top - zz) / self.p)
        chi = np.where(u > 0, chi, 0.0)
        ell = np.clip(np.minimum(zz, bottom) - top, 0, None)
        if self.sigma > 0:
            chi = ndimage.gaussian_filter1d(chi, self.sigma, axis=1, mode="nearest")
            ell = ndimage.gaussian_filter1d(ell, self.sigma, axis=1, mode="nearest")
        return np.stack([chi, ell])  # (2, rows, lines)


def _model(basis: np.ndarray, a: float, b: float) -> np.ndarray:
    """Mean ``ln I`` change: the intensities mixed (``ln(1 + (e^a - 1) chi)``), the shadow."""
    return np.log1p(np.expm1(a) * basis[0]) + b * basis[1]


def _profile_fit(geo: _Geometry, r: np.ndarray, valid: np.ndarray, theta: np.ndarray):
    """``(rss, (a, b))`` of the residual ``r`` on the valid pixels for the ellipse ``theta``
    (``a``, ``b`` by Gauss-Newton from the linear least squares of ``a chi + b L``)."""
    if theta[2] <= geo.p / 2 or theta[3] <= geo.p / 2:
        return np.inf, np.zeros(2)
    basis = geo.basis(theta)[:, valid]  # (2, pixels)
    if not np.any(basis[0] > 0.5):
        return np.inf, np.zeros(2)
    y = r[valid]
    coef, *_ = np.linalg.lstsq(basis.T, y, rcond=None)
    a, b = np.clip(coef[0], -8, 8), coef[1]
    for _ in range(6):
        mix = 1 + np.expm1(a) * basis[0]
        jac = np.stack([np.exp(a) * basis[0] / mix, basis[1]]).T
        step, *_ = np.linalg.lstsq(jac, y - np.log(mix) - b * basis[1], rcond=None)
        a, b = float(np.clip(a + step[0], -8, 8)), float(b + step[1])
        if abs(step[0]) < 1e-4:
            break
    res = y - _model(basis, a, b)
    return float(res @ res), np.array([a, b])


def _covariance(r: np.ndarray, quiet: np.ndarray, cells: int) -> tuple[dict, dict]:
    """Autocovariance of ``r`` on the ``quiet`` pixels: short lags ``(dz, dx)`` (|dz| <=
    SHORT_ROWS, |dx| <= cells) and the streaks' ``c_s(dx)`` (mean over dz in LAG..2 LAG)."""
    v = np.where(quiet, r, 0.0)
    m = quiet.astype(float)
    n_z, n_x = r.shape

    def cov(dz, dx):
        a = v[max(0, -dz) : n_z - max(0, dz), max(0, -dx) : n_x - max(0, dx)]
        b = v[max(0, dz) :, max(0, dx) :][: a.shape[0], : a.shape[1]]
        ma = m[max(0, -dz) : n_z - max(0, dz), max(0, -dx) : n_x - max(0, dx)]
        mb = m[max(0, dz) :, max(0, dx) :][: a.shape[0], : a.shape[1]]
        count = float(np.sum(ma * mb))
        return float(np.sum(a * b)) / count if count > 0 else 0.0

    short = {
        (dz, dx): cov(dz, dx)
        for dz in range(-SHORT_ROWS, SHORT_ROWS + 1)
        for dx in range(-cells, cells + 1)
    }
    streak = {
        dx: float(np.mean([cov(dz, dx) for dz in range(LAG, 2 * LAG + 1)]))
        for dx in range(-cells, cells + 1)
    }
    return short, streak


def _sandwich(jac: np.ndarray, short: dict, streak: dict, extra: np.ndarray | None = None):
    """``(J'J)^-1 J' S J (J'J)^-1`` with ``J`` ``(params, rows, lines)`` (0 off the window);
    ``extra`` is added to the meat (the layer model's error, :func:`_level_meat`)."""
    npar, n_z, n_x = jac.shape

    def cross(dz, dx):
        a = jac[:, max(0, -dz) : n_z - max(0, dz), max(0, -dx) : n_x - max(0, dx)]
        b = jac[:, max(0, dz) :, max(0, dx) :][:, : a.shape[1], : a.shape[2]]
        return np.einsum("izx,jzx->ij", a, b)

    col = jac.sum(axis=1)  # (params, lines)
    meat = np.zeros((npar, npar))
    for dx, cs in streak.items():
        a = col[:, max(0, -dx) : n_x - max(0, dx)]
        b = col[:, max(0, dx) :][:, : a.shape[1]]
        meat += cs * np.einsum("ix,jx->ij", a, b)
    for (dz, dx), c in short.items():
        meat += (c - streak[dx]) * cross(dz, dx)
    if extra is not None:
        meat = meat + extra
    flat = jac.reshape(npar, -1)
    bread = np.linalg.pinv(flat @ flat.T)
    return bread @ meat @ bread


def _level_meat(jac: np.ndarray, short: dict, streak: dict, n_row: np.ndarray) -> np.ndarray:
    """The layer model's own error in the sandwich's meat: the level at each row (a mean over
    ``n_row`` pixels of the row, outside the inclusions) enters every pixel of the row, so
    ``sum_{z,z'} u_z u_z' cov(level_z, level_z')`` with ``u`` the Jacobian's row sums and the
    levels' covariance the residual's summed over the lateral lags, over ``sqrt(n_z n_z')``:
    the streaks' at every row lag (constant down a line), the speckle's at the short lags."""
    npar, n_z, _ = jac.shape
    u = jac.sum(axis=2)  # (params, rows)
    inv = np.where(n_row > 0, 1 / np.sqrt(np.maximum(n_row, 1)), 0.0)
    all_streak = sum(streak.values())
    meat = np.zeros((npar, npar))
    for dz in range(-(n_z - 1), n_z):
        c = all_streak
        if abs(dz) <= SHORT_ROWS:
            c += sum(short[(dz, dx)] - streak[dx] for dx in streak)
        lo, hi = max(0, -dz), n_z - max(0, dz)
        a = u[:, lo:hi] * inv[lo:hi]
        b = u[:, lo + dz : hi + dz] * inv[lo + dz : hi + dz]
        meat += c * a @ b.T
    return meat


def fit_inclusions(
    li: np.ndarray,
    rows: np.ndarray,
    layers: xr.Dataset,
    cfg: ScannerConfig,
    x: np.ndarray,
    cdf,
    *,
    false_alarm: float = FALSE_ALARM,
    max_inclusions: int = MAX_INCLUSIONS,
) -> tuple[xr.Dataset, np.ndarray]:
    """Detect and fit inclusions in the central lines' ``ln I`` (module docstring).

    ``li`` (pixels, lines): every row of the central lines; ``rows``: the row indices the layer
    fit used (above the floor); ``layers``: the fit's Dataset (with its shape variables);
    ``x`` (µm): the central lines' positions; ``cdf``: the depth PSF's cumulative intensity
    (offsets in pixels, ``TransitionModel.cdf`` of ``_shapes``). Returns the Dataset of dim
    ``inclusion`` and the fitted inclusions' model of ``ln I`` (``a chi + b L``, pixels x lines:
    0 without).
    """
    p, pitch, r = cfg.pixel_size, cfg.line_pitch, cfg.beam_radius
    n_z, n_x = li.shape
    z = np.arange(n_z) * p
    coefficients = np.column_stack(
        [layers.top.values, layers.top_tilt.values, layers.top_curvature.values]
    )
    tops = profiles(coefficients, x, cfg.x_max)  # (layers, lines); row 0 the surface
    tops[0] = 0.0
    layer_of = np.sum(z[:, None, None] >= tops[None, 1:, :], axis=1)  # (rows, lines)
    top_of = tops[layer_of, np.arange(n_x)[None, :]]  # (rows, lines)
    depth_below = np.rint((z[:, None] - top_of) / p).astype(int)
    usable = np.zeros((n_z, n_x), bool)
    usable[rows] = True
    for k in range(1, tops.shape[0]):
        usable &= np.abs(z[:, None] - tops[k][None, :]) > EDGE * p
    cells = max(1.0, r / pitch)
    sigma = (SMOOTH_ROWS, SMOOTH_CELLS * cells)
    sigma_lines = r / 2 / pitch
    consts = slab_constants(r)
    cell_px = speckle_cell(cfg.n_pixels, r, pitch)  # pixels x lines of one speckle cell
    density_block = lines_per_block(DENSITY_BLOCK_RADII, cfg)
    a2, t_eq = consts["A2"], consts["t_eq"]
    key = layer_of * (n_z + 1) + np.clip(depth_below, 0, n_z)
    criterion = (
        f"connected regions of |Z| > t, Z the residual ln I smoothed ({SMOOTH_ROWS} rows, "
        f"{SMOOTH_CELLS} cells) over its row SD, t from the expected Euler characteristic "
        f"(false-alarm probability {false_alarm})"
    )

    def layer_model(mask, robust=False):
        """Mean ``ln I`` of each layer at each depth below its top (unmasked pixels); robust:
        the median plus the mean offset of the pixels from their median (an unfound
        inclusion's level step hardly moves a median)."""
        keep = usable & ~mask
        n_keys = (tops.shape[0]) * (n_z + 1)
        c = np.bincount(key[keep], minlength=n_keys)
        if robust:
            k, v = key[keep], li[keep]
            order = np.lexsort((v, k))
            first = np.concatenate([[0], np.cumsum(c)[:-1]])
            lo = first + np.maximum(c - 1, 0) // 2
            hi = first + c // 2
            sv = v[order]
            lo, hi = np.minimum(lo, sv.size - 1), np.minimum(hi, sv.size - 1)
            mid = np.where(c > 0, 0.5 * (sv[lo] + sv[hi]), np.nan)
            level = mid + np.mean(v - mid[k])
        else:
            with np.errstate(invalid="ignore", divide="ignore"):
                level = np.bincount(key[keep], li[keep], minlength=n_keys) / c
        out = level[key]
        out[~usable] = np.nan
        return out

    mask = np.zeros((n_z, n_x), bool)
    model = np.zeros((n_z, n_x))
    found, hosts = [], []
    attempts = 0
    while len(found) < max_inclusions and attempts < 2 * max_inclusions + 2:
        attempts += 1
        resid = li - layer_model(mask, robust=True) - model
        detrended = _detrended(resid)
        candidates, t = [], 0.0
        for scale in SCALES:  # each scale's share of the false alarm: 1/len(SCALES)
            zfield = _standardised(_smooth(detrended, (sigma[0] * scale, sigma[1] * scale)))
            zfield[mask] = np.nan  # an inclusion found (and its shadow) is not found again
            if not np.isfinite(zfield).any():
                continue
            t = max(t, _threshold(zfield, false_alarm / len(SCALES)))
            t_c = _threshold(zfield, CANDIDATE_REGIONS / len(SCALES))
            for sign in (1, -1):
                for reg in _regions(np.nan_to_num(sign * zfield) > t_c):
                    peak = float(np.max(np.abs(zfield[tuple(reg.coords.T)])))
                    candidates.append((peak / t_c, sign, reg))
        if not candidates:
            break
        # the most significant region; a shadow (its sign opposite to the inclusion's and
        # below it) gives way to the region of the other sign above it
        peak, sign, reg = max(candidates, key=lambda c: c[0])
        above = [
            c for c in candidates
            if c[1] != sign and c[2].bbox[0] < reg.bbox[0]
            and c[2].bbox[1] < reg.bbox[3] and reg.bbox[1] < c[2].bbox[3]
        ]  # fmt: skip
        if above:
            peak, sign, reg = min(above, key=lambda c: c[2].bbox[0])
        r0, c0, r1, c1 = reg.bbox
        half_x = max((c1 - c0) / 2 * pitch, 2 * pitch)
        half_z = max((r1 - r0) / 2 * p, 2 * p)
        lines = np.arange(max(0, c0 - (c1 - c0) - 6), min(n_x, c1 + (c1 - c0) + 6))
        rws = np.arange(max(0, r0 - (r1 - r0) - 6), n_z)
        geo = _Geometry(z[rws], x[lines], p, sigma_lines, cdf)
        rr = resid[np.ix_(rws, lines)]
        valid = np.isfinite(rr)
        xc0 = float(x[round(reg.centroid[1])])
        starts = [
            np.array([xc0, z[r0] + f * half_z, half_x * g, f * half_z])
            for f in (1.0, 1.5)
            for g in (1.0, 1.5)
        ]
        # a coarse grid of larger and shifted ellipses: a region of |Z| often covers only part
        # of a faint ellipse (its top half, one side), whose starts stop in a smaller minimum
        grid = [
            np.array([xc0 + dx * half_x, z[r0] + f * g * half_z, gw * half_x, g * half_z])
            for dx in GRID_SHIFTS
            for gw in GRID_SCALES
            for g in GRID_SCALES
            for f in (0.5, 1.0, 1.5)
        ]
        ranked = sorted(
            grid, key=lambda th, geo=geo, rr=rr, valid=valid: _profile_fit(geo, rr, valid, th)[0]
        )
        starts += ranked[:GRID_STARTS]
        best = None
        for s0 in starts:
            res = optimize.minimize(
                lambda th, geo=geo, rr=rr, valid=valid: min(
                    _profile_fit(geo, rr, valid, th)[0], 1e30
                ),
                s0,
                method="Nelder-Mead",
                options={"xatol": 0.05, "fatol": 1e-3, "maxiter": 600},
            )
            if best is None or res.fun < best.fun:
                best = res
        theta = best.x
        # again with the layer model taken without this inclusion's lines (the first model's
        # row means held its level step and shadow)
        trial = geo.basis(theta)
        hit = np.zeros((n_z, n_x), bool)
        hit[np.ix_(rws, lines)] = (trial[0] > 0.01) | (np.abs(trial[1]) > 0.01 * p)
        resid = li - layer_model(mask | hit) - model
        rr = resid[np.ix_(rws, lines)]
        valid = np.isfinite(rr)
        theta = optimize.minimize(
            lambda th, geo=geo, rr=rr, valid=valid: min(_profile_fit(geo, rr, valid, th)[0], 1e30),
            theta,
            method="Nelder-Mead",
            options={"xatol": 0.05, "fatol": 1e-3, "maxiter": 600},
        ).x
        rss, (a, b) = _profile_fit(geo, rr, valid, theta)
        if not np.isfinite(rss):
            break
        # Jacobian of the model (geometry numerically, a and b exact) on the window
        params = np.append(theta, [a, b])

        def full(par, geo=geo):
            return _model(geo.basis(par[:4]), par[4], par[5])

        jac = []
        for i in range(6):
            step = np.zeros(6)
            step[i] = 0.25 * (p if i in (1, 3) else pitch) if i < 4 else 1e-3
            jac.append((full(params + step) - full(params - step)) / (2 * step[i]))
        jac = np.where(valid[None], np.stack(jac), 0.0)
        basis = geo.basis(theta)
        footprint = np.zeros((n_z, n_x), bool)
        footprint[np.ix_(rws, lines)] = (basis[0] > 0.01) | (np.abs(basis[1]) > 0.01 * p)
        quiet = np.isfinite(resid) & ~footprint & ~mask
        quiet[: rws[0]] = False
        short, streak = _covariance(np.where(quiet, resid, 0.0), quiet, math.ceil(cells))
        keep = usable & ~mask & ~hit
        counts = np.bincount(key[keep], minlength=tops.shape[0] * (n_z + 1))[key]
        n_row = np.median(counts[np.ix_(rws, lines)], axis=1)
        cov = _sandwich(jac, short, streak, _level_meat(jac, short, streak, n_row))
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
        if not abs(a) > t * se[4]:  # the level step itself not significant: not an inclusion
            mask[tuple(reg.coords.T)] = True
            continue
        xc, zc, w, h = theta
        host = int(np.sum(zc >= profiles(coefficients[1:], [xc], cfg.x_max)[:, 0]))
        # the ellipse's mean intensity over its host's at the same rows (linear in the count)
        inside = np.zeros((n_z, n_x), bool)
        inside[np.ix_(rws, lines)] = (basis[0] > 0.5) & valid
        level_rows = inside.any(axis=1)
        host_px = usable & ~mask & ~footprint & level_rows[:, None]
        ratio = float(np.mean(np.exp(li[inside])) / np.mean(np.exp(li[host_px])))
        rho_h, bound_h = (float(layers[v].values[host]) for v in ("density", "density_bound"))
        if not np.isfinite(layers.log_variance.values[host]):  # no var ln I: the kurtosis
            own = usable & ~mask & ~footprint & (layer_of == host)
            bound_h = kurtosis_density(np.where(own, np.exp(li), np.nan), cfg,
                                       block_lines=density_block)[2]  # fmt: skip
        n_in = np.count_nonzero(inside)  # the pixels the ratio is measured on
        area, m = n_in * p * pitch, n_in / cell_px
        if not _count_significant(ratio, area, rho_h, t_eq, t, cells=m, bound=bound_h):
            mask[tuple(reg.coords.T)] = True  # a void (or cluster) of the host's scatterers
            continue
        re_h = float(layers.rho_e.values[host])
        re_h_se = float(layers.rho_e_se.values[host])
        rho_e = re_h * math.exp(a)
        rho_e_se = rho_e * math.hypot(se[4], re_h_se / re_h)
        shadow = re_h - b / 2 / a2
        model_b = np.zeros((n_z, n_x))  # the inclusion's own shadow, off its speckle
        model_b[np.ix_(rws, lines)] = b * basis[1]
        shadow_se = math.hypot(re_h_se, se[5] / 2 / a2)
        found.append(
            {
                "centre_x": xc, "centre_x_se": se[0], "centre_z": zc, "centre_z_se": se[1],
                "axis_x": abs(w), "axis_x_se": se[2], "axis_z": abs(h), "axis_z_se": se[3],
                "rho_e": rho_e, "rho_e_se": rho_e_se,
                "rho_e_shadow": shadow, "rho_e_shadow_se": shadow_se,
                **inclusion_density(li - model - model_b, z, theta, x, cfg, rho_e, rho_e_se),
                "log_contrast": a, "log_contrast_se": se[4],
                "shadow_step": -b / 2, "shadow_step_se": se[5] / 2,
                "significance": abs(a) / se[4],
            }
        )  # fmt: skip
        hosts.append(host)
        model[np.ix_(rws, lines)] += _model(basis, a, b)
        mask |= footprint
    return _dataset(found, hosts, criterion), model
