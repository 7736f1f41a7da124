"""The SynthOCT challenge's virtual scanner, reproduced: ``synthoct_scan``.

The official ``Part2_Scanner.exe`` is closed; its physics was identified from the four
published scans of the challenge's self-consistency check and the phantoms regenerated from the
baseline's seeds (``docs/explanation/synthoct.md`` gives each measurement):

* **geometry**: A-line ``i`` at ``x_i = -x_max/2 + i x_max/n_lines`` and ``y = 0``; pixel ``q``
  at depth ``q H/N`` with ``H = N`` x pixel size; ``k_n = k0 + n pi/H``, ``k0 = 2 pi/lambda``
  (no refractive index);
* **beam**: double-pass amplitude weight ``exp(-d^2/r^2)`` with ``r`` the INI's beam radius
  (waist ``sqrt(2) r`` in :func:`speckle.beam_scan`'s convention), no focus;
* **spectrum**: the Hann window over the ``N`` spectral samples (``numpy.hanning(N)``);
* **amplitude**: ``sqrt(Energy/100)``;
* **attenuation** (energy shadowing, no free parameter): along each A-line the amplitude at a
  scatterer is ``exp(-sum (E_l/100) W_l^2)`` over the scatterers ``l`` above it, ``W_l`` their
  double-pass weight for *that* line (per line, not a mean field);
* **8-bit mapping**: ``20 log10 |A|`` in a 51 dB window whose top is the image's maximum,
  ``floor(256 (L - L_max + 51)/51)`` clipped to 0..255.

Measured on the four published scans (tests/synthoct/test_scanner.py): correlation of the log
images, each row normalised, in the rows above the floor, 0.9967-0.9973; row means within
0.23 dB. The numpy core (:mod:`speckle.synthoct._scan`, numpy and FINUFFT only) is shared with
the ``speckle-scan`` command. Assumed, not identified (one B-scan at ``y_max = 0`` in every
published case): B-scan ``b`` at ``y_b = -y_max/2 + b y_max/n_bscans``, each imaging the whole
phantom with the weight ``exp(-((x - x_i)^2 + (y - y_b)^2)/r^2)``, written one below the other
in one PNG with one window.
"""

from __future__ import annotations

import os

import numpy as np

from .._validate import check_bool, check_int
from . import _scan
from .files import (
    ScannerConfig,
    phantom_table,
    read_phantom_table,
    read_scanner_config,
)

__all__ = ["FLOOR_FRACTION", "SHADOWING", "scan_agreement", "synthoct_scan"]

#: A row of the official scan is "below the floor" when more than this fraction of its pixels
#: sit at level 0 (clipped at the bottom of the 51 dB window).
FLOOR_FRACTION = 0.05

#: Shadowing laws (``"line"`` is the official scanner's).
SHADOWING = _scan.SHADOWING


def _config(config: object) -> ScannerConfig:
    if isinstance(config, ScannerConfig):
        return config
    if isinstance(config, (str, os.PathLike)):
        return read_scanner_config(config)
    raise TypeError(f"config must be a ScannerConfig or an INI path, got {type(config).__name__}")


def _table(phantom: object, config: ScannerConfig) -> np.ndarray:
    if isinstance(phantom, (str, os.PathLike)):
        return read_phantom_table(phantom, n_scatterers=config.n_scatterers)
    table = phantom_table(phantom)
    if not np.all(np.isfinite(table)):
        raise ValueError("phantom positions and energies must be finite")
    if np.any((table[:, 3] < 0) | (table[:, 3] > 100)):
        raise ValueError("phantom energies must be within 0..100 % (|amplitude| <= 1)")
    if table.shape[0] != config.n_scatterers:
        raise ValueError(
            f"phantom holds {table.shape[0]} scatterers, config's 'number of scatterers in "
            f"b-scan' (n_scatterers) is {config.n_scatterers}"
        )
    return table


def synthoct_scan(
    phantom: object,
    config: object,
    *,
    field: bool = False,
    shadowing: str = "line",
    noise: float | None = None,
    seed: int | None = None,
    tol: float = _scan.TOL,
    eps: float = _scan.EPS,
    nthreads: int | None = None,
):
    """Scan a phantom as the challenge's virtual scanner does (the drop-in).

    Parameters
    ----------
    phantom : xarray.Dataset, numpy.ndarray or path
        A shared scene (:func:`speckle.read_phantom`, :func:`speckle.baseline_phantom`,
        :func:`speckle.shared_scene`; amplitude ``sqrt(Energy/100)``, 2-D scenes at ``y = 0``),
        an ``(M, 4)`` array X, Y, Z (µm), Energy (%), or a phantom file.
    config : ScannerConfig or path
        The scanner's configuration (or its INI file). ``M`` must equal ``n_scatterers``.
    field : bool
        Off by default. True: return the complex field ``A`` (before the 51 dB mapping) instead
        of the 8-bit scan, e.g. to save with :func:`speckle.to_netcdf`.
    shadowing : {"line", "mean", "none"}
        The attenuation law: per A-line (official), its mean over the lines, or none.
    noise : float, optional
        Off by default. Complex Gaussian noise added to the field, its rms in dB relative to the
        field's peak (e.g. ``-45``); needs ``seed``.
    seed : int, optional
        Seed of the noise (``numpy.random.SeedSequence``).
    tol : float
        Scatterer-line pairs whose double-pass weight is below ``tol`` are dropped (0 < tol < 1).
    eps : float
        FINUFFT's tolerance. With the defaults (1e-4 each) the field's relative l2 error against
        the direct sum is ~1e-4 (tested) and 8-bit levels change in ~0.2 % of the pixels, by 1.
    nthreads : int, optional
        FINUFFT threads (default: the CPUs available).

    Returns
    -------
    xarray.DataArray
        uint8 scan ``(depth, x)`` with coordinates in µm (``(y, depth, x)`` for several
        B-scans), or with ``field=True`` the complex128 field, same dims.

    Raises
    ------
    TypeError, ValueError
        On a bad phantom (naming the line for files), configuration, count or option.

    Examples
    --------
    >>> import numpy as np, speckle
    >>> cfg = speckle.ScannerConfig(n_pixels=64, n_lines=32, x_max=192.0, n_scatterers=500)
    >>> rng = np.random.default_rng(0)
    >>> table = np.column_stack([rng.uniform(-96, 96, 500), rng.uniform(-10, 10, 500),
    ...                          rng.uniform(0, 384, 500), np.full(500, 1.0)])
    >>> scan = speckle.synthoct_scan(table, cfg)
    >>> scan.dims, scan.shape, int(scan.max())
    (('depth', 'x'), (64, 32), 255)
    """
    cfg = _config(config)
    field = check_bool(field, "field")
    if seed is not None:
        seed = check_int(seed, "seed", low=0)
    if nthreads is not None:
        nthreads = check_int(nthreads, "nthreads", low=1)
    if shadowing not in SHADOWING:
        raise ValueError(f"shadowing must be one of {SHADOWING}, got {shadowing!r}")
    for name, value in (("tol", tol), ("eps", eps)):
        if not (isinstance(value, (int, float)) and 0 < value < 1):
            raise ValueError(f"{name} must be a number in (0, 1), got {value!r}")
    if noise is not None:
        if not (isinstance(noise, (int, float)) and np.isfinite(noise)):
            raise ValueError(f"noise must be a finite level in dB (e.g. -45), got {noise!r}")
        if seed is None:
            raise ValueError("noise needs a seed (non-negative integer)")
    table = _table(phantom, cfg)
    fields = _scan.scan_fields(table, cfg, shadow=shadowing, tol=tol, eps=eps, nthreads=nthreads)
    if noise is not None:
        rng = np.random.default_rng(np.random.SeedSequence(seed))
        sigma = np.abs(fields).max(initial=0.0) * 10 ** (noise / 20) / np.sqrt(2)
        fields = fields + sigma * (
            rng.standard_normal(fields.shape) + 1j * rng.standard_normal(fields.shape)
        )
    values = fields if field else _scan.to_levels(fields)
    return _label(values, cfg, field)


def scan_agreement(scan: object, official: object, *, floor: float = FLOOR_FRACTION) -> dict:
    """How closely an 8-bit scan reproduces the official one, row by row (issue 33's criteria).

    Parameters
    ----------
    scan, official : array_like or xarray.DataArray
        uint8 scans ``(depth, x)`` of the same shape (levels are the log image, 51/256 dB each).
    floor : float
        Rows where more than this fraction of the official scan's pixels are 0 (clipped at
        the window's bottom) are below the floor and left out.

    Returns
    -------
    dict
        ``correlation``: Pearson correlation of the two log images over the rows above the
        floor, each row normalised to zero mean and unit variance (pooled over those rows);
        ``row_mean_error``: largest ``|mean_x(scan) - mean_x(official)|`` over those rows, dB;
        ``rows``: their number.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.random.default_rng(0).integers(1, 256, (4, 8)).astype(np.uint8)
    >>> round(scan_agreement(a, a)["correlation"], 12)
    1.0
    """
    a = np.asarray(getattr(scan, "values", scan), dtype=np.float64)
    b = np.asarray(getattr(official, "values", official), dtype=np.float64)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"scans must be 2-D of the same shape, got {a.shape} and {b.shape}")
    rows = np.mean(b == 0, axis=1) <= floor
    a, b = a[rows], b[rows]
    step = _scan.DYNAMIC_RANGE / _scan.LEVELS
    error = np.abs(a.mean(axis=1) - b.mean(axis=1)) * step
    za = (a - a.mean(axis=1, keepdims=True)) / a.std(axis=1, keepdims=True)
    zb = (b - b.mean(axis=1, keepdims=True)) / b.std(axis=1, keepdims=True)
    return {
        "correlation": float(np.mean(za * zb)) if rows.any() else float("nan"),
        "row_mean_error": float(error.max(initial=0.0)) if rows.any() else float("nan"),
        "rows": int(rows.sum()),
    }


def _label(values: np.ndarray, cfg: ScannerConfig, field: bool):
    """(bscan, depth, x) values as a DataArray ``(depth, x)``, or ``(y, depth, x)``."""
    import xarray as xr

    from ..conventions import attrs, coord, grid_attrs

    coords = {
        "depth": coord("depth", np.arange(cfg.n_pixels) * cfg.pixel_size),
        "x": coord("x", cfg.line_positions),
    }
    if field:
        name, attributes = "field", attrs("field", "complex field A of the SynthOCT scanner")
    else:
        name, attributes = "scan", attrs("dimensionless", "8-bit logarithmic OCT scan (51 dB)")
    attributes = {**attributes, **grid_attrs(cfg.n_pixels, cfg.depth_range, cfg.k0)}
    if values.shape[0] == 1:
        return xr.DataArray(values[0], dims=("depth", "x"), coords=coords, name=name,
                            attrs=attributes)  # fmt: skip
    coords["y"] = coord("y", cfg.bscan_positions, "B-scan position y")
    return xr.DataArray(values, dims=("y", "depth", "x"), coords=coords, name=name,
                        attrs=attributes)  # fmt: skip
