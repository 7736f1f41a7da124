"""Carrier phase exp(2i k0 z) in float64 and the naive-float32 failure mode."""

from __future__ import annotations

import numpy as np
import pytest

# private: the carrier phase of the fast methods (imaging/_methods)
from speckle.imaging._methods.carrier import carrier_and_position, naive_float32_phase_error

EPS32 = float(np.finfo(np.float32).eps)


def test_carrier_matches_numpy_at_large_phase():
    rng = np.random.default_rng(0)
    z = rng.uniform(-1e4, 1e5, 5000)  # µm, far beyond one unambiguous depth
    a = rng.normal(size=5000) + 1j * rng.normal(size=5000)
    k0, h, grid = 7.853, 2048.0, 512
    cr, ci, u = np.empty(5000), np.empty(5000), np.empty(5000)
    carrier_and_position(z, a, k0, h, grid, cr, ci, u)
    exact = a * np.exp(2j * k0 * z)
    # both round 2 k0 z (~1.6e6 rad) to float64: ~1e-10 rad; the polynomial adds < 1e-15
    np.testing.assert_allclose(cr + 1j * ci, exact, rtol=0, atol=1e-9 * np.abs(a).max())
    assert np.all((u >= 0) & (u < grid))
    np.testing.assert_allclose(u, np.mod(z, h) / h * grid, atol=1e-9)


@pytest.mark.parametrize("k0", [1.0, 10.0])
def test_naive_float32_phase_error_grows_with_k0_z(k0):
    """float32(z) is off by up to half an ulp; the phase error 2 k0 dz is then uniform with rms
    ~ 2 k0 z eps32/sqrt(12)*c, c in [0.5, 1] from the position of z in its binade. For z up to
    Z the rms error is between 0.1 and 1 times eps32 * 2 k0 Z."""
    rng = np.random.default_rng(1)
    for zmax in (1e3, 1e4):
        z = rng.uniform(0, zmax, 20000)
        err = naive_float32_phase_error(z, k0)
        scale = EPS32 * 2 * k0 * zmax
        assert 0.05 * scale < err < scale
    # at OCT values (k0/dk = 10, 8 µm pixels, 1024 px) it is far above a 1e-6 tolerance
    assert naive_float32_phase_error(rng.uniform(0, 8192, 20000), 10 * np.pi / 8) > 1e-4
