"""Numba kernels of the strain estimators (private: the one copy of each).

* :func:`vector_phase`: the vector method of :mod:`speckle.analysis.strain` in one pass per
  A-line: the interframe product ``d = A1 A2*``, the four-product ``C_L = d(z) d*(z+L)`` and
  ``|C_L|`` summed over (depth, x) windows (running sums in depth, the window's A-lines
  added in order), the phase of the sum, its quality and the multi-lag branch check. Nothing
  of image size is allocated but the two outputs.
* :func:`box_sums`: the (depth, x) window sums of
  :func:`speckle.analysis._strain_methods._box`,
  bit-identical to its numpy running sums (the same additions in the same order), in the
  input's memory layout.
* :func:`lagrange_resample`: the 8-point Lagrange interpolation of
  :func:`speckle.analysis.correlation.resample_depth` on its oversampled A-lines (and of the
  alignment of :func:`speckle.analysis.estimate_strain` on its tracker's half-pixel samples).

The kernels are serial (one core per pair): a sequence runs pairs in parallel on Dask, and the
numbers do not depend on threads. Float64 throughout, no ``fastmath`` (the order of every sum
is the order written).
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = [
    "LAGRANGE_TAPS",
    "MARGIN",
    "atan2",
    "atan2_array",
    "box_sums",
    "lag_sums",
    "lagrange_resample",
    "refine_shifts",
    "vector_phase",
    "window_moments",
]

# Cephes ``atan`` (S. Moshier): ``atan(x) = x + x z P(z)/Q(z)``, ``z = x^2``, for |x| <= 0.66
_P = (
    -8.750608600031904122785e-1,
    -1.615753718733365076637e1,
    -7.500855792314704667340e1,
    -1.228866684490136173410e2,
    -6.485021904942025371773e1,
)
_Q = (
    2.485846490142306297962e1,
    1.650270098316988542046e2,
    4.328810604912902668951e2,
    4.853903996359136964868e2,
    1.945506571482613964425e2,
)
#: pi/2 - float(pi/2): the bits of pi/2 below double precision
_MOREBITS = 6.123233995736765886130e-17


@numba.njit(inline="always")
def _atan01(t):
    """``atan(t)`` for ``0 <= t <= 1`` (Cephes reduction at 0.66: ``pi/4 + atan((t-1)/(t+1))``)."""
    if t > 0.66:
        x = (t - 1.0) / (t + 1.0)
        y = 0.25 * math.pi
        extra = 0.5 * _MOREBITS
    else:
        x = t
        y = 0.0
        extra = 0.0
    z = x * x
    num = (((_P[0] * z + _P[1]) * z + _P[2]) * z + _P[3]) * z + _P[4]
    den = ((((z + _Q[0]) * z + _Q[1]) * z + _Q[2]) * z + _Q[3]) * z + _Q[4]
    return y + (x + x * (z * num / den) + extra)


@numba.njit(inline="always")
def atan2(y, x):
    """``math.atan2`` to 2 ulp, three times faster (libm's is the vector method's largest
    cost): the Cephes polynomial on ``min/max`` of ``|x|``, ``|y|``, then the octant."""
    ax = abs(x)
    ay = abs(y)
    if ay > ax:
        r = 0.5 * math.pi - _atan01(ax / ay) + _MOREBITS
    elif ax > 0.0:
        r = _atan01(ay / ax)
    else:  # both zero: libm's signed-zero conventions
        return math.atan2(y, x)
    if x < 0.0:
        r = math.pi - r
    return math.copysign(r, y)


@numba.njit(cache=True)
def atan2_array(y, x, out):
    """:func:`atan2` elementwise (1-D arrays), for testing it against ``numpy.arctan2``."""
    for i in range(y.size):
        out[i] = atan2(y[i], x[i])


#: Margin of the branch pre-test of :func:`vector_phase`: the lag-1 predictor is evaluated only
#: where ``|phase| > MARGIN pi/2`` or ``|arg S1| > MARGIN pi/(2 c)``; elsewhere
#: ``|c arg S1 - phase| <= MARGIN pi < pi`` and the branch is 0 whatever the rounding.
MARGIN = 0.9


@numba.njit(cache=True, error_model="numpy")
def vector_phase(a1, a2, lag, wz, wx, denom, cfac, tan0, min_q, wrap, strain, quality):
    """Vector-method strain and quality of every window, written into ``strain``/``quality``.

    ``a1``, ``a2``: complex (depth, x) images (read depth-first: fastest when depth is the
    contiguous axis). Output row ``r``, column ``c`` holds the window of ``C_L`` rows
    ``[r - wz//2 - lag//2, ... + wz)`` and A-lines ``[c - wx//2, ... + wx)``; the outputs
    (prefilled with NaN by the caller) are left untouched where the window leaves the image.
    ``strain = -phase/denom`` where ``quality >= min_q`` (else NaN). With ``wrap``, the phase
    is moved to the ``2 pi`` branch nearest ``cfac * arg(S_1)`` (lag-1 sum over the lag-L
    window's rows shifted by ``lag//2``), evaluated where the branch can be non-zero
    (``tan0 = tan(MARGIN pi/(2 cfac))``).
    """
    n, m = a1.shape
    nl = n - lag - wz + 1
    if nl <= 0 or m < wx:
        return
    rl = wz // 2 + lag // 2
    h = lag // 2
    coll_r = np.empty((wx, nl))
    coll_i = np.empty((wx, nl))
    cola = np.empty((wx, nl))
    col1_r = np.empty((wx, nl))
    col1_i = np.empty((wx, nl))
    dr = np.empty(n)
    di = np.empty(n)
    e = np.empty(n)
    pr = np.empty(n + 1)
    pi_ = np.empty(n + 1)
    pa = np.empty(n + 1)
    two_pi = 2.0 * math.pi
    half = MARGIN * 0.5 * math.pi
    for j in range(m):
        for z in range(n):
            x = a1[z, j]
            y = a2[z, j]
            re = x.real * y.real + x.imag * y.imag
            im = x.imag * y.real - x.real * y.imag
            dr[z] = re
            di[z] = im
            e[z] = math.sqrt(re * re + im * im)
        slot = j % wx
        pr[0] = 0.0
        pi_[0] = 0.0
        pa[0] = 0.0
        for i in range(n - lag):  # running sums of d(i) d*(i+L) and |d(i)| |d(i+L)|
            pr[i + 1] = pr[i] + (dr[i] * dr[i + lag] + di[i] * di[i + lag])
            pi_[i + 1] = pi_[i] + (di[i] * dr[i + lag] - dr[i] * di[i + lag])
            pa[i + 1] = pa[i] + e[i] * e[i + lag]
        for i in range(nl):
            coll_r[slot, i] = pr[i + wz] - pr[i]
            coll_i[slot, i] = pi_[i + wz] - pi_[i]
            cola[slot, i] = pa[i + wz] - pa[i]
        if wrap:
            pr[0] = 0.0
            pi_[0] = 0.0
            for i in range(n - 1):
                pr[i + 1] = pr[i] + (dr[i] * dr[i + 1] + di[i] * di[i + 1])
                pi_[i + 1] = pi_[i] + (di[i] * dr[i + 1] - dr[i] * di[i + 1])
            for i in range(nl):
                col1_r[slot, i] = pr[i + h + wz] - pr[i + h]
                col1_i[slot, i] = pi_[i + h + wz] - pi_[i + h]
        if j < wx - 1:
            continue
        c = j - wx + 1 + wx // 2
        for i in range(nl):
            sr = 0.0
            si = 0.0
            sa = 0.0
            for k in range(wx):  # the window's A-lines in order
                s = (j - wx + 1 + k) % wx
                sr += coll_r[s, i]
                si += coll_i[s, i]
                sa += cola[s, i]
            q = math.sqrt(sr * sr + si * si) / sa
            ph = atan2(si, sr)
            if wrap:
                s1r = 0.0
                s1i = 0.0
                for k in range(wx):
                    s = (j - wx + 1 + k) % wx
                    s1r += col1_r[s, i]
                    s1i += col1_i[s, i]
                if abs(ph) > half or abs(s1i) > tan0 * s1r:
                    pred = cfac * atan2(s1i, s1r)
                    ph = ph + two_pi * np.round((pred - ph) / two_pi)
            quality[rl + i, c] = q
            strain[rl + i, c] = -ph / denom if q >= min_q else np.nan


@numba.njit(cache=True)
def box_sums(x, wz, wx, depth_major, target):
    """Window sums of ``x`` (depth, x) over ``wz`` rows and ``wx`` columns into ``target``.

    ``target[i, j] = sum x[i : i + wz, j : j + wx]`` for ``i < n - wz + 1``, ``j < m - wx + 1``,
    formed as numpy's running sums are: ``c = [0, cumsum(x, axis=0)]``, ``d = c[wz:] - c[:-wz]``,
    then along aline the same for ``wx > 3`` and ``((d_0 + d_1) + d_2)`` for ``wx <= 3``.
    ``depth_major``: walk each A-line in turn (a depth-contiguous ``x``), else row by row.
    """
    n, m = x.shape
    rows = n - wz + 1
    k = m - wx + 1
    if depth_major:  # every temporary A-line by A-line: d[j, i], run[j, i]
        d = np.empty((m, rows), dtype=x.dtype)
        col = np.empty(n + 1, dtype=x.dtype)
        for j in range(m):
            col[0] = 0
            col[1] = x[0, j]
            for i in range(1, n):
                col[i + 1] = col[i] + x[i, j]
            for i in range(rows):
                d[j, i] = col[i + wz] - col[i]
        if wx <= 3:
            for j in range(k):
                for i in range(rows):
                    acc = d[j, i]
                    for t in range(1, wx):
                        acc = acc + d[j + t, i]
                    target[i, j] = acc
        else:
            run = np.empty((m, rows), dtype=x.dtype)
            run[0] = d[0]
            for j in range(1, m):
                for i in range(rows):
                    run[j, i] = run[j - 1, i] + d[j, i]
            for i in range(rows):
                target[i, 0] = run[wx - 1, i]
            for j in range(1, k):
                for i in range(rows):
                    target[i, j] = run[wx - 1 + j, i] - run[j - 1, i]
        return
    c = np.empty((n + 1, m), dtype=x.dtype)
    for j in range(m):
        c[0, j] = 0
        c[1, j] = x[0, j]
    for i in range(1, n):
        for j in range(m):
            c[i + 1, j] = c[i, j] + x[i, j]
    if wx <= 3:
        for i in range(rows):
            for j in range(k):
                acc = c[i + wz, j] - c[i, j]
                for t in range(1, wx):
                    acc = acc + (c[i + wz, j + t] - c[i, j + t])
                target[i, j] = acc
    else:
        run = np.empty(m, dtype=x.dtype)
        for i in range(rows):
            run[0] = c[i + wz, 0] - c[i, 0]
            for j in range(1, m):
                run[j] = run[j - 1] + (c[i + wz, j] - c[i, j])
            target[i, 0] = run[wx - 1]
            for j in range(1, k):
                target[i, j] = run[wx - 1 + j] - run[j - 1]


@numba.njit(cache=True)
def lag_sums(a, lag_lo, lag_hi, power):
    """``sum_z A(z) A*(z+L)`` over every A-line of the (depth, x) image ``a`` for
    ``L = lag_lo ... lag_hi - 1``; with ``power`` (length depth, or empty), ``|A|^2`` summed
    per depth row is written into it on the way."""
    n, m = a.shape
    out = np.zeros(lag_hi - lag_lo, np.complex128)
    want_power = power.size == n
    if want_power:
        power[:] = 0.0
    for j in range(m):
        for k in range(lag_hi - lag_lo):
            lag = lag_lo + k
            sr = 0.0
            si = 0.0
            for z in range(n - lag):
                x = a[z, j]
                y = a[z + lag, j]
                sr += x.real * y.real + x.imag * y.imag
                si += x.imag * y.real - x.real * y.imag
            out[k] += complex(sr, si)
        if want_power:
            for z in range(n):
                x = a[z, j]
                power[z] += x.real * x.real + x.imag * x.imag
    return out


#: Points of the Lagrange polynomial of :func:`lagrange_resample`.
LAGRANGE_TAPS = 8


@numba.njit(cache=True)
def lagrange_resample(fine, y, factor, out):
    """``out[j, q]`` = A-line ``j`` of ``fine`` (shape (aline, factor * depth): ``factor``
    samples per pixel, periodic in depth) at depth ``y[j, q]`` pixels, by the Lagrange
    polynomial through the :data:`LAGRANGE_TAPS` = 8 samples ``floor(y factor) - 3 ... + 4``.

    At fraction ``t`` of a sample the weight of node ``k`` (``k = -3 ... 4``) is
    ``prod_{i != k} (t - i) / prod_{i != k} (k - i)``: products of the distances, pairs first,
    written out (eight weights in scalar registers, twice as fast as the loops over an array).
    """
    m, nf = fine.shape
    n = y.shape[1]
    # 1 / prod_{i != k} (k - i) for the nodes -3 ... 4
    s0, s1, s2, s3 = -1.0 / 5040, 1.0 / 720, -1.0 / 240, 1.0 / 144
    s4, s5, s6, s7 = -1.0 / 144, 1.0 / 240, -1.0 / 720, 1.0 / 5040
    for j in range(m):
        row = fine[j]
        for q in range(n):
            yf = y[j, q] * factor
            if yf < 0.0 or yf >= nf:  # periodic in depth
                yf -= nf * math.floor(yf / nf)
            i0 = math.floor(yf)
            if i0 >= nf:  # yf rounded up to nf
                i0 -= nf
            t = yf - i0
            d0, d1, d2, d3 = t + 3.0, t + 2.0, t + 1.0, t
            d4, d5, d6, d7 = t - 1.0, t - 2.0, t - 3.0, t - 4.0
            p01, p23, p45, p67 = d0 * d1, d2 * d3, d4 * d5, d6 * d7
            lo, hi = p01 * p23, p45 * p67
            w0, w1 = s0 * d1 * p23 * hi, s1 * d0 * p23 * hi
            w2, w3 = s2 * p01 * d3 * hi, s3 * p01 * d2 * hi
            w4, w5 = s4 * lo * d5 * p67, s5 * lo * d4 * p67
            w6, w7 = s6 * lo * p45 * d7, s7 * lo * p45 * d6
            first = i0 - 3
            if first >= 0 and first + 8 <= nf:
                v0, v1, v2, v3 = row[first], row[first + 1], row[first + 2], row[first + 3]
                v4, v5, v6, v7 = row[first + 4], row[first + 5], row[first + 6], row[first + 7]
            else:  # the polynomial reaches across the period
                v0, v1 = row[first % nf], row[(first + 1) % nf]
                v2, v3 = row[(first + 2) % nf], row[(first + 3) % nf]
                v4, v5 = row[(first + 4) % nf], row[(first + 5) % nf]
                v6, v7 = row[(first + 6) % nf], row[(first + 7) % nf]
            re = w0 * v0.real + w1 * v1.real + w2 * v2.real + w3 * v3.real
            re += w4 * v4.real + w5 * v5.real + w6 * v6.real + w7 * v7.real
            im = w0 * v0.imag + w1 * v1.imag + w2 * v2.imag + w3 * v3.imag
            im += w4 * v4.imag + w5 * v5.imag + w6 * v6.imag + w7 * v7.imag
            out[j, q] = complex(re, im)


@numba.njit(cache=True)
def window_moments(h, nx, nz, mx, mz, sx, sz, s1, s2):
    """Sums of ``h`` and ``h^2`` (float64) over the windows ``h[i sx : i sx + mx,
    k sz : k sz + mz]`` of a real (aline, depth) image, into ``s1``, ``s2`` of shape (nx, nz)."""
    m, n = h.shape
    c1 = np.empty((m, nz))
    c2 = np.empty((m, nz))
    p1 = np.empty(n + 1)
    p2 = np.empty(n + 1)
    for j in range(m):
        p1[0] = 0.0
        p2[0] = 0.0
        for z in range(n):
            v = np.float64(h[j, z])
            p1[z + 1] = p1[z] + v
            p2[z + 1] = p2[z] + v * v
        for k in range(nz):
            c1[j, k] = p1[k * sz + mz] - p1[k * sz]
            c2[j, k] = p2[k * sz + mz] - p2[k * sz]
    for i in range(nx):
        for k in range(nz):
            a = 0.0
            b = 0.0
            for j in range(i * sx, i * sx + mx):
                a += c1[j, k]
                b += c2[j, k]
            s1[i, k] = a
            s2[i, k] = b


@numba.njit(cache=True)
def _phasors(f, shift, size, powers, out):
    """``out[k] = exp(2i pi f[k] shift/size)`` for integer frequencies ``f`` (FFT order: any
    signs, ``|f| < powers.size``), from the powers of one phasor written to the workspace
    ``powers`` (two trigonometric calls instead of two per frequency; the powers' rounding grows
    as 1e-16 per step, 3e-15 at the 32nd)."""
    ang = 2.0 * math.pi * shift / size
    unit = complex(math.cos(ang), math.sin(ang))
    powers[0] = 1.0
    for j in range(1, powers.size):
        powers[j] = powers[j - 1] * unit
    for k in range(f.size):
        j = int(f[k])
        out[k] = powers[j] if j >= 0 else powers[-j].conjugate()


@numba.njit(cache=True)
def _powers_for(f):
    """The workspace of :func:`_phasors` for the frequencies ``f``: ``max |f| + 1`` entries."""
    top = 0
    for k in range(f.size):
        top = max(top, abs(int(f[k])))
    return np.empty(top + 1, np.complex128)


@numba.njit(cache=True)
def _refine_line(q, f, shift, size, up, table_re, table_im, powers):
    """Best offset on the ``1/up`` grid around ``shift`` of ``Re sum_f q_f exp(2i pi f s/size)``
    and its value; ``table[f, u] = exp(2i pi f (u - centre)/(up size))``; ``powers``: the
    workspace of :func:`_phasors` for ``f``."""
    region = table_re.shape[1]
    centre = region // 2
    base = np.round(shift * up) / up
    nf = q.size
    qb = np.empty(nf, np.complex128)
    _phasors(f, base, size, powers, qb)
    for k in range(nf):
        qb[k] *= q[k]
    acc = np.zeros(region)
    for k in range(nf):  # every offset at once: the table's rows are contiguous in u
        qr, qi = qb[k].real, qb[k].imag
        for u in range(region):
            acc[u] += qr * table_re[k, u] - qi * table_im[k, u]
    best = 0
    best_abs = -1.0
    for u in range(region):
        if abs(acc[u]) > best_abs:
            best_abs = abs(acc[u])
            best = u
    return base + (best - centre) / up, acc[best]


@numba.njit(cache=True)
def refine_shifts(p, mult, fz, fx, mz, mx, up, lateral, tz_re, tz_im, tx_re, tx_im, sz, sx, val):
    """Sub-sample refinement of every window's whole-sample peak (``sz``, ``sx``: depth and
    aline samples, overwritten with the refined offsets; ``val``: the CC there).

    ``p``: cross-power spectra (W, depth half frequencies ``fz``, aline frequencies ``fx``);
    ``mult``: multiplicity of each depth frequency (2, or 1 for 0 and Nyquist), so that
    ``CC(s) = Re sum mult p exp(2i pi (fz sz/mz + fx sx/mx))``. Depth at the whole-pixel aline
    offset; with ``lateral`` and ``mx > 1`` then aline at that depth, then depth again (the
    upsampled DFT of Guizar-Sicairos et al. 2008, one window at a time); ``t*``: the tables of
    :func:`_refine_line` for depth and aline.
    """
    w_count, nfz, nfx = p.shape
    qz = np.empty(nfz, np.complex128)
    pow_z, pow_x = _powers_for(fz), _powers_for(fx)  # phasor workspaces, shared by every window
    qx = np.empty(nfx, np.complex128)
    ex = np.empty(nfx, np.complex128)
    ez = np.empty(nfz, np.complex128)
    for w in range(w_count):
        z = sz[w]
        x = sx[w]
        steps = 3 if (lateral and mx > 1) else 1
        for step in range(steps):
            if step != 1:  # depth at the aline offset x
                _phasors(fx, x, mx, pow_x, ex)
                for f in range(nfz):
                    acc = 0j
                    for k in range(nfx):
                        acc += ex[k] * p[w, f, k]
                    qz[f] = acc * mult[f]
                z, v = _refine_line(qz, fz, z, mz, up, tz_re, tz_im, pow_z)
            else:  # aline at the depth offset z
                _phasors(fz, z, mz, pow_z, ez)
                for f in range(nfz):
                    ez[f] *= mult[f]
                for k in range(nfx):
                    acc = 0j
                    for f in range(nfz):
                        acc += ez[f] * p[w, f, k]
                    qx[k] = acc
                x, v = _refine_line(qx, fx, x, mx, up, tx_re, tx_im, pow_x)
        sz[w] = z
        sx[w] = x
        val[w] = v
