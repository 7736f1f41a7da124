"""Theory of speckle in time: expected g1, g2, Doppler phase, speckle variance, LIV and OCDS.

The field of a pixel is ``A = sum_j a_j W(x_j - X) h(z_j - z_q)``: the double-pass beam weight
``W(r) = exp(-2 r^2/w0^2)`` (:func:`speckle.beam_scan`, ``w0`` the one-way 1/e^2 intensity
radius) times the axial PSF ``h(z) = sum_n S_n exp(2i k_n z)`` (``k_n`` in the medium). With
the scatterers a Poisson process of uniform density and each displaced by ``d_j`` in ``tau``,
``E[A*(t) A(t+tau)] / E|A|^2 = E_d[ G_z(d_z) G_x(d_x) [G_y(d_y)] ]`` with

* ``G_z(d) = sum_n S_n^2 exp(2i k_n d) / sum_n S_n^2`` (the coherence gate; Parseval over the
  period ``H``, exact for a periodic scene) ``-> exp(2i k0 d)`` for a narrow band;
* ``G_x(d) = int W(x) W(x + d) dx / int W^2 dx = exp(-d^2/w0^2)`` (completing the square:
  ``2x^2 + 2xd + d^2 = 2(x + d/2)^2 + d^2/2``), the same along ``y`` in a 3-D scene.

Averaging over the displacement distribution of each model gives the functions below
(``q = 2 k0``):

* Brownian, ``d ~ N(0, 2 D tau)`` per axis: ``E exp(2i k d_z) = exp(-4 k^2 D tau)`` =
  ``exp(-q^2 D tau)`` and ``E exp(-d_x^2/w0^2) = (1 + 4 D tau/w0^2)^(-1/2)`` per lateral axis;
* ballistic, Gaussian velocities ``N(0, sigma^2)`` per axis: ``exp(-q^2 sigma^2 tau^2/2)`` and
  ``(1 + 2 sigma^2 tau^2/w0^2)^(-1/2)``; constant speed: the average over isotropic directions;
* transverse flow ``v``: ``exp(-(v tau)^2/w0^2)``; axial flow: ``G_z(v tau)``, whose phase is
  the Doppler shift ``2 k0 v_z tau`` and whose modulus the coherence-gate decay.

Circular Gaussian fields (developed speckle) then give: Siegert ``g2 = 1 + beta |g1|^2``; the
intensity covariance ``<I>^2 |g1|^2``; the log-intensity covariance ``Li2(|g1|^2)`` (Kibble's
bivariate exponential in Laguerre polynomials, ``int e^-I L_k(I) ln I dI = -1/k``, so
``cov(ln I1, ln I2) = sum_k |g1|^(2k)/k^2``; ``Li2(1) = pi^2/6`` the variance of ``ln I``).
The expected time variance over ``N`` frames (``ddof = 0``) of a quantity with variance
``v`` and lag covariances ``c_m`` is ``v (1 - 1/N) - (2/N^2) sum_{m=1}^{N-1} (N - m) c_m``:
:func:`speckle_variance_expected` (``c_m = |g1_m|^2`` in units of ``<I>^2``),
:func:`liv_expected` (``(10/ln 10)^2 Li2(|g1_m|^2)``). :func:`ocds_expected` is the slope of
the least-squares line through ``Li2(|g1|^2)/Li2(1)`` (linear in the data, so the expected
slope of the estimate is the slope of the expected correlation). For SSADA's amplitude ratio,
``u = I1/(I1 + I2)`` of the bivariate exponential has the density ``(1 - m)/(1 - 4 m u (1 -
u))^(3/2)`` (``m = |g1|^2``; integrate ``S exp(-aS) I0(bS)`` over ``S = I1 + I2``), so
``E[2 sqrt(I1 I2)/(I1 + I2)] = (E(m) - (1 - m) K(m))/m`` (complete elliptic integrals,
parameter ``m``; ``pi/4`` at ``m = 0``, 1 at ``m = 1``): :func:`ssada_expected`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import ellipe, ellipk, spence

from .._validate import as_finite_array, check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ._common import delay_selection

__all__ = [
    "doppler_shift",
    "g1_axial_flow",
    "g1_ballistic",
    "g1_brownian",
    "g1_transverse_flow",
    "liv_expected",
    "log_intensity_correlation",
    "ocds_expected",
    "siegert_g2",
    "speckle_variance_expected",
    "ssada_expected",
    "ssada_ratio",
]

#: ``(10/ln 10)^2``: the variance of ``10 log10 I`` per unit variance of ``ln I`` (dB^2).
DB2 = float((10.0 / np.log(10.0)) ** 2)


#: Lags in s (real, finite, non-empty; the sign is checked by :func:`_lags`) and
#: correlations (real or complex: ``|g1|`` is used), checked by the decorator.
_LAG = ArraySpec(kind="real")
_G1 = ArraySpec(kind="number")


def _lags(lag: np.ndarray, name: str = "lag") -> np.ndarray:
    """The decorator-checked lags as floats, refused by ``name`` when negative."""
    t = np.asarray(lag, dtype=float)
    if np.any(t < 0):
        raise ValueError(f"{name} must be >= 0 s")
    return t


def _band(spectrum: xr.DataArray | None, k0: float) -> tuple[np.ndarray, np.ndarray]:
    """Wavenumbers and normalised weights ``S_n^2/sum S^2`` (one line at ``k0`` without)."""
    if spectrum is None:
        return np.array([k0]), np.array([1.0])
    if not isinstance(spectrum, xr.DataArray) or "wavenumber" not in spectrum.coords:
        raise TypeError("spectrum must be a DataArray from speckle.spectrum")
    if spectrum.size == 0:
        raise ValueError("spectrum must hold at least one wavenumber, got an empty spectrum")
    k0s = float(spectrum.attrs.get("k0", np.nan))
    if not np.isclose(k0s, k0, rtol=1e-9):
        raise ValueError(f"k0 = {k0:g} rad/µm differs from the spectrum's k0 = {k0s:g} rad/µm")
    w = as_finite_array(spectrum.values, "spectrum") ** 2
    if not w.sum() > 0:
        raise ValueError("spectrum must have some power (all its weights are zero)")
    return np.asarray(spectrum.wavenumber.values, float), w / w.sum()


def _k0(k0: object) -> float:
    """``k0`` (rad/µm, >= 0), given or read from the spectrum by the decorator."""
    if k0 is None:
        raise TypeError("k0 is needed (rad/µm in the medium): give k0= or spectrum= (its k0)")
    return check_real(k0, "k0", low=0)


def _lateral(var: np.ndarray, waist: float | None, axes: int) -> np.ndarray:
    """``E exp(-d^2/w0^2)`` per lateral axis for ``d ~ N(0, var)``, to the power ``axes``."""
    if waist is None:
        return np.ones_like(var)
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    return (1.0 + 2.0 * var / w0**2) ** (-axes / 2.0)


@preprocess_and_wrap(checks={"lag": _LAG}, from_grid={"k0": "spectrum"})
def g1_brownian(
    lag: object,
    *,
    diffusion: float,
    k0: float | None = None,
    spectrum: xr.DataArray | None = None,
    waist: float | None = None,
    lateral_axes: int = 1,
) -> np.ndarray:
    """Field autocorrelation of Brownian motion, ``exp(-q^2 D tau)``, ``q = 2 k0``.

    Parameters
    ----------
    lag : array_like
        Time lags ``tau`` in s (>= 0).
    diffusion : float
        ``D`` in µm^2/s (>= 0).
    k0 : float, optional
        Central wavenumber in the medium, rad/µm (>= 0; ``n k_vacuum``). Read from
        ``spectrum`` when given (a value given as well must agree with it); required without.
    spectrum : xarray.DataArray, optional
        The source spectrum (:func:`speckle.spectrum`, same ``k0``): the axial factor becomes
        the ``S_n^2``-weighted mean of ``exp(-4 k_n^2 D tau)`` (exact for the sampled band).
    waist : float, optional
        Beam waist ``w0`` in µm: multiplies by ``(1 + 4 D tau/w0^2)^(-lateral_axes/2)``, the
        lateral displacements through the beam (module docstring). None: axial only.
    lateral_axes : int
        Lateral axes that move (1 in a 2-D scene, 2 in 3-D), with ``waist``.

    Returns
    -------
    numpy.ndarray
        Real ``g1(tau)``, shape of ``lag``.

    Examples
    --------
    >>> float(g1_brownian(0.5, diffusion=1.0, k0=1.0))  # exp(-4 * 0.5)
    0.1353352832366127
    """
    t = _lags(lag)
    d = check_real(diffusion, "diffusion", low=0)
    k = _k0(k0)
    ax = check_int(lateral_axes, "lateral_axes", low=0, high=2)
    kn, w = _band(spectrum, k)
    axial = np.tensordot(np.exp(-4.0 * np.multiply.outer(t, kn**2) * d), w, axes=([-1], [0]))
    return axial * _lateral(2.0 * d * t, waist, ax)


@preprocess_and_wrap(checks={"g1": _G1})
def siegert_g2(g1: object, *, beta: float = 1.0) -> np.ndarray:
    """Intensity autocorrelation of circular Gaussian speckle, ``1 + beta |g1|^2``.

    ``beta`` in ``[0, 1]`` (1: one polarised, fully developed speckle pattern per pixel).

    Examples
    --------
    >>> float(siegert_g2(0.5))
    1.25
    """
    g = np.abs(g1)
    b = check_real(beta, "beta", low=0, high=1)
    return 1.0 + b * g**2


@preprocess_and_wrap(checks={"lag": _LAG}, from_grid={"k0": "spectrum"})
def g1_ballistic(
    lag: object,
    *,
    speed: float,
    k0: float | None = None,
    ndim: int,
    distribution: str = "gaussian",
    waist: float | None = None,
    spectrum: xr.DataArray | None = None,
) -> np.ndarray:
    """Field autocorrelation of random ballistic motion (:func:`speckle.ballistic_motion`).

    Parameters
    ----------
    lag : array_like
        ``tau`` in s.
    speed : float
        µm/s: the rms speed (``"gaussian"``, each component ``N(0, speed^2/ndim)``) or every
        scatterer's speed (``"constant"``).
    k0 : float, optional
        rad/µm in the medium. Read from ``spectrum`` when given (a value given as well must
        agree with it); required without.
    ndim : int
        Axes that move: 1 (independent lines, depth only), 2 or 3 (shared scenes).
    distribution : {"gaussian", "constant"}
        As in :func:`speckle.ballistic_motion`.
    waist : float, optional
        Beam waist (µm) for the lateral factor (``ndim - 1`` lateral axes).
    spectrum : xarray.DataArray, optional
        Source spectrum (same ``k0``): the axial factor averaged over ``k_n`` with weights
        ``S_n^2`` (exact for the sampled band).

    Returns
    -------
    numpy.ndarray
        Real ``g1(tau)``: Gaussian ``exp(-q^2 sigma^2 tau^2/2) (1 + 2 sigma^2 tau^2/w0^2)^
        (-(ndim-1)/2)``, ``sigma^2 = speed^2/ndim``; for constant speed the average of
        ``cos(q s tau u_z) exp(-(s tau)^2 (1 - u_z^2)/w0^2)`` over isotropic directions
        (``cos``, ``J0`` and ``sin(x)/x`` without the beam, in 1, 2 and 3-D).

    Examples
    --------
    >>> round(float(g1_ballistic(1.0, speed=1.0, k0=0.5, ndim=1)), 6)  # exp(-1/2)
    0.606531
    """
    t = _lags(lag)
    s = check_real(speed, "speed", low=0)
    k = _k0(k0)
    nd = check_int(ndim, "ndim", low=1, high=3)
    check_choice(distribution, "distribution", ("gaussian", "constant"))
    kn, wn = _band(spectrum, k)
    if distribution == "gaussian":
        var = (s * t) ** 2 / nd
        axial = np.tensordot(np.exp(-2.0 * np.multiply.outer(var, kn**2)), wn, axes=([-1], [0]))
        return axial * _lateral(var, waist, nd - 1)
    w2 = np.inf if waist is None else check_real(waist, "waist", low=0, low_inclusive=False) ** 2
    d = s * t[..., None]
    if nd == 1:
        uz, wt = np.array([1.0]), np.array([1.0])
    elif nd == 2:
        th = 2 * np.pi * (np.arange(512) + 0.5) / 512  # periodic trapezoid: spectral accuracy
        uz, wt = np.cos(th), np.full(512, 1 / 512)
    else:
        uz, wt = np.polynomial.legendre.leggauss(256)  # u_z = cos(theta) uniform on [-1, 1]
        wt = wt / 2
    lat = np.exp(-(d**2) * (1 - uz**2) / w2) * wt
    return sum(
        w * np.sum(np.cos(2.0 * kk * d * uz) * lat, axis=-1) for kk, w in zip(kn, wn, strict=True)
    )


@preprocess_and_wrap(checks={"lag": _LAG})
def g1_transverse_flow(lag: object, *, velocity: float, waist: float) -> np.ndarray:
    """Field autocorrelation of uniform flow across the beam, ``exp(-(v tau)^2/w0^2)``.

    ``velocity`` (µm/s) is the speed perpendicular to the beam (in the B-scan plane or
    through it), ``waist`` the project's ``w0`` (µm; the double-pass amplitude weight is
    ``exp(-2 r^2/w0^2)``, so the field correlation falls to 1/e at ``v tau = w0``).

    Examples
    --------
    >>> round(float(g1_transverse_flow(1.0, velocity=2.0, waist=2.0)), 6)
    0.367879
    """
    t = _lags(lag)
    v = check_real(velocity, "velocity")
    w0 = check_real(waist, "waist", low=0, low_inclusive=False)
    return np.exp(-((v * t) ** 2) / w0**2)


@preprocess_and_wrap(checks={"lag": _LAG})
def g1_axial_flow(lag: object, *, velocity: float, spectrum: xr.DataArray) -> np.ndarray:
    """Complex field autocorrelation of uniform axial flow through the coherence gate.

    ``G_z(v tau) = sum_n S_n^2 exp(2i k_n v tau) / sum_n S_n^2`` (``v > 0``: deeper). Its
    phase is the Doppler shift ``2 k0 v tau`` (:func:`doppler_shift`) for a band symmetric
    about ``k0``; its modulus falls as the scatterers cross the coherence length (for a
    Gaussian spectrum of FWHM ``F``: ``exp(-F^2 (v tau)^2/(8 ln 2))``).

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10)
    >>> abs(complex(g1_axial_flow(0.0, velocity=1.0, spectrum=src)))
    1.0
    """
    t = _lags(lag)
    v = check_real(velocity, "velocity")
    if not isinstance(spectrum, xr.DataArray) or "k0" not in spectrum.attrs:
        raise TypeError("spectrum must be a DataArray from speckle.spectrum")
    kn, w = _band(spectrum, float(spectrum.attrs["k0"]))
    return np.tensordot(np.exp(2j * np.multiply.outer(t * v, kn)), w, axes=([-1], [0]))


@preprocess_and_wrap(checks={"lag": _LAG})
def doppler_shift(lag: object, *, velocity: float, k0: float) -> np.ndarray:
    """Doppler phase shift ``2 k0 v_z tau`` in rad (not wrapped; ``v_z > 0`` deeper).

    Examples
    --------
    >>> float(doppler_shift(1e-4, velocity=1000.0, k0=5.0))
    1.0
    """
    t = _lags(lag)
    v = check_real(velocity, "velocity")
    k = check_real(k0, "k0", low=0)
    return 2.0 * k * v * t


def _g1_series(g1: object) -> np.ndarray:
    g = np.abs(g1)
    if g.ndim != 1 or g.size < 2:
        raise ValueError(
            "g1 must be a finite 1-D sequence of |g1| at lags 0, dt, ..., (N-1) dt (N >= 2)"
        )
    if np.any(g > 1 + 1e-12):
        raise ValueError("|g1| must be at most 1")
    return np.minimum(g, 1.0)


def _time_variance(cov: np.ndarray, ddof: int) -> float:
    """Expected ``var_t`` (``ddof``) over ``N`` frames of lag covariances ``cov[0..N-1]``."""
    n = cov.size
    d = check_int(ddof, "ddof", low=0, high=1)
    m = np.arange(1, n)
    e = cov[0] * (1 - 1 / n) - 2.0 / n**2 * np.sum((n - m) * cov[1:])
    return float(e * n / (n - d))


@preprocess_and_wrap(checks={"g1": _G1})
def log_intensity_correlation(g1: object) -> np.ndarray:
    """Correlation of ``ln I`` (or ``I`` in dB) of developed speckle, ``Li2(|g1|^2)/Li2(1)``.

    Examples
    --------
    >>> float(log_intensity_correlation(1.0))
    1.0
    """
    g = np.abs(g1)
    return spence(1.0 - np.minimum(g, 1.0) ** 2) / (np.pi**2 / 6.0)


@preprocess_and_wrap(checks={"g1": _G1})
def speckle_variance_expected(g1: object, *, ddof: int = 0) -> float:
    """Expected speckle variance over ``N`` frames, in units of ``<I>^2``.

    ``g1``: ``|g1|`` at lags ``0, dt, ..., (N-1) dt`` (``g1[0] = 1``); ``ddof`` 0 or 1 as in
    :func:`speckle.analysis.dynamics.speckle_variance`. Uncorrelated frames: ``1 - 1/N``
    (``ddof=0``); a static scene: 0.

    Examples
    --------
    >>> speckle_variance_expected([1.0, 0.0, 0.0, 0.0])
    0.75
    """
    g = _g1_series(g1)
    return _time_variance(g**2, ddof)


@preprocess_and_wrap(checks={"g1": _G1})
def liv_expected(g1: object, *, ddof: int = 0) -> float:
    """Expected LIV (dB^2) of developed speckle over ``N`` frames from ``|g1|`` at its lags.

    ``E[LIV] = (10/ln 10)^2 [ (1 - 1/N) pi^2/6 - (2/N^2) sum_m (N - m) Li2(|g1(m dt)|^2) ]``
    (``ddof=0``; module docstring). Uncorrelated frames: ``(1 - 1/N) 31.0 dB^2``.

    Examples
    --------
    >>> round(liv_expected([1.0, 0.0]), 3)  # half of (10/ln10)^2 pi^2/6
    15.513
    """
    g = _g1_series(g1)
    return DB2 * _time_variance(spence(1.0 - g**2), ddof)


@preprocess_and_wrap(checks={"g1": _G1, "lags": _LAG})
def ocds_expected(g1: object, lags: object, *, delays: tuple[float, float]) -> float:
    """Expected OCDS (1/s): minus the least-squares slope of ``Li2(|g1|^2)/Li2(1)`` on ``tau``.

    Parameters
    ----------
    g1 : array_like
        ``|g1|`` at ``lags``.
    lags : array_like
        Lags in s (same shape).
    delays : (float, float)
        The delay range ``[tau1, tau2]`` (s) of the fit, as in
        :func:`speckle.analysis.dynamics.ocds`; at least two lags inside.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(4) * 0.01
    >>> abs(ocds_expected(np.ones(4), t, delays=(0.01, 0.03))) < 1e-9  # no decay
    True
    """
    g = np.abs(g1)
    t = _lags(lags, "lags")
    if g.shape != t.shape or g.ndim != 1:
        raise ValueError(f"g1 and lags must be 1-D of one shape, got {g.shape}, {t.shape}")
    sel = delay_selection(t, delays)
    rho = log_intensity_correlation(g[sel])
    return -float(np.polyfit(t[sel], rho, 1)[0])


@preprocess_and_wrap(checks={"g1": _G1})
def ssada_ratio(g1: object) -> np.ndarray:
    """``E[2 A1 A2/(A1^2 + A2^2)]`` of two developed speckle amplitudes of field correlation
    ``g1``: ``(E(m) - (1 - m) K(m))/m``, ``m = |g1|^2`` (``pi/4`` at 0, 1 at ``|g1| = 1``).

    Examples
    --------
    >>> round(float(ssada_ratio(0.0)), 6)
    0.785398
    """
    m = np.minimum(np.abs(g1) ** 2, 1.0)
    small = m < 1e-8
    mm = np.where(small, 0.5, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (ellipe(mm) - (1 - mm) * ellipk(mm)) / mm
    r = np.where(m >= 1.0, 1.0, r)
    return np.where(small, np.pi / 4 * (1 + m / 8), r)


@preprocess_and_wrap(checks={"g1_bands": _G1})
def ssada_expected(g1_bands: object) -> float:
    """Expected SSADA decorrelation of developed speckle from each sub-band's ``|g1|``.

    ``D = 1 - mean_b E[2 A_b(t) A_b(t+dt)/(A_b(t)^2 + A_b(t+dt)^2)]``, the expectation
    :func:`ssada_ratio` of each band at the frame interval ``dt`` (module docstring): 0 for a
    static scene, ``1 - pi/4`` for independent frames.

    Parameters
    ----------
    g1_bands : array_like
        ``|g1(dt)|`` of each sub-band (the band-limited spectrum's g1, e.g.
        :func:`g1_brownian` with ``spectrum`` times the band's window).

    Examples
    --------
    >>> round(ssada_expected([0.0, 0.0]), 6)  # 1 - pi/4
    0.214602
    >>> ssada_expected([1.0])
    0.0
    """
    g = np.atleast_1d(np.abs(g1_bands))
    if g.ndim != 1 or np.any(g > 1 + 1e-12):
        raise ValueError("g1_bands must be a non-empty 1-D sequence of |g1| <= 1, one per band")
    return float(1.0 - np.mean(ssada_ratio(g)))
