"""Physical speckle compounding: looks of one scene, how they are averaged, and their theory.

A *look* is one complex image of the same scene acquired differently; averaging ``L`` looks
whose speckle patterns are (partly) independent lowers the speckle contrast. Every look function
returns a complex ``DataArray`` with a leading dim ``look`` on the pixel grid of the reference
image, so any of :data:`AVERAGING` applies (:func:`compound`).

* **frequency** (split spectrum, :func:`frequency_looks`): the complex image is exactly
  band-limited to the ``N`` components ``k_n`` of Eq. 4, so its spectrum is the inverse DFT
  along depth; look ``i`` keeps ``W_i(k_n)`` of it (:func:`subband_apodizations`: rectangular,
  Gaussian or Hann apodizations of ``L`` sub-bands with a fractional ``overlap``). Exact: the same
  as imaging with the spectrum ``S W_i``.
* **angular** (:func:`angular_looks`): the scene is rotated by each angle about the image centre
  (the beam tilted the other way), imaged, and the complex image resampled back onto the
  reference grid (cubic spline, registration as in a scanner).
* **spatial** (:func:`spatial_looks`): lines offset laterally by each offset, kept at the
  reference line positions (averaging them is a lateral blur).
* **polarization** (:func:`polarization_looks`): the co and cross channels of
  :func:`speckle.depolarize`.
* **temporal** (:func:`brownian_frames`, :func:`temporal_looks`): frames ``interval`` s apart
  between which every scatterer makes a Brownian step of variance ``2 D interval`` per axis;
  a dense scene's field autocorrelation is ``g1(tau) = exp(-q^2 D tau)``, ``q = 2 k0``
  (:func:`brownian_g1`), to ``O((step/Lc)^2)`` from the PSF.

Theory (dense scene, equal mean intensities; tested): ``L`` uncorrelated looks give contrast
``1/sqrt(L)``; partially correlated ones ``C_L = sqrt(sum_ij |mu_ij|^2)/L``
(:func:`compounded_contrast`) with ``mu_ij`` the field correlation of looks ``i, j``, for split
spectrum the overlap of the apodizations weighted by ``|S|^2`` (:func:`apodization_correlation`;
``int W_i W_j* dk / sqrt(int |W_i|^2 int |W_j|^2)`` for a rectangular spectrum).
:func:`split_spectrum_contrast` adds the finite-density (Poisson) term exactly. A sub-band of
``M`` of the ``N`` samples has the intensity PSF ``|sin(pi M x/N)/(M sin(pi x/N))|^2``, ``N/M``
times wider (:func:`subband_fwhm`).

The looks that form images (angular, spatial, polarization, temporal) are in
:mod:`speckle.studies.looks` (this module imports no imaging); their old names here warn.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize as opt
import xarray as xr

from .._deprecate import moved, renamed_parameters
from .._validate import check_choice, check_int, check_memory, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, coord, units_of
from ..scene.motion import brownian_motion
from ._common import label_looks
from .dynamics_theory import g1_brownian

#: Looks that form images moved to :mod:`speckle.studies.looks` (issue 32); the old names warn.
_looks = moved(
    __name__,
    "speckle.studies.looks",
    ["angular_looks", "polarization_looks", "spatial_looks", "temporal_looks"],
)
#: Retired names (:data:`speckle.conventions.RETIRED`): spectral windows are apodizations.
_renamed = moved(
    __name__,
    __name__,
    [],
    {
        "WINDOWS": "SUBBAND_APODIZATIONS",
        "subband_windows": "subband_apodizations",
        "window_correlation": "apodization_correlation",
    },
)


def __getattr__(name: str) -> object:
    """The looks' old place and the retired names warn (``FutureWarning``) and resolve."""
    try:
        return _looks(name)
    except AttributeError:
        return _renamed(name)


__all__ = [
    "AVERAGING",
    "SUBBAND_APODIZATIONS",
    "apodization_correlation",
    "brownian_frames",
    "brownian_g1",
    "compound",
    "compounded_contrast",
    "frequency_looks",
    "noisy_looks",
    "split_spectrum_contrast",
    "subband_apodizations",
    "subband_fwhm",
]

#: Sub-band apodization shapes of :func:`subband_apodizations`.
SUBBAND_APODIZATIONS = ("rectangular", "gaussian", "hann")
#: How looks are averaged (:func:`compound`).
AVERAGING = ("intensity", "magnitude", "complex")


@renamed_parameters({"window": "apodization"})
def subband_apodizations(
    n_samples: int, n_looks: int, *, apodization: str = "rectangular", overlap: float = 0.0
) -> np.ndarray:
    """Split-spectrum apodizations (windows over wavenumber) ``W_i(k_n)``, ``i = 0 ... L-1``.

    Sub-bands of width ``w = N/(L - (L-1) overlap)`` samples, centred at
    ``w/2 + i w (1 - overlap)``, tile the band; sample ``n`` sits at ``n + 1/2``.
    ``"rectangular"``: 1 inside the sub-band; ``"hann"``: ``sin^2`` over the sub-band;
    ``"gaussian"``: FWHM ``w`` (tails over the whole band).

    Parameters
    ----------
    n_samples : int
        Spectral samples ``N`` (the spectrum's ``n_pixels``), >= 1.
    n_looks : int
        Sub-bands ``L``, ``1 <= L <= N`` (and each sub-band must hold one sample at least).
    apodization : {"rectangular", "gaussian", "hann"}
        Window shape.
    overlap : float
        Fraction of a sub-band shared with the next, in ``[0, 1)``.

    Returns
    -------
    numpy.ndarray, shape (L, N)
        Non-negative real apodizations (maximum 1), low to high wavenumber.

    Raises
    ------
    ValueError
        ``n_looks`` outside ``[1, N]``, ``overlap`` outside ``[0, 1)``, an unknown apodization, or a
        sub-band narrower than one sample.

    Examples
    --------
    >>> import speckle
    >>> w = speckle.subband_apodizations(64, 4)
    >>> w.shape, float(w.sum(axis=0).min())  # rectangular bands tile the spectrum
    ((4, 64), 1.0)
    """
    n = check_int(n_samples, "n_samples", low=1)
    if isinstance(n_looks, int | np.integer) and not isinstance(n_looks, bool) and n_looks > n:
        raise ValueError(
            f"n_looks must be at most the spectrum's {n} samples (one sample per sub-band at "
            f"least), got {n_looks}"
        )
    nl = check_int(n_looks, "n_looks", low=1, high=n)
    ov = check_real(overlap, "overlap", low=0.0, high=1.0, high_inclusive=False)
    check_choice(apodization, "apodization", SUBBAND_APODIZATIONS)
    check_memory(3 * 8.0 * nl * n, "n_samples", f"{nl} apodizations of {n} samples")
    w = n / (nl - (nl - 1) * ov)
    if w < 1.0:
        raise ValueError(
            f"n_looks={nl} with overlap={ov} gives sub-bands of {w:.3g} < 1 sample; "
            "use fewer looks or less overlap"
        )
    t = np.arange(n) + 0.5
    centres = w / 2 + np.arange(nl) * w * (1 - ov)
    u = (t[None, :] - centres[:, None]) / w  # position in sub-band widths from the centre
    if apodization == "rectangular":
        win = ((u >= -0.5) & (u < 0.5)).astype(float)
    elif apodization == "hann":
        win = np.where(np.abs(u) < 0.5, np.cos(np.pi * u) ** 2, 0.0)
    else:
        win = np.exp(-4 * np.log(2) * u**2)
    if np.any(win.max(axis=1) <= 0):
        raise ValueError(f"a sub-band of n_looks={nl}, overlap={ov} holds no spectral sample")
    return win


#: A finite non-empty (looks, samples) matrix, real or complex (the decorator's checks).
_MATRIX = ArraySpec(kind="number", ndim=2)


@renamed_parameters({"windows": "apodizations"})
@preprocess_and_wrap(
    checks={"apodizations": _MATRIX, "spectrum": ArraySpec(kind="real", optional=True)}
)
def apodization_correlation(apodizations: object, spectrum: object | None = None) -> np.ndarray:
    """Field correlation ``mu_ij`` of split-spectrum looks: the apodizations' weighted overlap.

    ``mu_ij = sum_n S_n^2 W_i W_j* / sqrt(sum S^2 |W_i|^2 sum S^2 |W_j|^2)`` (Parseval: the
    complex correlation of two looks of a dense scene), i.e. the overlap integral of the
    apodizations for a rectangular spectrum (``spectrum=None``).

    Parameters
    ----------
    apodizations : array_like, shape (L, N)
        Apodizations from :func:`subband_apodizations`.
    spectrum : array_like, shape (N,), optional
        Source weights ``S_n``.

    Returns
    -------
    numpy.ndarray, shape (L, L)
        Hermitian, unit diagonal.

    Raises
    ------
    TypeError, ValueError
        ``apodizations`` not a finite non-empty 2-D array, ``spectrum`` not ``N`` finite real
        weights, or an apodization with no power under the spectrum (its correlation is
        undefined).

    Examples
    --------
    >>> import speckle
    >>> abs(speckle.apodization_correlation(speckle.subband_apodizations(64, 2))).round(6)
    array([[1., 0.],
           [0., 1.]])
    """
    w = np.asarray(apodizations, dtype=np.complex128)
    s2 = np.ones(w.shape[1]) if spectrum is None else np.asarray(spectrum, dtype=float) ** 2
    if s2.shape != (w.shape[1],):
        raise ValueError(f"spectrum must hold {w.shape[1]} weights, got shape {s2.shape}")
    g = (w * s2) @ w.conj().T
    d = np.sqrt(np.real(np.diag(g)))
    if not np.all(d > 0):
        raise ValueError(
            f"apodizations {np.flatnonzero(~(d > 0)).tolist()} have no power under the spectrum: "
            "their correlation is undefined"
        )
    return g / np.outer(d, d)


@preprocess_and_wrap(checks={"mu": _MATRIX})
def compounded_contrast(mu: object) -> float:
    """Contrast of the intensity average of ``L`` looks of equal mean: ``sqrt(sum |mu_ij|^2)/L``.

    Dense-scene (Gaussian speckle) result; ``mu`` the (L, L) complex field correlations
    (identity: ``1/sqrt(L)``; one look, ``[[1]]``: 1).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> round(speckle.compounded_contrast(np.eye(4)), 6)  # N independent looks: 1/sqrt(N)
    0.5
    """
    m = np.asarray(mu, dtype=np.complex128)
    if m.shape[0] != m.shape[1]:
        raise ValueError(f"mu must be a square (L, L) matrix, got shape {m.shape}")
    if not (np.allclose(np.diag(m), 1.0, rtol=0, atol=1e-6) and np.all(np.abs(m) <= 1 + 1e-6)):
        raise ValueError(
            "mu must be field correlations: unit diagonal and |mu_ij| <= 1 "
            "(apodization_correlation)"
        )
    return float(np.sqrt(np.sum(np.abs(m) ** 2)) / m.shape[0])


@preprocess_and_wrap(checks={"weights": _MATRIX})
def split_spectrum_contrast(weights: object, density: float, *, kurtosis: float = 1.0) -> float:
    """Exact contrast of intensity-averaged looks of independent A-lines, Poisson scatterers.

    Look ``i`` has spectral weights ``G_i = S W_i``. For Poisson scatterers, ``rho`` per pixel,
    uniform over the depth (``2 k0 H`` a multiple of ``2 pi``), ``E|a|^2 = 1``,
    ``E|a|^4 = kurtosis``, Campbell's theorem gives per pixel ``E I_i = rho N sum |G_i|^2`` and
    ``Cov(I_i, I_j) = (rho N)^2 |sum G_i G_j*|^2 + rho kurtosis N sum_l R_i(l) R_j(l)*``,
    ``R_i`` the autocorrelation of ``G_i``; the contrast is
    ``sqrt(sum_ij Cov_ij) / sum_i E I_i``. ``density -> inf`` gives :func:`compounded_contrast`.

    Parameters
    ----------
    weights : array_like, shape (L, N)
        Spectral weights of the looks (apodization times spectrum).
    density : float
        Mean scatterers per pixel (> 0; ``inf`` for the dense limit).
    kurtosis : float
        ``E|a|^4 / (E|a|^2)^2`` of the amplitudes (1 for equal amplitudes).

    Returns
    -------
    float
        The contrast (std / mean) of the intensity averaged over the looks.

    Raises
    ------
    TypeError, ValueError
        ``weights`` not a finite non-empty 2-D array or without power; ``density`` not a
        positive real (``inf`` allowed); ``kurtosis`` below 1 (``E|a|^4 >= (E|a|^2)^2``,
        Cauchy-Schwarz) or not finite.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> w = speckle.subband_apodizations(64, 4)
    >>> round(speckle.split_spectrum_contrast(w, np.inf), 6)  # 4 disjoint bands: 1/sqrt(4)
    0.5
    """
    g = np.asarray(weights, dtype=np.complex128)
    dense = isinstance(density, float | np.floating) and density == np.inf
    rho = np.inf if dense else check_real(density, "density", low=0, low_inclusive=False)
    kap = check_real(kurtosis, "kurtosis", low=1)
    if not np.any(g):
        raise ValueError("weights must not all be zero (no signal: the contrast is undefined)")
    n = g.shape[1]
    cross = g @ g.conj().T  # sum_n G_i G_j*
    mean = np.real(np.diag(cross))
    cov = np.abs(cross) ** 2
    if np.isfinite(rho):
        # autocorrelations via FFT (lags -(N-1)..N-1), then sum_l R_i(l) R_j(l)*
        f = np.fft.fft(g, 2 * n, axis=1)
        r = np.fft.ifft(np.abs(f) ** 2, axis=1)
        cov = cov + kap / (rho * n) * np.real(r @ r.conj().T)
    return float(np.sqrt(np.sum(cov)) / np.sum(mean))


def subband_fwhm(n_pixels: int, n_samples: int) -> float:
    """FWHM in pixels of the intensity PSF of a rectangular band of ``M`` of ``N`` samples.

    The root of ``|sin(pi M x/N) / (M sin(pi x/N))|^2 = 1/2`` (times two); about
    ``0.886 N/M`` pixels (the continuum sinc^2), so ``N/M`` times the full band's.

    Examples
    --------
    >>> import speckle
    >>> round(speckle.subband_fwhm(256, 64), 3)
    3.544
    """
    n = check_int(n_pixels, "n_pixels", low=1)
    m = check_int(n_samples, "n_samples", low=1, high=n)
    if m == 1:
        return float("inf")

    def f(x: float) -> float:
        return (np.sin(np.pi * m * x / n) / (m * np.sin(np.pi * x / n))) ** 2 - 0.5

    return 2.0 * opt.brentq(f, 1e-9, n / m)


@renamed_parameters({"windows": "apodizations"})
@preprocess_and_wrap(
    checks={
        "img": ArraySpec(
            kind="complex",
            labelled=True,
            keep_labels=True,
            variable="field",
            dims=("depth",),
            extra_dims=True,
        ),
        "apodizations": ArraySpec(kind="real", ndim=2),
    }
)
def frequency_looks(img: xr.Dataset | xr.DataArray, apodizations: object) -> xr.DataArray:
    """Split-spectrum looks of a complex image: the depth spectrum times each apodization.

    Parameters
    ----------
    img : xarray.Dataset or DataArray
        Complex image (``field``) with a ``depth`` dim of ``N`` pixels, from any imaging
        function of the package (its depth spectrum holds the components ``k_n``,
        ``n = -(N//2) ... N-1-(N//2)``).
    apodizations : array_like, shape (L, N)
        From :func:`subband_apodizations` (low to high wavenumber).

    Returns
    -------
    xarray.DataArray
        Complex looks over ``(look, ...)``; look ``i`` equals the image formed with the spectrum
        ``S W_i`` (exact).

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(scene, src)
    >>> looks = speckle.frequency_looks(img, speckle.subband_apodizations(32, 2))
    >>> looks.dims, looks.sizes["look"]
    (('look', 'depth', 'x'), 2)
    """
    f = img  # the complex field (a Dataset's 'field'), checked by the decorator
    n = f.sizes["depth"]
    w = np.asarray(apodizations, dtype=float)
    if w.shape[1] != n:
        raise ValueError(
            f"apodizations must have shape (looks, {n}) for an image of {n} depth pixels, "
            f"got {w.shape}"
        )
    if np.any(w < 0):
        raise ValueError(
            "apodizations must be non-negative spectral weights (subband_apodizations)"
        )
    idx = np.arange(n) - n // 2  # spectral index n of sample position 0 ... N-1
    wrapped = np.zeros_like(w)
    wrapped[:, idx % n] = w  # apodization on the FFT's bin order

    def split(a: np.ndarray) -> np.ndarray:
        spec = np.fft.ifft(a, axis=-1)[..., None, :]  # G_n at bin n mod N (A = fft(G))
        return np.fft.fft(spec * wrapped, axis=-1)  # (..., look, depth)

    looks = xr.apply_ufunc(
        split,
        f,
        input_core_dims=[["depth"]],
        output_core_dims=[["look", "depth"]],
        dask="forbidden",
    )
    return label_looks(looks.transpose("look", *f.dims), "frequency")


#: Looks: a labelled, finite, non-empty DataArray with a ``look`` dim (the decorator's checks).
_LOOKS = {"looks": ArraySpec(labelled=True, keep_labels=True, dims=("look",), extra_dims=True)}


@preprocess_and_wrap(checks=_LOOKS)
def compound(looks: xr.DataArray, mode: str = "intensity") -> xr.DataArray:
    """Average looks (dim ``look``) into one intensity image.

    ``"intensity"``: ``mean |A_i|^2``; ``"magnitude"``: ``(mean |A_i|)^2`` (the squared mean
    amplitude, in intensity units); ``"complex"``: ``|mean A_i|^2`` (removes no speckle of one
    realisation; raises the SNR of noisy looks).

    Examples
    --------
    >>> import numpy as np
    >>> import xarray as xr
    >>> import speckle
    >>> looks = xr.DataArray(np.ones((3, 2, 2)), dims=("look", "depth", "x"))
    >>> speckle.compound(looks).values
    array([[1., 1.],
           [1., 1.]])
    """
    check_choice(mode, "mode", AVERAGING)
    if mode == "intensity":
        out = (abs(looks) ** 2).mean("look")
    elif mode == "magnitude":
        out = abs(looks).mean("look") ** 2
    else:
        out = abs(looks.mean("look")) ** 2
    return out.rename("intensity").assign_attrs(
        attrs(
            "dimensionless",
            f"{mode}-averaged intensity of {looks.sizes['look']} looks",
            averaging=mode,
        )
    )


@preprocess_and_wrap(checks=_LOOKS)
def noisy_looks(
    looks: xr.DataArray,
    snr_db: float,
    *,
    seed: int,
    signal_intensity: float | None = None,
) -> xr.DataArray:
    """Each look plus its own white receiver noise, circular complex Gaussian.

    Parameters
    ----------
    looks : xarray.DataArray
        Complex looks with a ``look`` dim.
    snr_db : float
        Signal intensity over noise intensity per pixel, in dB.
    seed : int
        Look ``i`` draws from ``SeedSequence(seed, spawn_key=(i,))``.
    signal_intensity : float, optional
        The signal intensity the SNR refers to (> 0), the same for every look (one receiver:
        e.g. the single look's mean intensity); default: each look's own mean intensity.

    Returns
    -------
    xarray.DataArray
        The looks plus noise (attrs ``snr_db``, ``noise_intensity`` of the first look).

    Examples
    --------
    >>> import numpy as np
    >>> import xarray as xr
    >>> import speckle
    >>> looks = xr.DataArray(np.ones((2, 32, 32), complex), dims=("look", "depth", "x"))
    >>> noisy = speckle.noisy_looks(looks, 10.0, seed=1)
    >>> round(float((abs(noisy - looks) ** 2).mean()), 2)  # noise intensity: 10 dB below 1
    0.1
    """
    snr = check_real(snr_db, "snr_db")
    sd = check_int(seed, "seed", low=0)
    ref = (
        None
        if signal_intensity is None
        else check_real(signal_intensity, "signal_intensity", low=0, low_inclusive=False)
    )
    lk = looks.transpose("look", ...)
    out = np.empty(lk.shape, dtype=np.complex128)
    sigma2 = []
    for i in range(lk.shape[0]):
        v = lk.values[i]
        s2 = (float(np.mean(np.abs(v) ** 2)) if ref is None else ref) / 10 ** (snr / 10)
        rng = np.random.default_rng(np.random.SeedSequence(sd, spawn_key=(i,)))
        e = rng.standard_normal((2, *v.shape))
        out[i] = v + np.sqrt(s2 / 2) * (e[0] + 1j * e[1])
        sigma2.append(s2)
    res = lk.copy(data=out).transpose(*looks.dims)
    return res.assign_attrs(looks.attrs, snr_db=snr, noise_intensity=sigma2[0])


@preprocess_and_wrap(checks={"tau": ArraySpec(kind="real")})
def brownian_g1(tau: object, diffusion: float, k0: float) -> np.ndarray:
    """Field autocorrelation ``exp(-q^2 D tau)``, ``q = 2 k0`` (rad/µm, in the medium).

    ``tau`` in s (>= 0), ``diffusion`` ``D`` in µm^2/s (>= 0); the one implementation is
    :func:`speckle.analysis.dynamics_theory.g1_brownian`.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> speckle.brownian_g1(np.array([0.0, 1e-3]), 1.0, 10.0).round(6)  # exp(-4 k0^2 D tau)
    array([1.     , 0.67032])
    """
    t = np.asarray(tau, dtype=float)  # named as here (g1_brownian calls it lag)
    if np.any(t < 0):
        raise ValueError("tau must be >= 0 (s)")
    return g1_brownian.__wrapped__(t, diffusion=diffusion, k0=k0)  # tau checked once, here


def brownian_frames(
    scene: xr.Dataset, n_frames: int, *, diffusion: float, interval: float, seed: int
) -> xr.Dataset:
    """The scene at ``n_frames`` times ``interval`` s apart, scatterers in Brownian motion.

    Between frames every scatterer moves by independent Gaussian steps of variance
    ``2 D interval`` (µm^2) along each axis it has (``z``, and ``x``, ``y`` of a shared scene).

    Parameters
    ----------
    scene : xarray.Dataset
        Shared scene or independent A-lines (only ``z`` moves there).
    n_frames : int
        Frames (>= 1); frame 0 is ``scene``.
    diffusion : float
        Diffusion coefficient ``D`` in µm^2/s, >= 0.
    interval : float
        Time between frames in s, > 0.
    seed : int
        Seed of the steps (non-negative).

    Returns
    -------
    xarray.Dataset
        The positions with a new leading dim ``frame`` (coordinate ``time`` in s).

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(4, 2.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> frames = speckle.brownian_frames(scene, 3, diffusion=1.0, interval=1e-3, seed=2)
    >>> frames.z.dims[0], frames.sizes[frames.z.dims[0]]
    ('frame', 3)
    """
    nf = check_int(n_frames, "n_frames", low=1)
    d = check_real(diffusion, "diffusion", low=0)
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    sd = check_int(seed, "seed", low=0)
    if not isinstance(scene, xr.Dataset) or "z" not in scene:
        raise TypeError("scene must be a scatterer Dataset with a variable 'z'")
    if scene.z.size == 0:
        raise ValueError("scene must hold at least one scatterer, got none")
    axes = sum(a in scene for a in ("z", "x", "y"))
    check_memory(2 * 8.0 * nf * scene.z.size * axes, "n_frames", f"{nf} frames of the scene")
    # one implementation: the scene layer's Brownian motion, its time dim named frame here
    out = brownian_motion(scene, np.arange(nf) * dt, diffusion=d, seed=sd)
    out = out.rename_dims(time="frame").assign_coords(
        time=coord("time", out.time.values, "time of the frame", dims="frame")
    )
    for k in [k for k in out.attrs if k not in scene.attrs]:
        del out.attrs[k]
    return out.assign_attrs(
        diffusion=d, diffusion_units=units_of("diffusion"), frame_interval=dt, brownian_seed=sd
    )
