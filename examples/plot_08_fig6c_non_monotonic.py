"""
Fig. 6c: is the correlation curve non-monotonic?
================================================

Correlation against strain up to 10 % at k0/Δk = 10 for three spectra. With the rectangular
and Gaussian spectra the compensated correlation falls monotonically to the incoherent floor;
only a spectrum with two separated peaks (two light sources) gives the minimum and revival the
paper describes, or a complex correlation over a short depth window that keeps the carrier
phase (a window artefact). Reduced here to 16 A-lines and 9 strains; the pipeline target is
``results/fig6/fig6c.png``.
"""

from speckle.figures import deformation
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig6 = config["fig6"]
strain = {"start": 0.0, "stop": 0.10, "num": 9}
fig6 = {**fig6, "n_alines": 16, "panel_c": {**fig6["panel_c"], "strain": strain}}

ds = deformation.fig6c_data(config["source"], fig6, config["dask"], config["seed"])
fig = deformation.plot_fig6c(ds)
