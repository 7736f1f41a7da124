"""The spectrometer chain: each step against its analytic result, the ideal chain against Eq. 4."""

import numpy as np
import pytest

import speckle
from speckle.system import spectrometer as sp

LN2 = np.log(2)
EPS = np.finfo(float).eps


def grid_of(src):
    return src.wavenumber.values, src.attrs["k0"]


def ideal_chain(z, a, src):
    k, k0 = grid_of(src)
    sig = sp.interferogram(z, a, k, src.values, k0=k0)
    return sp.process_interferogram(sig, grid=k, k0=k0)


@pytest.mark.parametrize(
    "spectrum",
    [
        dict(shape="rectangular"),
        dict(shape="gaussian", fwhm=0.3 * 64 * np.pi / 320.0),
        dict(shape="array", weights=np.random.default_rng(3).uniform(0, 1, 64)),
    ],
)
@pytest.mark.parametrize("k0_dk", [0.0, 1.0, 10.0])
def test_ideal_chain_is_eq4(spectrum, k0_dk):
    """Linear-k sampling, delta pixels, complex detection, no DC, no window == speckle.ascan."""
    n, h = 64, 320.0
    src = speckle.spectrum(n, h, k0_dk=k0_dk, **spectrum)
    rng = np.random.default_rng(7)
    z = rng.uniform(-h, 3 * h, (3, 2, 40))  # depths beyond H and before the zero delay
    a = rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)
    got = ideal_chain(z, a, src)
    ref = speckle.ascan(z, a, n_pixels=n, depth_range=h, k0=src.attrs["k0"], spectrum=src.values)
    assert got.shape == ref.shape == (3, 2, n)
    # rounding: phases 2 k z up to |2 k_max z_max| carry relative errors ~eps each
    phase_max = 2 * src.wavenumber.values.max() * 3 * h
    bound = 8 * EPS * max(phase_max, 1.0) * np.sqrt(40 * n)
    assert np.max(np.abs(got - ref)) / np.max(np.abs(ref)) < bound


def test_system_ideal_chain_is_eq4():
    s = speckle.example_system("840nm", camera_pixels=256)
    rng = np.random.default_rng(1)
    z = rng.uniform(0, s.depth_range, (4, 30))
    a = np.exp(2j * np.pi * rng.uniform(size=z.shape))
    got = speckle.system_ascan(
        s, z, a, sampling="wavenumber", pixel_width=False, resolution=False,
        detection="complex", resample="none",
    )  # fmt: skip
    src = s.spectrum()
    ref = speckle.ascan(z, a, n_pixels=256, depth_range=s.depth_range, k0=s.k0, spectrum=src.values)
    bound = 8 * EPS * 2 * src.wavenumber.values.max() * s.depth_range * np.sqrt(30 * 256)
    assert np.max(np.abs(got - ref)) / np.max(np.abs(ref)) < bound


def test_pixel_and_line_average_equal_quadrature():
    """The closed-form camera pixel (box) and spectrometer line (Gaussian) averages of the cross
    and autocorrelation terms equal direct numerical averages of the delta-pixel signal."""
    rng = np.random.default_rng(2)
    z = np.array([[35.0, 80.3, 81.0, 140.7]])
    a = rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)
    k = np.linspace(9.0, 10.0, 7)
    s = rng.uniform(0.5, 1.0, k.size)
    w, r = 0.02, 0.015
    x, wx = np.polynomial.legendre.leggauss(40)  # box: k + w x/2
    y, wy = np.polynomial.hermite_e.hermegauss(40)  # Gaussian: k + sigma y
    sigma = r / (2 * np.sqrt(2 * LN2))
    kk = k[:, None, None] + w * x[None, :, None] / 2 + sigma * y[None, None, :]
    weight = (wx[:, None] / 2) * (wy[None, :] / np.sqrt(2 * np.pi))
    field = np.einsum("j,jikl->ikl", a[0], np.exp(2j * kk[None] * z[0][:, None, None, None]))
    kw = dict(pixel_width=w, resolution=r, detection="real", dc=True, autocorrelation=True)
    got = sp.interferogram(z, a, k, s, reference_power=2.0, **kw)[0]
    expected = s * (2.0 + np.sum(weight * (2 * np.sqrt(2.0) * field.real + np.abs(field) ** 2),
                                 axis=(1, 2)))  # fmt: skip
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_rolloff_through_the_chain_is_closed_form():
    """k-linear camera with finite pixels and spectrometer line: a reflector at a pixel centre
    gives |A(q)| / sum S = sinc(w z) exp(-(r z)^2/(4 ln2)) exactly."""
    s = speckle.example_system("840nm", camera_pixels=512, fill_factor=0.8)
    q = np.arange(0, 256, 16)
    z = (q * s.pixel_size)[:, None]
    img = speckle.system_ascan(
        s, z, np.ones_like(z), sampling="wavenumber", detection="complex", resample="none"
    )
    peak = np.abs(img[np.arange(q.size), q]) / sp.source_weights(s, sp.grid_wavenumbers(s)).sum()
    measured_db = 20 * np.log10(peak)
    w = s.fill_factor * s.wavenumber_step
    np.testing.assert_allclose(
        measured_db, 10 * np.log10(sp.rolloff_power(z[:, 0], w, s.resolution_k)), atol=1e-9
    )


def test_rolloff_wavelength_camera_within_pixel_width_spread():
    """A wavelength-linear camera (exact linearisation): pixel widths vary across the spectrum,
    so the peak is the S-weighted mean of the per-pixel responses, between their extremes."""
    s = speckle.example_system("840nm", camera_pixels=512)
    q = np.array([32, 96, 160, 224])
    z = (q * s.pixel_size)[:, None]
    img = speckle.system_ascan(s, z, np.ones_like(z), detection="complex", resample="exact")
    grid = sp.grid_wavenumbers(s)
    weights = sp.source_weights(s, grid)
    peak = np.abs(img[np.arange(q.size), q]) / weights.sum()
    cam = sp.camera_sampling(s, "wavelength", at=grid)
    g = sp.carrier_response(z, cam["pixel_width"], cam["resolution"])  # (depth, n)
    np.testing.assert_allclose(peak, g @ weights / weights.sum(), rtol=1e-10)
    central = np.sqrt(s.rolloff(z[:, 0]))
    assert np.all((peak >= g.min(axis=1)) & (peak <= g.max(axis=1)))
    assert np.max(np.abs(20 * np.log10(peak / central))) < 0.5  # dB, vs the central-pixel curve


@pytest.mark.parametrize("b", [0.5, 1.0, 3.0])
def test_second_order_dispersion_broadens_as_gaussian_pulse(b):
    """Gaussian spectrum, phase c2 (k - k0)^2: the intensity PSF's rms width grows by
    sqrt(1 + b^2), b = c2 Dk^2/(4 ln2) (= 4 ln2 c2/dz^2 with dz = 4 ln2/Dk)."""
    n, h = 1024, 2048.0
    fwhm = 0.1 * n * np.pi / h
    src = speckle.spectrum(n, h, k0_dk=8.0, shape="gaussian", fwhm=fwhm)
    k, k0 = grid_of(src)
    c2 = b * 4 * LN2 / fwhm**2
    z = np.array([[n // 2 * h / n]])

    def rms_width(disp):
        img = sp.process_interferogram(sp.interferogram(z, np.ones((1, 1)), k, src.values, k0=k0,
                                          dispersion=disp), grid=k, k0=k0)[0]  # fmt: skip
        p = np.abs(img) ** 2
        u = np.arange(n) - n // 2
        mean = np.sum(u * p) / p.sum()
        return np.sqrt(np.sum((u - mean) ** 2 * p) / p.sum())

    w0, w1 = rms_width(None), rms_width({2: c2})
    assert w0 == pytest.approx(np.sqrt(1 / (8 * (fwhm / (2 * np.sqrt(2 * LN2))) ** 2)) * n / h,
                               rel=1e-9)  # fmt: skip
    assert w1 / w0 == pytest.approx(np.sqrt(1 + b**2), rel=1e-9)


def test_dispersion_compensation_restores_eq4():
    n, h = 256, 1024.0
    src = speckle.spectrum(n, h, k0_dk=10.0, shape="gaussian", fwhm=0.3 * n * np.pi / h)
    k, k0 = grid_of(src)
    rng = np.random.default_rng(5)
    z = rng.uniform(0, h, (2, 50))
    a = rng.normal(size=z.shape) + 0j
    disp = {2: 300.0, 3: -2000.0}
    sig = sp.interferogram(z, a, k, src.values, k0=k0, dispersion=disp)
    ref = speckle.ascan(z, a, n_pixels=n, depth_range=h, k0=k0, spectrum=src.values)
    bad = sp.process_interferogram(sig, grid=k, k0=k0)
    good = sp.process_interferogram(sig, grid=k, k0=k0, dispersion=disp)
    assert np.max(np.abs(bad - ref)) / np.max(np.abs(ref)) > 0.1
    assert np.max(np.abs(good - ref)) / np.max(np.abs(ref)) < 1e-11


@pytest.mark.parametrize("window", ["none", "hann", "gaussian"])
def test_apodization_sets_axial_speckle_correlation(window):
    """Pearson correlation of intensity at depth lags 1-3 px equals the Campbell/Siegert
    prediction from the window-weighted spectrum (Poisson scatterers, equal amplitudes)."""
    n, h, rho, lines = 128, 512.0, 2.0, 600
    src = speckle.spectrum(n, h, k0_dk=10.0)
    k, k0 = grid_of(src)
    rng = np.random.default_rng(11)
    counts = rng.poisson(rho * n, lines)
    z = rng.uniform(0, h, (lines, counts.max()))
    a = (np.arange(counts.max()) < counts[:, None]).astype(complex)
    sig = sp.interferogram(z, a, k, src.values, k0=k0)
    img = sp.process_interferogram(sig, grid=k, k0=k0, apodization=window)
    intensity = np.abs(img) ** 2
    lags = np.array([1, 2, 3])
    theory = sp.axial_intensity_correlation(
        src.values * sp.spectral_apodization(n, window), lags, rho
    )
    blocks = intensity.reshape(20, -1, n)

    def pearson(x, lag):
        y = np.roll(x, -lag, axis=-1)
        return np.corrcoef(x.ravel(), y.ravel())[0, 1]

    for lag, th in zip(lags, theory, strict=True):
        est = pearson(intensity, lag)
        per_block = np.array([pearson(b, lag) for b in blocks])
        se = per_block.std(ddof=1) / np.sqrt(len(blocks))
        assert abs(est - th) < 4 * se, (window, lag, est, th, se)
    if window == "hann":  # the window visibly widens the speckle grain
        none = sp.axial_intensity_correlation(src.values, lags, rho)
        assert theory[0] > none[0] + 0.3


def test_axial_correlation_dense_limit_is_siegert():
    """rho -> inf: |gamma|^2 with gamma the normalised Fourier transform of |u|^2."""
    u = speckle.spectrum(64, 64.0, k0_dk=5.0).values * sp.spectral_apodization(64, "hann")
    lags = np.array([0.0, 0.5, 1.0, 2.5])
    n = np.arange(64) - 32
    gamma = (u**2 @ np.exp(-2j * np.pi * np.outer(n, lags) / 64)) / np.sum(u**2)
    np.testing.assert_allclose(
        sp.axial_intensity_correlation(u, lags, 1e9), np.abs(gamma) ** 2, atol=1e-8
    )


@pytest.mark.parametrize("method", ["linear", "cubic"])
def test_resampling_error_grows_as_kernel_predicts(method):
    """Wavelength-linear camera, k-linearised by interpolation: the relative error against exact
    linearisation follows the kernel's tone response at theta = 2 z h (h the local camera step):
    z^2 growth for linear, z^4 for cubic. Tolerance 10 %: the prediction averages over uniformly
    spread fractional positions, the grids' actual ones are only roughly uniform."""
    s = speckle.example_system("840nm", camera_pixels=1024)
    grid = sp.grid_wavenumbers(s)
    cam = sp.camera_sampling(s, "wavelength")["wavenumber"]
    h_local = np.interp(grid, cam[:-1] + np.diff(cam) / 2, np.diff(cam))
    weights = sp.source_weights(s, grid)
    kw = dict(pixel_width=False, resolution=False, detection="complex")
    errors, predictions = [], []
    for frac in (1 / 64, 1 / 32, 1 / 16, 1 / 8):
        z = np.array([[frac * s.depth_range]])
        exact = speckle.system_ascan(s, z, np.ones((1, 1)), resample="exact", **kw)
        approx = speckle.system_ascan(s, z, np.ones((1, 1)), resample=method, **kw)
        measured = np.linalg.norm(approx - exact) / np.linalg.norm(exact)
        e = sp.resampling_error(2 * z[0, 0] * h_local, method)
        predicted = np.sqrt(np.sum(weights**2 * e**2) / np.sum(weights**2))
        assert measured == pytest.approx(predicted, rel=0.1)
        errors.append(measured)
        predictions.append(predicted)
    growth = np.array(errors[1:]) / errors[:-1]
    predicted_growth = np.array(predictions[1:]) / predictions[:-1]
    np.testing.assert_allclose(growth, predicted_growth, rtol=0.1)
    assert np.all(growth > (3.9 if method == "linear" else 15.0))  # ~z^2 and ~z^4 (x2 depth)


def test_resampling_error_small_theta_limit():
    th = np.array([1e-3, 2e-3])
    np.testing.assert_allclose(
        sp.resampling_error(th, "linear"), th**2 / (2 * np.sqrt(30)), rtol=1e-2
    )


def test_real_detection_dc_autocorrelation_mirror():
    """Real camera: DC at zero delay, the mirror image at -z, the autocorrelation peak at the
    reflectors' separation; background subtraction removes the DC."""
    n, h = 128, 256.0
    src = speckle.spectrum(n, h, k0_dk=10.0)
    k, k0 = grid_of(src)
    px = h / n
    z = np.array([[40 * px, 52 * px]] * 2)  # two A-lines, reflectors 12 px apart
    a = np.array([[0.5, 0.25]] * 2, dtype=complex)
    sig = sp.interferogram(
        z, a, k, src.values, k0=k0, detection="real", dc=True, autocorrelation=True,
        reference_power=4.0,
    )  # fmt: skip
    assert np.isrealobj(sig)
    img = sp.process_interferogram(sig, grid=k, k0=k0)[0]
    total = src.values.sum()  # = N
    assert abs(img[0]) == pytest.approx(total * (4.0 + 0.5**2 + 0.25**2), rel=1e-12)
    for q, amp in ((40, 0.5), (52, 0.25)):
        assert abs(img[q]) == pytest.approx(2.0 * amp * total, rel=1e-12)  # sqrt(P_r) a N
        assert abs(img[n - q]) == pytest.approx(2.0 * amp * total, rel=1e-12)  # mirror
    assert abs(img[12]) == pytest.approx(0.5 * 0.25 * total, rel=1e-12)  # autocorrelation
    rest = np.delete(np.abs(img), [0, 12, n - 12, 40, 52, n - 40, n - 52])
    assert rest.max() < 1e-9 * total
    clean = sp.process_interferogram(sig, grid=k, k0=k0, background="mean")[0]
    assert abs(clean[0]) < 1e-9 * total and abs(clean[12]) < 1e-9 * total  # identical lines
    dc_only = sp.process_interferogram(sig, grid=k, k0=k0, background=4.0 * src.values)[0]
    assert abs(dc_only[0]) == pytest.approx(total * (0.5**2 + 0.25**2), rel=1e-12)


def test_spectral_apodizations():
    np.testing.assert_allclose(
        sp.spectral_apodization(8, "hann"), np.cos(np.pi * np.arange(-4, 4) / 8) ** 2
    )
    g = sp.spectral_apodization(100, "gaussian", 0.2)
    assert g[50] == 1.0 and g[50 + 10] == pytest.approx(0.5, rel=1e-12)  # FWHM 0.2 N = 20
    assert np.all(sp.spectral_apodization(16) == 1)


def test_bad_inputs():
    src = speckle.spectrum(16, 32.0, k0_dk=4.0)
    k, k0 = grid_of(src)
    z, a = np.zeros((1, 1)), np.ones((1, 1))
    with pytest.raises(ValueError, match="dispersion order must be an integer in \\[2"):
        sp.interferogram(z, a, k, src.values, dispersion={-2: 1.0})
    with pytest.raises(ValueError, match="dispersion order"):
        sp.process_interferogram(np.ones(16), grid=k, k0=k0, dispersion={1: 1.0})
    with pytest.raises(ValueError, match="apodization must be one of"):
        sp.process_interferogram(np.ones(16), grid=k, k0=k0, apodization="hamming")
    with pytest.raises(ValueError, match="resample must be one of"):
        sp.process_interferogram(np.ones(16), grid=k, k0=k0, resample="sinc")
    with pytest.raises(ValueError, match="detection must be one of"):
        sp.interferogram(z, a, k, src.values, detection="balanced")
    with pytest.raises(ValueError, match="spectrum must have the shape"):
        sp.interferogram(z, a, k, src.values[:-1])
    with pytest.raises(ValueError, match="z and amplitude must have the same shape"):
        sp.interferogram(z, np.ones((1, 2)), k, src.values)
    with pytest.raises(ValueError, match="resample='none' needs the signal on the grid"):
        sp.process_interferogram(np.ones(15), grid=k, k0=k0)
    with pytest.raises(ValueError, match="no extrapolation"):
        sp.process_interferogram(np.ones(16), grid=k * 1.01, k0=k0, wavenumber=k, resample="linear")
    with pytest.raises(ValueError, match="needs wavenumber"):
        sp.process_interferogram(np.ones(16), grid=k, k0=k0, resample="cubic")
    with pytest.raises(ValueError, match="background must have shape"):
        sp.process_interferogram(np.ones((2, 16)), grid=k, k0=k0, background=np.ones(8))
    with pytest.raises(ValueError, match="at least 2 A-lines"):
        sp.process_interferogram(np.ones(16), grid=k, k0=k0, background="mean")
    with pytest.raises(ValueError, match="at least 2 A-lines"):
        sp.process_interferogram(np.ones((1, 16)), grid=k, k0=k0, background="mean")
    with pytest.raises(TypeError, match="dispersion must be a mapping"):
        sp.dispersion_phase(k, k0, [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="sampling must be one of"):
        sp.camera_sampling(speckle.example_system("840nm"), "time")


@pytest.mark.parametrize("tol", [1e-4, 1e-8, 1e-12])
def test_finufft_camera_within_tol(tol):
    """Type-3 FINUFFT camera (uniform pixel response) vs the direct sum: error <= tol."""
    rng = np.random.default_rng(int(-np.log10(tol)))
    for _ in range(4):
        n, h = int(rng.integers(8, 300)), float(rng.uniform(50, 3000))
        w = rng.uniform(0, 1, n)
        src = speckle.spectrum(n, h, k0_dk=float(rng.uniform(0, 20)), shape="array", weights=w)
        k = src.wavenumber.values
        z = rng.uniform(-h, 3 * h, (3, int(rng.integers(1, 400))))
        a = rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)
        resp = dict(pixel_width=float(rng.uniform(0, np.pi / h)),
                    resolution=float(rng.uniform(0, np.pi / h)))  # fmt: skip
        direct = sp.interferogram(z, a, k, src.values, **resp)
        fast = sp.interferogram(z, a, k, src.values, method="finufft", tol=tol, **resp)
        assert np.linalg.norm(fast - direct) <= tol * np.linalg.norm(direct)


@pytest.mark.parametrize("tol", [1e-4, 1e-8, 1e-10])
def test_finufft_wavelength_camera_within_tol(tol):
    """Wavelength-linear camera (pixel width and line vary with k): the Chebyshev expansion of
    the response plus batched FINUFFT type 3 stays within tol of the direct sum."""
    s = speckle.example_system("840nm", camera_pixels=512)
    cam = sp.camera_sampling(s, "wavelength")
    weights = sp.source_weights(s, cam["wavenumber"])
    rng = np.random.default_rng(int(-np.log10(tol)))
    z = rng.uniform(-s.depth_range, 3 * s.depth_range, (3, 300))
    a = rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)
    kw = dict(pixel_width=cam["pixel_width"], resolution=cam["resolution"], k0=s.k0,
              dispersion={2: 20.0})  # fmt: skip
    direct = sp.interferogram(z, a, cam["wavenumber"], weights, **kw)
    fast = sp.interferogram(z, a, cam["wavenumber"], weights, method="finufft", tol=tol, **kw)
    assert np.linalg.norm(fast - direct) <= tol * np.linalg.norm(direct)
    img = speckle.system_ascan(s, z, a, method="finufft", tol=tol)
    ref = speckle.system_ascan(s, z, a)
    assert np.linalg.norm(img - ref) <= tol * np.linalg.norm(ref)


def test_finufft_camera_refuses_rough_response():
    k = np.linspace(9.0, 10.0, 64)
    rough = np.random.default_rng(0).uniform(0.001, 0.002, 64)
    with pytest.raises(ValueError, match="not a smooth function of k"):
        sp.interferogram(np.ones((1, 3)), np.ones((1, 3)), k, np.ones(64), pixel_width=rough,
                         method="finufft", tol=1e-8)  # fmt: skip
    with pytest.raises(ValueError, match="method must be one of"):
        sp.interferogram(np.ones((1, 3)), np.ones((1, 3)), k, np.ones(64), method="nufft")


def test_chunking_does_not_change_the_signal(monkeypatch):
    """Chunks over lines and scatterers (memory bound) give the same sums."""
    rng = np.random.default_rng(4)
    k = np.linspace(9.0, 10.0, 50)
    z = rng.uniform(0, 300, (3, 40))
    a = rng.normal(size=z.shape) + 0j
    kw = dict(pixel_width=0.01, resolution=0.01, detection="real", autocorrelation=True)
    whole = sp.interferogram(z, a, k, np.ones(50), **kw)
    monkeypatch.setattr(sp, "CHUNK_ELEMENTS", 120)  # 2 scatterers x 50 pixels per chunk
    np.testing.assert_allclose(sp.interferogram(z, a, k, np.ones(50), **kw), whole, rtol=1e-12)


def test_finufft_autocorrelation_within_tol():
    """The pair sum of finite pixels by FINUFFT (pairs as sources) matches the direct one."""
    s = speckle.example_system("840nm", camera_pixels=256)
    cam = sp.camera_sampling(s, "wavelength")
    weights = sp.source_weights(s, cam["wavenumber"])
    rng = np.random.default_rng(9)
    z = rng.uniform(0, s.imaging_depth, (2, 60))
    a = 0.3 * (rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape))
    kw = dict(pixel_width=cam["pixel_width"], resolution=cam["resolution"], detection="real",
              autocorrelation=True)  # fmt: skip
    direct = sp.interferogram(z, a, cam["wavenumber"], weights, **kw)
    fast = sp.interferogram(z, a, cam["wavenumber"], weights, method="finufft", tol=1e-9, **kw)
    assert np.linalg.norm(fast - direct) <= 1e-9 * np.linalg.norm(direct)
