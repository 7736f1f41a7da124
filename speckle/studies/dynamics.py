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
* **decorrelation** (``decorrelation``): the amplitude decorrelation of adjacent frames,
  ``1 - mean of A_t A_t+1 / ((A_t^2 + A_t+1^2)/2)`` per pixel (SSADA of one band,
  :func:`speckle.analysis.dynamics.ssada_array`):
  ``E = 1 - (E(mu_1) - (1 - mu_1) K(mu_1))/mu_1`` (complete elliptic integrals,
  :func:`speckle.analysis.dynamics_theory.ssada_expected`); split into sub-bands it is
  the same for transverse flow;
* **logarithmic intensity variance** (``liv``, the Tsukuba group's LIV): the temporal variance
  of ``10 log10 I`` (``1/N``): ``E = (10/ln 10)^2 (N-1)/N (pi^2/6 - <Li2(mu_ij)>)``, since
  ``Cov(ln I_i, ln I_j) = Li2(mu_ij)`` for correlated speckle (Laguerre expansion of the
  bivariate exponential law).

The **static-tissue floor** of a contrast is its value for ``g1 = 1`` (static scatterers, the
frames differ by their noise only): ``(N-1)/N (1 - s^2)``, ``ssada_expected([s])`` and
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
from scipy.optimize import brentq

from .._validate import as_finite_array, check_choice, check_int, check_memory, check_real
from ..analysis.dynamics import (
    liv_array,
    speckle_variance_array,
    ssada_array,
)
from ..analysis.dynamics_theory import (
    g1_transverse_flow,
    liv_expected,
    speckle_variance_expected,
    ssada_expected,
)
from ..conventions import attrs, coord, units_of
from ..imaging.scan import scan_image
from ..system.noise import add_noise
from ._flow import (
    analysed_rows,
    check_geometry,
    homogeneous_phantom,
    run_attrs,
    scan_options,
    signal_fraction,
    signal_intensity,
    snr_value,
)
from .failure import mean_and_se

__all__ = [
    "FLOW_CONTRASTS",
    "contrast_estimates",
    "contrast_floors",
    "decorrelation_calibration",
    "expected_contrast",
    "flow_failure",
    "velocity_range",
]

#: Flow contrasts of the failure maps.
FLOW_CONTRASTS = ("speckle_variance", "decorrelation", "liv")
#: Status codes of the failure maps.
BELOW_FLOOR, MEASURABLE, SATURATED = 0, 1, 2


def expected_contrast(contrast: str, g1: object, *, snr_db: float = math.inf) -> float:
    """Expected flow contrast of ``N`` frames of developed speckle with receiver noise.

    The frames' total fields correlate as ``rho_m = s |g1(m interval)|`` (``s = SNR/(1 + SNR)``,
    white noise independent between frames); the speckle variance and LIV follow from
    :func:`speckle.analysis.dynamics_theory.speckle_variance_expected` and
    :func:`~speckle.analysis.dynamics_theory.liv_expected` (``ddof = 0``) of ``rho``, the
    decorrelation from :func:`~speckle.analysis.dynamics_theory.ssada_expected` of ``rho_1``.

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast (module docstring: intensity variance over ``(I_s + I_n)^2``,
        adjacent-frame amplitude decorrelation, log-intensity variance in dB^2).
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
    rho = np.r_[1.0, signal_fraction(snr_db) * g]
    if contrast == "decorrelation":
        return ssada_expected([rho[1]])
    if contrast == "speckle_variance":
        return speckle_variance_expected(rho, ddof=0)
    return liv_expected(rho, ddof=0)


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
    (1611, 7921)
    """
    n = check_int(n_frames, "n_frames", low=2)
    check_memory(64.0 * n, "n_frames", "the expected contrast at every lag")
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


def contrast_estimates(
    contrast: str, field: object, *, window: tuple[int, int], intensity: float | None = None
) -> tuple[float, np.ndarray]:
    """A flow contrast of a stack of frames: its region value and its window values.

    The estimators are those of :mod:`speckle.analysis.dynamics`:
    :func:`~speckle.analysis.dynamics.speckle_variance_array` (over ``intensity^2``),
    :func:`~speckle.analysis.dynamics.ssada_array` of one band (the full-band amplitude
    decorrelation of adjacent frames) and :func:`~speckle.analysis.dynamics.liv_array`, all
    with ``ddof = 0``.

    Parameters
    ----------
    contrast : {"speckle_variance", "decorrelation", "liv"}
        The contrast (module docstring).
    field : array_like of complex, shape (frame, depth, x)
        The complex frames of one region (>= 2 frames).
    window : (int, int)
        Boxcar (pixels x lines) of one contrast value, >= 1 each and within the frames.
    intensity : float, optional
        Expected intensity ``I_s + I_n`` normalising the speckle variance (required there).

    Returns
    -------
    (float, numpy.ndarray)
        The contrast's mean over the region's pixels, and its boxcar values at every pixel
        (their spread is that of one window's value).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.ones((3, 4, 4), complex)
    >>> contrast_estimates("decorrelation", f, window=(2, 2))[0]
    0.0
    """
    check_choice(contrast, "contrast", FLOW_CONTRASTS)
    a = np.asarray(field)
    if not np.iscomplexobj(a) or a.ndim != 3 or a.shape[0] < 2:
        raise ValueError("field must be complex frames (frame, depth, x) with >= 2 frames")
    if not isinstance(window, Sequence) or len(window) != 2:
        raise ValueError(f"window must be (pixels, lines), got {window!r}")
    w = (
        check_int(window[0], "window[0]", low=1, high=a.shape[1]),
        check_int(window[1], "window[1]", low=1, high=a.shape[2]),
    )
    if contrast == "decorrelation":
        amp = np.abs(a)[None]
        return float(ssada_array(amp)), ssada_array(amp, window=w).ravel()
    inten = np.abs(a) ** 2
    if contrast == "liv":
        return float(liv_array(inten)), liv_array(inten, window=w).ravel()
    if intensity is None:
        raise ValueError("intensity (the expected I_s + I_n, > 0) is required")
    ref = check_real(intensity, "intensity", low=0, low_inclusive=False) ** 2
    return (
        float(speckle_variance_array(inten)) / ref,
        speckle_variance_array(inten, window=w).ravel() / ref,
    )


# --- simulation --------------------------------------------------------------------------------


def _frames(ph: dict, shifts: np.ndarray, kw: dict) -> np.ndarray:
    """Complex frames of the scene translated by ``shifts`` (µm, along +x): (frame, depth, x).

    A scene translated by ``d`` images as the scene at lines ``x - d`` (the beam sees the same
    relative positions), exactly.
    """
    out = [
        scan_image(
            ph["scene"], ph["source"], waist=ph["waist"], lines=ph["lines"] - d, **kw
        ).field.values
        for d in shifts
    ]
    return np.stack(out)


def _noise(shape: tuple, seed: int) -> np.ndarray:
    """Unit circular complex Gaussian noise per frame (white; :func:`speckle.add_noise`)."""
    ds = xr.Dataset({"field": (("frame", "depth", "x"), np.zeros(shape, complex))})
    return add_noise(ds, 0.0, seed=seed, signal_intensity=1.0).noise.values


def _repeat_seeds(seed: int, repeats: int) -> list[tuple[int, int]]:
    """(scene seed, noise seed) of each repeat, from ``SeedSequence(seed)``."""
    out = []
    for r in range(repeats):
        a, b = np.random.SeedSequence(seed, spawn_key=(r,)).generate_state(2)
        out.append((int(a), int(b)))
    return out


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
    g = check_geometry(geometry)
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
    rows = analysed_rows(g)
    kw = scan_options(g)
    max_shift = float(vel[-1] * dts[-1] * (nf - 1))
    nc, nv, ns, ni = len(FLOW_CONTRASTS), vel.size, snrs.size, dts.size
    flow = np.full((nc, nv, ns, ni, nr), np.nan)
    static = np.full((nc, ns, nr), np.nan)
    noise = np.full((nc, ns, nr), np.nan)
    static_w: list[list[list[np.ndarray]]] = [[[] for _ in range(ns)] for _ in range(nc)]
    noise_w: list[list[list[np.ndarray]]] = [[[] for _ in range(ns)] for _ in range(nc)]
    for r, (scene_seed, noise_seed) in enumerate(_repeat_seeds(sd, nr)):
        ph = homogeneous_phantom(g, scene_seed, max_shift)
        i_s = signal_intensity(ph, g, kw)
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
                    g1 = g1_transverse_flow(lags * dt, velocity=v, waist=g["waist"])
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
    return ds.assign_attrs(run_attrs(g, nf, window, nr, sd) | {"z": zz})


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
        ``decorrelation_se`` and ``theory`` (``ssada_expected`` of ``s g1``) with
        ``g1 = exp(-(v interval)^2/w0^2)``; attrs: the geometry, ``interval``, ``snr_db``.

    Examples
    --------
    >>> geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0,
    ...            density=4.0, margin=2)
    >>> ds = decorrelation_calibration(geo, velocities=[0.0, 8000.0], interval=1e-3,
    ...                                snr_db=40.0, n_frames=2, repeats=2, seed=0)
    >>> round(float(ds.theory[1]), 3)
    0.201
    """
    g = check_geometry(geometry)
    vel = _positive_sorted(velocities, "velocities")
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    snr = snr_value(snr_db)
    nf = check_int(n_frames, "n_frames", low=2)
    nr = check_int(repeats, "repeats", low=2)
    sd = check_int(seed, "seed", low=0)
    rows, kw = analysed_rows(g), scan_options(g)
    out = np.full((vel.size, nr), np.nan)
    for r, (scene_seed, noise_seed) in enumerate(_repeat_seeds(sd, nr)):
        ph = homogeneous_phantom(g, scene_seed, float(vel[-1] * dt * (nf - 1)))
        i_s = signal_intensity(ph, g, kw)
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
            "decorrelation", g1_transverse_flow([dt], velocity=v, waist=g["waist"]), snr_db=snr
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
    meta = run_attrs(g, nf, (1, 1), nr, sd)
    meta.pop("window")
    return ds.assign_attrs(
        meta | {"interval": dt, "interval_units": units_of("time"), "snr_db": snr}
    )
