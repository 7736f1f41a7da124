"""An SD-OCT system described by its datasheet, and the model parameters it implies.

OCT engineers describe a system by its central wavelength and FWHM bandwidth (nm), the
spectrometer camera (pixels and wavelength range, or the imaging depth), the refractive index of
the sample, the lateral resolution (or beam waist) and the A-line pitch. :func:`datasheet`
turns these into the model's ``N``, ``H``, pixel size, ``k0`` and ``k0/delta_k``, the sampled
source spectrum and the expected sensitivity roll-off.

Conventions and closed forms
----------------------------
* Wavenumbers are in the medium, ``k = 2 pi n / lambda`` (rad/µm); depths in the medium (µm).
* The camera has ``M`` pixels of width ``dl = (lambda_max - lambda_min)/M`` tiling the range;
  pixel ``i`` is centred at ``lambda_min + (i + 1/2) dl``. The processing grid (the model's
  ``N`` spectral components ``k_n = k0 + n pi/H``) has ``N = M`` points spanning exactly the
  wavenumbers of the first and last pixel centres ``lambda_a, lambda_b``:
  ``dk = 2 pi n dl / (lambda_a lambda_b)``, so ``H = pi/dk`` and the imaging depth of the real
  interferogram is ``z_max = H/2 = lambda_a lambda_b / (4 n dl)`` -- the textbook
  ``lambda0^2/(4 n dl)`` with ``lambda0^2`` replaced by ``lambda_a lambda_b`` (equal to
  ``lambda0^2 (1 - ((M - 1) dl / (2 lambda0))^2)`` for a camera centred on ``lambda0``).
* The source is Gaussian in ``k`` about ``k_s = 2 pi n/lambda0`` with FWHM
  ``Delta_k = 2 pi n Delta_lambda / lambda0^2`` (the linearisation behind the textbook formula).
  The FWHM of the amplitude point-spread function is then ``4 ln2 / Delta_k =
  (2 ln2/pi) lambda0^2/(n Delta_lambda)`` (:attr:`System.gaussian_resolution`) for the uncut
  Gaussian; :attr:`System.axial_resolution` is the FWHM of the spectrum actually built on the
  camera's range, broader when the range cuts the tails (in tissue; in air for n = 1).
* Roll-off (Yun et al., Opt. Express 11, 3598 (2003)): a camera pixel of width ``w`` in ``k``
  averages the carrier ``exp(2ikz)`` into ``sinc(w z)`` (``sinc x = sin x / x``), and a
  Gaussian spectrometer line of FWHM ``d_res`` in ``k`` into ``exp(-(d_res z)^2/(4 ln2))``.
  The power roll-off is ``R(z) = sinc^2(w z) exp(-(d_res z)^2/(2 ln2))``; at ``lambda0`` and
  100 % fill ``w z = pi z/(2 z_max)``.
* Lateral resolution is the FWHM of the Gaussian beam intensity ``exp(-2 r^2/w0^2)``:
  ``sqrt(2 ln2) w0``.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from .._validate import check_choice, check_int, check_memory, check_real
from ._rolloff import rolloff_power
from .source import spectrum as _spectrum

__all__ = ["EXAMPLE_SYSTEMS", "TRUNCATION_SHOWN", "System", "datasheet", "example_system"]

FWHM_TO_WAIST = 1.0 / np.sqrt(2.0 * np.log(2.0))
#: Relative PSF broadening by the camera's cut of the spectrum above which the summary shows it.
TRUNCATION_SHOWN = 0.01


@dataclass(frozen=True)
class System:
    """An SD-OCT system from its datasheet (build it with :func:`datasheet`).

    Stored quantities are in µm (wavelengths in vacuum, lengths in the medium); derived model
    parameters are properties. ``summary()`` gives a readable text, ``_repr_html_`` a table for
    notebooks, ``to_dict()`` a plain record.

    Examples
    --------
    >>> import speckle
    >>> system = speckle.datasheet(840.0, 50.0, 1024, camera_range_nm=(790.0, 890.0))
    >>> type(system).__name__, round(system.wavelength, 3)
    ('System', 0.84)
    """

    wavelength: float  #: central vacuum wavelength lambda0, µm
    bandwidth: float  #: FWHM bandwidth Delta_lambda, µm
    camera_pixels: int  #: spectrometer camera pixels M (= model N)
    wavelength_min: float  #: short edge of the camera range, µm
    wavelength_max: float  #: long edge of the camera range, µm
    refractive_index: float = 1.0  #: refractive index n of the sample
    beam_waist: float | None = None  #: 1/e^2 intensity radius w0 of the focused beam, µm
    aline_pitch: float | None = None  #: lateral distance between A-lines, µm
    spectral_resolution: float = 0.0  #: FWHM of the spectrometer line (Gaussian), µm
    fill_factor: float = 1.0  #: camera pixel width as a fraction of the pixel pitch
    label: str = field(default="", compare=False)  #: free text (e.g. "illustrative")

    def __post_init__(self) -> None:
        """Each field's type and range (the cross-field rules are :func:`datasheet`'s)."""
        for name in ("wavelength", "bandwidth", "wavelength_min", "wavelength_max"):
            check_real(getattr(self, name), name, low=0, low_inclusive=False)
        if not self.wavelength_min < self.wavelength_max:
            raise ValueError(
                f"wavelength_min ({self.wavelength_min:g} µm) must be below wavelength_max "
                f"({self.wavelength_max:g} µm)"
            )
        m = check_int(self.camera_pixels, "camera_pixels", low=2)
        check_memory(64.0 * m, "camera_pixels", "the system's spectral arrays")
        check_real(self.refractive_index, "refractive_index", low=0, low_inclusive=False)
        for name in ("beam_waist", "aline_pitch"):
            if getattr(self, name) is not None:
                check_real(getattr(self, name), name, low=0, low_inclusive=False)
        check_real(self.spectral_resolution, "spectral_resolution", low=0)
        check_real(self.fill_factor, "fill_factor", low=0, high=1, low_inclusive=False)
        if not isinstance(self.label, str):
            raise TypeError(f"label must be a string, got {type(self.label).__name__}")

    # --- camera -------------------------------------------------------------------------
    @property
    def sampling_interval(self) -> float:
        """Camera wavelength step ``dl`` in µm (pixel pitch in wavelength)."""
        return (self.wavelength_max - self.wavelength_min) / self.camera_pixels

    def camera_wavelengths(self) -> np.ndarray:
        """Centres of the camera pixels in µm (vacuum), ascending."""
        return self.wavelength_min + (np.arange(self.camera_pixels) + 0.5) * self.sampling_interval

    # --- model parameters ---------------------------------------------------------------
    @property
    def n_pixels(self) -> int:
        """Model ``N`` (= camera pixels)."""
        return self.camera_pixels

    @property
    def wavenumber_step(self) -> float:
        """Grid spacing ``dk = 2 pi n dl/(lambda_a lambda_b)`` in rad/µm (medium)."""
        lam = self.camera_wavelengths()
        return 2 * np.pi * self.refractive_index * self.sampling_interval / (lam[0] * lam[-1])

    @property
    def depth_range(self) -> float:
        """Model unambiguous depth ``H = pi/dk`` in µm (medium); twice the imaging depth."""
        return np.pi / self.wavenumber_step

    @property
    def imaging_depth(self) -> float:
        """Imaging depth of the real interferogram ``z_max = H/2`` in µm (medium)."""
        return self.depth_range / 2

    @property
    def pixel_size(self) -> float:
        """Depth pixel ``H/N`` in µm (medium)."""
        return self.depth_range / self.n_pixels

    @property
    def k0(self) -> float:
        """Model ``k0``: wavenumber of the grid component ``n = 0`` in rad/µm (medium)."""
        k_low = 2 * np.pi * self.refractive_index / self.camera_wavelengths()[-1]
        return k_low + (self.n_pixels // 2) * self.wavenumber_step

    @property
    def delta_k(self) -> float:
        """Model spectral width ``N pi/H`` in rad/µm."""
        return self.n_pixels * self.wavenumber_step

    @property
    def k0_dk(self) -> float:
        """``k0/delta_k`` (= ``Lc/lambda0`` of the model)."""
        return self.k0 / self.delta_k

    @property
    def source_wavenumber(self) -> float:
        """Centre of the source spectrum ``k_s = 2 pi n/lambda0`` in rad/µm (medium)."""
        return 2 * np.pi * self.refractive_index / self.wavelength

    @property
    def fwhm_k(self) -> float:
        """Source FWHM in wavenumber ``2 pi n Delta_lambda/lambda0^2`` in rad/µm (medium)."""
        return 2 * np.pi * self.refractive_index * self.bandwidth / self.wavelength**2

    @property
    def fwhm_fraction(self) -> float:
        """Source FWHM as a fraction of ``delta_k``."""
        return self.fwhm_k / self.delta_k

    @property
    def gaussian_resolution(self) -> float:
        """Axial resolution of the untruncated Gaussian source, ``(2 ln2/pi) lambda0^2/(n
        Delta_lambda)`` in µm (the textbook closed form; :attr:`axial_resolution` is the FWHM of
        the spectrum actually built, broader when the camera cuts the Gaussian's tails)."""
        return 2 * np.log(2) / np.pi * self.wavelength**2 / (self.refractive_index * self.bandwidth)

    @property
    def axial_resolution(self) -> float:
        """Axial resolution in the sample, µm: the FWHM of the amplitude PSF of the spectrum
        this system builds (:attr:`psf_resolution`). The camera range cuts the Gaussian, e.g.
        at its FWHM x 2 (840 nm / 50 nm, camera 790-890 nm): 4.69 µm instead of the closed form
        :attr:`gaussian_resolution` 4.51 µm (n = 1.38)."""
        return self.psf_resolution

    @property
    def psf_resolution(self) -> float:
        """FWHM in µm of the amplitude PSF ``|sum_n S(k_n) exp(2i k_n z)|`` of the spectrum this
        system builds (:meth:`spectrum`, sampled on the grid and cut at the camera's ends).

        Equal to :attr:`gaussian_resolution` (the untruncated Gaussian's closed form) to sampling
        accuracy when the camera holds the Gaussian's tails; broader when the camera range cuts
        them. Found by root bracketing on ``|A(z)| = |A(0)|/2``.
        """
        from scipy.optimize import brentq

        k = self.k0 + (np.arange(self.n_pixels) - self.n_pixels // 2) * self.wavenumber_step
        w = np.exp(-4 * np.log(2) * ((k - self.source_wavenumber) / self.fwhm_k) ** 2)
        kc = k - self.source_wavenumber

        def half(z: float) -> float:
            return abs(np.sum(w * np.exp(2j * kc * z))) / w.sum() - 0.5

        z, step = 0.0, 0.05 * self.gaussian_resolution
        while half(z + step) > 0:  # |A| falls monotonically to half its peak
            z += step
            if z > 0.5 * self.imaging_depth:
                return float("nan")
        return 2.0 * float(brentq(half, z, z + step, xtol=1e-12 * self.gaussian_resolution))

    @property
    def truncation(self) -> float:
        """Relative broadening ``psf_resolution / gaussian_resolution - 1`` by the camera's cut."""
        return self.psf_resolution / self.gaussian_resolution - 1.0

    @property
    def lateral_resolution(self) -> float | None:
        """Lateral resolution (FWHM of the beam intensity) ``sqrt(2 ln2) w0`` in µm."""
        return None if self.beam_waist is None else self.beam_waist / FWHM_TO_WAIST

    # --- roll-off -----------------------------------------------------------------------
    @property
    def pixel_width_k(self) -> float:
        """Width in ``k`` of the camera pixel at ``lambda0`` in rad/µm (fill factor included)."""
        return self.fill_factor * self.sampling_interval * self.fwhm_k / self.bandwidth

    @property
    def resolution_k(self) -> float:
        """FWHM in ``k`` of the spectrometer line at ``lambda0`` in rad/µm."""
        return self.spectral_resolution * self.fwhm_k / self.bandwidth

    def rolloff(self, z: object) -> np.ndarray:
        """Analytic power roll-off ``sinc^2(w z) exp(-(d_res z)^2/(2 ln2))`` (linear, <= 1).

        Parameters
        ----------
        z : array_like
            Reflector depths ``z`` in µm (medium) from the zero delay.
        """
        return rolloff_power(z, self.pixel_width_k, self.resolution_k)

    def rolloff_db(self, z: object) -> np.ndarray:
        """:meth:`rolloff` in dB (``10 log10``) at reflector depths ``z`` (µm)."""
        return 10 * np.log10(self.rolloff(z))

    @property
    def rolloff_6db_depth(self) -> float:
        """Depth in µm where the analytic roll-off falls to -6 dB (NaN if not within z_max)."""
        from scipy.optimize import brentq

        f = lambda z: self.rolloff_db(z) + 6.0  # noqa: E731
        zmax = self.imaging_depth
        return float(brentq(f, 0.0, zmax)) if f(zmax) < 0 else float("nan")

    # --- outputs ------------------------------------------------------------------------
    def spectrum(self) -> xr.DataArray:
        """Source spectrum on the model grid, as :func:`speckle.spectrum` returns it.

        Gaussian in ``k`` about :attr:`source_wavenumber` with FWHM :attr:`fwhm_k`, sampled at
        ``k_n = k0 + n pi/H`` (``shape="array"``; attributes ``source_wavenumber``, ``fwhm``).
        """
        k = self.k0 + (np.arange(self.n_pixels) - self.n_pixels // 2) * self.wavenumber_step
        w = np.exp(-4 * np.log(2) * ((k - self.source_wavenumber) / self.fwhm_k) ** 2)
        s = _spectrum(self.n_pixels, self.depth_range, k0=self.k0, shape="array", weights=w)
        s.attrs.update(
            source_wavenumber=self.source_wavenumber, fwhm=self.fwhm_k, system=self.label
        )
        return s

    def to_dict(self) -> dict[str, float | int | str | None]:
        """Datasheet and derived quantities as a flat record (µm, rad/µm; ``None`` if unset)."""
        keys = (
            "wavelength bandwidth camera_pixels wavelength_min wavelength_max refractive_index "
            "beam_waist aline_pitch spectral_resolution fill_factor label sampling_interval "
            "n_pixels depth_range imaging_depth pixel_size k0 delta_k k0_dk source_wavenumber "
            "fwhm_k fwhm_fraction gaussian_resolution axial_resolution lateral_resolution "
            "rolloff_6db_depth"
        ).split()
        return {k: getattr(self, k) for k in keys}

    def _rows(self) -> list[tuple[str, str]]:
        nm = 1e3
        lat = self.lateral_resolution
        rows = [
            ("central wavelength", f"{self.wavelength * nm:.1f} nm"),
            ("FWHM bandwidth", f"{self.bandwidth * nm:.1f} nm"),
            (
                "camera",
                f"{self.camera_pixels} px, {self.wavelength_min * nm:.1f}-"
                f"{self.wavelength_max * nm:.1f} nm ({self.sampling_interval * nm:.4f} nm/px)",
            ),
            ("refractive index", f"{self.refractive_index:g}"),
            ("N, H", f"{self.n_pixels}, {self.depth_range:.1f} µm (in the sample)"),
            ("imaging depth z_max", f"{self.imaging_depth:.1f} µm (in the sample)"),
            ("pixel size H/N", f"{self.pixel_size:.3f} µm"),
            ("k0, k0/Δk", f"{self.k0:.4f} rad/µm, {self.k0_dk:.3f}"),
            ("source FWHM in k", f"{self.fwhm_k:.4f} rad/µm ({self.fwhm_fraction:.3f} Δk)"),
            (
                "axial resolution",
                f"{self.axial_resolution:.2f} µm (in the sample)"
                + (
                    f"; the camera cuts the Gaussian ({self.gaussian_resolution:.2f} µm uncut)"
                    if self.truncation > TRUNCATION_SHOWN
                    else ""
                ),
            ),
            ("lateral resolution", "-" if lat is None else f"{lat:.2f} µm (FWHM)"),
            ("A-line pitch", "-" if self.aline_pitch is None else f"{self.aline_pitch:g} µm"),
            (
                "roll-off at z_max",
                f"{float(self.rolloff_db(self.imaging_depth)):.2f} dB; -6 dB "
                + (
                    f"at {self.rolloff_6db_depth:.0f} µm"
                    if np.isfinite(self.rolloff_6db_depth)
                    else "not reached within z_max"
                ),
            ),
        ]
        return rows

    def summary(self) -> str:
        """Readable multi-line summary of the datasheet and the derived model parameters."""
        head = "SD-OCT system" + (f": {self.label}" if self.label else "")
        width = max(len(k) for k, _ in self._rows())
        return "\n".join([head, *(f"  {k:<{width}}  {v}" for k, v in self._rows())])

    def __str__(self) -> str:
        return self.summary()

    def _repr_html_(self) -> str:
        head = html.escape("SD-OCT system" + (f": {self.label}" if self.label else ""))
        body = "".join(
            f"<tr><th style='text-align:left'>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
            for k, v in self._rows()
        )
        return f"<table><caption>{head}</caption>{body}</table>"


def datasheet(
    wavelength_nm: float,
    bandwidth_nm: float,
    camera_pixels: int,
    *,
    camera_range_nm: tuple[float, float] | None = None,
    imaging_depth: float | None = None,
    refractive_index: float = 1.0,
    beam_waist: float | None = None,
    lateral_resolution: float | None = None,
    aline_pitch: float | None = None,
    spectral_resolution_nm: float = 0.0,
    fill_factor: float = 1.0,
    label: str = "",
) -> System:
    """An SD-OCT :class:`System` from datasheet quantities.

    Parameters
    ----------
    wavelength_nm : float
        Central vacuum wavelength ``lambda0`` in nm (> 0).
    bandwidth_nm : float
        FWHM bandwidth ``Delta_lambda`` in nm, in (0, wavelength_nm).
    camera_pixels : int
        Spectrometer camera pixels ``M`` (>= 2); the model's ``N``.
    camera_range_nm : (float, float), optional
        Wavelength range ``(lambda_min, lambda_max)`` covered by the camera, nm. It must cover
        the FWHM band ``lambda0 +- Delta_lambda/2``. Give this or ``imaging_depth``.
    imaging_depth : float, optional
        Imaging depth ``z_max`` in µm in the sample; the camera is then centred on ``lambda0``
        with the textbook step ``dl = lambda0^2/(4 n z_max)``.
    refractive_index : float
        Refractive index ``n`` of the sample (>= 1).
    beam_waist, lateral_resolution : float, optional
        Beam waist ``w0`` (1/e^2 intensity radius) or lateral resolution (intensity FWHM) in µm;
        at most one.
    aline_pitch : float, optional
        Lateral step between A-lines in µm (> 0).
    spectral_resolution_nm : float
        FWHM of the spectrometer's (Gaussian) line in nm (>= 0; 0 = ideal).
    fill_factor : float
        Camera pixel width / pixel pitch, in (0, 1].
    label : str
        Free text shown in the summary.

    Raises
    ------
    ValueError, TypeError
        Bandwidth not smaller than the wavelength, camera range not covering the FWHM band, both
        or neither of ``camera_range_nm`` / ``imaging_depth``, out-of-range values.

    Examples
    --------
    >>> import speckle
    >>> sheet = speckle.datasheet(840.0, 50.0, 1024, camera_range_nm=(790.0, 890.0))
    >>> round(sheet.axial_resolution, 2), sheet.camera_pixels
    (6.47, 1024)
    """
    lam = check_real(wavelength_nm, "wavelength_nm", low=0, low_inclusive=False)
    bw = check_real(bandwidth_nm, "bandwidth_nm", low=0, low_inclusive=False)
    if bw >= lam:
        raise ValueError(
            f"bandwidth_nm must be smaller than the central wavelength_nm={lam:g}, got {bw:g}"
        )
    m = check_int(camera_pixels, "camera_pixels", low=2)
    # the camera, grid, spectrum and PSF arrays (a few float64 and complex128 of M points)
    check_memory(64.0 * m, "camera_pixels", "the system's spectral arrays")
    n = check_real(refractive_index, "refractive_index", low=1.0)
    fill = check_real(fill_factor, "fill_factor", low=0, high=1, low_inclusive=False)
    res = check_real(spectral_resolution_nm, "spectral_resolution_nm", low=0)
    if (camera_range_nm is None) == (imaging_depth is None):
        raise ValueError("give exactly one of camera_range_nm (nm, nm) or imaging_depth (µm)")
    if camera_range_nm is not None:
        if (
            isinstance(camera_range_nm, str | bytes)
            or not hasattr(camera_range_nm, "__len__")
            or len(camera_range_nm) != 2
        ):
            raise ValueError("camera_range_nm must be (lambda_min, lambda_max) in nm")
        lo = check_real(camera_range_nm[0], "camera_range_nm[0]", low=0, low_inclusive=False)
        hi = check_real(camera_range_nm[1], "camera_range_nm[1]", low=lo, low_inclusive=False)
    else:
        zmax = check_real(imaging_depth, "imaging_depth", low=0, low_inclusive=False)
        step = (lam * 1e-3) ** 2 / (4 * n * zmax) * 1e3  # nm
        lo, hi = lam - m * step / 2, lam + m * step / 2
        if lo <= 0:
            raise ValueError(
                f"imaging_depth={zmax:g} µm is too small for {m} pixels at {lam:g} nm: the "
                f"camera range would reach {lo:g} nm"
            )
    if lo > lam - bw / 2 or hi < lam + bw / 2:
        what = (
            "camera_range_nm" if camera_range_nm is not None else "imaging_depth (its camera range)"
        )
        raise ValueError(
            f"{what} [{lo:g}, {hi:g}] nm must cover the FWHM band "
            f"[{lam - bw / 2:g}, {lam + bw / 2:g}] nm of the source (wavelength_nm +- "
            "bandwidth_nm/2)"
        )
    step = (hi - lo) / m
    if bw < 2 * step:
        raise ValueError(
            f"bandwidth_nm = {bw:g} spans fewer than 2 camera pixels of {step:.3g} nm: the camera "
            "does not resolve the source spectrum; use more camera_pixels or a narrower "
            "camera_range_nm (a longer imaging_depth)"
        )
    if beam_waist is not None and lateral_resolution is not None:
        raise ValueError("give at most one of beam_waist and lateral_resolution (µm)")
    w0 = None
    if beam_waist is not None:
        w0 = check_real(beam_waist, "beam_waist", low=0, low_inclusive=False)
    if lateral_resolution is not None:
        w0 = (
            check_real(lateral_resolution, "lateral_resolution", low=0, low_inclusive=False)
            * FWHM_TO_WAIST
        )
    pitch = None
    if aline_pitch is not None:
        pitch = check_real(aline_pitch, "aline_pitch", low=0, low_inclusive=False)
    system = System(
        wavelength=lam * 1e-3,
        bandwidth=bw * 1e-3,
        camera_pixels=m,
        wavelength_min=lo * 1e-3,
        wavelength_max=hi * 1e-3,
        refractive_index=n,
        beam_waist=w0,
        aline_pitch=pitch,
        spectral_resolution=res * 1e-3,
        fill_factor=fill,
        label=str(label),
    )
    return system


#: Columns of the rows of :data:`EXAMPLE_SYSTEMS` (datasheet keywords).
_EXAMPLE_COLUMNS = (
    "wavelength_nm",
    "bandwidth_nm",
    "camera_pixels",
    "camera_range_nm",
    "lateral_resolution",
    "aline_pitch",
    "spectral_resolution_nm",
)
_EXAMPLE_ROWS = {
    "840nm": (840.0, 50.0, 2048, (790.0, 890.0), 10.0, 5.0, 0.07),
    "1310nm": (1310.0, 100.0, 1024, (1200.0, 1420.0), 15.0, 7.5, 0.2),
}
#: Illustrative parameter sets of two common SD-OCT classes (not any vendor's specification).
EXAMPLE_SYSTEMS: dict[str, dict] = {
    name: {
        **dict(zip(_EXAMPLE_COLUMNS, row, strict=True)),
        "refractive_index": 1.38,
        "label": f"illustrative {row[0]:g} nm / {row[1]:g} nm class (not a vendor specification)",
    }
    for name, row in _EXAMPLE_ROWS.items()
}


def example_system(name: str, **overrides) -> System:
    """One of :data:`EXAMPLE_SYSTEMS` (illustrative), with datasheet overrides.

    Examples
    --------
    >>> import speckle
    >>> speckle.example_system("840nm").wavelength
    0.84
    """
    check_choice(name, "name", EXAMPLE_SYSTEMS)
    return datasheet(**{**EXAMPLE_SYSTEMS[name], **overrides})
