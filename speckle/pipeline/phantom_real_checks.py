"""The ``phantom_real`` section's checks, run when the workflow loads (``ValueError`` naming the
key): every image to fit is named in ``images``, its file exists and its rows, noise rows and
lines lie inside it with the sizes :func:`speckle.equivalent_system` needs.
:func:`speckle.pipeline.checks.check_config` calls :func:`check_phantom_real`."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping

import numpy as np

from ..conventions import canonical_keys
from ..io import load_image

__all__ = ["check_phantom_real"]

#: Fewest rows fitted, noise rows, and lines (the twin's waist: 16 blocks x (8 lags + 2)).
MIN_ROWS, MIN_NOISE_ROWS, MIN_LINES_TWIN, MIN_LINES = 32, 4, 160, 64


def _shape(cfg: Mapping, key: str) -> tuple[int, int]:
    """``(depth, x)`` of the image (an ``.npy`` memory-mapped, not read)."""
    path = cfg["image"]
    if not os.path.exists(path):
        raise ValueError(f"config key {key}.image = {path!r}: no such file (relative to the repo)")
    dims = cfg.get("dims")
    if str(path).endswith(".npy") and dims is not None:
        shape = np.load(path, mmap_mode="r").shape
        names = list(canonical_keys(dict.fromkeys(dims), f"config key {key}.dims"))
        if len(names) != len(shape):
            raise ValueError(
                f"config key {key}.dims = {list(dims)} does not name the {len(shape)} axes of "
                f"{path} (shape {shape})"
            )
        return shape[names.index("depth")], shape[names.index("x")]
    da = load_image(path, kind=cfg["kind"], pixel_size=cfg.get("pixel_size"),
                    pitch=cfg.get("pitch"), dims=None if dims is None else tuple(dims))  # fmt: skip
    return da.sizes["depth"], da.sizes["x"]


def _pair(cfg: Mapping, key: str, name: str, n: int, least: int) -> tuple[int, int]:
    value = cfg[name]
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        raise ValueError(f"config key {key}.{name} = {value!r} must be two integers")
    lo, hi = value
    if not (0 <= lo < hi <= n and hi - lo >= least):
        raise ValueError(
            f"config key {key}.{name} = {list(value)} must be a half-open range inside the "
            f"image (0..{n}) holding at least {least}"
        )
    return lo, hi


def check_phantom_real(cfg: Mapping) -> None:
    """What the schema cannot say about the ``phantom_real`` section (``ValueError`` naming it).

    Each name of ``fit`` is a key of ``images``; each such image exists, its ``rows`` (>= 32),
    ``noise_rows`` (>= 4, not overlapping ``rows``) and ``lines`` (>= 160 when the beam radius
    comes from the twin, else >= 64) lie inside it; ``beam_radius`` is finite.
    """
    images = cfg["images"]
    for name in cfg["fit"]:
        if name not in images:
            raise ValueError(
                f"config key phantom_real.fit names {name!r}, not a key of phantom_real.images "
                f"({sorted(images)})"
            )
    for name, image in images.items():
        key = f"phantom_real.images.{name}"
        nz, nx = _shape(image, key)
        a, b = _pair(image, key, "rows", nz, MIN_ROWS)
        na, nb = _pair(image, key, "noise_rows", nz, MIN_NOISE_ROWS)
        if na < b and nb > a:
            raise ValueError(
                f"config key {key}.noise_rows = {[na, nb]} overlaps {key}.rows = {[a, b]}: "
                "signal-free rows must lie outside the fitted tissue"
            )
        radius = image.get("beam_radius")
        least = MIN_LINES_TWIN if radius is None else MIN_LINES
        _pair(image, key, "lines", nx, least)
        if radius is not None and not (
            isinstance(radius, int | float)
            and not isinstance(radius, bool)
            and math.isfinite(radius)
        ):
            raise ValueError(
                f"config key {key}.beam_radius = {radius!r} must be a finite number > 0 µm or null"
            )
