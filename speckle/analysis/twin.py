"""A scanner's twin: fit the model's system to a measured image, simulate it, predict strain limits.

:func:`fit_system` measures, on a region of a user's image (:func:`speckle.load_image`), the
statistics that the model's system parameters set, and inverts their theory:

* **spectrum**: the intensity autocorrelation along depth (lags ``1 .. max_lag``) against
  :func:`~speckle.analysis.autocorrelation.axial_correlation_theory` of a Gaussian spectrum
  (FWHM as a fraction of the pixel band ``delta_k``) and of a rectangular one (full width as a
  fraction of the band, edge components weighted by their fractional overlap so the width is a
  continuous parameter); the shape with the smaller rms residual is kept. At finite density
  the Pearson correlation is ``(|gamma(m)|^2 + x d(m)) / ((1 + 1/r)^2 + x)`` (``x`` the
  contrast excess below, ``d`` the normalised autocorrelation of the intensity PSF, ``r`` the
  SNR): the scatterers' own intensities correlate neighbouring pixels even where ``gamma`` is
  0; across A-lines ``d = |gamma|^2``, so only the denominator changes. ``x <= 0`` is the dense
  limit (:func:`~speckle.analysis.autocorrelation.fit_spectral_width`, ``fit_waist``);
* **beam waist** ``w0``: the lateral autocorrelation against ``exp(-2 m^2 p^2/w0^2)`` (A-line
  pitch ``p``), and the same per depth band (``band_waist``), with a chi-square test of a
  depth-independent waist (``waist_depth_p_value``; the model's focused beam keeps the lateral
  correlation depth-independent, see :mod:`speckle.imaging.beam`);
* **focus**: rows are correlated along depth (point-spread function) and across A-lines, so
  the row means of ``ln I`` have the covariance ``C`` of their mean over x, from the region's
  2-D autocovariance of ``ln I`` (summed over lateral lags to the first non-positive one,
  kept to the first non-positive depth lag; Toeplitz). The test statistic is the largest
  reduction of the generalised least-squares residual sum of squares of ``a + b z`` when the
  confocal term ``ln (1 + u^2)^(-3/2)``, ``u = (z - z_f)/z_R`` (the 2-D confocal response of
  :func:`speckle.beam_scan`), is added with a positive coefficient, scanned over ``z_f`` (the
  region and a quarter of it either side) and ``z_R`` (1/2 to 2 times ``k0 w0^2/2``, ``k0`` in
  the medium, ``w0`` the fitted waist). Its p-value (``focus_p_value``) is from a seeded
  Monte-Carlo null (``FOCUS_NULL_DRAWS`` correlated Gaussian residuals with covariance ``C``):
  ``p = (1 + #{null >= observed})/(1 + n)``. Below 1 % (``FOCUS_P_VALUE``) the mean intensity
  per row is fitted by ``A exp(-2 mu_t z) (1 + u^2)^(-3/2) + N``;
* **SNR and noise floor** from signal-free rows (``noise_rows``, or found above the region when
  neither they nor ``snr_db`` are given: :func:`fit_system`): ``SNR = <I_region>/<I_noise>
  - 1`` (the region holds signal plus noise), ``noise_floor`` = mean noise intensity (for log
  data: the mean log level of those rows, data units); white noise multiplies every lag >= 1
  by ``(r/(1 + r))^2``, which the fits include;
* **attenuation** ``mu_t`` (1/µm, intensity): ``-1/2`` the least-squares slope of the mean log
  intensity per row against depth in the medium (``pixel_size / refractive_index``), its SE
  from the sandwich variance with the row means' covariance ``C`` (above);
* **intensity floor** ``b`` and, for log data, the gain ``g`` and offset ``c`` of
  ``D = g ln I + c`` (:func:`~speckle.analysis.measured.fit_floor`: skewness of the log data);
* **scatterer density**: from the intensity contrast. For Poisson scatterers of unit amplitude
  and a point-spread function ``h``, ``<I^2>/<I>^2 = 2 + x`` with ``x = A4 / (rho A^2)``,
  ``A = int |h|^2``, ``A4 = int |h|^4`` (over pixels x pitches). With noise ``N = S/r`` and
  floor ``b S``, ``var I = (S + N)^2 + x S^2`` and ``<I> = S (1 + b) + N``, so ``x`` (and so
  ``inverse_density = 1/rho``) follows from the mean and variance of the region. At high
  density ``x`` is small against its error: ``inverse_density`` is then consistent with 0 and
  ``density_lower_bound`` (at 2 standard errors) is what the image says. For linear data a
  second estimate comes from ``var ln I`` (``inverse_density_log``): exact for Poisson
  scatterers through the fitted PSF with the fitted noise (:mod:`speckle.analysis.sparse`,
  no floor), it resolves low densities (0.5-4 per pixel per pitch), where the contrast's
  error grows with the fourth moment of ``I``. The two share every pixel and are combined by
  the inverse of their jackknife covariance (``inverse_density``; ``density_identified``
  when it exceeds 2 SE). For log data ``var D = g^2 var ln I`` with the gain ``g`` unknown:
  ``var ln I`` is not observed and the contrast is used alone (the ``method`` attribute says
  which).

Estimates use every pixel pair of the region (the autocorrelation is then that of
:func:`~speckle.analysis.autocorrelation.intensity_autocorrelation`). Standard errors:
delete-one-block jackknife over ``n_blocks`` contiguous blocks of A-lines (speckle is
correlated over a few lines, blocks are nearly independent): every quantity above is
re-estimated without each block (statistics pooled over the remaining blocks, no pair across a
block edge) and ``SE^2 = (n - 1)/n sum (theta_i - mean theta)^2``. With a ``frame`` dim the
statistics pool every frame and each jackknife sample deletes the same block from all frames.
The attenuation's SE and the focus test use the row means' covariance ``C`` instead (a block
jackknife of a slope over ~16 blocks understates its error under a wide beam); with a ``frame``
dim ``C`` is that of the frame-averaged ``ln I``, right whether the frames' speckle is
independent, identical or in between. When a focus is
found its fit is repeated on each jackknife sample (those errors, attenuation included, are the
jackknife's).

:meth:`SystemFit.simulate` images a shared scene of the fitted density through the fitted
spectrum and scanned (focused) beam (:func:`speckle.beam_scan`), attenuated, with white noise
at the fitted SNR, the floor, and the fitted log mapping and quantisation for log images: a
twin of the same kind, dims and coordinates. :meth:`SystemFit.failure_maps` deforms the twin's
scene (uniform compression, ``u_z = -s z``) and scores every strain estimator
(:func:`speckle.estimate_strain`) against the known strain.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy import linalg, optimize, signal, stats

from .._validate import check_choice, check_int, check_real
from ..conventions import attrs, coord, spacing
from ..imaging.beam import beam_scan
from ..system.noise import add_complex_noise
from . import autocorrelation as ac
from . import measured as ms
from .image_files import IMAGE_KINDS
from .phase import DEFAULT_MAX_BIAS
from .sparse import depth_intensity_psf, sparse_inverse_density
from .strain import estimate_strain

__all__ = [
    "SPECTRUM_SHAPES",
    "SystemFit",
    "fit_system",
    "rectangular_weights",
]

SPECTRUM_SHAPES = ("gaussian", "rectangular")
#: k0/delta_k assumed when ``k0`` is not given (the realism target's value).
DEFAULT_K0_DK = 10.0
#: Intensity contrast std/mean below which a linear image is suspected to be log data.
LOG_AS_LINEAR_CONTRAST = 0.5
FOCUS_P_VALUE = 0.01
FOCUS_NULL_DRAWS = 1000  # Monte-Carlo draws of the focus test's null (seeded)
FOCUS_SCAN_DEPTHS = 41  # focus depths scanned over the region and a quarter of it either side
FOCUS_SCAN_RAYLEIGH = 5  # Rayleigh ranges scanned, 1/2 to 2 times k0 w0^2/2
#: Rows above the region whose mean intensity is this many dB below the region's are candidate
#: signal-free rows (found when ``noise_rows`` is not given).
NOISE_ROW_DB = 10.0
#: Fewest contiguous signal-free rows accepted.
MIN_NOISE_ROWS = 4


def rectangular_weights(width_fraction: float, n_pixels: int) -> np.ndarray:
    """Spectral weights of a rectangular spectrum of full width ``width_fraction * delta_k``.

    Component ``n`` (offset ``(n - N//2)/N`` from the centre, in units of ``delta_k``) gets the
    fraction of its cell ``[offset - 1/(2N), offset + 1/(2N)]`` inside the band, so the weights
    change continuously with the width (1 fills the pixel band).
    """
    f = check_real(width_fraction, "width_fraction", low=0, low_inclusive=False, high=1.0)
    n = check_int(n_pixels, "n_pixels", low=8)
    off = (np.arange(n) - n // 2) / n
    lo, hi = np.maximum(off - 0.5 / n, -f / 2), np.minimum(off + 0.5 / n, f / 2)
    return np.sqrt(np.clip((hi - lo) * n, 0.0, 1.0))  # S^2 is the covered fraction


def _gaussian_weights(fwhm_fraction: float, n: int) -> np.ndarray:
    idx = (np.arange(n) - n // 2) / n
    return np.exp(-4 * np.log(2) * (idx / fwhm_fraction) ** 2)


def _weights(shape: str, width: float, n: int) -> np.ndarray:
    return _gaussian_weights(width, n) if shape == "gaussian" else rectangular_weights(width, n)


def _depth_theory(lags, weights, snr_db, excess):
    """Pearson intensity autocorrelation along depth at finite density (module docstring).

    ``(|gamma(m)|^2 + x d(m)) / ((1 + 1/r)^2 + x)`` with ``d`` the normalised autocorrelation of
    the intensity PSF; ``x <= 0`` is the dense limit of
    :func:`~speckle.analysis.autocorrelation.axial_correlation_theory`.
    """
    if excess <= 0:
        return ac.axial_correlation_theory(lags, weights, snr_db)
    g2 = ac.axial_correlation_theory(lags, weights, None)
    p2 = depth_intensity_psf(weights)
    circ = np.fft.ifft(np.abs(np.fft.fft(p2)) ** 2).real  # circular autocorrelation of |P|^2
    d = circ[(8 * np.asarray(lags, dtype=int)) % p2.size] / circ[0]
    inv_r = 0.0 if snr_db is None else 10 ** (-snr_db / 10)
    out = (g2 + excess * d) / ((1 + inv_r) ** 2 + excess)
    return np.where(np.asarray(lags) == 0, 1.0, out)


def _fit_gaussian(acf, n, snr_db, excess) -> tuple[float, float]:
    if excess <= 0:
        return ac.fit_spectral_width(acf, n, snr_db)
    lags = np.arange(1, acf.size)

    def residual(p):
        return _depth_theory(lags, _gaussian_weights(p[0], n), snr_db, excess) - acf[1:]

    res = optimize.least_squares(residual, 0.5, bounds=(0.02, 5.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _fit_waist(acf, snr_db, excess) -> tuple[float, float]:
    """Lateral: the incoherent term has the same shape, so only the denominator changes."""
    if excess <= 0:
        return ac.fit_waist(acf, snr_db)
    lags = np.arange(1, acf.size)
    inv_r = 0.0 if snr_db is None else 10 ** (-snr_db / 10)
    scale = (1 + excess) / ((1 + inv_r) ** 2 + excess)

    def residual(p):
        return scale * ac.lateral_correlation_theory(lags, p[0], 1.0) - acf[1:]

    res = optimize.least_squares(residual, 2.0, bounds=(0.05, 100.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _fit_rectangular(acf, n, snr_db, excess) -> tuple[float, float]:
    lags = np.arange(1, acf.size)

    def residual(p):
        return _depth_theory(lags, rectangular_weights(p[0], n), snr_db, excess) - acf[1:]

    best = min(np.linspace(0.1, 1.0, 19), key=lambda f: np.sum(residual([f]) ** 2))
    res = optimize.least_squares(residual, best, bounds=(2.0 / n, 1.0))
    return float(res.x[0]), float(np.sqrt(np.mean(res.fun**2)))


def _psf_excess(shape: str, width: float, waist_pitch: float, n: int) -> float:
    """``A4/A^2`` of the model's point-spread function, per pixel x pitch (module docstring)."""
    p2 = depth_intensity_psf(_weights(shape, width, n))  # one period, 8 samples per pixel (exact)
    depth = np.sum(p2**2) / 8.0 / (np.sum(p2) / 8.0) ** 2
    lateral = np.sqrt(2 / np.pi) / waist_pitch  # int exp(-8x^2/w^2) / (int exp(-4x^2/w^2))^2
    return float(depth * lateral)


def _pearson_pooled(pairs: list[tuple[np.ndarray, np.ndarray]]) -> float:
    a = np.concatenate([p[0].ravel() for p in pairs])
    b = np.concatenate([p[1].ravel() for p in pairs])
    a = a - a.mean()
    b = b - b.mean()
    return float(np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b)))


def _acf(blocks: list[np.ndarray], max_lag: int, axis: str) -> np.ndarray:
    """Pearson autocorrelation pooled over column blocks (no pair crosses a block edge).

    One block is :func:`speckle.analysis.autocorrelation.intensity_autocorrelation`'s value.
    """
    out = np.ones(max_lag + 1)
    for m in range(1, max_lag + 1):
        if axis == "depth":
            pairs = [(b[:-m], b[m:]) for b in blocks]
        else:
            pairs = [(b[:, :-m], b[:, m:]) for b in blocks if b.shape[1] > m]
        out[m] = _pearson_pooled(pairs)
    return out


@dataclass
class _Data:
    """The region (and noise rows) of one image, as log data and intensity (``kind``-aware)."""

    kind: str
    signal: np.ndarray  # log data D (log kind) or intensity (linear kinds), (depth, x)
    noise: np.ndarray | None
    dz: float  # depth step in the medium, µm
    pitch: float

    def pieces(self, cols: list[np.ndarray]) -> tuple[list, list | None, float, dict]:
        """Intensity blocks, noise intensity blocks, gain and floor fit over columns ``cols``."""
        sig = [self.signal[:, c] for c in cols]
        flat = np.concatenate([s.ravel() for s in sig])
        if self.kind == "log":
            d = xr.DataArray(np.hstack(sig), dims=("depth", "aline"), attrs={"scale": "log"})
            fl = ms.fit_floor(d)
            g, mean = float(fl["gain"]), float(flat.mean())
            inten = [np.exp((s - mean) / g) for s in sig]
            noise = (
                None
                if self.noise is None
                else [np.exp((self.noise[:, c] - mean) / g) for c in cols]
            )
        else:
            d = xr.DataArray(
                np.log(np.hstack(sig)), dims=("depth", "aline"), attrs={"scale": "log"}
            )
            fl = ms.fit_floor(d)
            g = 1.0
            inten = sig
            noise = None if self.noise is None else [self.noise[:, c] for c in cols]
        return inten, noise, g, {k: float(fl[k]) for k in ("floor", "gain", "offset")}


def _estimate(
    data: _Data,
    cols: list[np.ndarray],
    *,
    n_pixels: int,
    max_lag: int,
    n_bands: int,
    snr_db: float | None,
) -> dict[str, object]:
    """Every fitted quantity from the columns ``cols`` of the region (module docstring)."""
    inten, noise, g, fl = data.pieces(cols)
    i_all = np.hstack(inten)
    out: dict[str, object] = {"gain": fl["gain"], "offset": fl["offset"], "floor": fl["floor"]}
    log_i = np.log(i_all) if data.kind != "log" else (np.hstack([data.signal[:, c] for c in cols]))
    out["skewness"] = float(stats.skew(log_i.ravel()))
    out["excess_kurtosis"] = float(stats.kurtosis(log_i.ravel()))
    if noise is not None:
        n_all = np.hstack(noise)
        ratio = float(i_all.mean() / n_all.mean())
        snr_db = 10 * np.log10(ratio - 1) if ratio > 1 else np.nan
        out["noise_floor"] = float(
            np.hstack([data.noise[:, c] for c in cols]).mean()
            if data.kind == "log"
            else n_all.mean()
        )
    out["snr_db"] = np.nan if snr_db is None else float(snr_db)
    snr = None if snr_db is None or not np.isfinite(snr_db) else float(snr_db)
    depth_acf = _acf(inten, max_lag, "depth")
    lat_acf = _acf(inten, max_lag, "lateral")
    out["depth_autocorrelation"], out["lateral_autocorrelation"] = depth_acf, lat_acf
    # contrast excess x (noise and floor removed): the low-density term of every correlation
    r = 10 ** (snr / 10) if snr is not None else np.inf
    s_mean = i_all.mean() / (1 + fl["floor"] + 1 / r)
    excess = float((i_all.var() - (s_mean * (1 + 1 / r)) ** 2) / s_mean**2)
    out["contrast_excess"] = excess
    out["gaussian_fwhm_fraction"], out["gaussian_rms"] = _fit_gaussian(
        depth_acf, n_pixels, snr, excess
    )
    out["rectangular_width_fraction"], out["rectangular_rms"] = _fit_rectangular(
        depth_acf, n_pixels, snr, excess
    )
    out["waist_pitch"], out["waist_rms"] = _fit_waist(lat_acf, snr, excess)
    bands = np.array_split(np.arange(i_all.shape[0]), n_bands) if n_bands >= 2 else []
    out["band_waist_pitch"] = np.array(
        [
            _fit_waist(_acf([b[rb] for b in inten], max_lag, "lateral"), snr, excess)[0]
            for rb in bands
        ]
    )
    rows = np.mean(log_i, axis=1) / g
    z = np.arange(rows.size) * data.dz
    out["attenuation"] = float(-np.polyfit(z, rows, 1)[0] / 2)
    out["row_mean_intensity"] = i_all.mean(axis=1)
    shape = "gaussian" if out["gaussian_rms"] <= out["rectangular_rms"] else "rectangular"
    width = out[f"{shape}_{'fwhm' if shape == 'gaussian' else 'width'}_fraction"]
    psf = _psf_excess(shape, float(width), float(out["waist_pitch"]), n_pixels)
    out["inverse_density_contrast"] = float(excess / psf)
    # var ln I of sparse speckle (speckle.analysis.sparse): linear data only (for log data the
    # unknown gain g scales var D = g^2 var ln I, so var ln I is not observed)
    if data.kind == "log":
        out["inverse_density_log"] = np.nan
    else:
        out["inverse_density_log"] = sparse_inverse_density(
            float(np.var(log_i)),
            _weights(shape, float(width), n_pixels),
            float(out["waist_pitch"]),
            0.0 if snr is None else 1 / r,
        )
    return out


def _jackknife(values: list[dict], keys: Sequence[str]) -> dict[str, np.ndarray]:
    n = len(values)
    se = {}
    for k in keys:
        v = np.array([np.asarray(d[k], dtype=float) for d in values])
        se[k] = np.sqrt((n - 1) / n * np.sum((v - v.mean(axis=0)) ** 2, axis=0))
    return se


def _confocal(z, a, mu, zf, zr, noise):
    return a * np.exp(-2 * mu * z) * (1 + ((z - zf) / zr) ** 2) ** -1.5 + noise


def _refit_focus(z, rows, rows_se, noise_level, p0):
    """The focused profile fitted from ``p0`` to the intensity row means: (parameters,
    covariance)."""
    span = z[-1] - z[0] + (z[1] - z[0])
    return optimize.curve_fit(
        lambda zz, a, mu, zf, zr: _confocal(zz, a, mu, zf, zr, noise_level),
        z, rows, p0=p0, sigma=rows_se, absolute_sigma=True,
        bounds=([0, -1, z[0] - 2 * span, span / 50], [np.inf, 1, z[-1] + 2 * span, 20 * span]),
        maxfev=20000,
    )  # fmt: skip


def _fit_focus(z, rows, rows_se, noise_level, start):
    """Weighted least squares of the focused profile to the intensity row means.

    Started from the focus test's best ``start = (z_f, z_R)`` and a few other points; returns
    ``(chi^2, parameters, covariance)`` of the best fit, or None.
    """
    mean = float(rows.mean())
    span = z[-1] - z[0] + (z[1] - z[0])
    grid = [(a, b) for a in np.linspace(z[0], z[-1], 5) for b in (span / 8, span / 3, span)]
    best = None
    for zf0, zr0 in [start, *grid]:
        try:
            p, cov = _refit_focus(z, rows, rows_se, noise_level, [mean, 0.0, zf0, zr0])
        except (RuntimeError, ValueError):
            continue
        chi = float(np.sum(((_confocal(z, *p, noise_level) - rows) / rows_se) ** 2))
        if best is None or chi < best[0]:
            best = (chi, p, cov)
    return best


def _row_mean_covariance(log_image: np.ndarray) -> np.ndarray:
    """Covariance of the row means of ``ln I`` (depth, x) from its 2-D autocovariance.

    The rows' means are removed; the autocovariance (FFT, :func:`scipy.signal.correlate`, over
    overlapping pairs) is summed over x-lags up to the first non-positive lateral lag ``L``,
    which gives ``S(m) = nx cov(row_i, row_{i+m})``; removing the row means scales the truncated
    sum by ``1 - (2 L + 1)/nx`` (corrected). ``S`` is kept up to its first non-positive depth
    lag (the point-spread function's correlation length) and the Toeplitz matrix
    ``S(|i - j|)/nx`` is returned (eigenvalues clipped to stay positive).
    """
    nz, nx = log_image.shape
    r = log_image - log_image.mean(axis=1, keepdims=True)
    count = signal.correlate(np.ones_like(r), np.ones_like(r), mode="full", method="fft")
    cxz = signal.correlate(r, r, mode="full", method="fft") / np.maximum(np.round(count), 1)
    z0, x0 = nz - 1, nx - 1
    lat = cxz[z0, x0:]
    stop = np.flatnonzero(lat[1:] <= 0)
    lx = min(int(stop[0]) if stop.size else lat.size - 1, nx // 4)
    s = cxz[z0:, x0 - lx : x0 + lx + 1].sum(axis=1) / (1 - (2 * lx + 1) / nx)
    stop = np.flatnonzero(s[1:] <= 0)
    lz = int(stop[0]) + 1 if stop.size else s.size
    col = np.zeros(nz)
    col[:lz] = s[:lz]
    w, v = linalg.eigh(linalg.toeplitz(col) / nx)
    return (v * np.maximum(w, 1e-6 * w.max())) @ v.T


def _focus_test(
    z: np.ndarray, rows: np.ndarray, cov: np.ndarray, rayleigh: float, seed: int = 0
) -> tuple[float, float, float]:
    """Scan test of a confocal term in the log row means (module docstring).

    Returns the p-value and the best focus depth and Rayleigh range (µm).
    """
    span = z[-1] - z[0] + (z[1] - z[0])
    chol = linalg.cholesky(cov, lower=True)
    x = np.column_stack([np.ones_like(z), z])
    q, _ = np.linalg.qr(linalg.solve_triangular(chol, x, lower=True))
    zf, zr = np.meshgrid(
        np.linspace(z[0] - span / 4, z[-1] + span / 4, FOCUS_SCAN_DEPTHS),
        rayleigh * 2.0 ** np.linspace(-1, 1, FOCUS_SCAN_RAYLEIGH),
    )
    zf, zr = zf.ravel(), zr.ravel()
    term = -1.5 * np.log1p(((z[:, None] - zf) / zr) ** 2)  # ln of (1 + u^2)^(-3/2)
    tw = linalg.solve_triangular(chol, term, lower=True)
    tw -= q @ (q.T @ tw)
    norm = np.linalg.norm(tw, axis=0)
    keep = norm > 1e-9 * norm.max()
    tw, zf, zr = tw[:, keep] / norm[keep], zf[keep], zr[keep]

    def statistic(white):  # largest one-sided GLS reduction of the residual sum of squares
        return np.max(np.maximum(white @ tw, 0.0) ** 2, axis=-1)

    yw = linalg.solve_triangular(chol, rows, lower=True)
    obs = float(statistic(yw))
    best = int(np.argmax(np.maximum(yw @ tw, 0.0)))
    null = statistic(np.random.default_rng(seed).standard_normal((FOCUS_NULL_DRAWS, z.size)))
    p = (1 + int(np.sum(null >= obs))) / (1 + FOCUS_NULL_DRAWS)
    return float(p), float(zf[best]), float(zr[best])


@dataclass
class SystemFit:
    """The fitted twin of a scanner (:func:`fit_system`).

    Attributes
    ----------
    parameters : xarray.Dataset
        One variable per fitted quantity and its standard error ``<name>_se`` (units in attrs);
        attributes: ``spectrum_shape``, ``focused``, ``kind``, ``k0``, ``k0_dk`` and the fit
        settings.
    """

    parameters: xr.Dataset
    template: xr.DataArray = field(repr=False)
    settings: dict = field(repr=False)

    # -- the twin --------------------------------------------------------------------------
    def _value(self, name: str) -> float:
        return float(self.parameters[name])

    def _model(self, shape: tuple[int, int]) -> dict:
        p = self.parameters
        nz, nx = shape
        n = max(int(self.settings["n_pixels"]), nz + nz % 2)
        dz = float(p.attrs["depth_step_medium"])
        h = n * dz
        spec = _weights(p.attrs["spectrum_shape"], self._value("spectrum_width"), n)
        k0 = float(p.attrs["k0_dk"]) * n * np.pi / h
        rho = self._value("density")
        if not np.isfinite(rho) or rho > self.settings["max_density"]:
            rho = float(
                min(max(self._value("density_lower_bound"), 4.0), self.settings["max_density"])
            )
        pitch = float(p.attrs["pitch"])
        beam = {
            "lines": np.arange(nx) * pitch,
            "waist": self._value("waist"),
            "n_pixels": n,
            "depth_range": h,
            "k0": k0,
            "spectrum": spec,
            "method": "nufft",
            "tol": 1e-6,
        }
        if bool(p.attrs["focused"]):
            beam["focus"] = float(np.clip(self._value("focus_depth"), 0.0, h * (1 - 1e-9)))
            beam["rayleigh_range"] = self._value("rayleigh_range")
        return {"n": n, "h": h, "k0": k0, "rho": rho, "pitch": pitch, "beam": beam, "dz": dz}

    def _scatterers(self, m: dict, nx: int, seed: int, depth_range: float) -> dict[str, np.ndarray]:
        w0 = m["beam"]["waist"]
        x0, x1 = -4.5 * w0, (nx - 1) * m["pitch"] + 4.5 * w0
        count = round(m["rho"] * (depth_range / m["dz"]) * (x1 - x0) / m["pitch"])
        rng = np.random.default_rng(np.random.SeedSequence([seed, 20]))
        return {"z": rng.uniform(0.0, depth_range, count), "x": rng.uniform(x0, x1, count)}

    def _field(self, m: dict, sc: dict, strain: float = 0.0) -> np.ndarray:
        """Noise-free complex field (depth, x) of the scatterers, compressed by ``strain``."""
        z = sc["z"] * (1 - strain)
        amp = np.exp(-self._value("attenuation") * z) * (z < m["h"])
        a = beam_scan(z, sc["x"], amp.astype(complex), **m["beam"]).T
        return a

    def simulate(self, shape: tuple[int, int] | None = None, seed: int = 0) -> xr.DataArray:
        """A twin image of the fitted system: same kind, dims and coordinates as the region.

        Parameters
        ----------
        shape : (int, int), optional
            ``(depth, x)`` pixels; default the fitted region's shape (then its coordinates).
        seed : int
            Non-negative seed of the scene and the noise.
        """
        sd = check_int(seed, "seed", low=0)
        t = self.template
        shp = t.shape if shape is None else tuple(check_int(v, "shape", low=2) for v in shape)
        if len(shp) != 2:
            raise ValueError(f"shape must be (depth, x) pixels, got {shape!r}")
        m = self._model(shp)
        a = self._field(m, self._scatterers(m, shp[1], sd, m["h"]))[: shp[0]]
        snr = self._value("snr_db")
        if np.isfinite(snr):
            a = add_complex_noise(a, snr, seed=sd + 1)
        kind = self.parameters.attrs["kind"]
        values = self._render(a, kind)
        if shape is None or tuple(shape) == t.shape:
            coords = {k: t.coords[k] for k in ("depth", "x")}
        else:
            coords = {
                "depth": (
                    "depth",
                    t.depth.values[0]
                    + np.arange(shp[0]) * float(self.parameters.attrs["pixel_size"]),
                    t.depth.attrs,
                ),
                "x": ("x", t.x.values[0] + np.arange(shp[1]) * m["pitch"], t.x.attrs),
            }
        return xr.DataArray(
            values,
            dims=("depth", "x"),
            coords=coords,
            name="twin",
            attrs={
                **{
                    k: v
                    for k, v in t.attrs.items()
                    if k
                    in (
                        "kind",
                        "pixel_size",
                        "pitch",
                        "clip_low",
                        "clip_high",
                        "long_name",
                        "units",
                    )
                },
                "source": "speckle twin (SystemFit.simulate)",
                "seed": sd,
            },
        )

    def _render(self, a: np.ndarray, kind: str) -> np.ndarray:
        if kind == "complex":
            return a * np.sqrt(self.settings["mean_intensity"] / np.mean(np.abs(a) ** 2))
        inten = np.abs(a) ** 2
        inten = inten / inten.mean()
        inten = inten + self._value("twin_floor")
        if kind == "log":
            d = self._value("twin_gain") * np.log(inten) + self._value("twin_offset")
            hi = self.template.attrs.get("clip_high")
            if hi is not None:
                d = np.clip(np.round(d), self.template.attrs["clip_low"], hi)
            return d
        inten = inten * self.settings["mean_intensity"] / inten.mean()
        return np.sqrt(inten) if kind == "amplitude" else inten

    def _fit_detection(self, region: xr.DataArray) -> None:
        """The floor (and log mapping) that give a floorless twin the image's log moments.

        The floor of :func:`~speckle.analysis.measured.fit_floor` assumes fully developed
        speckle; a sparse scene raises the skewness of the log data too. Here a floorless
        noisy twin image ``I0`` (seed 0, the region's shape) is taken as it is, and ``b`` solves
        ``skewness(ln(I0/<I0> + b)) = skewness`` of the image (``b = 0`` if the twin is already
        less skewed); its SE follows from the image's skewness SE. For log data ``g`` and ``c``
        then match the standard deviation and mean of ``D``.
        """
        p = self.parameters
        shape = self.template.shape
        m = self._model(shape)
        a = self._field(m, self._scatterers(m, shape[1], 0, m["h"]))[: shape[0]]
        if np.isfinite(self._value("snr_db")):
            a = add_complex_noise(a, self._value("snr_db"), seed=1)
        i0 = np.abs(a).ravel() ** 2
        i0 = i0 / i0.mean()
        target, target_se = self._value("skewness"), self._value("skewness_se")

        def gap(b):
            return float(stats.skew(np.log(i0 + b))) - target

        if gap(0.0) >= 0 or gap(5.0) < 0:
            b, b_se = 0.0, 0.0
        else:
            b = float(optimize.brentq(gap, 0.0, 5.0, xtol=1e-7))
            h = max(1e-4, 0.05 * b)
            slope = (gap(b + h) - gap(max(b - h, 0.0))) / (b + h - max(b - h, 0.0))
            b_se = target_se / abs(slope) if slope != 0 else np.inf
        ln = np.log(i0 + b)
        if p.attrs["kind"] == "log":
            d = region.values.ravel()
            g = float(d.std() / ln.std())
            c = float(d.mean() - g * ln.mean())
        else:
            g, c = 1.0, 0.0
        p["twin_floor"] = (
            (),
            b,
            attrs("dimensionless", "intensity floor / mean speckle intensity, twin-matched"),
        )
        p["twin_floor_se"] = (
            (),
            float(b_se),
            attrs("dimensionless", "standard error of twin_floor"),
        )
        p["twin_gain"] = ((), g, attrs("dimensionless", "g of the twin's log mapping"))
        p["twin_offset"] = ((), c, attrs("dimensionless", "c of the twin's log mapping"))

    # -- comparison ------------------------------------------------------------------------
    def compare(self, image: xr.DataArray, *, seed: int = 0) -> xr.Dataset:
        """Measured statistics against the twin's (same region, estimator and blocks).

        Returns
        -------
        xarray.Dataset
            Dim ``source`` = ``("measured", "twin")``: ``autocorrelation`` (``source, axis,
            lag``), ``skewness``, ``excess_kurtosis`` (of the log data), ``contrast_excess``
            and ``mean_log_profile`` (``source, row``), each with ``*_se``; ``z_score`` (the
            largest ``|measured - twin| / combined SE`` per statistic); histograms of the
            standardised log data; ``measured_image`` and ``twin_image`` (the region).
        """
        region = _region(_as_image(image), self.settings["region"])
        twin = self.simulate(seed=seed)
        stats_ = [self._statistics(x) for x in (region, twin)]
        if "frame" in region.dims:  # statistics pooled over frames; panels of the first
            region = region.isel(frame=0)
        ds = xr.concat(stats_, dim="source").assign_coords(source=["measured", "twin"])
        for k in ("autocorrelation", "skewness", "excess_kurtosis", "contrast_excess"):
            diff = abs(ds[k].sel(source="measured") - ds[k].sel(source="twin"))
            comb = np.hypot(ds[f"{k}_se"].sel(source="measured"), ds[f"{k}_se"].sel(source="twin"))
            z = diff / comb
            if k == "autocorrelation":
                z = z.sel(lag=slice(1, None))
            ds[f"z_{k}"] = (
                (),
                float(z.max()),
                attrs("dimensionless", f"largest |measured - twin| / combined SE, {k}"),
            )
        edges = np.linspace(-5, 3, 41)
        for name, x in (("measured", region), ("twin", twin)):
            lg = _log_data(x)
            zs = (lg - lg.mean()) / lg.std()
            ds[f"{name}_log_histogram"] = (
                ("bin",),
                np.histogram(zs, edges, density=True)[0],
                attrs("dimensionless", f"probability density of the standardised {name} log data"),
            )
            ds[f"{name}_image"] = (
                ("depth", "x"),
                _display(x),
                {
                    "long_name": f"{name} region, dB re mean"
                    if x.attrs["kind"] != "log"
                    else f"{name} region (log data)"
                },
            )
        ds = ds.assign_coords(
            bin=coord(
                "dimensionless",
                0.5 * (edges[1:] + edges[:-1]),
                "standardised log intensity",
                dims="bin",
            ),
            depth=region.depth,
            x=region.x,
        )
        ds.attrs.update(kind=self.parameters.attrs["kind"], seed=int(seed))
        return ds

    def _statistics(self, image: xr.DataArray) -> xr.Dataset:
        s = self.settings
        data = _data(image, None, s["refractive_index"])
        nx, nf = image.sizes["x"], image.sizes.get("frame", 1)
        blocks = np.array_split(np.arange(nx), s["n_blocks"])

        def one(cols):
            inten, _, g, _ = data.pieces(cols)
            i_all = np.hstack(inten)
            lg = (
                np.hstack([data.signal[:, c] for c in cols])
                if data.kind == "log"
                else np.log(i_all)
            )
            return {
                "depth": _acf(inten, s["max_lag"], "depth"),
                "lateral": _acf(inten, s["max_lag"], "lateral"),
                "skewness": float(stats.skew(lg.ravel())),
                "excess_kurtosis": float(stats.kurtosis(lg.ravel())),
                "contrast_excess": float(i_all.var() / i_all.mean() ** 2 - 1),
                "profile": lg.mean(axis=1) / g,
            }

        whole = one(_column_groups(nx, nf, [np.arange(nx)]))
        se = _jackknife(
            [one(_column_groups(nx, nf, blocks[:i] + blocks[i + 1 :])) for i in range(len(blocks))],
            list(whole),
        )
        lag = np.arange(s["max_lag"] + 1)
        acf = np.stack([whole["depth"], whole["lateral"]])
        acf_se = np.stack([se["depth"], se["lateral"]])
        return xr.Dataset(
            {
                "autocorrelation": (
                    ("axis", "lag"),
                    acf,
                    attrs("correlation", "intensity autocorrelation"),
                ),
                "autocorrelation_se": (
                    ("axis", "lag"),
                    acf_se,
                    attrs("correlation", "standard error of the autocorrelation"),
                ),
                **{
                    k: ((), whole[k], attrs("dimensionless", k.replace("_", " ")))
                    for k in ("skewness", "excess_kurtosis", "contrast_excess")
                },
                **{
                    f"{k}_se": (
                        (),
                        float(se[k]),
                        attrs("dimensionless", f"standard error of {k}"),
                    )
                    for k in ("skewness", "excess_kurtosis", "contrast_excess")
                },
                "mean_log_profile": (
                    ("row",),
                    whole["profile"] - whole["profile"].mean(),
                    attrs("dimensionless", "mean ln intensity per row, minus its mean"),
                ),
                "mean_log_profile_se": (
                    ("row",),
                    se["profile"],
                    attrs("dimensionless", "standard error of mean_log_profile"),
                ),
            },
            coords={
                "axis": ["depth", "lateral"],
                "lag": coord("lag", lag, "lag (pixels or lines)"),
                "row": np.arange(image.sizes["depth"]),
            },
        )

    # -- strain limits ---------------------------------------------------------------------
    def failure_maps(
        self,
        strains: Sequence[float] = (1e-4, 1e-3, 3e-3, 1e-2, 3e-2),
        methods: Sequence[str] = ("vector", "wls", "tracking", "correlation"),
        *,
        shape: tuple[int, int] = (128, 32),
        window: tuple[int, int] | None = None,
        seed: int = 0,
    ) -> xr.Dataset:
        """Each strain estimator's errors on twin image pairs under uniform compression.

        Parameters
        ----------
        strains : sequence of float
            Interframe strains (compression > 0), each in (-0.5, 0.5).
        methods : sequence of str
            Estimators of :func:`speckle.estimate_strain` (``"vector_unaligned"`` etc. as in
            the elastography config: ``_aligned``/``_unaligned`` set ``align``).
        shape : (int, int)
            Twin image ``(depth, x)`` pixels.
        window : (int, int), optional
            Estimator window (depth, x) in pixels; default each method's own.
        seed : int
            Scene seed; frame noise uses ``seed + 1``, ``seed + 2``.

        Returns
        -------
        xarray.Dataset
            ``median_error``, ``rms_error``, ``answered`` (fraction of pixels with an answer)
            over ``(strain, method)``; the twin's parameters in the attributes.
        """
        from .failure import method_options, strain_scores

        s_values = [check_real(s, "strains", low=-0.5, high=0.5) for s in strains]
        if not s_values:
            raise ValueError("strains must hold at least one strain")
        labels = [str(m) for m in methods]
        from .strain import METHODS

        for lab in labels:
            check_choice(method_options(lab)[0], "methods", METHODS)
        shp = tuple(check_int(v, "shape", low=8) for v in shape)
        m = self._model(shp)
        smax = max(abs(v) for v in s_values)
        depth = m["h"] / (1 - smax)
        sc = self._scatterers(m, shp[1], check_int(seed, "seed", low=0), depth)
        snr = self._value("snr_db")
        ref = self._field(m, sc)[: shp[0]]
        if np.isfinite(snr):
            a1 = add_complex_noise(ref, snr, seed=seed + 1)
        else:
            a1 = ref
        # the phase methods' lag from the fitted spectrum (speckle.analysis.phase.choose_lag's
        # rule on the theory, |gamma(L)|^2 < DEFAULT_MAX_BIAS), not from one noisy image
        gamma2 = ac.axial_correlation_theory(np.arange(shp[0]), m["beam"]["spectrum"])
        below = np.flatnonzero(gamma2[1:] < DEFAULT_MAX_BIAS)
        lag = int(below[0] + 1) if below.size else shp[0] // 4
        res = np.empty((len(s_values), len(labels), 3))
        for i, s in enumerate(s_values):
            dfm = self._field(m, sc, s)[: shp[0]]
            a2 = add_complex_noise(dfm, snr, seed=seed + 2) if np.isfinite(snr) else dfm
            for j, lab in enumerate(labels):
                method, opts = method_options(lab)
                if method in ("vector", "wls"):
                    opts = {"lag": lag, **opts}
                est = estimate_strain(
                    a1, a2, k0=m["k0"], pixel_size=m["dz"], method=method, window=window, **opts
                )
                res[i, j] = strain_scores(est, abs(s) if method == "correlation" else s)
        coords = {
            "strain": (
                "strain",
                np.asarray(s_values),
                attrs("strain"),
            ),
            "method": labels,
        }
        return xr.Dataset(
            {
                "median_error": (
                    ("strain", "method"),
                    res[..., 0],
                    attrs("strain", "median error"),
                ),
                "rms_error": (("strain", "method"), res[..., 1], attrs("strain", "rms error")),
                "answered": (
                    ("strain", "method"),
                    res[..., 2],
                    attrs("dimensionless", "fraction of pixels answered"),
                ),
            },
            coords=coords,
            attrs={
                "lag": lag,
                "shape": list(shp),
                "seed": int(seed),
                "k0": m["k0"],
                "pixel_size": m["dz"],
                "density": m["rho"],
                "window": "method default" if window is None else list(window),
            },
        )


def _as_image(image: object) -> xr.DataArray:
    if (
        isinstance(image, (list, tuple))
        and image
        and all(isinstance(x, xr.DataArray) for x in image)
    ):
        shapes = [x.shape for x in image]
        if len(set(shapes)) > 1:
            raise ValueError(
                f"image frames must all have the same shape, got {shapes}; crop them to one "
                "shape (the frames are fitted together)"
            )
        image = xr.concat([_as_image(x) for x in image], dim="frame", join="override")
    if not isinstance(image, xr.DataArray):
        raise TypeError(
            f"image must be an xarray.DataArray from speckle.load_image, got {type(image).__name__}"
        )
    kind = image.attrs.get("kind")
    if kind not in IMAGE_KINDS:
        raise ValueError(
            f"image.attrs['kind'] must be one of {IMAGE_KINDS} (load it with "
            f"speckle.load_image(path, kind=...)); got {kind!r}"
        )
    if "aline" in image.dims:
        image = image.rename({"aline": "x"})
    if set(image.dims) - {"frame"} != {"depth", "x"}:
        raise ValueError(
            f"image must have dims (depth, x) (and optionally frame), got {image.dims}"
        )
    return image.transpose(*(("frame",) if "frame" in image.dims else ()), "depth", "x")


def _region(image: xr.DataArray, region: Mapping | None) -> xr.DataArray:
    """The half-open pixel ranges ``{"depth": [a, b], "x": [a, b]}`` of ``image``, checked."""
    if region is None:
        return image
    if not isinstance(region, Mapping):
        raise TypeError(
            f"region must be a mapping {{'depth': [start, stop], 'x': [start, stop]}}, got "
            f"{region!r}"
        )
    sl = {}
    for key, value in region.items():
        if key not in ("depth", "x"):
            raise ValueError(f"region keys must be 'depth' and/or 'x', got {key!r}")
        size = image.sizes[key]
        if value is None:
            continue
        if isinstance(value, str) or len(value) != 2:
            raise ValueError(f"region[{key!r}] must be [start, stop], got {value!r}")
        lo, hi = (0 if value[0] is None else value[0]), (size if value[1] is None else value[1])
        if not (0 <= lo < hi <= size):
            raise ValueError(
                f"region[{key!r}] = {list(value)} lies outside the image ({key}: 0..{size}); need "
                f"0 <= start < stop <= {size}"
            )
        sl[key] = slice(int(lo), int(hi))
    return image.isel(sl)


def _log_data(image: xr.DataArray) -> np.ndarray:
    v = image.values
    if image.attrs["kind"] == "log":
        return v
    inten = np.abs(v) ** 2 if image.attrs["kind"] in ("complex", "amplitude") else v
    return np.log(inten)


def _display(image: xr.DataArray) -> np.ndarray:
    if image.attrs["kind"] == "log":
        return image.values.astype(float)
    lg = _log_data(image)
    return 10 / np.log(10) * (lg - np.log(np.mean(np.exp(lg))))


def _data(image: xr.DataArray, noise: xr.DataArray | None, n_medium: float) -> _Data:
    kind = image.attrs["kind"]

    def values(x):
        v = x.values
        if kind == "complex":
            v = np.abs(v) ** 2
        elif kind == "amplitude":
            v = v**2
        return v.astype(float)

    sig = _side_by_side(values(image))
    one = image.isel(frame=0) if "frame" in image.dims else image
    dz, pitch = _step(one, "depth"), _step(one, "x")
    noise_values = None if noise is None else _side_by_side(values(noise))
    return _Data(kind, sig, noise_values, dz / n_medium, pitch)


def _side_by_side(v: np.ndarray) -> np.ndarray:
    """``(frame, depth, x)`` -> ``(depth, frame * x)``: frame ``f`` in columns ``f nx ..``."""
    return v if v.ndim == 2 else np.concatenate(list(v), axis=1)


def _column_groups(nx: int, n_frames: int, blocks: list[np.ndarray]) -> list[np.ndarray]:
    """The column blocks of every frame (no pixel pair crosses a block or a frame edge)."""
    return [b + f * nx for f in range(n_frames) for b in blocks]


def _step(image: xr.DataArray, dim: str) -> float:
    """Pixel size (``depth``) or line pitch (``x``) in µm, read from the coordinate ``dim``.

    Spacing is never read from attributes (:func:`speckle.conventions.spacing`): a missing,
    non-uniform or non-µm coordinate is refused with a ``ValueError`` naming it.
    """
    if dim not in image.coords:
        raise ValueError(
            f"image has no {dim!r} coordinate (µm) to read its spacing from; load it with "
            "speckle.load_image(..., pixel_size=..., pitch=...)"
        )
    units = image[dim].attrs.get("units")
    if units is not None and units not in ("um", "µm", "micrometre", "micrometer"):
        raise ValueError(
            f"coordinate {dim!r} is in {units!r}, not µm; load the image with "
            "speckle.load_image(..., pixel_size=..., pitch=...)"
        )
    return spacing(image, dim)


def _find_noise_rows(img: xr.DataArray, region: Mapping | None) -> list[int] | None:
    """Signal-free rows above the region, or ``None`` (module docstring of :func:`fit_system`).

    Rows ``0 .. start`` of the region's columns whose mean intensity is :data:`NOISE_ROW_DB`
    below the region's; of those, the rows within a factor 2 of their median level (no depth
    structure: the rising tails of the sample's point-spread function are left out), and of
    these the longest contiguous run of at least :data:`MIN_NOISE_ROWS` rows.
    """
    reg = region or {}
    start = (reg.get("depth") or [0])[0] or 0
    if start < MIN_NOISE_ROWS:
        return None
    above = _region(img, {"depth": [0, start], "x": reg.get("x")})
    inside = _region(img, {"depth": reg.get("depth"), "x": reg.get("x")})
    kind = img.attrs["kind"]
    if not (np.all(np.isfinite(above.values)) and np.all(np.isfinite(inside.values))):
        return None
    if kind == "log":
        d_in = inside.values.astype(float)
        g = float(
            ms.fit_floor(
                xr.DataArray(
                    d_in.reshape(-1, d_in.shape[-1]),
                    attrs={"scale": "log"},
                    dims=("depth", "aline"),
                )
            )["gain"]
        )
        i_above, i_in = (np.exp((v.astype(float) - d_in.mean()) / g) for v in (above.values, d_in))
    else:
        i_above, i_in = (_data(x, None, 1.0).signal for x in (above, inside))
    axes = tuple(i for i in range(i_above.ndim) if i != i_above.ndim - 2)  # all but depth
    level = np.mean(i_above, axis=axes)
    low = level < np.mean(i_in) * 10 ** (-NOISE_ROW_DB / 10)
    if not low.any():
        return None
    flat = low & (level <= 2 * np.median(level[low]))
    best, run = None, None
    for i, ok in enumerate(np.append(flat, False)):
        if ok and run is None:
            run = i
        elif not ok and run is not None:
            if best is None or i - run > best[1] - best[0]:
                best = (run, i)
            run = None
    if best is None or best[1] - best[0] < MIN_NOISE_ROWS:
        return None
    return [int(best[0]), int(best[1])]


def _check_values(region: xr.DataArray, name: str, kind: str) -> None:
    v = region.values
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} has NaN or infinite pixels; choose a region without them")
    if np.ptp(np.abs(v)) == 0:
        raise ValueError(f"{name} is constant ({np.abs(v).flat[0]!r}); it holds no speckle")
    if kind in ("amplitude", "intensity", "complex") and np.any(np.abs(v) == 0):
        raise ValueError(
            f"{name} has exact zeros (their log is undefined); choose a region without them"
        )


#: Share of the region's pixels at the stored dtype's limits above which the fit warns.
MAX_CLIPPED = 0.01


def _warn_clipped(reg: xr.DataArray) -> None:
    """Warn when the region holds clipped pixels (``load_image``'s ``clip_low``/``clip_high``:
    the integer dtype's limits): their statistics are not those of speckle."""
    lo, hi = reg.attrs.get("clip_low"), reg.attrs.get("clip_high")
    if lo is None or hi is None:
        return
    v = reg.values
    share = float(np.mean((v <= lo) | (v >= hi)))
    if share > MAX_CLIPPED:
        warnings.warn(
            f"{share:.1%} of the region's pixels sit at the stored dtype's limits "
            f"({lo}, {hi}): clipped data bias every statistic of the fit (waist, spectrum, "
            "SNR); choose a region without saturation",
            UserWarning,
            stacklevel=3,
        )


def _outside_region(rows: Sequence[int], depth: Sequence | None, nz: int) -> None:
    """Noise rows must not overlap the fitted region's rows (they would be signal)."""
    lo, hi = (0, nz) if depth is None else (depth[0] or 0, nz if depth[1] is None else depth[1])
    if rows[0] < hi and rows[1] > lo:
        raise ValueError(
            f"noise_rows = {list(rows)} overlap the region's rows [{lo}, {hi}): signal-free "
            "rows must lie outside the fitted speckle"
        )


def fit_system(
    image: xr.DataArray,
    *,
    k0: float | None = None,
    refractive_index: float = 1.0,
    region: Mapping | None = None,
    noise_rows: Sequence[int] | None = None,
    snr_db: float | None = None,
    n_pixels: int = 64,
    max_lag: int = 8,
    n_blocks: int = 16,
    n_bands: int = 4,
    max_density: float = 16.0,
) -> SystemFit:
    """Fit the model's system to a measured image (module docstring).

    Parameters
    ----------
    image : xarray.DataArray or sequence of xarray.DataArray
        From :func:`speckle.load_image`: dims ``(depth, x)``, ``attrs["kind"]`` one of
        ``complex``, ``amplitude``, ``intensity``, ``log``. A ``frame`` dim (or a list of
        same-shaped images): every frame is fitted, the statistics pooled over all frames'
        pixel pairs and the jackknife deleting one block of A-lines from every frame at once
        (frames of one sample share speckle: their SE is not divided by sqrt(frames)).
    k0 : float, optional
        Central wavenumber in vacuum (rad/µm, > 0); the model uses ``refractive_index * k0``.
        Default: ``k0/delta_k = 10`` (:data:`DEFAULT_K0_DK`). It sets the twin's carrier (the
        strain estimators' phase) and nothing that a single intensity image shows.
    refractive_index : float
        Of the medium (>= 1): depths in the medium are ``pixel_size / refractive_index``.
    region : mapping, optional
        Homogeneous speckle to fit, ``{"depth": [start, stop], "x": [start, stop]}`` (pixel
        indices, half-open); default the whole image.
    noise_rows : [start, stop], optional
        Signal-free rows (air above the sample), same columns as the region: SNR and noise
        floor. Without them and without ``snr_db`` they are looked for above the region
        (:data:`NOISE_ROW_DB` below its mean intensity, flat, >= :data:`MIN_NOISE_ROWS`
        contiguous rows); the rows used and how they were chosen are in the attributes
        ``noise_rows`` and ``noise_rows_source``. None found: a warning, SNR not fitted.
    snr_db : float, optional
        A known SNR (dB) when there are no signal-free rows (not with ``noise_rows``).
    n_pixels : int
        Spectral components of the model A-scan used in the theory and the twin (>= 16).
    max_lag : int
        Largest autocorrelation lag (>= 2).
    n_blocks : int
        A-line blocks of the jackknife (>= 4).
    n_bands : int
        Depth bands of the per-band waist (0 or >= 2).
    max_density : float
        Largest density the twin simulates (the image cannot tell denser scenes apart).

    Returns
    -------
    SystemFit
        The fitted twin: parameters with their standard errors (see :class:`SystemFit`).

    Raises
    ------
    TypeError
        ``image`` not a DataArray.
    ValueError
        Unknown kind; frames of different shapes; a region or noise rows outside the image;
        NaN, constant or (linear) zero pixels; a region too small for ``max_lag`` and
        ``n_blocks``; bad settings. All before any fitting.

    Warns
    -----
    UserWarning
        A linear image (amplitude/intensity) whose intensity contrast std/mean is below
        :data:`LOG_AS_LINEAR_CONTRAST` (fully developed speckle: 1): probably log data. No
        signal-free rows found (``noise_rows`` and ``snr_db`` not given).
    """
    img = _as_image(image)
    kind = img.attrs["kind"]
    n_med = check_real(refractive_index, "refractive_index", low=1.0)
    k0v = None if k0 is None else check_real(k0, "k0", low=0, low_inclusive=False)
    npx = check_int(n_pixels, "n_pixels", low=16)
    ml = check_int(max_lag, "max_lag", low=2)
    nb = check_int(n_blocks, "n_blocks", low=4)
    nbands = check_int(n_bands, "n_bands", low=0)
    if nbands == 1:
        raise ValueError("n_bands must be 0 (no per-band waist) or >= 2, got 1")
    rmax = check_real(max_density, "max_density", low=0, low_inclusive=False)
    reg = _region(img, region)
    nz, nx = reg.sizes["depth"], reg.sizes["x"]
    nf = reg.sizes.get("frame", 1)
    if nz < ml + 4 or nx < nb * (ml + 2):
        raise ValueError(
            f"region of {nz} x {nx} pixels (depth, x) is too small for max_lag = {ml} and "
            f"n_blocks = {nb}: need depth >= max_lag + 4 = {ml + 4} and x >= n_blocks * "
            f"(max_lag + 2) = {nb * (ml + 2)}; enlarge the region or lower max_lag/n_blocks"
        )
    if nbands and nz // nbands < 2:
        raise ValueError(f"n_bands = {nbands} leaves fewer than 2 rows per band in {nz} rows")
    _check_values(reg, "image region", kind)
    noise = None
    noise_source = "given"
    if noise_rows is None and snr_db is None:
        noise_rows = _find_noise_rows(img, region)
        noise_source = "found automatically" if noise_rows is not None else "none found"
        if noise_rows is None:
            warnings.warn(
                "no signal-free rows found above the region (rows "
                f"{NOISE_ROW_DB:g} dB below it, >= {MIN_NOISE_ROWS} contiguous): SNR and "
                "noise floor are not fitted (pass noise_rows=[start, stop] or snr_db=)",
                UserWarning,
                stacklevel=2,
            )
    elif noise_rows is None:
        noise_source = "none (snr_db given)"
    if noise_rows is not None and snr_db is not None:
        raise ValueError(
            "give noise_rows or snr_db, not both: noise_rows measure the SNR that snr_db states"
        )
    if noise_rows is not None:
        if isinstance(noise_rows, str) or len(noise_rows) != 2:
            raise ValueError(f"noise_rows must be [start, stop], got {noise_rows!r}")
        cols = (region or {}).get("x")
        noise = _region(img, {"depth": list(noise_rows), "x": cols})
        _outside_region(noise_rows, (region or {}).get("depth"), img.sizes["depth"])
        if noise.sizes["depth"] < 2:
            raise ValueError(f"noise_rows = {list(noise_rows)} must hold at least 2 rows")
        _check_values(noise, "noise_rows", kind)
        snr_db = None
    elif snr_db is not None:
        snr_db = check_real(snr_db, "snr_db")
    _warn_clipped(reg)
    data = _data(reg, noise, n_med)
    if kind in ("amplitude", "intensity"):
        c = float(np.std(data.signal) / np.mean(data.signal))
        if c < LOG_AS_LINEAR_CONTRAST:
            warnings.warn(
                f"image given as kind={kind!r} has intensity contrast std/mean = {c:.3f} "
                "(fully developed speckle: 1; noise and a floor keep it near 1): it looks "
                "log-compressed; pass kind='log' if it is",
                UserWarning,
                stacklevel=2,
            )
    blocks = np.array_split(np.arange(nx), nb)
    kw = {"n_pixels": npx, "max_lag": ml, "n_bands": nbands, "snr_db": snr_db}
    # every pair of the region (of every frame); the jackknife deletes a block of A-lines from
    # every frame at once, so frames of one sample (correlated speckle) do not shrink the SE
    whole = _estimate(data, _column_groups(nx, nf, [np.arange(nx)]), **kw)
    if noise is not None and not np.isfinite(whole["snr_db"]):
        warnings.warn(
            f"noise_rows {list(noise_rows)} are as bright as the region (not signal-free): the "
            "SNR and the noise floor have no answer (NaN)",
            UserWarning,
            stacklevel=2,
        )
    jack = [
        _estimate(data, _column_groups(nx, nf, blocks[:i] + blocks[i + 1 :]), **kw)
        for i in range(nb)
    ]
    keys = [k for k, v in whole.items()]
    se = _jackknife(jack, keys)
    params = _parameters(whole, se, jack, data, reg, npx, noise is not None)
    # focus and attenuation: row means of ln I, their covariance from the region's 2-D
    # autocovariance (rows are correlated along depth by the point-spread function)
    dk = np.pi / data.dz  # delta_k = N pi / H = pi / pixel
    k_model = DEFAULT_K0_DK * dk if k0v is None else n_med * k0v
    z = np.arange(nz) * data.dz
    g = float(whole["gain"]) if kind == "log" else 1.0
    # the frame average: its row means are those of every frame, and its autocovariance holds
    # whatever correlation the frames share (none to all)
    log_mean = np.mean(
        [
            data.signal[:, c] / g if kind == "log" else np.log(data.signal[:, c])
            for c in _column_groups(nx, nf, [np.arange(nx)])
        ],
        axis=0,
    )
    log_rows = log_mean.mean(axis=1)
    focused = False
    if nz >= 8:
        cov = _row_mean_covariance(log_mean)
        # attenuation: least-squares slope, sandwich variance with the rows' covariance
        x = np.column_stack([np.ones_like(z), z])
        h = np.linalg.solve(x.T @ x, x.T)
        params["attenuation_se"] = (
            (),
            float(np.sqrt((h @ cov @ h.T)[1, 1]) / 2),
            params["attenuation_se"][2],
        )
        rayleigh = k_model * (float(whole["waist_pitch"]) * data.pitch) ** 2 / 2
        p_focus, zf_scan, zr_scan = _focus_test(z, log_rows, cov, rayleigh)
        params["focus_p_value"] = (
            (),
            p_focus,
            attrs(
                "probability",
                "p-value of a focus in the row means of ln I (scan statistic, Monte-Carlo "
                "null with the rows' covariance)",
            ),
        )
        rows = np.asarray(whole["row_mean_intensity"])
        rows_se = se["row_mean_intensity"]
        snr_v = float(whole["snr_db"])
        noise_level = float(rows.mean() / (1 + 10 ** (snr_v / 10))) if np.isfinite(snr_v) else 0.0
        best = None
        if p_focus < FOCUS_P_VALUE and np.all(rows_se > 0):
            best = _fit_focus(z, rows, rows_se, noise_level, (zf_scan, zr_scan))
        if best is not None:
            focused = True
            _, p, _ = best
            # errors: the same fit on each jackknife sample (rows are correlated along depth
            # by the point-spread function, so the least-squares covariance would be too small)
            refits = [
                {
                    "p": _refit_focus(
                        z, np.asarray(j["row_mean_intensity"]), rows_se, noise_level, p
                    )[0]
                }
                for j in jack
            ]
            pse = _jackknife(refits, ["p"])["p"]
            params["attenuation"] = ((), float(p[1]), params["attenuation"][2])
            params["attenuation_se"] = ((), float(pse[1]), params["attenuation"][2])
            for name, i, ln in (
                ("focus_depth", 2, "focal depth in the medium below the region's first row"),
                ("rayleigh_range", 3, "Rayleigh range in the medium"),
            ):
                params[name] = ((), float(p[i]), attrs("length", ln))
                params[f"{name}_se"] = (
                    (),
                    float(pse[i]),
                    attrs("length", f"standard error of {name}"),
                )
    if not focused:
        for name in ("focus_depth", "rayleigh_range"):
            params[name] = ((), np.nan, attrs("length", "no focus detected"))
            params[f"{name}_se"] = ((), np.nan, attrs("length", "no focus detected"))
    ds = xr.Dataset(params)
    ds.attrs.update(
        kind=kind,
        spectrum_shape=_shape(whole),
        focused=int(focused),
        k0=float(k_model),
        k0_dk=float(k_model / dk),
        k0_given=int(k0v is not None),
        refractive_index=n_med,
        pixel_size=float(data.dz * n_med),
        depth_step_medium=float(data.dz),
        pitch=float(data.pitch),
        region=repr(dict(region or {})),
        noise_rows=repr(None if noise_rows is None else list(noise_rows)),
        noise_rows_source=noise_source,
        n_pixels=npx,
        max_lag=ml,
        n_blocks=nb,
        source=str(img.attrs.get("source", "")),
        method="delete-one-block jackknife standard errors (speckle.analysis.twin)",
    )
    mean_i = (
        float(np.mean(np.abs(reg.values) ** 2))
        if kind == "complex"
        else float(np.mean(data.signal))
    )
    settings = {
        "region": dict(region) if region else None,
        "n_pixels": npx,
        "max_lag": ml,
        "n_blocks": nb,
        "refractive_index": n_med,
        "max_density": rmax,
        "mean_intensity": mean_i,
    }
    ds.attrs["n_frames"] = nf
    out = SystemFit(ds, reg.isel(frame=0) if "frame" in reg.dims else reg, settings)
    out._fit_detection(reg)
    return out


def _shape(whole: dict) -> str:
    return "gaussian" if whole["gaussian_rms"] <= whole["rectangular_rms"] else "rectangular"


def _parameters(whole, se, jack, data: _Data, reg, npx, have_noise) -> dict:
    shape = _shape(whole)
    width_key = "gaussian_fwhm_fraction" if shape == "gaussian" else "rectangular_width_fraction"
    p: dict = {}

    def put(name, value, err, quantity, long_name):
        p[name] = ((), float(value), attrs(quantity, long_name))
        p[f"{name}_se"] = ((), float(err), attrs(quantity, f"standard error of {name}"))

    put(
        "spectrum_width",
        whole[width_key],
        se[width_key],
        "dimensionless",
        f"{shape} spectrum width (FWHM) / delta_k",
    )
    put(
        "gaussian_fwhm_fraction",
        whole["gaussian_fwhm_fraction"],
        se["gaussian_fwhm_fraction"],
        "dimensionless",
        "Gaussian spectrum FWHM / delta_k",
    )
    put(
        "rectangular_width_fraction",
        whole["rectangular_width_fraction"],
        se["rectangular_width_fraction"],
        "dimensionless",
        "rectangular spectrum width / delta_k",
    )
    for s in SPECTRUM_SHAPES:
        p[f"{s}_rms_residual"] = (
            (),
            float(whole[f"{s}_rms"]),
            attrs("dimensionless", f"rms residual of the {s} fit to the depth autocorrelation"),
        )
    put(
        "waist",
        whole["waist_pitch"] * data.pitch,
        se["waist_pitch"] * data.pitch,
        "length",
        "beam waist w0 (1/e^2 intensity radius)",
    )
    put(
        "waist_pitch",
        whole["waist_pitch"],
        se["waist_pitch"],
        "dimensionless",
        "beam waist / A-line pitch",
    )
    p["waist_rms_residual"] = (
        (),
        float(whole["waist_rms"]),
        attrs("dimensionless", "rms residual of the waist fit to the lateral autocorrelation"),
    )
    bw, bse = np.asarray(whole["band_waist_pitch"]), np.asarray(se["band_waist_pitch"])
    if bw.size:
        nb = bw.size
        centre = np.array([r.mean() for r in np.array_split(np.arange(reg.sizes["depth"]), nb)])
        p["band_waist"] = (
            ("band",),
            bw * data.pitch,
            attrs("length", "waist fitted per depth band"),
        )
        p["band_waist_se"] = (
            ("band",),
            bse * data.pitch,
            attrs("length", "standard error of band_waist"),
        )
        p["band_depth"] = (
            ("band",),
            centre * data.dz,
            attrs("length", "band centre below the region's first row (medium)"),
        )
        wm = np.sum(bw / bse**2) / np.sum(1 / bse**2)
        chi = float(np.sum(((bw - wm) / bse) ** 2))
        p["waist_depth_p_value"] = (
            (),
            float(stats.chi2.sf(chi, nb - 1)),
            attrs("probability", "p-value of one waist at every depth band"),
        )
    put(
        "snr_db",
        whole["snr_db"],
        se["snr_db"] if have_noise else 0.0,
        "level",
        "mean signal intensity / noise intensity",
    )
    if have_noise:
        put(
            "noise_floor",
            whole["noise_floor"],
            se["noise_floor"],
            "dimensionless",
            "mean noise level (log data units, or intensity)",
        )
    put(
        "attenuation",
        whole["attenuation"],
        se["attenuation"],
        "attenuation",
        "intensity attenuation mu_t (medium)",
    )
    put(
        "floor",
        whole["floor"],
        se["floor"],
        "dimensionless",
        "intensity floor / mean speckle intensity",
    )
    if data.kind == "log":
        put("gain", whole["gain"], se["gain"], "dimensionless", "g in D = g ln I + c")
        put("offset", whole["offset"], se["offset"], "dimensionless", "c in D = g ln I + c")
    else:
        put("gain", 1.0, 0.0, "dimensionless", "linear image: ln I itself")
        put("offset", 0.0, 0.0, "dimensionless", "linear image")
    put(
        "contrast_excess",
        whole["contrast_excess"],
        se["contrast_excess"],
        "dimensionless",
        "<I_s^2>/<I_s>^2 - 2 (noise and floor removed)",
    )
    put(
        "inverse_density_contrast",
        whole["inverse_density_contrast"],
        se["inverse_density_contrast"],
        "dimensionless",
        "1 / scatterers per pixel per pitch, from the intensity contrast",
    )
    put(
        "inverse_density_log",
        whole["inverse_density_log"],
        se["inverse_density_log"],
        "dimensionless",
        "1 / scatterers per pixel per pitch, from var ln I (linear data only)",
    )
    inv, inv_se, how = _combined_inverse_density(whole, jack)
    put(
        "inverse_density",
        inv,
        inv_se,
        "dimensionless",
        f"1 / scatterers per pixel per pitch ({how})",
    )
    p["inverse_density"][2]["method"] = how
    significant = inv > 2 * inv_se
    put(
        "density",
        1 / inv if significant else np.nan,
        inv_se / inv**2 if significant else np.nan,
        "dimensionless",
        "scatterers per pixel per pitch",
    )
    p["density_identified"] = (
        (),
        int(significant),
        attrs("dimensionless", "1 if the inverse density exceeds 2 SE (density fitted)"),
    )
    p["density_lower_bound"] = (
        (),
        float(1 / (inv + 2 * inv_se)) if inv + 2 * inv_se > 0 else np.inf,
        attrs("dimensionless", "density at 2 SE of the inverse density"),
    )
    for k in ("skewness", "excess_kurtosis"):
        put(k, whole[k], se[k], "dimensionless", f"{k} of the log data")
    return p


def _combined_inverse_density(whole: dict, jack: list[dict]) -> tuple[float, float, str]:
    """Contrast and ``var ln I`` estimates of ``1/rho`` combined by their jackknife covariance.

    Weights ``C^-1 1 / (1' C^-1 1)`` (``C`` the delete-one-block covariance of the two
    estimates: they share every pixel); the combined SE is the jackknife SE of the weighted
    sum. One estimate alone when the other is missing (log data) or ``C`` is singular.
    """
    keys = ("inverse_density_contrast", "inverse_density_log")
    est = np.array([whole[k] for k in keys], dtype=float)
    reps = np.array([[j[k] for k in keys] for j in jack], dtype=float)
    n = len(jack)
    ok = np.isfinite(est) & np.all(np.isfinite(reps), axis=0)
    dev = reps - reps.mean(axis=0)
    if ok.all():
        cov = (n - 1) / n * dev.T @ dev
        if np.linalg.cond(cov) < 1e12:
            w = np.linalg.solve(cov, np.ones(2))
            w = w / w.sum()
            comb = reps @ w
            se = float(np.sqrt((n - 1) / n * np.sum((comb - comb.mean()) ** 2)))
            return (
                float(est @ w),
                se,
                (f"contrast and var ln I combined, weights {w[0]:.3f} and {w[1]:.3f}"),
            )
    i = int(np.flatnonzero(ok)[0]) if ok.any() else 0
    se = float(np.sqrt((n - 1) / n * np.sum(dev[:, i] ** 2)))
    how = "contrast only" if i == 0 else "var ln I only"
    if i == 0 and not ok[1]:
        how += " (var ln I not observed: log data with unknown gain)"
    return float(est[i]), se, how
