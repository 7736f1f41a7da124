"""SD-OCT sensitivity roll-off with depth (off unless applied).

Each spectrometer pixel integrates the interferogram over its width in wavenumber, and the
spectrometer's optical resolution blurs it further. For a fringe ``exp(2i k z)`` from depth ``z``
a box pixel of width ``delta`` (rad/µm) gives the amplitude factor ``sin(z delta)/(z delta)`` and
a Gaussian spectral blur of FWHM ``w delta`` the factor ``exp(-w^2 (z delta)^2/(4 ln 2))``, so the
intensity roll-off is the usual (Yun et al., Opt. Express 11, 2003)

    R(z) = [sin(zeta)/zeta]^2 exp(-w^2 zeta^2 / (2 ln 2)),   zeta = (pi/2) z/z_max,

with ``z_max = pi/(2 delta)`` the Nyquist depth of the real interferogram (``R(z_max) =
(2/pi)^2``, -3.9 dB, for ``w = 0``) and ``w`` the spectral resolution in units of the pixel
spacing. In this package's model the pixel spacing is ``delta = pi/H`` (``H`` the unambiguous
depth of the complex A-scan), so the default ``z_max`` is ``H/2`` and the sinc reaches its first
zero at ``z = H``.

The roll-off multiplies each scatterer's contribution by the *signed* amplitude factor of its
own depth (the fringe frequency is the scatterer's, not the pixel's); this is exact for box
pixels (see the tests: Eq. 4 integrated over each pixel's width). A measured curve can be given
instead (``curve``: intensity vs depth, linearly interpolated).

The closed forms in the spectrometer's own units (pixel width and line FWHM in rad/µm, used by
:mod:`speckle.system._datasheet` and :mod:`speckle.system.spectrometer`) are
:func:`carrier_response` and :func:`rolloff_power`; :func:`rolloff_amplitude` is the same
function with ``delta = pi/(2 z_max)`` and ``r = w delta``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_real
from ..conventions import depth_range_of
from ._scene import check_scene, scale_amplitudes

__all__ = ["carrier_response", "rolloff", "rolloff_amplitude", "rolloff_curve", "rolloff_power"]


def carrier_response(distance: object, pixel_width: object = 0.0, resolution: object = 0.0):
    """Pixel and spectrometer-line average of the carrier ``exp(2ikd)``, divided by it.

    ``g(d) = sinc(w d) exp(-(r d)^2/(4 ln2))`` with ``sinc x = sin x/x``: the mean of
    ``exp(2i kappa d)`` over a box of width ``w`` and over a Gaussian of FWHM ``r`` in ``kappa``.

    Parameters
    ----------
    distance : array_like
        Path difference ``d`` in µm (medium), one way.
    pixel_width, resolution : array_like
        Pixel width ``w`` and spectrometer-line FWHM ``r`` in rad/µm (>= 0), broadcast with
        ``distance``.
    """
    d = np.asarray(distance, dtype=float)
    w = np.asarray(pixel_width, dtype=float)
    r = np.asarray(resolution, dtype=float)
    return np.sinc(w * d / np.pi) * np.exp(-((r * d) ** 2) / (4 * np.log(2)))


def rolloff_power(z: object, pixel_width: float, resolution: float = 0.0) -> np.ndarray:
    """Power roll-off of a point reflector, ``sinc^2(w z) exp(-(r z)^2/(2 ln2))`` (linear).

    With ``w = pi/(2 z_max)`` (100 % fill at ``lambda0``) and ``r = omega w`` (``omega`` the
    spectrometer FWHM over the wavelength step) this is Yun et al. (Opt. Express 11, 3598,
    2003): ``sinc^2(zeta) exp(-omega^2 zeta^2/(2 ln2))``, ``zeta = pi z/(2 z_max)``.

    Parameters
    ----------
    z : array_like
        Depth ``z`` of the reflector from the zero delay, µm (medium).
    pixel_width : float
        Camera pixel width in ``k``, rad/µm (>= 0).
    resolution : float
        FWHM of the spectrometer line in ``k``, rad/µm (>= 0).
    """
    z = as_finite_array(z, "z")
    w = check_real(pixel_width, "pixel_width", low=0)
    r = check_real(resolution, "resolution", low=0)
    return carrier_response(z, w, r) ** 2


def rolloff_amplitude(z: object, z_max: float, resolution: float = 0.0) -> np.ndarray:
    """Signed amplitude factor ``sinc(zeta) exp(-w^2 zeta^2/(4 ln 2))`` (its square: ``R(z)``).

    Parameters
    ----------
    z : array_like
        Depths in µm.
    z_max : float
        Nyquist depth ``pi/(2 delta)`` in µm (> 0); ``H/2`` for this package's spectral sampling.
    resolution : float
        Spectral resolution ``w`` (Gaussian FWHM) in units of the pixel spacing (>= 0).
    """
    zm = check_real(z_max, "z_max", low=0, low_inclusive=False)
    w = check_real(resolution, "resolution", low=0)
    delta = 0.5 * np.pi / zm
    return carrier_response(as_finite_array(z, "z"), delta, w * delta)


def rolloff_curve(z: object, z_max: float, resolution: float = 0.0) -> np.ndarray:
    """Intensity roll-off ``R(z)`` (1 at ``z = 0``) of the module docstring."""
    return rolloff_amplitude(z, z_max, resolution) ** 2


def rolloff(
    scene: xr.Dataset,
    *,
    z_max: float | None = None,
    resolution: float = 0.0,
    curve: tuple[object, object] | None = None,
) -> xr.Dataset:
    """Apply the sensitivity roll-off to each scatterer by its depth.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field (``z`` in µm, ``amplitude``) with attribute ``depth`` (``H``, µm) when
        ``z_max`` is not given.
    z_max : float, optional
        Nyquist depth in µm (> 0); default ``H/2`` (spectral sampling ``pi/H``).
    resolution : float
        Spectral resolution ``w`` in pixel spacings (>= 0).
    curve : (depths, intensities), optional
        A user roll-off instead: increasing depths (µm) and intensity factors (>= 0) that are
        linearly interpolated (constant beyond the ends); amplitudes scale by the square root.

    Returns
    -------
    xarray.Dataset
        The scene with amplitudes multiplied by the amplitude roll-off.

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> rolled = speckle.rolloff(scene, z_max=256.0, resolution=2.0)
    >>> bool((abs(rolled.amplitude) <= abs(scene.amplitude) + 1e-12).all())
    True
    """
    check_scene(scene)
    if curve is not None:
        if z_max is not None or resolution != 0.0:
            raise ValueError("give either curve or z_max/resolution, not both")
        if len(curve) != 2:
            raise ValueError("curve must be (depths in µm, intensity factors)")
        zc = as_finite_array(curve[0], "curve depths")
        rc = as_finite_array(curve[1], "curve intensities")
        if zc.ndim != 1 or zc.shape != rc.shape or zc.size < 2 or np.any(np.diff(zc) <= 0):
            raise ValueError("curve needs >= 2 strictly increasing depths and as many values")
        if np.any(rc < 0):
            raise ValueError("curve intensities must be >= 0")
        factor = xr.apply_ufunc(lambda z: np.sqrt(np.interp(z, zc, rc)), scene.z)
        return scale_amplitudes(scene, factor, rolloff="user curve")
    if z_max is None:
        h = depth_range_of(scene, "scene", required=False)
        if h is None:
            raise ValueError(
                "give z_max (µm): the scene has no 'depth_range' attribute to take H/2 from"
            )
        z_max = 0.5 * h
    factor = xr.apply_ufunc(
        rolloff_amplitude, scene.z, kwargs={"z_max": z_max, "resolution": resolution}
    )
    return scale_amplitudes(
        scene,
        factor,
        rolloff="sinc^2 x Gaussian",
        rolloff_z_max=float(z_max),
        rolloff_resolution=float(resolution),
    )
