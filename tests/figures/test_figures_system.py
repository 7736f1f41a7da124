"""The system pipeline helpers: source by datasheet, config schema, the results/system data."""

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate

import speckle
from speckle.figures import system as fs
from speckle.pipeline import adapters

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = str(ROOT / "workflow/schemas/config.schema.yaml")
SHEET = {
    "wavelength_nm": 840.0,
    "bandwidth_nm": 50.0,
    "camera_pixels": 256,
    "camera_range_nm": [790.0, 890.0],
    "imaging_depth": None,
    "refractive_index": 1.38,
    "spectral_resolution_nm": 0.2,
    "fill_factor": 1.0,
}


def config():
    return yaml.safe_load((ROOT / "workflow/config/config.yaml").read_text())


def test_source_by_datasheet_resolves_to_model_parameters():
    old = config()["source"]
    assert adapters.resolve_source(old) == old
    src = adapters.resolve_source({"datasheet": SHEET})
    system = adapters.system_from_config(SHEET)
    assert src["n_pixels"] == 256 and src["shape"] == "gaussian"
    assert src["pixel_size"] == pytest.approx(system.pixel_size, rel=1e-15)
    spec = adapters.source_spectrum(src)
    assert spec.attrs["depth_range"] == pytest.approx(system.depth_range, rel=1e-14)
    assert spec.attrs["k0"] == pytest.approx(system.k0, rel=1e-13)
    assert spec.attrs["fwhm"] == pytest.approx(system.fwhm_k, rel=1e-13)


def test_schema_accepts_either_source_form():
    cfg = config()
    validate(copy.deepcopy(cfg), SCHEMA)
    cfg["source"] = {"datasheet": {k: v for k, v in SHEET.items() if v is not None}}
    validate(copy.deepcopy(cfg), SCHEMA)
    layered = config()  # a --configfile naming a datasheet over the default model keys
    layered["source"]["datasheet"] = {k: v for k, v in SHEET.items() if v is not None}
    validate(copy.deepcopy(layered), SCHEMA)
    assert adapters.resolve_source(layered["source"])["n_pixels"] == 256  # the datasheet wins
    missing = config()
    del missing["source"]["pixel_size"]
    with pytest.raises(WorkflowError):
        validate(missing, SCHEMA)
    bad_sheet = config()
    bad_sheet["source"]["datasheet"] = {"wavelength_nm": 840.0}
    with pytest.raises(WorkflowError):
        validate(bad_sheet, SCHEMA)
    bad = config()
    bad["system"]["bscan"]["apodization"] = "hamming"
    with pytest.raises(WorkflowError):
        validate(bad, SCHEMA)


def test_ci_config_validates():
    cfg = config()
    ci = yaml.safe_load((ROOT / "workflow/config/ci.yaml").read_text())
    for key in ("datasheet", "rolloff", "bscan"):
        cfg["system"][key].update(ci["system"][key])
    validate(cfg, SCHEMA)


def test_rolloff_dataset():
    system = adapters.system_from_config(SHEET)
    ds = fs.rolloff_dataset(system, 10, "cubic")
    assert set(ds.data_vars) == {"measured_db", "measured_exact_db", "analytic_db", "camera_db"}
    assert ds.depth.attrs["units"] == "um" and ds.analytic_db.attrs["units"] == "dB"
    assert float(ds.depth.max()) < system.imaging_depth
    np.testing.assert_allclose(ds.camera_db, system.rolloff_db(ds.depth.values))
    assert np.all(ds.analytic_db <= ds.camera_db + 1e-9)  # the spline only attenuates here
    # resampling only adds error: the cubic curve is never above the exact one (beyond rounding)
    assert np.all(ds.measured_db <= ds.measured_exact_db + 1e-6)


def test_psf_dataset_widths_order():
    system = adapters.system_from_config(SHEET)
    ds = fs.psf_dataset(system, [0.2, 0.6], {2: 20.0})
    w = ds.width
    assert np.all(w.sel(variant="compensated") < w.sel(variant="linearised"))
    assert np.all(w.sel(variant="linearised") < w.sel(variant="raw"))
    raw = w.sel(variant="raw").values
    assert raw[1] > raw[0]  # no k-linearisation: broadening grows with depth
    with pytest.raises(ValueError, match="fractions of the imaging depth"):
        fs.psf_dataset(system, [1.2], {})


def test_artefact_bscan_mirror_and_seed():
    system = adapters.system_from_config(SHEET)
    kw = dict(
        surface=-50.0, tilt=5.0, interfaces=[{"depth": 0.0, "amplitude": 1.0},
                                             {"depth": 100.0, "amplitude": 0.5}],
        density=0.2, scatterer_amplitude=0.05, dispersion={2: 20.0}, reference_power=4.0,
        apodization="hann", seed=3,
    )  # fmt: skip
    ds = fs.artefact_bscan(system, n_alines=3, **kw)
    assert ds.raw_db.dims == ("depth", "aline") and ds.sizes["depth"] == 256
    raw = ds.raw_db.values
    # a real camera signal has a Hermitian transform: |A(-z)| = |A(z)| (pixel 0 is depth 0)
    zero = int(np.argmin(np.abs(ds.depth.values)))
    np.testing.assert_allclose(raw[zero + 1 :], raw[zero - 1 : 0 : -1][: raw.shape[0] - zero - 1])
    # (the DC removal by reference subtraction is tested exactly in test_spectrometer.py)
    again = fs.artefact_bscan(system, n_alines=2, **kw)
    np.testing.assert_array_equal(again.processed_db.values, ds.processed_db.values[:, :2])


def test_dispersion_from_config():
    assert fs.dispersion_from_config({"second": 20.0, "third": 0.0}) == {2: 20.0}
    assert fs.dispersion_from_config(None) == {}
    assert isinstance(speckle.example_system("840nm"), speckle.System)
