"""Names, units and attributes used across the package: one table, one place.

Every labelled object ``speckle`` returns uses these dimension and coordinate names, and their
``units``/``long_name`` attributes come from :data:`COORDS` (coordinates) and
:data:`QUANTITIES` (data variables) through :func:`attrs` and :func:`coord`, never from
hand-written literals. Spacing (pixel size, A-line pitch) is read from coordinates, never from
attributes (:func:`spacing`).

============  ==========  ===============================================================
name          units       meaning
============  ==========  ===============================================================
depth         um          depth of a pixel centre in the medium, ``q*H/N`` (pixel axis)
x, y          um          lateral position: the lateral dim of every image, a shared scene's
                          scatterers, a scanned beam line
aline         um          retired name of ``x`` (:data:`RETIRED`, :func:`canonical_dims`), still
                          the line dim of independent-line scenes and their B-scans
z             um          depth of a scatterer (a variable, not a dim)
wavenumber    rad/um      spectral component ``k_n = k0 + n*pi/H``
strain        1           uniaxial strain, compression > 0
k0_dk         1           ``k0/delta_k`` (= ``Lc/lambda0``)
density       1           scatterers per pixel (independent lines) or per voxel
lag           1           lag in pixels or lines
region        1           region label of a shared scene (:mod:`speckle.scene.regions`)
waist_pitch   1           beam waist over the line pitch
lateral_lag   1           lag in lines
axial_lag     1           lag in pixels
position      pixel       scatterer depth in pixels (``H/N``)
pixel         1           pixel index ``q``
n             1           spectral index ``n``
reflector     um          depth of a point reflector
time          s           time of a frame, A-line or scatterer position (dim of moved scenes
                          and image series, :mod:`speckle.scene.motion`)
lag           s           a time lag ``tau`` (:mod:`speckle.analysis.dynamics`): the dim
                          ``lag`` with the attributes of ``time_lag``
map           1           image of the SynthOCT comparison: the scan (Struct), OAC, SC, RSC
experiment    1           a comparison of two SynthOCT scans (the orchestrator's rows)
phantom       1           a SynthOCT phantom by name (e.g. Exp2_Layers_A)
origin        1           where a SynthOCT scan or score comes from (published, drop-in)
boundary      um          depth of a two-layer phantom's boundary
energy        percent     backscattered energy of a phantom's scatterers (the file's %)
layer         1           layer of a fitted phantom, 0 at the top (:mod:`speckle.studies.phantom`)
inclusion     1           inclusion of a virtual patient or fitted phantom
case          1           closed-loop case of the phantom fit (its seed)
thickness     um          layer thickness (the phantom fit's failure map)
energy_ratio  1           ratio of neighbouring layers' ``rho E`` (the failure map)
seed          1           seed of a fitted phantom's draw (:mod:`speckle.studies.phantom.real`)
pair          1           pair of draws compared, the floor (:mod:`speckle.studies.phantom.real`)
candidate     1           a phantom scored against a target scan (fitted, floor, baseline)
configuration 1           a SynthOCT scanner configuration by name (challenge, 2025)
============  ==========  ===============================================================

Data variables (:data:`QUANTITIES`): ``field``, ``amplitude``, ``weight``, ``correlation``,
``contrast``, ``dimensionless``, ``label``, ``count``, ``probability`` (1); ``length``,
``displacement``, ``depth_range`` (um); ``area_density`` (um-2); ``volume_density`` (um-3);
``percent``; ``scene_density`` (um^-d,
per µm^2 or µm^3 of a 2-D or 3-D scene); ``level`` (dB,
``20 log10 |A|``); ``pixels`` (pixel); ``line_density`` (1/pixel) and ``beam_density``
(1/(pixel line)); ``modulus``, ``stress`` (kPa); ``attenuation`` (1/um); ``diffusion``
(um^2/s); ``curvature`` (1/um); ``time`` (s); ``rate`` (1/s); ``velocity`` (um/s);
``line_rate`` (Hz);
``phase`` (rad); ``log_variance`` (dB^2); ``decay_speed`` (1/s); ``angle`` (degree); and, for
measured images of
unknown calibration, ``data``, ``data_slope``, ``mean_intensity`` and ``log_data``.

A quantity whose units are carried over from an input (a histogram of a variable in µm, a
column of a property table) takes :func:`labelled`; ``<name>_units`` attributes take
:func:`units_of`. No other module writes a ``units`` attribute by hand
(``tests/test_conventions.py`` checks).

The unambiguous depth ``H`` (µm, the pixel step is ``H/N``) has one name, ``depth_range``: the
parameter of every function that takes it and the attribute of every spectrum, scene and B-scan
(:func:`depth_range_of` reads it). ``depth`` is only the pixel dim/coordinate.

Units strings follow UDUNITS (``um``, ``rad/um``, ``1``) so that NetCDF readers understand
them; docstrings write µm.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping

import numpy as np
import xarray as xr

__all__ = [
    "COORDS",
    "DEPTH_RANGE",
    "QUANTITIES",
    "RETIRED",
    "attrs",
    "canonical_dims",
    "canonical_keys",
    "coord",
    "depth_range_of",
    "grid",
    "grid_attrs",
    "inverse_units",
    "labelled",
    "spacing",
    "units_of",
    "with_grid",
]

#: Coordinate/dimension name -> (units, long_name).
COORDS: dict[str, tuple[str, str]] = {
    "depth": ("um", "depth in the medium (pixel centre)"),
    "aline": (
        "um",
        "lateral position of an independent A-line (scene dim of a scatterer field of "
        "independent lines; images over them have the dim x)",
    ),
    "x": ("um", "lateral position x"),
    "y": ("um", "lateral position y"),
    "z": ("um", "scatterer depth"),
    "wavenumber": ("rad/um", "wavenumber k_n in the medium"),
    "strain": ("1", "uniaxial strain (compression > 0)"),
    "k0_dk": ("1", "k0/delta_k (= Lc/lambda0)"),
    "density": ("1", "scatterers per pixel"),
    "lag": ("1", "lag"),
    "region": ("1", "region label (speckle.scene.regions)"),
    "waist_pitch": ("1", "waist / line pitch"),
    "lateral_lag": ("1", "lag in lines"),
    "axial_lag": ("1", "lag in pixels"),
    "position": ("pixel", "scatterer depth"),
    "pixel": ("1", "pixel index q"),
    "n": ("1", "spectral index"),
    "reflector": ("um", "reflector depth"),
    "time": ("s", "time"),
    "time_lag": ("s", "time lag tau"),
    "map": ("1", "image compared: the scan (Struct) or a map (OAC, SC, RSC)"),
    "experiment": ("1", "comparison of two scans"),
    "phantom": ("1", "phantom"),
    "origin": ("1", "origin of a scan or score"),
    "boundary": ("um", "depth of the layer boundary"),
    "energy": ("percent", "backscattered energy per scatterer"),
    "layer": ("1", "layer index from the top"),
    "inclusion": ("1", "inclusion of a phantom"),
    "case": ("1", "closed-loop case (its seed)"),
    "thickness": ("um", "layer thickness"),
    "energy_ratio": ("1", "ratio of neighbouring layers' rho E"),
    "seed": ("1", "seed of a phantom's draw"),
    "pair": ("1", "pair of draws compared (the floor)"),
    "candidate": ("1", "phantom scored against the target scan"),
    "configuration": ("1", "scanner configuration"),
}

#: Data-variable quantity -> (units, long_name); a variable's own long name may be more specific.
QUANTITIES: dict[str, tuple[str, str]] = {
    "field": ("1", "complex field A"),
    "amplitude": ("1", "amplitude |A|"),
    "weight": ("1", "spectral weight S(k_n)"),
    "correlation": ("1", "correlation coefficient"),
    "contrast": ("1", "speckle contrast std(I)/<I>"),
    "dimensionless": ("1", "dimensionless number"),
    "length": ("um", "length"),
    "displacement": ("um", "displacement"),
    "depth_range": ("um", "unambiguous depth H"),
    "area_density": ("um-2", "scatterers per square micrometre"),
    "volume_density": ("um-3", "scatterers per cubic micrometre"),
    "percent": ("percent", "percentage"),
    "scene_density": ("um^-d", "scatterers per um^d of a d-dimensional scene (d = 2 or 3)"),
    "level": ("dB", "level 20 log10 |A|"),
    "label": ("1", "region label"),
    "count": ("1", "number of items"),
    "probability": ("1", "probability"),
    "pixels": ("pixel", "length in pixels"),
    "line_density": ("1/pixel", "scatterers per pixel"),
    "beam_density": ("1/(pixel line)", "scatterers per pixel per line"),
    "modulus": ("kPa", "modulus"),
    "stress": ("kPa", "stress"),
    "attenuation": ("1/um", "intensity attenuation coefficient mu_t"),
    "curvature": ("1/um", "curvature of a boundary z(x) (half its second derivative)"),
    "time": ("s", "time"),
    "rate": ("1/s", "scatterers per second"),
    "angle": ("degree", "angle"),
    "velocity": ("um/s", "velocity"),
    "line_rate": ("Hz", "A-line rate"),
    "phase": ("rad", "phase"),
    "log_variance": ("dB^2", "variance of the dB-scaled intensity 10 log10 I"),
    "decay_speed": ("1/s", "decay speed of a correlation"),
    "diffusion": ("um^2/s", "diffusion coefficient"),
    "data": ("data units", "value in the units of the measured data"),
    "data_slope": ("data units per pixel", "slope in the units of the measured data per pixel"),
    "mean_intensity": (
        "mean speckle intensity",
        "intensity relative to the mean speckle intensity",
    ),
    "log_data": ("1 (log-compressed, unknown gain/offset)", "log-compressed measured data"),
}


#: Retired names, old -> (new, kind); kind is ``dim``, ``attr``, ``function``, ``constant``
#: (public names of the top level and their subpackage), ``parameter`` (key
#: ``"<function>.<parameter>"``: the parameter is retired in that function only) or ``module``
#: (key the old dotted module path, value the module that holds its code now).
#: Each old name keeps working for one release with a ``FutureWarning`` naming the new one
#: (dims through :func:`canonical_dims`); ``tests/test_names.py`` checks that no module uses
#: one outside its deprecation shim.
RETIRED: dict[str, tuple[str, str]] = {
    "aline": ("x", "dim"),  # as an IMAGE dim only: scenes of independent lines keep it
    "METHODS": ("ASCAN_METHODS", "constant"),
    "strain.METHODS": ("STRAIN_METHODS", "constant"),
    "image": ("scan_image", "function"),
    "process": ("process_interferogram", "function"),
    "compress": ("compress_phantom", "function"),
    "layers": ("layer_stack", "function"),
    "subband_windows": ("subband_apodizations", "function"),
    "window_correlation": ("apodization_correlation", "function"),
    "spectral_window": ("spectral_apodization", "function"),
    "spectrometer.WINDOWS": ("APODIZATIONS", "constant"),
    "compounding.WINDOWS": ("SUBBAND_APODIZATIONS", "constant"),
    "band_window": ("band_apodization", "attr"),
    # line positions are ``lines``; ``x`` is the lateral dim and scatterer positions
    **{
        f"{f}.x": ("lines", "parameter")
        for f in (
            "scan_image",
            "image_regions",
            "scan_kernel",
            "bscan_series",
            "speckle_free_image",
            "angular_looks",
            "spatial_looks",
            "polarization_looks",
            "temporal_looks",
        )
    },
    # spectral windows are apodizations; ``window`` is a pixel window only
    **{
        f"{f}.{old}": (new, "parameter")
        for f in ("process_interferogram", "system_ascan")
        for old, new in (
            ("window", "apodization"),
            ("window_fwhm_fraction", "apodization_fwhm_fraction"),
        )
    },
    "subband_apodizations.window": ("apodization", "parameter"),
    "apodization_correlation.windows": ("apodizations", "parameter"),
    "frequency_looks.windows": ("apodizations", "parameter"),
    "ssada.band_window": ("band_apodization", "parameter"),
    "load_measured.aline_pitch": ("pitch", "parameter"),
    # image axes say x (issue 32, xdim); count parameters of line scenes (n_alines) stay
    "interpolate_windows.centre_aline": ("centre_x", "parameter"),
    "interpolate_windows.aline": ("x", "parameter"),
    "interpolate_displacement.aline": ("x", "parameter"),
    "window_aline_pixels": ("window_x_pixels", "attr"),
    "step_aline_pixels": ("step_x_pixels", "attr"),
    # module paths (issue 32): old path -> the private module that holds the code now; the
    # shim at the old path warns once (``speckle._deprecate.retired_module``)
    "speckle.imaging.bscan": ("speckle.imaging._bscan", "module"),
    "speckle.system.rolloff": ("speckle.system._rolloff", "module"),
    "speckle.system.backscatter": ("speckle.system._backscatter", "module"),
    "speckle.system.datasheet": ("speckle.system._datasheet", "module"),
    "speckle.scene.layers": ("speckle.scene._layers", "module"),
    # imaging's method modules, in one private folder
    **{
        f"speckle.imaging.{m}": (f"speckle.imaging._methods.{m}", "module")
        for m in ("direct", "nufft", "psf", "carrier", "beam_nufft", "beam_row")
    },
    # displacement fields are quantities over the image (issue 32, xrest): dims (depth, x)
    "pixel_displacement.aline": ("x", "parameter"),
    "uniaxial_pixel_displacement.aline": ("x", "parameter"),
}


#: Attribute holding the unambiguous depth ``H`` (µm) on spectra, scenes and B-scans.
DEPTH_RANGE = "depth_range"


def attrs(name: str, long_name: str | None = None, **extra: object) -> dict[str, object]:
    """``units`` and ``long_name`` attributes of quantity ``name`` from the tables.

    Parameters
    ----------
    name : str
        A key of :data:`COORDS` (a coordinate) or :data:`QUANTITIES` (a data variable).
    long_name : str, optional
        A more specific description replacing the table's (the units stay the table's).
    **extra
        Further attributes (e.g. ``note``) added after ``units`` and ``long_name``; they may
        not be ``units`` or ``long_name``.

    Returns
    -------
    dict
        ``{"units": ..., "long_name": ..., **extra}``.

    Raises
    ------
    ValueError
        If ``name`` is in neither table.

    Examples
    --------
    >>> attrs("level")
    {'units': 'dB', 'long_name': 'level 20 log10 |A|'}
    """
    table = COORDS.get(name) or QUANTITIES.get(name)
    if table is None:
        raise ValueError(
            f"unknown quantity {name!r}: add it to speckle.conventions.COORDS or QUANTITIES "
            f"(known: {sorted({**COORDS, **QUANTITIES})})"
        )
    clash = {"units", "long_name"} & set(extra)
    if clash:
        raise ValueError(f"extra attributes may not set {sorted(clash)}: they come from the table")
    units, default = table
    return {"units": units, "long_name": default if long_name is None else long_name, **extra}


def units_of(name: str) -> str:
    """The ``units`` string of quantity ``name`` (for ``<name>_units`` attributes).

    Parameters
    ----------
    name : str
        A key of :data:`COORDS` or :data:`QUANTITIES`.

    Returns
    -------
    str
        Its units, e.g. ``"rad/um"`` for ``"wavenumber"``.

    Raises
    ------
    ValueError
        If ``name`` is in neither table.
    """
    return str(attrs(name)["units"])


def labelled(units: str, long_name: str) -> dict[str, str]:
    """``units``/``long_name`` attributes of a quantity whose units come from its input data.

    For outputs that carry the units of what they were computed from (a histogram of a
    variable in µm, a table column with its own units), never for a fixed quantity: those
    take :func:`attrs`.

    Parameters
    ----------
    units : str
        The input's ``units``.
    long_name : str
        Description of the output (non-empty).

    Returns
    -------
    dict
        ``{"units": units, "long_name": long_name}``.

    Raises
    ------
    TypeError
        If ``units`` is not a string or ``long_name`` not a non-empty string.
    """
    if not isinstance(units, str):
        raise TypeError(f"units must be a str, got {units!r}")
    if not isinstance(long_name, str) or not long_name:
        raise TypeError(f"long_name must be a non-empty str, got {long_name!r}")
    return {"units": units, "long_name": long_name}


def inverse_units(units: str) -> str:
    """Units of a density over a quantity in ``units``: ``"1"`` stays ``"1"``, else ``1/(units)``.

    Examples
    --------
    >>> inverse_units("um")
    '1/(um)'
    """
    return "1" if units == "1" else f"1/({units})"


def coord(
    name: str, values: object, long_name: str | None = None, *, dims: str | None = None
) -> tuple[str, np.ndarray, dict[str, str]]:
    """A coordinate tuple ``(dims, values, attrs)`` with the :func:`attrs` of ``name``.

    ``dims`` defaults to ``name`` (a dimension coordinate); give it for a coordinate along
    another dim, e.g. ``coords={"z0": coord("z", z0, dims="position")}``.

    Examples
    --------
    >>> coord("depth", [0.0, 8.0])[2]["units"]
    'um'
    """
    return (name if dims is None else dims, np.asarray(values), attrs(name, long_name))


def spacing(obj: xr.DataArray | xr.Dataset, dim: str, default: float | None = None) -> float:
    """Uniform step of coordinate ``dim`` of ``obj`` (in its units, µm for lengths).

    Parameters
    ----------
    obj : xarray.DataArray or xarray.Dataset
        Object with a 1-D coordinate ``dim``.
    dim : str
        Coordinate name, e.g. ``"depth"`` (pixel size) or ``"aline"``/``"x"`` (line pitch).
    default : float, optional
        Returned when the coordinate has a single value (no step to read); without it a
        single-valued coordinate is an error.

    Raises
    ------
    ValueError
        If ``dim`` is missing, has no step to read and no ``default`` is given, or is not
        uniformly spaced (relative deviation above 1e-9).
    """
    if dim not in obj.coords:
        raise ValueError(
            f"{dim!r} coordinate missing; the object has coordinates {list(obj.coords)}"
        )
    v = np.asarray(obj[dim].values, dtype=float)
    if v.ndim != 1:
        raise ValueError(f"coordinate {dim!r} must be 1-D, got shape {v.shape}")
    if v.size < 2:
        if default is None:
            raise ValueError(f"coordinate {dim!r} has {v.size} value(s): its spacing is undefined")
        return float(default)
    d = np.diff(v)
    step = float(d.mean())
    if step <= 0 or np.max(np.abs(d - step)) > 1e-9 * abs(step):
        raise ValueError(f"coordinate {dim!r} must be increasing and uniformly spaced")
    return step


#: Lateral dims whose coordinate gives the line pitch, in the order they are looked for (``x``
#: of images; ``aline`` of scenes of independent lines).
LATERAL_DIMS = ("x", "aline")


@dataclasses.dataclass(frozen=True)
class Grid:
    """The sampling grid of a source or an image (:func:`grid`); ``None`` where not given."""

    pixel_size: float | None = None  # axial pixel H/N, µm
    pitch: float | None = None  # line pitch, µm
    k0: float | None = None  # central wavenumber in the medium, rad/µm
    depth_range: float | None = None  # unambiguous depth H, µm
    n_pixels: int | None = None  # pixels per A-scan N
    spectrum: xr.DataArray | None = None  # source spectrum (dim wavenumber)


def grid(obj: xr.DataArray | xr.Dataset, *, need: tuple[str, ...] = (), what: str = "obj") -> Grid:
    """Pixel size, line pitch, k0, depth range, pixel count and spectrum of a source or image.

    Read from coordinates first (``depth`` step = pixel size, ``aline``/``x`` step = pitch),
    then from the attributes the package writes (``n_pixels``, ``depth_range``, ``k0``): a
    spectrum (:func:`speckle.spectrum`, dim ``wavenumber``) gives ``pixel_size = H/N``; a
    B-scan Dataset holding a ``spectrum`` variable gives it too.

    Parameters
    ----------
    obj : xarray.DataArray or xarray.Dataset
        A source spectrum, an image (DataArray or B-scan Dataset) or a coordinate.
    need : tuple of str
        Fields that must be found (else ``ValueError`` naming them and what ``obj`` has).
    what : str
        Name of ``obj`` in messages (the caller's parameter, e.g. ``"source"``).

    Returns
    -------
    Grid
        ``pixel_size`` (µm), ``pitch`` (µm), ``k0`` (rad/µm), ``depth_range`` (µm),
        ``n_pixels`` and ``spectrum``; ``None`` for what ``obj`` does not give.

    Raises
    ------
    TypeError
        ``obj`` is not labelled.
    ValueError
        A field of ``need`` is missing, or a coordinate is not uniformly spaced.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> img = xr.DataArray(np.zeros((4, 3)), dims=("depth", "aline"),
    ...                    coords={"depth": [0.0, 2.0, 4.0, 6.0], "aline": [0.0, 5.0, 10.0]},
    ...                    attrs={"k0": 10.0})
    >>> g = grid(img)
    >>> g.pixel_size, g.pitch, g.k0
    (2.0, 5.0, 10.0)
    """
    if not isinstance(obj, (xr.DataArray, xr.Dataset)):
        raise TypeError(
            f"{what} must be a labelled DataArray or Dataset (coordinates and attributes give "
            f"its grid), got {type(obj).__name__}"
        )
    a = obj.attrs
    h = depth_range_of(obj, what, required=False)
    n = int(a["n_pixels"]) if "n_pixels" in a else None
    k0 = float(a["k0"]) if "k0" in a else None
    spectrum = None
    if isinstance(obj, xr.DataArray) and "wavenumber" in obj.dims:
        spectrum = obj
    elif isinstance(obj, xr.Dataset) and "spectrum" in obj.data_vars:
        spectrum = obj["spectrum"]
    pixel = None
    if "depth" in obj.coords and obj["depth"].size > 1:
        pixel = spacing(obj, "depth")
    elif h is not None and n:
        pixel = h / n
    pitch = None
    for dim in LATERAL_DIMS:
        if dim in obj.dims and dim in obj.coords and obj[dim].size > 1:
            pitch = spacing(obj, dim)
            break
    out = Grid(pixel, pitch, k0, h, n, spectrum)
    missing = [f for f in need if getattr(out, f, None) is None]
    if missing:
        raise ValueError(
            f"{what}: the grid's {missing} cannot be read from this {type(obj).__name__}: it has "
            f"coordinates {list(obj.coords)} and attributes {sorted(a)} (pixel_size: a "
            f"'depth' coordinate or n_pixels and depth_range; pitch: an 'aline'/'x' "
            f"coordinate; k0, n_pixels, depth_range: attributes)"
        )
    return out


#: Attributes that carry an image's sampling grid (:func:`grid_attrs`, :func:`with_grid`).
GRID_ATTRS = ("n_pixels", "depth_range", "depth_range_units", "k0", "k0_units")


def grid_attrs(n_pixels: int, depth_range: float, k0: float | None = None) -> dict[str, object]:
    """The grid attributes of an image: ``n_pixels``, ``depth_range`` (µm) and ``k0`` (rad/µm).

    With their ``<name>_units`` from the tables; what :func:`grid` reads back.

    Parameters
    ----------
    n_pixels : int
        Pixels per A-scan ``N``.
    depth_range : float
        Unambiguous depth ``H`` in µm (the pixel size is ``H/N``).
    k0 : float, optional
        Central wavenumber in the medium, rad/µm; ``None``: not recorded (an image of unknown
        source).

    Returns
    -------
    dict
        ``n_pixels``, ``depth_range``, ``depth_range_units`` and (with ``k0``) ``k0`` and
        ``k0_units``.

    Examples
    --------
    >>> grid_attrs(64, 512.0, 10.0)["k0_units"]
    'rad/um'
    """
    out: dict[str, object] = {
        "n_pixels": int(n_pixels),
        "depth_range": float(depth_range),
        "depth_range_units": units_of("depth_range"),
    }
    if k0 is not None:
        out.update(k0=float(k0), k0_units=units_of("wavenumber"))
    return out


def with_grid(obj: xr.Dataset, **grid_values: object) -> xr.Dataset:
    """``obj`` with its grid attributes on itself and on every data variable over ``depth``.

    So that an image variable taken out of a B-scan Dataset (``img.field``,
    ``img.intensity``) carries its own grid, and keeps it through ``isel``/``sel``:
    :func:`grid` then finds ``k0`` on the DataArray alone. The one place producers of images
    write their grid.

    Parameters
    ----------
    obj : xarray.Dataset or xarray.DataArray
        An image Dataset (its attributes give the grid unless ``grid_values`` do) or an image
        DataArray.
    **grid_values
        ``n_pixels``, ``depth_range`` and ``k0`` (as in :func:`grid_attrs`); when not given,
        the grid attributes already on ``obj`` are spread.

    Returns
    -------
    xarray.Dataset or xarray.DataArray
        A shallow copy with the attributes added (values unchanged).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> ds = xr.Dataset({"field": (("depth", "x"), np.zeros((4, 2), complex))})
    >>> out = with_grid(ds, n_pixels=4, depth_range=32.0, k0=10.0)
    >>> out.field.isel(x=0).attrs["k0"], out.attrs["n_pixels"]
    (10.0, 4)
    """
    unknown = set(grid_values) - {"n_pixels", "depth_range", "k0"}
    if unknown:
        raise TypeError(f"with_grid takes n_pixels, depth_range and k0, got {sorted(unknown)}")
    if grid_values:
        carried = grid_attrs(**grid_values)
    else:
        carried = {k: obj.attrs[k] for k in GRID_ATTRS if k in obj.attrs}
    out = obj.copy(deep=False).assign_attrs(carried)
    if isinstance(out, xr.Dataset):
        for name in list(out.data_vars):
            if "depth" in out[name].dims:
                out[name] = out[name].assign_attrs(carried)
    return out


def depth_range_of(
    obj: xr.DataArray | xr.Dataset, what: str = "object", *, required: bool = True
) -> float | None:
    """The unambiguous depth ``H`` in µm stored as attribute ``depth_range`` of ``obj``.

    Parameters
    ----------
    obj : xarray.DataArray or xarray.Dataset
        A spectrum (:func:`speckle.spectrum`), scene or B-scan.
    what : str
        Name of ``obj`` used in error messages (e.g. ``"source"``, ``"scene"``).
    required : bool
        Without the attribute, raise (``True``) or return ``None`` (``False``).

    Returns
    -------
    float or None
        ``H`` in µm, or ``None`` if absent and not ``required``.

    Raises
    ------
    ValueError
        If ``obj`` carries the attribute ``depth`` of files written before the rename (with the
        one-line fix), or lacks ``depth_range`` while ``required``.
    """
    a = obj.attrs
    if DEPTH_RANGE in a:
        return float(a[DEPTH_RANGE])
    if "depth" in a:
        raise ValueError(
            f"{what} has attribute 'depth' (unambiguous depth H, the name used before speckle "
            f"renamed it 'depth_range'): rebuild it with this version, or rename the attribute "
            f"with obj.attrs['depth_range'] = obj.attrs.pop('depth')"
        )
    if required:
        raise ValueError(
            f"{what} needs attribute 'depth_range' (unambiguous depth H in µm); it has {sorted(a)}"
        )
    return None


def canonical_dims(obj: object, what: str = "image") -> object:
    """``obj`` with retired dim names renamed to their current ones (``aline`` -> ``x``).

    The front door of every function taking a labelled image: an image written before the
    rename, with dims ``(depth, aline)``, is accepted for one release and renamed to
    ``(depth, x)`` with a ``FutureWarning``; anything that is not an xarray object passes
    unchanged.

    Parameters
    ----------
    obj : xarray.DataArray, xarray.Dataset or any
        A labelled image (or anything else, returned as is).
    what : str
        Name of ``obj`` used in error messages (e.g. ``"image"``, ``"frames"``).

    Returns
    -------
    same type as ``obj``
        ``obj`` with every retired dim (and its coordinate) renamed.

    Raises
    ------
    ValueError
        If ``obj`` has both a retired dim and its new name (e.g. ``aline`` and ``x``).

    Warns
    -----
    FutureWarning
        Naming the new dim, e.g. ``dim 'aline' is now 'x'``.

    Examples
    --------
    >>> import warnings, xarray as xr
    >>> old = xr.DataArray([[1.0, 2.0]], dims=("depth", "aline"))
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", FutureWarning)
    ...     canonical_dims(old).dims
    ('depth', 'x')
    """
    if not isinstance(obj, xr.DataArray | xr.Dataset):
        return obj
    renames = {}
    for old, (new, kind) in RETIRED.items():
        if kind != "dim" or old not in obj.dims:
            continue
        if new in obj.dims or new in obj.coords:
            raise ValueError(
                f"{what} has both dims {old!r} (retired) and {new!r}: keep only {new!r}"
            )
        renames[old] = new
    if not renames:
        return obj
    for old, new in renames.items():
        warnings.warn(
            f"dim {old!r} is now {new!r}: {what} with dim {old!r} is renamed; the old name will "
            f"be refused in the next release",
            FutureWarning,
            stacklevel=3,
        )
    return obj.rename(renames)


def canonical_keys(mapping: object, what: str = "mapping") -> object:
    """``mapping`` with keys that are retired dim names renamed (``aline`` -> ``x``), warning.

    For mappings keyed by dim, e.g. a region of interest ``{"depth": [0, 64], "x": [0, 128]}``;
    anything that is not a mapping (``None`` included) passes unchanged.

    Parameters
    ----------
    mapping : mapping or any
        Keyed by dim names.
    what : str
        Name of ``mapping`` in messages (e.g. ``"roi"``).

    Returns
    -------
    same as ``mapping`` or dict
        A new dict when a key was renamed, else ``mapping`` itself.

    Raises
    ------
    ValueError
        If ``mapping`` has both a retired key and its new name.

    Warns
    -----
    FutureWarning
        Naming the new key, e.g. ``dim 'aline' is now 'x'``.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", FutureWarning)
    ...     canonical_keys({"depth": [0, 4], "aline": [0, 8]}, "roi")
    {'depth': [0, 4], 'x': [0, 8]}
    """
    if not isinstance(mapping, Mapping):
        return mapping
    dims = {old: new for old, (new, kind) in RETIRED.items() if kind == "dim"}
    found = [k for k in mapping if k in dims]
    for old in found:
        if dims[old] in mapping:
            raise ValueError(f"{what} has both keys {old!r} (retired) and {dims[old]!r}")
        warnings.warn(
            f"dim {old!r} is now {dims[old]!r}: {what} key {old!r} is renamed; the old name will "
            f"be refused in the next release",
            FutureWarning,
            stacklevel=3,
        )
    return {dims.get(k, k): v for k, v in mapping.items()} if found else mapping
