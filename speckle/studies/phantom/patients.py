"""Virtual patients of the closed loop (issue 34): random layered phantoms with their truth.

A virtual patient is a SynthOCT phantom (the four-column table that
:func:`speckle.synthoct_scan` takes) of ``K`` layers under the surface ``z = 0``, each layer
``k >= 1`` starting at a boundary

    t_k(x) = a_k + b_k x + c_k (x^2 - X^2/12)        (µm, x the lateral position, X = x_max)

(``a_k`` the mean depth over the box; flat: ``b = c = 0``; tilted: ``c = 0``; curved: ``c != 0``,
``b`` free), and elliptical inclusions ``((x - x_c)/w)^2 + ((z - z_c)/h)^2 < 1`` (through the
whole slab ``|y| <= r``), each inside one layer, their bounding boxes apart by at least
:data:`INCLUSION_GAP` pixels (drawn again until they are; the first drawn as a patient of one
inclusion draws it, so ``inclusions=True`` and ``inclusions=1`` are the same patient). Each
region has a density ``rho`` (scatterers per µm^3, the slab ``|y| <= r`` of
:meth:`~speckle.studies.phantom.PhantomFit.phantom`) and an energy ``E`` (%); its one-way
attenuation is ``mu = rho (E/100) A2`` with ``A2 = (pi r^2/2) erf(sqrt 2)``
(:func:`~speckle.studies.phantom.slab_constants`).

Drawing (all from ``SeedSequence(seed)``): the number of layers uniform in ``layers``; each
boundary's shape from ``shapes``; relative densities log-uniform in ``density_range`` (times the
config's mean density ``n_scatterers/(x_max 2 r H)``, then scaled so that the expected count is
``n_scatterers``); energies log-uniform in ``energy_range``, redrawn until neighbouring regions'
``rho E`` differ by at least ``min_contrast`` (the brightness and slope steps the fit needs);
boundaries' mean depths uniform, tilts up to ``max_tilt`` and sags up to ``max_sag`` (depth
change over the box), redrawn until layers are at least ``min_thickness`` thick everywhere.
Then every energy is scaled down (by 0.8 at a time, ratios kept) until every layer's bottom sits
at least 1 neper of mean intensity above the floor of the 51 dB window (the mean level 7 neper
below the brightest region's top: the window's top is the image's maximum, about
``ln(n_pixels)`` above its mean; the fit drops rows of fully developed speckle with more than
10 % clipped pixels, ``ln(1/0.105) = 2.25`` neper above the clip): every boundary is visible.
The scatterers: a multinomial count per region (``rho V``, ``V`` its volume from the exact
profiles on 8192 lines), uniform in each region by rejection.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ...conventions import attrs, coord
from ...synthoct.configs import synthoct_config
from ...synthoct.files import ScannerConfig
from ._slab import slab_constants

__all__ = [
    "SHAPES",
    "patient_table",
    "profiles",
    "region_volumes",
    "scanner_config_of",
    "virtual_patient",
]

#: Boundary shapes of a virtual patient.
SHAPES = ("flat", "tilted", "curved")
#: Mean intensity (neper of ln I) below the brightest region's top where the window's floor
#: starts to clip more than 10 % of a row, minus a margin of 1 neper.
VISIBLE_NEPER = 6.0
#: Most inclusions of a virtual patient.
MAX_PATIENT_INCLUSIONS = 4
#: Least gap (pixels, in depth or laterally) between the bounding boxes of two inclusions.
INCLUSION_GAP = 2
_GRID = 8192


def scanner_config_of(config: object) -> ScannerConfig:
    if isinstance(config, ScannerConfig):
        return config
    if isinstance(config, str):
        return synthoct_config(config)
    raise TypeError(
        f"config must be a ScannerConfig or a name ('challenge', '2025'), got {config!r}"
    )


def _range(name: str, value: object, low: float, high: float, *, integer: bool = False):
    ok = isinstance(value, tuple | list) and len(value) == 2
    if ok:
        a, b = value
        kinds = (int, np.integer) if integer else (int, float, np.integer, np.floating)
        ok = all(isinstance(v, kinds) and not isinstance(v, bool) for v in (a, b))
        ok = ok and low <= a <= b <= high
    if not ok:
        kind = "integers" if integer else "numbers"
        raise ValueError(
            f"{name} must be a pair (low, high) of {kind} in {low}..{high}, got {value!r}"
        )
    return value


def profiles(coefficients: np.ndarray, x: np.ndarray, x_max: float) -> np.ndarray:
    """``t_k(x) = a + b x + c (x^2 - X^2/12)`` of every boundary (rows) at ``x`` (µm)."""
    a, b, c = np.asarray(coefficients, float).T
    x = np.asarray(x, float)
    return a[:, None] + b[:, None] * x + c[:, None] * (x**2 - x_max**2 / 12)


def _inclusion_list(inclusion) -> list[tuple]:
    """Inclusions as a list of ``(x_c, z_c, w, h)``: ``None`` (none), one 4-tuple, or a
    sequence of them."""
    if inclusion is None:
        return []
    if len(inclusion) == 4 and np.ndim(inclusion[0]) == 0:
        return [tuple(float(v) for v in inclusion)]
    return [tuple(float(v) for v in e) for e in inclusion]


def _region(x, z, bounds_of, inclusion):
    """Region index of points: the layer (0..K-1), or K + j inside inclusion ``j`` (the
    inclusions do not overlap)."""
    tops = bounds_of(x)  # (K - 1, n)
    layer = np.sum(z[None, :] >= tops, axis=0) if tops.size else np.zeros(z.size, int)
    for j, (xc, zc, w, h) in enumerate(_inclusion_list(inclusion)):
        inside = ((x - xc) / w) ** 2 + ((z - zc) / h) ** 2 < 1
        layer = np.where(inside, tops.shape[0] + 1 + j, layer)
    return layer


def region_volumes(cfg: ScannerConfig, coefficients: np.ndarray, inclusion: tuple | None):
    """Volumes (µm^3, slab ``|y| <= r``) of the layers, then the inclusions (``None``, one
    ``(x_c, z_c, w, h)`` or a list of them, not overlapping), from the exact profiles on
    :data:`_GRID` lines; and the layers' edges on those lines."""
    h, xm, r = cfg.depth_range, cfg.x_max, cfg.beam_radius
    xs = (np.arange(_GRID) + 0.5) / _GRID * xm - xm / 2
    bounds = np.clip(profiles(coefficients, xs, xm), 0, h)
    edges = np.vstack([np.zeros((1, _GRID)), bounds, np.full((1, _GRID), h)])
    area = np.diff(edges, axis=0).sum(axis=1) * xm / _GRID
    inner = []
    for xc, zc, w, hh in _inclusion_list(inclusion):
        u = np.clip(1 - ((xs - xc) / w) ** 2, 0, None)
        lo, hi = zc - hh * np.sqrt(u), zc + hh * np.sqrt(u)
        overlap = np.clip(np.minimum(hi, edges[1:]) - np.maximum(lo, edges[:-1]), 0, None)
        area = area - overlap.sum(axis=1) * xm / _GRID
        inner.append(np.sum(hi - lo) * xm / _GRID)
    return np.append(area, inner) * 2 * r, edges


def patient_table(
    cfg: ScannerConfig,
    coefficients: np.ndarray,
    density: np.ndarray,
    energy: np.ndarray,
    inclusion: tuple | None,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """The four-column table of a patient (regions: layers, then the inclusions: ``None``,
    one ``(x_c, z_c, w, h)`` or a list of them) and the regions' densities scaled to
    ``cfg.n_scatterers`` expected scatterers (per µm^3)."""
    xm, r = cfg.x_max, cfg.beam_radius
    volume, edges = region_volumes(cfg, coefficients, inclusion)
    n_layers = edges.shape[0] - 1
    weights = np.asarray(density, float)[: volume.size]
    rho = weights * cfg.n_scatterers / np.sum(weights * volume)
    counts = rng.multinomial(cfg.n_scatterers, rho * volume / np.sum(rho * volume))

    def bounds_of(x):
        return profiles(coefficients, x, xm)

    parts = []
    for k, count in enumerate(counts):
        if k < n_layers:
            box = (-xm / 2, xm / 2, float(edges[k].min()), float(edges[k + 1].max()))
        else:
            xc, zc, w, hh = _inclusion_list(inclusion)[k - n_layers]
            box = (xc - w, xc + w, zc - hh, zc + hh)
        got = np.empty((0, 2))
        while got.shape[0] < count:
            n = 2 * (count - got.shape[0]) + 16
            x = rng.uniform(box[0], box[1], n)
            z = rng.uniform(box[2], box[3], n)
            keep = _region(x, z, bounds_of, inclusion) == k
            got = np.vstack([got, np.column_stack([x, z])[keep]])
        got = got[:count]
        parts.append(
            np.column_stack([
                got[:, 0], rng.uniform(-r, r, count), got[:, 1], np.full(count, energy[k])
            ])
        )  # fmt: skip
    table = np.concatenate(parts)
    return table[rng.permutation(table.shape[0])], rho


def virtual_patient(
    seed: int,
    *,
    config: object = "challenge",
    layers: tuple[int, int] = (1, 5),
    shapes: tuple[str, ...] = SHAPES,
    inclusions: bool | int = False,
    energy_range: tuple[float, float] = (0.05, 5.0),
    density_range: tuple[float, float] = (0.3, 3.0),
    min_contrast: float = 2.5,
    min_thickness: float | None = None,
    max_tilt: float = 0.1,
    max_sag: float = 0.05,
    visible: float = VISIBLE_NEPER,
    draw_seed: int | None = None,
) -> tuple[np.ndarray, xr.Dataset]:
    """A random layered phantom (tilted or curved boundaries, inclusions) and its truth.

    Parameters
    ----------
    seed : int
        Seed of the patient (``SeedSequence(seed)``): its geometry, densities and energies.
    config : str or ScannerConfig
        ``"challenge"``, ``"2025"`` (:func:`speckle.synthoct_config`) or a configuration; the
        phantom holds its ``n_scatterers`` rows in its box.
    layers : (int, int)
        Least and most layers (1..8), drawn uniformly.
    shapes : tuple of {"flat", "tilted", "curved"}
        Shapes each boundary is drawn from (uniformly).
    inclusions : bool or int
        Elliptical inclusions of the patient (module docstring): ``False`` none, ``True`` one,
        or their number (0..:data:`MAX_PATIENT_INCLUSIONS`, not overlapping).
    energy_range : (float, float)
        Energies (%, in (0, 100]) drawn log-uniform, before the visibility scaling.
    density_range : (float, float)
        Relative densities (0.01..100) drawn log-uniform, times the config's mean density.
    min_contrast : float
        Least ratio (>= 1) of neighbouring regions' ``rho E``.
    min_thickness : float, optional
        Least layer thickness, µm (> 0; default 15 pixels).
    max_tilt : float
        Largest depth change of a tilted boundary over the box, as a fraction of the depth
        range ``H`` (0..0.5).
    max_sag : float
        Largest sag of a curved boundary (its centre against its edges), fraction of ``H``
        (0..0.5).
    visible : float
        Least margin (neper of mean ``ln I``, 0.5..11) between every layer's bottom and the
        brightest region's top level: 6 (:data:`VISIBLE_NEPER`) keeps every boundary above the
        floor at the challenge's density; sparser speckle (the 2025 configuration's smaller
        cell) puts the image's maximum farther above the mean and needs less (4).
    draw_seed : int, optional
        Seed of the scatterers' draw (default ``seed``): the same patient drawn again with
        another seed (the closed loop's floor).

    Returns
    -------
    phantom : numpy.ndarray
        ``(n_scatterers, 4)``: X, Y, Z (µm), Energy (%).
    truth : xarray.Dataset
        Dims ``layer``, ``x`` (the A-lines), ``inclusion`` (their number): ``top`` (layer, x; µm),
        ``top_mean``, ``top_tilt`` (µm per µm), ``top_curvature`` (µm^-1, ``c``), ``shape``,
        ``attenuation`` (1/µm), ``density`` (µm^-3), ``energy`` (%), ``rho_e``; the
        inclusion's ``inclusion_x``, ``inclusion_z`` (centre, µm), ``inclusion_width``,
        ``inclusion_height`` (semi-axes, µm), ``inclusion_density``, ``inclusion_energy``,
        ``inclusion_attenuation``, ``inclusion_layer`` (its host).

    Raises
    ------
    TypeError, ValueError
        A bad seed, config or option (named with its allowed range), before any drawing.

    Examples
    --------
    >>> import speckle
    >>> cfg = speckle.ScannerConfig(n_pixels=128, n_lines=128, x_max=768.0, n_scatterers=37_500)
    >>> table, truth = speckle.virtual_patient(3, config=cfg, layers=(2, 2))
    >>> table.shape, truth.sizes["layer"]
    ((37500, 4), 2)
    """
    for name, value in (("seed", seed), ("draw_seed", seed if draw_seed is None else draw_seed)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
            raise ValueError(f"{name} must be a non-negative integer, got {value!r}")
    cfg = scanner_config_of(config)
    k_lo, k_hi = _range("layers", layers, 1, 8, integer=True)
    if not isinstance(shapes, tuple | list) or not shapes or any(s not in SHAPES for s in shapes):
        raise ValueError(f"shapes must be a non-empty tuple of {SHAPES}, got {shapes!r}")
    if not isinstance(inclusions, bool | int | np.integer):
        raise TypeError(f"inclusions must be a bool or an int, got {inclusions!r}")
    if not 0 <= int(inclusions) <= MAX_PATIENT_INCLUSIONS:
        raise ValueError(
            f"inclusions must be 0..{MAX_PATIENT_INCLUSIONS} (or a bool), got {inclusions!r}"
        )
    n_inclusions = int(inclusions)
    e_lo, e_hi = _range("energy_range", energy_range, 1e-6, 100.0)
    if e_lo <= 0:
        raise ValueError(f"energy_range must be > 0 %, got {energy_range!r}")
    d_lo, d_hi = _range("density_range", density_range, 0.01, 100.0)
    for name, value, lo, hi in (
        ("min_contrast", min_contrast, 1.0, 100.0),
        ("max_tilt", max_tilt, 0.0, 0.5),
        ("max_sag", max_sag, 0.0, 0.5),
        ("visible", visible, 0.5, 11.0),
    ):
        if isinstance(value, bool) or not isinstance(value, int | float) or not lo <= value <= hi:
            raise ValueError(f"{name} must be a number in {lo}..{hi}, got {value!r}")
    h, xm, r = cfg.depth_range, cfg.x_max, cfg.beam_radius
    t_min = 15 * cfg.pixel_size if min_thickness is None else min_thickness
    if isinstance(t_min, bool) or not isinstance(t_min, int | float) or not 0 < t_min < h / 2:
        raise ValueError(f"min_thickness must be a number in (0, {h / 2}) µm, got {t_min!r}")

    draw = seed if draw_seed is None else draw_seed
    rng = np.random.default_rng(np.random.SeedSequence(int(seed)))
    n_layers = int(rng.integers(k_lo, k_hi + 1))
    n_regions = n_layers + n_inclusions
    a2 = slab_constants(r)["A2"]
    x_lines = cfg.line_positions
    xs = np.linspace(-xm / 2, xm / 2, 257)

    # boundaries: mean depths, tilts, sags, at least t_min apart everywhere
    shape = ["flat"] + [str(rng.choice(list(shapes))) for _ in range(n_layers - 1)]
    slack = h - 2 * t_min - (n_layers - 1) * t_min
    if slack < 0:
        raise ValueError(
            f"no {n_layers} layers at least min_thickness={t_min} µm thick fit in the depth "
            f"range {h} µm: lower layers or min_thickness"
        )
    for attempt in range(1000):
        share = rng.dirichlet(np.ones(n_layers))[:-1]
        a = np.cumsum(t_min + share * slack)
        shrink = 0.99**attempt  # tilts and sags shrink until the layers fit
        tilt = rng.uniform(-max_tilt, max_tilt, n_layers - 1) * h / xm * shrink
        sag = rng.uniform(-max_sag, max_sag, n_layers - 1) * h * shrink
        kind = np.array(shape[1:])
        b = np.where(kind == "flat", 0.0, tilt)
        c = np.where(kind == "curved", sag / (xm / 2) ** 2, 0.0)
        coefficients = np.column_stack([a, b, c])
        edges = np.vstack([np.zeros((1, xs.size)), profiles(coefficients, xs, xm)])
        if np.all(np.diff(edges, axis=0) >= t_min) and np.all(edges[-1] <= h - 2 * t_min):
            break
    else:
        raise ValueError(
            f"no {n_layers} layers at least min_thickness={t_min} µm thick fit in the depth "
            f"range {h} µm: lower layers or min_thickness"
        )
    inclusion, hosts = [], []
    gap = INCLUSION_GAP * cfg.pixel_size
    for _ in range(n_inclusions):
        for _ in range(1000):
            host = int(rng.integers(0, n_layers))
            w = rng.uniform(0.05, 0.15) * xm
            hh = rng.uniform(0.3, 0.5) * t_min
            xc = rng.uniform(-xm / 4, xm / 4)
            top = edges[host] if host else np.zeros(xs.size)
            bottom = edges[host + 1] if host + 1 < n_layers else np.full(xs.size, h - 2 * t_min)
            near = np.abs(xs - xc) <= w
            lo, hi = top[near].max() + hh + 2 * cfg.pixel_size, bottom[near].min() - hh
            if hi > lo:
                zc = float(rng.uniform(lo, hi))
                if all(abs(xc - e[0]) >= w + e[2] + gap or abs(zc - e[1]) >= hh + e[3] + gap
                       for e in inclusion):  # fmt: skip
                    inclusion.append((xc, zc, w, hh))
                    hosts.append(host)
                    break
        else:
            raise ValueError("no inclusion fits in the drawn layers: raise min_thickness")
    # visibility: energies scaled down until every layer's bottom is above the floor
    volume, _ = region_volumes(cfg, coefficients.reshape(-1, 3), inclusion)
    centre = np.linspace(-xm / 2 + 3 * r, xm / 2 - 3 * r, 33)
    bounds = (
        np.clip(profiles(coefficients, centre, xm), 0, h) if n_layers > 1 else np.empty((0, 33))
    )
    last = bounds[-1] if n_layers > 1 else np.zeros(centre.size)
    lower = np.vstack([bounds, np.minimum(last + t_min, h - 2 * t_min)[None, :]])
    upper = np.vstack([np.zeros((1, centre.size)), bounds])
    thick = lower - upper
    pairs = [(k, k + 1) for k in range(n_layers - 1)]
    pairs += [(host, n_layers + j) for j, host in enumerate(hosts)]

    def is_visible(rel, energy):
        rho_guess = rel * cfg.n_scatterers / np.sum(rel * volume)
        mu = rho_guess[:n_layers] * energy[:n_layers] / 100 * a2
        shadow_top = np.vstack([np.zeros((1, centre.size)),
                                np.cumsum(mu[:, None] * thick, axis=0)[:-1]])  # fmt: skip
        base = np.log(mu)[:, None]
        level_top = base - 2 * shadow_top
        level_bottom = base - 2 * (shadow_top + mu[:, None] * thick)
        return bool(np.all(level_bottom >= level_top.max() - visible))

    # densities and energies, neighbours' rho E at least min_contrast apart, every layer
    # visible (else drawn again: a faint layer over a bright one sits under the floor)
    for _ in range(200):
        rel = np.exp(rng.uniform(math.log(d_lo), math.log(d_hi), n_regions))
        energy = np.exp(rng.uniform(math.log(e_lo), math.log(e_hi), n_regions))
        for _ in range(1000):
            bad = [j for i, j in pairs if max(rel[i] * energy[i], rel[j] * energy[j])
                   < min_contrast * min(rel[i] * energy[i], rel[j] * energy[j])]  # fmt: skip
            if not bad:
                break
            energy[bad[0]] = math.exp(rng.uniform(math.log(e_lo), math.log(e_hi)))
        else:
            raise ValueError(f"min_contrast={min_contrast} cannot be met in energy_range: lower it")
        for _ in range(60):
            if is_visible(rel, energy):
                break
            energy *= 0.8
        else:
            continue
        break
    else:
        raise ValueError(
            "no draw of densities and energies leaves every layer above the window's floor: "
            "narrow energy_range or density_range"
        )
    table, rho = patient_table(
        cfg, coefficients.reshape(-1, 3), rel, energy, inclusion,
        np.random.default_rng(np.random.SeedSequence([int(seed), int(draw)])),
    )  # fmt: skip
    mu = rho * energy / 100 * a2
    top = np.vstack([np.zeros((1, x_lines.size)), profiles(coefficients, x_lines, xm)])
    full = np.vstack([np.zeros((1, 3)), coefficients])
    lay = slice(0, n_layers)
    inc = slice(n_layers, n_regions)

    def per(quantity, values, long_name, dim="layer"):
        return (dim,), np.asarray(values), attrs(quantity, long_name)

    ellipses = np.array(inclusion, float).reshape(-1, 4)
    truth = xr.Dataset(
        {
            "top": (("layer", "x"), top, attrs("length", "upper boundary of the layer")),
            "top_mean": per("length", full[:, 0], "mean depth of the upper boundary"),
            "top_tilt": per("dimensionless", full[:, 1], "tilt b of the boundary (um per um)"),
            "top_curvature": (("layer",), full[:, 2],
                              attrs("curvature", "curvature c of the boundary")),
            "shape": (("layer",), np.array(shape, dtype=object), attrs("label", "boundary shape")),
            "attenuation": per("attenuation", mu[lay], "one-way amplitude attenuation mu"),
            "density": per("volume_density", rho[lay], "scatterers per um^3 (slab |y| <= r)"),
            "energy": per("percent", energy[lay], "energy per scatterer"),
            "rho_e": per("volume_density", rho[lay] * energy[lay] / 100, "rho E/100"),
            "inclusion_x": per("length", ellipses[:, 0], "centre x of the inclusion",
                               "inclusion"),
            "inclusion_z": per("length", ellipses[:, 1], "centre depth of the inclusion",
                               "inclusion"),
            "inclusion_width": per("length", ellipses[:, 2],
                                   "lateral semi-axis of the inclusion", "inclusion"),
            "inclusion_height": per("length", ellipses[:, 3],
                                    "depth semi-axis of the inclusion", "inclusion"),
            "inclusion_density": per("volume_density", rho[inc], "scatterers per um^3",
                                     "inclusion"),
            "inclusion_energy": per("percent", energy[inc], "energy per scatterer", "inclusion"),
            "inclusion_attenuation": per("attenuation", mu[inc], "one-way attenuation mu",
                                         "inclusion"),
            "inclusion_layer": per("label", np.array(hosts, int), "host layer", "inclusion"),
        },
        coords={
            "layer": coord("layer", np.arange(n_layers)),
            "x": coord("x", x_lines),
            "inclusion": coord("inclusion", np.arange(n_inclusions)),
        },
        attrs={"seed": int(seed), "draw_seed": int(draw),
               "n_scatterers": cfg.n_scatterers},
    )  # fmt: skip
    return table, truth
