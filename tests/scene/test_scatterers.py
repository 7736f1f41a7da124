"""Random scatterer fields: counts, ranges, seeding, amplitude models."""

from __future__ import annotations

import numpy as np
import pytest

from speckle.scene.scatterers import amplitude_kurtosis, random_scatterers

KW = {"n_pixels": 64, "depth_range": 512.0}


def test_fixed_count_and_range():
    sc = random_scatterers(5, 0.74, seed=1, **KW)
    assert sc.z.dims == ("aline", "scatterer")
    assert sc.sizes["scatterer"] == round(0.74 * 64)
    assert float(sc.z.min()) >= 0 and float(sc.z.max()) < 512.0
    np.testing.assert_allclose(sc.aline, np.arange(5) * 8.0)
    assert sc.z.attrs["units"] == "um" and sc.aline.attrs["units"] == "um"


def test_z_range_keeps_density_per_pixel():
    sc = random_scatterers(2, 2.0, seed=1, z_range=(-64.0, 576.0), **KW)
    assert sc.sizes["scatterer"] == round(2.0 * 64 * 640 / 512)
    assert float(sc.z.min()) >= -64.0 and float(sc.z.max()) < 576.0


def test_same_seed_same_field_and_lines_independent_of_count():
    a = random_scatterers(6, 2.0, seed=7, **KW)
    b = random_scatterers(6, 2.0, seed=7, **KW)
    sub = random_scatterers(2, 2.0, seed=7, first_aline=3, **KW)
    np.testing.assert_array_equal(a.z, b.z)
    np.testing.assert_array_equal(a.z[3:5], sub.z)
    np.testing.assert_array_equal(a.aline[3:5], sub.aline)
    c = random_scatterers(6, 2.0, seed=8, **KW)
    assert not np.array_equal(a.z, c.z)


def test_poisson_counts_are_padded_with_zero_amplitudes():
    sc = random_scatterers(400, 1.0, seed=3, count="poisson", **KW)
    counts = sc["count"].values
    # mean 64, standard error sqrt(64/400) = 0.4: 5 sigma
    assert abs(counts.mean() - 64) < 5 * 0.4
    pad = np.arange(sc.sizes["scatterer"])[None, :] >= counts[:, None]
    assert np.all(sc.amplitude.values[pad] == 0)
    assert np.all(sc.amplitude.values[~pad] == 1)


@pytest.mark.parametrize("model", ["equal", "rayleigh", "uniform"])
def test_amplitude_models_have_unit_mean_square_and_stated_kurtosis(model):
    sc = random_scatterers(200, 4.0, seed=11, amplitude=model, **KW)
    a2 = np.abs(sc.amplitude.values.ravel()) ** 2
    n = a2.size
    kappa = amplitude_kurtosis(model)
    # E|a|^2 = 1 with standard error sqrt((kappa - 1)/n); 5 sigma (+ tiny floor for "equal")
    assert abs(a2.mean() - 1) <= 5 * np.sqrt((kappa - 1) / n) + 1e-12
    if model != "equal":
        assert abs(np.mean(a2**2) - kappa) < 0.15 * kappa


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"density": -1.0}, ValueError, "density"),
        ({"density": np.nan}, ValueError, "density"),
        ({"n_alines": 0}, ValueError, "n_alines"),
        ({"seed": -1}, ValueError, "seed"),
        ({"seed": 1.5}, TypeError, "seed"),
        ({"amplitude": "gamma"}, ValueError, "amplitude"),
        ({"count": "binomial"}, ValueError, "count"),
        ({"z_range": (10.0, 5.0)}, ValueError, "z_range"),
        ({"aline_pitch": 0.0}, ValueError, "aline_pitch"),
    ],
)
def test_bad_scene_input(kwargs, exc, match):
    args = {"n_alines": 2, "density": 1.0, "seed": 0, **KW, **kwargs}
    with pytest.raises(exc, match=match):
        random_scatterers(args.pop("n_alines"), args.pop("density"), **args)
