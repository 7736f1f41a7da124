"""Fit a layered digital phantom to a SynthOCT scan (issue 34): ``fit_phantom``.

The scanner (:mod:`speckle.synthoct._scan`) shadows each A-line by ``C_i(z) = sum_{l: z_l < z}
(E_l/100) W_il^2`` with the double-pass weight ``W = exp(-(dx^2 + y^2)/r^2)``. For scatterers of
density ``rho`` (per µm^3) in a slab ``|y| <= r`` (the baseline's box, and the one
:meth:`PhantomFit.phantom` draws), the mean over lines grows with depth at

    dC/dz = rho (E/100) int W^2 dx dy = rho (E/100) (pi r^2/2) erf(sqrt 2)    (one-way, 1/µm),

the issue's ``rho E pi r^2/2`` times ``erf(sqrt 2) = 0.9545`` (the slab's cut of the beam).
``ln |A|^2`` averaged over the lines of a row is linear in ``C``, so the row-mean log profile of a
layer falls exactly as ``-2 mu z`` (no Jensen bias); the line-to-line spread of ``C_i`` adds
``4 var C = 4 mu (E/100) q z`` to ``var ln I`` (``q = erf(2)/(2 erf(sqrt 2))``, the ``W^4``
over ``W^2`` integrals).

The fit, on the central lines (``|x| <= x_max/2 - 3 r``, where the box does not cut the beam):

1. each pixel's ``ln I`` relative to the window's top from its 8-bit level (bin midpoints;
   a clipped pixel, level 0, gets ``ln c - 1``, the mean of ``ln I`` below the clip ``c`` of any
   intensity density flat near 0); rows with more than :data:`MAX_CLIPPED` of their pixels
   clipped are below the floor and left out unless their mean intensity puts the clip where
   fully developed speckle would clip at most :data:`SPARSE_CLIPPED` (the clipped pixels are
   then a sparse layer's empty ones: :func:`_above_floor`), as are the first and last ``GAP + 1``
   rows (the surface's transition, seen at the bottom through the periodic PSF); below a
   floor region, only runs of at least :data:`RUN_ROWS` rows above the floor are fitted (a
   faint layer's bottom may reach the floor above a brighter layer); a floor gap entered by
   the PSF's step is a layer under the floor, fitted from its censored pixels
   (:mod:`speckle.studies.phantom._floor`);
2. the row-mean profile is cut into ``K = 1 .. max_layers`` linear segments of slope <= 0 (a
   layer's mean ln I falls with depth), each boundary leaving out :data:`GAP` transition rows
   (the PSF's main lobe), by dynamic programming; ``K``
   is the one of least BIC, ``sum_q (residual_q/s_q)^2 + (3K - 1) ln n`` (weighted least
   squares), ``s_q^2`` the row means' variance from lateral blocks of lines about their
   quadratic trend across the lines (a shaped boundary's shift is not noise; a running median
   of 9 rows, times the integrated autocorrelation of 8 lags: ``_count.bic_row_variance``);
   fewer layers are taken while a boundary separates layers whose slopes and levels at the
   boundary both agree within 3 jackknife SEs (a fluctuation of the phantom's shadowing);
   with ``criterion="test"``, ``K`` is chosen instead by tests of ``K + 1`` against ``K``
   layers at a stated false-layer rate of 5 % (the best split's improvement against its
   exact null, the sign-flip randomisation over independent lateral blocks:
   :mod:`speckle.studies.phantom._count`);
3. per layer: ``mu`` from the slope (over a sparse layer's censored-slope gain: ``_censoring``),
   each boundary to a fraction of a pixel from the transition rows
   (the Hann PSF's intensity weights of the two layers' scatterers, each layer's exponential decay
   under the PSF included, its mean intensity from its mean ``ln I`` and the ``E ln(I/<I>)`` of its
   ``var ln I``, or of its intensity kurtosis where the floor leaves no rows for ``var ln I``:
   ``_shapes.TransitionModel``), ``var ln I`` (minus the shadowing spread, over rows whose predicted
   clipped fraction is at most 1 %, fully developed speckle's for the transitions, the layer's own
   rate of clipped pixels for the density; corrected for the lines' correlation) inverted to the
   density by the slab's exact sparse-speckle theory (its amplitudes ``exp(-y^2/r^2)``), identified
   where its excess over ``pi^2/6`` exceeds 5 SE (else a lower bound), the energy
   ``E = 100 mu/(rho A2)``, and the window's top from the layers' mean levels
   (:mod:`speckle.studies.phantom._density`); a layer without a significant slope takes ``rho E``
   from its rows' mean intensity under that window; a top layer cut by the floor (its only fitted
   rows a few in the next boundary's transition) takes ``rho E`` from the mean intensity of its own
   rows instead (:func:`_cut_top`);
4. standard errors: delete-one-block jackknife over :data:`BLOCKS` lateral blocks of lines
   (the line-to-line correlations of speckle and shadowing included), the segmentation fixed;
   ``var ln I`` and the density over blocks of 8 beam radii when there are more of them.

Tilted and curved boundaries: :mod:`speckle.studies.phantom._shapes`. Inclusions (with
``inclusions=True``, after the layers): :mod:`speckle.studies.phantom._inclusions`.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import os

import numpy as np
import xarray as xr
from scipy import optimize

from ...conventions import attrs, coord, units_of
from ...synthoct.files import ScannerConfig, read_png, read_scanner_config, write_scanner_config
from ._censoring import slope_gains
from ._count import CRITERION, bic_row_variance, count_blocks, layer_count, segment
from ._density import (
    BLOCKS,
    LAG,
    SIGNIFICANCE,
    _jackknife,
    _psf_area,
    both_rule_variances,
    clip_rates,
    kurtosis_density,
    layer_densities,
    lines_per_block,
    log_offset_se,
    log_offsets,
)
from ._floor import (
    _NEPER_DB,
    MAX_CLIPPED,
    _above_floor,
    _intensity,
    _log_intensity,
    dark_gaps,
    floor_layers,
    with_floor_layers,
)
from ._inclusions import fit_inclusions, no_inclusions, remove_inclusions, untouched_lines
from ._mixing import mixed_rows
from ._shapes import SHAPE_DEGREE, _transition_model, fit_shapes, flat_shapes
from ._slab import slab_constants
from ._window import window_and_brightness
from .patients import patient_table, region_volumes

__all__ = ["BLOCKS", "GAP", "MAX_CLIPPED", "PhantomFit", "fit_phantom"]

#: Width (beam radii) of the lateral blocks of a layer's kurtosis jackknife (the speckle and
#: the shadowing streaks are correlated over about a beam radius).
KURTOSIS_BLOCK_RADII = 2.0
#: Transition rows left out at each boundary (the Hann PSF's main lobe).
GAP = 2
#: Shortest layer, rows (fitted rows of a segment).
MIN_ROWS = 4
#: Shortest run of rows above the floor that is fitted below a floor region.
RUN_ROWS = MIN_ROWS + 2 * GAP

# --- input ------------------------------------------------------------------------------


def _config(config: object) -> ScannerConfig:
    if isinstance(config, ScannerConfig):
        return config
    if isinstance(config, (str, os.PathLike)):
        return read_scanner_config(config)
    raise TypeError(f"config must be a ScannerConfig or an INI path, got {type(config).__name__}")


def _levels(scan: object, cfg: ScannerConfig) -> np.ndarray:
    if isinstance(scan, (str, os.PathLike)):
        levels = read_png(scan)
    elif isinstance(scan, (xr.DataArray, np.ndarray)):
        if isinstance(scan, xr.DataArray):
            if scan.ndim == 2 and set(scan.dims) == {"depth", "x"}:
                scan = scan.transpose("depth", "x")
            scan = scan.values
        if scan.dtype != np.uint8:
            raise TypeError(f"scan must be uint8 (the official 8-bit levels), got {scan.dtype}")
        levels = scan
    else:
        raise TypeError(
            f"scan must be a PNG path, a uint8 array or a DataArray, got {type(scan).__name__}"
        )
    if cfg.n_bscans != 1:
        raise ValueError(f"config's n_bscans must be 1 (one B-scan is fitted), got {cfg.n_bscans}")
    if levels.shape != (cfg.n_pixels, cfg.n_lines):
        raise ValueError(
            f"scan has shape {levels.shape} (depth, x), config expects "
            f"({cfg.n_pixels}, {cfg.n_lines}) (n_pixels, n_lines)"
        )
    saturated = float(np.mean(levels == 255))
    if saturated > 0.01:
        raise ValueError(
            f"scan is saturated: {saturated:.1%} of its pixels at 255 (the scanner's window puts "
            "only its maximum there; at most 1 % allowed)"
        )
    if levels.max() == 0 or levels.min() == levels.max():
        raise ValueError("scan is empty (every pixel at one level): nothing to fit")
    return levels


# --- the fit ----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class PhantomFit:
    """A layered phantom fitted to a SynthOCT scan (:func:`fit_phantom`).

    Attributes
    ----------
    layers : xarray.Dataset
        Dim ``layer`` (0 at the top): ``top`` (µm), ``attenuation`` (one-way amplitude
        attenuation ``mu``, 1/µm), ``density`` (scatterers per µm^3, in the slab ``|y| <= r``),
        ``energy`` (%), ``rho_e`` (``rho E/100``, per µm^3, what the scan identifies at high
        density), each with ``*_se`` (``density_se``: half the way to the density of ``var ln I``
        2 SE lower, as ``density`` falls convexly with it); ``density_bound`` (lower bound where
        ``density`` is NaN: from ``var ln I``, or where the layer has no rows whose predicted
        clipped fraction is at most 1 % from its intensity kurtosis; NaN where neither gives
        one) and ``energy_bound`` (the upper bound it gives), ``kurtosis`` (the intensity's
        excess kurtosis ``1/(rho V)`` with its SE, where the layer has no ``var ln I``: the
        bound's source, ``V`` :func:`~speckle.studies.phantom._density.kurtosis_volume`),
        ``log_variance`` (``var ln I``, shadowing spread removed, over the rows whose predicted
        clipped fraction at the layer's own rate of clipped pixels is at most 1 %; NaN where
        none) with its SE, ``log_offset`` (``E ln(I/<I>)`` of the layer's sparse speckle, which
        the boundaries' transitions use: from ``var ln I`` over the rows of fully developed
        speckle's rate, or from the intensity kurtosis where the floor leaves no rows for it,
        ``-gamma`` where neither shows sparse speckle); ``floor`` (a layer under the window's
        floor: ``rho_e`` from its clipped and unclipped pixels, no density,
        :mod:`~speckle.studies.phantom._floor`) and ``rho_e_bound`` (its upper bound where its
        ``rho_e`` is not identified, else NaN). Attributes: ``window_top`` (dB re
        ``|A| = 1``, the 51 dB window's top) and ``window_top_se``, ``criterion``, ``bic``
        (per ``K``), ``p_values`` (``criterion="test"``: of the tests of ``K + 1`` against
        ``K`` layers made, from ``K = 1``), ``rows``.
    config : ScannerConfig
        The scanner's configuration.
    inclusions : xarray.Dataset
        Dim ``inclusion`` (0 or more, :mod:`speckle.studies.phantom._inclusions`): ``centre_x``,
        ``centre_z``, ``axis_x``, ``axis_z`` (µm), ``rho_e`` (from the level step) and
        ``rho_e_shadow`` (from the shadow below), ``log_contrast``, ``shadow_step`` (1/µm),
        ``density``, ``energy`` (NaN: not identified), each with ``*_se``; ``host`` (layer),
        ``significance``.

    Examples
    --------
    >>> from importlib import resources
    >>> import speckle
    >>> scan = resources.files("speckle.data") / "synthoct" / "Scan_Exp2_Layers_A.png"
    >>> fit = speckle.fit_phantom(scan, speckle.ScannerConfig())  # the challenge's default scanner
    >>> fit.layers.sizes["layer"], fit.layers.top.values.round(1)  # boundary near 400 µm
    (2, array([  0. , 399.9]))
    """

    layers: xr.Dataset
    config: ScannerConfig
    inclusions: xr.Dataset = dataclasses.field(default_factory=no_inclusions, kw_only=True)

    def layer_table(self) -> list[tuple[float, float, float, int]]:
        """``(top, bottom, rho_e, count)`` per layer as :meth:`phantom` draws it."""
        cfg = self.config
        h = cfg.depth_range
        tops = np.asarray(self.layers.top.values, float)
        bottoms = np.append(tops[1:], h)
        thick = bottoms - tops
        slab = cfg.x_max * 2 * cfg.beam_radius
        uniform = cfg.n_scatterers / (slab * h)
        dens = np.asarray(self.layers.density.values, float)
        bound = np.asarray(self.layers.density_bound.values, float)
        rho = np.where(np.isfinite(dens) & (dens > 0), dens, np.fmax(bound, uniform))
        share = rho * thick / np.sum(rho * thick) * cfg.n_scatterers
        counts = np.floor(share).astype(int)
        rest = cfg.n_scatterers - counts.sum()
        counts[np.argsort(counts - share)[:rest]] += 1  # largest remainders
        rho_e = np.asarray(self.layers.rho_e.values, float)
        return [(tops[k], bottoms[k], rho_e[k], int(counts[k])) for k in range(tops.size)]

    def phantom(self, seed: int) -> np.ndarray:
        """The four-column phantom ``(n_scatterers, 4)``: X, Y, Z (µm), Energy (%).

        Scatterers uniform in ``|x| <= x_max/2``, ``|y| <= r`` and each layer's depths, counts
        in proportion to the layers' densities (their lower bound, or the config's mean density
        if larger, where unidentified), scaled to ``n_scatterers``; energy ``100 rho_e/rho``.
        With a tilted or curved boundary the layers follow the fitted profiles
        (:func:`speckle.studies.phantom.patients.patient_table`: multinomial counts in the
        exact volumes).
        """
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        cfg = self.config
        rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
        layers = self.layers
        if self.inclusions.sizes["inclusion"]:
            return self._shaped_phantom(rng)
        if "top_tilt" in layers and np.any(
            (layers.top_tilt.values != 0) | (layers.top_curvature.values != 0)
        ):
            return self._shaped_phantom(rng)
        parts = []
        for top, bottom, rho_e, count in self.layer_table():
            rho = count / ((bottom - top) * cfg.x_max * 2 * cfg.beam_radius)
            energy = float(np.clip(100 * rho_e / rho, 1e-12, 100.0)) if count else 0.0
            parts.append(
                np.column_stack([
                    rng.uniform(-0.5, 0.5, count) * cfg.x_max,
                    rng.uniform(-1, 1, count) * cfg.beam_radius,
                    rng.uniform(top, bottom, count),
                    np.full(count, energy),
                ])
            )  # fmt: skip
        return np.concatenate(parts)

    def _shaped_phantom(self, rng: np.random.Generator) -> np.ndarray:
        """Tilted or curved boundaries, or an inclusion: the layers' densities (as
        :meth:`layer_table` takes them) scaled to ``n_scatterers`` in the exact volumes,
        energies ``100 rho_e/rho``; every fitted inclusion at its own density where
        identified (else its host's) and its level step's ``rho_e``."""
        cfg, layers = self.config, self.layers
        coefficients = np.column_stack(
            [layers.top.values, layers.top_tilt.values, layers.top_curvature.values]
        )[1:]
        uniform = cfg.n_scatterers / (cfg.x_max * 2 * cfg.beam_radius * cfg.depth_range)
        dens = np.asarray(layers.density.values, float)
        bound = np.asarray(layers.density_bound.values, float)
        rho = np.where(np.isfinite(dens) & (dens > 0), dens, np.fmax(bound, uniform))
        rho_e = np.asarray(layers.rho_e.values, float)
        inc = self.inclusions
        inclusion = [
            tuple(float(inc[v][j]) for v in ("centre_x", "centre_z", "axis_x", "axis_z"))
            for j in range(inc.sizes["inclusion"])
        ]
        own = np.asarray(inc.density.values, float)
        rho = np.append(rho, np.where(np.isfinite(own) & (own > 0), own,
                                      rho[inc.host.values.astype(int)]))  # fmt: skip
        rho_e = np.append(rho_e, np.asarray(inc.rho_e.values, float))
        volume, _ = region_volumes(cfg, coefficients, inclusion)
        scaled = rho * cfg.n_scatterers / np.sum(rho * volume)
        energy = np.clip(100 * rho_e / scaled, 1e-12, 100.0)
        table, _ = patient_table(cfg, coefficients, rho, energy, inclusion, rng)
        return table

    def write(self, path: str | os.PathLike, seed: int) -> None:
        """Write :meth:`phantom` as the official text file and the INI beside it
        (``Configuration.ini``)."""
        from ...synthoct.files import write_phantom

        table = self.phantom(seed)
        write_phantom(table, path)
        write_scanner_config(self.config, os.path.join(os.path.dirname(path) or ".",
                                                       "Configuration.ini"))  # fmt: skip

    def render(self, seed: int, **options):
        """:meth:`phantom` scanned by :func:`speckle.synthoct_scan` (``options`` passed on)."""
        from ...synthoct.scanner import synthoct_scan

        return synthoct_scan(self.phantom(seed), self.config, **options)


def fit_phantom(
    scan: object,
    config: object,
    *,
    max_layers: int = 5,
    blocks: int = BLOCKS,
    shapes: tuple[str, ...] = ("flat", "tilted", "curved"),
    inclusions: bool = False,
    criterion: str = "bic",
) -> PhantomFit:
    """Fit flat layers (depth, attenuation, density, energy) to a SynthOCT scan.

    Parameters
    ----------
    scan : str, path-like, numpy.ndarray or xarray.DataArray
        The official 8-bit scan ``(depth, x)``: a PNG file, a uint8 array or
        :func:`speckle.read_scan`'s DataArray; or a measured image
        (:func:`speckle.load_image`) with its :func:`speckle.equivalent_system` as ``config``.
    config : ScannerConfig, path or EquivalentSystem
        The scanner's configuration or its INI file (refused as
        :func:`speckle.read_scanner_config` refuses it); an :class:`EquivalentSystem` maps a
        measured image's rows into its 51 dB window first.
    max_layers : int
        Most layers tried (1..10); the number is chosen by BIC (module docstring).
    blocks : int
        Lateral blocks of lines of the jackknife (4..64).
    shapes : tuple of {"flat", "tilted", "curved"}
        Boundary shapes the fit may choose (by BIC, :mod:`speckle.studies.phantom._shapes`);
        ``("flat",)`` fits flat layers only.
    inclusions : bool
        Detect and fit elliptical inclusions after the layers
        (:mod:`speckle.studies.phantom._inclusions`: a stated false-alarm probability of
        0.05 per scan), then the layers again without them (a refit with more layers kept
        where the lines the inclusions do not reach show as many); False (the default): none.
    criterion : {"bic", "test"}
        How the number of layers is chosen: ``"bic"`` (the default), least BIC of the row-mean
        profile's segmentation, then fewer layers while a boundary's slope and level steps are
        both within 3 SEs (its false-layer rate measured, not derived); ``"test"``, tests of
        ``K + 1`` against ``K`` layers at a stated false-layer rate of 5 % per scan
        (:mod:`speckle.studies.phantom._count`: the exact sign-flip null over independent
        lateral blocks), which needs 6 blocks of 2 beam radii in the central lines.

    Returns
    -------
    PhantomFit
        ``.layers`` (Dataset, dim ``layer``), ``.phantom(seed)``, ``.write(path, seed)``,
        ``.render(seed)``.

    Raises
    ------
    TypeError, ValueError
        A scan whose shape disagrees with the config, a saturated or empty scan, too few rows
        above the floor or central lines, a bad INI or option; before any fitting.

    Examples
    --------
    >>> import speckle
    >>> from importlib.resources import files
    >>> fit = speckle.fit_phantom(files("speckle.data") / "synthoct" / "Scan_Exp2_Layers_A.png",
    ...                           speckle.ScannerConfig())
    >>> fit.layers.sizes["layer"], round(float(fit.layers.top[1]))
    (2, 400)
    """
    if hasattr(config, "scan_levels"):  # a measured image with its equivalent system (real.py)
        scan, config = config.scan_levels(scan).values, config.config
    cfg = _config(config)
    if isinstance(max_layers, bool) or not isinstance(max_layers, int) or not 1 <= max_layers <= 10:
        raise ValueError(f"max_layers must be an integer in 1..10, got {max_layers!r}")
    if isinstance(blocks, bool) or not isinstance(blocks, int) or not 4 <= blocks <= 64:
        raise ValueError(f"blocks must be an integer in 4..64, got {blocks!r}")
    if (
        not isinstance(shapes, tuple | list)
        or "flat" not in shapes
        or any(s not in SHAPE_DEGREE for s in shapes)
    ):
        raise ValueError(
            f"shapes must be a tuple of {tuple(SHAPE_DEGREE)} holding 'flat', got {shapes!r}"
        )
    if not isinstance(inclusions, bool):
        raise TypeError(f"inclusions must be a bool, got {inclusions!r}")
    if criterion not in ("bic", "test"):
        raise ValueError(f"criterion must be 'bic' or 'test', got {criterion!r}")
    levels = _levels(scan, cfg)
    r = cfg.beam_radius
    central = np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * r
    if central.sum() < 2 * blocks:
        raise ValueError(
            f"scan has {int(central.sum())} lines farther than 3 beam radii from the box's "
            f"edges; the fit needs at least {2 * blocks} (2 per jackknife block)"
        )
    if criterion == "test":  # refuses too few blocks for the layer count's test
        count_blocks(cfg.line_positions[central], r)
    lev = levels[:, central]

    def layers_of(lev):
        ds = _fit_levels(lev, cfg, max_layers, blocks, criterion)
        if len(shapes) > 1 and ds.sizes["layer"] > 1 and not ds.floor.any():  # floor: flat
            return fit_shapes(
                lev, _log_intensity(lev), ds, cfg, tuple(shapes),
                lambda lv: _fit_levels(lv, cfg, max_layers, blocks, criterion),
            )  # fmt: skip
        return flat_shapes(ds)

    ds = layers_of(lev)
    if not inclusions:
        return PhantomFit(layers=ds, config=cfg)
    # inclusions in the residual against the layers; with some found, the layers are fitted
    # again to the levels without the inclusions' model (their level step and shadow bias
    # the hosts' row means and slopes), and the inclusions again against those layers
    ok = _above_floor(lev)
    ok[: GAP + 1] = False
    ok[cfg.n_pixels - GAP - 1 :] = False
    li, x, cdf = (
        _log_intensity(lev),
        cfg.line_positions[central],
        _transition_model(cfg.n_pixels).cdf,
    )
    found, model = fit_inclusions(li, np.flatnonzero(ok), ds, cfg, x, cdf)
    if found.sizes["inclusion"]:
        again = layers_of(remove_inclusions(lev, model, _NEPER_DB))
        # a refit with more layers may be the removal's artefact (a shadow that clipped the
        # rows below it cannot be undone): kept where the lines the inclusions do not reach,
        # fitted flat (BIC), show as many layers (an inclusion hid a boundary from the first)
        far = untouched_lines(x, found, r)
        k_far = 0
        if again.sizes["layer"] > ds.sizes["layer"] and far.sum() >= 2 * blocks:
            try:
                k_far = _fit_levels(lev[:, far], cfg, max_layers, blocks).sizes["layer"]
            except ValueError:  # too few of their rows above the floor: no confirmation
                pass
        if again.sizes["layer"] <= max(ds.sizes["layer"], k_far):
            ds = again
            found, _ = fit_inclusions(li, np.flatnonzero(ok), ds, cfg, x, cdf)
    return PhantomFit(layers=ds, config=cfg, inclusions=found)


def _cut_top(lev, rows, segs, tops, keep, cfg) -> dict[str, np.ndarray] | None:
    """The top layer's own rows when the window's floor cut it, else None.

    Cut: the first fitted row lies below rows dropped at the floor (:func:`_above_floor`)
    and the top segment is shorter than :data:`RUN_ROWS` (a few rows at
    the layer's bottom, in the next boundary's transition). Its own rows are ``GAP + 1`` down
    to :data:`GAP` rows above the fitted boundary; their mean ``I/I_max`` over the lines
    (clipped pixels at half the clip level) and over each jackknife replicate's lines
    (``keep``) go to :func:`~speckle.studies.phantom._window.cut_top_rho_e`.
    """
    a, b = segs[0]
    if len(segs) < 2 or rows[a] <= GAP + 1 or b - a >= RUN_ROWS:
        return None
    p = cfg.pixel_size
    own = np.arange(GAP + 1, cfg.n_pixels)
    own = own[own * p < tops[1] - GAP * p]
    if own.size == 0:
        return None
    intensity = _intensity(lev[own])
    # E ln(I/<I>) of its rows as the row means see them (clipped pixels at ln c - 1)
    log_offset = np.mean(_log_intensity(lev[own]).mean(axis=1) - np.log(intensity.mean(axis=1)))
    return {
        "z": own * p,
        "log_offset": float(log_offset),
        "intensity": intensity.mean(axis=1),
        "intensity_jk": np.stack([intensity[:, k].mean(axis=1) for k in keep]),
    }


def _layer_kurtosis(intensity, segs, v, cfg) -> np.ndarray:
    """Each layer's intensity excess kurtosis, its SE and the density's lower bound it gives
    (:func:`kurtosis_density`, jackknife blocks of :data:`KURTOSIS_BLOCK_RADII` beam radii)
    where its ``var ln I`` is NaN (no rows that the floor leaves whole), else NaN: ``(3, K)``."""
    out = np.full((3, len(segs)), np.nan)
    block = lines_per_block(KURTOSIS_BLOCK_RADII, cfg)
    for k, (a, b) in enumerate(segs):
        if not np.isfinite(v[k]) and b - a >= LAG + 2:
            out[:, k] = kurtosis_density(intensity[a:b], cfg, block_lines=block)
    return out


def _fit_levels(
    lev: np.ndarray, cfg: ScannerConfig, max_layers: int, blocks: int, criterion: str = "bic"
) -> xr.Dataset:
    """The flat-layer fit of the central lines' levels ``lev`` (pixels, lines); ``criterion``
    of the number of layers as :func:`fit_phantom` takes it."""
    p = cfg.pixel_size
    # rows above the floor, in runs of at least RUN_ROWS (a dim layer's bottom may reach the
    # floor above a bright layer); the first and last GAP + 1 rows are left out (the last
    # see the top through the periodic PSF)
    ok = _above_floor(lev)
    ok[: GAP + 1] = False
    ok[cfg.n_pixels - GAP - 1 :] = False
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    runs = [(a, b) for a, b in zip(edges[::2], edges[1::2], strict=True)
            if b - a >= RUN_ROWS or a == GAP + 1]  # fmt: skip
    li_all = _log_intensity(lev)
    m_all = li_all.mean(axis=1)  # every row's mean ln I (the floor gaps' steps)
    # boundaries into layers under the floor (_floor.py): their transition rows left out, the
    # segmentation cut there (when max_layers allows the layers)
    dark = dark_gaps(m_all, runs, cfg.n_pixels, gap=GAP)
    n_cut = sum(hi < cfg.n_pixels - GAP - 1 for _, hi in dark)
    if len(dark) + n_cut + 1 > max_layers:
        dark = []
    starts, ends = {hi for _, hi in dark}, {lo for lo, _ in dark}

    def trim(a, b):  # a thin layer between floor layers keeps its transitions
        a2, b2 = a + GAP * (a in starts), b - GAP * (b in ends)
        return (a2, b2) if b2 - a2 >= MIN_ROWS else (a, b)

    trimmed = [trim(a, b) for a, b in runs]
    rows = np.concatenate([np.arange(a, b) for a, b in trimmed] or [np.arange(0)])
    cuts = tuple(int(np.searchsorted(rows, t[0]))
                 for r, t in zip(runs, trimmed, strict=True) if r[0] in starts)  # fmt: skip
    if rows.size < MIN_ROWS + 1:
        raise ValueError(
            f"scan has {rows.size} rows above the floor (<= {MAX_CLIPPED:.0%} clipped); "
            f"the fit needs at least {MIN_ROWS + 1}"
        )
    li = li_all[rows]  # (rows, lines)
    z = rows * p
    group = np.array_split(np.arange(li.shape[1]), blocks)
    keep = [np.setdiff1d(np.arange(li.shape[1]), g) for g in group]
    m = li.mean(axis=1)
    m_jk = np.stack([li[:, k].mean(axis=1) for k in keep])  # (blocks, rows)
    intensity = _intensity(lev[rows])
    i_rows, i_rows_jk = intensity.mean(axis=1), np.stack([intensity[:, k].mean(axis=1)
                                                          for k in keep])  # fmt: skip
    s2_rows = bic_row_variance(li, group)
    best = segment(z, m, 1.0 / s2_rows, max_layers - len(dark), gap=GAP, min_rows=MIN_ROWS,
                   cuts=cuts)  # fmt: skip
    bic = {k: rss + (3 * k - 1) * math.log(z.size) for k, (rss, _) in best.items()}

    def line_fit(mm, a, b):
        slope, icpt = np.polyfit(z[a:b], mm[a:b], 1)
        return slope, icpt

    def distinct(segs):
        """Every boundary separates layers whose slopes or levels at the boundary differ by
        more than SIGNIFICANCE jackknife SEs (else a fluctuation of the phantom's shadowing)."""
        for (a1, b1), (a2, b2) in itertools.pairwise(segs):
            if any(b1 <= c <= a2 for c in cuts):  # a floor layer between them
                continue
            zb = 0.5 * (z[b1 - 1] + z[a2])
            stats = []
            for mm in (m, *m_jk):
                (s1, i1), (s2_, i2) = line_fit(mm, a1, b1), line_fit(mm, a2, b2)
                stats.append((s2_ - s1, (s2_ - s1) * zb + i2 - i1))
            stats = np.array(stats)
            se = [_jackknife(stats[1:, c]) for c in (0, 1)]
            if all(abs(stats[0, c]) <= SIGNIFICANCE * se[c] for c in (0, 1)):
                return False
        return True

    p_values = []
    if criterion == "test":  # K + 1 against K at a stated false-layer rate (_count.py)
        x = cfg.line_positions[np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * cfg.beam_radius]
        clip = float(_log_intensity(np.zeros(1, np.uint8))[0]) + 1.0  # ln of the window's floor
        n_layers, p_values = layer_count(z, li, x, cfg.beam_radius, best, gap=GAP, clip=clip,
                                         min_rows=MIN_ROWS, start=len(cuts) + 1)  # fmt: skip
    else:
        n_layers = min(bic, key=bic.get)
        while n_layers > len(cuts) + 1 and not distinct(best[n_layers][1]):
            n_layers -= 1
    segs = best[n_layers][1]

    model = _transition_model(cfg.n_pixels)
    mixing = mixed_rows(cfg)  # the mixed rows' own speckle (_mixing.py)
    # var ln I per layer first: its E ln(I/<I>) sets the transition's mixed intensity
    # (the rows the fully developed clip allows: their E ln(I/<I>), censored as the transitions'
    # row means); the density's from the rows above the floor at each layer's own clipped rate
    rates = clip_rates(li, z, segs)  # each layer's rate of clipped pixels
    v, v_jk, mu_fine, v_own, v_own_jk = both_rule_variances(li, z, segs, keep, cfg, rates)
    kappa, kappa_se, kappa_bound = _layer_kurtosis(intensity, segs, v_own, cfg)
    offsets = log_offsets(v, cfg, kurtosis=kappa)

    def tops_of(mm, fits, first=None):
        """The boundaries; ``first``: the first row of boundary 1's window (a cut top layer's
        fitted rows are the transition's), else the row above its gap."""
        out = [0.0]
        for k in range(1, len(segs)):
            (s1, i1), (s2_, i2) = fits[k - 1], fits[k]
            lo, hi = segs[k - 1][1], segs[k][0]  # gap rows lo .. hi-1
            if any(lo <= c <= hi for c in cuts):  # a floor layer's (_floor.py)
                out.append(math.nan)
                continue
            idx = np.arange(lo - 1 if first is None or k > 1 else first, hi + 1)
            zz = z[idx]

            def misfit(t, zz=zz, idx=idx, s1=s1, i1=i1, s2_=s2_, i2=i2, c=offsets[k - 1 : k + 1]):
                # the PSF's share of each layer's mean intensity
                pred = model.log_mean(zz, t, s1, i1, s2_, i2, p, c, mixing)
                return float(np.sum((pred - mm[idx]) ** 2))

            res = optimize.minimize_scalar(
                misfit, bounds=(z[idx[0]] - p, z[hi] + p), method="bounded",
                options={"xatol": 1e-3},
            )  # fmt: skip
            out.append(float(res.x))
        return out

    def estimates(mm):
        fits = [line_fit(mm, a, b) for a, b in segs]
        return fits, tops_of(mm, fits)

    fits, tops = estimates(m)
    rep = [estimates(m_jk[j]) for j in range(blocks)]
    gain = slope_gains(lev[rows], segs, rates)  # the censored row means' slope over -2 mu
    cut = None if dark else _cut_top(lev, rows, segs, tops, keep, cfg)  # not with a floor layer
    if cut is not None:
        gain[0] = 1.0  # its line is its brightness's (below)
    mu = np.array([-f[0] / 2 for f in fits]) / gain
    mu_jk = np.array([[-f[0] / 2 for f in fr] for fr, _ in rep]) / gain
    mu_se = np.array([_jackknife(mu_jk[:, k]) for k in range(n_layers)])
    tops = np.array(tops)
    tops_jk = np.array([t for _, t in rep])
    top_se = np.array([_jackknife(tops_jk[:, k]) for k in range(n_layers)])

    # density, energy, the window and rho E/100: _density.py
    dens = layer_densities(v_own, v_own_jk, mu, mu_fine / gain, cfg, kurtosis_bound=kappa_bound)
    v_se = np.array([_jackknife(v_jk[:, k]) for k in range(n_layers)])
    offsets_se, is_floor = log_offset_se(v, v_se, cfg), np.zeros(n_layers, bool)
    segs_w, floor = segs, {}
    if dark:  # layers under the floor between (or below) the row layers: _floor.py
        m_all_jk = np.stack([li_all[:, k].mean(axis=1) for k in keep])
        fl = floor_layers(dark, segs, cuts, m_all, m_all_jk, _intensity(lev),
                          lev == 0, (fits, tops), rep, offsets, keep, model, p, gap=GAP,
                          cells=lev.shape[1] / lines_per_block(KURTOSIS_BLOCK_RADII, cfg),
                          mixing=mixing)  # fmt: skip
        ins, floor = functools.partial(with_floor_layers, after=fl["after"]), fl["floor"]
        mu, mu_jk, offsets_se = ins(mu, fill=0.0), ins(mu_jk, fill=0.0), ins(offsets_se, fill=0.0)
        mu_se, gain = ins(mu_se), ins(gain)
        offsets, is_floor = ins(offsets, fill=-np.euler_gamma), ins(is_floor, fill=True)
        v_own, kappa, kappa_se = ins(v_own), ins(kappa), ins(kappa_se)
        dens = {key: ins(val) for key, val in dens.items()}
        tops, tops_jk = fl["tops"], fl["tops_jk"]
        rows_of = iter(segs)
        n_layers, segs_w = tops.size, [None if f else next(rows_of) for f in is_floor]
        top_se = np.array([_jackknife(tops_jk[:, k]) for k in range(n_layers)])
    fitted = {
        "mu": mu, "mu_se": mu_se, "mu_jk": mu_jk, "tops": tops, "tops_jk": tops_jk,
        "offsets": offsets, "offsets_se": offsets_se, "floor": floor,
        "intensity": i_rows, "intensity_jk": i_rows_jk,
    }  # fmt: skip
    win = window_and_brightness(m, m_jk, z, segs_w, fitted, cfg, cut_top=cut)
    if floor and np.isfinite(win["wt"]):  # the floor layers' shadows from their brightness
        a2 = slab_constants(cfg.beam_radius)["A2"]
        for k in floor:
            mu[k], mu_se[k] = a2 * np.nan_to_num(win["rho_e"][k]), a2 * win["rho_e_se"][k]
            mu_jk[:, k] = mu[k]
        win = window_and_brightness(m, m_jk, z, segs_w, fitted, cfg, cut_top=cut)
    if cut is not None and np.isfinite(win["wt"]):
        # the cut top layer's line is its brightness's, not its few rows' (the transition's):
        # its boundary is located again over those rows too, then its brightness again
        consts = slab_constants(cfg.beam_radius)
        level = consts["a2_y"] * _psf_area(cfg)  # mean I per unit rho E/100, at the window top
        offsets = offsets.copy()
        offsets[0] = cut["log_offset"]  # the transition's; var ln I has no rows here

        def top_line(mu0, wt_):
            """Slope and intercept of the cut layer's mean ln I (the window's units)."""
            return -2 * mu0, math.log(mu0 / consts["A2"] * level) - wt_ + offsets[0]

        tops = np.array(tops_of(m, [top_line(win["mu"][0], win["wt"]), *fits[1:]], segs[0][0]))
        tops_jk = np.array([
            tops_of(m_jk[j], [top_line(win["mu_jk"][j, 0], win["wt_jk"][j]), *rep[j][0][1:]],
                    segs[0][0])
            for j in range(blocks)
        ])  # fmt: skip
        top_se = np.array([_jackknife(tops_jk[:, k]) for k in range(n_layers)])
        fitted.update(tops=tops, tops_jk=tops_jk)
        cut = _cut_top(lev, rows, segs, tops, keep, cfg)
        win = window_and_brightness(m, m_jk, z, segs, fitted, cfg, cut_top=cut)
    rho, rho_se, bound = dens["rho"], dens["rho_se"], dens["bound"]
    energy, energy_se, energy_bound = dens["energy"], dens["energy_se"], dens["energy_bound"]
    wt, wt_se, rho_e, rho_e_se = win["wt"], win["wt_se"], win["rho_e"], win["rho_e_se"]
    if cut is not None and np.isfinite(wt):
        # the top layer's mu from its brightness: its energy (and bound) with it
        mu, mu_se = win["mu"], win["mu_se"]
        energy_bound[0] = 100 * rho_e[0] / bound[0]
        energy[0] = 100 * rho_e[0] / rho[0]
        energy_se[0] = energy[0] * math.hypot(rho_e_se[0] / rho_e[0], rho_se[0] / rho[0])

    def var(name, values, quantity, long_name, extra=None):
        return ("layer",), np.asarray(values, float), attrs(quantity, long_name, **(extra or {}))

    ds = xr.Dataset(
        {
            "top": var("top", tops, "length", "upper boundary of the layer"),
            "top_se": var("top_se", top_se, "length", "standard error of top"),
            "attenuation": var("attenuation", mu, "attenuation",
                               "one-way amplitude attenuation mu (intensity decays as 2 mu)"),
            "attenuation_se": var("a", mu_se, "attenuation", "standard error of attenuation"),
            "density": var("d", rho, "volume_density", "scatterers per um^3 (slab |y| <= r)"),
            "density_se": var("d", rho_se, "volume_density", "standard error of density"),
            "density_bound": var("d", bound, "volume_density",
                                 "lower bound of the density where it is not identified "
                                 "(from var ln I, else from the intensity kurtosis)"),
            "energy": var("e", energy, "percent", "energy per scatterer"),
            "energy_se": var("e", energy_se, "percent", "standard error of energy"),
            "energy_bound": var("e", energy_bound, "percent",
                                "upper bound of the energy where the density is not identified"),
            "rho_e": var("re", rho_e, "volume_density", "rho E/100 (energy-weighted density)"),
            "rho_e_se": var("re", rho_e_se, "volume_density", "standard error of rho_e"),
            "rho_e_bound": var("re", win["rho_e_bound"], "volume_density",
                               "upper bound of rho_e where a floor layer's is not identified"),
            "floor": (("layer",), np.asarray(is_floor, bool),
                      attrs("label", "layer under the window's floor (rho_e from its clipped "
                            "pixels: _floor.py)")),
            "log_variance": var("v", v_own, "dimensionless",
                                "var ln I of the layer (shadowing spread removed)"),
            "log_variance_se": var("v", dens["v_se"], "dimensionless",
                                   "standard error of log_variance"),
            "log_slope_gain": var("g", gain, "dimensionless",
                                  "row-mean ln I slope over -2 attenuation (clipped pixels)"),
            "log_offset": var("c", offsets, "dimensionless",
                              "E ln(I/<I>) of the layer's speckle, as the transitions take it"),
            "kurtosis": var("k", kappa, "dimensionless",
                            "excess intensity kurtosis E I^2/(E I)^2 - 2 = 1/(rho V) (streaks "
                            "removed), where var ln I has no rows"),
            "kurtosis_se": var("k", kappa_se, "dimensionless", "standard error of kurtosis"),
        },
        coords={"layer": coord("layer", np.arange(n_layers))},
        attrs={
            "window_top": wt * _NEPER_DB,
            "window_top_se": wt_se * _NEPER_DB,
            "window_top_units": units_of("level"),
            "criterion": CRITERION if criterion == "test" else (
                "least BIC = sum (residual/s_q)^2 + (3K - 1) ln n of the row-mean ln I "
                "profile, fewer layers while a boundary's slope and level steps are both < 3 SE"
            ),
            "bic": [float(bic[k]) for k in sorted(bic)],
            "p_values": [float(v) for v in p_values],
            "rows": int(rows.size),
            "last_row": int(rows[-1]),
        },
    )  # fmt: skip
    return ds
