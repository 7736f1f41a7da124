"""The SynthOCT challenge's files: scanner INI, phantom tables, 8-bit PNG scans, baseline phantoms.

Formats (the challenge's baseline repository ``SynthOCTChallenge/SynthOCT_Baseline``, CC BY 4.0):

* **Configuration** (``Configuration.ini``): one ``[Parameters]`` section with exactly the eleven
  keys of :data:`INI_KEYS` (case-insensitive, as Python's ``configparser`` writes them); lengths
  in µm ("mcm"). :class:`ScannerConfig` holds them, with the scan geometry derived from them:
  pixel ``q`` at depth ``q * pixel_size`` (``depth_range = n_pixels * pixel_size``), A-line ``i``
  at ``x_i = -x_max/2 + i x_max/n_lines`` and B-scan ``b`` at ``y_b = -y_max/2 + b y_max/n_bscans``
  (``y = 0`` for the challenge's single B-scan; the line positions were identified from the
  published scans, the B-scan positions are assumed by analogy, see
  ``docs/explanation/synthoct.md``).
* **Phantom** (``Scatterers_*.txt`` of the challenge, ``*.dat`` of the group's 2025 release): one
  scatterer per line, four whitespace-separated numbers ``X Y Z`` (µm) and ``Energy`` (%, the
  backscattered energy, 0..100); the scanner's amplitude is ``sqrt(Energy/100)``. No header.
  Blank lines are ignored. The baseline writes ``%.4e`` (5 significant digits), so a phantom
  drawn in ``[-x_max/2, x_max/2) x [0, H)`` may hold values *on* the box's far edges.
* **Scan**: an 8-bit grayscale PNG, depth down the rows, A-lines across the columns (the
  published scans are RGBA files written by Matplotlib with equal colour channels; they are read
  as their gray level).

Scatterers outside the stated box (``|X| > x_max/2`` or ``Z`` outside ``[0, H]``) are **kept**:
the reader never drops or moves a scatterer, and records their number in the attribute
``n_outside_box`` (with a ``config``). The scanner images each by the same formula as the
others (:mod:`speckle.synthoct.scanner`): laterally through the beam's Gaussian tail, in depth
at ``Z`` modulo the unambiguous depth ``H`` (the model's wrap-around).

The numpy cores (:func:`read_phantom_table`, :func:`read_png`, :func:`write_png`,
:func:`baseline_table`) import neither xarray nor scipy: the ``speckle-scan`` command uses them.
"""

from __future__ import annotations

import configparser
import dataclasses
import io
import math
import os
from pathlib import Path

import numpy as np

from .._atomic import atomic_path
from .._validate import check_memory, check_path

__all__ = [
    "BASELINE_KINDS",
    "BASELINE_SEEDS",
    "INI_KEYS",
    "ScannerConfig",
    "baseline_phantom",
    "baseline_table",
    "phantom_table",
    "read_phantom",
    "read_phantom_table",
    "read_png",
    "read_scan",
    "read_scanner_config",
    "write_phantom",
    "write_png",
    "write_scan",
    "write_scanner_config",
]

#: INI key (lower case, as ``configparser`` stores it) -> (ScannerConfig field, type).
INI_KEYS: dict[str, tuple[str, type]] = {
    "scan filename": ("scan_filename", str),
    "scatterers coordinates file": ("scatterers_filename", str),
    "a-scan pixel numbers": ("n_pixels", int),
    "vertical pixel size mcm": ("pixel_size", float),
    "central wavelength mcm": ("wavelength", float),
    "number of a-scans in b-scan": ("n_lines", int),
    "xmax mcm": ("x_max", float),
    "number of b-scans": ("n_bscans", int),
    "ymax mcm": ("y_max", float),
    "beam radius mcm": ("beam_radius", float),
    "number of scatterers in b-scan": ("n_scatterers", int),
}
#: The INI's section.
SECTION = "Parameters"
#: Phantoms of the baseline generator (``Part1_Generator.py`` as called by ``Orchestrator.py``).
BASELINE_KINDS = ("uniform", "layers")
#: The baseline's two realisations of each phantom: legacy ``np.random.seed`` values.
BASELINE_SEEDS = {"A": 42, "B": 101}
#: Two-layer phantom of the self-consistency check: energy (%) above/below the boundary (µm).
LAYERS_BOUNDARY = 400.0
LAYERS_ENERGY = (0.01, 2.5)
#: Energy (%) of every scatterer of the uniform phantom.
UNIFORM_ENERGY = 1.0
#: Number format of the baseline's phantom files (numpy.savetxt).
PHANTOM_FORMAT = "%.4e"

_POSITIVE = ("pixel_size", "wavelength", "x_max", "beam_radius")


@dataclasses.dataclass(frozen=True)
class ScannerConfig:
    """The virtual scanner's configuration (one ``[Parameters]`` INI section), lengths in µm.

    The defaults are the challenge's (``Part1_Generator.py``): 256 pixels of 6 µm, λ = 1.3 µm,
    512 A-lines over 3072 µm, one B-scan, beam radius 10 µm, 300,000 scatterers. The group's
    2025 digital phantoms used 601 pixels of 2.2 µm, 975 A-lines over 3000 µm, radius 6 µm and
    255,000 scatterers.

    Attributes
    ----------
    n_pixels : int
        ``a-scan pixel numbers``: pixels per A-line ``N`` (>= 2).
    pixel_size : float
        ``vertical pixel size mcm``: pixel step in depth, µm (> 0).
    wavelength : float
        ``central wavelength mcm``: central wavelength, µm (> 0).
    n_lines : int
        ``number of a-scans in b-scan`` (>= 1).
    x_max : float
        ``xmax mcm``: lateral extent of a B-scan, µm (> 0).
    n_bscans : int
        ``number of b-scans`` (>= 1).
    y_max : float
        ``ymax mcm``: extent across the B-scans, µm (>= 0).
    beam_radius : float
        ``beam radius mcm``: ``r`` of the double-pass amplitude weight ``exp(-d^2/r^2)``, µm
        (> 0); the project's waist ``w0 = sqrt(2) r``.
    n_scatterers : int
        ``number of scatterers in b-scan``: rows the phantom must hold (>= 1).
    scan_filename, scatterers_filename : str
        ``scan filename`` and ``scatterers coordinates file`` (recorded, not used: the command
        line names the files).

    Examples
    --------
    >>> cfg = ScannerConfig()
    >>> cfg.depth_range, cfg.line_pitch, float(cfg.line_positions[0])
    (1536.0, 6.0, -1536.0)
    """

    n_pixels: int = 256
    pixel_size: float = 6.0
    wavelength: float = 1.3
    n_lines: int = 512
    x_max: float = 3072.0
    n_bscans: int = 1
    y_max: float = 0.0
    beam_radius: float = 10.0
    n_scatterers: int = 300_000
    scan_filename: str = "Scan_Raw.bin"
    scatterers_filename: str = "Scatterers_Exp.txt"

    def __post_init__(self):
        keys = {field: key for key, (field, _) in INI_KEYS.items()}
        for key, (field, kind) in INI_KEYS.items():
            value = getattr(self, field)
            if kind is str:
                if not isinstance(value, str):
                    raise TypeError(f"{field} ({key!r}) must be a str, got {type(value).__name__}")
                continue
            if kind is int:
                if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                    raise TypeError(f"{field} ({key!r}) must be an integer, got {value!r}")
                low = 2 if field == "n_pixels" else 1
                if value < low:
                    raise ValueError(f"{field} ({key!r}) must be >= {low}, got {value}")
                object.__setattr__(self, field, int(value))
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
                raise TypeError(f"{field} ({key!r}) must be a real number (µm), got {value!r}")
            value = float(value)
            if not math.isfinite(value):
                raise ValueError(f"{field} ({key!r}) must be finite (µm), got {value}")
            if field in _POSITIVE and value <= 0:
                raise ValueError(f"{field} ({keys[field]!r}) must be > 0 µm, got {value}")
            if value < 0:
                raise ValueError(f"{field} ({keys[field]!r}) must be >= 0 µm, got {value}")
            object.__setattr__(self, field, value)
        # the scan's field (complex128 per pixel, line and B-scan) and the phantom's table
        check_memory(
            16.0 * self.n_pixels * self.n_lines * self.n_bscans,
            "n_pixels x n_lines x n_bscans",
            "the scan's complex field",
        )
        check_memory(32.0 * self.n_scatterers, "n_scatterers", "the phantom's table")

    @property
    def depth_range(self) -> float:
        """Unambiguous depth ``H = n_pixels * pixel_size`` (µm)."""
        return self.n_pixels * self.pixel_size

    @property
    def line_pitch(self) -> float:
        """A-line pitch ``x_max/n_lines`` (µm)."""
        return self.x_max / self.n_lines

    @property
    def line_positions(self) -> np.ndarray:
        """A-line positions ``x_i = -x_max/2 + i x_max/n_lines`` (µm), shape ``(n_lines,)``."""
        return -0.5 * self.x_max + np.arange(self.n_lines) * self.line_pitch

    @property
    def bscan_positions(self) -> np.ndarray:
        """B-scan positions ``y_b = -y_max/2 + b y_max/n_bscans`` (µm), shape ``(n_bscans,)``."""
        return -0.5 * self.y_max + np.arange(self.n_bscans) * (self.y_max / self.n_bscans)

    @property
    def k0(self) -> float:
        """Central wavenumber ``2 pi/wavelength`` (rad/µm)."""
        return 2.0 * math.pi / self.wavelength


# --- configuration ----------------------------------------------------------------------


def _config_error(path: object, message: str) -> ValueError:
    return ValueError(f"{path}: {message}")


def read_scanner_config(path: str | os.PathLike) -> ScannerConfig:
    """Read the scanner's INI file.

    Parameters
    ----------
    path : str or path-like
        An INI file with one ``[Parameters]`` section holding exactly the keys of
        :data:`INI_KEYS` (any case).

    Returns
    -------
    ScannerConfig
        The scanner's parameters (lengths in µm), as the file states them.

    Raises
    ------
    ValueError
        Naming the file and the key: a missing section or key, an unknown key or section, a
        value that is not a number (integer where one is expected), or out of range.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "Configuration.ini"
    >>> write_scanner_config(ScannerConfig(), p)
    >>> read_scanner_config(p).n_lines
    512
    """
    check_path(path)
    parser = configparser.ConfigParser(interpolation=None)
    try:
        with open(path, encoding="utf-8-sig") as f:
            parser.read_file(f)
    except configparser.Error as err:
        raise _config_error(path, f"not a valid INI file: {err}") from None
    sections = parser.sections()
    if SECTION not in sections:
        raise _config_error(path, f"missing section [{SECTION}] (found {sections})")
    extra = [s for s in sections if s != SECTION]
    if extra:
        raise _config_error(path, f"unknown section(s) {extra}: only [{SECTION}] is allowed")
    section = parser[SECTION]
    unknown = [k for k in section if k not in INI_KEYS]
    if unknown:
        raise _config_error(
            path, f"unknown key {unknown[0]!r} in [{SECTION}]; allowed keys: {list(INI_KEYS)}"
        )
    missing = [k for k in INI_KEYS if k not in section]
    if missing:
        raise _config_error(path, f"missing key {missing[0]!r} in [{SECTION}]")
    values = {}
    for key, (field, kind) in INI_KEYS.items():
        text = section[key].strip()
        if kind is str:
            values[field] = text
            continue
        try:
            value = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise _config_error(path, f"key {key!r} must be {what}, got {text!r}") from None
        values[field] = value
    try:
        return ScannerConfig(**values)
    except (TypeError, ValueError) as err:
        raise _config_error(path, str(err)) from None


def write_scanner_config(config: ScannerConfig, path: str | os.PathLike) -> None:
    """Write ``config`` as the scanner's INI file (atomically), keys as the baseline writes them.

    Parameters
    ----------
    config : ScannerConfig
        The configuration.
    path : str or path-like
        Output file.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "c.ini"
    >>> write_scanner_config(ScannerConfig(n_scatterers=10), p)
    >>> "number of scatterers in b-scan = 10" in p.read_text()
    True
    """
    if not isinstance(config, ScannerConfig):
        raise TypeError(f"config must be a ScannerConfig, got {type(config).__name__}")
    lines = [f"[{SECTION}]"]
    for key, (field, _) in INI_KEYS.items():
        value = getattr(config, field)
        lines.append(f"{key} = {value!r}" if isinstance(value, float) else f"{key} = {value}")
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n\n", encoding="utf-8")


# --- phantoms ---------------------------------------------------------------------------


def _diagnose(path: object, text: str) -> None:
    """Raise a ValueError naming the first bad line of a phantom file (1-based)."""
    for number, line in enumerate(text.splitlines(), start=1):
        tokens = line.split()
        if not tokens:
            continue
        if len(tokens) != 4:
            raise ValueError(
                f"{path}, line {number}: {len(tokens)} columns, expected 4 (X Y Z Energy): "
                f"{line.strip()[:80]!r}"
            )
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            bad = next(t for t in tokens if not _is_float(t))
            raise ValueError(f"{path}, line {number}: {bad!r} is not a number") from None
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"{path}, line {number}: NaN or infinite value: {line.strip()!r}")
        if not 0.0 <= values[3] <= 100.0:
            raise ValueError(
                f"{path}, line {number}: energy {values[3]:g} % outside 0..100 (the backscattered "
                "energy in percent)"
            )


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def read_phantom_table(path: str | os.PathLike, *, n_scatterers: int | None = None) -> np.ndarray:
    """A phantom file as a float64 array ``(M, 4)``: X, Y, Z (µm), Energy (%); numpy only.

    The file is parsed by :func:`numpy.loadtxt` (its C reader in numpy >= 1.23: 0.07 s for the
    challenge's 300,000 rows, see ``benchmarks/bench_synthoct.py``); only a file that fails a
    check is read again line by line, to name the first bad line.

    Parameters
    ----------
    path : str or path-like
        Phantom file (``.txt`` or ``.dat``).
    n_scatterers : int, optional
        Rows the file must hold (the INI's ``number of scatterers in b-scan``).

    Returns
    -------
    numpy.ndarray
        Shape ``(M, 4)``, in file order.

    Raises
    ------
    ValueError
        Naming the file and line: a row without exactly four columns, a value that is not a
        number, NaN or infinite, an energy outside 0..100; or a row count other than
        ``n_scatterers``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.txt"
    >>> _ = p.write_text("0 0 10 1.0\\n5 0 20 2.5\\n")
    >>> read_phantom_table(p).shape
    (2, 4)
    """
    check_path(path)
    raw = Path(path).read_bytes()
    if not raw.strip():
        raise ValueError(f"{path}: no scatterers (the file is empty)")
    try:
        table = np.loadtxt(io.BytesIO(raw), dtype=np.float64, ndmin=2, comments=None)
    except ValueError:
        _diagnose(path, raw.decode("utf-8", errors="replace"))
        raise  # pragma: no cover  (the diagnosis always finds the line loadtxt refused)
    if table.shape[1] != 4 or not np.all(np.isfinite(table)):
        _diagnose(path, raw.decode("utf-8", errors="replace"))
    energy = table[:, 3]
    if np.any((energy < 0) | (energy > 100)):
        _diagnose(path, raw.decode("utf-8", errors="replace"))
    if n_scatterers is not None and table.shape[0] != n_scatterers:
        raise ValueError(
            f"{path}: {table.shape[0]} scatterers, but the configuration's 'number of "
            f"scatterers in b-scan' is {n_scatterers}"
        )
    return table


def _outside_box(table: np.ndarray, config: ScannerConfig) -> np.ndarray:
    half = 0.5 * config.x_max
    x, z = table[:, 0], table[:, 2]
    return (np.abs(x) > half) | (z < 0) | (z > config.depth_range)


def _scene(table: np.ndarray, config: ScannerConfig | None, source: str):
    import xarray as xr

    from ..conventions import attrs

    attributes = {"kind": "shared", "ndim": 3, "source": source}
    if config is not None:
        attributes["n_outside_box"] = int(np.count_nonzero(_outside_box(table, config)))
    return xr.Dataset(
        {
            "x": ("scatterer", table[:, 0].copy(), attrs("x", "scatterer lateral position x")),
            "y": ("scatterer", table[:, 1].copy(), attrs("y", "scatterer lateral position y")),
            "z": ("scatterer", table[:, 2].copy(), attrs("z")),
            "amplitude": (
                "scatterer",
                np.sqrt(table[:, 3] / 100.0).astype(np.complex128),
                attrs("amplitude", "scattering amplitude sqrt(Energy/100)"),
            ),
            "region": ("scatterer", np.zeros(table.shape[0], np.int32), attrs("label")),
        },
        attrs=attributes,
    )


def read_phantom(path: str | os.PathLike, *, config: ScannerConfig | None = None):
    """Read a phantom file (``.txt`` of the challenge, ``.dat`` of the 2025 release) as a scene.

    Parameters
    ----------
    path : str or path-like
        Four columns per line: X, Y, Z (µm), Energy (%).
    config : ScannerConfig, optional
        Given, the row count must equal its ``n_scatterers`` and the scatterers outside its box
        are counted (attribute ``n_outside_box``; they are kept, see the module docstring).

    Returns
    -------
    xarray.Dataset
        A 3-D shared scene (:mod:`speckle.scene.shared`, dim ``scatterer``, file order):
        ``x``, ``y``, ``z`` (µm), ``amplitude`` ``sqrt(Energy/100)`` (complex128, real),
        ``region`` 0.

    Raises
    ------
    ValueError
        As :func:`read_phantom_table`, naming the file and line.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.txt"
    >>> _ = p.write_text("0 0 10 1.0\\n5 0 20 4.0\\n")
    >>> read_phantom(p).amplitude.real.values.tolist()
    [0.1, 0.2]
    """
    check_path(path)
    if config is not None and not isinstance(config, ScannerConfig):
        raise TypeError(f"config must be a ScannerConfig or None, got {type(config).__name__}")
    n = None if config is None else config.n_scatterers
    table = read_phantom_table(path, n_scatterers=n)
    return _scene(table, config, str(path))


def phantom_table(phantom: object, energy_scale: float = 100.0) -> np.ndarray:
    """The ``(M, 4)`` table (X, Y, Z, Energy = ``energy_scale |a|^2``) of a shared scene, or
    an ``(M, 4)`` array as float64 (not checked further: :func:`write_phantom` checks)."""
    if isinstance(phantom, np.ndarray):
        table = np.asarray(phantom, dtype=np.float64)
        if table.ndim != 2 or table.shape[1] != 4:
            raise ValueError(
                f"phantom array must have shape (M, 4) (X, Y, Z, Energy), got {table.shape}"
            )
        return table
    variables = getattr(phantom, "data_vars", None)
    if variables is None or not {"x", "z", "amplitude"} <= set(variables):
        raise TypeError(
            "phantom must be a shared scene (xarray.Dataset with x, z[, y], amplitude over "
            f"'scatterer') or an (M, 4) array, got {type(phantom).__name__}"
        )
    x = np.asarray(phantom["x"].values, dtype=np.float64).ravel()
    z = np.asarray(phantom["z"].values, dtype=np.float64).ravel()
    y = np.asarray(phantom["y"].values, float).ravel() if "y" in variables else np.zeros_like(x)
    energy = energy_scale * np.abs(np.asarray(phantom["amplitude"].values)).ravel() ** 2
    return np.column_stack([x, y, z, energy])


def write_phantom(
    phantom: object,
    path: str | os.PathLike,
    *,
    config: ScannerConfig | None = None,
    energy_scale: float = 100.0,
) -> None:
    """Write a phantom file the official scanner accepts (atomically, ``%.4e`` as the baseline).

    Parameters
    ----------
    phantom : xarray.Dataset or numpy.ndarray
        A shared scene (:func:`speckle.shared_scene`, :func:`read_phantom`, ...; 2-D scenes get
        ``Y = 0``) or an ``(M, 4)`` array of X, Y, Z (µm), Energy (%).
    path : str or path-like
        Output file.
    config : ScannerConfig, optional
        Given, the scatterer count must equal its ``n_scatterers`` (write the matching INI with
        ``dataclasses.replace(config, n_scatterers=M)``).
    energy_scale : float
        Scenes only: Energy (%) ``= energy_scale |a|^2``. The default 100 inverts the scanner's
        ``a = sqrt(Energy/100)``; the project's scenes draw ``E|a|^2 = 1`` (a mirror each at
        100 %): pass e.g. ``energy_scale=1.0`` for tissue-like 1 % scatterers. The amplitudes'
        phases are not written (the scanner's phase comes from depth).

    Raises
    ------
    ValueError
        On non-finite values, an energy outside 0..100 (naming the scatterer) or a count that
        disagrees with ``config``.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.txt"
    >>> write_phantom(np.array([[0.0, 0.0, 12.5, 1.0]]), p)
    >>> p.read_text()
    '0.0000e+00 0.0000e+00 1.2500e+01 1.0000e+00\\n'
    """
    if isinstance(energy_scale, bool) or not (
        isinstance(energy_scale, (int, float)) and 0 < energy_scale < math.inf
    ):
        raise ValueError(f"energy_scale must be a positive finite number, got {energy_scale!r}")
    table = phantom_table(phantom, float(energy_scale))
    bad = np.flatnonzero(~np.all(np.isfinite(table), axis=1))
    if bad.size:
        raise ValueError(f"phantom scatterer {bad[0]} has a NaN or infinite value: {table[bad[0]]}")
    bad = np.flatnonzero((table[:, 3] < 0) | (table[:, 3] > 100))
    if bad.size:
        raise ValueError(
            f"phantom scatterer {bad[0]} has energy {table[bad[0], 3]:g} %, outside 0..100 "
            f"({bad.size} such scatterers); lower energy_scale or the amplitudes"
        )
    if config is not None and table.shape[0] != config.n_scatterers:
        raise ValueError(
            f"phantom holds {table.shape[0]} scatterers, config's 'number of scatterers in "
            f"b-scan' (n_scatterers) is {config.n_scatterers}"
        )
    with atomic_path(path) as tmp:
        np.savetxt(tmp, table, fmt=PHANTOM_FORMAT)


def baseline_table(kind: str, seed: int, *, config: ScannerConfig | None = None) -> np.ndarray:
    """The baseline generator's phantom as the ``(M, 4)`` table its file holds; numpy only.

    The recipe of ``Part1_Generator.py`` with the arguments of ``Orchestrator.py``: the legacy
    generator seeded with ``seed`` draws ``n_scatterers`` uniform numbers for X, then Y, then Z:
    ``X = (u - 1/2) x_max``, ``Y = (u - 1/2) 2 r``, ``Z = u H``; Energy 1 % (``"uniform"``), or
    0.01 % for ``Z <= 400`` µm and 2.5 % below (``"layers"``); every value rounded as the file
    stores it (``%.4e``). Byte for byte the published files (their git blob hashes, tested).
    """
    if kind not in BASELINE_KINDS:
        raise ValueError(f"kind must be one of {BASELINE_KINDS}, got {kind!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**32:
        raise ValueError(f"seed must be an integer in [0, 2**32), got {seed!r}")
    cfg = ScannerConfig() if config is None else config
    if not isinstance(cfg, ScannerConfig):
        raise TypeError(f"config must be a ScannerConfig or None, got {type(cfg).__name__}")
    rng = np.random.RandomState(int(seed))
    n = cfg.n_scatterers
    x = (rng.random_sample(n) - 0.5) * cfg.x_max
    y = (rng.random_sample(n) - 0.5) * (2.0 * cfg.beam_radius)
    z = rng.random_sample(n) * cfg.depth_range
    if kind == "uniform":
        energy = np.full(n, UNIFORM_ENERGY)
    else:
        energy = np.where(z > LAYERS_BOUNDARY, LAYERS_ENERGY[1], LAYERS_ENERGY[0])
    buffer = io.BytesIO()
    np.savetxt(buffer, np.column_stack([x, y, z, energy]), fmt=PHANTOM_FORMAT)
    buffer.seek(0)
    return np.loadtxt(buffer, dtype=np.float64, ndmin=2, comments=None)


def baseline_phantom(kind: str, seed: int | str, *, config: ScannerConfig | None = None):
    """The challenge baseline's phantom, regenerated exactly from its seed.

    Parameters
    ----------
    kind : {"uniform", "layers"}
        ``"uniform"``: every scatterer 1 %; ``"layers"``: 0.01 % above 400 µm, 2.5 % below
        (the self-consistency check of ``Orchestrator.py``).
    seed : int or {"A", "B"}
        Legacy ``np.random.seed`` value; ``"A"`` = 42 and ``"B"`` = 101 are the published
        realisations (``Scatterers_Exp*_A/B.txt``).
    config : ScannerConfig, optional
        Box and count (default: the challenge's).

    Returns
    -------
    xarray.Dataset
        As :func:`read_phantom`: what the published file holds (values rounded to ``%.4e``).

    Examples
    --------
    >>> ph = baseline_phantom("layers", "A")
    >>> ph.sizes["scatterer"], float(ph.x[0]), ph.attrs["n_outside_box"]
    (300000, -385.41, 0)
    """
    if isinstance(seed, str):
        if seed not in BASELINE_SEEDS:
            raise ValueError(f"seed must be an integer or one of {list(BASELINE_SEEDS)}: {seed!r}")
        seed = BASELINE_SEEDS[seed]
    cfg = ScannerConfig() if config is None else config
    table = baseline_table(kind, seed, config=cfg)
    return _scene(table, cfg, f"baseline {kind} seed {seed}")


# --- scans ------------------------------------------------------------------------------


def read_png(path: str | os.PathLike) -> np.ndarray:
    """The gray levels of an 8-bit PNG scan as a uint8 array ``(depth, x)``; Pillow only.

    Grayscale (``L``) files are read as they are; RGB/RGBA files (the published scans, written
    by Matplotlib) must have equal colour channels and an opaque alpha.

    Raises
    ------
    ValueError
        If the file is not an 8-bit grayscale image or an RGB(A) image with equal channels.

    Examples
    --------
    >>> from importlib.resources import files
    >>> read_png(files("speckle.data") / "synthoct" / "Scan_Exp1_Uniform_A.png").shape
    (256, 512)
    """
    from PIL import Image

    with Image.open(path) as image:
        mode = image.mode
        data = np.asarray(image)
    if mode == "L":
        return np.ascontiguousarray(data, dtype=np.uint8)
    if mode in ("RGB", "RGBA") and data.dtype == np.uint8:
        rgb = data[..., :3]
        if np.all(rgb == rgb[..., :1]) and (mode == "RGB" or np.all(data[..., 3] == 255)):
            return np.ascontiguousarray(rgb[..., 0])
    raise ValueError(
        f"{path}: not an 8-bit gray scan (mode {mode!r}; RGB(A) is accepted only with equal "
        "channels and an opaque alpha)"
    )


def write_png(levels: np.ndarray, path: str | os.PathLike) -> None:
    """Write a uint8 array ``(depth, x)`` as an 8-bit grayscale PNG, atomically; Pillow only."""
    from PIL import Image

    if not isinstance(levels, np.ndarray) or levels.dtype != np.uint8:
        raise TypeError(f"scan must be a uint8 array, got {getattr(levels, 'dtype', levels)!r}")
    if levels.ndim != 2:
        raise ValueError(f"scan must be 2-D (depth, x), got shape {levels.shape}")
    if levels.size == 0:
        raise ValueError(f"scan is empty (shape {levels.shape}): a PNG needs >= 1 pixel")
    with atomic_path(path) as tmp:
        Image.fromarray(np.ascontiguousarray(levels), mode="L").save(tmp, format="PNG")


def scan_array(levels: np.ndarray, config: ScannerConfig | None, source: str | None = None):
    """Label a uint8 scan ``(depth, x)`` with coordinates in µm (``config``'s geometry; without
    one, the challenge's 6 µm pixel and line pitch, lines centred as the scanner's)."""
    import xarray as xr

    from ..conventions import attrs, coord

    n_depth, n_x = levels.shape
    if config is None:
        base = ScannerConfig()
        config = dataclasses.replace(
            base, n_pixels=max(n_depth, 2), n_lines=n_x, x_max=n_x * base.line_pitch
        )
    elif (config.n_pixels, config.n_lines) != (n_depth, n_x):
        raise ValueError(
            f"scan has shape {levels.shape} (depth, x), config expects "
            f"({config.n_pixels}, {config.n_lines}) (n_pixels, n_lines)"
        )
    depth = np.arange(n_depth) * config.pixel_size
    extra = {} if source is None else {"source": source}
    return xr.DataArray(
        levels,
        dims=("depth", "x"),
        coords={"depth": coord("depth", depth), "x": coord("x", config.line_positions)},
        name="scan",
        attrs={**attrs("dimensionless", "8-bit logarithmic OCT scan (51 dB)"), **extra},
    )


def read_scan(path: str | os.PathLike, *, config: ScannerConfig | None = None):
    """Read an 8-bit PNG scan (the official scanner's or :func:`write_scan`'s).

    Parameters
    ----------
    path : str or path-like
        PNG file (grayscale, or RGB(A) with equal channels as the published scans).
    config : ScannerConfig, optional
        Geometry of the coordinates; default the challenge's 6 µm pixels and line pitch.

    Returns
    -------
    xarray.DataArray
        uint8, dims ``(depth, x)``, coordinates in µm.

    Examples
    --------
    >>> from importlib.resources import files
    >>> scan = read_scan(files("speckle.data") / "synthoct" / "Scan_Exp2_Layers_A.png")
    >>> scan.dims, float(scan.x[0]), float(scan.depth[1])
    (('depth', 'x'), -1536.0, 6.0)
    """
    check_path(path)
    return scan_array(read_png(path), config, str(path))


def write_scan(scan: object, path: str | os.PathLike) -> None:
    """Write a scan as an 8-bit grayscale PNG, atomically.

    Parameters
    ----------
    scan : xarray.DataArray or numpy.ndarray
        uint8, ``(depth, x)`` (a DataArray is transposed to that order).
    path : str or path-like
        Output PNG.

    Raises
    ------
    TypeError
        If the values are not uint8.

    Examples
    --------
    >>> import numpy as np, pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.png"
    >>> write_scan(np.zeros((4, 3), np.uint8), p)
    >>> read_scan(p).shape
    (4, 3)
    """
    if hasattr(scan, "dims") and hasattr(scan, "transpose"):
        if set(scan.dims) != {"depth", "x"}:
            raise ValueError(f"scan must have dims ('depth', 'x'), got {scan.dims}")
        scan = scan.transpose("depth", "x").values
    write_png(scan, path)
