"""The slope of a layer's censored row-mean ``ln I`` (private): ``slope_gains``.

The fit's row means take each clipped pixel (level 0) at ``ln c - 1``. Where every pixel's
``ln I`` moves by ``d`` (the layer's decay from one row to the next), the censored mean moves
by ``g d`` with

    g = 1 - f + p(ln c),

``1 - f`` from the pixels above the clip ``c`` (``f`` of them clipped) and ``p(ln c)``, the
density of ``ln I`` at the clip, from the pixels that cross it (their censored value jumps by
1). For an intensity density flat near 0, ``p(ln c) = f`` to first order and ``g = 1``: fully
developed speckle's is ``exp(-u)(1 + u) = 1 - u^2/2`` (``u = c/<I>``; 0.995 at 10 %
clipped). A sparse layer's empty pixels lie far under the clip and hardly cross it: 2025
patient 4 (``layers=(1, 3)``), a layer of 0.0012 scatterers per µm^3 with 15-19 % of its
pixels clipped and ``p(ln c)`` 0.04-0.05, has ``g = 0.87``; its attenuation read from the
slope as ``-2 mu`` came out 0.00162/µm against 0.00199 (pull -3.7).

``p(ln c)`` is level 1's share of the layer's pixels over its width in ``ln I`` (51/256 dB,
0.0459 neper). The gain is taken only for layers whose clipped count exceeds fully developed
speckle's (:func:`~speckle.studies.phantom._density.clip_rates`); elsewhere it is 1 (within
0.5 % of it above the floor).
"""

from __future__ import annotations

import math

import numpy as np

from ...synthoct import _scan
from ._density import DENSE_CLIP_RATE

#: Level 1's width in ``ln I`` (nepers of intensity).
LEVEL_WIDTH = _scan.DYNAMIC_RANGE / _scan.LEVELS * math.log(10.0) / 10.0


def slope_gains(levels: np.ndarray, segs: list[tuple[int, int]], rates: np.ndarray) -> np.ndarray:
    """Each layer's ``g``: its row-mean ``ln I`` falls as ``-2 g mu`` (module docstring).

    ``levels`` are the fitted rows' 8-bit levels ``(rows, lines)``, ``segs`` each layer's rows
    ``a .. b-1`` and ``rates`` each layer's rate of clipped pixels
    (:func:`~speckle.studies.phantom._density.clip_rates`); ``(K,)``, 1 where the layer clips
    as fully developed speckle does.
    """
    out = np.ones(len(segs))
    for k, (a, b) in enumerate(segs):
        if rates[k] != DENSE_CLIP_RATE:
            rows = levels[a:b]
            out[k] = 1.0 - np.mean(rows == 0) + np.mean(rows == 1) / LEVEL_WIDTH
    return out
