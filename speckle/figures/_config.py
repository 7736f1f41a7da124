"""Helpers turning the pipeline's config sections into package arguments (shared by figures).

Kept apart from the figure modules so that a figure module can use them without making its
rules depend on another figure's code (rules track the modules their scripts import).
"""

from __future__ import annotations

from collections.abc import Mapping

import xarray as xr

from .._validate import check_int, check_real
from ..system.source import spectrum

__all__ = [
    "dask_options",
    "resolve_source",
    "source_options",
    "source_spectrum",
    "system_from_config",
]


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


def system_from_config(sheet: Mapping):
    """:func:`speckle.datasheet` from a config mapping (``camera_range_nm`` as a list; null
    values are left out)."""
    from ..system.datasheet import datasheet

    args = {k: v for k, v in sheet.items() if v is not None}
    if args.get("camera_range_nm") is not None:
        args["camera_range_nm"] = tuple(args["camera_range_nm"])
    return datasheet(**args)


def resolve_source(source: Mapping) -> dict:
    """The pipeline's ``source`` section in its model form (``n_pixels``, ``pixel_size``, ...).

    The section gives the model parameters (``n_pixels``, ``pixel_size``, ``k0_dk``,
    ``shape``, ``fwhm_fraction``; returned unchanged while ``datasheet`` is absent or null), or
    names a system by its datasheet, ``datasheet: {wavelength_nm, bandwidth_nm, camera_pixels,
    camera_range_nm | imaging_depth, refractive_index, ...}`` (:func:`speckle.datasheet`). A
    datasheet defines the source: ``N`` = camera pixels, pixel size ``H/N``, ``k0/delta_k`` and
    a Gaussian spectrum with the datasheet FWHM replace any model values in the section (so a
    ``--configfile`` layered over the defaults can switch to a datasheet). The figures centre
    the Gaussian on the grid's ``k0``; the datasheet source is centred on ``2 pi n/lambda0``
    (:attr:`System.source_wavenumber`), a few per cent of ``delta_k`` away.
    """
    if source.get("datasheet") is None:
        return dict(source)
    system = system_from_config(source["datasheet"])
    return {
        "datasheet": dict(source["datasheet"]),
        "n_pixels": system.n_pixels,
        "pixel_size": system.pixel_size,
        "k0_dk": system.k0_dk,
        "shape": "gaussian",
        "fwhm_fraction": system.fwhm_fraction,
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
