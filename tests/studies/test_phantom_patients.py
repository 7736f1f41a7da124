"""Virtual patients (issue 34) and the named scanner configurations: the truth against the table."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.studies.phantom import slab_constants

#: The reduced closed-loop scanner: 128 x 128 pixels of 6 µm, radius 10 µm.
SMALL = speckle.ScannerConfig(n_pixels=128, n_lines=128, x_max=768.0, n_scatterers=37_500)


def test_named_configs():
    assert speckle.synthoct_config("challenge") == speckle.ScannerConfig()
    cfg = speckle.synthoct_config("2025")
    assert (cfg.n_pixels, cfg.pixel_size, cfg.beam_radius) == (601, 2.2, 6.0)
    assert (cfg.n_lines, cfg.x_max, cfg.n_scatterers) == (975, 3000.0, 255_000)
    assert speckle.synthoct_config("2025", n_scatterers=10).n_scatterers == 10
    with pytest.raises(ValueError, match="name must be one of"):
        speckle.synthoct_config("2024")
    with pytest.raises(TypeError, match="unknown ScannerConfig fields"):
        speckle.synthoct_config("2025", radius=3.0)
    with pytest.raises(ValueError, match="n_pixels"):
        speckle.synthoct_config("2025", n_pixels=0)


def _region_of(table, truth, cfg):
    """Region index of each scatterer from the truth's geometry (K + j for inclusion j)."""
    from speckle.studies.phantom.patients import profiles

    x, z = table[:, 0], table[:, 2]
    coefficients = np.column_stack(
        [truth.top_mean.values, truth.top_tilt.values, truth.top_curvature.values]
    )[1:]
    region = np.sum(z[None, :] >= profiles(coefficients, x, cfg.x_max), axis=0)
    for j in range(truth.sizes["inclusion"]):
        xc, zc = float(truth.inclusion_x[j]), float(truth.inclusion_z[j])
        w, h = float(truth.inclusion_width[j]), float(truth.inclusion_height[j])
        region = np.where(((x - xc) / w) ** 2 + ((z - zc) / h) ** 2 < 1,
                          truth.sizes["layer"] + j, region)  # fmt: skip
    return region


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_table_holds_the_truth(seed):
    """Every scatterer lies in its region (by the truth's profiles and ellipses) with that
    region's energy; each region's count against ``rho V`` within 4 binomial SEs (seed 4:
    three inclusions)."""
    inclusions = 3 if seed == 4 else seed % 2 == 1
    table, truth = speckle.virtual_patient(seed, config=SMALL, inclusions=inclusions)
    assert table.shape == (SMALL.n_scatterers, 4)
    assert np.all(np.abs(table[:, 0]) <= SMALL.x_max / 2)
    assert np.all(np.abs(table[:, 1]) <= SMALL.beam_radius)
    assert np.all((table[:, 2] >= 0) & (table[:, 2] <= SMALL.depth_range))
    region = _region_of(table, truth, SMALL)
    energy = np.concatenate([truth.energy.values, truth.inclusion_energy.values])
    density = np.concatenate([truth.density.values, truth.inclusion_density.values])
    assert np.allclose(table[:, 3], energy[region])
    # volumes on a fine grid of lines: each region's count is binomial(M, rho V/M)
    xs = (np.arange(20_000) + 0.5) / 20_000 * SMALL.x_max - SMALL.x_max / 2
    zs = (np.arange(1536) + 0.5) / 1536 * SMALL.depth_range
    gx, gz = np.meshgrid(xs[::10], zs, indexing="ij")
    cells = _region_of(np.column_stack([gx.ravel(), 0 * gx.ravel(), gz.ravel(), 0 * gx.ravel()]),
                       truth, SMALL)  # fmt: skip
    cell = (SMALL.x_max / xs[::10].size) * (SMALL.depth_range / zs.size) * 2 * SMALL.beam_radius
    m = SMALL.n_scatterers
    for k in range(energy.size):
        expected = density[k] * np.sum(cells == k) * cell
        se = np.sqrt(expected * (1 - expected / m))
        assert abs(np.sum(region == k) - expected) < 4 * se + 0.01 * expected
    a2 = slab_constants(SMALL.beam_radius)["A2"]
    assert np.allclose(truth.attenuation, truth.density * truth.energy / 100 * a2)
    assert np.allclose(truth.top.isel(layer=0), 0.0)


def test_seeded_and_redrawn():
    a, ta = speckle.virtual_patient(5, config=SMALL)
    b, tb = speckle.virtual_patient(5, config=SMALL)
    c, tc = speckle.virtual_patient(5, config=SMALL, draw_seed=9)
    assert np.array_equal(a, b) and ta.identical(tb)
    assert not np.array_equal(a, c)
    assert np.allclose(tc.top, ta.top) and np.allclose(tc.energy, ta.energy)
    assert np.allclose(tc.density, ta.density)
    assert tc.attrs["draw_seed"] == 9


def test_shapes_and_layers():
    for seed in range(6):
        _, truth = speckle.virtual_patient(seed, config=SMALL, layers=(4, 5), shapes=("curved",))
        assert 4 <= truth.sizes["layer"] <= 5
        assert list(truth.shape.values[1:]) == ["curved"] * (truth.sizes["layer"] - 1)
        assert np.all(truth.top_curvature.values[1:] != 0)
        # at least min_thickness (15 pixels) apart on every line
        assert np.all(np.diff(truth.top.values, axis=0) >= 15 * SMALL.pixel_size - 1e-9)
    _, flat = speckle.virtual_patient(0, config=SMALL, shapes=("flat",))
    assert np.all(flat.top_tilt == 0) and np.all(flat.top_curvature == 0)


def test_named_config_and_units():
    table, truth = speckle.virtual_patient(1, config="challenge", layers=(2, 2))
    assert table.shape == (300_000, 4)
    assert truth.sizes["x"] == 512 and truth.sizes["layer"] == 2
    assert truth.top.attrs["units"] == "um" and truth.attenuation.attrs["units"] == "1/um"
    assert truth.density.attrs["units"] == "um-3" and truth.energy.attrs["units"] == "percent"


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(seed=-1), "seed"),
        (dict(seed=1.5), "seed"),
        (dict(config="nope"), "name"),
        (dict(config=3), "config"),
        (dict(layers=(0, 3)), "layers"),
        (dict(layers=(3, 2)), "layers"),
        (dict(shapes=("wavy",)), "shapes"),
        (dict(inclusions=5), "inclusions"),
        (dict(inclusions="yes"), "inclusions"),
        (dict(energy_range=(0.0, 1.0)), "energy_range"),
        (dict(energy_range=(1.0, 200.0)), "energy_range"),
        (dict(density_range=(1.0, float("nan"))), "density_range"),
        (dict(min_contrast=0.5), "min_contrast"),
        (dict(min_thickness=-1.0), "min_thickness"),
        (dict(max_tilt=float("inf")), "max_tilt"),
        (dict(draw_seed=-2), "draw_seed"),
    ],
)
def test_refuses_bad_options(kwargs, match):
    args = {"seed": 0, "config": SMALL, **kwargs}
    with pytest.raises((TypeError, ValueError), match=match):
        speckle.virtual_patient(args.pop("seed"), **args)


def test_too_many_layers_is_refused_clearly():
    with pytest.raises(ValueError, match="min_thickness"):
        speckle.virtual_patient(0, config=SMALL, layers=(8, 8), min_thickness=120.0)
