"""Phantoms of known stiffness compressed by a flat probe: 2-D plane-strain finite elements.

A phantom is an integer label image over ``(depth, x)`` (coordinates in µm, pixel centres) with
a Young's modulus (kPa) and a Poisson ratio per label. :func:`compress_phantom` solves 2-D
plane-strain
linear elasticity for it with scikit-fem (bilinear quadrilaterals, one or more per label pixel)
and returns the displacement, strain and stress fields on the label grid, in the project's
conventions (those of :func:`speckle.uniaxial_strain`):

* ``z`` is depth (µm, increasing into the sample), the flat rigid probe is the plane ``z = 0``
  and is held fixed (the OCT frame moves with the probe); the sample rests on a flat rigid base
  at its far side ``z = L``, which moves towards the probe by ``strain * L``. A homogeneous block
  therefore has ``u_z = -strain * z`` exactly, as in :func:`speckle.uniaxial_strain`.
* Displacements ``uz``, ``ux`` point along ``+z`` (deeper) and ``+x``; compression gives
  ``uz < 0``.
* Strains and stresses are reported with the sign flipped (compression positive, like the
  ``strain`` of :func:`speckle.uniaxial_strain`): ``strain_ij = -eps_ij`` and
  ``stress_ij = -sigma_ij``, where ``eps``/``sigma`` are the usual tensile-positive small-strain
  and Cauchy stress tensors (``eps_xz`` is the tensor, not the engineering, shear strain).

Boundary conditions (:func:`compress_phantom`): lateral sides traction-free;
``contact="bonded"``: the
probe and base hold both displacement components (no lateral slip); ``contact="sliding"``:
they prescribe only ``u_z`` (frictionless), and the lateral rigid-body translation is fixed by
``u_x = 0`` at the probe centre ``(z, x) = (0, x_centre)``.

Plane strain (``eps_yy = 0`` out of the image plane): the plane-strain modulus is
``E' = E / (1 - nu**2)`` and a block free to expand laterally has
``eps_xx = -nu / (1 - nu) * eps_zz``. ``nu = 0.5`` is refused: the Lamé parameter
``lambda = E nu / ((1 + nu)(1 - 2 nu))`` is infinite (a displacement formulation cannot represent
an incompressible solid). Near 0.5 plain bilinear elements lock (spurious volumetric
stiffness; for a circular inclusion of radius 16 pixels the strain is 4 % off at nu = 0.499 and
79 % off at 0.49999). :func:`compress_phantom` integrates the volumetric term
``lambda div u div v`` at
the element centre (selective reduced integration, the B-bar method on rectangles), which
removes the locking (0.4 % at both, as at nu = 0.3). Up to 0.49999 is accepted; there the
stresses (not the strains) show a small checkerboard (the Q1/P0 pressure mode, ~1 % of the
axial stress at nu = 0.49999).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence

import numpy as np
import skfem as fem
import xarray as xr
from scipy.interpolate import RegularGridInterpolator
from scipy.sparse.linalg import splu
from skfem.helpers import ddot, div, sym_grad
from skfem.models.elasticity import lame_parameters

from speckle._deprecate import moved
from speckle._validate import (
    as_finite_array,
    broadcast,
    check_choice,
    check_int,
    check_memory,
    check_real,
)
from speckle.conventions import attrs, canonical_dims, coord, units_of
from speckle.scene.regions import check_modulus, in_ellipse

__all__ = [
    "CONTACTS",
    "compress_phantom",
    "displacement_at",
    "fem_bytes",
    "inclusion_labels",
    "inclusion_strain",
    "layer_strains",
    "layered_labels",
]

#: ``compress`` (retired, :data:`speckle.conventions.RETIRED`) is now ``compress_phantom``.
__getattr__ = moved(__name__, __name__, [], {"compress": "compress_phantom"})

#: Probe/base contact conditions accepted by :func:`compress_phantom`.
CONTACTS = ("bonded", "sliding")


#: Largest Poisson ratio accepted (plane strain needs nu < 0.5, see the module docstring).
NU_MAX = 0.5

Value = float | Mapping[int, float]


# --- label images ------------------------------------------------------------------------------


def _axis(values: object, name: str) -> np.ndarray:
    """A 1-D strictly increasing finite coordinate array (µm)."""
    c = as_finite_array(values, name)
    if c.ndim != 1 or c.size < 2:
        raise ValueError(f"{name} must be a 1-D array of at least 2 coordinates in µm")
    if np.any(np.diff(c) <= 0):
        raise ValueError(f"{name} must be strictly increasing (pixel centres in µm)")
    return c


def _label_image(values: np.ndarray, depth: np.ndarray, x: np.ndarray) -> xr.DataArray:
    return xr.DataArray(
        values.astype(np.int64),
        dims=("depth", "x"),
        coords={
            "depth": coord("depth", depth, "depth"),
            "x": coord("x", x, "lateral position"),
        },
        name="label",
        attrs=attrs("label"),
    )


def layered_labels(depth: object, x: object, interfaces: object) -> xr.DataArray:
    """Label image of horizontal layers spanning the whole width.

    Parameters
    ----------
    depth, x : array_like
        Pixel-centre depths and lateral positions in µm (strictly increasing).
    interfaces : sequence of float
        Depths in µm of the interfaces, strictly increasing. Layer ``k`` (label ``k``) holds the
        pixels with ``interfaces[k-1] <= depth < interfaces[k]`` (label 0 above the first). In
        :func:`compress_phantom` the interface then lies on the pixel edge, midway between the last
        pixel centre above it and the first at or below it (e.g. 97.5 µm for an interface at
        100 µm on 5 µm pixels centred at 0, 5, 10, ... µm).

    Returns
    -------
    xarray.DataArray
        Integer labels with dims ``(depth, x)``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> depth, x = np.arange(0.0, 50.0, 10.0), np.array([0.0, 10.0])
    >>> labels = speckle.layered_labels(depth, x, [15.0, 35.0])  # interfaces at 15 and 35 µm
    >>> labels.values[:, 0]
    array([0, 0, 1, 1, 2])
    """
    d, xx = _axis(depth, "depth"), _axis(x, "x")
    zi = as_finite_array(interfaces, "interfaces")
    if zi.ndim != 1 or np.any(np.diff(zi) <= 0):
        raise ValueError("interfaces must be a 1-D strictly increasing sequence of depths in µm")
    layer = np.searchsorted(zi, d, side="right")
    return _label_image(np.broadcast_to(layer[:, None], (d.size, xx.size)), d, xx)


def inclusion_labels(
    depth: object,
    x: object,
    center: Sequence[float],
    radii: float | Sequence[float],
    *,
    label: int = 1,
    background: int | xr.DataArray = 0,
) -> xr.DataArray:
    """Label image with an elliptical (or circular) inclusion.

    Parameters
    ----------
    depth, x : array_like
        Pixel-centre depths and lateral positions in µm (strictly increasing).
    center : (float, float)
        Centre ``(z, x)`` of the inclusion in µm.
    radii : float or (float, float)
        Semi-axes ``(r_z, r_x)`` in µm (one value: a circle). A pixel belongs to the inclusion
        when its centre satisfies ``((z - z_c)/r_z)**2 + ((x - x_c)/r_x)**2 <= 1``.
    label : int
        Label of the inclusion.
    background : int or xarray.DataArray
        Label of everything else, or a label image over the same ``depth`` and ``x`` (e.g. from
        :func:`layered_labels`) to put the inclusion into.

    Returns
    -------
    xarray.DataArray
        Integer labels with dims ``(depth, x)``.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> grid = np.arange(0.0, 50.0, 10.0)  # depth and x (µm)
    >>> labels = speckle.inclusion_labels(grid, grid, (20.0, 20.0), 10.0)
    >>> labels.values
    array([[0, 0, 0, 0, 0],
           [0, 0, 1, 0, 0],
           [0, 1, 1, 1, 0],
           [0, 0, 1, 0, 0],
           [0, 0, 0, 0, 0]])
    """
    d, xx = _axis(depth, "depth"), _axis(x, "x")
    c = as_finite_array(center, "center")
    if c.shape != (2,):
        raise ValueError(f"center must be (z, x) in µm, got shape {c.shape}")
    r = as_finite_array(radii, "radii")
    r = np.array([r, r]) if r.ndim == 0 else r
    if r.shape != (2,) or np.any(r <= 0):
        raise ValueError("radii must be one positive radius or (r_z, r_x) > 0 in µm")
    lab = check_int(label, "label")
    if isinstance(background, xr.DataArray):
        checked = _checked_labels(background)[0]
        base = checked.values
        if not (
            np.array_equal(checked["depth"].values, d) and np.array_equal(checked["x"].values, xx)
        ):
            raise ValueError("background label image must have exactly the given depth and x")
    else:
        base = np.full((d.size, xx.size), check_int(background, "background"))
    inside = in_ellipse([d[:, None], xx[None, :]], c, r)
    return _label_image(np.where(inside, lab, base), d, xx)


def _checked_labels(labels: object) -> tuple[xr.DataArray, str]:
    """Labels transposed to ``(depth, x)`` and the name of the lateral dim (``x``; a label
    image over the retired dim ``aline`` is renamed, warning)."""
    if not isinstance(labels, xr.DataArray):
        raise TypeError(
            f"labels must be an integer xarray.DataArray over (depth, x), got "
            f"{type(labels).__name__}"
        )
    labels = canonical_dims(labels, "labels")
    lateral = [d for d in labels.dims if d == "x"]
    if labels.ndim != 2 or "depth" not in labels.dims or len(lateral) != 1:
        raise ValueError(f"labels must have dims (depth, x) (coordinates in µm); got {labels.dims}")
    if not np.issubdtype(labels.dtype, np.integer):
        raise TypeError(f"labels must hold integers (region labels), got dtype {labels.dtype}")
    for dim in ("depth", lateral[0]):
        if dim not in labels.coords:
            raise ValueError(f"labels need a coordinate {dim!r} (pixel centres in µm)")
        _axis(labels[dim].values, f"labels coordinate {dim!r}")
    return labels.transpose("depth", lateral[0]), lateral[0]


def _pixel_edges(c: np.ndarray, top: float | None = None) -> np.ndarray:
    """Pixel boundaries: midpoints between centres, half a step beyond the ends (or ``top``)."""
    first = c[0] - 0.5 * (c[1] - c[0]) if top is None else top
    return np.concatenate([[first], 0.5 * (c[1:] + c[:-1]), [c[-1] + 0.5 * (c[-1] - c[-2])]])


def _subdivide(edges: np.ndarray, size: float) -> np.ndarray:
    """Nodes splitting each interval of ``edges`` into ``ceil(width / size)`` equal elements."""
    parts = [
        np.linspace(a, b, math.ceil((b - a) / size * (1 - 1e-12)) + 1)[:-1]
        for a, b in itertools.pairwise(edges)
    ]
    return np.concatenate([*parts, edges[-1:]])


def _as_table(value: object, name: str, units: str | None) -> object:
    """A per-region DataArray (dim ``region``, e.g. a regions table's column) as a mapping,
    after checking its ``units`` attribute is ``units`` (the one unit of the quantity)."""
    if not isinstance(value, xr.DataArray):
        return value
    have = value.attrs.get("units")
    if units is not None and have is not None and have != units:
        raise ValueError(
            f"{name} is given in {have!r}; compress takes {units!r} (convert the values, e.g. "
            "Pa / 1000 -> kPa, and set attrs['units'])"
        )
    if value.ndim == 0:
        return float(value.values)
    if value.dims != ("region",):
        raise ValueError(
            f"{name} as a DataArray must have the single dim 'region', got {value.dims}"
        )
    return {int(r): float(v) for r, v in zip(value.region.values, value.values, strict=True)}


def _per_label(
    value: Value, labels: np.ndarray, name: str, units: str | None = None, **bounds
) -> np.ndarray:
    """Map each pixel's label to a checked material value."""
    value = _as_table(value, name, units)
    present = np.unique(labels)
    check = check_modulus if name == "youngs_modulus" else None
    if isinstance(value, Mapping):
        missing = sorted(set(present.tolist()) - set(value))
        if missing:
            raise ValueError(f"{name} has no value for label(s) {missing} of the label image")
        table = {int(k): check_real(v, f"{name}[{k}]", **bounds) for k, v in value.items()}
        if check is not None:
            table = {k: check(v, f"{name}[{k}]") for k, v in table.items()}
        lut = np.array([table[int(k)] for k in present])
        return lut[np.searchsorted(present, labels)]
    v = check_real(value, name, **bounds)
    return np.full(labels.shape, v if check is None else check(v, name))


def _check_poisson(nu: np.ndarray, name: str = "poisson_ratio") -> None:
    if np.any(nu >= NU_MAX):
        raise ValueError(
            f"{name} must be in [0, 0.5): 0.5 (incompressible) makes the Lamé parameter "
            "lambda infinite (a displacement formulation cannot represent an incompressible "
            "solid); use at most 0.49999"
        )


# --- the solver ----------------------------------------------------------------------------------


@fem.BilinearForm
def _deviatoric(u, v, w):
    """Shear part ``2 mu eps(u) : eps(v)`` of plane-strain elasticity (element-wise ``w.mu``)."""
    return 2.0 * w.mu * ddot(sym_grad(u), sym_grad(v))


@fem.BilinearForm
def _volumetric(u, v, w):
    """Volumetric part ``lambda div(u) div(v)`` (element-wise ``w.lam``)."""
    return w.lam * div(u) * div(v)


#: One-point (element centre) quadrature on the reference square [0, 1]^2 of scikit-fem.
_CENTRE = (np.array([[0.5], [0.5]]), np.array([1.0]))


@fem.Functional
def _grad_xx(w):
    return w["u"].grad[0][0]


@fem.Functional
def _grad_zz(w):
    return w["u"].grad[1][1]


@fem.Functional
def _shear_xz(w):
    return 0.5 * (w["u"].grad[0][1] + w["u"].grad[1][0])


#: Sparse-LU factor entries per degree of freedom ``d``: ``FILL_COEF * d**0.25`` (SuperLU with
#: the MMD ordering on square label grids, 16x16 to 128x128 pixels: 10.5 to 11.8; rounded up),
#: at 12 bytes each (value and index), with the stiffness matrix and the FE fields beside them.
FILL_COEF = 16.0
FILL_EXPONENT = 0.25


def fem_bytes(n_nodes: int) -> float:
    """Estimated peak memory (bytes) of :func:`compress_phantom` on a mesh of ``n_nodes`` nodes: the
    sparse-LU factors (:data:`FILL_COEF`), the stiffness matrix and the FE fields."""
    dofs = 2.0 * n_nodes
    factor = FILL_COEF * dofs ** (1 + FILL_EXPONENT) * 12.0
    stiffness = 18.0 * dofs * 12.0 * 2  # assembled twice (deviatoric + volumetric)
    return factor + stiffness + 64.0 * dofs


def _solver(a, b, **_):
    """Sparse LU (SuperLU) for the symmetric positive definite stiffness matrix.

    A symmetric fill-reducing ordering (2.5x faster than scipy's default COLAMD on 20k DOFs)
    and diagonal pivots (a positive definite matrix needs no pivoting; with SuperLU's default
    partial pivoting a 21k-DOF solve at nu = 0.499 took 219 s instead of ~3 s).
    """
    lu = splu(
        a.tocsc(),
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )
    return lu.solve(b)


def compress_phantom(
    labels: xr.DataArray,
    youngs_modulus: Value,
    poisson_ratio: Value,
    *,
    strain: float,
    contact: str = "bonded",
    mesh_size: float | None = None,
) -> xr.Dataset:
    """Compress a phantom with a flat rigid probe at ``z = 0``: plane-strain finite elements.

    The sample occupies the union of the label pixels, from the probe plane ``z = 0`` to the
    bottom edge ``L`` of the last pixel row and between the outer edges of the first and last
    columns (pixel edges are midway between pixel centres; the first row starts at ``z = 0``).
    The probe ``z = 0`` is held fixed and the base ``z = L`` is moved by ``u_z = -strain * L``
    (nominal compressive strain ``strain``; the frame is the probe's, as in
    :func:`speckle.uniaxial_strain`). Boundary conditions: ``bonded``: ``u_x = 0`` on the probe
    and base too; ``sliding``: frictionless probe and base (``u_x`` free; ``u_x(0, x_centre)
    = 0`` fixes the lateral translation); lateral sides traction-free. Plane strain
    (``eps_yy = 0``), small strains (linear elasticity: displacements scale with ``strain``).

    Elements: bilinear quadrilaterals (scikit-fem ``ElementQuad1``) on the tensor grid of pixel
    edges, each pixel split into ``ceil(pixel size / mesh_size)`` equal elements per direction,
    so material interfaces lie on element edges; selective reduced integration of the
    volumetric term (no locking up to ``nu = 0.49999``, see the module docstring). A homogeneous
    block in sliding contact (``u_z = -strain z``, ``u_x = nu/(1 - nu) strain (x - x_centre)``,
    bilinear) is reproduced to rounding; stacked layers too when ``poisson_ratio = 0``.
    Material values given for labels absent from the image are ignored.

    Parameters
    ----------
    labels : xarray.DataArray
        Integer region labels with dims ``(depth, x)`` (``aline`` is read as ``x``, warning),
        coordinates = pixel centres in µm, strictly increasing (non-uniform grids allowed); the
        first depth must lie in ``[0, depth[1] - depth[0]]`` (the first pixel row starts at
        the probe).
    youngs_modulus : float or mapping of int to float
        Young's modulus in kPa (> 0), one for all or per label (every label present needs one).
    poisson_ratio : float or mapping of int to float
        Poisson ratio in ``[0, 0.5)``, one for all or per label (0.5 refused: see module
        docstring).
    strain : float
        Nominal compressive strain in (-1, 1) (``> 0`` compresses).
    contact : {"bonded", "sliding"}
        Probe and base contact (see above).
    mesh_size : float, optional
        Largest element edge in µm; default: one element per pixel. Must not exceed the largest
        pixel.

    Returns
    -------
    xarray.Dataset
        On the label grid ``(depth, x)``: ``label``, ``youngs_modulus`` (kPa), ``poisson_ratio``,
        ``uz``, ``ux`` (µm, the FE solution at pixel centres), ``strain_zz``, ``strain_xx``,
        ``strain_xz`` (pixel-averaged FE strain, compression positive: ``-eps``), ``stress_zz``,
        ``stress_xx``, ``stress_xz`` (pixel-averaged stress, kPa, compression positive);
        on the FE node grid ``(node_depth, node_x)``: ``uz_node``, ``ux_node`` (µm, the exact
        bilinear FE field, used by :func:`displacement_at`). Attributes: ``contact``,
        ``nominal_strain``, ``mesh_size`` (largest element edge, µm), ``element``, ``n_dofs``,
        ``sample_depth`` (``L``), ``lateral_extent``, ``x_centre``, ``probe_force`` (kPa µm per
        unit length out of plane: the compressive force on the probe).

    Examples
    --------
    A stiff inclusion under a sliding probe, moving an A-line scene (exact FE field)::

        scene = speckle.deformable_scene(
            64, 4.0, n_pixels=256, depth_range=2048.0, seed=1, strain=0.01
        )
        depth = np.arange(0.0, scene.attrs["populated_depth"] + 8.0, 8.0)
        x = scene.aline.values  # A-line positions, µm
        labels = speckle.inclusion_labels(depth, x, (1024.0, x.mean()), 160.0)
        fe = speckle.compress_phantom(
            labels, {0: 10.0, 1: 40.0}, 0.45, strain=0.01, contact="sliding"
        )
        moved = speckle.displace(scene, functools.partial(speckle.displacement_at, fe))

    ``fe[["uz", "ux"]]`` is also a field :func:`speckle.displace` accepts (linear
    interpolation between pixel centres instead of the exact FE field).
    """
    lab, lateral = _checked_labels(labels)
    s = check_real(strain, "strain", low=-1.0, high=1.0, low_inclusive=False, high_inclusive=False)
    check_choice(contact, "contact", CONTACTS)
    depth = lab["depth"].values.astype(float)
    xcoord = lab[lateral].values.astype(float)
    if depth[0] < 0 or depth[0] > depth[1] - depth[0]:
        raise ValueError(
            "labels depth must start at the probe z = 0: the first pixel centre must be in "
            f"[0, {depth[1] - depth[0]:g}] µm (at most one step below it), got {depth[0]:g}"
        )
    values = lab.values
    if np.any(values < 0):
        raise ValueError(
            f"labels hold {int(np.count_nonzero(values < 0))} of {values.size} pixel(s) with "
            "label -1 (no region): compress meshes every pixel and needs a material there; "
            "give every pixel a region (e.g. a background) or crop the label image"
        )
    young = _per_label(
        youngs_modulus, values, "youngs_modulus", "kPa", low=0.0, low_inclusive=False
    )
    nu = _per_label(poisson_ratio, values, "poisson_ratio", "1", low=0.0)
    _check_poisson(nu)
    z_edges, x_edges = _pixel_edges(depth, top=0.0), _pixel_edges(xcoord)
    largest = float(max(np.diff(z_edges).max(), np.diff(x_edges).max()))
    if mesh_size is None:
        size = largest
    else:
        size = check_real(mesh_size, "mesh_size", low=0.0, low_inclusive=False)
        if size > largest:
            raise ValueError(
                f"mesh_size must be <= the largest label pixel ({largest:g} µm): elements never "
                "span pixels (interfaces stay on element edges); coarsen the label image instead"
            )
    z_nodes, x_nodes = _subdivide(z_edges, size), _subdivide(x_edges, size)
    check_memory(
        fem_bytes(z_nodes.size * x_nodes.size),
        "labels (pixels) or 1/mesh_size",
        f"the FE solve on {z_nodes.size} x {x_nodes.size} nodes",
    )

    mesh = fem.MeshQuad.init_tensor(x_nodes, z_nodes)  # first coordinate x, second z
    basis = fem.Basis(mesh, fem.ElementVector(fem.ElementQuad1()))
    centroid = mesh.p[:, mesh.t].mean(axis=1)
    pz = np.searchsorted(z_edges, centroid[1]) - 1
    px = np.searchsorted(x_edges, centroid[0]) - 1
    lam, mu = lame_parameters(young[pz, px], nu[pz, px])
    # selective reduced integration: shear part with 2x2 Gauss points, volumetric part at the
    # element centre (no volumetric locking as nu -> 0.5; exact for linear displacement fields)
    centre_basis = fem.Basis(mesh, basis.elem, quadrature=_CENTRE)
    stiffness = _deviatoric.assemble(basis, mu=mu[:, None])
    stiffness += _volumetric.assemble(centre_basis, lam=lam[:, None])

    length = float(z_edges[-1])
    x_centre = 0.5 * float(x_edges[0] + x_edges[-1])
    ix = np.searchsorted(x_nodes, mesh.p[0])
    iz = np.searchsorted(z_nodes, mesh.p[1])
    dof_x, dof_z = basis.nodal_dofs
    u = basis.zeros()
    top, bottom = iz == 0, iz == z_nodes.size - 1
    u[dof_z[bottom]] = -s * length
    fixed = [dof_z[top], dof_z[bottom]]
    if contact == "bonded":
        fixed += [dof_x[top], dof_x[bottom]]
    else:
        fixed.append(dof_x[top & (ix == np.argmin(np.abs(x_nodes - x_centre)))])
    fixed_dofs = np.concatenate(fixed)
    u = fem.solve(*fem.condense(stiffness, x=u, D=fixed_dofs), solver=_solver)
    reaction = stiffness @ u

    uz_node = np.empty((z_nodes.size, x_nodes.size))
    ux_node = np.empty_like(uz_node)
    uz_node[iz, ix] = u[dof_z]
    ux_node[iz, ix] = u[dof_x]
    if contact == "sliding":  # fix the lateral translation at the probe centre exactly
        ux_node -= np.interp(x_centre, x_nodes, ux_node[0])

    # pixel averages of the FE strain (exact: element integrals summed per pixel)
    field = basis.interpolate(u)
    pixel = pz * xcoord.size + px
    area = np.bincount(pixel, weights=fem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).elemental(basis))

    def pixel_mean(form: fem.Functional) -> np.ndarray:
        total = np.bincount(pixel, weights=form.elemental(basis, u=field))
        return (total / area).reshape(depth.size, xcoord.size)

    exx, ezz, exz = pixel_mean(_grad_xx), pixel_mean(_grad_zz), pixel_mean(_shear_xz)
    lam_p, mu_p = lame_parameters(young, nu)
    sxx = lam_p * (exx + ezz) + 2 * mu_p * exx
    szz = lam_p * (exx + ezz) + 2 * mu_p * ezz
    sxz = 2 * mu_p * exz

    centres = np.stack(np.meshgrid(depth, xcoord, indexing="ij"), axis=-1)
    uz_pix = RegularGridInterpolator((z_nodes, x_nodes), uz_node)(centres)
    ux_pix = RegularGridInterpolator((z_nodes, x_nodes), ux_node)(centres)

    grid = ("depth", lateral)
    nodes = ("node_depth", "node_x")

    def var(dims, data, quantity, long_name):
        return (dims, data, attrs(quantity, long_name))

    ds = xr.Dataset(
        {
            "label": var(grid, values, "label", "region label"),
            "youngs_modulus": var(grid, young, "modulus", "Young's modulus"),
            "poisson_ratio": var(grid, nu, "dimensionless", "Poisson ratio"),
            "uz": var(grid, uz_pix, "displacement", "axial displacement (+z = deeper)"),
            "ux": var(grid, ux_pix, "displacement", "lateral displacement"),
            "strain_zz": var(grid, -ezz, "strain", "axial strain, compression positive"),
            "strain_xx": var(grid, -exx, "strain", "lateral strain, compression positive"),
            "strain_xz": var(grid, -exz, "strain", "shear strain (tensor), sign flipped"),
            "stress_zz": var(grid, -szz, "stress", "axial stress, compression positive"),
            "stress_xx": var(grid, -sxx, "stress", "lateral stress, compression positive"),
            "stress_xz": var(grid, -sxz, "stress", "shear stress, sign flipped"),
            "uz_node": var(nodes, uz_node, "displacement", "axial displacement at FE nodes"),
            "ux_node": var(nodes, ux_node, "displacement", "lateral displacement at FE nodes"),
        },
        coords={
            "depth": coord("depth", depth, "depth"),
            lateral: coord(lateral, xcoord, "lateral position"),
            "node_depth": coord("length", z_nodes, "FE node depth", dims="node_depth"),
            "node_x": coord("length", x_nodes, "FE node position", dims="node_x"),
        },
        attrs={
            "contact": contact,
            "nominal_strain": s,
            "mesh_size": float(max(np.diff(z_nodes).max(), np.diff(x_nodes).max())),
            "element": "skfem ElementQuad1 (bilinear), selective reduced integration, plane strain",
            "n_dofs": int(basis.N),
            "sample_depth": length,
            "lateral_extent": np.array([x_edges[0], x_edges[-1]]),
            "x_centre": x_centre,
            "probe_force": float(reaction[dof_z[top]].sum()),
            "sign_convention": "strain_ij = -eps_ij, stress_ij = -sigma_ij (compression > 0)",
            "youngs_modulus_units": units_of("modulus"),
        },
    )
    return ds


def displacement_at(result: xr.Dataset, z: object, x: object) -> tuple[np.ndarray, np.ndarray]:
    """The FE displacement of :func:`compress_phantom` at arbitrary material points.

    Bilinear interpolation of ``uz_node``/``ux_node`` on the FE node grid, which *is* the finite
    element solution (bilinear quadrilaterals on a rectangular grid): no error beyond the FE
    solution itself. Use it to deform scatterer scenes::

        speckle.displace(scene, functools.partial(speckle.displacement_at, result))

    Parameters
    ----------
    result : xarray.Dataset
        Output of :func:`compress_phantom` (also after a NetCDF round trip).
    z, x : array_like
        Depths and lateral positions in µm (broadcast together), inside the sample
        ``[0, sample_depth] x lateral_extent``.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        ``u_z`` and ``u_x`` in µm, shaped like ``broadcast(z, x)``.

    Raises
    ------
    ValueError
        If a point lies outside the sample (beyond a relative rounding margin of 1e-9).

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> depth, x = np.arange(4.0, 100.0, 8.0), np.arange(4.0, 100.0, 8.0)
    >>> labels = speckle.inclusion_labels(depth, x, (50.0, 50.0), 20.0)
    >>> result = speckle.compress_phantom(
    ...     labels, {0: 10.0, 1: 40.0}, 0.45, strain=0.01, contact="sliding"
    ... )
    >>> uz, ux = speckle.displacement_at(result, [0.0, 96.0], [48.0, 48.0])  # sample: 0 to 96 µm
    >>> np.round(uz, 6)  # the probe holds z = 0; the base moves by -strain * L
    array([ 0.  , -0.96])
    """
    if not isinstance(result, xr.Dataset) or not {"uz_node", "ux_node"} <= set(result):
        raise TypeError("result must be the xarray.Dataset returned by speckle.compress_phantom")
    zz, xx = broadcast(z=as_finite_array(z, "z"), x=as_finite_array(x, "x"))
    zn, xn = result["node_depth"].values, result["node_x"].values
    if zn.size < 2 or xn.size < 2:
        raise ValueError(
            f"result holds {zn.size} x {xn.size} nodes; a displacement field needs >= 2 x 2"
        )
    pts = np.stack([zz.ravel(), xx.ravel()], axis=-1)
    for k, (axis, name) in enumerate(((zn, "z"), (xn, "x"))):
        margin = 1e-9 * (axis[-1] - axis[0])
        if pts.size and (pts[:, k].min() < axis[0] - margin or pts[:, k].max() > axis[-1] + margin):
            raise ValueError(
                f"{name} must lie inside the sample, [{axis[0]:g}, {axis[-1]:g}] µm; got values "
                f"in [{pts[:, k].min():g}, {pts[:, k].max():g}] (extend the label image)"
            )
        pts[:, k] = np.clip(pts[:, k], axis[0], axis[-1])
    out = [
        RegularGridInterpolator((zn, xn), result[name].values)(pts).reshape(zz.shape)
        for name in ("uz_node", "ux_node")
    ]
    return out[0], out[1]


# --- analytic references -------------------------------------------------------------------------


def layer_strains(
    thickness: object, youngs_modulus: object, poisson_ratio: object, strain: float
) -> tuple[np.ndarray, float, float]:
    """Strains of bonded horizontal layers compressed between a sliding probe and base.

    Interior solution (far from the traction-free lateral sides, where edge effects decay over
    about a sample height) for plane strain: every layer ``i`` (thickness ``t_i``, Lamé
    ``lambda_i``, ``mu_i``, ``M_i = lambda_i + 2 mu_i``) has uniform strain; the axial stress
    ``sigma`` is the same in all (equilibrium), and so is the lateral strain ``e`` (the layers
    are bonded); the lateral stresses ``sigma_xx_i = E'_i e + nu_i/(1 - nu_i) sigma`` have zero
    resultant. With ``eps_zz_i = (sigma - lambda_i e) / M_i`` and ``sum t_i eps_zz_i = -strain
    L``, and ``a = sum t_i/M_i``, ``b = sum t_i nu_i/(1 - nu_i)``, ``c = sum t_i E'_i``::

        e = -sigma b / c,   sigma = -strain L / (a + b**2 / c).

    With ``nu = 0`` this is ``eps_zz_i = sigma / E_i``: strain inversely proportional to ``E``.
    With ``nu > 0`` a soft layer is laterally confined by stiffer neighbours, so it is strained
    less than ``1/E'`` proportionality predicts.

    Parameters
    ----------
    thickness : sequence of float
        Layer thicknesses ``t_i`` in µm (> 0), from the probe down.
    youngs_modulus : sequence of float
        ``E_i`` in kPa (> 0).
    poisson_ratio : sequence of float
        ``nu_i`` in [0, 0.5).
    strain : float
        Nominal compressive strain (``sum t_i strain_zz_i = strain * L``).

    Returns
    -------
    (numpy.ndarray, float, float)
        ``strain_zz`` per layer and the common ``strain_xx`` (compression positive, ``-eps``),
        and the axial stress ``stress_zz`` in kPa (compression positive).

    Examples
    --------
    >>> import speckle
    >>> strains, *_ = speckle.layer_strains([1.0, 1.0], [10.0, 30.0], [0.0, 0.0], -0.01)
    >>> strains.round(6)  # series springs: strain inversely proportional to modulus
    array([-0.015, -0.005])
    """
    t = as_finite_array(thickness, "thickness")
    e_mod = as_finite_array(youngs_modulus, "youngs_modulus")
    nu = as_finite_array(poisson_ratio, "poisson_ratio")
    if t.ndim != 1 or t.shape != e_mod.shape or t.shape != nu.shape:
        raise ValueError("thickness, youngs_modulus and poisson_ratio must be 1-D, equal length")
    if np.any(t <= 0) or np.any(e_mod <= 0) or np.any(nu < 0):
        raise ValueError("thickness and youngs_modulus must be > 0, poisson_ratio >= 0")
    _check_poisson(nu)
    s = check_real(strain, "strain", low=-1.0, high=1.0, low_inclusive=False, high_inclusive=False)
    lam, mu = lame_parameters(e_mod, nu)
    m = lam + 2 * mu
    a = np.sum(t / m)
    b = np.sum(t * nu / (1 - nu))
    c = np.sum(t * e_mod / (1 - nu**2))
    sigma = -s * t.sum() / (a + b**2 / c)
    e = -sigma * b / c
    return -(sigma - lam * e) / m, float(-e), float(-sigma)


def inclusion_strain(
    strain: float,
    youngs_modulus: float,
    poisson_ratio: float,
    inclusion_modulus: float,
    inclusion_poisson_ratio: float,
) -> tuple[float, float]:
    """Uniform strain inside a circular inclusion in an infinite plate (plane strain, Eshelby).

    The far field is the uniaxial plane-strain compression of the matrix (free lateral
    expansion): ``strain_zz = strain``, ``strain_xx = -nu/(1 - nu) strain``. Split the in-plane
    strain into its mean ``m = (eps_xx + eps_zz)/2`` and deviator ``d = (eps_xx - eps_zz)/2``.
    Inside a circular inclusion both are uniform (Eshelby; Muskhelishvili's solution), with
    ``kappa = 3 - 4 nu`` (matrix Kolosov constant, plane strain), in-plane bulk moduli
    ``K = lambda + mu``::

        m_in = m (K + mu) / (K_1 + mu),          d_in = d mu (1 + kappa) / (mu + kappa mu_1).

    (The mean part follows from the radial solution ``u_r = A r`` inside, ``B r + C / r``
    outside; the deviator from Eshelby's tensor for a cylinder, ``S_dev = kappa/(kappa + 1)``.
    Checks: equal materials give ``m, d``; a rigid inclusion ``d_in = 0``; a hole
    ``d_in = (1 + kappa) d``.)

    Parameters
    ----------
    strain : float
        Far-field nominal compressive strain.
    youngs_modulus, poisson_ratio : float
        Matrix ``E`` (kPa, > 0) and ``nu`` in [0, 0.5).
    inclusion_modulus, inclusion_poisson_ratio : float
        Inclusion ``E_1`` (kPa, > 0) and ``nu_1`` in [0, 0.5).

    Returns
    -------
    (float, float)
        ``strain_zz`` and ``strain_xx`` inside the inclusion (compression positive).

    Examples
    --------
    >>> import speckle
    >>> zz, xx = speckle.inclusion_strain(0.01, 10.0, 0.25, 10.0, 0.25)  # the matrix's own material
    >>> round(zz, 6), round(xx, 6)  # the far field: strain and -nu/(1 - nu) strain
    (0.01, -0.003333)
    """
    s = check_real(strain, "strain", low=-1.0, high=1.0, low_inclusive=False, high_inclusive=False)
    # only the ratio E_1/E enters: the rigid (1e12 x) and hole (1e-12 x) limits are allowed
    e0 = check_real(youngs_modulus, "youngs_modulus", low=0.0, low_inclusive=False)
    e1 = check_real(inclusion_modulus, "inclusion_modulus", low=0.0, low_inclusive=False)
    nu0 = check_real(poisson_ratio, "poisson_ratio", low=0.0)
    nu1 = check_real(inclusion_poisson_ratio, "inclusion_poisson_ratio", low=0.0)
    _check_poisson(np.array([nu0]))
    _check_poisson(np.array([nu1]), "inclusion_poisson_ratio")
    lam0, mu0 = lame_parameters(e0, nu0)
    lam1, mu1 = lame_parameters(e1, nu1)
    kappa = 3 - 4 * nu0
    ezz, exx = -s, nu0 / (1 - nu0) * s  # tensile-positive far field
    mean, dev = 0.5 * (exx + ezz), 0.5 * (exx - ezz)
    mean_in = mean * (lam0 + 2 * mu0) / (lam1 + mu1 + mu0)
    dev_in = dev * mu0 * (1 + kappa) / (mu0 + kappa * mu1)
    return float(-(mean_in - dev_in)), float(-(mean_in + dev_in))
