"""The spectrometer chain of an SD-OCT system: interferogram on the camera, then processing.

The paper's model (:func:`speckle.ascan`) treats the ``N`` spectral components as ideal: equally
spaced in ``k`` and each a delta. Here each step of a real system is optional; with every step
off (wavenumber-linear sampling, delta pixels, complex detection, no DC, no apodization) the chain
is the paper's model to rounding.

Camera (:func:`interferogram`)
    Each camera pixel ``i`` (centre ``k_i``, width ``w_i`` in rad/µm, a Gaussian spectrometer
    line of FWHM ``r_i``) records, for a path difference ``d``, the carrier ``exp(2i k d)``
    averaged over the pixel and the line:  ``exp(2i k_i d) g_i(d)``,
    ``g_i(d) = sinc(w_i d) exp(-(r_i d)^2/(4 ln2))`` (``sinc x = sin x / x``; box average and
    Gaussian characteristic function). The source weight ``S`` and the dispersion phase are
    taken constant across one pixel (they vary on the scale of the whole spectrum). The signal
    is ``DC + cross + autocorrelation``:

    * cross term ``sqrt(P_r) S_i exp(i phi(k_i)) sum_j a_j exp(2i k_i z_j) g_i(z_j)``; with
      ``detection="complex"`` it is recorded as is (the paper's analytic signal), with
      ``"real"`` as ``2 Re(cross)``, whose transform holds the image and its mirror at ``-z``;
    * DC ``P_r S_i`` (reference arm) and autocorrelation ``S_i sum_jl a_j a_l^* exp(2i k_i
      (z_j - z_l)) g_i(z_j - z_l)`` (sample-arm self-interference, near zero delay).

    ``phi(k) = sum_p c_p (k - k0)^p`` (orders ``p >= 2``, ``c_p`` in µm^p) is the dispersion
    mismatch between the arms; it enters the cross term only.

Processing (:func:`process_interferogram`)
    background subtraction, k-linearisation by resampling (``linear``, ``cubic``; ``exact``
    evaluates the camera model on the grid, see :func:`system_ascan`), numerical dispersion
    compensation (multiply by ``exp(-i phi)``), a spectral apodization (none, Hann, Gaussian) and
    the DFT ``A(q) = sum_n F_n exp(-2i pi n q/N)`` of the paper's Eq. 4.

Closed forms (tested): roll-off ``|g(z)|^2`` (:func:`rolloff`); a Gaussian spectrum of FWHM
``Dk`` with phase ``c_2 (k - k0)^2`` gives a Gaussian PSF broadened by
``sqrt(1 + (c_2 Dk^2/(4 ln2))^2)`` (= ``sqrt(1 + (4 ln2 c_2/dz^2)^2)`` with the amplitude-PSF
FWHM ``dz = 4 ln2/Dk``; the pulse-broadening formula with GDD -> ``c_2``); the axial intensity
correlation of speckle follows the apodized spectrum (:func:`axial_intensity_correlation`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._deprecate import keyword_only, moved, renamed_parameters
from .._validate import (
    as_finite_array,
    check_bool,
    check_choice,
    check_int,
    check_memory,
    check_real,
)
from ._closed_forms import (
    APODIZATIONS,
    CHUNK_ELEMENTS,
    axial_intensity_correlation,
    check_dispersion,
    dispersion_phase,
    interpolation_gain,
    resampling_error,
    spectral_apodization,
)
from ._rolloff import carrier_response, rolloff_power

__all__ = [
    "APODIZATIONS",
    "DETECTIONS",
    "RESAMPLING",
    "axial_intensity_correlation",
    "camera_sampling",
    "camera_signal",
    "carrier_response",
    "check_dispersion",
    "dispersion_phase",
    "interferogram",
    "interferogram_bytes",
    "interpolation_gain",
    "linearize",
    "process_interferogram",
    "resampling_error",
    "resampling_response",
    "rolloff_power",
    "spectral_apodization",
    "system_ascan",
    "to_pixels",
]


#: Retired names (:data:`speckle.conventions.RETIRED`) resolve to the new ones, warning.
__getattr__ = moved(
    __name__,
    __name__,
    [],
    {
        "process": "process_interferogram",
        "spectral_window": "spectral_apodization",
        "WINDOWS": "APODIZATIONS",
    },
)

DETECTIONS = ("complex", "real")
RESAMPLING = ("none", "linear", "cubic", "exact")
SAMPLINGS = ("wavelength", "wavenumber")


# --- closed forms of the chain (the rest: speckle.system._closed_forms) ---------------------
def resampling_response(system, z: object, method: str) -> np.ndarray:
    """Amplitude factor of the k-linearisation on a reflector's peak, from the kernel's response.

    The processing interpolates the wavelength-linear camera signal onto the linear-``k`` grid.
    At grid point ``k_n`` between camera pixels ``i`` and ``i + 1`` (step ``h_n``, fractional
    position ``t_n``) a reflector at depth ``z`` is a tone of ``theta_n = 2 z h_n`` per camera
    sample, so the interpolated signal is the exact one times :func:`interpolation_gain`
    ``H(theta_n, t_n)``. The DFT peak (pixel of ``z``) sums the grid samples weighted by the
    source, hence the factor

        ``F(z) = sum_n S(k_n) H(2 z h_n, t_n) / sum_n S(k_n)``

    (complex; ``|F|^2`` is the power attenuation). It neglects the change of the camera step
    within the kernel's support and the spline's end conditions (both second order). The
    fractional positions are the system's own (they drift slowly across the camera, so ``t``
    is not uniform and the mean response ``sinc^2(theta/2)`` would not do).

    Parameters
    ----------
    system : speckle.System
        The system (wavelength-linear camera, processing grid).
    z : array_like
        Reflector depths ``z`` in µm (medium).
    method : {"linear", "cubic", "exact"}
        The k-linearisation of :func:`system_ascan` (``"exact"``: 1).

    Returns
    -------
    numpy.ndarray
        Complex factor, shape of ``z``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> system = speckle.example_system("840nm")
    >>> f = speckle.resampling_response(system, np.array([0.0, 500.0]), "exact")
    >>> abs(f).round(6)  # exact resampling: no loss at any depth
    array([1., 1.])
    """
    z = as_finite_array(z, "z")
    check_choice(method, "method", ("linear", "cubic", "exact"))
    grid = grid_wavenumbers(system)
    cam = camera_sampling(system)["wavenumber"]
    i = np.clip(np.searchsorted(cam, grid, side="right") - 1, 0, cam.size - 2)
    h = cam[i + 1] - cam[i]
    t = np.clip((grid - cam[i]) / h, 0.0, 1.0)
    weights = source_weights(system, grid)
    out = np.empty(z.shape, complex)
    flat = z.ravel()
    for j0 in range(0, flat.size, max(1, CHUNK_ELEMENTS // grid.size)):
        zz = flat[j0 : j0 + max(1, CHUNK_ELEMENTS // grid.size), None]
        gain = interpolation_gain(2 * zz * h, t, method)
        out.ravel()[j0 : j0 + zz.shape[0]] = gain @ weights / weights.sum()
    return out


# --- camera ---------------------------------------------------------------------------------
def _as_pixel_array(value: object, name: str, size: int) -> np.ndarray:
    arr = as_finite_array(value, name)
    if arr.ndim == 0:
        arr = np.full(size, float(arr))
    if arr.shape != (size,):
        raise ValueError(f"{name} must be a scalar or hold one value per camera pixel ({size})")
    if np.any(arr < 0):
        raise ValueError(f"{name} must be >= 0 (rad/µm)")
    return arr


def interferogram(
    z: object,
    amplitude: object,
    wavenumber: object,
    spectrum: object,
    *,
    k0: float = 0.0,
    pixel_width: object = 0.0,
    resolution: object = 0.0,
    dispersion: Mapping | None = None,
    detection: str = "complex",
    dc: bool = False,
    autocorrelation: bool = False,
    reference_power: float = 1.0,
    method: str = "direct",
    tol: float | None = None,
) -> np.ndarray:
    """Spectral interferogram recorded by the camera pixels (module docstring for the model).

    Parameters
    ----------
    z : array_like, shape (..., M)
        Scatterer depths in µm (medium) from the zero delay; negative depths (zero delay inside
        the sample) are allowed. Leading dims are A-lines.
    amplitude : array_like
        Complex amplitudes, same shape as ``z`` (zeros pad ragged lines).
    wavenumber : array_like, shape (K,)
        Centres ``k_i`` of the camera pixels, rad/µm (medium), any order.
    spectrum : array_like, shape (K,)
        Source weights ``S(k_i)`` (>= 0).
    k0 : float
        Centre of the dispersion expansion, rad/µm.
    pixel_width, resolution : float or array_like (K,)
        Pixel width and spectrometer-line FWHM in ``k`` (rad/µm, >= 0); 0 = delta pixels.
    dispersion : mapping, optional
        ``{order: coefficient}``, orders >= 2, coefficients in µm^order.
    detection : {"complex", "real"}
        Record the cross term as is (the paper's model) or as ``2 Re`` (a real camera).
    dc, autocorrelation : bool
        Add the reference-arm DC term ``P_r S`` / the sample autocorrelation term.
    reference_power : float
        Reference-arm power ``P_r`` (> 0) relative to unit scatterer amplitude.
    method : {"direct", "finufft"}
        ``"direct"``: exact float64 sum over scatterers and pixels (``O(M K)`` per line).
        ``"finufft"``: FINUFFT type-3 transforms per line (sources ``2 z_j``, targets ``k_i``).
        A uniform pixel response (e.g. a k-linear camera, or delta pixels) moves onto the
        scatterers (one transform); one varying smoothly with ``k`` (a wavelength-linear
        camera) is expanded in Chebyshev polynomials of ``k`` (one batched transform of a few
        tens of terms). The autocorrelation of finite pixels, a sum over scatterer pairs,
        uses the pairs' path differences as sources.
    tol : float, optional
        Requested relative accuracy in (0, 1) of the cross term for ``"finufft"`` (FINUFFT runs
        at ``tol/20``); default 1e-12.

    Returns
    -------
    numpy.ndarray
        Shape (..., K); complex128 for ``"complex"``, float64 for ``"real"``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> k = np.linspace(7.0, 8.0, 256)  # camera pixels, rad/µm
    >>> signal = speckle.interferogram(np.array([100.0]), np.array([1.0 + 0j]), k, np.ones(256))
    >>> signal.shape
    (256,)
    """
    check_choice(detection, "detection", DETECTIONS)
    check_bool(dc, "dc")
    check_bool(autocorrelation, "autocorrelation")
    k = as_finite_array(wavenumber, "wavenumber")
    if k.ndim != 1 or k.size < 2:
        raise ValueError("wavenumber must be 1-D with at least 2 camera pixels")
    s = as_finite_array(spectrum, "spectrum")
    if s.shape != k.shape:
        raise ValueError(f"spectrum must have the shape of wavenumber {k.shape}, got {s.shape}")
    if np.any(s < 0):
        raise ValueError("spectrum weights must be >= 0")
    w = _as_pixel_array(pixel_width, "pixel_width", k.size)
    r = _as_pixel_array(resolution, "resolution", k.size)
    pr = check_real(reference_power, "reference_power", low=0, low_inclusive=False)
    check_choice(method, "method", ("direct", "finufft"))
    eps = 1e-12 if tol is None else check_real(tol, "tol", low=0, high=1, low_inclusive=False,
                                                high_inclusive=False)  # fmt: skip

    phase = np.exp(1j * dispersion_phase(k, k0, dispersion))
    zz = as_finite_array(z, "z")
    aa = as_finite_array(amplitude, "amplitude", dtype=np.complex128)
    if zz.ndim == 0 or aa.shape != zz.shape:
        raise ValueError(
            f"z and amplitude must have the same shape (..., M); got {zz.shape} and {aa.shape}"
        )
    batch = zz.shape[:-1]
    z2, a2 = zz.reshape(-1, zz.shape[-1]), aa.reshape(-1, zz.shape[-1])
    finite = bool(np.any(w) or np.any(r))
    check_memory(
        interferogram_bytes(
            z2.shape[0],
            z2.shape[1],
            k.size,
            method=method,
            finite_pixels=finite,
            autocorrelation=autocorrelation,
        ),
        "z (lines x scatterers) or the camera pixels",
        "the camera signal",
    )
    carrier = _carrier(z2, a2, k, w, r, method, eps)
    cross = np.sqrt(pr) * s * phase * carrier
    out = cross if detection == "complex" else 2 * cross.real
    if dc:
        out = out + pr * s
    if autocorrelation:
        ideal = not (np.any(w) or np.any(r))
        auto = np.abs(carrier) ** 2 if ideal else _autocorrelation(z2, a2, k, w, r, method, eps)
        out = out + s * auto
    return out.reshape(*batch, k.size)


@keyword_only("method", "finite_pixels", "autocorrelation")
def interferogram_bytes(
    lines: int,
    scatterers: int,
    pixels: int,
    *,
    method: str = "direct",
    finite_pixels: bool = True,
    autocorrelation: bool = False,
) -> float:
    """Estimated peak memory (bytes) of :func:`interferogram`.

    The signal and its terms (3 complex (lines, pixels) arrays), the direct sum's chunk
    (:data:`CHUNK_ELEMENTS` complex phase factors, twice with a pixel response), the Chebyshev
    coefficients of ``"finufft"`` with a varying response (up to 256 terms per scatterer, the
    values and the coefficients), and the pair sources of the autocorrelation of finite pixels
    (``M (M - 1)/2`` pairs of one line: two indices, a depth and a product). The arguments
    are checked as :func:`interferogram` takes them (``ValueError``/``TypeError`` naming one).

    Examples
    --------
    >>> import speckle
    >>> speckle.interferogram_bytes(16, 1000, 1024) > 0
    True
    """
    lines = check_int(lines, "lines", low=1)
    scatterers = check_int(scatterers, "scatterers", low=0)
    pixels = check_int(pixels, "pixels", low=1)
    check_choice(method, "method", ("direct", "finufft"))
    finite_pixels = check_bool(finite_pixels, "finite_pixels")
    autocorrelation = check_bool(autocorrelation, "autocorrelation")
    out = 3 * 16.0 * lines * pixels
    work = 2 * 16.0 * CHUNK_ELEMENTS
    if method == "finufft" and finite_pixels:
        work = max(work, 2 * 16.0 * 256 * lines * scatterers)
    pairs = 0.0
    if autocorrelation and finite_pixels:
        pairs = 40.0 * scatterers * (scatterers - 1) / 2 + 16.0 * pixels
    return out + work + pairs


def _carrier(z, a, k, w, r, method, tol):
    """``sum_j a_j exp(2i k_i z_j) g_i(z_j)`` for lines (B, M) -> (B, K) by ``method``."""
    if method == "direct":
        return _carrier_sum(z, a, k, w, r)
    if np.ptp(w) == 0 and np.ptp(r) == 0:
        return _carrier_nufft(z, a, k, w[0], r[0], tol)
    return _carrier_chebyshev(z, a, k, w, r, tol)


def _carrier_sum(z, a, k, w, r):
    """``sum_j a_j exp(2i k_i z_j) g_i(z_j)`` for lines (B, M) -> (B, K), chunked."""
    b, m = z.shape
    out = np.zeros((b, k.size), dtype=np.complex128)
    ideal = not (np.any(w) or np.any(r))
    mstep = max(1, min(m, CHUNK_ELEMENTS // k.size))  # scatterers per chunk
    step = max(1, CHUNK_ELEMENTS // (mstep * k.size))  # lines per chunk
    for b0 in range(0, b, step):
        for m0 in range(0, m, mstep):
            zc = z[b0 : b0 + step, m0 : m0 + mstep, None]
            terms = a[b0 : b0 + step, m0 : m0 + mstep, None] * np.exp(2j * k * zc)
            if not ideal:
                terms = terms * carrier_response(zc, w, r)
            out[b0 : b0 + step] += terms.sum(axis=1)
    return out


def _carrier_nufft(z, a, k, w, r, tol):
    """:func:`_carrier_sum` for a uniform response (scalars ``w``, ``r``) by FINUFFT type 3."""
    import finufft

    c = np.ascontiguousarray(a * carrier_response(z, w, r), dtype=np.complex128)
    x = np.ascontiguousarray(2 * z, dtype=np.float64)
    kk = np.ascontiguousarray(k, dtype=np.float64)
    out = np.empty((z.shape[0], k.size), dtype=np.complex128)
    # one thread: lines are independent, and OpenMP threads on a shared machine slow it ~80x
    plan = finufft.Plan(3, 1, eps=tol / 20, isign=1, dtype="complex128", nthreads=1)
    for b in range(z.shape[0]):
        plan.setpts(x[b], s=kk)
        out[b] = plan.execute(c[b])
    return out


def _chebyshev_fit(values: np.ndarray, u: np.ndarray, zmax: float, tol: float, name: str):
    """Chebyshev series (in ``u``) of per-pixel ``values`` (rad/µm) close enough for ``tol``.

    ``|dg/dw|`` and ``|dg/dr|`` are at most ``|z|``, so a fit residual ``e`` changes the
    response by at most ``zmax e``; the degree grows until that is below ``tol/10``.
    """
    from numpy.polynomial import chebyshev as C

    best = np.inf
    for deg in (2, 4, 8, 16, 32):
        coef = C.chebfit(u, values, min(deg, u.size - 1))
        best = min(best, np.max(np.abs(C.chebval(u, coef) - values)) * zmax)
        if best <= tol / 10:
            return coef
    raise ValueError(
        f"method='finufft': {name} is not a smooth function of k to the accuracy tol={tol:g} "
        f"asks (reachable: tol >= {10 * best:.1e}); use a larger tol or method='direct'"
    )


def _carrier_chebyshev(z, a, k, w, r, tol):
    """:func:`_carrier_sum` for a pixel response varying smoothly with ``k`` by FINUFFT.

    With ``u`` the pixel wavenumber mapped to [-1, 1], ``g(z, u) = sum_p c_p(z) T_p(u)``
    (Chebyshev interpolation in ``u`` for each scatterer, the degree doubled until the series
    tail is below ``tol/10`` of ``max |g|``), so the sum is ``sum_p T_p(u_i) F_p(k_i)`` with
    ``F_p`` one FINUFFT type-3 transform of the strengths ``a_j c_p(z_j)`` (all ``p`` in one
    batched plan).
    """
    import finufft
    from numpy.polynomial import chebyshev as C

    lo, hi = k.min(), k.max()
    u = (2 * k - (lo + hi)) / (hi - lo)
    zmax = float(np.abs(z).max())
    cw = _chebyshev_fit(w, u, zmax, tol, "pixel_width")
    cr = _chebyshev_fit(r, u, zmax, tol, "resolution")
    for n_nodes in (16, 32, 64, 128, 256):
        nodes = np.cos(np.pi * (np.arange(n_nodes) + 0.5) / n_nodes)  # Chebyshev points
        g = carrier_response(z[..., None], C.chebval(nodes, cw), C.chebval(nodes, cr))
        # coefficients by the discrete cosine transform at the Chebyshev points
        cos = np.cos(np.pi * np.outer(np.arange(n_nodes), np.arange(n_nodes) + 0.5) / n_nodes)
        coef = (2.0 / n_nodes) * (g @ cos.T)
        coef[..., 0] /= 2
        tail = np.abs(coef[..., -2:]).max()
        if tail <= tol / 10 * max(np.abs(g).max(), np.finfo(float).tiny):
            break
    else:
        raise ValueError("method='finufft': the pixel response is not resolved by 256 "
                         "Chebyshev terms; use method='direct'")  # fmt: skip
    keep = n_nodes - 2  # the last two terms are below the tolerance
    basis = C.chebvander(u, keep - 1).T  # (P, K)
    out = np.empty((z.shape[0], k.size), dtype=np.complex128)
    kk = np.ascontiguousarray(k, dtype=np.float64)
    plan = finufft.Plan(3, 1, n_trans=keep, eps=tol / 20 / np.sqrt(keep), isign=1,
                        dtype="complex128", nthreads=1)  # fmt: skip
    for b in range(z.shape[0]):
        plan.setpts(np.ascontiguousarray(2 * z[b], dtype=np.float64), s=kk)
        strengths = np.ascontiguousarray((a[b][:, None] * coef[b, :, :keep]).T)  # (P, M)
        out[b] = np.einsum("pk,pk->k", plan.execute(strengths), basis)
    return out


def _autocorrelation(z, a, k, w, r, method="direct", tol=1e-12):
    """``sum_jl a_j a_l^* exp(2i k (z_j - z_l)) g(z_j - z_l)`` per line (real, (B, K)); the
    pair sum of finite pixels (delta pixels use ``|sum_j a_j exp(2i k z_j)|^2`` instead), the
    pairs ``j < l`` being the sources of :func:`_carrier` (``method``)."""
    b, m = z.shape
    j, l_ = np.triu_indices(m, k=1)
    out = np.empty((b, k.size))
    for i in range(b):
        self_terms = np.sum(np.abs(a[i]) ** 2)
        d, prod = (z[i, j] - z[i, l_])[None], (a[i, j] * np.conj(a[i, l_]))[None]
        pair = _carrier(d, prod, k, w, r, method, tol)
        out[i] = self_terms + 2 * pair[0].real
    return out


# --- processing -----------------------------------------------------------------------------
def _camera_signal(signal: object) -> np.ndarray:
    """A camera signal (..., K): real or complex numbers, every one finite (NaN counted)."""
    y = np.asarray(signal)
    if not (y.dtype.kind in "iufc" and y.ndim >= 1):
        raise TypeError(
            f"signal must be a numeric array (..., K) of camera samples, got dtype {y.dtype} "
            f"and shape {y.shape}"
        )
    if y.shape[-1] < 2 or y.size == 0:
        raise ValueError(f"signal must hold >= 2 camera samples along its last dim, got {y.shape}")
    return as_finite_array(y, "signal", dtype=np.complex128 if y.dtype.kind == "c" else float)


def linearize(signal: object, wavenumber: object, grid: object, method: str = "cubic"):
    """Resample a camera signal from the pixel wavenumbers onto the linear-``k`` grid.

    Parameters
    ----------
    signal : array_like, shape (..., K)
        Camera signal (real or complex) at ``wavenumber``.
    wavenumber : array_like, shape (K,)
        Pixel wavenumbers (strictly monotonic), rad/µm.
    grid : array_like, shape (N,)
        Target wavenumbers, rad/µm; must lie within the range of ``wavenumber`` (no
        extrapolation beyond rounding, 1e-9 of the range).
    method : {"linear", "cubic"}
        Piecewise-linear or not-a-knot cubic spline (:class:`scipy.interpolate.CubicSpline`).
    """
    from scipy.interpolate import CubicSpline

    check_choice(method, "method", ("linear", "cubic"))
    k = as_finite_array(wavenumber, "wavenumber")
    g = as_finite_array(grid, "grid")
    y = _camera_signal(signal)
    if y.shape[-1:] != k.shape:
        raise ValueError(f"signal's last dim must match wavenumber ({k.size}), got {y.shape}")
    dk = np.diff(k)
    if not (np.all(dk > 0) or np.all(dk < 0)):
        raise ValueError("wavenumber must be strictly monotonic")
    if dk[0] < 0:
        k, y = k[::-1], y[..., ::-1]
    slack = 1e-9 * (k[-1] - k[0])  # grid and pixel edges may differ by rounding
    if g.min() < k[0] - slack or g.max() > k[-1] + slack:
        raise ValueError(
            f"grid [{g.min():.6g}, {g.max():.6g}] rad/µm must lie within the camera's "
            f"[{k[0]:.6g}, {k[-1]:.6g}] rad/µm (no extrapolation)"
        )
    if method == "cubic":
        return CubicSpline(k, y, axis=-1)(g)
    i = np.clip(np.searchsorted(k, g, side="right") - 1, 0, k.size - 2)
    t = (g - k[i]) / (k[i + 1] - k[i])
    return (1 - t) * y[..., i] + t * y[..., i + 1]


def to_pixels(field: np.ndarray) -> np.ndarray:
    """Eq. 4's sum over components, ``A(q) = sum_n F_n exp(-2i pi n q/N)``, by one FFT.

    ``field`` (..., N) is ordered ``n = -(N//2) ... N-1-(N//2)``; ``ifftshift`` moves ``n = 0``
    to index 0, so this is an exact DFT (no extra phase factors).
    """
    return np.fft.fft(np.fft.ifftshift(field, axes=-1), axis=-1)


@renamed_parameters({"window": "apodization", "window_fwhm_fraction": "apodization_fwhm_fraction"})
def process_interferogram(
    signal: object,
    *,
    grid: object,
    k0: float,
    wavenumber: object | None = None,
    background: object | str | None = None,
    resample: str = "none",
    dispersion: Mapping | None = None,
    apodization: str = "none",
    apodization_fwhm_fraction: float = 0.5,
) -> np.ndarray:
    """Camera signal -> complex A-scan(s): background, k-linearisation, dispersion, apodization,
    DFT.

    Parameters
    ----------
    signal : array_like, shape (..., K)
        Camera signal from :func:`interferogram`.
    grid : array_like, shape (N,)
        Linear-``k`` grid ``k_n = k0 + n pi/H`` (rad/µm), ``n = -(N//2) ...``.
    k0 : float
        Grid centre (the ``n = 0`` component) and dispersion expansion centre, rad/µm.
    wavenumber : array_like, shape (K,), optional
        Pixel wavenumbers; needed to resample (``resample`` ``"linear"`` / ``"cubic"``).
    background : array_like (K,) or "mean", optional
        Spectrum subtracted before anything else, or ``"mean"``: the mean over all A-lines
        (leading dims), which removes the DC term and the mean autocorrelation.
    resample : {"none", "linear", "cubic"}
        ``"none"``: the signal is taken as already on ``grid`` (it must have ``N`` samples, in
        increasing ``k``); skipping linearisation on a wavelength-linear camera is what
        broadens the PSF with depth.
    dispersion : mapping, optional
        ``{order: coefficient}`` to compensate: the signal is multiplied by ``exp(-i phi(k_n))``.
    apodization : {"none", "hann", "gaussian"}
        Spectral apodization (window over wavenumber, :func:`spectral_apodization`).
    apodization_fwhm_fraction : float
        FWHM of the Gaussian apodization as a fraction of ``N``.

    Returns
    -------
    numpy.ndarray
        Complex A-scans (..., N); pixel ``q`` at depth ``q H/N``, negative depths wrap to the
        end (the mirror image of a real signal appears there).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> n, depth_range = 64, 512.0
    >>> k0 = 64 * np.pi / depth_range
    >>> grid = k0 + (np.arange(n) - n // 2) * np.pi / depth_range  # k_n = k0 + n pi/H
    >>> z, a = np.array([200.0]), np.array([1.0 + 0j])  # one reflector at 200 µm
    >>> signal = speckle.interferogram(z, a, grid, np.ones(n), k0=k0)
    >>> ascan = speckle.process_interferogram(signal, grid=grid, k0=k0)
    >>> int(abs(ascan).argmax())  # the reflector's pixel, 200 µm / 8 µm
    25
    """
    check_choice(resample, "resample", ("none", "linear", "cubic"))
    check_choice(apodization, "apodization", APODIZATIONS)
    fwhm = check_real(
        apodization_fwhm_fraction, "apodization_fwhm_fraction", low=0, low_inclusive=False
    )
    comp = check_dispersion(dispersion)
    g = as_finite_array(grid, "grid")
    if g.ndim != 1 or g.size < 2:
        raise ValueError(f"grid must be a 1-D linear-k grid of >= 2 wavenumbers, got {g.shape}")
    kc = check_real(k0, "k0", low=0)
    y = _camera_signal(signal)
    if background is not None:
        if isinstance(background, str):
            check_choice(background, "background", ("mean",))
            lines = y.reshape(-1, y.shape[-1])
            if y.ndim < 2 or lines.shape[0] < 2:
                raise ValueError(
                    "background='mean' needs at least 2 A-lines (leading dims of signal); "
                    f"got signal of shape {y.shape}"
                )
            bg = lines.mean(axis=0)
        else:
            bg = as_finite_array(background, "background", dtype=y.dtype)
            if bg.shape != y.shape[-1:]:
                raise ValueError(f"background must have shape {y.shape[-1:]}, got {bg.shape}")
        y = y - bg
    if resample == "none":
        if y.shape[-1] != g.size:
            raise ValueError(
                f"resample='none' needs the signal on the grid ({g.size} samples), got "
                f"{y.shape[-1]}; pass wavenumber= and resample='linear' or 'cubic'"
            )
    else:
        if wavenumber is None:
            raise ValueError(f"resample={resample!r} needs wavenumber= (camera pixels, rad/µm)")
        y = linearize(y, wavenumber, g, resample)
    f = y * spectral_apodization(g.size, apodization, fwhm)
    if comp:
        f = f * np.exp(-1j * dispersion_phase(g, kc, comp))
    return to_pixels(f.astype(np.complex128, copy=False))


# --- a whole system -------------------------------------------------------------------------
def camera_sampling(system, sampling: str = "wavelength", at: object | None = None) -> dict:
    """Camera pixel wavenumbers, widths and line FWHMs (rad/µm, increasing ``k``) of a system.

    Parameters
    ----------
    system : speckle.System
        The system.
    sampling : {"wavelength", "wavenumber"}
        A camera linear in wavelength (a grating spectrometer; pixel ``i`` spans
        ``lambda_i +- f dl/2``) or linear in ``k`` (a k-linear spectrometer; pixels on the grid,
        width ``f dk``).
    at : array_like, optional
        Wavenumbers (rad/µm) at which to evaluate a wavelength-linear camera's pixel width and
        line instead of its pixel centres (the ``"exact"`` linearisation).

    Returns
    -------
    dict
        ``wavenumber``, ``pixel_width``, ``resolution`` arrays, increasing ``k``.
    """
    check_choice(sampling, "sampling", SAMPLINGS)
    n = system.refractive_index
    if sampling == "wavenumber":
        k = grid_wavenumbers(system) if at is None else as_finite_array(at, "at")
        return {
            "wavenumber": k,
            "pixel_width": np.full(k.size, system.fill_factor * system.wavenumber_step),
            "resolution": np.full(k.size, system.resolution_k),
        }
    if at is None:
        lam = system.camera_wavelengths()[::-1]
    else:
        lam = 2 * np.pi * n / as_finite_array(at, "at")
    half = system.fill_factor * system.sampling_interval / 2
    return {
        "wavenumber": 2 * np.pi * n / lam,
        # 2 pi n (1/(lam - half) - 1/(lam + half)) without the cancellation
        "pixel_width": 2 * np.pi * n * 2 * half / ((lam - half) * (lam + half)),
        "resolution": 2 * np.pi * n * system.spectral_resolution / lam**2,
    }


def grid_wavenumbers(system) -> np.ndarray:
    """Linear-``k`` processing grid ``k_n = k0 + n dk`` of a system, rad/µm."""
    return system.k0 + (np.arange(system.n_pixels) - system.n_pixels // 2) * system.wavenumber_step


def source_weights(system, wavenumber: object) -> np.ndarray:
    """The system's Gaussian source ``S(k)`` at arbitrary wavenumbers (rad/µm)."""
    k = as_finite_array(wavenumber, "wavenumber")
    return np.exp(-4 * np.log(2) * ((k - system.source_wavenumber) / system.fwhm_k) ** 2)


def camera_signal(
    system,
    z: object,
    amplitude: object,
    *,
    sampling: str = "wavelength",
    pixel_width: bool = True,
    resolution: bool = True,
    detection: str = "real",
    dc: bool = False,
    autocorrelation: bool = False,
    reference_power: float = 1.0,
    dispersion: Mapping | None = None,
    on_grid: bool = False,
    method: str = "direct",
    tol: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A system's camera signal for a scene: ``(signal (..., K), pixel wavenumbers (K,))``.

    Pixels in increasing ``k``. ``on_grid=True`` evaluates the camera model on the processing
    grid instead (each virtual pixel with the width and line of a camera pixel at that
    wavelength): the error-free reference for k-linearisation. ``pixel_width`` /
    ``resolution`` switch the pixel integration and the spectrometer line on or off. Other
    parameters: :func:`camera_sampling`, :func:`interferogram`.
    """
    grid = grid_wavenumbers(system)
    for flag, name in ((pixel_width, "pixel_width"), (resolution, "resolution"),
                       (on_grid, "on_grid")):  # fmt: skip
        check_bool(flag, name)
    cam = camera_sampling(system, sampling, at=grid if on_grid else None)
    sig = interferogram(
        z,
        amplitude,
        cam["wavenumber"],
        source_weights(system, cam["wavenumber"]),
        k0=system.k0,
        pixel_width=cam["pixel_width"] if pixel_width else 0.0,
        resolution=cam["resolution"] if resolution else 0.0,
        dispersion=dispersion,
        detection=detection,
        dc=dc,
        autocorrelation=autocorrelation,
        reference_power=reference_power,
        method=method,
        tol=tol,
    )
    return sig, cam["wavenumber"]


@renamed_parameters({"window": "apodization", "window_fwhm_fraction": "apodization_fwhm_fraction"})
def system_ascan(
    system,
    z: object,
    amplitude: object,
    *,
    background: object | str | None = None,
    resample: str = "cubic",
    compensate: Mapping | None = None,
    apodization: str = "none",
    apodization_fwhm_fraction: float = 0.5,
    **camera,
) -> np.ndarray:
    """A-scans of a scene through a system's camera (:func:`camera_signal`) and processing.

    ``resample="exact"`` evaluates the camera model directly on the processing grid, the
    error-free reference for ``"linear"`` and ``"cubic"``; ``"none"`` takes the camera pixels
    as if they were linear in ``k``. ``compensate`` is the dispersion the processing removes
    (the same mapping as ``dispersion`` for perfect compensation). ``camera``: keyword
    arguments of :func:`camera_signal` (``sampling``, ``pixel_width``, ``resolution``,
    ``detection``, ``dc``, ``autocorrelation``, ``reference_power``, ``dispersion``). Other
    parameters: :func:`process_interferogram`.

    Returns
    -------
    numpy.ndarray
        Complex A-scans (..., N), pixel ``q`` at ``q H/N``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> system = speckle.example_system("840nm")
    >>> img = speckle.system_ascan(system, np.array([[200.0]]), np.array([[1.0 + 0j]]))
    >>> img.shape  # (lines, pixels)
    (1, 2048)
    """
    check_choice(resample, "resample", RESAMPLING)
    sig, k = camera_signal(system, z, amplitude, on_grid=resample == "exact", **camera)
    interpolate = resample in ("linear", "cubic")
    return process_interferogram(
        sig,
        grid=grid_wavenumbers(system),
        k0=system.k0,
        wavenumber=k if interpolate else None,
        background=background,
        resample=resample if interpolate else "none",
        dispersion=compensate,
        apodization=apodization,
        apodization_fwhm_fraction=apodization_fwhm_fraction,
    )
