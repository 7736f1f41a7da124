"""Dask sweeps: stacked dims, and identical numbers whatever the scheduler or worker count."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.sweep import sweep


def small_bscan(density, k0_dk, seed):
    src = speckle.spectrum(32, 256.0, k0_dk=k0_dk)
    sc = speckle.random_scatterers(4, density, n_pixels=32, depth_range=256.0, seed=seed)
    return speckle.bscan(sc, src)[["field"]]


GRID = {"density": [0.5, 2.0, 4.0], "k0_dk": [1.0, 10.0]}


@pytest.fixture(scope="module")
def reference():
    return sweep(small_bscan, GRID, fixed={"seed": 3}, scheduler="synchronous")


def test_sweep_stacks_along_named_dims(reference):
    assert reference.field.dims == ("density", "k0_dk", "depth", "x")
    np.testing.assert_array_equal(reference.density, GRID["density"])
    direct = small_bscan(2.0, 10.0, 3)
    np.testing.assert_array_equal(reference.field.sel(density=2.0, k0_dk=10.0), direct.field)


@pytest.mark.parametrize(
    ("scheduler", "workers"), [("threads", 1), ("threads", 2), ("distributed", 2)]
)
def test_same_numbers_whatever_the_scheduler(reference, scheduler, workers):
    out = sweep(small_bscan, GRID, fixed={"seed": 3}, scheduler=scheduler, n_workers=workers)
    np.testing.assert_array_equal(out.field.values, reference.field.values)


def test_bad_sweep_input():
    with pytest.raises(ValueError, match="scheduler"):
        sweep(small_bscan, GRID, scheduler="mpi")
    with pytest.raises(ValueError, match="grid"):
        sweep(small_bscan, {})
    with pytest.raises(ValueError, match="density"):
        sweep(small_bscan, {"density": []})
    with pytest.raises(ValueError, match="n_workers"):
        sweep(small_bscan, GRID, n_workers=0)
