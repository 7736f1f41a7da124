"""Issue 21: malformed inputs to the datasheet and the spectrometer chain give a
TypeError/ValueError naming a parameter, or a finite answer; never another exception or a
hang. Plus the chain's NaN, boolean and memory cases."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from speckle.system import datasheet
from speckle.system import spectrometer as sp

SHEET = dict(
    wavelength_nm=840.0,
    bandwidth_nm=50.0,
    camera_pixels=32,
    camera_range_nm=(790.0, 890.0),
    refractive_index=1.38,
    spectral_resolution_nm=0.1,
    fill_factor=0.9,
    aline_pitch=5.0,
    beam_waist=8.0,
)
SYSTEM = datasheet(**SHEET)
SIGNAL, K = sp.camera_signal(SYSTEM, [[100.0, 200.0]], [[1.0, 0.5]], detection="real")
GRID = sp.grid_wavenumbers(SYSTEM)

VALID = {
    "datasheet": dict(SHEET),
    "interferogram": dict(
        z=[[50.0]],
        amplitude=[[1.0]],
        spectrum=np.ones(K.size),
        k0=SYSTEM.k0,
        detection="real",
        dc=False,
        autocorrelation=True,
        reference_power=2.0,
    ),
    "camera_signal": dict(
        pixel_width=True, resolution=False, dc=True, on_grid=False, sampling="wavelength"
    ),
    "process_interferogram": dict(
        signal=np.concatenate([SIGNAL, SIGNAL]),
        k0=SYSTEM.k0,
        resample="cubic",
        apodization="hann",
        apodization_fwhm_fraction=0.5,
        background="mean",
    ),
    "system_ascan": dict(resample="linear", apodization="gaussian", apodization_fwhm_fraction=0.4),
    "linearize": dict(signal=SIGNAL[0], method="linear"),
    "interpolation_gain": dict(theta=1.0, t=0.3, method="cubic"),
}


def _call(name: str, kw: dict):
    if name == "datasheet":
        return datasheet(**kw).to_dict()["axial_resolution"]
    if name == "interferogram":
        return sp.interferogram(kw.pop("z"), kw.pop("amplitude"), K, kw.pop("spectrum"), **kw)
    if name == "camera_signal":
        return sp.camera_signal(SYSTEM, [[100.0]], [[1.0]], **kw)[0]
    if name == "process_interferogram":
        return sp.process_interferogram(kw.pop("signal"), grid=GRID, wavenumber=K, **kw)
    if name == "system_ascan":
        return sp.system_ascan(SYSTEM, [[100.0]], [[1.0]], **kw)
    if name == "linearize":
        return sp.linearize(kw["signal"], K, GRID, kw["method"])
    return sp.interpolation_gain(**kw)


@given(data=st.data())
def test_malformed_chain_inputs(malformed_target, data, malformed):
    malformed.run(VALID, _call, malformed_target, data)


def test_valid_calls_work():
    for name, kw in VALID.items():
        _call(name, dict(kw))


def test_nan_in_the_camera_spectrum_is_refused_with_its_count():
    """Issue 21: one NaN gave an all-NaN A-scan (or scipy's 'y must contain only finite
    values' with cubic resampling)."""
    bad = SIGNAL.copy()
    bad[0, [3, 7]] = np.nan
    for resample in ("cubic", "linear"):
        with pytest.raises(ValueError, match="signal must be finite; it holds 2 NaN"):
            sp.process_interferogram(bad, grid=GRID, k0=SYSTEM.k0, wavenumber=K, resample=resample)
    with pytest.raises(ValueError, match="spectrum must be finite; it holds 1 NaN"):
        sp.interferogram([[1.0]], [[1.0]], K, np.r_[np.nan, np.ones(K.size - 1)])


def test_chain_flags_are_booleans():
    for flag in ("pixel_width", "dc", "on_grid"):
        for bad in ("False", 0.5):
            with pytest.raises(TypeError, match=f"{flag} must be True or False"):
                sp.camera_signal(SYSTEM, [[100.0]], [[1.0]], **{flag: bad})
    with pytest.raises(ValueError, match="camera_pixels too large"):
        datasheet(840.0, 50.0, 10**12, imaging_depth=1000.0)


def test_chain_memory_is_estimated_before_allocation():
    """Autocorrelation of finite pixels sums M^2/2 pairs: 2e5 scatterers on one line."""
    many = np.linspace(0.0, 500.0, 200_000)[None]
    with pytest.raises(ValueError, match=r"z \(lines x scatterers\).*GiB"):
        sp.interferogram(
            many, np.ones_like(many), K, np.ones(K.size), pixel_width=0.01, autocorrelation=True
        )
    est = sp.interferogram_bytes(
        1, 200_000, K.size, method="direct", finite_pixels=True, autocorrelation=True
    )
    assert est > 40 * 200_000**2 / 2 * 0.99
