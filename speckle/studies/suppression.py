"""The speckle-suppression study's phantom and how every processed image is scored.

:func:`build_phantom` builds the phantom of a ``despeckle`` geometry section (air with point
targets, two layers whose boundary is a step edge, an inclusion), its scene, source, lines,
speckle-free truth and region masks; :func:`quality` scores a processed intensity image against
it by every metric of :data:`METRICS` (conventions in :mod:`speckle.figures.despeckle`). Moved
from ``speckle.figures.despeckle`` (issue 32): figures draw, studies build experiments.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr

from ..analysis import image_quality as iq
from ..imaging.scan import beam_reach, scan_lines
from ..imaging.truth import speckle_free_image
from ..scene import regions as rg
from ..scene.shared import shared_scene
from ..system.source import spectrum

__all__ = ["DB_RANGE", "DB_TOP", "METRICS", "build_phantom", "quality"]

#: dB window of PSNR/SSIM, relative to the truth's mean in the uniform region.
DB_TOP, DB_RANGE = 15.0, 45.0


def build_phantom(
    geo: Mapping,
    *,
    seed: int,
    density: float | None = None,
    radius: float | None = None,
    margin_angle: float = 0.0,
) -> dict:
    """The phantom of a ``despeckle`` geometry section: scene, source, lines, truth, masks.

    ``geo`` keys: ``n_pixels``, ``n_lines``, ``pixel_size`` (µm; the line pitch too),
    ``k0_dk``, ``waist`` (µm), ``density`` (scatterers per pixel cell), ``air_rows``,
    ``layer_row``, ``backscatter`` ([layer 1, layer 2]), ``inclusion`` ({row, line, radius
    (pixels), backscatter}), ``points`` ({row, lines, db: peak over the layer-1 mean}),
    ``method``, ``tol``. ``density``/``radius`` override the section's; ``margin_angle``
    (degrees) widens the drawn scene for rotated looks.
    """
    n, nl, p = int(geo["n_pixels"]), int(geo["n_lines"]), float(geo["pixel_size"])
    h = n * p
    rho = float(geo["density"] if density is None else density)
    inc = dict(geo["inclusion"])
    r_inc = float(inc["radius"] if radius is None else radius)
    w0 = float(geo["waist"])
    src = spectrum(n, h, k0_dk=float(geo["k0_dk"]))
    x = scan_lines(nl, p)
    dens = rg.cell_density(rho, p, p)
    b1, b2 = (float(v) for v in geo["backscatter"])
    z_air, z_layer = geo["air_rows"] * p, geo["layer_row"] * p
    sin = abs(np.sin(np.deg2rad(margin_angle)))
    zmax = h * (1 + sin) + p
    regions = rg.make_regions(
        rg.background(density=0.0, name="air"),
        rg.layer(z_air, zmax, density=dens, backscatter=b1, name="layer 1"),
        rg.layer(z_layer, zmax, density=dens, backscatter=b2, name="layer 2"),
        rg.circle(
            inc["row"] * p,
            inc["line"] * p,
            r_inc * p,
            density=dens,
            backscatter=float(inc["backscatter"]),
            name="inclusion",
        ),
    )
    reach = beam_reach(w0) + h * sin
    sc = shared_scene(
        regions,
        z_range=(0.0, zmax),
        x_range=(x[0] - reach, x[-1] + reach + p),
        seed=seed,
        tile=64.0 * p,
    )
    # point targets: peak intensity `db` above the layer-1 mean rho N sum S^2 w0 sqrt(pi)/(2 p)
    s2 = float(np.sum(src.values**2))
    mean1 = b1 * rho * n * s2 * w0 * np.sqrt(np.pi) / (2 * p)
    pts = geo["points"]
    amp = np.sqrt(10 ** (pts["db"] / 10) * mean1) / float(np.sum(src.values))
    zp = np.full(len(pts["lines"]), (pts["row"] + 0.3) * p)
    xp = np.asarray(pts["lines"], float) * p + 0.2 * p
    sc = xr.concat(
        [
            sc,
            xr.Dataset(
                {
                    "z": ("scatterer", zp),
                    "x": ("scatterer", xp),
                    "amplitude": ("scatterer", np.full(zp.size, amp + 0j)),
                    "region": ("scatterer", np.full(zp.size, -1, sc.region.dtype)),
                }
            ),
        ],
        dim="scatterer",
        data_vars="all",
        combine_attrs="override",
    )
    sc = sc.isel(scatterer=np.argsort(sc.x.values, kind="stable"))
    kw = {"waist": w0, "lines": x, "method": geo["method"], "tol": geo["tol"]}
    truth = speckle_free_image(sc, src, **kw).values
    labels = rg.rasterize(regions, np.arange(n) * p, x)
    rows, cols = np.mgrid[0:n, 0:nl]
    d_inc = np.hypot(rows - inc["row"], cols - inc["line"])
    a, lr = int(geo["air_rows"]), int(geo["layer_row"])
    gap = max(1, min(6, (lr - a) // 4))  # rows kept clear of the layer-1 boundaries
    half = max(2, min(12, (lr - a) // 2, (n - lr) // 2))  # half-height of the edge window
    masks = {
        "uniform": (rows >= a + gap) & (rows < lr - gap),
        "inclusion": d_inc <= max(0.5 * r_inc, 1.0),
        "background": (d_inc >= r_inc + 4) & (d_inc <= r_inc + 10) & (rows > lr + 4),
    }
    ref = float(truth[masks["uniform"]].mean())
    return {
        "geo": geo,
        "source": src,
        "scene": sc,
        "x": x,
        "truth": truth,
        "labels": labels,
        "masks": masks,
        "ref": ref,
        "kw": kw,
        "pixel": p,
        "points": pts,
        "edge_rows": (lr - half, lr + half),
        "regions": regions,
        # lines clear of the inclusion where it reaches into the edge window
        "edge_lines": (np.abs(np.arange(nl) - inc["line"]) > r_inc + 2)
        | (inc["row"] - r_inc - 2 >= lr + half),
    }


def _point_fwhm(img: np.ndarray, ph: dict) -> tuple[float, float]:
    """Mean axial and lateral FWHM (µm) of the point targets (linear intensity)."""
    pts, p = ph["points"], ph["pixel"]
    ax, lat = [], []
    for line in pts["lines"]:
        r0, c0 = int(pts["row"]), int(line)
        win = img[max(r0 - 6, 0) : r0 + 7, max(c0 - 10, 0) : c0 + 11]
        i, j = np.unravel_index(np.argmax(win), win.shape)
        ax.append(iq.peak_fwhm(win[:, j], p))
        lat.append(iq.peak_fwhm(win[i, :], p))
    return _finite_mean(ax), _finite_mean(lat)


def _finite_mean(values: list[float]) -> float:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else np.nan


def quality(intensity: np.ndarray, ph: dict, *, edge: bool = True) -> dict:
    """Every metric of one processed intensity image of phantom ``ph`` (module docstring).

    ``edge``: also the step-edge width and its standard error from 4 blocks of lines (NaN
    otherwise; the failure map does not use them).
    """
    m = ph["masks"]
    img = np.asarray(intensity, float)
    img = img * ph["ref"] / max(float(img[m["uniform"]].mean()), 1e-300)
    db = iq.to_db(img, ph["ref"])
    tdb = iq.to_db(ph["truth"], ph["ref"])
    fa, fl = _point_fwhm(img, ph)
    e0, e1 = ph["edge_rows"]
    band = img[e0:e1, ph["edge_lines"]]
    width, se = np.nan, np.nan
    if edge:
        width = iq.edge_width(band.mean(axis=1), ph["pixel"])
        parts = np.array_split(band, 4, axis=1)
        blocks = np.array([iq.edge_width(b.mean(axis=1), ph["pixel"]) for b in parts])
        if np.isfinite(blocks).sum() > 1:
            se = float(np.nanstd(blocks, ddof=1) / np.sqrt(np.isfinite(blocks).sum()))
    inc = db[m["inclusion"]].mean() - db[m["background"]].mean()
    tinc = tdb[m["inclusion"]].mean() - tdb[m["background"]].mean()
    return {
        "contrast": iq.contrast(img, m["uniform"]),
        "enl": iq.enl(img, m["uniform"]),
        "cnr": iq.cnr(db, m["inclusion"], m["background"]),
        "psnr": iq.psnr_db(db, tdb, db_top=DB_TOP, db_range=DB_RANGE),
        "ssim": iq.ssim_db(db, tdb, db_top=DB_TOP, db_range=DB_RANGE),
        "fwhm_axial": fa,
        "fwhm_lateral": fl,
        "edge_width": width,
        "edge_width_se": se,
        "feature_retained": float(inc / tinc) if tinc != 0 else np.nan,
    }


#: metric -> (its quantity in :data:`speckle.conventions.QUANTITIES`, long name)
METRICS = {
    "contrast": ("contrast", "speckle contrast std/mean in the uniform region"),
    "enl": ("dimensionless", "equivalent number of looks mean^2/var in the uniform region"),
    "cnr": ("dimensionless", "contrast-to-noise ratio inclusion/background (dB images)"),
    "psnr": ("level", "PSNR against the truth (dB images)"),
    "ssim": ("dimensionless", "SSIM against the truth (dB images)"),
    "fwhm_axial": ("length", "axial FWHM of the point targets"),
    "fwhm_lateral": ("length", "lateral FWHM of the point targets"),
    "edge_width": ("length", "10-90 % width of the layer step edge"),
    "edge_width_se": ("length", "standard error of edge_width (4 blocks of lines)"),
    "feature_retained": ("dimensionless", "inclusion contrast (dB) kept, over the truth's"),
}
