"""The contract of the public API (issue 36): every public function and class refuses bad input.

Part 1 walks ``speckle.__all__`` (functions and classes; constants are not called). Each name
needs an entry in :data:`ENTRIES`: a valid call (tiny, fast arguments) and, per parameter, a
KIND. :data:`KINDS` turns a kind into the usual bad values (NaN, inf, negative, zero where a size
is meant, a float where an int is meant, a string, a bool, an empty or one-pixel array,
mismatched shapes or coordinates, a complex array where a real one is meant, a size beyond the
memory bound :data:`speckle._validate.MAX_BYTES`). Parameters without an entry kind take the
default kind of their name (:data:`BY_NAME`). For every (function, parameter, bad value) the
call must

* raise ``ValueError`` or ``TypeError`` whose message names the parameter (for a mismatch, the
  parameter or its partner), raised by the package's own code (the innermost frame of the
  traceback lies in ``speckle/``, not in numpy, scipy or xarray: the check ran before the work
  reached them), and for a ``huge`` size with less than :data:`HUGE_PEAK` bytes allocated on the
  way (``tracemalloc``: the bound is checked before the allocation), or
* be listed in :data:`ANSWERS` with the reason it is a documented right answer (then the call
  must return, not raise).

A public name without an entry fails with the entry to add; an entry whose kinds miss a
parameter of the signature fails naming the parameter. The property tests that exist
(``tests/test_strict.py``'s malformed-input test, the ``VALID`` tables of
``tests/system/test_properties_*.py``, ``tests/scene/test_properties_*.py``) draw other
values (``None``, ``{}``, ``[]``, ``-1e300``) through :mod:`tests.conftest`'s ``Malformed``
driver; this module is their exhaustive deterministic counterpart over the whole API.

Part 2 walks the pipeline's config sections: for every leaf key of the sections the schema
declares (number or integer), bad values (a float for an integer, NaN, inf, a negative or zero
size, a huge size) must be refused when the workflow loads (the schema validation or
:func:`check_config`) with the key named; and an unknown key is refused in every section.
"""

from __future__ import annotations

import copy
import functools
import inspect
import os
import re
import tracemalloc
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import speckle

REPO = Path(__file__).resolve().parents[1]
PACKAGE = str(Path(speckle.__file__).resolve().parent)
#: Largest allocation (bytes, tracemalloc peak) a refused ``huge`` request may make on the way.
HUGE_PEAK = 64 * 2**20
NAN, INF = float("nan"), float("inf")
#: The known gaps: cases that fail today, one per line. The list only shrinks: a new failure
#: fails the test, and so does a listed case that now holds (remove its line).
GAPS = Path(__file__).with_name("contract_gaps.txt")


# --- fixtures: tiny valid objects, built once ----------------------------------------------
class Fixtures:
    """Tiny valid inputs shared by the entries (each built on first use)."""

    @functools.cached_property
    def src(self):
        return speckle.spectrum(16, 128.0, k0_dk=3.0)

    @functools.cached_property
    def scene(self):
        return speckle.random_scatterers(4, 1.0, n_pixels=16, depth_range=128.0, seed=1)

    @functools.cached_property
    def dscene(self):
        """A deformable scene (populated for strains up to 0.02)."""
        return speckle.deformable_scene(4, 1.0, n_pixels=16, depth_range=128.0, seed=1, strain=0.02)

    @functools.cached_property
    def img(self):
        return speckle.bscan(self.scene, self.src)

    @functools.cached_property
    def pair(self):
        """A reference and a rigidly shifted B-scan (Datasets), 32 x 16 pixels."""
        sc = speckle.random_scatterers(16, 4.0, n_pixels=32, depth_range=256.0, seed=2)
        s = speckle.spectrum(32, 256.0, k0_dk=3)
        return speckle.bscan(sc, s), speckle.bscan(speckle.translate(sc, 3.0, wrap=True), s)

    @functools.cached_property
    def strain_pair(self):
        """Complex fields (depth, x) of 64 x 8 pixels at strains 0 and 1e-3, pixel 8 µm."""
        n, p = 64, 8.0
        src = speckle.spectrum(n, n * p, k0_dk=10, shape="gaussian", fwhm=0.5 * np.pi / p)
        sc = speckle.deformable_scene(8, 4.0, n_pixels=n, depth_range=n * p, seed=4, strain=1e-3)
        b = speckle.bscan(speckle.uniaxial_strain(sc, [0.0, 1e-3]), src)
        f = b.field.transpose("strain", "depth", "x").values
        return f[0], f[1], float(src.attrs["k0"])

    @functools.cached_property
    def frames(self):
        ref, dfm, _ = self.strain_pair
        return np.stack([ref, dfm, dfm])

    @functools.cached_property
    def regions(self):
        from speckle.scene import regions as reg

        return reg.make_regions(
            reg.background(density=0.01, attenuation=0.001),
            reg.circle(20.0, 20.0, 8.0, density=0.02),
        )

    @functools.cached_property
    def background(self):
        from speckle.scene import regions as reg

        return reg.background(density=0.01)

    @functools.cached_property
    def shared(self):
        return speckle.shared_scene(
            self.regions, z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile=20.0
        )

    @functools.cached_property
    def labels(self):
        return xr.DataArray(
            np.array([[0, 0], [1, 1], [1, 1]]),
            dims=("depth", "x"),
            coords={"depth": [0.0, 8.0, 16.0], "x": [0.0, 8.0]},
        )

    @functools.cached_property
    def props(self):
        return xr.Dataset(
            {"attenuation": ("region", [2e-3, 8e-3]), "backscatter": ("region", [1.0, 2.0])},
            coords={"region": [0, 1]},
        )

    @functools.cached_property
    def lines_scene(self):
        """A scatterer field on lines whose x and depth match :attr:`labels`."""
        sc = speckle.random_scatterers(2, 1.0, n_pixels=3, depth_range=24.0, seed=1)
        return sc

    @functools.cached_property
    def pol_img(self):
        return speckle.bscan(speckle.depolarize(self.scene, 0.3, seed=1), self.src)

    @functools.cached_property
    def fem_labels(self):
        return speckle.inclusion_labels(
            np.arange(4.0, 64.0, 8.0), np.arange(0.0, 48.0, 8.0), (32.0, 24.0), 10.0
        )

    @functools.cached_property
    def fem(self):
        return speckle.compress_phantom(self.fem_labels, {0: 10.0, 1: 40.0}, 0.3, strain=0.01)

    @functools.cached_property
    def system(self):
        return speckle.datasheet(
            840.0,
            50.0,
            32,
            camera_range_nm=(790.0, 890.0),
            refractive_index=1.38,
            spectral_resolution_nm=0.1,
            fill_factor=0.9,
            aline_pitch=5.0,
            beam_waist=8.0,
        )

    @functools.cached_property
    def camera(self):
        from speckle.system import spectrometer as sp

        signal, k = sp.camera_signal(self.system, [[100.0, 200.0]], [[1.0, 0.5]], detection="real")
        return signal, k, sp.grid_wavenumbers(self.system)

    @functools.cached_property
    def beam_args(self):
        rng = np.random.default_rng(0)
        z, x = rng.uniform(10.0, 120.0, 20), rng.uniform(-8.0, 40.0, 20)
        return dict(
            z=z,
            x=x,
            amplitude=np.ones(20, complex),
            lines=np.arange(8) * 4.0,
            waist=6.0,
            n_pixels=16,
            depth_range=128.0,
            k0=float(self.src.attrs["k0"]),
        )

    @functools.cached_property
    def beam_problem(self):
        return speckle.beam_problem(**self.beam_args)

    @functools.cached_property
    def looks(self):
        return speckle.frequency_looks(self.img, speckle.subband_apodizations(16, 2))

    @functools.cached_property
    def speckled(self):
        """A fully developed speckle intensity image 32 x 32 (numpy)."""
        rng = np.random.default_rng(3)
        return rng.exponential(1.0, (32, 32))

    @functools.cached_property
    def twin_image(self):
        rng = np.random.default_rng(5)
        n, lines = 48, 64
        return xr.DataArray(
            rng.exponential(1.0, (n, lines)) * np.exp(-np.arange(n) / 200.0)[:, None],
            dims=("depth", "x"),
            coords={"depth": np.arange(n) * 5.75, "x": np.arange(lines) * 4.0},
            attrs={"kind": "intensity", "pixel_size": 5.75, "pitch": 4.0},
        )

    @functools.cached_property
    def series(self):
        """A complex series (time, depth, x) of 6 x 8 x 4 pixels (Gaussian speckle)."""
        rng = np.random.default_rng(0)
        return rng.normal(size=(6, 8, 4)) + 1j * rng.normal(size=(6, 8, 4))

    @functools.cached_property
    def series_da(self):
        """:attr:`series` as a DataArray (time, depth, x) with coordinates."""
        return xr.DataArray(
            self.series,
            dims=("time", "depth", "x"),
            coords={
                "time": np.arange(6) * 1e-3,
                "depth": np.arange(8) * 8.0,
                "x": np.arange(4) * 8.0,
            },
        )

    @functools.cached_property
    def sc_config(self):
        return speckle.ScannerConfig(n_pixels=16, n_lines=8, x_max=96.0, n_scatterers=50)

    @functools.cached_property
    def sc_phantom(self):
        return speckle.baseline_phantom("uniform", 1, config=self.sc_config)

    @functools.cached_property
    def sc_scan(self):
        return speckle.synthoct_scan(self.sc_phantom, self.sc_config)

    @functools.cached_property
    def sc_files(self):
        """The scanner's INI, a phantom table and a scan PNG, written once."""
        ini, txt, png = self.tmp / "c.ini", self.tmp / "p.txt", self.tmp / "s.png"
        speckle.write_scanner_config(self.sc_config, ini)
        speckle.write_phantom(self.sc_phantom, txt, config=self.sc_config)
        speckle.write_scan(self.sc_scan, png)
        return ini, txt, png

    @functools.cached_property
    def tmp(self):
        import tempfile

        return Path(tempfile.mkdtemp(prefix="speckle-contract-"))

    @functools.cached_property
    def moved(self):
        """:attr:`shared` moved by Brownian motion over three times 1 ms apart."""
        return speckle.brownian_motion(self.shared, np.arange(3) * 1e-3, diffusion=1.0, seed=1)

    @functools.cached_property
    def flow_geometry(self):
        return dict(
            n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0, density=4.0, margin=2
        )

    @functools.cached_property
    def flow_phantom(self):
        return dict(
            interface=24.0,
            backscatter=[1.0, 2.0],
            cells=dict(centre=[12.0, 16.0], radius=6.0, diffusion=0.5),
            vessel=dict(depth=44.0, radius=8.0, peak_velocity=2000.0),
            angiography=dict(frames=3, interval=2e-3),
            doct=dict(frames=4, interval=4e-3, delays=[4e-3, 8e-3]),
            window=[3, 3],
            n_bands=2,
        )

    @functools.cached_property
    def metric_image(self):
        """A 24 x 24 8-bit grey image (the smallest the SynthOCT metrics take is 21 x 21)."""
        return np.random.default_rng(0).integers(0, 256, (24, 24), dtype=np.uint8)

    @functools.cached_property
    def npy(self):
        path = self.tmp / "image.npy"
        np.save(path, np.random.default_rng(0).uniform(1.0, 2.0, (20, 30)))
        return path

    @functools.cached_property
    def nc(self):
        path = self.tmp / "image.nc"
        speckle.to_netcdf(self.img, path)
        return path


F = Fixtures()


# --- kinds: one table of bad values -----------------------------------------------------------
def _scalar(*extra):
    common = [("nan", NAN), ("inf", INF), ("string", "1"), ("bool", True), ("complex", 1j)]
    return lambda v: common + list(extra)


def _int(*extra):
    common = [("float", 2.5), ("string", "4"), ("bool", True), ("nan", NAN)]
    return lambda v: common + list(extra)


def _with_nan(v):
    """A copy of ``v`` with its first element NaN."""
    if isinstance(v, xr.Dataset):
        name = next(n for n, a in v.data_vars.items() if a.dtype.kind in "fc")
        return v.assign({name: _with_nan(v[name])})
    if isinstance(v, xr.DataArray):
        out = v.astype(np.result_type(v.dtype, float), copy=True)
        out.values.flat[0] = NAN
        return out
    a = np.array(v, dtype=np.result_type(np.asarray(v).dtype, float))
    a.flat[0] = NAN
    return a


def _slice(v, stop):
    if isinstance(v, xr.DataArray | xr.Dataset):
        return v.isel({d: slice(0, stop) for d in v.dims})
    a = np.asarray(v)
    if a.ndim == 0:  # a scalar: its empty and one-element versions are 1-D
        return np.full(stop, a)
    return a[tuple(slice(0, stop) for _ in range(a.ndim))]


def _complex(v):
    return v * (1.0 + 0.5j) if not isinstance(v, list) else np.asarray(v) * (1.0 + 0.5j)


def _trim(v):
    """One row fewer along the first axis (a shape mismatch with the partner)."""
    if isinstance(v, xr.DataArray | xr.Dataset):
        d = next(iter(v.dims))
        return v.isel({d: slice(0, -1)})
    a = np.asarray(v)
    return a[:-1]


def _shifted(v):
    """The same values on coordinates shifted by half a step (a coordinate mismatch)."""
    d = "depth" if "depth" in v.dims else next(iter(v.dims))
    c = v[d].values.astype(float)
    step = float(np.diff(c)[0]) if c.size > 1 else 1.0
    return v.assign_coords({d: c + 0.5 * step})


def _array(real=True, min_pixels=True, partner=False, nan=True):
    def bad(v):
        if v is None:  # an optional array: a small stand-in to spoil
            v = np.array([1.0, 2.0])
        out = [("string", "x"), ("empty", _slice(v, 0))]
        if nan:
            out.append(("nan", _with_nan(v)))
        if real:
            out.append(("complex", _complex(v)))
        if min_pixels:
            out.append(("one_pixel", _slice(v, 1)))
        if partner:
            out.append(("mismatch_shape", _trim(v)))
            if isinstance(v, xr.DataArray | xr.Dataset):
                out.append(("mismatch_coords", _shifted(v)))
        return out

    return bad


def _dataset(v):
    out = [("string", "x"), ("array", np.zeros(3))]
    return out if v is None else [*out, ("empty", _slice(v, 0))]


KINDS = {
    "positive": _scalar(("negative", -1.0), ("zero", 0.0)),
    "positive_length": _scalar(("negative", -1.0), ("zero", 0.0)),
    "nonnegative": _scalar(("negative", -1.0)),
    "real": _scalar(),
    "probability": _scalar(("negative", -0.1), ("above_one", 1.5)),
    "count": _int(("zero", 0), ("negative", -1)),
    "size": _int(("zero", 0), ("negative", -1), ("huge", 10**12)),
    "count0": _int(("negative", -1)),
    "seed": _int(("negative", -1)),
    "choice": lambda v: [("unknown", "no-such-choice"), ("number", 1)],
    "flag": lambda v: [("string", "False"), ("number", 0.5), ("int", 1)],
    "window": _int(("zero", 0), ("negative", -1), ("pair_zero", (4, 0)), ("huge", 10**6)),
    "positions": _array(real=True, min_pixels=False),
    "real_array": _array(real=True, min_pixels=False),
    "complex_array": _array(real=False, min_pixels=False),
    "image": _array(real=True),
    "complex_image": _array(real=False),
    "image2": _array(real=True, partner=True),
    "complex_image2": _array(real=False, partner=True),
    "dataset": _dataset,
    "mapping": lambda v: [("string", "x"), ("list", [1, 2])],
    # a float: an int path is a file descriptor to open() (and closing it closed pytest's)
    "path": lambda v: [("missing", "/no/such/file.npy"), ("number", 3.5)],
    "dims": lambda v: [("unknown", "no_such_dim"), ("number", 1)],
    "none": lambda v: [],
}
#: Default kind of a parameter by its name (an entry's kinds override it).
BY_NAME = {
    "n_pixels": "size",
    "n_alines": "size",
    "n_lines": "size",
    "n_frames": "size",
    "n_samples": "size",
    "n_looks": "count",
    "chunk": "count",
    "seed": "seed",
    "depth_range": "positive_length",
    "waist": "positive_length",
    "k0": "real",
    "density": "positive",
    "method": "choice",
    "kind": "choice",
    "tol": "positive",
    "snr_db": "real",
    "pixel_size": "positive_length",
    "pitch": "positive_length",
    "wrap": "flag",
    "diffusion": "positive",
    "interval": "positive",
    "x": "positions",
    "lines": "positions",
    "z": "positions",
    "amplitude": "complex_array",
    "source": "dataset",
    "scene": "dataset",
    "spectrum": "real_array",
    "refractive_index": "positive",
    "oversample": "count",
    "upsample": "count",
    "window": "window",
    "step": "window",
    "progress": "flag",
    "poisson_ratio": "real",
    "strain": "real",
    "focus": "real",
    "rayleigh_range": "positive",
    "mode": "choice",
    "domain": "choice",
    "size": "count",
    "looks": "positive",
    "log": "flag",
    "dims": "dims",
    "dim": "dims",
    "image": "dataset",
    "intensity": "image",
    "signal_intensity": "positive",
}


# --- entries ----------------------------------------------------------------------------------
@dataclass
class Entry:
    """A valid call (``valid()`` returns fresh keyword arguments) and the kinds that differ from
    :data:`BY_NAME` (``"none"`` with a reason in ``why`` when a parameter has no bad value)."""

    valid: object
    kinds: dict = field(default_factory=dict)
    why: str = ""
    record: str = ""  #: a plain record another function builds and checks: no bad values fed


def E(valid, why="", record="", **kinds):
    return Entry(valid, kinds, why, record)


def _bscan_like(**kw):
    return lambda: dict(scene=F.scene, source=F.src, **kw)


@functools.cache
def _pdms_crop() -> xr.DataArray:
    """The shipped PDMS image's first 160 rows and 64 lines (log data, as load_image reads it)."""
    from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path

    image = speckle.load_image(
        sample_path("pdms"),
        kind="log",
        dims=("depth", "x"),
        pixel_size=SAMPLE_PIXEL_SIZE,
        pitch=SAMPLE_PITCH["pdms"],
    )
    return image[:160, :64]


_REAL_WHY = (
    "rows, noise_rows: (start, stop) row pairs, checked against the image "
    "(tests/studies/test_phantom_real.py)"
)

ENTRIES: dict[str, Entry] = {
    "equivalent_system": E(
        lambda: dict(image=_pdms_crop(), rows=(90, 150), noise_rows=(5, 40), beam_radius=8.0),
        image="image",
        rows="none",
        noise_rows="none",
        beam_radius="positive_length",
        per_cell="positive",
        wavelength="positive_length",
        denoise="flag",
        why=_REAL_WHY,
    ),
    "real_tissue_phantom": E(
        lambda: dict(
            image=_pdms_crop(), rows=(90, 150), noise_rows=(5, 40), seeds=(1, 2), beam_radius=8.0
        ),
        image="image",
        rows="none",
        noise_rows="none",
        seeds="none",
        beam_radius="positive_length",
        per_cell="positive",
        max_layers="count",
        variant="choice",
        why=_REAL_WHY + "; seeds: 2..16 distinct seeds (the same tests)",
    ),
    # --- scene -------------------------------------------------------------------------------
    "random_scatterers": E(
        lambda: dict(n_alines=2, density=1.0, n_pixels=8, depth_range=64.0, seed=0),
        amplitude="choice",
        count="choice",
        z_range="none",
        aline_pitch="positive_length",
        first_aline="count0",
        why="z_range: tuples checked in test_strict",
    ),
    "deformable_scene": E(
        lambda: dict(n_alines=2, density=1.0, n_pixels=8, depth_range=64.0, seed=0, strain=0.01),
        amplitude="choice",
        count="choice",
        strain="real_array",
    ),
    "translate": E(lambda: dict(scene=F.dscene, dz=1.0, dx=0.5), dz="real_array", dx="real"),
    "uniaxial_strain": E(
        lambda: dict(scene=F.dscene, strain=0.01),
        strain="real_array",
        x_centre="real",
        y_centre="real",
    ),
    "displace": E(
        lambda: dict(scene=F.scene, displacement=lambda z, x: 0.1 * z),
        displacement="none",
        why="displacement: a callable or a Dataset, checked in tests/scene",
    ),
    "layer_stack": E(
        lambda: dict(tops=[50.0, 80.0], properties={"backscatter": [2.0, 3.0]}),
        tops="positions",
        properties="none",
        why="**properties: arrays by name",
    ),
    "make_regions": E(
        lambda: dict(shapes=(F.background,)), shapes="none", why="*shapes: dicts of region.*"
    ),
    "rasterize": E(
        lambda: dict(regions=F.regions, depth_coord=np.arange(4.0), x_coord=np.arange(3.0)),
        regions="dataset",
        depth_coord="positions",
        x_coord="positions",
    ),
    "region_label": E(
        lambda: dict(regions=F.regions, z=np.array([1.0, 30.0]), x=np.array([1.0, 20.0])),
        regions="dataset",
        y="positions",
    ),
    "region_values": E(
        lambda: dict(labels=F.labels, properties=F.props, name="attenuation"),
        labels="dataset",
        properties="dataset",
        name="choice",
        outside="real",
    ),
    "shared_scene": E(
        lambda: dict(
            regions=F.regions, z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile=20.0
        ),
        regions="dataset",
        z_range="none",
        x_range="none",
        y_range="none",
        tile="positive_length",
        why="ranges: pairs checked in tests/scene/test_properties_scene.py",
    ),
    "from_lines": E(lambda: dict(scene=F.scene)),
    "compress_phantom": E(
        lambda: dict(
            labels=F.fem_labels,
            youngs_modulus={0: 10.0, 1: 40.0},
            poisson_ratio=0.3,
            strain=0.01,
            mesh_size=8.0,
        ),
        labels="dataset",
        youngs_modulus="none",
        poisson_ratio="probability",
        contact="choice",
        mesh_size="positive_length",
        why="youngs_modulus: a mapping, tests/scene/test_properties_fem",
    ),
    "displacement_at": E(
        lambda: dict(result=F.fem, z=[10.0, 20.0], x=[5.0, 30.0]), result="dataset"
    ),
    "inclusion_labels": E(
        lambda: dict(
            depth=np.arange(4.0, 64.0, 8.0),
            x=np.arange(0.0, 48.0, 8.0),
            center=(32.0, 24.0),
            radii=10.0,
        ),
        depth="positions",
        center="none",
        radii="positive_length",
        label="count0",
        background="none",
        why="center: a pair; background: a label map or int",
    ),
    "inclusion_strain": E(
        lambda: dict(
            strain=0.01,
            youngs_modulus=10.0,
            poisson_ratio=0.3,
            inclusion_modulus=40.0,
            inclusion_poisson_ratio=0.3,
        ),
        youngs_modulus="positive",
        inclusion_modulus="positive",
        poisson_ratio="probability",
        inclusion_poisson_ratio="probability",
    ),
    "layer_strains": E(
        lambda: dict(
            thickness=[10.0, 20.0],
            youngs_modulus=[10.0, 30.0],
            poisson_ratio=[0.2, 0.3],
            strain=0.01,
        ),
        thickness="real_array",
        youngs_modulus="real_array",
        poisson_ratio="real_array",
    ),
    "layered_labels": E(
        lambda: dict(
            depth=np.arange(4.0, 64.0, 8.0), x=np.arange(0.0, 48.0, 8.0), interfaces=[20.0, 40.0]
        ),
        depth="positions",
        interfaces="positions",
    ),
    # --- system ------------------------------------------------------------------------------
    "spectrum": E(
        lambda: dict(n_pixels=8, depth_range=64.0, k0_dk=3.0),
        k0_dk="positive",
        wavelength="positive_length",
        shape="choice",
        fwhm="positive",
        fwhm_fraction="positive",
        weights="real_array",
    ),
    "delta_k": E(lambda: dict(n_pixels=8, depth_range=64.0)),
    "k0_from_wavelength": E(lambda: dict(wavelength=1.3), wavelength="positive_length"),
    "wavelength_from_k0": E(lambda: dict(k0=5.0), k0="positive"),
    "datasheet": E(
        lambda: dict(
            wavelength_nm=840.0, bandwidth_nm=50.0, camera_pixels=32, camera_range_nm=(790.0, 890.0)
        ),
        wavelength_nm="positive",
        bandwidth_nm="positive",
        camera_pixels="size",
        camera_range_nm="none",
        imaging_depth="positive_length",
        beam_waist="positive_length",
        lateral_resolution="positive_length",
        aline_pitch="positive_length",
        spectral_resolution_nm="nonnegative",
        fill_factor="probability",
        label="none",
        why="camera_range_nm: a pair, tests/system/test_datasheet.py; label: free text",
    ),
    "System": E(
        lambda: dict(
            wavelength=0.84,
            bandwidth=0.05,
            camera_pixels=32,
            wavelength_min=0.79,
            wavelength_max=0.89,
        ),
        wavelength="positive_length",
        bandwidth="positive_length",
        camera_pixels="size",
        wavelength_min="positive_length",
        wavelength_max="positive_length",
        beam_waist="positive_length",
        aline_pitch="positive_length",
        spectral_resolution="nonnegative",
        fill_factor="probability",
        label="none",
        why="label: free text",
    ),
    "example_system": E(
        lambda: dict(name="840nm"),
        name="choice",
        overrides="none",
        why="**overrides: datasheet's keys",
    ),
    "attenuate": E(lambda: dict(scene=F.scene, attenuation=0.001), attenuation="nonnegative"),
    "attenuate_regions": E(
        lambda: dict(scene=F.lines_scene, labels=F.labels, properties=F.props),
        labels="dataset",
        properties="dataset",
    ),
    "attenuation_map": E(
        lambda: dict(labels=F.labels, properties=F.props), labels="dataset", properties="dataset"
    ),
    "optical_depth": E(lambda: dict(z=[1.0, 2.0], attenuation=0.001), attenuation="nonnegative"),
    "backscatter": E(lambda: dict(scene=F.scene, value=2.0), value="nonnegative"),
    "backscatter_regions": E(
        lambda: dict(scene=F.lines_scene, labels=F.labels, properties=F.props),
        labels="dataset",
        properties="dataset",
    ),
    "rolloff": E(
        lambda: dict(scene=F.scene, z_max=64.0, resolution=0.5),
        z_max="positive_length",
        resolution="nonnegative",
        curve="none",
        why="curve: a pair of arrays, tests/system/test_rolloff.py",
    ),
    "add_noise": E(
        lambda: dict(image=F.img, snr_db=20.0, seed=3, signal_intensity=1.0),
        signal_intensity="positive",
        spectrum="dataset",
    ),
    "add_complex_noise": E(
        lambda: dict(field=F.img.field.values, snr_db=20.0, seed=3), field="complex_image"
    ),
    "depolarize": E(
        lambda: dict(scene=F.scene, depolarization=0.3, seed=2),
        depolarization="probability",
        labels="dataset",
    ),
    "degree_of_polarization": E(lambda: dict(image=F.pol_img)),
    "phase_perturb": E(
        lambda: dict(scene=F.shared, index_variance=1e-6, correlation_length=20.0, k0=1.0, seed=4),
        index_variance="nonnegative",
        correlation_length="positive_length",
        lateral_correlation_length="positive_length",
    ),
    "log_compress": E(
        lambda: dict(intensity=F.img.intensity, gain=20.0, offset=100.0, bits=8),
        gain="positive",
        offset="real",
        bits="count",
    ),
    "log_expand": E(
        lambda: dict(
            data=speckle.log_compress(F.img.intensity, 20.0, 100.0), gain=20.0, offset=100.0
        ),
        data="image",
        gain="positive",
        offset="real",
    ),
    "add_floor": E(
        lambda: dict(intensity=F.img.intensity, floor=0.1, mean_intensity=1.0),
        floor="nonnegative",
        mean_intensity="positive",
    ),
    "interferogram": E(
        lambda: dict(
            z=[[50.0]],
            amplitude=[[1.0]],
            wavenumber=F.camera[1],
            spectrum=np.ones(F.camera[1].size),
            k0=F.system.k0,
        ),
        wavenumber="positions",
        pixel_width="nonnegative",
        resolution="nonnegative",
        dispersion="none",
        detection="choice",
        dc="flag",
        autocorrelation="flag",
        reference_power="positive",
        why="dispersion: a mapping, tests/system",
    ),
    "interferogram_bytes": E(
        lambda: dict(lines=1, scatterers=10, pixels=32),
        lines="count",
        scatterers="count0",
        pixels="count",
        finite_pixels="flag",
        autocorrelation="flag",
    ),
    "interpolation_gain": E(
        lambda: dict(theta=1.0, t=0.3, method="cubic"), theta="real_array", t="real_array"
    ),
    "process_interferogram": E(
        lambda: dict(
            signal=F.camera[0],
            grid=F.camera[2],
            k0=F.system.k0,
            wavenumber=F.camera[1],
            resample="cubic",
        ),
        signal="image",
        grid="positions",
        wavenumber="positions",
        background="none",
        resample="choice",
        dispersion="none",
        apodization="choice",
        apodization_fwhm_fraction="probability",
        why="background: array or 'mean'",
    ),
    "resampling_response": E(
        lambda: dict(system=F.system, z=[10.0], method="linear"),
        system="none",
        why="system: a System",
    ),
    "system_ascan": E(
        lambda: dict(system=F.system, z=[[100.0]], amplitude=[[1.0]], resample="linear"),
        system="none",
        background="none",
        resample="choice",
        compensate="none",
        apodization="choice",
        apodization_fwhm_fraction="probability",
        camera="none",
        why="system: a System; **camera: camera_signal's options",
    ),
    # --- imaging -----------------------------------------------------------------------------
    "ascan": E(
        lambda: dict(z=[8.0, 13.0], amplitude=[1.0, 0.5], n_pixels=8, depth_range=64.0, k0=0.1)
    ),
    "pixel_depths": E(lambda: dict(n_pixels=8, depth_range=64.0)),
    "stream_ascans": E(
        lambda: dict(n_alines=4, density=1.0, n_pixels=8, depth_range=64.0, k0=0.1, seed=0),
        amplitude="choice",
        count="choice",
        chunk_lines="count",
        lines="none",
        spectrum="real_array",
        why="lines: an index array",
    ),
    "bscan": E(_bscan_like(), normalise="choice"),
    "expected_intensity": E(
        lambda: dict(density=4.0, n_pixels=8, spectrum=None),
        spectrum="dataset",
        mean_square_amplitude="positive",
    ),
    "beam_scan": E(lambda: dict(F.beam_args), y="positions", lines="positions"),
    "beam_problem": E(lambda: dict(F.beam_args), y="positions", lines="positions"),
    "beam_weight": E(
        lambda: dict(dx=[0.0, 2.0], z=[10.0, 20.0], waist=6.0),
        dx="real_array",
        dy="real_array",
        z="real_array",
    ),
    "beam_estimates": E(
        lambda: dict(scene=F.beam_problem[0], beam=F.beam_problem[1], tol=None),
        scene="none",
        beam="none",
        why="scene, beam: beam_problem's output",
    ),
    "choose_beam_method": E(
        lambda: dict(scene=F.beam_problem[0], beam=F.beam_problem[1], tol=None),
        scene="none",
        beam="none",
        why="scene, beam: beam_problem's output",
    ),
    "Beam": E(
        lambda: dict(waist=6.0, focus=None, rayleigh_range=None),
        record="beam_problem (a NamedTuple of checked values)",
    ),
    "BeamScene": E(
        lambda: {
            k: getattr(F.beam_problem[0], k)
            for k in (
                "z",
                "x",
                "y",
                "amplitude",
                "lines",
                "n_pixels",
                "depth_range",
                "k0",
                "spectrum",
            )
        },
        lines="positions",
        y="none",
        why="a plain record",
        record="beam_problem (a NamedTuple of checked arrays)",
    ),
    "beam_reach": E(lambda: dict(waist=6.0), eps="probability", widening="positive"),
    "scan_lines": E(lambda: dict(n_lines=4, pitch=2.0), start="real"),
    "scan_image": E(
        lambda: dict(scene=F.shared, source=F.src, waist=4.0, lines=speckle.scan_lines(4, 4.0)),
        y="positions",
    ),
    "image_regions": E(
        lambda: dict(
            regions=F.regions,
            source=F.src,
            seed=1,
            waist=6.0,
            lines=speckle.scan_lines(4, 4.0),
            chunk=4,
        ),
        regions="dataset",
        tile="positive_length",
        y="positions",
    ),
    "choose_method": E(
        lambda: dict(n_lines=4, n_scatterers=16, n_pixels=16, spectrum=None, tol=1e-6),
        n_lines="count",
        n_scatterers="count0",
        float64_error="nonnegative",
    ),
    "method_estimates": E(
        lambda: dict(n_lines=4, n_scatterers=16, n_pixels=16, spectrum=None, tol=1e-6),
        n_lines="count",
        n_scatterers="count0",
        float64_error="nonnegative",
    ),
    "speckle_free_image": E(lambda: dict(scene=F.scene, source=F.src), waist="positive_length"),
    "speckle_free_lines": E(
        lambda: dict(z=[[8.0, 13.0]], amplitude=[[1.0, 0.5]], n_pixels=8, depth_range=64.0)
    ),
    "intensity_spectrum": E(lambda: dict(weights=np.ones(8)), weights="real_array"),
    # --- analysis ----------------------------------------------------------------------------
    "speckle_contrast": E(lambda: dict(intensity=F.img.intensity)),
    "contrast_theory": E(
        lambda: dict(density=4.0, n_pixels=16),
        density="positive",
        amplitude="choice",
        count="choice",
    ),
    "fit_exponential": E(
        lambda: dict(intensity=F.speckled.ravel()), chi2_bins="count", intensity="real_array"
    ),
    "fit_rayleigh": E(
        lambda: dict(amplitude=np.sqrt(F.speckled.ravel())),
        chi2_bins="count",
        amplitude="real_array",
    ),
    "correlation_map": E(
        lambda: dict(reference=F.pair[0], deformed=F.pair[1], window=4),
        reference="dataset",
        deformed="dataset",
    ),
    "pearson": E(
        lambda: dict(reference=F.pair[0], deformed=F.pair[1]),
        reference="dataset",
        deformed="dataset",
    ),
    "compensate": E(
        lambda: dict(
            deformed=F.pair[1],
            displacement=speckle.scene.deformation.pixel_displacement(
                lambda z, x: 0 * z, F.pair[1].depth, F.pair[1].x
            ),
        ),
        deformed="dataset",
        displacement="dataset",
        carrier="flag",
    ),
    "correlation_array": E(
        lambda: dict(x=F.speckled, y=F.speckled[::-1].copy(), window=(4, 4)),
        x="complex_image",
        y="complex_image2",
        axes="none",
        modulus="flag",
        why="axes: a pair of axes",
    ),
    "expected_correlation": E(
        lambda: dict(strain=0.0, spectrum=F.src, density=4.0),
        strain="real_array",
        spectrum="dataset",
        kurtosis="positive",
        compensation="choice",
        shift="real",
    ),
    "expected_gamma": E(
        lambda: dict(strain=0.0, spectrum=F.src), strain="real_array", spectrum="dataset"
    ),
    "amplitude_from_gamma": E(lambda: dict(gamma=0.5), gamma="real_array"),
    "oversample_depth": E(
        lambda: dict(field=F.img.field.values, factor=2),
        field="complex_image",
        factor="count",
        axis="none",
        why="axis: numpy's",
    ),
    "resample_depth": E(
        lambda: dict(
            field=F.img.field.values, positions=np.tile(np.arange(16.0)[:, None], 4) + 0.5
        ),
        field="complex_image",
        positions="positions",
    ),
    "sample_field": E(
        lambda: dict(field=F.img.field.values, positions=np.arange(16) + 0.5),
        field="complex_image",
        positions="positions",
    ),
    "track": E(
        lambda: dict(
            reference=F.pair[0], deformed=F.pair[1], window=(16, 8), step=(8, 8), upsample=4
        ),
        reference="dataset",
        deformed="dataset",
        quantity="choice",
        max_error="positive",
        truth="dataset",
    ),
    "track_array": E(
        lambda: dict(
            reference=F.pair[0].field.values,
            deformed=F.pair[1].field.values,
            window=(16, 8),
            step=(8, 8),
            upsample=4,
        ),
        reference="complex_image",
        deformed="complex_image2",
        quantity="choice",
        lateral="flag",
        error="flag",
    ),
    "track_axial": E(
        lambda: dict(
            reference=F.pair[0].field.values,
            deformed=F.pair[1].field.values,
            window=(16, 8),
            step=(8, 8),
            upsample=4,
        ),
        reference="complex_image",
        deformed="complex_image2",
        keep_samples="flag",
    ),
    "interpolate_displacement": E(
        lambda: dict(
            tracked=speckle.track(F.pair[0], F.pair[1], window=(16, 8), step=(8, 8), upsample=4),
            depth=F.pair[0].depth.values,
            x=F.pair[0].x.values,
        ),
        tracked="dataset",
        depth="positions",
        x="positions",
        axial_only="flag",
    ),
    "interpolate_windows": E(
        lambda: dict(
            values=np.ones((2, 2)),
            centre_depth=np.array([4.0, 12.0]),
            centre_x=np.array([1.0, 3.0]),
            depth=np.arange(16.0),
            x=np.arange(4.0),
        ),
        values="image",
        centre_depth="positions",
        centre_x="positions",
        depth="positions",
        x="positions",
        outside="choice",
    ),
    "estimate_strain": E(
        lambda: dict(
            reference=F.strain_pair[0],
            deformed=F.strain_pair[1],
            k0=F.strain_pair[2],
            pixel_size=8.0,
            window=(16, 4),
        ),
        reference="complex_image",
        deformed="complex_image2",
        return_quality="flag",
        options="none",
        why="**options: each method's, tests/analysis/test_strain_inputs.py",
    ),
    "estimate_displacement": E(
        lambda: dict(
            reference=F.strain_pair[0],
            deformed=F.strain_pair[1],
            k0=F.strain_pair[2],
            pixel_size=8.0,
            window=(16, 4),
        ),
        reference="complex_image",
        deformed="complex_image2",
        options="none",
        why="**options: each method's",
    ),
    "accumulate_strain": E(
        lambda: dict(frames=F.frames, k0=F.strain_pair[2], pixel_size=8.0, window=(16, 4)),
        frames="complex_image",
        path="none",
        options="none",
        why="path: a file to stream to; **options: estimate_strain's",
    ),
    "compound": E(lambda: dict(looks=F.looks), looks="dataset"),
    "compounded_contrast": E(lambda: dict(mu=np.eye(2)), mu="complex_image"),
    "frequency_looks": E(
        lambda: dict(img=F.img, apodizations=speckle.subband_apodizations(16, 2)),
        img="dataset",
        apodizations="image",
    ),
    "subband_apodizations": E(
        lambda: dict(n_samples=16, n_looks=2), apodization="choice", overlap="probability"
    ),
    "subband_fwhm": E(lambda: dict(n_pixels=16, n_samples=8)),
    "apodization_correlation": E(
        lambda: dict(apodizations=speckle.subband_apodizations(16, 2)),
        apodizations="complex_image",
        spectrum="real_array",
    ),
    "split_spectrum_contrast": E(
        lambda: dict(weights=np.ones((2, 16)), density=4.0),
        weights="complex_image",
        kurtosis="positive",
    ),
    "noisy_looks": E(
        lambda: dict(looks=F.looks, snr_db=10.0, seed=3),
        looks="dataset",
        signal_intensity="positive",
    ),
    "spatial_looks": E(
        lambda: dict(
            scene=F.shared,
            source=F.src,
            offsets=[0.0, 8.0],
            waist=6.0,
            lines=speckle.scan_lines(4, 4.0),
            chunk=4,
        ),
        offsets="real_array",
    ),
    "angular_looks": E(
        lambda: dict(
            scene=F.shared,
            source=F.src,
            angles=[-3.0, 3.0],
            waist=6.0,
            lines=speckle.scan_lines(4, 4.0),
            chunk=4,
        ),
        angles="real_array",
    ),
    "polarization_looks": E(
        lambda: dict(
            scene=F.shared,
            source=F.src,
            depolarization=0.3,
            seed=1,
            waist=6.0,
            lines=speckle.scan_lines(4, 4.0),
            chunk=4,
        ),
        depolarization="probability",
    ),
    "temporal_looks": E(
        lambda: dict(
            scene=F.shared,
            source=F.src,
            n_frames=2,
            diffusion=1.0,
            interval=0.01,
            seed=1,
            waist=6.0,
            lines=speckle.scan_lines(4, 4.0),
            chunk=4,
        )
    ),
    "brownian_frames": E(
        lambda: dict(scene=F.shared, n_frames=2, diffusion=1.0, interval=0.01, seed=1),
        diffusion="nonnegative",  # D = 0: a static scene (docstring)
    ),
    "brownian_g1": E(
        lambda: dict(tau=[0.0, 0.01], diffusion=1.0, k0=5.0),
        tau="real_array",
        diffusion="nonnegative",  # D = 0: g1 = 1 (docstring)
    ),
    "despeckle": E(
        lambda: dict(intensity=F.speckled, name="median"), name="choice", params="mapping"
    ),
    "filter_available": E(lambda: dict(name="median"), name="choice"),
    "lee": E(lambda: dict(img=F.speckled), img="image", size="count"),
    "kuan": E(lambda: dict(img=F.speckled), img="image", size="count"),
    "frost": E(lambda: dict(img=F.speckled), img="image", size="count", damping="positive"),
    "enl": E(
        lambda: dict(intensity=F.speckled, mask=F.speckled > 0.5),
        mask="none",
        why="mask: boolean, tests/analysis/test_image_quality.py",
    ),
    "cnr": E(
        lambda: dict(image_db=F.speckled, mask_a=F.speckled > 1, mask_b=F.speckled <= 1),
        image_db="image",
        mask_a="none",
        mask_b="none",
        why="masks: boolean",
    ),
    "psnr_db": E(
        lambda: dict(image_db=F.speckled, truth_db=F.speckled + 0.1),
        image_db="image",
        truth_db="image2",
        db_top="real",
        db_range="positive",
    ),
    "ssim_db": E(
        lambda: dict(image_db=F.speckled, truth_db=F.speckled + 0.1),
        image_db="image",
        truth_db="image2",
        db_top="real",
        db_range="positive",
    ),
    "edge_width": E(
        lambda: dict(profile=np.tanh(np.linspace(-4, 4, 32))),
        profile="real_array",
        spacing="positive_length",
    ),
    "peak_fwhm": E(
        lambda: dict(profile=np.exp(-(np.linspace(-4, 4, 33) ** 2))),
        profile="real_array",
        spacing="positive_length",
        background="real",
    ),
    "bandlimited": E(
        lambda: dict(field=F.img.field.values, factor=2),
        field="complex_image",
        factor="count",
        axis="none",
        why="axis: numpy's",
    ),
    "depth_intensity_psf": E(lambda: dict(weights=np.ones(8)), weights="real_array"),
    "log_intensity_moments": E(
        lambda: dict(weights=np.ones(8), waist_pitch=2.0, density=1.0),
        weights="real_array",
        waist_pitch="positive",
        inverse_snr="nonnegative",
    ),
    "sparse_inverse_density": E(
        lambda: dict(log_variance=2.0, weights=np.ones(8), waist_pitch=2.0),
        log_variance="positive",
        weights="real_array",
        waist_pitch="positive",
        inverse_snr="nonnegative",
    ),
    "load_image": E(
        lambda: dict(path=F.npy, kind="intensity", dims=("depth", "x"), pixel_size=1.0, pitch=1.0),
        path="path",
        variable="none",
        dims="none",
        k0="positive",
        why="variable, dims: tests/io/test_load_image.py",
    ),
    "load_measured": E(
        lambda: dict(path=F.npy),
        path="path",
        scale="choice",
        roi="mapping",
        pitch="positive_length",
    ),
    "compare_measured": E(
        lambda: dict(
            image=speckle.load_image(
                F.npy, kind="intensity", dims=("depth", "x"), pixel_size=1.0, pitch=1.0
            ),
            n_blocks=2,
        ),
        image="image",
        n_blocks="count",
    ),
    "fit_system": E(
        lambda: dict(
            image=F.twin_image,
            region={"depth": [0, 48]},
            n_pixels=48,
            max_lag=4,
            n_blocks=4,
            n_bands=0,
        ),
        image="image",
        region="mapping",
        noise_rows="none",
        snr_db="real",
        n_pixels="size",
        max_lag="count",
        n_blocks="count",
        n_bands="count0",
        max_density="positive",
        why="noise_rows: a pair, tests/analysis/test_twin.py",
    ),
    "SystemFit": E(
        lambda: dict(parameters=xr.Dataset(), template=F.twin_image, settings={}),
        parameters="none",
        template="none",
        settings="none",
        why="a record built by fit_system",
        record="fit_system",
    ),
    # --- speckle in time (merged from dynamics/dynstudy) ---------------------------------
    "doppler_shift": E(
        lambda: dict(lag=[0.0, 1e-3], velocity=100.0, k0=5.0), lag="real_array", velocity="real"
    ),
    "g1_axial_flow": E(
        lambda: dict(lag=[0.0, 1e-3], velocity=100.0, spectrum=F.src),
        lag="real_array",
        velocity="real",
        spectrum="dataset",
    ),
    "g1_ballistic": E(
        lambda: dict(lag=[0.0, 1e-3], speed=100.0, k0=5.0, ndim=1),
        lag="real_array",
        speed="nonnegative",
        ndim="count",
        distribution="choice",
        waist="positive_length",
        spectrum="dataset",
    ),
    "g1_brownian": E(
        lambda: dict(lag=[0.0, 1e-3], diffusion=1.0, k0=5.0),
        lag="real_array",
        diffusion="nonnegative",
        waist="positive_length",
        spectrum="dataset",
        lateral_axes="count0",
    ),
    "g1_transverse_flow": E(
        lambda: dict(lag=[0.0, 1e-3], velocity=100.0, waist=6.0), lag="real_array", velocity="real"
    ),
    "liv_expected": E(lambda: dict(g1=[1.0, 0.5, 0.2]), g1="complex_array", ddof="count0"),
    "log_intensity_correlation": E(lambda: dict(g1=[1.0, 0.5, 0.2]), g1="complex_array"),
    "siegert_g2": E(lambda: dict(g1=[1.0, 0.5, 0.2]), g1="complex_array", beta="probability"),
    "speckle_variance_expected": E(
        lambda: dict(g1=[1.0, 0.5, 0.2]), g1="complex_array", ddof="count0"
    ),
    "ssada_expected": E(lambda: dict(g1_bands=[0.5, 0.6]), g1_bands="complex_array"),
    "ssada_ratio": E(lambda: dict(g1=[0.5]), g1="complex_array"),
    "ocds_expected": E(
        lambda: dict(g1=[1.0, 0.8, 0.6, 0.4], lags=[0, 1, 2, 3], delays=(1, 2)),
        g1="complex_array",  # a complex correlation: |g1| is used (docstring)
        lags="real_array",
        delays="none",
        why="delays: a pair, tests/analysis/test_dynamics*",
    ),
    "raster_times": E(
        lambda: dict(n_frames=2, n_lines=4, line_rate=1000.0),
        line_rate="positive",
        frame_interval="positive",
        start="real",
    ),
    "contrast_floors": E(
        lambda: dict(contrast="liv", n_frames=4, snr_db=20.0), contrast="choice", n_frames="size"
    ),
    "expected_contrast": E(
        lambda: dict(contrast="liv", g1=[1.0, 0.5], snr_db=20.0), contrast="choice", g1="real_array"
    ),
    "g1_array": E(
        lambda: dict(field=F.series, lags=[1, 2]),
        field="complex_image",
        lags="real_array",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "g2_array": E(
        lambda: dict(intensity=np.abs(F.series) ** 2, lags=[1, 2]),
        lags="real_array",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "liv_array": E(
        lambda: dict(intensity=np.abs(F.series) ** 2),
        ddof="count0",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "speckle_variance_array": E(
        lambda: dict(intensity=np.abs(F.series) ** 2),
        ddof="count0",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "doppler_phase_array": E(
        lambda: dict(field=F.series),
        field="complex_image",
        lag="count",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "ssada_array": E(
        lambda: dict(amplitudes=np.abs(F.series)[None]),
        amplitudes="image",
        window="none",
        why="window: tests/analysis/test_dynamics*",
    ),
    "ocds_array": E(
        lambda: dict(
            intensity=np.abs(F.series) ** 2, lags=[1, 2], interval=1e-3, delays=(1e-3, 2e-3)
        ),
        lags="real_array",
        delays="none",
        window="none",
        why="delays, window: a pair, tests",
    ),
    "brownian_motion": E(
        lambda: dict(scene=F.scene, times=[0.0, 1e-3], diffusion=1.0, seed=1),
        times="real_array",
        diffusion="nonnegative",
        regions="none",
        fraction="probability",
        why="regions: labels, tests/scene",
    ),
    "moving_mask": E(
        lambda: dict(scene=F.scene),
        regions="none",
        fraction="probability",
        why="regions: labels, tests/scene",
    ),
    "velocity_range": E(
        lambda: dict(
            contrast="liv", n_frames=4, interval=1e-3, snr_db=20.0, waist=6.0, low=0.1, high=0.9
        ),
        contrast="choice",
        n_frames="size",
        low="real",
        high="real",
    ),
    "g1": E(
        lambda: dict(images=F.series_da, lags=[1, 2]),
        images="dataset",
        lags="real_array",
        blocks="count",
        block_dim="dims",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "g2": E(
        lambda: dict(images=F.series_da, lags=[1, 2]),
        images="dataset",
        lags="real_array",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "liv": E(
        lambda: dict(images=F.series_da),
        images="dataset",
        ddof="count0",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "speckle_variance": E(
        lambda: dict(images=F.series_da),
        images="dataset",
        ddof="count0",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "doppler_phase": E(
        lambda: dict(images=F.series_da),
        images="dataset",
        lag="count",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "ssada": E(
        lambda: dict(images=F.series_da, n_bands=2),
        images="dataset",
        n_bands="count",
        band_apodization="choice",
        overlap="probability",
        window="none",
        stride="count",
        why="window: tests/analysis/test_dynamics*",
    ),
    "ocds": E(
        lambda: dict(images=F.series_da, delays=(1e-3, 2e-3)),
        images="dataset",
        delays="none",
        window="none",
        stride="count",
        why="delays, window: pairs, tests",
    ),
    # --- synthoct (merged from scanner/metrics) ------------------------------------------
    "baseline_phantom": E(
        lambda: dict(kind="uniform", seed=1, config=F.sc_config),
        seed="none",
        config="none",
        why="seed: an int or 'A'/'B'; config: a ScannerConfig (tests/synthoct)",
    ),
    "synthoct_scan": E(
        lambda: dict(phantom=F.sc_phantom, config=F.sc_config),
        phantom="dataset",
        config="none",
        field="flag",
        shadowing="choice",
        noise="nonnegative",
        tol="positive",
        eps="positive",
        nthreads="count",
        why="config: a ScannerConfig",
    ),
    "read_scan": E(
        lambda: dict(path=REPO / "speckle/data/synthoct/Scan_Exp1_Uniform_A.png"),
        path="path",
        config="none",
        why="config: a ScannerConfig",
    ),
    "read_metrics_report": E(
        lambda: dict(path=REPO / "speckle/data/synthoct/Final_Metrics_Report.csv"), path="path"
    ),
    "synthoct_maps": E(
        lambda: dict(scan=F.sc_scan, window=4),
        scan="image",
        variant="choice",
        images="flag",
        pixel_size="positive_length",
        window="count",
        dynamic_range="positive",
    ),
    # --- the inverse problem (merged from phantom) ----------------------------------------
    "fit_phantom": E(
        lambda: dict(
            scan=REPO / "speckle/data/synthoct/Scan_Exp1_Uniform_A.png",
            config=speckle.ScannerConfig(),
        ),
        scan="path",
        config="none",
        max_layers="count",
        blocks="count",
        shapes="none",
        inclusions="flag",
        criterion="choice",
        why="config: a ScannerConfig or an INI path (tests/studies/test_phantom.py); shapes: a "
        "tuple of shape names (tests/studies/test_phantom_shapes.py)",
    ),
    "virtual_patient": E(
        lambda: dict(
            seed=1,
            config=speckle.ScannerConfig(n_pixels=64, n_lines=16, x_max=96.0, n_scatterers=200),
            layers=(1, 2),
        ),
        config="none",
        layers="none",
        shapes="none",
        energy_range="none",
        density_range="none",
        min_contrast="positive",
        min_thickness="positive_length",
        max_tilt="nonnegative",
        max_sag="nonnegative",
        visible="positive",
        draw_seed="seed",
        inclusions="flag",
        why="config: a name or ScannerConfig; layers, shapes and the ranges: pairs and tuples "
        "(tests/studies/test_phantom_patients.py)",
    ),
    "phantom_closed_loop_case": E(
        lambda: dict(
            seed=1,
            config=speckle.ScannerConfig(n_pixels=64, n_lines=64, x_max=384.0, n_scatterers=4000),
            layers=(1, 1),
        ),
        config="none",
        fit_seed="seed",
        max_layers="count",
        fit_inclusions="none",
        patient="none",
        why="config: a name or ScannerConfig; patient: virtual_patient's options (its entry); "
        "fit_inclusions: None or a bool (tests/studies/test_phantom_inclusions.py)",
    ),
    "phantom_failure_map": E(
        lambda: dict(
            config=speckle.ScannerConfig(n_pixels=64, n_lines=64, x_max=384.0, n_scatterers=4000),
            thickness=[8.0],
            contrast=[4.0],
        ),
        config="none",
        thickness="real_array",
        contrast="real_array",
        seeds="none",
        energy="positive",
        top_depth="positive_length",
        why="config: a name or ScannerConfig; seeds: a list of seeds (tests/studies/"
        "test_phantom_limits.py)",
    ),
    "synthoct_config": E(
        lambda: dict(name="2025"),
        name="choice",
        changes="none",
        why="changes: ScannerConfig's fields, checked by ScannerConfig (its own entry)",
    ),
    "PhantomFit": E(
        lambda: dict(layers=xr.Dataset(), config=speckle.ScannerConfig()),
        layers="none",
        config="none",
        inclusions="none",
        why="a record built by fit_phantom",
        record="fit_phantom",
    ),
    "EquivalentSystem": E(
        lambda: dict(
            config=speckle.ScannerConfig(),
            rows=(0, 256),
            gain=1.0,
            offset=0.0,
            noise_log=0.0,
            kind="intensity",
            waist=float("nan"),
            window_top_log=11.74,
            denoise=True,
        ),
        config="none",
        rows="none",
        gain="none",
        offset="none",
        noise_log="none",
        kind="none",
        waist="none",
        window_top_log="none",
        denoise="none",
        why="a record built by equivalent_system",
        record="equivalent_system",
    ),
    "phantom_score_power": E(
        lambda: dict(cases=8, sd=0.05), cases="count", sd="positive", beyond="positive"
    ),
    "phantom_closed_loop": E(
        lambda: dict(
            seeds=[1],
            config=speckle.ScannerConfig(n_pixels=64, n_lines=96, x_max=576.0),
            score=False,
            scheduler="synchronous",
        ),
        seeds="none",
        config="choice",
        layers="none",
        shapes="none",
        inclusions="flag",
        rescans="count",
        score="flag",
        lpips="flag",
        scheduler="choice",
        n_workers="count",
        why="seeds, layers, shapes: sequences (tests/studies/test_phantom_batch.py)",
    ),
    "ScannerConfig": E(
        lambda: dict(n_pixels=16, n_lines=8, x_max=96.0, n_scatterers=50),
        n_pixels="size",
        pixel_size="positive_length",
        wavelength="positive_length",
        n_lines="size",
        x_max="positive_length",
        n_bscans="count",
        y_max="nonnegative",
        beam_radius="positive_length",
        n_scatterers="size",
        scan_filename="none",
        scatterers_filename="none",
        why="file names: free text",
    ),
    "write_scanner_config": E(
        lambda: dict(config=F.sc_config, path=F.tmp / "w.ini"),
        config="none",
        path="none",
        why="config: a ScannerConfig",
    ),
    "read_scanner_config": E(lambda: dict(path=F.sc_files[0]), path="path"),
    "write_phantom": E(
        lambda: dict(phantom=F.sc_phantom, path=F.tmp / "w.txt", config=F.sc_config),
        phantom="dataset",
        path="none",
        config="none",
        energy_scale="positive",
        why="config: a ScannerConfig",
    ),
    "read_phantom": E(
        lambda: dict(path=F.sc_files[1], config=F.sc_config),
        path="path",
        config="none",
        why="config: a ScannerConfig",
    ),
    "write_scan": E(
        lambda: dict(scan=F.sc_scan, path=F.tmp / "w.png"),
        scan="image",
        path="none",
        why="path: any writable file",
    ),
    "ballistic_motion": E(
        lambda: dict(scene=F.scene, times=[0.0, 1e-3], speed=100.0, seed=1),
        times="real_array",
        speed="nonnegative",
        distribution="choice",
        wrap="none",
        regions="none",
        fraction="probability",
        why="regions: labels, tests/scene; wrap: None or bool",
    ),
    "bulk_motion": E(
        lambda: dict(scene=F.scene, times=[0.0, 1e-3], displacement=[[0.0], [1.0]]),
        times="real_array",
        displacement="real_array",
        wrap="none",
        regions="none",
        fraction="probability",
        why="regions: labels, tests/scene; wrap: None or bool",
    ),
    "flow_motion": E(
        lambda: dict(scene=F.scene, times=[0.0, 1e-3], velocity=[100.0]),
        times="real_array",
        velocity="real_array",
        wrap="none",
        regions="none",
        fraction="probability",
        why="regions: labels, tests/scene; wrap: None or bool",
    ),
    # --- io ----------------------------------------------------------------------------------
    "to_netcdf": E(
        lambda: dict(ds=F.img, path=F.tmp / "out.nc"),
        ds="dataset",
        path="none",
        why="path: tests/test_strict.py (directories, atomicity)",
    ),
    "stream_to_netcdf": E(
        lambda: dict(ds=F.img, path=F.tmp / "stream.nc", progress=False),
        ds="dataset",
        path="none",
        complevel="count0",
        why="path: tests/io",
    ),
    "open_dataset": E(lambda: dict(path=F.nc), path="path", load="flag"),
    # --- the formerly PENDING names (issue 36's merge) ------------------------------------------
    "bscan_series": E(
        lambda: dict(scene=F.moved, source=F.src, waist=6.0, lines=[8.0, 16.0]),
        y="real",
        line_rate="positive",
    ),
    "mmode": E(
        lambda: dict(scene=F.moved, source=F.src, waist=6.0, x=16.0),
        x="real",
        y="real",
        time_chunk="count",
    ),
    "scan_kernel": E(
        lambda: dict(source=F.src, waist=6.0, lines=[8.0, 16.0]),
        y="real",
        z_bounds="none",
        why="z_bounds: a (low, high) pair checked with the kernel's scene (tests/imaging)",
    ),
    "contrast_estimates": E(
        lambda: dict(contrast="liv", field=F.series, window=(2, 2)),
        contrast="choice",
        field="complex_image",
        intensity="positive",
    ),
    "decorrelation_calibration": E(
        lambda: dict(
            geometry=F.flow_geometry,
            velocities=[0.0, 1000.0],
            interval=1e-3,
            snr_db=20.0,
            n_frames=2,
            repeats=2,
            seed=0,
        ),
        geometry="mapping",
        velocities="real_array",
        repeats="count",
    ),
    "flow_failure": E(
        lambda: dict(
            geometry=F.flow_geometry,
            velocities=[0.0],
            snr_db=[20.0],
            intervals=[1e-3],
            n_frames=2,
            window=(2, 2),
            repeats=2,
            seed=0,
        ),
        geometry="mapping",
        velocities="real_array",
        snr_db="real_array",
        intervals="real_array",
        repeats="count",
        z="positive",
    ),
    "g1_curves": E(
        lambda: dict(
            geometry=F.flow_geometry,
            diffusion=0.5,
            velocity=1000.0,
            interval=1e-3,
            n_frames=2,
            blocks=2,
            snr_db=30.0,
            seed=0,
        ),
        geometry="mapping",
        diffusion="nonnegative",
        velocity="nonnegative",
        blocks="count",
    ),
    "phantom_series": E(
        lambda: dict(geometry=F.flow_geometry, phantom=F.flow_phantom, snr_db=30.0, seed=1),
        geometry="mapping",
        phantom="mapping",
    ),
    "poiseuille_velocity": E(
        lambda: dict(
            scene=F.shared,
            peak_velocity=100.0,
            radius=10.0,
            centre=[20.0, 0.0],
            direction=[0.0, 1.0],
        ),
        peak_velocity="real",
        radius="positive_length",
        centre="real_array",
        direction="real_array",
    ),
    "synthoct_metrics": E(
        lambda: dict(reference=F.metric_image, target=F.metric_image, lpips=False),
        reference="image",
        target="image2",
        variant="choice",
        lpips="flag",
    ),
}

#: Public names merged in without an entry yet (issue 36's merge of the rooms, scanner,
#: metrics, dynamics and dynstudy branches): listed here by module so that the lead sees them;
#: the list only shrinks (an entry for a listed name fails until its line is removed).
PENDING: dict[str, str] = {}

#: (function, parameter, bad value) -> why the call's answer is the right one.
ANSWERS: dict[tuple[str, str, str], str] = {
    ("virtual_patient", "inclusions", "int"): "an int is the number of inclusions (1: the "
    "patient of inclusions=True; tests/studies/test_phantom_patients.py)",
    ("phantom_closed_loop", "inclusions", "int"): "an int is each patient's number of "
    "inclusions (speckle.virtual_patient)",
    ("velocity_range", "snr_db", "inf"): "no noise: the noise floor is the static one",
    ("compounded_contrast", "mu", "one_pixel"): "one look: the contrast of one look (1)",
    ("apodization_correlation", "apodizations", "one_pixel"): "one look of one sample: [[1]]",
    ("split_spectrum_contrast", "weights", "one_pixel"): "one look of one spectral sample: "
    "sqrt(1 + kurtosis/density), the random walk of a Poisson number of phasors",
    ("split_spectrum_contrast", "density", "inf"): "the dense limit (docstring): "
    "compounded_contrast of the windows' correlations",
    ("subband_fwhm", "n_pixels", "huge"): "a scalar root (brentq): nothing is allocated",
    ("bandlimited", "field", "one_pixel"): "one sample: the constant polynomial, exact",
    ("contrast_theory", "n_pixels", "huge"): "a rectangular spectrum's moments are closed "
    "forms (speckle.analysis.statistics.spectrum_moments): nothing is allocated",
    **{
        (n, "intensity", "complex"): "a complex field is taken as its intensity |A|^2 "
        "(speckle.analysis._pooling.checked_series)"
        for n in ("g2_array", "liv_array", "ocds_array", "speckle_variance_array")
    },
    ("ssada_array", "amplitudes", "complex"): "complex sub-band fields: |A| is used",
    ("interpolate_windows", "values", "nan"): "a NaN window (no answer) spreads only to the "
    "pixels whose interpolation uses it (docstring)",
    ("interpolate_windows", "depth", "empty"): "no pixel asked: an empty grid",
    ("interpolate_windows", "x", "empty"): "no pixel asked: an empty grid",
    ("interpolate_displacement", "depth", "empty"): "no pixel asked: an empty grid",
    ("interpolate_displacement", "x", "empty"): "no pixel asked: an empty grid",
    ("correlation_array", "x", "nan"): "NaN pixels blank only the windows holding them "
    "(docstring; tests/test_strict.py)",
    ("correlation_array", "y", "nan"): "as x",
    # --- contracta (issue 36): documented answers of imaging, system, scene, studies ------------
    **{
        (n, "snr_db", "inf"): "snr_db=inf is documented as no noise (the noiseless answer)"
        for n in (
            "add_complex_noise",
            "contrast_floors",
            "expected_contrast",
            "decorrelation_calibration",
            "g1_curves",
            "phantom_series",
        )
    },
    **{
        (n, "density", "zero"): "density 0 is an empty medium (random_scatterers takes "
        "density >= 0): no scatterers, a zero field; normalise='density' refuses it"
        for n in ("random_scatterers", "deformable_scene", "stream_ascans", "expected_intensity")
    },
    ("expected_intensity", "mean_square_amplitude", "zero"): "zero amplitudes: expected "
    "intensity 0 (the closed form)",
    ("expected_intensity", "n_pixels", "huge"): "a closed form (no array): rho N <|a|^2> "
    "sum(S^2)/(sum S)^2 for the flat spectrum",
    ("delta_k", "n_pixels", "huge"): "a closed form (no array): N pi / H",
    **{
        (n, "ds", "empty"): "zero-length dims are valid netCDF: the empty dataset is written and "
        "read back as is (tests/test_io.py)"
        for n in ("to_netcdf", "stream_to_netcdf")
    },
    ("write_scan", "scan", "one_pixel"): "a 1 x 1 grey image is a valid PNG (read_scan reads "
    "it back)",
    ("interpolation_gain", "t", "empty"): "pointwise closed form: no point asked, an empty answer",
    ("interpolation_gain", "theta", "empty"): "as t",
    ("resampling_response", "z", "empty"): "pointwise closed form: no depth asked, an empty answer",
    (
        "process_interferogram",
        "signal",
        "complex",
    ): "documented: a complex camera signal (interferogram's complex detection) is processed as is",
    **{
        (
            n,
            "apodization_fwhm_fraction",
            "above_one",
        ): "a Gaussian apodization wider than the band (FWHM 1.5 N) is a valid, nearly flat window"
        for n in ("process_interferogram", "system_ascan")
    },
    ("add_complex_noise", "field", "one_pixel"): "one pixel: its intensity is the mean, the "
    "noise is drawn per pixel",
    ("layered_labels", "interfaces", "empty"): "no interface: one layer, label 0 everywhere",
    ("inclusion_labels", "label", "negative"): "-1 is the package's 'no region' label (an air "
    "hole; region_values' outside= gives its value)",
    ("optical_depth", "z", "empty"): "pointwise: no depth asked, an empty answer",
    **{
        (n, p, lab): "pointwise: every pixel is mapped alone (an empty image maps to an empty "
        "one); add_floor's mean is the given mean_intensity"
        for n, p in (
            ("log_compress", "intensity"),
            ("log_expand", "data"),
            ("add_floor", "intensity"),
        )
        for lab in ("empty", "one_pixel")
    },
    ("spectrum", "k0_dk", "zero"): "documented: k0 = 0 is the formal Fourier transform of the "
    "paper's Fig. 1",
    ("temporal_looks", "diffusion", "zero"): "no motion: identical frames, fully correlated "
    "looks (the compounding gain 1)",
    **{
        (n, "float64_error", "inf"): "documented: inf means depths beyond float64, no fast "
        "method admissible (the direct sum is chosen)"
        for n in ("choose_method", "method_estimates")
    },
    ("track_array", "reference", "nan"): "NaN pixels give the windows holding them NaN (docstring)",
    ("track_array", "deformed", "nan"): "as reference",
    ("track_axial", "reference", "nan"): "as track_array",
    ("track_axial", "deformed", "nan"): "as track_array",
    ("sample_field", "field", "one_pixel"): "N = 1: the band-limited interpolant is the constant "
    "A_0, exact",
    ("oversample_depth", "field", "one_pixel"): "as sample_field: the constant A_0",
    **{
        (n, "step", "huge"): "a step beyond the image: one window along that axis (the first), "
        "as a narrow image with the default step has"
        for n in ("track", "track_array", "track_axial")
    },
    ("amplitude_from_gamma", "gamma", "complex"): "a complex coherence: its modulus |gamma| is "
    "used (docstring)",
}


# --- the walk ------------------------------------------------------------------------------
def _public() -> list[str]:
    return [
        n
        for n in speckle.__all__
        if n != "__version__"
        and (inspect.isclass(getattr(speckle, n)) or callable(getattr(speckle, n)))
    ]


def _params(name: str) -> list[inspect.Parameter]:
    return list(inspect.signature(getattr(speckle, name)).parameters.values())


def _kind(entry: Entry, p: inspect.Parameter) -> str | None:
    if p.name in entry.kinds:
        return entry.kinds[p.name]
    return BY_NAME.get(p.name)


def _invoke(name: str, kw: dict):
    func = getattr(speckle, name)
    args, kwargs = [], {}
    for p in _params(name):
        if p.name not in kw:
            continue
        if p.kind is p.VAR_POSITIONAL:
            args.extend(kw[p.name])
        elif p.kind is p.POSITIONAL_ONLY:
            args.append(kw[p.name])
        elif p.kind is p.VAR_KEYWORD:
            kwargs.update(kw[p.name])
        else:
            kwargs[p.name] = kw[p.name]
    return func(*args, **kwargs)


def _names_param(msg: str, param: str, others: list[str], label: str) -> bool:
    def named(p):
        return re.search(rf"(?<![A-Za-z0-9_]){re.escape(p)}(?![A-Za-z0-9])", msg) is not None

    return named(param) or (label.startswith("mismatch") and any(named(o) for o in others))


def _raised_in_package(err: BaseException) -> bool:
    tb = err.__traceback__
    last = None
    while tb is not None:
        last = tb.tb_frame.f_code.co_filename
        tb = tb.tb_next
    return last is not None and str(Path(last).resolve()).startswith(PACKAGE)


def _cases(name: str):
    entry = ENTRIES[name]
    if entry.record:
        return  # a record: its builder is the front door (entry.record names it)
    valid = entry.valid()
    for p in _params(name):
        kind = _kind(entry, p)
        if kind is None:
            continue
        default = valid.get(p.name, p.default if p.default is not p.empty else None)
        for label, bad in KINDS[kind](default):
            yield p.name, label, bad


def _check_case(name: str, param: str, label: str, bad) -> str | None:
    """None if the case holds, else what is wrong."""
    kw = {**ENTRIES[name].valid(), param: bad}
    others = [p.name for p in _params(name) if p.name != param]
    huge = label == "huge"
    if huge:
        tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = _invoke(name, kw)
            if hasattr(out, "compute"):
                out = out.compute()  # a lazy answer must have been refused at the call
    except (TypeError, ValueError) as err:
        if (name, param, label) in ANSWERS:
            return f"listed in ANSWERS but raised {type(err).__name__}: {err}"[:300]
        msg = str(err)
        if not _names_param(msg, param, others, label):
            return f"{type(err).__name__} does not name {param!r}: {msg}"[:300]
        if not _raised_in_package(err):
            return f"raised outside the package (numpy/scipy/xarray internals): {msg}"[:300]
        if huge:
            peak = tracemalloc.get_traced_memory()[1]
            if peak > HUGE_PEAK:
                return f"refused after allocating {peak / 2**20:.0f} MiB"
        return None
    except FileNotFoundError as err:
        if label == "missing" and str(bad) in str(err):
            return None  # a missing file: FileNotFoundError naming it is the right refusal
        if label == "string" and getattr(err, "filename", None) == bad:
            return None  # a parameter that also takes a path: the string named a missing file
        return f"raised FileNotFoundError: {err}"[:300]
    except Exception as err:
        return f"raised {type(err).__name__} (not ValueError/TypeError): {err}"[:300]
    finally:
        if huge:
            tracemalloc.stop()
    if (name, param, label) in ANSWERS:
        return None
    return (
        f"returned {type(out).__name__} instead of refusing; refuse it naming {param!r}, or add "
        f"ANSWERS[({name!r}, {param!r}, {label!r})] = '<why the answer is right>'"
    )


# --- part 1: the public API ----------------------------------------------------------------
def test_every_public_name_has_an_entry():
    missing = [n for n in _public() if n not in ENTRIES and n not in PENDING]
    hints = "\n".join(
        f"    {n!r}: E(lambda: dict(<a tiny valid call of {', '.join(p.name for p in _params(n))}>)"
        ", <param>='<kind>', ...),"
        for n in missing
    )
    assert not missing, (
        f"add to ENTRIES in tests/test_contract.py:\n{hints}\nkinds: {sorted(KINDS)}"
    )
    stale = sorted(set(ENTRIES) - set(_public()))
    assert not stale, f"ENTRIES of names no longer public: {stale}"
    done = sorted(set(PENDING) & (set(ENTRIES) | (set(PENDING) - set(_public()))))
    assert not done, f"remove from PENDING (now with an entry, or gone): {done}"


@pytest.mark.parametrize("name", sorted(ENTRIES))
def test_entry_gives_every_parameter_a_kind(name):
    if name not in _public():
        pytest.skip(f"{name} not public in this tree")
    entry = ENTRIES[name]
    missing = [p.name for p in _params(name) if _kind(entry, p) is None]
    assert not missing, (
        f"ENTRIES[{name!r}] needs a kind for {missing} (one of {sorted(KINDS)}; 'none' with "
        "the reason in why=...)"
    )
    unknown = {k: v for k, v in entry.kinds.items() if v not in KINDS}
    assert not unknown, f"ENTRIES[{name!r}]: unknown kinds {unknown}"
    nones = [p.name for p in _params(name) if _kind(entry, p) == "none" and p.name in entry.kinds]
    assert not nones or entry.why, f"ENTRIES[{name!r}]: say why {nones} have no bad values"


def _gaps() -> set[str]:
    if not GAPS.exists():
        return set()
    return {
        ln.split("  #")[0].strip()
        for ln in GAPS.read_text().splitlines()
        if ln.strip() and not ln.startswith("#")
    }


@pytest.mark.parametrize("name", sorted(ENTRIES))
def test_bad_values_are_refused_naming_the_parameter(name):
    if name not in _public():
        pytest.skip(f"{name} not public in this tree")
    _invoke(name, ENTRIES[name].valid())  # the valid call works
    gaps = {g for g in _gaps() if g.startswith(f"{name}(")}
    failures, found = [], {}
    for param, label, bad in _cases(name):
        case = f"{name}({param}=<{label}>)"
        problem = _check_case(name, param, label, bad)
        if problem:
            found[case] = problem
            if case not in gaps:
                failures.append(f"{case}: {problem}")
    if os.environ.get("SPECKLE_CONTRACT_RECORD"):
        _record(name, found)
        return
    fixed = sorted(gaps - set(found))
    assert not failures, "\n".join(failures)
    assert not fixed, f"fixed (remove from {GAPS.name}): {fixed}"


def _record(name: str, found: dict) -> None:
    """Rewrite this function's lines of the gap list (``SPECKLE_CONTRACT_RECORD=1``)."""
    keep = [
        ln
        for ln in (GAPS.read_text().splitlines() if GAPS.exists() else [])
        if not ln.startswith(f"{name}(")
    ]
    new = [f"{case}  # {problem.splitlines()[0][:120]}" for case, problem in found.items()]
    header = [ln for ln in keep if ln.startswith("#")]
    body = sorted([ln for ln in keep if ln and not ln.startswith("#")] + new)
    GAPS.write_text("\n".join(header + body) + "\n")


def test_answers_are_cases_of_the_table():
    cases = {(n, p, lab) for n in ENTRIES if n in _public() for p, lab, _ in _cases(n)}
    stale = sorted(set(ANSWERS) - cases)
    assert not stale, f"ANSWERS entries that are no case of the table: {stale}"


# --- part 2: the pipeline's config sections --------------------------------------------------
def _config():
    import yaml

    from tests.conftest import ConfigRuns

    base = yaml.safe_load((REPO / "workflow/config/config.yaml").read_text())
    ci = yaml.safe_load((REPO / "workflow/config/ci.yaml").read_text())
    schema = yaml.safe_load((REPO / "workflow/schemas/config.schema.yaml").read_text())
    return ConfigRuns.merge(base, ci), schema


def _leaves(schema: dict, value: object, path: tuple):
    """(path, declared types, value) of every scalar leaf the schema declares."""
    props = schema.get("properties") if isinstance(schema, dict) else None
    if isinstance(value, dict) and props:
        for key, sub in value.items():
            if key in props:
                yield from _leaves(props[key], sub, (*path, key))
    elif isinstance(value, list) and isinstance(schema.get("items"), dict) and value:
        yield from _leaves(schema["items"], value[0], (*path, 0))
    else:
        kinds = schema.get("type", []) if isinstance(schema, dict) else []
        yield path, [kinds] if isinstance(kinds, str) else list(kinds), value


def _key(path: tuple) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def _set(config: dict, path: tuple, value: object) -> dict:
    out = copy.deepcopy(config)
    node = out
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    return out


def _config_cases():
    """Per leaf the bad value JSON Schema lets through: a float for an integer (``16.0``), NaN
    for a number; per section an unknown key."""
    config, schema = _config()
    cases = []
    for path, kinds, value in _leaves(schema, config, ()):
        if "integer" in kinds and isinstance(value, int) and not isinstance(value, bool):
            cases.append((_key(path), path, float(value)))
        elif "number" in kinds and isinstance(value, int | float) and not isinstance(value, bool):
            cases.append((_key(path), path, NAN))
    for section, value in config.items():
        if isinstance(value, dict):
            cases.append((f"{section}.no_such_key", (section, "no_such_key"), 1))
    return cases


def _refusal(config: dict, schema: dict) -> str | None:
    """The load's refusal message (schema validation, then :func:`check_config`), or None."""
    import jsonschema

    from speckle.pipeline.checks import check_config

    try:
        jsonschema.validators.validator_for(schema)(schema).validate(config)
    except jsonschema.ValidationError as err:
        return f"{_key(tuple(err.absolute_path))}: {err.message}"
    try:
        check_config(config, schema)
    except ValueError as err:
        return str(err)
    return None


def test_every_config_leaf_is_checked_at_load_naming_the_key():
    config, schema = _config()
    assert _refusal(config, schema) is None
    gaps = {g for g in _gaps() if g.startswith("config ")}
    failures, found = [], {}
    for key, path, bad in _config_cases():
        case = f"config {key}=<{bad!r}>"
        msg = _refusal(_set(config, path, bad), schema)
        parent = _key(path[:-1]) if path[-1] == "no_such_key" else key
        if msg is None:
            problem = "accepted at load"
        elif parent not in msg and not (path[-1] == "no_such_key" and "no_such_key" in msg):
            problem = f"refused without naming {key}: {msg[:160]}"
        else:
            continue
        found[case] = problem
        if case not in gaps:
            failures.append(f"{case}: {problem}")
    if os.environ.get("SPECKLE_CONTRACT_RECORD"):
        _record("config ", found)
        return
    fixed = sorted(gaps - set(found))
    assert not failures, "\n".join(failures)
    assert not fixed, f"fixed (remove from {GAPS.name}): {fixed}"
