"""The realism study: model-only path, self-consistency on a model-made 'measured' image."""

from __future__ import annotations

import shutil
import subprocess
import sys

import numpy as np
import pytest
import yaml

from speckle.analysis import autocorrelation as ac
from speckle.analysis import measured as ms
from speckle.figures import realism as fig
from speckle.io import open_dataset
from speckle.studies.realism import (
    EFFECTS,
    fit_parameters,
    image_statistics,
    realism_study,
    simulate,
)

KW = {
    "pixel_size": 5.75,
    "n_pixels": 32,
    "density": 8.0,
    "k0_dk": 10.0,
    "max_lag": 6,
    "n_blocks": 8,
    "phase": {"index_variance": 1e-6, "correlation_length": 20.0},
}
TRUE = {
    "fwhm_fraction": 0.3,
    "waist": 3.0,
    "snr_db": 15.0,
    "floor": 0.02,
    "attenuation": 0.0,
    "gain": 20.0,
    "offset": 120.0,
}


def test_model_only_without_measured_image():
    ds = realism_study(None, None, n_alines=64, fallback=TRUE, seed=1, **KW)
    assert ds.model_autocorrelation.dims == ("axis", "lag")
    assert list(ds.axis.values) == ["depth", "lateral"] and ds.lag.size == 7
    assert "measured_autocorrelation" not in ds and "needed" not in ds
    assert ds.attrs["final_effects"] == ",".join(EFFECTS)
    assert float(ds.fit_waist) == TRUE["waist"]
    fig.plot_realism(ds.assign_attrs(measured="none: test"))


def test_study_on_a_model_made_image_recovers_its_parameters():
    """'Measured' = the full model with known parameters (another seed): fits and needed set.

    Fit uncertainties: refit the autocorrelation shifted by +-1 SE (A-line blocks); the floor
    through its skewness, which must match the true floor's within 4 SE.
    """
    sim = {k: v for k, v in KW.items() if k not in ("max_lag", "n_blocks")}
    meas = simulate(frozenset(EFFECTS) - {"phase"}, TRUE, n_alines=512, seed=99, **sim)
    fit = fit_parameters(
        meas, None, pixel_size=5.75, n_pixels=32, max_lag=6, n_blocks=8, snr_db=TRUE["snr_db"]
    )
    st = image_statistics(meas, max_lag=6, n_blocks=8)
    a, se = st.autocorrelation, st.autocorrelation_se
    for name, axis, fitter in (
        ("fwhm_fraction", "depth", lambda y: ac.fit_spectral_width(y, 32, TRUE["snr_db"])[0]),
        ("waist", "lateral", lambda y: ac.fit_waist(y, TRUE["snr_db"])[0]),
    ):
        hi, lo = (fitter((a + s * se).sel(axis=axis).values) for s in (1, -1))
        assert abs(fit[name] - TRUE[name]) < 4 * abs(hi - lo) / 2
    skew_true = ms.log_speckle_moments(TRUE["floor"])["skewness"]
    assert abs(float(st.skewness) - skew_true) < 4 * float(st.skewness_se)
    ds = realism_study(meas, None, n_alines=256, fallback=TRUE, seed=1, **KW)
    needed = set(ds.attrs["final_effects"].split(","))
    assert {"spectral_width", "beam", "floor"} <= needed  # each moves a statistic by > 2 SE
    assert "phase" not in needed  # a smooth phase screen leaves single-image intensities alone
    assert float(ds.final_score) < float(ds.cumulative_score.sel(step="pure"))


@pytest.mark.pipeline
@pytest.mark.slow
def test_realism_target_without_the_measured_file(tmp_path, repo_root):
    """The pipeline target says it has no measured image and draws the model only."""
    for item in ("Snakefile", "workflow", "speckle", "pyproject.toml"):
        src = repo_root / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    override = tmp_path / "nomeasured.yaml"
    override.write_text(yaml.safe_dump({"realism": {"measured": {"path": None}}}))
    cmd = [
        sys.executable,
        "-m",
        "snakemake",
        "--cores",
        "1",
        "--configfile",
        "workflow/config/ci.yaml",
        str(override),
        "--",
        "results/realism/realism.png",
    ]
    env = {"PYTHONPATH": str(tmp_path), "PATH": __import__("os").environ["PATH"]}
    proc = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    ds = open_dataset(tmp_path / "results/realism/realism.nc")
    assert ds.attrs["measured"].startswith("none: not configured")
    assert "model_autocorrelation" in ds and "measured_autocorrelation" not in ds
    assert np.all(np.isfinite(ds.model_autocorrelation))
    log = (tmp_path / "results/logs/realism.log").read_text()
    assert "drawing the model only" in log
