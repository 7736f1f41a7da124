"""
Fig. 3: speckle contrast against scatterer density
==================================================

Amplitude histograms and the speckle contrast (std/mean of intensity) for each density,
against the exact finite-N theory (``speckle.contrast_theory``). The contrast falls to 1,
fully developed speckle, as the density grows. Reduced here to four densities and 16 A-lines
each; the pipeline target is ``results/fig3/fig3.png``.
"""

from speckle.figures import histograms, static
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig3, source = config["fig3"], config["source"]

ds = histograms.density_histograms(
    [0.5, 1.5, 4.0, 16.0],
    n_alines=16,
    k0_dk=source["k0_dk"],
    seed=config["seed"],
    normalise=fig3["normalise"],
    bins=fig3["bins"],
    amplitude_max=fig3["amplitude_max"],
    method=fig3["method"],
    **static.source_options(source),
)
fig = histograms.plot_density_histograms(ds)
print(ds[["contrast", "contrast_se", "contrast_theory"]].to_dataframe().round(3))
