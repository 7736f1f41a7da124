"""
Fig. 6a: correlation maps under 1 % strain
==========================================

Windowed correlation between a reference B-scan and the same scatterers under 1 % uniaxial
compression: without compensation (the speckle has moved), after exact compensation of the
known displacement, and after compensation of the displacement tracked from the images. What
remains after compensation is the decorrelation caused by strain itself. Reduced here to 64
A-lines; the pipeline target is ``results/fig6/fig6a.png``.
"""

from speckle.figures import deformation
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig6 = config["fig6"]
fig6 = {**fig6, "panel_a": {**fig6["panel_a"], "n_alines": 64}}

ds = deformation.fig6a_data(config["source"], fig6, config["seed"])
fig = deformation.plot_fig6a(ds)
