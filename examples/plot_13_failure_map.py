"""
Failure maps of the strain estimators
=====================================

Where each strain estimator fails: rms error relative to the strain (top) and the fraction of
pixels answered (bottom), sweeping one parameter at a time around a base strain of 0.2 %:
the interframe strain, the SNR, the depth window, k0/Δk, the spectral width and the density.
Vertical lines are the predicted limits (phase wrapping, decorrelation, displacement of a
speckle half-width); points are means over independent scenes with one standard error. Reduced
here to 128 pixels x 16 A-lines, two seeds, two estimators and short sweeps;
the pipeline target is ``results/elastography/failure_maps.png``.
"""

from speckle.figures import elastography
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
cfg = {**config["elastography"], "n_pixels": 128, "n_alines": 16, "methods": ["vector", "wls"]}
cfg["failure"] = {
    **cfg["failure"],
    "n_pixels": 128,
    "n_alines": 16,
    "n_seeds": 2,  # the pipeline: 512 x 256 px, 4 seeds (mean +- standard error drawn)
    "strain": [1.0e-4, 1.0e-3, 3.0e-3, 1.0e-2, 3.0e-2],
    "snr_db": [10.0, 30.0, None],
    "windows": [16, 32],
    "k0_dk": [3.0, 10.0],
    "fwhm_fraction": [0.5, 1.0],
    "density": [1.0, 4.0],
}

ds = elastography.failure_data(cfg, config["seed"])
print({k: v for k, v in ds.attrs.items() if k.startswith("limit_")})

# plot_failure draws the figure the pipeline rule saves
fig = elastography.plot_failure(ds)
