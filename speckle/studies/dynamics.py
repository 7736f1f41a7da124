"""Where flow contrasts fail: failure maps of flow detection and the decorrelation calibration.

A repeated B-scan (the angiography protocol) of ``n_frames`` frames ``interval`` s apart gives,
at each pixel, a stack of complex fields ``A_t = S_t + n_t``: the speckle field of the moving
scatterers plus circular Gaussian receiver noise of intensity ``I_n = I_s/SNR``, independent
from frame to frame. For developed speckle (a circular Gaussian field) every flow contrast is a
function of the pairwise field correlations of the frames,

``rho_ij = s |g1((j - i) interval)|``, ``s = SNR/(1 + SNR)``,

with ``g1`` the motion's field autocorrelation (transverse flow at velocity ``v`` through the
Gaussian beam of waist ``w0``: ``g1(tau) = exp(-(v tau)^2/w0^2)``). The three contrasts studied
here, and their expectations (derived in ``docs/explanation/dynamics_failure.md``), with
``mu_ij = rho_ij^2`` and ``<.>`` the mean over the ``N (N-1)/2`` pairs of frames:

* **speckle variance** (``speckle_variance``): the temporal variance of the intensity over the
  ``N`` frames (``1/N``), over the expected intensity squared ``(I_s + I_n)^2``:
  ``E = (N-1)/N (1 - <mu_ij>)`` (``Cov(I_i, I_j) = mu_ij <I>^2``, Siegert);
* **decorrelation** (``decorrelation``): one minus the amplitude correlation of adjacent frames,
  ``1 - sum A_t A_t+1 / sum (A_t^2 + A_t+1^2)/2`` (sums over the pairs and the pixels of a
  window, the full-band form of SSADA): ``E = 1 - (pi/4) 2F1(-1/2, -1/2; 1; mu_1)``;
* **logarithmic intensity variance** (``liv``, the Tsukuba group's LIV): the temporal variance
  of ``10 log10 I`` (``1/N``): ``E = (10/ln 10)^2 (N-1)/N (pi^2/6 - <Li2(mu_ij)>)``, since
  ``Cov(ln I_i, ln I_j) = Li2(mu_ij)`` for correlated speckle (Laguerre expansion of the
  bivariate exponential law).

The **static-tissue floor** of a contrast is its value for ``g1 = 1`` (static scatterers, the
frames differ by their noise only): ``(N-1)/N (1 - s^2)``, ``1 - (pi/4) 2F1(.., s^2)`` and
``(10/ln 10)^2 (N-1)/N (pi^2/6 - Li2(s^2))``, zero without noise. The **noise floor** is its
value where the frames are uncorrelated (``rho = 0``: noise alone, or flow fast enough to
decorrelate completely): ``(N-1)/N``, ``1 - pi/4`` and ``(10/ln 10)^2 (N-1)/N pi^2/6``. A
contrast detects flow above the first and measures velocity only below the second: the
**velocity range** of a contrast is where its mean in a window of pixels stands ``z`` window
standard deviations above the static floor and below the noise floor.

:func:`flow_failure` simulates it over velocity, SNR and inter-frame time (shared 2-D scenes
imaged by the scanned Gaussian beam, receiver noise at each SNR, independent repeats for the
standard errors) and :func:`decorrelation_calibration` draws the decorrelation against
velocity with its theory.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr
from scipy import special

from .._validate import as_finite_array, check_choice, check_int, check_real
from ..conventions import attrs, coord, units_of
from ..imaging.scan import beam_reach, image
from ..imaging.truth import speckle_free_image
from ..scene.regions import background, cell_density, make_regions
from ..scene.shared import shared_scene
from ..system.noise import add_noise
from ..system.source import spectrum
from .failure import mean_and_se

__all__ = [
    "FLOW_CONTRASTS",
    "contrast_estimates",
    "contrast_floors",
    "decorrelation_calibration",
    "expected_contrast",
    "flow_failure",
    "transverse_flow_g1",
    "velocity_range",
]

#: Flow contrasts of the failure maps.
FLOW_CONTRASTS = ("speckle_variance", "decorrelation", "liv")
#: ``(10/ln 10)^2``: dB^2 per (natural log)^2.
_DB2 = (10.0 / math.log(10.0)) ** 2
#: Status codes of the failure maps.
BELOW_FLOOR, MEASURABLE, SATURATED = 0, 1, 2


def transverse_flow_g1(velocity: object, lag: object, *, waist: float) -> np.ndarray:
    """``|g1|`` of transverse flow through the Gaussian beam: ``exp(-(v tau)^2/w0^2)``.

    The double-pass beam weight ``exp(-2 r^2/w0^2)`` of scatterers displaced by ``d = v tau``
    overlaps itself by ``exp(-d^2/w0^2)`` (uniform scatterers, independent phases).

    Parameters
    ----------
    velocity : array_like
        Lateral velocity ``v`` in µm/s.
    lag : array_like
        Time lag ``tau`` in s (>= 0), broadcast against ``velocity``.
    waist : float
        Beam waist ``w0`` in µm (> 0).

    Returns
    -------
    numpy.ndarray
        ``|g1|`` (dimensionless).

    Examples
    --------
    >>> float(transverse_flow_g1(1000.0, 0.008, waist=8.0))  # d = w0
    0.36787944117144233
    """
    v = as_finite_array(velocity, "velocity")
    t = as_finite_array(lag, "lag")
    if np.any(t < 0):
        raise ValueError("lag must be >= 0 s")
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    return np.exp(-((v * t / w0) ** 2))


def _signal_fraction(snr_db: float) -> float:
    """``s = SNR/(1 + SNR)``: the field correlation of two frames of one static pixel."""
    snr = _snr(snr_db)
    return 1.0 if math.isinf(snr) else 1.0 / (1.0 + 10.0 ** (-snr / 10.0))


def _snr(snr_db: object) -> float:
    """SNR in dB: a real number in [-300, 300], or +inf (no noise)."""
    if isinstance(snr_db, int | float | np.floating) and np.isposinf(snr_db):
        return math.inf
    return check_real(snr_db, "snr_db", low=-300.0, high=300.0)


def expected_contrast(contrast: str, g1: object, *, snr_db: float = math.inf) -> float:
    """Expected flow contrast of ``N`` frames of developed speckle with receiver noise.

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast (module docstring: normalised intensity variance, adjacent-frame
        amplitude decorrelation, log-intensity variance in dB^2).
    g1 : array_like
        ``|g1|`` of the motion at frame lags ``1 ... N-1`` (``N - 1 >= 1`` values in [0, 1]).
    snr_db : float
        Receiver SNR ``I_s/I_n`` in dB (``inf``: no noise).

    Returns
    -------
    float
        The expectation (dimensionless; dB^2 for ``liv``).

    Examples
    --------
    >>> round(expected_contrast("decorrelation", [0.0]), 6)  # 1 - pi/4
    0.214602
    """
    check_choice(contrast, "contrast", FLOW_CONTRASTS)
    g = np.atleast_1d(as_finite_array(g1, "g1"))
    if g.ndim != 1 or g.size < 1 or np.any((g < 0) | (g > 1)):
        raise ValueError("g1 must hold |g1| in [0, 1] at frame lags 1 ... N-1 (N >= 2 frames)")
    s = _signal_fraction(snr_db)
    n = g.size + 1
    mu = (s * g) ** 2  # mu at lag m = 1 ... N-1
    if contrast == "decorrelation":
        return float(1.0 - math.pi / 4.0 * special.hyp2f1(-0.5, -0.5, 1.0, mu[0]))
    pairs = n - np.arange(1, n)  # pairs of frames at lag m
    if contrast == "speckle_variance":
        cov, var = mu, 1.0
    else:
        cov, var = _DB2 * special.spence(1.0 - mu), _DB2 * math.pi**2 / 6.0  # Li2(mu)
    mean_cov = float(np.sum(pairs * cov) / np.sum(pairs))
    return (n - 1) / n * (var - mean_cov)


def contrast_floors(contrast: str, *, n_frames: int, snr_db: float) -> tuple[float, float]:
    """The static-tissue floor and the noise floor of a contrast (module docstring).

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast.
    n_frames : int
        Frames ``N`` (>= 2).
    snr_db : float
        Receiver SNR in dB.

    Returns
    -------
    (float, float)
        Expected contrast of static tissue (``g1 = 1``) and of uncorrelated frames (``g1 = 0``:
        noise alone, or flow decorrelating completely between frames).

    Examples
    --------
    >>> contrast_floors("speckle_variance", n_frames=4, snr_db=float("inf"))
    (0.0, 0.75)
    """
    n = check_int(n_frames, "n_frames", low=2)
    static = expected_contrast(contrast, np.ones(n - 1), snr_db=snr_db)
    noise = expected_contrast(contrast, np.zeros(n - 1), snr_db=snr_db)
    return static, noise


def velocity_range(
    contrast: str,
    *,
    n_frames: int,
    interval: float,
    snr_db: float,
    waist: float,
    low: float,
    high: float,
) -> tuple[float, float]:
    """Velocities (µm/s) at which the expected contrast of transverse flow reaches two levels.

    The contrast rises monotonically with velocity from the static floor to the noise floor;
    the velocity range a contrast can measure is between the velocity at which it first stands
    clear of the static floor (``low``) and the one at which it comes within reach of the noise
    floor (``high``), e.g. ``static + z sd`` and ``noise - z sd`` for window values of standard
    deviation ``sd`` (:func:`flow_failure`).

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast.
    n_frames : int
        Frames ``N`` (>= 2).
    interval : float
        Time between frames in s (> 0).
    snr_db : float
        Receiver SNR in dB.
    waist : float
        Beam waist ``w0`` in µm (> 0).
    low, high : float
        Contrast levels (the contrast's units).

    Returns
    -------
    (float, float)
        ``(v_low, v_high)`` in µm/s; NaN where a level lies outside the floors (``v_low`` NaN:
        flow is never told from static tissue; ``v_high`` NaN: the contrast never comes that
        close to the noise floor, or the range is empty).

    Examples
    --------
    >>> lo, hi = velocity_range("decorrelation", n_frames=4, interval=1e-3, snr_db=40.0,
    ...                         waist=8.0, low=0.05, high=0.2)
    >>> round(lo), round(hi)
    (2762, 9127)
    """
    n = check_int(n_frames, "n_frames", low=2)
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    lo_level = check_real(low, "low")
    hi_level = check_real(high, "high")
    static, noise = contrast_floors(contrast, n_frames=n, snr_db=snr_db)
    lags = np.arange(1, n)

    def value(u: float) -> float:  # u = v dt/w0
        return expected_contrast(contrast, np.exp(-((u * lags) ** 2)), snr_db=snr_db)

    def solve(level: float) -> float:
        if not static < level < noise:
            return math.nan
        from scipy.optimize import brentq

        hi = 1.0
        while value(hi) < level:
            hi *= 2.0
            if hi > 1e3:
                return math.nan
        return brentq(lambda u: value(u) - level, 0.0, hi, xtol=1e-12) * w0 / dt

    v_lo, v_hi = solve(lo_level), solve(hi_level)
    if not (math.isfinite(v_lo) and math.isfinite(v_hi) and v_lo < v_hi):
        v_hi = math.nan
    return v_lo, v_hi


# --- estimators on frame stacks ----------------------------------------------------------------


def _blocks(values: np.ndarray, window: tuple[int, int]) -> np.ndarray:
    """Sum over non-overlapping ``window`` blocks of the last two axes (the rest dropped)."""
    wz, wx = window
    nz, nx = values.shape[-2] // wz, values.shape[-1] // wx
    v = values[..., : nz * wz, : nx * wx]
    return v.reshape(*v.shape[:-2], nz, wz, nx, wx).sum(axis=(-3, -1))


def contrast_estimates(
    contrast: str, field: object, *, window: tuple[int, int], intensity: float | None = None
) -> tuple[float, np.ndarray]:
    """A flow contrast of a stack of frames: its region value and its window values.

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast (module docstring).
    field : array_like of complex, shape (frame, depth, x)
        The complex frames of one region (>= 2 frames).
    window : (int, int)
        Window (pixels x lines) of one contrast value, >= 1 each and within the frames.
    intensity : float, optional
        Expected intensity ``I_s + I_n`` normalising the speckle variance (required there).

    Returns
    -------
    (float, numpy.ndarray)
        The contrast of the whole region (pixel mean; for ``decorrelation`` the ratio of the
        region's sums, whose bias is O(1/pixels)) and its values on non-overlapping windows.
    """
    check_choice(contrast, "contrast", FLOW_CONTRASTS)
    a = np.asarray(field)
    if not np.iscomplexobj(a) or a.ndim != 3 or a.shape[0] < 2:
        raise ValueError("field must be complex frames (frame, depth, x) with >= 2 frames")
    wz = check_int(window[0], "window[0]", low=1, high=a.shape[1])
    wx = check_int(window[1], "window[1]", low=1, high=a.shape[2])
    inten = np.abs(a) ** 2
    if contrast == "decorrelation":
        amp = np.sqrt(inten)
        num = np.sum(amp[1:] * amp[:-1], axis=0)
        den = np.sum(0.5 * (inten[1:] + inten[:-1]), axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            windows = 1.0 - _blocks(num, (wz, wx)) / _blocks(den, (wz, wx))
            return float(1.0 - num.sum() / den.sum()), windows.ravel()
    if contrast == "speckle_variance":
        if intensity is None:
            raise ValueError("intensity (the expected I_s + I_n, > 0) is required")
        ref = check_real(intensity, "intensity", low=0, low_inclusive=False)
        per_pixel = inten.var(axis=0) / ref**2
    else:
        with np.errstate(divide="ignore"):
            per_pixel = (10.0 * np.log10(inten)).var(axis=0)
    windows = _blocks(per_pixel, (wz, wx)) / (wz * wx)
    return float(per_pixel.mean()), windows.ravel()


# --- simulation --------------------------------------------------------------------------------


def _phantom(geometry: dict, seed: int, max_shift: float) -> dict:
    """A homogeneous 2-D shared scene wide enough for every shift, its spectrum and lines.

    Equal amplitudes: the non-Gaussian (finite-density) part of the intensity covariance,
    ``E|a|^4/(E|a|^2)^2`` over the scatterers per resolution cell, is half the Rayleigh one.
    """
    n = int(geometry["n_pixels"])
    p = float(geometry["pixel_size"])
    pitch = float(geometry.get("pitch", p))
    w0 = float(geometry["waist"])
    src = spectrum(n, n * p, k0_dk=float(geometry["k0_dk"]))
    lines = np.arange(int(geometry["n_lines"])) * pitch
    reach = beam_reach(w0)
    rho = cell_density(float(geometry["density"]), p, pitch)
    scene = shared_scene(
        make_regions(background(density=rho, amplitude_model="equal")),
        z_range=(0.0, n * p),
        x_range=(lines[0] - max_shift - reach, lines[-1] + reach + pitch),
        seed=seed,
        tile=float(geometry.get("tile", 64.0)),
    )
    return {"scene": scene, "source": src, "lines": lines, "waist": w0}


def _kw(geometry: dict) -> dict:
    method = geometry.get("method", "finufft")
    tol = geometry.get("tol", 1e-9) if method != "direct" else None
    return {"method": method, "tol": tol}


def _frames(ph: dict, shifts: np.ndarray, kw: dict) -> np.ndarray:
    """Complex frames of the scene translated by ``shifts`` (µm, along +x): (frame, depth, x).

    A scene translated by ``d`` images as the scene at lines ``x - d`` (the beam sees the same
    relative positions), exactly.
    """
    out = [
        image(ph["scene"], ph["source"], waist=ph["waist"], x=ph["lines"] - d, **kw).field.values
        for d in shifts
    ]
    return np.stack(out)


def _noise(shape: tuple, seed: int) -> np.ndarray:
    """Unit circular complex Gaussian noise per frame (white; :func:`speckle.add_noise`)."""
    ds = xr.Dataset({"field": (("frame", "depth", "x"), np.zeros(shape, complex))})
    return add_noise(ds, 0.0, seed=seed, signal_intensity=1.0).noise.values


def _rows(geometry: dict) -> slice:
    """Depth rows analysed: away from the scene's top and bottom (the PSF is cut there)."""
    m = int(geometry.get("margin", 4))
    return slice(m, int(geometry["n_pixels"]) - m)


def _repeat_seeds(seed: int, repeats: int) -> list[tuple[int, int]]:
    """(scene seed, noise seed) of each repeat, from ``SeedSequence(seed)``."""
    out = []
    for r in range(repeats):
        a, b = np.random.SeedSequence(seed, spawn_key=(r,)).generate_state(2)
        out.append((int(a), int(b)))
    return out


def _check_geometry(geometry: object) -> dict:
    if not isinstance(geometry, dict):
        raise TypeError("geometry must be a dict (n_pixels, n_lines, pixel_size, ...)")
    g = dict(geometry)
    check_int(g.get("n_pixels"), "geometry.n_pixels", low=8)
    check_int(g.get("n_lines"), "geometry.n_lines", low=2)
    for key in ("pixel_size", "waist", "density", "k0_dk"):
        check_real(g.get(key), f"geometry.{key}", low=0, low_inclusive=False)
    m = check_int(g.get("margin", 4), "geometry.margin", low=0)
    if 2 * m >= int(g["n_pixels"]) - 1:
        raise ValueError("geometry.margin leaves fewer than 2 rows (need 2 margin < n_pixels - 1)")
    return g


def _positive_sorted(values: object, name: str, *, low: float = 0.0) -> np.ndarray:
    v = np.atleast_1d(as_finite_array(values, name))
    if v.ndim != 1 or v.size == 0 or np.any(v < low) or np.any(np.diff(v) <= 0):
        raise ValueError(f"{name} must be a non-empty increasing 1-D list of values >= {low}")
    return v


def flow_failure(
    geometry: dict,
    *,
    velocities: Sequence[float],
    snr_db: Sequence[float],
    intervals: Sequence[float],
    n_frames: int,
    window: tuple[int, int],
    repeats: int,
    seed: int,
    z: float = 2.0,
) -> xr.Dataset:
    """Failure maps of flow detection over velocity, SNR and inter-frame time, with floors.

    Each repeat draws a homogeneous 2-D shared scene (``geometry``), images ``n_frames``
    frames of it in transverse flow (frame ``t`` translated by ``v t interval`` along ``x``)
    for every velocity and interval, adds receiver noise at every SNR (the same unit noise,
    scaled), and computes each contrast on the analysed rows: its mean over the region and its
    values on ``window`` blocks. Static tissue (no motion) and noise alone (no signal) give
    the two floors, measured the same way.

    Parameters
    ----------
    geometry : dict
        ``n_pixels``, ``n_lines``, ``pixel_size`` (µm, also the pitch unless ``pitch``),
        ``k0_dk``, ``waist`` (µm), ``density`` (scatterers per pixel x pitch cell), optional
        ``margin`` (rows left out at the top and bottom, default 4), ``method``/``tol`` of the
        beam scan (default ``finufft``, 1e-9) and ``tile`` (µm).
    velocities : sequence of float
        Flow velocities in µm/s (>= 0, increasing).
    snr_db : sequence of float
        Receiver SNRs in dB (increasing).
    intervals : sequence of float
        Times between frames in s (> 0, increasing).
    n_frames : int
        Frames per measurement (>= 2).
    window : (int, int)
        Pixels x lines of one window value.
    repeats : int
        Independent scenes and noises (>= 2): the standard errors.
    seed : int
        Root seed (non-negative).
    z : float
        Window standard deviations a contrast must stand off each floor (> 0).

    Returns
    -------
    xarray.Dataset
        Over ``(contrast, velocity, snr_db, interval)``: ``measured`` and ``measured_se`` (the
        region mean over repeats), ``theory``, ``status`` (0 below the static floor's band,
        1 measurable, 2 within the noise floor's band); over ``(contrast, snr_db)``:
        ``static_floor``, ``noise_floor`` (measured, ``_se``, ``_theory``) and the window
        standard deviations ``static_sd``, ``noise_sd``; over ``(contrast, snr_db,
        interval)``: ``v_low``, ``v_high`` (theory, µm/s, from the theory floors +- ``z`` sd).

    Examples
    --------
    >>> geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0,
    ...            density=4.0, margin=2)
    >>> ds = flow_failure(geo, velocities=[0.0, 5000.0], snr_db=[20.0], intervals=[1e-3],
    ...                   n_frames=3, window=(2, 2), repeats=2, seed=1)
    >>> ds.measured.dims
    ('contrast', 'velocity', 'snr_db', 'interval')
    """
    g = _check_geometry(geometry)
    vel = _positive_sorted(velocities, "velocities")
    snrs = np.atleast_1d(as_finite_array(snr_db, "snr_db"))
    if snrs.ndim != 1 or snrs.size == 0 or np.any(np.diff(snrs) <= 0):
        raise ValueError("snr_db must be a non-empty increasing 1-D list (dB)")
    for i, s in enumerate(snrs):
        check_real(float(s), f"snr_db[{i}]", low=-300.0, high=300.0)
    dts = _positive_sorted(intervals, "intervals")
    if dts[0] <= 0:
        raise ValueError("intervals must be > 0 s")
    nf = check_int(n_frames, "n_frames", low=2)
    nr = check_int(repeats, "repeats", low=2)
    sd = check_int(seed, "seed", low=0)
    zz = check_real(z, "z", low=0, low_inclusive=False)
    if not isinstance(window, Sequence) or len(window) != 2:
        raise ValueError(f"window must be (pixels, lines), got {window!r}")
    rows = _rows(g)
    kw = _kw(g)
    max_shift = float(vel[-1] * dts[-1] * (nf - 1))
    nc, nv, ns, ni = len(FLOW_CONTRASTS), vel.size, snrs.size, dts.size
    flow = np.full((nc, nv, ns, ni, nr), np.nan)
    static = np.full((nc, ns, nr), np.nan)
    noise = np.full((nc, ns, nr), np.nan)
    static_w: list[list[list[np.ndarray]]] = [[[] for _ in range(ns)] for _ in range(nc)]
    noise_w: list[list[list[np.ndarray]]] = [[[] for _ in range(ns)] for _ in range(nc)]
    for r, (scene_seed, noise_seed) in enumerate(_repeat_seeds(sd, nr)):
        ph = _phantom(g, scene_seed, max_shift)
        i_s = _signal_intensity(ph, g, kw)
        cache: dict[float, np.ndarray] = {}
        frame0 = _frames(ph, np.zeros(1), kw)[0]
        unit = _noise((nf, *frame0.shape), noise_seed)
        for k, snr in enumerate(snrs):
            i_n = i_s / 10.0 ** (snr / 10.0)
            noisy_static = frame0[None] + math.sqrt(i_n) * unit
            for c, name in enumerate(FLOW_CONTRASTS):
                val, win = contrast_estimates(
                    name, noisy_static[:, rows], window=window, intensity=i_s + i_n
                )
                static[c, k, r] = val
                static_w[c][k].append(win)
                val, win = contrast_estimates(
                    name, math.sqrt(i_n) * unit[:, rows], window=window, intensity=i_n
                )
                noise[c, k, r] = val
                noise_w[c][k].append(win)
        for j, dt in enumerate(dts):
            for i, v in enumerate(vel):
                shifts = v * dt * np.arange(nf)
                frames = []
                for d in shifts:
                    key = round(float(d), 9)
                    if key not in cache:
                        cache[key] = _frames(ph, np.array([d]), kw)[0]
                    frames.append(cache[key])
                stack = np.stack(frames)
                for k, snr in enumerate(snrs):
                    i_n = i_s / 10.0 ** (snr / 10.0)
                    noisy = (stack + math.sqrt(i_n) * unit)[:, rows]
                    for c, name in enumerate(FLOW_CONTRASTS):
                        flow[c, i, k, j, r] = contrast_estimates(
                            name, noisy, window=window, intensity=i_s + i_n
                        )[0]
    m, se = mean_and_se(flow)
    sm, sse = mean_and_se(static)
    nm, nse = mean_and_se(noise)
    ssd = np.array([[np.std(np.concatenate(static_w[c][k])) for k in range(ns)] for c in range(nc)])
    nsd = np.array([[np.std(np.concatenate(noise_w[c][k])) for k in range(ns)] for c in range(nc)])
    theory = np.empty((nc, nv, ns, ni))
    floors_t = np.empty((2, nc, ns))
    v_low = np.full((nc, ns, ni), np.nan)
    v_high = np.full((nc, ns, ni), np.nan)
    lags = np.arange(1, nf)
    for c, name in enumerate(FLOW_CONTRASTS):
        for k, snr in enumerate(snrs):
            floors_t[:, c, k] = contrast_floors(name, n_frames=nf, snr_db=float(snr))
            lo = floors_t[0, c, k] + zz * ssd[c, k]
            hi = floors_t[1, c, k] - zz * nsd[c, k]
            for j, dt in enumerate(dts):
                for i, v in enumerate(vel):
                    g1 = transverse_flow_g1(v, lags * dt, waist=g["waist"])
                    theory[c, i, k, j] = expected_contrast(name, g1, snr_db=float(snr))
                v_low[c, k, j], v_high[c, k, j] = velocity_range(
                    name,
                    n_frames=nf,
                    interval=float(dt),
                    snr_db=float(snr),
                    waist=g["waist"],
                    low=lo,
                    high=hi,
                )
    lo_band = (sm + zz * ssd)[:, None, :, None]
    hi_band = (nm - zz * nsd)[:, None, :, None]
    status = np.where(m <= lo_band, BELOW_FLOOR, np.where(m >= hi_band, SATURATED, MEASURABLE))
    dims4 = ("contrast", "velocity", "snr_db", "interval")
    dims2 = ("contrast", "snr_db")
    dims3 = ("contrast", "snr_db", "interval")
    one = attrs("dimensionless", "flow contrast (liv in dB^2)")
    ds = xr.Dataset(
        {
            "measured": (dims4, m, one),
            "measured_se": (dims4, se, attrs("dimensionless", "standard error over repeats")),
            "theory": (dims4, theory, attrs("dimensionless", "expected contrast (theory)")),
            "status": (
                dims4,
                status.astype(np.int8),
                attrs("label", "0 below the static floor, 1 measurable, 2 at the noise floor"),
            ),
            "static_floor": (dims2, sm, attrs("dimensionless", "static-tissue floor")),
            "static_floor_se": (dims2, sse, attrs("dimensionless", "its standard error")),
            "static_floor_theory": (dims2, floors_t[0], attrs("dimensionless", "derived")),
            "static_sd": (dims2, ssd, attrs("dimensionless", "window sd, static tissue")),
            "noise_floor": (dims2, nm, attrs("dimensionless", "noise floor")),
            "noise_floor_se": (dims2, nse, attrs("dimensionless", "its standard error")),
            "noise_floor_theory": (dims2, floors_t[1], attrs("dimensionless", "derived")),
            "noise_sd": (dims2, nsd, attrs("dimensionless", "window sd, noise alone")),
            "v_low": (dims3, v_low, attrs("velocity", "lowest measurable velocity (theory)")),
            "v_high": (dims3, v_high, attrs("velocity", "highest measurable velocity (theory)")),
        },
        coords={
            "contrast": ("contrast", list(FLOW_CONTRASTS)),
            "velocity": coord("velocity", vel),
            "snr_db": ("snr_db", snrs, attrs("level", "receiver SNR")),
            "interval": coord("time", dts, "time between frames", dims="interval"),
        },
    )
    return ds.assign_attrs(_meta(g, nf, window, nr, sd) | {"z": zz})


def _signal_intensity(ph: dict, g: dict, kw: dict) -> float:
    """Expected signal intensity ``E|A|^2`` of the analysed rows (speckle-free image)."""
    truth = speckle_free_image(ph["scene"], ph["source"], waist=ph["waist"], x=ph["lines"], **kw)
    return float(truth.values[_rows(g)].mean())


def _meta(g: dict, nf: int, window: tuple, nr: int, sd: int) -> dict:
    k0 = float(g["k0_dk"]) * math.pi / float(g["pixel_size"])  # k0 = k0_dk * N pi / H
    return {
        "n_pixels": int(g["n_pixels"]),
        "n_lines": int(g["n_lines"]),
        "pixel_size": float(g["pixel_size"]),
        "pitch": float(g.get("pitch", g["pixel_size"])),
        "waist": float(g["waist"]),
        "waist_units": units_of("length"),
        "k0": k0,
        "k0_units": units_of("wavenumber"),
        "density": float(g["density"]),
        "n_frames": nf,
        "window": list(int(w) for w in window),
        "repeats": nr,
        "seed": sd,
        "motion": "transverse flow along +x (uniform), frames translated by v t interval",
        "contrasts": "speckle_variance: var_t(I)/<I>^2 (1/N); decorrelation: 1 - sum A_t "
        "A_t+1 / sum (A_t^2 + A_t+1^2)/2; liv: var_t(10 log10 I) in dB^2 (1/N)",
    }


def decorrelation_calibration(
    geometry: dict,
    *,
    velocities: Sequence[float],
    interval: float,
    snr_db: float,
    n_frames: int,
    repeats: int,
    seed: int,
) -> xr.Dataset:
    """Decorrelation of adjacent frames against transverse-flow velocity, with its theory.

    Parameters
    ----------
    geometry : dict
        As in :func:`flow_failure`.
    velocities : sequence of float
        Velocities in µm/s (>= 0, increasing).
    interval : float
        Time between frames in s (> 0).
    snr_db : float
        Receiver SNR in dB (``inf``: no noise).
    n_frames : int
        Frames (>= 2): ``n_frames - 1`` adjacent pairs per repeat.
    repeats : int
        Independent scenes and noises (>= 2).
    seed : int
        Root seed.

    Returns
    -------
    xarray.Dataset
        Over ``velocity``: ``decorrelation`` (mean over repeats of the region value),
        ``decorrelation_se`` and ``theory`` ``1 - (pi/4) 2F1(-1/2, -1/2; 1; s^2 g1^2)`` with
        ``g1 = exp(-(v interval)^2/w0^2)``; attrs: the geometry, ``interval``, ``snr_db``.

    Examples
    --------
    >>> geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0,
    ...            density=4.0, margin=2)
    >>> ds = decorrelation_calibration(geo, velocities=[0.0, 8000.0], interval=1e-3,
    ...                                snr_db=40.0, n_frames=2, repeats=2, seed=0)
    >>> round(float(ds.theory[1]), 3)
    0.188
    """
    g = _check_geometry(geometry)
    vel = _positive_sorted(velocities, "velocities")
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    snr = _snr(snr_db)
    nf = check_int(n_frames, "n_frames", low=2)
    nr = check_int(repeats, "repeats", low=2)
    sd = check_int(seed, "seed", low=0)
    rows, kw = _rows(g), _kw(g)
    out = np.full((vel.size, nr), np.nan)
    for r, (scene_seed, noise_seed) in enumerate(_repeat_seeds(sd, nr)):
        ph = _phantom(g, scene_seed, float(vel[-1] * dt * (nf - 1)))
        i_s = _signal_intensity(ph, g, kw)
        i_n = 0.0 if math.isinf(snr) else i_s / 10.0 ** (snr / 10.0)
        unit = None
        for i, v in enumerate(vel):
            stack = _frames(ph, v * dt * np.arange(nf), kw)
            if unit is None:
                unit = _noise(stack.shape, noise_seed)
            noisy = (stack + math.sqrt(i_n) * unit)[:, rows]
            out[i, r] = contrast_estimates("decorrelation", noisy, window=(1, 1))[0]
    m, se = mean_and_se(out)
    theory = [
        expected_contrast(
            "decorrelation", transverse_flow_g1(v, [dt], waist=g["waist"]), snr_db=snr
        )
        for v in vel
    ]
    ds = xr.Dataset(
        {
            "decorrelation": ("velocity", m, attrs("dimensionless", "amplitude decorrelation")),
            "decorrelation_se": ("velocity", se, attrs("dimensionless", "standard error")),
            "theory": ("velocity", np.array(theory), attrs("dimensionless", "theory")),
        },
        coords={"velocity": coord("velocity", vel)},
    )
    meta = _meta(g, nf, (1, 1), nr, sd)
    meta.pop("window")
    return ds.assign_attrs(
        meta | {"interval": dt, "interval_units": units_of("time"), "snr_db": snr}
    )
