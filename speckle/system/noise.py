"""Receiver noise: circular complex Gaussian noise added to the complex A-scan (off by default).

SNR definition
--------------
``SNR = <|A|^2> / <|n|^2>`` per pixel, in dB: the mean signal intensity over the pixels of the
image (or a given ``signal_intensity``) divided by the mean noise intensity per pixel,
``snr_db = 10 log10 SNR``. The noise is circular complex Gaussian: ``n = sigma (u + i v)/sqrt(2)``
with ``u, v`` independent standard normals and ``sigma^2 = <|A|^2>/SNR``.

Spectral shaping
----------------
Detector (thermal/read) noise is white across spectrometer pixels; shot noise has a variance
proportional to the spectral power ``S(k_n)`` in each pixel and relative-intensity noise (RIN)
to ``S(k_n)^2``. ``kind="white" | "shot" | "rin"`` draws independent circular noise ``e_n`` in
the spectral domain with ``E|e_n|^2 = c w_n`` (``w_n = 1, S_n, S_n^2``) and transforms it with
Eq. 4's sum ``sum_n e_n exp(-2i pi n q/N)``. The pixel noise is then stationary along depth with
complex autocorrelation at lag ``m``
``E[n(q+m) n*(q)] / E abs(n)^2 = sum_n w_n exp(-2i pi n m/N) / sum_n w_n``, and
``c`` is set so the mean noise intensity per pixel is ``sigma^2`` whatever the shape.

For a fixed signal ``A`` and two independent noisy looks, the phase of each look is Rician-phase
distributed with pixel SNR ``r = |A|^2/sigma^2``; :func:`phase_difference_coherence` gives
``E cos(phi_1 - phi_2) = (sqrt(pi r)/2 exp(-r/2) [I0(r/2) + I1(r/2)])^2`` and the phase difference
variance is ``~1/r`` at high ``r``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import special

from .._validate import as_finite_array, check_choice, check_int, check_real
from ..conventions import attrs, canonical_dims
from ._scene import line_rng
from .source import index_shift_phase

__all__ = [
    "NOISE_KINDS",
    "add_complex_noise",
    "add_noise",
    "noise_autocorrelation",
    "phase_difference_coherence",
]

NOISE_KINDS = ("white", "shot", "rin")
_STREAM = 101  # random stream of the noise (see speckle.system._scene.line_rng)


def _weights(kind: str, spectrum: xr.DataArray | None, n: int) -> np.ndarray:
    if kind == "white":
        return np.ones(n)
    if spectrum is None:
        raise ValueError(f"kind={kind!r} needs the source spectrum (speckle.spectrum)")
    s = as_finite_array(spectrum, "spectrum")
    if s.shape != (n,):
        raise ValueError(f"spectrum must hold n_pixels={n} weights, got shape {s.shape}")
    if np.any(s < 0) or not np.any(s > 0):
        raise ValueError(
            f"spectrum must hold non-negative source weights, not all zero, for kind={kind!r} "
            f"(the noise follows S or S^2); got min {s.min():g}, max {s.max():g}"
        )
    return s if kind == "shot" else s**2


def _image_rng(seed: int, line: int, index: tuple[int, ...]) -> np.random.Generator:
    """Noise stream of line ``line`` of the image at ``index`` along the leading dims (a 2-D
    image, ``index = ()``, uses the line's stream of :func:`speckle.system._scene.line_rng`)."""
    if not index:
        return line_rng(seed, line, _STREAM)
    key = (line, _STREAM, *(int(i) for i in index))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def noise_autocorrelation(
    n_pixels: int, lags: object, kind: str = "white", spectrum: xr.DataArray | None = None
) -> np.ndarray:
    """Complex autocorrelation of the pixel noise along depth at integer ``lags`` (pixels)."""
    n = check_int(n_pixels, "n_pixels", low=2)
    check_choice(kind, "kind", NOISE_KINDS)
    w = _weights(kind, spectrum, n)
    idx = np.arange(n) - n // 2
    m = np.asarray(lags, dtype=float)
    return np.exp(-2j * np.pi * np.multiply.outer(m, idx) / n) @ w / w.sum()


def phase_difference_coherence(snr: object) -> np.ndarray:
    """``E cos(phi_1 - phi_2)`` of two independent noisy looks of a fixed pixel of SNR ``r``.

    ``phi_i = arg(A + n_i)``: ``E exp(i (phi - arg A)) = sqrt(pi r)/2 exp(-r/2) [I0(r/2) +
    I1(r/2)]`` (Rician phase), squared for the difference of two independent looks. Uses the
    exponentially scaled Bessel functions (stable at any ``r >= 0``).
    """
    r = np.asarray(snr, dtype=float)
    if np.any(r < 0) or not np.all(np.isfinite(r)):
        raise ValueError("snr must be finite and >= 0 (linear pixel SNR)")
    m1 = 0.5 * np.sqrt(np.pi * r) * (special.i0e(r / 2) + special.i1e(r / 2))
    return m1**2


def add_noise(
    image: xr.Dataset,
    snr_db: float,
    *,
    seed: int,
    kind: str = "white",
    spectrum: xr.DataArray | None = None,
    signal_intensity: float | None = None,
) -> xr.Dataset:
    """Add receiver noise at a given SNR to a complex B-scan.

    Parameters
    ----------
    image : xarray.Dataset
        From :func:`speckle.bscan`: ``field`` with dims ``(..., depth, aline)``; a scanned
        shared scene's ``(..., depth, x)`` works the same (lines along ``x``).
    snr_db : float
        Mean signal intensity over mean noise intensity per pixel, in dB, in [-300, 300].
    seed : int
        Non-negative seed; line ``i`` (index along ``aline`` or ``x``) of each image (index
        along every other dim, e.g. ``strain``) draws from its own stream, so the noise of a
        line does not depend on how many lines or images there are (same seed: the same noise
        on the strain-0 image whatever the number of strains).
    kind : {"white", "shot", "rin"}
        Spectral shape of the noise (see module docstring); not white needs ``spectrum``.
    spectrum : xarray.DataArray, optional
        Source spectrum ``S(k_n)`` (:func:`speckle.spectrum`).
    signal_intensity : float, optional
        Reference ``<|A|^2>`` (> 0); default: the mean intensity of ``image``.

    Returns
    -------
    xarray.Dataset
        ``field`` + noise, ``amplitude`` and ``intensity`` recomputed; ``noise`` (the added
        complex noise); attributes ``snr_db``, ``noise_intensity`` (``sigma^2``), ``noise_kind``.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(scene, src)
    >>> noisy = speckle.add_noise(img, 20.0, seed=2)
    >>> noisy.field.shape == img.field.shape
    True
    """
    if not isinstance(image, xr.Dataset) or "field" not in image:
        raise TypeError("image must be a Dataset from speckle.bscan with a complex 'field'")
    snr = check_real(snr_db, "snr_db", low=-300.0, high=300.0)  # 10^(snr/10) stays finite
    sd = check_int(seed, "seed", low=0)
    check_choice(kind, "kind", NOISE_KINDS)
    field = canonical_dims(image.field, "image")  # (depth, aline) warns: the dim is now x
    as_finite_array(field.values, "image field", dtype=complex)  # NaN refused with its count
    lateral = "x"
    if "depth" not in field.dims or lateral not in field.dims:
        raise ValueError(f"field must have dims 'depth' and 'x', got {field.dims}")
    if field.size == 0:
        raise ValueError(f"image holds no pixel (field sizes {dict(field.sizes)})")
    if spectrum is not None:  # checked for every kind (white noise does not use it)
        _weights("shot" if kind == "white" else kind, spectrum, field.sizes["depth"])
    ref = (
        float((abs(field) ** 2).mean())
        if signal_intensity is None
        else check_real(signal_intensity, "signal_intensity", low=0, low_inclusive=False)
    )
    if not ref > 0:
        raise ValueError("the image has zero mean intensity: give signal_intensity (> 0)")
    sigma2 = ref / 10 ** (snr / 10)
    f = field.transpose(..., lateral, "depth")
    n = f.sizes["depth"]
    w = _weights(kind, spectrum, n)
    amp = np.sqrt(sigma2 * w / w.sum())  # rms of e_n: sum_n E|e_n|^2 = sigma^2 per pixel
    shift = index_shift_phase(n, np.arange(n))
    lead = f.shape[:-2]
    noise = np.empty(f.shape, dtype=np.complex128)
    for i in range(f.sizes[lateral]):
        for idx in np.ndindex(*lead):
            # one stream per image (index along every leading dim) and line: the noise of an
            # image never depends on how many other images (strains, channels, ...) there are
            rng = _image_rng(sd, i, idx)
            e = (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / np.sqrt(2)
            noise[(*idx, i)] = shift * np.fft.fft(e * amp)
    nz = f.copy(data=noise).transpose(*field.dims)
    noisy = field + nz
    out = image.assign(
        field=noisy.assign_attrs(field.attrs),
        amplitude=abs(noisy).assign_attrs(image.get("amplitude", field).attrs),
        intensity=(abs(noisy) ** 2).assign_attrs(image.get("intensity", field).attrs),
        noise=nz.assign_attrs(attrs("field", f"receiver noise ({kind})")),
    )
    return out.assign_attrs(snr_db=snr, noise_intensity=sigma2, noise_kind=kind, noise_seed=sd)


def add_complex_noise(
    field: object, snr_db: float, *, seed: int, signal_intensity: float | None = None
) -> np.ndarray:
    """:func:`add_noise` (white receiver noise) for a plain complex array ``(depth, x)``.

    Parameters
    ----------
    field : array_like of complex, shape (depth, x)
        The noise-free image (axis 0 = depth).
    snr_db : float
        Mean image intensity over noise power, in dB; ``inf`` returns a copy of ``field``.
    seed : int
        Non-negative seed (same seed, same noise; each A-line has its own stream).
    signal_intensity : float, optional
        The signal intensity the SNR refers to (> 0), instead of ``mean(|field|^2)``: needed
        for an all-zero field (no signal to refer to).

    Returns
    -------
    numpy.ndarray
        ``field + n``, ``n ~ CN(0, sigma^2)``, ``sigma^2 = mean(|field|^2) / 10^(snr_db/10)``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> field = np.ones((4, 1000), complex)
    >>> noisy = speckle.add_complex_noise(field, 10.0, seed=1)
    >>> round(float(np.mean(np.abs(noisy - field) ** 2)), 2)
    0.1
    """
    a = np.asarray(field)
    if a.dtype.kind in "US" or a.dtype == object:
        raise TypeError(f"field must be a complex image, got dtype {a.dtype}")
    if not np.iscomplexobj(a):
        raise TypeError("field must be a complex image (e.g. the 'field' of speckle.bscan)")
    if a.ndim != 2:
        raise ValueError(f"field must be 2-D (depth, x), got shape {a.shape}")
    if isinstance(snr_db, int | float | np.floating) and np.isposinf(snr_db):
        return a.astype(np.complex128, copy=True)
    if min(a.shape) < 1:
        raise ValueError(f"field must hold at least one pixel, got shape {a.shape}")
    image = xr.Dataset({"field": (("depth", "x"), a.astype(np.complex128))})
    return add_noise(image, snr_db, seed=seed, signal_intensity=signal_intensity).field.values
