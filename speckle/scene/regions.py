"""Regions of a shared scene: layers, ellipses (circles, ellipsoids) or a label image.

A set of regions is an ``xarray.Dataset`` with dim ``region`` (integer labels ``0 ... R-1``):
one row per region holding its geometry and its properties. Geometry is painted in order:
a point belongs to the *last* region whose shape contains it (so a background first, then
layers, then inclusions). A point that no region contains gets label ``-1`` and holds no
scatterers.

Shapes (variable ``shape``):

* ``"background"`` -- everywhere;
* ``"layer"`` -- depths ``z_top <= z < z_bottom`` (µm), all lateral positions;
* ``"ellipse"`` -- ``((z - centre_z)/radius_z)^2 + ((x - centre_x)/radius_x)^2
  [+ ((y - centre_y)/radius_y)^2] <= 1`` (µm); in a 3-D scene an ellipse without ``centre_y``
  is a cylinder along ``y``; in a 2-D scene (no ``y``) the ``y`` term is left out;
* a label image (:func:`from_label_image`): a variable ``label_image`` over ``(depth, x)``
  (pixel centres in µm); a point takes the label of its nearest pixel (``-1`` outside the
  image). This is the form the FEM mechanics uses.

Properties (one value per region; the scene generator uses the first three):

================  ============  ===========================================================
variable          units         meaning
================  ============  ===========================================================
density           um^-d         mean number of scatterers per µm^2 (2-D scene) or per µm^3
                                (3-D scene): a Poisson point process of this intensity
amplitude_model   --            one of :data:`speckle.scene.scatterers.AMPLITUDE_MODELS`
                                (normalised to E|a|^2 = 1)
backscatter       1             mean backscatter E|a|^2 of the region (amplitudes are scaled
                                by its square root)
attenuation       1/um          attenuation coefficient (default 0; used by system effects)
depolarization    1             cross-polarized fraction in [0, 1] (default 0)
youngs_modulus    kPa           Young's modulus (default 10, soft tissue; used by mechanics,
                                whose :func:`~speckle.scene.mechanics.compress_phantom` takes kPa);
                                values above :data:`MAX_MODULUS_KPA` are refused as given in Pa
poisson_ratio     1             Poisson ratio (default 0.45)
================  ============  ===========================================================

Extra numeric properties can be added as keywords; every region gets the column (NaN where
not given). :func:`cell_density` converts "scatterers per pixel x pitch [x pitch] cell" (the
paper's density per pixel, extended laterally) to the number density used here.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from .._validate import as_finite_array, check_choice, check_int, check_real
from ..conventions import attrs, coord, spacing
from .scatterers import AMPLITUDE_MODELS

__all__ = [
    "DEFAULTS",
    "MAX_MODULUS_KPA",
    "SHAPES",
    "background",
    "bounding_box",
    "cell_density",
    "check_modulus",
    "circle",
    "compile_regions",
    "ellipse",
    "from_label_image",
    "labels_of",
    "layer",
    "make_regions",
    "rasterize",
    "region_label",
]

SHAPES = ("background", "layer", "ellipse", "image")

#: Largest Young's modulus accepted, kPa (1 GPa; soft tissue, cartilage and elastography phantoms
#: are 0.1-1000 kPa). The package's one unit of modulus is kPa: a Pa value of a stiff material
#: (above 1 MPa) lands above the cap and is refused; tables carry ``units = "kPa"``, which
#: :func:`~speckle.scene.mechanics.compress_phantom` checks when given a DataArray.
MAX_MODULUS_KPA = 1.0e6

#: Default value of every property column other than density (units as in the module table).
DEFAULTS: dict[str, object] = {
    "amplitude_model": "rayleigh",
    "backscatter": 1.0,
    "attenuation": 0.0,
    "depolarization": 0.0,
    "youngs_modulus": 10.0,
    "poisson_ratio": 0.45,
}

#: property -> (its quantity in :data:`speckle.conventions.QUANTITIES`, long name)
_PROPERTIES = {
    "density": ("scene_density", "scatterers per um^2 (2-D) or um^3 (3-D)"),
    "backscatter": ("dimensionless", "mean backscatter E|a|^2"),
    "attenuation": ("attenuation", "attenuation coefficient"),
    "depolarization": ("dimensionless", "depolarisation ratio"),
    "youngs_modulus": ("modulus", "Young's modulus"),
    "poisson_ratio": ("dimensionless", "Poisson ratio"),
}
_GEOMETRY = (
    "z_top",
    "z_bottom",
    "centre_z",
    "centre_x",
    "centre_y",
    "radius_z",
    "radius_x",
    "radius_y",
)


def cell_density(per_cell: float, pixel_size: float, pitch: float, ndim: int = 2) -> float:
    """Number density (µm^-2 or µm^-3) of ``per_cell`` scatterers per pixel x pitch [x pitch] cell.

    Parameters
    ----------
    per_cell : float
        Mean scatterers per cell (>= 0).
    pixel_size, pitch : float
        Pixel size ``H/N`` and line pitch in µm (> 0).
    ndim : {2, 3}
        Scene dimension: the cell is ``pixel_size*pitch`` µm^2 or ``pixel_size*pitch^2`` µm^3.
    """
    rho = check_real(per_cell, "per_cell", low=0)
    p = check_real(pixel_size, "pixel_size", low=0, low_inclusive=False)
    d = check_real(pitch, "pitch", low=0, low_inclusive=False)
    nd = check_int(ndim, "ndim", low=2, high=3)
    return rho / (p * d ** (nd - 1))


def check_modulus(value: object, name: str = "youngs_modulus") -> float:
    """A Young's modulus in kPa: finite, > 0 and at most :data:`MAX_MODULUS_KPA`.

    Raises
    ------
    TypeError
        If ``value`` is not a real number.
    ValueError
        Naming ``name``, if it is out of range (a value above the cap is most likely in Pa).
    """
    e = check_real(value, name, low=0, low_inclusive=False)
    if e > MAX_MODULUS_KPA:
        raise ValueError(
            f"{name} = {e:g} kPa is above {MAX_MODULUS_KPA:g} kPa (1 GPa): moduli are in kPa "
            f"throughout speckle; a value in Pa must be divided by 1000 ({e / 1e3:g} kPa)"
        )
    return e


def _properties(density: float, props: Mapping) -> dict:
    out = {"density": check_real(density, "density", low=0)}
    for name, value in {**DEFAULTS, **props}.items():
        if name == "amplitude_model":
            out[name] = check_choice(value, "amplitude_model", AMPLITUDE_MODELS)
        elif name == "name":
            if not isinstance(value, str):
                raise TypeError(f"name must be a string, got {type(value).__name__}")
            out[name] = value
        elif name in ("backscatter", "attenuation"):
            out[name] = check_real(value, name, low=0)
        elif name == "depolarization":
            out[name] = check_real(value, name, low=0, high=1)
        elif name == "youngs_modulus":
            out[name] = check_modulus(value, name)
        elif name == "poisson_ratio":
            out[name] = check_real(value, name, low=-1.0, high=0.5, low_inclusive=False)
        else:
            out[name] = check_real(value, name)
    return out


def background(*, density: float, **props: object) -> dict:
    """A region covering the whole scene (paint it first); ``props`` as in the module table."""
    return {"shape": "background", **_properties(density, props)}


def layer(z_top: float, z_bottom: float, *, density: float, **props: object) -> dict:
    """A layer ``z_top <= z < z_bottom`` (µm) over all lateral positions."""
    top = check_real(z_top, "z_top")
    bottom = check_real(z_bottom, "z_bottom")
    if bottom <= top:
        raise ValueError(
            f"z_bottom must be below z_top (z_top < z_bottom), got {top:g}, {bottom:g}"
        )
    return {"shape": "layer", "z_top": top, "z_bottom": bottom, **_properties(density, props)}


def ellipse(
    centre_z: float,
    centre_x: float,
    radius_z: float,
    radius_x: float,
    *,
    density: float,
    centre_y: float | None = None,
    radius_y: float | None = None,
    **props: object,
) -> dict:
    """An ellipse (2-D) or ellipsoid (3-D, with ``centre_y``/``radius_y``), all in µm.

    Without ``centre_y`` it is, in a 3-D scene, an elliptic cylinder along ``y``.
    """
    geo = {
        "centre_z": check_real(centre_z, "centre_z"),
        "centre_x": check_real(centre_x, "centre_x"),
        "radius_z": check_real(radius_z, "radius_z", low=0, low_inclusive=False),
        "radius_x": check_real(radius_x, "radius_x", low=0, low_inclusive=False),
    }
    if (centre_y is None) != (radius_y is None):
        raise ValueError("centre_y and radius_y must be given together (an ellipsoid) or neither")
    if centre_y is not None:
        geo["centre_y"] = check_real(centre_y, "centre_y")
        geo["radius_y"] = check_real(radius_y, "radius_y", low=0, low_inclusive=False)
    return {"shape": "ellipse", **geo, **_properties(density, props)}


def circle(
    centre_z: float,
    centre_x: float,
    radius: float,
    *,
    density: float,
    centre_y: float | None = None,
    **props: object,
) -> dict:
    """A circle (2-D) or a sphere (3-D, with ``centre_y``) of ``radius`` µm."""
    ry = None if centre_y is None else radius
    return ellipse(
        centre_z,
        centre_x,
        radius,
        radius,
        density=density,
        centre_y=centre_y,
        radius_y=ry,
        **props,
    )


def _table(rows: list[dict]) -> xr.Dataset:
    """The ``region`` Dataset of property/geometry rows (missing numbers NaN)."""
    names: list[str] = []
    for r in rows:
        names += [k for k in r if k not in names]
    data = {}
    for name in names:
        values = [r.get(name) for r in rows]
        if name in ("shape", "amplitude_model", "name"):
            fill = {"name": "", "amplitude_model": DEFAULTS["amplitude_model"]}.get(name, "")
            arr = np.array([fill if v is None else v for v in values], dtype=object).astype(str)
        else:
            arr = np.array([np.nan if v is None else v for v in values], dtype=float)
        if name in _PROPERTIES:
            data[name] = ("region", arr, attrs(*_PROPERTIES[name]))
        else:
            data[name] = (
                "region",
                arr,
                attrs("dimensionless" if name not in _GEOMETRY else "length", name),
            )
    for name in _GEOMETRY:
        if name not in data:
            data[name] = ("region", np.full(len(rows), np.nan), attrs("length", name))
    return xr.Dataset(
        data,
        coords={"region": coord("region", np.arange(len(rows)))},
    )


def make_regions(*shapes: Mapping) -> xr.Dataset:
    """Regions from shapes painted in order (later shapes cover earlier ones).

    Parameters
    ----------
    *shapes : dict
        Results of :func:`background`, :func:`layer`, :func:`ellipse`, :func:`circle`.

    Returns
    -------
    xarray.Dataset
        Dim ``region`` (labels ``0 ... R-1`` in the given order), geometry and properties.

    Raises
    ------
    ValueError
        If no shape is given or a shape is not one made by this module.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.circle(100.0, 50.0, 20.0, density=0.2)
    ... )
    >>> regions.sizes["region"], [float(d) for d in regions.density.values]
    (2, [0.05, 0.2])
    """
    if not shapes:
        raise ValueError("regions need at least one shape (e.g. background(density=...))")
    rows = []
    for i, s in enumerate(shapes):
        if not isinstance(s, Mapping) or s.get("shape") not in SHAPES[:3]:
            raise ValueError(
                f"shape {i} must come from background(), layer(), ellipse() or circle(); got {s!r}"
            )
        rows.append(dict(s))
    return _table(rows)


def from_label_image(labels: xr.DataArray, properties: list[Mapping]) -> xr.Dataset:
    """Regions given by an integer label image over ``(depth, x)`` (e.g. from a FEM mesh).

    Parameters
    ----------
    labels : xarray.DataArray
        Integer labels ``0 ... R-1`` (or ``-1`` for "no region") with dims ``(depth, x)`` and
        uniformly spaced coordinates at pixel centres in µm.
    properties : list of dict
        One entry per label: ``{"density": ..., **props}`` as for :func:`background`.

    Returns
    -------
    xarray.Dataset
        Dim ``region`` with properties (shape ``"image"``) plus the variable ``label_image``.
    """
    if not isinstance(labels, xr.DataArray) or set(labels.dims) != {"depth", "x"}:
        raise ValueError("labels must be an xarray.DataArray with dims (depth, x) in µm")
    img = labels.transpose("depth", "x")
    for d in ("depth", "x"):
        spacing(img, d)  # uniform, increasing coordinates in µm
    values = np.asarray(img.values)
    if values.dtype.kind not in "iu":
        raise TypeError(f"labels must hold integers, got dtype {values.dtype}")
    r = len(properties)
    if r == 0:
        raise ValueError("properties must list at least one region")
    if values.min() < -1 or values.max() >= r:
        raise ValueError(
            f"labels must lie in [-1, {r - 1}] (one properties entry per label); "
            f"got [{values.min()}, {values.max()}]"
        )
    rows = []
    for i, p in enumerate(properties):
        p = dict(p)
        if "density" not in p:
            raise ValueError(f"properties[{i}] needs a 'density'")
        rows.append({"shape": "image", **_properties(p.pop("density"), p)})
    out = _table(rows)
    out["label_image"] = (
        ("depth", "x"),
        values.astype(np.int32),
        attrs("label"),
    )
    return out.assign_coords(depth=coord("depth", img.depth.values), x=coord("x", img.x.values))


def _check_regions(regions: xr.Dataset) -> None:
    if not isinstance(regions, xr.Dataset) or "region" not in regions.dims:
        raise TypeError("regions must be an xarray.Dataset with dim 'region' (see make_regions)")
    if regions.sizes["region"] == 0:
        raise ValueError("regions must hold at least one region")
    if not np.array_equal(regions.region.values, np.arange(regions.sizes["region"])):
        raise ValueError("region labels must be 0 ... R-1 in order")


def compile_regions(regions: xr.Dataset) -> list[dict]:
    """Plain-Python view of ``regions`` (one dict per region) for fast repeated lookups.

    Each dict holds ``shape``, ``density``, ``amplitude_model``, ``backscatter``, the geometry
    (floats, NaN where unused), ``box`` (:func:`bounding_box`) and, for label images,
    ``image`` (int32 array), ``origin`` and ``step`` (µm, ``(depth, x)``).
    """
    _check_regions(regions)
    out = []
    image = None
    if "label_image" in regions:
        img = regions.label_image.transpose("depth", "x")
        image = {
            "image": np.asarray(img.values, dtype=np.int32),
            "origin": (float(img.depth.values[0]), float(img.x.values[0])),
            "step": (spacing(img, "depth"), spacing(img, "x")),
        }
    for r in range(regions.sizes["region"]):
        row = {
            name: regions[name].values[r].item()
            for name in ("shape", "density", "amplitude_model", "backscatter", *_GEOMETRY)
        }
        row["shape"] = str(row["shape"])
        row["amplitude_model"] = str(row["amplitude_model"])
        row["box"] = _box(row, image)
        if image is not None:
            row.update(image)
        out.append(row)
    return out


def _box(row: dict, image: dict | None) -> dict[str, tuple[float, float]]:
    inf = (-np.inf, np.inf)
    box = {"z": inf, "x": inf, "y": inf}
    if row["shape"] == "layer":
        box["z"] = (row["z_top"], row["z_bottom"])
    elif row["shape"] == "ellipse":
        for ax in ("z", "x", "y"):
            c, rad = row[f"centre_{ax}"], row[f"radius_{ax}"]
            if np.isfinite(c):
                box[ax] = (c - rad, c + rad)
    elif row["shape"] == "image":
        nz, nx = image["image"].shape
        for i, ax in enumerate(("z", "x")):
            o, st = image["origin"][i], image["step"][i]
            box[ax] = (o - st / 2, o + ((nz, nx)[i] - 0.5) * st)
    return box


def labels_of(
    compiled: list[dict], z: np.ndarray, x: np.ndarray, y: np.ndarray | None = None
) -> np.ndarray:
    """:func:`region_label` on compiled regions (:func:`compile_regions`), no checks."""
    out = np.full(z.shape, -1, dtype=np.int32)
    if compiled and compiled[0]["shape"] == "image":
        first = compiled[0]
        iz = np.floor((z - first["origin"][0]) / first["step"][0] + 0.5).astype(np.int64)
        ix = np.floor((x - first["origin"][1]) / first["step"][1] + 0.5).astype(np.int64)
        nz, nx = first["image"].shape
        inside = (iz >= 0) & (iz < nz) & (ix >= 0) & (ix < nx)
        out[inside] = first["image"][iz[inside], ix[inside]]
        return out
    for r, row in enumerate(compiled):
        shape = row["shape"]
        if shape == "background":
            out[...] = r
            continue
        if shape == "layer":
            inside = (z >= row["z_top"]) & (z < row["z_bottom"])
        else:
            axes = ["z", "x"]
            if y is not None and np.isfinite(row["centre_y"]):
                axes.append("y")
            pts = [{"z": z, "x": x, "y": y}[a] for a in axes]
            centre = [row[f"centre_{a}"] for a in axes]
            radii = [row[f"radius_{a}"] for a in axes]
            inside = in_ellipse(pts, centre, radii)
        out[inside] = r
    return out


def in_ellipse(points: Sequence[np.ndarray], centre: Sequence[float], radii: Sequence[float]):
    """Whether points lie in the closed ellipse (ellipsoid) ``sum ((p - c)/r)^2 <= 1``.

    ``points``: one array per axis (µm, broadcast together), with ``centre`` and semi-axes
    ``radii`` (µm) in the same order. The one inside test of regions and label images.
    """
    q = sum(((p - c) / r) ** 2 for p, c, r in zip(points, centre, radii, strict=True))
    return q <= 1.0


def region_label(regions: xr.Dataset, z: object, x: object, y: object | None = None) -> np.ndarray:
    """Region label of each point (``-1`` where no region holds it).

    Parameters
    ----------
    regions : xarray.Dataset
        From :func:`make_regions` or :func:`from_label_image`.
    z, x : array_like
        Depths and lateral positions in µm (same shape).
    y : array_like, optional
        Second lateral coordinate in µm for 3-D scenes (same shape); label images and 2-D
        shapes ignore it.

    Returns
    -------
    numpy.ndarray
        int32 labels, shape of ``z``.

    Examples
    --------
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.layer(100.0, 200.0, density=0.1, attenuation=0.002)
    ... )
    >>> speckle.region_label(regions, [50.0, 150.0, 250.0], [0.0, 0.0, 0.0])
    array([0, 1, 0], dtype=int32)
    """
    compiled = compile_regions(regions)
    zz = as_finite_array(z, "z")
    xx = as_finite_array(x, "x")
    yy = None if y is None else as_finite_array(y, "y")
    if zz.shape != xx.shape or (yy is not None and yy.shape != zz.shape):
        raise ValueError(
            f"z, x (and y) must have the same shape, got {zz.shape}, {xx.shape}"
            + ("" if yy is None else f", {yy.shape}")
        )
    return labels_of(compiled, zz, xx, yy)


def bounding_box(regions: xr.Dataset, r: int) -> dict[str, tuple[float, float]]:
    """Axis-aligned box (µm) outside which region ``r`` holds no point (``±inf`` = unbounded).

    Returns ``{"z": (lo, hi), "x": (lo, hi), "y": (lo, hi)}``; the scene generator draws each
    region's Poisson points only inside its box (exact: points outside would be rejected).
    """
    _check_regions(regions)
    if not isinstance(r, numbers.Integral) or not 0 <= r < regions.sizes["region"]:
        raise ValueError(f"r must be a region label in [0, {regions.sizes['region'] - 1}]")
    return compile_regions(regions)[int(r)]["box"]


def rasterize(regions: xr.Dataset, depth_coord: object, x_coord: object) -> xr.DataArray:
    """Label image of ``regions`` sampled at pixel centres.

    Parameters
    ----------
    regions : xarray.Dataset
        From :func:`make_regions` or :func:`from_label_image`.
    depth_coord, x_coord : array_like or xarray.DataArray
        1-D pixel-centre depths and lateral positions in µm.

    Returns
    -------
    xarray.DataArray
        int32 labels with dims ``(depth, x)`` and those coordinates (``-1``: no region), the
        input the FEM mechanics takes.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> from speckle.scene import regions as R
    >>> regions = speckle.make_regions(
    ...     R.background(density=0.05), R.layer(100.0, 200.0, density=0.1, attenuation=0.002)
    ... )
    >>> labels = speckle.rasterize(regions, np.array([50.0, 150.0, 250.0]), np.array([0.0, 10.0]))
    >>> labels.dims, labels.values[:, 0]
    (('depth', 'x'), array([0, 1, 0], dtype=int32))
    """
    d = as_finite_array(depth_coord, "depth_coord")
    xs = as_finite_array(x_coord, "x_coord")
    if d.ndim != 1 or xs.ndim != 1 or d.size == 0 or xs.size == 0:
        raise ValueError("depth_coord and x_coord must be non-empty 1-D coordinates in µm")
    zz, xx = np.meshgrid(d, xs, indexing="ij")
    labels = region_label(regions, zz, xx)
    return xr.DataArray(
        labels,
        dims=("depth", "x"),
        coords={"depth": coord("depth", d), "x": coord("x", xs)},
        name="region",
        attrs=attrs("label", "region label (-1: none)"),
    )
