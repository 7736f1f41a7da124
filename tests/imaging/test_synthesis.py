"""method="auto": rules, admissibility (failure detection) and accuracy on random scenes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

# private: the methods' error models behind the choice
from speckle.imaging._methods.nufft import float32_error_estimate, kernel_width

# private: the methods' error models behind the choice
from speckle.imaging._methods.psf import half_width
from speckle.imaging.aline import ascan, stream_ascans
from speckle.imaging.methods import ASCAN_METHODS
from speckle.imaging.synthesis import (
    AUTO_CANDIDATES,
    choose_method,
    method_estimates,
)
from speckle.scene.scatterers import random_scatterers


def gaussian(n, fraction):
    idx = np.arange(n) - n // 2
    return np.exp(-4 * np.log(2) * (idx / (fraction * n)) ** 2)


SPECTRA = {"rectangular": None, "gaussian": 0.15, "wide-gaussian": 0.4}


def spectrum_of(name, n):
    return None if SPECTRA[name] is None else gaussian(n, SPECTRA[name])


sizes = dict(
    n_lines=st.integers(1, 4096),
    n_pixels=st.integers(2, 4096),
    density=st.sampled_from([0.25, 1, 4, 32]),
    shape=st.sampled_from(list(SPECTRA)),
    tol=st.sampled_from([1e-1, 1e-2, 1e-4, 1e-6, 3e-7, 1e-9, 1e-14]),
)


@settings(max_examples=200, deadline=None)
@given(**sizes)
def test_auto_stays_inside_every_valid_region(n_lines, n_pixels, density, shape, tol):
    """Rules only (no synthesis): whatever the scene, the choice is admissible."""
    m = max(1, round(density * n_pixels))
    s = spectrum_of(shape, n_pixels)
    choice = choose_method(n_lines, m, n_pixels, s, tol)
    assert choice in AUTO_CANDIDATES
    if choice == "nufft32":  # float32 only where its rounding (and phase) error fits in tol
        assert float32_error_estimate(m, n_pixels, kernel_width(tol / 2)) <= tol / 2
    if choice == "psf" and shape == "rectangular" and tol <= 1e-2:
        # a rectangular PSF is never truncated at a tight tol: only the full-width (exact) PSF
        assert half_width(np.ones(n_pixels), tol) == n_pixels // 2
    if tol < 1e-13:  # below the NUFFT floor: direct, or a psf that is exact on this spectrum
        assert choice in ("direct", "psf")
    est = method_estimates(n_lines, m, n_pixels, s, tol)
    assert est[choice]["error"] <= tol


def test_auto_never_picks_float32_below_its_floor():
    for n in (64, 256, 1024, 4096):
        for tol in (1e-7, 3e-7):
            floor = float32_error_estimate(4 * n, n, kernel_width(tol / 2))
            assert floor > tol / 2
            assert choose_method(512, 4 * n, n, None, tol) != "nufft32"
    # and where float32 does fit, it is chosen for a large scene (it is the fastest there)
    assert choose_method(512, 4096, 1024, None, 1e-3) == "nufft32"


def test_auto_never_picks_truncated_psf_on_rectangular_spectrum():
    for n in (8, 64, 256):
        for tol in (1e-3, 1e-6):
            est = method_estimates(16, 4 * n, n, None, tol)
            # a truncated rectangular PSF would err by ~1/(pi sqrt(hw)) >> tol: psf is only
            # admissible at full width, where its cost is ~N per scatterer
            if est["psf"]["admissible"]:
                assert half_width(np.ones(n), tol) == n // 2
            if choose_method(256, 4 * n, n, None, tol) == "psf":  # only untruncated (tiny N)
                assert half_width(np.ones(n), tol) == n // 2
    assert choose_method(256, 4 * 256, 256, None, 1e-6) != "psf"


def test_psf_is_admissible_on_a_narrow_gaussian():
    est = method_estimates(16, 64, 64, gaussian(64, 0.15), 1e-4)
    assert est["psf"]["admissible"] and est["psf"]["error"] <= 1e-4


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    n=st.integers(2, 160),
    lines=st.integers(1, 40),
    density=st.sampled_from([0.5, 4.0]),
    shape=st.sampled_from(list(SPECTRA)),
    tol=st.sampled_from([1e-1, 1e-3, 1e-6, 1e-10, 1e-14, None]),
)
# found by hypothesis: at N = 2 auto picks psf below the NUFFT floor (exact there: full line)
@example(seed=1, n=2, lines=3, density=4.0, shape="gaussian", tol=1e-14)
def test_auto_result_within_tol(seed, n, lines, density, shape, tol):
    rng = np.random.default_rng(seed)
    h = 8.0 * n
    m = max(1, round(density * n))
    z = rng.uniform(-h, 3 * h, (lines, m))
    a = rng.normal(size=(lines, m)) + 1j * rng.normal(size=(lines, m))
    s = spectrum_of(shape, n)
    k0 = 10 * n * np.pi / h
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s)
    out = ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=s, method="auto", tol=tol)
    err = np.linalg.norm(out - ref) / np.linalg.norm(ref)
    assert err <= (1e-12 if tol is None else tol)


def test_loose_nufft_tol_error_is_accounted_for():
    """At tol = 0.1 the NUFFT really errs by several percent; auto's prediction covers it."""
    rng = np.random.default_rng(2)
    n, h = 128, 1024.0
    z, a = rng.uniform(0, h, (8, 512)), rng.normal(size=(8, 512)) + 0j
    ref = ascan(z, a, n_pixels=n, depth_range=h, k0=3.0)
    for tol in (1e-1, 1e-2):
        err = np.linalg.norm(
            ascan(z, a, n_pixels=n, depth_range=h, k0=3.0, method="nufft", tol=tol) - ref
        )
        err /= np.linalg.norm(ref)
        predicted = method_estimates(8, 512, n, None, tol)["nufft"]["error"]
        assert tol / 20 < err <= predicted


def test_auto_runs_exactly_one_method(monkeypatch):
    calls = []
    for name in AUTO_CANDIDATES:
        real = ASCAN_METHODS[name]

        def spy(*args, _name=name, _real=real):
            calls.append(_name)
            return _real(*args)

        monkeypatch.setitem(ASCAN_METHODS, name, spy)
    ascan(
        np.ones((3, 10)),
        np.ones((3, 10)),
        n_pixels=16,
        depth_range=128.0,
        k0=1.0,
        method="auto",
        tol=1e-3,
    )
    assert len(calls) == 1


@pytest.mark.parametrize("bad", [0.0, 1.0, -1e-3, float("nan"), 2.0])
def test_bad_tol(bad):
    with pytest.raises(ValueError, match="tol"):
        ascan([1.0], [1.0], n_pixels=8, depth_range=64.0, k0=1.0, method="auto", tol=bad)


def test_bad_tol_type_and_unknown_method():
    with pytest.raises(TypeError, match="tol"):
        ascan([1.0], [1.0], n_pixels=8, depth_range=64.0, k0=1.0, method="nufft", tol="1e-6")
    with pytest.raises(ValueError, match=r"method must be one of.*auto"):
        ascan([1.0], [1.0], n_pixels=8, depth_range=64.0, k0=1.0, method="fastest")


def test_registry_holds_every_method():
    assert {"direct", "nufft", "nufft32", "finufft", "psf", "auto"} <= set(ASCAN_METHODS)


def test_stream_matches_whole_scene_and_is_chunk_independent():
    kw = dict(n_pixels=32, depth_range=256.0, k0=3.0, seed=7, tol=1e-9, method="nufft")
    a = stream_ascans(10, 2.0, chunk_lines=3, **kw)
    b = stream_ascans(10, 2.0, chunk_lines=256, **kw)
    np.testing.assert_array_equal(a, b)
    scene = random_scatterers(10, 2.0, n_pixels=32, depth_range=256.0, seed=7)
    ref = ascan(
        scene["z"].values, scene["amplitude"].values, n_pixels=32, depth_range=256.0, k0=3.0
    )
    assert np.linalg.norm(a - ref) <= 1e-9 * np.linalg.norm(ref)


def test_stream_only_requested_lines():
    kw = dict(n_pixels=32, depth_range=256.0, k0=3.0, seed=7, tol=1e-9, method="nufft")
    full = stream_ascans(12, 2.0, chunk_lines=5, **kw)
    part = stream_ascans(12, 2.0, chunk_lines=2, lines=[9, 2, 3, 4, 11], **kw)
    np.testing.assert_array_equal(part, full[[9, 2, 3, 4, 11]])
    with pytest.raises(ValueError, match="lines"):
        stream_ascans(12, 2.0, lines=[12], **kw)
