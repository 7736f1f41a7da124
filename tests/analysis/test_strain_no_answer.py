"""estimate_strain's no-answer warning: why, and advice that depends on the method and options.

Each method is driven to no answer the way a user meets it (a 5 % or 20 % compression beyond
the phase methods' range, an unrelated pair, a registration window at its chance level), and
the warning must name only what the call did not use: never the method in use, never
``align=True`` when the pair was aligned (``align=True``, or ``"auto"`` that aligned), never
``align`` for the methods without it.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

import speckle

N, H = 64, 512.0  # pixels, depth range (µm); k0/delta_k = 10: phase range 1/(2R) = 5 %


@functools.cache
def _pair(strain: float, seed: int = 1):
    src = speckle.spectrum(N, H, k0_dk=10)
    scene = speckle.deformable_scene(16, 4.0, n_pixels=N, depth_range=H, seed=seed, strain=strain)
    img = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, strain]), src).field
    return img.isel(strain=0), img.isel(strain=1)


def _message(reference, deformed, method, window, **options) -> str:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = speckle.estimate_strain(reference, deformed, method=method, window=window, **options)
    assert not np.isfinite(out.values).any()
    texts = [str(w.message) for w in caught if "has no answer" in str(w.message)]
    assert len(texts) == 1, [str(w.message) for w in caught]
    msg = texts[0]
    assert msg.startswith(f"estimate_strain(method={method!r}) has no answer at any pixel: ")
    assert f"method={method!r}" not in msg.split(": ", 1)[1]  # never the method in use
    return msg


UNRELATED = (lambda: _pair(0.05)[0], lambda: _pair(0.0, seed=7)[0])
STRAINED = (lambda: _pair(0.05)[0], lambda: _pair(0.05)[1])
CRUSHED = (lambda: _pair(0.2)[0], lambda: _pair(0.2)[1])


@pytest.mark.parametrize(
    ("pair", "method", "window", "options", "present", "absent"),
    [
        # 5 % without alignment: the pair decorrelates; both remedies are new to this call
        (STRAINED, "vector", (16, 4), {"align": False}, ["align=True", "method='tracking'"], []),
        # aligned already (align=True; "auto" aligned): only tracking is left
        (CRUSHED, "vector", (16, 4), {"align": True}, ["method='tracking'"], ["align"]),
        (STRAINED, "wls", (16, 4), {}, ["unwrapping failed", "method='tracking'"], ["align"]),
        (STRAINED, "wls", (16, 4), {"align": False}, ["align=True", "method='tracking'"], []),
        # tracking decorrelated under 5 %: a smaller registration window, no other method
        (STRAINED, "tracking", (16, 4), {}, ["smaller track_window than 32"], ["align"]),
        # tracking at its chance level (one line wide): a larger registration window
        (UNRELATED, "tracking", (16, 1), {}, ["chance level", "larger track_window"], ["align"]),
        (UNRELATED, "correlation", (32, 8), {}, ["method='tracking'"], ["align"]),
    ],
)
def test_each_method_suggests_only_what_it_did_not_use(
    pair, method, window, options, present, absent
):
    msg = _message(pair[0](), pair[1](), method, window, **options)
    for text in present:
        assert text in msg, msg
    for text in absent:
        assert text not in msg, msg
