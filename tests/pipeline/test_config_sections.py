"""Issue 21: the beam, datasheet, system, realism and speed_accuracy.beam sections are checked
when the workflow loads.

Each bad config is a small override layered over the CI config with ``--configfile``;
``snakemake -n`` must stop with the key path in its output and no job planned. The same
overrides go through :func:`speckle.pipeline.checks.check_config` directly (fast), and the
schema's enums are compared with the package's method tables.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import speckle.imaging.beam
import speckle.system.spectrometer

# private: the NUFFT tolerance floor the config check enforces
from speckle.imaging._methods.nufft import NUFFT_TOL_FLOOR
from speckle.pipeline.checks import check_config, tol_floor

SCHEMA = "workflow/schemas/config.schema.yaml"
#: a small measured image the ROI cases refer to (written into the repository copy)
MEASURED = "measured_64x48.npy"
MEASURED_SHAPE = (64, 48)
_SHEET = {"wavelength_nm": 840.0, "camera_pixels": 256, "imaging_depth": 500.0}
_MEAS = {"path": MEASURED, "kind": "intensity", "roi": {"depth": [10, 40], "x": [0, 48]}}

#: id -> (key expected in the error, override merged over the CI config)
BAD = {
    "beam.method enum": ("beam.method", {"beam": {"method": "bogus"}}),
    "beam.volume.method enum": ("beam.volume.method", {"beam": {"volume": {"method": "bogus"}}}),
    "beam.tol floor": ("beam.tol", {"beam": {"tol": 1e-20}}),
    "beam.tol floor nufft32": ("beam.tol", {"beam": {"method": "nufft32", "tol": 1e-9}}),
    "beam.volume.tol floor": (
        "beam.volume.tol",
        {"beam": {"volume": {"method": "nufft", "tol": 1e-20}}},
    ),
    "beam.volume finufft": ("beam.volume.method", {"beam": {"volume": {"method": "finufft"}}}),
    "beam.volume tiles": ("beam.volume.tile", {"beam": {"volume": {"tile": 0.05}}}),
    "beam.lags empties": ("beam.lags", {"beam": {"lags": 24}}),
    "beam memory": ("beam.n_lines", {"beam": {"n_lines": 20_000_000}}),
    "beam.volume memory": (
        "beam.volume.chunk",
        {"beam": {"volume": {"n_lines": 4096, "chunk": 4096}}},
    ),
    "source.datasheet bandwidth": (
        "source.datasheet.bandwidth_nm",
        {"source": {"datasheet": {**_SHEET, "bandwidth_nm": 900.0}}},
    ),
    "system.datasheet both ranges": (
        "system.datasheet.camera_range_nm",
        {"system": {"datasheet": {"imaging_depth": 1000.0}}},
    ),
    "system.datasheet narrow camera": (
        "system.datasheet.camera_range_nm",
        {"system": {"datasheet": {"camera_range_nm": [830.0, 850.0]}}},
    ),
    "system.datasheet fill": (
        "system.datasheet.fill_factor",
        {"system": {"datasheet": {"fill_factor": 0}}},
    ),
    "system.rolloff.resample enum": (
        "system.rolloff.resample",
        {"system": {"rolloff": {"resample": "quintic"}}},
    ),
    "system.bscan memory": (
        "system.bscan.n_alines",
        {"system": {"bscan": {"n_alines": 10_000_000}}},
    ),
    "realism.showcase.focus": (
        "realism.showcase.focus",
        {"realism": {"showcase": {"focus": 5000.0}}},
    ),
    "realism.showcase order": (
        "realism.showcase.surface",
        {"realism": {"showcase": {"surface": 500.0, "interface": 400.0}}},
    ),
    "realism.showcase finufft": (
        "realism.showcase.method",
        {"realism": {"showcase": {"method": "finufft"}}},
    ),
    "realism.showcase.tol floor": (
        "realism.showcase.tol",
        {"realism": {"showcase": {"method": "nufft", "tol": 1e-15}}},
    ),
    "realism.showcase memory": (
        "realism.showcase.n_lines",
        {"realism": {"showcase": {"n_lines": 50_000_000}}},
    ),
    "realism.measured.roi reversed": (
        "realism.measured.roi",
        {"realism": {"measured": {**_MEAS, "roi": {"depth": [40, 10]}}}},
    ),
    "realism.measured.roi outside": (
        "realism.measured.roi",
        {"realism": {"measured": {**_MEAS, "roi": {"x": [0, 500]}}}},
    ),
    "realism.measured.air_rows outside": (
        "realism.measured.air_rows",
        {"realism": {"measured": {**_MEAS, "air_rows": [60, 90]}}},
    ),
    "speed_accuracy.beam.sizes memory": (
        "speed_accuracy.beam.sizes[0]",
        {
            "speed_accuracy": {
                "beam": {
                    "sizes": [{"n_pixels": 65536, "n_lines": 65536, "density": 4, "waist_pitch": 2}]
                }
            }
        },
    ),
    "speed_accuracy.beam.methods enum": (
        "speed_accuracy.beam.methods",
        {"speed_accuracy": {"beam": {"methods": ["psf"]}}},
    ),
}


@pytest.fixture(scope="module")
def repo(tmp_path_factory, config_runs) -> Path:
    """A copy of the repository with the small measured image (dry runs write .snakemake)."""
    dest = config_runs.copy_repo(tmp_path_factory.mktemp("cfg21") / "repo")
    np.save(dest / MEASURED, np.ones(MEASURED_SHAPE))
    return dest


@pytest.fixture(scope="module")
def schema(repo_root) -> dict:
    return yaml.safe_load((repo_root / SCHEMA).read_text())


@pytest.fixture(scope="module")
def merged(repo_root, config_runs) -> dict:
    base = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    return config_runs.merge(
        base, yaml.safe_load((repo_root / "workflow/config/ci.yaml").read_text())
    )


@pytest.mark.slow
@pytest.mark.parametrize("case", list(BAD))
def test_bad_section_stops_before_any_job(repo, case, config_runs):
    key, override = BAD[case]
    name = f"bad21_{abs(hash(case))}.yaml"
    (repo / name).write_text(yaml.safe_dump(override))
    config_runs.assert_refused(config_runs.dry_run(repo, name), key)
    assert not (repo / "results").exists() and not (repo / "results_ci").exists()


@pytest.mark.parametrize("case", [c for c in BAD if "enum" not in c])
def test_check_config_names_the_key(merged, schema, repo, case, monkeypatch, config_runs):
    """The same cases without Snakemake (the enums are the schema's, tested below)."""
    key, override = BAD[case]
    monkeypatch.chdir(repo)  # the measured image's relative path
    with pytest.raises(ValueError, match=key.replace("[", r"\[").replace("]", r"\]")):
        check_config(config_runs.merge(merged, override), schema)


def test_good_sections_pass(merged, schema, repo, monkeypatch, config_runs):
    monkeypatch.chdir(repo)
    check_config(merged, schema)
    ok = {"realism": {"measured": {**_MEAS, "air_rows": [0, 8]}}}
    check_config(config_runs.merge(merged, ok), schema)
    sheet = {"source": {"datasheet": {**_SHEET, "bandwidth_nm": 50.0}}}
    check_config(config_runs.merge(merged, sheet), schema)
    check_config(
        config_runs.merge(merged, {"beam": {"lags": 23}}), schema
    )  # one pair of lines left


def _beam_methods() -> set[str]:
    """The package's beam-method table (re-point here if it moves)."""
    return set(speckle.imaging.beam.BEAM_METHODS)


def test_schema_enums_match_the_package(schema):
    props = schema["properties"]
    beam = set(_beam_methods())
    assert set(props["beam"]["properties"]["method"]["enum"]) == beam
    assert set(props["beam"]["properties"]["volume"]["properties"]["method"]["enum"]) == beam
    sa = props["speed_accuracy"]["properties"]["beam"]["properties"]["methods"]["items"]
    assert set(sa["enum"]) == beam
    show = props["realism"]["properties"]["showcase"]["properties"]["method"]
    assert set(show["enum"]) == beam
    sysp = props["system"]["properties"]
    # every k-linearisation but "none" (no closed-form roll-off for unresampled pixels)
    resample = set(sysp["rolloff"]["properties"]["resample"]["enum"])
    assert resample == set(speckle.system.spectrometer.RESAMPLING) - {"none"}
    assert set(sysp["bscan"]["properties"]["apodization"]["enum"]) == set(
        speckle.system.spectrometer.APODIZATIONS
    )


def test_tol_floors_are_the_methods_own():
    assert tol_floor("direct") == tol_floor("auto") == 0.0
    assert tol_floor("nufft") == tol_floor("finufft") == NUFFT_TOL_FLOOR
    # nufft32's bound: what the method itself refuses on the smallest image
    floor = tol_floor("nufft32", 32)
    z, x, a = np.array([10.0]), np.array([0.0]), np.array([1.0 + 0j])
    common = dict(lines=np.arange(8) * 4.0, waist=8.0, n_pixels=32, depth_range=256.0, k0=1.0)
    with pytest.raises(ValueError, match="nufft32"):
        speckle.imaging.beam.beam_scan(z, x, a, method="nufft32", tol=0.5 * floor, **common)
