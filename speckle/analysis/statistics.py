"""Speckle statistics: histograms, Rayleigh/exponential fits, speckle contrast and its theory.

Thin xarray-native wrappers over numpy/scipy. Histograms are probability densities (area 1);
fits are maximum-likelihood fits from :mod:`scipy.stats` with the location fixed at 0.

Goodness of fit
---------------
Each fit reports

* the Kolmogorov-Smirnov statistic ``ks_statistic`` (sup distance between the empirical and
  fitted CDFs): distribution-free and binning-free, so it is the primary measure;
* a Pearson chi-square (``chi2``, ``chi2_dof``) over bins of equal probability under the fitted
  law (edges at its quantiles, so every bin expects ``n/bins`` >= 5 counts; ``dof = bins - 2``
  for one fitted parameter). It is sensitive to the body of the histogram where the KS
  statistic is weak and complements what the figures show.

Both p-values assume independent pixels. They are not: in the model, pixels of one A-line share
their scatterers (and, with a fixed count, their number), and non-rectangular spectra correlate
neighbouring pixel fields; in measured images speckle is correlated over ~2 px in depth and
several A-lines. The effective sample size is therefore smaller than the pixel count and the
p-values are anti-conservative (too small). Use the statistics as distances, not as tests,
unless the data are thinned to independent pixels.

Speckle contrast theory
-----------------------
For an A-line with ``M`` scatterers uniform on ``[0, H)``, amplitudes with kurtosis
``kappa_a = E|a|^4/(E|a|^2)^2`` and ``k0 = m*pi/H`` with integer ``m > N/2`` (so ``E[A] = 0``
and ``E[A^2] = 0`` exactly), each pixel field is a sum of ``M`` i.i.d. zero-mean terms
``X_j = a_j exp(2i k0 z_j) g(z_j - z_q)`` with ``g(u) = sum_n S_n exp(2 pi i n u / H)``. Averaging
over ``z`` uniform on one period gives ``E|X|^2 = E|a|^2 mu2`` and
``E|X|^4 = E|a|^4 mu4`` with

    mu2 = sum_n S_n^2,      mu4 = sum_s (S*S)_s^2   (S*S: autoconvolution of the spectrum).

For ``I = |sum_j X_j|^2``: ``E I = M mu2 E|a|^2`` and
``E I^2 = M E|X|^4 + 2 M (M-1) (E|X|^2)^2``, hence

    fixed count:    C^2 = Var I / <I>^2 = 1 + (kappa_a mu4 / mu2^2 - 2) / M,
    Poisson count:  C^2 = 1 + kappa_a mu4 / (M mu2^2)          (E[K(K-1)] = M^2).

Rectangular spectrum: ``mu4/mu2^2 = (2 N^2 + 1) / (3 N)``. Contrast does not depend on ``k0``.
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr
from scipy import stats

from .._deprecate import keyword_only
from .._validate import as_finite_array, check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, inverse_units, labelled, units_of
from ..scene.scatterers import AMPLITUDE_MODELS, COUNT_MODELS, amplitude_kurtosis
from ..system.source import check_weights

__all__ = [
    "contrast_standard_error",
    "contrast_theory",
    "exponential_pdf",
    "fit_exponential",
    "fit_rayleigh",
    "histogram",
    "rayleigh_pdf",
    "speckle_contrast",
    "spectrum_moments",
]

#: Smallest expected count per chi-square bin (the number of bins is reduced to reach it).
MIN_EXPECTED = 5.0


#: Samples: finite real numbers, the DataArray kept for its units (the decorator's checks).
_SAMPLES = ArraySpec(kind="real", keep_labels=True)


def _flat(values: object, name: str) -> np.ndarray:
    """The decorator-checked samples, flattened floats (at least two)."""
    arr = np.asarray(values, dtype=float).ravel()
    if arr.size < 2:
        raise ValueError(f"{name} must hold at least 2 values, got {arr.size}")
    return arr


def _units(values: object) -> str:
    """The samples' units attribute (dimensionless for plain numpy)."""
    return str(getattr(values, "attrs", {}).get("units", units_of("dimensionless")))


def _usable(edges: np.ndarray) -> bool:
    """Strictly increasing edges whose widths have a finite reciprocal (no denormal bins)."""
    widths = np.diff(edges)
    with np.errstate(divide="ignore", over="ignore"):
        return bool(np.all(widths > 0) and np.all(np.isfinite(1.0 / widths)))


@preprocess_and_wrap(checks={"values": _SAMPLES})
def histogram(
    values: object, bins: int | object = 50, range: tuple[float, float] | None = None
) -> xr.DataArray:
    """Probability-density histogram (area 1) of all values, as a labelled DataArray.

    Parameters
    ----------
    values : array_like or xarray.DataArray
        Samples (any shape; flattened). Must be finite.
    bins : int or array_like
        Number of equal-width bins (>= 1) or the monotonically increasing bin edges.
    range : (float, float), optional
        Lower and upper edge for integer ``bins``; default: min and max of ``values``.

    Returns
    -------
    xarray.DataArray
        Density with dim ``bin``; coordinates ``bin`` (bin centre), ``bin_lower`` and
        ``bin_upper`` (edges), in the units of ``values``. Attributes: ``count`` (number of
        samples), ``outside`` (samples outside the edges, not counted), ``units`` (1/units of
        values). The density integrates to ``(count - outside)/count``.
    """
    x = _flat(values, "values")
    if isinstance(bins, int | np.integer) and not isinstance(bins, bool):
        nb = check_int(bins, "bins", low=1)
        if range is None:
            lo, hi = float(x.min()), float(x.max())
        else:
            if len(range) != 2:
                raise ValueError(f"range must be (low, high), got {range!r}")
            lo = check_real(range[0], "range[0]")
            hi = check_real(range[1], "range[1]", low=lo, low_inclusive=False)
        edges = np.linspace(lo, hi, nb + 1)
        if range is None and not _usable(edges):
            # (nearly) constant values: bins of unit width starting at the minimum
            edges = lo + np.arange(nb + 1, dtype=float)
        if not _usable(edges):
            raise ValueError(f"range {range!r} is too narrow for {nb} bins")
    else:
        if range is not None:
            raise ValueError("range is only used with an integer number of bins")
        edges = as_finite_array(bins, "bins").ravel()
        if edges.size < 2 or not _usable(edges):
            raise ValueError("bins must be an int >= 1 or >= 2 strictly increasing edges")
    counts, _ = np.histogram(x, bins=edges)
    density = counts / (x.size * np.diff(edges))
    units = _units(values)
    name = getattr(values, "name", None) or "values"
    return xr.DataArray(
        density,
        dims=("bin",),
        coords={
            "bin": ("bin", 0.5 * (edges[:-1] + edges[1:]), labelled(units, f"{name} (bin centre)")),
            "bin_lower": ("bin", edges[:-1], labelled(units, f"{name} (lower bin edge)")),
            "bin_upper": ("bin", edges[1:], labelled(units, f"{name} (upper bin edge)")),
        },
        name=f"{name}_density",
        attrs={
            **labelled(inverse_units(units), f"probability density of {name}"),
            "count": int(x.size),
            "outside": int(x.size - counts.sum()),
        },
    )


def rayleigh_pdf(x: object, sigma: float) -> object:
    """Rayleigh density ``(x/sigma^2) exp(-x^2/(2 sigma^2))`` for ``x >= 0`` (0 below).

    ``x`` may be a number, an array or a DataArray (returned with the same labels).
    """
    s = check_real(sigma, "sigma", low=0, low_inclusive=False)
    return xr.apply_ufunc(lambda v: stats.rayleigh.pdf(v, scale=s), x)


def exponential_pdf(x: object, mean: float) -> object:
    """Exponential density ``exp(-x/mean)/mean`` for ``x >= 0`` (0 below)."""
    m = check_real(mean, "mean", low=0, low_inclusive=False)
    return xr.apply_ufunc(lambda v: stats.expon.pdf(v, scale=m), x)


def _chi_square(x: np.ndarray, dist, bins: int) -> tuple[float, int]:
    """Pearson chi-square of ``x`` against frozen ``dist`` over equal-probability bins.

    Edges are the fitted distribution's quantiles, so every bin expects ``n/bins`` counts; the
    number of bins is reduced until each expects at least :data:`MIN_EXPECTED`.
    """
    nb = int(max(2, min(bins, x.size // MIN_EXPECTED)))
    if nb < 3:
        warnings.warn(
            f"chi-square: {x.size} samples give {nb} bins of {MIN_EXPECTED:g} expected counts, "
            "0 degrees of freedom: chi2_pvalue is NaN (use >= 15 samples)",
            RuntimeWarning,
            stacklevel=5,
        )
    edges = dist.ppf(np.linspace(0.0, 1.0, nb + 1))
    edges[0], edges[-1] = -np.inf, np.inf
    observed, _ = np.histogram(x, bins=edges)
    expected = x.size / nb
    chi2 = float(np.sum((observed - expected) ** 2) / expected)
    return chi2, nb - 2


def _fit(values: object, name: str, family, parameter: str, chi2_bins: int) -> xr.Dataset:
    """Maximum-likelihood fit (loc 0) of a one-parameter scipy family, with goodness of fit."""
    x = _flat(values, name)
    check_int(chi2_bins, "chi2_bins", low=3)
    if np.any(x < 0):
        raise ValueError(f"{name} must be non-negative")
    if not np.any(x > 0):
        raise ValueError(
            f"{name} must hold a positive value: all zero, the fitted law is degenerate"
        )
    # the maximum-likelihood scale in closed form (scipy's fit gives the same numbers, but
    # refuses a Rayleigh sample holding an exact zero, e.g. from 8-bit data)
    scale = np.sqrt(np.mean(x**2) / 2) if family.name == "rayleigh" else np.mean(x)
    model = {"rayleigh": "rayleigh", "expon": "exponential"}[family.name]
    return _fit_result(
        x, family(scale=scale), parameter, float(scale), _units(values), model, chi2_bins
    )


def _fit_result(
    x: np.ndarray, dist, parameter: str, value: float, units: str, model: str, chi2_bins: int
) -> xr.Dataset:
    ks = stats.kstest(x, dist.cdf)
    chi2, dof = _chi_square(x, dist, chi2_bins)
    note = (
        "p-values assume independent pixels; pixels within a speckle grain are correlated, "
        "so they are anti-conservative (too small)"
    )
    return xr.Dataset(
        {
            parameter: ((), value, labelled(units, f"fitted {model} {parameter}")),
            "ks_statistic": (
                (),
                float(ks.statistic),
                attrs("dimensionless", "Kolmogorov-Smirnov statistic"),
            ),
            "ks_pvalue": (
                (),
                float(ks.pvalue),
                attrs("probability", "Kolmogorov-Smirnov p-value", note=note),
            ),
            "chi2": (
                (),
                chi2,
                attrs("dimensionless", "Pearson chi-square over equal-probability bins"),
            ),
            "chi2_dof": ((), dof, attrs("count", "chi-square degrees of freedom")),
            "chi2_pvalue": (
                (),
                float(stats.chi2.sf(chi2, dof)),
                attrs("probability", "chi-square p-value", note=note),
            ),
            "n": ((), int(x.size), attrs("count", "number of samples")),
        },
        attrs={
            "model": model,
            "method": "maximum likelihood (scipy.stats), loc fixed at 0",
            "note": note,
        },
    )


@preprocess_and_wrap(checks={"amplitude": _SAMPLES})
def fit_rayleigh(amplitude: object, *, chi2_bins: int = 50) -> xr.Dataset:
    """Maximum-likelihood Rayleigh fit of speckle amplitudes (``scipy.stats.rayleigh``, loc 0).

    The MLE is ``sigma^2 = <A^2>/2``, i.e. half the mean intensity.

    Parameters
    ----------
    amplitude : array_like or xarray.DataArray
        Non-negative amplitudes (any shape; flattened).
    chi2_bins : int
        Number of equal-probability bins for the chi-square (>= 3; reduced if needed).

    Returns
    -------
    xarray.Dataset
        Scalars ``sigma`` (units of ``amplitude``), ``ks_statistic``, ``ks_pvalue``, ``chi2``,
        ``chi2_dof``, ``chi2_pvalue``, ``n`` (see the module docstring for caveats).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> amplitude = np.random.default_rng(0).rayleigh(1.0, size=10_000)
    >>> fit = speckle.fit_rayleigh(amplitude)
    >>> sorted(fit.data_vars)[:3]
    ['chi2', 'chi2_dof', 'chi2_pvalue']
    """
    return _fit(amplitude, "amplitude", stats.rayleigh, "sigma", chi2_bins)


@preprocess_and_wrap(checks={"intensity": _SAMPLES})
def fit_exponential(intensity: object, *, chi2_bins: int = 50) -> xr.Dataset:
    """Maximum-likelihood exponential fit of speckle intensities (``scipy.stats.expon``, loc 0).

    The MLE of the mean is the sample mean. Returns the same variables as :func:`fit_rayleigh`
    with ``mean`` in place of ``sigma``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> intensity = np.random.default_rng(0).exponential(2.0, size=10_000)
    >>> fit = speckle.fit_exponential(intensity)
    >>> sorted(fit.data_vars)[:3]
    ['chi2', 'chi2_dof', 'chi2_pvalue']
    """
    return _fit(intensity, "intensity", stats.expon, "mean", chi2_bins)


def _reduced_dims(data: xr.DataArray, dim: object) -> tuple[str, ...]:
    """The dims ``dim`` names (all when None), refused by name when unknown."""
    if dim is None:
        return tuple(data.dims)
    names = [dim] if isinstance(dim, str) else dim
    if not isinstance(names, list | tuple) or not all(isinstance(d, str) for d in names):
        raise TypeError(f"dim must be a dim name or a list of them, got {dim!r}")
    unknown = [d for d in names if d not in data.dims]
    if unknown:
        raise ValueError(f"dim {unknown} not among intensity's dims {tuple(data.dims)}")
    return tuple(names)


@preprocess_and_wrap(checks={"intensity": _SAMPLES})
def speckle_contrast(intensity: object, dim: str | list[str] | None = None) -> object:
    """Speckle contrast ``C = std(I)/mean(I)`` (population std, ``ddof=0``).

    Parameters
    ----------
    intensity : array_like or xarray.DataArray
        Pixel intensities ``|A|^2`` (finite; at least 2 values per contrast).
    dim : str or list of str, optional
        Dims to reduce over (DataArray only); default all.

    Returns
    -------
    float or xarray.DataArray
        The contrast (dimensionless); a DataArray over the remaining dims if ``dim`` is given.
        NaN, with a ``RuntimeWarning`` saying so, where the mean intensity is zero (no
        contrast is defined).

    Raises
    ------
    TypeError, ValueError
        ``intensity`` not finite numbers or with fewer than 2 values per contrast; ``dim`` not
        a dim of ``intensity`` (or given with a plain array).

    Examples
    --------
    >>> speckle_contrast([1.0, 3.0])  # std 1, mean 2
    0.5
    """
    if isinstance(intensity, xr.DataArray):
        dims = _reduced_dims(intensity, dim)
        n = int(np.prod([intensity.sizes[d] for d in dims]))
        if n < 2:
            raise ValueError(f"intensity must hold at least 2 values over {dims}, got {n}")
        mean = intensity.mean(dim=dim)
        zero = mean == 0
        if bool(zero.any()):
            _warn_zero_mean(int(zero.sum()))
        c = intensity.std(dim=dim) / mean.where(~zero)
        return c.rename("contrast").assign_attrs(attrs("contrast", "speckle contrast std/mean"))
    if dim is not None:
        raise TypeError("dim needs intensity as an xarray.DataArray")
    x = _flat(intensity, "intensity")
    mean = x.mean()
    if mean == 0:
        _warn_zero_mean(1)
        return float("nan")
    return float(x.std() / mean)


def _warn_zero_mean(count: int) -> None:
    warnings.warn(
        f"speckle_contrast: the mean intensity is zero in {count} place(s): no contrast, NaN",
        RuntimeWarning,
        stacklevel=3,
    )


@preprocess_and_wrap(checks={"intensity": ArraySpec(kind="real", labelled=True, keep_labels=True)})
def contrast_standard_error(intensity: xr.DataArray, sample_dim: str = "x") -> tuple[float, float]:
    """Contrast over all pixels and its standard error from independent samples along a dim.

    Pixels inside an A-line are correlated (shared scatterers, fixed count) but A-lines are
    independent, so the per-line moments ``m1_i = mean_q I``, ``m2_i = mean_q I^2`` are i.i.d.
    With ``M1 = mean_i m1_i``, ``M2 = mean_i m2_i``, the estimator ``C^2 = M2/M1^2 - 1`` has, by
    the delta method, ``Var(C^2) = grad^T Sigma grad / L`` with
    ``grad = (-2 M2/M1^3, 1/M1^2)``, ``Sigma`` the sample covariance of ``(m1_i, m2_i)`` and
    ``L`` the number of lines; ``SE(C) = SE(C^2) / (2 C)``.

    Returns
    -------
    (float, float)
        ``(C, SE(C))``; ``(NaN, NaN)`` at zero mean intensity and ``(0, NaN)`` for a constant
        one (each with a ``RuntimeWarning``).
    """
    if sample_dim not in intensity.dims:
        raise TypeError(
            f"intensity must be a DataArray with a {sample_dim!r} dim (sample_dim), got "
            f"dims {intensity.dims}"
        )
    n_lines = intensity.sizes[sample_dim]
    if n_lines < 3:
        raise ValueError(f"need >= 3 independent samples along {sample_dim!r}, got {n_lines}")
    x = np.asarray(intensity.transpose(sample_dim, ...).values, dtype=float)
    x = x.reshape(n_lines, -1)
    m1, m2 = x.mean(axis=1), (x**2).mean(axis=1)
    big1, big2 = m1.mean(), m2.mean()
    if big1 == 0:
        _warn_zero_mean(1)
        return float("nan"), float("nan")
    c2 = big2 / big1**2 - 1.0
    if c2 == 0:
        warnings.warn(
            "contrast_standard_error: the intensity is constant (contrast 0): the delta "
            "method's standard error (SE(C^2)/2C) is undefined, NaN",
            RuntimeWarning,
            stacklevel=2,
        )
        return 0.0, float("nan")
    grad = np.array([-2.0 * big2 / big1**3, 1.0 / big1**2])
    var_c2 = float(grad @ np.cov(np.vstack([m1, m2])) @ grad) / n_lines
    c = float(np.sqrt(c2))
    return c, float(np.sqrt(var_c2) / (2.0 * c))


@preprocess_and_wrap(arrays=["spectrum"])
def spectrum_moments(n_pixels: int, spectrum: object | None = None) -> tuple[float, float]:
    """``(mu2, mu4)``: ``sum S_n^2`` and ``sum_s (S*S)_s^2`` (squared autoconvolution).

    ``spectrum=None`` is the rectangular spectrum (``mu2 = N``, ``mu4 = (2N^3 + N)/3``).
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    if spectrum is None:  # closed form: no allocation for any N (exact integers to 2^53)
        return float(n), (2.0 * n**3 + n) / 3.0
    s = check_weights(spectrum, n)
    return float(np.sum(s**2)), float(np.sum(np.convolve(s, s) ** 2))


@keyword_only("amplitude", "count")
@preprocess_and_wrap(
    arrays=["density", "spectrum"],
    wrap_like="density",
    name="contrast_theory",
    quantity="contrast",
    long_name="speckle contrast (theory)",
)
def contrast_theory(
    density: object,
    n_pixels: int,
    spectrum: object | None = None,
    *,
    amplitude: str = "equal",
    count: str = "fixed",
) -> object:
    """Expected speckle contrast ``C = sqrt(Var I)/<I>`` of the model (see module docstring).

    Parameters
    ----------
    density : float, array_like or xarray.DataArray
        Scatterers per pixel ``rho`` (> 0). For ``count="fixed"`` the line holds
        ``M = round(rho*N)`` scatterers, which must be >= 1.
    n_pixels : int
        Pixels per A-line ``N`` (>= 2).
    spectrum : array_like or xarray.DataArray, optional
        ``N`` spectral weights; default rectangular.
    amplitude : {"equal", "rayleigh", "uniform"}
        Scatterer amplitude model (sets ``kappa_a``).
    count : {"fixed", "poisson"}
        Scatterer count model.

    Returns
    -------
    float, numpy.ndarray or xarray.DataArray
        Contrast, shaped like ``density``.

    Examples
    --------
    >>> import speckle
    >>> round(float(speckle.contrast_theory(1000.0, 64)), 3)  # dense limit: 1
    1.0
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    check_choice(amplitude, "amplitude", AMPLITUDE_MODELS)
    check_choice(count, "count", COUNT_MODELS)
    rho = as_finite_array(density, "density")
    if np.any(rho <= 0):
        raise ValueError("density must be > 0 scatterers per pixel")
    mu2, mu4 = spectrum_moments(n, spectrum)
    kappa = amplitude_kurtosis(amplitude)
    if count == "fixed":
        m = np.round(rho * n)
        if np.any(m < 1):
            raise ValueError(
                f"density must give round(density*n_pixels) >= 1, i.e. "
                f"density >= {0.5 / n:g} for n_pixels={n}"
            )
        c2 = 1.0 + (kappa * mu4 / mu2**2 - 2.0) / m
    else:
        c2 = 1.0 + kappa * mu4 / (rho * n * mu2**2)
    return np.sqrt(c2)  # labelled like density (preprocess_and_wrap)
