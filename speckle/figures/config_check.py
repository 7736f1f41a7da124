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
* the scan table: at least one row, no duplicate rows, densities above the floor.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from .._validate import MAX_BYTES

__all__ = ["check_config", "check_scan_table", "check_twin", "figure_bytes"]

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
        ("aline", n_alines, f"{key.split('.')[0]}.n_alines"),
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
    if "despeckle" in config:
        from .despeckle import check_despeckle_config

        check_despeckle_config(config["despeckle"])
    if "twin" in config:
        check_twin(config["twin"])


def _elastography(el: Mapping) -> None:
    """Estimator windows inside the images they slide over (depth >= 2 pixels)."""
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
    for i, w in enumerate(el.get("failure", {}).get("windows", [])):
        if not 2 <= int(w) <= n:
            raise ValueError(
                f"config key elastography.failure.windows[{i}] = {w} must be in [2, "
                f"elastography.n_pixels = {n}]"
            )
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
    for axis, dim in enumerate(("depth", "aline")):
        bounds = roi.get(dim) or [None, None]
        for b in bounds:
            if b is not None and len(shape) == 2 and b > shape[axis]:
                raise ValueError(
                    f"config key fig4.measured.roi.{dim} = {bounds} lies outside the measured "
                    f"image of shape {tuple(shape)} (depth, aline)"
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
        shape = np.load(path, mmap_mode="r").shape
        names = ["x" if d == "aline" else d for d in dims]
        if len(names) != len(shape):
            raise ValueError(
                f"config key twin.dims = {list(dims)} does not name the {len(shape)} axes of "
                f"{path} (shape {shape})"
            )
        return shape[names.index("depth")], shape[names.index("x")]
    from ..analysis.image_files import load_image

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
    fc = cfg["failure"]
    window = fc.get("window")
    if window is not None and (window[0] > fc["shape"][0] or window[1] > fc["shape"][1]):
        raise ValueError(
            f"config key twin.failure.window = {window} does not fit in twin.failure.shape = "
            f"{fc['shape']}"
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
