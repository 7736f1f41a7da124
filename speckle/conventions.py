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
aline         um          lateral position of an independent A-line (the paper's B-scans)
x, y          um          lateral position in a shared scene or of a scanned beam line
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

import numpy as np
import xarray as xr

__all__ = [
    "COORDS",
    "DEPTH_RANGE",
    "QUANTITIES",
    "attrs",
    "coord",
    "depth_range_of",
    "inverse_units",
    "labelled",
    "spacing",
    "units_of",
]

#: Coordinate/dimension name -> (units, long_name).
COORDS: dict[str, tuple[str, str]] = {
    "depth": ("um", "depth in the medium (pixel centre)"),
    "aline": ("um", "lateral position of the A-line"),
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
