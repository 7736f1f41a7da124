"""
A strain map: inclusion phantom compressed by finite elements
=============================================================

A stiff circular inclusion (40 vs 10 kPa, Poisson ratio 0.45) in a block compressed by 0.4 %
with a sliding probe, solved by plane-strain finite elements (``speckle.compress_phantom``). The
scatterers move with the FE displacement; each strain estimator reads the strain from the two
complex images. Top: modulus, FE strain and each method's strain map; bottom: error maps.
Reduced here to 128 pixels x 32 A-lines (x: A-line index, 8 µm apart; radius 80 µm) and
two estimators; the pipeline target is ``results/elastography/inclusion.png``.
"""

from speckle.figures import elastography
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
cfg = {**config["elastography"], "n_pixels": 128, "methods": ["vector", "wls"]}
cfg["inclusion"] = {**cfg["inclusion"], "n_alines": 32, "radius": 80.0}

ds = elastography.inclusion_data(cfg, config["seed"])
print(ds)

# plot_inclusion draws the figure the pipeline rule saves
fig = elastography.plot_inclusion(ds)
