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
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_real
from ._scene import check_scene, scale_amplitudes

__all__ = ["rolloff", "rolloff_amplitude", "rolloff_curve"]


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
    zeta = 0.5 * np.pi * as_finite_array(z, "z") / zm
    return np.sinc(zeta / np.pi) * np.exp(-(w**2) * zeta**2 / (4 * np.log(2)))


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
        if "depth" not in scene.attrs:
            raise ValueError("give z_max (µm): the scene has no 'depth' attribute to take H/2 from")
        z_max = 0.5 * float(scene.attrs["depth"])
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
