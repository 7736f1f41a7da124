"""A scanner's twin: fit the model's system to a measured image, simulate it, predict strain limits.

:func:`fit_system` measures, on a region of a user's image (:func:`speckle.load_image`), the
statistics that the model's system parameters set, and inverts their theory:

* **spectrum**: the intensity autocorrelation along depth (lags ``1 .. max_lag``) against
  :func:`~speckle.analysis.autocorrelation.axial_correlation_theory` of a Gaussian spectrum
  (FWHM as a fraction of the pixel band ``delta_k``) and of a rectangular one (full width as a
  fraction of the band, edge components weighted by their fractional overlap so the width is a
  continuous parameter); the shape with the smaller rms residual is kept. At finite density
  the Pearson correlation is ``(|gamma(m)|^2 + x d(m)) / ((1 + 1/r)^2 + x)`` (``x`` the
  contrast excess below, ``d`` the normalised autocorrelation of the intensity PSF, ``r`` the
  SNR): the scatterers' own intensities correlate neighbouring pixels even where ``gamma`` is
  0; across A-lines ``d = |gamma|^2``, so only the denominator changes. ``x <= 0`` is the dense
  limit (:func:`~speckle.analysis.autocorrelation.fit_spectral_width`, ``fit_waist``);
* **beam waist** ``w0``: the lateral autocorrelation against ``exp(-2 m^2 p^2/w0^2)`` (A-line
  pitch ``p``), and the same per depth band (``band_waist``), with a chi-square test of a
  depth-independent waist (``waist_depth_p_value``; the model's focused beam keeps the lateral
  correlation depth-independent, see :mod:`speckle.imaging.beam`);
* **focus**: rows are correlated along depth (point-spread function) and across A-lines, so
  the row means of ``ln I`` have the covariance ``C`` of their mean over x, from the region's
  2-D autocovariance of ``ln I`` (summed over lateral lags to the first non-positive one,
  kept to the first non-positive depth lag; Toeplitz). The test statistic is the largest
  reduction of the generalised least-squares residual sum of squares of ``a + b z`` when the
  confocal term ``ln (1 + u^2)^(-3/2)``, ``u = (z - z_f)/z_R`` (the 2-D confocal response of
  :func:`speckle.beam_scan`), is added with a positive coefficient, scanned over ``z_f`` (the
  region and a quarter of it either side) and ``z_R`` (1/2 to 2 times ``k0 w0^2/2``, ``k0`` in
  the medium, ``w0`` the fitted waist). Its p-value (``focus_p_value``) is from a seeded
  Monte-Carlo null (``FOCUS_NULL_DRAWS`` correlated Gaussian residuals with covariance ``C``):
  ``p = (1 + #{null >= observed})/(1 + n)``. Below 1 % (``FOCUS_P_VALUE``) the mean intensity
  per row is fitted by ``A exp(-2 mu_t z) (1 + u^2)^(-3/2) + N``;
* **SNR and noise floor** from signal-free rows (``noise_rows``, or found above the region when
  neither they nor ``snr_db`` are given: :func:`fit_system`): ``SNR = <I_region>/<I_noise>
  - 1`` (the region holds signal plus noise), ``noise_floor`` = mean noise intensity (for log
  data: the mean log level of those rows, data units); white noise multiplies every lag >= 1
  by ``(r/(1 + r))^2``, which the fits include;
* **attenuation** ``mu_t`` (1/µm, intensity): ``-1/2`` the least-squares slope of the mean log
  intensity per row against depth in the medium (``pixel_size / refractive_index``), its SE
  from the sandwich variance with the row means' covariance ``C`` (above);
* **intensity floor** ``b`` and, for log data, the gain ``g`` and offset ``c`` of
  ``D = g ln I + c`` (:func:`~speckle.analysis.measured.fit_floor`: skewness of the log data);
* **scatterer density**: from the intensity contrast. For Poisson scatterers of unit amplitude
  and a point-spread function ``h``, ``<I^2>/<I>^2 = 2 + x`` with ``x = A4 / (rho A^2)``,
  ``A = int |h|^2``, ``A4 = int |h|^4`` (over pixels x pitches). With noise ``N = S/r`` and
  floor ``b S``, ``var I = (S + N)^2 + x S^2`` and ``<I> = S (1 + b) + N``, so ``x`` (and so
  ``inverse_density = 1/rho``) follows from the mean and variance of the region. At high
  density ``x`` is small against its error: ``inverse_density`` is then consistent with 0 and
  ``density_lower_bound`` (at 2 standard errors) is what the image says. For linear data a
  second estimate comes from ``var ln I`` (``inverse_density_log``): exact for Poisson
  scatterers through the fitted PSF with the fitted noise (:mod:`speckle.analysis.sparse`,
  no floor), it resolves low densities (0.5-4 per pixel per pitch), where the contrast's
  error grows with the fourth moment of ``I``. The two share every pixel and are combined by
  the inverse of their jackknife covariance (``inverse_density``; ``density_identified``
  when it exceeds 2 SE). For log data ``var D = g^2 var ln I`` with the gain ``g`` unknown:
  ``var ln I`` is not observed and the contrast is used alone (the ``method`` attribute says
  which).

Estimates use every pixel pair of the region (the autocorrelation is then that of
:func:`~speckle.analysis.autocorrelation.intensity_autocorrelation`). Standard errors:
delete-one-block jackknife over ``n_blocks`` contiguous blocks of A-lines (speckle is
correlated over a few lines, blocks are nearly independent): every quantity above is
re-estimated without each block (statistics pooled over the remaining blocks, no pair across a
block edge) and ``SE^2 = (n - 1)/n sum (theta_i - mean theta)^2``. With a ``frame`` dim the
statistics pool every frame and each jackknife sample deletes the same block from all frames.
The attenuation's SE and the focus test use the row means' covariance ``C`` instead (a block
jackknife of a slope over ~16 blocks understates its error under a wide beam); with a ``frame``
dim ``C`` is that of the frame-averaged ``ln I``, right whether the frames' speckle is
independent, identical or in between. When a focus is
found its fit is repeated on each jackknife sample (those errors, attenuation included, are the
jackknife's).

:meth:`SystemFit.simulate` images a shared scene of the fitted density through the fitted
spectrum and scanned (focused) beam (:func:`speckle.beam_scan`), attenuated, with white noise
at the fitted SNR, the floor, and the fitted log mapping and quantisation for log images: a
twin of the same kind, dims and coordinates. :meth:`SystemFit.failure_maps` deforms the twin's
scene (uniform compression, ``u_z = -s z``) and scores every strain estimator
(:func:`speckle.estimate_strain`) against the known strain.
"""

from ..._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, __file__)
