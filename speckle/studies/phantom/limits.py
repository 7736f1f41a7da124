"""Where the phantom fit fails (issue 34): the failure map over thickness and contrast.

:func:`phantom_failure_map` scans, for each thickness ``T`` and contrast ``q``, three flat layers
of one density (the config's mean): a top layer of energy ``E`` from the surface to ``top_depth``, a
middle layer of energy ``q E`` and thickness ``T``, and a bottom layer of energy ``E`` (so
``rho E``, the brightness and the slope ``2 mu``, differ by ``q`` across both boundaries); each
case is fitted by :func:`speckle.fit_phantom` and succeeds when it gives three layers with both
boundaries within a pixel on every fitted line. The map is the fraction of ``seeds`` that
succeed (with the fractions of the two criteria apart). A middle layer inside the depth PSF's
main lobe (1 pixel) is never resolved; a contrast too small for the BIC's penalty merges the
layers (1.5 merges at every thickness of the default map); a ``top_depth`` near the window's
floor leaves too few rows above the floor (measured in docs/explanation/phantom_fit.md).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ...conventions import attrs, coord
from ...synthoct.scanner import synthoct_scan
from ._fit import fit_phantom
from .loop import fit_profiles
from .patients import patient_table, scanner_config_of

__all__ = ["phantom_failure_map"]


def _grid(name: str, values: object, low: float, high: float) -> np.ndarray:
    raw = np.asarray(values) if not isinstance(values, str | bytes) else np.array([])
    if raw.dtype.kind not in "iuf" or raw.dtype == bool:
        raise TypeError(f"{name} must be a sequence of real numbers, got {values!r}")
    arr = raw.astype(float)
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"{name} must be a non-empty 1-D sequence of finite numbers, got {values!r}"
        )
    if np.any(arr <= low) or np.any(arr > high):
        raise ValueError(f"{name} must lie in ({low}, {high}], got {values!r}")
    return arr


def _median(values: np.ndarray) -> np.ndarray:
    """Median over the last axis of the finite values (NaN where there are none)."""
    out = np.full(values.shape[:-1], np.nan)
    for idx in np.ndindex(out.shape):
        v = values[idx][np.isfinite(values[idx])]
        if v.size:
            out[idx] = np.median(v)
    return out


def phantom_failure_map(
    *,
    config: object = "reduced",
    thickness: object = (4, 8, 16),
    contrast: object = (1.5, 2.5, 4.0),
    seeds: object = (0,),
    energy: float = 0.2,
    top_depth: float | None = None,
) -> xr.Dataset:
    """Fraction of cases fitted right (layer count, boundaries within a pixel) over thickness x
    contrast of a middle layer (module docstring).

    Parameters
    ----------
    config : str or ScannerConfig
        ``"reduced"`` (128 x 128 pixels of 6 µm, the CI size), ``"challenge"``, ``"2025"``
        or a configuration.
    thickness : sequence of float
        The middle layer's thicknesses, in pixels (> 0, at most a third of the depth).
    contrast : sequence of float
        Ratios ``q`` of the middle layer's ``rho E`` to its neighbours' (> 1, at most 100).
    seeds : sequence of int
        Seeds of the scatterers' draws (non-negative, distinct), one case each.
    energy : float
        Energy ``E`` (%) of the top and bottom layers (0 < E <= 100; the middle one has ``q E``,
        at most 100).
    top_depth : float, optional
        Depth of the middle layer's top, µm (default a quarter of the depth range; > 0, and
        the middle layer must end a third of the depth range above the bottom).

    Returns
    -------
    xarray.Dataset
        Dims ``thickness`` (µm) and ``energy_ratio``: ``success`` (fraction of the seeds with
        both criteria), ``count_right``, ``boundary_right`` (fractions), ``boundary_error``
        (median over the seeds of the largest boundary error, pixels), ``n_cases``.

    Raises
    ------
    TypeError, ValueError
        A bad config, grid, seed list, energy or top_depth, before any scan.

    Examples
    --------
    >>> import speckle
    >>> fm = speckle.phantom_failure_map(thickness=[1, 16], contrast=[4.0], seeds=[1])
    >>> fm.success.values.ravel().tolist()  # 1 pixel: inside the depth PSF's main lobe
    [0.0, 1.0]
    """
    cfg = scanner_config_of(config)
    h, p = cfg.depth_range, cfg.pixel_size
    thick = _grid("thickness", thickness, 0.0, cfg.n_pixels / 3) * p
    ratio = _grid("contrast", contrast, 1.0, 100.0)
    if isinstance(seeds, str | bytes) or not hasattr(seeds, "__len__") or len(seeds) == 0:
        raise ValueError(f"seeds must be a non-empty sequence of non-negative integers: {seeds!r}")
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, int | np.integer) or s < 0:
            raise ValueError(f"seeds must hold non-negative integers, got {s!r}")
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must be distinct, got {seeds!r}")
    if isinstance(energy, bool) or not isinstance(energy, int | float) or not 0 < energy <= 100:
        raise ValueError(f"energy must be a number in (0, 100] %, got {energy!r}")
    if energy * ratio.max() > 100:
        raise ValueError(
            f"energy x the largest contrast must be <= 100 %, got {energy} x {ratio.max()}"
        )
    top = h / 4 if top_depth is None else top_depth
    if isinstance(top, bool) or not isinstance(top, int | float) or not 0 < top:
        raise ValueError(f"top_depth must be a number > 0 µm, got {top_depth!r}")
    if top + thick.max() > 2 * h / 3:
        raise ValueError(
            f"top_depth + the largest thickness ({top + thick.max():.1f} µm) must be <= 2/3 of the "
            f"depth range ({2 * h / 3:.1f} µm)"
        )
    central = np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * cfg.beam_radius
    xs = cfg.line_positions[central]
    shape = (thick.size, ratio.size, len(seeds))
    count_ok = np.zeros(shape, bool)
    bound_ok = np.zeros(shape, bool)
    worst = np.full(shape, np.nan)
    for i, t in enumerate(thick):
        coefficients = np.array([[top, 0.0, 0.0], [top + t, 0.0, 0.0]])
        truth = np.array([top, top + t])
        for j, q in enumerate(ratio):
            energies = np.array([energy, q * energy, energy])
            for k, s in enumerate(seeds):
                rng = np.random.default_rng(np.random.SeedSequence([int(s), i, j]))
                table, _ = patient_table(cfg, coefficients, np.ones(3), energies, None, rng)
                fit = fit_phantom(synthoct_scan(table, cfg, nthreads=1), cfg)
                layers = fit.layers
                count_ok[i, j, k] = layers.sizes["layer"] == 3
                if count_ok[i, j, k]:
                    prof = fit_profiles(layers, xs, cfg.x_max)[1:]
                    worst[i, j, k] = np.max(np.abs(prof - truth[:, None])) / p
                    bound_ok[i, j, k] = worst[i, j, k] < 1.0

    def frac(values, long_name):
        return ("thickness", "energy_ratio"), values.mean(axis=2), attrs("probability", long_name)

    return xr.Dataset(
        {
            "success": frac(count_ok & bound_ok, "fraction with 3 layers, boundaries within 1 px"),
            "count_right": frac(count_ok, "fraction with the layer count right"),
            "boundary_right": frac(bound_ok, "fraction with both boundaries within a pixel"),
            "boundary_error": (("thickness", "energy_ratio"), _median(worst),
                               attrs("pixels", "median largest boundary error (NaN: none)")),
            "n_cases": ((), len(seeds), attrs("count", "cases per cell (seeds)")),
        },
        coords={
            "thickness": coord("thickness", thick),
            "energy_ratio": coord("energy_ratio", ratio),
        },
        attrs={"energy": float(energy), "top_depth": float(top), "seeds": [int(s) for s in seeds]},
    )  # fmt: skip
