"""The ``synthoct`` section's checks, run when the workflow loads (``ValueError`` naming the
key): the batch's images fit in the published reference scan and hold the contrast window; its
boundaries lie inside the phantom. :func:`speckle.pipeline.checks.check_config` calls
:func:`check_synthoct`."""

from __future__ import annotations

from collections.abc import Mapping

from ..figures.synthoct import published_scan
from ..synthoct.files import ScannerConfig

__all__ = ["check_synthoct"]


def check_synthoct(cfg: Mapping) -> None:
    """What the schema cannot say about the ``synthoct`` section (``ValueError`` naming it).

    The batch's images fit in the published reference scan (256 x 512), hold the contrast
    window (at least 21 pixels a side); its boundaries lie inside the phantom's depth.
    """
    b = cfg["batch"]
    reference = published_scan(b["reference"])
    limit = dict(zip(("n_pixels", "n_lines"), reference.shape, strict=True))
    for key, most in limit.items():
        if not 21 <= int(b[key]) <= most:
            raise ValueError(
                f"config key synthoct.batch.{key} = {b[key]!r} must lie in 21..{most} (the "
                f"contrast window + 1 up to the reference scan's size)"
            )
    depth = int(b["n_pixels"]) * ScannerConfig().pixel_size
    for end in ("start", "stop"):
        z = float(b["boundary"][end])
        if not 0.0 < z < depth:
            raise ValueError(
                f"config key synthoct.batch.boundary.{end} = {z!r} must lie inside the phantom "
                f"(0 < boundary < n_pixels x 6 = {depth:g} µm)"
            )
