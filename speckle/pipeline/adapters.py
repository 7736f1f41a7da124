"""Config adapters: the pipeline's config sections -> the package's arguments and objects.

A ``source`` section gives a spectrum's and a scene's keyword arguments
(:func:`spectrum_kwargs`, :func:`scene_kwargs`: the dictionary core in ``speckle._adapters``,
below every layer, which the realism study shares), a datasheet gives a
:class:`speckle.System`, the ``dask`` section the sweeps' options. Kept apart from the figure
modules so that a figure module can use them without making its rules depend on another
figure's code (rules track the modules their scripts import).
"""

from __future__ import annotations

from collections.abc import Mapping

import xarray as xr

from .._adapters import scene_kwargs, spectrum_kwargs
from ..imaging._bscan import bscan
from ..scene.scatterers import random_scatterers
from ..system._datasheet import datasheet
from ..system.source import spectrum

__all__ = [
    "dask_options",
    "random_bscan",
    "resolve_source",
    "scene_kwargs",
    "source_options",
    "source_spectrum",
    "spectrum_kwargs",
    "system_from_config",
]


def source_spectrum(source: Mapping, **override: object) -> xr.DataArray:
    """:func:`speckle.spectrum` of a ``source`` section (see :func:`spectrum_kwargs`)."""
    return spectrum(**spectrum_kwargs(source, **override))


def source_options(source: Mapping) -> dict:
    """The figure functions' source keywords from the pipeline's ``source`` config.

    ``n_pixels``, ``pixel_size``, ``shape`` (default ``"rectangular"``) and ``fwhm_fraction``
    (default None): the names of the section itself, which the figure functions take as flat
    keywords (they are dataset attributes of the sweeps). ``k0_dk`` is left out: each figure
    sets it (Fig. 2 from ``source``, Figs. 1 and 5 sweep it).
    """
    return {
        "n_pixels": source["n_pixels"],
        "pixel_size": source["pixel_size"],
        "shape": source.get("shape", "rectangular"),
        "fwhm_fraction": source.get("fwhm_fraction"),
    }


def random_bscan(
    source: Mapping,
    density: float,
    *,
    n_alines: int,
    seed: int,
    method: str = "direct",
    normalise: str = "none",
) -> tuple[xr.Dataset, xr.DataArray]:
    """B-scan of a random scene of equal-amplitude scatterers and the spectrum it used.

    The scene (:func:`speckle.random_scatterers`, fixed count per A-line) depends on ``(seed,
    density, n_alines, n_pixels, pixel_size)`` only, not on ``k0_dk`` or the spectrum shape.

    Parameters
    ----------
    source : mapping
        A ``source`` section (:func:`spectrum_kwargs`).
    density : float
        Scatterers per pixel ``N_sc/N``.
    n_alines, seed : int
        Independent A-lines and the root seed.
    method : str
        A-scan method of :func:`speckle.bscan`.
    normalise : {"none", "density", "expected"}
        See :func:`speckle.bscan`.

    Returns
    -------
    (xarray.Dataset, xarray.DataArray)
        The :func:`speckle.bscan` dataset and the source spectrum.
    """
    src = source_spectrum(source)
    scene = random_scatterers(n_alines, density, **scene_kwargs(source), seed=seed)
    return bscan(scene, src, normalise=normalise, method=method), src


def system_from_config(sheet: Mapping):
    """:func:`speckle.datasheet` from a config mapping (``camera_range_nm`` as a list; null
    values are left out)."""
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
