"""The phantom fit's closed loop (issue 34): cases, pulls, layer counts, boundaries."""

from __future__ import annotations

import numpy as np
import pytest

import speckle

#: The reduced closed-loop scanner: 128 x 128 pixels of 6 µm, radius 10 µm.
SMALL = speckle.ScannerConfig(n_pixels=128, n_lines=128, x_max=768.0, n_scatterers=37_500)


def test_case_dataset():
    case = speckle.phantom_closed_loop_case(0, config=SMALL, layers=(2, 2), shapes=("flat",),
                                            fit_seed=4)  # fmt: skip
    assert case.sizes["layer"] == 2
    assert bool(case.layers_right) and bool(case.success) and str(case.failure.values) == ""
    assert np.all(case.boundary_error < 1)
    assert np.isnan(float(case.top_pull[0]))
    for name in ("target_scan", "fitted_scan", "floor_scan"):
        assert case[name].dims == ("depth", "x") and case[name].dtype == np.uint8
    assert case.fit_attenuation.attrs["units"] == "1/um"
    assert not np.array_equal(case.target_scan, case.floor_scan)
    no_scans = speckle.phantom_closed_loop_case(0, config=SMALL, layers=(2, 2), shapes=("flat",))
    assert "fitted_scan" not in no_scans and no_scans.attrs["fit_seed"] == -1
    assert np.array_equal(no_scans.fit_attenuation, case.fit_attenuation)


@pytest.mark.parametrize("kwargs, match", [(dict(fit_seed=-1), "fit_seed"),
                                           (dict(max_layers=0), "max_layers"),
                                           (dict(layers=(0, 1)), "layers")])  # fmt: skip
def test_case_refuses_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        speckle.phantom_closed_loop_case(0, config=SMALL, **kwargs)
