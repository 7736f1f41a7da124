"""Load-time checks of the ``dynamics`` config section (moved from the figure module: figures
only draw). :func:`check_dynamics_config` is called by :func:`speckle.pipeline.checks.check_config`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping

import numpy as np

from .._validate import MAX_BYTES
from ..figures.dynamics import target_geometry
from ..imaging.scan import beam_reach
from ..scene.motion import MAX_STEP_FRACTION

__all__ = ["check_dynamics_config"]


# --------------------------------------------------------------------------- config checks
def _fail(key: str, message: str) -> None:
    raise ValueError(f"config key dynamics.{key} {message}")


def _check_geo(geo: Mapping, key: str) -> None:
    n, m = int(geo["n_pixels"]), int(geo.get("margin", 4))
    if 2 * m >= n - 1:
        _fail(f"{key}.margin", f"= {m} leaves fewer than 2 rows of {key}.n_pixels = {n}")


def _increasing(values, key: str) -> None:
    if any(b <= a for a, b in itertools.pairwise(values)):
        _fail(key, f"= {list(values)} must increase strictly (times and axes in order)")


def _extent(geo: Mapping, shift: float = 0.0) -> tuple[float, float]:
    """Depth and lateral extent (µm) of a target's scene."""
    p = float(geo["pixel_size"])
    pitch = float(geo.get("pitch", p))
    span = (int(geo["n_lines"]) - 1) * pitch + 2 * beam_reach(float(geo["waist"])) + pitch
    return int(geo["n_pixels"]) * p, span + shift


def _step(step: float, extent: float, key: str, what: str) -> None:
    if step > MAX_STEP_FRACTION * extent:
        _fail(
            key,
            f"moves scatterers by {step:g} µm between frames ({what}), beyond "
            f"{MAX_STEP_FRACTION:g} of the scene's {extent:g} µm extent "
            "(speckle.scene.motion refuses it): lower it or the interval",
        )


def _memory(geo: Mapping, width: float, key: str, what: str) -> None:
    """The scene a target draws (``width`` µm wide, to hold the flow) within MAX_BYTES."""
    nbytes = _scene_bytes(geo, width)
    if nbytes > MAX_BYTES:
        _fail(
            key,
            f": {what} needs a scene {width:.3g} µm wide whose scatterers would hold "
            f"~{nbytes / 2**30:.3g} GiB, above the {MAX_BYTES / 2**30:.3g} GiB limit "
            "(speckle._validate.MAX_BYTES): lower the velocity or the interval",
        )


def _scene_bytes(geo: Mapping, width: float) -> float:
    cell = float(geo["pixel_size"]) * float(geo.get("pitch", geo["pixel_size"]))
    count = float(geo["density"]) / cell * int(geo["n_pixels"]) * float(geo["pixel_size"]) * width
    return 80.0 * 4 * count  # speckle.scene.shared.SCATTERER_BYTES


def check_dynamics_config(cfg: Mapping) -> None:
    """What the schema cannot say about the ``dynamics`` section (``ValueError`` naming it).

    Geometry: margins leave rows (``tol`` against the method's floor is checked by
    :func:`speckle.figures.config_check.check_config`); windows inside the
    analysed images; velocities, intervals and SNRs in increasing order; no motion moving
    scatterers beyond :data:`speckle.scene.motion.MAX_STEP_FRACTION` of the scene in one frame
    (flow and the rms Brownian step); the phantom's cells inside layer 1 and its vessel inside
    layer 2; the dOCT delay range holding at least two lags of the series; blocks of lines for
    the standard errors; the scenes within the memory limit.
    """
    base = target_geometry(cfg)
    _check_geo(base, "geometry")
    # phantom
    ph = cfg["phantom"]
    depth, _ = _extent(base)
    width = int(base["n_lines"]) * float(base.get("pitch", base["pixel_size"]))
    iface = float(ph["interface"])
    if not 0 < iface < depth:
        _fail("phantom.interface", f"= {iface:g} must lie inside the image depth (0, {depth:g}) µm")
    cz, cx = (float(v) for v in ph["cells"]["centre"])
    r = float(ph["cells"]["radius"])
    if cz - r < 0 or cz + r > iface or cx - r < 0 or cx + r > width:
        _fail(
            "phantom.cells",
            f"(centre {[cz, cx]}, radius {r:g} µm) must lie inside layer 1 (depth 0 to "
            f"interface {iface:g} µm) and the image width (0 to {width:g} µm)",
        )
    vz, vr = float(ph["vessel"]["depth"]), float(ph["vessel"]["radius"])
    if vz - vr < iface or vz + vr > depth:
        _fail(
            "phantom.vessel",
            f"(depth {vz:g} ± radius {vr:g} µm) must lie inside layer 2 (interface {iface:g} "
            f"to {depth:g} µm)",
        )
    _, ext_x = _extent(base)
    n_rows = int(base["n_pixels"])
    for part in ("angiography", "doct"):
        dt = float(ph[part]["interval"])
        _step(
            float(ph["vessel"]["peak_velocity"]) * dt,
            ext_x,
            "phantom.vessel.peak_velocity",
            f"{part} interval {dt:g} s",
        )
        _step(
            math.sqrt(2 * float(ph["cells"]["diffusion"]) * dt),
            min(depth, ext_x),
            "phantom.cells.diffusion",
            f"rms Brownian step in the {part} interval {dt:g} s",
        )
    wz, wx = (int(w) for w in ph["window"])
    if wz > n_rows or wx > int(base["n_lines"]):
        _fail(
            "phantom.window",
            f"= {[wz, wx]} does not fit in the image ({n_rows} x {base['n_lines']})",
        )
    dc = ph["doct"]
    lags = np.arange(1, int(dc["frames"])) * float(dc["interval"])
    d0, d1 = (float(t) for t in dc["delays"])
    inside = int(np.sum((lags >= d0 * (1 - 1e-9)) & (lags <= d1 * (1 + 1e-9))))
    if d1 <= d0 or inside < 2:
        _fail(
            "phantom.doct.delays",
            f"= {[d0, d1]} s must hold at least two lags of the dOCT series (multiples of "
            f"doct.interval = {dc['interval']:g} s up to {lags[-1]:g} s); it holds {inside}",
        )
    if int(ph.get("n_bands", 4)) > n_rows:
        _fail("phantom.n_bands", f"= {ph['n_bands']} exceeds the {n_rows} spectral samples")
    # g1
    g = cfg["g1"]
    geo = target_geometry(cfg, "g1")
    _check_geo(geo, "g1.geometry")
    gd, gx = _extent(geo, float(g["velocity"]) * float(g["interval"]) * (int(g["n_frames"]) - 1))
    _step(float(g["velocity"]) * float(g["interval"]), gx, "g1.velocity", "flow")
    _step(
        math.sqrt(2 * float(g["diffusion"]) * float(g["interval"])),
        min(gd, gx),
        "g1.diffusion",
        "rms Brownian step",
    )
    _memory(geo, gx, "g1.velocity", "the flow over the series")
    if int(g["blocks"]) > int(geo["n_lines"]) // 2:
        _fail(
            "g1.blocks",
            f"= {g['blocks']}: need at least 2 lines per block (n_lines = {geo['n_lines']})",
        )
    # failure and calibration
    f = cfg["failure"]
    geo = target_geometry(cfg, "failure")
    _check_geo(geo, "failure.geometry")
    for key in ("velocities", "snr_db", "intervals"):
        _increasing(list(f[key]), f"failure.{key}")
    rows = int(geo["n_pixels"]) - 2 * int(geo.get("margin", 4))
    fz, fx = (int(w) for w in f["window"])
    if fz > rows or fx > int(geo["n_lines"]):
        _fail(
            "failure.window",
            f"= {[fz, fx]} does not fit in the analysed rows ({rows}) x lines ({geo['n_lines']})",
        )
    shift = max(f["velocities"]) * max(f["intervals"]) * (int(f["n_frames"]) - 1)
    _memory(
        geo,
        _extent(geo, shift)[1],
        "failure.velocities",
        "the fastest flow over the longest interval",
    )
    c = cfg["calibration"]
    geo = target_geometry(cfg, "calibration")
    _check_geo(geo, "calibration.geometry")
    _increasing(list(c["velocities"]), "calibration.velocities")
    shift = max(c["velocities"]) * float(c["interval"]) * (int(c["n_frames"]) - 1)
    _memory(geo, _extent(geo, shift)[1], "calibration.velocities", "the fastest flow")
