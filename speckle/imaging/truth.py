"""The speckle-free image: the expected intensity over scatterer phases.

For scatterers ``j`` with amplitudes ``a_j`` imaged through a linear system (spectrum, beam,
every effect that acts on the scatterers), the field is ``A = sum_j a_j h_j`` and, averaged
over independent uniform phases of the ``a_j`` (positions fixed), the intensity is

    E|A|^2 = sum_j |a_j|^2 |h_j|^2,

the incoherent sum. Both factors of ``|h_j|^2`` are images of the same kind again:

* depth: with ``P(x) = sum_n S_n exp(-2i pi n x/N)`` the spectral PSF (Eq. 4),
  ``|P(x)|^2 = sum_l R_l exp(-2i pi l x/N)``, ``R_l = sum_m S_(m+l) S_m``, ``|l| < N``: an
  Eq. 4 A-scan with the *intensity spectrum* ``R`` at ``k0 = 0``. Its ``2N - 1`` frequencies
  need ``2N`` samples: it is evaluated on the half-pixel grid (``2N`` pixels over the same
  ``H``, spectral step ``pi/H`` unchanged) and every second sample is kept -- exact, no
  interpolation;
* laterally: the double-pass beam weight ``W = exp(-2 r^2/w0^2)`` squares to
  ``exp(-4 r^2/w0^2)``, the weight of a beam of waist ``w0/sqrt(2)``.

So the truth is :func:`speckle.imaging.scan.scan_image` (or :func:`speckle.ascan` for independent
A-lines) of the scatterers' intensities ``|a_j|^2`` with the intensity spectrum and the
narrower beam: the same code, methods and chunking as the speckled image. Effects on the
scatterers (attenuation, roll-off, backscatter, depolarization channels) are in the ``a_j``
and so in the truth; phase effects (a phase screen) change no ``|a_j|``; receiver noise is
not part of the signal. A focused beam (depth-dependent complex waist) has no such form and is
refused.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._deprecate import renamed_parameters
from .._validate import as_finite_array, check_int, check_real, check_size
from ..conventions import attrs, coord, grid_attrs, units_of
from ..provenance import provenance_attrs
from ..scene.shared import check_not_empty
from ..system.source import check_source, check_weights, spectrum
from ._bscan import map_lines
from ._rules import check_tol
from .aline import ascan, pixel_depths
from .methods import ASCAN_METHODS
from .scan import scan_image

__all__ = ["intensity_spectrum", "speckle_free_image", "speckle_free_lines"]


def intensity_spectrum(weights: object) -> np.ndarray:
    """Autocorrelation ``R_l = sum_m S_(m+l) S_m`` of ``N`` spectral weights, on ``2N`` samples.

    Parameters
    ----------
    weights : array_like, shape (N,)
        Non-negative spectral weights ``S(k_n)`` (low to high wavenumber).

    Returns
    -------
    numpy.ndarray, shape (2N,)
        ``R_l`` for ``l = -N ... N-1`` (``R_(-N) = 0``): the spectrum whose Eq. 4 A-scan on
        ``2N`` half pixels is ``|P|^2`` (see the module docstring). Non-negative.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> speckle.intensity_spectrum(np.ones(4))
    array([0., 1., 2., 3., 4., 3., 2., 1.])
    """
    s = as_finite_array(weights, "weights")
    s = check_weights(s, s.size, "weights")
    r = np.correlate(s, s, mode="full")  # lags -(N-1) ... N-1
    return np.concatenate([[0.0], np.clip(r, 0.0, None)])  # tiny negative rounding -> 0


def speckle_free_lines(
    z: object,
    amplitude: object,
    *,
    n_pixels: int,
    depth_range: float,
    spectrum: object | None = None,
    method: str = "direct",
    tol: float | None = None,
) -> np.ndarray:
    """Expected intensity ``sum_j |a_j|^2 |P(q - z_j N/H)|^2`` of independent A-lines.

    Parameters
    ----------
    z, amplitude : array_like, shape (..., M)
        Scatterer depths (µm) and amplitudes, batch dims as in :func:`speckle.ascan`.
    n_pixels, depth_range, spectrum
        As in :func:`speckle.ascan` (``k0`` does not enter the truth).
    method, tol
        Passed to :func:`speckle.ascan`.

    Returns
    -------
    numpy.ndarray
        Float64, shape ``(..., n_pixels)``: the speckle-free intensity (no normalisation).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> z, a = np.array([[64.0]]), np.array([[1.0]])  # one scatterer at 64 µm
    >>> truth = speckle.speckle_free_lines(z, a, n_pixels=16, depth_range=128.0)
    >>> truth.shape, int(truth.argmax())
    ((1, 16), 8)
    """
    n = check_size(n_pixels, "n_pixels", low=1, bytes_per=64.0)
    s = np.ones(n) if spectrum is None else check_weights(spectrum, n)
    a2 = np.abs(as_finite_array(amplitude, "amplitude", dtype=complex)) ** 2
    out = ascan(
        z,
        a2,
        n_pixels=2 * n,
        depth_range=depth_range,
        k0=0.0,
        spectrum=intensity_spectrum(s),
        method=method,
        tol=tol,
    )
    return np.ascontiguousarray(out[..., ::2].real)


@renamed_parameters({"x": "lines"})
def speckle_free_image(
    scene: xr.Dataset,
    source: xr.DataArray,
    *,
    waist: float | None = None,
    lines: object | None = None,
    chunk: int = 64,
    method: str = "direct",
    tol: float | None = None,
) -> xr.DataArray:
    """The speckle-free image ``E|A|^2`` of a scene, through the same spectrum and beam.

    Parameters
    ----------
    scene : xarray.Dataset
        Independent A-lines (dims ``(..., aline, scatterer)``, :func:`speckle.random_scatterers`)
        imaged as by :func:`speckle.bscan`; or a shared scene (:func:`speckle.shared_scene`)
        imaged as by :func:`speckle.scan_image` with ``waist`` and ``lines``. Extra dims
        (``channel``
        of :func:`speckle.depolarize`, ``frame``, ...) are carried through.
    source : xarray.DataArray
        Spectrum from :func:`speckle.spectrum`.
    waist : float, optional
        Beam waist in µm (shared scenes only; required there).
    lines : array_like, optional
        Lateral positions of the lines in µm (shared scenes only; required there).
    chunk, method, tol
        As in :func:`speckle.scan_image` / :func:`speckle.bscan`.

    Returns
    -------
    xarray.DataArray
        ``truth`` over ``(..., depth, x)``: real, non-negative, in
        the units of ``|A|^2`` of the unnormalised image (``normalise="none"``).

    Raises
    ------
    TypeError, ValueError
        On a scene or source of the wrong kind, a shared scene without ``waist``/``lines`` (or a
        line scene with them), and the errors of the imaging functions.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(R.background(density=0.05))
    >>> scene = speckle.shared_scene(regions, z_range=(0.0, 256.0), x_range=(-32.0, 64.0), seed=1)
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> x = speckle.scan_lines(8, 4.0)
    >>> truth = speckle.speckle_free_image(scene, src, waist=4.0, lines=x)
    >>> truth.dims, truth.shape
    (('depth', 'x'), (32, 8))
    """
    src = check_source(source)
    check_int(chunk, "chunk", low=1)
    if not isinstance(scene, xr.Dataset) or not {"z", "amplitude"} <= set(scene.data_vars):
        raise TypeError("scene must be an xarray.Dataset with variables 'z' and 'amplitude'")
    check_not_empty(scene)
    n, h = src["n_pixels"], src["depth_range"]
    r = intensity_spectrum(src["spectrum"])
    shared = "x" in scene.data_vars
    if shared:
        if waist is None or lines is None:
            raise ValueError("a shared scene needs waist= (µm) and lines= (line positions, µm)")
        w0 = check_real(waist, "waist", low=0, low_inclusive=False)
        src2 = spectrum(2 * n, h, k0=0.0, shape="array", weights=r)
        sc2 = scene.assign(amplitude=(abs(scene.amplitude) ** 2).astype(np.complex128))
        img = scan_image(
            sc2, src2, waist=w0 / np.sqrt(2.0), lines=lines, chunk=chunk, method=method, tol=tol
        )
        truth = img.field.isel(depth=slice(0, None, 2)).real
        truth = truth.assign_coords(depth=coord("depth", pixel_depths(n, h)))
        lateral = "x"
    else:
        if waist is not None or lines is not None:
            raise ValueError("waist and lines are for shared scenes; independent A-lines take none")
        if method not in ASCAN_METHODS:
            raise ValueError(f"method must be one of {ASCAN_METHODS}, got {method!r}")
        check_tol(tol)
        truth = map_lines(
            speckle_free_lines,
            scene,
            n,
            np.float64,
            depth_range=h,
            spectrum=source.values,
            method=method,
            tol=tol,
        )
        truth = truth.assign_coords(depth=coord("depth", pixel_depths(n, h)))
        lateral = "x"  # map_lines: the scene's lines become the image's x
    dims = [d for d in truth.dims if d not in ("depth", lateral)] + ["depth", lateral]
    truth = truth.transpose(*[d for d in dims if d in truth.dims])
    truth = truth.rename("truth").assign_attrs(
        attrs("dimensionless", "speckle-free intensity E|A|^2 (incoherent sum)"),
        **grid_attrs(n, h, float(source.attrs["k0"])),
        **({"waist": float(waist), "waist_units": units_of("length")} if shared else {}),
        **provenance_attrs(),
    )
    return truth
