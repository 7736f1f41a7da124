"""Issue 21: malformed inputs to the system effects (attenuation, backscatter, roll-off, noise,
polarization, phase screens, detection) give a TypeError/ValueError naming a parameter, or a
finite answer; never another exception or a hang. Plus the issue's silent wrong answers."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st

import speckle
import speckle.scene.regions as reg
import speckle.scene.shared as sh
from speckle.system import attenuation, detection, noise, phase, polarization

SRC = speckle.spectrum(16, 128.0, k0_dk=3.0)
LINES = speckle.random_scatterers(4, 2.0, n_pixels=16, depth_range=128.0, seed=1)
IMAGE = speckle.bscan(LINES, SRC)
REGIONS = reg.make_regions(reg.background(density=0.02, attenuation=0.001))
SCENE = sh.shared_scene(REGIONS, z_range=(0.0, 40.0), x_range=(0.0, 40.0), seed=1, tile=20.0)

VALID = {
    "attenuate": dict(attenuation=0.001),
    "backscatter": dict(value=2.0),
    "rolloff": dict(z_max=64.0, resolution=0.5),
    "add_noise": dict(snr_db=20.0, seed=3, kind="white", signal_intensity=1.0),
    "depolarize": dict(depolarization=0.3, seed=2),
    "phase_perturb": dict(index_variance=1e-6, correlation_length=20.0, k0=1.0, seed=4),
    "log_compress": dict(gain=20.0, offset=100.0, bits=8),
    "add_floor": dict(floor=0.1, mean_intensity=1.0),
}


def _call(name: str, kw: dict):
    if name == "attenuate":
        return attenuation.attenuate(LINES, **kw)
    if name == "backscatter":
        return speckle.system.backscatter(LINES, **kw)
    if name == "rolloff":
        return speckle.system.rolloff(LINES, **kw)
    if name == "add_noise":
        return noise.add_noise(IMAGE, **kw)
    if name == "depolarize":
        return polarization.depolarize(SCENE, **kw)
    if name == "phase_perturb":
        return phase.phase_perturb(SCENE, **kw)
    if name == "log_compress":
        return detection.log_compress(IMAGE.intensity, **kw)
    return detection.add_floor(IMAGE.intensity, **kw)


@given(data=st.data())
def test_malformed_effect_inputs(malformed_target, data, malformed):
    malformed.run(VALID, _call, malformed_target, data)


def test_valid_calls_work():
    for name, kw in VALID.items():
        _call(name, dict(kw))


# --- the silent wrong answers ------------------------------------------------------


def test_noise_of_an_image_does_not_depend_on_the_other_images():
    """Same seed, same noise on the strain-0 image whatever the number of strains."""
    scene = speckle.deformable_scene(4, 2.0, n_pixels=16, depth_range=128.0, seed=1, strain=0.02)
    noisy = []
    for strains in ([0.0, 0.01], [0.0, 0.005, 0.01, 0.02]):
        img = speckle.bscan(speckle.uniaxial_strain(scene, strains), SRC)
        noisy.append(noise.add_noise(img, 10.0, seed=5, signal_intensity=1.0).noise)
    np.testing.assert_array_equal(noisy[0].isel(strain=0), noisy[1].isel(strain=0))
    # and the images' noises are independent draws
    assert not np.allclose(noisy[1].isel(strain=0), noisy[1].isel(strain=1))


def test_nan_in_noise_and_detection_inputs_is_refused_with_its_count():
    bad = IMAGE.copy()
    bad["field"] = bad.field.where(~((bad.depth == bad.depth[3]) & (bad.x == 0)))
    with pytest.raises(ValueError, match="image field must be finite; it holds 1 NaN"):
        noise.add_noise(bad, 10.0, seed=1)
    inten = IMAGE.intensity.copy()
    inten[2, 1] = np.nan
    for func, args in ((detection.add_floor, (0.1,)), (detection.log_compress, (20.0, 100.0))):
        with pytest.raises(ValueError, match="intensity must be finite; it holds 1 NaN"):
            func(inten, *args)


def test_the_complex_field_is_not_an_intensity():
    with pytest.raises(TypeError, match="intensity must be real"):
        detection.log_compress(IMAGE.field, 20.0, 100.0)


def test_phase_screens_on_3d_scenes_vary_in_y():
    """Scatterers at one (z, x) but y far apart (>> the correlation length) get unrelated
    phases; at a lag dy the phase difference variance is 2 Var(phi) (1 - exp(-dy^2/l^2))."""
    ell, s2, k0 = 20.0, 1e-5, 5.0
    n = 400
    z = np.full(3, 30.0)
    x = np.zeros(3)
    y = np.array([0.0, 10.0, 400.0])
    d = np.array(
        [
            phase.shared_phase_screen(
                z, x, y=y, index_variance=s2, correlation_length=ell, k0=k0, seed=s
            )
            for s in range(n)
        ]
    )
    var = phase.phase_structure(30.0, s2, ell, k0)  # Var phi(z) = 4 k0^2 D(z)
    for j, dy in ((1, 10.0), (2, 400.0)):
        expected = 2 * var * (1 - np.exp(-(dy**2) / ell**2))
        measured = np.mean((d[:, 0] - d[:, j]) ** 2)
        # the mean of n squared normals: relative standard error sqrt(2/n) = 7 %
        assert measured == pytest.approx(expected, rel=5 * np.sqrt(2 / n))
    # and a 3-D shared scene uses y
    scene3 = sh.shared_scene(REGIONS, z_range=(0.0, 40.0), x_range=(0.0, 20.0),
                             y_range=(0.0, 400.0), seed=1, tile=40.0)  # fmt: skip
    out = phase.phase_perturb(scene3, index_variance=s2, correlation_length=ell, k0=k0, seed=1)
    phi = np.angle(out.amplitude.values / scene3.amplitude.values)
    far = np.abs(scene3.y.values - 200.0) > 150
    assert np.std(phi[far & (scene3.y.values < 200)]) > 0
    flat = phase.shared_phase_screen(scene3.z.values, scene3.x.values, index_variance=s2,
                                     correlation_length=ell, k0=k0, seed=1)  # fmt: skip
    assert not np.allclose(np.angle(np.exp(1j * flat)), phi)


def test_depolarization_tables_are_fractions():
    table = REGIONS.copy()
    table["depolarization"] = xr.ones_like(table.depolarization) * 1.5
    with pytest.raises(ValueError, match="depolarization"):
        polarization.depolarize(SCENE, table, seed=1)
