"""Tilted and curved boundaries of fit_phantom (issue 34): shape by BIC, profile, render."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.studies.phantom.patients import patient_table, profiles

REDUCED = speckle.synthoct_config("reduced")


def two_layers(cfg, tilt, curvature, seed, ratio=4.0):
    """Two layers of one density, energies 0.2 % and ``ratio`` x 0.2 %, the boundary
    ``a + b x + c (x^2 - X^2/12)`` at a third of the depth: ``(table, coefficients)``."""
    coefficients = np.array([[cfg.depth_range / 3, tilt, curvature]])
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    table, _ = patient_table(cfg, coefficients, np.ones(2), np.array([0.2, 0.2 * ratio]), None,
                             rng)  # fmt: skip
    return table, coefficients


def central(cfg):
    x = cfg.line_positions
    return x[np.abs(x) <= cfg.x_max / 2 - 3 * cfg.beam_radius]


@pytest.mark.parametrize(
    "tilt, curvature, shape",
    [(0.0, 0.0, "flat"), (0.08, 0.0, "tilted"), (0.0, 3e-4, "curved")],
)
def test_shape_chosen_and_profile_within_a_pixel(tilt, curvature, shape):
    """The boundary's shape by BIC and its profile within a pixel on every fitted line; the
    tilt (and curvature) within 3 jackknife SEs of the truth (0.08: 61 µm over the box; 3e-4:
    a sag of 44 µm at the box's edges)."""
    table, coefficients = two_layers(REDUCED, tilt, curvature, 5)
    fit = speckle.fit_phantom(speckle.synthoct_scan(table, REDUCED), REDUCED)
    layers = fit.layers
    assert layers.sizes["layer"] == 2
    assert str(layers.shape.values[1]) == shape
    x = central(REDUCED)
    got = speckle.studies.phantom.loop.fit_profiles(layers, x, REDUCED.x_max)[1]
    true = profiles(coefficients, x, REDUCED.x_max)[0]
    assert np.max(np.abs(got - true)) < REDUCED.pixel_size
    if shape != "flat":
        assert abs(float(layers.top_tilt[1]) - tilt) < 3 * float(layers.top_tilt_se[1])
    if shape == "curved":
        c, se = float(layers.top_curvature[1]), float(layers.top_curvature_se[1])
        assert abs(c - curvature) < 3 * se


def test_render_draws_the_fitted_boundary():
    """The fitted phantom of a tilted boundary, drawn and scanned again, is fitted back to the
    same tilt within the two fits' SEs combined (3 SE)."""
    table, _ = two_layers(REDUCED, 0.08, 0.0, 7)
    fit = speckle.fit_phantom(speckle.synthoct_scan(table, REDUCED), REDUCED)
    drawn = fit.phantom(3)
    assert drawn.shape == (REDUCED.n_scatterers, 4)
    x, z, e = drawn[:, 0], drawn[:, 2], drawn[:, 3]
    boundary = speckle.studies.phantom.loop.fit_profiles(fit.layers, x, REDUCED.x_max)[1]
    # every scatterer carries its layer's energy: the boundary follows the fitted profile
    assert np.unique(e[z < boundary]).size == 1 and np.unique(e[z >= boundary]).size == 1
    again = speckle.fit_phantom(fit.render(3), REDUCED).layers
    a, b = fit.layers, again
    se = np.hypot(float(a.top_tilt_se[1]), float(b.top_tilt_se[1]))
    assert abs(float(b.top_tilt[1]) - float(a.top_tilt[1])) < 3 * se


def test_flat_only_and_bad_shapes():
    table, _ = two_layers(REDUCED, 0.08, 0.0, 5)
    scan = speckle.synthoct_scan(table, REDUCED)
    flat = speckle.fit_phantom(scan, REDUCED, shapes=("flat",)).layers
    assert list(flat.shape.values) == ["flat", "flat"] and np.all(flat.top_tilt == 0)
    for bad in (("tilted",), ("flat", "wavy"), "flat"):
        with pytest.raises(ValueError, match="shapes"):
            speckle.fit_phantom(scan, REDUCED, shapes=bad)
