"""
Fig. 6b: correlation against strain for several k0/Δk
=====================================================

Area correlation between the reference and the strained image after exact compensation,
against strain, for k0/Δk = 1, 3 and 10, beside the theory (``speckle.expected_correlation``,
exact for finite N and density). The larger k0/Δk, the faster speckle decorrelates under the
same strain. Reduced here to 16 A-lines and 4 strains; the pipeline target is
``results/fig6/fig6b.png``.
"""

from speckle.figures import deformation
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig6 = config["fig6"]
strain = {"start": 0.0, "stop": 0.03, "num": 4}
fig6 = {**fig6, "n_alines": 16, "panel_b": {**fig6["panel_b"], "strain": strain}}

ds = deformation.fig6b_data(config["source"], fig6, config["dask"], config["seed"])
fig = deformation.plot_fig6b(ds)
