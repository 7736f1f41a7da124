"""The speckle of a row across a boundary (private): ``E ln(I/<I>)`` of mixed rows, exactly.

A row near a boundary collects the upper layer's scatterers through one side of the depth PSF
and the lower layer's through the other. :class:`~speckle.studies.phantom._shapes.TransitionModel`
mixes the layers' mean intensities exactly; the row's ``E ln(I/<I>)``, which turns its mean
intensity into its mean ``ln I``, was taken as the layers' offsets weighted by their shares of
the mean intensity. That is exact far from the boundary only. A bright sparse layer seen through
the PSF's edge contributes few scatterers of a spread of weights (its speckle sparser than the
layer's own: ``E ln(I/<I>)`` lower), and two comparable populations add to a field nearer the
Gaussian (higher): at the 2025 configuration (601 pixels of 2.2 µm, beam radius 6 µm) the
weighted offset is up to 0.14 neper off in the row at a boundary of contrast 20, and the scanner
agrees with the exact value below to 0.02 (16 draws, ``docs/explanation/phantom_fit.md``).

The exact value is Campbell's theorem with the PSF split at the boundary. Layer ``j`` (Poisson
scatterers of ``k_j`` per µm of ``y`` per pixel per pitch in the slab ``|y| <= r``, amplitudes
``a_j exp(-y^2/r^2) h(u, x)``) on the PSF offsets ``u`` between its edges contributes

    ln Phi_j(t) = k_j int_{-r}^{r} dy int_{u in j} du int dx [J0(t a_j e^{-y^2/r^2} |h|) - 1],

the field's characteristic function is ``Phi = prod_j Phi_j`` and ``E ln(I/<I>) = -gamma -
2 int (Phi - e^{-s2 t^2/4}) d ln t`` (:func:`speckle.analysis._sparse_theory.moments_of`),
``s2`` the row's mean intensity. A layer of fully developed speckle (``k`` infinite) is the
Gaussian ``ln Phi_j = -s2_j t^2/4``. The ``u`` integral is a cumulative sum over the PSF on
1/16 pixel, so the split at any ``v`` is a lookup; the layers' densities come from their full
offsets (the inverse of :func:`~speckle.studies.phantom._density.slab_log_moments`), so a row
far from the boundary gets each layer's offset back. Neglected: the layers' attenuation within
the PSF (its ``e^{s u}`` tilt is in the mean intensity's shares, not in the speckle's
statistics; ``s`` at most 0.3 per pixel) and a third layer within :data:`REACH` pixels (layers
are at least 15 pixels thick in the virtual patients).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import optimize

# private: the sparse-speckle theory's numerical core, shared with analysis.sparse
from ...analysis._sparse_theory import TAU, _lateral
from ...synthoct.files import ScannerConfig
from ._density import slab_log_moments
from ._slab import depth_psf, slab_constants

__all__ = ["REACH", "TAPER", "MixedRows", "mixed_rows"]

#: PSF samples per pixel of the split (the boundary's position within a sample interpolated).
SAMPLES = 16
#: Pixels either side of a boundary where the exact offset is used. The PSF's share of the
#: other layer there is 2e-7, but a sparse row's dark pixels are filled by a much brighter
#: neighbour's faint contribution: at 8 pixels the exact offset still exceeds the weighted one
#: by up to 0.021 neper at 2025 (0.3 times the mean density next to 3 times it, e^7 brighter;
#: 5e-4 at the challenge's configuration), so the transition model blends the two over the
#: last :data:`TAPER` pixels (no step in its misfit).
REACH = 8.0
#: Pixels over which the exact offset blends into the weighted one at :data:`REACH`.
TAPER = 2.0
#: Step of the tabulated ``ln`` intensity ratio of the two layers (linear interpolation: within
#: 3.3e-3 neper of the direct value, measured on four layer pairs, ``x`` -5.1..5.2).
X_STEP = 0.25
#: Every ``TAU_STRIDE``-th point of the theory's ``ln t`` grid (0.032 apart: the
#: characteristic function varies over ~1 in ``ln t``): the offsets agree with the full grid's
#: to 2e-4 neper (every 8th: 1e-3; measured on four layer pairs, |v| <= 3 pixels).
TAU_STRIDE = 4


class MixedRows:
    """``E ln(I/<I>)`` of rows across a boundary (module docstring) for one scanner.

    ``offset(v, x, c_above, c_below)``: ``v`` the boundary's offset below the row (pixels),
    ``x`` the ``ln`` ratio of the lower to the upper layer's mean intensity at the row,
    ``c_above``, ``c_below`` the layers' own ``E ln(I/<I>)`` (:func:`~speckle.studies.phantom.
    _density.log_offsets`). Columns of ``v`` are computed per ``x`` node and layer pair and kept.
    """

    def __init__(self, cfg: ScannerConfig):
        self.cfg = cfg
        r, pitch = cfg.beam_radius, cfg.line_pitch
        u, w = depth_psf(cfg.n_pixels, SAMPLES)
        waist = math.sqrt(2) * r / pitch
        per_area = waist * math.sqrt(math.pi) / 2 / SAMPLES  # int dx of |h|^2, per sample
        self.area = float(np.sum(w) * per_area)  # int |h|^2 (pixels x pitches)
        self.tau = TAU[::TAU_STRIDE]
        ln_t = self.tau - 0.5 * math.log(self.area)
        self.t2 = np.exp(2 * ln_t)
        # g(s) = int_{-r}^{r} lateral(e^{s - y^2/r^2}) dy: a sample's slab exponent at ln t|h| = s
        s = np.linspace(ln_t[0] - 30, ln_t[-1] + 1, 6000)
        nodes, weights = np.polynomial.legendre.leggauss(48)
        y = (nodes + 1) / 2 * r
        g = 2 * np.sum((weights * r / 2)[:, None]
                       * _lateral(np.exp(s[None, :] - (y[:, None] / r) ** 2)), axis=0)  # fmt: skip
        ln_h = 0.5 * np.log(np.maximum(w, 1e-300))
        per = np.interp(ln_t[:, None] + ln_h[None, :], s, g, left=0.0) * waist / SAMPLES
        # cumulative over u at the samples' edges: the upper layer's exponent for v on a grid
        edges = np.concatenate([u - 0.5 / SAMPLES, [u[-1] + 0.5 / SAMPLES]])
        cum = np.concatenate([np.zeros((self.tau.size, 1)), np.cumsum(per, axis=1)], axis=1)
        share = np.concatenate([[0.0], np.cumsum(w)])
        near = np.abs(edges) <= REACH + 1e-9
        self.v = edges[near]  # the boundary's offsets of the table (pixels)
        self._upper = cum[:, near]  # the upper layer's exponent at each v, (tau, v)
        self._lower = cum[:, -1:] - self._upper
        self._share = share[near] / share[-1]  # the upper layer's share of the PSF at each v
        self.a2y = slab_constants(r)["a2_y"]
        self._columns: dict = {}
        self._uppers: dict = {}  # the upper layer's ln Phi per density (:meth:`_column`)
        self._densities: dict = {}

    def density(self, offset: float) -> float:
        """Scatterers per µm of ``y`` per pixel per pitch whose slab ``E ln(I/<I>)`` is
        ``offset`` (infinite at ``-gamma`` and above: fully developed)."""
        key = float(offset)
        if key not in self._densities:
            cfg = self.cfg
            if not key < -np.euler_gamma - 1e-9:
                k = math.inf
            else:

                def gap(ln_rho):
                    return slab_log_moments(math.exp(ln_rho), cfg)[0] - key

                lo, hi = math.log(1e-9), math.log(1e3)
                if gap(lo) > 0:
                    k = math.exp(lo) * cfg.pixel_size * cfg.line_pitch
                elif gap(hi) < 0:
                    k = math.inf
                else:
                    rho = math.exp(optimize.brentq(gap, lo, hi, xtol=1e-10))
                    k = rho * cfg.pixel_size * cfg.line_pitch
            self._densities[key] = k
        return self._densities[key]

    def _term(self, k, lam, intensity, share):
        """``ln Phi`` of one layer's part (``lam``: its unit-amplitude exponent, tau x v)."""
        if not math.isfinite(k):
            return -(intensity * share)[None, :] * self.t2[:, None] / 4
        # amplitude a with k a^2 a2_y area = intensity: lam(t a) is lam shifted by ln a
        step = self.tau[1] - self.tau[0]
        shift = 0.5 * math.log(intensity / (k * self.a2y * self.area)) / step
        i0 = math.floor(shift)
        f = shift - i0
        idx = np.arange(self.tau.size) + i0
        lo = np.clip(idx, 0, self.tau.size - 1)
        hi = np.clip(idx + 1, 0, self.tau.size - 1)
        out = lam[lo] * (1 - f) + lam[hi] * f
        below = idx < 0  # under the grid: lam = -t^2 (its area)/4, from the first point
        if below.any():
            scale = np.exp(2 * step * (idx[below] + f))[:, None]
            out[below] = lam[0][None, :] * scale
        return k * out

    def _column(self, k1, k2, ix):
        """Offsets on :attr:`v` at ``x = ix X_STEP`` for densities ``k1`` (above), ``k2``."""
        key = (k1, k2, ix)
        col = self._columns.get(key)
        if col is None:
            upper, lower, s_up = self._upper, self._lower, self._share
            ratio = math.exp(ix * X_STEP)
            above = self._uppers.get(k1)  # the upper layer's part: the same at every x
            if above is None:
                if len(self._uppers) >= 64:
                    self._uppers.clear()
                above = self._uppers[k1] = self._term(k1, upper, 1.0, s_up)
            ln_phi = above + self._term(k2, lower, ratio, 1 - s_up)
            s2 = s_up + ratio * (1 - s_up)
            dphi = np.exp(ln_phi) - np.exp(-s2[None, :] * self.t2[:, None] / 4)
            col = -np.euler_gamma - 2 * np.trapezoid(dphi, self.tau, axis=0)
            if len(self._columns) >= 4096:
                self._columns.clear()
            self._columns[key] = col
        return col

    def offset(self, v, x, c_above: float, c_below: float) -> np.ndarray:
        """``E ln(I/<I>)`` of rows whose boundary lies ``v`` pixels below them (``|v| <=``
        :data:`REACH`), ``x = ln(<I_below>/<I_above>)`` at the rows (arrays, broadcast)."""
        v, x = np.broadcast_arrays(np.asarray(v, float), np.asarray(x, float))
        return self.offset_at(self.v_index(v), x, c_above, c_below)

    def v_index(self, v) -> tuple[np.ndarray, np.ndarray]:
        """The table's interval and fraction at offsets ``v`` (:meth:`offset_at`): computed once
        for rows whose ``x`` differs (a boundary's blocks at the same trial positions)."""
        iv = np.clip((np.asarray(v, float) - self.v[0]) * SAMPLES, 0, self.v.size - 1 - 1e-9)
        j0 = iv.astype(int)
        return j0, iv - j0

    def offset_at(self, at, x, c_above: float, c_below: float) -> np.ndarray:
        """:meth:`offset` at the offsets ``at = v_index(v)`` (``x`` of their shape)."""
        j0, fv = at
        x = np.asarray(x, float)
        k1, k2 = self.density(c_above), self.density(c_below)
        pos = x / X_STEP
        ix0 = np.floor(pos).astype(int)
        fx = pos - ix0
        if not x.size:
            return np.empty(x.shape)
        low = int(ix0.min())
        used = np.bincount((ix0 - low).ravel()) > 0
        used = np.concatenate([used, [False]]) | np.concatenate([[False], used])
        nodes = np.flatnonzero(used)  # the x nodes used (each node's and the next), - low
        table = np.stack([self._column(k1, k2, int(ix) + low) for ix in nodes]).ravel()
        row = np.cumsum(used) - 1  # each node's column in the table
        a = row[ix0 - low] * self.v.size + j0  # (x node, v) in the table
        b = row[ix0 - low + 1] * self.v.size + j0
        at_a = table[a] * (1 - fv) + table[a + 1] * fv
        at_b = table[b] * (1 - fv) + table[b + 1] * fv
        return at_a * (1 - fx) + at_b * fx


@functools.lru_cache(maxsize=4)
def mixed_rows(cfg: ScannerConfig) -> MixedRows:
    """The :class:`MixedRows` of ``cfg``, built once (~0.1 s) and shared by the fit's passes."""
    return MixedRows(cfg)
