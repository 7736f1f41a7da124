"""B-scans: images of a scatterer field as labelled xarray datasets.

:func:`bscan` applies :func:`speckle.ascan` to every A-line of a scatterer field (and along any
extra dims such as ``strain`` or ``k0_dk``) with :func:`xarray.apply_ufunc`, so Dask-backed
fields are imaged lazily, chunk by chunk.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import xarray as xr

from .._deprecate import keyword_only
from .._validate import check_choice, check_int, check_real
from ..conventions import attrs, coord, depth_range_of, grid_attrs, with_grid
from ..provenance import provenance_attrs
from ..scene.scatterers import AMPLITUDE_MODELS
from ..scene.shared import check_not_empty
from ..system.source import check_source, check_weights
from ._rules import check_tol
from .aline import ascan, pixel_depths
from .methods import ASCAN_METHODS

__all__ = ["NORMALISATIONS", "bscan", "expected_intensity", "map_lines"]

#: ``"none"``: Eq. 4 as is. ``"density"``: divide the field by sqrt(density) (paper's Fig. 2).
#: ``"expected"``: divide by sqrt of the expected mean intensity, so <|A|^2> = 1.
NORMALISATIONS = ("none", "density", "expected")


@keyword_only("mean_square_amplitude")
def expected_intensity(
    density: float,
    n_pixels: int,
    spectrum: xr.DataArray | None,
    *,
    mean_square_amplitude: float = 1.0,
) -> float:
    """Expected mean pixel intensity ``<|A|^2> = rho * N * <|a|^2> * sum_n S_n^2``.

    Exact for uniformly distributed scatterers over the full depth ``[0, H)`` when
    ``2*k0*H`` is a multiple of ``2*pi`` (so that the mean field vanishes), and accurate to
    ``O(1/(k0 H))`` otherwise. ``spectrum=None`` means rectangular (``sum S^2 = N``).

    Examples
    --------
    >>> import speckle
    >>> speckle.expected_intensity(4.0, 64, None)  # rho N sum S^2 = 4 * 64 * 64
    16384.0
    """
    rho = check_real(density, "density", low=0.0)
    n = check_int(n_pixels, "n_pixels", low=1)
    a2 = check_real(mean_square_amplitude, "mean_square_amplitude", low=0.0)
    if spectrum is None:
        s2 = float(n)
    else:
        s2 = float(np.sum(check_weights(spectrum, n) ** 2))
    return rho * n * a2 * s2


def map_lines(
    func: Callable[..., np.ndarray],
    scene: xr.Dataset,
    n_pixels: int,
    dtype: type,
    **kwargs: object,
) -> xr.DataArray:
    """``func(z, amplitude, n_pixels=N, **kwargs)`` over every line of a scene of A-lines.

    Parameters
    ----------
    func : callable
        Maps depths and amplitudes of shape ``(..., M)`` to ``(..., N)`` (e.g.
        :func:`speckle.ascan`).
    scene : xarray.Dataset
        Variables ``z`` and ``amplitude`` with a ``scatterer`` dim (numpy or Dask-backed: a
        Dask scene stays lazy, one task per chunk).
    n_pixels : int
        Pixels ``N`` of the new last dim ``depth``.
    dtype : numpy dtype
        The output's dtype.
    **kwargs
        Further keyword arguments of ``func``.

    Returns
    -------
    xarray.DataArray
        ``func``'s output over the scene's other dims and ``depth``; the scene's line dim
        ``aline`` becomes the image's lateral dim ``x`` (µm, the lines' positions). This is the
        one place where a scene of independent lines becomes an image (issue 32).
    """
    out = xr.apply_ufunc(
        func,
        scene.z,
        scene.amplitude,
        input_core_dims=[["scatterer"], ["scatterer"]],
        output_core_dims=[["depth"]],
        kwargs={"n_pixels": n_pixels, **kwargs},
        dask="parallelized",
        output_dtypes=[dtype],
        dask_gufunc_kwargs={"output_sizes": {"depth": n_pixels}},
    )
    if "aline" not in out.dims:  # the scene dim of independent lines (conventions.COORDS)
        return out
    out = out.rename({"aline": "x"})
    if "x" in out.coords:
        out = out.assign_coords(x=coord("x", out["x"].values))
    return out


def bscan(
    scene: xr.Dataset,
    source: xr.DataArray,
    *,
    normalise: str = "none",
    method: str = "direct",
    tol: float | None = None,
) -> xr.Dataset:
    """Image a scatterer field into a complex B-scan.

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field with variables ``z`` (µm) and ``amplitude`` sharing a ``scatterer`` dim
        (see :func:`speckle.random_scatterers`); other dims (``aline``, ``strain``,
        ...) are carried through. Its ``n_pixels`` and ``depth_range`` attributes, when present,
        must match the source's (``ValueError`` otherwise).
    source : xarray.DataArray
        Spectrum from :func:`speckle.system.source.spectrum`; its attributes give ``n_pixels``,
        ``depth_range`` (``H``, µm) and ``k0``.
    normalise : {"none", "density", "expected"}
        Explicit amplitude normalisation, recorded in the ``normalisation`` attribute.
    method, tol
        Passed to :func:`speckle.ascan`; checked before any work (also for Dask-backed
        scenes, whose imaging runs at ``.compute()``).

    Returns
    -------
    xarray.Dataset
        ``field`` (complex), ``amplitude`` = ``|field|`` and ``intensity`` = ``|field|^2`` with
        dims ``(..., depth, x)`` (a scene's lines ``aline`` become ``x``); coordinate
        ``depth`` = ``q*H/N`` in µm. Attributes carry
        the source and scene parameters and provenance.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(16, 4.0, n_pixels=64, depth_range=512.0, seed=3)
    >>> img = speckle.bscan(scene, src, normalise="density")
    >>> img.field.dims, img.field.shape
    (('depth', 'x'), (64, 16))
    """
    check_choice(normalise, "normalise", NORMALISATIONS)
    if not isinstance(scene, xr.Dataset) or not {"z", "amplitude"} <= set(scene.data_vars):
        raise TypeError("scene must be an xarray.Dataset with variables 'z' and 'amplitude'")
    check_not_empty(scene)
    src = check_source(source)
    n, h, k0 = src["n_pixels"], src["depth_range"], src["k0"]
    check_choice(method, "method", ASCAN_METHODS)
    check_tol(tol)
    for var in ("z", "amplitude"):
        if "scatterer" not in scene[var].dims:
            raise ValueError(
                f"scene variable {var!r} must have a 'scatterer' dim (see "
                f"speckle.random_scatterers); got dims {scene[var].dims}"
            )
    depth_range_of(scene, "scene", required=False)  # refuses a scene's pre-rename 'depth'
    for key, value in (("n_pixels", n), ("depth_range", h)):
        if key in scene.attrs and not np.isclose(
            float(scene.attrs[key]), value, rtol=1e-12, atol=0
        ):
            raise ValueError(
                f"scene was built for {key}={scene.attrs[key]!r} but the source has "
                f"{key}={value!r}; build the scene and the spectrum with the same n_pixels "
                "and depth_range (µm)"
            )
    field = map_lines(
        ascan,
        scene,
        n,
        np.complex128,
        depth_range=h,
        k0=k0,
        spectrum=source.values,
        method=method,
        tol=tol,
    )
    density = float(scene.attrs.get("density", np.nan))
    if normalise != "none" and not density > 0:
        raise ValueError(f"normalise={normalise!r} needs a scene density > 0, got {density}")
    scale = 1.0
    if normalise == "density":
        scale = 1.0 / np.sqrt(density)
    elif normalise == "expected":
        model = scene.attrs.get("amplitude_model", "equal")
        if model not in AMPLITUDE_MODELS:
            raise ValueError(f"scene amplitude_model must be one of {AMPLITUDE_MODELS}")
        scale = 1.0 / np.sqrt(expected_intensity(density, n, source.values))
    field = field * scale
    dims = [d for d in field.dims if d not in ("depth", "x")] + ["depth", "x"]
    dims = [d for d in dims if d in field.dims]
    field = field.transpose(*dims)
    ds = xr.Dataset(
        {
            "field": field.assign_attrs(attrs("field", "complex A-scan field A(q)")),
            "amplitude": abs(field).assign_attrs(attrs("amplitude", "speckle amplitude |A|")),
            "intensity": (abs(field) ** 2).assign_attrs(
                attrs("dimensionless", "speckle intensity |A|^2")
            ),
        },
        coords={"depth": coord("depth", pixel_depths(n, h), "depth of pixel centre q*H/N")},
    )
    ds.attrs.update({f"scene_{k}": v for k, v in scene.attrs.items()})
    ds.attrs.update(
        {
            **grid_attrs(n, h, k0),
            "delta_k": float(source.attrs["delta_k"]),
            "k0_dk": float(source.attrs["k0_dk"]),
            "spectrum_shape": source.attrs.get("shape", "array"),
            "spectrum_fwhm": float(source.attrs.get("fwhm", np.nan)),
            "normalisation": normalise,
            "normalisation_factor": scale,
            "method": method,
            "tol": np.nan if tol is None else float(tol),
            "pixel_step": "H/N (the paper's H/(N-1) is not DFT-consistent)",
        }
    )
    ds.attrs.update(provenance_attrs())
    return with_grid(ds)  # field, amplitude, intensity: each carries its grid
