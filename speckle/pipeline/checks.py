"""Checks of the pipeline configuration that JSON Schema cannot express, run when it loads.

The Snakefile calls :func:`check_config` right after ``validate(config, schema)`` and
:func:`check_scan_table` after validating the scan table, so a bad value stops the run before
any job, with the key path (e.g. ``fig2.fragment.depth``) in the message. JSON Schema accepts
``16.0`` as an integer and ``.inf``/``.nan`` as numbers, and cannot relate one key to another;
these checks add

* strict types: every key the schema declares ``integer`` must be a YAML integer (``16``, not
  ``16.0``), and every ``number`` must be finite;
* cross-field rules: a Gaussian source needs ``fwhm_fraction``; a shown fragment must lie inside
  the simulated image (``n_pixels`` x ``n_alines``); the correlation window must fit in the
  images; every density must give at least one scatterer per A-line
  (``round(density * n_pixels) >= 1``);
* memory: the scatterers and images a figure would hold must fit in
  :data:`speckle._validate.MAX_BYTES`;
* the scan table: at least one row, no duplicate rows, densities above the floor;
* the ``despeckle`` section (:func:`check_despeckle`) and the ``twin`` section
  (:func:`check_twin`).

Every config section's checks live here, in one place (issue 32): the figure modules only
draw.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from .._validate import MAX_BYTES
from ..analysis import compounding as cp
from ..analysis import filters as dsp
from ..analysis.measured import measured_shape, roi_slices
from ..conventions import canonical_keys
from ..figures.despeckle import parameter_grid
from ..imaging._methods.nufft import NUFFT_TOL_FLOOR, float32_error_estimate
from ..imaging.scan import beam_reach
from ..io import load_image
from ..scene.shared import MAX_TILES
from .adapters import system_from_config
from .dynamics_checks import check_dynamics_config
from .phantom_checks import check_phantom_fit
from .phantom_real_checks import check_phantom_real
from .synthoct_checks import check_synthoct

__all__ = [
    "check_config",
    "check_despeckle",
    "check_dynamics_config",
    "check_scan_table",
    "check_sections",
    "check_twin",
    "figure_bytes",
    "tol_floor",
]

#: Bytes per scatterer slot (z, amplitude as drawn and as complex128) and per image pixel
#: (complex field, amplitude, intensity).
SCATTERER_BYTES = 32
PIXEL_BYTES = 32


def _types(value: object, schema: Mapping, path: str) -> None:
    """Refuse non-integral integers and non-finite numbers, recursively (key path named)."""
    if not isinstance(schema, Mapping):
        return
    kinds = schema.get("type", [])
    kinds = [kinds] if isinstance(kinds, str) else list(kinds)
    if "integer" in kinds and isinstance(value, float):
        raise ValueError(f"config key {path} must be an integer (e.g. 16, not 16.0); got {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"config key {path} must be finite; got {value!r}")
    if isinstance(value, Mapping):
        props = schema.get("properties", {})
        for key, sub in value.items():
            if key in props:
                _types(sub, props[key], f"{path}.{key}" if path else str(key))
    elif isinstance(value, list) and isinstance(schema.get("items"), Mapping):
        for i, sub in enumerate(value):
            _types(sub, schema["items"], f"{path}[{i}]")


def _density_floor(density: float, n_pixels: int, key: str) -> None:
    if round(density * n_pixels) < 1:
        raise ValueError(
            f"config key {key} = {density!r} gives no scatterer in an A-line of "
            f"source.n_pixels = {n_pixels} pixels; use a density >= {0.5 / n_pixels:.3g} "
            "(round(density * n_pixels) >= 1)"
        )


def _fragment(frag: Mapping, n_pixels: int, n_alines: int, key: str) -> None:
    for dim, extent, what in (
        ("depth", n_pixels, "source.n_pixels"),
        ("x", n_alines, f"{key.split('.')[0]}.n_alines"),
    ):
        if frag[dim] + frag["size"] > extent:
            raise ValueError(
                f"config key {key}.{dim} = {frag[dim]} with {key}.size = {frag['size']} lies "
                f"outside the image ({what} = {extent}); need {dim} + size <= {extent}"
            )


def figure_bytes(n_images: int, n_alines: int, n_pixels: int, density: float) -> float:
    """Bytes of the scatterers of one image plus ``n_images`` images of ``n_alines`` lines."""
    scatterers = SCATTERER_BYTES * n_alines * max(1.0, density * n_pixels)
    return scatterers + PIXEL_BYTES * n_images * n_alines * n_pixels


def _memory(nbytes: float, key: str) -> None:
    if nbytes > MAX_BYTES:
        raise ValueError(
            f"config key {key} too large: the figure would hold ~{nbytes / 2**30:.3g} GiB, above "
            f"the {MAX_BYTES / 2**30:.3g} GiB limit (speckle._validate.MAX_BYTES)"
        )


def check_config(config: Mapping, schema: Mapping | None = None) -> None:
    """Refuse a pipeline config that passed JSON-Schema validation but cannot run.

    Parameters
    ----------
    config : Mapping
        The merged pipeline configuration (already validated against the schema).
    schema : Mapping, optional
        The loaded ``config.schema.yaml``; with it, integers and finite numbers are checked
        strictly for every key (see module docstring).

    Raises
    ------
    ValueError
        Naming the key path and the allowed values.
    """
    if schema is not None:
        _types(config, schema, "")
    src = config["source"]
    n = int(src["n_pixels"])
    if src.get("shape") == "gaussian" and src.get("fwhm_fraction") is None:
        raise ValueError(
            "config key source.fwhm_fraction must be a number > 0 when source.shape is "
            "'gaussian' (the FWHM as a fraction of delta_k); got null"
        )
    for name in ("fig2", "fig3"):
        for i, rho in enumerate(config[name]["densities"]):
            _density_floor(float(rho), n, f"{name}.densities[{i}]")
    for name in ("fig4", "fig5", "fig6"):
        _density_floor(float(config[name]["density"]), n, f"{name}.density")
    for name in ("fig2", "fig5"):
        sec = config[name]
        _fragment(sec["fragment"], n, int(sec["n_alines"]), f"{name}.fragment")
    fig6 = config["fig6"]
    wz, wx = fig6["window"]
    for key, lines in (
        ("fig6.n_alines", fig6["n_alines"]),
        ("scan.n_alines", config["scan"]["n_alines"]),
    ):
        if wz > n or wx > lines:
            raise ValueError(
                f"config key fig6.window = {[wz, wx]} does not fit in the images "
                f"(source.n_pixels = {n}, {key} = {lines})"
            )
    if "elastography" in config:
        _elastography(config["elastography"])
    # memory: the largest image stack each figure holds at once
    sizes = {
        "fig2.n_alines": (
            len(config["fig2"]["densities"]),
            config["fig2"]["n_alines"],
            max(config["fig2"]["densities"]),
        ),
        "fig3.n_alines": (1, config["fig3"]["n_alines"], max(config["fig3"]["densities"])),
        "fig4.n_alines": (1, config["fig4"]["n_alines"], config["fig4"]["density"]),
        "fig5.n_alines": (
            len(config["fig5"]["k0_dk"]),
            config["fig5"]["n_alines"],
            config["fig5"]["density"],
        ),
    }
    for key, (images, lines, rho) in sizes.items():
        _memory(figure_bytes(images, int(lines), n, float(rho)), key)
    measured = config["fig4"]["measured"]
    _measured_roi(measured.get("path"), measured.get("roi") or {})
    check_sections(config)
    if "despeckle" in config:
        check_despeckle(config["despeckle"])
    if "twin" in config:
        check_twin(config["twin"])
    if "synthoct" in config:
        check_synthoct(config["synthoct"])
    if "phantom_real" in config:
        check_phantom_real(config["phantom_real"])
    if "phantom_fit" in config:
        check_phantom_fit(config["phantom_fit"])
    if "dynamics" in config:
        dyn = config["dynamics"]
        check_dynamics_config(dyn)
        for part in (None, "g1", "failure", "calibration"):
            own = (dyn[part].get("geometry") or {}) if part else {}
            geo = {**dyn["geometry"], **own}
            key = f"dynamics.{part + '.' if part and 'tol' in own else ''}geometry.tol"
            _tol(geo.get("method", "finufft"), geo.get("tol"), key, int(geo["n_pixels"]), False)


def _elastography(el: Mapping) -> None:
    """Estimator windows inside the images they slide over (depth >= 2 pixels), and the
    failure maps' image pair within the memory limit."""
    n, lines = int(el["n_pixels"]), int(el["n_alines"])
    wz, wx = (int(v) for v in el["window"])
    images = {"elastography.n_alines": lines}
    if "inclusion" in el:
        images["elastography.inclusion.n_alines"] = int(el["inclusion"]["n_alines"])
    if "sequence_large" in el and "n_alines" in el["sequence_large"]:
        images["elastography.sequence_large.n_alines"] = int(el["sequence_large"]["n_alines"])
    if wz < 2:
        raise ValueError(
            f"config key elastography.window = {[wz, wx]}: the depth window must be >= 2 pixels "
            "(the estimators fit a gradient over it)"
        )
    for key, m in images.items():
        if wz > n or wx > m:
            raise ValueError(
                f"config key elastography.window = {[wz, wx]} does not fit in the images "
                f"(elastography.n_pixels = {n}, {key} = {m})"
            )
    fc = el.get("failure", {})
    fn = int(fc.get("n_pixels", n))
    flines = int(fc.get("n_alines", lines))
    fkey = "elastography.failure.n_pixels" if "n_pixels" in fc else "elastography.n_pixels"
    if wz > fn or wx > flines:
        raise ValueError(
            f"config key elastography.window = {[wz, wx]} does not fit in the failure-map "
            f"images ({fkey} = {fn}, elastography.failure.n_alines = {flines})"
        )
    for i, w in enumerate(fc.get("windows", [])):
        if not 2 <= int(w) <= fn:
            raise ValueError(
                f"config key elastography.failure.windows[{i}] = {w} must be in [2, {fkey} = {fn}]"
            )
    if "n_alines" in fc:
        densest = max([float(el["density"]), *(float(v) for v in fc.get("density", []))])
        _memory(figure_bytes(2, flines, fn, densest), "elastography.failure.n_alines")
    # the sequences: the in-memory one holds its frames (twice) and four float64 result stacks,
    # its scene populated for the total strain 1 - (1 - s)^(frames - 1) (below 1: the scene
    # must exist); the large one builds the FE field on its lines, holds each frame's images,
    # and its figure reads back the result's four stacks
    if "sequence" in el:
        sq = el["sequence"]
        frames = int(sq["n_frames"])
        total = 1.0 - (1.0 - float(sq["strain"])) ** (frames - 1)
        if not total < 1.0:
            raise ValueError(
                f"config key elastography.sequence.n_frames = {frames}: the total strain "
                f"1 - (1 - strain)^(n_frames - 1) reaches {total:g}, and a scene compressed by "
                "1 has no depth; use fewer frames or a smaller strain"
            )
        scat = SCATTERER_BYTES * lines * max(1.0, float(el["density"]) * n) / (1.0 - total)
        _memory(scat + 64.0 * frames * n * lines, "elastography.sequence.n_frames")
    if "sequence_large" in el:
        from ..scene.mechanics import fem_bytes

        sl = el["sequence_large"]
        slines = int(sl.get("n_alines", el.get("inclusion", {}).get("n_alines", lines)))
        fe = fem_bytes((n + 1) * (slines + 1))  # a node per pixel corner (mesh = pixel)
        _memory(fe + figure_bytes(4, slines, n, float(el["density"])),
                "elastography.sequence_large.n_alines")  # fmt: skip
        _memory(32.0 * int(sl["n_frames"]) * n * slines, "elastography.sequence_large.n_frames")
    for i, w in enumerate(el.get("speed", {}).get("windows", [])):
        if not 2 <= int(w) <= n:
            raise ValueError(
                f"config key elastography.speed.windows[{i}] = {w} must be in [2, "
                f"elastography.n_pixels = {n}]"
            )


def _measured_roi(path: str | None, roi: Mapping) -> None:
    """The fig4 region of interest must lie inside the measured image (if it is present)."""
    if not path or not str(path).endswith(".npy") or not os.path.isfile(path):
        return  # no file: Fig. 4 draws the simulated panels only (README)
    shape = np.load(path, mmap_mode="r").shape
    for axis, dim in enumerate(("depth", "x")):
        bounds = roi.get(dim) or [None, None]
        for b in bounds:
            if b is not None and len(shape) == 2 and b > shape[axis]:
                raise ValueError(
                    f"config key fig4.measured.roi.{dim} = {bounds} lies outside the measured "
                    f"image of shape {tuple(shape)} (depth, x)"
                )


def _image_shape(cfg: Mapping) -> tuple[int, int]:
    """``(depth, x)`` pixels of the twin's image (an ``.npy`` is memory-mapped, not read)."""
    path = cfg["image"]
    if not os.path.exists(path):
        raise ValueError(
            f"config key twin.image = {path!r}: no such file (relative to the repository root)"
        )
    dims = cfg.get("dims")
    if str(path).endswith(".npy") and dims is not None:
        arr = np.load(path, mmap_mode="r")
        shape = arr.shape
        kind = cfg["kind"]
        if (kind == "complex") != (arr.dtype.kind == "c"):
            raise ValueError(
                f"config key twin.kind = {kind!r} cannot describe {path} (dtype {arr.dtype}): "
                "'complex' needs complex values, the other kinds real ones"
            )
        if kind in ("amplitude", "intensity") and arr.size and float(np.min(arr)) < 0:
            raise ValueError(
                f"config key twin.kind = {kind!r} cannot describe {path}: it holds negative "
                "values (log-compressed data are kind 'log')"
            )
        names = list(canonical_keys(dict.fromkeys(dims), "config key twin.dims"))
        if len(names) != len(shape):
            raise ValueError(
                f"config key twin.dims = {list(dims)} does not name the {len(shape)} axes of "
                f"{path} (shape {shape})"
            )
        return shape[names.index("depth")], shape[names.index("x")]
    da = load_image(
        path,
        kind=cfg["kind"],
        pixel_size=cfg.get("pixel_size"),
        pitch=cfg.get("pitch"),
        dims=None if dims is None else tuple(dims),
        variable=cfg.get("variable"),
    )
    return da.sizes["depth"], da.sizes["x"]


def check_twin(cfg: Mapping) -> None:
    """The twin section: region and noise rows inside the image, sizes fit the lags and windows.

    Raises
    ------
    ValueError
        Naming the key (``twin.region.depth``, ...) and the allowed range.
    """
    nz, nx = _image_shape(cfg)
    region = cfg.get("region") or {}
    size = {}
    for dim, n in (("depth", nz), ("x", nx)):
        lo, hi = region.get(dim) or [None, None]
        lo, hi = (0 if lo is None else lo), (n if hi is None else hi)
        if not 0 <= lo < hi <= n:
            raise ValueError(
                f"config key twin.region.{dim} = {region.get(dim)} lies outside the image ({dim}: "
                f"0..{n}); need 0 <= start < stop <= {n}"
            )
        size[dim] = hi - lo
    ml, nb = cfg["max_lag"], cfg["n_blocks"]
    if size["depth"] < ml + 4 or size["x"] < nb * (ml + 2):
        raise ValueError(
            f"config key twin.region ({size['depth']} x {size['x']} pixels) is too small for "
            f"twin.max_lag = {ml} and twin.n_blocks = {nb}: need depth >= max_lag + 4 and "
            "x >= n_blocks * (max_lag + 2)"
        )
    if cfg.get("n_bands") and size["depth"] // cfg["n_bands"] < 2:
        raise ValueError(
            f"config key twin.n_bands = {cfg['n_bands']} leaves fewer than 2 rows per band of "
            "twin.region"
        )
    rows = cfg.get("noise_rows")
    if rows is not None and not 0 <= rows[0] < rows[1] - 1 < nz:
        raise ValueError(
            f"config key twin.noise_rows = {rows} must hold 2 or more rows inside the image "
            f"(0..{nz})"
        )
    lo, hi = region.get("depth") or [None, None]
    lo, hi = (0 if lo is None else lo), (nz if hi is None else hi)
    if rows is not None and rows[0] < hi and rows[1] > lo:
        raise ValueError(
            f"config key twin.noise_rows = {rows} overlap twin.region.depth = [{lo}, {hi}]: "
            "signal-free rows must lie outside the fitted speckle"
        )
    if rows is not None and cfg.get("snr_db") is not None:
        raise ValueError(
            "config keys twin.noise_rows and twin.snr_db: give one, not both (the rows measure "
            "the SNR that snr_db states)"
        )
    fc = cfg["failure"]
    window = fc.get("window")
    if window is not None and (window[0] > fc["shape"][0] or window[1] > fc["shape"][1]):
        raise ValueError(
            f"config key twin.failure.window = {window} does not fit in twin.failure.shape = "
            f"{fc['shape']}"
        )
    if window is None:
        from ..analysis.strain import DEFAULT_WINDOWS

        for m in fc["methods"]:
            wz, wx = DEFAULT_WINDOWS[m]
            if wz > fc["shape"][0] or wx > fc["shape"][1]:
                raise ValueError(
                    f"config key twin.failure.shape = {fc['shape']} is smaller than method "
                    f"{m!r}'s default window ({wz}, {wx}) (twin.failure.window is null); "
                    "enlarge the shape or set twin.failure.window"
                )


def check_scan_table(rows: Sequence[Mapping], n_pixels: int) -> None:
    """Refuse an empty scan table, duplicate rows and densities below the floor.

    Parameters
    ----------
    rows : sequence of mapping
        Table rows with keys ``density``, ``k0_dk``, ``spectrum`` (e.g.
        ``DataFrame.to_dict("records")``).
    n_pixels : int
        ``source.n_pixels``.

    Raises
    ------
    ValueError
        Naming ``scan.table`` and the offending rows (1-based, after the header).
    """
    if len(rows) == 0:
        raise ValueError("config key scan.table names a table with no rows; add at least one")
    seen: dict[tuple, int] = {}
    for i, row in enumerate(rows, start=1):
        key = (float(row["density"]), float(row["k0_dk"]), str(row["spectrum"]))
        if key in seen:
            raise ValueError(
                f"config key scan.table: rows {seen[key]} and {i} are the same point "
                f"(density, k0_dk, spectrum) = {key}; remove the duplicate"
            )
        seen[key] = i
        _density_floor(key[0], n_pixels, f"scan.table row {i} density")


# --- sections added since the first reliability round (issue 21) ---------------------------
# beam, source.datasheet, system, realism, speed_accuracy.beam: each value is checked by the
# package function the job will call (datasheet, roi_slices) or by the same rule (tol floors,
# memory), and the package's message is reworded with the config key.


def _reword(key: str, exc: Exception, names: Sequence[str] = ()) -> ValueError:
    """A ValueError naming ``key`` (and the first of ``names`` the message mentions)."""
    msg = str(exc)
    found = [(msg.index(n), -len(n), n) for n in names if n in msg]
    hit = min(found)[2] if found else None  # the parameter the message names first
    full = f"{key}.{hit}" if hit else key
    return ValueError(f"config key {full}: {msg}")


def tol_floor(method: str, n_pixels: int = 2) -> float:
    """Smallest ``tol`` a synthesis ``method`` accepts (0 for ``direct`` and ``auto``).

    ``nufft`` and ``finufft``: :data:`speckle.imaging._methods.nufft.NUFFT_TOL_FLOOR` (float64
    NUFFT); ``nufft32``: twice the float32 rounding estimate
    (:func:`speckle.imaging._methods.nufft.float32_error_estimate`) of an image of ``n_pixels``
    pixels with no scatterer (a lower bound: more scatterers raise it; the method refuses at run
    time what this bound lets through).
    """
    if method in ("nufft", "finufft"):
        return NUFFT_TOL_FLOOR
    if method == "nufft32":
        return max(NUFFT_TOL_FLOOR, 2.0 * float32_error_estimate(0, max(int(n_pixels), 2), 1))
    return 0.0


def _tol(method: str, tol: float | None, key: str, n_pixels: int, also_nufft: bool) -> None:
    """``tol`` (key ``key``) at or above the floor of ``method``; ``also_nufft``: the target
    also images independent lines with ``nufft`` at this tol whenever ``method != direct``."""
    if tol is None:
        return
    methods = [method] + (["nufft"] if also_nufft and method != "direct" else [])
    for m in methods:
        floor = tol_floor(m, n_pixels)
        if tol < floor:
            via = "" if m == method else " (the independent-line B-scan of this target)"
            raise ValueError(
                f"config key {key} = {tol:g} is below what method {m!r}{via} reaches: "
                f"tol >= {floor:.3g}; raise {key} or use method 'direct'"
            )


def _no_finufft(method: str, key: str, what: str) -> None:
    """The FINUFFT beam reference images 2-D scenes without focus only."""
    if method == "finufft":
        raise ValueError(
            f"config key {key} = 'finufft' cannot image {what} (the FINUFFT beam reference "
            "handles a 2-D scene without focus only); use 'auto', 'direct', 'nufft' or 'nufft32'"
        )


def _datasheet(sheet: Mapping | None, key: str) -> None:
    """The datasheet as :func:`speckle.datasheet` takes it (all its constraints, named)."""
    if sheet is None:
        return
    try:
        system_from_config(sheet)
    except (TypeError, ValueError) as exc:
        raise _reword(key, exc, list(sheet)) from None


def _pixel_size(config: Mapping) -> float:
    """Depth pixel (µm) of the source section (its datasheet's ``H/N`` when it has one)."""
    sheet = config["source"].get("datasheet")
    if sheet:
        return float(system_from_config(sheet).pixel_size)
    return float(config["source"]["pixel_size"])


def _source_pixels(config: Mapping) -> int:
    sheet = config["source"].get("datasheet")
    return int(sheet["camera_pixels"]) if sheet else int(config["source"]["n_pixels"])


def _beam(config: Mapping) -> None:
    beam = config["beam"]
    n = int(beam.get("n_pixels") or _source_pixels(config))
    lines = int(beam["n_lines"])
    if int(beam["lags"]) >= lines:
        raise ValueError(
            f"config key beam.lags = {beam['lags']} leaves no pair of lines at the largest lag "
            f"in a B-scan of beam.n_lines = {lines}; need beam.lags < beam.n_lines"
        )
    if int(beam["lags"]) >= n:
        raise ValueError(
            f"config key beam.lags = {beam['lags']} must be below the pixels per A-scan ({n})"
        )
    _tol(beam["method"], beam["tol"], "beam.tol", n, also_nufft=True)
    vol = beam["volume"]
    _no_finufft(vol["method"], "beam.volume.method", "a 3-D volume")
    _tol(vol["method"], vol["tol"], "beam.volume.tol", int(vol["n_pixels"]), also_nufft=False)
    pitch = float(beam["pitch"])
    ratios = [float(r) for r in beam["waist_pitch"]]
    halo_lines = 2 * beam_reach(max(ratios) * pitch) / pitch
    scat = float(beam["density"]) * n * (lines + halo_lines)
    img = (len(ratios) + 2) * lines * n  # the B-scans, their concatenation, independent lines
    _memory(SCATTERER_BYTES * scat + PIXEL_BYTES * img, "beam.n_lines")
    st = beam["strain"]
    sl = int(st["n_lines"])
    scat = float(beam["density"]) * n * (sl + 2 * beam_reach(float(st["waist_pitch"]) * pitch))
    _memory(
        SCATTERER_BYTES * scat * (1 + int(st["num"])) + PIXEL_BYTES * 4 * int(st["num"]) * sl * n,
        "beam.strain.num",
    )
    # the volume is streamed: a chunk of lines of every line along x at once, and one tile column
    vn, vl = int(vol["n_pixels"]), int(vol["n_lines"])
    _memory(PIXEL_BYTES * int(vol["chunk"]) * vl * vn, "beam.volume.chunk")
    tile = vol["tile"] if isinstance(vol["tile"], list) else [vol["tile"]] * 3
    span = vl * pitch + 2 * beam_reach(float(vol["waist_pitch"]) * pitch)
    extent = (vn * _pixel_size(config), span, span)
    tiles = math.prod(math.ceil(e / float(t)) + 1 for e, t in zip(extent, tile, strict=True))
    if tiles > MAX_TILES:
        raise ValueError(
            f"config key beam.volume.tile = {vol['tile']!r} is too small: the volume's scene "
            f"would visit ~{tiles:.3g} tiles, above speckle.scene.shared.MAX_TILES = "
            f"{MAX_TILES:g}; use larger tiles (µm)"
        )


def _realism(config: Mapping) -> None:
    real = config["realism"]
    meas = real["measured"]
    path = meas.get("path")
    if path and os.path.isfile(path):
        shape = measured_shape(path)
        for key, roi in (
            ("realism.measured.roi", meas.get("roi") or {}),
            (
                "realism.measured.air_rows",
                {"depth": meas["air_rows"]} if meas.get("air_rows") else {},
            ),
        ):
            try:
                roi_slices(roi, shape)
            except (TypeError, ValueError) as exc:
                raise ValueError(
                    f"config key {key} = {roi!r} does not fit the measured image {path} of shape "
                    f"{shape} (depth, x): {exc}"
                ) from None
    show = real.get("showcase")
    if show is None:
        return
    n, p = int(show["n_pixels"]), float(show["pixel_size"])
    depth = n * p
    for name in ("focus", "surface", "interface", "bottom"):
        if not 0.0 <= float(show[name]) <= depth:
            raise ValueError(
                f"config key realism.showcase.{name} = {show[name]!r} lies outside the scene: "
                f"need 0 <= {name} <= n_pixels * pixel_size = {depth:g} µm"
            )
    if not float(show["surface"]) < float(show["interface"]) < float(show["bottom"]):
        raise ValueError(
            "config keys realism.showcase.surface < interface < bottom must increase; got "
            f"{show['surface']}, {show['interface']}, {show['bottom']}"
        )
    _no_finufft(show["method"], "realism.showcase.method", "a focused beam")
    _tol(show["method"], show["tol"], "realism.showcase.tol", n, also_nufft=False)
    lines = int(show["n_lines"]) + 10 * float(show["waist"]) / float(show["pitch"])
    nbytes = SCATTERER_BYTES * 2 * float(show["density"]) * n * lines + PIXEL_BYTES * 6 * n * lines
    _memory(nbytes, "realism.showcase.n_lines")


def _speed_beam(config: Mapping) -> None:
    sec = config["speed_accuracy"]["beam"]
    images = len(sec["methods"]) + 1  # every method's B-scan and the direct reference
    for i, size in enumerate(sec["sizes"]):
        nbytes = figure_bytes(
            images, int(size["n_lines"]), int(size["n_pixels"]), float(size["density"])
        )
        _memory(nbytes, f"speed_accuracy.beam.sizes[{i}]")


def _system(config: Mapping) -> None:
    sysc = config["system"]
    sheet = sysc["datasheet"]
    m = int(sheet["camera_pixels"])
    b = sysc["bscan"]
    scat = max(1.0, float(b["density"]) * m) + len(b["interfaces"])
    # the chain sums every scatterer's carrier over the camera pixels per A-line (complex128)
    _memory(16.0 * int(b["n_alines"]) * scat * m, "system.bscan.n_alines")
    _memory(16.0 * len(sysc["psf"]["depths"]) * m * 8, "system.psf.depths")
    _memory(16.0 * int(sysc["rolloff"]["n_depths"]) * m * 8, "system.rolloff.n_depths")


def check_sections(config: Mapping) -> None:
    """Constraints of the ``beam``, ``source.datasheet``, ``system``, ``realism`` and
    ``speed_accuracy.beam`` sections that JSON Schema cannot express.

    * datasheets (``source.datasheet``, ``system.datasheet``): every constraint of
      :func:`speckle.datasheet` (bandwidth below the wavelength, exactly one of
      ``camera_range_nm`` / ``imaging_depth``, the camera range covering the FWHM band, ...);
    * ``tol`` at or above the floor of the method (:func:`tol_floor`);
    * ``beam.lags`` below ``beam.n_lines`` (a correlation at every lag);
    * ``realism.measured.roi`` / ``air_rows`` inside the measured file (when it exists);
      ``realism.showcase`` depths (``focus``, layers) inside the scene, layers in order;
    * the memory each target holds at once within :data:`speckle._validate.MAX_BYTES`.

    Raises
    ------
    ValueError
        Naming the key path and the allowed values.
    """
    _datasheet(config["source"].get("datasheet"), "source.datasheet")
    _datasheet(config["system"]["datasheet"], "system.datasheet")
    _beam(config)
    _realism(config)
    _speed_beam(config)
    _system(config)


# --- the despeckle section (moved from speckle.figures.despeckle) ---------------------------
def _key(path: str, check) -> None:
    try:
        check()
    except (ValueError, TypeError) as err:
        raise ValueError(f"config key despeckle.{path}: {err}") from None


def _check_geometry(geo: Mapping, path: str) -> None:
    n, nl = int(geo["n_pixels"]), int(geo["n_lines"])
    a, lr = int(geo["air_rows"]), int(geo["layer_row"])
    inc, pts = geo["inclusion"], geo["points"]
    if not (0 < a and a + 4 <= lr and lr + 4 <= n):
        raise ValueError(
            f"config key despeckle.{path}: need 0 < air_rows ({a}), air_rows + 4 "
            f"<= layer_row ({lr}), layer_row + 4 <= n_pixels ({n})"
        )
    if not (lr < inc["row"] < n and 0 <= inc["line"] < nl):
        raise ValueError(
            f"config key despeckle.{path}.inclusion: centre (row {inc['row']}, line "
            f"{inc['line']}) must lie in layer 2 (rows {lr}..{n}) and lines 0..{nl}"
        )
    if not pts["row"] < a or any(not 0 <= v < nl for v in pts["lines"]):
        raise ValueError(
            f"config key despeckle.{path}.points: row must be < air_rows ({a}) and "
            f"lines in [0, n_lines={nl})"
        )


def _check_radii(geo: Mapping, radii) -> None:
    """The failure sweep's inclusion radii (pixels) keep the inclusion inside layer 2 and the
    lines of the failure phantom."""
    n, nl, lr = int(geo["n_pixels"]), int(geo["n_lines"]), int(geo["layer_row"])
    row, line = geo["inclusion"]["row"], geo["inclusion"]["line"]
    room = min(row - lr, n - row, line + 1, nl - line)
    for i, r in enumerate(radii):
        if r >= room:
            raise ValueError(
                f"config key despeckle.failure.feature_radius[{i}] = {r} does not fit in the "
                f"failure phantom: the inclusion at (row {row}, line {line}) must stay inside "
                f"layer 2 (rows {lr}..{n}) and lines 0..{nl}; need radius < {room}"
            )


def _check_spec(spec: Mapping, geo: Mapping, path: str) -> None:
    """One failure-map method of the despeckle section, on the failure phantom ``geo``: a
    temporal method's frames are drawn on a scene of the phantom's extent (depth
    ``n_pixels x pixel_size``, width ``n_lines x pixel_size``, µm), whose bound on the step
    between frames is the scene layer's (:data:`speckle.scene.motion.MAX_STEP_FRACTION`)."""
    n = int(geo["n_pixels"])
    fam = spec["family"]
    if fam == "frequency":
        _key(
            path,
            lambda: cp.subband_apodizations(
                n, spec["looks"], apodization=spec["apodization"], overlap=spec["overlap"]
            ),
        )
    elif fam in dsp.FILTERS:
        _key(path, lambda: dsp.check_filter(fam, spec.get("params"), spec.get("domain", "linear")))
    elif fam == "temporal":
        _key(
            path,
            lambda: cp.brownian_frames(
                xr.Dataset(
                    {"z": ("scatterer", [0.0]), "x": ("scatterer", [0.0])},
                    attrs={
                        "z_min": 0.0,
                        "z_max": n * float(geo["pixel_size"]),
                        "x_min": 0.0,
                        "x_max": int(geo["n_lines"]) * float(geo["pixel_size"]),
                    },
                ),
                spec["frames"],
                diffusion=spec["diffusion"],
                interval=spec["interval"],
                seed=0,
            ),
        )


def check_despeckle(cfg: Mapping) -> None:
    """What the schema cannot say about the ``despeckle`` section (``ValueError`` naming it).

    Geometry inside the image; sub-bands: ``looks`` at most the spectrum's samples, the
    windows and overlaps valid, ``frequency_compounding.n_pixels`` a multiple of every
    ``looks`` (equal sub-bands); subsets no larger than their sets; every filter parameter in
    its range (:func:`speckle.analysis.filters.check_filter`); failure methods complete.
    """
    geo = cfg["phantom"]
    _check_geometry(geo, "phantom")
    _tol(geo["method"], geo.get("tol"), "despeckle.phantom.tol", int(geo["n_pixels"]), False)
    fgeo = {**geo, **cfg["failure"]["phantom"]}
    _check_geometry(fgeo, "failure.phantom")
    _check_radii(fgeo, cfg["failure"]["feature_radius"])
    n = int(geo["n_pixels"])
    fr = cfg["physical"]["frequency"]
    for nl in fr["looks"]:
        for w in fr["apodizations"]:
            for ov in fr["overlap"]:
                _key(
                    "physical.frequency",
                    lambda nl=nl, w=w, ov=ov: cp.subband_apodizations(
                        n, nl, apodization=w, overlap=ov
                    ),
                )
    phys = cfg["physical"]
    for fam, key in (("angular", "angles"), ("spatial", "offsets")):
        size = len(phys[fam][key])
        for m in phys[fam]["sets"]:
            if m > size or (size - m) % 2:
                raise ValueError(
                    f"config key despeckle.physical.{fam}.sets: {m} central {key} of {size} "
                    f"(need sets <= {size} with the same parity)"
                )
    tm = phys["temporal"]
    if max(tm["sets"]) > tm["frames"]:
        raise ValueError(
            f"config key despeckle.physical.temporal.sets must be <= frames "
            f"({tm['frames']}); got {tm['sets']}"
        )
    for name, params in cfg["filters"].items():
        for p in parameter_grid(params):
            _key(f"filters.{name}", lambda name=name, p=p: dsp.check_filter(name, p))
    for name, spec in cfg["failure"]["methods"].items():
        _check_spec(spec, fgeo, f"failure.methods.{name}")
    fc = cfg["frequency_compounding"]
    for nl in fc["looks"]:
        _key(
            "frequency_compounding.looks", lambda nl=nl: cp.subband_apodizations(fc["n_pixels"], nl)
        )
        if fc["n_pixels"] % nl:
            raise ValueError(
                f"config key despeckle.frequency_compounding.looks: {nl} equal sub-bands need "
                f"n_pixels ({fc['n_pixels']}) to be a multiple of it"
            )
