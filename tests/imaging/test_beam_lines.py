"""Per-line weighted fields image the same B-scan as the direct beam_scan reference."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.imaging.beam_lines import beam_lines, shared_scatterers


def test_beam_lines_equal_beam_scan():
    n, h, w0, p = 32, 128.0, 6.0, 2.0
    sc = shared_scatterers(12, p, 2.0, n_pixels=n, depth_range=h, waist=w0, seed=3)
    src = speckle.spectrum(n, h, k0_dk=8, shape="gaussian", fwhm_fraction=0.4)
    ref = speckle.beam_scan(
        sc["z"],
        sc["x"],
        sc["amplitude"],
        lines=sc["lines"],
        waist=w0,
        n_pixels=n,
        depth_range=h,
        k0=src.attrs["k0"],
        spectrum=src.values,
    )
    scene = beam_lines(sc["z"], sc["x"], sc["amplitude"], lines=sc["lines"], waist=w0)
    img = speckle.bscan(scene, src).field.transpose("x", "depth").values
    # dropped weights < 1e-17 each, a few hundred scatterers: far below 1e-13 of the field
    np.testing.assert_allclose(img, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


def test_beam_lines_bad_inputs():
    with pytest.raises(ValueError, match="waist"):
        beam_lines([1.0], [0.0], [1.0], lines=[0.0], waist=0.0)
    with pytest.raises(ValueError, match="same length"):
        beam_lines([1.0, 2.0], [0.0], [1.0], lines=[0.0], waist=1.0)
