"""Helpers turning the pipeline's config sections into package arguments (shared by figures).

Kept apart from the figure modules so that a figure module can use them without making its
rules depend on another figure's code (rules track the modules their scripts import).
"""

from __future__ import annotations

from collections.abc import Mapping

import xarray as xr

from .._validate import check_int, check_real
from ..system.source import spectrum

__all__ = ["dask_options", "source_options", "source_spectrum"]


def source_spectrum(
    n_pixels: int,
    pixel_size: float,
    k0_dk: float,
    shape: str = "rectangular",
    fwhm_fraction: float | None = None,
) -> xr.DataArray:
    """Spectrum of the pipeline's ``source`` config: depth ``H = N * pixel_size``.

    Parameters
    ----------
    n_pixels : int
        Pixels (= spectral components) per A-scan, >= 2.
    pixel_size : float
        Pixel size ``H/N`` in µm, > 0.
    k0_dk : float
        ``k0/delta_k`` (= ``Lc/lambda0``), >= 0.
    shape : {"rectangular", "gaussian"}
        Spectrum shape.
    fwhm_fraction : float, optional
        Gaussian FWHM as a fraction of ``delta_k = N*pi/H`` (needed for ``"gaussian"``).
    """
    n = check_int(n_pixels, "n_pixels", low=2)
    h = n * check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    frac = fwhm_fraction if shape == "gaussian" else None
    return spectrum(n, h, k0_dk=k0_dk, shape=shape, fwhm_fraction=frac)


def source_options(source: Mapping) -> dict:
    """Keyword arguments of :func:`source_spectrum` from the pipeline's ``source`` config.

    ``k0_dk`` is left out: each figure sets it (Fig. 2 from ``source``, Figs. 1 and 5 sweep it).
    """
    return {
        "n_pixels": source["n_pixels"],
        "pixel_size": source["pixel_size"],
        "shape": source.get("shape", "rectangular"),
        "fwhm_fraction": source.get("fwhm_fraction"),
    }


def dask_options(dask: Mapping, threads: int | None = None) -> dict:
    """The pipeline's ``dask`` config for :func:`speckle.sweep.sweep`.

    On a local scheduler the worker count is capped at ``threads`` (the rule's Snakemake
    threads), so that Snakemake's core accounting holds; a given ``address`` is used as is.
    """
    out = {
        "scheduler": dask.get("scheduler", "threads"),
        "address": dask.get("address"),
        "n_workers": dask.get("n_workers"),
    }
    if threads is not None and out["address"] is None:
        out["n_workers"] = min(int(out["n_workers"] or threads), int(threads))
    return out
